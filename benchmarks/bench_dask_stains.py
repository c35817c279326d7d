"""Stain-vector fits on Dask: time and computations of the whole graph, against in memory.

``macenko_stains`` (Macenko and Vahadane) of a synthetic 1024 x 1024 x 3 slide (float64,
16 chunks of 256 x 256) and of a real H&E slide region (``--slide``, uint8, in 4 x 4
chunks), on Dask (threaded scheduler) and in memory. For the Dask call: its median time,
the ``dask.compute`` calls it makes (each computes the graph from the image), the ones whose
graph holds the tissue mask's ``map_overlap`` (the mask's artefact rules) and their tasks;
the largest difference of the stain vectors and maximum concentrations from the in-memory
fit (relative) and whether the kept-pixel counts agree.

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_dask_stains.py
--slide FILE``. ``--src DIR --json FILE`` measures another source tree (the code before a
change); ``--before FILE`` adds that run's figures as "before" columns.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _setup_path(src: str | None) -> None:
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, src or str(ROOT / "src"))


def _inputs(slide: str | None) -> list[tuple[str, np.ndarray, tuple[int, int, int]]]:
    from imageform import analysis as an

    img, _, _ = an.synthetic_stain_image((1024, 1024), rng=0)
    out = [("synthetic 1024x1024 float64", np.asarray(img, dtype=np.float64), (256, 256, 3))]
    if slide:
        import imageio.v3 as iio

        reg = np.ascontiguousarray(np.asarray(iio.imread(slide))[..., :3])
        h, w = reg.shape[:2]
        name = f"{Path(slide).name} {w}x{h} uint8"
        out.append((name, reg, (-(-h // 4), -(-w // 4), 3)))
    return out


def measure(img: np.ndarray, chunks: tuple[int, int, int], method: str, repeat: int) -> dict:
    import dask.array as da
    from dask.callbacks import Callback

    from imageform import analysis as an

    calls: list[tuple[int, bool]] = []

    class _Count(Callback):  # type: ignore[misc]
        def _start(self, dsk: Any) -> None:
            keys = dict(dsk)
            calls.append((len(keys), any("overlap" in str(k) for k in keys)))

    eager, lazy, ref, got = [], [], None, None
    for _ in range(repeat):
        t = time.perf_counter()
        ref = an.macenko_stains(img, method=method)
        eager.append(time.perf_counter() - t)
        x = da.from_array(img, chunks=chunks)
        calls.clear()
        t = time.perf_counter()
        with _Count():
            got = an.macenko_stains(x, method=method)
        lazy.append(time.perf_counter() - t)
    assert ref is not None and got is not None
    rel = max(
        float(np.max(np.abs(got.stain_matrix - ref.stain_matrix))),
        float(np.max(np.abs(got.max_concentrations / ref.max_concentrations - 1.0))),
    )
    return {
        "eager_s": statistics.median(eager),
        "dask_s": statistics.median(lazy),
        "computes": len(calls),
        "mask_computes": sum(m for _, m in calls),
        "tasks": sum(n for n, _ in calls),
        "max_rel_diff": rel,
        "same_n": got.n_pixels == ref.n_pixels,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--slide", help="a real H&E region (PNG/TIFF)")
    ap.add_argument("--src", help="the src folder to import imageform from")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--before", help="figures of a run before a change (--json of that run)")
    args = ap.parse_args(argv)
    _setup_path(args.src)
    import dask

    from benchmarks._common import header, markdown_table

    dask.config.set(scheduler="threads")
    before = json.loads(Path(args.before).read_text()) if args.before else {}
    results, rows = {}, []
    for name, img, chunks in _inputs(args.slide):
        for method in ("macenko", "vahadane"):
            r = measure(img, chunks, method, args.repeat)
            key = f"{name} | {method}"
            results[key] = r
            print(f"{key}: {r}", file=sys.stderr, flush=True)
            b = before.get(key, {})
            rows.append(
                [
                    name,
                    method,
                    b.get("computes", ""),
                    r["computes"],
                    b.get("mask_computes", ""),
                    r["mask_computes"],
                    b.get("tasks", ""),
                    r["tasks"],
                    f"{b['dask_s']:.2f}" if b else "",
                    f"{r['dask_s']:.2f}",
                    f"{r['eager_s']:.2f}",
                    f"{r['dask_s'] / r['eager_s']:.2f}",
                    f"{b['max_rel_diff']:.0e}" if b else "",
                    f"{r['max_rel_diff']:.0e}",
                    "yes" if r["same_n"] else "NO",
                ]
            )
    print(header("Stain-vector fits on Dask"))
    print(
        f"dask {dask.__version__}; threaded scheduler; 16 chunks; medians of {args.repeat} "
        "runs (Dask and in memory interleaved).\n"
    )
    if args.slide:
        digest = hashlib.sha256(Path(args.slide).read_bytes()).hexdigest()
        print(f"Slide region: `{Path(args.slide).name}`, SHA-256 {digest}.\n")
    cols = [
        "image",
        "method",
        "computes before",
        "computes",
        "with the mask before",
        "with the mask",
        "tasks before",
        "tasks",
        "dask s before",
        "dask s",
        "in memory s",
        "dask / in memory",
        "max rel diff before",
        "max rel diff",
        "same n_pixels",
    ]
    print(markdown_table(cols, rows))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    raise SystemExit(main())
