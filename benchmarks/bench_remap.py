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
- kernel against kernel, the same dtypes in and out: uint8 rows run imageform with
  ``keep_dtype=True`` (uint8 out, rounded, as OpenCV); ``u8->f32`` rows (1 MP) time
  imageform's default float32 output of a uint8 image against the same OpenCV call;
- numba's and OpenCV's thread counts set equal: 1 thread, then 2 (the machine's cores).

Timing: warm numba; ``--rounds`` rounds, in each the median of 5 calls of imageform then of
OpenCV (interleaved, so both see the same load of this shared machine); the table gives the
medians over the rounds and the speed OpenCV ms / imageform ms as the median of the
per-round ratios (and its range). The load average is printed at the start and the end.

Accuracy (1 MP, each dtype and channel count): the largest |difference| between imageform
and OpenCV with float maps (``initUndistortRectifyMap(..., CV_32FC1)`` + ``remap``, which
OpenCV 5 interpolates without quantising) and a float64 reference (the NumPy twin on float64
image and map), in [0, 1] units for float outputs and in codes for uint8 outputs (OpenCV
rounds to the nearest code; cv2.undistort also quantises positions to 1/32 px).

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_remap.py [--rounds 7]

Prints a Markdown table and writes it to ``benchmarks/results/remap-<date>.md`` (or
``--write PATH``).
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
from benchmarks._common import markdown_table, paired_rounds  # noqa: E402

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
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, (w, h), cv2.CV_32FC1)
    f64 = f32.astype(np.float64).reshape(1, h, w, -1)
    ref_u = _remap_bilinear_numpy(f64, m64[..., 0], m64[..., 1], 0.0).reshape(img.shape)
    ref_r = _remap_bilinear_numpy(f64, m32[..., 0], m32[..., 1], 0.0).reshape(img.shape)
    inner = np.s_[2:-2, 2:-2]  # OpenCV blends its constant border into the edge half pixel

    def mx_(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.abs(a.astype(np.float64) - b)[inner].max())

    res: dict[str, str] = {}
    if img.dtype == np.uint8:
        ours_u = np.asarray(undistort_image(img, K, model, keep_dtype=True))
        ours_r = np.asarray(remap_bilinear(img, m32, keep_dtype=True))
        cv_u = cv2.remap(img, mx, my, cv2.INTER_LINEAR)
        cv_r = cv2.remap(img, m32, None, cv2.INTER_LINEAR)
        res["undistort"] = (
            f"codes: cv2 float maps {mx_(ours_u, cv_u):.0f}; "
            f"f64 ref {mx_(ours_u, ref_u * 255):.2f}; "
            f"cv2.undistort {mx_(ours_u, cv2.undistort(img, K, D)):.0f}"
        )
        res["remap"] = f"codes: cv2 {mx_(ours_r, cv_r):.0f}; f64 ref {mx_(ours_r, ref_r * 255):.2f}"
        fu = np.asarray(undistort_image(img, K, model))
        fr = np.asarray(remap_bilinear(img, m32))
        res["undistort f32"] = f"f64 ref {mx_(fu, ref_u):.1e}"
        res["remap f32"] = f"f64 ref {mx_(fr, ref_r):.1e}"
    else:
        ours_u = np.asarray(undistort_image(img, K, model))
        ours_r = np.asarray(remap_bilinear(img, m32))
        cv_u = cv2.remap(f32, mx, my, cv2.INTER_LINEAR)
        cv_r = cv2.remap(f32, m32, None, cv2.INTER_LINEAR)
        res["undistort"] = (
            f"cv2 float maps {mx_(ours_u, cv_u):.1e}; f64 ref {mx_(ours_u, ref_u):.1e}; "
            f"cv2.undistort (1/32 px) {mx_(ours_u, cv2.undistort(img, K, D)):.1e}"
        )
        res["remap"] = f"cv2 {mx_(ours_r, cv_r):.1e}; f64 ref {mx_(ours_r, ref_r):.1e}"
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--sizes", default="1 MP,12 MP")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--write", type=Path, help="the results file (default: remap-<date>.md)")
    args = ap.parse_args()
    model = BrownConrady.from_opencv(D)
    default_threads = numba.get_num_threads()
    default_cv = cv2.getNumThreads()
    thread_counts = [int(t) for t in args.threads.split(",")]
    load0 = os.getloadavg()[0]
    rows: list[list[object]] = []
    for size in (s.strip() for s in args.sizes.split(",")):
        h, w = SIZES[size]
        K = _k(h, w)
        imgs = _images(h, w)
        m32 = undistortion_map((h, w), K, model).astype(np.float32)
        for (dt, c), img in imgs.items():
            acc = _accuracy(img, K, model) if size == "1 MP" else {}
            variants = [(f"{dt}->{dt}", dt == "uint8", "")]
            if dt == "uint8" and size == "1 MP":
                variants.append(("u8->f32 (default)", False, " f32"))
            for nt in thread_counts:
                numba.set_num_threads(nt)
                cv2.setNumThreads(nt)
                for label, keep, key in variants:
                    cases = {
                        "undistort": (
                            lambda i=img, k=K, kd=keep: undistort_image(i, k, model, keep_dtype=kd),
                            lambda i=img, k=K: cv2.undistort(i, k, D),
                        ),
                        "remap": (
                            lambda i=img, m=m32, kd=keep: remap_bilinear(i, m, keep_dtype=kd),
                            lambda i=img, m=m32: cv2.remap(i, m, None, cv2.INTER_LINEAR),
                        ),
                    }
                    for op, (ours, cv) in cases.items():
                        t_if, t_cv, r, rmin, rmax = paired_rounds(ours, cv, args.rounds, speed=True)
                        rows.append(
                            [
                                f"{size} {c}ch",
                                label,
                                "undistort_image / cv2.undistort"
                                if op == "undistort"
                                else "remap_bilinear / cv2.remap",
                                nt,
                                f"{t_if * 1e3:.2f}",
                                f"{t_cv * 1e3:.2f}",
                                f"**{r:.2f}x** ({rmin:.2f}-{rmax:.2f})",
                                acc.get(op + key, "-"),
                            ]
                        )
                        print(rows[-1], flush=True)
    numba.set_num_threads(default_threads)
    cv2.setNumThreads(default_cv)
    cols = [
        "image",
        "dtype in->out",
        "imageform / OpenCV",
        "threads",
        "imageform ms",
        "OpenCV ms",
        "speed OpenCV/imageform (range)",
        "max |diff| (1 MP; [0, 1] units or codes)",
    ]
    load1 = os.getloadavg()[0]
    today = _dt.date.today().isoformat()
    text = (
        f"# Remap benchmark ({today})\n\n"
        f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared with other engineers: "
        f"load average {load0:.1f} at the start, {load1:.1f} at the end), Python "
        f"{platform.python_version()}, NumPy {np.__version__}, numba {numba.__version__}, "
        f"OpenCV {cv2.__version__}; OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}; numba and OpenCV threads set "
        f"equal. {args.rounds} rounds, in each the median of 5 calls of imageform then of "
        "OpenCV; the ms columns are the medians over the rounds, the speed the median of the "
        "per-round ratios (> 1: imageform faster). Same dtypes in and out: uint8 rows run "
        "imageform with `keep_dtype=True`; `u8->f32 (default)` rows time imageform's float32 "
        "output of a uint8 image against OpenCV's uint8 one.\n\n"
        + markdown_table(cols, rows)
        + "\nCommand: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_remap.py"
        + (f" --rounds {args.rounds}`\n" if args.rounds != 7 else "`\n")
    )
    print(text)
    out = args.write or ROOT / "benchmarks" / "results" / f"remap-{today}.md"
    out.write_text(text)
    print(f"written to {out}")


if __name__ == "__main__":
    main()
