"""``imageform cache``: where numba's compiled kernels live; warm or clear them.

numba compiles imageform's kernels on first use (15-25 s for the first ``pose``, ``demosaic``
or ``simulate``) and caches them on disk (``imageform._kernels.jit``: the policy and the
location). ``imageform cache --warm`` pays that once, ahead of time: after installing, in a
container image, or before a CI test run. It runs the commands people wait on (``simulate`` with its
built-in scene, ``pose --ransac`` with a Brown-Conrady camera, ``demosaic`` with each method,
``convert``, ``calibrate`` on three checkerboard views, ``undistort``, ``depth``,
``track`` with a ChArUco board and with one ArUco marker, ``vanishing``, ``develop`` (a DNG
and a GoPro GPR, whose VC-5 decoder alone takes 10-35 s to compile), ``characterize`` (board,
chart, slanted edge), ``segment``, ``delta-e``, and ``reconstruct`` on five frames of a textured
room when OpenCV is installed) on small inputs it writes to a temporary folder, each in its own
process (``--jobs`` at once), so that every kernel they use is compiled for the same types and
layouts as a real run, and written to the cache.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import click

__all__ = ["cache_command", "warm_cache"]

_INPUTS = r"""
import sys
from pathlib import Path
import numpy as np
from imageform.geometry import BrownConrady, Camera
from imageform.io import write_camera, write_image

work = Path(sys.argv[1])
K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
dist = BrownConrady(-0.2, 0.05, 1e-3, -5e-4, 0.0)
write_camera(work / "cam.toml", Camera(K, np.eye(3), np.zeros(3), (640, 480), distortion=dist),
             has_pose=True)
rng = np.random.default_rng(0)
X = rng.uniform(-1, 1, (40, 3)) + [0, 0, 6]
uv = np.asarray(Camera(K, np.eye(3), [0.1, 0.0, 0.2], distortion=dist).project(X).uv)
uv[::10] += 30.0
rows = [",".join(repr(float(v)) for v in (*a, *b)) for a, b in zip(X, uv, strict=True)]
(work / "pairs.csv").write_text("X,Y,Z,u,v\n" + "\n".join(rows) + "\n")
img = (rng.uniform(0, 1, (64, 96, 3)) * 255).astype(np.uint8)
write_image(work / "rgb8.png", img)
write_image(work / "mosaic8.png", np.ascontiguousarray(img[..., 1:2]))
# three views of a 9 x 6 checkerboard (30 mm squares) for calibrate's detector and refinement
vv, uu = np.mgrid[0:480, 0:640].astype(np.float64)
for k, (ax, ay) in enumerate(((0.3, 0.0), (0.0, 0.35), (-0.25, 0.2))):
    Rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    Ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    R = Rx @ Ry
    H = K @ np.column_stack([R[:, 0], R[:, 1], [-180.0, -135.0, 900.0]])
    q = np.linalg.solve(H, np.stack([uu.ravel(), vv.ravel(), np.ones(uu.size)]))
    x, y = (q[0] / q[2] + 30.0) / 30.0, (q[1] / q[2] + 30.0) / 30.0  # squares from -1
    inside = (x >= 0) & (x < 12) & (y >= 0) & (y < 9)
    dark = (np.floor(x) + np.floor(y)) % 2 == 0
    board = np.where(inside & ~((x >= 1) & (x < 11) & (y >= 1) & (y < 8) & dark), 230, 25)
    board = np.where(inside, board, 128).reshape(480, 640).astype(np.uint8)
    write_image(work / f"board{k}.png", board[..., None])
write_image(work / "board_rgb.png", np.repeat(board[..., None], 3, axis=2))
# a rectified stereo pair (a textured plane 10 px of disparity away) and its rig, for depth
from imageform.io import CameraFile, StereoCameraFile, write_stereo_camera
Kd = np.array([[200.0, 0.0, 79.5], [0.0, 200.0, 59.5], [0.0, 0.0, 1.0]])
write_stereo_camera(work / "rig.toml", StereoCameraFile(
    CameraFile(Camera(Kd, image_size=(160, 120))),
    CameraFile(Camera(Kd, np.eye(3), [-50.0, 0.0, 0.0], (160, 120)), has_pose=True)))
tex = (np.random.default_rng(7).uniform(0, 1, (120, 160)) * 255).astype(np.uint8)
write_image(work / "pair_r.png", tex[..., None])
write_image(work / "pair_l.png", np.roll(tex, 10, axis=1)[..., None])
# track: two frames of a 7 x 5 ChArUco board (5x5_100), two of one ArUco marker (4x4_50, id 7)
from imageform.geometry import CharucoBoard, aruco_marker_image
chart = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100").image(50, margin_px=20)
marker = np.pad(aruco_marker_image(7, "4x4_50", size_px=120), 40, constant_values=255)
for name, face in (("charuco", chart), ("marker", marker)):
    (work / name).mkdir()
    for k in range(2):
        frame = np.full((480, 640), 110, np.uint8)
        y, x = 60 + 8 * k, 90 + 12 * k
        frame[y : y + face.shape[0], x : x + face.shape[1]] = face
        write_image(work / name / f"frame{k}.png", np.repeat(frame[..., None], 3, axis=2))
