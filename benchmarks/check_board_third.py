"""Calibration boards in fresh real photographs (third round): ChArUco, auto-sized grids, tracking.

Three checks, each printing a markdown table.

``charuco PHOTOS``: ChArUco corners in real photographs from public repositories not used by
``check_charuco_real.py`` (``SETS`` below: repository, commit, path, licence). Put each set's
files in a folder of its name under ``PHOTOS`` (``git show COMMIT:PATH`` in a clone gives
them). The sets were split by source into a tuning half and a held-out half before any
was run (``heldout`` below); the held-out half was run once, with the final rules. Both
detectors get the same uint8 grey image: OpenCV's ``CharucoDetector`` (default parameters,
the set's board, ``setLegacyPattern`` as printed) and imageform's ``detect_charuco``. Per
set: corners found, views with at least 6, false corners (those farther than a quarter of
the local square from the homography fitted to the view's corners by least median of squares,
``cv2.findHomography(..., cv2.LMEDS)``: a corner on the wrong square or off any corner; the
square's size in pixels is the homography's local scale), corners both find and how far
apart, and the RMS reprojection error of ``cv2.calibrateCamera`` on the views both find
(at least 6 corners each, of the set's first view's size; each detector's own corners of those
views). CPU time per view: the process's, one thread each, after one untimed call of each on
the set's first view; median over the views.

``auto DIR``: ``find_checkerboard(..., pattern_size="auto")`` against the declared size on
greninja09/Camera_Calibration's views (``DIR/*.jpg``, 9 x 6 inner corners): the size found
and whether it is the board's.

``track DIR``: ``imageform.workflows.track``'s per-frame board search on a clip without a
board (``DIR/*.png``, frames of a real webcam), CPU time per frame, and the frames on which
the coarse-copy search for smeared boards ran; and on the same clip with a board pasted in
from a real photograph on some frames, whether every frame's corners are bit-identical with
the skipping on and off.

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``.
"""

from __future__ import annotations

import argparse
import os
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
    """A folder of real photographs of one ChArUco board, and where they came from."""

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
    heldout: bool


SETS = (
    PhotoSet(
        "cr139",
        "github.com/cr139139/charuco_calibration images/1.png ... 125.png @ 7aac620",
        "none stated",
        "*.png",
        (11, 8),
        30.0,
        22.0,
        "5x5_100",
        True,
        "robot-arm camera 640 x 480 (RealSense colour) of the board shown on a monitor, 125 views",
        False,
    ),
    PhotoSet(
        "saroj",
        "github.com/SarojDebnath/CharuCO_Calibration images/0.jpg ... 7.jpg @ 72571ba",
        "none stated",
        "*.jpg",
        (7, 5),
        20.0,
        10.0,
        "6x6_250",
        False,
        "webcam 640 x 480 in a warehouse, printed board held up, one view with no board",
        False,
    ),
    PhotoSet(
        "alexera",
        "github.com/AlexEra/camera_calibrating_Charuco res0.png ... res5.png @ 80d553b",
        "none stated",
        "*.png",
        (4, 4),
        45.0,
        30.0,
        "5x5_100",
        True,
        "webcam 640 x 480, printed board filling the frame, 6 views",
        True,
    ),
    PhotoSet(
        "caraido",
        "github.com/caraido/charuco multimedia/test.jpeg, test_1.jpeg @ bfc1bf0",
        "none stated",
        "*.jpeg",
        (9, 9),
        25.0,
        12.5,
        "4x4_50",
        False,
        "phone views of a tablet showing the board, 3024 x 4032 and 1080 x 720, 2 views",
        True,
    ),
)

CV_DICTS = {
    "4x4_50": "DICT_4X4_50",
    "5x5_100": "DICT_5X5_100",
    "6x6_250": "DICT_6X6_250",
}


