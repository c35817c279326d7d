"""Checkerboards cut by the image's border: calibration from whole views and partial ones.

``find_checkerboard(view, board, partial=True)`` returns the largest part of a board that is
not seen whole, its corners labelled in that part's own lattice; ``imageform calibrate
--partial`` uses such views. What that brings, measured two ways.

Rendered views (truth known): a 9 x 6 board rendered analytically through a lens
(``tests/geometry/checkerboard_support.render_board_through``: each pixel's ray meets the
board plane, edges blurred 1 px, noise 0.01, 8-bit), in random poses (tilts to 40 deg)
placed so that most views cut the board at the image's border: an endoscope-like fisheye
(768 x 576, Kannala-Brandt with the coefficients imageform fitted to a real PAL endoscope, f =
400 px, a round field of view of radius 330 px, dark outside) and a
wide-angle lens (640 x 480, Brown-Conrady k1 = -0.32, k2 = 0.11). Each trial calibrates from
the views seen whole only, then from those plus the partial views; errors against the truth:
fx, fy, cx, cy (px) and the field error, the distance between the true and the fitted
projection of the rays through a grid of pixels over the whole image (median, largest).
Every partial corner is checked against the true corners: labels consistent (one shift,
quarter turn or mirroring of the lattice for all of a view's corners) and the distance.

Real photographs (no truth): per set (``NAME=GLOB:COLSxROWS[:fisheye]``) the whole boards
found in every view; views lost today (no whole board) and how many of them give a part.
The views with a whole board are split by parity: the odd ones are held out, the even ones
fit. Among the fitting views every other one is cropped so that the board is cut (the crop
keeps 55 % of the board's extent, cut from the left, top, right or bottom in turn); the
part found in the crop, its corners moved back by the crop's offset, is checked against
the whole detection (labels consistent, corner distance). Calibrations (imageform's
``calibrate_camera``, Kannala-Brandt for fisheye sets, else Brown-Conrady, at most 1000
iterations): the fitting
views uncut (the reference, all whole), the uncut ones only (what a whole-only calibration
keeps when those views are cut), the uncut ones and the cropped views' parts, and all the
fitting views plus the views lost today that give a part. Per calibration: views (partial),
corners, RMS, held-out RMS (each held-out view's pose fitted with the intrinsics held), and
fx, fy, cx, cy, k1 against a calibration from every whole view of the set.

Sets used (the photographs are not in the repository; sources in
benchmarks/check_calibration_endoscope.py and check_corner_refinement.py). Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_partial_board.py "endo-sl=ENDO/endo-sl/Cam*.png:9x6:fisheye" ... \\
        --trials 3 --out TABLE.md
"""

from __future__ import annotations

import argparse
import glob
import os
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402
from imageform.errors import ConvergenceError, DegenerateConfigurationError  # noqa: E402

#: The eight labellings of a square lattice onto itself (quarter turns, mirrorings).
_TURNS = [np.array(m) for m in ([[1, 0], [0, 1]], [[0, -1], [1, 0]], [[-1, 0], [0, -1]],
                                [[0, 1], [-1, 0]], [[1, 0], [0, -1]], [[-1, 0], [0, 1]],
                                [[0, 1], [1, 0]], [[0, -1], [-1, 0]])]  # fmt: skip


