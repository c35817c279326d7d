"""Static size of the colour chain kernels in Hopper machine code (sm_90), without a GPU.

For each route the CUDA kernel of :mod:`imageform._cuda.color` is compiled to PTX by numba
(NVVM: a CUDA toolkit's ``libnvvm``), to machine code by ``ptxas -arch=sm_90 -O3``, and
disassembled by ``cuobjdump -sass`` (it needs ``nvdisasm``); the table counts instructions,
special-function-unit instructions (``MUFU``) and calls (slow paths of ``powf``, IEEE
division, ...). A static count is not a timing: the kernels of a pointwise conversion are
compute-bound at 4K on an H100/H200 when they run a few hundred instructions per pixel, so
fewer instructions on the path every pixel takes is what this tracks between device runs.
``ptxas``, ``cuobjdump`` and ``nvdisasm`` must be on PATH (the pip wheels
``nvidia-cuda-cuobjdump`` and ``nvidia-cuda-nvdisasm`` carry the last two).

    PYTHONPATH=src:. python benchmarks/sass_colour.py
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

ROUTES = [
    ("srgb", "lab"),
    ("lab", "srgb"),
    ("srgb", "linear_srgb"),
    ("prophoto", "luv"),
    ("srgb", "hsv"),
]


def main() -> None:
    import numba.cuda.dispatcher as d
    import numpy as np
    from numba import cuda
    from numba import types as T

    from imageform._cuda import color as cc
    from imageform.color.convert import _kernel_steps, path
    from tests.backends.test_cuda_kernels import _with_white

    # device functions compile for the current device's compute capability: name one
    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
    print("| route | dtype | SASS instructions | MUFU | calls |\n|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        ptx_path, cubin = Path(tmp) / "k.ptx", Path(tmp) / "k.cubin"
        for src, dst in ROUTES:
            route = path(src, dst)
            names, params = cc._params(_kernel_steps(route, _with_white(route, {})))
            for dt, nb in (("float32", T.float32), ("float64", T.float64)):
                vals = cc._cast(dt, params)
                sig = (T.Array(nb, 2, "C"), T.Array(nb, 2, "C"), T.int64) + tuple(
                    T.float32 if isinstance(v, np.float32) else T.float64 for v in vals
                )
                kernel = cc._kernel(names, dt, "cuda", None)
                ptx_path.write_text(cuda.compile_ptx(kernel.py_func, sig, cc=(9, 0))[0])
                subprocess.run(
                    ["ptxas", "-arch=sm_90", "-O3", str(ptx_path), "-o", str(cubin)], check=True
                )
                sass = subprocess.run(
                    ["cuobjdump", "-sass", str(cubin)], capture_output=True, text=True, check=True
                ).stdout
                n = len(re.findall(r"^\s+/\*[0-9a-f]{4}\*/", sass, re.M))
                print(f"| {src}→{dst} | {dt} | {n} | {sass.count('MUFU')} | {sass.count('CALL')} |")


if __name__ == "__main__":
    main()
