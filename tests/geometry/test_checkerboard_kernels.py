"""numba kernels of the checkerboard detector against their plain NumPy twins.

Tolerances: the refinement agrees to 1e-9 px (the same float64 arithmetic, different
summation order); the float32 smoothing to 1e-6
(float32 rounding, scipy accumulates in float64), the response (second differences of
those, cancellation) to 1e-4 of its peak; the local maxima are the same pixels.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from imageform._kernels.checkerboard import (
    corner_window_weights,
    gaussian_weights,
    local_maxima_numba,
    local_maxima_numpy,
    refine_corners_numba,
    refine_corners_numpy,
    smooth_saddle_numba,
    smooth_saddle_numpy,
)


@pytest.fixture(scope="module")
def image() -> np.ndarray:
    """A blurred random checker-like pattern with noise (many saddles, edges, flats)."""
    rng = np.random.default_rng(7)
    v, u = np.mgrid[0:120, 0:160]
    board = (((u + 3) // 13 + (v + 5) // 11) % 2).astype(np.float64)
    img = ndimage.gaussian_filter(board, 1.3) + rng.normal(0, 0.02, board.shape)
    return img


def test_gaussian_weights_match_scipy() -> None:
    """Same taps as scipy.ndimage.gaussian_filter with truncate=3 (an impulse response)."""
    taps = gaussian_weights(2.0)
    impulse = np.zeros(41)
    impulse[20] = 1.0
    ref = ndimage.gaussian_filter1d(impulse, 2.0, truncate=3.0)
    r = taps.size // 2
    assert np.allclose(ref[20 - r : 21 + r], taps, atol=1e-15)
    assert taps.sum() == pytest.approx(1.0, abs=1e-15)


def test_window_weights() -> None:
    w = corner_window_weights(2, 3)
    assert w.shape == (7, 5)
    assert w[3, 2] == 1.0
    assert w[0, 0] == pytest.approx(np.exp(-1.0) * np.exp(-1.0))


@pytest.mark.parametrize("sigma", [1.2, 2.0, 3.5])
def test_smooth_saddle_twin(image: np.ndarray, sigma: float) -> None:
    g = image.astype(np.float32)
    taps = gaussian_weights(sigma).astype(np.float32)
    s1, r1 = smooth_saddle_numba(g, taps)
    s2, r2 = smooth_saddle_numpy(g, taps)
    assert s1.dtype == s2.dtype == np.float32
    assert np.abs(s1 - s2).max() < 1e-6
    assert np.abs(r1 - r2).max() < 1e-4 * np.abs(r2).max()


def test_local_maxima_twin(image: np.ndarray) -> None:
    _, resp = smooth_saddle_numpy(image, gaussian_weights(2.0))
    thr = 0.02 * resp.max()
    y1, x1 = local_maxima_numba(resp, 3, thr, 7)
    y2, x2 = local_maxima_numpy(resp, 3, thr, 7)
    assert y1.size > 10
    assert sorted(zip(y1.tolist(), x1.tolist(), strict=True)) == sorted(
        zip(y2.tolist(), x2.tolist(), strict=True)
    )


def test_refine_twin(image: np.ndarray) -> None:
    rng = np.random.default_rng(3)
    pts = rng.uniform([5, 5], [155, 115], size=(40, 2))
    pts[0] = [-3.0, 50.0]  # outside: status 3 or 4 in both
    a, sa = refine_corners_numba(image, pts, 5, 4, 30, 1e-3)
    b, sb = refine_corners_numpy(image, pts, 5, 4, 30, 1e-3)
    assert np.abs(a - b).max() < 1e-9
    assert sa.tolist() == sb.tolist()
