"""A kernel launch without numba's per-call Python: arguments packed straight from the tensors.

On a lent H200 a ``convert`` call on CUDA tensors spent about 240 of its 330 µs of host time
in numba (``benchmarks/results/gpu-host-h200-2026-11-28.md``): a device-array view per
tensor (``from_cuda_array_interface``, about 24 µs each), the dispatcher's typing of every
argument, and ``_Kernel._prepare_args``, which packs each array as meminfo, parent, item
count, item size, data pointer, shape and strides. A 4K kernel takes 50-180 µs, so the call
was bound by the host.

This module does the same launch with the arguments packed in one pass from the tensors' own
attributes (``data_ptr()``, ``shape``, ``is_contiguous()``; CuPy's ``data.ptr``, ...), the
compiled function and its launch configuration held per kernel signature:

- :func:`pack_call` looks at each argument once: its type picks how (one dictionary lookup
  per type: PyTorch tensor, CuPy array, Python or NumPy number, :class:`Constants`), and it
  returns the signature (the compiled overload's key: each array's dtype, dimensions and
  C-contiguity, each number's type) with the packed arguments. What does not change from
  call to call is computed once: an array's item count, shape and C strides per shape and
  dtype, and a :class:`Constants`' numbers (a colour chain's matrices and whites) packed once
  per process;
- the first launch of a kernel for a given signature goes through numba as before (it
  compiles); then :func:`prepare` looks up the compiled overload and **checks** that
  :func:`pack_call` gives exactly the arguments numba's ``_prepare_args`` gave for the same
  call (every value and its C type). Only a signature that passed the check is launched fast
  afterwards; any difference, or an error, leaves it on numba's path for the process;
- the launch primitive is the one numba's overload itself calls: ``cuda.core``'s ``launch``
  with a ``LaunchConfig`` (numba-cuda; one per grid and block size, cached), or
  ``driver.launch_kernel`` with ctypes arguments (numba's built-in CUDA target).

It is on by default on a real device; ``IMAGEFORM_CUDA_FAST_LAUNCH=0`` turns it off (read
when :mod:`imageform._cuda._launch` first launches; ``_launch.refresh_switches()`` reads it
again). Under numba's simulator it never runs (there is no compiled function).
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

__all__ = [
    "Constants",
    "enabled",
    "expand",
    "forget",
    "launcher",
    "pack_call",
    "prepare",
    "same_arguments",
]

#: key -> a launcher ``run(grid, block, stream, packed)`` for signatures that passed the
#: check; key -> None for those that did not (numba's path, not checked again).
_READY: dict[tuple[Any, ...], Callable[..., None] | None] = {}

#: How this process's numba packs arguments: ``"core"`` (numba-cuda: an array's fields and a
#: boolean as Python values) or ``"ctypes"`` (the built-in target); set by :func:`prepare`
#: from the first compiled overload it sees (until then nothing is launched fast).
_FLAVOUR = ["core"]


def enabled() -> bool:
    """Whether fast launches may run (``IMAGEFORM_CUDA_FAST_LAUNCH`` unset or not ``0``)."""
    return os.environ.get("IMAGEFORM_CUDA_FAST_LAUNCH", "1") not in ("0", "")


class Constants:
    """Kernel arguments that are the same number in every call (a chain's matrices, whites).

    Given to :func:`imageform._cuda._launch.guarded` in place of the numbers themselves
    (numba's path receives them one by one, :func:`expand`); the fast launch packs them once
    per process instead of once per call. ``values``: Python or NumPy numbers.
    """

    __slots__ = ("_packed", "part", "values")

    def __init__(self, values: Sequence[Any]) -> None:
        self.values = tuple(values)
        #: the signature's part: the numbers' types
        self.part = ("constants", *(type(v) for v in self.values))
        self._packed: dict[str, list[Any] | None] = {}

    def __len__(self) -> int:
        return len(self.values)

    def __repr__(self) -> str:
        return f"Constants({self.values!r})"

    def packed(self, flavour: str) -> list[Any] | None:
        """Return the numbers as the kernel receives them (None: a type not packed here)."""
        got = self._packed.get(flavour, False)
        if got is False:
            out: list[Any] | None = []
            for v in self.values:
                c = _scalar_packer(type(v), flavour)
                if c is None:
                    out = None
                    break
                out.append(c(v))  # type: ignore[union-attr]
            got = self._packed[flavour] = out
        return got  # type: ignore[return-value]


def expand(args: Sequence[Any]) -> list[Any]:
    """``args`` with every :class:`Constants` replaced by its numbers (numba's arguments)."""
    out: list[Any] = []
    for a in args:
        if type(a) is Constants:
            out += a.values
        else:
            out.append(a)
    return out


# --- how each argument type is packed --------------------------------------------------------

_SCALAR, _TORCH, _CUPY, _CONSTANTS, _OTHER = 0, 1, 2, 3, 4
#: argument type -> one of the codes above (filled on first sight of a type)
_KINDS: dict[type, int] = {}


def _kind_of(t: type) -> int:
    torch = sys.modules.get("torch")
    cupy = sys.modules.get("cupy")
    if t is Constants:
        k = _CONSTANTS
    elif issubclass(t, (int, float, np.generic)):  # bool is an int
        k = _SCALAR
    elif torch is not None and issubclass(t, torch.Tensor):
        k = _TORCH
    elif cupy is not None and issubclass(t, cupy.ndarray):
        k = _CUPY
    else:
        k = _OTHER
    _KINDS[t] = k
    return k


def _as_bool(v: Any) -> bool:
    return bool(v)


def _as_uint8(v: Any) -> ctypes.c_uint8:
    return ctypes.c_uint8(int(v))


#: (number type, flavour) -> the C value numba passes for it (numba's typing of the type:
#: a Python int is int64, a float float64, a NumPy scalar its own type)
_SCALAR_PACK: dict[tuple[type, str], Callable[[Any], Any] | None] = {}


def _scalar_packer(t: type, flavour: str) -> Callable[[Any], Any] | None:
    key = (t, flavour)
    try:
        return _SCALAR_PACK[key]
    except KeyError:
        pass
    c: Callable[[Any], Any] | None
    if issubclass(t, (bool, np.bool_)):
        c = _as_bool if flavour == "core" else _as_uint8
    elif issubclass(t, int):
        c = ctypes.c_int64
    elif issubclass(t, float):  # np.float64 too
        c = ctypes.c_double
    elif issubclass(t, np.float32):
        c = ctypes.c_float
    elif issubclass(t, np.integer):
        c = getattr(ctypes, f"c_{np.dtype(t).name}", None)
    else:  # float16, complex: numba's path
        c = None
    _SCALAR_PACK[key] = c
    return c


def _c_strides(shape: Sequence[int], itemsize: int) -> tuple[int, ...]:
    out = []
    acc = itemsize
    for s in reversed(shape):
        out.append(acc)
        acc *= int(s)
    return tuple(reversed(out))


#: (shape, dtype, flavour) of a C-contiguous array -> (signature part, the fields before the
#: data pointer, the fields after it)
_LAYOUTS: dict[tuple[Any, ...], tuple[Any, list[Any], list[Any]]] = {}
#: a library's dtype object -> (NumPy name, item size)
_DTYPES: dict[Any, tuple[str, int]] = {}


def _dtype_info(dt: Any) -> tuple[str, int]:
    got = _DTYPES.get(dt)
    if got is None:
        npdt = np.dtype(str(dt).removeprefix("torch."))
        got = _DTYPES[dt] = (npdt.name, npdt.itemsize)
    return got


def _layout(
    shape: tuple[int, ...], name: str, itemsize: int, strides: tuple[int, ...] | None, core: bool
) -> tuple[Any, list[Any], list[Any]]:
    """Return numba's array fields around the data pointer (``strides`` None: C order)."""
    size = 1
    for s in shape:
        size *= s
    contiguous = strides is None
    st = _c_strides(shape, itemsize) if strides is None else strides
    part = (name, len(shape), contiguous)
    if core:
        return part, [0, 0, size, itemsize], [*shape, *st]
    c, p = ctypes.c_ssize_t, ctypes.c_void_p
    return part, [p(0), p(0), c(size), c(itemsize)], [c(s) for s in (*shape, *st)]


def _array_fields(a: Any, kind: int, core: bool) -> tuple[Any, list[Any], int, list[Any]]:
    """(signature part, fields before the pointer, pointer, fields after) of a device array."""
    if kind == _TORCH:
        dt = a.dtype
        if a.is_contiguous():
            key = (a.shape, dt, core)
            got = _LAYOUTS.get(key)
            if got is None:
                name, itemsize = _dtype_info(dt)
                shape = tuple(int(s) for s in a.shape)
                if len(_LAYOUTS) > 1024:
                    _LAYOUTS.clear()
                got = _LAYOUTS[key] = _layout(shape, name, itemsize, None, core)
        else:
            name, itemsize = _dtype_info(dt)
            shape = tuple(int(s) for s in a.shape)
            got = _layout(shape, name, itemsize, tuple(s * itemsize for s in a.stride()), core)
        return got[0], got[1], int(a.data_ptr()), got[2]
    # CuPy
    shape = tuple(int(s) for s in a.shape)
    name, itemsize = _dtype_info(a.dtype)
    cstrides = None if a.flags.c_contiguous else tuple(int(s) for s in a.strides)
    part, pre, post = _layout(shape, name, itemsize, cstrides, core)
    return part, pre, int(a.data.ptr), post


def pack_call(kernel: Any, args: Sequence[Any]) -> tuple[tuple[Any, ...], list[Any], Any] | None:
    """Return ``(signature, packed arguments, first array)`` of a launch, or None.

    The signature picks one compiled overload: the kernel, then per argument the array's
    dtype, dimensions and C-contiguity (numba's layout ``C`` or ``A``), a number's type, a
    :class:`Constants`' types. The packed arguments are numba's ABI: an array as meminfo,
    parent, item count, item size, data pointer, shape, byte strides (Python integers for
    numba-cuda's ``"core"`` launch, ``c_void_p``/``c_ssize_t`` for the built-in target);
    numbers as the C type of their numba type (a boolean a Python bool for ``"core"``,
    ``c_uint8`` otherwise). None: an argument packed only by numba (a numba device array,
    another library's array, a float16).
    """
    flavour = _FLAVOUR[0]
    core = flavour == "core"
    parts: list[Any] = [id(kernel)]
    out: list[Any] = []
    first = None
    for a in args:
        t = type(a)
        kind = _KINDS.get(t)
        if kind is None:
            kind = _kind_of(t)
        if kind == _SCALAR:
            c = _SCALAR_PACK.get((t, flavour)) or _scalar_packer(t, flavour)
            if c is None:
                return None
            parts.append(t)
            out.append(c(a))
        elif kind == _CONSTANTS:
            vals = a.packed(flavour)
            if vals is None:
                return None
            parts.append(a.part)
            out += vals
        elif kind == _OTHER:
            return None
        else:
            if first is None:
                first = a
            # a C-contiguous PyTorch tensor of a known shape (the common case): inline
            got = _LAYOUTS.get((a.shape, a.dtype, core)) if kind == _TORCH else None
            if got is not None and a.is_contiguous():
                parts.append(got[0])
                out += got[1]
                out.append(a.data_ptr() if core else ctypes.c_void_p(a.data_ptr()))
                out += got[2]
                continue
            part, pre, ptr, post = _array_fields(a, kind, core)
            parts.append(part)
            out += pre
            out.append(ptr if core else ctypes.c_void_p(ptr))
            out += post
    return tuple(parts), out, first


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


def _module(overload: Any) -> Any:
    return sys.modules[type(overload).__module__]


def _flavour(overload: Any) -> str:
    """``"core"`` (numba-cuda: ``cuda.core``'s launch) or ``"ctypes"`` (built-in target)."""
    mod = _module(overload)
    return "core" if hasattr(mod, "LaunchConfig") and hasattr(mod, "launch") else "ctypes"


def prepare(
    key: tuple[Any, ...], kernel: Any, config: Any, args: Sequence[Any], dargs: Sequence[Any]
) -> None:
    """After numba launched ``kernel`` on ``dargs`` (``args`` as the caller gave them): check.

    ``config``: the launch configuration numba used (``kernel[grid, block, stream]``);
    ``dargs``: the arguments numba received (:func:`expand`, device arrays). Looks up the
    compiled overload, packs ``args`` with :func:`pack_call` and compares with numba's own
    ``_prepare_args`` on ``dargs``; records a launcher for ``key`` when they agree, None
    otherwise (the check is made once per key).
    """
    if key in _READY:
        return
    _READY[key] = None
    try:
        argtypes = tuple(kernel.typeof_pyval(d) for d in dargs)
        overload = kernel.overloads.get(argtypes)
        if overload is None or getattr(overload, "debug", False) or overload.cooperative:
            return
        flavour = _FLAVOUR[0] = _flavour(overload)
        theirs: list[Any] = []
        for ty, v in zip(overload.argument_types, dargs, strict=True):
            overload._prepare_args(ty, v, config.stream, [], theirs)
        got = pack_call(kernel, args)
        if got is None or got[0] != key or not same_arguments(got[1], theirs):
            return
        _READY[key] = _launcher(overload, flavour)
    except Exception:  # any surprise keeps numba's path for this signature
        _READY[key] = None


def forget(key: tuple[Any, ...] | None) -> None:
    """Send ``key``'s launches through numba from now on (its fast launch raised)."""
    if key is not None:
        _READY[key] = None


def launcher(key: tuple[Any, ...] | None) -> Callable[..., None] | None:
    """Return the checked launcher of ``key``, or None (numba's path)."""
    return None if key is None else _READY.get(key)


def _launcher(overload: Any, flavour: str) -> Callable[..., None]:
    """Return ``run(grid, block, stream, packed)``: the launch numba's overload makes.

    ``grid`` and ``block``: 3-tuples (numba's normalised dimensions); ``stream``: what
    numba's launch configuration holds (0 or a numba stream).
    """
    cufunc = overload._codelibrary.get_cufunc()
    mod = _module(overload)
    if flavour == "core":
        launch, launch_config = mod.launch, mod.LaunchConfig
        coop = "is_cooperative" if getattr(mod, "CUDA_CORE_GE_1_0", True) else "cooperative_launch"
        kern = cufunc.kernel
        configs: dict[tuple[Any, ...], Any] = {}

        def run_core(grid: Any, block: Any, stream: Any, packed: list[Any]) -> None:
            cfg = configs.get((grid, block))
            if cfg is None:
                if len(configs) > 256:
                    configs.clear()
                cfg = launch_config(grid=grid, block=block, shmem_size=0, **{coop: False})
                configs[grid, block] = cfg
            launch(stream, cfg, kern, *packed)

        return run_core
    driver = mod.driver
    zero = driver.binding.CUstream(0) if getattr(driver, "USE_NV_BINDING", False) else None
    handle = cufunc.handle

    def run_ctypes(grid: Any, block: Any, stream: Any, packed: list[Any]) -> None:
        sh = (stream and stream.handle) or zero
        driver.launch_kernel(handle, *grid, *block, 0, sh, packed)

    return run_ctypes