def _cv(detector: Any, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    corners, ids, _, _ = detector.detectBoard(g)
    if ids is None:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    return ids.ravel().astype(np.int64), corners.reshape(-1, 2).astype(np.float64)


def false_corners(ids: np.ndarray, xy: np.ndarray, obj: np.ndarray, square: float) -> int:
    """Count the corners farther than a quarter square from the view's LMedS homography."""
    import cv2

    if len(ids) < 6:
        return 0
    src = obj[ids, :2].astype(np.float64)
    h, _ = cv2.findHomography(src, xy, cv2.LMEDS)
    if h is None:
        return 0
    p = np.c_[src, np.ones(len(src))] @ h.T
    proj = p[:, :2] / p[:, 2:]
    # local scale of the homography at each corner: the image length of one square
    q = np.c_[src + [square, 0.0], np.ones(len(src))] @ h.T
    step = np.hypot(*(q[:, :2] / q[:, 2:] - proj).T)
    return int(np.sum(np.hypot(*(proj - xy).T) > 0.25 * step))


def _rms(views: list[tuple[np.ndarray, np.ndarray]], obj: np.ndarray, shape: Any) -> str:
    import cv2

    if len(views) < 3:
        return "-"
    objs = [obj[i].astype(np.float32) for i, _ in views]
    pts = [xy.astype(np.float32) for _, xy in views]
    rms, *_ = cv2.calibrateCamera(objs, pts, (shape[1], shape[0]), None, None)
    return f"{rms:.3f}"


def run_charuco(s: PhotoSet, folder: Path) -> list[object] | None:
    """One set's row: both detectors on every view."""
    import cv2

    from imageform.geometry import CharucoBoard, detect_charuco

    files = sorted(folder.glob(s.pattern))
    if not files:
        return None
    board = CharucoBoard(s.squares, s.square, s.marker, s.dictionary)
    cv_board = cv2.aruco.CharucoBoard(
        s.squares,
        s.square,
        s.marker,
        cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, CV_DICTS[s.dictionary])),
    )
    cv_board.setLegacyPattern(s.legacy)
    detector = cv2.aruco.CharucoDetector(cv_board)
    obj = board.corner_points()
    n = [0, 0]
    six = [0, 0]
    bad = [0, 0]
    t = [[], []]
    apart: list[float] = []
    both_ours: list[tuple[np.ndarray, np.ndarray]] = []
    both_theirs: list[tuple[np.ndarray, np.ndarray]] = []
    shape = None
    first = cv2.imread(str(files[0]), cv2.IMREAD_GRAYSCALE)
    detect_charuco(first, board)  # untimed: numba's cache loaded, buffers made
    _cv(detector, first)
    for f in files:
        g = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
        shape = shape or g.shape
        t0 = time.process_time()
        found = detect_charuco(g, board)
        t[0].append(time.process_time() - t0)
        t0 = time.process_time()
        ids, xy = _cv(detector, g)
        t[1].append(time.process_time() - t0)
        for k, (i_s, p_s) in enumerate(((found.ids, found.corners), (ids, xy))):
            n[k] += len(i_s)
            six[k] += len(i_s) >= 6
            bad[k] += false_corners(np.asarray(i_s), np.asarray(p_s), obj, s.square)
        _, a, b = np.intersect1d(found.ids, ids, return_indices=True)
        apart.extend(np.hypot(*(found.corners[a] - xy[b]).T).tolist())
        if len(found) >= 6 and len(ids) >= 6 and g.shape == shape:
            both_ours.append((found.ids, found.corners))
            both_theirs.append((ids, xy))
    ap = np.asarray(apart) if apart else np.zeros(1)
    return [
        s.name + (" (held out)" if s.heldout else ""),
        len(files),
        f"{n[0]} / {n[1]}",
        f"{six[0]} / {six[1]}",
        f"{bad[0]} / {bad[1]}",
        f"{len(apart)}: {np.median(ap):.3f} / {ap.max():.2f}",
        len(both_ours),
        f"{_rms(both_ours, obj, shape)} / {_rms(both_theirs, obj, shape)}",
        f"{1000 * statistics.median(t[0]):.0f} / {1000 * statistics.median(t[1]):.0f}",
    ]


