"""PyTorch dispatch modes for the device tests: device mixing and op counts, without a GPU.

:class:`DeviceGuard` sees every ATen operator a call runs and refuses one whose tensor
arguments live on two devices (a 0-d CPU tensor is a scalar: CUDA accepts it, so does the
guard). Explicit copies (``.to``, ``copy_``) are allowed. With ``meta`` tensors as input this
is what a CUDA run would refuse, found on a CPU-only machine; it also counts the operators,
which on CUDA are the kernels launched (``tests/backends/test_op_counts.py``).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import torch
from torch.utils._python_dispatch import TorchDispatchMode
from torch.utils._pytree import tree_flatten

#: Operators that move data between devices on purpose (an explicit transfer).
_TRANSFERS = {"aten::_to_copy", "aten::copy_", "aten::to", "aten::lift_fresh"}
#: Operators that allocate or view without computing: not counted as kernels.
_NO_KERNEL = {
    "aten::view",
    "aten::_unsafe_view",
    "aten::reshape",
    "aten::expand",
    "aten::unsqueeze",
    "aten::squeeze",
    "aten::permute",
    "aten::t",
    "aten::transpose",
    "aten::slice",
    "aten::select",
    "aten::alias",
    "aten::detach",
    "aten::as_strided",
    "aten::unbind",
    "aten::split",
    "aten::split_with_sizes",
    "aten::diagonal",
    "aten::empty",
    "aten::empty_like",
    "aten::empty_strided",
    "aten::movedim",
    "aten::lift_fresh",
    "aten::_reshape_alias",
    "aten::broadcast_tensors",
    "aten::expand_as",
    "aten::view_as",
    "aten::unfold",
}


#: Operators whose result size or value the host must know: on CUDA each waits for the device.
_SYNCS = {
    "aten::nonzero",
    "aten::_local_scalar_dense",
    "aten::masked_select",
    "aten::is_nonzero",
    "aten::equal",
    "aten::unique_dim",
    "aten::_unique2",
    "aten::item",
}


def _bool_index(args: Any) -> bool:
    """An ``index``/``index_put_`` with a boolean mask (it runs ``nonzero``: a sync)."""
    indices = args[1] if len(args) > 1 else ()
    return any(isinstance(t, torch.Tensor) and t.dtype == torch.bool for t in (indices or ()))


#: Operators that make a 0-d tensor of a Python number.
_SCALARS = {"aten::scalar_tensor"}


class DeviceMixingError(AssertionError):
    """An operator got tensors on two devices (CUDA would refuse it)."""


class DeviceGuard(TorchDispatchMode):
    """Refuse operators mixing devices; count the operators that compute (``kernels``).

    ``syncs`` lists the operators that would make the host wait for a CUDA device.
    """

    def __init__(self) -> None:
        super().__init__()
        self.ops: Counter[str] = Counter()
        #: operators that would wait for a CUDA device (read a value or a data-dependent size)
        self.syncs: list[str] = []

    @property
    def kernels(self) -> int:
        """Operators that compute on whole arrays (views, allocations and scalars excluded).

        A Python number in ``where`` (``xp.where(m, x, 0.0)``) becomes ``scalar_tensor``: a
        one-element fill, counted in :attr:`scalars`, not here (it moves no data, unlike
        the full-size ``zeros_like`` it replaces).
        """
        return sum(n for name, n in self.ops.items() if name not in _NO_KERNEL | _SCALARS)

    @property
    def scalars(self) -> int:
        """One-element tensors made from Python numbers (a tiny fill each on CUDA)."""
        return sum(self.ops[name] for name in _SCALARS)

    def __torch_dispatch__(self, func: Any, types: Any, args: Any = (), kwargs: Any = None) -> Any:
        kwargs = kwargs or {}
        name = func._schema.name
        self.ops[name] += 1
        if name in _SYNCS or (
            name in ("aten::index", "aten::index_put_", "aten::index_put") and _bool_index(args)
        ):
            self.syncs.append(name)
        if name not in _TRANSFERS:
            leaves, _ = tree_flatten((args, kwargs))
            devices = {
                t.device
                for t in leaves
                if isinstance(t, torch.Tensor) and not (t.ndim == 0 and t.device.type == "cpu")
            }
            if len(devices) > 1:
                raise DeviceMixingError(f"{name} mixes devices {sorted(str(d) for d in devices)}")
        return func(*args, **kwargs)
