"""Endoscope cameras calibrated from real checkerboard photographs: imageform against OpenCV.

The photographs are third-party and not in this repository (no licence is stated with any set,
so they are not redistributable); ``SETS`` names each one's repository, commit and path.
Put each set's files in a folder of its name under the folder given on the command line
(``git show COMMIT:PATH`` in a clone of the repository gives them), then run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_calibration_endoscope.py PHOTOS --out TABLE.md

- ``endo-sl``: github.com/AlzuhiriMohand/Endoscopic-SL-and-laser-sensors-calibratiion,
  commit d3f06cc, ``CamCal/Cam*.png`` (39 views, 1664 x 1232): the fisheye camera of an
  endoscopic structured-light / laser sensor, a 10 x 7-square printed board (9 x 6 inner
  corners) on a monitor; the repository's own script calibrates it with ``cv2.fisheye``. No
  licence file.
- ``endo-orb``: github.com/cirauqui21/CameraCalibration_OpenCV, commit d95d772,
  ``inputFrames/6080HD.cal*.png`` and ``ExampleImages/6080HD.cal1090.png`` (9 views,
  768 x 576 PAL frames with a black surround and interlace lines): the calibration frames of
  "ORBSLAM Performance Evaluation in Medical Endoscope Sequences" (Universidad de Zaragoza), a
  board of 16 x 12 inner corners. No licence file.
- ``davinci-left``: github.com/nsujumnong/VisionPipelineSample, commit d659f20,
  ``Endoscope_Snapshot/small_chess/left*.png`` (40 views, 640 x 480): the left channel of a da
  Vinci surgical stereo endoscope (WPI AIM Lab), a board of 7 x 7 inner corners, dim, in a
  dark surround. No licence file.

Corners: imageform's ``find_checkerboard`` (defaults) against OpenCV's
``findChessboardCorners`` + ``cornerSubPix`` (the window of each set's own script: 3 x 3 for
endo-sl, 11 x 11 for the others) and ``findChessboardCornersSB`` (no flags); how far apart the
corners are on the views both find (each corner to the other's nearest), and (an accuracy
proxy: same camera, model and views) the RMS of imageform's ``kannala_brandt`` fit on each
detector's corners of the views all three find. Calibration, all on imageform's corners
(board in squares):
``calibrate_camera(model=...)`` for ``kannala_brandt``, ``rational`` and ``brown_conrady``
against ``cv2.fisheye.calibrate`` (``CALIB_RECOMPUTE_EXTRINSIC | CALIB_FIX_SKEW``, 300
iterations, ``ε = 1e-15``) and ``cv2.calibrateCamera`` (``CALIB_RATIONAL_MODEL`` and plain,
1000 iterations, ``ε = 1e-15``); OpenCV's RMS recomputed from its K, coefficients and poses.
``apart over the field``: the rays from the axis out to the largest angle of a corner in that
model's imageform fit, along 16 azimuths, projected by both fits (each its own K and
coefficients, through OpenCV's ``projectPoints``): the median and largest pixel distance.
Held out: the views split by parity (even, odd); each half calibrates and the other half's
views are fitted with that half's intrinsics held fixed (poses only: ``calibrate_camera`` with
every intrinsic in ``fix`` and ``max_iter=1000``, the same pose fit for OpenCV's intrinsics);
the RMS of those held-out views, both ways pooled, and the two halves' ``fx`` apart.
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
    """A folder of real endoscope photographs of one checkerboard, and where they came from."""

    name: str
    source: str
    licence: str
    pattern: str
    board: tuple[int, int]  # inner corners per row, per column (OpenCV's patternSize)
    what: str
    cv_win: int  # cornerSubPix half window of the set's own script


SETS = (
    PhotoSet(
        "endo-sl",
        "github.com/AlzuhiriMohand/Endoscopic-SL-and-laser-sensors-calibratiion "
        "CamCal/Cam*.png (commit d3f06cc, 2022)",
        "none stated (kept out of the repository)",
        "Cam*.png",
        (9, 6),
        "1664 x 1232 fisheye camera of an endoscopic structured-light sensor, a board of "
        "10 x 7 squares on a monitor, 39 views",
        3,
    ),
    PhotoSet(
        "endo-orb",
        "github.com/cirauqui21/CameraCalibration_OpenCV inputFrames/6080HD.cal*.png and "
        "ExampleImages/6080HD.cal1090.png (commit d95d772, 2021)",
        "none stated (kept out of the repository)",
        "6080HD.cal*.png",
        (16, 12),
        "768 x 576 PAL endoscope frames (black surround, interlace lines), a board of "
        "17 x 13 squares, 9 views",
        11,
    ),
    PhotoSet(
        "davinci-left",
        "github.com/nsujumnong/VisionPipelineSample Endoscope_Snapshot/small_chess/left*.png "
        "(commit d659f20, 2018)",
        "none stated (kept out of the repository)",
        "left*.png",
        (7, 7),
        "640 x 480 left channel of a da Vinci surgical stereo endoscope: a dim board of 8 x 8 "
        "squares in a dark surround, 40 views",
        11,
    ),
)

MODELS = ("kannala_brandt", "rational", "brown_conrady")
INTRINSICS = {
    "kannala_brandt": ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"),
    "rational": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "brown_conrady": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"),
}


def _cpu(fn: Any) -> tuple[Any, float]:
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def _match(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Each corner's distance to the nearest of the other detector's (a square board's corner
    order can differ by a quarter turn, a board's by a half turn, between detectors)."""
    return np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1).min(axis=1))


