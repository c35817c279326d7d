"""Numba kernels: bilinear remapping of a batch of channels-last images.

``remap_bilinear``: ``out[b, i, j, c] = scale * bilinear(img[b, :, :, c])`` at the source
position ``(u, v) = (map_uv[i, j, 0], map_uv[i, j, 1])`` (column, row; the centre of the
top-left pixel is ``(0, 0)``). Positions outside ``[0, W-1] × [0, H-1]`` or NaN get ``fill``
(not scaled). ``scale`` is ``1/255`` (``1/65535``) when ``img`` is uint8 (uint16) and the output
float, so an 8-bit image is sampled directly, without a float copy of it; ``1`` for float
images. When ``out`` has the image's integer dtype (``keep_dtype``), the interpolated code
value is rounded to the nearest integer (ties to even, as OpenCV's ``cvRound``) and ``scale``
is not used. ``undistort_brown_conrady`` fuses the source-position computation of
:func:`imageform.geometry.undistort.undistortion_map` for Brown-Conrady with the sampling (no
``(H, W, 2)`` map is allocated).

Arithmetic: the source position and its integer part in the map's precision (float32 for a
float32 map, float64 for a float64 map or the fused model, so ``u - floor(u)`` is exact);
the weights and the interpolation in float64 when ``out`` is float64, else in float32 (uint8,
uint16 and float32 images: relative error below 1e-7 of the value, far inside the 1e-3 the
issue asks for).

Both run in parallel over blocks of output rows and process each row in blocks of
:data:`_BLK` pixels, in two loops:

1. *locate* (vectorised by LLVM: no gathers, no branches): for every output pixel, the flat
   index of its top-left source sample ``k``, the weights ``ax, ay`` and whether it is
   inside, into L1-resident buffers. The left column is ``x0 = min(floor(u), W-2)``
   (``ax = u - x0`` is then 1 at ``u = W-1``), so the right and lower neighbours are always
   at the constant offsets ``nc`` and ``W * nc``: no per-pixel clamping;
2. *sample* (scalar: the four loads per sample are gathers, which LLVM does not vectorise
   on x86): the lerps ``top = I00 + ax (I01 - I00)``, ``bot = I10 + ax (I11 - I10)``,
   ``top + ay (bot - top)`` with fused multiply-adds (OpenCV 5's formula: the uint8 result
   equals ``cv2.remap``'s bit for bit), then ``fill`` where outside, the scale or the
   rounding as selects; uint8 samples become floats through a 256-entry table (a load, not
   a conversion). This loop is a function of its own (not inlined into the locate loops,
   whose registers it would share: 3-channel uint8 1.3 times faster). Indices are unsigned
   (no negative-index wrap-around code) and the channel loop is unrolled.

Every array is indexed through flat 1-D views: numba computes a C array's multi-dimensional
index from its runtime shape, which LLVM then versions on (falling back to scalar code);
1-D indices keep the locate loop vectorised (4 to 8 times faster on a 1 MP map). The
sampling loop has one version for each of 1, 3 and 4 channels (unrolled), one generic.

One-channel images take a third way (``_remap_grey_tasks``, a kernel of its own, so that a
one-channel remap compiles none of the general loops: 4.5 s of CPU less on a first ``imageform
simulate``, whose lateral colour remaps one channel at a time; and a colour remap compiles none of
this one; its loops written in it, on flat views made by the caller: no called kernel, no inlined
helper and no ``ravel`` to compile, and one copy of the block loop for rounded and float outputs:
0.6 s of CPU less, compile-simulate-2026-11-28.md): locate and sample fused in one loop that LLVM
vectorises with gathers. Two things make that possible: the results go to a buffer on the stack (an
intrinsic, ``_stack_block``), which LLVM knows aliases no input, so the gathers may run ahead of
the stores; and a uint8 pair ``I00, I01`` comes from one unaligned 32-bit load (``_word``; the
lower pair's word is read two bytes early and shifted, so that no load leaves the image). A second
loop rounds or converts the block into the output. The arithmetic is the general loops' (equal
results bit for bit); a 1 MP uint8 remap takes 1.5 ms instead of 2.7 ms on one thread of the
development machine.

The plain twin of both is :func:`imageform.geometry.undistort._remap_bilinear_numpy` on the
map from :func:`~imageform.geometry.undistort.undistortion_map`; tests check agreement to
1e-12 (float64).
"""

