"""One command-line grammar for every command, checked on the registry itself.

Inputs positional, the main output ``-o/--out``, ``--force`` where anything is written,
``--json`` everywhere, names with ``-`` or ``_`` alike, full summaries in ``imageform --help``,
and every ``imageform ...`` line of the docs parses.
"""

from __future__ import annotations

import dataclasses
import re
import shlex
from pathlib import Path

import click
import pytest

from imageform.cli import EXIT_CODES, main, root
from imageform.cli._build import build_command
from imageform.workflows import WORKFLOWS, choice_names
from imageform.workflows._spec import IMAGE_SUFFIXES, flag_of

ROOT = Path(__file__).resolve().parents[2]

#: A valid value for each required option (a new required option needs one here).
EXAMPLES = {
    "board": "9x6",
    "square": "30mm",
    "deficiency": "deutan",
    "camera": "cam.toml",
    "focal": "50mm",
    "f_number": 2.8,
    "focus": "2m",
    "target": "ref.png",
    "correction": "corr.json",
}


#: Options the EXAMPLES need though the grammar does not require them: track's --square (a
#: board's square, which --board aruco:ID does not take).
NEEDED = {"track": {"square": "30mm"}}


def _required(wf: object) -> dict[str, object]:
    """A valid value for each required option of ``wf`` (and those EXAMPLES need)."""
    fields = wf.options.fields()  # type: ignore[attr-defined]
    out = {f.name: EXAMPLES[f.name] for f in fields if f.default is dataclasses.MISSING}
    return {**out, **NEEDED.get(wf.name, {})}  # type: ignore[attr-defined]


def _flags(cmd: click.Command) -> set[str]:
    return {
        o
        for p in cmd.params
        if isinstance(p, click.Option)
        for o in (*p.opts, *p.secondary_opts)  # --x/--no-x flags: both spellings
    }


@pytest.mark.parametrize("name", list(WORKFLOWS))
def test_every_command_has_the_common_flags(name: str) -> None:
    wf = WORKFLOWS[name]
    cmd = build_command(wf)
    flags = _flags(cmd)
    assert "--json" in flags
    writes = wf.output is not None or any(f.metadata.get("output") for f in wf.options.fields())
    assert ("--force" in flags) == writes
    if wf.output is not None:
        assert {"-o", "--out"} <= flags
    assert "--output" not in flags, "the main output is -o/--out"
    if wf.batch:  # one file in, one image out: what imageform batch runs per file
        assert len(wf.inputs) == 1 and wf.inputs[0].kind == "file" and wf.output is not None


@pytest.mark.parametrize("name", list(WORKFLOWS))
def test_names_accept_both_spellings(name: str) -> None:
    """Every valid name of every option is accepted as written with - and with _."""
    wf = WORKFLOWS[name]
    required = _required(wf)
    for f in wf.options.fields():
        if f.metadata.get("choices") is None:
            continue
        for valid in choice_names(f.metadata["choices"]):
            for spelt in (valid.replace("_", "-"), valid.upper()):
                opts = wf.make_options(**{**required, f.name: spelt})
                assert getattr(opts, f.name) == valid


def test_root_help_lists_every_command_in_full(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    text = "".join(capsys.readouterr().out.split())
    for wf in WORKFLOWS.values():
        assert "".join(wf.summary.split()) in text, wf.name  # wrapped, never cut off
    for code, meaning in EXIT_CODES.items():
        assert f"{code}{''.join(meaning.split())}" in text


def test_unknown_values_and_commands_are_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["white-balance", "x.png", "-o", "y.png", "--method", "nope"]) == 2
    assert "valid: gray-world, white-patch" in capsys.readouterr().err
    assert main(["no-such-command"]) == 2
    assert main(["convert", "x.png", "-o", "y.png", "--no-such-flag"]) == 2


