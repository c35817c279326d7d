"""ChArUco corners: the point-symmetry refinement (markers masked) against the gradient one.

``detect_charuco(method="symmetric")`` moves each corner the gradient refinement found to the
centre of the board's point symmetry, the markers' bits left out (see
``imageform.geometry.charuco``). Here, per method:

- rendered views with known corners (``tests/geometry/test_charuco.py``'s ``_composite``: a
  7 x 5 board, 5x5_100, composited into the Kodak photographs, 20-60 px squares, any turn,
  up to ~35 deg of tilt, blur 0 / 0.7 / 1.5 px, noise 0 / 1 / 3 %, every fourth view cut by
  the border): corners found, median / 95th percentile / largest error against the truth
  (the corners both methods report), and CPU ms per view (each view's median of
  ``--repeat`` interleaved runs, median over the views);
- the same for variants of the mask (``--variants``): none (the plain symmetric cost,
  markers in), the markers masked whole (their square of cells), and the bits only (the
  markers' black border kept: it is point-symmetric too, as both markers are centred in
  their squares);
- the real photographs of ``benchmarks/check_charuco_real.py`` (``PHOTOS``, one folder per
  set, see there for sources and licences): corners, how far the symmetric refinement moves
  them (median / 95th pct px), the RMS reprojection error of ``cv2.calibrateCamera`` on each
  method's corners where 3 views or more have 6 corners, and a held-out RMS (two-fold: the
  camera calibrated on the even views, each odd view's pose solved by PnP with it and its
  corners' RMS reprojection error taken, and the other way round), and CPU ms per view;
- the degraded views of ``check_charuco_real`` (downscaled, blurred, JPEG, noise, dark, cut)
  against its reference (the corners the gradient method and OpenCV's CharucoDetector put
  within 0.5 px of each other in the undegraded view): corners found of it (all found) and
  those more than 1.5 px (scaled, at least 0.5 px) off it, per method.

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_charuco_symmetric.py PHOTOS --scenes 48
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402

METHODS = ("gradient", "symmetric")


@contextmanager
def variant(name: str) -> Iterator[None]:
    """Run ``detect_charuco(method="symmetric")`` with another mask (private settings)."""
    import imageform.geometry.charuco as ch

    inset, masked = ch._SYM_INSET, ch._SYM_MASKED
    try:
        if name == "unmasked":
            ch._SYM_MASKED = False
        elif name == "whole markers masked":
            ch._SYM_INSET = 0
        elif name == "bits masked":
            ch._SYM_INSET = 1
        yield
    finally:
        ch._SYM_INSET, ch._SYM_MASKED = inset, masked


def _timed(fn: Callable[[], Any], repeat: int) -> tuple[Any, float]:
    out, times = None, []
    for _ in range(max(1, repeat)):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return out, statistics.median(times)


def rendered(n: int, seed: int, repeat: int, variants: list[str]) -> list[list[object]]:
    """Rows of the rendered views' table: per method (and mask variant)."""
    from imageform.geometry import CharucoBoard, detect_charuco
    from tests.geometry.test_charuco import _composite, _kodak

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    rng = np.random.default_rng(seed)
    scenes = []
    for k in range(n):
        scenes.append(
            _composite(
                rng,
                board,
                _kodak(k % 24 + 1),
                square_px=int(rng.integers(20, 60)),
                blur=float(rng.choice([0.0, 0.7, 1.5])),
                noise=float(rng.choice([0.0, 0.01, 0.03])),
                cut=k % 4 == 3,
            )
        )
    runs = [("gradient", "gradient"), ("symmetric", "symmetric")]
    runs += [(f"symmetric, {v}", v) for v in variants]
    errs: dict[str, list[float]] = {name: [] for name, _ in runs}
    found: dict[str, int] = dict.fromkeys(errs, 0)
    cpu: dict[str, list[float]] = {name: [] for name, _ in runs}
    detect_charuco(scenes[0][0], board, method="symmetric")  # compile / load the kernels
    for img, truth in scenes:
        per = {}
        for name, v in runs:  # interleaved: one view, every method
            method = "gradient" if v == "gradient" else "symmetric"
            with variant(v):
                res, t = _timed(partial(detect_charuco, img, board, method=method), repeat)
            per[name] = res
            cpu[name].append(t)
            found[name] += len(res)
        common = per["gradient"].ids
        for res in per.values():
            common = np.intersect1d(common, res.ids)
        for name, res in per.items():
            at = np.searchsorted(res.ids, common)
            errs[name].extend(np.hypot(*(res.corners[at] - truth[common]).T).tolist())
    rows: list[list[object]] = []
    for name, _ in runs:
        e = np.asarray(errs[name])
        rows.append(
            [
                name,
                found[name],
                f"{np.median(e):.3f}",
                f"{np.percentile(e, 95):.3f}",
                f"{e.max():.2f}",
                int((e > 1.5).sum()),
                f"{1000 * statistics.median(cpu[name]):.1f}",
            ]
        )
    return rows


