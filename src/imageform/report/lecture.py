"""The lecture's worked examples and numeric practice answers, computed by the library.

Each :class:`WorkedExample` names the lecture's question, the formula, the answer the
lecture states and a function that computes it with imageform. ``imageform lecture`` prints
them as a table; ``tests/report/test_lecture.py`` checks every computed value against the
stated answer. Each domain keeps its examples in its own module (``lecture_geometry``,
``lecture_color`` ...) listed in :data:`_MODULES`.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

__all__ = ["WorkedExample", "all_examples", "lecture_topics"]


@dataclass(frozen=True)
class WorkedExample:
    """One worked example: the question, the formula, the lecture's answer and ours.

    ``compute`` returns the value(s) in ``unit``; ``expected`` is the lecture's answer and
    ``tol`` the absolute tolerance the lecture's own rounding allows.
    """

    topic: str
    question: str
    formula: str
    compute: Callable[[], float | Sequence[float]]
    expected: float | Sequence[float]
    unit: str = ""
    tol: float = 1e-9

    def computed(self) -> tuple[float, ...]:
        """Return our computed answer as a tuple of floats."""
        value = self.compute()
        if isinstance(value, int | float):
            return (float(value),)
        return tuple(float(v) for v in value)

    def expected_values(self) -> tuple[float, ...]:
        """Return the lecture's answer as a tuple of floats."""
        if isinstance(self.expected, int | float):
            return (float(self.expected),)
        return tuple(float(v) for v in self.expected)

    def agrees(self) -> bool:
        """Return True when our values match the lecture's in number, each within ``tol``."""
        got, want = self.computed(), self.expected_values()
        return len(got) == len(want) and all(
            math.isclose(g, w, rel_tol=0.0, abs_tol=self.tol)
            for g, w in zip(got, want, strict=True)
        )


_MODULES = (
    "imageform.report.lecture_geometry",
    "imageform.report.lecture_optics",
    "imageform.report.lecture_color",
    "imageform.report.lecture_color_measure",
    "imageform.report.lecture_vision",
)


def all_examples() -> list[WorkedExample]:
    """Every registered worked example, in lecture order (geometry first, then colour ...)."""
    out: list[WorkedExample] = []
    for name in _MODULES:
        out.extend(importlib.import_module(name).EXAMPLES)
    return out


def lecture_topics() -> tuple[str, ...]:
    """Return the topics of the worked examples, in lecture order, each once.

    Examples
    --------
    >>> "pinhole" in lecture_topics()
    True
    """
    return tuple(dict.fromkeys(e.topic for e in all_examples()))
