"""Two-view geometry and structure from motion on real photographs: imageform vs OpenCV, pycolmap.

Photographs nobody on the project made, in two folders given on the command line (nothing
is downloaded; the images stay out of the repository):

- ``--graf DIR``: the Oxford affine set's "graf" wall (Mikolajczyk et al. 2005, IJCV 65):
  ``graf1.png`` … (or ``img1.ppm`` …) and the ground-truth homographies ``H1to2p`` …
  (the dataset's 9 numbers, or OpenCV's XML of them). The homographies are for the 800 x
  640 originals and are rescaled to the images' width. The 400 x 320 copies measured were
  ``data/graf{1,2}.png`` of github.com/ml-lab/ComputerVision-HW2 (commit d6143bb) and the
  homography ``data/graf/H1to2p`` of github.com/matheusgadelha/DRINK (de86bbb); that
  repository's ``graf3.png`` is not the dataset's third view (its SIFT matches fit another
  homography than ``H1to3p``), so only the pair 1-2 is measured.
- ``--opensfm DIR``: an OpenSfM dataset, ``images/*.jpg`` and a ``reconstruction*.json``
  whose shots are the reference cameras (perspective model: focal times the longer side,
  radial ``k1, k2``). Measured: OpenSfM's ``data/berlin`` (github.com/mapillary/OpenSfM,
  BSD-2-Clause; three 3264 x 2448 iPhone 4S photographs of a street, and
  ``reconstruction_example.json``, OpenSfM's own reconstruction with ground control
  points). The reference is another program's estimate, not a survey: errors of a few
  tenths of a degree are at its own accuracy.

Tables: (1) homographies of SIFT matches (imageform's ``detect_features`` and
``match_features``, the same matches for everyone): ``find_homography`` vs OpenCV 5's
``findHomography`` (USAC_MAGSAC and RANSAC), 3 px; the error is the mean and the largest
distance, over a grid on the first image, between the estimate's and the truth's transfer.
(2) relative poses of every pair of the OpenSfM set: ``find_essential_matrix`` +
``recover_pose`` vs ``findEssentialMat`` (USAC_MAGSAC) + ``recoverPose`` on the same
undistorted matches, thresholds 1 and 2 px: rotation error and the angle between the
translation directions, degrees. (3) the whole set through ``reconstruct_sequence`` and
pycolmap (RADIAL camera fixed to the reference's, exhaustive matching), at the photographs'
size and upscaled by ``--upscale`` (24.5 Mpx): registered views, points, reprojection RMS,
largest relative-rotation error against the reference, wall time. (4) ``detect_features``
alone on one upscaled photograph with ``max_size`` 3200 (the default) and ``None``, each in
a fresh process: seconds and the process's peak resident memory. With ``--seeds N``
only the dependence on the random seed is measured instead: (5) the relative poses and (6)
the graf homography over the seeds ``0 .. N-1`` (``rng=`` for imageform, ``UsacParams``'
``randomGeneratorState`` for OpenCV's USAC with MAGSAC++ scoring, σ-consensus local
optimisation and the MAGSAC final polisher), median and worst of each error, besides
``findEssentialMat(..., USAC_MAGSAC)`` / ``findHomography(..., USAC_MAGSAC)`` as called
above (its one fixed seed). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_twoview_real.py \\
        --graf /tmp/sfm-eval/graf --opensfm /tmp/sfm-eval/berlin [--repeat 3] [--upscale 1.75]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_twoview_real.py \\
        --graf /tmp/sfm-eval/graf --opensfm /tmp/sfm-eval/berlin --seeds 10
"""

from __future__ import annotations

import argparse
import concurrent.futures
import itertools
import json
import multiprocessing
import re
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table


def _rot_err(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra.T @ Rb) - 1) / 2
    return float(np.degrees(np.arccos(np.clip(c, -1, 1))))


