"""Demosaicing (imageform.sensor.demosaic) and its numba kernels."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform._kernels import (
    demosaic_bilinear,
    demosaic_hamilton_adams,
    demosaic_malvar,
    demosaic_menon,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor import CFA_PATTERNS, DEMOSAIC_METHODS, cfa_masks, demosaic, mosaic
from tests.helpers import to_backend, to_np

KERNELS = {
    "bilinear": (demosaic_bilinear.bilinear_numba, demosaic_bilinear.bilinear_numpy),
    "malvar": (demosaic_malvar.malvar_numba, demosaic_malvar.malvar_numpy),
    "hamilton_adams": (
        demosaic_hamilton_adams.hamilton_adams_numba,
        demosaic_hamilton_adams.hamilton_adams_numpy,
    ),
    "menon": (demosaic_menon.menon_numba, demosaic_menon.menon_numpy),
    "menon_soft": (demosaic_menon.menon_soft_numba, demosaic_menon.menon_soft_numpy),
}
EDGE_DIRECTED = ("hamilton_adams", "menon", "menon_soft")


def smooth_image(h: int = 24, w: int = 32) -> np.ndarray:
    """A smooth colour image in [0.2, 0.8]."""
    yy, xx = np.mgrid[0:h, 0:w] / 8.0
    return np.stack(
        [
            0.5 + 0.3 * np.sin(yy * 0.7 + xx * 0.4),
            0.5 + 0.3 * np.sin(yy * 0.5 - xx * 0.6 + 1),
            0.5 + 0.3 * np.cos(yy * 0.3 + xx * 0.8),
        ],
        axis=-1,
    )


# ---- kernels against their NumPy twins ------------------------------------------------


@pytest.mark.parametrize("method", list(KERNELS))
@pytest.mark.parametrize(
    ("oy", "ox", "h", "w"), [(12, 12, 16, 20), (13, 12, 15, 20), (12, 13, 16, 19), (13, 13, 17, 21)]
)
def test_kernel_matches_twin_float64(method: str, oy: int, ox: int, h: int, w: int) -> None:
    """The numba kernel agrees with its NumPy twin to 1e-12 (float64; summation order)."""
    rng = np.random.default_rng(oy * 100 + ox)
    P = rng.random((h + 2 * 12 + 1, w + 2 * 12 + 1))
    fast, twin = KERNELS[method]
    np.testing.assert_allclose(fast(P, oy, ox, h, w), twin(P, oy, ox, h, w), rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", list(KERNELS))
def test_kernel_matches_twin_float32(method: str) -> None:
    """float32: kernel and twin round differently; agreement to 2e-6 (a few ulp of 1)."""
    rng = np.random.default_rng(7)
    P = rng.random((48, 56)).astype(np.float32)
    fast, twin = KERNELS[method]
    a, b = fast(P, 12, 12, 24, 32), twin(P, 12, 12, 24, 32)
    assert a.dtype == b.dtype == np.float32
    # float32 ties in the edge-directed decisions may flip; allow a few such pixels
    bad = np.abs(a - b) > 2e-6
    assert bad.mean() < 0.01


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
def test_numba_and_numpy_paths_agree(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    img = smooth_image(20, 26)
    raw = mosaic(img, "GBRG")
    fast = demosaic(raw, "GBRG", method)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    slow = demosaic(raw, "GBRG", method)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-12)


# ---- gold values and invariants ---------------------------------------------------------


def test_malvar_filter_taps_from_the_paper() -> None:
    """Malvar, He, Cutler (ICASSP 2004) fig. 2: the impulse response shows the filter taps."""
    raw = np.zeros((16, 16))
    raw[8, 8] = 1.0  # a red site of RGGB
    out = demosaic(raw, "RGGB", "malvar")
    assert out[8, 8, 1] == 4 / 8  # G at R: centre 4
    assert out[8, 10, 1] == -1 / 8  # G at R, 2 pixels away: -1
    assert out[8, 9, 0] == 4 / 8  # R at G in a red row, horizontal neighbour: 4
    assert out[9, 8, 0] == 4 / 8  # R at G in a blue row, vertical neighbour: 4
    assert out[9, 9, 0] == 2 / 8  # R at B, diagonal: 2
    assert out[10, 10, 2] == 0.0  # B at R, diagonal 2 away: no tap
    assert out[8, 8, 2] == 6 / 8  # B at R: centre 6
    assert out[10, 8, 2] == -1.5 / 8  # B at R, 2 pixels away: -3/2


def test_bilinear_taps() -> None:
    raw = np.zeros((8, 8))
    raw[4, 4] = 1.0
    out = demosaic(raw, "RGGB", "bilinear")
    assert out[4, 5, 0] == 0.5 and out[5, 5, 0] == 0.25 and out[5, 4, 0] == 0.5
    assert out[4, 4, 1] == 0.0


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
@pytest.mark.parametrize("pattern", CFA_PATTERNS)
def test_measured_samples_are_kept(method: str, pattern: str) -> None:
    rng = np.random.default_rng(8)
    img = rng.random((10, 14, 3))
    out = demosaic(mosaic(img, pattern), pattern, method)
    m = cfa_masks((10, 14), pattern)
    np.testing.assert_allclose(out[m], img[m], rtol=0, atol=1e-12)


@settings(max_examples=20, deadline=None)
@given(
    value=st.floats(0.0, 1.0),
    method=st.sampled_from(DEMOSAIC_METHODS),
    pattern=st.sampled_from(CFA_PATTERNS),
    h=st.integers(2, 9),
    w=st.integers(2, 9),
)
def test_flat_field_stays_flat(value: float, method: str, pattern: str, h: int, w: int) -> None:
    out = demosaic(np.full((h, w), value), pattern, method, allow_odd=True)
    np.testing.assert_allclose(out, value, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", EDGE_DIRECTED)
@pytest.mark.parametrize("axis", [0, 1])
def test_edge_directed_methods_keep_grey_step_edges(method: str, axis: int) -> None:
    """Grey vertical/horizontal step edges are reconstructed exactly by interpolating
    along the edge (bilinear and Malvar blur them)."""
    img = np.full((16, 18, 3), 0.2)
    if axis == 1:
        img[:, 9:] = 0.7
    else:
        img[7:] = 0.7
    out = demosaic(mosaic(img, "RGGB"), "RGGB", method)
    np.testing.assert_allclose(out, img, rtol=0, atol=1e-12)
    blurred = demosaic(mosaic(img, "RGGB"), "RGGB", "bilinear")
    assert np.abs(blurred - img).max() > 0.1


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
@pytest.mark.parametrize("pattern", ["GRBG", "GBRG", "BGGR"])
def test_pattern_phase(method: str, pattern: str) -> None:
    """An RGGB image shifted by one row/column is GRBG/GBRG/BGGR: away from the borders the
    reconstruction must not depend on where the crop started."""
    img = smooth_image(40, 44) ** 2
    dy, dx = {"GRBG": (0, 1), "GBRG": (1, 0), "BGGR": (1, 1)}[pattern]
    ref = demosaic(mosaic(img, "RGGB"), "RGGB", method)[dy:, dx:]
    got = demosaic(mosaic(img[dy:, dx:], pattern), pattern, method, allow_odd=True)
    r = 12
    np.testing.assert_allclose(got[r:-r, r:-r], ref[r:-r, r:-r], rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
def test_smooth_image_error_is_small(method: str) -> None:
    """RMS error on a smooth image, limits 1.5x the values measured when written."""
    img = smooth_image(48, 64)
    out = demosaic(mosaic(img, "RGGB"), "RGGB", method)
    rms = float(np.sqrt(((out - img)[4:-4, 4:-4] ** 2).mean()))
    limit = {"bilinear": 0.00065, "malvar": 0.0013, "hamilton_adams": 0.0015}.get(method, 0.0029)
    assert rms < 1.5 * limit


@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
def test_borders_not_much_worse_than_with_context(method: str, shared_data: Path) -> None:
    """The phase-preserving mirror: border pixels of a crop (4-pixel band) are reconstructed
    nearly as well as the same pixels with real neighbours (measured ratios 1.1-2.3 on
    these crops; colour-demosaicing's bilinear, which mirrors across the CFA phase, gives
    3-46)."""
    from PIL import Image

    for name in ("kodim08", "kodim13", "kodim19", "kodim23"):
        full = np.asarray(Image.open(shared_data / "kodak" / f"{name}.png").convert("RGB"))
        full = full.astype(np.float64) / 255
        sl = (slice(100, 228), slice(100, 292))
        crop = full[sl]
        e_crop = ((demosaic(mosaic(crop, "RGGB"), "RGGB", method) - crop) ** 2).mean(-1)
        e_full = ((demosaic(mosaic(full, "RGGB"), "RGGB", method)[sl] - crop) ** 2).mean(-1)
        band = np.ones(crop.shape[:2], bool)
        band[4:-4, 4:-4] = False
        assert e_crop[band].mean() < 3.0 * e_full[band].mean(), name


# ---- dtypes, shapes, backends --------------------------------------------------------------


@pytest.mark.parametrize(
    ("dtype", "scale", "out"),
    [
        ("uint8", 255, np.float32),
        ("uint16", 65535, np.float32),
        ("float32", 1, np.float32),
        ("float64", 1, np.float64),
    ],
)
@pytest.mark.parametrize("method", ["malvar", "menon_soft"])
def test_dtypes(dtype: str, scale: int, out: type, method: str) -> None:
    img = smooth_image()
    raw = mosaic(img, "RGGB")
    data = np.round(raw * scale).astype(dtype) if scale > 1 else raw.astype(dtype)
    got = demosaic(data, "RGGB", method)
    assert got.dtype == out
    ref = demosaic(data.astype(np.float64) / scale, "RGGB", method)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-5)


def test_batch_and_trailing_axis() -> None:
    rng = np.random.default_rng(9)
    raws = rng.random((2, 3, 10, 12, 1))
    out = demosaic(raws, "BGGR", "hamilton_adams")
    assert out.shape == (2, 3, 10, 12, 3)
    np.testing.assert_array_equal(out[1, 2], demosaic(raws[1, 2, ..., 0], "BGGR", "hamilton_adams"))


@pytest.mark.parametrize("shape", [(5, 7), (2, 2), (3, 2), (2, 9)])
@pytest.mark.parametrize("method", DEMOSAIC_METHODS)
def test_odd_and_tiny_sizes(shape: tuple[int, int], method: str) -> None:
    """Odd sizes, when allowed, demosaic a cut 2x2 cell at the edge; 2x2 is the minimum."""
    img = smooth_image(*shape)
    out = demosaic(mosaic(img, "GRBG"), "GRBG", method, allow_odd=True)
    assert out.shape == (*shape, 3)
    assert np.all(np.isfinite(out))
    m = cfa_masks(shape, "GRBG")
    np.testing.assert_allclose(out[m], img[m], atol=1e-12)


def test_clip() -> None:
    raw = np.zeros((12, 12))
    raw[6, 6] = 1.0
    out = demosaic(raw, "RGGB", "malvar")
    assert out.min() < 0
    clipped = demosaic(raw, "RGGB", "malvar", clip=True)
    assert clipped.min() == 0.0 and clipped.max() <= 1.0


def test_backends(xp_name: str) -> None:
    raw = mosaic(smooth_image(12, 14), "RGGB")
    x = to_backend(raw, xp_name)
    got = demosaic(x, "RGGB", "menon")
    assert type(got) is type(to_backend(np.zeros((2, 2, 3)), xp_name))
    np.testing.assert_allclose(to_np(got), demosaic(raw, "RGGB", "menon"), rtol=0, atol=0)
    got32 = demosaic(to_backend(raw, xp_name, "float32"), "RGGB", "bilinear")
    assert "float32" in str(got32.dtype)


# ---- bad input -------------------------------------------------------------------------------


def test_unknown_pattern_and_method() -> None:
    raw = np.zeros((4, 4))
    with pytest.raises(UnknownOptionError, match="unknown CFA pattern 'RGBX'; valid: 'RGGB'"):
        demosaic(raw, "RGBX")
    with pytest.raises(
        UnknownOptionError, match="unknown demosaicing method 'vng'; valid: 'bilinear'"
    ):
        demosaic(raw, "RGGB", "vng")


@pytest.mark.parametrize(
    ("shape", "match"),
    [
        ((8, 8, 3), r"single-channel raw mosaic .* got \(8, 8, 3\) with 3 channels"),
        ((2, 8, 8, 2), "with 2 channels"),
        ((8,), r"shape \(H, W\) or \(\.\.\., H, W, 1\), got \(8,\)"),
        ((1, 8), "at least 2x2"),
        ((8, 1, 1), "at least 2x2"),
    ],
)
def test_bad_shapes(shape: tuple[int, ...], match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        demosaic(np.zeros(shape), "RGGB")


def test_bad_values_and_dtypes() -> None:
    raw = np.zeros((4, 4))
    raw[1, 1] = np.inf
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        demosaic(raw)
    with pytest.raises(InvalidInputError, match="uint8, uint16 or floats"):
        demosaic(np.zeros((4, 4), np.int32))
    with pytest.raises(InvalidInputError, match="0-255"):
        demosaic(np.full((4, 4), 128.0))
    with pytest.raises(InvalidInputError, match="numeric array"):
        demosaic("raw.png")  # type: ignore[arg-type]


def test_odd_size_is_an_error_by_default() -> None:
    with pytest.raises(InvalidInputError, match=r"whole 2x2 Bayer cells.*\(5, 7\).*allow_odd"):
        demosaic(np.zeros((5, 7)), "RGGB", "bilinear")
