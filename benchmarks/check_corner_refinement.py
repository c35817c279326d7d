"""Checkerboard corner refinement: point symmetry against gradient orthogonality and OpenCV.

``find_checkerboard(view, board, method=M)`` with ``M = "gradient"`` (``refine_corners``,
OpenCV's ``cornerSubPix`` method, imageform's refinement before) and ``M = "symmetric"``
(``refine_corners_symmetric`` after it: Schöps et al. 2020), against OpenCV 5.0's
``findChessboardCornersSB`` (no flags) and ``findChessboardCorners`` + ``cornerSubPix`` with a
5 x 5 window (the fairer of OpenCV's windows on small squares).

Real photographs (no truth; an accuracy proxy: the same camera, views and model): per set
(``NAME=GLOB:COLSxROWS[:fisheye]`` on the command line) the RMS reprojection error of a
calibration on each detector's corners of the views all four find (``cv2.fisheye.calibrate``
for ``:fisheye`` sets, else ``cv2.calibrateCamera`` with its default five coefficients) and
the held-out RMS: the views split by parity, each half calibrated and the other half's views
fitted with those intrinsics held (poses only, Levenberg-Marquardt on the pixel error), both
ways pooled. The fitted RMS can drop by overfitting; the held-out one cannot. Also the CPU time
of ``find_checkerboard`` per view with each method (interleaved, median).

Rendered views (truth known): a board of 9 x 6 inner corners in random poses (tilts to 50
deg) through a lens with radial distortion, each pixel the mean of 6 x 6 jittered samples of
the sharp board (exact coverage on average), then a Gaussian blur, vignetting (a 35 % fall-off
to the corners), a shading slope, Gaussian noise and JPEG (quality 85); the median and 95th
percentile of the distance of each found corner to the true one.

Sets used on 2026-11-29 (photographs not in the repository; public repositories, no
redistribution implied; sources in benchmarks/check_calibration_endoscope.py and
check_checkerboard_real.py / check_checkerboard_auto.py): endo-sl (9 x 6, fisheye),
endo-orb (16 x 12, fisheye: interlaced PAL frames), davinci-left (7 x 7, fisheye),
OpenCV's left*.jpg (9 x 6), dreameer/stereocalibrate data1-3 left*.jpg (7 x 5, 7 x 7, 7 x 7),
Jackson-coder/calibrate 0*.jpg (11 x 8), javacv-examples OpenCV_Cookbook chessboards (6 x 4),
udacity CarND-Camera-Calibration calibration_wide (8 x 6) and CarND-Advanced-Lane-Lines
camera_cal (9 x 6). Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_corner_refinement.py endo-orb=DIR/6080HD.cal*.png:16x12:fisheye ... \\
        --out TABLE.md
"""

from __future__ import annotations

import argparse
import glob
import os
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Any, Literal

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table

METHODS: tuple[Literal["gradient", "symmetric"], ...] = ("gradient", "symmetric")
WHO = ("gradient", "symmetric", "SB", "cornerSubPix 5x5")


def _objp(board: tuple[int, int]) -> np.ndarray:
    c, r = board
    g = np.zeros((r * c, 3))
    g[:, :2] = np.mgrid[0:c, 0:r].T.reshape(-1, 2)
    return g


def _flag(cv2: Any, name: str) -> int:
    """A fisheye flag: ``cv2.fisheye.NAME`` in OpenCV 4, ``cv2.NAME`` in OpenCV 5."""
    return int(getattr(cv2.fisheye, name, getattr(cv2, name, 0)))


def _calib(cv2: Any, fisheye: bool, pts: list[np.ndarray], board: tuple[int, int],
           size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, float]:  # fmt: skip
    """Calibrate; return K, the coefficients and the RMS (px) recomputed from the fit."""
    o = _objp(board)
    if fisheye:
        fe = cv2.fisheye
        flags = _flag(cv2, "CALIB_RECOMPUTE_EXTRINSIC") | _flag(cv2, "CALIB_FIX_SKEW")
        crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 300, 1e-15)
        o3 = [o.reshape(1, -1, 3)] * len(pts)
        _, K, D, rv, tv = fe.calibrate(o3, [c.reshape(1, -1, 2) for c in pts], size,
                                       np.zeros((3, 3)), np.zeros((4, 1)), flags=flags,
                                       criteria=crit)  # fmt: skip
        proj = [
            fe.projectPoints(o.reshape(1, -1, 3), r, t, K, D)[0]
            for r, t in zip(rv, tv, strict=True)
        ]
    else:
        crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 1000, 1e-15)
        _, K, D, rv, tv = cv2.calibrateCamera([o.astype(np.float32)] * len(pts),
                                              [c.astype(np.float32) for c in pts], size, None,
                                              None, criteria=crit)  # fmt: skip
        proj = [cv2.projectPoints(o, r, t, K, D)[0] for r, t in zip(rv, tv, strict=True)]
    sq = [np.sum((p.reshape(-1, 2) - c) ** 2, 1) for p, c in zip(proj, pts, strict=True)]
    return K, D, float(np.sqrt(np.mean(np.concatenate(sq))))


