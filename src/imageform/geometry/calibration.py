"""Camera calibration: Zhang's method for planar targets, DLT for 3-D rigs, then LM.

:func:`calibrate_camera` estimates the intrinsics ``K`` (``fx, fy, cx, cy`` and optionally
the skew), the lens distortion (Brown-Conrady ``(k1, k2, p1, p2, k3)`` by default, OpenCV's
rational ``k1 ... k6`` or the Kannala-Brandt fisheye ``k1 ... k4``; any parameter can be
fixed) and one pose per view from known object points and their detected pixels, and returns a
:class:`CalibrationResult` with the reprojection errors (overall RMS as OpenCV defines it,
per view and per point) and the standard deviations of the parameters.

Helpers: ``calibration_zhang`` (closed-form initial values), ``calibration_refine``
(Levenberg-Marquardt on the Jacobian's blocks, the poses eliminated by the Schur
complement), ``calibration_result`` (the result dataclass and its TOML form).
"""

from __future__ import annotations

import warnings
from collections.abc import Collection, Sequence

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._validate import (
    as_bool,
    as_int,
    as_matrix_bounded,
    as_real,
    check_image_size,
    check_K,
    check_memory,
    check_option,
    describe,
    size_pair,
)
from imageform.errors import (
    ConvergenceError,
    DegenerateConfigurationError,
    IllConditionedWarning,
    InvalidInputError,
)
from imageform.geometry.calibration_refine import (
    CALIBRATION_MODELS,
    COND_WARN,
    RefineOutput,
    StalledRefinement,
    global_names,
    refine,
    rodrigues,
)
from imageform.geometry.calibration_result import CalibrationResult
from imageform.geometry.calibration_views import _views
from imageform.geometry.calibration_zhang import (
    centre_intrinsics,
    dlt_init,
    homographies_of,
    poses_from_homographies,
    zhang_intrinsics,
)
from imageform.geometry.distortion import BrownConrady, KannalaBrandt
from imageform.geometry.homography import estimate_homography

__all__ = ["CalibrationResult", "calibrate_camera", "checkerboard_points"]

F64 = NDArray[np.float64]

#: Views fewer than this (planar target) trigger an :class:`IllConditionedWarning`.
MIN_GOOD_VIEWS = 3
#: Largest board tilt (degrees) below which the focal length is poorly determined.
MIN_TILT_DEG = 10.0
#: Largest angle (degrees) between two views' board normals below which the views are
#: nearly one orientation: the focal length then trades against the board's distance.
MIN_SPREAD_DEG = 5.0
#: Largest angle (degrees) of the views' board normals from one plane through the camera below
#: which the board is tilted about nearly one axis: the focal length and the principal point
#: are then poorly determined (Sturm & Maybank 1999, "On plane-based camera calibration: a
#: general algorithm, singularities, applications", CVPR, sec. 4); named when the
#: refinement finds no minimum.
MIN_AXIS_DEG = 8.0
#: Largest angle (degrees) between two views' board normals below which a turn about nearly
#: one axis (:data:`MIN_AXIS_DEG`) is named as leaving the focal length open.
MAX_AXIS_TURN_DEG = 25.0
#: Fraction of the image area that the points of all views should span.
MIN_COVERAGE = 0.25


def checkerboard_points(pattern_size: tuple[int, int], square_size: float = 1.0) -> F64:
    r"""Board points ``(cols*rows, 3)`` in the detector's order: ``(c s, r s, 0)``, row by row.

    .. math:: \mathbf{X}_{r \cdot \text{cols} + c} = (c\,s,\ r\,s,\ 0)

    The order of :func:`~imageform.geometry.checkerboard.find_checkerboard` and OpenCV's
    tutorial (``objp[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2)``).

    Examples
    --------
    >>> checkerboard_points((3, 2), 25.0)[[0, 1, 3]].tolist()
    [[0.0, 0.0, 0.0], [25.0, 0.0, 0.0], [0.0, 25.0, 0.0]]
    """
    cols, rows = size_pair(pattern_size, "pattern_size (cols, rows)", minimum=2)
    check_memory(24.0 * cols * rows, "pattern_size", f"{cols} x {rows} board points")
    s = as_real(square_size, "square_size", positive=True, maximum=1e90)
    r, c = np.mgrid[0:rows, 0:cols]
    return np.stack([c.ravel() * s, r.ravel() * s, np.zeros(rows * cols)], axis=-1).astype(float)


