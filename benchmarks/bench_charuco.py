"""ChArUco corners in photographs: imageform's detect_charuco against OpenCV's CharucoDetector.

The same scenes for both (a 7 x 5 board, 5x5_100 markers, composited into the 24 Kodak
photographs by ``tests/geometry/test_charuco.py``'s ``_composite``: 20-60 px squares, any
in-plane turn, up to ~35 deg of tilt, blur up to 1.5 px, noise up to 3 %, every fourth view
cut by the border), uint8 grey in. Reported: corners found against the corners visible, the
error against the true corners (px), corners more than 1.5 px off (wrong), and the median
time per image, both run in the same process, interleaved, one thread each
(``cv2.setNumThreads(1)``, ``NUMBA_NUM_THREADS=1``): CPU time of the process (the fair
measure on a shared machine; the wall time is reported beside it). A second table does the
same on 720p frames of ``tests/video_scenes.py`` (the board drawn by OpenCV on a
photograph, seen from a camera circling it, as ``imageform track`` gets them), and the first
call's time (compilation, or loading numba's cache) is printed.

    NUMBA_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/bench_charuco.py --scenes 48
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--video-frames", type=int, default=40)
    ap.add_argument("--out", type=Path)
    ns = ap.parse_args()
    import cv2

    from imageform.geometry import CharucoBoard, detect_charuco
    from tests.geometry.test_charuco import _composite, _kodak

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    cv_board = cv2.aruco.CharucoBoard(
        (7, 5), 30.0, 22.0, cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    )
    detector = cv2.aruco.CharucoDetector(cv_board)
    cv2.setNumThreads(1)
    rng = np.random.default_rng(ns.seed)
    t0 = time.perf_counter()
    detect_charuco(board.image(40, margin_px=20), board)  # compile (or load) the kernels
    first_call = time.perf_counter() - t0
    scenes = []
    for k in range(ns.scenes):
        img, truth = _composite(
            rng,
            board,
            _kodak(k % 24 + 1),
            square_px=int(rng.integers(20, 60)),
            blur=float(rng.choice([0.0, 0.7, 1.5])),
            noise=float(rng.choice([0.0, 0.01, 0.03])),
            cut=k % 4 == 3,
        )
        scenes.append((img, truth))
    photo_table, photo_ratio = _compare(scenes, board, detector, detect_charuco)
    video = _video_frames(ns.video_frames) if ns.video_frames else []
    if video:
        video_table, video_ratio = _compare(video, board, detector, detect_charuco)
    headers = [
        "detector",
        "corners found / visible",
        "images with >= 6 corners",
        "median error (px)",
        "95th pct error (px)",
        "wrong (> 1.5 px)",
        "median CPU ms per image",
        "median wall ms per image",
    ]
    parts = [
        header("ChArUco corners in photographs: imageform vs OpenCV"),
        "",
        f"{ns.scenes} scenes, seed {ns.seed}; OpenCV {cv2.__version__} CharucoDetector "
        "(default parameters), one thread each; uint8 grey in, corners (px) out; load "
        f"average at the end {os.getloadavg()[0]:.1f} (both detectors ran interleaved under "
        "the same load).",
        "",
        markdown_table(headers, photo_table),
        "",
        f"Speed ratio OpenCV / imageform (median CPU times): {photo_ratio:.2f}x "
        "(above 1: imageform faster).",
    ]
    if video:
        parts += [
            "",
            f"720p video frames ({len(video)}, tests/video_scenes.py: the board drawn by OpenCV "
            "on a photograph, the camera circling it at 420 mm, f = 1000 px):",
            "",
            markdown_table(headers, video_table),
            "",
            f"Speed ratio OpenCV / imageform (median CPU times): {video_ratio:.2f}x.",
        ]
    parts += [
        "",
        f"First call in this process (numba kernels compiled or loaded from the cache): "
        f"{first_call:.1f} s.",
    ]
    text = "\n".join(parts)
    print(text)
    if ns.out:
        ns.out.write_text(text + "\n")


def _video_frames(n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` 720p grey frames of tests/video_scenes.py with the true inner corners."""
    import cv2

    from imageform.geometry import CharucoBoard
    from tests import video_scenes

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    K = np.array([[1000.0, 0, 639.5], [0, 1000.0, 359.5], [0, 0, 1]])
    tex, origin = video_scenes.board_texture()
    rng = np.random.default_rng(1)
    out = []
    for R, t in video_scenes.poses(n):
        frame = video_scenes.render(tex, origin, K, (R, t), (1280, 720), rng=rng)
        uv = (board.corner_points() @ R.T + t) @ K.T
        out.append((cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY), uv[:, :2] / uv[:, 2:]))
    return out


def _compare(
    scenes: list[tuple[np.ndarray, np.ndarray]], board: Any, detector: Any, detect: Any
) -> tuple[list[list[str]], float]:
    """Run both detectors on every image, interleaved: the table rows and the speed ratio."""
    rows: dict[str, dict[str, list[float]]] = {
        k: {"found": [], "err": [], "wrong": [], "t": [], "wall": [], "frames6": []}
        for k in ("imageform", "OpenCV")
    }
    visible = 0
    for img, truth in scenes:
        hgt, wid = img.shape
        inside = (truth > 4).all(axis=1) & (truth[:, 0] < wid - 5) & (truth[:, 1] < hgt - 5)
        visible += int(inside.sum())
        c0, w0 = time.process_time(), time.perf_counter()
        found = detect(img, board)
        c1, w1 = time.process_time(), time.perf_counter()
        cc, ci, _, _ = detector.detectBoard(img)
        c2, w2 = time.process_time(), time.perf_counter()
        ids_cv = np.zeros(0, int) if ci is None else ci.ravel()
        xy_cv = np.zeros((0, 2)) if cc is None else cc.reshape(-1, 2)
        for name, ids, xy, dt, dw in (
            ("imageform", found.ids, found.corners, c1 - c0, w1 - w0),
            ("OpenCV", ids_cv, xy_cv, c2 - c1, w2 - w1),
        ):
            err = np.hypot(*(xy - truth[ids]).T) if len(ids) else np.zeros(0)
            r = rows[name]
            r["found"].append(len(ids))
            r["err"].extend(err[err <= 1.5].tolist())
            r["wrong"].append(int((err > 1.5).sum()))
            r["t"].append(dt)
            r["wall"].append(dw)
            r["frames6"].append(len(ids) >= 6)
    table = []
    for name, r in rows.items():
        table.append(
            [
                name,
                f"{sum(r['found'])} / {visible}",
                f"{sum(r['frames6'])} / {len(scenes)}",
                f"{np.median(r['err']):.3f}",
                f"{np.percentile(r['err'], 95):.3f}",
                str(sum(r["wrong"])),
                f"{statistics.median(r['t']) * 1e3:.1f}",
                f"{statistics.median(r['wall']) * 1e3:.1f}",
            ]
        )
    ratio = statistics.median(rows["OpenCV"]["t"]) / statistics.median(rows["imageform"]["t"])
    return table, ratio


if __name__ == "__main__":
    main()
