"""Diffraction PSFs (imageform.optics.psf): each check against an analytic result or a peer.

Analytic: the diffraction-limited MTF of a circular pupil (Goodman eq. 6-31), the Airy
pattern's first zero at 1.22 lambda N, the Marechal approximation of the Strehl ratio, Parseval
(energy), Zernike orthonormality over the disc (Noll 1976) and symmetry. Peer: prysm (its
Zernike polynomials and its matrix-DFT propagation of the same pupil).
"""

from __future__ import annotations

import importlib.metadata
import math
import sys
import types
from typing import Any

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.optics import (
    diffraction_limited_mtf,
    diffraction_psf,
    field_psfs,
    mtf,
    noll_to_nm,
    otf,
    pixel_mtf,
    polychromatic_psf,
    psf_from_pupil,
    pupil_function,
    zernike,
    zernike_defocus,
    zernike_radial,
    zernike_wavefront,
)

LAM, N = 550e-9, 4.0


def _prysm() -> types.ModuleType:
    """prysm 0.21 reads its version through pkg_resources, which setuptools >= 81 no longer
    ships: give it a stand-in for that one call (importlib.metadata) if it is missing."""
    if "pkg_resources" not in sys.modules:
        try:
            import pkg_resources  # noqa: F401
        except ImportError:
            shim = types.ModuleType("pkg_resources")
            shim.get_distribution = lambda name: types.SimpleNamespace(  # type: ignore[attr-defined]
                version=importlib.metadata.version(name)
            )
            sys.modules["pkg_resources"] = shim
    return pytest.importorskip("prysm")


# --- Zernike -------------------------------------------------------------------------------


def test_noll_table() -> None:
    # Noll (1976) Table I, j = 1..22
    table = [(0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2), (3, -1), (3, 1), (3, -3),
             (3, 3), (4, 0), (4, 2), (4, -2), (4, 4), (4, -4), (5, 1), (5, -1), (5, 3),
             (5, -3), (5, 5), (5, -5), (6, 0)]  # fmt: skip
    assert [noll_to_nm(j) for j in range(1, 23)] == table
    for j in range(1, 200):  # every row n holds n + 1 terms, m of n's parity
        n, m = noll_to_nm(j)
        assert abs(m) <= n and (n - abs(m)) % 2 == 0
        assert n * (n + 1) // 2 < j <= (n + 1) * (n + 2) // 2


def test_zernike_closed_forms() -> None:
    r = np.linspace(0, 1, 11)
    t = np.linspace(-3, 3, 11)
    np.testing.assert_allclose(zernike(4, r, t), math.sqrt(3) * (2 * r**2 - 1), atol=1e-14)
    np.testing.assert_allclose(
        zernike(8, r, t), math.sqrt(8) * (3 * r**3 - 2 * r) * np.cos(t), atol=1e-14
    )
    np.testing.assert_allclose(
        zernike(11, r, t), math.sqrt(5) * (6 * r**4 - 6 * r**2 + 1), atol=1e-14
    )
    np.testing.assert_allclose(zernike(5, r, t), math.sqrt(6) * r**2 * np.sin(2 * t), atol=1e-14)
    np.testing.assert_allclose(zernike_radial(6, 0, 1.0), 1.0)


def test_zernike_orthonormal_over_the_disc() -> None:
    # Gauss-Legendre in rho (exact for these polynomials) x uniform theta (exact for trig)
    x, w = np.polynomial.legendre.leggauss(24)
    rho, wr = (x + 1) / 2, w / 2
    theta = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    weight = (wr * rho)[:, None] * (2 * np.pi / theta.size) / np.pi
    zs = np.stack([zernike(j, rr, tt) for j in range(1, 37)])
    gram = np.einsum("aij,bij,ij->ab", zs, zs, weight)
    np.testing.assert_allclose(gram, np.eye(36), atol=1e-12)


def test_zernike_matches_prysm() -> None:
    _prysm()
    import prysm.polynomials as prysm_poly

    r, t = np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 2 * np.pi, 13), indexing="ij")
    for j in range(1, 37):
        assert prysm_poly.noll_to_nm(j) == noll_to_nm(j)
        n, m = noll_to_nm(j)
        np.testing.assert_allclose(
            zernike(j, r, t), prysm_poly.zernike_nm(n, m, r, t, norm=True), atol=1e-12
        )


