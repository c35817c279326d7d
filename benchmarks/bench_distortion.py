"""Benchmark: projection with Brown-Conrady distortion, point undistortion, image undistortion.

imageform against OpenCV with the same coefficients, in the same run:

- ``project_points_distorted`` (fused numba kernel) vs ``cv2.projectPoints`` on 10^7 points,
  5 and 8 (rational) coefficients; the target is >= 5x faster, agreeing to 1e-9 px;
- ``BrownConrady.undistort`` (Newton, numba) vs ``cv2.undistortPoints`` (fixed point, 5 iter
  by default, and with a criteria of 100 iterations / 1e-15);
- ``undistort_image`` vs ``cv2.undistort`` on a 640×480 chessboard view.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_distortion.py [--n 10000000]

Prints a Markdown table and writes it to ``benchmarks/results/distortion-<date>.md``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import sys
from pathlib import Path

import cv2
import numba
import numpy as np

from imageform.geometry.distortion import BrownConrady, project_points_distorted
from imageform.geometry.undistort import undistort_image

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import median_time  # noqa: E402

# OpenCV tutorial calibration of the left*.jpg views (shared/data/README.md)
K = np.array([[536.07345314, 0, 342.37046827], [0, 536.01636274, 235.53687064], [0, 0, 1.0]])
D5 = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
D8 = np.array([0.1, -0.05, 0.001, -0.0005, 0.01, 0.2, -0.02, 0.005])


def bench_projection(n: int, reps: int, rows: list[list[str]]) -> None:
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(2.0, 6.0, n)]
    rvec = np.array([0.05, -0.1, 0.02])
    R = cv2.Rodrigues(rvec)[0]
    t = np.array([0.1, -0.05, 0.3])
    for dist in (D5, D8):
        model = BrownConrady.from_opencv(dist)
        ref = cv2.projectPoints(pts, rvec, t, K, dist)[0].reshape(-1, 2)
        uv, ok = project_points_distorted(pts, K, R, t, model)
        err = float(np.max(np.abs(uv - ref)))
        assert ok.all()
        t_cv = median_time(lambda d=dist: cv2.projectPoints(pts, rvec, t, K, d), reps)
        threads = numba.get_num_threads()
        results = {}
        for nt in sorted({1, threads}):
            numba.set_num_threads(nt)
            results[nt] = median_time(
                lambda m=model: project_points_distorted(pts, K, R, t, m), reps
            )
        numba.set_num_threads(threads)
        for nt, t_if in results.items():
            rows.append(
                [
                    f"project {n:.0e} pts, {dist.size} coeffs",
                    f"imageform (numba, {nt} thread{'s' if nt > 1 else ''})",
                    f"{t_if * 1e3:.1f}",
                    f"{t_cv * 1e3:.1f}",
                    f"{t_cv / t_if:.1f}x",
                    f"{err:.1e} px",
                ]
            )


def bench_undistort_points(n: int, reps: int, rows: list[list[str]]) -> None:
    rng = np.random.default_rng(1)
    model = BrownConrady.from_opencv(D5)
    xy = rng.uniform(-0.5, 0.5, (n, 2))
    xd = model.distort(xy)
    px = np.ascontiguousarray((xd * [K[0, 0], K[1, 1]] + K[:2, 2])[:, None])
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-15)
    ours, ok = model.undistort(xd)
    assert ok.all()
    e_ours = float(np.max(np.abs(ours - xy)))
    ref5 = cv2.undistortPoints(px, K, D5).reshape(-1, 2)
    ref100 = cv2.undistortPoints(px, K, D5, R=None, P=None, criteria=crit).reshape(-1, 2)
    t_ours = median_time(lambda: model.undistort(xd), reps)
    t5 = median_time(lambda: cv2.undistortPoints(px, K, D5), reps)
    t100 = median_time(lambda: cv2.undistortPoints(px, K, D5, R=None, P=None, criteria=crit), reps)
    name = f"undistort {n:.0e} pts"
    e5 = float(np.max(np.abs(ref5 - xy)))
    e100 = float(np.max(np.abs(ref100 - xy)))
    rows.append(
        [
            name,
            "imageform Newton vs cv2 default (5 iter)",
            f"{t_ours * 1e3:.1f}",
            f"{t5 * 1e3:.1f}",
            f"{t5 / t_ours:.1f}x",
            f"ours {e_ours:.0e}, cv2 {e5:.0e} (normalised)",
        ]
    )
    rows.append(
        [
            name,
            "imageform Newton vs cv2 (100 iter, 1e-15)",
            f"{t_ours * 1e3:.1f}",
            f"{t100 * 1e3:.1f}",
            f"{t100 / t_ours:.1f}x",
            f"cv2 {e100:.0e} (normalised)",
        ]
    )


def bench_undistort_image(reps: int, rows: list[list[str]]) -> None:
    path = ROOT.parent / "shared" / "data" / "opencv-left" / "left01.jpg"
    if path.is_file():
        img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE).astype(np.float32) / 255
    else:  # a synthetic view of the same size
        img = np.random.default_rng(2).random((480, 640)).astype(np.float32)
    model = BrownConrady.from_opencv(D5)
    ours = undistort_image(img, K, model)
    ref = cv2.undistort(img, K, D5)
    err = float(np.abs(ours - ref)[5:-5, 5:-5].mean())
    t_ours = median_time(lambda: undistort_image(img, K, model), reps)
    t_cv = median_time(lambda: cv2.undistort(img, K, D5), reps)
    rows.append(
        [
            "undistort image 640x480 float32",
            "imageform (fused numba map + bilinear)",
            f"{t_ours * 1e3:.1f}",
            f"{t_cv * 1e3:.1f}",
            f"{t_cv / t_ours:.2f}x",
            f"mean |diff| {err:.1e}",
        ]
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000_000, help="points to project")
    ap.add_argument("--reps", type=int, default=3, help="timed repetitions (median reported)")
    ap.add_argument("--out", type=Path, default=None, help="Markdown file to write")
    args = ap.parse_args()
    rows: list[list[str]] = []
    bench_projection(args.n, args.reps, rows)
    bench_undistort_points(1_000_000, args.reps, rows)
    bench_undistort_image(max(args.reps, 5), rows)
    header = ["case", "imageform", "imageform ms", "OpenCV ms", "speed-up", "agreement"]
    lines = [
        f"# Distortion benchmark ({_dt.date.today().isoformat()})",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared), Python "
        f"{platform.python_version()}, NumPy {np.__version__}, numba {numba.__version__}, "
        f"OpenCV {cv2.__version__}; OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}.",
        f"Median of {args.reps} repetitions after one warm-up; OpenCV measured in the same run.",
        "",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *("| " + " | ".join(r) + " |" for r in rows),
        "",
        "Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_distortion.py`",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    out = args.out or ROOT / "benchmarks" / "results" / f"distortion-{_dt.date.today()}.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
