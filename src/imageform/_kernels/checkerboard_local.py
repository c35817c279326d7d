r"""numba kernel of the point-symmetry corner refinement on a local map, with its NumPy twin.

:mod:`imageform._kernels.checkerboard_symmetric` compares the image at ``q + d`` and ``q - d``:
the board is taken as affine around the corner. Here each corner carries a local map ``F`` of
the board's coordinates ``x`` (in squares, the corner at 0) to pixel offsets, and the pairs
compared are the images of ``x`` and ``-x``, point-symmetric on the board whatever the
perspective and lens do to them (Schöps, Larsson, Pollefeys & Sattler 2020, "Why having 10,000
parameters in your camera model is better than twelve", CVPR, sec. 4, define their samples so,
through a homography). ``F`` is a polynomial of degree at most 2 in each of ``x = (s, t)``,

.. math::

    F(s, t) = \sum_{a, b \le 2} c_{ab}\, s^a t^b, \qquad c_{00} = 0,

(the biquadratic through the corner's 3 x 3 neighbours in the grid: perspective and lens
bending to second order). The window's offsets are those of the affine kernel, integer pixel
offsets ``d`` with ``|d| <= h + 1/2``, taken to the board by the inverse ``L⁻¹`` of ``F``'s
linear part (``x = L⁻¹ d``); the cost, with the same additive shading term, is

.. math::

    \min_{q, s} \sum_d w(d)\, \big(I(q + F(L^{-1} d)) - I(q + F(-L^{-1} d)) - 2\, s \cdot d\big)^2.

For an affine ``F`` it is the affine kernel's cost, sample for sample. Offsets whose board
coordinates pass ``extent`` (``max |x_i|``, in squares) are left out (weight 0; the shading
block ``4 Σ w d dᵀ`` is then each corner's own). The sums run over the half of the window
before ``d = 0`` in raster order: the pair of ``-d`` gives the same terms. The image is sampled
bilinearly (edge pixels replicated) with the bilinear interpolation of its central-difference
gradient; Gauss-Newton steps as the affine kernel's (the shading eliminated, steps limited to one
pixel, stop at ``max_iter`` or a step ``<= eps``), the same status codes (0 converged, 1
``max_iter`` reached, 2 singular or a non-finite map: start kept, 3 left the image, 4 moved
farther than ``h``: start kept).

Agreement of kernel and twin is tested (tests/geometry/test_checkerboard_local.py).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.checkerboard_symmetric import (
    PARALLEL_WORK,
    SINGULAR,
    finish_numpy,
    put_back,
    symmetric_step,
    symmetric_step_numpy,
    symmetric_window_weights,
    window_tables,
)
from imageform._kernels.jit import njit, run_tasks

__all__ = ["refine_local_numba", "refine_local_numpy"]


def refine_local_numba(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    linv: NDArray[np.float64],
    coef: NDArray[np.float64],
    h: int,
    max_iter: int,
    eps: float,
    extent: float = np.inf,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Refine ``corners`` (N, 2) on their maps; returns the refined corners and a status.

    ``linv`` (N, 2, 2): the inverse of each map's linear part (pixel offsets to the board);
    ``coef`` (N, 3, 3, 2): ``coef[k, a, b]`` is the pixel offset's coefficient of ``s^a t^b``;
    ``extent``: offsets whose board coordinates ``x = L⁻¹ d`` pass it (``max |x_i|``, in
    squares) are left out. A float32 ``image`` goes to the kernel beside an empty float64 one
    and the other way round.
    """
    w, _ = window_tables(h)
    li = np.ascontiguousarray(linv, dtype=np.float64).reshape(-1, 4)
    cf = np.ascontiguousarray(coef, dtype=np.float64).reshape(-1, 18)
    ext = float(extent)
    n = corners.shape[0]
    out = np.array(corners, dtype=np.float64, order="C")
    status = np.ones(n, dtype=np.int64)
    threads = None if n * (2 * h + 1) ** 2 >= PARALLEL_WORK else 1
    if image.dtype == np.float32:
        i32, i64, is32 = image, _EMPTY64, True
    else:
        i32, i64, is32 = _EMPTY32, np.ascontiguousarray(image, dtype=np.float64), False
    args = (i32, i64, is32, out, li, cf, h, w, ext, max_iter, eps, out, status)
    run_tasks(_refine_local, n, *args, threads=threads)
    return out, status


