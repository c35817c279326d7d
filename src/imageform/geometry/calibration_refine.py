"""Levenberg-Marquardt refinement of intrinsics, distortion and poses (private helper).

The parameter vector is ``[fx, fy, cx, cy, skew, <the model's coefficients>, (rvec_k, t_k)
for each view]`` (Brown-Conrady ``k1, k2, p1, p2, k3``; rational ``k1 ... k6`` in OpenCV's
order; Kannala-Brandt ``k1 ... k4``); fixed parameters are removed from it. Residuals are
the reprojection errors ``(u - û, v - v̂)`` of every point. The Jacobian has a block
structure (a view's pose moves only that view's residuals) and is analytic; the normal
equations ``JᵀJ`` are summed block by block (the globals' block, each view's 6 x 6 pose
block and their cross blocks: :func:`normal_blocks`, one pass of a numba kernel where numba
runs), and each Levenberg-Marquardt step eliminates the poses (the Schur complement,
:func:`schur_step`) to solve the small system of the globals. Stereo calibration's refinement
solves its dense normal equations (:func:`levenberg_marquardt`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imageform._validate import check_option
from imageform.errors import ConvergenceError

__all__ = [
    "CALIBRATION_MODELS",
    "COND_WARN",
    "GLOBAL_NAMES",
    "MODEL_CODES",
    "MODEL_COEFFICIENTS",
    "RefineOutput",
    "StalledRefinement",
    "global_names",
    "normal_blocks",
    "project_views",
    "refine",
    "schur_step",
]

F64 = NDArray[np.float64]

#: The distortion coefficients each calibration model fits, in vector order after
#: ``fx, fy, cx, cy, skew`` (OpenCV's ``distCoeffs`` order; the fisheye ``D``).
MODEL_COEFFICIENTS: dict[str, tuple[str, ...]] = {
    "brown_conrady": ("k1", "k2", "p1", "p2", "k3"),
    "rational": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "kannala_brandt": ("k1", "k2", "k3", "k4"),
}
#: The calibration models, as ``calibrate_camera(model=...)`` names them.
CALIBRATION_MODELS = tuple(MODEL_COEFFICIENTS)


def global_names(model: str = "brown_conrady") -> tuple[str, ...]:
    """Names of the global (view-independent) parameters of ``model``, in vector order.

    Examples
    --------
    >>> global_names("kannala_brandt")
    ('fx', 'fy', 'cx', 'cy', 'skew', 'k1', 'k2', 'k3', 'k4')
    """
    key = check_option(model, CALIBRATION_MODELS, "calibration model")
    return ("fx", "fy", "cx", "cy", "skew", *MODEL_COEFFICIENTS[key])


#: Names of the global parameters of the default model (Brown-Conrady), in vector order.
GLOBAL_NAMES = global_names()

# (xd, yd, d(xd)/d coeffs, d(yd)/d coeffs, d(xd, yd)/d(x, y)) of a distortion model
_Distorted = tuple[F64, F64, F64 | None, F64 | None, F64 | None]


def rodrigues(rvec: F64) -> F64:
    """Batched ``R`` (V, 3, 3) from ``rvec`` (V, 3) (Rodrigues' formula, series near 0)."""
    th2 = np.sum(rvec * rvec, axis=-1)
    th = np.sqrt(th2)
    small = th2 < 1e-12
    safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / (safe * safe))
    x, y, z = rvec[:, 0], rvec[:, 1], rvec[:, 2]
    o = np.zeros_like(x)
    Kx = np.stack([np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], 1)
    return np.eye(3) + a[:, None, None] * Kx + b[:, None, None] * (Kx @ Kx)


