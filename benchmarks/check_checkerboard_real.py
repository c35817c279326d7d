"""Checkerboards in real calibration sets nobody on the project made: imageform vs OpenCV.

Each set is a folder of one camera's (or one stereo rig's) views of one board, given on the
command line as ``NAME=FOLDER:COLSxROWS`` (inner corners). For every view imageform's
``find_checkerboard`` and OpenCV 5.0's ``findChessboardCorners`` (adaptive threshold,
normalise; ``cornerSubPix`` 11 x 11 as its tutorial, and 5 x 5) run on the same uint8 grey
image. The
table gives per set: the views each finds, the views only one finds, how far apart the two
put the corners of the views both find (median / largest, px, nearest corner: a square
board's corner order can differ; OpenCV's with the tutorial's window), and the RMS
reprojection error of ``cv2.calibrateCamera`` (default flags) on each detector's corners of
the views both find (an accuracy proxy: the
same camera, model and views), with imageform's ``calibrate_camera`` on its own corners
beside it (or the error it raises). Sets used on 2026-11-29 (photographs not in the
repository; public repositories, no redistribution implied):

- ``webcam-tray``: github.com/dreameer/stereocalibrate ``imgdata/data1`` (28 views, 320 x 240,
  7 x 5 on a tray held at arm's length: one orientation in every view).
- ``webcam-glass``: the same repository's ``imgdata/data2`` (28 views, 7 x 7, a poster on a
  glass door, a window frame just past the board's edge).
- ``webcam-hall``: ``imgdata/data3`` (22 readable views, 7 x 7).
- ``wide-angle``: github.com/Jackson-coder/calibrate ``0*.jpg`` (20 views, 1280 x 960,
  11 x 8, a lens with k1 about -0.39, boards turned steeply).
- ``ir-stereo``: github.com/Barry-Liang/stereoCalibrate (50 views, 640 x 512, 9 x 6, dark
  infrared-like views).
- ``opencv-stereo``: OpenCV's samples/data ``left*.jpg`` and ``right*.jpg`` (26 views, 9 x 6).

Run with ``--src`` to measure another source tree in the same way (a "before" checkout)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_checkerboard_real.py \\
        webcam-tray=DIR:7x5 webcam-glass=DIR:7x7 ...
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np


def _sets(specs: list[str]) -> list[tuple[str, Path, tuple[int, int]]]:
    out = []
    for spec in specs:
        name, rest = spec.split("=", 1)
        folder, board = rest.rsplit(":", 1)
        cols, rows = (int(v) for v in board.lower().split("x"))
        out.append((name, Path(folder), (cols, rows)))
    return out


def main() -> None:
    import warnings

    import cv2

    from benchmarks._common import header, markdown_table
    from imageform.errors import IllConditionedWarning
    from imageform.geometry import calibrate_camera, checkerboard_points, find_checkerboard

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sets", nargs="+", help="NAME=FOLDER:COLSxROWS")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    warnings.simplefilter("ignore", IllConditionedWarning)  # the notes; the RMS is the figure
    rows = []
    for name, folder, size in _sets(args.sets):
        files = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".png"))
        obj = checkerboard_points(size, 1.0).astype(np.float32)
        ours_n = cv_n = only_ours = only_cv = 0
        med, worst, t_ours, t_cv = [], [], [], []
        both_ours, both_cv, both_cv5 = [], [], []
        own = []
        shape = None
        for f in files:
            g = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
            if g is None:
                continue
            shape = g.shape[::-1]
            t0 = time.process_time()
            res = find_checkerboard(g, size)
            t_ours.append(time.process_time() - t0)
            t0 = time.process_time()
            flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
            ok, c = cv2.findChessboardCorners(g, size, flags=flags)
            if ok:
                c5 = cv2.cornerSubPix(g, c.copy(), (5, 5), (-1, -1), (3, 30, 0.001))
                c = cv2.cornerSubPix(g, c, (11, 11), (-1, -1), (3, 30, 0.001))
            t_cv.append(time.process_time() - t0)
            ours_n += res.found
            cv_n += bool(ok)
            only_ours += res.found and not ok
            only_cv += bool(ok) and not res.found
            if res.found:
                own.append(np.asarray(res.corners, np.float32))
            if res.found and ok:
                p, q = np.asarray(res.corners), c.reshape(-1, 2)
                d = np.min(np.linalg.norm(p[:, None] - q[None], axis=-1), axis=1)
                med.append(float(np.median(d)))
                worst.append(float(d.max()))
                both_ours.append(p.astype(np.float32).reshape(-1, 1, 2))
                both_cv.append(c)
                both_cv5.append(c5)
        rms_ours = rms_cv = rms_cv5 = "-"
        if len(both_ours) >= 3 and shape is not None:
            objs = [obj] * len(both_ours)
            rms_ours = f"{cv2.calibrateCamera(objs, both_ours, shape, None, None)[0]:.4f}"
            rms_cv = f"{cv2.calibrateCamera(objs, both_cv, shape, None, None)[0]:.4f}"
            rms_cv5 = f"{cv2.calibrateCamera(objs, both_cv5, shape, None, None)[0]:.4f}"
        try:
            cal = calibrate_camera([obj.astype(np.float64)] * len(own), own, shape)
            ours_cal = f"{cal.rms:.4f}"
        except Exception as exc:  # what a user sees: the first words of the message
            ours_cal = f"{type(exc).__name__}: {str(exc)[:60]}"
        rows.append([
            name, f"{size[0]} x {size[1]}", f"{shape[0]} x {shape[1]}" if shape else "-",
            len(t_ours), ours_n, cv_n, only_ours, only_cv,
            f"{statistics.median(med):.3f} / {max(worst):.3f}" if med else "-",
            rms_ours, rms_cv, rms_cv5, ours_cal,
            f"{1000 * statistics.median(t_ours):.1f}", f"{1000 * statistics.median(t_cv):.1f}",
        ])  # fmt: skip
    print(header("Checkerboards in real calibration sets: imageform vs OpenCV"))
    print(
        markdown_table(
            ["set", "board", "image", "views", "imageform found", "OpenCV found",
             "only imageform", "only OpenCV", "corner distance median / max (px)",
             "RMS cv2 calib on imageform's", "RMS cv2 calib on OpenCV's (11 x 11)",
             "RMS cv2 calib on OpenCV's (5 x 5)",
             "imageform calibrate_camera RMS", "imageform CPU ms", "OpenCV CPU ms"],
            rows,
        )
    )  # fmt: skip


if __name__ == "__main__":
    main()
