"""How often ``found`` is wrong: the data set of ``check_plumb_line.py --reliability``.

Cases, each with a true division coefficient (coordinates over the centre-to-corner
distance ``s``, as ``estimate_distortion_from_lines`` reports it):

- the rendered board and the 24 Kodak photographs (``../shared/data/kodak``), warped without
  black corners by corner displacements of 0, 5, 10 and 20 % barrel and 10 % pincushion;
- ``--photos DIR``: the photographs of a folder, warped by 0, 5, 10 and 20 % barrel (their
  own lens may add a little: the tolerance's 0.02);
- OpenCV's ``left*.jpg`` (``../shared/data/opencv-left``): real barrel distortion, the truth
  the published calibration (``../shared/data/README.md``: the OpenCV tutorial's f, c and
  k1, k2, p1, p2, k3) turned into the division model: the ``k`` whose undistortion matches
  the calibration's over the image after the best scale and shift, for the image centre or
  the principal point as distortion centre and over the whole image or within half its height
  of the principal point; the truth is the range of those four fits;
- ``--calibrated DIR``: Jackson-coder/calibrate's 20 frames (1280 x 960, a wide-angle lens)
  with the repository's own OpenCV calibration (``out_camera_data.yml``), fitted within half
  the image height only (the board never reached the corners).

An estimate is right when ``|k - k_true| <= 0.2 |k_true| + 0.02`` (distance to the range for
the real cases); ``found`` True on a wrong estimate is a false positive. The cases are split
into a tune half (odd Kodak numbers, odd views and frames, every other photograph of the
folder by name, the board) and a held-out half; the thresholds of ``found`` were chosen on
the tune half.
"""

from __future__ import annotations

import math
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT / ".." / "shared" / "data"
OPENCV_LEFT = {
    "size": (640, 480),
    "f": (536.07345314, 536.01636274),
    "c": (342.37046827, 235.53687064),
    "d": (-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221),
}
#: Jackson-coder/calibrate @ d3c6e4e, out_camera_data.yml (OpenCV, 11 x 8 board)
JACKSON = {
    "size": (1280, 960),
    "f": (712.39787607124015, 712.60663801079568),
    "c": (652.66087456356286, 449.94610712387629),
    "d": (-0.39450402568099502, 0.16048105420872713, 1.2582245751145658e-04, -9.13873e-04, 0.0),
}
WARPS = {"none": 0.0, "barrel 5 %": 0.05, "barrel 10 %": 0.10, "barrel 20 %": 0.20}
WARPS_PIN = {"pincushion 10 %": -0.10}


def division_truth(cal: dict[str, Any], whole: bool = True) -> tuple[float, float]:
    """The range of division ``k`` fitted to a Brown-Conrady calibration (see the module)."""
    from imageform.geometry.distortion import BrownConrady

    w, h = cal["size"]
    f, c = np.asarray(cal["f"]), np.asarray(cal["c"])
    v, u = np.mgrid[0:h:4, 0:w:4].astype(np.float64)
    uv = np.stack((u.ravel(), v.ravel()), axis=-1)
    k1, k2, p1, p2, k3 = cal["d"]
    xu, ok = BrownConrady(k1=k1, k2=k2, p1=p1, p2=p2, k3=k3).undistort((uv - c) / f)
    ref = np.asarray(xu) * f + c
    good = np.asarray(ok) & np.isfinite(ref).all(1)
    s = math.hypot((w - 1) / 2, (h - 1) / 2)
    fits = []
    for radius in (None, h / 2) if whole else (h / 2,):
        for centre in (np.array([(w - 1) / 2, (h - 1) / 2]), c):
            m = good if radius is None else good & (np.hypot(*(uv - c).T) <= radius)
            x = (uv[m] - centre) / s
            r2 = (x * x).sum(1)
            A = np.zeros((2 * len(x), 3))
            A[0::2, 1] = A[1::2, 2] = 1.0
            best = (math.inf, 0.0)
            for k in np.arange(-0.9, 0.3, 0.0025):
                A[0::2, 0], A[1::2, 0] = (x / (1 + k * r2)[:, None]).T
                sol, *_ = np.linalg.lstsq(A, ref[m].ravel(), rcond=None)
                e = float(((A @ sol - ref[m].ravel()) ** 2).sum())
                best = min(best, (e, float(k)))
            fits.append(best[1])
    return min(fits), max(fits)


