"""Numba kernels of the DNG WarpRectilinear opcode (:func:`imageform.io._dng_opcodes.apply_stage3`).

:func:`warp_rows` is :func:`imageform.io._dng_opcodes.warp_source_positions` followed by
:func:`imageform.io._dng_opcodes.bicubic_sample`, row by row (the NumPy functions are the
reference the tests hold it to). The source position is the Adobe DNG SDK's
``dng_filter_warp``, clamped to the image, Keys' bicubic kernel (a = -0.75) at the fraction
floored to 1/32 pixel (its 32 weights worked out once), 4 x 4 taps with the edge pixels
repeated, the result clamped to [0, 1]. :func:`warp_render_rows` is the same warp with
:func:`imageform._kernels.raw_develop.render_rows` done on each row as it is warped (the
colour matrix, the clipping and the transfer function): one pass, no warped image kept.
:func:`develop_warp_render_rows` is that from a Bayer mosaic, demosaiced band by band of
output rows (the rows a band's warp reads), so that no demosaiced image is made either.

Per output row (:func:`_warp_row`): the source positions of every column
(:func:`_row_sources`, a loop without branches the compiler vectorises), their weights, then
the row cut into runs of columns whose 4 x 4 source blocks lie inside the image and move one
column per output column (a mild warp shifts by a column every 70 to 110 pixels of a 12 Mpx
row). Within a run, the taps of a plane read consecutive source columns: a loop the compiler
vectorises (:func:`_run_taps`, eight pixels at a time with AVX-512), with the same sums in
the same order as the pixel-by-pixel loop (:func:`_pixel_taps`, which does the others: the
edges), so the values are those of the pixel-by-pixel loop bit for bit. The source image is
planar (C, H, W): a plane's rows are contiguous. 12 Mpx on one core: 0.19 s -> 0.11 s for
the warp (``benchmarks/check_phone_dng.py``). Run on numba's threads by
:func:`imageform._kernels.jit.run_tasks`, a row per task.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.raw_develop import MODE_PLANAR, develop_rows, render_planar_row

__all__ = ["band_source_rows", "develop_warp_render_rows", "warp_render_rows", "warp_rows"]


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
def _row_weights(krs, kcs, table, wts, w):  # type: ignore[no-untyped-def]
    """``wts[0..3, j]``: column ``j``'s four column weights, ``wts[4..7, j]`` its row weights."""
    for j in range(w):
        kc = kcs[j]
        kr = krs[j]
        wts[0, j] = table[kc, 0]
        wts[1, j] = table[kc, 1]
        wts[2, j] = table[kc, 2]
        wts[3, j] = table[kc, 3]
        wts[4, j] = table[kr, 0]
        wts[5, j] = table[kr, 1]
        wts[6, j] = table[kr, 2]
        wts[7, j] = table[kr, 3]


@njit(nogil=True)
def _row_runs(tops, lefts, h, w, starts, inner):  # type: ignore[no-untyped-def]
    """Cut a row into runs; return their number.

    Run ``r`` covers columns ``starts[r] .. starts[r + 1] - 1``. ``inner[r]``: every 4 x 4
    source block of the run lies inside the image and sits one column right of the previous
    one (same top row); otherwise the run is a single column (at the image's edges).
    """
    n = 0
    j = 0
    while j < w:
        top = tops[j]
        left = lefts[j]
        starts[n] = j
        if top < 0 or top > h - 4 or left < 0 or left > w - 4:
            inner[n] = False
            j += 1
        else:
            inner[n] = True
            shift = left - j
            j += 1
            while j < w and tops[j] == top and lefts[j] - j == shift and lefts[j] <= w - 4:
                j += 1
        n += 1
    starts[n] = w
    return n


