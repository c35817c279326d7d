"""Chart patches with marks over part of them: measured colour against the truth.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_chart_marks.py \
        [FOLDER --peer-cache FILE.json]

1. Rendered charts (:func:`synthetic_chart_photo`, true patch colours known; 6 charts,
   turned, tilted up to 25 degrees, under a colour cast, noise 0.005) with a mark drawn over
   10, 25 or 40 % of the sampled square of 8 of the 24 patches: a sticker of a random
   colour in a corner, a dark blue pen stroke through the patch, a red two-ring label. The
   chart's geometry is found on the unmarked photograph, so that the table measures the
   measurement. Per kind and share: the largest CIEDE2000 of the marked patches to their
   true colour, for the plain mean of the sampled square (what ``measure_chart_patches``
   did before) and for :func:`measure_chart_patches` now; the patches flagged; the share of
   pixels used.
2. With ``FOLDER`` (the held-out photographs of check_chart_real.py) and its peer cache: the
   three public photographs with marks on every patch (JTvD/arcu_colorchecker, MIT:
   ``example_colorchecker.jpg`` and ``example_mini_colorchecker.jpg``, each patch's number in
   red and a rectangle in green drawn on it; ``square_pattern.png``, a rendered Classic
   labelled "A1".."F4"). ``detect_colorchecker`` does not find them, so they are measured
   through OpenCV mcc's patch centres (from the cache; a homography fitted to them, sampling
   squares of half a pitch). The truth: for the rendered chart, each patch's most frequent
   pixel value (its fill); for the photographs, the same chart measured in an unmarked
   photograph of the same series (``color_checker (7).jpg``, the same desk; for the Mini,
   the series' photograph whose colours are nearest), which is a different exposure: a
   bound, not the error. And the mean CIEDE2000 to the published colours after a 3 x 3
   correction fitted on the measured patches (in-sample), to compare with the unmarked
   photographs' in chart-real.
"""

from __future__ import annotations