def _pose_sq(cv2: Any, fisheye: bool, K: np.ndarray, D: np.ndarray, pts: list[np.ndarray],
             board: tuple[int, int]) -> list[np.ndarray]:  # fmt: skip
    """Squared residuals of views fitted with the intrinsics held (poses only)."""
    from scipy.optimize import least_squares

    o = _objp(board)
    out = []
    for c in pts:
        if fisheye:
            und = cv2.fisheye.undistortPoints(c.reshape(-1, 1, 2), K, D).reshape(-1, 2)
            _, r, t = cv2.solvePnP(o, und, np.eye(3), None)

            def res(p: np.ndarray, c: np.ndarray = c) -> np.ndarray:
                q = cv2.fisheye.projectPoints(o.reshape(1, -1, 3), p[:3], p[3:], K, D)[0]
                return (q.reshape(-1, 2) - c).ravel()

            e = res(least_squares(res, np.r_[r.ravel(), t.ravel()], method="lm").x)
        else:
            _, r, t = cv2.solvePnP(o, c, K, D)
            r, t = cv2.solvePnPRefineLM(o, c, K, D, r, t)
            e = (cv2.projectPoints(o, r, t, K, D)[0].reshape(-1, 2) - c).ravel()
        out.append(np.sum(e.reshape(-1, 2) ** 2, 1))
    return out


def _evaluate(cv2: Any, fisheye: bool, pts: list[np.ndarray], board: tuple[int, int],
              size: tuple[int, int]) -> tuple[float, float]:  # fmt: skip
    """RMS of a calibration on all views, and the held-out RMS (halves by parity)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rms = _calib(cv2, fisheye, pts, board, size)[2]
        held: list[np.ndarray] = []
        for train, test in ((pts[0::2], pts[1::2]), (pts[1::2], pts[0::2])):
            K, D, _ = _calib(cv2, fisheye, train, board, size)
            held += _pose_sq(cv2, fisheye, K, D, test, board)
    return rms, float(np.sqrt(np.mean(np.concatenate(held))))


def _opencv(cv2: Any, grey: np.ndarray, board: tuple[int, int]) -> dict[str, np.ndarray | None]:
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    ok, c = cv2.findChessboardCorners(grey, board, None)
    c5 = cv2.cornerSubPix(grey, c, (5, 5), (-1, -1), crit).reshape(-1, 2) if ok else None
    ok_sb, sb = cv2.findChessboardCornersSB(grey, board, 0)
    return {
        "SB": sb.reshape(-1, 2).astype(np.float64) if ok_sb else None,
        "cornerSubPix 5x5": None if c5 is None else c5.astype(np.float64),
    }


def real_set(cv2: Any, name: str, pattern: str, board: tuple[int, int],
             fisheye: bool) -> list[object]:  # fmt: skip
    """One set's row: views, views each finds, RMS / held-out per detector, CPU per view."""
    from PIL import Image

    from imageform.geometry import find_checkerboard

    found: dict[str, list[np.ndarray | None]] = {w: [] for w in WHO}
    cpu: dict[str, list[float]] = {m: [] for m in METHODS}
    size = (0, 0)
    for f in sorted(glob.glob(pattern)):
        try:
            grey = np.asarray(Image.open(f).convert("L"))
        except Exception:  # an unreadable file is left out
            continue
        size = (grey.shape[1], grey.shape[0])
        for m in METHODS:
            t0 = time.process_time()
            det = find_checkerboard(grey, board, method=m)
            cpu[m].append(time.process_time() - t0)
            found[m].append(np.asarray(det.corners) if det.found else None)
        for w, c in _opencv(cv2, grey, board).items():
            found[w].append(c)
    n = len(found["gradient"])
    every = [k for k in range(n) if all(found[w][k] is not None for w in WHO)]
    row: list[object] = [name, f"{board[0]} x {board[1]}", "fisheye" if fisheye else "plain", n]
    row.append(" / ".join(str(sum(c is not None for c in found[w])) for w in WHO))
    both = [k for k in range(n) if all(found[m][k] is not None for m in METHODS)]
    for m in METHODS:
        rms, held = _evaluate(cv2, fisheye, [found[m][k] for k in both], board, size)  # type: ignore[misc]
        row.append(f"{rms:.4f} / {held:.4f}")
    row.append(len(every))
    for w in WHO:
        pts = [found[w][k] for k in every]
        if len(pts) < 6:
            row.append("—")
            continue
        rms, held = _evaluate(cv2, fisheye, pts, board, size)  # type: ignore[arg-type]
        row.append(f"{rms:.4f} / {held:.4f}")
    row.append(" / ".join(f"{1e3 * statistics.median(cpu[m]):.1f}" for m in METHODS))
    return row


