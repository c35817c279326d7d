"""CPU time of the robust two-view estimators on benchmarks/bench_twoview.py's scenes.

On a machine shared with other jobs the wall times of bench_twoview.py move by several
times between runs; the process's CPU time of one call is steadier. For each of the 30
scenes (H: seeds 1000 + i, planar; F and E: 2000 + i) one untimed call, then the least of
five calls' ``time.process_time``; the median over scenes, in ms. Run once per source tree
(before / after, interleaved)::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/time_twoview_cpu.py [--outliers 0.3] [--sigma 1.0]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.bench_twoview import K, scene


def main() -> None:
    from imageform.geometry import find_essential_matrix, find_fundamental_matrix, find_homography

    ap = argparse.ArgumentParser()
    ap.add_argument("--outliers", type=float, default=0.3)
    ap.add_argument("--sigma", type=float, default=1.0)
    ap.add_argument("--scenes", type=int, default=30)
    args = ap.parse_args()
    out = []
    for task in ("H", "F", "E"):
        per = []
        for s in range(args.scenes):
            sc = scene(
                (1000 if task == "H" else 2000) + s, 200, args.outliers, args.sigma, task == "H"
            )
            n1, n2 = sc["n1"], sc["n2"]
            calls: dict[str, Any] = {
                "E": lambda n1=n1, n2=n2, s=s: find_essential_matrix(
                    n1, n2, K, threshold=1.0, rng=s
                ),
                "F": lambda n1=n1, n2=n2, s=s: find_fundamental_matrix(
                    n1, n2, threshold=1.0, rng=s
                ),
                "H": lambda n1=n1, n2=n2, s=s: find_homography(n1, n2, threshold=3.0, rng=s),
            }
            fn = calls[task]
            fn()
            times = []
            for _ in range(5):
                t0 = time.process_time()
                fn()
                times.append(time.process_time() - t0)
            per.append(min(times))
        out.append(f"{task} {statistics.median(per) * 1e3:.3f} ms")
    print(f"outliers {args.outliers}, sigma {args.sigma}: " + ", ".join(out))


if __name__ == "__main__":
    main()