def _doc_commands() -> list[tuple[str, str]]:
    lines: list[tuple[str, str]] = []
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    for page in pages:
        in_block, pending = False, ""
        for raw in page.read_text(encoding="utf-8").splitlines():
            if raw.startswith("```"):
                in_block = raw.strip() in ("```bash", "```sh", "```console", "```shell")
                continue
            line = pending + " " + raw.split(" #")[0].strip().removeprefix("$ ")
            line = line.strip()
            if line.endswith("\\"):
                pending = line[:-1]
                continue
            pending = ""
            if in_block and line.startswith("imageform "):
                lines.append((page.name, line))
        for inline in re.findall(r"`(imageform [^`]+)`", page.read_text(encoding="utf-8")):
            lines.append((page.name, "inline: " + inline))
    return lines


@pytest.mark.parametrize(("page", "line"), _doc_commands())
def test_doc_command_lines_parse(page: str, line: str) -> None:
    """Each shell example in the docs names a real command and valid options (a mention in
    the text, `imageform calibrate --corners`, names a real command and real options)."""
    inline = line.startswith("inline: ")
    args = shlex.split(line.removeprefix("inline: "))[1:]
    if not args or args[0].startswith("-") or "..." in line or "COMMAND" in line:
        return
    ctx = root.make_context("imageform", [args[0]], resilient_parsing=True)
    cmd = root.get_command(ctx, args[0])
    assert cmd is not None, f"{page}: unknown command in `{line}`"
    if not args[1:]:
        return
    if isinstance(cmd, click.Group):  # imageform batch COMMAND ...: its subcommand parses
        if args[1].startswith("-"):
            return
        sub = cmd.get_command(ctx, args[1])
        assert sub is not None, f"{page}: unknown command in `{line}`"
        cmd, args = sub, args[1:]
    if inline:
        known = _flags(cmd) | {"--help", "-h"}
        for token in args[1:]:
            flag = token.split("=")[0]
            assert not flag.startswith("-") or flag in known, (
                f"{page}: no option {flag} in `{line}`"
            )
        return
    try:
        cmd.make_context(args[0], args[1:], parent=ctx)
    except click.exceptions.Exit:
        pass
    except click.UsageError as exc:
        pytest.fail(f"{page}: `{line}`: {exc.format_message()}")


def _defaults(cmd: click.Command) -> dict[str, object]:
    return {p.name: p.default for p in cmd.params if isinstance(p, click.Option) and p.name}


@pytest.mark.parametrize("name", [n for n, w in WORKFLOWS.items() if w.batch])
def test_batch_takes_the_commands_options_and_defaults(name: str) -> None:
    """`imageform batch NAME` is generated from the same workflow: every option of the single
    command, with the same default (Macenko for stain-normalize in both)."""
    ctx = root.make_context("imageform", ["batch"], resilient_parsing=True)
    group = root.get_command(ctx, "batch")
    assert isinstance(group, click.Group) and name in group.list_commands(ctx)
    sub = group.get_command(ctx, name)
    assert sub is not None
    wf = WORKFLOWS[name]
    single = build_command(wf)
    extra_outputs = {f.name for f in wf.options.fields() if f.metadata.get("output")}
    per_run = {o for p in single.params if p.name in extra_outputs for o in p.opts}
    assert _flags(single) - per_run <= _flags(sub)  # an extra output is one file per run
    assert not per_run & _flags(sub)
    defaults = _defaults(sub)
    for key, value in _defaults(single).items():
        if key not in ("out", "force", "json_out", *extra_outputs):
            assert defaults[key] == value, key
    assert {"--scheduler", "--workers", "--suffix", "--force", "--json", "-o"} <= _flags(sub)


def test_stain_normalize_defaults_to_macenko_everywhere() -> None:
    from imageform.batch import batch_options

    wf = WORKFLOWS["stain-normalize"]
    assert wf.make_options(target="t.png").method == "macenko"
    assert batch_options("stain-normalize", {"target": "t.png"}).method == "macenko"


def test_no_command_is_bridged() -> None:
    """Every command is generated (no typer command passed through unparsed)."""
    ctx = root.make_context("imageform", ["--help"], resilient_parsing=True)
    for name in root.list_commands(ctx):
        cmd = root.get_command(ctx, name)
        assert cmd is not None
        subs = [cmd]
        if isinstance(cmd, click.Group):
            subs = [cmd.get_command(ctx, n) for n in cmd.list_commands(ctx)]
        for sub in subs:
            assert sub is not None
            assert not any(getattr(p, "type", None) is click.UNPROCESSED for p in sub.params)


