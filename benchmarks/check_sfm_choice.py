"""The fisheye chosen by a robust cost on common tracks: ``imageform reconstruct`` before and after.

Without ``--camera``, where COLMAP's ``SIMPLE_RADIAL`` ran off or its barrel term reached
half its bound, ``imageform reconstruct`` also reconstructs with the equidistant fisheye
(``check_sfm_fisheye.py``). Before this change it kept the fisheye when its median
reprojection error was at most 5 % above the other's (the 2 px filter leaves both near 0.54
px on C3VD: a tie); after, when its robust cost on the tracks of both models is at most the
other's (each track triangulated with each model's cameras held, every view's squared
error in the image capped at 2 px, views it cannot explain at the cap, GRIC's penalty
ln(2n) per lens parameter: Torr 1998, Torr & Zisserman 2000; ``sfm._track_cost``). Each
sequence is run by the command before (``--before SRC``: main's ``src`` on ``PYTHONPATH``)
and after (this checkout), without ``--camera``; the fisheye sequences also by pycolmap's
fisheye self-calibration (``RADIAL_FISHEYE``, ``selfcal.json``, and ``SIMPLE_RADIAL_FISHEYE``,
``fisheye-pycolmap.json``: the cached runs of ``check_sfm_fisheye.py``, read from the data
folder). Columns as ``check_sfm_fisheye.py``'s, with the points and the two costs the
command's note printed (the fisheye's / the other's, px^2).

C3VD's reference is imageform's reconstruction with the working camera of
``tests/data/endo`` (``--camera``; a pycolmap self-calibration, not a calibration). How far
that reference itself moves is measured too: the same frames and camera with the RANSAC
seed 1, 2, 3 (``reconstruct_sequence(rng=)``, in-process, the command's masks and contrast)
against seed 0, the ``reference spread`` rows.

Sequences: ``check_sfm_k1.py``'s (its docstring names their repositories, commits and
licences) and its data folder (``--data``), as ``check_sfm_fisheye.py``.

Run::

    git archive BASE src | tar -x -C BEFORE
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_choice.py \\
        --data DATA --before BEFORE/src [--only c3vd colon-a colon-b]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402
from benchmarks.check_sfm_fresh import agreement  # noqa: E402
from benchmarks.check_sfm_k1 import prepare_c3vd, read_frames, run_cli  # noqa: E402

FISHEYE = ["c3vd", "colon-a", "colon-b"]
OTHERS = ["temple", "dino", "viking", "gun", "dt990", "sceaux-exif"]

COLUMNS = [
    "sequence",
    "run",
    "model",
    "f found px",
    "f vs reference",
    "k1",
    "registered",
    "points",
    "reprojection px (median)",
    "cost fisheye / other px^2",
    "poses vs reference: rotation / translation deg / centres % of path",
    "s (CPU s)",
]


def _model(r: dict[str, Any]) -> str:
    """The lens the command chose, from its notes."""
    if any("kept (the fisheye)" in n for n in r.get("notes", [])):
        return "equidistant fisheye (KB k1)"
    return "SIMPLE_RADIAL"


def _costs(r: dict[str, Any]) -> str:
    """The two costs of the fisheye tried, from the note (after only)."""
    for n in r.get("notes", []):
        got = re.findall(r"(\d+) px\^2", n)
        if "the fisheye tried" in n and len(got) >= 2:
            return f"{got[0]} / {got[1]}"
    return "-"


def _cached(folder: Path, name: str, w: float) -> dict[str, Any] | None:
    """A cached pycolmap run (``check_sfm_fisheye.py``'s), its camera's f and k."""
    path = folder / name
    if not path.exists():
        return None
    r = json.loads(path.read_text())
    r["R"], r["t"] = np.asarray(r["R"], float), np.asarray(r["t"], float)
    r["f0"] = 0.45 * w
    if "camera" in r:
        r["f"], r["k1"] = r["camera"][0], r["camera"][3]
    return r


def reference_spread(folder: Path, frames: list[np.ndarray]) -> list[list[Any]]:
    """C3VD with its working camera, RANSAC seeds 1-3 against seed 0 (in-process)."""
    from imageform.geometry import field_of_view_mask, reconstruct_sequence
    from imageform.io import read_camera

    cam = read_camera(folder / "given.toml").camera
    mask = field_of_view_mask(frames)
    recs = [
        reconstruct_sequence(
            frames, cam.K, cam.distortion, masks=mask, contrast_threshold=0.01, rng=seed
        )
        for seed in range(4)
    ]
    rows = []
    for seed in (1, 2, 3):
        rot, tra, rms = agreement(recs[seed].R, recs[seed].t, recs[0].R, recs[0].t)
        r = recs[seed]
        rows.append(
            [
                "c3vd",
                f"reference spread: the working camera, seed {seed} against seed 0",
                "the working camera (KB k1-k4)",
                f"{float(cam.K[0, 0]):.1f}",
                "+0.0 %",
                "-",
                f"{int(r.registered.sum())}/{len(frames)}",
                f"{r.points.shape[0]}",
                f"{float(np.median(r.residuals_px)):.2f}",
                "-",
                f"{rot:.2f} / {tra:.2f} / {rms:.2f}",
                "-",
            ]
        )
    return rows


def sequence(name: str, data: Path, before: Path) -> tuple[str, list[list[Any]], list[Any]]:
    endo = name.startswith("colon") or name == "c3vd"
    folder = prepare_c3vd(data) if name == "c3vd" else data / name
    frames = read_frames(folder)
    n = len(frames)
    h, w = frames[0].shape[:2]
    print(f"  {name}: {n} frames {w} x {h}", file=sys.stderr)
    runs: list[tuple[str, str, dict[str, Any]]] = []
    b = run_cli(folder, endo, before)
    runs.append(("imageform CLI before (--before)", _model(b), b))
    a = run_cli(folder, endo, ROOT / "src")
    runs.append(("imageform CLI after (this checkout)", _model(a), a))
    ref_label = "the run before"
    if name in FISHEYE:
        for file, model in (
            ("fisheye-pycolmap.json", "SIMPLE_RADIAL_FISHEYE"),
            ("selfcal.json", "RADIAL_FISHEYE"),
        ):
            r = _cached(folder, file, w)
            if r is not None:
                runs.append(("pycolmap, self-calibrated (cached)", model, r))
        if name == "c3vd":
            g = run_cli(folder, endo, ROOT / "src", folder / "given.toml")
            runs.append(("imageform CLI, --camera", "the working camera (KB k1-k4)", g))
            ref_label = "imageform with the working camera (--camera)"
        else:
            ref_label = "pycolmap's RADIAL_FISHEYE self-calibration"
    ref = runs[-1][2] if name in FISHEYE else runs[0][2]
    f_ref = ref.get("f")
    rows = []
    for label, model, r in runs:
        ok = r.get("reg", 0) > 0 and "R" in r
        if ok and r is not ref:
            rot, tra, rms = agreement(r["R"], r["t"], ref["R"], ref["t"])
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok else "-"
        f = r.get("f") if ok else None
        k1 = r.get("k1") if ok else None
        cpu = f" ({r['cpu']:.1f})" if "cpu" in r else ""
        reproj = r.get("reproj")
        rows.append(
            [
                name,
                label,
                model,
                f"{f:.1f}" if f is not None else "-",
                f"{100 * (f / f_ref - 1):+.1f} %" if f is not None and f_ref else "-",
                f"{k1:+.4f}" if k1 is not None else "-",
                f"{r.get('reg', 0)}/{n}",
                f"{r['points']}" if isinstance(r.get("points"), int) else "-",
                f"{reproj:.2f}" if ok and reproj is not None else "-",
                _costs(r),
                vs,
                f"{r['time']:.1f}{cpu}" if "time" in r else "-",
            ]
        )
    if name == "c3vd":
        rows += reference_spread(folder, frames)
    info = f"{name}: {n} frames, {w} x {h} px; f and poses against {ref_label}"
    notes = [(f"{name}, {label}", ln) for label, _, r in runs[:2] for ln in r.get("notes", [])]
    return info, rows, notes


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--before", type=Path, required=True, help="src folder of the code before")
    ap.add_argument("--only", nargs="+", default=None)
    args = ap.parse_args()
    import pycolmap

    names = [k for k in FISHEYE + OTHERS if not args.only or k in args.only]
    print(header("The fisheye chosen by a robust cost on common tracks"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine); pycolmap {pycolmap.__version__}\n")
    infos, rows, notes = [], [], []
    for name in names:
        info, r, nt = sequence(name, args.data, args.before)
        infos.append(f"- {info}")
        rows += r
        notes += nt
    print("\n".join(infos) + "\n")
    print(markdown_table(COLUMNS, rows))
    print("\nEvery note line about the camera `imageform reconstruct` printed:\n")
    keys = ("no camera file", "ran off", "fisheye")
    said = [(run, ln) for run, ln in notes if any(k in ln for k in keys)]
    print("\n".join(f"- {run}: `{line}`" for run, line in said) or "- none")


if __name__ == "__main__":
    main()