def _brown_conrady(x: F64, y: F64, d: F64, jac: bool) -> _Distorted:
    """Brown-Conrady ``(k1, k2, p1, p2, k3)`` on ``(x, y)`` and its derivatives."""
    k1, k2, p1, p2, k3 = d
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    rad = 1.0 + k1 * r2 + k2 * r4 + k3 * r6
    xd = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    if not jac:
        return xd, yd, None, None, None
    # d(xd, yd) / d(k1, k2, p1, p2, k3)
    dxd_k = np.stack([x * r2, x * r4, 2 * x * y, r2 + 2 * x * x, x * r6], -1)
    dyd_k = np.stack([y * r2, y * r4, r2 + 2 * y * y, 2 * x * y, y * r6], -1)
    # d(xd, yd) / d(x, y)
    drad = k1 + 2 * k2 * r2 + 3 * k3 * r4
    a11 = rad + 2 * x * x * drad + 2 * p1 * y + 6 * p2 * x
    a12 = 2 * x * y * drad + 2 * p1 * x + 2 * p2 * y
    a22 = rad + 2 * y * y * drad + 6 * p1 * y + 2 * p2 * x
    A = np.stack([np.stack([a11, a12], -1), np.stack([a12, a22], -1)], 1)  # (M, 2, 2)
    return xd, yd, dxd_k, dyd_k, A


def _rational(x: F64, y: F64, d: F64, jac: bool) -> _Distorted:
    """OpenCV's rational model ``(k1, k2, p1, p2, k3, k4, k5, k6)`` and its derivatives.

    ``ρ = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)``, tangential terms as
    Brown-Conrady (OpenCV calib3d documentation, ``CALIB_RATIONAL_MODEL``).
    """
    k1, k2, p1, p2, k3, k4, k5, k6 = d
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    num = 1.0 + k1 * r2 + k2 * r4 + k3 * r6
    iden = 1.0 / (1.0 + k4 * r2 + k5 * r4 + k6 * r6)
    rad = num * iden
    xd = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    if not jac:
        return xd, yd, None, None, None
    # dρ/dk: r^2n / den for the numerator, -ρ r^2n / den for the denominator
    drad_k = np.stack([r2, r4, r6, -rad * r2, -rad * r4, -rad * r6], -1) * iden[:, None]
    tan_x = np.stack([2 * x * y, r2 + 2 * x * x], -1)
    tan_y = np.stack([r2 + 2 * y * y, 2 * x * y], -1)
    dxd_k = np.concatenate([x[:, None] * drad_k[:, :2], tan_x, x[:, None] * drad_k[:, 2:]], -1)
    dyd_k = np.concatenate([y[:, None] * drad_k[:, :2], tan_y, y[:, None] * drad_k[:, 2:]], -1)
    # dρ/d(r²)
    drad = (k1 + 2 * k2 * r2 + 3 * k3 * r4 - rad * (k4 + 2 * k5 * r2 + 3 * k6 * r4)) * iden
    a11 = rad + 2 * x * x * drad + 2 * p1 * y + 6 * p2 * x
    a12 = 2 * x * y * drad + 2 * p1 * x + 2 * p2 * y
    a22 = rad + 2 * y * y * drad + 6 * p1 * y + 2 * p2 * x
    A = np.stack([np.stack([a11, a12], -1), np.stack([a12, a22], -1)], 1)
    return xd, yd, dxd_k, dyd_k, A


def _kannala_brandt(x: F64, y: F64, d: F64, jac: bool) -> _Distorted:
    """Kannala-Brandt ``(k1, k2, k3, k4)`` on ``(x, y)`` and its derivatives.

    ``θ = atan r``, ``θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)``, ``(x_d, y_d) = θ_d / r
    (x, y)`` (Kannala & Brandt 2006, eq. (6); OpenCV ``cv::fisheye``, which also takes
    ``θ_d / r = 1`` at ``r = 0``).
    """
    k1, k2, k3, k4 = d
    r2 = x * x + y * y
    r = np.sqrt(r2)
    at0 = r < 1e-8
    rs = np.where(at0, 1.0, r)
    th = np.arctan(r)
    t2 = th * th
    poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))
    s = np.where(at0, 1.0, th * poly / rs)  # θ_d / r
    xd, yd = s * x, s * y
    if not jac:
        return xd, yd, None, None, None
    # dθ_d/dk_i = θ^(2i+1)
    t3 = th * t2
    pw = np.stack([t3, t3 * t2, t3 * t2 * t2, t3 * t2 * t2 * t2], -1) / rs[:, None]
    dxd_k, dyd_k = x[:, None] * pw, y[:, None] * pw
    # s'(r) / r with s = θ_d / r:  (θ_d'(θ) / (1 + r²) - s) / r²; -> 2 (k1 - 1/3) at r = 0
    dpoly = 1.0 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
    ds = np.where(at0, 2.0 * (k1 - 1.0 / 3.0), (dpoly / (1.0 + r2) - s) / np.where(at0, 1.0, r2))
    a11 = s + ds * x * x
    a12 = ds * x * y
    a22 = s + ds * y * y
    A = np.stack([np.stack([a11, a12], -1), np.stack([a12, a22], -1)], 1)
    return xd, yd, dxd_k, dyd_k, A


