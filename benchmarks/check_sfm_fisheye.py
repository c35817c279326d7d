"""The equidistant fisheye tried without a camera file: ``imageform reconstruct`` before and after.

``imageform reconstruct`` without ``--camera`` refines f and COLMAP's ``SIMPLE_RADIAL`` k1
(``benchmarks/check_sfm_k1.py``); where that camera ran off (k1 at 90 % of its bound, f
moved a factor 3: the C3VD colonoscope) it fell back to f alone. After this change it
also tries the equidistant fisheye (``KannalaBrandt()``, :math:`r_d = f \\theta`, f and one
Kannala-Brandt term refined, the term kept only where it lowers the squared error by 2 %)
there and where the barrel term reached half its bound, and keeps it when it registers as
many frames at most 5 % above the median reprojection error. Each sequence is run by the
command before (``--before SRC``: the ``src`` of the code before on ``PYTHONPATH``) and
after (this checkout), without ``--camera``, and, on the fisheye sequences, by pycolmap's
fisheye self-calibration from its equidistant guess f = 0.45 w: ``RADIAL_FISHEYE`` (f, k1,
k2; ``selfcal.json``, as ``sfm-autok-2026-11-30e.md``) and ``SIMPLE_RADIAL_FISHEYE`` (f, k;
``fisheye-pycolmap.json``), run once and kept in the sequence's folder. Columns as
``check_sfm_k1.py``'s, with the lens model the command chose.

Sequences (``check_sfm_k1.py``'s docstring names their repositories, commits and licences;
its data folder, ``--data``, is reused): the fisheye ones, ``c3vd`` (the C3VD colonoscope's
13 frames of ``tests/data/endo``, CC BY 4.0; f and the poses against imageform with that
folder's working Kannala-Brandt camera, ``--camera``), ``colon-a`` and ``colon-b`` (a
fisheye colonoscope, 192 x 192; against pycolmap's ``RADIAL_FISHEYE`` self-calibration);
the others (``sceaux-exif``, ``temple``, ``dino``, ``viking``, ``gun``, ``dt990``): the
fisheye must not be tried there (their results unchanged; against the run before).

Run::

    git archive BASE src | tar -x -C BEFORE
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_fisheye.py \\
        --data DATA --before BEFORE/src [--only c3vd colon-a]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402
from benchmarks.check_sfm_fresh import agreement, run_pycolmap, self_calibrated_camera  # noqa: E402
from benchmarks.check_sfm_k1 import prepare_c3vd, read_frames, run_cli  # noqa: E402

FISHEYE = ["c3vd", "colon-a", "colon-b"]
OTHERS = ["temple", "dino", "viking", "gun", "dt990", "sceaux-exif"]

COLUMNS = [
    "sequence",
    "run",
    "model",
    "f start px",
    "f found px",
    "f vs reference",
    "k1",
    "registered",
    "reprojection px (median)",
    "poses vs reference: rotation / translation deg / centres % of path",
    "s (CPU s)",
]


def _model(r: dict[str, Any]) -> str:
    """The lens the command chose, from its notes."""
    if any("kept (the fisheye)" in n for n in r.get("notes", [])):
        return "equidistant fisheye (KB k1)"
    return "SIMPLE_RADIAL"


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
        _, sc = self_calibrated_camera(folder, frames)
        sc["R"], sc["t"] = np.asarray(sc["R"], float), np.asarray(sc["t"], float)
        sc["f0"], sc["f"], sc["k1"] = 0.45 * w, sc["camera"][0], sc["camera"][3]
        runs.append(("pycolmap, self-calibrated", "RADIAL_FISHEYE", sc))
        cached = folder / "fisheye-pycolmap.json"
        if cached.exists():
            sr = json.loads(cached.read_text())
        else:
            model = ("SIMPLE_RADIAL_FISHEYE", (0.45 * w, w / 2, h / 2, 0.0))
            sr = run_pycolmap(frames, None, True, True, model)
            keep = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in sr.items()}
            cached.write_text(json.dumps(keep))
        sr["R"], sr["t"] = np.asarray(sr["R"], float), np.asarray(sr["t"], float)
        sr["f0"] = 0.45 * w
        if "camera" in sr:
            sr["f"], sr["k1"] = sr["camera"][0], sr["camera"][3]
        runs.append(("pycolmap, self-calibrated", "SIMPLE_RADIAL_FISHEYE", sr))
        if name == "c3vd":
            g = run_cli(folder, endo, ROOT / "src", folder / "given.toml")
            g["f0"] = g["f"]
            runs.append(("imageform CLI, --camera", "the working camera (KB k1-k4)", g))
            ref_label = "imageform with the fisheye camera file"
        else:
            ref_label = "pycolmap's RADIAL_FISHEYE self-calibration"
            runs.append(runs.pop(2))  # the reference last
    ref = runs[-1][2] if name in FISHEYE else runs[0][2]
    f_ref = ref.get("f")
    rows = []
    for label, model, r in runs:
        ok = r["reg"] > 0 and "points" in r
        if ok and r is not ref:
            rot, tra, rms = agreement(r["R"], r["t"], ref["R"], ref["t"])
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok else "-"
        f = r.get("f") if ok else None
        k1 = r.get("k1") if ok else None
        cpu = f" ({r['cpu']:.1f})" if "cpu" in r else ""
        rows.append(
            [
                name,
                label,
                model,
                f"{r['f0']:.1f}" if r.get("f0") else "-",
                f"{f:.1f}" if f is not None else "-",
                f"{100 * (f / f_ref - 1):+.1f} %" if f is not None and f_ref else "-",
                f"{k1:+.4f}" if k1 is not None else "-",
                f"{r['reg']}/{n}",
                f"{r['reproj']:.2f}" if ok else "-",
                vs,
                f"{r['time']:.1f}{cpu}",
            ]
        )
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
    print(header("The equidistant fisheye tried without a camera file"))
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
    keys = ("no camera file", "distortion", "radial", "ran off", "settle", "fisheye")
    said = [(run, ln) for run, ln in notes if any(k in ln for k in keys)]
    print("\n".join(f"- {run}: `{line}`" for run, line in said) or "- none")


if __name__ == "__main__":
    main()
