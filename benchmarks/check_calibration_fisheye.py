"""Fisheye calibration of real photographs: imageform's three lens models against OpenCV's.

The photographs are third-party (public repositories, listed in ``SETS`` with the commit and
licence of each); they are not in this repository. Put each set's files in a folder of its
name under the folder given on the command line (``PHOTOS/sweetiepie/left0000.jpg`` ...;
``git archive COMMIT FOLDER`` in a clone of the repository gives them), then run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src \\
        python benchmarks/check_calibration_fisheye.py PHOTOS --out TABLE.md

Corners: imageform's ``find_checkerboard`` (default adaptive window) and OpenCV's
``findChessboardCorners`` + ``cornerSubPix`` (11 x 11, as the sets' own scripts) on the same
grey image; the views each finds, and how far apart the two put the corners of the views both
find. Calibration, all on imageform's corners (board in squares: the intrinsics do not
depend on the unit): ``calibrate_camera(model=...)`` for ``kannala_brandt``, ``rational`` and
``brown_conrady`` against ``cv2.fisheye.calibrate`` (``CALIB_RECOMPUTE_EXTRINSIC |
CALIB_FIX_SKEW``; once on its own, once given its documented start ``f = max(w, h)/π`` at the
image centre through ``CALIB_USE_INTRINSIC_GUESS``, 300 iterations, ``ε = 1e-15``) and
``cv2.calibrateCamera`` (``CALIB_RATIONAL_MODEL``, and plain; 1000 iterations,
``ε = 1e-15``). The RMS of OpenCV's fits is recomputed from its K, coefficients and poses
(OpenCV's fisheye returns the RMS before its last step). ``max θ`` is the largest angle from
the axis of a corner in the fisheye fit. CPU time of each fit: the process's, one thread.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402


@dataclass(frozen=True)
class PhotoSet:
    """A folder of real fisheye photographs of one checkerboard, and where they came from."""

    name: str
    source: str
    licence: str
    pattern: str
    board: tuple[int, int]  # inner corners per row, per column (OpenCV's patternSize)
    what: str
    step: int = 1  # every step-th view (the refinement's dense normal equations grow as V²)


SETS = (
    PhotoSet(
        "xinningshen",
        "github.com/XinningShen/Fisheye_Camera_Calibration fisheye_chessboard_train_pic/*.jpg "
        "(commit 127b2bf, 2015)",
        "none stated (not redistributable: kept out of the repository)",
        "*.jpg",
        (6, 9),
        "640 x 640 fisheye webcam, a hand-held printed board of 7 x 10 squares, 15 views",
    ),
    PhotoSet(
        "sweetiepie",
        "github.com/mkdir-sweetiepie/fisheye_camera_calibration distorted/left*.jpg "
        "(commit 5ab60f7, 2025)",
        "Apache-2.0 (17 MB: kept out of the repository)",
        "left*.jpg",
        (7, 9),
        "736 x 736 circular fisheye (its image circle about 180 deg), a board of 8 x 10 "
        "squares, 101 views; every third view used",
        step=3,
    ),
)


def _cpu(fn: Any) -> tuple[Any, float]:
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def _cv_corners(cv2: Any, grey: np.ndarray, board: tuple[int, int]) -> np.ndarray | None:
    ok, c = cv2.findChessboardCorners(grey, board, None)
    if not ok:
        return None
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    return cv2.cornerSubPix(grey, c, (11, 11), (-1, -1), crit).reshape(-1, 2)


def _match(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances of corresponding corners; the two detectors may start at opposite ends."""
    d1, d2 = np.hypot(*(a - b).T), np.hypot(*(a[::-1] - b).T)
    return d1 if np.median(d1) <= np.median(d2) else d2


