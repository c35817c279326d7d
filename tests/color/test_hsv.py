"""HSV / HSL / HSI and hue helpers: colorsys cross-checks, gold values, round trips."""

from __future__ import annotations

import colorsys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.color import (
    hsi_to_srgb,
    hsl_to_srgb,
    hsv_to_srgb,
    hue_difference,
    hue_distance,
    hue_in_range,
    hue_undefined_mask,
    srgb_to_hsi,
    srgb_to_hsl,
    srgb_to_hsv,
)
from tests.helpers import to_backend, to_np

RNG = np.random.default_rng(10)
RGB = RNG.uniform(0, 1, (2000, 3))


def test_cross_check_colorsys_hsv_hls() -> None:
    # Cross-check: Python's colorsys (hue in [0, 1), HLS order L, S): same definitions.
    ref = np.array([colorsys.rgb_to_hsv(*p) for p in RGB])
    got = srgb_to_hsv(RGB)
    np.testing.assert_allclose(got[:, 0], ref[:, 0] * 360, atol=1e-9)
    np.testing.assert_allclose(got[:, 1:], ref[:, 1:], atol=1e-12)
    ref = np.array([colorsys.rgb_to_hls(*p) for p in RGB])
    got = srgb_to_hsl(RGB)
    np.testing.assert_allclose(got[:, 0], ref[:, 0] * 360, atol=1e-9)
    np.testing.assert_allclose(got[:, 1], ref[:, 2], atol=1e-12)
    np.testing.assert_allclose(got[:, 2], ref[:, 1], atol=1e-12)


def test_cross_check_skimage_hsv() -> None:
    # Cross-check: scikit-image rgb2hsv (hue in [0, 1)).
    skc = pytest.importorskip("skimage.color")
    ref = skc.rgb2hsv(RGB[None])[0]
    got = srgb_to_hsv(RGB)
    np.testing.assert_allclose(got[:, 0], ref[:, 0] * 360, atol=1e-9)
    np.testing.assert_allclose(got[:, 1:], ref[:, 1:], atol=1e-12)


def test_gold_primaries() -> None:
    # Gold: definitions (Smith 1978; Gonzalez & Woods eq. 6-16..6-19) at the primaries.
    prim = np.array([[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1], [1, 0, 1.0]])
    hues = [0, 60, 120, 180, 240, 300]
    np.testing.assert_allclose(srgb_to_hsv(prim)[:, 0], hues, atol=1e-12)
    np.testing.assert_allclose(srgb_to_hsl(prim)[:, 0], hues, atol=1e-12)
    np.testing.assert_allclose(srgb_to_hsi(prim)[:, 0], hues, atol=1e-12)
    np.testing.assert_allclose(srgb_to_hsi([0.0, 1.0, 0.0]), [120, 1, 1 / 3], atol=1e-12)


def test_hsi_matches_gonzalez_woods_arccos() -> None:
    # θ = arccos(½[(R-G)+(R-B)] / sqrt((R-G)² + (R-B)(G-B))), H = 360 - θ if B > G.
    r, g, b = RGB.T
    num = 0.5 * ((r - g) + (r - b))
    den = np.sqrt((r - g) ** 2 + (r - b) * (g - b))
    theta = np.degrees(np.arccos(np.clip(num / den, -1, 1)))
    h = np.where(b > g, 360 - theta, theta)
    np.testing.assert_allclose(srgb_to_hsi(RGB)[:, 0], h, atol=1e-6)


rgb_strategy = arrays(np.float64, (3,), elements=st.floats(0, 1))


@settings(max_examples=150, deadline=None)
@given(rgb=rgb_strategy)
def test_round_trips(rgb: np.ndarray) -> None:
    np.testing.assert_allclose(hsv_to_srgb(srgb_to_hsv(rgb)), rgb, atol=1e-12)
    np.testing.assert_allclose(hsl_to_srgb(srgb_to_hsl(rgb)), rgb, atol=1e-12)
    np.testing.assert_allclose(hsi_to_srgb(srgb_to_hsi(rgb)), rgb, atol=1e-9)


def test_undefined_hue() -> None:
    grey = np.array([[0.5, 0.5, 0.5], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    hsv = srgb_to_hsv(grey)
    np.testing.assert_array_equal(hsv[:2, 0], 0.0)  # documented value
    assert hue_undefined_mask(hsv).tolist() == [True, True, False]
    assert hue_undefined_mask(srgb_to_hsi(grey)).tolist() == [True, True, False]
    assert hue_undefined_mask([[10.0, 0.01, 0.5]], atol=0.02).tolist() == [True]


def test_hue_helpers_wrap() -> None:
    assert float(hue_distance(350, 10)) == 20
    assert float(hue_distance(10, 350)) == 20
    assert float(hue_distance(0, 180)) == 180
    assert float(hue_difference(10, 350)) == -20
    assert hue_in_range([355, 5, 20, 21, 200], 350, 20).tolist() == [True, True, True, False, False]
    assert hue_in_range([355, 5, 100], 0, 90).tolist() == [False, True, False]
    assert hue_in_range([-10, 370], 350, 20).tolist() == [True, True]


def test_dtypes_and_backends(xp_name: str) -> None:
    assert srgb_to_hsv(RGB.astype(np.float32)).dtype == np.float32
    assert srgb_to_hsv((RGB * 255).astype(np.uint8)).dtype == np.float32
    for f in (srgb_to_hsv, srgb_to_hsl, srgb_to_hsi):
        got = to_np(f(to_backend(RGB[:50], xp_name)))
        np.testing.assert_allclose(got, f(RGB[:50]), atol=1e-9)
