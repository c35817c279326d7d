"""Structure from motion on real views with known cameras: imageform vs pycolmap.

Issue 28's real sequence: OpenCV's 13 views of a 9 x 6 chessboard
(``../shared/data/opencv-left``, 640 x 480 grey, or ``$IMAGEFORM_DATA/opencv-left``). The
truth is imageform's own calibration of those views (``calibrate_camera`` on the corners
``find_checkerboard`` finds; published: fx 536.07, fy 536.02, cx 342.37, cy 235.54, RMS
0.41 px) and each view's board pose from it, the board's frame being the world. The camera
stood still and the board moved, so the room behind is still while the world moves: both
libraries see the frames through the same masks, the convex hull of each view's corners
dilated by ``--dilate`` pixels (tests/sfm_scenes.py ``chessboard_views``). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_reconstruct_real.py \\
        [--dilate 25] [--ratio 0.8] [--repeat 3] [--masked-only]

Both get the calibrated camera, fixed (imageform: ``K`` and the Brown-Conrady distortion;
pycolmap: a ``FULL_OPENCV`` camera with the same numbers, ``ba_refine_*`` off) and every
pair of frames to match (imageform: ``window=12``; pycolmap: exhaustive matching), otherwise
their defaults. The views are not a video: the board turns by tens of degrees between
them. Trajectory RMS: the registered camera centres after the best similarity (Umeyama 1991)
to the true ones, RMS distance as a share of the true path's length (the registered views in
their order); time: the whole call, median of ``--repeat`` runs, CPU seconds of the process
and wall seconds. Both also run on the whole frames (unless ``--masked-only``), to show what
the still background does. A second table says why the board is hard: imageform's SIFT
matches of every pair checked against the truth's board homographies.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table
from benchmarks.bench_reconstruct import pycolmap_options, pycolmap_poses, pycolmap_reconstruct
from tests import sfm_scenes

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("IMAGEFORM_DATA", ROOT.parent / "shared" / "data")) / "opencv-left"


def run_imageform(
    scene: dict[str, Any], masked: bool, threads: int, ratio: float
) -> dict[str, Any]:
    import cv2

    from imageform.geometry import reconstruct_sequence

    cv2.setNumThreads(threads)
    images = scene["images"]
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        rec = reconstruct_sequence(
            images,
            scene["K"],
            scene["distortion"],
            window=len(images) - 1,
            ratio=ratio,
            masks=scene["masks"] if masked else None,
        )
    except Exception as exc:  # a failed start is a result too
        dt, dc = time.perf_counter() - t0, time.process_time() - c0
        n = len(images)
        note = f"{type(exc).__name__}: {exc}"
        nan = np.full((n, 3), np.nan)
        return {"C": nan, "R": np.full((n, 3, 3), np.nan), "points": 0, "time": dt, "cpu": dc,
                "note": note}  # fmt: skip
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    C = np.array([-R.T @ t for R, t in zip(rec.R, rec.t, strict=True)])
    note = "; ".join(rec.notes[:3]) + (" ..." if len(rec.notes) > 3 else "")
    out = {"C": C, "R": rec.R, "points": rec.points.shape[0], "time": dt, "cpu": dc}
    return {**out, "note": note}


def rotation_errors(R: np.ndarray, R_true: np.ndarray) -> np.ndarray:
    """Each registered view's rotation error relative to the first registered one, degrees."""
    reg = np.flatnonzero(np.all(np.isfinite(R), axis=(1, 2)))
    if reg.size < 2:
        return np.zeros(0)
    f = reg[0]
    out = []
    for i in reg[1:]:
        d = (R[i] @ R[f].T) @ (R_true[i] @ R_true[f].T).T
        out.append(np.degrees(np.arccos(np.clip((np.trace(d) - 1) / 2, -1, 1))))
    return np.array(out)


def match_check(scene: dict[str, Any], ratio: float = 0.8) -> dict[str, Any]:
    """Why the board is hard: imageform's SIFT matches of every pair against the truth.

    The board is the plane Z = 0, so view i's undistorted pixel of a board point is
    ``H_i (X, Y, 1)`` with ``H_i = K [r1 r2 t]``; a match (a, b) of views i, j is correct
    when ``H_j H_i^-1 a`` is within 3 pixels of ``b``.
    """
    from imageform.geometry import detect_features, match_features

    K, d = scene["K"], scene["distortion"]
    R, t = scene["R"], scene["t"]
    feats = [
        detect_features(im, mask=m) for im, m in zip(scene["images"], scene["masks"], strict=True)
    ]

    def ideal(xy: np.ndarray) -> np.ndarray:
        und, _ = d.undistort((xy - K[:2, 2]) / np.diag(K)[:2])
        return np.asarray(und) * np.diag(K)[:2] + K[:2, 2]

    und = [ideal(f.xy) for f in feats]
    H = [K @ np.column_stack([R[i][:, 0], R[i][:, 1], t[i]]) for i in range(len(feats))]
    total = correct = 0
    per_pair = []
    for i in range(len(feats)):
        for j in range(i + 1, len(feats)):
            m = match_features(feats[i].descriptors, feats[j].descriptors, ratio=ratio)
            q = np.c_[und[i][m[:, 0]], np.ones(len(m))] @ (H[j] @ np.linalg.inv(H[i])).T
            e = np.linalg.norm(q[:, :2] / q[:, 2:] - und[j][m[:, 1]], axis=1)
            good = int(np.sum(e < 3.0))
            total += len(m)
            correct += good
            per_pair.append(good)
    n_kp = [len(f) for f in feats]
    return {
        "keypoints": (min(n_kp), int(np.median(n_kp)), max(n_kp)),
        "pairs": len(per_pair),
        "matches": total,
        "correct": correct,
        "best_pair": max(per_pair),
        "pairs_30": sum(g >= 30 for g in per_pair),
    }


