"""Depth from a stereo pair: imageform's semi-global matching against truth and OpenCV's StereoSGBM.

``imageform.geometry.stereo_disparity`` (census costs, 8 paths, its defaults: 5 x 5 graded
census, ``census_step=4``, ``p1 = 8``, ``p2 = 32``, uniqueness 0.1, left-right check 1 px, the
equiangular sub-pixel fit; also with ``census_step=None``, the plain census that was the default
before 2026-11-30 (``imageform plain census (before 2026-11-30)``), with
``subpixel="parabola"``, OpenCV's fit and imageform's before, and with ``adaptive_p2``) against
``cv2.StereoSGBM_create`` at matched settings: the same block size (5), disparity range,
uniqueness (``uniquenessRatio=10``) and left-right check (``disp12MaxDiff=1``), OpenCV's own
recommended penalties for that block (``P1 = 8 * 5²``, ``P2 = 32 * 5²``: its Birchfield-Tomasi
costs summed over the block are on another scale than census bits, so the penalties cannot be
the same numbers) in ``MODE_HH`` (8 paths, as ours) and in its default mode (5 paths). No
speckle filter on either side. OpenCV's ``compute`` also passes every map through a 3 x 3 median
(``medianBlur(disp, disp, 3)`` in ``StereoSGBMImpl::compute``; no parameter turns it off), which
fills isolated invalid pixels: ``imageform median_filter`` (``stereo_disparity(...,
median_filter=True)``) is imageform with that median, the comparison at truly matched settings.
(OpenCV's left-right check cannot be turned off either: ``disp12MaxDiff <= 0`` is taken as 1.)

Pairs (``set``: ``tuning`` the pairs the defaults were chosen on, ``held out`` those looked at
only once, after the choice):

- ``rendered``, ``rendered-radiometric`` (tuning): ``tests/stereo_scenes.py``'s ray-cast scene
  (a slanted plane, a plane in front of it, a sphere, 3-D value-noise texture, 3 x 3 rays a
  pixel) at 640 x 480, ``f = 800`` px, baseline 60 mm (disparities 35 to 72 px), the truth
  exact; the second with the right image through ``0.75 I^0.8 + 0.06`` (another gain, gamma
  and offset: two sensors, auto-exposure) and both with Gaussian noise of 1/255.
- ``adirondack``, ``adirondack-exposure``, ``cones`` (tuning): Middlebury pairs (Scharstein
  et al.; Adirondack of the 2014 set at quarter size, 720 x 497, with the right image of
  another exposure ``E`` in the second; cones of the 2003 set at 450 x 375) as kept by
  github.com/2b-t/stereo-matching (MIT licence), commit a1a3ac2, ``data/``, with their masks of
  the non-occluded pixels. Their truths are 8-bit PNGs in whole pixels: cones' is the 2003
  quarter-pixel truth rounded (``np.round(disp2 / 4)`` reproduces it at every pixel), but
  Adirondack's is the 2014 disparity **truncated** (``floor``), not rounded: at the truth's
  steps from ``k - 1`` to ``k`` the two neighbours' matched disparities average ``k``, where a
  rounded truth puts them at ``k - 0.5`` (the table "Which whole pixel the truth keeps" below
  shows the test, checked on the rendered truth floored and rounded). A floored truth puts
  every disparity about half a pixel above it (the +0.55 px median error of every method in
  ``stereo-depth-2026-11-30a.md``) and turns sub-pixel disparities just past a whole pixel into
  errors over 1 px: Adirondack's truth is taken here as the PNG + 0.5 px (the middle of the
  pixel it was truncated from). Cones' truth is the 2003 quarter-pixel ``disp2.png / 4`` when
  ``--middlebury-2003`` gives it, else 2b-t's rounded PNG.
- ``teddy``, ``venus``, ``tsukuba`` (held out), with ``--middlebury-2003``: the 2003 teddy
  (450 x 375, truth in quarter pixels) and the 2001 venus (434 x 383, eighths) and tsukuba
  (384 x 288, whole pixels, ``im3``/``im4``) pairs of Middlebury's site, as kept with cones in
  github.com/r09921135/acv, commit bb7e9ca, ``hw4/testdata/`` (Middlebury: "We grant permission
  to use and publish all images and disparity maps", citing Scharstein & Szeliski 2002,
  2003; the repository states no licence of its own, so the files stay out of this one).
  Their non-occluded pixels: those of the truth that the right camera sees (the truth warped
  to the right image, nearer disparities winning, within 1 px).

Scores over the pixels with a truth that the right camera sees (non-occluded), off the left band
of ``num_disparities`` columns that both methods leave invalid: ``density`` the fraction with a
disparity, ``> 1 px`` and ``> 3 px`` the fraction of those more than 1 (3) px off, ``MAE`` their
mean absolute error, ``median d - truth`` their median signed error; ``> 1 px, d rounded`` the
``> 1 px`` of the disparities rounded to whole pixels. Sub-pixel accuracy: on the rendered pair
(exact truth), the mean error of the pixels within 1 px by the true disparity's fraction of a
pixel (a fit that pulls toward whole pixels, "pixel locking", errs negative just past a whole
pixel and positive just before the next). Uniqueness: density and errors of imageform (without
and with the median) and OpenCV at uniquenessRatio 5, 10, 15 %. Time: the matching alone
(imageform's kernels, compiled before; OpenCV's ``compute``), one thread each
(``OPENBLAS_NUM_THREADS=1``, ``NUMBA_NUM_THREADS=1``, ``cv2.setNumThreads(1)``): the process's
CPU time, the median of interleaved runs, as a ratio (the machine is shared: its load is
printed).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_depth.py --middlebury /tmp/middlebury \\
        --middlebury-2003 /tmp/acv-testdata --runs 9 \\
        --out benchmarks/results/stereo-depth-2026-11-30e.md

(``stereo-depth-2026-11-30d.md``, the plain census as the default, came from the same command;
``stereo-depth-2026-11-30g.md`` with ``cost_window=3`` as the default.)
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
#: the label of the plain census (``census_step=None``), the default before 2026-11-30
PLAIN = "imageform plain census (before 2026-11-30)"
#: the label of the pixel costs alone (``cost_window=1``), the default before 2026-11-30g
PIXEL = "imageform cost_window 1 (before 2026-11-30g)"
#: the 2003 / 2001 pairs of ``--middlebury-2003``: left, right, truth, its scale, disparities
PAIRS_2003 = {
    "teddy": ("im2.png", "im6.png", "disp2.png", 4, 64),
    "venus": ("im2.png", "im6.png", "disp2.pgm", 8, 32),
    "tsukuba": ("im3.png", "im4.png", "disp3.pgm", 16, 16),
}


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
        "set": "tuning",
        "kind": "exact",
    }


def _grey(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("L"))


def _png(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path)).astype(np.float64)


def _middlebury(folder: Path, name: str, right: str, n: int, half: float) -> dict[str, Any]:
    gt = _png(folder / f"{name}_gt.png")
    mask = _png(folder / f"{name}_mask.png") > 0
    return {
        "left": _grey(folder / f"{name}_left.png"),
        "right": _grey(folder / right),
        "truth": np.where(gt > 0, gt + half, 0.0),
        "png": gt,
        "mask": mask & (gt > 0),
        "n": n,
        "set": "tuning",
        "kind": "PNG + 0.5 (floored)" if half else "PNG (rounded)",
    }


def _visible(truth: np.ndarray) -> np.ndarray:
    """The pixels of a left truth that the right camera sees (nearer disparities win, 1 px)."""
    h, w = truth.shape
    ys, xs = np.nonzero(truth > 0)
    d = truth[ys, xs]
    seen = np.full((h, w + 1), -1.0)  # the nearest disparity landing on each right pixel
    for xr in (np.floor(xs - d), np.ceil(xs - d)):
        inside = (xr >= 0) & (xr < w)
        np.maximum.at(seen, (ys[inside], xr[inside].astype(np.int64)), d[inside])
    xr = np.round(xs - d).astype(np.int64)
    ok = (xr >= 0) & (xr < w)
    vis = np.zeros((h, w), dtype=bool)
    vis[ys[ok], xs[ok]] = d[ok] >= seen[ys[ok], xr[ok]] - 1.0
    return vis


def _pair_2003(folder: Path, name: str) -> dict[str, Any]:
    left, right, truth, scale, n = PAIRS_2003[name]
    gt = _png(folder / name / truth) / scale
    return {
        "left": _grey(folder / name / left),
        "right": _grey(folder / name / right),
        "truth": gt,
        "mask": _visible(gt) & (gt > 0),
        "n": n,
        "set": "held out",
        "kind": f"{truth} / {scale}",
    }


def _ours(pair: dict[str, Any], **kw: Any) -> np.ndarray:
    return stereo_disparity(pair["left"], pair["right"], num_disparities=pair["n"], **kw)


def _opencv(pair: dict[str, Any], mode: int, uniqueness: int = 10) -> np.ndarray:
    import cv2

    m = cv2.StereoSGBM_create(
        minDisparity=0,
        numDisparities=pair["n"],
        blockSize=BLOCK,
        P1=8 * BLOCK * BLOCK,
        P2=32 * BLOCK * BLOCK,
        disp12MaxDiff=1,
        uniquenessRatio=uniqueness,
        mode=mode,
    )
    d = m.compute(pair["left"], pair["right"]).astype(np.float32) / 16.0
    d[d < 0] = np.nan
    return d


def _region(pair: dict[str, Any]) -> np.ndarray:
    region = pair["mask"].copy()
    region[:, : pair["n"]] = False
    return region


def _scores(d: np.ndarray, pair: dict[str, Any]) -> tuple[float, ...]:
    region = _region(pair)
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


def _steps(d: np.ndarray, truth: np.ndarray, region: np.ndarray) -> tuple[int, float]:
    """Median of the mean d of two neighbours where a whole-pixel truth steps k-1 -> k, minus k."""
    ok = region & np.isfinite(d)
    both = ok[:, :-1] & ok[:, 1:]
    off: list[np.ndarray] = []
    for a, b in ((slice(None, -1), slice(1, None)), (slice(1, None), slice(None, -1))):
        step = both & (truth[:, b] == truth[:, a] + 1)  # rising to the right, then to the left
        mid = 0.5 * (d[:, :-1] + d[:, 1:])[step] - truth[:, b][step]
        off.append(mid[np.abs(mid) < 1.5])
    o = np.concatenate(off)
    return int(o.size), float(np.median(o))


def _locking(d: np.ndarray, pair: dict[str, Any], bins: int = 8) -> list[float]:
    """Mean error of the pixels within 1 px, by the true disparity's fraction of a pixel."""
    t = pair["truth"]
    ok = _region(pair) & np.isfinite(d) & (np.abs(d - t) < 1)
    e = (d - t)[ok]
    frac = np.minimum(((t - np.floor(t))[ok] * bins).astype(np.int64), bins - 1)
    return [float(e[frac == i].mean()) for i in range(bins)]


