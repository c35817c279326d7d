"""Illuminant estimation (white balance) on real photographs with a ColorChecker in them.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_illuminant_real.py \
        FOLDER [FOLDER ...] [--truth-cache FILE.json] [--overlays DIR]

The ground truth is made the way the Gehler-Shi and NUS colour-constancy sets made theirs:
the chart is found (:func:`~imageform.analysis.detect_colorchecker`), its patches read
(:func:`~imageform.analysis.measure_chart_patches`, for the missing and saturated flags), and
the illuminant is the mean linear RGB (sRGB decoded) of the achromatic patches 18-23 that are
neither flagged nor clipped (a channel's linear mean above 0.95) nor too dark to carry a
colour (below 0.01). The chart (its outline, grown by 10 % about its centre) is then set to
black so that the estimators do not see it (black pixels add nothing to a mean or a Minkowski
mean; the Gehler-Shi masks are used the same way), and the photograph is block-averaged in
linear light to a long side of at most 1024 pixels (the field's usual working size).

The error is the recovery angular error (Hordley & Finlayson 2006, JOSA A 23(5)): the angle in
degrees between the estimate and the truth as vectors in linear RGB. Per set and over all
photographs: mean, median, trimean (Q1 + 2 Q2 + Q3) / 4, the mean of the best 25 % and of the
worst 25 % (the statistics of Gijsenij, Gevers & van de Weijer 2011). ``none`` is the
estimate (1, 1, 1): the photograph as the camera balanced it. JPEGs from phones are
already white-balanced by the camera, so what is measured on them is the residual cast, and
a method that is worse than ``none`` makes the photograph worse. Only the machine-vision
photographs (luimoli: a camera under CWF, D65 and TL84 light) carry a cast of the light.

Every method of :data:`~imageform.color.WHITE_BALANCE_METHODS` but ``manual`` is run with its
defaults, plus ``max_rgb`` and ``gray_edge`` at sigma 2 / p 1 (its usual setting). The
photographs are those of ``check_chart_real.py`` that hold a ColorChecker (their sources and
licences are printed with the table); none is in this repository.

``--truth-cache`` keeps the truth and the chart outline per photograph in a JSON file (the
detection is the slow part); ``--overlays`` writes a JPEG per photograph with the chart's
outline and the grey patches used drawn on it, to check each detection by eye.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import ChartWarning, detect_colorchecker, measure_chart_patches
from imageform.analysis.chart_detect import _quad_mask_bounds
from imageform.color import WHITE_BALANCE_METHODS, estimate_illuminant
from imageform.color.transfer import decode

#: 0-based indices of the ColorChecker's achromatic patches (white .. black), row by row.
GREYS = (18, 19, 20, 21, 22, 23)
#: Photographs left out: the patches carry drawn marks, or the chart is a render or edited.
SKIP = {
    "jtvd_example_colorchecker.jpg": "patch numbers drawn on the patches",
    "jtvd_example_mini_colorchecker.jpg": "patch numbers drawn on the patches",
    "jtvd_square_pattern.png": "a render, not a photograph",
    "jan_Testbild5.png": "a chart with edited colours",
    "jarrel_203500.jpg": "the chart is shown on a screen: its greys are the screen's white",
    "jarrel_203507.jpg": "the chart is shown on a screen: its greys are the screen's white",
}
WORK_SIZE = 1024
#: Where the 2026-11-29 photographs come from (none is in this repository): file prefix ->
#: repository, commit, paths, licence, what.
SOURCES = (
    (
        "jan",
        "Jan-135/AutomatedColorcheckerFinder dfb9dac",
        "Testbild2.png",
        "none given",
        "a Classic among wooden blocks",
    ),
    (
        "jarrel",
        "jarrelscy/ColorCheckerDetector 9de6cab",
        "IMG_20140613_*.jpg",
        "MIT",
        "phone photographs of a printed chart on desks and floors, white blobs painted over "
        "parts of the frame",
    ),
    (
        "jtvd",
        "JTvD/arcu_colorchecker 0a1db96",
        "example_imgs/color_checker*.jpg",
        "MIT",
        "a Classic and a Mini on paper with ArUco markers, phone photographs",
    ),
    (
        "karnehen",
        "karnehen/ColorChecker",
        "seeds.jpg, *_cc_1.jpg",
        "none given",
        "a Classic beside seeds on white paper",
    ),
    (
        "luimoli",
        "luimoli/ColorcheckerCalibration",
        "data/mindvision/*.jpg",
        "none given",
        "a machine-vision camera, not balanced, under CWF, D65 and TL84 light: the only "
        "photographs with the light's cast",
    ),
    (
        "macduff",
        "mathandy/python-macduff-colorchecker-detector 555e3c7",
        "examples/below_fishbox*.jpg",
        "BSD-style",
        "a Passport small in a wide frame",
    ),
    (
        "oycq",
        "oycq/colorchecker bc57aa7",
        "data/*.jpg, data/DE.png",
        "none given",
        "a Classic on cardboard, three phones and a tilted view",
    ),
    (
        "pedro",
        "pedrodiamel/colorchecker-detection",
        "rec/img-colorchecker.jpg",
        "MIT",
        "a Classic held by hand",
    ),
    ("qiu", "QiuJueqin/color-checker-extraction", "images/passport.jpg", "MIT", "a Passport"),
)


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def _truth(im: np.ndarray) -> dict[str, Any]:
    """The chart's grey patches' mean linear RGB and its outline, or why there is none."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ChartWarning)
        det = detect_colorchecker(im)
        if not det.found:
            return {"found": False, "reason": det.reason}
        pat = measure_chart_patches(im, det)
    lin = decode(im, "srgb")
    used, means = [], []
    for k in GREYS:
        if pat.missing[k] or pat.saturated[k]:
            continue
        sv, su, mask = _quad_mask_bounds(det.quads[k], *im.shape[:2])
        m = lin[sv, su][mask].astype(np.float64).mean(axis=0)
        if m.max() > 0.95 or m.min() < 0.01:
            continue
        used.append(k)
        means.append(m)
    if not used:
        return {"found": False, "reason": "no unclipped grey patch"}
    e = np.mean(means, axis=0)
    spread = max(_angle(m, e) for m in means)
    return {
        "found": True,
        "truth": e.tolist(),
        "used": used,
        "spread": spread,
        "corners": np.asarray(det.corners).tolist(),
        "quads": np.asarray(det.quads)[list(GREYS)].tolist(),
    }


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Recovery angular error in degrees."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    c = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(min(1.0, max(-1.0, c))))


