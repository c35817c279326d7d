"""First run against warm run: what numba's compilation costs a user, for every command.

Run from the repository root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_first_run.py [--src DIR | --python EXE]
        [--repeat 3] [--commands all|simulate,pose,...] [--warm-cache] [--profile]
        [--write PATH]

Each command of README's list runs as a fresh process (``python -m imageform ...``), as a
user runs it, on small inputs made once before timing (the built-in scene's outputs, a lab
set from ``imageform simulate --lab``, a DNG from ``--raw``, Kodak ``kodim01``, OpenCV's
``left*.jpg`` checkerboards, synthetic correspondences and stereo views, 8 frames of
``bench_reconstruct.py``'s room walk at 320 x 240 for ``reconstruct``); their numba cache
is a folder of their own, so that they fill nothing the timed runs use.

*first*: ``NUMBA_CACHE_DIR`` points at a new empty folder (a new machine: nothing compiled);
*warm*: the same command again with the same folder, now filled by the first run. Each
repetition takes a new folder per command. ``--warm-cache``: also time ``imageform cache
--warm`` into a new empty folder, then the same command again from a copy of the package at
another path (a second clone or a reinstall of the same version on the same machine: it
should find everything compiled); ``--after-warm CMDS`` then also times those commands on a copy
of the cache that ``imageform cache --warm`` alone filled (what a user who ran it after
installing waits; with ``--profile``, the CPU seconds each still compiles there, all in its own
process; ``--no-first`` leaves out the first/warm runs). ``--against DIR``: the same commands
from another source tree (the code before a change), interleaved with this one's (the order
alternating between repetitions), each on its own empty cache: a second table gives both, and
their difference first - warm.
``--profile``: each first run also records the CPU seconds
numba spends compiling each kernel (numba's ``numba:compile`` events; nested compilations
are counted inside their caller) and prints the largest per command. The table gives
medians, the range, and the load average at the start and at the end (the machine is shared;
the ranges say how much that costs).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
KODAK = DATA / "kodak" / "kodim01.png"
KODAK2 = DATA / "kodak" / "kodim02.png"
LAKE = DATA / "kodak" / "kodim16.png"  # a lake and its horizon
BOARDS = DATA / "opencv-left"

_INPUTS = r"""
import sys
from pathlib import Path
import numpy as np
from imageform.geometry import BrownConrady, Camera
from imageform.geometry.calibration_refine import rodrigues
from imageform.io import write_camera, write_image

work = Path(sys.argv[1])
K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
dist = BrownConrady(-0.2, 0.05, 1e-3, -5e-4, 0.0)
write_camera(work / "cam.toml", Camera(K, np.eye(3), np.zeros(3), (640, 480), distortion=dist),
             has_pose=True)
rng = np.random.default_rng(0)
X = rng.uniform(-1, 1, (200, 3)) + [0, 0, 6]
R = rodrigues(np.array([[0.05, -0.15, 0.02]]))[0]
t = np.array([-0.5, 0.1, 0.2])
cam2 = Camera(K, R, t, (640, 480), distortion=dist)
write_camera(work / "cam2.toml", cam2, has_pose=True)
uv1 = np.asarray(Camera(K, np.eye(3), np.zeros(3), distortion=dist).project(X).uv)
uv = np.asarray(cam2.project(X).uv)
rows = [",".join(repr(float(v)) for v in (*a, *b)) for a, b in zip(uv1, uv, strict=True)]
(work / "obs.csv").write_text("\n".join(rows) + "\n")
(work / "points.csv").write_text(
    "X,Y,Z\n" + "\n".join(",".join(repr(float(v)) for v in p) for p in X) + "\n")