_EMPTY32 = np.empty((0, 0), dtype=np.float32)
_EMPTY64 = np.empty((0, 0), dtype=np.float64)


@njit(fastmath=False)
def _sample(
    image32: NDArray[np.float32],
    image64: NDArray[np.float64],
    is32: bool,
    x: float,
    y: float,
) -> tuple[float, float, float]:  # pragma: no cover - numba-compiled
    """Bilinear value and central-difference gradient at ``(x, y)`` (edges replicated)."""
    height, width = image32.shape if is32 else image64.shape
    fx = np.floor(min(max(x, -2.0), width + 1.0))
    fy = np.floor(min(max(y, -2.0), height + 1.0))
    ax = min(max(x, -2.0), width + 1.0) - fx
    ay = min(max(y, -2.0), height + 1.0) - fy
    x0 = int(fx)
    y0 = int(fy)
    ym = min(max(y0 - 1, 0), height - 1)
    ya = min(max(y0, 0), height - 1)
    yb = min(max(y0 + 1, 0), height - 1)
    yp = min(max(y0 + 2, 0), height - 1)
    xm = min(max(x0 - 1, 0), width - 1)
    xa = min(max(x0, 0), width - 1)
    xb = min(max(x0 + 1, 0), width - 1)
    xp = min(max(x0 + 2, 0), width - 1)
    if is32:
        v10 = np.float64(image32[ya, xm])
        v11 = np.float64(image32[ya, xa])
        v12 = np.float64(image32[ya, xb])
        v13 = np.float64(image32[ya, xp])
        v20 = np.float64(image32[yb, xm])
        v21 = np.float64(image32[yb, xa])
        v22 = np.float64(image32[yb, xb])
        v23 = np.float64(image32[yb, xp])
        v01 = np.float64(image32[ym, xa])
        v02 = np.float64(image32[ym, xb])
        v31 = np.float64(image32[yp, xa])
        v32 = np.float64(image32[yp, xb])
    else:
        v10 = image64[ya, xm]
        v11 = image64[ya, xa]
        v12 = image64[ya, xb]
        v13 = image64[ya, xp]
        v20 = image64[yb, xm]
        v21 = image64[yb, xa]
        v22 = image64[yb, xb]
        v23 = image64[yb, xp]
        v01 = image64[ym, xa]
        v02 = image64[ym, xb]
        v31 = image64[yp, xa]
        v32 = image64[yp, xb]
    b00 = (1.0 - ay) * (1.0 - ax)
    b01 = (1.0 - ay) * ax
    b10 = ay * (1.0 - ax)
    b11 = ay * ax
    val = b00 * v11 + b01 * v12 + b10 * v21 + b11 * v22
    gx = 0.5 * (b00 * (v12 - v10) + b01 * (v13 - v11) + b10 * (v22 - v20) + b11 * (v23 - v21))
    gy = 0.5 * (b00 * (v21 - v01) + b01 * (v22 - v02) + b10 * (v31 - v11) + b11 * (v32 - v12))
    return val, gx, gy


