"""Every numba kernel above its size threshold against the code it replaces (issue 30).

Each public function below dispatches NumPy input of at least a threshold size to a numba
kernel; ``IMAGEFORM_DISABLE_NUMBA=1`` makes the same call run the NumPy/Array-API path. The
two must agree on inputs that exercise every parameter the kernel reads (skew, a principal
point off centre, a rotation and translation, every distortion coefficient, both Bayer
phases, non-neutral whites), so that a kernel dropping a term (the mutation that removed
skew from the distortion kernel was caught by one twin test only) fails here by name.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform import color as c
from imageform import geometry as g
from imageform.sensor import demosaic

RNG = np.random.default_rng(30)
# a camera that uses every entry of K: skew, off-centre principal point, fx != fy
K = np.array([[812.0, 3.5, 331.0], [0.0, 797.0, 247.0], [0.0, 0.0, 1.0]])
R = np.asarray(g.camera_rotation(5.0, yaw=-10.0, roll=3.0))
T = np.array([0.05, -0.1, 0.3])
BC = g.BrownConrady(k1=-0.21, k2=0.05, p1=1.2e-3, p2=-8e-4, k3=-0.01, k4=0.002, k5=0.001, k6=5e-4)
KB = g.KannalaBrandt(k1=-0.01, k2=0.003, k3=-0.001, k4=2e-4)
N = 30_000  # above every point kernel's threshold (projection 20 000, distortion 2 x 4096)
PTS = np.column_stack([RNG.uniform(-1, 1, N), RNG.uniform(-0.8, 0.8, N), RNG.uniform(2, 6, N)])
XY = RNG.uniform(-0.6, 0.6, (N, 2))
IMG = RNG.uniform(0.0, 1.0, (96, 128, 3))  # 12 288 pixels: above convert's 4096
LAB1 = c.convert(IMG, "srgb", "lab")
LAB2 = c.convert(np.clip(IMG + RNG.normal(0, 0.05, IMG.shape), 0, 1), "srgb", "lab")
MOSAIC = RNG.uniform(0.0, 1.0, (96, 128))


def _first(x: Any) -> Any:
    return x[0] if isinstance(x, tuple) else x


CALLS: dict[str, tuple[Callable[[], Any], float]] = {
    "project_points": (lambda: g.project_points(PTS, K, R, T).uv, 1e-9),
    "project_points_distorted[brown_conrady]": (
        lambda: _first(g.project_points_distorted(PTS, K, R, T, BC)),
        1e-8,
    ),
    "project_points_distorted[kannala_brandt]": (
        lambda: _first(g.project_points_distorted(PTS, K, R, T, KB)),
        1e-8,
    ),
    "BrownConrady.distort": (lambda: BC.distort(XY), 1e-12),
    "BrownConrady.undistort": (lambda: BC.undistort(XY).xy, 1e-9),
    "KannalaBrandt.distort": (lambda: KB.distort(XY), 1e-12),
    "KannalaBrandt.undistort": (lambda: KB.undistort(XY).xy, 1e-9),
    "convert[srgb->lab]": (lambda: c.convert(IMG, "srgb", "lab"), 1e-9),
    "convert[srgb->lab, D50]": (lambda: c.convert(IMG, "srgb", "lab", white="D50"), 1e-9),
    "convert[lab->srgb]": (lambda: c.convert(LAB1, "lab", "srgb"), 1e-9),
    "convert[srgb->hsv]": (lambda: c.convert(IMG, "srgb", "hsv"), 1e-9),
    "convert[srgb->ycbcr]": (lambda: c.convert(IMG, "srgb", "ycbcr"), 1e-9),
    "convert[float32 srgb->lab]": (lambda: c.convert(IMG.astype(np.float32), "srgb", "lab"), 2e-3),
    **{
        f"delta_e[{m}]": ((lambda m=m: c.delta_e(LAB1, LAB2, m)), 1e-9)
        for m in ("cie76", "cie94", "cmc", "ciede2000")
    },
    **{
        f"demosaic[{m}-{p}]": ((lambda m=m, p=p: demosaic(MOSAIC, p, m)), 1e-9)
        for m in ("bilinear", "malvar")
        for p in ("RGGB", "GBRG")
    },
    "undistort_image[brown_conrady]": (lambda: g.undistort_image(IMG, K, BC), 1e-9),
}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_kernel_equals_the_path_it_replaces(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    fn, atol = CALLS[name]
    fast = np.asarray(fn())
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    slow = np.asarray(fn())
    assert fast.shape == slow.shape and fast.dtype == slow.dtype
    np.testing.assert_allclose(
        fast, slow, atol=atol, rtol=1e-7 if atol < 1e-3 else 1e-4, equal_nan=True, err_msg=name
    )


def test_the_switch_really_switches(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform._backend import use_numba

    assert use_numba(PTS)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    assert not use_numba(PTS)
