"""The lecture's camera-geometry worked examples."""

from __future__ import annotations

from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]

EXAMPLES: list[WorkedExample] = []
