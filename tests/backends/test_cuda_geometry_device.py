"""The geometry and demosaicing CUDA kernels on a real GPU (issue 29): skipped where there is none.

For each public function that dispatches to :mod:`imageform._cuda.geometry` or
:mod:`imageform._cuda.demosaic`, on PyTorch CUDA tensors of both dtypes, after one warm-up
call (the kernel compiled, constants uploaded): the call launches one kernel
(:func:`imageform._cuda._launch.launch_count`), runs under
``torch.cuda.set_sync_debug_mode("error")`` (no host synchronisation), returns CUDA tensors,
and gives the NumPy path's numbers. ``develop(device="cuda")`` gives the CPU pass's output.
The simulator half, which CI runs, is ``test_cuda_geometry_kernels.py``.

Run on a lent GPU:
``PYTHONPATH=src python -m pytest -q -n 0 tests/backends/test_cuda_geometry_device.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from tests.backends._gpu import torch_with_cuda

torch = torch_with_cuda()

from imageform._cuda import _launch  # noqa: E402
from imageform.geometry import (  # noqa: E402
    BrownConrady,
    project_points,
    project_points_distorted,
    remap_bilinear,
    undistort_image,
)
from imageform.sensor import demosaic  # noqa: E402

RNG = np.random.default_rng(29)
BC = BrownConrady(k1=-0.21, k2=0.05, p1=0.002, p2=-0.001, k3=-0.01, k4=0.02, k5=0.001)
K = np.array([[500.0, 0.3, 320.0], [0.0, 480.0, 240.0], [0.0, 0.0, 1.0]])
R = np.eye(3)
T = np.array([0.1, -0.2, 0.5])
PTS = np.concatenate([RNG.uniform(-1.5, 1.5, (5000, 2)), RNG.uniform(-1, 4, (5000, 1))], 1)
XY = RNG.uniform(-0.6, 0.6, (5000, 2))
IMG = RNG.uniform(0.0, 1.0, (2, 96, 128, 3))
MAP = np.stack(np.meshgrid(np.arange(120.0), np.arange(90.0)), -1) * 1.05 - 2.0
RAW = RNG.uniform(0.0, 1.0, (96, 128))
KS = np.array([[110.0, 0.0, 63.0], [0.0, 108.0, 47.0], [0.0, 0.0, 1.0]])

CALLS: list[tuple[str, Callable[..., Any], tuple[Any, ...]]] = [
    ("distort", BC.distort, (XY,)),
    ("undistort", lambda xy: tuple(BC.undistort(xy)), (np.asarray(BC.distort(XY)),)),
    ("project_points", lambda p, k, r, t: tuple(project_points(p, k, r, t)), (PTS, K, R, T)),
    (
        "project_points_distorted",
        lambda p, k, r, t: tuple(project_points_distorted(p, k, r, t, BC)),
        (PTS, K, R, T),
    ),
    ("remap_bilinear", remap_bilinear, (IMG, MAP)),
    ("undistort_image", lambda im: undistort_image(im, KS, BC), (IMG[0],)),
    ("demosaic bilinear", lambda r: demosaic(r, "GRBG", "bilinear"), (RAW,)),
    ("demosaic malvar", lambda r: demosaic(r, "RGGB", "malvar", clip=True), (RAW,)),
]


def _host(x: Any) -> Any:
    if isinstance(x, tuple):
        return tuple(_host(v) for v in x)
    return x.detach().cpu().numpy() if isinstance(x, torch.Tensor) else np.asarray(x)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize(("fn", "args"), [c[1:] for c in CALLS], ids=[c[0] for c in CALLS])
def test_one_kernel_no_sync_same_numbers(
    fn: Callable[..., Any], args: tuple[Any, ...], dtype: str
) -> None:
    host = [np.asarray(a, dtype=dtype) for a in args]
    ref = _host(fn(*host))
    xs = [torch.asarray(a, device="cuda") for a in host]
    fn(*xs)  # warm-up: the kernel compiled, the constants uploaded
    torch.cuda.synchronize()
    before = _launch.launch_count()
    torch.cuda.set_sync_debug_mode("error")
    try:
        out = fn(*xs)
    finally:
        torch.cuda.set_sync_debug_mode("default")
    assert _launch.launch_count() - before == 1
    outs = out if isinstance(out, tuple) else (out,)
    assert all(isinstance(o, torch.Tensor) and o.device.type == "cuda" for o in outs)
    got = _host(out)
    refs, gots = (ref, got) if isinstance(ref, tuple) else ((ref,), (got,))
    for g, r in zip(gots, refs, strict=True):
        assert g.dtype == r.dtype and g.shape == r.shape
        if r.dtype == np.bool_:
            assert np.array_equal(g, r)
        else:
            atol = 1e-3 if dtype == "float32" else 1e-9  # pixels; unit-range values: 1e-5
            np.testing.assert_allclose(g, r, atol=atol, rtol=1e-5, equal_nan=True)


def test_develop_on_the_gpu() -> None:
    from imageform.io import RawImage, develop

    raw = RawImage(
        mosaic=RNG.integers(40, 4200, size=(64, 96)).astype(np.uint16),
        black_level=np.array([[60.0, 64.0], [66.0, 70.0]]),
        white_level=4095.0,
        cfa_pattern="GBRG",
        white_balance=np.array([1.9, 1.0, 1.6]),
        xyz_to_camera=np.array([[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]]),
        camera_to_srgb=np.eye(3),
        calibration_illuminant="D65",
    )
    for method in ("bilinear", "malvar"):
        cpu = develop(raw, demosaic=method)
        gpu = develop(raw, demosaic=method, device="cuda")
        # float32 in the same order; the GPU may fuse multiply-adds (a few ulp)
        np.testing.assert_allclose(gpu.image, cpu.image, atol=1e-5, rtol=0)
        assert np.abs(gpu.to_integer(16).astype(int) - cpu.to_integer(16)).max() <= 1


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_demosaic_quads_every_pattern_and_edge(method: str, dtype: str) -> None:
    """The quad kernels on the device's blocks (32 x 8 quads: a warp a row, its barrier).

    Every CFA pattern, a batch of two, odd sizes (a cut quad in the last row and column),
    mosaics whose blocks are all edge blocks (70 x 90) and with inner blocks (131 x 261:
    inner from the second block row and column on), clipped and not: the NumPy path's
    numbers (the same sums; the GPU may fuse a multiply-add: a few ulp).
    """
    rng = np.random.default_rng(2929)
    atol = 2e-6 if dtype == "float32" else 1e-14
    for pattern in ("RGGB", "GRBG", "GBRG", "BGGR"):
        for shape in ((2, 70, 90, 1), (131, 261)):
            raw = rng.uniform(-0.05, 1.05, shape).astype(dtype)
            x = torch.asarray(raw, device="cuda")
            for clip in (False, True):
                ref = np.asarray(demosaic(raw, pattern, method, clip=clip, allow_odd=True))
                before = _launch.launch_count()
                got = demosaic(x, pattern, method, clip=clip, allow_odd=True)
                assert _launch.launch_count() - before == 1
                np.testing.assert_allclose(
                    _host(got), ref, atol=atol, rtol=0, err_msg=f"{pattern} {shape} {clip}"
                )