_MODELS: dict[str, Callable[[F64, F64, F64, bool], _Distorted]] = {
    "brown_conrady": _brown_conrady,
    "rational": _rational,
    "kannala_brandt": _kannala_brandt,
}


def project_views(
    g: F64,
    rvecs: F64,
    tvecs: F64,
    obj: F64,
    view: NDArray[np.intp],
    *,
    jac: bool = False,
    model: str = "brown_conrady",
) -> tuple[F64, F64 | None, F64 | None]:
    """Pixels (M, 2) of the stacked object points ``obj`` (M, 3) seen in views ``view`` (M,).

    ``g`` is ``(fx, fy, cx, cy, skew, *coefficients)`` with the coefficients of ``model``
    (:data:`MODEL_COEFFICIENTS`). With ``jac``, also the analytic derivatives:
    ``d(u, v)/d globals`` (M, 2, len(g)) and ``d(u, v)/d (rvec, t)`` of the point's own view
    (M, 2, 6), the rotation part by Gallego & Yezzi (2015), "A compact formula for the
    derivative of a 3-D rotation in exponential coordinates", J. Math. Imaging Vis. 51,
    eq. (9). Models other than Brown-Conrady (whose results stay as they were) give
    ``inf`` for points at or behind the camera, so that the refinement refuses a step that
    would carry the boards through the camera's plane (a mirrored solution with
    ``fx, fy < 0`` and ``Z < 0`` reprojects the same pixels).
    """
    R = rodrigues(rvecs)
    Rm = R[view]
    cam = (Rm @ obj[:, :, None])[:, :, 0] + tvecs[view]
    iz = 1.0 / cam[:, 2]
    x, y = cam[:, 0] * iz, cam[:, 1] * iz
    fx, fy, cx, cy, sk = g[:5]
    xd, yd, dxd_k, dyd_k, A = _MODELS[model](x, y, g[5:], jac)
    uv = np.stack([fx * xd + sk * yd + cx, fy * yd + cy], axis=-1)
    if model != "brown_conrady":  # a point at or behind the camera: no image (the step fails)
        uv = np.where(cam[:, 2:] > 0.0, uv, np.inf)
    if not jac:
        return uv, None, None
    assert dxd_k is not None and dyd_k is not None and A is not None
    M = x.size
    one, zero = np.ones(M), np.zeros(M)
    Jg = np.empty((M, 2, g.size))
    Jg[:, 0, :5] = np.stack([xd, zero, one, zero, yd], -1)
    Jg[:, 1, :5] = np.stack([zero, yd, zero, one, zero], -1)
    Jg[:, 0, 5:] = fx * dxd_k + sk * dyd_k
    Jg[:, 1, 5:] = fy * dyd_k
    Kp = np.stack([np.stack([fx * one, sk * one], -1), np.stack([zero, fy * one], -1)], 1)
    Pz = np.stack(
        [np.stack([iz, zero, -x * iz], -1), np.stack([zero, iz, -y * iz], -1)], 1
    )  # d(x, y)/d cam
    Jc = Kp @ A @ Pz  # (M, 2, 3) d(u, v)/d cam
    # d cam / d rvec = -R [X]x (r rᵀ + (Rᵀ - I)[r]x) / θ²  (-[X]x near θ = 0)
    r = rvecs[view]
    th2 = np.sum(r * r, -1)
    Xs = _skew(obj)
    small = th2 < 1e-12
    safe = np.where(small, 1.0, th2)
    G = (r[:, :, None] * r[:, None, :] + (np.swapaxes(Rm, 1, 2) - np.eye(3)) @ _skew(r)) / safe[
        :, None, None
    ]
    G = np.where(small[:, None, None], np.eye(3), G)
    dcam_dr = -Rm @ Xs @ G
    Jp = np.concatenate([Jc @ dcam_dr, Jc], axis=-1)
    return uv, Jg, Jp


