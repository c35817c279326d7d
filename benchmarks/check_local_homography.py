"""Checkerboard corners by point symmetry: an affine window, a local homography, the grid's map.

``find_checkerboard``'s symmetric step compared each corner's image at ``q + d`` and ``q - d``
(the board affine around the corner). Schöps et al. (CVPR 2020) define the samples on the
board instead and map them through a per-corner homography. Measured here, side by side:

- ``gradient``: ``find_checkerboard(method="gradient")`` (``refine_corners`` alone);
- ``affine``: the symmetric step on ``q ± d`` (imageform before this change);
- ``homography, fixed``: the samples through the homography of the corner's 3 x 3 grid
  neighbours (least squares), only the corner and the shading fitted;
- ``homography, fitted``: the same, its perspective fitted too by Gauss-Newton (the
  symmetry cost does not depend on the homography's linear part: the corner and the two
  perspective parameters are all of its eight that the cost fixes);
- ``grid map of the gradient corners, all corners``: the samples through the biquadratic
  through the corner's 3 x 3 grid neighbours (perspective and lens bending to second
  order), the maps read from the gradient corners, every corner, no affine step first;
- ``grid map, ...``: ``find_checkerboard`` with ``SYMMETRIC_MIN_BEND`` set: the affine step,
  then the grid map's step (maps read from the affine step's corners) on the corners whose
  map bends by more than that many pixels on the window's rim, its non-linear part less
  that many pixels (``bend less 1 px`` is the default; ``all corners`` is 0).

The two homography variants are NumPy prototypes in this script (same window, weights,
shading term, stopping rule, border and reach rules as the others).

Rendered views (truth known): a 9 x 6 board rendered analytically through a lens
(``tests/geometry/checkerboard_support.render_board_through``: each pixel's ray meets the
board plane, edges blurred 1 px, noise 0.01, 8-bit), wholly inside the image, in random
poses: an endoscope-like fisheye (768 x 576, Kannala-Brandt with the coefficients imageform
fitted to a real PAL endoscope, f = 300 px, corners within 330 px of the centre), a
wide-angle lens (640 x 480, Brown-Conrady k1 = -0.32, k2 = 0.11, f = 420 px; once more
with Gaussian noise of 4 codes and JPEG quality 80), both with tilts up to 45 deg, and
steep perspective (640 x 480, no distortion, f = 700 px, tilts 35-70 deg). Per scene: views
found, then the median, 95th percentile and largest corner error (px) and the count over
0.3 px; and the CPU time of ``find_checkerboard`` per mode (one after the other on each
view, median per view).

Real photographs (no truth): per set (``NAME=GLOB:COLSxROWS[:fisheye]``) the views found
in each mode, the RMS and two-fold held-out RMS of a calibration on each mode's corners of
the views every mode finds (``check_corner_refinement._evaluate``: OpenCV's calibration,
halves by parity, poses of the held-out half fitted with the intrinsics held, both ways
pooled), the median and largest distance between the affine corners and the default's, and
the CPU ms per view of ``find_checkerboard`` per mode (median). Run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:. python \\
        benchmarks/check_local_homography.py "opencv-left=DATA/opencv-left/left*.jpg:9x6" \\
        ... --views 20 --out TABLE.md
"""

from __future__ import annotations

import argparse
import glob
import math
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table

BOARD = (9, 6)


