"""``imageform lecture``: the lecture's worked examples, computed by the library."""

from __future__ import annotations

from typing import Any

import typer

__all__ = ["register"]


def lecture(
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
    topic: str = typer.Option("", help="Only examples whose topic contains this text."),
) -> None:
    """Every worked example and numeric practice answer of the lecture, computed by imageform."""
    from rich.console import Console
    from rich.table import Table

    from imageform.cli._common import print_json
    from imageform.report.lecture import all_examples

    examples = [e for e in all_examples() if topic.lower() in e.topic.lower()]
    rows: list[dict[str, Any]] = []
    for e in examples:
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
    if json_out:
        print_json(rows)
    else:
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
        Console(width=160).print(table)
    if not all(r["agrees"] for r in rows):
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("lecture")(lecture)
