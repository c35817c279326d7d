"""Whole-slide images: chunked colour conversion and stain normalisation of a pyramidal tiled
TIFF against the in-memory rate per megapixel, with the peak memory and the levels written.

A synthetic N x N H&E slide is written as scanners and OME-TIFF write them: 256-px JPEG tiles
(YCbCr 4:2:0, quality 90), reduced levels (halvings down to 1024 px or less) as SubIFDs,
0.25 um/px. Its content is a 2048 x 2048 super-tile (four synthetic H&E tiles,
:func:`imageform.analysis.synthetic_he_tile`, a strip of glass, Gaussian grain of 5 codes
for a scan's noise and texture) repeated with flips,
the reduced levels the same super-tile box-reduced, so every level shows the same tissue.

For each operation, two fresh processes in turn:

- **in memory**: a 4096 x 4096 crop of level 0 read into memory, then the operation alone
  timed (median of 3, after a warm-up on a small crop; run before and after the chunked
  run and the two rates averaged, as the machine's load drifts), the float result quantised to uint8
  like the chunked output: ``convert`` sRGB -> Display P3; ``stain_normalize`` Macenko or
  Reinhard applied with the slide's statistics given (the apply step only: a user's one
  call, which also measures the 16 Mpx, is slower, and printed too);
- **chunked**: :func:`imageform.batch.process_chunked` on the whole slide end to end:
  decoding, statistics (a reduced level), the operation, the reduced levels (box means),
  JPEG encoding, all levels written; after a warm-up on a small pyramid, with its peak RSS
  (``ru_maxrss``, confirmed by a psutil sampler every 50 ms) and the RSS before.

Both report wall-clock rates (the target: chunked at least 50 % of in memory) and CPU
seconds per megapixel (user + system of the process: what the load does not change).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_wsi.py --size 40000
--out benchmarks/results/wsi-2026-11-25.md`` (writes the slide to --dir, deleted at the end;
``--keep`` keeps it, ``--input`` reuses one).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

try:  # run as a script or as a module
    from benchmarks._common import header, markdown_table
except ImportError:  # pragma: no cover
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks._common import header, markdown_table

TILE = 256
SUPER = 2048
MIB = 2**20
QUALITY = 90


def _box(a: np.ndarray, f: int) -> np.ndarray:
    h, w, c = a.shape
    return np.round(a.reshape(h // f, f, w // f, f, c).mean(axis=(1, 3))).astype(np.uint8)


def super_tile(seed: int = 0) -> np.ndarray:
    """2048 x 2048: four 1024 x 1024 quadrants, each a 512-px synthetic H&E tile mirrored
    2 x 2 with its own stain intensity, and a glass strip."""
    from imageform.analysis import synthetic_he_tile

    quads = []
    for q in range(4):
        t = synthetic_he_tile((512, 512), rng=seed + q, nuclei=0.15 + 0.05 * q).image
        t = np.round(t * 255).astype(np.uint8)
        row = np.concatenate([t, t[:, ::-1]], axis=1)
        quads.append(np.concatenate([row, row[::-1]], axis=0))
    s = np.concatenate(
        [np.concatenate(quads[:2], axis=1), np.concatenate(quads[2:], axis=1)], axis=0
    )
    s[:, 1900:] = np.array([236, 234, 238], np.uint8)  # glass between tissue sections
    grain = np.random.default_rng(seed).normal(0.0, 5.0, s.shape)  # a scan's noise, texture
    return np.clip(np.round(s + grain), 0, 255).astype(np.uint8)


def write_slide(path: Path, n: int) -> tuple[float, list[int]]:
    """An n x n pyramidal JPEG-tiled RGB TIFF (n a multiple of 256), written tile by tile."""
    import tifffile

    base = super_tile()
    sizes = [n]
    while sizes[-1] > 1024:
        sizes.append(-(-sizes[-1] // 2))
    supers = [base]
    for _ in sizes[1:]:
        supers.append(_box(supers[-1], 2) if supers[-1].shape[0] >= 2 * TILE else supers[-1])

    def tiles(k: int):
        m, s = sizes[k], supers[k]
        p = s.shape[0]
        nt = -(-m // TILE)
        for i in range(nt):
            for j in range(nt):
                r0, c0 = i * TILE, j * TILE
                v = ((r0 // p) * 3 + (c0 // p)) % 4  # each super-tile flipped its own way
                t = s[r0 % p : r0 % p + TILE, c0 % p : c0 % p + TILE]
                yield t[::-1] if v & 1 else (t[:, ::-1] if v & 2 else t)

    kw = {
        "dtype": np.uint8,
        "tile": (TILE, TILE),
        "photometric": "rgb",
        "compression": "jpeg",
        "compressionargs": {"level": QUALITY},
        "resolution": (40000.0, 40000.0),  # 0.25 um/px, a 40x scan
        "resolutionunit": "CENTIMETER",
        "maxworkers": os.cpu_count(),
    }
    t0 = time.perf_counter()
    with tifffile.TiffWriter(path, bigtiff=True) as tw:
        tw.write(tiles(0), shape=(n, n, 3), subifds=len(sizes) - 1, **kw)
        for k, m in enumerate(sizes[1:], 1):
            tw.write(tiles(k), shape=(m, m, 3), subfiletype=1, **kw)
    return time.perf_counter() - t0, sizes


_OPS = textwrap.dedent(
    """
    import numpy as np
    from imageform import analysis
    from imageform.color import convert

    def make_op(name, target):
        if name == "convert":
            return (lambda img, stats: convert(img, "srgb", "display_p3")), None
        method = name.split(":")[1]
        if method == "macenko":
            t = analysis.MacenkoStains.from_json(target)
            return (lambda img, s: analysis.macenko_normalize(img, t, source=s)), \\
                (lambda img: analysis.macenko_stains(img)), \\
                (lambda img: analysis.macenko_normalize(img, t))
        t = analysis.ReinhardStats.from_json(target)
        return (lambda img, s: analysis.reinhard_normalize(img, t, source_stats=s)), \\
            (lambda img: analysis.reinhard_stats(img)), \\
            (lambda img: analysis.reinhard_normalize(img, t))
    """
)

_MEMORY = _OPS + textwrap.dedent(
    """
    import json, sys, time, tifffile, zarr
    src, name, target, crop = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
    store = tifffile.imread(src, aszarr=True, level=0)
    img = np.asarray(zarr.open(store, mode="r")[:crop, :crop])
    store.close()
    made = make_op(name, target)
    stats = made[1](img) if len(made) > 2 else None
    def run(a):
        f = made[0](a, stats)
        return np.round(np.clip(np.asarray(f), 0, 1) * 255).astype(np.uint8)
    run(img[:256, :256])
    import resource
    times, cpu = [], []
    for _ in range(3):
        u0 = resource.getrusage(resource.RUSAGE_SELF)
        t0 = time.perf_counter(); run(img); times.append(time.perf_counter() - t0)
        u1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append(u1.ru_utime + u1.ru_stime - u0.ru_utime - u0.ru_stime)
    full = None
    if len(made) > 2:
        t0 = time.perf_counter(); made[2](img); full = time.perf_counter() - t0
    print(json.dumps({"seconds": sorted(times)[1], "cpu": sorted(cpu)[1], "full": full,
                      "mpx": crop * crop / 1e6}))
    """
)

_CHUNKED = textwrap.dedent(
    """
    import json, os, resource, sys, threading, time, pathlib
    import numpy as np, psutil, tifffile
    from imageform.batch import process_chunked

    src, out, name, target, chunk = sys.argv[1:6]
    chunk = int(chunk)
    if name == "convert":
        cmd, opts = "convert", {"to": "display_p3"}
    else:
        cmd, opts = "stain_normalize", {"target": target, "method": name.split(":")[1]}
    warm = pathlib.Path(out).with_name("warm.tif")
    a = np.full((2 * chunk, 2 * chunk, 3), 200, np.uint8)
    a[::3] = (150, 60, 170)
    with tifffile.TiffWriter(warm) as tw:
        kw = dict(tile=(256, 256), photometric="rgb", compression="jpeg")
        tw.write(a, subifds=1, **kw)
        tw.write(a[::2, ::2], subfiletype=1, **kw)
    process_chunked(warm, warm.with_name("warm-out.tif"), cmd, opts, chunk=chunk, force=True)
    proc, peak, stop = psutil.Process(), [0], threading.Event()

    def sample():
        while not stop.is_set():
            peak[0] = max(peak[0], proc.memory_info().rss)
            time.sleep(0.05)

    rss_before = proc.memory_info().rss
    t = threading.Thread(target=sample, daemon=True)
    t.start()
    u0 = resource.getrusage(resource.RUSAGE_SELF)
    r = process_chunked(src, out, cmd, opts, chunk=chunk, force=True)
    u1 = resource.getrusage(resource.RUSAGE_SELF)
    stop.set()
    t.join()
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"rss_before": rss_before, "after": after, "sampled": peak[0],
                      "seconds": r.seconds, "levels": [list(v) for v in r.levels],
                      "cpu": u1.ru_utime + u1.ru_stime - u0.ru_utime - u0.ru_stime,
                      "compression": r.compression, "stats_from": r.stats_from,
                      "bytes": os.path.getsize(out)}))
    """
)


def _child(code: str, *args: object) -> dict:
    import imageform

    env = {**os.environ, "PYTHONPATH": str(Path(imageform.__file__).parents[1])}
    proc = subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode:
        raise RuntimeError(proc.stderr[-3000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def targets(scratch: Path) -> dict[str, Path]:
    """Macenko and Reinhard targets measured on another synthetic H&E tile."""
    from imageform import analysis

    ref = np.round(analysis.synthetic_he_tile((512, 512), rng=11).image * 255).astype(np.uint8)
    ref = ref.astype(np.float64) * np.array([0.97, 1.0, 0.94])  # another lab's staining
    ref = np.clip(np.round(ref), 0, 255).astype(np.uint8)
    out = {"macenko": scratch / "macenko.json", "reinhard": scratch / "reinhard.json"}
    analysis.macenko_stains(ref).to_json(out["macenko"])
    analysis.reinhard_stats(ref).to_json(out["reinhard"])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=8192)
    ap.add_argument("--chunk", type=int, default=1024)
    ap.add_argument("--crop", type=int, default=4096, help="side of the in-memory image")
    ap.add_argument("--ops", nargs="+", default=["convert", "stain:macenko", "stain:reinhard"])
    ap.add_argument("--dir", type=Path, default=None, help="scratch folder (default: tmp)")
    ap.add_argument("--input", type=Path, default=None, help="an existing slide (kept)")
    ap.add_argument("--keep", action="store_true", help="keep the slide written")
    ap.add_argument("--out", type=Path, default=None, help="write the Markdown table here")
    args = ap.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="bench-wsi-", dir=args.dir))
    rows, notes = [], []
    try:
        tg = targets(scratch)
        if args.input:
            src = args.input
            import tifffile

            with tifffile.TiffFile(src) as tf:
                sizes = [lv.shape[0] for lv in tf.series[0].levels]
            t_write = 0.0
        else:
            src = scratch / f"slide-{args.size}.tif"
            t_write, sizes = write_slide(src, args.size)
        n = sizes[0]
        gib = src.stat().st_size / 2**30
        print(f"slide {n} x {n}, {len(sizes)} levels, {gib:.2f} GiB, written in {t_write:.0f} s")
        for op in args.ops:
            target = tg.get(op.split(":")[-1], tg["macenko"])
            load0 = os.getloadavg()[0]
            mem = _child(_MEMORY, src, op, target, args.crop)  # before and after the
            out = scratch / "out.tif"  # chunked run, averaged: the load drifts
            ch = _child(_CHUNKED, src, out, op, target, args.chunk)
            mem2 = _child(_MEMORY, src, op, target, args.crop)
            load1 = os.getloadavg()[0]
            out.unlink()
            mem_rate = mem["mpx"] * (1 / mem["seconds"] + 1 / mem2["seconds"]) / 2
            mem_cpu = (mem["cpu"] + mem2["cpu"]) / 2 / mem["mpx"]  # CPU s per Mpx
            ch_rate = n * n / 1e6 / ch["seconds"]
            ch_cpu = ch["cpu"] / (n * n / 1e6)
            peak = max(ch["after"], ch["sampled"])
            name = "convert sRGB -> Display P3" if op == "convert" else f"stain-normalize {op[6:]}"
            rows.append(
                [
                    name,
                    f"{mem_rate:.2f}",
                    f"{ch_rate:.2f}",
                    f"**{ch_rate / mem_rate:.2f}**",
                    f"{mem_cpu:.2f} / {ch_cpu:.2f}",
                    f"{ch['seconds']:.0f}",
                    f"{ch['rss_before'] / MIB:.0f}",
                    f"**{peak / MIB:.0f}**",
                    f"{len(ch['levels'])} ({ch['levels'][0][0]} ... {ch['levels'][-1][0]})",
                    f"{ch['compression']}, {ch['bytes'] / 2**30:.2f} GiB",
                    f"{load0:.1f} / {load1:.1f}",
                ]
            )
            if mem["full"]:
                notes.append(
                    f"- {name}: the one in-memory call that also measures the slide's "
                    f"statistics on the {args.crop}^2 image: {mem['mpx'] / mem['full']:.2f} "
                    f"Mpx/s; chunked statistics from {ch['stats_from']}."
                )
            print(rows[-1], flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(scratch, ignore_errors=True)
        else:
            print(f"kept {scratch}")
    cols = [
        "operation",
        f"in memory Mpx/s ({args.crop}^2)",
        f"chunked Mpx/s ({n}^2)",
        "ratio",
        "CPU s per Mpx, in memory / chunked",
        "chunked s",
        "RSS before MiB",
        "peak RSS MiB",
        "levels written",
        "output",
        "load 1-min before / after",
    ]
    text = header("Whole-slide images: chunked vs in-memory rate, memory, pyramid levels")
    text += f"\nSlide: {n} x {n} RGB, {len(sizes)} levels, JPEG q{QUALITY} tiles of {TILE}, "
    text += f"{gib:.2f} GiB; chunk {args.chunk}.\n\n" + markdown_table(cols, rows)
    if notes:
        text += "\n" + "\n".join(notes) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
