"""Numba kernels for sRGB -> HSV and sRGB <-> Y'CbCr (float32 / float64 / uint8), parallel.

Plain twins: ``imageform._colormath.rgb_to_hsv`` and ``imageform.color.ycbcr._rgb_to_ycbcr``
/ ``_ycbcr_to_rgb`` (the array path of :func:`imageform.color.convert`); the kernels
evaluate the same expressions per pixel (``tests/color/test_kernels.py``).
uint8 input is read as v / 255 (full range) and gives float32.

Each kernel is a serial loop over a flat ``(N * 3,)`` slice (which LLVM can vectorise)
run over chunks of :data:`_BLOCK` pixels by a ``prange`` wrapper.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from imageform._kernels.jit import njit

__all__ = ["new_stats", "srgb_to_hsv", "summarize", "ycbcr_affine"]

_F32 = np.float32
_BLOCK = 65536  # pixels per parallel chunk
# fastmath without nnan/ninf (inputs are validated finite; NaN semantics stay intact)
_FM = {"nsz", "arcp", "contract", "afn", "reassoc"}


@njit(fastmath=_FM, error_model="numpy")
def _hsv_serial(src, dst, scale, stats, c):  # type: ignore[no-untyped-def]
    out = 0
    acc = _F32(0)
    for i in range(src.shape[0] // 3):
        r = src[3 * i] * scale
        g = src[3 * i + 1] * scale
        bl = src[3 * i + 2] * scale
        # branch-free (selects): with varied hues, branches would mispredict constantly
        mx = max(max(r, g), bl)
        mn = min(min(r, g), bl)
        # input statistics as a by-product: the boundary checks (NaN/inf, 0-255 floats);
        # plain add reductions, which vectorise (min/max reductions would not)
        out += (mn < 0) + (mx > 1)
        acc += r + g + bl
        d = mx - mn
        ds = d if d != 0 else _F32(1)
        hr = (g - bl) / ds
        hg = (bl - r) / ds + _F32(2)
        hb = (r - g) / ds + _F32(4)
        h = (hr if mx == r else (hg if mx == g else hb)) * _F32(60)
        h = h + _F32(360) if h < 0 else h
        h = h - _F32(360) if h >= _F32(360) else h
        dst[3 * i] = h if d != 0 else _F32(0)
        dst[3 * i + 1] = d / (mx if mx != 0 else _F32(1))
        dst[3 * i + 2] = mx
    stats[c, 0] = out
    stats[c, 1] = acc


@njit(parallel=True)
def _hsv(src, dst, scale, stats):  # type: ignore[no-untyped-def]
    n = src.shape[0] // 3
    for c in nb.prange((n + _BLOCK - 1) // _BLOCK):
        lo = c * _BLOCK
        hi = min(n, lo + _BLOCK)
        _hsv_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], scale, stats, c)


@njit(fastmath=_FM, error_model="numpy")
def _affine_serial(src, dst, m, off, scale, stats, c):  # type: ignore[no-untyped-def]
    m00, m01, m02 = m[0, 0], m[0, 1], m[0, 2]
    m10, m11, m12 = m[1, 0], m[1, 1], m[1, 2]
    m20, m21, m22 = m[2, 0], m[2, 1], m[2, 2]
    o0, o1, o2 = off[0], off[1], off[2]
    out = 0
    acc = m00 * 0
    for i in range(src.shape[0] // 3):
        r = src[3 * i] * scale
        g = src[3 * i + 1] * scale
        bl = src[3 * i + 2] * scale
        out += (r < 0) + (r > 1) + (g < 0) + (g > 1) + (bl < 0) + (bl > 1)
        acc += r + g + bl
        dst[3 * i] = m00 * r + m01 * g + m02 * bl + o0
        dst[3 * i + 1] = m10 * r + m11 * g + m12 * bl + o1
        dst[3 * i + 2] = m20 * r + m21 * g + m22 * bl + o2
    stats[c, 0] = out
    stats[c, 1] = acc


@njit(parallel=True)
def _affine(src, dst, m, off, scale, stats):  # type: ignore[no-untyped-def]
    n = src.shape[0] // 3
    for c in nb.prange((n + _BLOCK - 1) // _BLOCK):
        lo = c * _BLOCK
        hi = min(n, lo + _BLOCK)
        _affine_serial(src[3 * lo : 3 * hi], dst[3 * lo : 3 * hi], m, off, scale, stats, c)


def _out_dtype(image: np.ndarray) -> type:
    return np.float64 if image.dtype == np.float64 else np.float32


def new_stats(n_pixels: int) -> np.ndarray:
    """Per-chunk (count of values outside [0, 1], sum of values), filled by the kernels."""
    return np.zeros((max(1, (n_pixels + _BLOCK - 1) // _BLOCK), 2), np.float64)


def summarize(stats: np.ndarray) -> tuple[bool, bool]:
    """(any value outside [0, 1], all finite) from per-chunk stats.

    NaN/inf anywhere make the sum non-finite; a non-finite sum may also come from overflow
    of huge finite values, so callers confirm with ``np.isfinite`` before raising.
    """
    return bool(stats[:, 0].sum() > 0), bool(np.isfinite(stats).all())


def srgb_to_hsv(image: np.ndarray, out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Convert encoded sRGB (..., 3) -> HSV (degrees, [0, 1], [0, 1]) and the input's stats.

    ``out``: C-contiguous, the result's shape and dtype, not overlapping ``image`` (checked
    by the caller), written in place.
    """
    src = np.ascontiguousarray(image).reshape(-1)
    dt = _out_dtype(image)
    dst: np.ndarray = np.empty(src.shape, dt) if out is None else out.reshape(-1)
    stats = new_stats(src.size // 3)
    _hsv(src, dst, dt(1.0 / 255.0) if image.dtype == np.uint8 else dt(1.0), stats)
    return dst.reshape(image.shape), stats


def ycbcr_affine(
    image: np.ndarray, m: np.ndarray, off: np.ndarray, out: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``out = image @ m.T + off`` per pixel (the Y'CbCr transforms are affine), and stats."""
    src = np.ascontiguousarray(image).reshape(-1)
    dt = _out_dtype(image)
    dst: np.ndarray = np.empty(src.shape, dt) if out is None else out.reshape(-1)
    scale = dt(1.0 / 255.0) if image.dtype == np.uint8 else dt(1.0)
    stats = new_stats(src.size // 3)
    _affine(src, dst, m.astype(dt), off.astype(dt), scale, stats)
    return dst.reshape(image.shape), stats