def _skew(v: F64) -> F64:
    o = np.zeros(v.shape[0])
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.stack(
        [np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], 1
    )


class StalledRefinement(ConvergenceError):
    """The refinement used its budget without a minimum; ``rvecs`` (V, 3): its last poses.

    :func:`~imageform.geometry.calibrate_camera` asks of them what the views leave open
    (one orientation, one tilt axis): the start's poses come from a start ``K`` that can be
    far off along the very valley the refinement wanders (twice the focal length spreads
    boards held at one orientation over 5 deg and more).
    """

    def __init__(self, message: str, rvecs: F64 | None = None) -> None:
        super().__init__(message)
        self.rvecs = rvecs


@dataclass(frozen=True)
class RefineOutput:
    """Refined parameters and the statistics of the fit."""

    globals_: F64
    rvecs: F64
    tvecs: F64
    residuals: F64  # (M, 2) observed - projected
    std_globals: F64  # 0 where fixed
    std_poses: F64  # (V, 6)
    n_iter: int
    cond: float  # of the scaled JᵀJ where it may reach COND_WARN, else a bound below that


def levenberg_marquardt(
    fun: Callable[[F64], F64],
    jac: Callable[[F64], F64],
    p0: F64,
    *,
    max_iter: int,
    tol: float,
) -> tuple[F64, F64, F64, int]:
    """Minimise ``‖fun(p)‖²`` by Levenberg-Marquardt with Marquardt's diagonal scaling.

    Step ``(JᵀJ + λ diag(JᵀJ)) δ = -Jᵀr`` (Marquardt 1963, SIAM J. Appl. Math. 11, 431);
    ``λ`` is divided by 10 after a successful step and multiplied by 10 otherwise. Stops when
    the relative decrease of the cost or the relative step falls below ``tol``. Returns
    ``(p, r, J, iterations)`` with ``iterations = -1`` if ``max_iter`` was reached.
    """
    p = p0.copy()
    r = fun(p)
    cost = float(r @ r)
    lam = 1e-3
    J = jac(p)
    for it in range(1, max_iter + 1):
        A = J.T @ J
        gvec = J.T @ r
        d = np.diag(A).copy()
        d[d == 0] = 1.0
        while True:
            try:
                step = np.linalg.solve(A + lam * np.diag(d), -gvec)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            p_new = p + step
            r_new = fun(p_new)
            cost_new = float(r_new @ r_new)
            if np.isfinite(cost_new) and cost_new <= cost:
                break
            lam *= 10.0
            if lam > 1e16:
                return p, r, J, it
        small_step = np.linalg.norm(step) <= tol * (np.linalg.norm(p) + tol)
        small_gain = cost - cost_new <= tol * cost
        p, r, cost = p_new, r_new, cost_new
        J = jac(p)
        lam = max(lam / 10.0, 1e-12)
        if small_step or small_gain:
            return p, r, J, it
    return p, r, J, -1


#: The calibration models' codes in the numba kernel (``imageform._kernels.calibration``).
MODEL_CODES = {"brown_conrady": 0, "rational": 1, "kannala_brandt": 2}
#: Condition number of the normalised normal equations above which calibration warns.
COND_WARN = 1e14

# the normal equations' blocks over all globals: Ug (n, n), W (V, n, 6), U (V, 6, 6), bg (n,),
# bp (V, 6)
Blocks = tuple[F64, F64, F64, F64, F64]


