"""The boundary contract of issue 16, checked by calling every public callable with
malformed arguments (see :mod:`tests.fuzz.runner`).

- :func:`test_every_public_callable_has_an_entry`: a new public name needs a valid call in
  ``tests/fuzz/table.py`` (or a ``Skip`` with a reason).
- :func:`test_fuzz_default`: every valid call, and a fixed-seed sample of the malformed
  calls (:data:`BUDGET` calls in all: today every call but those of ``table.SLOW`` and
  the KNOWN timeouts, about 10 s on one core); findings must be in ``tests/fuzz/known.py``.
- :func:`test_fuzz_full` (slow): every malformed call; also fails on KNOWN entries that no
  longer happen, so the table shrinks as fixes land (regenerate it with
  ``PYTHONPATH=src python -m tests.fuzz --known tests/fuzz/known.py``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.fuzz.known import KNOWN
from tests.fuzz.runner import (
    KINDS,
    C,
    Skip,
    all_tasks,
    findings,
    format_findings,
    new_findings,
    public_callables,
    run,
    select,
)
from tests.fuzz.table import SLOW as SLOW_CALLS
from tests.fuzz.table import VALID

#: Calls in the default run (all valid calls, then a sample of the malformed ones).
BUDGET = 8000
SEED = 16
#: Seconds per call; a call past this is a finding ("timeout").
TIMEOUT = 30.0
#: Outcomes left out of the default run when KNOWN: each costs the whole timeout.
_SLOW = ("timeout", "crash")


def test_every_public_callable_has_an_entry() -> None:
    funcs = public_callables()
    missing = sorted(n for n in funcs if n not in VALID)
    stale = sorted(n for n in VALID if n not in funcs)
    assert not missing, (
        "public callables without an entry in tests/fuzz/table.py (add a valid call; "
        f"`python -m tests.fuzz.bootstrap` drafts one): {missing}"
    )
    assert not stale, f"entries in tests/fuzz/table.py for names no longer public: {stale}"
    for name, entry in VALID.items():
        assert isinstance(entry, C | Skip), name
        if isinstance(entry, Skip):
            assert entry.reason.strip(), f"{name}: a Skip needs a reason"


def test_known_entries_are_well_formed() -> None:
    funcs = public_callables()
    for (name, param, kind), reason in KNOWN.items():
        assert name in funcs, f"KNOWN entry for a name no longer public: {name}"
        assert kind in KINDS or (kind == "valid" and not param), (name, kind)
        assert reason.strip(), (name, param, kind)


def _default_tasks() -> list:
    slow = {k for k, reason in KNOWN.items() if reason.startswith(_SLOW)}
    tasks = [
        t for t in all_tasks() if (t.name, t.param, t.kind) not in slow and t.name not in SLOW_CALLS
    ]
    return select(tasks, BUDGET, SEED)


def test_fuzz_default() -> None:
    outcomes = run(_default_tasks(), workers=1, timeout=TIMEOUT)
    new = new_findings(outcomes, KNOWN)
    assert not new, (
        f"{len(new)} call(s) broke the boundary contract (fix them, or list them in "
        f"tests/fuzz/known.py with a reason):\n{format_findings(new)}"
    )


@pytest.mark.slow
def test_fuzz_full() -> None:
    outcomes = run(all_tasks(), workers=2, timeout=TIMEOUT)
    new = new_findings(outcomes, KNOWN)
    assert not new, f"{len(new)} new finding(s):\n{format_findings(new)}"
    found = findings(outcomes)
    fixed = sorted(k for k in KNOWN if k not in found)
    assert not fixed, (
        f"{len(fixed)} KNOWN finding(s) no longer happen: regenerate tests/fuzz/known.py "
        f"(python -m tests.fuzz --known tests/fuzz/known.py): {fixed[:20]}"
    )


def test_parameters_left_to_any_default_are_fuzzed() -> None:
    """Issue 25: a parameter whose default is None or not a plain value is mutated too."""
    from tests.fuzz.runner import mutations, parameters

    def f(x: float, *, a: float = 1.0, b: object = None, c: tuple = ("u", "v")) -> None:
        """A toy callable."""

    entry = C((2.0,))
    assert parameters(f, entry) == {"x": 2.0, "a": 1.0, "b": None, "c": ("u", "v")}
    assert parameters(f, entry, defaults="simple") == {"x": 2.0, "a": 1.0}
    assert parameters(f, entry, defaults="other") == {"b": None, "c": ("u", "v")}
    kinds = mutations(None)
    assert "none" not in kinds and {"complex", "huge", "object", "nan"} <= set(kinds)


def test_a_partial_run_keeps_the_known_entries_it_did_not_run() -> None:
    """``--known`` after ``--only``/``--budget``: entries of calls not made stay listed;
    those made and now clean go; new findings come in."""
    from tests.fuzz.__main__ import known_source
    from tests.fuzz.runner import Outcome

    known = {
        ("m.f", "x", "nan"): "raw:ValueError: kept, not run",
        ("m.g", "x", "nan"): "raw:ValueError: fixed since",
    }
    outcomes = [
        Outcome("m.g", "x", "nan", "clean"),
        Outcome("m.g", "x", "inf", "raw:OverflowError", "OverflowError: boom"),
    ]
    ns: dict = {}
    exec(known_source(outcomes, known), ns)
    assert ns["KNOWN"] == {
        ("m.f", "x", "nan"): "raw:ValueError: kept, not run",
        ("m.g", "x", "inf"): "raw:OverflowError: OverflowError: boom",
    }


def test_a_short_parameter_name_is_found_only_as_a_word() -> None:
    """Issue 25: ``R`` is named by "expected R of shape ...", not by the r of "error"."""
    from tests.fuzz.runner import _names_param

    assert _names_param("expected R of shape (3, 3), got (2, 2)", "R")
    assert not _names_param("expected a rotation matrix, got an error", "R")
    assert _names_param("expected max-iter >= 1", "max_iter")
    assert _names_param("image_size (width, height)[0]: expected ...", "image_size")
    assert not _names_param("expected xyz of shape (..., 3)", "xy")


def test_values_remove_their_temporary_folders(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.fuzz.values import V, remove_tmpdirs, resolve

    monkeypatch.setenv("IMAGEFORM_FUZZ_TMP", str(tmp_path))
    folder = resolve(V("tmpdir"))
    resolve(V("tmpfile_png")).write_bytes(b"x")
    (folder / "f.txt").write_text("x")
    assert len(list(tmp_path.iterdir())) == 2
    remove_tmpdirs()  # also registered with atexit
    assert list(tmp_path.iterdir()) == []


def test_a_run_leaves_no_temporary_folder(tmp_path: Path) -> None:
    # the workers' folders and the values' temporary files (about 33 imageform-fuzz-* folders
    # per default run were left in /tmp): removed when the run ends, also those of a worker
    # killed (on a timeout or a crash), which cannot remove its own
    import multiprocessing
    import signal

    tasks = [t for t in all_tasks() if t.name == "imageform.batch.plan_jobs"][:2]
    assert len(tasks) == 2
    seen: list[list[Path]] = []

    def kill_the_worker_at_the_end(done: int, total: int) -> None:
        if done == total:
            seen.append([p for d in tmp_path.iterdir() for p in d.iterdir()])
            for p in multiprocessing.active_children():
                os.kill(p.pid, signal.SIGKILL)
                p.join()

    outcomes = run(
        tasks, workers=1, timeout=TIMEOUT, progress=kill_the_worker_at_the_end, tmp=tmp_path
    )
    assert [o.result for o in outcomes if o.kind == "valid"] == ["ok"]
    assert seen and seen[0]  # the killed worker's folder (with the values' files) was there
    assert list(tmp_path.iterdir()) == []
