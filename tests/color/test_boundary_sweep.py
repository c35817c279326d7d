"""The boundary sweep of issue 16 as a test: every public callable of imageform.spectral and
imageform.color, each parameter replaced in turn by a malformed value, gives a clean one-line
error or a finite result (see ``tests/color/_sweep.py``; run it as a module for the counts)."""

from __future__ import annotations

from collections import Counter

import pytest

from tests.color import _sweep


@pytest.fixture(scope="module")
def outcomes() -> list[_sweep.Outcome]:
    return _sweep.sweep(timeout=10.0)


def test_sweep_covers_every_public_callable() -> None:
    covered = {t.name for t in _sweep.targets()}
    assert _sweep.public_callables() - covered == set()


def test_every_baseline_call_succeeds(outcomes: list[_sweep.Outcome]) -> None:
    assert [o for o in outcomes if o.kind == "baseline"] == []


def test_no_bad_outcome(outcomes: list[_sweep.Outcome]) -> None:
    bad = [o for o in outcomes if o.outcome in _sweep.BAD]
    lines = [f"{o.outcome} {o.target}({o.param}={o.kind}): {o.detail[:150]}" for o in bad]
    assert not bad, f"{len(bad)} bad outcomes:\n" + "\n".join(lines[:40])
    counts = Counter(o.outcome for o in outcomes)
    assert counts["error"] > 3000 and counts["result"] > 900  # the sweep really ran
