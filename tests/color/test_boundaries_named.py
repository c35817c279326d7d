"""Issue 16, second pass on imageform.color: every refusal names the parameter that was
wrong (``coords``, ``points``, ``src_white`` ... rather than "chromaticity diagram" or
"white"), stays one line under 200 characters for a 100,000-character option, and result
containers built by hand refuse NaN, inf and complex values."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform.color import (
    GamutFigures,
    SubsampledChroma,
    WhiteBalanceResult,
    are_metamers,
    brettel_planes,
    check_in_locus,
    chroma_subsample,
    chroma_upsample,
    chromatic_adaptation,
    chromatic_adaptation_matrix,
    cvd_matrix,
    estimate_illuminant,
    gamut_area,
    gamut_coverage,
    gamut_figures,
    gamut_triangle,
    gray_to_srgb,
    hue_in_range,
    hue_undefined_mask,
    in_gamut,
    in_locus,
    machado_matrix,
    metamer,
    metamerism_index,
    palette,
    palette_check,
    parse_colors,
    resolve_white,
    simulate_cvd,
    space_name,
    spectral_locus,
    srgb_to_ycbcr,
    subsample_round_trip,
    subsampling_delta_e,
    tristimulus,
    uv_prime_to_xy,
    visible_area,
    white_balance,
    whitepoint_xy,
    whitepoint_xyz,
    ycbcr_to_rgb,
    ycbcr_to_srgb,
)
from imageform.color.cct_methods import cct_to_uv_ohno2013, planckian_uv, uv_to_cct_ohno2013
from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.spectral import Spectrum, colorchecker_reflectances

RGB = np.random.default_rng(16).uniform(0.05, 0.95, (6, 8, 3))
HUGE = "x" * 100_000


@pytest.fixture(autouse=True)
def _no_warnings():
    """No ComplexWarning, no RuntimeWarning on the way to a refusal."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def _refused(call: Callable[[], Any], name: str) -> str:
    """``call()`` raises ImageformError or TypeError in one line <= 200 chars naming ``name``."""
    with pytest.raises((ImageformError, TypeError)) as exc:
        call()
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    assert name in msg, (name, msg)
    return msg


def _spectrum() -> Spectrum:
    return colorchecker_reflectances()["dark skin"]


# --------------------------------------------------------------------------- options


COORDS: dict[str, Callable[[Any], Any]] = {
    "spectral_locus": lambda c: spectral_locus(coords=c),
    "visible_area": lambda c: visible_area(c),
    "gamut_triangle": lambda c: gamut_triangle("srgb", c),
    "gamut_area": lambda c: gamut_area("srgb", c),
    "gamut_coverage": lambda c: gamut_coverage("srgb", c),
    "in_locus": lambda c: in_locus([[0.3, 0.3]], c),
    "check_in_locus": lambda c: check_in_locus([[0.3, 0.3]], c),
}


@pytest.mark.parametrize("func", list(COORDS))
@pytest.mark.parametrize("bad", [None, True, 0, ["xy", "xy"], object(), "", "lab", HUGE])
def test_coords_is_named(func: str, bad: object) -> None:
    kind = UnknownOptionError if isinstance(bad, str) else TypeError
    with pytest.raises(kind):
        COORDS[func](bad)
    _refused(lambda: COORDS[func](bad), "coords")


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda v: white_balance(RGB, normalize=v), "normalize"),
        (lambda v: palette(v), "name"),
        (lambda v: whitepoint_xy(v), "name"),
        (lambda v: whitepoint_xyz(v), "name"),
        (lambda v: space_name(v), "name"),
        (lambda v: brettel_planes(v), "deficiency"),
        (lambda v: cvd_matrix(v), "deficiency"),
        (lambda v: machado_matrix(v), "deficiency"),
        (lambda v: simulate_cvd(RGB, v), "deficiency"),
        (lambda v: white_balance(RGB, v), "method"),
        (lambda v: estimate_illuminant(RGB, v), "method"),
        (lambda v: chroma_subsample(srgb_to_ycbcr(RGB), v), "scheme"),
        (lambda v: chroma_upsample(*chroma_subsample(srgb_to_ycbcr(RGB)), v), "scheme"),
        (lambda v: subsample_round_trip(RGB, v), "scheme"),
        (lambda v: subsampling_delta_e(RGB, v), "scheme"),
        (lambda v: tristimulus(_spectrum(), illuminant=v), "illuminant"),
        (lambda v: are_metamers(_spectrum(), _spectrum(), illuminant=v), "illuminant"),
        (lambda v: metamer(_spectrum(), illuminant=v), "illuminant"),
        (lambda v: metamerism_index(_spectrum(), _spectrum(), v, "A"), "reference"),
        (lambda v: metamerism_index(_spectrum(), _spectrum(), "D65", v), "test"),
    ],
)
@pytest.mark.parametrize("bad", ["", HUGE, ["a", "b"], 0, True])
def test_option_names_are_named_and_short(
    call: Callable[[Any], Any], name: str, bad: object
) -> None:
    """An empty, huge or non-str option: one short line naming the parameter (the list of
    valid names is cut to fit)."""
    _refused(lambda: call(bad), name)


