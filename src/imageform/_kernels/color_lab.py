r"""Fused numba kernels: sRGB (float32 / float64 / uint8) <-> CIELAB, threads over pixel chunks.

Plain twin: the array path of :func:`imageform.color.convert` (``srgb_to_linear`` ->
``linear_srgb_to_xyz`` -> ``xyz_to_lab`` and back) computing the same equations;
``tests/color/test_kernels.py`` checks the two agree to the tolerances stated there.

Accuracy design of the fast path (float32 / uint8 input, float32 arithmetic):

- sRGB decode (uint8 read as v / 255): :math:`w^{2.4} = w^2 \cdot u^{0.8}`,
  :math:`u = \sqrt{w}`, :math:`u^{0.8}` a degree-7 minimax polynomial (relative error 5.4e-7);
  pixels with a value outside [0, 1] are recomputed with the exact float64 formulas.
- the cube root of CIELAB: a degree-4 seed in :math:`\sqrt{t}` and one Halley step
  (relative error ~2e-8). One square root each: on AVX2 a vector square root costs as much as
  several multiplies, and these two account for most of the kernel's time.
- the 1/2.4 power of the sRGB encode (:math:`x^{5/12} = \sqrt[3]{x \cdot x^{1/4}}`): a cubic
  seed in :math:`t^{1/4}` and two Halley steps (relative error ~1e-7, float32 rounding).
- Lab -> sRGB results above 1 (out of gamut) are recomputed in float64.

The hot loops have no calls, no data-dependent branches (selects only) and no reductions,
and use ``error_model="numpy"`` so that LLVM vectorises them. float64 input runs the exact
formulas in float64.

Chunks of :data:`_BLOCK` pixels run on numba's threads through
:func:`imageform._kernels.jit.run_tasks`: one serial ``nogil`` kernel per conversion, which
also serves a single chunk or a single thread in the calling thread (the ``parallel=True``
``prange`` wrappers and their serial twins before issue 25 compiled much slower).

The boundary checks of float32 / uint8 input (NaN/inf, values outside [0, 1]) are gathered
in the conversion's own pass over memory: each sub-block of :data:`_SUB` pixels is
converted, then counted and summed while it is still in the L1 cache. Gathered inside the
conversion loop itself (as before issue 25), the reduction made LLVM interleave the loop
twice and spill registers, and an int64 count held it to four lanes: 2.2x slower.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._kernels.jit import njit, run_tasks

__all__ = ["lab_to_srgb", "srgb_to_lab"]

_BLOCK = 65536  # pixels per chunk (a task of run_tasks); each runs a serial (vectorisable) loop
_SUB = 2048  # pixels per sub-block of a chunk: 24 kB of float32 input, checked while in L1

# the same constants as imageform.color.transfer / cielab (IEC 61966-2-1, CIE 15:2004)
_A = 0.055
_G = 2.4
_SLOPE = 12.92
_LIN_T = 0.0031308
_ENC_T = _SLOPE * _LIN_T
_DELTA = 6.0 / 29.0
_EPS = _DELTA**3
_LSLOPE = 1.0 / (3.0 * _DELTA**2)
_LOFF = 4.0 / 29.0


@njit(inline="always", error_model="numpy")
def _dec_exact(v):  # type: ignore[no-untyped-def]
    if v <= _ENC_T:
        return v / _SLOPE
    return ((v + _A) / (1.0 + _A)) ** _G


@njit(inline="always", error_model="numpy")
def _enc_exact(x):  # type: ignore[no-untyped-def]
    if x <= _LIN_T:
        return x * _SLOPE
    return (1.0 + _A) * x ** (1.0 / _G) - _A


@njit(inline="always", error_model="numpy")
def _f_exact(t):  # type: ignore[no-untyped-def]
    if t > _EPS:
        return np.cbrt(t)
    return _LSLOPE * t + _LOFF


_F32 = np.float32
_EPS32 = np.float32(_EPS)
_DELTA32 = np.float32(_DELTA)
_LSLOPE32 = np.float32(_LSLOPE)
_LOFF32 = np.float32(_LOFF)
_LIN_T32 = np.float32(_LIN_T)
_SLOPE32 = np.float32(_SLOPE)
_ENC_T32 = np.float32(_ENC_T)
# fastmath without nnan/ninf: inputs are validated finite, but NaN semantics stay intact.
# error_model="numpy": no ZeroDivisionError checks, so LLVM can vectorise the loops.
_FM = {"nsz", "arcp", "contract", "afn", "reassoc"}
_JIT: dict[str, Any] = {"fastmath": _FM, "error_model": "numpy"}

# Seed for the float32 cube root: t^(1/3) = u^(4/3) with u = t^(1/4), and u^(1/3) ~ cubic
# in u, least-squares on u in [0.15, 1.05] (t in [5e-4, 1.2]; max relative error 1.3 %);
# two Halley steps y <- y (y^3 + 2t) / (2y^3 + t) take 1.3e-2 to ~1e-6 to float32 rounding.
_C3, _C2, _C1, _C0 = (_F32(0.3550869), _F32(-0.96483168), _F32(1.23719213), _F32(0.37323781))


@njit(inline="always", **_JIT)
def _cbrt32(t):  # type: ignore[no-untyped-def]
    """Cube root of t > 0 in float32 (valid for t in [5e-4, 1.2]; callers fix up the rest)."""
    u = np.sqrt(np.sqrt(t))
    y = u * (_C0 + u * (_C1 + u * (_C2 + u * _C3)))
    y3 = y * y * y
    y = y * (y3 + _F32(2) * t) / (_F32(2) * y3 + t)
    y3 = y * y * y
    return y * (y3 + _F32(2) * t) / (_F32(2) * y3 + t)


# The decode and the cube root each take ONE square root (a vector square root costs as much as
# ~6 multiplies; the previous fourth-root seeds took two): coefficients from
# tools/fit_color_kernels.py (Lawson minimax fits of the relative error).
# sRGB decode, power branch: w^2.4 = w^2 * w^0.4 = w^2 * u^0.8 with u = sqrt(w), u^0.8 as a
# degree-7 polynomial on u in [0.3, 1] (w in [0.09, 1]); max relative error 5.4e-7.
_DEC = tuple(
    np.float32(c)
    for c in (
        0.15700797, -0.82108816, 1.86790406, -2.44337878,
        2.07281963, -1.29600726, 1.43510551, 0.02763756,
    )
)  # fmt: skip
# CIELAB cube root: t^(1/3) = s^(2/3) with s = sqrt(t), a degree-4 polynomial on s in
# [sqrt(eps), sqrt(1.2)] (t in [eps, 1.2]; max relative error 2.7e-3), then one Halley step
# (cubic convergence: 2e-8, float32 rounding).
_CBL = tuple(np.float32(c) for c in (-0.53410316, 1.52206240, -1.73456023, 1.68579010, 0.06292927))


@njit(inline="always", **_JIT)
def _dec32(v):  # type: ignore[no-untyped-def]
    """Decode sRGB in float32 for v in [0, 1] (callers fix up values outside)."""
    w = (v + _F32(_A)) / _F32(1.0 + _A)
    w = w if w > _F32(0.09) else _F32(0.09)
    u = np.sqrt(w)
    c7, c6, c5, c4, c3, c2, c1, c0 = _DEC
    p = c0 + u * (c1 + u * (c2 + u * (c3 + u * (c4 + u * (c5 + u * (c6 + u * c7))))))
    lin = w * w * p
    return lin if v > _ENC_T32 else v / _SLOPE32


@njit(inline="always", **_JIT)
def _cbrt32_lab(t):  # type: ignore[no-untyped-def]
    """Cube root for t in [eps, 1.2] (CIELAB): polynomial seed in sqrt(t) + one Halley step."""
    s = np.sqrt(t)
    c4, c3, c2, c1, c0 = _CBL
    y = c0 + s * (c1 + s * (c2 + s * (c3 + s * c4)))
    y3 = y * y * y
    return y * (y3 + _F32(2) * t) / (_F32(2) * y3 + t)


@njit(inline="always", **_JIT)
def _f32(t):  # type: ignore[no-untyped-def]
    c = _cbrt32_lab(t if t > _EPS32 else _EPS32)
    return c if t > _EPS32 else _LSLOPE32 * t + _LOFF32


@njit(**_JIT)
def _lab_exact_pixel(r, g, b, m, dst, k):  # type: ignore[no-untyped-def]
    """Exact float64 Lab of one pixel from linear RGB (the fix-up for rare inputs)."""
    fx = _f_exact(m[0, 0] * r + m[0, 1] * g + m[0, 2] * b)
    fy = _f_exact(m[1, 0] * r + m[1, 1] * g + m[1, 2] * b)
    fz = _f_exact(m[2, 0] * r + m[2, 1] * g + m[2, 2] * b)
    dst[k] = 116.0 * fy - 16.0
    dst[k + 1] = 500.0 * (fx - fy)
    dst[k + 2] = 200.0 * (fy - fz)


@njit(**_JIT)
def _srgb_to_lab_f32_rows(src, dst, m, scale):  # type: ignore[no-untyped-def]
    """float32 (scale 1) or uint8 (scale 1/255) sRGB -> Lab on a flat (N * 3,) slice.

    The hot loop: no calls, no data-dependent branches and no reduction. A reduction (the
    input statistics, once gathered here) makes LLVM interleave the vectorised body twice,
    which spills registers and reads stride-3 pixels four at a time: 2.2x slower on
    AVX-512 (benchmarks/results/color-2026-11-28.md).
    """
    n = src.shape[0] // 3
    # matrix entries in locals: loads from ``m`` inside the loop could alias ``dst`` and
    # would block vectorisation
    m00, m01, m02 = m[0, 0], m[0, 1], m[0, 2]
    m10, m11, m12 = m[1, 0], m[1, 1], m[1, 2]
    m20, m21, m22 = m[2, 0], m[2, 1], m[2, 2]
    for i in range(n):
        v0 = src[3 * i] * scale
        v1 = src[3 * i + 1] * scale
        v2 = src[3 * i + 2] * scale
        r = _dec32(v0)
        g = _dec32(v1)
        bl = _dec32(v2)
        fx = _f32(m00 * r + m01 * g + m02 * bl)
        fy = _f32(m10 * r + m11 * g + m12 * bl)
        fz = _f32(m20 * r + m21 * g + m22 * bl)
        dst[3 * i] = _F32(116) * fy - _F32(16)
        dst[3 * i + 1] = _F32(500) * (fx - fy)
        dst[3 * i + 2] = _F32(200) * (fy - fz)


@njit(**_JIT)
def _input_stats(src, scale):  # type: ignore[no-untyped-def]
    """Return (count of values outside [0, 1], sum of values) of a flat slice, in float32.

    The boundary checks' statistics: NaN/inf make the sum non-finite. A float32 count (a
    select and an add) keeps the loop in 8 or 16 float lanes; exact to 2**24 values.
    """
    out = _F32(0)
    acc = _F32(0)
    for k in range(src.shape[0]):
        v = src[k] * scale
        out += _F32(1) if (v < _F32(0)) | (v > _F32(1)) else _F32(0)
        acc += v
    return out, acc


@njit(**_JIT)
def _srgb_to_lab_f32_serial(src, dst, m, scale, stats, c):  # type: ignore[no-untyped-def]
    """Convert a flat (N * 3,) slice and gather its input statistics into ``stats[c]``.

    One pass over memory: each sub-block of :data:`_SUB` pixels is converted, then its
    values (still in the L1 cache) are counted and summed (:func:`_input_stats`).
    """
    n = src.shape[0] // 3
    out = 0.0
    acc = 0.0
    for lo in range(0, n, _SUB):
        hi = min(n, lo + _SUB)
        s = src[3 * lo : 3 * hi]
        _srgb_to_lab_f32_rows(s, dst[3 * lo : 3 * hi], m, scale)
        o, a = _input_stats(s, scale)
        out += o
        acc += a
    stats[c, 0] = out
    stats[c, 1] = acc


@njit(**_JIT)
def _srgb_to_lab_f32_fixup(src, dst, m, scale, idx):  # type: ignore[no-untyped-def]
    """Send pixels ``idx`` (a value outside [0, 1]) through the exact float64 path.

    A separate function over the few listed pixels: a call inside the hot loop's function
    would stop LLVM from vectorising it.
    """
    for i in idx:
        v0, v1, v2 = src[3 * i] * scale, src[3 * i + 1] * scale, src[3 * i + 2] * scale
        _lab_exact_pixel(
            _dec_exact(float(v0)), _dec_exact(float(v1)), _dec_exact(float(v2)), m, dst, 3 * i
        )


@njit(**_JIT)
def _srgb_to_lab_f64_serial(src, dst, m):  # type: ignore[no-untyped-def]
    """float64 sRGB -> Lab with the exact formulas."""
    for i in range(src.shape[0] // 3):
        _lab_exact_pixel(
            _dec_exact(src[3 * i]),
            _dec_exact(src[3 * i + 1]),
            _dec_exact(src[3 * i + 2]),
            m,
            dst,
            3 * i,
        )


# _cbrt32 is valid to t = 1.2: encoded 1.055 * 1.2^(1/2.4) - 0.055 = 1.0816; above, exact.
_ENC_MAX = np.float32(1.08)


@njit(inline="always", **_JIT)
def _enc32(x):  # type: ignore[no-untyped-def]
    # x^(1/2.4) = x^(5/12) = cbrt(x * x^(1/4))
    c = _F32(1.055) * _cbrt32(x * np.sqrt(np.sqrt(x if x > _LIN_T32 else _LIN_T32))) - _F32(_A)
    return c if x > _LIN_T32 else x * _SLOPE32


@njit(inline="always", **_JIT)
def _finv32(u):  # type: ignore[no-untyped-def]
    return u * u * u if u > _DELTA32 else (u - _LOFF32) / _LSLOPE32


@njit(**_JIT)
def _lab_exact_rgb(l, a, b, mi, dst, k):  # type: ignore[no-untyped-def]
    fy = (l + 16.0) / 116.0
    x = _finv(fy + a / 500.0)
    y = _finv(fy)
    z = _finv(fy - b / 200.0)
    dst[k] = _enc_exact(mi[0, 0] * x + mi[0, 1] * y + mi[0, 2] * z)
    dst[k + 1] = _enc_exact(mi[1, 0] * x + mi[1, 1] * y + mi[1, 2] * z)
    dst[k + 2] = _enc_exact(mi[2, 0] * x + mi[2, 1] * y + mi[2, 2] * z)


@njit(**_JIT)
def _lab_to_srgb_f32_serial(src, dst, mi):  # type: ignore[no-untyped-def]
    n = src.shape[0] // 3
    m00, m01, m02 = mi[0, 0], mi[0, 1], mi[0, 2]
    m10, m11, m12 = mi[1, 0], mi[1, 1], mi[1, 2]
    m20, m21, m22 = mi[2, 0], mi[2, 1], mi[2, 2]
    for i in range(n):  # hot loop, vectorised
        fy = (src[3 * i] + _F32(16)) / _F32(116)
        x = _finv32(fy + src[3 * i + 1] / _F32(500))
        y = _finv32(fy)
        z = _finv32(fy - src[3 * i + 2] / _F32(200))
        dst[3 * i] = _enc32(m00 * x + m01 * y + m02 * z)
        dst[3 * i + 1] = _enc32(m10 * x + m11 * y + m12 * z)
        dst[3 * i + 2] = _enc32(m20 * x + m21 * y + m22 * z)


@njit(**_JIT)
def _lab_to_srgb_f32_fixup(src, dst, mi, idx):  # type: ignore[no-untyped-def]
    """Send pixels ``idx`` beyond the float32 cube root's range to the exact float64 path.

    The range ends at linear > 1.2, encoded > 1.08: far out of gamut.
    """
    for i in idx:
        _lab_exact_rgb(
            float(src[3 * i]), float(src[3 * i + 1]), float(src[3 * i + 2]), mi, dst, 3 * i
        )


@njit(**_JIT)
def _lab_to_srgb_f64_serial(src, dst, mi):  # type: ignore[no-untyped-def]
    for i in range(src.shape[0] // 3):
        _lab_exact_rgb(src[3 * i], src[3 * i + 1], src[3 * i + 2], mi, dst, 3 * i)


@njit(nogil=True, error_model="numpy")
def _srgb_to_lab_f32_tasks(t0, t1, src, dst, m, scale, stats):  # type: ignore[no-untyped-def]
    """Chunks ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels, each with its own row of ``stats``.

    A task of :func:`imageform._kernels.jit.run_tasks`: a serial ``nogil`` kernel run on
    numba's threads, not a ``parallel=True`` ``prange`` (numba's parallel lowering and its
    gufunc cost seconds of CPU more to compile on a first ``imageform convert``), and the
    same compiled kernel serves one chunk or one thread in the calling thread (no serial
    twin to compile).
    """
    n = src.shape[0] // 3
    for c in range(t0, t1):
        lo = c * _BLOCK
        hi = min(n, lo + _BLOCK)
        _srgb_to_lab_f32_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], m, scale, stats, c)


@njit(nogil=True, error_model="numpy")
def _srgb_to_lab_f64_tasks(t0, t1, src, dst, m):  # type: ignore[no-untyped-def]
    """Chunks ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``), float64."""
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _srgb_to_lab_f64_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], m)


@njit(nogil=True, error_model="numpy")
def _lab_to_srgb_f32_tasks(t0, t1, src, dst, m):  # type: ignore[no-untyped-def]
    """Chunks ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``), float32."""
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _lab_to_srgb_f32_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], m)


@njit(nogil=True, error_model="numpy")
def _lab_to_srgb_f64_tasks(t0, t1, src, dst, m):  # type: ignore[no-untyped-def]
    """Chunks ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``), float64."""
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _lab_to_srgb_f64_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], m)


def _chunks(n_pixels: int) -> int:
    return (n_pixels + _BLOCK - 1) // _BLOCK


@njit(inline="always", **_JIT)
def _finv(u):  # type: ignore[no-untyped-def]
    if u > _DELTA:
        return u * u * u
    return (u - _LOFF) / _LSLOPE


def srgb_to_lab(
    image: np.ndarray, m: np.ndarray, out: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """Convert encoded sRGB (..., 3) -> CIELAB; ``m`` = diag(1/white) @ RGB->XYZ matrix (float64).

    ``out``: a C-contiguous array of the result's shape and dtype, not overlapping ``image``
    (checked by the caller), written in place.

    uint8 and float32 input give float32 (float32 arithmetic); float64 gives float64
    (exact formulas). Also returns the per-chunk input stats of the float32/uint8 kernel
    (see :func:`imageform._kernels.color_simple.summarize`), None for float64.
    """
    from imageform._kernels.color_simple import new_stats, summarize

    src = np.ascontiguousarray(image).reshape(-1)
    if image.dtype == np.float64:
        dst = np.empty(src.shape, np.float64) if out is None else out.reshape(-1)
        run_tasks(_srgb_to_lab_f64_tasks, _chunks(src.size // 3), src, dst, m)
        return dst.reshape(image.shape), None
    dst = np.empty(src.shape, np.float32) if out is None else out.reshape(-1)
    scale = np.float32(1.0 / 255.0) if image.dtype == np.uint8 else np.float32(1.0)
    m32 = m.astype(np.float32)
    stats = new_stats(src.size // 3)
    # one chunk, or one thread: run in the calling thread (run_tasks)
    run_tasks(_srgb_to_lab_f32_tasks, _chunks(src.size // 3), src, dst, m32, scale, stats)
    outside, finite = summarize(stats)
    if finite and outside:
        px = src.reshape(-1, 3).astype(np.float32) * scale
        idx = np.flatnonzero(((px < 0) | (px > 1)).any(axis=1))
        _srgb_to_lab_f32_fixup(src, dst, m32, scale, idx)
    return dst.reshape(image.shape), stats


def lab_to_srgb(lab: np.ndarray, mi: np.ndarray) -> np.ndarray:
    """CIELAB (..., 3) -> encoded sRGB; ``mi`` = XYZ->RGB matrix @ diag(white) (float64)."""
    src = np.ascontiguousarray(lab).reshape(-1)
    dst = np.empty(src.shape, lab.dtype)
    if lab.dtype == np.float64:
        run_tasks(_lab_to_srgb_f64_tasks, _chunks(src.size // 3), src, dst, mi)
    else:
        mi32 = mi.astype(np.float32)
        run_tasks(_lab_to_srgb_f32_tasks, _chunks(src.size // 3), src, dst, mi32)
        if dst.size and dst.max() > _ENC_MAX:
            idx = np.flatnonzero((dst.reshape(-1, 3) > _ENC_MAX).any(axis=1))
            _lab_to_srgb_f32_fixup(src, dst, mi32, idx)
    return dst.reshape(lab.shape)
