"""README tells a newcomer the truth (issue 25).

Its first command must work in a fresh clone: the folder it writes (``simulation/``) was once
committed, so ``imageform simulate`` refused to overwrite it on every new clone. Its command
table must name every command the CLI has, and its extras every extra pyproject defines.
(.ci/readme-first runs the first command itself, in a fresh copy, in CI.)
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tomllib
from pathlib import Path

import click
import pytest

from imageform.cli import root

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _between(marker: str) -> str:
    m = re.search(rf"<!-- {marker} -->\n(.*?)<!-- /{marker} -->", README, re.DOTALL)
    assert m, f"README has no {marker} block"
    return m.group(1)


def test_first_command_is_marked_and_writes_simulation() -> None:
    block = _between("first-command")
    assert "imageform simulate" in block
    assert ".ci/readme-first" in (ROOT / ".ci" / "run").read_text()


@pytest.mark.skipif(
    shutil.which("git") is None or not (ROOT / ".git").exists(), reason="not a git checkout"
)
def test_first_command_output_is_neither_committed_nor_committable() -> None:
    tracked = subprocess.run(
        ["git", "ls-files", "simulation"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout
    assert not tracked, f"README's first command's output is committed:\n{tracked}"
    ignored = subprocess.run(
        ["git", "check-ignore", "-q", "simulation/report.html"], cwd=ROOT, check=False
    )
    assert ignored.returncode == 0, "simulation/ is not in .gitignore"


def test_command_table_names_every_command() -> None:
    ctx = click.Context(root)
    commands = set(root.list_commands(ctx))
    table = set(re.findall(r"^\| `([a-z-]+)` \|", README, re.MULTILINE))
    assert commands - table == set(), f"commands missing from README: {commands - table}"
    assert table - commands == set(), f"README names commands the CLI lacks: {table - commands}"


def test_every_extra_is_named() -> None:
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    line = README[README.index("Extras:") :].split("\n\n")[0]
    for extra in extras:
        assert f"`{extra}`" in line, f"extra {extra!r} is not explained in README"
