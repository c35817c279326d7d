"""CUDA arrays of any library as numba device arrays, outputs in the input's library, launches.

The one place where imageform's GPU kernels (:mod:`imageform._cuda`) meet the caller's
arrays (docs/design.md, "GPU kernels"):

- :func:`is_cuda_array`: a PyTorch tensor on a CUDA device, a CuPy array, or anything else
  that exports ``__cuda_array_interface__`` (a numba device array, ...). PyTorch and CuPy are
  recognised without importing them (their modules are looked up in ``sys.modules``).
- :func:`as_device_array`: a numba device array viewing the same memory, no copy and no
  synchronisation (numba's own ``as_cuda_array`` synchronises the producer's stream; this
  launches on that stream instead, which orders the work the same way without waiting).
- :func:`empty_like`: an uninitialised output in the input's library and on its device.
- :func:`launch_1d`: one launch over ``n`` threads, on the stream of the first library
  array among the arguments (PyTorch's or CuPy's current stream, or the stream a
  ``__cuda_array_interface__`` names), with the arguments turned into device arrays;
  :func:`launch_rows` the same on a 2-D grid over an image's rows and columns.
- :func:`guarded`: a launch whose first compilation failing in numba (no NVVM, a typing
  error) switches the kernels off for the process instead of failing the call.
- :func:`use_cuda`: whether kernels may run (a CUDA device, or numba's simulator).

numba's CUDA target is imported on first use only (``import imageform`` does not touch it).
Under numba's simulator (``NUMBA_ENABLE_CUDASIM=1`` set before numba is imported) the same
code runs on the CPU, one Python thread per CUDA thread: CI tests the kernels that way, with
stand-in objects that export a ``__cuda_array_interface__`` pointing at host memory.
``IMAGEFORM_DISABLE_CUDA=1`` turns the kernels off (the Array-API path runs instead).

The environment switches (``IMAGEFORM_DISABLE_CUDA``, ``IMAGEFORM_DEVICE_CHECKS`` as the
kernels' dispatch reads it, ``IMAGEFORM_CUDA_FAST_LAUNCH``) are read once, on first use, not
in every call (an ``os.environ`` lookup costs about a microsecond); a program or test that
changes one at run time calls :func:`refresh_switches` after.
"""

from __future__ import annotations

import ctypes
import os
import sys
import threading
from functools import cache
from typing import Any

import numpy as np

from imageform._cuda import _fastlaunch
from imageform._cuda._fastlaunch import Constants, expand
from imageform._cuda._libs import is_cupy, is_torch

__all__ = [
    "Constants",
    "as_device_array",
    "cuda",
    "device_checks",
    "disable",
    "dtype_name",
    "empty_like",
    "guarded",
    "is_cuda_array",
    "launch_1d",
    "launch_count",
    "launch_rows",
    "refresh_switches",
    "simulated",
    "status",
    "use_cuda",
]

#: Threads per block of :func:`launch_1d` on a device (the simulator runs fewer: each
#: simulated thread is a Python thread).
THREADS = 256
_SIM_THREADS = 32

_LOCK = threading.Lock()
_LAUNCHES = [0]
#: Why the kernels were switched off in this process (a failed first compile), or "".
_DISABLED = [""]


def _env_on(name: str) -> bool:
    return os.environ.get(name, "") not in ("", "0")


#: numba's answer, once numba is imported (it reads the variable once, at import).
_SIMULATED: list[bool] = []


def simulated() -> bool:
    """Whether numba's CUDA simulator is on (``NUMBA_ENABLE_CUDASIM``, read by numba at import)."""
    if _SIMULATED:
        return _SIMULATED[0]
    if "numba" in sys.modules:
        from numba.core import config

        _SIMULATED.append(bool(getattr(config, "ENABLE_CUDASIM", 0)))
        return _SIMULATED[0]
    return _env_on("NUMBA_ENABLE_CUDASIM")


