"""Per-frame time of the marker and board trackers on webcam and 12 Mpx frames, vs OpenCV.

Frames (``DATA`` laid out as ``check_track_fresh.py`` says; all seen by earlier sessions,
tuning data):

- **webcam**: caliscope's ``charuco_calibration`` camera 0, frames 70-110 (1280 x 720 grey,
  the hand-held ChArUco board of ten 4x4 markers in view);
- **12 Mpx**: the same 41 frames enlarged 3.6 times (``cv2.resize``, bicubic: 4608 x 2592,
  11.9 Mpx; the camera matrix scaled with them);
- **photographs**: williambittner1/charuco_task's seven 4096 x 3072 photographs
  (``wb/data/{occlusion,motionblur,clean}``, the camera calibrated as
  ``check_track_fresh.py`` does; ChArUco 7 x 5, DICT_6X6_250).

Loops, each over the frames in order (one tracker a sequence):

- imageform ``MarkerMapTracker`` (the board's markers as a map; on the 12 Mpx frames also
  with ``predict=False``, every frame searched whole) against OpenCV's
  ``ArucoDetector.detectMarkers`` + ``Board.matchImagePoints`` + ``solvePnP``;
- imageform ``MarkerTracker`` (the marker OpenCV reads in most frames) against
  ``detectMarkers`` + ``solvePnP(SOLVEPNP_IPPE_SQUARE)``;
- imageform ``BoardTracker`` (ChArUco) against ``CharucoDetector.detectBoard`` +
  ``solvePnP`` (``check_track_fresh.run_opencv``).

One warm-up run, then ``--repeat`` runs with the loops interleaved; a run's figure is the
process's CPU time per frame (mean over the frames); the table gives the median over the
runs, and the frames with a pose of the last run. Both with one thread
(``cv2.setNumThreads(1)``, ``NUMBA_NUM_THREADS=1``).

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``:
``python benchmarks/check_track_large.py DATA [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import copy
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table

SCALE = 3.6


def _scaled(K: np.ndarray, s: float) -> np.ndarray:
    """The camera matrix of frames enlarged ``s`` times (pixel centres kept)."""
    k = K.astype(np.float64).copy()
    k[:2, :2] *= s
    k[:2, 2] = (k[:2, 2] + 0.5) * s - 0.5
    return k


def _loops(seq: Any, K: np.ndarray, dist: np.ndarray) -> dict[str, tuple[Callable, Callable]]:
    """Per loop: (a fresh imageform tracker's step, a fresh OpenCV step), a frame -> found."""
    import cv2

    from benchmarks.check_track_fresh import _cv_board
    from imageform.geometry import (
        BoardTracker,
        BrownConrady,
        CharucoBoard,
        MarkerMap,
        MarkerMapTracker,
        MarkerTracker,
    )

    b = seq.board
    board = CharucoBoard(b.size, b.square, b.marker, b.dictionary)
    corners = board.marker_points()
    n = len(corners)
    d = BrownConrady(*[float(v) for v in dist[:5]])
    cvd = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, "DICT_" + b.dictionary.upper()))
    det = cv2.aruco.ArucoDetector(cvd)
    seen = np.zeros(n, int)
    for g in seq.frames:
        _, ids, _ = det.detectMarkers(g)
        for i in [] if ids is None else ids.ravel():
            seen[i] += i < n
    k = int(np.argmax(seen))
    side = float(np.linalg.norm(corners[k, 1] - corners[k, 0]))
    whole = MarkerMap(np.arange(n), corners, b.dictionary)
    cv_map = cv2.aruco.Board(corners.astype(np.float32), cvd, np.arange(n))
    cvb = _cv_board(b)
    cdet = cv2.aruco.CharucoDetector(cvb)
    obj1 = np.array(
        [[-side / 2, side / 2, 0], [side / 2, side / 2, 0], [side / 2, -side / 2, 0]]
        + [[-side / 2, -side / 2, 0]],
        np.float64,
    )

    def imageform(make: Callable[[], Any]) -> Callable[[], Callable[[np.ndarray], bool]]:
        def fresh() -> Callable[[np.ndarray], bool]:
            tr = make()
            return lambda g: bool(tr.update(g).found)

        return fresh

    def cv_map_step() -> Callable[[np.ndarray], bool]:
        def step(g: np.ndarray) -> bool:
            c, ids, _ = det.detectMarkers(g)
            if ids is None:
                return False
            o, i = cv_map.matchImagePoints(c, ids)
            if o is None or len(o) < 4:
                return False
            ok, _, _ = cv2.solvePnP(o, i, K, dist)
            return bool(ok)

        return step

    def cv_one_step() -> Callable[[np.ndarray], bool]:
        def step(g: np.ndarray) -> bool:
            c, ids, _ = det.detectMarkers(g)
            if ids is None or k not in ids.ravel():
                return False
            q = c[list(ids.ravel()).index(k)].reshape(4, 2).astype(np.float64)
            ok, _, _ = cv2.solvePnP(obj1, q, K, dist, flags=cv2.SOLVEPNP_IPPE_SQUARE)
            return bool(ok)

        return step

    def cv_board_step() -> Callable[[np.ndarray], bool]:
        def step(g: np.ndarray) -> bool:
            cc, ci, _, _ = cdet.detectBoard(g)
            if ci is None or len(ci) < 6:
                return False
            o, i = cvb.matchImagePoints(cc, ci)
            ok, _, _ = cv2.solvePnP(o, i, K, dist)
            return bool(ok)

        return step

    return {
        "MarkerMapTracker (10 markers)": (
            imageform(lambda: MarkerMapTracker(whole, K, d)),
            cv_map_step,
        ),
        "MarkerMapTracker, whole frame each (predict=False)": (
            imageform(lambda: MarkerMapTracker(whole, K, d, predict=False)),
            cv_map_step,
        ),
        f"MarkerTracker (marker {k})": (
            imageform(lambda: MarkerTracker(k, side, K, d, dictionary=b.dictionary)),
            cv_one_step,
        ),
        "BoardTracker (ChArUco)": (
            imageform(lambda: BoardTracker(board, K, d, square=b.square)),
            cv_board_step,
        ),
    }


