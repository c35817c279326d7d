"""Numba kernels: bilinear remapping of a batch of channels-last images.

``remap_bilinear``: ``out[b, i, j, c] = scale * bilinear(img[b, :, :, c])`` at the source
position ``(u, v) = (map_uv[i, j, 0], map_uv[i, j, 1])`` (column, row; the centre of the
top-left pixel is ``(0, 0)``). Positions outside ``[0, W-1] × [0, H-1]`` or NaN get ``fill``
(not scaled). ``scale`` is ``1/255`` (``1/65535``) when ``img`` is uint8 (uint16) and the output
float32, so an 8-bit image is sampled directly, without a float copy of it; ``1`` for float
images. ``undistort_brown_conrady`` fuses the source-position computation of
:func:`imageform.geometry.undistort.undistortion_map` for Brown-Conrady with the sampling (no
``(H, W, 2)`` map is allocated).

Both run in parallel over output rows (``prange`` over batch × rows). Coordinates and
weights are float64 whatever the image dtype (float32 arithmetic saves nothing here: the
four gathers dominate).

The plain twin of both is :func:`imageform.geometry.undistort._remap_bilinear_numpy` on the
map from :func:`~imageform.geometry.undistort.undistortion_map`; tests check agreement to
1e-12 (float64).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["remap_bilinear", "undistort_brown_conrady"]


@njit(cache=True, inline="always", error_model="numpy")
def _sample(
    img: np.ndarray,
    u: float,
    v: float,
    scale: float,
    fill: float,
    orow: np.ndarray,
    j: int,
) -> None:
    """Write the bilinear sample of ``img`` (H, W, C) at ``(u, v)`` to ``orow[j, :]``."""
    h, w, nc = img.shape
    if not (u >= 0.0 and u <= w - 1.0 and v >= 0.0 and v <= h - 1.0):
        for c in range(nc):
            orow[j, c] = fill
        return
    x0 = int(u)  # u >= 0: truncation is floor
    y0 = int(v)
    x1 = x0 + 1 if x0 < w - 1 else x0
    y1 = y0 + 1 if y0 < h - 1 else y0
    ax = u - x0
    ay = v - y0
    # (1-ay)((1-ax) I00 + ax I01) + ay((1-ax) I10 + ax I11), as lerps (fewer operations)
    for c in range(nc):  # float64: uint8/uint16 differences must not wrap around
        i00 = np.float64(img[y0, x0, c])
        i10 = np.float64(img[y1, x0, c])
        top = i00 + ax * (np.float64(img[y0, x1, c]) - i00)
        bot = i10 + ax * (np.float64(img[y1, x1, c]) - i10)
        orow[j, c] = scale * (top + ay * (bot - top))


@njit(cache=True, parallel=True, error_model="numpy")
def remap_bilinear(
    img: np.ndarray, map_uv: np.ndarray, scale: float, fill: float, out: np.ndarray
) -> None:  # pragma: no cover
    nb = img.shape[0]
    ho, wo = map_uv.shape[0], map_uv.shape[1]
    for r in prange(nb * ho):
        b = r // ho
        i = r - b * ho
        src = img[b]
        orow = out[b, i]
        mrow = map_uv[i]
        for j in range(wo):
            _sample(src, np.float64(mrow[j, 0]), np.float64(mrow[j, 1]), scale, fill, orow, j)


@njit(cache=True, parallel=True, error_model="numpy")
def undistort_brown_conrady(
    img: np.ndarray,
    k_new: np.ndarray,
    k_src: np.ndarray,
    coeffs: np.ndarray,
    scale: float,
    fill: float,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """Brown-Conrady (OpenCV's rational model, as ``bc_distort_point``) fused with sampling:
    the coefficients are hoisted, the row terms computed once per row, and the rational
    denominator skipped when ``k4 = k5 = k6 = 0``."""
    nb = out.shape[0]
    ho = out.shape[1]
    wo = out.shape[2]
    fxn, sn, cxn, fyn, cyn = k_new[0, 0], k_new[0, 1], k_new[0, 2], k_new[1, 1], k_new[1, 2]
    fx, s, cx, fy, cy = k_src[0, 0], k_src[0, 1], k_src[0, 2], k_src[1, 1], k_src[1, 2]
    k1, k2, p1, p2, k3 = coeffs[0], coeffs[1], coeffs[2], coeffs[3], coeffs[4]
    k4, k5, k6 = coeffs[5], coeffs[6], coeffs[7]
    rational = k4 != 0.0 or k5 != 0.0 or k6 != 0.0
    for r in prange(nb * ho):
        b = r // ho
        i = r - b * ho
        src = img[b]
        orow = out[b, i]
        y = (i - cyn) / fyn
        yy = y * y
        x_off = cxn + sn * y
        for j in range(wo):
            x = (j - x_off) / fxn
            r2 = x * x + yy
            radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
            if rational:
                radial = radial / (1.0 + r2 * (k4 + r2 * (k5 + r2 * k6)))
            xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
            yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * x * y
            _sample(src, fx * xd + s * yd + cx, fy * yd + cy, scale, fill, orow, j)