def _masked_work(im: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Linear image, chart set to 0, block-averaged to a long side <= WORK_SIZE."""
    lin = decode(im, "srgb").astype(np.float64)
    c = np.asarray(corners, dtype=np.float64)
    grown = c.mean(axis=0) + 1.1 * (c - c.mean(axis=0))
    sv, su, mask = _quad_mask_bounds(grown, *im.shape[:2])
    lin[sv, su][mask] = 0.0
    f = max(1, math.ceil(max(im.shape[:2]) / WORK_SIZE))
    h, w = (im.shape[0] // f) * f, (im.shape[1] // f) * f
    return lin[:h, :w].reshape(h // f, f, w // f, f, 3).mean(axis=(1, 3))


def _methods() -> list[tuple[str, str, dict[str, Any]]]:
    out: list[tuple[str, str, dict[str, Any]]] = [("none", "none", {})]
    for name in WHITE_BALANCE_METHODS:
        if name != "manual":
            out.append((name, name, {}))
        if name == "white_patch":
            out.append(("max_rgb", "max_rgb", {}))
        if name == "gray_edge":
            out.append(("gray_edge s2 p1", "gray_edge", {"sigma": 2.0, "p": 1.0}))
    return out


def _stats(err: list[float]) -> list[str]:
    e = np.sort(np.asarray(err))
    q1, q2, q3 = np.percentile(e, [25, 50, 75])
    k = max(1, round(0.25 * e.size))
    vals = [e.mean(), q2, (q1 + 2 * q2 + q3) / 4, e[:k].mean(), e[-k:].mean()]
    return [f"{v:.2f}" for v in vals]


def _set_of(name: str) -> str:
    return name.split("_")[0]


def _overlay(im: np.ndarray, t: dict[str, Any], path: Path) -> None:
    from PIL import Image, ImageDraw

    img = Image.fromarray(im)
    d = ImageDraw.Draw(img)
    wid = max(2, max(im.shape[:2]) // 300)
    c = [tuple(p) for p in t["corners"]]
    d.line([*c, c[0]], fill=(255, 0, 255), width=wid)
    for k, q in zip(GREYS, t["quads"], strict=True):
        pts = [tuple(p) for p in q]
        colour = (0, 255, 0) if k in t["used"] else (255, 0, 0)
        d.line([*pts, pts[0]], fill=colour, width=wid)
    img.thumbnail((800, 800))
    img.save(path, quality=85)


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--truth-cache")
    ap.add_argument("--overlays")
    args = ap.parse_args(argv)
    cache_path = Path(args.truth_cache) if args.truth_cache else None
    cache: dict[str, Any] = (
        json.loads(cache_path.read_text()) if cache_path and cache_path.exists() else {}
    )
    files = sorted(
        p
        for f in args.folders
        for p in Path(f).iterdir()
        if p.suffix.lower() in {".jpg", ".jpeg", ".png"}
    )
    methods = _methods()
    rows: list[list[str]] = []
    errs: dict[str, dict[str, list[float]]] = {}
    skipped: list[tuple[str, str]] = []
    t_est: dict[str, float] = {}
    for path in files:
        if path.name in SKIP:
            skipped.append((path.name, SKIP[path.name]))
            continue
        im = _read(path)
        key = path.name + ":" + hashlib.sha1(im.tobytes()).hexdigest()[:16]
        if key not in cache:
            cache[key] = _truth(im)
            if cache_path:
                cache_path.write_text(json.dumps(cache))
        t = cache[key]
        if not t["found"]:
            skipped.append((path.name, f"no ground truth: {t['reason']}"))
            continue
        if args.overlays:
            Path(args.overlays).mkdir(parents=True, exist_ok=True)
            _overlay(im, t, Path(args.overlays) / (path.stem + ".jpg"))
        truth = np.asarray(t["truth"])
        work = _masked_work(im, np.asarray(t["corners"]))
        row = [path.name, " ".join(str(k) for k in t["used"]), f"{t['spread']:.1f}"]
        rgb = truth / truth.sum()
        row.append(f"{rgb[0]:.3f} {rgb[1]:.3f} {rgb[2]:.3f}")
        for label, m, kw in methods:
            t0 = time.perf_counter()
            if m == "none":
                e = np.ones(3)
            else:
                e = np.asarray(estimate_illuminant(work, m, transfer="linear", **kw))
            t_est[label] = t_est.get(label, 0.0) + time.perf_counter() - t0
            a = _angle(e, truth)
            errs.setdefault(label, {}).setdefault(_set_of(path.name), []).append(a)
            row.append(f"{a:.1f}")
        rows.append(row)
        print(path.name, row[4:], file=sys.stderr, flush=True)

    out = [header("Illuminant estimation on real photographs with a ColorChecker")]
    sets = sorted({_set_of(r[0]) for r in rows})
    counts = {s: sum(_set_of(r[0]) == s for r in rows) for s in sets}
    out.append(
        f"{len(rows)} photographs with a ground truth ("
        + ", ".join(f"{s} {counts[s]}" for s in sets)
        + f"); working size: long side <= {WORK_SIZE} px, chart masked.\n"
    )
    cols = ["method", "mean", "median", "trimean", "best 25 %", "worst 25 %", "closer than none"]
    out.append("## All photographs (recovery angular error, degrees)\n")
    out.append(
        '"closer than none": on how many photographs the estimate is closer to the truth '
        "than leaving the photograph as it came.\n"
    )
    none = np.array([a for s in sets for a in errs["none"][s]])
    all_rows = []
    for label, _, _ in methods:
        e = np.array([a for s in sets for a in errs[label][s]])
        closer = "-" if label == "none" else f"{int((e < none).sum())} of {e.size}"
        all_rows.append([label, *_stats(list(e)), closer])
    out.append(markdown_table(cols, all_rows))
    out.append("## Per set (mean / median, degrees)\n")
    set_cols = ["method", *[f"{s} ({counts[s]})" for s in sets]]
    set_rows = []
    for label, _, _ in methods:
        cells = []
        for s in sets:
            st = _stats(errs[label][s])
            cells.append(f"{st[0]} / {st[1]}")
        set_rows.append([label, *cells])
    out.append(markdown_table(set_cols, set_rows))
    out.append("## Seconds per photograph (working size, this machine)\n")
    out.append(
        markdown_table(
            ["method", "s"],
            [[label, f"{t_est[label] / max(1, len(rows)):.3f}"] for label, _, _ in methods],
        )
    )
    out.append("## Per photograph (angular error, degrees)\n")
    out.append(
        "Grey patches used (0-based; 18 is white), their largest angle to the truth (the "
        "spread of the chart's own greys: a floor on what any estimate can be judged to), "
        "the truth's r g b chromaticity.\n"
    )
    pcols = ["photograph", "greys used", "grey spread", "truth rgb", *[m[0] for m in methods]]
    out.append(markdown_table(pcols, rows))
    out.append("## Photographs\n")
    out.append(
        markdown_table(["prefix", "repository, commit", "paths", "licence", "what"], SOURCES)
    )
    if skipped:
        out.append("## Left out\n")
        out.append(markdown_table(["photograph", "why"], skipped))
    print("\n".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