def _scenes() -> dict[str, tuple[tuple[int, int], np.ndarray, Any, tuple[float, float], float]]:
    from imageform.geometry import BrownConrady, KannalaBrandt

    return {
        "fisheye (Kannala-Brandt), 768 x 576": (
            (768, 576), np.array([[300.0, 0, 390], [0, 300, 280], [0, 0, 1]]),
            KannalaBrandt(-0.091, -0.0161, 0.0198, -0.022), (4.0, 7.0), 45.0,
        ),
        "wide angle (Brown-Conrady k1 -0.32), 640 x 480": (
            (640, 480), np.array([[420.0, 0, 322], [0, 420, 236], [0, 0, 1]]),
            BrownConrady(-0.32, 0.11, 0, 0, 0), (5.0, 8.0), 45.0,
        ),
        "wide angle as above, noise 4 codes and JPEG quality 80": (
            (640, 480), np.array([[420.0, 0, 322], [0, 420, 236], [0, 0, 1]]),
            BrownConrady(-0.32, 0.11, 0, 0, 0), (5.0, 8.0), 45.0,
        ),
        "steep perspective (pinhole, tilt 35-70 deg), 640 x 480": (
            (640, 480), np.array([[700.0, 0, 320], [0, 700, 240], [0, 0, 1]]),
            BrownConrady(0, 0, 0, 0, 0), (9.0, 14.0), 70.0,
        ),
    }  # fmt: skip


