"""Structure from motion on fresh real sequences: imageform (library and CLI) against pycolmap.

Ten short real sequences from six public repositories that no earlier check used, split by
repository into a tuning half and a held-out half BEFORE anything was run (the held-out half
run once, with the final code; its source files frozen by their SHA-256 below, checked
before a held-out run). Nothing is downloaded: ``--prepare MIRRORS`` reads the repositories'
bare git directories (``MIRRORS/<owner>+<name>/...``, as the ``fetch`` tool leaves them) at
the commits below and writes each sequence's frames, camera file and truth (where there is
one) under ``--data`` (default /tmp/sfmfresh/data). None of these media is in this
repository.

Tuning half (three repositories, five sequences):

- ``colon-a``, ``colon-b``: meghakalia/unsupervised_pose_estimation at ``75da29a``,
  ``assets/colonoscopy.mp4`` (Monodepth2 licence, non-commercial: measured, never
  committed): a colonoscope in a colon phantom, 600 frames at 6 fps, its left 192 x 192
  panel (the right panel is a depth map); every 6th frame (the clip repeats a frame every
  sixth), frames 0-299 and 300-599: 50 frames each. No camera given.
- ``viking``: rshilliday/sfm at ``ca0eead`` (Apache-2.0), ``datasets/Viking``: 49 phone
  photographs of a figurine (504 x 672) by the repository's author, every 2nd (25); K from
  its ``matching.py``.
- ``temple``, ``dino``: maximm8/VisualHull at ``deca8bd`` (no licence; Middlebury's
  templeSparseRing and dinoSparseRing, no licence stated): 16 views each on a ring,
  640 x 480, K and the true poses from ``*_par.txt``; ordered around the ring (a view at
  latitude +82 degrees is the view opposite turned half a turn, Middlebury's README).

Held-out half (three repositories, five sequences):

- ``nasal-7``, ``nasal-43``: BaymaxShao/EndoMODE at ``58e5d07`` (no licence),
  ``vis_data/7.gif`` and ``vis_data/43.gif``: a nasal endoscope's video, the observation
  panel of the figure (216 x 122 px, a circular field of view about 120 px across, GIF
  colours), 224 and 200 frames, every 4th. No camera given.
- ``tum-desk``: jeannotes/Slam_Course at ``8e732f7`` (no licence; TUM RGB-D
  ``rgbd_dataset_freiburg1_desk``, CC BY 4.0), ``SLAM14Lectures/slambook/second_edition/
  ch8/data/data/rgb``: 9 consecutive frames, 640 x 480, TUM's published fr1 camera
  (fx 517.3, fy 516.5, cx 318.6, cy 255.3, k1 0.2624, k2 -0.9531, p1 -0.0054, p2 0.0026,
  k3 1.1633), the truth from its ``groundtruth.txt`` (motion capture).
- ``slambook-rgbd``: the same repository, ``.../second_edition/ch5/rgbd/color``: 5 frames
  of a room, 640 x 480, K from its ``joinMap.cpp`` (fx 518, fy 519, cx 325.5, cy 253.5),
  the poses of its ``pose.txt``.
- ``sceaux``: openMVG/ImageDataset_SceauxCastle at ``fde7f5f`` (photographs copyright
  2012 Pierre Moulon, no licence stated), 11 photographs of a castle, 2832 x 2128,
  reduced 4 times (708 x 532, OpenCV's bilinear resize), K from its ``K.txt`` scaled.

For a sequence without a camera (the two endoscopes) the camera is pycolmap's
self-calibration on the sequence itself (``RADIAL_FISHEYE``: one focal length, from 0.45
times the width, and two radial terms refined; the field of view masked, SIFT's peak
threshold a quarter of its default; ``OPENCV_FISHEYE``, its two focal lengths free,
diverged on the tuning clips: fx and fy 77 and 114 px, 2 frames registered), written as a
``kannala_brandt`` camera file (k1, k2) that both programs then use fixed (when the
self-calibration makes no model, its starting guess: f 0.45 w, equidistant), as
``check_endo_real.py`` does: the comparison is between two programs with the same camera,
and the row of the self-calibrating run is the reference. (Then imageform had no self-calibration
and ``imageform reconstruct`` needed ``--camera``: ``--autok`` below.)

Runs: imageform's library (:func:`imageform.geometry.reconstruct_sequence`) and its command
(``python -m imageform reconstruct FRAMES --camera camera.toml -o OUT``), with the
endoscope settings of docs/reconstruction.md for the endoscopes (``--auto-mask
--contrast-threshold 0.01``) and the defaults otherwise; pycolmap (sequential matching, the
camera fixed; for the endoscopes the field-of-view mask and a quarter of the peak
threshold). Columns: frames registered, points, mean track length, median reprojection
error (px), seconds (wall, one run, a loaded machine); against the truth where there is
one, else against the reference (pycolmap): over consecutive frames registered in both,
the median angle between relative rotations and between relative translation directions
(degrees), and the camera centres' RMS after the best similarity as a share of the
reference path's length (%). A sequence with a given camera and no truth has one more
pycolmap row, its focal length and radial term refined from the given camera
(``SIMPLE_RADIAL``): a check of the given camera (its note prints the focal length found).
pycolmap's runs are kept in the data folder (``pycolmap.json``, ``selfcal.json``): a second
run, e.g. with the code before a change on ``PYTHONPATH``, compares against the same ones.

``--autok`` (``sfm-autok-*.md``): the same sequences without a camera file. imageform's
library with the given K held (its check of K in the note) and with its focal length
refined; without a camera (f = 1.2 max(w, h), the principal point at the center, no
distortion, the focal length refined), by the library and by ``imageform reconstruct``
without ``--camera`` (the frames are PNGs: no EXIF); pycolmap from COLMAP's default for an
unknown camera (``SIMPLE_RADIAL`` from the same f, its focal length and k1 refined;
``autok-pycolmap.json``); for an endoscope its fisheye self-calibration above. The focal
length found against the truth (Middlebury's calibration) or, where there is none, against
pycolmap's; the poses as above; seconds wall (CPU for the library). With a given K,
also ``imageform reconstruct --camera`` (its check of K in the note); under the table
every ``note:`` line the command printed.
Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --prepare /work/.mirror --data /tmp/sfmfresh/data
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --data /tmp/sfmfresh/data --split tuning [--only temple dino]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --data /tmp/sfmfresh/data --split held-out
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --data /tmp/sfmfresh/data --autok [--split held-out]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --data /tmp/sfmfresh/data --exif /work/.mirror

``--exif MIRRORS`` (``--autok`` on Sceaux's original JPEGs, held-out): the EXIF focal length
(:func:`imageform.io.exif_camera`) as the command finds it, against K.txt and pycolmap.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402

#: The sequences: repository, commit, split, what to read.
SEQUENCES: dict[str, dict[str, Any]] = {
    "colon-a": {
        "repo": "meghakalia/unsupervised_pose_estimation",
        "commit": "75da29a49471bd3f93672bd343747f788bed04f7",
        "split": "tuning",
        "endoscope": True,
    },
    "colon-b": {
        "repo": "meghakalia/unsupervised_pose_estimation",
        "commit": "75da29a49471bd3f93672bd343747f788bed04f7",
        "split": "tuning",
        "endoscope": True,
    },
    "temple": {
        "repo": "maximm8/VisualHull",
        "commit": "deca8bdde2eafe79c96505d77ca388911489eb4d",
        "split": "tuning",
        "endoscope": False,
    },
    "viking": {
        "repo": "rshilliday/sfm",
        "commit": "ca0eead387ba68582bf166c9a0780adcd99e3bf3",
        "split": "tuning",
        "endoscope": False,
    },
    "dino": {
        "repo": "maximm8/VisualHull",
        "commit": "deca8bdde2eafe79c96505d77ca388911489eb4d",
        "split": "tuning",
        "endoscope": False,
    },
    "nasal-7": {
        "repo": "BaymaxShao/EndoMODE",
        "commit": "58e5d0704f5bcb24f0db7a4edbeb83211274debb",
        "split": "held-out",
        "endoscope": True,
    },
    "nasal-43": {
        "repo": "BaymaxShao/EndoMODE",
        "commit": "58e5d0704f5bcb24f0db7a4edbeb83211274debb",
        "split": "held-out",
        "endoscope": True,
    },
    "tum-desk": {
        "repo": "jeannotes/Slam_Course",
        "commit": "8e732f722b6a0cfdaf0f0cb3768b592ba5874de7",
        "split": "held-out",
        "endoscope": False,
    },
    "slambook-rgbd": {
        "repo": "jeannotes/Slam_Course",
        "commit": "8e732f722b6a0cfdaf0f0cb3768b592ba5874de7",
        "split": "held-out",
        "endoscope": False,
    },
    "sceaux": {
        "repo": "openMVG/ImageDataset_SceauxCastle",
        "commit": "fde7f5faba555e3c54700477c304488613346a19",
        "split": "held-out",
        "endoscope": False,
    },
}

_SLAM = "SLAM14Lectures/slambook/second_edition"
#: The held-out sequences' source files, frozen before any run: path -> SHA-256.
HELD_OUT_SHA256: dict[str, str] = {
    "BaymaxShao/EndoMODE:vis_data/7.gif": "3fd458edbcd583ccc195d3713c2cfad6d8479d51369111fecc675b0b88b44e42",  # noqa: E501
    "BaymaxShao/EndoMODE:vis_data/43.gif": "33bb3187c1e27e4c6b0fd3b18a89b92dd81e2886520d44f89182ea91a81b0f16",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.359684.png": "0830aec024d647839505c8a3ef24ac505384c3011af9cc2d06e1babeff8c33fa",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.391690.png": "d5272c812dc4a8215321d0cab3f200f4b6b4102420ba3d22d0e88ba4943f6b0d",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.423683.png": "153c260bd88c4de7ae0b199c99c35ad1f67eacd242454fd66f5dc4cc1f439197",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.459685.png": "d648701b8c1454afc2b8267153b4b8b3547dac91fd17f90040ba74f7a0a6af84",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.491698.png": "b6c0a4883ad7cc0ab953c517f82cc4d44a870a4e2aa8e0fde9b806cfea599eb7",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.523684.png": "7d7d71d4f65329e8b5fab4aff6dcb220e06f5f921c94a41ee15810ad9e23f1e2",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.559753.png": "473afbe7679a82f1fa4f8814a4d20b2cb3f45922e04cbfc656d72067dfc02abd",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.591640.png": "474ce9ee8ef5515ff9bccb68d0ec30284f24b66913f1a5c257a7cc4e7ec5352d",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/rgb/1305031453.627706.png": "86508ac1ab528bb3cd7eb825e1fa8542e1e20b2c2825a239983af9b9d783a0a6",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch8/data/data/groundtruth.txt": "48c4fa61f5d78310ea579f404d31d296738c4210c19c2bdac4a5cdf6bff50831",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/color/1.png": "07756976d509bd82dfa1d9201b828ca2319da419ebda5f1009d4ea1bc7284b2e",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/color/2.png": "c8b91988f4e149a3c0ccde58fc8be682d6cbde903f311c72cf626fdcad656fb1",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/color/3.png": "0b675c34f09e694f515090ad838e4a6327cf4414773035bab303f7578a29f99b",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/color/4.png": "48f75e50531ca655155fad2658e9f5ff92dae4c5daa3940898053286038b189c",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/color/5.png": "bde1c22257b932e28e69a01830354a7eb06ff4833c2de3ae137ca6e17f6a4007",  # noqa: E501
    "jeannotes/Slam_Course:SLAM14Lectures/slambook/second_edition/ch5/rgbd/pose.txt": "8a105e14e26fb22a45fef0f628c576c1b9e02e5a7ff662e48f6de13c7c9c783e",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7100.JPG": "b475a1f74cd54536b6fe186fb165431ef0ee502f56b0d9895d6da576e364ee1e",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7101.JPG": "05de696ef02054a3d22af94f48fa3cb88df801cfe48561ad82010a130f408723",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7102.JPG": "9c25103cf8411909773a189d524eb959a0f8a9ac74a1632b3ca343b605b7e034",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7103.JPG": "eebf00b09b773aff229e53c4d8c744c5f64f3c004fa8edece0f3d8c917a19411",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7104.JPG": "3b18d6112bb68aa15e1e20d3be234ea4fa88ecf349f42d89bd7830d75ebe4fc6",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7105.JPG": "e67d29ccf210fab3227fec99e5a32862d3266f81bf4694eeb30cbe984a0b309f",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7106.JPG": "83a977d2a1b5eb733c88bde10646e649ff87f75a94faa240354907920c070cda",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7107.JPG": "7719235b80e88646ae8dfd8fddfcfcb4a03d4ef9133a62a551004cd5ccfd86c5",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7108.JPG": "f1e6fd28a291337d578488a70c713f580d53f4d5073a66659a0d2401ff7071b2",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7109.JPG": "64ae29fe51d7f45f81edec73d9004d6c99e1c198192487aa9e3d00ff4cd3d433",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/100_7110.JPG": "cdc7bd37efaf04e6c84f7cc3cafdf5e6890b01756c936d60faae53dab95bf8e9",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/K.txt": "78bd7084ce90963768e7a714ecbb8aa68293741c37c729b49c819f76efb5d4aa",  # noqa: E501
    "openMVG/ImageDataset_SceauxCastle:images/Readme.txt": "4bdc6e27256b4cdd06f35d534b99a77dc6675793a95639c52cdeb2593249d799",  # noqa: E501
}


def _git_dir(mirrors: Path, repo: str) -> Path:
    base = mirrors / repo.replace("/", "+") / "repo"
    return base / ".git" if (base / ".git").is_dir() else base


def _show(mirrors: Path, repo: str, commit: str, path: str) -> bytes:
    gd = _git_dir(mirrors, repo)
    return subprocess.run(
        ["git", "--git-dir", str(gd), "show", f"{commit}:{path}"], check=True, capture_output=True
    ).stdout


def _ls(mirrors: Path, repo: str, commit: str, folder: str) -> list[str]:
    gd = _git_dir(mirrors, repo)
    out = subprocess.run(
        ["git", "--git-dir", str(gd), "ls-tree", "--name-only", f"{commit}:{folder}"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return sorted(out.split())


def _quat_to_R(q: np.ndarray) -> np.ndarray:
    """Rotation of a unit quaternion (qx, qy, qz, qw)."""
    x, y, z, w = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _sources(name: str, mirrors: Path) -> dict[str, bytes]:
    """The source files of a sequence: path -> bytes (what the SHA-256 list freezes)."""
    s = SEQUENCES[name]
    repo, commit = s["repo"], s["commit"]
    paths: list[str]
    if name.startswith("colon"):
        paths = ["assets/colonoscopy.mp4"]
    elif name == "viking":
        paths = [f"datasets/Viking/{f}" for f in _ls(mirrors, repo, commit, "datasets/Viking")]
        paths.append("matching.py")
    elif name in ("temple", "dino"):
        folder = f"{name}SparseRing"
        paths = [f"{folder}/{f}" for f in _ls(mirrors, repo, commit, folder) if f != "Thumbs.db"]
    elif name.startswith("nasal"):
        paths = [f"vis_data/{name.split('-')[1]}.gif"]
    elif name == "tum-desk":
        base = f"{_SLAM}/ch8/data/data"
        paths = [f"{base}/rgb/{f}" for f in _ls(mirrors, repo, commit, f"{base}/rgb")]
        paths.append(f"{base}/groundtruth.txt")
    elif name == "slambook-rgbd":
        base = f"{_SLAM}/ch5/rgbd"
        paths = [f"{base}/color/{f}" for f in _ls(mirrors, repo, commit, f"{base}/color")]
        paths.append(f"{base}/pose.txt")
    else:
        paths = [f"images/{f}" for f in _ls(mirrors, repo, commit, "images")]
    return {p: _show(mirrors, repo, commit, p) for p in paths}


def _video_frames(data: bytes, suffix: str) -> list[np.ndarray]:
    import cv2

    with tempfile.NamedTemporaryFile(suffix=suffix) as fh:
        fh.write(data)
        fh.flush()
        if suffix == ".gif":
            from PIL import Image, ImageSequence

            with Image.open(fh.name) as im:
                return [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(im)]
        cap = cv2.VideoCapture(fh.name)
        frames = []
        while True:
            ok, f = cap.read()
            if not ok:
                break
            frames.append(np.ascontiguousarray(f[..., ::-1]))
        cap.release()
    return frames


def _decode(data: bytes) -> np.ndarray:
    import cv2

    im = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if im is None:
        raise SystemExit("a source image could not be decoded")
    return np.ascontiguousarray(im[..., ::-1])


def prepare(name: str, mirrors: Path, out: Path) -> None:
    """Write the frames (PNG), ``camera.toml`` (when known) and ``truth.npz`` of a sequence."""
    import cv2

    from imageform.geometry import BrownConrady, Camera
    from imageform.io import write_camera

    src = _sources(name, mirrors)
    folder = out / name
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    frames: list[np.ndarray] = []
    K = dist = None
    truth: list[tuple[np.ndarray, np.ndarray]] | None = None
    if name.startswith("colon"):
        allf = _video_frames(src["assets/colonoscopy.mp4"], ".mp4")
        lo = 0 if name == "colon-a" else 300
        frames = [f[:, :192] for f in allf[lo : lo + 300 : 6]]
    elif name.startswith("nasal"):
        allf = _video_frames(next(iter(src.values())), ".gif")
        frames = [f[82:204, 220:436] for f in allf[::4]]
    elif name in ("temple", "dino"):
        stem = "templeSR" if name == "temple" else "dinoSR"
        par = src[f"{stem[:-2]}SparseRing/{stem}_par.txt"].decode().split("\n")
        rows = {r.split()[0]: r.split() for r in par[1:] if r.strip()}
        # the ring in order: a view at latitude +lat is the view at (-lat, lon + 180)
        # turned half a turn in the image plane (Middlebury's README)
        ang = [a.split() for a in src[f"{stem[:-2]}SparseRing/{stem}_ang.txt"].decode()
               .splitlines() if a.strip()]  # fmt: skip
        lon = {a[2]: (float(a[1]) + (180.0 if float(a[0]) > 0 else 0.0)) % 360 for a in ang}
        truth = []
        for key in sorted(rows, key=lambda k: lon[k]):
            r = rows[key]
            frames.append(_decode(src[f"{stem[:-2]}SparseRing/{key}"]))
            v = np.array(r[1:], float)
            K = v[:9].reshape(3, 3)
            truth.append((v[9:18].reshape(3, 3), v[18:21]))
    elif name == "viking":
        keys = sorted(k for k in src if k.endswith(".jpg"))[::2]
        frames = [_decode(src[k]) for k in keys]
        K = np.array([[523.81, 0, 252.0], [0, 523.81, 336.0], [0, 0, 1]])
    elif name == "tum-desk":
        keys = sorted(k for k in src if k.endswith(".png"))
        frames = [_decode(src[k]) for k in keys]
        K = np.array([[517.3, 0, 318.6], [0, 516.5, 255.3], [0, 0, 1]])
        dist = BrownConrady(0.2624, -0.9531, -0.0054, 0.0026, 1.1633)
        gt = np.array(
            [
                [float(x) for x in line.split()]
                for line in next(v for k, v in src.items() if k.endswith("groundtruth.txt"))
                .decode()
                .splitlines()
                if line and not line.startswith("#")
            ]
        )
        truth = []
        for k in keys:
            ts = float(Path(k).stem)
            g = gt[np.argmin(np.abs(gt[:, 0] - ts))]
            Rwc = _quat_to_R(g[4:8])
            truth.append((Rwc.T, -Rwc.T @ g[1:4]))
    elif name == "slambook-rgbd":
        keys = sorted(k for k in src if k.endswith(".png"))
        frames = [_decode(src[k]) for k in keys]
        K = np.array([[518.0, 0, 325.5], [0, 519.0, 253.5], [0, 0, 1]])
        poses = np.array(
            [[float(x) for x in line.split()] for line in src[f"{_SLAM}/ch5/rgbd/pose.txt"]
             .decode().splitlines() if line.strip()]
        )  # fmt: skip
        truth = []
        for p in poses:
            Rwc = _quat_to_R(p[3:7])
            truth.append((Rwc.T, -Rwc.T @ p[:3]))
    else:  # sceaux
        keys = sorted(k for k in src if k.lower().endswith(".jpg"))
        for k in keys:
            im = _decode(src[k])
            # OpenCV's default interpolation (bilinear): the frames the table measured
            frames.append(cv2.resize(im, (im.shape[1] // 4, im.shape[0] // 4)))
        Kf = np.array(src["images/K.txt"].decode().split(), float).reshape(3, 3)
        K = Kf.copy()
        K[:2] /= 4.0
        K[:2, 2] = (Kf[:2, 2] + 0.5) / 4.0 - 0.5
    for i, f in enumerate(frames):
        cv2.imwrite(str(folder / "frames" / f"{i:04d}.png"), f[..., ::-1])
    if K is not None:
        h, w = frames[0].shape[:2]
        write_camera(folder / "camera.toml", Camera(K, distortion=dist, image_size=(w, h)))
    if truth is not None:
        np.savez(
            folder / "truth.npz",
            R=np.stack([r for r, _ in truth]),
            t=np.stack([t for _, t in truth]),
        )
    meta = {"sources": {p: hashlib.sha256(b).hexdigest() for p, b in src.items()}}
    (folder / "meta.json").write_text(json.dumps(meta, indent=1))


def held_out_digests(data: Path) -> dict[str, str]:
    """The SHA-256 of every held-out source file, from the prepared ``meta.json`` files."""
    out: dict[str, str] = {}
    for name, s in SEQUENCES.items():
        if s["split"] == "held-out":
            meta = json.loads((data / name / "meta.json").read_text())
            out |= {f"{s['repo']}:{p}": h for p, h in meta["sources"].items()}
    return out


# ---------------------------------------------------------------------------------------
# comparisons


def agreement(
    R: np.ndarray, t: np.ndarray, Rr: np.ndarray, tr: np.ndarray
) -> tuple[float, float, float]:
    """Median relative-rotation and translation-direction angles (deg), centre RMS (%).

    Over the frames registered in both; consecutive registered frames for the angles; the
    camera centres after the best similarity (Umeyama), RMS as a share of the reference
    path's length.
    """
    both = np.flatnonzero(np.isfinite(R[:, 0, 0]) & np.isfinite(Rr[:, 0, 0]))
    rot, tra = [], []
    for i, j in itertools.pairwise(both):
        Ra, Rb = R[j] @ R[i].T, Rr[j] @ Rr[i].T
        c = (np.trace(Ra @ Rb.T) - 1) / 2
        rot.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
        ta, tb = t[j] - Ra @ t[i], tr[j] - Rb @ tr[i]
        na, nb = np.linalg.norm(ta), np.linalg.norm(tb)
        if na > 0 and nb > 0:
            tra.append(np.degrees(np.arccos(np.clip(ta @ tb / (na * nb), -1, 1))))
    med = lambda v: float(np.median(v)) if v else float("nan")  # noqa: E731
    rms = float("nan")
    if len(both) >= 3:
        C = np.stack([-R[i].T @ t[i] for i in both])
        Cr = np.stack([-Rr[i].T @ tr[i] for i in both])
        mu_e, mu_t = C.mean(0), Cr.mean(0)
        e, g = C - mu_e, Cr - mu_t
        U, S, Vt = np.linalg.svd(g.T @ e / len(e))
        d = np.sign(np.linalg.det(U @ Vt))
        D = np.diag([1.0, 1.0, d])
        Rs = U @ D @ Vt
        s = np.trace(np.diag(S) @ D) / max((e**2).sum(1).mean(), 1e-300)
        fit = s * e @ Rs.T + mu_t
        path = float(np.sum(np.linalg.norm(np.diff(Cr, axis=0), axis=1)))
        if path > 0:
            rms = 100 * float(np.sqrt(np.mean(np.sum((fit - g - mu_t) ** 2, 1)))) / path
    return med(rot), med(tra), rms


# ---------------------------------------------------------------------------------------
# runs


def _frames(folder: Path) -> list[np.ndarray]:
    import cv2

    out = []
    for p in sorted((folder / "frames").glob("*.png")):
        im = cv2.imread(str(p), cv2.IMREAD_COLOR)
        if im is None:
            raise SystemExit(f"{p}: not readable (run --prepare)")
        out.append(np.ascontiguousarray(im[..., ::-1]))
    return out


def _nan_poses(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan)


def run_imageform(
    frames: list[np.ndarray], cam: Any, endoscope: bool, refine_focal: bool = False
) -> dict[str, Any]:
    from imageform.geometry import field_of_view_mask, reconstruct_sequence

    n = len(frames)
    t0 = time.perf_counter()
    c0 = time.process_time()
    kw: dict[str, Any] = {}
    if endoscope:
        kw = {"masks": field_of_view_mask(frames), "contrast_threshold": 0.01}
    try:
        rec = reconstruct_sequence(frames, cam.K, cam.distortion, refine_focal=refine_focal, **kw)
    except Exception as exc:  # a refusal is a result too
        R, t = _nan_poses(n)
        msg = f"{type(exc).__name__}: {str(exc)[:160]}"
        return {"reg": 0, "time": time.perf_counter() - t0, "R": R, "t": t, "note": msg}
    r = np.asarray(rec.residuals_px)
    R, t = _nan_poses(n)
    R[rec.registered], t[rec.registered] = rec.R[rec.registered], rec.t[rec.registered]
    out = {"reg": int(rec.registered.sum()), "time": time.perf_counter() - t0, "R": R, "t": t}
    out |= {"points": int(rec.points.shape[0]), "track": float(np.mean(rec.track_length))}
    out |= {"reproj": float(np.median(r)) if r.size else float("nan")}
    out |= {"cpu": time.process_time() - c0, "f0": float(cam.K[0, 0])}
    out["f"] = float(cam.K[0, 0] if rec.K is None else rec.K[0, 0])
    fallback = sum("registered by" in note for note in rec.notes)
    said = [f"{fallback} by the fallbacks"] if fallback else []
    if rec.focal_fit_px is not None:  # K held: the check's focal length
        flag = any("fits the frames poorly" in note for note in rec.notes)
        said.append(f"check: f {rec.focal_fit_px:.1f} px" + (", flagged" if flag else ""))
    restarts = sum("reconstructed again from" in note for note in rec.notes)
    if restarts:
        said.append(f"{restarts} restarts from the f found")
    out["note"] = "; ".join(said)
    return out


#: Every ``note:`` line ``imageform reconstruct`` printed (``--autok``): (run, line).
CLI_NOTES: list[tuple[str, str]] = []


def run_cli(
    folder: Path, endoscope: bool, camera: bool = True, intrinsics: bool = False
) -> dict[str, Any]:
    """``python -m imageform reconstruct`` on the frames folder; its metrics.json.

    ``camera`` False: without ``--camera`` (K from the frames, its focal length refined);
    then, or with ``intrinsics``, its poses (cameras.csv) and focal lengths too (with
    ``--camera``, the given K's check in the note). Its ``note:`` lines go to ``CLI_NOTES``.
    """
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "imageform", "reconstruct", str(folder / "frames")]
        if camera:
            cmd += ["--camera", str(folder / "camera.toml")]
        cmd += ["-o", str(Path(tmp) / "out")]
        if endoscope:
            cmd += ["--auto-mask", "--contrast-threshold", "0.01"]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=os.environ.copy())
        dt = time.perf_counter() - t0
        run = f"{folder.name}, {'--camera' if camera else 'no --camera'}"
        said = [ln.strip().removeprefix("imageform: ") for ln in p.stderr.splitlines()]
        CLI_NOTES.extend((run, ln) for ln in said if ln.startswith("note:"))
        if p.returncode != 0:
            lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
            return {"reg": 0, "time": dt, "note": (lines[-1] if lines else "?")[:200]}
        m = json.loads((Path(tmp) / "out" / "metrics.json").read_text())
        out = {
            "reg": m["registered"],
            "points": m["points"],
            "track": m["track_length_mean"],
            "reproj": m["reprojection_px_median"],
            "time": dt,
            "note": "",
        }
        if not camera or intrinsics:
            import csv

            from imageform.geometry import rvec_to_matrix

            with (Path(tmp) / "out" / "cameras.csv").open() as fh:
                rows = list(csv.DictReader(fh))
            R, t = _nan_poses(len(rows))
            for i, r in enumerate(rows):
                if r["registered"] == "1":
                    R[i] = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
                    t[i] = [float(r[k]) for k in ("tx", "ty", "tz")]
            intr = m["intrinsics"]
            out |= {"R": R, "t": t, "f0": intr["focal_px_initial"], "f": intr["focal_px"]}
            if intr.get("focal_px_fit") is not None:  # K held: the check's focal length
                flag = any("fits the frames poorly" in note for note in m["notes"])
                out["note"] = f"check: f {intr['focal_px_fit']:.1f} px" + (
                    ", flagged" if flag else ""
                )
    return out


def run_pycolmap(
    frames: list[np.ndarray],
    cam: Any | None,
    endoscope: bool,
    self_calibrate: bool = False,
    camera_model: tuple[str, tuple[float, ...]] | None = None,
) -> dict[str, Any]:
    """pycolmap's sequential matching and incremental mapping; the camera fixed or refined.

    ``camera_model``: COLMAP's model and parameters, instead of the ones ``cam`` gives.
    """
    import cv2
    import pycolmap

    from benchmarks.bench_reconstruct import pycolmap_options, pycolmap_reconstruct
    from imageform.geometry import field_of_view_mask

    n = len(frames)
    h, w = frames[0].shape[:2]
    params: tuple[float, ...]
    if cam is None:  # an equidistant guess, one focal length: 0.45 w (the C3VD camera's)
        model, params = "RADIAL_FISHEYE", (0.45 * w, w / 2, h / 2, 0, 0)
    elif type(cam.distortion).__name__ == "KannalaBrandt":
        model = "OPENCV_FISHEYE"
        params = (*np.diag(cam.K)[:2], *cam.K[:2, 2], *cam.distortion.coeffs)
    elif self_calibrate:  # from the given camera: one focal length and k refined
        model = "SIMPLE_RADIAL"
        params = (float(np.mean(np.diag(cam.K)[:2])), *cam.K[:2, 2], 0.0)
    elif cam.distortion is not None and any(cam.distortion.coeffs):
        c = cam.distortion.coeffs
        model = "FULL_OPENCV"
        params = (*np.diag(cam.K)[:2], *cam.K[:2, 2], *c[:5], 0, 0, 0)
    else:
        model, params = "PINHOLE", (*np.diag(cam.K)[:2], *cam.K[:2, 2])
    if camera_model is not None:
        model, params = camera_model
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "images").mkdir()
        names = [f"{i:04d}.png" for i in range(n)]
        for name, f in zip(names, frames, strict=True):
            cv2.imwrite(str(root / "images" / name), f[..., ::-1])
        options = pycolmap_options(1, model, params)
        if self_calibrate:
            options[3].ba_refine_focal_length = True
            options[3].ba_refine_extra_params = True
        if endoscope:
            m = (field_of_view_mask(frames) * 255).astype(np.uint8)
            (root / "masks").mkdir()
            for name in names:
                cv2.imwrite(str(root / "masks" / f"{name}.png"), m)
            options[0].mask_path = str(root / "masks")
            options[1].sift.peak_threshold *= 0.25
        pairing = pycolmap.SequentialPairingOptions()
        pairing.num_threads = 1

        def match(db: Path) -> None:
            pycolmap.match_sequential(
                db, matching_options=options[2], pairing_options=pairing, device=pycolmap.Device.cpu
            )

        t0 = time.perf_counter()
        maps, _, _ = pycolmap_reconstruct(root, root / "images", options, match)
        dt = time.perf_counter() - t0
    R, t = _nan_poses(n)
    if not maps:
        return {"reg": 0, "time": dt, "R": R, "t": t, "note": "no model"}
    best = max(maps.values(), key=lambda r: r.num_reg_images())
    for image in best.images.values():
        if image.has_pose:
            pose = image.cam_from_world()
            R[names.index(image.name)] = pose.rotation.matrix()
            t[names.index(image.name)] = pose.translation
    out = {"reg": best.num_reg_images(), "time": dt, "R": R, "t": t}
    out |= {"points": best.num_points3D(), "track": best.compute_mean_track_length()}
    errs = [p.error for p in best.points3D.values()]
    out["reproj"] = float(np.median(errs)) if errs else float("nan")
    out["note"] = f"{len(maps)} models" if len(maps) > 1 else ""
    if self_calibrate:
        camera = next(iter(best.cameras.values()))
        out["camera"] = np.asarray(camera.params, float).tolist()
    return out


def self_calibrated_camera(folder: Path, frames: list[np.ndarray]) -> tuple[Any, dict[str, Any]]:
    """pycolmap's self-calibration of an unknown endoscope, written as ``camera.toml``."""
    from imageform.geometry import Camera, KannalaBrandt
    from imageform.io import read_camera, write_camera

    path = folder / "camera.toml"
    cache = folder / "selfcal.json"
    if path.exists() and cache.exists():
        res = json.loads(cache.read_text())
        res["R"], res["t"] = np.array(res["R"]), np.array(res["t"])
        return read_camera(path).camera, res
    res = run_pycolmap(frames, None, True, self_calibrate=True)
    h, w = frames[0].shape[:2]
    if "camera" not in res:  # no model: its starting guess, an equidistant fisheye
        res["camera"] = [0.45 * w, w / 2, h / 2, 0.0, 0.0]
        res["note"] = "no model: the camera is its guess (f 0.45 w, equidistant)"
    f, cx, cy, k1, k2 = res["camera"]  # RADIAL_FISHEYE: theta (1 + k1 theta^2 + k2 theta^4)
    K = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1]])
    lens = KannalaBrandt(k1, k2, 0.0, 0.0)
    write_camera(path, Camera(K, distortion=lens, image_size=(w, h)))
    keep = {key: (v.tolist() if isinstance(v, np.ndarray) else v) for key, v in res.items()}
    cache.write_text(json.dumps(keep))
    return read_camera(path).camera, res


