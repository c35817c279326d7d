"""Aberrations, vignetting and defocus as image effects: each checks its physics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.optics import (
    apply_vignetting,
    axial_chromatic_aberration,
    axial_chromatic_blur_diameters,
    blur_by_radius,
    chromatic_focal_lengths,
    circle_of_confusion,
    cos4_falloff,
    defocus_blur,
    disc_kernel,
    lateral_chromatic_aberration,
    mechanical_vignetting,
    pupil_overlap_fraction,
    spherical_aberration,
    spherical_blur_radius,
)


def _radius_of_disc(img: np.ndarray, centre: tuple[float, float]) -> float:
    """Radius of a uniform disc from its second moment: E[r²] = R²/2 (+1/6 for pixel area)."""
    v, u = np.mgrid[0 : img.shape[0], 0 : img.shape[1]]
    w = img / img.sum()
    m2 = float((w * ((u - centre[0]) ** 2 + (v - centre[1]) ** 2)).sum())
    return math.sqrt(2 * (m2 - 1 / 6))


def _point(n: int = 81) -> np.ndarray:
    img = np.zeros((n, n))
    img[n // 2, n // 2] = 1.0
    return img


# -- defocus ----------------------------------------------------------------------------------
@pytest.mark.parametrize("r", [0.0, 0.3, 1.0, 2.5, 7.0])
def test_disc_kernel_normalised_and_radius(r: float) -> None:
    k = disc_kernel(r)
    assert k.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(k, k.T)
    if r >= 2:  # the moment estimate needs a disc several pixels wide
        c = k.shape[0] // 2
        assert _radius_of_disc(k, (c, c)) == pytest.approx(r, rel=0.03)


def test_defocus_blur_diameter_equals_circle_of_confusion() -> None:
    f, n, s, p = 0.05, 2.0, 2.0, 10e-6
    depth = 2.5
    coc = circle_of_confusion(depth, focal_length=f, f_number=n, focus=s)  # metres, a diameter
    out = defocus_blur(_point(), depth, focal_length=f, f_number=n, focus=s, pixel_pitch=p)
    measured_diameter_px = 2 * _radius_of_disc(out, (40, 40))
    assert measured_diameter_px == pytest.approx(coc / p, rel=0.03)
    assert out.sum() == pytest.approx(1.0, abs=1e-9)  # light conserved


def test_defocus_depth_map_sharp_in_focus_blurred_elsewhere() -> None:
    img = np.zeros((41, 81))
    img[20, 20] = img[20, 60] = 1.0
    depth = np.full(img.shape, 2.0)
    depth[:, 40:] = 3.0
    out = defocus_blur(img, depth, focal_length=0.05, f_number=2, focus=2.0, pixel_pitch=10e-6)
    assert out[20, 20] == pytest.approx(1.0)
    assert out[20, 60] < 0.05


def test_blur_by_radius_shapes_and_dtype() -> None:
    img = np.random.default_rng(0).random((20, 30, 3)).astype(np.float32)
    out = blur_by_radius(img, np.linspace(0, 3, 600).reshape(20, 30))
    assert out.shape == img.shape and out.dtype == np.float32
    with pytest.raises(InvalidInputError, match="radius"):
        blur_by_radius(img, -1.0)


# -- spherical aberration ---------------------------------------------------------------------
def test_spherical_blur_grows_with_cube_of_aperture() -> None:
    # TSA ∝ h³ (Smith, Modern Optical Engineering §3.4): halving N → 8 × blur
    r1 = spherical_blur_radius(focal_length=0.05, f_number=4.0, sa_coefficient=0.5)
    r2 = spherical_blur_radius(focal_length=0.05, f_number=2.0, sa_coefficient=0.5)
    assert r2 / r1 == pytest.approx(8.0)
    assert r1 == pytest.approx(0.5 * 0.05 / (32 * 4.0**3))


def test_spherical_aberration_image_blur_radius_and_field_growth() -> None:
    p = 5e-6
    r0 = spherical_blur_radius(focal_length=0.05, f_number=2.0, sa_coefficient=0.25) / p  # 9.77 px
    img = np.zeros((121, 121))
    img[60, 60] = 1.0
    out = spherical_aberration(
        img, focal_length=0.05, f_number=2.0, pixel_pitch=p, sa_coefficient=0.25
    )
    assert _radius_of_disc(out, (60, 60)) == pytest.approx(r0, rel=0.03)
    # with field growth g = 1 the blur is unchanged on axis and larger off axis
    img2 = np.zeros((121, 121))
    img2[60, 60] = img2[60, 110] = 1.0
    out2 = spherical_aberration(
        img2,
        focal_length=0.05,
        f_number=4.0,
        pixel_pitch=p,
        sa_coefficient=0.5,
        field_coefficient=3.0,
    )
    assert out2[60, 60] > 2 * out2[60, 110]


# -- chromatic aberration ---------------------------------------------------------------------
def test_lateral_ca_magnifies_channels_about_centre() -> None:
    h, w = 101, 101
    v, u2 = np.mgrid[0:h, 0:w]
    blob = np.exp(-((u2 - 80.0) ** 2 + (v - 50.0) ** 2) / (2 * 2.0**2))  # 30 px right of centre
    img = np.repeat(blob[..., None], 3, axis=-1)
    out = lateral_chromatic_aberration(img, (1.02, 1.0, 0.98))
    u = np.arange(w)
    for c, m in enumerate((1.02, 1.0, 0.98)):
        row = out[50, :, c]
        centroid = float((row * u).sum() / row.sum())
        # bilinear resampling biases a centroid by up to ~0.01 px; the CA shift here is 0.6 px
        assert centroid - 50 == pytest.approx(30 * m, abs=0.015)
    with pytest.raises(InvalidInputError, match="magnification as 3 values"):
        lateral_chromatic_aberration(img, (1.0, 1.0))


def test_chromatic_focal_lengths_abbe() -> None:
    # f_R - f_B = f / V (Hecht §6.3.2); N-BK7 V_d = 64.17 (Schott datasheet)
    fr, fg, fb = chromatic_focal_lengths(focal_length=0.05, abbe_number=64.17)
    assert fr - fb == pytest.approx(0.05 / 64.17, rel=1e-12) and fg == 0.05


def test_axial_ca_defocus_differs_by_channel() -> None:
    fl = chromatic_focal_lengths(focal_length=0.05, abbe_number=30.0)
    b = axial_chromatic_blur_diameters(
        np.array([2.0, 5.0]), focal_lengths=fl, f_number=2, focus=2.0
    )
    assert b[0, 1] == 0.0 and b[0, 0] > 0 and b[0, 2] > 0
    # equal focal lengths reduce to the circle of confusion
    same = axial_chromatic_blur_diameters(5.0, focal_lengths=(0.05,) * 3, f_number=2, focus=2.0)
    np.testing.assert_allclose(
        same, circle_of_confusion(5.0, focal_length=0.05, f_number=2, focus=2.0), rtol=1e-12
    )
    img = np.zeros((81, 81, 3))
    img[40, 40] = 1.0
    p = 20e-6
    out = axial_chromatic_aberration(
        img, 2.0, focal_lengths=fl, f_number=2, focus=2.0, pixel_pitch=p
    )
    assert out[40, 40, 1] == pytest.approx(1.0)
    r_red = _radius_of_disc(out[..., 0], (40, 40))
    assert 2 * r_red == pytest.approx(b[0, 0] / p, rel=0.03)


# -- vignetting -------------------------------------------------------------------------------
def test_cos4_at_known_field_angle() -> None:
    # a pixel 100 px off-centre with f = 100 px is at 45°: cos⁴ 45° = 0.25 (Hecht §5.7.4)
    fall = cos4_falloff((1, 201), focal_length_px=100.0)
    assert fall[0, 100] == 1.0
    assert fall[0, 200] == pytest.approx(0.25, abs=1e-12)
    # 30°: tan 30° · f off-centre → cos⁴ 30° = 9/16
    f = 100.0
    fall2 = cos4_falloff((1, 1), focal_length_px=f, center=(-f * math.tan(math.pi / 6), 0.0))
    assert fall2[0, 0] == pytest.approx(9 / 16, abs=1e-12)


def test_mechanical_vignetting_overlap() -> None:
    assert pupil_overlap_fraction(1.0, 2.0, 0.5) == 1.0  # pupil inside the barrel
    assert pupil_overlap_fraction(1.0, 1.0, 2.5) == 0.0  # no overlap
    # equal circles at distance a: (2π/3 - √3/2)/π (MathWorld "Circle-Circle Intersection")
    assert pupil_overlap_fraction(1.0, 1.0, 1.0) == pytest.approx(
        (2 * math.pi / 3 - math.sqrt(3) / 2) / math.pi
    )
    v = mechanical_vignetting(
        (1, 201), focal_length_px=100.0, pupil_radius=1.0, barrel_radius=1.2, barrel_distance=1.0
    )
    assert v[0, 100] == 1.0 and np.all(np.diff(v[0, 100:]) <= 0)
    img = np.ones((1, 201, 3))
    out = apply_vignetting(img, v * cos4_falloff((1, 201), focal_length_px=100.0))
    assert out[0, 200, 0] < out[0, 150, 0] < out[0, 100, 0] == 1.0


@pytest.mark.parametrize(
    ("dtype", "want"), [(np.uint8, np.float32), (np.float32, np.float32), (np.float64, np.float64)]
)
def test_effects_dtype_policy(dtype: type, want: type) -> None:
    rng = np.random.default_rng(1)
    base = rng.random((24, 32, 3))
    img = (base * 255).astype(np.uint8) if dtype is np.uint8 else base.astype(dtype)
    outs = [
        lateral_chromatic_aberration(img, (1.01, 1.0, 0.99)),
        spherical_aberration(
            img, focal_length=0.05, f_number=2, pixel_pitch=10e-6, sa_coefficient=0.2
        ),
        defocus_blur(img, 3.0, focal_length=0.05, f_number=2, focus=2.0, pixel_pitch=20e-6),
        axial_chromatic_aberration(
            img,
            3.0,
            focal_lengths=chromatic_focal_lengths(focal_length=0.05, abbe_number=60),
            f_number=2,
            focus=2.0,
            pixel_pitch=20e-6,
        ),
        apply_vignetting(img, cos4_falloff((24, 32), focal_length_px=30.0)),
    ]
    for out in outs:
        assert out.dtype == want and out.shape == img.shape
    with pytest.raises(InvalidInputError, match="0-255"):
        defocus_blur(
            np.round(base * 255), 3.0, focal_length=0.05, f_number=2, focus=2.0, pixel_pitch=20e-6
        )
