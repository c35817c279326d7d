"""Markers read on enlarged (12 Mpx) and colour frames, and fresh photographs, vs OpenCV.

Four tables, each from the same frames given to imageform's
:func:`~imageform.geometry.detect_aruco_markers` (defaults) and OpenCV's
``cv2.aruco.ArucoDetector.detectMarkers`` (default parameters):

1. **Markers read.** caliscope's eight webcam sequences (``DATA`` laid out as
   ``check_track_fresh.py`` says; 1280 x 720, every 6th frame; tuning data seen by earlier
   sessions) as they are and enlarged 3.6 times (``cv2.resize``, bicubic: 4608 x 2592, the
   12 Mpx frames of ``check_track_large.py``), and williambittner1/charuco_task's
   photographs and video frames (every third of ``wb/data/*/*.jpg``, 4096 x 3072 and
   3840 x 2160). Per set: the markers OpenCV reads, those imageform reads, OpenCV's that
   imageform misses, imageform's that OpenCV does not read (and of those, ids not on the
   board: false), the frames where imageform reads every marker OpenCV reads, and the two
   detectors' corners apart (the largest coordinate difference of a marker's four corners,
   median over the markers both read; OpenCV's corners are contour pixels, imageform's the
   fitted sides' meeting points).
2. **Colour frames.** CPU ms a frame of the detector and of ``MarkerMapTracker`` (every frame
   searched whole) on the 41 enlarged frames of ``check_track_large.py`` (caliscope
   ``charuco_calibration`` camera 0, frames 70-110; the first ``--frames``) given grey and as
   RGB (the grey in three channels), and on the seven 4096 x 3072 colour photographs of
   ``wb`` (RGB; the first ``--frames``); OpenCV's
   ``detectMarkers`` on the same arrays (it makes a colour frame grey itself). Median over
   ``--repeat`` runs after a warm-up, one thread each.
3. **Clutter**: the markers each reads in Kodak's 24 photographs (``../shared/data/kodak``,
   none shows a marker: every one is false), as they are and enlarged 3.6 times, for five
   dictionaries.
4. **Fresh photographs** (``--fresh FRESH``): per image, the markers each reads, the ids,
   the corners apart, and the marker's pose from each (imageform's ``MarkerTracker``, a
   fresh tracker an image, on the colour image; OpenCV's corners with
   ``solvePnP(SOLVEPNP_IPPE_SQUARE)``), rotation apart in degrees and translation apart as a
   % of the distance; the camera is not known: ``f = 0.8 * width`` px, the principal point
   at the centre, no distortion, the same for both. Each image as it is and enlarged 3.6
   times. ``FRESH/tuning/*`` or, with ``--heldout``, ``FRESH/heldout/*``.

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``:
``python benchmarks/check_track_upscaled.py DATA [--fresh FRESH [--heldout]] [--repeat 3]``
``[--frames 41] [--only read|colour|clutter|fresh]``.
"""

from __future__ import annotations

import argparse
import glob
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks._common import header, markdown_table

SCALE = 3.6
KODAK = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "kodak"


def _enlarge(f: np.ndarray, s: float = SCALE) -> np.ndarray:
    import cv2

    return np.asarray(cv2.resize(f, None, fx=s, fy=s, interpolation=cv2.INTER_CUBIC))


def _cv_detector(name: str) -> Any:
    import cv2

    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, "DICT_" + name.upper()))
    return cv2.aruco.ArucoDetector(d)


def _read(frames: list[np.ndarray], name: str, n_ids: int) -> list[str]:
    """One row of table 1: the markers each detector reads in ``frames``."""
    from imageform.geometry import detect_aruco_markers

    det = _cv_detector(name)
    n_cv = n_if = missed = extra = false = whole = 0
    apart: list[float] = []
    for g in frames:
        c, ids, _ = det.detectMarkers(g)
        cv = (
            {}
            if ids is None
            else {int(i): q.reshape(4, 2) for i, q in zip(ids.ravel(), c, strict=True)}
        )
        m = detect_aruco_markers(g, name)
        ours = dict(zip(m.ids.tolist(), m.corners, strict=True))
        n_cv, n_if = n_cv + len(cv), n_if + len(ours)
        missed += len(set(cv) - set(ours))
        whole += set(cv) <= set(ours)
        more = set(ours) - set(cv)
        extra += len(more)
        false += sum(i >= n_ids for i in more)
        apart += [float(np.abs(ours[i] - cv[i]).max()) for i in set(cv) & set(ours)]
    return [
        str(n_cv),
        str(n_if),
        str(missed),
        f"{extra} ({false})",
        f"{whole} / {len(frames)}",
        f"{statistics.median(apart):.2f}" if apart else "-",
    ]


