"""Geometry's boundary checks (issue 16): scalars, pairs, shapes, K, and a magnitude bound.

The shared checks of :mod:`imageform._validate` do the work; this module adds what only
geometry needs:

- :func:`as_points` / :func:`as_matrix` / :func:`as_float`: the shared checks, the shape
  refused *before* the values are scanned, and one min/max pass that refuses NaN, inf and
  magnitudes beyond :data:`MAX_MAGNITUDE` (1e100: products of three coordinates, a
  determinant or a cross product of such values, stay finite in float64; beyond it a
  result would overflow to inf or NaN with only a RuntimeWarning);
- :func:`real_pair`, :func:`size_pair`: two numbers as a tuple, in one line naming the
  parameter;
- :func:`check_K`: a calibration matrix as :func:`~imageform.geometry.project_points`
  wants it (finite, upper-triangular, non-singular), optionally with positive focal lengths.
"""

from __future__ import annotations

import math
from typing import Any

import array_api_compat
import numpy as np

from imageform._backend import is_dask_namespace, namespace, reads_values, scalar, to_numpy
from imageform._validate import (
    as_float as _as_float,
)
from imageform._validate import (
    as_int,
    as_real,
    check_memory,
    describe,
    format_shape,
)
from imageform._validate import (
    as_matrix as _as_matrix,
)
from imageform._validate import (
    as_points as _as_points,
)
from imageform.errors import InvalidInputError

__all__ = [
    "MAX_MAGNITUDE",
    "as_float",
    "as_matrix",
    "as_points",
    "check_K",
    "check_bounded",
    "check_memory",
    "count",
    "real_pair",
    "size_pair",
]

#: The largest coordinate magnitude geometry accepts (see the module docstring).
MAX_MAGNITUDE = 1e100


def _min_max(x: Any, xp: Any) -> tuple[float, float]:
    if array_api_compat.is_torch_array(x):
        lo, hi = x.detach().aminmax()
        pair = xp.stack((lo, hi)).cpu().tolist()
        return float(pair[0]), float(pair[1])
    return scalar(xp.min(x)), scalar(xp.max(x))


def check_bounded(x: Any, name: str, xp: Any | None = None, limit: float = MAX_MAGNITUDE) -> None:
    """Refuse NaN, inf and ``|x| > limit`` in a real floating array, from one min/max pass.

    Device arrays (:func:`imageform._backend.reads_values` False) are not read.
    """
    xp = namespace(x) if xp is None else xp
    if not xp.isdtype(x.dtype, "real floating") or math.prod(x.shape) == 0:
        return
    if not reads_values(x):
        return
    if is_dask_namespace(xp):  # the shared check computes what it must
        from imageform._validate import check_finite

        check_finite(x, name, xp)
        return
    lo, hi = _min_max(x, xp)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    if max(-lo, hi) > limit:
        raise InvalidInputError(
            f"expected {name} with magnitudes <= {limit:g} (beyond, products overflow), "
            f"got {max(-lo, hi):g}"
        )


def _host(x: object, kw: dict[str, Any]) -> object:
    """Move a tensor asked for as NumPy (``xp=np``) to the host first."""
    if kw.get("xp") is np and array_api_compat.is_torch_array(x):
        return to_numpy(x)
    return x


def as_float(x: object, name: str, *, finite: bool = True, **kw: Any) -> Any:
    """:func:`imageform._validate.as_float` with the magnitude bound when ``finite``."""
    arr = _as_float(_host(x, kw), name, finite=False, **kw)
    if finite:
        check_bounded(arr, name, kw.get("xp"))
    return arr


def as_points(x: object, name: str, dim: Any, *, finite: bool = True, **kw: Any) -> Any:
    """:func:`imageform._validate.as_points`, the shape checked before the values."""
    arr = _as_points(_host(x, kw), name, dim, finite=False, **kw)
    if finite:
        check_bounded(arr, name, kw.get("xp"))
    return arr


