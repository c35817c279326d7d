"""Radial distortion refined without a camera file: ``imageform reconstruct`` before and after.

``imageform reconstruct`` without ``--camera`` guesses f (the EXIF's 35 mm equivalent, else
1.2 max(w, h)) and refines it; before this change it assumed no distortion, after it also
refines one radial term k1 (COLMAP's ``SIMPLE_RADIAL``, ``refine_distortion``). Each
sequence is run by the command before (``--before SRC``: the ``src`` folder of the code
before, on ``PYTHONPATH``) and after (this checkout), and by pycolmap from the same f
(``SIMPLE_RADIAL``, its focal length and k1 refined, sequential matching; kept in
``k1-pycolmap.json`` in the sequence's folder and reused by a second run). Columns: f
start and found (px) and against the reference, k1 found, frames registered, median
reprojection error (px), the poses against the reference (median relative rotation and
translation-direction angles over consecutive frames, degrees; camera centres' RMS after
the best similarity, % of the path: ``check_sfm_fresh.agreement``), wall seconds and the
command's CPU seconds (``RUSAGE_CHILDREN``), one run each on a shared machine.

Tuning sequences (the earlier sessions' data, ``benchmarks/check_sfm_fresh.py`` prepares
them with ``--prepare``; its docstring names their repositories, commits and licences):
``sceaux-exif`` (openMVG/ImageDataset_SceauxCastle, the 11 original 2832 x 2128 JPEGs with
their EXIF, copied from the mirror; f against ``K.txt``, the poses against pycolmap),
``temple`` and ``dino`` (Middlebury's rings: f and poses against the true calibration),
``viking`` (against pycolmap), ``colon-a`` and ``colon-b`` (a fisheye colonoscope, 192 x 192
PNG frames; against pycolmap's ``RADIAL_FISHEYE`` self-calibration, ``selfcal.json``, as
``sfm-autok-2026-11-30e.md``);
``dt990`` and ``gun`` (Promethaes/Photogrammatry at ``11cac0f``, no licence stated:
measured here, never committed; the 2026-11-30g held-out half, tuning data since): iPhone 11
photographs (3024 x 4032 JPEGs with EXIF, 26 mm equivalent) of headphones
(``Photos/DT990s``, every 4th of 46: 12) and of a toy gun (``Photos/Gun``, every 5th of 58:
12), reduced 4 times to 756 x 1008 with their EXIF (``_reduced``: two cores); no
calibration: f and the poses against pycolmap's. ``c3vd``: the C3VD colonoscope's 13 frames
of ``tests/data/endo`` (445 x 448, CC BY 4.0, a Kannala-Brandt fisheye), f and the poses
against imageform's reconstruction with the working camera of that folder (``--camera``).

Held-out (2026-11-30h, chosen for the radial term's checks: a repository no earlier check
used, frozen by the SHA-256 below before any run; run once with the final code):
bashtavenko/sfm at ``eb75fac`` (no licence stated: measured here, never committed), two
Pixel 6a video clips of 1080 x 1920 frames without EXIF, ``testdata/reconstruction/kleenex``
(13 frames of a tissue box) and ``testdata/reconstruction/frame_0..9`` (``clip10``, 10
frames), reduced 2 times to 540 x 960 (``prepare_video``); f against the repository's Pixel
6a calibration (``testdata/pixel_6a_calibration.txtpb``: fx 1419.4 px at full size, 709.7
px reduced), the poses against pycolmap's.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fresh.py \\
        --prepare /work/.mirror --data DATA --only colon-a colon-b temple viking dino
    git archive BASE src | tar -x -C BEFORE
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_k1.py \\
        --data DATA --mirrors /work/.mirror --before BEFORE/src [--only sceaux-exif temple]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_k1.py \\
        --data DATA --mirrors /work/.mirror --before BEFORE/src --held-out
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
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
from benchmarks.check_sfm_fresh import (  # noqa: E402
    HELD_OUT_SHA256,
    SEQUENCES,
    _decode,
    _nan_poses,
    _show,
    agreement,
    run_pycolmap,
    self_calibrated_camera,
)

TUNING = [
    "sceaux-exif", "temple", "dino", "viking", "colon-a", "colon-b", "dt990", "gun", "c3vd"
]  # fmt: skip

PHOTO_REPO = "Promethaes/Photogrammatry"
PHOTO_COMMIT = "11cac0fb3505f420f1f24cd0c422027fa33ff4e9"
#: The 2026-11-30g held-out photographs (tuning data since), frozen then: path -> SHA-256.
PHOTOS: dict[str, str] = {
    "Photos/DT990s/IMG_4936.JPG": "f0dde573a55a23b2db7b496229228dfd0d2c97b5bc3efc7ec4dc1f838ba7aff8",  # noqa: E501
    "Photos/DT990s/IMG_4940.JPG": "3534ebe158f97e45a8747923d1c94d21ec8b2f68b0d1ca1b76a6cca27cc714d1",  # noqa: E501
    "Photos/DT990s/IMG_4944.JPG": "ec5379ba1ce601056783bb27b31690420f6a88c26ee10f991fd8a77cdbd53103",  # noqa: E501
    "Photos/DT990s/IMG_4948.JPG": "c830cde2c672b60c79db8456665ff598236b8178f9d8ac025d9d4dc6c20e1319",  # noqa: E501
    "Photos/DT990s/IMG_4952.JPG": "744646989719f2374c06eae0584d7fa92b66ca42ef83e695acb86424b8804976",  # noqa: E501
    "Photos/DT990s/IMG_4956.JPG": "78bdbe7f8e2a3307005240d0478417176c96ed4540d5e749778b7917f4c03172",  # noqa: E501
    "Photos/DT990s/IMG_4960.JPG": "8538f55c561eee543b36996bfce542547eb5c3b05ad12344d017b9d4d8edafb5",  # noqa: E501
    "Photos/DT990s/IMG_4964.JPG": "d330ef8ba420cc57bb841d28cd1dffe84b7d8097bec5f3b6928dfebc2eb3d571",  # noqa: E501
    "Photos/DT990s/IMG_4968.JPG": "e327ddf82ea22f87ffe1072e0246b3dc1aa0cc275413838ea69e69a353f33854",  # noqa: E501
    "Photos/DT990s/IMG_4972.JPG": "0abac2da7755b5b2b2c754a898ac28ae40d37f7aa11e9bad41d10ee3d089ebb7",  # noqa: E501
    "Photos/DT990s/IMG_4976.JPG": "7e29412b29d435e0756394268a52ed64caffe96e78fb7a53f6f443b9d0d103ae",  # noqa: E501
    "Photos/DT990s/IMG_4980.JPG": "d3e511b6620c83214ce7d121efef619f92108f94a3552883e60b02421bbca569",  # noqa: E501
    "Photos/Gun/IMG_5033.JPG": "d71bc03e17a84e3596128430271099e0e4760fd3a42c41d65910ecb5f549c62f",
    "Photos/Gun/IMG_5038.JPG": "478bb35aafcca507f9a3d45cff4dbabee6184ce9faa512c8956ab4ab25a2dd43",
    "Photos/Gun/IMG_5043.JPG": "ab910eafd965f65035cd235f81e70befb0a87fd22f908d2d9b975c318fd0cab7",
    "Photos/Gun/IMG_5048.JPG": "280066b46bf8d034c709108aa5ba6f3900e1fc8864ebac8697e1b197584f95ef",
    "Photos/Gun/IMG_5053.JPG": "9268850022ccadbdb623f8d3dee7cdfc159ac75e1deb0e42b3009073e71c1f30",
    "Photos/Gun/IMG_5058.JPG": "f9b404fe13816c0c2f41030cad080312ea9e509e6b9a8b72df0f1dc782372e31",
    "Photos/Gun/IMG_5063.JPG": "896a9a112e2205f040fe5a078ea0f4cba9431d5ab29bb18497e45ccee0a870ee",
    "Photos/Gun/IMG_5068.JPG": "3871d6e3a65034c68ab871a46f4630c5ba2bd7d87c845093bc7d4664bad2c04e",
    "Photos/Gun/IMG_5073.JPG": "02c8e45655260bc8fdaa9092af6957c625f9244e3b2b0452b7c5b3762f204659",
    "Photos/Gun/IMG_5078.JPG": "e54bcd67227980f7de04fc5a51a457011b0069dab57b314b0f9d6455493922a9",
    "Photos/Gun/IMG_5083.JPG": "bcfeaccb6ca185a1772545b1e0a60455474e9a90214403f7846ed59d070850a2",
    "Photos/Gun/IMG_5088.JPG": "6c1099b8780c126840bd629fbc22da4c65f1d5cbc25e5053539a60d15347694c",
}
PHOTO_SETS = {"dt990": "Photos/DT990s/", "gun": "Photos/Gun/"}

HELD_REPO = "bashtavenko/sfm"
HELD_COMMIT = "eb75fac2de29f6ab7ded5e1a6d66e19e329aff5d"
#: The held-out video frames (2026-11-30h), frozen before any run: path -> SHA-256.
HELD_OUT: dict[str, str] = {
    "testdata/reconstruction/frame_0.jpg": "f38fbb75d58fa21093e15922bca795e9f784e6dd0e990dc2d542fa8fa511595c",  # noqa: E501
    "testdata/reconstruction/frame_1.jpg": "7a8ebdf53ee870f4f6b494da5c826dcc0762a933264d62cea8ce9ac81bcb2cbe",  # noqa: E501
    "testdata/reconstruction/frame_2.jpg": "9a39c504d7ffd9b3e3f45845891f7335ac12e397bd0b343d2a376711e1e8a7dd",  # noqa: E501
    "testdata/reconstruction/frame_3.jpg": "9db6e8898f9385e59305c56e21b1ccffa1a8420ab0a520b6e6a6a816e69206f4",  # noqa: E501
    "testdata/reconstruction/frame_4.jpg": "933ec8118506b1c6f44706f1fe224f05e4c62519aba749328d657b56c3d75c2c",  # noqa: E501
    "testdata/reconstruction/frame_5.jpg": "d91030dfb8e7274c67d1380f82050af58ec71c11c7c821ce35991e58fe2312cb",  # noqa: E501
    "testdata/reconstruction/frame_6.jpg": "6394f5642c70596948aa31da9d2b4539a8aa833c6b03b01844b517e86dcab0a9",  # noqa: E501
    "testdata/reconstruction/frame_7.jpg": "4b4a068cd339c8db8790d0862531c859e67a55010935da0fc1007f60687f42c3",  # noqa: E501
    "testdata/reconstruction/frame_8.jpg": "c974acca28ed51c6412ae9dbc4676438931e219593bd24d906b7686ddd9b9eaa",  # noqa: E501
    "testdata/reconstruction/frame_9.jpg": "867ecf4437f4bff841bde016871613972e102141496eed5d9b76ac33ec49e476",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_1.jpg": "986af40cdffc9be1b3c8e0cf522d0e16da75912580edef0b8d0b5fa55b02ceb2",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_16.jpg": "13beacbb68ec611340bdb6af132211befbfc7f0c0ee29b970c1d6696a6b4ffc2",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_24.jpg": "35f5fc1077a9dbfd98557d70cadaef0896a5b0c24f1b1898433fdac702dcc5d1",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_33.jpg": "35a082adb0a94a0a75206a850355a232ea5db4c71cf671d49bf98008d76afeb2",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_34.jpg": "b7550e8eed79871a675cca6cf1ed024179b9b6291db1374a9d44c4967ba21cf3",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_35.jpg": "06a3cd6c199df38221d63fc3e8d2ea1bf3e5f09b3c9f367cb160ddb6a6fe19d4",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_36.jpg": "63d835572f75f193c3eca7627b35e2871ad307b6dc69d75de2e66792d4bff668",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_37.jpg": "a9d640e4ef4d086774947a9c752e0bec79ce3ca50b9c22c2df0c501582a57c93",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_38.jpg": "04dde39fbb3a57c48497db89c0ccde49b901f7fe72b8ebbb2b9950fed75f05d7",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_41.jpg": "9ef34f5028408d69b287877ea392a3d66957e80e12746567cbfcd8814298fe6a",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_48.jpg": "f875803cbe21d01c79b055484c813ddca9f0bc2c194086f19afbe4c4ea1c36f5",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_58.jpg": "eed58d30cd625b8389195e92b5d05709dd89e886127208e70bcd39aa15117874",  # noqa: E501
    "testdata/reconstruction/kleenex/frame_70.jpg": "d545509e2f1683dcdc6b99e2dd85b4e2a658a7cb66815d5b7044b064fd8cbe4c",  # noqa: E501
}
HELD = {"kleenex": "testdata/reconstruction/kleenex/", "clip10": "testdata/reconstruction/frame_"}
#: The Pixel 6a's calibration in the repository (testdata/pixel_6a_calibration.txtpb) at
#: 1080 x 1920: fx 1419.35, fy 1424.78 px; the frames are reduced 2 times.
HELD_FOCAL = 1419.35339 / 2


def prepare_jpegs(name: str, mirrors: Path, data: Path) -> Path:
    """Copy a JPEG sequence byte for byte (its EXIF kept), its SHA-256 checked."""
    folder = data / name
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    if name == "sceaux-exif":
        repo, commit = SEQUENCES["sceaux"]["repo"], SEQUENCES["sceaux"]["commit"]
        frozen = {
            k.split(":", 1)[1]: h
            for k, h in HELD_OUT_SHA256.items()
            if k.startswith(repo) and k.endswith(".JPG")
        }
        kt = _show(mirrors, repo, commit, "images/K.txt")
        K = np.array(kt.decode().split(), float).reshape(3, 3)
        (folder / "K.json").write_text(json.dumps(K.tolist()))
    else:
        repo, commit = PHOTO_REPO, PHOTO_COMMIT
        frozen = {p: h for p, h in PHOTOS.items() if p.startswith(PHOTO_SETS[name])}
    for path, digest in sorted(frozen.items()):
        blob = _show(mirrors, repo, commit, path)
        if hashlib.sha256(blob).hexdigest() != digest:
            raise SystemExit(f"{repo}:{path} differs from the frozen SHA-256")
        if name in PHOTO_SETS:
            blob = _reduced(blob)
        (folder / "frames" / Path(path).name).write_bytes(blob)
    return folder


def prepare_video(name: str, mirrors: Path, data: Path) -> Path:
    """The held-out video frames, their SHA-256 checked, reduced 2 times (INTER_AREA), PNG."""
    import cv2

    folder = data / name
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    frozen = {p: h for p, h in HELD_OUT.items() if p.startswith(HELD[name])}
    for path, digest in frozen.items():
        blob = _show(mirrors, HELD_REPO, HELD_COMMIT, path)
        if hashlib.sha256(blob).hexdigest() != digest:
            raise SystemExit(f"{HELD_REPO}:{path} differs from the frozen SHA-256")
        im = _decode(blob)
        small = cv2.resize(im, (im.shape[1] // 2, im.shape[0] // 2), interpolation=cv2.INTER_AREA)
        index = int(Path(path).stem.split("_")[-1])  # frame_16: the video's order
        out = folder / "frames" / f"frame_{index:03d}.png"
        cv2.imwrite(str(out), np.ascontiguousarray(small[..., ::-1]))
    return folder


def prepare_c3vd(data: Path) -> Path:
    """The C3VD colonoscope's 13 frames of ``tests/data/endo`` (CC BY 4.0) and its camera."""
    import shutil

    folder = data / "c3vd"
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    for p in sorted((ROOT / "tests" / "data" / "endo").glob("*.jpg")):
        shutil.copyfile(p, folder / "frames" / p.name)
    shutil.copyfile(ROOT / "tests" / "data" / "endo" / "camera.toml", folder / "given.toml")
    return folder


