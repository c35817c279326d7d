"""Run the fuzz test from the command line and write its report and KNOWN table.

::

    PYTHONPATH=src python -m tests.fuzz [--budget N] [--seed S] [--workers W]
        [--timeout T] [--only PREFIX ...] [--defaults all|simple|other]
        [--report F.md] [--known OUT.py]

Without ``--budget`` every task runs (the slow test's run). ``--defaults other`` runs only
the parameters left to a default that is not a plain number or string (None, tuples of
names ...; see :func:`tests.fuzz.runner.parameters`).

``--known OUT.py`` writes a KNOWN table: this run's findings (reasons kept from
``tests/fuzz/known.py`` where the entry is already known) and every entry of
``tests/fuzz/known.py`` whose call this run did not make, so that a partial run
(``--only``, ``--budget``, ``--defaults``) never drops the findings of the calls it left out.
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
import time
from collections import Counter
from pathlib import Path

from tests.fuzz.runner import Outcome, all_tasks, findings, package_of, run, select
from tests.fuzz.table import VALID


def summary(outcomes: list[Outcome], *, seconds: float, command: str) -> str:
    """A Markdown summary: counts by outcome, by kind and by package, and the findings."""
    from tests.fuzz.known import KNOWN
    from tests.fuzz.runner import C

    n_valid = sum(isinstance(e, C) for e in VALID.values())
    found = findings(outcomes)
    new = {k: o for k, o in found.items() if k not in KNOWN}
    lines = [
        f"# Boundary fuzz run, {dt.date.today().isoformat()}",
        "",
        f"Command: `{command}`",
        "",
        f"- public callables and methods: {len(VALID)}; with a valid call: {n_valid}; "
        f"skipped: {len(VALID) - n_valid}",
        f"- calls: {len(outcomes)} in {seconds:.0f} s",
        f"- findings: {len(found)} ({len(found) - len(new)} in KNOWN, {len(new)} new)",
        "",
        "## Outcomes",
        "",
        "| outcome | calls |",
        "|---|---:|",
    ]
    for res, n in Counter(o.result for o in outcomes).most_common():
        lines.append(f"| {res} | {n} |")
    lines += ["", "## Findings by kind of malformed value", "", "| kind | findings |", "|---|---:|"]
    for kind, n in sorted(Counter(k[2] for k in found).items()):
        lines.append(f"| {kind} | {n} |")
    lines += ["", "## Findings by package", "", "| package | calls | findings |", "|---|---:|---:|"]
    calls = Counter(package_of(o.name) for o in outcomes)
    fpk = Counter(package_of(k[0]) for k in found)
    for pkg in sorted(calls):
        lines.append(f"| {pkg} | {calls[pkg]} | {fpk.get(pkg, 0)} |")
    lines += [
        "",
        "## Findings",
        "",
        "| callable | parameter | kind | outcome | detail |",
        "|---|---|---|---|---|",
    ]
    for (name, param, kind), o in sorted(found.items()):
        detail = o.detail.replace("|", "\\|").replace("\n", " ")[:160]
        lines.append(f"| `{name}` | {param} | {kind} | {o.result} | {detail} |")
    return "\n".join(lines) + "\n"


def known_source(
    outcomes: list[Outcome], known: dict[tuple[str, str, str], str] | None = None
) -> str:
    """The text of a ``known.py``: this run's findings, and the entries of ``known``
    (default: ``tests/fuzz/known.py``'s) for the calls this run did not make."""
    from tests.fuzz.runner import HARNESS_OUTCOMES

    if known is None:
        from tests.fuzz.known import KNOWN as known
    found = {k: o for k, o in findings(outcomes).items() if o.result not in HARNESS_OUTCOMES}
    ran = {(o.name, o.param, o.kind) for o in outcomes}
    kept = {k: reason for k, reason in known.items() if k not in ran}
    out = [
        "# ruff: noqa: E501",
        '"""Known findings of the fuzz test, not fixed yet (issue 16).',
        "",
        "One entry per ``(callable, parameter, kind)``: the outcome and why it is listed.",
        "Regenerate after a full run: ``PYTHONPATH=src python -m tests.fuzz --known",
        'tests/fuzz/known.py``; an entry disappears when its callable is fixed."""',
        "",
        "from __future__ import annotations",
        "",
        "KNOWN: dict[tuple[str, str, str], str] = {",
    ]
    reasons = dict(kept)
    for key, o in found.items():
        reasons[key] = known.get(key) or f"{o.result}: {o.detail}".strip().rstrip(":")
    for key, reason in sorted(reasons.items()):
        out.append(f"    {key!r}: {reason.replace(chr(10), ' ')[:160]!r},")
    out.append("}")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tests.fuzz")
    ap.add_argument("--budget", type=int, default=None)
    ap.add_argument("--seed", type=int, default=16)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--only", nargs="*", default=[])
    ap.add_argument("--defaults", choices=("all", "simple", "other"), default="all")
    ap.add_argument("--report", type=Path)
    ap.add_argument("--known", type=Path)
    ns = ap.parse_args(argv)
    tasks = all_tasks(defaults=ns.defaults)
    if ns.only:
        tasks = [t for t in tasks if any(t.name.startswith(p) for p in ns.only)]
    tasks = select(tasks, ns.budget, ns.seed)
    t0 = time.monotonic()

    def progress(done: int, total: int) -> None:
        if done % 200 == 0 or done == total:
            print(f"  {done}/{total} calls, {time.monotonic() - t0:.0f} s", file=sys.stderr)

    outcomes = run(tasks, workers=ns.workers, timeout=ns.timeout, progress=progress)
    command = "PYTHONPATH=src python -m tests.fuzz " + " ".join(argv or sys.argv[1:])
    text = summary(outcomes, seconds=time.monotonic() - t0, command=command.strip())
    if ns.report:
        ns.report.write_text(text)
    else:
        print(text)
    if ns.known:
        ns.known.write_text(known_source(outcomes))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
