"""Board tracking in fresh real videos and image sequences: imageform's BoardTracker vs OpenCV.

Per sequence, the same uint8 grey frames, the same camera (K and Brown-Conrady distortion) and
the same board go to two loops: imageform's :class:`~imageform.geometry.BoardTracker` (defaults:
corners tracked between detections, detection in the last box first) and OpenCV's loop
(``cv2.aruco.CharucoDetector.detectBoard`` with default parameters, or
``cv2.findChessboardCornersSB`` for a checkerboard, then ``cv2.solvePnP`` (iterative) on the
corners, as ``estimatePoseCharucoBoard`` did). Both need 6 corners for a pose. Per sequence:
frames with a pose (each, both), corners per posed frame (median), the two poses apart where
both have one (rotation in degrees and translation as a % of the distance, median and 95th
percentile; a checkerboard's pose compared in both of its half-turn orders, the nearer kept),
frames with the poses more than 5 degrees apart (a flip of the planar ambiguity, or a board
found in another order), jitter on still stretches (pairs of consecutive frames where both
loops' corners moved less than ``STILL_PX`` px, median; the frame-to-frame change of the
translation as a % of the distance and of the rotation in degrees), each loop's reprojection
RMS on its own corners (median), and the CPU time per frame (median, one thread, the process's,
each sequence run twice and the second run timed: numba's compilation is out of the figure).

Where the repository calibrated a synchronised multi-camera rig (caliscope's sessions), the
board's pose in the rig's frame from each pair of cameras that both see it is a check with a
truth independent of either detector: the board is one rigid object, so the poses from two
cameras should agree up to the rig's calibration error. That table compares the two loops on the
frames where both have a pose in both cameras.

The data (not in this repository; ``DATA`` below; ``git show COMMIT:PATH`` in a clone of each
repository gives the files). The split into a tuning and a held-out half was made by
repository before anything was run; the held-out files' SHA-256 were frozen then (the
results file lists them) and the held-out half was run once, with the final code:

- tuning, ``caliscope/``: github.com/mprib/caliscope @ ddda95b (BSD-2-Clause),
  ``tests/sessions/{charuco_calibration,4_cam_recording}/calibration/extrinsic/cam_{0..3}.mp4``
  as ``{session}_cam_{k}.mp4`` and the sessions' ``camera_array.toml`` as
  ``{session}_camera_array.toml``: four synchronised 1280 x 720 webcams at 6 frames per second,
  a hand-held ChArUco board of 4 x 5 squares (54 mm, markers 40.5 mm, DICT_4X4_50 ids),
  printed inverted (``cv2.bitwise_not`` of OpenCV's drawing: the frames are inverted back
  for both loops), laminated (glare), held by hand (fingers over the board), moved fast at
  6 frames per second (motion blur);
- tuning, ``p2s/``: github.com/perfanalytics/pose2sim @ f7b39c7 (BSD-3-Clause),
  ``Pose2Sim/Demo_SinglePerson/calibration/intrinsics/int_cam0{c}_img/cam0{c}_0{i}_int.jpg``
  as ``cam0{c}_0{i}.jpg``: four cameras, seven 1088 x 1920 views each of a hand-held
  checkerboard (4 x 7 inner corners, 60 mm) close to the lens, some cut by the frame; the
  camera is calibrated here from its own seven views (OpenCV, classic corners);
- held out, ``wb/``: github.com/williambittner1/charuco_task @ 4050481 (no licence stated),
  ``data/calibration_video/frame_0000{00..22}.jpg`` (23 consecutive 3840 x 2160 frames of a
  phone's video, the phone hand-held still in front of a ChArUco board of 7 x 5 squares,
  30 mm, markers 15 mm, DICT_6X6_250) with the repository's ``camera_calibration.npz``; and
  ``data/{occlusion,motionblur,clean}/*.jpg`` (7 photographs, 4096 x 3072, a hand over the
  board, motion blur), the camera calibrated here (OpenCV) from ``data/calibration_photo``
  (the nine of its views under 4 MiB);
- held out, ``heba/``: github.com/heba266/bev_charuco @ d3ebd7e (no licence stated),
  ``images/live_check_1920x1200_01.png`` with ``intrinsics_pinhole.json``: a ChArUco board of
  11 x 8 squares (20 mm, markers 15 mm, DICT_4X4_50) on the ground, taped, seen obliquely.

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``:
``python benchmarks/check_track_fresh.py DATA [--heldout]``.
"""

