"""ChArUco boards: a checkerboard with an ArUco marker in every white square.

The markers name the squares, so a board seen in part, at a slant or cut by the image
border still gives every visible inner corner with its identity; the checkerboard corners
(saddle points) are located to a fraction of a pixel. That makes ChArUco the target of
choice for calibration from views that do not show the whole board (Garrido-Jurado et al.,
2014; OpenCV's ``CharucoBoard``/``CharucoDetector``, whose layout this module follows, so
boards printed for OpenCV are read here and the other way round).

Layout (OpenCV's, tested against ``cv2.aruco.CharucoBoard.generateImage``): ``squares =
(cols, rows)``; the top-left square is black; square ``(r, c)`` is white when ``r + c`` is
odd, and the white squares hold markers ``0, 1, 2, ...`` row by row, each centred in its
square. Inner corner ``k = r (cols - 1) + c`` sits at ``((c + 1) s, (r + 1) s, 0)`` on the
board (``s`` the square length; x to the right, y down the printed board, z into it).
OpenCV before 4.6 drew boards with an even number of rows the other way round (the top-left
square white, holding marker 0: its ``setLegacyPattern(true)``, here ``legacy=True``); the
inner corners and their ids are the same in both layouts, and :func:`detect_charuco` reads a
board of either layout whichever it is told (the markers found decide).

Corner detection (:func:`detect_charuco`): the markers are found and decoded
(:func:`imageform.geometry.detect_aruco_markers`); each inner corner with at least
``min_markers`` decoded markers in the squares around it is predicted through the
homography fitted to those markers' corners, then refined by gradient orthogonality
(:func:`imageform.geometry.refine_corners`, OpenCV's ``cornerSubPix``) in a window that
stays clear of the markers, and kept when it converged near the prediction. With
``method="symmetric"`` each kept corner is then moved to the centre of the board's point
symmetry around it (:func:`imageform.geometry.refine_corners_symmetric`, Schöps et al. 2020)
in a round window of up to 0.8 of a square, every sample pair ``(q + d, q - d)`` with a point
on a marker (its whole square of cells, through the corner's homography, plus a 1 px guard
band) left out: what is left (the black squares, the white margins) is point-symmetric about
the corner. A corner whose symmetric refinement fails keeps its gradient position.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imageform._typing import ArrayLike
from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError
from imageform.geometry.aruco import (
    ArucoMarkers,
    _bilinear,
    _detect,
    _gray01,
    _grey_source,
    aruco_dictionary,
    aruco_marker_image,
)

__all__ = ["CharucoBoard", "CharucoCorners", "detect_charuco"]

#: Seen-whole check of a corner's four squares (:func:`_seen_whole`): samples per side of the
#: grid in each black square's interior and in each white square, and along each white margin.
_GRID_BLACK, _GRID_WHITE, _N_STRIP = 6, 12, 7
#: A black square's samples may not rise above its median by more than this share of the
#: board's contrast; a white margin's may not fall below the black level plus this share.
_BLACK_SPREAD, _WHITE_FLOOR = 0.3, 0.3
#: Smallest contrast of the white margins next to the corner, as a share of the contrast the
#: white squares' means give (1 when sharp): below it blur has merged the margins with the
#: markers' borders and the saddle is not resolved.
_MIN_RESOLVED = 0.6
#: Largest relative difference between the contrasts the two white squares give, each as a
#: share of its own white margins' contrast.
_WHITE_AGREE = 0.35
#: Below this resolved share (see ``_MIN_RESOLVED``) a corner is refined again through a
#: window a pixel larger, and refused when the two points are farther apart than
#: ``_MAX_WINDOW_SHIFT`` pixels.
_SHARP, _MAX_WINDOW_SHIFT = 0.9, 0.25
#: Smallest contrast (image in [0, 1]) between the black squares and the white margins.
_MIN_CONTRAST = 0.04
#: The symmetric refinement (``method="symmetric"``): its round window's radius as a share of
#: the local square size in pixels (at most ``_SYM_MAX_WINDOW`` px), the guard band around
#: each marker (px) and the marker cells left in (0: the whole marker masked; 1: its black
#: border kept, only the bits masked), and the farthest it may move a corner from the
#: gradient refinement's position (px) before that position is kept.
_SYM_WINDOW, _SYM_MAX_WINDOW, _SYM_GUARD_PX, _SYM_INSET = 0.8, 40, 1.0, 0
_SYM_MAX_MOVE = 1.0
#: Whether the symmetric refinement masks the markers (False: a check's variant only).
_SYM_MASKED = True
#: The guard band is at least this share of the white margin between a marker and its square's
#: edge: blur spreads a marker's border into the margin, and a marker printed a fraction of a
#: pixel off its square's centre makes that spread differ between the two white squares.
_SYM_GUARD_MARGIN = 0.5


@dataclass(frozen=True)
class CharucoBoard:
    """A ChArUco board of ``squares = (cols, rows)`` squares with markers from ``dictionary``.

    The squares have side ``square_length``, the markers side ``marker_length`` (OpenCV's
    ``CharucoBoard((cols, rows), square_length, marker_length, dictionary)``). ``legacy``:
    OpenCV's layout before 4.6 (``setLegacyPattern(true)``), which differs on boards with an
    even number of rows: their top-left square is white and holds marker 0.
    ``first_marker``: the dictionary id of the board's first marker, the others following
    (OpenCV's ``ids=np.arange(first, first + n_markers)``), for rigs of several boards from
    one dictionary; board marker ``k`` is dictionary marker ``first_marker + k``.

    Lengths are in the unit the calibration should use (mm, m, ...).

    Raises
    ------
    InvalidInputError
        Fewer than 2 squares along a side, a marker not smaller than its square, or more
        white squares (after ``first_marker``) than the dictionary has markers.

    Examples
    --------
    >>> board = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
    >>> board.n_markers, board.n_corners
    (17, 24)
    >>> board.corner_points()[:2].tolist()
    [[30.0, 30.0, 0.0], [60.0, 30.0, 0.0]]
    """

    squares: tuple[int, int]
    square_length: float
    marker_length: float
    dictionary: str = "6x6_250"
    legacy: bool = False
    first_marker: int = 0

    def __post_init__(self) -> None:
        """Check the squares, lengths (markers smaller than squares) and the dictionary."""
        sq = self.squares
        if not isinstance(sq, tuple | list) or len(sq) != 2:
            raise InvalidInputError(f"expected squares as (cols, rows), got {describe(sq)}")
        cols = as_int(sq[0], "squares (cols)", minimum=2, maximum=1000)
        rows = as_int(sq[1], "squares (rows)", minimum=2, maximum=1000)
        object.__setattr__(self, "squares", (cols, rows))
        s = as_real(self.square_length, "square_length", positive=True, maximum=1e12)
        m = as_real(self.marker_length, "marker_length", positive=True, maximum=1e12)
        if not m < s:
            raise InvalidInputError(
                f"expected marker_length smaller than square_length {s:g}, got {m:g}"
            )
        object.__setattr__(self, "square_length", s)
        object.__setattr__(self, "marker_length", m)
        d = aruco_dictionary(self.dictionary)
        object.__setattr__(self, "dictionary", d.name)
        if not isinstance(self.legacy, bool | np.bool_):
            raise InvalidInputError(
                f"expected legacy as True or False, got {describe(self.legacy)}"
            )
        object.__setattr__(self, "legacy", bool(self.legacy))
        first = as_int(self.first_marker, "first_marker", minimum=0, maximum=d.size - 1)
        object.__setattr__(self, "first_marker", first)
        if first + self.n_markers > d.size:
            start = f" from marker {first}" if first else ""
            raise InvalidInputError(
                f"a {cols} x {rows} board needs {self.n_markers} markers{start}; dictionary "
                f"{d.name} has {d.size}"
            )

    @property
    def n_markers(self) -> int:
        """How many markers (white squares) the board has."""
        cols, rows = self.squares
        return (cols * rows) // 2

    @property
    def n_corners(self) -> int:
        """How many inner (checkerboard) corners the board has."""
        cols, rows = self.squares
        return (cols - 1) * (rows - 1)

    @property
    def white_parity(self) -> int:
        """``(r + c) % 2`` of the white squares: 1, or 0 for a legacy board of even rows."""
        return 0 if self.legacy and self.squares[1] % 2 == 0 else 1

    def marker_squares(self) -> NDArray[np.int64]:
        """``(n_markers, 2)``: the ``(row, col)`` of each marker's square, by board marker.

        Board marker ``k`` is dictionary marker ``first_marker + k``.
        """
        cols, rows = self.squares
        r, c = np.divmod(np.arange(cols * rows), cols)
        white = (r + c) % 2 == self.white_parity
        return np.column_stack([r[white], c[white]]).astype(np.int64)

    def corner_points(self) -> NDArray[np.float64]:
        """``(n_corners, 3)``: the inner corners on the board, by corner id."""
        cols, rows = self.squares
        r, c = np.divmod(np.arange((cols - 1) * (rows - 1)), cols - 1)
        s = self.square_length
        return np.column_stack([(c + 1) * s, (r + 1) * s, np.zeros(r.shape)])

    def marker_points(self) -> NDArray[np.float64]:
        """``(n_markers, 4, 3)``: each marker's corners on the board, by board marker.

        The corners are top-left, top-right, bottom-right, bottom-left as printed.
        """
        sq = self.marker_squares()
        s, m = self.square_length, self.marker_length
        x0 = sq[:, 1] * s + (s - m) / 2
        y0 = sq[:, 0] * s + (s - m) / 2
        dx = np.array([0.0, m, m, 0.0])
        dy = np.array([0.0, 0.0, m, m])
        return np.stack([x0[:, None] + dx, y0[:, None] + dy, np.zeros((len(sq), 4))], axis=-1)

    def image(self, square_px: int = 100, *, margin_px: int = 0) -> NDArray[np.uint8]:
        """Draw the printable board (uint8, 0 black, 255 white), ``square_px`` pixels per square.

        Equal to OpenCV's ``CharucoBoard.generateImage`` at the same size when the marker's
        side in pixels, ``round(square_px * marker_length / square_length)``, is a multiple of
        its cells (tested); otherwise the marker cells are resized to the nearest pixel.

        Parameters
        ----------
        square_px : int
            Side of a square in pixels.
        margin_px : int, keyword-only
            White margin around the board.

        Returns
        -------
        ndarray, shape (rows * square_px + 2 margin_px, cols * square_px + 2 margin_px)
        """
        cols, rows = self.squares
        sp = as_int(square_px, "square_px", minimum=4, maximum=10000)
        margin = as_int(margin_px, "margin_px", minimum=0, maximum=10000)
        h, w = rows * sp + 2 * margin, cols * sp + 2 * margin
        if h * w > 400_000_000:
            raise InvalidInputError(f"a board image of {w} x {h} pixels is too large")
        out = np.full((h, w), 255, dtype=np.uint8)
        mp = round(sp * self.marker_length / self.square_length)
        d = aruco_dictionary(self.dictionary)
        if mp < d.marker_size + 2:
            raise InvalidInputError(
                f"square_px {sp} leaves {mp} pixels per marker, fewer than its "
                f"{d.marker_size + 2} cells"
            )
        off = (sp - mp) // 2
        whites = {tuple(rc) for rc in self.marker_squares().tolist()}
        mid = 0
        for r in range(rows):
            for c in range(cols):
                y, x = margin + r * sp, margin + c * sp
                if (r, c) in whites:
                    out[y + off : y + off + mp, x + off : x + off + mp] = aruco_marker_image(
                        self.first_marker + mid, d, size_px=mp
                    )
                    mid += 1
                else:
                    out[y : y + sp, x : x + sp] = 0
        return out


@dataclass(frozen=True)
class CharucoCorners:
    """Inner corners of a ChArUco board found in an image.

    ``ids`` (m,) int64: corner ids (row by row, see :class:`CharucoBoard`); ``corners``
    (m, 2) float64: their pixels; ``markers``: the decoded markers; ``board``.
    """

    ids: NDArray[np.int64]
    corners: NDArray[np.float64]
    markers: ArucoMarkers
    board: CharucoBoard

    def __len__(self) -> int:
        """How many corners were found."""
        return int(self.ids.shape[0])

    def object_points(self) -> NDArray[np.float64]:
        """``(m, 3)``: the found corners on the board (for :func:`calibrate_camera`)."""
        return np.asarray(self.board.corner_points()[self.ids])


def detect_charuco(
    image: ArrayLike,
    board: CharucoBoard,
    *,
    markers: ArucoMarkers | None = None,
    min_markers: int = 2,
    max_shift: float = 0.15,
    method: Literal["symmetric", "gradient"] = "symmetric",
) -> CharucoCorners:
    """Find the inner corners of ``board`` in ``image``, each with its id.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Grey or RGB image (uint8, uint16 or floats).
    board : CharucoBoard
        The board photographed.
    markers : ArucoMarkers, optional, keyword-only
        Markers already detected in ``image`` (by :func:`detect_aruco_markers`).
    min_markers : int, keyword-only
        Decoded markers needed among the squares around a corner (the 4 squares touching it
        and the 12 beyond them) before it is predicted; OpenCV's ``minMarkers`` (2).
    max_shift : float, keyword-only
        Largest distance, as a fraction of the local square size in pixels, between the
        predicted corner and the refined one; farther corners are dropped.
    method : {"gradient", "symmetric"}, keyword-only
        The sub-pixel refinement (:func:`find_checkerboard`'s words): ``"gradient"``, gradient
        orthogonality in a window clear of the markers (OpenCV's ``cornerSubPix``), or
        ``"symmetric"``, then the centre of the board's point symmetry with the markers left
        out of it (see the module). Both find the same corners; only their positions differ.

    Returns
    -------
    CharucoCorners
        Sorted by id; empty when no corner qualifies. On a board of an even number of rows,
        whose two layouts differ (see :class:`CharucoBoard`), both are tried and the one giving
        more corners is kept (the board's own on a tie); its ``board`` says which.

    Raises
    ------
    InvalidInputError
        ``board`` is not a :class:`CharucoBoard`, ``image`` is not an image, or ``method`` is
        not one of the two.

    Examples
    --------
    >>> board = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
    >>> found = detect_charuco(board.image(60, margin_px=30), board)
    >>> len(found), found.corners[0].round(1).tolist()
    (24, [89.5, 89.5])
    """
    if not isinstance(board, CharucoBoard):
        raise InvalidInputError(f"expected board as a CharucoBoard, got {describe(board)}")
    image = _grey_source(image)  # a colour frame read on its grey uint8, once
    g = _gray01(image, scratch=True)
    need = as_int(min_markers, "min_markers", minimum=1, maximum=16)
    shift = as_real(max_shift, "max_shift", positive=True, maximum=1.0)
    if method not in ("symmetric", "gradient"):
        raise InvalidInputError(
            f"expected method 'symmetric' or 'gradient', got {describe(method)}"
        )
    sym = method == "symmetric"
    if markers is None:
        markers = _detect(g, board.dictionary, source=image)
    elif not isinstance(markers, ArucoMarkers):
        raise InvalidInputError(f"expected markers as ArucoMarkers, got {describe(markers)}")
    found = _corners(g, board, markers, need, shift, sym)
    if board.squares[1] % 2 == 0 and len(markers) >= need:
        # OpenCV before 4.6 put the markers of such a board in the other squares: markers
        # read in the wrong layout give few corners (their squares' colours are swapped)
        other = _corners(g, replace(board, legacy=not board.legacy), markers, need, shift, sym)
        if len(other) > len(found):
            return other
    return found


def _detect_reduced(
    image: NDArray[np.uint8], board: CharucoBoard, f: int, method: str = "gradient"
) -> CharucoCorners:
    """:func:`detect_charuco` of a uint8 grey ``image`` with its markers read ``f`` times smaller.

    The markers are found in ``image`` reduced ``f`` times (block means,
    :func:`imageform._kernels.aruco.block_means_u8`: ``f²`` times fewer pixels to threshold
    and label) and their corners scaled back (the reduced pixel ``i`` covers the full pixels
    ``f i .. f i + f - 1``: ``x = f x' + (f - 1) / 2``); the corners are then predicted from
    them and refined, checked and kept at full resolution as :func:`detect_charuco` does, in
    the markers' box grown by three squares (the rest of the frame is not converted to
    floats). The markers' corners only seed the corners' prediction, which the full-resolution
    refinement corrects (it starts within a pixel or two of the saddle). For the frames of a
    4K camera, whose markers stay tens of pixels wide when halved (:class:`BoardTracker`);
    markers smaller than ``f`` times the detector's 6 px are not found.
    """
    from imageform._kernels.aruco import block_means_u8

    small = np.asarray(block_means_u8(np.ascontiguousarray(image), int(f)))
    markers = _detect(_gray01(small, scratch=True), board.dictionary, source=small)
    hgt, wid = image.shape
    empty = CharucoCorners(np.zeros(0, np.int64), np.zeros((0, 2)), markers, board)
    if len(markers) == 0:
        return empty
    full = ArucoMarkers(
        markers.ids, markers.corners * f + (f - 1) / 2.0, markers.hamming, markers.dictionary
    )
    # the markers' box, grown by three squares (a corner is predicted from markers within two
    # squares of it, and its seen-whole check looks one square beyond)
    side = float(np.max(np.hypot(*(np.roll(full.corners, -1, axis=1) - full.corners).T)))
    grow = 3.0 * side * board.square_length / board.marker_length
    lo = np.floor(full.corners.reshape(-1, 2).min(axis=0) - grow).astype(int)
    hi = np.ceil(full.corners.reshape(-1, 2).max(axis=0) + grow).astype(int)
    x0, y0 = max(int(lo[0]), 0), max(int(lo[1]), 0)
    x1, y1 = min(int(hi[0]) + 1, wid), min(int(hi[1]) + 1, hgt)
    if x1 - x0 < 16 or y1 - y0 < 16:
        return empty
    offset = np.array([x0, y0], np.float64)
    crop = ArucoMarkers(full.ids, full.corners - offset, full.hamming, full.dictionary)
    found = detect_charuco(image[y0:y1, x0:x1], board, markers=crop, method=method)  # type: ignore[arg-type]
    return CharucoCorners(found.ids, found.corners + offset, full, found.board)


def _corners(
    g: NDArray[np.float64],
    board: CharucoBoard,
    markers: ArucoMarkers,
    need: int,
    shift: float,
    sym: bool = False,
) -> CharucoCorners:
    """Find the corners of ``board`` (in its layout) from the ``markers`` found in ``g``.

    ``sym``: move the corners found to their centres of symmetry (:func:`_symmetric`).
    """
    from imageform.geometry.checkerboard_subpix import RefinedCorners, refine

    ids_m = markers.ids - board.first_marker  # the board's own marker numbers
    keep = (ids_m >= 0) & (ids_m < board.n_markers)
    ids_m, corners_m = ids_m[keep], markers.corners[keep]
    empty = CharucoCorners(np.zeros(0, np.int64), np.zeros((0, 2)), markers, board)
    if len(ids_m) == 0:
        return empty
    cand, homs, xy, hws, scales = _predicted(board, ids_m, corners_m, need, g.shape)
    if len(cand) == 0:
        return empty
    ok = np.zeros(len(cand), dtype=bool)
    found = np.zeros_like(xy)
    for hw in np.unique(hws):
        sel = np.nonzero(hws == hw)[0]
        # refine_corners without re-checking g (grey, finite, in [0, 1] already)
        ref = RefinedCorners(*refine(g, np.ascontiguousarray(xy[sel]), int(hw), int(hw), 40, 1e-4))
        moved = np.hypot(*(ref.corners - xy[sel]).T)
        ok[sel] = ((ref.status == 0) | (ref.status == 1)) & (moved <= shift * scales[sel])
        ok[sel] &= moved < hw
        found[sel] = ref.corners
    ks = np.nonzero(ok)[0]
    if len(ks) == 0:
        return empty
    found = found[ks]
    whole, resolved = _seen_whole(g, board, cand[ks], homs[ks], found)
    # a blurred saddle must give the same point through a window a pixel larger: where the
    # blur lets the markers' borders into the window the point depends on the window
    blurred = np.nonzero(whole & (resolved < _SHARP))[0]
    for hw in np.unique(hws[ks[blurred]]):
        sel = blurred[hws[ks[blurred]] == hw]
        alt = RefinedCorners(
            *refine(g, np.ascontiguousarray(found[sel]), int(hw) + 1, int(hw) + 1, 40, 1e-4)
        )
        whole[sel] &= np.hypot(*(alt.corners - found[sel]).T) <= _MAX_WINDOW_SHIFT
    if not whole.any():
        return empty
    kept = ks[whole]
    xy_out = found[whole]
    if sym:
        xy_out = _symmetric(g, board, cand[kept], homs[kept], xy[kept], scales[kept], xy_out)
    # the candidates are in id order already
    return CharucoCorners(cand[kept], xy_out, markers, board)


def _symmetric(
    g: NDArray[np.float64],
    board: CharucoBoard,
    ids: NDArray[np.int64],
    homs: NDArray[np.float64],
    pred: NDArray[np.float64],
    scales: NDArray[np.float64],
    start: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Move corners ``start`` to their centres of point symmetry, the markers left out.

    Each corner's window (radius ``_SYM_WINDOW`` of its square size ``scales``) is masked as
    :func:`_marker_mask` says through its homography ``homs`` (board square units to pixels,
    the corner at ``pred``), the offsets that reach past the image's border (a pixel inside
    it, from ``start``) left out too; a corner whose refinement does not converge, or moves
    more than ``_SYM_MAX_MOVE`` px from ``start``, keeps ``start``. One kernel call refines
    every corner, making each one's mask as it goes (``charuco_symmetric_numba``).
    """
    from imageform._backend import use_numba
    from imageform._kernels.checkerboard_symmetric import (
        charuco_symmetric_numba,
        charuco_symmetric_numpy,
    )

    hs = np.clip(np.floor(_SYM_WINDOW * scales), 3, _SYM_MAX_WINDOW).astype(np.int64)
    pts = np.ascontiguousarray(start)
    if _SYM_MASKED:
        lo, guard = _marker_box(board, scales)
        hinv = np.asarray(np.linalg.inv(homs), dtype=np.float64)  # pixels to board squares
        kernel = charuco_symmetric_numba if use_numba(g) else charuco_symmetric_numpy
        cols, rows = board.squares
        args = (pred, hinv, lo, guard, hs, cols, rows, board.white_parity, 30, 1e-3)
        ref, status = kernel(g, pts, *args)
    else:  # the markers left in (a check's variant): the plain symmetric refinement
        from imageform.geometry.checkerboard_subpix import refine_symmetric

        ref, status = np.empty_like(pts), np.empty(len(pts), dtype=np.int64)
        for h in np.unique(hs):
            sel = np.nonzero(hs == h)[0]
            ref[sel], status[sel] = refine_symmetric(g, pts[sel], int(h), 30, 1e-3)
    good = (status <= 1) & (np.hypot(*(ref - pts).T) <= _SYM_MAX_MOVE)
    return np.where(good[:, None], ref, start)


def _marker_box(
    board: CharucoBoard, scales: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the grown marker's box ``[lo, 1 - lo]²`` in its square and the guard band.

    Both in square units, per corner of local square size ``scales`` (px): the marker's inset
    (``_SYM_INSET`` cells in) less the guard band, ``_SYM_GUARD_PX`` pixels and at least
    ``_SYM_GUARD_MARGIN`` of the white margin.
    """
    frac = board.marker_length / board.square_length
    cell = frac / (aruco_dictionary(board.dictionary).marker_size + 2)
    guard = np.maximum(
        _SYM_GUARD_PX / np.maximum(scales, 1e-9), _SYM_GUARD_MARGIN * (1.0 - frac) / 2.0
    )
    return (1.0 - frac) / 2.0 + _SYM_INSET * cell - guard, guard


def _marker_mask(
    board: CharucoBoard,
    homs: NDArray[np.float64],
    pred: NDArray[np.float64],
    scales: NDArray[np.float64],
    start: NDArray[np.float64],
    h: int,
    shape: tuple[int, int],
) -> NDArray[np.bool_]:
    """Return which offsets ``d`` of each corner's ``(2h+1)²`` window are off every marker.

    ``pred + d`` is taken back to the board through the corner's homography (square units);
    it is masked off when on a marker (inset ``_SYM_INSET`` cells) grown by the guard band
    (``_SYM_GUARD_PX`` pixels, ``_SYM_GUARD_PX / scales`` squares, and at least
    ``_SYM_GUARD_MARGIN`` of the white margin), or off the board; and when ``start + d`` is
    not inside the image. The markers' part is a function of ``d`` alone (the homography
    moved to the corner), so the refinement's cost is smooth. (:func:`_symmetric` makes the
    same mask inside its kernel.)
    """
    from imageform._backend import use_numba
    from imageform._kernels.checkerboard_symmetric import marker_mask_numba, marker_mask_numpy

    cols, rows = board.squares
    lo, guard = _marker_box(board, scales)
    hinv = np.ascontiguousarray(np.linalg.inv(homs))  # pixels to board squares
    kernel = marker_mask_numba if use_numba(start) else marker_mask_numpy
    args = (np.ascontiguousarray(pred), np.ascontiguousarray(start), lo, guard)
    return np.asarray(kernel(hinv, *args, h, cols, rows, board.white_parity, shape))


def _predicted(
    board: CharucoBoard,
    ids_m: NDArray[np.int64],
    corners_m: NDArray[np.float64],
    need: int,
    shape: tuple[int, int],
) -> tuple[
    NDArray[np.int64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.float64],
]:
    """Predict the corners from the markers (board markers ``ids_m``, found at ``corners_m``).

    Each inner corner ``(r, c)`` with at least ``need`` markers in the 4 x 4 squares around it
    (rows ``r - 1 .. r + 2``, columns ``c - 1 .. c + 2``), one of them in the 2 x 2 squares
    touching it, is mapped through the homography fitted to those markers' corners (DLT,
    board in square units, all corners at once: one SVD of the stacked systems, a missing
    marker's rows left zero, which changes no singular vector) and kept when at least 2 px
    inside the image. Returns the corner ids (in order), the homographies (m, 3, 3), the
    predicted pixels (m, 2), the refinement half-windows and the local scales (pixels per
    square: twice the shorter of the half-square steps along x and y from the corner).
    """
    cols, rows = board.squares
    h_img, w_img = shape
    s = board.square_length
    squares = board.marker_squares()
    # the found markers on a grid of squares with a frame of one square (-1: none)
    at = np.full((rows + 2, cols + 2), -1, dtype=np.int64)
    at[squares[ids_m, 0] + 1, squares[ids_m, 1] + 1] = np.arange(len(ids_m))
    r, c = np.divmod(np.arange((cols - 1) * (rows - 1)), cols - 1)
    d4 = np.arange(-1, 3)
    near = at[r[:, None, None] + d4[None, :, None] + 1, c[:, None, None] + d4[None, None, :] + 1]
    near = near.reshape(len(r), 16)  # row by row, as the squares around the corner
    adjacent = near[:, [5, 6, 9, 10]]
    keep = ((near >= 0).sum(1) >= need) & (adjacent >= 0).any(1)
    cand = np.nonzero(keep)[0]
    if len(cand) == 0:
        z = np.zeros(0)
        return cand, np.zeros((0, 3, 3)), np.zeros((0, 2)), z.astype(np.int64), z
    near, adjacent = near[cand], adjacent[cand]
    # at most 8 of the 16 squares hold markers: compact them (in order) into 8 slots
    slot = np.argsort(near < 0, axis=1, kind="stable")[:, :8]
    idx = np.take_along_axis(near, slot, 1)  # (m, 8), -1 past the corner's markers
    there = idx >= 0
    mpts = board.marker_points()[:, :, :2] / s
    src = np.where(there[..., None, None], mpts[ids_m[idx]], 0.0).reshape(len(cand), 32, 2)
    dst = np.where(there[..., None, None], corners_m[idx], 0.0).reshape(len(cand), 32, 2)
    live = np.repeat(there, 4, axis=1).astype(np.float64)
    x, y = src[..., 0], src[..., 1]
    u, v = -dst[..., 0], -dst[..., 1]
    one, zero = live, np.zeros_like(x)
    # per point the rows (x y 1 0 0 0 -ux -uy -u) and (0 0 0 x y 1 -vx -vy -v), zero for a
    # missing marker
    ra = np.stack((x, y, one, zero, zero, zero, u * x, u * y, u * live), -1)
    rb = np.stack((zero, zero, zero, x, y, one, v * x, v * y, v * live), -1)
    a = np.stack((ra, rb), 2).reshape(len(cand), 64, 9)
    _, _, vt = np.linalg.svd(a, full_matrices=False)
    homs = vt[:, -1].reshape(-1, 3, 3)
    h22 = homs[:, 2, 2]
    scale_h = np.where(np.abs(h22) > 1e-15, h22, 1.0)
    homs = homs / scale_h[:, None, None]
    rr, cc = r[cand], c[cand]

    def at_board(bx: NDArray[np.float64], by: NDArray[np.float64]) -> NDArray[np.float64]:
        w = homs[:, 2, 0] * bx + homs[:, 2, 1] * by + homs[:, 2, 2]
        return np.stack(
            (
                (homs[:, 0, 0] * bx + homs[:, 0, 1] * by + homs[:, 0, 2]) / w,
                (homs[:, 1, 0] * bx + homs[:, 1, 1] * by + homs[:, 1, 2]) / w,
            ),
            -1,
        )

    with np.errstate(divide="ignore", invalid="ignore"):
        p = at_board(cc + 1.0, rr + 1.0)
        inside = (
            np.isfinite(p).all(1)
            & (p[:, 0] >= 2)
            & (p[:, 0] <= w_img - 3)
            & (p[:, 1] >= 2)
            & (p[:, 1] <= h_img - 3)
        )
        # local scale: pixels per square, and the distance to the nearest marker corner
        qx, qy = at_board(cc + 1.5, rr + 1.0), at_board(cc + 1.0, rr + 1.5)
    scale = 2.0 * np.minimum(np.hypot(*(qx - p).T), np.hypot(*(qy - p).T))
    adj = np.where((adjacent >= 0)[..., None, None], corners_m[adjacent], np.inf)
    with np.errstate(invalid="ignore"):
        d_marker = np.hypot(*(adj - p[:, None, None, :]).transpose(3, 0, 1, 2)).min((1, 2))
    # the window stays clear of the markers' corners (0.6 d keeps a marker corner at
    # distance d, on the diagonal, outside the square window)
    with np.errstate(invalid="ignore"):
        hw = np.maximum(
            2,
            np.minimum(
                np.minimum(np.floor(0.6 * d_marker), np.floor(0.3 * np.nan_to_num(scale))), 25
            ),
        )
    k = np.nonzero(inside)[0]
    return cand[k], homs[k], p[k], hw[k].astype(np.int64), scale[k]


def _printed(board: CharucoBoard, xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """Sample the printed board at board points ``xy`` (..., 2), square units: 1 white, 0 black."""
    cols, rows = board.squares
    d = aruco_dictionary(board.dictionary)
    n = d.marker_size + 2
    col = np.clip(np.floor(xy[..., 0]).astype(np.int64), 0, cols - 1)
    row = np.clip(np.floor(xy[..., 1]).astype(np.int64), 0, rows - 1)
    white = (row + col) % 2 == board.white_parity
    out = white.astype(np.float64)
    at = np.zeros((rows, cols), dtype=np.int64)
    sq = board.marker_squares()
    at[sq[:, 0], sq[:, 1]] = np.arange(len(sq))
    mid = at[row, col]
    frac = board.marker_length / board.square_length
    off = (1.0 - frac) / 2.0
    cu = np.floor((xy[..., 0] - col - off) / frac * n).astype(np.int64)
    cv = np.floor((xy[..., 1] - row - off) / frac * n).astype(np.int64)
    inside = white & (cu >= 0) & (cu < n) & (cv >= 0) & (cv < n)
    bits = (cu >= 1) & (cu <= n - 2) & (cv >= 1) & (cv <= n - 2)
    code = d.codes[
        np.clip(mid + board.first_marker, 0, d.size - 1),
        np.clip(cv - 1, 0, n - 3),
        np.clip(cu - 1, 0, n - 3),
    ]
    out[inside] = np.where(bits[inside], code[inside], 0).astype(np.float64)
    return out


@lru_cache(maxsize=32)
def _printed_white(board: CharucoBoard) -> NDArray[np.float64]:
    """Return the printed board (1 white, 0 black) at each corner's white squares' grid.

    ``(n_corners, 2 P)``, by corner id: :func:`_seen_whole`'s ``(qw, gw)`` points.
    """
    cols, rows = board.squares
    ids = np.arange((cols - 1) * (rows - 1))
    r, c = np.divmod(ids, cols - 1)
    corner = np.column_stack([c + 1.0, r + 1.0])
    tw = (np.arange(_GRID_WHITE) + 0.5) / _GRID_WHITE
    gw = np.stack(np.meshgrid(tw, tw), -1).reshape(-1, 2)
    quads = np.array([[-1.0, -1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, 1.0]])
    first = ((r + c) % 2 != board.white_parity)[:, None, None]
    qw = np.where(first, quads[None, 2:], quads[None, :2])
    pts = (corner[:, None, None, :] + qw[:, :, None, :] * gw[None, None]).reshape(len(ids), -1, 2)
    out = _printed(board, pts)
    out.setflags(write=False)
    return out


def _masked_median(v: NDArray[np.float64], ok: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Median of each row of ``v`` (m, P) over its ``ok`` entries (0 for a row without any)."""
    srt = np.sort(np.where(ok, v, np.inf), axis=1)
    n = ok.sum(1)
    lo = np.take_along_axis(srt, np.maximum((n - 1) // 2, 0)[:, None], 1)[:, 0]
    hi = np.take_along_axis(srt, np.maximum(n // 2, 0)[:, None], 1)[:, 0]
    return np.where(n > 0, 0.5 * (lo + hi), 0.0)


def _seen_whole(
    g: NDArray[np.float64],
    board: CharucoBoard,
    ids: NDArray[np.int64],
    homs: NDArray[np.float64],
    xy: NDArray[np.float64],
) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Which refined corners have their four squares seen whole, with a resolved saddle.

    Each corner's squares are sampled through its local homography (board squares to
    pixels, moved to the refined corner): a grid inside each black square (away from its
    edges), a dense grid over each white square, and the white margin along each of the
    four edges that meet at the corner. The dense grids' mean against the printed white
    share of the same points (the markers' bits are known) gives the contrast ``C`` between
    black and white whatever the blur, since blur keeps a square's mean. The corner is kept
    when the black samples are uniform (none above their median by ``_BLACK_SPREAD C``),
    no white-margin sample falls below the black level plus ``_WHITE_FLOOR C``, the two white
    squares give the same ``C`` as a share of their own margins' contrast (within
    ``_WHITE_AGREE``: light falling off across the board changes both), and the margins next to the
    corner keep ``_MIN_RESOLVED`` of ``C`` (a blur that merges them with the markers' black
    borders leaves no saddle to refine). An occluder over part of the squares breaks one of
    these; samples outside the image are left out (a corner by the image border is judged
    on what is in the image).
    """
    m = len(ids)
    cols = board.squares[0]
    r, c = np.divmod(ids, cols - 1)
    corner = np.column_stack([c + 1.0, r + 1.0])  # board, square units
    frac = board.marker_length / board.square_length
    margin = (1.0 - frac) / 2.0
    # quadrant directions; the top-left square (r, c) is black when r + c is even (odd on a
    # legacy board of even rows)
    quads = np.array([[-1.0, -1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, 1.0]])
    tb = (np.arange(_GRID_BLACK) + 0.5) / _GRID_BLACK * 0.6 + 0.2
    tw = (np.arange(_GRID_WHITE) + 0.5) / _GRID_WHITE
    ts = (np.arange(_N_STRIP) + 0.5) / _N_STRIP
    gb = np.stack(np.meshgrid(tb, tb), -1).reshape(-1, 2)
    gw = np.stack(np.meshgrid(tw, tw), -1).reshape(-1, 2)
    # white margin along the two corner edges of a white square (u along x, v along y)
    strip = np.concatenate(
        [
            np.column_stack([ts, np.full_like(ts, margin / 2)]),
            np.column_stack([np.full_like(ts, margin / 2), ts]),
        ]
    )
    near = ts < 0.5  # the half of each margin nearer the corner

    # per corner: the black and the white quadrants' directions (m, 2, 2)
    first = ((r + c) % 2 != board.white_parity)[:, None, None]
    qb = np.where(first, quads[None, :2], quads[None, 2:])
    qw = np.where(first, quads[None, 2:], quads[None, :2])

    def points(dirs: NDArray[np.float64], grid: NDArray[np.float64]) -> NDArray[np.float64]:
        """Board points (m, 2 P, 2): ``grid`` (P, 2) in the two quadrants ``dirs``."""
        pts = corner[:, None, None, :] + dirs[:, :, None, :] * grid[None, None]
        return pts.reshape(m, -1, 2)

    # the black squares whole (qb, gw), for the block's mean
    # homographies moved so that the corner lands on the refined pixel
    pc = np.einsum("mij,mj->mi", homs, np.column_stack([corner, np.ones(m)]))
    shift = np.zeros_like(homs)
    shift[:, 0, 0] = shift[:, 1, 1] = shift[:, 2, 2] = 1.0
    shift[:, :2, 2] = xy - pc[:, :2] / pc[:, 2:]
    hs = shift @ homs
    h_img, w_img = g.shape

    from imageform._backend import use_numba

    if use_numba(g):
        from imageform._kernels.aruco import sample_quadrants

        def sampled(
            dirs: NDArray[np.float64], grid: NDArray[np.float64]
        ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
            return sample_quadrants(g, hs, corner, np.ascontiguousarray(dirs), grid)

    else:

        def sampled(
            dirs: NDArray[np.float64], grid: NDArray[np.float64]
        ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
            return sample(points(dirs, grid))

    def sample(pts: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        q = np.concatenate([pts, np.ones((*pts.shape[:2], 1))], -1) @ np.swapaxes(hs, 1, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = q[..., :2] / q[..., 2:3]
        ok = (
            np.isfinite(uv).all(-1)
            & (uv[..., 0] >= 0)
            & (uv[..., 0] <= w_img - 1)
            & (uv[..., 1] >= 0)
            & (uv[..., 1] <= h_img - 1)
        )
        vals = _bilinear(g, np.where(ok[..., None], uv, 0.0).reshape(-1, 2)).reshape(ok.shape)
        return vals, ok

    vb, okb = sampled(qb, gb)
    vw, okw = sampled(qw, gw)
    vs, oks = sampled(qw, strip)
    nb = okb.sum(1)
    black = _masked_median(vb, okb)
    # each white square's contrast: (mean - black) / printed white share, same points
    okw2 = okw.reshape(m, 2, -1)
    n_in = okw2.sum(-1)
    printed_w = _printed_white(board)[ids]
    share = np.where(okw2, printed_w.reshape(m, 2, -1), 0.0).sum(-1) / np.maximum(n_in, 1)
    mean_w = np.where(okw2, vw.reshape(m, 2, -1), 0.0).sum(-1) / np.maximum(n_in, 1)
    usable = (n_in >= gw.shape[0] // 4) & (share > 0.05)
    with np.errstate(divide="ignore", invalid="ignore"):
        con = np.where(usable, (mean_w - black[:, None]) / share, np.nan)
    n_use = usable.sum(1)
    # the contrast from the whole 2 x 2 block: light that blur carries out of the white
    # squares' margins into the black squares stays in the block, and what crosses the
    # block's outline is on average as much in as out, so the block's mean against its
    # printed mean gives the contrast whatever the blur
    vf, okf = sampled(qb, gw)
    n_blk = okw.sum(1) + okf.sum(1)
    printed_blk = np.where(okw, printed_w, 0.0).sum(1) / np.maximum(n_blk, 1)
    mean_blk = (np.where(okw, vw, 0.0).sum(1) + np.where(okf, vf, 0.0).sum(1)) / np.maximum(
        n_blk, 1
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        cval = np.where((n_use > 0) & (printed_blk > 0.02), (mean_blk - black) / printed_blk, 0.0)
    # the two white squares' contrasts, each against its own white margins (light that
    # falls off across a large board, or a camera's exposure and tone curve, part the two
    # squares' contrasts but not their shares of their own margins' contrast); against the
    # block's contrast where a square's margins are not in the image
    own_vs, own_ok = vs.reshape(m, 2, -1), oks.reshape(m, 2, -1)
    margin_w = np.stack([_masked_median(own_vs[:, j], own_ok[:, j]) for j in range(2)], 1)
    lit = (own_ok.sum(-1) >= 3) & (margin_w - black[:, None] > _MIN_CONTRAST)
    with np.errstate(divide="ignore", invalid="ignore"):
        own = con / (margin_w - black[:, None])
        agree_own = np.abs(own[:, 0] - own[:, 1]) <= _WHITE_AGREE * 0.5 * (own[:, 0] + own[:, 1])
    agree_block = np.abs(con[:, 0] - con[:, 1]) <= _WHITE_AGREE * cval
    agree = (n_use < 2) | np.where(lit.all(1), agree_own, agree_block)
    b_max = np.where(okb, vb, -np.inf).max(1)
    s_min = np.where(oks, vs, np.inf).min(1)
    near_all = np.tile(near, 4)[None] & oks  # two margins per white square, two squares
    near_v = _masked_median(vs, near_all)
    with np.errstate(invalid="ignore", divide="ignore"):
        resolved = np.where(cval > 0, (near_v - black) / cval, 0.0)
        keep = np.asarray(
            (nb >= 4)
            & (oks.sum(1) >= 4)
            & (n_use > 0)
            & (cval >= _MIN_CONTRAST)
            & agree
            & (b_max <= black + _BLACK_SPREAD * cval)
            & (s_min >= black + _WHITE_FLOOR * cval)
            & (near_all.any(1))
            & (near_v - black >= _MIN_RESOLVED * cval)
        )
    return keep, resolved
