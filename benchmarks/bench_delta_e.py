"""CIEDE2000 between two 4K Lab images: imageform vs scikit-image vs colour-science.

Issue 3's target: at least 10x faster than both peers, within 1e-6 of the exact formula
(colour-science's float64 NumPy implementation of Sharma et al. 2005 serves as the exact
reference; scikit-image is checked too). Also measures the cost of chroma subsampling in ΔE00
on the Kodak set. Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_delta_e.py \\
        --out benchmarks/results/delta-e-2026-11-22.md

Prints (and with ``--out`` writes) Markdown tables: median seconds over ``--repeat`` runs,
ratios to the peers measured in the same run, max |ΔE| differences.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import markdown_table, median_time  # noqa: E402

KODAK = ROOT.parent / "shared" / "data" / "kodak"


def _header() -> str:
    import colour
    import numba
    import skimage

    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return (
        f"- machine: {cpu}, {os.cpu_count()} cores (shared), Python {platform.python_version()}\n"
        f"- NumPy {np.__version__}, numba {numba.__version__} ({numba.get_num_threads()} threads), "
        f"scikit-image {skimage.__version__}, colour-science {colour.__version__}\n"
        f"- load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}\n"
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n"
    )


def bench_ciede2000(height: int, width: int, repeat: int) -> str:
    import colour
    import numba
    from array_api_compat import numpy as xp
    from skimage.color import deltaE_ciede2000

    from imageform._kernels.delta_e import ciede2000_twin
    from imageform.color import delta_e

    rng = np.random.default_rng(0)
    lab1 = np.stack(
        [
            rng.uniform(0, 100, (height, width)),
            rng.uniform(-100, 100, (height, width)),
            rng.uniform(-100, 100, (height, width)),
        ],
        axis=-1,
    )
    lab2 = lab1 + rng.normal(0.0, 3.0, lab1.shape)

    threads = numba.get_num_threads()

    def one_thread() -> Any:
        numba.set_num_threads(1)
        try:
            return delta_e(lab1, lab2)
        finally:
            numba.set_num_threads(threads)

    runs: dict[str, Callable[[], Any]] = {
        f"imageform delta_e (numba, {threads} threads)": lambda: delta_e(lab1, lab2),
        "imageform delta_e (numba, 1 thread)": one_thread,
        "imageform array twin (NumPy, no numba)": lambda: ciede2000_twin(
            xp, lab1, lab2, 1.0, 1.0, 1.0
        ),
        "scikit-image deltaE_ciede2000": lambda: deltaE_ciede2000(lab1, lab2),
        "colour-science delta_E_CIE2000": lambda: colour.difference.delta_E_CIE2000(lab1, lab2),
    }
    times = {name: median_time(fn, repeat) for name, fn in runs.items()}
    ref = colour.difference.delta_E_CIE2000(lab1, lab2)
    sk = deltaE_ciede2000(lab1, lab2)
    t_sk = times["scikit-image deltaE_ciede2000"]
    t_co = times["colour-science delta_E_CIE2000"]
    rows = []
    for name, fn in runs.items():
        out = np.asarray(fn())
        rows.append(
            [
                name,
                f"{times[name]:.3f}",
                f"{t_sk / times[name]:.1f}x",
                f"{t_co / times[name]:.1f}x",
                f"{float(np.max(np.abs(out - ref))):.1e}",
                f"{float(np.max(np.abs(out - sk))):.1e}",
            ]
        )
    title = (
        f"## CIEDE2000, two {height}x{width} Lab images (float64), median of {repeat} runs\n\n"
        "Lab1: L* U(0, 100), a*, b* U(-100, 100); Lab2 = Lab1 + N(0, 3²) per channel.\n\n"
    )
    return title + markdown_table(
        [
            "implementation",
            "s",
            "vs scikit-image",
            "vs colour-science",
            "max |Δ| vs colour-science",
            "max |Δ| vs scikit-image",
        ],
        rows,
    )


def bench_kodak_subsampling() -> str:
    from PIL import Image

    from imageform.color import subsampling_delta_e

    files = sorted(KODAK.glob("kodim*.png"))
    if not files:
        return f"## Chroma subsampling on Kodak\n\nKodak images not found at {KODAK}.\n"
    configs = [
        ("4:2:2", "left", "bilinear"),
        ("4:2:2", "center", "bilinear"),
        ("4:2:0", "left", "bilinear"),
        ("4:2:0", "center", "bilinear"),
        ("4:2:0", "top_left", "bilinear"),
        ("4:2:0", "center", "nearest"),
    ]
    images = [np.asarray(Image.open(f)) for f in files]
    rows = []
    per_image: list[list[str]] = []
    for scheme, siting, method in configs:
        means, p95s, maxes, over1 = [], [], [], []
        for f, img in zip(files, images, strict=True):
            de = np.asarray(subsampling_delta_e(img, scheme, siting=siting, method=method))
            means.append(float(de.mean()))
            p95s.append(float(np.percentile(de, 95)))
            maxes.append(float(de.max()))
            over1.append(float(np.mean(de > 1.0)))
            if (scheme, siting, method) == ("4:2:0", "center", "bilinear"):
                per_image.append(
                    [f.stem, f"{means[-1]:.3f}", f"{p95s[-1]:.3f}", f"{maxes[-1]:.2f}"]
                )
        rows.append(
            [
                scheme,
                siting,
                method,
                f"{np.mean(means):.3f}",
                f"{min(means):.3f} - {max(means):.3f}",
                f"{np.mean(p95s):.3f}",
                f"{100 * np.mean(over1):.1f} %",
                f"{max(maxes):.2f}",
            ]
        )
    text = (
        f"## The cost of chroma subsampling in ΔE00, Kodak set ({len(files)} images)\n\n"
        "sRGB -> Y'CbCr (BT.601, full range, as JPEG) -> subsample -> upsample -> sRGB, clipped\n"
        "to [0, 1] as a decoder writing RGB does; ΔE00 against the original (CIELAB, D65),\n"
        "float32 (uint8 input). No quantisation or compression: the cost of the chroma\n"
        "resolution alone.\n\n"
    )
    text += markdown_table(
        [
            "scheme",
            "siting",
            "upsampling",
            "mean ΔE00 (set mean)",
            "range of image means",
            "p95 (set mean)",
            "pixels > 1",
            "max",
        ],
        rows,
    )
    text += "\n\nPer image, 4:2:0, centred chroma (JFIF), bilinear:\n\n"
    text += markdown_table(["image", "mean ΔE00", "p95", "max"], per_image)
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="2160x3840", help="HxW of the Lab images (4K UHD)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-kodak", action="store_true", help="skip the Kodak subsampling table")
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    args = ap.parse_args()
    h, w = (int(v) for v in args.size.lower().split("x"))
    parts = ["# ΔE benchmarks (issue 3)\n", _header(), bench_ciede2000(h, w, args.repeat)]
    if not args.no_kodak:
        parts.append(bench_kodak_subsampling())
    text = "\n\n".join(parts) + "\n"
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
