"""Helpers shared by the command modules: output paths, JSON printing, errors."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError

__all__ = ["check_output_path", "print_json"]


def check_output_path(out: Path, *, inputs: tuple[Path, ...] = (), force: bool = False) -> Path:
    """Refuse to overwrite an input, or an existing output without ``--force``."""
    out_r = out.resolve()
    for p in inputs:
        if p.resolve() == out_r:
            raise InvalidInputError(f"output {out} is also an input; choose another path")
    if out.exists() and not force:
        raise InvalidInputError(f"output {out} exists; pass --force to overwrite it")
    if not out.parent.exists():
        raise InvalidInputError(f"output folder {out.parent} does not exist")
    return out


def print_json(payload: Any) -> None:
    """Print ``payload`` as JSON on stdout (NaN written as null)."""

    def default(o: Any) -> Any:
        if hasattr(o, "tolist"):
            return o.tolist()
        if hasattr(o, "item"):
            return o.item()
        raise TypeError(f"not JSON serialisable: {type(o).__name__}")

    text = json.dumps(payload, default=default, indent=2, allow_nan=True)
    sys.stdout.write(text.replace("NaN", "null") + "\n")
