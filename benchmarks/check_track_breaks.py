"""Where imageform's tracks break on a real colonoscopy video, against pycolmap's long tracks.

The clip of ``check_endo_real.py`` (C3VD v3's preview, github.com/DurrLab/C3VDv3 at
``ad9391d``, CC BY 4.0; ``--video``), every ``--every``-th frame, the camera
tests/data/endo/camera.toml. pycolmap (aperture mask, SIFT peak threshold / 4, sequential
matching, incremental mapping: the reference row of ``check_endo_real.py``) gives its points
seen in ``--min-views`` frames or more, with each view's keypoint; imageform's
``reconstruct_sequence`` (``field_of_view_mask``, contrast threshold 0.01) runs with its
private trace on (``imageform.geometry.sfm._TRACE``), which keeps its keypoints, the pairs
matched and verified, the tracks built and every observation set aside and by what.

Each pycolmap view is given imageform's nearest keypoint within ``--radius`` pixels
(COLMAP's pixel centers are at +0.5, taken off). A link is two consecutive views of one
pycolmap point (by frame); it holds in imageform when the two keypoints are views of one
point of its final reconstruction. A broken link's cause is the first stage that parts them:

1. no keypoint: no imageform keypoint within ``--radius`` px of one of the two views;
2. matching: the two keypoints not joined by the putative matches (Lowe's ratio, mutual)
   of the pairs imageform matches; split by whether the two frames were a pair matched, and
   whether the other keypoint was the nearest descriptor (a ratio or mutual-check loss) or not;
3. verification: joined by the putative matches, not by the verified ones (the pair's
   essential matrix RANSAC, its cheirality and the three-frame loop check);
4. track building: joined by the verified matches, in two tracks (a component with two
   keypoints of a frame, rebuilt greedily);
5. after triangulation: one track, but not one point at the end: a view set aside (PnP's
   outlier at its frame's registration, the bundle adjustment's 4 px or 2 px filters), or
   the track never triangulated;
6. incremental order: a view that exists only once its frame is registered (none in
   imageform: its tracks are built before any registration, completion adds to them later;
   counted under 2 to 5 by where the link was lost).

A link lost at one stage and joined again later (completion adds views by projection, and
merges tracks) counts as kept. Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_track_breaks.py \\
        --video /tmp/endo/c3vdv3_prev.mp4 --cache /tmp/sfmtrack
"""

from __future__ import annotations

import argparse
import importlib
import itertools
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table
from benchmarks.check_endo_real import CAMERA, agreement, read_clip, worst_rotation


def pycolmap_tracks(frames: list[np.ndarray], cam: Any, cache: Path | None) -> dict[str, Any]:
    """pycolmap's reference reconstruction: poses and every view (point, frame, keypoint)."""
    name = f"pycolmap-tracks-{len(frames)}.npz"
    if cache is not None and (cache / name).exists():
        with np.load(cache / name) as z:
            return {key: z[key] for key in z.files}
    import cv2
    import pycolmap

    from benchmarks.bench_reconstruct import pycolmap_options, pycolmap_reconstruct
    from imageform.geometry import field_of_view_mask

    n = len(frames)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "images").mkdir()
        (root / "masks").mkdir()
        names = [f"{i:04d}.png" for i in range(n)]
        m = (field_of_view_mask(frames) * 255).astype(np.uint8)
        for nm, f in zip(names, frames, strict=True):
            cv2.imwrite(str(root / "images" / nm), f[..., ::-1])
            cv2.imwrite(str(root / "masks" / f"{nm}.png"), m)
        K, d = cam.K, cam.distortion
        options = pycolmap_options(1, "OPENCV_FISHEYE", (*np.diag(K)[:2], *K[:2, 2], *d.coeffs))
        options[0].mask_path = str(root / "masks")
        options[1].sift.peak_threshold *= 0.25
        pairing = pycolmap.SequentialPairingOptions()
        pairing.num_threads = 1

        def match(db: Path) -> None:
            pycolmap.match_sequential(
                db, matching_options=options[2], pairing_options=pairing, device=pycolmap.Device.cpu
            )

        maps, _, _ = pycolmap_reconstruct(root, root / "images", options, match)
    best = max(maps.values(), key=lambda r: r.num_reg_images())
    R, t = np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan)
    for image in best.images.values():
        if image.has_pose:
            pose = image.cam_from_world()
            R[names.index(image.name)] = pose.rotation.matrix()
            t[names.index(image.name)] = pose.translation
    pid, fr, xy = [], [], []
    for p3, pt in best.points3D.items():
        for el in pt.track.elements:
            image = best.images[el.image_id]
            pid.append(p3)
            fr.append(names.index(image.name))
            xy.append(np.asarray(image.points2D[el.point2D_idx].xy) - 0.5)
    out = {"R": R, "t": t, "pid": np.array(pid), "frame": np.array(fr), "xy": np.array(xy)}
    if cache is not None:
        cache.mkdir(parents=True, exist_ok=True)
        np.savez(cache / name, **out)  # type: ignore[arg-type]
    return out


