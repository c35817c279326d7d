"""Bayer patterns, sampling masks and mosaic (imageform.sensor.cfa)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor import CFA_PATTERNS, cfa_masks, cfa_pattern, mosaic
from tests.helpers import to_backend, to_np

# Bayer, US patent 3,971,065 (1976): the 2x2 cell read row by row; the pattern name says it.
CELLS = {
    "RGGB": [[0, 1], [1, 2]],
    "BGGR": [[2, 1], [1, 0]],
    "GRBG": [[1, 0], [2, 1]],
    "GBRG": [[1, 2], [0, 1]],
}


def test_pattern_names() -> None:
    assert CFA_PATTERNS == ("RGGB", "BGGR", "GRBG", "GBRG")
    assert cfa_pattern(" gbrg ") == "GBRG"


@pytest.mark.parametrize("bad", ["RGBG", "XYZ", "", "bayer"])
def test_unknown_pattern_lists_valid_ones(bad: str) -> None:
    with pytest.raises(UnknownOptionError, match=r"unknown CFA pattern .*valid: 'RGGB', 'BGGR'"):
        cfa_pattern(bad)


def test_pattern_not_a_string() -> None:
    with pytest.raises(UnknownOptionError, match="expected a CFA pattern name"):
        cfa_pattern(3)


@pytest.mark.parametrize("pattern", CFA_PATTERNS)
def test_masks_follow_the_cell(pattern: str) -> None:
    m = cfa_masks((6, 8), pattern)
    assert m.shape == (6, 8, 3)
    assert np.all(m.sum(axis=-1) == 1)
    channel = np.argmax(m, axis=-1)
    np.testing.assert_array_equal(channel, np.tile(CELLS[pattern], (3, 4)))
    # half the photosites are green, a quarter red, a quarter blue
    np.testing.assert_allclose(m.mean(axis=(0, 1)), [0.25, 0.5, 0.25])


def test_masks_odd_size_cuts_the_cell() -> None:
    m = cfa_masks((3, 5), "RGGB")
    np.testing.assert_array_equal(np.argmax(m, -1), np.tile(CELLS["RGGB"], (2, 3))[:3, :5])


@pytest.mark.parametrize("shape", [(0, 4), (4,), (2, -1), (2.5, 3)])
def test_masks_bad_shape(shape: object) -> None:
    with pytest.raises(InvalidInputError, match=r"expected shape \(H, W\)"):
        cfa_masks(shape, "RGGB")  # type: ignore[arg-type]


@pytest.mark.parametrize("pattern", CFA_PATTERNS)
def test_mosaic_keeps_the_filtered_channel(pattern: str) -> None:
    rng = np.random.default_rng(1)
    img = rng.random((4, 6, 3))
    raw = mosaic(img, pattern)
    assert raw.shape == (4, 6)
    idx = np.tile(CELLS[pattern], (2, 3))
    np.testing.assert_array_equal(raw, np.take_along_axis(img, idx[..., None], -1)[..., 0])


def test_mosaic_docstring_example() -> None:
    img = np.zeros((2, 2, 3))
    img[..., 0], img[..., 1], img[..., 2] = 0.9, 0.5, 0.1
    assert mosaic(img, "RGGB").tolist() == [[0.9, 0.5], [0.5, 0.1]]


@pytest.mark.parametrize(
    ("dtype", "scale", "out"),
    [
        ("uint8", 255, np.float32),
        ("uint16", 65535, np.float32),
        ("float32", 1, np.float32),
        ("float64", 1, np.float64),
    ],
)
def test_mosaic_dtypes(dtype: str, scale: int, out: type) -> None:
    rng = np.random.default_rng(2)
    img = (
        (rng.random((4, 4, 3)) * scale).astype(dtype)
        if scale > 1
        else rng.random((4, 4, 3)).astype(dtype)
    )
    raw = mosaic(img)
    assert raw.dtype == out
    np.testing.assert_allclose(raw[0, 0], img[0, 0, 0] / scale, rtol=1e-6)


def test_mosaic_batch_and_odd_sizes() -> None:
    rng = np.random.default_rng(3)
    img = rng.random((2, 5, 7, 3))
    raw = mosaic(img, "GBRG")
    assert raw.shape == (2, 5, 7)
    np.testing.assert_array_equal(raw[1], mosaic(img[1], "GBRG"))


@pytest.mark.parametrize(
    ("shape", "match"),
    [
        ((4, 4), "3 channels"),
        ((4, 4, 4), "alpha channel"),
        ((4, 4, 1), "3 channels"),
        ((3,), r"shape \(\.\.\., H, W, 3\)"),
    ],
)
def test_mosaic_bad_shapes(shape: tuple[int, ...], match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        mosaic(np.zeros(shape), "RGGB")


def test_mosaic_rejects_nan_and_0_255_floats() -> None:
    img = np.zeros((2, 2, 3))
    img[0, 0, 0] = np.nan
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        mosaic(img)
    with pytest.raises(InvalidInputError, match="0-255"):
        mosaic(np.full((2, 2, 3), 200.0))


def test_mosaic_backends(xp_name: str) -> None:
    rng = np.random.default_rng(4)
    img = rng.random((4, 6, 3))
    got = mosaic(to_backend(img, xp_name), "BGGR")
    assert (
        type(got).__module__.split(".")[0]
        == type(to_backend(img, xp_name)).__module__.split(".")[0]
    )
    np.testing.assert_allclose(to_np(got), mosaic(img, "BGGR"), rtol=0, atol=0)


@settings(max_examples=30, deadline=None)
@given(h=st.integers(1, 9), w=st.integers(1, 9), p=st.sampled_from(CFA_PATTERNS))
def test_mosaic_is_masked_sum(h: int, w: int, p: str) -> None:
    rng = np.random.default_rng(h * 10 + w)
    img = rng.random((h, w, 3))
    np.testing.assert_array_equal(mosaic(img, p), (img * cfa_masks((h, w), p)).sum(-1))


def test_opencv_names_rggb_bayerbg() -> None:
    """Cross-check (OpenCV, not a gold value): an RGGB mosaic is OpenCV's COLOR_BayerBG."""
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(5)
    img = (rng.random((16, 16, 3)) * 255).astype(np.uint8)
    raw = np.round(mosaic(img, "RGGB") * 255).astype(np.uint8)
    rgb = cv2.cvtColor(raw, cv2.COLOR_BayerBG2RGB)
    # measured samples come back unchanged from OpenCV's bilinear demosaicing
    m = cfa_masks((16, 16), "RGGB")
    np.testing.assert_array_equal(rgb[2:-2, 2:-2][m[2:-2, 2:-2]], img[2:-2, 2:-2][m[2:-2, 2:-2]])


