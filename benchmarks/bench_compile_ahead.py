"""First runs with and without the second process that compiles ahead (imageform._kernels.ahead).

For each command with a plan (``ahead.PLANS``), interleaved: a first run on an empty numba
cache with ``IMAGEFORM_COMPILE_AHEAD=1`` (the default) and one with ``=0``, then a warm run of
each (the same cache again); bench_first_run.py's inputs and arguments. Prints the medians
(wall and CPU seconds; CPU includes the second process, which the command waits for) and the
ratio of the first runs.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_compile_ahead.py --repeat 3 --inputs DIR
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks.bench_first_run import _commands, _env, _inputs, _load, _run  # noqa: E402
from imageform._kernels.ahead import PLANS  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", default="all", help="comma-separated, or all (planned)")
    ap.add_argument("--inputs", type=Path, default=None, help="bench_first_run's inputs")
    a = ap.parse_args()
    names = sorted(PLANS) if a.commands == "all" else a.commands.split(",")
    python, src = sys.executable, ROOT / "src"
    load0 = _load()
    runs: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    with tempfile.TemporaryDirectory(prefix="if-ahead-") as tmp:
        work = Path(tmp)
        w = a.inputs.resolve() if a.inputs else work / "inputs"
        if not (w / "corr.json").exists():
            w.mkdir(parents=True, exist_ok=True)
            _inputs(python, src, w)
        commands = _commands(w)
        for i in range(a.repeat):
            for name in names:
                for flag in ("1", "0") if i % 2 == 0 else ("0", "1"):
                    cache = work / f"cache-{name}-{flag}-{i}"
                    cache.mkdir()
                    env = {**_env(src, cache), "IMAGEFORM_COMPILE_AHEAD": flag}
                    first = _run(python, commands[name], env, work)
                    warm = _run(python, commands[name], env, work)
                    runs.setdefault((name, flag, "first"), []).append(first)
                    runs.setdefault((name, flag, "warm"), []).append(warm)
                    shutil.rmtree(cache, ignore_errors=True)
                    print(
                        f"{name} ahead={flag} #{i}: first {first[0]:.2f} s ({first[1]:.2f} CPU),"
                        f" warm {warm[0]:.2f} s ({warm[1]:.2f} CPU) (load {_load()})",
                        flush=True,
                    )

    def med(key: tuple[str, str, str], k: int) -> float:
        return statistics.median(r[k] for r in runs[key])

    lines = [
        f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average at the start {load0}, at the end {_load()}; median of {a.repeat}, "
        "interleaved; first = empty `NUMBA_CACHE_DIR`; CPU = user + system seconds of the "
        "command and its processes",
        "",
        "| command | first, ahead (s) | first, without (s) | ahead / without | first CPU, ahead "
        "| first CPU, without | warm, ahead (s) | warm, without (s) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name in names:
        f1, f0 = med((name, "1", "first"), 0), med((name, "0", "first"), 0)
        lines.append(
            f"| `{name}` | {f1:.2f} | {f0:.2f} | {f1 / f0:.2f} "
            f"| {med((name, '1', 'first'), 1):.2f} | {med((name, '0', 'first'), 1):.2f} "
            f"| {med((name, '1', 'warm'), 0):.2f} | {med((name, '0', 'warm'), 0):.2f} |"
        )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
