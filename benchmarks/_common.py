"""Shared helpers for the benchmark scripts: timing medians and a Markdown table."""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence
from datetime import date
from typing import Any

__all__ = ["header", "markdown_table", "median_time"]


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
