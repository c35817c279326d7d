"""Raw development against LibRaw (rawpy) at matched settings: time, peak memory, CIEDE2000.

The input is a DNG written from a real photograph (Kodak kodim23, upsampled to the size, as
a 12-bit RGGB mosaic of a made-up camera with an as-shot neutral), so both sides decode the
same file. Matched settings: bilinear demosaicing (LibRaw's LINEAR), the camera's white
balance, sRGB output, no auto-brightening, 16 bits out, the orientation applied.

- imageform: ``read_raw`` + ``develop`` + ``to_integer(16)``;
- LibRaw: ``rawpy.imread`` + ``postprocess(...)`` (16-bit sRGB).

Times are medians of interleaved rounds (median of 3 calls per side per round, same
process); peak memory is each side's peak resident set size (VmHWM) in a fresh process doing one
development (imports included). Accuracy: mean and 99th percentile CIEDE2000 between the two
outputs, 2-pixel border excluded.

Each thread setting runs in a process of its own (both libraries read it when loaded):
``1`` sets ``NUMBA_NUM_THREADS=1`` (imageform) and ``OMP_NUM_THREADS=1`` (LibRaw's OpenMP
loops); ``default`` leaves both unset (every core).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_raw.py [--sizes 6,24] [--rounds 3]
        [--threads 1,default]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT.parent / "shared" / "data" / "kodak" / "kodim23.png"
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])
NEUTRAL = (0.55, 1.0, 0.42)
SIZES = {6: (2000, 3000), 12: (3000, 4000), 24: (4000, 6000)}

SETTINGS = (
    "dict(use_camera_wb=True, no_auto_bright=True, output_bps=16, gamma=(2.4, 12.92), "
    "demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR, adjust_maximum_thr=0.0)"
)
OURS = "from imageform.io import read_raw, develop\nimg = develop(read_raw(PATH)).to_integer(16)\n"
THEIRS = f"import rawpy\nwith rawpy.imread(PATH) as r:\n    img = r.postprocess(**{SETTINGS})\n"


def make_dng(folder: Path, mpx: int) -> Path:
    import cv2

    from imageform.color import decode, linear_srgb_to_xyz
    from imageform.io import read_image, write_dng
    from imageform.sensor import mosaic

    h, w = SIZES[mpx]
    if KODAK.is_file():
        src = np.asarray(read_image(KODAK), np.float32) / 255.0
    else:  # without the reference data: a synthetic scene
        from imageform.simulate import default_scene, simulate

        src = np.asarray(simulate(default_scene().resized(768), rng=0).image, np.float32)
    src = cv2.resize(src, (w, h), interpolation=cv2.INTER_LINEAR)
    xyz = linear_srgb_to_xyz(decode(src.astype(np.float64), "srgb"))
    cam = np.clip(xyz @ CM.T * 0.9, 0, 1)
    dn = np.round(64 + mosaic(cam, "RGGB") * (4095 - 64)).astype(np.uint16)
    return write_dng(
        folder / f"kodim23-{mpx}mpx.dng",
        dn,
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        as_shot_neutral=NEUTRAL,
    )


def peak_rss_mib(code: str, path: Path) -> float:
    # VmHWM, the address space's high-water mark: ru_maxrss would carry over the parent's
    # peak through fork and exec
    prog = (
        f"PATH = {str(path)!r}\n{code}"
        "print([l.split()[1] for l in open('/proc/self/status') if l.startswith('VmHWM')][0])\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", prog],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    ).stdout
    return int(out.strip().splitlines()[-1]) / 1024


def run_once(code: str, path: Path) -> np.ndarray:
    import rawpy

    ns: dict[str, object] = {"PATH": str(path), "rawpy": rawpy}
    exec(code, ns)
    return ns["img"]  # type: ignore[return-value]


def mean_de00(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    from imageform.color import decode, delta_e, linear_srgb_to_xyz, xyz_to_lab

    step = max(1, a.shape[0] // 1000)  # every step-th row: enough pixels, little time
    a = a[2:-2:step, 2:-2] / 65535.0
    b = b[2:-2:step, 2:-2] / 65535.0
    lab1 = xyz_to_lab(linear_srgb_to_xyz(decode(a, "srgb")))
    lab2 = xyz_to_lab(linear_srgb_to_xyz(decode(b, "srgb")))
    de = np.asarray(delta_e(lab1, lab2))
    return float(de.mean()), float(np.percentile(de, 99))


def timed(code: str, path: Path, n: int) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        run_once(code, path)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def thread_env(threads: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS")}
    if threads != "default":
        env["NUMBA_NUM_THREADS"] = env["OMP_NUM_THREADS"] = threads
    env["PYTHONPATH"] = str(ROOT / "src")
    return env


def child(folder: Path, sizes: list[int], rounds: int) -> None:
    """Time both sides on the DNGs of ``folder`` in this process's thread setting (JSON out)."""
    rows: list[dict[str, Any]] = []
    for mpx in sizes:
        path = folder / f"kodim23-{mpx}mpx.dng"
        ours, theirs = run_once(OURS, path), run_once(THEIRS, path)  # warm-up
        de, de99 = mean_de00(ours, theirs)
        a, b, r = [], [], []
        for _ in range(rounds):
            ta, tb = timed(OURS, path, 3), timed(THEIRS, path, 3)
            a.append(ta)
            b.append(tb)
            r.append(tb / ta)
        mem_ours, mem_theirs = peak_rss_mib(OURS, path), peak_rss_mib(THEIRS, path)
        rows.append(
            {"mpx": mpx, "a": a, "b": b, "r": r, "mem": [mem_ours, mem_theirs], "de": [de, de99]}
        )
    print(json.dumps(rows))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="6,24")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", default="1,default")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    if args.child:
        child(Path(args.child), sizes, args.rounds)
        return
    import rawpy

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for mpx in sizes:
            make_dng(Path(tmp), mpx)
        found: dict[str, list[dict[str, Any]]] = {}
        for threads in args.threads.split(","):
            out = subprocess.run(
                [sys.executable, __file__, "--child", tmp, "--sizes", args.sizes]
                + ["--rounds", str(args.rounds)],
                capture_output=True,
                text=True,
                check=True,
                env=thread_env(threads),
            ).stdout
            found[threads] = json.loads(out.strip().splitlines()[-1])
    for i, mpx in enumerate(sizes):
        for threads, res in found.items():
            row = res[i]
            a, b, r = row["a"], row["b"], row["r"]
            mem, de = row["mem"], row["de"]
            n = os.cpu_count() if threads == "default" else int(threads)
            h, w = SIZES[mpx]
            rows.append(
                (
                    f"{w} x {h} ({mpx} Mpx)",
                    f"{threads} ({n})" if threads == "default" else threads,
                    f"{statistics.median(a):.2f}",
                    f"{statistics.median(b):.2f}",
                    f"{statistics.median(r):.2f} ({min(r):.2f}-{max(r):.2f})",
                    f"{mem[0]:.0f}",
                    f"{mem[1]:.0f}",
                    f"{de[0]:.3f} / {de[1]:.3f}",
                )
            )
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(header("Raw development: imageform against LibRaw (rawpy)"))
    print(
        f"rawpy {rawpy.__version__} (LibRaw {rawpy.libraw_version}, OpenMP "
        f"{rawpy.flags.get('OPENMP') if rawpy.flags else None}); load average {load} "
        f"(after the run); {args.rounds} interleaved rounds, median of 3 calls per side per "
        "round; threads 1: NUMBA_NUM_THREADS=1 and OMP_NUM_THREADS=1\n"
    )
    print(
        markdown_table(
            (
                "DNG",
                "threads",
                "imageform (s)",
                "LibRaw (s)",
                "speed ratio (LibRaw / imageform)",
                "imageform peak RSS (MiB)",
                "LibRaw peak RSS (MiB)",
                "ΔE00 mean / 99th pct",
            ),
            rows,
        )
    )
    print(
        f"Command: `OPENBLAS_NUM_THREADS=1 python benchmarks/bench_raw.py --rounds {args.rounds}`"
    )


if __name__ == "__main__":
    main()
