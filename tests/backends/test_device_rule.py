"""The device rule of docs/design.md ("Devices"): value checks read host memory only.

On a device (``reads_values`` False) a check is skipped and bad values propagate as NaN;
tested here on CPU tensors by making :func:`imageform._backend.reads_values` answer False,
so the numbers can be read.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

import imageform._backend as backend  # noqa: E402
from imageform import color as c  # noqa: E402
from imageform import geometry as g  # noqa: E402
from imageform.errors import InvalidInputError  # noqa: E402

_MODULES = (
    "imageform._validate",
    "imageform.color.cct",
    "imageform.color.chromaticity",
    "imageform.geometry._distortion_xp",
    "imageform.geometry.undistort",
)


@pytest.fixture
def on_device(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every PyTorch tensor treated as device memory (values not read by checks)."""
    import importlib

    def reads(x: object) -> bool:
        return not isinstance(x, torch.Tensor)

    for name in _MODULES:
        monkeypatch.setattr(importlib.import_module(name), "reads_values", reads)


def test_reads_values_table(monkeypatch: pytest.MonkeyPatch) -> None:
    import array_api_strict

    monkeypatch.delenv("IMAGEFORM_DEVICE_CHECKS", raising=False)
    assert backend.reads_values(np.zeros(2))
    assert backend.reads_values([1.0, 2.0])
    assert backend.reads_values(array_api_strict.asarray([1.0]))
    assert backend.reads_values(torch.zeros(2))
    assert not backend.reads_values(torch.zeros(2, device="meta"))
    monkeypatch.setenv("IMAGEFORM_DEVICE_CHECKS", "1")
    assert backend.reads_values(torch.zeros(2, device="meta"))


def test_host_tensors_are_still_checked() -> None:
    x = torch.full((2, 2, 3), 0.5, dtype=torch.float64)
    x[1, 1, 2] = math.nan
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        c.convert(x, "srgb", "lab")


@pytest.mark.usefixtures("on_device")
def test_nan_propagates_instead_of_an_error() -> None:
    x = torch.full((2, 2, 3), 0.5, dtype=torch.float64)
    x[1, 1, 2] = math.nan
    lab = c.convert(x, "srgb", "lab")
    assert torch.isnan(lab[1, 1]).all() and torch.isfinite(lab[0]).all()
    pts = torch.tensor([[0.1, 0.2, 3.0], [math.inf, 0.0, 2.0]], dtype=torch.float64)
    uv = g.project_points(pts, np.diag([500.0, 500.0, 1.0])).uv
    assert torch.isfinite(uv[0]).all() and not torch.isfinite(uv[1]).all()


@pytest.mark.usefixtures("on_device")
def test_cct_out_of_range_is_nan_on_a_device() -> None:
    xy = c.cct_to_xy(torch.tensor([1000.0, 6504.0], dtype=torch.float64))
    assert torch.isnan(xy[0]).all() and torch.isfinite(xy[1]).all()
    day = c.cct_to_xy(torch.tensor([3000.0, 6504.0], dtype=torch.float64), method="daylight")
    assert torch.isnan(day[0]).all() and torch.isfinite(day[1]).all()
    cct, duv = c.xy_to_cct(torch.tensor([[0.7, 0.29], [0.31271, 0.32902]], dtype=torch.float64))
    assert math.isnan(float(cct[0])) and math.isnan(float(duv[0]))
    assert abs(float(cct[1]) - 6503.6) < 1.0


@pytest.mark.usefixtures("on_device")
def test_newton_inverse_runs_a_fixed_count_with_the_same_numbers() -> None:
    bc = g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01)
    xy = np.random.default_rng(3).uniform(-0.4, 0.4, (50, 2))
    ref = bc.undistort(bc.distort(xy))
    out = bc.undistort(torch.asarray(bc.distort(xy)))
    np.testing.assert_allclose(out.xy.numpy(), ref.xy, rtol=0, atol=1e-12)
    assert bool(out.valid.all())


@pytest.mark.usefixtures("on_device")
def test_explicit_check_reads_on_a_device() -> None:
    with pytest.raises(InvalidInputError, match="outside the spectral locus"):
        c.check_in_locus(torch.tensor([[0.7, 0.7]], dtype=torch.float64))
    # the implicit check of xy_to_xyz is not read on a device
    out = c.xy_to_xyz(torch.tensor([[0.7, 0.7]], dtype=torch.float64))
    assert tuple(out.shape) == (1, 3)


def test_cached_constants_survive_inference_mode() -> None:
    # the first call under inference_mode fills the constant cache; a later call with
    # gradients must still work (an inference tensor cannot be saved for backward)
    import imageform._backend as b

    b._CONSTANTS.clear()
    with torch.inference_mode():
        c.convert(torch.rand(2, 2, 3, dtype=torch.float64), "srgb", "lab")
    x = torch.rand(2, 2, 3, dtype=torch.float64, requires_grad=True)
    c.convert(x, "srgb", "lab").sum().backward()
    assert x.grad is not None and torch.isfinite(x.grad).all()


def test_constants_are_uploaded_once() -> None:
    import imageform._backend as b

    x = torch.rand(2, 2, 3, dtype=torch.float32)
    c.convert(x, "srgb", "lab")
    n = len(b._CONSTANTS)
    c.convert(x, "srgb", "lab")
    assert len(b._CONSTANTS) == n > 0


@pytest.mark.parametrize("value", [0.0, [1.0, 2.0, 3.0], np.eye(3)], ids=["0-d", "1-d", "2-d"])
def test_small_host_arrays_upload_once_and_keep_their_shape(value: object) -> None:
    """A small host matrix given with device data (K, R, t, a skew of 0.0) is uploaded once.

    The cache behind ``asarray_like`` for CUDA/CuPy targets (a pageable host-to-device copy
    per call synchronises the stream: seen on a lent H200); checked here through its upload
    function, which a CPU can run. A 0-d value stays 0-d (``intrinsic_matrix``'s skew).
    """
    import imageform._backend as b

    host = np.asarray(value, dtype=np.float64)
    first = b.upload_cached(host, torch, torch.float32, torch.device("cpu"))
    again = b.upload_cached(host.copy(), torch, torch.float32, torch.device("cpu"))
    assert again is first
    assert tuple(first.shape) == host.shape and first.dtype == torch.float32
    np.testing.assert_array_equal(first.numpy(), host.astype(np.float32))
    # a CPU or meta target is not cached: no copy to save
    assert b._cached_host(host, torch, None, torch.device("meta")) is None
