"""ISO 12233 slanted-edge e-SFR (imageform.analysis.sfr) against edges of known MTF.

Truths: a Gaussian PSF of standard deviation sigma has the MTF exp(-2 pi^2 sigma^2 f^2); an
aberration-free circular pupil has Goodman's eq. 6-31 (imageform.optics.diffraction_limited_mtf);
an edge integrated over square pixels at angle theta multiplies either by the pixel
aperture's transfer along the edge normal, sinc(f cos theta) sinc(f sin theta).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.optimize import brentq

from imageform.analysis import (
    SFRResult,
    find_slanted_edges,
    mtf_crossing,
    render_sfr_chart,
    render_slanted_edge,
    slanted_edge_sfr,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from imageform.optics import diffraction_limited_mtf

ANGLES = (2.0, 3.0, 5.0, 7.0, 10.0)
PITCH = 2e-6  # m: frequencies in cycles/pixel are cycles/mm times 2e-3
WAVELENGTH = 550e-9


def _pixel(f: np.ndarray, angle: float) -> np.ndarray:
    t = math.radians(angle)
    return np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t))


def gauss_truth(f: np.ndarray, sigma: float, angle: float) -> np.ndarray:
    return np.exp(-2 * np.pi**2 * sigma**2 * np.asarray(f) ** 2) * _pixel(np.asarray(f), angle)


def diffraction_mtf(f: np.ndarray, f_number: float) -> np.ndarray:
    """The circular pupil's MTF at ``f`` cycles/pixel (2 um pixels, 550 nm)."""
    return diffraction_limited_mtf(
        np.asarray(f) / PITCH * 1e-3, wavelength=WAVELENGTH, f_number=f_number
    )


def diffraction_truth(f: np.ndarray, f_number: float, angle: float) -> np.ndarray:
    return diffraction_mtf(f, f_number) * _pixel(np.asarray(f), angle)


def crossing(truth, level: float) -> float:  # type: ignore[no-untyped-def]
    return float(brentq(lambda f: float(truth(f)) - level, 1e-6, 0.99))


_ESF_CACHE: dict[float, object] = {}


def diffraction_esf(f_number: float):  # type: ignore[no-untyped-def]
    """ESF of the circular pupil, from its MTF convolved in frequency:
    ESF(d) = 1/2 + (1/pi) int_0^fc MTF(f) sin(2 pi f d) / f df, tabulated and interpolated."""
    if f_number not in _ESF_CACHE:
        fc = PITCH / (WAVELENGTH * f_number)
        f = np.linspace(1e-9, fc, 1201)
        d = np.linspace(-60.0, 60.0, 8001)
        m = diffraction_mtf(f, f_number)
        vals = 0.5 + simpson(
            m[None, :] * np.sin(2 * np.pi * f[None, :] * d[:, None]) / (np.pi * f[None, :]),
            x=f,
            axis=1,
        )
        _ESF_CACHE[f_number] = (d, vals)
    d, vals = _ESF_CACHE[f_number]  # type: ignore[misc]
    return lambda x: np.interp(x, d, vals)


# --- known MTFs ------------------------------------------------------------------------------


@pytest.mark.parametrize("sigma", [0.5, 0.8, 1.2])
@pytest.mark.parametrize("angle", ANGLES)
def test_gaussian_edge_mtf50_mtf10_and_curve(sigma: float, angle: float) -> None:
    img = render_slanted_edge((80, 80), angle_deg=angle, sigma=sigma)
    r = slanted_edge_sfr(img)
    assert isinstance(r, SFRResult)
    assert r.channels == ("Y",) and r.orientation == "vertical"
    assert r.angle == pytest.approx(angle, abs=0.02)
    truth = lambda f: gauss_truth(f, sigma, angle)  # noqa: E731
    assert r.mtf50[0] == pytest.approx(crossing(truth, 0.5), rel=0.02)
    assert r.mtf10[0] == pytest.approx(crossing(truth, 0.1), rel=0.02)
    # the whole curve to Nyquist: within 0.01 (measured <= 0.0075)
    sel = r.frequency <= 0.5
    assert np.abs(r.sfr[sel, 0] - truth(r.frequency[sel])).max() < 0.01
    assert r.sfr[0, 0] == pytest.approx(1.0)


@pytest.mark.parametrize("f_number", [4.0, 8.0])
@pytest.mark.parametrize("angle", [2.0, 5.0, 10.0])
def test_diffraction_limited_edge(f_number: float, angle: float) -> None:
    img = render_slanted_edge((100, 100), angle_deg=angle, esf=diffraction_esf(f_number))
    r = slanted_edge_sfr(img)
    truth = lambda f: diffraction_truth(f, f_number, angle)  # noqa: E731
    assert r.mtf50[0] == pytest.approx(crossing(truth, 0.5), rel=0.02)
    # the Airy LSF's slow tails are cut by the 100-px ROI and the window: within 0.025
    sel = r.frequency <= 0.5
    assert np.abs(r.sfr[sel, 0] - truth(r.frequency[sel])).max() < 0.025


