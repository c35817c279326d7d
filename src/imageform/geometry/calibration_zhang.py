"""Closed-form initial values for camera calibration (private helpers of ``calibration``).

- :func:`zhang_intrinsics` — K from the homographies of a planar pattern (Zhang 2000, sec. 3.1
  and appendix B), with or without skew, in pixel coordinates normalised for conditioning.
- :func:`pose_from_homography` — ``R, t`` of one view from ``H`` and ``K`` (Zhang sec. 3.1).
- :func:`dlt_init` — K and poses of a non-planar rig from per-view DLT camera matrices.

All inputs are clean NumPy float64 arrays (validated by the public functions).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform.errors import DegenerateConfigurationError
from imageform.geometry.calibration_views import _views
from imageform.geometry.camera import decompose_projection_matrix
from imageform.geometry.dlt import estimate_projection_matrix
from imageform.geometry.homography import _homographies_padded
from imageform.geometry.rotations import matrix_to_rvec

__all__ = [
    "centre_intrinsics",
    "dlt_init",
    "homographies",
    "homographies_of",
    "poses_from_homographies",
    "zhang_intrinsics",
]

F64 = NDArray[np.float64]


def _checked(object_points: Any, image_points: Any) -> tuple[list[F64], list[F64]]:
    """Check the views as :func:`~imageform.geometry.calibrate_camera` does.

    One pass over the small point arrays.
    """
    return _views(object_points, image_points)


def homographies(object_points: list[F64], image_points: list[F64]) -> F64:
    """``H_k`` (V, 3, 3) with ``image ~ H_k (X, Y, 1)`` for every view (normalised DLT).

    The views are checked (as :func:`~imageform.geometry.calibrate_camera` does), then
    :func:`homographies_of`.
    """
    object_points, image_points = _checked(object_points, image_points)
    return homographies_of(object_points, image_points)


def homographies_of(object_points: list[F64], image_points: list[F64]) -> F64:
    """``H_k`` (V, 3, 3) of views already checked (:func:`homographies` checks them first).

    The views padded to one batch and solved by
    :func:`~imageform.geometry.homography._homographies_padded`:
    :func:`~imageform.geometry.estimate_homography`'s normalised DLT (Hartley & Zisserman
    Algorithm 4.2) of every view at once, a doubtful view on its own (refused with the same
    message as alone).
    """
    sizes = np.array([o.shape[0] for o in object_points])
    mask = np.arange(int(sizes.max()))[None, :] < sizes[:, None]
    src = np.zeros((*mask.shape, 2))
    dst = np.zeros((*mask.shape, 2))
    src[mask] = np.concatenate([o[:, :2] for o in object_points])
    dst[mask] = np.concatenate(image_points)
    return _homographies_padded(src, dst, sizes)


def _v(H: F64, i: int, j: int) -> F64:
    hi, hj = H[:, :, i], H[:, :, j]
    return np.stack(
        [
            hi[:, 0] * hj[:, 0],
            hi[:, 0] * hj[:, 1] + hi[:, 1] * hj[:, 0],
            hi[:, 1] * hj[:, 1],
            hi[:, 2] * hj[:, 0] + hi[:, 0] * hj[:, 2],
            hi[:, 2] * hj[:, 1] + hi[:, 1] * hj[:, 2],
            hi[:, 2] * hj[:, 2],
        ],
        axis=-1,
    )


def _centre_focal(Hn: F64) -> tuple[float, float]:
    """fx, fy with the principal point at the origin and no skew (as OpenCV's initialiser)."""
    rows, rhs = [], []
    for H in Hn:
        h1, h2 = H[:, 0], H[:, 1]
        # h1ᵀ ω h2 = 0 and h1ᵀ ω h1 = h2ᵀ ω h2 with ω = diag(1/fx², 1/fy², 1)
        rows.append([h1[0] * h2[0], h1[1] * h2[1]])
        rhs.append(-h1[2] * h2[2])
        rows.append([h1[0] ** 2 - h2[0] ** 2, h1[1] ** 2 - h2[1] ** 2])
        rhs.append(-(h1[2] ** 2 - h2[2] ** 2))
    a, *_ = np.linalg.lstsq(np.asarray(rows), np.asarray(rhs), rcond=None)
    if not np.all(a > 0):
        raise DegenerateConfigurationError(
            "the views do not determine the focal length (the board is seen without tilt "
            "in every view, or the homographies are inconsistent)"
        )
    return float(1.0 / np.sqrt(a[0])), float(1.0 / np.sqrt(a[1]))


def zhang_intrinsics(H: F64, image_size: tuple[int, int], *, skew: bool) -> F64:
    """Closed-form K from plane homographies (Zhang 2000, eqs. (8)-(9) and appendix B).

    Each view gives ``v12ᵀ b = 0`` and ``(v11 - v22)ᵀ b = 0`` on the image of the absolute
    conic ``B = K⁻ᵀ K⁻¹``; without skew ``B12 = 0`` is added. Pixels are first mapped to
    ``[-1, 1]`` (``N``) for conditioning. With too few views for the closed form (fewer than 3,
    or 2 without skew) or an indefinite ``B``, the principal point is put at the image centre
    and only ``fx, fy`` are solved for.
    """
    w, h = image_size
    s = 2.0 / max(w, h)
    N = np.array([[s, 0.0, -s * (w - 1) / 2], [0.0, s, -s * (h - 1) / 2], [0.0, 0.0, 1.0]])
    Hn = N @ H
    Hn = Hn / np.linalg.norm(Hn, axis=(1, 2), keepdims=True)
    n_views = Hn.shape[0]
    Kn = None
    if n_views >= (3 if skew else 2):
        V = np.concatenate([_v(Hn, 0, 1), _v(Hn, 0, 0) - _v(Hn, 1, 1)], axis=0)
        if not skew:
            V = np.concatenate([V, np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]]) * len(V)])
        b = np.linalg.svd(V)[2][-1]
        B11, B12, B22, B13, B23, B33 = b
        den = B11 * B22 - B12**2
        if B11 != 0 and den != 0:
            v0 = (B12 * B13 - B11 * B23) / den
            lam = B33 - (B13**2 + v0 * (B12 * B13 - B11 * B23)) / B11
            a2, b2 = lam / B11, lam * B11 / den
            if a2 > 0 and b2 > 0:
                alpha, beta = np.sqrt(a2), np.sqrt(b2)
                gamma = -B12 * alpha**2 * beta / lam if skew else 0.0
                u0 = gamma * v0 / beta - B13 * alpha**2 / lam
                Kn = np.array([[alpha, gamma, u0], [0.0, beta, v0], [0.0, 0.0, 1.0]])
    if Kn is None:
        fx, fy = _centre_focal(Hn)
        Kn = np.array([[fx, 0.0, 0.0], [0.0, fy, 0.0], [0.0, 0.0, 1.0]])
    K = np.linalg.solve(N, Kn)
    return K / K[2, 2]


