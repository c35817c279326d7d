"""Epipolar geometry of two views: fundamental and essential matrices, minimal and robust.

Convention: ``x2ᵀ F x1 = 0`` for pixel ``x1`` in the first image and ``x2`` in the second
(OpenCV's ``findFundamentalMat(points1, points2)``); ``E = [t]ₓ R`` with
``X_cam2 = R X_cam1 + t`` and ``F = K2⁻ᵀ E K1⁻¹``.

- :func:`fundamental_8point`, :func:`fundamental_7point`, :func:`essential_5point`: the
  minimal / linear solvers on exact data.
- :func:`find_fundamental_matrix`, :func:`find_essential_matrix`: RANSAC (MSAC scoring for
  F, MAGSAC++ for E, on the Sampson error in pixels; LO-RANSAC, adaptive trials), then
  Levenberg-Marquardt on the Sampson error (F: of the refinement support; E: MAGSAC++'s
  weighted least squares) over a minimal parametrisation.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy, use_numba
from imageform._random import RNGLike, as_rng
from imageform._validate import MAX_MAGNITUDE, as_int, as_matrix, as_real, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import _robust_core
from imageform.geometry._minimal import e5, f7, f8, rank2, sampson_sq
from imageform.geometry._robust_core import (
    check_confidence,
    check_pairs,
    hartley,
    levenberg_marquardt,
    ransac,
    result_dtype,
    rotation,
)

__all__ = [
    "EssentialResult",
    "FundamentalResult",
    "essential_5point",
    "find_essential_matrix",
    "find_fundamental_matrix",
    "fundamental_7point",
    "fundamental_8point",
]

F64 = NDArray[np.float64]

#: Runner-up hypotheses locally optimised before RANSAC may stop (see ``_robust_core.ransac``),
#: and the supports (multiples of the threshold) of the local optimisation's refits.
_LO_POOL = 8
_LO_STEPS = (3.0, 2.0, 2.0, 2.0)

#: The compiled essential matrix's adaptive sample count is that of the correspondences
#: within the refinement support (``3σ̂`` up to ``2τ``). It was kept on those within ``τ``
#: (1) when, with the wider count's fewer samples, one frame of tests/geometry/test_sfm.py's
#: walk-through kept 10 PnP inliers instead of 12; with the final refit in front of the
#: cameras it passes, and at 30 % outliers and ``σ = τ`` it draws about 5 times fewer
#: samples (issue 28).
_E_TERMINATION_FACTOR = 2.0

#: The essential matrix's MAGSAC++ IRLS (as ``imageform._kernels.ransac_e``): rounds and
#: tolerance of the local optimisation, the runner-up pool, the final IRLS's rounds and LM
#: steps per round.
_E_LO_ROUNDS = 10
_E_LO_TOL = 1e-12
_E_POOL = 8
_E_IRLS_ROUNDS = 10
_E_IRLS_ITER = 2
#: The least-squares refit after the IRLS (as ``imageform._kernels.ransac_e._refit_front``):
#: at most this many rounds in front of the cameras; kept when its MAGSAC++ score is at
#: most ``1 + _E_REFIT_TOL`` times the IRLS's (``ransac_e._REFIT_TOL``, the figures there).
_E_FRONT_ROUNDS = 6
_E_REFIT_TOL = 0.01
_E_FRONT_TOL = 0.05
#: ``recover_pose``'s default ``max_depth``.
_MAX_DEPTH = 50.0


class FundamentalResult(NamedTuple):
    """A robustly estimated fundamental matrix, its inlier mask, Sampson RMS and sample count.

    The matrix has ``x2ᵀ F x1 = 0``, rank 2, ``‖F‖_F = 1``; the inlier mask is ``(N,)``
    (Sampson distance below the threshold), then the Sampson RMS of the inliers in pixels and
    the number of minimal samples drawn.
    """

    F: F64
    inliers: NDArray[np.bool_]
    rms: float
    trials: int


class EssentialResult(NamedTuple):
    """A robustly estimated essential matrix, its inlier mask, Sampson RMS and sample count.

    The matrix has singular values ``(1, 1, 0)/√2``, ``‖E‖_F = 1``; the inlier mask is
    ``(N,)``, then the Sampson RMS of the inliers in pixels and the number of minimal samples
    drawn.
    """

    E: F64
    inliers: NDArray[np.bool_]
    rms: float
    trials: int


def _unit(F: F64) -> F64:
    """Scale to unit Frobenius norm, the sign fixed so that the largest-magnitude entry is > 0."""
    F = F / np.linalg.norm(F)
    return F if F.flat[np.argmax(np.abs(F))] > 0 else -F


def fundamental_8point(points1: npt.ArrayLike, points2: npt.ArrayLike) -> F64:
    """Fundamental matrix from N >= 8 correspondences by the normalised 8-point algorithm.

    Both point sets are Hartley-normalised, ``f`` is the least-squares null vector of the
    rows ``x2 ⊗ x1`` (``x2ᵀ F x1 = 0``), rank 2 is enforced by zeroing the smallest
    singular value, and the normalisation is undone: ``F = T2ᵀ F̂ T1`` (Hartley 1997, "In
    defense of the eight-point algorithm", PAMI 19(6); H&Z Algorithm 11.1).

    Parameters
    ----------
    points1, points2 : array_like (N, 2)
        Pixels in the first and second image.

    Returns
    -------
    ndarray (3, 3)
        ``F`` with unit Frobenius norm, largest entry positive.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(-1, 1, (8, 3)) + [0, 0, 5]
    >>> x1 = X[:, :2] / X[:, 2:]
    >>> x2 = (X + [1, 0, 0])[:, :2] / X[:, 2:]    # pure translation along x
    >>> (fundamental_8point(x1, x2).round(9) + 0.0).tolist()   # ∝ [t]x, t = (1, 0, 0)
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.707106781], [0.0, -0.707106781, 0.0]]
    """
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 8)
    F = f8(p1[None], p2[None])[0]
    if not np.all(np.isfinite(F)):
        raise DegenerateConfigurationError("the correspondences do not determine F")
    return _unit(F).astype(result_dtype(points1, points2))


def fundamental_7point(points1: npt.ArrayLike, points2: npt.ArrayLike) -> F64:
    """Return the one to three fundamental matrices through exactly 7 correspondences.

    The null space of the 7 x 9 system ``x2ᵀ F x1 = 0`` is the pencil
    ``F(α) = α F1 + (1 - α) F2``; the rank-2 condition ``det F(α) = 0`` is a cubic in
    ``α`` whose one or three real roots give the solutions (H&Z sec. 11.1.2).

    Returns
    -------
    ndarray (k, 3, 3)
        ``k`` in {1, 2, 3} matrices, unit Frobenius norm, largest entry positive.

    Examples
    --------
    >>> rng = np.random.default_rng(3)
    >>> X = rng.uniform(-1, 1, (7, 3)) + [0, 0, 5]
    >>> x1, x2 = X[:, :2] / X[:, 2:], (X + [1, 0.2, 0])[:, :2] / X[:, 2:]
    >>> Fs = fundamental_7point(x1, x2)
    >>> Fs.shape[0] in (1, 3), bool(np.allclose(np.linalg.det(Fs), 0, atol=1e-12))
    (True, True)
    """
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 7)
    if p1.shape[0] != 7:
        raise InvalidInputError(f"expected exactly 7 correspondences, got {p1.shape[0]}")
    Fs, _ = f7(p1[None], p2[None])
    if Fs.shape[0] == 0:
        raise DegenerateConfigurationError("the 7 correspondences do not determine F")
    return np.stack([_unit(F) for F in Fs]).astype(result_dtype(points1, points2))


def _check_K(K: object, name: str) -> F64:
    Km = np.asarray(to_numpy(as_matrix(K, name, (3, 3), batch=False)), dtype=np.float64)
    if (
        Km[0, 0] <= 0
        or Km[1, 1] <= 0
        or Km[1, 0] != 0
        or Km[2, 0] != 0
        or Km[2, 1] != 0
        or Km[2, 2] == 0
    ):
        raise InvalidInputError(
            f"expected {name} upper triangular with fx, fy > 0, got {describe(Km.tolist())}"
        )
    return Km / Km[2, 2]


def _normalised(p: F64, K: F64) -> F64:
    y = (p[:, 1] - K[1, 2]) / K[1, 1]
    x = (p[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    return np.stack([x, y], axis=-1)


def essential_5point(points1: npt.ArrayLike, points2: npt.ArrayLike) -> F64:
    """Return the up to ten essential matrices through exactly 5 correspondences.

    The correspondences are in normalised coordinates ``K⁻¹ x``.

    ``E`` lies in the 4-dimensional null space of the 5 x 9 system ``x2ᵀ E x1 = 0``;
    ``det E = 0`` and ``2 E Eᵀ E - tr(E Eᵀ) E = 0`` (Nister 2004, "An efficient solution to
    the five-point relative pose problem", PAMI 26(6), eqs. 1-2) give ten cubics in three
    unknowns, solved as the eigenproblem of a 10 x 10 action matrix (Stewenius, Engels &
    Nister 2006, "Recent developments on direct relative orientation", ISPRS J. 60).

    Parameters
    ----------
    points1, points2 : array_like (5, 2)
        Normalised image coordinates ``K⁻¹ (u, v, 1)`` (not pixels).

    Returns
    -------
    ndarray (k, 3, 3)
        The real solutions (``k`` even, at most 10), unit Frobenius norm.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> X = rng.uniform(-1, 1, (5, 3)) + [0, 0, 5]
    >>> x1, x2 = X[:, :2] / X[:, 2:], (X + [1, 0, 0])[:, :2] / X[:, 2:]
    >>> Es = essential_5point(x1, x2)
    >>> E = np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]]) / np.sqrt(2)   # [t]x, R = I
    >>> bool(min(min(np.abs(Ei - E).max(), np.abs(Ei + E).max()) for Ei in Es) < 1e-9)
    True
    """
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 5)
    if p1.shape[0] != 5:
        raise InvalidInputError(f"expected exactly 5 correspondences, got {p1.shape[0]}")
    Es, _ = e5(p1[None], p2[None])
    out = np.stack([_unit(E) for E in Es]) if Es.shape[0] else np.zeros((0, 3, 3))
    return out.astype(result_dtype(points1, points2))


def _rot_basis(F: F64) -> tuple[F64, F64, float]:
    """Decompose ``F = U diag(1, σ, 0) Vᵀ`` with U, V rotations.

    The orthonormal representation of Bartoli & Sturm 2004.
    """
    U, s, Vt = np.linalg.svd(F)
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    return U, Vt.T, float(s[1] / s[0])


def _refine_f(F: F64, p1: F64, p2: F64, max_iter: int) -> F64:
    """Refine F by LM on the Sampson distances over ``F = U diag(1, σ, 0) Vᵀ`` (7 parameters).

    Parametrised in Hartley-normalised coordinates, residuals in pixels.
    """
    T1, T2 = hartley(p1)[1], hartley(p2)[1]
    Fn = np.linalg.inv(T2).T @ F @ np.linalg.inv(T1)
    U0, V0, s0 = _rot_basis(Fn)

    def build(q: F64) -> F64:
        U = rotation(q[:3]) @ U0
        V = rotation(q[3:6]) @ V0
        return T2.T @ ((U * np.array([1.0, q[6], 0.0])) @ V.T) @ T1

    def residual(q: F64) -> F64:
        Fq = build(q)
        Fx1 = p1 @ Fq[:, :2].T + Fq[:, 2]
        Ftx2 = p2 @ Fq[:2, :] + Fq[2, :]
        num = np.sum(p2 * Fx1[:, :2], -1) + Fx1[:, 2]
        den = np.sqrt(Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2)
        return num / den

    with np.errstate(all="ignore"):
        q, _ = levenberg_marquardt(residual, np.r_[np.zeros(6), s0], max_iter=max_iter)
    Fr = build(q)
    return Fr / np.linalg.norm(Fr) if np.all(np.isfinite(Fr)) else F


def _sampson_parts(F: F64, p1: F64, p2: F64) -> tuple[F64, F64]:
    """Epipolar residuals ``x2ᵀ F x1`` (N,) and the Sampson denominators (N,)."""
    Fx1 = p1 @ F[:, :2].T + F[:, 2]
    Ftx2 = p2 @ F[:2, :] + F[2, :]
    num = np.sum(p2 * Fx1[:, :2], -1) + Fx1[:, 2]
    den = Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2
    return num, den


def _robust_args(
    threshold: object, confidence: object, max_trials: object, max_iter: object
) -> tuple[float, float, int, int]:
    return (
        # squared in Python floats: beyond 1e100 pixels it overflows (and means nothing)
        as_real(threshold, "threshold", positive=True, maximum=MAX_MAGNITUDE),
        check_confidence(confidence),
        as_int(max_trials, "max_trials", minimum=1),
        as_int(max_iter, "max_iter", minimum=0),
    )


def find_fundamental_matrix(
    points1: npt.ArrayLike,
    points2: npt.ArrayLike,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_trials: int = 2000,
    max_iter: int = 50,
    rng: RNGLike = 0,
) -> FundamentalResult:
    """Fundamental matrix from correspondences with outliers (7-point RANSAC + LM).

    Minimal 7-point samples give one to three hypotheses each, scored by the truncated
    squared Sampson distance (MSAC) with an adaptive number of samples
    (``k = log(1 - p) / log(1 - ε⁷)``); every new best hypothesis is re-fitted by the
    normalised 8-point algorithm on its inliers (LO-RANSAC). The final ``F`` minimises, by
    Levenberg-Marquardt over the orthonormal representation ``F = U diag(1, σ, 0) Vᵀ``
    (Bartoli & Sturm 2004, CVIU 97), which keeps rank 2, the Sampson distances of the
    correspondences within the refinement support (``3σ̂`` with ``σ̂`` the noise estimated
    from the inliers, between ``τ`` and ``3τ``); the inliers are those within ``τ`` of it.

    Parameters
    ----------
    points1, points2 : array_like (N, 2)
        Corresponding pixels in the two images, N >= 8.
    threshold : float
        Inlier threshold on the Sampson distance, pixels.
    confidence, max_trials, max_iter, rng
        As :func:`~imageform.geometry.find_homography`.

    Returns
    -------
    FundamentalResult
        ``F``, ``inliers``, ``rms``, ``trials``.

    Raises
    ------
    InvalidInputError
        Shapes other than (N, 2), different lengths, N < 8, NaN or inf.
    DegenerateConfigurationError
        No hypothesis with 8 inliers was found.

    References
    ----------
    Hartley & Zisserman 2nd ed., Algorithms 11.1, 11.6 and eq. 11.9 (Sampson); Chum, Matas &
    Kittler (2003), LO-RANSAC; Torr & Zisserman (2000), MSAC.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(-1, 1, (60, 3)) + [0, 0, 5]
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> u1 = X @ K.T; u1 = u1[:, :2] / u1[:, 2:]
    >>> u2 = (X + [1, 0.1, 0]) @ K.T; u2 = u2[:, :2] / u2[:, 2:]
    >>> u2[:12] += rng.uniform(-60, 60, (12, 2))   # 12 outliers
    >>> res = find_fundamental_matrix(u1, u2)
    >>> int(res.inliers[12:].sum()), bool(res.rms < 1e-9)
    (48, True)
    """
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 8)
    thr, p, trials, n_iter = _robust_args(threshold, confidence, max_trials, max_iter)
    n = p1.shape[0]
    if use_numba(p1):
        from imageform._kernels.ransac_f import fundamental_estimate

        Fk: F64 = np.empty((3, 3))
        inl = np.empty(n, dtype=bool)
        rms = np.empty(1)
        drawn = int(
            fundamental_estimate(
                np.ascontiguousarray(p1),
                np.ascontiguousarray(p2),
                thr,
                p,
                min(trials, 2**62),
                _robust_core.kernel_seed(rng),
                _LO_POOL,
                min(n_iter, 2**62),
                _robust_core.F_REFINE_FACTOR,
                _robust_core.TERMINATION_FACTOR,
                Fk,
                inl,
                rms,
            )
        )
        if drawn < 0:
            raise DegenerateConfigurationError(
                f"no fundamental matrix with at least 8 inliers within {thr:g} px after "
                f"{-drawn} samples"
            )
        # the kernel wrote F (unit norm), its inliers and their RMS
        Fk = Fk if Fk.flat[np.argmax(np.abs(Fk))] > 0 else -Fk  # _unit's sign
        dtype = result_dtype(points1, points2)
        return FundamentalResult(Fk.astype(dtype), inl, float(rms[0]), drawn)
    gen = as_rng(rng)

    def solve(idx: NDArray[np.intp]) -> F64:
        return f7(p1[idx], p2[idx])[0]

    def sq(models: F64) -> F64:
        return sampson_sq(models, p1, p2)

    def local_opt(F: F64, inl: NDArray[np.bool_]) -> F64:
        # Sampson-weighted 8-point fits (iteratively reweighted least squares) on the
        # correspondences within 3τ, then 2τ: with noise near τ, the inliers within τ of a
        # minimal-sample model are too few and too biased to pull it to the right basin
        for m in _LO_STEPS:
            num, den = _sampson_parts(F, p1, p2)
            sel = num * num < (m * thr) ** 2 * den
            if sel.sum() < 8:
                break
            w = 1.0 / np.sqrt(den[sel])
            F = f8(p1[sel][None], p2[sel][None], (w / w.mean())[None])[0]
        return F

    F, inl, drawn = ransac(n, 7, solve, sq, thr, p, trials, gen, local_opt, pool=_LO_POOL)
    if F is None or inl.sum() < 8:
        raise DegenerateConfigurationError(
            f"no fundamental matrix with at least 8 inliers within {thr:g} px after {drawn} samples"
        )
    F = rank2(F)
    F = _robust_core.refit_on_support(
        F,
        lambda m: sampson_sq(m, p1, p2),
        lambda m, sel: _refine_f(m, p1[sel], p2[sel], n_iter),
        thr,
        1,
        8,
        factor=_robust_core.F_REFINE_FACTOR,
    )
    return _fundamental_result(F, p1, p2, thr, drawn, points1, points2)


def _fundamental_result(
    F: F64, p1: F64, p2: F64, thr: float, drawn: int, points1: object, points2: object
) -> FundamentalResult:
    F = _unit(F)
    e = sampson_sq(F, p1, p2)
    inl = e < thr * thr
    rms = float(np.sqrt(np.mean(e[inl]))) if inl.any() else float("nan")
    return FundamentalResult(F.astype(result_dtype(points1, points2)), inl, rms, drawn)


def _skew(t: F64) -> F64:
    return np.array([[0.0, -t[2], t[1]], [t[2], 0.0, -t[0]], [-t[1], t[0], 0.0]])


def _essential_from_rt(R: F64, t: F64) -> F64:
    E = _skew(t) @ R
    return E / np.linalg.norm(E)


def _some_rt(E: F64) -> tuple[F64, F64]:
    """One ``(R, t)`` with ``E ∝ [t]ₓ R`` (no cheirality: refinement only needs the pair)."""
    U, _, Vt = np.linalg.svd(E)
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    return U @ W @ Vt, U[:, 2].copy()


def _refine_e(
    E: F64,
    q1: F64,
    q2: F64,
    K1: F64,
    K2: F64,
    p1: F64,
    p2: F64,
    max_iter: int,
    sw: F64 | None = None,
) -> F64:
    """LM over ``(R, t̂)`` (3 + 2 parameters) on the pixel Sampson distances.

    Each distance multiplied by ``sw`` (square roots of weights) when given.
    """
    R0, t0 = _some_rt(E)
    # tangent basis of the unit sphere at t0
    a = np.eye(3)[int(np.argmin(np.abs(t0)))]
    b1 = np.cross(t0, a)
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(t0, b1)
    K1i, K2i = np.linalg.inv(K1), np.linalg.inv(K2)

    def build(q: F64) -> F64:
        R = rotation(q[:3]) @ R0
        t = t0 + q[3] * b1 + q[4] * b2
        return _essential_from_rt(R, t / np.linalg.norm(t))

    def residual(q: F64) -> F64:
        F = K2i.T @ build(q) @ K1i
        Fx1 = p1 @ F[:, :2].T + F[:, 2]
        Ftx2 = p2 @ F[:2, :] + F[2, :]
        num = np.sum(p2 * Fx1[:, :2], -1) + Fx1[:, 2]
        den = np.sqrt(Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2)
        return num / den if sw is None else sw * num / den

    with np.errstate(all="ignore"):
        q, _ = levenberg_marquardt(residual, np.zeros(5), max_iter=max_iter)
    Er = build(q)
    return Er if np.all(np.isfinite(Er)) else E


def find_essential_matrix(
    points1: npt.ArrayLike,
    points2: npt.ArrayLike,
    K1: npt.ArrayLike,
    K2: npt.ArrayLike | None = None,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_trials: int = 2000,
    max_iter: int = 50,
    rng: RNGLike = 0,
) -> EssentialResult:
    """Essential matrix of two calibrated views from pixels with outliers (5-point RANSAC).

    The pixels are mapped to normalised coordinates ``K⁻¹ x``; minimal 5-point samples
    (:func:`essential_5point`, up to ten solutions each) are scored by MAGSAC++'s
    marginalised loss (Barath et al. 2020) of the Sampson distance *in pixels* of
    ``F = K2⁻ᵀ E K1⁻¹``: the noise ``σ`` of an inlier uniform on ``[0, σ_max]``, ``3.64
    σ_max = 3τ``, beyond which a correspondence costs as an outlier (adaptive trial count
    ``log(1 - p) / log(1 - ε⁵)``). Each new best hypothesis, and before sampling stops the
    8 best of the others, is locally optimised by MAGSAC++'s iteratively re-weighted least
    squares (weights ``ρ'(r)/r`` of that loss, one Levenberg-Marquardt step over ``(R,
    t/‖t‖)`` per round, up to 10 rounds: to its basin's minimum, so that the score compares
    basins, not how far each hypothesis got). The best is refitted by that IRLS, each round
    without the weighted correspondences that its factorisation (chosen as in
    :func:`recover_pose`) puts behind a camera: an outlier near its epipolar line by chance
    lies behind a camera about half the time. The final ``E = [t]ₓ R`` then minimises the
    plain Sampson distances of the correspondences within the refinement support of that
    ``E`` (``3σ̂``, between ``τ`` and ``2τ``) in front of the cameras, by Levenberg-Marquardt
    over ``(R, t/‖t‖)``, when that raises MAGSAC++'s score by at most 1 % and keeps 95 % of
    the inliers that :func:`recover_pose` would keep (in front of both cameras, nearer than
    50 baselines): the weights
    choose the basin, the unweighted fit is the efficient estimate under Gaussian noise
    within it, and a refit that leaves the basin (a pure rotation, a wrong pair) is not
    kept (docs/two-view.md). The result depends far less on
    ``rng`` than a model chosen by its inlier count (docs/two-view.md, "The seed"). The
    inliers are those within ``τ`` of the result. The compiled path (numba) solves the
    5-point problem by Nister's hidden variable and Sturm sequences and rejects bad
    hypotheses early by Wald's SPRT (Matas & Chum 2008), its sample count corrected for the
    SPRT's rejections of good ones.

    Parameters
    ----------
    points1, points2 : array_like (N, 2)
        Corresponding pixels, N >= 5 (prefer N >= 8).
    K1 : array_like (3, 3)
        Intrinsics of the first camera (upper triangular).
    K2 : array_like (3, 3), optional
        Intrinsics of the second camera (default: ``K1``).
    threshold : float
        Inlier threshold on the Sampson distance, pixels.
    confidence, max_trials, max_iter, rng
        As :func:`~imageform.geometry.find_homography`.

    Returns
    -------
    EssentialResult
        ``E`` (singular values ``(1, 1, 0)/√2``), ``inliers``, ``rms``, ``trials``.

    Raises
    ------
    InvalidInputError
        Shapes, lengths, N < 5, NaN, a K that is not upper triangular with positive focal
        lengths.
    DegenerateConfigurationError
        No hypothesis with 5 inliers was found.

    References
    ----------
    Nister (2004), PAMI 26(6); Stewenius, Engels & Nister (2006), ISPRS J. 60; Chum, Matas &
    Kittler (2003), LO-RANSAC; Matas & Chum (2008), "Optimal randomized RANSAC", PAMI
    30(8); Barath, Noskova, Ivashechkin & Matas (2020), "MAGSAC++, a fast, reliable and
    accurate robust estimator", CVPR.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = rng.uniform(-1, 1, (50, 3)) + [0, 0, 5]
    >>> u1 = X @ K.T; u1 = u1[:, :2] / u1[:, 2:]
    >>> u2 = (X + [1, 0, 0]) @ K.T; u2 = u2[:, :2] / u2[:, 2:]
    >>> u2[:10] += 30.0
    >>> res = find_essential_matrix(u1, u2, K)
    >>> int(res.inliers.sum()), (np.abs(res.E).round(9) + 0.0).tolist()[1]
    (40, [0.0, 0.0, 0.707106781])
    """
    p1, p2 = check_pairs(points1, points2, "points1", "points2", 5)
    Ka = _check_K(K1, "K1")
    Kb = Ka if K2 is None else _check_K(K2, "K2")
    thr, p, trials, n_iter = _robust_args(threshold, confidence, max_trials, max_iter)
    gen = as_rng(rng)
    n = p1.shape[0]
    q1, q2 = _normalised(p1, Ka), _normalised(p2, Kb)
    Kai: F64 = np.asarray(np.linalg.inv(Ka), dtype=np.float64)
    Kbi: F64 = np.asarray(np.linalg.inv(Kb), dtype=np.float64)
    if use_numba(p1):
        from imageform._kernels.ransac_e import essential_estimate

        Em = np.zeros((3, 3))
        drawn = int(
            essential_estimate(
                np.ascontiguousarray(p1),
                np.ascontiguousarray(p2),
                np.ascontiguousarray(q1),
                np.ascontiguousarray(q2),
                np.ascontiguousarray(Kai),
                np.ascontiguousarray(Kbi),
                thr,
                p,
                min(trials, 2**62),
                np.uint64(gen.integers(0, 2**63 - 1)),
                min(n_iter, 2**62),
                _robust_core.REFINE_FACTOR,
                _E_TERMINATION_FACTOR,
                _robust_core.MAGSAC_REACH,
                Em,
            )
        )
        if drawn < 0:
            raise DegenerateConfigurationError(
                f"no essential matrix with at least 5 inliers within {thr:g} px after "
                f"{-drawn} samples"
            )
        return _essential_result(Em, p1, p2, Kai, Kbi, thr, drawn, points1, points2)

    def to_f(E: F64) -> F64:
        return Kbi.T @ E @ Kai

    def solve(idx: NDArray[np.intp]) -> F64:
        return e5(q1[idx], q2[idx])[0]

    def sq(models: F64) -> F64:
        return sampson_sq(to_f(models), p1, p2)

    def project_e(M: F64) -> F64:
        U, _, Vt = np.linalg.svd(M)
        E = (U * np.array([1.0, 1.0, 0.0])) @ Vt
        return E / np.linalg.norm(E)

    def weighted_step(E: F64, sel: NDArray[np.bool_], w: F64, n_iter: int) -> F64:
        return _refine_e(E, q1[sel], q2[sel], Ka, Kb, p1[sel], p2[sel], n_iter, np.sqrt(w[sel]))

    def loss(e: F64) -> F64:
        return _robust_core.magsac(e, thr)[0]

    def local_opt(E: F64, inl: NDArray[np.bool_]) -> F64:
        # MAGSAC++'s IRLS: one LM step per round on the current weights, to convergence
        for _ in range(_E_LO_ROUNDS):
            w = _robust_core.magsac(sq(E), thr)[1]
            sel = w > 0
            if sel.sum() < 6:
                break
            En = weighted_step(E, sel, w, 1)
            moved = float(np.sum((En - E) ** 2))
            E = En
            if moved < _E_LO_TOL:
                break
        return E

    E, inl, drawn = ransac(n, 5, solve, sq, thr, p, trials, gen, local_opt, pool=_E_POOL, loss=loss)
    if E is None or inl.sum() < 5:
        raise DegenerateConfigurationError(
            f"no essential matrix with at least 5 inliers within {thr:g} px after {drawn} samples"
        )
    E = project_e(E)
    # the final IRLS, without the weighted correspondences behind a camera
    for _ in range(_E_IRLS_ROUNDS):
        w = _robust_core.magsac(sq(E), thr)[1]
        sel = w > 0
        sel &= _in_front(E, q1, q2, sel)
        if sel.sum() < 5:
            break
        En = weighted_step(E, sel, w, min(n_iter, _E_IRLS_ITER))
        moved = float(np.sum((En - E) ** 2))
        E = En
        if moved < 1e-14:
            break

    # then least squares on the refinement support of that E, less the points behind a
    # camera, kept when it stays in the IRLS's basin (MAGSAC++ score within _E_REFIT_TOL)
    def refit(m: F64, sel: NDArray[np.bool_]) -> F64:
        return _refine_e(m, q1[sel], q2[sel], Ka, Kb, p1[sel], p2[sel], n_iter)

    Er = _robust_core.refit_on_support(E, sq, refit, thr, 1, 5)
    prev: NDArray[np.bool_] | None = None
    for _ in range(_E_FRONT_ROUNDS):
        e = sq(Er)
        wide = _robust_core.refine_support(e[e < thr * thr], thr, 1)
        near = e < wide * wide
        sel = near & _in_front(Er, q1, q2, near)
        if sel.sum() < 5 or (prev is not None and np.array_equal(sel, prev)):
            break
        Er, prev = refit(Er, sel), sel

    def kept(m: F64, e: F64) -> int:
        """Count ``m``'s inliers that ``recover_pose`` keeps (in front, within 50 baselines)."""
        inl = e < thr * thr
        return int(_in_front(m, q1, q2, inl, _MAX_DEPTH)[inl].sum())

    e0, e1 = sq(E), sq(Er)
    f0, f1 = kept(E, e0), kept(Er, e1)
    if loss(e1).sum() <= (1.0 + _E_REFIT_TOL) * loss(e0).sum() and f1 >= (1.0 - _E_FRONT_TOL) * f0:
        E = Er
    return _essential_result(project_e(E), p1, p2, Kai, Kbi, thr, drawn, points1, points2)


