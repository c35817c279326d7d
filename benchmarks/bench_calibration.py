"""Calibration and PnP: imageform vs OpenCV, timed in the same run, interleaved.

1. Detection + calibration of OpenCV's 13 ``left*.jpg`` views (9 x 6, square 1):
   imageform ``find_checkerboard(half_window=11, method="gradient")`` + ``calibrate_camera``
   vs OpenCV
   ``findChessboardCorners`` + ``cornerSubPix((11, 11))`` + ``calibrateCamera`` (default
   flags, as the tutorial). Also the calibration alone on the same (imageform) corners, and
   on synthetic views (a 640 x 480 camera, Brown-Conrady distortion, 0.2 px noise): 40 views
   of an 11 x 8 board, and 30 partial views of it (ChArUco-like: each view a random part of
   the board, 20-60 of its 88 corners). The calibrations are timed in interleaved rounds
   (``paired_rounds``: median of 5 calls each per round; the ratio is the rounds' median).
2. PnP, 1000 problems of 50 points (non-planar, 0.5 px noise): imageform ``solve_pnp``
   (batched linear + LM refinement, numba kernel) vs ``cv2.solvePnP(SOLVEPNP_EPNP)`` called
   in a Python loop (EPnP without refinement), and vs ``SOLVEPNP_ITERATIVE``.

Medians over repetitions; ratios in the same run. Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_calibration.py [--repeat 7] [--out FILE]
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402  (oracle only)
from PIL import Image  # noqa: E402

from benchmarks._common import header, markdown_table, median_time, paired_rounds  # noqa: E402
from imageform.geometry import calibrate_camera, checkerboard_points, solve_pnp  # noqa: E402
from imageform.geometry.calibration_refine import rodrigues  # noqa: E402
from imageform.geometry.checkerboard import find_checkerboard  # noqa: E402

DATA = Path(os.environ.get("IMAGEFORM_DATA", ROOT.parent / "shared" / "data")) / "opencv-left"
PATTERN = (9, 6)
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)


def ours_detect(images: list[np.ndarray]) -> list[np.ndarray]:
    found = [find_checkerboard(im, PATTERN, half_window=11, method="gradient") for im in images]
    return [r.corners for r in found]  # type: ignore[misc]


def ours_calibrate(corners: list[np.ndarray]) -> object:
    obj = checkerboard_points(PATTERN)
    return calibrate_camera([obj] * len(corners), corners, (640, 480))


def cv_detect(images: list[np.ndarray]) -> list[np.ndarray]:
    out = []
    for im in images:
        _ok, c = cv2.findChessboardCorners(im, PATTERN, None)
        out.append(cv2.cornerSubPix(im, c, (11, 11), (-1, -1), CRITERIA))
    return out


def cv_calibrate(corners: list[np.ndarray]) -> tuple:
    obj = checkerboard_points(PATTERN).astype(np.float32)
    pts = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in corners]
    return cv2.calibrateCamera([obj] * len(pts), pts, (640, 480), None, None)


def synthetic_views(
    n_views: int, partial: bool, seed: int = 0
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Views of an 11 x 8 board (square 20) by a 640 x 480 camera with distortion, 0.2 px noise.

    ``partial``: each view keeps a random rectangle of the board's corners (20-60 of 88),
    as a ChArUco board partly seen or partly occluded.
    """
    from imageform.geometry import BrownConrady, project_points_distorted

    rng = np.random.default_rng(seed)
    board = checkerboard_points((11, 8), 20.0)
    K = np.array([[560.0, 0, 318], [0, 555, 242], [0, 0, 1]])
    lens = BrownConrady(k1=-0.28, k2=0.09, p1=1e-3, p2=-5e-4)
    objs: list[np.ndarray] = []
    imgs: list[np.ndarray] = []
    while len(objs) < n_views:
        rv = rng.normal(0, 0.35, 3)
        t = np.array([-100.0, -70.0, 0.0]) + np.r_[rng.normal(0, 30, 2), rng.uniform(330, 520)]
        R = rodrigues(rv[None])[0]
        uv = np.asarray(project_points_distorted(board, K, R, t, lens)[0])
        keep = np.ones(len(board), bool)
        if partial:
            c, r = board[:, 0] / 20.0, board[:, 1] / 20.0
            w, h = rng.integers(4, 12), rng.integers(4, 9)
            c0, r0 = rng.integers(0, 12 - w), rng.integers(0, 9 - h)
            keep = (c >= c0) & (c < c0 + w) & (r >= r0) & (r < r0 + h)
            if not 20 <= keep.sum() <= 60:
                continue
        inside = (uv[:, 0] > 0) & (uv[:, 0] < 639) & (uv[:, 1] > 0) & (uv[:, 1] < 479)
        if not np.all(inside[keep]):
            continue
        objs.append(board[keep])
        imgs.append(uv[keep] + rng.normal(0, 0.2, (int(keep.sum()), 2)))
    return objs, imgs


