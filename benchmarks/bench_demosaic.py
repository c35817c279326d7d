"""Demosaicing on the 24 Kodak images: quality (CPSNR) and speed against the peers.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_demosaic.py [--write PATH]

Quality: each Kodak image (8-bit sRGB, read with pillow, /255) is sampled with an RGGB
mosaic and reconstructed; CPSNR = 10 log10(1 / MSE) with the MSE pooled over the three
channels, on the output clipped to [0, 1] (as an 8-bit pipeline would; this is how
../shared/data/README.md's figures were made: colour-demosaicing's bilinear gives
30.25 / 29.21 dB only with clipping), mean over the 24 images, with a 10-pixel border crop
and on the full image. Values are the 8-bit sRGB codes directly, no linearisation.

Speed: the public call on a float32 mosaic in [0, 1] (OpenCV on uint8, which is all its
Bayer conversions take; colour-demosaicing on float64, its native type), median over
repetitions, in ms per megapixel; ratios are to the peer measured in the same run.
Peers (OpenCV 5, colour-demosaicing 0.2.7) are benchmark oracles only.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("IMAGEFORM_DATA", ROOT.parent / "shared" / "data")) / "kodak"
OURS = ("bilinear", "malvar", "hamilton_adams", "menon", "menon_soft")


def load_kodak() -> list[np.ndarray]:
    from PIL import Image

    files = sorted(DATA.glob("kodim*.png"))
    if len(files) != 24:
        raise SystemExit(f"expected 24 Kodak images in {DATA}, found {len(files)}")
    return [np.asarray(Image.open(f).convert("RGB"), dtype=np.float64) / 255 for f in files]


def cpsnr(out: np.ndarray, ref: np.ndarray, crop: int = 0) -> float:
    """CPSNR in dB of ``out`` (clipped to [0, 1]) against ``ref``, MSE pooled over RGB."""
    out = np.clip(out, 0.0, 1.0)
    if crop:
        out, ref = out[crop:-crop, crop:-crop], ref[crop:-crop, crop:-crop]
    return float(10 * np.log10(1.0 / np.mean((out - ref) ** 2)))


def methods() -> dict[
    str, tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], object]]
]:
    """name -> (reconstruct from float64 RGGB mosaic, prepare input for timing)."""
    import colour_demosaicing as cd
    import cv2

    from imageform.sensor import demosaic

    def ours(m: str) -> Callable[[np.ndarray], np.ndarray]:
        return lambda raw: demosaic(raw, "RGGB", m)

    def cv(code: int) -> Callable[[np.ndarray], np.ndarray]:
        def f(raw: np.ndarray) -> np.ndarray:
            u8 = raw if raw.dtype == np.uint8 else np.round(raw * 255).astype(np.uint8)
            return cv2.cvtColor(u8, code).astype(np.float64) / 255

        return f

    def f32(raw: np.ndarray) -> object:
        return raw.astype(np.float32)

    def u8(raw: np.ndarray) -> object:
        return np.round(raw * 255).astype(np.uint8)

    def f64(raw: np.ndarray) -> object:
        return raw

    table: dict[str, tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], object]]]
    table = {f"imageform {m}": (ours(m), f32) for m in OURS}
    table.update(
        {
            "colour-demosaicing bilinear": (
                lambda r: cd.demosaicing_CFA_Bayer_bilinear(r, "RGGB"),
                f64,
            ),
            "colour-demosaicing Malvar2004": (
                lambda r: cd.demosaicing_CFA_Bayer_Malvar2004(r, "RGGB"),
                f64,
            ),
            "colour-demosaicing Menon2007": (
                lambda r: cd.demosaicing_CFA_Bayer_Menon2007(r, "RGGB"),
                f64,
            ),
            "OpenCV bilinear": (cv(cv2.COLOR_BayerBG2RGB), u8),
            "OpenCV VNG": (cv(cv2.COLOR_BayerBG2RGB_VNG), u8),
            "OpenCV EA": (cv(cv2.COLOR_BayerBG2RGB_EA), u8),
        }
    )
    return table


def time_round_robin(
    table: dict[str, tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], object]]],
    raws: list[np.ndarray],
    reps: int,
) -> tuple[dict[str, float], dict[str, float]]:
    """Median wall-clock and CPU (all threads of this process) ms per MP of every method.

    The methods take turns within each repetition, so that a change in the load of this
    shared machine hits all of them alike (ratios are then comparable).
    """
    args = {name: [prep(r) for r in raws] for name, (_, prep) in table.items()}
    for name, (fn, _) in table.items():  # warm-up: numba compilation, caches
        fn(args[name][0])  # type: ignore[arg-type]
    wall: dict[str, list[float]] = {n: [] for n in table}
    cpu: dict[str, list[float]] = {n: [] for n in table}
    for _ in range(reps):
        for name, (fn, _) in table.items():
            for r, arg in zip(raws, args[name], strict=True):
                mp = r.shape[0] * r.shape[1] / 1e6
                t0, c0 = time.perf_counter(), time.process_time()
                fn(arg)  # type: ignore[arg-type]
                wall[name].append((time.perf_counter() - t0) * 1e3 / mp)
                cpu[name].append((time.process_time() - c0) * 1e3 / mp)
    return (
        {n: float(np.median(v)) for n, v in wall.items()},
        {n: float(np.median(v)) for n, v in cpu.items()},
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", type=Path, help="write the markdown table to this file")
    ap.add_argument("--reps", type=int, default=7, help="timing repetitions per method")
    ap.add_argument("--time-images", type=int, default=3, help="images used for timing")
    ap.add_argument("--threads", type=int, default=0, help="numba threads (0: numba's default)")
    args = ap.parse_args()

    import numba

    if args.threads:
        numba.set_num_threads(args.threads)

    from imageform.sensor import mosaic

    images = load_kodak()
    raws = [mosaic(img, "RGGB") for img in images]
    table = methods()
    quality = {}
    for name, (fn, _) in table.items():
        crop, full = [], []
        for r, im in zip(raws, images, strict=True):
            out = np.asarray(fn(r), dtype=np.float64)
            crop.append(cpsnr(out, im, 10))
            full.append(cpsnr(out, im))
        quality[name] = (float(np.mean(crop)), float(np.mean(full)), np.array(crop))
        print(f"{name:34s} crop {np.mean(crop):7.3f}  full {np.mean(full):7.3f}", flush=True)
    wall_ms, cpu_ms = time_round_robin(table, raws[: args.time_images], args.reps)
    rows = [(n, quality[n][0], quality[n][1], wall_ms[n], quality[n][2]) for n in table]
    for n, _, _, t, _ in rows:
        print(f"{n:34s} {t:8.2f} ms/MP (CPU {cpu_ms[n]:8.2f})")

    speed = {r[0]: r[3] for r in rows}
    ratios = [
        (
            "imageform bilinear / OpenCV bilinear (<= 5)",
            speed["imageform bilinear"] / speed["OpenCV bilinear"],
        ),
        (
            "colour-demosaicing Malvar2004 / imageform malvar (>= 15)",
            speed["colour-demosaicing Malvar2004"] / speed["imageform malvar"],
        ),
        (
            "colour-demosaicing Menon2007 / imageform menon (>= 20)",
            speed["colour-demosaicing Menon2007"] / speed["imageform menon"],
        ),
        (
            "colour-demosaicing Menon2007 / imageform menon_soft (>= 20)",
            speed["colour-demosaicing Menon2007"] / speed["imageform menon_soft"],
        ),
    ]
    pairs = [
        ("imageform bilinear", "OpenCV bilinear"),
        ("colour-demosaicing Malvar2004", "imageform malvar"),
        ("colour-demosaicing Menon2007", "imageform menon"),
        ("colour-demosaicing Menon2007", "imageform menon_soft"),
    ]
    cpu_ratios = [cpu_ms[a] / cpu_ms[b] for a, b in pairs]
    for (label, v), c in zip(ratios, cpu_ratios, strict=True):
        print(f"{label}: {v:.1f} (CPU time: {c:.1f})")

    if args.write:
        lines = [
            "# Demosaicing benchmark, 2026-11-22",
            "",
            f"Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_demosaic.py "
            f"--write {args.write}` (one run; {args.reps} round-robin repetitions on "
            f"{args.time_images} images, median).",
            f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores "
            f"shared with other jobs; numba threads {numba.get_num_threads()}; "
            f"Python {platform.python_version()}.",
            "",
            "Kodak, 24 images, RGGB mosaic; CPSNR in dB (MSE pooled over RGB, output clipped "
            "to [0, 1], 8-bit sRGB values), mean over the images; crop = 10-pixel border "
            "removed. Time: imageform on float32 input, OpenCV on uint8, colour-demosaicing "
            "on float64.",
            "",
            "| method | CPSNR crop | CPSNR full | ms per MP |",
            "|---|---|---|---|",
        ]
        lines[-2] = "| method | CPSNR crop | CPSNR full | ms per MP | CPU ms per MP |"
        lines[-1] = "|---|---|---|---|---|"
        lines += [
            f"| {n} | {c:.3f} | {f:.3f} | {t:.2f} | {cpu_ms[n]:.2f} |" for n, c, f, t, _ in rows
        ]
        lines += ["", "Speed ratios (same run; wall clock, and CPU time in brackets):", ""]
        lines += [
            f"- {label}: **{v:.1f}** ({c:.1f})"
            for (label, v), c in zip(ratios, cpu_ratios, strict=True)
        ]
        lines += [
            "",
            "Per-image CPSNR (crop), imageform methods:",
            "",
            "| image | " + " | ".join(OURS) + " |",
            "|---" * (len(OURS) + 1) + "|",
        ]
        per = {n: c for n, _, _, _, c in rows}
        for i in range(24):
            vals = " | ".join(f"{per['imageform ' + m][i]:.2f}" for m in OURS)
            lines.append(f"| kodim{i + 1:02d} | {vals} |")
        args.write.write_text("\n".join(lines) + "\n")
        print(f"wrote {args.write}")


if __name__ == "__main__":
    main()
