"""Vertical stereo rigs: the rectification against OpenCV, the matching along columns, depth.

Three checks of cameras stacked vertically (a stereo endoscope held sideways, a phone's dual
camera in portrait), and one of ``stereo-calibrate`` on a folder holding empty files:

- **Rectification**: ``stereo_rectify`` and ``rectification_map`` of a vertical rig (the
  right camera 100 mm below or above the left, turned 4.8 deg, both with Brown-Conrady
  distortion; the rig of ``tests/geometry/test_stereo.py``) against ``cv2.stereoRectify``
  and ``cv2.initUndistortRectifyMap`` on the same input, for alpha -1, 0 and 1: the largest
  differences of ``R1, R2`` (absolute), ``P1, P2, Q`` (relative to each matrix's largest
  entry) and of the maps (px, over all pixels).
- **Matching along columns**: ``stereo_disparity(left.T, right.T, vertical=True)`` against the
  horizontal run ``stereo_disparity(left, right)`` transposed, on the rendered pair of
  ``tests/stereo_scenes.py`` (640 x 480, f = 800 px, baseline 60 mm) and on Middlebury's
  cones (2003 set, 450 x 375) and Adirondack (2014 set, 720 x 497) as kept by
  github.com/2b-t/stereo-matching (MIT licence), commit a1a3ac2, ``data/`` (give the folder
  with ``--middlebury``; without it those rows are left out): the pixels whose disparity
  differs (NaN against NaN counts as equal) and the CPU time of both (the matching alone,
  one thread, the median of interleaved runs, as a ratio: the machine is shared).
- **Depth**: ``imageform depth`` on the ray-cast scene of ``tests/stereo_scenes.py``
  (640 x 480, f = 800 px, 2 x 2 rays a pixel) seen by a side-by-side rig (the right camera
  60 mm to the right of the left, turned 2 deg) and by the same rig stacked (60 mm below,
  and 60 mm above with ``--min-disparity`` negative), each rig's file written as
  ``stereo-calibrate`` writes it from exact board projections; the depth of the rectified
  left pixels against the truth (the scene's point on each pixel's ray): the valid fraction,
  the median relative error and the share within 2 % and 5 %.
- **Unreadable files** (with ``--data3``): ``stereo-calibrate`` on OpenCV's stereo sample
  ``imgdata/data3`` of github.com/dreameer/stereocalibrate (commit 73c58f9; no licence
  file: read from a local copy, never committed), whose ``left12-14.jpg`` and
  ``right12-14.jpg`` are empty: the pairs used and the RMS.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stereo_vertical.py \\
        --middlebury /tmp/middlebury --data3 /tmp/data3 \\
        --out benchmarks/results/stereo-vertical-2026-11-30b.md
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from stereo_scenes import hit_points, render_pair, render_view  # noqa: E402

from imageform.geometry import (  # noqa: E402
    BrownConrady,
    checkerboard_points,
    project_points_distorted,
    rectification_map,
    rvec_to_matrix,
    stereo_calibrate,
    stereo_disparity,
    stereo_rectify,
)


def _load() -> str:
    if not hasattr(os, "getloadavg"):
        return "n/a"
    return " / ".join(f"{v:.1f}" for v in os.getloadavg())


# ---------------------------------------------------------------- rectification

SIZE = (640, 480)
K1 = np.array([[810.0, 0, 322], [0, 805, 238], [0, 0, 1]])
D1 = BrownConrady(-0.12, 0.08, 0.001, -0.0005, 0.0)
K2 = np.array([[790.0, 0, 315], [0, 792, 245], [0, 0, 1]])
D2 = BrownConrady(-0.09, 0.05, -0.0008, 0.0006, 0.0)
R_TRUE = np.asarray(rvec_to_matrix([0.02, -0.08, 0.01]))


def _rectification_rows() -> list[str]:
    import cv2

    rows = []
    for where, ty in (("below", -100.0), ("above", 100.0)):
        T = np.array([1.5, ty, 2.0])
        for alpha in (-1.0, 0.0, 1.0):
            ours = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T, alpha=alpha)
            ref = cv2.stereoRectify(
                K1,
                np.array(D1.coeffs[:5]),
                K2,
                np.array(D2.coeffs[:5]),
                SIZE,
                R_TRUE,
                T.reshape(3, 1),
                alpha=alpha,
            )
            dR = max(float(np.abs(ours.R1 - ref[0]).max()), float(np.abs(ours.R2 - ref[1]).max()))
            dP = max(
                float(np.abs(a - b).max() / np.abs(b).max())
                for a, b in ((ours.P1, ref[2]), (ours.P2, ref[3]), (ours.Q, ref[4]))
            )
            dm = 0.0
            for K, D, Rr, P in ((K1, D1, ours.R1, ours.P1), (K2, D2, ours.R2, ours.P2)):
                m = rectification_map(K, D, Rr, P, SIZE)
                mx, my = cv2.initUndistortRectifyMap(
                    K, np.array(D.coeffs[:5]), Rr, P, SIZE, cv2.CV_32FC1
                )
                dm = max(
                    dm, float(np.abs(m[..., 0] - mx).max()), float(np.abs(m[..., 1] - my).max())
                )
            rows.append(
                f"| {where} | {alpha:g} | {'yes' if ours.vertical else 'no'} | {dR:.1e} | "
                f"{dP:.1e} | {dm:.1e} |"
            )
    return rows


# ---------------------------------------------------------------- matching along columns


def _pairs(middlebury: Path | None) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    s = render_pair(640, 480, f=800.0, baseline=60.0, ss=3, seed=0)
    u8 = [np.clip(np.round(a * 255), 0, 255).astype(np.uint8) for a in (s.left, s.right)]
    pairs = {"rendered 640 x 480": (u8[0], u8[1], 80)}
    if middlebury is not None:
        from PIL import Image

        def grey(name: str) -> np.ndarray:
            return np.asarray(Image.open(middlebury / name).convert("L"))

        pairs["Middlebury cones 450 x 375"] = (grey("cones_left.png"), grey("cones_right.png"), 64)
        pairs["Middlebury Adirondack 720 x 497"] = (
            grey("Adirondack_left.png"),
            grey("Adirondack_right.png"),
            64,
        )
    return pairs


def _matching_rows(middlebury: Path | None, runs: int) -> list[str]:
    rows = []
    for name, (left, right, n) in _pairs(middlebury).items():
        lt, rt = np.ascontiguousarray(left.T), np.ascontiguousarray(right.T)
        settings: tuple[dict[str, Any], ...] = ({}, {"adaptive_p2": True, "speckle_size": 50})
        for kw in settings:
            d = stereo_disparity(left, right, num_disparities=n, **kw)
            dv = stereo_disparity(lt, rt, num_disparities=n, vertical=True, **kw)
            same = (dv == d.T) | (np.isnan(dv) & np.isnan(d.T))
            label = "defaults" if not kw else "adaptive_p2, speckle_size 50"
            t_h, t_v = [], []
            for _ in range(runs if not kw else 0):
                t = time.process_time()
                stereo_disparity(left, right, num_disparities=n)
                t_h.append(time.process_time() - t)
                t = time.process_time()
                stereo_disparity(lt, rt, num_disparities=n, vertical=True)
                t_v.append(time.process_time() - t)
            timing = (
                f"{np.median(t_h):.3f} | {np.median(t_v):.3f} | "
                f"{np.median(t_v) / np.median(t_h):.2f}"
                if t_h
                else "| |"
            )
            rows.append(
                f"| {name} | {n} | {label} | {int((~same).sum())} of {same.size} | "
                f"{100 * np.isfinite(dv).mean():.1f} % | {timing} |"
            )
    return rows


# ---------------------------------------------------------------- depth through the command


W, H, F = 640, 480, 800.0
R_RIG = np.asarray(rvec_to_matrix([0.02, 0.01, -0.03]))


def _rig_file(path: Path, K: np.ndarray, R: np.ndarray, T: np.ndarray) -> None:
    """The rig as stereo-calibrate writes it, from exact projections of a 9 x 6 board."""
    from imageform.io import StereoCameraFile, write_stereo_camera

    obj = checkerboard_points((9, 6), 60.0)
    views = [
        ([0.3, 0.1, 0], [-240, -150, 700]),
        ([-0.2, 0.3, 0.1], [-220, -160, 760]),
        ([0.1, -0.35, -0.1], [-260, -120, 720]),
        ([0.2, 0.2, 0.3], [-200, -180, 740]),
    ]
    uvl, uvr = [], []
    for r, t in views:
        Rk = np.asarray(rvec_to_matrix(r))
        uvl.append(project_points_distorted(obj, K, Rk, t, None)[0])
        uvr.append(project_points_distorted(obj, K, R @ Rk, R @ np.asarray(t) + T, None)[0])
    res = stereo_calibrate([obj] * 4, uvl, uvr, (W, H), fix=("k1", "k2", "p1", "p2", "k3"))
    write_stereo_camera(path, StereoCameraFile.from_calibration(res, command="benchmark"))


def _depth_rows(tmp: Path) -> list[str]:
    from imageform.cli import main
    from imageform.io import read_image, write_image

    K = np.array([[F, 0, (W - 1) / 2], [0, F, (H - 1) / 2], [0, 0, 1]])
    left = render_view(K, None, np.eye(3), np.zeros(3), (W, H), ss=2)
    write_image(tmp / "left.png", (left * 255).round().astype(np.uint8))
    rows = []
    rigs = (
        ("side by side (right 60 mm to the right)", np.array([-60.0, 1.5, 2.0]), 0),
        ("stacked (right 60 mm below)", np.array([1.5, -60.0, 2.0]), 0),
        ("stacked (right 60 mm above)", np.array([1.5, 60.0, 2.0]), -95),
    )
    for label, T, dmin in rigs:
        _rig_file(tmp / "rig.toml", K, R_RIG, T)
        right = render_view(K, None, R_RIG, T, (W, H), ss=2)
        write_image(tmp / "right.png", (right * 255).round().astype(np.uint8))
        out = tmp / "z.npy"
        argv = ["depth", str(tmp / "left.png"), str(tmp / "right.png"), "--camera"]
        argv += [str(tmp / "rig.toml"), "--min-disparity", str(dmin), "--num-disparities", "96"]
        assert main([*argv, "-o", str(out), "--force"]) == 0
        z = np.load(out) if out.suffix == ".npy" else np.asarray(read_image(out))[..., 0]
        rect = stereo_rectify(K, None, K, None, (W, H), R_RIG, T)
        v, u = np.mgrid[0:H, 0:W].astype(np.float64)
        rays = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(rect.P1[:, :3]).T @ rect.R1
        z_true = (hit_points(np.zeros(3), rays) @ rect.R1.T)[..., 2]
        ok = np.isfinite(z) & np.isfinite(z_true)
        rel = np.abs(z - z_true)[ok] / z_true[ok]
        rows.append(
            f"| {label} | {'yes' if rect.vertical else 'no'} | {dmin} to {dmin + 95} | "
            f"{100 * ok.mean():.1f} % | {100 * np.median(rel):.2f} % | "
            f"{100 * np.mean(rel < 0.02):.1f} % | {100 * np.mean(rel < 0.05):.1f} % |"
        )
    return rows


def _data3_rows(data3: Path, tmp: Path) -> list[str]:
    import contextlib
    import io

    from imageform.cli import main

    out = tmp / "d3.toml"
    argv = ["stereo-calibrate", str(data3 / "left"), str(data3 / "right"), "--board", "auto"]
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()) as so, contextlib.redirect_stderr(err):
        code = main([*argv, "-o", str(out), "--force", "--json"])
    notes = [n for n in err.getvalue().splitlines() if " be read (" in n]
    if code != 0:
        return [f"| data3 | exit {code} | | | |"]
    s = json.loads(so.getvalue())
    return [
        f"| data3 ({s['board']['inner_corners'][0]}x{s['board']['inner_corners'][1]} board) | "
        f"{s['pairs_used']} of {s['pairs_total']} | {len(notes)} | {s['rms_px']:.4f} | "
        f"{s['baseline']:.3f} |"
    ]


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--middlebury", type=Path, help="folder of 2b-t/stereo-matching's data/")
    ap.add_argument("--data3", type=Path, help="folder with left/ and right/ of data3")
    ap.add_argument("--out", type=Path, help="write the markdown tables here too")
    ap.add_argument("--runs", type=int, default=5, help="timed runs of each orientation")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    stereo_disparity(np.zeros((40, 60)), np.zeros((40, 60)), num_disparities=8)  # compile
    lines = [
        "# Vertical stereo rigs: rectification, matching along columns, depth",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; load before: {_load()}.",
        "",
        "Rectification of a vertical rig against cv2.stereoRectify and "
        "cv2.initUndistortRectifyMap (the same input; largest differences):",
        "",
        "| right camera | alpha | vertical | R1, R2 | P1, P2, Q (relative) | maps px |",
        "|---|---:|---|---:|---:|---:|",
        *_rectification_rows(),
        "",
        "Matching along columns (the pair transposed, vertical=True) against the horizontal "
        f"run transposed; CPU time of the defaults, one thread, median of {args.runs} "
        "interleaved runs:",
        "",
        "| pair | disparities | settings | pixels that differ | density | horizontal s "
        "| vertical s | vertical / horizontal |",
        "|---|---:|---|---:|---:|---:|---:|---:|",
        *_matching_rows(args.middlebury, args.runs),
        "",
        "Depth through imageform depth (640 x 480, f 800 px, 96 disparities, the rig file "
        "from exact board projections) against the true depth of the rectified left pixels "
        "(valid: of all pixels; the band the range leaves out is 95 columns of 640 side by "
        "side, 95 rows of 480 stacked):",
        "",
        "| rig | vertical | disparities searched | valid | median error | within 2 % "
        "| within 5 % |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    with tempfile.TemporaryDirectory() as d:
        lines += _depth_rows(Path(d))
        if args.data3 is not None:
            lines += [
                "",
                "stereo-calibrate --board auto on the folders of OpenCV's stereo sample data3 "
                "(three empty .jpg on each side):",
                "",
                "| folders | pairs used | notes of pairs skipped | RMS px | baseline (squares) |",
                "|---|---:|---:|---:|---:|",
                *_data3_rows(args.data3, Path(d)),
            ]
    lines += ["", f"load after: {_load()}"]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
