"""Hardened boundaries of the PSF, MTF, thin-lens and depth-of-field API (issue 16).

Each case is one the fuzz test (:mod:`tests.fuzz`) found: a complex, string, object or
``None`` array cut or cast silently, a huge scalar overflowing ``int()`` or a formula, a
result dataclass accepting NaN. Each must end in one line naming the parameter.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.optics import (
    DepthOfField,
    ThinLensSolution,
    depth_of_field,
    diffraction_limited_mtf,
    diffraction_psf,
    field_psfs,
    mtf,
    otf,
    pixel_mtf,
    polychromatic_psf,
    thin_lens,
    zernike,
    zernike_defocus,
    zernike_radial,
    zernike_wavefront,
)
from imageform.optics.psf import MAX_NOLL_INDEX, MAX_ZERNIKE_ORDER

RHO = np.array([0.0, 0.5, 1.0])
THETA = np.array([0.0, 1.0, 2.0])
BAD_ARRAYS = [
    (None, "real numbers"),
    ("abc", "real numbers"),
    (RHO + 1e-3j, "real numbers"),
    (np.array([0.1, object()], dtype=object), "real numbers"),
    (np.array([0.0, np.nan]), "NaN"),
    (np.array([0.0, np.inf]), "inf"),
]


def _one_line(exc: pytest.ExceptionInfo[BaseException], name: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    assert name in msg, msg


@pytest.mark.parametrize(("value", "what"), BAD_ARRAYS)
def test_zernike_arrays_refused_by_name(value: object, what: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning: refused before any cast
        for call in (
            lambda: zernike_radial(2, 0, value),
            lambda: zernike(4, value, THETA),
            lambda: zernike_wavefront({4: 1e-7}, value, THETA),
        ):
            with pytest.raises(InvalidInputError, match=what) as exc:
                call()
            _one_line(exc, "rho")
        for call in (
            lambda: zernike(5, RHO, value),
            lambda: zernike_wavefront([0, 1e-7], RHO, value),
        ):
            with pytest.raises(InvalidInputError, match=what) as exc:
                call()
            _one_line(exc, "theta")


def test_zernike_shapes_and_orders() -> None:
    # rho and theta that do not broadcast: one line naming both (not numpy's message)
    with pytest.raises(InvalidInputError, match="rho and theta") as exc:
        zernike(4, RHO, np.zeros(4))
    _one_line(exc, "theta")
    with pytest.raises(InvalidInputError, match="rho and theta"):
        zernike_wavefront({4: 1e-7}, np.zeros(0), THETA)
    # the explicit sum is exact to 1e-6 up to order 30 (checked against Legendre), refused
    # beyond: before, j = 10**30 ran for minutes and n = 10**30 overflowed factorial()
    from scipy.special import eval_legendre

    r = np.linspace(0, 1, 101)
    np.testing.assert_allclose(
        zernike_radial(MAX_ZERNIKE_ORDER, 0, r),
        eval_legendre(MAX_ZERNIKE_ORDER // 2, 2 * r**2 - 1),
        atol=1e-5,
    )
    assert np.isfinite(zernike(MAX_NOLL_INDEX, r, r)).all()
    with pytest.raises(InvalidInputError, match="n <= 30"):
        zernike_radial(10**30, 0, RHO)
    with pytest.raises(InvalidInputError, match="j"):
        zernike(10**30, RHO, THETA)
    with pytest.raises(InvalidInputError, match="Noll j"):
        zernike_wavefront({MAX_NOLL_INDEX + 1: 1e-7}, RHO, THETA)
    # rho far outside the unit disc overflows: refused, never inf
    with pytest.raises(InvalidInputError, match="rho") as exc:
        zernike_radial(4, 0, np.array([0.0, 1e300]))
    _one_line(exc, "rho")
    with pytest.raises(InvalidInputError, match="float range"):
        zernike_wavefront({4: 1e300}, np.array([0.0, 1e200]), 0.0)
    # a 0-d rho gives a 0-d result (broadcasting, not a wrong shape)
    assert zernike_radial(2, 0, np.float64(1.0)).shape == ()


@pytest.mark.parametrize("coc", [1e-5 + 1j, object(), None, "abc", -1e-5])
def test_zernike_defocus_coc(coc: object) -> None:
    with pytest.raises(InvalidInputError) as exc:
        zernike_defocus(coc, f_number=4.0)
    _one_line(exc, "coc")


def test_psf_sampling_bounded_before_int() -> None:
    # a huge f-number, pitch or wavelength made Q = lambda N / pitch overflow int(ceil(...))
    kw = {"wavelength": 550e-9, "f_number": 4.0, "pixel_pitch": 2e-6, "size": 16, "n_pupil": 64}
    for name, value in (("f_number", 1e308), ("pixel_pitch", 1e308), ("wavelength", 1e308)):
        with pytest.raises(InvalidInputError, match="padded pupil") as exc:
            diffraction_psf(**{**kw, name: value})
        _one_line(exc, name)
    with pytest.raises(InvalidInputError, match="padded pupil") as exc:
        field_psfs(np.zeros((1, 1, 4)), **{**kw, "pixel_pitch": 1e308})
    _one_line(exc, "pixel_pitch")


@pytest.mark.parametrize(
    "wavelengths", [None, "abc", [5e-7 + 1j], [5e-7, math.nan], [0.0], True, [[5e-7]]]
)
def test_polychromatic_psf_wavelengths(wavelengths: object) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InvalidInputError) as exc:
            polychromatic_psf(wavelengths=wavelengths, f_number=4.0, pixel_pitch=2e-6, size=8)
    _one_line(exc, "wavelengths")


def test_polychromatic_psf_memory_names_wavelengths() -> None:
    # 1 m light at f/4 on 2 um pixels: a 260 GiB pupil; the message names wavelengths
    with pytest.raises(InvalidInputError, match="padded pupil") as exc:
        polychromatic_psf(wavelengths=[1.0], f_number=4.0, pixel_pitch=2e-6, size=8)
    _one_line(exc, "wavelengths")


@pytest.mark.parametrize("psf", ["abc", np.array([[object()]]), np.zeros((2, 2)) + 1j, None])
def test_otf_mtf_psf_refused(psf: object) -> None:
    for f in (otf, mtf):
        with pytest.raises(InvalidInputError) as exc:
            f(psf, pixel_pitch=1e-6)
        _one_line(exc, "psf")


@pytest.mark.parametrize("frequency", [None, "abc", np.array([0.0, 1j]), np.array([np.nan])])
def test_mtf_frequency_refused(frequency: object) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InvalidInputError) as exc:
            diffraction_limited_mtf(frequency, wavelength=5e-7, f_number=4.0)
        _one_line(exc, "frequency")
        with pytest.raises(InvalidInputError) as exc:
            pixel_mtf(frequency, pixel_pitch=2e-6)
        _one_line(exc, "frequency")


def test_mtf_overflow_refused() -> None:
    with pytest.raises(InvalidInputError, match="float range") as exc:
        diffraction_limited_mtf([0.0, 50.0], wavelength=1e308, f_number=4.0)
    _one_line(exc, "wavelength")
    with pytest.raises(InvalidInputError, match="float range") as exc:
        pixel_mtf([0.0, 50.0], pixel_pitch=1e308)
    _one_line(exc, "pixel_pitch")


def test_result_dataclasses_validated() -> None:
    good = thin_lens(focal_length=0.05, d_o=2.0)
    assert ThinLensSolution(0.05, 2.0, good.d_i, good.magnification, False) == good
    for name, value in (
        ("focal_length", math.nan),
        ("d_o", math.inf),
        ("d_i", 1 + 1j),
        ("magnification", None),
        ("virtual", 0),
    ):
        args = {
            "focal_length": 0.05,
            "d_o": 2.0,
            "d_i": good.d_i,
            "magnification": -0.0256,
            "virtual": False,
        }
        with pytest.raises(InvalidInputError) as exc:
            ThinLensSolution(**{**args, name: value})
        _one_line(exc, name)
    d = depth_of_field(focal_length=0.05, f_number=2.8, focus=2.0, coc=3e-5)
    assert DepthOfField(d.focus, d.near, d.far, d.hyperfocal) == d
    for name, value in (("near", math.nan), ("far", 1j), ("focus", math.inf), ("hyperfocal", None)):
        with pytest.raises(InvalidInputError) as exc:
            DepthOfField(**{**vars(d), name: value})
        _one_line(exc, name)
    with pytest.raises(InvalidInputError, match="near <= focus <= far"):
        DepthOfField(focus=2.0, near=2.5, far=3.0, hyperfocal=30.0)
    with pytest.raises(InvalidInputError, match="far = inf exactly"):
        DepthOfField(focus=2.0, near=1.5, far=math.inf, hyperfocal=30.0)


def test_depth_of_field_extreme_f_number_is_the_documented_limit() -> None:
    # f/1e308 (or a 1e308 m blur circle): everything is acceptably sharp, H -> f, so the
    # near limit -> 0 and the far limit is inf, as documented for focus >= H (the fuzz
    # test lists this as "nonfinite": the inf is the answer)
    d = depth_of_field(focal_length=0.05, f_number=1e308, focus=2.0, coc=3e-5)
    assert d.far == math.inf and d.near == 0.0


def test_apply_vignetting_shape_before_values() -> None:
    # the image's values (NaN here) are not read when its shape cannot match the falloff
    from imageform.optics import apply_vignetting

    with pytest.raises(InvalidInputError, match="falloff") as exc:
        apply_vignetting(np.full((4, 4, 3), np.nan), np.ones((5, 5)))
    _one_line(exc, "image")


def test_zero_d_tensor_broadcasts_to_a_zero_d_result() -> None:
    # an array parameter given as a 0-d tensor gives a 0-d (or (C,)) result, as NumPy
    # broadcasting does: the fuzz test's "wrong_result_shape" for these is expected
    torch = pytest.importorskip("torch")
    from imageform.optics import axial_chromatic_blur_diameters, pupil_overlap_fraction

    one = torch.tensor(1.0)
    for out in (
        diffraction_limited_mtf(one, wavelength=5e-7, f_number=4.0),
        pixel_mtf(one, pixel_pitch=2e-6),
        zernike_radial(2, 0, one),
        pupil_overlap_fraction(1.0, 1.0, one),
    ):
        assert np.shape(out) == () and np.isfinite(out)
    b = axial_chromatic_blur_diameters(
        torch.tensor(3.0), focal_lengths=(0.0501, 0.05, 0.0499), f_number=2.0, focus=2.0
    )
    assert b.shape == (3,) and np.isfinite(b).all()