@pytest.mark.parametrize("sigma", [0.5, 0.8])
@pytest.mark.parametrize("angle", [2.0, 5.0, 10.0])
def test_noise_snr50(sigma: float, angle: float) -> None:
    """SNR 50 (edge contrast / noise standard deviation) in a 200 x 64 ROI (200 rows along
    the edge): every one of 10 noisy copies within 5 %, their mean within 2 %. (In a
    128 x 64 ROI the sharpest edge, sigma 0.5 px, strays up to 6 %.)"""
    img = render_slanted_edge((200, 64), angle_deg=angle, sigma=sigma, low=0.2, high=0.8)
    f50 = crossing(lambda f: gauss_truth(f, sigma, angle), 0.5)
    rng = np.random.default_rng(12233)
    got = np.array(
        [slanted_edge_sfr(img + rng.normal(0, 0.6 / 50, img.shape)).mtf50[0] for _ in range(10)]
    )
    assert np.abs(got / f50 - 1).max() < 0.05
    assert got.mean() == pytest.approx(f50, rel=0.02)


def test_two_point_derivative_and_polynomial_edge() -> None:
    img = render_slanted_edge((80, 80), angle_deg=4.0, sigma=0.7)
    f50 = crossing(lambda f: gauss_truth(f, 0.7, 4.0), 0.5)
    two = slanted_edge_sfr(img, derivative="two-point")
    assert two.mtf50[0] == pytest.approx(f50, rel=0.02)
    quad = slanted_edge_sfr(img, edge_order=2)
    assert quad.mtf50[0] == pytest.approx(f50, rel=0.02)
    assert quad.edge.shape == (1, 3) and abs(quad.edge[0, 0]) < 1e-3


def test_uncorrected_derivative_is_lower() -> None:
    """Without the finite-difference correction the SFR would sit below the truth by the
    FIR's sinc(2 f / 4): the corrected curve is the one on the truth at Nyquist."""
    img = render_slanted_edge((80, 80), angle_deg=5.0, sigma=0.5)
    r = slanted_edge_sfr(img)
    k = int(np.argmin(np.abs(r.frequency - 0.5)))
    t = gauss_truth(r.frequency[k], 0.5, 5.0)
    assert r.sfr[k, 0] == pytest.approx(t, abs=0.01)
    assert r.sfr[k, 0] * np.sinc(2 * 0.5 / 4) < t - 0.01


def test_horizontal_edge_and_roi() -> None:
    vert = render_slanted_edge((80, 80), angle_deg=6.0, sigma=0.8)
    hor = render_slanted_edge((80, 80), angle_deg=6.0, sigma=0.8, orientation="horizontal")
    np.testing.assert_allclose(hor, vert.T, atol=1e-12)
    rv, rh = slanted_edge_sfr(vert), slanted_edge_sfr(hor)
    assert rh.orientation == "horizontal"
    assert rh.mtf50[0] == pytest.approx(rv.mtf50[0], rel=1e-9)
    big = np.full((120, 150), 0.2)
    big[20:100, 40:120] = vert
    rr = slanted_edge_sfr(big, roi=(40, 20, 80, 80))
    assert rr.mtf50[0] == pytest.approx(rv.mtf50[0], rel=1e-9)


def test_rgb_channels_and_luminance() -> None:
    sig = (1.0, 0.7, 0.5)
    img = np.stack([render_slanted_edge((80, 80), angle_deg=5.0, sigma=s) for s in sig], axis=2)
    r = slanted_edge_sfr(img)
    assert r.channels == ("R", "G", "B", "Y")
    assert r.sfr.shape[1] == 4 and r.mtf50.shape == (4,)
    for k, s in enumerate(sig):
        assert r.mtf50[k] == pytest.approx(
            crossing(lambda f, s=s: gauss_truth(f, s, 5.0), 0.5), rel=0.02
        )
    # Y is linear in R, G, B and the edges coincide: its SFR is the weighted mean
    mix = r.sfr[:, :3] @ np.array([0.213, 0.715, 0.072])
    sel = r.frequency <= 0.5
    assert np.abs(r.sfr[sel, 3] - mix[sel]).max() < 0.01
    np.testing.assert_array_equal(r.channel("G"), r.sfr[:, 1])


def test_integer_images() -> None:
    img = render_slanted_edge((80, 80), angle_deg=5.0, sigma=0.8)
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    r16 = slanted_edge_sfr(np.round(img * 65535).astype(np.uint16))
    assert r16.mtf50[0] == pytest.approx(f50, rel=0.02)
    r8 = slanted_edge_sfr(np.round(img * 255).astype(np.uint8))
    assert r8.mtf50[0] == pytest.approx(f50, rel=0.03)


def test_mtf_crossing() -> None:
    assert mtf_crossing([0.0, 0.1, 0.2], [1.0, 0.6, 0.4], 0.5) == pytest.approx(0.15)
    assert math.isnan(mtf_crossing([0.0, 0.1], [1.0, 0.9], 0.5))


# --- refusals --------------------------------------------------------------------------------