@cache
def cuda() -> Any:
    """Return numba's CUDA module (the ``numba-cuda`` package's when installed), imported once."""
    import warnings

    from numba import cuda as numba_cuda
    from numba.core.errors import NumbaPerformanceWarning

    # a small image is a small grid: numba's low-occupancy note is no news for a pointwise
    # kernel whose size is the caller's image (only this message is silenced)
    warnings.filterwarnings(
        "ignore", message=r"Grid size \d+ will likely", category=NumbaPerformanceWarning
    )
    return numba_cuda


@cache
def _available() -> bool:
    try:
        return bool(cuda().is_available())
    except Exception:  # pragma: no cover - a broken driver: the Array-API path runs instead
        return False


#: The switches read from the environment once (:func:`refresh_switches`): whether the
#: kernels may run (None: not read yet), and IMAGEFORM_DEVICE_CHECKS.
_USE: list[bool | None] = [None]
_CHECKS: list[bool | None] = [None]


def use_cuda() -> bool:
    """Whether imageform's CUDA kernels may run in this process.

    False when ``IMAGEFORM_DISABLE_CUDA`` is set or :func:`disable` was called; otherwise
    True under numba's simulator and when numba finds a CUDA device. Checked once, on first
    use (:func:`refresh_switches` checks again).
    """
    if _DISABLED[0]:
        return False
    on = _USE[0]
    if on is None:
        on = _USE[0] = not _env_on("IMAGEFORM_DISABLE_CUDA") and (simulated() or _available())
    return on


def device_checks() -> bool:
    """Whether ``IMAGEFORM_DEVICE_CHECKS`` asks for the value checks on device arrays.

    The kernels' dispatch reads it here (once, :func:`refresh_switches`), not through
    :func:`imageform._backend.reads_values` in every call.
    """
    on = _CHECKS[0]
    if on is None:
        on = _CHECKS[0] = _env_on("IMAGEFORM_DEVICE_CHECKS")
    return on


def refresh_switches() -> None:
    """Read the environment switches again (after a change of ``os.environ`` at run time).

    ``IMAGEFORM_DISABLE_CUDA``, ``IMAGEFORM_DEVICE_CHECKS`` and ``IMAGEFORM_CUDA_FAST_LAUNCH``
    are read once, on first use, so that a call does not pay for reading them; tests and
    benchmarks that switch the kernels off for a while (``bench_gpu.py``'s Array-API rows)
    call this after setting and after restoring the variable.
    """
    _USE[0] = None
    _CHECKS[0] = None
    _FAST[0] = None


_is_torch = is_torch
_is_cupy = is_cupy

#: Whether ``meta`` tensors count as CUDA tensors: only benchmarks/profile_gpu_host.py
#: ``--dry`` sets it, to drive the dispatch down to a stub launch without a GPU.
_META_AS_CUDA = False

#: What :func:`is_cuda_array` knows of a type: host (never a CUDA array), a PyTorch tensor,
#: a CuPy array, or another type (its ``__cuda_array_interface__`` is asked).
_HOST, _TORCH, _CUPY, _OTHER = 0, 1, 2, 3
_KINDS: dict[type, int] = {}
# a tuple, not a union of types: torch.compile traces this test (a union is an error there)
_HOST_TYPES = (np.ndarray, np.generic, float, int, complex, bool, str, list, tuple)


def _kind_of(t: type) -> int:
    torch = sys.modules.get("torch")
    cupy = sys.modules.get("cupy")
    if issubclass(t, _HOST_TYPES):
        k = _HOST
    elif torch is not None and issubclass(t, torch.Tensor):
        k = _TORCH
    elif cupy is not None and issubclass(t, cupy.ndarray):
        k = _CUPY
    else:
        k = _OTHER
    if torch is None or not torch.compiler.is_compiling():
        _KINDS[t] = k  # not while torch.compile traces (a global mutation breaks the graph)
    return k


def _is_sim_array(x: object) -> bool:
    return simulated() and type(x).__name__ == "FakeCUDAArray"