def _reduced(blob: bytes) -> bytes:
    """A phone's JPEG reduced 4 times as an editor does, its EXIF kept (the 35 mm equivalent
    focal length scales with the size), its orientation applied and the tag cleared (every
    reader sees the same pixels); Pillow's bilinear filter, quality 95."""
    import io

    from PIL import Image, ImageOps

    with Image.open(io.BytesIO(blob)) as im:
        exif = im.getexif()
        up = ImageOps.exif_transpose(im)
        small = up.resize((up.width // 4, up.height // 4), Image.Resampling.BILINEAR)
    exif[0x0112] = 1  # orientation: as stored
    out = io.BytesIO()
    small.save(out, "JPEG", quality=95, exif=exif.tobytes())
    return out.getvalue()


def read_frames(folder: Path) -> list[np.ndarray]:
    files = sorted(folder.glob("frames/*.png")) or sorted(folder.glob("frames/*.[Jj][Pp][Gg]"))
    return [_decode(p.read_bytes()) for p in files]


def run_cli(
    folder: Path,
    endoscope: bool,
    src: Path,
    camera: Path | None = None,
    extra: tuple[str, ...] = (),
) -> dict[str, Any]:
    """``python -m imageform reconstruct FRAMES`` without ``--camera`` (or with ``camera``),
    ``src`` imported; ``extra``: more options."""
    from imageform.geometry import rvec_to_matrix

    env = os.environ.copy()
    env["PYTHONPATH"] = f"{src}{os.pathsep}{ROOT}"
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "imageform", "reconstruct", str(folder / "frames")]
        cmd += ["-o", str(Path(tmp) / "out")]
        if endoscope:
            cmd += ["--auto-mask", "--contrast-threshold", "0.01"]
        if camera is not None:
            cmd += ["--camera", str(camera)]
        cmd += list(extra)
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        dt = time.perf_counter() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
        notes = [ln.strip().removeprefix("imageform: ") for ln in p.stderr.splitlines()]
        notes = [ln for ln in notes if ln.startswith("note:")]
        if p.returncode != 0:
            lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
            return {"reg": 0, "time": dt, "cpu": cpu, "note": (lines[-1] if lines else "?")[:160]}
        m = json.loads((Path(tmp) / "out" / "metrics.json").read_text())
        import csv

        with (Path(tmp) / "out" / "cameras.csv").open() as fh:
            rows = list(csv.DictReader(fh))
        R, t = _nan_poses(len(rows))
        for i, r in enumerate(rows):
            if r["registered"] == "1":
                R[i] = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
                t[i] = [float(r[k]) for k in ("tx", "ty", "tz")]
        intr = m["intrinsics"]
        restarts = sum("reconstructed again" in ln for ln in notes)
        return {
            "reg": m["registered"],
            "points": m["points"],
            "reproj": m["reprojection_px_median"],
            "R": R,
            "t": t,
            "f0": intr["focal_px_initial"],
            "f": intr["focal_px"],
            "k1": intr.get("k1"),
            "time": dt,
            "cpu": cpu,
            "note": f"{restarts} restarts" if restarts else "",
            "notes": notes,
        }


def sequence(
    name: str, data: Path, mirrors: Path, before: Path
) -> tuple[str, list[list[Any]], list[tuple[str, str]]]:
    from imageform.io import read_camera

    endo = name.startswith("colon") or name == "c3vd"
    if name == "sceaux-exif" or name in PHOTO_SETS:
        folder = prepare_jpegs(name, mirrors, data)
    elif name in HELD:
        folder = prepare_video(name, mirrors, data)
    elif name == "c3vd":
        folder = prepare_c3vd(data)
    else:
        folder = data / name
    frames = read_frames(folder)
    n = len(frames)
    h, w = frames[0].shape[:2]
    print(f"  {name}: {n} frames {w} x {h}", file=sys.stderr)
    runs: list[tuple[str, dict[str, Any]]] = []
    runs.append(("imageform CLI before (--before)", run_cli(folder, endo, before)))
    after = run_cli(folder, endo, ROOT / "src")
    runs.append(("imageform CLI after (this checkout)", after))
    f0 = after.get("f0") or runs[0][1].get("f0") or 1.2 * max(w, h)
    cached = folder / "k1-pycolmap.json"
    if cached.exists():
        pc = json.loads(cached.read_text())
        pc["R"], pc["t"] = np.array(pc["R"], float), np.array(pc["t"], float)
    else:
        pc = run_pycolmap(frames, None, endo, True, ("SIMPLE_RADIAL", (f0, w / 2, h / 2, 0.0)))
        keep = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in pc.items()}
        cached.write_text(json.dumps(keep))
    pc["f0"] = f0
    if "camera" in pc:
        pc["f"], pc["k1"] = pc["camera"][0], pc["camera"][3]
    runs.append(("pycolmap (SIMPLE_RADIAL)", pc))
    truth = None
    f_ref: float | None = None
    if (folder / "truth.npz").exists():
        with np.load(folder / "truth.npz") as z:
            truth = (z["R"], z["t"])
        f_ref, ref_label = float(read_camera(folder / "camera.toml").camera.K[0, 0]), "truth"
    elif name == "c3vd":
        given = run_cli(folder, endo, ROOT / "src", folder / "given.toml")
        given["f0"] = given["f"]
        given["note"] = "the working camera of tests/data/endo (Kannala-Brandt)"
        runs.append(("imageform CLI, --camera (the fisheye)", given))
        f_ref, ref_label = given["f"], "imageform with the fisheye camera file"
    elif endo:
        _, sc = self_calibrated_camera(folder, frames)
        sc["R"], sc["t"] = np.asarray(sc["R"], float), np.asarray(sc["t"], float)
        sc["f0"], sc["f"] = 0.45 * w, sc["camera"][0]
        sc["note"] = f"RADIAL_FISHEYE, k {sc['camera'][3]:.3f} {sc['camera'][4]:.3f}"
        runs.append(("pycolmap, self-calibrated fisheye", sc))
        f_ref, ref_label = sc["f"], "pycolmap's fisheye self-calibration"
    else:
        f_ref, ref_label = pc.get("f"), "pycolmap (SIMPLE_RADIAL)"
    if name == "sceaux-exif":
        f_ref = float(json.loads((folder / "K.json").read_text())[0][0])
    if name in HELD:
        f_ref = HELD_FOCAL
    ref = truth if truth is not None else (runs[-1][1]["R"], runs[-1][1]["t"])
    rows = []
    for label, r in runs:
        ok = r["reg"] > 0 and "points" in r
        is_ref = truth is None and r is runs[-1][1]
        if ok and not is_ref:
            rot, tra, rms = agreement(r["R"], r["t"], *ref)
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok else "-"
        f = r.get("f") if ok else None
        k1 = r.get("k1") if ok else None
        rows.append(
            [
                name,
                label,
                f"{r['f0']:.1f}" if r.get("f0") else "-",
                f"{f:.1f}" if f is not None else "-",
                f"{100 * (f / f_ref - 1):+.1f} %" if f is not None and f_ref else "-",
                f"{k1:+.4f}" if k1 is not None else "-",
                f"{r['reg']}/{n}",
                f"{r['reproj']:.2f}" if ok else "-",
                vs,
                f"{r['time']:.1f}" + (f" ({r['cpu']:.1f})" if "cpu" in r else ""),
                r.get("note", ""),
            ]
        )
    f_text = f"{f_ref:.1f} px" if f_ref else "none"
    fsrc = "K.txt" if name == "sceaux-exif" else ref_label
    if name in HELD:
        fsrc = "the repository's Pixel 6a calibration"
    info = (
        f"{name}: {n} frames, {w} x {h} px; f against {fsrc} ({f_text}), poses against {ref_label}"
    )
    notes = [(f"{name}, {label}", ln) for label, r in runs[:2] for ln in r.get("notes", [])]
    return info, rows, notes


