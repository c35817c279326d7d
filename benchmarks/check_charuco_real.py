"""ChArUco corners in real photographs: imageform's detect_charuco against OpenCV's CharucoDetector.

The photographs are third-party (public repositories, listed in ``SETS`` with the commit and
licence of each); they are not in this repository. Put each set's files in a folder of its
name under the folder given on the command line (``PHOTOS/jp_intrinsics/calib_000.png`` ...;
``git show COMMIT:PATH`` in a clone of the repository gives them), then run::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src \\
        python benchmarks/check_charuco_real.py PHOTOS

Both detectors get the same uint8 grey image (OpenCV 5.0's ``CharucoDetector`` with default
parameters and the set's board, ``setLegacyPattern`` as the board was printed; imageform's
``detect_charuco`` with the board declared the current way, whatever the print). Per set:
the corners each finds, the views with at least 6 (what ``imageform calibrate`` uses), the
ids both report and how far apart the two put them (median / largest, px), the ids only one
reports, and, where 3 views or more have 6 corners, the RMS reprojection error of
``cv2.calibrateCamera`` on each detector's corners (an accuracy proxy: the same camera and
model for both), and of imageform's ``calibrate_camera`` on its own.

Then the views degraded (downscaled 2x and 4x with INTER_AREA, Gaussian blur 1.5 px, JPEG
quality 30, Gaussian noise of 8 codes, 4x darker, the left 55 % only), against a reference:
the corners both detectors put within 0.5 px of each other in the undegraded view (their
mean, scaled); the corners each finds of it, and those more than 1.5 px times the scale (at
least 0.5 px of the degraded view) off it. CPU time per view: the process's, one thread
each (``cv2.setNumThreads(1)``, ``NUMBA_NUM_THREADS=1``), after one untimed call of each
on the set's first view, the two interleaved ``--repeat`` times a view (5; the median of
each), median over the views.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
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
    """A folder of real photographs of one board, and where they came from."""

    name: str
    source: str
    licence: str
    pattern: str
    squares: tuple[int, int]
    square: float
    marker: float
    dictionary: str
    legacy: bool
    what: str
    first_marker: int = 0
    folder: str = ""


SETS = (
    PhotoSet(
        "jp_intrinsics",
        "github.com/jpjp210202/Hand-Eye-Calibration-Doosan-A0509-IntelRealSenseA457-ChArUco "
        "data/intrinsics_images/calib_*.png (snapshot of 2025)",
        "MIT",
        "calib_*.png",
        (7, 5),
        30.0,
        22.0,
        "4x4_50",
        False,
        "Intel RealSense colour 1280 x 720, calib.io print, hand-held views",
    ),
    PhotoSet(
        "pettod",
        "github.com/pettod/charuco-corner-detection test_data/im1.jpg, im2.jpg",
        "none stated",
        "*.jpg",
        (12, 9),
        60.0,
        47.0,
        "5x5_250",
        False,
        "phone 1280 x 960, poster on a tripod",
    ),
    PhotoSet(
        "mex_charuco_pose",
        "github.com/jmehami1/mex_ChArUco_Pose test_images/charuco_test.png @ de2399b",
        "MIT (also in tests/data/charuco/)",
        "*.png",
        (8, 6),
        40.0,
        30.0,
        "4x4_50",
        True,
        "webcam 640 x 480, hand-held, centre covered; OpenCV 4.5.5 print (legacy layout)",
    ),
    PhotoSet(
        "deepcharuco",
        "github.com/JunkyByte/deepcharuco src/reference/samples_test/IMG_741[234].png "
        "(history, commits 6e7bc4d, 8415c11, 3d0ccb7)",
        "MIT",
        "*.png",
        (5, 5),
        10.0,
        7.5,
        "4x4_50",
        False,
        "phone 320 x 240 of a tablet showing the board, dark room, markers 6-11 px",
    ),
    PhotoSet(
        "floor_3x3",
        "github.com/Milotrince/charuco-lidar-calibration data/test_img.jpg",
        "none stated",
        "*.jpg",
        (3, 3),
        192.0,
        138.0,
        "4x4_250",
        False,
        "phone 3024 x 4032, three 3 x 3 boards (ids 0-3, 4-7, 8-11) on walls and floor; "
        "board 1 (markers 0-3) here",
    ),
    PhotoSet(
        "floor_3x3 #2",
        "github.com/Milotrince/charuco-lidar-calibration data/test_img.jpg",
        "none stated",
        "*.jpg",
        (3, 3),
        192.0,
        138.0,
        "4x4_250",
        False,
        "the same view: board 2 (markers 4-7)",
        first_marker=4,
        folder="floor_3x3",
    ),
    PhotoSet(
        "floor_3x3 #3",
        "github.com/Milotrince/charuco-lidar-calibration data/test_img.jpg",
        "none stated",
        "*.jpg",
        (3, 3),
        192.0,
        138.0,
        "4x4_250",
        False,
        "the same view: board 3 (markers 8-11)",
        first_marker=8,
        folder="floor_3x3",
    ),
    PhotoSet(
        "basler_3x3",
        "github.com/banksAcc/Halcon_Charuco_comparison history: Basler_acA2040-35gm_*.tiff "
        "(commits 0a2bff6^, d0fc4a4; one view each)",
        "Apache-2.0 (ChArUco/LICENSE)",
        "*.tiff",
        (3, 3),
        40.0,
        30.0,
        "5x5_100",
        False,
        "Basler 2064 x 1544 mono, two 3 x 3 boards (ids 0-3, 4-7); board 1 here",
    ),
    PhotoSet(
        "basler_3x3 #2",
        "github.com/banksAcc/Halcon_Charuco_comparison history: Basler_acA2040-35gm_*.tiff "
        "(commits 0a2bff6^, d0fc4a4; one view each)",
        "Apache-2.0 (ChArUco/LICENSE)",
        "*.tiff",
        (3, 3),
        40.0,
        30.0,
        "5x5_100",
        False,
        "the same views: the second board (markers 4-7)",
        first_marker=4,
        folder="basler_3x3",
    ),
)

CV_DICTS = {
    "4x4_50": "DICT_4X4_50",
    "4x4_250": "DICT_4X4_250",
    "5x5_100": "DICT_5X5_100",
    "5x5_250": "DICT_5X5_250",
}


def degrade(g: np.ndarray, kind: str, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """The degraded view and its scale to the original's pixels."""
    import cv2

    if kind == "half":
        return cv2.resize(g, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA), 0.5
    if kind == "quarter":
        return cv2.resize(g, None, fx=0.25, fy=0.25, interpolation=cv2.INTER_AREA), 0.25
    if kind == "blur 1.5":
        return cv2.GaussianBlur(g, (0, 0), 1.5), 1.0
    if kind == "JPEG 30":
        return cv2.imdecode(cv2.imencode(".jpg", g, [cv2.IMWRITE_JPEG_QUALITY, 30])[1], 0), 1.0
    if kind == "noise 8":
        return np.clip(g + rng.normal(0, 8, g.shape), 0, 255).astype(np.uint8), 1.0
    if kind == "dark x0.25":
        return (g.astype(np.float64) * 0.25).astype(np.uint8), 1.0
    if kind == "left 55 %":
        return np.ascontiguousarray(g[:, : int(g.shape[1] * 0.55)]), 1.0
    raise ValueError(kind)