def label_check(part: np.ndarray, size: tuple[int, int], truth: np.ndarray,
                board: tuple[int, int]) -> tuple[int, np.ndarray]:  # fmt: skip
    """Count a part's corners whose labels agree with the truth, and each corner's distance.

    ``part`` (pc*pr, 2) in the part's order, ``truth`` (cols*rows, 2) the board's corners (in
    the board's order). Each part corner's nearest true corner gives its board label; the
    labels agree when one lattice isometry (turn or mirroring, then a shift) maps every part
    label to its board label: the count is of the corners that isometry maps right.
    """
    d2 = ((part[:, None] - truth[None]) ** 2).sum(-1)
    near = d2.argmin(1)
    dist = np.sqrt(d2.min(1))
    ij = np.stack([near % board[0], near // board[0]], 1)
    k = np.arange(len(part))
    ab = np.stack([k % size[0], k // size[0]], 1)
    best = 0
    for R in _TURNS:
        shift = ij - ab @ R.T
        _, counts = np.unique(shift, axis=0, return_counts=True)
        best = max(best, int(counts.max()))
    return best, dist


def _points(size: tuple[int, int]) -> np.ndarray:
    from imageform.geometry import checkerboard_points

    return checkerboard_points(size, 1.0)


def calibrate(objs: list[np.ndarray], pts: list[np.ndarray], image_size: tuple[int, int],
              model: str) -> Any:  # fmt: skip
    """imageform's calibration of the views (warnings of poor conditioning silenced)."""
    from imageform.geometry import calibrate_camera

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate_camera(objs, pts, image_size, model=model, max_iter=1000)


def held_out(res: Any, objs: list[np.ndarray], pts: list[np.ndarray], model: str) -> float:
    """RMS (px) of views fitted with ``res``'s intrinsics held (each view's pose only)."""
    from imageform.geometry import calibrate_camera
    from imageform.geometry.calibration_refine import global_names

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = calibrate_camera(objs, pts, res.image_size, model=model, K_init=res.K,
                               distortion_init=res.distortion, fix=global_names(model),
                               max_iter=1000)  # fmt: skip
    return float(fit.rms)


# ---------------------------------------------------------------- rendered views

SCENES = {  # image size, K, lens, radius of a round field of view (px; None: the whole image)
    "endoscope fisheye (Kannala-Brandt), 768 x 576, round field": (
        (768, 576), np.array([[400.0, 0, 390.0], [0, 400.0, 280.0], [0, 0, 1]]),
        ("kannala_brandt", (-0.091, -0.0161, 0.0198, -0.022)), 330.0,
    ),
    "wide angle (Brown-Conrady k1 -0.32), 640 x 480": (
        (640, 480), np.array([[420.0, 0, 322.0], [0, 420.0, 236.0], [0, 0, 1]]),
        ("brown_conrady", (-0.32, 0.11, 0.0, 0.0, 0.0)), None,
    ),
}  # fmt: skip
BOARD = (9, 6)


def _lens(spec: tuple[str, tuple[float, ...]]) -> Any:
    from imageform.geometry import BrownConrady, KannalaBrandt

    model, coef = spec
    return KannalaBrandt(*coef) if model == "kannala_brandt" else BrownConrady(*coef)


def _pose(rng: np.random.Generator, camera: Any,
          radius: float | None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """A board pose: its centre seen at a random pixel of the image (or of its round field)."""
    from scipy.spatial.transform import Rotation

    w, h = camera.image_size
    rot = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.radians([35, 35, 30])).as_matrix()
    xy = np.full(2, np.nan)
    while not np.all(np.isfinite(xy)):
        u, v = rng.uniform(0.05, 0.95) * w, rng.uniform(0.05, 0.95) * h
        if radius is not None:
            a, r = rng.uniform(0, 2 * np.pi), radius * np.sqrt(rng.uniform(0.0, 0.9))
            u, v = camera.K[0, 2] + r * np.cos(a), camera.K[1, 2] + r * np.sin(a)
        xy = np.asarray(camera.undistort_pixels(np.array([[u, v]])))[0]
    centre = np.array([xy[0], xy[1], 1.0]) * rng.uniform(4.5, 8.0)
    # the board's centre (its inner corners span (cols-1, rows-1) squares) at ``centre``
    mid = np.array([(BOARD[0] - 1) / 2, (BOARD[1] - 1) / 2, 0.0])
    return rot, centre - rot @ mid


def rendered(trials: int, views: int, seed: int) -> list[list[object]]:
    """Rows: per scene and trial, the whole-only and whole + partial calibrations' errors."""
    from imageform.geometry import Camera, find_checkerboard, project_points_distorted
    from tests.geometry.checkerboard_support import render_board_through

    rows: list[list[object]] = []
    rng = np.random.default_rng(seed)
    obj = _points(BOARD)
    for name, (size, K, spec, radius) in SCENES.items():
        D = _lens(spec)
        model = spec[0]
        w, h = size
        gv, gu = np.mgrid[0:h:16, 0:w:16].astype(float)
        grid_px = np.stack([gu.ravel(), gv.ravel()], 1)
        truth_cam = Camera(K, image_size=size, distortion=D)
        rays = np.asarray(truth_cam.undistort_pixels(grid_px))
        seen = np.all(np.isfinite(rays), axis=1)  # pixels the lens maps (all, for these two)
        if radius is not None:  # the round field of view only
            seen &= np.hypot(*(grid_px - K[:2, 2]).T) <= radius
        mask = 1.0
        if radius is not None:  # dark outside the round field, its edge blurred over ~1 px
            from scipy.special import erf

            vv, uu = np.mgrid[0:h, 0:w].astype(float)
            mask = 0.5 * (1 - erf((np.hypot(uu - K[0, 2], vv - K[1, 2]) - radius) / 1.5))
        grid_px, rays = grid_px[seen], rays[seen]
        rays3 = np.c_[rays, np.ones(len(rays))]
        for trial in range(trials):
            whole_o, whole_p, part_o, part_p = [], [], [], []
            n_cut = n_lost = n_part = n_corners = n_ok = 0
            dists: list[np.ndarray] = []
            part_d: list[np.ndarray] = []
            for _ in range(views):
                R, t = _pose(rng, truth_cam, radius)
                cam = Camera(K, R, t, size, distortion=D)
                img = render_board_through(cam, *BOARD, 1.0, blur=1.0, noise=0.01,
                                           seed=int(rng.integers(1 << 30)))  # fmt: skip
                img = 0.03 + (img - 0.03) * mask
                u8 = np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)
                truth = np.asarray(project_points_distorted(obj, K, R, t, D)[0])
                inside = np.all((truth >= 0) & (truth <= [w - 1, h - 1]), axis=1)
                if radius is not None:
                    inside &= np.hypot(*(truth - K[:2, 2]).T) <= radius
                if not inside.all():
                    n_cut += 1
                res = find_checkerboard(u8, BOARD, partial=True)
                if not res.found:
                    n_lost += 1
                    continue
                if not res.partial:
                    whole_o.append(obj)
                    whole_p.append(res.corners)
                    dists.append(np.linalg.norm(res.corners - truth, axis=1))
                    continue
                ok, dist = label_check(res.corners, res.pattern_size, truth, BOARD)
                n_part += 1
                n_corners += len(dist)
                n_ok += ok
                part_d.append(dist)
                part_o.append(_points(res.pattern_size))
                part_p.append(res.corners)
            err = np.concatenate(dists) if dists else np.full(1, np.nan)
            perr = np.concatenate(part_d) if part_d else np.full(1, np.nan)
            for label, objs, pts in (
                ("whole only", whole_o, whole_p),
                ("whole + partial", whole_o + part_o, whole_p + part_p),
            ):
                if len(objs) < 3:
                    rows.append([name, trial, label, len(objs), *["—"] * 7])
                    continue
                try:
                    fit = calibrate(objs, pts, size, model)
                except (DegenerateConfigurationError, ConvergenceError) as exc:
                    why = str(exc).split(";")[0].split(" (")[0]
                    rows.append([name, trial, label, len(objs), f"fails: {why}", *["—"] * 6])
                    continue
                q = np.asarray(project_points_distorted(rays3, fit.K, np.eye(3), np.zeros(3),
                                                        fit.distortion)[0])  # fmt: skip
                field = np.linalg.norm(q - grid_px, axis=1)
                dK = fit.K - K
                rows.append([
                    name, trial, label,
                    f"{len(objs)} ({len(objs) - len(whole_o)})", sum(len(p) for p in pts),
                    f"{fit.rms:.3f}",
                    f"{dK[0, 0]:+.2f} / {dK[1, 1]:+.2f} / {dK[0, 2]:+.2f} / {dK[1, 2]:+.2f}",
                    f"{np.median(field):.3f} / {field.max():.2f}",
                    f"{views} views, {n_cut} cut; {len(whole_o)} whole, {n_part} partial "
                    f"({n_ok}/{n_corners} corners labelled consistently), {n_lost} none",
                    f"{np.median(err):.3f} / {np.percentile(err, 99):.3f} / {err.max():.3f}",
                    f"{np.median(perr):.3f} / {np.percentile(perr, 99):.3f} / {perr.max():.3f}",
                ])  # fmt: skip
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


# ---------------------------------------------------------------- real photographs


def _crop(corners: np.ndarray, shape: tuple[int, int], side: int) -> tuple[int, int, int, int]:
    """``(x0, y0, x1, y1)`` of a crop that cuts the board, keeping 55 % of its extent."""
    h, w = shape
    lo, hi = corners.min(0), corners.max(0)
    x0, y0, x1, y1 = 0, 0, w, h
    axis = side % 2  # 0: u (left, right), 1: v (top, bottom)
    if side in (0, 1):  # left or top cut away
        cut = round(float(lo[axis] + 0.45 * (hi[axis] - lo[axis])))
        if axis == 0:
            x0 = cut
        else:
            y0 = cut
    else:
        cut = round(float(hi[axis] - 0.45 * (hi[axis] - lo[axis])))
        if axis == 0:
            x1 = cut
        else:
            y1 = cut
    return x0, y0, x1, y1


def real_set(name: str, pattern: str, board: tuple[int, int],
             fisheye: bool) -> tuple[list[object], list[list[object]]]:  # fmt: skip
    """The set's summary row and its calibration rows."""
    from PIL import Image

    from imageform.geometry import find_checkerboard

    model = "kannala_brandt" if fisheye else "brown_conrady"
    files = sorted(glob.glob(pattern))
    greys, whole, lost = [], [], []
    for f in files:
        try:
            grey = np.asarray(Image.open(f).convert("L"))
        except OSError:  # an unreadable file is left out
            continue
        greys.append(grey)
        res = find_checkerboard(grey, board)
        if res.found:
            whole.append((len(greys) - 1, res.corners))
        else:
            part = find_checkerboard(grey, board, partial=True)
            lost.append((len(greys) - 1, part))
    size = (greys[0].shape[1], greys[0].shape[0])
    obj = _points(board)
    fit_views = whole[0::2]
    held = whole[1::2]
    cut_views = fit_views[1::2]
    uncut = fit_views[0::2]
    crops_o, crops_p = [], []
    n_ok = n_c = 0
    dists = []
    for j, (k, corners) in enumerate(cut_views):
        x0, y0, x1, y1 = _crop(corners, greys[k].shape, j % 4)
        res = find_checkerboard(greys[k][y0:y1, x0:x1], board, partial=True)
        if not res.found:
            continue
        if not res.partial:  # the crop left a whole board (it cannot: it cuts the board)
            continue
        pts = res.corners + [x0, y0]
        ok, dist = label_check(pts, res.pattern_size, corners, board)
        n_ok += ok
        n_c += len(dist)
        dists.append(dist)
        crops_o.append(_points(res.pattern_size))
        crops_p.append(pts)
    genuine = [(k, r) for k, r in lost if r.found]
    try:  # every whole view: what the changes are measured against
        ref = calibrate([obj] * len(whole), [c for _, c in whole], size, model)
    except (DegenerateConfigurationError, ConvergenceError):
        ref = None
    dist_all = np.concatenate(dists) if dists else np.full(1, np.nan)
    summary: list[object] = [
        name, f"{board[0]} x {board[1]}", model.replace("_", "-"), len(greys), len(whole),
        f"{len(lost)} ({len(genuine)})", f"{len(crops_p)} of {len(cut_views)}",
        f"{n_ok}/{n_c}", f"{np.median(dist_all):.3f} / {np.max(dist_all):.3f}",
    ]  # fmt: skip
    held_o = [obj] * len(held)
    held_p = [c for _, c in held]
    configs = [
        ("fitting views, all whole (reference)", [obj] * len(fit_views),
         [c for _, c in fit_views], 0),
        ("uncut only (whole-only when cut)", [obj] * len(uncut), [c for _, c in uncut], 0),
        ("uncut + parts of the cut", [obj] * len(uncut) + crops_o,
         [c for _, c in uncut] + crops_p, len(crops_p)),
    ]  # fmt: skip
    if genuine:
        configs.append((
            "all fitting + parts of views lost today",
            [obj] * len(fit_views) + [_points(r.pattern_size) for _, r in genuine],
            [c for _, c in fit_views] + [r.corners for _, r in genuine], len(genuine),
        ))  # fmt: skip
    rows: list[list[object]] = []
    for label, objs, pts, n_part in configs:
        if len(objs) < 3:
            rows.append([name, label, len(objs), "—", "—", "—", "—"])
            continue
        try:
            fit = calibrate(objs, pts, size, model)
            hrms = held_out(fit, held_o, held_p, model)
        except (DegenerateConfigurationError, ConvergenceError) as exc:
            why = str(exc).split(";")[0].split(" (")[0]
            rows.append([name, label, f"{len(objs)} ({n_part})", sum(len(p) for p in pts),
                         f"fails: {why}", "—", "—"])  # fmt: skip
            continue
        change = ["every whole view: fails", "—"]
        if ref is not None:
            dK = fit.K - ref.K
            change = [
                f"{dK[0, 0]:+.2f} / {dK[1, 1]:+.2f} / {dK[0, 2]:+.2f} / {dK[1, 2]:+.2f}",
                f"{fit.distortion.coeffs[0] - ref.distortion.coeffs[0]:+.4f}",
            ]
        rows.append([name, label, f"{len(objs)} ({n_part})", sum(len(p) for p in pts),
                     f"{fit.rms:.4f} / {hrms:.4f}", *change])  # fmt: skip
        print(rows[-1], file=sys.stderr, flush=True)
    return summary, rows


def main() -> None:
    """Run the rendered trials and the real sets given; print (or write) the tables."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("sets", nargs="*", help="NAME=GLOB:COLSxROWS[:fisheye]")
    ap.add_argument("--trials", type=int, default=3, help="rendered trials per scene")
    ap.add_argument("--views", type=int, default=20, help="rendered views per trial")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    synth = rendered(args.trials, args.views, args.seed) if args.trials else []
    summaries, calib = [], []
    for spec in args.sets:
        name, rest = spec.split("=", 1)
        parts = rest.split(":")
        fisheye = parts[-1] == "fisheye"
        if fisheye:
            parts = parts[:-1]
        cols, nrows = (int(v) for v in parts[-1].lower().split("x"))
        s, c = real_set(name, ":".join(parts[:-1]), (cols, nrows), fisheye)
        summaries.append(s)
        calib += c
        print(s, file=sys.stderr, flush=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = header("Checkerboards cut by the image's border: partial detections")
    text += (
        f"\nLoad average {load:.1f} when run. Made by `benchmarks/check_partial_board.py` (its "
        "docstring says how the views are made and names the sets).\n\n"
        "## Rendered views (truth known)\n\n"
        "Views (of them partial), corners, RMS (px) of the fit; the fitted fx / fy / cx / cy "
        "less the true ones (px); field error: the true and the fitted projection of rays "
        "over the whole image apart, median / largest (px); corners to truth: median / 99th "
        "percentile / largest (px), of the whole boards and of the parts.\n\n"
    )
    text += markdown_table(
        ("scene", "trial", "calibration", "views (partial)", "corners", "RMS px",
         "fx / fy / cx / cy error px", "field error px", "views found",
         "whole corners to truth px", "partial corners to truth px"),
        synth,
    )  # fmt: skip
    text += (
        "\n## Real photographs\n\n"
        "Views with a whole board; views lost today (no whole board) and, of them, those that "
        "give a part; the fitting views cropped to cut the board and the parts found in them; "
        "their corners whose labels agree with the whole detection's; their corners' distance "
        "to the whole detection's, median / largest (px).\n\n"
    )
    text += markdown_table(
        ("set", "board", "model", "views", "whole", "lost today (part found)",
         "crops: part found", "crop labels consistent", "crop corners to whole px"),
        summaries,
    )  # fmt: skip
    text += (
        "\nCalibrations: views (of them partial), corners, RMS / held-out RMS (px; the odd "
        "whole views, each view's pose fitted with the intrinsics held); fx / fy / cx / cy and "
        "k1 less those of a calibration from every whole view of the set.\n\n"
    )
    text += markdown_table(
        ("set", "calibration", "views (partial)", "corners", "RMS / held-out px",
         "fx / fy / cx / cy change px", "k1 change"),
        calib,
    )  # fmt: skip
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