# develop: a small DNG (the raw pipeline's kernels), written again with a GainMap in its
# OpcodeList2 (lens shading, as phones' DNGs and GoPro's GPRs carry: its kernel compiles in
# 10-30 s)
import struct
import tifffile
from imageform.io import write_dng
raw = (rng.uniform(0.05, 0.8, (64, 96)) * 4095).astype(np.uint16)
write_dng(work / "raw.dng", raw, white_level=4095, color_matrix=np.eye(3))
with tifffile.TiffFile(work / "raw.dng") as tf:
    dng_tags = [(t.code, int(t.dtype), t.count, t.value, True)
                for t in tf.pages[0].tags if t.code >= 33421]  # the CFA and DNG tags
params = struct.pack(">8I", 0, 0, 64, 96, 0, 1, 2, 2) + struct.pack(">2I4d", 3, 3, 0.5, 0.5, 0, 0)
params += struct.pack(">I", 1) + np.full(9, 1.2, ">f4").tobytes()
ops = struct.pack(">I", 1) + struct.pack(">4I", 9, 0x01030000, 1, len(params)) + params
tifffile.imwrite(work / "raw.dng", raw, photometric=32803,
                 extratags=[*dng_tags, (51009, 7, len(ops), ops, True)])
# develop a GoPro GPR: the VC-5 decoder's kernels (a first decode compiles them for 10-35 s).
# The package's 10 kB GPR of a synthetic 100 x 76 mosaic is tests/data/vc5/synthetic.gpr
from importlib.resources import files
(work / "warm.gpr").write_bytes(files("imageform.cli").joinpath("data", "warm.gpr").read_bytes())
# characterize: a lab folder of the three board views, a ColorChecker photograph and a
# slanted edge (a dark square turned 5 degrees, 4 x 4 rays a pixel)
from imageform.analysis import synthetic_chart_photo
lab = work / "lab"
for part in ("checkerboard", "colorchecker", "edge"):
    (lab / part).mkdir(parents=True)
(lab / "lab.toml").write_text('[checkerboard]\nboard = "9x6"\nsquare = "30mm"\n')
for k in range(3):
    (lab / "checkerboard" / f"view{k}.png").write_bytes((work / f"board{k}.png").read_bytes())
photo = synthetic_chart_photo(shape=(240, 320), width=0.6, tilt=10.0, rotation=3.0, rng=1)
write_image(lab / "colorchecker" / "developed.png", (photo.image * 255 + 0.5).astype(np.uint8))
ys, xs = (np.mgrid[0:160 * 4, 0:200 * 4] + 0.5) / 4.0
c, s = np.cos(np.radians(5.0)), np.sin(np.radians(5.0))
a, b = c * (xs - 100) + s * (ys - 80), -s * (xs - 100) + c * (ys - 80)
edge = np.where((np.abs(a) < 45) & (np.abs(b) < 45), 0.1, 0.8).reshape(160, 4, 200, 4).mean((1, 3))
edge = np.where(edge <= 0.0031308, 12.92 * edge, 1.055 * edge ** (1 / 2.4) - 0.055)
edge8 = (edge * 255 + 0.5).astype(np.uint8)
write_image(lab / "edge" / "edge.png", np.repeat(edge8[..., None], 3, axis=2))
# reconstruct: 5 frames (320 x 240) walking down a box room (4 x 6 x 2.5 m) whose walls carry
# blotchy random textures, ray-cast exactly (a ray's hit: the first wall it leaves the box by)
from imageform.geometry import look_at
(work / "room").mkdir()
Kr = np.array([[240.0, 0.0, 159.5], [0.0, 240.0, 119.5], [0.0, 0.0, 1.0]])
tex = 0.6 * rng.uniform(0, 1, (6, 40, 40, 3)).repeat(8, 1).repeat(8, 2)
tex = ((tex + 0.4 * rng.uniform(0, 1, (6, 160, 160, 3)).repeat(2, 1).repeat(2, 2)) * 255)
tex = tex.astype(np.uint8)  # (6, 320, 320, 3), a texel 1/64 m, tiled
vv, uu = np.mgrid[0:240, 0:320].astype(np.float64)
rays = np.linalg.solve(Kr, np.stack([uu.ravel(), vv.ravel(), np.ones(uu.size)]))
lo, hi = np.zeros(3), np.array([4.0, 6.0, 2.5])
for i in range(5):
    s = i / 4
    eye = np.array([2.0 + 0.3 * np.sin(2 * np.pi * s), 1.0 + 1.5 * s, 1.4])
    ahead = eye + np.array([0.6 * np.sin(1.5 * np.pi * s), 2.0, -0.2])
    d = (np.asarray(look_at(eye, ahead, up=(0.0, 0.0, 1.0)).R).T @ rays).T
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d > 0, (hi - eye) / d, (lo - eye) / d)
    t[~np.isfinite(t)] = np.inf
    axis = np.argmin(t, axis=1)
    rows = np.arange(len(t))
    p = eye + d * t[rows, axis][:, None]
    face = 2 * axis + (d[rows, axis] > 0)
    ta = (np.where(axis == 0, p[:, 1], p[:, 0]) * 64).astype(int) % 320
    tb = (np.where(axis == 2, p[:, 1], p[:, 2]) * 64).astype(int) % 320
    write_image(work / "room" / f"view{i}.png", tex[face, tb, ta].reshape(240, 320, 3))