uv[::10] += rng.uniform(-40, 40, uv[::10].shape)
rows = [",".join(repr(float(v)) for v in (*a, *b)) for a, b in zip(X, uv, strict=True)]
(work / "pairs.csv").write_text("X,Y,Z,u,v\n" + "\n".join(rows) + "\n")
# a stereo pair (60 mm baseline) seeing a 9 x 6 checkerboard (30 mm squares) in four poses
vv, uu = np.mgrid[0:480, 0:640].astype(np.float64)
for side, shift in (("left", 0.0), ("right", -60.0)):
    (work / side).mkdir()
    for k, (ax, ay) in enumerate(((0.3, 0.0), (0.0, 0.35), (-0.25, 0.2), (0.15, -0.3))):
        Rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
        Ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
        Rb = Rx @ Ry
        H = K @ np.column_stack([Rb[:, 0], Rb[:, 1], [-150.0 + shift, -105.0, 900.0]])
        q = np.linalg.solve(H, np.stack([uu.ravel(), vv.ravel(), np.ones(uu.size)]))
        x, y = (q[0] / q[2] + 30.0) / 30.0, (q[1] / q[2] + 30.0) / 30.0
        inside = (x >= 0) & (x < 12) & (y >= 0) & (y < 9)
        dark = (np.floor(x) + np.floor(y)) % 2 == 0
        board = np.where(inside & ~((x >= 1) & (x < 11) & (y >= 1) & (y < 8) & dark), 230, 25)
        board = np.where(inside, board, 128).reshape(480, 640).astype(np.uint8)
        write_image(work / side / f"view{k}.png", board[..., None])
(work / "many").mkdir()
img = (rng.uniform(0, 1, (48, 64, 3)) * 255).astype(np.uint8)
for k in range(3):
    write_image(work / "many" / f"im{k}.png", img)
write_image(work / "tiles.tif", np.repeat(img, 4, axis=0).astype(np.float32) / 255.0)
# a rectified stereo pair (a textured plane 10 px of disparity away) and its rig, for depth
from imageform.io import CameraFile, StereoCameraFile, write_stereo_camera
Kd = np.array([[200.0, 0.0, 79.5], [0.0, 200.0, 59.5], [0.0, 0.0, 1.0]])
write_stereo_camera(work / "rig.toml", StereoCameraFile(
    CameraFile(Camera(Kd, image_size=(160, 120))),
    CameraFile(Camera(Kd, np.eye(3), [-50.0, 0.0, 0.0], (160, 120)), has_pose=True)))
tex = (np.random.default_rng(7).uniform(0, 1, (120, 160)) * 255).astype(np.uint8)
write_image(work / "pair_r.png", tex[..., None])
write_image(work / "pair_l.png", np.roll(tex, 10, axis=1)[..., None])
"""

# imageform reconstruct's input: 8 frames (320 x 240) of the room walk of bench_reconstruct.py
# (tests/sfm_scenes.py, as tests/workflows/test_reconstruct.py) and their camera file
_ROOM = r"""
import sys
from pathlib import Path
import numpy as np
sys.path.insert(0, sys.argv[2])
from tests import sfm_scenes
from imageform.geometry import Camera
from imageform.io import write_camera, write_image

room = Path(sys.argv[1]) / "room"
(room / "frames").mkdir(parents=True)
K = np.array([[240.0, 0.0, 159.5], [0.0, 240.0, 119.5], [0.0, 0.0, 1.0]])
rng = np.random.default_rng(5)
for i, pose in enumerate(sfm_scenes.poses(16)[:8]):
    frame = sfm_scenes.render(K, pose, (320, 240), rng=rng)
    write_image(room / "frames" / f"view{i}.png", frame)
write_camera(room / "camera.toml", Camera(K, image_size=(320, 240)))
"""

# imageform track's inputs: 8 frames (640 x 360) of a ChArUco board on a photograph
# (tests/video_scenes.py, as tests/workflows/test_track.py), 6 frames of one ArUco marker,
# and their camera file
_TRACK = r"""
import sys
from pathlib import Path
import numpy as np
sys.path.insert(0, sys.argv[2])
from tests import video_scenes
from imageform.geometry import Camera
from imageform.io import write_camera, write_image

w = Path(sys.argv[1])
K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
write_camera(w / "track-camera.toml", Camera(K, image_size=(640, 360)))
video_scenes.write_video(w / "charuco", K, 8, (640, 360))
(w / "marker").mkdir()
rng = np.random.default_rng(3)
for i, pose in enumerate(video_scenes.marker_poses(6)):
    frame = video_scenes.marker_frame(K, pose, (640, 360), rng=rng)
    write_image(w / "marker" / f"frame{i:04d}.png", frame[..., None])
