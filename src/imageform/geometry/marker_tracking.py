r"""Pose of one square ArUco marker: IPPE-square's two solutions, and a video tracker.

A single printed marker fixed to the patient or to a tool is the simplest navigation target.
Its four corners give the pose by *infinitesimal plane-based pose estimation* for a square
(IPPE-square, Collins & Bartoli 2014; OpenCV's ``SOLVEPNP_IPPE_SQUARE``), which returns the
**two** poses a plane seen through a perspective camera admits: the marker tilted one way
or the mirror tilt about the line of sight. Far from face-on the wrong one reprojects
badly; nearly face-on (and for a small marker) both fit the corners within the noise, and a
frame-by-frame choice by reprojection error flips between them (the well-known "flip" of
marker-based AR). :class:`MarkerTracker` keeps the solution nearer the last pose found
(rotation and translation) when the two fit about equally well, and gives no pose when
nothing separates them (a first frame nearly face-on).

The marker's frame is OpenCV's (``cv2.aruco`` and ``SOLVEPNP_IPPE_SQUARE``): origin at the
marker's centre, x to the right and y up as printed, z out of the printed side (towards a
camera that sees it); corners top-left, top-right, bottom-right, bottom-left at
:math:`(\mp s/2, \pm s/2, 0)` for a side :math:`s`.

References
----------
T. Collins, A. Bartoli, "Infinitesimal Plane-Based Pose Estimation", International Journal
of Computer Vision 109(3):252-286, 2014.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imageform._typing import ArrayLike
from imageform._validate import as_int, as_matrix, as_points, as_real, describe
from imageform.errors import InvalidInputError
from imageform.geometry.distortion import BrownConrady, DivisionModel, KannalaBrandt
from imageform.geometry.tracking import BoardPose, _blend, _check_camera, _missing

__all__ = ["MarkerTracker", "SquarePoses", "marker_points", "solve_square_pose"]

F64 = NDArray[np.float64]

#: The second solution counts as fitting as well as the first (the choice then goes by
#: continuity with the previous frame) when its reprojection RMS is at most this many times
#: the first's plus ``_AMBIGUITY_PX`` pixels.
_AMBIGUITY_RATIO, _AMBIGUITY_PX = 4.0, 1.0

#: Two solutions are one pose (no choice to make) when their rotations are within this many
#: degrees and their translations within this fraction of the distance.
_SAME_DEG, _SAME_FRACTION = 5.0, 0.05

#: The motion prior (:func:`_pick`): from one frame to the next a pose moves by about
#: ``_PRIOR_DEG`` degrees and ``_PRIOR_FRACTION`` of its distance (one standard deviation
#: each, times the square root of the frames between the two poses: a random walk). It
#: separates two solutions when their squared normalised distances from the previous pose
#: differ by ``_PRIOR_MARGIN`` or more (a likelihood ratio of e^0.5) and the nearer lies
#: within ``_PRIOR_GATE`` (5 sigma).
#: A pose found up to ``_PRIOR_FRAMES`` frames before serves as the previous pose.
_PRIOR_DEG, _PRIOR_FRACTION = 5.0, 0.05
_PRIOR_MARGIN, _PRIOR_GATE = 1.0, 25.0
_PRIOR_FRAMES = 5

#: The fit separates two solutions (without a previous pose) when the worse one's sum of
#: squared corner errors exceeds the better one's by ``_FIT_CHI2`` times the corners' noise
#: variance (a likelihood-ratio test at 3 sigma), the noise estimated from the better fit's
#: residuals (6 parameters fitted) and taken as at least ``_NOISE_PX`` pixels a coordinate.
_FIT_CHI2, _NOISE_PX = 9.0, 0.05


class _Prior(NamedTuple):
    """The last pose found and how many frames ago (1: the previous frame)."""

    R: NDArray[np.float64]
    t: NDArray[np.float64]
    gap: int


def _prior_costs(R: NDArray[np.float64], t: NDArray[np.float64], prior: _Prior) -> F64:
    r"""Each pose's (``R (h, 3, 3)``, ``t (h, 3)``) squared normalised distance from ``prior``.

    :math:`(\angle(R_i R_p^\top) / (5^\circ \sqrt g))^2 + (\lVert t_i - t_p \rVert /
    (0.05 \sqrt g\,\lVert t_p \rVert))^2`, :math:`g` the frames since the prior (h,): a
    random walk, the variance growing with the interval.
    """
    g = np.sqrt(prior.gap)  # a random walk: the variance grows with the interval
    sr = np.radians(_PRIOR_DEG) * g
    st = _PRIOR_FRACTION * g * max(float(np.linalg.norm(prior.t)), 1e-300)
    return np.array(
        [
            (_angle(Ri, prior.R) / sr) ** 2 + (float(np.linalg.norm(ti - prior.t)) / st) ** 2
            for Ri, ti in zip(R, t, strict=True)
        ],
        np.float64,
    )


def _pick(
    rms: NDArray[np.float64],
    R: NDArray[np.float64],
    t: NDArray[np.float64],
    n_points: int,
    prior: _Prior | None,
    continuity: bool,
) -> int | None:
    r"""Choose between two poses (``R (2, 3, 3)``, ``t (2, 3)``) fitted to the same corners.

    ``rms (2,)``: their reprojection RMS over the same ``n_points`` corners. In order:

    1. one pose (rotations within 5 degrees, translations within 5 % of the distance): the
       better fit;
    2. the better fit when the other's RMS exceeds :math:`4\,\mathrm{rms}_a + 1` pixels;
    3. with ``continuity`` and a previous pose found :math:`g` frames before (``prior``,
       :math:`g \le 5`): each pose's squared distance from it,
       :math:`c_i = (\angle(R_i R_p^\top) / (5^\circ \sqrt g))^2 +
       (\lVert t_i - t_p \rVert / (0.05 \sqrt g\,\lVert t_p \rVert))^2` (rotation and
       translation; a random walk, the variance growing with the interval); the nearer when
       :math:`c_{far} - c_{near} \ge 1` and :math:`c_{near} \le 25`;
    4. the better fit when the fits differ beyond the noise (a likelihood-ratio test at 3
       sigma), :math:`n\,(\mathrm{rms}_b^2 - \mathrm{rms}_a^2) \ge 9\,\sigma^2`, the
       corners' noise variance a coordinate
       :math:`\sigma^2 = \max(n\,\mathrm{rms}_a^2 / (2n - 6),\ 0.05^2)` (the better
       fit's residuals, 6 parameters fitted);
    5. otherwise nothing separates them: None (ambiguous), or the better fit without
       ``continuity``.
    """
    if rms.size < 2 or not np.isfinite(rms[1]):
        return 0
    a = int(rms[1] < rms[0])
    b = 1 - a
    dist = max(float(np.linalg.norm(t[a])), 1e-300)
    if (
        _angle(R[0], R[1]) <= np.radians(_SAME_DEG)
        and float(np.linalg.norm(t[0] - t[1])) <= _SAME_FRACTION * dist
    ):
        return a
    if rms[b] > _AMBIGUITY_RATIO * rms[a] + _AMBIGUITY_PX:
        return a
    if continuity and prior is not None and prior.gap <= _PRIOR_FRAMES:
        cost = _prior_costs(R, t, prior)
        near = int(cost[1] < cost[0])
        if cost[near] <= _PRIOR_GATE and cost[1 - near] - cost[near] >= _PRIOR_MARGIN:
            return near
    var = max(n_points * float(rms[a]) ** 2 / max(2 * n_points - 6, 1), _NOISE_PX**2)
    if n_points * (float(rms[b]) ** 2 - float(rms[a]) ** 2) >= _FIT_CHI2 * var:
        return a
    return a if not continuity else None


class SquarePoses(NamedTuple):
    """The two poses of a square marker (:func:`solve_square_pose`), best fit first.

    ``R (2, 3, 3)``, ``rvec (2, 3)``, ``tvec (2, 3)`` map the marker's frame to the camera's
    (:math:`X_c = R X_m + t`); ``rms (2,)``: each one's reprojection RMS over the four
    corners in pixels (of the undistorted corners when a distortion model is given).
    """

    R: F64
    rvec: F64
    tvec: F64
    rms: F64


def marker_points(side: float) -> F64:
    r"""Return the four corners of a square marker of side ``side`` in its frame, (4, 3).

    Top-left, top-right, bottom-right, bottom-left as printed (the detector's order):
    :math:`(-s/2, s/2, 0), (s/2, s/2, 0), (s/2, -s/2, 0), (-s/2, -s/2, 0)`, OpenCV's
    ``SOLVEPNP_IPPE_SQUARE`` layout (x right, y up, z out of the printed side).

    Examples
    --------
    >>> marker_points(2.0)[:, :2].tolist()
    [[-1.0, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]]
    """
    h = as_real(side, "side", positive=True, maximum=1e12) / 2
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])


def _cross2(a: F64, b: F64) -> F64:
    """Return the z of the cross product of 2-D vectors ``a``, ``b`` (..., 2)."""
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0], np.float64)


def _homography4(src: F64, dst: F64) -> F64:
    """Return the homography (h33 = 1) mapping four points ``src`` (4, 2) to ``dst`` (4, 2)."""
    A = np.zeros((8, 8))
    b = np.zeros(8)
    for i, ((x, y), (u, v)) in enumerate(zip(src, dst, strict=True)):
        A[2 * i] = [x, y, 1, 0, 0, 0, -u * x, -u * y]
        A[2 * i + 1] = [0, 0, 0, x, y, 1, -v * x, -v * y]
        b[2 * i], b[2 * i + 1] = u, v
    return np.append(np.linalg.solve(A, b), 1.0).reshape(3, 3)


def _ippe_rotations(v: F64, J: F64) -> tuple[F64, F64]:
    r"""IPPE's two rotations from the point ``v`` (2,) and the Jacobian ``J`` (2, 2).

    Collins & Bartoli (2014), sec. 4 (their ``IPPE_dec``): :math:`R_v` turns the line of
    sight through ``v`` onto the z-axis; :math:`A = B^{-1} J` with
    :math:`B = [I_2\,|\,-v]\,R_v[:, :2]`; :math:`\gamma` is A's largest singular value,
    :math:`\tilde R = A/\gamma` the upper-left 2x2 block of the rotation, completed by
    :math:`b` (up to a sign) and the cross product of its columns.
    """
    t = float(np.hypot(v[0], v[1]))
    if t < 1e-15:
        Rv = np.eye(3)
    else:
        s = float(np.sqrt(t * t + 1.0))
        cos, sin = 1.0 / s, float(np.sqrt(1.0 - 1.0 / (s * s)))
        Kx = np.array([[0.0, 0.0, v[0]], [0.0, 0.0, v[1]], [-v[0], -v[1], 0.0]]) / t
        Rv = np.eye(3) + sin * Kx + (1.0 - cos) * (Kx @ Kx)
    B = np.column_stack([np.eye(2), -v]) @ Rv[:, :2]
    A = np.linalg.solve(B, J)
    ata = A.T @ A
    gamma = float(
        np.sqrt(
            0.5
            * (ata[0, 0] + ata[1, 1] + np.sqrt((ata[0, 0] - ata[1, 1]) ** 2 + 4 * ata[0, 1] ** 2))
        )
    )
    Rt = A / gamma
    h = np.eye(2) - Rt.T @ Rt
    b = np.sqrt(np.clip(np.diag(h), 0.0, None))
    if h[0, 1] < 0:
        b[1] = -b[1]
    d = np.cross(np.append(Rt[:, 0], b[0]), np.append(Rt[:, 1], b[1]))
    c, a = d[:2], d[2]
    R1 = Rv @ np.block([[Rt, c[:, None]], [b[None, :], np.array([[a]])]])
    R2 = Rv @ np.block([[Rt, -c[:, None]], [-b[None, :], np.array([[a]])]])
    return R1, R2


def _translation(R: F64, X: F64, xy: F64) -> F64:
    r"""Return the translation that best fits rotation ``R`` (linear least squares in t).

    :math:`(R X_i + t)_{x,y} - x_i\,(R X_i + t)_z = 0` for the normalised points
    :math:`x_i`, two equations per point.
    """
    q = X @ R.T
    A = np.zeros((2 * len(X), 3))
    A[0::2, 0], A[1::2, 1] = 1.0, 1.0
    A[0::2, 2], A[1::2, 2] = -xy[:, 0], -xy[:, 1]
    b = np.concatenate(
        [(xy[:, 0] * q[:, 2] - q[:, 0])[:, None], (xy[:, 1] * q[:, 2] - q[:, 1])[:, None]], 1
    )
    return np.linalg.lstsq(A, b.reshape(-1), rcond=None)[0]


def _ippe_pair(xy: F64, X: F64) -> tuple[F64, F64]:
    """IPPE-square's two closed-form poses (R (2, 3, 3), t (2, 3)) from normalised corners.

    ``xy`` (4, 2): the undistorted normalised corners; ``X`` (4, 3): :func:`marker_points`.
    """
    H = _homography4(X[:, :2], xy)
    v = H[:2, 2].copy()
    J = H[:2, :2] - np.outer(v, H[2, :2])
    Rs = np.stack(_ippe_rotations(v, J))
    return Rs, np.stack([_translation(R, X, xy) for R in Rs])


def solve_square_pose(
    image_points: ArrayLike,
    side: float,
    K: ArrayLike,
    distortion: BrownConrady | DivisionModel | KannalaBrandt | None = None,
    *,
    refine: bool = True,
    max_iter: int = 20,
) -> SquarePoses:
    r"""Solve the two poses of a square marker from its four corners (IPPE-square).

    The corners (top-left, top-right, bottom-right, bottom-left as printed) are undistorted
    and normalised, :math:`x_i = K^{-1} u_i`; the homography :math:`H` from the marker's
    plane to them (four points, exact) gives at the marker's centre the image point
    :math:`v = H(0)` and the Jacobian :math:`J = \partial H / \partial (X, Y)|_0`, from which
    IPPE (Collins & Bartoli 2014) reads the two rotations that agree with :math:`J` to first
    order,

    .. math:: R_{1,2} = R_v \begin{bmatrix} \tilde R & \pm c \\ \pm b^\top & a
              \end{bmatrix},

    each completed by its least-squares translation and refined by Levenberg-Marquardt on
    the pixel reprojection error :math:`\sum_i \| u_i - \pi(K (R X_i + t)) \|^2`.

    Parameters
    ----------
    image_points : array_like (4, 2)
        The corners in pixels, in :func:`marker_points`' order (as
        :func:`detect_aruco_markers` gives them).
    side : float
        The marker's side (its black square's), the translation's unit.
    K : array_like (3, 3)
        Intrinsics.
    distortion : distortion model, optional
        The lens distortion (the corners are undistorted first).
    refine : bool, keyword-only
        Refine both poses by Levenberg-Marquardt (otherwise IPPE's closed form).
    max_iter : int, keyword-only
        LM iterations.

    Returns
    -------
    SquarePoses
        Both solutions, ordered by reprojection RMS. Nearly face-on the two RMS are close
        and the first is not reliably the true one (:class:`MarkerTracker` chooses by
        continuity then).

    Raises
    ------
    InvalidInputError
        Not four finite corners, or corners that make no quadrilateral (three in a line).

    Notes
    -----
    Same method as OpenCV's ``solvePnPGeneric(..., SOLVEPNP_IPPE_SQUARE)`` (cross-checked
    in the tests); OpenCV returns the two closed-form poses unrefined.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = marker_points(50.0) + [0, 0, 500]  # face-on, 500 units away
    >>> uv = X[:, :2] / X[:, 2:] * 800 + [320, 240]
    >>> poses = solve_square_pose(uv, 50.0, K)
    >>> poses.tvec[0].round(6).tolist(), float(poses.rms[0]) < 1e-9
    ([0.0, 0.0, 500.0], True)
    """
    from imageform.geometry.distortion import _check_model
    from imageform.geometry.pnp import _normalised, refine_pose
    from imageform.geometry.rotations import matrix_to_rvec

    uv = np.asarray(as_points(image_points, "image_points", 2), np.float64)
    if uv.shape != (4, 2) or not np.all(np.isfinite(uv)):
        raise InvalidInputError(
            f"expected image_points as 4 finite corners (4, 2), got {describe(uv)}"
        )
    X = marker_points(side)
    k = np.asarray(as_matrix(K, "K", (3, 3), batch=False), np.float64)
    if k[2, 2] == 0 or k[0, 0] == 0 or k[1, 1] == 0:
        raise InvalidInputError(f"expected K with nonzero fx, fy and K[2, 2], got {describe(K)}")
    k = k / k[2, 2]
    if distortion is not None:
        _check_model(distortion)
    xy = np.asarray(_normalised(uv[None], k, distortion)[0], np.float64)
    a = xy[[1, 2, 3]] - xy[0]
    areas = [
        abs(_cross2(xy[j] - xy[i], xy[m] - xy[i]))
        for i, j, m in ((0, 1, 2), (1, 2, 3), (2, 3, 0), (3, 0, 1))
    ]
    if (
        not np.all(np.isfinite(a))
        or min(areas) <= 1e-12 * max(float(np.max(np.abs(a))), 1e-300) ** 2
    ):
        raise InvalidInputError(
            "expected image_points as a quadrilateral (no three corners in a line)"
        )
    Rs, ts = _ippe_pair(xy, X)
    ideal = np.stack(
        [k[0, 0] * xy[:, 0] + k[0, 1] * xy[:, 1] + k[0, 2], k[1, 1] * xy[:, 1] + k[1, 2]], -1
    )
    Xb, uvb = np.broadcast_to(X, (2, 4, 3)).copy(), np.broadcast_to(ideal, (2, 4, 2)).copy()
    if refine:
        Rs, ts, rms = refine_pose(
            Rs,
            ts,
            Xb,
            uvb,
            k,
            np.ones((2, 4)),
            as_int(max_iter, "max_iter", minimum=1, maximum=10**6),
        )
    else:
        from imageform.geometry.pnp import _residuals

        r, _ = _residuals(Rs, ts, Xb, uvb, k)
        rms = np.sqrt(np.mean(np.sum(r * r, -1), -1))
    order = np.argsort(rms, kind="stable")
    Rs, ts, rms = Rs[order], ts[order], rms[order]
    return SquarePoses(
        Rs, np.asarray(matrix_to_rvec(Rs), np.float64), ts, np.asarray(rms, np.float64)
    )


def _angle(Ra: F64, Rb: F64) -> float:
    """Return the angle (radians) of the rotation between ``Ra`` and ``Rb``."""
    c = (np.trace(Ra @ Rb.T) - 1.0) / 2.0
    return float(np.arccos(np.clip(c, -1.0, 1.0)))


def _refine_marker_corners(image: np.ndarray, uv: F64, marker_size: int) -> F64:
    """Refine markers' detected corners ``uv`` ((4, 2), or (m, 4, 2)) by the gradient criterion.

    :func:`refine_corners` (Förstner's: the gradients in the window are orthogonal to
    the directions from the corner), through a window half as wide as one of the
    marker's cells (``marker_size`` bits and a border cell each side), which sees the
    border's outer corner and none of its bits. A corner that does not converge, or moves
    more than a third of a cell, keeps the detector's. Markers whose windows are the same
    size are refined in one call; a uint8 grey frame is converted once, into the tracker's
    buffer when it lends one (:func:`imageform.geometry.aruco._grey32`).
    """
    from imageform.geometry.aruco import _grey32
    from imageform.geometry.checkerboard_subpix import refine, refine_corners

    one = uv.ndim == 2
    quads = uv[None] if one else uv
    out = quads.copy()
    sides = np.linalg.norm(quads - np.roll(quads, 1, axis=1), axis=2)
    cell = sides.mean(axis=1) / (marker_size + 2)
    hw = np.clip(np.round(cell / 2), 2, 10).astype(int)
    h, w = image.shape[:2]
    grey = _grey32(image) if np.any(cell >= 4) else None
    for size in np.unique(hw[cell >= 4]):
        group = np.flatnonzero((hw == size) & (cell >= 4))
        pts = quads[group].reshape(-1, 2)
        inside = np.all((pts >= size + 1) & (pts <= [w - size - 2, h - size - 2]), axis=1)
        if not np.any(inside):
            continue
        if grey is None:
            res = refine_corners(image, pts[inside], half_window=int(size))
            got, status = np.asarray(res.corners, np.float64), np.asarray(res.status)
        else:  # refine_corners' own steps on its own grey values, in the tracker's buffer
            got, status = refine(
                grey, np.ascontiguousarray(pts[inside]), int(size), int(size), 30, 1e-3
            )
        limit = np.repeat(cell[group], 4)[inside] / 3
        ok = np.isin(status, (0, 1)) & np.all(np.isfinite(got), axis=1)
        ok &= np.linalg.norm(got - pts[inside], axis=1) < limit
        new = pts.copy()
        new[np.flatnonzero(inside)[ok]] = got[ok]
        out[group] = new.reshape(-1, 4, 2)
    return out[0] if one else out


class MarkerTracker:
    r"""Follow one square ArUco marker through video frames (:class:`BoardTracker`'s interface).

    Each frame: the marker ``marker_id`` of ``dictionary`` is detected
    (:func:`detect_aruco_markers`: its corners where lines fitted to its four sides meet,
    then refined by :func:`refine_corners` through a window of half a cell), first in the
    previous frame's box grown by half its size (at least 32 pixels each way), then in the
    whole frame; its pose is solved by :func:`solve_square_pose` (IPPE-square's two
    solutions, each refined by LM). The choice:

    - the better fit, when the other's reprojection RMS exceeds
      :math:`4\,\mathrm{rms}_1 + 1` pixels (the mirrored tilt clearly fits worse);
    - otherwise (nearly face-on, the flip ambiguity), the solution nearer the last pose
      found, in rotation and translation, with a motion prior that widens with the frames
      since that pose (a random walk: 5 degrees and 5 % of the distance a frame, times
      :math:`\sqrt g` after :math:`g` frames; up to 5 frames back), when it is clearly
      nearer;
    - otherwise the better fit when the two fits differ beyond the corners' noise (a
      likelihood-ratio test at 3 sigma, the noise from the fit's residuals);
    - otherwise nothing separates them (a first frame of a marker nearly face-on): the pose
      is missing with ``searched = "ambiguous"`` and the corners in ``image_points``. With
      ``continuity=False``, always the better fit (never refused).

    The marker's id read in several places (a reflection, a second print:
    ``detect_aruco_markers(..., all_sightings=True)``): the sighting whose corners are
    nearest the previous frame's. A sighting in the box farther than half a side from the
    previous frame's corners (the marker gone out of the box, a second print in it) sends
    the search to the whole frame, where the nearest sighting is kept. On a first frame (or
    after a lost one) nothing tells the sightings apart: each is a square of the marker's
    code, and a print of another size is the marker's side at another distance (IPPE fits
    both exactly), so the tracker does not choose: the pose is missing with ``searched =
    "ambiguous"`` and every sighting's corners in ``image_points`` (4 a sighting), until one
    sighting is left in view (then followed as above). A known side does not settle it
    from one frame either: it fixes each sighting's distance, not which is the marker.

    A frame without the marker is a missing pose (NaN), never carried over.

    Parameters
    ----------
    marker_id : int
        The marker's id in the dictionary.
    side : float
        The marker's side (its black square's, as printed): the pose's unit.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        The lens distortion.
    dictionary : str or ArucoDictionary, keyword-only
        See :func:`aruco_dictionary`.
    smooth : float, keyword-only
        Weight :math:`\alpha` of the newest pose in (0, 1] (exponential filter, as
        :class:`BoardTracker`); 1 turns smoothing off.
    predict : bool, keyword-only
        Search the previous frame's box before the whole frame.
    continuity : bool, keyword-only
        Choose between the two solutions by continuity and refuse when nothing separates
        them (otherwise always the better fit).

    Examples
    --------
    >>> from imageform.geometry import aruco_marker_image
    >>> frame = np.full((240, 320), 255, np.uint8)
    >>> frame[60:180, 100:220] = aruco_marker_image(7, "4x4_50", size_px=120)
    >>> K = np.array([[300.0, 0, 159.5], [0, 300, 119.5], [0, 0, 1]])
    >>> pose = MarkerTracker(7, 40.0, K, dictionary="4x4_50").update(frame)
    >>> pose.found, pose.corners, (pose.tvec.round(0) + 0.0).tolist()
    (True, 4, [0.0, 0.0, 100.0])
    """

    def __init__(
        self,
        marker_id: int,
        side: float,
        K: object,
        distortion: BrownConrady | DivisionModel | KannalaBrandt | None = None,
        *,
        dictionary: object = "6x6_250",
        smooth: float = 1.0,
        predict: bool = True,
        continuity: bool = True,
    ) -> None:
        from imageform.geometry.aruco import aruco_dictionary

        self.dictionary = aruco_dictionary(dictionary)  # type: ignore[arg-type]
        # a name: the detector caches a predefined dictionary's rotated codes by name
        self._detect_with: object = dictionary if isinstance(dictionary, str) else self.dictionary
        self.marker_id = as_int(marker_id, "marker_id", minimum=0, maximum=self.dictionary.size - 1)
        self.side = as_real(side, "side", positive=True, maximum=1e12)
        self.K = _check_camera(K, distortion)
        self.distortion = distortion
        self.smooth = as_real(smooth, "smooth", positive=True, maximum=1.0)
        self.predict = bool(predict)
        self.continuity = bool(continuity)
        self._points = marker_points(self.side)
        self._box: tuple[int, int, int, int] | None = None
        self._last: BoardPose | None = None
        self._prior: _Prior | None = None
        from imageform.geometry.aruco import _WorkArea

        #: the work buffers of a frame larger than the detector keeps for every thread
        self._work = _WorkArea()

    def reset(self) -> None:
        """Forget the previous frames (a cut in the video)."""
        self._box = self._last = None
        self._prior = None

    def _find(
        self, image: np.ndarray, box: tuple[int, int, int, int] | None
    ) -> tuple[F64 | None, F64 | None]:
        """Return the marker's corners (4, 2), or None and, when ambiguous, every sighting's.

        Ambiguous: the id read in several places with no previous frame to choose by (the
        second item, (4 m, 2), the sightings' corners as detected).
        """
        from imageform.geometry.aruco import detect_aruco_markers

        x0, y0, x1, y1 = box if box is not None else (0, 0, image.shape[1], image.shape[0])
        found = detect_aruco_markers(
            image[y0:y1, x0:x1],
            self._detect_with,  # type: ignore[arg-type]
            all_sightings=True,
        )
        hit = np.flatnonzero(found.ids == self.marker_id)
        if hit.size == 0:
            return None, None
        c = found.corners[hit] + np.array([x0, y0], np.float64)
        best = hit[0]
        if hit.size > 1:
            last = self._last
            if last is None or not last.found:
                # no previous frame: nothing tells the marker from its second print
                return None, np.asarray(c.reshape(-1, 2), np.float64)
            # the same id twice (a reflection, a second print): the sighting whose corners
            # are nearest the previous frame's (the marker followed)
            best = hit[int(np.argmin(np.linalg.norm(c - last.image_points, axis=2).mean(1)))]
        uv = np.asarray(found.corners[best], np.float64)
        return self._refine(image[y0:y1, x0:x1], uv) + np.array([x0, y0], np.float64), None

    def _jumped(self, uv: F64) -> bool:
        """Whether corners ``uv`` lie more than half a side from the previous frame's."""
        last = self._last
        if last is None or not last.found:
            return False
        prev = last.image_points
        side = float(np.linalg.norm(prev - np.roll(prev, 1, axis=0), axis=1).mean())
        return float(np.linalg.norm(uv - prev, axis=1).mean()) > 0.5 * side

    def _refine(self, image: np.ndarray, uv: F64) -> F64:
        return _refine_marker_corners(image, uv, self.dictionary.marker_size)

    def choose(self, poses: SquarePoses) -> int | None:
        """Index (0 or 1) of the solution kept, None when nothing separates them.

        By fit, then by nearness to the pose of the last frames (rotation and translation),
        then by fit within the noise (the class's rules); None: ambiguous.
        """
        return _pick(poses.rms, poses.R, poses.tvec, 4, self._prior, self.continuity)

    def update(self, image: ArrayLike) -> BoardPose:
        """Find the marker in ``image`` (a frame, (H, W) or (H, W, 3)) and solve its pose."""
        from imageform.geometry.aruco import _working

        with _working(self._work):  # this tracker's buffers for a large frame
            return self._update(image)

    def _update(self, image: ArrayLike) -> BoardPose:
        from imageform.geometry.aruco import _grey_source

        a = np.asarray(image)
        if a.ndim not in (2, 3) or a.shape[0] < 8 or a.shape[1] < 8:
            raise InvalidInputError(f"expected a frame as an (H, W[, 3]) image, got {describe(a)}")
        a = np.asarray(_grey_source(a))  # a colour frame read on its grey uint8, once
        h, w = a.shape[:2]
        uv, searched = None, "none"
        if self.predict and self._box is not None:
            uv, _ = self._find(a, self._box)
            searched = "box"
            if uv is not None and self._jumped(uv):
                uv = None  # maybe a second print in the box: choose among the frame's
        if uv is None:
            uv, sightings = self._find(a, None)
            searched = "frame"
            if sightings is not None:
                self._box = self._last = None
                self._age()
                return _missing("ambiguous", sightings)
        if uv is None:
            return self._lost()
        try:
            poses = solve_square_pose(uv, self.side, self.K, self.distortion)
        except InvalidInputError:
            return self._lost(uv)
        i = self.choose(poses)
        if i is None:  # both tilts fit and no recent pose tells them apart
            self._box = self._last = None
            self._age()
            return _missing("ambiguous", uv)
        R, t, rms = poses.R[i], poses.tvec[i], float(poses.rms[i])
        X = self._points
        if not np.isfinite(rms) or np.any(X @ R[2] + t[2] <= 0):
            return self._lost(uv)
        self._prior = _Prior(R.copy(), t.copy(), 1)
        if self.smooth < 1.0 and self._last is not None and self._last.found:
            R, t = _blend(R, t, self._last, self.smooth)
        from imageform.geometry.rotations import matrix_to_rvec

        rvec = np.asarray(matrix_to_rvec(R), np.float64)
        pose = BoardPose(True, rvec, t, R, rms, uv, X.copy(), searched)
        lo, hi = uv.min(axis=0), uv.max(axis=0)
        grow = np.maximum((hi - lo) * 0.5, 32.0)
        x0, y0 = np.floor(lo - grow).astype(int)
        x1, y1 = np.ceil(hi + grow).astype(int)
        self._box = (max(x0, 0), max(y0, 0), min(x1, w), min(y1, h))
        self._last = pose
        return pose

    def _age(self) -> None:
        """One more frame since the last pose (the motion prior widens)."""
        if self._prior is not None:
            self._prior = self._prior._replace(gap=self._prior.gap + 1)

    def _lost(self, uv: F64 | None = None) -> BoardPose:
        self._box = self._last = None
        self._age()
        return _missing("none", uv)