from __future__ import annotations

import argparse
import glob
import json
import statistics
import sys
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402

#: Both loops' corners moved less than this (median, px) between two frames: a still pair.
STILL_PX = 0.5
#: Fewest corners for a pose, both loops (BoardTracker's default).
MIN_CORNERS = 6
#: Poses farther apart than this (degrees) are counted as disagreeing.
FLIP_DEG = 5.0


@dataclass
class Board:
    """A ChArUco board (squares, lengths in mm, dictionary) or a checkerboard's inner corners."""

    kind: str
    size: tuple[int, int]
    square: float
    marker: float = 0.0
    dictionary: str = ""


@dataclass
class Sequence:
    """Frames of one camera, its calibration and its board."""

    name: str
    board: Board
    K: np.ndarray
    dist: np.ndarray
    load: Callable[[], list[np.ndarray]]
    heldout: bool
    what: str
    rig: str = ""
    extrinsic: tuple[np.ndarray, np.ndarray] | None = None
    frames: list[np.ndarray] = field(default_factory=list)


# -- the data --------------------------------------------------------------------------------


def _video(path: Path, invert: bool, mirror: bool = False) -> Callable[[], list[np.ndarray]]:
    def load() -> list[np.ndarray]:
        import av

        with av.open(str(path)) as c:
            frames = [f.to_ndarray(format="gray") for f in c.decode(video=0)]
        frames = [np.ascontiguousarray(f[:, ::-1]) if mirror else f for f in frames]
        return [255 - f if invert else f for f in frames]

    return load


def _images(paths: list[str]) -> Callable[[], list[np.ndarray]]:
    def load() -> list[np.ndarray]:
        import cv2

        return [cv2.imread(p, cv2.IMREAD_GRAYSCALE) for p in paths]

    return load


def _calibrate_checker(paths: list[str], size: tuple[int, int], square: float) -> tuple[Any, Any]:
    import cv2

    obj = np.zeros((size[0] * size[1], 3), np.float32)
    obj[:, :2] = np.mgrid[0 : size[0], 0 : size[1]].T.reshape(-1, 2) * square
    O, I, shape = [], [], None
    for p in paths:
        g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        shape = g.shape[::-1]
        ok, c = cv2.findChessboardCorners(g, size)
        if ok:
            c = cv2.cornerSubPix(
                g,
                c,
                (11, 11),
                (-1, -1),
                (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 1e-3),
            )
            O.append(obj)
            I.append(c)
    _, K, d, _, _ = cv2.calibrateCamera(O, I, shape, None, None)
    return K, d.ravel()


def _calibrate_charuco(paths: list[str], board: Board) -> tuple[Any, Any]:
    import cv2

    cvb = _cv_board(board)
    det = cv2.aruco.CharucoDetector(cvb)
    O, I, shape = [], [], None
    for p in paths:
        g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        shape = g.shape[::-1]
        cc, ci, _, _ = det.detectBoard(g)
        if ci is not None and len(ci) >= MIN_CORNERS:
            o, i = cvb.matchImagePoints(cc, ci)
            O.append(o)
            I.append(i)
    _, K, d, _, _ = cv2.calibrateCamera(O, I, shape, None, None)
    return K, d.ravel()


