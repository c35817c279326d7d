"""Static size of the colour kernels in Hopper machine code (sm_90), without a GPU.

For each route (and each colour difference) the CUDA kernel of :mod:`imageform._cuda.color`
is compiled to PTX by numba (NVVM: a CUDA toolkit's ``libnvvm``), to machine code by
``ptxas -arch=sm_90 -O3``, and disassembled by ``cuobjdump -sass`` (it needs ``nvdisasm``);
the table counts instructions, the kernel body's instructions (``body``: before the first
subroutine that a ``CALL`` enters, padding ``NOP`` excluded: the slow paths of IEEE
division, ``sqrt`` and ``sinf``'s large-argument reduction live in those subroutines, which
a pixel of ordinary values never enters), special-function-unit instructions (``MUFU``) and
calls. A static count is not a timing: the kernels of a pointwise conversion are
compute-bound at 4K on an H100/H200 when they run a few hundred instructions per pixel, so
fewer instructions on the path every pixel takes is what this tracks between device runs.
``ptxas``, ``cuobjdump`` and ``nvdisasm`` must be on PATH (the pip wheels
``nvidia-cuda-cuobjdump`` and ``nvidia-cuda-nvdisasm`` carry the last two).

    PYTHONPATH=src:. python benchmarks/sass_colour.py
    PYTHONPATH=src:. python benchmarks/sass_colour.py --accuracy   # needs no CUDA tools

``--accuracy`` prints instead the float32 kernels' error against NumPy's float64 result
of the same float32 input, run by the CPU twin with each GPU approximation emulated at
twice its documented bound (:mod:`imageform._cuda.scalar`), on 100 000 pixels of
``tests/backends/test_cuda_kernels.f32_sample``.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import types
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

ROUTES = [
    ("srgb", "lab"),
    ("lab", "srgb"),
    ("srgb", "linear_srgb"),
    ("prophoto", "luv"),
    ("srgb", "hsv"),
]
#: The colour differences of :data:`imageform._cuda.scalar.DELTA_E`.
DELTA_E = ["de76", "de94", "decmc", "de00"]

_INSN = re.compile(r"^\s+/\*([0-9a-f]{4,})\*/\s+(.*?)\s*;", re.M)
_CALL = re.compile(r"CALL\.\S+\s+(0x[0-9a-f]+)")


def counts(sass: str) -> tuple[int, int, int, int]:
    """(instructions, body instructions, MUFU, CALL) of one kernel's SASS listing."""
    insns = [(int(a, 16), text) for a, text in _INSN.findall(sass)]
    targets = [int(t, 16) for t in _CALL.findall(sass)]
    end = min(targets) if targets else max((a for a, _ in insns), default=0) + 1
    body = sum(1 for a, text in insns if a < end and not text.startswith("NOP"))
    return len(insns), body, sass.count("MUFU"), sass.count("CALL")


def _sass(ptx: str, tmp: Path) -> str:
    ptx_path, cubin = tmp / "k.ptx", tmp / "k.cubin"
    ptx_path.write_text(ptx)
    subprocess.run(["ptxas", "-arch=sm_90", "-O3", str(ptx_path), "-o", str(cubin)], check=True)
    return subprocess.run(
        ["cuobjdump", "-sass", str(cubin)], capture_output=True, text=True, check=True
    ).stdout