def _oriented(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``b`` in ``a``'s corner order (reversed when the detectors started at opposite ends)."""
    d1, d2 = np.hypot(*(a - b).T), np.hypot(*(a[::-1] - b).T)
    return b if np.median(d1) <= np.median(d2) else b[::-1]


def _rms(sq: list[np.ndarray]) -> float:
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def _fmt(v: float, nd: int = 3) -> str:
    return "—" if not np.isfinite(v) else f"{v:.{nd}f}"


def _coeffs(c: Any) -> str:
    return ", ".join(f"{float(v):.5g}" for v in np.ravel(c))


def run_set(s: PhotoSet, folder: Path, cv2: Any) -> tuple[list[list[object]], list[list[object]]]:
    """Return the set's detection row(s) and its calibration rows."""
    from PIL import Image

    from imageform.geometry import calibrate_camera, checkerboard_points
    from imageform.geometry.checkerboard import find_checkerboard

    files = sorted(folder.glob(s.pattern))[:: s.step]
    ours, theirs, names, dists, cv_views, far = [], [], [], [], [], []
    size = (0, 0)
    for f in files:
        grey = np.asarray(Image.open(f).convert("L"))
        size = (grey.shape[1], grey.shape[0])
        det = find_checkerboard(grey, s.board)
        c_cv = _cv_corners(cv2, grey, s.board)
        if det.found:
            ours.append(np.asarray(det.corners, dtype=np.float64))
            names.append(f.name)
        theirs.append(c_cv is not None)
        if det.found and c_cv is not None:
            dists.append(_match(ours[-1], c_cv))
            cv_views.append((ours[-1], _oriented(ours[-1], c_cv)))
            if dists[-1].max() > 1.0:
                far.append(f"{f.name} ({dists[-1].max():.1f})")
    missed = [
        f.name for f, o, t in zip(files, _found(files, names), theirs, strict=True) if t and not o
    ]
    only_ours = [
        f.name for f, o, t in zip(files, _found(files, names), theirs, strict=True) if o and not t
    ]
    d = np.concatenate(dists) if dists else np.zeros(0)
    detection = [
        s.name,
        len(files),
        len(ours),
        sum(theirs),
        ", ".join(missed) or "none",
        ", ".join(only_ours) or "none",
        _fmt(float(np.median(d)) if d.size else np.nan),
        _fmt(float(d.max()) if d.size else np.nan),
        ", ".join(far) or "none",
    ]
    obj = checkerboard_points(s.board, 1.0)
    objs = [obj] * len(ours)
    rows: list[list[object]] = []
    w, h = size

    def add(model: str, who: str, K: Any, coef: Any, rms: float, t: float, note: str = "") -> None:
        rows.append(
            [s.name, model, who, len(ours), _fmt(rms, 6), _fmt(K[0, 0]), _fmt(K[1, 1]),
             _fmt(K[0, 2]), _fmt(K[1, 2]), _coeffs(coef), f"{t:.2f}", note]
        )  # fmt: skip

    # imageform, three models
    fits = {}
    for model in ("kannala_brandt", "rational", "brown_conrady"):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res, t = _cpu(lambda m=model: calibrate_camera(objs, ours, size, model=m))
        except Exception as exc:  # the table says what failed
            rows.append([s.name, model, "imageform", len(ours), "failed", *[""] * 6, "",
                         type(exc).__name__ + ": " + str(exc)[:80]])  # fmt: skip
            continue
        fits[model] = res
        note = ""
        if model == "kannala_brandt":
            cam = [obj @ r.T + tv for r, tv in zip(res.rotations, res.tvecs, strict=True)]
            th = max(
                float(np.degrees(np.arctan2(np.hypot(c[:, 0], c[:, 1]), c[:, 2])).max())
                for c in cam
            )
            note = f"max θ {th:.1f} deg"
        add(model, "imageform", res.K, res.distortion.coeffs[: len(res.std) - 5], res.rms, t, note)
    # OpenCV fisheye, alone and from its documented start
    fe = cv2.fisheye
    flags = _flag(cv2, "CALIB_RECOMPUTE_EXTRINSIC") | _flag(cv2, "CALIB_FIX_SKEW")
    guess = _flag(cv2, "CALIB_USE_INTRINSIC_GUESS")
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 300, 1e-15)
    f0 = max(w, h) / np.pi
    K0 = np.array([[f0, 0.0, (w - 1) / 2], [0.0, f0, (h - 1) / 2], [0.0, 0.0, 1.0]])
    o3 = [obj.reshape(1, -1, 3) for obj in objs]
    i2 = [c.reshape(1, -1, 2) for c in ours]
    for label, fl, Kin in (("cv2.fisheye", flags, np.zeros((3, 3))),
                           ("cv2.fisheye, f = max(w, h)/π given", flags | guess, K0)):  # fmt: skip
        try:
            (_, Kc, Dc, rv, tv), t = _cpu(
                lambda fl=fl, Kin=Kin: fe.calibrate(
                    o3, i2, size, Kin.copy(), np.zeros((4, 1)), flags=fl, criteria=crit
                )
            )
        except cv2.error as exc:
            rows.append([s.name, "kannala_brandt", label, len(ours), "failed", *[""] * 6, "",
                         str(exc).strip().splitlines()[-1][:90]])  # fmt: skip
            continue
        sq = [
            np.sum((fe.projectPoints(o, r, tt, Kc, Dc)[0].reshape(-1, 2) - c) ** 2, axis=1)
            for o, c, r, tt in zip(o3, ours, rv, tv, strict=True)
        ]
        add("kannala_brandt", label, Kc, Dc, _rms(sq), t)
    # the fisheye on OpenCV's corners (the views both detectors find)
    cv_c = [c for _, c in cv_views]
    if len(cv_c) >= 3:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res, t = _cpu(lambda: calibrate_camera([obj] * len(cv_c), cv_c, size,
                                                   model="kannala_brandt"))  # fmt: skip
        rows.append(
            [s.name, "kannala_brandt", "imageform on OpenCV's corners", len(cv_c),
             _fmt(res.rms, 6), _fmt(res.K[0, 0]), _fmt(res.K[1, 1]), _fmt(res.K[0, 2]),
             _fmt(res.K[1, 2]), _coeffs(res.distortion.coeffs), f"{t:.2f}", ""]
        )  # fmt: skip
    # OpenCV pinhole models
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 1000, 1e-15)
    o32 = [o.astype(np.float32) for o in objs]
    i32 = [c.astype(np.float32) for c in ours]
    for model, fl, n in (("rational", cv2.CALIB_RATIONAL_MODEL, 8), ("brown_conrady", 0, 5)):
        try:
            (_, Kc, Dc, rv, tv), t = _cpu(
                lambda fl=fl: cv2.calibrateCamera(
                    o32, i32, size, None, None, flags=fl, criteria=crit
                )
            )
        except cv2.error as exc:
            rows.append([s.name, model, "cv2.calibrateCamera", len(ours), "failed", *[""] * 6,
                         "", str(exc).strip().splitlines()[-1][:90]])  # fmt: skip
            continue
        sq = [
            np.sum((cv2.projectPoints(o, r, tt, Kc, Dc)[0].reshape(-1, 2) - c) ** 2, axis=1)
            for o, c, r, tt in zip(objs, ours, rv, tv, strict=True)
        ]
        add(model, "cv2.calibrateCamera", Kc, np.ravel(Dc)[:n], _rms(sq), t)
    return [detection], rows