def is_cuda_array(x: object) -> bool:
    """Whether ``x`` lives in CUDA device memory (PyTorch CUDA, CuPy, ``__cuda_array_interface__``).

    NumPy arrays, CPU or ``meta`` tensors and tensors being traced by ``torch.compile``
    answer False. Under the simulator its own device arrays answer True too. One dictionary
    lookup of the type decides which test applies.
    """
    t = type(x)
    kind = _KINDS.get(t)
    if kind is None:
        kind = _kind_of(t)
    if kind == _TORCH:
        # inside torch.compile tracing the tensor is a stand-in without memory: the traced
        # Array-API path runs (and fuses) instead
        if x.is_cuda or (_META_AS_CUDA and x.is_meta):  # type: ignore[attr-defined]
            return not _compiling()
        return False
    if kind == _HOST:
        return False
    if kind == _CUPY or _is_sim_array(x):
        return True
    try:
        return isinstance(x.__cuda_array_interface__, dict)  # type: ignore[attr-defined]
    except Exception:
        return False


def _compiling() -> bool:
    """Whether ``torch.compile`` is tracing (PyTorch imported: a tensor was seen)."""
    return bool(sys.modules["torch"].compiler.is_compiling())


def _interface(x: Any) -> dict[str, Any]:
    if _is_torch(x):
        x = x.detach()
    desc = x.__cuda_array_interface__
    return dict(desc)


def _host_view(desc: dict[str, Any]) -> np.ndarray:
    """NumPy view of a ``__cuda_array_interface__`` in host memory (the simulator's stand-ins)."""
    dtype = np.dtype(desc["typestr"])
    shape = tuple(int(s) for s in desc["shape"])
    strides = desc.get("strides")
    ptr = int(desc["data"][0])
    count = int(np.prod(shape)) if shape else 1
    if strides is None:
        span = count * dtype.itemsize
    else:
        span = sum((s - 1) * abs(st) for s, st in zip(shape, strides, strict=True)) + dtype.itemsize
    if count == 0:
        return np.empty(shape, dtype=dtype)
    buf = (ctypes.c_char * span).from_address(ptr)
    return np.ndarray(shape, dtype=dtype, buffer=buf, strides=strides)


def as_device_array(x: Any) -> Any:
    """Return a numba device array viewing the memory of the CUDA array ``x`` (no copy, no sync).

    PyTorch tensors that record gradients are viewed through ``detach()`` (the kernels do
    not record a graph; callers keep gradient-recording tensors on the Array-API path).
    Numba device arrays are returned as they are.
    """
    c = cuda()
    if simulated():
        if _is_sim_array(x):
            return x
        from numba.cuda.simulator.cudadrv.devicearray import FakeCUDAArray

        return FakeCUDAArray(_host_view(_interface(x)))
    if c.is_cuda_array(x) and not (_is_torch(x) or _is_cupy(x)) and hasattr(x, "gpu_data"):
        return x
    return c.from_cuda_array_interface(_interface(x), owner=x, sync=False)


#: a library's dtype object (NumPy's, PyTorch's, CuPy's) -> its name without the prefix
_DTYPE_NAMES: dict[Any, str] = {}


def dtype_name(x: Any) -> str:
    """Return the name of ``x``'s dtype without its library's prefix (``"float32"``).

    Cached per dtype object: a kernel's :func:`guarded` key costs one dict lookup per call.
    """
    dt = getattr(x, "dtype", None)
    try:
        return _DTYPE_NAMES[dt]
    except KeyError:
        name = _DTYPE_NAMES[dt] = str("" if dt is None else dt).removeprefix("torch.")
        return name
    except TypeError:  # pragma: no cover - an unhashable dtype
        return str(dt).removeprefix("torch.")


def _numpy_dtype(x: Any, dtype: Any) -> np.dtype[Any]:
    if dtype is None:
        if _is_torch(x):
            return np.dtype(str(x.dtype).removeprefix("torch."))
        return np.dtype(_interface(x)["typestr"]) if not hasattr(x, "dtype") else np.dtype(x.dtype)
    if _is_torch(x) and not isinstance(dtype, str | np.dtype | type):
        return np.dtype(str(dtype).removeprefix("torch."))
    return np.dtype(dtype)


