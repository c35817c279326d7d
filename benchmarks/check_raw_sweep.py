"""A robustness sweep of raw files from public repositories: each file classified.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_raw_sweep.py \\
        "tuning=FOLDER" "held-out=FOLDER" [--repeat 3] [--bright DNG]

Each FOLDER holds raw files (read from /tmp, not committed). The files swept on 2026-11-30,
split by repository before anything ran (the held-out half frozen by SHA-256, in the results
file), came from repositories no earlier sweep here had used:

- tuning: gopro/gpr c8e7032, data/samples/ (Apache-2.0 or MIT): four GoPro GPR
  raws (DNG with VC-5 compression) of a Fusion (front and back) and a HERO6 and HERO7, 3.0 to
  4.2 MB; ErisVentures/js-image 0eec94f, packages/*/test/fixtures/ (MIT): seven raws (d4s.nef,
  d610.nef, nikon.nef, source-google.nef, m50.cr3, olympus-2.orf, olympus-m10.orf) as the Git
  LFS pointers a clone without ``git lfs`` holds (132-133 bytes).
- held-out: AlpineSnowfall/neoTest c955454 (no licence named): three ``.nef`` files that are Neo
  smart-contract executables (NEF3 magic), 103 to 1338 bytes; woss/fork-exif-oxidex 1b1c35a,
  tests/fixtures/raw/sample.dng: a 70-byte TIFF header with Make and Model only.

Whole real raws small enough for a repository snapshot (4 MiB) and in no repository used
before were not found: photostructure/exif-oxide's test-images (iPhone, Pixel, Leica, Nikon,
Canon, Sony, Olympus raws) are gone from its newest snapshot, ISET/isetcam's Pixel 4 DNG is in
a snapshot over the size that can be fetched, and the rest are Git LFS or over 4 MiB.

For each file: ``imageform info``, ``imageform develop`` and ``imageform develop
--auto-bright`` in subprocesses (exit status; a refusal must be one line, never a
traceback); ``read_raw`` + ``develop`` against LibRaw's ``postprocess`` at matched settings
(LINEAR demosaicing, ``use_camera_wb``, no auto-brightening, 16 bits, the sRGB curve), and
with ``auto_bright=True`` against LibRaw's default brightening: mean CIEDE2000 (2-pixel
border left out); time of read + develop against ``imread`` + ``postprocess``, medians of
``--repeat`` interleaved runs. Class: **ok** (mean ΔE00 to LibRaw at most 1 at both
brightnesses), **differs** (above 1), **black** (median of the development under 0.01),
**crash** (a traceback, an exit status other than 0-2, or an exception not imageform's),
**refused** (a one-line refusal, which is quoted), **slow** (read + develop over 3x
LibRaw's time).

``--bright DNG`` (a DNG with a large BaselineExposure: imageio/test_images' Blackmagic
Pocket Cinema Camera 4K frame, +2.65 stops, was used): the share of pixels with a channel at
white with ``--baseline-exposure`` clipped and with ``--highlight-rolloff``, and the mean
CIEDE2000 between the two over the pixels whose linear values both keep under the knee.
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


def _cell(value: Any, width: int = 110) -> str:
    s = str(value).replace("|", "/").replace("[", "(").replace("]", ")").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def _cli(args: list[str]) -> tuple[str, str]:
    """Run ``imageform ARGS`` in a subprocess: a short status and its last stderr line."""
    with tempfile.TemporaryDirectory() as tmp:
        args = [a.replace("{tmp}", tmp) for a in args]
        cp = subprocess.run(
            [sys.executable, "-m", "imageform", *args], capture_output=True, text=True, check=False
        )
    lines = [s for s in cp.stderr.splitlines() if s.strip()]
    if "Traceback" in cp.stderr or cp.returncode not in (0, 1, 2):
        return f"exit {cp.returncode}, TRACEBACK" if "Traceback" in cp.stderr else (
            f"exit {cp.returncode}"
        ), lines[-1] if lines else ""
    errors = [s for s in lines if "error:" in s]
    if cp.returncode == 0:
        return "exit 0", ""
    return f"exit {cp.returncode}, {len(errors)} line(s)", errors[-1] if errors else ""


def _lab(a: np.ndarray) -> np.ndarray:
    from imageform.color import decode, linear_srgb_to_xyz, xyz_to_lab

    a = np.asarray(a, np.float64)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    return np.asarray(xyz_to_lab(linear_srgb_to_xyz(decode(a, "srgb"))))


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


def _check(path: Path, repeat: int) -> list[str]:
    import rawpy

    from imageform.color import delta_e
    from imageform.errors import ImageformError
    from imageform.io import develop, read_raw

    info, _ = _cli(["info", str(path)])
    dev_cli, _ = _cli(["develop", str(path), "-o", "{tmp}/x.png"])
    bright_cli, _ = _cli(["develop", str(path), "-o", "{tmp}/x.png", "--auto-bright"])
    row = [path.name, f"{path.stat().st_size / 1e6:.3f}", info, dev_cli, bright_cli]
    crashed = any("TRACEBACK" in s or not s.startswith(("exit 0", "exit 1", "exit 2"))
                  for s in (info, dev_cli, bright_cli))  # fmt: skip
    try:
        raw = read_raw(path)
    except ImageformError as exc:
        why = str(exc).splitlines()[0].replace(str(path.parent) + "/", "")
        cls = "crash" if crashed else "refused"
        return [*row, cls, _cell(why), "", ""]
    except Exception as exc:  # not imageform's: a crash
        return [*row, "crash", _cell(f"{type(exc).__name__}: {exc}"), "", ""]
    settings: dict[str, Any] = {
        "use_camera_wb": True,
        "no_auto_bright": True,
        "output_bps": 16,
        "gamma": (2.4, 12.92),
        "demosaic_algorithm": rawpy.DemosaicAlgorithm.LINEAR,
    }
    ours = develop(raw).image
    ours_b = develop(raw, auto_bright=True).image
    try:
        with rawpy.imread(str(path)) as r:
            ref = r.postprocess(**settings) / 65535.0
            ref_b = r.postprocess(**{**settings, "no_auto_bright": False}) / 65535.0
    except Exception as exc:
        return [*row, "black" if np.median(ours) < 0.01 else "ok (no LibRaw)",
                f"LibRaw: {type(exc).__name__}", "", ""]  # fmt: skip
    des = []
    for a, b in ((ours, ref), (ours_b, ref_b)):
        if a.shape != b.shape:
            des.append(float("inf"))
        else:
            des.append(float(np.mean(delta_e(_lab(a), _lab(b))[2:-2, 2:-2])))
    t_ours, t_lr = _median_times(
        [
            lambda: develop(read_raw(path)).to_integer(16),
            lambda: _libraw_develop(path, settings),
        ],
        repeat,
    )
    ratio = t_ours / t_lr
    if np.median(ours) < 0.01:
        cls = "black"
    elif crashed:
        cls = "crash"
    elif max(des) > 1.0:
        cls = "differs"
    elif ratio > 3.0:
        cls = "slow"
    else:
        cls = "ok"
    return [*row, cls, "", f"{des[0]:.3f} / {des[1]:.3f}",
            f"{t_ours:.3f} / {t_lr:.3f} ({ratio:.2f}x)"]  # fmt: skip


def _libraw_develop(path: Path, settings: dict[str, Any]) -> None:
    import rawpy

    with rawpy.imread(str(path)) as r:
        r.postprocess(**settings)


def _bright(path: Path) -> list[list[str]]:
    """The clipped and rolled-off BaselineExposure developments of one DNG."""
    from imageform.color import delta_e
    from imageform.io import develop, read_raw

    raw = read_raw(path)
    rows = []
    images = {}
    for label, kw in (
        ("develop (no brightening)", {}),
        ("--baseline-exposure (clipped)", {"baseline_exposure": True}),
        (
            "--baseline-exposure --highlight-rolloff",
            {"baseline_exposure": True, "highlight_rolloff": True},
        ),
    ):
        try:
            dev = develop(raw, **kw)
            img = dev.image
        except TypeError as exc:  # a tree without the option
            rows.append([label, "not there", _cell(exc, 60), ""])
            continue
        images[label] = img
        white = float(np.mean(np.any(img >= 65534.5 / 65535, axis=-1)))
        rows.append([label, f"{dev.brightness:.3f}", f"{100 * white:.1f} %",
                     f"{float(np.median(img)):.3f}"])  # fmt: skip
    a = images.get("--baseline-exposure (clipped)")
    b = images.get("--baseline-exposure --highlight-rolloff")
    if a is not None and b is not None:
        from imageform.color import decode

        keep = np.all(decode(a, "srgb") < 0.79, axis=-1)
        de = delta_e(_lab(a), _lab(b))
        rows.append(
            [
                "the two brightened, ΔE00 where both stay under the knee "
                f"({100 * float(np.mean(keep)):.1f} % of the pixels)",
                "",
                f"mean {float(np.mean(de[keep])):.4f}",
                f"everywhere {float(np.mean(de)):.2f}",
            ]
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="*", help="LABEL=FOLDER of raw files")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--bright", type=Path, default=None, help="a DNG with BaselineExposure")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    import rawpy

    print(header("A sweep of raw files from public repositories: imageform against LibRaw"))
    print(f"rawpy {rawpy.__version__} (LibRaw {'.'.join(map(str, rawpy.libraw_version))})\n")
    columns = [
        "file",
        "MB",
        "imageform info",
        "imageform develop",
        "develop --auto-bright",
        "class",
        "refusal (read_raw)",
        "ΔE00 to LibRaw, matched / auto-bright",
        "read + develop s, ours / LibRaw",
    ]
    for spec in args.folders:
        label, _, folder = spec.partition("=")
        rows = [_check(p, args.repeat) for p in sorted(Path(folder).iterdir()) if p.is_file()]
        counts: dict[str, int] = {}
        for r in rows:
            counts[r[5]] = counts.get(r[5], 0) + 1
        print(f"## {label}\n")
        print(", ".join(f"{k}: {v}" for k, v in sorted(counts.items())) + "\n")
        print(markdown_table(columns, [[_cell(c) for c in r] for r in rows]))
        print()
    if args.bright is not None:
        print(f"## BaselineExposure: {args.bright.name}\n")
        cols = ["development", "brightness", "pixels with a channel at white", "median"]
        print(markdown_table(cols, _bright(args.bright)))
        print()


if __name__ == "__main__":
    main()
