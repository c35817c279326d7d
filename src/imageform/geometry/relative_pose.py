"""Relative pose from an essential matrix (cheirality check) and two-view triangulation.

- :func:`recover_pose`: the one of the four ``(R, t)`` factorisations of ``E`` that puts
  the most correspondences in front of both cameras (as OpenCV's ``recoverPose``).
- :func:`triangulate_two_view`: 3-D points from two projection matrices by the linear DLT
  (as ``cv2.triangulatePoints``), the midpoint of the common perpendicular, or the optimal
  correction of Lindstrom (2010) followed by the DLT.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy, use_numba
from imageform._validate import as_bool, as_matrix, check_option, check_positive
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry._robust_core import check_pairs, result_dtype
from imageform.geometry.twoview import _check_K, _normalised

__all__ = ["RelativePose", "TwoViewPoints", "recover_pose", "triangulate_two_view"]

F64 = NDArray[np.float64]

_METHODS = ("linear", "midpoint", "optimal")


class RelativePose(NamedTuple):
    """Pose of the second camera relative to the first: ``X_cam2 = R X_cam1 + t``.

    ``t (3,)`` has unit norm (the scale is not observable); ``inliers (N,)`` marks the
    correspondences (among those given) triangulated in front of both cameras, closer than
    ``max_depth``; ``points (N, 3)`` are the triangulated points in the first camera's
    frame (units of ``‖t‖ = 1``), NaN where ``inliers`` is False.
    """

    R: F64
    t: F64
    inliers: NDArray[np.bool_]
    points: F64


class TwoViewPoints(NamedTuple):
    """Triangulated points ``(N, 3)`` and ``valid (N,)``.

    Valid: finite and in front of both cameras (positive depth in each).
    """

    points: F64
    valid: NDArray[np.bool_]


def _dlt(P1: F64, P2: F64, p1: F64, p2: F64) -> F64:
    """Homogeneous points (N, 4) by the linear DLT (H&Z sec. 12.2), no row scaling."""
    A = np.stack(
        [
            p1[:, :1] * P1[2] - P1[0],
            p1[:, 1:] * P1[2] - P1[1],
            p2[:, :1] * P2[2] - P2[0],
            p2[:, 1:] * P2[2] - P2[1],
        ],
        axis=1,
    )
    return np.linalg.svd(A)[2][:, -1, :]


def _depths(P: F64, Xh: F64) -> F64:
    """Depth sign-corrected so that points in front of the camera are positive."""
    return (Xh @ P[2]) * np.sign(np.linalg.det(P[:, :3])) * Xh[:, 3]


def _dehom(Xh: F64) -> F64:
    with np.errstate(divide="ignore", invalid="ignore"):
        return Xh[:, :3] / Xh[:, 3:]


#: An essential matrix has singular values (s, s, 0): its second must be above this fraction
#: of the first (rank 2, not 1 or 0), its third below it (not rank 3).
_RANK_TOL = (1e-6, 0.1)

_NONE_IN_FRONT = "no correspondence lies in front of both cameras for any factorisation of E"


def _check_rank_2(E: NDArray[np.float64]) -> None:
    """Refuse an ``E`` that is not of rank 2 within :data:`_RANK_TOL` (all-zero, rank 1, 3)."""
    s = np.linalg.svd(E, compute_uv=False)
    low, high = _RANK_TOL
    if not (s[0] > 0 and s[1] > low * s[0] and s[2] < high * s[0]):
        shown = ", ".join(f"{v:.3g}" for v in s)
        raise InvalidInputError(
            f"expected E of rank 2 (an essential matrix, singular values (s, s, 0)), got "
            f"singular values {shown}"
        )


def recover_pose(
    E: npt.ArrayLike,
    points1: npt.ArrayLike,
    points2: npt.ArrayLike,
    K1: npt.ArrayLike,
    K2: npt.ArrayLike | None = None,
    *,
    inliers: npt.ArrayLike | None = None,
    max_depth: float = 50.0,
) -> RelativePose:
    """Relative pose ``(R, t)`` from an essential matrix, chosen by the cheirality check.

    With ``E = U diag(1, 1, 0) Vᵀ`` (``U, V`` rotations) the four candidates are
    ``R ∈ {U W Vᵀ, U Wᵀ Vᵀ}``, ``t = ±u₃`` (H&Z result 9.19). For each, the depths
    ``λ₁, λ₂`` of every correspondence follow from ``λ₂ x̃₂ ≈ λ₁ R x̃₁ + t`` (least squares on
    normalised coordinates), and the candidate with the most points at positive depth in
    both cameras, nearer than ``max_depth`` (units of ``‖t‖ = 1``; far points have no
    reliable sign), wins. Its points and final mask come from the linear DLT, as OpenCV's
    ``recoverPose`` computes them.

    Parameters
    ----------
    E : array_like (3, 3)
        Essential matrix with ``x2ᵀ E x1 = 0`` on normalised coordinates.
    points1, points2 : array_like (N, 2)
        Corresponding pixels.
    K1 : array_like (3, 3)
        Intrinsics of the first camera.
    K2 : array_like (3, 3), optional
        Intrinsics of the second camera (default ``K1``).
    inliers : array_like of bool (N,), optional
        Only these correspondences vote (e.g. ``find_essential_matrix(...).inliers``).
    max_depth : float
        Points farther than this (in units of the baseline) do not vote.

    Returns
    -------
    RelativePose
        ``R``, unit ``t``, ``inliers``, ``points``.

    Raises
    ------
    InvalidInputError
        Bad shapes, NaN, a mask of the wrong length; an ``E`` not of rank 2 (all zero, rank
        1, or a third singular value above a tenth of the first).
    DegenerateConfigurationError
        No correspondence is in front of both cameras for any candidate.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = np.random.default_rng(0).uniform(-1, 1, (20, 3)) + [0, 0, 5]
    >>> u1 = X @ K.T; u1 = u1[:, :2] / u1[:, 2:]
    >>> u2 = (X + [-1, 0, 0]) @ K.T; u2 = u2[:, :2] / u2[:, 2:]
    >>> E = np.array([[0, 0, 0], [0, 0, 1], [0, -1, 0]])   # [t]x R, t = (-1, 0, 0), R = I
    >>> pose = recover_pose(E, u1, u2, K)
    >>> (pose.t.round(9) + 0.0).tolist(), bool(np.allclose(pose.R, np.eye(3)))
    ([-1.0, 0.0, 0.0], True)
    >>> int(pose.inliers.sum())
    20
    """
    Em = np.asarray(to_numpy(as_matrix(E, "E", (3, 3), batch=False)), dtype=np.float64)
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 1)
    Ka = _check_K(K1, "K1")
    Kb = Ka if K2 is None else _check_K(K2, "K2")
    dmax = check_positive(max_depth, "max_depth")
    n = p1.shape[0]
    if inliers is None:
        mask = np.ones(n, dtype=bool)
    else:
        mask = np.asarray(inliers)
        if mask.shape != (n,) or mask.dtype != np.bool_:
            raise InvalidInputError(
                f"expected inliers a bool array of shape ({n},), got {mask.dtype} {mask.shape}"
            )
    _check_rank_2(Em)  # after every shape check
    q1, q2 = _normalised(p1, Ka), _normalised(p2, Kb)
    dt = result_dtype(points1, points2)
    if use_numba(p1):
        from imageform._kernels.relative_pose import pose_from_essential

        R, t = np.empty((3, 3)), np.empty(3)
        X, good = np.empty((n, 3)), np.empty(n, dtype=bool)
        m = pose_from_essential(
            np.ascontiguousarray(Em),
            np.ascontiguousarray(q1),
            np.ascontiguousarray(q2),
            np.ascontiguousarray(mask),
            dmax,
            R,
            t,
            X,
            good,
        )
        if m == 0:
            raise DegenerateConfigurationError(_NONE_IN_FRONT)
        return RelativePose(R.astype(dt), t.astype(dt), good, X.astype(dt))
    U, _, Vt = np.linalg.svd(Em)
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    P1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    h1, h2 = np.c_[q1, np.ones(n)], np.c_[q2, np.ones(n)]
    best: tuple[int, F64, F64] | None = None
    for R in (U @ W @ Vt, U @ W.T @ Vt):
        for t in (U[:, 2], -U[:, 2]):
            # depths of the two rays' closest points: λ2 x2 ≈ λ1 R x1 + t (least squares)
            a = h1 @ R.T
            aa, ab, bb = np.sum(a * a, -1), np.sum(a * h2, -1), np.sum(h2 * h2, -1)
            at, bt = a @ t, h2 @ t
            det = aa * bb - ab * ab
            with np.errstate(divide="ignore", invalid="ignore"):
                z1 = (ab * bt - bb * at) / det
                z2 = (aa * bt - ab * at) / det
                good = mask & (z1 > 0) & (z2 > 0) & (z1 < dmax) & (z2 < dmax)
            count = int(good.sum())
            if best is None or count > best[0]:
                best = (count, R, t)
    assert best is not None
    _, R, t = best
    # the winner's points and final mask by the linear DLT (as OpenCV's recoverPose)
    Xh = _dlt(P1, np.hstack([R, t[:, None]]), q1, q2)
    Xh = Xh * np.sign(Xh[:, 3:])
    with np.errstate(divide="ignore", invalid="ignore"):
        z1 = Xh[:, 2] / Xh[:, 3]
        z2 = (Xh @ np.r_[R[2], t[2]]) / Xh[:, 3]
        good = mask & (z1 > 0) & (z2 > 0) & (z1 < dmax) & (z2 < dmax)
    X = _dehom(Xh)
    if not good.any():
        raise DegenerateConfigurationError(_NONE_IN_FRONT)
    X = np.where(good[:, None], X, np.nan)
    return RelativePose(R.astype(dt), (t / np.linalg.norm(t)).astype(dt), good, X.astype(dt))


def _camera_centre(P: F64) -> F64:
    return np.asarray(np.linalg.svd(P)[2][-1], dtype=np.float64)


def _fundamental_from_p(P1: F64, P2: F64) -> F64:
    """``F = [e₂]ₓ P2 P1⁺`` (H&Z result 9.1)."""
    e2 = P2 @ _camera_centre(P1)
    ex = np.array([[0.0, -e2[2], e2[1]], [e2[2], 0.0, -e2[0]], [-e2[1], e2[0], 0.0]])
    return ex @ P2 @ np.linalg.pinv(P1)


def _lindstrom(F: F64, p1: F64, p2: F64) -> tuple[F64, F64]:
    """Correct the points optimally by ``niter2`` so that ``x̂2ᵀ F x̂1 = 0``.

    Lindstrom 2010, "Triangulation made easy", CVPR, Listing 3: minimal
    ``‖x̂1 - x1‖² + ‖x̂2 - x2‖²``.
    """
    x = np.c_[p2, np.ones(len(p2))]  # Lindstrom's x: x^T F x' = 0
    xp = np.c_[p1, np.ones(len(p1))]
    Et = F[:2, :2]
    n = xp @ F[:2, :].T  # S F x'
    npr = x @ F[:, :2]  # S F^T x
    a = np.einsum("ni,ij,nj->n", n, Et, npr)
    b = 0.5 * (np.sum(n * n, -1) + np.sum(npr * npr, -1))
    c = np.einsum("ni,ij,nj->n", x, F, xp)
    d = np.sqrt(np.maximum(b * b - a * c, 0.0))
    lam = c / (b + d)
    dx, dxp = lam[:, None] * n, lam[:, None] * npr
    n = n - dxp @ Et.T
    npr = npr - dx @ Et
    lam = lam * 2.0 * d / (np.sum(n * n, -1) + np.sum(npr * npr, -1))
    dx, dxp = lam[:, None] * n, lam[:, None] * npr
    return p1 - dxp, p2 - dx


def triangulate_two_view(
    P1: npt.ArrayLike,
    P2: npt.ArrayLike,
    points1: npt.ArrayLike,
    points2: npt.ArrayLike,
    *,
    method: Literal["optimal", "linear", "midpoint"] = "optimal",
    check_depth: bool = True,
) -> TwoViewPoints:
    """3-D points from their pixels in two views with projection matrices ``P1, P2``.

    - ``"linear"``: the homogeneous DLT, ``min ‖A X̃‖`` with rows ``u P₃ - P₁``,
      ``v P₃ - P₂`` of each view (H&Z sec. 12.2; what ``cv2.triangulatePoints`` computes).
    - ``"midpoint"``: the midpoint of the shortest segment between the two back-projected
      rays (H&Z sec. 12.1).
    - ``"optimal"``: the pixels are first moved, minimising
      ``‖x̂₁ - x₁‖² + ‖x̂₂ - x₂‖²``, onto the epipolar constraint ``x̂₂ᵀ F x̂₁ = 0``
      (``F`` from ``P1, P2``) by Lindstrom's ``niter2`` (2010), whose rays then meet
      exactly; the DLT gives their intersection (the maximum-likelihood point under
      isotropic Gaussian pixel noise, H&Z sec. 12.5).

    Parameters
    ----------
    P1, P2 : array_like (3, 4)
        Projection matrices ``K [R | t]``.
    points1, points2 : array_like (N, 2)
        Corresponding pixels.
    method : {"optimal", "linear", "midpoint"}
        Hartley-Sturm optimal correction then linear, the linear (DLT) method alone, or the
        midpoint of the closest points of the two rays.
    check_depth : bool
        Mark points at or behind either camera as not valid (their coordinates are kept).

    Returns
    -------
    TwoViewPoints
        ``points (N, 3)``, ``valid (N,)``.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> P1 = K @ np.hstack([np.eye(3), np.zeros((3, 1))])
    >>> P2 = K @ np.hstack([np.eye(3), [[-1.0], [0], [0]]])
    >>> X = np.array([[0.2, -0.1, 4.0], [0.5, 0.3, 6.0]])
    >>> u1 = X @ P1[:, :3].T + P1[:, 3]; u2 = X @ P2[:, :3].T + P2[:, 3]
    >>> res = triangulate_two_view(P1, P2, u1[:, :2] / u1[:, 2:], u2[:, :2] / u2[:, 2:])
    >>> (res.points.round(9) + 0.0).tolist(), res.valid.tolist()
    ([[0.2, -0.1, 4.0], [0.5, 0.3, 6.0]], [True, True])
    """
    Pa = np.asarray(to_numpy(as_matrix(P1, "P1", (3, 4), batch=False)), dtype=np.float64)
    Pb = np.asarray(to_numpy(as_matrix(P2, "P2", (3, 4), batch=False)), dtype=np.float64)
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 1)
    how = check_option(method, _METHODS, "triangulation method")
    depth = as_bool(check_depth, "check_depth")
    for P, name in ((Pa, "P1"), (Pb, "P2")):
        if abs(np.linalg.det(P[:, :3])) <= 1e-12 * np.linalg.norm(P[:, :3]) ** 3:
            raise InvalidInputError(f"expected {name} with an invertible left 3 x 3 block")
    if how == "midpoint":
        C1, C2 = -np.linalg.solve(Pa[:, :3], Pa[:, 3]), -np.linalg.solve(Pb[:, :3], Pb[:, 3])
        d1 = np.linalg.solve(Pa[:, :3], np.c_[p1, np.ones(len(p1))].T).T
        d2 = np.linalg.solve(Pb[:, :3], np.c_[p2, np.ones(len(p2))].T).T
        w = C2 - C1
        a, b, c = np.sum(d1 * d1, -1), np.sum(d1 * d2, -1), np.sum(d2 * d2, -1)
        dd, ee = d1 @ w, d2 @ w
        den = a * c - b * b
        with np.errstate(divide="ignore", invalid="ignore"):
            s1 = (dd * c - b * ee) / den
            s2 = (b * dd - a * ee) / den
        X = 0.5 * (C1 + s1[:, None] * d1 + C2 + s2[:, None] * d2)
        Xh = np.c_[X, np.ones(len(X))]
    else:
        if how == "optimal":
            F = _fundamental_from_p(Pa, Pb)
            if not np.all(np.isfinite(F)) or np.linalg.norm(F) == 0:
                raise DegenerateConfigurationError("P1 and P2 share their centre: no baseline")
            p1, p2 = _lindstrom(F / np.linalg.norm(F), p1, p2)
        Xh = _dlt(Pa, Pb, p1, p2)
        X = _dehom(Xh)
    valid = np.all(np.isfinite(X), axis=-1)
    if depth:
        with np.errstate(invalid="ignore"):
            valid &= (_depths(Pa, Xh) > 0) & (_depths(Pb, Xh) > 0)
    return TwoViewPoints(X.astype(result_dtype(points1, points2)), valid)
