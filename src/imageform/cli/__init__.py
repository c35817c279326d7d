"""The ``imageform`` command.

One module per command group; each defines ``register(app)``. Exit codes: 0 success,
1 failure with a one-line reason on stderr, 2 bad usage (unknown option, bad value).
Outputs never overwrite inputs; existing outputs need ``--force``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from imageform.cli._app import app

__all__ = ["app", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``imageform`` console script; returns the exit code."""
    from imageform.errors import ImageformError

    try:
        app(args=list(argv) if argv is not None else None, prog_name="imageform")
    except SystemExit as exc:
        code = exc.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except (ImageformError, OSError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"imageform: error: {msg}", file=sys.stderr)
        return 1
    return 0