"""


def _env(src: Path | None, cache: Path | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    if src is not None:
        env["PYTHONPATH"] = str(src)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
        env["XDG_CACHE_HOME"] = str(cache.parent / (cache.name + "-xdg"))
    return env


# numba's compile events, recorded in a child process (the one listener of this script,
# compile_plan.py and compile_literals.py): ``records`` gets one dict per compilation, in the
# order they end (callees before callers): the kernel ("module.qualname", the module's last
# part), its module and qualname, the dispatcher's id, whether it is imageform's, the argument
# types (numba's text, and as a signature in numba's syntax where one can be written), CPU
# seconds with its nested compilations (incl) and without (own), the indices of those it
# nested (kids), its nesting depth and its index n.
LISTENER = r"""
import time
from numba.core import event as ev, types


def _compact(t):
    if isinstance(t, types.Array) and t.mutable and t.aligned and t.ndim > 0:
        dims = [":"] * t.ndim
        if t.layout == "C":
            dims[-1] = "::1"
        elif t.layout == "F":
            dims[0] = "::1"
        dtype = "boolean" if str(t.dtype) == "bool" else str(t.dtype)
        return f"{dtype}[{', '.join(dims)}]"
    if isinstance(t, types.UniTuple):
        return f"UniTuple({_compact(t.dtype)}, {t.count})"
    if isinstance(t, types.Tuple):
        return "Tuple((" + ", ".join(_compact(x) for x in t.types) + ",))"
    if isinstance(t, types.Boolean):
        return "boolean"
    if isinstance(t, (types.Integer, types.Float, types.Complex)):
        return str(t)
    return None


records, _stack = [], []


class _Timer(ev.Listener):
    def on_start(self, event):
        _stack.append([time.process_time(), 0.0, []])

    def on_end(self, event):
        t0, inner, kids = _stack.pop()
        dt = time.process_time() - t0
        disp = event.data["dispatcher"]
        fn = disp.py_func
        module = fn.__module__ or ""
        parts = [_compact(a) for a in event.data["args"]]
        rec = {"kernel": module.rsplit(".", 1)[-1] + "." + fn.__qualname__, "module": module,
               "qualname": fn.__qualname__, "id": id(disp),
               "ours": module.startswith("imageform."), "args": str(event.data["args"]),
               "signature": None if None in parts else "(" + ", ".join(parts) + ")",
               "incl": dt, "own": dt - inner, "kids": kids, "depth": len(_stack),
               "n": len(records)}
        records.append(rec)
        if _stack:
            _stack[-1][1] += dt
            _stack[-1][2].append(rec["n"])


ev.register("numba:compile", _Timer())
"""

# the profiler: the listener, then the command as `python -m imageform`; the records are
# written to IF_PROFILE_OUT at exit
_PROFILE = (
    LISTENER
    + r"""