def test_refusals() -> None:
    edge = render_slanted_edge((40, 40), angle_deg=5.0, sigma=0.8)
    with pytest.raises(DegenerateConfigurationError, match="too close to vertical"):
        slanted_edge_sfr(render_slanted_edge((40, 40), angle_deg=0.0, sigma=0.8))
    with pytest.raises(DegenerateConfigurationError, match="no edge"):
        slanted_edge_sfr(np.full((40, 40), 0.5))
    with pytest.raises(UnknownOptionError, match="derivative"):
        slanted_edge_sfr(edge, derivative="sobel")
    with pytest.raises(InvalidInputError, match="roi"):
        slanted_edge_sfr(edge, roi=(30, 0, 20, 20))
    with pytest.raises(InvalidInputError, match="at least 8"):
        slanted_edge_sfr(edge, roi=(0, 0, 6, 40))
    with pytest.raises(InvalidInputError, match="NaN"):
        slanted_edge_sfr(np.where(edge > 0.5, np.nan, edge))
    with pytest.raises(InvalidInputError, match="shape"):
        slanted_edge_sfr(np.zeros((4, 4, 4)))
    with pytest.raises(InvalidInputError, match="oversampling"):
        slanted_edge_sfr(edge, oversampling=0)
    with pytest.raises(InvalidInputError, match="weights"):
        slanted_edge_sfr(np.stack([edge] * 3, axis=2), weights=(1.0, 0.0))
    with pytest.raises(InvalidInputError, match="name"):
        slanted_edge_sfr(edge).channel("R")


# --- the chart ---------------------------------------------------------------------------


def test_find_edges_in_a_chart_and_measure_them() -> None:
    img = render_sfr_chart((240, 320), grid=(2, 3), angle_deg=5.0, sigma=0.8, supersampling=4)
    rois = find_slanted_edges(img)
    assert len(rois) == 24  # 6 squares x 4 sides
    assert sorted(r.side for r in rois).count("left") == 6
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    for roi in rois:
        assert abs(roi.angle) == pytest.approx(5.0, abs=0.1)
        r = slanted_edge_sfr(img, roi.roi)
        assert r.orientation == roi.orientation
        assert r.angle == pytest.approx(roi.angle, abs=0.1)
        assert r.mtf50[0] == pytest.approx(f50, rel=0.02)
        assert roi.crop(img).shape == (roi.height, roi.width)


def test_find_edges_filters_by_angle_and_noise() -> None:
    upright = render_sfr_chart((120, 160), grid=(1, 1), angle_deg=0.0, supersampling=2)
    assert find_slanted_edges(upright) == []
    steep = render_sfr_chart((160, 160), grid=(1, 1), angle_deg=15.0, supersampling=2)
    assert find_slanted_edges(steep) == []
    assert len(find_slanted_edges(steep, max_angle=20.0)) == 4
    img = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=-7.0, supersampling=2)
    noisy = img + np.random.default_rng(3).normal(0, 0.012, img.shape)
    rois = find_slanted_edges(noisy)
    assert len(rois) == 4
    assert all(abs(r.angle) == pytest.approx(7.0, abs=0.3) for r in rois)
    rgb = np.repeat(img[:, :, None], 3, axis=2)
    assert len(find_slanted_edges(rgb)) == 4
    with pytest.raises(InvalidInputError, match="max_angle"):
        find_slanted_edges(img, min_angle=5.0, max_angle=3.0)


# --- the simulator's lens stage ------------------------------------------------------------


def _kernel_mtf(kernel: np.ndarray, f: np.ndarray, angle: float) -> np.ndarray:
    """|DTFT| of a centred 2-D kernel along the edge normal (cos t, -sin t)."""
    t = math.radians(angle)
    n = kernel.shape[0]
    i, j = np.mgrid[0:n, 0:n] - n // 2
    arg = j.ravel()[None, :] * math.cos(t) - i.ravel()[None, :] * math.sin(t)
    return np.abs(np.exp(-2j * np.pi * f[:, None] * arg) @ kernel.ravel())


@pytest.mark.parametrize("f_number", [2.8, 4.0, 8.0])
def test_simulator_diffraction_stage(f_number: float) -> None:
    """A step edge integrated over the pixels (the renderer's supersampled pixels) through
    imageform.simulate's diffraction stage. The stage's kernel carries the optics alone: its
    DTFT is the continuous band-averaged pupil MTF to 0.02 up to Nyquist, so the simulated
    edge's MTF is the pixel box's times the pupil's, as in a camera (the earlier
    pixel-integrated kernel counted the pixel twice: up to 17 % off at f/2.8). Every
    channel's measured MTF50 within 3 % of that continuous model (a 96-column ROI, wide
    enough for the Airy wings at f/8)."""
    from imageform.optics import diffraction_limited_mtf
    from imageform.simulate.stages import (
        DIFFRACTION_BANDS,
        diffraction_blur,
        diffraction_psf_kernel,
    )

    angle = 5.0
    step = render_slanted_edge((160, 128), angle_deg=angle, sigma=0.0, supersampling=16)
    out = diffraction_blur(
        np.repeat(step[:, :, None], 3, axis=2), f_number=f_number, pixel_pitch=PITCH
    )
    r = slanted_edge_sfr(out[16:-16, 16:-16])
    f = np.linspace(0.0, 1.0, 1001)
    for k, band in enumerate(reversed(DIFFRACTION_BANDS)):  # R, G, B
        kernel = diffraction_psf_kernel(band, f_number=f_number, pixel_pitch=PITCH)
        optics = np.mean(
            [
                diffraction_limited_mtf(f / (PITCH * 1e3), wavelength=w, f_number=f_number)
                for w in band
            ],
            axis=0,
        )
        nyq = f <= 0.5
        assert np.abs(_kernel_mtf(kernel, f, 0.0)[nyq] - optics[nyq]).max() < 0.02
        model = optics * _pixel(f, angle)
        assert r.mtf50[k] == pytest.approx(mtf_crossing(f, model, 0.5), rel=0.03)