def sequence_table(name: str, data: Path) -> tuple[str, list[list[Any]]]:
    from imageform.io import read_camera

    s = SEQUENCES[name]
    folder = data / name
    frames = _frames(folder)
    n = len(frames)
    h, w = frames[0].shape[:2]
    endo = s["endoscope"]
    runs: list[tuple[str, dict[str, Any]]] = []
    if (folder / "camera.toml").exists() and not (folder / "selfcal.json").exists():
        cam = read_camera(folder / "camera.toml").camera
        cam_note = "given"
    else:
        cam, selfcal = self_calibrated_camera(folder, frames)
        runs.append(("pycolmap, self-calibrated", selfcal))
        cam_note = "pycolmap's self-calibration"
        if selfcal["reg"] == 0:
            cam_note = "a guess (pycolmap's self-calibration made no model)"
    print(f"  {name}: {n} frames {w} x {h}, camera {cam_note}", file=sys.stderr)
    runs.insert(0, ("imageform library", run_imageform(frames, cam, endo)))
    runs.insert(1, ("imageform CLI", run_cli(folder, endo)))
    cached = folder / "pycolmap.json"  # pycolmap's run, kept for a second (before/after) run
    if cached.exists():
        fixed = json.loads(cached.read_text())
        fixed["R"], fixed["t"] = np.array(fixed["R"], float), np.array(fixed["t"], float)
    else:
        fixed = run_pycolmap(frames, cam, endo)
        keep = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in fixed.items()}
        cached.write_text(json.dumps(keep))
    runs.insert(2, ("pycolmap, camera fixed", fixed))
    truth = None
    if (folder / "truth.npz").exists():
        with np.load(folder / "truth.npz") as z:
            truth = (z["R"], z["t"])
    # the self-calibration for an endoscope (when it made a model), else the fixed camera's
    ref_run = runs[-1][1] if runs[-1][1]["reg"] > 0 else fixed
    if truth is None and cam_note == "given":  # a check of the given camera: pycolmap's own
        check = run_pycolmap(frames, cam, endo, self_calibrate=True)
        f, _, _, k1 = check.get("camera", [np.nan] * 4)
        check["note"] = f"its f {f:.1f} px (given {cam.K[0, 0]:.1f}), k {k1:.3f}"
        runs.append(("pycolmap, focal length and k refined", check))
    ref_label = "truth" if truth is not None else next(lb for lb, r in runs if r is ref_run)
    ref = truth if truth is not None else (ref_run["R"], ref_run["t"])
    rows = []
    for label, r in runs:
        ok = r["reg"] > 0 and "points" in r
        if "R" in r and ok and not (truth is None and r is ref_run):
            rot, tra, rms = agreement(r["R"], r["t"], *ref)
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        elif truth is None and r is ref_run:
            vs = "reference"
        else:
            vs = "-" if not ok else "(as the library)"
        rows.append(
            [
                name,
                label,
                f"{r['reg']}/{n}",
                r.get("points", "-"),
                f"{r['track']:.2f}" if ok else "-",
                f"{r['reproj']:.2f}" if ok else "-",
                vs,
                f"{r['time']:.1f}",
                r.get("note", ""),
            ]
        )
    info = f"{name} ({s['repo']}): {n} frames, {w} x {h} px, camera {cam_note}; against {ref_label}"
    return info, rows


