"""Focal length from vanishing points in real photographs with a known camera.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_vp_real.py

The only real photographs in ``../shared/data`` whose camera is known are OpenCV's 13
checkerboard views ``opencv-left/left*.jpg`` (640 x 480, grey; calibrated in OpenCV's
tutorial: f = 536.07 px, principal point (342.37, 235.54), 23 px right of the image centre;
k1 = -0.265). Each view is undistorted with that calibration (straight lines must be straight)
and ``detect_vanishing_points(image, principal_point=...)`` runs on it with the default
settings otherwise. The scenes: a board held at various angles in front of a wall, shelves and
a ceiling - the board's rows and columns give two orthogonal directions, the room adds
clutter and sometimes a third direction.

Four ways to place the principal point: the image centre (the default), the orthocentre of
three finite vanishing points (the textbook construction, the detector's behaviour before
2026-11-26), ``"estimate"`` (the orthocentre only where three finite, well-supported points
fix it and a focal length there tightly, within 20 % of the image's size of the centre;
the centre otherwise), and the calibrated one (as from a camera file). The table gives the
focal length found and its error against 536.07 px; "-" where no K was determined.

This is not the York Urban DB (the benchmark issue 17's targets refer to, not available here):
13 frames of one camera, dominated by one planar object.

``--photos DIR`` adds a table for the photographs in a folder (``*.jpg``, ``*.png``; read
with their EXIF orientation) and an optional ``DIR/truth.csv`` (columns ``file``, ``f_px``,
``horizon_left``, ``horizon_right``, ``note``: the focal length in pixels where the camera is
known, e.g. from EXIF or a calibration, and the annotated horizon's rows at the image's
first and last columns), with the default settings: a summary (K found, the median focal
length error, within 5 %, off by more than 20 %; the horizon error as York Urban scores it,
the larger distance at the left and right edges over the height, an image without a horizon
counting as infinite; how many versions give the original's answer), then for each
photograph the time, the segments, the points found (``inf``: beyond 20 diagonals),
the focal length and its error, the horizon (its tilt, its row at the image centre, its
error) and why no K was given (``K_reason``, where the library has it), and,
for each photograph, the same on four versions of it: half size (f and the row scaled back),
JPEG quality 30, Gaussian noise (sigma 8 of 255), rolled 10 degrees about the centre (the
horizon's tilt should change by 10 degrees, f not at all) and with barrel distortion (the
division model with λ = -0.1 on coordinates over half the diagonal: corners 11 % inwards;
f at the centre unchanged; lines bent)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python -m benchmarks.check_vp_real --photos DIR

``--principal-point estimate`` runs the photographs with ``principal_point="estimate"``.

``--photos-only`` leaves the checkerboard views out. No photograph is in the repository:
the results file names where they came from.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "data" / "opencv-left"
F_TRUE = 536.07345314
K = np.array([[F_TRUE, 0.0, 342.37046827], [0.0, 536.01636274, 235.53687064], [0.0, 0.0, 1.0]])
D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
MODES = {
    "centre": "center",
    "orthocentre": "orthocenter",
    "estimate": "estimate",
    "calibrated": K[:2, 2],
}


def measure() -> tuple[list[tuple[object, ...]], dict[str, list[float]]]:
    from PIL import Image

    from imageform.geometry import detect_vanishing_points, undistort_image
    from imageform.geometry.distortion import BrownConrady

    rows: list[tuple[object, ...]] = []
    errors: dict[str, list[float]] = {m: [] for m in MODES}
    for path in sorted(DATA.glob("left*.jpg")):
        img = np.asarray(Image.open(path).convert("L"))
        und = undistort_image(img, K, BrownConrady.from_opencv(D), keep_dtype=True)
        cells: list[object] = [path.name]
        for mode, pp in MODES.items():
            res = detect_vanishing_points(und, principal_point=pp)
            if res.K is None:
                cells += ["-", "-"]
                errors[mode].append(math.inf)
                continue
            f = float(res.K[0, 0])
            err = 100.0 * (f / F_TRUE - 1.0)
            errors[mode].append(abs(err))
            cells += [f"{f:.1f}", f"{err:+.1f} %"]
        rows.append(tuple(cells))
    return rows, errors


def summary(errors: dict[str, list[float]]) -> list[tuple[object, ...]]:
    out: list[tuple[object, ...]] = []
    for mode, errs in errors.items():
        e = np.array(errs)
        found = np.isfinite(e)
        out.append(
            (
                mode,
                f"{int(found.sum())} / {len(e)}",
                f"{np.median(e):.1f} %",  # a view without K counts as an infinite error
                f"{int((e <= 3).sum())}",
                f"{int((e <= 10).sum())}",
            )
        )
    return out


def _variants(rgb: np.ndarray) -> dict[str, tuple[np.ndarray, float, float]]:
    """The photograph and its versions: ``name -> (image, scale, roll in degrees)``."""
    from PIL import Image

    base = Image.fromarray(rgb)
    out = {"original": (rgb, 1.0, 0.0)}
    half = base.resize((base.width // 2, base.height // 2), Image.Resampling.LANCZOS)
    out["half size"] = (np.asarray(half), base.width // 2 / base.width, 0.0)
    buf = io.BytesIO()
    base.save(buf, "JPEG", quality=30)
    out["JPEG q30"] = (np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("RGB")), 1.0, 0.0)
    noise = np.random.default_rng(1).normal(0.0, 8.0, rgb.shape)
    out["noise 8"] = (np.clip(rgb + noise, 0, 255).astype(np.uint8), 1.0, 0.0)
    rolled = base.rotate(10.0, resample=Image.Resampling.BICUBIC)  # counter-clockwise
    out["rolled 10"] = (np.asarray(rolled), 1.0, 10.0)
    out["barrel 0.1"] = (_barrel(rgb, -0.1), 1.0, 0.0)
    return out


def _barrel(rgb: np.ndarray, lam: float) -> np.ndarray:
    """The photograph as a lens with barrel distortion would show it (division model).

    A pixel ``x_d`` of the result shows the photograph at ``c + (x_d - c) / (1 + λ r²)``,
    ``r = |x_d - c|`` over half the diagonal (Fitzgibbon 2001): λ = -0.1 moves the corners
    11 % of the half diagonal inwards, the centre not at all (f there is unchanged).
    """
    from scipy import ndimage

    h, w = rgb.shape[:2]
    c = np.array([(h - 1) / 2, (w - 1) / 2])
    big = math.hypot(*c)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    scale = 1.0 + lam * (((yy - c[0]) / big) ** 2 + ((xx - c[1]) / big) ** 2)
    src = [(yy - c[0]) / scale + c[0], (xx - c[1]) / scale + c[1]]
    chans = [
        ndimage.map_coordinates(rgb[..., k].astype(np.float64), src, order=1) for k in range(3)
    ]
    return np.clip(np.round(np.stack(chans, axis=-1)), 0, 255).astype(np.uint8)


def _describe(res: object, w: int, h: int, scale: float) -> tuple[str, str, float, float]:
    """``(points, f, tilt in degrees, horizon row at the centre)`` of a result."""
    diag = math.hypot(w, h)
    pts = []
    for v in res.vanishing_points:  # type: ignore[attr-defined]
        far = v[2] == 0 or math.hypot(v[0] / v[2] - w / 2, v[1] / v[2] - h / 2) > 20 * diag
        pts.append("inf" if far else f"({v[0] / v[2] / scale:.0f}, {v[1] / v[2] / scale:.0f})")
    K = res.K  # type: ignore[attr-defined]
    f = f"{K[0, 0] / scale:.0f}" if K is not None else "-"
    tilt = row = math.nan
    hz = res.horizon  # type: ignore[attr-defined]
    if hz is not None and abs(hz[1]) > 1e-9:
        tilt = math.degrees(math.atan2(-hz[0], hz[1]))
        row = -(hz[0] * (w - 1) / 2 + hz[2]) / hz[1] / scale
    return ", ".join(pts) or "-", f, tilt, row


def photos(
    folder: Path, principal_point: str = "center"
) -> tuple[list[tuple[object, ...]], list[tuple[object, ...]], list[tuple[object, ...]]]:
    """The per-photograph table and the versions table for the photographs in ``folder``."""
    from imageform.geometry import detect_vanishing_points
    from imageform.io import read_image

    truth: dict[str, float] = {}
    horizons: dict[str, tuple[float, float]] = {}
    if (folder / "truth.csv").is_file():
        with open(folder / "truth.csv", newline="") as fh:
            for r in csv.DictReader(fh):
                if r.get("f_px"):
                    truth[r["file"]] = float(r["f_px"])
                if r.get("horizon_left") and r.get("horizon_right"):
                    horizons[r["file"]] = (float(r["horizon_left"]), float(r["horizon_right"]))
    rows: list[tuple[object, ...]] = []
    versions: list[tuple[object, ...]] = []
    stats: list[dict[str, Any]] = []
    paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".jpeg", ".png"))
    for path in paths:
        img = np.asarray(read_image(path))
        rgb = img[..., :3] if img.ndim == 3 else np.repeat(img[..., None], 3, axis=-1)
        if rgb.dtype != np.uint8:
            rgb = np.clip(np.round(np.asarray(rgb, dtype=np.float64) * 255), 0, 255)
            rgb = rgb.astype(np.uint8)
        h, w = rgb.shape[:2]
        base: tuple[str, float, float] | None = None
        for name, (arr, scale, roll) in _variants(rgb).items():
            t0 = time.perf_counter()
            res = detect_vanishing_points(arr, principal_point=principal_point)
            dt = time.perf_counter() - t0
            pts, f, tilt, row = _describe(res, arr.shape[1], arr.shape[0], scale)
            if name == "original":
                base = (f, tilt, row)
                ft = truth.get(path.name)
                err = f"{100 * (float(f) / ft - 1):+.1f} %" if ft and f != "-" else "-"
                herr = _horizon_error(res.horizon, horizons.get(path.name), w, h)
                stats.append(
                    {
                        "f_truth": ft,
                        "f_err": abs(float(f) / ft - 1) * 100 if ft and f != "-" else None,
                        "K": f != "-",
                        "h_truth": path.name in horizons,
                        "h_err": herr,
                        "same": 0,
                    }
                )
                # why no K, or the library's note on the K it gave
                reason = getattr(res, "K_reason", None) or getattr(res, "K_note", None)
                rows.append(
                    (
                        path.name,
                        f"{w} x {h}",
                        f"{dt:.2f}",
                        len(res.segments),
                        pts,
                        f,
                        f"{ft:.0f}" if ft else "-",
                        err,
                        "-" if math.isnan(tilt) else f"{tilt:+.1f}",
                        "-" if math.isnan(row) else f"{row:.0f}",
                        "-" if herr is None else f"{herr:.2f} %",
                        reason or "-",
                    )
                )
                continue
            assert base is not None
            same_f = (
                f"{100 * (float(f) / float(base[0]) - 1):+.1f} %"
                if f != "-" and base[0] != "-"
                else ("both -" if f == base[0] else f"{base[0]} -> {f}")
            )
            dtilt = tilt - base[1] + roll  # a counter-clockwise roll turns it clockwise
            stats[-1]["same"] += int(
                (f == "-" and base[0] == "-")
                or (f != "-" and base[0] != "-" and abs(float(f) / float(base[0]) - 1) <= 0.05)
            )
            versions.append(
                (
                    path.name,
                    name,
                    f"{dt:.2f}",
                    same_f,
                    "-" if math.isnan(dtilt) else f"{dtilt:+.1f}",
                    "-" if math.isnan(row - base[2]) or roll else f"{row - base[2]:+.0f}",
                )
            )
    return rows, versions, _photo_summary(stats)


def _horizon_error(
    line: np.ndarray | None, truth: tuple[float, float] | None, w: int, h: int
) -> float | None:
    """The horizon's error as York Urban scores it: the larger distance from the true one
    at the image's left and right edges, over the height (per cent); inf if none found."""
    if truth is None:
        return None
    if line is None or abs(float(line[1])) < 1e-9:
        return math.inf
    a, b, c = (float(x) for x in line)
    rows = (-c / b, -(a * (w - 1) + c) / b)
    return 100.0 * max(abs(rows[0] - truth[0]), abs(rows[1] - truth[1])) / h


