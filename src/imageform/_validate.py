"""Boundary checks: shapes, dtypes, finiteness, ranges and option names.

Public functions validate once, here, and hand clean arrays to private helpers. Messages
say what was expected and what came, e.g. ``expected points of shape (..., 3), got (4, 2)``;
unknown option names list the valid ones.
"""

from __future__ import annotations

import math
import numbers
import os
import re
from collections.abc import Collection, Sequence
from typing import Any

import array_api_compat
import numpy as np

from imageform._backend import (
    COORD_INTEGER_DTYPE,
    IMAGE_INTEGER_DTYPE,
    asarray_like,
    device_of,
    float_dtype,
    is_dask_namespace,
    namespace,
    reads_values,
    scalar,
    to_numpy,
)
from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = [
    "DEFAULT_MAX_MEMORY",
    "INTEGER_SCALE",
    "MAX_COLOR_MAGNITUDE",
    "MAX_MAGNITUDE",
    "MAX_MEAN_ELECTRONS",
    "MAX_SIDE",
    "any_value",
    "as_bool",
    "as_float",
    "as_float_bounded",
    "as_float_strict",
    "as_image",
    "as_image_strict",
    "as_int",
    "as_matrix",
    "as_matrix_bounded",
    "as_path",
    "as_points",
    "as_points_bounded",
    "as_points_strict",
    "as_real",
    "as_real_array",
    "as_real_ndarray",
    "as_reals",
    "as_shape",
    "as_size",
    "check_K",
    "check_bounded",
    "check_electrons",
    "check_finite",
    "check_image_size",
    "check_magnitude",
    "check_memory",
    "check_min_side",
    "check_name",
    "check_nonempty",
    "check_nonzero_rows",
    "check_option",
    "check_path",
    "check_positive",
    "check_real_values",
    "check_result_array",
    "check_rng",
    "check_rotation",
    "check_type",
    "describe",
    "det3",
    "dtype_kind",
    "finite_result",
    "format_shape",
    "memory_limit",
    "points_pass_bounded",
    "real_array",
    "real_pair",
    "refuse_non_real",
    "shape_text",
    "shorten",
    "shorten_names",
    "size_pair",
]


def format_shape(shape: Sequence[int | None]) -> str:
    """``(4, 2)`` for a tuple shape; ``(3,)`` for one element."""
    dims = ["?" if d is None else str(d) for d in shape]
    return "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"


def _raw(x: object, name: str, xp: Any, device: Any) -> Any:
    if isinstance(x, str | bytes):
        raise InvalidInputError(f"expected a numeric array for {name}, got {type(x).__name__}")
    try:
        arr = asarray_like(x, xp, device=device)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"expected a numeric array for {name}, got {describe(x)}") from exc
    dt = arr.dtype
    if not (xp.isdtype(dt, "numeric") or xp.isdtype(dt, "bool")):
        raise InvalidInputError(f"expected a numeric array for {name}, got dtype {dt}")
    if xp.isdtype(dt, "complex floating"):
        raise InvalidInputError(f"expected real values for {name}, got dtype {dt}")
    return arr


def _min_max(x: Any, xp: Any) -> tuple[float, float]:
    """``(min, max)`` of a non-empty real array, NaN if it holds a NaN.

    One read of the data and one host synchronisation where the library allows (PyTorch's
    ``aminmax``), two reads otherwise; nothing the size of ``x`` is allocated. The Array API
    standard has ``min``/``max`` propagate NaN, so the pair is finite exactly when every
    element is: this replaces ``all(isfinite(x))`` (PyTorch runs ``isfinite`` as three
    passes plus a boolean temporary) and gives the maximum for the 0-255 check in the same
    pass.
    """
    if array_api_compat.is_torch_array(x):
        lo, hi = x.detach().aminmax()
        pair = xp.stack((lo, hi)).cpu().tolist()
        return float(pair[0]), float(pair[1])
    return scalar(xp.min(x)), scalar(xp.max(x))


