"""Fresh DNGs of public repositories nobody here had used: imageform against LibRaw (rawpy).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_raw_fresh_e.py \\
        "tuning=FOLDER" "held-out=FOLDER" [--repeat 5] [--gpr FILE.GPR]

Each FOLDER holds raw files (read from /tmp, not committed). The files checked on 2026-12-01,
split by repository before imageform ran on any (the held-out half frozen by SHA-256, in the
results file), came from:

- tuning: bpatrik/pigallery2 cd42146 (MIT), src/backend/model/diagnostics/image_formats/
  ``test.dng``: a Google Pixel 7 DNG, 510 x 382, lossless JPEG, 14-bit levels (black 1024),
  Orientation 5 (transposed); Autoenhance-ai/adobe-dng-sdk 7ea219d, sample_files/ (Adobe's DNG
  SDK 1.7 examples, the eight under 4 MiB): 200 x 200 LinearRaw images, lossy JPEG of 8 bits,
  whose ProfileGainTableMap 2 is stored as uint8, uint16, float16 and float32, three of an
  ImageSequenceInfo set, and a 1000 x 100 image with HDR and SDR profiles (synthetic test
  images, no camera).
- held-out: rust-skia/rust-skia 259b9cf (MIT; the file is Skia's, BSD-3-Clause),
  skia-safe/tests/images/``sample_1mp.dng``: an LG-H815 (LG G4) DNG, 600 x 338 LinearRaw,
  lossy JPEG (Compression 34892) in a SubIFD.

(The earlier table of this name, ``raw-fresh-2026-11-30g.md``, came from
``benchmarks/check_raw_fresh.py`` on other repositories' files.) The snapshots this session
could fetch hold no file of 4 MiB or more, which leaves out nearly
every full-size camera raw (CR2/CR3, NEF, ARW, RAF, ORF, RW2, PEF were found only above it).

For each file: ``imageform develop`` in a subprocess (exit status; a refusal must be one line,
never a traceback) and, when it fails, the one-line message; the make and model LibRaw reads;
size, orientation (LibRaw's flip), black and white levels, ours against LibRaw's; the
development (bilinear, camera white balance, sRGB) against LibRaw's ``postprocess`` at matched
settings (LINEAR demosaicing, ``use_camera_wb``, no auto-brightening, 16 bits, the sRGB curve,
``adjust_maximum_thr=0``): CIEDE2000 median and 95th percentile (2-pixel border left out;
again without the OpcodeList3 imageform applies and LibRaw does not, when the file has one), the
median of the encoded image (a black image: under 0.02) and its mean G / (R + B) / 2 (a green
image: over 1.5), each for both; time, ``read_raw`` + ``develop(...).to_integer(16)`` against
``imread`` + ``postprocess``, medians of ``--repeat`` interleaved runs after one warm-up.

``--gpr FILE``: the first ``develop`` of a GoPro GPR on an empty kernel cache, then on an
empty cache that ``imageform cache --warm``'s two ``develop`` jobs (its DNG with a GainMap and
its GPR) filled, then once more (all kernels cached): seconds each, in fresh processes.
"""

from __future__ import annotations

import argparse
import dataclasses
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


def _cell(value: Any, width: int = 110) -> str:
    s = str(value).replace("|", "/").replace("[", "(").replace("]", ")").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def _cli(path: Path) -> tuple[str, str]:
    """``imageform develop`` in a subprocess: its status and, when it failed, its last line."""
    with tempfile.TemporaryDirectory() as tmp:
        cp = subprocess.run(
            [sys.executable, "-m", "imageform", "develop", str(path), "-o", f"{tmp}/x.png"],
            capture_output=True,
            text=True,
            check=False,
        )
    lines = [s for s in cp.stderr.splitlines() if s.strip()]
    if "Traceback" in cp.stderr:
        return f"exit {cp.returncode}, TRACEBACK", lines[-1] if lines else ""
    if cp.returncode == 0:
        return "exit 0", ""
    last = lines[-1].replace(str(path.parent) + "/", "") if lines else ""
    return f"exit {cp.returncode}, {len(lines)} line(s)", last


def _median_times(fns: list[Any], repeat: int) -> list[float]:
    for fn in fns:
        fn()
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return [statistics.median(t) for t in times]


def _lab(a: np.ndarray) -> np.ndarray:
    from imageform.color import decode, linear_srgb_to_xyz, xyz_to_lab

    a = np.asarray(a, np.float64)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    return np.asarray(xyz_to_lab(linear_srgb_to_xyz(decode(a, "srgb"))))


def _looks(img: np.ndarray) -> str:
    """The encoded image's median and mean G / ((R + B) / 2): a black or a green image."""
    a = np.asarray(img, np.float64)
    if a.ndim == 2:
        return f"{np.median(a):.3f}, grey"
    m = a.reshape(-1, a.shape[-1]).mean(0)
    return f"{np.median(a):.3f}, G/RB {m[1] / max((m[0] + m[2]) / 2, 1e-9):.2f}"


SETTINGS: dict[str, Any] = {
    "use_camera_wb": True,
    "no_auto_bright": True,
    "output_bps": 16,
    "gamma": (2.4, 12.92),
    "adjust_maximum_thr": 0.0,
}


