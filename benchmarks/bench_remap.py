"""Benchmark: ``undistort_image`` vs ``cv2.undistort`` and ``remap_bilinear`` vs ``cv2.remap``.

Issue 19, "Remapping": imageform at least as fast as OpenCV (bilinear, float32 maps), the
same pixels to 1e-3. Both libraries run on the same inputs in the same run:

- images: the Kodak photo ``kodim01.png`` (shared/data/kodak) resized (bicubic) to 1 MP
  (1000 x 1000) and 12 MP (4000 x 3000), uint8 and float32 (``/ 255``), 1 channel (its grey
  version) and 3 channels;
- ``undistort_image(img, K, BrownConrady.from_opencv(D))`` (the fused numba kernel) against
  ``cv2.undistort(img, K, D)``;
- ``remap_bilinear(img, map32)`` against ``cv2.remap(img, map32, None, INTER_LINEAR)`` with
  the same ``(H, W, 2)`` float32 map (``undistortion_map(...).astype(np.float32)``);
- numba's and OpenCV's thread counts set equal: 1 thread, then the default (all cores);
  medians of ``--reps`` runs after one warm-up call (numba compiled before timing).

Outputs differ in type where OpenCV keeps 8 bits: imageform returns float32 in [0, 1] for a
uint8 image (docs/conventions.md), OpenCV uint8. Accuracy (1 MP, each dtype and channel
count): the largest |difference| between imageform and OpenCV with float maps on the float
image (``initUndistortRectifyMap(..., CV_32FC1)`` + ``remap``, which OpenCV 5 interpolates
without quantising) and a float64 reference (the NumPy twin on float64 image and map), both
in [0, 1] units; for uint8, also the difference to OpenCV's 8-bit output in codes
(OpenCV rounds to the nearest code; cv2.undistort also quantises positions to 1/32 px).

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_remap.py [--reps 5]

Prints a Markdown table and writes it to ``benchmarks/results/remap-<date>.md``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import sys
from pathlib import Path

import cv2
import numba
import numpy as np

from imageform.geometry.distortion import BrownConrady
from imageform.geometry.undistort import (
    _remap_bilinear_numpy,
    remap_bilinear,
    undistort_image,
    undistortion_map,
)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import markdown_table, median_time  # noqa: E402

# the OpenCV tutorial's left*.jpg calibration (shared/data/README.md), scaled to each size
D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
SIZES = {"1 MP": (1000, 1000), "12 MP": (3000, 4000)}


def _k(h: int, w: int) -> np.ndarray:
    f = 536.0 * w / 640.0
    return np.array([[f, 0, (w - 1) / 2 + 3.2], [0, f, (h - 1) / 2 - 2.1], [0, 0, 1.0]])


def _images(h: int, w: int) -> dict[tuple[str, int], np.ndarray]:
    photo = cv2.imread(str(ROOT.parent / "shared" / "data" / "kodak" / "kodim01.png"))
    if photo is None:
        raise SystemExit("missing ../shared/data/kodak/kodim01.png")
    rgb = cv2.resize(photo, (w, h), interpolation=cv2.INTER_CUBIC)
    gray = cv2.cvtColor(rgb, cv2.COLOR_BGR2GRAY)
    out = {}
    for c, img in ((1, gray), (3, rgb)):
        out[("uint8", c)] = np.ascontiguousarray(img)
        out[("float32", c)] = (img / 255.0).astype(np.float32)
    return out


def _accuracy(img: np.ndarray, K: np.ndarray, model: BrownConrady) -> dict[str, str]:
    """max |diff| of imageform against OpenCV float maps and a float64 reference."""
    h, w = img.shape[:2]
    f32 = img.astype(np.float32) / 255 if img.dtype == np.uint8 else img
    m64 = undistortion_map((h, w), K, model)
    m32 = m64.astype(np.float32)
    ours_u = np.asarray(undistort_image(img, K, model))
    ours_r = np.asarray(remap_bilinear(img, m32))
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    cv_u = cv2.remap(f32, mx, my, cv2.INTER_LINEAR)
    cv_r = cv2.remap(f32, m32, None, cv2.INTER_LINEAR)
    f64 = f32.astype(np.float64).reshape(1, h, w, -1)
    ref_u = _remap_bilinear_numpy(f64, m64[..., 0], m64[..., 1], 0.0).reshape(ours_u.shape)
    ref_r = _remap_bilinear_numpy(f64, m32[..., 0], m32[..., 1], 0.0).reshape(ours_r.shape)
    res = {
        "undistort": f"cv2 float maps {np.abs(ours_u - cv_u).max():.1e}; "
        f"f64 ref {np.abs(ours_u - ref_u).max():.1e}",
        "remap": f"cv2 {np.abs(ours_r - cv_r).max():.1e}; "
        f"f64 ref {np.abs(ours_r - ref_r).max():.1e}",
    }
    if img.dtype == np.uint8:
        u8 = cv2.undistort(img, K, D).astype(np.float64)
        r8 = cv2.remap(img, m32, None, cv2.INTER_LINEAR).astype(np.float64)
        res["undistort"] += f"; cv2.undistort uint8 {np.abs(ours_u * 255 - u8).max():.2f} codes"
        res["remap"] += f"; cv2 uint8 {np.abs(ours_r * 255 - r8).max():.2f} codes"
    else:
        fx = cv2.undistort(img, K, D)
        res["undistort"] += f"; cv2.undistort (1/32 px) {np.abs(ours_u - fx).max():.1e}"
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--sizes", default="1 MP,12 MP")
    args = ap.parse_args()
    model = BrownConrady.from_opencv(D)
    default_threads = numba.get_num_threads()
    thread_counts = sorted({1, default_threads})
    rows: list[list[object]] = []
    for size in args.sizes.split(","):
        h, w = SIZES[size.strip()]
        K = _k(h, w)
        imgs = _images(h, w)
        m32 = undistortion_map((h, w), K, model).astype(np.float32)
        for (dt, c), img in imgs.items():
            acc = _accuracy(img, K, model) if size.strip() == "1 MP" else {}
            for nt in thread_counts:
                numba.set_num_threads(nt)
                cv2.setNumThreads(nt)
                t = {
                    "undistort": (
                        median_time(lambda i=img, k=K: undistort_image(i, k, model), args.reps),
                        median_time(lambda i=img, k=K: cv2.undistort(i, k, D), args.reps),
                    ),
                    "remap": (
                        median_time(lambda i=img, m=m32: remap_bilinear(i, m), args.reps),
                        median_time(
                            lambda i=img, m=m32: cv2.remap(i, m, None, cv2.INTER_LINEAR), args.reps
                        ),
                    ),
                }
                for op, (t_if, t_cv) in t.items():
                    rows.append(
                        [
                            f"{size.strip()} {dt} {c}ch",
                            "undistort_image / cv2.undistort"
                            if op == "undistort"
                            else "remap_bilinear / cv2.remap",
                            nt,
                            f"{t_if * 1e3:.1f}",
                            f"{t_cv * 1e3:.1f}",
                            f"{t_cv / t_if:.2f}x",
                            acc.get(op, "-"),
                        ]
                    )
                print(rows[-2], rows[-1], flush=True)
    numba.set_num_threads(default_threads)
    cv2.setNumThreads(default_threads)
    cols = [
        "image",
        "imageform / OpenCV",
        "threads",
        "imageform ms",
        "OpenCV ms",
        "speed (OpenCV ms / ours)",
        "max |diff| (1 MP; [0, 1] units)",
    ]
    load = os.getloadavg()
    text = (
        f"# Remap benchmark ({_dt.date.today().isoformat()})\n\n"
        f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared, load average "
        f"{load[0]:.1f} at the end), Python {platform.python_version()}, NumPy {np.__version__}, "
        f"numba {numba.__version__}, OpenCV {cv2.__version__}; numba and OpenCV threads set "
        f"equal. Median of {args.reps} runs after one warm-up call, both libraries in the same "
        "run on the same input. imageform returns float32 for uint8 input, OpenCV uint8.\n\n"
        + markdown_table(cols, rows)
        + "\nCommand: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_remap.py"
        + (f" --reps {args.reps}`\n" if args.reps != 5 else "`\n")
    )
    print(text)
    out = ROOT / "benchmarks" / "results" / f"remap-{_dt.date.today().isoformat()}.md"
    out.write_text(text)
    print(f"written to {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
