"""The graded census against the plain one on flat, noisy real pairs; tuning / held out.

``stereo_disparity``'s plain census (one bit per neighbour, set where it is darker than the
centre) reads differences of a grey level or two as texture: in flat regions (a board's
squares, a dim endoscope's tissue, a wall) the bits follow each sensor's own faint shading and
noise, and the disparities scatter (``stereo-fresh-2026-11-30e.md``: 33.6 % of a da Vinci
endoscope's board pixels more than 1 px off the board's plane, OpenCV's StereoSGBM 13.6 %). A
threshold (``census_threshold``) drops those bits but also the fine texture of low contrast
that Middlebury's scenes match on. The graded census (``census_step``, two bits a neighbour:
darker, and darker by more than the step) keeps both: a difference within the step costs one
bit, a larger one two.

Candidates measured here on the tuning data (the figures are this script's tables):

- **plain**: ``census_step=None`` (the default before).
- **threshold 4**: ``census_step=None, census_threshold=4`` (the opt-in of before).
- **graded, step 2, 4, 8**: ``census_step`` 2, 4 (the new default), 8.
- **AD-Census** (X. Mei et al., "On building an accurate stereo matching system on graphics
  hardware", ICCV Workshops 2011): the census's Hamming distance and the absolute grey
  difference through robust exponentials, summed (lambda 12 for the 24 bits, 20 grey levels;
  prototyped here on the library's kernels: of 12 / 10, 12 / 20 and 8 / 5 tried, the best).
- OpenCV's Birchfield-Tomasi costs on Sobel-prefiltered images are OpenCV's own row.
- **noise-adaptive threshold** (``threshold = c sigma``): the table of noise estimates shows
  why it is not kept: the sigma of the pairs where the plain census fails (the endoscope's,
  0.0 to 0.2 grey levels: its bilinearly rectified, dim images) is the lowest of all, the
  Middlebury pairs the threshold harms have the largest. sigma: J. Immerkaer's 1996 operator
  (the 3 x 3 difference of two Laplacians, ``sqrt(36) sigma`` for white noise), as his mean
  absolute value and as the median absolute value / 0.6745 (robust to edges).

Data (none of it in this repository):

- tuning, as ``check_stereo_fresh.py`` names them (``--fresh``, its folder): ``davinci``
  (40 board pairs of a da Vinci endoscope, truth the board's plane) and ``urban`` (4 LIBELAS
  street pairs, no truth: density, agreement with OpenCV); as ``check_stereo_depth.py``
  (``--middlebury``, ``--middlebury-2003``): Adirondack (and its exposure pair), cones, teddy,
  venus, tsukuba, the rendered pair.
- secondary (spent: their figures were seen before, by the census_threshold work):
  ``webcam-1``, ``webcam-2``, ``ximea`` board sets of ``check_stereo_fresh.py``.
- held out (``--heldout``, fixed with its digests below before anything was run on it):
  Middlebury's 2005 / 2006 scenes (D. Scharstein & C. Pal, CVPR 2007; H. Hirschmüller &
  D. Scharstein, CVPR 2007) at half size (height 555), as kept in
  github.com/omkarbhoite25/3D-Sensing-Sensor-Fusion, commit 3e85948, ``Input_Images/``:
  Aloe, Baby1, Bowling1, Cloth1, Flowerpots, Rocks1 (``view1.png`` left, ``view5.png``
  right, ``disp1.png`` the left truth in half pixels: value / 2; 0 unknown), put as
  ``view1.png``, ``view5.png``, ``disp1.png`` in a folder of the scene's name in lower case
  (Baby1's and Bowling1's and Cloth1's ``disp1.png`` lie in the repository's ``Baby/Baby/``,
  ``Bowling/Bowling/``, ``Cloth/Cloth/``, beside a ``view1.png`` identical to theirs).
  Middlebury grants permission to use and publish its images; the repository states no
  licence of its own. Its Art and Books are full size (1390 x 1110, some 250 disparities:
  over 1 GB of costs) and were left out before any run; its cones is a tuning pair. Scored
  as the 2003 pairs of ``check_stereo_depth.py``: the pixels with a truth that the right camera
  sees, off the left band of ``num_disparities`` columns (``num_disparities``: the truth's
  largest disparity + 1 rounded up to 16).

Time: the matching alone, one thread, the process's CPU time, the median of interleaved runs
of the graded and the plain census (the machine is shared: its load is printed).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_noise.py --fresh /tmp/stereofresh \\
        --middlebury /tmp/stereofast/mb --middlebury-2003 /tmp/stereodense/acv \\
        --half tuning

    ... --heldout /tmp/stereonoise/heldout --half all \\
        --out benchmarks/results/stereo-noise-2026-11-30e.md

(``stereo-noise-2026-11-30g.md``: ``--half held-out`` with ``cost_window=3``, the costs summed
over 3 x 3 pixels, as the default, beside ``cost_window=1``, the default before: the held-out
tables alone, the tuning ones being ``check_stereo_webcam.py``'s.)
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

from imageform.geometry import (  # noqa: E402
    checkerboard_points,
    rectification_map,
    remap_bilinear,
    stereo_calibrate,
    stereo_disparity,
    stereo_rectify,
)

#: held-out scenes: folder -> SHA-256 of ``sha256sum`` of its three files in byte order
HELDOUT = {
    "aloe": "f7adb66ff5990bd49cf3fe0dc1d3531e34cba33a411c9d3dff11dd0760c63cf3",
    "baby1": "2f27b12281eb8411a207287b15ebfc654b8ebb5e80a77fab5323061c0471fbe4",
    "bowling1": "f2e3d84a88e92314f7b69d4eb00b9cd2c1d80d656ef659da8b5f9d84d970e26f",
    "cloth1": "d70d7c47c84de908b3b925b607781b5fad20ed4b422df394f12235e5a353f6d8",
    "flowerpots": "a79e4efb0ae8b938a3b0c8ec6faf11384374105b37b9d02164a43df1f8d0ec38",
    "rocks1": "bbf86961ad54c690ff8c939fc1d0c5f706ef85dec2d86644473857dccebdb93f",
}

Fn = Any  # (left, right, min_disparity, num_disparities) -> disparity map


def _ours(**kw: Any) -> Fn:
    def fn(L: np.ndarray, R: np.ndarray, lo: int, n: int) -> np.ndarray:
        return stereo_disparity(L, R, min_disparity=lo, num_disparities=n, **kw)

    return fn


def _ad_census(lam_census: float = 12.0, lam_ad: float = 20.0) -> Fn:
    """AD-Census (X. Mei et al., ICCV Workshops 2011) on the library's kernels: the 5 x 5
    census's Hamming distance and the absolute grey difference, each through
    ``1 - exp(-c / lambda)``, summed, on 0-48 (the graded census's range and penalties)."""
    from imageform._kernels import sgm

    def fn(L: np.ndarray, R: np.ndarray, lo: int, n: int) -> np.ndarray:
        gl = np.ascontiguousarray(L, np.float32)
        gr = np.ascontiguousarray(R, np.float32)
        h, w = gl.shape
        z, off = np.float32(0), np.float32(-1)
        cl, cr = sgm.census(gl, 2, z, off), sgm.census(gr, 2, z, off)
        ham = sgm.cost_volume(cl, cr, lo, n, 24, np.empty((h, w, n), np.uint8))
        ham = ham.astype(np.float32)
        ad = np.full((h, w, n), 255.0, np.float32)
        for k in range(n):
            d = lo + k
            if 0 <= d < w:
                ad[:, d:, k] = np.abs(gl[:, d:] - gr[:, : w - d])
            elif -w < d < 0:
                ad[:, : w + d, k] = np.abs(gl[:, : w + d] - gr[:, -d:])
        c = 24 * ((1 - np.exp(-ham / lam_census)) + (1 - np.exp(-ad / lam_ad)))
        cost = np.ascontiguousarray(np.round(c).astype(np.uint8))
        total = np.empty((h, w, n), np.uint16)
        return np.asarray(sgm.match(cost, gl, 16, 64, False, lo, 0.1, 1.0, total, True))

    return fn


#: the tuning candidates (name -> matcher), OpenCV last
TUNING: dict[str, Fn] = {
    "plain census (before)": _ours(census_step=None),
    "plain, threshold 4": _ours(census_step=None, census_threshold=4.0),
    "graded, step 2": _ours(census_step=2.0),
    "graded, step 4 (default)": _ours(),
    "graded, step 4, cost_window 1 (before 2026-11-30g)": _ours(cost_window=1),
    "graded, step 8": _ours(census_step=8.0),
    "AD-Census (lambda 12, 20)": _ad_census(),
    "OpenCV SGBM MODE_HH": fresh._sgbm,
}
#: the secondary and held-out comparison
FINAL = {
    k: TUNING[k]
    for k in (
        "plain census (before)",
        "graded, step 4, cost_window 1 (before 2026-11-30g)",
        "graded, step 4 (default)",
    )
}
FINAL["OpenCV SGBM MODE_HH"] = fresh._sgbm


def _sigma(img: np.ndarray) -> tuple[float, float]:
    """Immerkaer's noise sigma: from the mean and from the median of ``|I * N|``."""
    from scipy.ndimage import convolve

    N = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], dtype=np.float64)
    r = np.abs(convolve(np.asarray(img, np.float64), N, mode="nearest")[1:-1, 1:-1])
    return float(np.sqrt(np.pi / 2) * r.mean() / 6), float(np.median(r) / 0.6745 / 6)