def _is_planar_z0(objs: list[F64]) -> bool:
    scale = max(float(np.abs(o).max()) for o in objs) or 1.0
    return all(float(np.abs(o[:, 2]).max()) <= 1e-9 * scale for o in objs)


def _check_fix(fix: Collection[str], skew: bool, model: str) -> NDArray[np.bool_]:
    if isinstance(fix, str):
        fix = (fix,)
    if not hasattr(fix, "__iter__") or getattr(fix, "ndim", 1) == 0:
        raise InvalidInputError(f"expected fix as parameter names, got {describe(fix)}")
    items = list(fix)
    for f in items:
        if not isinstance(f, str):
            raise InvalidInputError(f"expected fix as parameter names (str), got {describe(f)}")
    every = global_names(model)
    names = {check_option(f, every, f"{model} calibration parameter in fix") for f in items}
    free = np.array([n not in names for n in every])
    if not skew:
        free[every.index("skew")] = False
    return free


def _warn_conditioning(
    planar: bool, rvecs: F64, imgs: list[F64], image_size: tuple[int, int], cond: float
) -> tuple[str, ...]:
    notes = []
    if planar and len(imgs) < MIN_GOOD_VIEWS:
        notes.append(
            f"only {len(imgs)} view(s) of a planar target; use at least {MIN_GOOD_VIEWS} "
            "(10-20 recommended) at different tilts"
        )
    if planar:
        notes.extend(_orientation_problems(rvecs))
    pts = np.concatenate(imgs)
    w, h = image_size
    span = (np.ptp(pts[:, 0]) * np.ptp(pts[:, 1])) / float(w * h)
    if span < MIN_COVERAGE:
        notes.append(
            f"the points of all views span only {100 * span:.0f} % of the image; cover the "
            "whole frame (distortion is determined only where there are points)"
        )
    if cond > COND_WARN:
        notes.append(f"the normal equations are nearly singular (condition number {cond:.2g})")
    for n in notes:
        warnings.warn(n, IllConditionedWarning, stacklevel=3)
    return tuple(notes)


def _orientation_problems(rvecs: F64) -> list[str]:
    """Name what the boards' orientations leave open (Zhang 2000, sec. 3.3): tilt, spread.

    The focal length is fixed by the foreshortening of a tilted plane, and only when the
    views' planes are not parallel: the same tilt in every view leaves a valley in which
    focal length and board distance trade against each other.
    """
    R = rodrigues(rvecs)
    normal = R[:, :, 2]  # the board's normal in camera coordinates, one per view
    tilt = np.degrees(np.arccos(np.clip(np.abs(normal[:, 2]), 0.0, 1.0)))
    if float(tilt.max()) < MIN_TILT_DEG:
        return [
            f"the board is tilted at most {tilt.max():.1f} deg from fronto-parallel; tilts "
            f"of {MIN_TILT_DEG:g} deg or more are needed to determine the focal length"
        ]
    spread = np.degrees(np.arccos(np.clip(np.abs(normal @ normal.T), 0.0, 1.0)))
    if len(rvecs) > 1 and float(spread.max()) < MIN_SPREAD_DEG:
        return [
            f"the board has nearly one orientation in every view (normals within "
            f"{spread.max():.1f} deg of each other); the focal length is not determined: "
            "tilt it differently across views (20-45 deg, about different axes)"
        ]
    return []


def _normal_spreads(rvecs: F64) -> tuple[float, float]:
    """Largest angle (degrees) between two views' board normals, and from their best plane."""
    n = rodrigues(rvecs)[:, :, 2]
    apart = float(np.degrees(np.arccos(np.clip(np.abs(n @ n.T), 0.0, 1.0))).max())
    off = float(np.abs(n @ np.linalg.svd(n)[2][-1]).max())
    return apart, float(np.degrees(np.arcsin(min(off, 1.0))))