@njit(fastmath=False)
def _sample_inside(
    image32: NDArray[np.float32],
    image64: NDArray[np.float64],
    is32: bool,
    x: float,
    y: float,
) -> tuple[float, float, float]:  # pragma: no cover - numba-compiled
    """:func:`_sample` at ``1 <= x < width - 2``, ``1 <= y < height - 2``: no clamping needed.

    The same arithmetic as :func:`_sample` (whose clamps change nothing there), the same bits.
    """
    fx = np.floor(x)
    fy = np.floor(y)
    ax = x - fx
    ay = y - fy
    xa = int(fx)
    ya = int(fy)
    if is32:
        v10 = np.float64(image32[ya, xa - 1])
        v11 = np.float64(image32[ya, xa])
        v12 = np.float64(image32[ya, xa + 1])
        v13 = np.float64(image32[ya, xa + 2])
        v20 = np.float64(image32[ya + 1, xa - 1])
        v21 = np.float64(image32[ya + 1, xa])
        v22 = np.float64(image32[ya + 1, xa + 1])
        v23 = np.float64(image32[ya + 1, xa + 2])
        v01 = np.float64(image32[ya - 1, xa])
        v02 = np.float64(image32[ya - 1, xa + 1])
        v31 = np.float64(image32[ya + 2, xa])
        v32 = np.float64(image32[ya + 2, xa + 1])
    else:
        v10 = image64[ya, xa - 1]
        v11 = image64[ya, xa]
        v12 = image64[ya, xa + 1]
        v13 = image64[ya, xa + 2]
        v20 = image64[ya + 1, xa - 1]
        v21 = image64[ya + 1, xa]
        v22 = image64[ya + 1, xa + 1]
        v23 = image64[ya + 1, xa + 2]
        v01 = image64[ya - 1, xa]
        v02 = image64[ya - 1, xa + 1]
        v31 = image64[ya + 2, xa]
        v32 = image64[ya + 2, xa + 1]
    b00 = (1.0 - ay) * (1.0 - ax)
    b01 = (1.0 - ay) * ax
    b10 = ay * (1.0 - ax)
    b11 = ay * ax
    val = b00 * v11 + b01 * v12 + b10 * v21 + b11 * v22
    gx = 0.5 * (b00 * (v12 - v10) + b01 * (v13 - v11) + b10 * (v22 - v20) + b11 * (v23 - v21))
    gy = 0.5 * (b00 * (v21 - v01) + b01 * (v22 - v02) + b10 * (v31 - v11) + b11 * (v32 - v12))
    return val, gx, gy