def _time(fresh: Callable[[], Callable[[np.ndarray], bool]], frames: list) -> tuple[float, int]:
    step = fresh()
    found = 0
    t0 = time.process_time()
    for g in frames:
        found += step(g)
    return 1e3 * (time.process_time() - t0) / len(frames), found


def main() -> None:
    import cv2

    from benchmarks.check_track_fresh import sequences

    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    cam = sequences(args.data, False)[0]
    cam.frames = cam.load()[70:111]
    big = copy.copy(cam)
    big.frames = [
        cv2.resize(f, None, fx=SCALE, fy=SCALE, interpolation=cv2.INTER_CUBIC) for f in cam.frames
    ]
    photos = next(s for s in sequences(args.data, True) if s.name == "bittner photos")
    photos.frames = photos.load()
    sets = [
        ("webcam 1280 x 720", cam, cam.K),
        (f"12 Mpx (webcam x {SCALE})", big, _scaled(cam.K, SCALE)),
        ("photographs 4096 x 3072", photos, photos.K),
    ]
    rows = []
    for label, seq, K in sets:
        loops = _loops(seq, np.asarray(K, np.float64), np.asarray(seq.dist, np.float64))
        for name, (mine, theirs) in loops.items():
            if ("photographs" in label and "Board" not in name) or (
                "whole frame" in name and "12 Mpx" not in label
            ):
                continue
            _time(mine, seq.frames), _time(theirs, seq.frames)  # warm-up
            a, b = [], []
            for _ in range(args.repeat):
                ta, fa = _time(mine, seq.frames)
                tb, fb = _time(theirs, seq.frames)
                a.append(ta)
                b.append(tb)
            ma, mb = statistics.median(a), statistics.median(b)
            rows.append(
                [
                    label,
                    name,
                    f"{len(seq.frames)} x {seq.frames[0].shape[1]} x {seq.frames[0].shape[0]}",
                    f"{fa} / {fb}",
                    f"{ma:.1f}",
                    f"{mb:.1f}",
                    f"{ma / mb:.2f}",
                ]
            )
    print(header("Marker and board trackers on webcam and 12 Mpx frames: CPU ms a frame"))
    print(
        markdown_table(
            [
                "frames",
                "imageform tracker",
                "frames x width x height",
                "frames with a pose: imageform / OpenCV",
                "imageform ms a frame (mean)",
                "OpenCV ms a frame (mean)",
                "ratio imageform / OpenCV",
            ],
            rows,
        )
    )
    print(
        f"\nMedian over {args.repeat} runs after a warm-up (loops interleaved); CPU time of "
        "the process, one thread each."
    )


if __name__ == "__main__":
    main()