def table_read(data: Path) -> str:
    import cv2

    from benchmarks.check_track_fresh import sequences

    rows = []
    for seq in sequences(data, False)[:8]:
        frames = seq.load()[::6]
        for label, fr in (("1280 x 720", frames), ("x 3.6: 4608 x 2592", None)):
            if fr is None:
                fr = [_enlarge(f) for f in frames]
            rows.append([seq.name, label, str(len(fr)), *_read(fr, "4x4_50", 10)])
            del fr
    wb = sorted(glob.glob(str(data / "wb" / "data" / "*" / "*.jpg")))[::3]
    frames = [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in wb]
    rows.append(
        [
            "bittner photographs and video",
            "4096 x 3072, 3840 x 2160",
            str(len(frames)),
            *_read(frames, "6x6_250", 17),
        ]
    )
    return markdown_table(
        [
            "frames",
            "size",
            "frames",
            "markers OpenCV reads",
            "markers imageform reads",
            "OpenCV's imageform misses",
            "imageform's OpenCV does not read (ids off the board)",
            "frames with all of OpenCV's",
            "corners apart px (median)",
        ],
        rows,
    )


def _cpu_ms(step: Callable[[np.ndarray], object], frames: list[np.ndarray]) -> float:
    t0 = time.process_time()
    for g in frames:
        step(g)
    return 1e3 * (time.process_time() - t0) / len(frames)


def table_colour(data: Path, repeat: int, count: int = 41) -> str:
    import cv2

    from benchmarks.check_track_fresh import sequences
    from imageform.geometry import MarkerMap, MarkerMapTracker, detect_aruco_markers

    cam = sequences(data, False)[0]
    big = [_enlarge(f) for f in cam.load()[70 : 70 + count]]
    rgb = [np.repeat(g[..., None], 3, axis=2) for g in big]
    wb = sorted(
        p
        for sub in ("clean", "occlusion", "motionblur")
        for p in glob.glob(str(data / "wb" / "data" / sub / "*.jpg"))
    )
    photos = [np.ascontiguousarray(cv2.imread(p)[..., ::-1]) for p in wb[:count]]
    b = cam.board
    from imageform.geometry import CharucoBoard

    corners = CharucoBoard(b.size, b.square, b.marker, b.dictionary).marker_points()
    whole = MarkerMap(np.arange(len(corners)), corners, b.dictionary)
    K = np.asarray(cam.K, np.float64).copy()
    K[:2, :2] *= SCALE
    K[:2, 2] = (K[:2, 2] + 0.5) * SCALE - 0.5
    det4, det6 = _cv_detector("4x4_50"), _cv_detector("6x6_250")

    def tracker() -> Callable[[np.ndarray], object]:
        tr = MarkerMapTracker(whole, K, predict=False)
        return tr.update

    cases: list[tuple[str, str, list[np.ndarray], Callable[[], Callable], Callable]] = [
        (
            "12 Mpx enlarged webcam, grey",
            "detect_aruco_markers",
            big,
            lambda: lambda g: detect_aruco_markers(g, "4x4_50"),
            det4.detectMarkers,
        ),
        (
            "12 Mpx enlarged webcam, RGB",
            "detect_aruco_markers",
            rgb,
            lambda: lambda g: detect_aruco_markers(g, "4x4_50"),
            det4.detectMarkers,
        ),
        (
            "12 Mpx enlarged webcam, RGB",
            "MarkerMapTracker (predict=False)",
            rgb,
            tracker,
            det4.detectMarkers,
        ),
        (
            "photographs 4096 x 3072, RGB",
            "detect_aruco_markers",
            photos,
            lambda: lambda g: detect_aruco_markers(g, "6x6_250"),
            det6.detectMarkers,
        ),
    ]
    rows = []
    for label, what, frames, make, theirs in cases:
        _cpu_ms(make(), frames[:3]), _cpu_ms(theirs, frames[:3])  # warm-up
        a, o = [], []
        for _ in range(repeat):
            a.append(_cpu_ms(make(), frames))
            o.append(_cpu_ms(theirs, frames))
        ma, mo = statistics.median(a), statistics.median(o)
        shape = frames[0].shape
        rows.append(
            [label, what, f"{len(frames)} x {shape[1]} x {shape[0]}", f"{ma:.1f}", f"{mo:.1f}"]
            + [f"{ma / mo:.2f}"]
        )
    return markdown_table(
        [
            "frames",
            "imageform",
            "frames x width x height",
            "imageform ms a frame",
            "OpenCV detectMarkers ms a frame",
            "ratio",
        ],
        rows,
    )


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra @ Rb.T) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def table_fresh(folder: Path) -> str:
    import cv2

    from imageform.geometry import MarkerTracker, detect_aruco_markers

    side = 1.0
    obj = (
        np.array([[-0.5, 0.5, 0], [0.5, 0.5, 0], [0.5, -0.5, 0], [-0.5, -0.5, 0]], np.float64)
        * side
    )
    rows = []
    for path in sorted(folder.glob("*")):
        bgr = cv2.imread(str(path))
        for label, s in (("as it is", 1.0), ("x 3.6", SCALE)):
            img = bgr if s == 1.0 else _enlarge(bgr, s)
            rgb = np.ascontiguousarray(img[..., ::-1])
            h, w = rgb.shape[:2]
            K = np.array([[0.8 * w, 0, (w - 1) / 2], [0, 0.8 * w, (h - 1) / 2], [0, 0, 1]])
            c, ids, _ = _cv_detector("4x4_50").detectMarkers(img)
            cv = (
                {}
                if ids is None
                else {int(i): q.reshape(4, 2) for i, q in zip(ids.ravel(), c, strict=True)}
            )
            detect_aruco_markers(rgb, "4x4_50")  # warm-up: compiled, buffers made
            t0 = time.process_time()
            m = detect_aruco_markers(rgb, "4x4_50")
            ms = 1e3 * (time.process_time() - t0)
            ours = dict(zip(m.ids.tolist(), m.corners, strict=True))
            both = sorted(set(cv) & set(ours))
            apart = max((float(np.abs(ours[i] - cv[i]).max()) for i in both), default=np.nan)
            rot, tra, note = [], [], []
            for i in both:
                ok, rv, tv = cv2.solvePnP(obj, cv[i], K, None, flags=cv2.SOLVEPNP_IPPE_SQUARE)
                pose = MarkerTracker(i, side, K, dictionary="4x4_50").update(rgb)
                if not (ok and pose.found):
                    note.append(f"{i}: {pose.searched if not pose.found else 'OpenCV none'}")
                    continue
                Rc = cv2.Rodrigues(rv)[0]
                rot.append(_angle(pose.R, Rc))
                tv = tv.ravel()
                tra.append(100 * float(np.linalg.norm(pose.tvec - tv) / np.linalg.norm(tv)))
            rows.append(
                [
                    path.name,
                    label,
                    f"{w} x {h}",
                    str(sorted(cv)),
                    str(sorted(ours)),
                    f"{apart:.2f}",
                    ", ".join(f"{r:.2f}" for r in rot) or "-",
                    ", ".join(f"{t:.2f}" for t in tra) or "-",
                    "; ".join(note) or "-",
                    f"{ms:.0f}",
                ]
            )
    return markdown_table(
        [
            "image",
            "enlarged",
            "width x height",
            "OpenCV's ids",
            "imageform's ids",
            "corners apart px (largest)",
            "rotation apart deg",
            "translation apart %",
            "imageform no pose",
            "imageform ms (detector, RGB, second call)",
        ],
        rows,
    )


