"""imageform on PyTorch (CUDA when available, else CPU) against kornia and the memory bandwidth.

Issues 9 and 29's GPU benchmark, one prepared script for a lent GPU: sRGB -> CIELAB,
CIEDE2000, projection of 10^8 points (pinhole, and with Brown-Conrady), Brown-Conrady and
its inverse on 10^8 points, demosaicing (bilinear, Malvar), bilinear remapping and image
undistortion, each in every ``--dtypes`` (float32 and float64 by default), imageform on
PyTorch tensors (on CUDA the fused kernels of :mod:`imageform._cuda`, elsewhere the
namespace-generic code) against kornia (``kornia.color.rgb_to_lab``,
``kornia.color.raw_to_rgb`` (bilinear), ``kornia.geometry.camera.project_points``,
``kornia.geometry.calibration.distort_points`` / ``undistort_points`` / ``undistort_image``,
``kornia.geometry.transform.remap``); on CUDA also the raw development of a ``--raw-size``
(24 Mpx) mosaic to 16-bit sRGB, the kernel alone (frames per second) and with the copies;
and against the device's memory bandwidth: the bytes
an operation must move (read inputs + write outputs, once) divided by its time, as a share
of the bandwidth of a plain tensor copy on the same device (``dst.copy_(src)``, 2 x bytes /
time), the practical ceiling of a memory-bound kernel. Kornia has no ΔE: CIEDE2000 is
compared with the bandwidth only. Each library runs in its native layout (imageform
channels-last ``(H, W, 3)``, kornia channels-first ``(1, 3, H, W)``); no transposes are timed.

The colour set (sRGB→Lab, Lab→sRGB, sRGB→linear, sRGB→HSV, ProPhoto→Luv, chromatic
adaptation, white-balance gains, the four ΔE) runs imageform's fused numba-CUDA kernels on
CUDA tensors (issue 29, docs/design.md "GPU kernels"); each such call has a second row,
``imageform array-API``, the same call with ``IMAGEFORM_DISABLE_CUDA=1`` (the path before the
kernels), and the header says whether the kernels ran (``_cuda._launch.status()``: numba's
CUDA target needs its NVVM compiler, from numba-cuda's ``[cu12]``/``[cu13]`` extra or a CUDA
toolkit; where it is missing, the kernels are off with one warning and both rows time the
Array-API path). On CUDA the kernels-per-call column of a kernel row should read 1.

Per row: the median time, the share of the copy bandwidth, the **kernels per call** (on
CUDA the kernels and copies the profiler sees in one call; on a CPU the PyTorch operators
that compute, counted by a dispatch mode: what a CUDA run would launch), whether the call
ran **without a host synchronisation** (CUDA: ``torch.cuda.set_sync_debug_mode("error")``
around one call; a CPU cannot tell: "-") and the **ratio to kornia** (its time over
imageform's: above 1, imageform is faster). ``--compile`` adds rows for the same imageform
calls through ``torch.compile(fullgraph=True)`` (the fused path), for the first dtype only
(compiling costs up to a minute per call on first use).

On a lent GPU, the whole check is one command (about 5-8 minutes on an H100/H200, most of
it compiling; the device's budget is 15)::

    PYTHONPATH=src python -m pytest -q -n 0 -p no:cacheprovider \\
        tests/backends/test_cuda_device.py tests/backends/test_meta_device.py \\
        tests/backends/test_cuda_geometry_device.py; \\
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_gpu.py --device cuda \\
        --compile --out benchmarks/results/gpu-h200-DATE.md

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_gpu.py --device cuda \\
        --compile --out benchmarks/results/gpu-h100-DATE.md
    # on a CPU: fewer points, streamed in chunks the same way
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_gpu.py --device cpu \\
        --points 1e7 --size 1080x1920 --out benchmarks/results/gpu-cpu-DATE.md
    # a smoke run (tiny inputs, seconds): every row, numbers meaningless
    PYTHONPATH=src python benchmarks/bench_gpu.py --device cpu --smoke

Timings are medians over ``--repeat`` runs after a warm-up run; on CUDA every timed call is
bracketed by ``torch.cuda.synchronize()``. Projection streams ``--points`` points through
the device in chunks of ``--chunk`` (one resident chunk re-used, so memory stays bounded);
its kernel count is per chunk.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
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


def kernels_per_call(fn: Callable[[], Any], device: Any) -> tuple[int, float | None]:
    """Kernels one call launches, and their device time in seconds (CUDA; else None).

    CUDA: the kernels and copies the profiler sees over three calls, and the sum of their
    durations on the device, both per call (the kernels' own time, without the host's
    Python, launch latency and synchronisation that the wall-clock median includes). On a
    CPU the operators are counted by a dispatch mode (views and allocations left out): each
    would be one CUDA kernel, so the count is the GPU's without a GPU.
    """
    import torch

    fn()
    _sync(device)
    if device.type == "cuda":
        from torch.autograd import DeviceType
        from torch.profiler import ProfilerActivity, profile

        calls = 3
        with profile(activities=[ProfilerActivity.CPU, ProfilerActivity.CUDA]) as prof:
            for _ in range(calls):
                fn()
            torch.cuda.synchronize(device)
        kern = [e for e in prof.events() if e.device_type == DeviceType.CUDA]
        busy = sum(e.time_range.elapsed_us() for e in kern) * 1e-6 / calls
        return round(len(kern) / calls), busy
    from tests.backends._dispatch import DeviceGuard

    with DeviceGuard() as guard:
        fn()
    return guard.kernels, None


def queued(fn: Callable[[], Any], device: Any, calls: int = 20) -> float | None:
    """Seconds per call of ``calls`` back-to-back calls and one synchronisation (CUDA).

    The throughput a pipeline sees: the host's work for one call overlaps the device's for
    the one before, so this is the larger of the two per call. None on a CPU.
    """
    if device.type != "cuda":
        return None
    fn()
    _sync(device)
    t0 = time.perf_counter()
    for _ in range(calls):
        fn()
    _sync(device)
    return (time.perf_counter() - t0) / calls


def sync_free(fn: Callable[[], Any], device: Any) -> str:
    """``"yes"`` if one call runs under ``set_sync_debug_mode("error")`` (CUDA), else why not."""
    import torch

    if device.type != "cuda":
        return "-"
    fn()
    torch.cuda.synchronize(device)
    torch.cuda.set_sync_debug_mode("error")
    try:
        fn()
    except RuntimeError as exc:
        return "no: " + str(exc).splitlines()[0][:40]
    finally:
        torch.cuda.set_sync_debug_mode("default")
    return "yes"


@dataclass
class Op:
    """One timed call: its name, implementation, function and the bytes it must move."""

    name: str
    impl: str
    fn: Callable[[], Any]
    nbytes: int
    note: str = ""
    #: the implementation whose time the ratio column divides by this one's (kornia's name)
    versus: str | None = None
    #: the call whose kernels are counted (default ``fn``; a streamed op: one chunk)
    one_call: Callable[[], Any] | None = None
    #: chunks per call of a streamed op (its kernel time is one chunk's times this)
    chunks: int = 1


def measure(ops: list[Op], device: Any, dtype: Any, repeat: int, ceiling: float) -> list[list[str]]:
    """Time, count and check every op; the ratio column is ``versus``'s time over this one's."""
    times: dict[str, float] = {}
    failed: dict[str, str] = {}
    for op in ops:  # one failing call (a compile error ...) costs its row, not the run
        try:
            times[op.impl] = timed(op.fn, device, repeat)
        except Exception as exc:
            failed[op.impl] = f"failed: {type(exc).__name__}: {str(exc).splitlines()[0][:80]}"
    rows = []
    for op in ops:
        if op.impl in failed:
            rows.append(
                [op.name, str(dtype).removeprefix("torch."), op.impl, *"--------", failed[op.impl]]
            )
            continue
        t = times[op.impl]
        gbs = op.nbytes / t / 1e9
        ratio = f"{times[op.versus] / t:.2f}x" if op.versus in times else "-"
        count, busy = kernels_per_call(op.one_call or op.fn, device)
        if busy and op.one_call is not None:  # a streamed op: busy is one chunk's
            busy *= op.chunks
        q = queued(op.fn, device)
        rows.append(
            [
                op.name,
                str(dtype).removeprefix("torch."),
                op.impl,
                f"{t * 1e3:.3f}",
                f"{100 * gbs / ceiling:.1f} %",
                "-" if not busy else f"{busy * 1e3:.3f}",
                "-" if not busy else f"{100 * op.nbytes / busy / 1e9 / ceiling:.1f} %",
                "-" if q is None else f"{q * 1e3:.3f}",
                str(count),
                sync_free(op.fn, device) if op.impl.startswith("imageform") else "-",
                ratio,
                op.note,
            ]
        )
    for row in rows:  # progress on stderr: a run cut short still shows what it measured
        print("| " + " | ".join(row) + " |", file=sys.stderr, flush=True)
    return rows


def _compiled(fn: Callable[..., Any], *args: Any) -> Callable[[], Any]:
    import torch

    cfn = torch.compile(fn, fullgraph=True)  # compiled on the first (warm-up) call
    return lambda: cfn(*args)


def _array_api(fn: Callable[[], Any]) -> Callable[[], Any]:
    """``fn`` with imageform's CUDA kernels switched off (``IMAGEFORM_DISABLE_CUDA=1``)."""

    from imageform._cuda import _launch

    def run() -> Any:
        old = os.environ.get("IMAGEFORM_DISABLE_CUDA")
        os.environ["IMAGEFORM_DISABLE_CUDA"] = "1"
        _launch.refresh_switches()  # the switches are read once, not in every call
        try:
            return fn()
        finally:
            if old is None:
                del os.environ["IMAGEFORM_DISABLE_CUDA"]
            else:
                os.environ["IMAGEFORM_DISABLE_CUDA"] = old
            _launch.refresh_switches()

    return run


