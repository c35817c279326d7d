"""Raw files of public repositories nobody here had used: imageform against LibRaw (rawpy).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_raw_fresh.py \\
        "tuning=FOLDER" "held-out=FOLDER" [--repeat 5]

Each FOLDER holds raw files (read from /tmp, not committed). The files checked on 2026-11-30,
split by repository before anything ran (the held-out half frozen by SHA-256, in the results
file), came from:

- tuning: imageio/test_images f676c96 (``Blackmagic.dng``: a Blackmagic Pocket Cinema Camera
  4K CinemaDNG frame, 12-bit lossless JPEG; ``Nikon_uncompressed.nef``: a Nikon Coolscan IV
  film scan, RGB); evanoberholster/imagemeta 22280bb, testImages/ (MIT: ``CRW.CRW`` a Canon
  CRW, ``Hero8.GPR`` a GoPro HERO8 GPR (DNG, VC-5 compressed), ``NEF.exif``, ``ARW.exif``,
  ``CR2.exif`` raws cut after their metadata); apache/tika 2b70202, test-documents/ (Apache
  2.0: testARW, testCR2, testDNG, testDNG_bigtiff, testNEF, testPEF, headers of 1.7-2.1 kB);
  serptools/testdata d556886 (test.arw/.cr2/.cr3/.dng, stubs of 25-38 bytes).
- held-out: cfpgomes/emubayer ffa58e4 (MIT: ``test.dng``, a 1024 x 1024 16-bit DNG the tool
  writes from a PNG); KDE/kimageformats 320ded4 (autotests/read/raw/
  ``RAW_KODAK_C330_FORMAT_NONE_YRGB.raw``, a Kodak EasyShare C330); mindeng/nom-exif 383d0f6
  (``canon-r6.cr3``, 336 kB); Sjerd/php_bug_mime_content_type_nef_recognized_as_tif b27e460
  (``test.NEF``, 59 kB); sindresorhus/file-type 2c54d06, fixture/ (MIT: a Leica M10 DNG and a
  Sony ZV-E10 ARW cut at 100 kB, a CR3 at 128 kB, NEF/ORF/RAF/RW2 magic numbers of 128 bytes).

For each file: ``imageform develop`` in a subprocess (exit status; a refusal must be one line,
never a traceback), what ``read_raw`` gives against rawpy (mosaic shape, CFA pattern, black
and white levels, orientation; the mosaic equal to LibRaw's ``raw_image_visible``), the
development (bilinear, camera white balance, sRGB) against LibRaw's ``postprocess`` at matched
settings (LINEAR demosaicing, ``use_camera_wb``, no auto-brightening, 16 bits, the sRGB curve,
``adjust_maximum_thr=0``): mean CIEDE2000 (2-pixel border left out) and PSNR of the encoded
values; time: ``read_raw`` against rawpy's ``imread`` + ``raw_image`` copy, ``read_raw`` +
``develop(...).to_integer(16)`` against ``imread`` + ``postprocess``, medians of ``--repeat``
interleaved runs after one warm-up.
"""

from __future__ import annotations

import argparse
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


def _cell(value: Any, width: int = 90) -> str:
    s = str(value).replace("|", "/").replace("[", "(").replace("]", ")").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def _cli(path: Path) -> str:
    """``imageform develop`` in a subprocess: its exit status and the last line it printed."""
    with tempfile.TemporaryDirectory() as tmp:
        cp = subprocess.run(
            [sys.executable, "-m", "imageform", "develop", str(path), "-o", f"{tmp}/x.png"],
            capture_output=True,
            text=True,
            check=False,
        )
    lines = [s for s in cp.stderr.splitlines() if s.strip()]
    if "Traceback" in cp.stderr:
        return f"exit {cp.returncode}, TRACEBACK"
    if cp.returncode == 0:
        return "exit 0"
    return f"exit {cp.returncode}, {len(lines)} line(s)"


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


