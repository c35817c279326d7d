"""The simulator's boundary checks (issue 16).

Typed arguments of its stages, the fields of its dataclasses checked against the scene schema, and
real arrays, each refused in one line that names the parameter (:func:`imageform._validate.describe`
shows the value).

O(1) per parameter (or one pass over a small array): never an extra pass over an image the
stage did not already read.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._validate import as_bool, as_int, as_real, describe
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.simulate.validation import MAX_LENGTH_M

__all__: list[str] = []


def check_type(value: Any, cls: type | tuple[type, ...], name: str, what: str = "") -> Any:
    """``value`` when it is an instance of ``cls``; else a :class:`TypeError` naming ``name``.

    Examples
    --------
    >>> check_type(None, int, "rows", "an int")
    Traceback (most recent call last):
    ...
    TypeError: expected rows as an int, got None
    """
    if not isinstance(value, cls):
        if not what:
            names = cls if isinstance(cls, tuple) else (cls,)
            what = " or ".join(f"a {c.__name__}" for c in names)
        raise TypeError(f"expected {name} as {what}, got {describe(value)}")
    return value


def real_array(
    value: Any,
    name: str,
    *,
    ndim: int | tuple[int, ...] | None = None,
    last: int | None = None,
    finite: bool = True,
    min_size: int = 0,
) -> np.ndarray:
    """Return ``value`` as a float64 array of real numbers, ``ndim`` dimensions, ``last`` values.

    None, bool, complex, object and string values are refused by name before any conversion; the
    array has ``ndim`` dimensions and ``last`` values on its last axis; NaN and inf are refused
    unless ``finite=False``.
    """
    if value is None or isinstance(value, str | bytes | bool | np.bool_):
        raise InvalidInputError(
            f"expected {name} as an array of real numbers, got {describe(value)}"
        )
    if hasattr(value, "detach") and hasattr(value, "cpu"):  # a torch tensor
        value = value.detach().cpu().numpy()
    arr = np.asarray(value) if not isinstance(value, np.ndarray) else value
    if arr.dtype.kind not in "iuf":
        what = {"b": "bool values", "c": "complex values"}.get(arr.dtype.kind, f"dtype {arr.dtype}")
        raise InvalidInputError(f"expected {name} as real numbers, got {what}")
    dims = None if ndim is None else ((ndim,) if isinstance(ndim, int) else ndim)
    if dims is not None and arr.ndim not in dims:
        want = " or ".join(f"{d}-d" for d in dims)
        raise InvalidInputError(f"expected {name} as a {want} array, got shape {arr.shape}")
    if last is not None and (arr.ndim < 1 or arr.shape[-1] != last):
        raise InvalidInputError(f"expected {name} of shape (..., {last}), got {arr.shape}")
    if arr.size < min_size:
        raise InvalidInputError(
            f"expected {name} with at least {min_size} value(s), got shape {arr.shape}"
        )
    out = np.asarray(arr, dtype=np.float64)
    if finite and out.size and not np.isfinite(out).all():
        raise InvalidInputError(f"{name} contains NaN or inf")
    return out


def _reals(value: Any, name: str, n: int) -> tuple[float, ...]:
    if (
        isinstance(value, str | bytes)
        or not hasattr(value, "__iter__")
        or getattr(value, "ndim", 1) != 1
    ):
        raise InvalidInputError(f"expected {name} as {n} numbers, got {describe(value)}")
    items = list(value)
    if len(items) != n:
        raise InvalidInputError(
            f"expected {name} as {n} numbers, got {len(items)} value(s): {describe(value)}"
        )
    return tuple(as_real(v, f"{name}[{i}]") for i, v in enumerate(items))


def check_field(value: Any, spec: Any, name: str) -> Any:
    """Check a dataclass field's value against its schema entry ``spec``.

    ``spec`` is a :class:`imageform.simulate.schema.Field`: kind, choices and bounds, in the units
    the typed config holds (already converted). ``None`` is accepted only for an optional key
    (default ``None``).
    """
    if value is None:
        if spec.default is None:
            return None
        raise TypeError(f"expected {name} as a {spec.kind} value, got None")
    kind = spec.kind
    if kind == "str":
        if not isinstance(value, str):
            raise TypeError(f"expected {name} as a string, got {describe(value)}")
        if spec.choices:
            key = value.strip().lower().replace("-", "_")
            valid = {c.lower(): c for c in spec.choices}
            if key in valid:
                return valid[key]
            if value in spec.choices:
                return value
            raise UnknownOptionError(
                f"unknown {name} {describe(value, 30)}; valid: {', '.join(spec.choices)}"[:200]
            )
        return value
    if kind == "bool":
        return as_bool(value, name)
    if kind == "int":
        lo = spec.minimum if spec.minimum is not None else (1 if spec.positive else None)
        hi = spec.maximum
        return as_int(
            value,
            name,
            minimum=None if lo is None else math.ceil(lo),
            maximum=None if hi is None else math.floor(hi),
        )
    if kind == "float_or_auto" and isinstance(value, str):
        if value.strip().lower() == "auto":
            return "auto"
        raise InvalidInputError(f"expected {name} as a number or 'auto', got {describe(value)}")
    if kind in ("float", "float_or_auto"):
        return _bounded(as_real(value, name), spec, name)
    if kind == "reflectance":
        if isinstance(value, str):
            from imageform.spectral import COLORCHECKER_PATCHES

            if value not in COLORCHECKER_PATCHES:
                raise UnknownOptionError(
                    f"unknown ColorChecker patch {describe(value, 30)} for {name}"
                )
            return value
        return as_real(value, name, minimum=0.0, maximum=1.0)
    if kind == "mat3":
        if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
            raise InvalidInputError(
                f"expected {name} as 3 rows of 3 numbers, got {describe(value)}"
            )
        rows = list(value)
        if len(rows) != 3:
            raise InvalidInputError(
                f"expected {name} as 3 rows of 3 numbers, got {describe(value)}"
            )
        return tuple(_reals(r, f"{name}[{i}]", 3) for i, r in enumerate(rows))
    n = {"vec2": 2, "vec3": 3, "ivec2": 2}.get(kind)
    if n is None:  # pragma: no cover - a schema kind this module does not know
        return value
    if kind == "ivec2":
        if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
            raise InvalidInputError(f"expected {name} as 2 integers, got {describe(value)}")
        items = list(value)
        if len(items) != 2:
            raise InvalidInputError(f"expected {name} as 2 integers, got {describe(value)}")
        return tuple(as_int(v, f"{name}[{i}]", minimum=2) for i, v in enumerate(items))
    out = _reals(value, name, n)
    return tuple(_bounded(x, spec, f"{name}[{i}]") for i, x in enumerate(out))


def _bounded(x: float, spec: Any, name: str) -> float:
    if spec.positive and x <= 0:
        raise InvalidInputError(f"expected {name} > 0, got {x:g}")
    if spec.minimum is not None and x < spec.minimum:
        raise InvalidInputError(f"expected {name} >= {spec.minimum:g}, got {x:g}")
    if spec.maximum is not None and x > spec.maximum:
        raise InvalidInputError(f"expected {name} <= {spec.maximum:g}, got {x:g}")
    if spec.dimension == "length" and abs(x) > MAX_LENGTH_M:
        raise InvalidInputError(f"expected {name} within ±{MAX_LENGTH_M:g}, got {x:g}")
    return x


def check_section(obj: Any, schema: dict[str, Any], section: str) -> None:
    """Check (and normalise, on a frozen dataclass) each field of ``obj`` that ``schema`` describes.

    ``schema`` is a section of :data:`~imageform.simulate.schema.SCENE_SCHEMA`; the error names
    ``section.field``.
    """
    import dataclasses

    from imageform.simulate.schema import Field

    for f in dataclasses.fields(obj):
        spec = schema.get(f.name)
        if isinstance(spec, Field):
            name = f"{section}.{f.name}" if section else f.name
            object.__setattr__(obj, f.name, check_field(getattr(obj, f.name), spec, name))
