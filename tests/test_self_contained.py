"""The repository is self-contained: no code, test or page refers to a file outside it, except
the test data under ``../shared/data`` (docs/design.md)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: What is scanned: everything a user or a contributor reads.
SCANNED = ("src", "tests", "docs", "examples", "benchmarks", "tools", "README.md", "CHANGELOG.md")
SUFFIXES = {".py", ".md", ".toml", ".txt", ".cfg", ".sh", ".html", ".rst"}

#: References to the design brief and style guide that lived outside the repository, and to
#: anything under ../shared but its data folder.
OUTSIDE = re.compile(r"\b(?:DESIGN|STYLE)\.md\b|\.\./shared/(?!data\b)[\w.-]+|shared/reference")


def _files() -> list[Path]:
    out: list[Path] = []
    for name in SCANNED:
        path = ROOT / name
        if path.is_file():
            out.append(path)
        elif path.is_dir():
            out += [p for p in sorted(path.rglob("*")) if p.suffix in SUFFIXES and p.is_file()]
    return [p for p in out if p.resolve() != Path(__file__).resolve()]


def test_nothing_refers_outside_the_repository() -> None:
    found = [
        f"{p.relative_to(ROOT)}:{i}: {m.group(0)}"
        for p in _files()
        for i, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
        for m in OUTSIDE.finditer(line)
    ]
    assert not found, "references outside the repository:\n" + "\n".join(found)


def test_the_design_pages_exist() -> None:
    for page in ("design.md", "conventions.md", "camera-file.md"):
        assert (ROOT / "docs" / page).is_file(), page
