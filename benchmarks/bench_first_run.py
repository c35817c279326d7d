"""First run against warm run: what numba's compilation costs a user, per command.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_first_run.py [--src DIR | --python EXE]
        [--repeat 3] [--write PATH]

Each command runs as a fresh process (``python -m imageform ...``), as a user runs it:

- ``simulate``: ``imageform simulate -o OUT --force`` (the built-in scene);
- ``pose``: ``imageform pose cam.toml pairs.csv --ransac`` (a Brown-Conrady camera and 200
  synthetic 3-D/2-D correspondences with 10 % outliers);
- ``demosaic``: ``imageform demosaic mosaic.png -o rgb.png`` (Menon, the default; the mosaic is
  ``imageform mosaic`` of Kodak ``kodim01``, 768 x 512).

*cold*: ``NUMBA_CACHE_DIR`` points at a new empty folder, so numba finds no cache (a folder it
names wins over the ``__pycache__`` beside the source, so stale in-tree files do not count);
*warm*: the same command again with the same folder, now filled by the cold run. Each repetition
takes a new folder: cold then warm, ``--repeat`` times; the table gives the medians and
cold/warm ratio. ``--after-warm``: each repetition's new folder is first filled by ``imageform
cache --warm`` (timed, once per repetition for all commands), then each command runs twice:
*first* (the first run after installing and warming) and *warm*. ``--src DIR`` runs the
imageform found in ``DIR`` (default: this checkout's ``src``); ``--python EXE`` runs an
installed imageform with that interpreter instead. Inputs are made once, before timing, with
``IMAGEFORM_DISABLE_NUMBA=1`` (no kernel is compiled).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT.parent / "shared" / "data" / "kodak" / "kodim01.png"

_INPUTS = r"""
import sys
from pathlib import Path
import numpy as np
from imageform.geometry import BrownConrady, Camera
from imageform.geometry.calibration_refine import rodrigues
from imageform.io import write_camera

work = Path(sys.argv[1])
K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
dist = BrownConrady(-0.2, 0.05, 1e-3, -5e-4, 0.0)
write_camera(work / "cam.toml", Camera(K, np.eye(3), np.zeros(3), (640, 480), distortion=dist),
             has_pose=True)
rng = np.random.default_rng(0)
X = rng.uniform(-1, 1, (200, 3)) + [0, 0, 6]
R = rodrigues(np.array([[0.05, -0.15, 0.02]]))[0]
uv = np.asarray(Camera(K, R, [-0.5, 0.1, 0.2], distortion=dist).project(X).uv)
uv[::10] += rng.uniform(-40, 40, uv[::10].shape)
rows = [",".join(repr(float(v)) for v in (*a, *b)) for a, b in zip(X, uv, strict=True)]
(work / "pairs.csv").write_text("X,Y,Z,u,v\n" + "\n".join(rows) + "\n")
"""


def _env(src: Path | None, cache: Path | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    if src is not None:
        env["PYTHONPATH"] = str(src)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    return env


def _run(python: str, args: list[str], env: dict[str, str], cwd: Path) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(
        [python, "-m", "imageform", *args], env=env, cwd=cwd, capture_output=True, text=True
    )
    dt = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"imageform {' '.join(args)} failed:\n{done.stderr[-2000:]}")
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", type=Path, default=ROOT / "src")
    ap.add_argument("--python", default=None, help="an interpreter with imageform installed")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", default="simulate,pose,demosaic")
    ap.add_argument("--write", type=Path, default=None)
    ap.add_argument("--after-warm", action="store_true", help="imageform cache --warm first")
    ap.add_argument("--jobs", type=int, default=2, help="processes for imageform cache --warm")
    a = ap.parse_args()
    python = a.python or sys.executable
    src = None if a.python else a.src.resolve()
    with tempfile.TemporaryDirectory(prefix="if-first-run-") as tmp:
        work = Path(tmp)
        setup = {**_env(src, None), "IMAGEFORM_DISABLE_NUMBA": "1"}
        subprocess.run([python, "-c", _INPUTS, str(work)], env=setup, check=True)
        subprocess.run(
            [python, "-m", "imageform", "mosaic", str(KODAK), "-o", str(work / "mosaic.png")],
            env=setup,
            check=True,
            capture_output=True,
        )
        commands = {
            "simulate": ["simulate", "-o", str(work / "sim"), "--force"],
            "pose": ["pose", str(work / "cam.toml"), str(work / "pairs.csv"), "--ransac"],
            "demosaic": [
                "demosaic",
                str(work / "mosaic.png"),
                "-o",
                str(work / "rgb.png"),
                "--force",
            ],
        }
        rows = []
        names = a.commands.split(",")
        cold: dict[str, list[float]] = {n: [] for n in names}
        warm: dict[str, list[float]] = {n: [] for n in names}
        warming: list[float] = []
        for i in range(a.repeat):
            if a.after_warm:
                cache = work / f"cache-{i}"
                cache.mkdir()
                warming.append(
                    _run(python, ["cache", "--warm", "--jobs", str(a.jobs)], _env(src, cache), work)
                )
                print(f"#{i}: imageform cache --warm {warming[-1]:.2f} s", flush=True)
            for name in names:
                if not a.after_warm:
                    cache = work / f"cache-{name}-{i}"
                    cache.mkdir()
                env = _env(src, cache)
                cold[name].append(_run(python, commands[name], env, work))
                warm[name].append(_run(python, commands[name], env, work))
                print(
                    f"{name} #{i}: first {cold[name][-1]:.2f} s, warm {warm[name][-1]:.2f} s",
                    flush=True,
                )
        for name in names:
            c, w = statistics.median(cold[name]), statistics.median(warm[name])
            rows.append(
                f"| `imageform {name}` | {c:.2f} | {w:.2f} | {c / w:.2f} "
                f"| {min(cold[name]):.2f}-{max(cold[name]):.2f} "
                f"| {min(warm[name]):.2f}-{max(warm[name]):.2f} |"
            )
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    lines = [
        f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average at the end {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}; "
        f"imageform from {a.python or src}; median of {a.repeat}; "
        + (
            f"first run after `imageform cache --warm --jobs {a.jobs}` "
            f"({statistics.median(warming):.1f} s, median)"
            if a.after_warm
            else "first run with an empty cache"
        ),
        "",
        "| command | first (s) | warm (s) | first / warm | first range | warm range |",
        "|---|---:|---:|---:|---:|---:|",
        *rows,
    ]
    text = "\n".join(lines)
    print(text)
    if a.write:
        a.write.parent.mkdir(parents=True, exist_ok=True)
        with a.write.open("a") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