def _dir_err(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    return float(np.degrees(np.arccos(np.clip(a @ b, -1, 1))))


def _transfer(H: np.ndarray, p: np.ndarray) -> np.ndarray:
    q = np.c_[p, np.ones(len(p))] @ H.T
    return q[:, :2] / q[:, 2:]


def _read_h(path: Path) -> np.ndarray:
    text = path.read_text()
    if "<data>" in text:
        text = text.split("<data>")[1].split("</data>")[0]
    return np.array([float(v) for v in re.findall(r"[-+0-9.eE]+", text)[:9]]).reshape(3, 3)


def _read_rgb(path: Path) -> np.ndarray:
    import cv2

    im = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if im is None:
        raise SystemExit(f"cannot read {path}")
    return np.ascontiguousarray(im[..., ::-1])


def _median_s(fn: Any, repeat: int) -> tuple[Any, float]:
    out, times = None, []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def homography_table(folder: Path, repeat: int) -> str:
    import cv2

    from imageform.geometry import detect_features, find_homography, match_features

    def image(i: int) -> Path:
        for name in (f"graf{i}.png", f"img{i}.png", f"img{i}.ppm"):
            if (folder / name).exists():
                return folder / name
        raise SystemExit(f"{folder}: no graf{i}.png, img{i}.png or img{i}.ppm")

    im1 = _read_rgb(image(1))
    h, w = im1.shape[:2]
    S = np.diag([w / 800.0, w / 800.0, 1.0])
    f1 = detect_features(im1)
    ys, xs = np.mgrid[0:h:8, 0:w:8]
    grid = np.c_[xs.ravel(), ys.ravel()].astype(float)
    rows = []
    for k in range(2, 7):
        hfile = folder / f"H1to{k}p"
        if not hfile.exists():
            continue
        Ht = S @ _read_h(hfile) @ np.linalg.inv(S)
        f2 = detect_features(_read_rgb(image(k)))
        m = match_features(f1.descriptors, f2.descriptors)
        a, b = f1.xy[m[:, 0]], f2.xy[m[:, 1]]
        true = int((np.linalg.norm(_transfer(Ht, a) - b, axis=1) < 3).sum())
        runs = {
            "imageform find_homography": lambda a=a, b=b: find_homography(a, b, threshold=3.0).H,
            "OpenCV USAC_MAGSAC": lambda a=a, b=b: cv2.findHomography(a, b, cv2.USAC_MAGSAC, 3.0)[
                0
            ],
            "OpenCV RANSAC": lambda a=a, b=b: cv2.findHomography(a, b, cv2.RANSAC, 3.0)[0],
        }
        for name, fn in runs.items():
            try:
                fn()  # warm-up (numba)
                H, dt = _median_s(fn, repeat)
            except Exception as exc:  # a failure is a result
                rows.append([f"1-{k}", len(m), true, name, type(exc).__name__, "", ""])
                continue
            if H is None:
                rows.append([f"1-{k}", len(m), true, name, "no H", "", ""])
                continue
            e = np.linalg.norm(_transfer(np.asarray(H), grid) - _transfer(Ht, grid), axis=1)
            inl = int((np.linalg.norm(_transfer(np.asarray(H), a) - b, axis=1) < 3).sum())
            rows.append(
                [f"1-{k}", len(m), true, name, inl, f"{e.mean():.3f} / {e.max():.2f}",
                 f"{dt * 1e3:.2f}"]
            )  # fmt: skip
    cols = ["pair", "matches", "true (3 px)", "method", "within 3 px", "grid error mean / max px",
            "ms"]  # fmt: skip
    return f"## Homographies, Oxford graf ({w} x {h})\n\n" + markdown_table(cols, rows)


def _opensfm(folder: Path) -> tuple[list[str], dict[str, Any], dict[str, Any]]:
    import cv2

    recs = sorted(folder.glob("reconstruction*.json")) + sorted(folder.glob("rec*.json"))
    if not recs:
        raise SystemExit(f"{folder}: no reconstruction*.json")
    rec = json.loads(recs[0].read_text())[0]
    cam = next(iter(rec["cameras"].values()))
    names = sorted(rec["shots"])
    poses = {}
    for n, s in rec["shots"].items():
        poses[n] = (cv2.Rodrigues(np.array(s["rotation"], float))[0], np.array(s["translation"]))
    return names, poses, cam


def _images_dir(folder: Path) -> Path:
    return folder / "images" if (folder / "images").is_dir() else folder


def _camera(cam: dict[str, Any], w: int, h: int) -> tuple[np.ndarray, float, float]:
    f = float(cam.get("focal", cam.get("focal_x", 0.0))) * max(w, h)
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])
    return K, float(cam.get("k1", 0.0)), float(cam.get("k2", 0.0))


