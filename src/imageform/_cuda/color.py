"""Fused CUDA colour kernels: a chain of per-pixel steps, or a colour difference, in one launch.

A colour conversion is a chain of steps (:data:`imageform._cuda.scalar.NAMES`: transfer
curves, 3x3 matrices, CIELAB, LCh, Luv, xyY, HSV/HSL/HSI, Y'CbCr, gains); :func:`run_chain`
generates one kernel per chain and dtype that reads a pixel once, applies every step in
registers and writes it once, so ``convert(x, "srgb", "lab")`` is one launch whatever the
length of its path. The steps' numbers (matrices, whites, exponents) are kernel arguments,
not device arrays: a call uploads nothing. :func:`run_delta_e` is one launch per ΔE.

Inputs are CUDA arrays of any library (:mod:`imageform._cuda._launch`), shape ``(..., 3)``,
float32 or float64; the result is a new array of the input's library, device and dtype.
The kernels are compiled by numba's CUDA target on first use of each chain and dtype (about
a second each), then cached for the process.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from imageform._cuda import _launch
from imageform._cuda.scalar import DELTA_E, NAMES, functions

__all__ = [
    "INT_SCALE",
    "KernelUnavailable",
    "Step",
    "chain_source",
    "run_chain",
    "run_chain_twin",
    "run_delta_e",
    "run_delta_e_twin",
    "run_elementwise",
]

#: One step of a chain: its name in :data:`~imageform._cuda.scalar.NAMES` and its numbers.
Step = tuple[str, tuple[float, ...]]

_LOCK = threading.Lock()
_KERNELS: dict[tuple[Any, ...], Any] = {}


def chain_source(names: Sequence[str], target: str = "cuda", scale: float | None = None) -> str:
    """Return the Python source of the kernel that applies the steps ``names`` in turn.

    The kernel takes ``(x, out, n, p0, p1, ...)``: ``x`` and ``out`` of shape ``(n, 3)``
    (any strides), then every step's numbers in order. ``target="cuda"``: one thread per
    pixel (``cuda.grid(1)``); ``"cpu"``: the CPU twin, a loop over the pixels with the same
    body. ``scale``: integer code values in ``x`` (uint8: 255, uint16: 65535), read as
    ``F(code) / F(scale)`` as the array path's ``as_image`` does.
    """
    args: list[str] = []
    body: list[str] = []
    for k, name in enumerate(names):
        ps = [f"p{len(args) + j}" for j in range(NAMES[name])]
        args += ps
        call = ", ".join(["a", "b", "c", *ps])
        body.append(f"        a, b, c = s{k}({call})")
    head = ", ".join(["x", "out", "n", *args])
    lines = [
        f"def kernel({head}):",
        *(
            ["    i = cuda.grid(1)", "    if i < n:"]
            if target == "cuda"
            else ["    for i in range(n):"]
        ),
        *(
            [f"        {v} = x[i, {j}]" for j, v in enumerate("abc")]
            if scale is None
            else [f"        {v} = F(x[i, {j}]) / F({float(scale)!r})" for j, v in enumerate("abc")]
        ),
        *body,
        "        out[i, 0] = a",
        "        out[i, 1] = b",
        "        out[i, 2] = c",
    ]
    return "\n".join(lines) + "\n"


def _cached(key: tuple[Any, ...], build: Any) -> Any:
    """Return the kernel cached under ``key``, built by ``build()`` once per process."""
    k = _KERNELS.get(key)
    if k is None:
        with _LOCK:
            k = _KERNELS.get(key)
            if k is None:
                k = _KERNELS[key] = build()
    return k


def _kernel(
    names: tuple[str, ...], dtype: str, target: str = "cuda", scale: float | None = None
) -> Any:
    def build() -> Any:
        fns = functions(dtype, target)
        ns: dict[str, Any] = {"cuda": _launch.cuda() if target == "cuda" else None}
        ns["F"] = np.float32 if dtype == "float32" else np.float64
        for j, name in enumerate(names):
            ns[f"s{j}"] = fns[name]
        src = chain_source(names, target, scale)
        exec(compile(src, f"<imageform chain {names}>", "exec"), ns)
        if target == "cuda":
            return _launch.cuda().jit(ns["kernel"])
        from imageform._kernels.jit import njit

        return njit(cache=False)(ns["kernel"])

    return _cached(("chain", names, dtype, target, scale), build)


class KernelUnavailable(RuntimeError):
    """numba's CUDA target could not compile a kernel here; the kernels are now off."""