def autok_table(name: str, data: Path) -> tuple[str, list[list[Any]]]:
    """The focal length without a camera file (``--autok``): imageform against pycolmap.

    Rows: imageform's library with the given K held (the reference run of the table
    above) and with its focal length refined (what ``--refine-focal`` does); imageform's
    command without ``--camera`` (PNG frames, no EXIF: f = 1.2 max(w, h), refined);
    pycolmap from COLMAP's default for a camera it does not know (``SIMPLE_RADIAL`` from
    f = 1.2 max(w, h), its focal length and k1 refined), kept in ``autok-pycolmap.json``;
    for an endoscope, the self-calibration the table above uses (``selfcal.json``).
    """
    from imageform.geometry import Camera
    from imageform.io import read_camera

    s = SEQUENCES[name]
    folder = data / name
    frames = _frames(folder)
    n = len(frames)
    h, w = frames[0].shape[:2]
    endo = s["endoscope"]
    given = read_camera(folder / "camera.toml").camera
    truth = None
    if (folder / "truth.npz").exists():
        with np.load(folder / "truth.npz") as z:
            truth = (z["R"], z["t"])
    guess = 1.2 * max(w, h)
    print(f"  {name}: {n} frames {w} x {h}", file=sys.stderr)
    runs: list[tuple[str, dict[str, Any]]] = []
    if not endo:  # the endoscopes' camera file is pycolmap's fisheye self-calibration
        runs.append(("imageform library, given K held", run_imageform(frames, given, endo)))
        runs.append(
            ("imageform library, given f refined", run_imageform(frames, given, endo, True))
        )
    pinhole = Camera(np.array([[guess, 0, (w - 1) / 2], [0, guess, (h - 1) / 2], [0, 0, 1]]))
    if not endo:  # the command with the given K: its check of K
        runs.append(
            ("imageform CLI, --camera (K held)", run_cli(folder, endo, True, intrinsics=True))
        )
    runs.append(("imageform library, no camera", run_imageform(frames, pinhole, endo, True)))
    runs.append(("imageform CLI, no --camera", run_cli(folder, endo, camera=False)))
    cached = folder / "autok-pycolmap.json"
    if cached.exists():
        pc = json.loads(cached.read_text())
        pc["R"], pc["t"] = np.array(pc["R"], float), np.array(pc["t"], float)
    else:
        pc = run_pycolmap(frames, None, endo, True, ("SIMPLE_RADIAL", (guess, w / 2, h / 2, 0.0)))
        keep = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in pc.items()}
        cached.write_text(json.dumps(keep))
    pc["f0"] = guess
    if "camera" in pc:
        pc["f"] = pc["camera"][0]
        pc["note"] = (pc.get("note", "") + f" k1 {pc['camera'][3]:.3f}").strip()
    runs.append(("pycolmap, no camera (SIMPLE_RADIAL)", pc))
    if endo:
        sc = json.loads((folder / "selfcal.json").read_text())
        sc["R"], sc["t"] = np.array(sc["R"], float), np.array(sc["t"], float)
        sc["f0"], sc["f"] = 0.45 * w, sc["camera"][0]
        sc["note"] = f"RADIAL_FISHEYE, k {sc['camera'][3]:.3f} {sc['camera'][4]:.3f}"
        runs.append(("pycolmap, self-calibrated fisheye", sc))
    f_ref: float | None = float(given.K[0, 0])
    if truth is not None:
        ref, ref_label = truth, "truth"
    else:
        ref_run = runs[-1][1]
        ref, ref_label, f_ref = (ref_run["R"], ref_run["t"]), runs[-1][0], ref_run.get("f")
    rows = []
    for label, r in runs:
        ok = r["reg"] > 0 and "points" in r
        if ok and "R" in r and not (truth is None and r is runs[-1][1]):
            rot, tra, rms = agreement(r["R"], r["t"], *ref)
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok and truth is None and r is runs[-1][1] else "-"
        f = r.get("f")
        rows.append(
            [
                name,
                label,
                f"{r['f0']:.1f}" if r.get("f0") else "-",
                f"{f:.1f}" if f is not None else "-",
                f"{100 * (f / f_ref - 1):+.1f} %" if f is not None and f_ref else "-",
                f"{r['reg']}/{n}",
                f"{r['reproj']:.2f}" if ok else "-",
                vs,
                f"{r['time']:.1f}" + (f" ({r['cpu']:.1f})" if "cpu" in r else ""),
                r.get("note", ""),
            ]
        )
    f_ref_text = f"{f_ref:.1f} px" if f_ref else "none"
    info = (
        f"{name} ({s['repo']}): {n} frames, {w} x {h} px, given f {given.K[0, 0]:.1f} px; "
        f"f against {'the given (true) K' if truth is not None else ref_label} "
        f"({f_ref_text}), poses against {ref_label}"
    )
    return info, rows


