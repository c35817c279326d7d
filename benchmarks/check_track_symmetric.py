"""BoardTracker on a checkerboard video: the gradient refinement against the point-symmetry one.

Frames of ``tests/video_scenes.py`` (a 7 x 5-square checkerboard of 30 mm squares pasted on a
photograph, the camera circling it at 420 mm, f = 1000 px, 1280 x 720, sensor noise of 2
codes), rendered in memory (no video coding), fed to one ``BoardTracker`` per refinement
(its private ``_refinement``: ``"gradient"``, today's, or ``"symmetric"``: the detected frames
through ``find_checkerboard(method="symmetric")``, the tracked ones refined again by
``refine_corners_symmetric`` in a window of 0.8 of a square, at most 30 px). Reported against
the truth: the corners' error (the true corners projected, px), the pose's translation error
(share of the distance) and rotation error, the jitter (median frame-to-frame change of the
translation error), and the CPU time per frame (median and 95th percentile, tracked and
detected frames together; one pass, the two trackers interleaved frame by frame).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_track_symmetric.py --frames 120
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402
from tests import video_scenes  # noqa: E402

K = np.array([[1000.0, 0, 639.5], [0, 1000.0, 359.5], [0, 0, 1]])
SIZE = (1280, 720)
SQUARES = (7, 5)
SQUARE = 30.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=120)
    ns = ap.parse_args()
    from imageform.geometry import BoardTracker, rvec_to_matrix

    tex, origin = video_scenes.board_texture("checker", SQUARES)
    truth = video_scenes.poses(ns.frames)
    rng = np.random.default_rng(1)
    frames = [video_scenes.render(tex, origin, K, p, SIZE, rng=rng) for p in truth]
    cols, rows = SQUARES[0] - 1, SQUARES[1] - 1
    r, c = np.divmod(np.arange(cols * rows), cols)
    inner = np.column_stack([(c + 1) * SQUARE, (r + 1) * SQUARE, np.zeros(r.size)])
    names = ("gradient", "symmetric")
    trackers = {}
    for name in names:
        tr = BoardTracker((cols, rows), K, square=SQUARE)
        tr._refinement = name
        trackers[name] = tr
        tr.update(frames[0])  # compile / load the kernels
        tr.reset()
    stats: dict[str, dict[str, list[float]]] = {
        n: {"corner": [], "t": [], "r": [], "cpu": [], "tracked": []} for n in names
    }
    for frame, (R, t) in zip(frames, truth, strict=True):
        proj = (K @ (R @ inner.T + t[:, None])).T
        true_uv = proj[:, :2] / proj[:, 2:]
        for name in names:
            t0 = time.process_time()
            pose = trackers[name].update(frame)
            stats[name]["cpu"].append(time.process_time() - t0)
            if not pose.found:
                for k in ("corner", "t", "r"):
                    stats[name][k].append(np.nan)
                continue
            stats[name]["tracked"].append(float(pose.searched == "tracked"))
            uv = pose.image_points
            e0 = np.hypot(*(uv - true_uv).T)
            e1 = np.hypot(*(uv - true_uv[::-1]).T)  # half a turn: the same board
            turned = np.median(e1) < np.median(e0)
            stats[name]["corner"].append(float(np.median(e1 if turned else e0)))
            # the tracker's board frame: the first (or, turned, last) inner corner at 0
            Rb = np.asarray(rvec_to_matrix(pose.rvec))
            o = inner[-1] if turned else inner[0]
            flip = np.diag([-1.0, -1.0, 1.0]) if turned else np.eye(3)
            Rt = R @ flip
            tt = R @ o + t
            stats[name]["t"].append(float(np.linalg.norm(pose.tvec - tt) / np.linalg.norm(tt)))
            dR = Rb @ Rt.T
            stats[name]["r"].append(math.degrees(math.acos(np.clip((np.trace(dR) - 1) / 2, -1, 1))))
    rows_out = []
    for name in names:
        s = {k: np.asarray(v) for k, v in stats[name].items()}
        rows_out.append(
            [
                name,
                f"{np.isfinite(s['t']).sum()} / {len(frames)}",
                f"{100 * np.mean(s['tracked']):.0f} %",
                f"{np.nanmedian(s['corner']):.3f} / {np.nanpercentile(s['corner'], 95):.3f}",
                f"{100 * np.nanmedian(s['t']):.3f} / {100 * np.nanpercentile(s['t'], 95):.3f}",
                f"{np.nanmedian(s['r']):.3f} / {np.nanpercentile(s['r'], 95):.3f}",
                f"{100 * np.nanmedian(np.abs(np.diff(s['t']))):.4f}",
                f"{1000 * np.median(s['cpu']):.1f} / {1000 * np.percentile(s['cpu'], 95):.1f}",
            ]
        )
    print(header("BoardTracker on a checkerboard video: gradient vs point-symmetry refinement"))
    print(
        f"{len(frames)} frames of tests/video_scenes.py (7 x 5 squares of 30 mm, 1280 x 720, "
        f"f = 1000 px); load average at the end {os.getloadavg()[0]:.1f} (2 shared cores).\n"
    )
    print(
        markdown_table(
            [
                "refinement",
                "frames with a pose",
                "frames tracked",
                "corner error px (median of the frames' medians / 95th pct)",
                "translation error % (median / 95th pct)",
                "rotation error deg (median / 95th pct)",
                "jitter % (median frame-to-frame change of the translation error)",
                "CPU ms per frame (median / 95th pct)",
            ],
            rows_out,
        )
    )


if __name__ == "__main__":
    main()
