"""NumPy twins of the semi-global matching kernels (:mod:`imageform._kernels.sgm`).

The same integers as the kernels, step for step (``tests/geometry/test_stereo_matching.py``
holds them equal): each twin loops over one image axis in Python and computes a whole row
or column of pixels and disparities at once. They run where numba does not
(``IMAGEFORM_DISABLE_NUMBA=1``), some 10 to 50 times slower.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "aggregate",
    "census",
    "cost_volume",
    "match",
    "median3",
    "select",
    "speckles",
    "window_costs",
]

#: bits set in each byte value
_POP8 = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)


def _popcount(v: NDArray[np.uint64]) -> NDArray[np.uint8]:
    b = np.ascontiguousarray(v).view(np.uint8).reshape(*v.shape, 8)
    return _POP8[b].sum(axis=-1, dtype=np.uint8)


def census(
    img: NDArray[np.float32], r: int, threshold: np.float32, step: np.float32
) -> NDArray[np.uint64]:
    """Census codes of ``img``, ``2r+1`` window (the kernel's bit order, border replicated).

    A bit is set where the neighbour is darker than the centre by more than ``threshold``;
    with ``step >= 0`` a second bit after it where darker by more than ``threshold + step``.
    """
    h, w = img.shape
    pad = np.pad(img, r, mode="edge")
    code = np.zeros((h, w), dtype=np.uint64)
    one = np.uint64(1)
    centre = img - np.float32(threshold)  # float32, as the kernel
    centre2 = centre - np.float32(step)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dy == 0 and dx == 0:
                continue
            nb = pad[r + dy : r + dy + h, r + dx : r + dx + w]
            code = (code << one) | (nb < centre).astype(np.uint64)
            if step >= 0:
                code = (code << one) | (nb < centre2).astype(np.uint64)
    return code


def cost_volume(
    cl: NDArray[np.uint64],
    cr: NDArray[np.uint64],
    min_d: int,
    n_d: int,
    nbits: int,
    out: NDArray[np.uint8] | None = None,
) -> NDArray[np.uint8]:
    """Hamming costs ``(H, W, n_d)``; ``nbits`` where ``x - d`` leaves the right image."""
    h, w = cl.shape
    if out is None:
        out = np.empty((h, w, n_d), dtype=np.uint8)
    out[...] = nbits
    for k in range(n_d):
        d = min_d + k
        x0, x1 = max(0, d), min(w, w + d)  # x with 0 <= x - d < w
        if x0 < x1:
            out[:, x0:x1, k] = _popcount(cl[:, x0:x1] ^ cr[:, x0 - d : x1 - d])
    return out


def window_costs(
    cl: NDArray[np.uint64],
    cr: NDArray[np.uint64],
    min_d: int,
    n_d: int,
    nbits: int,
    r: int,
    div: int,
    out: NDArray[np.uint8] | None = None,
) -> NDArray[np.uint8]:
    """Block sums of the Hamming costs over ``(2r+1)²`` pixels, divided by ``div``, rounded."""
    c = cost_volume(cl, cr, min_d, n_d, nbits).astype(np.uint32)
    h, w = cl.shape
    p = np.pad(c, ((r, r), (r, r), (0, 0)), mode="edge")
    cs = np.zeros((h, w + 2 * r, n_d), dtype=np.uint32)
    for dy in range(2 * r + 1):
        cs += p[dy : dy + h]
    t = np.full((h, w, n_d), div // 2, dtype=np.uint32)
    for dx in range(2 * r + 1):
        t += cs[:, dx : dx + w]
    mul = np.uint32((2**20 + div - 1) // div)
    q = ((t * mul) >> np.uint32(20)).astype(np.uint8)
    if out is None:
        return q
    out[...] = q
    return out


def _step(
    c: NDArray[np.int32], lp: NDArray[np.int32], p1: int, p2: NDArray[np.int32]
) -> NDArray[np.int32]:
    """``L_r(p)`` for a line of pixels: costs ``c`` (N, D), ``lp = L_r(p - r)``, ``P2`` (N,)."""
    lpmin = lp.min(axis=1, keepdims=True)
    v = lp.copy()
    v[:, 1:] = np.minimum(v[:, 1:], lp[:, :-1] + p1)
    v[:, :-1] = np.minimum(v[:, :-1], lp[:, 1:] + p1)
    v = np.minimum(v, lpmin + p2[:, None])
    return np.asarray(c + v - lpmin, dtype=np.int32)


#: the value beyond both ends of a path's disparities (the kernel's ``_BIG``)
_BIG = 16384


def _shifted(lp: NDArray[np.int32], g: NDArray[np.int64]) -> NDArray[np.int32]:
    """``L(k - g)`` of each line's path vector ``lp`` (N, D) for ``g`` (N,) in 1/256 px.

    The kernel's ``_shifted``: ``_BIG`` beyond the ends, a fractional ``g`` interpolated
    linearly in integers, ``L(k - i) + ((L(k - i - 1) - L(k - i)) f + 128) >> 8``.
    """
    n = lp.shape[1]
    pad = np.full((lp.shape[0], n + 2), _BIG, dtype=np.int64)
    pad[:, 1:-1] = lp
    i = (g >> 8)[:, None]
    f = (g & 255)[:, None]
    k = np.arange(n)[None, :]

    def at(a: NDArray[np.int64]) -> NDArray[np.int64]:
        inside = (a >= 0) & (a <= n + 1)
        return np.where(inside, np.take_along_axis(pad, np.clip(a, 0, n + 1), axis=1), _BIG)

    va = at(k - i + 1)
    vb = at(k - i)
    out = np.where(f == 0, va, va + (((vb - va) * f + 128) >> 8))
    return np.asarray(out, dtype=np.int32)


def _step_slant(
    c: NDArray[np.int32],
    lp: NDArray[np.int32],
    p1: int,
    p2: NDArray[np.int32],
    g: NDArray[np.int64] | None,
) -> NDArray[np.int32]:
    """:func:`_step` with the previous vectors shifted by the slant ``g`` (1/256 px)."""
    if g is None or not g.any():
        return _step(c, lp, p1, p2)
    lpmin = lp.min(axis=1, keepdims=True)
    sh = np.where((g != 0)[:, None], _shifted(lp, g), lp)
    big = np.full((sh.shape[0], 1), _BIG, dtype=np.int64)
    padded = np.concatenate([big, sh, big], axis=1)
    v = np.minimum(sh, np.minimum(padded[:, :-2], padded[:, 2:]) + p1)
    v = np.minimum(v, lpmin + p2[:, None])
    return np.asarray(c + v - lpmin, dtype=np.int32)


def _p2(a: NDArray[np.float32], b: NDArray[np.float32], p1: int, p2: int, adaptive: bool) -> Any:
    n = a.shape[0]
    if not adaptive:
        return np.full(n, p2, dtype=np.int32)
    diff = np.maximum(np.abs(a.astype(np.float64) - b.astype(np.float64)), 1.0)
    return np.maximum(p1, (np.float64(p2) / diff).astype(np.int32))


def aggregate(
    cost: NDArray[np.uint8],
    grey: NDArray[np.float32],
    p1: int,
    p2: int,
    adaptive: bool,
    slant: NDArray[np.int32] | None = None,
) -> NDArray[np.uint16]:
    """Sum of the 8 paths' ``L_r`` (the kernel's), as ``uint16 (H, W, D)``."""
    h, w, _n = cost.shape
    c32 = cost.astype(np.int32)
    total = np.zeros(cost.shape, dtype=np.int32)
    sl = None if slant is None or slant.shape[0] != 4 else slant.astype(np.int64)
    for s in (1, -1):
        # horizontal: from x - s, column after column
        xs = range(w) if s == 1 else range(w - 1, -1, -1)
        lp = None
        for x in xs:
            if lp is None:
                L = c32[:, x]
            else:
                g = None if sl is None else sl[0, :, x] * s
                q = _p2(grey[:, x], grey[:, x - s], p1, p2, adaptive)
                L = _step_slant(c32[:, x], lp, p1, q, g)
            total[:, x] += L
            lp = L
        # from the row before: x - s, x, x + s
        ys = range(h) if s == 1 else range(h - 1, -1, -1)
        cols = np.arange(w)
        for j in range(3):
            xp = cols + (j - 1) * s
            inside = (xp >= 0) & (xp < w)
            xq = np.clip(xp, 0, w - 1)
            lp = None
            for y in ys:
                if lp is None:
                    L = c32[y]
                else:
                    q = _p2(grey[y], grey[y - s, xq], p1, p2, adaptive)
                    g = None if sl is None else np.where(inside, sl[j + 1, y] * s, 0)
                    L = np.where(inside[:, None], _step_slant(c32[y], lp[xq], p1, q, g), c32[y])
                total[y] += L
                lp = L
    return total.astype(np.uint16)


def select(
    total: NDArray[np.uint16],
    min_d: int,
    uniqueness: float,
    lr_check: float,
    equiangular: bool = False,
) -> NDArray[np.float32]:
    """Disparities from the summed costs (the kernel's rules; NaN where invalid)."""
    h, w, n = total.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    x0 = min(max(min_d + n - 1, 0), w)
    x1 = max(min(w, w + min_d), x0)
    if x1 == x0:
        return out
    S = total[:, x0:x1].astype(np.int64)  # the columns whose whole range stays inside
    b = np.argmin(S, axis=2)  # the first on ties, as the kernel
    bc = np.take_along_axis(S, b[..., None], axis=2)[..., 0]
    k = np.arange(n)
    far = np.abs(k - b[..., None]) > 1
    sec = np.where(far, S, 65535).min(axis=2)
    has_far = (b > 1) | (b + 2 < n)
    unique = ~(has_far & (sec.astype(np.float64) * (1.0 - uniqueness) < bc.astype(np.float64)))
    d = (min_d + b).astype(np.float64)
    mid = (b > 0) & (b < n - 1)
    bm = np.clip(b, 1, max(n - 2, 1))
    a0 = np.take_along_axis(S, np.minimum(bm - 1, n - 1)[..., None], axis=2)[..., 0]
    a2 = np.take_along_axis(S, np.minimum(bm + 1, n - 1)[..., None], axis=2)[..., 0]
    # the equiangular V's denominator, or the parabola's
    den = np.maximum(np.maximum(a0, a2) - bc if equiangular else a0 + a2 - 2 * bc, 1)
    d = np.where(mid, d + (a0 - a2).astype(np.float64) / (2 * den).astype(np.float64), d)
    out[:, x0:x1] = np.where(unique, d.astype(np.float32), np.float32(np.nan))
    if lr_check < 0:
        return out
    # the claims of the unique winners on their right pixels, from the row's right end: a
    # lower cost takes a pixel over, an equal one does not
    none = np.int64(2**40)
    claim = np.full((h, w), -none, dtype=np.int64)
    claim_cost = np.full((h, w), none, dtype=np.int64)
    rows = np.arange(h)
    for x in range(x1 - 1, x0 - 1, -1):
        i = x - x0
        u = unique[:, i]
        r = rows[u]
        xr = x - min_d - b[u, i]
        c = bc[u, i]
        take = c < claim_cost[r, xr]
        claim_cost[r[take], xr[take]] = c[take]
        claim[r[take], xr[take]] = min_d + b[u, i][take]
    dd = out.astype(np.float64)
    valid = np.isfinite(dd)
    dd0 = np.where(valid, dd, 0.0)
    X = np.arange(w)[None, :]
    fails = np.zeros((h, w), dtype=np.int64)
    for di in (np.floor(dd0), np.ceil(dd0)):
        xr = X - di.astype(np.int64)
        inside = (xr >= 0) & (xr < w)
        xc = np.clip(xr, 0, w - 1)
        cc = np.take_along_axis(claim_cost, xc, axis=1)
        cd = np.take_along_axis(claim, xc, axis=1).astype(np.float64)
        fails += valid & inside & (cc < none) & (np.abs(cd - di) > lr_check)
    out[fails == 2] = np.nan
    return out


def match(
    cost: NDArray[np.uint8],
    grey: NDArray[np.float32],
    p1: int,
    p2: int,
    adaptive: bool,
    min_d: int,
    uniqueness: float,
    lr_check: float,
    total: NDArray[np.uint16] | None = None,
    equiangular: bool = False,
    slant: NDArray[np.int32] | None = None,
) -> NDArray[np.float32]:
    """:func:`select` of :func:`aggregate` (the kernel fuses the two; ``total`` unused)."""
    S = aggregate(cost, grey, p1, p2, adaptive, slant)
    return select(S, min_d, uniqueness, lr_check, equiangular)


def median3(disp: NDArray[np.float32]) -> NDArray[np.float32]:
    """Take the 3 x 3 median of ``disp``, NaN below every number, the border replicated."""
    h, w = disp.shape
    a = np.pad(np.where(np.isnan(disp), np.float32(-np.inf), disp), 1, mode="edge")
    nine = np.stack([a[dy : dy + h, dx : dx + w] for dy in range(3) for dx in range(3)])
    m = np.sort(nine, axis=0)[4]
    return np.where(np.isneginf(m), np.float32(np.nan), m).astype(np.float32)


def speckles(disp: NDArray[np.float32], max_size: int, max_diff: float) -> int:
    """Set to NaN (in place) the regions of at most ``max_size`` pixels; return the count."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    h, w = disp.shape
    v = disp.astype(np.float64)
    idx = np.arange(h * w).reshape(h, w)
    rows, cols = [], []
    for a, b, va, vb in (
        (idx[:, :-1], idx[:, 1:], v[:, :-1], v[:, 1:]),
        (idx[:-1], idx[1:], v[:-1], v[1:]),
    ):
        e = np.isfinite(va) & np.isfinite(vb) & (np.abs(va - vb) <= max_diff)
        rows.append(a[e])
        cols.append(b[e])
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(h * w, h * w))
    _n, labels = connected_components(graph, directed=False)
    size = np.bincount(labels)
    small = (size[labels] <= max_size) & np.isfinite(v).ravel()
    disp.reshape(-1)[small] = np.nan
    return int(small.sum())
