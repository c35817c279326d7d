"""Checkerboard (chessboard) inner-corner detection with sub-pixel refinement.

:func:`find_checkerboard` finds the ``cols x rows`` inner corners of a checkerboard in one
image and returns them in OpenCV's order; :func:`refine_corners` is the sub-pixel step on
its own (the gradient-orthogonality least squares of OpenCV's ``cornerSubPix``), and
:func:`refine_corners_symmetric` the second, default one (each corner the centre of the
board's point symmetry; ``find_checkerboard(..., method="gradient")`` leaves it out).

Pipeline (helpers in ``checkerboard_candidates`` and ``checkerboard_grid``): saddle
response ``I_uv² - I_uu I_vv`` of the Gaussian-smoothed image → local maxima → ring test
(four alternating sectors, two edge directions) → neighbour graph along the edge directions
→ lattice labels → the largest complete rectangle → lattice and colour checks → order →
sub-pixel refinement (gradients, then point symmetry). A grid that is not exactly
``cols x rows`` or fails a check is reported as not found, with the reason; a wrong grid is
never returned.

Order convention (OpenCV's, verified on its 13 ``left*.jpg`` views)
-------------------------------------------------------------------
``pattern_size = (cols, rows)`` counts inner corners per row and per column; corners come
row by row, ``corners[r * cols + c]``. Which end of the board is "first" is ambiguous
geometrically (a rectangular grid has a 180° symmetry), so the rule is:

1. rows run along the side with ``cols`` corners;
2. the row direction ``x = corners[1] - corners[0]`` and the column direction
   ``y = corners[cols] - corners[0]`` turn clockwise on screen (image ``v`` down):
   ``x_u y_v - x_v y_u > 0`` (a board seen from its front);
3. when ``cols + rows`` is odd (e.g. 9 x 6) the board's colours break the 180° symmetry:
   the first cell (between corners ``0, 1, cols, cols + 1``) is the **dark** one. This is
   what OpenCV 5.0 returns on all 13 views (tested) — the first corner is *not* always the
   one nearest the image's top-left (on ``left02`` it is the bottom-left one);
4. when ``cols + rows`` is even the colours are symmetric too; then, as OpenCV does for
   even x even boards, the first row is the upper one (``corners[(rows-1)*cols]`` has a
   ``v`` not smaller than ``corners[0]``); for square patterns the first corner is the one
   with the smallest ``u + v`` among the four rotations.

When several complete boards of the asked size are visible, the largest (image area) is
returned.

``pattern_size="auto"`` (MATLAB's ``detectCheckerboardPoints`` gives the board's size too):
any complete lattice of at least 3 x 3 corners that passes the same checks is a board, the
board continuing past the lattice's edge included (so a lattice short of a board by a
missed corner is not taken for a smaller board), and its size is reported as ``(cols,
rows)`` with ``cols >= rows``. A board cut by the image's border shows a smaller complete
lattice: :func:`find_checkerboards` takes the size most views show.

``partial=True`` (MATLAB's ``PartialDetections``): when the whole board is not found, the
largest complete lattice of it (at least 3 x 3 and 12 corners, at most the board in either
orientation) that passes the same checks but the board's edge, less the rows and columns
with a corner near the image's border, refined off its saddle or in a window that is not
point-symmetric (an endoscope's dark surround), is returned with ``partial=True``, its own
``pattern_size`` (``cols >= rows``) and the order above for that size. Its labels are the
part's own: valid for intrinsic calibration (a shift, quarter turn or mirroring of the
labels is absorbed by the view's pose), not for stereo.
"""

from __future__ import annotations

import math
import warnings
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform import _deprecate
from imageform._backend import to_numpy
from imageform._validate import (
    as_bool,
    as_float_bounded,
    as_int,
    as_real,
    describe,
    format_shape,
    size_pair,
)
from imageform.errors import ImageformWarning, InvalidInputError
from imageform.geometry.checkerboard_candidates import Candidates, find_candidates
from imageform.geometry.checkerboard_grid import (
    _outer_x_share,
    board_continues,
    cell_means,
    cell_parity_ok,
    lattice_problem,
    lattice_rectangle,
    neighbors,
)
from imageform.geometry.checkerboard_subpix import (
    MAX_HALF_WINDOW,
    as_gray,
    gray_codes,
    gray_from_codes,
    refine_corners,
    refine_corners_symmetric,
    refine_local_inside,
    refine_symmetric_inside,
    refine_symmetric_pyramid,
    room_to_border,
)
from imageform.geometry.checkerboard_subpix import refine as refine_clean

__all__ = [
    "CheckerboardNotFoundWarning",
    "CheckerboardResult",
    "find_checkerboard",
    "find_checkerboards",
    "refine_corners",
    "refine_corners_symmetric",
    "set_pattern_size",
]

#: ``find_checkerboard``'s refinements: gradient orthogonality (``cornerSubPix``), then
#: point symmetry (the default) or not.
METHODS = ("symmetric", "gradient")
#: The point-symmetry window's radius, as a fraction of the shortest grid step (0.6-1.0 tried
#: on eleven real sets: benchmarks/results/corner-refinement-2026-11-29i.md).
SYMMETRIC_WINDOW = 0.8
#: A point-symmetric corner farther than this fraction of the shortest grid step from the
#: detected saddle is not taken (a square's centre is a centre of symmetry too: a start pulled
#: off by a wide gradient window, ``half_window=11`` on 20 px squares, can slide to it).
SYMMETRIC_REACH = 0.25
#: A corner is refined again through its grid map (``refine_local_inside``) where the map's
#: non-linear part reaches this many pixels on the window's rim, less this many pixels (a soft
#: threshold). 0 (every corner through its map) was nearest the truth on rendered wide-angle
#: views but fitted real sets' calibrations worse (held-out RMS up to 3.5 % higher); 1 px
#: kept them within 0.5 % (benchmarks/results/local-homography-2026-11-30a.md).
SYMMETRIC_MIN_BEND = 1.0
#: The window through a grid map keeps the offsets within this many squares of the corner on
#: the board (the affine window's radius, 0.8 of the shortest step, in squares).
SYMMETRIC_EXTENT = 0.8

#: A point-symmetry window of at least this radius (px; squares of 50 px and more) is refined
#: coarse to fine (``refine_symmetric_pyramid``): both steps on block means of
#: ``ceil(h / SYMMETRIC_COARSE_WINDOW)`` pixels a side, then one step at full resolution.
SYMMETRIC_COARSE_MIN = 40
SYMMETRIC_COARSE_WINDOW = 40

#: Smoothing scales (pixels) tried in turn until the board is found.
DEFAULT_SIGMAS = (2.0, 1.2, 3.5)
#: Seeds (strongest candidates) tried per scale.
MAX_SEEDS = 40
#: Longest side (pixels) of the averaged copy a large image is searched on too
#: (:func:`find_checkerboard`): above 2000 px always, up to 2000 px (a video frame) when the
#: board is not found at full resolution or some corner did not converge.
COARSE_SIZE = 1000
#: A board found neither at full resolution nor on that copy is sought again on copies
#: averaged over twice as many pixels a side at each step, while the copy's longest side keeps
#: at least this many pixels: blur wider than the largest smoothing scale (a hand-held board
#: moved while the frame was exposed: a smear of 20-40 px along the motion) merges the two
#: squares of one colour at each corner into a bar, and the ring test sees no four sectors
#: until the scale reaches past the smear (benchmarks/results/board-fresh-2026-11-30b.md).
BLUR_MIN_SIDE = 320
#: The coarser copies are searched only where the image is soft or shows a part of a board:
#: the mean absolute second difference of the grey image (every second pixel each way) under
#: this many times its mean absolute first difference (measured when the rule was set: 1.44-1.71
#: on Kodak's 24 photographs, 0.76-1.21 on rex-blur's 100 webcam frames of a hand-held board,
#: 0.20-0.40 on the rendered smeared boards of the tests; white noise 1.73), or a lattice of at
#: least :data:`AUTO_MIN_CORNERS` corners seen at full resolution: a sharp photograph without
#: a board skips their search (benchmarks/results/board-fresh-2026-11-30c.md).
BLUR_SOFT = 1.3
#: ``partial=True``: a corner of a part of a board refined farther than this fraction of its
#: nearest neighbour's distance from the saddle found drops its row or column.
PARTIAL_REACH = 0.25
#: ``partial=True``: a corner whose :func:`_asymmetry` passes this drops its row or column
#: (rendered endoscope views, a round field of view: corners refined 0.5-5.4 px off the truth
#: read 0.70-1.72; of those within 0.5 px, 99 % read under 0.66 and the median 0.04).
PARTIAL_ASYMMETRY = 0.5
#: ``pattern_size="auto"``: corner candidates kept per scale (boards up to about a thousand
#: inner corners), the lattice walk's reach in grid steps, the fewest corners a side of the
#: board and the whole board may have (a 2 x N lattice is too easily a pair of tiles' rows,
#: a 3 x 3 one a patch of a checked pattern or of a board shown on a monitor), and the
#: shortest mean grid step in pixels (squares too small to tell the board's edge by).
AUTO_MAX_CANDIDATES = 1200
AUTO_MAX_HOPS = 120
AUTO_MIN_SIDE = 3
AUTO_MIN_CORNERS = 12
AUTO_MIN_STEP = 8.0