def normal_blocks(
    g: F64,
    rvecs: F64,
    tvecs: F64,
    obj: F64,
    img: F64,
    view: NDArray[np.intp],
    *,
    model: str = "brown_conrady",
    jac: bool = True,
    kernel: bool | None = None,
) -> tuple[F64, Blocks | None]:
    """Residuals ``r`` (M, 2) (projected minus observed) and the blocks of ``JᵀJ``, ``Jᵀr``.

    ``J`` is the Jacobian of ``r`` in all globals ``g`` (``fx, fy, cx, cy, skew``, the model's
    coefficients) and each view's pose ``(rvec, t)``; the blocks are ``Ug = J_gᵀ J_g`` (n, n),
    per view ``W_k = J_gᵀ J_k`` (V, n, 6) and ``U_k = J_kᵀ J_k`` (V, 6, 6), and the gradients
    ``bg = J_gᵀ r`` (n,), ``bp_k = J_kᵀ r`` (V, 6) (``None`` without ``jac``). One pass of
    the numba kernel ``imageform._kernels.calibration.calib_blocks`` where numba runs
    (``kernel`` None: :func:`imageform._backend.use_numba`), else :func:`project_views` and
    array products (its twin).
    """
    from imageform._backend import use_numba

    V = rvecs.shape[0]
    n = g.size
    if use_numba(obj) if kernel is None else kernel:
        from imageform._kernels.calibration import calib_blocks

        r = np.empty((obj.shape[0], 2))
        if jac:
            out = (np.empty((n, n)), np.empty((V, n, 6)), np.empty((V, 6, 6)), np.empty(n),
                   np.empty((V, 6)))  # fmt: skip
        else:
            out = (np.empty((0, 0)), np.empty((0, 0, 0)), np.empty((0, 0, 0)), np.empty(0),
                   np.empty((0, 0)))  # fmt: skip
        calib_blocks(
            MODEL_CODES[model],
            np.ascontiguousarray(g, np.float64),
            np.ascontiguousarray(rvecs, np.float64),
            np.ascontiguousarray(tvecs, np.float64),
            np.ascontiguousarray(obj, np.float64),
            np.ascontiguousarray(img, np.float64),
            np.ascontiguousarray(view, np.int64),
            jac,
            r,
            *out,
        )
        return r, (out if jac else None)
    uv, Jg, Jp = project_views(g, rvecs, tvecs, obj, view, jac=jac, model=model)
    r = uv - img
    if not jac:
        return r, None
    assert Jg is not None and Jp is not None
    Ug = np.einsum("mai,maj->ij", Jg, Jg)
    W = np.zeros((V, n, 6))
    np.add.at(W, view, np.einsum("mai,maj->mij", Jg, Jp))
    U = np.zeros((V, 6, 6))
    np.add.at(U, view, np.einsum("mai,maj->mij", Jp, Jp))
    bg = np.einsum("mai,ma->i", Jg, r)
    bp = np.zeros((V, 6))
    np.add.at(bp, view, np.einsum("mai,ma->mi", Jp, r))
    return r, (Ug, W, U, bg, bp)


def _damped_diagonals(Ug: F64, U: F64) -> tuple[F64, F64]:
    """Marquardt's scaling: the diagonals of ``JᵀJ``, zeros replaced by 1."""
    dg = np.diag(Ug).copy()
    dg[dg == 0] = 1.0
    du = np.diagonal(U, axis1=1, axis2=2).copy()
    du[du == 0] = 1.0
    return dg, du


