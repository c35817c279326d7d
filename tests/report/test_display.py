"""Stage display: the one conversion from every stage kind to 8-bit sRGB, and raw to 16 bits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.report.display import raw_to_uint16, stage_display_image


def _srgb8(linear: float) -> int:
    """IEC 61966-2-1:1999 clause 5.3 encoding, rounded to 8 bits."""
    v = 12.92 * linear if linear <= 0.0031308 else 1.055 * linear ** (1 / 2.4) - 0.055
    return round(255 * v)


def test_linear_percentile_becomes_white_and_srgb_encoded() -> None:
    # 100 values 0.01 ... 1.00 times 7: the 99th percentile (linear interpolation) is 6.937
    img = (np.arange(1, 101, dtype=np.float64) / 100 * 7.0).reshape(10, 10)
    out = stage_display_image(img, "linear", percentile=99.0)
    assert out.shape == (10, 10, 3) and out.dtype == np.uint8
    p99 = np.percentile(img, 99.0)
    assert out[0, 0, 0] == _srgb8(0.07 / p99)
    assert out[4, 9, 1] == _srgb8(3.5 / p99)
    assert out[9, 9, 2] == 255  # above the percentile: white (display only)


def test_linear_all_zero_stays_black_and_negative_noise_shows_black() -> None:
    assert not stage_display_image(np.zeros((3, 4, 3)), "linear").any()
    out = stage_display_image(np.array([[-0.1, 0.5, 1.0]]), "linear", percentile=100)
    assert out[0, 0].tolist() == [0, 0, 0] and out[0, 2].tolist() == [255, 255, 255]


def test_raw_grey_by_white_level() -> None:
    raw = np.array([[0, 1023, 4095]], dtype=np.uint16)
    out = stage_display_image(raw, "raw", white_level=4095.0)
    assert out[0, :, 0].tolist() == [0, round(255 * 1023 / 4095), 255]
    assert np.all(out[..., 0] == out[..., 2])


def test_srgb_as_is_and_single_channel() -> None:
    img = np.array([[[0.0, 0.5, 1.0]]], dtype=np.float32)
    assert stage_display_image(img, "srgb").tolist() == [[[0, 128, 255]]]
    grey = stage_display_image(np.full((2, 2, 1), 0.5), "srgb")
    assert grey.shape == (2, 2, 3) and np.all(grey == 128)


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.uint8])
def test_dtypes(dtype: type) -> None:
    img = np.ones((4, 5, 3), dtype=dtype)
    assert stage_display_image(img, "linear").dtype == np.uint8


def test_bad_inputs() -> None:
    with pytest.raises(UnknownOptionError, match=r"valid: 'linear', 'raw', 'srgb'"):
        stage_display_image(np.zeros((2, 2)), "log")
    with pytest.raises(InvalidInputError, match="white_level"):
        stage_display_image(np.zeros((2, 2)), "raw")
    with pytest.raises(InvalidInputError, match=r"raw stage of shape \(H, W\)"):
        stage_display_image(np.zeros((2, 2, 3)), "raw", white_level=1.0)
    with pytest.raises(InvalidInputError, match="NaN"):
        stage_display_image(np.array([[np.nan]]), "linear")
    with pytest.raises(InvalidInputError, match=r"\(H, W, 3\)"):
        stage_display_image(np.zeros((2, 2, 4)), "srgb")
    with pytest.raises(InvalidInputError, match="percentile"):
        stage_display_image(np.zeros((2, 2)), "linear", percentile=0)


def test_raw_to_uint16() -> None:
    assert raw_to_uint16(np.array([[0, 65535]], dtype=np.int32)).tolist() == [[0, 65535]]
    assert raw_to_uint16(np.array([[70000]], dtype=np.int32)) is None
    assert raw_to_uint16(np.array([[-1.0]])) is None
    assert raw_to_uint16(np.array([[3.0, 4095.0]], dtype=np.float32)).dtype == np.uint16


@settings(max_examples=40, deadline=None)
@given(
    arrays(np.float64, (4, 5, 3), elements=st.floats(0.0, 1e4, allow_nan=False)),
    st.floats(50.0, 100.0),
)
def test_linear_display_is_monotone(img: np.ndarray, pct: float) -> None:
    """Brighter light never shows darker: the display map is one increasing function."""
    out = stage_display_image(img, "linear", percentile=pct).astype(int)
    order = np.argsort(img.ravel(), kind="stable")
    assert np.all(np.diff(out.ravel()[order]) >= 0)


_json_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**40), 2**40),
    st.floats(allow_nan=True),
    st.text(max_size=5),
)
_json_tree = st.recursive(
    _json_leaf,
    lambda kids: (
        st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=4), kids, max_size=3)
    ),
    max_leaves=12,
)


@settings(max_examples=60, deadline=None)
@given(_json_tree)
def test_json_values_round_trip(value: object) -> None:
    import json

    from imageform.report.metrics import to_json_value

    plain = to_json_value(value)
    assert json.loads(json.dumps(plain, allow_nan=False)) == plain
    assert to_json_value(plain) == plain
