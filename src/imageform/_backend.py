"""Array-namespace dispatch, dtype policy and numba availability.

NumPy is the reference implementation. Public functions call :func:`namespace` on their
array arguments and compute with the returned Array-API namespace ``xp``, so PyTorch, CuPy,
JAX, Dask and array-api-strict arrays come back as the same kind, on the same device, with
gradients flowing where the library supports them. Python scalars, lists and tuples are
NumPy input.

dtype policy (docs/conventions.md): float32 in → float32 out, float64 in → float64 out. Integer
*images* compute in float32 (:data:`IMAGE_INTEGER_DTYPE`); integer *coordinates* compute in
float64 (:data:`COORD_INTEGER_DTYPE`), because hand-typed integer points (``[3, -1, 5]``)
are exact numbers whose answers should not lose digits to float32.

Hot NumPy paths dispatch to numba kernels in :mod:`imageform._kernels` when
:func:`use_numba` says so; set ``IMAGEFORM_DISABLE_NUMBA=1`` to force the plain array twins.
"""

from __future__ import annotations

import os
from functools import cache
from typing import Any, Literal

import array_api_compat
import numpy as np

__all__ = [
    "COORD_INTEGER_DTYPE",
    "IMAGE_INTEGER_DTYPE",
    "Array",
    "asarray_like",
    "common_device",
    "constant",
    "device_of",
    "float_dtype",
    "have_numba",
    "is_dask_namespace",
    "is_numpy_namespace",
    "linalg",
    "namespace",
    "numba_enabled",
    "reads_values",
    "scalar",
    "sign_of",
    "to_numpy",
    "use_numba",
]

#: Any Array-API array (NumPy, PyTorch, CuPy, JAX, Dask, array-api-strict).
Array = Any

IMAGE_INTEGER_DTYPE: Literal["float32"] = "float32"
COORD_INTEGER_DTYPE: Literal["float64"] = "float64"


@cache
def have_numba() -> bool:
    """Whether numba imports (checked on first use, not when imageform is imported).

    numba is a hard dependency, but a broken install should degrade to the plain array
    twins, not crash; importing it costs about 0.1 s, paid only by the first hot path.
    """
    try:
        # numba through the kernels' policy module: it points numba's cache at the user's
        # cache folder first when the package folder is read-only (imageform._kernels.jit)
        import imageform._kernels.jit  # noqa: F401
    except Exception:  # pragma: no cover - exercised only on broken installs
        return False
    return True


def _is_array(x: object) -> bool:
    # NumPy arrays and PyTorch tensors answer in one test each (array-api-compat's general
    # test asks half a dozen libraries first: a GPU call's host time is made of such tests)
    if isinstance(x, np.ndarray) or array_api_compat.is_torch_array(x):
        return True
    return bool(array_api_compat.is_array_api_obj(x)) and not isinstance(x, np.generic)


@cache
def _compat_numpy() -> Any:
    # array-api-compat's NumPy namespace costs about 0.1 s to import (it touches NumPy's
    # lazy submodules): paid by the first computation, not by importing imageform
    from array_api_compat import numpy as compat_numpy

    return compat_numpy


def namespace(*arrays: object) -> Any:
    """Return the Array-API namespace shared by ``arrays``.

    Non-arrays (Python scalars, lists, tuples, ``None``) and NumPy arrays do not decide the
    namespace when another library's array is present: a NumPy ``K`` with PyTorch points
    computes in PyTorch. Two different non-NumPy libraries raise ``TypeError``.
    """
    foreign = [a for a in arrays if _is_array(a) and not array_api_compat.is_numpy_array(a)]
    if not foreign:
        return _compat_numpy()
    return array_api_compat.array_namespace(*foreign)


def is_numpy_namespace(xp: Any) -> bool:
    """Tell whether ``xp`` is NumPy (through array-api-compat or directly)."""
    return bool(array_api_compat.is_numpy_namespace(xp))


def is_dask_namespace(xp: Any) -> bool:
    """Tell whether ``xp`` is Dask's array namespace (through array-api-compat)."""
    return bool(array_api_compat.is_dask_namespace(xp))


