"""imageform on PyTorch (CUDA when available, else CPU) against kornia and the memory bandwidth.

Issue 9's GPU benchmark: sRGB -> CIELAB, CIEDE2000, projection of 10^8 points and
demosaicing (bilinear, Malvar), imageform's namespace-generic code on PyTorch tensors against
kornia (``kornia.color.rgb_to_lab``, ``kornia.color.raw_to_rgb`` (bilinear),
``kornia.geometry.camera.project_points``) and against the device's memory bandwidth:
the bytes an operation must move (read inputs + write outputs, once) divided by its time,
next to the bandwidth of a plain tensor copy on the same device (``dst.copy_(src)``, 2 x
bytes / time), the practical ceiling of a memory-bound kernel. Kornia has no ΔE: CIEDE2000
is compared with the bandwidth only. Each library runs in its native layout (imageform
channels-last ``(H, W, 3)``, kornia channels-first ``(1, 3, H, W)``); no transposes are timed.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_gpu.py --device cuda \\
        --out benchmarks/results/gpu-h100-DATE.md
    # on a CPU: fewer points, streamed in chunks the same way
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_gpu.py --device cpu \\
        --points 1e7 --size 1080x1920 --out benchmarks/results/gpu-cpu-DATE.md

Timings are medians over ``--repeat`` runs after a warm-up run; on CUDA every timed call is
bracketed by ``torch.cuda.synchronize()``. Projection streams ``--points`` points through
the device in chunks of ``--chunk`` (one resident chunk re-used, so memory stays bounded).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import markdown_table  # noqa: E402


def _sync(device: Any) -> None:
    import torch

    if device.type == "cuda":
        torch.cuda.synchronize(device)


def timed(fn: Callable[[], Any], device: Any, repeat: int, warmup: int = 1) -> float:
    """Median seconds of ``fn()``, synchronising the device around every call."""
    for _ in range(warmup):
        fn()
    _sync(device)
    times = []
    for _ in range(repeat):
        _sync(device)
        t0 = time.perf_counter()
        fn()
        _sync(device)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def copy_bandwidth(device: Any, nbytes: int, repeat: int) -> float:
    """GB/s of ``dst.copy_(src)`` for ``nbytes`` (counted twice: read + write)."""
    import torch

    n = nbytes // 4
    src = torch.rand(n, device=device, dtype=torch.float32)
    dst = torch.empty_like(src)
    t = timed(lambda: dst.copy_(src), device, repeat)
    return 2 * n * 4 / t / 1e9


def _row(name: str, impl: str, t: float, nbytes: int, ceiling: float, extra: str) -> list[str]:
    gbs = nbytes / t / 1e9
    return [name, impl, f"{t * 1e3:.2f}", f"{gbs:.2f}", f"{100 * gbs / ceiling:.0f} %", extra]


def bench_lab(
    device: Any, dtype: Any, h: int, w: int, repeat: int, ceiling: float
) -> list[list[str]]:
    import kornia
    import torch

    from imageform.color import convert

    g = torch.Generator(device="cpu").manual_seed(1)
    rgb = torch.rand((h, w, 3), generator=g, dtype=dtype).to(device)
    rgb_k = rgb.permute(2, 0, 1).contiguous()[None]
    ours = convert(rgb, "srgb", "lab")
    theirs = kornia.color.rgb_to_lab(rgb_k)[0].permute(1, 2, 0)
    diff = float((ours - theirs).abs().max())
    nbytes = 2 * rgb.numel() * rgb.element_size()  # read RGB, write Lab
    t_i = timed(lambda: convert(rgb, "srgb", "lab"), device, repeat)
    t_k = timed(lambda: kornia.color.rgb_to_lab(rgb_k), device, repeat)
    return [
        _row(f"sRGB→Lab {h}x{w}", "imageform", t_i, nbytes, ceiling, f"{t_k / t_i:.2f}x kornia"),
        _row(f"sRGB→Lab {h}x{w}", "kornia", t_k, nbytes, ceiling, f"max |ΔLab| {diff:.1e}"),
    ]


def bench_ciede2000(
    device: Any, dtype: Any, h: int, w: int, repeat: int, ceiling: float
) -> list[list[str]]:
    import torch

    from imageform.color import convert, delta_e_ciede2000

    g = torch.Generator(device="cpu").manual_seed(2)
    lab1 = convert(torch.rand((h, w, 3), generator=g, dtype=dtype), "srgb", "lab").to(device)
    lab2 = convert(torch.rand((h, w, 3), generator=g, dtype=dtype), "srgb", "lab").to(device)
    nbytes = (2 * lab1.numel() + h * w) * lab1.element_size()  # read 2 Lab, write ΔE
    t_i = timed(lambda: delta_e_ciede2000(lab1, lab2), device, repeat)
    return [_row(f"CIEDE2000 {h}x{w}", "imageform", t_i, nbytes, ceiling, "kornia: none")]


def bench_projection(
    device: Any, dtype: Any, n_points: int, chunk: int, repeat: int, ceiling: float
) -> list[list[str]]:
    import kornia
    import torch

    from imageform.geometry import project_points

    chunk = min(chunk, n_points)
    n_chunks = max(1, round(n_points / chunk))
    g = torch.Generator(device="cpu").manual_seed(3)
    X = (torch.rand((chunk, 3), generator=g, dtype=torch.float64) * 2 - 1).to(dtype)
    X[:, 2] += 4.0
    X = X.to(device)
    K = torch.tensor([[800.0, 0, 640], [0, 800, 360], [0, 0, 1]], dtype=dtype, device=device)
    Kb = K[None]
    Xb = X[None]

    def ours() -> None:
        for _ in range(n_chunks):
            project_points(X, K)

    def theirs() -> None:
        for _ in range(n_chunks):
            kornia.geometry.camera.project_points(Xb, Kb)

    uv = project_points(X, K).uv
    diff = float((uv - kornia.geometry.camera.project_points(Xb, Kb)[0]).abs().max())
    # read (N, 3), write uv (N, 2) and the validity mask (N bytes)
    nbytes = n_chunks * chunk * (5 * X.element_size() + 1)
    t_i = timed(ours, device, repeat)
    t_k = timed(theirs, device, repeat)
    label = f"projection {n_chunks * chunk:.1e} pts ({n_chunks} x {chunk:.1e})"
    return [
        _row(label, "imageform", t_i, nbytes, ceiling, f"{t_k / t_i:.2f}x kornia"),
        _row(label, "kornia", t_k, nbytes - n_chunks * chunk, ceiling, f"max |Δuv| {diff:.1e}"),
    ]


def bench_demosaic(
    device: Any, dtype: Any, h: int, w: int, repeat: int, ceiling: float
) -> list[list[str]]:
    import kornia
    import torch

    from imageform.sensor import demosaic

    g = torch.Generator(device="cpu").manual_seed(4)
    raw = torch.rand((h, w), generator=g, dtype=dtype).to(device)
    raw_k = raw[None, None]
    nbytes = 4 * raw.numel() * raw.element_size()  # read the mosaic, write RGB
    ours_bl = demosaic(raw, "RGGB", "bilinear")
    theirs = kornia.color.raw_to_rgb(raw_k, kornia.color.CFA.BG)[0].permute(1, 2, 0)
    diff = float((ours_bl - theirs).abs().max())  # same border handling: the whole image
    t_b = timed(lambda: demosaic(raw, "RGGB", "bilinear"), device, repeat)
    t_m = timed(lambda: demosaic(raw, "RGGB", "malvar"), device, repeat)
    t_k = timed(lambda: kornia.color.raw_to_rgb(raw_k, kornia.color.CFA.BG), device, repeat)
    lab = f"demosaic {h}x{w}"
    return [
        _row(lab, "imageform bilinear", t_b, nbytes, ceiling, f"{t_k / t_b:.2f}x kornia"),
        _row(lab, "imageform malvar", t_m, nbytes, ceiling, f"{t_k / t_m:.2f}x kornia bilinear"),
        _row(lab, "kornia bilinear", t_k, nbytes, ceiling, f"max |Δ| {diff:.1e}"),
    ]


def _header(device: Any, dtype: Any, ceiling: float) -> str:
    import kornia
    import torch

    if device.type == "cuda":
        dev = torch.cuda.get_device_name(device)
    else:
        dev = platform.processor() or platform.machine()
        try:
            for line in Path("/proc/cpuinfo").read_text().splitlines():
                if line.startswith("model name"):
                    dev = line.split(":", 1)[1].strip()
                    break
        except OSError:
            pass
        dev += f", {torch.get_num_threads()} torch threads, {os.cpu_count()} cores"
    return (
        f"Device: {device.type} ({dev}) · dtype {str(dtype).removeprefix('torch.')} · "
        f"torch {torch.__version__} · kornia {kornia.__version__} · "
        f"Python {platform.python_version()}\n\n"
        f"Measured copy bandwidth (ceiling): **{ceiling:.1f} GB/s**\n"
    )


def main() -> None:
    import torch

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default=None, help="cuda or cpu (default: cuda if available)")
    ap.add_argument("--dtype", default="float32", choices=["float32", "float64"])
    ap.add_argument("--size", default="2160x3840", help="HxW of the images (4K UHD)")
    ap.add_argument("--points", type=float, default=1e8, help="points to project")
    ap.add_argument("--chunk", type=float, default=2.5e7, help="points per streamed chunk")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--note", default="", help="a paragraph for the file's header")
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    args = ap.parse_args()
    name = args.device or ("cuda" if torch.cuda.is_available() else "cpu")
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise SystemExit("--device cuda asked for, but torch.cuda.is_available() is False")
    device = torch.device(name)
    dtype = getattr(torch, args.dtype)
    h, w = (int(v) for v in args.size.lower().split("x"))
    ceiling = copy_bandwidth(device, 8 * h * w * 3 * 4 // 3, args.repeat)
    rows = []
    rows += bench_lab(device, dtype, h, w, args.repeat, ceiling)
    rows += bench_ciede2000(device, dtype, h, w, args.repeat, ceiling)
    rows += bench_projection(device, dtype, int(args.points), int(args.chunk), args.repeat, ceiling)
    rows += bench_demosaic(device, dtype, h, w, args.repeat, ceiling)
    cols = ["operation", "implementation", "median ms", "GB/s moved", "of copy BW", "notes"]
    text = "# GPU / array benchmarks (issue 9)\n\n"
    if args.note:
        text += args.note.strip() + "\n\n"
    text += _header(device, dtype, ceiling) + "\n" + markdown_table(cols, rows)
    text += (
        "\nGB/s moved = bytes the operation must read and write once / median time "
        "(sRGB→Lab 2 x 3 values per pixel; CIEDE2000 7 values per pixel; projection 3 in, 2 "
        "out per point + a 1-byte mask (kornia: no mask); demosaicing 1 in, 3 out per "
        "pixel). Copy BW = 2 x bytes / time of `dst.copy_(src)` on the same device.\n"
    )
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