def test_curved_edge_needs_the_polynomial_fit() -> None:
    """An edge bowed by 1.5 px over 96 rows (barrel distortion): a line fit smears the ESF
    (MTF50 10 % low), the quadratic fit of ISO 12233:2017 / sfrmat5 recovers it."""
    from scipy.special import ndtr

    h = w = 96
    s, sigma = 16, 0.8
    off = (np.arange(s) + 0.5) / s - 0.5
    u = (np.arange(w)[:, None] + off).ravel()[None, :]
    v = (np.arange(h)[:, None] + off).ravel()[:, None]
    b, k, yc = math.tan(math.radians(5.0)), 1.5 / (h / 2) ** 2, (h - 1) / 2
    xe = (w - 1) / 2 + b * (v - yc) + k * (v - yc) ** 2
    d = (u - xe) * np.cos(np.arctan(b + 2 * k * (v - yc)))
    img = (0.2 + 0.6 * ndtr(d / sigma)).reshape(h, s, w, s).mean(axis=(1, 3))
    f50 = crossing(lambda f: gauss_truth(f, sigma, 5.0), 0.5)
    assert slanted_edge_sfr(img).mtf50[0] < 0.95 * f50
    quad = slanted_edge_sfr(img, edge_order=2)
    assert quad.mtf50[0] == pytest.approx(f50, rel=0.02)
    assert quad.edge[0, 0] == pytest.approx(k, rel=0.05)


def _slanted_square(S: int, N: float = 8.0) -> np.ndarray:
    """A dark square (24 mm, reflectance 0.1) turned 5 deg on a light background (0.8),
    ray-cast by imageform.simulate's renderer (S x S supersampling) and blurred by its lens
    stage (diffraction at f/``N``, 2 um pixels; no defocus, vignetting or colour shift);
    benchmarks/bench_sfr.py renders the same."""
    from imageform.simulate import load_scene
    from imageform.simulate.render import render_scene
    from imageform.simulate.stages import apply_lens

    a = math.radians(5.0)
    scene = load_scene(
        {
            "name": "slanted edge",
            "render": {
                "width": 288,
                "height": 240,
                "supersampling": S,
                "background_reflectance": 0.8,
            },
            "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
            "camera": {
                "focal_length_mm": 10.0,
                "pixel_pitch_um": 2.0,
                "eye_m": [0.0, -1.0, 0.0],
                "target_m": [0.0, 0.0, 0.0],
                "up": [0.0, 0.0, 1.0],
            },
            "lens": {
                "f_number": N,
                "focus_distance_m": 1.0,
                "defocus": False,
                "vignetting": "none",
                "lateral_ca": [1.0, 1.0, 1.0],
                "diffraction": True,
            },
            "objects": [
                {
                    "type": "plane",
                    "name": "dark square",
                    "center_m": [0.0, 0.0, 0.0],
                    "normal": [0.0, -1.0, 0.0],
                    "up": [math.sin(a), 0.0, math.cos(a)],
                    "size_m": [0.024, 0.024],
                    "reflectance": 0.1,
                }
            ],
        }
    )
    rendered = render_scene(scene)
    return apply_lens(
        rendered, scene.camera, scene.config.lens, scene.config.camera.focal_length_mm
    )


def _sub_box(x: np.ndarray, S: int) -> np.ndarray:
    """|MTF| of the mean of S point samples across a pixel: sin(pi x) / (S sin(pi x / S))."""
    out = np.ones_like(x)
    nz = np.abs(x) > 1e-12
    out[nz] = np.sin(np.pi * x[nz]) / (S * np.sin(np.pi * x[nz] / S))
    return np.abs(out)


