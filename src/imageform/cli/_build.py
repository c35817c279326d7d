"""The ``imageform`` command line, generated from the workflow registry.

One grammar for every command: inputs are positional; the main output is ``-o/--out``;
``--force`` overwrites existing outputs; ``--json`` prints the machine-readable result;
method and option names may be spelt with ``-`` or ``_``. Commands are built only when used,
so ``imageform --help`` imports no numerical code.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import types
import typing
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from imageform._files import glob_paths
from imageform.errors import ImageformError, InvalidInputError
from imageform.workflows import Result, Workflow, choice_names, flag_of

__all__ = [
    "EXIT_CODES",
    "CommandExit",
    "build_command",
    "emit",
    "expand_inputs",
    "option_params",
    "take_old_flags",
]

#: Exit codes of every command.
EXIT_CODES = {
    0: "success",
    1: "failure (one line on stderr says why)",
    2: "bad usage (unknown option or value)",
    3: "a check the command performs failed (palette-check, lecture)",
    130: "interrupted (Ctrl-C); nothing new was left behind",
}


class CommandExit(Exception):
    """Leave a command with an exit code (caught by :func:`imageform.cli.main`)."""

    def __init__(self, code: int) -> None:
        super().__init__(code)
        self.code = code


# ---------------------------------------------------------------- parameters from options


def _unwrap(tp: Any) -> tuple[Any, bool]:
    """(type, optional) from ``X | None``."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0], True
    return tp, False


class _PathValue(click.Path):
    """A file name that is not one of the command's own flags.

    ``--corners --plot p.png`` would otherwise write the corners to a file named ``--plot``
    and take ``p.png`` for an input ("input file p.png does not exist"): a forgotten value.
    """

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and value.startswith("-") and ctx is not None:
            flags = {
                o
                for p in ctx.command.params
                if isinstance(p, click.Option)
                for o in (*p.opts, *p.secondary_opts)
            }
            if value in flags | {"-h", "--help"}:
                self.fail(f"a file name is missing: got the option {value} instead", param, ctx)
        return super().convert(value, param, ctx)


def _click_type(tp: Any) -> Any:
    if tp is Path:
        return _PathValue(path_type=Path, dir_okay=True)
    return {int: click.INT, float: click.FLOAT, str: click.STRING}.get(tp, click.STRING)


def _choices_text(choices: Any) -> str:
    try:
        names = choice_names(choices)
    except Exception:  # pragma: no cover - a broken reference shows no list
        return ""
    return " [" + "|".join(n.replace("_", "-") for n in names) + "]"


def option_params(wf: Workflow) -> list[click.Parameter]:
    """Return the click options of a workflow's options dataclass (flags, types, defaults, help)."""
    params: list[click.Parameter] = []
    hints = wf.options.types()
    for f in wf.options.fields():
        tp, optional = _unwrap(hints[f.name])
        meta = f.metadata
        decls = [flag_of(f), f.name]
        if meta.get("short"):
            decls.append(meta["short"])
        help_text = meta.get("help", "")
        default = None if f.default is dataclasses.MISSING else f.default
        kw: dict[str, Any] = {"help": help_text, "hidden": bool(meta.get("hidden"))}
        if meta.get("metavar"):
            kw["metavar"] = meta["metavar"]
        elif meta.get("choices") is not None:
            kw["metavar"] = _choices_text(meta["choices"]).strip()
        origin = typing.get_origin(tp)
        if tp is bool:
            if default:
                decls = [f"{flag_of(f)}/--no-{flag_of(f)[2:]}", f.name]
            params.append(click.Option(decls, is_flag=True, default=bool(default), **kw))
            continue
        if origin is tuple:
            args = typing.get_args(tp)
            if len(args) == 2 and args[1] is Ellipsis:
                params.append(click.Option(decls, type=_click_type(args[0]), multiple=True, **kw))
            else:
                params.append(
                    click.Option(
                        decls, type=_click_type(args[0]), nargs=len(args), default=default, **kw
                    )
                )
            continue
        shown = default is not None and not isinstance(default, Path)
        if isinstance(default, str):
            default = default.replace("_", "-") if meta.get("choices") is not None else default
        if f.default is not dataclasses.MISSING:  # click >= 8.3: default=None is a value
            kw["default"] = default
        params.append(
            click.Option(
                decls,
                type=_click_type(tp),
                show_default=shown,
                required=f.default is dataclasses.MISSING and not optional,
                **kw,
            )
        )
    params += _old_flags(wf)
    return params