def _views(name: str, n: int, rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` rendered views (8-bit) of the whole board and their true corners."""
    from scipy.spatial.transform import Rotation

    from imageform.geometry import Camera, checkerboard_points, project_points_distorted
    from tests.geometry.checkerboard_support import render_board_through

    size, K, D, dist, tilt = _scenes()[name]
    w, h = size
    cam0 = Camera(K, image_size=size, distortion=D)
    obj = checkerboard_points(BOARD, 1.0)
    mid = np.array([(BOARD[0] - 1) / 2, (BOARD[1] - 1) / 2, 0.0])
    out: list[tuple[np.ndarray, np.ndarray]] = []
    while len(out) < n:
        ax = rng.normal(size=3)
        ax[2] *= 0.3
        ax /= np.linalg.norm(ax)
        lo = 0.5 * tilt if tilt > 50 else 0.0
        rot = Rotation.from_rotvec(ax * np.radians(rng.uniform(lo, tilt))).as_matrix()
        u, v = rng.uniform(0.3, 0.7) * w, rng.uniform(0.3, 0.7) * h
        xy = np.asarray(cam0.undistort_pixels(np.array([[u, v]])))[0]
        t = np.array([xy[0], xy[1], 1.0]) * rng.uniform(*dist) - rot @ mid
        truth = np.asarray(project_points_distorted(obj, K, rot, t, D)[0])
        if not np.all(np.isfinite(truth)) or not np.all((truth > 8) & (truth < [w - 9, h - 9])):
            continue
        if name.startswith("fisheye") and not np.all(np.hypot(*(truth - K[:2, 2]).T) < 330):
            continue
        cam = Camera(K, rot, t, size, distortion=D)
        img = render_board_through(cam, *BOARD, 1.0, blur=1.0, noise=0.01,
                                   seed=int(rng.integers(1 << 30)))  # fmt: skip
        u8 = np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)
        if "JPEG" in name:
            import cv2

            noisy = np.clip(u8 + rng.normal(0, 4, u8.shape), 0, 255).astype(np.uint8)
            u8 = cv2.imdecode(cv2.imencode(".jpg", noisy, [cv2.IMWRITE_JPEG_QUALITY, 80])[1], 0)
        out.append((u8, truth))
    return out


# ----------------------------------------------------- the homography prototypes (NumPy)


def _neighbour_homographies(grid: np.ndarray) -> np.ndarray:
    """Per corner (R*C, 3, 3): the homography (DLT) of its 3 x 3 grid block, board squares
    (the corner at 0) to pixels."""
    rows, cols, _ = grid.shape
    out = np.zeros((rows * cols, 3, 3))
    for r in range(rows):
        for c in range(cols):
            r0, c0 = min(max(r - 1, 0), rows - 3), min(max(c - 1, 0), cols - 3)
            jj, ii = np.meshgrid(np.arange(c0, c0 + 3), np.arange(r0, r0 + 3))
            X = np.stack([(jj - c).ravel(), (ii - r).ravel()], 1).astype(float)
            U = (grid[r0:r0 + 3, c0:c0 + 3].reshape(-1, 2) - grid[r, c]) / 100.0  # fmt: skip
            A = []
            for (x, y), (u, v) in zip(X, U, strict=True):
                A.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
                A.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
            H = np.linalg.svd(np.array(A))[2][-1].reshape(3, 3)
            H = np.diag([100.0, 100.0, 1.0]) @ H
            H[:2] += np.outer(grid[r, c], H[2])  # back to pixels
            out[r * cols + c] = H / H[2, 2]
    return out


def _perspective(H: np.ndarray) -> np.ndarray:
    """``m`` of ``H(x) = q + y / (1 + m . y)``, ``y`` the linear part's image of ``x``."""
    c, l_ = H[:2, 2], H[2, :2]
    A = H[:2, :2] - np.outer(c, l_)
    return np.asarray(np.linalg.solve(A.T, l_))


def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, ...]:
    from imageform._kernels.checkerboard_local import _sample_numpy

    return _sample_numpy(img, x, y)


def _refine_homography(img: np.ndarray, q0: np.ndarray, m0: np.ndarray, h: int,
                       fit_m: bool, max_iter: int = 30, tol: float = 1e-3,
                       ) -> tuple[np.ndarray, int]:  # fmt: skip
    """One corner: samples ``q + y / (1 + m . y)`` and ``q - y / (1 - m . y)`` over the
    affine window's pixel offsets ``y``; Gauss-Newton on ``q``, the shading and (``fit_m``)
    ``m``. Returns the corner and 0 (converged), 1 (``max_iter``) or 2 (singular)."""
    from imageform._kernels.checkerboard_symmetric import symmetric_window_weights

    w = symmetric_window_weights(h)
    dy, dx = np.mgrid[-h:h + 1, -h:h + 1].astype(float)  # fmt: skip
    keep = w > 0
    y = np.stack([dx[keep], dy[keep]], 1)
    wt = w[keep]
    q, m = q0.astype(float).copy(), m0.astype(float).copy()
    for _ in range(max_iter):
        zp, zm = 1 + y @ m, 1 - y @ m
        if np.any(zp <= 0.1) or np.any(zm <= 0.1):
            return q0, 2
        vp, gxp, gyp = _bilinear(img, q[0] + y[:, 0] / zp, q[1] + y[:, 1] / zp)
        vm, gxm, gym = _bilinear(img, q[0] - y[:, 0] / zm, q[1] - y[:, 1] / zm)
        gp, gm = np.stack([gxp, gyp], 1), np.stack([gxm, gym], 1)
        parts = [gp - gm]
        if fit_m:
            parts.append(-((gp * y).sum(1) / zp**2)[:, None] * y
                         + ((gm * y).sum(1) / zm**2)[:, None] * y)  # fmt: skip
        J = np.concatenate([*parts, -2 * y], 1)
        N = (J * wt[:, None]).T @ J
        try:
            st = -np.linalg.solve(N, (J * wt[:, None]).T @ (vp - vm))
        except np.linalg.LinAlgError:
            return q0, 2
        n = math.hypot(*st[:2])
        if n > 1:
            st = st / n
        q += st[:2]
        if fit_m:
            m += st[2:4]
        if n <= tol:
            return q, 0
    return q, 1


def _homography_step(img: np.ndarray, start: np.ndarray, grid: np.ndarray, h: int,
                     reach: float, fit_m: bool) -> np.ndarray:  # fmt: skip
    """The border and reach rules of ``refine_symmetric_inside`` around the prototype."""
    from imageform.geometry.checkerboard_subpix import room_to_border

    Hs = _neighbour_homographies(grid)
    out = start.copy()
    room = room_to_border(start, *img.shape)
    for k in range(len(start)):
        if room[k] < h + 1:
            continue
        q, st = _refine_homography(img, start[k], _perspective(Hs[k]), h, fit_m)
        if st <= 1 and math.hypot(*(q - start[k])) <= reach:
            out[k] = q
    return out


# ------------------------------------------------------------------------ the two modes


#: find_checkerboard's symmetric step in each mode: the bend (px) of a corner's grid map on
#: its window's rim below which the map is not used, less which it is used (inf: the affine
#: window everywhere; the default is SYMMETRIC_MIN_BEND)
MODES = {"affine": math.inf, "grid map, bend less 1 px (default)": 1.0,
         "grid map, bend less 0.5 px": 0.5, "grid map, all corners": 0.0}  # fmt: skip


DEFAULT = "grid map, bend less 1 px (default)"
WHO = ("gradient", "affine", "homography, fixed", "homography, fitted",
       "grid map of the gradient corners, all corners", *list(MODES)[1:])  # fmt: skip


def _find(img: np.ndarray, board: tuple[int, int], min_bend: float) -> Any:
    import imageform.geometry.checkerboard as cb

    keep = cb.SYMMETRIC_MIN_BEND
    cb.SYMMETRIC_MIN_BEND = min_bend
    try:
        return cb.find_checkerboard(img, board)
    finally:
        cb.SYMMETRIC_MIN_BEND = keep


def rendered(views: int, seed: int) -> tuple[list[list[object]], list[list[object]]]:
    """Rows of corner errors per scene and detector; rows of CPU times per scene."""
    from imageform.geometry import find_checkerboard
    from imageform.geometry.checkerboard_subpix import refine_local_inside

    rng = np.random.default_rng(seed)
    rows: list[list[object]] = []
    cpu_rows: list[list[object]] = []
    for name in _scenes():
        errs: dict[str, list[np.ndarray]] = {w: [] for w in WHO}
        n_found = dict.fromkeys(WHO, 0)
        cpu: dict[str, list[float]] = {m: [] for m in MODES}
        for u8, truth in _views(name, views, rng):
            grad = find_checkerboard(u8, BOARD, method="gradient")
            got: dict[str, np.ndarray | None] = {"gradient": grad.corners}
            for mode, min_bend in MODES.items():
                t0 = time.process_time()
                res = _find(u8, BOARD, min_bend)
                cpu[mode].append(time.process_time() - t0)
                got[mode] = res.corners
            if grad.corners is not None:
                g = grad.corners.reshape(BOARD[1], BOARD[0], 2)
                step = min(float(np.linalg.norm(np.diff(g, axis=a), axis=-1).min())
                           for a in (0, 1))  # fmt: skip
                h = max(2, math.floor(0.8 * step))
                img = u8.astype(np.float32) / 255
                for label, fit_m in (("homography, fixed", False), ("homography, fitted", True)):
                    got[label] = _homography_step(img, grad.corners, g, h, 0.25 * step, fit_m)
                got["grid map of the gradient corners, all corners"] = refine_local_inside(
                    img, grad.corners, grad.corners, g, h, 30, 1e-3, 0.25 * step, 0.0, 0.8
                )[0]
            for w, c in got.items():
                if c is not None:
                    n_found[w] += 1
                    errs[w].append(np.linalg.norm(c - truth, axis=1))
        for w in WHO:
            e = np.concatenate(errs[w]) if errs[w] else np.full(1, np.nan)
            rows.append([name, w, f"{n_found[w]} of {views}", f"{np.median(e):.3f}",
                         f"{np.percentile(e, 95):.3f}", f"{e.max():.3f}",
                         f"{int((e > 0.3).sum())} of {e.size}"])  # fmt: skip
        cpu_rows.append([name, _cpu(cpu)])
        print(rows[-1], cpu_rows[-1], file=sys.stderr, flush=True)
    return rows, cpu_rows


def _cpu(cpu: dict[str, list[float]]) -> str:
    """CPU ms a view per mode (median) and the ratio to the affine mode's."""
    base = statistics.median(cpu["affine"])
    return " / ".join(f"{1e3 * statistics.median(v):.1f} ({statistics.median(v) / base:.2f})"
                      for v in cpu.values())  # fmt: skip


def real_set(cv2: Any, name: str, pattern: str, board: tuple[int, int],
             fisheye: bool) -> list[object]:  # fmt: skip
    """One set's row: views found, RMS / held-out per mode, corner shifts, CPU per view."""
    from PIL import Image

    from benchmarks.check_corner_refinement import _evaluate

    found: dict[str, list[np.ndarray | None]] = {m: [] for m in MODES}
    cpu: dict[str, list[float]] = {m: [] for m in MODES}
    size = (0, 0)
    for f in sorted(glob.glob(pattern)):
        try:
            grey = np.asarray(Image.open(f).convert("L"))
        except Exception:  # an unreadable file is left out
            continue
        size = (grey.shape[1], grey.shape[0])
        for mode, min_bend in MODES.items():
            t0 = time.process_time()
            det = _find(grey, board, min_bend)
            cpu[mode].append(time.process_time() - t0)
            found[mode].append(None if det.corners is None else np.asarray(det.corners))
    n = len(found["affine"])
    both = [k for k in range(n) if all(found[m][k] is not None for m in MODES)]
    row: list[object] = [name, f"{board[0]} x {board[1]}", "fisheye" if fisheye else "plain",
                         n, " / ".join(str(sum(c is not None for c in found[m]))
                                       for m in MODES)]  # fmt: skip
    for mode in MODES:
        rms, held = _evaluate(cv2, fisheye, [found[mode][k] for k in both], board, size)  # type: ignore[misc]
        row.append(f"{rms:.4f} / {held:.4f}")
    d = np.concatenate([np.linalg.norm(found[DEFAULT][k] - found["affine"][k],  # type: ignore[operator]
                                       axis=1) for k in both])  # fmt: skip
    row.append(f"{np.median(d):.3f} / {d.max():.3f}")
    row.append(_cpu(cpu))
    return row


def main() -> None:
    """Run the real sets given and the rendered views; print (or write) the tables."""
    import cv2

    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("sets", nargs="*", help="NAME=GLOB:COLSxROWS[:fisheye]")
    ap.add_argument("--views", type=int, default=20, help="rendered views per scene")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    _find(np.zeros((64, 64), np.uint8), BOARD, 0.0)  # compile
    synth, cpu_rows = rendered(args.views, args.seed)
    rows = []
    for spec in args.sets:
        name, rest = spec.split("=", 1)
        parts = rest.split(":")
        fisheye = parts[-1] == "fisheye"
        if fisheye:
            parts = parts[:-1]
        cols, nrows = (int(v) for v in parts[-1].lower().split("x"))
        rows.append(real_set(cv2, name, ":".join(parts[:-1]), (cols, nrows), fisheye))
        print(rows[-1], file=sys.stderr, flush=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = header("Checkerboard corners by point symmetry: affine window, homography, grid map")
    text += (
        f"\nOpenCV {cv2.__version__}; load average {load:.1f} when run (CPU times are "
        "indicative). Made by `benchmarks/check_local_homography.py` (its docstring says what "
        "each detector is and how the views are made).\n\n## Rendered views (truth known)\n\n"
        "Corner error (px) against the true corners, of the views each finds.\n\n"
    )
    text += markdown_table(("scene", "detector", "views found", "median", "95th pct", "largest",
                            "over 0.3 px"), synth)  # fmt: skip
    modes = "; ".join(MODES)
    text += f"\nCPU ms a view of find_checkerboard (median; ratio to affine): {modes}.\n\n"
    text += markdown_table(("scene", "CPU ms a view"), cpu_rows)
    if rows:
        text += (
            "\n## Real photographs\n\nRMS / held-out RMS (px) of a calibration on the corners "
            "of the views every mode finds, per mode; the distance (px) between the affine "
            "corners and the default's (median / largest); CPU ms a view of "
            f"find_checkerboard (median; ratio to affine). Modes: {modes}.\n\n"
        )
        text += markdown_table(
            ("set", "board", "model", "views", "found per mode", *MODES, "corner shift",
             "CPU ms a view per mode"),
            rows,
        )  # fmt: skip
    if args.out:
        args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
