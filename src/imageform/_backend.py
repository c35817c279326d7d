"""Array-namespace dispatch, dtype policy and numba availability.

NumPy is the reference implementation. Public functions call :func:`namespace` on their
array arguments and compute with the returned Array-API namespace ``xp``, so PyTorch, CuPy,
JAX, Dask and array-api-strict arrays come back as the same kind, on the same device, with
gradients flowing where the library supports them. Python scalars, lists and tuples are
NumPy input.

dtype policy (DESIGN.md): float32 in → float32 out, float64 in → float64 out. Integer
*images* compute in float32 (:data:`IMAGE_INTEGER_DTYPE`); integer *coordinates* compute in
float64 (:data:`COORD_INTEGER_DTYPE`), because hand-typed integer points (``[3, -1, 5]``)
are exact numbers whose answers should not lose digits to float32.

Hot NumPy paths dispatch to numba kernels in :mod:`imageform._kernels` when
:func:`use_numba` says so; set ``IMAGEFORM_DISABLE_NUMBA=1`` to force the plain array twins.
"""

from __future__ import annotations

import os
from typing import Any, Literal

import array_api_compat
import numpy as np
from array_api_compat import numpy as compat_numpy

__all__ = [
    "COORD_INTEGER_DTYPE",
    "HAVE_NUMBA",
    "IMAGE_INTEGER_DTYPE",
    "Array",
    "asarray_like",
    "device_of",
    "float_dtype",
    "is_numpy_namespace",
    "namespace",
    "to_numpy",
    "use_numba",
]

#: Any Array-API array (NumPy, PyTorch, CuPy, JAX, Dask, array-api-strict).
Array = Any

IMAGE_INTEGER_DTYPE: Literal["float32"] = "float32"
COORD_INTEGER_DTYPE: Literal["float64"] = "float64"

try:  # numba is a hard dependency, but a broken install should degrade, not crash imports.
    import numba  # noqa: F401

    HAVE_NUMBA = True
except Exception:  # pragma: no cover - exercised only on broken installs
    HAVE_NUMBA = False


def _is_array(x: object) -> bool:
    return bool(array_api_compat.is_array_api_obj(x)) and not isinstance(x, np.generic)


def namespace(*arrays: object) -> Any:
    """Return the Array-API namespace shared by ``arrays``.

    Non-arrays (Python scalars, lists, tuples, ``None``) and NumPy arrays do not decide the
    namespace when another library's array is present: a NumPy ``K`` with PyTorch points
    computes in PyTorch. Two different non-NumPy libraries raise ``TypeError``.
    """
    foreign = [a for a in arrays if _is_array(a) and not array_api_compat.is_numpy_array(a)]
    if not foreign:
        return compat_numpy
    return array_api_compat.array_namespace(*foreign)


def is_numpy_namespace(xp: Any) -> bool:
    """True when ``xp`` is NumPy (through array-api-compat or directly)."""
    return bool(array_api_compat.is_numpy_namespace(xp))


def device_of(x: object) -> Any:
    """Device of an array, or ``None`` for non-arrays and NumPy."""
    if _is_array(x) and not array_api_compat.is_numpy_array(x):
        return array_api_compat.device(x)
    return None


def float_dtype(x: Any, xp: Any, *, integer: str = IMAGE_INTEGER_DTYPE) -> Any:
    """The floating dtype a computation on ``x`` runs in.

    float32 and float64 are kept; float16/bfloat16 compute in float32; integers and bools
    compute in ``integer`` (``"float32"`` for images, ``"float64"`` for coordinates).
    """
    dt = x.dtype
    if xp.isdtype(dt, "real floating"):
        if dt == xp.float64 or dt == xp.float32:
            return dt
        return xp.float32
    if xp.isdtype(dt, "complex floating"):
        raise TypeError(f"complex input is not supported, got dtype {dt}")
    return getattr(xp, integer)


def asarray_like(x: object, xp: Any, dtype: Any = None, device: Any = None) -> Any:
    """Convert ``x`` to an array of namespace ``xp`` (optionally with ``dtype``/``device``)."""
    if array_api_compat.is_numpy_array(x) and not is_numpy_namespace(xp):
        x = np.asarray(x)
    if dtype is None:
        return xp.asarray(x, device=device) if device is not None else xp.asarray(x)
    if device is not None:
        return xp.asarray(x, dtype=dtype, device=device)
    return xp.asarray(x, dtype=dtype)


def to_numpy(x: object) -> np.ndarray:
    """A NumPy view/copy of any array (moves GPU tensors to host, detaches gradients)."""
    if array_api_compat.is_torch_array(x):
        return x.detach().cpu().numpy()  # type: ignore[attr-defined, no-any-return]
    return np.asarray(x)


def use_numba(*arrays: object, min_size: int = 0) -> bool:
    """Whether a hot path should run its numba kernel for these arrays.

    True only for NumPy arrays (numba cannot take other libraries' arrays), when numba
    imports, ``IMAGEFORM_DISABLE_NUMBA`` is not set, and the first array has at least
    ``min_size`` elements (below that, compilation and call overhead dominate).
    """
    if not HAVE_NUMBA or os.environ.get("IMAGEFORM_DISABLE_NUMBA", "") not in ("", "0"):
        return False
    if not all(isinstance(a, np.ndarray) for a in arrays):
        return False
    return bool(arrays) and arrays[0].size >= min_size  # type: ignore[attr-defined]