def pose_table(folder: Path, repeat: int) -> str:
    import cv2

    from imageform.geometry import (
        BrownConrady,
        detect_features,
        find_essential_matrix,
        match_features,
        recover_pose,
    )

    names, poses, cam = _opensfm(folder)
    imgs = {n: _read_rgb(_images_dir(folder) / n) for n in names}
    h, w = next(iter(imgs.values())).shape[:2]
    K, k1, k2 = _camera(cam, w, h)
    dist = BrownConrady(k1=k1, k2=k2)
    Kinv = np.linalg.inv(K)

    def undistort(p: np.ndarray) -> np.ndarray:
        x = (np.c_[p, np.ones(len(p))] @ Kinv.T)[:, :2]
        return np.asarray(dist.undistort(x).xy) @ K[:2, :2].T + K[:2, 2]

    feats = {n: detect_features(im) for n, im in imgs.items()}
    rows = []
    for a, b in itertools.combinations(names, 2):
        (Ra, ta), (Rb, tb) = poses[a], poses[b]
        R, t = Rb @ Ra.T, tb - Rb @ Ra.T @ ta
        m = match_features(feats[a].descriptors, feats[b].descriptors)
        p1, p2 = undistort(feats[a].xy[m[:, 0]]), undistort(feats[b].xy[m[:, 1]])
        for thr in (1.0, 2.0):

            def ours(thr: float = thr, p1: Any = p1, p2: Any = p2) -> tuple[Any, ...]:
                e = find_essential_matrix(p1, p2, K, threshold=thr)
                r = recover_pose(e.E, p1, p2, K, inliers=e.inliers)
                return r.R, r.t, int(e.inliers.sum())

            def theirs(thr: float = thr, p1: Any = p1, p2: Any = p2) -> tuple[Any, ...]:
                E, mask = cv2.findEssentialMat(p1, p2, K, cv2.USAC_MAGSAC, 0.999, thr)
                _, Rc, tc, _ = cv2.recoverPose(E[:3], p1, p2, K, mask=mask.copy())
                return Rc, tc, int(mask.sum())

            for name, fn in (("imageform", ours), ("OpenCV USAC_MAGSAC", theirs)):
                fn()
                (Re, te, inl), dt = _median_s(fn, repeat)
                rows.append(
                    [f"{a}-{b}", len(m), thr, name, inl, f"{_rot_err(Re, R):.2f}",
                     f"{_dir_err(np.ravel(te), t):.2f}", f"{dt * 1e3:.1f}"]
                )  # fmt: skip
    cols = ["pair", "matches", "threshold px", "method", "inliers", "rotation error deg",
            "translation error deg", "ms"]  # fmt: skip
    return f"## Relative poses, {folder.name} ({w} x {h})\n\n" + markdown_table(cols, rows)


def _usac_params(thr: float, seed: int) -> Any:
    import cv2

    prm = cv2.UsacParams()
    prm.confidence = 0.999
    prm.threshold = thr
    prm.maxIterations = 10000
    prm.sampler = cv2.SAMPLING_UNIFORM
    prm.score = cv2.SCORE_METHOD_MAGSAC
    prm.loMethod = cv2.LOCAL_OPTIM_SIGMA
    prm.loIterations = 10
    prm.final_polisher = cv2.MAGSAC
    prm.final_polisher_iterations = 20
    prm.isParallel = False
    prm.randomGeneratorState = seed
    return prm


def _spread(values: list[float]) -> str:
    return f"{statistics.median(values):.2f} / {max(values):.2f}"


