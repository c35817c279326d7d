"""Memory ceiling of chunked processing of an image larger than memory (imageform chunked).

For each size N, an N x N RGB uint8 tiled TIFF (256-px tiles) is written tile by tile, then a
fresh Python process runs :func:`imageform.batch.process_chunked` on it, writing a tiled TIFF:

- ``convert``: sRGB -> Display P3, one pointwise pass, uint8 output;
- ``white_balance``: grey world, a global reduction pass (float64 sums) then the pointwise pass.

The child warms up on a one-block image (imports, numba compilation, thread pools), then
reports its peak RSS (``resource.getrusage(RUSAGE_SELF).ru_maxrss``) before and after the
run, and a psutil sampler (every 50 ms) confirms the peak. The in-memory path would need the
uint8 image plus several float32 copies (``12 N^2`` bytes each).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_chunked.py --sizes 4096 20000
--out benchmarks/results/chunked-2026-11-22.md`` (needs 2 x 3 N^2 bytes of disk in --dir).

``--layout strip`` writes an uncompressed strip TIFF instead (tifffile's default layout: one
strip per image, unless ``--rows-per-strip``), ``--layout strip-zlib`` zlib strips of
``--rows-per-strip`` rows; ``--src`` runs another checkout's ``src`` (the code before a
change) in the child.
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
MIB = 2**20

_CHILD = textwrap.dedent(
    """
    import json, resource, sys, threading, time, pathlib
    import numpy as np, psutil, tifffile
    from imageform.batch import process_chunked

    src, out, cmd, chunk = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
    opts = {"to": "display_p3"} if cmd == "convert" else {"method": "gray_world"}
    warm = pathlib.Path(out).with_name("warm.tif")
    tifffile.imwrite(warm, np.full((chunk, chunk, 3), 100, np.uint8), tile=(256, 256),
                     photometric="rgb")
    process_chunked(warm, warm.with_name("warm-out.tif"), cmd, opts, chunk=chunk, force=True)
    proc, peak, stop = psutil.Process(), [0], threading.Event()

    def sample():
        while not stop.is_set():
            peak[0] = max(peak[0], proc.memory_info().rss)
            time.sleep(0.05)

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    rss_before = proc.memory_info().rss
    t = threading.Thread(target=sample, daemon=True)
    t.start()
    r = process_chunked(src, out, cmd, opts, chunk=chunk, force=True)
    stop.set()
    t.join()
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"before": before, "rss_before": rss_before, "after": after,
                      "sampled": peak[0], "seconds": r.seconds, "clipped": r.clipped}))
    """
)


def write_strips(path: Path, n: int, rows: int | None, compression: str | None) -> float:
    """An n x n RGB uint8 strip TIFF, written band by band (``rows`` rows per strip; None:
    one strip, uncompressed only)."""
    import tifffile

    band = 256
    xx = np.arange(n)[None, :]

    def bands():
        for r0 in range(0, n, band):
            yy = np.arange(r0, min(n, r0 + band))[:, None]
            t = (xx * 7 + yy * 13) % 61
            yield np.stack(
                [t + 40 + (150 * yy) // n, t + 40 + (150 * xx) // n, t + 90 + 0 * xx], axis=-1
            ).astype(np.uint8)

    t0 = time.perf_counter()
    if rows is None and compression is None:  # one contiguous strip, written band by band
        with tifffile.TiffWriter(path, bigtiff=3 * n * n > 2**32 - 2**26) as tw:
            tw.write(shape=(n, n, 3), dtype=np.uint8, photometric="rgb", rowsperstrip=n)
            fh = tw.filehandle
            for b in bands():
                fh.write(b.tobytes())
    else:
        data = np.concatenate(list(bands()))  # small sizes only: held in memory while writing
        tifffile.imwrite(
            path,
            data,
            photometric="rgb",
            rowsperstrip=rows,
            compression=compression,
            bigtiff=3 * n * n > 2**32 - 2**26,
        )
    return time.perf_counter() - t0


def write_tiled(path: Path, n: int) -> float:
    """An n x n RGB uint8 tiled TIFF, written tile by tile (a colour ramp with texture)."""
    yy, xx = np.mgrid[0:TILE, 0:TILE]
    texture = ((xx * 7 + yy * 13) % 61).astype(np.int32)

    def tiles():
        nt = -(-n // TILE)
        for i in range(nt):
            for j in range(nt):
                r = 40 + (150 * i) // nt
                g = 40 + (150 * j) // nt
                t = np.stack([texture + r, texture + g, texture + 90], axis=-1)
                yield t.astype(np.uint8)

    import tifffile

    t0 = time.perf_counter()
    tifffile.imwrite(
        path,
        tiles(),
        shape=(n, n, 3),
        dtype=np.uint8,
        tile=(TILE, TILE),
        photometric="rgb",
        bigtiff=3 * n * n > 2**32 - 2**26,
    )
    return time.perf_counter() - t0


def run_child(
    src: Path, out: Path, command: str, chunk: int, code: Path | None = None
) -> dict[str, float]:
    import imageform

    env = {**os.environ, "PYTHONPATH": str(code or Path(imageform.__file__).parents[1])}
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, str(src), str(out), command, str(chunk)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode:
        raise RuntimeError(proc.stderr[-2000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4096, 20000])
    ap.add_argument("--chunk", type=int, default=1024)
    ap.add_argument("--commands", nargs="+", default=["convert", "white_balance"])
    ap.add_argument("--dir", type=Path, default=None, help="scratch folder (default: tmp)")
    ap.add_argument("--out", type=Path, default=None, help="write the Markdown table here")
    ap.add_argument(
        "--input", type=Path, default=None, help="an existing N x N tiled TIFF (kept) instead"
    )
    ap.add_argument("--make-input", type=Path, default=None, help="only write --sizes[0] here")
    ap.add_argument("--layout", choices=["tiled", "strip", "strip-zlib"], default="tiled")
    ap.add_argument("--rows-per-strip", type=int, default=None)
    ap.add_argument("--src", type=Path, default=None, help="the src folder the child imports")
    args = ap.parse_args()
    if args.make_input:
        print(f"wrote in {write_tiled(args.make_input, args.sizes[0]):.1f} s")
        return
    if args.input:
        import tifffile

        with tifffile.TiffFile(args.input) as tf:
            args.sizes = [tf.pages[0].shape[0]]
    scratch = Path(tempfile.mkdtemp(prefix="bench-chunked-", dir=args.dir))
    rows = []
    try:
        for n in args.sizes:
            src = args.input or scratch / f"in-{n}.tif"
            if args.input:
                t_write = 0.0
            elif args.layout == "tiled":
                t_write = write_tiled(src, n)
            else:
                zlib = args.layout == "strip-zlib"
                t_write = write_strips(
                    src, n, args.rows_per_strip or (16 if zlib else None), "zlib" if zlib else None
                )
            for command in args.commands:
                out = scratch / f"out-{n}-{command}.tif"
                m = run_child(src, out, command, args.chunk, args.src)
                peak = max(m["after"], m["sampled"])
                rows.append(
                    [
                        f"{n} x {n} {args.layout}",
                        f"{3 * n * n / MIB:.0f}",
                        f"{12 * n * n / MIB:.0f}",
                        command,
                        args.chunk,
                        f"{m['rss_before'] / MIB:.0f}",
                        f"**{peak / MIB:.0f}**",
                        f"{(peak - m['rss_before']) / MIB:.0f}",
                        f"{m['seconds']:.1f}",
                        f"{n * n / 1e6 / m['seconds']:.1f}",
                    ]
                )
                print(rows[-1], f"(input written in {t_write:.1f} s)", flush=True)
                out.unlink()
            if not args.input:
                src.unlink()
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    cols = [
        "image",
        "uint8 MiB",
        "one float32 copy MiB",
        "command",
        "chunk",
        "RSS before MiB",
        "peak RSS MiB",
        "growth MiB",
        "time s",
        "Mpx/s",
    ]
    text = header("Chunked processing of an image larger than memory: memory ceiling")
    text += "\n" + markdown_table(cols, rows)
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
