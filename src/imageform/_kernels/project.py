"""Pinhole projection of large point clouds (numba), with its plain array twin.

``project_pinhole(points, P3x4_K, R, t)`` computes, for each row ``X`` of ``points``::

    Xc = R @ X + t;  valid = Xc_z > 0, Xc and (u, v) finite;  u = fx x + s y + cx, v = fy y + cy

with ``x = Xc_x / Xc_z``, ``y = Xc_y / Xc_z``; invalid points get NaN. The twin is
:func:`imageform.geometry.camera._project_xp`; ``tests/geometry/test_camera.py`` checks that
they agree to 1e-12 px in float64.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from imageform._kernels.jit import njit

__all__ = ["project_pinhole"]


@njit(parallel=True, fastmath=False, nogil=True)
def _project_kernel(pts, K, R, t, uv, valid):  # type: ignore[no-untyped-def]  # pragma: no cover
    n = pts.shape[0]
    fx = K[0, 0]
    s = K[0, 1]
    cx = K[0, 2]
    fy = K[1, 1]
    cy = K[1, 2]
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    t0, t1, t2 = t[0], t[1], t[2]
    nan = np.nan
    for i in prange(n):
        X = pts[i, 0]
        Y = pts[i, 1]
        Z = pts[i, 2]
        xc = r00 * X + r01 * Y + r02 * Z + t0
        yc = r10 * X + r11 * Y + r12 * Z + t1
        zc = r20 * X + r21 * Y + r22 * Z + t2
        u = nan
        v = nan
        if 0.0 < zc < np.inf:  # a NaN/inf xc or yc gives a NaN/inf u or v (fx, fy != 0)
            x = xc / zc
            y = yc / zc
            u = fx * x + s * y + cx
            v = fy * y + cy
        ok = np.isfinite(u) and np.isfinite(v)  # a projection that overflows is invalid
        uv[i, 0] = u if ok else nan
        uv[i, 1] = v if ok else nan
        valid[i] = ok


def project_pinhole(
    points: np.ndarray, K: np.ndarray, R: np.ndarray, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Project ``points`` ``(N, 3)`` (float32 or float64, any strides) through K, R, t.

    Returns ``uv`` ``(N, 2)`` in the points' dtype and ``valid`` ``(N,)`` bool.
    """
    dtype = points.dtype
    pts = np.ascontiguousarray(points)
    uv = np.empty((pts.shape[0], 2), dtype=dtype)
    valid = np.empty(pts.shape[0], dtype=np.bool_)
    _project_kernel(
        pts,
        np.ascontiguousarray(K, dtype=dtype),
        np.ascontiguousarray(R, dtype=dtype),
        np.ascontiguousarray(t, dtype=dtype),
        uv,
        valid,
    )
    return uv, valid
