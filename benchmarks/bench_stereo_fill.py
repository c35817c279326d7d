"""Stereo matching's CPU time, two source trees against each other and OpenCV's StereoSGBM.

``imageform.geometry.stereo_disparity`` at its defaults (the plane fill on) from the tree
``--before`` and from ``--after``, each in its own process (its numba kernels compiled before
timing), against ``cv2.StereoSGBM_create`` ``MODE_HH`` at matched settings (block 5, ``P1 =
8·25``, ``P2 = 32·25``, uniqueness 10 %, ``disp12MaxDiff`` 1) in the same process; CPU seconds
(``time.process_time``) of the whole call and of its plane fill alone
(``stereo_matching._plane_fill`` on the same matched map), one thread each
(``NUMBA_NUM_THREADS=1``, ``cv2.setNumThreads(1)``).
The processes alternate, before and after, for ``--rounds`` rounds (the order flipped every
round); each process times each pair ``--per`` times (the median) and OpenCV after each call.
Ratios: medians over the rounds of the per-round ratios. Pairs (not in the repository;
Middlebury's: "We grant permission to use and publish all images and disparity maps"):
cones and teddy of the 2003 set (450 x 375) as kept by github.com/r09921135/acv
``hw4/testdata/``, Adirondack of the 2014 set at quarter size (720 x 497) as kept by
github.com/2b-t/stereo-matching ``data/``, aloe of the 2006 set at half its third size
(320 x 277)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_stereo_fill.py --before /tmp/main/src \\
        --after src --acv /tmp/stereog/data/acv --middlebury /tmp/stereog/data/mb \\
        --scenes-0506 /tmp/stereog/data/ho0506 --rounds 8 --per 3
"""

from __future__ import annotations

import argparse
import json
import os
import sys
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


def _pairs(acv: Path, mb: Path, ho: Path) -> list[tuple[str, Path, Path, int, bool]]:
    return [
        *((name, lp, rp, n, False) for name, lp, rp, n in stereo_pairs(acv, mb)),
        ("aloe (half)", ho / "aloe" / "view1.png", ho / "aloe" / "view5.png", 64, True),
    ]


def _worker(args: argparse.Namespace) -> None:
    import cv2

    from imageform.geometry import stereo_disparity
    from imageform.geometry import stereo_matching as sm

    cv2.setNumThreads(1)
    res = {}
    for name, lp, rp, n, half in _pairs(args.acv, args.middlebury, args.scenes_0506):
        L, R = read_pair(lp, rp, half=half)
        sgbm = matched_sgbm(n)
        stereo_disparity(L, R, num_disparities=n)
        sgbm.compute(L, R)
        d = stereo_disparity(L, R, num_disparities=n, plane_fill=False)
        gl, gr = sm._grey(L, "left"), sm._grey(R, "right")
        sm._plane_fill(d, gl, 0, n, gr)
        fill, ours, cv = cpu_medians(
            [
                lambda: sm._plane_fill(d, gl, 0, n, gr),  # noqa: B023
                lambda: stereo_disparity(L, R, num_disparities=n),  # noqa: B023
                lambda: sgbm.compute(L, R),  # noqa: B023
            ],
            args.per,
        )
        size = f"{L.shape[1]} x {L.shape[0]}"
        res[name] = [ours, cv, size, n, fill]
    print(json.dumps(res))


def main() -> None:
    ap = stereo_parser(__doc__.splitlines()[0], rounds=8, per=3)
    ap.add_argument("--scenes-0506", type=Path, required=True, help="the 2005 / 2006 scenes")
    args = ap.parse_args()
    if args.worker:
        _worker(args)
        return
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    load0 = os.getloadavg()[0]
    runs = alternate_trees(__file__, sys.argv[1:], trees, args.rounds)
    lines = [
        "# Stereo matching: CPU time before and after, against OpenCV's StereoSGBM",
        "",
        f"{args.rounds} rounds, {args.per} calls a pair a process, one thread each; load "
        f"average {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end (a shared "
        "2-core machine: the ratios, taken within each process, are the figures to read).",
        "",
        "| pair | size | disparities | before s | after s | OpenCV s | after / before | "
        "before / OpenCV | after / OpenCV | plane fill alone: before / after ms (after / before) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for name in runs["before"][0]:
        b = [x[name][0] for x in runs["before"]]
        a = [x[name][0] for x in runs["after"]]
        cb = [x[name][1] for x in runs["before"]]
        ca = [x[name][1] for x in runs["after"]]
        fb = [x[name][4] for x in runs["before"]]
        fa = [x[name][4] for x in runs["after"]]
        size, n = runs["before"][0][name][2], runs["before"][0][name][3]
        lines.append(
            f"| {name} | {size} | {n} | {np.median(b):.3f} | {np.median(a):.3f} | "
            f"{np.median(cb + ca):.3f} | {median_ratio(a, b):.2f} | "
            f"{median_ratio(b, cb):.2f} | {median_ratio(a, ca):.2f} | "
            f"{np.median(fb) * 1e3:.1f} / {np.median(fa) * 1e3:.1f} "
            f"({median_ratio(fa, fb):.2f}) |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
