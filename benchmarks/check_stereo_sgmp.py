"""Slant-aware aggregation in SGM: a second pass whose paths follow the first map's slants.

``stereo_disparity(slant_prior=True)`` runs the 8-path aggregation twice on the same costs.
The first map (its flat regions given the plane fill) gives each pixel the slant of the
least-squares plane of the valid disparities in the 9 x 9 window about it, where that plane
fits them (root mean square residual under ``SLANT_FIT`` px). The second pass compares each
path's ``L_r(p, d)`` with ``L_r(p - r, d - g_r(p))``, ``g_r`` the slant's change of the
disparity along the step ``r`` (fractional shifts interpolated linearly): a slanted surface
costs no ``P1`` steps along the paths (SGM-P, D. Scharstein, T. Taniai, S. Sinha, "Semi-global
stereo matching with surface orientation priors", 3DV 2017, with the priors taken from the
first pass instead of another sensor). The plane fill then runs on the second map.

Rows: **before** the defaults of main (``slant_prior=False``); **after** ``slant_prior=True``;
OpenCV's ``StereoSGBM`` ``MODE_HH`` at matched settings (block 5, ``P1 = 8·25``,
``P2 = 32·25``, uniqueness 10 %, ``disp12MaxDiff`` 1, no speckle filter).

Tuning data: every set of ``check_stereo_recess.py`` (seen before) and, fresh, 7 MPI-Sintel
stereo training pairs (1024 x 436, synthetic, dense truth, occlusion masks) shipped in
github.com/MinluLi/semi_global_match (commit ed77310, ``sgm_project/data/sintel/``:
``N-imgL.ppm``, ``N-imgR.ppm``, ``N-gt.float3``, ``N-occ.pgm``; scored on the non-occluded
pixels off the left band; Sintel's licence is for research use, the files stay out of this
repository). Held out (fresh, split by repository before anything ran, frozen by SHA-256 in
the results file, run once with the final code, ``--heldout``):

- github.com/gkouros/intro-to-cv-ud810 (commit efede1b), ``ps2_python/input/``: Middlebury
  2005 Art (``pair1-L.png``, ``pair1-R.png``, truth ``pair1-D_L.png``) and Laundry
  (``pair2-*``), resized to 640 px wide; the truth's grey levels are full-size disparities
  (Middlebury's ``disp1.png``), scaled here by the width ratio (640 / 1390 and 640 / 1342;
  that scale was checked on the truth alone before the split was frozen: the right image
  warped by it matches the left best, median absolute difference 3.2 grey levels against 7
  at a scale of 0.5); scored on the truth's non-zero pixels off the left band.
- github.com/todavis/stereo-correspondence (commit 38d7ea4), ``stereo/kitti/``: KITTI 2012
  training pair 000070 (``image_0``, ``image_1``; truth ``disp_noc`` / 256, LiDAR, sparse);
  scored on its non-zero pixels off the left band.

Disparities searched: 0 to the truth's largest + 1 rounded up to 16 on Sintel and the
held-out pairs. Put the files as ``--sintel DIR`` (``N-imgL.ppm`` ...) and ``--heldout DIR``
(``ud810/{art,laundry}-{L,R,D_L}.png``, ``kitti070/{image_0,image_1,disp_noc}.png``).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_sgmp.py --fresh /tmp/stereog/data/fresh \\
        --cache /tmp/stereog/cache --middlebury /tmp/stereog/data/mb \\
        --middlebury-2003 /tmp/stereog/data/acv --scenes-0506 /tmp/stereog/data/ho0506 \\
        --eth3d /tmp/stereoh2/heldout/eth3d --sintel /tmp/stereoh4/tune/sintel \\
        --out benchmarks/results/stereo-sgmp-2026-12-01a.md
    ... python benchmarks/check_stereo_sgmp.py --curved --scenes-0506 /tmp/stereog/data/ho0506 \\
        --out benchmarks/results/stereo-sgmp-2026-12-01b.md
    # once, at the end:
    ... python benchmarks/check_stereo_sgmp.py --heldout /tmp/stereoh4/heldout \\
        --out benchmarks/results/stereo-sgmp-2026-12-01c.md
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import check_stereo_fresh as fresh  # noqa: E402
import check_stereo_recess as recess  # noqa: E402
import check_stereo_slant as slant  # noqa: E402

from imageform.geometry import stereo_disparity  # noqa: E402

BEFORE = "imageform before (slant_prior=False)"
AFTER = "imageform after (slant_prior=True)"
OPENCV = "OpenCV SGBM MODE_HH"
METHODS = (BEFORE, AFTER, OPENCV)
Fn = Any
#: one pair: name, left, right, first disparity, number, truth, scored pixels
Pair = tuple[str, np.ndarray, np.ndarray, int, int, np.ndarray, np.ndarray]

#: SHA-256 of the held-out files, frozen before any matcher ran on them
HELDOUT_SHA256 = {
    "kitti070/disp_noc.png": "809a165396035442ae06a330ace3d1f804c64c2c8b57e2592d053eb871285549",
    "kitti070/image_0.png": "584248c8ead36379489f4e0961c87d9689560f4cb26cfda6a82003a974ec0335",
    "kitti070/image_1.png": "18cfdd3e8395d3ca290b9a260e703dbf39ab8486cad486c07ebb5fe3646c6d4e",
    "ud810/art-D_L.png": "84a0a302cf12ed2f2325a44c882b24baca4b08d58412ab410dc8ae2834be811f",
    "ud810/art-L.png": "454fe4bfa4abe35c1997c858f2dc28a2371bd1fba1403af0282f30a2032ceea7",
    "ud810/art-R.png": "82dd658e2feea39a18630ed7c9150118d13de17f2987e77b2e2104f9b64fb834",
    "ud810/laundry-D_L.png": "1f32a272b20965cd3400fcfff01e2c34ed2e7e00594afcf89daf3f9fc290d8b5",
    "ud810/laundry-L.png": "b74e93b52fb48cbaf6edd60520c4d543a768db1f490f7165fec72033db523cf6",
    "ud810/laundry-R.png": "fdb0d591d63477de6c38536230e3b95d7781fe8392068a0d80a819d5125fb88a",
}
#: full-size widths of the Middlebury 2005 scenes the ud810 pairs were resized from
FULL_WIDTH = {"art": 1390, "laundry": 1342}


def _ours(prior: bool) -> Fn:
    def fn(L: np.ndarray, R: np.ndarray, lo: int, n: int) -> np.ndarray:
        return stereo_disparity(L, R, min_disparity=lo, num_disparities=n, slant_prior=prior)

    return fn


RUN: dict[str, Fn] = {BEFORE: _ours(False), AFTER: _ours(True), OPENCV: fresh._sgbm}


def _range(truth: np.ndarray) -> int:
    return int(np.ceil((float(np.nanmax(truth)) + 1.0) / 16.0) * 16)


def _banded(valid: np.ndarray, n: int) -> np.ndarray:
    region = valid.copy()
    region[:, :n] = False
    return region


def _float3(path: Path) -> np.ndarray:
    """A CMatrix ``float3`` file: ``float\\n2\\nW\\nH\\n`` then W x H little-endian floats."""
    raw = path.read_bytes()
    parts = raw.split(b"\n", 4)
    w, h = int(parts[2]), int(parts[3])
    return np.frombuffer(parts[4][: w * h * 4], "<f4").reshape(h, w).astype(np.float32)


def _sintel(folder: Path) -> list[Pair]:
    import cv2

    out = []
    for i in range(1, 8):
        L = cv2.imread(str(folder / f"{i}-imgL.ppm"))
        R = cv2.imread(str(folder / f"{i}-imgR.ppm"))
        t = _float3(folder / f"{i}-gt.float3")
        occ = cv2.imread(str(folder / f"{i}-occ.pgm"), cv2.IMREAD_GRAYSCALE)
        n = _range(t)
        out.append((f"sintel-{i}", L, R, 0, n, t, _banded((occ == 0) & np.isfinite(t), n)))
    return out


def _check(folder: Path) -> None:
    for rel, digest in HELDOUT_SHA256.items():
        got = hashlib.sha256((folder / rel).read_bytes()).hexdigest()
        if got != digest:
            raise SystemExit(f"{folder / rel}: SHA-256 {got}, frozen {digest}")


def _heldout(folder: Path) -> dict[str, list[Pair]]:
    import cv2

    _check(folder)
    mb = []
    for name, full in FULL_WIDTH.items():
        L = cv2.imread(str(folder / f"ud810/{name}-L.png"))
        R = cv2.imread(str(folder / f"ud810/{name}-R.png"))
        raw = cv2.imread(str(folder / f"ud810/{name}-D_L.png"), cv2.IMREAD_GRAYSCALE)
        t = raw.astype(np.float32) * np.float32(L.shape[1] / full)
        t[raw == 0] = np.nan
        n = _range(t)
        mb.append((name, L, R, 0, n, t, _banded(raw > 0, n)))
    L = cv2.imread(str(folder / "kitti070/image_0.png"), cv2.IMREAD_GRAYSCALE)
    R = cv2.imread(str(folder / "kitti070/image_1.png"), cv2.IMREAD_GRAYSCALE)
    raw = cv2.imread(str(folder / "kitti070/disp_noc.png"), cv2.IMREAD_UNCHANGED)
    t = raw.astype(np.float32) / 256.0
    t[raw == 0] = np.nan
    n = _range(t)
    kitti = [("kitti2012-000070", L, R, 0, n, t, _banded(raw > 0, n))]
    return {"ud810 (Middlebury 2005, 640 px)": mb, "todavis (KITTI 2012)": kitti}


def _tuning(args: Any) -> dict[str, list[Pair]]:
    sets, names = recess._sets(args)
    out: dict[str, list[Pair]] = {}
    for s, items in sets.items():
        nm = names.get(s, [f"{s} {i}" for i in range(len(items))])
        out[s] = [(k, *it) for k, it in zip(nm, items, strict=True)]
    out["sintel (fresh)"] = _sintel(args.sintel)
    return out


def _table(sets: dict[str, list[Pair]], maps: dict[str, list[dict[str, np.ndarray]]]) -> list[str]:
    """Per set the mean over its pairs (worst pair's > 1 px in brackets); pairs one by one
    for the sets of a few pairs."""
    lines = [
        "| set / pair | method | density | > 1 px (worst) | > 3 px | MAE px |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for s, items in sets.items():
        for k in METHODS:
            sc = np.array(
                [fresh._score(m[k], p[5], p[6]) for p, m in zip(items, maps[s], strict=True)]
            )
            lines.append(
                f"| **{s}** ({len(items)}) | {k} | {100 * sc[:, 0].mean():.1f} % | "
                f"{100 * sc[:, 1].mean():.2f} % ({100 * sc[:, 1].max():.1f} %) | "
                f"{100 * sc[:, 2].mean():.2f} % | {sc[:, 3].mean():.3f} |"
            )
        if len(items) > 8:
            continue
        for p, m in zip(items, maps[s], strict=True):
            for k in METHODS:
                sc1 = fresh._score(m[k], p[5], p[6])
                lines.append(
                    f"| {p[0]} | {k} | {100 * sc1[0]:.1f} % | {100 * sc1[1]:.2f} % | "
                    f"{100 * sc1[2]:.2f} % | {sc1[3]:.3f} |"
                )
    return lines


def _times(sets: dict[str, list[Pair]], runs: int) -> list[str]:
    pick: dict[str, list[Pair]] = {b: sets[b][:2] for b in recess.BOARDS if b in sets}
    for s, i, nm in (
        ("middlebury 2003 / 2014", 0, "adirondack"),
        ("eth3d", 0, "terrace"),
        ("sintel (fresh)", 0, "sintel-1"),
    ):
        if s in sets:
            pick[nm] = [sets[s][i]]
    for s, items in sets.items():
        if s not in recess.BOARDS and not s.startswith(("middlebury", "eth3d", "sintel")):
            pick[s] = items
    lines = []
    for name, prs in pick.items():
        ts: dict[str, list[float]] = {k: [] for k in METHODS}
        four = [p[1:5] for p in prs]
        for _ in range(runs):
            for k in METHODS:
                ts[k].append(slant._cpu(RUN[k], four))
        a, b, o = (float(np.median(ts[k])) for k in METHODS)
        lines.append(
            f"| {name} | {prs[0][4]} | {a:.3f} | {b:.3f} | {o:.3f} | {b / a:.2f} | {b / o:.2f} |"
        )
    return lines


def _curved(args: Any) -> list[str]:
    """The flat regions of the Middlebury 2005 / 2006 scenes whose fill moved 20 or more
    scored pixels across the 1 px line: how well a plane and a quadratic fit their truth."""
    import check_stereo_noise as noise
    import check_stereo_planes as planes

    from imageform.geometry import stereo_matching as sm

    lines = [
        "| scene | region px | > 1 px: no fill -> fill | with slant_prior | truth's range px "
        "| truth's plane RMS px | truth's quadratic RMS px |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, p in noise._heldout(args.scenes_0506).items():
        L, R, n, t = p["left"], p["right"], p["n"], p["truth"]
        r = recess.depth._region(p)
        lab = planes._flat_regions(sm._grey(L, "left"))
        maps = [
            stereo_disparity(L, R, num_disparities=n, **kw)
            for kw in ({"plane_fill": False}, {}, {"slant_prior": True})
        ]
        m = int(lab.max()) + 1
        bad = [
            np.bincount(lab[np.isfinite(d) & ~(np.abs(d - t) <= 1) & r], minlength=m) for d in maps
        ]
        area = np.bincount(lab.ravel(), minlength=m)
        for k in np.nonzero(np.abs(bad[1] - bad[0]) >= 20)[0]:
            if k == 0:
                continue
            ys, xs = np.nonzero((lab == k) & r & np.isfinite(t))
            if ys.size < 10:
                continue
            z = t[ys, xs].astype(np.float64)
            X = np.column_stack([xs, ys, np.ones(xs.size)]).astype(np.float64)
            X2 = np.column_stack([X, xs * xs, xs * ys, ys * ys]).astype(np.float64)
            rms = [
                float(np.sqrt(np.mean((z - A @ np.linalg.lstsq(A, z, rcond=None)[0]) ** 2)))
                for A in (X, X2)
            ]
            lines.append(
                f"| {name} | {area[k]} | {bad[0][k]} -> {bad[1][k]} | {bad[2][k]} | "
                f"{np.ptp(z):.1f} | {rms[0]:.2f} | {rms[1]:.2f} |"
            )
    return lines


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fresh", type=Path, help="check_stereo_fresh.py's folder")
    ap.add_argument("--cache", type=Path, help="the rectified board pairs, pickled")
    ap.add_argument("--middlebury", type=Path, help="2b-t's data/ folder")
    ap.add_argument("--middlebury-2003", type=Path, help="acv's hw4/testdata/")
    ap.add_argument("--scenes-0506", type=Path, help="the 2005 / 2006 scenes")
    ap.add_argument("--eth3d", type=Path, help="check_stereo_planes' --heldout")
    ap.add_argument("--sintel", type=Path, help="MinluLi/semi_global_match's data/sintel/")
    ap.add_argument("--heldout", type=Path, help="the held-out pairs (run once, at the end)")
    ap.add_argument("--runs", type=int, default=3, help="timed runs of each matcher")
    ap.add_argument(
        "--curved", action="store_true", help="the 2005 / 2006 flat regions' table alone"
    )
    ap.add_argument("--out", type=Path, help="write the markdown tables here")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    z = np.zeros((40, 60))
    stereo_disparity(z, z, num_disparities=16, slant_prior=True)
    load0 = slant._load()
    t0 = time.time()
    if args.curved:
        text = "\n".join(
            [
                "# Stereo: the plane fill on curved surfaces (Middlebury 2005 / 2006, tuning)",
                "",
                "The flat regions (as the plane fill finds them) of the six 2005 / 2006 scenes "
                "of check_stereo_noise.py at half size whose fill moved 20 or more scored "
                "pixels across the 1 px line (no fill -> fill), the same count with "
                "slant_prior=True (and the fill), and the least-squares plane's and "
                "quadratic's root mean square residual on the region's truth (a curved "
                "surface: the quadratic fits much better); benchmarks/check_stereo_sgmp.py "
                f"--curved; load before: {load0}.",
                "",
                *_curved(args),
                "",
                f"load after: {slant._load()}",
            ]
        )
        print(text)
        if args.out is not None:
            args.out.write_text(text + "\n", encoding="utf-8")
        return
    sets = _heldout(args.heldout) if args.heldout else _tuning(args)
    maps = {s: [{k: RUN[k](*p[1:5]) for k in METHODS} for p in items] for s, items in sets.items()}
    what = (
        "HELD OUT (fresh, frozen by SHA-256 below, run once with the final code)"
        if args.heldout
        else "tuning data (the sets of check_stereo_recess.py, seen before, and 7 fresh "
        "MPI-Sintel pairs)"
    )
    lines = [
        "# Stereo: slant-aware aggregation (a second SGM pass along the first map's slants)",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no median, no speckle filter; imageform's defaults (graded "
        "census, 3 x 3 cost window, plane fill) but where a row says otherwise; OpenCV: P1 "
        "8·25, P2 32·25, MODE_HH; benchmarks/check_stereo_sgmp.py names the data; "
        f"{what}; load before: {load0}.",
        "",
        "Share of the scored pixels more than 1 px / 3 px off the truth, of the valid ones "
        "(boards: against the board's plane, inside the outer corners shrunk by 10 %):",
        "",
        *_table(sets, maps),
    ]
    if args.heldout:
        lines += [
            "",
            "Held-out files (SHA-256, frozen before any run):",
            "",
            *[f"- `{k}` {v}" for k, v in HELDOUT_SHA256.items()],
        ]
    lines += [
        "",
        f"CPU time of the matching alone, one thread each, median of {args.runs} interleaved "
        "runs (board sets: their first two pairs):",
        "",
        "| pairs | disparities | before s | after s | OpenCV s | after / before | after / OpenCV |",
        "|---|---:|---:|---:|---:|---:|---:|",
        *_times(sets, args.runs),
        "",
        f"load after: {slant._load()}; wall {time.time() - t0:.0f} s",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