def test_simulator_rendered_edge_within_3_percent_of_its_own_mtf() -> None:
    """A dark square turned 5 deg on a light background, ray-cast by imageform.simulate's
    renderer (S x S supersampling) and blurred by its lens stage (diffraction at f/8, 2 um
    pixels; no defocus, vignetting or colour shift). The simulator's own MTF along the edge
    normal is the S-point box of each axis, sin(pi x) / (S sin(pi x / S)) at x = f cos t and
    f sin t, times the DTFT of the stage's kernel (the optics' MTF). A 24 mm square and
    96-pixel ROIs, wide enough for the Airy wings at f/8 (a 56-pixel ROI cut them: +3.5 % in
    red). Every edge the finder returns, every channel: MTF50 within 3 % (measured +0.2 to
    +1.4 %)."""
    from imageform.simulate.stages import DIFFRACTION_BANDS, diffraction_psf_kernel

    S, N = 4, 8.0
    img = _slanted_square(S, N)
    rois = find_slanted_edges(img, roi_width=96, roi_length=0.7)
    assert sorted(r.side for r in rois) == ["bottom", "left", "right", "top"]
    f = np.linspace(0.0, 1.0, 1001)

    kernels = [
        diffraction_psf_kernel(band, f_number=N, pixel_pitch=PITCH)
        for band in reversed(DIFFRACTION_BANDS)
    ]
    for roi in rois:
        r = slanted_edge_sfr(img, roi.roi)
        assert abs(r.angle) == pytest.approx(5.0, abs=0.1)
        t = math.radians(abs(r.angle))
        for k, kernel in enumerate(kernels):
            own = (
                _kernel_mtf(kernel, f, r.angle)
                * _sub_box(f * math.cos(t), S)
                * _sub_box(f * math.sin(t), S)
            )
            assert r.mtf50[k] == pytest.approx(mtf_crossing(f, own, 0.5), rel=0.03)


@pytest.mark.parametrize(("sigma", "angle"), [(0.0, 0.0), (0.6, 5.0), (1.3, 8.0)])
def test_fit_gaussian_sigma_recovers_the_model(sigma: float, angle: float) -> None:
    """A model SFR (a Gaussian times the tilted pixel aperture) gives its sigma back, NaN
    samples and frequencies above Nyquist ignored."""
    from imageform.analysis import fit_gaussian_sigma

    f = np.linspace(0.0, 1.0, 101)
    t = math.radians(angle)
    s = np.exp(-2 * np.pi**2 * sigma**2 * f**2) * np.abs(
        np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t))
    )
    s[70:] = np.nan
    assert fit_gaussian_sigma(f, s, angle_deg=angle) == pytest.approx(sigma, abs=1e-3)


def test_fit_gaussian_sigma_refusals() -> None:
    from imageform.analysis import fit_gaussian_sigma

    with pytest.raises(InvalidInputError, match="one length"):
        fit_gaussian_sigma(np.linspace(0, 0.5, 5), np.ones(4))
    with pytest.raises(InvalidInputError, match="finite value"):
        fit_gaussian_sigma(np.linspace(0.6, 1.0, 5), np.ones(5))
    with pytest.raises(InvalidInputError, match="angle_deg"):
        fit_gaussian_sigma(np.linspace(0, 0.5, 5), np.ones(5), angle_deg=120.0)


# --- finding edges in real charts: grey surrounds, notched sides, clutter beside an edge -------


def _square_on_grey_surround() -> np.ndarray:
    """A dark square (0.2) on its own grey surround (0.45), on white paper with a black patch.

    Like the ISO 12233 e-SFR charts: the halfway threshold of the whole image (0.46) takes
    the surround as dark too, so only a level between the square's two greys separates it.
    """
    chart = render_sfr_chart(
        (160, 160), grid=(1, 1), angle_deg=5.0, sigma=0.8, low=0.2, high=0.45, supersampling=4
    )
    img = np.full((300, 400), 0.9)
    img[70:230, 40:200] = chart
    img[100:180, 260:340] = 0.02
    return img


def test_find_edges_of_a_square_on_its_own_grey_surround() -> None:
    img = _square_on_grey_surround()
    rois = find_slanted_edges(img)
    assert sorted(r.side for r in rois) == ["bottom", "left", "right", "top"]
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    for roi in rois:
        assert abs(roi.angle) == pytest.approx(5.0, abs=0.1)
        assert slanted_edge_sfr(img, roi.roi).mtf50[0] == pytest.approx(f50, rel=0.02)


def _left_side(img: np.ndarray) -> tuple[float, float, float]:
    (roi,) = [r for r in find_slanted_edges(img) if r.side == "left"]
    return roi.center[0], roi.center[1], math.tan(math.radians(roi.angle))


def test_a_notched_side_is_not_an_edge() -> None:
    img = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    u0, v0, slope = _left_side(img)
    notched = img.copy()
    for v in range(int(v0) - 6, int(v0) + 7):  # a 13-row notch, 5 px deep, mid-side
        u = u0 + slope * (v - v0)
        notched[v, int(u) - 2 : int(u) + 6] = 0.8
    rois = find_slanted_edges(notched)
    assert sorted(r.side for r in rois) == ["bottom", "right", "top"]