class CheckerboardNotFoundWarning(ImageformWarning):
    """Some views of a set show no complete checkerboard (each is named with its reason)."""


@dataclass(frozen=True)
class CheckerboardResult:
    """The outcome of :func:`find_checkerboard`.

    Attributes
    ----------
    found : bool
        True when the full ``cols x rows`` grid was found and passed the checks (or, with
        ``partial=True``, a part of it: see ``partial``).
    corners : ndarray (cols*rows, 2) float64 or None
        Inner corners ``(u, v)`` in pixels (centre of the top-left pixel = (0, 0)), row by
        row in the module's order convention; None when not found.
    reason : str
        Why the board was not found ("" when found).
    pattern_size : tuple of int
        ``(cols, rows)`` as asked; with ``"auto"`` the size found, ``(0, 0)`` when none; of a
        partial board the size of the part found (``cols >= rows``).
    status : ndarray (cols*rows,) int64 or None
        Sub-pixel status per corner (0 converged, 1 ``max_iter`` reached, 2 flat window,
        3 left the image, 4 moved farther than the window — kept unrefined); None when not
        refined or not found.
    sigma : float or None
        The smoothing scale at which the board was found.
    partial : bool
        True when only a part of the board was found (``find_checkerboard(...,
        partial=True)``, the board cut by the image's border or hidden): ``corners`` are the
        ``pattern_size`` lattice's, in the module's order for that size; which corners of the
        board they are is not known (their board coordinates are the part's own,
        :func:`~imageform.geometry.checkerboard_points` of ``pattern_size``).
    """

    found: bool
    corners: NDArray[np.float64] | None
    reason: str = ""
    pattern_size: tuple[int, int] = (0, 0)
    status: NDArray[np.int64] | None = field(default=None, repr=False)
    sigma: float | None = None
    partial: bool = False

    def __post_init__(self) -> None:
        """Check every field (corners required when found) and convert the arrays to NumPy."""
        object.__setattr__(self, "found", as_bool(self.found, "found"))
        object.__setattr__(self, "partial", as_bool(self.partial, "partial"))
        if self.partial and not self.found:
            raise InvalidInputError("expected partial False when found is False, got True")
        if not isinstance(self.reason, str):
            raise InvalidInputError(f"expected reason as a str, got {describe(self.reason)}")
        object.__setattr__(
            self, "pattern_size", size_pair(self.pattern_size, "pattern_size", minimum=0)
        )
        n = self.pattern_size[0] * self.pattern_size[1]
        if self.corners is not None:
            c = np.asarray(
                to_numpy(as_float_bounded(self.corners, "corners", xp=np, dtype=np.float64))
            )
            if c.shape != (n, 2):
                raise InvalidInputError(
                    f"expected corners of shape ({n}, 2) for pattern_size {self.pattern_size}, "
                    f"got {format_shape(c.shape)}"
                )
            object.__setattr__(self, "corners", c)
        elif self.found:
            raise InvalidInputError("expected corners (N, 2) when found is True, got None")
        if self.status is not None:
            st = np.asarray(to_numpy(as_float_bounded(self.status, "status", xp=np, finite=True)))
            if st.shape != (n,) or np.any(st != np.round(st)):
                raise InvalidInputError(
                    f"expected status as ({n},) integers, got {describe(self.status)}"
                )
            object.__setattr__(self, "status", st.astype(np.int64))
        if self.sigma is not None:
            object.__setattr__(self, "sigma", as_real(self.sigma, "sigma", positive=True))

    def grid(self) -> NDArray[np.float64]:
        """Return the corners as ``(rows, cols, 2)``; raises when not found."""
        if self.corners is None:
            raise InvalidInputError(f"no checkerboard was found: {self.reason}")
        cols, rows = self.pattern_size
        return self.corners.reshape(rows, cols, 2)


def _check_pattern(pattern_size: object) -> tuple[int, int]:
    # (cols, rows) inner corners, each >= 2, at most 10 000 (a board of 10^8 corners)
    cols, rows = size_pair(pattern_size, "pattern_size (cols, rows) inner corners", minimum=2)
    if max(cols, rows) > 10_000:
        raise InvalidInputError(
            f"expected pattern_size (cols, rows) of at most 10000 each, got ({cols}, {rows})"
        )
    return cols, rows


def _check_pattern_or_auto(pattern_size: object) -> tuple[int, int]:
    """``(cols, rows)`` of a ``pattern_size``, or ``(0, 0)`` for ``"auto"``."""
    if isinstance(pattern_size, str) and pattern_size.strip().lower() == "auto":
        return 0, 0
    return _check_pattern(pattern_size)


