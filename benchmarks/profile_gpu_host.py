"""Where the host's time goes in one imageform call on CUDA tensors (issue 29).

On a GPU a 4K colour conversion's kernel takes tens of microseconds, so a call's wall time
is mostly the host's: Python validation, the dispatch to the kernels and the launch. This
script times tiny calls (8x8 pixels, 64 points: the kernel's time is nil, so the time is
the host's) for the fused operations, then profiles them with cProfile (the functions with
the largest own time). On a lent GPU::

    PYTHONPATH=src python benchmarks/profile_gpu_host.py > host-profile.txt

``--dry`` measures the same calls without a GPU: every call goes from the public function
through imageform's dispatch, :mod:`imageform._cuda._launch` and the fast launch
(:mod:`imageform._cuda._fastlaunch`, its packing checked against numba's ``_prepare_args``
as on a device) down to the launch primitive, which is a stub. The stand-ins:

- the tensors are PyTorch ``meta`` tensors (shape, dtype, strides, no memory), counted as
  CUDA tensors (``_launch._META_AS_CUDA``); the device rule treats them as a GPU's (no value
  is read);
- numba's CUDA module is a stand-in (``jit`` gives kernels that record their overload on the
  first launch; one GPU; ``external_stream``), and the first launch of a signature, which on
  a device compiles, views the tensors as stand-in device arrays that numba's own
  ``_Kernel._prepare_args`` packs for the check;
- the launch primitive is ``cuda.core``'s ``launch(stream, config, kernel, *args)`` as
  numba-cuda calls it (``--flavour core``, the default, as on the H200) or numba's built-in
  target's ``driver.launch_kernel`` (``--flavour ctypes``): a stub that counts;
- PyTorch's current stream is a stand-in (stream 0, PyTorch's default stream).

So the figures are imageform's own Python plus PyTorch's ``meta`` tensor operations (the
output allocation and views: cheaper than CUDA's), without numba's or the driver's time::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/profile_gpu_host.py --dry

It prints, per call, the median wall and process (CPU) time, the Python function calls per
call (all, and imageform's own: a count that does not depend on the machine's load) and the
share of the profiled time spent in imageform's own functions, then each call's cProfile by
own time.
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import ctypes
import io
import pstats
import statistics
import sys
import time
import types as pytypes
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

#: The rows, in order (``--rows`` takes a comma-separated subset of these names).
ROWS = (
    "convert srgb->lab",
    "convert srgb->linear_srgb",
    "delta_e ciede2000",
    "project_points (64 pts)",
    "BrownConrady.distort (64 pts)",
    "demosaic bilinear (8x8)",
    "remap_bilinear (8x8x3)",
    "NumPy convert srgb->lab (8x8, the CPU path)",
)

# --- stand-ins for a device (--dry) ---------------------------------------------------------

#: launches the stub primitive received, numba-path launches (first of each signature)
COUNTS = {"fast": 0, "numba": 0}
#: the arguments of the last fast launch (tests read it)
LAST: list[Any] = [None]


class _Stream:
    """A numba stream wrapping a handle (``cuda.external_stream``)."""

    def __init__(self, handle: int) -> None:
        self.handle = ctypes.c_void_p(handle)


class _LaunchConfig:
    """``cuda.core``'s ``LaunchConfig``."""

    def __init__(self, grid: Any, block: Any, shmem_size: int = 0, **flags: Any) -> None:
        self.grid, self.block, self.shmem_size, self.flags = grid, block, shmem_size, flags


def _core_launch(stream: Any, config: Any, kernel: Any, *args: Any) -> None:
    """``cuda.core``'s ``launch``: counts, keeps the arguments."""
    COUNTS["fast"] += 1
    LAST[0] = args


def _driver_launch(handle: Any, *rest: Any, cooperative: bool = False) -> None:
    """numba's ``driver.launch_kernel(handle, gx, gy, gz, bx, by, bz, shmem, stream, args)``."""
    COUNTS["fast"] += 1
    LAST[0] = rest[-1]


class _DeviceArray:
    """What numba's ``_prepare_args`` reads of a device array (as the fast-launch tests)."""

    __cuda_memory__ = True

    def __init__(self, t: Any) -> None:
        import numpy as np

        dt = np.dtype(str(t.dtype).removeprefix("torch."))
        self.dtype, self.shape, self.ndim = dt, tuple(int(s) for s in t.shape), t.dim()
        self.size = int(t.numel())
        self.contiguous = bool(t.is_contiguous())
        if self.contiguous:
            acc, st = dt.itemsize, []
            for s in reversed(self.shape):
                st.append(acc)
                acc *= s
            self.strides = tuple(reversed(st))
        else:
            self.strides = tuple(int(s) * dt.itemsize for s in t.stride())
        self.device_ctypes_pointer = ctypes.c_void_p(int(t.data_ptr()))

    @property
    def __cuda_array_interface__(self) -> dict[str, Any]:
        return {"shape": self.shape, "typestr": self.dtype.str, "data": (0, False), "version": 3}