@pytest.mark.parametrize(
    "name", [n for n, w in WORKFLOWS.items() if "bit_depth" in {f.name for f in w.options.fields()}]
)
def test_the_old_bits_flag_stays_hidden_beside_bit_depth(name: str) -> None:
    """Issue 30: ``--bit-depth`` is the flag; ``--bits`` (its old spelling) is still taken,
    hidden, on the command and in ``imageform batch``, and ``bits=`` by the options class."""
    wf = WORKFLOWS[name]
    assert getattr(wf.options, "__renamed_fields__", {}).get("bits") == "bit_depth"
    cmd = build_command(wf)
    old = [p for p in cmd.params if isinstance(p, click.Option) and "--bits" in p.opts]
    assert len(old) == 1 and old[0].hidden and "--bit-depth" in _flags(cmd)
    required = _required(wf)
    with pytest.warns(DeprecationWarning, match="use bit_depth="):
        assert wf.options(**required, bits=16).bit_depth == 16


#: Numeric options of a measured quantity, and a unit their --help must name.
UNITS = {
    ("project", "cx"): "pixels",
    ("project", "cy"): "pixels",
    ("project", "skew"): "pixels",
    ("triangulate", "sigma"): "px",
    ("calibrate", "half_window"): "pixels",
    ("stereo-calibrate", "half_window"): "pixels",
    ("track", "fps"): "frames/s",
    ("flatfield", "working_size"): "pixels",
    ("segment", "s"): "0-1 (OpenCV's 0-255 with --opencv-ranges)",
    ("segment", "v"): "0-1 (OpenCV's 0-255 with --opencv-ranges)",
    ("segment", "h"): "degrees, 0-360 (OpenCV's 0-180",
    ("sfr", "roi"): "in pixels",
}


@pytest.mark.parametrize(("name", "field"), list(UNITS))
def test_measured_options_say_their_unit(name: str, field: str) -> None:
    """A newcomer reading --help learns the unit of a number (found missing walking the docs)."""
    (f,) = [f for f in WORKFLOWS[name].options.fields() if f.name == field]
    assert UNITS[name, field] in f.metadata["help"]


def _path_flags(name: str) -> list[str]:
    cmd = build_command(WORKFLOWS[name])
    return [
        p.opts[-1]
        for p in cmd.params
        if isinstance(p, click.Option) and isinstance(p.type, click.Path) and not p.hidden
    ]


