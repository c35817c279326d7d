"""Vanishing points, focal length and horizon on degraded photographs: haze, dim, blur, noise.

Run (once per source tree; ``--save`` keeps each photograph's answers, ``--table`` prints
the before/after tables from two such files)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_vp_stress \\
        --york DIR --split tune --save after-tune.json
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=/path/to/main/src:. python -m benchmarks.check_vp_stress \\
        --york DIR --split tune --save before-tune.json
    python -m benchmarks.check_vp_stress --table before-tune.json after-tune.json

``--york DIR``: the York Urban DB (Denis, Elder and Estrada 2008; free for research) as in
trocolit2/vanishing-point-detection @ d07ba01 (``resource/datasets/yorkurban/``: 102
photographs ``000.jpg`` to ``101.jpg``, 640 x 480, and ``gt_data.yml`` with the annotated
horizon of each, ``y = a x + c`` in pixels), one calibrated camera: f = 674.92 px (the same
photographs and truth as ``check_vp_real.py``'s ``york_*``; not in the repository). The
tuning half is the even-numbered photographs, the held-out half the odd-numbered ones (the
split of ``vp-real-2026-11-29c.md``). Kodak (``../shared/data/kodak``, no geometry known)
adds a stability check: whether a degraded version gives the horizon the original gave
(within 2 % of H), odd-numbered images with the tuning half, even-numbered with the
held-out one.

Each photograph is run as it is and in ten degraded versions (8-bit, as a camera would
write them): ``haze 1/5`` (``0.2 I + 0.8 x 220``: fog, washed out), ``contrast 1/20``
(``mean + (I - mean) / 20``), ``dim 1/10`` (``I / 10``: underexposed), ``gamma 2.5``
(``255 (I / 255)^2.5``: dark mid-tones), ``dim 1/8 + noise 2`` (a dim room: ``I / 8`` plus
Gaussian noise σ = 2 levels), ``blur 2`` (Gaussian σ = 2 px), ``noise 12`` (Gaussian σ =
12 levels), ``JPEG q20``, ``crop 60 %`` (the central 60 % of width and height: the
principal point stays at the centre, the horizon moves with the crop) and ``crop left 70
%`` (the left 70 % of the width, all of the height: the principal point is 15 % of the
crop's width right of its centre, which the default principal point does not know).

Scores as York Urban evaluations (and ``check_vp_real.py``) give them: the horizon error is
the larger distance between the found and the annotated horizon at the image's left and
right edges over the height (none found: infinite), within 2 % and 5 % of H; the focal
length error against 674.92 px, within 5 %, off by more than 20 %. ``horizon_spread`` (where
the library has it) is reported against the error it comes with.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import re
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT / ".." / "shared" / "data" / "kodak"
F_YORK = 674.92
VERSIONS = (
    "original",
    "haze 1/5",
    "contrast 1/20",
    "dim 1/10",
    "gamma 2.5",
    "dim 1/8 + noise 2",
    "blur 2",
    "noise 12",
    "JPEG q20",
    "crop 60 %",
    "crop left 70 %",
)


def _u8(x: np.ndarray) -> np.ndarray:
    return np.clip(np.round(x), 0, 255).astype(np.uint8)


def version(rgb: np.ndarray, name: str, seed: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The degraded photograph and the offset ``(x0, y0)`` of its pixels in the original."""
    from PIL import Image
    from scipy import ndimage

    x = rgb.astype(np.float64)
    h, w = rgb.shape[:2]
    rng = np.random.default_rng(seed)
    if name == "original":
        return rgb, (0, 0)
    if name == "haze 1/5":
        return _u8(0.2 * x + 0.8 * 220.0), (0, 0)
    if name == "contrast 1/20":
        return _u8(x.mean() + (x - x.mean()) / 20.0), (0, 0)
    if name == "dim 1/10":
        return _u8(x / 10.0), (0, 0)
    if name == "gamma 2.5":
        return _u8(255.0 * (x / 255.0) ** 2.5), (0, 0)
    if name == "dim 1/8 + noise 2":
        return _u8(x / 8.0 + rng.normal(0.0, 2.0, x.shape)), (0, 0)
    if name == "blur 2":
        return _u8(ndimage.gaussian_filter(x, (2.0, 2.0, 0.0))), (0, 0)
    if name == "noise 12":
        return _u8(x + rng.normal(0.0, 12.0, x.shape)), (0, 0)
    if name == "JPEG q20":
        buf = io.BytesIO()
        Image.fromarray(rgb).save(buf, "JPEG", quality=20)
        return np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("RGB")), (0, 0)
    if name == "crop 60 %":
        y0, x0 = round(0.2 * h), round(0.2 * w)
        return rgb[y0 : y0 + round(0.6 * h), x0 : x0 + round(0.6 * w)], (x0, y0)
    if name == "crop left 70 %":
        return rgb[:, : round(0.7 * w)], (0, 0)
    raise ValueError(name)