@njit(fastmath=False, nogil=True)
def _refine_local(
    t0: int,
    t1: int,
    image32: NDArray[np.float32],
    image64: NDArray[np.float64],
    is32: bool,
    corners: NDArray[np.float64],
    linv: NDArray[np.float64],
    coef: NDArray[np.float64],
    h: int,
    w: NDArray[np.float64],
    extent: float,
    max_iter: int,
    eps: float,
    out: NDArray[np.float64],
    status: NDArray[np.int64],
) -> None:  # pragma: no cover - numba-compiled
    """:func:`refine_local_numba`'s kernel over the corners ``t0 .. t1 - 1``.

    A task of :func:`imageform._kernels.jit.run_tasks` (each corner's arithmetic its own: the
    same corners on any number of threads). ``image32`` if ``is32``, else ``image64``.
    ``linv`` (N, 4) and ``coef`` (N, 18): the maps flattened (row-major). The sums run over
    the first half of the window in raster order (``-d`` gives the same terms). A step whose
    samples all lie at least a pixel inside the image reads them without clamping
    (:func:`_sample_inside`, the same bits). Writes ``out[k]`` (``corners`` may be ``out``)
    and ``status[k]`` (1 on entry).
    """
    height, width = image32.shape if is32 else image64.shape
    m = 2 * h + 1
    plus = np.empty((m, m, 2))
    minus = np.empty((m, m, 2))
    wk = np.zeros((m, m))
    eps2 = eps * eps
    for k in range(t0, t1):
        sx = corners[k, 0]
        sy = corners[k, 1]
        finite = np.isfinite(sx) and np.isfinite(sy)
        for i in range(4):
            finite = finite and np.isfinite(linv[k, i])
        for i in range(18):
            finite = finite and np.isfinite(coef[k, i])
        if not finite:
            status[k] = 2
            continue
        # the window's offsets through the map, F(x) and F(-x) for x = L^-1 d, their
        # weights (0 past the extent on the board) and the shading block 4 sum w d d^T
        d11 = 0.0
        d12 = 0.0
        d22 = 0.0
        for i in range(h + 1):
            for j in range(m if i < h else h):
                du = float(j - h)
                dv = float(i - h)
                s = linv[k, 0] * du + linv[k, 1] * dv
                t = linv[k, 2] * du + linv[k, 3] * dv
                wt = w[i, j]
                if abs(s) > extent or abs(t) > extent:
                    wt = 0.0
                wk[i, j] = wt
                d11 += wt * du * du
                d12 += wt * du * dv
                d22 += wt * dv * dv
                pu = 0.0
                pv = 0.0
                mu = 0.0
                mv = 0.0
                sa = 1.0
                for a in range(3):
                    tb = 1.0
                    for b in range(3):
                        if a + b > 0:
                            c = 6 * a + 2 * b
                            sign = 1.0 if (a + b) % 2 == 0 else -1.0
                            pu += coef[k, c] * sa * tb
                            pv += coef[k, c + 1] * sa * tb
                            mu += sign * coef[k, c] * sa * tb
                            mv += sign * coef[k, c + 1] * sa * tb
                        tb *= t
                    sa *= s
                plus[i, j, 0] = pu
                plus[i, j, 1] = pv
                minus[i, j, 0] = mu
                minus[i, j, 1] = mv
        dd = d11 * d22 - d12 * d12
        if not (dd > SINGULAR * (d11 + d22) * (d11 + d22)):
            status[k] = 2
            continue
        # the offsets' extent (weighted ones), for the steps that need no clamping
        lo_u = np.inf
        hi_u = -np.inf
        lo_v = np.inf
        hi_v = -np.inf
        for i in range(h + 1):
            for j in range(m if i < h else h):
                if wk[i, j] != 0.0:
                    lo_u = min(lo_u, plus[i, j, 0], minus[i, j, 0])
                    hi_u = max(hi_u, plus[i, j, 0], minus[i, j, 0])
                    lo_v = min(lo_v, plus[i, j, 1], minus[i, j, 1])
                    hi_v = max(hi_v, plus[i, j, 1], minus[i, j, 1])
        i11 = d22 / (4.0 * dd)
        i12 = -d12 / (4.0 * dd)
        i22 = d11 / (4.0 * dd)
        cx = sx
        cy = sy
        for _ in range(max_iter):
            a11_ = 0.0
            a12_ = 0.0
            a22_ = 0.0
            b11 = 0.0
            b12 = 0.0
            b21 = 0.0
            b22 = 0.0
            g1 = 0.0
            g2 = 0.0
            e1 = 0.0
            e2 = 0.0
            # every sample's 4 x 4 neighbourhood inside (NaN bounds fail the test)
            inside = (
                cx + lo_u - 1.0 >= 1.0
                and cx + hi_u + 1.0 < width - 2.0
                and cy + lo_v - 1.0 >= 1.0
                and cy + hi_v + 1.0 < height - 2.0
            )
            for i in range(h + 1):
                for j in range(m if i < h else h):
                    wt = wk[i, j]
                    if wt == 0.0:
                        continue
                    if inside:
                        vp, gxp, gyp = _sample_inside(
                            image32, image64, is32, cx + plus[i, j, 0], cy + plus[i, j, 1]
                        )
                        vm, gxm, gym = _sample_inside(
                            image32, image64, is32, cx + minus[i, j, 0], cy + minus[i, j, 1]
                        )
                    else:
                        vp, gxp, gyp = _sample(
                            image32, image64, is32, cx + plus[i, j, 0], cy + plus[i, j, 1]
                        )
                        vm, gxm, gym = _sample(
                            image32, image64, is32, cx + minus[i, j, 0], cy + minus[i, j, 1]
                        )
                    r = vp - vm
                    jx = gxp - gxm
                    jy = gyp - gym
                    dx = -2.0 * (j - h)
                    dy = -2.0 * (i - h)
                    a11_ += wt * jx * jx
                    a12_ += wt * jx * jy
                    a22_ += wt * jy * jy
                    b11 += wt * jx * dx
                    b12 += wt * jx * dy
                    b21 += wt * jy * dx
                    b22 += wt * jy * dy
                    g1 += wt * jx * r
                    g2 += wt * jy * r
                    e1 += wt * dx * r
                    e2 += wt * dy * r
            cx, cy, st = symmetric_step(
                a11_, a12_, a22_, b11, b12, b21, b22, g1, g2, e1, e2,
                i11, i12, i12, i22, cx, cy, width, height, eps2,
            )  # fmt: skip
            if st >= 0:
                status[k] = st
                break
        cx, cy, status[k] = put_back(cx, cy, sx, sy, h, status[k])
        out[k, 0] = cx
        out[k, 1] = cy