def _boards(folder: Path, name: str) -> dict[str, Any]:
    """The set's rectified board pairs with the board-plane truth (check_stereo_fresh's)."""
    spec = fresh.SETS[name]
    got = fresh._digest(folder)
    if got != spec[6]:
        raise SystemExit(f"{folder}: SHA-256 digest {got}, expected {spec[6]}")
    _, _, lg, rg, board, square, _ = spec
    det = fresh._detect(fresh._pairs(folder, lg, rg), board)
    size = det["size"]
    obj = [checkerboard_points(board, square or 1.0)] * len(det["used"])
    cal = stereo_calibrate(obj, det["left"], det["right"], size)
    rect = stereo_rectify(
        cal.left.K, cal.left.distortion, cal.right.K, cal.right.distortion, size, cal.R, cal.T
    )
    map_l = rectification_map(cal.left.K, cal.left.distortion, rect.R1, rect.P1, size)
    map_r = rectification_map(cal.right.K, cal.right.distortion, rect.R2, rect.P2, size)
    items = []
    for (lf, rf), a, b in zip(det["used"], det["left"], det["right"], strict=True):
        L = np.asarray(remap_bilinear(fresh._grey(lf), map_l, keep_dtype=True))
        R = np.asarray(remap_bilinear(fresh._grey(rf), map_r, keep_dtype=True))
        truth, region, _ = fresh._board_truth(a, b, cal, rect, L.shape, board[0])
        items.append((L, R, truth, region))
    lo_t = min(float(t[r].min()) for _, _, t, r in items)
    hi_t = max(float(t[r].max()) for _, _, t, r in items)
    lo, n = fresh._range(lo_t, hi_t, size[0])
    return {"items": items, "lo": lo, "n": n}


