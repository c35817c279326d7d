"""A usage error is one line on stderr, exit 2 (docs/design.md, Errors; docs/conventions.md).

``imageform X: error: <reason> (see 'imageform X --help')``: the command as typed, why, and
where its options are listed. click's own four lines (usage, hint, blank line, ``Error:``) were
what a newcomer walking the docs met instead.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from imageform.cli import main


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (
            ["--no-such-flag"],
            "imageform: error: No such option '--no-such-flag'. (see 'imageform --help')",
        ),
        (
            ["no-such-command"],
            "imageform: error: No such command 'no-such-command'. (see 'imageform --help')",
        ),
        (
            ["track", "v.mp4", "-o", "poses.csv"],
            "imageform track: error: Missing option '--camera'. (see 'imageform track --help')",
        ),
        (
            ["batch", "no-such-command"],
            "imageform batch: error: No such command 'no-such-command'. "
            "(see 'imageform batch --help')",
        ),
        (
            ["chunked", "convert", "in.tif", "-o", "out.tif", "--chunk", "0"],
            "imageform chunked convert: error: Invalid value for '--chunk': 0 is not in the range "
            "1<=x<=16384. (see 'imageform chunked convert --help')",
        ),
    ],
    ids=["root-option", "root-command", "missing", "batch", "chunked-range"],
)
def test_a_usage_error_is_one_line(
    args: list[str], line: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(args) == 2
    out, err = capsys.readouterr()
    assert err.splitlines() == [line]
    assert out == ""


@pytest.mark.parametrize(
    ("args", "head"),
    [
        (
            ["convert", "x.png", "-o", "y.png", "--no-such-flag"],
            "imageform convert: error: No such option '--no-such-flag'.",
        ),
        (
            ["white-balance", "x.png", "-o", "y.png", "--method", "nope"],
            "imageform white-balance: error: unknown --method 'nope'; valid: gray-world, ",
        ),
    ],
)
def test_a_command_s_usage_error_names_the_command(
    args: list[str], head: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(args) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(head)
    assert line.endswith(f" (see 'imageform {args[0]} --help')")


def test_a_command_alone_still_prints_its_help(capsys: pytest.CaptureFixture[str]) -> None:
    """No arguments at all is a request for help, not a mistake to explain in one line."""
    assert main(["white-balance"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("Usage: imageform white-balance [OPTIONS] IMAGE")
    assert "--method" in err


@pytest.mark.parametrize(
    ("typed", "suggestion"),
    [
        ("--bit", "(Did you mean '--bit-depth'?)"),  # click offered --bits, --to, --white
        ("--bi", "(Did you mean '--bit-depth'?)"),
        ("--too", "(Did you mean '--to'?)"),
        ("--white-pt", "(Did you mean '--white'?)"),
    ],
)
def test_an_unknown_option_suggests_only_options_help_lists(
    typed: str, suggestion: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Suggestions come from the visible options (never the hidden deprecated ``--bits``),
    those that start with what was typed first."""
    assert main(["convert", typed, "in.png", "-o", "out.png"]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"imageform convert: error: No such option '{typed}'. {suggestion} "
        "(see 'imageform convert --help')\n"
    )
    assert "--bits" not in err


def test_an_unknown_option_far_from_every_option_suggests_nothing(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["convert", "--bogus", "in.png", "-o", "out.png"]) == 2
    assert capsys.readouterr().err == (
        "imageform convert: error: No such option '--bogus'. (see 'imageform convert --help')\n"
    )
