"""The wave-optics defocus PSF ([lens] psf = "wave"): the geometric defocus as the pupil's
Zernike defocus term, diffraction included (issue 18, "Optics that diffract")."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import ImageformError
from imageform.optics import blur_by_radius, disc_kernel
from imageform.simulate import default_scene, load_scene, simulate
from imageform.simulate.stages import diffraction_blur, wave_defocus_blur
from tests.simulate.test_diffraction import _scene


def _point(n: int = 81) -> np.ndarray:
    img = np.zeros((n, n, 3))
    img[n // 2, n // 2] = 1.0
    return img


def _rms_radius(g: np.ndarray) -> float:
    c = g.shape[0] // 2
    yy, xx = np.mgrid[-c : c + 1, -c : c + 1]
    return float(np.sqrt((g * (xx**2 + yy**2)).sum() / g.sum()))


def _r50(g: np.ndarray) -> float:
    """The radius holding half the light (a uniform disc of radius R: R / sqrt(2))."""
    c = g.shape[0] // 2
    yy, xx = np.mgrid[-c : c + 1, -c : c + 1]
    rr = np.hypot(xx, yy).ravel()
    order = np.argsort(rr)
    ee = np.cumsum(g.ravel()[order]) / g.sum()
    return float(np.interp(0.5, ee, rr[order]))


def test_large_defocus_tends_to_the_geometric_disc() -> None:
    """A geometric blur radius of 20 pixels at f/4 with 3 um pixels is about 7 waves of
    defocus (W020 = c / (8 N)): the radius holding half the light is within 3 % of the disc's
    (R / sqrt(2)). At 12 pixels (4 waves) it is still 5 % smaller: the PSF of a few waves of
    defocus is not yet a uniform disc."""
    for r in (20.0,):
        out = wave_defocus_blur(_point(141), r, f_number=4.0, pixel_pitch=3e-6)
        assert out.sum(axis=(0, 1)) == pytest.approx([1.0, 1.0, 1.0], abs=1e-9)
        for ch in range(3):
            assert _r50(out[..., ch]) == pytest.approx(r / np.sqrt(2), rel=0.03)
        geo = blur_by_radius(_point(141)[..., 1], r)
        assert _r50(geo) == pytest.approx(r / np.sqrt(2), rel=0.03)


def test_in_focus_it_is_the_airy_pattern() -> None:
    """No defocus: the Airy pattern of each band, as the diffraction stage's (band-limited)
    kernel gives it, to a few per cent of the peak; red's blur is wider than blue's."""
    img = _point(61)
    wave = wave_defocus_blur(img, 0.0, f_number=16.0, pixel_pitch=2e-6)
    airy = diffraction_blur(img, f_number=16.0, pixel_pitch=2e-6)
    for ch in range(3):
        assert np.abs(wave[..., ch] - airy[..., ch]).max() < 0.04 * airy[..., ch].max()
    assert _rms_radius(wave[..., 0]) > _rms_radius(wave[..., 2])


def test_blur_by_radius_kernel_factory() -> None:
    img = np.random.default_rng(0).random((32, 40))
    rad = np.linspace(0.0, 3.0, 32 * 40).reshape(32, 40)
    np.testing.assert_allclose(
        blur_by_radius(img, rad, kernel=disc_kernel), blur_by_radius(img, rad), atol=1e-12
    )
    with pytest.raises(TypeError, match="kernel"):
        blur_by_radius(img, rad, kernel=3)  # type: ignore[arg-type]


def test_scene_psf_wave() -> None:
    """[lens] psf = "wave" renders: light kept, edges softer than the geometric disc's with
    diffraction off (the wave PSF holds the Airy pattern), the default unchanged."""
    assert default_scene().config.lens.psf == "geometric"
    a = simulate(load_scene(_scene())).stage("optics").image
    b = simulate(load_scene(_scene(psf="wave"))).stage("optics").image
    c = simulate(load_scene(_scene(diffraction=True))).stage("optics").image
    assert b.min() >= 0
    assert b.sum() == pytest.approx(a.sum(), rel=3e-3)
    for ch in range(3):
        sharp = np.abs(np.diff(a[..., ch], axis=1)).max()
        assert np.abs(np.diff(b[..., ch], axis=1)).max() < 0.9 * sharp
        # in focus, the wave PSF is the diffraction stage's Airy pattern (point-sampled)
        assert np.abs(b[..., ch] - c[..., ch]).max() < 0.05 * c[..., ch].max()


def test_scene_psf_refused_by_name() -> None:
    with pytest.raises(ImageformError, match=r"lens\.psf"):
        load_scene(_scene(psf="fourier"))


def test_wave_defocus_blur_bad_input() -> None:
    with pytest.raises(ImageformError, match="image"):
        wave_defocus_blur(np.zeros((8, 8)), 1.0, f_number=4.0, pixel_pitch=3e-6)
    with pytest.raises(ImageformError, match="f_number"):
        wave_defocus_blur(_point(9), 1.0, f_number=-1.0, pixel_pitch=3e-6)