def exif_table(mirrors: Path, data: Path) -> tuple[str, list[list[Any]]]:
    """Sceaux's original JPEGs, their EXIF kept (``--exif MIRRORS``): the EXIF focal length.

    The 11 photographs as the repository holds them (2832 x 2128, their SHA-256 checked
    against the frozen list), copied byte for byte to ``DATA/sceaux-exif/frames``: the CLI
    without ``--camera`` (f from the EXIF 35 mm equivalent, refined), the CLI with
    ``--camera`` K.txt (K held: its check), pycolmap from the EXIF focal length
    (``SIMPLE_RADIAL``, its focal length and k1 refined; ``autok-pycolmap.json``). The
    focal lengths against K.txt (openMVG's calibration); the poses against pycolmap's.
    """
    from imageform.geometry import Camera
    from imageform.io import exif_camera, write_camera

    s = SEQUENCES["sceaux"]
    src = _sources("sceaux", mirrors)
    folder = data / "sceaux-exif"
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    keys = sorted(k for k in src if k.lower().endswith(".jpg"))
    for k in keys:
        if hashlib.sha256(src[k]).hexdigest() != HELD_OUT_SHA256[f"{s['repo']}:{k}"]:
            raise SystemExit(f"{k}: differs from the frozen SHA-256 list")
        (folder / "frames" / Path(k).name).write_bytes(src[k])
    frames = [_decode(src[k]) for k in keys]
    n = len(frames)
    h, w = frames[0].shape[:2]
    K = np.array(src["images/K.txt"].decode().split(), float).reshape(3, 3)
    write_camera(folder / "camera.toml", Camera(K, image_size=(w, h)))
    exif = exif_camera(folder / "frames" / Path(keys[0]).name)
    f_exif = exif.focal_length_px
    if f_exif is None:
        raise SystemExit("the Sceaux JPEGs carry no EXIF focal length")
    print(f"  sceaux-exif: {n} frames {w} x {h}, EXIF f {f_exif:.1f} px", file=sys.stderr)
    runs: list[tuple[str, dict[str, Any]]] = []
    runs.append(("imageform CLI, no --camera (EXIF)", run_cli(folder, False, camera=False)))
    runs.append(
        ("imageform CLI, --camera K.txt (K held)", run_cli(folder, False, True, intrinsics=True))
    )
    cached = folder / "autok-pycolmap.json"
    if cached.exists():
        pc = json.loads(cached.read_text())
        pc["R"], pc["t"] = np.array(pc["R"], float), np.array(pc["t"], float)
    else:
        start = ("SIMPLE_RADIAL", (f_exif, w / 2, h / 2, 0.0))
        pc = run_pycolmap(frames, None, False, True, start)
        keep = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in pc.items()}
        cached.write_text(json.dumps(keep))
    pc["f0"] = f_exif
    if "camera" in pc:
        pc["f"] = pc["camera"][0]
        pc["note"] = (pc.get("note", "") + f" k1 {pc['camera'][3]:.3f}").strip()
    runs.append(("pycolmap, from the EXIF f (SIMPLE_RADIAL)", pc))
    f_ref = float(K[0, 0])
    rows = []
    for label, r in runs:
        ok = r["reg"] > 0 and "points" in r
        if ok and "R" in r and r is not pc and pc["reg"] > 0:
            rot, tra, rms = agreement(r["R"], r["t"], pc["R"], pc["t"])
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok and r is pc else "-"
        f = r.get("f")
        pcf = pc.get("f")
        vs_pc = f" ({100 * (f / pcf - 1):+.1f} % vs pycolmap)" if f and pcf and r is not pc else ""
        rows.append(
            [
                "sceaux-exif",
                label,
                f"{r['f0']:.1f}" if r.get("f0") else "-",
                f"{f:.1f}" if f is not None else "-",
                (f"{100 * (f / f_ref - 1):+.1f} %" + vs_pc) if f is not None else "-",
                f"{r['reg']}/{n}",
                f"{r['reproj']:.2f}" if ok else "-",
                vs,
                f"{r['time']:.1f}",
                r.get("note", ""),
            ]
        )
    info = (
        f"sceaux-exif ({s['repo']}, the original JPEGs with their EXIF: {exif.model}, "
        f"{exif.focal_length_mm:g} mm, 35 mm equivalent {exif.equivalent_focal_length_mm:g} mm): "
        f"{n} frames, {w} x {h} px, EXIF f {f_exif:.1f} px; f against K.txt "
        f"({f_ref:.1f} px), poses against pycolmap, from the EXIF f"
    )
    return info, rows