def sequences(data: Path, heldout: bool) -> list[Sequence]:
    """The sequences of one half (tuning, or held out)."""
    out: list[Sequence] = []
    if not heldout:
        charuco = Board("charuco", (4, 5), 54.0, 40.5, "4x4_50")
        for session, what in (
            ("charuco_calibration", "111 frames"),
            ("4_cam_recording", "48 frames"),
        ):
            rig = tomllib.loads((data / "caliscope" / f"{session}_camera_array.toml").read_text())
            for k in range(4):
                cam = rig["cameras"][str(k)]
                K = np.array(cam["matrix"], float)
                dist = np.array(cam["distortions"], float)
                # this camera sees the board's back through the glass it is pressed in: its
                # frames are mirrored left-right for both loops (cx -> w - 1 - cx, p2 -> -p2)
                mirror = session == "4_cam_recording" and k == 1
                if mirror:
                    K[0, 2] = cam["size"][0] - 1 - K[0, 2]
                    dist[3] = -dist[3]
                out.append(
                    Sequence(
                        f"caliscope {session} cam {k}" + (" (mirrored)" if mirror else ""),
                        charuco,
                        K,
                        dist,
                        _video(data / "caliscope" / f"{session}_cam_{k}.mp4", True, mirror),
                        False,
                        f"webcam 1280 x 720, 6 fps, {what}"
                        + (", the board seen from behind, frames mirrored" if mirror else ""),
                        rig="" if mirror else session,
                        extrinsic=(np.array(cam["rotation"], float), np.array(cam["translation"])),
                    )
                )
        checker = Board("checker", (4, 7), 60.0)
        for c in range(1, 5):
            paths = sorted(glob.glob(str(data / "p2s" / f"cam0{c}_0*.jpg")))
            K, d = _calibrate_checker(paths, checker.size, checker.square)
            out.append(
                Sequence(
                    f"pose2sim cam0{c}",
                    checker,
                    K,
                    d,
                    _images(paths),
                    False,
                    "7 views 1088 x 1920, camera calibrated from them",
                )
            )
    else:
        wbb = Board("charuco", (7, 5), 30.0, 15.0, "6x6_250")
        cal = np.load(data / "wb" / "camera_calibration.npz")
        paths = sorted(glob.glob(str(data / "wb" / "data" / "calibration_video" / "*.jpg")))
        out.append(
            Sequence(
                "bittner video",
                wbb,
                cal["camera_matrix"],
                cal["dist_coeffs"].ravel(),
                _images(paths),
                True,
                "23 consecutive frames 3840 x 2160, hand-held phone",
            )
        )
        calib = sorted(glob.glob(str(data / "wb" / "data" / "calibration_photo" / "*.jpg")))
        K, d = _calibrate_charuco(calib, wbb)
        photos = [
            p
            for sub in ("clean", "occlusion", "motionblur")
            for p in sorted(glob.glob(str(data / "wb" / "data" / sub / "*.jpg")))
        ]
        out.append(
            Sequence(
                "bittner photos",
                wbb,
                K,
                d,
                _images(photos),
                True,
                "7 photographs 4096 x 3072: clean, a hand over the board, motion blur",
            )
        )
        js = json.loads((data / "heba" / "intrinsics_pinhole.json").read_text())
        out.append(
            Sequence(
                "heba live check",
                Board("charuco", (11, 8), 20.0, 15.0, "4x4_50"),
                np.array(js["K"], float),
                np.array(js["dist"], float).ravel(),
                _images([str(data / "heba" / "live_check_1920x1200_01.png")]),
                True,
                "1 frame 1920 x 1200, board on the ground",
            )
        )
    return out


# -- the two loops ---------------------------------------------------------------------------


def _cv_board(board: Board) -> Any:
    import cv2

    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, "DICT_" + board.dictionary.upper()))
    return cv2.aruco.CharucoBoard(board.size, board.square, board.marker, d)


@dataclass
class Track:
    """One loop's result on one frame (pose None when not found)."""

    pose: tuple[np.ndarray, np.ndarray] | None
    ids: np.ndarray
    uv: np.ndarray
    rms: float
    ms: float


