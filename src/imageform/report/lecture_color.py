"""The lecture's colour-representation numbers, computed by imageform.color.

What the lecture states: grey = 0.299 R + 0.587 G + 0.114 B; display gamma 2.2 (decode
before any linear operation); CMY = 1 - RGB and K = min(C, M, Y); OpenCV's 8-bit HSV stores
H / 2. The inputs are small hand-checkable cases; the answers follow from those formulas.
"""

from __future__ import annotations

from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]


def _gray() -> float:
    from imageform.color import srgb_to_gray

    return float(srgb_to_gray([1.0, 0.5, 0.0])[0])


def _gamma() -> tuple[float, float]:
    from imageform.color import gamma_to_linear, linear_to_gamma

    return float(gamma_to_linear(0.5)), float(linear_to_gamma(0.5))


def _mix() -> tuple[float, float]:
    from imageform.color import mean_linear_light

    wrong = 0.5  # the mean of the encoded values 0 and 1
    return wrong, float(mean_linear_light([0.0, 1.0], transfer="gamma"))


def _cmyk() -> tuple[float, ...]:
    from imageform.color import srgb_to_cmyk

    return tuple(float(v) for v in srgb_to_cmyk([0.2, 0.4, 0.6]))


def _cmy() -> tuple[float, ...]:
    from imageform.color import srgb_to_cmy

    return tuple(float(v) for v in srgb_to_cmy([1.0, 0.0, 0.25]))


def _hsv8() -> tuple[float, ...]:
    from imageform.color import srgb_to_hsv, to_opencv

    return tuple(float(v) for v in to_opencv(srgb_to_hsv([0.0, 0.0, 1.0]), "hsv8"))


EXAMPLES: list[WorkedExample] = [
    WorkedExample(
        topic="colour representation",
        question="Grey value of the orange (R, G, B) = (1, 0.5, 0)?",
        formula="gray = 0.299 R + 0.587 G + 0.114 B",
        compute=_gray,
        expected=0.5925,
        tol=1e-12,
    ),
    WorkedExample(
        topic="colour representation",
        question="Gamma 2.2: the linear light of the code value 0.5, and the code of 50 % light?",
        formula="L = V^2.2, V = L^(1/2.2)",
        compute=_gamma,
        expected=(0.2176376, 0.7297401),
        tol=1e-7,
    ),
    WorkedExample(
        topic="colour representation",
        question="Black and white pixels averaged: as codes, and in linear light (gamma 2.2)?",
        formula="decode, average, encode: (0.5 (0^2.2 + 1^2.2))^(1/2.2)",
        compute=_mix,
        expected=(0.5, 0.7297401),
        tol=1e-7,
    ),
    WorkedExample(
        topic="colour representation",
        question="CMY of (R, G, B) = (1, 0, 0.25)?",
        formula="CMY = 1 - RGB",
        compute=_cmy,
        expected=(0.0, 1.0, 0.75),
        tol=1e-12,
    ),
    WorkedExample(
        topic="colour representation",
        question="CMYK of (R, G, B) = (0.2, 0.4, 0.6)?",
        formula="K = min(C, M, Y); C' = (C - K) / (1 - K) ...",
        compute=_cmyk,
        expected=(2 / 3, 1 / 3, 0.0, 0.4),
        tol=1e-12,
    ),
    WorkedExample(
        topic="colour representation",
        question="Pure blue in OpenCV's 8-bit HSV?",
        formula="H8 = H / 2, S8 = 255 S, V8 = 255 V (H = 240°)",
        compute=_hsv8,
        expected=(120.0, 255.0, 255.0),
        tol=0.0,
    ),
]
