"""The typer application; command groups register themselves here."""

from __future__ import annotations

import typer

from imageform.cli import (
    analysis_cmds,
    batch_cmd,
    calibration_cmds,
    color_analysis_cmds,
    color_cmds,
    geometry_cmds,
    lecture_cmd,
    optics_cmds,
    sensor_cmds,
    simulate_cmd,
    vanishing_cmd,
    vision_cmds,
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
    simulate_cmd,
    lecture_cmd,
    geometry_cmds,
    vanishing_cmd,
    calibration_cmds,
    optics_cmds,
    sensor_cmds,
    color_cmds,
    color_analysis_cmds,
    vision_cmds,
    analysis_cmds,
    batch_cmd,
):
    _module.register(app)


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