@pytest.mark.parametrize(
    ("name", "flag"), [(n, f) for n in WORKFLOWS for f in _path_flags(n)], ids=str
)
def test_a_file_option_without_its_value_names_it(
    name: str, flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--corners --plot p.png`` forgot the corners' file: a usage error naming --corners,
    not a file named --plot and 'input file p.png does not exist' after the work."""
    assert main([name, flag, "--json"]) == 2
    err = capsys.readouterr().err
    assert "a file name is missing: got the option --json instead" in err, err
    assert f"'{flag}'" in err


#: The commands whose output is a data file (TOML, CSV, JSON) or a figure (SVG, PDF).
DATA_OUTPUTS = [
    (name, wf.suffixes)
    for name, wf in WORKFLOWS.items()
    if wf.output is not None and set(wf.suffixes) - set(IMAGE_SUFFIXES)
]


@pytest.mark.parametrize(("name", "suffixes"), DATA_OUTPUTS, ids=[n for n, _ in DATA_OUTPUTS])
def test_a_data_output_under_another_name_is_refused_first(
    name: str, suffixes: tuple[str, ...], tmp_path: Path
) -> None:
    """``calibrate -o cam.json`` wrote TOML into a .json file, ``emva -o e.png`` JSON into a
    .png, ``gamut -o g.txt`` failed in matplotlib: refused before any input is read (the inputs
    here do not exist)."""
    from imageform.errors import InvalidInputError
    from imageform.workflows import execute

    wf = WORKFLOWS[name]
    required = _required(wf)
    if name == "project":  # a camera: a file or a focal length
        required["fx"] = 500.0
    inputs = {i.name: ["nothere.png"] if i.many else "nothere.png" for i in wf.inputs}
    out = tmp_path / "result.txt"
    with pytest.raises(InvalidInputError, match=rf"{name} writes a .* file: give -o a "):
        execute(wf, out=out, options=wf.make_options(**required), **inputs)
    assert not out.exists()


#: The commands whose output is one image file.
IMAGE_OUTPUTS = [
    name
    for name, wf in WORKFLOWS.items()
    if wf.output is not None
    and not wf.output.folder
    and not set(wf.suffixes) - {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".npy", ".pgm", ".ppm"}
]


@pytest.mark.parametrize("name", IMAGE_OUTPUTS)
def test_an_image_output_under_another_name_is_refused_first(name: str, tmp_path: Path) -> None:
    """``undistort -o u.json`` (and every image command) computed the whole result and then
    failed in the writer with 'unknown image file type': refused before any input is read
    (the inputs here do not exist), naming the suffixes the command writes."""
    from imageform.errors import InvalidInputError
    from imageform.workflows import execute

    wf = WORKFLOWS[name]
    required = _required(wf)
    inputs = {i.name: ["nothere.png"] if i.many else "nothere.png" for i in wf.inputs}
    out = tmp_path / "result.json"
    kinds = ", ".join(wf.suffixes[:-1]) + f" or {wf.suffixes[-1]}"
    with pytest.raises(InvalidInputError, match=rf"^{name} writes an image: give -o a {kinds} "):
        execute(wf, out=out, options=wf.make_options(**required), **inputs)
    assert not out.exists()


def _doc_blocks() -> list[tuple[str, list[str]]]:
    """Each shell block of the docs as the list of its imageform command lines, in order."""
    blocks: list[tuple[str, list[str]]] = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        in_block, pending, lines = False, "", []
        for raw in page.read_text(encoding="utf-8").splitlines():
            if raw.startswith("```"):
                if lines:
                    blocks.append((page.name, lines))
                lines = []
                in_block = raw.strip() in ("```bash", "```sh", "```console", "```shell")
                continue
            line = (pending + " " + raw.split(" #")[0].strip().removeprefix("$ ")).strip()
            if line.endswith("\\"):
                pending = line[:-1]
                continue
            pending = ""
            if in_block and line.startswith("imageform "):
                lines.append(line)
    return blocks


def test_a_doc_block_run_in_order_never_stops_on_its_own_output() -> None:
    """A newcomer pastes a block's lines in order: a line that writes what an earlier line of
    the block wrote needs --force, or it stops with 'output ... exists' (found walking
    white-balance.md, biomedical.md, geometry.md and reconstruction.md). imageform batch
    resumes into its folder and is left out."""
    stops = []
    for page, lines in _doc_blocks():
        written: set[str] = set()
        for line in lines:
            args = shlex.split(line)
            outs = {args[i + 1] for i, t in enumerate(args[:-1]) if t in ("-o", "--out")}
            if args[1] != "batch" and "--force" not in args and outs & written:
                stops.append(f"{page}: `{line}`")
            written |= outs
    assert not stops, stops


FOLDER_OUTPUTS = [n for n, wf in WORKFLOWS.items() if wf.output is not None and wf.output.folder]


@pytest.mark.parametrize("name", FOLDER_OUTPUTS)
def test_a_folder_output_is_not_given_a_file_name(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``reconstruct -o room.ply`` made a folder named room.ply holding points.ply: refused
    before the inputs are read (they do not exist here), saying what the folder holds."""
    wf = WORKFLOWS[name]
    args = [name, *(["nothere"] * len(wf.inputs)), "-o", str(tmp_path / "result.json")]
    required = [f for f in wf.options.fields() if f.default is dataclasses.MISSING]
    for f in required:
        args += [flag_of(f), str(EXAMPLES[f.name])]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert f"{name} writes a folder (" in err and "not the file name 'result.json'" in err, err
    assert list(tmp_path.iterdir()) == []