def _stall_cause(pose_sets: list[F64]) -> str | None:
    """Why the refinement found no minimum, from the poses of its starts and its last steps.

    The start's poses come from a start K that can be far off along the very valley the
    views leave open (a focal length twice the truth spread boards held at one orientation,
    normals within 1.3 deg, over 5.5 deg), so each set of poses is asked: nearly one
    orientation (or no tilt) first, then a small turn about nearly one axis: every normal
    within :data:`MIN_AXIS_DEG` of one plane and within :data:`MAX_AXIS_TURN_DEG` of each
    other (four of OpenCV's views, normals within 3.1 deg of a plane but 57 deg apart,
    calibrate).
    """
    for rv in pose_sets:
        why = _orientation_problems(rv)
        if why:
            return why[0]
    if min(len(rv) for rv in pose_sets) < 3:
        return None
    near = [
        (off, apart)
        for apart, off in map(_normal_spreads, pose_sets)
        if off < MIN_AXIS_DEG and apart < MAX_AXIS_TURN_DEG
    ]
    if not near:
        return None
    off, apart = min(near)
    return (
        f"the board is turned about nearly one axis in every view, and little (normals within "
        f"{off:.1f} deg of one plane and {apart:.0f} deg of each other); the focal length and "
        "principal point are not determined: add views with the board tilted 20-45 deg about "
        "another axis"
    )


#: Iteration budget of the refinement of each model when ``max_iter`` is not given: the
#: rational model's numerator and denominator nearly share a factor, and the refinement
#: walks that long valley for hundreds of iterations before it stops.
DEFAULT_MAX_ITER = {"brown_conrady": 100, "rational": 1000, "kannala_brandt": 100}
#: Largest ray angle (degrees) from the axis of the points that start a fisheye calibration:
#: near 90 deg the pinhole coordinates ``tan θ`` of the unwarped points run to infinity.
MAX_START_ANGLE_DEG = 80.0


def _equidistant_start(
    objs: list[F64],
    imgs: list[F64],
    size: tuple[int, int],
    K_given: F64 | None,
    d0: KannalaBrandt,
    planar: bool,
) -> tuple[F64, F64, F64]:
    r"""K and poses that start a fisheye calibration, as ``cv::fisheye::calibrate`` does.

    ``f = max(w, h) / π`` (an equidistant lens, ``r_d = f θ``, whose 180 deg field spans the
    image), the principal point at the image centre (or ``K_given``); each view's pixels are
    unwarped through ``d0`` to pinhole coordinates ``tan θ (cos φ, sin φ)``, the points beyond
    :data:`MAX_START_ANGLE_DEG` dropped, and the pose comes from the homography of the board
    to them (``K = I``; Zhang 2000, sec. 3.1), or the DLT of a 3-D rig.
    """
    w, h = size
    if K_given is None:
        f = max(w, h) / np.pi
        K0 = np.array([[f, 0.0, (w - 1) / 2.0], [0.0, f, (h - 1) / 2.0], [0.0, 0.0, 1.0]])
    else:
        K0 = K_given
    lim = np.tan(np.radians(MAX_START_ANGLE_DEG))
    rv, tv = [], []
    for k, (o, i) in enumerate(zip(objs, imgs, strict=True)):
        xd = np.linalg.solve(K0, np.c_[i, np.ones(len(i))].T).T[:, :2]
        xy, ok = d0.undistort(xd)
        ok = np.asarray(ok) & (np.hypot(xy[:, 0], xy[:, 1]) < lim)
        if int(ok.sum()) < 6:
            raise DegenerateConfigurationError(
                f"view {k}: fewer than 6 points within {MAX_START_ANGLE_DEG:g} deg of the "
                "axis at the start of the fisheye calibration; give K_init"
            )
        if planar:
            H = np.asarray(estimate_homography(o[ok, :2], xy[ok]), dtype=np.float64)
            r, t = poses_from_homographies(H[None], np.eye(3))
            rv.append(r[0])
            tv.append(t[0])
        else:
            _, r, t = dlt_init([o[ok]], [xy[ok]])
            rv.append(r[0])
            tv.append(t[0])
    return K0, np.stack(rv), np.stack(tv)