def _orient(
    grid: NDArray[np.float64],
    gray: NDArray[np.floating],
    cols: int,
    rows: int,
    means: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Apply the module's order convention to a ``(rows, cols, 2)`` or ``(cols, rows, 2)`` grid.

    ``means``: the grid's :func:`cell_means` when the caller has them (they follow the
    grid's transposition and mirroring; only their sign pattern is used).
    """
    if grid.shape[:2] != (rows, cols):
        grid = grid.transpose(1, 0, 2)
        means = None if means is None else means.T
    x = grid[0, 1] - grid[0, 0]
    y = grid[1, 0] - grid[0, 0]
    if x[0] * y[1] - x[1] * y[0] < 0:
        grid = grid[:, ::-1]
        means = None if means is None else means[:, ::-1]
    if (cols + rows) % 2 == 1:
        if means is None:
            means = cell_means(gray, grid)
        flip = 1 - 2 * (np.add.outer(np.arange(rows - 1), np.arange(cols - 1)) % 2)
        # > 0 when the parity-0 cells (the first cell among them) are the bright ones
        if float(np.mean(means * flip)) > 0:
            grid = grid[::-1, ::-1]
    elif rows != cols:
        if grid[-1, 0, 1] < grid[0, 0, 1]:
            grid = grid[::-1, ::-1]
    else:
        options = [np.rot90(grid, k, axes=(0, 1)) for k in range(4)]
        grid = min(options, key=lambda g: float(g[0, 0, 0] + g[0, 0, 1]))
    return np.ascontiguousarray(grid)


class _Gray:
    """Hold the grey image as the detector reads it, and as floats made on first use only.

    The image is ``codes / scale`` (see ``gray_codes``); the candidates are found on the codes, so
    that the smoothed image and a float copy of the input are never held together (a full-size
    temporary costs its page faults, which at 640 x 480 cost as much as the arithmetic).
    """

    __slots__ = ("_float", "_links", "_seen", "codes", "lattice", "scale")

    def __init__(self, codes: NDArray[np.number], scale: float) -> None:
        self.codes = codes
        self.scale = scale
        self._float: NDArray[np.floating] | None = None
        self._seen: dict[tuple[float, int], Candidates] = {}
        self._links: dict[tuple[float, int], NDArray[np.int64]] = {}
        #: the most corners of a lattice :func:`_detect` saw and refused on this image
        self.lattice = 0

    def candidates(self, sigma: float, cap: int) -> Candidates:
        """Return the corner candidates at ``sigma``, at most ``cap`` (kept: read again later)."""
        key = (float(sigma), int(cap))
        if key not in self._seen:
            self._seen[key] = find_candidates(
                self.codes, sigma, max_candidates=cap, scale=self.scale
            )
        return self._seen[key]

    def links(self, sigma: float, cap: int) -> NDArray[np.int64]:
        """Return the neighbour table of :meth:`candidates` ``(sigma, cap)`` (kept too)."""
        key = (float(sigma), int(cap))
        if key not in self._links:
            self._links[key] = neighbors(self.candidates(sigma, cap), min_dist=2.0 * sigma)
        return self._links[key]

    @property
    def float(self) -> NDArray[np.floating]:
        if self._float is None:
            self._float = gray_from_codes(self.codes, self.scale)
        return self._float


def _detect(
    image: _Gray, cols: int, rows: int, sigma: float, partial: bool = False
) -> tuple[NDArray[np.float64] | None, str, int]:
    """One scale: the ordered grid or (None, reason, size of the best partial grid).

    When several complete boards pass the checks (a board on a monitor behind the target),
    the one covering the largest image area is returned. ``partial``: the largest lattice of
    the ``cols x rows`` board (any size from :data:`AUTO_MIN_SIDE` a side and
    :data:`AUTO_MIN_CORNERS` corners up to the board's, in either orientation) that passes the
    same checks but the board's edge (it is cut there), ``(cols, rows)`` with ``cols >= rows``.
    """
    auto = cols == 0
    grown = auto or partial  # the largest rectangle and its regrowths, its size found
    cap = AUTO_MAX_CANDIDATES if auto else max(300, 4 * cols * rows)
    cand = image.candidates(sigma, cap)
    n = cand.xy.shape[0]
    need = AUTO_MIN_CORNERS if grown else cols * rows
    if n < need:
        what = "a board's" if auto else f"the {cols * rows}"
        if partial:
            what = "a partial board's"
        return None, f"{n} corner candidates, fewer than {what} inner corners", n
    nbr = image.links(sigma, cap)
    tried = np.zeros(n, dtype=bool)
    best_reason, best_size = "no grid of corners found", 0
    want = sorted((cols, rows))
    hops = AUTO_MAX_HOPS if auto else cols + rows
    boards: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
    for seed in range(min(n, MAX_SEEDS)):
        if tried[seed] or np.any(nbr[seed] < 0):
            continue
        rect = lattice_rectangle(seed, cand, nbr, max_hops=hops)
        if rect.size == 0:
            continue
        tried[rect.ravel()] = True
        if grown:  # the largest of it and its regrowths (a board of any size)
            rect = _regrown(rect, cand, nbr, hops, None)
            tried[rect.ravel()] = True
        elif rect.size < cols * rows:
            rect = _regrown(rect, cand, nbr, hops, want)
        variants = [cand.xy[rect]]
        if auto:  # a row the lattice took past the board's edge (a thin margin) is dropped;
            # where one row was dropped the lattice as taken is judged too when the trimmed
            # grid is refused (the row was the board's own, its outer squares' margin too thin
            # to show it); not where blur failed the test on several rows (a smeared board,
            # whose lattice may miss a column as well: an 8 x 6 board taken as 7 x 6)
            edged = _x_edged(image.float, variants[0])
            dropped = sum(variants[0].shape[:2]) - sum(edged.shape[:2])
            variants = [edged, variants[0]] if dropped == 1 else [edged]
        refused = (best_size, best_reason)
        for k, grid in enumerate(variants):
            if k:  # the untrimmed lattice, the trimmed grid refused
                refused = (best_size, best_reason)
            shape = sorted(grid.shape[:2])
            if grown:
                cols, rows = shape[1], shape[0]
            if grown and (shape[0] < AUTO_MIN_SIDE or shape[0] * shape[1] < AUTO_MIN_CORNERS):
                if rect.size > best_size:
                    best_size = rect.size
                    best_reason = (
                        f"largest grid found has {rect.shape[1]} x {rect.shape[0]} corners, too "
                        f"few to tell a {'partial ' if partial else ''}board by (at least "
                        f"{AUTO_MIN_CORNERS}, {AUTO_MIN_SIDE} a side)"
                    )
                continue
            if partial and (shape[0] > want[0] or shape[1] > want[1]):
                if rect.size > best_size:
                    best_size = rect.size
                    best_reason = (
                        f"found a grid of {rect.shape[1]} x {rect.shape[0]} corners, larger than "
                        f"the pattern {want[1]} x {want[0]} in either orientation: wrong "
                        "pattern_size?"
                    )
                continue
            step = _mean_step(grid) if auto else math.inf
            if step < AUTO_MIN_STEP:
                if best_size == 0:  # not counted as a larger grid beside a board found
                    best_reason = (
                        f"a {rect.shape[1]} x {rect.shape[0]} grid of squares of {step:.1f} px, "
                        f"too small to tell the board's edge by (at least {AUTO_MIN_STEP:g} px)"
                    )
                continue
            if not grown and shape != want:
                if rect.size > best_size:
                    best_size = rect.size
                    if shape[0] >= want[0] and shape[1] >= want[1]:
                        best_reason = (
                            f"found a grid of {rect.shape[1]} x {rect.shape[0]} corners, larger "
                            f"than the pattern {cols} x {rows}: wrong pattern_size?"
                        )
                    else:
                        best_reason = (
                            f"largest grid found has {rect.shape[1]} x {rect.shape[0]} corners, "
                            f"pattern {cols} x {rows} asked: board not fully visible, corners "
                            "missed, or pattern_size too large"
                        )
                continue
            problem = lattice_problem(grid)
            if problem is not None and not problem.startswith("the grid's cells"):
                # a response peak sits up to ~2 px off its corner where squares are small and
                # foreshortened (a board turned steeply, a wide-angle lens): the bend and spacing
                # tests are made again on the sub-pixel corners before the grid is dropped
                sharp = _sharpened(image.float, grid)
                if lattice_problem(sharp) is None:
                    grid, problem = sharp, None
            means = None if problem is not None else cell_means(image.float, grid)
            if means is not None and not cell_parity_ok(means):
                problem = "the cells of the grid do not alternate dark and bright"
            if problem is None and not partial:  # a partial board is cut: it continues
                side = board_continues(image.float, grid, means, saddles=not auto)
                if side is not None:
                    problem = (
                        f"the checkerboard continues {side} of the {cols} x {rows} grid (a "
                        "larger board cut by the image border? check pattern_size)"
                    )
            if problem is None and auto:
                side = _edge_outside(grid, image.codes.shape[:2], 3.0 * sigma)
                if side is not None:
                    problem = (
                        f"the {cols} x {rows} grid's outer squares reach past the image's "
                        f"{side} border: the board may continue there (give pattern_size)"
                    )
            if problem is not None:
                if rect.size >= best_size:
                    best_size, best_reason = rect.size, f"grid rejected: {problem}"
                continue
            boards.append((grid, means))  # type: ignore[arg-type]  # means is set here
            break
        else:
            if len(variants) > 1:  # both refused: the trimmed grid's reason is reported
                best_size, best_reason = refused
    if boards:
        if partial:  # the most corners, then the largest area
            grid, means = max(boards, key=lambda b: (b[0].shape[0] * b[0].shape[1], _area(b[0])))
        else:
            grid, means = max(boards, key=lambda b: _area(b[0]))
        if grown:  # (cols, rows) with cols >= rows: the longer side along the rows
            rows, cols = sorted(grid.shape[:2])
        grid = _orient(grid, image.float, cols, rows, means)
        if auto and best_size > cols * rows:  # a larger grid was seen (and refused)
            return grid, best_reason, best_size
        return grid, "", cols * rows
    image.lattice = max(image.lattice, best_size)
    return None, best_reason, best_size


def _x_edged(gray: NDArray[np.floating], grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """``grid`` (R, C, 2) less the outer rows and columns that are not X-corners.

    ``pattern_size="auto"`` takes the largest lattice of corner candidates; where a board's
    margin is thin (a few pixels) against a darker background, the corners of the outer
    squares with the margin can pass the ring test and the lattice checks as one more row
    (a 9 x 6 board read as 10 x 6 in a 270 x 180 view). Such a row is not of X-corners: its
    outer quadrants are both background (:func:`_outer_x_share`). The side with the fewest
    X-corners, when under half of those read, is dropped, and again, while the grid keeps
    :data:`AUTO_MIN_SIDE` a side.
    """
    while min(grid.shape[:2]) > AUTO_MIN_SIDE:
        share = _outer_x_share(gray, grid, cell_means(gray, grid))
        read = [(v, k) for k, v in enumerate(share) if v is not None]
        if not read or min(read)[0] >= 0.5:
            break
        grid = (grid[1:], grid[:-1], grid[:, 1:], grid[:, :-1])[min(read)[1]]
    return grid


def _regrown(
    rect: NDArray[np.int64],
    cand: Candidates,
    nbr: NDArray[np.int64],
    hops: int,
    want: list[int] | None,
) -> NDArray[np.int64]:
    """Grow the rectangle again from next to each of its corners.

    Returns the first of ``want``'s shape (the size given), or with ``want=None`` (``"auto"``)
    the largest, the rectangle itself when none is larger. The rectangle grows from its seed
    a row or column at a time, each new one whole and within a third of a step of its
    straight continuation. Seeded on one side of a board whose squares shrink toward the
    other (turned steeply, or near a wide-angle or endoscope lens's edge) it meets the far,
    bent columns at full height, and one corner too far off stops it; seeded on that side it
    takes those columns while they are short.
    """
    best = rect
    for a, b in ((1, 1), (1, -2), (-2, 1), (-2, -2)):
        if min(rect.shape) < 3:
            break
        seed = int(rect[a, b])
        if np.any(nbr[seed] < 0):
            continue
        other = lattice_rectangle(seed, cand, nbr, max_hops=hops)
        if want is not None and sorted(other.shape) == want:
            return other
        if want is None and other.size > best.size:
            best = other
    return best


def _auto_grid(
    image: _Gray, sigmas: Sequence[float]
) -> tuple[NDArray[np.float64] | None, float, str]:
    """``pattern_size="auto"``: the largest board found at any scale, or None with the reason.

    Every scale is searched; a board is refused when a larger grid of corners was seen at
    any scale (refused by a check: a board cut by the image's border, a corner missed), as
    a smaller board found beside it is likely a part of it.
    """
    found: tuple[NDArray[np.float64], float] | None = None
    largest, largest_why = 0, "no checkerboard found"
    for s in sigmas:
        grid, why, n = _detect(image, 0, 0, s)
        if grid is not None and (found is None or grid.size > found[0].size):
            found = (grid, s)
        if n > largest:
            largest, largest_why = n, why
    if found is None:
        return None, 0.0, largest_why
    grid, s = found
    if largest > grid.shape[0] * grid.shape[1]:
        return (
            None,
            0.0,
            (
                f"a {grid.shape[1]} x {grid.shape[0]} board found, but a larger grid of {largest} "
                f"corners was seen too ({largest_why}): the board's size is uncertain (give "
                "pattern_size)"
            ),
        )
    return grid, s, ""


def _mean_step(grid: NDArray[np.float64]) -> float:
    """Mean distance (px) between neighbouring corners of a ``(R, C, 2)`` grid."""
    rows = np.linalg.norm(np.diff(grid, axis=1), axis=-1)
    cols = np.linalg.norm(np.diff(grid, axis=0), axis=-1)
    return float((rows.sum() + cols.sum()) / (rows.size + cols.size))


def _edge_outside(
    grid: NDArray[np.float64], shape: tuple[int, ...], margin: float = 0.0
) -> str | None:
    """Say which image border a grid's outer squares reach past, None when they are inside.

    A board's outer squares end one grid step beyond its outer inner corners; a quarter to
    nearly half a step further on ``board_continues`` reads whether a larger board goes on.
    Those points, up to 1.45 steps beyond each outer corner along its row or column
    (extrapolated linearly), must lie ``margin`` pixels inside the image (the caller's three
    smoothing scales: a row of corners closer to the border than the detector's ring escapes
    it, and the lattice stops a row short of a board that goes on): otherwise the board may
    continue past the image's border and its size cannot be told.
    """
    h, w = shape[0] - margin, shape[1] - margin
    edges = (
        2.45 * grid[0] - 1.45 * grid[1],
        2.45 * grid[-1] - 1.45 * grid[-2],
        2.45 * grid[:, 0] - 1.45 * grid[:, 1],
        2.45 * grid[:, -1] - 1.45 * grid[:, -2],
    )
    pts = np.concatenate(edges)
    for name, bad in (
        ("left", pts[:, 0] < margin - 0.5),
        ("right", pts[:, 0] > w - 0.5),
        ("top", pts[:, 1] < margin - 0.5),
        ("bottom", pts[:, 1] > h - 0.5),
    ):
        if np.any(bad):
            return name
    return None


def _area(grid: NDArray[np.float64]) -> float:
    """Image area of the quadrilateral of a grid's four outer corners (shoelace)."""
    q = np.array([grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]])
    x, y = q[:, 0], q[:, 1]
    return 0.5 * abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1)))