def _check_values(x: Any, xp: Any, name: str, *, finite: bool, range_check: bool) -> None:
    """Run the value checks of :func:`check_finite` and :func:`as_image` on a float array.

    NaN/inf (``finite``) and 0-255 values stored as floats (``range_check``), from one
    min/max reduction. Skipped where the values are on a device (:func:`reads_values`):
    there NaN and inf propagate to the result instead (docs/design.md, "Devices").
    """
    if not (finite or range_check) or math.prod(x.shape) == 0 or not reads_values(x):
        return
    lo, mx = _min_max(x, xp)
    if finite and not (math.isfinite(lo) and math.isfinite(mx)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    if range_check and mx > 1.5 and bool(xp.all(x == xp.round(x))):
        raise InvalidInputError(
            f"{name} looks like 0-255 values stored as floats (max {mx:g}); "
            "divide by 255 or pass uint8"
        )


def any_value(cond: Any, xp: Any) -> bool:
    """``bool(xp.any(cond))`` for a boundary check; False, unread, on device arrays.

    The condition is read only where :func:`imageform._backend.reads_values` allows (host
    memory); on a GPU (or ``meta``) it is skipped, so the check never waits for the device,
    and the bad elements come out as NaN/inf or flagged in the function's documented mask
    instead of an error (docs/design.md, "Devices").
    """
    return reads_values(cond) and bool(xp.any(cond))


def check_finite(x: Any, name: str, xp: Any | None = None) -> None:
    """Raise :class:`InvalidInputError` if ``x`` holds NaN or inf.

    On device arrays (:func:`imageform._backend.reads_values` is False) nothing is read.
    """
    xp = namespace(x) if xp is None else xp
    if xp.isdtype(x.dtype, "real floating"):
        _check_values(x, xp, name, finite=True, range_check=False)


def as_float(
    x: object,
    name: str,
    *,
    xp: Any | None = None,
    dtype: Any = None,
    device: Any = None,
    integer: str = COORD_INTEGER_DTYPE,
    finite: bool = True,
    strict: bool = False,
    bound: float | None = None,
) -> Any:
    """``x`` as a floating array of namespace ``xp``.

    ``dtype`` forces the result dtype (parameters follow their data argument); otherwise
    the dtype policy of :func:`imageform._backend.float_dtype` applies. ``strict`` refuses
    bool, complex, object and string values before any conversion
    (:func:`refuse_non_real`); ``bound`` (with ``finite``) refuses magnitudes above it as well
    as NaN and inf (:func:`check_bounded`), and a tensor asked for as NumPy (``xp=np``) is
    moved to the host first.
    """
    x = _prepare(x, name, xp, strict=strict, bound=bound)
    xp = namespace(x) if xp is None else xp
    if device is None:
        device = device_of(x)
    arr = _raw(x, name, xp, device)
    target = float_dtype(arr, xp, integer=integer) if dtype is None else dtype
    if arr.dtype != target:
        arr = xp.astype(arr, target)
    _check_float_values(arr, name, xp, finite=finite, bound=bound)
    return arr


def _prepare(x: object, name: str, xp: Any, *, strict: bool, bound: float | None) -> Any:
    """Run the checks before any conversion: the kind (``strict``), then the host copy."""
    if strict:
        refuse_non_real(x, name)
    if bound is not None and xp is np and array_api_compat.is_torch_array(x):
        return to_numpy(x)
    return x


def _check_float_values(arr: Any, name: str, xp: Any, *, finite: bool, bound: float | None) -> None:
    """Run the value checks after the shape: NaN and inf, and the magnitude ``bound``."""
    if finite and bound is not None:
        check_bounded(arr, name, xp, bound)
    elif finite:
        check_finite(arr, name, xp)


def _refuse_last_axis(x: object, name: str, dims: tuple[int, ...]) -> None:
    """Refuse a wrong last axis from ``x.shape`` before any value is converted."""
    shape = _shape_of(x)
    if shape is not None and (not shape or shape[-1] not in dims):
        want = " or ".join(f"(..., {d})" for d in dims)
        raise InvalidInputError(f"expected {name} of shape {want}, got {format_shape(shape)}")


def as_points(
    x: object,
    name: str,
    dim: int | Collection[int],
    *,
    xp: Any | None = None,
    dtype: Any = None,
    device: Any = None,
    finite: bool = True,
    strict: bool = False,
    bound: float | None = None,
) -> Any:
    """Points of shape ``(..., dim)`` as floats (integers compute in float64).

    The shape is checked before the values; ``strict`` and ``bound`` as in :func:`as_float`.
    """
    dims = (dim,) if isinstance(dim, int) else tuple(dim)
    if strict:
        refuse_non_real(x, name)
        _refuse_last_axis(x, name, dims)
    x = _prepare(x, name, xp, strict=False, bound=bound)
    arr = as_float(x, name, xp=xp, dtype=dtype, device=device, finite=False)
    if arr.ndim < 1 or arr.shape[-1] not in dims:
        want = " or ".join(f"(..., {d})" for d in dims)
        raise InvalidInputError(
            f"expected {name} of shape {want}, got {format_shape(tuple(arr.shape))}"
        )
    _check_float_values(arr, name, xp, finite=finite, bound=bound)
    return arr


def as_matrix(
    x: object,
    name: str,
    shape: tuple[int, int],
    *,
    xp: Any | None = None,
    dtype: Any = None,
    device: Any = None,
    batch: bool = True,
    finite: bool = True,
    bound: float | None = None,
) -> Any:
    """Check a matrix (or batch of matrices when ``batch``) of trailing shape ``shape``.

    The shape is checked before the values; ``bound`` as in :func:`as_float`.
    """
    x = _prepare(x, name, xp, strict=False, bound=bound)
    arr = as_float(x, name, xp=xp, dtype=dtype, device=device, finite=False)
    ok = arr.ndim >= 2 and tuple(arr.shape[-2:]) == shape
    if ok and not batch and arr.ndim != 2:
        ok = False
    if not ok:
        want = format_shape(shape) if not batch else "(..., " + format_shape(shape)[1:]
        raise InvalidInputError(
            f"expected {name} of shape {want}, got {format_shape(tuple(arr.shape))}"
        )
    _check_float_values(arr, name, xp, finite=finite, bound=bound)
    return arr


def check_rotation(R: Any, name: str = "R", *, xp: Any | None = None, atol: float = 1e-6) -> None:
    """Raise unless every ``R`` in the batch is orthonormal with determinant +1.

    The tolerance applies to ``max |R Rᵀ - I|`` and ``|det R - 1|``; float32 input is checked
    with ``max(atol, 1e-4)``.
    """
    xp = namespace(R) if xp is None else xp
    if not reads_values(R):  # on a device: no synchronising check (docs/design.md)
        return
    if R.dtype == xp.float32:
        atol = max(atol, 1e-4)
    eye = xp.eye(3, dtype=R.dtype, device=device_of(R))
    err = xp.max(xp.abs(R @ xp.matrix_transpose(R) - eye))
    if scalar(err) > atol:
        raise InvalidInputError(
            f"expected {name} to be a rotation matrix (R Rᵀ = I), "
            f"max |R Rᵀ - I| = {scalar(err):.3g}"
        )
    det = det3(R)
    worst = scalar(xp.max(xp.abs(det - 1.0)))
    if worst > max(atol, 10 * atol):
        raise InvalidInputError(
            f"expected {name} to be a proper rotation (det R = +1), got det R = "
            f"{scalar(xp.min(det)):.6g} (a reflection)"
        )


def det3(M: Any) -> Any:
    """Compute the determinant of (a batch of) 3×3 matrices by cofactor expansion.

    Works in every Array-API namespace, including those without ``linalg.det`` (Dask).
    """
    return (
        M[..., 0, 0] * (M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
        - M[..., 0, 1] * (M[..., 1, 0] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 0])
        + M[..., 0, 2] * (M[..., 1, 0] * M[..., 2, 1] - M[..., 1, 1] * M[..., 2, 0])
    )


def check_option(value: object, valid: Collection[str], what: str) -> str:
    """Return ``value`` normalised (lower-case, ``_`` for ``-``) if valid, else raise.

    Examples
    --------
    >>> check_option("Gray-World", ["gray_world", "white_patch"], "white-balance method")
    'gray_world'
    """
    if not isinstance(value, str):
        raise UnknownOptionError(f"expected a {what} name (str), got {type(value).__name__}")
    key = value.strip().lower().replace("-", "_").replace(" ", "_")
    if key not in valid:
        names = ", ".join(repr(v) for v in sorted(valid))
        if len(names) > 120:  # one line: list what fits, say how many more
            shown = ""
            for i, v in enumerate(sorted(valid)):
                part = (", " if shown else "") + repr(v)
                if len(shown) + len(part) > 110:
                    shown += f", ... ({len(valid) - i} more)"
                    break
                shown += part
            names = shown
        raise UnknownOptionError(f"unknown {what} {describe(value, 60)}; valid: {names}")
    return key


def describe(value: object, width: int = 40) -> str:
    """Describe a value briefly for an error message.

    Its repr cut to ``width`` characters (arrays as their type, shape and dtype, never their
    contents).

    Examples
    --------
    >>> describe("x" * 100)[:12], describe(np.zeros((300, 400)))
    ("'xxxxxxxxxxx", 'ndarray of shape (300, 400), float64')
    """
    shape = getattr(value, "shape", None)
    if shape is not None and getattr(value, "ndim", None):
        dtype = getattr(value, "dtype", "")
        return f"{type(value).__name__} of shape {format_shape(tuple(shape))}, {dtype}"
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def shorten(text: object, width: int = 80) -> str:
    """Return ``str(text)`` cut to ``width`` characters (``...`` in the middle), on one line.

    For a file name or other text a message quotes: a 100 kB argument is never echoed.

    Examples
    --------
    >>> shorten("x" * 100_000, 20)
    'xxxxxxxx...xxxxxxxxx'
    """
    s = " ".join(str(text).split()) if "\n" in str(text) else str(text)
    if len(s) <= width:
        return s
    head = (width - 3) // 2
    return s[:head] + "..." + s[len(s) - (width - 3 - head) :]


def shorten_names(names: Collection[str], width: int = 110) -> str:
    """Join ``names`` with commas, cut to about ``width`` characters with a count of the rest.

    For the "valid: ..." part of a one-line message, however many names are valid.

    Examples
    --------
    >>> shorten_names([f"topic {i}" for i in range(40)], width=30)
    'topic 0, topic 1, topic 2, ... (37 more)'
    """
    items = [str(n) for n in names]
    shown: list[str] = []
    size = 0
    for n in items:
        size += len(n) + 2
        if size > width:
            break
        shown.append(n)
    more = f", ... ({len(items) - len(shown)} more)" if len(shown) < len(items) else ""
    return ", ".join(shown) + more


def _as_number(value: object, name: str) -> float:
    """Check a real number from a Python or NumPy scalar (or a 0-d real array or tensor).

    Never a bool, string, complex, None or a sequence.
    """
    item = value
    if getattr(value, "ndim", None) == 0 and hasattr(value, "item"):
        item = value.item()
    if isinstance(item, bool | np.bool_) or item is None or isinstance(item, str | bytes):
        raise InvalidInputError(f"expected {name} as a number, got {describe(value)}")
    if isinstance(item, numbers.Real):
        return float(item)
    if isinstance(item, numbers.Complex):
        raise InvalidInputError(f"expected {name} as a real number, got {describe(value)}")
    raise InvalidInputError(
        f"expected {name} as a number, got {type(value).__name__} {describe(value)}"
    )


#: The smallest positive normal float64: a positive value below it (subnormal) passes ``> 0``
#: but its reciprocal is inf, and its square 0.
_SMALLEST_NORMAL = float(np.finfo(np.float64).tiny)


def as_real(
    value: object,
    name: str,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    positive: bool = False,
    nonnegative: bool = False,
    allow_inf: bool = False,
) -> float:
    """Convert a finite real scalar (Python or NumPy number, 0-d array) to ``float``.

    Refuses bool, None, strings, complex numbers, NaN, inf (unless ``allow_inf``) and values
    outside the bounds, in one line naming ``name``. With ``positive``, a subnormal value
    (below 2.2e-308, whose reciprocal overflows) is refused too.

    Examples
    --------
    >>> as_real(np.float32(2.5), "sigma", positive=True)
    2.5
    >>> as_real("5", "sigma")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected sigma as a number, got '5'
    """
    v = _as_number(value, name)
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise InvalidInputError(f"expected {name} as a finite number, got {v:g}")
    if positive and v <= 0:
        raise InvalidInputError(f"expected {name} > 0, got {v:g}")
    if positive and v < _SMALLEST_NORMAL:  # passes > 0, but 1 / v overflows
        raise InvalidInputError(
            f"expected {name} > 0 and at least {_SMALLEST_NORMAL:.3g} (its reciprocal "
            f"must be finite), got {v:g}"
        )
    if nonnegative and v < 0:
        raise InvalidInputError(f"expected {name} >= 0, got {v:g}")
    if minimum is not None and v < minimum:
        raise InvalidInputError(f"expected {name} >= {minimum:g}, got {v:g}")
    if maximum is not None and v > maximum:
        raise InvalidInputError(f"expected {name} <= {maximum:g}, got {v:g}")
    return v


def as_int(
    value: object, name: str, *, minimum: int | None = None, maximum: int | None = None
) -> int:
    """Convert an integer (Python ``int`` or any NumPy integer; a 0-d integer array) to ``int``.

    Floats are refused even when whole (``2.0``), as are bool, None, strings and inf.

    Examples
    --------
    >>> as_int(np.int64(3), "max_iter", minimum=1)
    3
    >>> as_int(2.0, "n")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected n as an integer, got 2.0
    """
    if isinstance(value, bool | np.bool_):
        raise InvalidInputError(f"expected {name} as an integer, got {value!r}")
    item = value
    if getattr(value, "ndim", None) == 0 and hasattr(value, "item"):
        item = value.item()
    if isinstance(item, numbers.Integral) and not isinstance(item, bool):
        v = int(item)
    else:
        raise InvalidInputError(f"expected {name} as an integer, got {describe(value)}")
    if minimum is not None and v < minimum:
        raise InvalidInputError(f"expected {name} >= {minimum}, got {v}")
    if maximum is not None and v > maximum:
        raise InvalidInputError(f"expected {name} <= {maximum}, got {v}")
    return v


def as_bool(value: object, name: str) -> bool:
    """Check a bool (Python or NumPy); 0/1 and strings are refused.

    Examples
    --------
    >>> as_bool(np.True_, "clip")
    True
    """
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise InvalidInputError(f"expected {name} as True or False, got {describe(value)}")


def as_size(
    value: object, name: str, n: int = 2, *, minimum: int = 1, maximum: int | None = None
) -> tuple[int, ...]:
    """Check a tuple of ``n`` integers (a shape or an image size), each ``>= minimum``.

    Examples
    --------
    >>> as_size((640, np.int64(480)), "image_size")
    (640, 480)
    """
    if (
        isinstance(value, str | bytes)
        or not hasattr(value, "__len__")
        or not hasattr(value, "__iter__")
        or getattr(value, "ndim", 1) != 1  # a 0-d tensor has a len() that raises
    ):
        raise InvalidInputError(f"expected {name} as {n} integers, got {describe(value)}")
    items = list(value)
    if len(items) != n:
        raise InvalidInputError(
            f"expected {name} as {n} integers, got {len(items)} value(s): {describe(value)}"
        )
    return tuple(
        as_int(v, f"{name}[{i}]", minimum=minimum, maximum=maximum) for i, v in enumerate(items)
    )


#: The memory budget without ``IMAGEFORM_MAX_MEMORY``: 4 GiB (a 100 Mpx image goes through any
#: single-image command in it; larger inputs are refused in one line, or processed block by
#: block with ``imageform chunked``).
DEFAULT_MAX_MEMORY = 4 * 2**30

_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
_MEMORY = re.compile(r"\s*([0-9.eE+]+)\s*([KMGT]?)(?:I?B)?\s*", re.IGNORECASE)


def memory_limit() -> int:
    """Return the memory budget: the most bytes a command or one call may ask for.

    ``IMAGEFORM_MAX_MEMORY`` if set: bytes, or with a unit (``4GiB``, ``4G``, ``512MiB``,
    ``512M``; K, M, G and T count powers of 1024), else :data:`DEFAULT_MAX_MEMORY` (4 GiB).

    Examples
    --------
    >>> import os
    >>> os.environ["IMAGEFORM_MAX_MEMORY"] = "1.5GiB"
    >>> memory_limit() == 1.5 * 2**30
    True
    >>> del os.environ["IMAGEFORM_MAX_MEMORY"]
    """
    text = os.environ.get("IMAGEFORM_MAX_MEMORY", "").strip()
    if not text:
        return DEFAULT_MAX_MEMORY
    m = _MEMORY.fullmatch(text)
    try:
        value = float(m.group(1)) * _UNITS[m.group(2).upper()] if m else float("nan")
    except ValueError:
        value = float("nan")
    if not (value >= 1 and math.isfinite(value)):
        raise InvalidInputError(
            f"expected IMAGEFORM_MAX_MEMORY as bytes or with a unit (e.g. 4GiB), got {text[:40]!r}"
        )
    return int(value)


def _gib(n_bytes: float) -> str:
    """``12.3`` below a million GiB, ``1.2e+294`` above: a number of bytes, short."""
    g = n_bytes / 2**30
    return f"{g:.1f}" if g < 1e6 else f"{g:.3g}"


def check_memory(n_bytes: float, name: str, what: str = "the result") -> None:
    """Refuse, before allocating, what would need more than :func:`memory_limit` bytes.

    Examples
    --------
    >>> check_memory(1e15, "shape", "an image of 1e15 bytes")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: shape: an image of 1e15 bytes would need 931322.6 GiB, ...
    """
    limit = memory_limit()
    if not n_bytes <= limit:  # NaN too
        raise InvalidInputError(
            f"{name}: {what} would need {_gib(n_bytes)} GiB, more than the "
            f"{limit / 2**30:.1f} GiB allowed (IMAGEFORM_MAX_MEMORY)"
        )


def check_image_size(size: object, name: str = "image_size") -> tuple[int, int]:
    """Check a ``(width, height)`` pair of positive integers, returned as a tuple of ``int``.

    Examples
    --------
    >>> check_image_size((640, 480))
    (640, 480)
    """
    w, h = as_size(size, f"{name} (width, height)", maximum=MAX_SIDE)
    return w, h


def check_min_side(shape: Sequence[int], side: int, name: str = "image") -> None:
    """Refuse an image whose height or width is under ``side`` pixels, in one spelling.

    ``shape`` is the array's shape, rows first; the message gives width x height.

    Examples
    --------
    >>> check_min_side((8, 40), 16)
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected an image of at least 16 x 16 pixels, got 40 x 8
    """
    h, w = int(shape[0]), int(shape[1]) if len(shape) > 1 else 1
    if min(h, w) < side:
        article = "an " if name == "image" else ""
        raise InvalidInputError(
            f"expected {article}{name} of at least {side} x {side} pixels, got {w} x {h}"
        )


def check_nonempty(image: Any, name: str = "image") -> Any:
    """Refuse an image (any array) without a single pixel, saying "empty image"; return it.

    Examples
    --------
    >>> check_nonempty(np.empty((0, 4, 3)), "image")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected image with at least one pixel, got an empty image of shape (0, 4, 3)
    """  # noqa: E501
    shape = tuple(getattr(image, "shape", ()))
    if any(d == 0 for d in shape):
        raise InvalidInputError(
            f"expected {name} with at least one pixel, got an empty image of shape "
            f"{format_shape(shape)}"
        )
    return image


def check_positive(value: object, name: str, *, allow_zero: bool = False) -> float:
    """Check a finite scalar ``> 0`` (or ``>= 0`` with ``allow_zero``), returned as ``float``."""
    return as_real(value, name, positive=not allow_zero, nonnegative=allow_zero)


#: The integer sample types :func:`as_image` takes, by dtype name, and their full scale.
INTEGER_SCALE = {"uint8": 255.0, "uint16": 65535.0}


def _check_image_block(a: Any, name: str, finite: bool, range_check: bool) -> Any:
    """:func:`as_image`'s value checks on one NumPy chunk of a Dask image."""
    _check_values(a, np, name, finite=finite, range_check=range_check)
    return a


def as_image(
    image: object,
    name: str = "image",
    *,
    channels: int | None = 3,
    channel_axis: int = -1,
    xp: Any | None = None,
    range_check: bool = True,
    finite: bool = True,
    strict: bool = False,
) -> Any:
    """Check an image as floats, channels last, per the colour conventions of docs/conventions.md.

    - ``uint8`` / ``uint16`` are full-range encoded values: divided by 255 / 65535, float32.
    - Python integers (a list or tuple such as ``(200, 50, 50)``) are 8-bit codes 0-255, read
      as uint8; a Python integer outside 0-255 raises (pass a uint16 array for 16-bit codes).
    - other integer dtypes raise (their scale is a guess): pass uint8/uint16 or floats.
    - float input that is plainly 0–255 (all values whole numbers, max > 1.5) raises with a
      hint, when ``range_check``.
    - ``channels`` (if given) must match the size of ``channel_axis``; the channel axis is
      moved last. A 4th (alpha) channel is rejected with a hint to split it off.
    - Dask arrays stay lazy: the value checks (finite, 0–255) run on each chunk when it is
      computed.
    - ``strict`` (colour values): bool, complex, object and string values are refused before
      any conversion, the channel count is checked from ``image.shape`` before any value is
      read, and values read without the 0–1 range check (XYZ, Lab, HSV ...) are bounded by
      :data:`MAX_COLOR_MAGNITUDE` (:func:`check_magnitude`).
    """
    if strict:
        refuse_non_real(image, name)
        _refuse_channels(image, name, channels, channel_axis)
    xp = namespace(image) if xp is None else xp
    arr = _raw(image, name, xp, device_of(image))
    axis = -1
    if channels is not None:  # the shape before any pass over the values
        if arr.ndim < 1:
            raise InvalidInputError(f"expected {name} with a channel axis, got a scalar")
        axis = channel_axis % arr.ndim
        n = arr.shape[axis]
        if n != channels:
            raise InvalidInputError(
                f"expected {name} with {channels} channels on axis {channel_axis}, "
                f"got shape {format_shape(tuple(arr.shape))}{_channel_hint(channels, n)}"
            )
    dt = arr.dtype
    if isinstance(image, list | tuple) and xp.isdtype(dt, "integral") and math.prod(arr.shape):
        lo, hi = _min_max(arr, xp)
        if lo < 0 or hi > 255:
            raise InvalidInputError(
                f"expected {name} as Python integers 0-255 (8-bit codes), got values "
                f"{lo:g}..{hi:g}; pass a uint16 array for 16-bit codes or floats in [0, 1]"
            )
        arr = xp.astype(arr, xp.uint8)
        dt = arr.dtype
    if xp.isdtype(dt, "integral") or xp.isdtype(dt, "bool"):
        dname = str(dt).removeprefix("torch.")
        if dname not in INTEGER_SCALE:
            raise InvalidInputError(
                f"expected {name} as uint8, uint16 or floats in [0, 1], got dtype {dname}; "
                "integer images other than uint8/uint16 have no known full range"
            )
        arr = xp.astype(arr, getattr(xp, IMAGE_INTEGER_DTYPE)) / INTEGER_SCALE[dname]
    else:
        arr = xp.astype(arr, float_dtype(arr, xp), copy=False)
        if is_dask_namespace(xp):
            # lazily: each chunk is checked when it is computed (nothing computed here)
            if finite or range_check:
                arr = arr.map_blocks(_check_image_block, name, finite, range_check, dtype=arr.dtype)
        else:
            _check_values(arr, xp, name, finite=finite, range_check=range_check)
    if channels is not None and axis != arr.ndim - 1:
        arr = xp.moveaxis(arr, axis, -1)
    if strict and not range_check:
        check_magnitude(arr, name)
    return arr


def _channel_hint(channels: int | None, n: int) -> str:
    if channels == 3 and n == 4:
        return "; an alpha channel? split it off (image[..., :3]) and handle it separately"
    return ""


def _refuse_channels(image: object, name: str, channels: int | None, axis: object) -> None:
    """Refuse a wrong channel count from ``image.shape``, before any value is converted."""
    shape = _shape_of(image)
    if (
        channels is not None
        and shape
        and isinstance(axis, int)
        and -len(shape) <= axis < len(shape)
        and shape[axis] != channels
    ):
        raise InvalidInputError(
            f"expected {name} with {channels} channels on axis {axis}, "
            f"got shape {format_shape(shape)}{_channel_hint(channels, shape[axis])}"
        )


# --- h16optsens ---
# Shared by imageform.optics and imageform.sensor (issue 16): real arrays that refuse
# None/complex/object/strings before any value is read, shapes bounded by the memory
# limit, fixed-length tuples of reals, and formulas whose overflow is refused in one line.


def as_real_array(
    x: object,
    name: str,
    *,
    finite: bool = True,
    nonnegative: bool = False,
    positive: bool = False,
    ndim: int | Collection[int] | None = None,
    check: bool = True,
) -> np.ndarray:
    """``x`` (a real number, sequence, NumPy array or tensor) as a float64 NumPy array.

    Refuses None, bool, strings, complex, object and string arrays; then the number of
    dimensions (``ndim``), before any value is read; then (``check``) NaN, inf (unless
    ``finite=False``) and signs: with ``check=False`` the caller checks the shape first and
    then calls :func:`check_real_values`.

    Examples
    --------
    >>> as_real_array([1, 2], "depth").tolist()
    [1.0, 2.0]
    >>> as_real_array(None, "depth")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected depth as real numbers, got None
    """
    if x is None or isinstance(x, str | bytes | bool | np.bool_):
        raise InvalidInputError(f"expected {name} as real numbers, got {describe(x)}")
    if isinstance(x, numbers.Real) and not isinstance(x, np.generic):
        try:
            arr = np.asarray(float(x))
        except OverflowError:
            raise InvalidInputError(
                f"expected {name} within the float range, got {describe(x)}"
            ) from None
    else:
        try:
            arr = np.asarray(_to_numpy_host(x))
        except (TypeError, ValueError, RuntimeError) as exc:
            raise InvalidInputError(f"expected {name} as real numbers, got {describe(x)}") from exc
    if arr.dtype.kind not in "iuf":
        what = "a boolean" if arr.dtype.kind == "b" else f"dtype {arr.dtype}"
        raise InvalidInputError(f"expected {name} as real numbers, got {what} ({describe(x)})")
    if ndim is not None:
        dims = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if arr.ndim not in dims:
            want = " or ".join(f"{d}-d" for d in dims)
            raise InvalidInputError(
                f"expected {name} as a {want} array, got shape {format_shape(arr.shape)}"
            )
    arr = arr.astype(np.float64, copy=False)
    if check:
        check_real_values(arr, name, finite=finite, nonnegative=nonnegative, positive=positive)
    return arr


def check_real_values(
    arr: np.ndarray,
    name: str,
    *,
    finite: bool = True,
    nonnegative: bool = False,
    positive: bool = False,
) -> None:
    """Run the value checks of :func:`as_real_array` on a float NumPy array (one min/max pass).

    NaN always, inf unless ``finite=False`` (one message, "contains NaN or inf"), and the sign.
    """
    if not arr.size:
        return
    lo, hi = float(np.min(arr)), float(np.max(arr))
    if finite and not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    if math.isnan(lo) or math.isnan(hi):
        raise InvalidInputError(f"{name} contains NaN")
    if positive and lo <= 0:
        raise InvalidInputError(f"expected {name} > 0, got min {lo:g}")
    if nonnegative and lo < 0:
        raise InvalidInputError(f"expected {name} >= 0, got min {lo:g}")


def _to_numpy_host(x: object) -> Any:
    if array_api_compat.is_torch_array(x):
        return x.detach().cpu().numpy()
    return x


def as_reals(
    value: object,
    name: str,
    n: int | None = None,
    *,
    positive: bool = False,
    nonnegative: bool = False,
) -> tuple[float, ...]:
    """Convert a sequence of finite real numbers (``n`` of them if given) to a tuple of floats.

    Examples
    --------
    >>> as_reals((3, np.float32(1.5)), "center", 2)
    (3.0, 1.5)
    """
    if (
        isinstance(value, str | bytes)
        or not hasattr(value, "__iter__")
        or getattr(value, "ndim", 1) != 1
    ):
        want = f"{n} numbers" if n is not None else "a sequence of numbers"
        raise InvalidInputError(f"expected {name} as {want}, got {describe(value)}")
    items = list(value)
    if n is not None and len(items) != n:
        raise InvalidInputError(
            f"expected {name} as {n} numbers, got {len(items)} value(s): {describe(value)}"
        )
    if not items:
        raise InvalidInputError(f"expected {name} as a non-empty sequence of numbers, got none")
    return tuple(
        as_real(v, f"{name}[{i}]", positive=positive, nonnegative=nonnegative)
        for i, v in enumerate(items)
    )


def as_shape(
    value: object, name: str, n: int = 2, *, itemsize: int = 8, copies: int = 1
) -> tuple[int, ...]:
    """Check a shape of ``n`` positive integers whose arrays fit :func:`memory_limit`.

    The arrays are ``copies`` of ``itemsize``-byte elements; checked before anything is
    allocated.

    Examples
    --------
    >>> as_shape((np.int64(4), 6), "shape")
    (4, 6)
    """
    if getattr(value, "ndim", 1) != 1:  # a 0-d tensor has a len() that raises
        raise InvalidInputError(
            f"expected {name} as a tuple of {n} integers, got {describe(value)}"
        )
    shape = as_size(value, name, n)
    check_memory(
        float(math.prod(shape)) * itemsize * copies,
        name,
        f"an array of shape {format_shape(shape)}",
    )
    return shape


def _short(value: object) -> str:
    if isinstance(value, float | np.floating):
        return f"{float(value):.4g}"
    return describe(value, 24)


def finite_result(what: str, compute: Any, /, **inputs: object) -> Any:
    """Call ``compute()`` with floating-point warnings off, refusing non-finite results.

    An overflow, a division by zero or a non-finite result is refused in one line naming
    ``inputs`` (a formula evaluated beyond the float range: refuse it rather than return inf
    or NaN).

    Examples
    --------
    >>> finite_result("the blur", lambda: 1e300 * 1e300, f_number=1e300)
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: the blur is out of the float range for f_number=1e+300
    """
    try:
        with np.errstate(all="ignore"):
            out = compute()
        ok = _all_finite(out)
    except (ZeroDivisionError, OverflowError):
        ok = False
    if not ok:
        args = ", ".join(f"{k}={_short(v)}" for k, v in inputs.items())
        raise InvalidInputError(f"{what} is out of the float range for {args}"[:200])
    return out


def _all_finite(out: Any) -> bool:
    if isinstance(out, tuple | list):
        return all(_all_finite(v) for v in out)
    if isinstance(out, int):  # a Python int is exact (np.isfinite refuses a big one)
        return True
    if isinstance(out, float | np.generic | np.ndarray):
        return bool(np.all(np.isfinite(out)))
    xp = namespace(out)
    if is_dask_namespace(xp) or not reads_values(out):
        return True  # lazy, or on a device: not read here
    return bool(xp.all(xp.isfinite(out)))


# --- h16color ---


def dtype_kind(value: object) -> str:
    """Return NumPy's dtype kind of ``value`` without converting an array.

    ``"b"`` bool, ``"c"`` complex, ``"O"`` object, ``"U"`` string ...; ``""`` when it has
    none.
    """
    dt = getattr(value, "dtype", None)
    if dt is None:
        if isinstance(value, bool | np.bool_):
            return "b"
        if isinstance(value, complex):
            return "c"
        if isinstance(value, str | bytes):
            return "U"
        if isinstance(value, list | tuple):
            try:
                return np.asarray(value).dtype.kind
            except (TypeError, ValueError):
                return "O"
        return ""
    text = str(dt).removeprefix("torch.")
    if text == "bool":
        return "b"
    if text.startswith("complex"):
        return "c"
    return getattr(dt, "kind", "")


def refuse_non_real(value: object, name: str) -> None:
    """Refuse, before any conversion, values that are not real numbers.

    Bool arrays and bools (:class:`TypeError`: a mask is not a measurement), complex, object
    and string arrays (:class:`InvalidInputError`). Never casts, so no ComplexWarning is ever
    issued.

    Examples
    --------
    >>> refuse_non_real(np.array([True, False]), "xyz")
    Traceback (most recent call last):
    ...
    TypeError: expected xyz as real numbers, got bool values (cast with .astype(float) if meant)
    """
    kind = dtype_kind(value)
    if kind == "b":
        raise TypeError(
            f"expected {name} as real numbers, got bool values (cast with .astype(float) if meant)"
        )
    if kind == "c":
        raise InvalidInputError(f"expected {name} as real numbers, got complex values")
    if kind in ("O", "U", "S", "V", "M", "m"):
        raise InvalidInputError(f"expected {name} as real numbers, got {describe(value)}")


def as_real_ndarray(
    value: object,
    name: str,
    *,
    ndim: int | Collection[int] | None = None,
    last: int | None = None,
    min_size: int = 0,
    finite: bool = True,
) -> np.ndarray:
    """Convert ``value`` to a float64 NumPy array of reals (no bool, complex, object, string).

    With ``ndim`` dimensions (one of them), a last axis of ``last`` and ``>= min_size``
    elements, finite unless ``finite=False``; every refusal is one line naming ``name``.

    Examples
    --------
    >>> as_real_ndarray([400, 500], "wavelengths", ndim=1).tolist()
    [400.0, 500.0]
    """
    if value is None:
        raise InvalidInputError(f"expected {name} as an array of numbers, got None")
    refuse_non_real(value, name)
    return real_array(value, name, ndim=ndim, last=last, min_size=min_size, finite=finite)


def check_name(value: object, valid: Collection[str], what: str, name: str = "") -> str:
    """Check an option like :func:`check_option`, naming the parameter ``name``.

    The message reads like ``"unknown spectral table 'x' for key"`` and lists at most ~110
    characters of the valid names, so that it stays one line under 200 characters however
    many names are valid; a non-str is a TypeError.
    """
    if not isinstance(value, str):
        raise TypeError(f"expected {name or what} as a {what} name (str), got {describe(value)}")
    try:
        return check_option(value, valid, what)
    except UnknownOptionError:
        where = f" for {name}" if name else ""
        head = f"unknown {what} {describe(value, 30)}{where}; valid: "
        budget = min(110, 180 - len(head))  # the whole line stays under 200 characters
        names = sorted(valid)
        shown: list[str] = []
        size = 0
        for n in names:
            size += len(n) + 4
            if size > budget:
                break
            shown.append(repr(n))
        more = f", ... ({len(names) - len(shown)} more)" if len(shown) < len(names) else ""
        raise UnknownOptionError(f"{head}{', '.join(shown)}{more}") from None


# --- h16wf ---


def as_path(value: object, name: str) -> Any:
    """Convert a file or folder name (``str`` or ``os.PathLike``, not empty, no NUL) to a Path.

    The result is a :class:`pathlib.Path`; anything else is refused in one line naming
    ``name``.

    Examples
    --------
    >>> as_path("out/a.png", "out_dir").name
    'a.png'
    >>> as_path(0, "out_dir")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected out_dir as a file or folder name, got 0
    """
    from pathlib import Path

    if isinstance(value, str | os.PathLike) and not isinstance(value, bytes):
        text = os.fspath(value)
        if isinstance(text, str) and text.strip() and "\0" not in text:
            return Path(text)
    raise InvalidInputError(f"expected {name} as a file or folder name, got {describe(value)}")


def check_path(path: object, name: str) -> None:
    """Raise :class:`TypeError` naming ``name`` unless ``path`` is a str or os.PathLike.

    An empty string is refused too. Unlike :func:`as_path` (an
    :class:`~imageform.errors.InvalidInputError`), a wrong type is a :class:`TypeError`: the
    report functions' rule (moved from ``imageform.report._checks``, issue 30).
    """
    if not isinstance(path, str | os.PathLike) or (isinstance(path, str) and not path):
        raise TypeError(f"expected {name} as a non-empty path (str or Path), got {path!r:.40}")


# --- one home (issue 30): the checks the packages once kept in modules of their own ---
# (color/_guard.py, geometry/_checks.py, analysis/_guard.py, simulate/_guard.py,
# sensor/_guard.py). The variants below are the shared functions with a keyword fixed, for
# the packages whose rule it is: colour refuses non-real kinds first (``strict``), geometry
# bounds coordinates (``bound``).

#: Largest magnitude a colour value (RGB, XYZ, Lab, Luv, hue, ...) may have: 1e15 in float64,
#: 1e5 in float32. No colour is near it, and the formulas' powers of it (L*'s cube,
#: CIEDE2000's C*⁷) stay finite below it; larger values are refused instead of overflowing to
#: inf or NaN.
MAX_COLOR_MAGNITUDE = {"float64": 1e15, "float32": 1e5}

#: The largest coordinate magnitude geometry accepts: products of three coordinates, a
#: determinant or a cross product of such values stay finite in float64; beyond it a result
#: would overflow to inf or NaN with only a RuntimeWarning.
MAX_MAGNITUDE = 1e100

#: The largest image side accepted (pixels); :func:`check_memory` bounds the area.
MAX_SIDE = 2**31 - 1

#: The largest mean number of electrons per pixel a capture draws: far beyond any full well
#: (1e5-1e6 e⁻), and below NumPy's Poisson limit (about 9.2e18), which raises a bare
#: ``ValueError: lam value too large`` naming nothing.
MAX_MEAN_ELECTRONS = 1e15


def _shape_of(x: object) -> tuple[int, ...] | None:
    """Return the shape of an array-like that has one (NumPy, torch, Dask ...), unconverted."""
    shape = getattr(x, "shape", None)
    if shape is None or getattr(x, "ndim", None) is None:
        return None
    try:
        return tuple(int(d) for d in shape)
    except (TypeError, ValueError):  # unknown (NaN) Dask chunk sizes
        return None


def check_bounded(
    x: Any,
    name: str,
    xp: Any | None = None,
    limit: float = MAX_MAGNITUDE,
    *,
    finite: bool = True,
    why: str = "beyond it, products overflow",
) -> None:
    """Refuse ``|x| > limit`` (and, when ``finite``, NaN and inf) from one min/max pass.

    Only real floating arrays are read; device arrays (:func:`reads_values` False) are not.
    A Dask array is computed for the NaN/inf check when ``finite``, else skipped.

    Examples
    --------
    >>> check_bounded(np.array([1.0, -3e100]), "points")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected points within ±1e+100 (beyond it, products overflow), got values -3e+100..1
    """  # noqa: E501
    xp = namespace(x) if xp is None else xp
    if not xp.isdtype(x.dtype, "real floating") or math.prod(x.shape) == 0:
        return
    if not reads_values(x):
        return
    if is_dask_namespace(xp):
        if finite:
            check_finite(x, name, xp)
        return
    lo, hi = _min_max(x, xp)
    if finite and not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    if max(abs(lo), abs(hi)) > limit:
        raise InvalidInputError(
            f"expected {name} within ±{limit:g} ({why}), got values {lo:.3g}..{hi:.3g}"
        )


def check_magnitude(arr: Any, name: str, xp: Any | None = None) -> None:
    """Refuse colour values beyond :data:`MAX_COLOR_MAGNITUDE` (NaN is left to the caller).

    Skipped for Dask (lazy) and device arrays (:func:`reads_values`).
    """
    xp = namespace(arr) if xp is None else xp
    limit = MAX_COLOR_MAGNITUDE["float32" if arr.dtype == xp.float32 else "float64"]
    check_bounded(arr, name, xp, limit, finite=False, why="a colour value")


def as_float_strict(x: object, name: str, **kw: Any) -> Any:
    """:func:`as_float` with ``strict=True``: bool, complex, object, string refused first."""
    return as_float(x, name, strict=True, **kw)


def as_points_strict(x: object, name: str, dim: int | Collection[int], **kw: Any) -> Any:
    """:func:`as_points` with ``strict=True``: the kind, then the shape, then the values."""
    return as_points(x, name, dim, strict=True, **kw)


def as_image_strict(image: object, name: str = "image", **kw: Any) -> Any:
    """:func:`as_image` with ``strict=True``: the colour functions' image check."""
    return as_image(image, name, strict=True, **kw)


def as_float_bounded(x: object, name: str, **kw: Any) -> Any:
    """:func:`as_float` with ``bound=MAX_MAGNITUDE``: geometry's coordinates."""
    return as_float(x, name, bound=MAX_MAGNITUDE, **kw)


def as_points_bounded(x: object, name: str, dim: int | Collection[int], **kw: Any) -> Any:
    """:func:`as_points` with ``bound=MAX_MAGNITUDE``: geometry's points."""
    return as_points(x, name, dim, bound=MAX_MAGNITUDE, **kw)


def points_pass_bounded(arrays: Sequence[object], dim: int) -> bool:
    """Whether every array passes :func:`as_points_bounded` as it is, from one min/max pass.

    True when each is a float64 NumPy array of shape ``(..., dim)`` and their values, all
    together, are finite and within :data:`MAX_MAGNITUDE` (:func:`check_bounded`'s rule):
    then ``as_points_bounded(a, name, dim)`` returns every ``a`` itself, and a batch of
    point sets (the views of a calibration) need not be checked one by one. False says
    no more than that: check each with :func:`as_points_bounded`, which names the one that
    fails, and why.

    Examples
    --------
    >>> points_pass_bounded([np.zeros((4, 2)), np.ones((5, 2))], 2)
    True
    >>> points_pass_bounded([np.zeros((4, 2)), np.array([[np.nan, 0.0]])], 2)
    False
    """
    values = []
    for a in arrays:
        if type(a) is not np.ndarray:
            return False
        if a.dtype != np.float64 or a.ndim < 1 or a.shape[-1] != dim:
            return False
        if a.size:
            values.append(a.ravel())
    if not values:
        return True
    lo, hi = _min_max(np.concatenate(values), np)
    return math.isfinite(lo) and math.isfinite(hi) and max(abs(lo), abs(hi)) <= MAX_MAGNITUDE


def as_matrix_bounded(x: object, name: str, shape: tuple[int, int], **kw: Any) -> Any:
    """:func:`as_matrix` with ``bound=MAX_MAGNITUDE``: geometry's matrices."""
    return as_matrix(x, name, shape, bound=MAX_MAGNITUDE, **kw)


def check_result_array(x: object, name: str) -> None:
    """Refuse a field of a caller-built result container that is not a real, finite array.

    The container is built by a caller (not by imageform); refused are bool, complex, object
    and string values, NaN and inf. Lazy Dask arrays are not computed here.
    """
    if x is None:
        raise TypeError(f"expected {name} as an array of numbers, got None")
    refuse_non_real(x, name)
    if not (hasattr(x, "shape") and hasattr(x, "dtype")):
        x = as_real_ndarray(x, name, finite=False)
    xp = namespace(x)
    if not is_dask_namespace(xp):
        check_finite(x, name, xp)


def real_array(
    value: object,
    name: str,
    shape: tuple[int | None, ...] | None = None,
    *,
    ndim: int | Collection[int] | None = None,
    last: int | None = None,
    min_size: int = 0,
    finite: bool = True,
) -> np.ndarray:
    """Return ``value`` as a float64 NumPy array of real numbers, its shape checked first.

    The conversion is :func:`as_real_array`'s (None, bool, complex, object and string values
    are refused by name before any value is read; a tensor is copied to the host); then the
    shape: ``shape`` (``None`` for any length on
    that axis), ``ndim`` dimensions (one of them), ``last`` values on the last axis, at least
    ``min_size`` values; then NaN and inf unless ``finite=False``.

    Examples
    --------
    >>> real_array([[1, 2, 3]], "stains", (None, 3)).tolist()
    [[1.0, 2.0, 3.0]]
    >>> real_array([1, 2], "stains", (None, 3))
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: expected stains of shape (?, 3), got (2,)
    """
    arr = as_real_array(value, name, ndim=ndim, check=False)
    if shape is not None and (
        arr.ndim != len(shape)
        or any(want is not None and got != want for got, want in zip(arr.shape, shape, strict=True))
    ):
        raise InvalidInputError(
            f"expected {name} of shape {format_shape(shape)}, got {format_shape(arr.shape)}"
        )
    if last is not None and (arr.ndim < 1 or arr.shape[-1] != last):
        raise InvalidInputError(
            f"expected {name} of shape (..., {last}), got {format_shape(arr.shape)}"
        )
    if arr.size < min_size:
        raise InvalidInputError(
            f"expected {name} with at least {min_size} value(s), got shape "
            f"{format_shape(arr.shape)}"
        )
    if finite:
        check_real_values(arr, name)
    return arr


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


def check_nonzero_rows(m: np.ndarray, name: str) -> Any:
    """Return the row norms of ``m``; refuse a zero-length row (it has no direction)."""
    norms = np.linalg.norm(m, axis=-1)
    if np.any(norms <= 1e-12):
        i = int(np.argmin(norms))
        raise InvalidInputError(f"expected {name} rows of non-zero length, row {i} is zero")
    return norms


def real_pair(
    value: object,
    name: str,
    *,
    positive: bool = False,
    scalar_ok: bool = False,
    limit: float = MAX_MAGNITUDE,
) -> tuple[float, float]:
    """Two finite reals ``(a, b)`` within ``±limit``; one number for both when ``scalar_ok``."""
    if scalar_ok and (
        isinstance(value, int | float | np.number)
        or (getattr(value, "ndim", None) == 0 and not isinstance(value, str | bytes))
    ):
        v = as_real(value, name, positive=positive, maximum=limit, minimum=-limit)
        return v, v
    if getattr(value, "ndim", 1) != 1 or not hasattr(value, "__len__"):
        raise InvalidInputError(f"expected {name} as 2 numbers, got {describe(value)}")
    a, b = as_reals(value, name, 2)
    return (
        as_real(a, f"{name}[0]", positive=positive, maximum=limit, minimum=-limit),
        as_real(b, f"{name}[1]", positive=positive, maximum=limit, minimum=-limit),
    )


def size_pair(value: object, name: str, *, minimum: int = 1) -> tuple[int, int]:
    """Two integers ``(a, b)``, each in ``[minimum, MAX_SIDE]``."""
    a, b = as_size(value, name, 2, minimum=minimum, maximum=MAX_SIDE)
    return a, b


def shape_text(x: Any) -> str:
    """``(4, 2)``: the shape of an array for a message."""
    return format_shape(tuple(x.shape))


def check_K(K: Any, xp: Any, name: str = "K", *, positive: bool = False) -> None:
    """Refuse a K that is not upper-triangular with a non-zero diagonal (singular).

    When ``positive``, also refuse focal lengths ``K[0, 0] / K[2, 2]``, ``K[1, 1] / K[2, 2]``
    that are not > 0. ``K`` has been through :func:`as_matrix` (finite). Device arrays
    (:func:`reads_values` False) are not read.
    """
    if not reads_values(K):
        return
    if (
        bool(xp.any(K[..., 2, 0] != 0))
        or bool(xp.any(K[..., 2, 1] != 0))
        or bool(xp.any(K[..., 1, 0] != 0))
    ):
        raise InvalidInputError(
            f"expected an upper-triangular {name} with last row (0, 0, k33), got {describe(K)}"
        )
    if bool(xp.any(K[..., 0, 0] * K[..., 1, 1] * K[..., 2, 2] == 0)):
        raise InvalidInputError(f"{name} is singular (fx, fy or {name}[2, 2] is zero)")
    if positive:
        fx = K[..., 0, 0] / K[..., 2, 2]
        fy = K[..., 1, 1] / K[..., 2, 2]
        if bool(xp.any(~(fx > 0))) or bool(xp.any(~(fy > 0))):
            raise InvalidInputError(
                f"expected focal lengths fx > 0 and fy > 0 in {name}, got fx min "
                f"{float(xp.min(fx)):g}, fy min {float(xp.min(fy)):g} (a negative focal "
                "length mirrors the image)"
            )


def check_rng(rng: object, name: str = "rng") -> object:
    """Return ``rng`` unchanged when :func:`imageform._random.as_rng` takes it.

    An int seed, a :class:`numpy.random.Generator`, a :class:`numpy.random.SeedSequence` or
    None; anything else is refused in one line that never prints an array.
    """
    if (
        rng is None
        or isinstance(rng, np.random.Generator | np.random.SeedSequence)
        or (isinstance(rng, numbers.Integral) and not isinstance(rng, bool | np.bool_))
    ):
        return rng
    raise InvalidInputError(
        f"expected {name} as an int seed, a numpy.random.Generator or None, got {describe(rng)}"
    )


def check_electrons(mean: float, names: str) -> None:
    """Refuse a mean signal above :data:`MAX_MEAN_ELECTRONS` electrons per pixel."""
    if not mean <= MAX_MEAN_ELECTRONS:
        raise InvalidInputError(
            f"expected {names} giving at most {MAX_MEAN_ELECTRONS:g} mean electrons per pixel, "
            f"got {mean:.3g}"
        )
