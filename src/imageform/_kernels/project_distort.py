"""Fused numba kernel: world points → camera → Brown-Conrady distortion → pixels.

One pass over the points, no temporaries: ``X_cam = R X + t``, ``(x, y) = (X/Z, Y/Z)``,
Brown-Conrady (OpenCV order ``k1, k2, p1, p2, k3, k4, k5, k6``), then ``K`` (skew included).
Points with ``Z <= 0`` (at or behind the camera) come back as NaN with ``valid = False``;
they are never projected as if in front. The plain twin is
:func:`imageform.geometry.distortion._project_xp`; a test checks agreement to 1e-9 px.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from imageform._kernels.distortion import bc_distort_point
from imageform._kernels.jit import njit

__all__ = ["project_brown_conrady", "project_brown_conrady_into"]


@njit(parallel=True)
def project_brown_conrady_into(
    pts: np.ndarray,
    K: np.ndarray,
    R: np.ndarray,
    t: np.ndarray,
    c: np.ndarray,
    uv: np.ndarray,
    valid: np.ndarray,
) -> None:  # pragma: no cover
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    t0, t1, t2 = t[0], t[1], t[2]
    fx, s, cx = K[0, 0], K[0, 1], K[0, 2]
    fy, cy = K[1, 1], K[1, 2]
    for i in prange(pts.shape[0]):
        X = pts[i, 0]
        Y = pts[i, 1]
        Z = pts[i, 2]
        zc = r20 * X + r21 * Y + r22 * Z + t2
        if zc > 0.0:
            inv = 1.0 / zc
            x = (r00 * X + r01 * Y + r02 * Z + t0) * inv
            y = (r10 * X + r11 * Y + r12 * Z + t1) * inv
            xd, yd = bc_distort_point(x, y, c)
            uv[i, 0] = fx * xd + s * yd + cx
            uv[i, 1] = fy * yd + cy
            valid[i] = True
        else:
            uv[i, 0] = np.nan
            uv[i, 1] = np.nan
            valid[i] = False


def project_brown_conrady(
    points_world: np.ndarray,
    K: np.ndarray,
    R: np.ndarray,
    t: np.ndarray,
    coeffs: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Project ``(N, 3)`` float64 world points; returns ``(uv (N, 2), valid (N,))``.

    Inputs must already be validated: C-contiguous float64, ``K``/``R`` ``(3, 3)``, ``t``
    ``(3,)``, ``coeffs`` ``(8,)`` in OpenCV order.
    """
    pts = np.ascontiguousarray(points_world, dtype=np.float64)
    uv = np.empty((pts.shape[0], 2), dtype=np.float64)
    valid = np.empty(pts.shape[0], dtype=np.bool_)
    project_brown_conrady_into(
        pts,
        np.ascontiguousarray(K, dtype=np.float64),
        np.ascontiguousarray(R, dtype=np.float64),
        np.ascontiguousarray(t, dtype=np.float64).reshape(3),
        np.ascontiguousarray(coeffs, dtype=np.float64).reshape(8),
        uv,
        valid,
    )
    return uv, valid
