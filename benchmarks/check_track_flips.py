"""Which of two fitting poses the marker trackers keep: flips, refusals, rendered and real.

A marker (or a planar map of markers) nearly face-on admits two poses that fit its corners
about as well (IPPE's two solutions: the true tilt and its mirror about the line of sight).
This script counts, per sequence and tracker, the frames with a pose, the frames *flipped*
(the pose's rotation nearer the mirrored pose than the truth, where the two are more than 5
degrees apart), and the frames refused as ambiguous (``searched == "ambiguous"``).

Rendered (``tests/video_scenes``; f = 520 px, 640 x 360; the truth known):

- **one marker**: ``check_track_marker.py``'s near-frontal sequence (a 40 mm marker at
  700 mm, about 30 px, tilt 48 -> 6-10 degrees), a one-marker ``MarkerMap`` and
  ``MarkerTracker``;
- **2 x 2 grid**: ``check_track_markers.py``'s near-frontal sequence (four 30 mm markers at
  800 mm, the board about 50 px);

each run three ways: *video* (the frames in order), *dropped* (every third frame blank: the
tracker loses the marker for a frame, so the frame after it has no previous frame, only the
pose of two frames before), *cold* (each frame given to a fresh tracker: a first frame).

Real (``DATA`` laid out as ``check_track_fresh.py`` says; caliscope's eight 1280 x 720
webcam sequences, 6 frames per second, a hand-held ChArUco board of 10 markers; all seen by
earlier sessions, tuning data): ``MarkerMapTracker`` with the board's ten markers as a map,
and with one marker (the one OpenCV reads in most frames); the reference is OpenCV's
``CharucoDetector`` + ``solvePnP`` on the board's corners (``check_track_fresh.run_opencv``).
A frame is flipped when the tracker's rotation is nearer the reference's mirror (IPPE's
other solution for the tracked markers' outline, projected by the reference pose) than the
reference, the two more than 5 degrees apart; "> 5 deg" counts every frame more than 5
degrees from the reference.

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``:
``python benchmarks/check_track_flips.py [DATA]`` (without DATA, the rendered tables only).
"""

from __future__ import annotations

import statistics
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table
from tests import video_scenes

K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
SIZE = (640, 360)
Pose = tuple[np.ndarray, np.ndarray]


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))


def _mirror(outline: np.ndarray, R: np.ndarray, t: np.ndarray, k: np.ndarray) -> Any:
    """The mirrored pose of a planar square ``outline`` (4, 3) seen by the pose (R, t).

    IPPE's other solution on the outline's exact projection, carried to the object's frame.
    """
    from imageform.geometry import marker_points, solve_square_pose
    from imageform.geometry.marker_map import _fit_rotation

    side = float(np.linalg.norm(outline[1] - outline[0]))
    centre = outline.mean(axis=0)
    Ri = _fit_rotation(marker_points(side), outline - centre)  # marker frame -> object
    c = outline @ R.T + t
    uv = c[:, :2] / c[:, 2:]
    uv = uv @ k[:2, :2].T + k[:2, 2]  # ideal pixels: the mirror is the lens-free geometry's
    poses = solve_square_pose(uv, side, k, refine=False)
    # the solution nearer the truth is the truth; the other its mirror
    Rm = [Rs @ Ri.T for Rs in poses.R]
    return Rm[1] if _angle(Rm[0], R) <= _angle(Rm[1], R) else Rm[0]


def _score(poses: list[Any], truth: list[Pose | None], mirrors: list[Any]) -> list[Any]:
    """Frames with a pose, ambiguous, flipped, > 5 deg off, rotation error median."""
    found = amb = flips = off = 0
    err = []
    for p, tr, m in zip(poses, truth, mirrors, strict=True):
        amb += p.searched == "ambiguous"
        if not p.found:
            continue
        found += 1
        if tr is None:
            continue
        e = _angle(p.R, tr[0])
        err.append(e)
        off += e > 5.0
        flips += m is not None and _angle(tr[0], m) > 5.0 and _angle(p.R, m) < e
    med = f"{statistics.median(err):.2f}" if err else "-"
    return [f"{found} / {len(poses)}", amb, flips, off, med]


def _run(make: Callable[[], Any], frames: list[np.ndarray], how: str) -> list[Any]:
    blank = np.full_like(frames[0], 128)
    out = []
    tracker = make()
    for i, f in enumerate(frames):
        if how == "cold":
            tracker = make()
        if how == "dropped" and i % 3 == 2:
            tracker.update(blank)
            out.append(None)
            continue
        out.append(tracker.update(f))
    return out