def test_brettel_planes_cache_is_not_poisoned() -> None:
    """A list used to reach the cache (TypeError: unhashable type); the cached arrays are
    not handed out, so writing into a result cannot change the next one."""
    with pytest.raises(TypeError, match="deficiency"):
        brettel_planes(["protan"])  # type: ignore[arg-type]
    h1, _, _ = brettel_planes("protan")
    h1[:] = 0.0
    assert np.abs(brettel_planes("protan").H1).max() > 0.1


# --------------------------------------------------------------------------- arrays


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda v: uv_prime_to_xy(v), "uv"),
        (lambda v: in_locus(v), "points"),
        (lambda v: check_in_locus(v), "points"),
        (lambda v: in_gamut(v), "values"),
        (lambda v: in_gamut(v, kind="xy"), "values"),
        (lambda v: hue_undefined_mask(v), "values"),
        (lambda v: ycbcr_to_rgb(v), "ycbcr"),
        (lambda v: ycbcr_to_srgb(v), "ycbcr"),
        (lambda v: gray_to_srgb(v), "gray"),
    ],
)
@pytest.mark.parametrize(
    "bad",
    [None, True, "abc", 0, np.array([[0.2, 0.3, 0.4]], dtype=object), np.ones((2, 3)) + 1j],
)
def test_arrays_are_named(call: Callable[[Any], Any], name: str, bad: object) -> None:
    _refused(lambda: call(bad), name)


def test_gray_to_srgb_names_gray() -> None:
    g = RGB[..., :1]
    _refused(lambda: gray_to_srgb(g * 1e300 + 1e300), "gray")
    _refused(lambda: gray_to_srgb(np.where(g > 0.5, np.nan, g)), "gray")
    _refused(lambda: gray_to_srgb(RGB[..., :2]), "gray")
    assert gray_to_srgb(g).shape == (6, 8, 3)


@pytest.mark.parametrize("param", ["src_white", "dst_white"])
@pytest.mark.parametrize(
    "bad", [None, True, 0, "", HUGE, ["D65", "D65"], object(), np.array([0.3, 0.3]) + 1j]
)
def test_white_parameters_are_named(param: str, bad: object) -> None:
    kw: dict[str, Any] = {"src_white": "D65", "dst_white": "D50", param: bad}
    _refused(lambda: chromatic_adaptation_matrix(**kw), param)
    _refused(lambda: chromatic_adaptation(RGB, **kw), param)


def test_resolve_white_names_the_callers_parameter() -> None:
    _refused(lambda: resolve_white(None), "white")
    _refused(lambda: resolve_white([0.3, -1.0, 0.2], name="reference_white"), "reference_white")
    np.testing.assert_allclose(resolve_white("D65", name="x"), resolve_white("D65"))


def test_colors_are_named() -> None:
    _refused(lambda: parse_colors(HUGE), "colors")
    _refused(lambda: parse_colors(["#ff0000,#00ff00"]), "colors")
    _refused(lambda: palette_check(["#GG0000"]), "colors")
    assert parse_colors(["#ff0000"]).tolist() == [[1.0, 0.0, 0.0]]


def test_hue_in_range_of_a_0d_tensor_is_0d() -> None:
    """An elementwise mask keeps its input's shape: a 0-d tensor gives a 0-d mask (the fuzz
    harness reports this as ``wrong_result_shape`` against the 1-d valid call; it is right)."""
    torch = pytest.importorskip("torch")
    out = hue_in_range(torch.tensor(350.0), 340, 20)
    assert out.ndim == 0 and bool(out)


# --------------------------------------------------------------------------- cct methods


@pytest.mark.parametrize(
    "bad", [True, None, 1 + 1j, object(), 1e308, 10.0, -5.0, np.nan, np.inf, "6500"]
)
def test_planckian_uv_refuses_what_it_cannot_compute(bad: object) -> None:
    """True used to be read as 1 K and 1e308 K overflowed: both returned NaN."""
    _refused(lambda: planckian_uv(bad), "cct")
    _refused(lambda: cct_to_uv_ohno2013(bad), "cct")


def test_planckian_uv_domain_ends_are_finite() -> None:
    uv = planckian_uv(np.array([50.0, 6504.0, 1e15]))
    assert np.isfinite(uv).all()
    np.testing.assert_allclose(uv[2], [0.180064, 0.263521], atol=1e-6)


@pytest.mark.parametrize("bad", [None, np.nan, np.inf, 1j, object(), 2.0])
def test_cct_to_uv_ohno2013_refuses_bad_duv(bad: object) -> None:
    _refused(lambda: cct_to_uv_ohno2013(6500.0, bad), "duv")


