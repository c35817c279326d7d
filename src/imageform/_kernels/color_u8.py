r"""8-bit in, 8-bit out colour kernels: uint8 sRGB -> OpenCV-encoded uint8 Lab / HSV (numba).

Output encodings (the ``"lab8"`` / ``"hsv8"`` conventions of :mod:`imageform.color.opencv`,
i.e. ``cv2.cvtColor(img, cv2.COLOR_RGB2Lab)`` / ``COLOR_RGB2HSV`` on uint8):

- Lab: :math:`(L^* \cdot 255/100,\ a^* + 128,\ b^* + 128)`, rounded and saturated to [0, 255].
- HSV: :math:`(H/2,\ 255 S,\ 255 V)`, H in degrees, so the first channel is in [0, 180).

Plain twin: ``to_opencv(convert(img, "srgb", <space>), "<space>8")`` (the float path,
then OpenCV's rounding); ``tests/color/test_kernels_u8.py`` compares the two.

Arithmetic: the sRGB decode is a 256-entry float32 table (exact IEC 61966-2-1 values,
computed in float64 and rounded once) folded with the RGB -> XYZ / white matrix into
integer tables (``t`` in 16-bit fixed point, as OpenCV's 8-bit path does, but finer), and
the CIELAB :math:`f(t)` a table of :math:`2^{16} + 8` float32 samples read at the nearest
one (error < 6e-5 in f, < 0.06 in a*), so the error is dominated by the final rounding to
8 bits (half a code of each channel). The loops are serial over a flat ``(N * 3,)`` slice
(table reads: scalar code, no gathers), run over work items of :data:`_BLOCK` pixels on
numba's threads by :func:`imageform._kernels.jit.run_tasks` (one compiled kernel per
conversion: no ``parallel=True`` wrapper, whose parallel lowering compiles much slower).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._kernels.jit import njit, parallel_pays, run_tasks

__all__ = ["DECODE_LUT", "srgb8_to_hsv8", "srgb8_to_lab8", "srgb8_to_lab_f32"]

_F32 = np.float32
#: Pixels per work item (:func:`imageform._kernels.jit.run_tasks` cuts at these bounds).
_BLOCK = 16384
#: Images of fewer pixels (under 4 work items) run the serial loop in the calling thread:
#: waking numba's thread pool costs more than it gains there.
PARALLEL_MIN_PIXELS = 1 << 16
_FM = {"nsz", "arcp", "contract", "afn", "reassoc"}
_JIT: dict[str, Any] = {"fastmath": _FM, "error_model": "numpy"}


def _decode_table() -> np.ndarray:
    v = np.arange(256, dtype=np.float64) / 255.0
    lin = np.where(v <= 12.92 * 0.0031308, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
    return lin.astype(np.float32)


#: sRGB decode of the 256 code values (float32, IEC 61966-2-1).
DECODE_LUT: np.ndarray = _decode_table()

#: Fixed point of the linear XYZ / white values: t = X / SCALE (16 bits, as OpenCV's
#: 8-bit path quantises linear light, but finer).
SCALE = 1 << 16


def _f_table() -> np.ndarray:
    """Tabulate the CIELAB function f(t) at t = k / SCALE, k = 0 .. SCALE + 7 (float32)."""
    t = np.arange(SCALE + 8, dtype=np.float64) / SCALE
    d = 6.0 / 29.0
    return np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0).astype(np.float32)


#: f(k / SCALE): read at the nearest sample, an error of at most max|f'| / (2 SCALE) = 6e-5
#: in f (0.06 in a*), well under the half code of the output rounding. t > 1 + 7 / SCALE
#: (a white other than the RGB space's) saturates, see ``srgb8_to_lab8``.
F_TABLE: np.ndarray = _f_table()


#: The lab8 L channel at t = k / SCALE: round(2.55 (116 f(t) - 16)), saturated (uint8): one
#: table read instead of the float arithmetic and rounding (twice as fast, measured).
L_TABLE: np.ndarray = np.clip(
    np.rint(2.55 * (116.0 * F_TABLE.astype(np.float64) - 16.0)), 0, 255
).astype(np.uint8)


#: Extra fixed-point bits of the float Lab path's tables (:func:`srgb8_to_lab_f32`): each
#: entry rounded to 2**-24, the sum once to the f table's 2**-16 grid.
FINE_BITS = 8


def xyz_tables(m: np.ndarray, extra_bits: int = 0) -> np.ndarray:
    """Build the uint32 (3 * 3 * 256,) fixed-point table of an RGB->XYZ matrix ``m``.

    Entry ``768 i + 256 j + v`` is ``round(m[i, j] decode(v) SCALE)`` (negative entries,
    which no RGB->XYZ matrix has, clipped to 0), so that ``X_i = sum_j T[768 i + 256 j + v_j]``
    is the fixed-point linear XYZ / white of a pixel.
    """
    t = m[:, :, None] * DECODE_LUT.astype(np.float64)[None, None, :] * (SCALE << extra_bits)
    return np.clip(np.rint(t), 0, None).astype(np.uint32).reshape(-1)


@njit(inline="always", **_JIT)
def _sat8(x):  # type: ignore[no-untyped-def]
    x = x if x > _F32(0) else _F32(0)
    x = x if x < _F32(255) else _F32(255)
    return np.uint8(np.int32(x + _F32(0.5)))


@njit(**_JIT)
def _lab8_serial(src, dst, tx, tab, lt):  # type: ignore[no-untyped-def]
    # unsigned indices into flat tables: no negative-index wrap-around selects
    top = np.uint32(tab.shape[0] - 1)
    for i in range(src.shape[0] // 3):
        r = np.uint32(src[3 * i])
        g = np.uint32(src[3 * i + 1]) + np.uint32(256)
        bl = np.uint32(src[3 * i + 2]) + np.uint32(512)
        x = min(tx[r] + tx[g] + tx[bl], top)
        y = min(tx[768 + r] + tx[768 + g] + tx[768 + bl], top)
        z = min(tx[1536 + r] + tx[1536 + g] + tx[1536 + bl], top)
        fy = tab[y]
        dst[3 * i] = lt[y]  # L* 255/100 = (116 fy - 16) 2.55, rounded, from its own table
        dst[3 * i + 1] = _sat8(_F32(500) * (tab[x] - fy) + _F32(128))  # a* + 128
        dst[3 * i + 2] = _sat8(_F32(200) * (fy - tab[z]) + _F32(128))  # b* + 128


@njit(nogil=True, error_model="numpy")
def _lab8_tasks(t0, t1, src, dst, tx, tab, lt):  # type: ignore[no-untyped-def]
    """Work items ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``).

    A serial ``nogil`` kernel, not a ``parallel=True`` ``prange``: numba's parallel lowering
    and its gufunc cost seconds of CPU more to compile on a first run, and the same compiled
    kernel serves small images in the calling thread (no serial twin to compile).
    """
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _lab8_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], tx, tab, lt)


@njit(**_JIT)
def _labf_serial(src, dst, tx, tab):  # type: ignore[no-untyped-def]
    # as _lab8_serial with FINE_BITS more bits per table entry (one rounding, at the sum), and
    # the float result kept (no rounding to lab8 codes)
    top = np.uint32(tab.shape[0] - 1)
    half = np.uint32(1 << (FINE_BITS - 1))
    sh = np.uint32(FINE_BITS)
    for i in range(src.shape[0] // 3):
        r = np.uint32(src[3 * i])
        g = np.uint32(src[3 * i + 1]) + np.uint32(256)
        bl = np.uint32(src[3 * i + 2]) + np.uint32(512)
        fx = tab[min((tx[r] + tx[g] + tx[bl] + half) >> sh, top)]
        fy = tab[min((tx[768 + r] + tx[768 + g] + tx[768 + bl] + half) >> sh, top)]
        fz = tab[min((tx[1536 + r] + tx[1536 + g] + tx[1536 + bl] + half) >> sh, top)]
        dst[3 * i] = _F32(116) * fy - _F32(16)
        dst[3 * i + 1] = _F32(500) * (fx - fy)
        dst[3 * i + 2] = _F32(200) * (fy - fz)


@njit(nogil=True, error_model="numpy")
def _labf_tasks(t0, t1, src, dst, tx, tab):  # type: ignore[no-untyped-def]
    """Work items ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``)."""
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _labf_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], tx, tab)


@njit(**_JIT)
def _hsv8_serial(src, dst):  # type: ignore[no-untyped-def]
    # the hue's numerator and offset selected first: one division for H (not one per case),
    # and S = 255 d / max needs no clamping (d <= max): 11 % faster than three divisions
    for i in range(src.shape[0] // 3):
        r = _F32(src[3 * i])
        g = _F32(src[3 * i + 1])
        bl = _F32(src[3 * i + 2])
        mx = max(max(r, g), bl)
        mn = min(min(r, g), bl)
        d = mx - mn
        ds = d if d != 0 else _F32(1)
        isr = mx == r
        isg = mx == g
        num = (g - bl) if isr else ((bl - r) if isg else (r - g))
        off = _F32(0) if isr else (_F32(60) if isg else _F32(120))
        h = num * _F32(30) / ds + off  # H / 2 in [-30, 180)
        h = h + _F32(180) if h < 0 else h
        h = h if d != 0 else _F32(0)
        hq = np.int32(h + _F32(0.5))
        dst[3 * i] = np.uint8(hq if hq < 180 else hq - 180)
        sat = _F32(255) * d / (mx if mx != 0 else _F32(1))
        dst[3 * i + 1] = np.uint8(np.int32(sat + _F32(0.5)))
        dst[3 * i + 2] = np.uint8(np.int32(mx))


@njit(nogil=True, error_model="numpy")
def _hsv8_tasks(t0, t1, src, dst):  # type: ignore[no-untyped-def]
    """Work items ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of ``run_tasks``)."""
    lo = t0 * _BLOCK
    hi = min(src.shape[0] // 3, t1 * _BLOCK)
    _hsv8_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi])


def _run(kernel: Any, src: np.ndarray, *args: Any) -> None:
    """Run ``kernel`` over the work items of the flat ``(N * 3,)`` image ``src``.

    On numba's threads (:func:`imageform._kernels.jit.run_tasks`) from
    :data:`PARALLEL_MIN_PIXELS` up, in the calling thread below.
    """
    n = src.size // 3
    threads = None if parallel_pays(n, PARALLEL_MIN_PIXELS) else 1
    run_tasks(kernel, (n + _BLOCK - 1) // _BLOCK, src, *args, threads=threads)


def _flat_out(image: np.ndarray, out: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    src = np.ascontiguousarray(image).reshape(-1)
    if out is None:
        res = np.empty(image.shape, np.uint8)
        return src, res
    return src, out


def srgb8_to_lab8(image: np.ndarray, m: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """uint8 sRGB (..., 3) -> uint8 Lab (OpenCV's encoding); ``m`` = RGB->XYZ / white.

    ``out`` (C-contiguous uint8 of the image's shape, checked by the caller) is written in place.
    """
    src, res = _flat_out(image, out)
    _run(_lab8_tasks, src, res.reshape(-1), xyz_tables(m), F_TABLE, L_TABLE)
    return res


def srgb8_to_lab_f32(image: np.ndarray, m: np.ndarray, out: np.ndarray) -> np.ndarray:
    """uint8 sRGB (..., 3) -> float32 Lab from the tables of :func:`srgb8_to_lab8`, unrounded.

    ``out``: C-contiguous float32 of the image's shape (checked by the caller).
    """
    src = np.ascontiguousarray(image).reshape(-1)
    _run(_labf_tasks, src, out.reshape(-1), xyz_tables(m, FINE_BITS), F_TABLE)
    return out


def srgb8_to_hsv8(image: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """uint8 sRGB (..., 3) -> uint8 HSV (H/2 in [0, 180), 255 S, V), as ``COLOR_RGB2HSV``."""
    src, res = _flat_out(image, out)
    _run(_hsv8_tasks, src, res.reshape(-1))
    return res