def _run(key: tuple[Any, ...], kernel: Any, n: int, *args: Any) -> None:
    """Launch over ``n`` pixels; :class:`KernelUnavailable` when numba cannot compile it here.

    :func:`imageform._cuda._launch.guarded` has then switched the kernels off; the callers
    run the Array-API path.
    """
    if not _launch.guarded(key, kernel, n, *args):
        raise KernelUnavailable(_launch.status())


def _dtype_name(x: Any) -> str | None:
    dt = _launch.dtype_name(x)
    return dt if dt in ("float32", "float64") else None


#: Full-range code values (docs/conventions.md): uint8 / 255, uint16 / 65535, in float32.
INT_SCALE = {"uint8": 255.0, "uint16": 65535.0}


def _int_scale(x: Any) -> float | None:
    return INT_SCALE.get(_launch.dtype_name(x))


def _flat(x: Any, channels: bool = True) -> Any:
    """Return ``x`` as ``(n, 3)`` (``(n,)``: ``channels=False``), a view where it can."""
    if _launch._is_torch(x):
        return x.reshape(-1, x.shape[-1]) if channels else x.reshape(-1)
    full = tuple(int(s) for s in x.shape)
    lead = full[:-1] if channels else full
    n = 1
    for s in lead:
        n *= int(s)
    return _reshape(x, (n, full[-1]) if channels else (n,))


def _reshape(x: Any, shape: tuple[int, ...]) -> Any:
    """Return ``x`` reshaped in its library (PyTorch, CuPy) or as a numba device array."""
    if _launch._is_torch(x) or _launch._is_cupy(x):
        return x.reshape(shape)
    d = _launch.as_device_array(x).reshape(shape)
    if isinstance(d, np.ndarray):  # the simulator's device arrays reshape to NumPy views
        from numba.cuda.simulator.cudadrv.devicearray import FakeCUDAArray

        d = FakeCUDAArray(d)
    return d


def _cast(dtype: str, values: Sequence[float]) -> tuple[Any, ...]:
    f = np.float32 if dtype == "float32" else np.float64
    return tuple(f(v) for v in values)


#: (steps, dtype, code-value scale) -> (kernel, its guarded key, the numbers as kernel
#: arguments of the dtype, packed once for the fast launch)
_PREPARED: dict[Any, tuple[Any, tuple[Any, ...], _launch.Constants]] = {}


def _prepared(
    steps: Sequence[Step], dtype: str, scale: float | None
) -> tuple[Any, tuple[Any, ...], _launch.Constants]:
    """Return the kernel, key and numbers of a chain (once per chain, dtype and scale)."""
    key = (tuple(steps), dtype, scale)
    got = _PREPARED.get(key)
    if got is None:
        if len(_PREPARED) > 256:
            _PREPARED.clear()
        names, params = _chain_params(steps, dtype)
        kernel = _kernel(names, dtype, "cuda", scale)
        values = _launch.Constants(_cast(dtype, params))
        got = _PREPARED[key] = (kernel, ("chain", names, dtype, scale), values)
    return got


def _chain_params(steps: Sequence[Step], dtype: str) -> tuple[tuple[str, ...], list[float]]:
    """Return the step names and numbers a chain's kernel runs with (float32: folded)."""
    names, params = _params(steps)
    if dtype == "float32":
        names, params = _fold_white(names, params)
    return names, params


