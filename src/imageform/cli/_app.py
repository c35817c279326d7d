"""The typer application; command groups register themselves here."""

from __future__ import annotations

import functools
from collections.abc import Callable

import click
import typer

from imageform.cli import (
    analysis_cmds,
    batch_cmd,
    sensor_cmds,
)

app = typer.Typer(
    name="imageform",
    help="Image formation: simulate a camera, measure colour, calibrate and project.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

for _module in (
    sensor_cmds,
    analysis_cmds,
    batch_cmd,
):
    _module.register(app)


def legacy_commands() -> dict[str, Callable[[], click.Command]]:
    """The hand-written typer commands not yet moved to the workflow registry, bridged into
    the click root (typer bundles its own click)."""
    group = typer.main.get_command(app)

    def bridge(name: str, short: str) -> click.Command:
        def callback(args: tuple[str, ...]) -> None:
            from imageform.cli._build import CommandExit

            try:
                rv = app(args=[name, *args], prog_name="imageform", standalone_mode=False)
            except Exception as exc:  # typer's bundled click exceptions -> ours
                kind = type(exc).__name__
                if kind == "Exit":
                    raise CommandExit(int(getattr(exc, "exit_code", 0))) from None
                if kind == "Abort":
                    raise KeyboardInterrupt from None
                if hasattr(exc, "format_message") and hasattr(exc, "exit_code"):
                    raise click.UsageError(exc.format_message()) from None
                raise
            if isinstance(rv, int) and rv:
                raise CommandExit(rv)

        return click.Command(
            name,
            callback=callback,
            params=[click.Argument(["args"], nargs=-1, type=click.UNPROCESSED)],
            context_settings={"ignore_unknown_options": True, "allow_extra_args": True},
            add_help_option=False,
            short_help=short,
        )

    out: dict[str, Callable[[], click.Command]] = {}
    for name, cmd in group.commands.items():  # type: ignore[attr-defined]
        short = (cmd.help or "").strip().splitlines()[0] if cmd.help else ""
        out[name] = functools.partial(bridge, name, short)
    return out


@app.callback(invoke_without_command=True)
def _root(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", help="Print the version and exit."),
) -> None:
    """imageform: image formation, end to end."""
    if version:
        from imageform import __version__

        typer.echo(f"imageform {__version__}")
        raise typer.Exit(0)
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit(0)
