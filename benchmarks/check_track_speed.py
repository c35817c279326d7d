"""Speed of ChArUco board tracking on real 720p, 1080p and 4K sequences: imageform vs OpenCV.

The sequences, the two loops and the accuracy figures are those of
``benchmarks/check_track_fresh.py`` (imageform's :class:`~imageform.geometry.BoardTracker`
with its defaults; OpenCV's ``CharucoDetector.detectBoard`` or ``findChessboardCornersSB``,
then ``solvePnP``), on the same uint8 grey frames, camera and board. Both run with the same
number of threads: ``cv2.setNumThreads`` is set to ``NUMBA_NUM_THREADS`` (1 unless set).

Each sequence is run once to warm up (numba compiles, caches fill), then ``--repeat`` times,
the two loops interleaved; a run's time is the CPU time of the process per frame. The table
gives, over the runs, the median of each run's median frame and of each run's mean frame
(a tracked video's frames cost unevenly: detected frames more than tracked ones), and the
ratio of the two loops' mean frames. Accuracy is from the last run: frames with a pose, the
corners found, the corners' distance from OpenCV's (same corner ids, where both have a pose),
the poses apart, each loop's reprojection RMS; and how imageform found the board (its corners
tracked, detected in the last box, or in the whole frame).

The data (not in this repository; ``DATA`` laid out as ``check_track_fresh.py`` says):

- ``caliscope/``: 8 webcam sequences 1280 x 720 (tuning);
- ``p2s/``: 4 cameras x 7 views 1088 x 1920 of a checkerboard (tuning);
- ``wb/``: williambittner1/charuco_task's 23 consecutive 3840 x 2160 frames of a phone's video
  (4K), the same frames halved (block means, 1920 x 1080, the camera matrix halved) and the
  repository's 7 photographs 4096 x 3072 (all seen by earlier sessions: tuning).

With ``--command``, a second table: the ``imageform track`` command end to end (a separate
process, its frames decoded by the video reader in RGB) on the 4K frames encoded here as an
H.264 video (libx264, CRF 14, 30 fps, yuv420p): frames per second as the command prints them
(wall clock, decoding included; the median of ``--repeat`` runs after a warm-up), the
process's CPU time per frame, the frames with a pose, and the poses apart from OpenCV's loop
on the same decoded frames (grey, OpenCV's luma) as in the first table.

Run with ``OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=src:.``:
``python benchmarks/check_track_speed.py DATA [--repeat 5] [--only NAME] [--command]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "src"))

from benchmarks._common import header, markdown_table  # noqa: E402
from benchmarks.check_track_fresh import (  # noqa: E402
    Sequence,
    Track,
    _apart,
    _med,
    _pct,
    run_opencv,
    sequences,
)


def halved(seq: Sequence) -> Sequence:
    """``seq`` with its frames reduced twice (2 x 2 block means) and its camera matrix halved."""
    K = seq.K.copy()
    K[:2, :2] /= 2
    K[:2, 2] = (K[:2, 2] + 0.5) / 2 - 0.5  # pixel centres at integers
    load = seq.load

    def small() -> list[np.ndarray]:
        out = []
        for f in load():
            h, w = f.shape[0] // 2 * 2, f.shape[1] // 2 * 2
            b = f[:h, :w].astype(np.uint16)
            m = (b[0::2, 0::2] + b[1::2, 0::2] + b[0::2, 1::2] + b[1::2, 1::2] + 2) // 4
            out.append(m.astype(np.uint8))
        return out

    return Sequence(
        seq.name + " halved", seq.board, K, seq.dist, small, seq.heldout, "the same frames halved"
    )


def run_imageform(seq: Sequence) -> tuple[list[Track], list[str]]:
    """imageform's BoardTracker (defaults) over the frames, and how each frame was found."""
    from imageform.geometry import BoardTracker, BrownConrady, CharucoBoard

    b = seq.board
    board: Any
    if b.kind == "charuco":
        board = CharucoBoard(b.size, b.square, b.marker, b.dictionary)
        pts = board.corner_points()
    else:
        board, pts = b.size, None
    d = list(seq.dist[:5]) + [0.0] * (5 - min(5, seq.dist.size))
    tracker = BoardTracker(board, seq.K, BrownConrady(*d), square=b.square)
    out, how = [], []
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
        how.append(p.searched)
    return out, how