import atexit, json, os, runpy, sys
atexit.register(lambda: open(os.environ["IF_PROFILE_OUT"], "w").write(json.dumps(records)))
sys.argv = ["imageform", *sys.argv[1:]]
runpy.run_module("imageform", run_name="__main__", alter_sys=True)
"""
)


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(
    python: str, args: list[str], env: dict[str, str], cwd: Path, profile: Path | None = None
) -> tuple[float, float]:
    """Run one command; its wall-clock and CPU seconds (user + system, all its threads)."""
    if profile is not None:
        argv = [python, "-c", _PROFILE, *args]
        env = {**env, "IF_PROFILE_OUT": str(profile)}
    else:
        argv = [python, "-m", "imageform", *args]
    c0, t0 = _cpu(), time.perf_counter()
    done = subprocess.run(argv, env=env, cwd=cwd, capture_output=True, text=True)
    dt, dc = time.perf_counter() - t0, _cpu() - c0
    if done.returncode not in (0, 3):  # 3: palette-check's "a check failed"
        raise SystemExit(f"imageform {' '.join(args)} failed:\n{done.stderr[-2000:]}")
    return dt, dc


def _commands(w: Path) -> dict[str, list[str]]:
    """README's command list, each on small inputs (``w``: the folder of inputs)."""
    lab = w / "lab"
    stage = w / "sim0" / "stages" / "07-output.png"
    o = str(w / "out")
    return {
        "simulate": ["simulate", "-o", f"{o}/sim", "--force"],
        "characterize": ["characterize", str(lab), "-o", f"{o}/twin", "--force"],
        "lecture": ["lecture"],
        "project": [
            "project",
            str(w / "points.csv"),
            "--camera",
            str(w / "cam.toml"),
            "-o",
            f"{o}/uv.csv",
            "--force",
        ],
        "pose": ["pose", str(w / "cam.toml"), str(w / "pairs.csv"), "--ransac"],
        "triangulate": [
            "triangulate",
            str(w / "obs.csv"),
            str(w / "cam.toml"),
            str(w / "cam2.toml"),
            "-o",
            f"{o}/X.csv",
            "--force",
        ],
        "calibrate": [
            "calibrate",
            *sorted(str(p) for p in BOARDS.glob("left0[1-6].jpg")),
            "--board",
            "9x6",
            "--square",
            "25mm",
            "-o",
            f"{o}/c.toml",
            "--force",
        ],
        "undistort": [
            "undistort",
            str(BOARDS / "left01.jpg"),
            "--camera",
            str(w / "cam.toml"),
            "-o",
            f"{o}/u.png",
            "--force",
        ],
        "stereo-calibrate": [
            "stereo-calibrate",
            str(w / "left" / "*.png"),
            str(w / "right" / "*.png"),
            "--board",
            "9x6",
            "--square",
            "30mm",
            "-o",
            f"{o}/st.toml",
            "--force",
        ],
        "depth": [
            "depth",
            str(w / "pair_l.png"),
            str(w / "pair_r.png"),
            "--camera",
            str(w / "rig.toml"),
            "--num-disparities",
            "16",
            "--speckle-size",
            "10",
            "-o",
            f"{o}/z.tif",
            "--force",
        ],
        "track-charuco": [
            "track",
            str(w / "charuco"),
            "--camera",
            str(w / "track-camera.toml"),
            "--board",
            "charuco:7x5",
            "--square",
            "30mm",
            "--marker",
            "22mm",
            "--dictionary",
            "5x5_100",
            "-o",
            f"{o}/track.csv",
            "--force",
        ],
        "track-aruco": [
            "track",
            str(w / "marker"),
            "--camera",
            str(w / "track-camera.toml"),
            "--board",
            "aruco:7",
            "--marker",
            "40mm",
            "--dictionary",
            "4x4_50",
            "-o",
            f"{o}/marker.csv",
            "--force",
        ],
        "vanishing": ["vanishing", str(stage), "--json"],
        "horizon": ["horizon", str(LAKE), "--json"],
        "lens": ["lens", "--focal", "50mm", "--f-number", "2.8", "--focus", "2m"],
        "sfr": ["sfr", str(lab / "edge" / "edge.dng")],  # the lab set writes its edge as a DNG
        "info": ["info", str(w / "raw.dng"), "--json"],
        "convert": [
            "convert",
            str(KODAK),
            "--from",
            "srgb",
            "--to",
            "lab",
            "-o",
            f"{o}/lab.tif",
            "--force",
        ],
        "white-balance": ["white-balance", str(KODAK), "-o", f"{o}/wb.png", "--force"],
        "delta-e": ["delta-e", str(KODAK), str(KODAK2), "--json"],
        "cvd": ["cvd", str(KODAK), "--type", "deutan", "-o", f"{o}/cvd.png", "--force"],
        "gamut": ["gamut", "--spaces", "srgb,display-p3,rec2020", "--json"],
        "palette-check": ["palette-check", "#E69F00,#56B4E9,#009E73"],
        "develop": ["develop", str(w / "raw.dng"), "-o", f"{o}/dev.png", "--force"],
        "develop-rolloff": [
            "develop",
            str(w / "raw.dng"),
            "--auto-bright",
            "--highlight-rolloff",
            "-o",
            f"{o}/dev-roll.png",
            "--force",
        ],
        "mosaic": ["mosaic", str(KODAK), "-o", f"{o}/mos.png", "--force"],
        "demosaic": ["demosaic", str(w / "mosaic.png"), "-o", f"{o}/rgb.png", "--force"],
        "emva": ["emva", str(lab), "-o", f"{o}/emva.json", "--force"],
        "segment": ["segment", str(KODAK), "-o", f"{o}/mask.png", "--force"],
        "stain-normalize": [
            "stain-normalize",
            str(KODAK),
            "--target",
            str(KODAK2),
            "-o",
            f"{o}/stain.png",
            "--force",
        ],
        "fit-correction": [
            "fit-correction",
            str(lab / "colorchecker" / "developed.png"),
            "-o",
            f"{o}/corr.json",
            "--force",
        ],
        "flatfield": ["flatfield", str(w / "many"), "-o", f"{o}/flat", "--force"],
        "harmonize": [
            "harmonize",
            str(KODAK),
            "--correction",
            str(w / "corr.json"),
            "-o",
            f"{o}/harm.png",
            "--force",
        ],
        "chart": [
            "chart",
            str(lab / "colorchecker" / "developed.png"),
            "-o",
            f"{o}/chart.json",
            "--force",
        ],
        "batch": [
            "batch",
            "convert",
            str(w / "many" / "*.png"),
            "-o",
            f"{o}/batch",
            "--to",
            "lab",
            "--suffix",
            ".tif",
            "--workers",
            "1",
            "--force",
        ],
        "chunked": [
            "chunked",
            "convert",
            str(w / "tiles.tif"),
            "-o",
            f"{o}/ch.tif",
            "--from",
            "srgb",
            "--to",
            "lab",
            "--force",
        ],
        "cache": ["cache"],
        "reconstruct": [
            "reconstruct",
            str(w / "room" / "frames"),
            "--camera",
            str(w / "room" / "camera.toml"),
            "-o",
            f"{o}/room",
            "--max-features",
            "1000",
            "--force",
        ],
    }


