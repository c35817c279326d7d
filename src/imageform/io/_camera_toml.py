"""The camera file's reading and writing primitives (internal to :mod:`imageform.io`).

:class:`Reader` (checks values, one-line errors naming the file and the key),
:func:`short_list` and the TOML value writer; the lowest of the camera-file modules.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = ["Reader", "short_list", "toml_string", "toml_value"]


def load_toml(p: Path, what: str, form: str) -> dict[str, Any]:
    """Return the TOML file ``p`` (a camera file, a marker map) parsed, or refuse it in one line.

    ``what`` names the kind of file in the messages, ``form`` says what it should be (an image
    given for it is "not UTF-8 text"). A long name is shortened in the messages; a name the
    file system refuses, a FIFO or device, and an integer beyond Python's 4300 digits are
    refused in one line too.
    """
    from imageform._files import not_a_regular_file
    from imageform._validate import describe

    name = str(p) if len(str(p)) <= 100 else describe(str(p), 100)
    try:
        found = p.is_file()
    except OSError as exc:  # a name too long for the file system
        raise InvalidInputError(f"cannot use {name} as a {what}: {exc.strerror}") from None
    if not found:
        kind = not_a_regular_file(p)
        if kind is not None:
            raise InvalidInputError(f"{what} {name} {kind}")
        raise InvalidInputError(f"{what} {name} does not exist")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:  # an image or other binary file given for it
        raise InvalidInputError(
            f"{name} is not a {what}: not UTF-8 text (byte {exc.start}); a {what} is {form}"
        ) from None
    except OSError as exc:
        raise InvalidInputError(f"cannot read {what} {name}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError) as exc:  # ValueError: a 5000-digit integer
        reason = " ".join(str(exc).split())
        raise InvalidInputError(f"{name}: not valid TOML: {reason}") from None


class Reader:
    """Checks values of one file; every message names the file and the key."""

    def __init__(self, where: str) -> None:
        self.where = where

    def fail(self, key: str, problem: str) -> InvalidInputError:
        return InvalidInputError(f"{self.where}: {key}: {problem}")

    def number(self, value: Any, key: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise self.fail(key, f"expected a number, got {_show(value)}")
        v = float(value)
        if not math.isfinite(v):
            raise self.fail(key, f"expected a finite number, got {value}")
        return v

    def positive(self, value: Any, key: str, what: str = "") -> float:
        v = self.number(value, key)
        if v <= 0:
            raise self.fail(key, f"expected {what or 'a number'} > 0, got {value:g}")
        return v

    def count(self, value: Any, key: str, *, minimum: int = 0) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise self.fail(key, f"expected an integer >= {minimum}, got {_show(value)}")
        return int(value)

    def text(self, value: Any, key: str) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"expected a string, got {_show(value)}")
        return value

    def vector(self, value: Any, key: str, n: int = 3) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(key, f"expected a list of {n} numbers, got {_show(value)}")
        return tuple(self.number(v, f"{key}[{i}]") for i, v in enumerate(value))

    def matrix(self, value: Any, key: str) -> np.ndarray:
        if not isinstance(value, list) or len(value) != 3:
            raise self.fail(key, f"expected 3 rows of 3 numbers, got {_show(value)}")
        return np.array([self.vector(row, f"{key}[{i}]") for i, row in enumerate(value)])

    def table(self, data: Mapping[str, Any], name: str) -> dict[str, Any]:
        value = data.get(name, {})
        if not isinstance(value, dict):
            raise self.fail(name, f"expected a table [{name}], got {_show(value)}")
        return value

    def known(self, table: Mapping[str, Any], valid: tuple[str, ...], where: str) -> None:
        unknown = [k for k in table if k not in valid]
        if unknown:
            raise UnknownOptionError(
                f"{self.where}: unknown key(s) {short_list([where + k for k in unknown], 40)}; "
                f"valid{' in [' + where[:-1] + ']' if where else ''}: {short_list(valid, 90)}"
            )


def short_list(names: Sequence[str], budget: int) -> str:
    """``names`` joined by commas, cut to about ``budget`` characters (``... (3 more)``).

    Each name is cut to 30: an error message stays one line however many or long the keys are.
    """
    shown: list[str] = []
    size = 0
    for n in names:
        text = n if len(n) <= 30 else n[:27] + "..."
        size += len(text) + 2
        if shown and size > budget:
            return ", ".join(shown) + f", ... ({len(names) - len(shown)} more)"
        shown.append(text)
    return ", ".join(shown)


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def toml_value(value: Any) -> str:
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, datetime):
        return value.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    v = float(value)
    if not math.isfinite(v):
        raise InvalidInputError(f"cannot write a non-finite number ({v}) to a camera file")
    return repr(v)


def toml_string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)
