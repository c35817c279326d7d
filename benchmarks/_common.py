"""Shared helpers for the benchmark scripts: timing medians and a Markdown table."""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence
from datetime import date
from typing import Any

__all__ = ["header", "markdown_table", "median_time", "paired_rounds"]


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