def local_offsets(
    linv: NDArray[np.float64], coef: NDArray[np.float64], h: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Return ``F(x)``, ``F(-x)`` (N, 2h+1, 2h+1, 2) and ``max |x_i|`` of ``x = L⁻¹ d``.

    ``d`` runs over the window's offsets (N, 2h+1, 2h+1).
    """
    d = np.arange(-h, h + 1, dtype=np.float64)
    dv, du = np.meshgrid(d, d, indexing="ij")
    s = linv[:, 0, 0, None, None] * du + linv[:, 0, 1, None, None] * dv
    t = linv[:, 1, 0, None, None] * du + linv[:, 1, 1, None, None] * dv
    plus = np.zeros((*s.shape, 2))
    minus = np.zeros((*s.shape, 2))
    for a in range(3):
        for b in range(3):
            if a + b == 0:
                continue
            mono = (s**a * t**b)[..., None]
            c = coef[:, None, None, a, b, :]
            plus += c * mono
            minus += (1.0 if (a + b) % 2 == 0 else -1.0) * c * mono
    return plus, minus, np.maximum(np.abs(s), np.abs(t))


def _sample_numpy(
    img: NDArray[np.floating], x: NDArray[np.float64], y: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Bilinear values and central-difference gradients at ``(x, y)`` (edges replicated)."""
    height, width = img.shape
    xc = np.clip(x, -2.0, width + 1.0)
    yc = np.clip(y, -2.0, height + 1.0)
    fx, fy = np.floor(xc), np.floor(yc)
    ax, ay = xc - fx, yc - fy
    x0, y0 = fx.astype(np.int64), fy.astype(np.int64)

    def at(di: int, dj: int) -> NDArray[np.float64]:
        yy = np.clip(y0 + di, 0, height - 1)
        xx = np.clip(x0 + dj, 0, width - 1)
        return np.asarray(img[yy, xx], dtype=np.float64)

    v11, v12, v21, v22 = at(0, 0), at(0, 1), at(1, 0), at(1, 1)
    b00 = (1.0 - ay) * (1.0 - ax)
    b01 = (1.0 - ay) * ax
    b10 = ay * (1.0 - ax)
    b11 = ay * ax
    val = b00 * v11 + b01 * v12 + b10 * v21 + b11 * v22
    gx = 0.5 * (
        b00 * (v12 - at(0, -1))
        + b01 * (at(0, 2) - v11)
        + b10 * (v22 - at(1, -1))
        + b11 * (at(1, 2) - v21)
    )
    gy = 0.5 * (
        b00 * (v21 - at(-1, 0))
        + b01 * (v22 - at(-1, 1))
        + b10 * (at(2, 0) - v11)
        + b11 * (at(2, 1) - v12)
    )
    return val, gx, gy


def refine_local_numpy(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    linv: NDArray[np.float64],
    coef: NDArray[np.float64],
    h: int,
    max_iter: int,
    eps: float,
    extent: float = np.inf,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Plain NumPy twin of :func:`refine_local_numba` (corners in chunks of 64)."""
    n = corners.shape[0]
    out = corners.astype(np.float64).copy()
    status = np.ones(n, dtype=np.int64)
    for lo in range(0, n, 64):
        sl = slice(lo, min(n, lo + 64))
        out[sl], status[sl] = _refine_local_chunk(
            image, corners[sl], linv[sl], coef[sl], h, max_iter, eps, extent
        )
    return out, status


def _refine_local_chunk(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    linv: NDArray[np.float64],
    coef: NDArray[np.float64],
    h: int,
    max_iter: int,
    eps: float,
    extent: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`refine_local_numpy` on at most 64 corners."""
    height, width = image.shape
    n = corners.shape[0]
    half = (2 * h + 1) ** 2 // 2  # the offsets before d = 0 in raster order: -d the others
    dyy, dxx = np.mgrid[-h : h + 1, -h : h + 1].astype(np.float64)
    dxx, dyy = dxx.reshape(-1)[:half], dyy.reshape(-1)[:half]
    dx = -2.0 * dxx
    dy = -2.0 * dyy
    cur = corners.astype(np.float64).copy()
    start = cur.copy()
    status = np.ones(n, dtype=np.int64)
    finite = (
        np.all(np.isfinite(cur), axis=1)
        & np.all(np.isfinite(linv.reshape(n, -1)), axis=1)
        & np.all(np.isfinite(coef.reshape(n, -1)), axis=1)
    )
    safe_l = np.where(finite[:, None, None], linv, 0.0)
    safe_c = np.where(finite[:, None, None, None], coef, 0.0)
    plus, minus, board = local_offsets(safe_l, safe_c, h)
    plus = plus.reshape(n, -1, 2)[:, :half]
    minus = minus.reshape(n, -1, 2)[:, :half]
    w_all = symmetric_window_weights(h).reshape(-1)[:half] * (
        board.reshape(n, -1)[:, :half] <= extent
    )
    d11 = np.sum(w_all * dxx * dxx, axis=1)
    d12 = np.sum(w_all * dxx * dyy, axis=1)
    d22 = np.sum(w_all * dyy * dyy, axis=1)
    dd = d11 * d22 - d12 * d12
    flat = ~(dd > SINGULAR * (d11 + d22) * (d11 + d22))
    safe = np.where(flat, 1.0, 4.0 * dd)
    inv_all = np.stack([np.stack([d22, -d12], -1), np.stack([-d12, d11], -1)], 1)
    inv_all = inv_all / safe[:, None, None]
    status[~finite | flat] = 2
    active = finite & ~flat
    eps2 = eps * eps
    img = np.asarray(image)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        c = cur[idx]
        w = w_all[idx]
        inv = inv_all[idx]
        cxx = c[:, 0, None]
        cyy = c[:, 1, None]
        vp, gxp, gyp = _sample_numpy(img, cxx + plus[idx, :, 0], cyy + plus[idx, :, 1])
        vm, gxm, gym = _sample_numpy(img, cxx + minus[idx, :, 0], cyy + minus[idx, :, 1])
        r = (vp - vm) * w
        jx = gxp - gxm
        jy = gyp - gym
        wjx = w * jx
        wjy = w * jy
        a11 = np.sum(wjx * jx, axis=1)
        a12 = np.sum(wjx * jy, axis=1)
        a22 = np.sum(wjy * jy, axis=1)
        b = np.stack(
            [
                np.stack([np.sum(wjx * dx, axis=1), np.sum(wjx * dy, axis=1)], -1),
                np.stack([np.sum(wjy * dx, axis=1), np.sum(wjy * dy, axis=1)], -1),
            ],
            1,
        )
        g = np.stack([np.sum(jx * r, axis=1), np.sum(jy * r, axis=1)], -1)
        e = np.stack([np.sum(dx * r, axis=1), np.sum(dy * r, axis=1)], -1)
        nxy, st = symmetric_step_numpy(a11, a12, a22, b, g, e, inv, c, width, height, eps2)
        moved = st != 2
        cur[idx[moved]] = nxy[moved]
        stop = st >= 0
        status[idx[stop]] = st[stop]
        active[idx[stop]] = False
    return finish_numpy(cur, start, status, h)