@_deprecate.parameters(renamed={"eps": "tol"})
def find_checkerboard(
    image: npt.ArrayLike,
    pattern_size: tuple[int, int] | Literal["auto"],
    *,
    refine: bool = True,
    sigma: float | None = None,
    half_window: int | None = None,
    max_iter: int = 30,
    tol: float = 1e-3,
    method: Literal["symmetric", "gradient"] = "symmetric",
    partial: bool = False,
) -> CheckerboardResult:
    r"""Find the inner corners of a ``cols x rows`` checkerboard, sub-pixel refined.

    Corners are saddle points of the smoothed intensity; candidates are local maxima of

    .. math::  s = I_{uv}^2 - I_{uu} I_{vv}  \quad (= -\det \nabla^2 I)

    that show four alternating dark/bright sectors on a ring; their edge directions link
    them into a lattice, which must be exactly ``cols x rows``, nearly straight and evenly
    spaced locally, with convex cells of one orientation and alternating cell colours.
    The corners are then refined with :func:`refine_corners` and, by default, as centres of
    point symmetry with :func:`refine_corners_symmetric`.

    Parameters
    ----------
    image : array_like (H, W), (H, W, 1) or (H, W, 3)
        Grey or RGB image (RGB is turned grey with BT.601 luma weights); uint8, uint16 or
        floats of any scale (detection does not depend on the scale); finite. Arrays of
        other libraries are converted to NumPy: detection runs on NumPy.
    pattern_size : (int, int) or "auto"
        ``(cols, rows)``: inner corners per row and per column, each >= 2 (OpenCV's
        ``patternSize``; the OpenCV sample board is ``(9, 6)``). ``"auto"``: the largest
        board of at least 3 x 3 inner corners, whatever its size; the result's
        ``pattern_size`` says which, ``(cols, rows)`` with ``cols >= rows`` (``(0, 0)`` when
        none is found). An outer row or column of the lattice whose corners are not
        X-corners (a thin margin against a darker background read as one more row) is
        dropped before the board is sized.
    refine : bool
        Run the sub-pixel refinement (otherwise positions are the response peaks, ~0.5 px).
    sigma : float, optional
        Smoothing scale in pixels; by default 2.0, then 1.2, then 3.5 are tried until found,
        then (a board blurred wider than that: a hand-held board moved during the exposure)
        the same scales on copies averaged over 2, 4, ... times as many pixels a side while
        the copy keeps 320 px on its longest side. Given, only that scale is tried.
        Squares must be at least about ``5 sigma`` pixels wide.
    half_window : int, optional
        Half size of the refinement window (OpenCV's ``winSize``); by default
        ``min(11, max(2, floor(0.4 s), min(5, floor(0.5 s))))`` for the shortest grid
        step ``s``, so that the window never reaches the neighbouring corners (half the
        step, up to 5 px, where squares are small: blurred narrow squares need it).
    max_iter, tol : int, float
        Refinement stopping rule: at most ``max_iter`` iterations, or a step of at most
        ``tol`` pixels (OpenCV's ``TermCriteria(EPS + COUNT, 30, 0.001)``; ``eps`` is the
        deprecated name of ``tol``).
    method : {"symmetric", "gradient"}
        ``"symmetric"``: the corners refined by :func:`refine_corners` are refined again by
        :func:`refine_corners_symmetric` in a round window of radius 0.8 of the shortest grid
        step (at least 2 px; ``half_window`` is the first step's); a corner that step cannot
        refine (status 2-4), or whose window would reach past the image's border, keeps the
        first step's position and status. Where the board bends or foreshortens within a
        corner's window (a wide-angle lens, a fisheye, a steep view: the grid's map around
        the corner departs from an affine one by more than 1 px on the window's rim), the
        corner is refined once more with the window's pairs taken through that map
        (benchmarks/results/local-homography-2026-11-30a.md). Windows of radius 40 px and
        more (squares of 50 px and more) run both of those steps on block means of 2 x 2
        pixels or more, then one step at full resolution: the corners within about 0.02 px
        of the full-resolution steps' (benchmarks/results/checkerboard-pyramid-2026-12-02a.md).
        ``"gradient"``:
        :func:`refine_corners` only (OpenCV's ``cornerSubPix``, imageform's only refinement
        before ``method`` existed; use it to reproduce OpenCV's corners). On eleven sets of
        real calibration photographs the symmetric corners fit a camera model better than the
        gradient ones and than OpenCV's ``findChessboardCornersSB`` (calibration and held-out
        RMS), and on rendered views they lie 2-3 times closer to the truth
        (benchmarks/results/corner-refinement-2026-11-29i.md).
    partial : bool
        When the whole board is not found, return the largest part of it that is: a complete
        lattice of at least 3 x 3 and 12 inner corners, at most ``cols x rows`` in either
        orientation, that passes every check of a whole board but its edge (straight, evenly
        spaced rows and columns, convex cells, alternating colours), refined as a whole board,
        with ``partial=True`` and its own ``pattern_size`` (``cols >= rows``). A board cut by
        the image's border (an endoscope's round field of view) then still gives the corners
        near the border, where distortion is strongest. Its corners are labelled in the part's
        own lattice: for intrinsic calibration any such labelling is valid (a shift, quarter
        turn or mirroring of the labels is absorbed by the view's pose), not for poses against
        the board's own origin or for stereo. Searched at full resolution only. A whole board
        is returned exactly as without it. Not with ``"auto"`` (which takes a board of any
        size already).

    Returns
    -------
    CheckerboardResult
        ``found``, ``corners`` (cols*rows, 2) in the order of the module docstring (row by
        row; first cell dark when ``cols + rows`` is odd) or None, ``reason`` when not found.

    Notes
    -----
    Saddle response: Chen & Zhang (2005), "Accurate calibration for a camera-projector
    measurement system based on structured light projection" (eq. 3); the ring test and
    grid growing follow Geiger et al. (2012), "Automatic camera and range sensor calibration
    using a single shot", ICRA, sec. III; refinement: Förstner & Gülch (1987) as in OpenCV's
    ``cornerSubPix``, then point symmetry (Schöps, Larsson, Pollefeys & Sattler 2020, "Why
    having 10,000 parameters in your camera model is better than twelve", CVPR). With
    ``method="gradient"`` and ``half_window=11``, on OpenCV's ``left*.jpg`` views the corners
    agree with OpenCV 5.0's ``findChessboardCorners`` + ``cornerSubPix`` to about 1e-5 px
    (median; tested).

    Examples
    --------
    A synthetic board of 6 x 5 squares of 20 pixels (5 x 4 inner corners) on a white margin:

    >>> import numpy as np
    >>> v, u = np.mgrid[0:140, 0:160]
    >>> i, j = (u - 20) // 20, (v - 20) // 20
    >>> dark = (i >= 0) & (i < 6) & (j >= 0) & (j < 5) & ((i + j) % 2 == 0)
    >>> res = find_checkerboard(np.where(dark, 0.1, 0.9), (5, 4))
    >>> res.found, res.corners.shape
    (True, (20, 2))
    >>> np.round(res.corners[[0, 1, 5]], 2)
    array([[39.5, 39.5],
           [59.5, 39.5],
           [39.5, 59.5]])

    Without the board's size:

    >>> find_checkerboard(np.where(dark, 0.1, 0.9), "auto").pattern_size
    (5, 4)
    """
    codes, scale, span = gray_codes(image)
    cols, rows = _check_pattern_or_auto(pattern_size)
    partial = as_bool(partial, "partial")
    if partial and cols == 0:
        raise InvalidInputError(
            "partial=True needs the board's pattern_size (cols, rows); 'auto' takes a board of "
            "any size"
        )
    if sigma is not None:
        # a Gaussian wider than 1000 px blurs any board away (and its kernel is 8 sigma)
        sigma = as_real(sigma, "sigma", positive=True, maximum=1000.0)
    if half_window is not None:
        half_window = as_int(half_window, "half_window", minimum=1, maximum=MAX_HALF_WINDOW)
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", nonnegative=True)
    if not isinstance(method, str) or method not in METHODS:
        raise InvalidInputError(
            f"expected method 'symmetric' or 'gradient', got {describe(method)}"
        )
    how = method if as_bool(refine, "refine") else None
    size = (cols, rows)
    found, _ = _search(codes, scale, span, size, sigma, how, half_window, max_iter, tol, partial)
    return found


