"""Illumination-robust segmentation: RGB vs HSV vs CIELAB on the same task (docs page
docs/color-space-choice.md). Red objects on a yellow-green background under a shadow
ramp (linear light × 1.0 at the left to × 0.1 at the right); thresholds are set once on the
lit scene and kept, as one would in practice.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.analysis import mask_iou, synthetic_shading_scene
from imageform.color import convert, hue_in_range, srgb_to_hsv


def segment_rgb(img: np.ndarray) -> np.ndarray:
    return (img[..., 0] > 0.5) & (img[..., 1] < 0.4) & (img[..., 2] < 0.4)


def segment_hsv_hs(img: np.ndarray) -> np.ndarray:
    hsv = srgb_to_hsv(img)
    return hue_in_range(hsv[..., 0], 340, 20) & (hsv[..., 1] > 0.5)  # V ignored


def segment_lab_a(img: np.ndarray) -> np.ndarray:
    return convert(img, "srgb", "lab")[..., 1] > 25  # a* (L* ignored)


METHODS = {"rgb": segment_rgb, "hsv": segment_hsv_hs, "lab": segment_lab_a}


def iou_table(shading: tuple[float, float]) -> dict[str, float]:
    img, truth = synthetic_shading_scene(shading=shading, rng=0)
    return {k: mask_iou(f(img), truth) for k, f in METHODS.items()}


def test_all_equal_without_shading() -> None:
    table = iou_table((1.0, 1.0))
    print("no shading:", {k: round(v, 3) for k, v in table.items()})
    assert min(table.values()) > 0.99


def test_shading_breaks_rgb_thresholds() -> None:
    table = iou_table((1.0, 0.1))
    print("shadow ramp 1.0 -> 0.1:", {k: round(v, 3) for k, v in table.items()})
    # HSV's H and S are invariant to scaling the encoded RGB (and nearly so for linear-light
    # scaling through the sRGB curve); a* shrinks with lightness; RGB boxes fail in the dark.
    assert table["hsv"] > 0.99
    assert table["lab"] > 0.9
    assert table["rgb"] < 0.9
    assert table["hsv"] >= table["lab"] > table["rgb"]


@pytest.mark.parametrize("dark", [0.5, 0.2, 0.1, 0.05])
def test_hsv_never_worse_than_rgb(dark: float) -> None:
    table = iou_table((1.0, dark))
    assert table["hsv"] >= table["rgb"]
