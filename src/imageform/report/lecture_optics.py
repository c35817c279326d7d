"""The lecture's optics worked examples (thin lens, depth of field)."""

from __future__ import annotations

from imageform.optics.depth_of_field import hyperfocal_distance
from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]

EXAMPLES: list[WorkedExample] = [
    WorkedExample(
        topic="optics: depth of field",
        question="Hyperfocal distance of a 50 mm lens at f/8 with a 0.03 mm circle of confusion?",
        formula="H = f² / (N c) + f",
        compute=lambda: hyperfocal_distance(focal_length=0.050, f_number=8.0, coc=0.03e-3),
        expected=10.47,
        unit="m",
        tol=0.005,
    ),
]
