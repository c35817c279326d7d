"""The simulation report: how long writing it takes against the simulation, how big
report.html is, and how long the page takes to load in headless Chromium.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_report.py [--repeat 5] [--src SRC]
        [--label NAME] [--out FILE]

Each run is a fresh ``python -m imageform simulate -o TMP --force --json`` process on the
built-in scene (1280 x 720), as a user runs it: the report's time (``report_time_s``, what
``write_report`` measured, matplotlib's import included) against the simulation's
(``summary.simulation_time_s``, the simulator's own wall time of the chain). One unmeasured
run first (numba compiles and caches). ``--src`` puts another source tree first on
``PYTHONPATH`` (e.g. an exported older commit, to measure "before" with the same script).

Page load: each run's report.html opened in a new page of one headless Chromium
(``/usr/bin/chromium`` through Playwright, ``executable_path``: no download), the wall time
of ``page.goto(file://..., wait_until="load")`` (the HTML parsed and every image decoded).

Columns are medians over the runs.
"""

from __future__ import annotations

import argparse
import json
import os
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
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    data: dict[str, Any] = json.loads(proc.stdout)
    return {
        "sim": float(data["summary"]["simulation_time_s"]),
        "report": float(data["report_time_s"]),
        "process": wall,
        "html_bytes": (out / "report.html").stat().st_size,
        "page_dir_bytes": sum(p.stat().st_size for p in out.rglob("*") if p.is_file()),
    }


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
    ap.add_argument("--src", type=Path, default=ROOT / "src")
    ap.add_argument("--label", default="this tree")
    ap.add_argument("--out", type=Path, default=None, help="append the table to this file")
    args = ap.parse_args(argv)

    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        _simulate(Path(tmp) / "warmup", args.src)
        htmls = []
        for i in range(args.repeat):
            out = Path(tmp) / f"run{i}"
            runs.append(_simulate(out, args.src))
            htmls.append(out / "report.html")
            r = runs[-1]
            print(
                f"run {i}: simulation {r['sim']:.2f} s, report {r['report']:.2f} s, "
                f"html {r['html_bytes'] / 1e6:.2f} MB",
                file=sys.stderr,
            )
        loads = _load_times(htmls) if CHROMIUM.is_file() else []

    def med(key: str) -> float:
        return statistics.median(r[key] for r in runs)

    ratios = [r["report"] / r["sim"] for r in runs]
    row = [
        args.label,
        f"{med('sim'):.2f}",
        f"{med('report'):.2f}",
        f"{statistics.median(ratios) * 100:.0f} %",
        f"{med('html_bytes') / 1e6:.2f}",
        f"{med('page_dir_bytes') / 1e6:.2f}",
        f"{statistics.median(loads):.2f}" if loads else "n/a (no Chromium)",
    ]
    cols = [
        "code",
        "simulation s",
        "report s",
        "report / simulation",
        "report.html MB",
        "whole folder MB",
        "Chromium load s",
    ]
    table = markdown_table(cols, [row])
    text = (
        header("Simulation report: time, size and page load")
        + f"\nBuilt-in scene 1280x720, `imageform simulate` in a fresh process per run; "
        f"medians of {args.repeat} runs after one unmeasured run.\n\n" + table
    )
    print(text)
    if args.out is not None:
        with args.out.open("a", encoding="utf-8") as f:
            f.write(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
