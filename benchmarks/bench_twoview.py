"""Robust two-view geometry: imageform vs OpenCV on the same noisy, outlier-laden scenes.

Issue 17: median errors no worse than OpenCV's findHomography, findFundamentalMat,
findEssentialMat, recoverPose (and triangulatePoints). Issue 28: the robust estimators at
least as fast as OpenCV's USAC_MAGSAC at equal or better accuracy, one thread each
(``OPENBLAS_NUM_THREADS=1``, ``NUMBA_NUM_THREADS=1``, ``cv2.setNumThreads(1)``: set here
before NumPy, numba and OpenCV are imported). Run::

    python benchmarks/bench_twoview.py [--scenes 30] [--repeat 3]
    python benchmarks/bench_twoview.py --outliers 0.5 --sigma 0.5
    python benchmarks/bench_twoview.py --scenes 100 --tasks homography,fundamental
    python benchmarks/bench_twoview.py --kodak ../shared/data/kodak

Every scene (seeded) is a random 3-D point cloud (or a plane, for the homography) seen by
two cameras ``K = [[800, 0, 320], [0, 800, 240], [0, 0, 1]]`` (640 x 480) with a random
relative pose; Gaussian pixel noise ``sigma`` is added to both images and a fraction of
the second image's points is replaced by uniform random pixels (outliers). Both libraries
get the same arrays and the same threshold. Errors are measured against the noise-free
truth; the table gives the median over scenes of each error and of the wall time of one
call (each call timed ``--repeat`` times, median kept, after one untimed call), and the
ratios to OpenCV's USAC_MAGSAC row of the task (to the first row where there is none).
"""

from __future__ import annotations

import argparse
import os

