"""Regression tests of issue 16 ("hardened boundaries") for imageform.color."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform.color import (
    RGBSpace,
    cct_to_xy,
    chromatic_adaptation_matrix,
    convert,
    delta_e,
    delta_e_cie76,
    downsample,
    estimate_illuminant,
    gamut_area,
    hsv_to_srgb,
    hue_difference,
    hue_in_range,
    lab_to_xyz,
    mean_linear_light,
    palette,
    polygon_area,
    resolve_white,
    simulate_cvd,
    space_name,
    spectral_locus,
    srgb_to_hsv,
    viridis,
    white_balance,
    xy_to_cct,
    xy_to_xyz_white,
)
from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError

LAB = np.array([[50.0, 10.0, -20.0], [70.0, -30.0, 5.0]])


@pytest.fixture(autouse=True)
def _no_warnings():
    """Every call here must stay silent: no ComplexWarning, no RuntimeWarning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def _one_line(exc: pytest.ExceptionInfo[BaseException], *names: str) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    for n in names:
        assert n in msg, (n, msg)
    return msg


@pytest.mark.parametrize(
    "call",
    [
        lambda: chromatic_adaptation_matrix(np.array([0.95, 1.0, 1.09]) + 0j, "D50"),
        lambda: resolve_white(np.array([0.3127, 0.329]) + 0j),
        lambda: polygon_area(np.array([[0, 0], [1, 0], [0, 1]]) + 1j),
        lambda: spectral_locus(wavelength_range=np.array([380.0, 780.0]) + 0j),
        lambda: delta_e(LAB + 0j, LAB),
        lambda: srgb_to_hsv(np.array([[0.2, 0.4, 0.6]]) + 0j),
    ],
)
def test_complex_input_is_refused_not_cut_to_real(call) -> None:
    with pytest.raises(InvalidInputError, match="complex") as exc:
        call()
    _one_line(exc)


@pytest.mark.parametrize(
    "value", [np.array([0.1, 0.2, 0.3], dtype=object), np.array(["0.1", "0.2", "0.3"])]
)
def test_object_and_string_arrays_are_refused(value) -> None:
    with pytest.raises(InvalidInputError) as exc:
        delta_e_cie76(value, LAB[0])
    _one_line(exc, "lab1")


def test_bool_arrays_are_a_type_error() -> None:
    """docs/conventions.md: a bool array where numbers are taken is a TypeError."""
    with pytest.raises(TypeError, match="bool") as exc:
        delta_e(LAB > 20, LAB)
    _one_line(exc, "lab1")
    with pytest.raises(TypeError, match="bool"):
        srgb_to_hsv(np.ones((2, 2, 3), dtype=bool))
    with pytest.raises(InvalidInputError, match="clip"):
        simulate_cvd(np.full((1, 3), 0.5), "protan", clip=np.array([True, False]))


def test_delta_e_at_1e300_is_refused_without_a_runtime_warning() -> None:
    with pytest.raises(InvalidInputError, match=r"lab1 within ±1e\+15") as exc:
        delta_e(LAB * 1e300, LAB)
    _one_line(exc)
    for method in ("cie76", "cie94", "cmc", "ciede2000"):
        with pytest.raises(InvalidInputError):
            delta_e(LAB, LAB * 1e300, method)
    with pytest.raises(InvalidInputError, match=r"kC in \[0.001, 1000\]"):
        delta_e(LAB, LAB, kC=1e-300)
    # a factor the chosen method does not use is checked too
    with pytest.raises(InvalidInputError, match="expected l as a finite number"):
        delta_e(LAB, LAB, "ciede2000", l=np.nan)
    # the valid range is computed as before
    np.testing.assert_allclose(delta_e(LAB, LAB + [1.0, 0.0, 0.0], "cie76"), [1.0, 1.0])


def test_huge_values_in_inverse_conversions_are_refused() -> None:
    for call in (lambda: hsv_to_srgb([[1e300, 0.5, 0.5]]), lambda: lab_to_xyz([[1e300, 0, 0]])):
        with pytest.raises(InvalidInputError, match="within") as exc:
            call()
        _one_line(exc)


def test_empty_images_are_errors_not_nan() -> None:
    with pytest.raises(InvalidInputError, match="image with at least one pixel"):
        estimate_illuminant(np.zeros((0, 0, 3)))
    with pytest.raises(InvalidInputError, match="image with at least one pixel"):
        white_balance(np.zeros((0, 4, 3)))
    with pytest.raises(InvalidInputError, match="non-empty image"):
        mean_linear_light(np.zeros((0, 3)))
    with pytest.raises(InvalidInputError, match="non-empty image"):
        mean_linear_light(np.zeros((4, 0, 3)), axis=(0, 1))
    # an empty batch through a pointwise conversion stays an empty result
    assert srgb_to_hsv(np.zeros((0, 3))).shape == (0, 3)