def _heldout(views: list[tuple[np.ndarray, np.ndarray]], obj: np.ndarray, size: Any) -> str:
    """Two-fold held-out RMS (px): calibrate on even views, PnP + reproject the odd, and back."""
    import cv2

    if len(views) < 6:
        return "-"
    sq = []
    folds = (list(range(0, len(views), 2)), list(range(1, len(views), 2)))
    for train, test in (folds, folds[::-1]):
        objs = [obj[views[k][0]].astype(np.float32) for k in train]
        pts = [views[k][1].astype(np.float32) for k in train]
        _, K, D, _, _ = cv2.calibrateCamera(objs, pts, size, None, None)
        for k in test:
            o, p = obj[views[k][0]].astype(np.float32), views[k][1].astype(np.float32)
            _, rv, tv = cv2.solvePnP(o, p, K, D)
            pr, _ = cv2.projectPoints(o, rv, tv, K, D)
            sq.append(np.sum((pr.reshape(-1, 2) - p) ** 2, axis=1))
    return f"{np.sqrt(np.concatenate(sq).mean()):.3f}"


def real(
    photos: Path, repeat: int, only: list[str]
) -> tuple[list[list[object]], list[list[object]]]:
    """Rows of the real photographs' table and of the degraded views' table."""
    import cv2

    from benchmarks.check_charuco_real import CV_DICTS, KINDS, SETS, _cv, _rms, degrade
    from imageform.geometry import CharucoBoard, detect_charuco

    summary: list[list[object]] = []
    degraded: list[list[object]] = []
    for s in SETS:
        if only and s.name not in only:
            continue
        files = sorted((photos / (s.folder or s.name)).glob(s.pattern))
        if not files:
            print(f"(no photographs for {s.name} under {photos})", file=sys.stderr)
            continue
        extra = {"first_marker": s.first_marker} if s.first_marker else {}
        board = CharucoBoard(s.squares, s.square, s.marker, s.dictionary, **extra)
        cv_board = cv2.aruco.CharucoBoard(
            s.squares,
            s.square,
            s.marker,
            cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, CV_DICTS[s.dictionary])),
            np.arange(s.first_marker, s.first_marker + board.n_markers),
        )
        cv_board.setLegacyPattern(s.legacy)
        detector = cv2.aruco.CharucoDetector(cv_board)
        obj = board.corner_points()
        greys = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE) for f in files]
        size = (greys[0].shape[1], greys[0].shape[0])
        for m in METHODS:
            detect_charuco(greys[0], board, method=m)  # untimed
        views: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {m: [] for m in METHODS}
        n: dict[str, int] = dict.fromkeys(METHODS, 0)
        cpu: dict[str, list[float]] = {m: [] for m in METHODS}
        moved: list[float] = []
        refs = []
        for g in greys:
            got = {}
            for m in METHODS:
                got[m], t = _timed(partial(detect_charuco, g, board, method=m), repeat)
                cpu[m].append(t)
                n[m] += len(got[m])
                if len(got[m]) >= 6:
                    views[m].append((got[m].ids, got[m].corners))
            a, b = got["gradient"], got["symmetric"]
            common, ia, ib = np.intersect1d(a.ids, b.ids, return_indices=True)
            moved.extend(np.hypot(*(a.corners[ia] - b.corners[ib]).T).tolist())
            ids, xy = _cv(detector, g)
            common, ia, ib = np.intersect1d(a.ids, ids, return_indices=True)
            ok = np.hypot(*(a.corners[ia] - xy[ib]).T) < 0.5
            mean = 0.5 * (a.corners[ia] + xy[ib])
            refs.append(dict(zip(common[ok].tolist(), mean[ok], strict=True)))
        mv = np.asarray(moved) if moved else np.zeros(1)
        summary.append(
            [
                s.name,
                len(files),
                f"{n['gradient']} / {n['symmetric']}",
                f"{np.median(mv):.3f} / {np.percentile(mv, 95):.3f}",
                " / ".join(_rms(views[m], obj, greys[0].shape) for m in METHODS),
                " / ".join(_heldout(views[m], obj, size) for m in METHODS),
                " / ".join(f"{1000 * statistics.median(cpu[m]):.0f}" for m in METHODS),
            ]
        )
        n_ref = sum(len(r) for r in refs)
        for kind in KINDS if n_ref else ():
            rng = np.random.default_rng(0)
            tally = {m: [0, 0, 0] for m in METHODS}  # found of the reference, off, all
            for g, ref in zip(greys, refs, strict=True):
                view, scale = degrade(g, kind, rng)
                for m in METHODS:
                    res = detect_charuco(view, board, method=m)
                    tally[m][2] += len(res)
                    for i, p in zip(res.ids.tolist(), res.corners, strict=True):
                        if i in ref:
                            q = (ref[i] + 0.5) * scale - 0.5
                            tally[m][0] += 1
                            tally[m][1] += bool(np.hypot(*(p - q)) > max(1.5 * scale, 0.5))
            degraded.append(
                [s.name, kind, n_ref]
                + [f"{tally[m][0]} ({tally[m][2]}) / {tally[m][1]}" for m in METHODS]
            )
    return summary, degraded


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("photos", type=Path, nargs="?", help="folder with a subfolder per set")
    ap.add_argument("--scenes", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3, help="timed runs a view (median)")
    ap.add_argument("--only", nargs="*", default=[], help="real set names")
    ap.add_argument(
        "--variants",
        nargs="*",
        default=["unmasked", "whole markers masked", "bits masked"],
        help="mask variants of the symmetric refinement on the rendered views",
    )
    ns = ap.parse_args()
    import cv2

    cv2.setNumThreads(1)
    parts = [header("ChArUco corners: point-symmetry refinement (markers masked) vs gradient")]
    if ns.scenes:
        rows = rendered(ns.scenes, ns.seed, ns.repeat, ns.variants)
        parts += [
            f"Rendered views with known corners: {ns.scenes} scenes, seed {ns.seed} (see the "
            "script); errors over the corners every row reports; CPU ms per view for the "
            "whole detection (markers included).",
            "",
            markdown_table(
                [
                    "refinement",
                    "corners found",
                    "median error px",
                    "95th pct error px",
                    "largest error px",
                    "wrong (> 1.5 px)",
                    "CPU ms per view",
                ],
                rows,
            ),
        ]
    if ns.photos:
        summary, degraded = real(ns.photos, ns.repeat, ns.only)
        parts += [
            "Real photographs (benchmarks/check_charuco_real.py's sets and sources); each "
            "pair of figures is gradient / symmetric:",
            "",
            markdown_table(
                [
                    "set",
                    "views",
                    "corners",
                    "symmetric moves them: median / 95th pct px",
                    "cv2.calibrateCamera RMS px",
                    "held-out RMS px (two-fold)",
                    "CPU ms per view",
                ],
                summary,
            ),
            "Degraded views against check_charuco_real's reference: found of it (all found) "
            "/ more than 1.5 px (scaled) off it, gradient and symmetric:",
            "",
            markdown_table(
                ["set", "degraded", "reference corners", "gradient", "symmetric"], degraded
            ),
        ]
    parts.append(f"Load average at the end: {os.getloadavg()[0]:.1f} (2 shared cores).")
    print("\n".join(parts))


if __name__ == "__main__":
    main()
