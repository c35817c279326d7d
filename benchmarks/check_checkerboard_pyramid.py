"""Checkerboard corners on large rendered views: this tree against a ``--before`` tree.

``find_checkerboard(view, (9, 6))`` (default symmetric refinement) on rendered views with
known corners (:func:`check_corner_refinement._render`: random poses tilted up to 45 deg,
radial distortion, a Gaussian blur, vignetting, a shading slope, Gaussian noise, JPEG) at
640 x 480 (``--scale 1``) and at ``3`` times the size (1920 x 1440, the blur 3 times as wide:
squares of 60-110 px, windows of radius 40 and more, refined coarse to fine since
2026-12-02); per condition the mean and largest distance (px) of the corners to the truth,
for this tree's ``src`` and ``--before``'s (another checkout's ``src``, e.g. main's), each in
its own process on the same saved views. With ``--real DIR`` (OpenCV's ``left*.jpg``, 9 x 6),
also the real views as they are (640 x 480) and upscaled to 1920 x 1440 (``cv2.resize``,
bilinear): the largest difference (px) between the two trees' corners and the RMS of
``calibrate_camera`` (this tree's) on each tree's corners. Run from the project root::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 python benchmarks/check_checkerboard_pyramid.py \\
        --before /tmp/main/src [--views 6] [--seed 3] [--scales 1,3] [--real DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.check_corner_refinement import CONDITIONS, _render  # noqa: E402


def worker(npz: str) -> None:
    """Print (JSON) the corner errors of this process's imageform on the views in ``npz``."""
    from imageform.geometry import find_checkerboard

    data = np.load(npz)
    out: list[list[float] | None] = []
    for k in range(int(data["n"])):
        det = find_checkerboard(data[f"img{k}"], (9, 6))
        if not det.found:
            out.append(None)
            continue
        truth = data[f"truth{k}"]
        c = np.asarray(det.corners)
        d = np.sqrt(((c[:, None] - truth[None]) ** 2).sum(-1)).min(1)
        out.append(d.tolist())
    print(json.dumps(out))


def real_worker(folder: str, size: str, npz: str) -> None:
    """Save (``npz``) this process's corners of the views in ``folder`` at ``size`` (WxH)."""
    import cv2

    from imageform.geometry import find_checkerboard

    w, h = (int(v) for v in size.split("x"))
    corners = []
    for p in sorted(Path(folder).glob("left*.jpg")):
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        assert img is not None, p
        if img.shape != (h, w):
            img = cv2.resize(img, (w, h), interpolation=cv2.INTER_LINEAR)
        det = find_checkerboard(img, (9, 6))
        corners.append(np.asarray(det.corners) if det.found else np.full((54, 2), np.nan))
    np.save(npz, np.stack(corners))


def real(trees: dict[str, str], folder: str, tmp: str) -> None:
    """Print the real views' rows: corner differences and calibrate_camera's RMS per tree."""
    from imageform.geometry import calibrate_camera, checkerboard_points

    print("\n| views | code | found | max corner diff vs before (px) | calibrate_camera RMS (px) |")
    print("|---|---|---|---|---|")
    obj = checkerboard_points((9, 6), 1.0)
    for size in ("640x480", "1920x1440"):
        got = {}
        for name, src in trees.items():
            npz = f"{tmp}/real-{name}-{size}.npy"
            env = dict(os.environ, PYTHONPATH=src)
            cmd = [sys.executable, __file__, "--before", src, "--worker", npz,
                   "--real", folder, "--size", size]  # fmt: skip
            run = subprocess.run(cmd, env=env, capture_output=True, text=True)
            if run.returncode != 0:
                raise RuntimeError(run.stderr[-2000:])
            got[name] = np.load(npz)
        ok = np.all(np.isfinite(got["before"]), axis=(1, 2)) & np.all(
            np.isfinite(got["after"]), axis=(1, 2)
        )
        wh = tuple(int(v) for v in size.split("x"))
        for name, c in got.items():
            diff = float(np.abs(c[ok] - got["before"][ok]).max())
            rms = calibrate_camera([obj] * int(ok.sum()), list(c[ok]), wh).rms  # type: ignore[arg-type]
            print(f"| {size} | {name} | {int(ok.sum())}/{len(c)} | {diff:.4f} | {rms:.5f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--before", required=True, help="another tree's src (e.g. main's)")
    ap.add_argument("--views", type=int, default=6, help="rendered views per condition")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--scales", default="1,3")
    ap.add_argument("--worker", default="")
    ap.add_argument("--real", default="", help="OpenCV's left*.jpg folder")
    ap.add_argument("--size", default="")
    args = ap.parse_args()
    if args.worker and args.real:
        real_worker(args.real, args.size, args.worker)
        return
    if args.worker:
        worker(args.worker)
        return
    trees = {"before": args.before, "after": str(ROOT / "src")}
    print("| views | condition | code | found | mean error (px) | largest error (px) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scale in (int(s) for s in args.scales.split(",") if s):
            for label, blur, k1, noise, jpeg in CONDITIONS:
                rng = np.random.default_rng(args.seed)
                views = [_render(rng, blur, k1, noise, jpeg, scale) for _ in range(args.views)]
                npz = f"{tmp}/views.npz"
                arrays = {f"img{k}": v[0] for k, v in enumerate(views)}
                arrays.update({f"truth{k}": v[1] for k, v in enumerate(views)})
                arrays["n"] = np.array(len(views))
                np.savez(npz, **arrays)  # type: ignore[arg-type]
                for name, src in trees.items():
                    env = dict(os.environ, PYTHONPATH=src)
                    cmd = [sys.executable, __file__, "--before", src, "--worker", npz]
                    run = subprocess.run(cmd, env=env, capture_output=True, text=True)
                    if run.returncode != 0:
                        raise RuntimeError(run.stderr[-2000:])
                    got = json.loads(run.stdout.strip().splitlines()[-1])
                    errs = [np.array(e) for e in got if e is not None]
                    e = np.concatenate(errs) if errs else np.full(1, np.nan)
                    size = f"{640 * scale}x{480 * scale}"
                    print(
                        f"| {size} | {label} | {name} | {len(errs)}/{len(got)} "
                        f"| {e.mean():.4f} | {e.max():.4f} |",
                        flush=True,
                    )
        if args.real:
            real(trees, args.real, tmp)


if __name__ == "__main__":
    main()