def _inputs(python: str, src: Path | None, w: Path) -> None:
    """Make every input once, with a numba cache of their own (not the timed runs')."""
    env = _env(src, w / "inputs-cache")
    (w / "out").mkdir()

    def im(*args: str) -> None:
        done = subprocess.run(
            [python, "-m", "imageform", *args], env=env, cwd=w, capture_output=True, text=True
        )
        if done.returncode != 0:
            raise SystemExit(f"input: imageform {' '.join(args)} failed:\n{done.stderr[-2000:]}")

    subprocess.run([python, "-c", _INPUTS, str(w)], env=env, check=True)
    subprocess.run([python, "-c", _ROOM, str(w), str(ROOT)], env=env, check=True)
    subprocess.run([python, "-c", _TRACK, str(w), str(ROOT)], env=env, check=True)
    im("mosaic", str(KODAK), "-o", str(w / "mosaic.png"))
    im("simulate", "-o", str(w / "sim0"))
    im(
        "simulate",
        "-o",
        str(w / "sim1"),
        "--camera",
        str(w / "sim0" / "camera.toml"),
        "--lab",
        str(w / "lab"),
        "--raw",
        str(w / "raw.dng"),
    )
    im(
        "fit-correction",
        str(w / "lab" / "colorchecker" / "developed.png"),
        "-o",
        str(w / "corr.json"),
    )


def _compiled(recs: list[dict[str, object]]) -> tuple[float, int, str]:
    """CPU seconds compiling (top-level compilations), their count, the four largest."""
    top = [r for r in recs if r["depth"] == 0]
    total = sum(float(str(r["incl"])) for r in top)
    big = sorted(top, key=lambda r: -float(str(r["incl"])))[:4]
    what = ", ".join(f"{r['kernel']} {float(str(r['incl'])):.1f}" for r in big)
    return total, len(recs), what


def _compiling(recs: list[dict[str, object]]) -> str:
    total, n, what = _compiled(recs)
    return f"{total:.1f} s in {n} compilations; {what}"


