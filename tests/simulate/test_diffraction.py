"""The simulator's optional diffraction blur ([lens] diffraction = true; off by default)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imageform.optics import diffraction_limited_mtf, otf, pixel_mtf
from imageform.simulate import default_scene, load_scene, simulate
from imageform.simulate.stages import diffraction_blur, diffraction_psf_kernel


def _scene(**lens: Any) -> dict[str, Any]:
    # 4 mm lens, fx = 2000 px: pixels of 2 um, so at f/16 the Airy disc (2.44 lambda N) spans
    # about 10 pixels
    return {
        "render": {"width": 64, "height": 48, "supersampling": 1},
        "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
        "camera": {
            "focal_length_mm": 4.0,
            "fx_px": 2000.0,
            "eye_m": [0.0, -1.0, 0.0],
            "target_m": [0.0, 0.0, 0.0],
        },
        "lens": {"defocus": False, "vignetting": "none", "f_number": 16.0, **lens},
        "sensor": {"noise": False, "exposure_time_s": 0.002},
        "processing": {"white_balance": "none", "color_correction": "none", "demosaic": "bilinear"},
        "objects": [
            {"type": "plane", "center_m": [0.0, 0.0, 0.0], "size_m": [20.0, 20.0],
             "reflectance": 0.2},
            {"type": "plane", "center_m": [0.0, -0.001, 0.0], "size_m": [0.005, 0.005],
             "reflectance": 0.9},
        ],
    }  # fmt: skip


def test_off_by_default() -> None:
    assert default_scene().config.lens.diffraction is False
    assert load_scene(_scene()).config.lens.diffraction is False


def test_diffraction_softens_edges_keeps_light_and_reddens_the_blur() -> None:
    a = simulate(load_scene(_scene())).stage("optics").image
    b = simulate(load_scene(_scene(diffraction=True))).stage("optics").image
    assert b.min() >= 0
    for ch in range(3):
        assert (
            np.abs(np.diff(b[..., ch], axis=1)).max()
            < 0.9 * np.abs(np.diff(a[..., ch], axis=1)).max()
        )
    # light is moved, not lost (the background is uniform, so reflected borders keep it)
    assert b.sum() == pytest.approx(a.sum(), rel=2e-3)
    # longer wavelengths diffract more: red's edge is softer than blue's
    edge = [np.abs(np.diff(b[..., ch], axis=1)).max() / np.abs(np.diff(a[..., ch], axis=1)).max()
            for ch in range(3)]  # fmt: skip
    assert edge[0] < edge[2]


def test_kernel_is_the_pixel_integrated_airy_pattern() -> None:
    # one wavelength, well sampled: the kernel's MTF is the circular pupil's times the pixel
    # aperture's sinc (Goodman eq. 6-31), up to the kernel's truncation at 10 lambda N
    lam, fn, pitch = 550e-9, 16.0, 2e-6
    k = diffraction_psf_kernel((lam,), f_number=fn, pixel_pitch=pitch)
    assert k.shape[0] % 2 == 1 and k.sum() == pytest.approx(1.0)
    t = otf(k, pixel_pitch=pitch)
    c = k.shape[0] // 2
    f = t.fx[c:]
    # kernel[n] = (PSF * pixel box)(n p): the optics' MTF times the pixel's (one sinc)
    ref = diffraction_limited_mtf(f, wavelength=lam, f_number=fn) * pixel_mtf(f, pixel_pitch=pitch)
    assert np.abs(np.abs(t.value[c, c:]) - ref).max() < 0.025


def test_tiny_airy_disc_barely_changes_the_image() -> None:
    k = diffraction_psf_kernel(
        (650e-9,), f_number=1.0, pixel_pitch=50e-6
    )  # Airy disc 1.6 um, pixels 50 um
    assert k[k.shape[0] // 2, k.shape[0] // 2] > 0.99
    img = np.random.default_rng(0).uniform(0, 1, (20, 30, 3))
    out = diffraction_blur(img, f_number=1.0, pixel_pitch=50e-6)
    assert out.shape == img.shape and np.abs(out - img).max() < 0.02
