"""Which array library an object belongs to, without importing the library."""

from __future__ import annotations

import sys

__all__ = ["is_cupy", "is_torch"]


def is_torch(x: object) -> bool:
    """Whether ``x`` is a PyTorch tensor (False when PyTorch was never imported)."""
    torch = sys.modules.get("torch")
    return torch is not None and isinstance(x, torch.Tensor)


def is_cupy(x: object) -> bool:
    """Whether ``x`` is a CuPy array (False when CuPy was never imported)."""
    cupy = sys.modules.get("cupy")
    return cupy is not None and isinstance(x, cupy.ndarray)