def _time(pair: dict[str, Any], runs: int) -> tuple[float, float, float, float]:
    import cv2

    ours, plain, par, cv = [], [], [], []
    for _ in range(runs):
        t = time.process_time()
        _ours(pair)
        ours.append(time.process_time() - t)
        t = time.process_time()
        _ours(pair, census_step=None)
        plain.append(time.process_time() - t)
        t = time.process_time()
        _ours(pair, subpixel="parabola")
        par.append(time.process_time() - t)
        t = time.process_time()
        _opencv(pair, cv2.STEREO_SGBM_MODE_HH)
        cv.append(time.process_time() - t)
    return (
        float(np.median(ours)),
        float(np.median(plain)),
        float(np.median(par)),
        float(np.median(cv)),
    )


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--middlebury", type=Path, help="folder of 2b-t/stereo-matching's data/")
    ap.add_argument(
        "--middlebury-2003",
        type=Path,
        help="folder of r09921135/acv's hw4/testdata/ (cones, teddy, venus, tsukuba)",
    )
    ap.add_argument("--out", type=Path, help="write the markdown tables here too")
    ap.add_argument("--runs", type=int, default=7, help="timed runs of each matcher")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    pairs: dict[str, dict[str, Any]] = {
        "rendered": _rendered(False),
        "rendered-radiometric": _rendered(True),
    }
    if args.middlebury is not None:
        mb = args.middlebury
        pairs["adirondack"] = _middlebury(mb, "Adirondack", "Adirondack_right.png", 64, 0.5)
        pairs["adirondack-exposure"] = _middlebury(
            mb, "Adirondack", "AdirondackE_right.png", 64, 0.5
        )
        pairs["cones"] = _middlebury(mb, "cones", "cones_right.png", 64, 0.0)
        if args.middlebury_2003 is not None:  # the quarter-pixel truth the PNG was rounded from
            quarter = _png(args.middlebury_2003 / "cones" / "disp2.png") / 4
            pairs["cones"]["truth"] = quarter
            pairs["cones"]["kind"] = "disp2.png / 4"
    if args.middlebury_2003 is not None:
        for name in PAIRS_2003:
            pairs[name] = _pair_2003(args.middlebury_2003, name)
    _ours(pairs["rendered"])  # compile the kernels before anything is timed
    _ours(pairs["rendered"], subpixel="parabola")
    _ours(pairs["rendered"], census_step=None)
    methods = {
        "imageform": lambda p: _ours(p),
        PIXEL: lambda p: _ours(p, cost_window=1),
        PLAIN: lambda p: _ours(p, census_step=None),
        "imageform parabola": lambda p: _ours(p, subpixel="parabola"),
        "imageform adaptive_p2": lambda p: _ours(p, adaptive_p2=True),
        "imageform median_filter": lambda p: _ours(p, median_filter=True),
        "OpenCV SGBM MODE_HH": lambda p: _opencv(p, cv2.STEREO_SGBM_MODE_HH),
        "OpenCV SGBM (5 paths)": lambda p: _opencv(p, cv2.STEREO_SGBM_MODE_SGBM),
    }
    results = {
        name: {label: fn(pair) for label, fn in methods.items()} for name, pair in pairs.items()
    }
    lines = [
        "# Stereo depth: semi-global matching against truth and OpenCV's StereoSGBM",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no speckle filter; scores over the non-occluded pixels with a "
        "truth, off the left band of num_disparities columns. imageform: its defaults (the "
        "graded census, census_step 4, its costs summed over 3 x 3 pixels, cost_window 3, and "
        "the equiangular sub-pixel fit); imageform cost_window 1 (before 2026-11-30g): each "
        "pixel's cost alone, the default before; imageform plain "
        "census (before 2026-11-30): census_step None (with cost_window 3); imageform "
        "parabola: the parabola (OpenCV's fit, imageform's before). Adirondack's truth: its "
        "PNG + 0.5 px (the PNG holds the disparity truncated, see below).",
        "",
        "| pair | set | truth | size | disparities | method | density | > 1 px "
        "| > 1 px, d rounded | > 3 px | MAE px | median d - truth |",
        "|---|---|---|---|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, pair in pairs.items():
        h, w = pair["left"].shape
        for label, d in results[name].items():
            dens, b1, b1w, b3, mae, bias = _scores(d, pair)
            lines.append(
                f"| {name} | {pair['set']} | {pair['kind']} | {w} x {h} | {pair['n']} | "
                f"{label} | {100 * dens:.1f} % | {100 * b1:.2f} % | {100 * b1w:.2f} % | "
                f"{100 * b3:.2f} % | {mae:.3f} | {bias:+.3f} |"
            )
    # which whole pixel a whole-pixel truth keeps: the test, on truths known either way
    lines += [
        "",
        "Which whole pixel the truth keeps: where a whole-pixel truth steps from k - 1 to k "
        "between two neighbours, the median of their two matched disparities' mean minus k "
        "(about 0 for a truth truncated from the disparity, about -0.5 for one rounded):",
        "",
        "| pair | truth | method | steps | median mean d - k |",
        "|---|---|---|---:|---:|",
    ]
    checks: list[tuple[str, str, np.ndarray]] = []
    exact = pairs["rendered"]["truth"]
    checks += [
        ("rendered", "floor(exact)", np.floor(exact)),
        ("rendered", "round(exact)", np.round(exact)),
    ]
    for name in ("adirondack", "cones"):
        if name in pairs:
            checks.append((name, "2b-t's PNG", pairs[name]["png"]))
    for name, label, truth in checks:
        for method in ("imageform", "OpenCV SGBM MODE_HH"):
            n, med = _steps(results[name][method], truth, _region(pairs[name]))
            lines.append(f"| {name} | {label} | {method} | {n} | {med:+.3f} |")
    # pixel locking on the exact truth
    lines += [
        "",
        "Sub-pixel bias on the rendered pair (exact truth): mean error (px) of the pixels within "
        "1 px, by the true disparity's fraction of a pixel (0 to 1/8, 1/8 to 1/4, ...), and "
        "the RMS of those errors:",
        "",
        "| pair | method | 0 | 1/8 | 1/4 | 3/8 | 1/2 | 5/8 | 3/4 | 7/8 | RMS px |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name in ("rendered", "rendered-radiometric"):
        pair = pairs[name]
        for method in ("imageform", PIXEL, PLAIN, "imageform parabola", "OpenCV SGBM MODE_HH"):
            d = results[name][method]
            t = pair["truth"]
            ok = _region(pair) & np.isfinite(d) & (np.abs(d - t) < 1)
            rms = float(np.sqrt(np.mean((d - t)[ok] ** 2)))
            cells = " | ".join(f"{v:+.3f}" for v in _locking(d, pair))
            lines.append(f"| {name} | {method} | {cells} | {rms:.3f} |")
    # density against errors at three uniqueness ratios
    lines += [
        "",
        "Uniqueness: density, > 1 px and > 3 px at uniquenessRatio 5, 10 and 15 % "
        "(imageform's `uniqueness` 0.05, 0.1, 0.15) of imageform (its defaults), with the 3 x 3 "
        "median (median_filter) and OpenCV MODE_HH (whose compute always applies that median):",
        "",
        "| pair | set | uniqueness | imageform density | > 1 px | > 3 px "
        "| with median density | > 1 px | > 3 px | OpenCV density | > 1 px | > 3 px |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, pair in pairs.items():
        if name.startswith("rendered"):
            continue
        for u in (5, 10, 15):
            row = [
                _scores(_ours(pair, uniqueness=u / 100), pair),
                _scores(_ours(pair, uniqueness=u / 100, median_filter=True), pair),
                _scores(_opencv(pair, cv2.STEREO_SGBM_MODE_HH, u), pair),
            ]
            cells = " | ".join(
                f"{100 * a[0]:.1f} % | {100 * a[1]:.2f} % | {100 * a[3]:.2f} %" for a in row
            )
            lines.append(f"| {name} | {pair['set']} | {u} % | {cells} |")
    lines += [
        "",
        "CPU time of the matching alone, one thread each, median of "
        f"{args.runs} interleaved runs (load before: {_load()}):",
        "",
        "| pair | imageform s | plain census s | imageform parabola s | OpenCV MODE_HH s "
        "| imageform / plain | imageform / parabola | imageform / OpenCV | plain / OpenCV |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name in ("rendered", "adirondack", "cones"):
        if name not in pairs:
            continue
        t_ours, t_plain, t_par, t_cv = _time(pairs[name], args.runs)
        lines.append(
            f"| {name} | {t_ours:.3f} | {t_plain:.3f} | {t_par:.3f} | {t_cv:.3f} | "
            f"{t_ours / t_plain:.2f} | {t_ours / t_par:.2f} | {t_ours / t_cv:.2f} | "
            f"{t_plain / t_cv:.2f} |"
        )
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