if __name__ == "__main__":
    # one thread each, set before NumPy's BLAS or numba start their pools; only when run as a
    # script (the tests import this module's scenes and must not change their process's threads)
    for _var in ("OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
#: What ``--tasks`` can choose (all by default); ``essential`` includes recoverPose.
TASKS = ("homography", "fundamental", "essential", "triangulation")
W, H = 640, 480


def _rot(rvec: np.ndarray) -> np.ndarray:
    from imageform.geometry import rvec_to_matrix

    return np.asarray(rvec_to_matrix(rvec), dtype=np.float64)


def _project(X: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    h = (X @ R.T + t) @ K.T
    return h[:, :2] / h[:, 2:]


def scene(seed: int, n: int, outliers: float, sigma: float, planar: bool) -> dict[str, Any]:
    """Noise-free and noisy correspondences of one random two-view scene."""
    rng = np.random.default_rng(seed)
    R = _rot(rng.normal(0.0, 0.15, 3))
    t = rng.normal(0.0, 1.0, 3) * [1.0, 0.5, 0.3]
    t = t / np.linalg.norm(t)
    X: np.ndarray = np.empty((0, 3))
    for _ in range(100):  # a few poses see (almost) none of the cloud: seed 2515, say
        if len(X) >= n:
            break
        Y = rng.uniform([-3, -2, 4], [3, 2, 10], (4 * n, 3))
        if planar:
            normal = np.array([0.2, -0.1, 1.0])
            Y[:, 2] = 6.0 - (Y[:, :2] @ normal[:2]) / normal[2]
        u1, u2 = _project(Y, np.eye(3), np.zeros(3)), _project(Y, R, t)
        inside = np.all((u1 >= 0) & (u1 < [W, H]) & (u2 >= 0) & (u2 < [W, H]), axis=1)
        inside &= (Y @ R.T + t)[:, 2] > 0.5
        X = np.concatenate([X, Y[inside]])[:n]
    if len(X) < n:
        raise ValueError(f"scene {seed}: the second camera sees fewer than {n} of its points")
    u1, u2 = _project(X, np.eye(3), np.zeros(3)), _project(X, R, t)
    n1 = u1 + rng.normal(0.0, sigma, u1.shape)
    n2 = u2 + rng.normal(0.0, sigma, u2.shape)
    out = rng.random(n) < outliers
    n2[out] = rng.uniform([0, 0], [W, H], (int(out.sum()), 2))
    return {"X": X, "R": R, "t": t, "u1": u1, "u2": u2, "n1": n1, "n2": n2, "out": out}


def _angle_deg(R1: np.ndarray, R2: np.ndarray) -> float:
    c = (np.trace(R1.T @ R2) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _dir_deg(a: np.ndarray, b: np.ndarray) -> float:
    c = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _timed(fn: Callable[[], Any], repeat: int) -> tuple[Any, float]:
    out = fn()  # untimed: a first call (compilation, caches)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def _one_scene(
    s: int, args: argparse.Namespace, add: Callable[[str, str, float, float], None]
) -> None:
    import cv2

    cv2.setNumThreads(1)
    from imageform.geometry import (
        find_essential_matrix,
        find_fundamental_matrix,
        find_homography,
        recover_pose,
        triangulate_two_view,
    )
    from imageform.geometry._minimal import sampson_sq

    # --- homography (plane) -----------------------------------------------------
    sc = scene(1000 + s, args.n, args.outliers, args.sigma, planar=True)
    u1, u2, n1, n2 = sc["u1"], sc["u2"], sc["n1"], sc["n2"]

    def h_err(Hm: np.ndarray) -> float:
        q = np.c_[u1, np.ones(len(u1))] @ Hm.T
        return float(np.sqrt(np.mean(np.sum((q[:, :2] / q[:, 2:] - u2) ** 2, -1))))

    if "homography" in args.tasks:
        cv2.setRNGSeed(s)
        Hc, t_c = _timed(lambda: cv2.findHomography(n1, n2, cv2.RANSAC, args.h_thr)[0], args.repeat)
        add(
            "homography: RMS transfer error of the true points (px)",
            "OpenCV findHomography RANSAC",
            h_err(Hc),
            t_c,
        )
        cv2.setRNGSeed(s)
        Hm, t_m = _timed(
            lambda: cv2.findHomography(n1, n2, cv2.USAC_MAGSAC, args.h_thr)[0], args.repeat
        )
        add(
            "homography: RMS transfer error of the true points (px)",
            "OpenCV findHomography USAC_MAGSAC",
            h_err(Hm),
            t_m,
        )
        res, t_i = _timed(lambda: find_homography(n1, n2, threshold=args.h_thr, rng=s), args.repeat)
        add(
            "homography: RMS transfer error of the true points (px)",
            "imageform find_homography",
            h_err(res.H),
            t_i,
        )

    # --- fundamental / essential / pose (general scene) ---------------------------
    sc = scene(2000 + s, args.n, args.outliers, args.sigma, planar=False)
    u1, u2, n1, n2 = sc["u1"], sc["u2"], sc["n1"], sc["n2"]

    def f_err(F: np.ndarray) -> float:
        return float(np.sqrt(np.mean(sampson_sq(F, u1, u2))))

    if "fundamental" in args.tasks:
        cv2.setRNGSeed(s)
        Fc, t_c = _timed(
            lambda: cv2.findFundamentalMat(n1, n2, cv2.FM_RANSAC, args.f_thr, 0.999)[0], args.repeat
        )
        add(
            "fundamental: RMS Sampson distance of the true points (px)",
            "OpenCV findFundamentalMat FM_RANSAC",
            f_err(Fc[:3]),
            t_c,
        )
        cv2.setRNGSeed(s)
        Fm, t_m = _timed(
            lambda: cv2.findFundamentalMat(n1, n2, cv2.USAC_MAGSAC, args.f_thr, 0.999)[0],
            args.repeat,
        )
        add(
            "fundamental: RMS Sampson distance of the true points (px)",
            "OpenCV findFundamentalMat USAC_MAGSAC",
            f_err(Fm[:3]),
            t_m,
        )
        resf, t_i = _timed(
            lambda: find_fundamental_matrix(n1, n2, threshold=args.f_thr, rng=s), args.repeat
        )
        add(
            "fundamental: RMS Sampson distance of the true points (px)",
            "imageform find_fundamental_matrix",
            f_err(resf.F),
            t_i,
        )

    if "essential" in args.tasks:
        cv2.setRNGSeed(s)
        (Ec, mc), t_c = _timed(
            lambda: cv2.findEssentialMat(n1, n2, K, cv2.RANSAC, 0.999, args.f_thr), args.repeat
        )
        rese, t_i = _timed(
            lambda: find_essential_matrix(n1, n2, K, threshold=args.f_thr, rng=s), args.repeat
        )
        cv2.setRNGSeed(s)
        (Em, mm), t_m = _timed(
            lambda: cv2.findEssentialMat(n1, n2, K, cv2.USAC_MAGSAC, 0.999, args.f_thr), args.repeat
        )
        mc = mc.ravel().astype(bool)
        Ec = Ec[:3]
        mm = mm.ravel().astype(bool)
        Em = Em[:3]
        (_, Rm, tm, _), t_pm = _timed(
            lambda: cv2.recoverPose(Em, n1, n2, K, mask=mm.astype(np.uint8).copy()), args.repeat
        )
        # pose of each library from its own E
        (_, Rc, tc, _), t_pc = _timed(
            lambda: cv2.recoverPose(Ec, n1, n2, K, mask=mc.astype(np.uint8).copy()), args.repeat
        )
        pose, t_pi = _timed(
            lambda: recover_pose(rese.E, n1, n2, K, inliers=rese.inliers), args.repeat
        )
        add(
            "essential + pose: rotation error (deg)",
            "OpenCV findEssentialMat RANSAC + recoverPose",
            _angle_deg(Rc, sc["R"]),
            t_c + t_pc,
        )
        add(
            "essential + pose: rotation error (deg)",
            "OpenCV findEssentialMat USAC_MAGSAC + recoverPose",
            _angle_deg(Rm, sc["R"]),
            t_m + t_pm,
        )
        add(
            "essential + pose: rotation error (deg)",
            "imageform find_essential_matrix + recover_pose",
            _angle_deg(pose.R, sc["R"]),
            t_i + t_pi,
        )
        add(
            "essential + pose: translation direction error (deg)",
            "OpenCV findEssentialMat RANSAC + recoverPose",
            _dir_deg(tc.ravel(), sc["t"]),
            t_c + t_pc,
        )
        add(
            "essential + pose: translation direction error (deg)",
            "OpenCV findEssentialMat USAC_MAGSAC + recoverPose",
            _dir_deg(tm.ravel(), sc["t"]),
            t_m + t_pm,
        )
        add(
            "essential + pose: translation direction error (deg)",
            "imageform find_essential_matrix + recover_pose",
            _dir_deg(pose.t, sc["t"]),
            t_i + t_pi,
        )
        # recoverPose alone, on the same (OpenCV's) E and mask
        (_, Rc2, _tc2, _), t_c = _timed(
            lambda: cv2.recoverPose(Ec, n1, n2, K, mask=mc.astype(np.uint8).copy()), args.repeat
        )
        pose2, t_i = _timed(lambda: recover_pose(Ec, n1, n2, K, inliers=mc), args.repeat)
        add(
            "recoverPose on the same E: rotation error (deg)",
            "OpenCV recoverPose",
            _angle_deg(Rc2, sc["R"]),
            t_c,
        )
        add(
            "recoverPose on the same E: rotation error (deg)",
            "imageform recover_pose",
            _angle_deg(pose2.R, sc["R"]),
            t_i,
        )

    # --- triangulation (true cameras, noisy inlier pixels) -----------------------------
    if "triangulation" in args.tasks:
        inl = ~sc["out"]
        P1 = K @ np.hstack([np.eye(3), np.zeros((3, 1))])
        P2 = K @ np.hstack([sc["R"], sc["t"][:, None]])
        a, b = n1[inl], n2[inl]
        Xt = sc["X"][inl]

        def x_err(X: np.ndarray) -> float:
            return float(np.median(np.linalg.norm(X - Xt, axis=-1)))

        Xc, t_c = _timed(lambda: cv2.triangulatePoints(P1, P2, a.T, b.T), args.repeat)
        add(
            "triangulation: median 3-D error (baseline = 1)",
            "OpenCV triangulatePoints",
            x_err((Xc[:3] / Xc[3]).T),
            t_c,
        )

        def reproj(X: np.ndarray) -> float:
            h1, h2 = X @ P1[:, :3].T + P1[:, 3], X @ P2[:, :3].T + P2[:, 3]
            e = np.sum((h1[:, :2] / h1[:, 2:] - a) ** 2 + (h2[:, :2] / h2[:, 2:] - b) ** 2, -1)
            return float(np.median(np.sqrt(e / 2.0)))

        add(
            "triangulation: median reprojection error, both views (px)",
            "OpenCV triangulatePoints",
            reproj((Xc[:3] / Xc[3]).T),
            t_c,
        )
        for method in ("linear", "midpoint", "optimal"):

            def tri(m: str = method) -> Any:
                return triangulate_two_view(P1, P2, a, b, method=m)

            r, t_i = _timed(tri, args.repeat)
            add(
                "triangulation: median reprojection error, both views (px)",
                f"imageform triangulate_two_view {method}",
                reproj(r.points),
                t_i,
            )
            add(
                "triangulation: median 3-D error (baseline = 1)",
                f"imageform triangulate_two_view {method}",
                x_err(r.points),
                t_i,
            )


def run_kodak(args: argparse.Namespace) -> str:
    """Real SIFT matches between each Kodak image and a warp of it by a known homography."""
    import cv2 as _cv2

    _cv2.setNumThreads(1)

    from imageform.geometry import find_homography

    cv2: Any = _cv2

    names = sorted(n for n in os.listdir(args.kodak) if n.endswith(".png"))
    sift = cv2.SIFT_create(nfeatures=1500)
    rng = np.random.default_rng(0)
    rec: dict[str, list[tuple[float, float]]] = {}
    n_match, out_frac = [], []
    for name in names:
        im = cv2.imread(os.path.join(args.kodak, name), cv2.IMREAD_GRAYSCALE)
        h, w = im.shape
        corners = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=np.float32)
        moved = (corners + rng.uniform(-0.12, 0.12, (4, 2)) * [w, h]).astype(np.float32)
        Ht = cv2.getPerspectiveTransform(corners, moved)
        im2 = cv2.warpPerspective(im, Ht, (w, h))
        im2 = np.clip(im2 + rng.normal(0, 3, im2.shape), 0, 255).astype(np.uint8)
        k1, d1 = sift.detectAndCompute(im, None)
        k2, d2 = sift.detectAndCompute(im2, None)
        good = [
            m for m, m2 in cv2.BFMatcher().knnMatch(d1, d2, k=2) if m.distance < 0.85 * m2.distance
        ]
        p1 = np.array([k1[g.queryIdx].pt for g in good])
        p2 = np.array([k2[g.trainIdx].pt for g in good])
        grid = np.stack(np.meshgrid(np.linspace(0, w - 1, 20), np.linspace(0, h - 1, 20)), -1)
        grid = grid.reshape(-1, 2)

        def apply(Hm: np.ndarray, p: np.ndarray) -> np.ndarray:
            q = np.c_[p, np.ones(len(p))] @ Hm.T
            return q[:, :2] / q[:, 2:]

        def err(Hm: np.ndarray, grid: np.ndarray = grid, Ht: np.ndarray = Ht) -> float:
            return float(np.sqrt(np.mean(np.sum((apply(Hm, grid) - apply(Ht, grid)) ** 2, -1))))

        n_match.append(len(p1))
        out_frac.append(float(np.mean(np.linalg.norm(apply(Ht, p1) - p2, axis=1) > 3.0)))
        runs = {
            "OpenCV findHomography RANSAC": lambda p1=p1, p2=p2: cv2.findHomography(
                p1, p2, cv2.RANSAC, 3.0
            )[0],
            "OpenCV findHomography USAC_MAGSAC": lambda p1=p1, p2=p2: cv2.findHomography(
                p1, p2, cv2.USAC_MAGSAC, 3.0
            )[0],
            "imageform find_homography": lambda p1=p1, p2=p2: (
                find_homography(p1, p2, threshold=3.0).H
            ),
        }
        for who, fn in runs.items():
            cv2.setRNGSeed(0)
            Hm, sec = _timed(fn, args.repeat)
            rec.setdefault(who, []).append((err(Hm), sec))
    base = rec["OpenCV findHomography RANSAC"]
    b_err = statistics.median(v[0] for v in base)
    b_sec = statistics.median(v[1] for v in base)
    rows = []
    for who, vals in rec.items():
        err_m = statistics.median(v[0] for v in vals)
        sec = statistics.median(v[1] for v in vals)
        rows.append(
            [who, f"{err_m:.4g}", f"{err_m / b_err:.4f}", f"{sec * 1e3:.3g}", f"{sec / b_sec:.2f}"]
        )
    text = header("Homography on real SIFT matches (Kodak): imageform vs OpenCV " + cv2.__version__)
    text += (
        f"\n{len(names)} Kodak images, each matched (SIFT, 1500 features, ratio test 0.85) "
        "with a copy warped by a random known homography (corners moved by up to 12 % of the "
        "size) plus Gaussian noise (3 grey levels); median "
        f"{statistics.median(n_match):.0f} matches, median outlier fraction "
        f"{statistics.median(out_frac):.1%} (true transfer error > 3 px); threshold 3 px. "
        "Error: RMS distance between the estimated and the true mapping of a 20 x 20 grid "
        "over the image (px), median over images; time per call (median of "
        f"{args.repeat}, then over images).\n\n"
    )
    cols = ["method", "median error (px)", "error / OpenCV", "median ms", "time / OpenCV"]
    return text + markdown_table(cols, rows)


def run(args: argparse.Namespace) -> str:
    rec: dict[tuple[str, str], list[tuple[float, float]]] = {}

    def add(task: str, who: str, err: float, sec: float) -> None:
        if not args.essential_only or task.startswith(("essential", "recoverPose")):
            rec.setdefault((task, who), []).append((err, sec))

    for s in range(args.scenes):
        _one_scene(s, args, add)

    rows = []
    tasks = list(dict.fromkeys(task for task, _ in rec))
    for task in tasks:
        entries = [(who, vals) for (t, who), vals in rec.items() if t == task]
        base = next((vals for who, vals in entries if "USAC_MAGSAC" in who), entries[0][1])
        b_err = statistics.median(v[0] for v in base)
        b_sec = statistics.median(v[1] for v in base)
        for who, vals in entries:
            err = statistics.median(v[0] for v in vals)
            sec = statistics.median(v[1] for v in vals)
            rows.append(
                [
                    task,
                    who,
                    f"{err:.4g}",
                    f"{err / b_err:.4f}" if b_err > 0 else "-",
                    f"{sec * 1e3:.3g}",
                    f"{sec / b_sec:.2f}",
                ]
            )
    cols = ["task", "method", "median error", "error / ref.", "median ms", "time / ref."]
    text = header("Robust two-view geometry: imageform vs OpenCV " + __import__("cv2").__version__)
    text += (
        f"\n{args.scenes} scenes, N = {args.n} correspondences, {args.outliers:.0%} outliers, "
        f"pixel noise sigma = {args.sigma} px in both images; thresholds: homography "
        f"{args.h_thr} px, fundamental / essential {args.f_thr} px; each call timed "
        f"{args.repeat} times (median, after one untimed call), then the median over scenes. "
        "The ratios (ref.) are to the OpenCV USAC_MAGSAC row of each task, to the first row "
        "where there is none. One thread each.\n\n"
    )
    return text + markdown_table(cols, rows)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--outliers", type=float, default=0.3)
    ap.add_argument("--sigma", type=float, default=1.0)
    ap.add_argument("--h-thr", type=float, default=3.0)
    ap.add_argument("--f-thr", type=float, default=1.0)
    ap.add_argument(
        "--essential-only", action="store_true", help="table only the essential + pose rows"
    )
    ap.add_argument("--kodak", default=None, help="folder of the Kodak PNGs: run that test only")
    ap.add_argument(
        "--tasks",
        default=",".join(TASKS),
        type=lambda v: v.split(","),
        help="comma-separated subset of " + ", ".join(TASKS),
    )
    args = ap.parse_args()
    print(run_kodak(args) if args.kodak else run(args))


if __name__ == "__main__":
    main()
