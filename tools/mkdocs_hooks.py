"""MkDocs hooks for the documentation site (mkdocs.yml): the command-line reference is
generated from the command definitions (the workflow registry through click), so it cannot
drift from ``imageform --help``."""

from __future__ import annotations

from typing import Any

MARKER = "<!-- cli-reference -->"


def _command_help(name: str, command: Any, ctx_parent: Any) -> str:
    import click

    ctx = click.Context(command, info_name=name, parent=ctx_parent)
    text = command.get_help(ctx)
    return f"## `imageform {name}`\n\n```text\n{text}\n```\n"


def cli_reference() -> str:
    """Markdown: ``imageform --help``, then every command's ``--help``, in the root's order."""
    import click

    from imageform.cli import root

    ctx = click.Context(root, info_name="imageform")
    parts = ["```text\n" + root.get_help(ctx) + "\n```\n"]
    for name in root.list_commands(ctx):
        command = root.get_command(ctx, name)
        if command is not None and not getattr(command, "hidden", False):
            parts.append(_command_help(name, command, ctx))
    return "\n".join(parts)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if MARKER in markdown:
        return markdown.replace(MARKER, cli_reference())
    return markdown
