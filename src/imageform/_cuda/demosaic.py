r"""CUDA kernels of demosaicing and raw development: one launch per call, one thread a pixel.

- :func:`demosaic`: bilinear and Malvar-He-Cutler on a float ``(B, H, W)`` Bayer mosaic into
  ``(B, H, W, 3)``, the optional clipping to [0, 1] fused. The mosaic is read in place with
  the phase-preserving mirror about the edge pixel (index ``-k`` reads ``k``), which is what
  :func:`imageform.sensor.demosaic` builds with ``numpy.pad(mode="reflect")``: no padded copy
  is made. The filters are those of :mod:`imageform._kernels.demosaic_bilinear` and
  :mod:`imageform._kernels.demosaic_malvar` (the same sums in the same order), evaluated for
  the one phase of the pixel; float32 mosaics are computed in float32 (the constants typed),
  as the CPU kernels do.
- :func:`develop_bayer`: :func:`imageform._kernels.raw_develop.develop_rows` per pixel (the
  digital numbers linearised, white-balanced and clipped per photosite of the 3x3 or 5x5
  window, bilinear or Malvar demosaicing, the 3x3 matrix, clipping, the transfer table,
  float32 or uint16 rounded half up): the whole raw pipeline of ``imageform develop`` in one
  kernel, float32 throughout as on the CPU.

Tests run the kernels under numba's CUDA simulator against the NumPy twins and compile them
for ``sm_90`` where NVVM is installed (``tests/backends/test_cuda_kernels.py``).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from imageform._cuda import _launch
from imageform._cuda._launch import empty_like, guarded
from imageform._cuda.geometry import import_cuda, row_grid

__all__ = [
    "MODE_CAMERA",
    "MODE_FLOAT",
    "MODE_UINT16",
    "demosaic",
    "develop_bayer",
    "develop_on_device",
    "develop_parameters",
]

#: :func:`develop_bayer` outputs, as :mod:`imageform._kernels.raw_develop`'s.
MODE_CAMERA, MODE_FLOAT, MODE_UINT16 = 0, 1, 2

#: Demosaicing methods of the kernels (``method`` argument).
_METHODS = {"bilinear": 0, "malvar": 1}


#: ``numba.cuda`` (a module global: numba's simulator swaps the global named ``cuda``).
cuda: Any = None


@functools.cache
def _kernels() -> Any:
    import math
    import types

    global cuda
    cuda = import_cuda()

    def mirror(i, n):  # type: ignore[no-untyped-def]
        # index i in [-2, n + 1] mirrored about the edge samples (-1 reads 1, n reads n - 2)
        if i < 0:
            return -i
        if i >= n:
            return 2 * n - 2 - i
        return i

    mirror_d = cuda.jit(device=True)(mirror)

    def clip01(v, zero, one):  # type: ignore[no-untyped-def]
        # min(max(v, 0), 1) by comparisons (NaN stays NaN, as numpy.clip)
        return zero if v < zero else (one if v > one else v)

    clip_d = cuda.jit(device=True)(clip01)
    row_grid_d = row_grid()

    def make_rgb_at(get: Any, T: Any) -> Any:
        """Return a device function: ``(R, G, B)`` at pixel ``(y, x)``, samples read by ``get``.

        ``get(a, b, yy, xx)`` reads one (mirrored) sample as type ``T``; the constants are of
        type ``T`` (float32 arithmetic for float32 data, as the CPU kernels).
        """

        def rgb_at(a, b, y, x, h, w, ry, rx, method):  # type: ignore[no-untyped-def]
            ym = mirror_d(y - 1, h)
            yp = mirror_d(y + 1, h)
            xm = mirror_d(x - 1, w)
            xp = mirror_d(x + 1, w)
            c = get(a, b, y, x)
            s1h = get(a, b, y, xm) + get(a, b, y, xp)
            s1v = get(a, b, ym, x) + get(a, b, yp, x)
            dg = get(a, b, ym, xm) + get(a, b, ym, xp) + get(a, b, yp, xm) + get(a, b, yp, xp)
            red_row = (y & 1) == ry
            is_rb = (x & 1) == (rx if red_row else 1 - rx)
            if method == 0:  # bilinear: demosaic_bilinear.bilinear_numba
                q = T(0.25)
                half = T(0.5)
                g = q * (s1h + s1v) if is_rb else c
                own = c if is_rb else half * s1h
                oth = q * dg if is_rb else half * s1v
            else:  # Malvar-He-Cutler: demosaic_malvar.malvar_numba
                s2h = get(a, b, y, mirror_d(x - 2, w)) + get(a, b, y, mirror_d(x + 2, w))
                s2v = get(a, b, mirror_d(y - 2, h), x) + get(a, b, mirror_d(y + 2, h), x)
                eighth = T(0.125)
                if is_rb:
                    g = (T(4.0) * c + T(2.0) * (s1h + s1v) - (s2h + s2v)) * eighth
                    own = c
                    oth = (T(6.0) * c + T(2.0) * dg - T(1.5) * (s2h + s2v)) * eighth
                else:
                    base = T(5.0) * c - dg
                    g = c
                    own = (base + T(4.0) * s1h - s2h + T(0.5) * s2v) * eighth
                    oth = (base + T(4.0) * s1v - s2v + T(0.5) * s2h) * eighth
            if red_row:
                return own, g, oth
            return oth, g, own

        return cuda.jit(device=True)(rgb_at)

    def make_px(T: Any, malvar: bool, is_rb: bool, red_row: bool) -> Any:
        """Return a device function: ``(R, G, B)`` of one pixel of a known CFA position.

        The arguments are the samples around it (``c`` the pixel, ``w``/``e`` left/right,
        ``n``/``s`` above/below, then the diagonals; Malvar also 2 away); ``is_rb`` and
        ``red_row`` are compile-time constants (a closure), so each pixel of a quad runs its
        own filter only, without a branch. The sums and products are those of
        :func:`imageform._kernels.demosaic_bilinear._bilinear_tasks` and
        :func:`imageform._kernels.demosaic_malvar._malvar_tasks`, in the same order.
        """
        if malvar:

            def px(c, w, e, n, s, ww, ee, nn, ss, nw, ne, sw, se):  # type: ignore[no-untyped-def]
                s1h = w + e
                s1v = n + s
                s2h = ww + ee
                s2v = nn + ss
                dg = nw + ne + sw + se
                if is_rb:
                    g = (T(4.0) * c + T(2.0) * (s1h + s1v) - (s2h + s2v)) * T(0.125)
                    own = c
                    oth = (T(6.0) * c + T(2.0) * dg - T(1.5) * (s2h + s2v)) * T(0.125)
                else:
                    base = T(5.0) * c - dg
                    g = c
                    own = (base + T(4.0) * s1h - s2h + T(0.5) * s2v) * T(0.125)
                    oth = (base + T(4.0) * s1v - s2v + T(0.5) * s2h) * T(0.125)
                if red_row:
                    return own, g, oth
                return oth, g, own

        else:

            def px(c, w, e, n, s, nw, ne, sw, se):  # type: ignore[no-untyped-def]
                if is_rb:
                    g = T(0.25) * ((w + e) + (n + s))
                    own = c
                    oth = T(0.25) * (nw + ne + sw + se)
                else:
                    g = c
                    own = T(0.5) * (w + e)
                    oth = T(0.5) * (n + s)
                if red_row:
                    return own, g, oth
                return oth, g, own

        return cuda.jit(device=True)(px)

    def make_quad(T: Any, malvar: bool, ry: int, rx: int) -> Any:
        """Return a device function: the 12 outputs of a 2x2 quad from its window's samples.

        The quad's top-left pixel is at an even row and column; red at ``(ry, rx)`` (fixed at
        compile time) places R, Gr, Gb and B in it. Window sample ``vRC`` is at row ``R - 2``,
        column ``C - 2`` from the top-left pixel: rows and columns -1..2 (bilinear, 16
        samples) or -2..3 less the corners no filter reads (Malvar, 24 samples).
        """
        kinds = []
        for dy in (0, 1):
            for dx in (0, 1):
                red_row = dy == ry
                kinds.append(make_px(T, malvar, dx == (rx if red_row else 1 - rx), red_row))
        p00, p01, p10, p11 = kinds
        if malvar:

            def quad(v):  # type: ignore[no-untyped-def]
                (v02, v03, v11, v12, v13, v14, v20, v21, v22, v23, v24, v25) = v[:12]
                (v30, v31, v32, v33, v34, v35, v41, v42, v43, v44, v52, v53) = v[12:]
                r0, g0, b0 = p00(v22, v21, v23, v12, v32, v20, v24, v02, v42, v11, v13, v31, v33)
                r1, g1, b1 = p01(v23, v22, v24, v13, v33, v21, v25, v03, v43, v12, v14, v32, v34)
                r2, g2, b2 = p10(v32, v31, v33, v22, v42, v30, v34, v12, v52, v21, v23, v41, v43)
                r3, g3, b3 = p11(v33, v32, v34, v23, v43, v31, v35, v13, v53, v22, v24, v42, v44)
                return r0, g0, b0, r1, g1, b1, r2, g2, b2, r3, g3, b3

        else:

            def quad(v):  # type: ignore[no-untyped-def]
                (v11, v12, v13, v14, v21, v22, v23, v24) = v[:8]
                (v31, v32, v33, v34, v41, v42, v43, v44) = v[8:]
                r0, g0, b0 = p00(v22, v21, v23, v12, v32, v11, v13, v31, v33)
                r1, g1, b1 = p01(v23, v22, v24, v13, v33, v12, v14, v32, v34)
                r2, g2, b2 = p10(v32, v31, v33, v22, v42, v21, v23, v41, v43)
                r3, g3, b3 = p11(v33, v32, v34, v23, v43, v22, v24, v42, v44)
                return r0, g0, b0, r1, g1, b1, r2, g2, b2, r3, g3, b3

        return cuda.jit(device=True)(quad)

    u = np.uint64  # unsigned indices: numba adds no negative-index wraparound to them

    # The quad's window, rows and columns -2..3 (Malvar: 24 samples, the corners no filter
    # reads left out) or -1..2 (bilinear: 16). Inside the mosaic the samples are at constant
    # offsets from the quad (one address per row); at an edge the indices are mirrored. The
    # edge variants load in another order, so that the compiler keeps the two apart (merged,
    # every load of the inner path would compute its own address).

    def window6_inner(raw, b, y, x):  # type: ignore[no-untyped-def]
        r = raw[u(b)]
        a = r[u(y - 2)]
        bb = r[u(y - 1)]
        c = r[u(y)]
        d = r[u(y + 1)]
        e = r[u(y + 2)]
        f = r[u(y + 3)]
        return (
            a[u(x)], a[u(x + 1)],
            bb[u(x - 1)], bb[u(x)], bb[u(x + 1)], bb[u(x + 2)],
            c[u(x - 2)], c[u(x - 1)], c[u(x)], c[u(x + 1)], c[u(x + 2)], c[u(x + 3)],
            d[u(x - 2)], d[u(x - 1)], d[u(x)], d[u(x + 1)], d[u(x + 2)], d[u(x + 3)],
            e[u(x - 1)], e[u(x)], e[u(x + 1)], e[u(x + 2)],
            f[u(x)], f[u(x + 1)],
        )  # fmt: skip

    def window6_edge(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
        r = raw[u(b)]
        f = r[u(mirror_d(y + 3, h))]
        e = r[u(mirror_d(y + 2, h))]
        d = r[u(mirror_d(y + 1, h))]
        c = r[u(y)]
        bb = r[u(mirror_d(y - 1, h))]
        a = r[u(mirror_d(y - 2, h))]
        x3 = u(mirror_d(x + 3, w))
        x2 = u(mirror_d(x + 2, w))
        x1 = u(mirror_d(x + 1, w))
        x0 = u(x)
        xm = u(mirror_d(x - 1, w))
        xmm = u(mirror_d(x - 2, w))
        f1, f0 = f[x1], f[x0]
        e3, e2, e1, e0 = e[x2], e[x1], e[x0], e[xm]
        d5, d4, d3, d2, d1, d0 = d[x3], d[x2], d[x1], d[x0], d[xm], d[xmm]
        c5, c4, c3, c2, c1, c0 = c[x3], c[x2], c[x1], c[x0], c[xm], c[xmm]
        b3, b2, b1, b0 = bb[x2], bb[x1], bb[x0], bb[xm]
        a1, a0 = a[x1], a[x0]
        return (
            a0, a1, b0, b1, b2, b3, c0, c1, c2, c3, c4, c5,
            d0, d1, d2, d3, d4, d5, e0, e1, e2, e3, f0, f1,
        )  # fmt: skip

    def window4_inner(raw, b, y, x):  # type: ignore[no-untyped-def]
        r = raw[u(b)]
        a = r[u(y - 1)]
        bb = r[u(y)]
        c = r[u(y + 1)]
        d = r[u(y + 2)]
        return (
            a[u(x - 1)], a[u(x)], a[u(x + 1)], a[u(x + 2)],
            bb[u(x - 1)], bb[u(x)], bb[u(x + 1)], bb[u(x + 2)],
            c[u(x - 1)], c[u(x)], c[u(x + 1)], c[u(x + 2)],
            d[u(x - 1)], d[u(x)], d[u(x + 1)], d[u(x + 2)],
        )  # fmt: skip

    def window4_edge(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
        r = raw[u(b)]
        d = r[u(mirror_d(y + 2, h))]
        c = r[u(mirror_d(y + 1, h))]
        bb = r[u(y)]
        a = r[u(mirror_d(y - 1, h))]
        x2 = u(mirror_d(x + 2, w))
        x1 = u(mirror_d(x + 1, w))
        x0 = u(x)
        xm = u(mirror_d(x - 1, w))
        d3, d2, d1, d0 = d[x2], d[x1], d[x0], d[xm]
        c3, c2, c1, c0 = c[x2], c[x1], c[x0], c[xm]
        b3, b2, b1, b0 = bb[x2], bb[x1], bb[x0], bb[xm]
        a3, a2, a1, a0 = a[x2], a[x1], a[x0], a[xm]
        return (a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3)

    win6_in_d = cuda.jit(device=True)(window6_inner)
    win6_edge_d = cuda.jit(device=True)(window6_edge)
    win4_in_d = cuda.jit(device=True)(window4_inner)
    win4_edge_d = cuda.jit(device=True)(window4_edge)

    from imageform._cuda._launch import ROW_BLOCK, _SIM_ROW_BLOCK, simulated

    # the block shape of launch_rows (a compile-time constant here: the staging tile's
    # offsets become immediates); on a device a block row is one warp (32 threads), whose
    # threads stage and store their own two output rows, so a warp barrier orders them; the
    # simulator has no warps (a block barrier)
    bw, bh = _SIM_ROW_BLOCK if simulated() else ROW_BLOCK
    warp_rows = bw == 32 and not simulated()

    def barrier_warp():  # type: ignore[no-untyped-def]
        cuda.syncwarp()

    def barrier_block():  # type: ignore[no-untyped-def]
        cuda.syncthreads()

    barrier_d = cuda.jit(device=True)(barrier_warp if warp_rows else barrier_block)

    def stage(tile, i, o, clip, zero, one):  # type: ignore[no-untyped-def]
        # the quad's 12 values into the tile: its top row's 6 at i, its bottom row's a tile
        # row (6 bw values) further
        o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11 = o
        if clip:
            o0, o1, o2 = clip_d(o0, zero, one), clip_d(o1, zero, one), clip_d(o2, zero, one)
            o3, o4, o5 = clip_d(o3, zero, one), clip_d(o4, zero, one), clip_d(o5, zero, one)
            o6, o7, o8 = clip_d(o6, zero, one), clip_d(o7, zero, one), clip_d(o8, zero, one)
            o9, o10 = clip_d(o9, zero, one), clip_d(o10, zero, one)
            o11 = clip_d(o11, zero, one)
        tile[u(i)] = o0
        tile[u(i + 1)] = o1
        tile[u(i + 2)] = o2
        tile[u(i + 3)] = o3
        tile[u(i + 4)] = o4
        tile[u(i + 5)] = o5
        tile[u(i + 6 * bw)] = o6
        tile[u(i + 6 * bw + 1)] = o7
        tile[u(i + 6 * bw + 2)] = o8
        tile[u(i + 6 * bw + 3)] = o9
        tile[u(i + 6 * bw + 4)] = o10
        tile[u(i + 6 * bw + 5)] = o11

    stage_d = cuda.jit(device=True)(stage)

    def make_demosaic(T: Any, malvar: bool) -> Any:
        """The demosaicing kernel of a dtype and method: one thread per 2x2 quad.

        A 2-D launch over quad rows and columns (:func:`~imageform._cuda._launch.launch_rows`
        blocks, a warp along a row). Each thread loads its quad's window once (constant
        offsets inside the mosaic; mirrored indices only in the blocks that touch an edge, a
        branch uniform over the block), evaluates the four pixels' filters for the pattern (a
        branch uniform over the launch, none per pixel) and writes its 12 values into a
        shared-memory tile; each row of threads then stores its two output rows as
        consecutive values, one coalesced store per 32 values.
        """
        r = 2 if malvar else 1
        win_in_d = win6_in_d if malvar else win4_in_d
        win_edge_d = win6_edge_d if malvar else win4_edge_d
        q00, q01, q10, q11 = (make_quad(T, malvar, ry, rx) for ry in (0, 1) for rx in (0, 1))
        n_tile = 12 * bw * bh

        def demosaic_kernel(raw, ry, rx, clip, out):  # type: ignore[no-untyped-def]
            # raw (B, H, W); out (B, H, 3 W): the (B, H, W, 3) result, a row of values a row
            nb, h, w = raw.shape
            tile = cuda.shared.array(n_tile, T)
            tx = cuda.threadIdx.x
            ty = cuda.threadIdx.y
            qx0 = cuda.blockIdx.x * bw  # the block's first quad column
            x = 2 * (qx0 + tx)
            inner_x = qx0 >= 1 and 2 * (qx0 + bw) + r - 1 < w
            n_vals = 3 * w - 6 * qx0  # values of an output row from the block's first one
            mine = ty * (12 * bw) + 6 * tx  # this thread's values in the tile
            zero = T(0.0)
            one = T(1.0)
            qy0 = cuda.blockIdx.y * bh
            while qy0 < (h + 1) >> 1:  # the same trips for the whole block (its barriers)
                y = 2 * (qy0 + ty)
                inner = inner_x and qy0 >= 1 and 2 * (qy0 + bh) + r - 1 < h
                active = x < w and y < h
                for b in range(nb):
                    if active:
                        if inner:
                            v = win_in_d(raw, b, y, x)
                        else:
                            v = win_edge_d(raw, b, y, x, h, w)
                        if ry == 0:
                            o = q00(v) if rx == 0 else q01(v)
                        else:
                            o = q10(v) if rx == 0 else q11(v)
                        stage_d(tile, mine, o, clip, zero, one)
                    barrier_d()
                    for dy in range(2):
                        if y + dy < h:
                            row = out[u(b), u(y + dy)]
                            src = (2 * ty + dy) * (6 * bw) + tx
                            dst = 6 * qx0 + tx
                            for k in range(6):
                                if k * bw + tx < n_vals:
                                    row[u(dst + k * bw)] = tile[u(src + k * bw)]
                    barrier_d()
                qy0 += cuda.gridDim.y * bh

        return demosaic_kernel

    def balanced(mosaic, prm, y, x):  # type: ignore[no-untyped-def]
        # clip((DN - B_s) k_s, 0, 1) of the photosite (y, x): raw_develop._balance_row
        p = y & 1
        q = x & 1
        v = (np.float32(mosaic[y, x]) - prm[p, q]) * prm[2 + p, q]
        return clip_d(v, np.float32(0.0), np.float32(1.0))

    rgb_balanced_d = make_rgb_at(cuda.jit(device=True)(balanced), np.float32)

    def develop_pixel(mosaic, prm, y, x, ry, rx, method, m, lut, encode, mode, out_f, out_u):  # type: ignore[no-untyped-def]
        h, w = mosaic.shape
        f = np.float32
        r, g, b = rgb_balanced_d(mosaic, prm, y, x, h, w, ry, rx, method)
        if mode == 0:
            out_f[y, x, 0] = r
            out_f[y, x, 1] = g
            out_f[y, x, 2] = b
            return
        zero = f(0.0)
        one = f(1.0)
        v0 = clip_d(m[0, 0] * r + m[0, 1] * g + m[0, 2] * b, zero, one)
        v1 = clip_d(m[1, 0] * r + m[1, 1] * g + m[1, 2] * b, zero, one)
        v2 = clip_d(m[2, 0] * r + m[2, 1] * g + m[2, 2] * b, zero, one)
        if encode:
            nm1 = lut.shape[0] - 2
            fn = f(lut.shape[0] - 1)
            s = math.sqrt(v0) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v0 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
            s = math.sqrt(v1) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v1 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
            s = math.sqrt(v2) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v2 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
        if mode == 1:
            out_f[y, x, 0] = v0
            out_f[y, x, 1] = v1
            out_f[y, x, 2] = v2
        else:
            top = f(65535.0)
            half = f(0.5)
            out_u[y, x, 0] = int(v0 * top + half)
            out_u[y, x, 1] = int(v1 * top + half)
            out_u[y, x, 2] = int(v2 * top + half)

    develop_pixel_d = cuda.jit(device=True)(develop_pixel)

    def develop_kernel(mosaic, prm, ry, rx, method, m, lut, encode, mode, out_f, out_u):  # type: ignore[no-untyped-def]
        # prm (4, 2) float32: rows 0-1 the black level, rows 2-3 the scale of the 2x2 tile;
        # a 2-D launch (launch_rows): thread (row y, column x)
        x, y, step = row_grid_d()
        if x >= mosaic.shape[1]:
            return
        while y < mosaic.shape[0]:
            develop_pixel_d(mosaic, prm, y, x, ry, rx, method, m, lut, encode, mode, out_f, out_u)
            y += step

    k = types.SimpleNamespace()
    k.py = {
        "bilinear32": make_demosaic(np.float32, False),
        "bilinear64": make_demosaic(np.float64, False),
        "malvar32": make_demosaic(np.float32, True),
        "malvar64": make_demosaic(np.float64, True),
        "develop": develop_kernel,
    }
    for name, fn in k.py.items():
        setattr(k, name, cuda.jit(fn))
    return k


def demosaic(raw: Any, ry: int, rx: int, method: str, clip: bool) -> Any | None:
    """Demosaic a float device mosaic ``(B, H, W)`` (red at ``(ry, rx)``) into ``(B, H, W, 3)``.

    ``method``: ``"bilinear"`` or ``"malvar"``; ``clip``: clip to [0, 1] in the same pass.
    One kernel launch; ``None`` when the kernels turned out unusable (the caller's Array-API
    path runs).
    """
    nb, h, w = (int(s) for s in raw.shape)
    out = empty_like(raw, (nb, h, w, 3))
    args = (raw, int(ry), int(rx), bool(clip), out.reshape((nb, h, 3 * w)))
    bits = 32 if str(raw.dtype).endswith("float32") else 64
    kern = getattr(_kernels(), f"{method}{bits}")
    # a thread per 2x2 quad: (H + 1) // 2 rows of (W + 1) // 2
    if not guarded(("demosaic", method, bits), kern, ((h + 1) // 2, (w + 1) // 2), *args):
        return None
    return out


def develop_bayer(
    mosaic: np.ndarray,
    black: np.ndarray,
    scale: np.ndarray,
    ry: int,
    rx: int,
    method: str,
    m: np.ndarray,
    lut: np.ndarray | None,
    mode: int,
) -> np.ndarray:
    """Develop a uint16 Bayer mosaic on the GPU; the NumPy result of ``mode``.

    The arguments of :func:`imageform._kernels.raw_develop.develop_rows` (``black`` and
    ``scale`` per photosite of the 2x2 tile, ``m`` camera RGB to the output's linear RGB,
    ``lut`` the transfer table or ``None`` for linear output), plus the demosaicing
    ``method`` (bilinear or malvar). The mosaic is copied to the device, developed in one
    launch (:func:`develop_on_device`), and the result copied back.
    """
    cuda = import_cuda()
    h, w = mosaic.shape
    prm = develop_parameters(black, scale)
    table = np.zeros(2, np.float32) if lut is None else np.asarray(lut, np.float32)
    out = cuda.device_array((h, w, 3), np.uint16 if mode == MODE_UINT16 else np.float32)
    develop_on_device(
        cuda.to_device(np.ascontiguousarray(mosaic, dtype=np.uint16)),
        cuda.to_device(prm),
        ry,
        rx,
        method,
        cuda.to_device(np.ascontiguousarray(m, dtype=np.float32)),
        cuda.to_device(table),
        lut is not None,
        mode,
        out,
    )
    return np.asarray(out.copy_to_host())


def develop_parameters(black: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Return the ``(4, 2)`` float32 parameters of the kernel: black levels above the scales."""
    return np.ascontiguousarray(
        np.concatenate([np.asarray(black, np.float32), np.asarray(scale, np.float32)])
    )