from __future__ import annotations

import functools
import sys
from typing import Any

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from imageform._kernels.jit import njit, parallel_pays, run_tasks

__all__ = [
    "PARALLEL_MIN_SAMPLES",
    "pick",
    "remap_bilinear",
    "remap_bilinear_serial",
    "undistort_brown_conrady",
    "undistort_brown_conrady_serial",
]

#: Row blocks per image (the parallel work items); each allocates its buffers once.
_BLOCKS = 64
#: Output pixels per inner block (buffers of this many pixels stay in L1).
_BLK = 256

# every kernel: error_model="numpy" (no ZeroDivisionError checks), fastmath
# {"contract"} (fused multiply-adds only; NaN/inf semantics kept)


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _locate(
    u: float,
    v: float,
    zero: float,
    wm1: float,
    hm1: float,
    xmax: int,
    ymax: int,
    row: int,
    nc: int,
    t: int,
    kidx: np.ndarray,
    ax: np.ndarray,
    ay: np.ndarray,
    ok: np.ndarray,
) -> None:
    """Branch-free: where output pixel ``t`` of the block reads from (module docstring, 1).

    ``zero``, ``wm1``, ``hm1`` in the positions' float type; ``xmax``, ``ymax``, ``row`` in
    ``kidx``'s integer type (int32 when the image has fewer than 2**31 samples).
    """
    inside = (u >= zero) & (u <= wm1) & (v >= zero) & (v <= hm1)
    uc = u if inside else zero  # NaN and outside: a safe index, the pixel gets ``fill``
    vc = v if inside else zero
    K = kidx.dtype.type
    x0 = K(uc)  # uc >= 0: truncation is floor
    y0 = K(vc)
    x0 = x0 if x0 < xmax else xmax
    y0 = y0 if y0 < ymax else ymax
    M = type(zero)
    T = ax.dtype.type
    ax[t] = T(uc - M(x0))  # exact in the positions' type
    ay[t] = T(vc - M(y0))
    kidx[t] = y0 * row + x0 * K(nc)
    ok[t] = inside


def _value(flat: np.ndarray, k: np.uint64, lut: np.ndarray) -> float:  # pragma: no cover
    """Sample ``flat[k]`` as a float of ``lut``'s dtype (jitted code: :func:`_value_impl`)."""
    return lut.dtype.type(flat[k])