def empty_like(x: Any, shape: Any = None, dtype: Any = None) -> Any:
    """Return an uninitialised C-contiguous array in ``x``'s library, on ``x``'s device.

    ``shape`` defaults to ``x``'s shape and ``dtype`` to ``x``'s dtype (a NumPy dtype or
    name, or the library's own dtype). PyTorch gives a tensor, CuPy an array, anything else
    (and the simulator's stand-ins) a numba device array.
    """
    t = type(x)
    kind = _KINDS.get(t)
    if kind is None:
        kind = _kind_of(t)
    if kind == _TORCH:
        torch = sys.modules["torch"]
        tdt = x.dtype if dtype is None else _TORCH_DTYPES.get(dtype)
        if tdt is None:
            tdt = dtype if isinstance(dtype, torch.dtype) else getattr(torch, np.dtype(dtype).name)
            _TORCH_DTYPES[dtype] = tdt
        return torch.empty(x.shape if shape is None else shape, dtype=tdt, device=x.device)
    shp = tuple(int(s) for s in (x.shape if shape is None else shape))
    if kind == _CUPY:
        import cupy

        with x.device:
            return cupy.empty(shp, dtype=_numpy_dtype(x, dtype))
    return cuda().device_array(shp, dtype=_numpy_dtype(x, dtype))


#: dtype (a NumPy dtype or name, a PyTorch dtype) -> the PyTorch dtype (:func:`empty_like`)
_TORCH_DTYPES: dict[Any, Any] = {}

# (library stream handle) -> numba stream object
_STREAMS: dict[int, Any] = {}


def _torch_stream(x: Any) -> int:
    """Return the handle of PyTorch's current stream on ``x``'s device.

    ``torch._C._cuda_getCurrentRawStream(index)`` (what ``torch.compile``'s generated code
    calls) is one C call; ``torch.cuda.current_stream(device)`` builds a Stream object
    (several microseconds). The same handle either way.
    """
    torch = sys.modules["torch"]
    raw = getattr(torch._C, "_cuda_getCurrentRawStream", None)
    if raw is not None and x.is_cuda:
        _RAW_STREAM[0] = raw
        return int(raw(x.get_device()))
    return int(torch.cuda.current_stream(x.device).cuda_stream)


def _stream_handle(x: Any) -> int | None:
    if _is_torch(x):
        return _torch_stream(x)
    if _is_cupy(x):
        import cupy

        with x.device:
            return int(cupy.cuda.get_current_stream().ptr)
    try:
        s = x.__cuda_array_interface__.get("stream")
    except Exception:
        return None
    return None if s is None else int(s)


def _fast_stream(x: Any) -> Any:
    """:func:`_stream_for` of a fast launch (not simulated): a CUDA tensor's in one C call."""
    if _RAW_STREAM[0] is not None and x.is_cuda and _KINDS.get(type(x)) == _TORCH:
        handle = _RAW_STREAM[0](x.get_device())
        if not handle:  # PyTorch's default stream
            return 0
        st = _STREAMS.get(handle)
        if st is not None:
            return st
    return _stream_for(x)


#: ``torch._C._cuda_getCurrentRawStream`` once PyTorch has a CUDA tensor here (else None)
_RAW_STREAM: list[Any] = [None]


def _stream_for(x: Any) -> Any:
    """Return the numba stream that orders a launch after ``x``'s producer (0: numba's default)."""
    if simulated():
        return 0
    handle = _stream_handle(x)
    if not handle:
        return 0
    st = _STREAMS.get(handle)
    if st is None:
        if len(_STREAMS) > 64:
            _STREAMS.clear()
        st = cuda().external_stream(handle)
        _STREAMS[handle] = st
    return st


def _device_index(x: Any) -> int | None:
    if _is_torch(x):
        return x.device.index
    if _is_cupy(x):
        return int(x.device.id)
    return None