def table_clutter() -> str:
    """Markers read in photographs without any (Kodak's 24, ``../shared/data/kodak``): false."""
    import cv2

    paths = sorted(glob.glob(str(KODAK / "kodim*.png")))
    rows = []
    for name in ("4x4_50", "4x4_1000", "5x5_100", "6x6_250", "aruco_original"):
        from imageform.geometry import detect_aruco_markers

        det = _cv_detector(name)
        for s in (1.0, SCALE):
            ours = theirs = 0
            for p in paths:
                g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
                g = g if s == 1.0 else _enlarge(g, s)
                ours += len(detect_aruco_markers(g, name))
                _, ids, _ = det.detectMarkers(g)
                theirs += 0 if ids is None else len(ids)
            rows.append([name, "as they are" if s == 1.0 else "x 3.6", str(ours), str(theirs)])
    return markdown_table(
        ["dictionary", "photographs", "imageform's markers (false)", "OpenCV's (false)"], rows
    )


def main() -> None:
    import cv2

    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("--fresh", type=Path)
    ap.add_argument("--heldout", action="store_true")
    ap.add_argument("--only", choices=("read", "colour", "fresh", "clutter"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--frames", type=int, default=41, help="frames of table 2's sets, at most")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    print(header("Markers read on enlarged, colour and fresh frames: imageform vs OpenCV"))
    if args.only in (None, "read"):
        print("\n## Markers read\n")
        print(table_read(args.data))
    if args.only in (None, "colour"):
        print(f"\n## Colour frames: CPU ms a frame (median of {args.repeat} runs)\n")
        print(table_colour(args.data, args.repeat, args.frames))
    if args.only in (None, "clutter"):
        print(f"\n## Photographs without markers: {len(glob.glob(str(KODAK / '*.png')))}\n")
        print(table_clutter())
    if args.fresh is not None and args.only in (None, "fresh"):
        half = "heldout" if args.heldout else "tuning"
        print(f"\n## Fresh photographs: {half}\n")
        print(table_fresh(args.fresh / half))


if __name__ == "__main__":
    main()
