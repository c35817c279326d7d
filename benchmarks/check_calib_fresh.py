"""``imageform calibrate`` on fresh real calibration sets against OpenCV, tuning and held-out.

Each set is one camera's views of one checkerboard, given on the command line as
``NAME=GLOB:COLSxROWS[:EVERY][:heldout]`` (inner corners; every ``EVERY``-th file of the
sorted glob; ``heldout`` marks a set kept out while rules were studied). Two tables.

Detection, per view on the same uint8 grey image: imageform's ``find_checkerboard`` given the
size and with ``"auto"``; OpenCV 5's ``findChessboardCornersSB`` (``CALIB_CB_EXHAUSTIVE |
CALIB_CB_ACCURACY``) and ``findChessboardCorners`` (adaptive threshold, normalise) +
``cornerSubPix`` (5 x 5 window, 30 iterations, 0.001 px). Columns: views each finds, the views
``"auto"`` sizes right / wrong / not at all, the views only imageform or only OpenCV (either
detector) finds, and where imageform and OpenCV's SB both find the board the median and the
largest distance between the same corners (the grids matched up to the board's symmetries;
a distance of squares means a shifted or flipped grid), median CPU ms per view.

Calibration: ``imageform calibrate --board COLSxROWS`` and ``--board auto`` (the command line,
Brown-Conrady default model) against ``cv2.calibrateCamera`` (default flags) on every view
OpenCV finds (SB's corners, else the classic detector's). Columns: views used, RMS
reprojection error, fx, fy, cx, cy, k1; and where the set's repository ships its own
calibration, that result for reference.

Sets used on 2026-12-01 (photographs not in the repository; public repositories, no
redistribution implied; ``git show COMMIT:PATH`` gives them). Split by repository before any
was run; the held-out files' SHA-256 are listed in the results file.

- tuning: ``tamara-*`` github.com/TamaraRudaljevic/Camera_calibration (2f34e4d): ``pic``
  ``Python/newCalibrationImages/Pic_*.jpg`` and ``test`` ``.../Test_*.jpg`` (13 + 13 views,
  625 x 448, 9 x 6: Bouguet's toolbox-style grey views, monitor and clutter behind), ``r1``
  ``r2`` ``r3`` ``CameraCalibration/imagesCalib/{1,2,3}/*.png`` (8, 12, 5 views, 1920 x 1080
  and 960 x 540, 9 x 6, rendered boards on a flat grey background); ``chusei-left/right``
  github.com/GoDKyLiN/chusei_3D_webcam_stereo_calibrator (5ea7b32) ``build/{left,right}/*.jpg``
  (118 views each, every 4th used, 320 x 480 halves of a side-by-side stereo webcam: pixels
  twice as tall as wide, 8 x 6); ``prozyr`` github.com/prozyr/Chessboard_Based_Camera_Calibration
  (293e7ba) ``images_smaller/*.jpg`` (23 phone views, 700 x 934, a wooden chess board held in
  hand: 7 x 7 inner corners, wood grain, a seam across it), ``prozyr-wide`` its
  ``photos/*.jpg`` (4 views, 1920 x 1080, a wide-angle camera over a desk).
- held out (run once, at the end): ``ksonod`` github.com/ksonod/camera_calibration (32120e9)
  ``data/*.jpg`` (12 views, 768 x 1024, 8 x 5, a printed calib.io board, MIT licence);
  ``waveshare-left/right`` github.com/keli95566/Waveshare_Stereo_Calib (9efc78f)
  ``images/{left,right}_*.png`` (31 views each, 960 x 540, IMX219-83 wide-angle stereo pair,
  6 x 8); ``wildcat`` github.com/wildcat5566/OpenCV_Camera_Calibration (d8475b3)
  ``chessboard/*.jpg`` (16 views, 9 x 6).

Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_calib_fresh.py "prozyr=DIR/prozyr/*.jpg:7x7" ...
"""

from __future__ import annotations

import argparse
import glob
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
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


def _apart(a: np.ndarray, b: np.ndarray, size: tuple[int, int]) -> float:
    """Largest distance between the same corners, the grids matched up to the board's symmetry."""
    cols, rows = size
    ga = a.reshape(rows, cols, 2)
    gb = b.reshape(rows, cols, 2)
    cands = [gb, gb[::-1, ::-1]]
    if cols == rows:
        cands += [gb.transpose(1, 0, 2), gb.transpose(1, 0, 2)[::-1, ::-1]]
        cands += [gb[::-1, :], gb[:, ::-1]]
    best = min(float(np.sqrt(((ga - c) ** 2).sum(-1)).max()) for c in cands)
    return best


