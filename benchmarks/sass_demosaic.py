"""Static size of the CUDA demosaicing kernels in Hopper machine code (sm_90), without a GPU.

Each kernel of :mod:`imageform._cuda.demosaic_quads` (bilinear and Malvar, float32 and
float64) is compiled to PTX by numba (NVVM: a CUDA toolkit's ``libnvvm``), to machine code by
``ptxas -arch=sm_90 -O3``, and disassembled by ``cuobjdump -sass`` (it needs ``nvdisasm``).
Three builds of each: **one case**, the pattern (RGGB), the method and ``clip=False`` given
to numba as literals, so that the code of the other cases folds away (every instruction a
thread of that call may run: the inner and the edge path); **inner path**, the same with the
edge blocks' window loader replaced by the inner one (what a thread of a block inside the
mosaic runs, less the column mirror of the edge path, which the compiler computes before the
row loop for every thread: the difference to the one-case build's prologue); and the
**whole** kernel as launched (all four patterns and the clipping behind run-time branches).
Per build: registers per thread, SASS instructions, global loads (``LDG``), global stores
(``STG``), shared-memory stores and loads (``STS``/``LDS``); per output pixel: instructions
and the global loads of an inner thread (the inner-path build; the per-pixel kernel's
one-case build, which is its path: its mirror is selects), divided by the pixels a thread
computes (4 for a quad, 1 for the per-pixel kernel). The window of a quad is 16 (24) samples,
of which each pattern's filters read 14 (24).

``--before REV`` measures the per-pixel kernel of an earlier revision instead (its
``imageform/_cuda/demosaic.py`` read with ``git show``; one kernel for both methods, the
method a literal in the one-case build). A static count is not a timing: the next lent GPU
times the kernels (``benchmarks/bench_gpu.py``, its "kernel of copy BW" column).

    PATH=$PATH:/path/to/cuda/bin PYTHONPATH=src:. python benchmarks/sass_demosaic.py
    PYTHONPATH=src:. python benchmarks/sass_demosaic.py --before 0f65d9e
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import subprocess
import sys
import tempfile
import types
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _sass(ptx: str, tmp: Path) -> dict[str, Any]:
    """Compile PTX for sm_90; return the counts of its machine code."""
    ptx_path, cubin = tmp / "k.ptx", tmp / "k.cubin"
    ptx_path.write_text(ptx)
    info = subprocess.run(
        ["ptxas", "-arch=sm_90", "-O3", "-v", str(ptx_path), "-o", str(cubin)],
        capture_output=True,
        text=True,
        check=True,
    ).stderr
    sass = subprocess.run(
        ["cuobjdump", "-sass", str(cubin)], capture_output=True, text=True, check=True
    ).stdout
    lines = re.findall(r"^\s+/\*[0-9a-f]{4}\*/\s+(.*)$", sass, re.M)
    ops = [re.sub(r"^@!?U?P\w+\s+", "", ln).split(" ")[0] for ln in lines]

    def n(prefix: str) -> int:
        return sum(op.split(".")[0] == prefix for op in ops)

    regs = re.search(r"Used (\d+) registers", info)
    return {
        "regs": int(regs.group(1)) if regs else -1,
        "instr": len(lines),
        "LDG": n("LDG"),
        "STG": n("STG"),
        "STS": n("STS"),
        "LDS": n("LDS"),
    }


def _old_module(rev: str) -> Any:
    """Import ``imageform._cuda.demosaic`` as it was at ``rev`` (a module of its own)."""
    src = subprocess.run(
        ["git", "show", f"{rev}:src/imageform/_cuda/demosaic.py"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    path = Path(tempfile.mkdtemp()) / "demosaic_before.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("demosaic_before", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _inner_only(dq: Any) -> Any:
    """Rebuild :mod:`imageform._cuda.demosaic_quads`'s kernels with inner loaders only.

    Returns the real ``_windows`` (put it back and clear ``kernels``'s cache after).
    """
    real = dq._windows

    def windows() -> Any:
        inner6, _, inner4, _ = real()

        def edge6(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
            return inner6(raw, b, y, x)

        def edge4(raw, b, y, x, h, w):  # type: ignore[no-untyped-def]
            return inner4(raw, b, y, x)

        jit = dq.cuda.jit(device=True)
        return inner6, jit(edge6), inner4, jit(edge4)

    dq._windows = windows
    dq.kernels.cache_clear()
    return real


def main() -> None:
    import numba.cuda.dispatcher as d
    from numba import cuda
    from numba import types as T

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default=None, help="a revision with the per-pixel kernel")
    args = ap.parse_args()
    # device functions compile for the current device's compute capability: name one
    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
    cols = [
        "kernel",
        "dtype",
        "build",
        "registers",
        "SASS instructions",
        "LDG",
        "STG",
        "STS / LDS",
        "instructions / output pixel",
        "global loads / output pixel",
    ]
    print("| " + " | ".join(cols) + " |\n|" + "---|" * len(cols))
    with tempfile.TemporaryDirectory() as tmp:
        for method in ("bilinear", "malvar"):
            for dt, nb in (("float32", T.float32), ("float64", T.float64)):
                a3 = T.Array(nb, 3, "C")
                if args.before:
                    k = _old_module(args.before)._kernels()
                    fn = k.py["demosaic32" if dt == "float32" else "demosaic64"]
                    m = 0 if method == "bilinear" else 1
                    out = T.Array(nb, 4, "C")
                    one: tuple[Any, ...] = (a3, T.literal(0), T.literal(0), T.literal(m))
                    one += (T.literal(False), out)
                    whole: tuple[Any, ...] = (a3, T.int64, T.int64, T.int64, T.boolean, out)
                    px, name = 1, "per pixel (both methods)"
                else:
                    from imageform._cuda import demosaic_quads

                    fn = demosaic_quads.kernels().py[f"{method}{dt[-2:]}"]
                    one = (a3, T.literal(0), T.literal(0), T.literal(False), a3)
                    whole = (a3, T.int64, T.int64, T.boolean, a3)
                    px, name = 4, "a 2x2 quad"
                builds = [("one case", fn, one), ("whole", fn, whole)]
                if not args.before:
                    real = _inner_only(demosaic_quads)
                    fn_inner = demosaic_quads.kernels().py[f"{method}{dt[-2:]}"]
                    builds.insert(1, ("inner path", fn_inner, one))
                    demosaic_quads._windows = real
                    demosaic_quads.kernels.cache_clear()
                for build, f, sig in builds:
                    c = _sass(cuda.compile_ptx(f, sig, cc=(9, 0))[0], Path(tmp))
                    # the path of an inner thread: the per-pixel kernel's one case, a quad's
                    # inner path (a thread's loads: the window's samples its filters read)
                    path = build == ("one case" if args.before else "inner path")
                    per_px = f"{c['instr'] / px:.0f}" if build != "whole" else "-"
                    loads = f"{c['LDG'] / px:g}" if path else "-"
                    row = [
                        f"{method} ({name})",
                        dt,
                        build,
                        c["regs"],
                        c["instr"],
                        c["LDG"],
                        c["STG"],
                        f"{c['STS']} / {c['LDS']}",
                        per_px,
                        loads,
                    ]
                    print("| " + " | ".join(str(v) for v in row) + " |", flush=True)


if __name__ == "__main__":
    main()
