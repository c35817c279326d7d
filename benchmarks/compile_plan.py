"""Record what a command compiles on a new machine, and propose its compile-ahead plan.

Runs ``imageform COMMAND`` (bench_first_run.py's inputs and arguments) once on an empty numba
cache with a listener on numba's ``numba:compile`` events, and prints the tree of compilations
(inclusive and own CPU seconds, the argument types) and a split for
``imageform._kernels.ahead.PLANS``: the heaviest subtrees (a subtree above a third of the total
is split into its callees; its root then compiles in the command, its callees cached),
shared between the second process (which starts ~1 s late) and the command by longest-first
scheduling. The proposal is a start: the plan kept is the one a benchmark measured best.

    python benchmarks/compile_plan.py reconstruct --inputs /tmp/first-run-inputs
    python benchmarks/compile_plan.py simulate --check   # is PLANS['simulate'] still current?

``--check`` compares the plan in the source with the recording: every entry must be compiled
by the command, with the same signature (exit 1 otherwise).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_first_run import _commands, _env, _inputs  # noqa: E402

_RECORD = r"""
import atexit, json, os, runpy, sys, time
from numba.core import event as ev, types

def compact(t):
    if isinstance(t, types.Array) and t.mutable and t.aligned and t.ndim > 0:
        dims = [":"] * t.ndim
        if t.layout == "C":
            dims[-1] = "::1"
        elif t.layout == "F":
            dims[0] = "::1"
        dtype = "boolean" if str(t.dtype) == "bool" else str(t.dtype)
        return f"{dtype}[{', '.join(dims)}]"
    if isinstance(t, types.UniTuple):
        return f"UniTuple({compact(t.dtype)}, {t.count})"
    if isinstance(t, types.Tuple):
        return "Tuple((" + ", ".join(compact(x) for x in t.types) + ",))"
    if isinstance(t, types.Boolean):
        return "boolean"
    if isinstance(t, (types.Integer, types.Float, types.Complex)):
        return str(t)
    return None

records, stack = [], []

class T(ev.Listener):
    def on_start(self, event):
        stack.append([time.process_time(), 0.0, []])

    def on_end(self, event):
        t0, inner, kids = stack.pop()
        dt = time.process_time() - t0
        fn = event.data["dispatcher"].py_func
        parts = [compact(a) for a in event.data["args"]]
        rec = {"module": fn.__module__, "kernel": fn.__qualname__, "incl": dt, "own": dt - inner,
               "kids": kids, "depth": len(stack), "n": len(records),
               "signature": None if None in parts else "(" + ", ".join(parts) + ")"}
        records.append(rec)
        if stack:
            stack[-1][1] += dt
            stack[-1][2].append(rec["n"])

ev.register("numba:compile", T())
out = os.environ["IF_RECORD_OUT"]
atexit.register(lambda: open(out, "w").write(json.dumps(records)))
sys.argv = ["imageform", *sys.argv[1:]]
runpy.run_module("imageform", run_name="__main__", alter_sys=True)
"""

_PREFIX = "imageform._kernels."


def record(command: str, inputs: Path, work: Path) -> list[dict[str, Any]]:
    """The compilations of one cold run of ``command`` (bench_first_run's arguments)."""
    args = _commands(inputs)[command]
    args = [a.replace(str(inputs / "out"), str(work / "out")) for a in args]
    (work / "out").mkdir(exist_ok=True)
    cache = work / "cache"
    env = {**_env(ROOT / "src", cache), "IF_RECORD_OUT": str(work / "rec.json")}
    env["IMAGEFORM_COMPILE_AHEAD"] = "0"
    done = subprocess.run(
        [sys.executable, "-c", _RECORD, *args], env=env, cwd=work, capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"imageform {command} failed:\n{done.stderr[-2000:]}")
    return list(json.loads((work / "rec.json").read_text()))


def _ours(rec: dict[str, Any]) -> bool:
    return str(rec["module"]).startswith(_PREFIX)


def units(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Subtrees to compile ahead: the tops, a top above a third of the total split into its
    callees (recursively), imageform's kernels with a signature that can be written only."""
    total = sum(r["own"] for r in records)
    todo = [r for r in records if r["depth"] == 0]
    out = []
    while todo:
        r = todo.pop(0)
        if r["incl"] > total / 3 and r["kids"]:
            todo = [records[k] for k in r["kids"]] + todo
            continue
        if _ours(r) and r["signature"] is not None and r["incl"] >= 0.1:
            out.append(r)
    return out


def propose(records: list[dict[str, Any]], startup: float = 1.0) -> tuple[list[Any], list[Any]]:
    """Longest-first onto two processes, the second ``startup`` seconds late."""
    load = [0.0, startup]  # here, child
    bins: tuple[list[Any], list[Any]] = ([], [])
    for u in sorted(units(records), key=lambda r: -r["incl"]):
        k = 0 if load[0] <= load[1] else 1
        bins[k].append(u)
        load[k] += u["incl"]
    return sorted(bins[1], key=lambda r: (r["module"], r["n"])), sorted(
        bins[0], key=lambda r: r["n"]
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("command")
    ap.add_argument("--inputs", type=Path, default=None, help="bench_first_run's inputs")
    ap.add_argument("--check", action="store_true", help="compare with ahead.PLANS")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="if-plan-") as tmp:
        work = Path(tmp)
        inputs = a.inputs or work / "inputs"
        if not (inputs / "corr.json").exists():
            inputs.mkdir(parents=True, exist_ok=True)
            _inputs(sys.executable, ROOT / "src", inputs)
        records = record(a.command, inputs.resolve(), work)
    total = sum(r["own"] for r in records)
    print(f"imageform {a.command}: {len(records)} compilations, {total:.2f} s CPU compiling")
    for r in records:
        if r["depth"] == 0 or r["incl"] >= 0.1:
            name = str(r["module"]).removeprefix(_PREFIX) + "." + r["kernel"]
            print(f"{'  ' * r['depth']}{name}: {r['incl']:.2f} s ({r['own']:.2f} own)")
    if a.check:
        sys.path.insert(0, str(ROOT / "src"))
        from imageform._kernels.ahead import PLANS

        seen = {
            (str(r["module"]).removeprefix(_PREFIX), r["kernel"], r["signature"]) for r in records
        }
        plan = PLANS[a.command]
        stale = [e for e in plan.child + plan.here if tuple(e) not in seen]
        for e in stale:
            print(f"not compiled by the command with this signature: {e}")
        raise SystemExit(1 if stale else 0)
    child, here = propose(records)
    for label, entries in (("child", child), ("here", here)):
        print(f"{label} ({sum(r['incl'] for r in entries):.2f} s):")
        for r in entries:
            mod = str(r["module"]).removeprefix(_PREFIX)
            print(f'    Entry("{mod}", "{r["kernel"]}", "{r["signature"]}"),  # {r["incl"]:.2f} s')


if __name__ == "__main__":
    main()