def _check(path: Path, repeat: int) -> list[str]:
    import rawpy

    from imageform.color import delta_e
    from imageform.io import develop, read_raw

    settings = {**SETTINGS, "demosaic_algorithm": rawpy.DemosaicAlgorithm.LINEAR}
    cli, refusal = _cli(path)
    try:
        with rawpy.imread(str(path)) as r:
            s = r.sizes
            black = np.asarray(r.black_level_per_channel[:3], float)
            theirs = (
                f"{s.width}x{s.height}, flip {s.flip}, black {np.unique(black).tolist()}, "
                f"white {r.white_level}"
            )
            ref = r.postprocess(**settings) / 65535.0
    except Exception as exc:
        theirs, ref = f"LibRaw: {type(exc).__name__}", None
    make = _make(path)
    row = [path.name, make, f"{path.stat().st_size / 1e6:.2f}", cli]
    try:
        raw = read_raw(path)
    except Exception as exc:
        why = str(exc).splitlines()[0].replace(str(path.parent) + "/", "")
        return [*row, "", theirs, "", "", "", "", "refused", _cell(refusal or why)]
    dev = develop(raw)
    ours = dev.image
    h, w = ours.shape[:2]
    mine = (
        f"{w}x{h}, flip {raw.orientation}, black {np.unique(raw.black_level).tolist()}, "
        f"white {raw.white_level:g}"
    )
    looks = _looks(ours) + (f" / {_looks(ref)}" if ref is not None else "")
    if ref is None:
        de, times, status = "LibRaw cannot decode it", "", "ours only"
    elif ours.shape != ref.shape:
        de, times, status = f"size {ours.shape} vs {ref.shape}", "", "DIFFERENT SIZE"
    else:
        d = np.asarray(delta_e(_lab(ours), _lab(ref)))[2:-2, 2:-2]
        med, p95 = float(np.median(d)), float(np.percentile(d, 95))
        de = f"{med:.3f} / {p95:.3f}"
        if raw.metadata.get("opcodes_stage3"):  # LibRaw applies no OpcodeList3: without them
            plain = dataclasses.replace(raw, metadata={**raw.metadata, "opcodes_stage3": ()})
            d = np.asarray(delta_e(_lab(develop(plain).image), _lab(ref)))[2:-2, 2:-2]
            med, p95 = float(np.median(d)), float(np.percentile(d, 95))
            de += f" ({med:.3f} / {p95:.3f} without OpcodeList3, as LibRaw)"

        def ours_dev() -> None:
            develop(read_raw(path)).to_integer(16)

        def lr_dev() -> None:
            with rawpy.imread(str(path)) as r:
                r.postprocess(**settings)

        to, tl = _median_times([ours_dev, lr_dev], repeat)
        times = f"{to:.3f} / {tl:.3f} ({to / tl:.2f}x)"
        status = "ok" if p95 < 1.0 else ("close" if med < 1.0 else "WRONG")
    notes = "; ".join(n.removeprefix("note: ") for n in dev.notes)
    return [*row, mine, theirs, de, looks, times, status, _cell(notes)]


def _make(path: Path) -> str:
    import tifffile

    try:
        with tifffile.TiffFile(path) as tf:
            t = tf.pages[0].tags
            return f"{t.valueof(271, '?')} {t.valueof(272, '?')}".strip()
    except Exception:
        return "?"


def _gpr_warm(gpr: Path) -> list[list[str]]:
    """Seconds of a GPR's first develop: empty cache, after the warm jobs, all cached."""
    py, src = sys.executable, str(Path(__file__).resolve().parents[1] / "src")
    env = {**os.environ, "PYTHONPATH": src}
    warm = (
        "from imageform.cli import _cache\n"
        "jobs = _cache._jobs\n"
        "_cache._jobs = lambda w: [j for j in jobs(w) if j[0] == 'develop']\n"
        "print(_cache.warm_cache(jobs=2))\n"
    )
    rows = []
    with tempfile.TemporaryDirectory() as tmp:

        def run(argv: list[str], cache: str) -> float:
            t0 = time.perf_counter()
            subprocess.run(argv, env={**env, "NUMBA_CACHE_DIR": f"{tmp}/{cache}"},
                           check=True, capture_output=True)  # fmt: skip
            return time.perf_counter() - t0

        def develop(cache: str, k: int) -> list[str]:
            return [py, "-m", "imageform", "develop", str(gpr), "-o", f"{tmp}/{cache}{k}.png"]

        rows.append(["first develop, empty cache", f"{run(develop('cold', 0), 'cold'):.1f}"])
        rows.append(["`cache --warm`'s develop jobs alone", f"{run([py, '-c', warm], 'w'):.1f}"])
        rows.append(["first develop after them", f"{run(develop('w', 1), 'w'):.1f}"])
        rows.append(["develop again (all cached)", f"{run(develop('w', 2), 'w'):.1f}"])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="*", help="LABEL=FOLDER of raw files")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--gpr", type=Path, default=None, help="a GPR for the warm-cache check")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    import rawpy

    print(header("Fresh DNGs nobody here had used: imageform against LibRaw"))
    print(f"rawpy {rawpy.__version__} (LibRaw {'.'.join(map(str, rawpy.libraw_version))})\n")
    columns = [
        "file",
        "make / model",
        "MB",
        "imageform develop",
        "ours: size, flip, black, white",
        "LibRaw",
        "ΔE00 median / p95",
        "median, G/RB: ours / LibRaw",
        "read + develop s, ours / LibRaw",
        "status",
        "notes or refusal",
    ]
    for spec in args.folders:
        label, _, folder = spec.partition("=")
        rows = [_check(p, args.repeat) for p in sorted(Path(folder).iterdir()) if p.is_file()]
        print(f"## {label}\n")
        print(markdown_table(columns, [[_cell(c) for c in r] for r in rows]))
        print()
    if args.gpr is not None:
        print(f"## `cache --warm` and a GPR ({args.gpr.name}), seconds, fresh processes\n")
        print(markdown_table(["run", "s"], _gpr_warm(args.gpr)))
        print()


if __name__ == "__main__":
    main()
