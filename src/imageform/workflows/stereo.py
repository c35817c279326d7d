"""Stereo workflows: ``imageform stereo-calibrate`` and ``imageform depth``.

``stereo-calibrate``: checkerboard pairs to a stereo camera file; ``depth``: a stereo pair and
that file to a depth or disparity map and a coloured point cloud.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnreadableFileError
from imageform.workflows._images import ImageIn, not_read, read
from imageform.workflows._spec import (
    Input,
    Output,
    Result,
    Run,
    Workflow,
    option,
)
from imageform.workflows.calibration import (
    MIN_VIEWS,
    REFINEMENT_HELP,
    Model,
    Refinement,
    _auto_board_reading,
    _BoardChecks,
    _converging,
    _settle_auto_board,
    board_hint,
    board_reading,
    is_auto_board,
    parse_board,
)

__all__ = ["WORKFLOWS", "DepthOptions", "StereoCalibrateOptions"]

#: The sub-pixel fits of ``--subpixel`` (geometry.stereo_matching.SUBPIXEL_FITS, spelt out
#: here: ``imageform --help`` imports no NumPy).
Subpixel = Literal["equiangular", "parabola"]


@dataclass(frozen=True, kw_only=True)
class StereoCalibrateOptions(_BoardChecks, ImageIn):
    """Options of ``imageform stereo-calibrate``."""

    board: str = option(
        help="Checkerboard COLSxROWS of inner corners (9x6), or say which with 9x6corners or "
        "10x7squares; auto: the size most images show. The output says how it was read.",
        metavar="CxR",
    )
    square: str = option(
        "1",
        help="Side of a square with unit (25mm, 2.5cm, 1in; bare number: mm): the unit of T "
        "(the default counts it in squares).",
    )
    fix: tuple[str, ...] = option(
        (),
        help="Hold a parameter of both cameras at its initial value (repeatable): fx, fy, cx, "
        "cy, skew and the model's k1, k2, p1, p2, k3 (brown-conrady; rational also k4, k5, k6; "
        "kannala-brandt k1, k2, k3, k4).",
        metavar="NAME",
    )
    fix_intrinsics: bool = option(
        False,
        help="Keep both cameras' single-camera intrinsics and distortion; refine only the poses "
        "(OpenCV's CALIB_FIX_INTRINSIC).",
    )
    skew: bool = option(False, help="Estimate the skew of both cameras (default: 0).")
    half_window: int | None = option(
        None, help="Sub-pixel window half size in pixels (OpenCV's tutorial: 11); default adaptive."
    )
    refinement: Refinement = option("symmetric", help=REFINEMENT_HELP, choices=get_args(Refinement))
    model: Model = option(
        "brown_conrady",
        help="Lens model of both cameras: brown-conrady (k1, k2, p1, p2, k3), rational (also "
        "k4, k5, k6) or kannala-brandt (fisheye k1 ... k4), as imageform calibrate --model.",
        choices=get_args(Model),
    )
    max_iter: int | None = option(
        None,
        help="Most iterations of the joint Levenberg-Marquardt refinement (default 100; 1000 for "
        "--model rational; raise it when it does not converge).",
        minimum=1,
        maximum=1_000_000,
    )


def _expand(pattern: str, what: str) -> tuple[list[Path], bool]:
    """Return the files a name, a folder or a glob pattern names, sorted; none is an error.

    And whether they were gathered (a folder or a pattern, not a file named): those may be
    skipped when they cannot be read; a file named not.
    """
    from imageform._files import glob_paths, not_a_regular_file
    from imageform.io import image_files

    p = str(pattern)
    if os.path.exists(p) or not any(c in p for c in "*?["):
        path = Path(p)
        kind = not_a_regular_file(path)
        if kind == "is a folder":
            return image_files(path), True
        if kind is not None:
            raise InvalidInputError(f"{what} {path} {kind}")
        if not path.is_file():
            raise InvalidInputError(f"{what} file {path} does not exist")
        return [path], False
    hits = sorted(glob_paths(p))
    if not hits:
        raise InvalidInputError(f"no files match {what} pattern {p!r}")
    return [Path(h) for h in hits], True


def _check_distinct(left: str, right: str, lefts: list[Path], rights: list[Path]) -> None:
    """Refuse left and right images that are the same files: a camera paired with itself."""
    from imageform._files import same_file

    if str(left) == str(right) or (
        os.path.exists(left) and os.path.exists(right) and same_file(Path(left), Path(right))
    ):
        raise InvalidInputError(
            f"left and right are both {left}; give each camera's own images (a quoted glob "
            "pattern each: 'left/*.png' 'right/*.png')"
        )
    for a in lefts:
        for b in rights:
            if same_file(a, b):
                raise InvalidInputError(
                    f"left and right both name the image {a}; give each camera's own images"
                )


def _detect(
    opts: StereoCalibrateOptions,
    files: list[Path],
    board: tuple[int, int] | Literal["auto"],
    skip: bool = False,
) -> tuple[tuple[int, int] | None, list[Any]]:
    """Each image's checkerboard (``board``: its inner corners, or ``"auto"``), all of one size.

    Returns the images' size ``(W, H)`` (None when none was read) and each image's
    ``CheckerboardResult``; with ``skip`` (the files of a folder or a glob pattern), a file
    that cannot be read gets instead the reason, a str (``UnreadableFileError.brief``).
    """
    from imageform.geometry.checkerboard import find_checkerboard

    size: tuple[int, int] | None = None
    found: list[Any] = []
    for f in files:
        try:
            img = read(f, opts)
        except UnreadableFileError as exc:
            if not skip:
                raise
            found.append(exc.brief)
            continue
        if size is None:
            size = (int(img.shape[1]), int(img.shape[0]))
        elif (int(img.shape[1]), int(img.shape[0])) != size:
            raise InvalidInputError(
                f"expected all images of one camera of one size, got {files[0]} of {size[0]} x "
                f"{size[1]} px and {f} of {img.shape[1]} x {img.shape[0]} px"
            )
        grey = img[..., 0] if img.shape[-1] == 1 else img
        found.append(
            find_checkerboard(grey, board, half_window=opts.half_window, method=opts.refinement)
        )
    return size, found


def _drop_unreadable(
    run: Run, files: tuple[list[Path], list[Path]], dets: tuple[list[Any], list[Any]]
) -> tuple[list[Path], list[Path], list[Any], list[Any]]:
    """Leave out the pairs with an image that cannot be read, a note naming both images each."""
    keep_l: list[Path] = []
    keep_r: list[Path] = []
    kd_l: list[Any] = []
    kd_r: list[Any] = []
    for fl, fr, dl, dr in zip(*files, *dets, strict=True):
        if isinstance(dl, str) and isinstance(dr, str):
            why = dl if dl == dr else f"{dl}; {dr}"
            run.note(f"warning: {fl} and its pair {fr}: skipped, neither can be read ({why})")
            continue
        if isinstance(dl, str) or isinstance(dr, str):
            bad, why, other = (fl, dl, fr) if isinstance(dl, str) else (fr, dr, fl)
            run.note(f"warning: {bad}: skipped with its pair {other}, cannot be read ({why})")
            continue
        keep_l.append(fl)
        keep_r.append(fr)
        kd_l.append(dl)
        kd_r.append(dr)
    return keep_l, keep_r, kd_l, kd_r


def stereo_calibrate_cmd(
    run: Run, opts: StereoCalibrateOptions, *, out: Path, left: str, right: str
) -> Result:
    """``imageform stereo-calibrate``: a stereo camera file from checkerboard pairs."""
    import numpy as np

    from imageform._kernels import ahead
    from imageform.geometry import checkerboard_points, stereo_calibrate
    from imageform.io import StereoCameraFile, write_stereo_camera

    if str(left) == str(right):
        _check_distinct(left, right, [], [])
    (lefts, gathered_l), (rights, gathered_r) = _expand(left, "left"), _expand(right, "right")
    _check_distinct(left, right, lefts, rights)
    if len(lefts) != len(rights):
        raise InvalidInputError(
            f"expected as many right images as left ones (paired in sorted order), got "
            f"{len(lefts)} left and {len(rights)} right"
        )
    auto = is_auto_board(opts.board)
    board = (0, 0) if auto else parse_board(opts.board)
    ahead.start("stereo-calibrate")  # a first run: its kernels compiled on two cores
    if run.progress is not None:
        run.progress("detecting", 0.0)
    size_l, det_l = _detect(opts, lefts, "auto" if auto else board, gathered_l)
    if run.progress is not None:
        run.progress("detecting", 0.5)
    size_r, det_r = _detect(opts, rights, "auto" if auto else board, gathered_r)
    n_given = len(lefts)
    bad = [(f, d) for f, d in zip(lefts + rights, det_l + det_r, strict=True) if isinstance(d, str)]
    lefts, rights, det_l, det_r = _drop_unreadable(run, (lefts, rights), (det_l, det_r))
    unread = not_read(n_given, len(lefts))
    if bad and len(lefts) < MIN_VIEWS:
        raise DegenerateConfigurationError(
            f"{len(lefts)} of the {n_given} pairs can be read ({bad[0][0]}: {bad[0][1]}"
            f"{'; ...' if len(bad) > 1 else ''}); stereo-calibrate needs at least {MIN_VIEWS}"
        )
    assert size_l is not None and size_r is not None
    reading = None
    if auto:
        both = det_l + det_r

        def search(files: list[Path], size: tuple[int, int]) -> list[Any]:
            return _detect(opts, files, size)[1]  # read before: each can be read

        board, line, _ = _settle_auto_board(lefts + rights, both, search, "images")
        det_l, det_r = both[: len(lefts)], both[len(lefts) :]
        reading = _auto_board_reading(board, line)
    for f, d in zip(lefts + rights, det_l + det_r, strict=True):
        if not d.found:
            run.note(f"warning: {f}: no {board[0]}x{board[1]} board found ({d.reason})")
    pairs = [
        (fl, fr, dl.corners, dr.corners)
        for fl, fr, dl, dr in zip(lefts, rights, det_l, det_r, strict=True)
        if dl.found and dr.found
    ]
    if len(pairs) < MIN_VIEWS:
        raise DegenerateConfigurationError(
            f"found the {board[0]}x{board[1]} board in both images of {len(pairs)} of the "
            f"{len(lefts)} pairs{unread}; stereo-calibrate needs at least {MIN_VIEWS} "
            f"({board_hint(f'{board[0]}x{board[1]}' if auto else opts.board)})"
        )
    if run.progress is not None:
        run.progress("calibrating", 1.0)
    obj = checkerboard_points(board, opts.square_mm())
    from imageform.geometry.calibration import DEFAULT_MAX_ITER

    max_iter = DEFAULT_MAX_ITER[opts.model] if opts.max_iter is None else opts.max_iter
    with _converging(max_iter):
        rig = stereo_calibrate(
            [obj] * len(pairs),
            [p[2] for p in pairs],
            [p[3] for p in pairs],
            size_l,
            image_size_right=size_r,
            fix_intrinsics=opts.fix_intrinsics,
            fix=opts.fix,
            skew=opts.skew,
            max_iter=max_iter,
            model=opts.model,
        )
    command = f"imageform stereo-calibrate --board {board[0]}x{board[1]} --square {opts.square}"
    if opts.model != "brown_conrady":
        command += f" --model {opts.model.replace('_', '-')}"
    command += "".join(f" --fix {p}" for p in opts.fix) + (" --skew" if opts.skew else "")
    command += " --fix-intrinsics" if opts.fix_intrinsics else ""
    sf = StereoCameraFile.from_calibration(
        rig,
        images_left=[p[0].name for p in pairs],
        images_right=[p[1].name for p in pairs],
        command=command,
    )
    write_stereo_camera(run.file(out), sf)
    rvec_deg = np.degrees(rig.rvec)
    std_deg = np.degrees(rig.std_rvec)
    per_pair = [
        {
            "left": p[0].name,
            "right": p[1].name,
            "rms_left_px": float(e[0]),
            "rms_right_px": float(e[1]),
        }
        for p, e in zip(pairs, rig.per_view_rms, strict=True)
    ]
    if reading is None:
        reading = board_reading(opts.board)
    n = len(rig.left.std) - 5  # the model's coefficients
    summary = {
        "output": out,
        "board": {k: v for k, v in reading.items() if k != "line"},
        "pairs_used": len(pairs),
        "pairs_total": n_given,
        "rms_px": rig.rms,
        "R": rig.R.tolist(),
        "rvec_deg": rvec_deg.tolist(),
        "std_rvec_deg": std_deg.tolist(),
        "T": rig.T.tolist(),
        "std_T": rig.std_T.tolist(),
        "baseline": rig.baseline,
        "unit": "mm",
        "model": rig.left.model,
        "left": {"K": rig.left.K.tolist(), "distortion": list(rig.left.distortion.coeffs[:n])},
        "right": {"K": rig.right.K.tolist(), "distortion": list(rig.right.distortion.coeffs[:n])},
        "per_pair": per_pair,
    }
    text = [reading["line"], f"{'left':<20} {'right':<20} {'RMS l px':>8} {'RMS r px':>8}"]
    text += [
        f"{r['left']:<20} {r['right']:<20} {r['rms_left_px']:8.4f} {r['rms_right_px']:8.4f}"
        for r in per_pair
    ]
    text.append(f"RMS {rig.rms:.4f} px over {len(pairs)} pairs; baseline {rig.baseline:.3f} mm")
    text.append(
        "T (mm): " + ", ".join(f"{t:.3f} ± {s:.3f}" for t, s in zip(rig.T, rig.std_T, strict=True))
    )
    text.append(
        "rvec (deg): "
        + ", ".join(f"{r:.4f} ± {s:.4f}" for r, s in zip(rvec_deg, std_deg, strict=True))
    )
    text.append(f"wrote {out}")
    return Result(summary, tuple(text))


@dataclass(frozen=True, kw_only=True)
class DepthOptions(ImageIn):
    """Options of ``imageform depth``."""

    camera: Path = option(
        help="Stereo camera file of the pair (imageform stereo-calibrate's; docs/camera-file.md, "
        "'Stereo rigs').",
        metavar="FILE",
        input=True,
    )
    disparity: bool = option(
        False,
        help="Write the disparity (px, x_left - x_right in the rectified pair; y_left - y_right "
        "for cameras stacked vertically) instead of depth.",
    )
    points: Path | None = option(
        None,
        help="Also write the 3-D points of the valid pixels, coloured by the left image (PLY).",
        metavar="FILE",
        output=True,
    )
    min_disparity: int = option(
        0,
        help="Smallest disparity searched (px; negative when the rectified principal points "
        "are apart, or when the right camera is to the left of or above the left one).",
        minimum=-100_000,
        maximum=100_000,
    )
    num_disparities: int = option(
        64,
        help="How many disparities are searched (px); the nearest depth seen is f B / "
        "(min + num - 1).",
        minimum=1,
        maximum=4096,
    )
    block_size: int = option(5, help="Census window side: 3, 5 or 7 px.", minimum=3, maximum=7)
    p1: int | None = option(
        None,
        help="Penalty of a disparity step of 1 px along a path (bits; default "
        "(block_size^2 - 1) / 3, twice that for the graded census, times the summed block's "
        "pixels divided to fit a byte).",
        minimum=1,
        maximum=7999,
    )
    p2: int | None = option(
        None,
        help="Penalty of a larger disparity step (bits, > --p1; default 4 x --p1, 32 x --p1 "
        "with --adaptive-p2).",
        minimum=2,
        maximum=8000,
    )
    adaptive_p2: bool = option(
        False, help="Divide --p2 by the intensity step along a path (cheaper jumps at edges)."
    )
    uniqueness: float = option(
        0.1,
        help="Margin by which the best disparity must beat any other more than 1 px away "
        "(OpenCV's uniquenessRatio / 100).",
        minimum=0.0,
        maximum=0.99,
    )
    lr_check: float = option(
        1.0,
        help="Largest difference of a disparity and those claiming its right pixel (px; "
        "OpenCV's disp12MaxDiff and rule); larger ones are invalid.",
        minimum=0.0,
        maximum=100_000.0,
    )
    speckle_size: int = option(
        0,
        help="Make invalid the regions of at most this many pixels (0: keep all; OpenCV's "
        "speckleWindowSize).",
        minimum=0,
        maximum=1_000_000_000,
    )
    speckle_range: float = option(
        1.0,
        help="Largest disparity difference of neighbours within one region (px).",
        minimum=0.0,
        maximum=100_000.0,
    )
    subpixel: Subpixel = option(
        "equiangular",
        help="Fit of the matching cost around the best disparity for its sub-pixel value: "
        "equiangular (two lines of opposite slopes) or parabola (OpenCV's).",
        choices=get_args(Subpixel),
    )
    median_filter: bool = option(
        False,
        help="Apply the 3 x 3 median OpenCV's StereoSGBM applies to every map: fills "
        "isolated invalid pixels (denser, a few more 1-3 px errors).",
    )
    census_threshold: float = option(
        0.0,
        help="Grey levels (0-255) by which a neighbour must be darker than the centre to "
        "count in the census (0: any darker). With --census-step 0, 2-4 for views with flat "
        "regions (a board's squares, a dim endoscope): fewer errors there, less fine texture "
        "matched.",
        minimum=0.0,
        maximum=255.0,
    )
    census_step: float = option(
        4.0,
        help="Grey levels (0-255) of the graded census's second bit: a neighbour darker by "
        "more than this counts twice, so faint shading and noise weigh half as much as "
        "texture. 0: the plain census (one bit a neighbour).",
        minimum=0.0,
        maximum=255.0,
    )
    cost_window: int = option(
        3,
        help="Side of the block over which the census costs are summed before the paths "
        "(1, 3, 5 or 7; OpenCV's blockSize sum): averages the sensor noise of flat regions "
        "(a board's squares) out; 1: each pixel's cost alone (before 2026-11-30), 5: flatter "
        "views, less fine detail.",
        minimum=1,
        maximum=7,
    )
    plane_fill: bool = option(
        True,
        help="Give each flat region of the left view (a board's squares, a wall) the plane of "
        "the disparities on its textured rim, where one plane fits 80 % of them and the "
        "images fit the plane about as well as the matched values: slanted surfaces without "
        "texture follow their slant; --no-plane-fill keeps the matched values (before "
        "2026-11-30h).",
    )
    slant_prior: bool = option(
        False,
        help="Match twice: the second time each path follows the slant of the first map's "
        "local planes, so slanted surfaces (ground, walls seen at an angle, a tilted board) "
        "cost no disparity steps along the paths: fewer errors on them, 2-3 times the "
        "matching time.",
    )


def _pair_image(path: Path, opts: DepthOptions, size: tuple[int, int] | None, side: str) -> Any:
    import numpy as np

    img = np.asarray(read(path, opts))
    h, w = int(img.shape[0]), int(img.shape[1])
    if size is not None and (w, h) != tuple(size):
        raise InvalidInputError(
            f"{path} is {w} x {h} px; the {side} camera of {opts.camera} is for {size[0]} x "
            f"{size[1]} px images"
        )
    if img.dtype.kind == "f" and not np.isfinite(img).all():
        raise InvalidInputError(f"{path} holds NaN or inf; give an image of finite values")
    return img


def _check_baseline(rig: Any, camera: Path) -> None:
    """Refuse a rig whose baseline is zero, or zero within its standard deviation (one line)."""
    import numpy as np

    b = float(np.linalg.norm(rig.T))
    std = rig.std_T
    s = float(np.linalg.norm(std)) if std is not None and np.all(np.isfinite(std)) else 0.0
    if not b > 3.0 * s or not b > 0:
        within = f", within 3 standard deviations ({s:.3g}) of zero" if b > 0 else ""
        raise DegenerateConfigurationError(
            f"the baseline of {camera} is {b:.3g}{within}: its two cameras are at one place, "
            "and depth needs them apart (side by side or stacked)"
        )


def _check_disparity_sign(rect: Any, opts: DepthOptions) -> None:
    """Refuse a disparity range that puts every point behind the cameras (one line).

    ``Q`` gives a point in front for ``Q[3, 2] d + Q[3, 3] > 0``: positive disparities when
    the right (second) camera is to the right of (below) the left one, negative when it is
    to the left (above).
    """
    lo = opts.min_disparity
    hi = lo + opts.num_disparities - 1
    Q = rect.Q
    if max(Q[3, 2] * lo + Q[3, 3], Q[3, 2] * hi + Q[3, 3]) > 0:
        return
    where = "above" if rect.vertical else "to the left of"
    raise InvalidInputError(
        f"the disparities searched, {lo} to {hi} px, all put the points behind the cameras: "
        f"the right camera of {opts.camera} is {where} the left one, so the disparities are "
        f"negative: search them with --min-disparity {-hi}"
    )


def depth_cmd(run: Run, opts: DepthOptions, *, out: Path, left: Path, right: Path) -> Result:
    """``imageform depth``: rectify a stereo pair, match it, write depth or disparity."""
    import numpy as np

    from imageform.geometry import (
        disparity_to_depth,
        disparity_to_points,
        rectification_map,
        remap_bilinear,
        stereo_disparity,
    )
    from imageform.geometry.stereo import stereo_rectify
    from imageform.io import read_stereo_camera, write_image
    from imageform.workflows._ply import write_points_ply

    if opts.points is not None and opts.points.suffix.lower() != ".ply":
        raise InvalidInputError(f"--points writes a PLY file: give a .ply name, not {opts.points}")
    if opts.block_size not in (3, 5, 7):
        raise InvalidInputError(f"--block-size must be 3, 5 or 7, got {opts.block_size}")
    if opts.cost_window not in (1, 3, 5, 7):
        raise InvalidInputError(f"--cost-window must be 1, 3, 5 or 7, got {opts.cost_window}")
    if opts.p1 is not None and opts.p2 is not None and not opts.p2 > opts.p1:
        raise InvalidInputError(f"--p2 ({opts.p2}) must exceed --p1 ({opts.p1})")
    _check_distinct(str(left), str(right), [Path(left)], [Path(right)])
    rig = read_stereo_camera(opts.camera)
    cl, cr = rig.left.camera, rig.right.camera
    img_l = _pair_image(Path(left), opts, cl.image_size, "left")
    img_r = _pair_image(Path(right), opts, cr.image_size, "right")
    from imageform._kernels import ahead

    ahead.start("depth")  # a first run: the matching kernels compiled on two cores
    size = (int(img_l.shape[1]), int(img_l.shape[0]))
    _check_baseline(rig, opts.camera)
    rect = stereo_rectify(
        np.asarray(cl.K), cl.distortion, np.asarray(cr.K), cr.distortion, size, rig.R, rig.T
    )
    _check_disparity_sign(rect, opts)
    if run.progress is not None:
        run.progress("rectifying", 0.0)
    map_l = rectification_map(np.asarray(cl.K), cl.distortion, rect.R1, rect.P1, rect.image_size)
    map_r = rectification_map(np.asarray(cr.K), cr.distortion, rect.R2, rect.P2, rect.image_size)
    rl = np.asarray(remap_bilinear(img_l, map_l))
    rr = np.asarray(remap_bilinear(img_r, map_r))
    if run.progress is not None:
        run.progress("matching", 0.2)
    disp = stereo_disparity(
        rl,
        rr,
        min_disparity=opts.min_disparity,
        num_disparities=opts.num_disparities,
        block_size=opts.block_size,
        p1=opts.p1,
        p2=opts.p2,
        adaptive_p2=opts.adaptive_p2,
        uniqueness=opts.uniqueness,
        lr_check=opts.lr_check,
        speckle_size=opts.speckle_size,
        speckle_range=opts.speckle_range,
        subpixel=opts.subpixel,
        median_filter=opts.median_filter,
        census_threshold=opts.census_threshold,
        census_step=opts.census_step,
        cost_window=opts.cost_window,
        plane_fill=opts.plane_fill,
        slant_prior=opts.slant_prior,
        vertical=rect.vertical,
    )
    # left pixels whose source lies outside the left image hold no measurement
    W0, H0 = size
    outside = ~(
        (map_l[..., 0] >= 0) & (map_l[..., 0] <= W0 - 1) & (map_l[..., 1] >= 0)
        & (map_l[..., 1] <= H0 - 1)
    )  # fmt: skip
    disp[outside] = np.nan
    depth = disparity_to_depth(disp, rect)
    valid = np.isfinite(depth)
    result = disp if opts.disparity else depth
    write_image(run.file(out), np.ascontiguousarray(result, dtype=np.float32))
    n_points = 0
    if opts.points is not None:
        pts = disparity_to_points(disp, rect)
        keep = np.isfinite(pts).all(axis=-1)
        col = np.asarray(rl)
        if col.ndim == 2:
            col = col[..., None]
        col = col[..., :3] if col.shape[-1] >= 3 else np.repeat(col[..., :1], 3, axis=-1)
        if col.dtype == np.uint16:
            col8 = (col.astype(np.float64) / 257.0).round()
        elif col.dtype.kind == "f":
            col8 = np.clip(col, 0.0, 1.0) * 255.0
        else:
            col8 = col.astype(np.float64)
        n_points = int(keep.sum())
        write_points_ply(
            run.file(opts.points),
            pts[keep],
            np.clip(np.round(col8[keep]), 0, 255).astype(np.uint8),
            None,
            comment=f"imageform depth {Path(left).name} {Path(right).name} --camera "
            f"{Path(opts.camera).name}: rectified left camera frame, units of T",
        )
    f = float(rect.P1[0, 0])
    baseline = float(np.linalg.norm(rig.T))
    d_ok = disp[valid]
    z_ok = depth[valid]
    summary = {
        "output": out,
        "written": "disparity" if opts.disparity else "depth",
        "points": opts.points,
        "n_points": n_points,
        "size": list(rect.image_size),
        "vertical": bool(rect.vertical),
        "focal_px": f,
        "baseline": baseline,
        "valid_fraction": float(valid.mean()),
        "disparity_range_px": [float(d_ok.min()), float(d_ok.max())] if d_ok.size else None,
        "depth_range": [float(z_ok.min()), float(z_ok.max())] if z_ok.size else None,
        "depth_median": float(np.median(z_ok)) if z_ok.size else None,
    }
    text = [f"rectified {size[0]} x {size[1]} px: f {f:.1f} px, baseline {baseline:.3f}"]
    if rect.vertical:
        text[0] += " (cameras stacked: matched along columns)"
    if d_ok.size:
        text.append(
            f"valid {100 * valid.mean():.1f} % of the pixels; disparity {d_ok.min():.2f} to "
            f"{d_ok.max():.2f} px, depth {z_ok.min():.4g} to {z_ok.max():.4g} (median "
            f"{np.median(z_ok):.4g}) in the units of T"
        )
    else:
        run.note(
            "warning: no pixel has a valid disparity; check --min-disparity and "
            "--num-disparities against the scene's depth"
        )
    what = "disparity (px)" if opts.disparity else "depth (units of T)"
    text.append(f"wrote {out} ({what}, float32, NaN where invalid)")
    if opts.points is not None:
        text.append(f"wrote {opts.points} ({n_points} points)")
    return Result(summary, tuple(text))


WORKFLOWS = (
    Workflow(
        "stereo-calibrate",
        "Calibrate a stereo pair from checkerboard views: writes the stereo camera file.",
        "imageform.workflows.stereo:stereo_calibrate_cmd",
        StereoCalibrateOptions,
        (
            Input(
                "left",
                "The left camera's images: a folder, a file or a quoted glob ('left/*.png').",
                kind="text",
            ),
            Input(
                "right",
                "The right camera's images, paired with the left ones in sorted order.",
                kind="text",
            ),
        ),
        Output("Stereo camera file to write (TOML, docs/camera-file.md, 'Stereo rigs')."),
        suffixes=(".toml",),
        group="geometry",
        description=f"Needs the board in both images of at least {MIN_VIEWS} pairs. Each camera "
        "is calibrated alone, then one Levenberg-Marquardt refines both cameras, R and T "
        "(X_right = R X_left + T) on all reprojection errors.",
    ),
    Workflow(
        "depth",
        "Depth (or disparity) of a stereo pair by semi-global matching, with a stereo camera file.",
        "imageform.workflows.stereo:depth_cmd",
        DepthOptions,
        (
            Input("left", "The left camera's image."),
            Input("right", "The right camera's image, taken at the same time."),
        ),
        Output("Depth map to write (float32 TIFF or .npy; NaN where invalid)."),
        suffixes=(".tif", ".tiff", ".npy"),
        group="geometry",
        description="Both images are rectified (Bouguet, as OpenCV's stereoRectify), matched by "
        "semi-global matching on census costs (8 paths, sub-pixel, uniqueness and left-right "
        "checks; imageform.geometry.stereo_disparity) and the disparity d turned into depth "
        "Z = f B / d in the units of the rig's T (mm from stereo-calibrate). The map is in "
        "the rectified left camera's pixels; --points writes x, y, z in its frame. Cameras "
        "stacked vertically are rectified to shared columns and matched along them. "
        "docs/calibration.md, 'Depth from a stereo pair'.",
    ),
)
