"""The one table of length units (internal core module).

Lengths given as text (``"50mm"``, ``"2.5 cm"``, ``"0.03mm"``, ``"inf"``) are parsed here and
nowhere else, so every command and scene key accepts the same units.
"""

from __future__ import annotations

import math
import re
from types import MappingProxyType

from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = ["LENGTH_UNITS", "length_unit", "parse_length"]

#: Metres per unit.
LENGTH_UNITS = MappingProxyType(
    {
        "m": 1.0,
        "cm": 1e-2,
        "mm": 1e-3,
        "um": 1e-6,
        "µm": 1e-6,
        "nm": 1e-9,
        "in": 0.0254,
        "ft": 0.3048,
    }
)

_NUMBER = re.compile(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?)([a-zµ]*)")


def _shown(text: object, width: int = 40) -> str:
    """``text`` for a one-line message: its repr, cut to ``width`` characters."""
    shown = repr(str(text))
    return shown if len(shown) <= width else shown[: width - 3] + "..."


def length_unit(text: str | float, default_unit: str = "m") -> str:
    """Return the unit a length is written in (``"30mm"`` -> ``"mm"``; a bare number: the default).

    The same reading as :func:`parse_length`, which checks the unit and the value.

    Examples
    --------
    >>> length_unit("30mm"), length_unit("2.5 cm"), length_unit("25", default_unit="mm")
    ('mm', 'cm', 'mm')
    """
    m = _NUMBER.fullmatch(str(text).strip().lower().replace(" ", ""))
    return (m.group(2) if m else "") or default_unit


def parse_length(
    text: str | float,
    name: str,
    *,
    default_unit: str = "m",
    unit: str = "m",
    positive: bool = True,
    allow_inf: bool = False,
) -> float:
    """Parse a length given as text, in ``unit`` (metres by default).

    Parameters
    ----------
    text : str or float
        A number with an optional unit (``"50mm"``, ``"2 m"``, ``"1in"``); a bare number (or a
        float) is in ``default_unit``; ``"inf"`` is infinity when ``allow_inf``.
    name : str
        How the caller calls it in messages (``--focal``, ``square``).
    default_unit, unit : str
        Unit of a bare number, and of the result (keys of :data:`LENGTH_UNITS`).
    positive : bool
        Refuse zero and negative lengths.
    allow_inf : bool
        Accept ``inf``.

    Raises
    ------
    InvalidInputError
        Not a number with a unit; not positive; not finite.
    UnknownOptionError
        An unknown unit (the valid ones are listed).

    Examples
    --------
    >>> parse_length("50mm", "--focal"), parse_length("2", "--focus")
    (0.05, 2.0)
    >>> parse_length("25", "--square", default_unit="mm", unit="mm")
    25.0
    """
    for u in (default_unit, unit):
        if u not in LENGTH_UNITS:
            raise UnknownOptionError(f"unknown unit {u!r}; valid: {', '.join(LENGTH_UNITS)}")
    if isinstance(text, bool) or not isinstance(text, (str, int, float)):
        raise InvalidInputError(
            f"expected {name} as a length (e.g. 50mm), got {type(text).__name__}"
        )
    t = str(text).strip().lower().replace(" ", "")
    if t in ("inf", "infinity", "+inf"):
        if not allow_inf:
            raise InvalidInputError(f"expected {name} as a finite length, got {_shown(text)}")
        return math.inf
    m = _NUMBER.fullmatch(t)
    if not m:
        raise InvalidInputError(
            f"expected {name} as a number with a unit (e.g. 50mm, 2m, 0.03mm), got {_shown(text)}"
        )
    u = m.group(2) or default_unit
    if u not in LENGTH_UNITS:
        raise UnknownOptionError(f"unknown unit {u!r} for {name}; valid: {', '.join(LENGTH_UNITS)}")
    value = float(m.group(1)) * LENGTH_UNITS[u] / LENGTH_UNITS[unit]
    if not math.isfinite(value):
        raise InvalidInputError(f"expected {name} as a finite length, got {_shown(text)}")
    if positive and value <= 0:
        raise InvalidInputError(f"expected {name} > 0, got {_shown(text)}")
    return value
