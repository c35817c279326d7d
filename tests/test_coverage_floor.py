"""Branch coverage is measured in CI and its floor only rises (issue 30).

README's test command (the one CI runs) measures the branch coverage of ``src/imageform``
with ``--cov`` and fails under ``[tool.coverage.report] fail_under`` of pyproject.toml. This
test keeps that wiring in place and checks that the floor is never lowered: it is at least
every value it has had in the repository's history (``git log``; skipped without git or
history).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def _floor(text: str) -> float | None:
    try:
        value = tomllib.loads(text)["tool"]["coverage"]["report"]["fail_under"]
    except (tomllib.TOMLDecodeError, KeyError):
        return None
    return float(value)


def test_the_test_command_measures_branch_coverage_of_src() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    m = re.search(r"<!-- test-command -->(.*?)<!-- /test-command -->", readme, re.S)
    assert m is not None
    assert re.search(r"-m pytest\b.*\s--cov(\s|$)", m.group(1)), "README's pytest has no --cov"
    cfg = _config()
    run = cfg["tool"]["coverage"]["run"]
    assert run["branch"] is True and run["source"] == ["imageform"]
    assert any(d.startswith("pytest-cov") for d in cfg["project"]["optional-dependencies"]["test"])


def test_the_floor_only_rises() -> None:
    floor = _floor((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert floor is not None and 0.0 <= floor <= 100.0
    git = shutil.which("git")
    if git is None or not (ROOT / ".git").exists():
        pytest.skip("no git repository to read the floor's history from")
    log = subprocess.run(
        [git, "log", "--format=%H", "--", "pyproject.toml"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    if log.returncode != 0:
        pytest.skip(f"git log failed: {log.stderr.strip()[:200]}")
    earlier: list[tuple[str, float]] = []
    for sha in log.stdout.split():
        show = subprocess.run(
            [git, "show", f"{sha}:pyproject.toml"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=False,
        )
        value = _floor(show.stdout) if show.returncode == 0 else None
        if value is not None:
            earlier.append((sha[:10], value))
    lowered = [(sha, v) for sha, v in earlier if v > floor]
    assert not lowered, f"coverage floor {floor} is below its earlier value(s) {lowered}"