def _check(path: Path, repeat: int) -> list[str]:
    import rawpy

    from imageform.color import delta_e
    from imageform.io import develop, read_raw

    settings: dict[str, Any] = {
        "use_camera_wb": True,
        "no_auto_bright": True,
        "output_bps": 16,
        "gamma": (2.4, 12.92),
        "demosaic_algorithm": rawpy.DemosaicAlgorithm.LINEAR,
        "adjust_maximum_thr": 0.0,
    }
    row = [path.name, f"{path.stat().st_size / 1e6:.2f}", _cli(path)]
    try:
        raw = read_raw(path)
    except Exception as exc:
        why = str(exc).splitlines()[0].replace(str(path.parent) + "/", "")
        return [*row, f"{type(exc).__name__}: {why}", "", "", "", "", "", ""]
    try:
        with rawpy.imread(str(path)) as r:
            vis = np.array(r.raw_image_visible, copy=True)
            theirs_black = np.asarray(r.black_level_per_channel[:3], float)
            layout = (
                f"{r.sizes.width}x{r.sizes.height} of {r.sizes.raw_width}x"
                f"{r.sizes.raw_height}, flip {r.sizes.flip}, white {r.white_level}, "
                f"black {theirs_black.tolist()}"
            )
            ref = r.postprocess(**settings) / 65535.0
    except Exception as exc:  # imageform's own reader took over
        vis, ref, layout = None, None, f"LibRaw: {type(exc).__name__}"
    h, w = raw.mosaic.shape[:2]
    ours_layout = (
        f"{w}x{h} {raw.cfa_pattern or raw.metadata.get('raw_type')}, flip {raw.orientation}, "
        f"white {raw.white_level:g}, black {np.unique(raw.black_level).tolist()}"
    )
    if vis is None:
        same = "no LibRaw mosaic"
    else:
        v = vis if vis.ndim == 2 else vis[..., :3]
        equal = v.shape == raw.mosaic.shape and np.array_equal(v, raw.mosaic)
        same = "equal" if equal else "DIFFER"
    dev = develop(raw)
    ours = dev.image
    if ref is None:
        quality = f"median {np.median(ours):.3f}"
    elif ours.shape != ref.shape:
        quality = f"size {ours.shape} vs LibRaw {ref.shape}"
    else:
        de = float(np.mean(delta_e(_lab(ours), _lab(ref))[2:-2, 2:-2]))
        mse = float(np.mean((np.asarray(ours, np.float64) - ref) ** 2))
        psnr = 10 * np.log10(1 / mse) if mse > 0 else float("inf")
        quality = f"{de:.3f} / {psnr:.1f} dB (median {np.median(ours):.3f})"

    def ours_read() -> None:
        read_raw(path)

    def ours_dev() -> None:
        develop(read_raw(path)).to_integer(16)

    def lr_read() -> None:
        with rawpy.imread(str(path)) as r:
            np.array(r.raw_image)

    def lr_dev() -> None:
        with rawpy.imread(str(path)) as r:
            r.postprocess(**settings)

    if vis is None:
        times = "LibRaw cannot decode it"
    else:
        tr, tl, dr, dl = _median_times([ours_read, lr_read, ours_dev, lr_dev], repeat)
        times = f"{tr:.3f} / {tl:.3f} ({tr / tl:.2f}x); {dr:.3f} / {dl:.3f} ({dr / dl:.2f}x)"
    notes = "; ".join(n.removeprefix("note: ") for n in dev.notes)
    return [*row, ours_layout, layout, same, quality, times, _cell(notes, 120), ""][:10]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", help="LABEL=FOLDER of raw files")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    import rawpy

    print(header("Raw files nobody here had used: imageform against LibRaw"))
    print(f"rawpy {rawpy.__version__} (LibRaw {'.'.join(map(str, rawpy.libraw_version))})\n")
    columns = [
        "file",
        "MB",
        "imageform develop",
        "read_raw (or its one-line refusal)",
        "LibRaw",
        "mosaic vs LibRaw",
        "ΔE00 / PSNR vs LibRaw",
        "read; read + develop s, ours / LibRaw",
        "notes",
    ]
    for spec in args.folders:
        label, _, folder = spec.partition("=")
        rows = [
            _check(p, args.repeat)[: len(columns)]
            for p in sorted(Path(folder).iterdir())
            if p.is_file()
        ]
        print(f"## {label}\n")
        print(markdown_table(columns, [[_cell(c) for c in r] for r in rows]))
        print()


if __name__ == "__main__":
    main()
