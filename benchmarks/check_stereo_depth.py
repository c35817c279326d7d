"""Depth from a stereo pair: imageform's semi-global matching against truth and OpenCV's StereoSGBM.

``imageform.geometry.stereo_disparity`` (census costs, 8 paths, its defaults: 5 x 5 census,
``p1 = 8``, ``p2 = 32``, uniqueness 0.1, left-right check 1 px; also with ``adaptive_p2``)
against ``cv2.StereoSGBM_create`` at matched settings: the same block size (5), disparity range,
uniqueness (``uniquenessRatio=10``) and left-right check (``disp12MaxDiff=1``), OpenCV's own
recommended penalties for that block (``P1 = 8 * 5²``, ``P2 = 32 * 5²``: its Birchfield-Tomasi
costs summed over the block are on another scale than census bits, so the penalties cannot be
the same numbers) in ``MODE_HH`` (8 paths, as ours) and in its default mode (5 paths). No
speckle filter on either side.

Pairs:

- ``rendered``, ``rendered-radiometric``: ``tests/stereo_scenes.py``'s ray-cast scene (a
  slanted plane, a plane in front of it, a sphere, 3-D value-noise texture, 3 x 3 rays a pixel)
  at 640 x 480, ``f = 800`` px, baseline 60 mm (disparities 35 to 72 px), the truth exact; the
  second with the right image through ``0.75 I^0.8 + 0.06`` (another gain, gamma and offset:
  two sensors, auto-exposure) and both with Gaussian noise of 1/255.
- ``adirondack``, ``adirondack-exposure``, ``cones``: Middlebury pairs (Scharstein et al.;
  Adirondack of the 2014 set at 720 x 497, with the right image of another exposure ``E`` in
  the second; cones of the 2003 set at 450 x 375) as kept by github.com/2b-t/stereo-matching
  (MIT licence), commit a1a3ac2, ``data/``: their ground truth is stored in whole pixels (8-bit
  PNG), so the mean error carries the truth's own rounding (about 0.25 px), and their masks
  mark the non-occluded pixels. Put the files in a folder and give it with ``--middlebury``
  (``git show a1a3ac2:data/NAME.png``); without it these rows are left out.

Scores over the pixels with a truth that the right camera sees (non-occluded), off the left band
of ``num_disparities`` columns that both methods leave invalid: ``density`` the fraction with a
disparity, ``> 1 px`` and ``> 3 px`` the fraction of those more than 1 (3) px off, ``MAE`` their
mean absolute error, ``median d - truth`` their median signed error (Adirondack's truth here
sits about half a pixel below both matchers' disparities: a floored truth); ``> 1 px, d
rounded`` the ``> 1 px`` of the disparities rounded to whole pixels, as the Middlebury truths
here are (OpenCV's disparities are in 16ths and many whole: an error of exactly 1 px does not
count, a sub-pixel 1.1 px does). Time: the
matching alone (imageform's kernels, compiled before; OpenCV's ``compute``), one thread each
(``OPENBLAS_NUM_THREADS=1``, ``cv2.setNumThreads(1)``): the process's CPU time, the median of
interleaved runs, as a ratio (the machine is shared: its load is printed).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stereo_depth.py \\
        --middlebury /tmp/middlebury --out benchmarks/results/stereo-depth-2026-11-30a.md
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from stereo_scenes import render_pair  # noqa: E402

from imageform.geometry import stereo_disparity  # noqa: E402

BLOCK = 5


def _u8(a: np.ndarray) -> np.ndarray:
    return np.clip(np.round(a * 255.0), 0, 255).astype(np.uint8)


def _rendered(radiometric: bool) -> dict[str, Any]:
    s = render_pair(640, 480, f=800.0, baseline=60.0, ss=3, seed=0)
    rng = np.random.default_rng(11)
    left = s.left + rng.normal(0, 1 / 255, s.left.shape)
    right = s.right
    if radiometric:
        right = 0.75 * np.clip(right, 0, 1) ** 0.8 + 0.06
    right = right + rng.normal(0, 1 / 255, right.shape)
    return {
        "left": _u8(left),
        "right": _u8(right),
        "truth": s.disparity,
        "mask": s.visible,
        "n": 80,
    }


def _middlebury(folder: Path, name: str, right: str, n: int) -> dict[str, Any]:
    from PIL import Image

    def grey(p: str) -> np.ndarray:
        return np.asarray(Image.open(folder / p).convert("L"))

    gt = np.asarray(Image.open(folder / f"{name}_gt.png")).astype(np.float64)
    mask = np.asarray(Image.open(folder / f"{name}_mask.png")) > 0
    return {
        "left": grey(f"{name}_left.png"),
        "right": grey(right),
        "truth": gt,
        "mask": mask & (gt > 0),
        "n": n,
    }


def _ours(pair: dict[str, Any], **kw: Any) -> np.ndarray:
    return stereo_disparity(pair["left"], pair["right"], num_disparities=pair["n"], **kw)


def _opencv(pair: dict[str, Any], mode: int) -> np.ndarray:
    import cv2

    m = cv2.StereoSGBM_create(
        minDisparity=0,
        numDisparities=pair["n"],
        blockSize=BLOCK,
        P1=8 * BLOCK * BLOCK,
        P2=32 * BLOCK * BLOCK,
        disp12MaxDiff=1,
        uniquenessRatio=10,
        mode=mode,
    )
    d = m.compute(pair["left"], pair["right"]).astype(np.float32) / 16.0
    d[d < 0] = np.nan
    return d


def _scores(d: np.ndarray, pair: dict[str, Any]) -> tuple[float, ...]:
    region = pair["mask"].copy()
    region[:, : pair["n"]] = False
    ok = region & np.isfinite(d)
    signed = (d - pair["truth"])[ok]
    err = np.abs(signed)
    whole = np.abs(np.round(d[ok]) - pair["truth"][ok])
    return (
        float(ok.sum() / region.sum()),
        float(np.mean(err > 1)),
        float(np.mean(whole > 1)),
        float(np.mean(err > 3)),
        float(np.mean(err)),
        float(np.median(signed)),
    )


def _time(pair: dict[str, Any], runs: int) -> tuple[float, float]:
    import cv2

    ours, cv = [], []
    for _ in range(runs):
        t = time.process_time()
        _ours(pair)
        ours.append(time.process_time() - t)
        t = time.process_time()
        _opencv(pair, cv2.STEREO_SGBM_MODE_HH)
        cv.append(time.process_time() - t)
    return float(np.median(ours)), float(np.median(cv))


def main() -> None:
    """Print (and write with ``--out``) the table."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--middlebury", type=Path, help="folder of 2b-t/stereo-matching's data/")
    ap.add_argument("--out", type=Path, help="write the markdown table here too")
    ap.add_argument("--runs", type=int, default=7, help="timed runs of each matcher")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    pairs: dict[str, dict[str, Any]] = {
        "rendered": _rendered(False),
        "rendered-radiometric": _rendered(True),
    }
    if args.middlebury is not None:
        mb = args.middlebury
        pairs["adirondack"] = _middlebury(mb, "Adirondack", "Adirondack_right.png", 64)
        pairs["adirondack-exposure"] = _middlebury(mb, "Adirondack", "AdirondackE_right.png", 64)
        pairs["cones"] = _middlebury(mb, "cones", "cones_right.png", 64)
    _ours(pairs["rendered"])  # compile the kernels before anything is timed
    methods = {
        "imageform": lambda p: _ours(p),
        "imageform adaptive_p2": lambda p: _ours(p, adaptive_p2=True),
        "OpenCV SGBM MODE_HH": lambda p: _opencv(p, cv2.STEREO_SGBM_MODE_HH),
        "OpenCV SGBM (5 paths)": lambda p: _opencv(p, cv2.STEREO_SGBM_MODE_SGBM),
    }
    lines = [
        "# Stereo depth: semi-global matching against truth and OpenCV's StereoSGBM",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no speckle filter; scores over the non-occluded pixels with a "
        "truth, off the left band of num_disparities columns.",
        "",
        "| pair | size | disparities | method | density | > 1 px | > 1 px, d rounded | > 3 px "
        "| MAE px | median d - truth |",
        "|---|---|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, pair in pairs.items():
        h, w = pair["left"].shape
        for label, fn in methods.items():
            dens, b1, b1w, b3, mae, bias = _scores(fn(pair), pair)
            lines.append(
                f"| {name} | {w} x {h} | {pair['n']} | {label} | {100 * dens:.1f} % | "
                f"{100 * b1:.2f} % | {100 * b1w:.2f} % | {100 * b3:.2f} % | {mae:.3f} | "
                f"{bias:+.3f} |"
            )
    lines += [
        "",
        "CPU time of the matching alone, one thread each, median of "
        f"{args.runs} interleaved runs (load before: {_load()}):",
        "",
        "| pair | imageform s | OpenCV MODE_HH s | imageform / OpenCV |",
        "|---|---:|---:|---:|",
    ]
    for name in ("rendered", "adirondack", "cones"):
        if name not in pairs:
            continue
        t_ours, t_cv = _time(pairs[name], args.runs)
        lines.append(f"| {name} | {t_ours:.3f} | {t_cv:.3f} | {t_ours / t_cv:.2f} |")
    lines += ["", f"load after: {_load()}"]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


def _load() -> str:
    if not hasattr(os, "getloadavg"):
        return "n/a"
    return " / ".join(f"{v:.1f}" for v in os.getloadavg())


if __name__ == "__main__":
    main()
