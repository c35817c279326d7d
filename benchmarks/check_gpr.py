"""GoPro GPR raws (DNG with VC-5 tiles): imageform's VC-5 decoder against GoPro's reference.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_gpr.py \\
        "tuning=FOLDER" "held-out=FOLDER" --gpr-src GPR --gpr-build BUILD \\
        [--repeat 5] [--before OTHER_SRC]

Each FOLDER holds .GPR files (read from /tmp, not committed). ``GPR`` is a checkout of
github.com/gopro/gpr (Apache-2.0 or MIT; c8e7032 on 2026-12-01), ``BUILD`` its CMake build
(``cmake -DCMAKE_BUILD_TYPE=Release GPR && make gpr_tools``: ``-O3 -DNDEBUG``). The files
checked on 2026-12-01, split by repository before anything ran (the held-out files frozen by
SHA-256 in the results file):

- tuning: gopro/gpr c8e7032, ``data/samples/`` (Apache-2.0 or MIT): ``Hero6/GOPR0024.GPR``,
  ``HERO7/GOPR9231.GPR`` (4000 x 3000, RGGB);
- held-out: evanoberholster/imagemeta 22280bb, ``testImages/Hero8.GPR`` (MIT), and, from the
  tuning half's repository but of another camera, gopro/gpr's ``Fusion/GPBK7066.GPR`` and
  ``Fusion/GPFR7066.GPR`` (3104 x 3000, the two lenses of a Fusion). The repository's other
  two samples (HERO9, Hero5) are not in its snapshot.

For each file:

- the reference: GoPro's ``gpr_tools -i F.GPR -o F.RAW`` (the CFA it decodes) and ``-o F.DNG``
  (an uncompressed DNG with the same metadata);
- the CFA: imageform's (``imageform.io._vc5.decoded_tiles``) against the reference's, sample
  for sample (maximum difference and how many differ); ``read_raw`` of the GPR against
  ``read_raw`` of the reference DNG (LibRaw reads that one);
- decode time, the VC-5 tile to the Bayer mosaic: imageform (tile read + decode, after one
  warm-up) against the reference decoder's ``vc5_decoder_process`` in a small C program linked
  with the build's libraries (the same tile in memory, its second decode in the process),
  interleaved, medians of ``--repeat``;
- ``imageform develop`` on the GPR in a subprocess (exit status, what it wrote), and the
  development (bilinear, camera white balance, sRGB) of the GPR against the development of the
  reference DNG: mean and maximum CIEDE2000, 2-pixel border left out; the developed image's
  mean and the median of each channel (not black, colours plausible);
- with ``--before``: ``imageform develop`` with another source tree (``main`` before the
  decoder), exit status and the first words of its one line.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

#: a C harness: decodes a VC-5 file N times with GoPro's reference decoder, times each decode
_HARNESS = r"""
#include <stdio.h>
#include <stdint.h>
#include <stddef.h>
#include <stdbool.h>
#include <stdlib.h>
#include <time.h>
#include "vc5_decoder.h"
static double now(void) {
  struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9;
}
int main(int argc, char **argv) {
  FILE *f = fopen(argv[1], "rb"); fseek(f, 0, SEEK_END); long n = ftell(f);
  fseek(f, 0, SEEK_SET); void *buf = malloc(n); if (fread(buf, 1, n, f) != (size_t)n) return 2;
  fclose(f);
  int runs = atoi(argv[2]);
  for (int r = 0; r < runs; r++) {
    vc5_decoder_parameters p; vc5_decoder_parameters_set_default(&p);
    p.mem_alloc = malloc; p.mem_free = free;
    p.pixel_format = VC5_DECODER_PIXEL_FORMAT_RGGB_14;
    gpr_buffer in = {buf, (size_t)n}; gpr_buffer out = {NULL, 0};
    double t0 = now(); int e = vc5_decoder_process(&p, &in, &out, NULL); double t1 = now();
    if (e) { printf("error %d\n", e); return 1; }
    printf("%.6f\n", t1 - t0); free(out.buffer);
  }
  return 0;
}
"""


def _harness(src: Path, build: Path, work: Path) -> Path:
    """Compile the C harness against the reference decoder's static libraries."""
    lib = src / "source" / "lib"
    c = work / "vc5_bench.c"
    c.write_text(_HARNESS)
    exe = work / "vc5_bench"
    incs = [
        f"-I{lib / d}" for d in ("vc5_decoder", "vc5_common", "common/public", "common/private")
    ]
    libs = [
        str(build / "source/lib/vc5_decoder/libvc5_decoder.a"),
        str(build / "source/lib/vc5_common/libvc5_common.a"),
        str(build / "source/lib/common/libcommon.a"),
    ]
    cmd = ["gcc", "-O3", "-DNDEBUG", "-std=gnu99", *incs, str(c), "-o", str(exe), *libs, "-lm"]
    subprocess.run(cmd, check=True)
    return exe


