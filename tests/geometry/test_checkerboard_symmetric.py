"""Point-symmetry corner refinement (refine_corners_symmetric, find_checkerboard's default).

Truth: rendered corners at known positions (a blurred corner ``0.5 + a erf(x) erf(y)`` in the
board's affine axes, exact and point-symmetric; boards of checkerboard_support rendered under
a homography, and supersampled through a lens below), kernel against its NumPy twin, and
OpenCV's findChessboardCornersSB on its own left*.jpg views (a cross-check, not the truth).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import erf

from imageform.errors import InvalidInputError
from imageform.geometry import find_checkerboard, refine_corners, refine_corners_symmetric

from .checkerboard_support import board_corners, homography, render_board


def _corner(q: tuple[float, float], A: np.ndarray, size: int = 48, blur: float = 1.5,
            ramp: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:  # fmt: skip
    """A blurred checker corner at ``q`` whose axes are the columns of ``A`` (image px)."""
    v, u = np.mgrid[0:size, 0:size].astype(np.float64)
    xy = np.stack([u - q[0], v - q[1]], -1) @ np.linalg.inv(A).T
    s = blur * np.sqrt(2.0)
    return 0.5 + 0.4 * erf(xy[..., 0] / s) * erf(xy[..., 1] / s) + ramp[0] * u + ramp[1] * v


def test_exact_on_a_rendered_corner() -> None:
    img = _corner((23.37, 24.81), np.eye(2))
    res = refine_corners_symmetric(img, [[22.0, 26.0]], half_window=8)
    assert res.status.tolist() == [0]
    # bilinear resampling is not itself point-symmetric off the pixel grid: a bias of < 0.01 px
    assert np.abs(res.corners[0] - [23.37, 24.81]).max() < 1e-2


@settings(max_examples=25, deadline=None)
@given(
    qx=st.floats(20.0, 28.0),
    qy=st.floats(20.0, 28.0),
    angle=st.floats(0.0, np.pi),
    shear=st.floats(-0.5, 0.5),
    aspect=st.floats(0.6, 1.6),
    ramp=st.tuples(st.floats(-0.01, 0.01), st.floats(-0.01, 0.01)),
)
def test_affine_warped_corner_refines_to_its_warped_position(
    qx: float, qy: float, angle: float, shear: float, aspect: float, ramp: tuple[float, float]
) -> None:
    """Point symmetry survives any affine map and a linear shading: the warped corner is found."""
    c, s = np.cos(angle), np.sin(angle)
    A = np.array([[c, -s], [s, c]]) @ np.array([[1.0, shear], [0.0, aspect]])
    img = _corner((qx, qy), A, ramp=ramp)
    res = refine_corners_symmetric(img, [[qx + 0.8, qy - 0.6]], half_window=7)
    assert res.status.tolist() == [0]
    # the bilinear bias grows as the edges sharpen (here to about 1 px wide): 0.02 px at most
    assert np.hypot(*(res.corners[0] - [qx, qy])) < 2e-2


def test_shading_does_not_move_the_corner() -> None:
    a = refine_corners_symmetric(_corner((24.3, 23.6), np.eye(2)), [[25.0, 23.0]], half_window=6)
    img = _corner((24.3, 23.6), np.eye(2), ramp=(0.02, -0.015))
    b = refine_corners_symmetric(img, [[25.0, 23.0]], half_window=6)
    assert np.abs(a.corners - b.corners).max() < 1e-4


def test_accuracy_on_a_rendered_board_beats_the_gradient_method() -> None:
    """A board under perspective, blurred, with noise: corners within 0.03 px (median)."""
    H = homography(20.0, (160.0, 120.0), 0.3, 0.03, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.2, noise=0.01, seed=2)
    truth = board_corners(9, 6, H)
    start = truth + np.random.default_rng(0).uniform(-0.7, 0.7, truth.shape)
    sym = refine_corners_symmetric(img, start, half_window=14)
    grad = refine_corners(img, start, half_window=8)
    e_sym = np.hypot(*(sym.corners - truth).T)
    e_grad = np.hypot(*(grad.corners - truth).T)
    assert (sym.status == 0).all()
    assert np.median(e_sym) < 0.03 and e_sym.max() < 0.1
    assert np.median(e_sym) < np.median(e_grad)


def test_flat_and_edge_windows_are_singular_and_keep_their_start() -> None:
    flat = np.full((40, 40), 0.5)
    u = np.mgrid[0:40, 0:40][1]
    edge = 0.5 + 0.4 * erf((u - 20.3) / 2.0)
    res = refine_corners_symmetric(np.stack([flat, edge]).reshape(80, 40), [[20, 20], [20, 60]])
    assert res.status.tolist() == [2, 2]
    assert res.corners.tolist() == [[20.0, 20.0], [20.0, 60.0]]


def test_non_finite_start_and_empty_input() -> None:
    img = _corner((24.0, 24.0), np.eye(2))
    res = refine_corners_symmetric(img, np.zeros((0, 2)))
    assert res.corners.shape == (0, 2) and res.status.shape == (0,)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"half_window": 1},
        {"half_window": 0},
        {"half_window": 2.5},
        {"half_window": 10**6},
        {"max_iter": 0},
        {"tol": -1.0},
        {"corners": [[1.0, 2.0, 3.0]]},
        {"corners": [[np.nan, 2.0]]},
        {"image": np.zeros((8, 8))},
    ],
)
def test_bad_input(kwargs: dict) -> None:
    args = {"image": _corner((24.0, 24.0), np.eye(2)), "corners": [[24.0, 24.0]], **kwargs}
    with pytest.raises(InvalidInputError):
        refine_corners_symmetric(**args)


@pytest.mark.parametrize("image", ["float32", "float64"])
def test_kernel_and_twin_agree(image: str) -> None:
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_symmetric import (
        refine_symmetric_numba,
        refine_symmetric_numpy,
    )

    H = homography(18.0, (160.0, 120.0), 0.5, 0.04, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.0, noise=0.02, seed=5).astype(image)
    rng = np.random.default_rng(1)
    pts = np.concatenate([board_corners(9, 6, H) + rng.uniform(-1, 1, (54, 2)),
                          rng.uniform(0, 320, (20, 2)), [[-2.0, 30.0], [5.0, 200.0]]])  # fmt: skip
    a, sa = refine_symmetric_numba(img, pts, 6, 30, 1e-3)
    b, sb = refine_symmetric_numpy(img, pts, 6, 30, 1e-3)
    assert sa.tolist() == sb.tolist()
    assert np.abs(a - b).max() < 1e-9
    assert (sa[:54] == 0).all() and set(sa[54:].tolist()) > {0}
    # a per-corner mask of the window's offsets (ChArUco's markers): the pairs (d, -d) left
    # out, the shading block each corner's own; an empty mask is singular (start kept)
    mask = rng.uniform(size=(len(pts), 13, 13)) > 0.4
    mask[0] = False
    a, sa = refine_symmetric_numba(img, pts, 6, 30, 1e-3, mask)
    b, sb = refine_symmetric_numpy(img, pts, 6, 30, 1e-3, mask)
    assert sa.tolist() == sb.tolist() and sa[0] == 2 and a[0].tolist() == pts[0].tolist()
    assert np.abs(a - b).max() < 1e-9
    assert (sa[1:54] <= 1).all()
    # a mask of all offsets is no mask
    full = np.ones((len(pts), 13, 13), dtype=bool)
    c, sc = refine_symmetric_numba(img, pts, 6, 30, 1e-3, full)
    d, sd = refine_symmetric_numba(img, pts, 6, 30, 1e-3)
    assert sc.tolist() == sd.tolist() and np.abs(c - d).max() < 1e-9


def test_find_checkerboard_methods() -> None:
    H = homography(22.0, (160.0, 120.0), 0.2, 0.03, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.5, noise=0.01, seed=3)
    truth = board_corners(9, 6, H)
    sym = find_checkerboard(img, (9, 6))
    grad = find_checkerboard(img, (9, 6), method="gradient", half_window=8)
    assert sym.corners is not None and grad.corners is not None
    # the gradient method is refine_corners alone, as before
    raw = find_checkerboard(img, (9, 6), refine=False).corners
    assert raw is not None
    again = refine_corners(img, raw, half_window=8)
    assert np.abs(grad.corners - again.corners).max() < 1e-9
    e_sym = np.median(np.hypot(*(sym.corners - truth).T))
    e_grad = np.median(np.hypot(*(grad.corners - truth).T))
    assert e_sym < 0.02 and e_sym < e_grad
    with pytest.raises(InvalidInputError, match="method"):
        find_checkerboard(img, (9, 6), method="sb")  # type: ignore[arg-type]


def test_opencv_views_near_findchessboardcornerssb(views: dict[str, np.ndarray]) -> None:
    """OpenCV's left*.jpg: the symmetric corners within 0.2 px (median) of SB's (a cross-check)."""
    cv2 = pytest.importorskip("cv2")
    for name in ("left01.jpg", "left12.jpg"):
        ours = find_checkerboard(views[name], (9, 6))
        ok, sb = cv2.findChessboardCornersSB(views[name], (9, 6), 0)
        assert ours.corners is not None and ok
        d = np.sqrt(((ours.corners[:, None] - sb.reshape(1, -1, 2)) ** 2).sum(-1)).min(1)
        assert np.median(d) < 0.2, name


def test_corners_whose_window_leaves_the_image_keep_the_gradient_position() -> None:
    """A board near the image's left edge: its first column's windows would read replicated
    edge pixels, so those corners stay where the gradient method put them."""
    H = homography(20.0, (95.0, 120.0), 0.0, 0.0, 9, 6)  # first column at u = 15
    img = render_board(9, 6, H, (240, 320), blur=1.2, noise=0.01, seed=4)
    sym = find_checkerboard(img, (9, 6))
    grad = find_checkerboard(img, (9, 6), method="gradient")
    assert sym.corners is not None and grad.corners is not None
    h = int(0.8 * 20.0)
    near = sym.corners[:, 0] < h + 1
    assert near.any() and not near.all()
    assert np.array_equal(sym.corners[near], grad.corners[near])
    assert not np.array_equal(sym.corners[~near], grad.corners[~near])


def test_a_start_pulled_off_by_a_wide_window_does_not_slide_to_a_square_center(
    views: dict[str, np.ndarray],
) -> None:
    """OpenCV's tutorial window (``half_window=11``) on left02.jpg's ~20 px squares pulls some
    gradient corners px off; from there the symmetric step slid to a square's centre (also a
    centre of symmetry) and the grid was rejected. A symmetric corner farther than
    SYMMETRIC_REACH of a step from the detected saddle keeps the first step's position."""
    from imageform.geometry.checkerboard import SYMMETRIC_REACH

    img = views["left02.jpg"]
    wide = find_checkerboard(img, (9, 6), half_window=11)
    assert wide.found, wide.reason
    grad = find_checkerboard(img, (9, 6), method="gradient", half_window=11)
    default = find_checkerboard(img, (9, 6))
    raw = find_checkerboard(img, (9, 6), refine=False)
    assert grad.corners is not None and default.corners is not None and raw.corners is not None
    assert wide.corners is not None
    step = np.median(np.hypot(*np.diff(raw.corners.reshape(6, 9, 2), axis=1).reshape(-1, 2).T))
    moved = np.hypot(*(wide.corners - grad.corners).T) > 0
    assert np.all(np.hypot(*(wide.corners - raw.corners)[moved].T) <= SYMMETRIC_REACH * step)
    # where the wide window did no harm the symmetric corners are the default ones
    fine = np.hypot(*(grad.corners - default.corners).T) < 0.5
    assert np.median(np.hypot(*(wide.corners - default.corners)[fine].T)) < 0.01


