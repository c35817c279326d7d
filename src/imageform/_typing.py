"""Type aliases shared by the package."""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

__all__ = ["Array", "ArrayLike", "FloatArray"]

#: Any Array-API array; NumPy in, NumPy out; PyTorch in, PyTorch out.
Array: TypeAlias = Any
#: Anything :func:`numpy.asarray` accepts, or an Array-API array.
ArrayLike: TypeAlias = npt.ArrayLike | Any
FloatArray: TypeAlias = npt.NDArray[np.floating[Any]]
