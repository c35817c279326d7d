"""Several ArUco markers on one object (a marker map) tracked by imageform and by OpenCV.

Rendered sequences with known poses (``tests/video_scenes.map_frame``: imageform's marker
images warped at 4x4 supersampling, Gaussian blur, sensor noise; f = 520 px, 640 x 360):

- **grid**: a 4 x 3 grid of 30 mm markers (8 mm apart, 4x4_50) seen from a path around it
  at about 450 mm (markers about 35 px);
- **grid, occluded and misread**: the same frames with a bar (a hand, an instrument) across
  a third of the board, and marker 5's place printed with marker 0 (id 0 twice, one of
  them where the map does not have it);
- **cube**: five faces of a 50 mm cube each carrying a 36 mm marker (ids 10-14), seen from
  a path around it at about 400 mm (two or three faces at a time);
- **near-frontal**: a 2 x 2 grid of 30 mm markers at 800 mm (the board about 50 px) whose
  tilt settles from 48 to 6-10 degrees, where the mirrored pose fits about as well.

Methods: ``imageform.geometry.MarkerMapTracker`` (with and without continuity), OpenCV's
``ArucoDetector`` (default corners and ``CORNER_REFINE_SUBPIX``), then
``cv2.aruco.Board(objPoints, dictionary, ids).matchImagePoints`` and ``solvePnP`` (its
default iterative method) over all matched corners. Corner error: the corners each method
used against their true projection (the map's corners of their id), the median per frame.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table
from tests import video_scenes

K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
SIZE = (640, 360)

Pose = tuple[np.ndarray, np.ndarray]
Got = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None


def cube_map(side: float = 50.0, marker: float = 36.0, first_id: int = 10):  # type: ignore[no-untyped-def]
    """Five faces of a cube centred at the origin (all but -z), a marker on each."""
    from imageform.geometry import MarkerMap, marker_points

    faces = [
        ((0, 0, 1), (1, 0, 0)),
        ((1, 0, 0), (0, 1, 0)),
        ((-1, 0, 0), (0, -1, 0)),
        ((0, 1, 0), (-1, 0, 0)),
        ((0, -1, 0), (1, 0, 0)),
    ]
    corners = []
    for n, x in faces:
        nz, nx = np.array(n, float), np.array(x, float)
        R = np.column_stack([nx, np.cross(nz, nx), nz])
        corners.append(marker_points(marker) @ R.T + nz * side / 2)
    return MarkerMap(first_id + np.arange(5), np.array(corners), "4x4_50")


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))


def _project(X: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    c = X @ R.T + t
    return c[:, :2] / c[:, 2:] * K[0, 0] + K[:2, 2]


def _around(n: int, centre: np.ndarray, radius: tuple[float, float], distance: float) -> list[Pose]:
    from imageform.geometry import look_at

    out = []
    for i in range(n):
        a = 2 * np.pi * i / n
        eye = centre + np.array([radius[0] * np.cos(a), radius[1] * np.sin(a), -distance])
        p = look_at(eye, centre + [5 * np.sin(a), 0.0, 0.0], up=(0.0, -1.0, 0.0))
        out.append((np.asarray(p.R, np.float64), np.asarray(p.t, np.float64)))
    return out


def _cube_path(n: int) -> list[Pose]:
    from imageform.geometry import look_at

    out = []
    for i in range(n):
        a = 2 * np.pi * i / n
        eye = 400 * np.array([np.cos(a) * 0.8, np.sin(a) * 0.8, 0.6])
        p = look_at(eye, np.zeros(3), up=(0.0, 0.0, 1.0))
        out.append((np.asarray(p.R, np.float64), np.asarray(p.t, np.float64)))
    return out


def _near_frontal(n: int = 60) -> list[Pose]:
    from imageform.geometry import rvec_to_matrix

    out = []
    for i in range(n):
        tilt = 40 * np.exp(-i / 4) + 8 + 2 * np.sin(i / 3)
        R = np.asarray(rvec_to_matrix(np.array([0.6, 0.8, 0.0]) * np.radians(tilt)))
        c = R @ np.array([33.0, 33.0, 0.0])  # the board's centre on the line of sight
        out.append((R, np.array([20 * np.sin(i / 5), 10.0, 800.0]) - c))
    return out


def _occlude(frame: np.ndarray, i: int) -> np.ndarray:
    import cv2

    f = frame.copy()
    x = 200 + 12 * (i % 12)
    pts = np.array([[x, 0], [x + 70, 0], [x + 130, 360], [x + 60, 360]], np.int32)
    cv2.fillConvexPoly(f, pts, 150)
    return f


def _opencv(marker_map: object, subpix: bool) -> Callable[[np.ndarray], Got]:
    import cv2

    params = cv2.aruco.DetectorParameters()
    if subpix:
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    det = cv2.aruco.ArucoDetector(dictionary, params)
    obj = [np.asarray(c, np.float32) for c in marker_map.corners]  # type: ignore[attr-defined]
    board = cv2.aruco.Board(obj, dictionary, np.asarray(marker_map.ids, np.int32))  # type: ignore[attr-defined]

    def pose(image: np.ndarray) -> Got:
        corners, ids, _ = det.detectMarkers(image)
        if ids is None:
            return None
        X, uv = board.matchImagePoints(corners, ids)
        if X is None or len(X) < 4:
            return None
        ok, rv, tv = cv2.solvePnP(X, uv, K, None)
        if not ok:
            return None
        return cv2.Rodrigues(rv)[0], tv.ravel(), uv.reshape(-1, 2), X.reshape(-1, 3)

    return pose


def _imageform(marker_map: object, continuity: bool) -> Callable[[np.ndarray], Got]:
    from imageform.geometry import MarkerMapTracker

    tracker = MarkerMapTracker(marker_map, K, continuity=continuity)  # type: ignore[arg-type]

    def pose(image: np.ndarray) -> Got:
        p = tracker.update(image)
        return (p.R, p.tvec, p.image_points, p.object_points) if p.found else None

    return pose


METHODS = {
    "imageform MarkerMapTracker": lambda m: _imageform(m, True),
    "imageform, no continuity": lambda m: _imageform(m, False),
    "OpenCV ArucoDetector + Board + solvePnP": lambda m: _opencv(m, False),
    "OpenCV, CORNER_REFINE_SUBPIX": lambda m: _opencv(m, True),
}


def _run(truth: list[Pose], frames: list[np.ndarray], marker_map: object, name: str) -> list:
    pose = METHODS[name](marker_map)
    found = off = 0
    cerr, terr, rerr, ms = [], [], [], []
    for (R, t), f in zip(truth, frames, strict=True):
        t0 = time.process_time()
        got = pose(f)
        ms.append(1000 * (time.process_time() - t0))
        if got is None:
            continue
        Rg, tg, uv, X = got
        found += 1
        cerr.append(float(np.median(np.linalg.norm(uv - _project(X, R, t), axis=1))))
        terr.append(100 * float(np.linalg.norm(tg - t) / np.linalg.norm(t)))
        rerr.append(_angle(Rg, R))
        off += rerr[-1] > 5
    fmt = lambda v, d: f"{statistics.median(v):.{d}f} / {max(v):.{d}f}" if v else "-"  # noqa: E731
    return [
        name,
        f"{found} / {len(frames)}",
        off,
        fmt(cerr, 2),
        fmt(terr, 2),
        fmt(rerr, 2),
        f"{statistics.median(ms):.1f}",
    ]


def sequences() -> list[tuple[str, list[Pose], list[np.ndarray], object]]:
    """The four rendered sequences: (title, truth, frames, map)."""
    from imageform.geometry import MarkerMap, grid_marker_map

    grid = grid_marker_map((4, 3), 30.0, 8.0, dictionary="4x4_50")
    path = _around(36, np.array([72.0, 53.0, 0.0]), (110.0, 80.0), 450.0)
    rng = np.random.default_rng(11)
    frames = [video_scenes.map_frame(K, p, SIZE, grid, noise=2.0, blur=0.7, rng=rng) for p in path]
    rng = np.random.default_rng(12)
    bad = [
        _occlude(
            video_scenes.map_frame(K, p, SIZE, grid, drawn={5: 0}, noise=2.0, blur=0.7, rng=rng),
            i,
        )
        for i, p in enumerate(path)
    ]
    cube = cube_map()
    cpath = _cube_path(36)
    rng = np.random.default_rng(13)
    cframes = [
        video_scenes.map_frame(K, p, SIZE, cube, noise=2.0, blur=0.7, rng=rng) for p in cpath
    ]
    small: MarkerMap = grid_marker_map((2, 2), 30.0, 6.0, dictionary="4x4_50")
    near = _near_frontal()
    rng = np.random.default_rng(14)
    nframes = [
        video_scenes.map_frame(K, p, SIZE, small, noise=4.0, blur=0.8, rng=rng) for p in near
    ]
    return [
        ("Grid: 36 frames, 4 x 3 markers of 30 mm at about 450 mm (35 px), noise 2, blur 0.7 "
         "px.", path, frames, grid),
        ("Grid, occluded and misread: the same path, a bar across a third of the board, "
         "marker 5's place printed with id 0.", path, bad, grid),
        ("Cube: 36 frames around a 50 mm cube, a 36 mm marker on each of five faces, at "
         "400 mm.", cpath, cframes, cube),
        ("Near-frontal: 60 frames, 2 x 2 markers of 30 mm at 800 mm (the board about 50 px), "
         "tilt 48 -> 6-10 deg, noise 4, blur 0.8 px.", near, nframes, small),
    ]  # fmt: skip


def main() -> None:
    columns = [
        "method",
        "frames with a pose",
        "poses > 5 deg off",
        "corner error px (median / max)",
        "translation error % (median / max)",
        "rotation error deg (median / max)",
        "CPU ms per frame (median)",
    ]
    print(header("A marker map (several markers on one object): imageform vs OpenCV (rendered)"))
    for title, truth, frames, marker_map in sequences():
        print(title + "\n")
        print(markdown_table(columns, [_run(truth, frames, marker_map, m) for m in METHODS]))


if __name__ == "__main__":
    main()