def _load() -> str:
    if not hasattr(os, "getloadavg"):
        return "n/a"
    return " / ".join(f"{v:.1f}" for v in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--src", type=Path, default=ROOT / "src")
    ap.add_argument("--python", default=None, help="an interpreter with imageform installed")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", default="all", help="comma-separated, or all")
    ap.add_argument("--warm-cache", action="store_true", help="time imageform cache --warm")
    ap.add_argument("--jobs", type=int, default=2, help="processes for imageform cache --warm")
    ap.add_argument("--profile", action="store_true", help="seconds compiling, per kernel")
    ap.add_argument("--inputs", type=Path, default=None, help="reuse (or make) inputs here")
    ap.add_argument("--write", type=Path, default=None, help="append the table to this file")
    ap.add_argument(
        "--against", type=Path, default=None, help="another src tree (before): interleaved A/B"
    )
    ap.add_argument(
        "--no-first",
        action="store_true",
        help="skip the first/warm runs (with --warm-cache --after-warm: only those)",
    )
    ap.add_argument(
        "--after-warm",
        default="",
        help="commands (comma-separated, or all) also timed on a copy of the cache that "
        "'imageform cache --warm' filled (with --warm-cache)",
    )
    a = ap.parse_args()
    python = a.python or sys.executable
    src = None if a.python else a.src.resolve()
    against = a.against.resolve() if a.against and src is not None else None
    load0 = _load()
    with tempfile.TemporaryDirectory(prefix="if-first-run-") as tmp:
        work = Path(tmp)
        w = a.inputs.resolve() if a.inputs else work / "inputs"
        if not (w / "corr.json").exists():
            w.mkdir(parents=True, exist_ok=True)
            t0 = time.perf_counter()
            _inputs(python, src, w)
            print(f"inputs made in {time.perf_counter() - t0:.1f} s", flush=True)
        commands = _commands(w)
        names = list(commands) if a.commands == "all" else a.commands.split(",")
        # (wall, CPU) seconds per run
        first: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        warm: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        compiled: dict[str, list[dict[str, object]]] = {}
        compiled_aw: dict[str, list[dict[str, object]]] = {}  # after cache --warm (--profile)
        warming: list[tuple[float, float]] = []
        after_warm: dict[str, list[tuple[float, float]]] = {}
        clone: list[tuple[float, float]] = []
        # --against: the same command from the other tree, right after or before (the order
        # alternates between repetitions), on its own empty cache
        before: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        before_warm: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        for i in range(a.repeat):
            for name in [] if a.no_first else names:
                trees = [("", src), ("before", against)] if against else [("", src)]
                for label, tree in trees if i % 2 == 0 else trees[::-1]:
                    cache = work / f"cache-{name}-{i}{label}"
                    cache.mkdir()
                    env = _env(tree, cache)
                    mine = label == ""
                    prof = work / f"prof-{name}.json" if a.profile and i == 0 and mine else None
                    one = _run(python, commands[name], env, work, prof)
                    again = _run(python, commands[name], env, work)
                    (first if mine else before)[name].append(one)
                    (warm if mine else before_warm)[name].append(again)
                    shutil.rmtree(cache, ignore_errors=True)
                    (f, fc), (m, mc) = one, again
                    print(
                        f"{name}{' (before)' if label else ''} #{i}: first {f:.2f} s ({fc:.2f} "
                        f"CPU), warm {m:.2f} s ({mc:.2f} CPU) (load {_load()})",
                        flush=True,
                    )
                    if prof is not None:
                        compiled[name] = json.loads(prof.read_text())
            if a.warm_cache and src is not None:
                cache = work / f"cache-warm-{i}"
                cache.mkdir()
                env = _env(src, cache)
                argv = ["cache", "--warm", "--jobs", str(a.jobs)]
                warming.append(_run(python, argv, env, work))
                # a second clone of the same version, elsewhere: the same cache serves it
                other = work / f"clone-{i}" / "src"
                shutil.copytree(src, other, ignore=shutil.ignore_patterns("__pycache__"))
                clone.append(_run(python, ["cache", "--warm"], _env(other, cache), work))
                for name in names if a.after_warm == "all" else a.after_warm.split(","):
                    if name not in first:
                        continue
                    copy = work / f"cache-aw-{name}-{i}"
                    shutil.copytree(cache, copy)
                    xdg = cache.parent / (cache.name + "-xdg")
                    if xdg.exists():
                        shutil.copytree(xdg, copy.parent / (copy.name + "-xdg"))
                    # --profile: what the command still compiles, all of it in its own process
                    # (no second process: IMAGEFORM_COMPILE_AHEAD=0)
                    prof = work / f"prof-aw-{name}.json" if a.profile and i == 0 else None
                    env = _env(src, copy)
                    if prof is not None:
                        env["IMAGEFORM_COMPILE_AHEAD"] = "0"
                    after_warm.setdefault(name, []).append(
                        _run(python, commands[name], env, work, prof)
                    )
                    if prof is not None:
                        compiled_aw[name] = json.loads(prof.read_text())
                    shutil.rmtree(copy, ignore_errors=True)
                    print(
                        f"{name} #{i} after cache --warm: {after_warm[name][-1][0]:.2f} s "
                        f"({after_warm[name][-1][1]:.2f} CPU)"
                        + (f", {_compiling(compiled_aw[name])}" if prof is not None else ""),
                        flush=True,
                    )
                shutil.rmtree(cache, ignore_errors=True)
                print(
                    f"#{i}: cache --warm {warming[-1][0]:.2f} s ({warming[-1][1]:.2f} CPU), "
                    f"again from a second clone {clone[-1][0]:.2f} s (load {_load()})",
                    flush=True,
                )

    def med(runs: list[tuple[float, float]], k: int) -> float:
        return statistics.median(r[k] for r in runs)

    def span(runs: list[tuple[float, float]]) -> str:
        return f"{min(r[0] for r in runs):.2f}-{max(r[0] for r in runs):.2f}"

    rows = []
    for name in [] if a.no_first else names:
        f, m = med(first[name], 0), med(warm[name], 0)
        rows.append(
            f"| `{name}` | {f:.2f} | {m:.2f} | {f / m:.2f} | {span(first[name])} "
            f"| {span(warm[name])} | {med(first[name], 1):.2f} | {med(warm[name], 1):.2f} |"
        )
    lines = [
        f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average at the start {load0}, at the end {_load()}; imageform from "
        f"{a.python or src}; median of {a.repeat}; first = empty `NUMBA_CACHE_DIR`; "
        "CPU = user + system seconds of the process and its threads",
    ]
    if rows:
        lines += [
            "",
            "| command | first (s) | warm (s) | first / warm | first range | warm range "
            "| first CPU (s) | warm CPU (s) |",
            "|---|---:|---:|---:|---:|---:|---:|---:|",
            *rows,
        ]
    if against is not None:
        lines += [
            "",
            f"Interleaved with the tree before ({against}), each on its own empty cache:",
            "",
            "| command | first before (s) | first after (s) | after / before "
            "| first CPU before | first CPU after | warm before (s) | warm after (s) "
            "| first - warm before (s) | first - warm after (s) |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for name in names:
            fb, fa = med(before[name], 0), med(first[name], 0)
            wb, wa = med(before_warm[name], 0), med(warm[name], 0)
            lines.append(
                f"| `{name}` | {fb:.2f} | {fa:.2f} | {fa / fb:.2f} | {med(before[name], 1):.2f} "
                f"| {med(first[name], 1):.2f} | {wb:.2f} | {wa:.2f} | {fb - wb:.2f} "
                f"| {fa - wa:.2f} |"
            )
    if after_warm and a.no_first:
        lines += [
            "",
            "A first run on a cache that only `imageform cache --warm` filled (median; CPU "
            "seconds compiling and compilations: numba's compile events, all in the command: "
            "IMAGEFORM_COMPILE_AHEAD=0):",
            "",
            "| command | after cache --warm (s) | CPU (s) | compiling (CPU s) | compilations "
            "| largest |",
            "|---|---:|---:|---:|---:|---|",
        ]
        for name, runs in after_warm.items():
            recs = compiled_aw.get(name)
            total, n, what = _compiled(recs) if recs is not None else (0.0, 0, "n/a")
            lines.append(
                f"| `{name}` | {med(runs, 0):.2f} | {med(runs, 1):.2f} | {total:.1f} | {n} "
                f"| {what} |"
            )
    elif after_warm:
        lines += [
            "",
            "A first run on a cache that only `imageform cache --warm` filled (median):",
            "",
            "| command | after cache --warm (s) | first, empty cache (s) | warm (s) |",
            "|---|---:|---:|---:|",
        ]
        for name, runs in after_warm.items():
            lines.append(
                f"| `{name}` | {med(runs, 0):.2f} | {med(first[name], 0):.2f} "
                f"| {med(warm[name], 0):.2f} |"
            )
    if warming:
        lines += [
            "",
            f"`imageform cache --warm --jobs {a.jobs}` into an empty cache: "
            f"{med(warming, 0):.1f} s (median; {span(warming)}; {med(warming, 1):.1f} s CPU);"
            f" the same again from a second copy of the package at another path, same cache: "
            f"{med(clone, 0):.1f} s",
        ]
    if compiled:
        lines += ["", "CPU seconds compiling (first run), the largest kernels per command:", ""]
        for name, recs in compiled.items():
            lines.append(f"- `{name}`: {_compiling(recs)}")
    text = "\n".join(lines)
    print(text)
    if a.write:
        a.write.parent.mkdir(parents=True, exist_ok=True)
        with a.write.open("a") as fh:
            fh.write(text + "\n")


if __name__ == "__main__":
    main()