@overload(_value)
def _value_impl(flat: Any, k: Any, lut: Any) -> object:
    """Return ``_value``'s implementation for ``flat``'s dtype.

    uint8: ``lut[flat[k]]`` from the 256-entry table of the codes as floats (a load in place
    of an integer-to-float conversion, two micro-ops on the ports the lerps use: 3 channels
    sampled 1.3 times faster); other dtypes: converted (``lut`` gives the float type).

    Not ``inline="always"``: numba's IR inlining made the 1-channel loop twice as slow (2.9
    -> 6.5 ms per 1 MP remap); LLVM inlines the call anyway.
    """
    # the implementations' signatures must equal this one's, annotations included
    if flat.dtype == types.uint8:

        def table(flat: Any, k: Any, lut: Any) -> object:
            return lut[flat[k]]

        return table

    def convert(flat: Any, k: Any, lut: Any) -> object:
        return lut.dtype.type(flat[k])

    return convert


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _sample(
    flat: np.ndarray,
    k: np.uint64,
    udx: np.uint64,
    udy: np.uint64,
    a: float,
    b: float,
    inside: bool,
    sc: float,
    fl: float,
    rounded: bool,
    lut: np.ndarray,
) -> float:
    """Return one output sample (module docstring, 2).

    The lerps with fused multiply-adds, then ``fill`` where outside and the scale or the
    rounding, as selects.
    """
    T = type(a)
    i00 = _value(flat, k, lut)  # floats: uint8/uint16 differences must not wrap
    i10 = _value(flat, k + udy, lut)
    top = i00 + a * (_value(flat, k + udx, lut) - i00)
    bot = i10 + a * (_value(flat, k + udx + udy, lut) - i10)
    r = top + b * (bot - top)
    if rounded:
        # to the nearest integer, ties to even (as np.rint, without its call): adding and
        # subtracting 1.5 * 2**23 (float32; 1.5 * 2**52 in float64) rounds in the FPU's mode.
        # The value lies in [0, hi] up to rounding (a convex combination of codes) and
        # ``fill`` was checked to, so no clamping.
        magic = T(12582912.0) if T(16777217.0) == T(16777216.0) else T(6755399441055744.0)
        x = r if inside else fl
        return (x + magic) - magic
    return sc * r if inside else fl


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _sample_loop(
    flat: np.ndarray,
    n: int,
    nc: int,
    udx: np.uint64,
    udy: np.uint64,
    kidx: np.ndarray,
    ax: np.ndarray,
    ay: np.ndarray,
    ok: np.ndarray,
    sc: float,
    fl: float,
    rounded: bool,
    ob: np.ndarray,
    lut: np.ndarray,
) -> None:
    """Loop over the block's pixels (``nc`` and ``rounded`` constants where inlined)."""
    O = ob.dtype.type
    for t in range(n):
        k = np.uint64(kidx[t])
        a, b, inside = ax[t], ay[t], ok[t]
        for c in range(nc):
            v = _sample(flat, k + np.uint64(c), udx, udy, a, b, inside, sc, fl, rounded, lut)
            ob[nc * t + c] = O(v)


@njit(error_model="numpy", fastmath={"contract"})
def _sample_block(
    flat: np.ndarray,
    n: int,
    nc: int,
    dx: int,
    dy: int,
    kidx: np.ndarray,
    ax: np.ndarray,
    ay: np.ndarray,
    ok: np.ndarray,
    scale: float,
    fill: float,
    rounded: bool,
    hi: float,
    ob: np.ndarray,
    lut: np.ndarray,
) -> None:
    """Write the block's ``n`` pixels into the flat output block ``ob``.

    A function of its own (not inlined: its loops get the registers to themselves), with one
    loop per channel count 1, 3, 4 (unrolled over the channels) and rounding, one generic.
    """
    T = ax.dtype.type
    sc = T(scale)
    fl = T(fill)
    udx = np.uint64(dx)  # unsigned indices: no negative-index wrap-around code
    udy = np.uint64(dy)
    if rounded:
        if nc == 1:
            _sample_loop(flat, n, 1, udx, udy, kidx, ax, ay, ok, sc, fl, True, ob, lut)
        elif nc == 3:
            _sample_loop(flat, n, 3, udx, udy, kidx, ax, ay, ok, sc, fl, True, ob, lut)
        elif nc == 4:
            _sample_loop(flat, n, 4, udx, udy, kidx, ax, ay, ok, sc, fl, True, ob, lut)
        else:
            _sample_loop(flat, n, nc, udx, udy, kidx, ax, ay, ok, sc, fl, True, ob, lut)
    elif nc == 1:
        _sample_loop(flat, n, 1, udx, udy, kidx, ax, ay, ok, sc, fl, False, ob, lut)
    elif nc == 3:
        _sample_loop(flat, n, 3, udx, udy, kidx, ax, ay, ok, sc, fl, False, ob, lut)
    elif nc == 4:
        _sample_loop(flat, n, 4, udx, udy, kidx, ax, ay, ok, sc, fl, False, ob, lut)
    else:
        _sample_loop(flat, n, nc, udx, udy, kidx, ax, ay, ok, sc, fl, False, ob, lut)


