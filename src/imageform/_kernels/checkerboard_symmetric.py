r"""numba kernel of the point-symmetry corner refinement, with its plain NumPy twin.

A checkerboard corner is the centre of a point symmetry of the board: ``I(q + d) = I(q - d)``
for every offset ``d``, and that stays true through any affine map of the board (a view's
local perspective) and any point-symmetric blur (defocus, a Gaussian lens blur, the
sensor's pixel area). The refinement (Schöps, Larsson, Pollefeys & Sattler 2020, "Why having
10,000 parameters in your camera model is better than twelve", CVPR, sec. 4 on feature
refinement) moves ``q`` to the least-squares centre of symmetry of a round window, with an
additive linear shading term ``s · d`` (a brightness gradient across the window):

.. math::

    \min_{q, s} \sum_d w(d)\, \big(I(q + d) - I(q - d) - 2\, s \cdot d\big)^2,
    \qquad w(d) = e^{-|d|^2 / (2 (h/2)^2)}, \quad |d| \le h + 1/2,

over the integer offsets ``d`` of the ``(2 h + 1)²`` square. The image is resampled bilinearly
(edge pixels replicated) on the integer grid ``q + d``, so that ``q + d`` and ``q - d`` are
samples of one ``(2 h + 3)²`` patch; the derivatives are central differences of that patch
(the bilinear interpolation of the image's central-difference gradient). Each Gauss-Newton step
solves the 4 x 4 normal equations by eliminating ``s`` (the shading block ``4 Σ w d dᵀ`` is
constant) and is limited to one pixel. It stops after ``max_iter`` steps or when a step is
``<= eps``; ``status`` as ``refine_corners``' (0 converged, 1 ``max_iter`` reached, 2 singular:
a flat window or a straight edge, 3 left the image, 4 moved farther than ``h`` — start kept).

An optional ``mask`` (N, 2 h + 1, 2 h + 1) of 0/1 per corner multiplies the window: the pairs
``(q + d, q - d)`` with ``mask[d] = 0`` (or ``mask[-d] = 0``: the product of the two is used) are
left out of the sums, and the shading block is then each corner's own (a ChArUco corner's
markers, whose bits are not point-symmetric, are left out so). ChArUco's own kernel
(:func:`charuco_symmetric_numba`) makes each corner's mask (:func:`marker_mask_numpy`) inside
it, from the corner's homography, and refines every corner, whatever its window, in one call;
its twin is the mask and :func:`refine_symmetric_numpy` per window size.

Agreement of kernel and twin is tested (tests/geometry/test_checkerboard_symmetric.py).
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit, run_tasks

__all__ = ["refine_symmetric_numba", "refine_symmetric_numpy", "symmetric_window_weights"]

#: a step's normal matrix is singular when ``det < SINGULAR * trace²`` (an edge, a flat window)
SINGULAR = 1e-8

#: the corners run on numba's threads (:func:`imageform._kernels.jit.run_tasks`) when their
#: windows hold at least this many offsets in all (``N (2 h + 1)²``); fewer run in the calling
#: thread (the pool's hand-over, tens of microseconds, is then a fair share of the work)
PARALLEL_WORK = 8192


def symmetric_window_weights(h: int) -> NDArray[np.float64]:
    """Return the ``(2 h + 1)²`` window: ``exp(-|d|²/(2 (h/2)²))`` inside ``|d| <= h + 1/2``."""
    d = np.arange(-h, h + 1, dtype=np.float64)
    r2 = d[:, None] ** 2 + d[None, :] ** 2
    s2 = (0.5 * h) ** 2
    return np.where(r2 <= (h + 0.5) ** 2, np.exp(-r2 / (2.0 * s2)), 0.0).astype(np.float64)


def _shading_inverse(h: int, w: NDArray[np.float64]) -> NDArray[np.float64]:
    """Inverse of the shading block ``4 Σ w d dᵀ`` of the normal equations (2 x 2)."""
    dy, dx = np.mgrid[-h : h + 1, -h : h + 1].astype(np.float64)
    m = 4.0 * np.array(
        [[np.sum(w * dx * dx), np.sum(w * dx * dy)], [np.sum(w * dx * dy), np.sum(w * dy * dy)]]
    )
    return np.asarray(np.linalg.inv(m), dtype=np.float64)


@functools.lru_cache(maxsize=32)
def window_tables(h: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return :func:`symmetric_window_weights` ``(h)`` and its :func:`_shading_inverse`, kept.

    Computed once per window size (each call of a refinement needs both: a fair share of a
    small view's time). Shared: the kernels only read them.
    """
    w = symmetric_window_weights(h)
    return w, _shading_inverse(h, w)


def symmetric_pair_mask(
    mask: NDArray[np.floating] | NDArray[np.bool_] | None, n: int, h: int
) -> NDArray[np.float64]:
    """Return ``mask`` (n, 2h+1, 2h+1) as 0/1 float64 kept only where ``d`` and ``-d`` both are.

    ``(0, 2h+1, 2h+1)`` (no mask) for ``None``.
    """
    m = 2 * h + 1
    if mask is None:
        return np.empty((0, m, m), dtype=np.float64)
    k = np.asarray(mask) != 0
    if k.shape != (n, m, m):
        raise ValueError(f"expected a mask of shape {(n, m, m)}, got {k.shape}")
    return np.ascontiguousarray(k & k[:, ::-1, ::-1], dtype=np.float64)


