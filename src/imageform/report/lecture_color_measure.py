"""The lecture's colour-measurement examples.

The ΔE*ab formula, the practice questions on HSV, chroma subsampling and the Bayer pattern, grey
world.

The lecture states the formulas (ΔE*ab as the Euclidean distance in CIELAB; grey-world
gains that scale every channel mean to the mean grey) and the reading of a ΔE (below 1
imperceptible, about 2 just noticeable, above 10 obviously different). The input numbers of
these examples are small hand-checkable cases chosen here, with the answers worked by hand.
"""

from __future__ import annotations

import numpy as np

from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]


def _delta_e_345() -> float:
    from imageform.color.delta_e import delta_e

    return float(delta_e([50.0, 0.0, 0.0], [50.0, 3.0, 4.0], method="cie76"))


def _hsv_200_50_50() -> tuple[float, float]:
    from imageform.color import convert

    _, s, v = convert((200, 50, 50), "srgb", "hsv")
    return float(v), float(s)


def _bayer_green_share() -> float:
    from imageform.sensor import cfa_masks

    masks = np.asarray(cfa_masks((4, 4), "RGGB"), dtype=np.float64)
    green = masks[..., 1] if masks.shape[-1] == 3 else masks[1]
    return float(green.mean())


def _chroma_420_data() -> float:
    from imageform.color import chroma_subsample, srgb_to_ycbcr

    ycc = srgb_to_ycbcr(np.full((4, 4, 3), 0.5))
    sub = chroma_subsample(ycc, "4:2:0")
    kept = int(np.asarray(sub.luma).size) + int(np.asarray(sub.chroma).size)
    return kept / ycc.size


def _gray_world() -> tuple[float, ...]:
    from imageform.color.white_balance import white_balance

    img = np.ones((2, 2, 3)) * np.array([0.4, 0.5, 0.6])
    _, gains = white_balance(img, "gray_world", transfer="linear")
    return tuple(float(g) for g in gains)


EXAMPLES: list[WorkedExample] = [
    WorkedExample(
        topic="colour difference",
        question="ΔE*ab between L*a*b* = (50, 0, 0) and (50, 3, 4)?",
        formula="ΔE*ab = sqrt(ΔL*² + Δa*² + Δb*²)",
        compute=_delta_e_345,
        expected=5.0,
        tol=1e-12,
    ),
    WorkedExample(
        topic="colour representation",
        question="Practice question 9: V and S of the 8-bit pixel (200, 50, 50)?",
        formula="V = max / 255, S = (max - min) / max",
        compute=_hsv_200_50_50,
        expected=(200 / 255, 0.75),
        tol=1e-6,
    ),
    WorkedExample(
        topic="colour representation",
        question="Practice question 13: 4:2:0 keeps which share of the samples of 4:4:4?",
        formula="(1 + 2 x 1/4) / 3",
        compute=_chroma_420_data,
        expected=0.5,
        tol=1e-12,
    ),
    WorkedExample(
        topic="vision",
        question="Practice question 6: which share of a Bayer sensor's pixels are green?",
        formula="2 of every 2 x 2 tile of 4",
        compute=_bayer_green_share,
        expected=0.5,
        tol=1e-12,
    ),
    WorkedExample(
        topic="white balance",
        question="Grey world: linear channel means R, G, B = 0.4, 0.5, 0.6; the gains?",
        formula="g_c = ((R̄ + Ḡ + B̄)/3) / c̄",
        compute=_gray_world,
        expected=(1.25, 1.0, 0.8333),
        tol=1e-4,
    ),
]
