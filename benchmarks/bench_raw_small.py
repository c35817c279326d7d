"""Small raw files, where a development's fixed cost shows: imageform against LibRaw (rawpy).

Per file, in one process, interleaved rounds (``paired_rounds``: each round the median of 5
calls of each side, after one warm-up call of each; the table gives the medians over the
rounds and the median, least and largest per-round ratio):

- imageform: ``develop(read_raw(path)).to_integer(16)``: the DNG's header, LibRaw's
  ``open_file`` + ``unpack`` (rawpy), the copy of the visible image, the opcodes (a Pixel 7's
  GainMaps and WarpRectilinear), bilinear demosaicing of a Bayer mosaic (none for a linear
  raw), the camera's white balance, the colour matrix, sRGB encoding: uint16 (H, W, 3), turned
  for display.
- LibRaw: ``rawpy.imread(path)`` + ``postprocess(use_camera_wb=True, no_auto_bright=True,
  output_bps=16, gamma=(2.4, 12.92), demosaic_algorithm=LINEAR, adjust_maximum_thr=0)``: the
  same steps at matched settings (no opcodes: LibRaw applies none), uint16 (H, W, 3).

A file rawpy cannot open (a GoPro GPR) has imageform's time only.

The last column: how far apart the two outputs are (they differ by the opcodes imageform
applies and LibRaw does not, and by rounding).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_raw_small.py FOLDER_OR_FILE...
        [--rounds 7]

The files are not in the repository (see ``benchmarks/check_raw_fresh_e.py`` for where the
DNGs of ``benchmarks/results/raw-small-2026-12-01g.md`` came from, and their SHA-256).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table, paired_rounds

RAW_SUFFIXES = (".dng", ".gpr")
SETTINGS = (
    "dict(use_camera_wb=True, no_auto_bright=True, output_bps=16, gamma=(2.4, 12.92), "
    "demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR, adjust_maximum_thr=0.0)"
)


def _files(args: list[str]) -> list[Path]:
    out: list[Path] = []
    for a in args:
        p = Path(a)
        if p.is_dir():
            out += sorted(q for q in p.iterdir() if q.suffix.lower() in RAW_SUFFIXES)
        elif p.is_file():
            out.append(p)
    return out


def _ours(path: Path) -> Any:
    from imageform.io import develop, read_raw

    return develop(read_raw(path)).to_integer(16)


def _theirs(path: Path) -> Any:
    import rawpy

    with rawpy.imread(str(path)) as r:
        return r.postprocess(**eval(SETTINGS, {"rawpy": rawpy}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args()
    import numpy as np
    import rawpy

    rows = []
    for path in _files(a.paths):
        ours = _ours(path)
        try:
            theirs = _theirs(path)
        except Exception as exc:  # rawpy cannot open it
            t = paired_rounds(lambda p=path: _ours(p), lambda: None, a.rounds)[0]
            rows.append([path.name, f"{ours.shape[1]}x{ours.shape[0]} {ours.dtype}",
                         f"{t * 1e3:.2f}", f"({type(exc).__name__})", "", ""])  # fmt: skip
            continue
        same = ours.shape == theirs.shape and ours.dtype == theirs.dtype
        ta, tb, r, lo, hi = paired_rounds(lambda p=path: _ours(p), lambda p=path: _theirs(p),
                                          a.rounds)  # fmt: skip
        d = np.abs(ours.astype(np.int64) - theirs.astype(np.int64)) if same else None
        rows.append(
            [
                path.name,
                f"{ours.shape[1]}x{ours.shape[0]} {ours.dtype}"
                + ("" if same else f" (LibRaw {theirs.shape[1]}x{theirs.shape[0]})"),
                f"{ta * 1e3:.2f}",
                f"{tb * 1e3:.2f}",
                f"{r:.2f} ({lo:.2f}-{hi:.2f})",
                "" if d is None else f"{float(np.median(d)):.0f} / {int(d.max())}",
            ]
        )
    print(header("Small raw files: imageform develop against LibRaw (rawpy)"))
    print(f"rawpy {rawpy.__version__} (LibRaw {rawpy.libraw_version})\n")
    print(
        markdown_table(
            [
                "file",
                "output",
                "imageform ms",
                "LibRaw ms",
                "ratio (min-max)",
                "abs(ours - LibRaw) median / max, 16-bit codes",
            ],
            rows,
        )
    )


if __name__ == "__main__":
    main()