KINDS = ("half", "quarter", "blur 1.5", "JPEG 30", "noise 8", "dark x0.25", "left 55 %")


def _cv(detector: Any, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    corners, ids, _, _ = detector.detectBoard(g)
    if ids is None:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    return ids.ravel().astype(np.int64), corners.reshape(-1, 2).astype(np.float64)


def _rms(views: list[tuple[np.ndarray, np.ndarray]], obj: np.ndarray, shape: Any) -> str:
    import cv2

    if len(views) < 3:
        return "-"
    objs = [obj[i].astype(np.float32) for i, _ in views]
    pts = [xy.astype(np.float32) for _, xy in views]
    rms, *_ = cv2.calibrateCamera(objs, pts, (shape[1], shape[0]), None, None)
    return f"{rms:.3f}"


def _rms_imageform(views: list[tuple[np.ndarray, np.ndarray]], obj: np.ndarray, shape: Any) -> str:
    from imageform.geometry import calibrate_camera

    if len(views) < 3:
        return "-"
    res = calibrate_camera([obj[i] for i, _ in views], [xy for _, xy in views], shape[::-1])
    return f"{res.rms:.3f}"


def run_set(
    s: PhotoSet, folder: Path, rng: np.random.Generator, repeat: int = 5
) -> tuple[list[object], list[list[object]]] | None:
    import cv2

    from imageform.geometry import CharucoBoard, detect_charuco

    files = sorted(folder.glob(s.pattern))
    if not files:
        return None
    if s.first_marker and "first_marker" not in CharucoBoard.__dataclass_fields__:
        return [s.name, len(files), "(no first_marker in this version)"], []
    extra = {"first_marker": s.first_marker} if s.first_marker else {}
    board = CharucoBoard(s.squares, s.square, s.marker, s.dictionary, **extra)
    cv_board = cv2.aruco.CharucoBoard(
        s.squares,
        s.square,
        s.marker,
        cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, CV_DICTS[s.dictionary])),
        np.arange(s.first_marker, s.first_marker + board.n_markers),
    )
    cv_board.setLegacyPattern(s.legacy)
    detector = cv2.aruco.CharucoDetector(cv_board)
    obj = board.corner_points()
    greys = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE) for f in files]
    n_ours = n_theirs = six_ours = six_theirs = only_ours = only_theirs = 0
    apart: list[float] = []
    t_ours, t_theirs = [], []
    v_ours: list[tuple[np.ndarray, np.ndarray]] = []
    v_theirs: list[tuple[np.ndarray, np.ndarray]] = []
    refs = []
    detect_charuco(greys[0], board)  # untimed: numba's cache loaded, buffers made
    _cv(detector, greys[0])
    for g in greys:
        mine, other = [], []
        for _ in range(max(1, repeat)):
            t0 = time.process_time()
            found = detect_charuco(g, board)
            mine.append(time.process_time() - t0)
            t0 = time.process_time()
            ids, xy = _cv(detector, g)
            other.append(time.process_time() - t0)
        t_ours.append(statistics.median(mine))
        t_theirs.append(statistics.median(other))
        n_ours, n_theirs = n_ours + len(found), n_theirs + len(ids)
        six_ours += len(found) >= 6
        six_theirs += len(ids) >= 6
        common, a, b = np.intersect1d(found.ids, ids, return_indices=True)
        d = np.hypot(*(found.corners[a] - xy[b]).T)
        apart.extend(d.tolist())
        only_ours += len(found) - len(common)
        only_theirs += len(ids) - len(common)
        if len(found) >= 6:
            v_ours.append((found.ids, found.corners))
        if len(ids) >= 6:
            v_theirs.append((ids, xy))
        ok = d < 0.5
        mean = 0.5 * (found.corners[a] + xy[b])
        refs.append(dict(zip(common[ok].tolist(), mean[ok], strict=True)))
    ap = np.asarray(apart) if apart else np.zeros(1)
    summary: list[object] = [
        s.name,
        len(files),
        f"{n_ours} / {n_theirs}",
        f"{six_ours} / {six_theirs}",
        f"{len(apart)}: {np.median(ap):.3f} / {ap.max():.2f}",
        f"{only_ours} / {only_theirs}",
        f"{_rms(v_ours, obj, greys[0].shape)} / {_rms(v_theirs, obj, greys[0].shape)}",
        _rms_imageform(v_ours, obj, greys[0].shape),
        f"{1000 * statistics.median(t_ours):.0f} / {1000 * statistics.median(t_theirs):.0f}",
    ]
    rows = []
    n_ref = sum(len(r) for r in refs)
    for kind in KINDS if n_ref else ():
        got = {"ours": [0, 0, 0], "theirs": [0, 0, 0]}  # found of the reference, off, all
        for g, ref in zip(greys, refs, strict=True):
            view, scale = degrade(g, kind, rng)
            found = detect_charuco(view, board)
            ids, xy = _cv(detector, view)
            for who, (i_s, p_s) in (("ours", (found.ids, found.corners)), ("theirs", (ids, xy))):
                got[who][2] += len(i_s)
                for i, p in zip(i_s.tolist(), p_s, strict=True):
                    if i in ref:
                        q = (ref[i] + 0.5) * scale - 0.5
                        got[who][0] += 1
                        got[who][1] += bool(np.hypot(*(p - q)) > max(1.5 * scale, 0.5))
        rows.append(
            [
                s.name,
                kind,
                n_ref,
                f"{got['ours'][0]} ({got['ours'][2]})",
                got["ours"][1],
                f"{got['theirs'][0]} ({got['theirs'][2]})",
                got["theirs"][1],
            ]
        )
    return summary, rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("photos", type=Path, help="folder with a subfolder per set (see SETS)")
    ap.add_argument("--only", nargs="*", default=[], help="set names")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs a view (median)")
    ns = ap.parse_args()
    import os

    import cv2

    cv2.setNumThreads(1)
    rng = np.random.default_rng(0)
    summaries, rows, used = [], [], []
    for s in SETS:
        if ns.only and s.name not in ns.only:
            continue
        res = run_set(s, ns.photos / (s.folder or s.name), rng, ns.repeat)
        if res is None:
            print(f"(no photographs for {s.name} under {ns.photos})", file=sys.stderr)
            continue
        summaries.append(res[0])
        rows.extend(res[1])
        used.append(s)
    load = os.getloadavg()[0]
    print(header("ChArUco corners in real photographs: imageform vs OpenCV 5.0"))
    print(f"Machine load average {load:.1f} when run (shared; times are CPU times).\n")
    print("Photographs (third-party, not in this repository):\n")
    for s in used:
        board = f"{s.squares[0]} x {s.squares[1]} squares, {s.dictionary}, "
        board += f"square/marker {s.square:g}/{s.marker:g}"
        legacy = ", OpenCV legacy layout" if s.legacy else ""
        if s.first_marker:
            print(f"- `{s.name}`: {s.what}")
            continue
        print(f"- `{s.name}`: {s.source}; licence {s.licence}; {board}{legacy}; {s.what}")
    print()
    print(
        markdown_table(
            [
                "set",
                "views",
                "corners ours / OpenCV",
                "views >= 6 ours / OpenCV",
                "common ids: apart median / max px",
                "ids only ours / only OpenCV",
                "cv2.calibrateCamera RMS px ours / OpenCV",
                "calibrate_camera RMS px ours",
                "CPU ms per view ours / OpenCV",
            ],
            summaries,
        )
    )
    print(
        "Degraded views against the reference (corners both put within 0.5 px of each other "
        "in the undegraded view); found of the reference (all found), and found more than "
        "1.5 px (scaled, at least 0.5 px) off it:\n"
    )
    print(
        markdown_table(
            [
                "set",
                "degraded",
                "reference corners",
                "ours found (all)",
                "ours off",
                "OpenCV found (all)",
                "OpenCV off",
            ],
            rows,
        )
    )


if __name__ == "__main__":
    main()
