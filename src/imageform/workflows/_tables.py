"""CSV tables and camera files as the geometry workflows read and write them.

A table is comma-separated; lines starting with ``#`` and blank lines are skipped; the first
line is a header when any of its cells is not a number. Empty cells and ``nan`` are NaN.
NumPy is imported when a table is converted, so declaring the workflows stays cheap.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError

__all__ = ["Table", "camera_from", "read_table", "write_table"]


@dataclass(frozen=True)
class Table:
    """A CSV table: its header (lower case, or None) and its rows as text."""

    path: Path
    header: tuple[str, ...] | None
    rows: tuple[tuple[str, ...], ...]
    lines: tuple[int, ...]

    def column(self, name: str) -> int | None:
        """Index of the column called ``name`` (case-insensitive), if the table has a header."""
        if self.header is None:
            return None
        key = name.lower()
        return self.header.index(key) if key in self.header else None

    def named(self, names: Sequence[str]) -> list[int] | None:
        """Return the indices of the columns ``names``, or None to take them by position.

        By position: no header, or a header that names none of them with as many columns.

        Raises
        ------
        InvalidInputError
            A header that names some of ``names`` but not all, or none of them with another
            number of columns: one line saying which columns are needed.
        """
        cols = [self.column(n) for n in names]
        if self.header is None:
            return None
        if None not in cols:
            return [c for c in cols if c is not None]
        needed = ", ".join(n.upper() if len(n) == 1 else n for n in names)
        shown = ", ".join(h[:20] for h in self.header[:8]) + (
            ", ..." if len(self.header) > 8 else ""
        )
        if all(c is None for c in cols) and len(self.header) == len(names):
            return None
        missing = ", ".join(
            (n.upper() if len(n) == 1 else n) for n, c in zip(names, cols, strict=True) if c is None
        )
        raise InvalidInputError(
            f"{self.path}: needs the columns {needed} (a header naming them, or {len(names)} "
            f"numbers per row without a header); its header has {shown}, no {missing}"
        )

    def numbers(
        self, columns: Sequence[int], *, finite: bool, rows: Sequence[int] | None = None
    ) -> Any:
        """Return the given columns of the given rows as floats (NaN for empty cells), (N, C)."""
        import numpy as np

        out = []
        for i in range(len(self.rows)) if rows is None else rows:
            row, line = self.rows[i], self.lines[i]
            vals = []
            for c in columns:
                cell = row[c].strip() if c < len(row) else ""
                try:
                    v = float(cell) if cell else float("nan")
                except ValueError:
                    raise InvalidInputError(
                        f"{self.path}:{line}: expected a number, got {cell[:40]!r}"
                    ) from None
                if finite and not np.isfinite(v):
                    got = repr(cell) if cell else "an empty cell"
                    raise InvalidInputError(
                        f"{self.path}:{line}: expected finite numbers, got {got}"
                    )
                vals.append(v)
            out.append(vals)
        return np.asarray(out, dtype=np.float64).reshape(len(out), len(columns))


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return not cell.strip()
    return True


def read_table(path: Path, *, columns: int | None = None, what: str = "") -> Table:
    """Read a CSV table; ``columns`` (without a header) is the number every row must have."""
    if not path.is_file():
        raise InvalidInputError(f"{path} does not exist")
    rows: list[tuple[str, ...]] = []
    lines: list[int] = []
    header: tuple[str, ...] | None = None
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            for lineno, row in enumerate(csv.reader(fh), start=1):
                if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
                    continue
                if not rows and header is None and not all(_is_number(c) for c in row):
                    header = tuple(c.strip().lower() for c in row)
                    continue
                rows.append(tuple(row))
                lines.append(lineno)
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InvalidInputError(f"{path}: not a CSV text file ({exc})") from None
    if not rows:
        raise InvalidInputError(f"{path}: no rows")
    want = len(header) if header is not None else columns
    for cells, line in zip(rows, lines, strict=True):
        if want is not None and len(cells) != want:
            raise InvalidInputError(
                f"{path}:{line}: expected {what or f'{want} columns'}, got {len(cells)} columns"
            )
    return Table(path, header, tuple(rows), tuple(lines))


def write_table(path: Path, header: Sequence[str], rows: Any) -> None:
    """Write a CSV table; floats as ``repr`` (exact round trip), NaN as ``nan``."""
    import numpy as np

    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(list(header))
        for row in rows:
            w.writerow(
                [
                    str(int(v))
                    if isinstance(v, (bool, np.bool_, int, np.integer))
                    else v
                    if isinstance(v, str)
                    else repr(float(v))
                    for v in row
                ]
            )


def camera_from(path: Path, *, need_pose: bool = False, what: str = "") -> Any:
    """Read the :class:`~imageform.io.CameraFile` at ``path``.

    ``need_pose`` refuses one without a pose, naming the file and what needs it.
    """
    from imageform.io import read_camera

    cf = read_camera(path)
    if need_pose and not cf.has_pose:
        raise InvalidInputError(
            f"camera file {path} has no pose ([pose] R or rvec, and t){what}; estimate one "
            "with imageform pose"
        )
    return cf