def _search(
    codes: NDArray[np.number],
    scale: float,
    span: float,
    size: tuple[int, int],
    sigma: float | None,
    how: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
    partial: bool,
    soft: bool = True,
) -> tuple[CheckerboardResult, bool]:
    """:func:`find_checkerboard` on checked arguments; and whether a smear search was in vain.

    ``soft=False`` leaves out the soft image's search of the coarser copies (of
    :func:`_smear_possible`'s two reasons only the lattice seen at full resolution): the tracker's
    way not to pay for it frame after frame where it finds nothing. The flag says that the
    coarser copies were searched for a board not found at full resolution and none was found.
    """
    if span == 0.0:
        return CheckerboardResult(False, None, "the image is constant (no contrast)", size), False
    sigmas: tuple[float, ...] = DEFAULT_SIGMAS if sigma is None else (float(sigma),)
    gray = _Gray(codes, scale)
    factor = math.ceil(max(codes.shape[:2]) / COARSE_SIZE) if sigma is None else 1
    whole = _whole(gray, size, sigmas, factor, how, half_window, max_iter, tol)
    vain = False
    smear = _smear_possible if soft else (lambda g: g.lattice >= AUTO_MIN_CORNERS)
    if sigma is None and (_unsettled(whole) or (not whole.found and smear(gray)
                                                and not _larger_board(whole))):  # fmt: skip
        blurred = _blurred(gray, size, factor, how, half_window, max_iter, tol)
        vain = not whole.found and blurred is None
        if blurred is not None and (not whole.found or _failed(blurred) < _failed(whole)):
            whole = blurred
    if not partial or whole.found:
        return whole, vain
    return _partial(gray, size, sigmas, how, half_window, max_iter, tol, whole.reason), vain


def _tracking_search(
    image: npt.ArrayLike,
    pattern_size: tuple[int, int],
    method: Literal["symmetric", "gradient"],
    soft: bool,
) -> tuple[CheckerboardResult, bool]:
    """``find_checkerboard(image, pattern_size, method=method)`` for a tracker's frame.

    ``soft=False``: a frame soft all over does not, alone, get the coarser copies searched
    (see :func:`_search`, which also gives the second value).
    """
    codes, scale, span = gray_codes(image)
    size = _check_pattern(pattern_size)
    return _search(codes, scale, span, size, None, method, None, 30, 1e-3, False, soft)


def _whole(
    gray: _Gray,
    size: tuple[int, int],
    sigmas: tuple[float, ...],
    factor: int,
    how: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
) -> CheckerboardResult:
    """Find the whole board of ``size`` (``(0, 0)``: ``"auto"``), as :func:`find_checkerboard`."""
    cols, rows = size
    reason, best = "no checkerboard found", -1
    full: CheckerboardResult | None = None
    if cols == 0:  # "auto": the board found at every scale, and no larger grid seen
        grid, s, why = _auto_grid(gray, sigmas)
        if grid is None:
            reason = why
        else:
            size = (grid.shape[1], grid.shape[0])
            full = _finish(gray.float, grid, size, s, how, half_window, max_iter, tol)
            if factor == 1 or not full.found:
                return full
        sigmas = ()
    for s in sigmas:
        grid, why, n = _detect(gray, cols, rows, s)
        if grid is not None:
            full = _finish(gray.float, grid, size, s, how, half_window, max_iter, tol)
            if factor == 1 or not full.found:
                return full
            break
        if n > best:
            reason, best = why, n
    steady = full is not None and (full.status is None or not np.any(full.status))
    if factor > 2 or (factor == 2 and not steady):  # not for a video frame found cleanly
        # a large photograph (a phone's 12 Mpx): squares of 100-300 px whose edges are
        # several pixels wide defeat the fixed smoothing scales, and corners refined at full
        # resolution on such edges wander; the board is also sought on a copy averaged over
        # factor x factor blocks. Of the boards found, the one whose corners lie closest to
        # a plane's projection (a homography) is kept: sharp photographs keep their full
        # resolution, blurred or blocky ones the averaged copy's steadier corners
        found = [r for r in (full, _coarse(gray, factor, size, how, half_window, max_iter, tol))
                 if r is not None and r.found]  # fmt: skip
        if found:
            return min(found, key=lambda r: _plane_rms(r.corners, r.pattern_size))
    if full is not None:
        return full
    return CheckerboardResult(False, None, reason, size)