def _renamed(wf: Workflow) -> dict[str, dataclasses.Field[Any]]:
    """Return the old names of a workflow's options fields (kept one release): old -> field."""
    fields = {f.name: f for f in wf.options.fields()}
    renamed: dict[str, str] = getattr(wf.options, "__renamed_fields__", {})
    return {old: fields[new] for old, new in renamed.items()}


def _old_flags(wf: Workflow) -> list[click.Parameter]:
    """Hidden options under the old flags of renamed fields (``--bits``: ``--bit-depth``).

    :func:`take_old_flags` turns their values into the new fields', with a note.
    """
    params: list[click.Parameter] = []
    hints = wf.options.types()
    for old, f in _renamed(wf).items():
        tp, _ = _unwrap(hints[f.name])
        if tp is bool or typing.get_origin(tp) is tuple:  # pragma: no cover - none yet
            raise TypeError(f"{old}: only a scalar option keeps its old flag")
        params.append(
            click.Option(
                ["--" + old.replace("_", "-"), old],
                type=_click_type(tp),
                default=None,
                hidden=True,
                help=f"Deprecated: {flag_of(f)}.",
            )
        )
    return params


def take_old_flags(wf: Workflow, kw: dict[str, Any]) -> dict[str, Any]:
    """Give the values of old flags (:func:`_old_flags`) to their new fields, with a note each.

    ``kw`` are the command's values by parameter name; an old flag and its new one together
    are a usage error.
    """
    from imageform._deprecate import REMOVED_IN

    for old, f in _renamed(wf).items():
        value = kw.pop(old, None)
        if value is None:
            continue
        old_flag, new_flag = "--" + old.replace("_", "-"), flag_of(f)
        if kw.get(f.name) not in (None, f.default):
            raise click.UsageError(f"give {new_flag} or the deprecated {old_flag}, not both")
        click.echo(
            f"imageform: note: {old_flag} is deprecated and will be removed in imageform "
            f"{REMOVED_IN}; use {new_flag}",
            err=True,
        )
        kw[f.name] = value
    return kw


# ---------------------------------------------------------------- running


def expand_inputs(patterns: tuple[str, ...] | list[str]) -> list[Path]:
    """Return the files named or matched by glob patterns; no match is an error naming the pattern.

    A name that exists is taken literally, so a file called ``scan[1].png`` works.
    """
    files: list[Path] = []
    for p in patterns:
        if os.path.exists(p) or not any(c in p for c in "*?["):
            files.append(Path(p))
            continue
        hits = sorted(glob_paths(p))  # ** enters each real folder once (looping links)
        if not hits:
            raise InvalidInputError(f"no files match {p!r}")
        files += [Path(h) for h in hits]
    return files


@contextmanager
def progress_bar(enabled: bool) -> Iterator[Callable[[str, float], None] | None]:
    """Yield a progress bar on stderr driven by ``progress(stage, fraction)``; None if disabled."""
    if not enabled:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn("{task.description:<24}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f} %"),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=False,
    ) as bar:
        task = bar.add_task("working", total=1.0)

        def progress(stage: str, fraction: float) -> None:
            done = min(max(float(fraction), 0.0), 1.0)
            bar.update(task, completed=done, description=str(stage)[:24])

        yield progress


def emit(result: Result, as_json: bool) -> None:
    """Print a result: JSON or text on stdout, notes on stderr (one line each)."""
    from imageform._jsonio import dumps

    if as_json:
        click.echo(dumps(result.summary))
    else:
        console = None
        for line in result.text:
            if isinstance(line, str):
                click.echo(line)
            else:
                if console is None:
                    from rich.console import Console

                    console = Console(width=max(100, min(160, _terminal_width())), highlight=False)
                console.print(line)
    for note in result.notes:
        click.echo(f"imageform: {note}", err=True)


def _terminal_width() -> int:
    import shutil

    return shutil.get_terminal_size((120, 24)).columns


class UnexpectedError(ImageformError):
    """An exception the library did not expect, in one line naming the input file(s).

    The original is its ``__cause__`` (``--traceback`` shows both).
    """


