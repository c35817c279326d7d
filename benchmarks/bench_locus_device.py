"""Spectral-locus membership on the device path: peak memory and time, against NumPy's answers.

``imageform.color.in_locus`` on arrays that cannot be read on the host for free (a GPU,
array-api-strict, PyTorch ``meta``) bisects each point's slab on the device and tests it
against the widest slab's K edges (54 for the 2° observer's xy). This script runs that path
on array-api-strict and on PyTorch CPU tensors with the host view turned off (the code a
CUDA tensor runs), and on ``meta`` tensors (no values: time only), for 400401 and 2^20
points uniform in [-0.05, 0.9]^2 (float64 and float32), and reports the peak resident memory
above the memory before the call (``VmHWM`` after resetting it, Linux), the median time and
the answers that differ from NumPy's ``in_locus`` (its host path).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_locus_device.py``;
``--src DIR --json FILE`` measures another source tree (the code before a change),
``--before FILE`` adds that run's figures as "before" columns.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _setup_path(src: str | None) -> None:
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, src or str(ROOT / "src"))


def _status(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024
    return 0


def _peak(fn: Any) -> tuple[Any, int]:
    """``fn()`` and the peak resident memory above the memory before it, in bytes."""
    Path("/proc/self/clear_refs").write_text("5")  # resets VmHWM to the current RSS
    base = _status("VmRSS")
    out = fn()
    return out, _status("VmHWM") - base


BACKENDS = ("array-api-strict", "PyTorch CPU, device path", "PyTorch meta")


def run_case(n: int, dtype: str, name: str, repeat: int) -> dict[str, Any]:
    """One case in this process: the peak of the first call, the median time, the answers."""
    import array_api_strict as xps
    import torch

    from imageform.color import chromaticity, in_locus

    torch.set_num_threads(1)
    pts = np.random.default_rng(0).uniform(-0.05, 0.9, (n, 2)).astype(dtype)
    want = in_locus(pts)
    if name == "array-api-strict":
        arr: Any = xps.asarray(pts)
    elif name == "PyTorch meta":
        arr = torch.empty(pts.shape, dtype=getattr(torch, dtype), device="meta")
    else:
        arr = torch.from_numpy(pts)
    chromaticity._host_view = lambda a: None  # type: ignore[assignment,misc]  # a device's path
    got, peak = _peak(lambda: in_locus(arr))
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        in_locus(arr)
        times.append(time.perf_counter() - t)
    diff = "-"
    if name != "PyTorch meta":
        got_np = got.numpy() if hasattr(got, "numpy") else np.asarray(got)
        diff = str(int(np.count_nonzero(got_np != want)))
    return {"peak_mb": peak / 2**20, "s": statistics.median(times), "diff": diff}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--src", help="the src folder to import imageform from")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--before", help="figures of a run before a change (--json of that run)")
    ap.add_argument("--case", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    _setup_path(args.src)
    if args.case:
        n, dtype, name = args.case
        print(json.dumps(run_case(int(n), dtype, name, args.repeat)))
        return 0
    import torch

    from benchmarks._common import header, markdown_table

    before = json.loads(Path(args.before).read_text()) if args.before else {}
    results, rows = {}, []
    for n in (400401, 1 << 20):
        for dtype in ("float64", "float32"):
            for name in BACKENDS:
                # a fresh process per case: the peak is not hidden by memory freed before
                cmd = [sys.executable, __file__, "--case", str(n), dtype, name]
                cmd += ["--repeat", str(args.repeat)] + (["--src", args.src] if args.src else [])
                done = subprocess.run(cmd, capture_output=True, text=True, check=True)
                r = json.loads(done.stdout.strip().splitlines()[-1])
                key = f"{n} | {dtype} | {name}"
                results[key] = r
                print(f"{key}: {r}", file=sys.stderr, flush=True)
                b = before.get(key, {})
                rows.append(
                    [
                        n,
                        dtype,
                        name,
                        f"{b['peak_mb']:.1f}" if b else "",
                        f"{r['peak_mb']:.1f}",
                        f"{b['s']:.3f}" if b else "",
                        f"{r['s']:.3f}",
                        b.get("diff", ""),
                        r["diff"],
                    ]
                )
    print(header("Spectral locus membership on the device path"))
    print(
        f"Points uniform in [-0.05, 0.9]^2 (2° observer, xy); PyTorch {torch.__version__} "
        f"(1 thread); medians of {args.repeat} runs; peak: resident memory above the memory "
        "before the call (VmHWM), MiB.\n"
    )
    cols = [
        "points",
        "dtype",
        "backend",
        "peak MiB before",
        "peak MiB",
        "s before",
        "s",
        "answers != NumPy before",
        "answers != NumPy",
    ]
    print(markdown_table(cols, rows))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    raise SystemExit(main())
