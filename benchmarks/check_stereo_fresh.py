"""The stereo chain on real data beyond Middlebury, against OpenCV, split tuning / held out.

The chain: ``find_checkerboard`` on both views of real board pairs, ``stereo_calibrate``
(against ``cv2.stereoCalibrate`` on the very same corners), ``stereo_rectify`` and
``rectification_map`` (the rectification error of the board corners), ``stereo_disparity``
(against ``cv2.StereoSGBM`` in ``MODE_HH`` at matched settings, on the same rectified
images) scored against the board plane, and ``imageform stereo-calibrate`` (the CLI) on the
same folders.

Data (third-party, none of it in this repository: no set states a licence; put each set's
files in a folder of its name under the folder given on the command line, ``git show
COMMIT:PATH`` in a clone of the repository gives them; the script checks every folder
against the SHA-256 digest below, the digest of ``sha256sum`` of its files in byte order):

- ``davinci`` (tuning): github.com/nsujumnong/VisionPipelineSample, commit d659f20,
  ``Endoscope_Snapshot/small_chess/`` (the 40 ``leftNN.png`` / ``rightNN.png`` pairs,
  640 x 480; the folder's 13 ``.jpg`` copies are not read): both channels of a da Vinci
  surgical stereo endoscope (WPI AIM Lab), a board of 7 x 7 inner corners, dim, in a
  dark surround. Square size not stated: ``T`` in squares. Digest 8800343b...
- ``urban`` (tuning): github.com/ezhangle/LIBELAS (a copy of Geiger's libELAS), commit
  06c0505, ``img/urban{1,2,3,4}_{left,right}.pgm``: four rectified grey pairs of a car's
  stereo rig in streets (Karlsruhe, the sequences before KITTI), 1344 x 391 px, no truth:
  density, left-right consistency, agreement with OpenCV, time. Digest cc6d80f7...
- ``webcam-1``, ``webcam-2`` (held out): github.com/sourishg/stereo-calibration, commit
  2578889, ``calib_imgs/1/`` (29 pairs, 640 x 360) and ``calib_imgs/2/`` (28 pairs,
  270 x 180): two webcams side by side, a 9 x 6 board of 24.23 mm squares (the README's
  ``-s 0.02423``). Digests 0a246784..., 6b6ec167...
- ``ximea`` (held out): github.com/Barry-Liang/stereoCalibrate, commit 1c3c1ad,
  ``left01-25.jpg`` / ``right01-25.jpg`` (640 x 512): a XIMEA stereo pair, a 9 x 6 board,
  square size not stated (its ``extrinsics.yml`` gives a baseline of 92.1 units: ``T`` here
  in squares). Digest 2c4f9d11...

The split is by repository, fixed before anything was run on it (tuning: the endoscope and
the street pairs; held out: the two other repositories), and the held-out digests were
frozen with it. The board sizes of all sets were probed once before (``find_checkerboard``
``"auto"`` on 3 left and 2 right views of each): nothing else of the held-out sets was looked
at before the final code. Run ``--half tuning`` while tuning, ``--half held-out`` once at
the end.

What is measured, per board set:

- **Calibration** on the pairs whose board both views show, corners from imageform's
  ``find_checkerboard`` (the ``symmetric`` refinement), both libraries on the same corners:
  imageform ``stereo_calibrate`` (each camera alone, then a joint Levenberg-Marquardt over
  both cameras, ``R``, ``T``) against ``cv2.calibrateCamera`` on each side then
  ``cv2.stereoCalibrate(..., CALIB_USE_INTRINSIC_GUESS)`` (the same joint refinement):
  the RMS (both libraries' definition: ``sqrt(Σ e² / 2N)`` over both cameras), the baseline
  ``‖T‖``, the angle between the two ``R``, the focal lengths. The CLI ``imageform
  stereo-calibrate`` on the set's files: pairs used, RMS, baseline (it should equal the
  function's), and ``imageform depth --disparity`` with that rig file on the first pair.
- **Rectification**: each library's calibration rectified by its own ``stereoRectify``
  (alpha -1, zero disparity), the board corners of every pair taken through it
  (``cv2.undistortPoints`` iterated to 1e-10, the same Brown-Conrady model in both): the
  RMS and the largest ``|y_left - y_right|`` (px), the error a matcher along rows meets.
- **Matching** on every used pair, rectified with imageform's maps (``rectification_map``,
  ``remap_bilinear``), the same images to both matchers: imageform ``stereo_disparity``
  (its defaults, block 5: the graded census, ``census_step=4``), with ``census_step=None``
  (the plain census, the default before 2026-11-30), with ``median_filter=True`` (OpenCV's
  compute always applies that 3 x 3 median) and with ``census_threshold=4`` (``THRESHOLD``:
  the value chosen on the tuning half's endoscope pairs, where thresholds 0, 1, 2, 3, 4, 6
  were tried, with the plain census; here with the default ``census_step``) against
  ``cv2.StereoSGBM_create`` (``MODE_HH``, block 5, ``P1 = 8·25``, ``P2 = 32·25``,
  ``uniquenessRatio = 10``, ``disp12MaxDiff = 1``, no speckle filter) over
  the same disparity range (from the truth of all pairs, rounded out to 16). The truth: the
  board is a plane, so its disparity is affine in the rectified left pixel; the plane
  ``d = a u + b v + c`` is fitted to the rectified corners' disparities ``u_l - u_r``
  (its RMS residual printed), scored inside the quadrilateral of the outer inner corners
  shrunk by 10 % (off the board's edge): density, share more than 1 and 3 px off, MAE,
  median signed error.
- **Left-right consistency** (every set): the share of valid left pixels whose partner
  ``x - d`` in the right view's own map (the pair mirrored) has a disparity within 1 px;
  agreement: the share of pixels valid in both libraries' maps within 1 px of each other.
- **Time**: the matching alone, one thread each, the process's CPU time, the median of
  interleaved runs, as a ratio (the machine is shared; its load is printed).

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_fresh.py /tmp/stereofresh --half tuning

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. \\
        python benchmarks/check_stereo_fresh.py /tmp/stereofresh --half all \\
        --acv /tmp/acv-testdata --out benchmarks/results/stereo-fresh-2026-11-30f.md

(``stereo-fresh-2026-11-30e.md``, the plain census as the default, came from the same command;
``stereo-fresh-2026-11-30g.md`` with ``cost_window=3``, the costs summed over 3 x 3 pixels, as
the default.)

``--acv`` (r09921135/acv's ``hw4/testdata/``, see ``check_stereo_depth.py``) adds the
Middlebury tsukuba analysis: where imageform's > 1 px errors lie against OpenCV's, and the
census thresholds 1, 2 and 4 there.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from imageform.geometry import (  # noqa: E402
    checkerboard_points,
    find_checkerboard,
    rectification_map,
    remap_bilinear,
    stereo_calibrate,
    stereo_disparity,
    stereo_rectify,
)

BLOCK = 5
#: the census threshold shown beside the defaults: chosen on the tuning half (davinci)
THRESHOLD = 4.0
#: the label of the plain census (``census_step=None``), the default before 2026-11-30
PLAIN = "imageform plain census (before 2026-11-30)"
#: name -> (half, kind, left glob, right glob, board (cols, rows), square mm or None, digest)
SETS: dict[str, tuple[str, str, str, str, tuple[int, int], float | None, str]] = {
    "davinci": (
        "tuning", "board", "left*.png", "right*.png", (7, 7), None,
        "8800343bb1a561040cc6b6c7501f509430a576b92c99f2a872a51271ac358a08",
    ),
    "urban": (
        "tuning", "scene", "urban*_left.pgm", "urban*_right.pgm", (0, 0), None,
        "cc6d80f74067bc9c306ad7b1ead5d529651595cab8256c2e8ae6e1a3cf84b962",
    ),
    "webcam-1": (
        "held out", "board", "left*.jpg", "right*.jpg", (9, 6), 24.23,
        "0a24678465a1bb2e428a782b87d441ab39f94e0da16c8c0f7898120064325b67",
    ),
    "webcam-2": (
        "held out", "board", "left*.jpg", "right*.jpg", (9, 6), 24.23,
        "6b6ec167abf4e09bf1585967327f9938d6a29839bf7c15c167c27052cb18499a",
    ),
    "ximea": (
        "held out", "board", "left*.jpg", "right*.jpg", (9, 6), None,
        "2c4f9d11f59b5398ae5ffe139b81186ee75c4fd911dc28b4f517173b80b4b45b",
    ),
}  # fmt: skip


def _load() -> str:
    if not hasattr(os, "getloadavg"):
        return "n/a"
    return " / ".join(f"{v:.1f}" for v in os.getloadavg())


def _digest(folder: Path) -> str:
    lines = []
    for f in sorted(p for p in folder.iterdir() if p.is_file()):
        lines.append(f"{hashlib.sha256(f.read_bytes()).hexdigest()}  {f.name}\n")
    return hashlib.sha256("".join(lines).encode()).hexdigest()


def _natural(p: Path) -> tuple[str, int]:
    stem = p.stem
    digits = "".join(c for c in stem if c.isdigit())
    return (stem.rstrip("0123456789"), int(digits) if digits else -1)


def _grey(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("L"))


def _pairs(folder: Path, lg: str, rg: str) -> list[tuple[Path, Path]]:
    lefts = sorted(folder.glob(lg), key=_natural)
    rights = sorted(folder.glob(rg), key=_natural)
    if [_natural(p)[1] for p in lefts] != [_natural(p)[1] for p in rights]:
        raise SystemExit(f"{folder}: left and right files do not pair up")
    return list(zip(lefts, rights, strict=True))


# ------------------------------------------------------------------ calibration


def _dist(cal: Any) -> np.ndarray:
    c = cal.distortion.coeffs
    c = c() if callable(c) else c
    return np.asarray(c[:5], dtype=np.float64)


def _detect(pairs: list[tuple[Path, Path]], board: tuple[int, int]) -> dict[str, Any]:
    used, lc, rc, skipped = [], [], [], 0
    size = None
    for lf, rf in pairs:
        gl, gr = _grey(lf), _grey(rf)
        size = (gl.shape[1], gl.shape[0])
        a = find_checkerboard(gl, board)
        b = find_checkerboard(gr, board)
        if not (a.found and b.found):
            skipped += 1
            continue
        cols = board[0]
        # the same corner first in both views (the board's order is fixed up to a turn)
        ok = all(
            float(np.dot(a.corners[j] - a.corners[0], b.corners[j] - b.corners[0])) > 0
            for j in (cols - 1, len(a.corners) - cols)
        )
        if not ok:
            skipped += 1
            continue
        used.append((lf, rf))
        lc.append(a.corners)
        rc.append(b.corners)
    return {"used": used, "left": lc, "right": rc, "skipped": skipped, "size": size}


def _opencv_calibrate(
    obj: list[np.ndarray], lc: list[np.ndarray], rc: list[np.ndarray], size: tuple[int, int]
) -> dict[str, Any]:
    import cv2

    o = [x.astype(np.float32) for x in obj]
    lp = [x.astype(np.float32).reshape(-1, 1, 2) for x in lc]
    rp = [x.astype(np.float32).reshape(-1, 1, 2) for x in rc]
    _, K1, D1, _, _ = cv2.calibrateCamera(o, lp, size, None, None)
    _, K2, D2, _, _ = cv2.calibrateCamera(o, rp, size, None, None)
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    rms, K1, D1, K2, D2, R, T, _, _ = cv2.stereoCalibrate(
        o, lp, rp, K1, D1, K2, D2, size, flags=cv2.CALIB_USE_INTRINSIC_GUESS, criteria=crit
    )
    return {"rms": rms, "K1": K1, "D1": D1.ravel()[:5], "K2": K2, "D2": D2.ravel()[:5],
            "R": R, "T": T.ravel()}  # fmt: skip


def _rect_points(
    pts: np.ndarray, K: np.ndarray, D: np.ndarray, R: np.ndarray, P: np.ndarray
) -> np.ndarray:
    import cv2

    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 50, 1e-10)
    out = cv2.undistortPoints(
        pts.reshape(-1, 1, 2).astype(np.float64), K, D, R=R, P=P, criteria=crit
    )
    return out.reshape(-1, 2)


def _rect_error(
    lc: list[np.ndarray], rc: list[np.ndarray], cams: tuple[Any, ...], rect: tuple[Any, ...]
) -> tuple[float, float]:
    K1, D1, K2, D2 = cams
    R1, R2, P1, P2 = rect
    dy = np.concatenate(
        [
            _rect_points(a, K1, D1, R1, P1)[:, 1] - _rect_points(b, K2, D2, R2, P2)[:, 1]
            for a, b in zip(lc, rc, strict=True)
        ]
    )
    return float(np.sqrt(np.mean(dy**2))), float(np.max(np.abs(dy)))


def _cli(
    folder: Path, lg: str, rg: str, board: tuple[int, int], square: float | None, tmp: Path
) -> dict[str, Any] | None:
    """``imageform stereo-calibrate`` on the set's files; the rig file written in ``tmp``."""
    from imageform.cli import main

    out = tmp / "rig.toml"
    argv = ["stereo-calibrate", str(folder / lg), str(folder / rg)]
    argv += ["--board", f"{board[0]}x{board[1]}", "-o", str(out), "--force", "--json"]
    if square is not None:
        argv += ["--square", f"{square}mm"]
    with (
        contextlib.redirect_stdout(io.StringIO()) as so,
        contextlib.redirect_stderr(io.StringIO()),
    ):
        code = main(argv)
    if code != 0:
        return None
    return dict(json.loads(so.getvalue()))


