"""Stereo calibration and rectification: two cameras that see the same target.

:func:`stereo_calibrate` estimates both cameras (each started by
:func:`~imageform.geometry.calibrate_camera`) and the pose of the right camera relative to
the left, ``X_right = R X_left + T`` (OpenCV's ``stereoCalibrate`` convention), by a joint
Levenberg-Marquardt over everything; :func:`stereo_rectify` computes Bouguet's rectifying
rotations and projections (as OpenCV's ``stereoRectify``) and :func:`rectification_map`
the maps that :func:`~imageform.geometry.remap_bilinear` applies (as OpenCV's
``initUndistortRectifyMap``).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    check_bounded,
    check_memory,
    check_option,
    check_positive,
    describe,
    size_pair,
)
from imageform.errors import (
    ConvergenceError,
    DegenerateConfigurationError,
    InvalidInputError,
)
from imageform.geometry.calibration import DEFAULT_MAX_ITER, calibrate_camera
from imageform.geometry.calibration_refine import (
    CALIBRATION_MODELS,
    _skew,
    global_names,
    levenberg_marquardt,
    project_views,
    rodrigues,
)
from imageform.geometry.calibration_result import CalibrationResult
from imageform.geometry.calibration_views import _views
from imageform.geometry.distortion import BrownConrady, KannalaBrandt

if TYPE_CHECKING:
    from imageform.geometry.distortion import DistortionModel

__all__ = [
    "StereoCalibrationResult",
    "StereoRectification",
    "rectification_map",
    "stereo_calibrate",
    "stereo_rectify",
]

F64 = NDArray[np.float64]


def _rvec(R: F64) -> F64:
    """Rodrigues vector of a rotation (3, 3) (the angle in [0, pi])."""
    from imageform.geometry.rotations import matrix_to_rvec

    return np.asarray(matrix_to_rvec(R), dtype=np.float64)


def _mean_rotation(Rs: F64) -> F64:
    """Chordal L2 mean of rotations (V, 3, 3): the projection of their sum onto SO(3).

    Hartley, Trumpf, Dai & Li (2013), "Rotation averaging", IJCV 103, sec. 5.3.
    """
    U, _, Vt = np.linalg.svd(Rs.sum(axis=0))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def _dcam_drvec(rvecs: F64, view: NDArray[np.intp], obj: F64) -> F64:
    """``d(R_k X)/d rvec_k`` (M, 3, 3) (Gallego & Yezzi 2015, eq. (9))."""
    r = rvecs[view]
    Rm = rodrigues(rvecs)[view]
    th2 = np.sum(r * r, -1)
    small = th2 < 1e-12
    safe = np.where(small, 1.0, th2)
    G = (r[:, :, None] * r[:, None, :] + (np.swapaxes(Rm, 1, 2) - np.eye(3)) @ _skew(r)) / safe[
        :, None, None
    ]
    G = np.where(small[:, None, None], np.eye(3), G)
    return np.asarray(-Rm @ _skew(obj) @ G)


@dataclass(frozen=True)
class StereoCalibrationResult:
    """Both cameras of a stereo calibration and their relative pose.

    Attributes
    ----------
    left, right : CalibrationResult
        Each camera after the joint refinement: ``K``, ``distortion``, the standard
        deviations of its intrinsics (``std``; 0 where fixed), its per-view poses (the
        right ones are ``R R_k, R t_k + T``) and its reprojection residuals. The per-view
        poses are parameters of the left camera only: ``left.std_poses`` are their standard
        deviations, ``right.std_poses`` are NaN (derived poses).
    R : ndarray (3, 3)
        Rotation from the left to the right camera frame: ``X_right = R X_left + T``.
    T : ndarray (3,)
        Translation (object-point units, e.g. mm); the baseline is ``‖T‖``.
    rms : float
        ``sqrt(Σ‖u - û‖² / (2N))`` over the N points of both cameras (the value
        ``cv2.stereoCalibrate`` returns).
    std_rvec, std_T : ndarray (3,)
        Standard deviations of ``rvec = rodrigues⁻¹(R)`` (radians) and of ``T``.
    per_view_rms : ndarray (V, 2)
        RMS of each view in the left and the right camera (``perViewErrors`` of
        ``cv2.stereoCalibrateExtended``).
    fixed_intrinsics : bool
        Whether the intrinsics and distortion were held at the single-camera values.
    n_evaluations : int
        Iterations of the joint refinement.
    """

    left: CalibrationResult
    right: CalibrationResult
    R: F64
    T: F64
    rms: float
    std_rvec: F64 = field(repr=False)
    std_T: F64 = field(repr=False)
    per_view_rms: F64 = field(repr=False)
    fixed_intrinsics: bool = False
    n_evaluations: int = field(default=0, repr=False)

    @property
    def rvec(self) -> F64:
        """``R`` as a Rodrigues vector (radians)."""
        return _rvec(self.R)

    @property
    def baseline(self) -> float:
        """``‖T‖`` in object-point units."""
        return float(np.linalg.norm(self.T))

    @property
    def E(self) -> F64:
        """Essential matrix ``E = [T]ₓ R`` (Hartley & Zisserman, 2nd ed., eq. (9.12))."""
        return np.asarray(_skew(self.T[None])[0] @ self.R)

    @property
    def F(self) -> F64:
        """Fundamental matrix ``F = K_r⁻ᵀ E K_l⁻¹`` (H&Z eq. (9.18)), scaled to ``F[2, 2] = 1``.

        ``x_rᵀ F x_l = 0`` for corresponding homogeneous pixels of undistorted images.
        """
        F = np.linalg.inv(self.right.K).T @ self.E @ np.linalg.inv(self.left.K)
        return np.asarray(F / F[2, 2] if abs(F[2, 2]) > 1e-300 else F)

    def rectify(self, *, alpha: float = -1.0, zero_disparity: bool = True) -> StereoRectification:
        """:func:`stereo_rectify` of these cameras (left image size)."""
        return stereo_rectify(
            self.left.K,
            self.left.distortion,
            self.right.K,
            self.right.distortion,
            self.left.image_size,
            self.R,
            self.T,
            alpha=alpha,
            zero_disparity=zero_disparity,
        )


def _as_calibration(value: Any, name: str) -> CalibrationResult:
    if not isinstance(value, CalibrationResult):
        raise InvalidInputError(
            f"expected {name} to be a CalibrationResult (from calibrate_camera), got "
            f"{type(value).__name__}"
        )
    return value


def stereo_calibrate(
    object_points: Sequence[npt.ArrayLike],
    image_points_left: Sequence[npt.ArrayLike],
    image_points_right: Sequence[npt.ArrayLike],
    image_size: tuple[int, int],
    *,
    image_size_right: tuple[int, int] | None = None,
    left: CalibrationResult | None = None,
    right: CalibrationResult | None = None,
    fix_intrinsics: bool = False,
    fix: Collection[str] = (),
    skew: bool = False,
    max_iter: int | None = None,
    tol: float = 1e-12,
    model: str = "brown_conrady",
) -> StereoCalibrationResult:
    r"""Calibrate a stereo pair: both cameras and ``(R, T)`` by a joint Levenberg-Marquardt.

    Minimises the reprojection errors of both cameras over the intrinsics and distortion
    of both, the relative pose ``(R, T)`` and the target pose ``(R_k, t_k)`` of every view
    in the left camera (the right camera sees the target at ``(R R_k, R t_k + T)``):

    .. math::

        \min \sum_{k=1}^{V} \sum_{i=1}^{N_k}
        \left\| \mathbf{u}^{l}_{ki} - \pi(K_l, d_l, R_k \mathbf{X}_{ki} + \mathbf{t}_k)
        \right\|^2 +
        \left\| \mathbf{u}^{r}_{ki} - \pi\!\left(K_r, d_r,
        R (R_k \mathbf{X}_{ki} + \mathbf{t}_k) + \mathbf{T}\right) \right\|^2

    This is the formulation of Bouguet's Camera Calibration Toolbox for Matlab
    (``stereo_calib.m``) and of OpenCV's ``stereoCalibrate``. Initial values: each camera
    from :func:`~imageform.geometry.calibrate_camera` (or ``left``/``right`` when given),
    ``R`` the chordal mean of the per-view ``R^r_k (R^l_k)ᵀ`` (Hartley et al. 2013,
    "Rotation averaging", IJCV 103) and ``T`` the per-component median of
    ``t^r_k - R t^l_k`` (OpenCV takes the median of both). The Jacobian is analytic.

    Parameters
    ----------
    object_points : sequence of array_like (N_k, 3)
        The target points of each view (target units, e.g. mm).
    image_points_left, image_points_right : sequence of array_like (N_k, 2)
        Their pixels in the left and in the right camera (the same points, in the same
        order: both cameras must see the whole target in every view used).
    image_size : (int, int)
        ``(width, height)`` of the left camera (and of the right, unless
        ``image_size_right`` is given).
    image_size_right : (int, int), optional
        ``(width, height)`` of the right camera when it differs from the left's.
    left, right : CalibrationResult, optional
        Single-camera calibrations to start from (default: computed here).
    fix_intrinsics : bool
        Keep both cameras' ``K`` and distortion at the single-camera values and refine only
        the poses (OpenCV's ``CALIB_FIX_INTRINSIC``).
    fix : collection of str
        Parameters held fixed in both cameras (names as in ``calibrate_camera`` for the
        ``model``: ``fx, fy, cx, cy, skew, k1, k2, p1, p2, k3`` for Brown-Conrady; e.g.
        ``("k3",)`` as ``CALIB_FIX_K3``).
    skew : bool
        Estimate the skew of both cameras (default fixed at 0).
    max_iter, tol : int, float
        Iteration budget (default the model's, as ``calibrate_camera``: 100, 1000 for
        ``rational``) and relative tolerance of the joint refinement.
    model : {"brown_conrady", "rational", "kannala_brandt"}
        The lens model of both cameras (``calibrate_camera``'s; ``left`` and ``right``,
        when given, must be calibrations of this model).

    Returns
    -------
    StereoCalibrationResult
        ``left``, ``right`` (CalibrationResult), ``R``, ``T``, ``rms``, ``std_rvec``,
        ``std_T``, ``per_view_rms``; properties ``rvec``, ``baseline``, ``E``, ``F``.

    Raises
    ------
    InvalidInputError
        Different numbers of views or points in the two cameras, bad sizes or types.
    DegenerateConfigurationError
        Too few views or points, ``T`` of zero length.
    ConvergenceError
        The joint refinement did not converge within ``max_iter`` iterations.

    Notes
    -----
    ``rms`` is ``sqrt(Σ‖u - û‖² / (2N))`` over the N points of each camera (both cameras'
    residuals), the figure ``cv2.stereoCalibrate`` returns. Standard deviations are
    ``sqrt(diag(σ² (JᵀJ)⁻¹))`` with ``σ² = Σ‖u - û‖² / (4N - n_params)``, for ``rvec``,
    ``T`` and every free intrinsic (in ``left.std`` and ``right.std``).

    Examples
    --------
    >>> from imageform.geometry import checkerboard_points, project_points_distorted
    >>> from imageform.geometry import rvec_to_matrix
    >>> obj = checkerboard_points((9, 6), 25.0)
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> R, T = rvec_to_matrix([0.0, -0.05, 0.0]), np.array([-120.0, 0.0, 0.0])
    >>> views = [([0.3, 0.1, 0], [-100, -60, 420]), ([-0.2, 0.3, 0.1], [-90, -70, 450]),
    ...          ([0.1, -0.35, -0.1], [-110, -50, 430]), ([0.2, 0.2, 0.3], [-80, -80, 440])]
    >>> uvl, uvr = [], []
    >>> for r, t in views:
    ...     Rk = rvec_to_matrix(r)
    ...     uvl.append(project_points_distorted(obj, K, Rk, t, None)[0])
    ...     uvr.append(project_points_distorted(obj, K, R @ Rk, R @ t + T, None)[0])
    >>> res = stereo_calibrate([obj] * 4, uvl, uvr, (640, 480), fix=("k3",))
    >>> np.round(res.T, 6).tolist() == [-120.0, 0.0, 0.0], round(res.rms, 9)
    (True, 0.0)
    """
    objs, imgs_l = _views(object_points, image_points_left, "image_points_left")
    objs_r, imgs_r = _views(object_points, image_points_right, "image_points_right")
    del objs_r
    model = check_option(model, CALIBRATION_MODELS, "calibration model")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[model]
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", minimum=0.0, maximum=1.0)
    size_l = _size(image_size, "image_size")
    size_r = size_l if image_size_right is None else _size(image_size_right, "image_size_right")
    V = len(objs)
    if V < 2:
        raise DegenerateConfigurationError(
            f"expected at least 2 views of the target seen by both cameras, got {V}"
        )
    if not isinstance(fix, str) and not (
        isinstance(fix, Collection) and all(isinstance(n, str) for n in fix)
    ):
        raise TypeError(f"expected fix as parameter names (str), got {describe(fix)}")
    fix_t = (fix,) if isinstance(fix, str) else tuple(fix)
    if left is None:
        cal_l = calibrate_camera(objs, imgs_l, size_l, skew=skew, fix=fix_t, model=model)
    else:
        cal_l = _as_calibration(left, "left")
    if right is None:
        cal_r = calibrate_camera(objs, imgs_r, size_r, skew=skew, fix=fix_t, model=model)
    else:
        cal_r = _as_calibration(right, "right")
    # each view's pose in each camera: from the single-camera fits, or by PnP when the
    # calibrations were given (their poses may belong to other views)
    rv_l, tv_l = _poses(cal_l, objs, imgs_l)
    rv_r, tv_r = _poses(cal_r, objs, imgs_r)
    Rl, Rr = rodrigues(rv_l), rodrigues(rv_r)
    R0 = _mean_rotation(Rr @ np.swapaxes(Rl, 1, 2))
    T0 = np.median(tv_r - (R0 @ tv_l[:, :, None])[:, :, 0], axis=0)
    if not np.linalg.norm(T0) > 0:
        raise DegenerateConfigurationError("the two cameras are at the same place (T = 0)")

    gl0 = _globals(cal_l, model, "left")
    gr0 = _globals(cal_r, model, "right")
    names = global_names(model)
    if fix_intrinsics:
        free_l = np.zeros(len(names), dtype=bool)
        free_r = np.zeros(len(names), dtype=bool)
    else:
        free_l = np.array([n not in cal_l.fixed and n not in fix_t for n in names])
        free_r = np.array([n not in cal_r.fixed and n not in fix_t for n in names])
        if not skew:
            free_l[4] = free_r[4] = False
    il, ir = np.flatnonzero(free_l), np.flatnonzero(free_r)
    nl, nr = il.size, ir.size
    obj = np.concatenate(objs)
    uv_l = np.concatenate(imgs_l)
    uv_r = np.concatenate(imgs_r)
    view = np.concatenate([np.full(o.shape[0], k, dtype=np.intp) for k, o in enumerate(objs)])
    M = obj.shape[0]
    n_par = nl + nr + 6 + 6 * V
    if n_par >= 4 * M:
        raise DegenerateConfigurationError(
            f"{M} points in {V} views give {4 * M} equations for {n_par} parameters"
        )
    o_rel = nl + nr  # columns of (rvec, T)
    o_pose = o_rel + 6
    zero_view = np.zeros(M, dtype=np.intp)

    def unpack(p: F64) -> tuple[F64, F64, F64, F64, F64, F64]:
        gl, gr = gl0.copy(), gr0.copy()
        gl[il] = p[:nl]
        gr[ir] = p[nl:o_rel]
        poses = p[o_pose:].reshape(V, 6)
        return gl, gr, p[o_rel : o_rel + 3], p[o_rel + 3 : o_pose], poses[:, :3], poses[:, 3:]

    def left_frame(rv: F64, tv: F64) -> F64:
        return np.asarray((rodrigues(rv)[view] @ obj[:, :, None])[:, :, 0] + tv[view])

    def fun(p: F64) -> F64:
        gl, gr, rr, T, rv, tv = unpack(p)
        ul = project_views(gl, rv, tv, obj, view, model=model)[0]
        ur = project_views(gr, rr[None], T[None], left_frame(rv, tv), zero_view, model=model)[0]
        return np.concatenate([(ul - uv_l).ravel(), (ur - uv_r).ravel()])

    rows = np.arange(M)[:, None, None]
    two = np.arange(2)[None, :, None]
    pose_cols = o_pose + 6 * view[:, None] + np.arange(6)

    def jac(p: F64) -> F64:
        gl, gr, rr, T, rv, tv = unpack(p)
        _, Jgl, Jpl = project_views(gl, rv, tv, obj, view, jac=True, model=model)
        Y = left_frame(rv, tv)
        _, Jgr, Jrel = project_views(gr, rr[None], T[None], Y, zero_view, jac=True, model=model)
        assert Jgl is not None and Jpl is not None and Jgr is not None and Jrel is not None
        Jc_r = Jrel[:, :, 3:] @ rodrigues(rr[None])[0]  # d u_r / d Y
        Jpose_r = np.concatenate([Jc_r @ _dcam_drvec(rv, view, obj), Jc_r], axis=-1)
        J = np.zeros((2, M, 2, n_par))
        J[0, :, :, :nl] = Jgl[:, :, il]
        J[0][rows, two, pose_cols[:, None, :]] = Jpl
        J[1, :, :, nl:o_rel] = Jgr[:, :, ir]
        J[1, :, :, o_rel:o_pose] = Jrel
        J[1][rows, two, pose_cols[:, None, :]] = Jpose_r
        return J.reshape(4 * M, n_par)

    p0 = np.concatenate(
        [gl0[il], gr0[ir], _rvec(R0), T0, np.concatenate([rv_l, tv_l], axis=1).ravel()]
    )
    p, r, J, n_it = levenberg_marquardt(fun, jac, p0, max_iter=max_iter, tol=tol)
    if n_it < 0:
        raise ConvergenceError(
            f"stereo refinement did not converge in {max_iter} iterations (RMS "
            f"{np.sqrt(np.sum(r**2) / (2 * M)):.4g} px); raise max_iter or check the input"
        )
    gl, gr, rr, T, rv, tv = unpack(p)
    std = _std(J, r, p.size)
    res = -r.reshape(2, M, 2)
    R = rodrigues(rr[None])[0]
    Rr_views = R @ rodrigues(rv)
    rv_right = np.array([_rvec(Rk) for Rk in Rr_views])
    tv_right = (R @ tv[:, :, None])[:, :, 0] + T
    sq = np.sum(res**2, axis=2)  # (2, M)
    per_view = np.array([[np.sqrt(np.mean(sq[c, view == k])) for c in range(2)] for k in range(V)])
    cams = []
    for c, (g, idx, off, cal, rvs, tvs, size) in enumerate(
        (
            (gl, il, 0, cal_l, rv, tv, size_l),
            (gr, ir, nl, cal_r, rv_right, tv_right, size_r),
        )
    ):
        sd = np.zeros(len(names))
        sd[idx] = std[off : off + idx.size]
        K = np.array([[g[0], g[4], g[2]], [0.0, g[1], g[3]], [0.0, 0.0, 1.0]])
        coeffs = (float(v) for v in g[5:])
        cams.append(
            CalibrationResult(
                K=K,
                distortion=(
                    KannalaBrandt(*coeffs) if model == "kannala_brandt" else BrownConrady(*coeffs)
                ),
                image_size=size,
                rvecs=rvs,
                tvecs=tvs,
                rms=float(np.sqrt(sq[c].mean())),
                per_view_rms=per_view[:, c],
                residuals=tuple(res[c][view == k] for k in range(V)),
                std={n: float(s) for n, s in zip(names, sd, strict=True)},
                std_poses=std[o_pose:].reshape(V, 6) if c == 0 else np.full((V, 6), np.nan),
                fixed=tuple(
                    n for n, f in zip(names, free_l if c == 0 else free_r, strict=True) if not f
                ),
                warnings=cal.warnings,
                n_evaluations=n_it,
                model=model,
            )
        )
    return StereoCalibrationResult(
        left=cams[0],
        right=cams[1],
        R=R,
        T=T.copy(),
        rms=float(np.sqrt(sq.mean())),
        std_rvec=std[o_rel : o_rel + 3],
        std_T=std[o_rel + 3 : o_pose],
        per_view_rms=per_view,
        fixed_intrinsics=bool(fix_intrinsics),
        n_evaluations=n_it,
    )


def _size(value: Any, name: str) -> tuple[int, int]:
    if (
        not isinstance(value, tuple | list)
        or len(value) != 2
        or not all(isinstance(n, int | np.integer) and n > 0 for n in value)
    ):
        raise InvalidInputError(f"expected {name} (width, height) > 0, got {describe(value)}")
    return size_pair(value, f"{name} (width, height)")


def _model(value: Any, name: str, method: str) -> Any:
    """Check a distortion model (anything with ``method`` on normalised coordinates) or None."""
    if value is not None and not callable(getattr(value, method, None)):
        raise InvalidInputError(
            f"expected {name} as a distortion model (BrownConrady, DivisionModel, "
            f"KannalaBrandt) or None, got {describe(value)}"
        )
    return value


def _globals(cal: CalibrationResult, model: str, side: str) -> F64:
    """``(fx, fy, cx, cy, skew, coefficients of model)`` of a calibration of that model."""
    K = cal.K
    d = cal.distortion
    cls = KannalaBrandt if model == "kannala_brandt" else BrownConrady
    if not isinstance(d, cls) or cal.model != model:
        got = cal.model if isinstance(d, cls) else f"{type(d).__name__} distortion"
        raise InvalidInputError(
            f"expected {side} as a {model} calibration (the model of stereo_calibrate), got {got}"
        )
    n = len(global_names(model)) - 5
    return np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], K[0, 1], *d.coeffs[:n]], dtype=float)


def _poses(cal: CalibrationResult, objs: list[F64], imgs: list[F64]) -> tuple[F64, F64]:
    """Return the per-view poses of ``cal``, or (when it holds other views) from PnP with its K."""
    if cal.rvecs.shape[0] == len(objs):
        return np.asarray(cal.rvecs, dtype=float), np.asarray(cal.tvecs, dtype=float)
    from imageform.geometry.pnp import solve_pnp

    rv, tv = [], []
    for o, i in zip(objs, imgs, strict=True):
        sol = solve_pnp(o, i, cal.K, distortion=cal.distortion)
        rv.append(np.asarray(sol.rvec, dtype=np.float64).reshape(3))
        tv.append(np.asarray(sol.tvec, dtype=np.float64).reshape(3))
    return np.array(rv), np.array(tv)


def _std(J: F64, r: F64, n: int) -> F64:
    """``sqrt(diag(σ² (JᵀJ)⁻¹))``, ``σ² = ‖r‖² / (m - n)``, with Jacobi scaling."""
    dof = r.size - n
    sigma2 = float(r @ r) / dof if dof > 0 else np.nan
    JtJ = J.T @ J
    d = np.sqrt(np.diag(JtJ))
    d = np.where(d > 0, d, 1.0)
    try:
        cov = np.linalg.inv(JtJ / np.outer(d, d)) / np.outer(d, d) * sigma2
    except np.linalg.LinAlgError:
        return np.full(n, np.inf)
    dg = np.diag(cov)
    return np.where(dg >= 0, np.sqrt(np.abs(dg)), np.nan)


# ---------------------------------------------------------------- rectification


class StereoRectification(NamedTuple):
    """Rectifying rotations and projections of a stereo pair (``cv2.stereoRectify``).

    Attributes
    ----------
    R1, R2 : ndarray (3, 3)
        Rotations from each (unrectified) camera frame to its rectified frame.
    P1, P2 : ndarray (3, 4)
        Projections of the rectified cameras, in the rectified left frame:
        ``P1 = [[f, 0, c1x, 0], [0, f, c1y, 0], [0, 0, 1, 0]]``, ``P2`` the same with
        ``c2x, c2y`` and ``P2[0, 3] = f T'_x`` (horizontal pair) or ``P2[1, 3] = f T'_y``.
    Q : ndarray (4, 4)
        Disparity-to-depth matrix: ``(X, Y, Z, W)ᵀ = Q (u, v, d, 1)ᵀ`` with
        ``d = u_left - u_right``.
    image_size : (int, int)
        ``(width, height)`` of the rectified images.
    vertical : bool
        True when the cameras are stacked vertically (``|T'_y| > |T'_x|``): the rectified
        images then share columns, not rows.
    """

    R1: F64
    R2: F64
    P1: F64
    P2: F64
    Q: F64
    image_size: tuple[int, int]
    vertical: bool


def _undistort_pixels(uv: F64, K: F64, dist: Any) -> F64:
    y = (uv[:, 1] - K[1, 2]) / K[1, 1]
    x = (uv[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    xy = np.stack([x, y], -1)
    if dist is not None:
        xy = np.asarray(to_numpy(dist.undistort(xy).xy), dtype=np.float64)
    return xy


def _rectified_pixels(uv: F64, K: F64, dist: Any, Rr: F64, P: F64) -> F64:
    """Where pixels ``uv`` of the original image land in the rectified image."""
    xy = _undistort_pixels(uv, K, dist)
    X = np.concatenate([xy, np.ones((xy.shape[0], 1))], 1) @ Rr.T
    x = X[:, :2] / X[:, 2:]
    return np.stack([P[0, 0] * x[:, 0] + P[0, 2], P[1, 1] * x[:, 1] + P[1, 2]], -1)


def _rectangles(
    K: F64, dist: Any, Rr: F64, P: F64, size: tuple[int, int]
) -> tuple[tuple[float, float, float, float], tuple[float, float, float, float]]:
    """Inner and outer rectangles ``(x0, y0, x1, y1)`` of the valid rectified pixels.

    A 9 x 9 grid over the pixel centres ``[0, W-1] x [0, H-1]`` (OpenCV 4/5's
    ``getUndistortRectangles``).
    """
    n = 9
    p = _rectified_pixels(_grid(size, n), K, dist, Rr, P).reshape(n, n, 2)
    ok = np.all(np.isfinite(p), axis=-1)
    if ok.all():
        inner = (
            float(p[:, 0, 0].max()),
            float(p[0, :, 1].max()),
            float(p[:, -1, 0].min()),
            float(p[-1, :, 1].min()),
        )
    else:  # a lens model not invertible out to the image's edge: its outermost valid points
        rows, cols = np.flatnonzero(ok.any(axis=1)), np.flatnonzero(ok.any(axis=0))
        first_c, last_c = ok.argmax(axis=1), n - 1 - ok[:, ::-1].argmax(axis=1)
        first_r, last_r = ok.argmax(axis=0), n - 1 - ok[::-1, :].argmax(axis=0)
        inner = (
            float(p[rows, first_c[rows], 0].max()),
            float(p[first_r[cols], cols, 1].max()),
            float(p[rows, last_c[rows], 0].min()),
            float(p[last_r[cols], cols, 1].min()),
        )
    q = p[ok]
    outer = (float(q[:, 0].min()), float(q[:, 1].min()), float(q[:, 0].max()), float(q[:, 1].max()))
    return inner, outer


def _grid(size: tuple[int, int], n: int) -> F64:
    """Return an ``n`` x ``n`` grid over the pixel centres ``[0, W-1] x [0, H-1]``, row by row."""
    w, h = size
    gy, gx = np.mgrid[0:n, 0:n].astype(np.float64)
    return np.stack([gx.ravel() * (w - 1) / (n - 1), gy.ravel() * (h - 1) / (n - 1)], -1)


def _rectified_center(K: F64, dist: Any, Rr: F64, P0: F64, size: tuple[int, int]) -> F64:
    """Mean rectified position of the image's four corners (``cvStereoRectify``'s rule).

    Where the lens model cannot be inverted at a corner (a fitted polynomial that folds back
    before the image's edge: Newton's inverse is NaN there), the rectified position of the
    image's middle pixel stands for the mean (the two agree without distortion and rotation).
    """
    nx, ny = size
    corners = np.array([[0.0, 0.0], [nx - 1.0, 0.0], [0.0, ny - 1.0], [nx - 1.0, ny - 1.0]])
    pts = _rectified_pixels(corners, K, dist, Rr, P0)
    if np.all(np.isfinite(pts)):
        return np.asarray(pts.mean(axis=0), dtype=np.float64)
    mid = _rectified_pixels(np.array([[(nx - 1) / 2.0, (ny - 1) / 2.0]]), K, dist, Rr, P0)[0]
    if not np.all(np.isfinite(mid)):
        raise InvalidInputError(
            "the lens distortion cannot be inverted at the image's middle: the calibration's "
            "distortion is not usable for rectification"
        )
    return np.asarray(mid, dtype=np.float64)


def _matrix(value: Any, name: str, shape: tuple[int, ...]) -> F64:
    # None, strings, complex and object arrays refused by name; the shape before the values
    a = as_real_array(value, name, check=False)
    if a.shape != shape and not (shape == (3,) and a.size == 3):
        raise InvalidInputError(f"expected {name} of shape {shape}, got shape {a.shape}")
    check_bounded(a, name, np)
    return a.reshape(shape)


def stereo_rectify(
    K1: npt.ArrayLike,
    distortion1: DistortionModel | None,
    K2: npt.ArrayLike,
    distortion2: DistortionModel | None,
    image_size: tuple[int, int],
    R: npt.ArrayLike,
    T: npt.ArrayLike,
    *,
    alpha: float = -1.0,
    zero_disparity: bool = True,
    new_image_size: tuple[int, int] | None = None,
) -> StereoRectification:
    r"""Bouguet's rectification of a calibrated stereo pair (as ``cv2.stereoRectify``).

    Each camera is rotated by half the relative rotation, ``r = rodrigues(-rvec(R)/2)``
    (so the left turns by ``rᵀ`` and the right by ``r``), then both by the rotation
    ``W`` that takes the rotated baseline ``t = r T`` to the x axis (or y axis, for a
    vertical pair):

    .. math::

        R_1 = W r^\mathsf{T}, \quad R_2 = W r, \quad
        W = \mathrm{rodrigues}\!\left(\frac{t \times u}{\|t \times u\|}
        \arccos\frac{|t_x|}{\|t\|}\right),\ u = (\mathrm{sign}\,t_x, 0, 0)

    which minimises the reprojection distortion while making epipolar lines horizontal
    (J.-Y. Bouguet, Camera Calibration Toolbox for Matlab, ``rectify_stereo_pair.m``;
    Bradski & Kaehler, *Learning OpenCV*, 2008, ch. 12, "Bouguet's algorithm"). Both
    rectified cameras get the focal length ``f = (f_{y,1} + f_{y,2}) / 2`` (``f_x`` for a
    vertical pair) and principal points that centre the undistorted image corners; with
    ``zero_disparity`` both principal points are the same (points at infinity have zero
    disparity), otherwise only the shared coordinate. ``P2`` carries the baseline:
    ``P2[0, 3] = f T'_x`` with ``T' = R_2 T``.

    Parameters
    ----------
    K1, K2 : array_like (3, 3)
        Intrinsics of the left and the right camera.
    distortion1, distortion2 : BrownConrady or other model, or None
        Their distortion (anything with ``undistort`` on normalised coordinates).
    image_size : (int, int)
        ``(width, height)`` of the images.
    R, T : array_like (3, 3), (3,)
        ``X_right = R X_left + T`` (:func:`stereo_calibrate`'s ``R``, ``T``).
    alpha : float
        Free scaling. ``-1`` (default, as OpenCV): no scaling, ``f`` as above. ``0``: zoom so
        that every rectified pixel is valid (no black border; pixels of the originals are
        lost); ``1``: shrink so that every original pixel is kept (black borders); values
        in between interpolate the scale linearly (OpenCV's behaviour).
    zero_disparity : bool
        Equal principal points in both rectified images (OpenCV's
        ``CALIB_ZERO_DISPARITY``, its default).
    new_image_size : (int, int), optional
        Size of the rectified images (default ``image_size``).

    Returns
    -------
    StereoRectification
        ``R1, R2, P1, P2, Q, image_size, vertical``.

    Notes
    -----
    The undistorted image corners are computed exactly (Newton iterations) where OpenCV
    uses 5 fixed-point iterations in float32, so principal points differ from OpenCV's
    by the error of those (≪ 0.01 px for moderate distortion); ``R1, R2`` are identical.
    """
    K1m = _matrix(K1, "K1", (3, 3))
    K2m = _matrix(K2, "K2", (3, 3))
    distortion1 = _model(distortion1, "distortion1", "undistort")
    distortion2 = _model(distortion2, "distortion2", "undistort")
    Rm = _matrix(R, "R", (3, 3))
    Tv = _matrix(T, "T", (3,))
    size = _size(image_size, "image_size")
    new_size = size if new_image_size is None else _size(new_image_size, "new_image_size")
    a = float(as_real(alpha, "alpha"))
    nx, ny = size
    om = _rvec(Rm) * -0.5
    r_r = rodrigues(om[None])[0]
    t = r_r @ Tv
    idx = 0 if abs(t[0]) > abs(t[1]) else 1
    c = t[idx]
    nt = float(np.linalg.norm(t))
    if not nt > 0:
        raise DegenerateConfigurationError("expected a non-zero baseline T, got T = 0")
    uu = np.zeros(3)
    uu[idx] = 1.0 if c > 0 else -1.0
    ww = np.cross(t, uu)
    nw = float(np.linalg.norm(ww))
    if nw > 0:
        ww *= np.arccos(min(abs(c) / nt, 1.0)) / nw
    wR = rodrigues(ww[None])[0]
    R1 = wR @ r_r.T
    R2 = wR @ r_r
    t2 = R2 @ Tv
    ratio = (new_size[0] / nx if idx == 1 else new_size[1] / ny) / 2.0
    j = idx ^ 1
    fc = (K1m[j, j] + K2m[j, j]) * ratio
    cc = np.zeros((2, 2))
    for k, (K, d, Rk) in enumerate(((K1m, distortion1, R1), (K2m, distortion2, R2))):
        P0 = np.array([[fc, 0.0, 0.0], [0.0, fc, 0.0], [0.0, 0.0, 1.0]])
        mid = _rectified_center(K, d, Rk, P0, (nx, ny))
        cc[k] = [(nx - 1) / 2.0 - mid[0], (ny - 1) / 2.0 - mid[1]]
    if zero_disparity:
        cc[:] = cc.mean(axis=0)
    else:
        cc[:, j] = cc[:, j].mean()
    P1 = np.zeros((3, 4))
    P1[0, 0] = P1[1, 1] = fc
    P1[:2, 2] = cc[0]
    P1[2, 2] = 1.0
    P2 = P1.copy()
    P2[:2, 2] = cc[1]
    P2[idx, 3] = t2[idx] * fc
    a = min(a, 1.0)
    c1 = (new_size[0] * cc[0, 0] / nx, new_size[1] * cc[0, 1] / ny)
    c2 = (new_size[0] * cc[1, 0] / nx, new_size[1] * cc[1, 1] / ny)
    s = 1.0
    if a >= 0:
        in1, out1 = _rectangles(K1m, distortion1, R1, P1, size)
        in2, out2 = _rectangles(K2m, distortion2, R2, P2, size)
        W, H = new_size

        def scales(cn: tuple[float, float], c0: F64, rect: tuple[float, ...]) -> list[float]:
            x0, y0, x1, y1 = rect
            return [
                cn[0] / (c0[0] - x0),
                cn[1] / (c0[1] - y0),
                (W - 1 - cn[0]) / (x1 - c0[0]),
                (H - 1 - cn[1]) / (y1 - c0[1]),
            ]

        s0 = max(scales(c1, cc[0], in1) + scales(c2, cc[1], in2))
        s1 = min(scales(c1, cc[0], out1) + scales(c2, cc[1], out2))
        s = s0 * (1.0 - a) + s1 * a
    fc *= s
    P1[0, 0] = P1[1, 1] = P2[0, 0] = P2[1, 1] = fc
    P1[:2, 2] = c1
    P2[:2, 2] = c2
    P2[idx, 3] *= s
    Q = np.array(
        [
            [1.0, 0.0, 0.0, -c1[0]],
            [0.0, 1.0, 0.0, -c1[1]],
            [0.0, 0.0, 0.0, fc],
            [0.0, 0.0, -1.0 / t2[idx], (c1[idx] - c2[idx]) / t2[idx]],
        ]
    )
    return StereoRectification(R1, R2, P1, P2, Q, new_size, idx == 1)


def rectification_map(
    K: npt.ArrayLike,
    distortion: DistortionModel | None,
    R_rect: npt.ArrayLike,
    P: npt.ArrayLike,
    image_size: tuple[int, int],
) -> F64:
    r"""Source pixel of every rectified pixel (as ``cv2.initUndistortRectifyMap``).

    For a rectified pixel ``(u, v)``:

    .. math::

        (X, Y, W)^\mathsf{T} = R_{rect}^\mathsf{T}\, P_{3 \times 3}^{-1} (u, v, 1)^\mathsf{T},
        \quad (u_s, v_s, 1)^\mathsf{T} = K\,(\mathrm{distort}(X/W, Y/W), 1)^\mathsf{T}

    (OpenCV, ``initUndistortRectifyMap`` documentation). Apply it with
    :func:`~imageform.geometry.remap_bilinear`: ``remap_bilinear(image, map_uv)``.

    Parameters
    ----------
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model or None
        Its distortion (``distort`` on normalised coordinates).
    R_rect : array_like (3, 3)
        ``R1`` or ``R2`` of :func:`stereo_rectify`.
    P : array_like (3, 4) or (3, 3)
        ``P1`` or ``P2`` (only its left 3 x 3 block is used).
    image_size : (int, int)
        ``(width, height)`` of the rectified image.

    Returns
    -------
    ndarray (height, width, 2)
        Source ``(u, v)`` in the original image; NaN where behind the camera.
    """
    Km = _matrix(K, "K", (3, 3))
    Rr = _matrix(R_rect, "R_rect", (3, 3))
    distortion = _model(distortion, "distortion", "distort")
    Pm = as_real_array(P, "P", check=False)
    if Pm.shape not in ((3, 4), (3, 3)):
        raise InvalidInputError(f"expected P of shape (3, 4) or (3, 3), got shape {Pm.shape}")
    check_bounded(Pm, "P", np)
    w, h = _size(image_size, "image_size")
    check_memory(8.0 * w * h * 12, "image_size", f"a ({h}, {w}, 2) rectification map")
    check_positive(abs(float(np.linalg.det(Pm[:, :3]))), "det(P[:, :3])")
    A = Rr.T @ np.linalg.inv(Pm[:, :3])
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    X = np.stack([u, v, np.ones_like(u)], -1) @ A.T
    with np.errstate(divide="ignore", invalid="ignore"):
        xy = X[..., :2] / X[..., 2:]
    xy[X[..., 2] <= 0] = np.nan
    if distortion is not None:
        xy = np.asarray(to_numpy(distortion.distort(xy)), dtype=np.float64)
    us = Km[0, 0] * xy[..., 0] + Km[0, 1] * xy[..., 1] + Km[0, 2]
    vs = Km[1, 1] * xy[..., 1] + Km[1, 2]
    return np.stack([us, vs], axis=-1)