def _overload_module(flavour: str) -> pytypes.ModuleType:
    """The module of a compiled overload's type: where ``_fastlaunch`` finds the primitive."""
    from numba.core import types

    name = f"imageform_dry_{flavour}"
    mod = sys.modules.get(name)
    if mod is not None:
        return mod
    mod = pytypes.ModuleType(name)
    mod.types = types  # type: ignore[attr-defined]
    if flavour == "core":
        mod.launch = _core_launch  # type: ignore[attr-defined]
        mod.LaunchConfig = _LaunchConfig  # type: ignore[attr-defined]
        mod.CUDA_CORE_GE_1_0 = True  # type: ignore[attr-defined]
    else:
        mod.driver = pytypes.SimpleNamespace(  # type: ignore[attr-defined]
            launch_kernel=_driver_launch, USE_NV_BINDING=False
        )

    class Overload:
        """A compiled overload: its argument types, numba's packing, a cufunc."""

        debug = False
        cooperative = False

        def __init__(self, argtypes: tuple[Any, ...]) -> None:
            self.argument_types = argtypes
            cufunc = pytypes.SimpleNamespace(kernel=object(), handle=ctypes.c_void_p(1))
            self._codelibrary = pytypes.SimpleNamespace(get_cufunc=lambda: cufunc)

        def _prepare_args(self, ty: Any, val: Any, stream: Any, retr: Any, out: list) -> None:
            # numba's own packing (the built-in target's: ctypes); numba-cuda passes an
            # array's fields as Python integers and a boolean as a Python bool
            from numba.cuda.dispatcher import _Kernel

            got: list[Any] = []
            _Kernel._prepare_args(pytypes.SimpleNamespace(extensions=[]), ty, val, 0, retr, got)
            if flavour == "core" and isinstance(ty, types.Array):
                got = [int(getattr(v, "value", v) or 0) for v in got]
            elif flavour == "core" and ty == types.boolean:
                got = [bool(val)]
            out += got

    Overload.__module__ = name
    mod.Overload = Overload  # type: ignore[attr-defined]
    sys.modules[name] = mod
    return mod


class _Config:
    """``kernel[grid, block, stream]``: calling it is numba's launch (it compiles first)."""

    def __init__(self, kernel: _Kernel, grid: Any, block: Any, stream: Any) -> None:
        self.kernel, self.griddim, self.blockdim, self.stream = kernel, grid, block, stream

    def __call__(self, *args: Any) -> None:
        k = self.kernel
        sig = tuple(k.typeof_pyval(a) for a in args)
        if sig not in k.overloads:
            k.overloads[sig] = k.overload_type(sig)
        COUNTS["numba"] += 1


class _Kernel:
    """A numba CUDA dispatcher: configurations, overloads, argument typing."""

    def __init__(self, fn: Any, overload_type: type) -> None:
        self.py_func, self.overload_type = fn, overload_type
        self.overloads: dict[tuple[Any, ...], Any] = {}

    def __getitem__(self, cfg: tuple[Any, ...]) -> _Config:
        return _Config(self, *cfg[:3])

    def typeof_pyval(self, v: Any) -> Any:
        from numba import typeof
        from numba.core import types
        from numba.np.numpy_support import from_dtype

        if isinstance(v, _DeviceArray):
            return types.Array(from_dtype(v.dtype), v.ndim, "C" if v.contiguous else "A")
        return typeof(v)


class _Cuda:
    """numba's CUDA module, as far as imageform uses it."""

    implementation = "dry stand-in"

    def __init__(self, flavour: str) -> None:
        self._overload = _overload_module(flavour).Overload
        self.gpus = [pytypes.SimpleNamespace(id=0)]

    def is_available(self) -> bool:
        return True

    def get_current_device(self) -> Any:
        return pytypes.SimpleNamespace(id=0, name="no device: --dry")

    def jit(self, fn: Any = None, **kw: Any) -> Any:
        if fn is None or isinstance(fn, str):
            return lambda f: self.jit(f, **kw)
        return fn if kw.get("device") else _Kernel(fn, self._overload)

    def is_cuda_array(self, x: Any) -> bool:
        return hasattr(x, "__cuda_array_interface__")

    def external_stream(self, handle: int) -> _Stream:
        return _Stream(handle)

    def device_array(self, shape: Any, dtype: Any) -> Any:
        import torch

        return _DeviceArray(torch.empty(shape, dtype=getattr(torch, str(dtype)), device="meta"))


