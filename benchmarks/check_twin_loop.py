"""The camera-twin loop of docs/characterize.md, measured for every camera simulate ships.

For each camera X: ``imageform simulate`` renders the built-in scene through X; ``simulate
--camera x/camera.toml --lab lab`` photographs X's lab set; ``imageform characterize lab``
measures the twin; ``simulate --camera twin/camera.toml`` renders the scene through the
twin. X is also rendered once more through its own camera file (another noise draw): the
noise floor of the comparison. The cameras are those of tests/workflows/test_twin_loop.py:
the built-in scene's (CMOS preset), the CCD preset, the Nikon D5100 sensitivities (the
scene file edited), and OpenCV's left camera calibrated from its 13 chessboard views of
``../shared/data/opencv-left`` (640 x 480, given to the first command as ``--camera``).

Columns: the chart's mean ΔE00 in characterize (the lab's developed chart against its
reference); the scene's ColorChecker against the truth (``metrics.json``'s
``colorchecker.delta_e00_mean``) through X and through the twin; the twin's patches
against X's (mean and max ΔE00 over the patches both measured); the vanishing point's
error in pixels (``vanishing.vanishing_point_error_px``) through X and through the twin;
and the noise floor (X again through its own file against X: mean ΔE00, vanishing-point
distance). All runs use simulate's default seed.

Run (about 3-5 minutes a camera on 2 shared cores)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_twin_loop.py \\
        [--data ../shared/data] [--only builtin ccd nikon opencv-left] [--out TABLE.md]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

_CAMERAS = {
    "builtin": ("built-in (CMOS preset)", None),
    "ccd": ("CCD preset", ('preset = "cmos"', 'preset = "ccd"')),
    "nikon": (
        "Nikon D5100 sensitivities",
        ('spectral_sensitivity = "preset"', 'spectral_sensitivity = "nikon_d5100"'),
    ),
    "opencv-left": ("OpenCV's left camera (640 x 480)", None),
}
_VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]


def _cli(*args: str) -> str:
    from imageform.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = main(list(args))
    if code != 0:
        raise RuntimeError(f"imageform {' '.join(args)} exited {code}")
    return out.getvalue()


def _metrics(folder: Path) -> Any:
    return json.loads((folder / "metrics.json").read_text())


def _lab(m: Any) -> np.ndarray:
    return np.array(
        [p["lab_measured"] or [np.nan] * 3 for p in m["colorchecker"]["patches"]], float
    )


def _patch_de(a: Any, b: Any) -> tuple[float, float]:
    from imageform.color import delta_e_ciede2000

    la, lb = _lab(a), _lab(b)
    ok = np.isfinite(la).all(axis=1) & np.isfinite(lb).all(axis=1)
    de = np.asarray(delta_e_ciede2000(la[ok], lb[ok]))
    return float(np.mean(de)), float(np.max(de))


def _vp(m: Any) -> np.ndarray:
    return np.asarray(m["vanishing"]["detected_vanishing_point_px"], float)


def _loop(tmp: Path, key: str, data: Path) -> list[object]:
    label, edit = _CAMERAS[key]
    scene: list[str] = []
    camera: list[str] = []
    if edit is not None:
        text = (files("imageform.simulate") / "scenes" / "default.toml").read_text()
        if edit[0] not in text:
            raise RuntimeError(f"the default scene no longer holds {edit[0]!r}")
        path = tmp / "scene.toml"
        path.write_text(text.replace(*edit))
        scene = ["--scene", str(path)]
    if key == "opencv-left":
        left = tmp / "left.toml"
        images = [str(data / "opencv-left" / v) for v in _VIEWS]
        _cli("calibrate", *images, "--board", "9x6", "--square", "25mm", "-o", str(left))
        camera = ["--camera", str(left)]
    t0 = time.perf_counter()
    _cli("simulate", *scene, *camera, "-o", str(tmp / "x"))
    x_file = str(tmp / "x" / "camera.toml")
    _cli("simulate", *scene, "--camera", x_file, "--lab", str(tmp / "lab"), "-o", str(tmp / "x2"))
    char = json.loads(_cli("characterize", str(tmp / "lab"), "-o", str(tmp / "twin"), "--json"))
    _cli("simulate", *scene, "--camera", str(tmp / "twin" / "camera.toml"), "-o", str(tmp / "t"))
    seconds = time.perf_counter() - t0
    x, t, x2 = _metrics(tmp / "x"), _metrics(tmp / "t"), _metrics(tmp / "x2")
    mean, worst = _patch_de(x, t)
    floor, _ = _patch_de(x, x2)
    pa, pb = _vp(x), _vp(x2)
    vp_floor = float(np.hypot(*(pa[:2] / pa[2] - pb[:2] / pb[2])))
    co = char["color"]
    return [
        label,
        f"{co['delta_e00_mean']:.2f}",
        f"{x['colorchecker']['delta_e00_mean']:.2f} / {t['colorchecker']['delta_e00_mean']:.2f}",
        f"{mean:.2f} ({worst:.2f})",
        f"{x['vanishing']['vanishing_point_error_px']:.2f} / "
        f"{t['vanishing']['vanishing_point_error_px']:.2f}",
        f"{floor:.2f}, {vp_floor:.2f}",
        f"{seconds:.0f}",
    ]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--only", nargs="+", choices=sorted(_CAMERAS), default=list(_CAMERAS))
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    rows = []
    for key in args.only:
        with tempfile.TemporaryDirectory() as d:
            rows.append(_loop(Path(d), key, args.data))
        print(f"done {key}", file=sys.stderr, flush=True)
    cols = [
        "camera X",
        "chart ΔE00 in characterize",
        "scene ΔE00, X / twin",
        "twin vs X, mean (max)",
        "vanishing-point error (px), X / twin",
        "noise floor: X again vs X, ΔE00 mean, VP px",
        "s",
    ]
    text = header("The camera-twin loop: simulate, lab, characterize, simulate through the twin")
    text += "\n" + markdown_table(cols, rows) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
