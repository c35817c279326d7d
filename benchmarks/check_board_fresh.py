"""Checkerboards in fresh real calibration sets: imageform against OpenCV, tuning and held-out.

Each set is a folder of one camera's views of one board, given on the command line as
``NAME=GLOB:COLSxROWS[:EVERY][:heldout]`` (inner corners; every ``EVERY``-th file of the sorted
glob, 1 by default; ``heldout`` marks a set kept out while rules were studied). Per view, on
the same uint8 grey image: imageform's ``find_checkerboard`` given the size and with
``"auto"``; OpenCV 5.0's ``findChessboardCornersSB`` (``CALIB_CB_EXHAUSTIVE |
CALIB_CB_ACCURACY``) and ``findChessboardCorners`` (adaptive threshold, normalise) followed by
``cornerSubPix`` (5 x 5 window, 30 iterations, 0.001 px). Per set the table gives the views
each finds, the views ``"auto"`` sizes right / wrong, the views only imageform or only OpenCV
(either detector) finds, and per detector, on its own found views: the RMS reprojection error
of ``cv2.calibrateCamera`` (default model) and the held-out RMS: the views split by parity,
each half calibrates and the other half's views are fitted with those intrinsics held
(``cv2.solvePnP``), both ways pooled; then the same two figures on the views all three
detectors find (the same views for each: an accuracy proxy). Where fewer than 6 views are
found the figures are left out. The last columns are median CPU milliseconds per view (the
process's time, one thread each: ``cv2.setNumThreads(1)``, ``NUMBA_NUM_THREADS=1``), after
one untimed call of each on the set's first view.

Sets used on 2026-11-30 (photographs not in the repository: no licence is stated with any of
them; public repositories, no redistribution implied; ``git show COMMIT:PATH`` gives them):

- tuning (studied): ``sourish-640`` github.com/sourishg/stereo-calibration (2578889)
  ``calib_imgs/1/*.jpg`` (58 views of a stereo webcam pair, 640 x 360, 9 x 6);
  ``sourish-270`` the same repository's ``calib_imgs/2/*.jpg`` (56 views, 270 x 180, 9 x 6:
  squares of 6-12 px); ``rex-blur`` github.com/RexGoliath1/dumb-markers (6bb5866)
  ``calibration_images/*.png`` (300 views, every third used, 1920 x 1080 webcam frames of a
  hand-held 8 x 6 board, most of them motion-blurred); ``hepro-c2``
  github.com/hepromark/StereoVisionDepthMap (ea2d0c1) ``Calibration/C2/imgs/*.jpg`` (13 views,
  1920 x 1080 webcam, 8 x 6 on a table).
- held out (run once, after the change): ``greninja`` github.com/greninja09/Camera_Calibration
  (14f24cd) ``calibration_images/*.jpg`` (18 views, 1980 x 891, 9 x 6 shown on a tablet's
  screen); ``christos`` github.com/ChristosP1/Camera-Geometric-Calibration (75d2edb)
  ``calibration_inputs/*.jpg`` (25 phone views, 1197 x 1600, 9 x 6 on a glossy board: glare).

Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_board_fresh.py "sourish-640=DIR/sourishg1/left*.jpg:9x6" ...
"""

from __future__ import annotations

import argparse
import glob
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # benchmarks._common; imageform from PYTHONPATH (a "before" tree)

from benchmarks._common import header, markdown_table  # noqa: E402


def _spec(spec: str) -> tuple[str, list[str], tuple[int, int], bool]:
    name, rest = spec.split("=", 1)
    parts = rest.split(":")
    pattern, board = parts[0], parts[1]
    every = int(parts[2]) if len(parts) > 2 and parts[2].isdigit() else 1
    held = "heldout" in parts[2:]
    cols, rows = (int(v) for v in board.lower().split("x"))
    return name, sorted(glob.glob(pattern))[::every], (cols, rows), held


def _rms(cv2, obj, pts, shape) -> tuple[str, str]:  # type: ignore[no-untyped-def]
    """Calibration RMS on all views and the parity-split held-out RMS (px)."""
    if len(pts) < 6:
        return "-", "-"
    objs = [obj] * len(pts)
    rms = cv2.calibrateCamera(objs, pts, shape, None, None)[0]
    sq, n = 0.0, 0
    for half in (0, 1):
        fit = pts[half::2]
        test = pts[1 - half :: 2]
        _, k, dist, _, _ = cv2.calibrateCamera([obj] * len(fit), fit, shape, None, None)
        for p in test:
            _, rv, tv = cv2.solvePnP(obj, p, k, dist)
            q, _ = cv2.projectPoints(obj, rv, tv, k, dist)
            sq += float(((q.reshape(-1, 2) - p.reshape(-1, 2)) ** 2).sum())
            n += len(p)
    return f"{rms:.4f}", f"{np.sqrt(sq / n):.4f}"


