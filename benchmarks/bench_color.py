"""Colour-space conversions on 3840x2160 images: imageform vs OpenCV (and peers for Lab).

Issue 3's targets: sRGB -> Lab float32 at least as fast as OpenCV ``cvtColor`` with the
error within 1e-3 ΔE00 of a float64 reference; Lab -> sRGB, sRGB -> HSV and sRGB -> Y'CbCr
within 1.5x of OpenCV; all at the same thread count. Run from the repository root::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_color.py \\
        --threads 1 --size 1920x1080 --repeat 21 --out benchmarks/results/color-2026-11-28.md

The image is a Kodak photograph (kodim23) tiled to ``--size`` (default 1920x1080; real
colour statistics, not uniform noise); float32 is uint8 / 255. Timings are medians of
``--repeat`` round-robin runs (every method once per round, so load changes on a shared
machine hit all alike); the ratio is the median over rounds of imageform's time over
OpenCV's in the same round, and "speed" its inverse (above 1: imageform is faster).
Kernel against kernel, the same dtypes in and out: float32 -> float32 for the float rows,
uint8 -> uint8 (``dtype="uint8"``, OpenCV's 8-bit layouts) for Lab and HSV from uint8;
Y'CbCr from uint8 gives float32 (imageform has no 8-bit Y'CbCr output), OpenCV uint8.

Accuracy: ΔE00 (colour-science's ``delta_E`` "CIE 2000" as the oracle) between each
method's Lab and the float64 reference (imageform's exact float64 path, which agrees with
colour-science to 1e-9: tests/color/test_convert.py), on a 1-megapixel random subset.
OpenCV's Lab differs from the reference partly by definition (its own matrix and D65 white)
and partly by its float32 / 8-bit approximations; the column shows the total.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import markdown_table  # noqa: E402

KODAK = ROOT.parent / "shared" / "data" / "kodak"


def _image(width: int, height: int) -> np.ndarray:
    from imageform.io import read_image

    src = read_image(KODAK / "kodim23.png")[..., :3]
    reps = (-(-height // src.shape[0]), -(-width // src.shape[1]), 1)
    return np.ascontiguousarray(np.tile(src, reps)[:height, :width])


def _round_robin_times(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, list[float]]:
    for fn in fns.values():  # warm-up (numba compile, caches)
        fn()
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return times


def _round_robin(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, float]:
    return {k: statistics.median(v) for k, v in _round_robin_times(fns, repeat).items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--size", default="1920x1080", help="WxH of the tiled image")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--peers", action="store_true", help="also time scikit-image/colour (slow)")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()

    import colour
    import cv2
    import numba

    from imageform.color import convert

    cv2.setNumThreads(args.threads)
    numba.set_num_threads(args.threads)
    width, height = (int(v) for v in args.size.lower().split("x"))
    load0 = os.getloadavg()
    u8 = _image(width, height)
    f32 = u8.astype(np.float32) / np.float32(255)
    lab32 = convert(f32, "srgb", "lab")
    ref64 = convert(u8.astype(np.float64) / 255.0, "srgb", "lab")  # exact float64 path

    cases = [
        (
            "sRGB -> Lab",
            "float32",
            lambda: convert(f32, "srgb", "lab"),
            lambda: cv2.cvtColor(f32, cv2.COLOR_RGB2Lab),
            1.0,
        ),
        (
            "sRGB -> Lab",
            "uint8",
            lambda: convert(u8, "srgb", "lab", dtype="uint8"),
            lambda: cv2.cvtColor(u8, cv2.COLOR_RGB2Lab),
            None,
        ),
        (
            "Lab -> sRGB",
            "float32",
            lambda: convert(lab32, "lab", "srgb"),
            lambda: cv2.cvtColor(lab32, cv2.COLOR_Lab2RGB),
            1.5,
        ),
        (
            "sRGB -> HSV",
            "float32",
            lambda: convert(f32, "srgb", "hsv"),
            lambda: cv2.cvtColor(f32, cv2.COLOR_RGB2HSV),
            1.5,
        ),
        (
            "sRGB -> HSV",
            "uint8",
            lambda: convert(u8, "srgb", "hsv", dtype="uint8"),
            lambda: cv2.cvtColor(u8, cv2.COLOR_RGB2HSV),
            None,
        ),
        (
            "sRGB -> YCbCr",
            "float32",
            lambda: convert(f32, "srgb", "ycbcr"),
            lambda: cv2.cvtColor(f32, cv2.COLOR_RGB2YCrCb),
            1.5,
        ),
        (
            "sRGB -> YCbCr",
            "uint8",
            lambda: convert(u8, "srgb", "ycbcr"),
            lambda: cv2.cvtColor(u8, cv2.COLOR_RGB2YCrCb),
            None,
        ),
    ]
    fns: dict[str, Callable[[], Any]] = {}
    for name, dt, ours, cv, _ in cases:
        fns[f"{name}|{dt}|ours"] = ours
        fns[f"{name}|{dt}|cv2"] = cv
    times = _round_robin_times(fns, args.repeat)
    t = {k: statistics.median(v) for k, v in times.items()}

    rows = []
    for name, dt, _, _, target in cases:
        o, c = t[f"{name}|{dt}|ours"], t[f"{name}|{dt}|cv2"]
        t_ours, t_cv = times[f"{name}|{dt}|ours"], times[f"{name}|{dt}|cv2"]
        per_round = [a / b for a, b in zip(t_ours, t_cv, strict=True)]
        r = statistics.median(per_round)
        lo, hi = min(per_round), max(per_round)
        verdict = "-" if target is None else ("yes" if r <= target else "NO")
        tgt = "-" if target is None else f"<= {target:g}x"
        rows.append(
            [
                name,
                dt,
                f"{o * 1e3:.1f}",
                f"{c * 1e3:.1f}",
                f"{r:.2f} ({lo:.2f}-{hi:.2f})",
                f"{1 / r:.2f}x",
                tgt,
                verdict,
            ]
        )

    # accuracy in ΔE00 against the float64 reference, 1 Mpx random subset
    rng = np.random.default_rng(0)
    idx = rng.choice(u8.shape[0] * u8.shape[1], 1_000_000, replace=False)
    ref = ref64.reshape(-1, 3)[idx]
    labs = {
        "imageform float32": convert(f32, "srgb", "lab"),
        "imageform uint8 (float32 result)": convert(u8, "srgb", "lab"),
        "OpenCV float32": cv2.cvtColor(f32, cv2.COLOR_RGB2Lab),
        "OpenCV uint8 (decoded: L*100/255, a-128, b-128)": (
            cv2.cvtColor(u8, cv2.COLOR_RGB2Lab).astype(np.float64) - [0, 128, 128]
        )
        * [100 / 255, 1, 1],
    }
    acc_rows = []
    for k, v in labs.items():
        de = colour.delta_E(np.asarray(v, np.float64).reshape(-1, 3)[idx], ref, method="CIE 2000")
        acc_rows.append([k, f"{de.max():.2e}", f"{de.mean():.2e}", f"{np.percentile(de, 99):.2e}"])

    peer_rows = []
    if args.peers:
        import skimage.color as skc

        sk = _round_robin({"sk": lambda: skc.rgb2lab(f32)}, 1)["sk"]
        cs = _round_robin({"cs": lambda: colour.XYZ_to_Lab(colour.sRGB_to_XYZ(f32))}, 1)["cs"]
        o = t["sRGB -> Lab|float32|ours"]
        peer_rows = [
            ["imageform convert", f"{o:.3f}", "1.0x"],
            ["scikit-image rgb2lab", f"{sk:.3f}", f"{sk / o:.1f}x slower"],
            ["colour-science sRGB_to_XYZ + XYZ_to_Lab", f"{cs:.3f}", f"{cs / o:.1f}x slower"],
        ]

    cpu = "unknown CPU"
    with open("/proc/cpuinfo") as f:
        for ln in f:
            if ln.startswith("model name"):
                cpu = ln.split(":", 1)[1].strip()
                break
    head = [
        "# Colour-space conversion benchmarks (issue 3)",
        "",
        f"- machine: {cpu}, {os.cpu_count()} cores (shared), Python {platform.python_version()}",
        f"- NumPy {np.__version__}, numba {numba.__version__}, OpenCV {cv2.__version__}, "
        f"colour-science {colour.__version__}; {args.threads} thread(s) for both numba and OpenCV",
        f"- load average at start / end: {' '.join(f'{v:.2f}' for v in load0)} / "
        f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- image: kodim23 tiled to {width}x{height}; median of {args.repeat} round-robin runs",
        "",
        "## Speed (ms), ratio to OpenCV cvtColor in the same rounds",
        "",
        markdown_table(
            [
                "conversion",
                "input",
                "imageform ms",
                "OpenCV ms",
                "time ratio (min-max)",
                "speed vs OpenCV",
                "target",
                "met",
            ],
            rows,
        ),
        "",
        "imageform's time includes its boundary checks (NaN/inf, 0-255 floats).",
        "",
        "## Accuracy of sRGB -> Lab: ΔE00 against the float64 reference (1 Mpx subset)",
        "",
        markdown_table(["method", "max ΔE00", "mean ΔE00", "p99 ΔE00"], acc_rows),
        "",
    ]
    if peer_rows:
        head += [
            "## sRGB -> Lab float32 against the other peers (one run each, s)",
            "",
            markdown_table(["implementation", "s", "vs imageform"], peer_rows),
            "",
        ]
    text = "\n".join(head)
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
