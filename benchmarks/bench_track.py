"""``imageform track`` against OpenCV's own loop on a rendered 720p video with known poses.

The bar of issue 27: an OpenCV-drawn ChArUco board (7 x 5 squares of 30 mm, 22 mm 5x5_100
markers) pasted on a real photograph, seen from a smooth path of known poses, 20 s of 720p
at 30 frames per second, H.264. Both sides decode the same file with PyAV (FFmpeg) and report
poses board-to-camera:

- imageform: ``imageform track`` (in this process, as a user runs it; its own timing), once
  writing only ``poses.csv`` and once also the overlay video (``--overlay`` with ``--plan``:
  the board's axes, corners and a plan drawn on every frame and encoded at the input's frame
  rate), whose frames are counted against the input's;
- OpenCV: ``cv2.aruco.CharucoDetector.detectBoard`` on every frame, ``cv2.solvePnP``
  (iterative) and ``cv2.projectPoints`` (the overlay's projection), ``cv2.setNumThreads(1)``.

Each loop runs ``--repeat`` times after a warm-up (kernels compiled), interleaved; the table
gives the median speed. With ``--cores 1`` (the default: the issue's "one core") the process
is pinned to one CPU, FFmpeg's decoding and encoding threads included.

Accuracy against the truth: the median and 95th percentile of the translation error (as a
share of the distance) and of the rotation error, the share of frames with a pose, and the
jitter: the median frame-to-frame change of the error (how much the pose shakes).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 python benchmarks/bench_track.py [--seconds 20]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table
from tests import video_scenes

K = np.array([[1000.0, 0, 639.5], [0, 1000.0, 359.5], [0, 0, 1]])
SIZE = (1280, 720)


def render(path: Path, frames: int, fps: float) -> list[tuple[np.ndarray, np.ndarray]]:
    from imageform.io import VideoWriter

    tex, origin = video_scenes.board_texture()
    # slower than the tests' path: a full circle in 10 s, as a hand moves an endoscope
    truth = [
        video_scenes.poses(int(10 * fps), distance=650)[i % int(10 * fps)] for i in range(frames)
    ]
    rng = np.random.default_rng(3)
    with VideoWriter(path, fps=fps, quality=14) as video:
        for p in truth:
            video.write(video_scenes.render(tex, origin, K, p, SIZE, rng=rng))
    return truth


def errors(poses: list[tuple[np.ndarray, np.ndarray] | None], truth: list) -> dict[str, float]:
    from imageform.geometry import rvec_to_matrix

    te, re = [], []
    for p, (R, t) in zip(poses, truth, strict=True):
        if p is None:
            te.append(np.nan)
            re.append(np.nan)
            continue
        rv, tv = p
        te.append(np.linalg.norm(tv - t) / np.linalg.norm(t))
        dR = np.asarray(rvec_to_matrix(rv)) @ R.T
        re.append(math.degrees(math.acos(np.clip((np.trace(dR) - 1) / 2, -1, 1))))
    t_err, r_err = np.array(te), np.array(re)
    ok = np.isfinite(t_err)
    jitter = np.abs(np.diff(t_err))
    return {
        "found": float(ok.mean()),
        "t_med": float(np.nanmedian(t_err)),
        "t_95": float(np.nanpercentile(t_err, 95)),
        "r_med": float(np.nanmedian(r_err)),
        "r_95": float(np.nanpercentile(r_err, 95)),
        "jitter": float(np.nanmedian(jitter)) if np.any(np.isfinite(jitter)) else float("nan"),
    }


PLAN = "x,y,z,path\n60,60,0,cut\n150,60,0,cut\n150,90,-20,cut\n105,75,-40,\n"


def run_imageform(video: Path, camera: Path, out: Path, *extra: str) -> tuple[float, float, list]:
    import contextlib
    import io

    from imageform.cli import main

    args = ["track", str(video), "--camera", str(camera), "--board", "charuco:7x5"]
    args += ["--square", "30mm", "--marker", "22mm", "--dictionary", "5x5_100"]
    args += ["-o", str(out), "--json", "--force", *extra]
    buf = io.StringIO()
    t0, c0 = time.perf_counter(), time.process_time()
    with contextlib.redirect_stdout(buf):
        code = main(args)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    assert code == 0, code
    json.loads(buf.getvalue())
    poses = []
    with out.open() as fh:
        for row in csv.DictReader(fh):
            if row["found"] != "1":
                poses.append(None)
                continue
            poses.append(
                (
                    np.array([float(row[k]) for k in ("rx", "ry", "rz")]),
                    np.array([float(row[k]) for k in ("tx", "ty", "tz")]),
                )
            )
    return wall, cpu, poses


def count_frames(video: Path) -> tuple[int, float]:
    """Decode every frame of ``video``: how many, and the stream's frame rate."""
    from imageform.io import open_video

    with open_video(video) as reader:
        return sum(1 for _ in reader), reader.info.fps


