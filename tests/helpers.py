"""Test helpers: move arrays between backends."""

from __future__ import annotations

import numpy as np


def to_backend(x: object, name: str, dtype: str = "float64") -> object:
    """Convert a NumPy array to the backend ``name``."""
    a = np.asarray(x, dtype=dtype)
    if name == "numpy":
        return a
    if name == "array_api_strict":
        import array_api_strict

        return array_api_strict.asarray(a)
    if name == "torch":
        import torch

        return torch.asarray(a)
    if name == "dask":
        import dask.array as da

        # the leading axes in two chunks each, the last (channel / coordinate) axis whole:
        # functions must work across chunk boundaries
        chunks = tuple(max(1, (n + 1) // 2) for n in a.shape[:-1]) + a.shape[-1:]
        return da.from_array(a, chunks=chunks)
    raise ValueError(name)


def to_np(x: object) -> np.ndarray:
    """Any backend's array as NumPy."""
    if hasattr(x, "detach"):
        return x.detach().cpu().numpy()  # type: ignore[no-any-return]
    if hasattr(x, "compute"):
        return np.asarray(x.compute())
    return np.asarray(x)


def array_type(name: str) -> type:
    """The array class of backend ``name`` (as in ``to_backend``)."""
    if name == "torch":
        import torch

        return torch.Tensor
    if name == "array_api_strict":
        import array_api_strict

        return type(array_api_strict.asarray([1.0]))
    if name == "dask":
        import dask.array as da

        return da.Array
    return np.ndarray