def _blurred(
    gray: _Gray,
    size: tuple[int, int],
    factor: int,
    how: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
) -> CheckerboardResult | None:
    """Seek a board :func:`_whole` did not find on ever coarser averaged copies, or None.

    The copies average ``2 f``, ``4 f``, ... pixels a side (``f`` the factor of
    :func:`_whole`'s own averaged copy, 1 where it made none) while their longest side keeps
    :data:`BLUR_MIN_SIDE` pixels; each is searched and refined as :func:`_coarse` does (its
    corners refined again at full resolution, the set closer to a plane's projection kept).
    Each step doubles the smoothing scales in full pixels, so that the ring test reaches
    past a blur wider than the largest of them. A board found with most of its corners
    unrefined (:func:`_unsettled`) is kept only when no coarser copy does better.
    """
    level, first = 2 * factor, None
    while max(gray.codes.shape[:2]) / level >= BLUR_MIN_SIDE:
        found = _coarse(gray, level, size, how, half_window, max_iter, tol)
        if found is not None and found.found:
            if not _unsettled(found):
                return found
            first = first or found
        level *= 2
    return first


def _larger_board(result: CheckerboardResult) -> bool:
    """Whether the full-resolution search refused a grid as part of a larger board.

    A grid of the pattern's size seen sharp and refused because the board visibly goes on
    past it (or a larger grid was seen) is not sought again on the coarser copies: averaged
    over blocks, half an outer row hidden in black no longer reads as the board going on,
    and the sub-grid was taken (OpenCV's 13 sample views, half an outer row or column hidden,
    the pattern one short: refused 34 of 52 with the copies searched, 38 without).
    """
    return not result.found and (
        "the checkerboard continues" in result.reason or "larger than the pattern" in result.reason
    )


def _smear_possible(gray: _Gray) -> bool:
    """Whether a board :func:`_whole` did not find may be smeared past its scales.

    True where the full-resolution search saw a lattice of at least
    :data:`AUTO_MIN_CORNERS` corners (a part of a board), or where the image is soft: its mean
    absolute second difference under :data:`BLUR_SOFT` times its mean absolute first
    difference, both on every second pixel each way (a sharp photograph's fine detail keeps
    the two alike; a blur removes the second faster). A sharp image with no part of a board
    skips the coarser copies' search (a board smeared on a sharp background with no lattice
    left at full resolution is not sought there).
    """
    if gray.lattice >= AUTO_MIN_CORNERS:
        return True
    codes = gray.codes[::2, ::2]
    if codes.ndim != 2 or min(codes.shape) < 3:
        return False
    exact = np.int16 if codes.dtype.itemsize == 1 else np.int32  # codes' differences, exactly
    half = codes.astype(exact if codes.dtype.kind in "ui" else np.float32)
    d0, d1 = np.diff(half, axis=0), np.diff(half, axis=1)
    first = np.abs(d0).sum(dtype=np.float64) / d0.size + np.abs(d1).sum(dtype=np.float64) / d1.size
    e0, e1 = np.diff(d0, axis=0), np.diff(d1, axis=1)
    second = np.abs(e0).sum(dtype=np.float64) / e0.size + np.abs(e1).sum(dtype=np.float64) / e1.size
    return bool(second < BLUR_SOFT * first)


def _failed(result: CheckerboardResult) -> int:
    """Count the corners of a found board whose sub-pixel refinement failed (status > 0)."""
    return 0 if result.status is None else int(np.count_nonzero(result.status))


def _unsettled(result: CheckerboardResult) -> bool:
    """Whether most corners of a found board failed their refinement (:func:`_failed`).

    Smeared over most of a square (a smear of 61 px on squares of 64), the saddle response
    of every corner peaks at one end of the bar the smear draws through it, 25 px off the
    corner, and every refinement step from there leaves its window (status 4): the lattice
    is regular and passes the checks, but none of its corners is where the board's is. On
    a copy averaged over blocks wide enough the same board's corners converge, 0.01 px
    from the truth.
    """
    return result.found and 2 * _failed(result) > result.pattern_size[0] * result.pattern_size[1]


def _partial(
    gray: _Gray,
    size: tuple[int, int],
    sigmas: tuple[float, ...],
    how: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
    whole_reason: str,
) -> CheckerboardResult:
    """``partial=True``: the largest lattice of the board at any scale, refined, or not found.

    Searched at full resolution only (not on :func:`_coarse`'s averaged copy); a view without
    it says why the whole board was not found and why no part of it was.
    """
    found: tuple[NDArray[np.float64], float] | None = None
    why, most = "no grid of corners found", -1
    for s in sigmas:
        grid, reason, n = _detect(gray, *size, s, partial=True)
        if grid is not None and (found is None or grid.size > found[0].size):
            found = (grid, s)
        elif grid is None and n > most:
            why, most = reason, n
    if found is None:
        return CheckerboardResult(False, None, f"{whole_reason}; no part of it: {why}", size)
    grid, s = found
    h, w = gray.codes.shape[:2]
    grid = _trimmed(grid, lambda g: room_to_border(g, h, w) < _window(g, half_window) + 1)
    while True:
        if min(grid.shape[:2]) < AUTO_MIN_SIDE or grid.size // 2 < AUTO_MIN_CORNERS:
            return CheckerboardResult(
                False,
                None,
                f"{whole_reason}; no part of it: the largest grid found, less its rows and "
                "columns within a refinement window of the image's border or refined off "
                f"their saddles, has {grid.shape[1]} x {grid.shape[0]} corners (at least "
                f"{AUTO_MIN_CORNERS}, {AUTO_MIN_SIDE} a side)",
                size,
            )
        grid = _orient(grid, gray.float, max(grid.shape[:2]), min(grid.shape[:2]))
        part = (grid.shape[1], grid.shape[0])
        res = _finish(gray.float, grid, part, s, how, half_window, max_iter, tol, partial=True)
        if not res.found or res.status is None:
            break
        assert res.corners is not None
        refined = res.corners.reshape(grid.shape)
        # a corner pulled off its saddle (a window wider than narrow, foreshortened squares
        # slid a row of them half a square: 6 px, consistently, so the lattice checks pass),
        # or whose window takes in something else than the board (an endoscope's dark
        # surround: corners up to 7 px off on rendered views)
        off = np.linalg.norm(refined - grid, axis=-1) > PARTIAL_REACH * _local_step(grid)
        off |= _asymmetry(gray.float, refined) > PARTIAL_ASYMMETRY
        if not off.any():
            break
        grid = _trimmed(grid, _fixed(off), once=True)
    if not res.found:
        return CheckerboardResult(
            False, None, f"{whole_reason}; the {part[0]} x {part[1]} part: {res.reason}", size
        )
    return res