def _photo_summary(stats: list[dict[str, Any]]) -> list[tuple[object, ...]]:
    """One row per kind of truth: how many got K, its error, the horizon's, the versions."""
    out: list[tuple[object, ...]] = []
    with_f = [s for s in stats if s["f_truth"]]
    if with_f:
        e = np.array([s["f_err"] if s["f_err"] is not None else math.inf for s in with_f])
        found = np.isfinite(e)
        out.append(
            (
                "focal length (EXIF or calibration)",
                len(with_f),
                f"{int(found.sum())}",
                f"{np.median(e[found]):.1f} %" if found.any() else "-",
                f"{int((e <= 5).sum())}",
                f"{int((found & (e > 20)).sum())}",
            )
        )
    no_f = [s for s in stats if not s["f_truth"]]
    if no_f:
        out.append(
            (
                "photographs without a known focal length",
                len(no_f),
                str(sum(bool(s["K"]) for s in no_f)),
                "-",
                "-",
                "-",
            )
        )
    with_h = [s for s in stats if s["h_truth"]]
    if with_h:
        e = np.array([float(s["h_err"]) for s in with_h])
        found = np.isfinite(e)
        out.append(
            (
                "horizon (annotated)",
                len(with_h),
                f"{int(found.sum())}",
                f"{np.median(e):.2f} % of H (none: inf)",
                f"{int((e <= 2).sum())} within 2 % of H",
                f"{int((found & (e > 10)).sum())} off by > 10 % of H",
            )
        )
    out.append(
        (
            "versions giving the original's answer (f within 5 % or both without K)",
            5 * len(stats),
            str(sum(int(s["same"]) for s in stats)),
            "-",
            "-",
            "-",
        )
    )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--photos", type=Path, help="a folder of photographs to add")
    parser.add_argument(
        "--photos-only", action="store_true", help="leave out OpenCV's checkerboard views"
    )
    parser.add_argument(
        "--principal-point",
        choices=("center", "estimate"),
        default="center",
        help="detect_vanishing_points' principal_point for the photographs (default: the "
        "image centre)",
    )
    args = parser.parse_args()
    if args.photos is not None:
        rows, versions, summ = photos(args.photos, args.principal_point)
        print(header("Vanishing points, focal length and horizon: photographs"))
        print(f"Folder: `{args.photos.name}`, principal point: {args.principal_point}\n")
        print(
            markdown_table(
                ("truth", "photographs", "K (or horizon) found", "median error", "good", "wrong"),
                summ,
            )
        )
        print(
            markdown_table(
                (
                    "photograph",
                    "size",
                    "s",
                    "segments",
                    "points",
                    "f px",
                    "f truth",
                    "f error",
                    "horizon tilt deg",
                    "horizon row at centre",
                    "horizon error",
                    "why no K (or the note on K)",
                ),
                rows,
            )
        )
        print("## Versions (against the original)\n")
        print(
            markdown_table(
                (
                    "photograph",
                    "version",
                    "s",
                    "f change",
                    "tilt change - roll, deg",
                    "row change px",
                ),
                versions,
            )
        )
        print(
            "Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python -m benchmarks.check_vp_real "
            "--photos DIR`\n"
        )
    if args.photos_only:
        return
    rows, errors = measure()
    print(header("Focal length from vanishing points: OpenCV's checkerboard photographs"))
    print("## Per view (f in px; truth 536.07 px)\n")
    cols = ["view"]
    for mode in MODES:
        cols += [f"f ({mode})", f"error ({mode})"]
    print(markdown_table(tuple(cols), rows))
    print("## Summary\n")
    print(
        markdown_table(
            ("principal point", "K found", "median |f error|", "within 3 %", "within 10 %"),
            summary(errors),
        )
    )
    print("Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_vp_real.py`")


if __name__ == "__main__":
    main()