AUTOK_COLUMNS = [
    "sequence",
    "run",
    "f start px",
    "f found px",
    "f vs truth or reference",
    "registered",
    "reprojection px (median)",
    "vs truth or reference: rotation / translation deg / centres % of path",
    "s (CPU s)",
    "note",
]

COLUMNS = [
    "sequence",
    "run",
    "registered",
    "points",
    "track length",
    "reprojection px (median)",
    "vs truth or reference: rotation / translation deg / centres % of path",
    "s",
    "note",
]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=Path("/tmp/sfmfresh/data"))
    ap.add_argument("--prepare", type=Path, default=None, help="folder of the bare git mirrors")
    ap.add_argument("--split", choices=("tuning", "held-out"), default="tuning")
    ap.add_argument("--only", nargs="+", default=None)
    ap.add_argument("--digests", action="store_true", help="print the held-out SHA-256 list")
    ap.add_argument(
        "--autok",
        action="store_true",
        help="without a camera file: the focal lengths found (imageform, pycolmap)",
    )
    ap.add_argument(
        "--exif",
        type=Path,
        default=None,
        metavar="MIRRORS",
        help="with --autok: Sceaux's original JPEGs and their EXIF, from the bare git mirrors",
    )
    args = ap.parse_args()
    if args.prepare is not None:
        for name in args.only or SEQUENCES:
            prepare(name, args.prepare, args.data)
            print(f"prepared {name}", file=sys.stderr)
        return
    if args.digests:
        for key, h in held_out_digests(args.data).items():
            print(f"    {key!r}: {h!r},")
        return
    names = [k for k, s in SEQUENCES.items() if s["split"] == args.split]
    if args.exif is not None:  # the EXIF run alone (Sceaux: held-out)
        args.autok, args.split, names = True, "held-out", []
    if args.only:
        names = [k for k in names if k in args.only]
    if args.split == "held-out" and HELD_OUT_SHA256:
        found = held_out_digests(args.data)
        if found != HELD_OUT_SHA256:
            raise SystemExit("the held-out sources differ from the frozen SHA-256 list")
    import pycolmap

    title = f"Structure from motion on fresh real sequences: the {args.split} half"
    if args.autok:
        title = f"Reconstruction without a camera file: the {args.split} half"
    print(header(title))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine); pycolmap {pycolmap.__version__}\n")
    rows: list[list[Any]] = []
    infos = []
    for name in names:
        info, r = (autok_table if args.autok else sequence_table)(name, args.data)
        infos.append(f"- {info}")
        rows += r
    if args.exif is not None:
        info, r = exif_table(args.exif, args.data)
        infos.append(f"- {info}")
        rows += r
    print("\n".join(infos) + "\n")
    print(markdown_table(AUTOK_COLUMNS if args.autok else COLUMNS, rows))
    if args.autok:
        print("\nEvery note line `imageform reconstruct` printed:\n")
        print("\n".join(f"- {run}: `{line}`" for run, line in CLI_NOTES) or "- none")


if __name__ == "__main__":
    main()
