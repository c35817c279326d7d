"""Interlaced video: detection, and what tracking and reconstruction lose to combing.

Interlaced clips with a known truth are made from progressive ones: frame ``k``'s even rows
(the top field) from time ``2k``, its odd rows (the bottom field) from time ``2k + 1`` of a
progressive source at twice the frame rate (top field first; ``--order bottom`` swaps). They
are written as PNG sequences (lossless: the fields as woven) and, for the detection table,
also as H.264 (x264 CRF 18, 4:2:0, coded progressive as a grabber's re-encode would be).

1. **Detection** (:func:`imageform.io.detect_interlacing`, FFmpeg idet's rule on up to 120
   frames): each clip progressive and interlaced, and a still scene (one frame repeated:
   interlacing invisible, nothing to change).
2. **Tracking** (``imageform track``): a ChArUco board (7 x 5 squares of 30 mm, 22 mm 5x5_100
   markers, tests/video_scenes.py) on a Kodak photograph, 720 x 576 px (PAL SD, square
   pixels: fx = fy = 700), rendered at 50 field times a second along a circle of
   ``--circle-seconds`` (fast hand motion of an endoscope); the truth is the render's pose.
   Rows: the progressive frames (the top field's instants, 25 a second) tracked as they are;
   the interlaced frames with ``--deinterlace off`` (the truth: the top field's instant, the
   frame's time), ``linear``, ``blend`` and ``auto`` (here the fields: 50 poses a second,
   each field's truth). Errors: translation as a share of the distance, rotation in degrees,
   median and 95th percentile over the frames with a pose; the share of frames with one.
3. **Reconstruction** (``imageform reconstruct --auto-mask --contrast-threshold 0.01``): the
   real colonoscopy clip ``--video`` (C3VD v3's preview ``assets/aligned_prev_final.mp4``,
   github.com/DurrLab/C3VDv3 at ``ad9391d``, CC BY 4.0; 289 frames at 60 fps, the colour
   panel the first 445 columns), interlaced at 30 frames a second (144 frames), every 4th
   frame reconstructed (the top field's instants are the source's every 8th frame, 0 to
   280). Rows: the progressive frames of those instants, and the interlaced ones with each
   ``--deinterlace`` (``auto`` is ``linear`` for reconstruct; ``fields`` the first field at
   half height). No ground truth: the references are imageform on the progressive frames
   and, with ``--reference`` (check_endo_real.py's cached pycolmap 4.2.1 poses of every 8th
   source frame, aperture mask, peak threshold / 4), pycolmap. The agreement columns
   (median angles between consecutive relative rotations and translation directions,
   degrees; the worst rotation) are as in check_endo_real.py; the trajectory column is the
   RMS distance of the camera centres to the reference's after a similarity fit, a share of
   the reference's extent (the RMS distance of its centres to their mean).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_interlace.py \\
        --video /tmp/endo/c3vdv3_prev.mp4 [--frames 60] [--circle-seconds 2]
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table
from benchmarks.check_endo_real import agreement, read_clip, worst_rotation
from tests import video_scenes

SIZE = (720, 576)
K = np.array([[700.0, 0, 359.5], [0, 700.0, 287.5], [0, 0, 1]])
ENDO_CAMERA = Path(__file__).resolve().parents[1] / "tests" / "data" / "endo" / "camera.toml"


def centers(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Camera centres -R^T t (NaN rows where not registered)."""
    return -np.einsum("nji,nj->ni", R, t)


def trajectory_error(R: np.ndarray, t: np.ndarray, Rr: np.ndarray, tr: np.ndarray) -> float:
    """RMS distance of the centres to the reference's after a similarity (Umeyama), a share of
    the reference's extent (its centres' RMS distance to their mean); frames in both."""
    a, b = centers(R, t), centers(Rr, tr)
    ok = np.isfinite(a[:, 0]) & np.isfinite(b[:, 0])
    a, b = a[ok], b[ok]
    if len(a) < 3:
        return float("nan")
    ma, mb = a.mean(0), b.mean(0)
    A, B = a - ma, b - mb
    U, S, Vt = np.linalg.svd(B.T @ A / len(a))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    rot = U @ D @ Vt
    scale = np.trace(np.diag(S) @ D) / np.mean(np.sum(A**2, 1))
    fit = scale * A @ rot.T
    extent = np.sqrt(np.mean(np.sum(B**2, 1)))
    return float(np.sqrt(np.mean(np.sum((fit - B) ** 2, 1))) / extent)