def test_a_faint_line_beside_an_edge_drops_its_roi() -> None:
    # a printed guide line 12 px from the side, 30 % of the contrast: inside the side's ROI,
    # where ISO 12233 wants a uniform area
    img = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    u0, v0, slope = _left_side(img)
    lined = img.copy()
    for v in range(int(v0) - 30, int(v0) + 31):
        u = u0 - 12 + slope * (v - v0)
        lined[v, round(u) - 1 : round(u) + 1] = 0.62
    rois = find_slanted_edges(lined)
    assert sorted(r.side for r in rois) == ["bottom", "right", "top"]


def test_an_edge_crop_is_found_whole() -> None:
    # sfrmat's input: a crop around one edge, both areas reaching the border
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    for ori, side in (("vertical", "right"), ("horizontal", "bottom")):
        img = render_slanted_edge((100, 60), angle_deg=5.0, sigma=0.8, orientation=ori)
        (roi,) = find_slanted_edges(img)
        assert (roi.x, roi.y) == (0, 0) and roi.crop(img).shape == img.shape
        assert (roi.orientation, roi.side) == (ori, side)
        assert abs(roi.angle) == pytest.approx(5.0, abs=0.1)
        assert slanted_edge_sfr(img, roi.roi).mtf50[0] == pytest.approx(f50, rel=0.02)
    flipped = render_slanted_edge((100, 60), angle_deg=5.0, sigma=0.8)[:, ::-1]
    assert [r.side for r in find_slanted_edges(flipped)] == ["left"]
    # not one edge: a bar (two edges), an upright edge, an edge too steep for max_angle
    rise = render_slanted_edge((100, 60), angle_deg=5.0, center=(20, 50))  # light from u=20
    fall = render_slanted_edge((100, 60), angle_deg=5.0, center=(19, 50))[:, ::-1]  # to u=40
    bar = rise + fall - 0.8
    assert bar[50, [5, 30, 55]].round(1).tolist() == [0.2, 0.8, 0.2]
    assert find_slanted_edges(bar) == []
    assert find_slanted_edges(render_slanted_edge((100, 60), angle_deg=0.0)) == []
    assert find_slanted_edges(render_slanted_edge((100, 60), angle_deg=15.0)) == []


@pytest.mark.parametrize(
    ("angle", "shape"),
    [
        (20.0, (120, 120)),
        (35.0, (120, 120)),
        (41.0, (120, 120)),
        (43.0, (120, 120)),
        (25.0, (200, 100)),
    ],
)
def test_steep_edges_bin_along_the_rows(angle: float, shape: tuple[int, int]) -> None:
    # binning the distance along the normal steps q cos(theta) bins per pixel: the phases
    # bunch at some angles (-2.6 % at 20 deg, +3 % at 35 and 41, +8 % at 43) and a tall ROI
    # of a steep edge kept only a few pixels of ESF (+13 % at 25 deg); along the rows (ISO,
    # sfrmat3) a row's pixels are q bins apart at every angle
    edge = render_slanted_edge(shape, angle_deg=angle, sigma=0.6, supersampling=8)
    r = slanted_edge_sfr(edge)
    assert r.angle == pytest.approx(angle, abs=0.05)
    assert r.mtf50[0] == pytest.approx(
        crossing(lambda f: gauss_truth(f, 0.6, angle), 0.5), rel=0.01
    )


def test_a_found_roi_must_be_measured_at_its_angle() -> None:
    # the finder's last check: the e-SFR accepts the ROI and finds the edge within 1 deg of
    # the threshold fit (a glyph's rounded side passes a threshold fit but not this)
    from imageform.analysis.sfr import SlantedEdgeROI, _measurable

    img = render_slanted_edge((100, 60), angle_deg=5.0, sigma=0.8)
    ok = SlantedEdgeROI(0, 0, 60, 100, 5.0, "vertical", "right", (29.5, 49.5))
    assert _measurable(img, ok)
    assert not _measurable(img, ok._replace(angle=7.0))  # another angle: another edge
    assert not _measurable(img, ok._replace(orientation="horizontal"))
    # 10 rows: the edge moves 0.87 px along it, less than one phase cycle: e-SFR refuses
    assert not _measurable(img, ok._replace(height=10))


def _wedge(angle: float, sigma: float, s: int = 8) -> np.ndarray:
    """A dark triangle (0.2 on 0.8) with one side ``angle`` deg from the vertical, blurred.

    Like a blade of the ISO 12233:2017/2023 chart's pinwheels: its bounding box is half
    empty, so it is no square. Rendered at ``s`` x ``s`` sub-samples per pixel.
    """
    from scipy import ndimage

    h, w = 200, 200
    v, u = (np.mgrid[0 : h * s, 0 : w * s] + 0.5) / s
    t = math.radians(angle)
    # the left side through (60, 30) turned `angle`, a level top side, a 45 deg diagonal
    inside = ((u - 60) * math.cos(t) - (v - 30) * math.sin(t) > 0) & (v > 30) & (u + v < 230)
    img = np.where(inside, 0.2, 0.8)
    img = ndimage.gaussian_filter(img, sigma * s, mode="nearest")
    return np.asarray(img.reshape(h, s, w, s).mean(axis=(1, 3)))