#: Threads per block of :func:`launch_rows`: a warp along a row (coalesced), 8 rows.
ROW_BLOCK = (32, 8)
_SIM_ROW_BLOCK = (8, 4)
#: The largest grid height (CUDA's limit); taller images loop over rows in the kernel.
_MAX_GRID_Y = 65535

# Python numbers and NumPy scalars go to numba as they are (no array test on them)
_SCALARS = (int, float, bool, np.generic)


def _launch(kernel: Any, grid: tuple[int, ...], block: tuple[int, ...], args: Any) -> None:
    """Launch ``kernel[grid, block, stream](*args)``, CUDA arrays viewed as device arrays.

    ``grid`` and ``block``: 3-tuples. A signature that passed the fast launch's check
    (:mod:`imageform._cuda._fastlaunch`) is launched from its packed arguments; otherwise
    numba launches: each argument is looked at once, numbers pass as they are,
    :class:`Constants` as their numbers, CUDA arrays of any library become numba device
    arrays (:func:`as_device_array`; numba's own are passed as they are), the first one
    names the stream and the device.
    """
    key = None
    fast = _FAST[0]
    if fast is None:
        fast = _fast_on()
    if fast:
        got = _fastlaunch.pack_call(kernel, args)
        if got is not None:
            key, packed, first = got
            run = _fastlaunch._READY.get(key)
            if run is not None:  # checked against numba's own packing (_fastlaunch.prepare)
                try:
                    run(grid, block, _fast_stream(first), packed)
                except Exception:  # never the call's failure: numba's path from now on
                    _fastlaunch.forget(key)
                else:
                    with _LOCK:
                        _LAUNCHES[0] += 1
                    return
    sim = simulated()
    first = None
    dargs = []
    for a in expand(args):
        if not isinstance(a, _SCALARS) and is_cuda_array(a):
            if first is None:
                first = a
            a = as_device_array(a)
        dargs.append(a)
    stream = 0 if first is None else _stream_for(first)
    dev = None if first is None or sim else _device_index(first)
    with _LOCK:
        _LAUNCHES[0] += 1
    c = cuda()
    if dev is not None and len(c.gpus) > 1 and c.get_current_device().id != dev:
        with c.gpus[dev]:
            kernel[grid, block, stream](*dargs)
        return
    config = kernel[grid, block, stream]
    config(*dargs)
    if key is not None:  # the first launch of this signature: check the fast packing once
        _fastlaunch.prepare(key, kernel, config, args, dargs)


#: Whether fast launches run (None: not decided yet; :func:`refresh_switches`).
_FAST: list[bool | None] = [None]


def _fast_on() -> bool:
    """Fast launches (:mod:`imageform._cuda._fastlaunch`): on, unless turned off; one GPU.

    Never under the simulator. Decided on the first launch (numba's CUDA module is imported
    by then).
    """
    on = _FAST[0] = (
        not simulated() and _fastlaunch.enabled() and use_cuda() and len(cuda().gpus) == 1
    )
    return on