import hashlib
import json
import sys
import warnings
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import (
    ChartWarning,
    detect_colorchecker,
    fit_color_correction,
    measure_chart_patches,
    synthetic_chart_photo,
)
from imageform.analysis.chart_detect import (
    _GRID,
    ChartDetection,
    _apply_h,
    _fit_h,
    _quad_mask_bounds,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from imageform.color.convert import convert
from imageform.color.delta_e import delta_e

MARKED = [0, 3, 7, 10, 14, 18, 19, 23]
REF = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0


def _de00(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lab_a = np.asarray(convert(np.clip(a, 0.0, 1.0), "srgb", "lab"))
    lab_b = np.asarray(convert(np.clip(b, 0.0, 1.0), "srgb", "lab"))
    return np.asarray(delta_e(lab_a, lab_b))


def _pitch(c: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(np.diff(c.reshape(4, 6, 2), axis=1), axis=2)))


def _mark(img: np.ndarray, c: np.ndarray, kind: str, share: float, seed: int) -> np.ndarray:
    """The marks of tests/analysis/test_chart_patch_marks.py."""
    out = img.copy()
    p = _pitch(c)
    half = 0.25 * p
    vv, uu = np.mgrid[: img.shape[0], : img.shape[1]]
    rng = np.random.default_rng(seed)
    for k in MARKED:
        du, dv = uu - c[k][0], vv - c[k][1]
        if kind == "sticker":
            side = np.sqrt(share) * 2 * half
            m = (du >= -half - 3) & (du < -half + side) & (dv >= -half - 3) & (dv < -half + side)
            color = rng.uniform(0.0, 1.0, 3)
        elif kind == "pen stroke":
            a = rng.uniform(0.0, np.pi)
            across = np.abs(du * np.sin(a) - dv * np.cos(a))
            m = (across < share * half) & (np.hypot(du, dv) < 0.45 * p)
            color = np.array([0.05, 0.05, 0.6])
        else:
            m = np.zeros(img.shape[:2], dtype=bool)
            for off in (-0.12, 0.12):
                r = np.hypot((du - off * p) / (0.1 * p), dv / (0.2 * p))
                m |= (r > 1.0 - 1.35 * share) & (r < 1.0)
            color = np.array([0.9, 0.1, 0.1])
        out[m] = color
    return out


def _plain(im: np.ndarray, det: ChartDetection, full: float) -> np.ndarray:
    out = []
    for q in det.quads:
        sv, su, m = _quad_mask_bounds(q, *im.shape[:2])
        out.append(im[sv, su][m].astype(np.float64).mean(axis=0) / full)
    return np.asarray(out)


def rendered() -> str:
    rows = []
    for kind in ("sticker", "pen stroke", "label"):
        for share in (0.1, 0.25, 0.4):
            worst_plain, worst, flagged, used = 0.0, 0.0, 0, []
            for seed in range(6):
                rng = np.random.default_rng([91, seed])
                ph = synthetic_chart_photo(
                    width=rng.uniform(0.4, 0.6),
                    tilt=rng.uniform(0.0, 25.0),
                    rotation=rng.uniform(-180.0, 180.0),
                    shading=0.0,
                    noise=0.005,
                    cast=rng.uniform(0.7, 1.0, 3),
                    rng=rng,
                )
                det = detect_colorchecker(ph.image)
                img = _mark(ph.image, ph.centers, kind, share, seed)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", ChartWarning)
                    pat = measure_chart_patches(img, det)
                ok = ~pat.missing[MARKED]
                flagged += int((~ok).sum())
                err = _de00(pat.means[MARKED], ph.patches[MARKED])
                worst = max(worst, float(err[ok].max()) if ok.any() else 0.0)
                worst_plain = max(
                    worst_plain,
                    float(_de00(_plain(img, det, 1.0)[MARKED], ph.patches[MARKED]).max()),
                )
                used.extend(pat.used[MARKED].tolist())
            rows.append(
                (
                    kind,
                    f"{share:.0%}",
                    f"{worst_plain:.1f}",
                    f"{worst:.2f}",
                    f"{flagged} / {6 * len(MARKED)}",
                    f"{min(used):.2f} - {max(used):.2f}",
                )
            )
    return markdown_table(
        (
            "mark",
            "share of the sampled square",
            "plain mean: largest ΔE00 to truth",
            "measure_chart_patches: largest ΔE00 to truth",
            "marked patches flagged",
            "share of pixels used",
        ),
        rows,
    )


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def _from_centers(c: np.ndarray) -> ChartDetection:
    h = _fit_h(_GRID.astype(np.float64), c)
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    quads = _apply_h(h, (_GRID[:, None, :] + 0.5 * unit[None]).reshape(-1, 2)).reshape(-1, 4, 2)
    corners = _apply_h(h, unit * [6, 4] + [2.5, 1.5])
    centers = _apply_h(h, _GRID.astype(np.float64))
    return ChartDetection(
        h, corners, centers, quads, np.ones(24, bool), np.zeros(24, bool), 1.0, 0.0
    )


def _fit_de(means: np.ndarray, valid: np.ndarray) -> float:
    from imageform.analysis import ChartPatches

    p = ChartPatches(means, np.zeros_like(means), np.zeros(24, bool), ~valid)
    corr = fit_color_correction(p, REF)
    fixed = corr.apply(means[valid][:, None, :])[:, 0, :]
    return float(_de00(fixed, REF[valid]).mean())


def real(folder: Path, cache: Path) -> str:
    peers = json.loads(cache.read_text())
    rows = []
    for name, twins in (
        ("jtvd_example_colorchecker.jpg", ["jtvd_cc7.jpg"]),
        ("jtvd_example_mini_colorchecker.jpg", [f"jtvd_mini{i}.jpg" for i in range(1, 7)]),
        ("jtvd_square_pattern.png", []),
    ):
        im = _read(folder / name)
        got = peers.get("mcc:" + hashlib.sha1(np.ascontiguousarray(im).tobytes()).hexdigest())
        if got is None:
            rows.append((name, "mcc not in the cache", *["-"] * 7))
            continue
        det = _from_centers(np.asarray(got[1]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ChartWarning)
            pat = measure_chart_patches(im, det)
            plain = _plain(im, det, 255.0)
            if twins:
                best = None
                for t in twins:
                    tim = _read(folder / t)
                    tp = measure_chart_patches(tim, detect_colorchecker(tim))
                    d = float(np.median(_de00(pat.means, tp.means)))
                    if best is None or d < best[0]:
                        best = (d, t, tp.means)
                assert best is not None
                truth, what = best[2], f"unmarked {best[1]}"
            else:
                fills: list[np.ndarray] = []
                for q in det.quads:
                    sv, su, m = _quad_mask_bounds(q, *im.shape[:2])
                    vals, counts = np.unique(im[sv, su][m], axis=0, return_counts=True)
                    fills.append(vals[counts.argmax()] / 255.0)
                truth, what = np.asarray(fills), "each patch's fill"
        ok = pat.valid
        e_plain, e_now = _de00(plain, truth), _de00(pat.means, truth)
        rows.append(
            (
                name,
                what,
                f"{np.median(e_plain):.1f} / {e_plain.max():.1f}",
                f"{np.median(e_now[ok]):.1f} / {e_now[ok].max():.1f}",
                " ".join(str(i) for i in np.flatnonzero(~ok)) or "none",
                f"{pat.used.min():.2f} / {np.median(pat.used):.2f}",
                f"{_fit_de(plain, np.ones(24, bool)):.1f}",
                f"{_fit_de(pat.means, ok):.1f}",
            )
        )
    return markdown_table(
        (
            "photograph",
            "truth",
            "plain mean: ΔE00 to truth, median / max",
            "measure_chart_patches: ΔE00 to truth, median / max (usable)",
            "flagged",
            "share of pixels used, least / median",
            "plain mean: ΔE00 to published after fit",
            "measure_chart_patches: ΔE00 after fit",
        ),
        rows,
    )


if __name__ == "__main__":
    args = sys.argv[1:]
    print(header("Chart patches with marks"))
    print("Rendered charts, marks on 8 of 24 patches, 6 charts per row:\n")
    print(rendered())
    if len(args) == 3 and args[1] == "--peer-cache":
        print("\nReal photographs with marks on every patch, through mcc's patch centres:\n")
        print(real(Path(args[0]), Path(args[2])))
