"""Structure from motion: imageform's reconstruct_sequence vs pycolmap on a walk through a room.

Issue 28's bar: 40 frames walking through a room whose walls are real photographs (the
Kodak set when ``../shared/data/kodak`` is there, scikit-image's photographs otherwise),
with defocus blur, sensor noise and JPEG compression (``tests/sfm_scenes.py``), every frame
registered (95 % at least), the camera path after a similarity alignment within 0.1 % of
its length of the truth and no worse than pycolmap's, in no more time. Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_reconstruct.py [--frames 40] [--repeat 3] \
        [--window W] [--contrast-threshold C] [--seed S]

``--window``, ``--contrast-threshold`` and ``--seed`` (``rng``) go to imageform's
``reconstruct_sequence`` (its defaults otherwise); imageform's row adds the largest rotation
error over the frames (degrees, ``sfm_scenes.rotation_errors_deg``) and the mean track length.

Both get the same frames (pycolmap reads them as lossless PNGs of the degraded frames) and
the same pinhole camera, fixed (pycolmap: a ``PINHOLE`` camera with the true intrinsics,
``ba_refine_*`` off; SIFT features, sequential matching with its default overlap of 10 and
loop detection off, incremental mapping). Each library runs with one thread
(``--threads``). Trajectory RMS: the camera centres after the best similarity (Umeyama
1991) to the true ones, RMS distance as a share of the true path's length; time: the whole
call (features, matching, mapping), median of ``--repeat`` runs, in CPU seconds of the
process (every thread; the fair figure on a shared machine) and in wall seconds.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table
from tests import sfm_scenes

#: ``reconstruct_sequence``'s keyword arguments (``--window``, ``--contrast-threshold``);
#: empty: its defaults.
IMAGEFORM_KWARGS: dict[str, Any] = {}


def run_imageform(frames: list[np.ndarray], K: np.ndarray, threads: int) -> dict[str, object]:
    import cv2

    from imageform.geometry import reconstruct_sequence

    cv2.setNumThreads(threads)
    t0, c0 = time.perf_counter(), time.process_time()
    rec = reconstruct_sequence(frames, K, **IMAGEFORM_KWARGS)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    C = np.array([-R.T @ t for R, t in zip(rec.R, rec.t, strict=True)])
    out = {"C": C, "reg": rec.registered, "points": rec.points.shape[0], "time": dt, "cpu": dc}
    out |= {"R": rec.R, "track": float(np.mean(rec.track_length)) if len(rec.points) else 0.0}
    return out


def pycolmap_options(threads: int, model: str, params: Sequence[float]) -> tuple[Any, ...]:
    """pycolmap's options as the benchmarks set them: ``(reader, extraction, matching, mapping)``.

    One camera ``model`` with ``params`` (COLMAP's order), kept fixed (``ba_refine_*`` off);
    features and matching on the CPU; ``threads`` threads each; mapping seed 0.
    """
    import pycolmap

    reader = pycolmap.ImageReaderOptions()
    reader.camera_model = model
    reader.camera_params = ",".join(str(float(v)) for v in params)
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.num_threads = threads
    extraction.use_gpu = False
    matching = pycolmap.FeatureMatchingOptions()
    matching.num_threads = threads
    matching.use_gpu = False
    opts = pycolmap.IncrementalPipelineOptions()
    opts.num_threads = threads
    opts.ba_refine_focal_length = False
    opts.ba_refine_principal_point = False
    opts.ba_refine_extra_params = False
    opts.random_seed = 0
    return reader, extraction, matching, opts


def pycolmap_reconstruct(
    root: Path, images: Path, options: tuple[Any, ...], match: Callable[[Path], object]
) -> tuple[dict[int, Any], float, float]:
    """Features, ``match(database)`` and incremental mapping of ``images``: the models, times.

    ``options`` from :func:`pycolmap_options`; the database and the models go in ``root``.
    Returns the models, the wall and the CPU seconds of the whole.
    """
    import pycolmap

    reader, extraction, _, opts = options
    db = root / "database.db"
    t0, c0 = time.perf_counter(), time.process_time()
    pycolmap.extract_features(
        db,
        images,
        camera_mode=pycolmap.CameraMode.SINGLE,
        reader_options=reader,
        extraction_options=extraction,
        device=pycolmap.Device.cpu,
    )
    match(db)
    maps = pycolmap.incremental_mapping(db, images, root / "sparse", options=opts)
    return maps, time.perf_counter() - t0, time.process_time() - c0


def pycolmap_poses(maps: dict[int, Any], names: list[str]) -> tuple[np.ndarray, np.ndarray, int]:
    """Camera centres and rotations (NaN where not registered) of the largest model, points."""
    C = np.full((len(names), 3), np.nan)
    R = np.full((len(names), 3, 3), np.nan)
    points = 0
    if maps:
        best = max(maps.values(), key=lambda r: r.num_reg_images())
        points = best.num_points3D()
        for image in best.images.values():
            if image.has_pose:
                C[names.index(image.name)] = image.projection_center()
                R[names.index(image.name)] = image.cam_from_world().rotation.matrix()
    return C, R, points


def run_pycolmap(frames: list[np.ndarray], K: np.ndarray, threads: int) -> dict[str, object]:
    import cv2
    import pycolmap

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        images = root / "images"
        images.mkdir()
        names = [f"{i:04d}.png" for i in range(len(frames))]
        for name, f in zip(names, frames, strict=True):
            cv2.imwrite(str(images / name), f[..., ::-1])
        options = pycolmap_options(threads, "PINHOLE", (K[0, 0], K[1, 1], K[0, 2], K[1, 2]))
        pairing = pycolmap.SequentialPairingOptions()
        pairing.num_threads = threads

        def match(db: Path) -> None:
            pycolmap.match_sequential(
                db, matching_options=options[2], pairing_options=pairing, device=pycolmap.Device.cpu
            )

        maps, dt, dc = pycolmap_reconstruct(root, images, options, match)
    C, _, points = pycolmap_poses(maps, names)
    reg = np.all(np.isfinite(C), axis=1)
    return {"C": C, "reg": reg, "points": points, "time": dt, "cpu": dc}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--focal", type=float, default=450.0)
    ap.add_argument("--blur", type=float, default=0.7)
    ap.add_argument("--noise", type=float, default=2.0)
    ap.add_argument("--jpeg", type=int, default=90)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--only", choices=["imageform", "pycolmap"], default=None)
    ap.add_argument("--window", type=int, default=None, help="imageform's window (default: its)")
    ap.add_argument(
        "--contrast-threshold", type=float, default=None, help="imageform's SIFT contrast"
    )
    ap.add_argument("--seed", type=int, default=None, help="imageform's RANSAC seed (rng)")
    args = ap.parse_args()
    if args.seed is not None:
        IMAGEFORM_KWARGS["rng"] = args.seed
    if args.window is not None:
        IMAGEFORM_KWARGS["window"] = args.window
    if args.contrast_threshold is not None:
        IMAGEFORM_KWARGS["contrast_threshold"] = args.contrast_threshold
    w, h = args.width, args.height
    K = np.array([[args.focal, 0, (w - 1) / 2], [0, args.focal, (h - 1) / 2], [0, 0, 1.0]])
    frames, truth = sfm_scenes.sequence(
        K, args.frames, (w, h), noise=args.noise, blur=args.blur, jpeg=args.jpeg
    )
    C_true = np.array([-R.T @ t for R, t in truth])
    runners = {"imageform": run_imageform, "pycolmap": run_pycolmap}
    rows = []
    for name, fn in runners.items():
        if args.only and name != args.only:
            continue
        runs = [fn(frames, K, args.threads) for _ in range(args.repeat)]
        r = runs[-1]
        reg = np.asarray(r["reg"], bool)
        C = np.asarray(r["C"])
        rms = sfm_scenes.align_rms(C[reg], C_true[reg]) if reg.sum() >= 3 else float("nan")
        rot = "-"
        if "R" in r and reg[0]:
            sub = [truth[i] for i in np.flatnonzero(reg)]
            err = sfm_scenes.rotation_errors_deg(np.asarray(r["R"])[reg], sub)
            rot = f"{float(np.max(err)):.3f}"
        t = statistics.median(float(x["time"]) for x in runs)  # type: ignore[arg-type]
        c = statistics.median(float(x["cpu"]) for x in runs)  # type: ignore[arg-type]
        rows.append(
            [
                name,
                f"{reg.sum()}/{reg.size}",
                f"{100 * rms:.4f} %",
                rot,
                r["points"],
                f"{r['track']:.2f}" if "track" in r else "-",
                f"{c:.1f}",
                f"{t:.1f}",
            ]
        )
        print(rows[-1], flush=True)
    load = os.getloadavg()
    print(header("Structure from motion: imageform vs pycolmap (a walk through a room)"))
    print(
        f"{args.frames} frames {w} x {h}, f = {args.focal:g} px, blur {args.blur} px, "
        f"noise {args.noise} grey levels, JPEG quality {args.jpeg}; {args.threads} thread(s) "
        f"each; median of {args.repeat} runs; machine loaded (load average "
        f"{load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}).\n"
    )
    print(
        markdown_table(
            [
                "library",
                "registered",
                "trajectory RMS (of path)",
                "rotation error deg (largest)",
                "points",
                "track length",
                "CPU time s",
                "wall time s",
            ],
            rows,
        )
    )


if __name__ == "__main__":
    main()
