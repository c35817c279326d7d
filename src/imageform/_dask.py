"""Dask support: pointwise functions run chunk-wise on NumPy blocks.

A pointwise colour function (one output pixel from one input pixel) decorated with
:func:`chunkwise` takes Dask arrays lazily: the call returns a Dask array at once, one task
per chunk, and nothing is computed until ``.compute()``. Each chunk is a NumPy array, so it
runs the NumPy path (numba kernels included) and is validated when it is computed (an
invalid value raises at ``.compute()``, not at the call). Shapes and option names are still
checked at the call, on a one-pixel probe of the input's dtype.

The trailing ``core`` axes of every array argument (``1``: the colour channels; ``0``: a
scalar per pixel, e.g. hue angles) are put in one chunk; the leading axes keep the input's
chunks, and the output has those chunks followed by its own trailing axes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

import array_api_compat
import numpy as np

from imageform._validate import format_shape
from imageform.errors import ImageformError

__all__ = ["chunkwise", "is_dask_array"]

F = TypeVar("F", bound=Callable[..., Any])

#: the value of the probe pixel: inside every colour space's domain (RGB, Lab, xy, hue ...)
_PROBE = 0.3


def is_dask_array(x: object) -> bool:
    """Tell whether ``x`` is a ``dask.array.Array``."""
    return bool(array_api_compat.is_dask_array(x))


def chunkwise(core: int = 1) -> Callable[[F], F]:
    """Run ``fn`` block by block when its leading positional arguments are Dask (a decorator).

    ``core`` is the number of trailing axes of each array argument that one output element
    needs whole (they are rechunked into a single chunk). Non-Dask calls go straight to
    ``fn``.
    """

    def deco(fn: F) -> F:
        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            n = 0
            while n < len(args) and is_dask_array(args[n]):
                n += 1
            if n == 0:
                return fn(*args, **kwargs)
            return _map_chunks(fn, args[:n], args[n:], kwargs, core)

        wrapper.__wrapped_chunkwise__ = True  # type: ignore[attr-defined]
        return wrapper  # type: ignore[return-value]

    return deco


def _map_chunks(
    fn: Callable[..., Any],
    arrays: tuple[Any, ...],
    rest: tuple[Any, ...],
    kwargs: dict[str, Any],
    core: int,
) -> Any:
    import dask.array as da

    arrays = tuple(da.broadcast_arrays(*arrays)) if len(arrays) > 1 else arrays
    ndim = arrays[0].ndim
    if ndim < core:
        return fn(*arrays, *rest, **kwargs)  # let the function's own validation speak
    batch = ndim - core
    first = arrays[0].rechunk(dict.fromkeys(range(batch, ndim), -1))
    arrays = (first, *(a.rechunk(first.chunks) for a in arrays[1:]))
    # a one-pixel probe: checks shapes and options now, and gives the output's layout
    probes = [np.full((1,) * batch + tuple(a.shape[batch:]), _PROBE, dtype=a.dtype) for a in arrays]
    try:
        out0 = fn(*probes, *rest, **kwargs)
    except (ImageformError, TypeError) as exc:  # name the input's shape, not the probe's
        raise _with_shapes(exc, probes, arrays) from None
    if not isinstance(out0, np.ndarray) or out0.ndim < batch:
        raise TypeError(f"{fn.__name__}: chunk-wise Dask needs an array result per pixel")
    out_core = tuple(out0.shape[batch:])
    chunks = first.chunks[:batch] + tuple((d,) for d in out_core)
    out_ndim = batch + len(out_core)
    extra: dict[str, Any] = {}
    if out_ndim < ndim:
        extra["drop_axis"] = list(range(out_ndim, ndim))
    elif out_ndim > ndim:
        extra["new_axis"] = list(range(ndim, out_ndim))

    def block(*blocks: np.ndarray) -> np.ndarray:
        return np.asarray(fn(*blocks, *rest, **kwargs))

    name = f"imageform-{fn.__name__}"
    return da.map_blocks(
        block,
        *arrays,
        chunks=chunks,
        dtype=out0.dtype,
        meta=np.empty((0,) * out_ndim, dtype=out0.dtype),
        token=name,
        **extra,
    )


def _with_shapes(exc: Exception, probes: list[np.ndarray], arrays: tuple[Any, ...]) -> Exception:
    """Return ``exc`` with every probe shape in its message replaced by its array's shape.

    A refusal on the one-pixel probe must not report ``(1, 4)`` for a (100, 4) input.
    """
    msg = str(exc)
    for p, a in zip(probes, arrays, strict=True):
        if p.shape != a.shape:
            for fmt in (format_shape, str):
                msg = msg.replace(fmt(p.shape), fmt(tuple(a.shape)))
    if msg == str(exc):
        return exc
    try:
        return type(exc)(msg)
    except Exception:  # an exception class with another signature: keep it as it is
        return exc