@contextmanager
def _naming_files(inputs: dict[str, Any]) -> Iterator[None]:
    """Turn an unexpected exception into one line naming the input file(s).

    Unexpected: not an :class:`ImageformError`, an ``OSError`` naming its file, an interrupt or a
    memory error.
    """
    try:
        yield
    except (ImageformError, click.ClickException, CommandExit, MemoryError):
        raise
    except OSError as exc:
        if exc.filename is not None:
            raise
        raise UnexpectedError(_unexpected(exc, inputs)) from exc
    except Exception as exc:
        raise UnexpectedError(_unexpected(exc, inputs)) from exc


def _unexpected(exc: BaseException, inputs: dict[str, Any]) -> str:
    """One line for an exception nobody expected: its type and first line, naming the input(s).

    A command without input files (``simulate``) names none; a ``RecursionError`` (a file
    nested too deeply for Python to read) says so.
    """
    files: list[str] = []
    for value in inputs.values():
        if value is None:
            continue
        files += [str(v) for v in (value if isinstance(value, list | tuple) else [value])]
    if not files:
        where = ""
    elif len(files) == 1:
        where = files[0]
    else:
        where = f"{files[0]} (and {len(files) - 1} more)"
    if isinstance(exc, RecursionError):
        reason = "nested too deeply to process (RecursionError)"
        return f"{where}: {reason}" if where else reason
    text = str(exc).strip().splitlines()
    reason = text[0][:120] if text else ""
    head = f"{where}: " if where else ""
    return (
        f"{head}unexpected {type(exc).__name__}: {reason} (run again with --traceback to see where)"
    ).replace(":  (", " (")


def _input_fields(wf: Workflow) -> list[Any]:
    return [f for f in wf.options.fields() if f.metadata.get("input")]


def build_command(wf: Workflow) -> click.Command:
    """Return the click command of a workflow.

    It has the workflow's inputs, ``-o/--out``, its options, ``--force`` and ``--json``.
    """
    params: list[click.Parameter] = []
    for inp in wf.inputs:
        ptype = click.STRING if inp.kind == "text" or inp.many else click.Path(path_type=Path)
        params.append(
            click.Argument(
                [inp.name],
                type=ptype,
                nargs=-1 if inp.many else 1,
                required=True,
                metavar=inp.metavar or inp.name.upper() + ("..." if inp.many else ""),
            )
        )
    if wf.output is not None:
        params.append(
            click.Option(
                ["-o", "--out", "out"],
                type=_PathValue(path_type=Path),
                default=Path(wf.output.default) if wf.output.default else None,
                show_default=wf.output.default is not None,
                required=wf.output.required and wf.output.default is None,
                help=wf.output.help,
            )
        )
    params += option_params(wf)
    has_outputs = wf.output is not None or any(
        f.metadata.get("output") for f in wf.options.fields()
    )
    if has_outputs:
        params.append(click.Option(["--force"], is_flag=True, help="Overwrite existing outputs."))
    params.append(
        click.Option(["--json", "json_out"], is_flag=True, help="Print the result as JSON.")
    )

    def callback(**kw: Any) -> None:
        force = bool(kw.pop("force", False))
        as_json = bool(kw.pop("json_out", False))
        out = kw.pop("out", None)
        inputs: dict[str, Any] = {}
        for inp in wf.inputs:
            value = kw.pop(inp.name)
            # an input that takes folders gets its glob patterns expanded by execute, which
            # knows then which files were named and which a folder or pattern stood for
            if inp.many:
                value = list(value) if inp.folders else expand_inputs(value)
            inputs[inp.name] = value
        try:
            opts = wf.make_options(**take_old_flags(wf, kw))
        except ImageformError as exc:
            raise click.UsageError(str(exc)) from None
        from imageform.workflows import execute

        show = not as_json and sys.stderr.isatty()
        named = dict(inputs)  # the files an unexpected error names: inputs, then option inputs
        named.update({f.name: getattr(opts, f.name) for f in _input_fields(wf)})
        with progress_bar(show) as progress, _naming_files(named):
            result = execute(wf, options=opts, out=out, force=force, progress=progress, **inputs)
        emit(result, as_json)
        if result.check_failed:
            raise CommandExit(3)

    help_text = wf.summary + ("\n\n" + wf.description if wf.description else "")
    # the positional inputs' own help (a file's format: pose's POINTS, palette-check's COLORS)
    for inp in wf.inputs:
        name = inp.metavar or inp.name.upper() + ("..." if inp.many else "")
        help_text += f"\n\n{name}: {inp.help}"
    return click.Command(
        wf.name,
        params=params,
        callback=callback,
        help=help_text,
        short_help=wf.summary,
        no_args_is_help=bool(wf.inputs),
    )
