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

Corner detection (:func:`detect_charuco`): the markers are found and decoded
(:func:`imageform.geometry.detect_aruco_markers`); each inner corner with at least
``min_markers`` decoded markers in the squares around it is predicted through the
homography fitted to those markers' corners, then refined by gradient orthogonality
(:func:`imageform.geometry.refine_corners`, OpenCV's ``cornerSubPix``) in a window that
stays clear of the markers, and kept when it converged near the prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError
from imageform.geometry.aruco import (
    ArucoMarkers,
    _apply_h,
    _gray01,
    _homography,
    aruco_dictionary,
    aruco_marker_image,
    detect_aruco_markers,
)

__all__ = ["CharucoBoard", "CharucoCorners", "detect_charuco"]


@dataclass(frozen=True)
class CharucoBoard:
    """A ChArUco board of ``squares = (cols, rows)`` squares with markers from ``dictionary``.

    The squares have side ``square_length``, the markers side ``marker_length`` (OpenCV's
    ``CharucoBoard((cols, rows), square_length, marker_length, dictionary)``).

    Lengths are in the unit the calibration should use (mm, m, ...).

    Raises
    ------
    InvalidInputError
        Fewer than 2 squares along a side, a marker not smaller than its square, or more
        white squares than the dictionary has markers.

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
        if self.n_markers > d.size:
            raise InvalidInputError(
                f"a {cols} x {rows} board needs {self.n_markers} markers; dictionary "
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

    def marker_squares(self) -> NDArray[np.int64]:
        """``(n_markers, 2)``: the ``(row, col)`` of each marker's square, by marker id."""
        cols, rows = self.squares
        r, c = np.divmod(np.arange(cols * rows), cols)
        white = (r + c) % 2 == 1
        return np.column_stack([r[white], c[white]]).astype(np.int64)

    def corner_points(self) -> NDArray[np.float64]:
        """``(n_corners, 3)``: the inner corners on the board, by corner id."""
        cols, rows = self.squares
        r, c = np.divmod(np.arange((cols - 1) * (rows - 1)), cols - 1)
        s = self.square_length
        return np.column_stack([(c + 1) * s, (r + 1) * s, np.zeros(r.shape)])

    def marker_points(self) -> NDArray[np.float64]:
        """``(n_markers, 4, 3)``: each marker's corners on the board, by marker id.

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
                        mid, d, size_px=mp
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
    image: object,
    board: CharucoBoard,
    *,
    markers: ArucoMarkers | None = None,
    min_markers: int = 2,
    max_shift: float = 0.15,
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

    Returns
    -------
    CharucoCorners
        Sorted by id; empty when no corner qualifies.

    Raises
    ------
    InvalidInputError
        ``board`` is not a :class:`CharucoBoard`, or ``image`` is not an image.

    Examples
    --------
    >>> board = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
    >>> found = detect_charuco(board.image(60, margin_px=30), board)
    >>> len(found), found.corners[0].round(1).tolist()
    (24, [89.5, 89.5])
    """
    from imageform.geometry.checkerboard_subpix import RefinedCorners, refine

    if not isinstance(board, CharucoBoard):
        raise InvalidInputError(f"expected board as a CharucoBoard, got {describe(board)}")
    g = _gray01(image)
    need = as_int(min_markers, "min_markers", minimum=1, maximum=16)
    shift = as_real(max_shift, "max_shift", positive=True, maximum=1.0)
    if markers is None:
        markers = detect_aruco_markers(g, board.dictionary)
    elif not isinstance(markers, ArucoMarkers):
        raise InvalidInputError(f"expected markers as ArucoMarkers, got {describe(markers)}")
    keep = markers.ids < board.n_markers
    ids_m, corners_m = markers.ids[keep], markers.corners[keep]
    empty = CharucoCorners(np.zeros(0, np.int64), np.zeros((0, 2)), markers, board)
    if len(ids_m) == 0:
        return empty
    cols, rows = board.squares
    squares = board.marker_squares()
    mpts = board.marker_points()[:, :, :2]
    at_square = {(int(squares[i, 0]), int(squares[i, 1])): k for k, i in enumerate(ids_m)}
    s = board.square_length
    cand_ids, cand_xy, cand_hw, cand_scale = [], [], [], []
    h_img, w_img = g.shape
    for cid in range((cols - 1) * (rows - 1)):
        r, c = divmod(cid, cols - 1)
        # squares around corner (r, c): rows r-1 .. r+2, cols c-1 .. c+2
        near = [
            at_square[(rr, cc)]
            for rr in range(r - 1, r + 3)
            for cc in range(c - 1, c + 3)
            if (rr, cc) in at_square
        ]
        adjacent = [
            at_square[(rr, cc)] for rr in (r, r + 1) for cc in (c, c + 1) if (rr, cc) in at_square
        ]
        if len(near) < need or not adjacent:
            continue
        src = np.concatenate([mpts[ids_m[k]] for k in near])
        dst = np.concatenate([corners_m[k] for k in near])
        hom = _homography(src / s, dst)
        board_xy = np.array([[(c + 1.0), (r + 1.0)]])
        p = _apply_h(hom, board_xy)[0]
        if not (np.all(np.isfinite(p)) and 2 <= p[0] <= w_img - 3 and 2 <= p[1] <= h_img - 3):
            continue
        # local scale: pixels per square, and the distance to the nearest marker corner
        q = _apply_h(hom, board_xy + np.array([[0.5, 0.0], [0.0, 0.5]]))
        scale = 2.0 * float(min(np.hypot(*(q[0] - p)), np.hypot(*(q[1] - p))))
        d_marker = float(
            np.min(np.hypot(*(np.concatenate([corners_m[k] for k in adjacent]) - p).T))
        )
        # the window stays clear of the markers' corners (0.6 d keeps a marker corner at
        # distance d, on the diagonal, outside the square window)
        hw = max(2, min(int(0.6 * d_marker), int(0.3 * scale), 25))
        cand_ids.append(cid)
        cand_xy.append(p)
        cand_hw.append(hw)
        cand_scale.append(scale)
    if not cand_ids:
        return empty
    xy = np.asarray(cand_xy)
    hws = np.asarray(cand_hw)
    out_ids, out_xy = [], []
    for hw in np.unique(hws):
        sel = np.nonzero(hws == hw)[0]
        # refine_corners without re-checking g (grey, finite, in [0, 1] already)
        ref = RefinedCorners(*refine(g, np.ascontiguousarray(xy[sel]), int(hw), int(hw), 40, 1e-4))
        for j, k in enumerate(sel):
            moved = float(np.hypot(*(ref.corners[j] - xy[k])))
            if ref.status[j] in (0, 1) and moved <= shift * cand_scale[k] and moved < hw:
                out_ids.append(cand_ids[k])
                out_xy.append(ref.corners[j])
    if not out_ids:
        return empty
    order = np.argsort(out_ids)
    return CharucoCorners(
        np.asarray(out_ids, dtype=np.int64)[order],
        np.asarray(out_xy, dtype=np.float64)[order],
        markers,
        board,
    )
