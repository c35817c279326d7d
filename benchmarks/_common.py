"""Shared helpers for the benchmark scripts: timing medians and a Markdown table.

The stereo benchmarks' set-up too: their Middlebury pairs, read as OpenCV reads them,
OpenCV's StereoSGBM at the matched settings, CPU-time medians, and the alternation of worker
processes, one per source tree (before and after).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from datetime import date
from pathlib import Path
from typing import Any

__all__ = [
    "alternate_trees",
    "cpu_medians",
    "header",
    "markdown_table",
    "matched_sgbm",
    "median_ratio",
    "median_time",
    "paired_rounds",
    "read_pair",
    "stereo_pairs",
    "stereo_parser",
]


def median_time(fn: Callable[[], Any], repeat: int = 5, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` in seconds over ``repeat`` runs after ``warmup`` runs."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def paired_rounds(
    ours: Callable[[], Any], theirs: Callable[[], Any], rounds: int, *, speed: bool = False
) -> tuple[float, float, float, float, float]:
    """Time two callables in ``rounds`` interleaved rounds (median of 5 calls each per round).

    Both are called once first (warm-up). Returns the medians over the rounds of our and
    their seconds, then the median, minimum and maximum of the per-round ratio: ours / theirs
    (a time ratio), or theirs / ours with ``speed`` (a speed ratio, > 1: ours faster).
    """
    ours()
    theirs()
    a, b, r = [], [], []
    for _ in range(rounds):
        ta, tb = median_time(ours, warmup=0), median_time(theirs, warmup=0)
        a.append(ta)
        b.append(tb)
        r.append(tb / ta if speed else ta / tb)
    return statistics.median(a), statistics.median(b), statistics.median(r), min(r), max(r)


def header(title: str) -> str:
    """A Markdown heading with the date, machine and thread settings."""
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    numba_threads = os.environ.get("NUMBA_NUM_THREADS", str(os.cpu_count()))
    return (
        f"# {title}\n\n{date.today().isoformat()} · {platform.machine()} · "
        f"{os.cpu_count()} cores · "
        f"Python {platform.python_version()} · OPENBLAS_NUM_THREADS={threads} · "
        f"numba threads={numba_threads}\n"
    )


def markdown_table(columns: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub Markdown table."""
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def stereo_pairs(acv: Path, mb: Path) -> list[tuple[str, Path, Path, int]]:
    """The Middlebury pairs both stereo benchmarks time: ``(name, left, right, disparities)``.

    Not in the repository (Middlebury's: "We grant permission to use and publish all images
    and disparity maps"): cones and teddy of the 2003 set (450 x 375) as kept by
    github.com/r09921135/acv ``hw4/testdata/`` (``acv``), Adirondack of the 2014 set at
    quarter size (720 x 497) as kept by github.com/2b-t/stereo-matching ``data/`` (``mb``).
    """
    return [
        ("cones", acv / "cones" / "im2.png", acv / "cones" / "im6.png", 64),
        ("teddy", acv / "teddy" / "im2.png", acv / "teddy" / "im6.png", 64),
        ("adirondack", mb / "Adirondack_left.png", mb / "Adirondack_right.png", 64),
    ]


def read_pair(left: Path, right: Path, *, half: bool = False) -> tuple[Any, Any]:
    """A pair as grey uint8 (``cv2.imread(path, 0)``), at half size (``INTER_AREA``) if ``half``."""
    import cv2

    L, R = cv2.imread(str(left), 0), cv2.imread(str(right), 0)
    if L is None or R is None:
        raise FileNotFoundError(f"cannot read the pair {left} / {right}")
    if half:
        size = (L.shape[1] // 2, L.shape[0] // 2)
        L = cv2.resize(L, size, interpolation=cv2.INTER_AREA)
        R = cv2.resize(R, size, interpolation=cv2.INTER_AREA)
    return L, R


def matched_sgbm(n: int) -> Any:
    """OpenCV's StereoSGBM at the settings matched to imageform's defaults.

    ``MODE_HH`` (8 paths), block 5, ``P1 = 8·25``, ``P2 = 32·25``, uniqueness 10 %,
    ``disp12MaxDiff`` 1, ``n`` disparities from 0.
    """
    import cv2

    return cv2.StereoSGBM_create(  # type: ignore[attr-defined]
        minDisparity=0, numDisparities=n, blockSize=5, P1=8 * 25, P2=32 * 25,
        disp12MaxDiff=1, uniquenessRatio=10, mode=cv2.STEREO_SGBM_MODE_HH,
    )  # fmt: skip


def cpu_medians(fns: Sequence[Callable[[], Any]], per: int) -> list[float]:
    """Median CPU seconds (``time.process_time``) of each of ``fns`` over ``per`` rounds.

    Each round calls them once each, in order (interleaved: a slow moment of a shared
    machine falls on all of them).
    """
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(per):
        for fn, t in zip(fns, times, strict=True):
            t0 = time.process_time()
            fn()
            t.append(time.process_time() - t0)
    return [statistics.median(t) for t in times]


def median_ratio(a: Sequence[float], b: Sequence[float]) -> float:
    """The median over rounds of the per-round ratios ``a[i] / b[i]``."""
    return statistics.median(x / y for x, y in zip(a, b, strict=True))


def stereo_parser(description: str, rounds: int, per: int) -> argparse.ArgumentParser:
    """The stereo benchmarks' common options: the two trees, the pairs, rounds and calls."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--before", type=Path, required=True, help="the src/ of the tree before")
    ap.add_argument("--after", type=Path, required=True, help="the src/ of the tree after")
    ap.add_argument("--acv", type=Path, required=True, help="acv's hw4/testdata/")
    ap.add_argument("--middlebury", type=Path, required=True, help="2b-t's data/")
    ap.add_argument("--rounds", type=int, default=rounds)
    ap.add_argument("--per", type=int, default=per)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path)
    return ap


def alternate_trees(
    script: str,
    argv: Sequence[str],
    trees: dict[str, Path],
    rounds: int,
    extra: Callable[[str], list[str]] | None = None,
) -> dict[str, list[Any]]:
    """Run ``script --worker *argv`` from each source tree in turn, for ``rounds`` rounds.

    Each run is a fresh process with ``PYTHONPATH`` the tree's ``src/`` and one thread
    (``OPENBLAS_NUM_THREADS=1``, ``NUMBA_NUM_THREADS=1``); the order of the trees is flipped
    every round. ``extra(name)`` adds a tree's own arguments. Returns, per tree, the JSON
    each run printed on its last line of output.
    """
    runs: dict[str, list[Any]] = {k: [] for k in trees}
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    for r in range(rounds):
        for k in list(trees) if r % 2 == 0 else list(trees)[::-1]:
            env["PYTHONPATH"] = str(trees[k])
            cmd = [sys.executable, script, "--worker", *argv, *(extra(k) if extra else [])]
            out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            runs[k].append(json.loads(out.stdout.strip().splitlines()[-1]))
    return runs