def _board_rows(name: str, data: dict[str, Any], methods: dict[str, Fn]) -> list[str]:
    lo, n = data["lo"], data["n"]
    rows = []
    for k, fn in methods.items():
        sc = np.array([fresh._score(fn(L, R, lo, n), t, r) for L, R, t, r in data["items"]])
        rows.append(
            f"| {name} | {k} | {100 * sc[:, 0].mean():.1f} % | {100 * sc[:, 1].mean():.2f} % "
            f"({100 * sc[:, 1].max():.1f} %) | {100 * sc[:, 2].mean():.2f} % | "
            f"{sc[:, 3].mean():.3f} |"
        )
    return rows


def _urban_rows(folder: Path, methods: dict[str, Fn]) -> tuple[list[str], list[Any]]:
    spec = fresh.SETS["urban"]
    if fresh._digest(folder) != spec[6]:
        raise SystemExit(f"{folder}: SHA-256 digest differs from {spec[6]}")
    pairs = [(fresh._grey(a), fresh._grey(b)) for a, b in fresh._pairs(folder, spec[2], spec[3])]
    cv = [fresh._sgbm(L, R, 0, 64) for L, R in pairs]
    rows = []
    for k, fn in methods.items():
        dens, agree, lr = [], [], []
        for (L, R), c in zip(pairs, cv, strict=True):
            d = fn(L, R, 0, 64)
            dens.append(np.isfinite(d)[:, 63:].mean())
            agree.append(fresh._agree(d, c))
            lr.append(fresh._lr_share(d, fresh._mirror(fn, L, R, 0, 64)))
        rows.append(
            f"| urban (4 pairs) | {k} | {100 * np.mean(dens):.1f} % | "
            f"{100 * np.min(dens):.1f} % | {100 * np.mean(lr):.1f} % | "
            f"{100 * np.mean(agree):.1f} % |"
        )
    return rows, pairs