def run_opencv(video: Path) -> tuple[float, float, list]:
    import cv2

    from imageform.io import open_video

    cv2.setNumThreads(1)
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    board = cv2.aruco.CharucoBoard((7, 5), 30.0, 22.0, d)
    detector = cv2.aruco.CharucoDetector(board)
    points = board.getChessboardCorners()
    axes = np.float32([[0, 0, 0], [60, 0, 0], [0, 60, 0], [0, 0, 60]])
    poses: list = []
    t0, c0 = time.perf_counter(), time.process_time()
    with open_video(video) as reader:
        for frame in reader:
            grey = cv2.cvtColor(frame.image, cv2.COLOR_RGB2GRAY)
            corners, ids, _, _ = detector.detectBoard(grey)
            if ids is None or len(ids) < 6:
                poses.append(None)
                continue
            ok, rvec, tvec = cv2.solvePnP(points[ids.ravel()], corners, K, None)
            if not ok:
                poses.append(None)
                continue
            cv2.projectPoints(axes, rvec, tvec, K, None)
            poses.append((rvec.ravel(), tvec.ravel()))
    return time.perf_counter() - t0, time.process_time() - c0, poses


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each loop")
    ap.add_argument("--cores", type=int, default=1, help="pin to this many CPUs (0: all)")
    args = ap.parse_args()
    from imageform.geometry import Camera
    from imageform.io import write_camera

    if args.cores:
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[: args.cores])
    n = round(args.seconds * args.fps)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        video = folder / "board.mp4"
        truth = render(video, n, args.fps)
        camera = write_camera(folder / "camera.toml", Camera(K, image_size=SIZE))
        plan = folder / "plan.csv"
        plan.write_text(PLAN)
        overlay = folder / "overlay.mp4"
        extra = ("--overlay", str(overlay), "--plan", str(plan))
        loops = {
            "imageform track": lambda: run_imageform(video, camera, folder / "poses.csv"),
            "imageform track --overlay --plan": lambda: run_imageform(
                video, camera, folder / "poses-overlay.csv", *extra
            ),
            "OpenCV loop": lambda: run_opencv(video),
        }
        loops["imageform track"]()  # compile / load the kernels
        walls: dict[str, list[float]] = {name: [] for name in loops}
        cpus: dict[str, list[float]] = {name: [] for name in loops}
        poses: dict[str, list] = {}
        for _ in range(args.repeat):
            for name, loop in loops.items():
                wall, cpu, poses[name] = loop()
                walls[name].append(wall)
                cpus[name].append(cpu)
        overlay_frames, overlay_fps = count_frames(overlay)
        overlay_mb = overlay.stat().st_size / 1e6
    rows = []
    for name in loops:
        wall, cpu = statistics.median(walls[name]), statistics.median(cpus[name])
        e = errors(poses[name], truth)
        rows.append(
            (
                name,
                f"**{n / cpu:.1f}** ({n / max(cpus[name]):.1f} to {n / min(cpus[name]):.1f})",
                f"{cpu / args.seconds:.2f}",
                f"{n / wall:.1f}",
                f"{100 * e['found']:.1f}",
                f"{100 * e['t_med']:.3f} / {100 * e['t_95']:.3f}",
                f"{e['r_med']:.3f} / {e['r_95']:.3f}",
                f"{100 * e['jitter']:.4f}",
            )
        )
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    cores = f"pinned to {args.cores} CPU" if args.cores else "all CPUs"
    print(header("Tracking a ChArUco board in 720p video: imageform track against OpenCV"))
    print(
        f"{n} frames, {SIZE[0]}x{SIZE[1]} H.264 at {args.fps:g} fps ({args.seconds:g} s); "
        f"decode included (PyAV, both sides); {cores} ({cores_note(args.cores)}); median of "
        f"{args.repeat} runs each. Speed is frames per second of the process's CPU time (all "
        f"its threads), the speed the loop has with its core to itself: the machine was "
        f"shared with other work (load average {load} on {os.cpu_count()} cores), so the "
        f"wall-clock speed, also given, is lower by how much of the core others took.\n"
    )
    print(
        markdown_table(
            (
                "loop",
                "frames per CPU second (slowest to fastest run)",
                "CPU time / video length",
                "frames per wall-clock second (loaded machine)",
                "frames with a pose (%)",
                "translation error median / p95 (% of distance)",
                "rotation error median / p95 (deg)",
                "jitter: median frame-to-frame change of the error (% of distance)",
            ),
            rows,
        )
    )
    ok = "every frame" if overlay_frames == n else "FRAMES MISSING"
    print(
        f"\nOverlay video (`--overlay overlay.mp4 --plan plan.csv`: axes, corners and a plan of "
        f"a polyline and a target drawn on every frame, H.264 with x264's ultrafast preset): "
        f"{overlay_frames} frames of {n} decoded back ({ok}), {overlay_fps:g} fps (the "
        f"input's {args.fps:g}), {overlay_mb:.0f} MB.\n"
    )
    print(
        "Command: `OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 python benchmarks/bench_track.py"
        + (f" --cores {args.cores}`" if args.cores != 1 else "`")
    )
    if overlay_frames != n:
        raise SystemExit(f"the overlay has {overlay_frames} frames, the input {n}")


def cores_note(cores: int) -> str:
    """What pinning means for the threads of each side."""
    if cores == 1:
        return "FFmpeg's decoder and encoder threads share that core with the tracking"
    return "FFmpeg's decoder and encoder threads may run beside the tracking"


if __name__ == "__main__":
    main()
