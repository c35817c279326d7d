"""Options two commands share are declared once.

``--field-order`` was declared twice, in ``track`` and ``reconstruct``, with the same words:
one edit away from two meanings. It is :func:`imageform.workflows._video.field_order_option`
in both.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path
from typing import Any

import click
import pytest

from imageform.cli._build import build_command
from imageform.workflows import WORKFLOWS

SRC = Path(__file__).resolve().parents[2] / "src" / "imageform" / "workflows"


def _field(command: str, name: str) -> dataclasses.Field[Any]:
    (f,) = [f for f in WORKFLOWS[command].options.fields() if f.name == name]
    return f


def _param(command: str, flag: str) -> click.Option:
    (p,) = [
        p
        for p in build_command(WORKFLOWS[command]).params
        if isinstance(p, click.Option) and flag in p.opts
    ]
    return p


def test_field_order_is_one_option_in_track_and_reconstruct() -> None:
    track, recon = _field("track", "field_order"), _field("reconstruct", "field_order")
    assert track.metadata == recon.metadata
    assert track.default is recon.default is None
    a, b = _param("track", "--field-order"), _param("reconstruct", "--field-order")
    assert (a.help, a.metavar, a.default) == (b.help, b.metavar, b.default)
    assert a.metavar == "[top|bottom]"


@pytest.mark.parametrize("module", ["track.py", "reconstruct.py"])
def test_field_order_is_declared_by_the_shared_option(module: str) -> None:
    tree = ast.parse((SRC / module).read_text(encoding="utf-8"))
    (decl,) = [
        n
        for n in ast.walk(tree)
        if isinstance(n, ast.AnnAssign)
        and isinstance(n.target, ast.Name)
        and n.target.id == "field_order"
    ]
    assert isinstance(decl.value, ast.Call) and isinstance(decl.value.func, ast.Name)
    assert decl.value.func.id == "field_order_option"


@pytest.mark.parametrize("command", ["track", "reconstruct"])
def test_a_bad_field_order_is_one_usage_line(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main

    args = [command, "nothere.mp4", "--field-order", "middle", "--camera", "cam.toml"]
    if command == "track":
        args += ["--board", "9x6", "--square", "30mm"]
    assert main(args) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(
        f"imageform {command}: error: unknown --field-order 'middle'; valid: top, bottom"
    ), line


FOLDER_OUTPUTS = [n for n, wf in WORKFLOWS.items() if wf.output is not None and wf.output.folder]


@pytest.mark.parametrize("name", FOLDER_OUTPUTS)
def test_a_folder_output_says_what_it_holds(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The refusal of a file name for a folder output (``reconstruct -o room.ply``) quotes
    ``Output.holds``, given by the workflow, where it parsed the option's help text; --help
    says the same words."""
    from imageform.cli import main
    from tests.cli.test_grammar import EXAMPLES

    out = WORKFLOWS[name].output
    assert out is not None and out.holds
    assert out.help.startswith(f"Output folder: {out.holds}")
    args = [name, *(["nothere"] * len(WORKFLOWS[name].inputs)), "-o", str(tmp_path / "x.json")]
    for f in WORKFLOWS[name].options.fields():
        if f.default is dataclasses.MISSING:
            args += [
                f.metadata.get("flag") or "--" + f.name.replace("_", "-"),
                str(EXAMPLES[f.name]),
            ]
    assert main(args) == 1
    assert capsys.readouterr().err.splitlines() == [
        f"imageform: error: {name} writes a folder ({out.holds}): give -o a folder name, "
        "not the file name 'x.json'"
    ]


def test_a_folder_output_without_holds_still_refuses_a_file_name(tmp_path: Path) -> None:
    from imageform.errors import InvalidInputError
    from imageform.workflows import Output, execute

    wf = dataclasses.replace(WORKFLOWS["reconstruct"], output=Output("Output folder.", folder=True))
    with pytest.raises(InvalidInputError, match=r"^reconstruct writes a folder: give -o a folder"):
        execute(wf, out=tmp_path / "room.ply", frames="nothere")
    with pytest.raises(TypeError, match="expected holds as a str"):
        Output("Output folder.", folder=True, holds=None)  # type: ignore[arg-type]
