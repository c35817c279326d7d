"""Checkerboards in large photographs: imageform vs OpenCV, views brought to 12 and 27 Mpx.

Each of OpenCV's 13 ``left*.jpg`` views (640 x 480, 9 x 6 inner corners) is enlarged with
``cv2.resize(..., INTER_CUBIC)`` to 4032 x 3024 (a phone's 12 Mpx: squares of about 150 px,
edges about 9 px wide) and to 6048 x 4536 (27 Mpx), as it is or with Gaussian noise (sigma 4
codes) and JPEG quality 85. imageform ``find_checkerboard(img, (9, 6))`` and OpenCV 5.0
``findChessboardCorners(img, (9, 6))`` (default flags) run on the same uint8 image, one
after the other; the table gives the views found, the median seconds per view, and for
imageform the median and largest distance of its corners, brought back to the 640 x 480
view's pixels, to its corners found in that view (OpenCV's own to 1e-5 px). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_checkerboard_large.py
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
VIEWS = ROOT.parent / "shared" / "data" / "opencv-left"


def main() -> None:
    import cv2

    from benchmarks._common import header, markdown_table
    from imageform.geometry import find_checkerboard
    from imageform.io import read_image

    names = sorted(p.name for p in VIEWS.glob("left*.jpg"))
    rng = np.random.default_rng(0)
    rows = []
    for width, height in ((4032, 3024), (6048, 4536)):
        for noisy in (False, True):
            ours_found = theirs_found = 0
            ours_s, theirs_s, med, worst = [], [], [], []
            for name in names:
                small = read_image(VIEWS / name)[..., 0]
                big = cv2.resize(small, (width, height), interpolation=cv2.INTER_CUBIC)
                if noisy:
                    noise = rng.normal(0, 4, big.shape)
                    big = np.clip(big + noise, 0, 255).astype(np.uint8)
                    big = cv2.imdecode(
                        cv2.imencode(".jpg", big, [cv2.IMWRITE_JPEG_QUALITY, 85])[1], 0
                    )
                t0 = time.perf_counter()
                res = find_checkerboard(big, (9, 6))
                ours_s.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                found, _ = cv2.findChessboardCorners(big, (9, 6))
                theirs_s.append(time.perf_counter() - t0)
                theirs_found += bool(found)
                if res.found:
                    ours_found += 1
                    ref = find_checkerboard(small, (9, 6)).corners
                    back = (res.corners + 0.5) * (640 / width) - 0.5
                    d = np.linalg.norm(back - ref, axis=1)
                    med.append(float(np.median(d)))
                    worst.append(float(d.max()))
            rows.append(
                [
                    f"{width} x {height}",
                    "noise 4 + JPEG 85" if noisy else "-",
                    f"{ours_found} / {len(names)}",
                    f"{statistics.median(ours_s):.2f}",
                    f"{statistics.median(med):.3f} / {max(worst):.3f}" if med else "-",
                    f"{theirs_found} / {len(names)}",
                    f"{statistics.median(theirs_s):.2f}",
                ]
            )
    print(header("Checkerboards in large photographs: imageform vs OpenCV"))
    print(
        markdown_table(
            ["image", "degraded", "imageform found", "imageform s/view",
             "corner error median / max (640 px)", "OpenCV found", "OpenCV s/view"],
            rows,
        )
    )  # fmt: skip


if __name__ == "__main__":
    main()