def _cli_depth(pair: tuple[Path, Path], rig: Path, lo: int, n: int, extra: list[str]) -> Any:
    """``imageform depth --disparity`` of one pair with the CLI's rig file (None: it failed)."""
    from imageform.cli import main

    out = rig.parent / "d.npy"
    argv = ["depth", str(pair[0]), str(pair[1]), "--camera", str(rig), "--disparity"]
    argv += ["--min-disparity", str(lo), "--num-disparities", str(n), "-o", str(out), "--force"]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main([*argv, *extra])
    return np.load(out) if code == 0 else None


# ------------------------------------------------------------------ matching


def _ours(left: np.ndarray, right: np.ndarray, lo: int, n: int, **kw: Any) -> np.ndarray:
    return stereo_disparity(left, right, min_disparity=lo, num_disparities=n, **kw)


def _sgbm(left: np.ndarray, right: np.ndarray, lo: int, n: int) -> np.ndarray:
    import cv2

    m = cv2.StereoSGBM_create(
        minDisparity=lo, numDisparities=n, blockSize=BLOCK, P1=8 * BLOCK * BLOCK,
        P2=32 * BLOCK * BLOCK, disp12MaxDiff=1, uniquenessRatio=10,
        mode=cv2.STEREO_SGBM_MODE_HH,
    )  # fmt: skip
    d = m.compute(left, right).astype(np.float32) / 16.0
    d[d < lo] = np.nan
    return d