write_camera(work / "room.toml", Camera(Kr, image_size=(320, 240)))
"""


def _jobs(work: Path) -> list[list[str]]:
    w = str(work)
    board = ["--camera", f"{w}/cam.toml", "--board"]
    jobs = [
        ["simulate", "-o", f"{w}/sim"],
        # GoPro's VC-5 decoder (_kernels.vc5, 10-35 s compiled alone): early, one of the longest
        ["develop", f"{w}/warm.gpr", "-o", f"{w}/gpr.png"],
        ["pose", f"{w}/cam.toml", f"{w}/pairs.csv", "--ransac"],
        ["convert", f"{w}/rgb8.png", "--from", "srgb", "--to", "lab", "-o", f"{w}/lab.tif"],
        ["calibrate", f"{w}/board*.png", "--board", "9x6", "--square", "30mm", "-o", f"{w}/c.toml"],
        ["undistort", f"{w}/board_rgb.png", "--camera", f"{w}/cam.toml", "-o", f"{w}/u.png"],
        ["segment", f"{w}/rgb8.png", "-o", f"{w}/mask.png"],
        ["delta-e", f"{w}/rgb8.png", f"{w}/rgb8.png", "--json"],
        [
            "depth",
            f"{w}/pair_l.png",
            f"{w}/pair_r.png",
            "--camera",
            f"{w}/rig.toml",
            "--num-disparities",
            "16",
            "--speckle-size",
            "10",
            "-o",
            f"{w}/z.tif",
        ],
        [
            "track",
            f"{w}/charuco",
            *board,
            "charuco:7x5",
            "--square",
            "30mm",
            "--marker",
            "22mm",
            "--dictionary",
            "5x5_100",
            "-o",
            f"{w}/charuco.csv",
        ],
        [
            "track",
            f"{w}/marker",
            *board,
            "aruco:7",
            "--marker",
            "40mm",
            "--dictionary",
            "4x4_50",
            "-o",
            f"{w}/marker.csv",
        ],
        # the full line-segment detector (vanishing and horizon; simulate's analysis uses it too)
        ["vanishing", f"{w}/board_rgb.png", "-o", f"{w}/vp.png"],
        ["develop", f"{w}/raw.dng", "-o", f"{w}/dev.png"],
        # the chart and slanted-edge kernels as characterize calls them (late: calibrate's
        # board kernels are compiled by then)
        ["characterize", f"{w}/lab", "-o", f"{w}/twin"],
    ]
    if importlib.util.find_spec("cv2") is not None:  # the reconstruct extra (SIFT)
        # the 5-point RANSAC, relative pose, PnP and bundle adjustment (10-30 s of CPU, most
        # of it one kernel): started second, beside simulate, the longest two first
        jobs.insert(1, ["reconstruct", f"{w}/room", "--camera", f"{w}/room.toml", "-o", f"{w}/rec"])
    # 8-bit mosaics only: 16-bit ones run the same float32 kernels
    for method in ("menon", "bilinear", "malvar", "hamilton-adams"):
        out = f"{w}/rgb-{method}.png"
        jobs.append(["demosaic", f"{w}/mosaic8.png", "--method", method, "-o", out])
    return jobs


def warm_cache(jobs: int | None = None) -> list[tuple[str, float, str]]:
    """Compile the hot kernels into the cache; return ``(command, seconds, error)`` per command.

    ``error`` is the last line the command wrote on stderr when it failed, else ``""``.

    Each command runs as ``python -m imageform ...`` in its own process, at most ``jobs`` at
    once (default: the CPU count); the processes share the cache folder of this one.
    """
    n = max(1, jobs or os.cpu_count() or 1)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    if n > 1:  # the jobs use the cores already: no second process per command (_kernels.ahead)
        env["IMAGEFORM_COMPILE_AHEAD"] = "0"
    done: list[tuple[str, float, str]] = []
    with tempfile.TemporaryDirectory(prefix="imageform-warm-") as tmp:
        work = Path(tmp)
        subprocess.run(
            [sys.executable, "-c", _INPUTS, str(work)],
            env={**env, "IMAGEFORM_DISABLE_NUMBA": "1"},
            check=True,
            stdout=subprocess.DEVNULL,
        )
        pending = _jobs(work)
        running: list[tuple[list[str], float, subprocess.Popen[bytes], Path]] = []
        while pending or running:
            while pending and len(running) < n:
                argv = pending.pop(0)
                err = work / f"job{len(pending)}.err"
                with err.open("wb") as stderr:
                    proc = subprocess.Popen(
                        [sys.executable, "-m", "imageform", *argv],
                        env=env,
                        stdout=subprocess.DEVNULL,
                        stderr=stderr,
                    )
                running.append((argv, time.perf_counter(), proc, err))
            time.sleep(0.05)
            for item in list(running):
                argv, t0, proc, err = item
                if proc.poll() is not None:
                    running.remove(item)
                    name = " ".join(a for a in argv if not a.startswith(str(work)) and a != "-o")
                    lines = err.read_text(errors="replace").strip().splitlines()
                    why = "" if proc.returncode == 0 else (lines or [f"exit {proc.returncode}"])[-1]
                    done.append((name, time.perf_counter() - t0, why))
    return done


def _files() -> list[Path]:
    """List the compiled kernels in this process's cache folder (``cache_location``)."""
    from imageform._kernels.jit import cache_location

    where, _ = cache_location()
    if not where.is_dir():
        return []
    return [p for p in where.iterdir() if p.suffix in (".nbi", ".nbc")]


