"""The lecture's optics examples agree with imageform."""

from __future__ import annotations

import pytest

from imageform.report.lecture_optics import EXAMPLES


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda e: e.question[:40])
def test_optics_examples_agree(example) -> None:  # type: ignore[no-untyped-def]
    assert example.agrees(), (example.question, example.computed(), example.expected)
