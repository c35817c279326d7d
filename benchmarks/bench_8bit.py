"""8-bit in, 8-bit out: imageform's uint8 kernels against OpenCV's, kernel against kernel.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_8bit.py [--write PATH]

Inputs: Kodak ``kodim23`` (8-bit sRGB) resized with ``cv2.resize`` (bicubic) to 1 MP
(1224 x 816) and 12 MP (4000 x 3000); the Bayer mosaic is its RGGB sampling (uint8; uint16 =
code x 257). Every call takes uint8 (uint16) and returns uint8 (uint16), same layout:

- demosaic: ``demosaic(raw, "RGGB", "bilinear", keep_dtype=True)`` against
  ``cv2.cvtColor(raw, cv2.COLOR_BayerBG2RGB)`` (OpenCV's ``BayerBG`` is ``RGGB``: checked
  below, the interiors are equal);
- Lab: ``convert(img, "srgb", "lab", dtype="uint8")`` against ``cv2.COLOR_RGB2Lab`` (both
  L* x 255/100, a* + 128, b* + 128);
- HSV: ``convert(img, "srgb", "hsv", dtype="uint8")`` against ``cv2.COLOR_RGB2HSV``
  (H/2 in [0, 180), S, V x 255);
- Lab from 8-bit without the 8-bit rounding: ``srgb8_to_lab(img)`` (uint8 in, float32 out,
  from tables) against OpenCV's 8-bit path ``cv2.COLOR_RGB2Lab`` (the issue's target: at
  least its speed with at most 0.5 CIEDE2000, which no uint8 Lab output can reach: the
  rounding floor below is 0.88).

Each call allocates its result (``alloc``) or writes a preallocated one (``out``:
imageform's ``out=``, OpenCV's ``dst=``). Timing: warm numba; R rounds, in each round the
median of 5 calls of imageform then of OpenCV (interleaved, so both see the same load of
this shared machine); the table gives the medians over the rounds and the ratio
imageform / OpenCV (median, and its range over the rounds). Threads: 1 (numba
``set_num_threads(1)``, ``cv2.setNumThreads(1)``) and the defaults of both.

Accuracy against the float64 reference (``convert`` on float64, exact formulas), over
all 2^24 8-bit colours for Lab and HSV: CIEDE2000 of the decoded 8-bit Lab
(``from_opencv(.., "lab8")``); the rounding floor is the float64 reference itself rounded
to lab8. HSV and demosaicing: the largest code error (hue circular, modulo 180).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._common import header, markdown_table, paired_rounds

DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "kodak"


def _images(cv2: Any) -> dict[str, np.ndarray]:
    bgr = cv2.imread(str(DATA / "kodim23.png"))
    rgb = np.ascontiguousarray(bgr[..., ::-1])
    return {
        "1 MP": np.ascontiguousarray(cv2.resize(rgb, (1224, 816), interpolation=cv2.INTER_CUBIC)),
        "12 MP": np.ascontiguousarray(cv2.resize(rgb, (4000, 3000), interpolation=cv2.INTER_CUBIC)),
    }


def _mosaic(rgb: np.ndarray) -> np.ndarray:
    raw = rgb[..., 1].copy()
    raw[0::2, 0::2] = rgb[0::2, 0::2, 0]
    raw[1::2, 1::2] = rgb[1::2, 1::2, 2]
    return raw


def _cases(cv2: Any, img: np.ndarray) -> list[tuple[str, Callable[[], Any], Callable[[], Any]]]:
    from imageform.color import convert, srgb8_to_lab
    from imageform.sensor import demosaic

    raw = _mosaic(img)
    of = np.empty(img.shape, np.float32)
    raw16 = raw.astype(np.uint16) * np.uint16(257)
    o8 = np.empty(img.shape, np.uint8)
    c8 = np.empty(img.shape, np.uint8)
    bayer, lab, hsv = cv2.COLOR_BayerBG2RGB, cv2.COLOR_RGB2Lab, cv2.COLOR_RGB2HSV
    return [
        (
            "demosaic bilinear, uint8, alloc",
            lambda: demosaic(raw, "RGGB", "bilinear", keep_dtype=True),
            lambda: cv2.cvtColor(raw, bayer),
        ),
        (
            "demosaic bilinear, uint16, alloc",
            lambda: demosaic(raw16, "RGGB", "bilinear", keep_dtype=True),
            lambda: cv2.cvtColor(raw16, bayer),
        ),
        (
            "sRGB->Lab uint8, alloc",
            lambda: convert(img, "srgb", "lab", dtype="uint8"),
            lambda: cv2.cvtColor(img, lab),
        ),
        (
            "sRGB->Lab uint8, out",
            lambda: convert(img, "srgb", "lab", dtype="uint8", out=o8),
            lambda: cv2.cvtColor(img, lab, dst=c8),
        ),
        (
            "sRGB->Lab uint8 -> float32 (srgb8_to_lab), alloc",
            lambda: srgb8_to_lab(img),
            lambda: cv2.cvtColor(img, lab),
        ),
        (
            "sRGB->Lab uint8 -> float32 (srgb8_to_lab), out",
            lambda: srgb8_to_lab(img, out=of),
            lambda: cv2.cvtColor(img, lab, dst=c8),
        ),
        (
            "sRGB->HSV uint8, alloc",
            lambda: convert(img, "srgb", "hsv", dtype="uint8"),
            lambda: cv2.cvtColor(img, hsv),
        ),
        (
            "sRGB->HSV uint8, out",
            lambda: convert(img, "srgb", "hsv", dtype="uint8", out=o8),
            lambda: cv2.cvtColor(img, hsv, dst=c8),
        ),
    ]


def _accuracy(cv2: Any, img1: np.ndarray) -> list[list[object]]:
    from imageform.color import (
        convert,
        delta_e_ciede2000,
        from_opencv,
        srgb8_to_lab,
        to_opencv,
    )
    from imageform.sensor import demosaic

    rows: list[list[object]] = []
    cube = np.arange(1 << 24, dtype=np.uint32)
    stats: dict[str, list[float]] = {k: [] for k in ("if", "cv", "floor", "f32", "tab")}
    hue: dict[str, int] = {"if": 0, "cv": 0}
    n_chunk = 1 << 20
    for lo in range(0, 1 << 24, n_chunk):
        c = cube[lo : lo + n_chunk]
        px = np.stack([(c >> 16) & 255, (c >> 8) & 255, c & 255], axis=-1).astype(np.uint8)
        px = px.reshape(1024, -1, 3)
        ref = convert(px.astype(np.float64) / 255.0, "srgb", "lab")
        for key, lab8 in (
            ("if", convert(px, "srgb", "lab", dtype="uint8")),
            ("cv", cv2.cvtColor(px, cv2.COLOR_RGB2Lab)),
            ("floor", to_opencv(ref, "lab8")),
        ):
            de = delta_e_ciede2000(from_opencv(lab8, "lab8").astype(np.float64), ref)
            stats[key] += [float(de.max()), float(de.sum())]
        de = delta_e_ciede2000(convert(px, "srgb", "lab").astype(np.float64), ref)
        stats["f32"] += [float(de.max()), float(de.sum())]
        de = delta_e_ciede2000(srgb8_to_lab(px).astype(np.float64), ref)
        stats["tab"] += [float(de.max()), float(de.sum())]
        href = to_opencv(convert(px.astype(np.float64) / 255.0, "srgb", "hsv"), "hsv8")
        for key, h8 in (
            ("if", convert(px, "srgb", "hsv", dtype="uint8")),
            ("cv", cv2.cvtColor(px, cv2.COLOR_RGB2HSV)),
        ):
            d = np.abs(h8.astype(np.int32) - href)
            d[..., 0] = np.minimum(d[..., 0], 180 - d[..., 0])
            hue[key] = max(hue[key], int(d.max()))
    n = float(1 << 24)
    for key, what in (
        ("if", "imageform convert(uint8, dtype='uint8')"),
        ("cv", "OpenCV COLOR_RGB2Lab (uint8)"),
        ("floor", "float64 reference rounded to lab8 (the floor)"),
        ("f32", "imageform convert(uint8) -> float32"),
        ("tab", "imageform srgb8_to_lab(uint8) -> float32 (tables)"),
    ):
        mx = max(stats[key][0::2])
        mean = sum(stats[key][1::2]) / n
        rows.append([f"sRGB->Lab: {what}", f"{mx:.3g}", f"{mean:.3g}"])
    rows.append(["sRGB->HSV: imageform, max code error vs float64 rounded", hue["if"], ""])
    rows.append(["sRGB->HSV: OpenCV, max code error vs float64 rounded", hue["cv"], ""])
    raw = _mosaic(img1)
    ours = demosaic(raw, "RGGB", "bilinear", keep_dtype=True).astype(np.float64)
    ref = demosaic(raw.astype(np.float64) / 255.0, "RGGB", "bilinear") * 255.0
    cvd = cv2.cvtColor(raw, cv2.COLOR_BayerBG2RGB)
    same = float((cvd[1:-1, 1:-1] == ours[1:-1, 1:-1]).mean())
    rows.append(
        [
            "demosaic uint8 (1 MP): max abs(ours - 255 ref) / max abs(ours - rint(255 ref))",
            f"{np.abs(ours - ref).max():.3f} / {np.abs(ours - np.rint(ref)).max():.0f}",
            "",
        ]
    )
    rows.append(["demosaic uint8: interior equal to OpenCV BayerBG2RGB (fraction)", same, ""])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", type=Path, help="write the Markdown report here")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    import cv2
    import numba

    default_nb, default_cv = numba.config.NUMBA_NUM_THREADS, cv2.getNumThreads()
    images = _images(cv2)
    out = [header("8-bit in, 8-bit out: imageform against OpenCV")]
    out.append(f"OpenCV {cv2.__version__}, numba {numba.__version__}; ")
    out.append(f"load average at start: {os.getloadavg()[0]:.1f}\n\n")
    rows = []
    for threads in (1, None):
        nb_t, cv_t = (1, 1) if threads == 1 else (default_nb, default_cv)
        numba.set_num_threads(nb_t)
        cv2.setNumThreads(cv_t)
        for size, img in images.items():
            for name, ours, cv in _cases(cv2, img):
                a, b, r, rmin, rmax = paired_rounds(ours, cv, args.rounds)
                rows.append(
                    [
                        name,
                        size,
                        f"{nb_t} / {cv_t}",
                        f"{a * 1e3:.2f}",
                        f"{b * 1e3:.2f}",
                        f"{r:.2f} ({rmin:.2f}-{rmax:.2f})",
                    ]
                )
                print(rows[-1], flush=True)
    out.append("## Speed (ms, uint8/uint16 in and out)\n\n")
    out.append(
        markdown_table(
            [
                "case",
                "size",
                "threads numba / OpenCV",
                "imageform ms",
                "OpenCV ms",
                "ratio imageform/OpenCV (range)",
            ],
            rows,
        )
    )
    out.append(
        f"\nRatios < 1: imageform faster. {args.rounds} rounds, median of 5 calls each; the "
        "ratio column is the median of the per-round ratios (the ms columns are medians over "
        "the rounds, so they need not divide to it on this loaded machine).\n"
    )
    numba.set_num_threads(default_nb)
    cv2.setNumThreads(default_cv)
    acc = _accuracy(cv2, images["1 MP"])
    out.append("\n## Accuracy against the float64 reference (all 2^24 colours)\n\n")
    out.append(markdown_table(["quantity", "max", "mean"], acc))
    text = "".join(out)
    print(text)
    if args.write:
        args.write.write_text(text)


if __name__ == "__main__":
    main()
