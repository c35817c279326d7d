"""Slanted surfaces in flat regions: the plane of a flat region's textured rim (``plane_fill``).

``stereo-webcam-2026-11-30g.md``: with the census costs summed over 3 x 3 pixels most of
``stereo_disparity``'s remaining > 1 px errors on the webcam and XIMEA board pairs lie in
the boards' flat squares, on slanted boards. In a region without texture every disparity
costs alike, and each of the 8 paths carries in the disparity of the edge it came from, a
step of one pixel costing ``P1``: the sum picks about the median of those edges'
disparities, one value where a slanted surface's disparity changes (SGM's fronto-parallel
bias). OpenCV's ``StereoSGBM`` was ahead there (webcam-1 6.51 % against 8.08 %).

The change (``plane_fill``, default on): the flat regions of the left image (5 x 5 standard
deviation under 3 grey levels; 4-connected; 30 pixels to 2 % of the image) take the
least-squares plane of the disparities on their textured rim (the pixels within 3 px
outside), refitted twice on the rim pixels within 1 px of it, where at least 80 % of the
rim's valid pixels are such inliers and half of the rim is valid (a rim across two surfaces
fails). The segment-based plane fits of the literature (e.g. A. Klaus, M. Sormann, K.
Karner, "Segment-based stereo matching using belief propagation and a self-adapting
dissimilarity measure", ICPR 2006; H. Hirschmüller's own "Stereo processing by semiglobal
matching and mutual information", PAMI 30(2), 2008, which for untextured areas fits planes to
segments of the intensity image), with the flat regions as segments and their rims as the
disparities trusted. Candidates measured on the tuning data (seen before: the board sets of
``check_stereo_fresh.py``, Middlebury 2003 / 2014 of ``check_stereo_depth.py``, the 2005 /
2006 scenes of ``check_stereo_noise.py``):

- **before**: ``plane_fill=False`` (main at bd91c74f: its defaults).
- **after**: the defaults now.
- **no area cap**: every flat region of 30 pixels or more (Venus's background, 10 % of the
  image, takes a plane off by more than 1 px: the cap of 2 %).
- **adaptive P2** (Hirschmüller's eq. 12, ``adaptive_p2=True``, without the plane fill): the
  Middlebury scenes gain, the boards lose (a board's square edges are strong intensity
  steps, so the paths jump there cheaply and each square keeps its own disparity).
- **plain census**: ``census_step=None`` (with the plane fill): the re-check of the graded
  census's default now that the costs are summed over a block.
- OpenCV's ``StereoSGBM`` ``MODE_HH`` at matched settings (block 5, ``P1 = 8·25``,
  ``P2 = 32·25``, uniqueness 10 %, ``disp12MaxDiff`` 1, no speckle filter).

Held out (fresh, frozen by SHA-256 before any run, run once with the final code):
``argoverse``: github.com/argoverse/argoverse-api, commit f886ac5,
``tests/test_data/stereo/``: one rectified pair of Argoverse 1.1's stereo cameras
(``stereo_front_left_rect_1.jpg``, ``stereo_front_right_rect_1.jpg``, 2464 x 2056) and its
LiDAR disparity truth (``disparity_maps_v1.1/test/1/stereo_front_left_rect_disparity/
disparity_1.png``, value / 256, 0 unknown), put as ``left.jpg``, ``right.jpg``,
``disparity.png`` and ``calib.json`` (``vehicle_calibration_stereo_info.json``) in one
folder. Halved (2 x 2 means; the truth the mean of a block's known values / 2), disparities 0
to the truth's largest + 1 rounded up to 16, scored on every pixel with a truth off the
left band. Argoverse's data licence (CC BY-NC-SA 4.0) keeps the files out of this repository.
A search of the stored GitHub index for Middlebury 2014 / ETH3D / KITTI pairs with their
truth found none stored (the binary files are not indexed), hence one pair.

Time: the matching alone, one thread each, the process's CPU time, the median of
interleaved runs.

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_slant.py --fresh /tmp/stereog/data/fresh \\
        --cache /tmp/stereog/cache --middlebury /tmp/stereog/data/mb \\
        --middlebury-2003 /tmp/stereog/data/acv --scenes-0506 /tmp/stereog/data/ho0506 \\
        --heldout /tmp/stereoh/heldout/argoverse \\
        --out benchmarks/results/stereo-slant-2026-11-30h.md

Each part (``--part NAME``: a board set, middlebury, 0506, heldout, time) may run in its
own process with ``--out part.json``; ``--merge part*.json --out ...`` prints the tables.
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
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "tests"))

import check_stereo_depth as depth  # noqa: E402
import check_stereo_fresh as fresh  # noqa: E402
import check_stereo_noise as noise  # noqa: E402
import check_stereo_webcam as webcam  # noqa: E402

from imageform.geometry import stereo_disparity  # noqa: E402
from imageform.geometry import stereo_matching as sm  # noqa: E402

#: the held-out folder's digest (``check_stereo_fresh._digest``), frozen before any run
HELDOUT_DIGEST = "421c79aa3505dedd5a48703d6c2dca392d06ccc0023b9750f6a2ae15436bb853"
#: the held-out files' SHA-256 (``sha256sum`` in byte order; their listing's digest above)
HELDOUT_FILES = (
    "4136b3396ebd572b8c3a295255df942c73f174bf1d82d36e0ee711c59cb05c04  calib.json",
    "809707cab86ece42996a84758292537cbfbc0c1220733644138ec8f1980cd6b6  disparity.png",
    "89fd3b09a183bb1493ffad97c8abd65d6d99552f1ab3b0efafbf1c3acb80551b  left.jpg",
    "ff327124827a15c3203843ddf942a1681bc5c917702627a40981dd2c82039e56  right.jpg",
)
BOARDS = webcam.BOARDS
BEFORE = "imageform before (plane_fill=False)"
AFTER = "imageform after (default)"
NOCAP = "imageform plane_fill, no area cap"
ADAPTIVE = "imageform adaptive_p2, no plane_fill"
PLAIN = "imageform plain census (census_step=None)"
OPENCV = webcam.OPENCV

Fn = Any


def _ours(**kw: Any) -> Fn:
    def fn(L: np.ndarray, R: np.ndarray, lo: int, n: int) -> np.ndarray:
        return stereo_disparity(L, R, min_disparity=lo, num_disparities=n, **kw)

    return fn


def _nocap(L: np.ndarray, R: np.ndarray, lo: int, n: int) -> np.ndarray:
    keep = sm.PLANE_AREA
    sm.PLANE_AREA = (keep[0], 1.0)
    try:
        return stereo_disparity(L, R, min_disparity=lo, num_disparities=n)
    finally:
        sm.PLANE_AREA = keep


METHODS: dict[str, Fn] = {
    BEFORE: _ours(plane_fill=False),
    AFTER: _ours(),
    NOCAP: _nocap,
    ADAPTIVE: _ours(adaptive_p2=True, plane_fill=False),
    PLAIN: _ours(census_step=None),
    OPENCV: fresh._sgbm,
}
#: the methods of the held-out run and of the CPU times
FINAL = (BEFORE, AFTER, PLAIN, OPENCV)


def _load() -> str:
    return " / ".join(f"{v:.1f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else ""


def _board_part(name: str, d: dict[str, Any]) -> dict[str, list[str]]:
    rows, where = [], []
    lo, n = d["lo"], d["n"]
    for k, fn in METHODS.items():
        sc, counts, slant = [], np.zeros(5), 0.0
        for L, R, t, r in d["items"]:
            m = fn(L, R, lo, n)
            sc.append(fresh._score(m, t, r))
            c = webcam._where(m, L, t, r)
            counts += c
            if float(t[r].max() - t[r].min()) > 20:
                slant += c[1]
        a = np.array(sc)
        rows.append(
            f"| {name} | {k} | {100 * a[:, 0].mean():.1f} % | {100 * a[:, 1].mean():.2f} % "
            f"({100 * a[:, 1].max():.1f} %) | {100 * a[:, 2].mean():.2f} % | "
            f"{a[:, 3].mean():.3f} |"
        )
        if k in (BEFORE, AFTER, OPENCV):
            bad = max(counts[1], 1.0)
            where.append(
                f"| {name} | {k} | {100 * counts[1] / counts[0]:.2f} % | "
                f"{100 * counts[2] / bad:.0f} % | {100 * counts[3] / bad:.0f} % | "
                f"{100 * slant / bad:.0f} % | {100 * counts[4] / bad:.0f} % |"
            )
    return {f"rows:{name}": rows, f"where:{name}": where}


def _pair_rows(pairs: dict[str, dict[str, Any]], methods: tuple[str, ...]) -> list[str]:
    rows = []
    means: dict[str, list[tuple[float, ...]]] = {}
    for name, p in pairs.items():
        for k in methods:
            s = depth._scores(METHODS[k](p["left"], p["right"], 0, p["n"]), p)
            means.setdefault(k, []).append(s)
            rows.append(
                f"| {name} | {k} | {100 * s[0]:.1f} % | {100 * s[1]:.2f} % | "
                f"{100 * s[3]:.2f} % | {s[4]:.3f} |"
            )
    for k, v in means.items():
        a = np.array(v)
        rows.append(
            f"| mean of {len(v)} | {k} | {100 * a[:, 0].mean():.1f} % | "
            f"{100 * a[:, 1].mean():.2f} % | {100 * a[:, 3].mean():.2f} % | {a[:, 4].mean():.3f} |"
        )
    return rows


def _middlebury(mb: Path, acv: Path) -> dict[str, dict[str, Any]]:
    pairs = {"adirondack": depth._middlebury(mb, "Adirondack", "Adirondack_right.png", 64, 0.5)}
    pairs["cones"] = depth._middlebury(mb, "cones", "cones_right.png", 64, 0.0)
    pairs["cones"]["truth"] = depth._png(acv / "cones" / "disp2.png") / 4
    for name in depth.PAIRS_2003:
        pairs[name] = depth._pair_2003(acv, name)
    return pairs


def _halve(a: np.ndarray) -> np.ndarray:
    h, w = (a.shape[0] // 2) * 2, (a.shape[1] // 2) * 2
    return a[:h, :w].reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3))


def _argoverse(folder: Path) -> dict[str, Any]:
    from PIL import Image

    got = fresh._digest(folder)
    if got != HELDOUT_DIGEST:
        raise SystemExit(f"{folder}: SHA-256 digest {got}, expected {HELDOUT_DIGEST}")

    def grey(f: str) -> np.ndarray:
        g = _halve(np.asarray(Image.open(folder / f).convert("L"), dtype=np.float64))
        return np.clip(np.round(g), 0, 255).astype(np.uint8)

    raw = np.asarray(Image.open(folder / "disparity.png"), dtype=np.float64) / 256.0
    known = _halve((raw > 0).astype(np.float64))
    truth = np.where(known > 0, _halve(raw) / np.maximum(known, 1e-9) / 2.0, 0.0)
    n = int(16 * np.ceil((truth.max() + 1) / 16))
    return {
        "left": grey("left.jpg"),
        "right": grey("right.jpg"),
        "truth": truth,
        "mask": truth > 0,
        "n": n,
    }


def _heldout_lines(folder: Path) -> list[str]:
    p = _argoverse(folder)
    h, w = p["left"].shape
    region = depth._region(p)
    return [
        f"Held out, run once with the final code: argoverse (argoverse/argoverse-api, "
        f"{w} x {h} after halving), disparities 0 to {p['n'] - 1}, {int(region.sum())} pixels "
        f"with a LiDAR truth off the left band (truth {p['truth'][region].min():.1f} to "
        f"{p['truth'][region].max():.1f} px); folder digest {HELDOUT_DIGEST} (frozen before "
        "the run):",
        "",
        "| pair | method | density | > 1 px | > 3 px | MAE px |",
        "|---|---|---:|---:|---:|---:|",
        *[r for r in _pair_rows({"argoverse": p}, FINAL) if not r.startswith("| mean")],
    ]


def _cpu(fn: Fn, pairs: list[tuple[np.ndarray, np.ndarray, int, int]]) -> float:
    t = time.process_time()
    for L, R, lo, n in pairs:
        fn(L, R, lo, n)
    return time.process_time() - t


def _time_lines(args: Any) -> list[str]:
    sets: dict[str, list[tuple[np.ndarray, np.ndarray, int, int]]] = {}
    for b in BOARDS:
        d = webcam._boards(args.fresh, b, args.cache)
        sets[b] = [(L, R, d["lo"], d["n"]) for L, R, *_ in d["items"][:2]]
    p = depth._middlebury(args.middlebury, "Adirondack", "Adirondack_right.png", 64, 0.5)
    sets["adirondack"] = [(p["left"], p["right"], 0, 64)]
    lines = []
    for name, prs in sets.items():
        ts: dict[str, list[float]] = {k: [] for k in (BEFORE, AFTER, OPENCV)}
        for _ in range(args.runs):
            for k in ts:
                ts[k].append(_cpu(METHODS[k], prs))
        a, b, c = (float(np.median(ts[k])) for k in (BEFORE, AFTER, OPENCV))
        lines.append(
            f"| {name} | {prs[0][3]} | {a:.3f} | {b:.3f} | {c:.3f} | {b / a:.2f} | {b / c:.2f} |"
        )
    return lines


def _part(name: str, args: Any) -> dict[str, list[str]]:
    if name in BOARDS:
        return _board_part(name, webcam._boards(args.fresh, name, args.cache))
    if name == "middlebury":
        return {"middlebury": _pair_rows(_middlebury(args.middlebury, args.middlebury_2003),
                                         tuple(METHODS))}  # fmt: skip
    if name == "0506":
        return {"0506": _pair_rows(noise._heldout(args.scenes_0506), tuple(METHODS))}
    if name == "heldout":
        return {"heldout": _heldout_lines(args.heldout)}
    if name == "time":
        return {"time": _time_lines(args)}
    raise SystemExit(f"unknown part {name!r}")


def _report(parts: dict[str, list[str]], load0: str, runs: int) -> str:
    import cv2

    head = "| set | method | density | > 1 px (worst) | > 3 px | MAE px |"
    lines = [
        "# Stereo matching on slanted surfaces: the plane of a flat region's rim",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no median, no speckle filter; imageform's defaults (the graded "
        "census, census_step 4, its costs summed over 3 x 3 pixels) but where a row says "
        "otherwise; before: plane_fill=False (main at bd91c74f); OpenCV: P1 8·25, P2 32·25, "
        f"MODE_HH; benchmarks/check_stereo_slant.py names the data; load before: {load0}.",
        "",
        "Where the > 1 px errors lie on the board pairs (tuning; pooled pixels; as in "
        "stereo-webcam-2026-11-30g.md): the share of the board's valid pixels more than 1 px "
        "off its plane, and of those errors the shares in flat regions (5 x 5 standard "
        "deviation under 3 grey levels), within 15 px of the scored region's border, on "
        "pairs whose board's disparity varies by more than 20 px (slanted), and isolated:",
        "",
        "| set | method | > 1 px | in flat regions | near the border | on slanted boards "
        "| isolated pixels |",
        "|---|---|---:|---:|---:|---:|---:|",
        *[x for b in BOARDS for x in parts.get(f"where:{b}", [])],
        "",
        "Board pairs against the board's plane (tuning: seen before; inside the outer corners "
        "shrunk by 10 %), the mean over the pairs (worst pair's > 1 px in brackets):",
        "",
        head,
        "|---|---|---:|---:|---:|---:|",
        *[x for b in BOARDS for x in parts.get(f"rows:{b}", [])],
        "",
        "Middlebury 2003 / 2014 pairs (tuning: seen before; scored as in "
        "stereo-depth-2026-11-30e.md, non-occluded pixels off the invalid band):",
        "",
        "| pair | method | density | > 1 px | > 3 px | MAE px |",
        "|---|---|---:|---:|---:|---:|",
        *parts.get("middlebury", []),
        "",
        "Middlebury 2005 / 2006 scenes at half size (tuning now: the held-out set of "
        "stereo-noise-2026-11-30e.md, spent there; scored as there):",
        "",
        "| pair | method | density | > 1 px | > 3 px | MAE px |",
        "|---|---|---:|---:|---:|---:|",
        *parts.get("0506", []),
    ]
    if "heldout" in parts:
        lines += ["", *parts["heldout"], "", "The held-out files' SHA-256 (frozen before the run):"]
        lines += ["", "```", *HELDOUT_FILES, "```"]
    lines += [
        "",
        f"CPU time of the matching alone, one thread each, median of {runs} interleaved "
        "runs on the first two pairs of each board set and on Adirondack:",
        "",
        "| set | disparities | before s | after s | OpenCV MODE_HH s | after / before "
        "| after / OpenCV |",
        "|---|---:|---:|---:|---:|---:|---:|",
        *parts.get("time", []),
        "",
        f"load after: {_load()}",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import json

    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fresh", type=Path, help="check_stereo_fresh.py's folder")
    ap.add_argument("--cache", type=Path, help="the rectified board pairs, pickled")
    ap.add_argument("--middlebury", type=Path, help="2b-t's data/ folder")
    ap.add_argument("--middlebury-2003", type=Path, help="acv's hw4/testdata/")
    ap.add_argument("--scenes-0506", type=Path, help="check_stereo_noise.py's --heldout folder")
    ap.add_argument("--heldout", type=Path, help="the held-out folder (run once)")
    ap.add_argument("--runs", type=int, default=5, help="timed runs of each matcher")
    ap.add_argument("--part", help="one part only (a board set, middlebury, 0506, heldout, time)")
    ap.add_argument("--merge", type=Path, nargs="+", help="the parts' JSON files to print")
    ap.add_argument("--load", default="", help="with --merge: the load before the parts ran")
    ap.add_argument("--out", type=Path, help="write the markdown tables (or the part) here")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    if args.merge:
        parts: dict[str, list[str]] = {}
        for f in args.merge:
            parts.update(json.loads(f.read_text(encoding="utf-8")))
        text = _report(parts, args.load, args.runs)
    else:
        z = np.zeros((40, 60))
        stereo_disparity(z, z, num_disparities=16)
        load0 = _load()
        names = [args.part] if args.part else [*BOARDS, "middlebury", "0506", "time"]
        if not args.part and args.heldout is not None:
            names.insert(-1, "heldout")
        parts = {}
        for name in names:
            parts.update(_part(name, args))
        if args.part:
            if args.out is not None:
                args.out.write_text(json.dumps(parts), encoding="utf-8")
            return
        text = _report(parts, load0, args.runs)
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