@njit(nogil=True)
def _pixel_taps(flat, p0, p1, h, hs, row0, w, tops, lefts, wts, j0, j1, o):  # type: ignore[no-untyped-def]
    """Warp columns ``j0 .. j1 - 1`` of planes ``p0 .. p1 - 1`` pixel by pixel into ``o``.

    ``flat``: the planar source (C, ``hs``, W), flat, from the image's row ``row0`` (of
    ``h``). Each pixel's 4 x 4 taps with the edge pixels
    repeated (its rows and columns clamped once for every plane), the sums in the order of
    :func:`_run_taps`: per tap row ``0 + w0 v0 + w1 v1 + w2 v2 + w3 v3``, then ``0 + a0 x0 +
    a1 x1 + a2 x2 + a3 x3``, clamped to [0, 1]. For the edges, and runs too short for the
    vectorised loop; three planes read together.
    """
    for j in range(j0, j1):
        top = tops[j]
        left = lefts[j]
        wc0, wc1, wc2, wc3 = wts[0, j], wts[1, j], wts[2, j], wts[3, j]
        wr0, wr1, wr2, wr3 = wts[4, j], wts[5, j], wts[6, j], wts[7, j]
        c0 = min(max(left, 0), w - 1)
        c1 = min(max(left + 1, 0), w - 1)
        c2 = min(max(left + 2, 0), w - 1)
        c3 = min(max(left + 3, 0), w - 1)
        a0 = min(max(top, 0), h - 1) - row0
        a1 = min(max(top + 1, 0), h - 1) - row0
        a2 = min(max(top + 2, 0), h - 1) - row0
        a3 = min(max(top + 3, 0), h - 1) - row0
        u = np.uint64
        if p1 - p0 == 3:
            hw = u(hs * w)
            b0 = u(p0 * hs * w)
            r0 = b0 + u(a0 * w)
            r1 = b0 + u(a1 * w)
            r2 = b0 + u(a2 * w)
            r3 = b0 + u(a3 * w)
            t0 = 0.0
            t1 = 0.0
            t2 = 0.0
            x0 = 0.0 + wc0 * flat[r0 + u(c0)]
            x1 = 0.0 + wc0 * flat[r0 + u(c0) + hw]
            x2 = 0.0 + wc0 * flat[r0 + u(c0) + hw + hw]
            x0 += wc1 * flat[r0 + u(c1)]
            x1 += wc1 * flat[r0 + u(c1) + hw]
            x2 += wc1 * flat[r0 + u(c1) + hw + hw]
            x0 += wc2 * flat[r0 + u(c2)]
            x1 += wc2 * flat[r0 + u(c2) + hw]
            x2 += wc2 * flat[r0 + u(c2) + hw + hw]
            x0 += wc3 * flat[r0 + u(c3)]
            x1 += wc3 * flat[r0 + u(c3) + hw]
            x2 += wc3 * flat[r0 + u(c3) + hw + hw]
            t0 += wr0 * x0
            t1 += wr0 * x1
            t2 += wr0 * x2
            x0 = 0.0 + wc0 * flat[r1 + u(c0)]
            x1 = 0.0 + wc0 * flat[r1 + u(c0) + hw]
            x2 = 0.0 + wc0 * flat[r1 + u(c0) + hw + hw]
            x0 += wc1 * flat[r1 + u(c1)]
            x1 += wc1 * flat[r1 + u(c1) + hw]
            x2 += wc1 * flat[r1 + u(c1) + hw + hw]
            x0 += wc2 * flat[r1 + u(c2)]
            x1 += wc2 * flat[r1 + u(c2) + hw]
            x2 += wc2 * flat[r1 + u(c2) + hw + hw]
            x0 += wc3 * flat[r1 + u(c3)]
            x1 += wc3 * flat[r1 + u(c3) + hw]
            x2 += wc3 * flat[r1 + u(c3) + hw + hw]
            t0 += wr1 * x0
            t1 += wr1 * x1
            t2 += wr1 * x2
            x0 = 0.0 + wc0 * flat[r2 + u(c0)]
            x1 = 0.0 + wc0 * flat[r2 + u(c0) + hw]
            x2 = 0.0 + wc0 * flat[r2 + u(c0) + hw + hw]
            x0 += wc1 * flat[r2 + u(c1)]
            x1 += wc1 * flat[r2 + u(c1) + hw]
            x2 += wc1 * flat[r2 + u(c1) + hw + hw]
            x0 += wc2 * flat[r2 + u(c2)]
            x1 += wc2 * flat[r2 + u(c2) + hw]
            x2 += wc2 * flat[r2 + u(c2) + hw + hw]
            x0 += wc3 * flat[r2 + u(c3)]
            x1 += wc3 * flat[r2 + u(c3) + hw]
            x2 += wc3 * flat[r2 + u(c3) + hw + hw]
            t0 += wr2 * x0
            t1 += wr2 * x1
            t2 += wr2 * x2
            x0 = 0.0 + wc0 * flat[r3 + u(c0)]
            x1 = 0.0 + wc0 * flat[r3 + u(c0) + hw]
            x2 = 0.0 + wc0 * flat[r3 + u(c0) + hw + hw]
            x0 += wc1 * flat[r3 + u(c1)]
            x1 += wc1 * flat[r3 + u(c1) + hw]
            x2 += wc1 * flat[r3 + u(c1) + hw + hw]
            x0 += wc2 * flat[r3 + u(c2)]
            x1 += wc2 * flat[r3 + u(c2) + hw]
            x2 += wc2 * flat[r3 + u(c2) + hw + hw]
            x0 += wc3 * flat[r3 + u(c3)]
            x1 += wc3 * flat[r3 + u(c3) + hw]
            x2 += wc3 * flat[r3 + u(c3) + hw + hw]
            t0 += wr3 * x0
            t1 += wr3 * x1
            t2 += wr3 * x2
            o[p0 + 0, j] = min(max(t0, 0.0), 1.0)
            o[p0 + 1, j] = min(max(t1, 0.0), 1.0)
            o[p0 + 2, j] = min(max(t2, 0.0), 1.0)
            continue
        for p in range(p0, p1):
            base = u(p * hs * w)
            r0 = base + u(a0 * w)
            r1 = base + u(a1 * w)
            r2 = base + u(a2 * w)
            r3 = base + u(a3 * w)
            x = 0.0 + wc0 * flat[r0 + u(c0)]
            x += wc1 * flat[r0 + u(c1)]
            x += wc2 * flat[r0 + u(c2)]
            x += wc3 * flat[r0 + u(c3)]
            t = 0.0
            t += wr0 * x
            x = 0.0 + wc0 * flat[r1 + u(c0)]
            x += wc1 * flat[r1 + u(c1)]
            x += wc2 * flat[r1 + u(c2)]
            x += wc3 * flat[r1 + u(c3)]
            t += wr1 * x
            x = 0.0 + wc0 * flat[r2 + u(c0)]
            x += wc1 * flat[r2 + u(c1)]
            x += wc2 * flat[r2 + u(c2)]
            x += wc3 * flat[r2 + u(c3)]
            t += wr2 * x
            x = 0.0 + wc0 * flat[r3 + u(c0)]
            x += wc1 * flat[r3 + u(c1)]
            x += wc2 * flat[r3 + u(c2)]
            x += wc3 * flat[r3 + u(c3)]
            t += wr3 * x
            o[p, j] = min(max(t, 0.0), 1.0)