def _former_kernel(img: np.ndarray, pts: np.ndarray, h: int, max_iter: int, eps: float,
                   mask: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The kernel as it was before its corners ran on threads, in plain Python floats.

    Each sample interpolated alone (clamped indices), the central differences taken in the
    sums: the same IEEE operations in the same order, so the kernel must agree bit for bit.
    """
    from imageform._kernels.checkerboard_symmetric import (
        _shading_inverse,
        put_back,
        symmetric_pair_mask,
        symmetric_step,
        symmetric_window_weights,
    )

    height, width = img.shape
    w = symmetric_window_weights(h)
    inv0 = _shading_inverse(h, w)
    pm = symmetric_pair_mask(mask, len(pts), h)
    m = 2 * h + 3
    out = pts.copy()
    status = np.ones(len(pts), dtype=np.int64)
    for k in range(len(pts)):
        sx, sy = float(pts[k, 0]), float(pts[k, 1])
        if not (np.isfinite(sx) and np.isfinite(sy)):
            status[k] = 2
            continue
        wk, inv = w, inv0
        if mask is not None:
            wk = np.empty_like(w)
            d11 = d12 = d22 = 0.0
            for i in range(2 * h + 1):
                for j in range(2 * h + 1):
                    wt = float(w[i, j]) * float(pm[k, i, j])
                    wk[i, j] = wt
                    d11 += wt * (j - h) * (j - h)
                    d12 += wt * (j - h) * (i - h)
                    d22 += wt * (i - h) * (i - h)
            dd = d11 * d22 - d12 * d12
            if not (dd > 1e-8 * (d11 + d22) * (d11 + d22)):
                status[k] = 2
                continue
            inv = np.array([[d22 / (4.0 * dd), -d12 / (4.0 * dd)],
                            [-d12 / (4.0 * dd), d11 / (4.0 * dd)]])  # fmt: skip
        cx, cy = sx, sy
        for _ in range(max_iter):
            fx = float(np.floor(min(max(cx, -h - 2.0), width + h + 1.0)))
            fy = float(np.floor(min(max(cy, -h - 2.0), height + h + 1.0)))
            ax, ay = cx - fx, cy - fy
            x0, y0 = int(fx) - h - 1, int(fy) - h - 1
            ys = [min(max(y0 + i, 0), height - 1) for i in range(m + 1)]
            xs = [min(max(x0 + i, 0), width - 1) for i in range(m + 1)]
            p = [[(1.0 - ay) * ((1.0 - ax) * float(img[ys[i], xs[j]])
                                + ax * float(img[ys[i], xs[j + 1]]))
                  + ay * ((1.0 - ax) * float(img[ys[i + 1], xs[j]])
                          + ax * float(img[ys[i + 1], xs[j + 1]]))
                  for j in range(m)] for i in range(m)]  # fmt: skip
            s = [0.0] * 11
            for i in range(2 * h + 1):
                for j in range(2 * h + 1):
                    wt = float(wk[i, j])
                    if wt == 0.0:
                        continue
                    pi, pj = i + 1, j + 1
                    qi, qj = m - 1 - pi, m - 1 - pj
                    r = p[pi][pj] - p[qi][qj]
                    jx = 0.5 * (p[pi][pj + 1] - p[pi][pj - 1]) - 0.5 * (
                        p[qi][qj + 1] - p[qi][qj - 1]
                    )
                    jy = 0.5 * (p[pi + 1][pj] - p[pi - 1][pj]) - 0.5 * (
                        p[qi + 1][qj] - p[qi - 1][qj]
                    )
                    dx, dy = -2.0 * (j - h), -2.0 * (i - h)
                    terms = (wt * jx * jx, wt * jx * jy, wt * jy * jy, wt * jx * dx, wt * jx * dy,
                             wt * jy * dx, wt * jy * dy, wt * jx * r, wt * jy * r, wt * dx * r,
                             wt * dy * r)  # fmt: skip
                    s = [a + b for a, b in zip(s, terms, strict=True)]
            cx, cy, st = symmetric_step.py_func(
                *s, inv[0, 0], inv[0, 1], inv[1, 0], inv[1, 1], cx, cy, width, height, eps * eps
            )
            if st >= 0:
                status[k] = st
                break
        cx, cy, status[k] = put_back.py_func(cx, cy, sx, sy, h, status[k])
        out[k] = cx, cy
    return out, status


@pytest.mark.parametrize("image", ["float32", "float64"])
@pytest.mark.parametrize("masked", [False, True])
def test_kernel_on_threads_is_the_former_serial_kernel_bit_for_bit(
    image: str, masked: bool
) -> None:
    """The corners on 1 and 3 threads, and the former one-corner-at-a-time arithmetic, agree
    exactly (windows inside the image and past its border, singular and non-finite starts)."""
    pytest.importorskip("numba")
    from imageform._kernels import checkerboard_symmetric as ks
    from imageform._kernels.jit import run_tasks

    H = homography(18.0, (160.0, 120.0), 0.5, 0.04, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=1.0, noise=0.02, seed=5).astype(image)
    rng = np.random.default_rng(2)
    pts = np.concatenate([board_corners(9, 6, H)[::4] + rng.uniform(-1, 1, (14, 2)),
                          rng.uniform(0, 320, (4, 2)),
                          [[-2.0, 30.0], [2.0, 200.0], [318.5, 238.0], [np.nan, 3.0]]])  # fmt: skip
    h = 4
    mask = rng.uniform(size=(len(pts), 2 * h + 1, 2 * h + 1)) > 0.3 if masked else None
    mask_arg = mask if masked else None
    want, want_st = _former_kernel(img, pts, h, 30, 1e-3, mask_arg)
    got, got_st = ks.refine_symmetric_numba(img, pts, h, 30, 1e-3, mask_arg)
    assert got_st.tolist() == want_st.tolist()
    assert np.array_equal(got, want, equal_nan=True)
    # the task kernel itself on 1 and 3 threads
    w = ks.symmetric_window_weights(h)
    inv = ks._shading_inverse(h, w)
    pm = ks.symmetric_pair_mask(mask_arg, len(pts), h)
    i32 = img if image == "float32" else ks._EMPTY32
    i64 = img if image == "float64" else ks._EMPTY64
    outs = []
    for threads in (1, 3):
        out = pts.copy()
        st = np.ones(len(pts), dtype=np.int64)
        run_tasks(ks._refine_symmetric, len(pts), i32, i64, image == "float32", out, h, w, inv,
                  pm, masked, 30, 1e-3, out, st, False, threads=threads)  # fmt: skip
        outs.append((out, st))
    for out, st in outs:
        assert st.tolist() == want_st.tolist() and np.array_equal(out, want, equal_nan=True)