def weave(first: np.ndarray, second: np.ndarray, order: str = "top") -> np.ndarray:
    """One interlaced frame: the first field's rows from ``first``, the other's from ``second``."""
    rows = np.arange(first.shape[0]) % 2 == (0 if order == "top" else 1)
    return np.where(rows[:, None, None], first, second)


def write_png_folder(folder: Path, frames: list[np.ndarray]) -> Path:
    from imageform.io import write_image

    folder.mkdir(parents=True, exist_ok=True)
    for i, f in enumerate(frames):
        write_image(folder / f"f{i:05d}.png", f)
    return folder


def write_h264(path: Path, frames: list[np.ndarray], fps: float) -> Path:
    from imageform.io import VideoWriter

    with VideoWriter(path, fps=fps) as w:
        for f in frames:
            w.write(f)
    return path


def detect(source: Path, fps: float) -> Any:
    from imageform.io import open_video

    with open_video(source, fps=fps, deinterlace="auto") as reader:
        for _ in reader:
            break
        return reader.interlacing


def cli(args: list[str]) -> dict[str, Any]:
    from imageform.cli import main

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main([*args, "--json", "--force"])
    assert code == 0, (code, args)
    return json.loads(buf.getvalue())


def track_rows(path: Path) -> list[tuple[float, Any]]:
    out: list[tuple[float, Any]] = []
    with path.open() as fh:
        for row in csv.DictReader(fh):
            pose = None
            if row["found"] == "1":
                pose = (
                    np.array([float(row[k]) for k in ("rx", "ry", "rz")]),
                    np.array([float(row[k]) for k in ("tx", "ty", "tz")]),
                )
            out.append((float(row["time_s"]), pose))
    return out


def pose_errors(rows: list[tuple[float, Any]], truth: list, field_s: float) -> dict[str, float]:
    from imageform.geometry import rvec_to_matrix

    te, re = [], []
    for time_s, pose in rows:
        if pose is None:
            continue
        R, t = truth[round(time_s / field_s)]
        rv, tv = pose
        te.append(np.linalg.norm(tv - t) / np.linalg.norm(t))
        dR = np.asarray(rvec_to_matrix(rv)) @ R.T
        re.append(math.degrees(math.acos(np.clip((np.trace(dR) - 1) / 2, -1, 1))))
    t_err, r_err = np.array(te), np.array(re)
    nan = float("nan")
    return {
        "found": len(te) / len(rows),
        "poses": len(rows),
        "t_med": float(np.median(t_err)) if te else nan,
        "t_95": float(np.percentile(t_err, 95)) if te else nan,
        "r_med": float(np.median(r_err)) if re else nan,
        "r_95": float(np.percentile(r_err, 95)) if re else nan,
    }


def detection_row(name: str, found: Any) -> list[str]:
    return [
        name,
        "interlaced" if found.interlaced else "not interlaced",
        str(found.field_order or "-"),
        f"{found.top_first} / {found.bottom_first} / {found.progressive} / {found.undetermined}",
        f"{found.combing:.2f}",
    ]


