r"""CUDA kernels of bilinear and Malvar-He-Cutler demosaicing: one thread per 2x2 CFA quad.

:func:`imageform._cuda.demosaic.demosaic` launches them. Per dtype (float32, float64) and
method, one kernel over a 2-D grid of quads (:func:`imageform._cuda._launch.launch_rows`:
blocks of 32 x 8 quads, a warp along a row). Each thread:

- loads its quad's window once into registers: rows and columns -1..2 of the quad's top-left
  pixel for bilinear (16 samples), -2..3 less the corners no filter reads for Malvar (24);
  in a block whose windows all lie inside the mosaic at constant offsets from one address
  per row (no index arithmetic per sample, no bounds test); in the blocks along an edge
  (a branch uniform over the block) with the indices mirrored about the edge pixel (index
  ``-k`` reads ``k``, ``n - 1 + k`` reads ``n - 1 - k``: :func:`numpy.pad`'s ``"reflect"``,
  which :func:`imageform.sensor.demosaic` pads with on the CPU);
- evaluates the four pixels' filters: the quad's top-left pixel is at an even row and column,
  so the red site's position ``(ry, rx)`` fixes which filter each pixel runs. The four
  arrangements are four compiled bodies behind a branch uniform over the launch: no branch
  per pixel, no warp divergence on the colour position. The sums are those of
  :mod:`imageform._kernels.demosaic_bilinear` and :mod:`imageform._kernels.demosaic_malvar`
  (the same additions in the same order, float32 arithmetic for float32 data);
- writes its 12 values (clipped to [0, 1] when asked) into a shared-memory tile; after a
  warp barrier each row of threads stores its two output rows as consecutive values, 32
  consecutive values per store instruction (the (H, W, 3) output's row is 3 W values: a
  thread per pixel storing R, G, B touched three times the cache sectors it filled).

The one-thread-per-pixel kernel these replace (issue 29) branched on the CFA position in
every pixel (a warp alternates even and odd columns), read 9 (13) samples per pixel with a
mirror and 64-bit index arithmetic per sample, and stored 3 strided values per pixel; on an
H200 it reached 27-30 % of the copy bandwidth at 4K float32 (``benchmarks/sass_demosaic.py``
counts the machine code of both without a GPU).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from imageform._cuda import _launch
from imageform._cuda.geometry import import_cuda

__all__ = ["kernels"]

#: ``numba.cuda`` (a module global: numba's simulator swaps the global named ``cuda``).
cuda: Any = None


def _px(T: Any, malvar: bool, is_rb: bool, red_row: bool) -> Any:
    """Return a device function: ``(R, G, B)`` of one pixel whose CFA position is known.

    The arguments are the samples around it: ``c`` the pixel, ``w``/``e`` left/right,
    ``n``/``s`` above/below, for Malvar ``ww``/``ee``/``nn``/``ss`` two away, then the
    diagonals. ``is_rb`` (a red or blue site) and ``red_row`` are compile-time constants of
    the closure: each pixel of a quad runs its own filter, without a branch. ``own`` is the
    colour of the pixel's row (red in a red row), ``oth`` the other one, as in the CPU kernels
    (:func:`imageform._kernels.demosaic_bilinear._bilinear_tasks`,
    :func:`imageform._kernels.demosaic_malvar._malvar_tasks`), whose sums these are.
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

        def px(c, w, e, n, s, nw, ne, sw, se):  # type: ignore[no-untyped-def,misc]
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


