# ruff: noqa: E501
"""Known findings of the fuzz test, not fixed yet (issue 16).

One entry per ``(callable, parameter, kind)``: the outcome and why it is listed.
Regenerate after a full run: ``PYTHONPATH=src python -m tests.fuzz --known
tests/fuzz/known.py``; an entry disappears when its callable is fixed."""

from __future__ import annotations

KNOWN: dict[tuple[str, str, str], str] = {
}
