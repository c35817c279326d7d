"""Known findings of the fuzz test, not fixed yet (issue 16).

One entry per ``(callable, parameter, kind)``: the outcome and why it is listed.
Regenerate after a full run: ``PYTHONPATH=src python -m tests.fuzz --known
tests/fuzz/known.py``; an entry disappears when its callable is fixed."""

from __future__ import annotations

KNOWN: dict[tuple[str, str, str], str] = {
    # normalize_choice names the value by its caller's label (``what``: "--method" on the
    # command line, "thing" in the table's call), as users see it: "unknown --method 'x';
    # valid: ...". Kept on purpose.
    ("imageform.workflows.normalize_choice", "value", "empty"): (
        "unnamed: by design, named by the caller's label: unknown thing ''; valid: a, b"
    ),
    ("imageform.workflows.normalize_choice", "value", "huge"): (
        "unnamed: by design, named by the caller's label: unknown thing 'xxx...'; valid: a, b"
    ),
}
