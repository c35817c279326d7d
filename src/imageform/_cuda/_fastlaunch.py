"""A kernel launch without numba's per-call Python: arguments packed straight from the tensors.

On a lent H200 a ``convert`` call on CUDA tensors spent about 240 of its 330 µs of host time
in numba (``benchmarks/results/gpu-host-h200-2026-11-28.md``): a device-array view per
tensor (``from_cuda_array_interface``, about 24 µs each), the dispatcher's typing of every
argument, and ``_Kernel._prepare_args``, which packs each array as meminfo, parent, item
count, item size, data pointer, shape and strides. A 4K kernel takes 50-180 µs, so the call
was bound by the host.

This module does the same launch with the packing done once per argument from the tensor's
own attributes (``data_ptr()``, ``shape``, ``stride()``; CuPy's ``data.ptr``, ...), and the
compiled function and its launch configuration held per kernel:

- the first launch of a kernel for a given argument signature goes through numba as before
  (it compiles); then :func:`prepare` looks up the compiled overload and **checks** that
  :func:`pack` gives exactly the arguments numba's ``_prepare_args`` gave for the same call
  (every value and its C type). Only a signature that passed the check is launched fast
  afterwards; any difference, or an error, leaves it on numba's path for the process;
- the launch primitive is the one numba's overload itself calls: ``cuda.core``'s ``launch``
  with a ``LaunchConfig`` (numba-cuda), or ``driver.launch_kernel`` with ctypes arguments
  (numba's built-in CUDA target).

It is on by default on a real device; ``IMAGEFORM_CUDA_FAST_LAUNCH=0`` turns it off. Under
numba's simulator it never runs (there is no compiled function).
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

from imageform._cuda._libs import is_cupy as _is_cupy
from imageform._cuda._libs import is_torch as _is_torch

__all__ = [
    "describe",
    "enabled",
    "forget",
    "key_of",
    "kinds_of",
    "launcher",
    "pack",
    "prepare",
    "same_arguments",
]

#: key -> a launcher (grid, block, stream config source, args) for signatures that passed
#: the check; key -> None for those that did not (numba's path, not checked again).
_READY: dict[tuple[Any, ...], Callable[..., None] | None] = {}


def enabled() -> bool:
    """Whether fast launches may run (``IMAGEFORM_CUDA_FAST_LAUNCH`` unset or not ``0``)."""
    return os.environ.get("IMAGEFORM_CUDA_FAST_LAUNCH", "1") not in ("0", "")


def _c_strides(shape: Sequence[int], itemsize: int) -> tuple[int, ...]:
    out = []
    acc = itemsize
    for s in reversed(shape):
        out.append(acc)
        acc *= int(s)
    return tuple(reversed(out))


def describe(x: Any) -> tuple[int, int, int, tuple[int, ...], tuple[int, ...], bool, str] | None:
    """``(pointer, size, itemsize, shape, byte strides, C-contiguous, dtype)`` of a CUDA array.

    PyTorch tensors and CuPy arrays are read from their attributes; anything else returns
    None (numba's path). The strides are numba's: computed from the shape for a
    C-contiguous array (as numba does when the interface gives none), the array's own
    otherwise.
    """
    if _is_torch(x):
        shape = tuple(int(s) for s in x.shape)
        itemsize = int(x.element_size())
        contiguous = bool(x.is_contiguous())
        strides = (
            _c_strides(shape, itemsize)
            if contiguous
            else tuple(int(s) * itemsize for s in x.stride())
        )
        dtype = str(x.dtype).removeprefix("torch.")
        return int(x.data_ptr()), int(x.numel()), itemsize, shape, strides, contiguous, dtype
    if _is_cupy(x):
        shape = tuple(int(s) for s in x.shape)
        itemsize = int(x.itemsize)
        contiguous = bool(x.flags.c_contiguous)
        strides = _c_strides(shape, itemsize) if contiguous else tuple(int(s) for s in x.strides)
        return int(x.data.ptr), int(x.size), itemsize, shape, strides, contiguous, str(x.dtype)
    return None


def key_of(
    kernel: Any,
    args: Sequence[Any],
    scalars: tuple[type, ...],
    descs: list[Any] | None = None,
) -> tuple[Any, ...] | None:
    """Return the signature a launch of ``kernel`` on ``args`` compiles for, or None.

    Arrays by dtype, dimensions and C-contiguity (numba's layout ``C`` or ``A``), numbers by
    their Python or NumPy type: together they pick one compiled overload. None: an argument
    this module cannot describe (numba's path). ``descs``, if given, receives each
    argument's :func:`describe` (None for a number), for :func:`pack` to reuse.
    """
    parts: list[Any] = [id(kernel)]
    for a in args:
        if isinstance(a, scalars):
            parts.append(type(a))
            if descs is not None:
                descs.append(None)
            continue
        d = describe(a)
        if d is None:
            return None
        parts.append((d[6], len(d[3]), d[5]))
        if descs is not None:
            descs.append(d)
    return tuple(parts)


def _module(overload: Any) -> Any:
    return sys.modules[type(overload).__module__]


def _flavour(overload: Any) -> str:
    """``"core"`` (numba-cuda: ``cuda.core``'s launch) or ``"ctypes"`` (built-in target)."""
    mod = _module(overload)
    return "core" if hasattr(mod, "LaunchConfig") and hasattr(mod, "launch") else "ctypes"


def kinds_of(types_: Sequence[Any], types_module: Any) -> tuple[str, ...]:
    """One code per argument: ``"array"``, ``"c_<int type>"``, ``"f64"``, ``"f32"``, ``"bool"``.

    ``types_module``: the numba ``types`` module the overload's types come from (numba's or
    numba-cuda's own). Raises TypeError for a type this module does not pack.
    """
    t = types_module
    out = []
    for ty in types_:
        if isinstance(ty, t.Array):
            out.append("array")
        elif isinstance(ty, t.Integer):
            out.append(f"c_{ty}")
        elif ty == t.float64:
            out.append("f64")
        elif ty == t.float32:
            out.append("f32")
        elif ty == t.boolean:
            out.append("bool")
        else:
            raise TypeError(f"no fast packing of numba type {ty}")
    return tuple(out)


def pack(
    kinds: Sequence[str],
    args: Sequence[Any],
    flavour: str,
    descs: Sequence[Any] | None = None,
) -> list[Any]:
    """Return the kernel arguments numba's ``_Kernel._prepare_args`` would pass for ``args``.

    ``kinds``: :func:`kinds_of` the overload's argument types. Arrays expand to meminfo,
    parent, item count, item size, data pointer, shape, byte strides; ``"core"`` passes
    those as Python integers (numba-cuda), ``"ctypes"`` as ``c_void_p``/``c_ssize_t`` (the
    built-in target). Numbers go as the C type of their numba type (a boolean as a Python
    bool for ``"core"``, ``c_uint8`` otherwise), as numba does. ``descs``: the arguments'
    :func:`describe` from :func:`key_of` (else they are described here). Raises TypeError for
    an array this module cannot describe.
    """
    out: list[Any] = []
    core = flavour == "core"
    for i, (kind, v) in enumerate(zip(kinds, args, strict=True)):
        if kind == "array":
            d = describe(v) if descs is None else descs[i]
            if d is None:
                raise TypeError(f"no fast description of {type(v).__name__}")
            ptr, size, itemsize, shape, strides, _, _ = d
            if core:
                out += [0, 0, size, itemsize, ptr, *shape, *strides]
            else:
                c = ctypes.c_ssize_t
                out += [ctypes.c_void_p(0), ctypes.c_void_p(0), c(size), c(itemsize)]
                out.append(ctypes.c_void_p(ptr))
                out += [c(s) for s in shape] + [c(s) for s in strides]
        elif kind == "f64":
            out.append(ctypes.c_double(v))
        elif kind == "f32":
            out.append(ctypes.c_float(v))
        elif kind == "bool":
            out.append(v if core else ctypes.c_uint8(int(v)))
        else:
            out.append(getattr(ctypes, kind)(v))
    return out


def _norm(v: Any) -> tuple[str, Any]:
    if isinstance(v, ctypes._SimpleCData):
        return type(v).__name__, v.value
    if isinstance(v, bool):
        return "bool", v
    if isinstance(v, int):
        return "int", int(v)
    return type(v).__name__, v


def same_arguments(mine: Sequence[Any], numba_s: Sequence[Any]) -> bool:
    """Whether two packed argument lists are equal value by value and C type by C type."""
    return len(mine) == len(numba_s) and all(
        _norm(a) == _norm(b) for a, b in zip(mine, numba_s, strict=True)
    )


def prepare(
    key: tuple[Any, ...], kernel: Any, config: Any, args: Sequence[Any], dargs: Sequence[Any]
) -> None:
    """After numba launched ``kernel`` on ``dargs`` (``args`` as the caller gave them): check.

    ``config``: the launch configuration numba used (``kernel[grid, block, stream]``).
    Looks up the compiled overload, packs ``args`` with :func:`pack` and compares with
    numba's own ``_prepare_args`` on ``dargs``; records a launcher for ``key`` when they
    agree, None otherwise (the check is made once per key).
    """
    if key in _READY:
        return
    _READY[key] = None
    try:
        argtypes = tuple(kernel.typeof_pyval(d) for d in dargs)
        overload = kernel.overloads.get(argtypes)
        if overload is None or getattr(overload, "debug", False) or overload.cooperative:
            return
        flavour = _flavour(overload)
        kinds = kinds_of(overload.argument_types, _module(overload).types)
        theirs: list[Any] = []
        for ty, v in zip(overload.argument_types, dargs, strict=True):
            overload._prepare_args(ty, v, config.stream, [], theirs)
        if not same_arguments(pack(kinds, args, flavour), theirs):
            return
        _READY[key] = _launcher(overload, flavour, kinds)
    except Exception:  # any surprise keeps numba's path for this signature
        _READY[key] = None


def forget(key: tuple[Any, ...] | None) -> None:
    """Send ``key``'s launches through numba from now on (its fast launch raised)."""
    if key is not None:
        _READY[key] = None


def launcher(key: tuple[Any, ...] | None) -> Callable[..., None] | None:
    """Return the checked launcher of ``key``, or None (numba's path)."""
    return None if key is None else _READY.get(key)


def _launcher(overload: Any, flavour: str, kinds: tuple[str, ...]) -> Callable[..., None]:
    """Return the launch numba's overload makes, with :func:`pack`'s arguments."""
    cufunc = overload._codelibrary.get_cufunc()
    mod = _module(overload)
    if flavour == "core":
        launch, launch_config = mod.launch, mod.LaunchConfig
        coop = "is_cooperative" if getattr(mod, "CUDA_CORE_GE_1_0", True) else "cooperative_launch"
        kern = cufunc.kernel
        configs: dict[tuple[Any, ...], Any] = {}

        def run_core(config: Any, args: Sequence[Any], descs: Sequence[Any]) -> None:
            dims = (config.griddim, config.blockdim)
            cfg = configs.get(dims)
            if cfg is None:
                cfg = launch_config(grid=dims[0], block=dims[1], shmem_size=0, **{coop: False})
                configs[dims] = cfg
            launch(config.stream, cfg, kern, *pack(kinds, args, "core", descs))

        return run_core
    driver = mod.driver
    zero = driver.binding.CUstream(0) if getattr(driver, "USE_NV_BINDING", False) else None
    handle = cufunc.handle

    def run_ctypes(config: Any, args: Sequence[Any], descs: Sequence[Any]) -> None:
        stream = config.stream
        sh = (stream and stream.handle) or zero
        driver.launch_kernel(
            handle, *config.griddim, *config.blockdim, 0, sh, pack(kinds, args, "ctypes", descs)
        )

    return run_ctypes