def _mirror(fn: Any, left: np.ndarray, right: np.ndarray, lo: int, n: int) -> np.ndarray:
    """The right view's disparity map (``x_right + d`` is its left pixel): the pair mirrored.

    Mirrored and swapped, the right image becomes a left one with the same disparities.
    """
    a = np.ascontiguousarray(right[:, ::-1])
    b = np.ascontiguousarray(left[:, ::-1])
    return fn(a, b, lo, n)[:, ::-1]


def _lr_share(dl: np.ndarray, dr: np.ndarray) -> float:
    """Share of valid left pixels whose right partner's disparity is within 1 px."""
    w = dl.shape[1]
    ys, xs = np.nonzero(np.isfinite(dl))
    xr = np.round(xs - dl[ys, xs]).astype(np.int64)
    inside = (xr >= 0) & (xr < w)
    partner = np.full(ys.shape, np.nan)
    partner[inside] = dr[ys[inside], xr[inside]]
    good = np.abs(partner - dl[ys, xs]) <= 1.0
    return float(np.mean(good)) if ys.size else float("nan")


def _agree(a: np.ndarray, b: np.ndarray) -> float:
    both = np.isfinite(a) & np.isfinite(b)
    return float(np.mean(np.abs(a[both] - b[both]) <= 1.0)) if both.any() else float("nan")