def test_find_the_straight_side_of_a_wedge() -> None:
    img = _wedge(5.0, 0.8)
    rois = [r for r in find_slanted_edges(img) if r.side == "left"]
    assert len(rois) == 1
    assert abs(rois[0].angle) == pytest.approx(5.0, abs=0.15)
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    assert slanted_edge_sfr(img, rois[0].roi).mtf50[0] == pytest.approx(f50, rel=0.03)
    # the side is 130 rows long: an ROI of half of it, 65 rows, is kept with min_size=60 and
    # dropped with min_size=80 (a short straight run is mostly a glyph's stroke)
    assert [r.side for r in find_slanted_edges(img, min_size=60)].count("left") == 1
    assert [r.side for r in find_slanted_edges(img, min_size=80)].count("left") == 0


def _fields() -> list[tuple[np.ndarray, float]]:
    """Smoothed noise of several grains and sizes (1-row, 1-column too), with thresholds."""
    from scipy import ndimage

    rng = np.random.default_rng(7)
    out = []
    for h, w, sigma in [(1, 40, 1.0), (40, 1, 1.0), (37, 53, 0.0), (64, 80, 1.5), (90, 70, 3.0)]:
        g = ndimage.gaussian_filter(rng.random((h, w)), sigma)
        out += [(g, float(np.quantile(g, q))) for q in (0.2, 0.5, 0.8)]
    out.append((render_sfr_chart((120, 160), grid=(2, 2), supersampling=2), 0.5))
    return out


def test_component_kernel_matches_scipy_labelling() -> None:
    """The numba run-based labelling gives scipy's components, boxes, masks and order."""
    pytest.importorskip("numba")
    from imageform.analysis.sfr import _components_at

    for g, t in _fields():
        for msz in (1, 3, 8):
            # the dark (g < t) and the light (g > t) components, from one scan
            for fast, twin in zip(
                _components_at(g, t, msz, kernel=True),
                _components_at(g, t, msz, kernel=False),
                strict=True,
            ):
                assert [(a, b, m.shape) for a, b, m in fast] == [
                    (a, b, m.shape) for a, b, m in twin
                ]
                assert all((x[2] == y[2]).all() for x, y in zip(fast, twin, strict=True))


def test_outline_kernel_matches_its_twin() -> None:
    pytest.importorskip("numba")
    from imageform.analysis.sfr import _components_at, _outline

    for g, t in _fields():
        dark, light = _components_at(g, t, 1, kernel=False)
        for _r, _c, m in dark + light:
            for name in ("left", "right", "top", "bottom"):
                a, b = _outline(m, name, True), _outline(m, name, False)
                assert (a[0] == b[0]).all() and (a[1] == b[1]).all()


def test_lsf_window_does_not_depend_on_where_the_edge_lies() -> None:
    """The LSF's Hamming window spans the ESF array centred on the LSF (sfrmat3, ISO 12233).

    A window reaching from the LSF to the far end of the array (as before 2026-11-29) grew
    when the edge lay off the ROI's middle and tapered a long-tailed LSF (flare) less: the
    same edge read 0.3 % apart at four places in one ROI, and 0.6 % below sfrmat3 on its
    own edge crops.
    """
    from scipy.special import ndtr

    def esf(d: np.ndarray) -> np.ndarray:
        return np.asarray(0.85 * ndtr(d / 0.7) + 0.15 * ndtr(d / 6.0))

    m50 = []
    for off in (0.0, 12.0, -20.0, 30.0):
        img = render_slanted_edge(
            (200, 100), angle_deg=5.0, esf=esf, center=(49.5 + off, 99.5), supersampling=8
        )
        m50.append(float(slanted_edge_sfr(img).mtf50[0]))
    assert np.ptp(m50) / np.mean(m50) < 5e-4


def test_light_squares_on_a_dark_surround_are_found() -> None:
    """The inverted chart (light squares on dark) gives the same ROIs and MTF50 (0 before)."""
    img = render_sfr_chart((240, 320), grid=(2, 3), angle_deg=5.0, sigma=0.8, supersampling=4)
    dark = find_slanted_edges(img)
    light = find_slanted_edges(1.0 - img)
    assert len(light) == 24
    assert [r.roi for r in light] == [r.roi for r in dark]
    assert [r.side for r in light] == [r.side for r in dark]
    for r in light:
        assert slanted_edge_sfr(1.0 - img, r.roi).mtf50[0] == pytest.approx(
            slanted_edge_sfr(img, r.roi).mtf50[0], rel=1e-9
        )
    # both polarities in one image: each half's 24 edges
    both = np.concatenate([img, 1.0 - img], axis=1)
    assert len(find_slanted_edges(both)) == 48


def _phantom_band(angle: float = 6.0, sigma: float = 1.0) -> np.ndarray:
    """A dark band across a 240 x 400 field, edges at rows ~80 and ~160 (an X-ray phantom's)."""
    h, w = 240, 400
    # light above row 80 (an edge with dark above, flipped) and light below row 160
    top = render_slanted_edge(
        (h, w), angle_deg=-angle, sigma=sigma, orientation="horizontal", center=(199.5, h - 81)
    )[::-1]
    bottom = render_slanted_edge(
        (h, w), angle_deg=angle, sigma=sigma, orientation="horizontal", center=(199.5, 160)
    )
    return top + bottom - 0.2