def _stale() -> list[Path]:
    """List imageform's other cache folders here: other versions, or edited kernels."""
    from imageform._kernels.jit import cache_location, cache_root

    where, _ = cache_location()
    root = cache_root()[0]
    if not root.is_dir():
        return []
    return [p for p in root.glob("imageform-*") if p.is_dir() and p != where]


@click.command(
    "cache",
    short_help="Where numba's compiled kernels are cached; --warm compiles them, --clear "
    "removes them.",
)
@click.option("--warm", is_flag=True, help="Compile the hot kernels now (once per machine).")
@click.option("--clear", is_flag=True, help="Remove imageform's compiled kernels.")
@click.option("--jobs", type=click.IntRange(1), default=None, help="Processes for --warm.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def cache_command(warm: bool, clear: bool, jobs: int | None, as_json: bool) -> None:
    """Show where numba caches imageform's compiled kernels; warm or clear that cache.

    One cache per machine, whatever the clone or install: NUMBA_CACHE_DIR when set, else the
    user's cache folder (~/.cache/imageform/numba on Linux), in a folder named after
    imageform's version and a hash of the kernels' code. --clear also removes the folders of
    other versions and of edited kernels.
    """
    import shutil

    from imageform._kernels.jit import cache_location

    where, reason = cache_location()
    removed = 0
    if clear:
        for f in _files():
            f.unlink(missing_ok=True)
            removed += 1
        for folder in _stale():
            removed += sum(1 for p in folder.iterdir() if p.suffix in (".nbi", ".nbc"))
            shutil.rmtree(folder, ignore_errors=True)
    warmed = warm_cache(jobs) if warm else []
    files = _files()
    size = sum(f.stat().st_size for f in files)
    failed = [f"imageform {name}: {why}" for name, _, why in warmed if why]
    if as_json:
        out = {"cache_dir": str(where), "reason": reason, "files": len(files), "bytes": size}
        out |= {"removed": removed} if clear else {}
        out |= {
            "warmed": [{"command": n, "seconds": round(t, 2), "error": e} for n, t, e in warmed]
        }
        click.echo(json.dumps(out))
    else:
        why = {
            "NUMBA_CACHE_DIR": "NUMBA_CACHE_DIR is set",
            "in-tree": "the user's cache folder cannot be written: numba's, beside the source",
            "user": "the user's cache folder, one per machine",
        }[reason]
        click.echo(f"cache: {where} ({why})")
        if clear:
            click.echo(f"removed {removed} file{'' if removed == 1 else 's'}")
        for name, secs, why in warmed:
            click.echo(f"warmed: imageform {name}: {secs:.1f} s" + (" FAILED" if why else ""))
        click.echo(f"{len(files)} files, {size / 1e6:.1f} MB")
    if failed:
        raise click.ClickException(f"cache --warm: {len(failed)} command(s) failed: {failed[0]}")
