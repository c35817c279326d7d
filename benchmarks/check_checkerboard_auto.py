"""A checkerboard of unknown size (``pattern_size="auto"``, ``--board auto``) in real photographs.

Each set is a folder of one camera's views of one board, given as ``NAME=GLOB:COLSxROWS`` (the
board's inner corners, the truth), or ``NAME=GLOB:none`` for photographs without a board. Per
set the table gives:

- *auto, each view alone*: the views where ``find_checkerboard(view, "auto")`` finds the true
  size, another size (wrong), or none (refused: a board whose outer squares reach the image's
  border, or a larger grid seen beside it, cannot be sized);
- *the set* (``find_checkerboards(views, "auto")``, what ``imageform calibrate --board auto``
  does): the size it settles on and the views found with it, against
  ``find_checkerboard(view, (cols, rows))`` given the true size, and OpenCV 5.0's
  ``findChessboardCornersSB`` (exhaustive and accuracy flags) given it;
- *crops*: random windows of each view with a board (``--crops`` per view, 50-100 % of the
  width and height, seed ``--seed``), most of them cutting the board: a window whose board
  comes out at any size but the true one is *wrong*; a cut board must come out as none;
- CPU seconds of auto and of the given size over the set's views.

A view of another size than most of its set's (one 1281 x 721 view among 1280 x 720 ones) is
left out.

Sets used on 2026-11-29 (photographs not in the repository; public repositories, no
redistribution implied): OpenCV's ``left*.jpg`` (../shared/data/opencv-left, 9 x 6);
github.com/dreameer/stereocalibrate ``imgdata/data1`` (7 x 5), ``data2`` and ``data3``
(7 x 7), 320 x 240 webcam views; github.com/Jackson-coder/calibrate ``0*.jpg`` (11 x 8,
1280 x 960, a wide-angle lens); github.com/bytedeco/javacv-examples (c8aff16)
``OpenCV_Cookbook/data/chessboards`` (6 x 4, 320 x 240 views through a fisheye lens);
held out while the rule was set, run once after: github.com/udacity/CarND-Camera-Calibration
(a9c8b5b, MIT) ``calibration_wide/GOPR*.jpg`` (8 x 6, a GoPro, 1280 x 960) and
github.com/udacity/CarND-Advanced-Lane-Lines (91b0803, MIT) ``camera_cal`` (9 x 6, a car's
camera, 1280 x 720, boards cut by the frame); without a board: Kodak (24), and the
vanishing-point photographs of ``check_vp_real.py`` (236: York Urban, Eurasian Cities,
streets, buildings, landscapes). Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_checkerboard_auto.py left=DIR/left*.jpg:9x6 ... kodak=DIR/*.png:none
"""

from __future__ import annotations

import argparse
import glob
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table


def _read(path: str) -> np.ndarray | None:
    from imageform.io import read_image

    try:
        return np.asarray(read_image(path))
    except Exception:  # an unreadable file is left out of the set
        return None


def _set_row(name: str, files: list[str], size: tuple[int, int], crops: int, seed: int) -> list:
    from imageform.geometry import find_checkerboard, find_checkerboards

    truth = tuple(sorted(size, reverse=True))
    views = [v for v in (_read(f) for f in files) if v is not None]
    shapes = [v.shape[:2] for v in views]
    common = max(set(shapes), key=shapes.count)  # one camera: a stray size is left out
    views = [v for v in views if v.shape[:2] == common]
    right = wrong = none = 0
    t_auto = t_fixed = 0.0
    fixed = []
    for v in views:
        t0 = time.process_time()
        a = find_checkerboard(v, "auto")
        t_auto += time.process_time() - t0
        t0 = time.process_time()
        q = find_checkerboard(v, size)
        t_fixed += time.process_time() - t0
        fixed.append(q)
        if not a.found:
            none += 1
        elif a.pattern_size == truth:
            right += 1
        else:
            wrong += 1
    sb = sum(_opencv_sb(v, size) for v in views)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = find_checkerboards(views, "auto")
    sizes = {r.pattern_size for r in res if r.found}
    settled = "x".join(map(str, sizes.pop())) if len(sizes) == 1 else "none"
    set_found = sum(r.found for r in res)
    rng = np.random.default_rng(seed)
    c_n = c_found = c_wrong = c_cut_found = 0
    for v, q in zip(views, fixed, strict=True):
        if not q.found:
            continue
        h, w = v.shape[:2]
        for _ in range(crops):
            ch, cw = int(h * rng.uniform(0.5, 1.0)), int(w * rng.uniform(0.5, 1.0))
            y0, x0 = int(rng.integers(0, h - ch + 1)), int(rng.integers(0, w - cw + 1))
            a = find_checkerboard(v[y0 : y0 + ch, x0 : x0 + cw], "auto")
            c = q.corners - [x0, y0]
            whole = bool(np.all((c > 0) & (c < [cw - 1, ch - 1])))
            c_n += 1
            if a.found:
                c_found += 1
                c_wrong += a.pattern_size != truth
                c_cut_found += not whole
    return [
        name,
        f"{size[0]} x {size[1]}",
        len(views),
        right,
        wrong,
        none,
        settled,
        f"{set_found} / {sum(q.found for q in fixed)} / {sb}",
        f"{c_n}: {c_found} found ({c_cut_found} of them cut), {c_wrong} wrong",
        f"{t_auto:.2f} / {t_fixed:.2f}",
    ]


def _opencv_sb(view: np.ndarray, size: tuple[int, int]) -> bool:
    """OpenCV 5.0's ``findChessboardCornersSB`` (exhaustive, accuracy flags) finds the board."""
    import cv2

    g = view if view.ndim == 2 else view[..., 0] if view.shape[-1] == 1 else None
    if g is None:
        g = cv2.cvtColor(np.ascontiguousarray(view[..., :3]), cv2.COLOR_RGB2GRAY)
    flags = cv2.CALIB_CB_EXHAUSTIVE + cv2.CALIB_CB_ACCURACY
    return bool(cv2.findChessboardCornersSB(np.ascontiguousarray(g), size, flags=flags)[0])


def _negative_row(name: str, files: list[str]) -> list:
    from imageform.geometry import find_checkerboard

    n = found = 0
    t = 0.0
    for f in files:
        v = _read(f)
        if v is None:
            continue
        n += 1
        t0 = time.process_time()
        found += find_checkerboard(v, "auto").found
        t += time.process_time() - t0
    return [name, "none", n, "-", found, n - found, "-", "-", "-", f"{t:.2f} / -"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sets", nargs="+", help="NAME=GLOB:COLSxROWS or NAME=GLOB:none")
    ap.add_argument("--crops", type=int, default=6, help="random windows per view")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(header("A checkerboard of unknown size in real photographs: imageform"))
    rows = []
    for spec in args.sets:
        name, rest = spec.split("=", 1)
        pattern, _, board = rest.rpartition(":")
        files = sorted(glob.glob(pattern))
        if board == "none":
            rows.append(_negative_row(name, files))
        else:
            cols, rws = (int(x) for x in board.lower().split("x"))
            rows.append(_set_row(name, files, (cols, rws), args.crops, args.seed))
    cols_ = [
        "set",
        "board",
        "views",
        "auto alone: right size",
        "wrong size",
        "none",
        "the set's size (auto)",
        "views found: auto set / size given / OpenCV SB, size given",
        "crops",
        "CPU s: auto / size given",
    ]
    print(markdown_table(cols_, rows))


if __name__ == "__main__":
    main()