@njit(error_model="numpy", fastmath={"contract"})
def _remap_rows(
    flat: np.ndarray,
    mf: np.ndarray,
    i0: int,
    i1: int,
    wo: int,
    h: int,
    w: int,
    nc: int,
    scale: float,
    fill: float,
    rounded: bool,
    hi: float,
    of: np.ndarray,
    bufs: tuple[np.ndarray, ...],
) -> None:
    """Output rows ``i0:i1`` of one image from the flat map ``mf`` (``nc`` may be a constant)."""
    kidx, ax, ay, ok = bufs
    lut = np.arange(256).astype(ax.dtype)  # the uint8 codes as floats (see _value_impl)
    M = mf.dtype.type
    K = kidx.dtype.type
    zero = M(0)
    wm1 = M(w - 1)
    hm1 = M(h - 1)
    xmax = K(max(w - 2, 0))
    ymax = K(max(h - 2, 0))
    row = K(w * nc)
    dx = nc if w > 1 else 0
    dy = row if h > 1 else 0
    for i in range(i0, i1):
        for j0 in range(0, wo, _BLK):
            n = min(_BLK, wo - j0)
            base = i * wo + j0
            mb = mf[2 * base : 2 * (base + n)]
            for t in range(n):
                _locate(
                    mb[2 * t],
                    mb[2 * t + 1],
                    zero,
                    wm1,
                    hm1,
                    xmax,
                    ymax,
                    row,
                    nc,
                    t,
                    kidx,
                    ax,
                    ay,
                    ok,
                )
            ob = of[base * nc : (base + n) * nc]
            _sample_block(flat, n, nc, dx, dy, kidx, ax, ay, ok, scale, fill, rounded, hi, ob, lut)


# --- one channel: a single vectorised loop --------------------------------------------------

#: The one-channel path reads two neighbouring uint8 samples with one unaligned 32-bit load
#: (little-endian byte order assumed; elsewhere the general loops run).
_LITTLE = sys.byteorder == "little"


def _stack_block_typing(typingctx: Any, like: Any) -> object:  # pragma: no cover - jitted
    """Return a C array of :data:`_BLK` elements of ``like``'s dtype on the caller's stack.

    LLVM knows that a stack buffer aliases none of the arrays passed in, so a loop that
    gathers from the image and stores into it vectorises (a store into a heap array may alias
    the gathered image: LLVM cannot check that at run time and keeps the loop scalar).
    """
    dtype = like.dtype
    arrty = types.Array(dtype, 1, "C")

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        lty = context.get_data_type(dtype)
        ptr = cgutils.alloca_once(builder, lty, size=_BLK)
        ary = context.make_array(arrty)(context, builder)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(lty))
        context.populate_array(
            ary,
            data=ptr,
            shape=[context.get_constant(types.intp, _BLK)],
            strides=[itemsize],
            itemsize=itemsize,
            meminfo=None,
        )
        return ary._getvalue()

    return arrty(like), codegen


#: ``_stack_block(like)`` in jitted code (see :func:`_stack_block_typing`).
_stack_block: Any = intrinsic(_stack_block_typing)


def _word_typing(typingctx: Any, flat: Any, k: Any) -> object:  # pragma: no cover - jitted
    """Return the 32-bit word that starts at element ``k`` of the 1-D array ``flat`` (unaligned).

    The caller keeps the four bytes inside ``flat``.
    """

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        ptr = builder.gep(ary.data, [args[1]], inbounds=True)
        return builder.load(builder.bitcast(ptr, ir.IntType(32).as_pointer()), align=1)

    return types.uint32(flat, k), codegen


