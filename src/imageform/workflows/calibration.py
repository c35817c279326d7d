"""Calibration workflows: calibrate (checkerboard views to a camera file) and undistort."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import (
    ConvergenceError,
    DegenerateConfigurationError,
    InvalidInputError,
    UnreadableFileError,
)
from imageform.workflows._images import (
    ImageIn,
    ImageOut,
    image_out_renames,
    not_read,
    read,
    write,
)
from imageform.workflows._spec import (
    IMAGE_SUFFIXES,
    Input,
    Output,
    Result,
    Run,
    Workflow,
    normalize_choice,
    option,
)

__all__ = [
    "MAX_BOARD_CORNERS",
    "MIN_VIEWS",
    "WORKFLOWS",
    "CalibrateOptions",
    "UndistortOptions",
    "board_hint",
    "board_reading",
    "is_auto_board",
    "parse_board",
]

#: Fewest views with the board that ``imageform calibrate`` accepts: Zhang's method gets two
#: constraints on K per view of a plane, so three views determine fx, fy, cx, cy (and skew)
#: with redundancy left for the distortion.
MIN_VIEWS = 3
#: Most inner corners per row or column of a board.
MAX_BOARD_CORNERS = 200
#: Fewest pixels a square of the board may span (the detector needs about 5 sigma).
_MIN_SQUARE_PX = 4
#: The lens models of ``--model`` (``calibrate_camera``'s names; ``-`` and ``_`` are one).
Model = Literal["brown_conrady", "rational", "kannala_brandt"]
#: The sub-pixel refinement of a checkerboard's corners (find_checkerboard's ``method``).
Refinement = Literal["symmetric", "gradient"]
#: ``--refinement``'s help, the same for calibrate and stereo-calibrate.
REFINEMENT_HELP = (
    "Sub-pixel refinement of a checkerboard's corners: symmetric (each corner at the centre of "
    "the board's point symmetry, Schöps et al. 2020; the most accurate on real views) or "
    "gradient (OpenCV's cornerSubPix alone, to reproduce its figures). ChArUco boards the same "
    "(symmetric: the markers left out of the symmetry)."
)


_BOARD = re.compile(
    r"\s*(\d{1,9})\s*[xX×]\s*(\d{1,9})\s*(corners|inner[ _-]?corners|inner|squares)?\s*",
    re.IGNORECASE,
)


def _board_counts(text: str, what: str) -> tuple[int, int, str | None]:
    """``(cols, rows, unit)`` of ``COLSxROWS[corners|squares]``; unit None when not given."""
    from imageform._validate import describe

    m = _BOARD.fullmatch(text) if isinstance(text, str) else None
    if not m:
        raise InvalidInputError(
            f"expected the --board text as {what} (e.g. 9x6, 9x6corners or 10x7squares), got "
            f"{describe(text)}"
        )
    unit = m.group(3)
    if unit is not None:
        unit = "squares" if unit.lower() == "squares" else "corners"
    return int(m.group(1)), int(m.group(2)), unit


def parse_board(text: str) -> tuple[int, int]:
    """``"9x6"`` -> ``(9, 6)``: inner corners per row x per column (OpenCV's patternSize).

    A bare count is of inner corners; ``"9x6corners"`` says so, ``"10x7squares"`` counts the
    squares instead (one more each way: the same board). Each count of inner corners must be 2
    to :data:`MAX_BOARD_CORNERS`: a row of one corner has no squares on both sides, and larger
    boards are not made.

    Examples
    --------
    >>> parse_board("9x6"), parse_board("9x6 corners"), parse_board("10x7squares")
    ((9, 6), (9, 6), (9, 6))
    """
    from imageform._validate import describe

    cols, rows, unit = _board_counts(text, "COLSxROWS of inner corners")
    if unit == "squares":
        cols, rows = cols - 1, rows - 1
    for n in (cols, rows):
        if not 2 <= n <= MAX_BOARD_CORNERS:
            raise InvalidInputError(
                f"expected the --board text as COLSxROWS with 2 to {MAX_BOARD_CORNERS} inner "
                f"corners each (a checkerboard of 3 x 3 squares has 2x2), got {describe(text)}"
            )
    return cols, rows


#: ``--board`` prefix of a ChArUco board (its size in squares follows).
CHARUCO_PREFIX = "charuco:"
#: Fewest ChArUco corners a view must give to be used.
MIN_CHARUCO_CORNERS = 6


def parse_charuco(text: str) -> tuple[int, int] | None:
    """``"charuco:7x5"`` -> ``(7, 5)`` squares per row x per column; None for a checkerboard.

    A bare count is of squares (as OpenCV's CharucoBoard); ``"charuco:6x4corners"`` counts the
    inner corners instead (one fewer each way: the same board). Each count must be 3 to
    :data:`MAX_BOARD_CORNERS` squares (a board of 3 x 3 squares has four inner corners).

    Examples
    --------
    >>> parse_charuco("charuco:7x5"), parse_charuco("charuco:6x4corners"), parse_charuco("9x6")
    ((7, 5), (7, 5), None)
    """
    from imageform._validate import describe

    if not isinstance(text, str) or not text.strip().lower().startswith(CHARUCO_PREFIX):
        return None
    body = text.strip()[len(CHARUCO_PREFIX) :]
    m = _BOARD.fullmatch(body)
    cols = rows = 0
    if m:
        cols, rows, unit = _board_counts(body, "charuco:COLSxROWS of squares")
        if unit == "corners":
            cols, rows = cols + 1, rows + 1
    if not m or not all(3 <= n <= MAX_BOARD_CORNERS for n in (cols, rows)):
        raise InvalidInputError(
            f"expected the --board text charuco:COLSxROWS with 3 to {MAX_BOARD_CORNERS} "
            f"squares each (e.g. charuco:7x5), got {describe(text)}"
        )
    return cols, rows


def is_auto_board(text: str) -> bool:
    """Return whether a ``--board`` text asks for the checkerboard's size to be found (auto).

    Examples
    --------
    >>> is_auto_board("auto"), is_auto_board(" AUTO "), is_auto_board("9x6")
    (True, True, False)
    """
    return isinstance(text, str) and text.strip().lower() == "auto"


def board_hint(text: str) -> str:
    """Return the hint for a board not found: what ``text`` counts, and the other spelling.

    Examples
    --------
    >>> board_hint("9x6")
    "check --board: '9x6' counts inner corners; a board of 9x6 squares is --board 9x6squares"
    """
    r = board_reading(text)
    if r["type"] == "charuco" or r["read_as"] == "squares":
        return f"check --board: {r['line'][len('board: ') :]}"
    c = "x".join(str(n) for n in r["inner_corners"])
    given = text.strip()
    if given.lower().endswith("corners"):
        return f"check --board: {given!r} counts inner corners"
    return (
        f"check --board: {given!r} counts inner corners; a board of {c} squares is "
        f"--board {c}squares"
    )


def board_reading(text: str) -> dict[str, Any]:
    """Say how a ``--board`` text was read: the board's type, its corners and squares.

    ``read_as`` is ``"inner corners"`` or ``"squares"``: what the two numbers given count (a
    bare checkerboard count is of inner corners, a bare ChArUco count of squares); ``line``
    says it in one line for a person.

    Examples
    --------
    >>> board_reading("10x7squares")["line"]
    "board: checkerboard, 9x6 inner corners = 10x7 squares ('10x7squares' counts squares)"
    >>> board_reading("9x6")["read_as"], board_reading("9x6")["squares"]
    ('inner corners', [10, 7])
    >>> board_reading("charuco:7x5")["read_as"], board_reading("charuco:7x5")["inner_corners"]
    ('squares', [6, 4])
    """
    charuco = parse_charuco(text)
    kind = "charuco" if charuco is not None else "checkerboard"
    body = text.strip()[len(CHARUCO_PREFIX) :] if charuco is not None else text
    unit = _board_counts(body, "COLSxROWS")[2]
    if charuco is not None:
        squares = charuco
        corners = (squares[0] - 1, squares[1] - 1)
    else:
        corners = parse_board(text)
        squares = (corners[0] + 1, corners[1] + 1)
    read_as = {"squares": "squares", "corners": "inner corners"}.get(unit or "", "")
    default = not read_as
    if default:
        read_as = "squares" if charuco is not None else "inner corners"
    name = "ChArUco" if charuco is not None else "checkerboard"
    c, q = f"{corners[0]}x{corners[1]}", f"{squares[0]}x{squares[1]}"
    sizes = f"{q} squares = {c} inner corners" if charuco else f"{c} inner corners = {q} squares"
    given = body.strip()
    article = "" if charuco is not None else "a "
    how = f"{given!r} counts {read_as}" + (f", the default for {article}{name}" if default else "")
    return {
        "type": kind,
        "inner_corners": list(corners),
        "squares": list(squares),
        "read_as": read_as,
        "line": f"board: {name}, {sizes} ({how})",
    }


def _settle_auto_board(
    files: list[Path],
    dets: list[Any],
    search: Callable[[list[Path], tuple[int, int]], list[Any]],
    noun: str,
) -> tuple[tuple[int, int], str, list[tuple[Path, tuple[int, int]]]]:
    """``--board auto``: the size most of ``files`` show, each searched again for it if need be.

    ``dets`` holds each file's ``find_checkerboard(..., "auto")``; where it showed another size
    or none, it is replaced (in place) by ``search(those files, size)``. Returns the size, the
    output's first line saying how it was found (``noun``: "views", "images") and the files
    that showed another size, with theirs. No board in any file: one-line error.
    """
    from imageform.geometry.checkerboard import set_pattern_size

    size = set_pattern_size([d.pattern_size if d.found else None for d in dets])
    if size is None:
        raise DegenerateConfigurationError(
            f"no checkerboard found in any of the {len(files)} images ({files[0].name}: "
            f"{dets[0].reason}{'; ...' if len(files) > 1 else ''}); --board auto looks for "
            "boards of at least 3x3 inner corners: give the board's size with --board COLSxROWS"
        )
    agree = sum(d.found and d.pattern_size == size for d in dets)
    other = [(f, d.pattern_size) for f, d in zip(files, dets, strict=True)
             if d.found and d.pattern_size != size]  # fmt: skip
    again = [i for i, d in enumerate(dets) if not d.found or d.pattern_size != size]
    if again:
        for i, d in zip(again, search([files[i] for i in again], size), strict=True):
            dets[i] = d
    cols, rows = size
    line = (
        f"board: checkerboard, {cols}x{rows} inner corners = {cols + 1}x{rows + 1} squares "
        f"(--board auto: {agree} of the {len(files)} {noun} sized alone show it)"
    )
    return size, line, other


def _auto_board_reading(size: tuple[int, int], line: str) -> dict[str, Any]:
    """:func:`board_reading` of the size ``--board auto`` found, with the line saying how."""
    reading = board_reading(f"{size[0]}x{size[1]}")
    reading["line"], reading["read_as"] = line, "auto"
    return reading


class _BoardChecks:
    """The option checks a checkerboard calibration shares (``calibrate``, ``stereo-calibrate``).

    The board, the square size, ``--fix`` names (those of ``--model`` where the command has
    one, else Brown-Conrady's), ``--skew``, ``--half-window``. Mixed in before the options' base
    class; adds no field.
    """

    board: str
    square: str
    fix: tuple[str, ...]
    skew: bool
    half_window: int | None

    def check(self) -> None:
        super().check()  # type: ignore[misc]
        if is_auto_board(self.board):
            pass  # the checkerboard's size is found from the views
        elif parse_charuco(self.board) is None:
            parse_board(self.board)
        elif not hasattr(self, "marker"):
            raise InvalidInputError(
                "a ChArUco --board is read by imageform calibrate; this command takes a "
                "checkerboard --board COLSxROWS of inner corners"
            )
        self.square_mm()
        from imageform.geometry.calibration_refine import global_names

        model = getattr(self, "model", "brown_conrady")
        names = global_names(model)
        what = "--fix" if model == "brown_conrady" else f"--fix (--model {model.replace('_', '-')})"
        fixed = tuple(normalize_choice(f, names, what) for f in self.fix)
        object.__setattr__(self, "fix", fixed)
        if self.skew and "skew" in fixed:
            raise InvalidInputError("--skew estimates the skew; --fix skew holds it: not both")
        if self.half_window is not None and not 1 <= self.half_window <= 50:
            raise InvalidInputError(
                f"expected --half-window 1 to 50 pixels, got {self.half_window}"
            )

    def square_mm(self) -> float:
        """Return the square size in millimetres (0.1 um to 1000 m: beyond, the fit fails)."""
        from imageform._units import parse_length

        mm = parse_length(self.square, "--square", default_unit="mm", unit="mm")
        if not SQUARE_MM[0] * (1 - 1e-9) <= mm <= SQUARE_MM[1] * (1 + 1e-9):
            raise InvalidInputError(
                f"expected --square from 0.1um to 1000m (a printed board: 2mm to 100mm), got "
                f"{self.square}"
            )
        return mm


#: The sizes of a square ``--square`` takes, in mm: calibrations of views of the same board with
#: squares of 1e-12 mm to 1e9 mm agree to the printed digits; 1e-20 mm and 1e12 m do not converge.
SQUARE_MM = (1e-4, 1e6)


@contextmanager
def _converging(max_iter: int) -> Iterator[None]:
    """Say ``--max-iter`` (the command's option) where the library advises its ``max_iter``."""
    try:
        yield
    except ConvergenceError as exc:
        text = str(exc).replace("raise max_iter", f"raise --max-iter (now {max_iter})")
        raise ConvergenceError(text) from exc


# ---------------------------------------------------------------- calibrate

#: The figure files ``--plot`` writes.
_PLOT_SUFFIXES = (".png", ".svg", ".pdf")


@dataclass(frozen=True, kw_only=True)
class CalibrateOptions(_BoardChecks, ImageIn):
    """Options of ``imageform calibrate``."""

    board: str = option(
        "auto",
        help="Checkerboard COLSxROWS of inner corners (9x6), or say which with 9x6corners or "
        "10x7squares; auto: a checkerboard of the size most views show; a ChArUco board "
        "charuco:COLSxROWS of squares (charuco:7x5, or charuco:6x4corners; with --marker). "
        "The output says how it was read.",
        metavar="CxR",
    )
    square: str = option(
        "1",
        help="Side of a square with unit (25mm, 2.5cm, 1in; bare number: mm). Only poses and "
        "--corners depend on it (the default counts them in squares).",
    )
    plot: Path | None = option(
        None, help="Also write a reprojection-error plot (PNG, SVG or PDF).", output=True
    )
    corners: Path | None = option(
        None,
        help="Also write the detected corners: CSV of image, X, Y, Z (board, in mm), u, v; "
        "imageform pose and triangulate read it.",
        output=True,
    )
    half_window: int | None = option(
        None, help="Sub-pixel window half size in pixels (OpenCV's tutorial: 11); default adaptive."
    )
    refinement: Refinement = option("symmetric", help=REFINEMENT_HELP, choices=get_args(Refinement))
    partial: bool = option(
        False,
        help="Also use views where the checkerboard is cut by the image's border or partly "
        "hidden: the largest part found (at least 3x3 and 12 inner corners), labelled in its "
        "own lattice (valid for the intrinsics; the corners near the border are where the "
        "distortion is strongest). The table says which views are partial.",
    )
    fix: tuple[str, ...] = option(
        (),
        help="Hold a parameter at its initial value (repeatable): fx, fy, cx, cy, skew and the "
        "model's k1, k2, p1, p2, k3 (brown-conrady; rational also k4, k5, k6; kannala-brandt "
        "k1, k2, k3, k4).",
        metavar="NAME",
    )
    skew: bool = option(False, help="Estimate the skew (default: 0, as OpenCV).")
    model: Model = option(
        "brown_conrady",
        help="Lens model: brown-conrady (k1, k2, p1, p2, k3; OpenCV's calibrateCamera), "
        "rational (also k4, k5, k6; CALIB_RATIONAL_MODEL, to about 120 deg) or kannala-brandt "
        "(fisheye k1 ... k4; cv::fisheye, to 180 deg). docs/calibration.md says "
        "which to choose.",
        choices=get_args(Model),
    )
    max_iter: int | None = option(
        None,
        help="Most iterations of the Levenberg-Marquardt refinement (default 100; 1000 for "
        "--model rational; raise it when it does not converge).",
        minimum=1,
        maximum=1_000_000,
    )
    marker: str | None = option(
        None,
        help="ChArUco: side of a marker with unit (22mm; bare number: mm), smaller than "
        "--square; needed with --board charuco:COLSxROWS.",
    )
    dictionary: str = option(
        "6x6_250",
        help="ChArUco: the markers' ArUco dictionary (OpenCV's: 4x4_50 ... 7x7_1000, "
        "aruco_original).",
        choices="imageform.geometry.aruco:ARUCO_DICTIONARIES",
    )
    first_marker: int = option(
        0,
        help="ChArUco: the dictionary id of the board's first marker (the others follow), "
        "for a board of a rig of several from one dictionary.",
        minimum=0,
        maximum=1023,
    )

    def check(self) -> None:
        """Check the board; a ChArUco board needs a ``--marker`` smaller than ``--square``."""
        from imageform._validate import describe

        super().check()
        if self.plot is not None and self.plot.suffix.lower() not in _PLOT_SUFFIXES:
            raise InvalidInputError(
                f"expected --plot as a .png, .svg or .pdf file, got {describe(self.plot.name, 60)}"
            )
        charuco = parse_charuco(self.board)
        if charuco is not None and self.partial:
            raise InvalidInputError(
                "--partial is for a checkerboard --board; ChArUco views are used in part already"
            )
        if charuco is None:
            if self.marker is not None:
                raise InvalidInputError("--marker is for a ChArUco --board charuco:COLSxROWS")
            if self.first_marker:
                raise InvalidInputError("--first-marker is for a ChArUco --board charuco:COLSxROWS")
            return
        if self.marker is None:
            raise InvalidInputError(
                "--board charuco:COLSxROWS needs --marker, the side of a marker (e.g. 22mm)"
            )
        if not self.marker_mm() < self.square_mm():
            raise InvalidInputError(
                f"expected --marker smaller than --square, got {self.marker} and {self.square}"
            )

    def marker_mm(self) -> float:
        """Return the marker size in millimetres (ChArUco)."""
        from imageform._units import parse_length

        if self.marker is None:
            raise InvalidInputError("--board charuco:COLSxROWS needs --marker (e.g. 22mm)")
        return parse_length(self.marker, "--marker", default_unit="mm", unit="mm")


def _plot(path: Path, res: Any, names: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.5))
    for name, r in zip(names, res.residuals, strict=True):
        ax1.scatter(r[:, 0], r[:, 1], s=6, label=name)
    ax1.set_xlabel("u error (px)")
    ax1.set_ylabel("v error (px)")
    ax1.set_aspect("equal")
    ax1.set_title(f"reprojection errors (RMS {res.rms:.4f} px)")
    ax2.bar(np.arange(len(names)), res.per_view_rms)
    ax2.set_xticks(np.arange(len(names)), names, rotation=60, ha="right", fontsize=7)
    ax2.set_ylabel("RMS per view (px)")
    fig.tight_layout()
    fig.savefig(path, dpi=100, format=path.suffix.lstrip(".").lower() or "png")
    plt.close(fig)


def _read_views(run: Run, opts: CalibrateOptions, images: list[Path]) -> Iterator[tuple[Path, Any]]:
    """Read each image as ``(path, grey or RGB array)``, with progress, all of one size.

    Images of different sizes are refused in one line naming both files; progress "calibrating" once
    they are read. A file a folder or a glob pattern stood for (``run.gathered``) that cannot be
    read is skipped with a note naming it; a file named is refused.
    """
    shape0: tuple[int, ...] | None = None
    for i, f in enumerate(images):
        if run.progress is not None:
            run.progress("detecting", i / max(len(images), 1))
        try:
            img = read(f, opts)
        except UnreadableFileError as exc:
            if f not in run.gathered:
                raise
            run.note(f"warning: {f}: skipped, cannot be read ({exc.brief})")
            continue
        if shape0 is None:
            shape0 = tuple(img.shape[:2])
        elif img.shape[:2] != shape0:
            raise InvalidInputError(
                f"expected all images of one size, got {images[0]} of {shape0[1]} x "
                f"{shape0[0]} px and {f} of {img.shape[1]} x {img.shape[0]} px"
            )
        yield f, img[..., 0] if img.shape[-1] == 1 else img
    if run.progress is not None:
        run.progress("calibrating", 1.0)


def calibrate(run: Run, opts: CalibrateOptions, *, out: Path, images: list[Path]) -> Result:
    """``imageform calibrate``: a camera file from checkerboard views.

    Zhang, then Levenberg-Marquardt on every reprojection error.
    """
    from imageform._kernels import ahead
    from imageform.geometry import checkerboard_points
    from imageform.geometry.checkerboard import find_checkerboard

    charuco = parse_charuco(opts.board)
    if charuco is not None:
        return _calibrate_charuco(run, opts, out=out, images=images, squares=charuco)
    auto = is_auto_board(opts.board)
    cols, rows = (0, 0) if auto else parse_board(opts.board)
    ahead.start("calibrate")  # a first run: its kernels compiled on two cores
    square = opts.square_mm()
    shape0: tuple[int, int] | None = None
    dets: list[Any] = []  # each view's detection, in the images' order
    n_given = len(images)
    read_ok: list[Path] = []  # the images read (those that cannot be are skipped with a note)
    for f, grey in _read_views(run, opts, images):
        read_ok.append(f)
        if shape0 is None:
            shape0 = (int(grey.shape[0]), int(grey.shape[1]))
            h, w = shape0
            if not auto and ((cols + 1) * _MIN_SQUARE_PX > w or (rows + 1) * _MIN_SQUARE_PX > h):
                raise InvalidInputError(
                    f"a {cols}x{rows} board cannot be seen in {w} x {h} px images "
                    f"({f}): each of its {cols + 1} x {rows + 1} squares needs at least "
                    f"{_MIN_SQUARE_PX} px; {board_hint(opts.board)}"
                )
        dets.append(
            find_checkerboard(
                grey,
                "auto" if auto else (cols, rows),
                half_window=opts.half_window,
                method=opts.refinement,
                partial=opts.partial and not auto,
            )
        )
    if not read_ok:  # every file was skipped: the first one's own reason
        try:
            read(images[0], opts)
        except InvalidInputError as exc:
            raise DegenerateConfigurationError(
                f"none of the {n_given} images can be read ({exc})"
            ) from None
    images = read_ok
    unread = not_read(n_given, len(images))
    reading = None
    if auto:

        def search(files: list[Path], size: tuple[int, int]) -> list[Any]:
            return [find_checkerboard(g, size, half_window=opts.half_window,
                                      method=opts.refinement, partial=opts.partial)
                    for _, g in _read_views(run, opts, files)]  # fmt: skip

        (cols, rows), line, other = _settle_auto_board(images, dets, search, "views")
        for f, (c, r) in other:
            run.note(
                f"note: {f}: a {c}x{r} board, not the {cols}x{rows} of most views: "
                f"searched again for {cols}x{rows}"
            )
        reading = _auto_board_reading((cols, rows), line)
    missed = [(f, d.reason) for f, d in zip(images, dets, strict=True) if not d.found]
    for f, why in missed:
        run.note(f"warning: {f}: no {cols}x{rows} board found ({why})")
    names = [f.name for f, d in zip(images, dets, strict=True) if d.found]
    corners = [d.corners for d in dets if d.found]
    parts = [d.pattern_size if d.partial else None for d in dets if d.found]
    if not corners:
        raise DegenerateConfigurationError(
            f"no {cols}x{rows} checkerboard found in any of the {len(images)} images{unread} "
            f"({missed[0][0].name}: {missed[0][1]}{'; ...' if len(missed) > 1 else ''}; "
            f"{board_hint(opts.board)})"
        )
    if len(corners) < MIN_VIEWS:
        raise DegenerateConfigurationError(
            f"found the {cols}x{rows} board in {len(corners)} view(s) ({', '.join(names)}) of "
            f"{len(images)}{unread}; "
            f"calibrate needs at least {MIN_VIEWS} (one view of a plane gives two constraints "
            "on K: fewer views leave the focal length and the principal point undetermined)"
        )
    assert shape0 is not None
    obj = checkerboard_points((cols, rows), square)
    objs = [obj if p is None else checkerboard_points(p, square) for p in parts]
    command = f"imageform calibrate --board {cols}x{rows} --square {opts.square}"
    if opts.partial:
        command += " --partial"
    return _calibrate_views(
        run,
        opts,
        out,
        n_given,
        names,
        objs,
        corners,
        shape0,
        command,
        reading=reading,
        parts=parts if opts.partial else None,
    )


def _calibrate_views(
    run: Run,
    opts: CalibrateOptions,
    out: Path,
    n_images: int,
    names: list[str],
    objs: list[Any],
    corners: list[Any],
    shape: tuple[int, int],
    command: str,
    *,
    reading: dict[str, Any] | None = None,
    parts: list[tuple[int, int] | None] | None = None,
) -> Result:
    """Calibrate from the views' board points and corners and write the camera file.

    The plot and corners table asked for are written too, and the result says what was found.
    ``reading``: how the board was read where it is not ``board_reading(opts.board)``
    (``--board auto``: the size found, :func:`_auto_board_reading`). ``parts`` (``--partial``):
    per view the ``(cols, rows)`` of the part of the board found, None for a whole one; the
    table then counts each view's corners and says which are partial.
    """
    import numpy as np

    from imageform.geometry import calibrate_camera
    from imageform.geometry.calibration import DEFAULT_MAX_ITER
    from imageform.geometry.calibration_refine import MODEL_COEFFICIENTS
    from imageform.io import CameraFile, write_camera
    from imageform.workflows._tables import write_table

    max_iter = DEFAULT_MAX_ITER[opts.model] if opts.max_iter is None else opts.max_iter
    with _converging(max_iter):
        res = calibrate_camera(
            objs,
            corners,
            (shape[1], shape[0]),
            skew=opts.skew,
            fix=opts.fix,
            max_iter=max_iter,
            model=opts.model,
        )
    if opts.model != "brown_conrady":
        command += f" --model {opts.model.replace('_', '-')}"
    command += "".join(f" --fix {p}" for p in opts.fix) + (" --skew" if opts.skew else "")
    cf = CameraFile.from_calibration(res, images=names, command=command)
    write_camera(run.file(out), cf)
    if opts.plot is not None:
        _plot(run.file(opts.plot), res, names)
    if opts.corners is not None:
        write_table(
            run.file(opts.corners),
            ("image", "X", "Y", "Z", "u", "v"),
            (
                (n, *X, *uv)
                for n, o, c in zip(names, objs, corners, strict=True)
                for X, uv in zip(o, c, strict=True)
            ),
        )
    per_view = [
        {"view": n, "rms_px": float(e), "max_px": float(np.max(p)), "points": len(c)}
        for n, e, p, c in zip(names, res.per_view_rms, res.per_point_errors, corners, strict=True)
    ]
    if parts is not None:
        for row, part in zip(per_view, parts, strict=True):
            row["partial"] = None if part is None else list(part)
    K, d = res.K, res.distortion
    coef_names = MODEL_COEFFICIENTS[res.model]
    board = board_reading(opts.board) if reading is None else reading
    summary = {
        "output": out,
        "views_used": len(names),
        "views_total": n_images,
        "views_partial": None if parts is None else sum(p is not None for p in parts),
        "image_size": list(res.image_size),
        "rms_px": res.rms,
        "fx": K[0, 0],
        "fy": K[1, 1],
        "cx": K[0, 2],
        "cy": K[1, 2],
        "skew": K[0, 1],
        "model": res.model,
        "distortion": {
            "model": "kannala_brandt" if res.model == "kannala_brandt" else "brown_conrady",
            **dict(zip(coef_names, d.coeffs[: len(coef_names)], strict=True)),
        },
        "board": {k: v for k, v in board.items() if k != "line"},
        "std": res.std,
        "fixed": list(res.fixed),
        "per_view": per_view,
        "plot": opts.plot,
        "corners": opts.corners,
    }
    text = [board["line"], f"{'view':<24} {'RMS px':>8} {'max px':>8}"]
    text += [f"{r['view']:<24} {r['rms_px']:8.4f} {r['max_px']:8.4f}" for r in per_view]
    over = f"{len(names)} views"
    if parts is not None:
        text[1] += f" {'corners':>8}  part"
        for k, (r, part) in enumerate(zip(per_view, parts, strict=True), start=2):
            what = "whole" if part is None else f"partial {part[0]}x{part[1]}"
            text[k] += f" {r['points']:8d}  {what}"
        n_part = sum(p is not None for p in parts)
        over += f" ({n_part} partial, {sum(len(c) for c in corners)} corners)"
    text.append(
        f"RMS {res.rms:.4f} px over {over}; fx {K[0, 0]:.3f} ± {res.std['fx']:.3f}, "
        f"fy {K[1, 1]:.3f} ± {res.std['fy']:.3f}, cx {K[0, 2]:.3f}, cy {K[1, 2]:.3f}"
    )
    coefs = ", ".join(f"{c:.6g}" for c in d.coeffs[: len(coef_names)])
    label = ", ".join(coef_names)
    if res.model != "brown_conrady":
        label = f"{res.model.replace('_', '-')} {label}"
    text.append(f"{label}: {coefs}")
    text.append(f"wrote {out}")
    return Result(summary, tuple(text))


def _calibrate_charuco(
    run: Run,
    opts: CalibrateOptions,
    *,
    out: Path,
    images: list[Path],
    squares: tuple[int, int],
) -> Result:
    """``imageform calibrate --board charuco:COLSxROWS``: calibrate from ChArUco views.

    Every view that gives at least :data:`MIN_CHARUCO_CORNERS` identified corners is used, whole or
    in part.
    """
    from imageform.geometry import CharucoBoard, detect_charuco

    board = CharucoBoard(
        squares,
        opts.square_mm(),
        opts.marker_mm(),
        opts.dictionary,
        first_marker=opts.first_marker,
    )
    cols, rows = squares
    shape0: tuple[int, int] | None = None
    objs, corners, names, missed = [], [], [], []
    first_missed: object = None
    legacy_noted = False
    for f, grey in _read_views(run, opts, images):
        shape0 = (int(grey.shape[0]), int(grey.shape[1]))
        found = detect_charuco(grey, board, method=opts.refinement)
        if found.board.legacy and len(found) and not legacy_noted:
            run.note(
                f"{f}: the markers are in OpenCV's legacy layout (boards of even rows drawn "
                "before OpenCV 4.6: the top-left square white); read as such"
            )
            legacy_noted = True
        if len(found) >= MIN_CHARUCO_CORNERS:
            objs.append(found.object_points())
            corners.append(found.corners)
            names.append(f.name)
        else:
            why = f"{len(found.markers)} markers, {len(found)} corners"
            run.note(f"warning: {f}: too little of the charuco:{cols}x{rows} board ({why})")
            missed.append(f"{f.name}: {why}")
            if first_missed is None and len(found.markers) < 2:
                first_missed = grey
    if len(corners) < MIN_VIEWS:
        hint = _dictionary_hint(first_missed, opts.dictionary)
        raise DegenerateConfigurationError(
            f"found at least {MIN_CHARUCO_CORNERS} corners of the charuco:{cols}x{rows} board "
            f"({opts.dictionary} markers) in {len(corners)} view(s) of {len(images)}; "
            f"calibrate needs at least {MIN_VIEWS}"
            + (f" ({missed[0]}{'; ...' if len(missed) > 1 else ''})" if missed else "")
            + hint
        )
    assert shape0 is not None
    command = (
        f"imageform calibrate --board charuco:{cols}x{rows} --square {opts.square} "
        f"--marker {opts.marker} --dictionary {opts.dictionary}"
        + (f" --first-marker {opts.first_marker}" if opts.first_marker else "")
    )
    return _calibrate_views(run, opts, out, len(images), names, objs, corners, shape0, command)


def _dictionary_hint(grey: object, dictionary: str) -> str:
    """Return a hint naming the predefined dictionary a view's markers belong to, else ``""``.

    The hint, ``"; the markers look like 4x4_50: try --dictionary 4x4_50"``, is given when a view
    that showed (almost) no marker of ``dictionary`` shows those of another predefined dictionary.
    """
    if grey is None:
        return ""
    from imageform.geometry import identify_aruco_dictionary

    other = identify_aruco_dictionary(grey)
    if other is None or other == dictionary:
        return ""
    return f"; the markers look like {other}: try --dictionary {other}"


# ---------------------------------------------------------------- undistort


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class UndistortOptions(ImageIn, ImageOut):
    """Options of ``imageform undistort``."""

    camera: Path | None = option(
        None,
        help="Camera file (docs/camera-file.md) of the input image: K and distortion "
        "(or --from-lines).",
        metavar="FILE",
        input=True,
    )
    from_lines: bool = option(
        False,
        help="Estimate the distortion from the image's own straight lines (plumb lines; "
        "the one-parameter division model about the image centre) instead of a camera file.",
    )
    estimate: Path | None = option(
        None,
        help="With --from-lines: also write the estimate as a camera file (division model; "
        "its focal length is the centre-to-corner distance, not a measured one).",
        metavar="FILE",
        output=True,
    )
    camera_out: Path | None = option(
        None,
        help="Also write the camera file of the output: the same camera without distortion "
        "(for imageform vanishing --camera, project, ...).",
        metavar="FILE",
        output=True,
    )


def _from_lines(run: Run, img: Any, image: Path, opts: UndistortOptions) -> tuple[Any, Any]:
    """Return the camera file estimated from the image's straight lines and its summary."""
    import numpy as np

    from imageform.geometry import Camera, estimate_distortion_from_lines
    from imageform.io import CameraFile, Provenance

    arr = np.asarray(img)
    arr = arr[..., 0] if arr.shape[-1] == 1 else arr[..., :3]
    if arr.dtype == np.uint16:
        arr = arr.astype(np.float64) / 65535.0
    res = estimate_distortion_from_lines(arr)
    h, w = int(arr.shape[0]), int(arr.shape[1])
    cam = Camera(res.K, image_size=(w, h), distortion=res.distortion if res.found else None)
    prov = Provenance(
        command="imageform undistort --from-lines",
        rms_px=res.residual_px,
        points_used=sum(len(c) for c in res.lines),
        images=(image.name,),
        fixed=("fx", "fy", "cx", "cy"),
    )
    std = {"k1": res.k1_std} if res.found else {}
    summary = {
        "k1": res.k1,
        "k1_std": res.k1_std,
        "k1_interval": list(res.k1_interval),
        "found": res.found,
        "center": res.center,
        "scale_px": float(res.K[0, 0]),
        "lines": len(res.lines),
        "straightness_rms_px": res.residual_px,
        "straightness_rms_before_px": res.residual_before_px,
        "max_displacement_px": res.max_displacement_px,
        "corner_distortion": res.corner_distortion,
    }
    return CameraFile(cam, std=std, provenance=prov), summary


def undistort(run: Run, opts: UndistortOptions, *, out: Path, image: Path) -> Result:
    """``imageform undistort``: remove lens distortion with the camera file's K and model.

    Inverse mapping, bilinear sampling; the output keeps K.
    """
    import numpy as np

    from imageform.geometry.undistort import undistort_image
    from imageform.io import read_camera, write_camera

    if (opts.camera is None) == (not opts.from_lines):
        raise InvalidInputError("give either --camera FILE or --from-lines")
    if opts.estimate is not None and not opts.from_lines:
        raise InvalidInputError("--estimate needs --from-lines (it writes the estimated camera)")
    img = read(image, opts)
    h, w = int(img.shape[0]), int(img.shape[1])
    lines: dict[str, Any] = {}
    if opts.camera is not None:
        cf = read_camera(opts.camera)
        none = f"{opts.camera} has no distortion (model none)"
    else:
        cf, lines = _from_lines(run, img, image, opts)
        none = f"no distortion found in the straight lines of {image}"
    cam = cf.camera
    if cam.image_size is not None and tuple(cam.image_size) != (w, h):
        raise InvalidInputError(
            f"camera file {opts.camera} is for {cam.image_size[0]} x {cam.image_size[1]} px "
            f"images, {image} is {w} x {h} px"
        )
    model = cf.distortion_model
    if cam.distortion is None:
        run.note(f"note: {none}: the image is copied")
        result = img
    else:
        result = undistort_image(img, np.asarray(cam.K), cam.distortion)
    n_out = write(run, out, np.asarray(result), opts, like=img)
    if opts.camera_out is not None:
        from dataclasses import replace

        from imageform.geometry import Camera

        flat = Camera(cam.K, cam.R, cam.t, (w, h), cam.image_plane, None)
        based_on = opts.camera.name if opts.camera is not None else image.name
        # a new file: its date and imageform version are this writing's, not the source's
        prov = replace(
            cf.provenance,
            command="imageform undistort",
            based_on=based_on,
            date=None,
            imageform_version=None,
        )
        std = {
            k: v for k, v in cf.std.items() if k in ("fx", "fy", "cx", "cy", "skew", "rvec", "t")
        }
        write_camera(run.file(opts.camera_out), replace(cf, camera=flat, std=std, provenance=prov))
    if opts.estimate is not None:
        write_camera(run.file(opts.estimate), cf)
    coeffs = list(cam.distortion.coeffs) if cam.distortion is not None else []
    summary = {
        "input": image,
        "output": out,
        "camera": opts.camera,
        "camera_out": opts.camera_out,
        "shape": list(np.shape(result)),
        "model": model,
        "coefficients": coeffs,
        "values_clipped": n_out,
        "estimate": opts.estimate,
        "from_lines": lines or None,
    }
    text = []
    if lines:
        text.append(
            f"distortion from {lines['lines']} straight lines: division k1 = {lines['k1']:.4f} "
            f"(90 % over the lines {lines['k1_interval'][0]:.4f} to "
            f"{lines['k1_interval'][1]:.4f}; coordinates over {lines['scale_px']:.1f} px from the "
            f"centre), corner {100 * lines['corner_distortion']:+.1f} %, "
            f"{lines['max_displacement_px']:.1f} px; lines straight to "
            f"{lines['straightness_rms_px']:.2f} px RMS ({lines['straightness_rms_before_px']:.2f} "
            "px before)"
            if lines["found"]
            else f"no distortion found from {lines['lines']} straight lines (k1 = "
            f"{lines['k1']:.4f}, the lines' bootstrap 90 % interval "
            f"{lines['k1_interval'][0]:.4f} to {lines['k1_interval'][1]:.4f}: lines from "
            f"{lines['straightness_rms_before_px']:.2f} to {lines['straightness_rms_px']:.2f} "
            "px RMS)"
        )
    removed = "copied, no distortion" if cam.distortion is None else f"{model} distortion removed"
    text.append(f"wrote {out} ({w} x {h}, {removed})")
    if opts.camera_out is not None:
        text.append(f"wrote {opts.camera_out} (the same camera, distortion none)")
    if opts.estimate is not None:
        what = "no distortion found: model none" if model == "none" else f"{model} distortion"
        text.append(f"wrote {opts.estimate} (the estimated camera, {what})")
    return Result(summary, tuple(text))


WORKFLOWS = (
    Workflow(
        "calibrate",
        "Calibrate a camera from checkerboard or ChArUco views: writes the camera file.",
        "imageform.workflows.calibration:calibrate",
        CalibrateOptions,
        (
            Input(
                "images",
                "Image files, folders of them or quoted glob patterns ('views/*.jpg').",
                many=True,
                folders=True,
            ),
        ),
        Output("Camera file to write (TOML, docs/camera-file.md)."),
        suffixes=(".toml",),
        group="geometry",
        description=f"Needs the board in at least {MIN_VIEWS} views. Zhang's closed form (a "
        "fisheye: cv::fisheye's equidistant start too), then Levenberg-Marquardt on all "
        "reprojection errors; K, the --model's coefficients (Brown-Conrady k1, k2, p1, p2, k3 "
        "by default; rational k1 ... k6; Kannala-Brandt fisheye k1 ... k4), their standard "
        "deviations and the RMS go to the camera file.",
    ),
    Workflow(
        "undistort",
        "Remove lens distortion from an image with a camera file (any distortion model), or "
        "estimated from its straight lines (--from-lines).",
        "imageform.workflows.calibration:undistort",
        UndistortOptions,
        (Input("image", "Distorted image (PNG, JPEG, TIFF, .npy, WebP, BMP, GIF, PGM/PPM)."),),
        Output("Undistorted image to write (same size and K)."),
        batch=True,
        suffixes=IMAGE_SUFFIXES,
        group="geometry",
    ),
)