COLUMNS = [
    "sequence",
    "run",
    "f start px",
    "f found px",
    "f vs reference",
    "k1",
    "registered",
    "reprojection px (median)",
    "poses vs reference: rotation / translation deg / centres % of path",
    "s (CPU s)",
    "note",
]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--mirrors", type=Path, default=Path("/work/.mirror"))
    ap.add_argument("--before", type=Path, required=True, help="src folder of the code before")
    ap.add_argument("--held-out", action="store_true")
    ap.add_argument("--only", nargs="+", default=None)
    args = ap.parse_args()
    import pycolmap

    names = list(HELD) if args.held_out else TUNING
    if args.only:
        names = [k for k in names if k in args.only]
    half = "held-out" if args.held_out else "tuning"
    print(header(f"Radial distortion refined without a camera file: the {half} half"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine); pycolmap {pycolmap.__version__}\n")
    infos, rows, notes = [], [], []
    for name in names:
        info, r, nt = sequence(name, args.data, args.mirrors, args.before)
        infos.append(f"- {info}")
        rows += r
        notes += nt
    print("\n".join(infos) + "\n")
    print(markdown_table(COLUMNS, rows))
    print("\nEvery note line about the camera `imageform reconstruct` printed:\n")
    keys = ("no camera file", "moved", "distortion", "focal", "radial", "ran off", "settle")
    said = [(run, ln) for run, ln in notes if any(k in ln for k in keys)]
    print("\n".join(f"- {run}: `{line}`" for run, line in said) or "- none")


if __name__ == "__main__":
    main()
