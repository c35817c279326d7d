"""Numba kernel: bilinear remapping of a batch of channels-last images.

``out[b, i, j, c]`` samples ``img[b, :, :, c]`` at the source position
``(u, v) = (map_u[i, j], map_v[i, j])`` (column, row; the centre of the top-left pixel is
``(0, 0)``) by bilinear interpolation. Positions outside ``[0, W-1] × [0, H-1]`` or NaN get
``fill``. The plain twin is :func:`imageform.geometry.undistort._remap_bilinear_numpy`; a test
checks agreement to 1e-12 (float64).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = ["remap_bilinear"]


@njit(cache=True, parallel=True)
def remap_bilinear(
    img: np.ndarray, map_u: np.ndarray, map_v: np.ndarray, fill: float, out: np.ndarray
) -> None:  # pragma: no cover
    nb, h, w, nc = img.shape
    ho, wo = map_u.shape
    for i in prange(ho):
        for j in range(wo):
            u = map_u[i, j]
            v = map_v[i, j]
            if not (u >= 0.0 and u <= w - 1.0 and v >= 0.0 and v <= h - 1.0):
                for b in range(nb):
                    for c in range(nc):
                        out[b, i, j, c] = fill
                continue
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
