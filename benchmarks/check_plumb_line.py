"""Lens distortion from one photograph's straight lines (plumb lines) against known distortion.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python -m benchmarks.check_plumb_line

``estimate_distortion_from_lines`` on images whose distortion is known:

1. Synthetic: Kodak photographs with straight edges (``../shared/data/kodak``) and a rendered
   checkerboard (4 x 4 samples a pixel), warped with the division model (coordinates over the
   centre-to-corner distance) so that the corner moves by 5, 10 and 20 % (barrel, k = -0.048,
   -0.091, -0.167) and by -10 % (pincushion, k = 0.111), and unwarped (expected: no
   distortion found). The k found, its error, whether distortion was reported, the time.
   The warp is scaled so that every pixel shows the photograph (``distort``); the same
   with black corners (the warped frame's border, a perfect plumb line, in view) is shown
   apart. A photograph's own lens may already bend it: the error is also given for the
   change of k from the unwarped photograph's estimate (to first order the added k).
2. ``--photos DIR``: the same on the photographs of a folder, and the focal length from
   vanishing points on 11 %-barrel copies (λ = -0.1): ``benchmarks/check_vp_real.py``'s
   (black corners) and one without black corners (magnified 1/0.9 at the centre: its f is
   shown times 0.9), without and with the correction (what ``imageform vanishing
   --distortion`` does), against the undistorted photograph's f (``DIR/truth.csv``, column
   ``f_px``, gives the EXIF one).
3. ``--calibrated DIR --camera FILE``: a real wide-angle camera calibrated with a board
   (``imageform calibrate``): each frame's estimate against the camera file's distortion, as
   pixel displacements over the image: the undistortion of every 8th pixel by the
   estimate and by the calibration, the estimate's mapped onto the calibration's by the best
   scale and shift (a plumb-line estimate fixes straightness, not the focal length), the
   largest and the RMS difference: over the pixels where both models are defined, and,
   aligned there, within half the image height of the centre (where a board calibration
   has its points).
4. ``--reliability`` (with ``--photos DIR`` and ``--calibrated DIR``): how often ``found`` is
   True on a wrong estimate, before (the rule of main at 0b10ef8, recomputed from the same
   result: displacement >= 1 px, ``|k1| >= 3 k1_std``, straightness gain >= 1.25, not at the
   range's end) and after (the branch's ``found``), on a tune and a held-out half; the data
   set and the meaning of "right" are in ``benchmarks/_plumb_reliability.py``.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT / ".." / "shared" / "data" / "kodak"
KODAK_LINES = ("kodim01.png", "kodim08.png", "kodim16.png", "kodim22.png", "kodim24.png")
#: corner displacement (r_u / r_d - 1) -> k = 1 / (1 + p) - 1
CASES = {"none": 0.0, "barrel 5 %": 0.05, "barrel 10 %": 0.10, "barrel 20 %": 0.20}
CASES_PIN = {"pincushion 10 %": -0.10}


def _k(p: float) -> float:
    return 1.0 / (1.0 + p) - 1.0


def distort(img: np.ndarray, k: float, border: bool = False) -> np.ndarray:
    """The image as a lens with division distortion ``k`` would show it (same size).

    Without ``border``, barrel distortion is scaled so that the corners show the image's
    corners: every pixel shows the photograph (no black corners, whose curved edge, the
    image's own border bent by the lens, would be a perfect plumb line no real lens shows).
    """
    from imageform.geometry import DivisionModel, remap_bilinear

    if k == 0:
        return img
    h, w = img.shape[:2]
    c = np.array([(w - 1) / 2, (h - 1) / 2])
    s = math.hypot(*c)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    x = np.stack(((u - c[0]) / s, (v - c[1]) / s), axis=-1)
    xu, _ = DivisionModel(k1=k).undistort(x)
    scale = s if border else s * min(1.0, 1.0 + k)
    return np.asarray(remap_bilinear(img, np.asarray(xu) * scale + c, keep_dtype=True))


def board(w: int = 640, h: int = 480, square: int = 40) -> np.ndarray:
    """A rendered checkerboard filling the frame, 4 x 4 samples a pixel, uint8."""
    v, u = (np.mgrid[0 : 4 * h, 0 : 4 * w] + 0.5) / 4 - 0.5
    b = ((u // square + v // square) % 2).reshape(h, 4, w, 4).mean(axis=(1, 3))
    return np.round(40 + 160 * b).astype(np.uint8)


def _read(path: Path) -> np.ndarray:
    """An image file as uint8 grey or RGB."""
    from imageform.io import read_image

    img = np.asarray(read_image(path))
    if img.dtype != np.uint8:
        img = np.clip(np.round(np.asarray(img, dtype=np.float64) * 255), 0, 255).astype(np.uint8)
    return img[..., 0] if img.shape[-1] == 1 else img[..., :3]


def _estimate(img: np.ndarray, **kwargs: Any) -> tuple[Any, float]:
    from imageform.geometry import estimate_distortion_from_lines

    t0 = time.perf_counter()
    try:
        res = estimate_distortion_from_lines(img, **kwargs)
    except ValueError as exc:  # too few lines
        return str(exc), time.perf_counter() - t0
    return res, time.perf_counter() - t0


def synthetic(
    images: dict[str, np.ndarray], pincushion: bool = True, border: bool = False
) -> list[tuple[object, ...]]:
    rows: list[tuple[object, ...]] = []
    cases = dict(CASES, **(CASES_PIN if pincushion else {}))
    for name, img in images.items():
        k_none = math.nan  # what the photograph shows unwarped (its own lens)
        for case, p in cases.items():
            k = _k(p)
            if border and k >= 0:
                continue
            res, dt = _estimate(distort(img, k, border))
            if isinstance(res, str):
                rows.append(
                    (name, case, f"{k:.4f}", "-", "-", "-", "error: " + res[:60], f"{dt:.1f}")
                )
                continue
            if k == 0:
                k_none = res.k1
            err = f"{100 * (res.k1 / k - 1):+.1f} %" if k else f"{res.k1:+.4f} (abs)"
            step = res.k1 - (0.0 if border or math.isnan(k_none) else k_none)
            err2 = f"{100 * (step / k - 1):+.1f} %" if k and not border else "-"
            rows.append(
                (
                    name,
                    case,
                    f"{k:.4f}",
                    f"{res.k1:.4f} ± {res.k1_std:.4f}",
                    err,
                    err2,
                    "yes" if res.found else "none",
                    f"{dt:.1f}",
                )
            )
    return rows


def _f(img: np.ndarray) -> float:
    from imageform.geometry import detect_vanishing_points

    K = detect_vanishing_points(img).K
    return math.nan if K is None else float(K[0, 0])


def _corrected(img: np.ndarray) -> np.ndarray:
    from imageform.geometry import estimate_distortion_from_lines, undistort_image

    est = estimate_distortion_from_lines(img)
    if not est.found:
        return img
    return np.asarray(undistort_image(img, est.K, est.distortion, keep_dtype=True))


def vanishing(folder: Path) -> list[tuple[object, ...]]:
    from benchmarks.check_vp_real import _barrel

    truth: dict[str, float] = {}
    if (folder / "truth.csv").is_file():
        with open(folder / "truth.csv", newline="") as fh:
            truth = {r["file"]: float(r["f_px"]) for r in csv.DictReader(fh) if r.get("f_px")}
    rows: list[tuple[object, ...]] = []
    for path in sorted(p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".png")):
        rgb = _read(path)
        rgb = rgb if rgb.ndim == 3 else np.repeat(rgb[..., None], 3, axis=-1)
        f0 = _f(rgb)
        bent = _barrel(rgb, -0.1)  # check_vp_real's copy: black corners
        f1 = _f(bent)
        f2 = _f(_corrected(bent))
        clean = distort(rgb, -0.1)  # no black corners, magnified 1 / 0.9 at the centre
        f3 = _f(clean) * 0.9
        f4 = _f(_corrected(clean)) * 0.9
        ft = truth.get(path.name)

        def cell(f: float, ref: float | None = f0) -> str:
            if not math.isfinite(f):
                return "-"
            if ref is None or not math.isfinite(ref):
                return f"{f:.0f}"
            return f"{f:.0f} ({100 * (f / ref - 1):+.1f} %)"

        rows.append(
            (
                path.name,
                f"{f0:.0f}" if math.isfinite(f0) else "-",
                f"{ft:.0f}" if ft else "-",
                cell(f1),
                cell(f2),
                cell(f3),
                cell(f4),
            )
        )
    return rows


def _undistorted_px(cam: Any, uv: np.ndarray) -> np.ndarray:
    """Undistorted pixel positions of distorted pixels ``uv`` (the camera's own K)."""
    K = np.asarray(cam.K, dtype=np.float64)
    x = (uv - K[:2, 2]) / np.diag(K)[:2]
    xu, ok = cam.distortion.undistort(x)
    out = np.asarray(xu) * np.diag(K)[:2] + K[:2, 2]
    out[~np.asarray(ok)] = np.nan
    return out


def _aligned_difference(est: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``|a est + b - ref|`` over ``mask`` with the least-squares scale ``a`` and shift ``b``."""
    A = np.zeros((2 * mask.sum(), 3))
    A[0::2, 0], A[1::2, 0] = est[mask, 0], est[mask, 1]
    A[0::2, 1] = 1.0
    A[1::2, 2] = 1.0
    sol = np.linalg.lstsq(A, ref[mask].ravel(), rcond=None)[0]
    return np.hypot(*(est[mask] * sol[0] + sol[1:] - ref[mask]).T)


def compare(folder: Path, camera: Path) -> list[tuple[object, ...]]:
    from imageform.geometry import Camera
    from imageform.io import read_camera

    cal = read_camera(camera).camera
    assert cal.image_size is not None, "the camera file needs [image]"
    w, h = cal.image_size
    v, u = np.mgrid[0:h:8, 0:w:8].astype(np.float64)
    uv = np.stack((u.ravel(), v.ravel()), axis=-1)
    ref = _undistorted_px(cal, uv)
    ref_disp = np.hypot(*(ref - uv).T)
    print(
        f"The calibration: principal point ({cal.K[0, 2]:.1f}, {cal.K[1, 2]:.1f}), the largest "
        f"pixel shift where its undistortion exists {np.nanmax(ref_disp):.1f} px "
        f"({np.isfinite(ref).all(1).mean():.0%} of the pixels).\n"
    )
    rows: list[tuple[object, ...]] = []
    for path in sorted(folder.glob("*.jpg")):
        img = _read(path)
        if img.shape[1] != w or img.shape[0] != h:
            continue
        for centre in ("image centre", "estimated"):
            res, dt = _estimate(img, estimate_center=centre == "estimated")
            if isinstance(res, str):
                rows.append((path.name, centre, "-", "-", "-", "-", "error: " + res[:60], "-"))
                continue
            est = _undistorted_px(Camera(res.K, distortion=res.distortion), uv)
            ok = np.isfinite(est).all(1) & np.isfinite(ref).all(1)
            inner = ok & (np.hypot(*(uv - [(w - 1) / 2, (h - 1) / 2]).T) <= h / 2)
            whole = _aligned_difference(est, ref, ok)
            mid = _aligned_difference(est, ref, inner)
            rows.append(
                (
                    path.name,
                    f"{centre} ({res.center[0]:.0f}, {res.center[1]:.0f})",
                    f"{res.k1:.4f} ± {res.k1_std:.4f}",
                    len(res.lines),
                    f"{res.max_displacement_px:.1f}",
                    f"{whole.max():.1f} / {np.sqrt((whole**2).mean()):.1f}",
                    f"{mid.max():.1f} / {np.sqrt((mid**2).mean()):.1f}",
                    f"{dt:.1f}",
                )
            )
    return rows


def reliability(photos: Path | None, calibrated: Path | None, jobs: int) -> None:
    """Print the tables of ``--reliability``."""
    from concurrent.futures import ProcessPoolExecutor

    from benchmarks import _plumb_reliability as rel

    todo = rel.cases(photos, calibrated)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(rel.run_case, todo))
    print("## found: before and after, on the tune and the held-out halves\n")
    print(
        "Each cell 'found / wrong (rate)': the cases reported as distorted and, of them, those "
        "whose k is wrong (the false-positive rate of found); 'right found': the distorted "
        "cases reported with a right k, of all distorted cases.\n"
    )
    print(
        markdown_table(
            (
                "half",
                "set",
                "cases",
                "estimated",
                "before: found / wrong",
                "before: right found",
                "after: found / wrong",
                "after: right found",
            ),
            rel.summary(results),
        )
    )
    print("## Every case\n")
    print(
        markdown_table(
            (
                "image",
                "half",
                "distortion",
                "k true",
                "k found",
                "chain bootstrap 90 %",
                "right",
                "found before / after",
                "s",
            ),
            rel.detail(results),
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--photos", type=Path, help="a folder of photographs (and truth.csv)")
    parser.add_argument("--calibrated", type=Path, help="frames of a calibrated camera")
    parser.add_argument("--camera", type=Path, help="the camera file of --calibrated")
    parser.add_argument("--skip-synthetic", action="store_true")
    parser.add_argument("--skip-vanishing", action="store_true", help="with --photos")
    parser.add_argument("--reliability", action="store_true", help="only the found/wrong tables")
    parser.add_argument("--jobs", type=int, default=1, help="processes for --reliability")
    args = parser.parse_args()
    print(header("Lens distortion from straight lines (plumb lines)"))
    if args.reliability:
        reliability(args.photos, args.calibrated, args.jobs)
        return
    cols = (
        "image",
        "distortion",
        "k true",
        "k found ± std",
        "error",
        "error of k found - k found unwarped",
        "reported",
        "s",
    )
    if not args.skip_synthetic:
        images = {"board 640x480": board()}
        for name in KODAK_LINES:
            if (KODAK / name).is_file():
                images[name] = _read(KODAK / name)
        print("## Synthetic distortion: Kodak photographs and a rendered board\n")
        print(markdown_table(cols, synthetic(images)))
        print("## The same with black corners (the warped image's own border in view)\n")
        print(markdown_table(cols, synthetic(images, border=True)))
    if args.photos is not None:
        photos = {
            p.name: _read(p)
            for p in sorted(args.photos.iterdir())
            if p.suffix.lower() in (".jpg", ".png")
        }
        print(f"## Synthetic distortion: the photographs of {args.photos.name}\n")
        print(markdown_table(cols, synthetic(photos, pincushion=False)))
    if args.photos is not None and not args.skip_vanishing:
        print("## Focal length from vanishing points on the 11 %-barrel copies\n")
        print(
            markdown_table(
                (
                    "photograph",
                    "f original",
                    "f EXIF",
                    "black corners: f barrel (vs original)",
                    "corrected",
                    "no black corners: f barrel x 0.9",
                    "corrected x 0.9",
                ),
                vanishing(args.photos),
            )
        )
    if args.calibrated is not None and args.camera is not None:
        print(f"## One frame against the calibration of {args.camera.name}\n")
        print(
            markdown_table(
                (
                    "frame",
                    "centre",
                    "k found ± std",
                    "lines",
                    "estimate's corner shift px",
                    "difference max / RMS px (where both exist)",
                    "within h/2 of the centre (aligned there)",
                    "s",
                ),
                compare(args.calibrated, args.camera),
            )
        )


if __name__ == "__main__":
    main()