def seed_pose_table(folder: Path, seeds: int, tasks: tuple[str, ...] | None = None) -> str:
    import cv2

    from imageform.geometry import (
        BrownConrady,
        detect_features,
        find_essential_matrix,
        find_fundamental_matrix,
        match_features,
        recover_pose,
    )

    names, poses, cam = _opensfm(folder)
    imgs = {n: _read_rgb(_images_dir(folder) / n) for n in names}
    h, w = next(iter(imgs.values())).shape[:2]
    K, k1, k2 = _camera(cam, w, h)
    dist = BrownConrady(k1=k1, k2=k2)
    Kinv = np.linalg.inv(K)
    no_dist = np.zeros((1, 5))
    which = ("E", "F") if tasks is None else tasks

    def undistort(p: np.ndarray) -> np.ndarray:
        x = (np.c_[p, np.ones(len(p))] @ Kinv.T)[:, :2]
        return np.asarray(dist.undistort(x).xy) @ K[:2, :2].T + K[:2, 2]

    feats = {n: detect_features(im) for n, im in imgs.items()}
    rows = []
    for a, b in itertools.combinations(names, 2):
        (Ra, ta), (Rb, tb) = poses[a], poses[b]
        R, t = Rb @ Ra.T, tb - Rb @ Ra.T @ ta
        m = match_features(feats[a].descriptors, feats[b].descriptors)
        p1, p2 = undistort(feats[a].xy[m[:, 0]]), undistort(feats[b].xy[m[:, 1]])
        for thr in (1.0, 2.0):
            runs: dict[str, Any] = {}
            if "E" in which:
                runs.update(_essential_runs(find_essential_matrix, p1, p2, K, thr, no_dist))
            if "F" in which:
                runs.update(_fundamental_runs(find_fundamental_matrix, p1, p2, thr))
            for name, fn in runs.items():
                fn(0)  # warm-up (numba)
                rot, tra, inl, ms = [], [], [], []
                for s in range(seeds):
                    t0 = time.perf_counter()
                    out = fn(s)
                    Re: Any
                    te: Any
                    if name.startswith("imageform"):
                        Ee = out.E if hasattr(out, "E") else K.T @ out.F @ K
                        pose = recover_pose(Ee, p1, p2, K, inliers=out.inliers)
                        Re, te, n_in = pose.R, pose.t, int(out.inliers.sum())
                    else:
                        E, mask = out
                        if name.startswith("F:"):
                            E = K.T @ E[:3] @ K
                        _, Re, te, _ = cv2.recoverPose(E[:3], p1, p2, K, mask=mask.copy())
                        n_in = int(mask.sum())
                    ms.append((time.perf_counter() - t0) * 1e3)
                    rot.append(_rot_err(Re, R))
                    tra.append(_dir_err(np.ravel(te), t))
                    inl.append(n_in)
                rows.append(
                    [f"{a}-{b}", len(m), thr, name, f"{statistics.median(inl):.0f}", _spread(rot),
                     f"{max(rot) - min(rot):.2f}", _spread(tra), f"{statistics.median(ms):.1f}"]
                )  # fmt: skip
    cols = ["pair", "matches", "threshold px", "method", "inliers (median)",
            "rotation error median / worst deg", "rotation spread deg",
            "translation error median / worst deg", "ms (median)"]  # fmt: skip
    return f"## Relative poses over {seeds} seeds, {folder.name} ({w} x {h})\n\n" + markdown_table(
        cols, rows
    )


def _essential_runs(
    find_essential_matrix: Any, p1: Any, p2: Any, K: Any, thr: float, no_dist: Any
) -> dict[str, Any]:
    import cv2

    return {
        "imageform": lambda s: find_essential_matrix(p1, p2, K, threshold=thr, rng=s),
        "OpenCV USAC (MAGSAC++), seeded": lambda s: cv2.findEssentialMat(
            p1.reshape(-1, 1, 2), p2.reshape(-1, 1, 2), K, K, no_dist, no_dist,
            _usac_params(thr, s),
        ),
        "OpenCV USAC_MAGSAC (fixed seed)": lambda s: cv2.findEssentialMat(
            p1, p2, K, cv2.USAC_MAGSAC, 0.999, thr
        ),
    }  # fmt: skip