def tracking(tmp: Path, frames: int, circle_s: float, order: str) -> tuple[str, list[list[str]]]:
    from imageform.geometry import Camera
    from imageform.io import write_camera

    field_rate = 50.0
    tex, origin = video_scenes.board_texture()
    per_circle = round(circle_s * field_rate)
    path = video_scenes.poses(per_circle, distance=420.0)
    truth = [path[i % per_circle] for i in range(2 * frames)]
    rng = np.random.default_rng(5)
    fields = [video_scenes.render(tex, origin, K, p, SIZE, rng=rng) for p in truth]
    prog = fields[0::2]
    woven = [weave(fields[2 * k], fields[2 * k + 1], order) for k in range(frames)]
    camera = write_camera(tmp / "pal.toml", Camera(K, image_size=SIZE))
    p_dir = write_png_folder(tmp / "track-prog", prog)
    i_dir = write_png_folder(tmp / "track-intl", woven)
    h264 = write_h264(tmp / "track-intl.mp4", woven, 25.0)
    still = write_png_folder(tmp / "track-still", [woven[0]] * 12)
    det = [
        detection_row("board, progressive (PNG)", detect(p_dir, 25.0)),
        detection_row("board, interlaced (PNG)", detect(i_dir, 25.0)),
        detection_row("board, interlaced (H.264 4:2:0)", detect(h264, 25.0)),
        detection_row("board, interlaced, still (one frame x 12)", detect(still, 25.0)),
    ]
    base = ["--camera", str(camera), "--board", "charuco:7x5", "--square", "30mm"]
    base += ["--marker", "22mm", "--dictionary", "5x5_100", "--fps", "25"]
    runs = [
        ("progressive frames", p_dir, "off"),
        ("interlaced, --deinterlace off", i_dir, "off"),
        ("interlaced, --deinterlace linear", i_dir, "linear"),
        ("interlaced, --deinterlace blend", i_dir, "blend"),
        ("interlaced, --deinterlace auto", i_dir, "auto"),
        ("interlaced H.264, --deinterlace auto", h264, "auto"),
    ]
    rows = []
    for label, src, how in runs:
        out = tmp / "poses.csv"
        res = cli(["track", str(src), *base, "--deinterlace", how, "-o", str(out)])
        # a frame's time is its first field's instant; a field's its own: the truth there
        e = pose_errors(track_rows(out), truth, 1 / field_rate)
        applied = res["deinterlace"]["method"]
        rows.append(
            [label, applied, str(e["poses"]), f"{100 * e['found']:.0f} %",
             f"{100 * e['t_med']:.3f} %", f"{100 * e['t_95']:.3f} %", f"{e['r_med']:.3f}",
             f"{e['r_95']:.3f}"]
        )  # fmt: skip
        print(f"  track {label}: {rows[-1]}", file=sys.stderr)
    return markdown_table(
        ["clip", "track's --deinterlace applied", "poses", "found", "translation median",
         "translation p95", "rotation median deg", "rotation p95 deg"],
        rows,
    ), det  # fmt: skip