#: ``_word(flat, k)`` in jitted code (see :func:`_word_typing`).
_word: Any = intrinsic(_word_typing)


def _pair(flat: np.ndarray, k: Any, zero: float, lower: bool) -> tuple[float, float]:
    """``flat[k], flat[k + 1]`` as floats of ``zero``'s type (jitted code: :func:`_pair_impl`)."""
    T = type(zero)
    return T(flat[k]), T(flat[k + 1])  # pragma: no cover


@overload(_pair)
def _pair_impl(flat: Any, k: Any, zero: Any, lower: Any) -> object:
    """Return ``_pair``'s implementation for ``flat``'s dtype.

    uint8: one unaligned 32-bit load (a gather when vectorised) holds both samples. The upper
    pair's word is read at ``k`` (it ends at ``k + 3 <= (h - 2) w + w + 1 < h w``); the lower
    pair's (``lower``, a constant) two bytes earlier and shifted, so that it ends at ``k + 1``
    (``k - 2 >= w - 2 >= 0``): no load leaves the image, and no per-pixel test is needed.
    uint16: one 32-bit load, always inside (``k + 1`` is). Floats: two loads.
    """
    if flat.dtype == types.uint8:

        def bytes2(flat: Any, k: Any, zero: Any, lower: Any) -> object:
            T = type(zero)
            # lower: the word ending at k + 1 (see above), its upper half
            word = _word(flat, k - 2) >> np.uint32(16) if lower else _word(flat, k)
            return T(word & np.uint32(255)), T((word >> np.uint32(8)) & np.uint32(255))

        return bytes2
    if flat.dtype == types.uint16:

        def halves(flat: Any, k: Any, zero: Any, lower: Any) -> object:
            T = type(zero)
            word = _word(flat, k)
            return T(word & np.uint32(65535)), T(word >> np.uint32(16))

        return halves

    def floats(flat: Any, k: Any, zero: Any, lower: Any) -> object:
        T = type(zero)
        return T(flat[k]), T(flat[k + 1])

    return floats


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _block_buffers(kcar: np.ndarray, acc: np.ndarray) -> tuple[np.ndarray, ...]:
    """Return one thread's locate buffers (module docstring, 1): ``kidx, ax, ay, ok``."""
    kidx = np.empty(_BLK, kcar.dtype)
    ax = np.empty(_BLK, acc.dtype)
    ay = np.empty(_BLK, acc.dtype)
    ok = np.empty(_BLK, np.bool_)
    return (kidx, ax, ay, ok)


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _task_rows(t: int, nblk: int, ho: int) -> tuple[int, int, int]:
    """Task ``t`` of a batch remap: image ``t // nblk``, its row block ``t % nblk``.

    Returns the image's index and the block's output rows ``i0:i1`` (of ``ho``).
    """
    b = t // nblk
    blk = t - b * nblk
    return b, blk * ho // nblk, (blk + 1) * ho // nblk


@njit(nogil=True, error_model="numpy", fastmath={"contract"})
def _remap_tasks(
    t0: int,
    t1: int,
    img: np.ndarray,
    map_uv: np.ndarray,
    scale: float,
    fill: float,
    out: np.ndarray,
    acc: np.ndarray,
    kcar: np.ndarray,
    hi: float,
    nblk: int,
) -> None:  # pragma: no cover
    # tasks t0 .. t1 - 1 of remap_bilinear: image t // nblk, row block t % nblk
    _, h, w, nc = img.shape
    ho, wo = map_uv.shape[0], map_uv.shape[1]
    mf = map_uv.ravel()
    rounded = hi > 0.0
    bufs = _block_buffers(kcar, acc)
    for t in range(t0, t1):
        b, i0, i1 = _task_rows(t, nblk, ho)
        of = out[b].ravel()
        _remap_rows(img[b].ravel(), mf, i0, i1, wo, h, w, nc, scale, fill, rounded, hi, of, bufs)


