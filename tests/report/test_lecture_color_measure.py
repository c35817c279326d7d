"""The colour-measurement worked examples agree with their stated answers."""

from __future__ import annotations

import pytest

from imageform.report.lecture import all_examples
from imageform.report.lecture_color_measure import EXAMPLES


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda e: e.question[:40])
def test_example_agrees(example) -> None:  # type: ignore[no-untyped-def]
    assert example.agrees(), (example.computed(), example.expected_values())


def test_registered() -> None:
    assert all(e in all_examples() for e in EXAMPLES)