@contextlib.contextmanager
def dry_device(flavour: str = "core") -> Iterator[None]:
    """Run imageform's CUDA dispatch on ``meta`` tensors down to a stub launch primitive.

    For a process of its own (a benchmark, a test's subprocess): the kernel caches filled
    inside are stand-ins, and nothing empties them afterwards.
    """
    import torch

    from imageform._cuda import _launch, geometry

    cuda = _Cuda(flavour)
    saved = {
        "cuda": _launch.cuda,
        "_META_AS_CUDA": _launch._META_AS_CUDA,
        "as_device_array": _launch.as_device_array,
    }
    saved_stream = torch.cuda.current_stream
    setattr(_launch, "cuda", lambda: cuda)  # noqa: B010 - stand-ins, put back on exit
    setattr(_launch, "_META_AS_CUDA", True)  # noqa: B010
    setattr(  # noqa: B010
        _launch, "as_device_array", lambda x: x if isinstance(x, _DeviceArray) else _DeviceArray(x)
    )
    _launch._available.cache_clear()
    _launch.refresh_switches()
    geometry.cuda = None
    # PyTorch's default stream (handle 0), as on a device outside torch.cuda.stream(...)
    stream0 = pytypes.SimpleNamespace(cuda_stream=0)
    setattr(torch.cuda, "current_stream", lambda device=None: stream0)  # noqa: B010
    try:
        yield
    finally:
        for k, v in saved.items():
            setattr(_launch, k, v)
        _launch._available.cache_clear()
        _launch.refresh_switches()
        setattr(torch.cuda, "current_stream", saved_stream)  # noqa: B010


# --- the calls ------------------------------------------------------------------------------


def calls(device: str) -> dict[str, Callable[[], Any]]:
    """The profiled calls on tensors of ``device`` (``"cuda"``, or ``"meta"`` for --dry)."""
    import numpy as np
    import torch

    from imageform import color as c
    from imageform import geometry as g
    from imageform import sensor as s

    dev = torch.device(device)
    rgb = torch.rand(8, 8, 3).to(dev)
    lab = torch.rand(8, 8, 3).to(dev)
    pts = (torch.rand(64, 3) + torch.tensor([0.0, 0.0, 4.0])).to(dev)
    K = torch.tensor([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]]).to(dev)
    bc = g.BrownConrady(k1=-0.1, k2=0.01)
    xy = (torch.rand(64, 2) - 0.5).to(dev)
    raw = torch.rand(8, 8).to(dev)
    img = torch.rand(8, 8, 3).to(dev)
    grid = torch.stack(torch.meshgrid(torch.arange(8.0), torch.arange(8.0), indexing="xy"), -1)
    map_uv = (grid + 0.25).to(dev)
    host = np.random.default_rng(0).random((8, 8, 3))
    fns: dict[str, Callable[[], Any]] = {
        "convert srgb->lab": lambda: c.convert(rgb, "srgb", "lab"),
        "convert srgb->linear_srgb": lambda: c.convert(rgb, "srgb", "linear_srgb"),
        "delta_e ciede2000": lambda: c.delta_e(lab, lab, "ciede2000"),
        "project_points (64 pts)": lambda: g.project_points(pts, K),
        "BrownConrady.distort (64 pts)": lambda: bc.distort(xy),
        "demosaic bilinear (8x8)": lambda: s.demosaic(raw, "RGGB", "bilinear"),
        "remap_bilinear (8x8x3)": lambda: g.remap_bilinear(img, map_uv),
        # the CPU path: a NumPy call must not pay for the GPU dispatch
        "NumPy convert srgb->lab (8x8, the CPU path)": lambda: c.convert(host, "srgb", "lab"),
    }
    assert tuple(fns) == ROWS
    return fns


def timed(
    fn: Callable[[], Any], sync: Callable[[], Any], calls: int = 300, rounds: int = 5
) -> tuple[float, float]:
    """Median over ``rounds`` rounds of ``calls`` calls: (wall µs, process CPU µs) per call."""
    for _ in range(5):
        fn()
    sync()
    wall, cpu = [], []
    for _ in range(rounds):
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(calls):
            fn()
        sync()
        wall.append((time.perf_counter() - t0) / calls)
        cpu.append((time.process_time() - c0) / calls)
    return statistics.median(wall) * 1e6, statistics.median(cpu) * 1e6


def _own(filename: str) -> bool:
    """Whether a profiled function is imageform's (its source under ``imageform/``)."""
    f = filename.replace("\\", "/")
    return "/imageform/" in f and "/benchmarks/" not in f