@njit(nogil=True, error_model="numpy", fastmath={"contract"})
def _remap_grey_tasks(
    t0: int,
    t1: int,
    img: np.ndarray,
    mf: np.ndarray,
    h: int,
    w: int,
    ho: int,
    wo: int,
    scale: float,
    fill: float,
    out: np.ndarray,
    acc: np.ndarray,
    hi: float,
    nblk: int,
) -> None:  # pragma: no cover
    # tasks t0 .. t1 - 1 of a one-channel remap_bilinear (h, w >= 2): a kernel of its own, so
    # that a grey remap (the simulator's lateral colour) compiles none of the general loops.
    # img (B, h w), out (B, ho wo) and mf (ho wo 2): flat views made by the caller (no ravel
    # to compile). The rows' loop is written here, not in a kernel of its own: a called
    # kernel is compiled on its own and then optimised again inside its caller.
    # The same arithmetic as _remap_rows (equal results bit for bit). No inline="always"
    # helpers either: numba's IR inlining costs compile time of its own.
    res: np.ndarray = _stack_block(acc)
    T = acc.dtype.type
    O = out.dtype.type
    M = mf.dtype.type
    rounded = hi > 0.0
    sc = T(1.0) if rounded else T(scale)  # rounded: codes, not scaled
    fl = T(fill)
    magic = T(12582912.0) if T(16777217.0) == T(16777216.0) else T(6755399441055744.0)
    zero = M(0)
    wm1 = M(w - 1)
    hm1 = M(h - 1)
    xmax = np.int32(w - 2)
    ymax = np.int32(h - 2)
    tz = T(0)
    for t in range(t0, t1):
        b = t // nblk  # image b, its row block blk: output rows i0:i1 (as _task_rows)
        blk = t - b * nblk
        i0 = blk * ho // nblk
        i1 = (blk + 1) * ho // nblk
        flat = img[b]
        of = out[b]
        for i in range(i0, i1):
            for j0 in range(0, wo, _BLK):
                n = wo - j0 if wo - j0 < _BLK else _BLK  # no min() overload to compile
                base = i * wo + j0
                mb = mf[2 * base : 2 * (base + n)]
                ob = of[base : base + n]
                # one block: locate (as _locate) and sample (as _sample) fused in one loop
                # that LLVM vectorises with gathers; res gets sc * the result (sc = 1 when
                # rounded: 1 * r is r bit for bit, and this loop is compiled once) or fill
                for k in range(n):
                    u = mb[2 * k]
                    v = mb[2 * k + 1]
                    inside = (u >= zero) & (u <= wm1) & (v >= zero) & (v <= hm1)
                    uc = u if inside else zero
                    vc = v if inside else zero
                    x0 = np.int32(uc)  # uc >= 0: truncation is floor
                    y0 = np.int32(vc)
                    x0 = x0 if x0 < xmax else xmax
                    y0 = y0 if y0 < ymax else ymax
                    ax = T(uc - M(x0))
                    ay = T(vc - M(y0))
                    q = np.int64(y0) * w + x0
                    i00, i01 = _pair(flat, q, tz, False)
                    i10, i11 = _pair(flat, q + w, tz, True)
                    top = i00 + ax * (i01 - i00)
                    bot = i10 + ax * (i11 - i10)
                    r = top + ay * (bot - top)
                    res[k] = sc * r if inside else fl
                # then into the output, rounded (ties to even, as _sample) or converted
                if rounded:
                    for k in range(n):
                        ob[k] = O(np.int32((res[k] + magic) - magic))
                else:
                    for k in range(n):
                        ob[k] = O(res[k])