def main_charuco(photos: Path, only: list[str]) -> None:
    """Print the ChArUco table for the sets under ``photos``."""
    import cv2

    cv2.setNumThreads(1)
    rows, used = [], []
    for s in SETS:
        if only and s.name not in only:
            continue
        row = run_charuco(s, photos / s.name)
        if row is None:
            print(f"(no photographs for {s.name} under {photos})", file=sys.stderr)
            continue
        rows.append(row)
        used.append(s)
    print(
        header(f"ChArUco corners in fresh real photographs: imageform vs OpenCV {cv2.__version__}")
    )
    print(f"Machine load average {os.getloadavg()[0]:.1f} when run (shared; CPU times).\n")
    print("Photographs (third-party, not in this repository):\n")
    for s in used:
        board = f"{s.squares[0]} x {s.squares[1]} squares, {s.dictionary}, "
        board += f"square/marker {s.square:g}/{s.marker:g}"
        legacy = ", printed in OpenCV's legacy layout" if s.legacy else ""
        half = "held out" if s.heldout else "tuning"
        print(f"- `{s.name}` ({half}): {s.source}; licence {s.licence}; {board}{legacy}; {s.what}")
    print()
    print(
        markdown_table(
            [
                "set",
                "views",
                "corners ours / OpenCV",
                "views >= 6 ours / OpenCV",
                "false corners ours / OpenCV",
                "common ids: apart median / max px",
                "views both find",
                "cv2.calibrateCamera RMS px there ours / OpenCV",
                "CPU ms per view ours / OpenCV",
            ],
            rows,
        )
    )


def main_auto(folder: Path) -> None:
    """Print the auto-sized search's result on each view of greninja's 9 x 6 board."""
    import cv2

    from imageform.geometry import find_checkerboard

    rows = []
    files = sorted(folder.glob("*.jpg"), key=lambda f: int(f.stem) if f.stem.isdigit() else 0)
    for f in files:
        g = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
        a = find_checkerboard(g, "auto")
        d = find_checkerboard(g, (9, 6))
        same = "-"
        if a.found and d.found and a.pattern_size == (9, 6):
            same = f"{np.abs(a.corners - d.corners).max():.2g}"
        size = f"{a.pattern_size[0]} x {a.pattern_size[1]}" if a.found else "none"
        rows.append([f.name, size, a.pattern_size == (9, 6), same, a.reason or "-"])
    print(header('find_checkerboard(..., "auto") on greninja09/Camera_Calibration (9 x 6)'))
    print(
        markdown_table(
            ["view", "auto size", "right", "corners vs (9, 6): max px", "reason if refused"],
            rows,
        )
    )


def _clip(folder: Path, first: int, n: int) -> list[np.ndarray]:
    """Frames ``first`` .. ``first + n - 1`` of the webcam's, grey."""
    import cv2

    return [
        cv2.imread(str(folder / f"{i}.png"), cv2.IMREAD_GRAYSCALE) for i in range(first, first + n)
    ]


def _boardless(folder: Path, n: int) -> tuple[list[np.ndarray], list[int]]:
    """The first ``n`` frames whose board imageform finds, the board painted out.

    The grid's hull, dilated by two squares (the paper's margin), is filled by
    ``cv2.inpaint`` (Telea); neither ``find_checkerboard(..., (8, 6))`` nor ``"auto"`` finds
    a board in any of the frames made (checked here).
    """
    import cv2

    from imageform.geometry import find_checkerboard

    frames, used = [], []
    i = 0
    while len(frames) < n and (folder / f"{i}.png").exists():
        g = cv2.imread(str(folder / f"{i}.png"), cv2.IMREAD_GRAYSCALE)
        r = find_checkerboard(g, (8, 6))
        if r.found:
            c = r.corners.reshape(6, 8, 2)
            step = float(np.median(np.hypot(*np.diff(c, axis=1).reshape(-1, 2).T)))
            mask = np.zeros_like(g)
            cv2.fillConvexPoly(
                mask, cv2.convexHull(r.corners.astype(np.float32)).astype(np.int32), 255
            )
            k = int(4 * step) | 1
            mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
            f = cv2.inpaint(g, mask, 5, cv2.INPAINT_TELEA)
            if find_checkerboard(f, (8, 6)).found or find_checkerboard(f, "auto").found:
                raise RuntimeError(f"frame {i}: a board is still found once painted out")
            frames.append(f)
            used.append(i)
        i += 1
    return frames, used