#: Runs shorter than this are warped pixel by pixel: the vectorised loop's width (eight
#: float64 with AVX-512).
_MIN_RUN = 8


@njit(nogil=True)
def _run_taps(n, flat, q, w, wflat, v, ww, oflat, r, planes, hw):  # type: ignore[no-untyped-def]
    """One plane's taps for a run of ``n`` columns whose source blocks move a column each.

    ``flat``: the planar source, flat; ``q``: the index of the run's first tap (its top row
    and left column); ``w``: the source's row length. ``wflat``: :func:`_row_weights`'s
    (8, ``ww``) flat, ``v`` the run's first column; ``oflat``: the output, flat, from ``r``.
    :func:`_pixel_taps`' sums, without the clamping of the indices (inside the image). The
    indices are unsigned, so that numba adds no test for negative ones and the compiler
    sees consecutive loads: the loop is vectorised.
    """
    u = np.uint64
    v0 = u(v)
    v1 = u(v + ww)
    v2 = u(v + 2 * ww)
    v3 = u(v + 3 * ww)
    v4 = u(v + 4 * ww)
    v5 = u(v + 5 * ww)
    v6 = u(v + 6 * ww)
    v7 = u(v + 7 * ww)
    one, two, three = u(1), u(2), u(3)
    for p in range(planes):
        q0 = u(q + p * hw)
        q1 = u(q + p * hw + w)
        q2 = u(q + p * hw + 2 * w)
        q3 = u(q + p * hw + 3 * w)
        ro = u(r + p * ww)
        for j in range(u(n)):
            wc0 = wflat[v0 + j]
            wc1 = wflat[v1 + j]
            wc2 = wflat[v2 + j]
            wc3 = wflat[v3 + j]
            x = 0.0 + wc0 * flat[q0 + j]
            x += wc1 * flat[q0 + j + one]
            x += wc2 * flat[q0 + j + two]
            x += wc3 * flat[q0 + j + three]
            t = 0.0
            t += wflat[v4 + j] * x
            x = 0.0 + wc0 * flat[q1 + j]
            x += wc1 * flat[q1 + j + one]
            x += wc2 * flat[q1 + j + two]
            x += wc3 * flat[q1 + j + three]
            t += wflat[v5 + j] * x
            x = 0.0 + wc0 * flat[q2 + j]
            x += wc1 * flat[q2 + j + one]
            x += wc2 * flat[q2 + j + two]
            x += wc3 * flat[q2 + j + three]
            t += wflat[v6 + j] * x
            x = 0.0 + wc0 * flat[q3 + j]
            x += wc1 * flat[q3 + j + one]
            x += wc2 * flat[q3 + j + two]
            x += wc3 * flat[q3 + j + three]
            t += wflat[v7 + j] * x
            oflat[ro + j] = min(max(t, 0.0), 1.0)