def york_truth(folder: Path) -> list[tuple[float, float]]:
    """``(a, c)`` of each annotated horizon ``y = a x + c`` in ``gt_data.yml``."""
    text = (folder / "gt_data.yml").read_text()
    block = text.split("horizon_lines:")[1].split("zeniths:")[0]
    nums = [float(v) for v in re.findall(r"-?\d+\.?\d*(?:[eE][-+]?\d+)?", block.split("data:")[1])]
    return [(nums[k], nums[k + 2]) for k in range(0, len(nums), 3)]


def rows_of(line: Any, w: int) -> tuple[float, float] | None:
    """The line's rows at the first and last column, or None."""
    if line is None or abs(float(line[1])) < 1e-9:
        return None
    a, b, c = (float(t) for t in line)
    return (-c / b, -(a * (w - 1) + c) / b)


def run_one(arr: np.ndarray, seed: int = 0) -> dict[str, Any]:
    """detect_vanishing_points on ``arr``: its horizon rows, f, spreads and time."""
    from imageform.geometry import detect_vanishing_points

    t0 = time.perf_counter()
    res = detect_vanishing_points(arr, rng=seed)
    dt = time.perf_counter() - t0
    w = arr.shape[1]
    spread = getattr(res, "horizon_spread", None)
    return {
        "rows": rows_of(res.horizon, w),
        "f": None if res.K is None else float(res.K[0, 0]),
        "horizon_spread": None if spread is None else float(spread),
        "segments": len(res.segments),
        "s": dt,
    }


def _stretched(arr: np.ndarray) -> bool | None:
    try:
        from imageform.geometry.lsd import _stretch_low_contrast
    except ImportError:
        return None
    return _stretch_low_contrast(arr) is not arr