def schur_step(Ug: F64, W: F64, U: F64, bg: F64, bp: F64, lam: float) -> tuple[F64, F64]:
    """Solve ``(JᵀJ + λ diag(JᵀJ)) δ = -Jᵀr`` by eliminating the poses (Schur complement).

    With the pose blocks ``U'_k = U_k + λ D_k``: ``(U'_g - Σ W_k U'_k⁻¹ W_kᵀ) δ_g = -b_g + Σ
    W_k U'_k⁻¹ b_k``, then ``δ_k = -U'_k⁻¹ (b_k + W_kᵀ δ_g)`` (Triggs et al. 2000, "Bundle
    adjustment — a modern synthesis", sec. 6.1). Returns ``(δ_g, δ_poses (V, 6))``; raises
    ``LinAlgError`` where a system is singular.
    """
    n = Ug.shape[0]
    dg, du = _damped_diagonals(Ug, U)
    Ud = U.copy()
    i6 = np.arange(6)
    Ud[:, i6, i6] += lam * du
    Z = np.linalg.solve(Ud, np.concatenate([np.swapaxes(W, 1, 2), bp[:, :, None]], axis=2))
    ZW, Zb = Z[:, :, :n], Z[:, :, n]
    S = Ug - np.einsum("kij,kjl->il", W, ZW)
    S[np.arange(n), np.arange(n)] += lam * dg
    step_g = np.linalg.solve(S, np.einsum("kij,kj->i", W, Zb) - bg)
    step_p = -Zb - ZW @ step_g
    return step_g, step_p


def _statistics(blocks: Blocks, cost: float, dof: int) -> tuple[F64, float]:
    """Return the standard deviations of every parameter and the condition of ``JᵀJ``.

    ``sqrt(diag(σ² (JᵀJ)⁻¹))`` with ``σ² = cost / dof``, computed on the Jacobi-scaled
    ``D⁻½ JᵀJ D⁻½`` (``D = diag(JᵀJ)``) by its blocks: ``S = U_g - Σ W_k U_k⁻¹ W_kᵀ``, the
    globals' diagonal that of ``S⁻¹``, each view's that of ``U_k⁻¹ + Z_k S⁻¹ Z_kᵀ`` with
    ``Z_k = U_k⁻¹ W_kᵀ``. The 2-norm condition number of the scaled matrix is bounded by
    ``trace · trace of the inverse`` (both positive semi-definite); where that bound reaches
    :data:`COND_WARN`, the matrix is assembled and its condition number computed, else the
    bound is returned.
    """
    Ug, W, U, _, _ = blocks
    n, V = Ug.shape[0], U.shape[0]
    sg = np.sqrt(np.diag(Ug))
    sg = np.where(sg > 0, sg, 1.0)
    sp = np.sqrt(np.diagonal(U, axis1=1, axis2=2))
    sp = np.where(sp > 0, sp, 1.0)
    Ugn = Ug / np.outer(sg, sg)
    Wn = W / (sg[None, :, None] * sp[:, None, :])
    Un = U / (sp[:, :, None] * sp[:, None, :])
    sigma2 = cost / dof if dof > 0 else np.nan
    try:
        Uinv = np.linalg.inv(Un)
        Z = Uinv @ np.swapaxes(Wn, 1, 2)  # (V, 6, n)
        Sinv = np.linalg.inv(Ugn - np.einsum("kij,kjl->il", Wn, Z))
        inv_g = np.diag(Sinv)
        inv_p = np.diagonal(Uinv, axis1=1, axis2=2) + np.einsum("kia,ab,kib->ki", Z, Sinv, Z)
        dgn = np.concatenate([inv_g, inv_p.ravel()])
        d2 = np.concatenate([sg, sp.ravel()]) ** 2
        dg = dgn / d2 * sigma2
        std = np.where(dg >= 0, np.sqrt(np.abs(dg)), np.nan)
        bound = float(np.trace(Ugn) + np.trace(Un, axis1=1, axis2=2).sum()) * float(dgn.sum())
        exact = not (np.all(dgn >= 0) and bound < COND_WARN)
    except np.linalg.LinAlgError:
        std = np.full(n + 6 * V, np.inf)
        exact = True
    if not exact:
        return std, bound
    Jn = np.zeros((n + 6 * V, n + 6 * V))
    Jn[:n, :n] = Ugn
    for k in range(V):
        c = n + 6 * k
        Jn[:n, c : c + 6] = Wn[k]
        Jn[c : c + 6, :n] = Wn[k].T
        Jn[c : c + 6, c : c + 6] = Un[k]
    return std, float(np.linalg.cond(Jn))