def _rms(sq: list[np.ndarray]) -> float:
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def _fmt(v: float, nd: int = 3) -> str:
    return "—" if not np.isfinite(v) else f"{v:.{nd}f}"


def _flag(cv2: Any, name: str) -> int:
    """A fisheye flag: ``cv2.fisheye.NAME`` in OpenCV 4, ``cv2.NAME`` in OpenCV 5."""
    return int(getattr(cv2.fisheye, name, getattr(cv2, name, 0)))


@dataclass
class Fit:
    """One calibration: K, the coefficients (OpenCV's order), RMS, CPU s and a note."""

    K: np.ndarray
    coef: np.ndarray
    rms: float
    cpu: float
    note: str = ""


def _if_fit(model: str, objs: list[np.ndarray], pts: list[np.ndarray], size: Any) -> Fit:
    from imageform.geometry import calibrate_camera

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res, t = _cpu(lambda: calibrate_camera(objs, pts, size, model=model))
    n = {"kannala_brandt": 4, "rational": 8, "brown_conrady": 5}[model]
    note = f"{res.n_evaluations} evaluations"
    if res.warnings:
        note += "; warns: " + res.warnings[0][:60]
    return Fit(res.K, np.asarray(res.distortion.coeffs[:n], dtype=np.float64), res.rms, t, note)


def _cv_fit(cv2: Any, model: str, objs: list[np.ndarray], pts: list[np.ndarray], size: Any) -> Fit:
    if model == "kannala_brandt":
        fe = cv2.fisheye
        flags = _flag(cv2, "CALIB_RECOMPUTE_EXTRINSIC") | _flag(cv2, "CALIB_FIX_SKEW")
        crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 300, 1e-15)
        o3 = [o.reshape(1, -1, 3) for o in objs]
        i2 = [c.reshape(1, -1, 2) for c in pts]
        (_, K, D, rv, tv), t = _cpu(
            lambda: fe.calibrate(o3, i2, size, np.zeros((3, 3)), np.zeros((4, 1)), flags=flags,
                                 criteria=crit)
        )  # fmt: skip
        sq = [
            np.sum((fe.projectPoints(o, r, tt, K, D)[0].reshape(-1, 2) - c) ** 2, axis=1)
            for o, c, r, tt in zip(o3, pts, rv, tv, strict=True)
        ]
        return Fit(K, np.ravel(D).astype(np.float64), _rms(sq), t)
    fl, n = (cv2.CALIB_RATIONAL_MODEL, 8) if model == "rational" else (0, 5)
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 1000, 1e-15)
    o32 = [o.astype(np.float32) for o in objs]
    i32 = [c.astype(np.float32) for c in pts]
    (_, K, D, rv, tv), t = _cpu(
        lambda: cv2.calibrateCamera(o32, i32, size, None, None, flags=fl, criteria=crit)
    )
    sq = [
        np.sum((cv2.projectPoints(o, r, tt, K, D)[0].reshape(-1, 2) - c) ** 2, axis=1)
        for o, c, r, tt in zip(objs, pts, rv, tv, strict=True)
    ]
    return Fit(K, np.ravel(D)[:n].astype(np.float64), _rms(sq), t)