def launch_1d(kernel: Any, n: int, *args: Any) -> None:
    """Launch ``kernel`` over ``n`` threads (``cuda.grid(1)`` in ``[0, n)``; guard ``i < n``).

    ``args`` are passed in order; CUDA arrays of any library (:func:`is_cuda_array`) are
    turned into numba device arrays (:func:`as_device_array`), numbers pass as they are. The
    launch goes on the current stream of the first library array (PyTorch's or CuPy's, or
    the stream its ``__cuda_array_interface__`` names), on that array's device; it does not
    wait for the kernel. Nothing is launched when ``n == 0``.
    """
    if n <= 0:
        return
    threads = _SIM_THREADS if simulated() else THREADS
    _launch(kernel, ((int(n) + threads - 1) // threads, 1, 1), (threads, 1, 1), args)


def launch_rows(kernel: Any, rows: int, cols: int, *args: Any) -> None:
    """Launch ``kernel`` on a 2-D grid: ``x`` over ``cols``, ``y`` over ``rows``.

    :func:`launch_1d`'s conventions (device arrays of any library viewed without a copy or a
    sync, the producer's stream and device, the launch counted), with a 2-D grid of
    :data:`ROW_BLOCK` blocks, so that a kernel over an image finds its pixel without 64-bit
    integer divisions (tens of instructions each on a GPU). The grid height is capped at
    CUDA's 65535 blocks: kernels loop over rows with a stride of ``gridDim.y * blockDim.y``,
    and guard ``column < cols``. Nothing is launched when either size is 0.
    """
    if rows <= 0 or cols <= 0:
        return
    bx, by = _SIM_ROW_BLOCK if simulated() else ROW_BLOCK  # a simulated thread: a Python one
    grid = ((cols + bx - 1) // bx, min((rows + by - 1) // by, _MAX_GRID_Y), 1)
    _launch(kernel, grid, (bx, by, 1), args)


#: Kernels (their callers' keys) that have compiled and run once in this process.
_COMPILED: set[Any] = set()


def guarded(key: Any, kernel: Any, size: int | tuple[int, int], *args: Any) -> bool:
    """Launch; False when the kernel's first compilation failed (the kernels are then off).

    ``size``: ``n`` threads (:func:`launch_1d`) or ``(rows, cols)`` (:func:`launch_rows`);
    ``args``: the kernel's arguments, numbers that are the same in every call optionally
    grouped as one :class:`Constants` (packed once for the fast launch);
    ``key`` (hashable) names the kernel and what it is compiled for (its dtype). A machine
    whose numba CUDA target lacks its compiler (NVVM) or cannot type a kernel turns the
    kernels off for the process (:func:`disable`, one warning) and the caller runs the
    Array-API path. Errors of a key that has run once, and errors that are not numba's,
    propagate. numba's errors include any exception raised inside numba's own code on the
    first compilation, such as numba-cuda 0.30 meeting NumPy 2.5 (``np.row_stack`` is gone
    and numba's CUDA lowering module fails to import: an AttributeError, not a numba type).
    """
    try:
        if isinstance(size, tuple):
            launch_rows(kernel, size[0], size[1], *args)
        else:
            launch_1d(kernel, size, *args)
    except Exception as exc:
        if key in _COMPILED or not _raised_by_numba(exc):
            raise
        disable(f"{type(exc).__name__}: {str(exc).splitlines()[0][:200]}")
        return False
    _COMPILED.add(key)
    return True


def disable(reason: str) -> None:
    """Switch the kernels off for this process (the Array-API path runs), with one warning.

    Called when numba's CUDA target cannot compile a kernel on this machine (no NVVM
    library: ``pip install "imageform[cuda]"``), so that a missing toolkit costs speed, not
    the call.
    """
    import warnings

    if not _DISABLED[0]:
        _DISABLED[0] = reason
        warnings.warn(
            f"imageform's CUDA kernels are off for this process: {reason}",
            RuntimeWarning,
            stacklevel=3,
        )


def _raised_by_numba(exc: BaseException) -> bool:
    """Whether ``exc`` is numba's: its type is numba's, or numba's code raised it."""
    if type(exc).__module__.startswith("numba"):
        return True
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:  # the innermost frame raised it
        tb = tb.tb_next
    name = str(tb.tb_frame.f_globals.get("__name__", "")) if tb is not None else ""
    return name == "numba" or name.startswith(("numba.", "numba_cuda"))


def status() -> str:
    """One line: whether the kernels run here, on which numba CUDA target, or why not."""
    on = use_cuda()
    if not on and _env_on("IMAGEFORM_DISABLE_CUDA"):
        return "off (IMAGEFORM_DISABLE_CUDA)"
    if _DISABLED[0]:
        return f"off ({_DISABLED[0]})"
    if not on:
        return "off (numba finds no CUDA device)"
    c = cuda()
    where = "simulator" if simulated() else str(c.get_current_device().name)
    return f"on ({getattr(c, 'implementation', 'numba-cuda')} numba CUDA target, {where})"


def launch_count() -> int:
    """How many kernels :func:`launch_1d` and :func:`launch_rows` have launched (tests, benches)."""
    return _LAUNCHES[0]
