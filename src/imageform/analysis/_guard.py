"""Boundary checks shared by the analysis tools (issue 16).

Real arrays and the validation of the result dataclasses a user can also build by hand.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._validate import as_float, as_int, as_real, describe, format_shape
from imageform.errors import InvalidInputError

__all__ = ["count", "dtype_kind", "real_array", "real_triple", "target_source", "unit_rows"]


def real_array(
    x: object, name: str, shape: tuple[int | None, ...] | None = None, *, finite: bool = True
) -> np.ndarray:
    """Return ``x`` as a float64 NumPy array, its ``shape`` checked before the values.

    Complex, object, string and bool-only input is refused; ``shape`` may hold ``None`` for any
    length on that axis.
    """
    if x is None or isinstance(x, str | bytes):
        raise InvalidInputError(f"expected {name} as a numeric array, got {describe(x)}")
    arr = np.asarray(as_float(x, name, finite=False), dtype=np.float64)
    if shape is not None and (
        arr.ndim != len(shape)
        or any(want is not None and got != want for got, want in zip(arr.shape, shape, strict=True))
    ):
        want_s = format_shape(shape)
        raise InvalidInputError(
            f"expected {name} of shape {want_s}, got {format_shape(tuple(arr.shape))}"
        )
    if finite and arr.size and not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    return arr


def real_triple(x: object, name: str, *, nonnegative: bool = False) -> tuple[float, float, float]:
    """Three finite real numbers (a tuple, list or array of length 3)."""
    if isinstance(x, str | bytes) or not hasattr(x, "__len__") or not hasattr(x, "__iter__"):
        raise InvalidInputError(f"expected {name} as 3 numbers, got {describe(x)}")
    items = list(x)
    if len(items) != 3:
        raise InvalidInputError(f"expected {name} as 3 numbers, got {len(items)}: {describe(x)}")
    a, b, c = (as_real(v, f"{name}[{i}]", nonnegative=nonnegative) for i, v in enumerate(items))
    return a, b, c


def count(x: object, name: str) -> int:
    """Return a count >= 0 (Python or NumPy integer)."""
    return as_int(x, name, minimum=0)


def unit_rows(m: np.ndarray, name: str) -> Any:
    """Refuse a zero-length row (a stain vector of length 0 has no direction)."""
    norms = np.linalg.norm(m, axis=-1)
    if np.any(norms <= 1e-12):
        i = int(np.argmin(norms))
        raise InvalidInputError(f"expected {name} rows of non-zero length, row {i} is zero")
    return norms


def target_source(target: object, name: str, what: str) -> Any:
    """Return a normalisation target that is not a statistics object: a JSON path or an image.

    An existing JSON file is returned as its :class:`~pathlib.Path`; an image is validated under the
    parameter's own ``name`` (never reported as ``image``).
    """
    from pathlib import Path

    from imageform.analysis._arrays import image_in

    if target is None:
        raise TypeError(f"expected {name} as an image, {what} or a JSON path, got None")
    if isinstance(target, str | Path):
        path = Path(target)
        if not path.is_file():
            raise InvalidInputError(
                f"expected {name} as an image, {what} or an existing JSON file, got "
                f"{describe(str(target))} (no such file)"
            )
        return path
    return image_in(target, name)


def dtype_kind(value: object) -> str:
    """Return the NumPy dtype kind of ``value`` (``"O"`` when it does not convert)."""
    dtype = getattr(value, "dtype", None)
    if dtype is not None and not isinstance(dtype, np.dtype):  # a tensor: by its name
        text = str(dtype).removeprefix("torch.")
        return "b" if text == "bool" else "c" if text.startswith("complex") else "f"
    try:
        return np.asarray(value).dtype.kind
    except (TypeError, ValueError):
        return "O"