def test_wavefront_rms_is_root_sum_square() -> None:
    x, w = np.polynomial.legendre.leggauss(16)
    rho, wr = (x + 1) / 2, w / 2
    theta = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    wgt = (wr * rho)[:, None] / theta.size * 2
    coef = [0.0, 0.0, 0.0, 30e-9, 10e-9, 0.0, 20e-9]  # sequence form: index 0 is j = 1
    wf = zernike_wavefront(coef, rr, tt)
    assert math.sqrt(float((wf**2 * wgt).sum())) == pytest.approx(math.sqrt(14e-16), rel=1e-10)
    assert np.array_equal(zernike_wavefront({4: 30e-9, 5: 10e-9, 7: 20e-9}, rr, tt), wf)


# --- PSF and MTF -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("lam", "fn", "pitch"), [(550e-9, 4.0, 1e-6), (450e-9, 11.0, 1.4e-6), (633e-9, 2.8, 0.5e-6)]
)
def test_mtf_matches_the_analytic_circular_pupil(lam: float, fn: float, pitch: float) -> None:
    h = diffraction_psf(wavelength=lam, f_number=fn, pixel_pitch=pitch, size=None)
    t = mtf(h, pixel_pitch=pitch)
    c = h.shape[0] // 2
    ref = diffraction_limited_mtf(t.fx[c:], wavelength=lam, f_number=fn)
    assert np.abs(t.value[c, c:] - ref).max() < 1e-3  # along x
    assert np.abs(t.value[c:, c] - ref).max() < 1e-3  # along y
    assert t.fx[c] == 0 and t.value[c, c] == pytest.approx(1.0)
    # cut-off 1 / (lambda N) in cycles/mm
    assert np.all(t.value[c, c:][t.fx[c:] > 1.001 / (lam * 1e3 * fn)] < 1e-3)


def test_airy_first_zero_at_1_22_lambda_n() -> None:
    pitch = LAM * N / 16  # 16 samples per lambda N
    h = diffraction_psf(wavelength=LAM, f_number=N, pixel_pitch=pitch, size=129)
    c = 64
    assert h.argmax() == c * 129 + c
    profile = h[c, c : c + 40]
    i = int(np.argmin(profile[5:30])) + 5  # first minimum after the core
    # parabolic refinement of the minimum
    a, b, d = profile[i - 1], profile[i], profile[i + 1]
    x = i + 0.5 * (a - d) / (a - 2 * b + d)
    assert x * pitch == pytest.approx(1.2197 * LAM * N, rel=2e-3)
    assert profile[i] / profile[0] < 1e-3  # a dark ring (the first side lobe is 0.0175)


def test_energy_is_conserved() -> None:
    p = pupil_function({4: 100e-9, 8: 80e-9}, wavelength=LAM, n_samples=100)
    h = psf_from_pupil(p, pad_to=256)
    assert h.sum() == pytest.approx(float((np.abs(p) ** 2).sum()), rel=1e-12)  # Parseval
    # aberrations move light, they do not add or take it
    h0 = psf_from_pupil(pupil_function(wavelength=LAM, n_samples=100), pad_to=256)
    assert h.sum() == pytest.approx(h0.sum(), rel=1e-12)
    k = diffraction_psf({4: 50e-9}, wavelength=LAM, f_number=N, pixel_pitch=1e-6, size=48)
    assert k.sum() == pytest.approx(1.0, abs=1e-12) and k.min() >= 0


@pytest.mark.parametrize("sigma_waves", [0.02, 0.04, 0.07])
@pytest.mark.parametrize("j", [4, 6, 8, 11])
def test_strehl_follows_marechal(sigma_waves: float, j: int) -> None:
    pitch = LAM * N / 4
    kw: dict[str, Any] = {
        "wavelength": LAM,
        "f_number": N,
        "pixel_pitch": pitch,
        "size": None,
        "n_pupil": 128,
    }
    h0 = diffraction_psf(**kw)
    h = diffraction_psf({j: sigma_waves * LAM}, **kw)
    c = h.shape[0] // 2
    strehl = h[c, c] / h0[c, c]  # on-axis intensity (no tilt: the peak stays on axis)
    marechal = math.exp(-((2 * math.pi * sigma_waves) ** 2))
    # Marechal is the first terms of the expansion: error O(sigma^4)
    assert strehl == pytest.approx(marechal, abs=2 * (2 * math.pi * sigma_waves) ** 4 + 2e-3)
    assert strehl < 1


