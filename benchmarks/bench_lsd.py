"""LSD line segments: imageform against OpenCV's createLineSegmentDetector on real photographs.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_lsd.py [--repeat 7] [--images kodim01,kodim24]

Inputs: each Kodak image (``../shared/data/kodak``) converted once to 8-bit grey with
``cv2.cvtColor(RGB2GRAY)``; that same uint8 (H, W) array goes to both detectors (imageform
reads uint8 grey as 0-255 codes as is, as OpenCV does). Same parameters on both sides:
scale 0.8, sigma_scale 0.6, quant 2, τ = 22.5°, log_eps 0, density 0.7, 1024 bins.

Two OpenCV modes:

- **default** ``cv2.createLineSegmentDetector()`` = ``LSD_REFINE_STD``: refined regions
  are returned without any NFA computation or validation;
- **ADV** ``LSD_REFINE_ADV``: rectangle improvement and NFA validation, as the reference LSD
  (and imageform's ``method="lsd"``) does.

imageform runs as ``lsd_segments(validate=True)`` (the full LSD, ``detect_line_segments``'
default) and ``validate=False`` (the same refinement without the NFA test, OpenCV-STD-like).

Columns, per image (cv = the OpenCV output of that table):

- ``len ratio``: total segment length, imageform / cv;
- ``ep≤1px``: fraction of the cv segments that have an imageform segment with both end points
  within 1 px (either order);
- ``cov≤1px``: length-weighted fraction of the cv segments lying within 1 px of some
  imageform segment (points every 0.5 px along each cv segment; distance point-to-segment);
- ``cv self ep/cov``: the same two figures for OpenCV against itself on the image shifted by
  one pixel (cropped by one row and column, coordinates shifted back): how repeatable the
  end points are at all;
- times: median wall time of ``--repeat`` runs after a warm-up (numba compiled and cached),
  single-threaded OpenCV (``cv2.setNumThreads(1)``; LSD is single-threaded anyway).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "kodak"


def _seg_dist(pts: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Distances (k, m) from points (k, 2) to segments (m, 4)."""
    a = segs[None, :, :2]
    d = segs[None, :, 2:] - a
    l2 = (d**2).sum(-1)
    t = np.clip(((pts[:, None] - a) * d).sum(-1) / np.where(l2 == 0, 1.0, l2), 0.0, 1.0)
    q = a + t[..., None] * d
    return np.hypot(pts[:, None, 0] - q[..., 0], pts[:, None, 1] - q[..., 1])


def match(ref: np.ndarray, ours: np.ndarray, tol: float = 1.0) -> tuple[float, float]:
    """(end-point match fraction, length-weighted coverage) of ``ref`` segments by ``ours``."""
    if len(ref) == 0:
        return float("nan"), float("nan")
    if len(ours) == 0:
        return 0.0, 0.0
    n_ep = 0
    covered = 0.0
    total = 0.0
    for s in ref:
        d_same = np.maximum(np.hypot(*(ours[:, :2] - s[:2]).T), np.hypot(*(ours[:, 2:] - s[2:]).T))
        d_swap = np.maximum(np.hypot(*(ours[:, :2] - s[2:]).T), np.hypot(*(ours[:, 2:] - s[:2]).T))
        n_ep += bool(min(d_same.min(), d_swap.min()) <= tol)
        length = float(np.hypot(s[2] - s[0], s[3] - s[1]))
        k = max(2, int(np.ceil(length / 0.5)) + 1)
        pts = s[:2] + np.linspace(0.0, 1.0, k)[:, None] * (s[2:] - s[:2])
        covered += length * float((_seg_dist(pts, ours).min(1) <= tol).mean())
        total += length
    return n_ep / len(ref), covered / total


def _length(s: np.ndarray) -> float:
    return float(np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]).sum())


