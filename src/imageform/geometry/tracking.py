r"""Track a calibration board's pose frame by frame: detection, PnP, prediction, smoothing.

The course's surgical-navigation loop: with the camera calibrated (K and its distortion),
each frame's board corners give the pose :math:`[R\,|\,\mathbf t]` of the board in the
camera frame (:math:`\mathbf X_c = R\,\mathbf X_b + \mathbf t`) by PnP, which places a plan
drawn in board coordinates on the live image.

:class:`BoardTracker` keeps what one frame teaches the next:

- **prediction**: the board is searched first in the previous frame's board box, grown by a
  margin (half the box's size and at least 32 pixels each way); only when it is not found
  there is the whole frame searched. A box is a fraction of the frame, so detection costs a
  fraction too;
- **corner tracking**: when the last frame's pose is known, its corners are moved by their
  last motion (constant velocity) and refined in the new frame with the sub-pixel saddle
  refinement (:func:`~imageform.geometry.refine_corners`, a window of a third of a square,
  then the detector's own window from there: for a ChArUco board at most 25 px, as the
  detector's; a wider one on a 4K phone video's squares put the corners 1-2 px off the
  detected ones and no frame was tracked)
  instead of detecting the board again; the frame is accepted only when at least 80 % of
  the corners refine, none moves more than half a square from its prediction, and the PnP
  fit of all of them leaves every corner within 1.5 pixels (RMS within 0.75). A ChArUco
  corner must also pass the detector's blur test (refined again through a window a pixel
  larger, it moves at most ``charuco._MAX_WINDOW_SHIFT``): corners smeared by motion are
  left out, and when fewer than 80 % pass, the board is detected again, the tracked
  corners standing in only where that finds no board (hand-held boards filmed at 6 frames
  a second: benchmarks/results/track-fresh-2026-11-30g.md). Anything
  else, and every ``redetect``-th frame (to pick up corners that came into view), falls
  back to detection. A refinement costs a few milliseconds where a detection costs tens.
  The detected frames use the same gradient refinement (``find_checkerboard`` and
  ``detect_charuco`` with ``method="gradient"``): the point-symmetry one was no nearer the
  truth on a rendered checkerboard video and cost half as much again a frame
  (benchmarks/results/track-symmetric-2026-11-29j.md);
- **4K frames**: a ChArUco frame of at least 2560 pixels a side has its markers read on its
  half (block means: a quarter of the pixels to threshold and label), the corners then
  predicted, refined and checked at full resolution, only around the markers; the whole
  frame is searched at full resolution when that finds too few corners for a pose, or
  fewer than the last frame had (80 %) with a marker under 96 px among those read, and
  when the last detection's markers were under 48 px
  (benchmarks/results/track-speed-2026-11-30h.md). Such a frame in RGB uint8 (a video
  reader's) is first made grey uint8 with the detector's luma weights, rounded (smaller
  frames are read in RGB as before);
- **no search in vain**: a checkerboard not found in a soft frame is sought on coarser
  copies of it (a board smeared by motion, :func:`~imageform.geometry.find_checkerboard`);
  after ``_SMEAR_PATIENCE`` frames in a row where that found nothing (a webcam's frames
  without a board are all soft) it is made only where part of a board is seen at full
  resolution, and on one frame in ``_SMEAR_RETRY``, until a board is found;
- **one orientation**: a checkerboard looks the same turned half a turn; its corners are
  ordered as the previous frame's were (the order nearer to them), so the pose never jumps;
- **smoothing** (off by default): an exponential filter of the pose,
  :math:`\mathbf t_k = \alpha\,\mathbf t + (1-\alpha)\,\mathbf t_{k-1}` and the rotation
  interpolated on the unit quaternions (normalised linear interpolation) with the same
  :math:`\alpha`; it trades lag for jitter.

Frames where the board is not found, or its pose cannot be solved, are reported as not
found (NaN pose), never invented from earlier frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from imageform._typing import ArrayLike
from imageform._validate import as_int, as_matrix, as_real, describe
from imageform.errors import InvalidInputError
from imageform.geometry.charuco import CharucoBoard

__all__ = ["BoardPose", "BoardTracker"]

#: A checkerboard not found at full resolution in a soft frame (a webcam's frames all are) is
#: sought on coarser copies of the frame (a board smeared by motion); after this many
#: frames in a row where that search ran and found nothing, frames without a board seen in
#: part at full resolution skip it, but for one in every ``_SMEAR_RETRY`` (the search costs
#: several times the frame's own; benchmarks/results/board-third-2026-11-30d.md).
_SMEAR_PATIENCE, _SMEAR_RETRY = 15, 10


@dataclass(frozen=True)
class BoardPose:
    """The board's pose in one frame (:meth:`BoardTracker.update`).

    Attributes
    ----------
    found : bool
        The board was found and its pose solved.
    rvec, tvec : ndarray (3,)
        Rodrigues vector and translation, board to camera (:math:`X_c = R X_b + t`, t in the
        board's unit); NaN when not found.
    R : ndarray (3, 3)
        The rotation (NaN when not found).
    rms_px : float
        Reprojection RMS of the corners used, in pixels (NaN when not found).
    image_points : ndarray (m, 2)
        The corners found (distorted pixels, as detected).
    object_points : ndarray (m, 3)
        The same corners on the board.
    searched : {"tracked", "box", "frame", "none", "ambiguous"}
        How the board was found: its corners tracked from the last frame, detected in the
        predicted box, in the whole frame, or not at all; ``"ambiguous"`` (a marker
        tracker's first frame, :class:`MarkerTracker`, :class:`MarkerMapTracker`): not
        found because the target was read in two places and nothing in the frame tells
        which is it (``image_points``: every sighting's corners).
    """

    found: bool
    rvec: NDArray[np.float64]
    tvec: NDArray[np.float64]
    R: NDArray[np.float64]
    rms_px: float
    image_points: NDArray[np.float64]
    object_points: NDArray[np.float64]
    searched: str

    @property
    def corners(self) -> int:
        """How many corners were used."""
        return int(self.image_points.shape[0])


#: A ChArUco frame of at least this many pixels a side has its markers read on its half
#: (:meth:`BoardTracker._reduction`), unless the last detection's markers were smaller than
#: twice this many pixels a side.
_REDUCE_FROM, _REDUCE_MIN_MARKER = 2560, 24.0
#: A tracked ChArUco corner's final refinement window (half side, px) at most: the
#: detector's (``charuco._predicted``).
_MAX_FINE = 25


def _marker_side(corners: NDArray[np.float64]) -> float:
    """Return the shortest side (px) of the markers ``corners`` (n, 4, 2); 0 when none."""
    c = np.asarray(corners, np.float64).reshape(-1, 4, 2)
    if c.shape[0] == 0:
        return 0.0
    e = np.roll(c, -1, axis=1) - c
    return float(np.hypot(e[..., 0], e[..., 1]).min())


def _missing(searched: str = "none", uv: NDArray[np.float64] | None = None) -> BoardPose:
    nan3 = np.full(3, np.nan)
    empty = np.zeros((0, 2)) if uv is None else uv
    return BoardPose(
        False, nan3, nan3.copy(), np.full((3, 3), np.nan), np.nan, empty,
        np.zeros((empty.shape[0], 3)), searched,
    )  # fmt: skip


def _check_camera(K: object, distortion: object) -> NDArray[np.float64]:
    """Return ``K`` as a (3, 3) float array after checking it and ``distortion`` (trackers').

    ``K[2, 2]`` must not be 0; a distortion model must be one of the models
    (:class:`BrownConrady`, :class:`DivisionModel`, :class:`KannalaBrandt`) or None.
    """
    from imageform.geometry.distortion import _check_model

    k = np.asarray(as_matrix(K, "K", (3, 3), batch=False), dtype=np.float64)
    if k[2, 2] == 0:
        raise InvalidInputError(f"expected K with K[2, 2] != 0, got {describe(K)}")
    if distortion is not None:
        _check_model(distortion)
    return k


def _quat(R: NDArray[np.float64]) -> NDArray[np.float64]:
    from imageform.geometry.rotations import matrix_to_quaternion

    return np.asarray(matrix_to_quaternion(R), np.float64)


def _blend(
    R: NDArray[np.float64], t: NDArray[np.float64], last: BoardPose, a: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the pose ``a`` of the way from ``last`` to ``(R, t)`` (every tracker's smoothing).

    The rotations by normalised linear interpolation of their quaternions (the nearer sign),
    the translations linearly.
    """
    from imageform.geometry.rotations import quaternion_to_matrix

    q0, q1 = _quat(last.R), _quat(R)
    if np.dot(q0, q1) < 0:  # the same rotation, the nearer sign
        q1 = -q1
    q = (1 - a) * q0 + a * q1
    q /= np.linalg.norm(q)
    return np.asarray(quaternion_to_matrix(q), np.float64), (1 - a) * last.tvec + a * t


class BoardTracker:
    r"""Follow a ChArUco board or a checkerboard through video frames.

    Parameters
    ----------
    board : CharucoBoard or (int, int)
        A ChArUco board (its lengths are the pose's unit), or a checkerboard's inner corners
        ``(cols, rows)``.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        The camera's lens distortion (:class:`BrownConrady`, ...): corners are undistorted
        before PnP.
    square : float
        A checkerboard's square side, the pose's unit (ignored for a ChArUco board, which
        has its own).
    min_corners : int
        Fewest corners accepted for a pose (4 at least: a planar target).
    smooth : float
        The smoothing weight :math:`\alpha` of the newest pose, in (0, 1]; 1 (the default)
        turns smoothing off.
    predict : bool
        Track the last frame's corners, then search its box, before the whole frame.
    redetect : int
        Detect the board (instead of tracking its corners) at least every ``redetect``
        frames, so that corners coming into view are picked up.

    Examples
    --------
    >>> board = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
    >>> K = np.array([[600.0, 0, 200], [0, 600, 250], [0, 0, 1]])
    >>> tracker = BoardTracker(board, K)
    >>> pose = tracker.update(board.image(60, margin_px=30))
    >>> pose.found, pose.corners
    (True, 24)
    """

    def __init__(
        self,
        board: CharucoBoard | tuple[int, int],
        K: object,
        distortion: object = None,
        *,
        square: float = 1.0,
        min_corners: int = 6,
        smooth: float = 1.0,
        predict: bool = True,
        redetect: int = 10,
    ) -> None:
        from imageform.geometry.calibration import checkerboard_points

        if isinstance(board, CharucoBoard):
            self._charuco: CharucoBoard | None = board
            self._pattern: tuple[int, int] | None = None
            self._points = board.corner_points()
        elif isinstance(board, tuple | list) and len(board) == 2:
            cols = as_int(board[0], "board (cols)", minimum=2, maximum=1000)
            rows = as_int(board[1], "board (rows)", minimum=2, maximum=1000)
            self._charuco, self._pattern = None, (cols, rows)
            s = as_real(square, "square", positive=True, maximum=1e12)
            self._points = checkerboard_points((cols, rows), s)
        else:
            raise InvalidInputError(
                f"expected board as a CharucoBoard or (cols, rows) inner corners, got "
                f"{describe(board)}"
            )
        self.K = _check_camera(K, distortion)
        self.distortion = distortion
        self.min_corners = as_int(min_corners, "min_corners", minimum=4, maximum=100000)
        a = as_real(smooth, "smooth", positive=True, maximum=1.0)
        self.smooth = a
        self.predict = bool(predict)
        self.redetect = as_int(redetect, "redetect", minimum=1, maximum=1_000_000)
        self._box: tuple[int, int, int, int] | None = None
        self._last_uv: NDArray[np.float64] | None = None
        self._last: BoardPose | None = None
        self._last_ids: NDArray[np.int64] | None = None
        self._prev_uv: dict[int, NDArray[np.float64]] = {}
        self._since_detection = 0
        #: frames in a row whose coarse-copy search for a smeared board found nothing, the
        #: frames since they reached _SMEAR_PATIENCE, and whether this frame's did
        self._vain = self._quiet = 0
        self._frame_vain = False
        #: the checkerboard's sub-pixel refinement (find_checkerboard's ``method``), detected
        #: and tracked frames alike
        self._refinement: Literal["symmetric", "gradient"] = "gradient"
        #: a ChArUco frame's tracked corners, blurred ones included, kept in case detection
        #: finds no board in the frame
        self._spare: tuple[NDArray[np.float64], NDArray[np.int64]] | None = None
        #: the frame's size, and the last detection's smallest marker side in pixels (0:
        #: none yet), which decide whether a ChArUco frame's markers are read reduced
        self._frame: tuple[int, int] = (0, 0)
        self._marker_px = 0.0
        from imageform.geometry.aruco import _WorkArea

        #: the work buffers of a frame larger than the detector keeps for every thread
        self._work = _WorkArea()

    def reset(self) -> None:
        """Forget the previous frames (a cut in the video)."""
        self._box = self._last_uv = self._last = self._last_ids = None
        self._prev_uv = {}
        self._since_detection = 0
        self._vain = self._quiet = 0
        self._marker_px = 0.0

    # -- detection ------------------------------------------------------------------------

    def _detect(self, image: np.ndarray) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Return the corners (m, 2) in ``image`` and their indices into the board's points."""
        if self._charuco is not None:
            from imageform.geometry.charuco import _detect_reduced, detect_charuco

            f = self._reduction(image)
            if f > 1:
                # the markers read on the frame reduced f times, the corners refined at full
                # resolution; the full-resolution search when that finds too few corners for
                # a pose, or fewer than the last frame had while the markers it read are not
                # all large (a marker lost to the reduction, not to a hand over the board)
                found = _detect_reduced(image, self._charuco, f)
                last = self._last.corners if self._last is not None and self._last.found else 0
                side = _marker_side(found.markers.corners)
                if len(found) >= self.min_corners and (
                    len(found) >= 0.8 * last or side >= 4 * _REDUCE_MIN_MARKER
                ):
                    self._marker_px = side
                    return np.asarray(found.corners, np.float64), np.asarray(found.ids, np.int64)
            # the gradient refinement, as the tracked frames': one method in a video
            found = detect_charuco(image, self._charuco, method="gradient")
            self._marker_px = _marker_side(found.markers.corners)
            return np.asarray(found.corners, np.float64), np.asarray(found.ids, np.int64)
        from imageform.geometry.checkerboard import _tracking_search

        assert self._pattern is not None
        # the tracked frames' refinement: one method in a video; the soft frame's search for a
        # smeared board left out while it keeps finding nothing (_SMEAR_PATIENCE)
        soft = self._vain < _SMEAR_PATIENCE or self._quiet % _SMEAR_RETRY == 0
        res, vain = _tracking_search(image, self._pattern, self._refinement, soft)
        self._frame_vain |= vain
        if not res.found or res.corners is None:
            return np.zeros((0, 2)), np.zeros(0, np.int64)
        uv = np.asarray(res.corners, np.float64)
        return uv, np.arange(uv.shape[0], dtype=np.int64)

    def _reduction(self, image: np.ndarray) -> int:
        """Return the factor by which a ChArUco frame's markers are read (1: not reduced).

        2 for a uint8 grey frame of a camera of at least ``_REDUCE_FROM`` pixels a side
        (4K; an RGB uint8 one is made grey by :meth:`update` first), unless the last
        detection's markers were under ``_REDUCE_MIN_MARKER`` pixels
        (twice that when halved): reading the markers of a 3840 x 2160 frame costs a
        quarter as much on its half (benchmarks/results/track-speed-2026-11-30h.md).
        """
        if not (isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 2):
            return 1
        if max(self._frame) < _REDUCE_FROM or min(image.shape) < 64:
            return 1
        if 0 < self._marker_px < 2 * _REDUCE_MIN_MARKER:
            return 1
        return 2

    def _in(
        self, image: np.ndarray, box: tuple[int, int, int, int]
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        x0, y0, x1, y1 = box
        uv, ids = self._detect(image[y0:y1, x0:x1])
        return uv + np.array([x0, y0], np.float64), ids

    def _order_like_last(self, uv: NDArray[np.float64]) -> NDArray[np.float64]:
        """Order a checkerboard's corners as the last frame's (they may be half a turn off)."""
        if self._last_uv is None or self._last_uv.shape != uv.shape:
            return uv
        turned = uv[::-1]
        d0 = np.mean(np.sum((uv - self._last_uv) ** 2, axis=1))
        d1 = np.mean(np.sum((turned - self._last_uv) ** 2, axis=1))
        return turned if d1 < d0 else uv

    def _project(self, X: NDArray[np.float64], R: object, t: object) -> tuple[Any, Any]:
        """Project board points through the full camera model (``Camera.project``)."""
        from imageform.geometry.camera import Camera

        return tuple(Camera(self.K, R, t, distortion=self.distortion).project(X))

    def _scale_px(self, pose: BoardPose) -> float:
        """Return a square's side in pixels near the board's corners (from the last pose)."""
        X = pose.object_points
        step = float(np.linalg.norm(self._points[1] - self._points[0])) or 1.0
        both = np.concatenate([X, X + np.array([step, 0.0, 0.0])])
        uv, _ = self._project(both, pose.R, pose.tvec)
        uv = np.asarray(uv, np.float64)
        d = np.linalg.norm(uv[X.shape[0] :] - uv[: X.shape[0]], axis=1)
        d = d[np.isfinite(d)]
        return float(np.median(d)) if d.size else 0.0

    def _track(self, image: np.ndarray) -> tuple[NDArray[np.float64], NDArray[np.int64]] | None:
        """Refine the last frame's corners, moved by their last motion, in ``image``.

        None when the corners do not follow (too few refine, one jumps, or they do not fit
        one pose): the caller detects the board instead.
        """
        from imageform.geometry.checkerboard_subpix import refine_corners

        last, ids = self._last, self._last_ids
        if last is None or ids is None or self._last_uv is None:
            return None
        uv = self._last_uv
        velocity = np.array(
            [uv[k] - self._prev_uv[int(i)] if int(i) in self._prev_uv else (0.0, 0.0)
             for k, i in enumerate(ids)]
        )  # fmt: skip
        pred = uv + velocity
        square = self._scale_px(last)
        if not square > 8:  # too small to refine reliably (a detection decides)
            return None
        hw = int(np.clip(round(square / 3), 2, 15))
        sym = self._pattern is not None and self._refinement == "symmetric"
        hs = int(np.clip(np.floor(0.8 * square), 2, 30)) if sym else 0
        h, w = image.shape[:2]
        reach = max(2 * hw + 2, hs + 3)
        lo = np.floor(pred.min(axis=0) - reach).astype(int)
        hi = np.ceil(pred.max(axis=0) + reach + 1).astype(int)
        x0, y0 = max(lo[0], 0), max(lo[1], 0)
        x1, y1 = min(hi[0], w), min(hi[1], h)
        if x1 - x0 < 8 or y1 - y0 < 8:
            return None
        inside = np.all((pred >= [x0 + hw, y0 + hw]) & (pred <= [x1 - 1 - hw, y1 - 1 - hw]), 1)
        if not np.any(inside):
            return None
        offset = np.array([x0, y0], np.float64)
        crop = image[y0:y1, x0:x1]
        res = refine_corners(crop, pred[inside] - offset, half_window=hw)
        # then, from there, the detector's own window: clear of the markers' corners for a
        # ChArUco board (whose bits would pull a wide window off the saddle)
        fine = int(0.3 * square)
        if self._charuco is not None:
            b = self._charuco
            gap = (b.square_length - b.marker_length) / 2 * np.sqrt(2) / b.square_length
            # at most the detector's own window (charuco._predicted's): a wider one on a 4K
            # frame's squares moves the corners off the detected ones (benchmarks/results/
            # track-speed-2026-11-30h.md), and costs its area
            fine = min(fine, int(0.6 * gap * square), _MAX_FINE)
        res2 = refine_corners(
            crop, np.asarray(res.corners), half_window=max(2, fine), max_iter=40, tol=1e-4
        )
        got = np.asarray(res2.corners, np.float64)
        # a ChArUco corner must pass the detector's blur test: a saddle that blur has merged
        # with the markers' borders moves when the window grows by a pixel
        steady = np.ones(got.shape[0], dtype=bool)
        if self._charuco is not None:
            from imageform.geometry.charuco import _MAX_WINDOW_SHIFT

            res3 = refine_corners(crop, got, half_window=max(2, fine) + 1, max_iter=40, tol=1e-4)
            steady = np.linalg.norm(np.asarray(res3.corners) - got, axis=1) <= _MAX_WINDOW_SHIFT
        if sym:
            got = self._symmetric(crop, got, hs, square)
        got = got + offset
        ok = np.isin(np.asarray(res.status), (0, 1)) & np.isin(np.asarray(res2.status), (0, 1))
        ok &= np.linalg.norm(got - pred[inside], axis=1) < 0.5 * square
        need = max(self.min_corners, int(np.ceil(0.8 * ids.size)))
        keep = np.flatnonzero(inside)[ok]
        if keep.size < need:
            return None
        held = ok & steady
        if np.count_nonzero(held) < need:
            # too many corners blurred: the board is detected again, and these corners are
            # the frame's pose only if that finds no board (_spare)
            self._spare = (got[ok], ids[keep])
            return None
        return got[held], ids[np.flatnonzero(inside)[held]]

    def _symmetric(
        self, crop: np.ndarray, uv: NDArray[np.float64], h: int, square: float
    ) -> NDArray[np.float64]:
        """Move a checkerboard's corners ``uv`` in ``crop`` to their centres of symmetry.

        As :func:`find_checkerboard`'s ``method="symmetric"``: a round window of radius
        ``h`` (0.8 of a square); a corner whose window leaves ``crop``, or that does not
        converge or moves more than a quarter of a square, keeps ``uv``.
        """
        from imageform.geometry.checkerboard_subpix import (
            _gray_and_corners,
            refine_symmetric_inside,
        )

        gray, pts = _gray_and_corners(crop, uv)
        return refine_symmetric_inside(gray, pts, pts, h, 30, 1e-3, 0.25 * square)[0]

    def _fits(self, uv: NDArray[np.float64], X: NDArray[np.float64], res: object) -> bool:
        """Whether every corner lies within 1.5 px of the pose's reprojection."""
        R, t = np.asarray(res.R), np.asarray(res.tvec)  # type: ignore[attr-defined]
        proj, _ = self._project(X, R, t)
        err = np.linalg.norm(np.asarray(proj, np.float64) - uv, axis=1)
        return bool(np.all(np.isfinite(err)) and err.max() < 1.5 and float(res.rms) < 0.75)  # type: ignore[attr-defined]

    # -- one frame ------------------------------------------------------------------------

    def update(self, image: ArrayLike) -> BoardPose:
        """Find the board in ``image`` (a frame, (H, W) or (H, W, 3)) and solve its pose."""
        from imageform.geometry.aruco import _working

        with _working(self._work):  # this tracker's buffers for a large frame
            return self._update(image)

    def _update(self, image: ArrayLike) -> BoardPose:
        from imageform.geometry.aruco import _grey_source
        from imageform.geometry.pnp import solve_pnp
        from imageform.geometry.rotations import matrix_to_rvec

        a = np.asarray(image)
        if a.ndim not in (2, 3) or a.shape[0] < 8 or a.shape[1] < 8:
            raise InvalidInputError(f"expected a frame as an (H, W[, 3]) image, got {describe(a)}")
        h, w = a.shape[:2]
        self._frame = (h, w)
        if self._charuco is not None:
            # an RGB uint8 frame (imageform track's video reader) to its grey, rounded to
            # uint8, once: the markers and corners read on it as on a grey frame (the integer
            # threshold, the buffers; on a 4K frame the markers' reading on its half)
            a = np.asarray(_grey_source(a))
        self._quiet = self._quiet + 1 if self._vain >= _SMEAR_PATIENCE else 0
        self._frame_vain = False
        self._spare = None
        uv = np.zeros((0, 2))
        ids = np.zeros(0, np.int64)
        searched = "none"
        res = None
        if (
            self.predict
            and self._last is not None
            and self._last.found
            and self._since_detection + 1 < self.redetect
        ):
            tracked = self._track(a)
            if tracked is not None:
                uv, ids = tracked
                X = self._points[ids]
                try:
                    res = solve_pnp(X, uv, self.K, self.distortion)
                except InvalidInputError:
                    res = None
                if res is not None and bool(res.valid) and self._fits(uv, X, res):
                    searched = "tracked"
                else:
                    res = None
        if res is None:
            if self.predict and self._box is not None:
                uv, ids = self._in(a, self._box)
                searched = "box"
            if uv.shape[0] < self.min_corners:
                uv, ids = self._detect(a)
                searched = "frame"
            if uv.shape[0] < self.min_corners and self._spare is not None:
                uv, ids = self._spare
                searched = "tracked"
            if uv.shape[0] < self.min_corners:
                return self._lost(uv)
            if self._pattern is not None:
                uv = self._order_like_last(uv)
            X = self._points[ids]
            try:
                res = solve_pnp(X, uv, self.K, self.distortion)
            except InvalidInputError:
                return self._lost(uv)
            if not bool(res.valid) or not np.isfinite(res.rms):
                return self._lost(uv)
            if searched != "tracked":
                self._since_detection = 0
            elif not self._fits(uv, X, res):
                return self._lost(uv)
            else:
                self._since_detection += 1
        else:
            self._since_detection += 1
        self._vain = self._quiet = 0
        R = np.asarray(res.R, np.float64)
        t = np.asarray(res.tvec, np.float64)
        if self.smooth < 1.0 and self._last is not None and self._last.found:
            R, t = _blend(R, t, self._last, self.smooth)
        rvec = np.asarray(matrix_to_rvec(R), np.float64)
        pose = BoardPose(True, rvec, t, R, float(res.rms), uv, X, searched)
        # the next frame's box: this one's corners, grown by half their extent (>= 32 px)
        lo, hi = uv.min(axis=0), uv.max(axis=0)
        grow = np.maximum((hi - lo) * 0.5, 32.0)
        x0, y0 = np.floor(lo - grow).astype(int)
        x1, y1 = np.ceil(hi + grow).astype(int)
        self._box = (max(x0, 0), max(y0, 0), min(x1, w), min(y1, h))
        if self._last_ids is not None and self._last_uv is not None:
            self._prev_uv = {int(i): p for i, p in zip(self._last_ids, self._last_uv, strict=True)}
        else:
            self._prev_uv = {}
        self._last_uv = uv
        self._last_ids = ids
        self._last = pose
        return pose

    def _lost(self, uv: NDArray[np.float64]) -> BoardPose:
        """Forget the board (not found in this frame) and report the frame as missing."""
        self._box = None
        self._last = None
        if self._frame_vain:
            self._vain += 1
        return _missing("none", uv)
