"""imageform.color's boundary checks.

The shared ones of :mod:`imageform._validate` with the refusals of issue 16 in front (bool,
complex, object and string input never converted), plus a magnitude bound for formulas
whose powers would overflow.

The wrappers keep the shared functions' signatures, so a module switches by its import line.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import Any

from imageform import _validate as _v
from imageform._backend import is_dask_namespace, namespace, reads_values
from imageform.errors import InvalidInputError

__all__ = [
    "MAX_COLOR_MAGNITUDE",
    "as_bool",
    "as_float",
    "as_image",
    "as_points",
    "check_magnitude",
    "check_nonempty",
    "check_option",
]

#: Largest magnitude a colour value (RGB, XYZ, Lab, Luv, hue, ...) may have: 1e15 in float64,
#: 1e5 in float32. No colour is near it, and the formulas' powers of it (L*'s cube,
#: CIEDE2000's C*⁷) stay finite below it; larger values are refused instead of overflowing to
#: inf or NaN.
MAX_COLOR_MAGNITUDE = {"float64": 1e15, "float32": 1e5}


def _shape_of(x: object) -> tuple[int, ...] | None:
    """Return the shape of an array-like that has one (NumPy, torch, Dask ...), unconverted."""
    shape = getattr(x, "shape", None)
    if shape is None or getattr(x, "ndim", None) is None:
        return None
    try:
        return tuple(int(d) for d in shape)
    except (TypeError, ValueError):  # unknown (NaN) Dask chunk sizes
        return None


def as_points(x: object, name: str, dim: int | Collection[int], **kw: Any) -> Any:
    """Check points like :func:`imageform._validate.as_points`, refusing bad dtypes first.

    It first refuses bool/complex/object/string and a wrong last axis (before any value is
    read: a misshaped array is refused at once).
    """
    _v.refuse_non_real(x, name)
    shape = _shape_of(x)
    dims = (dim,) if isinstance(dim, int) else tuple(dim)
    if shape is not None and (not shape or shape[-1] not in dims):
        want = " or ".join(f"(..., {d})" for d in dims)
        raise InvalidInputError(f"expected {name} of shape {want}, got {_v.format_shape(shape)}")
    return _v.as_points(x, name, dim, **kw)


def as_float(x: object, name: str, **kw: Any) -> Any:
    """:func:`imageform._validate.as_float` that first refuses bool/complex/object/string."""
    _v.refuse_non_real(x, name)
    return _v.as_float(x, name, **kw)


def as_image(image: object, name: str = "image", **kw: Any) -> Any:
    """Check an image like :func:`imageform._validate.as_image`, refusing bad dtypes first.

    It first refuses bool/complex/object/string; values read without the 0-1 range check
    (XYZ, Lab, HSV ...) are bounded by :data:`MAX_COLOR_MAGNITUDE`.
    """
    _v.refuse_non_real(image, name)
    channels = kw.get("channels", 3)
    axis = kw.get("channel_axis", -1)
    shape = _shape_of(image)
    if (
        channels is not None
        and shape
        and isinstance(axis, int)
        and -len(shape) <= axis < len(shape)
        and shape[axis] != channels
    ):
        # refused before any value is read; the message is as_image's
        hint = (
            "; an alpha channel? split it off (image[..., :3]) and handle it separately"
            if channels == 3 and shape[axis] == 4
            else ""
        )
        raise InvalidInputError(
            f"expected {name} with {channels} channels on axis {axis}, "
            f"got shape {_v.format_shape(shape)}{hint}"
        )
    arr = _v.as_image(image, name, **kw)
    if kw.get("range_check", True) is False:
        check_magnitude(arr, name)
    return arr


def as_bool(value: object, name: str) -> bool:
    """Check a flag: Python or NumPy bool (:func:`imageform._validate.as_bool`).

    0/1, strings and arrays are refused.
    """
    return _v.as_bool(value, name)


def check_option(value: object, valid: Collection[str], what: str, name: str = "") -> str:
    """Check an option like :func:`imageform._validate.check_name`.

    The error names its parameter and lists a short line of valid names.
    """
    return _v.check_name(value, valid, what, name)


def check_magnitude(arr: Any, name: str, xp: Any | None = None) -> None:
    """Refuse values beyond :data:`MAX_COLOR_MAGNITUDE`.

    Skipped for Dask (lazy) and device arrays (:func:`imageform._backend.reads_values`).
    """
    xp = namespace(arr) if xp is None else xp
    if is_dask_namespace(xp) or math.prod(arr.shape) == 0 or not reads_values(arr):
        return
    limit = MAX_COLOR_MAGNITUDE["float32" if arr.dtype == xp.float32 else "float64"]
    lo, hi = _v._min_max(arr, xp)  # one pass, detached
    if max(abs(lo), abs(hi)) > limit:
        raise InvalidInputError(
            f"expected {name} within ±{limit:g} (a colour value), got values {lo:.3g}..{hi:.3g}"
        )


def check_nonempty(arr: Any, name: str) -> None:
    """Refuse an empty array where a statistic of it is computed (it would be NaN)."""
    if math.prod(arr.shape) == 0:
        raise InvalidInputError(
            f"expected a non-empty {name}, got shape {_v.format_shape(tuple(arr.shape))}"
        )


def check_result_array(x: object, name: str) -> None:
    """Refuse a field of a caller-built result container that is not a real, finite array.

    The container is built by a caller (not by imageform); refused are bool, complex, object
    and string values, NaN and inf. Lazy Dask arrays are not computed here.
    """
    if x is None:
        raise TypeError(f"expected {name} as an array of numbers, got None")
    _v.refuse_non_real(x, name)
    if not (hasattr(x, "shape") and hasattr(x, "dtype")):
        x = _v.as_real_ndarray(x, name, finite=False)
    xp = namespace(x)
    if not is_dask_namespace(xp):
        _v.check_finite(x, name, xp)