def corners_apart(im: Track, cv: Track) -> list[float]:
    """Distances (px) between the two loops' corners of the same id."""
    _, ia, ib = np.intersect1d(im.ids, cv.ids, return_indices=True)
    return [float(x) for x in np.linalg.norm(im.uv[ia] - cv.uv[ib], axis=1)]


def row(seq: Sequence, runs: list[tuple[list[Track], list[Track], list[str]]]) -> list[object]:
    """One sequence's figures over its timed runs (accuracy from the last)."""
    im, cv, how = runs[-1]
    n = len(seq.frames)
    both = [k for k in range(n) if im[k].pose is not None and cv[k].pose is not None]
    rot, tra, px = [], [], []
    for k in both:
        r, t = _apart(seq.board, im[k].pose, cv[k].pose)  # type: ignore[arg-type]
        rot.append(r)
        tra.append(t)
        if seq.board.kind == "charuco":
            px += corners_apart(im[k], cv[k])
    med = [statistics.median(t.ms for t in r[i]) for r in runs for i in (0, 1)]
    mean = [statistics.fmean(t.ms for t in r[i]) for r in runs for i in (0, 1)]
    im_med, cv_med = statistics.median(med[0::2]), statistics.median(med[1::2])
    im_mean, cv_mean = statistics.median(mean[0::2]), statistics.median(mean[1::2])
    h, w = seq.frames[0].shape[:2]
    return [
        seq.name,
        f"{n} x {w} x {h}",
        f"{sum(t.pose is not None for t in im)} / {sum(t.pose is not None for t in cv)} / "
        f"{len(both)}",
        f"{_med([im[k].ids.size for k in both], '{:.0f}')} / "
        f"{_med([cv[k].ids.size for k in both], '{:.0f}')}",
        f"{_med(px)} / {_pct(px, 95)}" if px else "-",
        f"{_med(rot)} / {_pct(rot, 95)}",
        f"{_med(tra)} / {_pct(tra, 95)}",
        f"{_med([im[k].rms for k in both])} / {_med([cv[k].rms for k in both])}",
        " / ".join(str(how.count(s)) for s in ("tracked", "box", "frame")),
        f"{im_med:.1f} / {cv_med:.1f}",
        f"{im_mean:.1f} / {cv_mean:.1f}",
        f"{im_mean / cv_mean:.2f}",
    ]


def _wb_video(data: Path, tmp: Path) -> tuple[Path, Path, Sequence]:
    """Encode the 4K frames as an H.264 video, write its camera file; the decoded frames."""
    import glob

    import av
    import cv2

    from imageform.geometry import BrownConrady, Camera
    from imageform.io import write_camera

    wb = sequences(data, True)[0]
    paths = sorted(glob.glob(str(data / "wb" / "data" / "calibration_video" / "*.jpg")))
    video = tmp / "wb4k.mp4"
    out = av.open(str(video), "w")
    st = out.add_stream("libx264", rate=30)
    st.width, st.height, st.pix_fmt = 3840, 2160, "yuv420p"
    st.options = {"crf": "14", "preset": "fast"}
    for p in paths:
        rgb = cv2.cvtColor(cv2.imread(p), cv2.COLOR_BGR2RGB)
        for pk in st.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
            out.mux(pk)
    for pk in st.encode():
        out.mux(pk)
    out.close()
    d = list(wb.dist[:5]) + [0.0] * (5 - min(5, wb.dist.size))
    camera = tmp / "wb4k.toml"
    write_camera(camera, Camera(wb.K, distortion=BrownConrady(*d), image_size=(3840, 2160)))
    with av.open(str(video)) as c:
        rgb = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
    grey = [cv2.cvtColor(f, cv2.COLOR_RGB2GRAY) for f in rgb]
    seq = Sequence(wb.name + " (H.264)", wb.board, wb.K, wb.dist, lambda: grey, True, "")
    seq.frames = grey
    return video, camera, seq