def reconstruction(
    tmp: Path, video: Path, order: str, every: int, reference: Path | None
) -> tuple[str, list[list[str]]]:
    from imageform.geometry import rvec_to_matrix

    frames = read_clip(video, 445)
    n = len(frames) // 2
    prog = [frames[2 * k] for k in range(n)]
    woven = [weave(frames[2 * k], frames[2 * k + 1], order) for k in range(n)]
    p_dir = write_png_folder(tmp / "endo-prog", prog)
    i_dir = write_png_folder(tmp / "endo-intl", woven)
    h264 = write_h264(tmp / "endo-intl.mp4", [f[:, :444] for f in woven], 30.0)  # even width
    still = write_png_folder(tmp / "endo-still", [woven[40]] * 12)
    det = [
        detection_row("C3VD colonoscopy, progressive 30 fps (PNG)", detect(p_dir, 30.0)),
        detection_row("C3VD colonoscopy, progressive 60 fps (source)", detect(video, 60.0)),
        detection_row("C3VD colonoscopy, interlaced (PNG)", detect(i_dir, 30.0)),
        detection_row("C3VD colonoscopy, interlaced (H.264 4:2:0)", detect(h264, 30.0)),
        detection_row("C3VD colonoscopy, still (one frame x 12)", detect(still, 30.0)),
    ]
    base = ["--camera", str(ENDO_CAMERA), "--auto-mask", "--contrast-threshold", "0.01"]
    base += ["--every", str(every)]
    runs = [
        ("progressive frames", p_dir, "off"),
        ("interlaced, --deinterlace off", i_dir, "off"),
        ("interlaced, --deinterlace linear", i_dir, "linear"),
        ("interlaced, --deinterlace blend", i_dir, "blend"),
        ("interlaced, --deinterlace fields", i_dir, "fields"),
        ("interlaced, --deinterlace auto", i_dir, "auto"),
    ]
    results = []
    for label, src, how in runs:
        out = tmp / f"rec-{how}-{src.name}"
        res = cli(["reconstruct", str(src), *base, "--deinterlace", how, "-o", str(out)])
        R, t = [], []
        with (out / "cameras.csv").open() as fh:
            for row in csv.DictReader(fh):
                rv = np.array([float(row[k]) for k in ("rx", "ry", "rz")])
                tv = np.array([float(row[k]) for k in ("tx", "ty", "tz")])
                ok = row["registered"] == "1"
                R.append(np.asarray(rvec_to_matrix(rv)) if ok else np.full((3, 3), np.nan))
                t.append(tv if ok else np.full(3, np.nan))
        results.append((label, res, np.array(R), np.array(t)))
        print(f"  reconstruct {label}: {res['registered']}/{res['frames']}", file=sys.stderr)
    ref = results[0]
    theirs = None
    if reference is not None and reference.exists():  # pycolmap, every 8th source frame
        with np.load(reference) as z:
            theirs = (z["R"][: len(ref[2])], z["t"][: len(ref[2])])
    rows = []
    for label, res, R, t in results:
        rot, tra = agreement(R, t, ref[2], ref[3]) if res is not ref[1] else (0.0, 0.0)
        worst = worst_rotation(R, ref[2]) if res is not ref[1] else 0.0
        traj = trajectory_error(R, t, ref[2], ref[3]) if res is not ref[1] else 0.0
        row = [label, res["deinterlace"]["method"], f"{res['registered']}/{res['frames']}",
               str(res["points"]), f"{res['track_length_mean']:.2f}",
               f"{res['reprojection_px_median']:.3f}", f"{rot:.2f} / {tra:.2f}", f"{worst:.2f}",
               f"{100 * traj:.1f} %"]  # fmt: skip
        if theirs is not None:
            row.append(f"{100 * trajectory_error(R, t, *theirs):.1f} %")
        rows.append(row)
    columns = ["clip", "--deinterlace applied", "registered", "points", "track length",
               "reprojection px (median)", "vs progressive: rotation / translation deg (median)",
               "worst rotation deg", "vs progressive: trajectory"]  # fmt: skip
    if theirs is not None:
        columns.append("vs pycolmap: trajectory")
    return markdown_table(columns, rows), det


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--video", type=Path, default=Path("/tmp/endo/c3vdv3_prev.mp4"))
    ap.add_argument("--frames", type=int, default=60, help="interlaced frames of the board")
    ap.add_argument("--circle-seconds", type=float, default=2.0)
    ap.add_argument("--order", choices=("top", "bottom"), default="top")
    ap.add_argument("--every", type=int, default=4)
    ap.add_argument("--skip-reconstruct", action="store_true")
    ap.add_argument("--skip-track", action="store_true")
    ap.add_argument(
        "--reference",
        type=Path,
        default=Path("/tmp/endo/refcache/pycolmap-every8-1.npz"),
        help="check_endo_real.py's cached pycolmap poses of every 8th source frame",
    )
    ap.add_argument("--real", type=Path, nargs="*", default=[], help="real interlaced files")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        track_table, det = "", []
        if not args.skip_track:
            track_table, det = tracking(folder, args.frames, args.circle_seconds, args.order)
        rec_table = ""
        if not args.skip_reconstruct:
            rec_table, det_endo = reconstruction(
                folder, args.video, args.order, args.every, args.reference
            )
            det += det_endo
        for path in sorted(args.real):
            det.append(detection_row(f"`{path.name}`", detect(path, 30.0)))
    print(header("Interlaced video: detection, tracking and reconstruction"))
    print(f"Fields woven {args.order} first.\n")
    print("## Detection (detect_interlacing on up to 120 frames)\n")
    print(
        markdown_table(
            [
                "clip",
                "found",
                "field first",
                "frames: top first / bottom first / progressive / undetermined",
                "combing (median)",
            ],
            det,
        )
    )
    if track_table:
        print(f"## Tracking: {args.frames} frames, a circle in {args.circle_seconds:g} s\n")
        print(track_table)
    if rec_table:
        print(f"## Reconstruction: C3VD colonoscopy, every {args.every}th interlaced frame\n")
        print(rec_table)


if __name__ == "__main__":
    main()
