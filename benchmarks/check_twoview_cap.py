"""Robust two-view estimators at low inlier ratios: the sample cap and the seed.

The adaptive count ``log(1 - p) / log(1 - ε^s)`` asks for about 2840 5-point samples at
``ε = 0.3`` and 4210 7-point samples at ``ε = 0.4`` (``p = 0.999``), above the default
``max_trials = 2000``. Two tables, each from seeded synthetic scenes (errors deterministic):

(1) ``find_essential_matrix`` + ``recover_pose`` on benchmarks/bench_twoview.py's scenes
(seeds 3000 + i, 200 points, 30 % inliers, σ = τ = 1 px) with ``max_trials`` 2000, 5000
and 10000: rotation error median / mean, scenes off by more than 2 degrees, the samples
drawn and how many calls stopped at the cap, the median time.
(2) ``find_fundamental_matrix`` on tests/geometry/test_twoview.py's wide-baseline pairs
(``_wide_scene``: 40 % inliers, 1 px, a 25-35 degree orbit; scenes 0-5) over the seeds
0-9, with ``max_trials`` 2000 and 10000, against OpenCV 5's USAC (MAGSAC++ score,
σ-consensus, MAGSAC polisher, 10000 iterations at most) seeded by ``randomGeneratorState``:
the rotation of ``recover_pose(Kᵀ F K)``, its median, worst and spread over the seeds.
Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_twoview_cap.py [--scenes 50]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "geometry"))

from benchmarks._common import header, markdown_table


def essential_table(scenes: int) -> str:
    from benchmarks.bench_twoview import K, _angle_deg, scene
    from imageform.geometry import find_essential_matrix, recover_pose

    rows = []
    for cap in (2000, 5000, 10000):
        errs, drawn, ms = [], [], []
        for s in range(scenes):
            sc = scene(3000 + s, 200, 0.7, 1.0, planar=False)
            t0 = time.perf_counter()
            r = find_essential_matrix(sc["n1"], sc["n2"], K, threshold=1.0, rng=s, max_trials=cap)
            ms.append((time.perf_counter() - t0) * 1e3)
            pose = recover_pose(r.E, sc["n1"], sc["n2"], K, inliers=r.inliers)
            errs.append(_angle_deg(pose.R, sc["R"]))
            drawn.append(r.trials)
        e = np.array(errs)
        rows.append(
            [cap, f"{np.median(e):.3f} / {e.mean():.3f}", int((e > 2).sum()),
             f"{statistics.median(drawn):.0f}", sum(d >= cap for d in drawn),
             f"{statistics.median(ms):.1f}"]
        )  # fmt: skip
    cols = ["max_trials", "rotation error median / mean deg", "scenes > 2 deg",
            "samples (median)", "calls at the cap", "ms (median)"]  # fmt: skip
    return f"## Essential matrix, {scenes} scenes, 30 % inliers, σ = τ = 1 px\n\n" + markdown_table(
        cols, rows
    )


def fundamental_table() -> str:
    import cv2
    import test_twoview as tt

    from benchmarks.check_twoview_real import _usac_params
    from imageform.geometry import find_fundamental_matrix, recover_pose

    K = tt.K
    rows = []
    for sc in range(6):
        R, _t, n1, n2, _out = tt._wide_scene(sc)
        runs: dict[str, Any] = {
            "imageform, max_trials 2000": lambda s, n1=n1, n2=n2: find_fundamental_matrix(
                n1, n2, threshold=1.0, rng=s
            ),
            "imageform, max_trials 10000": lambda s, n1=n1, n2=n2: find_fundamental_matrix(
                n1, n2, threshold=1.0, rng=s, max_trials=10000
            ),
            "OpenCV USAC (MAGSAC++), seeded": lambda s, n1=n1, n2=n2: cv2.findFundamentalMat(
                n1, n2, _usac_params(1.0, s)
            ),
        }
        for name, fn in runs.items():
            errs = []
            for s in range(10):
                out: Any = fn(s)
                if name.startswith("imageform"):
                    E = K.T @ np.asarray(out.F, np.float64) @ K
                    Re = recover_pose(E, n1, n2, K, inliers=out.inliers).R
                else:
                    Fc, mc = out
                    _, Re, _, _ = cv2.recoverPose(K.T @ Fc[:3] @ K, n1, n2, K, mask=mc.copy())
                errs.append(tt.angle_deg(Re, R))
            e = np.array(errs)
            rows.append([sc, name, f"{np.median(e):.2f} / {e.max():.2f}", f"{np.ptp(e):.2f}"])
    cols = ["scene", "method", "rotation error median / worst deg", "spread deg"]
    return (
        "## Fundamental matrix over 10 seeds, wide-baseline pairs, 40 % inliers, 1 px\n\n"
        + markdown_table(cols, rows)
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=50)
    args = ap.parse_args()
    print(header("Robust two-view estimators at low inlier ratios"))
    print(f"load average: {' / '.join(Path('/proc/loadavg').read_text().split()[:3])}\n")
    print(essential_table(args.scenes))
    print(fundamental_table())


if __name__ == "__main__":
    main()