def _truth_rows(pairs: dict[str, dict[str, Any]], methods: dict[str, Fn]) -> list[str]:
    rows = []
    for name, p in pairs.items():
        for k, fn in methods.items():
            s = depth._scores(fn(p["left"], p["right"], 0, p["n"]), p)
            rows.append(
                f"| {name} | {p['set']} | {k} | {100 * s[0]:.1f} % | {100 * s[1]:.2f} % | "
                f"{100 * s[3]:.2f} % | {s[4]:.3f} |"
            )
    return rows


def _heldout(folder: Path) -> dict[str, dict[str, Any]]:
    out = {}
    for name, want in HELDOUT.items():
        got = fresh._digest(folder / name)
        if got != want:
            raise SystemExit(f"{folder / name}: SHA-256 digest {got}, expected {want}")
        gt = depth._png(folder / name / "disp1.png") / 2.0  # half size: half pixels
        n = int(16 * np.ceil((gt.max() + 1) / 16))
        out[name] = {
            "left": depth._grey(folder / name / "view1.png"),
            "right": depth._grey(folder / name / "view5.png"),
            "truth": gt,
            "mask": depth._visible(gt) & (gt > 0),
            "n": n,
            "set": "held out",
        }
    return out


def _cpu(fn: Fn, pairs: list[tuple[np.ndarray, np.ndarray, int, int]]) -> float:
    t = time.process_time()
    for L, R, lo, n in pairs:
        fn(L, R, lo, n)
    return time.process_time() - t


