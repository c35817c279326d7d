"""The root ``imageform`` group: every workflow of the registry, plus ``batch`` and ``chunked``.

Built on first use and listed by section.
"""

from __future__ import annotations

from collections.abc import Callable

import click

from imageform.cli._batch import batch_group, chunked_group
from imageform.cli._build import EXIT_CODES, build_command

__all__ = ["root"]

_GROUPS = {
    "simulation": "Simulate a camera",
    "geometry": "Camera geometry",
    "optics": "Optics",
    "colour": "Colour",
    "sensor": "Sensor",
    "analysis": "Biomedical colour analysis",
    "scale": "Scale out",
    "tools": "Other",
}


# ---------------------------------------------------------------- the root group


def _extra_commands() -> dict[str, Callable[[], click.Command]]:
    """Return the commands that are not single workflows: batch, chunked and cache.

    batch and chunked are generated from the same registry; cache handles numba's compiled kernels.
    """
    return {"batch": batch_group, "chunked": chunked_group, "cache": _cache_command}


def _cache_command() -> click.Command:
    from imageform.cli._cache import cache_command

    return cache_command


class _Root(click.Group):
    """The root group: commands built on first use, listed by section."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        from imageform.workflows.registry import WORKFLOWS

        return [*WORKFLOWS, *_extra_commands()]

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        from imageform.workflows.registry import WORKFLOWS

        key = cmd_name.replace("_", "-")
        if key in WORKFLOWS:
            return build_command(WORKFLOWS[key])
        extra = _extra_commands()
        if key in extra:
            return extra[key]()
        return None

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        from imageform.workflows.registry import WORKFLOWS

        sections: dict[str, list[tuple[str, str]]] = {}
        for wf in WORKFLOWS.values():
            sections.setdefault(wf.group, []).append((wf.name, wf.summary))
        for name, make in _extra_commands().items():
            cmd = make()
            sections.setdefault("scale" if name in ("batch", "chunked") else "tools", []).append(
                (name, cmd.get_short_help_str(limit=200))
            )
        for key, title in _GROUPS.items():
            rows = sections.get(key)
            if rows:
                with formatter.section(title):
                    formatter.write_dl(rows)


def _version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    if value and not ctx.resilient_parsing:
        from imageform import __version__

        click.echo(f"imageform {__version__}")
        ctx.exit(0)


_EPILOG = (
    "Every command: inputs are positional, the output is -o/--out (an existing output needs "
    "--force; outputs are written all or nothing), --json prints the result as JSON, and "
    "names may be spelt with - or _. Exit codes: "
    + "; ".join(f"{k} {v}" for k, v in EXIT_CODES.items())
    + "."
)

root = _Root(
    "imageform",
    help="Image formation, end to end: simulate a camera, measure colour, calibrate and "
    "project. The main job: imageform simulate.",
    epilog=_EPILOG,
    params=[
        click.Option(
            ["--version"],
            is_flag=True,
            expose_value=False,
            is_eager=True,
            callback=_version,
            help="Print the version and exit.",
        ),
        click.Option(
            ["--traceback"],
            is_flag=True,
            expose_value=False,
            help="On an error, print the full Python traceback.",
        ),
    ],
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
    no_args_is_help=True,
)