def _render(rng: np.random.Generator, blur: float, k1: float, noise: float,
            jpeg: int, upscale: int = 1) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """A rendered 640 x 480 view of a 9 x 6 board (uint8) and its true inner corners.

    ``upscale``: the same view at ``upscale`` times the size (the blur ``upscale`` times as
    wide, ``6 // upscale`` jittered samples a side per pixel), for large views."""
    import cv2
    from scipy.ndimage import gaussian_filter
    from scipy.spatial.transform import Rotation

    w, h, f = 640 * upscale, 480 * upscale, 520.0 * upscale
    blur = blur * upscale
    cols, rows = 9, 6
    rot = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.radians([45, 45, 20])).as_matrix()
    board_c = np.array([(cols + 1) / 2, (rows + 1) / 2, 0.0])
    t = np.array([rng.uniform(-1.2, 1.2), rng.uniform(-0.8, 0.8), rng.uniform(11.0, 15.0)])

    def to_board(xu: np.ndarray, yu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # ray (xu, yu, 1) meets the board plane: board point p with rot (p - c) + t on the ray
        d = np.stack([xu, yu, np.ones_like(xu)], -1)
        n = rot[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (n @ t) / (d @ n)
        s = np.where(s > 0, s, np.nan)  # the plane behind the camera is not seen
        p = (s[..., None] * d - t) @ rot + board_c
        return p[..., 0], p[..., 1]

    ss = max(1, 6 // upscale)
    img = np.zeros((h, w))
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    for a in range(ss):
        for b in range(ss):
            ju = uu + (a + rng.uniform(0, 1, uu.shape)) / ss - 0.5
            jv = vv + (b + rng.uniform(0, 1, uu.shape)) / ss - 0.5
            xd, yd = (ju - w / 2) / f, (jv - h / 2) / f
            r2 = xd * xd + yd * yd
            bx, by = to_board(xd * (1 + k1 * r2), yd * (1 + k1 * r2))
            inb = (bx >= 0) & (bx < cols + 1) & (by >= 0) & (by < rows + 1)
            margin = (bx >= -0.7) & (bx < cols + 1.7) & (by >= -0.7) & (by < rows + 1.7)
            dark = (np.floor(bx) + np.floor(by)) % 2 == 0
            img += np.where(inb, np.where(dark, 0.12, 0.88), np.where(margin, 0.88, 0.4))
    img /= ss * ss
    img = gaussian_filter(img, blur)
    r2n = ((uu - w / 2) ** 2 + (vv - h / 2) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)
    img = img * (1 - 0.35 * r2n) * (1 + 0.15 * (uu / w - 0.5))
    img = img + rng.normal(0, noise, img.shape)
    u8 = np.clip(np.round(img * 255), 0, 255).astype(np.uint8)
    _, enc = cv2.imencode(".jpg", u8, [cv2.IMWRITE_JPEG_QUALITY, jpeg])
    u8 = np.asarray(cv2.imdecode(enc, cv2.IMREAD_GRAYSCALE), dtype=np.uint8)
    # true corners: board (c + 1, r + 1) -> undistorted normalised -> distorted pixels
    r, c = np.mgrid[1 : rows + 1, 1 : cols + 1]
    P = (np.stack([c.ravel(), r.ravel(), np.zeros(c.size)], 1) - board_c) @ rot.T + t
    xu, yu = P[:, 0] / P[:, 2], P[:, 1] / P[:, 2]
    ru = np.hypot(xu, yu)
    rd = ru.copy()
    for _ in range(50):  # ru = rd (1 + k1 rd²), Newton
        rd -= (rd * (1 + k1 * rd * rd) - ru) / (1 + 3 * k1 * rd * rd)
    scale = np.where(ru > 0, rd / np.maximum(ru, 1e-300), 1.0)
    truth = np.stack([xu * scale * f + w / 2, yu * scale * f + h / 2], 1)
    return u8, truth


CONDITIONS = (
    ("sharp, no distortion", 0.6, 0.0, 0.01, 90),
    ("blur 1.2, distortion k1 0.15", 1.2, 0.15, 0.01, 85),
    ("blur 2.0, noise 0.02, JPEG 75", 2.0, 0.1, 0.02, 75),
    ("blur 0.8, distortion k1 0.3", 0.8, 0.3, 0.015, 85),
)


def rendered(cv2: Any, views: int, seed: int) -> list[list[object]]:
    """Rows of corner errors (px) on rendered views: median / 95th percentile per detector."""
    from imageform.geometry import find_checkerboard

    rng = np.random.default_rng(seed)
    out = []
    for label, blur, k1, noise, jpeg in CONDITIONS:
        errs: dict[str, list[np.ndarray]] = {w: [] for w in WHO}
        n_found = dict.fromkeys(WHO, 0)
        for _ in range(views):
            u8, truth = _render(rng, blur, k1, noise, jpeg)
            got: dict[str, np.ndarray | None] = {}
            for m in METHODS:
                det = find_checkerboard(u8, (9, 6), method=m)
                got[m] = np.asarray(det.corners) if det.found else None
            got.update(_opencv(cv2, u8, (9, 6)))
            for w, c in got.items():
                if c is None:
                    continue
                n_found[w] += 1
                d = np.sqrt(((c[:, None] - truth[None]) ** 2).sum(-1)).min(1)
                errs[w].append(d)
        row: list[object] = [label, views]
        for w in WHO:
            e = np.concatenate(errs[w]) if errs[w] else np.full(1, np.nan)
            row.append(f"{n_found[w]}: {np.median(e):.3f} / {np.percentile(e, 95):.3f}")
        out.append(row)
    return out


def main() -> None:
    """Run the real sets given and the rendered views; print (or write) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("sets", nargs="*", help="NAME=GLOB:COLSxROWS[:fisheye]")
    ap.add_argument("--views", type=int, default=12, help="rendered views per condition")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    rows = []
    for spec in args.sets:
        name, rest = spec.split("=", 1)
        parts = rest.split(":")
        fisheye = parts[-1] == "fisheye"
        if fisheye:
            parts = parts[:-1]
        cols, nrows = (int(v) for v in parts[-1].lower().split("x"))
        rows.append(real_set(cv2, name, ":".join(parts[:-1]), (cols, nrows), fisheye))
        print(rows[-1], file=sys.stderr, flush=True)
    synth = rendered(cv2, args.views, args.seed)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = header("Checkerboard corner refinement: point symmetry, gradients, OpenCV")
    text += (
        f"\nOpenCV {cv2.__version__}; load average {load:.1f} when run (CPU times are "
        "indicative). Made by `benchmarks/check_corner_refinement.py` (its docstring names the "
        "sets and the command).\n\n## Real photographs\n\n"
        "RMS / held-out RMS (px) of a calibration on each detector's corners: of every view "
        "imageform finds (both methods), then of the views all four detectors find; gradient "
        "and symmetric are imageform's find_checkerboard with that method (symmetric is the "
        "default).\n\n"
    )
    text += markdown_table(
        ("set", "board", "model", "views", "found: gradient / symmetric / SB / cornerSubPix",
         "every view imageform finds: gradient", "symmetric",
         "views all four find", "gradient", "symmetric", "SB", "cornerSubPix 5x5",
         "find_checkerboard CPU ms a view: gradient / symmetric"),
        rows,
    )  # fmt: skip
    text += (
        "\n## Rendered views (truth known)\n\nViews found: median / 95th percentile of the "
        "corner error (px).\n\n"
    )
    text += markdown_table(("condition", "views", *WHO), synth)
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
