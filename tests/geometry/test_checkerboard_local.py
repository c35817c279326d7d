"""Point-symmetry refinement through each corner's grid map (find_checkerboard's default).

Truth: a board rendered through a wide-angle lens (checkerboard_support.render_board_through:
each pixel's ray meets the board plane), whose squares are bent and foreshortened; the affine
window's corners against the grid map's. Kernel against its NumPy twin, and against the
affine kernel when the map is affine.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imageform.geometry import BrownConrady, Camera, find_checkerboard
from imageform.geometry.checkerboard_subpix import (
    grid_maps,
    refine_local_inside,
    refine_symmetric_inside,
)

from .checkerboard_support import board_corners, homography, render_board, render_board_through


def _wide_angle_view() -> tuple[np.ndarray, np.ndarray]:
    """A 9 x 6 board near a corner of a 640 x 480 wide-angle view (k1 = -0.32), 8-bit."""
    from scipy.spatial.transform import Rotation

    from imageform.geometry import checkerboard_points, project_points_distorted

    K = np.array([[420.0, 0, 322], [0, 420, 236], [0, 0, 1]])
    D = BrownConrady(-0.32, 0.11, 0, 0, 0)
    R = Rotation.from_rotvec((0.3, -0.4, 0.1)).as_matrix()
    t = np.array([-4.3, -2.3, 5.2])
    img = render_board_through(Camera(K, R, t, (640, 480), distortion=D), 9, 6, 1.0,
                               blur=1.0, noise=0.01, seed=3)  # fmt: skip
    truth = np.asarray(project_points_distorted(checkerboard_points((9, 6), 1.0), K, R, t, D)[0])
    return np.round(np.clip(img, 0, 1) * 255).astype(np.uint8), truth


def test_bent_squares_affine_window_fails_grid_map_succeeds() -> None:
    """Through a wide-angle lens the affine window's corners are biased (median 0.044 px here,
    the gradient method's 0.027); through each corner's grid map they are within 0.015 px
    (median); find_checkerboard, which uses the map only less its first pixel of bend, lands
    between the two."""
    u8, truth = _wide_angle_view()
    grad = find_checkerboard(u8, (9, 6), method="gradient")
    new = find_checkerboard(u8, (9, 6))
    assert grad.corners is not None and new.corners is not None
    grid = grad.corners.reshape(6, 9, 2)
    step = min(float(np.linalg.norm(np.diff(grid, axis=a), axis=-1).min()) for a in (0, 1))
    h = max(2, math.floor(0.8 * step))
    gray = u8.astype(np.float32) / 255
    aff = refine_symmetric_inside(gray, grad.corners, grad.corners, h, 30, 1e-3, 0.25 * step)[0]
    local, status, moved = refine_local_inside(
        gray, aff, grad.corners, aff.reshape(6, 9, 2), h, 30, 1e-3, 0.25 * step, 0.0, 0.8
    )
    e_aff = np.hypot(*(aff - truth).T)
    e_loc = np.hypot(*(local - truth).T)
    e_new = np.hypot(*(new.corners - truth).T)
    assert moved.size == 54 and (status <= 1).all()
    assert np.median(e_aff) > 0.035
    assert np.median(e_loc) < 0.015
    assert np.percentile(e_loc, 75) < 0.5 * np.percentile(e_aff, 75)
    assert np.median(e_new) < 0.8 * np.median(e_aff) and e_new.max() <= e_aff.max() + 0.01


def test_grid_maps_pass_through_the_neighbours() -> None:
    """Each corner's map gives its grid neighbours' offsets at their board coordinates, at the
    board's edges too (the nearest 3 x 3 block), and along a side of 2 corners (2 nodes)."""
    rng = np.random.default_rng(2)
    for rows, cols in ((4, 5), (2, 6), (3, 2)):
        grid = np.stack(np.meshgrid(np.arange(cols) * 20.0, np.arange(rows) * 17.0), -1)
        grid = grid + rng.normal(0, 1.5, grid.shape) + 40.0
        linv, coef = grid_maps(grid)
        assert coef.shape == (rows * cols, 3, 3, 2) and linv.shape == (rows * cols, 2, 2)
        for k in range(rows * cols):
            r, c = divmod(k, cols)
            for rr in range(max(0, r - 1), min(rows, r + 2)):
                for cc in range(max(0, c - 1), min(cols, c + 2)):
                    s, t = cc - c, rr - r
                    off = sum(coef[k, a, b] * s**a * t**b for a in range(3) for b in range(3))
                    assert np.allclose(off, grid[rr, cc] - grid[r, c], atol=1e-9)
            lin = np.stack([coef[k, 1, 0], coef[k, 0, 1]], -1)
            assert np.allclose(linv[k] @ lin, np.eye(2), atol=1e-12)


