"""Numba kernels: bilinear remapping of a batch of channels-last images.

``remap_bilinear``: ``out[b, i, j, c]`` samples ``img[b, :, :, c]`` at the source position
``(u, v) = (map_u[i, j], map_v[i, j])`` (column, row; the centre of the top-left pixel is
``(0, 0)``) by bilinear interpolation. Positions outside ``[0, W-1] × [0, H-1]`` or NaN get
``fill``. ``undistort_brown_conrady`` fuses the source-position computation of
:func:`imageform.geometry.undistort.undistortion_map` for Brown-Conrady with the sampling.
The plain twin of both is :func:`imageform.geometry.undistort._remap_bilinear_numpy` on the
map from :func:`~imageform.geometry.undistort.undistortion_map`; tests check agreement to
1e-12 (float64).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from imageform._kernels.distortion import bc_distort_point

__all__ = ["remap_bilinear", "undistort_brown_conrady"]


@njit(cache=True, inline="always")
def _sample(
    img: np.ndarray, u: float, v: float, fill: float, out: np.ndarray, i: int, j: int
) -> None:
    nb, h, w, nc = img.shape
    if not (u >= 0.0 and u <= w - 1.0 and v >= 0.0 and v <= h - 1.0):
        for b in range(nb):
            for c in range(nc):
                out[b, i, j, c] = fill
        return
    x0 = min(math.floor(u), w - 1)
    y0 = min(math.floor(v), h - 1)
    x1 = min(x0 + 1, w - 1)
    y1 = min(y0 + 1, h - 1)
    ax = u - x0
    ay = v - y0
    w00 = (1.0 - ax) * (1.0 - ay)
    w01 = ax * (1.0 - ay)
    w10 = (1.0 - ax) * ay
    w11 = ax * ay
    for b in range(nb):
        for c in range(nc):
            out[b, i, j, c] = (
                w00 * img[b, y0, x0, c]
                + w01 * img[b, y0, x1, c]
                + w10 * img[b, y1, x0, c]
                + w11 * img[b, y1, x1, c]
            )


@njit(cache=True, parallel=True)
def remap_bilinear(
    img: np.ndarray, map_u: np.ndarray, map_v: np.ndarray, fill: float, out: np.ndarray
) -> None:  # pragma: no cover
    ho, wo = map_u.shape
    for i in prange(ho):
        for j in range(wo):
            _sample(img, map_u[i, j], map_v[i, j], fill, out, i, j)


@njit(cache=True, parallel=True)
def undistort_brown_conrady(
    img: np.ndarray,
    k_new: np.ndarray,
    k_src: np.ndarray,
    coeffs: np.ndarray,
    fill: float,
    out: np.ndarray,
) -> None:  # pragma: no cover
    ho = out.shape[1]
    wo = out.shape[2]
    fxn, sn, cxn, fyn, cyn = k_new[0, 0], k_new[0, 1], k_new[0, 2], k_new[1, 1], k_new[1, 2]
    fx, s, cx, fy, cy = k_src[0, 0], k_src[0, 1], k_src[0, 2], k_src[1, 1], k_src[1, 2]
    for i in prange(ho):
        y = (i - cyn) / fyn
        for j in range(wo):
            x = (j - cxn - sn * y) / fxn
            xd, yd = bc_distort_point(x, y, coeffs)
            _sample(img, fx * xd + s * yd + cx, fy * yd + cy, fill, out, i, j)