def _cell(value: Any, width: int = 90) -> str:
    s = str(value).replace("|", "/").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def _lab(a: np.ndarray) -> np.ndarray:
    from imageform.color import decode, linear_srgb_to_xyz, xyz_to_lab

    return np.asarray(xyz_to_lab(linear_srgb_to_xyz(decode(np.asarray(a, np.float64), "srgb"))))


def _develop_cli(path: Path, src: str, work: Path) -> str:
    """``imageform develop`` with the source tree ``src``: exit status and its one line."""
    out = work / f"{path.stem}-{abs(hash(src)) % 10000}.png"
    env = {**os.environ, "PYTHONPATH": src, "OPENBLAS_NUM_THREADS": "1"}
    cp = subprocess.run(
        [sys.executable, "-m", "imageform", "develop", str(path), "-o", str(out)],
        capture_output=True,
        text=True,
        check=False,
        env=env,
    )
    if "Traceback" in cp.stderr:
        return f"exit {cp.returncode}, TRACEBACK"
    lines = [s for s in cp.stderr.splitlines() if s.strip()]
    if cp.returncode == 0:
        return f"exit 0, {out.stat().st_size / 1e6:.1f} MB PNG"
    return f"exit {cp.returncode}, {len(lines)} line(s): {lines[-1][:70] if lines else ''}"


def _check(path: Path, exe: Path, tools: Path, work: Path, repeat: int, before: str | None):
    import tifffile

    from imageform.color import delta_e
    from imageform.io import _vc5, develop, read_raw

    ref_raw, ref_dng, tile = (work / f"{path.stem}.{s}" for s in ("RAW", "DNG", "VC5"))
    for out in (ref_raw, ref_dng):
        subprocess.run([str(tools), "-i", str(path), "-o", str(out)], capture_output=True)
    with tifffile.TiffFile(path) as tf:
        page = tf.pages[0]
        fh = tf.filehandle
        fh.seek(int(page.dataoffsets[0]))
        tile.write_bytes(fh.read(int(page.databytecounts[0])))
        ours = _vc5.decoded_tiles(page, fh)

        def decode() -> None:
            _vc5.decoded_tiles(page, fh)

        decode()
        times, c_times = [], []
        for _ in range(repeat):  # interleaved: ours, then the reference (its second decode)
            t0 = time.perf_counter()
            decode()
            times.append(time.perf_counter() - t0)
            cp = subprocess.run([str(exe), str(tile), "2"], capture_output=True, text=True)
            c_times.append(float(cp.stdout.split()[1]))
    ours_s, c_s = statistics.median(times), statistics.median(c_times)
    ref = np.fromfile(ref_raw, "<u2").reshape(ours.shape)
    diff = np.abs(ours.astype(np.int64) - ref)
    a, b = read_raw(path), read_raw(ref_dng)
    same_read = np.array_equal(a.mosaic, b.mosaic)
    da, db = develop(a).image, develop(b).image
    de = np.asarray(delta_e(_lab(da), _lab(db)))[2:-2, 2:-2]
    med = np.median(np.asarray(da).reshape(-1, 3), axis=0)
    row = [
        path.name,
        f"{path.stat().st_size / 1e6:.2f}",
        f"{ours.shape[1]} x {ours.shape[0]}",
        f"{int(diff.max())} ({int(np.count_nonzero(diff))} differ)",
        "equal" if same_read else "DIFFERENT",
        f"{ours_s:.3f} / {c_s:.3f} ({ours_s / c_s:.2f}x)",
        _develop_cli(path, "src", work),
        f"{float(de.mean()):.4f} / {float(de.max()):.3f}",
        f"{float(np.mean(da)):.3f}; R G B medians {med[0]:.2f} {med[1]:.2f} {med[2]:.2f}",
    ]
    if before is not None:
        row.append(_develop_cli(path, before, work))
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", help="LABEL=FOLDER of .GPR files")
    parser.add_argument("--gpr-src", type=Path, required=True)
    parser.add_argument("--gpr-build", type=Path, required=True)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--before", help="another source tree, for imageform develop before")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    print(header("GoPro GPR raws: imageform's VC-5 decoder against GoPro's reference"))
    columns = [
        "file",
        "MB",
        "size",
        "CFA vs reference: max diff",
        "read_raw vs reference DNG",
        "decode s, ours / reference C",
        "imageform develop",
        "ΔE00 vs reference DNG developed, mean / max",
        "developed mean; channel medians",
    ]
    if args.before:
        columns.append("develop before")
    tools = args.gpr_build / "source/app/gpr_tools/gpr_tools"
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        exe = _harness(args.gpr_src, args.gpr_build, work)
        for spec in args.folders:
            label, _, folder = spec.partition("=")
            files = sorted(p for p in Path(folder).iterdir() if p.suffix.upper() == ".GPR")
            rows = [_check(p, exe, tools, work, args.repeat, args.before) for p in files]
            print(f"## {label}\n")
            print(markdown_table(columns, [[_cell(c) for c in r] for r in rows]))
            print()


if __name__ == "__main__":
    main()