def centre_intrinsics(H: F64, image_size: tuple[int, int]) -> F64:
    """K with the principal point at the image's centre and ``fx, fy`` from the homographies.

    OpenCV's ``initIntrinsicParams2D`` start: each view's ``h1ᵀ ω h2 = 0`` and
    ``h1ᵀ ω h1 = h2ᵀ ω h2`` with ``ω = diag(1/fx², 1/fy², 1)`` in pixels centred on
    ``((w - 1)/2, (h - 1)/2)`` (Zhang 2000, eqs. (3)-(4) with the principal point known).
    Where the views leave the principal point ill-determined (little tilt, or tilt about one
    axis only), Zhang's closed form can put it thousands of pixels away, a start the
    refinement does not recover from; this one stays near any real lens's.
    """
    w, h = image_size
    s = 2.0 / max(w, h)
    N = np.array([[s, 0.0, -s * (w - 1) / 2], [0.0, s, -s * (h - 1) / 2], [0.0, 0.0, 1.0]])
    Hn = N @ H
    Hn = Hn / np.linalg.norm(Hn, axis=(1, 2), keepdims=True)
    fx, fy = _centre_focal(Hn)
    K = np.linalg.solve(N, np.array([[fx, 0.0, 0.0], [0.0, fy, 0.0], [0.0, 0.0, 1.0]]))
    return K / K[2, 2]


def poses_from_homographies(H: F64, K: F64) -> tuple[F64, F64]:
    """``rvecs, tvecs`` (V, 3) of a plane ``Z = 0`` from ``H_k ~ K [r1 r2 t]`` (Zhang sec. 3.1).

    ``λ = 1 / ‖K⁻¹ h1‖`` with the sign that puts the board in front (``t_z > 0``); the
    rotation ``[r1 r2 r1×r2]`` is projected on SO(3) by SVD.
    """
    A = np.linalg.solve(K, H)
    lam = 1.0 / np.linalg.norm(A[:, :, 0], axis=-1)
    lam = np.where(A[:, 2, 2] * lam < 0, -lam, lam)[:, None]
    r1, r2, t = lam * A[:, :, 0], lam * A[:, :, 1], lam * A[:, :, 2]
    Rm = np.stack([r1, r2, np.cross(r1, r2)], axis=-1)
    U, _, Vt = np.linalg.svd(Rm)
    D = np.ones((H.shape[0], 3))
    D[:, 2] = np.linalg.det(U @ Vt)
    R = (U * D[:, None, :]) @ Vt
    return np.asarray(matrix_to_rvec(R), dtype=np.float64), t


def dlt_init(object_points: list[F64], image_points: list[F64]) -> tuple[F64, F64, F64]:
    """K (mean over views) and per-view ``rvecs, tvecs`` of a non-planar rig by the DLT.

    Each view's ``P_k`` (Hartley & Zisserman Algorithm 7.1) is split by RQ into
    ``K_k [R_k | t_k]``; the initial K is the mean of the ``K_k`` and the poses are each
    view's own (the refinement then makes them consistent).
    """
    object_points, image_points = _checked(object_points, image_points)
    Ks, rv, tv = [], [], []
    for o, i in zip(object_points, image_points, strict=True):
        P = np.asarray(estimate_projection_matrix(o, i), dtype=np.float64)
        K, R, t = decompose_projection_matrix(P)
        Ks.append(np.asarray(K))
        rv.append(np.asarray(matrix_to_rvec(R)))
        tv.append(np.asarray(t))
    return np.mean(Ks, axis=0), np.stack(rv), np.stack(tv)
