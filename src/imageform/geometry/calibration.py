"""Camera calibration: Zhang's method for planar targets, DLT for 3-D rigs, then LM.

:func:`calibrate_camera` estimates the intrinsics ``K`` (``fx, fy, cx, cy`` and optionally
the skew), Brown-Conrady distortion ``(k1, k2, p1, p2, k3)`` (any of them can be fixed) and
one pose per view from known object points and their detected pixels, and returns a
:class:`CalibrationResult` with the reprojection errors (overall RMS as OpenCV defines it,
per view and per point) and the standard deviations of the parameters.

Helpers: ``calibration_zhang`` (closed-form initial values), ``calibration_refine``
(Levenberg-Marquardt with a sparse Jacobian structure), ``calibration_result``
(the result dataclass and its TOML form).
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
from imageform.geometry.calibration_refine import GLOBAL_NAMES, refine, rodrigues
from imageform.geometry.calibration_result import CalibrationResult
from imageform.geometry.calibration_views import _views
from imageform.geometry.calibration_zhang import (
    dlt_init,
    homographies,
    poses_from_homographies,
    zhang_intrinsics,
)
from imageform.geometry.distortion import BrownConrady

__all__ = ["CalibrationResult", "calibrate_camera", "checkerboard_points"]

F64 = NDArray[np.float64]

#: Views fewer than this (planar target) trigger an :class:`IllConditionedWarning`.
MIN_GOOD_VIEWS = 3
#: Largest board tilt (degrees) below which the focal length is poorly determined.
MIN_TILT_DEG = 10.0
#: Largest angle (degrees) between two views' board normals below which the views are
#: nearly one orientation: the focal length then trades against the board's distance.
MIN_SPREAD_DEG = 5.0
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


def _check_fix(fix: Collection[str], skew: bool) -> NDArray[np.bool_]:
    if isinstance(fix, str):
        fix = (fix,)
    if not hasattr(fix, "__iter__") or getattr(fix, "ndim", 1) == 0:
        raise InvalidInputError(f"expected fix as parameter names, got {describe(fix)}")
    items = list(fix)
    for f in items:
        if not isinstance(f, str):
            raise InvalidInputError(f"expected fix as parameter names (str), got {describe(f)}")
    names = {check_option(f, GLOBAL_NAMES, "calibration parameter in fix") for f in items}
    free = np.array([n not in names for n in GLOBAL_NAMES])
    if not skew:
        free[GLOBAL_NAMES.index("skew")] = False
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
    if cond > 1e14:
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


def calibrate_camera(
    object_points: Sequence[npt.ArrayLike],
    image_points: Sequence[npt.ArrayLike],
    image_size: tuple[int, int],
    *,
    skew: bool = False,
    fix: Collection[str] = (),
    K_init: npt.ArrayLike | None = None,
    distortion_init: BrownConrady | None = None,
    method: str = "auto",
    max_iter: int = 100,
    tol: float = 1e-10,
) -> CalibrationResult:
    r"""Calibrate a camera from views of a known target: closed form, then Levenberg-Marquardt.

    Minimises the reprojection error over ``K``, Brown-Conrady ``(k1, k2, p1, p2, k3)`` and
    the poses ``(R_k, t_k)`` of the V views:

    .. math::

        \min \sum_{k=1}^{V} \sum_{i=1}^{N_k}
        \left\| \mathbf{u}_{ki} - \pi\!\left(K, d, R_k \mathbf{X}_{ki} + \mathbf{t}_k
        \right) \right\|^2

    Initial values: for a planar target (all ``Z = 0``) Zhang's closed form from the
    homographies (Zhang 2000, "A flexible new technique for camera calibration", IEEE TPAMI
    22(11), sec. 3.1 and appendix B); for a non-planar rig the normalised DLT per view and
    its RQ decomposition (Hartley & Zisserman, 2nd ed., Algorithm 7.1, sec. 6.2.4) —
    OpenCV's ``calibrateCamera`` cannot start from a 3-D rig without ``K_init``.
    Distortion starts at zero. The refinement is ``scipy.optimize.least_squares`` (TRF)
    with the block-sparse Jacobian structure.

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
        Parameters held at their initial values: any of ``fx, fy, cx, cy, skew, k1, k2, p1,
        p2, k3`` (fixing e.g. ``k3`` as OpenCV's ``CALIB_FIX_K3``; a fixed distortion
        coefficient keeps its ``distortion_init`` value, 0 by default).
    K_init, distortion_init : optional
        Initial ``K`` (3, 3) (skips the closed form) and distortion.
    method : {"auto", "zhang", "dlt"}
        Initialiser; ``auto`` is Zhang for a planar ``Z = 0`` target, DLT otherwise.
    max_iter, tol : int, float
        Iteration budget and the relative tolerances of the refinement.

    Returns
    -------
    CalibrationResult
        ``K``, ``distortion``, ``rvecs``, ``tvecs``, ``rms``, ``per_view_rms``,
        ``residuals`` (per view), ``std`` (per parameter), ``warnings``.

    Raises
    ------
    InvalidInputError
        Mismatched point arrays, NaN, a bad ``image_size``, an unknown parameter name.
    DegenerateConfigurationError
        Fewer observations than parameters, fewer than 4 points in a view, a non-planar
        target that is coplanar in a view (DLT), no tilt at all; a refinement that did not
        converge when the boards' tilts or orientations leave the focal length open.
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
    """
    objs, imgs = _views(object_points, image_points)
    size = check_image_size(image_size)
    skew = as_bool(skew, "skew")
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", minimum=0.0, maximum=1.0)
    if K_init is not None:
        K_given = np.asarray(
            to_numpy(as_matrix_bounded(K_init, "K_init", (3, 3), batch=False)), dtype=np.float64
        )
        check_K(K_given, np, "K_init", positive=True)
        K_given = K_given / K_given[2, 2]
    method = check_option(method, ("auto", "zhang", "dlt"), "calibration method")
    planar = _is_planar_z0(objs)
    if method == "auto":
        method = "zhang" if planar else "dlt"
    if method == "zhang" and not planar:
        raise InvalidInputError(
            "method 'zhang' needs a planar target with Z = 0 in every view; the object "
            "points have Z != 0 (use method 'dlt' for a 3-D rig)"
        )
    free = _check_fix(fix, skew)
    n_obs = 2 * sum(o.shape[0] for o in objs)
    n_par = int(free.sum()) + 6 * len(objs)
    if n_obs <= n_par:
        raise DegenerateConfigurationError(
            f"{n_obs // 2} points in {len(objs)} views give {n_obs} equations for {n_par} "
            "parameters; add views or points, or fix parameters"
        )
    d0 = distortion_init if distortion_init is not None else BrownConrady()
    if not isinstance(d0, BrownConrady):
        raise InvalidInputError(
            f"expected distortion_init to be BrownConrady, got {type(d0).__name__}"
        )
    if method == "zhang":
        H = homographies(objs, imgs)
        K0 = zhang_intrinsics(H, size, skew=skew) if K_init is None else K_given
        rv0, tv0 = poses_from_homographies(H, K0)
    else:
        K0, rv0, tv0 = dlt_init(objs, imgs)
        if K_init is not None:
            K0 = K_given
    if not skew:
        K0 = K0.copy()
        K0[0, 1] = 0.0
    g0 = np.array([K0[0, 0], K0[1, 1], K0[0, 2], K0[1, 2], K0[0, 1], *d0.coeffs[:5]])
    view = np.concatenate([np.full(o.shape[0], k, dtype=np.intp) for k, o in enumerate(objs)])
    try:
        out = refine(
            g0,
            rv0,
            tv0,
            np.concatenate(objs),
            np.concatenate(imgs),
            view,
            free,
            max_iter=max_iter,
            tol=tol,
        )
    except ConvergenceError as err:
        why = _orientation_problems(rv0) if planar else []
        if why:  # the refinement wandered along the valley the views leave open
            raise DegenerateConfigurationError(
                f"{why[0]} (the refinement found no minimum in {max_iter} iterations)"
            ) from err
        raise
    notes = _warn_conditioning(planar, out.rvecs, imgs, size, out.cond)
    return CalibrationResult.from_fit(out, view, size, free, notes)