def pnp_problems(B: int = 1000, N: int = 50) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    X = rng.uniform(-1, 1, (B, N, 3))
    R = rodrigues(rng.normal(0, 0.5, (B, 3)))
    t = np.c_[rng.uniform(-0.5, 0.5, (B, 2)), rng.uniform(4, 8, B)]
    cam = X @ np.swapaxes(R, 1, 2) + t[:, None]
    uv = cam[..., :2] / cam[..., 2:] * 800 + [320, 240]
    return X, uv + rng.normal(0, 0.5, uv.shape), K


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    files = sorted(DATA.glob("left*.jpg"))
    images = [np.asarray(Image.open(f).convert("L")) for f in files]
    r = args.repeat

    t_od = median_time(lambda: ours_detect(images), r)
    t_cd = median_time(lambda: cv_detect(images), r)
    corners = ours_detect(images)
    t_oc, t_cc, q_c, _, _ = paired_rounds(
        lambda: ours_calibrate(corners), lambda: cv_calibrate(corners), r
    )
    res = ours_calibrate(corners)
    synth = []
    for label, n_views, partial in (
        ("40 views 11 x 8, synthetic", 40, False),
        ("30 partial views (ChArUco-like), synthetic", 30, True),
    ):
        objs, imgs = synthetic_views(n_views, partial)
        o32 = [o.astype(np.float32) for o in objs]
        i32 = [i.astype(np.float32).reshape(-1, 1, 2) for i in imgs]
        ta, tb, q, _, _ = paired_rounds(
            functools.partial(calibrate_camera, objs, imgs, (640, 480)),
            functools.partial(cv2.calibrateCamera, o32, i32, (640, 480), None, None),
            r,
        )
        mine = calibrate_camera(objs, imgs, (640, 480))
        rms_c, K_c, *_ = cv2.calibrateCamera(o32, i32, (640, 480), None, None)
        dK = float(np.max(np.abs(mine.K - K_c)))
        synth.append((label, ta, tb, q, mine.rms, rms_c, dK))
    rms_cv, K_cv, *_ = cv_calibrate(cv_detect(images))

    X, uv, K = pnp_problems()
    X32 = [np.ascontiguousarray(x) for x in X]
    uv32 = [np.ascontiguousarray(u) for u in uv]

    def cv_loop(flag: int) -> None:
        for x, u in zip(X32, uv32, strict=True):
            cv2.solvePnP(x, u, K, None, flags=flag)

    t_op = median_time(lambda: solve_pnp(X, uv, K), r)
    t_cp = median_time(lambda: cv_loop(cv2.SOLVEPNP_EPNP), r)
    t_ci = median_time(lambda: cv_loop(cv2.SOLVEPNP_ITERATIVE), r)

    ms = lambda s: f"{1000 * s:.1f}"  # noqa: E731
    rows = [
        ["detect 13 views", ms(t_od), ms(t_cd), f"{t_od / t_cd:.2f}"],
        ["calibrate (13 views, same corners)", ms(t_oc), ms(t_cc), f"{q_c:.2f}"],
        *[[f"calibrate {lb}", ms(ta), ms(tb), f"{q:.2f}"] for lb, ta, tb, q, *_ in synth],
        [
            "**detect + calibrate**",
            ms(t_od + t_oc),
            ms(t_cd + t_cc),
            f"**{(t_od + t_oc) / (t_cd + t_cc):.2f}**",
        ],
        ["**PnP 1000 x 50** vs solvePnP EPnP loop", ms(t_op), ms(t_cp), f"**{t_op / t_cp:.2f}**"],
        ["PnP 1000 x 50 vs solvePnP ITERATIVE loop", ms(t_op), ms(t_ci), f"{t_op / t_ci:.2f}"],
    ]
    K = res.K  # type: ignore[attr-defined]
    text = header("Calibration and PnP benchmark: imageform vs OpenCV")
    text += (
        f"\nmedian of {r} runs (after 1 warm-up), times in ms; the calibrations in {r} "
        "interleaved rounds of 5 calls each (times: the rounds' medians; ratio: the median of "
        "the rounds' ratios)\n\n"
    )
    text += markdown_table(["task", "imageform", "OpenCV", "ratio"], rows)
    text += (
        f"\nimageform on its own corners: fx {K[0, 0]:.4f}, fy {K[1, 1]:.4f}, cx {K[0, 2]:.4f}, "
        f"cy {K[1, 2]:.4f}, RMS {res.rms:.4f} px"  # type: ignore[attr-defined]
        f"\nOpenCV on its own corners: fx {K_cv[0, 0]:.4f}, fy {K_cv[1, 1]:.4f}, "
        f"cx {K_cv[0, 2]:.4f}, cy {K_cv[1, 2]:.4f}, RMS {rms_cv:.4f} px\n"
    )
    for lb, *_, rms_o, rms_c, dK in synth:
        text += (
            f"\n{lb}: RMS imageform {rms_o:.4f} px, OpenCV {rms_c:.4f} px; "
            f"K differs by at most {dK:.2g} px\n"
        )
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
