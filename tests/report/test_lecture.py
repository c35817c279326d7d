"""Every worked example of the lecture is computed by the library and agrees with its answer."""

from __future__ import annotations

import pytest

from imageform.report.lecture import all_examples

EXAMPLES = all_examples()


def test_examples_registered() -> None:
    assert len(EXAMPLES) >= 6
    topics = {e.topic for e in EXAMPLES}
    assert {"pinhole", "projection", "vanishing points"} <= topics


@pytest.mark.parametrize("example", EXAMPLES, ids=[e.question[:40] for e in EXAMPLES])
def test_example_agrees(example: object) -> None:
    e = example
    assert e.agrees(), f"{e.question}: lecture {e.expected_values()}, imageform {e.computed()}"  # type: ignore[attr-defined]


def test_no_filler_rows() -> None:
    """Every row computes a number from the course: no row of yes/no flags (once, a row
    answered "1, 1, 1")."""
    from imageform.report.lecture import all_examples

    for ex in all_examples():
        values = ex.expected_values()
        assert not (len(values) > 1 and set(values) <= {0.0, 1.0}), ex.question
