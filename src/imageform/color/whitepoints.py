"""White points of the CIE standard illuminants for the 2° and 10° observers.

The chromaticities are those of CIE 15:2004 *Colorimetry*, 3rd ed., Table T.3 ("Colorimetric
data for CIE illuminants"), to the five decimals printed there; illuminant E is the
equal-energy white, x = y = 1/3 exactly. XYZ values are derived from xy with Y = 1
(docs/conventions.md: XYZ scaled so that the reference white has Y = 1).

Note on D65. CIE 15:2004 gives D65 (2°) as (0.31271, 0.32902). The RGB standards
(IEC 61966-2-1 sRGB, ITU-R BT.709, BT.2020, SMPTE EG 432-1 Display P3, Adobe RGB (1998))
write it to four decimals, (0.3127, 0.3290), and derive their matrices from that value.
:mod:`imageform.color.rgb_spaces` keeps each standard's own white; this table keeps the
CIE's. A ``white=`` parameter accepts a name of this table, an RGB space name (its
standard's white), an ``(x, y)`` pair or an ``(X, Y, Z)`` triple, see :func:`resolve_white`.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import MappingProxyType
from typing import Any

import numpy as np

from imageform import _deprecate
from imageform._typing import ArrayLike
from imageform._validate import as_real_ndarray, describe, refuse_non_real
from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = [
    "OBSERVERS",
    "WHITEPOINTS_XY",
    "resolve_white",
    "whitepoint_xy",
    "whitepoint_xyz",
    "xy_to_xyz_white",
]

#: Observers for which white points are tabulated: CIE 1931 2° and CIE 1964 10°.
OBSERVERS: tuple[int, ...] = (2, 10)

_THIRD = 1.0 / 3.0

# CIE 15:2004, Table T.3, columns x, y for the 2° (CIE 1931) and 10° (CIE 1964) observers.
_XY_2 = {
    "A": (0.44757, 0.40745),
    "B": (0.34842, 0.35161),
    "C": (0.31006, 0.31616),
    "D50": (0.34567, 0.35850),
    "D55": (0.33242, 0.34743),
    "D65": (0.31271, 0.32902),
    "D75": (0.29902, 0.31485),
    "E": (_THIRD, _THIRD),  # equal-energy white: x = y = 1/3 by definition
    "F2": (0.37208, 0.37529),
    "F7": (0.31292, 0.32933),
    "F11": (0.38052, 0.37713),
}
_XY_10 = {
    "A": (0.45117, 0.40594),
    "B": (0.34980, 0.35270),
    "C": (0.31039, 0.31905),
    "D50": (0.34773, 0.35952),
    "D55": (0.33411, 0.34877),
    "D65": (0.31382, 0.33100),
    "D75": (0.29968, 0.31740),
    "E": (_THIRD, _THIRD),
    "F2": (0.37925, 0.36733),
    "F7": (0.31569, 0.32960),
    "F11": (0.38541, 0.37123),
}

#: ``WHITEPOINTS_XY[observer][name] -> (x, y)``; observer 2 or 10 (CIE 15:2004 Table T.3).
WHITEPOINTS_XY: MappingProxyType[int, MappingProxyType[str, tuple[float, float]]] = (
    MappingProxyType({2: MappingProxyType(_XY_2), 10: MappingProxyType(_XY_10)})
)


def _canonical(name: str) -> str:
    key = name.strip().upper().replace(" ", "").replace("_", "").replace("-", "")
    if key.startswith("FL"):  # colour-science spells the fluorescent ones FL2, FL7, FL11
        key = "F" + key[2:]
    return key


def _check_observer(observer: object) -> int:
    if isinstance(observer, bool | np.bool_) or not isinstance(observer, int | np.integer):
        raise TypeError(f"expected observer as 2 or 10 (degrees), got {describe(observer)}")
    if observer not in OBSERVERS:
        raise UnknownOptionError(f"unknown observer {observer!r}; valid: 2, 10 (degrees)")
    return int(observer)


@_deprecate.parameters(positional=("observer",))
def whitepoint_xy(name: str, *, observer: int = 2) -> tuple[float, float]:
    """Chromaticity ``(x, y)`` of a CIE illuminant.

    Parameters
    ----------
    name : str
        One of A, B, C, D50, D55, D65, D75, E, F2, F7, F11 (case-insensitive; ``FL2`` also
        accepted).
    observer : {2, 10}, keyword-only
        CIE 1931 2° or CIE 1964 10° standard observer.

    Returns
    -------
    tuple of float
        ``(x, y)`` as CIE 15:2004 Table T.3 prints them.

    Notes
    -----
    Source: CIE 15:2004, Table T.3.

    Examples
    --------
    >>> whitepoint_xy("D65")
    (0.31271, 0.32902)
    >>> whitepoint_xy("d50", observer=10)
    (0.34773, 0.35952)
    """
    obs = _check_observer(observer)
    if not isinstance(name, str):
        raise TypeError(f"expected name as a white point name (str), got {describe(name)}")
    table = WHITEPOINTS_XY[obs]
    key = _canonical(name)
    if key not in table:
        raise UnknownOptionError(
            f"unknown white point {describe(name, 30)} for name; "
            f"valid: {', '.join(repr(k) for k in table)}"
        )
    return table[key]


def xy_to_xyz_white(xy: Sequence[float]) -> np.ndarray:
    r"""XYZ (float64, Y = 1) of a chromaticity.

    .. math:: X = x / y, \quad Y = 1, \quad Z = (1 - x - y) / y

    Examples
    --------
    >>> xy_to_xyz_white((0.3127, 0.3290)).round(6).tolist()
    [0.950456, 1.0, 1.089058]
    """
    v = as_real_ndarray(xy, "xy", finite=False)
    if v.shape != (2,):
        raise InvalidInputError(f"expected xy as a chromaticity (x, y), got {describe(xy)}")
    x, y = float(v[0]), float(v[1])
    if not (np.isfinite(x) and np.isfinite(y)) or not 1e-9 <= y <= 1e3 or abs(x) > 1e3:
        raise InvalidInputError(
            f"expected xy as a chromaticity (x, y) with y > 0 (1e-9 to 1000), |x| <= 1000, got "
            f"{describe(tuple(v.tolist()))}"
        )
    return np.array([x / y, 1.0, (1.0 - x - y) / y], dtype=np.float64)


@_deprecate.parameters(positional=("observer",))
def whitepoint_xyz(name: str, *, observer: int = 2) -> np.ndarray:
    r"""Tristimulus values ``(X, Y, Z)`` of a CIE illuminant's white, scaled to Y = 1.

    .. math:: X = x / y, \quad Y = 1, \quad Z = (1 - x - y) / y

    Parameters
    ----------
    name : str
        Illuminant name, see :func:`whitepoint_xy`.
    observer : {2, 10}, keyword-only
        Standard observer in degrees.

    Returns
    -------
    ndarray, shape (3,), float64

    Notes
    -----
    Source: CIE 15:2004, Table T.3 for ``(x, y)``; the XYZ follow from the definition of
    chromaticity, CIE 15:2004 eq. (7.3).

    Examples
    --------
    >>> whitepoint_xyz("D65").round(5).tolist()
    [0.95043, 1.0, 1.0889]
    >>> whitepoint_xyz("E").round(12).tolist()
    [1.0, 1.0, 1.0]
    """
    return xy_to_xyz_white(whitepoint_xy(name, observer=observer))


@_deprecate.parameters(positional=("observer",))
def resolve_white(white: str | ArrayLike, *, observer: int = 2, name: str = "white") -> np.ndarray:
    """Resolve a ``white=`` argument to XYZ (float64, shape (3,), Y as given or 1).

    Accepted forms: an illuminant name (``"D65"``, see :data:`WHITEPOINTS_XY`); an RGB space
    name (``"srgb"``, ``"prophoto"`` ...: the white its standard writes, see
    :data:`imageform.color.rgb_spaces.RGB_SPACES`); a chromaticity ``(x, y)``; a tristimulus
    ``(X, Y, Z)`` with ``Y > 0`` (used as given). ``observer`` (keyword-only, 2 or 10) picks
    the illuminant table for a name. ``name`` (keyword-only) is the parameter the errors
    name (a caller's ``src_white`` ...).

    Examples
    --------
    >>> resolve_white("srgb").round(6).tolist()
    [0.950456, 1.0, 1.089058]
    >>> resolve_white((0.34567, 0.35850)).round(4).tolist()
    [0.9642, 1.0, 0.8252]
    """
    if isinstance(white, str):
        if _canonical(white) in WHITEPOINTS_XY[_check_observer(observer)]:
            return whitepoint_xyz(white, observer=observer)
        from imageform.color.rgb_spaces import RGB_SPACES, _space_key

        key = _space_key(white)
        if key in RGB_SPACES:
            return xy_to_xyz_white(RGB_SPACES[key].white_xy)
        names = [*WHITEPOINTS_XY[2], *RGB_SPACES]
        raise UnknownOptionError(
            f"unknown white {describe(white, 30)} for {name}; valid: a white point or RGB "
            f"space name ({', '.join(repr(n) for n in names[:6])}, ...), (x, y) or (X, Y, Z)"
        )
    if white is None:
        raise TypeError(f"expected {name} as a white point name, (x, y) or (X, Y, Z), got None")
    refuse_non_real(white, name)
    try:
        arr = np.asarray(white, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(
            f"expected {name} as a white point name, (x, y) or (X, Y, Z), got {describe(white)}"
        ) from exc
    if arr.shape == (2,):
        return xy_to_xyz_white(arr.tolist())
    if (
        arr.shape == (3,)
        and bool(np.all(np.isfinite(arr)))
        and arr[1] > 0
        and bool(np.all(arr >= 0))
        and bool(np.all(arr <= 1e6))
    ):
        return arr.copy()
    raise InvalidInputError(
        f"expected {name} as a name, (x, y) or (X, Y, Z) with Y > 0, all in [0, 1e6], "
        f"got {describe(white)}"
    )


#: :func:`resolve_white`'s answers for names (read-only arrays), the lookup of every
#: conversion that takes a white: a dict lookup instead of a resolution, and a constant
#: ``torch.compile`` can trace (D65 is resolved when this module loads, so the default white
#: compiles cold; other names after one eager call).
_NAMED_WHITES: dict[tuple[str, int], np.ndarray] = {}


def named_white(white: Any, observer: int = 2) -> np.ndarray:
    """:func:`resolve_white` (XYZ, float64), cached for names; read-only for names."""
    if isinstance(white, str) and isinstance(observer, int) and not isinstance(observer, bool):
        w = _NAMED_WHITES.get((white, observer))
        if w is None:
            w = resolve_white(white, observer=observer)
            w.setflags(write=False)
            _NAMED_WHITES[(white, observer)] = w
        return w
    return resolve_white(white, observer=observer)


named_white("D65")
