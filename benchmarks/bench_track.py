"""``imageform track`` against OpenCV's own loop on a rendered 720p video with known poses.

The bar of issue 27: an OpenCV-drawn ChArUco board (7 x 5 squares of 30 mm, 22 mm 5x5_100
markers) pasted on a real photograph, seen from a smooth path of known poses, 20 s of 720p
at 30 frames per second, H.264. Both sides decode the same file with PyAV (FFmpeg) on one
thread and report poses board-to-camera:

- imageform: ``imageform track`` (in this process, as a user runs it; its own timing);
- OpenCV: ``cv2.aruco.CharucoDetector.detectBoard`` on every frame, ``cv2.solvePnP``
  (iterative) and ``cv2.projectPoints`` (the overlay's projection), ``cv2.setNumThreads(1)``.

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
    truth = video_scenes.poses(frames, distance=650)
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


def run_imageform(video: Path, camera: Path, out: Path) -> tuple[float, list]:
    import contextlib
    import io

    from imageform.cli import main

    args = ["track", str(video), "--camera", str(camera), "--board", "charuco:7x5"]
    args += ["--square", "30mm", "--marker", "22mm", "--dictionary", "5x5_100"]
    args += ["-o", str(out), "--json", "--force"]
    buf = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(buf):
        code = main(args)
    wall = time.perf_counter() - t0
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
    return wall, poses


def run_opencv(video: Path) -> tuple[float, list]:
    import cv2

    from imageform.io import open_video

    cv2.setNumThreads(1)
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    board = cv2.aruco.CharucoBoard((7, 5), 30.0, 22.0, d)
    detector = cv2.aruco.CharucoDetector(board)
    points = board.getChessboardCorners()
    axes = np.float32([[0, 0, 0], [60, 0, 0], [0, 60, 0], [0, 0, 60]])
    poses: list = []
    t0 = time.perf_counter()
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
    return time.perf_counter() - t0, poses


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--fps", type=float, default=30.0)
    args = ap.parse_args()
    from imageform.geometry import Camera
    from imageform.io import write_camera

    n = round(args.seconds * args.fps)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        video = folder / "board.mp4"
        truth = render(video, n, args.fps)
        camera = write_camera(folder / "camera.toml", Camera(K, image_size=SIZE))
        run_imageform(video, camera, folder / "warm.csv")  # compile / load the kernels
        t_ours, ours = run_imageform(video, camera, folder / "poses.csv")
        t_cv, theirs = run_opencv(video)
    rows = []
    for name, wall, poses in (("imageform track", t_ours, ours), ("OpenCV loop", t_cv, theirs)):
        e = errors(poses, truth)
        rows.append(
            (
                name,
                f"{n / wall:.1f}",
                f"{wall / args.seconds:.2f}",
                f"{100 * e['found']:.1f}",
                f"{100 * e['t_med']:.3f} / {100 * e['t_95']:.3f}",
                f"{e['r_med']:.3f} / {e['r_95']:.3f}",
                f"{100 * e['jitter']:.4f}",
            )
        )
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(header("Tracking a ChArUco board in 720p video: imageform track against OpenCV"))
    print(
        f"{n} frames, {SIZE[0]}x{SIZE[1]} H.264 at {args.fps:g} fps ({args.seconds:g} s); "
        f"decode included (PyAV, both sides); load average {load}\n"
    )
    print(
        markdown_table(
            (
                "loop",
                "frames per second",
                "time / video length",
                "frames with a pose (%)",
                "translation error median / p95 (% of distance)",
                "rotation error median / p95 (deg)",
                "jitter: median frame-to-frame change of the error (% of distance)",
            ),
            rows,
        )
    )
    print("Command: `OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 python benchmarks/bench_track.py`")


if __name__ == "__main__":
    main()