def run_imageform(seq: Sequence, predict: bool = True) -> list[Track]:
    """imageform's BoardTracker over the frames (``predict=False``: a detection every frame)."""
    from imageform.geometry import BoardTracker, BrownConrady, CharucoBoard

    b = seq.board
    board: Any
    if b.kind == "charuco":
        board = CharucoBoard(b.size, b.square, b.marker, b.dictionary)
        pts = board.corner_points()
    else:
        board = b.size
        pts = None
    d = list(seq.dist[:5]) + [0.0] * (5 - min(5, seq.dist.size))
    tracker = BoardTracker(
        board, seq.K, BrownConrady(d[0], d[1], d[2], d[3], d[4]), square=b.square, predict=predict
    )
    out = []
    for g in seq.frames:
        t0 = time.process_time()
        p = tracker.update(g)
        ms = (time.process_time() - t0) * 1e3
        if pts is None:
            ids = np.arange(p.image_points.shape[0])
        else:
            X = p.object_points
            ids = np.array([int(np.argmin(np.sum((pts - x) ** 2, axis=1))) for x in X], dtype=int)
        pose = (np.asarray(p.R), np.asarray(p.tvec)) if p.found else None
        out.append(Track(pose, ids, p.image_points, float(p.rms_px), ms))
    return out


def run_opencv(seq: Sequence) -> list[Track]:
    """OpenCV's loop: detect (ChArUco or SB checkerboard), then solvePnP."""
    import cv2

    b = seq.board
    K, dist = seq.K.astype(np.float64), seq.dist.astype(np.float64)
    if b.kind == "charuco":
        cvb = _cv_board(b)
        det = cv2.aruco.CharucoDetector(cvb)
    else:
        obj = np.zeros((b.size[0] * b.size[1], 3), np.float64)
        obj[:, :2] = np.mgrid[0 : b.size[0], 0 : b.size[1]].T.reshape(-1, 2) * b.square
    out = []
    for g in seq.frames:
        t0 = time.process_time()
        if b.kind == "charuco":
            cc, ci, _, _ = det.detectBoard(g)
            n = 0 if ci is None else len(ci)
            if n >= MIN_CORNERS:
                o, i = cvb.matchImagePoints(cc, ci)
                ids = ci.ravel().astype(int)
                uv = cc.reshape(-1, 2).astype(np.float64)
        else:
            ok, c = cv2.findChessboardCornersSB(g, b.size)
            n = b.size[0] * b.size[1] if ok else 0
            if ok:
                o, i = obj, c.reshape(-1, 2).astype(np.float64)
                ids, uv = np.arange(n), i
        pose, rms = None, float("nan")
        if n >= MIN_CORNERS:
            ok, rv, tv = cv2.solvePnP(
                np.asarray(o, np.float64).reshape(-1, 3),
                np.asarray(i, np.float64).reshape(-1, 2),
                K,
                dist,
                flags=cv2.SOLVEPNP_ITERATIVE,
            )
            if ok and tv.ravel()[2] > 0:
                R = cv2.Rodrigues(rv)[0]
                pose = (R, tv.ravel())
                proj = cv2.projectPoints(np.asarray(o, np.float64), rv, tv, K, dist)[0]
                rms = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - uv) ** 2, axis=1))))
        ms = (time.process_time() - t0) * 1e3
        if pose is None:
            out.append(Track(None, np.zeros(0, int), np.zeros((0, 2)), float("nan"), ms))
        else:
            out.append(Track(pose, ids, uv, rms, ms))
    return out


