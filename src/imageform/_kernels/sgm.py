"""Numba kernels of semi-global matching (:func:`imageform.geometry.stereo_disparity`).

H. Hirschmüller, "Stereo processing by semiglobal matching and mutual information", IEEE
PAMI 30(2), 2008. The steps, each a kernel here with its NumPy twin in
:mod:`imageform.geometry._sgm_numpy` (the tests hold both to the same integers):

* :func:`census`: the census transform of an image over a ``block_size`` window (R. Zabih,
  J. Woodfill, ECCV 1994): one bit per neighbour, set where the neighbour is darker than the
  centre, neighbours in raster order, the image's border replicated.
* :func:`cost_volume`: the Hamming distance of the left pixel's code and the right code at
  ``x - d`` for every disparity ``d`` (``uint8``); a disparity that leaves the right image
  costs the most a code can (its bit count).
* :func:`aggregate`: the sum over 8 paths (horizontal, vertical, both diagonals, both ways)
  of Hirschmüller's recursion (his eq. 13),
  ``L_r(p, d) = C(p, d) + min(L_r(p-r, d), L_r(p-r, d±1) + P1, min_k L_r(p-r, k) + P2)
  - min_k L_r(p-r, k)``, in two raster passes (four paths each, as OpenCV's ``MODE_HH``).
  ``P2`` may be divided by the intensity step along the path (his eq. 12 with
  ``P2 = P2' / |I_p - I_{p-r}|``, never below ``P1``).
* :func:`select`: winner-take-all where every disparity stays inside the right image,
  the uniqueness test, the parabola through the best cost and its two neighbours (sub-pixel),
  the right image's disparities from the same costs, and the left-right check.
* :func:`speckles`: OpenCV's ``filterSpeckles`` (4-connected regions of disparities within
  ``max_diff`` of each other, at most ``max_size`` pixels, made invalid).
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["aggregate", "census", "cost_volume", "popcount64", "select", "speckles"]


@njit
def popcount64(v):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Count the set bits of an unsigned 64-bit integer (SWAR)."""
    v = v - ((v >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (v * np.uint64(0x0101010101010101)) >> np.uint64(56)


@njit
def census(img, r):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Census codes ``uint64 (H, W)`` of ``img`` (float32, H x W) over a ``2r+1`` window."""
    h, w = img.shape
    out = np.zeros((h, w), dtype=np.uint64)
    for y in range(h):
        for x in range(w):
            c = img[y, x]
            code = np.uint64(0)
            for dy in range(-r, r + 1):
                yy = min(max(y + dy, 0), h - 1)
                for dx in range(-r, r + 1):
                    if dy == 0 and dx == 0:
                        continue
                    xx = min(max(x + dx, 0), w - 1)
                    code = code << np.uint64(1)
                    if img[yy, xx] < c:
                        code = code | np.uint64(1)
            out[y, x] = code
    return out


@njit
def cost_volume(cl, cr, min_d, n_d, nbits):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Hamming costs ``uint8 (H, W, n_d)`` of left codes against right codes at ``x - d``."""
    h, w = cl.shape
    out = np.empty((h, w, n_d), dtype=np.uint8)
    for y in range(h):
        for x in range(w):
            a = cl[y, x]
            for k in range(n_d):
                xr = x - (min_d + k)
                if xr < 0 or xr >= w:
                    out[y, x, k] = nbits
                else:
                    out[y, x, k] = popcount64(a ^ cr[y, xr])
    return out


@njit
def _path(c, lp, lpmin, p1, p2, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """One step of the recursion: ``out = L_r(p)`` from costs ``c`` and ``lp = L_r(p - r)``.

    Returns ``min_k out[k]``.
    """
    n = c.shape[0]
    big = lpmin + p2
    best = np.int32(2**30)
    for k in range(n):
        v = lp[k]
        if k > 0 and lp[k - 1] + p1 < v:
            v = lp[k - 1] + p1
        if k < n - 1 and lp[k + 1] + p1 < v:
            v = lp[k + 1] + p1
        if big < v:
            v = big
        v = np.int32(c[k]) + v - lpmin
        out[k] = v
        if v < best:
            best = v
    return best


@njit
def _start(c, out):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Start a path: ``L_r(p) = C(p)``; return its minimum."""
    best = np.int32(2**30)
    for k in range(c.shape[0]):
        v = np.int32(c[k])
        out[k] = v
        if v < best:
            best = v
    return best


@njit
def _p2(grey, y0, x0, y1, x1, p1, p2, adaptive):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``P2``, or with ``adaptive`` ``max(P1, int(P2 / max(|I_0 - I_1|, 1)))``."""
    if not adaptive:
        return p2
    diff = abs(np.float64(grey[y0, x0]) - np.float64(grey[y1, x1]))
    if diff < 1.0:
        diff = np.float64(1.0)
    q = np.int32(np.float64(p2) / diff)
    return max(p1, q)


@njit
def aggregate(cost, grey, p1, p2, adaptive):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Sum ``uint16 (H, W, D)`` of the 8 paths' costs ``L_r`` (two raster passes).

    ``grey`` (H, W) float32 on a 0-255 scale: the intensities of the adaptive ``P2``.
    Each ``L_r`` is at most ``max C + P2``: the sum fits 16 bits for ``P2 <= 8000``.
    """
    h, w, n = cost.shape
    total = np.zeros((h, w, n), dtype=np.uint16)
    p1 = np.int32(p1)
    p2 = np.int32(p2)
    for sweep in range(2):
        s = 1 if sweep == 0 else -1
        # previous and current rows of L for the three paths that come from the row before
        # (from x - s, x and x + s); the horizontal path from x - s in this row
        prev = np.zeros((3, w, n), dtype=np.int32)
        cur = np.zeros((3, w, n), dtype=np.int32)
        prev_min = np.zeros((3, w), dtype=np.int32)
        cur_min = np.zeros((3, w), dtype=np.int32)
        hor = np.zeros(n, dtype=np.int32)
        hor_new = np.zeros(n, dtype=np.int32)
        hor_min = np.int32(0)
        for yi in range(h):
            y = yi if s == 1 else h - 1 - yi
            yp = y - s
            for xi in range(w):
                x = xi if s == 1 else w - 1 - xi
                c = cost[y, x]
                if xi == 0:
                    m = _start(c, hor_new)
                else:
                    q = _p2(grey, y, x, y, x - s, p1, p2, adaptive)
                    m = _path(c, hor, hor_min, p1, q, hor_new)
                hor_min = m
                for k in range(n):
                    hor[k] = hor_new[k]
                    total[y, x, k] += np.uint16(hor_new[k])
                for j in range(3):
                    xp = x + (j - 1) * s  # j = 0: from x - s; 1: from x; 2: from x + s
                    if yi == 0 or xp < 0 or xp >= w:
                        m = _start(c, cur[j, x])
                    else:
                        q = _p2(grey, y, x, yp, xp, p1, p2, adaptive)
                        m = _path(c, prev[j, xp], prev_min[j, xp], p1, q, cur[j, x])
                    cur_min[j, x] = m
                    for k in range(n):
                        total[y, x, k] += np.uint16(cur[j, x, k])
            prev, cur = cur, prev
            prev_min, cur_min = cur_min, prev_min
    return total


@njit
def select(total, min_d, uniqueness, lr_check):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Disparities ``float32 (H, W)`` from the summed costs; NaN where invalid.

    Winner-take-all over the disparities; invalid where some disparity of the range takes
    ``x - d`` out of the right image (OpenCV's rule: the left band of ``min_d + n - 1``
    columns), when another disparity more than 1 away costs less than
    ``best / (1 - uniqueness)`` (OpenCV's ``uniquenessRatio``), or, with ``lr_check >= 0``,
    when the right image's winner at ``x - d`` (the least ``total[y, x_r + d', d']`` over
    the ``d'`` whose left pixel ``x_r + d'`` is outside that band) differs from ``d`` by more
    than ``lr_check``. Sub-pixel: the vertex of the parabola through the best cost and its
    neighbours (none at the range's ends).
    """
    h, w, n = total.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    best_k = np.empty(w, dtype=np.int64)
    right_k = np.empty(w, dtype=np.int64)
    right_cost = np.empty(w, dtype=np.int64)
    keep = 1.0 - uniqueness
    for y in range(h):
        for x in range(w):
            right_k[x] = -1
            right_cost[x] = 2**62
        for x in range(w):
            lo = max(0, x - w + 1 - min_d)
            hi = min(n - 1, x - min_d)
            best_k[x] = -1
            if lo != 0 or hi != n - 1:  # part of the range leaves the right image
                continue
            row = total[y, x]
            b = lo
            bc = np.int64(row[lo])
            for k in range(lo, hi + 1):
                v = np.int64(row[k])
                if v < bc:
                    bc = v
                    b = k
                xr = x - (min_d + k)
                if v < right_cost[xr]:
                    right_cost[xr] = v
                    right_k[xr] = k
            unique = True
            for k in range(lo, hi + 1):
                if abs(k - b) > 1 and np.float64(row[k]) * keep < np.float64(bc):
                    unique = False
                    break
            if not unique:
                continue
            best_k[x] = b
            d = np.float64(min_d + b)
            if lo < b < hi:
                a0 = np.int64(row[b - 1])
                a2 = np.int64(row[b + 1])
                den = a0 + a2 - 2 * bc
                if den < 1:
                    den = np.int64(1)
                d += np.float64(a0 - a2) / np.float64(2 * den)
            out[y, x] = np.float32(d)
        if lr_check >= 0:
            for x in range(w):
                b = best_k[x]
                if b < 0:
                    continue
                xr = x - (min_d + b)
                if abs(right_k[xr] - b) > lr_check:
                    out[y, x] = np.nan
    return out


@njit
def speckles(disp, max_size, max_diff):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Set to NaN (in place) the 4-connected regions of at most ``max_size`` pixels.

    Neighbours belong to one region when both are valid and differ by at most ``max_diff``.
    Returns how many pixels were removed.
    """
    h, w = disp.shape
    label = np.full((h, w), -1, dtype=np.int64)
    stack = np.empty(h * w, dtype=np.int64)
    members = np.empty(h * w, dtype=np.int64)
    removed = 0
    n = 0
    for y0 in range(h):
        for x0 in range(w):
            if label[y0, x0] >= 0 or np.isnan(disp[y0, x0]):
                continue
            label[y0, x0] = n
            top = 0
            stack[0] = y0 * w + x0
            top = 1
            count = 0
            while top > 0:
                top -= 1
                p = stack[top]
                members[count] = p
                count += 1
                y = p // w
                x = p - y * w
                v = disp[y, x]
                for j in range(4):
                    yy, xx = y, x
                    if j == 0:
                        yy = y - 1
                    elif j == 1:
                        yy = y + 1
                    elif j == 2:
                        xx = x - 1
                    else:
                        xx = x + 1
                    if yy < 0 or yy >= h or xx < 0 or xx >= w or label[yy, xx] >= 0:
                        continue
                    u = disp[yy, xx]
                    if np.isnan(u) or abs(np.float64(u) - np.float64(v)) > max_diff:
                        continue
                    label[yy, xx] = n
                    stack[top] = yy * w + xx
                    top += 1
            if count <= max_size:
                for i in range(count):
                    p = members[i]
                    disp[p // w, p - (p // w) * w] = np.nan
                removed += count
            n += 1
    return removed
