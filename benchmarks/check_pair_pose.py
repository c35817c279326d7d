"""The pair-pose fallback of structure from motion: why it registered a frame 12.8 degrees off.

``reconstruct_sequence``'s last fallback gives a frame the rotation of a verified pair's
essential matrix and only the scale from its 2-D/3-D correspondences; a pair is now taken only
when its inliers, refined in six degrees of freedom, turn the frame less than 5 degrees from the
pair's rotation (``_pair_pose_disagreement``). For each pose the fallback weighed (``_TRACE``):
its correspondences, the distinct points among them (one image position, 0.01 px), their spread
in the image (the standard deviations along its two axes), the rotation's error against the
truth (the pair's; refined by imageform's ``refine_pose``; refined by OpenCV's iterative
``solvePnP`` from the same start), the angle the rule measures and the largest reprojection
error after refining. Scenes: OpenCV's 13 chessboard views (``test_real_chessboard_views``' call;
truth: imageform's calibration of them, ``tests/sfm_scenes.py``), and the walk through a room
with a burned-in overlay and Kodak photographs 3 and 20 (``tests/geometry/test_sfm_intruders.py``;
no truth printed). Run::

    PYTHONPATH=src:. python benchmarks/check_pair_pose.py [--data ../shared/data]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402


def _deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))


def rows(name: str, rec: Any, trace: dict[str, Any], K: np.ndarray, R_true: Any) -> list[list[str]]:
    """One row per pose the fallback weighed in one reconstruction."""
    import cv2

    from imageform.geometry.pnp import refine_pose
    from imageform.geometry.sfm import _PAIR_POSE_TOL_DEG

    out = []
    for d in trace.get("pair_pose", []):
        X, uv = d["X"], d["uv"]
        Rr, tr, _ = refine_pose(
            d["R"][None].copy(), d["t"][None].copy(), X[None], uv[None], K, np.ones((1, len(X))), 30
        )
        cam = X @ Rr[0].T + tr[0]
        proj = cam @ K.T
        err = np.linalg.norm(proj[:, :2] / proj[:, 2:] - uv, axis=1)
        rv = None
        if len(X) >= 4:  # OpenCV's least
            _, rv, _ = cv2.solvePnP(
                X,
                uv,
                K,
                None,
                cv2.Rodrigues(d["R"])[0],
                d["t"].reshape(3, 1).copy(),
                True,
                cv2.SOLVEPNP_ITERATIVE,
            )
        distinct = np.unique(np.round(uv, 2), axis=0)
        spread = np.linalg.svd(distinct - distinct.mean(0), compute_uv=False) / np.sqrt(
            len(distinct)
        )
        f, g = d["frame"], d["pair"]
        if R_true is not None:
            truth = R_true[f] @ R_true[g].T  # frame g's camera to frame f's
            Rs = [d["R"], Rr[0]] + ([cv2.Rodrigues(rv)[0]] if rv is not None else [])
            errs = [f"{_deg(R @ d['R_other'].T @ truth.T):.2f}" for R in Rs]
            errs += ["-"] * (3 - len(errs))
        else:
            errs = ["-"] * 3
        out.append(
            [name, str(f), str(g), str(len(X)), str(len(distinct))]
            + [f"{spread[0]:.0f} / {spread[1]:.0f}"]
            + errs
            + [f"{d['angle']:.2f}", "refused" if d["angle"] >= _PAIR_POSE_TOL_DEG else "passes"]
            + [f"{err.max():.2f}"]
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data")
    args = ap.parse_args()
    import imageform.geometry.sfm as sfm
    from benchmarks.bench_reconstruct_real import rotation_errors
    from imageform.geometry import reconstruct_sequence
    from tests import sfm_scenes
    from tests.geometry.test_sfm_intruders import K as K_walk
    from tests.geometry.test_sfm_intruders import _kodak

    table, regs = [], []
    scene = sfm_scenes.chessboard_views(args.data / "opencv-left", dilate=25)
    K, R_true = np.asarray(scene["K"]), np.asarray(scene["R"])
    sfm._TRACE = {}
    rec = reconstruct_sequence(
        scene["images"], K, scene["distortion"], window=12, masks=scene["masks"]
    )
    table += rows("chessboard views", rec, sfm._TRACE or {}, K, R_true)
    errs = ", ".join(f"{e:.2f}" for e in rotation_errors(rec.R, R_true))
    regs.append(["chessboard views", " ".join(map(str, np.flatnonzero(rec.registered))), errs])
    frames, _ = sfm_scenes.sequence(K_walk, 8, (400, 300))
    photos = [_kodak(args.data, i, (400, 300)) for i in (3, 20)]
    seq = [sfm_scenes.burn_in(f) for f in [*frames, *photos]]
    sfm._TRACE = {}
    rec = reconstruct_sequence(seq, K_walk, max_features=2000)
    trace = sfm._TRACE or {}
    sfm._TRACE = None
    table += rows("walk, overlay", rec, trace, K_walk, None)
    regs.append(["walk, overlay", " ".join(map(str, np.flatnonzero(rec.registered))), "-"])
    print(header("The pair-pose fallback: a pair's rotation against its points"))
    cols = [
        "scene",
        "frame",
        "by its pair with",
        "correspondences",
        "distinct points",
        "spread px",
        "pair's rotation error deg",
        "refined (imageform) deg",
        "refined (OpenCV solvePnP) deg",
        "the rule's angle deg",
        "the rule",
        "largest error after refining px",
    ]
    print(markdown_table(cols, table))
    print(
        "\nThe rule's angle: the refined rotation against the pair's; a pose it passes still "
        "needs 6 correspondences (and half of those the frame has, 12 at most) to register the "
        "frame. The rotation errors: frame to frame, against the truth's.\n"
    )
    print(markdown_table(["scene", "registered", "rotation errors deg (to the first)"], regs))


if __name__ == "__main__":
    main()
