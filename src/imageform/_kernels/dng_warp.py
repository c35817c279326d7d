"""Numba kernel of the DNG WarpRectilinear opcode (:func:`imageform.io._dng_opcodes.apply_stage3`).

:func:`warp_rows` is :func:`imageform.io._dng_opcodes.warp_source_positions` followed by
:func:`imageform.io._dng_opcodes.bicubic_sample`, row by row (the NumPy functions are the
reference the tests hold it to): the source positions of a row (:func:`_row_sources`, for both
paths), then its taps. The source position is the Adobe DNG SDK's
``dng_filter_warp``, clamped to the image, Keys' bicubic kernel (a = -0.75) at the fraction
floored to 1/32 pixel (its 32 weights worked out once), 4 x 4 taps with the edge pixels
repeated, the result clamped to [0, 1]. One set of coefficients and three planes (a phone's
warp): :func:`_warp_rows3`, the same sums in the same order (bit for bit the plane-by-plane
loop's values), 0.57 s -> 0.19 s on one core for 12 Mpx (``benchmarks/check_phone_dng.py``).
Run on numba's threads by :func:`imageform._kernels.jit.run_tasks`, a row per task.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["warp_rows"]


@njit(nogil=True)
def _keys(t):  # type: ignore[no-untyped-def]
    t = abs(t)
    if t < 1.0:
        return (1.25 * t - 2.25) * t * t + 1.0
    if t < 2.0:
        return ((-0.75 * t + 3.75) * t - 6.0) * t + 3.0
    return 0.0


@njit(nogil=True)
def _weight_table():  # type: ignore[no-untyped-def]
    """Return the normalised weights (32, 4) of the 32 fractions (rows and columns alike)."""
    table = np.empty((32, 4))
    for k in range(32):
        fk = k / 32.0
        total_k = 0.0
        for t in range(4):
            table[k, t] = _keys(t - 1 - fk)
            total_k += table[k, t]
        for t in range(4):
            table[k, t] /= total_k
    return table


@njit(nogil=True)
def _row_sources(i, k, xs, geometry, h, w, tops, lefts, krs, kcs):  # type: ignore[no-untyped-def]
    """Fill the first tap's row and column and the fractions' indices (32nds) of row ``i``.

    ``xs``: every column's ``x`` (worked out once); ``k``: one plane's six coefficients. A
    loop without branches, which the compiler vectorises (it was half of the warp's time).
    """
    dt, dl, full_h, full_w, cy, cx, radius = (
        geometry[0], geometry[1], geometry[2], geometry[3], geometry[4], geometry[5], geometry[6]
    )  # fmt: skip
    k0, k1, k2, k3, k4, k5 = k[0], k[1], k[2], k[3], k[4], k[5]
    y = (i + dt - cy) / radius
    yy = y * y
    for j in range(w):
        x = xs[j]
        r2 = min(x * x + yy, 1.0)
        f = k0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        ty = k4 * (r2 + 2.0 * yy) + 2.0 * k5 * x * y
        tx = k5 * (r2 + 2.0 * x * x) + 2.0 * k4 * x * y
        sr = min(max(cy + radius * (y * f + ty), 0.0), full_h - 1.0) - dt
        sc = min(max(cx + radius * (x * f + tx), 0.0), full_w - 1.0) - dl
        sr = min(max(sr, 0.0), h - 1.0)
        sc = min(max(sc, 0.0), w - 1.0)
        fr0 = math.floor(sr)
        fc0 = math.floor(sc)
        krs[j] = np.int32((sr - fr0) * 32.0)  # the fraction in 32nds
        kcs[j] = np.int32((sc - fc0) * 32.0)
        tops[j] = np.int32(fr0) - 1
        lefts[j] = np.int32(fc0) - 1


@njit(nogil=True)
def _columns(geometry, w):  # type: ignore[no-untyped-def]
    """Return every column's ``x``, its offset from the centre over the radius."""
    xs = np.empty(w)
    for j in range(w):
        xs[j] = (j + geometry[1] - geometry[5]) / geometry[6]
    return xs


@njit(nogil=True)
def warp_rows(r0, r1, src, out, coef, geometry):  # type: ignore[no-untyped-def]
    """Warp output rows ``r0 .. r1 - 1`` of ``out`` (H, W, C float32) from ``src`` (same shape).

    ``coef`` (planes, 6) float64: ``kr0..kr3, kt0, kt1`` per plane (one row: every plane).
    ``geometry`` float64: the offset of the image's first pixel in the opcode's image (rows,
    columns), that image's height and width, the centre (row, column) and the radius ``R``.
    One row of ``coef`` and three planes (a phone's warp): every plane's 4 x 4 taps in one
    pass over the source position (the same sums, in the same order, as plane by plane).
    """
    h, w, nc = src.shape
    table = _weight_table()
    if coef.shape[0] == 1 and nc == 3:
        _warp_rows3(r0, r1, src, out, coef[0], geometry, table)
        return
    xs = _columns(geometry, w)
    tops = np.empty(w, np.int32)
    lefts = np.empty(w, np.int32)
    krs = np.empty(w, np.int32)
    kcs = np.empty(w, np.int32)
    for i in range(r0, r1):
        for p in range(nc):
            k = coef[min(p, coef.shape[0] - 1)]
            _row_sources(i, k, xs, geometry, h, w, tops, lefts, krs, kcs)
            for j in range(w):
                top, left, kr, kc = tops[j], lefts[j], krs[j], kcs[j]
                total = 0.0
                for a in range(4):
                    rr = min(max(top + a, 0), h - 1)
                    row = 0.0
                    for b in range(4):
                        cc = min(max(left + b, 0), w - 1)
                        row += table[kc, b] * src[rr, cc, p]
                    total += table[kr, a] * row
                out[i, j, p] = min(max(total, 0.0), 1.0)


@njit(nogil=True)
def _warp_rows3(r0, r1, src, out, k, geometry, table):  # type: ignore[no-untyped-def]
    """:func:`warp_rows` for three planes sharing one source position.

    The same values as the plane-by-plane loop, bit for bit: ``x`` of every column worked out
    once (the same division); per row, first the source positions of every column (a loop
    without branches, which the compiler vectorises: it was half the time), then the 4 x 4
    taps of the three planes read together (one clamp of the rows and columns per pixel).
    """
    h, w = src.shape[0], src.shape[1]
    xs = _columns(geometry, w)
    tops = np.empty(w, np.int32)
    lefts = np.empty(w, np.int32)
    krs = np.empty(w, np.int32)
    kcs = np.empty(w, np.int32)
    for i in range(r0, r1):
        _row_sources(i, k, xs, geometry, h, w, tops, lefts, krs, kcs)
        for j in range(w):
            top, left, kr, kc = tops[j], lefts[j], krs[j], kcs[j]
            wc0, wc1, wc2, wc3 = table[kc, 0], table[kc, 1], table[kc, 2], table[kc, 3]
            c0 = min(max(left, 0), w - 1)  # the edge pixels repeated
            c1 = min(max(left + 1, 0), w - 1)
            c2 = min(max(left + 2, 0), w - 1)
            c3 = min(max(left + 3, 0), w - 1)
            t0 = 0.0
            t1 = 0.0
            t2 = 0.0
            for a in range(4):
                s = src[min(max(top + a, 0), h - 1)]
                # the sums as the plane-by-plane loop makes them: 0 + w0 v0 + w1 v1 + ...
                x0 = 0.0 + wc0 * s[c0, 0]
                x1 = 0.0 + wc0 * s[c0, 1]
                x2 = 0.0 + wc0 * s[c0, 2]
                x0 += wc1 * s[c1, 0]
                x1 += wc1 * s[c1, 1]
                x2 += wc1 * s[c1, 2]
                x0 += wc2 * s[c2, 0]
                x1 += wc2 * s[c2, 1]
                x2 += wc2 * s[c2, 2]
                x0 += wc3 * s[c3, 0]
                x1 += wc3 * s[c3, 1]
                x2 += wc3 * s[c3, 2]
                wa = table[kr, a]
                t0 += wa * x0
                t1 += wa * x1
                t2 += wa * x2
            out[i, j, 0] = min(max(t0, 0.0), 1.0)
            out[i, j, 1] = min(max(t1, 0.0), 1.0)
            out[i, j, 2] = min(max(t2, 0.0), 1.0)


@njit(nogil=True, error_model="numpy")
def gain_map_rows(r0, r1, mosaic, black, white, maps, grid, rows, cols, out):  # type: ignore[no-untyped-def]
    """Apply GainMaps to rows ``r0 .. r1 - 1`` of ``mosaic`` (H, W uint16) into ``out``.

    :func:`imageform.io._dng_opcodes.apply_stage2`'s arithmetic for a list of GainMaps alone,
    one row at a time: ``x = (m - black) / (white - black)`` (float64), each map in order
    ``x = min(x g, 1)`` on its lattice, ``g`` as :func:`imageform.io._dng_opcodes.
    gain_map_gains` interpolates it, then ``rint(clip(x (white - black) + black, 0, 65535))``.
    ``black`` (H, W) float64 (a broadcast view will do). Per map ``k``, ``maps[k]``: the
    offset of its grid in ``grid`` (flat float64) and its number of columns; the offset of its
    lattice rows in ``rows`` and their first row, step and count in the mosaic; the same of
    its lattice columns in ``cols``. ``rows`` and ``cols`` (3, n) float64: the lower grid
    index, the upper one, the weight of the upper (``_axis_weights``).
    """
    w = mosaic.shape[1]
    x = np.empty(w)
    along = np.empty(max(1, int(maps[:, 1].max())) if maps.shape[0] else 1)
    for i in range(r0, r1):
        for j in range(w):
            b = black[i, j]
            x[j] = (mosaic[i, j] - b) / (white - b)
        for k in range(maps.shape[0]):
            g_off, g_cols, r_off, r_first, r_step, r_count, c_off, c_first, c_step, c_count = (
                maps[k, 0], maps[k, 1], maps[k, 2], maps[k, 3], maps[k, 4], maps[k, 5],
                maps[k, 6], maps[k, 7], maps[k, 8], maps[k, 9],
            )  # fmt: skip
            d = i - r_first
            if d < 0 or d % r_step != 0 or d // r_step >= r_count:
                continue
            q = r_off + d // r_step
            lo = g_off + int(rows[0, q]) * g_cols
            hi = g_off + int(rows[1, q]) * g_cols
            wr = rows[2, q]
            for t in range(g_cols):  # the map's row at this row: between its two rows
                along[t] = grid[lo + t] * (1 - wr) + grid[hi + t] * wr
            for n in range(c_count):
                p = c_off + n
                wc = cols[2, p]
                g = along[int(cols[0, p])] * (1 - wc) + along[int(cols[1, p])] * wc
                j = c_first + n * c_step
                x[j] = min(x[j] * g, 1.0)
        for j in range(w):
            b = black[i, j]
            v = x[j] * (white - b) + b
            out[i, j] = np.uint16(np.rint(min(max(v, 0.0), 65535.0)))