def _timed(fn, repeat: int) -> tuple[float, object]:  # type: ignore[no-untyped-def]
    out = fn()
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--images", default="", help="comma-separated kodim names (default: all)")
    args = ap.parse_args()
    import cv2
    from PIL import Image

    from imageform.geometry import detect_line_segments
    from imageform.geometry.lsd import lsd_segments

    cv2.setNumThreads(1)
    names = (
        [n.strip() for n in args.images.split(",") if n.strip()]
        if args.images
        else sorted(p.stem for p in DATA.glob("kodim*.png"))
    )
    det_std = cv2.createLineSegmentDetector()
    det_adv = cv2.createLineSegmentDetector(cv2.LSD_REFINE_ADV)

    def cv_run(det, g):  # type: ignore[no-untyped-def]
        lines = det.detect(g)[0]
        return np.zeros((0, 4)) if lines is None else lines.reshape(-1, 4).astype(np.float64)

    rows_adv, rows_std = [], []
    agg: dict[str, list[float]] = {}
    lsd_segments(np.zeros((16, 16), np.uint8))  # compile (or load the numba cache)
    for name in names:
        rgb = np.asarray(Image.open(DATA / f"{name}.png").convert("RGB"))
        g = np.ascontiguousarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))
        t_full, full = _timed(lambda g=g: lsd_segments(g)[0].reshape(-1, 4), args.repeat)
        t_nov, nov = _timed(
            lambda g=g: lsd_segments(g, validate=False)[0].reshape(-1, 4), args.repeat
        )
        t_adv, adv = _timed(lambda g=g: cv_run(det_adv, g), args.repeat)
        t_std, std = _timed(lambda g=g: cv_run(det_std, g), args.repeat)
        shifted = np.ascontiguousarray(g[1:, 1:])
        adv_s = cv_run(det_adv, shifted) + 1.0
        std_s = cv_run(det_std, shifted) + 1.0
        for label, ours, ref, ref_s, t_o, t_r, rows in (
            ("adv", full, adv, adv_s, t_full, t_adv, rows_adv),
            ("std", nov, std, std_s, t_nov, t_std, rows_std),
        ):
            ep, cov = match(ref, ours)
            ep_s, cov_s = match(ref, ref_s)
            ratio = _length(ours) / _length(ref)
            rows.append(
                (
                    name,
                    f"{len(ours)} / {len(ref)}",
                    f"{ratio:.3f}",
                    f"{ep:.2f}",
                    f"{cov:.3f}",
                    f"{ep_s:.2f} / {cov_s:.3f}",
                    f"{t_o * 1e3:.1f}",
                    f"{t_r * 1e3:.1f}",
                    f"{t_o / t_r:.2f}",
                )
            )
            for key, v in (
                ("ratio", ratio),
                ("ep", ep),
                ("cov", cov),
                ("ep_s", ep_s),
                ("cov_s", cov_s),
                ("t", t_o / t_r),
            ):
                agg.setdefault(f"{label}_{key}", []).append(v)
        # the default pairing, imageform's default against OpenCV's default; the earlier
        # detector (method="simple") for reference
        t_simple, simple = _timed(
            lambda g=g: detect_line_segments(g, method="simple").endpoints.reshape(-1, 4),
            max(1, args.repeat // 2),
        )
        agg.setdefault("simple_vs_std_ratio", []).append(_length(simple) / _length(std))
        agg.setdefault("simple_vs_std_cov", []).append(match(std, simple)[1])
        agg.setdefault("simple_vs_std_t", []).append(t_simple / t_std)
        agg.setdefault("full_vs_std_ratio", []).append(_length(full) / _length(std))
        agg.setdefault("full_vs_std_cov", []).append(match(std, full)[1])
        agg.setdefault("full_vs_std_t", []).append(t_full / t_std)

    cols = (
        "image",
        "segments ours / cv",
        "len ratio",
        "ep≤1px",
        "cov≤1px",
        "cv self ep / cov",
        "ours ms",
        "cv ms",
        "time ratio",
    )
    med = {k: statistics.median(v) for k, v in agg.items()}
    mn = {k: min(v) for k, v in agg.items()}
    mx = {k: max(v) for k, v in agg.items()}
    print(header("LSD line segments: imageform vs OpenCV createLineSegmentDetector"))
    print(
        f"OpenCV {cv2.__version__}; {len(names)} Kodak images, uint8 grey (cv2 RGB2GRAY) to "
        f"both; medians of {args.repeat} runs after a warm-up.\n"
    )
    print(
        "## Full LSD: imageform `lsd_segments()` (the default of `detect_line_segments`) "
        "vs OpenCV `LSD_REFINE_ADV`\n"
    )
    print(markdown_table(cols, rows_adv))
    print(
        "## Without NFA validation: imageform `lsd_segments(validate=False)` vs OpenCV "
        "default (`LSD_REFINE_STD`)\n"
    )
    print(markdown_table(cols, rows_std))
    print("## Summary (median, min-max over the images)\n")
    summary = []

    def span(key: str, nd: int) -> str:
        return f"{med[key]:.{nd}f} ({mn[key]:.{nd}f}-{mx[key]:.{nd}f})"

    for label, title in (("adv", "full LSD vs cv ADV"), ("std", "validate=False vs cv default")):
        summary.append(
            (
                title,
                span(label + "_ratio", 3),
                f"{med[label + '_ep']:.2f}",
                span(label + "_cov", 3),
                f"{med[label + '_ep_s']:.2f} / {med[label + '_cov_s']:.3f}",
                span(label + "_t", 2),
            )
        )
    for key, title in (
        ("full_vs_std", "full LSD vs cv default"),
        ("simple_vs_std", 'method="simple" (the earlier detector) vs cv default'),
    ):
        summary.append(
            (
                title,
                span(key + "_ratio", 3),
                "",
                f"{med[key + '_cov']:.3f}",
                "",
                span(key + "_t", 2),
            )
        )
    print(
        markdown_table(
            ("pairing", "len ratio", "ep≤1px", "cov≤1px", "cv self ep / cov", "time ratio"),
            summary,
        )
    )


if __name__ == "__main__":
    main()