def _fold_white(names: tuple[str, ...], params: list[float]) -> tuple[tuple[str, ...], list[float]]:
    """float32 chains: a ``matrix`` step followed by ``xyz_lab`` takes the white's division.

    The matrix's rows are divided by the white's X, Y, Z here (in float64, once per chain)
    and ``xyz_lab`` becomes ``xyz_lab1`` (no division): three divisions fewer per pixel and
    one rounding fewer. float64 chains keep the division of the array path.
    """
    out: list[str] = []
    vals: list[float] = []
    k = 0
    for name in names:
        ps = list(params[k : k + NAMES[name]])
        k += NAMES[name]
        if name == "xyz_lab" and out and out[-1] == "matrix":
            m = vals[-9:]
            vals[-9:] = [m[3 * r + j] / ps[r] for r in range(3) for j in range(3)]
            out.append("xyz_lab1")
        else:
            out.append(name)
            vals += ps
    return tuple(out), vals


def _params(steps: Sequence[Step]) -> tuple[tuple[str, ...], list[float]]:
    names = tuple(s for s, _ in steps)
    params: list[float] = []
    for name, ps in steps:
        if len(ps) != NAMES[name]:
            raise ValueError(f"step {name} takes {NAMES[name]} numbers, got {len(ps)}")
        params += list(ps)
    return names, params


def run_chain_twin(x: np.ndarray, steps: Sequence[Step]) -> np.ndarray:
    """Run the CPU twin of :func:`run_chain` on a NumPy array (same source, numba's CPU target).

    The kernel body and the scalar functions are those of the CUDA kernel, compiled for the
    CPU with the same dtype (float32 arithmetic for float32 input): CI checks the kernels'
    arithmetic with it without a GPU.
    """
    dtype, scale = _dtype_name(x), _int_scale(x)
    if dtype is None and scale is None:
        raise TypeError(f"expected float32, float64, uint8 or uint16, got dtype {x.dtype}")
    if dtype is None:
        dtype = "float32"
    names, params = _chain_params(steps, dtype)
    xf = np.ascontiguousarray(x).reshape(-1, 3)
    out = np.empty(xf.shape, dtype)
    _kernel(names, dtype, "cpu", scale)(xf, out, xf.shape[0], *_cast(dtype, params))
    return out.reshape(x.shape)


def run_chain(x: Any, steps: Sequence[Step]) -> Any:
    """Apply ``steps`` to every pixel of the CUDA array ``x`` (``(..., 3)``) in one launch.

    Returns a new array of ``x``'s library, device, dtype and shape.
    """
    name = _launch.dtype_name(x)
    dtype = name if name in ("float32", "float64") else None
    scale = INT_SCALE.get(name)
    if dtype is None and scale is None:
        raise TypeError(f"expected a float or uint8/uint16 CUDA array, got dtype {x.dtype}")
    if dtype is None:
        dtype = "float32"  # code values compute in float32 (IMAGE_INTEGER_DTYPE)
    kernel, key, values = _prepared(steps, dtype, scale)
    out = _launch.empty_like(x, dtype=dtype if scale is not None else None)
    xf, of = _flat(x), _flat(out)
    n = int(xf.shape[0])
    _run(key, kernel, n, xf, of, n, values)
    return out