def command_rows(data: Path, repeat: int) -> list[list[object]]:
    """``imageform track`` end to end on the 4K video: speed, poses, poses apart from OpenCV's."""
    import csv
    import json
    import resource
    import subprocess
    import tempfile

    from imageform.geometry import rvec_to_matrix

    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        video, camera, seq = _wb_video(data, tmp)
        cv = run_opencv(seq)
        b = seq.board
        cmd = [
            sys.executable, "-m", "imageform", "track", str(video), "-o", str(tmp / "p.csv"),
            "--camera", str(camera), "--board", f"charuco:{b.size[0]}x{b.size[1]}",
            "--square", f"{b.square}mm", "--marker", f"{b.marker}mm",
            "--dictionary", b.dictionary.replace("_", "-"), "--json", "--force",
        ]  # fmt: skip
        env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
        fps, cpu, lat = [], [], []
        for k in range(repeat + 1):
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            doc = json.loads(done.stdout)
            if k:  # the first run warms up (numba's cache, the files' pages)
                fps.append(float(doc["fps"]))
                lat.append(float(doc["latency_ms_median"]))
                used = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
                cpu.append(1e3 * used / int(doc["frames"]))
        with open(tmp / "p.csv") as fh:
            rows = list(csv.DictReader(fh))
    rot = []
    for r, c in zip(rows, cv, strict=True):
        if r["found"] == "1" and c.pose is not None:
            rv = np.array([float(r[x]) for x in ("rx", "ry", "rz")])
            tv = np.array([float(r[x]) for x in ("tx", "ty", "tz")])
            rot.append(_apart(seq.board, (np.asarray(rvec_to_matrix(rv)), tv), c.pose))
    found = sum(r["found"] == "1" for r in rows)
    return [
        [
            seq.name,
            f"{len(rows)} x 3840 x 2160",
            f"{found} / {sum(c.pose is not None for c in cv)} / {len(rot)}",
            f"{_med([a for a, _ in rot])} / {_pct([a for a, _ in rot], 95)}",
            f"{_med([t for _, t in rot])} / {_pct([t for _, t in rot], 95)}",
            f"{statistics.median(fps):.2f}",
            f"{statistics.median(lat):.1f}",
            f"{statistics.median(cpu):.0f}",
        ]
    ]


def main(argv: list[str] | None = None) -> int:
    """Run the sequences and print the table."""
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", type=Path, help="folder with caliscope/, p2s/, wb/")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs of each sequence")
    ap.add_argument("--only", default="", help="run only the sequences whose name has this")
    ap.add_argument("--command", action="store_true", help="also imageform track end to end")
    args = ap.parse_args(argv)
    threads = int(os.environ.get("NUMBA_NUM_THREADS", "1"))
    cv2.setNumThreads(threads)
    seqs = sequences(args.data, False)
    wb = sequences(args.data, True)[:2]  # the 4K video and the photographs (heba left out)
    seqs += [wb[0], halved(wb[0]), wb[1]]
    rows = []
    for seq in seqs:
        if args.only not in seq.name:
            continue
        seq.frames = seq.load()
        run_imageform(seq), run_opencv(seq)  # warm-up
        runs = []
        for _ in range(args.repeat):
            im, how = run_imageform(seq)
            runs.append((im, run_opencv(seq), how))
        rows.append(row(seq, runs))
        print(rows[-1], file=sys.stderr)
        seq.frames = []
    print(header(f"ChArUco board tracking speed: imageform vs OpenCV, {threads} thread(s) each"))
    cols = [
        "sequence",
        "frames x width x height",
        "with a pose: imageform / OpenCV / both",
        "corners where both (median) imageform / OpenCV",
        "corners apart px (same id), median / p95",
        "rotation apart deg, median / p95",
        "translation apart % of distance, median / p95",
        "reprojection RMS px where both imageform / OpenCV",
        "imageform frames tracked / box / frame",
        "ms per frame, median: imageform / OpenCV",
        "ms per frame, mean: imageform / OpenCV",
        "mean time ratio imageform / OpenCV",
    ]
    print(markdown_table(cols, rows))
    print(f"Median over {args.repeat} timed runs after a warm-up; CPU time of the process.")
    if args.command:
        cols = [
            "video",
            "frames x width x height",
            "with a pose: imageform track / OpenCV / both",
            "rotation apart deg, median / p95",
            "translation apart % of distance, median / p95",
            "frames per second (wall, as printed)",
            "median latency ms (a frame's tracking, wall)",
            "CPU ms per frame (the process's, start-up included)",
        ]
        print()
        print("`imageform track` end to end (decoding included):")
        print()
        print(markdown_table(cols, command_rows(args.data, args.repeat)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
