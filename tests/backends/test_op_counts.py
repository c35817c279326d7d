"""Operators per call on a device (issue 29): pinned, so that they can only go down.

Each call runs on PyTorch ``meta`` tensors (the device path: no value checks, constants
on the device) under :class:`~tests.backends._dispatch.DeviceGuard`, which counts the
operators that compute; on CUDA each is a kernel launch. :data:`PINS` holds the count per
call; a change that adds operators fails here, one that removes some must lower its pin
(the message says to what). ``benchmarks/bench_gpu.py`` reports the same counts measured
on a GPU.

A fused path (``torch.compile``, see ``test_compile_fullgraph``) runs one or a few kernels;
these counts are the eager path's.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from imageform import color as c  # noqa: E402
from imageform import geometry as g  # noqa: E402
from imageform.sensor import demosaic  # noqa: E402
from tests.backends._dispatch import DeviceGuard  # noqa: E402

K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
BC = g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01)
BC_RADIAL = g.BrownConrady(k1=-0.2, k2=0.05)
KS = np.array([[8.0, 0.0, 3.5], [0.0, 8.0, 3.5], [0.0, 0.0, 1.0]])


def _m(*shape: int) -> Any:
    return torch.empty(shape, dtype=torch.float32, device="meta")


#: name -> (call, operators per call).
CALLS: dict[str, tuple[Callable[[], Any], int]] = {
    "convert srgb->lab": (lambda: c.convert(_m(64, 64, 3), "srgb", "lab"), 22),
    "convert lab->srgb": (lambda: c.convert(_m(64, 64, 3), "lab", "srgb"), 22),
    "convert srgb->xyz": (lambda: c.convert(_m(64, 64, 3), "srgb", "xyz"), 8),
    "convert srgb->hsv": (lambda: c.convert(_m(64, 64, 3), "srgb", "hsv"), 33),
    "convert srgb->ycbcr": (lambda: c.convert(_m(64, 64, 3), "srgb", "ycbcr"), 16),
    "srgb_to_linear": (lambda: c.srgb_to_linear(_m(64, 64, 3)), 7),
    "linear_to_srgb": (lambda: c.linear_to_srgb(_m(64, 64, 3)), 7),
    "delta_e_cie76": (lambda: c.delta_e_cie76(_m(64, 64, 3), _m(64, 64, 3)), 4),
    "delta_e_cie94": (lambda: c.delta_e_cie94(_m(64, 64, 3), _m(64, 64, 3)), 45),
    "delta_e_ciede2000": (lambda: c.delta_e_ciede2000(_m(64, 64, 3), _m(64, 64, 3)), 181),
    "delta_e_cmc": (lambda: c.delta_e_cmc(_m(64, 64, 3), _m(64, 64, 3)), 81),
    "chromatic_adaptation": (lambda: c.chromatic_adaptation(_m(64, 64, 3), "D65", "D50"), 2),
    "white_balance": (lambda: c.white_balance(_m(64, 64, 3)).image, 20),
    "project_points": (lambda: g.project_points(_m(1000, 3), K).uv, 24),
    "project_points_distorted": (
        lambda: g.project_points_distorted(_m(1000, 3), K, np.eye(3), np.zeros(3), BC)[0],
        52,
    ),
    "BrownConrady.distort": (lambda: BC.distort(_m(1000, 2)), 30),
    "BrownConrady.undistort": (lambda: BC.undistort(_m(1000, 2)).xy, 1672),
    "BrownConrady.undistort[radial]": (lambda: BC_RADIAL.undistort(_m(1000, 2)).xy, 979),
    "demosaic bilinear": (lambda: demosaic(_m(64, 64), "RGGB", "bilinear"), 31),
    "demosaic malvar": (lambda: demosaic(_m(64, 64), "RGGB", "malvar"), 56),
    "undistort_image": (lambda: g.undistort_image(_m(8, 8, 3), KS, BC), 113),
}


def count(call: Callable[[], Any]) -> int:
    """Operators that compute in one call (the second: caches warm)."""
    call()
    with DeviceGuard() as guard:
        call()
    return guard.kernels


@pytest.mark.parametrize("name", list(CALLS))
def test_operator_count_is_pinned(name: str) -> None:
    call, pin = CALLS[name]
    n = count(call)
    assert n <= pin, f"{name}: {n} operators per call, more than the {pin} pinned"
    assert n == pin, f"{name}: {n} operators per call, fewer than pinned: lower the pin to {n}"


@pytest.mark.slow
def test_compile_fullgraph() -> None:
    """``convert`` sRGB -> Lab compiles as one graph (no graph break: no host read-back)."""
    import shutil

    if not (shutil.which("g++") or shutil.which("c++") or shutil.which("clang++")):
        pytest.skip("no C++ compiler: inductor cannot build CPU kernels here")
    x = torch.rand(16, 16, 3, generator=torch.Generator().manual_seed(2))
    fn = torch.compile(lambda v: c.convert(v, "srgb", "lab"), fullgraph=True)
    np.testing.assert_allclose(
        fn(x).numpy(), c.convert(x.numpy(), "srgb", "lab"), rtol=0, atol=2e-3
    )