class _DaskLinalg:
    """The Array-API ``linalg`` functions imageform uses, lazily on Dask arrays.

    ``dask.array.linalg`` covers only tall-and-skinny SVDs and square-chunked LU, and has no
    ``cross``; imageform's matrices are small stacks (``(..., 3, 3)``, DLT systems), so each
    function runs NumPy's on every batch block with the core (matrix) axes in one chunk
    (:func:`dask.array.apply_gufunc` with ``allow_rechunk``): still lazy, one task per block.
    """

    @staticmethod
    def _gufunc(fn: Any, signature: str, *args: Any, **kwargs: Any) -> Any:
        import dask.array as da

        return da.apply_gufunc(fn, signature, *args, allow_rechunk=True, **kwargs)

    @staticmethod
    def cross(a: Any, b: Any, axis: int = -1) -> Any:
        if axis != -1:
            raise NotImplementedError("cross on Dask arrays: axis=-1 only")
        import dask.array as da

        a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2]
        b1, b2, b3 = b[..., 0], b[..., 1], b[..., 2]
        return da.stack([a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1], axis=-1)

    def det(self, a: Any) -> Any:
        return self._gufunc(np.linalg.det, "(i,j)->()", a, output_dtypes=a.dtype)

    def inv(self, a: Any) -> Any:
        return self._gufunc(np.linalg.inv, "(i,j)->(i,j)", a, output_dtypes=a.dtype)

    def solve(self, a: Any, b: Any) -> Any:
        return self._gufunc(np.linalg.solve, "(i,j),(j,k)->(i,k)", a, b, output_dtypes=a.dtype)

    def svdvals(self, a: Any) -> Any:
        m, n = int(a.shape[-2]), int(a.shape[-1])
        return self._gufunc(
            lambda x: np.linalg.svd(x, compute_uv=False),
            "(m,n)->(k)",
            a,
            output_dtypes=a.dtype,
            output_sizes={"k": min(m, n)},
        )

    def svd(self, a: Any, full_matrices: bool = True) -> tuple[Any, Any, Any]:
        m, n = int(a.shape[-2]), int(a.shape[-1])
        k = min(m, n)
        return tuple(
            self._gufunc(
                lambda x: tuple(np.linalg.svd(x, full_matrices=full_matrices)),
                "(m,n)->(m,p),(k),(q,n)",
                a,
                output_dtypes=(a.dtype, a.dtype, a.dtype),
                output_sizes={
                    "p": m if full_matrices else k,
                    "k": k,
                    "q": n if full_matrices else k,
                },
            )
        )

    def qr(self, a: Any) -> tuple[Any, Any]:
        m, n = int(a.shape[-2]), int(a.shape[-1])
        k = min(m, n)
        return tuple(
            self._gufunc(
                lambda x: tuple(np.linalg.qr(x)),
                "(m,n)->(m,k),(k,n)",
                a,
                output_dtypes=(a.dtype, a.dtype),
                output_sizes={"k": k},
            )
        )


_DASK_LINALG = _DaskLinalg()


def linalg(xp: Any) -> Any:
    """``xp.linalg``, or for Dask a lazy stand-in covering small stacked matrices."""
    return _DASK_LINALG if is_dask_namespace(xp) else xp.linalg


def device_of(x: object) -> Any:
    """Device of an array, or ``None`` for non-arrays and NumPy."""
    if isinstance(x, np.ndarray):
        return None
    if array_api_compat.is_torch_array(x):
        return x.device  # what array_api_compat.device answers, without its other tests
    if _is_array(x) and not array_api_compat.is_numpy_array(x):
        return array_api_compat.device(x)
    return None


def common_device(*arrays: object) -> Any:
    """Device of the first non-NumPy array among ``arrays``, or ``None``.

    For the parameters of a call that are not arrays of the computing library (Python lists,
    defaults, NumPy constants): converting them with ``device=common_device(...)`` puts them
    where the caller's data is, so a CUDA call never mixes in CPU tensors.
    """
    for a in arrays:
        dev = device_of(a)
        if dev is not None:
            return dev
    return None


