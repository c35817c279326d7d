"""Numba kernels of semi-global matching (:func:`imageform.geometry.stereo_disparity`).

H. Hirschmüller, "Stereo processing by semiglobal matching and mutual information", IEEE
PAMI 30(2), 2008. The steps, each a kernel here with its NumPy twin in
:mod:`imageform.geometry._sgm_numpy` (the tests hold both to the same integers):

* :func:`census`: the census transform of an image over a ``block_size`` window (R. Zabih,
  J. Woodfill, ECCV 1994): one bit per neighbour, set where the neighbour is darker than the
  centre, neighbours in raster order, the image's border replicated; graded, two bits per
  neighbour (darker, and darker by more than a step).
* :func:`cost_volume`: the Hamming distance of the left pixel's code and the right code at
  ``x - d`` for every disparity ``d`` (``uint8``); a disparity that leaves the right image
  costs the most a code can (its bit count).
* :func:`window_costs`: those costs summed over a ``(2r+1)`` x ``(2r+1)`` block of left pixels
  (the border replicated), divided by ``div`` and rounded (``((t + div // 2) M) >> 20`` with
  ``M = ceil(2^20 / div)``: exact for the sums that occur), still ``uint8``: OpenCV's
  ``blockSize`` sum of its pixel costs, which averages the sensor noise of flat regions out.
* :func:`aggregate`: the sum over 8 paths (horizontal, vertical, both diagonals, both ways)
  of Hirschmüller's recursion (his eq. 13),
  ``L_r(p, d) = C(p, d) + min(L_r(p-r, d), L_r(p-r, d±1) + P1, min_k L_r(p-r, k) + P2)
  - min_k L_r(p-r, k)``, in two raster passes (four paths each, as OpenCV's ``MODE_HH``).
  ``P2`` may be divided by the intensity step along the path (his eq. 12 with
  ``P2 = P2' / |I_p - I_{p-r}|``, never below ``P1``).
* :func:`select`: winner-take-all where every disparity stays inside the right image,
  the uniqueness test, the sub-pixel vertex of the parabola, or of the equiangular V (two lines
  of opposite slopes), through the best cost and its two neighbours,
  the right pixels claimed by the unique winners, and OpenCV's left-right check on them.
* :func:`match`: :func:`select` of :func:`aggregate`, each row selected as soon as the
  second pass completes it (what :func:`~imageform.geometry.stereo_disparity` runs).

Speed (``benchmarks/check_stereo_depth.py``): the paths are ``int16`` vectors padded at both
ends of the disparities (no branch in the inner loops, 16-bit vector lanes), the sums of the
first pass are the only volume written besides the costs, and the second pass never writes
its sums back.
* :func:`median3`: the 3 x 3 median of the disparities that OpenCV's ``StereoSGBM::compute``
  applies to every map (``medianBlur(disp, disp, 3)``), invalid pixels counted below every
  valid one, the border replicated.
* :func:`speckles`: OpenCV's ``filterSpeckles`` (4-connected regions of disparities within
  ``max_diff`` of each other, at most ``max_size`` pixels, made invalid).
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = [
    "aggregate",
    "census",
    "cost_volume",
    "hidden_share",
    "match",
    "median3",
    "photo_spread",
    "plane_sums",
    "plane_weights",
    "plane_write",
    "popcount64",
    "rim_labels",
    "select",
    "speckles",
    "window_costs",
]


@njit
def popcount64(v):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Count the set bits of an unsigned 64-bit integer (SWAR)."""
    v = v - ((v >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (v * np.uint64(0x0101010101010101)) >> np.uint64(56)


@njit
def census(img, r, threshold, step):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Census codes ``uint64 (H, W)`` of ``img`` (float32, H x W) over a ``2r+1`` window.

    A neighbour's bit is set where it is darker than the centre by more than ``threshold``
    (float32, >= 0; 0 is the plain census). With ``step >= 0`` (the graded census) each
    neighbour gives two bits, that one and, after it, one set where the neighbour is darker by
    more than ``threshold + step``: ``2 ((2r+1)² - 1)`` bits, at most 48 (``r <= 2``).
    """
    h, w = img.shape
    pad = np.empty((h + 2 * r, w + 2 * r), dtype=np.float32)  # the border replicated
    for yy in range(h + 2 * r):
        src = img[min(max(yy - r, 0), h - 1)]
        row = pad[yy]
        for xx in range(w + 2 * r):
            row[xx] = src[min(max(xx - r, 0), w - 1)]
    out = np.zeros((h, w), dtype=np.uint64)
    one = np.uint64(1)
    graded = step >= 0
    for y in range(h):
        code = out[y]
        c = img[y] - threshold  # float32: the twin's arithmetic
        c2 = c - step
        for dy in range(-r, r + 1):
            nb = pad[y + r + dy]
            for dx in range(-r, r + 1):
                if dy == 0 and dx == 0:
                    continue
                o = r + dx
                for x in range(w):  # one neighbour for the whole row: vectorised
                    bit = one if nb[x + o] < c[x] else np.uint64(0)
                    code[x] = (code[x] << one) | bit
                if graded:
                    for x in range(w):
                        bit = one if nb[x + o] < c2[x] else np.uint64(0)
                        code[x] = (code[x] << one) | bit
    return out


@njit
def cost_volume(cl, cr, min_d, n_d, nbits, out=None):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Hamming costs ``uint8 (H, W, n_d)`` of left codes against right codes at ``x - d``.

    Written into ``out`` where given: an array NumPy allocated (on Linux it asks for huge
    pages for large arrays, numba's allocator does not: a volume of tens of MB then costs
    several ms of page faults more when allocated here).
    """
    h, w = cl.shape
    if out is None:
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
def _cost_row(cl, cr, y, min_d, n_d, nbits, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Hamming costs ``(W, n_d)`` of row ``y`` into ``out`` (:func:`cost_volume`'s row).

    Indexed as :func:`cost_volume` does, ``out[x, k]`` and ``cr[y, xr]``: through row views
    (``out[x][k]``, ``cr[y][xr]``) the loop ran four times slower.
    """
    w = cl.shape[1]
    for x in range(w):
        a = cl[y, x]
        for k in range(n_d):
            xr = x - (min_d + k)
            if xr < 0 or xr >= w:
                out[x, k] = nbits
            else:
                out[x, k] = popcount64(a ^ cr[y, xr])


@njit
def window_costs(cl, cr, min_d, n_d, nbits, r, div, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Block sums of the Hamming costs, ``uint8 (H, W, n_d)`` written into ``out``.

    ``round(Σ C / div)`` over the ``(2r+1)²`` left pixels about each one (rows and columns
    beyond the image replicated), ``C`` :func:`cost_volume`'s costs, the rounding
    ``((Σ C + div // 2) M) >> 20`` with ``M = ceil(2^20 / div)`` (the quotient rounded half up,
    exactly, for sums below 2^20 / div²). The rows of costs are computed once each, in a ring
    of ``2r + 2`` rows; the column sums slide down (a row in, a row out), and each row's block
    sums add ``2r + 1`` shifted copies of them: every step one loop over the row's ``W n_d``
    values (no loop per pixel: the vector lanes run the whole row). The shifted column sums are
    read through views of ``cs`` indexed by the loop's own counter: indexed as
    ``cs[c0 + i]``, each load checked for a negative index, the loops ran scalar, twice the
    time.
    """
    h, w = cl.shape
    m = 2 * r + 1
    wn = w * n_d
    ring = np.empty((m + 1, w, n_d), dtype=np.uint8)
    have = np.full(m + 1, -1, dtype=np.int64)
    # the column sums of the block's rows, flat (x, k), r columns replicated at both ends
    cs = np.zeros((w + 2 * r) * n_d, dtype=np.uint16)
    t = np.empty(wn, dtype=np.uint16)  # (2r + 1)² nbits + div // 2 <= 49 * 48 + 6 fits
    mul = np.uint32((2**20 + div - 1) // div)
    half = np.uint16(div // 2)
    sh = np.uint32(20)
    c0 = r * n_d  # column 0 in cs
    for y in range(h):
        for dy in range(-r - 1, r + 1):  # the rows of the block, and the one that leaves it
            yy = min(max(y + dy, 0), h - 1)
            if have[yy % (m + 1)] != yy:
                _cost_row(cl, cr, yy, min_d, n_d, nbits, ring[yy % (m + 1)])
                have[yy % (m + 1)] = yy
        cv = cs[c0 : c0 + wn]
        if y == 0:
            for i in range(wn):
                cv[i] = 0
            for dy in range(-r, r + 1):
                src = ring[min(max(dy, 0), h - 1) % (m + 1)].reshape(wn)
                for i in range(wn):
                    cv[i] += np.uint16(src[i])
        else:  # slide the block down a row
            add = ring[min(y + r, h - 1) % (m + 1)].reshape(wn)
            sub = ring[max(y - r - 1, 0) % (m + 1)].reshape(wn)
            for i in range(wn):
                cv[i] = cv[i] + np.uint16(add[i]) - np.uint16(sub[i])
        last = c0 + wn - n_d  # column w - 1
        for x in range(r):
            for k in range(n_d):
                cs[x * n_d + k] = cs[c0 + k]
                cs[c0 + wn + x * n_d + k] = cs[last + k]
        o = out[y].reshape(wn)
        if m == 3:
            c1 = cs[n_d : n_d + wn]
            c2 = cs[2 * n_d : 2 * n_d + wn]
            for i in range(wn):
                v = np.uint32(half + cs[i] + c1[i] + c2[i])
                o[i] = np.uint8((v * mul) >> sh)
        else:
            for i in range(wn):
                t[i] = half
            for dx in range(m):
                cx = cs[dx * n_d : dx * n_d + wn]
                for i in range(wn):
                    t[i] += cx[i]
            for i in range(wn):
                o[i] = np.uint8((np.uint32(t[i]) * mul) >> sh)
    return out


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


#: the value beyond both ends of a path's disparities (int16; ``BIG + P1`` still fits)
_BIG = 16384


@njit
def _shifted(lp, g, out):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """``out[k + 1] = L(k - g)`` of a padded path vector ``lp`` for ``g`` in 1/256 px.

    ``lp`` holds ``L(0 .. D - 1)`` at ``1 .. D`` and ``_BIG`` at both ends; beyond them every
    value is ``_BIG``. A fractional ``g`` interpolates linearly between the two whole shifts,
    ``L(k - i) + ((L(k - i - 1) - L(k - i)) f + 128) >> 8`` with ``i = g >> 8``,
    ``f = g & 255`` (integers: the NumPy twin gives the same numbers).
    """
    n = lp.shape[0] - 2
    i = np.int64(g) >> 8
    f = np.int32(np.int64(g) & 255)
    big = np.int64(_BIG)
    # k - i + 1 and k - i inside the padded vector: no test in the loop (vector lanes)
    k0 = min(max(i, 0), n)
    k1 = max(min(n, n + i + 1), k0)
    if f == 0:
        for k in range(k0, k1):
            out[k + 1] = lp[k - i + 1]
    else:
        for k in range(k0, k1):
            va = np.int32(lp[k - i + 1])
            out[k + 1] = np.int16(va + (((np.int32(lp[k - i]) - va) * f + 128) >> 8))
    for kk in range(n - (k1 - k0)):  # the ends: _BIG beyond the padded vector
        k = kk if kk < k0 else kk - k0 + k1
        a = k - i + 1
        ea = np.int64(lp[a]) if 0 <= a <= n + 1 else big
        eb = np.int64(lp[a - 1]) if 0 <= a - 1 <= n + 1 else big
        out[k + 1] = np.int16(ea + (((eb - ea) * np.int64(f) + 128) >> 8))
    return out


@njit
def _sweeps_plain(cost, grey, p1, p2, adaptive, fused, min_d, keep, lr_check, total, equiangular):  # type: ignore[no-untyped-def]  # pragma: no cover
    """:func:`_sweeps` without a slant: the same numbers, none of its code in the loops.

    The slant's branches (a call of :func:`_shifted` that may replace a path's vector) kept in
    the loops cost the plain paths some 40 % of their time even where never taken; and
    ``_p2`` is called only with ``adaptive`` (its plain value is ``p2``).
    """
    h, w, n = cost.shape
    big_end = np.int16(_BIG)
    q1 = np.int16(p1)
    disp = np.full((h if fused else 0, w), np.nan, dtype=np.float32)
    srow = np.empty((w, n), dtype=np.uint16)
    claim = np.empty(w, dtype=np.int64)
    claim_cost = np.empty(w, dtype=np.int64)
    # rows before and this row of the three paths that come from the row before (j = 0: from
    # x - s, 1: from x, 2: from x + s), columns shifted by one (0 and w + 1: outside)
    prev = np.zeros((3, w + 2, n + 2), dtype=np.int16)
    cur = np.zeros((3, w + 2, n + 2), dtype=np.int16)
    prev_min = np.zeros((3, w + 2), dtype=np.int16)
    cur_min = np.zeros((3, w + 2), dtype=np.int16)
    hor = np.zeros(n + 2, dtype=np.int16)  # the horizontal path (from x - s)
    acc = np.empty(n, dtype=np.int16)
    for sweep in range(2):
        s = 1 if sweep == 0 else -1
        into_row = fused and sweep == 1
        prev[:] = 0
        cur[:] = 0
        prev_min[:] = 0
        cur_min[:] = 0
        prev[:, :, 0] = big_end
        prev[:, :, n + 1] = big_end
        cur[:, :, 0] = big_end
        cur[:, :, n + 1] = big_end
        hor[0] = big_end
        hor[n + 1] = big_end
        for yi in range(h):
            y = yi if s == 1 else h - 1 - yi
            yp = y - s
            for k in range(n):
                hor[k + 1] = 0
            hmin = np.int16(0)
            for xi in range(w):
                x = xi if s == 1 else w - 1 - xi
                c = cost[y, x]
                q = p2 if xi == 0 or not adaptive else _p2(grey, y, x, y, x - s, p1, p2, adaptive)
                big = np.int16(hmin + q)
                m = np.int16(32767)
                src = hor
                for k in range(n):
                    a = np.int16(min(src[k], src[k + 2]) + q1)
                    v = np.int16(np.int16(c[k]) + min(min(src[k + 1], big), a) - hmin)
                    acc[k] = v
                    m = min(m, v)
                for k in range(n):  # (a slice assignment would test for overlap)
                    hor[k + 1] = acc[k]
                hmin = m
                tt = srow[x] if into_row else total[y, x]
                if sweep == 0:
                    for k in range(n):
                        tt[k] = np.uint16(acc[k])
                else:
                    t0 = total[y, x]
                    for k in range(n):
                        tt[k] = np.uint16(t0[k] + np.uint16(acc[k]))
                for j in range(3):
                    xp = x + (j - 1) * s
                    if yi == 0 or xp < 0 or xp >= w or not adaptive:
                        q = p2
                    else:
                        q = _p2(grey, y, x, yp, xp, p1, p2, adaptive)
                    lp = prev[j, xp + 1]
                    lm = prev_min[j, xp + 1]
                    out = cur[j, x + 1]
                    big = np.int16(lm + q)
                    m = np.int16(32767)
                    for k in range(n):
                        a = np.int16(min(lp[k], lp[k + 2]) + q1)
                        v = np.int16(np.int16(c[k]) + min(min(lp[k + 1], big), a) - lm)
                        out[k + 1] = v
                        tt[k] = np.uint16(tt[k] + v)
                        m = min(m, v)
                    cur_min[j, x + 1] = m
            if into_row:
                _select_row(srow, disp[y], min_d, keep, lr_check, claim, claim_cost, equiangular)
            prev, cur = cur, prev
            prev_min, cur_min = cur_min, prev_min
    return total, disp


@njit
def _sweeps(cost, grey, p1, p2, adaptive, fused, min_d, keep, lr_check, total, equiangular, slant):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Run the two raster passes of :func:`aggregate`; with ``fused``, :func:`select` too.

    Returns the sums ``uint16 (H, W, D)`` (in ``total``) and, with ``fused``, the
    disparities ``float32 (H, W)``: the second pass then adds its four paths of a row into a
    row buffer, not into the sums, and selects that row's disparities as soon as it is
    complete (the volume of sums is not written a second time nor read again). ``slant``
    ``int32 (4, H, W)`` (or an empty array): the expected change of the disparity, in 1/256
    px, along the steps ``(dx, dy) = (1, 0), (1, 1), (0, 1), (-1, 1)`` into each pixel (the
    reverse steps its negation); each path then compares ``L_r(p, d)`` with
    ``L_r(p - r, d - g)`` (:func:`_shifted`), a surface's slant costing no ``P1`` steps.
    """
    if slant.shape[0] != 4:
        return _sweeps_plain(
            cost, grey, p1, p2, adaptive, fused, min_d, keep, lr_check, total, equiangular
        )
    h, w, n = cost.shape
    big_end = np.int16(_BIG)
    q1 = np.int16(p1)
    disp = np.full((h if fused else 0, w), np.nan, dtype=np.float32)
    srow = np.empty((w, n), dtype=np.uint16)
    claim = np.empty(w, dtype=np.int64)
    claim_cost = np.empty(w, dtype=np.int64)
    # rows before and this row of the three paths that come from the row before (j = 0: from
    # x - s, 1: from x, 2: from x + s), columns shifted by one (0 and w + 1: outside)
    prev = np.zeros((3, w + 2, n + 2), dtype=np.int16)
    cur = np.zeros((3, w + 2, n + 2), dtype=np.int16)
    prev_min = np.zeros((3, w + 2), dtype=np.int16)
    cur_min = np.zeros((3, w + 2), dtype=np.int16)
    hor = np.zeros(n + 2, dtype=np.int16)  # the horizontal path (from x - s)
    acc = np.empty(n, dtype=np.int16)
    use_slant = slant.shape[0] == 4
    sh = np.empty(n + 2, dtype=np.int16)  # a path vector shifted by the slant
    sh[0] = big_end
    sh[n + 1] = big_end
    for sweep in range(2):
        s = 1 if sweep == 0 else -1
        into_row = fused and sweep == 1
        prev[:] = 0
        cur[:] = 0
        prev_min[:] = 0
        cur_min[:] = 0
        prev[:, :, 0] = big_end
        prev[:, :, n + 1] = big_end
        cur[:, :, 0] = big_end
        cur[:, :, n + 1] = big_end
        hor[0] = big_end
        hor[n + 1] = big_end
        for yi in range(h):
            y = yi if s == 1 else h - 1 - yi
            yp = y - s
            for k in range(n):
                hor[k + 1] = 0
            hmin = np.int16(0)
            for xi in range(w):
                x = xi if s == 1 else w - 1 - xi
                c = cost[y, x]
                q = p2 if xi == 0 else _p2(grey, y, x, y, x - s, p1, p2, adaptive)
                big = np.int16(hmin + q)
                m = np.int16(32767)
                src = hor
                if use_slant and xi > 0:
                    g = slant[0, y, x] * s
                    if g != 0:
                        src = _shifted(hor, g, sh)
                for k in range(n):
                    a = np.int16(min(src[k], src[k + 2]) + q1)
                    v = np.int16(np.int16(c[k]) + min(min(src[k + 1], big), a) - hmin)
                    acc[k] = v
                    m = min(m, v)
                for k in range(n):  # (a slice assignment would test for overlap)
                    hor[k + 1] = acc[k]
                hmin = m
                tt = srow[x] if into_row else total[y, x]
                if sweep == 0:
                    for k in range(n):
                        tt[k] = np.uint16(acc[k])
                else:
                    t0 = total[y, x]
                    for k in range(n):
                        tt[k] = np.uint16(t0[k] + np.uint16(acc[k]))
                for j in range(3):
                    xp = x + (j - 1) * s
                    if yi == 0 or xp < 0 or xp >= w:
                        q = p2
                    else:
                        q = _p2(grey, y, x, yp, xp, p1, p2, adaptive)
                    lp = prev[j, xp + 1]
                    lm = prev_min[j, xp + 1]
                    if use_slant and yi > 0 and 0 <= xp < w:
                        g = slant[j + 1, y, x] * s
                        if g != 0:
                            lp = _shifted(lp, g, sh)
                    out = cur[j, x + 1]
                    big = np.int16(lm + q)
                    m = np.int16(32767)
                    for k in range(n):
                        a = np.int16(min(lp[k], lp[k + 2]) + q1)
                        v = np.int16(np.int16(c[k]) + min(min(lp[k + 1], big), a) - lm)
                        out[k + 1] = v
                        tt[k] = np.uint16(tt[k] + v)
                        m = min(m, v)
                    cur_min[j, x + 1] = m
            if into_row:
                _select_row(srow, disp[y], min_d, keep, lr_check, claim, claim_cost, equiangular)
            prev, cur = cur, prev
            prev_min, cur_min = cur_min, prev_min
    return total, disp


@njit
def aggregate(cost, grey, p1, p2, adaptive, slant=None):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Sum ``uint16 (H, W, D)`` of the 8 paths' costs ``L_r`` (two raster passes).

    ``grey`` (H, W) float32 on a 0-255 scale: the intensities of the adaptive ``P2``.
    Each ``L_r`` is at most ``max C + P2 <= 8048``: the paths are kept as ``int16`` (every
    step's sum and difference fits, the casts are exact and let the compiler use 16-bit
    vector lanes) and their sum fits 16 bits for ``P2 <= 8000``. A path starts as
    ``L_r = C``: the recursion from ``L_r(p - r) = 0``, so the rows before the first and the
    columns beyond the image are held as zeros. Each path's vector of disparities is padded
    with ``_BIG`` at both ends (no test for the neighbours ``d ± 1``).
    """
    total = np.empty(cost.shape, dtype=np.uint16)
    if slant is None:
        none = np.zeros((0, 1, 1), dtype=np.int32)
        return _sweeps(cost, grey, p1, p2, adaptive, False, 0, 1.0, -1.0, total, False, none)[0]
    return _sweeps(cost, grey, p1, p2, adaptive, False, 0, 1.0, -1.0, total, False, slant)[0]


@njit
def match(  # type: ignore[no-untyped-def]  # pragma: no cover
    cost,
    grey,
    p1,
    p2,
    adaptive,
    min_d,
    uniqueness,
    lr_check,
    total=None,
    equiangular=False,
    slant=None,
):
    """``select(aggregate(cost, grey, p1, p2, adaptive, slant), min_d, uniqueness, ...)``.

    The same numbers, with each row selected as the second pass completes it. ``total``: an
    array ``uint16`` of the shape of ``cost`` for the sums of the first pass (its content is
    overwritten), best allocated by NumPy (:func:`cost_volume`'s ``out``).
    """
    if total is None:
        total = np.empty(cost.shape, dtype=np.uint16)
    keep = 1.0 - uniqueness
    if slant is None:
        none = np.zeros((0, 1, 1), dtype=np.int32)
        out = _sweeps(
            cost, grey, p1, p2, adaptive, True, min_d, keep, lr_check, total, equiangular, none
        )
    else:
        out = _sweeps(
            cost, grey, p1, p2, adaptive, True, min_d, keep, lr_check, total, equiangular, slant
        )
    return out[1]


@njit
def _select_row(S, out, min_d, keep, lr_check, claim, claim_cost, equiangular):  # type: ignore[no-untyped-def]  # pragma: no cover
    """:func:`select` on one row: sums ``S`` (W, D) into disparities ``out`` (W,)."""
    w, n = S.shape
    x0 = min(max(min_d + n - 1, 0), w)
    x1 = max(min(w, w + min_d), x0)
    none = np.int64(2**40)
    for x in range(w):
        claim[x] = -none
        claim_cost[x] = none
    for x in range(x1 - 1, x0 - 1, -1):
        row = S[x]
        # the least (sum, k): the least sum and its first k, in one vectorised pass
        key = np.uint32(0xFFFFFFFF)
        for k in range(n):
            key = min(key, np.uint32((np.uint32(row[k]) << np.uint32(12)) | np.uint32(k)))
        b = np.int64(key & np.uint32(0xFFF))
        bc = row[b]
        # the least sum more than 1 away from b: two plain loops (vector lanes; a test of
        # |k - b| in one loop ran scalar, half of the selection's time)
        sec = np.uint16(65535)
        for k in range(b - 1 if b > 1 else 0):
            sec = min(sec, row[k])
        sec_hi = np.uint16(65535)
        for k in range(min(b + 2, n), n):
            sec_hi = min(sec_hi, row[k])
        sec = min(sec, sec_hi)
        if (b > 1 or b + 2 < n) and np.float64(sec) * keep < np.float64(bc):
            continue
        xr = x - min_d - b
        if np.int64(bc) < claim_cost[xr]:
            claim_cost[xr] = bc
            claim[xr] = min_d + b
        d = np.float64(min_d + b)
        if 0 < b < n - 1:
            a0 = np.int64(row[b - 1])
            a2 = np.int64(row[b + 1])
            if equiangular:  # the V of two lines of opposite slopes through the three
                den = max(max(a0, a2) - np.int64(bc), np.int64(1))
            else:  # the parabola
                den = max(a0 + a2 - 2 * np.int64(bc), np.int64(1))
            d += np.float64(a0 - a2) / np.float64(2 * den)
        out[x] = np.float32(d)
    if lr_check >= 0:
        for x in range(x0, x1):
            d = np.float64(out[x])
            if np.isnan(d):
                continue
            fails = 0
            for di in (np.floor(d), np.ceil(d)):
                xr = x - np.int64(di)
                claimed = 0 <= xr < w and claim_cost[xr] < none
                if claimed and abs(np.float64(claim[xr]) - di) > lr_check:
                    fails += 1
            if fails == 2:
                out[x] = np.nan


@njit
def select(total, min_d, uniqueness, lr_check, equiangular=False):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Disparities ``float32 (H, W)`` from the summed costs; NaN where invalid.

    OpenCV's ``StereoSGBM`` rules on the sums ``S``, pixel after pixel from the right end of
    the row to the left: invalid where some disparity of the range takes ``x - d`` out of the
    right image (the left band of ``min_d + n - 1`` columns, the right band of ``-min_d``);
    the winner ``b = argmin S`` (the first on ties) is not unique when another disparity more
    than 1 away costs less than ``S_b / (1 - uniqueness)``. A unique winner claims its right
    pixel ``x_r = x - d`` unless a pixel before it (further right) claimed it at a lower or
    equal sum. Sub-pixel: the vertex of the parabola through ``S_b`` and its neighbours
    ``S_-``, ``S_+``, ``(S_- - S_+) / (2 (S_- + S_+ - 2 S_b))``, or with ``equiangular`` of
    the V of two lines of opposite slopes through them, ``(S_- - S_+) / (2 (max(S_-, S_+) -
    S_b))`` (M. Shimizu, M. Okutomi, ICCV 2001), each denominator at least 1 (none at the
    range's ends). With ``lr_check >= 0``, a pixel is made invalid when both
    ``floor(d)`` and ``ceil(d)`` of its sub-pixel ``d`` land on right pixels claimed by a
    disparity more than ``lr_check`` away from them (a right pixel no one claimed, or one
    outside the image, passes).
    """
    h, w, _n = total.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    claim = np.empty(w, dtype=np.int64)
    claim_cost = np.empty(w, dtype=np.int64)
    for y in range(h):
        _select_row(
            total[y], out[y], min_d, 1.0 - uniqueness, lr_check, claim, claim_cost, equiangular
        )
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


@njit
def median3(disp):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Take the 3 x 3 median ``float32 (H, W)`` of ``disp``, NaN (invalid) below every number.

    OpenCV's ``medianBlur(disp, disp, 3)`` of ``StereoSGBM::compute`` on its 16-bit map, whose
    invalid value ``(min_d - 1) * 16`` lies below every valid one: NaN where the median is
    invalid. The border replicated (``BORDER_REPLICATE``, as ``medianBlur``). The median of the
    nine by the 19 exchanges of A. Paeth's network (Graphics Gems, 1990), branch-free.
    """
    h, w = disp.shape
    low = np.float32(-np.inf)
    pad = np.empty((h + 2, w + 2), dtype=np.float32)
    for yy in range(h + 2):
        src = disp[min(max(yy - 1, 0), h - 1)]
        row = pad[yy]
        for xx in range(w + 2):
            a = src[min(max(xx - 1, 0), w - 1)]
            row[xx] = low if np.isnan(a) else a
    out = np.empty((h, w), dtype=np.float32)
    for y in range(h):
        r0, r1, r2, o = pad[y], pad[y + 1], pad[y + 2], out[y]
        for x in range(w):
            p0, p1, p2 = r0[x], r0[x + 1], r0[x + 2]
            p3, p4, p5 = r1[x], r1[x + 1], r1[x + 2]
            p6, p7, p8 = r2[x], r2[x + 1], r2[x + 2]
            p1, p2 = min(p1, p2), max(p1, p2)
            p4, p5 = min(p4, p5), max(p4, p5)
            p7, p8 = min(p7, p8), max(p7, p8)
            p0, p1 = min(p0, p1), max(p0, p1)
            p3, p4 = min(p3, p4), max(p3, p4)
            p6, p7 = min(p6, p7), max(p6, p7)
            p1, p2 = min(p1, p2), max(p1, p2)
            p4, p5 = min(p4, p5), max(p4, p5)
            p7, p8 = min(p7, p8), max(p7, p8)
            p3 = max(p0, p3)
            p5 = min(p5, p8)
            p4, p7 = min(p4, p7), max(p4, p7)
            p6 = max(p3, p6)
            p4 = max(p1, p4)
            p2 = min(p2, p5)
            p4 = min(p4, p7)
            p4, p2 = min(p4, p2), max(p4, p2)
            p4 = max(p6, p4)
            p4 = min(p4, p2)
            o[x] = np.float32(np.nan) if p4 == low else p4
    return out


@njit
def plane_weights(seg, x, y, z, coef, limit, weight):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write ``weight[i]`` 1 where point ``i`` lies within ``limit`` px of its segment's plane.

    The plane fill's inlier test (:func:`imageform.geometry.stereo_matching._fit_planes`):
    ``|z - (a x + b y + c)| <= limit`` with ``(a, b, c) = coef[seg[i]]``, else 0 (float64).
    """
    for i in range(seg.size):
        s = seg[i]
        r = z[i] - (coef[s, 0] * x[i] + coef[s, 1] * y[i] + coef[s, 2])
        weight[i] = 1.0 if abs(r) <= limit else 0.0


@njit
def plane_sums(seg, x, y, z, weight, sums):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Add each point's weighted moments to its segment's row of ``sums`` (float64, (m, 9)).

    The columns ``x², x y, y², x, y, 1, x z, y z, z``, each times ``weight``, summed in the
    points' order (``np.bincount``'s: the same sums to the last bit).
    """
    for i in range(seg.size):
        s = seg[i]
        w, xi, yi, zi = weight[i], x[i], y[i], z[i]
        sums[s, 0] += w * (xi * xi)
        sums[s, 1] += w * (xi * yi)
        sums[s, 2] += w * (yi * yi)
        sums[s, 3] += w * xi
        sums[s, 4] += w * yi
        sums[s, 5] += w
        sums[s, 6] += w * (xi * zi)
        sums[s, 7] += w * (yi * zi)
        sums[s, 8] += w * zi


@njit
def photo_spread(left, right, ys, xs, d, seg, m):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Per segment ``mean |D - mean D|`` of ``D = L - R(x - d)`` (float64 ``(m,)``).

    ``left`` the left pixels (float64, one per point), ``right`` the right image (float32,
    H x W), interpolated linearly along its row at ``x - d`` clipped to the row, the point
    ``i`` at ``ys[i], xs[i]`` in segment ``seg[i]`` (``_photo_ratio``'s ``E(d)``).
    """
    w = right.shape[1]
    n = seg.size
    cnt = np.zeros(m, dtype=np.int64)
    mu = np.zeros(m)
    diff = np.empty(n)
    for i in range(n):
        xr = min(max(xs[i] - d[i], 0.0), w - 1.0)
        j0 = int(np.floor(xr))
        f = xr - j0
        j1 = min(j0 + 1, w - 1)
        row = right[ys[i]]
        v = left[i] - (row[j0] * (1.0 - f) + row[j1] * f)
        diff[i] = v
        mu[seg[i]] += v
        cnt[seg[i]] += 1
    out = np.zeros(m)
    for s in range(m):
        mu[s] = mu[s] / max(cnt[s], 1)
    for i in range(n):
        out[seg[i]] += abs(diff[i] - mu[seg[i]])
    for s in range(m):
        out[s] = out[s] / max(cnt[s], 1)
    return out


@njit
def hidden_share(disp, lab, take, coef, limit):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Per segment the share of its pixels whose plane would hide a matched textured pixel.

    ``_hidden_share``: the valid pixels outside the segments (``lab == 0``) claim the right
    pixels ``floor(x - d)`` and ``ceil(x - d)`` with their lowest disparity; a pixel of a
    segment ``k`` with ``take[k]`` whose plane ``p = coef[k] . (x, y, 1)`` lands (rounded half
    to even) on a right pixel claimed by a disparity below ``p - limit`` hides it.
    """
    h, w = disp.shape
    m = take.size
    low = np.full(h * w, np.inf)
    for y in range(h):
        for x in range(w):
            if lab[y, x] == 0:
                v = disp[y, x]
                if np.isfinite(v):
                    d = np.float64(v)
                    a = np.floor(x - d)
                    if a >= 0 and a < w:
                        at = y * w + int(a)
                        low[at] = min(low[at], d)
                    b = np.ceil(x - d)
                    if b >= 0 and b < w:
                        at = y * w + int(b)
                        low[at] = min(low[at], d)
    hides = np.zeros(m)
    cnt = np.zeros(m, dtype=np.int64)
    for y in range(h):
        for x in range(w):
            k = lab[y, x]
            if k > 0 and take[k]:
                p = coef[k, 0] * x + coef[k, 1] * y + coef[k, 2]
                xr = np.rint(x - p)
                cnt[k] += 1
                if xr >= 0 and xr < w and p > low[y * w + int(xr)] + limit:
                    hides[k] += 1.0
    out = np.empty(m)
    for k in range(m):
        out[k] = hides[k] / max(cnt[k], 1)
    return out


@njit
def rim_labels(lab, r2):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Each pixel's nearest segment within ``sqrt(r2)`` px: ``int64 (H, W)``, 0 where none.

    ``_rim_labels``'s numbers without SciPy's feature transform over the whole image: for the
    pixels outside the segments (``lab == 0``), the label of the nearest pixel with
    ``lab > 0`` whose squared distance is at most ``r2``, ties between equally near pixels
    going, as SciPy's ``distance_transform_edt(return_indices=True)`` gives them, to the
    least column and then the least row. Each segment pixel with a 4-neighbour outside the
    segments (the only ones nearest to an outside pixel) scatters ``(d², x, y)`` into the
    pixels of its disc, the least of them kept.
    """
    h, w = lab.shape
    q = 0
    while (q + 1) * (q + 1) <= r2:
        q += 1
    bd = np.full((h, w), r2 + 1, dtype=np.int64)
    bx = np.zeros((h, w), dtype=np.int64)
    by = np.zeros((h, w), dtype=np.int64)
    for y in range(h):
        for x in range(w):
            if lab[y, x] == 0:
                continue
            edge = (
                (y > 0 and lab[y - 1, x] == 0)
                or (y < h - 1 and lab[y + 1, x] == 0)
                or (x > 0 and lab[y, x - 1] == 0)
                or (x < w - 1 and lab[y, x + 1] == 0)
            )
            if not edge:
                continue
            for ty in range(max(y - q, 0), min(y + q + 1, h)):
                dy2 = (ty - y) * (ty - y)
                for tx in range(max(x - q, 0), min(x + q + 1, w)):
                    d2 = dy2 + (tx - x) * (tx - x)
                    if d2 > r2 or lab[ty, tx] != 0:
                        continue
                    b, c = bd[ty, tx], bx[ty, tx]
                    if d2 < b or (d2 == b and (x < c or (x == c and y < by[ty, tx]))):
                        bd[ty, tx] = d2
                        bx[ty, tx] = x
                        by[ty, tx] = y
    out = np.zeros((h, w), dtype=np.int64)
    for y in range(h):
        for x in range(w):
            if bd[y, x] <= r2:
                out[y, x] = lab[by[y, x], bx[y, x]]
    return out


@njit
def plane_write(disp, lab, take, coef, x0, x1):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Return ``disp`` with the taken segments' pixels in columns ``x0 .. x1 - 1`` on their planes.

    ``_plane_fill``'s last step in one pass: ``float32(a x + b y + c)`` (``coef[k]``, summed in
    float64 in that order; a copy) where ``lab[y, x] = k > 0`` and ``take[k]``.
    """
    out = disp.copy()
    for y in range(disp.shape[0]):
        for x in range(x0, x1):
            k = lab[y, x]
            if k > 0 and take[k]:
                out[y, x] = np.float32(coef[k, 0] * x + coef[k, 1] * y + coef[k, 2])
    return out