def run_pycolmap(scene: dict[str, Any], masked: bool, threads: int, ratio: float) -> dict[str, Any]:
    import cv2
    import pycolmap

    images = scene["images"]
    K, d = scene["K"], scene["distortion"]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        folder, mask_folder = root / "images", root / "masks"
        folder.mkdir()
        mask_folder.mkdir()
        names = [f"{i:04d}.png" for i in range(len(images))]
        for name, im, m in zip(names, images, scene["masks"], strict=True):
            cv2.imwrite(str(folder / name), im)
            cv2.imwrite(str(mask_folder / f"{name}.png"), m)  # COLMAP: IMAGE_NAME.png
        # FULL_OPENCV: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6
        params = (K[0, 0], K[1, 1], K[0, 2], K[1, 2], d.k1, d.k2, d.p1, d.p2, d.k3, 0, 0, 0)
        options = pycolmap_options(threads, "FULL_OPENCV", params)
        reader, _, matching, _ = options
        if masked:
            reader.mask_path = str(mask_folder)
        matching.sift.max_ratio = ratio

        def match(db: Path) -> None:
            pycolmap.match_exhaustive(db, matching_options=matching, device=pycolmap.Device.cpu)

        maps, dt, dc = pycolmap_reconstruct(root, folder, options, match)
    C, R, points = pycolmap_poses(maps, names)
    note = "" if maps else "no model"
    return {"C": C, "R": R, "points": points, "time": dt, "cpu": dc, "note": note}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dilate", type=int, default=25, help="mask: the hull dilated, pixels")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--ratio", type=float, default=0.8, help="Lowe's ratio, both libraries")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--only", choices=["imageform", "pycolmap"], default=None)
    ap.add_argument("--masked-only", action="store_true", help="skip the runs on the whole frames")
    args = ap.parse_args()
    scene = sfm_scenes.chessboard_views(DATA, dilate=args.dilate)
    K = scene["K"]
    C_true = np.asarray(scene["centres"])
    runs_of: list[tuple[str, bool, Any]] = [
        ("imageform", True, run_imageform),
        ("pycolmap", True, run_pycolmap),
    ]
    if not args.masked_only:
        runs_of += [("imageform", False, run_imageform), ("pycolmap", False, run_pycolmap)]
    rows, notes = [], []
    for name, masked, fn in runs_of:
        if args.only and name != args.only:
            continue
        runs = [fn(scene, masked, args.threads, args.ratio) for _ in range(args.repeat)]
        r = runs[-1]
        C = np.asarray(r["C"])
        reg = np.all(np.isfinite(C), axis=1)
        rms = sfm_scenes.align_rms(C[reg], C_true[reg]) if reg.sum() >= 3 else float("nan")
        t = statistics.median(float(x["time"]) for x in runs)
        c = statistics.median(float(x["cpu"]) for x in runs)
        rot = rotation_errors(np.asarray(r["R"]), np.asarray(scene["R"]))
        label = f"{name}, {'board mask' if masked else 'whole frames'}"
        names = scene["names"]
        which = ", ".join(names[i].split(".")[0] for i in np.flatnonzero(reg).tolist()) or "-"
        rows.append(
            [
                label,
                f"{reg.sum()}/{reg.size}",
                which,
                "-" if not np.isfinite(rms) else f"{100 * rms:.2f} %",
                "-" if rot.size == 0 else f"{np.median(rot):.2f}",
                r["points"],
                f"{c:.1f}",
                f"{t:.1f}",
            ]
        )
        if r["note"]:
            notes.append(f"- {label}: {r['note']}")
        print(rows[-1], r["note"], flush=True)
    load = os.getloadavg()
    print(header("Structure from motion on real views: imageform vs pycolmap (a chessboard)"))
    print(
        f"OpenCV's 13 views of a 9 x 6 chessboard (opencv-left, 640 x 480 grey); truth: "
        f"imageform's calibration of them (fx {K[0, 0]:.2f}, fy {K[1, 1]:.2f}, cx "
        f"{K[0, 2]:.2f}, cy {K[1, 2]:.2f}, RMS {scene['rms']:.2f} px) and its board poses; "
        f"masks: the corners' convex hull dilated by {args.dilate} px; every pair matched, "
        f"Lowe's ratio {args.ratio:g}; "
        f"{args.threads} thread(s) each; median of {args.repeat} runs; machine loaded (load "
        f"average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}).\n"
    )
    print(
        markdown_table(
            [
                "library",
                "registered",
                "which views",
                "trajectory RMS (of path)",
                "rotation error deg (median)",
                "points",
                "CPU time s",
                "wall time s",
            ],
            rows,
        )
    )
    if notes:
        print("\nWhat each reported (the first notes):\n\n" + "\n".join(notes))
    mc = match_check(scene, args.ratio)
    share = 100 * int(mc["correct"]) / max(int(mc["matches"]), 1)
    print(
        f"\nWhy (imageform's SIFT on the masked views, Lowe's ratio {args.ratio:g} and the "
        "mutual check, "
        "every pair; a match is correct when the truth's board homography carries it within "
        "3 px):\n"
    )
    print(
        markdown_table(
            ["keypoints a view (min / median / max)", "pairs", "matches", "correct",
             "best pair (correct)", "pairs with 30 correct"],
            [[" / ".join(str(v) for v in mc["keypoints"]), mc["pairs"], mc["matches"],
              f"{mc['correct']} ({share:.0f} %)", mc["best_pair"], mc["pairs_30"]]],
        )
    )  # fmt: skip


if __name__ == "__main__":
    main()
