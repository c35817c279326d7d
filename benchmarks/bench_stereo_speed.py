"""Stereo matching's CPU time per pair: imageform (two source trees) against OpenCV's StereoSGBM.

``imageform.geometry.stereo_disparity`` at its defaults (graded census, 3 x 3 cost sums, plane
fill) from the tree ``--before`` and from ``--after``, each in its own process (its numba
kernels compiled before timing), against ``cv2.StereoSGBM_create`` ``MODE_HH`` at matched
settings (block 5, ``P1 = 8·25``, ``P2 = 32·25``, uniqueness 10 %, ``disp12MaxDiff`` 1) and
``cv2.StereoBM_create`` (block 15) in the same process: CPU ms (``time.process_time``) a call,
one thread each (``NUMBA_NUM_THREADS=1``, ``cv2.setNumThreads(1)``), and of the matching
kernels alone (census, cost sums, the 8 paths fused with the selection: ``match``) of the
same call. The processes alternate, before and after, for ``--rounds`` rounds (the order
flipped every round); each process times each pair ``--per`` times (the median), OpenCV after
each call. Ratios: medians over the rounds of the per-round ratios. Each process also writes
its maps; the table says whether before and after are the same bit for bit (NaN equal).

Pairs (not in the repository; Middlebury's: "We grant permission to use and publish all
images and disparity maps"): cones and teddy of the 2003 set (450 x 375) as kept by
github.com/r09921135/acv ``hw4/testdata/``, Adirondack of the 2014 set at quarter size
(720 x 497) and bowling (400 x 354) as kept by github.com/2b-t/stereo-matching ``data/``::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_stereo_speed.py --before /tmp/main/src \\
        --after src --acv /tmp/data/acv --middlebury /tmp/data/mb --rounds 6 --per 5
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks._common

from benchmarks._common import (
    alternate_trees,
    cpu_medians,
    matched_sgbm,
    median_ratio,
    read_pair,
    stereo_pairs,
    stereo_parser,
)


def _pairs(acv: Path, mb: Path) -> list[tuple[str, Path, Path, int]]:
    return [
        *stereo_pairs(acv, mb),
        ("bowling", mb / "bowling_left.png", mb / "bowling_right.png", 64),
    ]


def _kernels(gl: np.ndarray, gr: np.ndarray, n: int) -> None:
    """The defaults' matching kernels: census, 3 x 3 cost sums, ``match``."""
    from imageform._kernels import sgm
    from imageform.geometry import stereo_matching as sm

    z, st = np.float32(0.0), np.float32(sm.CENSUS_STEP)
    cl, cr = sgm.census(gl, 2, z, st), sgm.census(gr, 2, z, st)
    h, w = gl.shape
    vol = np.empty((h, w, n), np.uint8)
    cost = sgm.window_costs(cl, cr, 0, n, 48, 1, 3, vol)
    total = np.empty((h, w, n), np.uint16)
    none = np.zeros((0, 1, 1), np.int32)
    sgm.match(cost, gl, 48, 192, False, 0, 0.1, 1.0, total, True, none)


def _worker(args: argparse.Namespace) -> None:
    import cv2

    from imageform.geometry import stereo_disparity
    from imageform.geometry import stereo_matching as sm

    cv2.setNumThreads(1)
    res = {}
    maps = {}
    for name, lp, rp, n in _pairs(args.acv, args.middlebury):
        L, R = read_pair(lp, rp)
        sgbm = matched_sgbm(n)
        bm = cv2.StereoBM_create(numDisparities=n, blockSize=15)  # type: ignore[attr-defined]
        maps[name] = stereo_disparity(L, R, num_disparities=n)
        sgbm.compute(L, R)
        bm.compute(L, R)
        gl, gr = sm._grey(L, "left"), sm._grey(R, "right")

        _kernels(gl, gr, n)
        times = cpu_medians(
            [
                lambda: stereo_disparity(L, R, num_disparities=n),  # noqa: B023
                lambda: _kernels(gl, gr, n),  # noqa: B023
                lambda: sgbm.compute(L, R),  # noqa: B023
                lambda: bm.compute(L, R),  # noqa: B023
            ],
            args.per,
        )
        size = f"{L.shape[1]} x {L.shape[0]}"
        res[name] = [*times, size, n]
    if args.maps:
        np.savez(args.maps, **maps)  # type: ignore[arg-type]
    print(json.dumps(res))


def main() -> None:
    ap = stereo_parser(__doc__.splitlines()[0], rounds=6, per=5)
    ap.add_argument("--maps", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        _worker(args)
        return
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    load0 = os.getloadavg()[0]
    tmp = Path(tempfile.mkdtemp())
    runs = alternate_trees(
        __file__, sys.argv[1:], trees, args.rounds, lambda k: ["--maps", str(tmp / f"{k}.npz")]
    )
    mb, ma = np.load(tmp / "before.npz"), np.load(tmp / "after.npz")
    lines = [
        "# Stereo matching: CPU time per pair, imageform before and after, against OpenCV",
        "",
        f"`python benchmarks/bench_stereo_speed.py --rounds {args.rounds} --per {args.per}`; "
        f"{time.strftime('%Y-%m-%d')}; one thread each; load average {load0:.1f} at the "
        f"start, {os.getloadavg()[0]:.1f} at the end (a shared 2-core machine: read the "
        "ratios, each taken within one process). imageform: `stereo_disparity` defaults "
        "(plane fill on); kernels: census, 3 x 3 cost sums and `match` of the same call; "
        "OpenCV: StereoSGBM MODE_HH (block 5, P1 200, P2 800, uniqueness 10, disp12MaxDiff 1) "
        "and StereoBM (block 15).",
        "",
        "| pair | size | disparities | before ms | after ms | kernels before / after ms | "
        "SGBM ms | BM ms | after / before | before / SGBM | after / SGBM | after / BM | "
        "same map |",
        "|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    for name in runs["before"][0]:
        b = [x[name][0] for x in runs["before"]]
        a = [x[name][0] for x in runs["after"]]
        kb = [x[name][1] for x in runs["before"]]
        ka = [x[name][1] for x in runs["after"]]
        cb = [x[name][2] for x in runs["before"]]
        ca = [x[name][2] for x in runs["after"]]
        bma = [x[name][3] for x in runs["after"]]
        bmb = [x[name][3] for x in runs["before"]]
        size, n = runs["before"][0][name][4], runs["before"][0][name][5]
        same = np.array_equal(mb[name], ma[name], equal_nan=True)
        lines.append(
            f"| {name} | {size} | {n} | {np.median(b) * 1e3:.1f} | {np.median(a) * 1e3:.1f} | "
            f"{np.median(kb) * 1e3:.1f} / {np.median(ka) * 1e3:.1f} | "
            f"{np.median(cb + ca) * 1e3:.1f} | {np.median(bmb + bma) * 1e3:.1f} | "
            f"{median_ratio(a, b):.2f} | {median_ratio(b, cb):.2f} | "
            f"{median_ratio(a, ca):.2f} | {median_ratio(a, bma):.2f} | "
            f"{'yes' if same else 'NO'} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
