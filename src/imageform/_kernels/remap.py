"""Numba kernels: bilinear remapping of a batch of channels-last images.

``remap_bilinear``: ``out[b, i, j, c] = scale * bilinear(img[b, :, :, c])`` at the source
position ``(u, v) = (map_uv[i, j, 0], map_uv[i, j, 1])`` (column, row; the centre of the
top-left pixel is ``(0, 0)``). Positions outside ``[0, W-1] × [0, H-1]`` or NaN get ``fill``
(not scaled). ``scale`` is ``1/255`` (``1/65535``) when ``img`` is uint8 (uint16) and the output
float32, so an 8-bit image is sampled directly, without a float copy of it; ``1`` for float
images. ``undistort_brown_conrady`` fuses the source-position computation of
:func:`imageform.geometry.undistort.undistortion_map` for Brown-Conrady with the sampling (no
``(H, W, 2)`` map is allocated).

Both run in parallel over blocks of output rows, and split each row in two loops: the first
computes, for every output pixel, the flat index of its top-left source pixel, the steps to
its right and lower neighbours (0 on the last column/row), the weights and whether it is
inside; it has no gathers and no branches, so LLVM vectorises it (the Brown-Conrady model
included); the second gathers the four neighbours and interpolates, specialised for 1 and 3
channels. Coordinates and weights are float64 whatever the image dtype.

The plain twin of both is :func:`imageform.geometry.undistort._remap_bilinear_numpy` on the
map from :func:`~imageform.geometry.undistort.undistortion_map`; tests check agreement to
1e-12 (float64).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from imageform._kernels.jit import njit

__all__ = ["remap_bilinear", "undistort_brown_conrady"]

#: Row blocks per image (the parallel work items); each allocates its row buffers once.
_BLOCKS = 64

# every kernel: error_model="numpy" (no ZeroDivisionError checks), fastmath
# {"contract"} (fused multiply-adds only; NaN/inf semantics kept)


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _locate(
    u: float,
    v: float,
    h: int,
    w: int,
    nc: int,
    j: int,
    idx: np.ndarray,
    step: np.ndarray,
    wts: np.ndarray,
    ok: np.ndarray,
) -> None:
    """Branch-free: where output pixel ``j`` of the row reads from (see the module docstring)."""
    inside = (u >= 0.0) & (u <= w - 1.0) & (v >= 0.0) & (v <= h - 1.0)
    uc = u if inside else 0.0  # NaN and outside: a safe index, the pixel gets ``fill``
    vc = v if inside else 0.0
    x0 = np.int64(uc)  # uc >= 0: truncation is floor
    y0 = np.int64(vc)
    wts[j, 0] = uc - x0
    wts[j, 1] = vc - y0
    step[j, 0] = nc if x0 < w - 1 else 0
    step[j, 1] = w * nc if y0 < h - 1 else 0
    idx[j] = (y0 * w + x0) * nc
    ok[j] = inside


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _gather_row(
    flat: np.ndarray,
    nc: int,
    idx: np.ndarray,
    step: np.ndarray,
    wts: np.ndarray,
    ok: np.ndarray,
    scale: float,
    fill: float,
    orow: np.ndarray,
) -> None:
    """Interpolate one output row bilinearly (``orow`` flat, ``wo * nc``), as lerps.

    ``(1-ay)((1-ax) I00 + ax I01) + ay((1-ax) I10 + ax I11)``.
    """
    for j in range(idx.shape[0]):
        o = j * nc
        if not ok[j]:
            for c in range(nc):
                orow[o + c] = fill
            continue
        k = idx[j]
        dx = step[j, 0]
        dy = step[j, 1]
        ax = wts[j, 0]
        ay = wts[j, 1]
        if nc == 1:
            i00 = np.float64(flat[k])  # float64: uint8/uint16 differences must not wrap
            i10 = np.float64(flat[k + dy])
            top = i00 + ax * (np.float64(flat[k + dx]) - i00)
            bot = i10 + ax * (np.float64(flat[k + dx + dy]) - i10)
            orow[o] = scale * (top + ay * (bot - top))
        elif nc == 3:
            for c in range(3):
                i00 = np.float64(flat[k + c])
                i10 = np.float64(flat[k + dy + c])
                top = i00 + ax * (np.float64(flat[k + dx + c]) - i00)
                bot = i10 + ax * (np.float64(flat[k + dx + dy + c]) - i10)
                orow[o + c] = scale * (top + ay * (bot - top))
        else:
            for c in range(nc):
                i00 = np.float64(flat[k + c])
                i10 = np.float64(flat[k + dy + c])
                top = i00 + ax * (np.float64(flat[k + dx + c]) - i00)
                bot = i10 + ax * (np.float64(flat[k + dx + dy + c]) - i10)
                orow[o + c] = scale * (top + ay * (bot - top))


@njit(parallel=True, error_model="numpy", fastmath={"contract"})
def remap_bilinear(
    img: np.ndarray, map_uv: np.ndarray, scale: float, fill: float, out: np.ndarray
) -> None:  # pragma: no cover
    """``img`` (B, H, W, C) and ``out`` (B, H', W', C) C-contiguous, ``map_uv`` (H', W', 2)."""
    nb, h, w, nc = img.shape
    ho, wo = map_uv.shape[0], map_uv.shape[1]
    nblk = min(ho, _BLOCKS)
    for t in prange(nb * nblk):
        b = t // nblk
        blk = t - b * nblk
        idx = np.empty(wo, np.int64)
        step = np.empty((wo, 2), np.int64)
        wts = np.empty((wo, 2), np.float64)
        ok = np.empty(wo, np.bool_)
        flat = img[b].ravel()
        for i in range(blk * ho // nblk, (blk + 1) * ho // nblk):
            mrow = map_uv[i]
            for j in range(wo):
                u = np.float64(mrow[j, 0])
                v = np.float64(mrow[j, 1])
                _locate(u, v, h, w, nc, j, idx, step, wts, ok)
            _gather_row(flat, nc, idx, step, wts, ok, scale, fill, out[b, i].ravel())


@njit(parallel=True, error_model="numpy", fastmath={"contract"})
def undistort_brown_conrady(
    img: np.ndarray,
    k_new: np.ndarray,
    k_src: np.ndarray,
    coeffs: np.ndarray,
    scale: float,
    fill: float,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """Distort with Brown-Conrady (OpenCV's rational model, as ``bc_distort_point``) and sample.

    The coefficients are hoisted, the row terms computed once per row, and the rational
    denominator skipped when ``k4 = k5 = k6 = 0``.
    """
    nb, h, w, nc = img.shape
    ho = out.shape[1]
    wo = out.shape[2]
    fxn, sn, cxn, fyn, cyn = k_new[0, 0], k_new[0, 1], k_new[0, 2], k_new[1, 1], k_new[1, 2]
    fx, s, cx, fy, cy = k_src[0, 0], k_src[0, 1], k_src[0, 2], k_src[1, 1], k_src[1, 2]
    k1, k2, p1, p2, k3 = coeffs[0], coeffs[1], coeffs[2], coeffs[3], coeffs[4]
    k4, k5, k6 = coeffs[5], coeffs[6], coeffs[7]
    rational = k4 != 0.0 or k5 != 0.0 or k6 != 0.0
    nblk = min(ho, _BLOCKS)
    for t in prange(nb * nblk):
        b = t // nblk
        blk = t - b * nblk
        idx = np.empty(wo, np.int64)
        step = np.empty((wo, 2), np.int64)
        wts = np.empty((wo, 2), np.float64)
        ok = np.empty(wo, np.bool_)
        flat = img[b].ravel()
        for i in range(blk * ho // nblk, (blk + 1) * ho // nblk):
            y = (i - cyn) / fyn
            yy = y * y
            x_off = cxn + sn * y
            if rational:
                for j in range(wo):
                    x = (j - x_off) / fxn
                    r2 = x * x + yy
                    radial = (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (
                        1.0 + r2 * (k4 + r2 * (k5 + r2 * k6))
                    )
                    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
                    yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * x * y
                    _locate(fx * xd + s * yd + cx, fy * yd + cy, h, w, nc, j, idx, step, wts, ok)
            else:
                for j in range(wo):
                    x = (j - x_off) / fxn
                    r2 = x * x + yy
                    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
                    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
                    yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * x * y
                    _locate(fx * xd + s * yd + cx, fy * yd + cy, h, w, nc, j, idx, step, wts, ok)
            _gather_row(flat, nc, idx, step, wts, ok, scale, fill, out[b, i].ravel())