def measure(york: Path | None, split: str, limit: int | None) -> list[dict[str, Any]]:
    from PIL import Image

    from imageform.geometry import vp_detection

    # the time spent in the horizon's resampling, where the library has it
    spent = {"t": 0.0}
    inner = getattr(vp_detection, "_horizon_spread", None)
    if inner is not None:

        def timed(*a: Any, **k: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return inner(*a, **k)
            finally:
                spent["t"] += time.perf_counter() - t0

        vp_detection._horizon_spread = timed  # type: ignore[attr-defined]
    parity = 0 if split == "tune" else 1
    items: list[tuple[str, Path, tuple[float, float] | None]] = []
    if york is not None:
        truth = york_truth(york)
        for k, t in enumerate(truth):
            if k % 2 == parity:
                items.append(("york", york / f"{k:03d}.jpg", t))
    for k in range(1, 25):
        if k % 2 != parity:  # odd-numbered Kodak images with the tuning half
            items.append(("kodak", KODAK / f"kodim{k:02d}.png", None))
    if limit:
        items = items[:limit]
    out: list[dict[str, Any]] = []
    for n, (src, path, t) in enumerate(items):
        rgb = np.asarray(Image.open(path).convert("RGB"))
        for name in VERSIONS:
            arr, (x0, y0) = version(rgb, name, seed=n)
            spent["t"] = 0.0
            r = run_one(arr)
            r["spread_s"] = spent["t"] if inner is not None else None
            r.update(
                source=src,
                photo=path.name,
                version=name,
                size=[int(arr.shape[1]), int(arr.shape[0])],
                stretched=_stretched(arr),
            )
            if t is not None:
                a, c = t
                w = arr.shape[1]
                r["truth_rows"] = (a * x0 + c - y0, a * (x0 + w - 1) + c - y0)
            out.append(r)
        print(f"{n + 1}/{len(items)} {path.name}", flush=True)
    return out


def _herr(r: dict[str, Any], ref: tuple[float, float] | None) -> float:
    if ref is None:
        return math.nan
    if r["rows"] is None:
        return math.inf
    h = r["size"][1]
    return 100.0 * max(abs(r["rows"][0] - ref[0]), abs(r["rows"][1] - ref[1])) / h


def _ferr(r: dict[str, Any]) -> float:
    return math.inf if r["f"] is None else 100.0 * abs(r["f"] / F_YORK - 1.0)


def _pct(x: list[float], q: float) -> str:
    a = np.array(x, dtype=np.float64)
    return "-" if a.size == 0 else f"{np.percentile(a, q):.2f}"


def tables(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> str:
    """The before/after tables of two ``--save`` files of the same photographs."""
    lines: list[str] = []
    rows: list[tuple[object, ...]] = []
    for name in VERSIONS:
        cells: list[object] = [name]
        for recs in (before, after):
            y = [r for r in recs if r["source"] == "york" and r["version"] == name]
            he = [_herr(r, r["truth_rows"]) for r in y]
            fe = [_ferr(r) for r in y]
            cells.append(
                f"{sum(e <= 2 for e in he)} / {sum(e <= 5 for e in he)} / "
                f"{sum(math.isfinite(e) for e in he)} of {len(y)}"
            )
            cells.append(
                f"{sum(e <= 5 for e in fe)} / {sum(math.isfinite(e) and e > 20 for e in fe)}"
                f" / {sum(math.isfinite(e) for e in fe)}"
            )
        y = [r for r in after if r["source"] == "york" and r["version"] == name]
        cells.append(sum(bool(r["stretched"]) for r in y))
        rows.append(tuple(cells))
    lines.append("### York Urban: horizon and focal length against the truth\n")
    lines.append(
        markdown_table(
            (
                "version",
                "horizon within 2 % / 5 % of H / found, before",
                "f within 5 % / off > 20 % / found, before",
                "horizon within 2 % / 5 % of H / found, after",
                "f within 5 % / off > 20 % / found, after",
                "stretched (after)",
            ),
            rows,
        )
    )
    rows = []
    for name in VERSIONS[1:]:
        cells = [name]
        for recs in (before, after):
            base = {r["photo"]: r for r in recs if r["version"] == "original"}
            k = [r for r in recs if r["source"] == "kodak" and r["version"] == name]
            with_h = [r for r in k if base[r["photo"]]["rows"] is not None]
            same = 0
            for r in with_h:
                ref = base[r["photo"]]["rows"]
                if name.startswith("crop"):
                    continue
                same += _herr(r, ref) <= 2
            cells.append(f"{same} of {len(with_h)}" if not name.startswith("crop") else "-")
        k = [r for r in after if r["source"] == "kodak" and r["version"] == name]
        cells.append(sum(bool(r["stretched"]) for r in k))
        rows.append(tuple(cells))
    lines.append("### Kodak: the original's horizon again (within 2 % of H), where it had one\n")
    lines.append(markdown_table(("version", "before", "after", "stretched (after)"), rows))
    # horizon_spread against the error it comes with (York, every version)
    y = [r for r in after if r["source"] == "york" and r["rows"] is not None]
    bins = [(0.0, 0.005), (0.005, 0.01), (0.01, 0.02), (0.02, 0.05), (0.05, math.inf)]
    rows = []
    for lo, hi in bins:
        sel = [
            _herr(r, r["truth_rows"])
            for r in y
            if r["horizon_spread"] is not None and lo <= r["horizon_spread"] < hi
        ]
        rows.append(
            (
                f"{100 * lo:g}-{100 * hi:g} %" if math.isfinite(hi) else f">= {100 * lo:g} %",
                len(sel),
                _pct(sel, 50),
                _pct(sel, 90),
                f"{sum(e <= 2 for e in sel)}",
                f"{sum(e > 5 for e in sel)}",
            )
        )
    inf = [
        _herr(r, r["truth_rows"])
        for r in y
        if r["horizon_spread"] is not None and not math.isfinite(r["horizon_spread"])
    ]
    none = [_herr(r, r["truth_rows"]) for r in y if r["horizon_spread"] is None]
    rows.append(("inf", len(inf), _pct(inf, 50), _pct(inf, 90), sum(e <= 2 for e in inf),
                 sum(e > 5 for e in inf)))  # fmt: skip
    rows.append(("None (visible horizon)", len(none), _pct(none, 50), _pct(none, 90),
                 sum(e <= 2 for e in none), sum(e > 5 for e in none)))  # fmt: skip
    lines.append(
        "### York Urban, after: the horizon's error by its `horizon_spread` (all versions)\n"
    )
    lines.append(
        markdown_table(
            (
                "horizon_spread, % of H",
                "horizons",
                "median error, % of H",
                "90th pct",
                "within 2 %",
                "off > 5 %",
            ),
            rows,
        )
    )
    t_all = [r["s"] for r in after]
    t_sp = [r["spread_s"] / r["s"] for r in after if r.get("spread_s") is not None]
    t_b = {(r["photo"], r["version"]): r["s"] for r in before}
    ratio = [r["s"] / t_b[(r["photo"], r["version"])] for r in after if not r["stretched"]]
    # the answers on the photographs not stretched: the same as before, bit for bit?
    a_b = {(r["photo"], r["version"]): r for r in before}
    kept = [r for r in after if not r["stretched"]]
    same = sum(
        r["rows"] == a_b[(r["photo"], r["version"])]["rows"]
        and r["f"] == a_b[(r["photo"], r["version"])]["f"]
        and r["segments"] == a_b[(r["photo"], r["version"])]["segments"]
        for r in kept
    )
    lines.append(
        f"Photographs and versions not stretched: {len(kept)}; the same segments' count, "
        f"horizon and f as before (exactly): {same}.\n"
    )
    spent = (
        f"the horizon's resampling median {100 * np.median(t_sp):.1f} % of the call (90th "
        f"percentile {100 * np.percentile(t_sp, 90):.1f} %)"
        if t_sp
        else "no horizon resampling timed"
    )
    lines.append(
        f"Time per call, after: median {np.median(t_all):.3f} s; {spent}; after / before per "
        f"call, versions not stretched: median {np.median(ratio):.2f} (separate runs on a "
        "shared, loaded machine: not a measure of speed; see `--timing`).\n"
    )
    return "\n".join(lines)


def timing(york: Path, reps: int = 3) -> str:
    """Median time of the call with and without its two additions, interleaved, one process.

    The peer is the same code with the stretch test and the horizon's resampling replaced by
    no-ops (what the call did before them; the answers are otherwise the same), on the first
    ten even-numbered York Urban photographs, ``reps`` rounds each.
    """
    from PIL import Image

    from imageform.geometry import detect_vanishing_points, vp_detection

    full = (vp_detection._stretch_low_contrast, vp_detection._horizon_spread)
    bare = (lambda a: a, lambda *a, **k: None)
    ratios = []
    for k in range(0, 20, 2):
        rgb = np.asarray(Image.open(york / f"{k:03d}.jpg").convert("RGB"))
        detect_vanishing_points(rgb)
        t: dict[int, list[float]] = {0: [], 1: []}
        for _ in range(reps):
            for which, (st, hs) in enumerate((bare, full)):
                vp_detection._stretch_low_contrast, vp_detection._horizon_spread = st, hs
                t0 = time.perf_counter()
                detect_vanishing_points(rgb)
                t[which].append(time.perf_counter() - t0)
        ratios.append(float(np.median(t[1]) / np.median(t[0])))
    vp_detection._stretch_low_contrast, vp_detection._horizon_spread = full
    return (
        f"Interleaved in one process (`--timing`, 10 photographs x {reps} rounds): with / "
        f"without the stretch test and `horizon_spread`, median of the per-photograph ratios "
        f"of median times {np.median(ratios):.3f} (range {min(ratios):.3f}-{max(ratios):.3f}).\n"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--york", type=Path, help="York Urban folder (NNN.jpg, gt_data.yml)")
    parser.add_argument("--split", choices=("tune", "held"), default="tune")
    parser.add_argument("--limit", type=int, default=None, help="the first N photographs only")
    parser.add_argument("--save", type=Path, help="write each answer to this JSON file")
    parser.add_argument("--table", type=Path, nargs=2, metavar=("BEFORE", "AFTER"))
    parser.add_argument("--timing", action="store_true", help="time the additions (--york)")
    args = parser.parse_args()
    if args.timing:
        print(timing(args.york))
        return
    if args.table is not None:
        before, after = (json.loads(p.read_text()) for p in args.table)
        print(header("Vanishing points on degraded photographs"))
        print(tables(before, after))
        return
    recs = measure(args.york, args.split, args.limit)
    if args.save is not None:
        args.save.write_text(json.dumps(recs))
    print(tables(recs, recs))


if __name__ == "__main__":
    main()