def test_an_edge_across_the_field_is_found() -> None:
    # an X-ray detector's edge phantom (IEC 62220-1-1) or a knife edge spans the field: its
    # shapes touch the border, where squares are not looked for, and the image holds two
    # edges (no edge crop); the straight runs of their outlines give one ROI per edge, in the
    # middle, no longer than keeps the edge within the middle half of the ROI's width
    img = _phantom_band()
    assert img[[40, 120, 200], 200].round(2).tolist() == [0.8, 0.2, 0.8]
    rois = find_slanted_edges(img)
    assert [r.orientation for r in rois] == ["horizontal", "horizontal"]
    f50 = crossing(lambda f: gauss_truth(f, 1.0, 6.0), 0.5)
    for roi, row in zip(rois, (80, 160), strict=True):
        assert abs(roi.angle) == pytest.approx(6.0, abs=0.1)
        assert roi.center[0] == pytest.approx(199.5, abs=40)
        assert roi.center[1] == pytest.approx(row, abs=4)
        drift = roi.width * math.tan(math.radians(6.0))
        assert drift <= 0.5 * roi.height + 1
        assert slanted_edge_sfr(img, roi.roi).mtf50[0] == pytest.approx(f50, rel=0.02)
    # one ROI per edge however many levels and runs see it; noise and specks change nothing
    noisy = img + np.random.default_rng(3).normal(0.0, 0.01, img.shape)
    assert len(find_slanted_edges(noisy)) == 2
    # a chart's squares still come first: the band beside a square adds nothing
    assert find_slanted_edges(np.zeros((50, 50)) + 0.5) == []


def test_a_speck_does_not_hide_an_edge() -> None:
    # a dust speck or hot pixel one line tall in the flat area of an edge crop crossed the
    # 1/4 and 3/4 levels twice on its line, and the crop was no longer taken as one edge
    img = render_slanted_edge((120, 80), angle_deg=5.0, sigma=0.8)
    specked = img.copy()
    specked[30, 70] = 0.2  # a dark speck on the light side
    specked[90, 8] = 0.8  # a light one on the dark side
    (roi,) = find_slanted_edges(specked)
    assert roi.crop(specked).shape == img.shape
    # a mark three lines tall survives the median of three lines and still drops the crop
    # (a second edge, a bar: test_an_edge_crop_is_found_whole)
    streak = img.copy()
    streak[40:43, 70] = 0.2
    assert find_slanted_edges(streak) == []


def test_a_rectangle_gets_roi_along_its_long_sides() -> None:
    # a long dark bar (the ISO 12233 chart's slanted bars, a rectangle on MITRE's test edge):
    # its long sides' ROIs are half the side, not half the side of a square of equal area
    h, w = 320, 200
    # light left of u = 70 (an edge mirrored), light right of u = 130: a 60-px bar between
    left = render_slanted_edge((h, w), angle_deg=-5.0, sigma=0.8, center=(w - 1 - 70, 160))
    right = render_slanted_edge((h, w), angle_deg=5.0, sigma=0.8, center=(130, 160))
    img = left[:, ::-1] + right - 0.2
    img[:40] = 0.8  # 240 rows long
    img[280:] = 0.8
    assert img[160, [40, 100, 160]].round(2).tolist() == [0.8, 0.2, 0.8]
    rois = {r.side: r for r in find_slanted_edges(img, max_angle=10)}
    assert {"left", "right"} <= set(rois)
    for side in ("left", "right"):
        assert rois[side].height >= 100  # half of the 240-row side, not ~60
        assert rois[side].width <= 48  # 60 % of the bar's box (81 px) across, not 64
    f50 = crossing(lambda f: gauss_truth(f, 0.8, 5.0), 0.5)
    assert slanted_edge_sfr(img, rois["left"].roi).mtf50[0] == pytest.approx(f50, rel=0.02)


def test_every_found_roi_of_a_colour_image_is_measured() -> None:
    # the e-SFR of an RGB image fits and projects each channel on its own: a red square on
    # white has no edge in red, and a small ROI's channel may cross too few phases in the
    # rows the luminance keeps; the finder tested the luminance only and gave ROIs that
    # slanted_edge_sfr refused (`imageform sfr` then stopped on the whole image)
    grey = render_sfr_chart((160, 320), grid=(1, 2), angle_deg=5.0, sigma=0.8, supersampling=4)
    rgb = np.stack([grey, grey, grey], axis=2)
    rgb[:, :160, 0] = grey.max()  # the left square is red: no edge in R
    rois = find_slanted_edges(rgb)
    assert len(rois) == 4 and all(r.center[0] > 160 for r in rois)
    for roi in rois:
        assert np.isfinite(slanted_edge_sfr(rgb, roi.roi).mtf50).all()
    assert len(find_slanted_edges(rgb[..., 1])) == 8  # both squares in one channel
