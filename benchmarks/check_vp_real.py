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

Three ways to place the principal point: the image centre (the default), the orthocentre of
three finite vanishing points (the textbook construction, the detector's behaviour before
2026-11-26), and the calibrated one (as from a camera file). The table gives the focal length
found and its error against 536.07 px; "-" where no K was determined.

This is not the York Urban DB (the benchmark issue 17's targets refer to, not available here):
13 frames of one camera, dominated by one planar object.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "data" / "opencv-left"
F_TRUE = 536.07345314
K = np.array([[F_TRUE, 0.0, 342.37046827], [0.0, 536.01636274, 235.53687064], [0.0, 0.0, 1.0]])
D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
MODES = {"centre": "center", "orthocentre": "orthocenter", "calibrated": K[:2, 2]}


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


def main() -> None:
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