def rendered() -> list[tuple[str, list[Any]]]:
    from benchmarks import check_track_marker as one
    from benchmarks import check_track_markers as several
    from imageform.geometry import MarkerMap, MarkerMapTracker, MarkerTracker, marker_points

    near1 = one._near_frontal()
    rng = np.random.default_rng(3)
    f1 = [video_scenes.marker_frame(K, p, SIZE, noise=4.0, blur=0.8, rng=rng) for p in near1]
    lone = MarkerMap([7], [marker_points(one.SIDE)], "4x4_50")
    m1 = [_mirror(marker_points(one.SIDE), R, t, K) for R, t in near1]
    _, near4, f4, small = several.sequences()[3]
    outline = np.array([[0, 0, 0], [66, 0, 0], [66, 66, 0], [0, 66, 0]], float)
    m4 = [_mirror(outline, R, t, K) for R, t in near4]
    cases = [
        ("one marker", "MarkerMapTracker", lambda: MarkerMapTracker(lone, K), f1, near1, m1),
        (
            "one marker",
            "MarkerTracker",
            lambda: MarkerTracker(7, one.SIDE, K, dictionary="4x4_50"),
            f1,
            near1,
            m1,
        ),
        ("2 x 2 grid", "MarkerMapTracker", lambda: MarkerMapTracker(small, K), f4, near4, m4),
    ]
    rows = []
    for name, cls, make, frames, truth, mirrors in cases:
        for how in ("video", "dropped", "cold"):
            got = _run(make, frames, how)
            keep = [i for i, g in enumerate(got) if g is not None]
            rows.append(
                [
                    name,
                    cls,
                    how,
                    *_score(
                        [got[i] for i in keep], [truth[i] for i in keep], [mirrors[i] for i in keep]
                    ),
                ]
            )
    return [("rendered", rows)]


def real(data: Path) -> list[list[Any]]:
    import cv2

    from benchmarks.check_track_fresh import run_opencv, sequences
    from imageform.geometry import BrownConrady, CharucoBoard, MarkerMap, MarkerMapTracker

    cv2.setNumThreads(1)
    rows = []
    for seq in sequences(data, False)[:8]:
        seq.frames = seq.load()
        ref = [t.pose for t in run_opencv(seq)]
        b = seq.board
        board = CharucoBoard(b.size, b.square, b.marker, b.dictionary)
        corners = board.marker_points()
        n = len(corners)
        d = seq.dist
        dist = BrownConrady(d[0], d[1], d[2], d[3], d[4])
        whole = MarkerMap(np.arange(n), corners, b.dictionary)
        # the marker OpenCV reads in most frames
        det = cv2.aruco.ArucoDetector(
            cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, "DICT_" + b.dictionary.upper()))
        )
        seen = np.zeros(n, int)
        for g in seq.frames:
            _, ids, _ = det.detectMarkers(g)
            if ids is not None:
                for i in ids.ravel():
                    if i < n:
                        seen[i] += 1
        k = int(np.argmax(seen))
        lone = MarkerMap([k], corners[k : k + 1], b.dictionary)
        for label, mm, outline in (
            ("10 markers", whole, _board_outline(b)),
            (f"marker {k} alone", lone, corners[k]),
        ):
            mirrors = [None if r is None else _mirror(outline, r[0], r[1], seq.K) for r in ref]
            tracker = MarkerMapTracker(mm, seq.K, dist)
            got = [tracker.update(g) for g in seq.frames]
            both = [i for i, (p, r) in enumerate(zip(got, ref, strict=True)) if r is not None]
            s = _score(got, list(ref), mirrors)
            rows.append([seq.name, label, s[0], len(both), s[1], s[2], s[3], s[4]])
        seq.frames = []
    return rows


def _board_outline(b: Any) -> np.ndarray:
    """The board's inner-corner rectangle made square (its largest inscribed square)."""
    s = b.square
    side = (min(b.size) - 2) * s
    return np.array([[s, s, 0], [s + side, s, 0], [s + side, s + side, 0], [s, s + side, 0]], float)


def main() -> None:
    print(header("Which pose a marker tracker keeps: flips and refusals"))
    cols = [
        "sequence",
        "tracker",
        "frames",
        "frames with a pose",
        "refused as ambiguous",
        "flipped",
        "> 5 deg from the truth",
        "rotation error deg (median)",
    ]
    print(
        "Rendered, near-frontal (tilt 48 -> 6-10 deg): one 40 mm marker at 700 mm (30 px), "
        "noise 4, blur 0.8; a 2 x 2 grid of 30 mm markers at 800 mm (50 px). video: in order; "
        "dropped: every third frame blank (not counted); cold: each frame a first frame.\n"
    )
    for _, rows in rendered():
        print(markdown_table(cols, rows))
    if len(sys.argv) > 1:
        print(
            "\nReal: caliscope's eight webcam sequences (1280 x 720, 6 fps, tuning data); the "
            "reference is OpenCV's CharucoDetector + solvePnP on the board's corners.\n"
        )
        print(
            markdown_table(
                [
                    "sequence",
                    "map",
                    "frames with a pose",
                    "frames with a reference pose",
                    "refused as ambiguous",
                    "flipped vs the reference",
                    "> 5 deg from the reference",
                    "rotation apart deg (median)",
                ],
                real(Path(sys.argv[1])),
            )
        )


if __name__ == "__main__":
    main()