def _short_paths(text: str) -> str:
    """The listing's file names relative to the repository or to site-packages."""
    import re

    root = str(Path(__file__).resolve().parents[1]) + "/"
    text = text.replace(root, "")
    return re.sub(r"\S*/(site-packages|lib/python3\.\d+)/", r"\1/", text)


def profiled(fn: Callable[[], Any], sync: Callable[[], Any], calls: int, top: int) -> Any:
    """cProfile of ``calls`` calls: (calls per call, own calls per call, own share, listing)."""
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(calls):
        fn()
    sync()
    prof.disable()
    st = pstats.Stats(prof)
    n_all = n_own = 0
    t_all = t_own = 0.0
    for (filename, _, _), (_, nc, tt, _, _) in st.stats.items():  # type: ignore[attr-defined]
        n_all += nc
        t_all += tt
        if _own(filename):
            n_own += nc
            t_own += tt
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(top)
    text = _short_paths(s.getvalue().strip())
    return n_all / calls, n_own / calls, t_own / t_all if t_all else 0.0, text


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dry", action="store_true", help="no GPU: meta tensors, a stub launch")
    ap.add_argument("--flavour", choices=("core", "ctypes"), default="core")
    ap.add_argument("--calls", type=int, default=300, help="calls per timing round")
    ap.add_argument("--rounds", type=int, default=5, help="timing rounds (the median is shown)")
    ap.add_argument("--rows", default="", help="comma-separated row names (default: all)")
    ap.add_argument("--top", type=int, default=25, help="profile lines per row")
    opts = ap.parse_args(argv)
    want = [r.strip() for r in opts.rows.split(",") if r.strip()] or list(ROWS)
    unknown = sorted(set(want) - set(ROWS))
    if unknown:
        ap.error(f"unknown rows {unknown}; choose from {list(ROWS)}")
    with dry_device(opts.flavour) if opts.dry else contextlib.nullcontext():
        run(opts, want)


def run(opts: Any, want: list[str]) -> None:
    import torch

    from imageform._cuda import _fastlaunch, _launch

    device = "meta" if opts.dry else "cuda"
    sync = (lambda: None) if opts.dry else torch.cuda.synchronize
    fns = calls(device)
    print(f"imageform CUDA kernels: {_launch.status()}")
    print(f"fast launch (IMAGEFORM_CUDA_FAST_LAUNCH): {_fastlaunch.enabled()}")
    if opts.dry:
        print(f"--dry: meta tensors, stub launch primitive ({opts.flavour} flavour)")
    print()
    if not opts.dry:
        dev = torch.device("cuda")
        rgb = torch.rand(8, 8, 3, device=dev)
        empty = torch.empty(8, 8, 3, device=dev)
        dargs = _launch.as_device_array(rgb)
        print("| reference (tiny input) | host µs per call |\n|---|---|")
        for name, fn in [
            ("torch.empty (8x8x3)", lambda: torch.empty(8, 8, 3, device=dev)),
            ("torch add (8x8x3, one kernel)", lambda: rgb + 1.0),
            ("_launch.as_device_array (one tensor)", lambda: _launch.as_device_array(rgb)),
            ("numba device-array view reused (no-op)", lambda: dargs),
            ("empty_like + copy_ (8x8x3)", lambda: empty.copy_(rgb)),
        ]:
            print(f"| {name} | {timed(fn, sync, opts.calls)[0]:.1f} |")
        print()
    head = (
        f"| call (tiny input) | wall µs per call (median of {opts.rounds} x {opts.calls}) "
        "| CPU µs per call | Python calls per call "
        "| of which imageform's | imageform's share of profiled time |"
    )
    print(head + "\n|---|---|---|---|---|---|")
    listings = []
    for name in want:
        fn = fns[name]
        wall, cpu = timed(fn, sync, opts.calls, opts.rounds)
        n_all, n_own, share, text = profiled(fn, sync, opts.calls, opts.top)
        print(f"| {name} | {wall:.1f} | {cpu:.1f} | {n_all:.0f} | {n_own:.0f} | {share:.0%} |")
        listings.append((name, text))
    ready = list(_fastlaunch._READY.values())
    fast = sum(r is not None for r in ready)
    print(f"\nfast launch: {fast} of {len(ready)} kernel signatures passed the packing check")
    if opts.dry:
        print(f"launches: {COUNTS['fast']} fast (stub primitive), {COUNTS['numba']} numba's path")
    for name, text in listings:
        print(f"\ncProfile of {opts.calls} calls of {name}, by own time:\n\n```text")
        print(text + "\n```")


if __name__ == "__main__":
    main()
