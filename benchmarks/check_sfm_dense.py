"""Denser SIFT keypoints in structure from motion on a real colonoscopy video: where the CPU goes.

The clip of ``check_endo_real.py`` (``--video``: C3VD v3's preview
``assets/aligned_prev_final.mp4``, github.com/DurrLab/C3VDv3 at ``ad9391d``, CC BY 4.0; its
colour panel, the camera ``tests/data/endo/camera.toml``), every ``--every``-th frame, the
aperture mask (``field_of_view_mask``, as ``imageform reconstruct --auto-mask``), and
``reconstruct_sequence`` at SIFT contrast thresholds ``--contrast`` (0.01, the threshold
``check_endo_real.py``'s rows use for endoscopic tissue, and lower ones: more keypoints).

Three tables:

1. **Where the CPU goes** (``--before DIR``: another checkout's root, e.g. ``git archive`` of
   main): each run in a fresh process, the checkout under test first on ``PYTHONPATH``, the
   before and after runs interleaved ``--repeat`` times at contrast 0.01 and the lowest of
   ``--contrast``; CPU seconds (``time.process_time``) of the mask and the whole call, and of
   each stage (the module functions it calls, timed by wrappers): SIFT (``detect_features``),
   matching (``match_features``), the visual-word pairs (``_similar_pairs``), the pairs'
   verification (``find_essential_matrix`` and ``recover_pose``), track building
   (``_build_tracks``), PnP (``solve_pnp_ransac``), triangulation (``_triangulate_tracks``),
   bundle adjustment (``_schur_lm``), the rest (the mask, completion, filters, imports, ...).
   Medians over the repeats.
2. **Before and after, the same inputs**: the reconstructions' figures side by side (registered
   frames, points, mean track length, points seen in 8 frames or more, agreement with
   pycolmap, the frames registered by a verified pair's pose: the last fallback, from the
   notes).
3. **Is a lower contrast worth it now** (the checkout under test alone): every contrast of
   ``--contrast`` with RANSAC seeds ``--seeds``; against contrast 0.01 the registered frames,
   points, mean track length, long tracks, the agreement with pycolmap (median rotation and
   translation direction of consecutive relative poses, the worst rotation: ``agreement`` and
   ``worst_rotation`` of ``check_endo_real.py``) and the CPU, also as a ratio to the
   before-checkout's median CPU at 0.01 (table 1).

The reference is pycolmap's reconstruction with the aperture mask and SIFT's peak threshold / 4,
read from ``--reference-cache`` (``check_endo_real.py --reference-cache DIR`` writes it:
``pycolmap-every{E}-1.npz``). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_dense.py \\
        --video /tmp/endo/c3vdv3_prev.mp4 --reference-cache /tmp/endo/refcache \\
        --before /tmp/main-checkout [--every 8 4] [--repeat 3] [--seeds 0 1 2 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402

#: the stages timed: (label, module, function name)
STAGES = (
    ("SIFT (detect_features)", "imageform.geometry.sfm", "detect_features"),
    ("matching (match_features)", "imageform.geometry.sfm", "match_features"),
    ("visual-word pairs (_similar_pairs)", "imageform.geometry.sfm", "_similar_pairs"),
    ("verification (essential matrix)", "imageform.geometry.twoview", "find_essential_matrix"),
    ("verification (recover_pose)", "imageform.geometry.relative_pose", "recover_pose"),
    ("track building (_build_tracks)", "imageform.geometry.sfm", "_build_tracks"),
    ("PnP (solve_pnp_ransac)", "imageform.geometry.pnp_ransac", "solve_pnp_ransac"),
    ("triangulation (_triangulate_tracks)", "imageform.geometry.sfm", "_triangulate_tracks"),
    ("bundle adjustment (_schur_lm)", "imageform.geometry.sfm", "_schur_lm"),
)


def child(spec: dict[str, Any]) -> dict[str, Any]:
    """One run, in this process: the figures and the stages' CPU seconds."""
    import importlib

    from benchmarks.check_endo_real import agreement, read_clip, worst_rotation
    from imageform.geometry import field_of_view_mask, reconstruct_sequence
    from imageform.io import read_camera

    spent = {label: 0.0 for label, _, _ in STAGES}
    for label, module, name in STAGES:
        mod = importlib.import_module(module)
        fn = getattr(mod, name)

        def timed(*a: Any, _fn: Any = fn, _label: str = label, **k: Any) -> Any:
            c = time.process_time()
            try:
                return _fn(*a, **k)
            finally:
                spent[_label] += time.process_time() - c

        setattr(mod, name, timed)
    cam = read_camera(Path(spec["camera"])).camera
    frames = read_clip(Path(spec["video"]), 445)[:: spec["every"]]
    c0 = time.process_time()
    masks = field_of_view_mask(frames)
    rec = reconstruct_sequence(
        frames,
        cam.K,
        cam.distortion,
        masks=masks,
        contrast_threshold=spec["contrast"],
        rng=spec["seed"],
    )
    cpu = time.process_time() - c0
    with np.load(Path(spec["reference"]), allow_pickle=False) as ref:
        rot, tra = agreement(rec.R, rec.t, ref["R"], ref["t"])
        worst = worst_rotation(rec.R, ref["R"])
    tl = np.asarray(rec.track_length)
    return {
        "reg": int(rec.registered.sum()),
        "n": len(frames),
        "points": int(rec.points.shape[0]),
        "track": float(tl.mean()) if tl.size else float("nan"),
        "long": int((tl >= 8).sum()),
        "rot": rot,
        "tra": tra,
        "worst": worst,
        "by_pair": sum("registered by the pose of its pair" in m for m in rec.notes),
        "cpu": cpu,
        "stages": spent,
    }


