"""Triangulation of 3-D points from two or more calibrated views, with uncertainty.

:func:`triangulate_points` runs the linear (DLT) triangulation of every point at once, then
Gauss-Newton/Levenberg-Marquardt on the reprojection error, and returns the first-order
covariance of each point from the Jacobian.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._validate import (
    MAX_MAGNITUDE,
    as_bool,
    as_int,
    as_matrix_bounded,
    as_points_bounded,
    as_real,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = ["TriangulationResult", "triangulate_points"]

F64 = NDArray[np.float64]


class TriangulationResult(NamedTuple):
    """Triangulated points ``(M, 3)``, their covariances, reprojection RMS and validity.

    The covariances are ``(M, 3, 3)`` (world units²), the reprojection RMS per point ``(M,)``
    in pixels, and ``valid (M,)``: in front of every camera that sees it and finite. A point
    whose rays are parallel (no baseline) has no finite solution: NaN, covariance inf,
    ``valid`` False.
    """

    points: F64
    covariance: F64
    rms: F64
    valid: NDArray[np.bool_]


def _project(P: F64, X: F64) -> tuple[F64, F64]:
    """Pixels (M, V, 2) and depths (M, V) of points X (M, 3) in cameras P (V, 3, 4)."""
    h = np.einsum("vij,mj->mvi", P[:, :, :3], X) + P[None, :, :, 3]
    with np.errstate(divide="ignore", invalid="ignore"):  # depth 0: NaN, judged by callers
        return h[..., :2] / h[..., 2:3], h[..., 2]


def _linear(P: F64, uv: F64, seen: NDArray[np.bool_]) -> F64:
    """DLT triangulation (Hartley & Zisserman 2nd ed., sec. 12.2), rows scaled to unit norm."""
    u, v = uv[..., 0:1], uv[..., 1:2]
    u = np.where(seen[..., None], u, 0.0)
    v = np.where(seen[..., None], v, 0.0)
    r1 = u * P[None, :, 2, :] - P[None, :, 0, :]
    r2 = v * P[None, :, 2, :] - P[None, :, 1, :]
    A = np.concatenate([r1, r2], axis=1)  # (M, 2V, 4)
    A = A / np.linalg.norm(A, axis=-1, keepdims=True)
    A = A * np.concatenate([seen, seen], axis=1)[..., None]
    lam, vec = np.linalg.eigh(np.swapaxes(A, 1, 2) @ A)
    w = vec[..., 0]
    # Parallel rays (no baseline) leave a null space of dimension 2 (the ray and the camera
    # centre): any vector in it solves the DLT, so the solution is undefined, not the camera
    # centre that eigh may happen to return. Rank is judged at rounding level.
    rank_deficient = lam[:, 1] <= 64 * np.finfo(float).eps * lam[:, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        X = w[:, :3] / w[:, 3:4]  # inf/NaN: a point at infinity (parallel rays)
    X[rank_deficient] = np.nan
    return X


def triangulate_points(
    projection_matrices: npt.ArrayLike,
    image_points: npt.ArrayLike,
    *,
    refine: bool = True,
    sigma: float = 1.0,
    max_iter: int = 20,
) -> TriangulationResult:
    r"""3-D points from their pixels in V >= 2 calibrated views: DLT, then LM, with covariance.

    .. math::

        \hat{\mathbf{X}} = \arg\min_{\mathbf{X}} \sum_{v}
        \left\| \mathbf{u}_v - \pi(P_v \tilde{\mathbf{X}}) \right\|^2, \qquad
        \Sigma_{\mathbf{X}} = \sigma^2 (J^T J)^{-1}

    Parameters
    ----------
    projection_matrices : array_like (V, 3, 4)
        Camera matrices ``P_v = K_v [R_v | t_v]`` (pixels; undistort the points first).
    image_points : array_like (V, M, 2)
        Pixels of the M points in each view; NaN marks a point a view does not see (each
        point needs two views).
    refine : bool
        Refine the linear estimate on the reprojection error.
    sigma : float
        Standard deviation of the image points (pixels) for the covariance.
    max_iter : int
        LM iterations.

    Returns
    -------
    TriangulationResult
        ``points (M, 3)``, ``covariance (M, 3, 3)``, ``rms (M,)``, ``valid (M,)``.

    Raises
    ------
    InvalidInputError
        Wrong shapes, NaN/inf in P, fewer than 2 views.
    DegenerateConfigurationError
        A point seen by fewer than 2 views.

    Notes
    -----
    Linear method: Hartley & Zisserman, *Multiple View Geometry* 2nd ed., sec. 12.2; the
    covariance is the first-order back-propagation of sec. 5.2.3 (result 5.10). Points with
    two nearly parallel rays get a large covariance, not an error. Cross-checked against
    OpenCV's ``triangulatePoints`` in the tests. Each ``P`` is scaled to
    ``det P[:, :3] > 0`` so that the third coordinate of ``P X̃`` is the depth.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> P1 = K @ np.hstack([np.eye(3), np.zeros((3, 1))])
    >>> P2 = K @ np.hstack([np.eye(3), [[-1.0], [0], [0]]])
    >>> X = np.array([[0.2, -0.1, 5.0]])
    >>> uv = [(X @ P[:, :3].T + P[:, 3])[:, :2] / (X @ P[:, :3].T + P[:, 3])[:, 2:]
    ...       for P in (P1, P2)]
    >>> res = triangulate_points([P1, P2], uv)
    >>> res.points.round(9).tolist(), bool(res.valid[0])
    ([[0.2, -0.1, 5.0]], True)
    """
    P = np.asarray(
        to_numpy(as_matrix_bounded(projection_matrices, "projection_matrices", (3, 4))), float
    )
    uv0 = to_numpy(as_points_bounded(image_points, "image_points", 2, finite=False))
    out_dtype = np.float32 if uv0.dtype == np.float32 else np.float64  # float32 in -> out
    uv = np.asarray(uv0, dtype=np.float64)
    if P.ndim != 3 or uv.ndim != 3 or uv.shape[0] != P.shape[0]:
        raise InvalidInputError(
            "expected projection_matrices (V, 3, 4) and image_points (V, M, 2) with the same V, "
            f"got {P.shape} and {uv.shape}"
        )
    if P.shape[0] < 2:
        raise InvalidInputError(
            f"expected projection_matrices of at least 2 views, got {P.shape[0]}"
        )
    if np.any(np.isinf(uv)):
        raise InvalidInputError("image_points contains inf (use NaN for a missing observation)")
    if uv.size and not np.all(np.isnan(uv)) and float(np.nanmax(np.abs(uv))) > MAX_MAGNITUDE:
        raise InvalidInputError(
            f"expected image_points with magnitudes <= {MAX_MAGNITUDE:g}, got "
            f"{float(np.nanmax(np.abs(uv))):g}"
        )
    s = as_real(sigma, "sigma", positive=True, maximum=1e100)
    refine = as_bool(refine, "refine")
    max_iter = as_int(max_iter, "max_iter", minimum=0, maximum=10**6)
    det = np.linalg.det(P[:, :, :3])
    if np.any(det == 0):
        raise DegenerateConfigurationError("a projection matrix has a singular left 3x3 block")
    P = P * np.sign(det)[:, None, None]
    obs = np.swapaxes(uv, 0, 1)  # (M, V, 2)
    seen = np.all(np.isfinite(obs), axis=-1)
    n_seen = seen.sum(axis=1)
    if np.any(n_seen < 2):
        bad = np.flatnonzero(n_seen < 2)
        raise DegenerateConfigurationError(
            f"{bad.size} point(s) are seen in fewer than 2 views (first: index {bad[0]})"
        )
    obs = np.where(seen[..., None], obs, 0.0)
    wgt = seen.astype(float)
    X = _linear(P, obs, seen)
    finite = np.all(np.isfinite(X), axis=1)  # False: rays parallel (e.g. no baseline)
    X = np.where(finite[:, None], X, 0.0)
    M = X.shape[0]

    def cost_of(Xc: F64) -> tuple[F64, F64, F64]:
        pr, depth = _project(P, Xc)
        r = (pr - obs) * wgt[..., None]
        return np.sum(r * r, axis=(1, 2)), r, depth

    def jacobian(Xc: F64) -> F64:
        pr, depth = _project(P, Xc)
        J = (P[None, :, :2, :3] - pr[..., None] * P[None, :, 2:3, :3]) / depth[..., None, None]
        return (J * wgt[..., None, None]).reshape(M, -1, 3)

    cost, r, depth = cost_of(X)
    if refine:
        lam = np.full(M, 1e-3)
        active = finite.copy()
        for _ in range(max_iter):
            J = jacobian(X)
            A = np.swapaxes(J, 1, 2) @ J
            g = (np.swapaxes(J, 1, 2) @ r.reshape(M, -1, 1))[..., 0]
            D = np.einsum("mii->mi", A) * lam[:, None]
            Areg = A + D[..., None] * np.eye(3)
            # a point whose rays are (nearly) parallel or that is not active has a singular
            # system: it must not stop the batch (numpy's solve raises for any one of them)
            Areg[~active] = np.eye(3)
            tr = np.einsum("mii->m", Areg)
            Areg += (1e-14 * np.abs(tr) + 1e-300)[:, None, None] * np.eye(3)
            with np.errstate(all="ignore"):
                step = -np.linalg.solve(Areg, g[..., None])[..., 0]
            Xn = X + np.where(active[:, None], step, 0.0)
            cn, rn, dn = cost_of(Xn)
            front = np.all((dn > 0) | ~seen, axis=1)
            ok = active & front & np.isfinite(cn) & (cn <= cost)
            done = ok & (cost - cn <= 1e-12 * cost)
            X = np.where(ok[:, None], Xn, X)
            r = np.where(ok[:, None, None], rn, r)
            depth = np.where(ok[:, None], dn, depth)
            cost = np.where(ok, cn, cost)
            lam = np.where(ok, lam / 10.0, lam * 10.0)
            active &= ~done & (lam < 1e12)
            if not np.any(active):
                break
    J = jacobian(X)
    cov = np.full((M, 3, 3), np.inf)
    JtJ = np.swapaxes(J, 1, 2) @ J
    ok = finite & np.all(np.isfinite(JtJ), axis=(1, 2))
    cov[ok] = s**2 * np.linalg.pinv(JtJ[ok])
    rms = np.sqrt(cost / n_seen)
    valid = np.all((depth > 0) | ~seen, axis=1) & finite
    X[~finite] = np.nan
    rms[~finite] = np.nan
    return TriangulationResult(
        X.astype(out_dtype), cov.astype(out_dtype), rms.astype(out_dtype), valid
    )