def run_elementwise(x: Any, steps: Sequence[Step]) -> Any:
    """Apply channel-independent ``steps`` (transfer curves) to a CUDA array of any shape.

    The array's elements are read three at a time (its size must be a multiple of 3); the
    result has ``x``'s shape.
    """
    shape = tuple(int(s) for s in x.shape)
    size = 1
    for s in shape:
        size *= s
    if size % 3:
        raise ValueError(f"expected a size that is a multiple of 3, got shape {shape}")
    if shape[-1:] == (3,):
        return run_chain(x, steps)
    out = run_chain(_reshape(x, (size // 3, 3)), steps)
    return _reshape(out, shape)


_DE_SOURCE = """
def kernel(x, y, out, n, {params}):
    i = cuda.grid(1)
    if i < n:
        out[i] = fn(x[i, 0], x[i, 1], x[i, 2], y[i, 0], y[i, 1], y[i, 2]{call})
"""


def _de_source(name: str, target: str) -> str:
    ps = [f"p{j}" for j in range(DELTA_E[name])]
    src = _DE_SOURCE.format(params=", ".join(ps) or "_unused", call="".join(", " + p for p in ps))
    if target == "cpu":
        src = src.replace("    i = cuda.grid(1)\n    if i < n:", "    for i in range(n):")
    return src


def _de_kernel(name: str, dtype: str, target: str = "cuda") -> Any:
    def build() -> Any:
        ns: dict[str, Any] = {"fn": functions(dtype, target)[name]}
        if target == "cuda":
            ns["cuda"] = _launch.cuda()
        src = _de_source(name, target)
        exec(compile(src, f"<imageform delta_e {name} {target}>", "exec"), ns)
        if target == "cuda":
            return _launch.cuda().jit(ns["kernel"])
        from imageform._kernels.jit import njit

        return njit(cache=False)(ns["kernel"])

    return _cached(("de", name, dtype, target), build)


def run_delta_e(x: Any, y: Any, name: str, params: Sequence[float] = ()) -> Any:
    """ΔE ``name`` (``de76``, ``de94``, ``decmc``, ``de00``) of two same-shape CUDA arrays.

    ``x`` and ``y``: ``(..., 3)`` CIELAB of one library and dtype; returns ``(...)``.
    """
    dtype = _dtype_name(x)
    if dtype is None or _dtype_name(y) != dtype:
        raise TypeError("expected two CUDA arrays of one float dtype")
    kernel, key, vals = _de_prepared(name, dtype, tuple(params))
    lead = x.shape[:-1] if _launch._is_torch(x) else tuple(int(s) for s in x.shape)[:-1]
    out = _launch.empty_like(x, shape=lead)
    xf, yf = _flat(x), _flat(y)
    n = int(xf.shape[0])
    of = _flat(out, channels=False)
    _run(key, kernel, n, xf, yf, of, n, vals)
    return out


#: (ΔE name, dtype, its parameters) -> (kernel, its guarded key, the parameters as kernel
#: arguments of the dtype)
_DE_PREPARED: dict[Any, tuple[Any, tuple[Any, ...], _launch.Constants]] = {}


def _de_prepared(
    name: str, dtype: str, params: tuple[float, ...]
) -> tuple[Any, tuple[Any, ...], _launch.Constants]:
    """Return the kernel, key and numbers of a ΔE (once per name, dtype and parameters)."""
    key = (name, dtype, params)
    got = _DE_PREPARED.get(key)
    if got is None:
        if len(params) != DELTA_E[name]:
            raise ValueError(f"{name} takes {DELTA_E[name]} numbers, got {len(params)}")
        if len(_DE_PREPARED) > 256:
            _DE_PREPARED.clear()
        vals = _launch.Constants(_cast(dtype, params) if params else (0.0,))
        got = _DE_PREPARED[key] = (_de_kernel(name, dtype), ("de", name, dtype), vals)
    return got


def run_delta_e_twin(x: np.ndarray, y: np.ndarray, name: str, params: Sequence[float] = ()) -> Any:
    """Run the CPU twin of :func:`run_delta_e` (the same scalar function, numba's CPU target)."""
    dtype = _dtype_name(x)
    if dtype is None:
        raise TypeError(f"expected float32 or float64, got dtype {x.dtype}")
    k = _de_kernel(name, dtype, "cpu")
    xf = np.ascontiguousarray(x).reshape(-1, 3)
    yf = np.ascontiguousarray(y).reshape(-1, 3)
    out = np.empty(xf.shape[0], x.dtype)
    vals = _cast(dtype, params) if params else (0.0,)
    k(xf, yf, out, xf.shape[0], *vals)
    return out.reshape(x.shape[:-1])