@njit(nogil=True)
def _warp_row(i, src, coef, geometry, table, xs, buf, wts, starts, inner, o, runs, h, row0, known):  # type: ignore[no-untyped-def]
    """Warp output row ``i`` of every plane of ``src`` (C, H, W) into ``o`` (C, W) float32.

    ``src`` holds the image's rows ``row0 ..`` of its ``h`` (all: ``row0`` 0). ``buf`` (4,
    W) int32: the first tap's rows and columns, the fractions' indices (``known``: already
    there, for one row of ``coef``); ``runs``
    False: every column pixel by pixel (:func:`_pixel_taps`; the tests' reference). A run of
    columns (:func:`_row_runs`) inside the image, :data:`_MIN_RUN` long or more, plane by
    plane by the vectorised loop (:func:`_run_taps`); the others pixel by pixel.
    """
    nc, hs, w = src.shape
    flat = src.reshape(nc * hs * w)
    wflat = wts.reshape(8 * w)
    oflat = o.reshape(nc * w)
    tops, lefts, krs, kcs = buf[0], buf[1], buf[2], buf[3]
    shared = coef.shape[0] == 1  # one set of positions for every plane
    for p in range(1 if shared else nc):
        if p < coef.shape[0]:  # this plane's positions (the last row: the other planes')
            if not known:
                _row_sources(i, coef[p], xs, geometry, h, w, tops, lefts, krs, kcs)
            _row_weights(krs, kcs, table, wts, w)
            n = _row_runs(tops, lefts, h, w, starts, inner)
        p1 = nc if shared else p + 1
        for r in range(n):
            j0 = starts[r]
            j1 = starts[r + 1]
            if runs and inner[r] and j1 - j0 >= _MIN_RUN:
                q = (p * hs + tops[j0] - row0) * w + lefts[j0]
                _run_taps(j1 - j0, flat, q, w, wflat, j0, w, oflat, p * w + j0, p1 - p, hs * w)
            else:
                _pixel_taps(flat, p, p1, h, hs, row0, w, tops, lefts, wts, j0, j1, o)


