"""The simulation report: how long writing it takes against the simulation, how big
report.html is, and how long the page takes to load in headless Chromium.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_report.py [--repeat 5] [--cpu]
        [--src LABEL=SRC ...] [--out FILE]

Each run is a fresh ``python -m imageform simulate -o TMP --force --json`` process on the
built-in scene (1280 x 720), as a user runs it: the report's time (``report_time_s``, what
``write_report`` measured, matplotlib's import included) against the simulation's
(``summary.simulation_time_s``, the simulator's own wall time of the chain). One unmeasured
run first per source tree (numba compiles and caches). ``--src LABEL=SRC`` (repeatable)
measures the source tree SRC on ``PYTHONPATH`` (e.g. an older commit exported with
``git archive``, to measure "before" with the same script); with several, their runs
alternate (before, after, before, after ...) so that a changing load on a shared machine
falls on each alike. Default: this tree's ``src``.

Page load: each run's report.html opened in a new page of one headless Chromium
(``/usr/bin/chromium`` through Playwright, ``executable_path``: no download), the wall time
of ``page.goto(file://..., wait_until="load")`` (the HTML parsed and every image decoded).

``--cpu``: each run also renders the scene and writes the report in one more fresh process
(``imageform.simulate.simulate`` and ``write_report``, as the command calls them) and times
the CPU of each (every thread, ``time.process_time``): on a machine shared with other jobs
the wall times stretch with the load, the CPU times much less.

Columns are medians over the runs.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = Path(os.environ.get("IMAGEFORM_CHROMIUM", "/usr/bin/chromium"))


def _simulate(out: Path, src: Path) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, "-m", "imageform", "simulate", "-o", str(out), "--force", "--json"]
    t0 = time.perf_counter()
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = time.perf_counter() - t0
    data: dict[str, Any] = json.loads(proc.stdout)
    return {
        "sim": float(data["summary"]["simulation_time_s"]),
        "report": float(data["report_time_s"]),
        "process": wall,
        "process_cpu": (ru1.ru_utime + ru1.ru_stime) - (ru0.ru_utime + ru0.ru_stime),
        "html_bytes": (out / "report.html").stat().st_size,
        "page_dir_bytes": sum(p.stat().st_size for p in out.rglob("*") if p.is_file()),
    }


_CPU_SPLIT = """
import json, time
from imageform.simulate import default_scene, simulate
from imageform.report.html import write_report
scene = default_scene()
t0 = time.process_time()
result = simulate(scene, rng=0)
t1 = time.process_time()
write_report(result, {out!r}, force=True)
t2 = time.process_time()
print(json.dumps({{"sim_cpu": t1 - t0, "report_cpu": t2 - t1}}))
"""


def _cpu_split(out: Path, src: Path) -> dict[str, float]:
    """CPU seconds (every thread) of the simulation and of the report in one fresh process.

    The built-in scene as ``imageform simulate`` renders it (seed 0), then the report written
    once, as the command does (imports of imageform and numba outside, matplotlib's inside
    the report's time, as in ``report_time_s``): less sensitive than wall times to other jobs
    on the machine.
    """
    env = dict(os.environ, PYTHONPATH=str(src))
    code = _CPU_SPLIT.format(out=str(out))
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    data: dict[str, float] = json.loads(proc.stdout.strip().splitlines()[-1])
    return data


def _load_times(paths: list[Path]) -> list[float]:
    from playwright.sync_api import sync_playwright

    times = []
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=str(CHROMIUM),
            args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
        )
        try:
            for path in paths:
                page = browser.new_page(viewport={"width": 1280, "height": 900})
                t0 = time.perf_counter()
                page.goto(path.resolve().as_uri(), wait_until="load")
                times.append(time.perf_counter() - t0)
                page.close()
        finally:
            browser.close()
    return times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--src", action="append", default=[], metavar="LABEL=SRC")
    ap.add_argument("--out", type=Path, default=None, help="write the text to this file")
    ap.add_argument(
        "--cpu",
        action="store_true",
        help="also time the simulation's and the report's CPU in a fresh process per run",
    )
    args = ap.parse_args(argv)
    sources = [tuple(s.split("=", 1)) for s in args.src] or [("this tree", str(ROOT / "src"))]

    runs: dict[str, list[dict[str, Any]]] = {label: [] for label, _ in sources}
    loads: dict[str, list[float]] = {}
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        for j, (_, src) in enumerate(sources):
            _simulate(Path(tmp) / f"warmup{j}", Path(src))
        htmls: dict[str, list[Path]] = {label: [] for label, _ in sources}
        for i in range(args.repeat):
            for j, (label, src) in enumerate(sources):
                out = Path(tmp) / f"src{j}-run{i}"
                r = _simulate(out, Path(src))
                if args.cpu:
                    r |= _cpu_split(Path(tmp) / f"cpu{j}-run{i}", Path(src))
                runs[label].append(r)
                htmls[label].append(out / "report.html")
                print(
                    f"{label} run {i}: simulation {r['sim']:.2f} s, report {r['report']:.2f} s, "
                    f"html {r['html_bytes'] / 1e6:.2f} MB",
                    file=sys.stderr,
                )
        if CHROMIUM.is_file():
            loads = {label: _load_times(paths) for label, paths in htmls.items()}

    rows = []
    for label, rs in runs.items():

        def med(key: str, rs: list[dict[str, Any]] = rs) -> float:
            return statistics.median(r[key] for r in rs)

        ratios = [r["report"] / r["sim"] for r in rs]
        cpu_ratios = [r["report_cpu"] / r["sim_cpu"] for r in rs] if args.cpu else []
        rows.append(
            [
                label,
                f"{med('sim'):.2f}",
                f"{med('report'):.2f}",
                f"{statistics.median(ratios) * 100:.0f} % ({min(ratios) * 100:.0f}-"
                f"{max(ratios) * 100:.0f} %)",
                f"{med('process_cpu'):.2f}",
                *(
                    [
                        f"{med('sim_cpu'):.2f}",
                        f"{med('report_cpu'):.2f}",
                        f"{statistics.median(cpu_ratios) * 100:.0f} %",
                    ]
                    if args.cpu
                    else []
                ),
                f"{med('html_bytes') / 1e6:.2f}",
                f"{med('page_dir_bytes') / 1e6:.2f}",
                f"{statistics.median(loads[label]):.2f}" if loads else "n/a (no Chromium)",
            ]
        )
    cols = [
        "code",
        "simulation s",
        "report s",
        "report / simulation (min-max)",
        "process CPU s",
        *(["simulation CPU s", "report CPU s", "report / simulation CPU"] if args.cpu else []),
        "report.html MB",
        "whole folder MB",
        "Chromium load s",
    ]
    table = markdown_table(cols, rows)
    text = (
        header("Simulation report: time, size and page load")
        + f"\nBuilt-in scene 1280x720, `imageform simulate` in a fresh process per run; "
        f"medians of {args.repeat} runs after one unmeasured run.\n"
        f"Load average (1, 5, 15 min) at start {' '.join(f'{v:.2f}' for v in load0)}, at end "
        f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}.\n\n" + table
    )
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
