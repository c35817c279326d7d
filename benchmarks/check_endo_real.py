"""Structure from motion on a real colonoscopy video: imageform's masks and SIFT contrast, pycolmap.

A real endoscopic clip, given on the command line (nothing is downloaded; the video stays
out of the repository): ``--video``, C3VD v3's preview ``assets/aligned_prev_final.mp4``
(github.com/DurrLab/C3VDv3 at ``ad9391d``, CC BY 4.0; 289 frames at 60 fps of a
colonoscope in a colon phantom, six panels side by side, the colour video the first
``--panel-width`` 445 columns; tests/data/endo/README.md has ten of its frames and the
source). An octagonal aperture in black corners, smooth low-contrast tissue, specular
highlights, a dark lumen, strong fisheye distortion. There is no ground-truth trajectory
for this clip: the reference is pycolmap's reconstruction with the aperture masked and
SIFT's peak threshold at a quarter of its default (all frames registered), and the
agreement columns are a cross-check between two programs, not errors.

Both get one camera, fixed (``--camera``, default tests/data/endo/camera.toml, an
OpenCV-fisheye camera pycolmap self-calibrated on the clip: imageform ``KannalaBrandt``,
pycolmap ``OPENCV_FISHEYE`` with the same numbers, ``ba_refine_*`` off), and every
``--every``-th frame. imageform: ``reconstruct_sequence`` with its defaults (``window=3``
and visual-word loop pairs), through the masks of ``field_of_view_mask`` (``--auto-mask``)
and ``highlight_mask`` (``--highlights``) and the SIFT contrast threshold
(``--contrast-threshold``) in each combination measured. pycolmap: sequential matching
(its defaults: 10 neighbours, no loop detection), incremental mapping, with and without
the same field-of-view mask (``ImageReaderOptions.mask_path``) and SIFT's peak threshold
(its default 0.02/3, and a quarter of it, the ratio of imageform's 0.01 to OpenCV's 0.04).

Columns: registered frames, points, mean track length (observations a point), median
reprojection error (px), median SIFT keypoints a frame (imageform's ``detect_features``
with the row's mask and threshold), wall seconds of the whole call (one run: the machine
is shared, ``--repeat`` for medians) and imageform's CPU seconds; agreement with the
reference: over consecutive frames registered in both, the median angle between the
relative rotations and between the relative translation directions, degrees, and the
largest of the rotation angles;
the note says how many frames ``reconstruct_sequence``'s fallbacks registered (a frame
whose tracks give PnP fewer than 12 inliers). A second table a stride: the keypoints on
the specular highlights (``highlight_mask``'s core and its default 4 px growth), how many
matches touch them and how often those fit the pair's essential matrix, against the
others. ``--reference-cache DIR`` keeps pycolmap's results: the first run writes them, a
second (a before/after comparison, another checkout on ``PYTHONPATH``) reads them.
``--window``, ``--seed`` (``rng``) and ``--contrast-threshold`` (in place of the rows' 0.01)
go to every imageform row; ``--rows`` keeps the rows named; ``--pycolmap-pairs`` adds which
pairs pycolmap's sequential matching matches and verifies, by the distance between frames
(its features and matching again, without the mapping). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_endo_real.py \\
        --video /tmp/endo/c3vdv3_prev.mp4 [--every 8 4] [--repeat 1] [--reference-cache DIR]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table
from benchmarks.bench_reconstruct import pycolmap_options, pycolmap_reconstruct

ROOT = Path(__file__).resolve().parents[1]
CAMERA = ROOT / "tests" / "data" / "endo" / "camera.toml"

#: imageform's configurations: (label, field of view mask, highlights, contrast threshold).
IMAGEFORM = (
    ("defaults", False, False, 0.04),
    ("--auto-mask", True, False, 0.04),
    ("--contrast-threshold 0.01", False, False, 0.01),
    ("--auto-mask --contrast-threshold 0.01", True, False, 0.01),
    ("--auto-mask --highlights --contrast-threshold 0.01", True, True, 0.01),
)
#: ``reconstruct_sequence``'s keyword arguments for every imageform row (``--window``,
#: ``--contrast-threshold``, which replaces the rows' 0.01); empty: as the rows say.
SETTINGS: dict[str, Any] = {}
#: pycolmap's: (label, field of view mask, peak threshold factor).
PYCOLMAP = (("defaults", False, 1.0), ("aperture mask, peak threshold / 4", True, 0.25))


def read_clip(video: Path, width: int) -> list[np.ndarray]:
    """The colour panel of every frame, RGB uint8."""
    import cv2

    cap = cv2.VideoCapture(str(video))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(np.ascontiguousarray(f[:, :width, ::-1]))
    cap.release()
    if not frames:
        raise SystemExit(f"{video}: no frames read")
    return frames


def agreement(R: np.ndarray, t: np.ndarray, Rr: np.ndarray, tr: np.ndarray) -> tuple[float, float]:
    """Median rotation and translation-direction angles (deg) of consecutive relative poses."""
    both = np.flatnonzero(np.isfinite(R[:, 0, 0]) & np.isfinite(Rr[:, 0, 0]))
    rot, tra = [], []
    for i, j in itertools.pairwise(both):
        Ra, Rb = R[j] @ R[i].T, Rr[j] @ Rr[i].T
        c = (np.trace(Ra @ Rb.T) - 1) / 2
        rot.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
        ta, tb = t[j] - Ra @ t[i], tr[j] - Rb @ tr[i]
        na, nb = np.linalg.norm(ta), np.linalg.norm(tb)
        if na > 0 and nb > 0:
            tra.append(np.degrees(np.arccos(np.clip(ta @ tb / (na * nb), -1, 1))))
    med = lambda v: float(np.median(v)) if v else float("nan")  # noqa: E731
    return med(rot), med(tra)


def worst_rotation(R: np.ndarray, Rr: np.ndarray) -> float:
    """The largest angle (deg) between consecutive relative rotations of two runs."""
    both = np.flatnonzero(np.isfinite(R[:, 0, 0]) & np.isfinite(Rr[:, 0, 0]))
    out = [
        np.degrees(
            np.arccos(np.clip((np.trace((R[j] @ R[i].T) @ (Rr[j] @ Rr[i].T).T) - 1) / 2, -1, 1))
        )
        for i, j in itertools.pairwise(both)
    ]
    return float(max(out)) if out else float("nan")


def highlight_table(frames: list[np.ndarray], every: int, cam: Any) -> str:
    """Keypoints on the highlights: how many, and how often their matches fit the geometry.

    Keypoints of ``detect_features`` (field of view mask, contrast 0.01); the pairs of
    frames up to 3 apart; a match touches the highlights when either keypoint is on
    ``highlight_mask`` (its core, ``grow=0``, and the default ``grow=4``); its inlier rate
    is the share of the pair's essential matrix inliers (threshold 2 px, undistorted),
    against the other matches'.
    """
    from imageform.geometry import (
        detect_features,
        field_of_view_mask,
        find_essential_matrix,
        highlight_mask,
        match_features,
    )

    sel = frames[::every]
    K = cam.K
    fov = field_of_view_mask(sel)
    feats = [detect_features(f, mask=fov, contrast_threshold=0.01) for f in sel]

    def ideal(xy: np.ndarray) -> np.ndarray:
        x = (xy - K[:2, 2]) / np.diag(K)[:2]
        u, ok = cam.distortion.undistort(x)
        u = np.asarray(u, np.float64)
        u[~np.asarray(ok, bool)] = np.nan
        return u * np.diag(K)[:2] + K[:2, 2]

    pairs = []
    for i in range(len(sel)):
        for j in range(i + 1, min(len(sel), i + 4)):
            m = match_features(feats[i].descriptors, feats[j].descriptors)
            p1, p2 = ideal(feats[i].xy[m[:, 0]]), ideal(feats[j].xy[m[:, 1]])
            g = np.isfinite(p1).all(1) & np.isfinite(p2).all(1)
            if g.sum() < 30:
                continue
            try:
                er = find_essential_matrix(p1[g], p2[g], K, threshold=2.0, rng=0)
            except Exception:  # a pair without a model: no inliers to count
                continue
            pairs.append((i, j, m[g], np.asarray(er.inliers, bool)))
    rows = []
    h, w = sel[0].shape[:2]
    for grow in (0, 4):
        spec = [highlight_mask(f, grow=grow) for f in sel]
        on = []
        for sm, ft in zip(spec, feats, strict=True):
            x = np.clip(np.round(ft.xy[:, 0]).astype(int), 0, w - 1)
            y = np.clip(np.round(ft.xy[:, 1]).astype(int), 0, h - 1)
            on.append(sm[y, x])
        n_in = i_in = n_out = i_out = 0
        for i, j, m, inl in pairs:
            hit = on[i][m[:, 0]] | on[j][m[:, 1]]
            n_in += int(hit.sum())
            i_in += int((hit & inl).sum())
            n_out += int((~hit).sum())
            i_out += int((~hit & inl).sum())
        rows.append(
            [
                grow,
                f"{100 * np.mean([sm[fov].mean() for sm in spec]):.2f}",
                f"{100 * np.mean(np.concatenate(on)):.2f}",
                f"{n_in} ({100 * n_in / max(n_in + n_out, 1):.2f} %)",
                f"{i_in / max(n_in, 1):.3f}",
                f"{i_out / max(n_out, 1):.3f}",
            ]
        )
    cols = [
        "grow px",
        "highlights: % of the field of view",
        "% of the keypoints",
        "matches touching them",
        "their inlier rate",
        "the others' inlier rate",
    ]
    title = f"### Keypoints on the specular highlights, every {every}th frame\n\n"
    return title + markdown_table(cols, rows)


def run_imageform(
    frames: list[np.ndarray], cam: Any, fov: bool, highlights: bool, ct: float
) -> dict[str, Any]:
    from imageform.geometry import (
        detect_features,
        field_of_view_mask,
        highlight_mask,
        reconstruct_sequence,
    )

    n = len(frames)
    t0, c0 = time.perf_counter(), time.process_time()
    masks: Any = field_of_view_mask(frames) if fov else None
    if highlights:
        masks = [(~highlight_mask(f)) & (True if masks is None else masks) for f in frames]
    if ct == 0.01 and "contrast_threshold" in SETTINGS:
        ct = SETTINGS["contrast_threshold"]
    kw = {key: SETTINGS[key] for key in ("window", "rng", "equalize") if key in SETTINGS}
    try:
        rec = reconstruct_sequence(
            frames, cam.K, cam.distortion, masks=masks, contrast_threshold=ct, **kw
        )
    except Exception as exc:  # a sequence that cannot start is a result too
        out: dict[str, Any] = {"reg": 0, "time": time.perf_counter() - t0}
        out["note"] = f"{type(exc).__name__}: {str(exc)[:90]}"
        out["R"], out["t"] = np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan)
    else:
        r = np.asarray(rec.residuals_px)
        out = {"reg": int(rec.registered.sum()), "time": time.perf_counter() - t0}
        out["cpu"] = time.process_time() - c0
        out |= {"points": rec.points.shape[0], "track": float(np.mean(rec.track_length))}
        out |= {"reproj": float(np.median(r)), "R": rec.R, "t": rec.t, "note": ""}
        fallback = sum("registered by" in note for note in rec.notes)
        if fallback:
            out["note"] = f"{fallback} by the fallbacks"
        out["rot_max"] = float("nan")
    per = masks if isinstance(masks, list) else [masks] * n
    kps = [
        len(detect_features(f, mask=m, contrast_threshold=ct))
        for f, m in zip(frames, per, strict=True)
    ]
    out["kps"] = int(np.median(kps))
    return out


def run_pycolmap(frames: list[np.ndarray], cam: Any, fov: bool, factor: float) -> dict[str, Any]:
    import cv2
    import pycolmap

    from imageform.geometry import field_of_view_mask

    n = len(frames)
    K, d = cam.K, cam.distortion
    params = (K[0, 0], K[1, 1], K[0, 2], K[1, 2], *d.coeffs)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "images").mkdir()
        names = [f"{i:04d}.png" for i in range(n)]
        for name, f in zip(names, frames, strict=True):
            cv2.imwrite(str(root / "images" / name), f[..., ::-1])
        options = pycolmap_options(1, "OPENCV_FISHEYE", params)
        t0 = time.perf_counter()
        if fov:
            m = (field_of_view_mask(frames) * 255).astype(np.uint8)
            (root / "masks").mkdir()
            for name in names:
                cv2.imwrite(str(root / "masks" / f"{name}.png"), m)
            options[0].mask_path = str(root / "masks")
        options[1].sift.peak_threshold *= factor
        pairing = pycolmap.SequentialPairingOptions()
        pairing.num_threads = 1

        def match(db: Path) -> None:
            pycolmap.match_sequential(
                db, matching_options=options[2], pairing_options=pairing, device=pycolmap.Device.cpu
            )

        maps, _, _ = pycolmap_reconstruct(root, root / "images", options, match)
        dt = time.perf_counter() - t0
    R, t = np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan)
    if not maps:
        return {"reg": 0, "time": dt, "R": R, "t": t, "note": "no model"}
    best = max(maps.values(), key=lambda r: r.num_reg_images())
    for image in best.images.values():
        if image.has_pose:
            pose = image.cam_from_world()
            R[names.index(image.name)] = pose.rotation.matrix()
            t[names.index(image.name)] = pose.translation
    out = {"reg": best.num_reg_images(), "time": dt, "R": R, "t": t}
    out |= {"points": best.num_points3D(), "track": best.compute_mean_track_length()}
    errs = [p.error for p in best.points3D.values()]
    out |= {"reproj": float(np.median(errs)) if errs else float("nan")}
    out["note"] = f"{len(maps)} models" if len(maps) > 1 else ""
    return out


def pycolmap_pairs(frames: list[np.ndarray], every: int, cam: Any) -> str:
    """Which frame pairs pycolmap's sequential matching verifies: a table by frame distance.

    The reference row's features and matching (aperture mask, peak threshold / 4, sequential
    pairing with its defaults), without the mapping; from its database: the pairs matched,
    the pairs with verified inliers and their median count, at each distance between frames.
    """
    import sqlite3

    import cv2
    import pycolmap

    from imageform.geometry import field_of_view_mask

    sel = frames[::every]
    K, d = cam.K, cam.distortion
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "images").mkdir()
        (root / "masks").mkdir()
        names = [f"{i:04d}.png" for i in range(len(sel))]
        m = (field_of_view_mask(sel) * 255).astype(np.uint8)
        for name, f in zip(names, sel, strict=True):
            cv2.imwrite(str(root / "images" / name), f[..., ::-1])
            cv2.imwrite(str(root / "masks" / f"{name}.png"), m)
        options = pycolmap_options(1, "OPENCV_FISHEYE", (*np.diag(K)[:2], *K[:2, 2], *d.coeffs))
        options[0].mask_path = str(root / "masks")
        options[1].sift.peak_threshold *= 0.25
        db = root / "database.db"
        pycolmap.extract_features(
            db,
            root / "images",
            camera_mode=pycolmap.CameraMode.SINGLE,
            reader_options=options[0],
            extraction_options=options[1],
            device=pycolmap.Device.cpu,
        )
        pairing = pycolmap.SequentialPairingOptions()
        pairing.num_threads = 1
        pycolmap.match_sequential(
            db, matching_options=options[2], pairing_options=pairing, device=pycolmap.Device.cpu
        )
        con = sqlite3.connect(db)
        big = 2147483647  # COLMAP's pair id: image_id1 * big + image_id2
        matched: dict[int, int] = {}
        inliers: dict[int, list[int]] = {}
        for pid, _ in con.execute("SELECT pair_id, rows FROM matches"):
            gap = abs(pid % big - pid // big)
            matched[gap] = matched.get(gap, 0) + 1
        for pid, rows in con.execute("SELECT pair_id, rows FROM two_view_geometries"):
            if rows > 0:
                inliers.setdefault(abs(pid % big - pid // big), []).append(rows)
        kps = [r[0] for r in con.execute("SELECT rows FROM keypoints")]
        con.close()
    rows = [
        [gap, matched[gap], len(inliers.get(gap, [])), int(np.median(inliers.get(gap, [0])))]
        for gap in sorted(matched)
    ]
    title = (
        f"### pycolmap's pairs, every {every}th frame (overlap {pairing.overlap}, quadratic "
        f"overlap {pairing.quadratic_overlap}; keypoints a frame: median {int(np.median(kps))})"
        "\n\n"
    )
    cols = ["frames apart", "pairs matched", "pairs verified", "inliers a pair (median)"]
    return title + markdown_table(cols, rows)


def _median_run(fn: Any, repeat: int) -> dict[str, Any]:
    runs = [fn() for _ in range(repeat)]
    best = runs[0]
    best["time"] = statistics.median(r["time"] for r in runs)
    if all("cpu" in r for r in runs):
        best["cpu"] = statistics.median(r["cpu"] for r in runs)
    return best


def table(
    frames: list[np.ndarray],
    every: int,
    cam: Any,
    repeat: int,
    cache: Path | None = None,
    rows_wanted: list[str] | None = None,
) -> str:
    import pycolmap

    sel = frames[::every]
    n = len(sel)
    theirs: list[tuple[str, dict[str, Any]]] = []
    for k, (label, fov, factor) in enumerate(PYCOLMAP):
        cached = None if cache is None else cache / f"pycolmap-every{every}-{k}.npz"
        if cached is not None and cached.exists():
            with np.load(cached, allow_pickle=False) as z:
                res = {key: z[key][()] if z[key].ndim == 0 else z[key] for key in z.files}
            res["note"] = str(res.get("note", ""))
        else:
            res = _median_run(lambda: run_pycolmap(sel, cam, fov, factor), repeat)  # noqa: B023
            if cached is not None:
                cached.parent.mkdir(parents=True, exist_ok=True)
                np.savez(cached, **res)
        theirs.append((f"pycolmap {pycolmap.__version__} {label}", res))
        print(f"  every {every}: pycolmap {label}: {res['reg']}/{n}", file=sys.stderr)
    ref = theirs[-1][1]
    ours: list[tuple[str, dict[str, Any]]] = []
    for label, fov, hl, ct in IMAGEFORM:
        if rows_wanted is not None and f"imageform {label}" not in rows_wanted:
            continue
        res = _median_run(lambda: run_imageform(sel, cam, fov, hl, ct), repeat)  # noqa: B023
        ours.append((f"imageform {label}", res))
        print(f"  every {every}: imageform {label}: {res['reg']}/{n}", file=sys.stderr)
    results = ours + theirs
    rows = []
    for label, r in results:
        ok = r["reg"] > 0 and "points" in r
        rot, tra = agreement(r["R"], r["t"], ref["R"], ref["t"]) if r is not ref else (0, 0)
        worst = worst_rotation(r["R"], ref["R"]) if r is not ref else 0.0
        rows.append(
            [
                label,
                f"{r['reg']}/{n}",
                r.get("points", "-"),
                f"{r['track']:.2f}" if ok else "-",
                f"{r['reproj']:.2f}" if ok else "-",
                r.get("kps", "-"),
                f"{rot:.2f} / {tra:.2f}" if ok and r is not ref else ("reference" if ok else "-"),
                f"{worst:.2f}" if ok and r is not ref else "-",
                f"{r['time']:.1f}",
                f"{r['cpu']:.1f}" if "cpu" in r else "-",
                r.get("note", ""),
            ]
        )
    cols = [
        "run",
        "registered",
        "points",
        "track length",
        "reprojection px (median)",
        "keypoints a frame (median)",
        "vs reference: rotation / translation deg",
        "worst rotation deg",
        "s",
        "CPU s",
        "note",
    ]
    title = f"## Every {every}th frame: {n} frames of {len(frames)}, {sel[0].shape[1]} x "
    return title + f"{sel[0].shape[0]} px\n\n" + markdown_table(cols, rows)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--video", type=Path, required=True)
    ap.add_argument("--panel-width", type=int, default=445)
    ap.add_argument("--camera", type=Path, default=CAMERA)
    ap.add_argument("--every", type=int, nargs="+", default=[8, 4])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument(
        "--reference-cache",
        type=Path,
        default=None,
        help="folder for pycolmap's results: written on the first run, read after (a before/"
        "after comparison runs pycolmap once)",
    )
    ap.add_argument("--window", type=int, default=None, help="imageform's window (default: its)")
    ap.add_argument(
        "--contrast-threshold",
        type=float,
        default=None,
        help="imageform's SIFT contrast threshold in the rows of 0.01 (their labels keep 0.01)",
    )
    ap.add_argument(
        "--rows", nargs="+", default=None, help="only these imageform rows (labels, as printed)"
    )
    ap.add_argument("--seed", type=int, default=None, help="imageform's RANSAC seed (rng)")
    ap.add_argument("--no-highlight-table", action="store_true")
    ap.add_argument(
        "--pycolmap-pairs",
        action="store_true",
        help="also pycolmap's matched and verified pairs by the distance between frames",
    )
    args = ap.parse_args()
    if args.window is not None:
        SETTINGS["window"] = args.window
    if args.contrast_threshold is not None:
        SETTINGS["contrast_threshold"] = args.contrast_threshold
    if args.seed is not None:
        SETTINGS["rng"] = args.seed
    from imageform.io import read_camera

    cam = read_camera(args.camera).camera
    frames = read_clip(args.video, args.panel_width)
    print(header("Structure from motion on a real colonoscopy video"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine)\n")
    print(f"{args.video.name}: {len(frames)} frames; camera {args.camera.name}\n")
    for every in args.every:
        print(table(frames, every, cam, args.repeat, args.reference_cache, args.rows))
        if not args.no_highlight_table:
            print(highlight_table(frames, every, cam))
        if args.pycolmap_pairs:
            print(pycolmap_pairs(frames, every, cam))


if __name__ == "__main__":
    main()