def _in_front(
    E: F64, q1: F64, q2: F64, sel: NDArray[np.bool_], max_depth: float = np.inf
) -> NDArray[np.bool_]:
    """Return the correspondences in front of both cameras for ``E``'s likeliest factorisation.

    The factorisation that puts the most of ``sel`` in front of both cameras, nearer than
    ``max_depth`` (the cheirality vote of ``relative_pose.recover_pose``).
    """
    U, _, Vt = np.linalg.svd(E)
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    h1, h2 = np.c_[q1, np.ones(len(q1))], np.c_[q2, np.ones(len(q2))]
    best: NDArray[np.bool_] = np.zeros(len(q1), dtype=bool)
    for R in (U @ W @ Vt, U @ W.T @ Vt):
        for t in (U[:, 2], -U[:, 2]):
            # depths of the two rays' closest points: λ2 x2 ≈ λ1 R x1 + t (least squares)
            a = h1 @ R.T
            aa, ab, bb = np.sum(a * a, -1), np.sum(a * h2, -1), np.sum(h2 * h2, -1)
            at, bt = a @ t, h2 @ t
            det = aa * bb - ab * ab
            with np.errstate(divide="ignore", invalid="ignore"):
                z1, z2 = (ab * bt - bb * at) / det, (aa * bt - ab * at) / det
                front = (z1 > 0) & (z2 > 0) & (z1 < max_depth) & (z2 < max_depth)
            if (front & sel).sum() > (best & sel).sum():
                best = front
    return best


def _essential_result(
    E: F64,
    p1: F64,
    p2: F64,
    Kai: F64,
    Kbi: F64,
    thr: float,
    drawn: int,
    points1: object,
    points2: object,
) -> EssentialResult:
    U, _, Vt = np.linalg.svd(E)
    E = _unit((U * np.array([1.0, 1.0, 0.0])) @ Vt)
    e = sampson_sq(Kbi.T @ E @ Kai, p1, p2)
    inl = e < thr * thr
    rms = float(np.sqrt(np.mean(e[inl]))) if inl.any() else float("nan")
    return EssentialResult(E.astype(result_dtype(points1, points2)), inl, rms, drawn)