def _ours(files: list[str], board: str) -> dict[str, object]:
    """``imageform calibrate`` on the files (copied names kept) with ``--board``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cam.toml"
        cmd = [sys.executable, "-m", "imageform", "calibrate", *files, "--board", board,
               "-o", str(out)]  # fmt: skip
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        if p.returncode != 0 or not out.exists():
            msg = (p.stderr.strip().splitlines() or ["?"])[-1]
            return {"error": msg[:160], "wall": wall}
        cam = tomllib.loads(out.read_text())
        first = [ln for ln in p.stdout.splitlines() if ln.startswith("board:")]
        return {"cam": cam, "wall": wall, "board": first[0] if first else ""}


def main() -> None:
    import cv2

    from imageform.errors import IllConditionedWarning
    from imageform.geometry import checkerboard_points, find_checkerboard

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sets", nargs="+", help="NAME=GLOB:COLSxROWS[:EVERY][:heldout]")
    ap.add_argument("--ref", action="append", default=[], help="NAME=fx,fy,cx,cy,k1 (repo's own)")
    ap.add_argument("--list", action="store_true", help="print the views only one side finds")
    args = ap.parse_args()
    refs = {r.split("=")[0]: [float(v) for v in r.split("=")[1].split(",")] for r in args.ref}
    cv2.setNumThreads(1)
    warnings.simplefilter("ignore", IllConditionedWarning)
    sb_flags = cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    cl_flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    term = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    det_rows, cal_rows, notes = [], [], []
    for name, files, size, held in (_spec(s) for s in args.sets):
        label = name + (" (held out)" if held else "")
        truth = tuple(sorted(size, reverse=True))
        obj = checkerboard_points(size, 1.0).astype(np.float32)
        n_if = n_sb = n_cl = only_if = only_cv = 0
        auto_right = auto_wrong = auto_none = 0
        apart: list[float] = []
        times: dict[str, list[float]] = {"if": [], "auto": [], "sb": [], "cl": []}
        cv_pts: list[np.ndarray] = []
        used: list[str] = []
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
            used.append(f)
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
            n_if += bool(res.found)
            n_sb += bool(ok_sb)
            n_cl += bool(ok_cl)
            if auto.found:
                auto_right += auto.pattern_size == truth
                auto_wrong += auto.pattern_size != truth
                if auto.pattern_size != truth:
                    notes.append(f"{name} {Path(f).name}: auto chose {auto.pattern_size}")
            else:
                auto_none += 1
            cv_any = bool(ok_sb) or bool(ok_cl)
            if cv_any:
                cv_pts.append((c_sb if ok_sb else c_cl).astype(np.float32).reshape(-1, 1, 2))
            if res.found and ok_sb:
                d = _apart(np.asarray(res.corners, float), c_sb.reshape(-1, 2).astype(float), size)
                apart.append(d)
                if d > 2.0:
                    notes.append(f"{name} {Path(f).name}: grids {d:.1f} px apart")
            if res.found and not cv_any:
                only_if += 1
                notes.append(f"{name} {Path(f).name}: only imageform")
            if cv_any and not res.found:
                only_cv += 1
                notes.append(f"{name} {Path(f).name}: only OpenCV ({res.reason})")
        ms = {k: f"{1000 * statistics.median(v):.0f}" if v else "-" for k, v in times.items()}
        det_rows.append([
            label, f"{size[0]} x {size[1]}", f"{shape[0]} x {shape[1]}" if shape else "-",
            len(used), n_if, n_sb, n_cl, f"{auto_right} / {auto_wrong} / {auto_none}",
            only_if, only_cv,
            f"{statistics.median(apart):.2f} / {max(apart):.2f}" if apart else "-",
            f"{ms['if']} / {ms['auto']} / {ms['sb']} / {ms['cl']}",
        ])  # fmt: skip

        def fmt(fx: float, fy: float, cx: float, cy: float, k1: float) -> list[str]:
            return [f"{fx:.1f}", f"{fy:.1f}", f"{cx:.1f}", f"{cy:.1f}", f"{k1:.3f}"]

        if len(cv_pts) >= 3 and shape is not None:
            rms, k, dist, _, _ = cv2.calibrateCamera([obj] * len(cv_pts), cv_pts, shape, None, None)
            d = dist.ravel()
            cal_rows.append([label, "OpenCV", len(cv_pts), f"{rms:.3f}",
                             *fmt(k[0, 0], k[1, 1], k[0, 2], k[1, 2], d[0]), "-"])  # fmt: skip
        else:
            cal_rows.append([label, "OpenCV", len(cv_pts), "-", "-", "-", "-", "-", "-", "-"])
        for board in (f"{size[0]}x{size[1]}", "auto"):
            r = _ours(used, board)
            what = f"imageform --board {board}"
            if "error" in r:
                cal_rows.append([label, what, 0, "-", "-", "-", "-", "-", "-", f"{r['wall']:.0f}"])
                notes.append(f"{name} --board {board}: {r['error']}")
                continue
            cam = r["cam"]
            i, dd, pv = cam["intrinsics"], cam["distortion"], cam["provenance"]  # type: ignore[index]
            cal_rows.append([label, what, pv["views_used"], f"{pv['rms_px']:.3f}",
                             *fmt(i["fx"], i["fy"], i["cx"], i["cy"], dd["k1"]),
                             f"{r['wall']:.0f}"])  # fmt: skip
            if board == "auto":
                notes.append(f"{name} --board auto: {r['board']}")
        if name in refs:
            cal_rows.append([label, "repository's own", "-", "-", *fmt(*refs[name]), "-"])
        print(name, "done", file=sys.stderr, flush=True)
    print(header("imageform calibrate on fresh real calibration sets: imageform vs OpenCV"))
    print("### Detection per view\n")
    print(
        markdown_table(
            ["set", "board", "image", "views", "imageform found", "SB found", "classic found",
             "auto right / wrong / none", "only imageform", "only OpenCV",
             "imageform vs SB: median / max px", "CPU ms: imageform / auto / SB / classic"],
            det_rows,
        )
    )  # fmt: skip
    print("\n### Calibration (Brown-Conrady k1, k2, p1, p2, k3)\n")
    print(
        markdown_table(
            ["set", "by", "views used", "RMS px", "fx", "fy", "cx", "cy", "k1", "wall s"],
            cal_rows,
        )
    )  # fmt: skip
    if notes:
        print("\nNotes:\n")
        for n in notes:
            print(f"- {n}")


if __name__ == "__main__":
    main()