def test_symmetry_defocus_symmetric_coma_not() -> None:
    kw: dict[str, Any] = {"wavelength": LAM, "f_number": N, "pixel_pitch": 1e-6, "size": 65}
    d = diffraction_psf({4: 0.15 * LAM}, **kw)
    for other in (d[::-1, :], d[:, ::-1], d.T):
        np.testing.assert_allclose(other, d, atol=1e-12 * d.max())
    coma = diffraction_psf({8: 0.15 * LAM}, **kw)  # x coma: symmetric in y, not in x
    np.testing.assert_allclose(coma[::-1, :], coma, atol=1e-12 * coma.max())
    assert np.abs(coma[:, ::-1] - coma).max() > 0.05 * coma.max()
    x = np.arange(65) - 32
    assert abs(float((coma.sum(axis=0) * x).sum())) > 0.05  # its centroid is off axis
    # the PSF of a real pupil is centro-symmetric even with coma for opposite sign of W
    coma_neg = diffraction_psf({8: -0.15 * LAM}, **kw)
    np.testing.assert_allclose(coma_neg, coma[::-1, ::-1], atol=1e-12 * coma.max())
    # otf of a symmetric PSF is real
    t = otf(d, pixel_pitch=1e-6)
    assert np.abs(t.value.imag).max() < 1e-10


def test_sampling_follows_the_pitch() -> None:
    # doubling the pitch halves the PSF's width in pixels; below Nyquist it is point-sampled
    fine = diffraction_psf(wavelength=LAM, f_number=N, pixel_pitch=0.5e-6, size=65)
    coarse = diffraction_psf(wavelength=LAM, f_number=N, pixel_pitch=1.0e-6, size=33)
    np.testing.assert_allclose(coarse / coarse.max(), fine[::2, ::2][:33, :33] / fine.max(),
                               atol=1e-3)  # fmt: skip
    under = diffraction_psf(wavelength=LAM, f_number=N, pixel_pitch=3e-6, size=9)  # Q = 0.73
    assert under.shape == (9, 9) and under.argmax() == 40 and under[4, 4] > 0.9


