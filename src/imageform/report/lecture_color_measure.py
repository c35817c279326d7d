"""The lecture's colour-measurement examples: the ΔE*ab formula and its reading, grey world.

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


def _reading() -> tuple[float, float, float]:
    from imageform.color.delta_e import describe_delta_e

    return (
        float(describe_delta_e(0.5) == "imperceptible"),
        float(describe_delta_e(2.0) == "just noticeable"),
        float(describe_delta_e(15.0) == "obviously different"),
    )


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
        topic="colour difference",
        question="Reading of ΔE = 0.5, 2 and 15 (1 = imperceptible / just noticeable / "
        "obviously different as the lecture says)",
        formula="< 1 imperceptible; about 2 just noticeable; > 10 obviously different",
        compute=_reading,
        expected=(1.0, 1.0, 1.0),
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