def test_numpy_integers_are_integers() -> None:
    img = np.random.default_rng(0).uniform(0, 1, (4, 4, 3))
    np.testing.assert_array_equal(downsample(img, np.int64(2)), downsample(img, 2))
    np.testing.assert_array_equal(palette("okabe_ito", np.int32(3)), palette("okabe_ito", 3))
    np.testing.assert_array_equal(viridis(np.int64(4)), viridis(4))
    np.testing.assert_array_equal(
        xy_to_cct([0.3127, 0.329], iterations=np.int64(5))[0], xy_to_cct([0.3127, 0.329])[0]
    )
    with pytest.raises(InvalidInputError, match="factor"):
        downsample(img, 2.0)
    with pytest.raises(InvalidInputError, match="factor"):
        downsample(img, True)


def test_none_never_becomes_nan() -> None:
    with pytest.raises(InvalidInputError, match="start"):
        hue_in_range([10.0, 20.0], None, 30.0)
    with pytest.raises(InvalidInputError, match="percentile"):
        estimate_illuminant(np.full((2, 2, 3), 0.5), "white_patch", percentile=np.nan)
    with pytest.raises(InvalidInputError, match="duv"):
        cct_to_xy(6500.0, None)


def test_white_balance_parameters_are_checked_whatever_the_method() -> None:
    img = np.full((3, 3, 3), 0.5)
    for kw in ({"p": np.nan}, {"sigma": -1.0}, {"cct": "warm"}, {"percentile": 101}):
        with pytest.raises(ImageformError) as exc:
            white_balance(img, "gray_world", **kw)
        _one_line(exc, next(iter(kw)))
    with pytest.raises(InvalidInputError) as exc, pytest.warns(DeprecationWarning):
        estimate_illuminant(np.full((4, 5, 3), 0.5), channel_axis=0)
    _one_line(exc, "channel_axis")


def test_python_int_tuples_are_8_bit_codes() -> None:
    """docs/conventions.md: a tuple of Python ints is 8-bit codes 0-255."""
    got = convert((200, 50, 50), "srgb", "hsv")
    np.testing.assert_allclose(got, convert(np.array([200, 50, 50], np.uint8), "srgb", "hsv"))
    np.testing.assert_allclose(got, [0.0, 0.75, 200 / 255], rtol=1e-6)
    with pytest.raises(InvalidInputError, match="0-255"):
        convert((300, 50, 50), "srgb", "hsv")


def test_rgb_space_is_validated_in_post_init() -> None:
    good = ((0.64, 0.33), (0.3, 0.6), (0.15, 0.06))
    with pytest.raises(InvalidInputError, match="primaries_xy"):
        RGBSpace("x", ((np.nan, 0.33), (0.3, 0.6), (0.15, 0.06)), (0.3127, 0.329), "srgb", "")
    with pytest.raises(InvalidInputError, match="white_xy"):
        RGBSpace("x", good, (0.3127, np.inf), "srgb", "")
    with pytest.raises(InvalidInputError, match="primaries_xy"):
        RGBSpace("x", ((0.64, 0.33), (0.3, 0.6)), (0.3127, 0.329), "srgb", "")
    with pytest.raises(UnknownOptionError, match="transfer"):
        RGBSpace("x", good, (0.3127, 0.329), "gamma3", "")
    sp = RGBSpace("x", good, (0.3127, 0.329), "srgb", "")
    assert gamut_area(sp) == pytest.approx(gamut_area("srgb"))


def test_unknown_colour_space_is_one_short_line() -> None:
    with pytest.raises(UnknownOptionError) as exc:
        space_name("no-such-space", "--to")
    _one_line(exc, "--to", "more")


def test_daylight_locus_ends_take_one_ulp_outside() -> None:
    for T, d in ((4000.0, 1.0), (25000.0, -1.0)):
        x, y = (float(v) for v in cct_to_xy(T, method="daylight"))
        outside = float(np.nextafter(x, x + d))
        got = float(xy_to_cct([outside, y], method="daylight")[0])
        assert got == pytest.approx(T, rel=1e-12)
    with pytest.raises(InvalidInputError, match="outside the daylight locus"):
        xy_to_cct([0.3834, 0.38], method="daylight")


def test_messages_name_the_parameter() -> None:
    with pytest.raises(InvalidInputError) as exc:
        hue_difference([1.0, 2.0, 3.0], [1.0, 2.0])
    _one_line(exc, "h1", "h2")
    with pytest.raises(InvalidInputError) as exc:
        xy_to_xyz_white([0.3])
    _one_line(exc, "xy")


def test_misshaped_arrays_are_refused_before_their_values_are_read() -> None:
    """A wrong channel count is refused from the shape alone (NaN inside is never reached)."""
    rgba = np.full((64, 64, 4), np.nan)
    with pytest.raises(InvalidInputError, match=r"3 channels on axis -1.*alpha"):
        srgb_to_hsv(rgba)
    with pytest.raises(InvalidInputError, match=r"lab1 of shape \(\.\.\., 3\)"):
        delta_e(np.full((5, 4), np.nan), LAB[0])