def remap_bilinear(
    img: np.ndarray,
    map_uv: np.ndarray,
    scale: float,
    fill: float,
    out: np.ndarray,
    acc: np.ndarray,
    kcar: np.ndarray,
    hi: float,
    threads: int | None = None,
) -> None:
    """``img`` (B, H, W, C), ``out`` (B, H', W', C) and ``map_uv`` (H', W', 2), C-contiguous.

    ``out`` float32/float64, or the image's integer dtype when ``hi`` (its largest code) is
    positive: rounded, ``fill`` in codes. ``acc``: an empty array of the arithmetic's dtype
    (float64 for a float64 ``out``, else float32); ``kcar``: one of the sample indices'
    dtype (int32 when the image has fewer than 2**31 samples, else int64). The row blocks
    run on numba's threads (:func:`imageform._kernels.jit.run_tasks`; ``threads=1``: in the
    calling thread).
    """
    nblk = min(map_uv.shape[0], _BLOCKS)
    _, h, w, nc = img.shape
    if _LITTLE and nc == 1 and h >= 2 and w >= 2:
        b, ho, wo = out.shape[0], out.shape[1], out.shape[2]
        flat, mf, of = img.reshape(b, h * w), map_uv.reshape(-1), out.reshape(b, ho * wo)
        args_grey = (flat, mf, h, w, ho, wo, scale, fill, of, acc, hi, nblk)
        run_tasks(_remap_grey_tasks, b * nblk, *args_grey, threads=threads)
        return
    args = (img, map_uv, scale, fill, out, acc, kcar, hi, nblk)
    run_tasks(_remap_tasks, img.shape[0] * nblk, *args, threads=threads)


#: :func:`remap_bilinear` in the calling thread (small images: no pool to wake).
remap_bilinear_serial = functools.partial(remap_bilinear, threads=1)


