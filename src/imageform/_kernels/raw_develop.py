r"""Numba kernels of raw development (:func:`imageform.io.develop`), float32.

- :func:`develop_rows`: the digital numbers of a Bayer mosaic to the encoded output, one row
  at a time, every stage fused: per photosite of the 2x2 tile
  :math:`\min(\max((DN - B_s)\,k_s, 0), 1)` with :math:`k_s = g_s / (W - B_s)` (linearisation
  and white balance), bilinear demosaicing (:func:`imageform._kernels.demosaic_bilinear.
  bilinear_numba`'s arithmetic, the mosaic mirrored about its edge pixels), the 3x3 matrix
  (camera RGB to the output space's linear RGB, adaptation included), clipping to [0, 1]
  and the transfer function from a table (below); written as float32, as uint16 rounded half
  up, or, before the matrix, as the demosaiced camera RGB (pixel by pixel, or as three
  planes for the DNG warp's kernel). The working set is three
  white-balanced rows, one demosaiced row, one output row (about 220 kB at 6000 columns) and
  the 256 kB table: in the core's L2 cache; no full-size temporary is made.
- :func:`render_rows`: demosaiced camera RGB to the encoded output in one pass (a linear raw,
  which has no mosaic, and the other demosaicing methods); :func:`render_planar_row`, the
  same for one row given as planes (the DNG warp renders each row it warps with it).
- :func:`quantize`: a float image in [0, 1] to integers, rounded half up.

The transfer table is sampled uniformly in :math:`\sqrt{x}` (65,537 entries, linear
interpolation: within 1e-6 of the exact curve for sRGB, and for pure power laws, whose slope
at 0 is infinite, within 2e-6; ``tests/io/test_raw_fast.py``).

:func:`develop_rows` is a serial kernel of one explicit signature, run on numba's threads by
:func:`imageform._kernels.jit.run_tasks` (contiguous row ranges; each range white-balances the
rows just above and below it again), so it compiles once, as a serial loop (no ``parallel=True``
lowering).
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = [
    "LUT_SIZE",
    "MODE_CAMERA",
    "MODE_FLOAT",
    "MODE_PLANAR",
    "MODE_UINT16",
    "develop_rows",
    "quantize",
    "render_planar_row",
    "render_rows",
]

#: Intervals of the transfer table (in sqrt(x)).
LUT_SIZE = 65536

#: :func:`develop_rows` outputs: demosaiced camera RGB (float32), the encoded output as
#: float32, the encoded output as uint16, demosaiced camera RGB as planes (3, H, W) float32
#: (the warp's source: :func:`imageform._kernels.dng_warp.warp_render_rows`).
MODE_CAMERA, MODE_FLOAT, MODE_UINT16, MODE_PLANAR = 0, 1, 2, 3

_ROWS_SIGNATURE = (
    "void(int64, int64, uint16[:, ::1], float32[:, ::1], float32[:, ::1], int64, int64, "
    "float32[:, ::1], float32[::1], boolean, int64, float32[:, :, ::1], uint16[:, :, ::1], int64)"
)


@njit(inline="always", error_model="numpy")
def _mirror(i, n):  # type: ignore[no-untyped-def]
    """Index ``i`` in ``[-1, n]`` mirrored about the edge samples (-1 reads 1, n reads n - 2)."""
    if i < 0:
        return -i
    if i >= n:
        return 2 * n - 2 - i
    return i


@njit(error_model="numpy")
def _balance_row(mosaic, black, scale, i, buf):  # type: ignore[no-untyped-def]
    """``buf[1 + j] = clip((DN[i, j] - B) * k, 0, 1)``; ``buf[0]``, ``buf[w + 1]`` mirrored."""
    w = mosaic.shape[1]
    src = mosaic[i]
    b0 = black[i & 1, 0]
    b1 = black[i & 1, 1]
    s0 = scale[i & 1, 0]
    s1 = scale[i & 1, 1]
    zero = np.float32(0)
    one = np.float32(1)
    for p in range(w // 2):  # even and odd column of each pair: no select, vectorised
        v0 = (np.float32(src[2 * p]) - b0) * s0
        v1 = (np.float32(src[2 * p + 1]) - b1) * s1
        buf[2 * p + 1] = min(max(v0, zero), one)
        buf[2 * p + 2] = min(max(v1, zero), one)
    if w & 1:
        v0 = (np.float32(src[w - 1]) - b0) * s0
        buf[w] = min(max(v0, zero), one)
    buf[0] = buf[2]
    buf[w + 1] = buf[w - 1]


@njit(_ROWS_SIGNATURE, nogil=True, error_model="numpy")
def develop_rows(r0, r1, mosaic, black, scale, ry, rx, m, lut, encode, mode, out_f, out_u, row0):  # type: ignore[no-untyped-def]
    """Develop rows ``r0 .. r1 - 1`` of ``mosaic`` into ``out_f`` or ``out_u`` (``mode``).

    ``out_f`` (H, W, 3), or (3, H, W) for :data:`MODE_PLANAR`; row ``i`` of the mosaic
    is written to row ``i - row0`` of ``out_f`` or ``out_u`` (0: the whole image; the DNG
    warp's kernel demosaics bands of rows, :func:`imageform._kernels.dng_warp.
    develop_warp_render_rows`). ``black``, ``scale``: per
    photosite of the 2x2 tile; red at ``(ry, rx)``; ``m``: camera RGB to the output's linear
    RGB; ``lut``: the transfer table (used when ``encode``).
    """
    h, w = mosaic.shape
    bal = np.empty((3, w + 2), np.float32)  # the white-balanced rows, by row index % 3
    rgb = np.empty((3, w), np.float32)
    q = np.float32(0.25)
    half = np.float32(0.5)
    zero = np.float32(0)
    one = np.float32(1)
    lin = np.empty(3 * w, np.float32)  # the row's output samples, interleaved
    nm1 = np.int32(lut.shape[0] - 2)
    fn = np.float32(lut.shape[0] - 1)
    top = np.float32(65535)
    m00, m01, m02 = m[0, 0], m[0, 1], m[0, 2]
    m10, m11, m12 = m[1, 0], m[1, 1], m[1, 2]
    m20, m21, m22 = m[2, 0], m[2, 1], m[2, 2]
    for k in range(r0 - 1, r1 + 1):  # white-balance row k, then develop row k - 1
        _balance_row(mosaic, black, scale, _mirror(k, h), bal[(k + 3) % 3])
        i = k - 1
        if i < r0:
            continue
        u = bal[(i + 2) % 3]
        c = bal[i % 3]
        d = bal[(i + 1) % 3]
        red_row = (i & 1) == ry
        par = rx if red_row else 1 - rx  # column parity of this row's red (blue) sites
        own = rgb[0] if red_row else rgb[2]
        oth = rgb[2] if red_row else rgb[0]
        grn = rgb[1]
        for j in range(w):
            x = c[j + 1]
            s1h = c[j] + c[j + 2]
            s1v = u[j + 1] + d[j + 1]
            dg = u[j] + u[j + 2] + d[j] + d[j + 2]
            is_rb = (j & 1) == par
            grn[j] = q * (s1h + s1v) if is_rb else x
            own[j] = x if is_rb else half * s1h
            oth[j] = q * dg if is_rb else half * s1v
        if mode == 0:
            o = out_f[i - row0]
            for j in range(w):
                o[j, 0] = rgb[0, j]
                o[j, 1] = rgb[1, j]
                o[j, 2] = rgb[2, j]
            continue
        if mode == 3:
            for c in range(3):
                out_f[c, i - row0] = rgb[c]
            continue
        # the matrix and the clipping, then (a second loop, of gathers) the table
        for j in range(w):
            r = rgb[0, j]
            g = rgb[1, j]
            b = rgb[2, j]
            v0 = min(max(m00 * r + m01 * g + m02 * b, zero), one)
            v1 = min(max(m10 * r + m11 * g + m12 * b, zero), one)
            v2 = min(max(m20 * r + m21 * g + m22 * b, zero), one)
            if encode:
                v0 = np.sqrt(v0) * fn
                v1 = np.sqrt(v1) * fn
                v2 = np.sqrt(v2) * fn
            lin[3 * j] = v0
            lin[3 * j + 1] = v1
            lin[3 * j + 2] = v2
        if encode:
            for j in range(3 * w):
                t = lin[j]
                e = min(np.int32(t), nm1)
                f = t - np.float32(e)
                lo = lut[e]
                lin[j] = lo + f * (lut[e + 1] - lo)
        if mode == 1:
            of = out_f[i - row0].reshape(3 * w)
            for j in range(3 * w):
                of[j] = lin[j]
        else:
            ou = out_u[i - row0].reshape(3 * w)
            for j in range(3 * w):
                ou[j] = np.int32(lin[j] * top + half)


@njit(nogil=True, error_model="numpy")
def render_rows(r0, r1, cam, m, lut, encode, out):  # type: ignore[no-untyped-def]
    """``out = T(clip(cam @ m.T, 0, 1))`` per pixel of rows ``r0 .. r1 - 1``.

    T from ``lut`` when ``encode``; run on threads by :func:`imageform._kernels.jit.run_tasks`.
    ``cam``, ``m``, ``out`` float32. :func:`develop_rows`'s arithmetic and its two loops per
    row (the matrix, then the table's gathers): 0.31 s -> 0.085 s for 12 Mpx on one core.
    """
    _, w, _ = cam.shape
    zero = np.float32(0)
    one = np.float32(1)
    nm1 = np.int32(lut.shape[0] - 2)
    fn = np.float32(lut.shape[0] - 1)
    m00, m01, m02 = m[0, 0], m[0, 1], m[0, 2]
    m10, m11, m12 = m[1, 0], m[1, 1], m[1, 2]
    m20, m21, m22 = m[2, 0], m[2, 1], m[2, 2]
    for i in range(r0, r1):
        # as develop_rows: the matrix and the clipping, then (a second loop, of gathers) the
        # table, over the row's samples in place
        c = cam[i]
        o = out[i]
        for j in range(w):
            r = c[j, 0]
            g = c[j, 1]
            b = c[j, 2]
            v0 = min(max(m00 * r + m01 * g + m02 * b, zero), one)
            v1 = min(max(m10 * r + m11 * g + m12 * b, zero), one)
            v2 = min(max(m20 * r + m21 * g + m22 * b, zero), one)
            if encode:
                v0 = np.sqrt(v0) * fn
                v1 = np.sqrt(v1) * fn
                v2 = np.sqrt(v2) * fn
            o[j, 0] = v0
            o[j, 1] = v1
            o[j, 2] = v2
        if encode:
            for j in range(w):
                for k in range(3):
                    t = o[j, k]
                    e = min(np.int32(t), nm1)
                    f = t - np.float32(e)
                    lo = lut[e]
                    o[j, k] = lo + f * (lut[e + 1] - lo)


@njit(nogil=True, error_model="numpy")
def render_planar_row(r, g, b, m, lut, encode, o, idx):  # type: ignore[no-untyped-def]
    """:func:`render_rows` of one row given as three planes ``r``, ``g``, ``b`` (W,) into ``o``.

    ``o`` (W, 3) float32; ``r``, ``g``, ``b`` are overwritten, ``idx`` (3, W) int32 is room
    for the table's indices. The same arithmetic, in the same order, as :func:`render_rows`
    (the same values bit for bit), in two loops: the matrix, the clipping, the square root,
    the table's index and the fraction over the planes (contiguous: the compiler vectorises
    it), then the table's gathers into ``o``, pixel by pixel. The warp's kernel
    renders each row it warps with it (:func:`imageform._kernels.dng_warp.warp_render_rows`).
    """
    w = o.shape[0]
    zero = np.float32(0)
    one = np.float32(1)
    nm1 = np.int32(lut.shape[0] - 2)
    fn = np.float32(lut.shape[0] - 1)
    m00, m01, m02 = m[0, 0], m[0, 1], m[0, 2]
    m10, m11, m12 = m[1, 0], m[1, 1], m[1, 2]
    m20, m21, m22 = m[2, 0], m[2, 1], m[2, 2]
    if not encode:
        for j in range(w):
            x = r[j]
            y = g[j]
            z = b[j]
            o[j, 0] = min(max(m00 * x + m01 * y + m02 * z, zero), one)
            o[j, 1] = min(max(m10 * x + m11 * y + m12 * z, zero), one)
            o[j, 2] = min(max(m20 * x + m21 * y + m22 * z, zero), one)
        return
    for j in range(w):  # the table's index and fraction too: only the gathers left
        x = r[j]
        y = g[j]
        z = b[j]
        v0 = min(max(m00 * x + m01 * y + m02 * z, zero), one)
        v1 = min(max(m10 * x + m11 * y + m12 * z, zero), one)
        v2 = min(max(m20 * x + m21 * y + m22 * z, zero), one)
        t0 = np.float32(np.sqrt(v0) * fn)
        t1 = np.float32(np.sqrt(v1) * fn)
        t2 = np.float32(np.sqrt(v2) * fn)
        e0 = min(np.int32(t0), nm1)
        e1 = min(np.int32(t1), nm1)
        e2 = min(np.int32(t2), nm1)
        idx[0, j] = e0
        idx[1, j] = e1
        idx[2, j] = e2
        r[j] = t0 - np.float32(e0)
        g[j] = t1 - np.float32(e1)
        b[j] = t2 - np.float32(e2)
    for j in range(w):
        for k in range(3):
            e = idx[k, j]
            f = r[j] if k == 0 else (g[j] if k == 1 else b[j])
            lo = lut[e]
            o[j, k] = lo + f * (lut[e + 1] - lo)


@njit(error_model="numpy")
def quantize(src, top, out):  # type: ignore[no-untyped-def]
    """``out = round(src * top)`` for ``src`` in [0, 1] (flat arrays; ``out`` an integer type).

    Rounds half up (``src * top + 0.5`` truncated, exact for non-negative values), which
    differs from ``numpy.rint`` (half to even) only on exact halves.
    """
    half = np.float32(0.5)
    for i in range(src.shape[0]):
        out[i] = src[i] * top + half
