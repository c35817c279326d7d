"""Dask: lazy chunk-wise colour conversions, demosaicing and undistortion with overlap,
white balance from real reductions; the same numbers as the in-memory path (issue 9).

Laziness is checked by counting dask computations with a scheduler callback: the calls
build graphs and compute nothing; ``.compute()`` then gives the in-memory numbers.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from imageform import color as c
from imageform import geometry as g
from imageform.errors import DegenerateConfigurationError
from imageform.sensor import demosaic

da = pytest.importorskip("dask.array")
from dask.callbacks import Callback  # noqa: E402

RNG = np.random.default_rng(90)
IMG = RNG.uniform(0.02, 0.98, (48, 60, 3))
RAW = RNG.uniform(0.0, 1.0, (50, 62))


class _Counter(Callback):  # type: ignore[misc]
    def __init__(self) -> None:
        super().__init__()
        self.n = 0

    def _start(self, dsk: object) -> None:
        self.n += 1


@contextmanager
def no_compute() -> Iterator[None]:
    """Fail if anything is computed inside the block."""
    with _Counter() as cb:
        yield
    assert cb.n == 0, f"{cb.n} dask computation(s) during a lazy call"


def test_counter_sees_a_compute() -> None:
    with _Counter() as cb:
        da.ones(4, chunks=2).sum().compute()
    assert cb.n == 1


@pytest.mark.parametrize(
    "fn",
    [
        lambda x: c.convert(x, "srgb", "lab"),
        lambda x: c.convert(x, "srgb", "hsv"),
        c.srgb_to_linear,
        lambda x: c.xyz_to_lab(c.linear_srgb_to_xyz(c.srgb_to_linear(x))),
        lambda x: c.delta_e_ciede2000(
            c.convert(x, "srgb", "lab"), c.convert(x[..., ::-1], "srgb", "lab")
        ),
    ],
    ids=["srgb_lab", "srgb_hsv", "srgb_to_linear", "chain", "ciede2000"],
)
def test_pointwise_is_lazy_one_task_per_chunk(fn: object) -> None:
    x = da.from_array(IMG, chunks=(16, 20, 3))
    with no_compute():
        y = fn(x)  # type: ignore[operator]
    assert isinstance(y, da.Array)
    assert y.chunks[:2] == x.chunks[:2]
    # the function's own layer holds one task per output chunk
    assert len(y.dask.layers[y.name]) == y.npartitions == 9
    np.testing.assert_allclose(y.compute(), fn(IMG), rtol=1e-12, atol=1e-12)  # type: ignore[operator]


def test_pointwise_validates_values_at_compute() -> None:
    bad = IMG.copy()
    bad[40, 50, 1] = np.nan
    y = c.convert(da.from_array(bad, chunks=(16, 20, 3)), "srgb", "lab")  # lazy: no error
    with pytest.raises(ValueError, match="NaN"):
        y.compute()


@pytest.mark.parametrize("method", ["bilinear", "malvar", "hamilton_adams", "menon"])
@pytest.mark.parametrize("pattern", ["RGGB", "GBRG"])
def test_demosaic_overlap_equals_in_memory(method: str, pattern: str) -> None:
    # odd chunk sizes on purpose: demosaic makes them even, keeping the CFA phase per block
    raw = da.from_array(RAW, chunks=(13, 17))
    with no_compute():
        rgb = demosaic(raw, pattern, method)
    assert isinstance(rgb, da.Array) and rgb.shape == (*RAW.shape, 3)
    assert all(ch % 2 == 0 for ch in rgb.chunks[0][:-1] + rgb.chunks[1][:-1])
    np.testing.assert_array_equal(rgb.compute(), demosaic(RAW, pattern, method))


def test_demosaic_dask_batch_and_uint16() -> None:
    raw = (RNG.uniform(0, 1, (2, 20, 24, 1)) * 65535).astype(np.uint16)
    out = demosaic(da.from_array(raw, chunks=(1, 10, 12, 1)), "BGGR", "malvar")
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out.compute(), demosaic(raw, "BGGR", "malvar"))


@pytest.mark.parametrize(
    "model",
    [g.BrownConrady(k1=-0.25, k2=0.05, p1=1e-3), g.KannalaBrandt(k1=0.1), None],
    ids=["brown_conrady", "kannala_brandt", "none"],
)
def test_undistort_blockwise_equals_in_memory(model: object) -> None:
    K = np.array([[40.0, 0.0, 29.5], [0.0, 40.0, 23.5], [0.0, 0.0, 1.0]])
    x = da.from_array(IMG, chunks=(16, 20, 3))
    with no_compute():
        out = g.undistort_image(x, K, model)
    assert isinstance(out, da.Array) and out.chunks == x.chunks
    np.testing.assert_allclose(out.compute(), g.undistort_image(IMG, K, model), atol=1e-12)
    # a new camera matrix and output size: still block-wise, still equal
    Kn = K * [[0.8], [0.8], [1.0]]
    out2 = g.undistort_image(x, K, model, new_K=Kn, out_shape=(40, 50), fill=0.5)
    ref2 = g.undistort_image(IMG, K, model, new_K=Kn, out_shape=(40, 50), fill=0.5)
    np.testing.assert_allclose(out2.compute(), ref2, atol=1e-12)


def test_remap_bilinear_dask() -> None:
    K = np.array([[40.0, 0.0, 29.5], [0.0, 40.0, 23.5], [0.0, 0.0, 1.0]])
    m = g.undistortion_map((48, 60), K, g.BrownConrady(k1=0.2))
    out = g.remap_bilinear(da.from_array(IMG[..., 0], chunks=(16, 30)), m, fill=-1.0)
    np.testing.assert_allclose(out.compute(), g.remap_bilinear(IMG[..., 0], m, fill=-1.0))


@pytest.mark.parametrize(
    "method, kw",
    [
        ("gray_world", {}),
        ("shades_of_gray", {"p": 6.0}),
        ("white_patch", {}),
        ("white_patch", {"percentile": 97.3}),
        ("max_rgb", {}),
    ],
)
def test_white_balance_reductions(method: str, kw: dict[str, float]) -> None:
    x = da.from_array(IMG * [1.0, 0.8, 0.6], chunks=(16, 20, 3))
    with no_compute():
        out, gains = c.white_balance(x, method, **kw)
    assert isinstance(out, da.Array) and isinstance(gains, da.Array)
    assert out.chunks == x.chunks
    layers = " ".join(gains.dask.layers)
    assert any(r in layers for r in ("mean", "topk")), layers  # a dask reduction, not numpy
    ref_out, ref_gains = c.white_balance(IMG * [1.0, 0.8, 0.6], method, **kw)
    np.testing.assert_allclose(gains.compute(), ref_gains, rtol=1e-12)
    np.testing.assert_allclose(out.compute(), ref_out, rtol=1e-12, atol=1e-14)


def test_white_balance_zero_channel_raises_at_compute() -> None:
    x = da.from_array(IMG * [1.0, 1.0, 0.0], chunks=(16, 20, 3))
    out, _ = c.white_balance(x)
    with pytest.raises(DegenerateConfigurationError, match="zero"):
        out.compute()


@pytest.mark.parametrize(
    "model",
    [g.BrownConrady(k1=-0.2, p1=1e-3), g.KannalaBrandt(k1=0.05), g.DivisionModel(k1=-0.1)],
    ids=["brown_conrady", "kannala_brandt", "division"],
)
def test_distortion_models_lazy_chunkwise(model: object) -> None:
    pts = RNG.uniform(-0.5, 0.5, (1000, 2))
    x = da.from_array(pts, chunks=(250, 2))
    with no_compute():
        d = model.distort(x)  # type: ignore[attr-defined]
        u, ok = model.undistort(d)  # type: ignore[attr-defined]
    assert d.npartitions == u.npartitions == ok.npartitions == 4
    np.testing.assert_allclose(d.compute(), model.distort(pts), atol=1e-13)  # type: ignore[attr-defined]
    ref_u, ref_ok = model.undistort(model.distort(pts))  # type: ignore[attr-defined]
    np.testing.assert_allclose(u.compute(), ref_u, atol=1e-13)
    np.testing.assert_array_equal(ok.compute(), ref_ok)