# -- the comparisons -------------------------------------------------------------------------


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra.T @ Rb) - 1) / 2
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _half_turn(board: Board, R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A checkerboard's pose with its corners in the other (half-turned) order."""
    w = (board.size[0] - 1) * board.square
    h = (board.size[1] - 1) * board.square
    F = np.diag([-1.0, -1.0, 1.0])  # X' = F X + (w, h, 0)
    return R @ F, t + R @ np.array([w, h, 0.0])


def _apart(board: Board, a: tuple, b: tuple) -> tuple[float, float]:
    """Rotation (deg) and translation (% of distance) between two poses of the board."""
    cands = [b]
    if board.kind == "checker":
        cands.append(_half_turn(board, *b))
    best = None
    for R, t in cands:
        # compare the board's centre, not its origin corner
        if board.kind == "checker":
            c = np.array(
                [(board.size[0] - 1) * board.square / 2, (board.size[1] - 1) * board.square / 2, 0]
            )
        else:
            c = np.array([board.size[0] * board.square / 2, board.size[1] * board.square / 2, 0])
        pa = a[0] @ c + a[1]
        pb = R @ c + t
        d = (_angle(a[0], R), float(np.linalg.norm(pa - pb) / np.linalg.norm(pa) * 100))
        if best is None or d[0] < best[0]:
            best = d
    assert best is not None
    return best


def _moved(a: Track, b: Track) -> float:
    """Median move (px) of the corners two frames share; inf without 3 in common."""
    common, ia, ib = np.intersect1d(a.ids, b.ids, return_indices=True)
    if common.size < 3:
        return float("inf")
    return float(np.median(np.linalg.norm(a.uv[ia] - b.uv[ib], axis=1)))


def _pct(v: list[float], q: float) -> str:
    return f"{np.percentile(v, q):.3f}" if v else "-"


def _med(v: list[float], f: str = "{:.3f}") -> str:
    return f.format(statistics.median(v)) if v else "-"


def compare(seq: Sequence, im: list[Track], cv: list[Track]) -> dict[str, Any]:
    """The per-sequence figures."""
    n = len(seq.frames)
    both = [k for k in range(n) if im[k].pose is not None and cv[k].pose is not None]
    rot, tra, flips = [], [], []
    for k in both:
        r, t = _apart(seq.board, im[k].pose, cv[k].pose)  # type: ignore[arg-type]
        rot.append(r)
        tra.append(t)
        if r > FLIP_DEG:
            flips.append(k)
    still = [
        k
        for k in range(1, n)
        if k in both
        and k - 1 in both
        and _moved(im[k - 1], im[k]) < STILL_PX
        and _moved(cv[k - 1], cv[k]) < STILL_PX
    ]

    def jitter(tr: list[Track]) -> tuple[list[float], list[float]]:
        dt, dr = [], []
        for k in still:
            (Ra, ta), (Rb, tb) = tr[k - 1].pose, tr[k].pose  # type: ignore[misc]
            dt.append(float(np.linalg.norm(tb - ta) / np.linalg.norm(tb) * 100))
            dr.append(_angle(Ra, Rb))
        return dt, dr

    (jit_im, jitr_im), (jit_cv, jitr_cv) = jitter(im), jitter(cv)
    return {
        "n": n,
        "im_found": sum(t.pose is not None for t in im),
        "cv_found": sum(t.pose is not None for t in cv),
        "both": len(both),
        "im_corners": [im[k].ids.size for k in both],
        "cv_corners": [cv[k].ids.size for k in both],
        "rot": rot,
        "tra": tra,
        "flips": flips,
        "still": len(still),
        "jit_im": jit_im,
        "jit_cv": jit_cv,
        "jitr_im": jitr_im,
        "jitr_cv": jitr_cv,
        "im_rms": [im[k].rms for k in both],
        "cv_rms": [cv[k].rms for k in both],
        "im_ms": [t.ms for t in im],
        "cv_ms": [t.ms for t in cv],
        "only_im": [k for k in range(n) if im[k].pose is not None and cv[k].pose is None],
        "only_cv": [k for k in range(n) if cv[k].pose is not None and im[k].pose is None],
    }


def rig_consistency(
    seqs: list[Sequence], tracks: dict[str, tuple[list[Track], list[Track]]]
) -> list[list[object]]:
    """Board pose in the rig's frame from every pair of cameras that both see it, per loop."""
    rows: list[list[object]] = []
    for rig in sorted({s.rig for s in seqs if s.rig}):
        cams = [s for s in seqs if s.rig == rig]
        errs: dict[int, tuple[list[float], list[float]]] = {i: ([], []) for i in range(3)}
        pairs = 0
        n = min(len(s.frames) for s in cams)
        for k in range(n):
            for a in range(len(cams)):
                for b in range(a + 1, len(cams)):
                    sa, sb = cams[a], cams[b]
                    ta, tb = tracks[sa.name], tracks[sb.name]
                    if any(x[k].pose is None for x in (*ta, *tb)):
                        continue
                    pairs += 1
                    for ia in range(3):
                        w = []
                        for s, t in ((sa, ta[ia][k]), (sb, tb[ia][k])):
                            Rc, tc = s.extrinsic  # type: ignore[misc]
                            R, tt = t.pose  # type: ignore[misc]
                            # world <- camera: X_w = Rc^T (X_c - tc); board in mm, rig in m
                            w.append((Rc.T @ R, Rc.T @ (tt / 1000.0 - tc)))
                        errs[ia][0].append(_angle(w[0][0], w[1][0]))
                        errs[ia][1].append(float(np.linalg.norm(w[0][1] - w[1][1]) * 1000))
        rows.append(
            [
                rig,
                pairs,
                " / ".join(_med(errs[i][0]) for i in (0, 2, 1)),
                " / ".join(_med(errs[i][1], "{:.2f}") for i in (0, 2, 1)),
                " / ".join(_pct(errs[i][1], 95) for i in (0, 2, 1)),
            ]
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run one half and print its tables."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path, help="folder with caliscope/, p2s/, wb/, heba/")
    ap.add_argument("--heldout", action="store_true", help="run the held-out half")
    ap.add_argument("--details", action="store_true", help="print per-frame disagreements")
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    seqs = sequences(args.data, args.heldout)
    rows, tracks = [], {}
    for seq in seqs:
        seq.frames = seq.load()
        run_imageform(seq), run_opencv(seq)  # warm-up: numba compiles, caches fill
        im, cv, det = run_imageform(seq), run_opencv(seq), run_imageform(seq, predict=False)
        tracks[seq.name] = (im, cv, det)
        c = compare(seq, im, cv)
        if args.details:
            print(seq.name, "only imageform:", c["only_im"], "only OpenCV:", c["only_cv"],
                  "apart > 5 deg:", c["flips"], file=sys.stderr)  # fmt: skip
        rows.append(
            [
                seq.name + (" (held out)" if seq.heldout else ""),
                c["n"],
                f"{c['im_found']} / {c['cv_found']} / {c['both']}",
                sum(t.pose is not None for t in det),
                f"{_med(c['im_corners'], '{:.0f}')} / {_med(c['cv_corners'], '{:.0f}')}",
                f"{_med(c['rot'])} / {_pct(c['rot'], 95)}",
                f"{_med(c['tra'])} / {_pct(c['tra'], 95)}",
                len(c["flips"]),
                c["still"],
                f"{_med(c['jit_im'])} / {_med(c['jit_cv'])}",
                f"{_med(c['jitr_im'])} / {_med(c['jitr_cv'])}",
                f"{_med(c['im_rms'])} / {_med(c['cv_rms'])}",
                f"{_med(c['im_ms'], '{:.1f}')} / {_med(c['cv_ms'], '{:.1f}')}",
            ]
        )
        seq.frames = seq.frames if seq.rig else []
    title = "Board tracking in fresh real sequences: imageform vs OpenCV"
    print(header(title + (" (held-out half)" if args.heldout else " (tuning half)")))
    cols = [
        "sequence",
        "frames",
        "with a pose: imageform / OpenCV / both",
        "imageform detecting every frame: with a pose",
        "corners where both (median) imageform / OpenCV",
        "rotation apart deg, median / p95",
        "translation apart % of distance, median / p95",
        f"frames > {FLIP_DEG:g} deg apart",
        "still pairs",
        "jitter % of distance imageform / OpenCV",
        "jitter deg imageform / OpenCV",
        "reprojection RMS px where both imageform / OpenCV",
        "ms per frame imageform / OpenCV",
    ]
    print(markdown_table(cols, rows))
    rig = rig_consistency(seqs, tracks)
    if rig:
        print("## The rig's check: the board's pose from two cameras\n")
        print(
            markdown_table(
                [
                    "session",
                    "camera pairs x frames (every loop's pose in both)",
                    "rotation apart deg, median: imageform / detecting every frame / OpenCV",
                    "translation apart mm, median: same order",
                    "translation apart mm, p95: same order",
                ],
                rig,
            )
        )
    for s in seqs:
        print(f"- {s.name}: {s.what}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