@njit(nogil=True)
def warp_rows(r0, r1, src, out, coef, geometry, runs=True):  # type: ignore[no-untyped-def]
    """Warp output rows ``r0 .. r1 - 1`` of ``out`` (H, W, C float32) from ``src`` (C, H, W).

    ``src`` float32, planar. ``coef`` (planes, 6) float64: ``kr0..kr3, kt0, kt1`` per plane
    (one row: every plane's, the positions worked out once). ``geometry`` float64: the
    offset of the image's first pixel in the opcode's image (rows, columns), that image's
    height and width, the centre (row, column) and the radius ``R``. ``runs`` False: every
    pixel by the pixel-by-pixel loop (the same values).
    """
    nc, h, w = src.shape
    table = _weight_table()
    xs = _columns(geometry, w)
    buf = np.empty((4, w), np.int32)
    wts = np.empty((8, w))
    starts = np.empty(w + 1, np.int64)
    inner = np.empty(w, np.bool_)
    o = np.empty((nc, w), np.float32)
    for i in range(r0, r1):
        _warp_row(i, src, coef, geometry, table, xs, buf, wts, starts, inner, o, runs, h, 0, False)
        oi = out[i]
        for p in range(nc):
            op = o[p]
            for j in range(w):
                oi[j, p] = op[j]


@njit(nogil=True, error_model="numpy")
def warp_render_rows(r0, r1, src, coef, geometry, m, lut, encode, out):  # type: ignore[no-untyped-def]
    """:func:`warp_rows` of three planes, each row rendered as it is warped, into ``out``.

    ``out`` (H, W, 3) float32: :func:`imageform._kernels.raw_develop.render_rows` of the
    warped rows (``m``, ``lut``, ``encode`` as there), the same values bit for bit as the
    warp followed by the render, without the warped image written and read again.
    """
    nc, h, w = src.shape
    table = _weight_table()
    xs = _columns(geometry, w)
    buf = np.empty((4, w), np.int32)
    wts = np.empty((8, w))
    starts = np.empty(w + 1, np.int64)
    inner = np.empty(w, np.bool_)
    o = np.empty((nc, w), np.float32)
    idx = np.empty((3, w), np.int32)
    for i in range(r0, r1):
        _warp_row(i, src, coef, geometry, table, xs, buf, wts, starts, inner, o, True, h, 0, False)
        render_planar_row(o[0], o[1], o[2], m, lut, encode, out[i], idx)


@njit(nogil=True, error_model="numpy")
def develop_warp_render_rows(r0, r1, mosaic, black, scale, ry, rx, coef, geo, m, lut, enc, n, out):  # type: ignore[no-untyped-def]
    """:func:`warp_render_rows` straight from a Bayer mosaic, ``n`` output rows at a time.

    For each band of output rows, the source rows its warp reads (one row of ``coef``) are
    demosaiced into planes by :func:`imageform._kernels.raw_develop.develop_rows` (its
    arguments ``mosaic`` .. ``rx``; ``geo`` and ``enc``: :func:`warp_render_rows`'
    ``geometry`` and ``encode``), then the band is warped and rendered from them: the
    same values, bit for bit, as the whole image demosaiced first, without it made (a
    band's source rows stay in the cache; the rows two bands share are demosaiced twice).
    """
    h, w = mosaic.shape
    table = _weight_table()
    xs = _columns(geo, w)
    bufs = np.empty((n, 4, w), np.int32)
    wts = np.empty((8, w))
    starts = np.empty(w + 1, np.int64)
    inner = np.empty(w, np.bool_)
    o = np.empty((3, w), np.float32)
    idx = np.empty((3, w), np.int32)
    no_u = np.empty((0, 0, 3), np.uint16)
    k = coef[0]
    for i0 in range(r0, r1, n):
        i1 = min(i0 + n, r1)
        lo = h
        hi = -1
        for i in range(i0, i1):  # the band's positions, and the source rows they read
            b = bufs[i - i0]
            _row_sources(i, k, xs, geo, h, w, b[0], b[1], b[2], b[3])
            tops = b[0]
            for j in range(w):
                lo = min(lo, tops[j])
                hi = max(hi, tops[j])
        s0 = max(lo, 0)
        s1 = min(hi + 3, h - 1)
        planes = np.empty((3, s1 - s0 + 1, w), np.float32)
        develop_rows(s0, s1 + 1, mosaic, black, scale, ry, rx, m, lut, enc, MODE_PLANAR,
                     planes, no_u, s0)  # fmt: skip
        for i in range(i0, i1):
            _warp_row(i, planes, coef, geo, table, xs, bufs[i - i0], wts, starts, inner, o,
                      True, h, s0, True)  # fmt: skip
            render_planar_row(o[0], o[1], o[2], m, lut, enc, out[i], idx)