def _behind_camera(objs: list[F64], rvecs: F64, tvecs: F64) -> bool:
    """Whether a point of some view is at or behind the camera (``Z_c <= 0``) in these poses."""
    R = rodrigues(rvecs)
    return any(bool(np.any(o @ R[k][2] + tvecs[k][2] <= 0.0)) for k, o in enumerate(objs))


def calibrate_camera(
    object_points: Sequence[npt.ArrayLike],
    image_points: Sequence[npt.ArrayLike],
    image_size: tuple[int, int],
    *,
    skew: bool = False,
    fix: Collection[str] = (),
    K_init: npt.ArrayLike | None = None,
    distortion_init: BrownConrady | KannalaBrandt | None = None,
    method: str = "auto",
    max_iter: int | None = None,
    tol: float = 1e-10,
    model: str = "brown_conrady",
) -> CalibrationResult:
    r"""Calibrate a camera from views of a known target: closed form, then Levenberg-Marquardt.

    Minimises the reprojection error over ``K``, the lens model's coefficients ``d`` and the
    poses ``(R_k, t_k)`` of the V views:

    .. math::

        \min \sum_{k=1}^{V} \sum_{i=1}^{N_k}
        \left\| \mathbf{u}_{ki} - \pi\!\left(K, d, R_k \mathbf{X}_{ki} + \mathbf{t}_k
        \right) \right\|^2

    The models (``model``), on the normalised coordinates ``(x, y) = (X_c/Z_c, Y_c/Z_c)``,
    ``r² = x² + y²``:

    - ``"brown_conrady"`` (default): ``(k1, k2, p1, p2, k3)``,
      ``x_d = x (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2 x²)`` (OpenCV's
      ``calibrateCamera``).
    - ``"rational"``: ``(k1, k2, p1, p2, k3, k4, k5, k6)``, the radial factor
      ``(1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶)`` (OpenCV's
      ``CALIB_RATIONAL_MODEL``); wide-angle lenses to about 120 deg.
    - ``"kannala_brandt"``: ``(k1, k2, k3, k4)``, ``θ = atan r``,
      ``θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)``, ``(x_d, y_d) = (θ_d / r) (x, y)``
      (Kannala & Brandt 2006, IEEE TPAMI 28(8), eq. (6); OpenCV's ``cv::fisheye``): fisheye
      and endoscope lenses, fields of view to 180 deg (rays to 90 deg from the axis).

    Initial values: for a planar target (all ``Z = 0``) Zhang's closed form from the
    homographies (Zhang 2000, "A flexible new technique for camera calibration", IEEE TPAMI
    22(11), sec. 3.1 and appendix B); for a non-planar rig the normalised DLT per view and
    its RQ decomposition (Hartley & Zisserman, 2nd ed., Algorithm 7.1, sec. 6.2.4) —
    OpenCV's ``calibrateCamera`` cannot start from a 3-D rig without ``K_init``.
    Kannala-Brandt starts as ``cv::fisheye::calibrate`` does (``method="equidistant"``):
    ``f = max(w, h) / π``, the principal point at the image centre, each view's pose from
    the homography of the board to its pixels unwarped by the equidistant model (rays
    beyond 80 deg dropped); for a planar target it also starts from Zhang's pinhole
    closed form and keeps the fit of lower cost. Distortion starts at zero (or
    ``distortion_init``). The refinement is Levenberg-Marquardt with the analytic,
    block-sparse Jacobian of each model.

    Parameters
    ----------
    object_points : sequence of array_like (N_k, 3)
        Target points of each view, in target units (e.g. mm); ``Z = 0`` for a planar board
        (see :func:`checkerboard_points`).
    image_points : sequence of array_like (N_k, 2)
        Their pixels ``(u, v)``, top-left pixel centre = (0, 0).
    image_size : (int, int)
        ``(width, height)`` in pixels.
    skew : bool
        Estimate the skew ``K[0, 1]`` (default: fixed at 0, as OpenCV).
    fix : collection of str
        Parameters held at their initial values: any of ``fx, fy, cx, cy, skew`` and the
        model's coefficients (Brown-Conrady ``k1, k2, p1, p2, k3``; rational also ``k4, k5,
        k6``; Kannala-Brandt ``k1 ... k4``, no ``p1, p2``) (fixing e.g. ``k3`` as OpenCV's
        ``CALIB_FIX_K3``; a fixed distortion coefficient keeps its ``distortion_init``
        value, 0 by default).
    K_init, distortion_init : optional
        Initial ``K`` (3, 3) (skips the closed form) and distortion: a
        :class:`~imageform.geometry.BrownConrady` (``brown_conrady``, ``rational``) or a
        :class:`~imageform.geometry.KannalaBrandt` (``kannala_brandt``).
    method : {"auto", "zhang", "dlt", "equidistant"}
        Initialiser; ``auto`` is Zhang for a planar ``Z = 0`` target, DLT otherwise, and
        for ``kannala_brandt`` the equidistant start (and Zhang's, for a planar target).
        ``equidistant`` is for ``kannala_brandt`` only.
    max_iter, tol : int, float
        Iteration budget (default :data:`DEFAULT_MAX_ITER` of the model: 100, 1000 for
        ``rational``) and the relative tolerances of the refinement.
    model : {"brown_conrady", "rational", "kannala_brandt"}
        The lens model to fit (the camera file's names; ``rational`` is written as
        ``brown_conrady`` with ``k4, k5, k6``).

    Returns
    -------
    CalibrationResult
        ``K``, ``distortion``, ``rvecs``, ``tvecs``, ``rms``, ``per_view_rms``,
        ``residuals`` (per view), ``std`` (per parameter), ``warnings``.

    Raises
    ------
    InvalidInputError
        Mismatched point arrays, NaN, a bad ``image_size``, an unknown model, a parameter
        name in ``fix`` that the model does not have, a ``distortion_init`` of another model.
    DegenerateConfigurationError
        Fewer observations than parameters, fewer than 4 points in a view, a non-planar
        target that is coplanar in a view (DLT), no tilt at all; a refinement that did not
        converge when the boards' tilts or orientations leave the focal length open (too
        little tilt, nearly one orientation, or a tilt about nearly one axis in every view,
        judged on the poses of each start and of each refinement's last step).
    ConvergenceError
        The refinement did not converge within ``max_iter`` evaluations.

    Warns
    -----
    IllConditionedWarning
        Fewer than 3 views of a planar target, less than 10 deg of tilt, board normals
        within 5 deg of each other, points covering less than a quarter of the image,
        nearly singular normal equations.

    Notes
    -----
    ``rms`` is OpenCV's figure: ``sqrt(Σ‖u - û‖² / N)`` over all N points.
    Standard deviations are ``sqrt(diag(σ² (JᵀJ)⁻¹))`` with
    ``σ² = Σ‖u - û‖² / (2N - n_params)`` (as OpenCV's ``stdDeviationsIntrinsics``).

    Examples
    --------
    >>> from imageform.geometry import project_points_distorted, rvec_to_matrix
    >>> obj = checkerboard_points((9, 6), 25.0)
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> views = [([0.3, 0.1, 0], [-100, -60, 380]), ([-0.2, 0.3, 0.1], [-90, -70, 400]),
    ...          ([0.1, -0.35, -0.1], [-110, -50, 390])]
    >>> uv = [project_points_distorted(obj, K, rvec_to_matrix(r), t, BrownConrady(k1=-0.1))[0]
    ...       for r, t in views]
    >>> res = calibrate_camera([obj] * 3, uv, (640, 480))
    >>> round(float(res.K[0, 0]), 6), round(res.distortion.k1, 6)
    (800.0, -0.1)

    A fisheye (Kannala-Brandt) lens:

    >>> from imageform.geometry import KannalaBrandt
    >>> K = np.array([[300.0, 0, 320], [0, 300, 240], [0, 0, 1]])
    >>> fish = [([0.3, 0.1, 0], [-100, -60, 200]), ([-0.2, 0.3, 0.1], [-90, -70, 150]),
    ...         ([0.1, -0.35, -0.1], [-150, -50, 190]), ([0.0, 0.5, 0.0], [20, -80, 160])]
    >>> uv = [project_points_distorted(obj, K, rvec_to_matrix(r), t, KannalaBrandt(k1=0.05))[0]
    ...       for r, t in fish]
    >>> res = calibrate_camera([obj] * 4, uv, (640, 480), model="kannala_brandt")
    >>> round(float(res.K[0, 0]), 6), round(res.distortion.k1, 6), res.rms < 1e-9
    (300.0, 0.05, True)
    """
    objs, imgs = _views(object_points, image_points)
    size = check_image_size(image_size)
    skew = as_bool(skew, "skew")
    model = check_option(model, CALIBRATION_MODELS, "calibration model")
    if max_iter is None:
        max_iter = DEFAULT_MAX_ITER[model]
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", minimum=0.0, maximum=1.0)
    K_given = None
    if K_init is not None:
        K_given = np.asarray(
            to_numpy(as_matrix_bounded(K_init, "K_init", (3, 3), batch=False)), dtype=np.float64
        )
        check_K(K_given, np, "K_init", positive=True)
        K_given = K_given / K_given[2, 2]
    method = check_option(method, ("auto", "zhang", "dlt", "equidistant"), "calibration method")
    planar = _is_planar_z0(objs)
    if method == "equidistant" and model != "kannala_brandt":
        raise InvalidInputError(
            f"method 'equidistant' starts a fisheye (model 'kannala_brandt'), not model {model!r}"
        )
    both = method == "auto" and model == "kannala_brandt" and planar and K_init is None
    if method == "auto":
        method = "zhang" if planar else "dlt"
        if model == "kannala_brandt":
            method = "equidistant"
    if method == "zhang" and not planar:
        raise InvalidInputError(
            "method 'zhang' needs a planar target with Z = 0 in every view; the object "
            "points have Z != 0 (use method 'dlt' for a 3-D rig)"
        )
    free = _check_fix(fix, skew, model)
    n_obs = 2 * sum(o.shape[0] for o in objs)
    n_par = int(free.sum()) + 6 * len(objs)
    if n_obs <= n_par:
        raise DegenerateConfigurationError(
            f"{n_obs // 2} points in {len(objs)} views give {n_obs} equations for {n_par} "
            "parameters; add views or points, or fix parameters"
        )
    d_cls = KannalaBrandt if model == "kannala_brandt" else BrownConrady
    d0 = distortion_init if distortion_init is not None else d_cls()
    if not isinstance(d0, d_cls):
        raise InvalidInputError(
            f"expected distortion_init to be {d_cls.__name__} (model {model!r}), got "
            f"{type(d0).__name__}"
        )
    n_coef = len(global_names(model)) - 5
    if model == "brown_conrady" and any(d0.coeffs[5:]):
        raise InvalidInputError(
            "distortion_init has rational terms k4, k5, k6; model 'brown_conrady' fits "
            "k1, k2, p1, p2, k3 only (use model 'rational')"
        )
    coef0 = d0.coeffs[:n_coef]
    starts = []  # (K, rvecs, tvecs) to refine from; the lowest cost is kept
    if method == "equidistant":
        assert isinstance(d0, KannalaBrandt)  # method "equidistant" is the fisheye's alone
        try:
            starts.append(_equidistant_start(objs, imgs, size, K_given, d0, planar))
        except DegenerateConfigurationError:
            if not both:
                raise
        if both:
            try:  # Zhang's pinhole start too: it wins on a moderately wide lens
                H = homographies_of(objs, imgs)
                K0 = zhang_intrinsics(H, size, skew=skew)
                starts.append((K0, *poses_from_homographies(H, K0)))
            except (DegenerateConfigurationError, np.linalg.LinAlgError):
                if not starts:
                    raise
    elif method == "zhang":
        H = homographies_of(objs, imgs)
        K0 = zhang_intrinsics(H, size, skew=skew) if K_given is None else K_given
        starts.append((K0, *poses_from_homographies(H, K0)))
        if K_given is None and not (0 <= K0[0, 2] <= size[0] and 0 <= K0[1, 2] <= size[1]):
            # the closed form's principal point off the image: views that leave it
            # ill-determined (a stereo webcam's 320 x 480 halves, pixels twice as tall as
            # wide: cy -1522 px, and the refinement wandered 1000 iterations without a
            # minimum); OpenCV's start (the centre) too, the lower cost kept
            try:
                K1 = centre_intrinsics(H, size)
                starts.append((K1, *poses_from_homographies(H, K1)))
            except DegenerateConfigurationError:
                pass
    else:
        K0, rv0, tv0 = dlt_init(objs, imgs)
        starts.append((K_given if K_given is not None else K0, rv0, tv0))
    view = np.concatenate([np.full(o.shape[0], k, dtype=np.intp) for k, o in enumerate(objs)])
    best: RefineOutput | None = None
    failure: ConvergenceError | None = None
    rv0 = starts[0][1]
    tried = []  # the poses of every start refined and of every refinement's last step
    behind = 0
    for K0, rv, tv in starts:
        if model != "brown_conrady" and _behind_camera(objs, rv, tv):
            behind += 1  # the fisheye projection has no image there: not a start
            continue
        if not skew:
            K0 = K0.copy()
            K0[0, 1] = 0.0
        g0 = np.array([K0[0, 0], K0[1, 1], K0[0, 2], K0[1, 2], K0[0, 1], *coef0])
        tried.append(rv)
        try:
            out = refine(
                g0,
                rv,
                tv,
                np.concatenate(objs),
                np.concatenate(imgs),
                view,
                free,
                max_iter=max_iter,
                tol=tol,
                model=model,
            )
        except ConvergenceError as err:
            failure = failure or err
            if isinstance(err, StalledRefinement) and err.rvecs is not None:
                tried.append(err.rvecs)
            continue
        if best is None or float(np.sum(out.residuals**2)) < float(np.sum(best.residuals**2)):
            best, rv0 = out, rv
    if best is not None and both:
        # a fisheye fit is refined once more with each view's pose taken afresh through the
        # fitted lens (pixels unwarped by it, as the equidistant start does): a narrow
        # endoscope's views (rays to about 22 deg) left the refinement from Zhang's start in
        # a minimum of poses and large k3, k4 with the principal point 16 px off the one
        # OpenCV finds, at a higher cost (benchmarks/check_calibration_endoscope.py)
        g = best.globals_
        K1 = np.array([[g[0], g[4], g[2]], [0.0, g[1], g[3]], [0.0, 0.0, 1.0]])
        try:
            _, rv1, tv1 = _equidistant_start(objs, imgs, size, K1, KannalaBrandt(*g[5:9]), planar)
            if not _behind_camera(objs, rv1, tv1):
                again = refine(
                    g.copy(), rv1, tv1, np.concatenate(objs), np.concatenate(imgs), view, free,
                    max_iter=max_iter, tol=tol, model=model,
                )  # fmt: skip
                if float(np.sum(again.residuals**2)) < float(np.sum(best.residuals**2)):
                    best = again
        except (DegenerateConfigurationError, ConvergenceError, np.linalg.LinAlgError):
            pass  # the fit stands
    if best is None:
        if failure is None:
            raise DegenerateConfigurationError(
                f"no initial pose puts every point in front of the camera ({behind} start(s) "
                "tried); give K_init, or check the object points against the image points"
            )
        why = _stall_cause([rv0, *tried]) if planar else None
        if why:  # the refinement wandered along the valley the views leave open
            raise DegenerateConfigurationError(
                f"{why} (the refinement found no minimum in {max_iter} iterations)"
            ) from failure
        raise failure
    out = best
    notes = _warn_conditioning(planar, out.rvecs, imgs, size, out.cond)
    return CalibrationResult.from_fit(out, view, size, free, notes, model)