def as_matrix(
    x: object, name: str, shape: tuple[int, int], *, finite: bool = True, **kw: Any
) -> Any:
    """:func:`imageform._validate.as_matrix`, the shape checked before the values."""
    arr = _as_matrix(_host(x, kw), name, shape, finite=False, **kw)
    if finite:
        check_bounded(arr, name, kw.get("xp"))
    return arr


def count(value: object, name: str, *, minimum: int = 1, maximum: int = 10**9) -> int:
    """Check an integer count (Python or NumPy integer) within ``[minimum, maximum]``."""
    return as_int(value, name, minimum=minimum, maximum=maximum)


def _items(value: object, name: str, n: int, what: str) -> list[Any]:
    if (
        isinstance(value, str | bytes)
        or not hasattr(value, "__len__")
        or not hasattr(value, "__iter__")
        or getattr(value, "ndim", 1) != 1
    ):
        raise InvalidInputError(f"expected {name} as {n} {what}, got {describe(value)}")
    items = list(value)
    if len(items) != n:
        raise InvalidInputError(
            f"expected {name} as {n} {what}, got {len(items)} value(s): {describe(value)}"
        )
    return items


def real_pair(
    value: object,
    name: str,
    *,
    positive: bool = False,
    scalar_ok: bool = False,
    limit: float = MAX_MAGNITUDE,
) -> tuple[float, float]:
    """Two finite reals ``(a, b)``; one number stands for both when ``scalar_ok``."""
    if scalar_ok and (
        isinstance(value, int | float | np.number)
        or (getattr(value, "ndim", None) == 0 and not isinstance(value, str | bytes))
    ):
        v = as_real(value, name, positive=positive, maximum=limit, minimum=-limit)
        return v, v
    a, b = _items(value, name, 2, "numbers")
    return (
        as_real(a, f"{name}[0]", positive=positive, maximum=limit, minimum=-limit),
        as_real(b, f"{name}[1]", positive=positive, maximum=limit, minimum=-limit),
    )


#: The largest image side geometry accepts (pixels); the memory check bounds the area.
MAX_SIDE = 2**31 - 1


def size_pair(value: object, name: str, *, minimum: int = 1) -> tuple[int, int]:
    """Two integers ``(a, b)``, each in ``[minimum, 2**31 - 1]``."""
    a, b = _items(value, name, 2, "integers")
    return (
        as_int(a, f"{name}[0]", minimum=minimum, maximum=MAX_SIDE),
        as_int(b, f"{name}[1]", minimum=minimum, maximum=MAX_SIDE),
    )


def check_K(K: Any, xp: Any, name: str = "K", *, positive: bool = False) -> None:
    """Refuse a K that is not upper-triangular with a non-zero diagonal (singular).

    When ``positive``, also refuse focal lengths ``K[0, 0] / K[2, 2]``, ``K[1, 1] / K[2, 2]``
    that are not > 0. ``K`` has been through :func:`as_matrix` (finite). Device arrays
    (:func:`imageform._backend.reads_values` False) are not read.
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


def shape_text(x: Any) -> str:
    """``(4, 2)``: the shape of an array for a message."""
    return format_shape(tuple(x.shape))


def check_image_size(size: object, name: str = "image_size") -> tuple[int, int]:
    """Check a ``(width, height)`` pair of positive integers.

    A 0-d array or a string is refused in one line, as every other malformed pair.
    """
    return size_pair(size, f"{name} (width, height)")


def check_rng(value: object, name: str = "rng") -> object:
    """Refuse an array for a seed before the shared :func:`imageform._random.as_rng`.

    That function's message would print the array; the value is returned unchanged.
    """
    if getattr(value, "ndim", 0) and not isinstance(value, str | bytes):
        raise InvalidInputError(
            f"expected {name} an int seed, a numpy.random.Generator or None, got " + describe(value)
        )
    return value
