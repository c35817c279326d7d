"""``imageform track``: a board's pose in every frame of a video, and the plan drawn on it.

The course's surgical-navigation loop: the endoscope is calibrated (its camera file), a
board (ChArUco or checkerboard), one ArUco marker or a map of several markers is fixed to
the patient's frame, and each frame's pose of the board places a plan drawn in board
coordinates on the live image. The maths lives in
:class:`imageform.geometry.BoardTracker` (detection, PnP, prediction, smoothing),
:class:`imageform.geometry.MarkerTracker` (one marker: IPPE-square),
:class:`imageform.geometry.MarkerMapTracker` (a marker map: PnP over its markers) and
:func:`imageform.report.overlays.draw_pose_overlay`; this module reads the video, writes
``poses.csv`` and the overlay video, and reports speed and jitter.
"""

from __future__ import annotations

import csv
import math
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._spec import Input, Options, Output, Result, Run, Workflow, option
from imageform.workflows._video import (
    DEINTERLACE_CHOICES,
    DeinterlaceChoice,
    FieldOrderChoice,
    field_order_option,
)

__all__ = ["POSE_COLUMNS", "WORKFLOWS", "TrackOptions", "parse_track_board", "track_map_path"]

#: Columns of ``poses.csv``.
POSE_COLUMNS = ("frame", "time_s", "found", "corners", "rx", "ry", "rz", "tx", "ty", "tz", "rms_px")

_BOARD = re.compile(r"^(charuco|checkerboard):(\d+)x(\d+)$|^(\d+)x(\d+)$")
_MARKER = re.compile(r"^aruco:(\d+)$")
_MAP = re.compile(r"^markers:(.+)$", re.IGNORECASE | re.DOTALL)


def parse_track_board(text: str) -> tuple[str, tuple[int, ...]]:
    """Parse ``--board``: ``charuco:``, ``checkerboard:COLSxROWS``, ``aruco:ID``, ``markers:FILE``.

    A checkerboard is given by its inner corners (OpenCV's pattern size, as ``imageform
    calibrate``); a bare ``COLSxROWS`` is a checkerboard; ``aruco:ID`` is one ArUco marker
    (its id in ``--dictionary``, checked by the caller), returned as ``("aruco", (ID,))``;
    ``markers:FILE`` is several markers on one object (a marker map file, read by
    :func:`imageform.io.read_marker_map`; :func:`track_map_path` gives its path), returned
    as ``("markers", ())``.

    Examples
    --------
    >>> parse_track_board("charuco:7x5"), parse_track_board("checkerboard:9x6")
    (('charuco', (7, 5)), ('checkerboard', (9, 6)))
    >>> parse_track_board("aruco:23"), parse_track_board("markers:tool.toml")
    (('aruco', (23,)), ('markers', ()))
    """
    if not isinstance(text, str):
        raise InvalidInputError(f"expected text (--board) as a str, got {type(text).__name__}")
    if _MAP.match(text.strip()):
        track_map_path(text)
        return "markers", ()
    key = text.strip().lower()
    marker = _MARKER.match(key)
    if marker:
        return "aruco", (int(marker.group(1)),)
    m = _BOARD.match(key)
    if not m:
        raise InvalidInputError(
            "expected --board (text) as charuco:COLSxROWS (squares), checkerboard:COLSxROWS "
            f"(inner corners), aruco:ID (one marker) or markers:FILE (a marker map), got "
            f"{text[:40]!r}"
        )
    if m.group(1):
        kind, cols, rows = m.group(1), int(m.group(2)), int(m.group(3))
    else:
        kind, cols, rows = "checkerboard", int(m.group(4)), int(m.group(5))
    low = 3 if kind == "charuco" else 2
    if not (low <= cols <= 1000 and low <= rows <= 1000):
        what = "squares" if kind == "charuco" else "inner corners"
        raise InvalidInputError(f"expected {low} to 1000 {what} a side in --board, got {text!r}")
    return kind, (cols, rows)


