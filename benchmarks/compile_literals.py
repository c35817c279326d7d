"""Which numba kernels compile more than once in a first run, and for which signatures.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/compile_literals.py [--src DIR]
        [--targets ransac_f,ransac_h,...,cli:pose,...]
    OPENBLAS_NUM_THREADS=1 python benchmarks/compile_literals.py --cold ransac_f,ransac_h
        --before DIR [--rounds 3]

Listing (the default): one fresh process, ``NUMBA_CACHE_DIR`` a new empty folder,
``NUMBA_NUM_THREADS=1``, imports the kernel modules and compiles their estimators with an
explicit signature (on import; a deferred one, ``njit(..., lazy=True)``, at once), first-calls
the two-view estimators, then runs the CLI commands ``calibrate``, ``pose --ransac``,
``simulate`` and ``vanishing`` in the same process (on ``bench_first_run.py``'s inputs). numba's
``numba:compile`` events give every compilation (the dispatcher and its argument types) with its
CPU seconds (``time.process_time``, including the kernels compiled inside it, and *self*:
without them); every imageform kernel compiled for more than one signature is listed, each
signature with its seconds, a ``Literal`` one flagged: a call site passing an integer that numba
types as a literal (a count that starts at ``m = 0`` is ``Literal[int](0)``) compiles the called
kernel once more, for that literal.

``--cold``: the cold compile of each named kernel module, before (``--before``, a ``src``
folder of the other version) and after (``--src``), interleaved, ``--rounds`` rounds: each
run a fresh process with a new empty ``NUMBA_CACHE_DIR``, ``NUMBA_NUM_THREADS=1``, CPU seconds
(``time.process_time``) of ``import imageform._kernels.<module>`` and of its deferred kernels'
compilation.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import bench_first_run as bfr  # noqa: E402

DEFAULT_TARGETS = (
    "ransac_f,ransac_h,ransac_e,relative_pose,pnp,checkerboard,call:twoview,"
    "cli:calibrate,cli:pose,cli:simulate,cli:vanishing"
)

# the child: records numba's compile events (bench_first_run's listener), then imports /
# calls / runs each target
_CHILD = (
    bfr.LISTENER
    + r"""
import importlib, json, os, sys, time

work = os.environ["IF_WORK"]


def twoview():
    import numpy as np
    from imageform.geometry import (find_essential_matrix, find_fundamental_matrix,
                                    find_homography, recover_pose)
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (150, 3)) + [0, 0, 6]
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    c, s = np.cos(0.1), np.sin(0.1)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    t = np.array([-0.6, 0.05, 0.1])
    u1 = (X / X[:, 2:]) @ K.T
    Y = X @ R.T + t
    u2 = (Y / Y[:, 2:]) @ K.T
    u1, u2 = u1[:, :2], u2[:, :2] + rng.normal(0, 0.3, (150, 2))
    u2[::7] += rng.uniform(-50, 50, u2[::7].shape)
    find_fundamental_matrix(u1, u2, rng=0)
    find_homography(u1, u2, rng=0)
    E = find_essential_matrix(u1, u2, K, rng=0)
    recover_pose(E.E, u1, u2, K)


for target in sys.argv[1].split(","):
    t0 = time.process_time()
    if target.startswith("cli:"):
        from imageform.cli import main
        with open(os.path.join(work, "cmd.json")) as f:
            argv = json.load(f)[target[4:]]
        cwd = os.getcwd()
        os.chdir(work)
        try:
            code = main(argv)
        finally:
            os.chdir(cwd)
        if code not in (0, 3):  # listed as failed; the other targets still run
            records.append({"target": target, "failed": f"exit {code}"})
            continue
    elif target == "call:twoview":
        twoview()
    else:
        from imageform._kernels.jit import Deferred

        module = importlib.import_module("imageform._kernels." + target)
        for kernel in list(vars(module).values()):  # deferred: compiled at the first call
            if isinstance(kernel, Deferred):
                kernel.compile()
    records.append({"target": target, "s": time.process_time() - t0})
with open(os.environ["IF_OUT"], "w") as f:
    json.dump(records, f)
"""
)

_COLD = r"""
import importlib, sys, time
t0 = time.process_time()
from imageform._kernels.jit import Deferred
module = importlib.import_module("imageform._kernels." + sys.argv[1])
for kernel in list(vars(module).values()):  # deferred: compiled at the first call
    if isinstance(kernel, Deferred):
        kernel.compile()
print(time.process_time() - t0)
"""


def _env(src: Path, cache: Path) -> dict[str, str]:
    """bench_first_run's environment, on one numba thread."""
    return {**bfr._env(src, cache), "NUMBA_NUM_THREADS": "1"}


def _cli_inputs(src: Path, w: Path, targets: str) -> dict[str, list[str]]:
    """The CLI commands' inputs (``bench_first_run.py``'s), made with a numba cache of their own.

    The lab set, DNG, mosaic and correction only when a target needs them, the room walk only
    for ``reconstruct``.
    """
    env = _env(src, w / "inputs-cache")
    (w / "out").mkdir(exist_ok=True)
    if not (w / "cam.toml").exists():
        subprocess.run([sys.executable, "-c", bfr._INPUTS, str(w)], env=env, check=True)

    def im(*args: str) -> None:
        run = [sys.executable, "-m", "imageform", *args]
        subprocess.run(run, env=env, cwd=w, check=True, capture_output=True)

    if not (w / "sim0").exists():
        im("simulate", "-o", str(w / "sim0"))
    lab = ("characterize", "sfr", "develop", "demosaic", "emva", "fit-correction", "harmonize")
    needs_lab = any(f"cli:{c}" in targets.split(",") for c in (*lab, "chart"))
    if needs_lab and not (w / "corr.json").exists():
        im("mosaic", str(bfr.KODAK), "-o", str(w / "mosaic.png"))
        cam = str(w / "sim0" / "camera.toml")
        sim = ["simulate", "-o", str(w / "sim1"), "--camera", cam]
        im(*sim, "--lab", str(w / "lab"), "--raw", str(w / "raw.dng"))
        chart = str(w / "lab" / "colorchecker" / "developed.png")
        im("fit-correction", chart, "-o", str(w / "corr.json"))
    if "cli:reconstruct" in targets.split(",") and not (w / "room").exists():
        subprocess.run([sys.executable, "-c", bfr._ROOM, str(w), str(ROOT)], env=env, check=True)
    return bfr._commands(w)


