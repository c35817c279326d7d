"""numba kernels of the checkerboard detector against their plain NumPy twins.

Tolerances: the refinement agrees to 1e-9 px (the same float64 arithmetic, different
summation order); the float32 smoothing to 1e-6
(float32 rounding, scipy accumulates in float64), the response (second differences of
those, cancellation) to 1e-4 of its peak; the local maxima are the same pixels; the ring
test gives the same verdicts and directions to 1e-9; the neighbour tables are equal.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from imageform._kernels.checkerboard import (
    corner_window_weights,
    gaussian_weights,
    local_maxima_numpy,
    neighbors_numba,
    neighbors_numpy,
    refine_corners_numba,
    refine_corners_numpy,
    ring_test_numba,
    ring_test_numpy,
    saddle_maxima_numba,
    saddle_maxima_numpy,
    sample_bilinear_numba,
    sample_bilinear_numpy,
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
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_saddle_maxima_twin(image: np.ndarray, sigma: float, dtype: type) -> None:
    """One pass (smoothing, response in a ring of rows, maxima) = smoothing then maxima."""
    g = image.astype(dtype)
    taps = gaussian_weights(sigma).astype(dtype)
    radius, border = max(2, round(1.5 * sigma)), taps.size // 2 + 1
    s1, p1, y1, x1, v1 = saddle_maxima_numba(g, taps, radius, border, 0.02, 1.0)
    s2, p2, y2, x2, v2 = saddle_maxima_numpy(g, taps, radius, border, 0.02, 1.0)
    assert s1.dtype == s2.dtype == dtype
    assert np.abs(s1 - s2).max() < 1e-6
    assert p1 == pytest.approx(p2, rel=1e-4)
    # the kernel keeps maxima against its running peak (a superset): the final threshold
    keep = v1[:, 1, 1] > 0.02 * p1
    assert y2.size > 10
    assert list(zip(y1[keep].tolist(), x1[keep].tolist(), strict=True)) == list(
        zip(y2.tolist(), x2.tolist(), strict=True)
    )
    assert np.abs(v1[keep] - v2).max() < 1e-4 * p2


def test_saddle_maxima_relative_zero_keeps_every_positive_maximum(image: np.ndarray) -> None:
    g = image.astype(np.float32)
    taps = gaussian_weights(2.0).astype(np.float32)
    _, resp = smooth_saddle_numpy(g, taps)
    _, peak, ys, _, vals = saddle_maxima_numba(g, taps, 3, 7, 0.0, 1.0)
    assert peak == pytest.approx(float(resp.max()), rel=1e-4)
    assert np.all(vals[:, 1, 1] > 0)
    assert ys.size == local_maxima_numpy(resp, 3, 0.0, 7)[0].size


def test_saddle_maxima_peak_in_the_frame(image: np.ndarray) -> None:
    """The strongest response within ``border`` of the edge (where no maximum is sought)
    is still the peak; relative >= 1 keeps nothing but the peak is still right."""
    v, u = np.mgrid[0:8, 0:8]
    g = image.copy()  # noisy: no exact ties
    g[:8, :8] = np.where((u < 4) ^ (v < 4), 1.5, -0.5)  # a strong corner at (3.5, 3.5)
    taps = gaussian_weights(1.0)
    _, resp = smooth_saddle_numpy(g, taps)
    for rel in (0.02, 1.0, 5.0):
        _, p1, y1, x1, v1 = saddle_maxima_numba(g, taps, 2, 9, rel, 1.0)
        _, p2, y2, x2, _ = saddle_maxima_numpy(g, taps, 2, 9, rel, 1.0)
        assert p1 == pytest.approx(p2, rel=1e-9) and p2 == resp.max()
        assert resp[:9, :9].max() == resp.max() > 10 * resp[9:-9, 9:-9].max()
        keep = v1[:, 1, 1] > rel * p1
        assert y1[keep].tolist() == y2.tolist() and x1[keep].tolist() == x2.tolist()
        assert (y2.size > 0) == (rel < 1)


def test_saddle_maxima_flat_image() -> None:
    s, peak, ys, _, vals = saddle_maxima_numba(
        np.full((40, 50), 0.5, np.float32),
        gaussian_weights(2.0).astype(np.float32),
        3,
        7,
        0.02,
        1.0,
    )
    assert peak == 0.0 and ys.size == 0 and vals.shape == (0, 3, 3)
    assert np.all(s == s[0, 0])


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_saddle_maxima_reads_integer_codes(image: np.ndarray, dtype: type) -> None:
    """uint8/uint16 codes with their scale: the numbers of the float32 image, bit for bit."""
    scale = float(np.iinfo(dtype).max)
    codes = np.clip(np.round(image * 0.8 * scale + 0.1 * scale), 0, scale).astype(dtype)
    taps = gaussian_weights(2.0).astype(np.float32)
    a = saddle_maxima_numba(codes, taps, 3, 7, 0.02, scale)
    b = saddle_maxima_numba(codes.astype(np.float32) / scale, taps, 3, 7, 0.02, 1.0)
    assert a[0].dtype == np.float32
    assert np.array_equal(a[0], b[0]) and a[1] == b[1]
    for x, y in zip(a[2:], b[2:], strict=True):
        assert np.array_equal(x, y)
    c = saddle_maxima_numpy(codes, taps, 3, 7, 0.02, scale)
    assert np.abs(c[0] - a[0]).max() < 1e-6


def test_local_maxima_numpy(image: np.ndarray) -> None:
    _, resp = smooth_saddle_numpy(image, gaussian_weights(2.0))
    thr = 0.02 * resp.max()
    y, x = local_maxima_numpy(resp, 3, thr, 7)
    assert y.size > 10
    for yy, xx in zip(y.tolist(), x.tolist(), strict=True):
        assert resp[yy, xx] > thr
        assert resp[yy, xx] >= resp[yy - 3 : yy + 4, xx - 3 : xx + 4].max()


def test_ring_test_twin(image: np.ndarray) -> None:
    from imageform.geometry.checkerboard_candidates import _ring_offsets

    g = image.astype(np.float32)
    smooth, _ = smooth_saddle_numpy(g, gaussian_weights(2.0).astype(np.float32))
    rng = np.random.default_rng(9)
    xy = rng.uniform([-2, -2], [162, 122], size=(300, 2))
    off = _ring_offsets(5.0)
    ok1, d1, c1 = ring_test_numba(smooth, xy, off, 0.1)
    ok2, d2, c2 = ring_test_numpy(smooth, xy, off, 0.1)
    assert 20 < ok1.sum() < 300
    assert ok1.tolist() == ok2.tolist()
    assert np.abs(c1 - c2).max() < 1e-9
    assert np.abs(d1[ok1] - d2[ok2]).max() < 1e-9


def test_neighbors_twin() -> None:
    """On a jittered, rotated grid with clutter: the same table (no exact distance ties)."""
    rng = np.random.default_rng(4)
    i, j = np.mgrid[0:9, 0:7]
    a = 0.3
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    grid = np.stack([i.ravel(), j.ravel()], 1) * 20.0 @ R.T + 100 + rng.normal(0, 0.5, (63, 2))
    clutter = rng.uniform(0, 300, (60, 2))
    xy = np.concatenate([grid, clutter])
    dirs = np.empty((xy.shape[0], 2, 2))
    dirs[:, 0] = R[:, 0]
    dirs[:, 1] = R[:, 1]
    dirs[63:] = np.stack(
        [np.cos(rng.uniform(0, 3, (60, 2))), np.sin(rng.uniform(0, 3, (60, 2)))], -1
    )
    dirs /= np.linalg.norm(dirs, axis=2, keepdims=True)
    for k in (16, 3):
        t1 = neighbors_numba(xy, dirs, 4.0, k, float(np.cos(0.3)))
        t2 = neighbors_numpy(xy, dirs, 4.0, k, float(np.cos(0.3)))
        assert np.array_equal(t1, t2)
    assert (t1[:63] >= 0).sum() > 100
    assert neighbors_numba(xy[:1], dirs[:1], 4.0, 16, 0.9).tolist() == [[[-1, -1], [-1, -1]]]


def test_refine_twin(image: np.ndarray) -> None:
    rng = np.random.default_rng(3)
    pts = rng.uniform([5, 5], [155, 115], size=(40, 2))
    pts[0] = [-3.0, 50.0]  # outside: status 3 or 4 in both
    a, sa = refine_corners_numba(image, pts, 5, 4, 30, 1e-3)
    b, sb = refine_corners_numpy(image, pts, 5, 4, 30, 1e-3)
    assert np.abs(a - b).max() < 1e-9
    assert sa.tolist() == sb.tolist()


def test_sample_bilinear_twin(image: np.ndarray) -> None:
    rng = np.random.default_rng(5)
    u = rng.uniform(-3, 163, size=(50, 8))
    v = rng.uniform(-3, 123, size=(50, 8))
    a = sample_bilinear_numba(image, u, v)
    b = sample_bilinear_numpy(image, u, v)
    assert a.shape == (50, 8)
    assert np.abs(a - b).max() < 1e-12


def test_lattice_rectangle_twin(views: dict[str, np.ndarray]) -> None:
    """The one-kernel lattice walk and rectangle growth give the rectangles of
    label_lattice + grow_rectangle from every seed of three real views (boards, clutter)."""
    from imageform._kernels.checkerboard import lattice_rectangle_numba
    from imageform.geometry.checkerboard_candidates import find_candidates
    from imageform.geometry.checkerboard_grid import grow_rectangle, label_lattice, neighbors

    compared = found = 0
    for name in ("left01.jpg", "left04.jpg", "left12.jpg"):
        cand = find_candidates(views[name], 2.0, scale=255.0)
        nbr = neighbors(cand, 4.0)
        for seed in range(cand.xy.shape[0]):
            for hops in (15, 3):
                a = lattice_rectangle_numba(seed, cand.dirs, nbr, cand.xy, hops, 0.35)
                b = grow_rectangle(label_lattice(seed, cand, nbr, max_hops=hops), cand.xy)
                assert a.shape == b.shape and np.array_equal(a, b), (name, seed, hops)
                compared += 1
                found += a.size == 54
    assert compared > 300 and found > 20


def test_lattice_problem_twin() -> None:
    """The kernel's verdicts and messages are the NumPy twin's, on good and broken grids."""
    from imageform.geometry.checkerboard_grid import lattice_problem, lattice_problem_numpy

    rng = np.random.default_rng(2)
    i, j = np.mgrid[0:6, 0:9]
    base = np.stack([j * 20.0 + 30, i * 18.0 + 40], -1)
    kinds = set()
    for trial in range(400):
        g = base + rng.normal(0, [0.5, 2.0, 4.0, 8.0][trial % 4], base.shape)
        if trial % 7 == 0:
            g = g[:, ::-1]  # the other orientation
        if trial % 11 == 0:
            g[2, 3] = g[2, 4]  # a duplicated point: a zero step
        if trial % 13 == 0:
            g[1, 1] = np.nan
        if trial % 17 == 0:
            g = g[:2]  # too few rows for second differences
        a, b = lattice_problem(g), lattice_problem_numpy(g)
        assert a == b, trial
        kinds.add(None if a is None else a.split(" (")[0])
    # two straight rows that cross: no second differences across rows, cells flip
    row = np.stack([np.arange(9) * 20.0, np.zeros(9)], -1)
    crossing = np.stack([row, row + np.stack([np.zeros(9), 18.0 * (np.arange(9) - 4.5)], -1)])
    a = lattice_problem(crossing)
    assert a == lattice_problem_numpy(crossing) and a is not None and "convex" in a
    kinds.add(a)
    assert len(kinds) >= 3


@pytest.mark.parametrize("taps_sigma", [0.6, 1.2, 3.5])
def test_saddle_maxima_border_zero_is_border_one(image: np.ndarray, taps_sigma: float) -> None:
    """The response is 0 on the outer pixel ring: a border under 1 (taken as 1) finds the
    same maxima and peak, whatever the number of taps (4 at a time and the remainder)."""
    g = image.astype(np.float32)
    taps = gaussian_weights(taps_sigma).astype(np.float32)
    a = saddle_maxima_numba(g, taps, 2, 0, 0.02, 1.0)
    b = saddle_maxima_numba(g, taps, 2, 1, 0.02, 1.0)
    c = saddle_maxima_numpy(g, taps, 2, 1, 0.02, 1.0)
    assert a[1] == b[1] and np.array_equal(a[0], b[0])
    for x, y in zip(a[2:], b[2:], strict=True):
        assert np.array_equal(x, y)
    assert np.abs(a[0] - c[0]).max() < 1e-6
    keep = a[4][:, 1, 1] > 0.02 * a[1]
    assert a[2][keep].tolist() == c[2].tolist() and a[3][keep].tolist() == c[3].tolist()