def develop_on_device(
    mosaic: Any,
    prm: Any,
    ry: int,
    rx: int,
    method: str,
    m: Any,
    lut: Any,
    encode: bool,
    mode: int,
    out: Any,
) -> Any:
    """Launch the development kernel on arrays already on the device (one launch, no copy).

    ``mosaic`` ``(H, W)`` uint16, ``prm`` from :func:`develop_parameters`, ``m`` ``(3, 3)``
    and ``lut`` float32, all device arrays of any library; ``out`` ``(H, W, 3)``: float32
    (camera RGB or the float output) or uint16 (``MODE_UINT16``). Returns ``out``.
    """
    cuda = import_cuda()
    h, w = (int(s) for s in mosaic.shape)
    none_f = cuda.device_array((0, 0, 3), np.float32)
    none_u = cuda.device_array((0, 0, 3), np.uint16)
    out_f, out_u = (none_f, out) if mode == MODE_UINT16 else (out, none_u)
    args = (mosaic, prm, int(ry), int(rx), _METHODS[method], m, lut, bool(encode), int(mode))
    if not guarded(("develop", mode), _kernels().develop, (h, w), *args, out_f, out_u):
        from imageform.errors import InvalidInputError

        raise InvalidInputError(
            "device='cuda': numba's CUDA target cannot compile the kernel here "
            f"({_launch.status()}); use the CPU"
        )
    return out