def cases(photos: Path | None, calibrated: Path | None) -> list[dict[str, Any]]:
    """The cases: name, group, half, the image's path (or 'board'), the warp, the truth."""
    from benchmarks.check_plumb_line import _k

    out: list[dict[str, Any]] = []

    def warped(name: str, group: str, half: str, path: str, pin: bool) -> None:
        for warp, p in dict(WARPS, **(WARPS_PIN if pin else {})).items():
            k = _k(p)
            out.append(
                {
                    "name": name,
                    "group": group,
                    "half": half,
                    "path": path,
                    "warp": warp,
                    "k": k,
                    "lo": k,
                    "hi": k,
                }
            )

    warped("board 640x480", "board", "tune", "board", True)
    for i in range(1, 25):
        p = SHARED / "kodak" / f"kodim{i:02d}.png"
        if p.is_file():
            warped(p.name, "Kodak", "tune" if i % 2 else "held", str(p), True)
    if photos is not None:
        files = sorted(q for q in photos.iterdir() if q.suffix.lower() in (".jpg", ".png"))
        for j, q in enumerate(files):
            warped(q.name, "photographs", "tune" if j % 2 == 0 else "held", str(q), False)
    reals = []
    left = sorted((SHARED / "opencv-left").glob("left*.jpg"))
    if left:
        reals.append((left, "opencv-left", division_truth(OPENCV_LEFT)))
    if calibrated is not None:
        reals.append((sorted(calibrated.glob("0*.jpg")), "Jackson", division_truth(JACKSON, False)))
    for files, group, (lo, hi) in reals:
        for q in files:
            num = int("".join(ch for ch in q.stem if ch.isdigit()))
            half = "tune" if num % 2 else "held"
            out.append(
                {
                    "name": q.name,
                    "group": group,
                    "half": half,
                    "path": str(q),
                    "warp": "real",
                    "k": 0.5 * (lo + hi),
                    "lo": lo,
                    "hi": hi,
                }
            )
    return out


def run_case(case: dict[str, Any]) -> dict[str, Any]:
    """Estimate on one case; the old ``found`` rule (main at 0b10ef8) from the same result."""
    from benchmarks.check_plumb_line import _k, _read, board, distort
    from imageform.geometry import estimate_distortion_from_lines

    img = board() if case["path"] == "board" else _read(Path(case["path"]))
    if case["warp"] != "real":
        img = distort(img, _k(WARPS.get(case["warp"], WARPS_PIN.get(case["warp"], 0.0))))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            res = estimate_distortion_from_lines(img)
        except ValueError:
            return dict(case, est=None, s=time.perf_counter() - t0)
    dt = time.perf_counter() - t0
    at_bound = min(res.k1 + 0.9, 0.6 - res.k1) < 0.0025
    old = (
        not at_bound
        and res.max_displacement_px >= 1.0
        and abs(res.k1) >= 3.0 * res.k1_std
        and res.residual_before_px >= 1.25 * res.residual_px
    )
    return dict(
        case,
        est=res.k1,
        interval=res.k1_interval,
        lines=len(res.lines),
        old=bool(old),
        new=bool(res.found),
        s=dt,
    )


def right(r: dict[str, Any]) -> bool:
    """Whether the estimate is within ``0.2 |k_true| + 0.02`` of the truth (its range)."""
    miss = max(r["lo"] - r["est"], 0.0, r["est"] - r["hi"])
    return bool(miss <= 0.2 * abs(r["k"]) + 0.02)


def summary(results: list[dict[str, Any]]) -> list[tuple[object, ...]]:
    """Per half and group: found and wrong before and after."""
    rows: list[tuple[object, ...]] = []
    groups = list(dict.fromkeys(r["group"] for r in results)) + ["all"]
    for half in ("tune", "held"):
        for g in groups:
            sel = [r for r in results if r["half"] == half and g in ("all", r["group"])]
            if not sel:
                continue
            cells: list[object] = [half, g, len(sel), sum(r["est"] is not None for r in sel)]
            dist = [r for r in sel if r["k"] != 0]
            for key in ("old", "new"):
                f = [r for r in sel if r["est"] is not None and r[key]]
                wrong = sum(not right(r) for r in f)
                ok = sum(right(r) for r in f if r["k"] != 0)
                rate = f"{100 * wrong / len(f):.0f} %" if f else "-"
                cells += [f"{len(f)} / {wrong} ({rate})", f"{ok} / {len(dist)}"]
            rows.append(tuple(cells))
    return rows


def detail(results: list[dict[str, Any]]) -> list[tuple[object, ...]]:
    """One row a case."""
    rows: list[tuple[object, ...]] = []
    for r in results:
        truth = f"{r['k']:.4f}" if r["lo"] == r["hi"] else f"{r['lo']:.3f} to {r['hi']:.3f}"
        if r["est"] is None:
            rows.append(
                (r["name"], r["half"], r["warp"], truth, "too few lines", "-", "-", "-", "-")
            )
            continue
        lo, hi = r["interval"]
        rows.append(
            (
                r["name"],
                r["half"],
                r["warp"],
                truth,
                f"{r['est']:.4f}",
                f"{lo:.3f} to {hi:.3f}",
                "yes" if right(r) else "**no**",
                ("yes" if r["old"] else "none") + " / " + ("yes" if r["new"] else "none"),
                f"{r['s']:.1f}",
            )
        )
    return rows
