"""The one Rec. 601 luma (imageform._colormath): its two forms and the bits each site keeps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform._colormath import LUMA_601, luma_601, luma_601_matmul

SRC = Path(__file__).resolve().parents[1] / "src" / "imageform"
RNG_RGB = np.random.default_rng(601).integers(0, 256, (20, 24, 3), dtype=np.uint8)


def _elementwise(a: np.ndarray) -> np.ndarray:
    return a[..., 0] * 0.299 + a[..., 1] * 0.587 + a[..., 2] * 0.114


def test_weights_and_gold_values() -> None:
    """ITU-R BT.601-7 section 2.5.1: Y' = 0.299 R' + 0.587 G' + 0.114 B'; white to white."""
    assert LUMA_601 == (0.299, 0.587, 0.114)
    assert float(luma_601(np, np.array([255.0, 0.0, 0.0]))) == 0.299 * 255.0
    assert float(luma_601_matmul(np, np.array([0.0, 255.0, 0.0]))) == 0.587 * 255.0
    assert float(luma_601(np, np.array([200.0, 100.0, 50.0]))) == pytest.approx(124.2, abs=1e-12)
    assert float(luma_601_matmul(np, np.ones(3))) == pytest.approx(1.0, abs=1e-15)


def test_elementwise_form_keeps_its_bits_and_dtype() -> None:
    """Channel by channel, left to right: float32 stays float32, uint8 becomes float64."""
    for a in (RNG_RGB, RNG_RGB / 255.0, (RNG_RGB / np.float32(255)).astype(np.float32)):
        y = luma_601(np, a)
        assert y.dtype == _elementwise(a).dtype
        np.testing.assert_array_equal(y, _elementwise(a))
    assert luma_601(np, RNG_RGB).dtype == np.float64
    assert luma_601(np, RNG_RGB.astype(np.float32)).dtype == np.float32
    rgba = np.concatenate([RNG_RGB, np.full((20, 24, 1), 255, np.uint8)], axis=-1)
    np.testing.assert_array_equal(luma_601(np, rgba), luma_601(np, RNG_RGB))  # alpha ignored


def test_matmul_form_keeps_its_bits_and_weights_dtype() -> None:
    """``rgb @ w``, ``w`` float64 by default or in the dtype given (float32-rounded weights)."""
    w64 = np.array([0.299, 0.587, 0.114])
    np.testing.assert_array_equal(luma_601_matmul(np, RNG_RGB), RNG_RGB @ w64)
    f64 = RNG_RGB / 255.0
    np.testing.assert_array_equal(luma_601_matmul(np, f64), f64 @ w64)
    f32 = (RNG_RGB / np.float32(255)).astype(np.float32)
    y = luma_601_matmul(np, f32, np.float32)
    assert y.dtype == np.float32
    np.testing.assert_array_equal(y, f32 @ w64.astype(np.float32))
    # float64 pixels with float32 weights: float64 out, the weights rounded to float32
    np.testing.assert_array_equal(
        luma_601_matmul(np, f64, np.float32), f64 @ np.array(LUMA_601, np.float32)
    )
    assert luma_601_matmul(np, f64).dtype == np.float64


def test_the_two_forms_differ_in_the_last_place() -> None:
    """Why each caller keeps its form: the sums are not the same bits on float64 pixels."""
    f64 = np.random.default_rng(7).random((64, 64, 3))
    y1, y2 = luma_601(np, f64), luma_601_matmul(np, f64)
    np.testing.assert_allclose(y1, y2, rtol=0, atol=4e-16)
    assert np.any(y1 != y2)


def test_sites_keep_their_form() -> None:
    """The grey readers' luma, bit for bit the expression each site had inline."""
    from imageform.geometry import checkerboard_subpix, stereo_matching
    from imageform.geometry._plumb_edges import grey_levels
    from imageform.io import interlace

    rgb = RNG_RGB
    np.testing.assert_array_equal(
        stereo_matching._grey(rgb, "left"), np.float32(_elementwise(rgb.astype(np.float64)))
    )
    np.testing.assert_array_equal(interlace._luma(rgb, "frame"), np.float32(_elementwise(rgb)))
    np.testing.assert_array_equal(grey_levels(rgb), _elementwise(rgb.astype(np.float64)))
    f32 = (rgb / np.float32(255)).astype(np.float32)
    np.testing.assert_array_equal(
        checkerboard_subpix.as_gray(f32), f32 @ np.array(LUMA_601, np.float32)
    )


def test_no_inline_luma_outside_the_core() -> None:
    """One way per job: the Rec. 601 weights are written in _colormath (and colour, the text)."""
    allowed = {"_colormath.py", "report/lecture_color.py", "_kernels/aruco.py"}
    found = []
    for p in SRC.rglob("*.py"):
        rel = p.relative_to(SRC).as_posix()
        if rel in allowed or rel.startswith("color/"):
            continue
        if "0.299" in p.read_text("utf-8"):
            found.append(rel)
    assert found == []