def run(checkout: Path, spec: dict[str, Any]) -> dict[str, Any]:
    """One run in a fresh process with ``checkout``'s sources first on the path."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(checkout / "src"), str(ROOT)])
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    done = subprocess.run(
        [sys.executable, __file__, "--child", json.dumps(spec)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        raise SystemExit(f"a run failed ({checkout}, {spec}):\n{done.stderr[-2000:]}")
    out: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return out


def _med(runs: list[dict[str, Any]], key: str) -> float:
    return statistics.median(float(r[key]) for r in runs)


def _figures(r: dict[str, Any]) -> list[str]:
    return [
        f"{r['reg']}/{r['n']}",
        str(r["points"]),
        f"{r['track']:.2f}",
        str(r["long"]),
        f"{r['rot']:.2f} / {r['tra']:.2f}",
        f"{r['worst']:.2f}",
        str(r["by_pair"]),
    ]


def profile_table(
    before: Path, every: int, low: float, repeat: int, base: dict[str, Any]
) -> tuple[str, float, dict[tuple[str, float], list[dict[str, Any]]]]:
    """Table 1 and 2 of one stride; the before-checkout's median CPU at contrast 0.01."""
    runs: dict[tuple[str, float], list[dict[str, Any]]] = {}
    for _ in range(repeat):
        for ct in (0.01, low):
            for side, checkout in (("before", before), ("after", ROOT)):
                r = run(checkout, base | {"every": every, "contrast": ct, "seed": 0})
                runs.setdefault((side, ct), []).append(r)
                print(
                    f"  every {every}, {side}, contrast {ct:g}: {r['cpu']:.2f} s", file=sys.stderr
                )
    keys = [("before", 0.01), ("after", 0.01), ("before", low), ("after", low)]
    rows = []
    for label, _, _ in STAGES:
        rows.append(
            [label]
            + [f"{statistics.median(r['stages'][label] for r in runs[k]):.2f}" for k in keys]
        )
    rest = [statistics.median(r["cpu"] - sum(r["stages"].values()) for r in runs[k]) for k in keys]
    rows.append(["the rest (mask, completion, filters, imports)"] + [f"{v:.2f}" for v in rest])
    tot = [_med(runs[k], "cpu") for k in keys]
    rows.append(["**all (CPU s)**"] + [f"**{v:.2f}**" for v in tot])
    rows.append(["all, to before at 0.01"] + [f"{v / tot[0]:.2f}" for v in tot])
    cols = ["stage", "before, 0.01", "after, 0.01", f"before, {low:g}", f"after, {low:g}"]
    n = runs[keys[0]][0]["n"]
    text = f"### Every {every}th frame ({n} frames): CPU s by stage, median of {repeat}\n\n"
    text += markdown_table(cols, rows)
    same = []
    for ct in (0.01, low):
        b, a = runs[("before", ct)][0], runs[("after", ct)][0]
        same.append([f"{ct:g}", "before"] + _figures(b))
        same.append([f"{ct:g}", "after"] + _figures(a))
    cols2 = [
        "contrast",
        "checkout",
        "registered",
        "points",
        "track length",
        "points seen in 8 frames or more",
        "vs pycolmap: rotation / translation deg (median)",
        "worst rotation deg",
        "registered by a pair's pose",
    ]
    text += f"\n\n### Every {every}th frame: the reconstructions before and after (seed 0)\n\n"
    text += markdown_table(cols2, same)
    return text, tot[0], runs


