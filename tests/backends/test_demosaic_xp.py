"""The namespace-generic demosaicing path (bilinear, Malvar; shifted slices, no convolution)
equals the NumPy path (numba kernels and their NumPy twins) on PyTorch and array-api-strict."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.sensor import demosaic
from tests.helpers import to_backend, to_np

RAW = np.random.default_rng(91).uniform(0.0, 1.0, (18, 22))


@pytest.mark.parametrize("backend", ["torch", "array_api_strict"])
@pytest.mark.parametrize("method", ["bilinear", "malvar"])
@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_generic_equals_numpy(backend: str, method: str, pattern: str) -> None:
    pytest.importorskip("torch" if backend == "torch" else "array_api_strict")
    ref = demosaic(RAW, pattern, method)
    raw = to_backend(RAW, backend)
    out = demosaic(raw, pattern, method)
    assert type(out) is type(raw)
    np.testing.assert_allclose(to_np(out), ref, rtol=0, atol=1e-15)


@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_generic_float32_batch_odd_clip(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    torch = pytest.importorskip("torch")
    raw = np.random.default_rng(92).uniform(0.0, 1.0, (2, 11, 13, 1)).astype(np.float32)
    out = demosaic(torch.asarray(raw), "GRBG", method, allow_odd=True, clip=True)
    assert out.dtype == torch.float32 and tuple(out.shape) == (2, 11, 13, 3)
    np.testing.assert_allclose(
        out.numpy(), demosaic(raw, "GRBG", method, allow_odd=True, clip=True), atol=1e-6
    )
    # and against the plain NumPy twin (numba disabled)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    np.testing.assert_allclose(
        out.numpy(), demosaic(raw, "GRBG", method, allow_odd=True, clip=True), atol=1e-6
    )


def test_uint8_torch_generic() -> None:
    torch = pytest.importorskip("torch")
    raw = (RAW * 255).astype(np.uint8)
    out = demosaic(torch.asarray(raw), "RGGB", "malvar")
    assert out.dtype == torch.float32
    np.testing.assert_allclose(out.numpy(), demosaic(raw, "RGGB", "malvar"), atol=1e-6)
