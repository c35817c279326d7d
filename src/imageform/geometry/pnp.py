"""Camera pose from 3-D/2-D correspondences (PnP), batched over many problems.

:func:`solve_pnp` runs, for every problem of a batch at once (NumPy, no Python loop over
problems): a linear estimate — the normalised DLT of ``[R | t]`` for non-planar points, the
plane homography for planar ones — projected onto SO(3), then Levenberg-Marquardt on the
reprojection error in pixels, with the cheirality condition enforced (every point in front
of the camera; a mirrored pose behind the camera is never returned as valid).
:func:`solve_pnp_ransac` adds RANSAC for outliers (``pnp_ransac``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy, use_numba
from imageform._validate import (
    as_bool,
    as_int,
    as_matrix_bounded,
    as_points_bounded,
    check_K,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry.calibration_refine import rodrigues
from imageform.geometry.distortion import DistortionModel, _check_model
from imageform.geometry.rotations import matrix_to_rvec

__all__ = ["PnPResult", "solve_pnp"]

F64 = NDArray[np.float64]

#: Relative size of the third principal axis below which a point set counts as planar.
PLANAR_RTOL = 1e-6


class PnPResult(NamedTuple):
    """Poses of a batch of PnP problems (leading shape ``B`` = the problems' batch shape).

    ``rvec (B..., 3)``, ``tvec (B..., 3)``, ``R (B..., 3, 3)`` map world to camera
    (``X_c = R X + t``); ``rms (B...)`` is the reprojection RMS in pixels (of the
    undistorted points when a distortion model is given); ``valid (B...)`` is True where all
    points lie in front of the camera (``Z_c > 0``) and the fit is finite; ``inliers
    (B..., N)`` marks the points used (all True without RANSAC).
    """

    rvec: F64
    tvec: F64
    R: F64
    rms: F64
    valid: NDArray[np.bool_]
    inliers: NDArray[np.bool_]


def _normalised(uv: F64, K: F64, distortion: DistortionModel | None) -> F64:
    """Ideal normalised coordinates ``K⁻¹ (u, v, 1)``, undistorted when a model is given."""
    y = (uv[..., 1] - K[1, 2]) / K[1, 1]
    x = (uv[..., 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    xy = np.stack([x, y], axis=-1)
    if distortion is not None:
        xy, ok = distortion.undistort(xy)
        if not bool(np.all(ok)):
            raise InvalidInputError(
                f"{int(np.size(ok) - np.count_nonzero(ok))} image point(s) lie outside the "
                "valid radius of the distortion model (undistortion did not converge)"
            )
    return np.asarray(xy, dtype=np.float64)


def _procrustes(M: F64) -> F64:
    """Nearest rotation to each ``M`` (B, 3, 3) (SVD, det +1)."""
    U, _, Vt = np.linalg.svd(M)
    D = np.ones(M.shape[:-1])
    D[..., 2] = np.linalg.det(U @ Vt)
    return (U * D[..., None, :]) @ Vt


def _null_vector(A: F64) -> F64:
    """Return the unit ``x`` minimising ``‖A x‖`` for each ``A`` (B, m, n) (eigh of ``AᵀA``)."""
    return np.linalg.eigh(np.swapaxes(A, -1, -2) @ A)[1][..., 0]


def _linear_dlt(X: F64, xy: F64) -> tuple[F64, F64]:
    """``R, t`` (B, 3, 3), (B, 3) by the DLT of ``[R | t]`` on normalised coordinates.

    Hartley & Zisserman (2nd ed.) sec. 7.1 with known K; world points centred and scaled
    (their Algorithm 7.1 normalisation), ``R`` from the nearest rotation of the 3x3 block.
    """
    c = X.mean(axis=1, keepdims=True)
    s = np.sqrt(np.mean(np.sum((X - c) ** 2, axis=-1), axis=1))[:, None, None] / np.sqrt(3.0)
    Xn = (X - c) / s
    B, N, _ = X.shape
    Xh = np.concatenate([Xn, np.ones((B, N, 1))], axis=-1)
    x, y = xy[..., 0], xy[..., 1]
    # AᵀA of the 2N x 12 DLT matrix, from weighted sums of Xh Xhᵀ (no 2N x 12 temporary)
    O = (Xh[..., :, None] * Xh[..., None, :]).reshape(B, N, 16)
    wts = np.stack([np.ones_like(x), x, y, x * x + y * y], axis=1)  # (B, 4, N)
    S = (wts @ O).reshape(B, 4, 4, 4)
    # AᵀA = [[S0, 0, -S1], [0, S0, -S2], [-S1, -S2, S3]] acting on p = (p1, p2, p3), the rows
    # of P. For fixed p3 the minimum over p1, p2 is p1 = S0⁻¹ S1 p3, p2 = S0⁻¹ S2 p3, leaving
    # p3ᵀ (S3 - S1 S0⁻¹ S1 - S2 S0⁻¹ S2) p3 -> a 4x4 eigenproblem with |p3| = 1 (the scale of
    # the depth row) instead of a 12x12 one with |p| = 1; exact for noise-free data.
    S0i = np.linalg.inv(S[:, 0])
    G1, G2 = S0i @ S[:, 1], S0i @ S[:, 2]
    Mred = S[:, 3] - S[:, 1] @ G1 - S[:, 2] @ G2
    p3 = np.linalg.eigh(0.5 * (Mred + np.swapaxes(Mred, 1, 2)))[1][..., 0]
    P = np.stack([(G1 @ p3[..., None])[..., 0], (G2 @ p3[..., None])[..., 0], p3], axis=1)
    P = P * np.sign(np.linalg.det(P[:, :, :3]))[:, None, None]
    U, sv, Vt = np.linalg.svd(P[:, :, :3])
    D = np.ones((B, 3))
    D[:, 2] = np.linalg.det(U @ Vt)
    R = (U * D[:, None, :]) @ Vt
    lam = sv.mean(axis=-1) / s[:, 0, 0]
    t = P[:, :, 3] / lam[:, None] - (R @ c[:, 0, :, None])[..., 0]
    return R, t


def _linear_planar(X: F64, xy: F64) -> tuple[F64, F64]:
    """``R, t`` of planar point sets from the plane-to-image homography (Zhang 2000, sec. 3.1)."""
    B, N, _ = X.shape
    c = X.mean(axis=1, keepdims=True)
    E = np.linalg.svd(X - c)[2]  # rows: in-plane axes, then the normal
    E[:, 2] *= np.sign(np.linalg.det(E))[:, None]
    L = (X - c) @ np.swapaxes(E, 1, 2)
    s = np.sqrt(np.mean(np.sum(L[..., :2] ** 2, axis=-1), axis=1))[:, None, None]
    Lh = np.concatenate([L[..., :2] / s, np.ones((B, N, 1))], axis=-1)
    zero = np.zeros_like(Lh)
    x, y = xy[..., 0:1], xy[..., 1:2]
    A = np.concatenate(
        [
            np.concatenate([Lh, zero, -x * Lh], axis=-1),
            np.concatenate([zero, Lh, -y * Lh], axis=-1),
        ],
        axis=1,
    )
    H = _null_vector(A).reshape(B, 3, 3)
    scale = 0.5 * (np.linalg.norm(H[:, :, 0], axis=-1) + np.linalg.norm(H[:, :, 1], axis=-1))
    H = H / (scale * np.sign(H[:, 2, 2]))[:, None, None]  # board centre in front: t_z > 0
    r1, r2 = H[:, :, 0], H[:, :, 1]
    Rl = _procrustes(np.stack([r1, r2, np.cross(r1, r2)], axis=-1))
    tl = H[:, :, 2] * s[:, 0]
    R = Rl @ E
    t = tl - (R @ c[:, 0, :, None])[..., 0]
    return R, t


def _is_planar(X: F64) -> NDArray[np.bool_]:
    """Whether each point set (B, N, 3) is planar; raises if one is collinear or a point."""
    Xc = X - X.mean(axis=-2, keepdims=True)
    ev = np.linalg.eigvalsh(np.swapaxes(Xc, -1, -2) @ Xc)  # squared singular values
    line = ev[..., 1] <= PLANAR_RTOL**2 * ev[..., 2]
    if np.any(line):
        first = np.unravel_index(int(np.flatnonzero(line.ravel())[0]), line.shape)
        raise DegenerateConfigurationError(
            f"the object points of problem {tuple(int(i) for i in first)} are collinear (or "
            "all equal): the rotation about their line is undetermined"
        )
    return ev[..., 0] <= PLANAR_RTOL**2 * ev[..., 2]


def linear_pose(X: F64, xy: F64) -> tuple[F64, F64]:
    """Linear ``R, t`` for a flat batch (B, N, 3), (B, N, 2); planar and general mixed."""
    planar = _is_planar(X)
    B = X.shape[0]
    R = np.empty((B, 3, 3))
    t = np.empty((B, 3))
    for mask, fn, n_min in ((planar, _linear_planar, 4), (~planar, _linear_dlt, 6)):
        if np.any(mask):
            if X.shape[1] < n_min:
                kind = "planar" if fn is _linear_planar else "non-planar"
                raise DegenerateConfigurationError(
                    f"expected at least {n_min} points for a {kind} PnP problem, got {X.shape[1]}"
                )
            R[mask], t[mask] = fn(X[mask], xy[mask])
    return R, t


def _residuals(R: F64, t: F64, X: F64, uv: F64, K: F64) -> tuple[F64, F64]:
    cam = X @ np.swapaxes(R, -1, -2) + t[:, None, :]
    z = cam[..., 2]
    x, y = cam[..., 0] / z, cam[..., 1] / z
    r = np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], -1) - uv
    return r, cam


def refine_pose(
    R: F64, t: F64, X: F64, uv: F64, K: F64, w: F64, max_iter: int, tol: float = 1e-8
) -> tuple[F64, F64, F64]:
    """Batched LM on ``Σ w ‖π(K, R X + t) - u‖²`` (updates ``R ← exp([δω]×) R, t ← t + δt``).

    Steps that put a point with ``w > 0`` at or behind the camera are rejected. Returns
    ``R, t`` and the weighted RMS in pixels. NumPy input runs the numba kernel
    :func:`imageform._kernels.pnp.refine_pose_batch` (this function's plain twin otherwise).
    """
    if use_numba(X):
        from imageform._kernels.pnp import refine_pose_batch

        Ro, to = (
            np.ascontiguousarray(R, dtype=np.float64),
            np.ascontiguousarray(t, dtype=np.float64),
        )
        rms = np.empty(X.shape[0])
        refine_pose_batch(
            Ro,
            to,
            np.ascontiguousarray(X),
            np.ascontiguousarray(uv),
            K,
            np.ascontiguousarray(w, dtype=np.float64),
            int(max_iter),
            float(tol),
            rms,
        )
        return Ro, to, rms
    return _refine_pose_np(R, t, X, uv, K, w, max_iter, tol)


def _refine_pose_np(
    R: F64, t: F64, X: F64, uv: F64, K: F64, w: F64, max_iter: int, tol: float
) -> tuple[F64, F64, F64]:
    B = X.shape[0]
    r, cam = _residuals(R, t, X, uv, K)
    cost = np.sum(w * np.sum(r * r, -1), -1)
    lam = np.full(B, 1e-3)
    active = np.ones(B, dtype=bool)
    for _ in range(max_iter):
        z = cam[..., 2]
        iz = 1.0 / z
        x, y = cam[..., 0] * iz, cam[..., 1] * iz
        J = np.zeros(r.shape + (6,))
        # d(u, v)/d cam = [[fx/z, s/z, -(fx x + s y)/z], [0, fy/z, -fy y/z]]
        du = np.stack([K[0, 0] * iz, K[0, 1] * iz, -(K[0, 0] * x + K[0, 1] * y) * iz], -1)
        dv = np.stack([np.zeros_like(z), K[1, 1] * iz, -K[1, 1] * y * iz], -1)
        q = cam - t[:, None, :]  # R X; d cam / d δω = -[R X]x
        J[..., 0, 3:], J[..., 1, 3:] = du, dv
        J[..., 0, :3] = np.cross(q, du)  # du · (-[q]x) = (q x du)
        J[..., 1, :3] = np.cross(q, dv)
        Jr = J.reshape(B, -1, 6)
        JwT = np.swapaxes(Jr * np.repeat(w, 2, axis=1)[..., None], 1, 2)
        A = JwT @ Jr
        g = (JwT @ r.reshape(B, -1, 1))[..., 0]
        D = np.einsum("bii->bi", A).copy()
        D[D == 0] = 1.0
        step = -np.linalg.solve(A + lam[:, None, None] * (D[:, :, None] * np.eye(6)), g[..., None])[
            ..., 0
        ]
        step[~active] = 0.0
        Rn = rodrigues(step[:, :3]) @ R
        tn = t + step[:, 3:]
        rn, camn = _residuals(Rn, tn, X, uv, K)
        costn = np.sum(w * np.sum(rn * rn, -1), -1)
        front = np.all((camn[..., 2] > 0) | (w == 0), axis=-1)
        ok = active & front & np.isfinite(costn) & (costn <= cost)
        gain = cost - np.where(ok, costn, cost)
        R = np.where(ok[:, None, None], Rn, R)
        t = np.where(ok[:, None], tn, t)
        r = np.where(ok[:, None, None], rn, r)
        cam = np.where(ok[:, None, None], camn, cam)
        done = ok & (gain <= tol * cost)
        cost = np.where(ok, costn, cost)
        lam = np.where(ok, lam / 10.0, lam * 10.0)
        active &= ~done & (lam < 1e12)
        if not np.any(active):
            break
    rms = np.sqrt(cost / np.maximum(w.sum(axis=-1), 1.0))
    return R, t, rms


def _pnp_result(
    R: F64,
    t: F64,
    rms: F64,
    Xf: F64,
    batch: tuple[int, ...],
    points_shape: tuple[int, ...],
    out_dtype: npt.DTypeLike,
) -> PnPResult:
    """Pack the flat batch's poses as a :class:`PnPResult` of shape ``batch``.

    Valid where every point is in front of the camera and the RMS is finite; every point an
    inlier.
    """
    depth = np.einsum("bnj,bj->bn", Xf, R[:, 2, :]) + t[:, 2:3]
    valid = np.all(depth > 0, axis=-1) & np.isfinite(rms)
    rvec = np.asarray(matrix_to_rvec(R), dtype=np.float64)
    return PnPResult(
        rvec.reshape(*batch, 3).astype(out_dtype),
        t.reshape(*batch, 3).astype(out_dtype),
        R.reshape(*batch, 3, 3).astype(out_dtype),
        rms.reshape(batch).astype(out_dtype),
        valid.reshape(batch),
        np.ones(points_shape, dtype=bool),
    )


def _validate(
    object_points: Any, image_points: Any, K: Any, distortion: Any
) -> tuple[F64, F64, F64, tuple[int, ...], Any]:
    X0 = to_numpy(as_points_bounded(object_points, "object_points", 3))
    uv0 = to_numpy(as_points_bounded(image_points, "image_points", 2))
    # float32 in -> float32 out (computation in float64 either way)
    out_dtype = np.float32 if X0.dtype == uv0.dtype == np.float32 else np.float64
    X = np.asarray(X0, dtype=np.float64)
    uv = np.asarray(uv0, dtype=np.float64)
    Km = np.asarray(to_numpy(as_matrix_bounded(K, "K", (3, 3), batch=False)), dtype=np.float64)
    if X.ndim < 2 or X.shape[:-1] != uv.shape[:-1]:
        raise InvalidInputError(
            "expected object_points (..., N, 3) and image_points (..., N, 2) with the same "
            f"leading shape, got {X.shape} and {uv.shape}"
        )
    check_K(Km, np, "K", positive=True)
    Km = Km / Km[2, 2]
    _check_model(distortion)
    return X, uv, Km, X.shape[:-2], out_dtype


def solve_pnp(
    object_points: npt.ArrayLike,
    image_points: npt.ArrayLike,
    K: npt.ArrayLike,
    distortion: DistortionModel | None = None,
    *,
    refine: bool = True,
    max_iter: int = 20,
) -> PnPResult:
    r"""Pose ``(R, t)`` of a calibrated camera from N point correspondences, batched.

    Linear estimate on the ideal normalised coordinates ``(x, y) = K⁻¹ u`` (undistorted),
    then Levenberg-Marquardt on the pixel reprojection error

    .. math:: \min_{R, t} \sum_i \left\| \mathbf{u}_i - \pi\left(K (R \mathbf{X}_i
              + \mathbf{t})\right) \right\|^2 \quad \text{s.t. } (R\mathbf{X}_i
              + \mathbf{t})_z > 0

    Parameters
    ----------
    object_points : array_like (..., N, 3)
        World points; N >= 6 for a general set, N >= 4 for a planar one (each problem of the
        batch is classified on its own).
    image_points : array_like (..., N, 2)
        Their pixels.
    K : array_like (3, 3)
        Intrinsics, shared by the batch.
    distortion : BrownConrady, DivisionModel, KannalaBrandt or None
        Applied to the image points first (undistortion).
    refine : bool
        Run the LM refinement (otherwise the linear pose).
    max_iter : int
        LM iterations.

    Returns
    -------
    PnPResult
        ``rvec, tvec, R, rms, valid, inliers`` with leading shape ``(...)``.

    Raises
    ------
    InvalidInputError
        Shapes that do not match, NaN, a K that is not upper triangular.
    DegenerateConfigurationError
        Too few points for the linear method.

    Notes
    -----
    DLT with known K: Hartley & Zisserman, *Multiple View Geometry* 2nd ed., sec. 7.1;
    the planar case as Zhang (2000) sec. 3.1. ``valid`` is the cheirality check: a problem
    whose refined pose leaves a point at or behind the camera is reported invalid, not
    mirrored. Cross-checked against OpenCV's ``solvePnP`` in the tests.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5], [0.5, 0.2, 1], [0.1, 0.9, 0.7]])
    >>> uv = (X + [0, 0, 5]) @ K.T
    >>> res = solve_pnp(X, uv[:, :2] / uv[:, 2:], K)
    >>> (res.tvec.round(9) + 0.0).tolist(), bool(res.valid)
    ([0.0, 0.0, 5.0], True)
    """
    refine = as_bool(refine, "refine")
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    X, uv, Km, batch, out_dtype = _validate(object_points, image_points, K, distortion)
    N = X.shape[-2]
    Xf = X.reshape(-1, N, 3)
    uvf = uv.reshape(-1, N, 2)
    xy = _normalised(uvf, Km, distortion)
    R, t = linear_pose(Xf, xy)
    uv_ideal = np.stack(
        [
            Km[0, 0] * xy[..., 0] + Km[0, 1] * xy[..., 1] + Km[0, 2],
            Km[1, 1] * xy[..., 1] + Km[1, 2],
        ],
        axis=-1,
    )
    w = np.ones(Xf.shape[:2])
    if refine:
        R, t, rms = refine_pose(R, t, Xf, uv_ideal, Km, w, max_iter)
    else:
        r, _ = _residuals(R, t, Xf, uv_ideal, Km)
        rms = np.sqrt(np.mean(np.sum(r * r, -1), -1))
    return _pnp_result(R, t, rms, Xf, batch, X.shape[:-1], out_dtype)