def _asymmetry(gray: NDArray[np.floating], grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """Measure how far each corner of ``grid`` (R, C, 2) is from a centre of point symmetry.

    ``sqrt(mean (I(q + d) - I(q - d))²) / std I`` over offsets ``d`` in a disk of 0.6 of the
    corner's nearest-neighbour distance (bilinear samples): near 0 at a checker corner
    through any affine view of the board and any symmetric blur, larger where something else
    enters the window (the dark surround of an endoscope's round field of view).
    """
    from imageform.geometry.checkerboard_grid import _sample

    ang = np.linspace(0.0, np.pi, 12, endpoint=False)
    rad = np.array([0.2, 0.4, 0.6])
    unit = np.stack([np.cos(ang), np.sin(ang)], -1)  # a half disk: -d gives the other half
    d = (rad[:, None, None] * unit[None]).reshape(-1, 2)  # (K, 2) in steps
    step = _local_step(grid)[..., None, None]  # (R, C, 1, 1)
    q = grid[..., None, :]
    a = _sample(gray, q + step * d)
    b = _sample(gray, q - step * d)
    spread = np.std(np.concatenate([a, b], axis=-1), axis=-1)
    rms = np.sqrt(np.mean((a - b) ** 2, axis=-1))
    return np.asarray(rms / np.maximum(spread, 1e-12), dtype=np.float64)


def _fixed(
    flags: NDArray[np.bool_],
) -> Callable[[NDArray[np.float64]], NDArray[np.bool_]]:
    """Return ``flags`` whatever the grid (:func:`_trimmed` with ``once``)."""

    def read(grid: NDArray[np.float64]) -> NDArray[np.bool_]:
        return flags

    return read


def _window(grid: NDArray[np.float64], half_window: int | None) -> int:
    """Return the refinement's half window for ``grid`` (given, else :func:`_half_window`)."""
    return _half_window(grid) if half_window is None else half_window


def _local_step(grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return each corner's distance (px) to its nearest lattice neighbour, ``(R, C)``."""
    step = np.full(grid.shape[:2], np.inf)
    rows = np.linalg.norm(np.diff(grid, axis=0), axis=-1)
    cols = np.linalg.norm(np.diff(grid, axis=1), axis=-1)
    step[1:] = np.minimum(step[1:], rows)
    step[:-1] = np.minimum(step[:-1], rows)
    step[:, 1:] = np.minimum(step[:, 1:], cols)
    step[:, :-1] = np.minimum(step[:, :-1], cols)
    return step


def _trimmed(
    grid: NDArray[np.float64],
    bad: Callable[[NDArray[np.float64]], NDArray[np.bool_]],
    once: bool = False,
) -> NDArray[np.float64]:
    """``grid`` (R, C, 2) less the outer rows and columns that hold corners ``bad`` says are.

    Side by side, the side with the most such corners first, until none is left (``once``:
    one side dropped, ``bad`` read on the grid as given only). An empty grid when only inner
    corners are bad. Used on a part of a board (a whole board keeps
    every corner: it has no others): a corner whose refinement window reaches past the image's
    border is refined on replicated edge pixels, not the board (a corner 5 px from the border
    of a board of 30 px squares came out 0.27 px off, the others within 0.02).
    """
    while min(grid.shape[:2]) >= 2:
        near = bad(grid)
        if not near.any():
            break
        sides = (near[0].sum(), near[-1].sum(), near[:, 0].sum(), near[:, -1].sum())
        k = int(np.argmax(sides))
        if sides[k] == 0:  # only inner corners (a strongly bent board)
            return grid[:0, :0]
        grid = (grid[1:], grid[:-1], grid[:, 1:], grid[:, :-1])[k]
        if once:
            break
    return grid


def _coarse(
    gray: _Gray,
    factor: int,
    size: tuple[int, int],
    refine: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
) -> CheckerboardResult | None:
    """Find the board on ``gray`` averaged over ``factor`` x ``factor`` blocks, in full pixels.

    Found there and refined there; its corners, mapped to full pixels, and the same corners
    refined again at full resolution are the two candidates, the one closer to a plane's
    projection returned (:func:`_plane_rms`). None when the averaged copy shows no board.
    """
    from imageform._kernels.chart import block_mean_numpy

    coarse = block_mean_numpy(np.asarray(gray.float)[..., None], factor, 1.0)[..., 0]
    codes, scale, _ = gray_codes(coarse)
    small = _Gray(codes, scale)
    for s in DEFAULT_SIGMAS if size[0] else (None,):
        if s is None:  # "auto": the board found at every scale, its size
            grid, s, _ = _auto_grid(small, DEFAULT_SIGMAS)
            if grid is not None:
                size = (grid.shape[1], grid.shape[0])
        else:
            grid, _, _ = _detect(small, *size, s)
        if grid is None:
            continue
        found = _finish(small.float, grid, size, s, refine, None, max_iter, tol)
        if not found.found:
            continue
        assert found.corners is not None
        up = found.corners * factor + (factor - 1) / 2.0  # block centres, in full pixels
        if not refine or found.status is None:
            return CheckerboardResult(True, up, "", size, None, s * factor)
        fine = _finish(gray.float, up.reshape(grid.shape), size, s * factor, refine,
                       half_window, max_iter, tol)  # fmt: skip
        if fine.found and _plane_rms(fine.corners, size) < _plane_rms(up, size):
            return fine
        return _found(up, size, found.status, s * factor)
    return None


def _plane_rms(corners: NDArray[np.float64] | None, size: tuple[int, int]) -> float:
    """RMS distance (px) of a board's corners to the best homography of its flat lattice."""
    from imageform.geometry.calibration import checkerboard_points
    from imageform.geometry.homography import apply_homography, estimate_homography

    assert corners is not None
    board = checkerboard_points(size, 1.0)[:, :2]  # the detector's order, row by row
    H = estimate_homography(board, corners)
    fit = np.asarray(apply_homography(H, board))
    return float(np.sqrt(np.mean(np.sum((fit - corners) ** 2, axis=1))))


def _half_window(grid: NDArray[np.float64]) -> int:
    """Give the refinement's default half window: 0.4 of the shortest grid step, 2-11 px.

    Where squares are small (the shortest step under 12.5 px: a board far away or turned
    steeply) the window takes half the step, up to 5 px: a window of 2-3 px on an edge
    blurred over 2 px left corners 0.4-0.8 px off (median) and up to 3.6 px, half the step
    brought them to 0.1-0.2 px (rendered views through a wide-angle lens, 11 x 8 board).
    """
    step = _shortest_step(grid)
    return min(11, max(2, math.floor(0.4 * step), min(5, math.floor(0.5 * step))))


def _shortest_step(grid: NDArray[np.float64]) -> float:
    """Return the shortest distance (px) between neighbouring corners of ``grid`` (R, C, 2)."""
    return min(
        float(np.linalg.norm(np.diff(grid, axis=0), axis=-1).min()),
        float(np.linalg.norm(np.diff(grid, axis=1), axis=-1).min()),
    )


def _sharpened(gray: NDArray[np.floating], grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """``grid`` (R, C, 2) with each corner refined as :func:`_finish` refines it."""
    hw = _half_window(grid)
    refined, _ = refine_clean(gray, grid.reshape(-1, 2), hw, hw, 30, 1e-3)
    return refined.reshape(grid.shape)


def _finish(
    gray: NDArray[np.floating],
    grid: NDArray[np.float64],
    size: tuple[int, int],
    sigma: float,
    refine: str | None,
    half_window: int | None,
    max_iter: int,
    tol: float,
    partial: bool = False,
) -> CheckerboardResult:
    """Refine a detected grid (``refine``: a :data:`METHODS` name, None for none) and check it.

    ``partial``: the grid is a part of the board (the result says so).
    """
    pts = grid.reshape(-1, 2)
    if not refine:
        return CheckerboardResult(True, pts.copy(), "", size, None, sigma, partial)
    if half_window is None:
        half_window = _half_window(grid)
    refined, status = refine_clean(gray, pts, half_window, half_window, max_iter, tol)
    if refine == "symmetric" and lattice_problem(refined.reshape(grid.shape)) is None:
        step = _shortest_step(refined.reshape(grid.shape))
        h = max(2, math.floor(SYMMETRIC_WINDOW * step))
        # a window past the image's border reads replicated edge pixels, not the board's
        # symmetry (lane-lines' boards cut by the frame: held-out RMS 1.048 -> 1.029 px when
        # those corners keep the first step's position); converged or max_iter, near the
        # saddle found: a singular, lost or far one keeps the first step's position too
        if h >= SYMMETRIC_COARSE_MIN:
            # large squares: both steps on block means, one step at full resolution
            refined, sym_status, moved = refine_symmetric_pyramid(
                gray,
                refined,
                pts,
                grid.shape[:2],
                h,
                max_iter,
                tol,
                SYMMETRIC_REACH * step,
                SYMMETRIC_MIN_BEND,
                SYMMETRIC_EXTENT,
                math.ceil(h / SYMMETRIC_COARSE_WINDOW),
            )
            status = status.copy()
            status[moved] = sym_status[moved]
        else:
            refined, status = _symmetric_steps(
                gray, refined, status, pts, grid, h, step, max_iter, tol
            )
    return _checked(refined, grid.shape, size, status, sigma, partial)


def _symmetric_steps(
    gray: NDArray[np.floating],
    refined: NDArray[np.float64],
    status: NDArray[np.int64],
    pts: NDArray[np.float64],
    grid: NDArray[np.float64],
    h: int,
    step: float,
    max_iter: int,
    tol: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`_finish`'s two symmetric steps at full resolution: the corners and status."""
    refined, sym_status, moved = refine_symmetric_inside(
        gray, refined, pts, h, max_iter, tol, SYMMETRIC_REACH * step
    )
    status = status.copy()
    status[moved] = sym_status[moved]
    # where the board bends or foreshortens within the window, the window again through
    # each corner's map from its symmetric neighbours
    refined, sym_status, moved = refine_local_inside(
        gray,
        refined,
        pts,
        refined.reshape(grid.shape),
        h,
        max_iter,
        tol,
        SYMMETRIC_REACH * step,
        SYMMETRIC_MIN_BEND,
        SYMMETRIC_EXTENT,
    )
    status[moved] = sym_status[moved]
    return refined, status


def _checked(
    refined: NDArray[np.float64],
    shape: tuple[int, ...],
    size: tuple[int, int],
    status: NDArray[np.int64],
    sigma: float,
    partial: bool,
) -> CheckerboardResult:
    """Return :func:`_finish`'s result for its refined corners (R*C, 2), or the lattice's fault.

    ``shape``: the grid's (R, C, 2).
    """
    problem = lattice_problem(refined.reshape(shape))
    if problem is not None:
        return CheckerboardResult(False, None, f"refined grid rejected: {problem}", size)
    return _found(refined, size, status, sigma, partial)


def _found(
    corners: NDArray[np.float64],
    size: tuple[int, int],
    status: NDArray[np.int64],
    sigma: float,
    partial: bool = False,
) -> CheckerboardResult:
    """Build a found result from the detector's own checked values.

    The checks of ``__post_init__`` are skipped (meant for callers' values: here they would cost a
    tenth of a millisecond per view for nothing). Equal to ``CheckerboardResult(True, corners, "",
    size, status, sigma, partial)``.
    """
    res = object.__new__(CheckerboardResult)
    for name, value in (
        ("found", True),
        ("corners", corners),
        ("reason", ""),
        ("pattern_size", size),
        ("status", status),
        ("sigma", float(sigma)),
        ("partial", partial),
    ):
        object.__setattr__(res, name, value)
    return res


def set_pattern_size(sizes: Sequence[tuple[int, int] | None]) -> tuple[int, int] | None:
    """Return the board size of a set of views from each view's ``pattern_size="auto"`` size.

    The size found in the most views (None for a view without a board); a tie goes to the
    larger board (a view of a board cut by the image's border can show a smaller complete
    lattice, never a larger one). None when no view shows a board.

    Raises
    ------
    InvalidInputError
        ``sizes`` not a list of ``(cols, rows)`` pairs (each >= 2) and None.

    Examples
    --------
    >>> set_pattern_size([(9, 6), None, (9, 6), (7, 4)])
    (9, 6)
    >>> set_pattern_size([(7, 4), (9, 6)]), set_pattern_size([None])
    ((9, 6), None)
    """
    if isinstance(sizes, str | bytes) or not isinstance(sizes, Sequence):
        raise InvalidInputError(
            f"expected sizes as a list of (cols, rows) or None, one per view, got {describe(sizes)}"
        )
    checked = [None if s is None else size_pair(s, "sizes (cols, rows)", minimum=2) for s in sizes]
    counts = Counter(s for s in checked if s is not None)
    if not counts:
        return None
    return max(counts, key=lambda s: (counts[s], s[0] * s[1], s))


def find_checkerboards(
    images: Sequence[npt.ArrayLike],
    pattern_size: tuple[int, int] | Literal["auto"],
    *,
    names: Sequence[str] | None = None,
    **options: Any,
) -> list[CheckerboardResult]:
    r""":func:`find_checkerboard` on every view of a calibration set, with the set's checks.

    All views must have the same size ``(H, W)`` (one camera, one resolution); views without
    a complete board are reported in one :class:`CheckerboardNotFoundWarning` naming each
    view and its reason (their results have ``found=False``), never silently dropped.

    .. math::  \text{result}_k = \operatorname{find\_checkerboard}(\text{image}_k), \quad
               k = 0 \ldots N-1

    Parameters
    ----------
    images : sequence of array_like (H, W) or (H, W, 3)
        The views (a list or tuple; a single array is refused as ambiguous).
    pattern_size : (int, int) or "auto"
        ``(cols, rows)`` inner corners, the same for every view; ``"auto"``: every view is
        searched with :func:`find_checkerboard`'s ``"auto"``, the set's size is the one most
        views show (:func:`set_pattern_size`), and the views that showed another size or none
        are searched again for that size.
    names : sequence of str, optional
        Names of the views (file names) used in messages; default ``view 0``, ``view 1`` ...
    **options
        Passed to :func:`find_checkerboard` (``refine``, ``sigma``, ``half_window``, ``method``,
        ...).

    Returns
    -------
    list of CheckerboardResult
        One per view, in order.

    Raises
    ------
    InvalidInputError
        No views, a bad view (its name in the message), views of different sizes,
        ``names`` of the wrong length, a bad ``pattern_size``.

    Notes
    -----
    The set-level checks mirror what calibration needs (Zhang 2000, "A flexible new
    technique for camera calibration", sec. 3: one camera, several views of one planar
    pattern).

    Examples
    --------
    >>> import numpy as np
    >>> v, u = np.mgrid[0:140, 0:160]
    >>> i, j = (u - 20) // 20, (v - 20) // 20
    >>> dark = (i >= 0) & (i < 6) & (j >= 0) & (j < 5) & ((i + j) % 2 == 0)
    >>> board = np.where(dark, 0.1, 0.9)
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     res = find_checkerboards([board, np.full((140, 160), 0.5)], (5, 4))
    >>> [r.found for r in res], caught[0].category.__name__
    ([True, False], 'CheckerboardNotFoundWarning')
    """
    if isinstance(images, str | bytes) or not isinstance(images, Sequence):
        raise InvalidInputError(
            "expected images as a list or tuple of images, got "
            f"{type(images).__name__}; wrap a single image in a list"
        )
    if len(images) == 0:
        raise InvalidInputError("expected at least one image, got an empty sequence")
    if names is None:
        labels = [f"view {k}" for k in range(len(images))]
    else:
        if isinstance(names, str | bytes) or not isinstance(names, Sequence):
            raise InvalidInputError(
                f"expected names as a list of str, one per image, got {describe(names)}"
            )
        labels = [str(n) for n in names]
        if len(labels) != len(images):
            raise InvalidInputError(
                f"expected {len(images)} names (one per image of images), got {len(labels)}"
            )
    size = _check_pattern_or_auto(pattern_size)
    grays = []
    for label, image in zip(labels, images, strict=True):
        try:
            grays.append(as_gray(image))
        except InvalidInputError as exc:
            raise InvalidInputError(f"{label}: {exc}") from exc
    shapes = [g.shape for g in grays]
    if len(set(shapes)) > 1:
        odd = next(k for k, sh in enumerate(shapes) if sh != shapes[0])
        raise InvalidInputError(
            "expected all images of one size (one camera, one resolution), got "
            f"{labels[0]} of {shapes[0][1]} x {shapes[0][0]} px and {labels[odd]} of "
            f"{shapes[odd][1]} x {shapes[odd][0]} px"
        )
    if size == (0, 0):
        first = [find_checkerboard(g, "auto", **options) for g in grays]
        common = set_pattern_size([r.pattern_size if r.found else None for r in first])
        if common is None:
            missing = [f"{lab} ({r.reason})" for lab, r in zip(labels, first, strict=True)]
            warnings.warn(
                f"no complete checkerboard (pattern_size 'auto') in any of the {len(first)} "
                "views: " + "; ".join(missing),
                CheckerboardNotFoundWarning,
                stacklevel=2,
            )
            return first
        size = common
        results = [
            r if r.found and r.pattern_size == size else find_checkerboard(g, size, **options)
            for r, g in zip(first, grays, strict=True)
        ]
    else:
        results = [find_checkerboard(g, size, **options) for g in grays]
    missing = [f"{lab} ({r.reason})" for lab, r in zip(labels, results, strict=True) if not r.found]
    if missing:
        warnings.warn(
            f"no complete {size[0]} x {size[1]} checkerboard in {len(missing)} of "
            f"{len(results)} views: " + "; ".join(missing),
            CheckerboardNotFoundWarning,
            stacklevel=2,
        )
    return results
