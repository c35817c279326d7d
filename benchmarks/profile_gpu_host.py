"""Where the host's time goes in one imageform call on CUDA tensors (issue 29).

On a GPU a 4K colour conversion's kernel takes tens of microseconds, so a call's wall time
is mostly the host's: Python validation, the CUDA-array views numba needs and numba's
launch. This script times tiny calls (8x8 pixels, 64 points: the kernel's time is nil, so
the time is the host's) for the fused operations, then profiles 300 ``convert`` calls with
cProfile (the functions with the largest own time). Run on a lent GPU::

    PYTHONPATH=src python benchmarks/profile_gpu_host.py > host-profile.txt
"""

from __future__ import annotations

import cProfile
import io
import pstats
import statistics
import time
from collections.abc import Callable
from typing import Any


def per_call_us(fn: Callable[[], Any], calls: int = 300) -> float:
    import torch

    for _ in range(5):
        fn()
    torch.cuda.synchronize()
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        torch.cuda.synchronize()
        times.append((time.perf_counter() - t0) / calls)
    return statistics.median(times) * 1e6


def main() -> None:
    import torch

    from imageform import color as c
    from imageform import geometry as g
    from imageform._cuda import _launch

    dev = torch.device("cuda")
    rgb = torch.rand(8, 8, 3, device=dev)
    lab = c.convert(rgb, "srgb", "lab")
    pts = torch.rand(64, 3, device=dev) + torch.tensor([0.0, 0.0, 4.0], device=dev)
    K = torch.tensor([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]], device=dev)
    bc = g.BrownConrady(k1=-0.1, k2=0.01)
    xy = torch.rand(64, 2, device=dev) - 0.5
    empty = torch.empty(8, 8, 3, device=dev)
    dargs = _launch.as_device_array(rgb)
    rows = [
        ("torch.empty (8x8x3)", lambda: torch.empty(8, 8, 3, device=dev)),
        ("torch add (8x8x3, one kernel)", lambda: rgb + 1.0),
        ("_launch.as_device_array (one tensor)", lambda: _launch.as_device_array(rgb)),
        ("numba device-array view reused (no-op)", lambda: dargs),
        ("convert srgb->lab", lambda: c.convert(rgb, "srgb", "lab")),
        ("convert srgb->linear_srgb", lambda: c.convert(rgb, "srgb", "linear_srgb")),
        ("delta_e ciede2000", lambda: c.delta_e(lab, lab, "ciede2000")),
        ("project_points (64 pts)", lambda: g.project_points(pts, K)),
        ("BrownConrady.distort (64 pts)", lambda: bc.distort(xy)),
        ("empty_like + copy_ (8x8x3)", lambda: empty.copy_(rgb)),
    ]
    from imageform._cuda import _fastlaunch

    print(f"imageform CUDA kernels: {_launch.status()}")
    print(f"fast launch (IMAGEFORM_CUDA_FAST_LAUNCH): {_fastlaunch.enabled()}\n")
    print("| call (tiny input) | host µs per call (median of 5 x 300) |\n|---|---|")
    for name, fn in rows:
        print(f"| {name} | {per_call_us(fn):.1f} |")
    ready = list(_fastlaunch._READY.values())
    fast = sum(r is not None for r in ready)
    print(f"\nfast launch: {fast} of {len(ready)} kernel signatures passed the packing check")
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(300):
        c.convert(rgb, "srgb", "lab")
    torch.cuda.synchronize()
    prof.disable()
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(30)
    print("\ncProfile of 300 convert(srgb->lab) calls, by own time:\n\n```text")
    print(s.getvalue().strip() + "\n```")


if __name__ == "__main__":
    main()