def _flag(cv2: Any, name: str) -> int:
    """A fisheye flag: ``cv2.fisheye.NAME`` in OpenCV 4, ``cv2.NAME`` in OpenCV 5."""
    return int(getattr(cv2.fisheye, name, getattr(cv2, name, 0)))


def _found(files: list[Path], names: list[str]) -> list[bool]:
    have = set(names)
    return [f.name in have for f in files]


def main() -> None:
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("photos", type=Path, help="folder with one sub-folder per set (SETS)")
    ap.add_argument("--out", type=Path, default=None, help="write the Markdown table here")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    detect, calib = [], []
    for s in SETS:
        folder = args.photos / s.name
        if not folder.is_dir():
            print(f"skipping {s.name}: no folder {folder}", file=sys.stderr)
            continue
        d, c = run_set(s, folder, cv2)
        detect += d
        calib += c
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = header("Fisheye calibration of real photographs: imageform against OpenCV")
    text += (
        f"\nOpenCV {cv2.__version__}; load average {load:.1f} when run (a shared machine: "
        "times are indicative). Made by\n\n```bash\nOPENBLAS_NUM_THREADS=1 PYTHONPATH=src "
        "python benchmarks/check_calibration_fisheye.py PHOTOS --out TABLE.md\n```\n\n"
        "with the sets below in PHOTOS/<set>/ (see the script's docstring).\n\n## Sets\n\n"
    )
    text += markdown_table(
        ("set", "source", "licence", "what"), [(s.name, s.source, s.licence, s.what) for s in SETS]
    )
    text += "\n## Corners: imageform's find_checkerboard and cv2.findChessboardCorners\n\n"
    text += markdown_table(
        (
            "set",
            "views",
            "imageform found",
            "OpenCV found",
            "OpenCV only",
            "imageform only",
            "median apart (px)",
            "largest apart (px)",
            "views > 1 px apart (largest, px)",
        ),
        detect,
    )
    text += "\n## Calibration on imageform's corners\n\n"
    text += markdown_table(
        (
            "set",
            "model",
            "by",
            "views",
            "RMS (px)",
            "fx",
            "fy",
            "cx",
            "cy",
            "coefficients",
            "CPU s",
            "note",
        ),
        calib,
    )
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
