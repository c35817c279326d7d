r"""Several ArUco markers rigidly attached to one object: a marker map and its video tracker.

A navigation tool, a patient reference or a cube carries several markers whose corners are
known in the object's own frame (a *marker map*, OpenCV's ``cv2.aruco.Board(objPoints,
dictionary, ids)``). Each frame, every marker of the map that is seen gives four
correspondences, and the object's pose is solved from all of them jointly (PnP over all
corners), so that a marker covered by a hand or gone out of view only removes its four
corners.

A marker decoded with a wrong id that the map also holds (a bit misread, a second print of
one marker on another object) brings four corners that disagree with the others. Each
visible marker's two IPPE-square poses (:func:`solve_square_pose`) are hypotheses for the
whole object; the hypothesis under which the most markers reproject within a fifth of their
side wins (a RANSAC over markers, every hypothesis tried), and only those markers enter the
joint refinement. A single visible marker keeps IPPE's two solutions and the continuity
rule of :class:`MarkerTracker`.

The map's frame is the user's; :func:`grid_marker_map` makes a planar grid in the frame of
:class:`CharucoBoard` (origin at the first marker's top-left corner, x to the right, y down
the rows, z into the print), the layout of OpenCV's ``cv2.aruco.GridBoard``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from imageform._typing import ArrayLike
from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError
from imageform.geometry.distortion import BrownConrady, DivisionModel, KannalaBrandt
from imageform.geometry.marker_tracking import (
    _PRIOR_FRAMES,
    _PRIOR_GATE,
    _PRIOR_MARGIN,
    _angle,
    _cross2,
    _ippe_pair,
    _pick,
    _Prior,
    _prior_costs,
    _refine_marker_corners,
    marker_points,
)
from imageform.geometry.tracking import BoardPose, _blend, _check_camera, _missing

__all__ = ["MarkerMap", "MarkerMapTracker", "grid_marker_map"]

F64 = NDArray[np.float64]

#: A marker's corners must form a square: each side and diagonal within this fraction of
#: the square's (a hand-measured map is a percent off at most).
_SQUARE_TOLERANCE = 0.02

#: A marker agrees with a hypothesis of the object's pose when its four corners reproject
#: within this fraction of its side in pixels (at least ``_AGREE_PX``); after the joint
#: refinement, within ``_KEEP_FRACTION`` of its side (at least ``_KEEP_PX``).
_AGREE_FRACTION, _AGREE_PX = 0.2, 3.0
_KEEP_FRACTION, _KEEP_PX = 0.1, 2.0

#: Hypotheses come from the largest this many visible markers (two poses each).
_MAX_SEEDS = 8


def _one_each(agree: NDArray[np.bool_], err: F64, which: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Return ``agree`` (h, m) with at most one sighting of each map marker per row.

    Of the sightings of one marker (``which`` (m,): their indices in the map) that agree
    with a hypothesis, the one of the smallest error ``err`` (h, m) stays (the first of
    equal ones): two copies of one marker never enter one pose.
    """
    if np.unique(which).size == which.size:
        return agree
    out = agree.copy()
    for k in np.unique(which):
        seen = np.flatnonzero(which == k)
        if seen.size < 2:
            continue
        e = np.where(agree[:, seen], err[:, seen], np.inf)
        best = seen[np.argmin(e, axis=1)]
        out[:, seen] = False
        rows = np.flatnonzero(agree[:, seen].any(axis=1))
        out[rows, best[rows]] = True
    return out


def _rival_sightings(agree: NDArray[np.bool_], which: NDArray[np.int64]) -> bool:
    """Whether hypotheses ``agree`` (h, m) take different sightings of one map marker.

    ``which`` (m,): each sighting's marker in the map. The hypotheses are the best supported
    (as many agreeing markers each): when two of them take different sightings of a marker
    read twice (only one marker of the map visible, read in two places; two copies of the
    object in view), the frame alone cannot say which is the object.
    """
    for k in np.unique(which):
        seen = np.flatnonzero(which == k)
        if seen.size < 2:
            continue
        taken = agree[:, seen]
        if np.count_nonzero(taken.any(axis=0)) > 1:
            return True
    return False