def rows() -> list[tuple[str, str, tuple[int, int, int, int]]]:
    """(route or ΔE, dtype, counts) for every route and colour difference, both dtypes."""
    import numba.cuda.dispatcher as d
    import numpy as np
    from numba import cuda
    from numba import types as T

    from imageform._cuda import color as cc
    from imageform._cuda.scalar import DELTA_E as NPARAMS
    from imageform.color.convert import _kernel_steps, path
    from tests.backends.test_cuda_kernels import _with_white

    # device functions compile for the current device's compute capability: name one
    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
    out: list[tuple[str, str, tuple[int, int, int, int]]] = []
    dtypes: tuple[tuple[str, Any], ...] = (("float32", T.float32), ("float64", T.float64))
    with tempfile.TemporaryDirectory() as tmp:
        for src, dst in ROUTES:
            route = path(src, dst)
            steps = _kernel_steps(route, _with_white(route, {}))
            for dt, nb in dtypes:
                names, params = cc._chain_params(steps, dt)  # as run_chain launches it
                vals = cc._cast(dt, params)
                sig = (T.Array(nb, 2, "C"), T.Array(nb, 2, "C"), T.int64) + tuple(
                    T.float32 if isinstance(v, np.float32) else T.float64 for v in vals
                )
                kernel = cc._kernel(names, dt, "cuda", None)
                ptx = cuda.compile_ptx(kernel.py_func, sig, cc=(9, 0))[0]
                out.append((f"{src}→{dst}", dt, counts(_sass(ptx, Path(tmp)))))
        for name in DELTA_E:
            for dt, nb in dtypes:
                arr = T.Array(nb, 2, "C")
                # run_delta_e: the numbers in the dtype, or one unused Python float
                ps = (nb,) * NPARAMS[name] if NPARAMS[name] else (T.float64,)
                sig = (arr, arr, T.Array(nb, 1, "C"), T.int64, *ps)
                kernel = cc._de_kernel(name, dt, "cuda")
                ptx = cuda.compile_ptx(kernel.py_func, sig, cc=(9, 0))[0]
                out.append((name, dt, counts(_sass(ptx, Path(tmp)))))
    return out


def accuracy(n: int = 100_000) -> None:
    """Print the float32 kernels' largest error against float64 (the CPU twin, emulated)."""
    import numpy as np

    from imageform import color as c
    from imageform._cuda.color import run_chain_twin, run_delta_e_twin
    from imageform.color.convert import _kernel_steps, path
    from tests.backends import test_cuda_kernels as t

    rgb, lab1, lab2 = t.f32_sample(n)
    atol, rtol = t.F32_VS_F64
    print("| kernel | largest error per channel | NumPy float32's | share of the bound |")
    print("|---|---|---|---|")
    for src, dst in t.F32_ROUTES:
        x = np.asarray(c.convert(rgb, "srgb", src)).astype(np.float32)
        route = path(src, dst)
        got = run_chain_twin(x, _kernel_steps(route, t._with_white(route, {})))
        ref = np.asarray(c.convert(x.astype(np.float64), src, dst))
        own = np.abs(np.asarray(c.convert(x, src, dst)) - ref).max(0)
        err = np.abs(got - ref)
        share = (err / (atol + rtol * np.abs(ref))).max()
        print(
            f"| {src}→{dst} | {', '.join(f'{v:.1e}' for v in err.max(0))} | "
            f"{', '.join(f'{v:.1e}' for v in own)} | {share:.0%} |"
        )
    a, b = lab1.astype(np.float32), lab2.astype(np.float32)
    for name, params, fn in t.F32_DELTA_E:
        ps = list(params)
        if name == "de00":
            ps.append(float(np.finfo(np.float32).smallest_normal) ** 0.5)
        ref = np.asarray(fn(a.astype(np.float64), b.astype(np.float64)))
        err = np.abs(run_delta_e_twin(a, b, name, ps) - ref)
        own = np.abs(np.asarray(fn(a, b)) - ref).max()
        share = (err / (atol + rtol * np.abs(ref))).max()
        print(f"| {name} | {err.max():.1e} | {own:.1e} | {share:.0%} |")


def main() -> None:
    if "--accuracy" in sys.argv[1:]:
        accuracy()
        return
    print("| kernel | dtype | SASS instructions | body | MUFU | calls |")
    print("|---|---|---|---|---|---|")
    for name, dt, (n, body, mufu, calls) in rows():
        print(f"| {name} | {dt} | {n} | {body} | {mufu} | {calls} |")


if __name__ == "__main__":
    main()