def track_map_path(text: str) -> Path:
    """Return the marker map file of ``--board markers:FILE``.

    Examples
    --------
    >>> track_map_path("markers:maps/tool.toml").as_posix()
    'maps/tool.toml'
    """
    m = _MAP.match(text.strip()) if isinstance(text, str) else None
    if not m or not m.group(1).strip():
        raise InvalidInputError(
            f"expected text (--board) as markers:FILE (a marker map file), got {str(text)[:40]!r}"
        )
    return Path(m.group(1).strip())


#: The video files ``--overlay`` writes (imageform.io.VideoWriter's containers).
OVERLAY_SUFFIXES = (".mp4", ".m4v", ".mov", ".mkv", ".avi")


@dataclass(frozen=True, kw_only=True)
class TrackOptions(Options):
    """Options of ``imageform track``."""

    camera: Path = option(
        help="Camera file of the video's camera (K and distortion: imageform calibrate).",
        metavar="FILE",
        input=True,
    )
    board: str = option(
        help="charuco:COLSxROWS (squares, with --square and --marker), checkerboard:COLSxROWS "
        "(inner corners, with --square), aruco:ID (one ArUco marker of --dictionary, with "
        "--marker) or markers:FILE (several markers on one object: a marker map file, TOML, "
        "its lengths the poses' unit).",
        metavar="KIND:SPEC",
    )
    square: str | None = option(
        None,
        help="Side of a square with unit (30mm, 3cm; bare number: mm): the unit of the poses "
        "(ChArUco and checkerboard).",
    )
    marker: str | None = option(
        None,
        help="Side of a marker's black square with unit (22mm): ChArUco's, smaller than "
        "--square, or the one marker's of aruco:ID (the unit of its poses).",
    )
    dictionary: str = option(
        "6x6_250",
        help="ChArUco or aruco:ID: the markers' ArUco dictionary (4x4_50 ... 7x7_1000, "
        "aruco_original).",
        choices="imageform.geometry.aruco:ARUCO_DICTIONARIES",
    )
    overlay: Path | None = option(
        None,
        help="Also write the video with the board axes, corners and plan drawn (.mp4, .mkv, "
        ".avi), at the input's frame rate.",
        output=True,
    )
    plan: Path | None = option(
        None,
        help="A plan in the board's frame and unit: CSV x,y,z[,path] or a mesh (.ply, .obj, "
        ".stl), drawn on --overlay.",
        input=True,
    )
    smooth: float | None = option(
        None,
        help="Smooth the poses: weight of the newest pose in (0, 1) (exponential filter; "
        "less jitter, more lag). Off by default.",
        metavar="ALPHA",
    )
    fps: float | None = option(
        None,
        help="Frame rate (frames/s) of an image sequence (default 30), or to ask a device for.",
    )
    max_frames: int | None = option(
        None, help="Stop after this many frames (a device runs until Ctrl-C otherwise)."
    )
    no_predict: bool = option(
        False, help="Search every frame whole (default: the previous frame's box first)."
    )
    deinterlace: DeinterlaceChoice = option(
        "auto",
        help="Interlaced video: auto (track the fields when the first frames comb), off, "
        "fields (each field at half height with its own camera matrix: a pose per field), "
        "linear or blend (full frames).",
        choices=DEINTERLACE_CHOICES,
    )
    field_order: FieldOrderChoice | None = field_order_option()

    def check(self) -> None:
        """Check the board, the lengths and the smoothing weight."""
        from imageform._units import parse_length

        super().check()
        kind, spec = parse_track_board(self.board)
        if kind == "markers":
            for name, value in (("--marker", self.marker), ("--square", self.square)):
                if value is not None:
                    raise InvalidInputError(
                        f"{name} is not for --board markers:FILE (the map file holds the "
                        "markers' corners and unit)"
                    )
            self._check_rest()
            return
        if kind == "aruco":
            from imageform.geometry.aruco import aruco_dictionary

            size = aruco_dictionary(self.dictionary).size
            if spec[0] >= size:
                raise InvalidInputError(
                    f"expected an ArUco marker id 0 to {size - 1} of --dictionary "
                    f"{self.dictionary} in --board, got {self.board}"
                )
            if self.marker is None:
                raise InvalidInputError("--board aruco:ID needs --marker (its side, e.g. 50mm)")
            if self.square is not None:
                raise InvalidInputError(
                    "--square is for a ChArUco board or a checkerboard; aruco:ID's side is --marker"
                )
            parse_length(self.marker, "--marker", default_unit="mm", unit="mm")
            self._check_rest()
            return
        if self.square is None:
            raise InvalidInputError(f"--board {kind}:COLSxROWS needs --square (e.g. 30mm)")
        parse_length(self.square, "--square", default_unit="mm", unit="mm")
        if kind == "charuco":
            if self.marker is None:
                raise InvalidInputError("--board charuco:COLSxROWS needs --marker (e.g. 22mm)")
            m = parse_length(self.marker, "--marker", default_unit="mm", unit="mm")
            s = parse_length(self.square, "--square", default_unit="mm", unit="mm")
            if not m < s:
                raise InvalidInputError(
                    f"expected --marker smaller than --square, got {self.marker}"
                )
        elif self.marker is not None:
            raise InvalidInputError(
                "--marker is for a ChArUco --board charuco:COLSxROWS or an ArUco aruco:ID"
            )
        self._check_rest()

    def _check_rest(self) -> None:
        """Check the smoothing weight, the overlay's suffix, --fps and --max-frames."""
        if self.smooth is not None and not 0 < self.smooth < 1:
            raise InvalidInputError(f"expected --smooth in (0, 1), got {self.smooth:g}")
        if self.overlay is not None and self.overlay.suffix.lower() not in OVERLAY_SUFFIXES:
            raise InvalidInputError(
                f"expected --overlay as a video file ({', '.join(OVERLAY_SUFFIXES)}), "
                f"got {_shown(self.overlay.name)!r}"
            )
        if self.fps is not None and not 0 < self.fps < 10_000:
            raise InvalidInputError(f"expected --fps in (0, 10000) frames/s, got {self.fps:g}")
        if self.max_frames is not None and self.max_frames < 1:
            raise InvalidInputError(f"expected --max-frames >= 1, got {self.max_frames}")


