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

from benchmarks.bench_first_run import _PROFILE, _commands, _env, _inputs  # noqa: E402

_PREFIX = "imageform._kernels."


def record(command: str, inputs: Path, work: Path) -> list[dict[str, Any]]:
    """The compilations of one cold run of ``command`` (bench_first_run's arguments)."""
    args = _commands(inputs)[command]
    args = [a.replace(str(inputs / "out"), str(work / "out")) for a in args]
    (work / "out").mkdir(exist_ok=True)
    cache = work / "cache"
    env = {**_env(ROOT / "src", cache), "IF_PROFILE_OUT": str(work / "rec.json")}
    env["IMAGEFORM_COMPILE_AHEAD"] = "0"
    done = subprocess.run(
        [sys.executable, "-c", _PROFILE, *args], env=env, cwd=work, capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"imageform {command} failed:\n{done.stderr[-2000:]}")
    return list(json.loads((work / "rec.json").read_text()))


def _ours(rec: dict[str, Any]) -> bool:  # a kernel of imageform._kernels
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
            print(f"{'  ' * r['depth']}{r['kernel']}: {r['incl']:.2f} s ({r['own']:.2f} own)")
    if a.check:
        sys.path.insert(0, str(ROOT / "src"))
        from imageform._kernels.ahead import PLANS

        seen = {
            (str(r["module"]).removeprefix(_PREFIX), r["qualname"], r["signature"]) for r in records
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
            entry = f'Entry("{mod}", "{r["qualname"]}", "{r["signature"]}")'
            print(f"    {entry},  # {r['incl']:.2f} s")


if __name__ == "__main__":
    main()