def test_huge_pattern_name_is_one_short_line() -> None:
    """Issue 16: a 100,000-character name was echoed whole."""
    from imageform.sensor import demosaic

    rgb = np.full((4, 6, 3), 0.5)
    for call in (
        lambda p: cfa_pattern(p),
        lambda p: cfa_masks((4, 6), p),
        lambda p: mosaic(rgb, p),
        lambda p: demosaic(rgb[..., :1], p),
    ):
        with pytest.raises(UnknownOptionError, match="CFA pattern") as exc:
            call("x" * 100_000)
        assert len(str(exc.value)) <= 200 and "\n" not in str(exc.value)


def test_misshaped_rgb_is_refused_before_its_values_are_read() -> None:
    """Issue 16: the channel count is checked from the shape, before the NaN/range pass."""
    a = np.full((2000, 2000, 4), np.nan)
    with pytest.raises(InvalidInputError, match="expected rgb with 3 channels"):
        mosaic(a)


@pytest.mark.parametrize("pattern", CFA_PATTERNS)
def test_superpixel_is_the_mosaic_of_a_half_size_image(pattern: str) -> None:
    """mosaic() of an image constant over each 2x2 cell, then superpixel(), gives it back."""
    from imageform.sensor import superpixel

    rng = np.random.default_rng(3)
    small = rng.uniform(0.05, 0.95, (5, 7, 3))
    full = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)
    raw = np.asarray(mosaic(full, pattern))
    np.testing.assert_allclose(superpixel(raw, pattern), small, atol=1e-12)
    odd = np.pad(raw, ((0, 1), (0, 1)))  # the odd last row and column are dropped
    np.testing.assert_allclose(superpixel(odd, pattern), small, atol=1e-12)


@pytest.mark.parametrize("pattern", CFA_PATTERNS)
def test_equalize_cfa_removes_the_pattern_of_a_grey_edge(pattern: str) -> None:
    """A grey edge seen through the CFA with per-colour gains: equalised, the four
    photosites of a cell agree (to the edge's own variation) and the greens keep their
    levels."""
    from imageform.sensor import equalize_cfa

    x = np.arange(64)
    edge = np.where(x[None, :] + 0.2 * np.arange(64)[:, None] < 32, 0.1, 0.8) * np.ones((64, 1))
    gains = {"R": 0.5, "G": 1.0, "B": 0.7}
    masks = cfa_masks((64, 64), pattern)
    raw = edge * sum(masks[..., c] * g for c, g in enumerate(gains.values()))
    out = equalize_cfa(raw, pattern)
    np.testing.assert_allclose(out, edge, atol=1e-9)


def test_superpixel_and_equalize_cfa_refuse_bad_input() -> None:
    from imageform.sensor import equalize_cfa, superpixel

    for fn in (superpixel, equalize_cfa):
        with pytest.raises(InvalidInputError, match="raw"):
            fn(np.zeros((1, 4)), "RGGB")
        with pytest.raises(InvalidInputError, match="raw"):
            fn(np.zeros((4, 4, 3)), "RGGB")
        with pytest.raises(UnknownOptionError):
            fn(np.zeros((4, 4)), "RGBX")
