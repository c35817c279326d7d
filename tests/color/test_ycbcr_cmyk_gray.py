"""Y'CbCr (BT.601/709/2020 test values), CMY/CMYK (the lecture), grey (601 luma, 709 Y)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.color import (
    cmy_to_cmyk,
    cmyk_to_srgb,
    gray_to_srgb,
    linear_srgb_to_luminance,
    rgb_to_xyz_matrix,
    rgb_to_ycbcr,
    srgb_to_cmy,
    srgb_to_cmyk,
    srgb_to_gray,
    ycbcr_to_rgb,
)
from imageform.errors import InvalidInputError, UnknownOptionError

BARS = np.array(  # 100 % colour bars: white, yellow, cyan, green, magenta, red, blue, black
    [[1, 1, 1], [1, 1, 0], [0, 1, 1], [0, 1, 0], [1, 0, 1], [1, 0, 0], [0, 0, 1], [0, 0, 0.0]]
)


def test_gold_bt601_colour_bars_8bit() -> None:
    # Gold: ITU-R BT.601-7 quantisation of 100 % colour bars (as tabulated in ITU-R BT.801 /
    # SMPTE EG 1): Y', Cb, Cr codes.
    ref = [
        [235, 128, 128],
        [210, 16, 146],
        [170, 166, 16],
        [145, 54, 34],
        [106, 202, 222],
        [81, 90, 240],
        [41, 240, 110],
        [16, 128, 128],
    ]
    got = np.round(rgb_to_ycbcr(BARS, "bt601", signal_range="limited", bit_depth=8))
    np.testing.assert_array_equal(got, ref)


def test_gold_bt709_colour_bars_8bit() -> None:
    # Gold: ITU-R BT.709-6 with 8-bit limited range, 100 % bars (SMPTE RP 219 Table 2 codes).
    ref = [
        [235, 128, 128],
        [219, 16, 138],
        [188, 154, 16],
        [173, 42, 26],
        [78, 214, 230],
        [63, 102, 240],
        [32, 240, 118],
        [16, 128, 128],
    ]
    got = np.round(rgb_to_ycbcr(BARS, "bt709", signal_range="limited", bit_depth=8))
    np.testing.assert_array_equal(got, ref)


def test_gold_10bit_and_full_range() -> None:
    # Gold: BT.709/BT.2020 10-bit limited: white 940, black 64, chroma zero 512; full range
    # (H.273): white 1023 (10-bit), 255 (8-bit), chroma zero 2^(n-1).
    np.testing.assert_allclose(
        rgb_to_ycbcr([1.0, 1, 1], "bt2020", signal_range="limited", bit_depth=10), [940, 512, 512]
    )
    np.testing.assert_allclose(
        rgb_to_ycbcr([0.0, 0, 0], "bt709", signal_range="limited", bit_depth=10), [64, 512, 512]
    )
    np.testing.assert_allclose(rgb_to_ycbcr([1.0, 1, 1], bit_depth=10), [1023, 512, 512])
    np.testing.assert_allclose(
        rgb_to_ycbcr([1.0, 0, 0], "bt601"), [0.299, -0.168736, 0.5], atol=1e-6
    )


def test_cross_check_opencv_ycrcb() -> None:
    # Cross-check: OpenCV COLOR_RGB2YCrCb on float32 (BT.601, full range, Y Cr Cb, +0.5).
    cv2 = pytest.importorskip("cv2")
    x = np.random.default_rng(5).uniform(0, 1, (16, 16, 3)).astype(np.float32)
    ref = cv2.cvtColor(x, cv2.COLOR_RGB2YCrCb)
    got = rgb_to_ycbcr(x)
    np.testing.assert_allclose(got[..., 0], ref[..., 0], atol=2e-6)
    np.testing.assert_allclose(got[..., 2] + 0.5, ref[..., 1], atol=2e-3)  # OpenCV 0.713 coeff
    np.testing.assert_allclose(got[..., 1] + 0.5, ref[..., 2], atol=2e-3)  # OpenCV 0.564 coeff


@pytest.mark.parametrize("std", ["bt601", "bt709", "bt2020"])
@pytest.mark.parametrize(
    ("rng", "bits"), [("full", None), ("full", 8), ("limited", 8), ("limited", 10)]
)
def test_round_trip(std: str, rng: str, bits: int | None) -> None:
    x = np.random.default_rng(6).uniform(0, 1, (100, 3))
    ycc = rgb_to_ycbcr(x, std, signal_range=rng, bit_depth=bits)
    np.testing.assert_allclose(
        ycbcr_to_rgb(ycc, std, signal_range=rng, bit_depth=bits), x, atol=1e-12
    )


def test_ycbcr_errors() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'bt2020', 'bt601', 'bt709'"):
        rgb_to_ycbcr([0.5, 0.5, 0.5], "bt.999")
    with pytest.raises(UnknownOptionError, match="valid: 'full', 'limited'"):
        rgb_to_ycbcr([0.5, 0.5, 0.5], signal_range="studio")
    with pytest.raises(InvalidInputError, match="bit_depth"):
        rgb_to_ycbcr([0.5, 0.5, 0.5], bit_depth=9)


def test_ycbcr_integer_codes_read_as_numbers() -> None:
    codes = np.array([235, 128, 128], dtype=np.uint8)
    np.testing.assert_allclose(
        ycbcr_to_rgb(codes, "bt709", signal_range="limited"), [1, 1, 1], atol=1e-6
    )
    with pytest.raises(InvalidInputError, match="exceed"):
        ycbcr_to_rgb(np.array([1023, 512, 512], dtype=np.uint16), bit_depth=8)


def test_cmy_cmyk_lecture() -> None:
    # The lecture: CMY = 1 - RGB; K = min(C, M, Y); remaining inks scaled by 1 / (1 - K).
    np.testing.assert_allclose(srgb_to_cmy([1.0, 0.0, 0.5]), [0, 1, 0.5])
    np.testing.assert_allclose(srgb_to_cmyk([0.2, 0.4, 0.6]), [2 / 3, 1 / 3, 0, 0.4], atol=1e-12)
    np.testing.assert_allclose(srgb_to_cmyk([0.0, 0.0, 0.0]), [0, 0, 0, 1])
    np.testing.assert_allclose(cmy_to_cmyk([0.0, 0.0, 0.0]), [0, 0, 0, 0])


@settings(max_examples=100, deadline=None)
@given(rgb=arrays(np.float64, (3,), elements=st.floats(0, 1)))
def test_cmyk_round_trip(rgb: np.ndarray) -> None:
    np.testing.assert_allclose(cmyk_to_srgb(srgb_to_cmyk(rgb)), rgb, atol=1e-12)


def test_gray_lecture_and_709() -> None:
    # The lecture: gray = 0.299 R + 0.587 G + 0.114 B (BT.601 luma).
    np.testing.assert_allclose(
        srgb_to_gray([0.2, 0.4, 0.6]), [0.299 * 0.2 + 0.587 * 0.4 + 0.114 * 0.6]
    )
    # BT.709 luminance equals the Y row of the derived sRGB matrix to its 4 printed decimals.
    y = linear_srgb_to_luminance(np.eye(3))[:, 0]
    np.testing.assert_allclose(y, rgb_to_xyz_matrix("srgb")[1], atol=5e-5)
    assert srgb_to_gray(np.ones((2, 2, 3), np.float32)).shape == (2, 2, 1)
    np.testing.assert_allclose(gray_to_srgb([[0.3]]), [[0.3, 0.3, 0.3]])
    with pytest.raises(UnknownOptionError, match="grey method"):
        srgb_to_gray([0.1, 0.2, 0.3], "average")


def test_cross_check_opencv_gray() -> None:
    cv2 = pytest.importorskip("cv2")
    x = np.random.default_rng(7).uniform(0, 1, (8, 8, 3)).astype(np.float32)
    np.testing.assert_allclose(
        srgb_to_gray(x)[..., 0], cv2.cvtColor(x, cv2.COLOR_RGB2GRAY), atol=2e-6
    )


@pytest.mark.parametrize(
    ("std", "cs_key"),
    [("bt601", "ITU-R BT.601"), ("bt709", "ITU-R BT.709"), ("bt2020", "ITU-R BT.2020")],
)
@pytest.mark.parametrize(
    ("rng", "bits", "legal"), [("limited", 8, True), ("limited", 10, True), ("full", 10, False)]
)
def test_cross_check_colour_science_ycbcr(
    std: str, cs_key: str, rng: str, bits: int, legal: bool
) -> None:
    # Cross-check: colour-science RGB_to_YCbCr with the same K and quantisation (float codes).
    colour = pytest.importorskip("colour")
    x = np.random.default_rng(8).uniform(0, 1, (200, 3))
    ref = colour.RGB_to_YCbCr(
        x,
        K=colour.WEIGHTS_YCBCR[cs_key],
        in_bits=10,
        in_legal=False,
        in_int=False,
        out_bits=bits,
        out_legal=legal,
        out_int=False,
    )
    # colour returns normalised values (code / (2^n - 1)): compare code values. For full
    # range colour keeps chroma centred on 0; H.273 full-range codes (ours) add 2^(n-1).
    ref = ref * (2**bits - 1)
    if not legal:
        ref[:, 1:] += 2 ** (bits - 1)
    np.testing.assert_allclose(
        rgb_to_ycbcr(x, std, signal_range=rng, bit_depth=bits), ref, atol=1e-9
    )