@pytest.mark.parametrize("bad", [None, [], [1.001, 1.001], 1 + 1j, object(), 1.0, 1.5, 1 + 1e-9])
def test_uv_to_cct_ohno2013_spacing(bad: object) -> None:
    """``float(spacing)`` named nothing; a spacing of 1 + 1e-9 would build a table of
    4.6e9 temperatures in a Python loop."""
    _refused(lambda: uv_to_cct_ohno2013([0.1978, 0.3122], spacing=bad), "spacing")


def test_uv_to_cct_ohno2013_huge_uv_is_short() -> None:
    _refused(lambda: uv_to_cct_ohno2013(np.array([0.2, 0.3]) * 1e300 + 1e300), "uv")


# --------------------------------------------------------------------------- results


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1 + 1j, None, "1.0", -1.0])
def test_gamut_figures_fields_are_checked(bad: object) -> None:
    good = gamut_figures(["srgb"])[0].as_dict()
    for field in ("area_xy", "coverage_uv", "area_ratio_xy"):
        _refused(lambda f=field: GamutFigures(**{**good, f: bad}), field)
    assert GamutFigures(**good) == gamut_figures(["srgb"])[0]


@pytest.mark.parametrize(
    "bad", [np.full((3, 4, 2), np.nan), np.full((3, 4, 2), np.inf), np.ones((3, 4, 2)) + 1j, None]
)
def test_result_containers_refuse_non_finite_fields(bad: object) -> None:
    luma = np.zeros((6, 8))
    _refused(lambda: SubsampledChroma(luma, bad), "chroma")
    _refused(lambda: SubsampledChroma(bad, np.zeros((3, 4, 2))), "luma")
    _refused(lambda: WhiteBalanceResult(RGB, bad), "gains")
    _refused(lambda: WhiteBalanceResult(bad, np.ones(3)), "image")


def test_result_containers_from_the_functions_are_unchanged() -> None:
    sub = chroma_subsample(srgb_to_ycbcr(RGB))
    assert isinstance(sub, SubsampledChroma) and sub.chroma.shape == (3, 4, 2)
    luma, chroma = sub
    assert SubsampledChroma(luma, chroma).luma is luma
    wb = white_balance(RGB)
    assert isinstance(wb, WhiteBalanceResult) and wb.gains.shape == (3,)
    assert WhiteBalanceResult(*wb).gains is wb.gains
    assert wb._replace(gains=np.ones(3)).gains.tolist() == [1.0, 1.0, 1.0]


def test_metamerism_index_refuses_a_missing_test_illuminant() -> None:
    """``test=None`` used to reach the Lab white as None ("expected white ...")."""
    _refused(lambda: metamerism_index(_spectrum(), _spectrum(), "D65", None), "test")
    s = _spectrum()
    assert metamerism_index(s, s, "D65", "A") == pytest.approx(0.0, abs=1e-9)
    assert metamerism_index(s, s, None, Spectrum(s.wavelengths, np.ones(len(s)))) == 0.0


def test_invalid_input_still_a_value_error() -> None:
    """The refusals keep their classes (callers catch ValueError / UnknownOptionError)."""
    with pytest.raises(UnknownOptionError):
        white_balance(RGB, normalize="max")
    with pytest.raises(InvalidInputError):
        whitepoint_xy("D93")


def test_dask_refusals_report_the_arrays_shape_not_the_probes() -> None:
    """Issue 16 ("no chunk shape where the array's shape is meant"): a chunk-wise function
    checks shapes on a one-pixel probe; its refusal used to report the probe's (1, 4)."""
    da = pytest.importorskip("dask.array")
    from imageform.color import delta_e, xyz_to_lab

    x = da.from_array(np.full((100, 4), 0.5), chunks=(10, 4))
    msg = _refused(lambda: xyz_to_lab(x), "XYZ")
    assert "(100, 4)" in msg and "(1, 4)" not in msg
    msg = _refused(lambda: delta_e(x, x), "lab1")
    assert "(100, 4)" in msg
    y = da.from_array(np.full((5, 100, 4), 0.5), chunks=(1, 10, 4))
    assert "(5, 100, 4)" in _refused(lambda: in_locus(y), "points")


@pytest.mark.parametrize("bad", [None, object(), True, 0, "srgb"])
def test_gamut_figures_spaces_is_a_list(bad: object) -> None:
    """A None-default or non-simple optional parameter the fuzz table does not reach:
    "'NoneType' object is not iterable", and a bare "srgb" read letter by letter."""
    _refused(lambda: gamut_figures(bad), "spaces")  # type: ignore[arg-type]


def test_gamut_figures_names_the_bad_entry() -> None:
    msg = _refused(lambda: gamut_figures(["srgb", "cmyk"]), "spaces[1]")
    assert "unknown RGB space 'cmyk'" in msg


@pytest.mark.parametrize("bad", [True, np.array([True, False, True]), object(), "nope"])
def test_white_balance_illuminant_is_named(bad: object) -> None:
    _refused(lambda: white_balance(RGB, "manual", illuminant=bad), "illuminant")
    _refused(lambda: estimate_illuminant(RGB, "manual", illuminant=bad), "illuminant")
