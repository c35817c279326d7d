"""Levenberg-Marquardt refinement of intrinsics, distortion and poses (private helper).

The parameter vector is ``[fx, fy, cx, cy, skew, <the model's coefficients>, (rvec_k, t_k)
for each view]`` (Brown-Conrady ``k1, k2, p1, p2, k3``; rational ``k1 ... k6`` in OpenCV's
order; Kannala-Brandt ``k1 ... k4``); fixed parameters are removed from it. Residuals are
the reprojection errors ``(u - û, v - v̂)`` of every point. The Jacobian has a block
structure (a view's pose moves only that view's residuals); the Jacobian is analytic and
assembled block by block, and the Levenberg-Marquardt steps solve the small normal
equations ``JᵀJ`` (n_params²).
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
    "GLOBAL_NAMES",
    "MODEL_COEFFICIENTS",
    "RefineOutput",
    "StalledRefinement",
    "global_names",
    "project_views",
    "refine",
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
    cond: float


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
) -> RefineOutput:
    """Minimise the reprojection error over the free globals and all poses (TRF, sparse FD)."""
    V = rvecs0.shape[0]
    idx_free = np.flatnonzero(free)
    n_g = idx_free.size

    def unpack(p: F64) -> tuple[F64, F64, F64]:
        g = g0.copy()
        g[idx_free] = p[:n_g]
        poses = p[n_g:].reshape(V, 6)
        return g, poses[:, :3], poses[:, 3:]

    M = obj.shape[0]

    def fun(p: F64) -> F64:
        g, rv, tv = unpack(p)
        return (project_views(g, rv, tv, obj, view, model=model)[0] - img).ravel()

    cols = n_g + 6 * view[:, None] + np.arange(6)  # (M, 6) pose columns of each point

    def jac(p: F64) -> F64:
        g, rv, tv = unpack(p)
        _, Jg, Jp = project_views(g, rv, tv, obj, view, jac=True, model=model)
        assert Jg is not None and Jp is not None
        J = np.zeros((M, 2, n_g + 6 * V))
        J[:, :, :n_g] = Jg[:, :, idx_free]
        J[np.arange(M)[:, None, None], np.arange(2)[None, :, None], cols[:, None, :]] = Jp
        return J.reshape(2 * M, -1)

    p0 = np.concatenate([g0[idx_free], np.concatenate([rvecs0, tvecs0], axis=1).ravel()])
    p, r, J, n_eval = levenberg_marquardt(fun, jac, p0, max_iter=max_iter, tol=tol)
    g, rv, tv = unpack(p)
    if n_eval < 0:
        raise StalledRefinement(
            f"calibration refinement did not converge in {max_iter} iterations "
            f"(RMS {np.sqrt(np.sum(r**2) / M):.4g} px); raise max_iter or check the input",
            rv.copy(),
        )
    JtJ = J.T @ J
    dof = 2 * M - p.size
    sigma2 = float(np.sum(r**2)) / dof if dof > 0 else np.nan
    d = np.sqrt(np.diag(JtJ))
    d = np.where(d > 0, d, 1.0)
    Jn = JtJ / np.outer(d, d)
    cond = float(np.linalg.cond(Jn))
    try:
        cov = np.linalg.inv(Jn) / np.outer(d, d) * sigma2
        dg = np.diag(cov)
        std = np.where(dg >= 0, np.sqrt(np.abs(dg)), np.nan)
    except np.linalg.LinAlgError:
        std = np.full(p.size, np.inf)
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