#: Uploaded constants: (bytes, shape, library, dtype, device) -> array (small matrices and
#: white points; bounded, cleared when full).
_CONSTANTS: dict[tuple[Any, ...], Any] = {}
_MAX_CONSTANTS = 1024


def constant(values: np.ndarray, like: Any, xp: Any) -> Any:
    """Return a NumPy constant (matrix, white point) as an ``xp`` array like ``like``.

    NumPy: a cast copy. PyTorch and CuPy: uploaded once per device and dtype and cached, so a
    call does not copy its constants host-to-device each time; inside ``torch.compile``
    tracing the constant is made in the graph instead (no cache, no ``.tolist()``).
    """
    if isinstance(like, np.ndarray):
        return np.ascontiguousarray(values, dtype=like.dtype)
    dev = device_of(like)
    if array_api_compat.is_torch_array(like):
        import torch

        if torch.compiler.is_compiling():
            return torch.as_tensor(values, dtype=like.dtype, device=dev)
    elif not array_api_compat.is_cupy_array(like):
        return xp.asarray(values.tolist(), dtype=like.dtype, device=dev)
    return upload_cached(values, xp, like.dtype, dev)


def float_dtype(x: Any, xp: Any, *, integer: str = IMAGE_INTEGER_DTYPE) -> Any:
    """Return the floating dtype a computation on ``x`` runs in.

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


#: Host arrays up to this many values go through the upload cache (:func:`asarray_like`).
_SMALL_HOST = 64


def _cached_host(x: np.ndarray, xp: Any, dtype: Any, device: Any) -> Any:
    """``x`` on a GPU ``device`` as ``dtype``, uploaded once and cached; else None.

    PyTorch CUDA tensors and CuPy arrays only (a CPU or ``meta`` tensor costs no copy, and
    ``torch.compile`` makes constants in its graph); the shape is ``x``'s, 0-d included.
    """
    name = getattr(xp, "__name__", "")
    if "torch" in name:
        import torch

        if torch.compiler.is_compiling() or torch.device(device).type in ("cpu", "meta"):
            return None
    elif "cupy" not in name:
        return None
    return upload_cached(x, xp, dtype, device)


def upload_cached(x: np.ndarray, xp: Any, dtype: Any, device: Any) -> Any:
    """Return host ``x`` as an ``xp`` array on ``device`` (``dtype``), from the upload cache."""
    name = getattr(xp, "__name__", "")
    key = (x.tobytes(), x.shape, x.dtype.str, name, str(dtype), str(device))
    out = _CONSTANTS.get(key)
    if out is None:
        if len(_CONSTANTS) >= _MAX_CONSTANTS:
            _CONSTANTS.clear()
        host = np.array(x, order="C")  # 0-d stays 0-d (ascontiguousarray makes it 1-d)
        if "torch" in name:
            import torch

            # a plain tensor even when the first call runs under inference_mode: an
            # inference tensor in the cache would break every later call that records
            # gradients
            with torch.inference_mode(False):
                out = torch.tensor(host, dtype=dtype, device=device)
        else:
            out = xp.asarray(host, dtype=dtype, device=device, copy=True)
        _CONSTANTS[key] = out
    return out


def asarray_like(x: object, xp: Any, dtype: Any = None, device: Any = None) -> Any:
    """Convert ``x`` to an array of namespace ``xp`` (optionally with ``dtype``/``device``)."""
    if not is_numpy_namespace(xp) and (
        array_api_compat.is_numpy_array(x) or isinstance(x, list | tuple | float | int)
    ):
        # Python numbers and lists are read by NumPy's rules (a float list is float64), as
        # on the NumPy path, not by the other library's default dtype (torch: float32)
        x = np.asarray(x)
        if device is not None and x.size <= _SMALL_HOST and x.dtype.kind in "biuf":
            # a small host matrix (K, R, t, coefficients) with device data: uploaded once
            # and cached, as constants are, so a call does not copy it host-to-device
            # each time (a pageable copy synchronises the stream)
            cached = _cached_host(x, xp, dtype, device)
            if cached is not None:
                return cached
    elif _is_array(x) and namespace(x) is xp and (device is None or device == device_of(x)):
        # already an array of this namespace: no copy, the autograd graph is kept
        return x if dtype is None or x.dtype == dtype else xp.astype(x, dtype)  # type: ignore[attr-defined]
    if dtype is None:
        return xp.asarray(x, device=device) if device is not None else xp.asarray(x)
    if device is not None:
        return xp.asarray(x, dtype=dtype, device=device)
    return xp.asarray(x, dtype=dtype)


#: Host values (a tuple, not a union: ``torch.compile`` traces ``isinstance`` with it).
_HOST_TYPES = (np.ndarray, np.generic, float, int)


def _env_device_checks() -> bool:
    return os.environ.get("IMAGEFORM_DEVICE_CHECKS", "") not in ("", "0")


def reads_values(x: object) -> bool:
    """Whether a boundary check may read the values of ``x`` (docs/design.md, "Devices").

    True when the data is in host memory and reading it costs no synchronisation: NumPy
    arrays, Python numbers, array-api-strict arrays, PyTorch tensors on the CPU (outside
    ``torch.compile`` tracing, where values are unknown). False for everything else (CUDA,
    ROCm, MPS and ``meta`` tensors, CuPy, JAX): there imageform checks shapes and dtypes only,
    and a NaN or inf in the input comes out as NaN/inf in the output instead of an error. Set
    ``IMAGEFORM_DEVICE_CHECKS=1`` to read device values too (each check then waits for the
    device). Dask arrays answer True; their checks run per chunk, lazily.
    """
    if isinstance(x, _HOST_TYPES):
        return True
    if array_api_compat.is_torch_array(x):
        import torch

        if torch.compiler.is_compiling():
            return False
        if x.device.type == "cpu":
            return True
        return _env_device_checks()
    if not _is_array(x) or array_api_compat.is_numpy_array(x) or array_api_compat.is_dask_array(x):
        return True
    if type(x).__module__.startswith("array_api_strict"):
        return True
    return _env_device_checks()


def sign_of(x: Any, xp: Any) -> Any:
    """``xp.sign(x)`` (NaN stays NaN) without array-api-compat's masked write on PyTorch.

    array-api-compat patches ``torch.sign``'s NaN with ``out[isnan(x)] = nan``: a boolean
    index, which on CUDA waits for the device (``nonzero``) and fails on ``meta``; one
    ``where`` does the same on the device.
    """
    if array_api_compat.is_torch_array(x):
        import torch

        return torch.where(torch.isnan(x), x, torch.sign(x))
    return xp.sign(x)


def scalar(x: Any) -> float:
    """Convert a 0-d array (any library, any device, with or without gradient) to a Python float."""
    if hasattr(x, "detach"):
        x = x.detach()
    return float(x)


def to_numpy(x: object) -> np.ndarray:
    """Return a NumPy view/copy of any array (moves GPU tensors to host, detaches gradients).

    An explicit copy to the host (CuPy refuses the implicit ``np.asarray``): for results
    that are host objects by contract (reports, Python numbers), never inside a pointwise
    computation.
    """
    if array_api_compat.is_torch_array(x):
        return np.asarray(x.detach().cpu().numpy())
    if array_api_compat.is_cupy_array(x):
        return np.asarray(x.get())  # type: ignore[attr-defined]
    return np.asarray(x)


def numba_enabled() -> bool:
    """Whether imageform's numba kernels run at all.

    True when numba imports and ``IMAGEFORM_DISABLE_NUMBA`` is not set.
    """
    if os.environ.get("IMAGEFORM_DISABLE_NUMBA", "") not in ("", "0"):
        return False
    return have_numba()


def use_numba(*arrays: object, min_size: int = 0) -> bool:
    """Whether a hot path should run its numba kernel for these arrays.

    True only for NumPy arrays (numba cannot take other libraries' arrays), when
    :func:`numba_enabled`, and the first array has at least ``min_size`` elements (below
    that, compilation and call overhead dominate).
    """
    if not all(isinstance(a, np.ndarray) for a in arrays):
        return False
    if not numba_enabled():
        return False
    return bool(arrays) and arrays[0].size >= min_size  # type: ignore[attr-defined]