def _project(cv2: Any, model: str, fit: Fit, rays: np.ndarray) -> np.ndarray:
    z = np.zeros(3)
    if model == "kannala_brandt":
        out = cv2.fisheye.projectPoints(rays.reshape(1, -1, 3), z, z, fit.K, fit.coef[:4])[0]
    else:
        out = cv2.projectPoints(rays, z, z, fit.K, fit.coef)[0]
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def _max_theta(model: str, objs: list[np.ndarray], pts: list[np.ndarray], size: Any) -> float:
    from imageform.geometry import calibrate_camera

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = calibrate_camera(objs, pts, size, model=model)
    cam = [o @ r.T + tv for o, r, tv in zip(objs, res.rotations, res.tvecs, strict=True)]
    return max(float(np.arctan2(np.hypot(c[:, 0], c[:, 1]), c[:, 2]).max()) for c in cam)


def _apart(cv2: Any, model: str, a: Fit, b: Fit, theta: float) -> tuple[float, float]:
    th = np.linspace(0.0, theta, 40)
    ph = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    T, P = np.meshgrid(th, ph)
    rays = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    d = np.hypot(*(_project(cv2, model, a, rays) - _project(cv2, model, b, rays)).T)
    return float(np.median(d)), float(d.max())


def _held_out(model: str, fit: Fit, objs: list[np.ndarray], pts: list[np.ndarray],
              size: Any) -> list[np.ndarray]:  # fmt: skip
    """Squared residuals of views fitted with ``fit``'s intrinsics held (poses only)."""
    from imageform.geometry import BrownConrady, KannalaBrandt, calibrate_camera

    c = [float(v) for v in fit.coef]
    dist = KannalaBrandt(*c) if model == "kannala_brandt" else BrownConrady(*c)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = calibrate_camera(objs, pts, size, model=model, K_init=fit.K, distortion_init=dist,
                               fix=INTRINSICS[model], max_iter=1000)  # fmt: skip
    return [np.sum(np.asarray(r).reshape(-1, 2) ** 2, axis=1) for r in res.residuals]