AA = "imageform array-API"


def ops_lab(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
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
    name = f"sRGB→Lab {h}x{w}"
    ops = [
        Op(name, "imageform", lambda: convert(rgb, "srgb", "lab"), nbytes, versus="kornia"),
        Op(name, AA, _array_api(lambda: convert(rgb, "srgb", "lab")), nbytes, versus="kornia"),
        Op(
            name, "kornia", lambda: kornia.color.rgb_to_lab(rgb_k), nbytes, f"max |ΔLab| {diff:.1e}"
        ),
    ]
    if compile_:
        fn = _compiled(lambda x: convert(x, "srgb", "lab"), rgb)
        ops.append(Op(name, "imageform compiled", fn, nbytes, versus="kornia"))
    return ops


def ops_ciede2000(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
    import torch

    from imageform.color import convert, delta_e_ciede2000

    g = torch.Generator(device="cpu").manual_seed(2)
    lab1 = convert(torch.rand((h, w, 3), generator=g, dtype=dtype), "srgb", "lab").to(device)
    lab2 = convert(torch.rand((h, w, 3), generator=g, dtype=dtype), "srgb", "lab").to(device)
    nbytes = (2 * lab1.numel() + h * w) * lab1.element_size()  # read 2 Lab, write ΔE
    name = f"CIEDE2000 {h}x{w}"
    ops = [
        Op(name, "imageform", lambda: delta_e_ciede2000(lab1, lab2), nbytes, versus=AA),
        Op(name, AA, _array_api(lambda: delta_e_ciede2000(lab1, lab2)), nbytes, "kornia: none"),
    ]
    if compile_:
        fn = _compiled(delta_e_ciede2000, lab1, lab2)
        ops.append(Op(name, "imageform compiled", fn, nbytes, versus="imageform"))
    return ops


def ops_projection(device: Any, dtype: Any, n_points: int, chunk: int, compile_: bool) -> list[Op]:
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

    def streamed(fn: Callable[[], Any]) -> Callable[[], Any]:
        def run() -> None:
            for _ in range(n_chunks):
                fn()

        return run

    uv = project_points(X, K).uv
    diff = float((uv - kornia.geometry.camera.project_points(Xb, Kb)[0]).abs().max())
    # read (N, 3), write uv (N, 2) and the validity mask (N bytes)
    nbytes = n_chunks * chunk * (5 * X.element_size() + 1)
    name = f"projection {n_chunks * chunk:.1e} pts ({n_chunks} x {chunk:.1e})"
    ops = [
        Op(
            name,
            "imageform",
            streamed(lambda: project_points(X, K)),
            nbytes,
            versus="kornia",
            chunks=n_chunks,
            one_call=lambda: project_points(X, K),
        ),
        Op(
            name,
            "kornia",
            streamed(lambda: kornia.geometry.camera.project_points(Xb, Kb)),
            nbytes - n_chunks * chunk,
            f"max |Δuv| {diff:.1e}; no mask",
            chunks=n_chunks,
            one_call=lambda: kornia.geometry.camera.project_points(Xb, Kb),
        ),
    ]
    if compile_:
        cfn = _compiled(lambda x, k: project_points(x, k).uv, X, K)
        ops.append(
            Op(
                name,
                "imageform compiled",
                streamed(cfn),
                nbytes,
                versus="kornia",
                chunks=n_chunks,
                one_call=cfn,
            )
        )
    return ops


def ops_demosaic(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
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
    name = f"demosaic {h}x{w}"
    kb = "kornia bilinear"
    ops = [
        Op(
            name, "imageform bilinear", lambda: demosaic(raw, "RGGB", "bilinear"), nbytes, versus=kb
        ),
        Op(name, "imageform malvar", lambda: demosaic(raw, "RGGB", "malvar"), nbytes, versus=kb),
        Op(
            name,
            kb,
            lambda: kornia.color.raw_to_rgb(raw_k, kornia.color.CFA.BG),
            nbytes,
            f"max |Δ| {diff:.1e}",
        ),
    ]
    if compile_:
        fn = _compiled(lambda r: demosaic(r, "RGGB", "bilinear"), raw)
        ops.append(Op(name, "imageform compiled bilinear", fn, nbytes, versus=kb))
    return ops


def ops_remap(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
    import kornia
    import torch

    from imageform.geometry import BrownConrady, remap_bilinear, undistortion_map

    g = torch.Generator(device="cpu").manual_seed(5)
    img = torch.rand((h, w, 3), generator=g, dtype=dtype).to(device)
    K = torch.tensor(
        [[0.8 * w, 0, w / 2], [0, 0.8 * w, h / 2], [0, 0, 1]], dtype=torch.float64, device=device
    )
    m = undistortion_map((h, w), K, BrownConrady(k1=-0.2, k2=0.05))  # float64 on the device
    mx, my = m[None, ..., 0].to(dtype), m[None, ..., 1].to(dtype)
    img_k = img.permute(2, 0, 1).contiguous()[None]
    # read the map (2 values) and the image once, write the image
    nbytes = (2 * h * w) * m.element_size() + 2 * img.numel() * img.element_size()

    def theirs() -> Any:
        return kornia.geometry.transform.remap(img_k, mx, my, align_corners=True)

    diff = float((remap_bilinear(img, m) - theirs()[0].permute(1, 2, 0)).abs().max())
    name = f"remap (undistort) {h}x{w}"
    ops = [
        Op(name, "imageform", lambda: remap_bilinear(img, m), nbytes, versus="kornia"),
        Op(name, "kornia", theirs, nbytes, f"max |Δ| {diff:.1e} (border rules differ)"),
    ]
    if compile_:
        ops.append(Op(name, "imageform compiled", _compiled(remap_bilinear, img, m), nbytes))
    return ops


#: The lens of the distortion rows (OpenCV's rational model, every coefficient used).
_LENS = {"k1": -0.21, "k2": 0.05, "p1": 0.002, "p2": -0.001, "k3": -0.01, "k4": 0.02, "k5": 0.001}


def _streamed(fn: Callable[[], Any], n_chunks: int) -> Callable[[], Any]:
    def run() -> None:
        for _ in range(n_chunks):
            fn()

    return run


def ops_projection_distorted(
    device: Any, dtype: Any, n_points: int, chunk: int, compile_: bool
) -> list[Op]:
    """Projection with Brown-Conrady (``Camera.project``'s path) against kornia's two steps."""
    import kornia
    import torch

    from imageform.geometry import BrownConrady, project_points_distorted

    chunk = min(chunk, n_points)
    n_chunks = max(1, round(n_points / chunk))
    g = torch.Generator(device="cpu").manual_seed(6)
    X = (torch.rand((chunk, 3), generator=g, dtype=torch.float64) * 2 - 1).to(dtype)
    X[:, 2] += 4.0
    X = X.to(device)
    K = torch.tensor([[800.0, 0, 640], [0, 800, 360], [0, 0, 1]], dtype=dtype, device=device)
    R = torch.eye(3, dtype=dtype, device=device)
    t = torch.zeros(3, dtype=dtype, device=device)
    bc = BrownConrady(**_LENS)
    dist = torch.tensor([[*bc.coeffs]], dtype=dtype, device=device)

    def ours() -> Any:
        return project_points_distorted(X, K, R, t, bc)

    def theirs() -> Any:  # kornia: the pinhole, then the distortion of the pixel coordinates
        uv = kornia.geometry.camera.project_points(X[None], K[None])
        return kornia.geometry.calibration.distort_points(uv, K[None], dist)

    diff = float((ours().uv - theirs()[0]).abs().max())
    nbytes = n_chunks * chunk * (5 * X.element_size() + 1)
    name = f"projection + distortion {n_chunks * chunk:.1e} pts ({n_chunks} x {chunk:.1e})"
    ops = [
        Op(
            name,
            "imageform",
            _streamed(ours, n_chunks),
            nbytes,
            versus="kornia",
            chunks=n_chunks,
            one_call=ours,
        ),
        Op(
            name,
            "kornia",
            _streamed(theirs, n_chunks),
            nbytes - n_chunks * chunk,
            f"max |Δuv| {diff:.1e}; no mask",
            chunks=n_chunks,
            one_call=theirs,
        ),
    ]
    if compile_:
        cfn = _compiled(lambda x: project_points_distorted(x, K, R, t, bc).uv, X)
        ops.append(
            Op(
                name,
                "imageform compiled",
                _streamed(cfn, n_chunks),
                nbytes,
                chunks=n_chunks,
                one_call=cfn,
            )
        )
    return ops


def ops_distortion(device: Any, dtype: Any, n_points: int, chunk: int, compile_: bool) -> list[Op]:
    """Brown-Conrady and its inverse on points against kornia's ``distort/undistort_points``.

    imageform works on normalised coordinates (``K`` applied by the caller), kornia on pixels
    (``K`` inverted and applied inside); imageform's inverse is Newton's method (at most 20
    steps, to 64 ulp), kornia's five fixed-point iterations (OpenCV's).
    """
    import kornia
    import torch

    from imageform.geometry import BrownConrady

    chunk = min(chunk, n_points)
    n_chunks = max(1, round(n_points / chunk))
    g = torch.Generator(device="cpu").manual_seed(7)
    xy = ((torch.rand((chunk, 2), generator=g, dtype=torch.float64) - 0.5) * 1.2).to(dtype)
    xy = xy.to(device)
    K = torch.tensor([[800.0, 0, 640], [0, 800, 360], [0, 0, 1]], dtype=dtype, device=device)
    uv = xy * 800.0 + torch.tensor([640.0, 360.0], dtype=dtype, device=device)
    bc = BrownConrady(**_LENS)
    dist = torch.tensor([[*bc.coeffs]], dtype=dtype, device=device)
    xyd = bc.distort(xy)
    uvd = kornia.geometry.calibration.distort_points(uv[None], K[None], dist)

    def und() -> Any:
        return bc.undistort(xyd)

    def k_und() -> Any:
        return kornia.geometry.calibration.undistort_points(uvd, K[None], dist)

    d_fwd = float((xyd * 800.0 + K[:2, 2] - uvd[0]).abs().max())
    d_inv = float((und().xy * 800.0 + K[:2, 2] - k_und()[0]).abs().nan_to_num(0.0).max())
    nb_fwd = n_chunks * chunk * 4 * xy.element_size()  # read 2, write 2
    nb_inv = nb_fwd + n_chunks * chunk  # and the 1-byte mask
    fwd = f"distort {n_chunks * chunk:.1e} pts"
    inv = f"undistort (inverse) {n_chunks * chunk:.1e} pts"
    return [
        Op(
            fwd,
            "imageform",
            _streamed(lambda: bc.distort(xy), n_chunks),
            nb_fwd,
            versus="kornia",
            chunks=n_chunks,
            one_call=lambda: bc.distort(xy),
        ),
        Op(
            fwd,
            "kornia",
            _streamed(
                lambda: kornia.geometry.calibration.distort_points(uv[None], K[None], dist),
                n_chunks,
            ),
            nb_fwd,
            f"max |Δ| {d_fwd:.1e} px; kornia on pixels",
            chunks=n_chunks,
            one_call=lambda: kornia.geometry.calibration.distort_points(uv[None], K[None], dist),
        ),
        Op(
            inv,
            "imageform",
            _streamed(und, n_chunks),
            nb_inv,
            versus="kornia",
            chunks=n_chunks,
            one_call=und,
        ),
        Op(
            inv,
            "kornia",
            _streamed(k_und, n_chunks),
            nb_fwd,
            f"max |Δ| {d_inv:.1e} px; kornia: 5 fixed-point steps, no mask",
            chunks=n_chunks,
            one_call=k_und,
        ),
    ]


def ops_undistort_image(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
    """Undistortion of an image (the map computed where it is sampled) against kornia's."""
    import kornia
    import torch

    from imageform.geometry import BrownConrady, undistort_image

    g = torch.Generator(device="cpu").manual_seed(8)
    img = torch.rand((h, w, 3), generator=g, dtype=dtype).to(device)
    img_k = img.permute(2, 0, 1).contiguous()[None]
    K = torch.tensor(
        [[0.8 * w, 0, w / 2], [0, 0.8 * w, h / 2], [0, 0, 1]], dtype=torch.float64, device=device
    )
    bc = BrownConrady(k1=-0.2, k2=0.05, p1=0.001, p2=-0.001)
    dist = torch.tensor([[*bc.coeffs[:5]]], dtype=dtype, device=device)
    Kk = K.to(dtype)[None]

    def ours() -> Any:
        return undistort_image(img, K, bc)

    def theirs() -> Any:
        return kornia.geometry.calibration.undistort_image(img_k, Kk, dist)

    diff = float((ours() - theirs()[0].permute(1, 2, 0)).abs().max())
    nbytes = 2 * img.numel() * img.element_size()  # read the image once, write it
    name = f"undistort image {h}x{w}"
    return [
        Op(name, "imageform", ours, nbytes, versus="kornia"),
        Op(name, "kornia", theirs, nbytes, f"max |Δ| {diff:.1e} (border rules differ)"),
    ]


def ops_develop(device: Any, h: int, w: int) -> list[Op]:
    """The whole raw development of a ``h x w`` Bayer mosaic on the GPU (CUDA only).

    The kernel alone on device-resident arrays (uint16 mosaic in, 16-bit sRGB out: 8 bytes a
    pixel; the frames per second in the notes), and ``develop(device="cuda").to_integer(16)``
    with the copies to and from the device.
    """
    import numpy as np

    from imageform._cuda.demosaic import MODE_UINT16, develop_on_device, develop_parameters
    from imageform.io import RawImage, develop
    from imageform.io.raw import _transfer_table

    rng = np.random.default_rng(9)
    mosaic = rng.integers(64, 4095, size=(h, w)).astype(np.uint16)
    raw = RawImage(
        mosaic=mosaic,
        black_level=np.full((2, 2), 64.0),
        white_level=4095.0,
        cfa_pattern="RGGB",
        white_balance=np.array([2.0, 1.0, 1.5]),
        xyz_to_camera=np.array([[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]]),
        camera_to_srgb=np.eye(3),
        calibration_illuminant="D65",
    )
    # numba device arrays (torch's uint16 support is partial); torch.cuda.synchronize()
    # waits for them too (numba launches on the legacy default stream)
    from imageform._cuda.geometry import import_cuda

    cu = import_cuda()
    d_mosaic = cu.to_device(mosaic)
    prm = cu.to_device(develop_parameters(np.full((2, 2), 64.0), np.full((2, 2), 1 / 4031)))
    m = cu.to_device(np.eye(3, dtype=np.float32))
    lut = cu.to_device(_transfer_table("srgb"))
    out = cu.device_array((h, w, 3), np.uint16)
    nbytes = 8 * h * w
    ops = []
    for method in ("bilinear", "malvar"):

        def kernel(method: str = method) -> Any:
            return develop_on_device(d_mosaic, prm, 0, 0, method, m, lut, True, MODE_UINT16, out)

        def whole(method: str = method) -> Any:
            return develop(raw, demosaic=method, device="cuda").to_integer(16)

        t = timed(kernel, device, 5)
        name = f"develop {h}x{w} raw -> 16-bit sRGB"
        ops.append(Op(name, f"imageform {method} kernel", kernel, nbytes, f"{1 / t:.0f} fps"))
        ops.append(
            Op(
                name,
                f"imageform {method} with copies",
                whole,
                nbytes,
                "host mosaic in, host RGB out",
            )
        )
    return ops


def ops_color(device: Any, dtype: Any, h: int, w: int, compile_: bool) -> list[Op]:
    """The rest of the colour pointwise set (issue 29's fused kernels): one row per call.

    Each imageform call is also timed on the Array-API path (``IMAGEFORM_DISABLE_CUDA=1``:
    the path before the kernels); the ratio column of the kernel rows is kornia's time over
    theirs where kornia has the operation, else the Array-API path's.
    """
    import kornia
    import torch

    from imageform.color import (
        chromatic_adaptation,
        convert,
        delta_e_cie76,
        delta_e_cie94,
        delta_e_cmc,
        srgb_to_linear,
    )
    from imageform.color.white_balance import apply_white_balance_gains

    g = torch.Generator(device="cpu").manual_seed(6)
    rgb = torch.rand((h, w, 3), generator=g, dtype=dtype).to(device)
    rgb_k = rgb.permute(2, 0, 1).contiguous()[None]
    lab = convert(rgb, "srgb", "lab")
    lab_k = lab.permute(2, 0, 1).contiguous()[None]
    lab2 = convert(torch.rand((h, w, 3), generator=g, dtype=dtype).to(device), "srgb", "lab")
    xyz = convert(rgb, "srgb", "xyz")
    img = 2 * rgb.numel() * rgb.element_size()  # read 3, write 3 values per pixel
    de = (2 * lab.numel() + h * w) * lab.element_size()  # read 2 Lab, write ΔE
    gains = [1.3, 1.0, 0.7]
    calls: list[tuple[str, Callable[[], Any], int, Callable[[], Any] | None]] = [
        (
            "Lab→sRGB",
            lambda: convert(lab, "lab", "srgb"),
            img,
            lambda: kornia.color.lab_to_rgb(lab_k),
        ),
        (
            "sRGB→linear",
            lambda: srgb_to_linear(rgb),
            img,
            lambda: kornia.color.rgb_to_linear_rgb(rgb_k),
        ),
        (
            "sRGB→HSV",
            lambda: convert(rgb, "srgb", "hsv"),
            img,
            lambda: kornia.color.rgb_to_hsv(rgb_k),
        ),
        ("ProPhoto→Luv", lambda: convert(rgb, "prophoto", "luv"), img, None),
        ("adaptation D65→D50", lambda: chromatic_adaptation(xyz, "D65", "D50"), img, None),
        ("white balance gains", lambda: apply_white_balance_gains(rgb, gains), img, None),
        ("ΔE76", lambda: delta_e_cie76(lab, lab2), de, None),
        ("ΔE94", lambda: delta_e_cie94(lab, lab2), de, None),
        ("ΔE CMC", lambda: delta_e_cmc(lab, lab2), de, None),
    ]
    ops: list[Op] = []
    for label, fn, nbytes, theirs in calls:
        name = f"{label} {h}x{w}"
        ops.append(Op(name, "imageform", fn, nbytes, versus="kornia" if theirs else AA))
        ops.append(Op(name, AA, _array_api(fn), nbytes, versus="kornia" if theirs else None))
        if theirs is not None:
            ops.append(Op(name, "kornia", theirs, nbytes))
    return ops


def _header(device: Any, dtypes: list[Any], ceiling: float) -> str:
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
        f"Device: {device.type} ({dev}) · dtypes "
        f"{', '.join(str(d).removeprefix('torch.') for d in dtypes)} · "
        f"torch {torch.__version__} · kornia {kornia.__version__} · "
        f"Python {platform.python_version()}\n\n"
        f"Measured copy bandwidth (ceiling): **{ceiling:.1f} GB/s** · imageform's CUDA "
        f"kernels: {_kernel_status(device)}\n"
    )


def _kernel_status(device: Any) -> str:
    """Whether imageform's colour kernels ran (they do on CUDA tensors when numba can)."""
    if device.type != "cuda":
        return "not used (CPU tensors)"
    from imageform._cuda import _launch

    return _launch.status()


def main() -> None:
    import torch

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default=None, help="cuda or cpu (default: cuda if available)")
    ap.add_argument("--dtypes", default="float32,float64", help="comma-separated dtypes")
    ap.add_argument("--dtype", default=None, help="one dtype (same as --dtypes with one)")
    ap.add_argument("--size", default="2160x3840", help="HxW of the images (4K UHD)")
    ap.add_argument("--points", type=float, default=1e8, help="points to project")
    ap.add_argument("--chunk", type=float, default=2.5e7, help="points per streamed chunk")
    ap.add_argument("--raw-size", default="4000x6000", help="HxW of the raw mosaic (24 Mpx)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--compile", action="store_true", help="also time torch.compile'd calls")
    ap.add_argument("--smoke", action="store_true", help="tiny inputs, one repeat: a check")
    ap.add_argument("--note", default="", help="a paragraph for the file's header")
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    args = ap.parse_args()
    if args.smoke:
        args.size, args.points, args.chunk, args.repeat = "16x24", 1000.0, 500.0, 1
        args.raw_size = "16x24"
    name = args.device or ("cuda" if torch.cuda.is_available() else "cpu")
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise SystemExit("--device cuda asked for, but torch.cuda.is_available() is False")
    device = torch.device(name)
    names = [args.dtype] if args.dtype else args.dtypes.split(",")
    if not set(names) <= {"float32", "float64"}:
        raise SystemExit(f"--dtypes: float32 and/or float64, got {names}")
    dtypes = [getattr(torch, n.strip()) for n in names]
    h, w = (int(v) for v in args.size.lower().split("x"))
    ceiling = copy_bandwidth(device, 8 * h * w * 3 * 4 // 3, args.repeat)
    rows = []
    for dtype in dtypes:
        comp = args.compile and dtype == dtypes[0]  # compiled rows: the first dtype only
        for make in (ops_lab, ops_ciede2000, ops_color, ops_demosaic, ops_remap):
            ops = make(device, dtype, h, w, comp)
            for name in dict.fromkeys(op.name for op in ops):  # one group per operation
                group = [op for op in ops if op.name == name]
                rows += measure(group, device, dtype, args.repeat, ceiling)
        proj = ops_projection(device, dtype, int(args.points), int(args.chunk), comp)
        rows += measure(proj, device, dtype, args.repeat, ceiling)
        pts, chunk = int(args.points), int(args.chunk)
        for ops in (
            ops_projection_distorted(device, dtype, pts, chunk, comp),
            ops_distortion(device, dtype, pts, chunk, comp),
            ops_undistort_image(device, dtype, h, w, comp),
        ):
            for name in dict.fromkeys(op.name for op in ops):  # one table block per operation
                group = [op for op in ops if op.name == name]
                rows += measure(group, device, dtype, args.repeat, ceiling)
    if device.type == "cuda":  # the raw pipeline's kernel: CUDA only
        rh, rw = (int(v) for v in args.raw_size.lower().split("x"))
        rows += measure(ops_develop(device, rh, rw), device, "uint16", args.repeat, ceiling)
    cols = [
        "operation",
        "dtype",
        "implementation",
        "median ms",
        "of copy BW",
        "kernel ms",
        "kernel of copy BW",
        "queued ms",
        "kernels/call",
        "no host sync",
        "vs kornia",
        "notes",
    ]
    text = "# GPU / array benchmarks (issues 9, 29)\n\n"
    if args.note:
        text += args.note.strip() + "\n\n"
    text += _header(device, dtypes, ceiling) + "\n" + markdown_table(cols, rows)
    text += (
        "\nOf copy BW = (bytes the operation must read and write once / median time) / the copy "
        "bandwidth above (sRGB→Lab 2 x 3 values per pixel; CIEDE2000 7 values per pixel; "
        "projection 3 in, 2 out per point + a 1-byte mask (kornia: no mask); distortion 2 in, "
        "2 out per point (+ the mask for the inverse); demosaicing 1 in, 3 out per pixel; remap "
        "the float64 map, 3 in and 3 out per pixel; undistortion 3 in and 3 out per pixel (no "
        "map); development 2 bytes in, 6 out per pixel). Kernels/call: "
        + (
            "CUDA kernels and copies in one call (torch.profiler)"
            if device.type == "cuda"
            else "PyTorch operators that compute (a dispatch-mode count: the kernels a CUDA "
            "run launches, plus the 1-4 of imageform's value checks, which run on host memory "
            "only)"
        )
        + "; projection: per chunk. Kernel ms: the device time of the call's kernels "
        "(torch.profiler, mean of three calls; streamed ops: every chunk), so kernel of copy "
        "BW is the kernels' own share (a kernel that mostly reads can pass 100 %: the copy "
        "reads and writes equal bytes; inputs smaller than the 60 MB L2 stay in it between "
        "calls); the gap to the median is the host's time per call (see "
        "profile_gpu_host.py). Queued ms: 20 calls back to back, one synchronisation, per "
        "call (a pipeline's rate: host and device overlap). vs kornia: kornia's time / this "
        "row's (above 1: faster; "
        "CIEDE2000 compiled: vs eager imageform; where kornia lacks the operation, the "
        "imageform row's ratio is over the Array-API path's time). imageform: on CUDA "
        "tensors the colour set runs imageform's fused numba-CUDA kernels (issue 29, one "
        "launch per call); imageform array-API: the same call with IMAGEFORM_DISABLE_CUDA=1.\n"
    )
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