def _quad(T: Any, malvar: bool, ry: int, rx: int) -> Any:
    """Return a device function: the quad's 12 values (R, G, B of 4 pixels) from its window.

    The quad's top-left pixel is at an even row and column; red at ``(ry, rx)`` (fixed at
    compile time) places R, the two greens and B in it. Window sample ``vRC`` lies ``R - 2``
    rows and ``C - 2`` columns from the top-left pixel (the order of :func:`_windows`).
    """
    kinds = []
    for dy in (0, 1):
        for dx in (0, 1):
            red_row = dy == ry
            kinds.append(_px(T, malvar, dx == (rx if red_row else 1 - rx), red_row))
    p00, p01, p10, p11 = kinds
    if malvar:

        def quad(v):  # type: ignore[no-untyped-def]
            v02, v03, v11, v12, v13, v14, v20, v21, v22, v23, v24, v25 = v[:12]
            v30, v31, v32, v33, v34, v35, v41, v42, v43, v44, v52, v53 = v[12:]
            r0, g0, b0 = p00(v22, v21, v23, v12, v32, v20, v24, v02, v42, v11, v13, v31, v33)
            r1, g1, b1 = p01(v23, v22, v24, v13, v33, v21, v25, v03, v43, v12, v14, v32, v34)
            r2, g2, b2 = p10(v32, v31, v33, v22, v42, v30, v34, v12, v52, v21, v23, v41, v43)
            r3, g3, b3 = p11(v33, v32, v34, v23, v43, v31, v35, v13, v53, v22, v24, v42, v44)
            return r0, g0, b0, r1, g1, b1, r2, g2, b2, r3, g3, b3

    else:

        def quad(v):  # type: ignore[no-untyped-def]
            v11, v12, v13, v14, v21, v22, v23, v24 = v[:8]
            v31, v32, v33, v34, v41, v42, v43, v44 = v[8:]
            r0, g0, b0 = p00(v22, v21, v23, v12, v32, v11, v13, v31, v33)
            r1, g1, b1 = p01(v23, v22, v24, v13, v33, v12, v14, v32, v34)
            r2, g2, b2 = p10(v32, v31, v33, v22, v42, v21, v23, v41, v43)
            r3, g3, b3 = p11(v33, v32, v34, v23, v43, v22, v24, v42, v44)
            return r0, g0, b0, r1, g1, b1, r2, g2, b2, r3, g3, b3

    return cuda.jit(device=True)(quad)