def _load() -> str:
    return " / ".join(f"{v:.1f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else ""


def _heldout_only(args: Any, load0: str) -> None:
    """Print (and write) the held-out tables alone, the cost_window 1 row beside the default."""
    import cv2

    if args.heldout is None:
        raise SystemExit("--half held-out needs --heldout")
    held = _heldout(args.heldout)
    lines = [
        "# The graded census on the held-out Middlebury 2005 / 2006 scenes, re-run",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no median, no speckle filter (OpenCV: P1 8·25, P2 32·25, "
        "MODE_HH); benchmarks/check_stereo_noise.py --half held-out; load before: "
        f"{load0}. The held-out set of stereo-noise-2026-11-30e.md (spent there), re-run with "
        "the costs summed over 3 x 3 pixels (cost_window 3, the default since 2026-11-30g) "
        "beside cost_window 1 (the default before); the plain census row sums over 3 x 3 too. "
        "Middlebury 2005 / 2006 scenes at half size (truth disp1.png / 2), non-occluded "
        "pixels off the invalid band:",
        "",
        "| pair | set | method | density | > 1 px | > 3 px | MAE px |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    pooled: dict[str, list[tuple[float, ...]]] = {k: [] for k in FINAL}
    for name, p in held.items():
        for k, fn in FINAL.items():
            sc = depth._scores(fn(p["left"], p["right"], 0, p["n"]), p)
            pooled[k].append(sc)
            lines.append(
                f"| {name} | {p['set']} | {k} | {100 * sc[0]:.1f} % | {100 * sc[1]:.2f} % | "
                f"{100 * sc[3]:.2f} % | {sc[4]:.3f} |"
            )
    lines += ["", "| held out, mean of the 6 pairs | density | > 1 px | > 3 px | MAE px |"]
    lines += ["|---|---:|---:|---:|---:|"]
    for k, scs in pooled.items():
        a = np.array(scs).mean(axis=0)
        lines.append(
            f"| {k} | {100 * a[0]:.1f} % | {100 * a[1]:.2f} % | {100 * a[3]:.2f} % | {a[4]:.3f} |"
        )
    lines += ["", f"load after: {_load()}"]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text)


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fresh", type=Path, required=True, help="check_stereo_fresh.py's folder")
    ap.add_argument("--middlebury", type=Path, required=True, help="2b-t's data/ folder")
    ap.add_argument("--middlebury-2003", type=Path, required=True, help="acv's hw4/testdata/")
    ap.add_argument("--heldout", type=Path, help="the held-out scenes' folder")
    ap.add_argument("--half", choices=("tuning", "all", "held-out"), default="tuning")
    ap.add_argument("--runs", type=int, default=5, help="timed runs of each census")
    ap.add_argument("--out", type=Path, help="write the markdown tables here too")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    stereo_disparity(np.zeros((40, 60)), np.zeros((40, 60)), num_disparities=16)  # compile
    stereo_disparity(np.zeros((40, 60)), np.zeros((40, 60)), num_disparities=16, census_step=None)
    load0 = _load()
    if args.half == "held-out":  # the held-out tables alone (a re-run with a later default)
        _heldout_only(args, load0)
        return
    boards = {"davinci": _boards(args.fresh / "davinci", "davinci")}
    mb = args.middlebury
    tuning = {
        "adirondack": depth._middlebury(mb, "Adirondack", "Adirondack_right.png", 64, 0.5),
        "adirondack-exposure": depth._middlebury(
            mb, "Adirondack", "AdirondackE_right.png", 64, 0.5
        ),
        "cones": depth._middlebury(mb, "cones", "cones_right.png", 64, 0.0),
    }
    tuning["cones"]["truth"] = depth._png(args.middlebury_2003 / "cones" / "disp2.png") / 4
    for name in depth.PAIRS_2003:
        tuning[name] = depth._pair_2003(args.middlebury_2003, name)
        tuning[name]["set"] = "tuning"
    tuning["rendered"] = depth._rendered(False)
    lines = [
        "# The graded census on flat, noisy real pairs: tuning and held out",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; block 5, uniqueness 10 %, "
        "left-right check 1 px, no median, no speckle filter (OpenCV: P1 8·25, P2 32·25, "
        "MODE_HH); benchmarks/check_stereo_noise.py names the data; load before: "
        f"{load0}. Every imageform row but the cost_window 1 one sums its costs over 3 x 3 "
        "pixels (cost_window 3, the default since 2026-11-30g; stereo-noise-2026-11-30e.md's "
        "rows are cost_window 1).",
        "",
        "Noise sigma (grey levels) by Immerkaer's operator, the mean of both views (the first "
        "6 pairs of a board set): from the mean of its absolute value and from its median "
        "(robust to edges):",
        "",
        "| set | sigma, mean | sigma, median |",
        "|---|---:|---:|",
    ]
    sig_sets: dict[str, list[np.ndarray]] = {
        "davinci": [x for L, R, *_ in boards["davinci"]["items"][:6] for x in (L, R)],
    }
    for k in ("adirondack", "cones", "teddy", "venus", "tsukuba"):
        sig_sets[k] = [tuning[k]["left"], tuning[k]["right"]]
    urban_rows, urban_pairs = _urban_rows(args.fresh / "urban", TUNING)
    sig_sets["urban"] = [x for pr in urban_pairs for x in pr]
    for k, imgs in sig_sets.items():
        s = np.array([_sigma(x) for x in imgs]).mean(axis=0)
        lines.append(f"| {k} | {s[0]:.2f} | {s[1]:.2f} |")
    lines += [
        "",
        "Tuning, board pairs against the board's plane (inside the outer corners shrunk by "
        "10 %), the mean over the pairs (worst pair's > 1 px in brackets):",
        "",
        "| set | method | density | > 1 px (worst) | > 3 px | MAE px |",
        "|---|---|---:|---:|---:|---:|",
        *_board_rows("davinci", boards["davinci"], TUNING),
        "",
        "Tuning, street pairs without a truth (64 disparities, right of the invalid band): "
        "density (mean, least), left-right consistent (the right view's own map within 1 px), "
        "agreement with OpenCV (within 1 px where both are valid):",
        "",
        "| set | method | density | least | left-right consistent | agreement with OpenCV |",
        "|---|---|---:|---:|---:|---:|",
        *urban_rows,
        "",
        "Tuning, Middlebury and the rendered pair (scored as in stereo-depth-2026-11-30d.md: "
        "non-occluded pixels off the invalid band):",
        "",
        "| pair | set | method | density | > 1 px | > 3 px | MAE px |",
        "|---|---|---|---:|---:|---:|---:|",
        *_truth_rows(tuning, TUNING),
    ]
    if args.half == "all":
        sec = {k: _boards(args.fresh / k, k) for k in ("webcam-1", "webcam-2", "ximea")}
        lines += [
            "",
            "Secondary (spent: seen before by the census_threshold work), the board sets of "
            "check_stereo_fresh.py, as the tuning boards:",
            "",
            "| set | method | density | > 1 px (worst) | > 3 px | MAE px |",
            "|---|---|---:|---:|---:|---:|",
        ]
        for k, data in sec.items():
            lines += _board_rows(k, data, FINAL)
        if args.heldout is None:
            raise SystemExit("--half all needs --heldout")
        held = _heldout(args.heldout)
        lines += [
            "",
            "Held out, run once with the final code: Middlebury 2005 / 2006 scenes at half "
            "size (truth disp1.png / 2), non-occluded pixels off the invalid band:",
            "",
            "| pair | set | method | density | > 1 px | > 3 px | MAE px |",
            "|---|---|---|---:|---:|---:|---:|",
            *_truth_rows(held, FINAL),
        ]
        pooled: dict[str, list[tuple[float, ...]]] = {k: [] for k in FINAL}
        for p in held.values():
            for k, fn in FINAL.items():
                pooled[k].append(depth._scores(fn(p["left"], p["right"], 0, p["n"]), p))
        lines += ["", "| held out, mean of the 6 pairs | density | > 1 px | > 3 px | MAE px |"]
        lines += ["|---|---:|---:|---:|---:|"]
        for k, sc in pooled.items():
            a = np.array(sc).mean(axis=0)
            lines.append(
                f"| {k} | {100 * a[0]:.1f} % | {100 * a[1]:.2f} % | {100 * a[3]:.2f} % | "
                f"{a[4]:.3f} |"
            )
    # time: interleaved, graded against plain
    timed = {
        "davinci": [(L, R, boards["davinci"]["lo"], boards["davinci"]["n"])
                    for L, R, *_ in boards["davinci"]["items"][:4]],
        "urban": [(L, R, 0, 64) for L, R in urban_pairs[:2]],
        "adirondack": [(tuning["adirondack"]["left"], tuning["adirondack"]["right"], 0, 64)],
    }  # fmt: skip
    lines += [
        "",
        f"CPU time of the matching alone, one thread, median of {args.runs} interleaved runs:",
        "",
        "| pairs | graded s | plain s | graded / plain |",
        "|---|---:|---:|---:|",
    ]
    graded, plain = TUNING["graded, step 4 (default)"], TUNING["plain census (before)"]
    for k, prs in timed.items():
        a, b = [], []
        for _ in range(args.runs):
            a.append(_cpu(graded, prs))
            b.append(_cpu(plain, prs))
        ma, mb_ = float(np.median(a)), float(np.median(b))
        lines.append(f"| {k} ({len(prs)}) | {ma:.3f} | {mb_:.3f} | {ma / mb_:.2f} |")
    lines += ["", f"load after: {_load()}"]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
