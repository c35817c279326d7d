"""ChArUco corners in photographs: imageform's detect_charuco against OpenCV's CharucoDetector.

The same scenes for both (a 7 x 5 board, 5x5_100 markers, composited into the 24 Kodak
photographs by ``tests/geometry/test_charuco.py``'s ``_composite``: 20-60 px squares, any
in-plane turn, up to ~35 deg of tilt, blur up to 1.5 px, noise up to 3 %, every fourth view
cut by the border), uint8 grey in. Reported: corners found against the corners visible, the
error against the true corners (px), corners more than 1.5 px off (wrong), and the median
time per image, both run in the same process, interleaved.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_charuco.py --scenes 48
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path)
    ns = ap.parse_args()
    import cv2

    from imageform.geometry import CharucoBoard, detect_charuco
    from tests.geometry.test_charuco import _composite, _kodak

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    cv_board = cv2.aruco.CharucoBoard(
        (7, 5), 30.0, 22.0, cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    )
    detector = cv2.aruco.CharucoDetector(cv_board)
    rng = np.random.default_rng(ns.seed)
    detect_charuco(board.image(40, margin_px=20), board)  # compile the refinement kernel
    rows: dict[str, dict[str, list[float]]] = {
        k: {"found": [], "err": [], "wrong": [], "t": [], "frames6": []}
        for k in ("imageform", "OpenCV")
    }
    visible = 0
    for k in range(ns.scenes):
        img, truth = _composite(
            rng,
            board,
            _kodak(k % 24 + 1),
            square_px=int(rng.integers(20, 60)),
            blur=float(rng.choice([0.0, 0.7, 1.5])),
            noise=float(rng.choice([0.0, 0.01, 0.03])),
            cut=k % 4 == 3,
        )
        hgt, wid = img.shape
        inside = (truth > 4).all(axis=1) & (truth[:, 0] < wid - 5) & (truth[:, 1] < hgt - 5)
        visible += int(inside.sum())
        t0 = time.perf_counter()
        found = detect_charuco(img, board)
        t1 = time.perf_counter()
        cc, ci, _, _ = detector.detectBoard(img)
        t2 = time.perf_counter()
        ids_cv = np.zeros(0, int) if ci is None else ci.ravel()
        xy_cv = np.zeros((0, 2)) if cc is None else cc.reshape(-1, 2)
        for name, ids, xy, dt in (
            ("imageform", found.ids, found.corners, t1 - t0),
            ("OpenCV", ids_cv, xy_cv, t2 - t1),
        ):
            err = np.hypot(*(xy - truth[ids]).T) if len(ids) else np.zeros(0)
            r = rows[name]
            r["found"].append(len(ids))
            r["err"].extend(err[err <= 1.5].tolist())
            r["wrong"].append(int((err > 1.5).sum()))
            r["t"].append(dt)
            r["frames6"].append(len(ids) >= 6)
    table = []
    for name, r in rows.items():
        table.append(
            [
                name,
                f"{sum(r['found'])} / {visible}",
                f"{sum(r['frames6'])} / {ns.scenes}",
                f"{np.median(r['err']):.3f}",
                f"{np.percentile(r['err'], 95):.3f}",
                str(sum(r["wrong"])),
                f"{statistics.median(r['t']) * 1e3:.0f}",
            ]
        )
    ratio = statistics.median(rows["imageform"]["t"]) / statistics.median(rows["OpenCV"]["t"])
    text = "\n".join(
        [
            header("ChArUco corners in photographs: imageform vs OpenCV"),
            "",
            f"{ns.scenes} scenes, seed {ns.seed}; OpenCV {cv2.__version__} CharucoDetector "
            "(default parameters); uint8 grey in, corners (px) out; load average at the end "
            f"{os.getloadavg()[0]:.1f} (both detectors ran interleaved under the same load).",
            "",
            markdown_table(
                [
                    "detector",
                    "corners found / visible",
                    "images with >= 6 corners",
                    "median error (px)",
                    "95th pct error (px)",
                    "wrong (> 1.5 px)",
                    "median ms per image",
                ],
                table,
            ),
            "",
            f"Time ratio imageform / OpenCV (medians): {ratio:.1f}x.",
        ]
    )
    print(text)
    if ns.out:
        ns.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
