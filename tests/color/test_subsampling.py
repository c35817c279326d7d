"""Tests of imageform.color.subsampling: shapes, siting, exactness on ramps, Kodak cost."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color.subsampling import (
    CHROMA_SCHEMES,
    CHROMA_SITINGS,
    chroma_subsample,
    chroma_upsample,
    subsample_round_trip,
    subsampling_delta_e,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np


def _ramp_ycc(h: int = 12, w: int = 14) -> np.ndarray:
    """Y'CbCr whose chroma is an affine function of (row, column)."""
    r, c = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    y = 0.5 + 0.01 * r
    cb = 0.01 * r - 0.02 * c + 0.1
    cr = -0.015 * r + 0.01 * c
    return np.stack([y, cb, cr], axis=-1)


@pytest.mark.parametrize("scheme", list(CHROMA_SCHEMES))
@pytest.mark.parametrize("siting", list(CHROMA_SITINGS))
@pytest.mark.parametrize("shape", [(12, 14), (11, 13)])
def test_shapes(scheme: str, siting: str, shape: tuple[int, int]) -> None:
    ycc = np.random.default_rng(0).uniform(-0.5, 0.5, (*shape, 3))
    y, c = chroma_subsample(ycc, scheme, siting=siting)
    fv, fh = CHROMA_SCHEMES[scheme]
    assert y.shape == shape
    assert c.shape == (-(-shape[0] // fv), -(-shape[1] // fh), 2)
    back = chroma_upsample(y, c, scheme, siting=siting)
    assert back.shape == (*shape, 3)
    np.testing.assert_array_equal(back[..., 0], ycc[..., 0])  # luma untouched


@pytest.mark.parametrize("siting", list(CHROMA_SITINGS))
def test_affine_chroma_is_reproduced_in_the_interior(siting: str) -> None:
    """Both filters preserve affine signals and linear interpolation at the sample positions
    reproduces them: the round trip is exact away from the replicated edges."""
    ycc = _ramp_ycc()
    for scheme in ("4:2:2", "4:2:0"):
        y, c = chroma_subsample(ycc, scheme, siting=siting)
        back = chroma_upsample(y, c, scheme, siting=siting)
        np.testing.assert_allclose(back[2:-2, 2:-2], ycc[2:-2, 2:-2], atol=1e-14)


def test_siting_positions() -> None:
    """Centre siting averages 2x2 blocks (JFIF); co-sited keeps the [1,2,1]/4-filtered even
    samples (H.264 chroma_sample_loc_type 2 for top_left)."""
    ycc = np.random.default_rng(1).uniform(-0.5, 0.5, (6, 8, 3))
    _, c = chroma_subsample(ycc, "4:2:0", siting="center")
    blocks = ycc[..., 1:].reshape(3, 2, 4, 2, 2).mean(axis=(1, 3))
    np.testing.assert_allclose(c, blocks, atol=1e-15)
    _, c = chroma_subsample(ycc, "4:2:2", siting="left")
    x = ycc[..., 1:]
    xm1 = np.concatenate([x[:, :1], x[:, :-1]], axis=1)
    ref = 0.25 * xm1[:, 0::2] + 0.5 * x[:, 0::2] + 0.25 * x[:, 1::2]
    np.testing.assert_allclose(c, ref, atol=1e-15)


def test_444_is_identity_and_nearest() -> None:
    ycc = np.random.default_rng(2).uniform(-0.5, 0.5, (5, 7, 3))
    y, c = chroma_subsample(ycc, "4:4:4")
    np.testing.assert_array_equal(chroma_upsample(y, c, "4:4:4"), ycc)
    y, c = chroma_subsample(ycc, "4:2:0", siting="center")
    nn = chroma_upsample(y, c, "4:2:0", siting="center", method="nearest")
    np.testing.assert_array_equal(nn[0, 1, 1:], c[0, 0])
    np.testing.assert_array_equal(nn[1, 0, 1:], c[0, 0])


def test_round_trip_flat_and_clip() -> None:
    flat = np.full((6, 6, 3), [0.8, 0.3, 0.1])
    np.testing.assert_allclose(subsample_round_trip(flat), flat, atol=1e-12)
    edge = np.zeros((6, 6, 3))
    edge[:, 3:] = [1.0, 0.0, 0.0]
    raw = subsample_round_trip(edge)
    assert raw.min() < 0.0 or raw.max() > 1.0  # ringing outside the gamut is kept ...
    clipped = subsample_round_trip(edge, clip=True)
    assert clipped.min() >= 0.0 and clipped.max() <= 1.0  # ... unless clipping is asked for


def test_backends(xp_name: str) -> None:
    ycc = np.random.default_rng(3).uniform(-0.5, 0.5, (2, 7, 9, 3))
    y, c = chroma_subsample(ycc, "4:2:0")
    ref = chroma_upsample(y, c, "4:2:0")
    yb, cb = chroma_subsample(to_backend(ycc, xp_name), "4:2:0")
    np.testing.assert_allclose(to_np(cb), c, atol=1e-15)
    np.testing.assert_allclose(to_np(chroma_upsample(yb, cb, "4:2:0")), ref, atol=1e-15)


def test_dtype_float32() -> None:
    ycc = np.random.default_rng(4).uniform(-0.5, 0.5, (4, 4, 3)).astype(np.float32)
    y, c = chroma_subsample(ycc)
    assert c.dtype == np.float32 and chroma_upsample(y, c).dtype == np.float32


def test_kodak_420_cost(shared_data) -> None:  # type: ignore[no-untyped-def]
    """The cost of 4:2:0 (JFIF: BT.601 full range, centred chroma, bilinear upsampling) on
    kodim23, measured by this library (a regression figure, not a published one): the mean
    ΔE00 is about 0.5, well under the lecture's 'just noticeable' 2; 4:2:2 costs less."""
    from PIL import Image

    img = np.asarray(Image.open(shared_data / "kodak" / "kodim23.png"))
    d420 = subsampling_delta_e(img, "4:2:0", siting="center")
    d422 = subsampling_delta_e(img, "4:2:2", siting="center")
    assert d420.shape == img.shape[:2]
    assert 0.3 < float(d420.mean()) < 0.8
    assert float(d422.mean()) < float(d420.mean())


def test_bad_inputs() -> None:
    ycc = np.zeros((4, 4, 3))
    with pytest.raises(InvalidInputError, match="valid: '4:4:4', '4:2:2', '4:2:0'"):
        chroma_subsample(ycc, "4:1:1")
    with pytest.raises(UnknownOptionError, match="chroma siting"):
        chroma_subsample(ycc, siting="bottom")
    with pytest.raises(InvalidInputError, match="NaN"):
        chroma_subsample(np.full((4, 4, 3), np.nan))
    with pytest.raises(InvalidInputError, match="3 channels"):
        chroma_subsample(np.zeros((4, 4, 2)))
    y, c = chroma_subsample(ycc, "4:2:0")
    with pytest.raises(InvalidInputError, match=r"expected chroma of shape \(\.\.\., 2, 2, 2\)"):
        chroma_upsample(y, c[:1], "4:2:0")
    with pytest.raises(UnknownOptionError, match="bilinear"):
        chroma_upsample(y, c, method="bicubic")


def test_dask_round_trip_keeps_the_graph_small() -> None:
    """On Dask the filters run block by block: shifting whole arrays split the chunks at every
    shift (6560 tasks for 1024 x 1024 in 256-px chunks, 410 a chunk); now 632."""
    da = pytest.importorskip("dask.array")
    big = da.zeros((1024, 1024, 3), chunks=(256, 256, 3))
    for siting, method in (("left", "bilinear"), ("center", "nearest")):
        lazy = subsample_round_trip(big, "4:2:0", siting=siting, method=method)
        assert len(lazy.__dask_graph__()) < 50 * big.npartitions


@pytest.mark.parametrize("siting", list(CHROMA_SITINGS))
def test_dask_blockwise_equals_eager(siting: str) -> None:
    """The block-wise filters give the eager values bit for bit, odd sizes and chunks too."""
    da = pytest.importorskip("dask.array")
    img = np.random.default_rng(5).uniform(0, 1, (23, 29, 3))
    x = da.from_array(img, chunks=(7, 9, 3))
    for scheme, method in (("4:2:0", "bilinear"), ("4:2:2", "nearest")):
        got = subsample_round_trip(x, scheme, siting=siting, method=method)
        ref = subsample_round_trip(img, scheme, siting=siting, method=method)
        np.testing.assert_array_equal(got.compute(), ref)
