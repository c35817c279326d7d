"""Structure from motion through a strong fisheye: the room walk with its truth, at the rim.

The walk of ``tests/sfm_scenes.py`` rendered through an equidistant fisheye
(``KannalaBrandt`` with k = 0, f = 110 px, 320 x 240: the frame's sides 83 degrees off axis,
undistortion stretching the rim's pixels many times), as in
``tests/geometry/test_sfm_fisheye.py``: ``--frames`` frames of a walk of twice as many, the
keypoints kept out of a central disc (``--rims``: its radius in pixels, 0 none; an
endoscope's dark lumen) and the render's noise (``--noises``, grey levels), each with the
RANSAC seeds ``--seeds`` (``rng``). Errors against the true poses: the camera centres after
the best similarity (Umeyama 1991), RMS as a share of the path's length, and the largest
rotation error over the frames (degrees, ``sfm_scenes.rotation_errors_deg``); the mean track
length (views a point) and the CPU seconds of ``reconstruct_sequence``. A before/after
comparison runs it on two checkouts. Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/bench_reconstruct_fisheye.py \\
        [--frames 8 12 16] [--rims 0 60 100] [--noises 1.5 4] [--seeds 0 1 2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table
from tests import sfm_scenes

SIZE = (320, 240)
K = np.array([[110.0, 0, 159.5], [0, 110.0, 119.5], [0, 0, 1]])


def run(n: int, rim: float, noise: float, seed: int) -> dict[str, float]:
    """One reconstruction of the fisheye walk and its errors against the truth."""
    from imageform.geometry import KannalaBrandt, reconstruct_sequence

    lens = KannalaBrandt(0.0, 0.0, 0.0, 0.0)
    truth = sfm_scenes.poses(2 * n)[:n]
    rng = np.random.default_rng(5)
    frames = [sfm_scenes.render(K, p, SIZE, rng=rng, distortion=lens, noise=noise) for p in truth]
    yy, xx = np.mgrid[: SIZE[1], : SIZE[0]]
    mask = np.hypot(xx - K[0, 2], yy - K[1, 2]) > rim
    c0 = time.process_time()
    rec = reconstruct_sequence(frames, K, lens, masks=mask, rng=seed)
    cpu = time.process_time() - c0
    reg = rec.registered
    C = np.array([-r.T @ t for r, t in zip(rec.R, rec.t, strict=True)])
    Ct = np.array([-r.T @ t for r, t in truth])
    rms = sfm_scenes.align_rms(C[reg], Ct[reg]) if reg.sum() >= 3 else float("nan")
    err = sfm_scenes.rotation_errors_deg(rec.R[reg], [truth[i] for i in np.flatnonzero(reg)])
    return {
        "reg": int(reg.sum()),
        "rms": 100 * rms,
        "rot": float(np.max(err)),
        "track": float(np.mean(rec.track_length)),
        "cpu": cpu,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, nargs="+", default=[8, 12, 16])
    ap.add_argument("--rims", type=float, nargs="+", default=[0.0, 60.0, 100.0])
    ap.add_argument("--noises", type=float, nargs="+", default=[1.5, 4.0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    args = ap.parse_args()
    rows = []
    for n in args.frames:
        for rim in args.rims:
            for noise in args.noises:
                res = [run(n, rim, noise, s) for s in args.seeds]
                rows.append(
                    [
                        n,
                        f"{rim:g}",
                        f"{noise:g}",
                        " / ".join(f"{r['reg']}" for r in res),
                        " / ".join(f"{r['rms']:.4f}" for r in res),
                        " / ".join(f"{r['rot']:.3f}" for r in res),
                        f"{np.mean([r['track'] for r in res]):.2f}",
                        f"{np.median([r['cpu'] for r in res]):.2f}",
                    ]
                )
                print(rows[-1], file=sys.stderr, flush=True)
    print(header("Structure from motion through a strong fisheye: the walk against its truth"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine)\n")
    seeds = " / ".join(str(s) for s in args.seeds)
    cols = [
        "frames",
        "no keypoints within px of the center",
        "noise",
        f"registered, seeds {seeds}",
        "trajectory RMS % of the path",
        "largest rotation error deg",
        "track length (mean)",
        "CPU s (median)",
    ]
    print(markdown_table(cols, rows))


if __name__ == "__main__":
    main()
