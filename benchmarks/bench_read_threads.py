"""``read_image`` of JPEG and WebP files in threads of one process: serial against 2 threads.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_read_threads.py \\
        [--before OLD_SRC] [--rounds 7]

Inputs: the 16 first Kodak images (``/work/shared/data/kodak``, 768 x 512 PNG, the Kodak
Lossless True Color Image Suite) enlarged 4 times (Pillow's bicubic, 3072 x 2048 = 6.3 Mpx, a
camera's size, so that decoding and not the call's overhead is timed) and written once as JPEG
(quality 90) and as WebP (lossy, quality 80) into a temporary folder.

In each round, one fresh process per source tree reads the 16 files of a format once
(warm-up), then times a serial pass (a loop) and a pass through a ``ThreadPoolExecutor`` of 2
workers; the threaded arrays are checked equal to the serial ones. ``--before OLD_SRC`` adds
the same runs with another source tree (``git archive`` of the base commit's ``src``): the two
trees alternate in every round, so that both see the same load of this shared machine. The
table gives the medians over the rounds and the speed-up serial / 2 threads, and, a measure the
machine's load does not hide, the share of the threaded pass's wall time during which two
decodes (Pillow's ``load``: ``ImageFile.load``, WebP's own) were in flight at once: 0 under a
lock held through the decoding.
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

KODAK = Path("/work/shared/data/kodak")

CHILD = r"""
import json, sys, time
from concurrent.futures import ThreadPoolExecutor
import numpy as np
from imageform.io import read_image
files = sys.argv[1:]
for f in files:
    read_image(f)
t0 = time.perf_counter(); serial = [read_image(f) for f in files]; t1 = time.perf_counter()
import threading
from PIL import ImageFile, WebPImagePlugin
spans, depth = [], threading.local()
def timed(original):
    def load(self):  # the outermost load of a thread (WebP's calls ImageFile's)
        depth.n = getattr(depth, "n", 0) + 1
        a = time.perf_counter()
        try:
            return original(self)
        finally:
            depth.n -= 1
            if depth.n == 0:
                spans.append((a, time.perf_counter()))
    return load
for cls in (ImageFile.ImageFile, WebPImagePlugin.WebPImageFile):
    cls.load = timed(cls.__dict__["load"])
with ThreadPoolExecutor(2) as pool:
    t2 = time.perf_counter(); threaded = list(pool.map(read_image, files)); t3 = time.perf_counter()
same = all(np.array_equal(a, b) for a, b in zip(serial, threaded))
edges = sorted([(a, 1) for a, _ in spans] + [(b, -1) for _, b in spans])
both, n, last = 0.0, 0, None
for t, step in edges:
    if n >= 2:
        both += t - last
    n, last = n + step, t
print(json.dumps({"serial": t1 - t0, "threads": t3 - t2, "same": same,
                  "overlap": both / (t3 - t2)}))
"""


def make_files(folder: Path, count: int = 16) -> dict[str, list[str]]:
    """Write the Kodak images as JPEG and WebP into ``folder``; return the paths per format."""
    from PIL import Image

    out: dict[str, list[str]] = {"jpeg": [], "webp": []}
    for png in sorted(KODAK.glob("kodim*.png"))[:count]:
        with Image.open(png) as im:
            rgb = im.convert("RGB").resize((im.width * 4, im.height * 4), Image.Resampling.BICUBIC)
            for fmt, suffix, quality in (("jpeg", ".jpg", 90), ("webp", ".webp", 80)):
                path = folder / f"{png.stem}{suffix}"
                rgb.save(path, quality=quality)
                out[fmt].append(str(path))
    return out


def run_child(src: str, files: list[str]) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=src, OPENBLAS_NUM_THREADS="1")
    done = subprocess.run(
        [sys.executable, "-c", CHILD, *files], capture_output=True, text=True, env=env, check=True
    )
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    from benchmarks._common import header, markdown_table

    ap = argparse.ArgumentParser()
    ap.add_argument("--before", metavar="OLD_SRC", help="another source tree to compare")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    trees = [("this branch", str(Path("src").resolve()))]
    if args.before:
        trees.insert(0, ("before", str(Path(args.before).resolve())))
    with tempfile.TemporaryDirectory() as tmp:
        files = make_files(Path(tmp))
        times: dict[tuple[str, str], dict[str, list[float]]] = {}
        same = True
        for _ in range(args.rounds):
            for fmt, paths in files.items():
                for name, src in trees:
                    r = run_child(src, paths)
                    t = times.setdefault(
                        (fmt, name), {"serial": [], "threads": [], "ratio": [], "overlap": []}
                    )
                    t["overlap"].append(r["overlap"])
                    t["serial"].append(r["serial"])
                    t["threads"].append(r["threads"])
                    t["ratio"].append(r["serial"] / r["threads"])
                    same = same and bool(r["same"])
    load = os.getloadavg()
    print(
        header("read_image in threads: 16 JPEG and 16 WebP files of 6.3 Mpx, serial and 2 threads")
    )
    print(
        "`OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_read_threads.py"
        + (" --before OLD_SRC" if args.before else "")
        + f" --rounds {args.rounds}` (OLD_SRC: the base commit's `src`). Load average at the "
        f"end: {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} (1 / 5 / 15 min) on "
        f"{os.cpu_count()} cores. Threaded arrays equal to the serial ones: "
        f"{'yes' if same else 'NO'}.\n"
    )
    rows = []
    for (fmt, name), t in times.items():
        ratios = t["ratio"]
        rows.append([
            fmt, name, f"{statistics.median(t['serial']) * 1e3:.0f}",
            f"{statistics.median(t['threads']) * 1e3:.0f}",
            f"{statistics.median(ratios):.2f} ({min(ratios):.2f} to {max(ratios):.2f})",
            f"{100 * statistics.median(t['overlap']):.0f} %",
        ])  # fmt: skip
    print(
        markdown_table(
            [
                "format",
                "source",
                "serial ms",
                "2 threads ms",
                "speed-up (range over rounds)",
                "two decodes at once",
            ],
            rows,
        )
    )


if __name__ == "__main__":
    main()
