"""Checkerboard detection: imageform vs OpenCV on OpenCV's 13 ``left*.jpg`` views.

Times, in the same run and interleaved, the detection of the 9 x 6 board in all 13 views:

- imageform ``find_checkerboard(img, (9, 6), half_window=11, method="gradient")``
  (detection + sub-pixel);
- OpenCV ``findChessboardCorners(img, (9, 6))`` (default flags, as in the calibration
  tutorial) + ``cornerSubPix(winSize (11, 11), zeroZone (-1, -1), EPS + COUNT 30, 0.001)``,
  with OpenCV's default thread count and with ``cv2.setNumThreads(1)``.

Reports the median over repetitions of the total time for the 13 views, the ratio, and the
median corner distance between the two. Images are read once (not timed), as uint8.

Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_checkerboard.py [--repeat 9] [--out FILE]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import cv2  # noqa: E402  (oracle only)

from imageform.geometry.checkerboard import find_checkerboard  # noqa: E402

DATA = Path(os.environ.get("IMAGEFORM_DATA", ROOT.parent / "shared" / "data")) / "opencv-left"
VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]
PATTERN = (9, 6)
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)


def run_imageform(images: list[np.ndarray]) -> list[np.ndarray | None]:
    out = []
    for img in images:
        r = find_checkerboard(img, PATTERN, half_window=11, method="gradient")
        out.append(r.corners)
    return out


def run_opencv(images: list[np.ndarray]) -> list[np.ndarray | None]:
    out = []
    for img in images:
        ok, c = cv2.findChessboardCorners(img, PATTERN, None)
        if ok:
            c = cv2.cornerSubPix(img, c, (11, 11), (-1, -1), CRITERIA)
            out.append(c.reshape(-1, 2).astype(np.float64))
        else:
            out.append(None)
    return out


def timed(fn, images):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    res = fn(images)
    return time.perf_counter() - t0, res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--out", type=Path, default=None, help="write a markdown table here")
    args = ap.parse_args()

    images = [cv2.imread(str(DATA / v), cv2.IMREAD_GRAYSCALE) for v in VIEWS]
    assert all(im is not None for im in images), f"views missing under {DATA}"
    # warm-up: numba compilation / caches, OpenCV's first-call setup
    run_imageform(images)
    run_opencv(images)

    threads = cv2.getNumThreads()
    t_if, t_cv, t_cv1 = [], [], []
    for _ in range(args.repeat):
        dt, ours = timed(run_imageform, images)
        t_if.append(dt)
        dt, theirs = timed(run_opencv, images)
        t_cv.append(dt)
        cv2.setNumThreads(1)  # like for like: imageform runs on one thread
        dt, _ = timed(run_opencv, images)
        t_cv1.append(dt)
        cv2.setNumThreads(threads)
    found_if = sum(c is not None for c in ours)
    found_cv = sum(c is not None for c in theirs)
    dists = [
        np.linalg.norm(a - b, axis=1)
        for a, b in zip(ours, theirs, strict=True)
        if a is not None and b is not None
    ]
    med_d = float(np.median(np.concatenate(dists)))
    max_d = float(max(d.max() for d in dists))
    m_if, m_cv = float(np.median(t_if)), float(np.median(t_cv))
    m_cv1 = float(np.median(t_cv1))
    ratio = m_if / m_cv

    lines = [
        "# Checkerboard detection: imageform vs OpenCV",
        "",
        f"OpenCV's 13 `left*.jpg` views (640 x 480, 9 x 6 inner corners); median of "
        f"{args.repeat} interleaved repetitions of the whole set, same run.",
        "",
        "| method | found | total, 13 views (ms) | per view (ms) | time / OpenCV |",
        "|---|---|---|---|---|",
        f"| imageform `find_checkerboard` (half_window=11) | {found_if}/13 | {m_if * 1e3:.1f} "
        f"| {m_if / 13 * 1e3:.2f} | {ratio:.2f} |",
        f"| OpenCV {cv2.__version__} `findChessboardCorners` + `cornerSubPix` | {found_cv}/13 "
        f"| {m_cv * 1e3:.1f} | {m_cv / 13 * 1e3:.2f} | 1.00 |",
        f"| same, `cv2.setNumThreads(1)` | {found_cv}/13 | {m_cv1 * 1e3:.1f} "
        f"| {m_cv1 / 13 * 1e3:.2f} | {m_cv1 / m_cv:.2f} |",
        "",
        f"imageform / OpenCV: **{ratio:.2f}** (OpenCV default threads, {threads}); "
        f"{m_if / m_cv1:.2f} against single-threaded OpenCV (imageform is single-threaded).",
        "",
        f"Corner agreement (all 702 corners): median {med_d:.2e} px, max {max_d:.2e} px.",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, load average "
        f"{os.getloadavg()[0]:.1f} at the end (shared machine), Python "
        f"{platform.python_version()}, numpy {np.__version__}, OpenCV threads "
        f"{threads}, OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}.",
        "",
        "Command: `OPENBLAS_NUM_THREADS=1 python benchmarks/bench_checkerboard.py "
        f"--repeat {args.repeat} --out <this file>`",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
