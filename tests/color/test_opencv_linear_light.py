"""OpenCV conventions against cv2 itself; the linear-light helpers."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import (
    OPENCV_CONVENTIONS,
    bgr_to_srgb,
    convert,
    downsample,
    from_opencv,
    linear_light_error,
    mean_linear_light,
    srgb_to_bgr,
    to_opencv,
)
from imageform.errors import InvalidInputError, UnknownOptionError

cv2 = pytest.importorskip("cv2")
RGB8 = np.random.default_rng(20).integers(0, 256, (32, 32, 3), dtype=np.uint8)


def test_bgr_matches_cv2() -> None:
    np.testing.assert_array_equal(srgb_to_bgr(RGB8), RGB8[..., ::-1] / np.float32(255))
    np.testing.assert_array_equal(bgr_to_srgb(RGB8[..., ::-1]), RGB8 / np.float32(255))
    np.testing.assert_array_equal(
        to_opencv(RGB8 / np.float32(255), "bgr"), convert(RGB8, "srgb", "bgr")
    )


def test_hsv8_matches_cv2() -> None:
    # Cross-check: cv2 COLOR_RGB2HSV on uint8 (H/2). OpenCV rounds its own float hue; ours
    # rounds the exact hue: codes differ by at most 1.
    ours = to_opencv(convert(RGB8, "srgb", "hsv"), "hsv8").astype(int)
    ref = cv2.cvtColor(RGB8, cv2.COLOR_RGB2HSV).astype(int)
    dh = np.abs(ours[..., 0] - ref[..., 0])
    assert np.all(np.minimum(dh, 180 - dh) <= 1)
    assert np.abs(ours[..., 1:] - ref[..., 1:]).max() <= 1
    full = to_opencv(convert(RGB8, "srgb", "hsv"), "hsv8_full").astype(int)
    ref_full = cv2.cvtColor(RGB8, cv2.COLOR_RGB2HSV_FULL).astype(int)
    dh = np.abs(full[..., 0] - ref_full[..., 0])
    assert np.all(np.minimum(dh, 256 - dh) <= 1)


def test_lab8_matches_cv2() -> None:
    # Cross-check: cv2 COLOR_RGB2Lab on uint8 (L*255/100, a+128, b+128). OpenCV's 8-bit path
    # uses fixed-point LUTs and a D65 of (0.950456, 1, 1.088754): codes differ by <= 2.
    ours = to_opencv(convert(RGB8, "srgb", "lab"), "lab8").astype(int)
    ref = cv2.cvtColor(RGB8, cv2.COLOR_RGB2Lab).astype(int)
    assert np.abs(ours - ref).max() <= 2
    back = from_opencv(ref.astype(np.uint8), "lab8")
    np.testing.assert_allclose(back, convert(RGB8, "srgb", "lab"), atol=1.5)


def test_ycrcb_matches_cv2() -> None:
    ours = to_opencv(convert(RGB8, "srgb", "ycbcr"), "ycrcb8").astype(int)
    ref = cv2.cvtColor(RGB8, cv2.COLOR_RGB2YCrCb).astype(int)
    assert np.abs(ours - ref).max() <= 1
    f = RGB8.astype(np.float32) / 255
    ours_f = to_opencv(convert(f, "srgb", "ycbcr"), "ycrcb")
    np.testing.assert_allclose(ours_f, cv2.cvtColor(f, cv2.COLOR_RGB2YCrCb), atol=2e-3)


@pytest.mark.parametrize("conv", list(OPENCV_CONVENTIONS))
def test_round_trip_layouts(conv: str) -> None:
    x = np.random.default_rng(21).uniform(0, 1, (50, 3))
    space = OPENCV_CONVENTIONS[conv]
    vals = convert(x, "srgb", space)
    back = from_opencv(to_opencv(vals, conv), conv)
    tol = {"hsv": 2.0, "lab": 0.6, "ycbcr": 0.003, "srgb": 0}[space]
    if conv in ("ycrcb", "bgr"):
        tol = 1e-12
    np.testing.assert_allclose(back[:, 1:], vals[:, 1:], atol=tol if space != "hsv" else 0.003)


def test_opencv_errors() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'bgr'"):
        to_opencv([0.0, 0.0, 0.0], "hsv16")
    with pytest.raises(InvalidInputError, match="3 channels"):
        from_opencv(np.zeros((2, 2)), "lab8")


def test_linear_light_lecture() -> None:
    # The lecture's rule: decode before averaging. Black and white mixed half-and-half are
    # 50 % of white's light: encoded 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354, not 0.5.
    half = 1.055 * 0.5 ** (1 / 2.4) - 0.055
    assert float(mean_linear_light([0.0, 1.0])) == pytest.approx(half, abs=1e-12)
    checker = (np.indices((8, 8)).sum(0)[..., None] % 2) * np.ones(3)
    cmp = linear_light_error(checker, 2)
    np.testing.assert_allclose(cmp.right, half, atol=1e-12)
    np.testing.assert_allclose(cmp.wrong, 0.5)
    assert cmp.max_error == pytest.approx(half - 0.5)
    assert downsample(np.zeros((5, 7, 3)), 2).shape == (2, 3, 3)
    with pytest.raises(InvalidInputError, match="factor"):
        downsample(checker, 0)
    with pytest.raises(InvalidInputError, match="smaller"):
        downsample(checker, 16)
    g = mean_linear_light([0.0, 1.0], transfer="gamma")
    assert float(g) == pytest.approx(0.5 ** (1 / 2.2))