def _windows() -> Any:
    """Return the window loaders, ``(inner6, edge6, inner4, edge4)`` device functions.

    ``inner(raw, b, y, x)``: the window of the quad at ``(y, x)`` of image ``b``, all inside
    the mosaic (one address per row, the samples at constant offsets from it); ``edge(raw,
    b, y, x, h, w)``: the same with mirrored indices, in 32-bit arithmetic. Indices are cast
    to unsigned: numba adds no negative-index wraparound to those. The edge loaders load in
    another order than the inner ones, so that the compiler does not merge the two (merged,
    every load of the inner path computed its own address).
    """
    u = np.uint64
    i32 = np.int32

    def mirror(i, n):  # type: ignore[no-untyped-def]
        # i in [-3, n + 2], n >= 4: -k reads k, n - 1 + k reads n - 1 - k, as
        # n - 1 - |n - 1 - |i||; numba widens integer arithmetic to 64 bits, each result
        # cast back keeps it 32-bit
        return i32(n - i32(1) - abs(i32(n - i32(1) - abs(i))))

    m = cuda.jit(device=True)(mirror)

    def inner6(raw, b, y, x):  # type: ignore[no-untyped-def]
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

    def edge6(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
        y, x, h, w = i32(y), i32(x), i32(h), i32(w)
        r = raw[u(b)]
        f = r[u(m(i32(y + i32(3)), h))]
        e = r[u(m(i32(y + i32(2)), h))]
        d = r[u(m(i32(y + i32(1)), h))]
        c = r[u(y)]
        bb = r[u(m(i32(y - i32(1)), h))]
        a = r[u(m(i32(y - i32(2)), h))]
        x3 = u(m(i32(x + i32(3)), w))
        x2 = u(m(i32(x + i32(2)), w))
        x1 = u(m(i32(x + i32(1)), w))
        x0 = u(x)
        xm = u(m(i32(x - i32(1)), w))
        xmm = u(m(i32(x - i32(2)), w))
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

    def inner4(raw, b, y, x):  # type: ignore[no-untyped-def]
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

    def edge4(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
        y, x, h, w = i32(y), i32(x), i32(h), i32(w)
        r = raw[u(b)]
        d = r[u(m(i32(y + i32(2)), h))]
        c = r[u(m(i32(y + i32(1)), h))]
        bb = r[u(y)]
        a = r[u(m(i32(y - i32(1)), h))]
        x2 = u(m(i32(x + i32(2)), w))
        x1 = u(m(i32(x + i32(1)), w))
        x0 = u(x)
        xm = u(m(i32(x - i32(1)), w))
        d3, d2, d1, d0 = d[x2], d[x1], d[x0], d[xm]
        c3, c2, c1, c0 = c[x2], c[x1], c[x0], c[xm]
        b3, b2, b1, b0 = bb[x2], bb[x1], bb[x0], bb[xm]
        a3, a2, a1, a0 = a[x2], a[x1], a[x0], a[xm]
        return (a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3)

    return tuple(cuda.jit(device=True)(f) for f in (inner6, edge6, inner4, edge4))


def block_shape() -> tuple[int, int]:
    """Return the block of :func:`~imageform._cuda._launch.launch_rows` (threads x, y).

    A compile-time constant of the kernels (the staging tile's size and offsets); the
    simulator runs smaller blocks (each simulated thread is a Python thread).
    """
    return _launch._SIM_ROW_BLOCK if _launch.simulated() else _launch.ROW_BLOCK


def _make(T: Any, malvar: bool, parts: Any) -> Any:
    """Return the kernel (a Python function for ``cuda.jit``) of a dtype and method."""
    bw, bh = block_shape()
    r = 2 if malvar else 1  # the filters' radius
    n_tile = 12 * bw * bh
    inner_d, edge_d = (parts.inner6, parts.edge6) if malvar else (parts.inner4, parts.edge4)
    q00, q01, q10, q11 = (_quad(T, malvar, ry, rx) for ry in (0, 1) for rx in (0, 1))
    stage_d, barrier_d = parts.stage, parts.barrier
    u = np.uint64

    def demosaic_kernel(raw, ry, rx, clip, out):  # type: ignore[no-untyped-def]
        # raw (B, H, W); out (B, H, 3 W): the (B, H, W, 3) result, its rows as value rows
        nb, h, w = raw.shape
        tile = cuda.shared.array(n_tile, T)
        tx = cuda.threadIdx.x
        ty = cuda.threadIdx.y
        qx0 = cuda.blockIdx.x * bw  # the block's first quad column
        x = 2 * (qx0 + tx)
        inner_x = qx0 >= 1 and 2 * (qx0 + bw) + r - 1 < w
        n_vals = 3 * w - 6 * qx0  # values of an output row from the block's first pixel on
        mine = ty * (12 * bw) + 6 * tx  # this thread's first value in the tile
        zero = T(0.0)
        one = T(1.0)
        qy0 = cuda.blockIdx.y * bh
        while qy0 < (h + 1) >> 1:  # the same trips for every thread of the block (barriers)
            y = 2 * (qy0 + ty)
            inner = inner_x and qy0 >= 1 and 2 * (qy0 + bh) + r - 1 < h
            active = x < w and y < h
            for b in range(nb):
                if active:
                    v = inner_d(raw, b, y, x) if inner else edge_d(raw, b, y, x, h, w)
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


def _parts() -> Any:
    """Return the device functions the kernels share: window loaders, staging, barrier."""
    import types

    def clip01(v, zero, one):  # type: ignore[no-untyped-def]
        # min(max(v, 0), 1) by comparisons (NaN stays NaN, as numpy.clip)
        return zero if v < zero else (one if v > one else v)

    clip_d = cuda.jit(device=True)(clip01)
    bw, _ = block_shape()
    u = np.uint64

    def stage(tile, i, o, clip, zero, one):  # type: ignore[no-untyped-def]
        # the quad's top row's 6 values at i, its bottom row's one tile row (6 bw) further
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

    # on a device a block row is one warp (32 threads), which stages and stores its own two
    # output rows: a warp barrier orders it; the simulator has no warps (a block barrier)
    def barrier_warp():  # type: ignore[no-untyped-def]
        cuda.syncwarp()

    def barrier_block():  # type: ignore[no-untyped-def]
        cuda.syncthreads()

    warp_rows = bw == 32 and not _launch.simulated()
    p = types.SimpleNamespace()
    p.inner6, p.edge6, p.inner4, p.edge4 = _windows()
    p.stage = cuda.jit(device=True)(stage)
    p.barrier = cuda.jit(device=True)(barrier_warp if warp_rows else barrier_block)
    return p


@functools.cache
def kernels() -> Any:
    """Return the kernels: ``bilinear32``, ``bilinear64``, ``malvar32``, ``malvar64``.

    numba CUDA dispatchers, compiled on first launch, with their Python functions in ``.py``
    (``kernel(raw, ry, rx, clip, out)``: ``raw`` ``(B, H, W)`` with H, W >= 4, red at
    ``(ry, rx)``, ``out`` the ``(B, H, W, 3)`` result viewed as ``(B, H, 3 W)``; launched on
    ``((H + 1) // 2, (W + 1) // 2)`` quads by ``launch_rows``).
    """
    import types

    global cuda
    cuda = import_cuda()
    parts = _parts()
    k = types.SimpleNamespace()
    k.py = {
        f"{name}{bits}": _make(T, name == "malvar", parts)
        for name in ("bilinear", "malvar")
        for bits, T in ((32, np.float32), (64, np.float64))
    }
    for name, fn in k.py.items():
        setattr(k, name, cuda.jit(fn))
    return k