def _run_tracker(frames: list[np.ndarray], skip: bool) -> tuple[list[Any], list[float], int]:
    """Each frame's pose, CPU seconds, and the coarse-copy searches made, skipping or not."""
    import imageform.geometry.checkerboard as cb
    import imageform.geometry.tracking as tr
    from imageform.geometry import BoardTracker

    h, w = frames[0].shape
    K = np.array([[1400.0, 0, w / 2], [0, 1400.0, h / 2], [0, 0, 1]])
    tracker = BoardTracker((8, 6), K, square=25.0)
    calls = [0]
    blurred = cb._blurred

    def counted(*a: Any, **k: Any) -> Any:
        calls[0] += 1
        return blurred(*a, **k)

    patience = tr._SMEAR_PATIENCE
    cb._blurred = counted  # type: ignore[assignment]
    tr._SMEAR_PATIENCE = patience if skip else 10**9
    poses, times = [], []
    try:
        for f in frames:
            t0 = time.process_time()
            poses.append(tracker.update(f))
            times.append(time.process_time() - t0)
    finally:
        cb._blurred = blurred  # type: ignore[assignment]
        tr._SMEAR_PATIENCE = patience
    return poses, times, calls[0]


def _same(a: Any, b: Any) -> bool:
    if a.found != b.found or a.searched != b.searched:
        return False
    same = np.array_equal(a.image_points, b.image_points)
    return bool(same and (not a.found or np.array_equal(a.rvec, b.rvec)))


def main_track(folder: Path, n: int, rounds: int) -> None:
    """Print the tracker's cost on board-less webcam frames, skipping the search or not."""
    import cv2

    cv2.setNumThreads(1)
    from imageform.geometry import tracking

    less, used = _boardless(folder, n)
    visible = _clip(folder, 0, n)
    half = n // 2
    clips = {
        f"board-less: {n} frames, the board painted out": less,
        f"board visible: frames 0-{n - 1}": visible,
        f"board-less {n} frames, then frames 0-{half - 1} with the board": less + visible[:half],
    }
    print(f"Board-less frames made from frames {', '.join(map(str, used))}.", file=sys.stderr)
    patience = tracking._SMEAR_PATIENCE
    rows = []
    for name, frames in clips.items():
        _run_tracker(frames[:2], True)  # untimed: numba's cache loaded
        per: dict[bool, list[float]] = {True: [], False: []}
        t: dict[bool, list[float]] = {}
        got: dict[bool, tuple[list[Any], int]] = {}
        for _ in range(rounds):  # interleaved, the median of the rounds' totals
            for skip in (False, True):
                poses, times, calls = _run_tracker(frames, skip)
                per[skip].append(sum(times))
                t[skip] = times
                got[skip] = (poses, calls)
        same = sum(_same(a, b) for a, b in zip(got[False][0], got[True][0], strict=True))
        found = [sum(p.found for p in got[k][0]) for k in (False, True)]
        off, on = statistics.median(per[False]), statistics.median(per[True])
        tail = [statistics.median(t[k][patience:]) for k in (False, True)]
        rows.append(
            [
                name,
                len(frames),
                f"{found[0]} / {found[1]}",
                f"{got[False][1]} / {got[True][1]}",
                f"{1000 * off / len(frames):.0f} / {1000 * on / len(frames):.0f}",
                f"{off / on:.2f}x",
                f"{1000 * tail[0]:.0f} / {1000 * tail[1]:.0f}",
                f"{same} / {len(frames)}",
            ]
        )
    print(header("imageform track on webcam frames: the smeared-board search skipped or not"))
    print(f"Machine load average {os.getloadavg()[0]:.1f} at the end (shared; CPU times).\n")
    print(
        markdown_table(
            [
                "clip",
                "frames",
                "board found: always searched / skipping",
                "coarse-copy searches",
                "CPU ms per frame always / skipping",
                "speed-up",
                f"median CPU ms per frame after frame {patience}",
                "frames identical (pose, corners, how found)",
            ],
            rows,
        )
    )


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    p = sub.add_parser("charuco")
    p.add_argument("photos", type=Path)
    p.add_argument("--only", nargs="*", default=[])
    p = sub.add_parser("auto")
    p.add_argument("folder", type=Path)
    p = sub.add_parser("track")
    p.add_argument("folder", type=Path)
    p.add_argument("--frames", type=int, default=40)
    p.add_argument("--rounds", type=int, default=3)
    ns = ap.parse_args()
    if ns.what == "charuco":
        main_charuco(ns.photos, ns.only)
    elif ns.what == "auto":
        main_auto(ns.folder)
    else:
        main_track(ns.folder, ns.frames, ns.rounds)