def run_set(s: PhotoSet, folder: Path, cv2: Any) -> tuple[list[object], list[list[object]]]:
    """Return the set's detection row and its calibration rows."""
    from PIL import Image

    from imageform.geometry import checkerboard_points
    from imageform.geometry.checkerboard import find_checkerboard

    files = sorted(folder.glob(s.pattern))
    ours: list[np.ndarray] = []
    n_cv = n_sb = 0
    d_cv: list[np.ndarray] = []
    d_sb: list[np.ndarray] = []
    missed: list[str] = []
    trio: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # the views all three find
    size = (0, 0)
    t_if = 0.0
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    for f in files:
        grey = np.asarray(Image.open(f).convert("L"))
        size = (grey.shape[1], grey.shape[0])
        det, t = _cpu(lambda g=grey: find_checkerboard(g, s.board))
        t_if += t
        ok, c = cv2.findChessboardCorners(grey, s.board, None)
        c_cv = None
        if ok:
            w = s.cv_win
            c_cv = cv2.cornerSubPix(grey, c, (w, w), (-1, -1), crit).reshape(-1, 2)
            n_cv += 1
        ok_sb, c_sb = cv2.findChessboardCornersSB(grey, s.board, 0)
        n_sb += int(ok_sb)
        if det.found:
            ours.append(np.asarray(det.corners, dtype=np.float64))
            if c_cv is not None:
                d_cv.append(_match(ours[-1], c_cv))
            if ok_sb:
                d_sb.append(_match(ours[-1], c_sb.reshape(-1, 2).astype(np.float64)))
            if c_cv is not None and ok_sb:
                trio.append((ours[-1], c_cv.astype(np.float64),
                             c_sb.reshape(-1, 2).astype(np.float64)))  # fmt: skip
        elif ok or ok_sb:
            missed.append(f"{f.name} ({det.reason[:70]})")
    obj = checkerboard_points(s.board, 1.0)
    trio_rms = []
    for k in range(3):
        pts = [v[k] for v in trio]
        trio_rms.append(_if_fit("kannala_brandt", [obj] * len(pts), pts, size).rms
                        if len(pts) >= 3 else np.nan)  # fmt: skip
    a = np.concatenate(d_cv) if d_cv else np.full(1, np.nan)
    b = np.concatenate(d_sb) if d_sb else np.full(1, np.nan)
    detection: list[object] = [
        s.name, len(files), len(ours), n_cv, n_sb,
        f"{_fmt(float(np.median(a)))} / {_fmt(float(a.max()))}",
        f"{_fmt(float(np.median(b)))} / {_fmt(float(b.max()))}",
        f"{len(trio)}: " + " / ".join(_fmt(v, 4) for v in trio_rms),
        "; ".join(missed) or "none", f"{t_if / max(len(files), 1):.2f}",
    ]  # fmt: skip
    objs = [obj] * len(ours)
    rows: list[list[object]] = []
    even = list(range(0, len(ours), 2))
    odd = list(range(1, len(ours), 2))

    def sub(idx: list[int]) -> tuple[list[np.ndarray], list[np.ndarray]]:
        return [objs[i] for i in idx], [ours[i] for i in idx]

    for model in MODELS:
        theta = _max_theta(model, objs, ours, size)
        fits: dict[str, Fit] = {}
        for who, fn in (("imageform", _if_fit), ("OpenCV", None)):
            try:
                if fn is not None:
                    fits[who] = fn(model, objs, ours, size)
                else:
                    fits[who] = _cv_fit(cv2, model, objs, ours, size)
            except Exception as exc:  # the table says what failed
                rows.append([s.name, model, who, len(ours), "failed", "", "", "", "", "", "",
                             "", type(exc).__name__ + ": " + str(exc).strip()[:80]])  # fmt: skip
        for who, fit in fits.items():
            held: list[np.ndarray] = []
            fxs: list[float] = []
            try:
                for train, test in ((even, odd), (odd, even)):
                    o_tr, p_tr = sub(train)
                    o_te, p_te = sub(test)
                    if who == "imageform":
                        half = _if_fit(model, o_tr, p_tr, size)
                    else:
                        half = _cv_fit(cv2, model, o_tr, p_tr, size)
                    fxs.append(float(half.K[0, 0]))
                    held += _held_out(model, half, o_te, p_te, size)
                held_txt = f"{_rms(held):.3f}"
                fx_txt = f"{abs(fxs[0] - fxs[1]):.2f}"
            except Exception as exc:
                held_txt, fx_txt = "failed: " + type(exc).__name__, ""
            apart = ""
            if who == "OpenCV" and "imageform" in fits:
                med, big = _apart(cv2, model, fits["imageform"], fit, theta)
                apart = f"{med:.1e} / {big:.1e} (to {np.degrees(theta):.0f} deg)"
            rows.append(
                [s.name, model, who, len(ours), _fmt(fit.rms, 4), _fmt(fit.K[0, 0], 2),
                 _fmt(fit.K[1, 1], 2), _fmt(fit.K[0, 2], 2), _fmt(fit.K[1, 2], 2), apart,
                 held_txt, fx_txt, f"{fit.cpu:.2f}" + (f"; {fit.note}" if fit.note else "")]
            )  # fmt: skip
    return detection, rows


def main() -> None:
    """Run every set found under PHOTOS and print (or write) the Markdown tables."""
    import cv2

    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
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
        detect.append(d)
        calib += c
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = header("Endoscope calibration from real photographs: imageform against OpenCV")
    text += (
        f"\nOpenCV {cv2.__version__}; load average {load:.1f} when run (a shared machine: "
        "times are indicative). Made by\n\n```bash\nOPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. "
        "python benchmarks/check_calibration_endoscope.py PHOTOS --out TABLE.md\n```\n\n"
        "with the sets below in PHOTOS/<set>/ (see the script's docstring).\n\n## Sets\n\n"
    )
    text += markdown_table(
        ("set", "source", "licence", "what"), [(s.name, s.source, s.licence, s.what) for s in SETS]
    )
    text += "\n## Corners: imageform's find_checkerboard and OpenCV's two detectors\n\n"
    text += markdown_table(
        ("set", "views", "imageform found", "findChessboardCorners found",
         "findChessboardCornersSB found", "apart from findChessboardCorners + cornerSubPix, "
         "median / largest (px)", "apart from SB, median / largest (px)",
         "views all three find: kannala_brandt RMS on imageform / cornerSubPix / SB corners (px)",
         "found by OpenCV, not imageform (imageform's reason)", "imageform CPU s a view"),
        detect,
    )  # fmt: skip
    text += "\n## Calibration on imageform's corners\n\n"
    text += markdown_table(
        ("set", "model", "by", "views", "RMS (px)", "fx", "fy", "cx", "cy",
         "apart over the field from imageform, median / largest (px)",
         "held-out RMS (px)", "fx of the two halves apart", "CPU s; note"),
        calib,
    )  # fmt: skip
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