def quality_table(
    every: int, contrasts: list[float], seeds: list[int], base: dict[str, Any], ref_cpu: float
) -> str:
    """Table 3 of one stride: each contrast and seed, then medians over the seeds."""
    rows, summary = [], []
    for ct in contrasts:
        runs = []
        for seed in seeds:
            r = run(ROOT, base | {"every": every, "contrast": ct, "seed": seed})
            runs.append(r)
            print(f"  every {every}, contrast {ct:g}, seed {seed}: {r['reg']}", file=sys.stderr)
            rows.append([f"{ct:g}", str(seed)] + _figures(r) + [f"{r['cpu']:.1f}"])
        worst = [r["worst"] for r in runs]
        summary.append(
            [
                f"{ct:g}",
                f"{min(r['reg'] for r in runs)}/{runs[0]['n']}",
                f"{_med(runs, 'points'):.0f}",
                f"{_med(runs, 'track'):.2f}",
                f"{_med(runs, 'long'):.0f}",
                f"{_med(runs, 'rot'):.2f} / {_med(runs, 'tra'):.1f}",
                f"{statistics.median(worst):.2f} ({min(worst):.2f} to {max(worst):.2f})",
                f"{_med(runs, 'cpu'):.1f}",
                f"{_med(runs, 'cpu') / ref_cpu:.2f}",
            ]
        )
    cols = [
        "contrast",
        "seed",
        "registered",
        "points",
        "track length",
        "points seen in 8 frames or more",
        "vs pycolmap: rotation / translation deg (median)",
        "worst rotation deg",
        "registered by a pair's pose",
        "CPU s",
    ]
    cols_s = [
        "contrast",
        "registered (fewest)",
        "points",
        "track length",
        "points seen in 8 frames or more",
        "rotation deg / translation deg (median)",
        "worst rotation deg: median (range)",
        "CPU s",
        "CPU to before at 0.01",
    ]
    text = (
        f"### Every {every}th frame, after: medians over RANSAC seeds {seeds[0]} to {seeds[-1]}\n\n"
    )
    text += markdown_table(cols_s, summary)
    text += f"\n\n### Every {every}th frame, after: each run\n\n" + markdown_table(cols, rows)
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--video", type=Path)
    ap.add_argument("--camera", type=Path, default=ROOT / "tests" / "data" / "endo" / "camera.toml")
    ap.add_argument("--reference-cache", type=Path)
    ap.add_argument("--before", type=Path, default=None, help="the checkout to compare with")
    ap.add_argument("--every", type=int, nargs="+", default=[8, 4])
    ap.add_argument("--contrast", type=float, nargs="+", default=[0.01, 0.0075, 0.005])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if args.child is not None:
        print(json.dumps(child(json.loads(args.child))))
        return
    if args.video is None or args.reference_cache is None:
        ap.error("--video and --reference-cache are needed")
    print(header("Denser SIFT keypoints in structure from motion: where the CPU goes"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average at the start: {load} (a shared machine)\n")
    for every in args.every:
        base = {
            "video": str(args.video),
            "camera": str(args.camera),
            "reference": str(args.reference_cache / f"pycolmap-every{every}-1.npz"),
        }
        ref_cpu = float("nan")
        if args.before is not None:
            text, ref_cpu, _ = profile_table(
                args.before, every, min(args.contrast), args.repeat, base
            )
            print(text + "\n")
        print(quality_table(every, sorted(args.contrast, reverse=True), args.seeds, base, ref_cpu))
        print()
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average at the end: {load}")


if __name__ == "__main__":
    main()