def refine_symmetric_numba(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    h: int,
    max_iter: int,
    eps: float,
    mask: NDArray[np.floating] | NDArray[np.bool_] | None = None,
    half: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Refine ``corners`` (N, 2) in ``(u, v)``; returns the refined corners and a status.

    A float32 ``image`` goes to the kernel beside an empty float64 one and the other way round
    (one compilation serves both); other dtypes are read as float64. ``mask``: see the module.
    ``half``: the sums run over the half of the window before ``d = 0`` in raster order (the
    pair of ``-d`` gives the same terms), the normal equations halved: the same steps but for
    the rounding, in about two thirds of the time (a large window's steps); False (the
    default) sums the whole window, as before.
    """
    w, inv = window_tables(h)
    pm = symmetric_pair_mask(mask, corners.shape[0], h)
    has = mask is not None
    n = corners.shape[0]
    out = np.array(corners, dtype=np.float64, order="C")
    status = np.ones(n, dtype=np.int64)
    threads = None if n * (2 * h + 1) ** 2 >= PARALLEL_WORK else 1
    if image.dtype == np.float32:
        i32, i64, is32 = image, _EMPTY64, True
    else:
        i32, i64, is32 = _EMPTY32, np.ascontiguousarray(image, dtype=np.float64), False
    args = (i32, i64, is32, out, h, w, inv, pm, has, max_iter, eps, out, status, bool(half))
    run_tasks(_refine_symmetric, n, *args, threads=threads)
    return out, status


@njit(fastmath=False)
def symmetric_step(
    a11_: float,
    a12_: float,
    a22_: float,
    b11: float,
    b12: float,
    b21: float,
    b22: float,
    g1: float,
    g2: float,
    e1: float,
    e2: float,
    i00: float,
    i01: float,
    i10: float,
    i11: float,
    cx: float,
    cy: float,
    width: int,
    height: int,
    eps2: float,
) -> tuple[float, float, int]:  # pragma: no cover - numba-compiled
    """One Gauss-Newton step of a symmetric refinement: the corner moved, and a status.

    The normal equations of (q, s) are [[A, B], [B^T, D]] with rhs (g, e) and D's inverse
    ``[[i00, i01], [i10, i11]]`` (the shading block); the step solves the Schur complement
    S = A - B D^-1 B^T against g - B D^-1 e, its length clamped to 1 px. Status -1: go on;
    0: converged (the step's square at most ``eps2``); 2: singular (the corner not moved);
    3: moved off the image. Shared by every symmetric kernel (the checkerboard's, ChArUco's
    and the local map's), the same arithmetic in each.
    """
    c11 = b11 * i00 + b12 * i10
    c12 = b11 * i01 + b12 * i11
    c21 = b21 * i00 + b22 * i10
    c22 = b21 * i01 + b22 * i11
    s11 = a11_ - (c11 * b11 + c12 * b12)
    s12 = a12_ - (c11 * b21 + c12 * b22)
    s22 = a22_ - (c21 * b21 + c22 * b22)
    r1 = g1 - (c11 * e1 + c12 * e2)
    r2 = g2 - (c21 * e1 + c22 * e2)
    det = s11 * s22 - s12 * s12
    tr = s11 + s22
    if not (det > SINGULAR * tr * tr) or not np.isfinite(det):
        return cx, cy, 2
    stx = -(s22 * r1 - s12 * r2) / det
    sty = -(-s12 * r1 + s11 * r2) / det
    nrm2 = stx * stx + sty * sty
    if nrm2 > 1.0:
        f = 1.0 / np.sqrt(nrm2)
        stx *= f
        sty *= f
        nrm2 = 1.0
    cx += stx
    cy += sty
    if cx < 0 or cx >= width or cy < 0 or cy >= height:
        return cx, cy, 3
    if nrm2 <= eps2:
        return cx, cy, 0
    return cx, cy, -1


@njit(fastmath=False)
def put_back(
    cx: float, cy: float, sx: float, sy: float, h: int, status: int
) -> tuple[float, float, int]:  # pragma: no cover - numba-compiled
    """Return a refined corner put back at its start ``(sx, sy)`` where it failed.

    A singular step (status 2) keeps the start; a corner that moved more than ``h`` (the
    window's half size) either way is put back with status 4 (:func:`finish_numpy`'s rule,
    one corner).
    """
    if status == 2:
        cx = sx
        cy = sy
    if abs(cx - sx) > h or abs(cy - sy) > h:
        return sx, sy, 4
    return cx, cy, status


_EMPTY32 = np.empty((0, 0), dtype=np.float32)
_EMPTY64 = np.empty((0, 0), dtype=np.float64)


@njit(fastmath=False, nogil=True)
def _refine_symmetric(
    t0: int,
    t1: int,
    image32: NDArray[np.float32],
    image64: NDArray[np.float64],
    is32: bool,
    corners: NDArray[np.float64],
    h: int,
    w: NDArray[np.float64],
    inv_all: NDArray[np.float64],
    masks: NDArray[np.float64],
    has_mask: bool,
    max_iter: int,
    eps: float,
    out: NDArray[np.float64],
    status: NDArray[np.int64],
    half: bool,
) -> None:  # pragma: no cover - numba-compiled
    """:func:`refine_symmetric_numba`'s kernel over the corners ``t0 .. t1 - 1``.

    A task of :func:`imageform._kernels.jit.run_tasks`: each corner's arithmetic is its own
    (no sum runs across corners), so the corners are the same on any number of threads.
    ``image32`` if ``is32``, else ``image64``. ``masks[k]`` (when ``has_mask``) multiplies
    ``w`` for corner ``k``, whose shading block is then inverted here. Writes ``out[k]``
    (``corners`` may be ``out``: a corner is read before it is written) and ``status[k]``
    (1 on entry). The patch is interpolated along the rows first, each row once (the same
    products and sums as per sample); a window inside the image reads it without clamping;
    its halved central differences are taken once per step (each serves ``d`` and ``-d``:
    the same values); the sums skip the offsets outside the window's disk (weight 0, skipped
    before too) and add in the same order as before. ``half``: the sums over the rows
    ``0 .. h`` only (row ``h`` up to ``d = 0``), the shading block's inverse doubled.
    """
    height, width = image32.shape if is32 else image64.shape
    m = 2 * h + 3
    nn = 2 * h + 1
    patch = np.empty((m, m))
    gxs = np.empty((m, m))
    gys = np.empty((m, m))
    rowi = np.empty((m + 1, m))
    ys = np.empty(m + 1, dtype=np.int64)
    xs = np.empty(m + 1, dtype=np.int64)
    eps2 = eps * eps
    wk = w.copy()
    inv = inv_all.copy()
    # the columns j0[i] .. j1[i] - 1 of row i that hold the disk's (nonzero) weights
    j0 = np.full(nn, nn, dtype=np.int64)
    j1 = np.zeros(nn, dtype=np.int64)
    for i in range(nn):
        for j in range(nn):
            if w[i, j] != 0.0:
                j0[i] = min(j0[i], j)
                j1[i] = j + 1
    rows = nn
    scale = 1.0
    if half:
        rows = h + 1
        j1[h] = h
        scale = 2.0
    for k in range(t0, t1):
        sx = corners[k, 0]
        sy = corners[k, 1]
        if not (np.isfinite(sx) and np.isfinite(sy)):
            status[k] = 2
            continue
        if has_mask:
            d11 = 0.0
            d12 = 0.0
            d22 = 0.0
            for i in range(nn):
                for j in range(nn):
                    wt = w[i, j] * masks[k, i, j]
                    wk[i, j] = wt
                    d11 += wt * (j - h) * (j - h)
                    d12 += wt * (j - h) * (i - h)
                    d22 += wt * (i - h) * (i - h)
            dd = d11 * d22 - d12 * d12
            if not (dd > SINGULAR * (d11 + d22) * (d11 + d22)):
                out[k, 0] = sx
                out[k, 1] = sy
                status[k] = 2
                continue
            inv[0, 0] = d22 / (4.0 * dd)
            inv[0, 1] = -d12 / (4.0 * dd)
            inv[1, 0] = -d12 / (4.0 * dd)
            inv[1, 1] = d11 / (4.0 * dd)
        cx = sx
        cy = sy
        for _ in range(max_iter):
            fx = np.floor(min(max(cx, -h - 2.0), width + h + 1.0))
            fy = np.floor(min(max(cy, -h - 2.0), height + h + 1.0))
            ax = cx - fx
            ay = cy - fy
            bx = 1.0 - ax
            by = 1.0 - ay
            x0 = int(fx) - h - 1
            y0 = int(fy) - h - 1
            if x0 >= 0 and y0 >= 0 and x0 + m < width and y0 + m < height:
                for i in range(m + 1):
                    if is32:
                        src32 = image32[y0 + i, x0 : x0 + m + 1]
                        for j in range(m):
                            rowi[i, j] = bx * np.float64(src32[j]) + ax * np.float64(src32[j + 1])
                    else:
                        src64 = image64[y0 + i, x0 : x0 + m + 1]
                        for j in range(m):
                            rowi[i, j] = bx * src64[j] + ax * src64[j + 1]
            else:
                for i in range(m + 1):
                    ys[i] = min(max(y0 + i, 0), height - 1)
                    xs[i] = min(max(x0 + i, 0), width - 1)
                for i in range(m + 1):
                    for j in range(m):
                        if is32:
                            a0 = np.float64(image32[ys[i], xs[j]])
                            a1 = np.float64(image32[ys[i], xs[j + 1]])
                        else:
                            a0 = image64[ys[i], xs[j]]
                            a1 = image64[ys[i], xs[j + 1]]
                        rowi[i, j] = bx * a0 + ax * a1
            for i in range(m):
                for j in range(m):
                    patch[i, j] = by * rowi[i, j] + ay * rowi[i + 1, j]
            # the central differences, halved, at the window's offsets (patch's 1 .. m - 2)
            for i in range(1, m - 1):
                for j in range(1, m - 1):
                    gxs[i, j] = 0.5 * (patch[i, j + 1] - patch[i, j - 1])
                    gys[i, j] = 0.5 * (patch[i + 1, j] - patch[i - 1, j])
            # normal equations of (q, s): [[A, B], [B^T, D]] (D constant), rhs (g, e)
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
            for i in range(rows):
                for j in range(j0[i], j1[i]):
                    wt = wk[i, j]
                    if wt == 0.0:
                        continue
                    pi = i + 1
                    pj = j + 1
                    qi = m - 1 - pi
                    qj = m - 1 - pj
                    r = patch[pi, pj] - patch[qi, qj]
                    jx = gxs[pi, pj] - gxs[qi, qj]
                    jy = gys[pi, pj] - gys[qi, qj]
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
                scale * inv[0, 0], scale * inv[0, 1], scale * inv[1, 0], scale * inv[1, 1],
                cx, cy, width, height, eps2,
            )  # fmt: skip
            if st >= 0:
                status[k] = st
                break
        cx, cy, status[k] = put_back(cx, cy, sx, sy, h, status[k])
        out[k, 0] = cx
        out[k, 1] = cy


def symmetric_step_numpy(
    a11: NDArray[np.float64],
    a12: NDArray[np.float64],
    a22: NDArray[np.float64],
    b: NDArray[np.float64],
    g: NDArray[np.float64],
    e: NDArray[np.float64],
    inv: NDArray[np.float64],
    c: NDArray[np.float64],
    width: int,
    height: int,
    eps2: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`symmetric_step` for k corners at once: the moved corners (k, 2) and a status.

    ``b`` (k, 2, 2), ``g`` and ``e`` (k, 2), ``inv`` the shading blocks' inverses (k, 2, 2),
    ``c`` the corners. Status -1: go on; 0: converged; 2: singular (not moved); 3: off the
    image.
    """
    cm = b @ inv
    s = np.stack([np.stack([a11, a12], -1), np.stack([a12, a22], -1)], 1)
    s = s - cm @ np.swapaxes(b, 1, 2)
    rhs = g - np.einsum("kij,kj->ki", cm, e)
    s11, s12, s22 = s[:, 0, 0], 0.5 * (s[:, 0, 1] + s[:, 1, 0]), s[:, 1, 1]
    det = s11 * s22 - s12 * s12
    tr = s11 + s22
    singular = ~(det > SINGULAR * tr * tr) | ~np.isfinite(det)
    safe = np.where(singular, 1.0, det)
    stx = -(s22 * rhs[:, 0] - s12 * rhs[:, 1]) / safe
    sty = -(-s12 * rhs[:, 0] + s11 * rhs[:, 1]) / safe
    nrm2 = stx * stx + sty * sty
    big = nrm2 > 1.0
    fac = np.where(big, 1.0 / np.sqrt(np.where(big, nrm2, 1.0)), 1.0)
    stx, sty = stx * fac, sty * fac
    nrm2 = np.where(big, 1.0, nrm2)
    moved = ~singular
    nx = c[:, 0] + stx
    ny = c[:, 1] + sty
    outside = moved & ((nx < 0) | (nx >= width) | (ny < 0) | (ny >= height))
    done = moved & ~outside & (nrm2 <= eps2)
    st = np.full(c.shape[0], -1, dtype=np.int64)
    st[singular] = 2
    st[outside] = 3
    st[done] = 0
    return np.stack([nx, ny], -1), st


def finish_numpy(
    cur: NDArray[np.float64], start: NDArray[np.float64], status: NDArray[np.int64], h: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Put back the corners that went singular (status 2) or moved more than ``h`` (status 4)."""
    back = status == 2
    cur[back] = start[back]
    with np.errstate(invalid="ignore"):
        far = (np.abs(cur[:, 0] - start[:, 0]) > h) | (np.abs(cur[:, 1] - start[:, 1]) > h)
    cur[far] = start[far]
    status[far] = 4
    return cur, status


def refine_symmetric_numpy(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    h: int,
    max_iter: int,
    eps: float,
    mask: NDArray[np.floating] | NDArray[np.bool_] | None = None,
    half: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Plain NumPy twin of :func:`refine_symmetric_numba` (all corners at once).

    ``half``, a matter of the kernel's rounding, changes nothing here.
    """
    height, width = image.shape
    n = corners.shape[0]
    w0 = symmetric_window_weights(h)
    dyy, dxx = np.mgrid[-h : h + 1, -h : h + 1].astype(np.float64)
    if mask is None:
        w_all = np.broadcast_to(w0, (n, 2 * h + 1, 2 * h + 1))
        inv_all = np.broadcast_to(_shading_inverse(h, w0), (n, 2, 2))
        flat = np.zeros(n, dtype=bool)
    else:
        w_all = w0 * symmetric_pair_mask(mask, n, h)
        d11 = np.sum(w_all * dxx * dxx, axis=(1, 2))
        d12 = np.sum(w_all * dxx * dyy, axis=(1, 2))
        d22 = np.sum(w_all * dyy * dyy, axis=(1, 2))
        dd = d11 * d22 - d12 * d12
        flat = ~(dd > SINGULAR * (d11 + d22) * (d11 + d22))
        safe = np.where(flat, 1.0, 4.0 * dd)
        inv_all = np.stack([np.stack([d22, -d12], -1), np.stack([-d12, d11], -1)], 1)
        inv_all = inv_all / safe[:, None, None]
    dx = -2.0 * dxx
    dy = -2.0 * dyy
    o = np.arange(-h - 1, h + 2)
    cur = corners.astype(np.float64).copy()
    start = cur.copy()
    status = np.ones(n, dtype=np.int64)
    active: NDArray[np.bool_] = np.all(np.isfinite(cur), axis=1)
    status[~active] = 2
    status[active & flat] = 2
    active &= ~flat
    eps2 = eps * eps
    img = np.asarray(image)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        c = cur[idx]
        w = w_all[idx]
        inv = inv_all[idx]
        lo = np.array([-h - 2.0, -h - 2.0])
        hi = np.array([width + h + 1.0, height + h + 1.0])
        f = np.floor(np.clip(c, lo, hi))
        ax = (c[:, 0] - f[:, 0])[:, None, None]
        ay = (c[:, 1] - f[:, 1])[:, None, None]
        ys = f[:, 1].astype(np.int64)[:, None] + o[None, :]
        xs = f[:, 0].astype(np.int64)[:, None] + o[None, :]
        ya = np.clip(ys, 0, height - 1)[:, :, None]
        yb = np.clip(ys + 1, 0, height - 1)[:, :, None]
        xa = np.clip(xs, 0, width - 1)[:, None, :]
        xb = np.clip(xs + 1, 0, width - 1)[:, None, :]
        p = (1.0 - ay) * ((1.0 - ax) * img[ya, xa].astype(np.float64) + ax * img[ya, xb]) + ay * (
            (1.0 - ax) * img[yb, xa].astype(np.float64) + ax * img[yb, xb]
        )
        mid = p[:, 1:-1, 1:-1]
        gx = 0.5 * (p[:, 1:-1, 2:] - p[:, 1:-1, :-2])
        gy = 0.5 * (p[:, 2:, 1:-1] - p[:, :-2, 1:-1])
        r = (mid - mid[:, ::-1, ::-1]) * w
        jx = gx - gx[:, ::-1, ::-1]
        jy = gy - gy[:, ::-1, ::-1]
        wjx = w * jx
        wjy = w * jy
        a11 = np.sum(wjx * jx, axis=(1, 2))
        a12 = np.sum(wjx * jy, axis=(1, 2))
        a22 = np.sum(wjy * jy, axis=(1, 2))
        b = np.stack(
            [
                np.stack([np.sum(wjx * dx, axis=(1, 2)), np.sum(wjx * dy, axis=(1, 2))], -1),
                np.stack([np.sum(wjy * dx, axis=(1, 2)), np.sum(wjy * dy, axis=(1, 2))], -1),
            ],
            1,
        )  # (k, 2, 2)
        g = np.stack([np.sum(jx * r, axis=(1, 2)), np.sum(jy * r, axis=(1, 2))], -1)
        e = np.stack([np.sum(dx * r, axis=(1, 2)), np.sum(dy * r, axis=(1, 2))], -1)
        nxy, st = symmetric_step_numpy(a11, a12, a22, b, g, e, inv, c, width, height, eps2)
        moved = st != 2
        cur[idx[moved]] = nxy[moved]
        stop = st >= 0
        status[idx[stop]] = st[stop]
        active[idx[stop]] = False
    return finish_numpy(cur, start, status, h)


def marker_mask_numpy(
    hinv: NDArray[np.float64],
    pred: NDArray[np.float64],
    start: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    h: int,
    cols: int,
    rows: int,
    parity: int,
    shape: tuple[int, int],
) -> NDArray[np.bool_]:
    """Which offsets ``d`` of each ChArUco corner's ``(2h+1)²`` window are usable (m, 2h+1, 2h+1).

    ``pred + d`` is taken to the board by ``hinv`` (pixels to square units); it is off when on a
    white square's marker grown by ``guard`` (the box ``[lo, 1 - lo]²`` of its square, ``lo``
    the marker's inset less the guard), off the board (by ``guard``), or when ``start + d`` is
    not a pixel inside the image (``shape``). ``d`` is kept only when ``-d`` is too.
    """
    d = np.arange(-h, h + 1, dtype=np.float64)
    du, dv = np.meshgrid(d, d)
    pu = pred[:, 0, None, None] + du[None]
    pv = pred[:, 1, None, None] + dv[None]
    x = hinv[:, 0, 0, None, None] * pu + hinv[:, 0, 1, None, None] * pv + hinv[:, 0, 2, None, None]
    y = hinv[:, 1, 0, None, None] * pu + hinv[:, 1, 1, None, None] * pv + hinv[:, 1, 2, None, None]
    z = hinv[:, 2, 0, None, None] * pu + hinv[:, 2, 1, None, None] * pv + hinv[:, 2, 2, None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        bx, by = x / z, y / z
    g = guard[:, None, None]
    lo3 = lo[:, None, None]
    ok = np.isfinite(bx) & np.isfinite(by) & (z != 0)
    ok &= (bx >= g) & (bx <= cols - g) & (by >= g) & (by <= rows - g)
    bx, by = np.where(ok, bx, 0.0), np.where(ok, by, 0.0)
    fx, fy = np.floor(bx), np.floor(by)
    reach = 1.0 if bool(np.any(lo < 0)) else 0.0  # a guard past the margin: the neighbours too
    for oy in np.arange(-reach, reach + 1):
        for ox in np.arange(-reach, reach + 1):
            sc, sr = fx + ox, fy + oy
            white = (sr + sc) % 2 == parity
            on = (
                (bx >= sc + lo3)
                & (bx <= sc + 1.0 - lo3)
                & (by >= sr + lo3)
                & (by <= sr + 1.0 - lo3)
            )
            ok &= ~(white & on)
    height, width = shape
    u = start[:, 0, None] + d[None]
    v = start[:, 1, None] + d[None]
    in_u = (u >= 1.0) & (u <= width - 2.0)
    in_v = (v >= 1.0) & (v <= height - 2.0)
    ok &= in_v[:, :, None] & in_u[:, None, :]
    return np.asarray(ok & ok[:, ::-1, ::-1])


@njit(fastmath=False)
def marker_mask_numba(
    hinv: NDArray[np.float64],
    pred: NDArray[np.float64],
    start: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    h: int,
    cols: int,
    rows: int,
    parity: int,
    shape: tuple[int, int],
) -> NDArray[np.bool_]:  # pragma: no cover - numba-compiled
    """:func:`marker_mask_numpy`'s kernel (the same arithmetic, one sample at a time)."""
    m = hinv.shape[0]
    n = 2 * h + 1
    height, width = shape
    out = np.zeros((m, n, n), dtype=np.bool_)
    for k in range(m):
        _marker_mask_one(
            out[k],
            hinv,
            pred,
            start,
            lo,
            guard,
            k,
            h,
            cols,
            rows,
            parity,
            height,
            width,
            _NO_WEIGHTS,
            True,
        )
    return out


_NO_WEIGHTS = np.empty(0, dtype=np.float64)


@njit(fastmath=False, error_model="numpy")
def _marker_mask_one(
    out: NDArray[np.bool_],
    hinv: NDArray[np.float64],
    pred: NDArray[np.float64],
    start: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    k: int,
    h: int,
    cols: int,
    rows: int,
    parity: int,
    height: int,
    width: int,
    w: NDArray[np.float64],
    pairs: bool,
) -> None:  # pragma: no cover - numba-compiled
    """Corner ``k``'s mask (:func:`marker_mask_numpy`) into ``out`` (at least 2h+1 square).

    ``w`` (the window's ``(2h+1)²`` weights, flat) when not empty: the offsets of weight 0 are
    left off without being computed (they count for nothing). ``pairs``: keep ``d`` only where
    ``-d`` is kept too (else the caller pairs them).
    """
    n = 2 * h + 1
    g = guard[k]
    lk = lo[k]
    reach = 1 if lk < 0 else 0
    has_w = w.shape[0] > 0
    h00, h01, h02 = hinv[k, 0, 0], hinv[k, 0, 1], hinv[k, 0, 2]
    h10, h11, h12 = hinv[k, 1, 0], hinv[k, 1, 1], hinv[k, 1, 2]
    h20, h21, h22 = hinv[k, 2, 0], hinv[k, 2, 1], hinv[k, 2, 2]
    par = float(parity)
    right = cols - g
    bottom = rows - g
    pus = np.empty(n)
    bxs = np.empty(n)
    bys = np.empty(n)
    zs = np.empty(n)
    # the columns inside the image (start + d a pixel in), a run
    j0 = n
    j1 = 0
    for j in range(n):
        pus[j] = pred[k, 0] + (j - h)
        u = start[k, 0] + (j - h)
        if u >= 1.0 and u <= width - 2.0:
            j0 = min(j0, j)
            j1 = max(j1, j + 1)
    for i in range(n):
        for j in range(n):
            out[i, j] = False
        pv = pred[k, 1] + (i - h)
        v = start[k, 1] + (i - h)
        if not (v >= 1.0 and v <= height - 2.0):
            continue
        lo_j = j0
        hi_j = j1
        if has_w:  # the round window's run in this row
            while lo_j < hi_j and w[i * n + lo_j] == 0.0:
                lo_j += 1
            while hi_j > lo_j and w[i * n + hi_j - 1] == 0.0:
                hi_j -= 1
        c0 = h01 * pv
        c1 = h11 * pv
        c2 = h21 * pv
        if reach == 0:  # only the square's own marker: branch-free, vectorised
            for j in range(lo_j, hi_j):
                pu = pus[j]
                z = h20 * pu + c2 + h22
                bx = (h00 * pu + c0 + h02) / z
                by = (h10 * pu + c1 + h12) / z
                fx = np.floor(bx)
                fy = np.floor(by)
                sq = fx + fy
                white = sq - 2.0 * np.floor(0.5 * sq) == par  # (row + col) % 2, NaN: False
                on = (fx + lk <= bx) & (bx <= fx + 1.0 - lk) & (fy + lk <= by)
                on &= by <= fy + 1.0 - lk
                inside = (z != 0) & (bx >= g) & (bx <= right) & (by >= g) & (by <= bottom)
                inside &= (abs(bx) < np.inf) & (abs(by) < np.inf)
                out[i, j] = inside & (not (white & on))
            continue
        for j in range(lo_j, hi_j):  # vectorised: the same products and quotients
            pu = pus[j]
            z = h20 * pu + c2 + h22
            bxs[j] = (h00 * pu + c0 + h02) / z
            bys[j] = (h10 * pu + c1 + h12) / z
            zs[j] = z
        for j in range(lo_j, hi_j):
            if zs[j] == 0:
                continue
            bx = bxs[j]
            by = bys[j]
            if not (np.isfinite(bx) and np.isfinite(by)):
                continue
            if not (bx >= g and bx <= cols - g and by >= g and by <= rows - g):
                continue
            fx = np.floor(bx)
            fy = np.floor(by)
            ixy = int(fx) + int(fy)
            free = True
            for oy in range(-reach, reach + 1):
                for ox in range(-reach, reach + 1):
                    if (ixy + ox + oy) & 1 != parity:  # (row + col) % 2: not a white square
                        continue
                    sc = fx + ox
                    sr = fy + oy
                    if sc + lk <= bx <= sc + 1.0 - lk and sr + lk <= by <= sr + 1.0 - lk:
                        free = False
            out[i, j] = free
    if not pairs:
        return
    for i in range(n):
        for j in range(n):
            if out[i, j] and not out[n - 1 - i, n - 1 - j]:
                out[i, j] = False


#: the window sizes the weight table holds at least (ChArUco's windows are at most 40 px)
_TABLE_H = 40


@functools.lru_cache(maxsize=4)
def _weight_table(hmax: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Every window's weights for ``h = 0 .. hmax``, flat, and where each starts (hmax + 2)."""
    tables = [np.ones(1)] + [symmetric_window_weights(h).ravel() for h in range(1, hmax + 1)]
    offsets = np.zeros(hmax + 2, dtype=np.int64)
    offsets[1:] = np.cumsum([t.size for t in tables])
    return np.concatenate(tables), offsets


def _check_charuco_args(
    start: NDArray[np.float64],
    pred: NDArray[np.float64],
    hinv: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    hs: NDArray[np.int64],
) -> None:
    """Raise ValueError unless the per-corner arrays agree in shape and the windows are >= 1."""
    n = start.shape[0]
    shapes = [(start.shape, (n, 2)), (pred.shape, (n, 2)), (hinv.shape, (n, 3, 3))]
    shapes += [(lo.shape, (n,)), (guard.shape, (n,)), (hs.shape, (n,))]
    for got, want in shapes:
        if got != want:
            raise ValueError(f"expected per-corner arrays of shape {want}, got {got}")
    if int(np.min(hs)) < 1:
        raise ValueError(f"expected windows of at least 1 px, got {int(np.min(hs))}")


def charuco_symmetric_numba(
    image: NDArray[np.float64],
    start: NDArray[np.float64],
    pred: NDArray[np.float64],
    hinv: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    hs: NDArray[np.int64],
    cols: int,
    rows: int,
    parity: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Refine ChArUco corners ``start`` (N, 2) by point symmetry, the markers masked.

    Corner ``k`` gets :func:`refine_symmetric_numba` with the window ``hs[k]`` and the mask
    :func:`marker_mask_numpy` gives for its row of ``hinv``, ``pred``, ``start``, ``lo`` and
    ``guard``: the mask is made inside the kernel, corner by corner, and all the corners are
    refined in one call, whatever their windows. Returns the corners and their status.
    """
    if start.shape[0] == 0:
        return np.array(start, dtype=np.float64), np.zeros(0, dtype=np.int64)
    _check_charuco_args(start, pred, hinv, lo, guard, hs)
    hs = np.ascontiguousarray(hs, dtype=np.int64)
    wtab, woff = _weight_table(max(int(hs.max()), _TABLE_H))
    img = np.ascontiguousarray(image, dtype=np.float64)
    return _charuco_symmetric(
        img,
        np.ascontiguousarray(start, dtype=np.float64),
        np.ascontiguousarray(pred, dtype=np.float64),
        np.ascontiguousarray(hinv, dtype=np.float64),
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(guard, dtype=np.float64),
        hs,
        wtab,
        woff,
        cols,
        rows,
        parity,
        max_iter,
        eps,
    )


def charuco_symmetric_numpy(
    image: NDArray[np.float64],
    start: NDArray[np.float64],
    pred: NDArray[np.float64],
    hinv: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    hs: NDArray[np.int64],
    cols: int,
    rows: int,
    parity: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Plain NumPy twin of :func:`charuco_symmetric_numba`.

    The corners of each window size masked by :func:`marker_mask_numpy` and refined by
    :func:`refine_symmetric_numpy`.
    """
    out = np.array(start, dtype=np.float64, copy=True)
    status = np.zeros(out.shape[0], dtype=np.int64)
    if out.shape[0]:
        _check_charuco_args(start, pred, hinv, lo, guard, hs)
    for h in np.unique(hs):
        sel = np.nonzero(hs == h)[0]
        pts = np.ascontiguousarray(out[sel])
        args = (pred[sel], pts, lo[sel], guard[sel], int(h), cols, rows, parity, image.shape)
        mask = marker_mask_numpy(hinv[sel], *args)
        out[sel], status[sel] = refine_symmetric_numpy(image, pts, int(h), max_iter, eps, mask)
    return out, status


@njit(fastmath=False, error_model="numpy")
def _charuco_symmetric(
    image: NDArray[np.float64],
    start: NDArray[np.float64],
    pred: NDArray[np.float64],
    hinv: NDArray[np.float64],
    lo: NDArray[np.float64],
    guard: NDArray[np.float64],
    hs: NDArray[np.int64],
    wtab: NDArray[np.float64],
    woff: NDArray[np.int64],
    cols: int,
    rows: int,
    parity: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # pragma: no cover - numba-compiled
    """:func:`charuco_symmetric_numba`'s kernel.

    The arithmetic of :func:`marker_mask_numba` (the same mask, its weight-0 offsets not
    computed) and of :func:`_refine_symmetric` (``has_mask``; the patch interpolated along its
    rows first: the same values), but for the sums: the terms of ``d`` and ``-d`` are equal
    (the residual and the Jacobian change sign together), so half the window is summed and
    doubled, in any order (:func:`_pair_sums`). The corners agree with the twin's to rounding
    (1e-13 px on real views).
    """
    n = start.shape[0]
    height, width = image.shape
    out = start.copy()
    status = np.ones(n, dtype=np.int64)
    hmax = 0
    for k in range(n):
        hmax = max(hmax, hs[k])
    nw = 2 * hmax + 1
    mw = nw + 2
    ok = np.zeros((nw, nw), dtype=np.bool_)
    # the kept half of the window's weights (0 elsewhere) and the shading's Jacobian -2 d,
    # laid out as the patch (q + d at (i + 1) m + j + 1), over its rows 1 .. h + 1
    wk = np.zeros(mw * mw)
    dxs = np.zeros(mw * mw)
    dys = np.zeros(mw * mw)
    rowi = np.empty((mw + 1) * mw)
    patch = np.empty(mw * mw)
    mirror = np.empty(mw * mw)
    ys = np.empty(mw + 1, dtype=np.int64)
    xs = np.empty(mw + 1, dtype=np.int64)
    eps2 = eps * eps
    for k in range(n):
        sx = start[k, 0]
        sy = start[k, 1]
        if not (np.isfinite(sx) and np.isfinite(sy)):
            status[k] = 2
            continue
        h = hs[k]
        nn = 2 * h + 1
        m = nn + 2
        w = wtab[woff[h] : woff[h + 1]]
        _marker_mask_one(
            ok, hinv, pred, start, lo, guard, k, h, cols, rows, parity, height, width, w, False
        )
        d11 = 0.0
        d12 = 0.0
        d22 = 0.0
        # the offsets d before 0 in row order (one of each pair d, -d), kept when -d is too
        for t in range(m * (h + 3)):
            wk[t] = 0.0
        for i in range(h + 1):
            for j in range(nn):
                t = (i + 1) * m + j + 1
                dxs[t] = -2.0 * (j - h)
                dys[t] = -2.0 * (i - h)
                if (i == h and j >= h) or not (ok[i, j] and ok[nn - 1 - i, nn - 1 - j]):
                    continue
                wt = w[i * nn + j]
                wk[t] = wt
                d11 += wt * (j - h) * (j - h)
                d12 += wt * (j - h) * (i - h)
                d22 += wt * (i - h) * (i - h)
        d11 *= 2.0
        d12 *= 2.0
        d22 *= 2.0
        dd = d11 * d22 - d12 * d12
        if not (dd > SINGULAR * (d11 + d22) * (d11 + d22)):
            status[k] = 2
            continue
        i00 = d22 / (4.0 * dd)
        i01 = -d12 / (4.0 * dd)
        i10 = -d12 / (4.0 * dd)
        i11 = d11 / (4.0 * dd)
        cx = sx
        cy = sy
        for _ in range(max_iter):
            fx = np.floor(min(max(cx, -h - 2.0), width + h + 1.0))
            fy = np.floor(min(max(cy, -h - 2.0), height + h + 1.0))
            ax = cx - fx
            ay = cy - fy
            x0 = int(fx) - h - 1
            y0 = int(fy) - h - 1
            bx_ = 1.0 - ax
            by_ = 1.0 - ay
            if x0 >= 0 and y0 >= 0 and x0 + m < width and y0 + m < height:
                for i in range(m + 1):
                    src = image[y0 + i, x0 : x0 + m + 1]
                    dst = rowi[i * m : i * m + m]
                    for j in range(m):
                        dst[j] = bx_ * src[j] + ax * src[j + 1]
            else:
                for i in range(m + 1):
                    ys[i] = min(max(y0 + i, 0), height - 1)
                    xs[i] = min(max(x0 + i, 0), width - 1)
                for i in range(m + 1):
                    for j in range(m):
                        rowi[i * m + j] = bx_ * image[ys[i], xs[j]] + ax * image[ys[i], xs[j + 1]]
            for t in range(m * m):
                patch[t] = by_ * rowi[t] + ay * rowi[t + m]
            for t in range((h + 3) * m):  # patch(-d) at d's place, the rows the sums read
                mirror[t] = patch[m * m - 1 - t]
            a11_, a12_, a22_, b11, b12, b21, b22, g1, g2, e1, e2 = _pair_sums(
                patch, mirror, wk, dxs, dys, m + 1, (h + 1) * m + h + 1
            )
            cx, cy, st = symmetric_step(
                a11_, a12_, a22_, b11, b12, b21, b22, g1, g2, e1, e2,
                i00, i01, i10, i11, cx, cy, width, height, eps2,
            )  # fmt: skip
            if st >= 0:
                status[k] = st
                break
        cx, cy, status[k] = put_back(cx, cy, sx, sy, h, status[k])
        out[k, 0] = cx
        out[k, 1] = cy
    return out, status


@njit(fastmath={"reassoc"}, error_model="numpy")
def _pair_sums(
    patch: NDArray[np.float64],
    mirror: NDArray[np.float64],
    wk: NDArray[np.float64],
    dxs: NDArray[np.float64],
    dys: NDArray[np.float64],
    t0: int,
    t1: int,
) -> tuple[
    float, float, float, float, float, float, float, float, float, float, float
]:  # pragma: no cover - numba-compiled
    """Return the normal equations' sums of a step over the window's pairs ``(d, -d)``.

    ``patch`` (``m`` square, flat) is the image resampled at ``q + d``, ``mirror`` the same
    reversed (at ``q - d``); ``wk``, ``dxs``, ``dys`` (laid out as ``patch``) the weights of
    the offsets ``d`` before 0 (0 for the others and for a pair left out) and the shading's
    Jacobian, ``-2 d``; ``t0`` to ``t1`` the patch's positions that hold them. The terms of
    ``d`` and ``-d`` are equal (the residual and the Jacobian change sign together): half the
    window is summed and doubled. Sums in any order (``reassoc``: vectorised over one run);
    the offsets of weight 0 add ``0`` (the image is finite).
    """
    n = t1 - t0
    m = t0 - 1  # the row stride
    pc = patch[t0:t1]
    pl = patch[t0 - 1 : t1 - 1]
    pg = patch[t0 + 1 : t1 + 1]
    pu = patch[t0 - m : t1 - m]
    pd = patch[t0 + m : t1 + m]
    qc = mirror[t0:t1]
    ql = mirror[t0 + 1 : t1 + 1]  # mirror's next is the patch's previous
    qg = mirror[t0 - 1 : t1 - 1]
    qu = mirror[t0 + m : t1 + m]
    qd = mirror[t0 - m : t1 - m]
    wr = wk[t0:t1]
    xr = dxs[t0:t1]
    yr = dys[t0:t1]
    a11 = 0.0
    a12 = 0.0
    a22 = 0.0
    b11 = 0.0
    b12 = 0.0
    b21 = 0.0
    b22 = 0.0
    g1 = 0.0
    g2 = 0.0
    e1 = 0.0
    e2 = 0.0
    for t in range(n):
        wt = wr[t]
        r = pc[t] - qc[t]
        jx = 0.5 * (pg[t] - pl[t]) - 0.5 * (qg[t] - ql[t])
        jy = 0.5 * (pd[t] - pu[t]) - 0.5 * (qd[t] - qu[t])
        dx = xr[t]
        dy = yr[t]
        a11 += wt * jx * jx
        a12 += wt * jx * jy
        a22 += wt * jy * jy
        b11 += wt * jx * dx
        b12 += wt * jx * dy
        b21 += wt * jy * dx
        b22 += wt * jy * dy
        g1 += wt * jx * r
        g2 += wt * jy * r
        e1 += wt * dx * r
        e2 += wt * dy * r
    return (
        2.0 * a11,
        2.0 * a12,
        2.0 * a22,
        2.0 * b11,
        2.0 * b12,
        2.0 * b21,
        2.0 * b22,
        2.0 * g1,
        2.0 * g2,
        2.0 * e1,
        2.0 * e2,
    )