def _fundamental_runs(find_fundamental_matrix: Any, p1: Any, p2: Any, thr: float) -> dict[str, Any]:
    """F's runs: the pose is ``recover_pose`` of ``K^T F K`` (its two singular values unequal)."""
    import cv2

    return {
        "imageform F": lambda s: find_fundamental_matrix(p1, p2, threshold=thr, rng=s),
        "F: OpenCV USAC (MAGSAC++), seeded": lambda s: cv2.findFundamentalMat(
            p1, p2, _usac_params(thr, s)
        ),
        "F: OpenCV USAC_MAGSAC (fixed seed)": lambda s: cv2.findFundamentalMat(
            p1, p2, cv2.USAC_MAGSAC, thr, 0.999, 10000
        ),
    }


def seed_homography_table(folder: Path, seeds: int) -> str:
    import cv2

    from imageform.geometry import detect_features, find_homography, match_features

    im1 = _read_rgb(folder / "graf1.png")
    h, w = im1.shape[:2]
    S = np.diag([w / 800.0, w / 800.0, 1.0])
    Ht = S @ _read_h(folder / "H1to2p") @ np.linalg.inv(S)
    f1, f2 = detect_features(im1), detect_features(_read_rgb(folder / "graf2.png"))
    m = match_features(f1.descriptors, f2.descriptors)
    a, b = f1.xy[m[:, 0]], f2.xy[m[:, 1]]
    ys, xs = np.mgrid[0:h:8, 0:w:8]
    grid = np.c_[xs.ravel(), ys.ravel()].astype(float)
    runs: dict[str, Any] = {
        "imageform find_homography": lambda s: find_homography(a, b, threshold=3.0, rng=s).H,
        "OpenCV USAC (MAGSAC++), seeded": lambda s: cv2.findHomography(a, b, _usac_params(3.0, s))[
            0
        ],
        "OpenCV USAC_MAGSAC (fixed seed)": lambda s: cv2.findHomography(a, b, cv2.USAC_MAGSAC, 3.0)[
            0
        ],
    }
    rows = []
    for name, fn in runs.items():
        means, maxes = [], []
        for s in range(seeds):
            e = np.linalg.norm(_transfer(np.asarray(fn(s)), grid) - _transfer(Ht, grid), axis=1)
            means.append(float(e.mean()))
            maxes.append(float(e.max()))
        rows.append(["1-2", len(m), name, f"{statistics.median(means):.3f} / {max(means):.3f}",
                     f"{statistics.median(maxes):.2f} / {max(maxes):.2f}"])  # fmt: skip
    cols = ["pair", "matches", "method", "grid error mean px, median / worst over seeds",
            "grid error max px, median / worst over seeds"]  # fmt: skip
    return f"## Homography over {seeds} seeds, Oxford graf ({w} x {h})\n\n" + markdown_table(
        cols, rows
    )


def _rel_rot_max(R: np.ndarray, R_ref: list[np.ndarray]) -> float:
    reg = [i for i in range(len(R_ref)) if np.all(np.isfinite(R[i]))]
    errs = [
        _rot_err(R[j] @ R[i].T, R_ref[j] @ R_ref[i].T) for i, j in itertools.combinations(reg, 2)
    ]
    return max(errs) if errs else float("nan")


def sfm_table(folder: Path, upscale: float) -> str:
    import cv2

    from imageform.geometry import BrownConrady, reconstruct_sequence

    names, poses, cam = _opensfm(folder)
    R_ref = [poses[n][0] for n in names]
    base = [_read_rgb(_images_dir(folder) / n) for n in names]
    rows = []
    for s in (1.0, upscale):
        imgs = base
        if s != 1.0:
            size = (round(base[0].shape[1] * s), round(base[0].shape[0] * s))
            imgs = [cv2.resize(im, size, interpolation=cv2.INTER_CUBIC) for im in base]
        h, w = imgs[0].shape[:2]
        K, k1, k2 = _camera(cam, w, h)
        label = f"{w} x {h} ({w * h / 1e6:.1f} Mpx)"
        t0 = time.perf_counter()
        try:
            rec = reconstruct_sequence(imgs, K, BrownConrady(k1=k1, k2=k2), window=len(imgs) - 1)
            rms = float(np.sqrt(np.mean(rec.residuals_px**2)))
            rows.append(
                [label, "imageform", f"{int(rec.registered.sum())}/{len(imgs)}",
                 len(rec.points), f"{rms:.2f}", f"{_rel_rot_max(rec.R, R_ref):.2f}",
                 f"{time.perf_counter() - t0:.1f}"]
            )  # fmt: skip
        except Exception as exc:  # a failure is a result
            rows.append([label, "imageform", type(exc).__name__, "", "", "", ""])
        rows.append([label, "pycolmap", *_pycolmap(imgs, names, K, k1, k2, R_ref)])
    cols = ["images", "library", "registered", "points", "RMS px", "worst rotation error deg",
            "s"]  # fmt: skip
    return f"## Structure from motion, {folder.name}\n\n" + markdown_table(cols, rows)