def _shown(text: str) -> str:
    """Return ``text`` cut to 60 characters (an error message quotes it)."""
    return text if len(text) <= 60 else text[:60] + "..."


def _fmt(x: float) -> str:
    return "nan" if not math.isfinite(x) else f"{x:.6g}"


def _median(values: list[float]) -> float | None:
    import numpy as np

    return float(np.median(values)) if values else None


def track(run: Run, opts: TrackOptions, *, out: Path, video: str) -> Result:
    """Track the board through the video; write poses.csv (and the overlay)."""
    import numpy as np

    from imageform._units import length_unit, parse_length
    from imageform.geometry import BoardTracker, CharucoBoard, MarkerMapTracker, MarkerTracker
    from imageform.io import (
        VideoWriter,
        field_camera_matrix,
        open_video,
        read_camera,
        read_marker_map,
        read_plan,
    )
    from imageform.report.overlays import draw_pose_overlay
    from imageform.workflows._video import deinterlace_note, deinterlace_summary

    cf = read_camera(opts.camera)
    cam = cf.camera
    kind, size = parse_track_board(opts.board)
    smooth = opts.smooth if opts.smooth is not None else 1.0
    tracker: Any
    if kind == "markers":
        marker_map = read_marker_map(track_map_path(opts.board), dictionary=opts.dictionary)
        if opts.dictionary not in ("6x6_250", marker_map.dictionary):
            raise InvalidInputError(
                f"--dictionary {opts.dictionary} differs from the marker map's "
                f"{marker_map.dictionary} (leave --dictionary out)"
            )
        unit = marker_map.unit
        tracker = MarkerMapTracker(
            marker_map, cam.K, cam.distortion, smooth=smooth, predict=not opts.no_predict
        )
    elif kind == "aruco":
        assert opts.marker is not None
        unit = length_unit(opts.marker, default_unit="mm")
        side = parse_length(opts.marker, "--marker", default_unit="mm", unit=unit)
        tracker = MarkerTracker(
            size[0],
            side,
            cam.K,
            cam.distortion,
            dictionary=opts.dictionary,
            smooth=smooth,
            predict=not opts.no_predict,
        )
    else:
        assert opts.square is not None
        unit = length_unit(opts.square, default_unit="mm")
        square = parse_length(opts.square, "--square", default_unit="mm", unit=unit)
        if kind == "charuco":
            assert opts.marker is not None
            marker = parse_length(opts.marker, "--marker", default_unit="mm", unit=unit)
            board: Any = CharucoBoard((size[0], size[1]), square, marker, opts.dictionary)
        else:
            board = (size[0], size[1])
        tracker = BoardTracker(
            board,
            cam.K,
            cam.distortion,
            square=square,
            smooth=smooth,
            predict=not opts.no_predict,
        )
    plan = read_plan(opts.plan) if opts.plan is not None else None
    reader = open_video(
        video, fps=opts.fps, deinterlace=opts.deinterlace, field_order=opts.field_order
    )
    info = reader.info
    K_of: dict[str | None, Any] = {None: cam.K}
    K_of.update({f: field_camera_matrix(cam.K, f) for f in ("top", "bottom")})
    if cam.image_size is not None and tuple(cam.image_size) != (info.width, info.height):
        reader.close()
        raise InvalidInputError(
            f"camera file {opts.camera} is for {cam.image_size[0]} x {cam.image_size[1]} px "
            f"images, {video} has {info.width} x {info.height} px frames"
        )
    from imageform._kernels import ahead

    ahead.start(f"track-{kind}")  # a first run: the detector's kernels compiled on two cores
    live = info.kind == "device"
    writer = None
    rows: list[list[str]] = []
    rms: list[float] = []
    steps: list[float] = []
    angles: list[float] = []
    latency: list[float] = []
    last: Any = None
    found = 0
    ambiguous = 0
    interrupted = False
    t0 = time.perf_counter()
    try:
        with reader:
            for frame in reader:
                if writer is None and opts.overlay:
                    # x264's fastest preset: encoding keeps up with tracking (bench_track.py)
                    rate = info.fps * (2 if frame.field is not None else 1)
                    writer = VideoWriter(run.file(opts.overlay), fps=rate, preset="ultrafast")
                K = K_of[frame.field]
                tracker.K = K  # a field's own rows: fy / 2, cy of its parity
                got = time.perf_counter()
                pose = tracker.update(frame.image)
                latency.append(time.perf_counter() - got)
                rows.append(
                    [
                        str(frame.index),
                        f"{frame.time_s:.6f}",
                        str(int(pose.found)),
                        str(pose.corners),
                        *(_fmt(float(v)) for v in pose.rvec),
                        *(_fmt(float(v)) for v in pose.tvec),
                        _fmt(pose.rms_px),
                    ]
                )
                ambiguous += pose.searched == "ambiguous"
                if pose.found:
                    found += 1
                    rms.append(pose.rms_px)
                    if last is not None and last.found:
                        steps.append(float(np.linalg.norm(pose.tvec - last.tvec)))
                        dR = pose.R @ last.R.T
                        c = float(np.clip((np.trace(dR) - 1) / 2, -1.0, 1.0))
                        angles.append(math.degrees(math.acos(c)))
                last = pose
                if writer is not None:
                    label = f"frame {frame.index}" + (
                        f"  {pose.corners} corners  rms {pose.rms_px:.2f} px"
                        if pose.found
                        else "  ambiguous: two poses fit, no pose"
                        if pose.searched == "ambiguous"
                        else "  board not found"
                    )
                    drawn = draw_pose_overlay(
                        frame.image, pose, K, cam.distortion, plan=plan, label=label
                    )
                    if frame.field is not None:  # a field's rows doubled: the frame's size
                        drawn = np.repeat(drawn, 2, axis=0)[: 2 * (info.height // 2)]
                    writer.write(drawn)
                if live and frame.index % 30 == 29:
                    dt = time.perf_counter() - t0
                    print(
                        f"imageform track: frame {frame.index + 1}, "
                        f"{(frame.index + 1) / dt:.1f} fps, latency "
                        f"{1000 * latency[-1]:.0f} ms",
                        file=sys.stderr,
                        flush=True,
                    )
                if opts.max_frames is not None and len(rows) >= opts.max_frames:
                    break
    except KeyboardInterrupt:
        if not live:
            raise
        interrupted = True  # a live capture stops on Ctrl-C: the outputs are completed
    finally:
        if writer is not None:
            writer.close()
    elapsed = time.perf_counter() - t0
    if not rows:
        raise InvalidInputError(f"{video}: no frame was read")
    with open(run.file(out), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(POSE_COLUMNS)
        w.writerows(rows)
    n = len(rows)
    if interrupted:
        run.note(f"note: stopped by Ctrl-C after {n} frames; {out} is complete")
    if found == 0:
        run.note(f"note: the board was found in none of the {n} frames (check --board)")
    if ambiguous:
        run.note(
            f"note: {ambiguous} of the {n} frames were ambiguous, no pose there: a marker's "
            "id read in two places, or a marker nearly face-on whose two tilts fit alike, "
            "with no recent pose to choose by (is an id printed twice? tilt the marker, or "
            "see more of the map)"
        )
    deint = deinterlace_note(reader, info.fps)
    if deint:
        run.note(f"note: {deint}")
    summary: dict[str, Any] = {
        "video": video,
        "out": out,
        "overlay": opts.overlay,
        "frames": n,
        "found": found,
        "found_fraction": found / n,
        "unit": unit,
        "fps": n / elapsed if elapsed > 0 else None,
        "latency_ms_median": 1000 * (_median(latency) or 0.0),
        "rms_px_median": _median(rms),
        "jitter_translation_median": _median(steps),
        "jitter_rotation_deg_median": _median(angles),
        "source": {"kind": info.kind, "width": info.width, "height": info.height, "fps": info.fps},
        "interrupted": interrupted,
        "deinterlace": deinterlace_summary(reader),
    }
    text = (
        f"{video}: {n} {'fields' if summary['deinterlace']['method'] == 'fields' else 'frames'} "
        f"({info.width}x{info.height}, {info.fps:g} fps), board found in "
        f"{found} ({100 * found / n:.0f} %)",
        f"{summary['fps']:.1f} frames per second, median latency "
        f"{summary['latency_ms_median']:.1f} ms, median reprojection RMS "
        + (f"{summary['rms_px_median']:.3f} px" if rms else "-")
        + (
            f", frame-to-frame change median {summary['jitter_translation_median']:.3g} {unit} "
            f"/ {summary['jitter_rotation_deg_median']:.3g} deg"
            if steps
            else ""
        ),
        f"poses -> {out}" + (f", overlay -> {opts.overlay}" if opts.overlay else ""),
    )
    return Result(summary, text)


WORKFLOWS = (
    Workflow(
        "track",
        "Track a board's pose in every frame of a video (or a camera) and overlay a plan.",
        "imageform.workflows.track:track",
        TrackOptions,
        (
            Input(
                "video",
                "A video file, a folder or glob of images, or a capture device (/dev/video0); "
                "files and devices need imageform[video].",
                metavar="VIDEO",
                kind="text",
            ),
        ),
        Output("Poses to write: CSV of frame,time_s,found,corners,rx,ry,rz,tx,ty,tz,rms_px."),
        suffixes=(".csv",),
        group="geometry",
        description="Per frame: detect the board (the previous frame's box first), undistort "
        "the corners with the camera file's model, solve PnP with refinement (X_cam = R X_board "
        "+ t, r a Rodrigues vector, t in the unit of --square); one ArUco marker (aruco:ID) by "
        "IPPE-square, its mirror-tilt ambiguity settled by continuity (t in the unit of "
        "--marker); several markers on one object (markers:FILE) by PnP over all the corners "
        "of the markers that agree (a misread id left out; t in the map's unit); frames "
        "without the board are NaN rows. A capture device runs until "
        "Ctrl-C (or --max-frames) and prints its speed.",
    ),
)
