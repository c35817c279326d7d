"""Stereo workflow: ``imageform stereo-calibrate`` (checkerboard pairs to a stereo camera file)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.workflows._images import ImageIn, read
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

__all__ = ["WORKFLOWS", "StereoCalibrateOptions"]


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
        None, help="Sub-pixel window half size (OpenCV's tutorial: 11); default adaptive."
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


def _expand(pattern: str, what: str) -> list[Path]:
    """Return the files a name, a folder or a glob pattern names, sorted; none is an error."""
    from imageform._files import glob_paths, not_a_regular_file
    from imageform.io import image_files

    p = str(pattern)
    if os.path.exists(p) or not any(c in p for c in "*?["):
        path = Path(p)
        kind = not_a_regular_file(path)
        if kind == "is a folder":
            return image_files(path)
        if kind is not None:
            raise InvalidInputError(f"{what} {path} {kind}")
        if not path.is_file():
            raise InvalidInputError(f"{what} file {path} does not exist")
        return [path]
    hits = sorted(glob_paths(p))
    if not hits:
        raise InvalidInputError(f"no files match {what} pattern {p!r}")
    return [Path(h) for h in hits]


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
    opts: StereoCalibrateOptions, files: list[Path], board: tuple[int, int] | Literal["auto"]
) -> tuple[tuple[int, int], list[Any]]:
    """Each image's checkerboard (``board``: its inner corners, or ``"auto"``), all of one size.

    Returns the images' size ``(W, H)`` and each image's ``CheckerboardResult``.
    """
    from imageform.geometry.checkerboard import find_checkerboard

    size: tuple[int, int] | None = None
    found: list[Any] = []
    for f in files:
        img = read(f, opts)
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
    assert size is not None
    return size, found


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
    lefts, rights = _expand(left, "left"), _expand(right, "right")
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
    size_l, det_l = _detect(opts, lefts, "auto" if auto else board)
    if run.progress is not None:
        run.progress("detecting", 0.5)
    size_r, det_r = _detect(opts, rights, "auto" if auto else board)
    reading = None
    if auto:
        both = det_l + det_r

        def search(files: list[Path], size: tuple[int, int]) -> list[Any]:
            return _detect(opts, files, size)[1]

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
            f"{len(lefts)} pairs; stereo-calibrate needs at least {MIN_VIEWS} "
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
        "pairs_total": len(lefts),
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
)
