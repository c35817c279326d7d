"""Coarse-to-fine point-symmetry refinement of large views (refine_symmetric_pyramid).

Truth: boards rendered with known corners (checkerboard_support: a perspective view through
a homography, and a wide-angle view through a lens whose squares bend within the window), at
twice OpenCV's sample size, where the windows' radius passes ``SYMMETRIC_COARSE_MIN`` px. The
coarse-to-fine corners are checked against the truth and against the two full-resolution
refinements (the path taken below that radius), which they must match to about 0.02 px.
"""

from __future__ import annotations

import numpy as np
import pytest

import imageform.geometry.checkerboard as cb
from imageform.geometry import BrownConrady, Camera, find_checkerboard
from imageform.geometry.checkerboard_subpix import block_mean

from .checkerboard_support import board_corners, homography, render_board, render_board_through


def test_block_mean_values_and_centres() -> None:
    """Means of 2 x 2 and 3 x 3 blocks (a last partial block dropped); float32 kept."""
    g = np.arange(35, dtype=np.float32).reshape(5, 7)
    two = block_mean(g, 2)
    assert two.dtype == np.float32 and two.shape == (2, 3)
    np.testing.assert_array_equal(two, [[4.0, 6.0, 8.0], [18.0, 20.0, 22.0]])
    three = block_mean(g.astype(np.float64), 3)
    assert three.dtype == np.float64
    np.testing.assert_array_equal(three, [[8.0, 11.0]])  # the 3 x 3 blocks' centre pixels


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.uint8])
@pytest.mark.parametrize("factor", [1, 2, 3, 4])
def test_block_mean_kernel_is_its_twin_bit_for_bit(dtype: type, factor: int) -> None:
    """The one-pass kernel adds the twin's terms in its order: the same bits, on a rectangle
    read in place (odd offsets, partial blocks dropped), float32 kept, others as float64."""
    from imageform._kernels.checkerboard_pyramid import block_mean_numba, block_mean_numpy

    rng = np.random.default_rng(factor)
    g = (rng.random((61, 83)) * 255).astype(dtype)
    for bounds in [(0, 61, 0, 83), (3, 50, 5, 78), (7, 7 + factor - 1, 2, 40), (4, 4, 0, 0)]:
        a = block_mean_numba(g, factor, *bounds)
        b = block_mean_numpy(g, factor, *bounds)
        assert a.dtype == b.dtype == (np.float32 if dtype is np.float32 else np.float64)
        assert a.shape == b.shape == ((bounds[1] - bounds[0]) // factor,
                                      (bounds[3] - bounds[2]) // factor)  # fmt: skip
        assert a.tobytes() == b.tobytes()
    # a block's mean: its float32 sum, from 0 in raster order, times 1/f² rounded to float32
    block = rng.random((factor, factor)).astype(np.float32)
    total = np.float32(0.0)
    for v in block.ravel():
        total = np.float32(total + v)
    mean = block_mean_numba(block, factor, 0, factor, 0, factor)[0, 0]
    assert mean == total * np.float32(1.0 / factor**2)
    with pytest.raises(ValueError, match="expected 0 <= y0 <= y1"):
        block_mean_numba(g, factor, 0, 62, 0, 83)


@pytest.mark.parametrize("masked", [False, True])
def test_half_window_sums_are_the_whole_windows_but_for_rounding(masked: bool) -> None:
    """``half=True`` (each pair ``(d, -d)`` summed once, the normal equations halved) takes the
    same steps as the whole window's sums, to rounding (1e-9 px), masked or not."""
    from imageform._kernels.checkerboard_symmetric import refine_symmetric_numba

    H = homography(24.0, (80.0, 70.0), 0.2, 0.02, 5, 4)
    img = render_board(5, 4, H, (140, 160), blur=1.5, noise=0.01, seed=2).astype(np.float32)
    truth = board_corners(5, 4, H)
    start = truth + np.random.default_rng(1).uniform(-1.0, 1.0, truth.shape)
    mask = None
    if masked:
        mask = np.random.default_rng(2).uniform(size=(len(start), 19, 19)) > 0.2
    whole, s_whole = refine_symmetric_numba(img, start, 9, 30, 1e-3, mask)
    half, s_half = refine_symmetric_numba(img, start, 9, 30, 1e-3, mask, half=True)
    assert s_whole.tolist() == s_half.tolist() and not np.any(s_half)
    np.testing.assert_allclose(half, whole, atol=1e-9)
    assert np.hypot(*(half - truth).T).max() < 0.05


def _both(
    u8: np.ndarray, monkeypatch: pytest.MonkeyPatch, pattern: tuple[int, int] = (9, 6)
) -> tuple[np.ndarray, np.ndarray]:
    """find_checkerboard's corners coarse to fine (checked to be taken) and at full resolution."""
    calls: list[int] = []
    real = cb.refine_symmetric_pyramid

    def spy(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(int(args[-1]))
        return real(*args, **kwargs)

    monkeypatch.setattr(cb, "refine_symmetric_pyramid", spy)
    fast = find_checkerboard(u8, pattern)
    assert calls and calls[-1] >= 2  # block means of 2 x 2 pixels or more
    monkeypatch.setattr(cb, "SYMMETRIC_COARSE_MIN", 10**6)
    full = find_checkerboard(u8, pattern)
    assert fast.corners is not None and full.corners is not None
    assert fast.status is not None and not np.any(fast.status)
    return fast.corners, full.corners


def test_large_perspective_view_matches_truth(monkeypatch: pytest.MonkeyPatch) -> None:
    """A tilted 5 x 4 board (grid steps of 57-68 px: windows of radius 45, block means of 2 x 2
    pixels), blurred (2 px) and noisy (1 %): the corners as near the truth as the
    full-resolution ones (mean 0.0063 / 0.0063 px, largest 0.016 / 0.016 px when measured)
    and within 0.01 px of them."""
    H = homography(62.0, (240.0, 210.0), 0.3, 0.03, 5, 4)
    img = render_board(5, 4, H, (420, 480), blur=2.0, noise=0.01, seed=5)
    u8 = np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)
    truth = board_corners(5, 4, H)
    fast, full = _both(u8, monkeypatch, (5, 4))
    e_fast, e_full = np.hypot(*(fast - truth).T), np.hypot(*(full - truth).T)
    assert e_fast.mean() < 0.02 and e_fast.max() < 0.06
    assert e_fast.mean() < e_full.mean() + 0.002
    assert np.abs(fast - full).max() < 0.01


@pytest.mark.slow
def test_large_wide_angle_view_matches_truth(monkeypatch: pytest.MonkeyPatch) -> None:
    """A board bent by a wide-angle lens (k1 = -0.32) at 1280 x 960, where most corners are
    refined through their grid maps: coarse to fine within 0.02 px of the full-resolution
    corners, and as near the truth."""
    from scipy.spatial.transform import Rotation

    from imageform.geometry import checkerboard_points, project_points_distorted

    K = np.array([[840.0, 0, 644], [0, 840, 472], [0, 0, 1]])
    D = BrownConrady(-0.32, 0.11, 0, 0, 0)
    R = Rotation.from_rotvec((0.3, -0.4, 0.1)).as_matrix()
    t = np.array([-3.0, -1.6, 6.5])
    cam = Camera(K, R, t, (1280, 960), distortion=D)
    img = render_board_through(cam, 9, 6, 1.0, blur=2.0, noise=0.01, seed=3)
    u8 = np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)
    truth = np.asarray(project_points_distorted(checkerboard_points((9, 6), 1.0), K, R, t, D)[0])
    fast, full = _both(u8, monkeypatch)
    e_fast, e_full = np.hypot(*(fast - truth).T), np.hypot(*(full - truth).T)
    assert e_fast.mean() < e_full.mean() + 0.005
    assert e_fast.max() < e_full.max() + 0.02
    assert np.abs(fast - full).max() < 0.02
