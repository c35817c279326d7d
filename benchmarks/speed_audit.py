"""List the timing tables of the newest result of every benchmark, for a speed audit by hand.

For every name in ``benchmarks/results/`` (``<name>-<date><letter>.md``) the newest file (the
latest date, then letter), and in it each markdown table whose header names a time (``ms``,
``s``, ``CPU``, ``time``, ``speed``, ``ratio``, ``faster``): its header and rows, so that the rows
where imageform is slower than a peer can be picked out and written up
(``speed-audit-2026-12-01e.md`` was written from this listing; which rows compare imageform
with a peer, on the same input, is for the reader to judge from each table's own text)::

    python benchmarks/speed_audit.py > /tmp/timing-tables.txt
"""

from __future__ import annotations

import re
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
TIME = re.compile(r"\b(ms|s|CPU|time|speed|ratio|faster)\b|/ OpenCV|speed-up", re.IGNORECASE)


def newest() -> list[Path]:
    """The newest file of every benchmark name, sorted by name."""
    best: dict[str, tuple[str, Path]] = {}
    for p in RESULTS.glob("*.md"):
        m = re.match(r"(.*)-(\d{4}-\d\d-\d\d[a-z]?)$", p.stem)
        if m and (m.group(1) not in best or m.group(2) > best[m.group(1)][0]):
            best[m.group(1)] = (m.group(2), p)
    return [best[k][1] for k in sorted(best)]


def timing_tables(path: Path) -> list[list[str]]:
    """The markdown tables of ``path`` whose header names a time, each as its lines."""
    tables, cur = [], []
    for line in [*path.read_text(encoding="utf-8").splitlines(), ""]:
        if line.startswith("|"):
            cur.append(line)
            continue
        if len(cur) > 2 and TIME.search(cur[0]):
            tables.append(cur)
        cur = []
    return tables


def main() -> None:
    for p in newest():
        for table in timing_tables(p):
            print(f"## {p.name}\n")
            print("\n".join(table) + "\n")


if __name__ == "__main__":
    main()
