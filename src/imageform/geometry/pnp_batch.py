"""PnP for a batch of problems, each with its own intrinsics ``K``.

:func:`~imageform.geometry.solve_pnp` shares one ``K`` across its batch (one camera, many
frames). :func:`solve_pnp_batch` takes ``K (..., 3, 3)`` per problem (many cameras, or a
zoom lens whose K changes per frame): the same linear estimate on normalised coordinates,
then a Levenberg-Marquardt on the pixel reprojection error of every problem at once.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._validate import as_bool, as_int, as_matrix, as_points
from imageform.errors import InvalidInputError
from imageform.geometry.calibration_refine import rodrigues
from imageform.geometry.pnp import PnPResult, _pnp_result, linear_pose

__all__ = ["solve_pnp_batch"]

F64 = NDArray[np.float64]


def _residuals(R: F64, t: F64, X: F64, uv: F64, K: F64) -> tuple[F64, F64]:
    """Pixel residuals (B, N, 2) and camera points (B, N, 3), ``K`` (B, 3, 3)."""
    cam = X @ np.swapaxes(R, -1, -2) + t[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = cam[..., 0] / cam[..., 2], cam[..., 1] / cam[..., 2]
    k = K[:, None]
    u = k[..., 0, 0] * x + k[..., 0, 1] * y + k[..., 0, 2]
    v = k[..., 1, 1] * y + k[..., 1, 2]
    return np.stack([u, v], -1) - uv, cam


def _refine(
    R: F64, t: F64, X: F64, uv: F64, K: F64, max_iter: int, tol: float = 1e-10
) -> tuple[F64, F64, F64]:
    """Refine by batched LM on ``Σ ‖π(K_b (R X + t)) - u‖²``.

    Updates are ``R ← exp([δω]ₓ) R``, ``t ← t + δt``; steps that put a point at or behind the
    camera are rejected.
    """
    B = X.shape[0]
    r, cam = _residuals(R, t, X, uv, K)
    cost = np.sum(r * r, axis=(-2, -1))
    lam = np.full(B, 1e-3)
    active = np.isfinite(cost)
    fx, s, fy = K[:, None, 0, 0], K[:, None, 0, 1], K[:, None, 1, 1]
    for _ in range(max_iter):
        iz = 1.0 / cam[..., 2]
        x, y = cam[..., 0] * iz, cam[..., 1] * iz
        du = np.stack([fx * iz, s * iz, -(fx * x + s * y) * iz], -1)
        dv = np.stack([np.zeros_like(iz), fy * iz, -fy * y * iz], -1)
        q = cam - t[:, None, :]
        J = np.empty(r.shape + (6,))
        J[..., 0, :3], J[..., 1, :3] = np.cross(q, du), np.cross(q, dv)
        J[..., 0, 3:], J[..., 1, 3:] = du, dv
        Jr = J.reshape(B, -1, 6)
        A = np.swapaxes(Jr, 1, 2) @ Jr
        g = (np.swapaxes(Jr, 1, 2) @ r.reshape(B, -1, 1))[..., 0]
        D = np.einsum("bii->bi", A).copy()
        D[D <= 0] = 1.0
        Ad = A + lam[:, None, None] * (D[:, :, None] * np.eye(6))
        Ad[~active] = np.eye(6)
        step = -np.linalg.solve(Ad, g[..., None])[..., 0]
        step[~active] = 0.0
        Rn = rodrigues(step[:, :3]) @ R
        tn = t + step[:, 3:]
        rn, camn = _residuals(Rn, tn, X, uv, K)
        costn = np.sum(rn * rn, axis=(-2, -1))
        front = np.all(camn[..., 2] > 0, axis=-1)
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
    return R, t, np.sqrt(cost / X.shape[1])


def solve_pnp_batch(
    object_points: npt.ArrayLike,
    image_points: npt.ArrayLike,
    K: npt.ArrayLike,
    *,
    refine: bool = True,
    max_iter: int = 20,
) -> PnPResult:
    r"""Poses ``(R, t)`` of a batch of PnP problems, each with its own intrinsics.

    For each problem ``b``: the linear pose on the normalised coordinates ``K_b⁻¹ u``
    (DLT of ``[R | t]`` for non-planar points, the plane homography for planar ones, as
    :func:`~imageform.geometry.solve_pnp`), then Levenberg-Marquardt on

    .. math:: \min_{R_b, t_b} \sum_i \left\| \mathbf{u}_{bi} - \pi\left(K_b (R_b
              \mathbf{X}_{bi} + \mathbf{t}_b)\right) \right\|^2 \quad
              \text{s.t. } (R_b\mathbf{X}_{bi} + \mathbf{t}_b)_z > 0,

    all problems at once (NumPy, no Python loop over problems).

    Parameters
    ----------
    object_points : array_like (..., N, 3)
        World points; N >= 6 (non-planar) or N >= 4 (planar).
    image_points : array_like (..., N, 2)
        Their (undistorted) pixels.
    K : array_like (..., 3, 3)
        Intrinsics per problem (upper triangular, fx, fy > 0), broadcast against the
        batch shape ``...`` (a single (3, 3) is shared).
    refine : bool
        Run the LM refinement (otherwise the linear pose).
    max_iter : int
        LM iterations.

    Returns
    -------
    PnPResult
        ``rvec, tvec, R, rms, valid, inliers`` with leading shape ``(...)``; ``valid`` is
        the cheirality check (every point in front of its camera, finite fit).

    Raises
    ------
    InvalidInputError
        Shapes that do not match or broadcast, NaN, a K that is not upper triangular.
    DegenerateConfigurationError
        Too few or collinear points.

    Examples
    --------
    >>> X = np.random.default_rng(0).uniform(-1, 1, (3, 10, 3))   # 3 problems
    >>> K = np.array([[[f, 0, 320], [0, f, 240], [0, 0, 1]] for f in (500.0, 800.0, 1200.0)])
    >>> h = np.einsum("bij,bnj->bni", K, X + [0, 0, 6])
    >>> res = solve_pnp_batch(X, h[..., :2] / h[..., 2:], K)
    >>> (res.tvec.round(9) + 0.0).tolist(), res.valid.tolist()
    ([[0.0, 0.0, 6.0], [0.0, 0.0, 6.0], [0.0, 0.0, 6.0]], [True, True, True])
    """
    X0 = to_numpy(as_points(object_points, "object_points", 3))
    uv0 = to_numpy(as_points(image_points, "image_points", 2))
    out_dtype = np.float32 if X0.dtype == uv0.dtype == np.float32 else np.float64
    X = np.asarray(X0, dtype=np.float64)
    uv = np.asarray(uv0, dtype=np.float64)
    if X.ndim < 2 or X.shape[:-1] != uv.shape[:-1]:
        raise InvalidInputError(
            "expected object_points (..., N, 3) and image_points (..., N, 2) with the same "
            f"leading shape, got {X.shape} and {uv.shape}"
        )
    Km = np.asarray(to_numpy(as_matrix(K, "K", (3, 3))), dtype=np.float64)
    batch = X.shape[:-2]
    try:
        Kb = np.broadcast_to(Km, (*batch, 3, 3))
    except ValueError:
        raise InvalidInputError(
            f"expected K of shape (3, 3) or {(*batch, 3, 3)}, got {Km.shape}"
        ) from None
    Kf = Kb.reshape(-1, 3, 3)
    bad = (
        (Kf[:, 0, 0] <= 0)
        | (Kf[:, 1, 1] <= 0)
        | (Kf[:, 1, 0] != 0)
        | (Kf[:, 2, 0] != 0)
        | (Kf[:, 2, 1] != 0)
        | (Kf[:, 2, 2] == 0)
    )
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise InvalidInputError(
            f"expected every K upper triangular with fx, fy > 0, got {Kf[i].tolist()} "
            f"(problem {i} of the flattened batch)"
        )
    do_refine = as_bool(refine, "refine")
    n_iter = as_int(max_iter, "max_iter", minimum=0)
    Kf = Kf / Kf[:, 2:3, 2:3]
    N = X.shape[-2]
    Xf = X.reshape(-1, N, 3)
    uvf = uv.reshape(-1, N, 2)
    k = Kf[:, None]
    y = (uvf[..., 1] - k[..., 1, 2]) / k[..., 1, 1]
    x = (uvf[..., 0] - k[..., 0, 2] - k[..., 0, 1] * y) / k[..., 0, 0]
    R, t = linear_pose(Xf, np.stack([x, y], -1))
    if do_refine:
        R, t, rms = _refine(R, t, Xf, uvf, Kf, n_iter)
    else:
        r, _ = _residuals(R, t, Xf, uvf, Kf)
        rms = np.sqrt(np.mean(np.sum(r * r, -1), -1))
    return _pnp_result(R, t, rms, Xf, batch, X.shape[:-1], out_dtype)