def components(total: int, pairs: dict[tuple[int, int], np.ndarray], offset: np.ndarray) -> Any:
    """Connected components of the keypoints (global ids) joined by ``pairs``' matches."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    e = [np.column_stack([offset[i] + m[:, 0], offset[j] + m[:, 1]]) for (i, j), m in pairs.items()]
    edges = np.concatenate(e) if e else np.zeros((0, 2), np.int64)
    g = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(total, total))
    return connected_components(g, directed=False)[1]


def diagnose(
    frames: list[np.ndarray],
    cam: Any,
    ref: dict[str, Any],
    radius: float,
    min_views: int,
    ct: float = 0.01,
) -> dict[str, Any]:
    """Run imageform with its trace on; classify each link of pycolmap's long tracks."""
    from scipy.spatial import cKDTree

    sfm: Any = importlib.import_module("imageform.geometry.sfm")
    from imageform.geometry import field_of_view_mask, reconstruct_sequence

    masks = field_of_view_mask(frames)
    tr: dict[str, Any] = {}
    sfm._TRACE = tr
    c0 = time.process_time()
    try:
        rec = reconstruct_sequence(
            frames, cam.K, cam.distortion, masks=masks, contrast_threshold=ct
        )
    finally:
        sfm._TRACE = None
    cpu = time.process_time() - c0
    offset, xy = tr["offset"], tr["xy"]
    total = int(offset[-1])
    put = components(total, tr["putative"], offset)
    ver = components(total, tr["verified"], offset)
    built = tr["node_track"]
    # the final views: usable, of a point, in a registered frame
    ok = tr["o_ok"] & tr["has_point"][tr["o_track"]] & tr["registered"][tr["o_frame"]]
    final = -np.ones(total, np.int64)
    g_ok = offset[tr["o_frame"][ok]] + tr["o_kp"][ok]
    final[g_ok] = tr["o_track"][ok]
    in_obs = -np.ones(total, np.int64)  # each keypoint's observation (-1: none)
    in_obs[offset[tr["o_frame"]] + tr["o_kp"]] = np.arange(tr["o_frame"].size)
    why: dict[int, str] = {}
    for f, q, w in tr["dropped"]:
        why.setdefault(int(offset[f] + q), w)
    trees = [cKDTree(p) for p in xy]
    # pycolmap's long tracks
    pid, pfr, pxy = ref["pid"], ref["frame"], ref["xy"]
    ids, cnt = np.unique(pid, return_counts=True)
    long_ = set(ids[cnt >= min_views].tolist())
    causes: Counter[str] = Counter()
    nearest_d: list[float] = []
    runs: list[tuple[int, int]] = []
    gaps: Counter[int] = Counter()
    desc = None
    for p in sorted(long_):
        sel = np.flatnonzero(pid == p)
        sel = sel[np.argsort(pfr[sel], kind="stable")]
        nodes = []
        for s in sel:
            f = int(pfr[s])
            d, q = trees[f].query(pxy[s])
            nearest_d.append(float(d))
            nodes.append((f, int(offset[f] + q) if d <= radius else -1))
        # the longest run of pycolmap's views in one imageform point
        labels = [final[g] if g >= 0 else -1 for _, g in nodes]
        lab = Counter(x for x in labels if x >= 0)
        runs.append((len(nodes), max(lab.values()) if lab else 0))
        for (f, a), (g, b) in itertools.pairwise(nodes):
            gaps[g - f] += 1
            if g == f:
                causes["0 pycolmap: two views in one frame (not a link)"] += 1
                continue
            if a < 0 or b < 0:
                causes["1 no keypoint within radius"] += 1
                continue
            if final[a] >= 0 and final[a] == final[b]:
                causes["kept"] += 1
                continue
            if put[a] != put[b]:
                if (f, g) not in tr["putative"]:
                    causes["2b matching: the two frames not a pair matched"] += 1
                    continue
                if desc is None:
                    from imageform.geometry import detect_features

                    desc = [
                        detect_features(im, mask=masks, contrast_threshold=ct).descriptors
                        for im in frames
                    ]
                da = desc[f][a - offset[f]]
                dist = np.linalg.norm(desc[g] - da, axis=1)
                if int(np.argmin(dist)) == b - offset[g]:
                    causes["2a matching: nearest descriptor, lost to ratio or mutual check"] += 1
                else:
                    causes["2c matching: not the nearest descriptor"] += 1
                continue
            if ver[a] != ver[b]:
                if (f, g) in tr["verified"]:
                    causes["3a verification: pair verified, this match an outlier"] += 1
                elif (f, g) in tr["putative"]:
                    causes["3b verification: the pair not verified (or dropped)"] += 1
                else:
                    causes["3c verification: joined through other frames only"] += 1
                continue
            if built[a] != built[b] or built[a] < 0:
                causes["4 track building: split (a frame twice in the component)"] += 1
                continue
            for x in (a, b):
                if final[x] < 0:
                    if x in why:
                        causes[f"5 set aside: {why[x]}"] += 1
                    elif in_obs[x] >= 0 and not tr["has_point"][tr["o_track"][in_obs[x]]]:
                        causes["5 track never triangulated (or its point dropped)"] += 1
                    else:
                        causes["5 other"] += 1
                    break
            else:
                causes["5 in two points after merges"] += 1
    return {
        "rec": rec,
        "cpu": cpu,
        "causes": causes,
        "runs": runs,
        "gaps": gaps,
        "near": np.array(nearest_d),
        "long": len(long_),
        "pairs": len(tr["putative"]),
        "verified": len(tr["verified"]),
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--video", type=Path, required=True)
    ap.add_argument("--panel-width", type=int, default=445)
    ap.add_argument("--every", type=int, default=8)
    ap.add_argument("--radius", type=float, default=2.0)
    ap.add_argument("--min-views", type=int, default=8)
    ap.add_argument("--contrast-threshold", type=float, default=0.01)
    ap.add_argument("--cache", type=Path, default=None, help="folder for pycolmap's tracks")
    args = ap.parse_args()
    from imageform.io import read_camera

    cam = read_camera(CAMERA).camera
    frames = read_clip(args.video, args.panel_width)[:: args.every]
    ref = pycolmap_tracks(frames, cam, args.cache)
    out = diagnose(frames, cam, ref, args.radius, args.min_views, args.contrast_threshold)
    rec = out["rec"]
    print(header("Where imageform's tracks break against pycolmap's long tracks"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine)\n")
    rot, tra = agreement(rec.R, rec.t, ref["R"], ref["t"])
    n = len(frames)
    _, cnt = np.unique(ref["pid"], return_counts=True)
    print(
        f"Every {args.every}th frame, {n} frames. pycolmap: {cnt.size} points, track length "
        f"{cnt.mean():.2f}, {out['long']} seen in {args.min_views} frames or more. imageform: "
        f"{int(rec.registered.sum())}/{n} registered, {rec.points.shape[0]} points, track "
        f"length {np.mean(rec.track_length):.2f}, "
        f"{int(np.sum(rec.track_length >= args.min_views))} seen in {args.min_views} or more; "
        f"{out['pairs']} pairs matched, {out['verified']} verified; against pycolmap: "
        f"rotation / translation {rot:.2f} / {tra:.2f} deg (median), worst rotation "
        f"{worst_rotation(rec.R, ref['R']):.2f} deg; CPU {out['cpu']:.1f} s.\n"
    )
    near = out["near"]
    print(
        f"pycolmap's views with an imageform keypoint within {args.radius:g} px: "
        f"{np.mean(near <= args.radius):.1%} (within 1 px {np.mean(near <= 1):.1%}, "
        f"median distance {np.median(near):.2f} px)\n"
    )
    c = out["causes"]
    links = sum(c.values())
    rows = [[k, v, f"{100 * v / links:.1f}"] for k, v in sorted(c.items())]
    print(f"### The {links} links of pycolmap's {out['long']} long tracks\n")
    print(markdown_table(["stage", "links", "%"], rows))
    runs = np.array(out["runs"])
    print(
        f"\nA long track's views in one imageform point: median {np.median(runs[:, 1]):.0f} of "
        f"{np.median(runs[:, 0]):.0f} (mean {runs[:, 1].mean():.2f} of {runs[:, 0].mean():.2f}).\n"
    )
    gaps = out["gaps"]
    rows = [[g, v] for g, v in sorted(gaps.items())]
    print("### Frames between a link's two views (pycolmap)\n")
    print(markdown_table(["frames apart", "links"], rows))


if __name__ == "__main__":
    main()