@pytest.mark.parametrize("pitch", [1e-6, 3e-6])  # Q = 2.2 and 0.73 (oversampled, then sampled)
def test_cropped_psf_is_the_full_grid_cropped(pitch: float) -> None:
    kw: dict[str, Any] = {"wavelength": LAM, "f_number": N, "pixel_pitch": pitch}
    coef = {4: 40e-9, 7: 30e-9}
    full = diffraction_psf(coef, size=None, **kw)
    crop = diffraction_psf(coef, size=21, **kw)
    c = full.shape[0] // 2
    part = full[c - 10 : c + 11, c - 10 : c + 11]
    np.testing.assert_allclose(crop, part / part.sum(), rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("pitch", [1e-6, 0.9e-6, 0.5e-6])
def test_given_aperture_matches_the_circle_and_the_exact_dft(pitch: float) -> None:
    d = 200
    c = np.arange(d + 2) - (d + 2) // 2
    disc = np.hypot(c[:, None], c[None, :]) <= d / 2
    ap = disc[1 : d + 1, 1 : d + 1]  # the array spans the pupil diameter: d samples
    kw: dict[str, Any] = {"wavelength": LAM, "f_number": N, "pixel_pitch": pitch, "size": 33}
    h_ap = diffraction_psf({7: 40e-9}, aperture=ap, **kw)
    h = diffraction_psf({7: 40e-9}, n_pupil=d, **kw)
    assert np.abs(h_ap - h).max() < 1e-3 * h.max()
    # the same pupil by a direct (matrix) DFT at exactly the requested image points: checks
    # the cubic resampling used when Q * d is not a whole FFT length
    p = pupil_function({7: 40e-9}, wavelength=LAM, aperture=ap)
    x = (np.arange(d) - d // 2) / d  # pupil coordinates, units of D
    u = (np.arange(33) - 16) * pitch / (LAM * N)  # image coordinates, units of lambda N
    a = np.exp(-2j * np.pi * np.outer(u, x))
    ref = np.abs(a @ p @ a.T) ** 2
    ref /= ref.sum()
    assert np.abs(h_ap - ref).max() < 1e-3 * ref.max()


def test_polychromatic_is_the_weighted_sum() -> None:
    kw: dict[str, Any] = {"f_number": N, "pixel_pitch": 1e-6, "size": 33}
    lams, w = [450e-9, 650e-9], [1.0, 3.0]
    poly = polychromatic_psf({4: 40e-9}, wavelengths=lams, weights=w, **kw)
    mono = [diffraction_psf({4: 40e-9}, wavelength=lam, **kw) for lam in lams]
    np.testing.assert_allclose(poly, 0.25 * mono[0] + 0.75 * mono[1], atol=1e-15)
    assert poly.sum() == pytest.approx(1.0)


def test_field_psfs_by_zone() -> None:
    c = np.zeros((2, 2, 8))
    c[1, 1, 7] = 0.2 * LAM  # coma in one corner zone
    out = field_psfs(c, wavelength=LAM, f_number=N, pixel_pitch=1e-6, size=33)
    assert out.shape == (2, 2, 33, 33)
    np.testing.assert_allclose(out[0, 0], out[0, 1])
    np.testing.assert_allclose(out[1, 1], diffraction_psf(c[1, 1], wavelength=LAM, f_number=N,
                                                          pixel_pitch=1e-6, size=33))  # fmt: skip
    assert out[1, 1].max() < out[0, 0].max()


def test_same_pupil_psf_as_prysm() -> None:
    from scipy import fft

    prysm = _prysm()
    from prysm.propagation import focus_fixed_sampling

    pitch, size, npup = 1e-6, 64, 256
    for coef in ({}, {4: 40e-9, 7: 30e-9, 11: 20e-9}, {6: 60e-9, 8: -50e-9}):
        h = diffraction_psf(coef, wavelength=LAM, f_number=N, pixel_pitch=pitch, size=size)
        q = LAM * N / pitch  # the pupil diffraction_psf draws: D = M / Q samples wide
        d = fft.next_fast_len(max(math.ceil(q * npup), size + 1, 8)) / q
        p = pupil_function(coef, wavelength=LAM, n_samples=d)
        dmm = 10.0  # any pupil diameter: only f / D = N matters
        e = focus_fixed_sampling(p, dmm / d, dmm * N, LAM * 1e6, pitch * 1e6, size)
        hp = np.abs(e) ** 2
        hp /= hp.sum()
        assert np.abs(h - hp).max() < 1e-3 * h.max(), prysm.__version__


def test_refusals() -> None:
    kw: dict[str, Any] = {"wavelength": LAM, "f_number": N, "pixel_pitch": 1e-6}
    with pytest.raises(InvalidInputError, match="wavelength"):
        diffraction_psf(wavelength=-1.0, f_number=N, pixel_pitch=1e-6)
    with pytest.raises(InvalidInputError, match="Noll"):
        diffraction_psf({0: 1e-7}, **kw)
    with pytest.raises(InvalidInputError, match="coefficients"):
        diffraction_psf("defocus", **kw)
    with pytest.raises(InvalidInputError, match="aperture"):
        diffraction_psf(aperture=np.ones((4, 5)), **kw)
    with pytest.raises(InvalidInputError, match="weights"):
        polychromatic_psf(wavelengths=[5e-7, 6e-7], weights=[1.0], f_number=N, pixel_pitch=1e-6)
    with pytest.raises(InvalidInputError, match=r"n - \|m\|"):
        zernike_radial(3, 0, 0.5)
    with pytest.raises(InvalidInputError, match=r"rows, cols, J"):
        field_psfs(np.zeros(8), **kw)


def test_zernike_defocus_tends_to_the_geometric_disc() -> None:
    # a large defocus: the PSF approaches the geometric disc of the circle of confusion
    c, pitch = 120e-6, 1e-6
    c4 = zernike_defocus(c, f_number=N)
    assert c4 == pytest.approx(c / (16 * math.sqrt(3) * N))
    h = diffraction_psf({4: c4}, wavelength=LAM, f_number=N, pixel_pitch=pitch, size=201)
    y, x = np.indices(h.shape) - 100
    r = np.hypot(x, y) * pitch
    # a uniform disc holds frac of its light within sqrt(frac) R; diffraction softens its rim
    # (the geometric shadow's edge has a quarter of the inner intensity), so looser there
    for frac, tol in ((0.25, 0.02), (0.5, 0.02), (0.75, 0.08)):
        assert h[r <= c / 2 * math.sqrt(frac)].sum() == pytest.approx(frac, abs=tol)
    assert h[r <= 1.1 * c / 2].sum() > 0.95
    np.testing.assert_allclose(zernike_defocus(np.array([0.0, c]), f_number=N), [0.0, c4])


def test_pixel_mtf() -> None:
    f = np.array([0.0, 125.0, 250.0, 500.0])  # cycles/mm for 2 um pixels: 0, 1/4, Nyquist, 1
    np.testing.assert_allclose(
        pixel_mtf(f, pixel_pitch=2e-6),
        [1.0, math.sin(math.pi / 4) / (math.pi / 4), 2 / math.pi, 0],
        atol=1e-15,
    )
    # a quarter fill factor halves the aperture's width: its first zero moves to 2 / p
    assert pixel_mtf(1000.0, pixel_pitch=2e-6, fill_factor=0.25) < 1e-15
    with pytest.raises(InvalidInputError, match="fill_factor"):
        pixel_mtf(1.0, pixel_pitch=2e-6, fill_factor=1.5)