@njit(error_model="numpy", fastmath={"contract"})
def _undistort_rows(
    flat: np.ndarray,
    i0: int,
    i1: int,
    wo: int,
    h: int,
    w: int,
    nc: int,
    p: np.ndarray,
    rational: bool,
    scale: float,
    fill: float,
    rounded: bool,
    hi: float,
    of: np.ndarray,
    bufs: tuple[np.ndarray, ...],
) -> None:
    """Write output rows ``i0:i1`` of one image.

    The source positions come from the Brown-Conrady model (``p``: the hoisted coefficients,
    see :func:`undistort_brown_conrady`).
    """
    kidx, ax, ay, ok = bufs
    lut = np.arange(256).astype(ax.dtype)  # the uint8 codes as floats (see _value_impl)
    fxn, sn, cxn, fyn, cyn = p[0], p[1], p[2], p[3], p[4]
    fx, s, cx, fy, cy = p[5], p[6], p[7], p[8], p[9]
    k1, k2, p1, p2, k3, k4, k5, k6 = p[10], p[11], p[12], p[13], p[14], p[15], p[16], p[17]
    K = kidx.dtype.type
    zero = np.float64(0.0)
    wm1 = np.float64(w - 1)
    hm1 = np.float64(h - 1)
    xmax = K(max(w - 2, 0))
    ymax = K(max(h - 2, 0))
    row = K(w * nc)
    dx = nc if w > 1 else 0
    dy = row if h > 1 else 0
    for i in range(i0, i1):
        y = (i - cyn) / fyn
        yy = y * y
        x_off = cxn + sn * y
        for j0 in range(0, wo, _BLK):
            n = min(_BLK, wo - j0)
            if rational:
                for t in range(n):
                    x = (j0 + t - x_off) / fxn
                    r2 = x * x + yy
                    radial = (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (
                        1.0 + r2 * (k4 + r2 * (k5 + r2 * k6))
                    )
                    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
                    yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * x * y
                    u = fx * xd + s * yd + cx
                    _locate(
                        u, fy * yd + cy, zero, wm1, hm1, xmax, ymax, row, nc, t, kidx, ax, ay, ok
                    )
            else:
                for t in range(n):
                    x = (j0 + t - x_off) / fxn
                    r2 = x * x + yy
                    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
                    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
                    yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * x * y
                    u = fx * xd + s * yd + cx
                    _locate(
                        u, fy * yd + cy, zero, wm1, hm1, xmax, ymax, row, nc, t, kidx, ax, ay, ok
                    )
            base = i * wo + j0
            ob = of[base * nc : (base + n) * nc]
            _sample_block(flat, n, nc, dx, dy, kidx, ax, ay, ok, scale, fill, rounded, hi, ob, lut)


@njit(nogil=True, error_model="numpy", fastmath={"contract"})
def _undistort_tasks(
    t0: int,
    t1: int,
    img: np.ndarray,
    p: np.ndarray,
    rational: bool,
    scale: float,
    fill: float,
    out: np.ndarray,
    acc: np.ndarray,
    kcar: np.ndarray,
    hi: float,
    nblk: int,
) -> None:  # pragma: no cover
    # tasks t0 .. t1 - 1 of undistort_brown_conrady: image t // nblk, row block t % nblk
    _, h, w, nc = img.shape
    ho = out.shape[1]
    wo = out.shape[2]
    rounded = hi > 0.0
    bufs = _block_buffers(kcar, acc)
    for t in range(t0, t1):
        b, i0, i1 = _task_rows(t, nblk, ho)
        flat = img[b].ravel()
        of = out[b].ravel()
        _undistort_rows(flat, i0, i1, wo, h, w, nc, p, rational, scale, fill, rounded, hi, of, bufs)


def undistort_brown_conrady(
    img: np.ndarray,
    k_new: np.ndarray,
    k_src: np.ndarray,
    coeffs: np.ndarray,
    scale: float,
    fill: float,
    out: np.ndarray,
    acc: np.ndarray,
    kcar: np.ndarray,
    hi: float,
    threads: int | None = None,
) -> None:
    """Undistort: Brown-Conrady (OpenCV's rational model) fused with the sampling.

    As ``bc_distort_point``; the coefficients hoisted, the row terms computed once per row,
    the positions in float64, and the rational denominator skipped when ``k4 = k5 = k6 = 0``.
    ``out`` as for :func:`remap_bilinear`; the row blocks on numba's threads.
    """
    p = np.empty(18, np.float64)
    p[0:5] = k_new[0, 0], k_new[0, 1], k_new[0, 2], k_new[1, 1], k_new[1, 2]
    p[5:10] = k_src[0, 0], k_src[0, 1], k_src[0, 2], k_src[1, 1], k_src[1, 2]
    p[10:18] = np.asarray(coeffs, np.float64)[:8]
    rational = bool(coeffs[5] != 0.0 or coeffs[6] != 0.0 or coeffs[7] != 0.0)
    nblk = min(out.shape[1], _BLOCKS)
    args = (img, p, rational, scale, fill, out, acc, kcar, hi, nblk)
    run_tasks(_undistort_tasks, img.shape[0] * nblk, *args, threads=threads)


#: :func:`undistort_brown_conrady` in the calling thread.
undistort_brown_conrady_serial = functools.partial(undistort_brown_conrady, threads=1)


#: Outputs of fewer samples (pixels x channels x images) run in the calling thread. On the
#: idle 2-core machine two threads already halve a 96 x 96 grey remap (0.03 ms); the threshold
#: only keeps the pool's wake-up off the smallest calls. One compiled kernel serves both.
PARALLEL_MIN_SAMPLES = 1 << 14


def pick(kernel: str, n_samples: int) -> object:
    """Return the parallel or the serial kernel ``kernel`` for ``n_samples`` output samples."""
    serial = not parallel_pays(n_samples, PARALLEL_MIN_SAMPLES)
    if kernel == "remap":
        return remap_bilinear_serial if serial else remap_bilinear
    return undistort_brown_conrady_serial if serial else undistort_brown_conrady