def _maps_and_image(image: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    H = homography(18.0, (160.0, 120.0), 0.5, 0.04, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.0, noise=0.02, seed=5).astype(image)
    grid = board_corners(9, 6, H).reshape(6, 9, 2)
    linv, coef = grid_maps(grid)
    return img, grid.reshape(-1, 2), linv, coef


@pytest.mark.parametrize("image", ["float32", "float64"])
def test_kernel_and_twin_agree(image: str) -> None:
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_local import refine_local_numba, refine_local_numpy

    img, truth, linv, coef = _maps_and_image(image)
    rng = np.random.default_rng(1)
    n = len(truth)
    # starts near the corners, anywhere, past the borders; a map bent hard (its windows
    # reach far past the image), a non-finite map and a singular one
    pts = np.concatenate([truth + rng.uniform(-1, 1, (n, 2)), rng.uniform(0, 320, (20, 2)),
                          [[-2.0, 30.0], [5.0, 200.0], [3.0, 3.0], [150.0, 100.0],
                           [150.0, 100.0]]])  # fmt: skip
    extra = len(pts) - n
    pick = rng.integers(0, n, extra)
    li = np.concatenate([linv, linv[pick]])
    cf = np.concatenate([coef, coef[pick]])
    cf[-3, 2, 2] = 500.0
    li[-2, 0, 0] = np.nan
    li[-1] = 0.0
    a, sa = refine_local_numba(img, pts, li, cf, 6, 30, 1e-3)
    b, sb = refine_local_numpy(img, pts, li, cf, 6, 30, 1e-3)
    assert sa.tolist() == sb.tolist()
    assert np.abs(a - b).max() < 1e-10
    assert (sa[:n] == 0).all() and np.median(np.hypot(*(a[:n] - truth).T)) < 0.05
    assert sa[-2] == 2 and a[-2].tolist() == pts[-2].tolist()
    assert sa[-1] == 2 and a[-1].tolist() == pts[-1].tolist()
    # the window cut to 0.4 squares on the board (per-corner shading block), and to nothing
    # (singular: start kept)
    a, sa = refine_local_numba(img, pts, li, cf, 6, 30, 1e-3, 0.4)
    b, sb = refine_local_numpy(img, pts, li, cf, 6, 30, 1e-3, 0.4)
    assert sa.tolist() == sb.tolist() and np.abs(a - b).max() < 1e-10
    assert (sa[:n] <= 1).all()
    a, sa = refine_local_numba(img, pts[:3], li[:3], cf[:3], 6, 30, 1e-3, 0.0)
    b, sb = refine_local_numpy(img, pts[:3], li[:3], cf[:3], 6, 30, 1e-3, 0.0)
    assert sa.tolist() == sb.tolist() == [2, 2, 2] and np.array_equal(a, pts[:3])


def test_an_affine_map_is_the_affine_window() -> None:
    """With the map's quadratic terms dropped, the kernel is the affine kernel (half the sums:
    the same steps)."""
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_local import refine_local_numba, refine_local_numpy
    from imageform._kernels.checkerboard_symmetric import refine_symmetric_numba

    img, truth, linv, coef = _maps_and_image("float32")
    flat = np.zeros_like(coef)
    flat[:, 1, 0], flat[:, 0, 1] = coef[:, 1, 0], coef[:, 0, 1]
    pts = truth + np.random.default_rng(4).uniform(-1, 1, truth.shape)
    a, sa = refine_local_numba(img, pts, linv, flat, 7, 30, 1e-3)
    b, sb = refine_local_numpy(img, pts, linv, flat, 7, 30, 1e-3)
    c, sc = refine_symmetric_numba(img, pts, 7, 30, 1e-3)
    assert sa.tolist() == sb.tolist() == sc.tolist()
    assert np.abs(a - c).max() < 1e-10 and np.abs(b - c).max() < 1e-10


def test_only_bent_corners_are_refined_again() -> None:
    """An affine board (no bend): with a bend threshold no corner is refined through its map
    (all keep their start, status 0); with none every corner is, as the affine step would."""
    H = homography(18.0, (160.0, 120.0), 0.5, 0.0, 9, 6)  # affine: no perspective
    img = render_board(9, 6, H, (240, 320), blur=1.0, noise=0.02, seed=5).astype(np.float32)
    grid = board_corners(9, 6, H).reshape(6, 9, 2)
    pts = grid.reshape(-1, 2) + 0.3
    out, status, moved = refine_local_inside(img, pts, pts, grid, 7, 30, 1e-3, 4.0, 0.01)
    assert np.array_equal(out, pts) and not status.any() and moved.size == 0
    aff = refine_symmetric_inside(img, pts, pts, 7, 30, 1e-3, 4.0)
    out, status, moved = refine_local_inside(img, pts, pts, grid, 7, 30, 1e-3, 4.0)
    assert np.abs(out - aff[0]).max() < 1e-6 and np.array_equal(moved, aff[2])


def test_windows_through_the_map_past_the_border_keep_the_start() -> None:
    """A board near the image's left edge: corners whose window through the map would read
    replicated edge pixels keep their start."""
    H = homography(20.0, (95.0, 120.0), 0.0, 0.03, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.2, noise=0.01, seed=4)
    grid = board_corners(9, 6, H).reshape(6, 9, 2)
    pts = grid.reshape(-1, 2) + 0.2
    out, status, moved = refine_local_inside(img, pts, pts, grid, 12, 30, 1e-3, 5.0)
    near = pts[:, 0] < 13
    assert near.any() and not near.all()
    assert np.array_equal(out[near], pts[near]) and not status[near].any()
    assert set(moved.tolist()) == set(np.flatnonzero(~near).tolist())


def test_extreme_maps_and_starts_are_bounds_safe() -> None:
    """Maps whose offsets overflow (inf - inf: NaN samples) and a start far off the image read
    only clamped pixels: kernel and twin agree, the singular ones keep their start."""
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_local import refine_local_numba, refine_local_numpy

    img = np.random.default_rng(0).uniform(size=(40, 50)).astype(np.float32)
    pts = np.array([[20.0, 20.0], [25.0, 18.0], [1e308, 5.0]])
    linv = np.tile(np.eye(2) * 0.1, (3, 1, 1))
    coef = np.zeros((3, 3, 3, 2))
    coef[:, 1, 0, 0] = coef[:, 0, 1, 1] = 10.0
    coef[0, 2, 0], coef[0, 0, 2], coef[0, 2, 2] = 1e300, -1e300, 1e308
    coef[1, 1, 1] = 1e308
    with np.errstate(all="ignore"):
        a, sa = refine_local_numba(img, pts, linv, coef, 6, 30, 1e-3)
        b, sb = refine_local_numpy(img, pts, linv, coef, 6, 30, 1e-3)
    assert sa.tolist() == sb.tolist() and np.array_equal(a, b)
    assert sa[0] == 2 and sa[2] == 2 and np.array_equal(a[[0, 2]], pts[[0, 2]])


@pytest.mark.parametrize("image", ["float32", "float64"])
def test_kernel_on_threads_is_bit_for_bit_the_serial_one(image: str) -> None:
    """Each corner's arithmetic is its own: 1 and 3 threads give the same bits."""
    pytest.importorskip("numba")
    from imageform._kernels import checkerboard_local as kl
    from imageform._kernels.jit import run_tasks

    img, truth, linv, coef = _maps_and_image(image)
    rng = np.random.default_rng(4)
    pts = np.concatenate([truth + rng.uniform(-1, 1, truth.shape), [[-2.0, 30.0]]])
    li = np.concatenate([linv, linv[:1]]).reshape(-1, 4)
    cf = np.concatenate([coef, coef[:1]]).reshape(-1, 18)
    h = 6
    w = kl.symmetric_window_weights(h)
    i32 = img if image == "float32" else kl._EMPTY32
    i64 = img if image == "float64" else kl._EMPTY64
    outs = []
    for threads in (1, 3):
        out = pts.copy()
        st = np.ones(len(pts), dtype=np.int64)
        run_tasks(kl._refine_local, len(pts), i32, i64, image == "float32", out,
                  np.ascontiguousarray(li), np.ascontiguousarray(cf), h, w, np.inf, 30, 1e-3,
                  out, st, threads=threads)  # fmt: skip
        outs.append((out, st))
    assert outs[0][1].tolist() == outs[1][1].tolist()
    assert np.array_equal(outs[0][0], outs[1][0])
    a, sa = kl.refine_local_numba(img, pts, li.reshape(-1, 2, 2), cf.reshape(-1, 3, 3, 2), h,
                                  30, 1e-3)  # fmt: skip
    assert sa.tolist() == outs[0][1].tolist() and np.array_equal(a, outs[0][0])