def refine(
    g0: F64,
    rvecs0: F64,
    tvecs0: F64,
    obj: F64,
    img: F64,
    view: NDArray[np.intp],
    free: NDArray[np.bool_],
    *,
    max_iter: int,
    tol: float,
    model: str = "brown_conrady",
    kernel: bool | None = None,
) -> RefineOutput:
    """Minimise the reprojection error over the free globals and all poses.

    Levenberg-Marquardt with Marquardt's diagonal scaling on the analytic Jacobian's blocks
    (:func:`normal_blocks`), each step solved by the Schur complement of the poses
    (:func:`schur_step`): ``λ`` divided by 10 after a successful step, multiplied by 10
    otherwise; stops when the relative decrease of the cost or the relative step falls below
    ``tol`` (the rules of :func:`levenberg_marquardt`, whose steps it takes).
    """
    from imageform._backend import use_numba

    if kernel is None:
        kernel = use_numba(obj)
    V = rvecs0.shape[0]
    idx_free = np.flatnonzero(free)
    n_g = idx_free.size
    M = obj.shape[0]

    def unpack(p: F64) -> tuple[F64, F64, F64]:
        g = g0.copy()
        g[idx_free] = p[:n_g]
        poses = p[n_g:].reshape(V, 6)
        return g, poses[:, :3], poses[:, 3:]

    def evaluate(p: F64, jac: bool) -> tuple[F64, Blocks | None]:
        g, rv, tv = unpack(p)
        r, b = normal_blocks(g, rv, tv, obj, img, view, model=model, jac=jac, kernel=kernel)
        if b is None:
            return r.ravel(), None
        Ug, W, U, bg, bp = b
        return r.ravel(), (Ug[np.ix_(idx_free, idx_free)], W[:, idx_free], U, bg[idx_free], bp)

    p = np.concatenate([g0[idx_free], np.concatenate([rvecs0, tvecs0], axis=1).ravel()])
    # the kernel gives the blocks with the residuals at little more cost: at every trial step
    r, blocks = evaluate(p, True)
    assert blocks is not None
    cost = float(r @ r)
    lam = 1e-3
    n_eval = -1
    for it in range(1, max_iter + 1):
        Ug, W, U, bg, bp = blocks
        stalled = False
        while True:
            try:
                step_g, step_p = schur_step(Ug, W, U, bg, bp, lam)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            step = np.concatenate([step_g, step_p.ravel()])
            p_new = p + step
            r_new, blocks_new = evaluate(p_new, kernel)
            cost_new = float(r_new @ r_new)
            if np.isfinite(cost_new) and cost_new <= cost:
                break
            lam *= 10.0
            if lam > 1e16:
                stalled = True
                break
        if stalled:
            n_eval = it
            break
        small_step = np.linalg.norm(step) <= tol * (np.linalg.norm(p) + tol)
        small_gain = cost - cost_new <= tol * cost
        p, r, cost = p_new, r_new, cost_new
        blocks = blocks_new if blocks_new is not None else evaluate(p, True)[1]
        assert blocks is not None
        lam = max(lam / 10.0, 1e-12)
        if small_step or small_gain:
            n_eval = it
            break
    g, rv, tv = unpack(p)
    if n_eval < 0:
        raise StalledRefinement(
            f"calibration refinement did not converge in {max_iter} iterations "
            f"(RMS {np.sqrt(np.sum(r**2) / M):.4g} px); raise max_iter or check the input",
            rv.copy(),
        )
    std, cond = _statistics(blocks, float(np.sum(r**2)), 2 * M - p.size)
    std_g = np.zeros(g0.size)
    std_g[idx_free] = std[:n_g]
    return RefineOutput(
        globals_=g,
        rvecs=rv,
        tvecs=tv,
        residuals=-r.reshape(M, 2),
        std_globals=std_g,
        std_poses=std[n_g:].reshape(V, 6),
        n_iter=n_eval,
        cond=cond,
    )
