"""Spectral-locus membership of 2^20 chromaticities: in_locus vs every edge vs matplotlib.

``imageform.color.in_locus`` tests each point against the edges of its horizontal slab only
(a bisection over the distinct vertex ordinates); before, it tested every edge of the
401-vertex locus at once (a (N, 401) temporary per operation: the Dask audit's 24 s eager
``check_in_locus``, ``benchmarks/results/dask-graphs-2026-11-30k.md``). The reference is that
every-edge test, run here in blocks of 2^14 points so that its memory stays bounded; the peer
is matplotlib's ``Path.contains_points`` (C++, radius 0). Points: uniform in
[-0.05, 0.9]^2 (xy, 2° observer), float64. Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_locus.py \\
        --out benchmarks/results/locus-2026-11-30k.md

Prints (and with ``--out`` writes) a Markdown table: median seconds over ``--repeat`` runs,
the ratio to the every-edge reference, and the answers that differ from it.
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
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import markdown_table, median_time  # noqa: E402


def every_edge(pts: np.ndarray, poly: np.ndarray, block: int = 1 << 14) -> np.ndarray:
    """The former in_locus: even-odd crossings of every edge, in blocks of ``block`` points."""
    x1, y1 = poly[:, 0].astype(pts.dtype), poly[:, 1].astype(pts.dtype)
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    dy = y2 - y1
    div = np.where(dy == 0, 1.0, dy).astype(pts.dtype)
    out = np.empty(pts.shape[0], dtype=bool)
    for s in range(0, pts.shape[0], block):
        x, y = pts[s : s + block, 0][:, None], pts[s : s + block, 1][:, None]
        crosses = (y1 > y) != (y2 > y)
        xint = x1 + (y - y1) * (x2 - x1) / div
        out[s : s + block] = np.sum((crosses & (x < xint)).astype(np.int32), axis=-1) % 2 == 1
    return out


def main() -> None:
    """Time the methods and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log2n", type=int, default=20, help="2^log2n points (default 20)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", type=Path)
    a = ap.parse_args()

    import matplotlib
    import torch
    from matplotlib.path import Path as MplPath

    from imageform.color import check_in_locus, in_locus, spectral_locus

    torch.set_num_threads(1)
    poly = spectral_locus().chromaticities
    n = 1 << a.log2n
    pts = np.random.default_rng(0).uniform(-0.05, 0.9, (n, 2))
    inside = pts[in_locus(pts)]
    ref = every_edge(pts, poly)
    mpl = MplPath(np.array(poly), closed=False)
    t_pts = torch.from_numpy(pts)

    methods = {
        "imageform in_locus (NumPy)": (lambda: in_locus(pts), True),
        "imageform in_locus (PyTorch CPU)": (lambda: in_locus(t_pts).numpy(), True),
        f"imageform check_in_locus ({inside.shape[0]} points inside)": (
            lambda: check_in_locus(inside),
            False,
        ),
        "every edge (the former in_locus, blocks of 2^14)": (lambda: every_edge(pts, poly), True),
        f"matplotlib {matplotlib.__version__} Path.contains_points": (
            lambda: mpl.contains_points(pts),
            True,
        ),
    }
    t_ref = median_time(lambda: every_edge(pts, poly), repeat=max(1, a.repeat // 2))
    rows = []
    for name, (fn, compare) in methods.items():
        t = t_ref if name.startswith("every edge") else median_time(fn, repeat=a.repeat)
        diff = str(int(np.count_nonzero(np.asarray(fn()) != ref))) if compare else "-"
        rows.append([name, f"{t:.4f}", f"{t_ref / t:.1f}", diff])
    load = os.getloadavg()
    text = (
        f"# Spectral locus membership, 2^{a.log2n} chromaticities\n\n"
        f"- machine: {os.cpu_count()} cores (shared), Python {platform.python_version()}, "
        f"NumPy {np.__version__}, PyTorch {torch.__version__} (1 thread)\n"
        f"- load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}\n"
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n"
        f"- {int(ref.sum())} of {n} points inside; medians of {a.repeat} runs "
        f"({max(1, a.repeat // 2)} for every edge)\n\n"
        + markdown_table(["method", "median s", "x every edge", "answers != every edge"], rows)
    )
    print(text)
    if a.out:
        a.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