def listing(src: Path, targets: str, w: Path) -> None:
    """Compile events of one fresh process; the kernels compiled more than once."""
    commands = _cli_inputs(src, w, targets)
    (w / "cmd.json").write_text(json.dumps(commands))
    with tempfile.TemporaryDirectory(prefix="if-literals-") as tmp:
        out = Path(tmp) / "events.json"
        env = {**_env(src, Path(tmp) / "cache"), "IF_OUT": str(out), "IF_WORK": str(w)}
        subprocess.run(
            [sys.executable, "-c", _CHILD, targets], env=env, check=True, stdout=subprocess.DEVNULL
        )
        records = json.loads(out.read_text())
    events = [r for r in records if "kernel" in r]
    print(f"load average {' / '.join(f'{v:.1f}' for v in os.getloadavg())}; imageform from {src}")
    for r in records:
        if "failed" in r:
            print(f"  {r['target']}: FAILED ({r['failed']})")
        elif "target" in r:
            print(f"  {r['target']}: {r['s']:.2f} CPU s")
    total = sum(r["own"] for r in events)
    print(f"{len(events)} compilations, {total:.1f} CPU s compiling (self seconds, summed)")
    theirs = [r for r in events if not r["ours"]]
    print(
        f"  of which numba's own overload implementations: {len(theirs)}, "
        f"{sum(r['own'] for r in theirs):.1f} CPU s (each its own dispatcher: not listed)"
    )
    # one dispatcher: the same Python function compiled for several signatures
    by: dict[str, list[dict[str, Any]]] = {}
    for r in events:
        if r["ours"]:
            by.setdefault(f"{r['kernel']}#{r['id']}", []).append(r)
    dup = {k: v for k, v in by.items() if len(v) > 1}
    if not dup:
        print("no kernel compiled more than once")
    for k, v in sorted(dup.items(), key=lambda kv: -sum(float(r["incl"]) for r in kv[1])):
        lit = any("Literal" in str(r["args"]) for r in v)
        name = k.split("#")[0]
        print(f"{name}: {len(v)} compilations{'  [LITERAL]' if lit else ''}")
        for r in v:
            flag = "LITERAL " if "Literal" in str(r["args"]) else ""
            print(f"    {flag}{float(r['incl']):6.2f} s (self {float(r['own']):5.2f}) {r['args']}")


def cold(src: Path, before: Path, modules: list[str], rounds: int) -> None:
    """Interleaved cold compiles (CPU s of the import), before and after, per module."""
    runs: dict[tuple[str, str], list[float]] = {}
    print(f"load average at the start {' / '.join(f'{v:.1f}' for v in os.getloadavg())}")
    for _ in range(rounds):
        for mod in modules:
            for name, s in (("before", before), ("after", src)):
                with tempfile.TemporaryDirectory(prefix="if-cold-") as tmp:
                    done = subprocess.run(
                        [sys.executable, "-c", _COLD, mod],
                        env=_env(s, Path(tmp) / "cache"),
                        check=True,
                        capture_output=True,
                        text=True,
                    )
                runs.setdefault((mod, name), []).append(float(done.stdout.split()[-1]))
                print(f"  {mod} {name}: {runs[(mod, name)][-1]:.2f}", flush=True)
    print(f"load average at the end {' / '.join(f'{v:.1f}' for v in os.getloadavg())}")
    print("| kernel module | before: runs | before: median | after: runs | after: median | ratio |")
    print("|---|---|---:|---|---:|---:|")
    for mod in modules:
        b, a = runs[(mod, "before")], runs[(mod, "after")]
        mb, ma = statistics.median(b), statistics.median(a)
        print(
            f"| `{mod}` | {', '.join(f'{x:.2f}' for x in b)} | {mb:.2f} | "
            f"{', '.join(f'{x:.2f}' for x in a)} | {ma:.2f} | {ma / mb:.2f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--src", type=Path, default=ROOT / "src")
    ap.add_argument("--targets", default=DEFAULT_TARGETS)
    ap.add_argument("--inputs", type=Path, default=None, help="reuse (or make) inputs here")
    ap.add_argument("--cold", default=None, help="comma-separated kernel modules to time")
    ap.add_argument("--before", type=Path, default=None, help="src folder of the other version")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    if a.cold:
        if a.before is None:
            raise SystemExit("--cold needs --before")
        cold(a.src.resolve(), a.before.resolve(), a.cold.split(","), a.rounds)
        return
    with tempfile.TemporaryDirectory(prefix="if-literal-inputs-") as tmp:
        w = a.inputs.resolve() if a.inputs else Path(tmp)
        w.mkdir(parents=True, exist_ok=True)
        listing(a.src.resolve(), a.targets, w)


if __name__ == "__main__":
    main()