def main() -> None:
    import cv2

    from imageform.errors import IllConditionedWarning
    from imageform.geometry import checkerboard_points, find_checkerboard

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sets", nargs="+", help="NAME=GLOB:COLSxROWS[:EVERY][:heldout]")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    warnings.simplefilter("ignore", IllConditionedWarning)
    sb_flags = cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    cl_flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    term = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    rows = []
    for name, files, size, held in (_spec(s) for s in args.sets):
        truth = tuple(sorted(size, reverse=True))
        obj = checkerboard_points(size, 1.0).astype(np.float32)
        found: dict[str, list[np.ndarray]] = {"if": [], "sb": [], "cl": []}
        common: dict[str, list[np.ndarray]] = {"if": [], "sb": [], "cl": []}
        times: dict[str, list[float]] = {"if": [], "auto": [], "sb": [], "cl": []}
        auto_right = auto_wrong = only_if = only_cv = views = 0
        shape = None
        for f in files:
            g = cv2.imread(f, cv2.IMREAD_GRAYSCALE)
            if g is None:
                continue
            if shape is None:
                shape = g.shape[::-1]
                find_checkerboard(g, size)  # untimed first calls
                cv2.findChessboardCornersSB(g, size, flags=sb_flags)
            if g.shape[::-1] != shape:
                continue
            views += 1
            t0 = time.process_time()
            res = find_checkerboard(g, size)
            times["if"].append(time.process_time() - t0)
            t0 = time.process_time()
            auto = find_checkerboard(g, "auto")
            times["auto"].append(time.process_time() - t0)
            t0 = time.process_time()
            ok_sb, c_sb = cv2.findChessboardCornersSB(g, size, flags=sb_flags)
            times["sb"].append(time.process_time() - t0)
            t0 = time.process_time()
            ok_cl, c_cl = cv2.findChessboardCorners(g, size, flags=cl_flags)
            if ok_cl:
                c_cl = cv2.cornerSubPix(g, c_cl, (5, 5), (-1, -1), term)
            times["cl"].append(time.process_time() - t0)
            if auto.found:
                auto_right += auto.pattern_size == truth
                auto_wrong += auto.pattern_size != truth
            if res.found:
                found["if"].append(np.asarray(res.corners, np.float32).reshape(-1, 1, 2))
            if ok_sb:
                found["sb"].append(c_sb.astype(np.float32).reshape(-1, 1, 2))
            if ok_cl:
                found["cl"].append(c_cl.astype(np.float32).reshape(-1, 1, 2))
            if res.found and ok_sb and ok_cl:
                for k in common:
                    common[k].append(found[k][-1])
            cv_any = bool(ok_sb) or bool(ok_cl)
            only_if += res.found and not cv_any
            only_cv += cv_any and not res.found
        figs = {k: _rms(cv2, obj, v, shape) for k, v in found.items()}
        same = {k: _rms(cv2, obj, v, shape) for k, v in common.items()}
        ms = {k: f"{1000 * statistics.median(v):.1f}" if v else "-" for k, v in times.items()}
        rows.append([
            name + (" (held out)" if held else ""), f"{size[0]} x {size[1]}",
            f"{shape[0]} x {shape[1]}" if shape else "-", views,
            len(found["if"]), f"{auto_right} / {auto_wrong}", len(found["sb"]), len(found["cl"]),
            only_if, only_cv,
            f"{figs['if'][0]} / {figs['if'][1]}", f"{figs['sb'][0]} / {figs['sb'][1]}",
            f"{figs['cl'][0]} / {figs['cl'][1]}", len(common["if"]),
            " / ".join(same[k][0] for k in ("if", "sb", "cl")),
            " / ".join(same[k][1] for k in ("if", "sb", "cl")),
            ms["if"], ms["auto"], ms["sb"], ms["cl"],
        ])  # fmt: skip
        print(name, "done", file=sys.stderr, flush=True)
    print(header("Checkerboards in fresh real calibration sets: imageform vs OpenCV"))
    print(
        markdown_table(
            ["set", "board", "image", "views", "imageform found", "auto right / wrong",
             "SB found", "classic found", "only imageform", "only OpenCV",
             "imageform RMS / held-out", "SB RMS / held-out", "classic RMS / held-out",
             "views all find", "RMS there: imageform / SB / classic",
             "held-out there: imageform / SB / classic", "imageform ms", "auto ms", "SB ms",
             "classic ms"],
            rows,
        )
    )  # fmt: skip


if __name__ == "__main__":
    main()