def _quad_mask(shape: tuple[int, int], quad: np.ndarray, shrink: float = 0.1) -> np.ndarray:
    """Pixels inside the convex quadrilateral ``quad`` (4, 2), shrunk toward its centre."""
    c = quad.mean(axis=0)
    q = c + (1.0 - shrink) * (quad - c)
    h, w = shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    inside = np.ones(shape, dtype=bool)
    sign = None
    for i in range(4):
        a, b = q[i], q[(i + 1) % 4]
        cross = (b[0] - a[0]) * (v - a[1]) - (b[1] - a[1]) * (u - a[0])
        s = np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
        sign = s if sign is None else sign
        inside &= cross * s > 0
    return inside


def _score(d: np.ndarray, truth: np.ndarray, region: np.ndarray) -> tuple[float, ...]:
    ok = region & np.isfinite(d)
    e = (d - truth)[ok]
    if e.size == 0:
        return (0.0, float("nan"), float("nan"), float("nan"), float("nan"))
    return (
        float(ok.sum() / region.sum()),
        float(np.mean(np.abs(e) > 1)),
        float(np.mean(np.abs(e) > 3)),
        float(np.mean(np.abs(e))),
        float(np.median(e)),
    )


def _board_truth(
    a: np.ndarray, b: np.ndarray, cal: Any, rect: Any, shape: tuple[int, int], cols: int
) -> tuple[np.ndarray, np.ndarray, float]:
    K1, D1, K2, D2 = cal.left.K, _dist(cal.left), cal.right.K, _dist(cal.right)
    pl = _rect_points(a, K1, D1, rect.R1, rect.P1)
    pr = _rect_points(b, K2, D2, rect.R2, rect.P2)
    disp = pl[:, 0] - pr[:, 0]
    A = np.column_stack([pl[:, 0], pl[:, 1], np.ones(len(pl))])
    coef, *_ = np.linalg.lstsq(A, disp, rcond=None)
    resid = float(np.sqrt(np.mean((A @ coef - disp) ** 2)))
    h, w = shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    truth = coef[0] * u + coef[1] * v + coef[2]
    n = len(pl)
    quad = pl[[0, cols - 1, n - 1, n - cols]]
    return truth, _quad_mask(shape, quad), resid


def _time(
    pairs: list[tuple[np.ndarray, np.ndarray]], lo: int, n: int, runs: int
) -> tuple[float, float, float]:
    ours, plain, cv = [], [], []
    for _ in range(runs):
        for left, right in pairs:
            t = time.process_time()
            _ours(left, right, lo, n)
            ours.append(time.process_time() - t)
            t = time.process_time()
            _ours(left, right, lo, n, census_step=None)
            plain.append(time.process_time() - t)
            t = time.process_time()
            _sgbm(left, right, lo, n)
            cv.append(time.process_time() - t)
    return float(np.median(ours)), float(np.median(plain)), float(np.median(cv))


