"""Checkerboard corner refinement on large views: this tree vs a ``--before`` tree vs OpenCV.

Times ``find_checkerboard(img, (9, 6))`` (default ``refine=True, method="symmetric"``) on
OpenCV's 13 ``left*.jpg`` views (``/work/shared/data/opencv-left``, 640 x 480) and on the same
views upscaled to 1920 x 1440 (``cv2.resize``, bilinear), per view, with numba's pool at 1 and
2 threads (``NUMBA_NUM_THREADS``), for this tree's ``src`` and for ``--before``'s (another
checkout's ``src``, e.g. main's); the time inside the two symmetric refinements
(``refine_symmetric_numba``, ``refine_local_numba``) is reported apart. OpenCV:
``findChessboardCorners(img, (9, 6))`` (default flags) + ``cornerSubPix`` (11 x 11 window,
EPS + COUNT 30, 0.001) with ``cv2.setNumThreads(1)`` and ``(2)``.

Each configuration runs in its own process (the two trees cannot share one); the processes
are interleaved over ``--rounds`` rounds; each reports the median of ``--repeat`` timed passes
over the views (after one untimed pass: compilation or cache loading), and the table gives the
median over rounds, in ms per view. The corners of every configuration are compared with this
tree's on one thread: the largest difference (px), 0 where both refine the same way (the
kernels are the same on any number of threads).

Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_checkerboard_refine.py \\
        --before /work/main/src [--rounds 5] [--repeat 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "opencv-left"
if not DATA.is_dir():
    DATA = Path("/work/shared/data/opencv-left")
PATTERN = (9, 6)
SIZES = {"640x480": None, "1920x1440": (1920, 1440)}


def load(size: str) -> list[np.ndarray]:
    import cv2

    out = []
    for p in sorted(DATA.glob("left*.jpg")):
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        if SIZES[size] is not None:
            img = cv2.resize(img, SIZES[size], interpolation=cv2.INTER_LINEAR)
        out.append(img)
    return out


def worker(kind: str, size: str, repeat: int, npz: str) -> None:
    """One configuration: print its times (JSON) and save its corners to ``npz``."""
    images = load(size)
    spent = [0.0]
    if kind == "opencv":
        import cv2

        cv2.setNumThreads(int(os.environ.get("NUMBA_NUM_THREADS", "1")))
        crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)

        def one(img: np.ndarray) -> np.ndarray:
            ok, c = cv2.findChessboardCorners(img, PATTERN, None)
            if not ok:
                return np.full((PATTERN[0] * PATTERN[1], 2), np.nan)
            c = cv2.cornerSubPix(img, c, (11, 11), (-1, -1), crit)
            return np.asarray(c.reshape(-1, 2), dtype=np.float64)
    else:
        import imageform._kernels.checkerboard_local as loc
        import imageform._kernels.checkerboard_symmetric as sym
        from imageform.geometry import find_checkerboard

        def timing(fn):  # type: ignore[no-untyped-def]
            def wrapped(*a, **k):  # type: ignore[no-untyped-def]
                t0 = time.perf_counter()
                try:
                    return fn(*a, **k)
                finally:
                    spent[0] += time.perf_counter() - t0

            return wrapped

        sym.refine_symmetric_numba = timing(sym.refine_symmetric_numba)
        loc.refine_local_numba = timing(loc.refine_local_numba)

        def one(img: np.ndarray) -> np.ndarray:
            r = find_checkerboard(img, PATTERN)
            if r.corners is None:
                return np.full((PATTERN[0] * PATTERN[1], 2), np.nan)
            return np.asarray(r.corners, dtype=np.float64)

    corners = [one(img) for img in images]  # untimed: compilation / cache loading
    totals, refine = [], []
    for _ in range(repeat):
        spent[0] = 0.0
        t0 = time.perf_counter()
        for img in images:
            one(img)
        totals.append(time.perf_counter() - t0)
        refine.append(spent[0])
    np.savez(npz, *corners)
    n = len(images)
    print(
        json.dumps(
            {"total": 1e3 * float(np.median(totals)) / n, "refine": 1e3 * np.median(refine) / n}
        )
    )


def run(kind: str, src: str, size: str, threads: int, repeat: int, npz: str) -> dict[str, float]:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", NUMBA_NUM_THREADS=str(threads))
    env["PYTHONPATH"] = src
    cmd = [sys.executable, __file__, "--worker", kind, "--size", size, "--repeat", str(repeat)]
    out = subprocess.run(cmd + ["--npz", npz], env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-2000:])
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="", help="another tree's src (e.g. main's)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--worker", default="")
    ap.add_argument("--size", default="1920x1440")
    ap.add_argument("--npz", default="")
    args = ap.parse_args()
    if args.worker:
        worker(args.worker, args.size, args.repeat, args.npz)
        return
    import cv2
    import numba

    trees = {"after": str(ROOT / "src")}
    if args.before:
        trees["before"] = args.before
    configs = [(k, t, "imageform") for k in trees for t in (1, 2)]
    configs += [("opencv", t, "opencv") for t in (1, 2)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in SIZES:
            times: dict[tuple[str, int], list[dict[str, float]]] = {c[:2]: [] for c in configs}
            for _ in range(args.rounds):
                for name, t, kind in configs:
                    npz = f"{tmp}/{size}-{name}-{t}.npz"
                    src = trees.get(name, trees["after"])
                    times[(name, t)].append(run(kind, src, size, t, args.repeat, npz))
            ref = np.load(f"{tmp}/{size}-after-1.npz")
            for name, t, _kind in configs:
                got = np.load(f"{tmp}/{size}-{name}-{t}.npz")
                diffs = [np.abs(got[f] - ref[f]) for f in ref.files]
                both = [d[np.isfinite(d)] for d in diffs]
                dmax = max((float(d.max()) for d in both if d.size), default=float("nan"))
                total = float(np.median([r["total"] for r in times[(name, t)]]))
                refine = float(np.median([r["refine"] for r in times[(name, t)]]))
                rows.append((size, name, t, total, refine, dmax))
    opencv = {(s, t): tot for s, n, t, tot, _r, _d in rows if n == "opencv"}
    print(
        f"Python {platform.python_version()}, numba {numba.__version__}, OpenCV {cv2.__version__}"
    )
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"{platform.machine()}, {os.cpu_count()} CPUs (load average {load:.1f} at the end);")
    print("OPENBLAS_NUM_THREADS=1; ms per view,")
    print(f"median of {args.rounds} rounds (processes) of the median of {args.repeat} passes.\n")
    print(
        "| views | code | threads | ms / view | in the two refinements "
        "| OpenCV's time / this (same threads) | max corner diff vs after, 1 thread (px) |"
    )
    print("|---|---|---|---|---|---|---|")
    for size, name, t, total, refine, dmax in rows:
        ref_txt = "" if name == "opencv" else f"{refine:.1f}"
        ratio = opencv[(size, t)] / total
        diff = f"{dmax:.3g}" if name != "opencv" else "-"
        print(f"| {size} | {name} | {t} | {total:.1f} | {ref_txt} | {ratio:.2f} | {diff} |")


if __name__ == "__main__":
    main()