def _pycolmap(
    imgs: list[np.ndarray], names: list[str], K: np.ndarray, k1: float, k2: float, R_ref: Any
) -> list[object]:
    try:
        import cv2
        import pycolmap

        from benchmarks.bench_reconstruct import (
            pycolmap_options,
            pycolmap_poses,
            pycolmap_reconstruct,
        )
    except ImportError:
        return ["not installed", "", "", "", ""]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "images").mkdir()
        for n, im in zip(names, imgs, strict=True):
            cv2.imwrite(str(root / "images" / n), im[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 95])
        options = pycolmap_options(1, "RADIAL", (K[0, 0], K[0, 2], K[1, 2], k1, k2))

        def match(db: Path) -> None:
            pycolmap.match_exhaustive(db, matching_options=options[2], device=pycolmap.Device.cpu)

        maps, dt, _ = pycolmap_reconstruct(root, root / "images", options, match)
        _, R, points = pycolmap_poses(maps, names)
        rms = max(maps.values(), key=lambda r: r.num_reg_images()).compute_mean_reprojection_error()
    reg = int(np.all(np.isfinite(R), axis=(1, 2)).sum())
    return [f"{reg}/{len(names)}", points, f"{rms:.2f} (mean)", f"{_rel_rot_max(R, R_ref):.2f}",
            f"{dt:.1f}"]  # fmt: skip


def _detect_in_child(path: str, scale: float, max_size: int | None) -> tuple[float, int, int]:
    import cv2

    from imageform.geometry import detect_features

    im = _read_rgb(Path(path))
    im = cv2.resize(im, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)
    t0 = time.perf_counter()
    f = detect_features(im, max_size=max_size)
    dt = time.perf_counter() - t0
    return dt, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024, len(f)


def memory_table(folder: Path, upscale: float) -> str:
    names, _, _ = _opensfm(folder)
    path = str(_images_dir(folder) / names[0])
    rows = []
    ctx = multiprocessing.get_context("spawn")
    for s in (1.0, upscale):
        for cap in (3200, None):
            with concurrent.futures.ProcessPoolExecutor(1, mp_context=ctx) as pool:
                dt, mb, n = pool.submit(_detect_in_child, path, s, cap).result()
            rows.append([f"{s:g}", cap, n, f"{dt:.1f}", mb])
    cols = ["upscale", "max_size", "keypoints", "s", "peak memory MB (whole process)"]
    return f"## detect_features on {names[0]}, one process each\n\n" + markdown_table(cols, rows)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--graf", type=Path)
    ap.add_argument("--opensfm", type=Path)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--upscale", type=float, default=1.75)
    ap.add_argument("--seeds", type=int, default=0)
    ap.add_argument("--tasks", default="E,F,H", help="with --seeds: of E, F, H")
    args = ap.parse_args()
    print(header("Two-view geometry and SfM on real photographs"))
    print(f"load average: {' / '.join(Path('/proc/loadavg').read_text().split()[:3])}\n")
    if args.seeds > 0:
        tasks = tuple(args.tasks.split(","))
        if args.opensfm is not None and ("E" in tasks or "F" in tasks):
            print(seed_pose_table(args.opensfm, args.seeds, tasks))
        if args.graf is not None and "H" in tasks:
            print(seed_homography_table(args.graf, args.seeds))
        load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
        print(f"load average at the end: {load}")
        return
    if args.graf is not None:
        print(homography_table(args.graf, args.repeat))
    if args.opensfm is not None:
        print(pose_table(args.opensfm, args.repeat))
        print(memory_table(args.opensfm, args.upscale))
        print(sfm_table(args.opensfm, args.upscale))


if __name__ == "__main__":
    main()