def _range(lo_truth: float, hi_truth: float, width: int) -> tuple[int, int]:
    lo = 0 if lo_truth >= 4 else int(16 * np.floor((lo_truth - 4) / 16))
    hi = hi_truth + 4
    n = int(16 * np.ceil((hi - lo) / 16))
    return lo, min(n, 16 * ((width // 2) // 16))


# ------------------------------------------------------------------ the sets


def _board_set(name: str, folder: Path, spec: tuple[Any, ...], runs: int) -> dict[str, Any]:
    half, _, lg, rg, board, square, _ = spec
    det = _detect(_pairs(folder, lg, rg), board)
    size = det["size"]
    obj = [checkerboard_points(board, square or 1.0)] * len(det["used"])
    ours = stereo_calibrate(obj, det["left"], det["right"], size)
    cv = _opencv_calibrate(obj, det["left"], det["right"], size)
    cvrect = _opencv_rect(cv, size)
    rect = stereo_rectify(
        ours.left.K, ours.left.distortion, ours.right.K, ours.right.distortion, size, ours.R,
        ours.T,
    )  # fmt: skip
    ang = np.degrees(
        np.arccos(np.clip((np.trace(ours.R @ np.asarray(cv["R"]).T) - 1) / 2, -1.0, 1.0))
    )
    err_ours = _rect_error(
        det["left"], det["right"],
        (ours.left.K, _dist(ours.left), ours.right.K, _dist(ours.right)),
        (rect.R1, rect.R2, rect.P1, rect.P2),
    )  # fmt: skip
    err_cv = _rect_error(
        det["left"], det["right"], (cv["K1"], cv["D1"], cv["K2"], cv["D2"]), cvrect
    )
    tmpdir = tempfile.TemporaryDirectory()
    cli = _cli(folder, lg, rg, board, square, Path(tmpdir.name))
    # matching on every used pair
    map_l = rectification_map(ours.left.K, ours.left.distortion, rect.R1, rect.P1, size)
    map_r = rectification_map(ours.right.K, ours.right.distortion, rect.R2, rect.P2, size)
    items = []
    for (lf, rf), a, b in zip(det["used"], det["left"], det["right"], strict=True):
        L = np.asarray(remap_bilinear(_grey(lf), map_l, keep_dtype=True))
        R = np.asarray(remap_bilinear(_grey(rf), map_r, keep_dtype=True))
        truth, region, resid = _board_truth(a, b, ours, rect, L.shape, board[0])
        items.append((L, R, truth, region, resid))
    lo_t = min(float(t[r].min()) for _, _, t, r, _ in items)
    hi_t = max(float(t[r].max()) for _, _, t, r, _ in items)
    lo, n = _range(lo_t, hi_t, size[0])
    methods = {
        "imageform": lambda L, R: _ours(L, R, lo, n),
        PLAIN: lambda L, R: _ours(L, R, lo, n, census_step=None),
        "imageform median_filter": lambda L, R: _ours(L, R, lo, n, median_filter=True),
        f"imageform census_threshold {THRESHOLD:g}": lambda L, R: _ours(
            L, R, lo, n, census_threshold=THRESHOLD
        ),
        "OpenCV SGBM MODE_HH": lambda L, R: _sgbm(L, R, lo, n),
    }
    mirrored = {
        "imageform": lambda a, b, lo_, n_: _ours(a, b, lo_, n_),
        PLAIN: lambda a, b, lo_, n_: _ours(a, b, lo_, n_, census_step=None),
        f"imageform census_threshold {THRESHOLD:g}": lambda a, b, lo_, n_: _ours(
            a, b, lo_, n_, census_threshold=THRESHOLD
        ),
        "OpenCV SGBM MODE_HH": _sgbm,
    }
    scores: dict[str, list[tuple[float, ...]]] = {k: [] for k in methods}
    lr: dict[str, list[float]] = {k: [] for k in mirrored}
    agree: dict[str, list[float]] = {"imageform": [], PLAIN: []}
    for L, R, truth, region, _ in items:
        maps = {}
        for k, fn in methods.items():
            d = fn(L, R)
            maps[k] = d
            scores[k].append(_score(d, truth, region))
        for k, f in mirrored.items():
            lr[k].append(_lr_share(np.where(region, maps[k], np.nan), _mirror(f, L, R, lo, n)))
        for k, ag in agree.items():
            ag.append(_agree(maps[k], maps["OpenCV SGBM MODE_HH"]))
    # the command line end to end: its rig file, imageform depth on the first pair
    cli_scores = []
    if cli is not None:
        for extra in ([], ["--census-step", "0"], ["--census-threshold", f"{THRESHOLD:g}"]):
            d = _cli_depth(det["used"][0], Path(tmpdir.name) / "rig.toml", lo, n, extra)
            cli_scores.append(None if d is None else _score(d, items[0][2], items[0][3]))
    tmpdir.cleanup()
    t_ours, t_plain, t_cv = _time([(L, R) for L, R, *_ in items[:2]], lo, n, runs)
    return {
        "cli_depth": cli_scores,
        "first": scores["imageform"][0],
        "first_plain": scores[PLAIN][0],
        "first_thr": scores[f"imageform census_threshold {THRESHOLD:g}"][0],
        "half": half, "size": size, "pairs": len(det["used"]), "total": len(det["used"]) +
        det["skipped"], "ours": ours, "cv": cv, "angle": ang, "err_ours": err_ours,
        "err_cv": err_cv, "cli": cli, "lo": lo, "n": n, "scores": scores, "lr": lr,
        "agree": agree, "resid": [it[4] for it in items], "time": (t_ours, t_plain, t_cv),
        "truth_range": (lo_t, hi_t), "square": square,
    }  # fmt: skip


def _opencv_rect(cv: dict[str, Any], size: tuple[int, int]) -> tuple[np.ndarray, ...]:
    import cv2

    R1, R2, P1, P2, *_ = cv2.stereoRectify(
        cv["K1"], cv["D1"], cv["K2"], cv["D2"], size, cv["R"], cv["T"].reshape(3, 1), alpha=-1
    )
    return R1, R2, P1, P2


def _scene_set(name: str, folder: Path, spec: tuple[Any, ...], runs: int) -> dict[str, Any]:
    half, _, lg, rg, *_ = spec
    rows = []
    pairs = [(_grey(a), _grey(b)) for a, b in _pairs(folder, lg, rg)]
    lo, n = 0, 64
    for (L, R), (lf, _) in zip(pairs, _pairs(folder, lg, rg), strict=True):
        d_o = _ours(L, R, lo, n)
        d_p = _ours(L, R, lo, n, census_step=None)
        d_m = _ours(L, R, lo, n, median_filter=True)
        d_t = _ours(L, R, lo, n, census_threshold=THRESHOLD)
        d_c = _sgbm(L, R, lo, n)
        band = np.zeros(L.shape, dtype=bool)
        band[:, lo + n - 1 :] = True

        def thr(a: np.ndarray, b: np.ndarray, c: int, e: int) -> np.ndarray:
            return _ours(a, b, c, e, census_threshold=THRESHOLD)

        def plain(a: np.ndarray, b: np.ndarray, c: int, e: int) -> np.ndarray:
            return _ours(a, b, c, e, census_step=None)

        rows.append(
            {
                "pair": lf.stem.replace("_left", ""),
                "size": (L.shape[1], L.shape[0]),
                "density": [float(np.isfinite(x)[band].mean()) for x in (d_o, d_p, d_m, d_t, d_c)],
                "lr": [
                    _lr_share(d_o, _mirror(lambda a, b, c, e: _ours(a, b, c, e), L, R, lo, n)),
                    _lr_share(d_p, _mirror(plain, L, R, lo, n)),
                    _lr_share(d_t, _mirror(thr, L, R, lo, n)),
                    _lr_share(d_c, _mirror(_sgbm, L, R, lo, n)),
                ],
                "agree": [_agree(d_o, d_c), _agree(d_p, d_c), _agree(d_t, d_c)],
            }
        )
    t_ours, t_plain, t_cv = _time(pairs[:2], lo, n, runs)
    return {"half": half, "rows": rows, "time": (t_ours, t_plain, t_cv), "n": n}


# ------------------------------------------------------------------ tsukuba


def _tsukuba(acv: Path) -> list[str]:
    import cv2
    from scipy.ndimage import binary_dilation, uniform_filter

    sys.path.insert(0, str(ROOT / "benchmarks"))
    sys.path.insert(0, str(ROOT / "tests"))
    from check_stereo_depth import _opencv, _pair_2003, _region

    p = _pair_2003(acv, "tsukuba")
    t = p["truth"]
    reg = _region(p)
    g = np.zeros(t.shape, dtype=bool)
    for ax in (0, 1):
        step = np.abs(np.diff(t, axis=ax)) >= 1
        if ax == 1:
            g[:, 1:] |= step
            g[:, :-1] |= step
        else:
            g[1:] |= step
            g[:-1] |= step
    near = binary_dilation(g, iterations=3)
    img = p["left"].astype(np.float64)
    sd = np.sqrt(np.maximum(uniform_filter(img * img, 5) - uniform_filter(img, 5) ** 2, 0.0))
    flat = sd < 3.0
    maps = {
        "imageform": stereo_disparity(p["left"], p["right"], num_disparities=16),
        PLAIN: stereo_disparity(p["left"], p["right"], num_disparities=16, census_step=None),
        "imageform median_filter": stereo_disparity(
            p["left"], p["right"], num_disparities=16, median_filter=True
        ),
        "OpenCV SGBM MODE_HH": _opencv(p, cv2.STEREO_SGBM_MODE_HH),
    }
    for thr in (1.0, 2.0, THRESHOLD):
        maps[f"imageform census_threshold {thr:g}"] = stereo_disparity(
            p["left"], p["right"], num_disparities=16, census_threshold=thr
        )
    lines = [
        "| method | density | > 1 px | > 1 px within 3 px of a truth step | > 1 px elsewhere, "
        "texture sd < 3 | > 1 px elsewhere, textured | MAE elsewhere px | within 1/4 px of a "
        "whole pixel, elsewhere |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for k, d in maps.items():
        ok = reg & np.isfinite(d)
        bad = ok & (np.abs(d - t) > 1)
        far = ok & ~near
        frac = np.abs(d - np.round(d))[far]
        lines.append(
            f"| {k} | {100 * ok.sum() / reg.sum():.1f} % | {100 * bad.sum() / ok.sum():.2f} % | "
            f"{100 * (bad & near).sum() / ok.sum():.2f} % | "
            f"{100 * (bad & ~near & flat).sum() / ok.sum():.2f} % | "
            f"{100 * (bad & ~near & ~flat).sum() / ok.sum():.2f} % | "
            f"{np.abs(d - t)[far].mean():.3f} | {100 * np.mean(frac <= 0.25):.1f} % |"
        )
    return lines


# ------------------------------------------------------------------ report


def main() -> None:
    """Print (and write with ``--out``) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path, help="folder holding one folder per set")
    ap.add_argument("--half", choices=("tuning", "held-out", "all"), default="tuning")
    ap.add_argument("--acv", type=Path, help="r09921135/acv's hw4/testdata/ (tsukuba)")
    ap.add_argument("--out", type=Path, help="write the markdown tables here too")
    ap.add_argument("--runs", type=int, default=5, help="timed runs of each matcher")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    stereo_disparity(np.zeros((40, 60)), np.zeros((40, 60)), num_disparities=16)  # compile
    want = {"tuning": ("tuning",), "held-out": ("held out",), "all": ("tuning", "held out")}
    results: dict[str, dict[str, Any]] = {}
    failed: dict[str, str] = {}
    load0 = _load()
    for name, spec in SETS.items():
        if spec[0] not in want[args.half]:
            continue
        folder = args.data / name
        got = _digest(folder)
        if got != spec[6]:
            raise SystemExit(f"{folder}: SHA-256 digest {got}, expected {spec[6]}")
        fn = _board_set if spec[1] == "board" else _scene_set
        try:
            results[name] = fn(name, folder, spec, args.runs)
        except Exception as exc:  # a set that fails is a finding: reported, not fatal
            failed[name] = f"{type(exc).__name__}: {exc}".splitlines()[0]
    lines = [
        "# The stereo chain on fresh real data: calibration, rectification, matching",
        "",
        f"numpy {np.__version__}, OpenCV {cv2.__version__}; sets: {args.half} "
        f"(benchmarks/check_stereo_fresh.py names their sources); load before: {load0}. "
        "imageform: stereo_disparity's defaults (the graded census, census_step 4, the costs "
        "summed over 3 x 3 pixels, cost_window 3: the default since 2026-11-30g; "
        "benchmarks/check_stereo_webcam.py compares cost_window 1, the default before); "
        f"{PLAIN}: census_step None, the default before; census_threshold "
        f"{THRESHOLD:g}: with the default census_step.",
        "",
        "Stereo calibration on the same corners (imageform's find_checkerboard), imageform "
        "stereo_calibrate against cv2.calibrateCamera + cv2.stereoCalibrate "
        "(CALIB_USE_INTRINSIC_GUESS); baseline in mm where the square is known, else in "
        "squares; the CLI: imageform stereo-calibrate on the set's files:",
        "",
        "| set | half | size | pairs used | RMS px imageform | RMS px OpenCV | baseline "
        "imageform | baseline OpenCV | angle between R deg | fx left imageform / OpenCV "
        "| CLI pairs | CLI RMS px | CLI baseline |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    boards = {k: r for k, r in results.items() if "scores" in r}
    for name, r in boards.items():
        o, c, cli = r["ours"], r["cv"], r["cli"]
        unit = " mm" if r["square"] else " sq"
        cli_cells = (
            f"{cli['pairs_used']} | {cli['rms_px']:.4f} | {cli['baseline']:.3f}{unit}"
            if cli
            else "failed | | "
        )
        lines.append(
            f"| {name} | {r['half']} | {r['size'][0]} x {r['size'][1]} | {r['pairs']} of "
            f"{r['total']} | {o.rms:.4f} | {c['rms']:.4f} | {o.baseline:.3f}{unit} | "
            f"{np.linalg.norm(c['T']):.3f}{unit} | {r['angle']:.4f} | "
            f"{o.left.K[0, 0]:.1f} / {c['K1'][0, 0]:.1f} | {cli_cells} |"
        )
    lines += [
        "",
        "Rectification error: the board corners of every used pair through each library's "
        "own calibration and stereoRectify (alpha -1), |y_left - y_right|; the board-plane "
        "truth's fit (the RMS residual of the affine plane through the corners' disparities, "
        "median over the pairs) and the disparity range searched:",
        "",
        "| set | RMS px imageform | max px imageform | RMS px OpenCV | max px OpenCV "
        "| plane fit RMS px | truth disparities | searched |",
        "|---|---:|---:|---:|---:|---:|---|---|",
    ]
    for name, r in boards.items():
        eo, ec = r["err_ours"], r["err_cv"]
        lo_t, hi_t = r["truth_range"]
        lines.append(
            f"| {name} | {eo[0]:.3f} | {eo[1]:.3f} | {ec[0]:.3f} | {ec[1]:.3f} | "
            f"{np.median(r['resid']):.3f} | {lo_t:.1f} to {hi_t:.1f} | {r['lo']} to "
            f"{r['lo'] + r['n'] - 1} |"
        )
    lines += [
        "",
        "Matching on the rectified board pairs against the board plane (inside the outer "
        "corners' quadrilateral shrunk by 10 %), pooled over the pairs (the mean of the "
        "pairs' figures; worst pair's > 1 px in brackets); left-right consistent: the share "
        "of valid pixels of the board whose right-view partner is within 1 px; agreement: "
        "pixels valid in both within 1 px (the whole image):",
        "",
        "| set | method | density | > 1 px (worst pair) | > 3 px | MAE px | median d - truth "
        "| left-right consistent | agreement with OpenCV |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, r in boards.items():
        for k, sc in r["scores"].items():
            a = np.array(sc, dtype=np.float64)
            lr = f"{100 * np.nanmean(r['lr'][k]):.1f} %" if r["lr"].get(k) else ""
            ag = f"{100 * np.nanmean(r['agree'][k]):.1f} %" if k in r["agree"] else ""
            lines.append(
                f"| {name} | {k} | {100 * np.nanmean(a[:, 0]):.1f} % | "
                f"{100 * np.nanmean(a[:, 1]):.2f} % ({100 * np.nanmax(a[:, 1]):.1f} %) | "
                f"{100 * np.nanmean(a[:, 2]):.2f} % | {np.nanmean(a[:, 3]):.3f} | "
                f"{np.nanmedian(a[:, 4]):+.3f} | {lr} | {ag} |"
            )
    lines += [
        "",
        "The command line end to end on each board set's first pair: imageform stereo-calibrate's "
        "rig file, imageform depth --disparity (the same range; its rectified images are "
        "float, the table's above 8-bit), against the board plane; beside it the function's "
        "figures on that pair above:",
        "",
        "| set | options | density | > 1 px | > 3 px | MAE px | function: density | > 1 px |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, r in boards.items():
        for extra, sc, ref in zip(
            ("defaults", "--census-step 0", f"--census-threshold {THRESHOLD:g}"),
            r["cli_depth"],
            (r["first"], r["first_plain"], r["first_thr"]),
            strict=False,
        ):
            cells = (
                "failed | | | "
                if sc is None
                else f"{100 * sc[0]:.1f} % | {100 * sc[1]:.2f} % | {100 * sc[2]:.2f} % | "
                f"{sc[3]:.3f}"
            )
            lines.append(
                f"| {name} | {extra} | {cells} | {100 * ref[0]:.1f} % | {100 * ref[1]:.2f} % |"
            )
    scenes = {k: r for k, r in results.items() if "rows" in r}
    if scenes:
        lines += [
            "",
            "Real pairs without a truth (64 disparities, right of the invalid band): density "
            "of imageform (its defaults), the plain census (before 2026-11-30), with "
            f"median_filter, with census_threshold {THRESHOLD:g} and of OpenCV; left-right "
            "consistent shares; agreement with OpenCV (within 1 px):",
            "",
            "| set | pair | size | density imageform | plain | median | threshold | OpenCV "
            "| left-right consistent imageform | plain | threshold | OpenCV "
            "| agreement imageform | plain | threshold |",
            "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for name, r in scenes.items():
            for row in r["rows"]:
                cells = " | ".join(
                    f"{100 * v:.1f} %" for v in (*row["density"], *row["lr"], *row["agree"])
                )
                lines.append(
                    f"| {name} | {row['pair']} | {row['size'][0]} x {row['size'][1]} | {cells} |"
                )
    lines += [
        "",
        f"CPU time of the matching alone, one thread each, median of {args.runs} interleaved "
        "runs on the first two pairs of each set:",
        "",
        "| set | disparities | imageform s | plain census s | OpenCV MODE_HH s "
        "| imageform / plain | imageform / OpenCV | plain / OpenCV |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, r in results.items():
        to, tp, tc = r["time"]
        lines.append(
            f"| {name} | {r['n']} | {to:.3f} | {tp:.3f} | {tc:.3f} | {to / tp:.2f} | "
            f"{to / tc:.2f} | {tp / tc:.2f} |"
        )
    if args.acv is not None:
        lines += [
            "",
            "Middlebury tsukuba (384 x 288, 16 disparities, whole-pixel truth, scored as in "
            "stereo-depth-2026-11-30d.md): where the > 1 px errors lie (shares of the valid "
            "scored pixels): within 3 px of a step of the truth, or elsewhere in weak texture "
            "(the left image's 5 x 5 standard deviation under 3 grey levels) or in texture; "
            "the mean error away from the steps, and the share of disparities there within "
            "1/4 px of a whole pixel (the truth is whole pixels):",
            "",
            *_tsukuba(args.acv),
        ]
    if failed:
        lines += ["", "Sets that failed:", ""]
        lines += [f"- {name}: {why}" for name, why in failed.items()]
    lines += ["", f"load after: {_load()}"]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