def _fit_rotation(A: F64, B: F64) -> F64:
    """Return the rotation R minimising ``sum ||R a_i - b_i||^2`` (centred points, Kabsch)."""
    U, _, Vt = np.linalg.svd(B.T @ A)
    d = np.sign(np.linalg.det(U @ Vt)) or 1.0
    return np.asarray(U @ np.diag([1.0, 1.0, d]) @ Vt, np.float64)


@dataclass(frozen=True)
class MarkerMap:
    r"""ArUco markers with known ids rigidly attached to one object (a marker map).

    Parameters
    ----------
    ids : array_like of int (n,)
        The markers' ids in ``dictionary``, all different.
    corners : array_like (n, 4, 3)
        Each marker's corners in the object's frame, in :func:`marker_points`' order
        (top-left, top-right, bottom-right, bottom-left as printed), in ``unit``. Each must
        be a square (sides and diagonals within 2 % of a square's), of any size.
    dictionary : str
        The markers' ArUco dictionary (:func:`aruco_dictionary`'s names).
    unit : str
        The unit of the corners: the unit of the poses (a label only, e.g. ``"mm"``).

    Notes
    -----
    Marker :math:`i`'s frame (:func:`marker_points`, side :math:`s_i`) maps into the
    object's by the rigid motion :math:`X = R_i X_m + t_i` fitted to its corners
    (Kabsch's): :attr:`marker_poses`. A map file is read and written by
    :func:`imageform.io.read_marker_map` and :func:`imageform.io.write_marker_map`.

    Examples
    --------
    >>> m = MarkerMap([3, 9], [marker_points(20.0), marker_points(20.0) + [30, 0, 0]], "4x4_50")
    >>> len(m), m.sides.tolist()
    (2, [20.0, 20.0])
    """

    ids: NDArray[np.int64]
    corners: F64
    dictionary: str = "6x6_250"
    unit: str = "mm"
    sides: F64 = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Check the ids, the corners (squares) and the dictionary."""
        from imageform.geometry.aruco import aruco_dictionary

        if not isinstance(self.dictionary, str):
            raise InvalidInputError(
                f"expected dictionary as a str (a name), got {describe(self.dictionary)}"
            )
        if not isinstance(self.unit, str) or not self.unit.strip():
            raise InvalidInputError(f"expected unit as a non-empty str, got {describe(self.unit)}")
        size = aruco_dictionary(self.dictionary).size
        raw = np.asarray(self.ids)
        if raw.ndim != 1 or raw.size == 0 or raw.dtype.kind not in "iu":
            raise InvalidInputError(f"expected ids as a 1-D array of integers, got {describe(raw)}")
        ids = raw.astype(np.int64)
        if np.any(ids < 0) or np.any(ids >= size):
            raise InvalidInputError(
                f"expected ids 0 to {size - 1} of dictionary {self.dictionary}, got "
                f"{int(ids.min())} to {int(ids.max())}"
            )
        if np.unique(ids).size != ids.size:
            raise InvalidInputError("expected ids each once in a marker map, got an id twice")
        try:
            c = np.asarray(self.corners, dtype=np.float64)
        except (TypeError, ValueError):
            c = np.zeros(0)
        if c.shape != (ids.size, 4, 3) or not np.all(np.isfinite(c)):
            raise InvalidInputError(
                f"expected corners as ({ids.size}, 4, 3) finite numbers (one marker per id), "
                f"got {describe(self.corners)}"
            )
        sides = np.linalg.norm(c - np.roll(c, 1, axis=1), axis=2)
        s = sides.mean(axis=1)
        diag = np.stack(
            [np.linalg.norm(c[:, 2] - c[:, 0], axis=1), np.linalg.norm(c[:, 3] - c[:, 1], axis=1)],
            1,
        )
        bad = (
            ~(s > 0)
            | np.any(np.abs(sides - s[:, None]) > _SQUARE_TOLERANCE * s[:, None], axis=1)
            | np.any(
                np.abs(diag - np.sqrt(2) * s[:, None])
                > _SQUARE_TOLERANCE * np.sqrt(2) * s[:, None],
                axis=1,
            )
        )
        if np.any(bad):
            raise InvalidInputError(
                f"expected each marker's corners as a square (top-left, top-right, "
                f"bottom-right, bottom-left), marker id {int(ids[np.argmax(bad)])} is not"
            )
        ids.setflags(write=False)
        c.setflags(write=False)
        s.setflags(write=False)
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "corners", c)
        object.__setattr__(self, "sides", s)

    def __len__(self) -> int:
        """How many markers the map holds."""
        return int(self.ids.size)

    @property
    def marker_poses(self) -> tuple[F64, F64]:
        """Each marker's frame in the object's: ``R (n, 3, 3)``, ``t (n, 3)``, X = R Xm + t."""
        Rs = np.empty((len(self), 3, 3))
        ts = np.empty((len(self), 3))
        for i, (c, s) in enumerate(zip(self.corners, self.sides, strict=True)):
            centre = c.mean(axis=0)
            Rs[i] = _fit_rotation(marker_points(float(s)), c - centre)
            ts[i] = centre
        return Rs, ts


def grid_marker_map(
    shape: tuple[int, int],
    side: float,
    gap: float,
    *,
    first_id: int = 0,
    dictionary: str = "6x6_250",
    unit: str = "mm",
) -> MarkerMap:
    r"""Return a planar grid of markers (OpenCV's ``GridBoard`` layout) as a :class:`MarkerMap`.

    Marker :math:`k = r\,\mathrm{cols} + c` (id ``first_id + k``) has its top-left corner at
    :math:`(c\,(s + g),\; r\,(s + g),\; 0)` and its others at :math:`+(s, 0)`,
    :math:`+(s, s)`, :math:`+(0, s)`: x to the right, y down the rows, z into the print
    (:class:`CharucoBoard`'s frame).

    Parameters
    ----------
    shape : (int, int)
        Markers a row and rows, ``(cols, rows)``.
    side : float
        A marker's side (its black square's), in ``unit``.
    gap : float
        The white space between neighbouring markers (>= 0).
    first_id : int, keyword-only
        The first (top-left) marker's id; the others follow row by row.
    dictionary : str, keyword-only
        The ArUco dictionary.
    unit : str, keyword-only
        The lengths' unit (the poses').

    Returns
    -------
    MarkerMap

    Examples
    --------
    >>> m = grid_marker_map((2, 1), 40.0, 10.0, first_id=4, dictionary="4x4_50")
    >>> m.ids.tolist(), m.corners[1, 0].tolist()
    ([4, 5], [50.0, 0.0, 0.0])
    """
    if not isinstance(shape, tuple | list) or len(shape) != 2:
        raise InvalidInputError(f"expected shape as (cols, rows), got {describe(shape)}")
    cols = as_int(shape[0], "shape (cols)", minimum=1, maximum=1000)
    rows = as_int(shape[1], "shape (rows)", minimum=1, maximum=1000)
    s = as_real(side, "side", positive=True, maximum=1e12)
    g = as_real(gap, "gap", minimum=0.0, maximum=1e12)
    first = as_int(first_id, "first_id", minimum=0, maximum=1_000_000)
    r, c = np.divmod(np.arange(cols * rows), cols)
    x0, y0 = c * (s + g), r * (s + g)
    dx, dy = np.array([0.0, s, s, 0.0]), np.array([0.0, 0.0, s, s])
    corners = np.stack(
        [x0[:, None] + dx, y0[:, None] + dy, np.zeros((cols * rows, 4))], axis=-1
    ).astype(np.float64)
    return MarkerMap(first + np.arange(cols * rows), corners, dictionary, unit)


class MarkerMapTracker:
    r"""Follow an object carrying several ArUco markers (a :class:`MarkerMap`) through video.

    :class:`BoardTracker`'s interface: :meth:`update` returns a :class:`BoardPose` of the
    map's frame in the camera's (:math:`X_c = R X + t`, the map's unit), NaN when lost.
    Each frame:

    1. the map's markers are detected (:func:`detect_aruco_markers`), first in the box of
       the whole map as the previous frame's pose projects it, grown by half its size (at
       least 32 pixels each way), in the whole frame when none is there and every
       ``redetect``-th frame (markers coming into view); an id read in two places (a
       misread marker, a second print, a reflection) keeps both sightings
       (``detect_aruco_markers(..., all_sightings=True)``: step 2 settles which agrees, and
       at most one sighting of a marker, the nearer, counts for a hypothesis and enters the
       pose); each marker's corners are refined by the
       gradient criterion through half a cell (as :class:`MarkerTracker`);
    2. every visible marker's two IPPE-square poses (:func:`solve_square_pose`, closed
       form) give two hypotheses of the object's pose, :math:`R = R_m R_i^\top`,
       :math:`t = t_m - R\,t_i` (:attr:`MarkerMap.marker_poses`); under each, a marker
       *agrees* when its four corners reproject within :math:`\max(3,\ 0.2\,s_{px})`
       pixels (:math:`s_{px}` its side in the image). The hypothesis with most agreeing
       markers wins (ties: the smaller error over them). When the best-supported
       hypotheses take different sightings of a marker read twice (the only marker of the
       map in view, read in two places; two copies of the object), nothing in the frame
       tells which is the object: the one nearer the last pose found (rotation and
       translation, the motion prior of :class:`MarkerTracker`) is taken when it is
       clearly nearer; on a first frame, or when none is, the pose is missing with
       ``searched = "ambiguous"`` and every sighting's corners in ``image_points`` (the
       tracker does not guess; a later frame with more of the map in view, or one copy
       only, settles it). A misread marker among others of the map is no such case: only
       its true sighting agrees with them;
    3. the pose is refined by Levenberg-Marquardt on the reprojection error of all
       agreeing markers' corners jointly (undistorted), the markers then farther than
       :math:`\max(2,\ 0.1\,s_{px})` pixels are dropped and the pose refined again;
    4. the best hypothesis of the other tilt (more than 5 degrees away: the mirror of a
       marker's IPPE pair) is refined on the same corners, and :class:`MarkerTracker`'s
       rules choose: the better fit when the other's RMS exceeds
       :math:`4\,\mathrm{rms}_1 + 1` pixels, else the one nearer the last pose (rotation
       and translation, the prior widening with the frames since), else the better fit
       when the fits differ beyond the noise, else none (``searched = "ambiguous"``: both
       tilts fit and nothing tells them apart, a first frame of a map seen nearly
       face-on). With one marker this is :class:`MarkerTracker`'s choice exactly.

    Parameters
    ----------
    marker_map : MarkerMap
        The markers and their corners on the object.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        The lens distortion.
    smooth : float, keyword-only
        Weight :math:`\alpha` of the newest pose in (0, 1] (:class:`BoardTracker`'s
        exponential filter); 1 turns smoothing off.
    predict : bool, keyword-only
        Search the previous frame's box before the whole frame.
    continuity : bool, keyword-only
        Settle the mirror-tilt ambiguity by continuity, refusing when nothing separates the
        two tilts (otherwise the better fit, never refused).
    min_markers : int, keyword-only
        Fewest agreeing markers for a pose.
    redetect : int, keyword-only
        Search the whole frame at least every ``redetect`` frames.

    Examples
    --------
    >>> from imageform.geometry import aruco_marker_image
    >>> frame = np.full((240, 320), 255, np.uint8)
    >>> frame[80:160, 60:140] = aruco_marker_image(0, "4x4_50", size_px=80)
    >>> frame[80:160, 180:260] = aruco_marker_image(1, "4x4_50", size_px=80)
    >>> K = np.array([[300.0, 0, 159.5], [0, 300, 119.5], [0, 0, 1]])
    >>> tracker = MarkerMapTracker(grid_marker_map((2, 1), 40.0, 20.0, dictionary="4x4_50"), K)
    >>> pose = tracker.update(frame)
    >>> pose.found, pose.corners, (pose.tvec.round(0) + 0.0).tolist()
    (True, 8, [-50.0, -20.0, 150.0])
    """

    def __init__(
        self,
        marker_map: MarkerMap,
        K: object,
        distortion: BrownConrady | DivisionModel | KannalaBrandt | None = None,
        *,
        smooth: float = 1.0,
        predict: bool = True,
        continuity: bool = True,
        min_markers: int = 1,
        redetect: int = 10,
    ) -> None:
        from imageform.geometry.aruco import aruco_dictionary

        if not isinstance(marker_map, MarkerMap):
            raise InvalidInputError(
                f"expected marker_map as a MarkerMap, got {describe(marker_map)}"
            )
        self.map = marker_map
        self.dictionary = aruco_dictionary(marker_map.dictionary)
        self.K = _check_camera(K, distortion)
        self.distortion = distortion
        self.smooth = as_real(smooth, "smooth", positive=True, maximum=1.0)
        self.predict = bool(predict)
        self.continuity = bool(continuity)
        self.min_markers = as_int(min_markers, "min_markers", minimum=1, maximum=len(marker_map))
        self.redetect = as_int(redetect, "redetect", minimum=1, maximum=1_000_000)
        self._index = {int(i): k for k, i in enumerate(marker_map.ids)}
        self._Rm, self._tm = marker_map.marker_poses
        self._box: tuple[int, int, int, int] | None = None
        self._last: BoardPose | None = None
        self._prior: _Prior | None = None
        self._since_frame = 0
        from imageform.geometry.aruco import _WorkArea

        #: the work buffers of a frame larger than the detector keeps for every thread
        self._work = _WorkArea()

    def reset(self) -> None:
        """Forget the previous frames (a cut in the video)."""
        self._box = self._last = None
        self._prior = None
        self._since_frame = 0

    # -- detection ------------------------------------------------------------------------

    def _find(
        self, image: np.ndarray, box: tuple[int, int, int, int] | None
    ) -> tuple[NDArray[np.int64], F64]:
        """Return the map's markers found (indices into the map) and their corners (m, 4, 2)."""
        from imageform.geometry.aruco import detect_aruco_markers

        x0, y0, x1, y1 = box if box is not None else (0, 0, image.shape[1], image.shape[0])
        crop = image[y0:y1, x0:x1]
        # by name: the detector caches a predefined dictionary's rotated codes by name
        found = detect_aruco_markers(crop, self.map.dictionary, all_sightings=True)
        # every sighting of the map's ids: an id seen twice (a second print, a misread
        # marker, a reflection) is settled by which sighting agrees with the others (_solve)
        keep = [j for j in range(len(found)) if int(found.ids[j]) in self._index]
        if not keep:
            return np.zeros(0, np.int64), np.zeros((0, 4, 2))
        which = np.array([self._index[int(found.ids[j])] for j in keep], np.int64)
        raw = np.asarray(found.corners, np.float64)[keep]
        uv = _refine_marker_corners(crop, raw, self.dictionary.marker_size)
        return which, uv + np.array([x0, y0], np.float64)

    # -- pose -----------------------------------------------------------------------------

    def _errors(self, R: F64, t: F64, X: F64, ideal: F64) -> F64:
        """Return each marker's largest corner error (m,) in pixels under poses ``R``, ``t``.

        ``R (h, 3, 3)``, ``t (h, 3)``; ``X (m, 4, 3)``, ``ideal (m, 4, 2)`` undistorted
        pixels; a corner at or behind the camera counts as infinitely far. Returns (h, m).
        """
        k = self.K / self.K[2, 2]
        c = np.einsum("hij,mkj->hmki", R, X) + t[:, None, None, :]
        z = c[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = c[..., 0] / z, c[..., 1] / z
            u = k[0, 0] * x + k[0, 1] * y + k[0, 2]
            v = k[1, 1] * y + k[1, 2]
            e = np.hypot(u - ideal[None, ..., 0], v - ideal[None, ..., 1])
        e = np.where((z > 0) & np.isfinite(e), e, np.inf)
        return np.asarray(e.max(axis=-1), np.float64)

    def _solve(
        self, which: NDArray[np.int64], uv: F64
    ) -> tuple[F64, F64, float, NDArray[np.bool_]] | str | None:
        """Solve the object's pose from the markers ``which`` seen at ``uv`` (m, 4, 2).

        ``"ambiguous"`` on a first frame whose best-supported hypotheses take different
        sightings of a marker read twice (:func:`_rival_sightings`).
        """
        from imageform.geometry.pnp import _normalised, refine_pose

        k = self.K / self.K[2, 2]
        m = which.size
        try:
            xy = np.asarray(_normalised(uv.reshape(-1, 2), k, self.distortion), np.float64)
        except InvalidInputError:
            return None
        ideal = np.stack(
            [k[0, 0] * xy[:, 0] + k[0, 1] * xy[:, 1] + k[0, 2], k[1, 1] * xy[:, 1] + k[1, 2]], -1
        ).reshape(m, 4, 2)
        X = self.map.corners[which]
        side_px = np.linalg.norm(ideal - np.roll(ideal, 1, axis=1), axis=2).mean(axis=1)
        # hypotheses: each of the largest markers' two IPPE poses, carried to the object
        seeds = np.argsort(-side_px, kind="stable")[:_MAX_SEEDS]
        Rh, th, seed_of = [], [], []
        quads = xy.reshape(m, 4, 2)
        for j in seeds:
            q = quads[j]
            if not np.all(np.abs(_cross2(q[[1, 2, 3, 0]] - q, q[[3, 0, 1, 2]] - q)) > 1e-12):
                continue  # three corners in a line: no quadrilateral
            pair = _ippe_pair(q, marker_points(float(self.map.sides[which[j]])))
            Ri, ti = self._Rm[which[j]], self._tm[which[j]]
            for Rs, ts in zip(*pair, strict=True):
                R = Rs @ Ri.T
                Rh.append(R)
                th.append(ts - R @ ti)
                seed_of.append(int(j))
        if not Rh:
            return None
        R_all, t_all, seed = np.stack(Rh), np.stack(th), np.array(seed_of, np.int64)
        loose = np.maximum(_AGREE_PX, _AGREE_FRACTION * side_px)
        own = np.arange(m)[None, :] == seed[:, None]
        err = self._errors(R_all, t_all, X, ideal)
        agree = _one_each((err < loose) | own, err, which)
        # local optimisation: each hypothesis refined on the markers that agree with it, which
        # are counted again (a pose from one marker extrapolates poorly to far ones)
        Xb = np.broadcast_to(X.reshape(-1, 3), (len(Rh), 4 * m, 3)).copy()
        ub = np.broadcast_to(ideal.reshape(-1, 2), (len(Rh), 4 * m, 2)).copy()
        for _ in range(2):
            w = np.repeat(agree, 4, axis=1).astype(np.float64)
            R_all, t_all, _ = refine_pose(R_all, t_all, Xb, ub, k, w, 10)
            err = self._errors(R_all, t_all, X, ideal)
            agree = _one_each((err < loose) | own, err, which)
        count = agree.sum(axis=1)
        total = np.where(agree, err, 0.0).sum(axis=1)
        # the most agreeing markers, then the smallest error over them
        best = int(np.lexsort((total, -count))[0])
        top = np.flatnonzero(count == count[best])
        if _rival_sightings(agree[top], which):
            # as well supported, on different sightings of a marker: the sightings told
            # apart by the last pose (rotation and translation), or not at all
            prior = self._prior if self.continuity else None
            if prior is None or prior.gap > _PRIOR_FRAMES:
                return "ambiguous"
            cost = _prior_costs(R_all[top], t_all[top], prior)
            near = int(np.argmin(cost))
            rivals = np.array(
                [_rival_sightings(agree[[top[near], h]], which) for h in top], np.bool_
            )
            if cost[near] > _PRIOR_GATE or np.any(cost[rivals] - cost[near] < _PRIOR_MARGIN):
                return "ambiguous"
            best = int(top[near])
        # the other tilt: the best hypothesis more than 5 degrees from the winner (with one
        # marker, its IPPE mirror)
        far = np.array([_angle(R, R_all[best]) > np.radians(5.0) for R in R_all])
        starts = [best]
        if np.any(far):
            cand = np.flatnonzero(far)
            starts.append(int(cand[np.lexsort((total[cand], -count[cand]))[0]]))
        R0, t0 = R_all[starts], t_all[starts]
        inl = err[best] < np.maximum(_KEEP_PX, _KEEP_FRACTION * side_px)
        inl |= own[best] & ~np.any(inl)
        inl = _one_each(inl[None], err[best][None], which)[0]
        used = inl
        for _ in range(3):
            used = inl
            n = int(inl.sum())
            Xb = np.broadcast_to(X[inl].reshape(-1, 3), (len(starts), 4 * n, 3)).copy()
            ub = np.broadcast_to(ideal[inl].reshape(-1, 2), (len(starts), 4 * n, 2)).copy()
            R1, t1, rms = refine_pose(R0, t0, Xb, ub, k, np.ones((len(starts), 4 * n)), 20)
            e = self._errors(R1[:1], t1[:1], X, ideal)[0]
            keep = _one_each(
                (e < np.maximum(_KEEP_PX, _KEEP_FRACTION * side_px))[None], e[None], which
            )[0]
            if not np.any(keep) or np.array_equal(keep, inl):
                break
            inl = keep
        pick = _pick(rms, R1, t1, 4 * int(inl.sum()), self._prior, self.continuity)
        if pick is None:
            return "ambiguous"  # both tilts fit and no recent pose tells them apart
        i = pick
        if int(used.sum()) < self.min_markers or not np.isfinite(rms[i]):
            return None
        e = self._errors(R1[i : i + 1], t1[i : i + 1], X[used], ideal[used])[0]
        if not np.all(np.isfinite(e)):
            return None
        return R1[i], t1[i], float(rms[i]), used

    # -- one frame ------------------------------------------------------------------------

    def update(self, image: ArrayLike) -> BoardPose:
        """Find the map's markers in ``image`` ((H, W) or (H, W, 3)) and solve its pose."""
        from imageform.geometry.aruco import _working

        with _working(self._work):  # this tracker's buffers for a large frame
            return self._update(image)

    def _update(self, image: ArrayLike) -> BoardPose:
        from imageform.geometry.aruco import _grey_source
        from imageform.geometry.rotations import matrix_to_rvec

        a = np.asarray(image)
        if a.ndim not in (2, 3) or a.shape[0] < 8 or a.shape[1] < 8:
            raise InvalidInputError(f"expected a frame as an (H, W[, 3]) image, got {describe(a)}")
        a = np.asarray(_grey_source(a))  # a colour frame read on its grey uint8, once
        h, w = a.shape[:2]
        which, uv, searched = np.zeros(0, np.int64), np.zeros((0, 4, 2)), "none"
        if self.predict and self._box is not None and self._since_frame + 1 < self.redetect:
            which, uv = self._find(a, self._box)
            searched = "box"
        if which.size == 0:
            which, uv = self._find(a, None)
            searched = "frame"
        if which.size == 0:
            return self._lost()
        got = self._solve(which, uv)
        if got == "ambiguous":
            self._lost()
            return _missing("ambiguous", uv.reshape(-1, 2))
        if got is None or isinstance(got, str):
            return self._lost(uv.reshape(-1, 2))
        R, t, rms, inl = got
        self._prior = _Prior(R.copy(), t.copy(), 1)
        self._since_frame = 0 if searched == "frame" else self._since_frame + 1
        if self.smooth < 1.0 and self._last is not None and self._last.found:
            R, t = _blend(R, t, self._last, self.smooth)
        pts = uv[inl].reshape(-1, 2)
        pose = BoardPose(
            True,
            np.asarray(matrix_to_rvec(R), np.float64),
            t,
            R,
            rms,
            pts,
            self.map.corners[which[inl]].reshape(-1, 3),
            searched,
        )
        # the next frame's box: the whole map where this pose puts it (the markers not used
        # in this frame included: hidden, misread or coming into view), grown
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        whole = self._projected(R, t)
        if whole.size:
            lo = np.minimum(lo, np.maximum(whole.min(axis=0), -w))
            hi = np.maximum(hi, np.minimum(whole.max(axis=0), 2 * w))
        grow = np.maximum((hi - lo) * 0.5, 32.0)
        x0, y0 = np.floor(lo - grow).astype(int)
        x1, y1 = np.ceil(hi + grow).astype(int)
        self._box = (max(x0, 0), max(y0, 0), min(x1, w), min(y1, h))
        self._last = pose
        return pose

    def _projected(self, R: F64, t: F64) -> F64:
        """Return the map's corners projected by the pose (ideal pixels), those in front."""
        k = self.K / self.K[2, 2]
        c = self.map.corners.reshape(-1, 3) @ R.T + t
        c = c[c[:, 2] > 1e-9 * np.abs(c).max()]
        x, y = c[:, 0] / c[:, 2], c[:, 1] / c[:, 2]
        return np.stack([k[0, 0] * x + k[0, 1] * y + k[0, 2], k[1, 1] * y + k[1, 2]], -1)

    def _lost(self, uv: F64 | None = None) -> BoardPose:
        self._box = self._last = None
        self._since_frame = 0
        if self._prior is not None:  # one more frame since the last pose
            self._prior = self._prior._replace(gap=self._prior.gap + 1)
        return _missing("none", uv)