@njit(nogil=True)
def band_source_rows(coef, geometry, h, w, band):  # type: ignore[no-untyped-def]
    """Return about the most source rows a band of ``band`` output rows reads.

    For :func:`develop_warp_render_rows`' choice: from the positions of every 16th row (the
    warp is smooth; every ``band``-th where less) and the sampled rows just before and after
    each band, plus the taps' four rows.
    """
    step = min(16, band)
    xs = _columns(geometry, w)
    buf = np.empty((4, w), np.int32)
    tops, lefts, krs, kcs = buf[0], buf[1], buf[2], buf[3]
    n = (h - 1) // step + 2
    rows = np.empty(n, np.int64)
    lows = np.empty(n, np.int64)
    highs = np.empty(n, np.int64)
    for k in range(n):
        rows[k] = min(k * step, h - 1)
        _row_sources(rows[k], coef[0], xs, geometry, h, w, tops, lefts, krs, kcs)
        lows[k] = tops.min()
        highs[k] = tops.max()
    most = 0
    for b in range(0, h, band):
        lo = h
        hi = -h
        for k in range(n):
            if b - step < rows[k] < b + band + step:
                lo = min(lo, lows[k])
                hi = max(hi, highs[k])
        most = max(most, hi - lo + 4)
    return most


@njit(nogil=True, error_model="numpy")
def gain_map_rows(r0, r1, mosaic, black, white, maps, grid, rows, cols, out):  # type: ignore[no-untyped-def]
    """Apply GainMaps to rows ``r0 .. r1 - 1`` of ``mosaic`` (H, W uint16) into ``out``.

    :func:`imageform.io._dng_opcodes.apply_stage2`'s arithmetic for a list of GainMaps alone,
    one row at a time: ``x = (m - black) / (white - black)`` (float64), each map in order
    ``x = min(x g, 1)`` on its lattice, ``g`` as :func:`imageform.io._dng_opcodes.
    gain_map_gains` interpolates it, then ``rint(clip(x (white - black) + black, 0, 65535))``.
    ``black`` (R, W) float64, C-contiguous: row ``i`` of the mosaic takes black row ``i % R``
    (R = 1: one black level; R = H: one per photosite), so that the loops over a row read
    contiguous values (the compiler vectorises them, the division included). Per map ``k``,
    ``maps[k]``: the offset of its grid in ``grid`` (flat float64) and its number of columns;
    the offset of its lattice rows in ``rows`` and their first row, step and count in the
    mosaic; the same of its lattice columns in ``cols``. ``rows`` and ``cols`` (3, n)
    float64: the lower grid index, the upper one, the weight of the upper
    (``_axis_weights``).
    """
    w = mosaic.shape[1]
    x = np.empty(w)
    along = np.empty(max(1, int(maps[:, 1].max())) if maps.shape[0] else 1)
    for i in range(r0, r1):
        brow = black[i % black.shape[0]]
        mrow = mosaic[i]
        for j in range(w):
            b = brow[j]
            x[j] = (mrow[j] - b) / (white - b)
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
        orow = out[i]
        for j in range(w):
            b = brow[j]
            v = x[j] * (white - b) + b
            orow[j] = np.uint16(np.rint(min(max(v, 0.0), 65535.0)))
