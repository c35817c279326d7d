"""Vanishing points on degraded images: the low-contrast stretch before LSD, and how far
resampling the segments moves the horizon (``VanishingPointResult.horizon_spread``).

The measurements on degraded real photographs (York Urban, Kodak) are in
``benchmarks/check_vp_stress.py`` and ``benchmarks/results/vp-stress-2026-12-01g.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.geometry import (
    camera_rotation,
    detect_line_segments,
    detect_vanishing_points,
    horizon_line,
    vp_detection,
)
from imageform.geometry.lsd import _stretch_low_contrast
from tests.geometry.scene_render import render_manhattan
from tests.geometry.test_line_segments_vp import K, _row_at


def _render(seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A rendered Manhattan scene (uint8, 768 x 512, f = 700 px) and its true horizon."""
    R = camera_rotation(0.25, 0.5, 0.03)
    img = render_manhattan(K, R, np.zeros(3), seed=seed)
    return np.round(img * 255).astype(np.uint8), np.asarray(horizon_line(K, R))


def _horizon_error(line: np.ndarray | None, truth: np.ndarray) -> float:
    """The larger distance at the image's left and right edges (px); inf when none."""
    if line is None:
        return float("inf")
    return max(abs(_row_at(line, u) - _row_at(truth, u)) for u in (0.0, 767.0))


def _reduce(img: np.ndarray, factor: float) -> np.ndarray:
    """Contrast divided by ``factor`` about the mean, back to 8 bits."""
    m = img.astype(np.float64).mean()
    return np.clip(np.round(m + (img - m) / factor), 0, 255).astype(np.uint8)


def test_normal_contrast_is_left_bit_identical() -> None:
    """An image of normal contrast (the render; a Kodak photograph where the data are) is
    returned as it is, and the segments the detector works on are LSD's on it, bit for bit."""
    img, _ = _render()
    assert _stretch_low_contrast(img) is img
    for arr in (img, img.astype(np.float64) / 255.0, np.repeat(img[..., None], 3, axis=-1)):
        assert _stretch_low_contrast(arr) is arr
    res = detect_vanishing_points(img)
    ref = detect_line_segments(img)
    assert np.array_equal(res.segments.endpoints, ref.endpoints)
    assert np.array_equal(res.segments.widths, ref.widths)
    flat = np.full((40, 50), 128, dtype=np.uint8)  # no range at all: nothing to stretch
    assert _stretch_low_contrast(flat) is flat


def test_normal_contrast_photograph_is_left_as_it_is(shared_data: Path) -> None:
    from PIL import Image

    for name in ("kodim01.png", "kodim08.png", "kodim24.png"):
        img = np.asarray(Image.open(shared_data / "kodak" / name))
        assert _stretch_low_contrast(img) is img


def test_stretch_recovers_a_twenty_times_lower_contrast(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The render with its contrast divided by 20 (10 grey levels between the 1st and 99th
    percentiles): every edge is below LSD's gradient threshold (5.2 levels per pixel), no
    segment and no vanishing point without the stretch; with it, K within 1 % and the
    horizon within 2 px, as on the original."""
    img, truth = _render()
    low = _reduce(img, 20.0)
    lo, hi = np.percentile(low, [1, 99])
    assert hi - lo <= 12
    stretched = _stretch_low_contrast(low)
    assert stretched is not low and stretched.dtype == np.float64
    assert stretched.min() == 0.0 and stretched.max() == 1.0
    res = detect_vanishing_points(low)
    assert res.K is not None and res.K[0, 0] == pytest.approx(700.0, rel=0.01)
    assert _horizon_error(res.horizon, truth) < 2.0
    assert len(res.segments) > 0.9 * len(detect_vanishing_points(img).segments)
    monkeypatch.setattr(vp_detection, "_stretch_low_contrast", lambda a: a)
    before = detect_vanishing_points(low)
    assert len(before.segments) < 10 and before.K is None


def test_a_dim_rgb_photograph_is_stretched_as_grey() -> None:
    """A dim RGB image (a tenth of its levels): stretched to grey floats in [0, 1] with its
    1st and 99th percentiles at 0 and 1; uint16 and float inputs on their own scales."""
    img, _ = _render()
    dim = np.repeat((img // 10)[..., None], 3, axis=-1)
    out = _stretch_low_contrast(dim)
    assert out.shape == img.shape and out.dtype == np.float64
    lo, hi = np.percentile(out, [1, 99])
    assert lo == pytest.approx(0.0, abs=0.02) and hi == pytest.approx(1.0, abs=0.02)
    as16 = (img // 10).astype(np.uint16) * 257
    np.testing.assert_allclose(_stretch_low_contrast(as16), out, atol=1e-6)
    np.testing.assert_allclose(_stretch_low_contrast((img // 10) / 255.0), out, atol=1e-6)


def test_horizon_spread_small_on_a_clean_render_larger_on_a_noisy_one() -> None:
    """Resampling the segments of the clean render moves its horizon by well under 1 px
    (under 0.2 % of the height); the same scene with Gaussian noise of 30 grey levels moves
    it more (the segments scatter about their points), and the error it comes with stays
    within a few spreads."""
    img, truth = _render()
    clean = detect_vanishing_points(img)
    assert clean.horizon_spread is not None and 0 < clean.horizon_spread < 0.002
    rng = np.random.default_rng(1)
    noisy_img = np.clip(np.round(img + rng.normal(0.0, 30.0, img.shape)), 0, 255)
    noisy = detect_vanishing_points(noisy_img.astype(np.uint8))
    assert noisy.horizon_spread is not None
    assert noisy.horizon_spread > 1.5 * clean.horizon_spread
    assert _horizon_error(noisy.horizon, truth) < 8 * noisy.horizon_spread * 512


def test_horizon_spread_is_none_without_a_horizon_from_points() -> None:
    """No vanishing point (a flat image): no horizon, no spread."""
    res = detect_vanishing_points(np.full((120, 160), 0.5))
    assert res.horizon is None and res.horizon_spread is None


def test_horizon_spread_does_not_change_the_answer() -> None:
    """The spread is drawn after everything else: K, the points and the horizon are those of
    the same call with the spread's resampling replaced by a constant."""
    img, _ = _render(seed=5)
    res = detect_vanishing_points(img)
    orig = vp_detection._horizon_spread
    try:
        vp_detection._horizon_spread = lambda *a, **k: 0.0  # type: ignore[assignment]
        plain = detect_vanishing_points(img)
    finally:
        vp_detection._horizon_spread = orig  # type: ignore[assignment]
    assert np.array_equal(res.vanishing_points, plain.vanishing_points)
    assert res.K is not None and plain.K is not None and np.array_equal(res.K, plain.K)
    assert res.horizon is not None and plain.horizon is not None
    assert np.array_equal(res.horizon, plain.horizon)
    assert res.focal_spread == plain.focal_spread
