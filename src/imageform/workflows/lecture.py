"""``imageform lecture``: the course's worked examples, computed by the library."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from imageform.errors import UnknownOptionError
from imageform.workflows._spec import Options, Result, Run, Workflow, option

__all__ = ["WORKFLOWS", "LectureOptions"]


@dataclass(frozen=True, kw_only=True)
class LectureOptions(Options):
    """Options of ``imageform lecture``."""

    topic: str | None = option(
        None, help="Only the examples whose topic contains this text (e.g. pinhole, gamut)."
    )

    def check(self) -> None:
        """Check that ``--topic``, when given, matches a lecture topic."""
        super().check()
        if self.topic is not None:
            from imageform._validate import shorten_names
            from imageform.report.lecture import lecture_topics

            topics = lecture_topics()
            if not any(self.topic.strip().lower() in t.lower() for t in topics):
                raise UnknownOptionError(
                    f"no lecture topic matches --topic {self.topic[:40]!r}; "
                    f"valid: {shorten_names(topics, 90)}"
                )


def lecture(run: Run, opts: LectureOptions, *, out: None) -> Result:
    """Tabulate every worked example and numeric practice answer, the reader's value beside ours.

    The check fails (exit 3) if one disagrees.
    """
    from rich.table import Table

    from imageform.report.lecture import all_examples

    wanted = (opts.topic or "").strip().lower()
    rows: list[dict[str, Any]] = []
    for e in all_examples():
        if wanted and wanted not in e.topic.lower():
            continue
        rows.append(
            {
                "topic": e.topic,
                "question": e.question,
                "formula": e.formula,
                "lecture": list(e.expected_values()),
                "imageform": list(e.computed()),
                "unit": e.unit,
                "agrees": e.agrees(),
            }
        )
    table = Table(title="The lecture's worked examples, computed by imageform", show_lines=True)
    for col in ("topic", "question", "formula", "lecture", "imageform", "unit", "ok"):
        table.add_column(col, overflow="fold")
    for r in rows:
        table.add_row(
            r["topic"],
            r["question"],
            r["formula"],
            ", ".join(f"{v:g}" for v in r["lecture"]),
            ", ".join(f"{v:.6g}" for v in r["imageform"]),
            r["unit"],
            "yes" if r["agrees"] else "NO",
        )
    ok = all(r["agrees"] for r in rows)
    return Result({"examples": rows, "all_agree": ok}, (table,), check_failed=not ok)


WORKFLOWS = (
    Workflow(
        "lecture",
        "Print every worked example of the course, the reader's value beside imageform's.",
        "imageform.workflows.lecture:lecture",
        LectureOptions,
        group="simulation",
        description="Exit code 3 if a computed value disagrees with the reader's.",
    ),
)
