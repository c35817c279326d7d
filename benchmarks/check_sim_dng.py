"""A simulated camera's DNG developed: does the developer render what the simulator rendered?

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sim_dng.py \\
        [--src before=/path/to/old/src] [--src after=src] [--width 1280]

Each ``--src`` tree, in its own processes, runs ``imageform simulate --raw sim.dng`` on the
built-in scene (seed 0) and develops the DNG with ``imageform develop`` (Menon demosaicing,
the simulator's own, camera white balance, sRGB): as LibRaw does by default for brightness
(nothing), ``--auto-bright`` (LibRaw's default brightening) and, where the tree has it,
``--baseline-exposure`` (the DNG's BaselineExposure, as Adobe's readers apply it). Each
image goes through ``imageform chart``: the mean CIEDE2000 of its 24 patches to the
ColorChecker's D65 values, beside the same figure for the simulator's own output image (the
target: a developed DNG can do no better than the simulation it came from). LibRaw's
matched rendering (rawpy, ``no_auto_bright=True``, sRGB curve, AHD) is a third reference.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _imageform(src: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=f"{src}{os.pathsep}{ROOT}")
    cmd = [sys.executable, "-m", "imageform", *args]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)


def _chart_de(src: str, image: Path, out: Path) -> str:
    r = _imageform(src, "chart", str(image), "-o", str(out), "--force")
    if r.returncode != 0:
        return "no chart: " + (r.stderr.strip().splitlines() or ["?"])[-1][:60]
    return f"{statistics.mean(json.loads(out.read_text())['delta_e00_before']):.2f}"


def _libraw(dng: Path, png: Path) -> bool:
    try:
        import rawpy
        import tifffile
    except ImportError:
        return False
    with rawpy.imread(str(dng)) as r:
        rgb = r.postprocess(
            use_camera_wb=True,
            no_auto_bright=True,
            output_bps=16,
            gamma=(2.4, 12.92),
            adjust_maximum_thr=0.0,
            user_flip=0,
        )
    tifffile.imwrite(png, rgb)
    return True


def run_tree(name: str, src: str, width: int, folder: Path) -> list[list[str]]:
    scene = folder / "scene.toml"
    dng, sim = folder / "sim.dng", folder / "sim"
    args = ["simulate", "--raw", str(dng), "-o", str(sim), "--force", "--seed", "0"]
    if width != 1280:
        text = (ROOT / "src/imageform/simulate/scenes/default.toml").read_text()
        height = width * 9 // 16
        text = text.replace("width = 1280", f"width = {width}")
        scene.write_text(text.replace("height = 720", f"height = {height}"))
        args += ["--scene", str(scene)]
    r = _imageform(src, *args)
    if r.returncode != 0:
        raise SystemExit(f"{name}: simulate failed: {r.stderr.strip()[-300:]}")
    rows = [
        [
            name,
            "the simulator's output image",
            _chart_de(src, sim / "stages" / "07-output.png", folder / "c0.json"),
        ]
    ]
    for label, extra in (
        ("develop (no brightening, LibRaw's matched settings)", []),
        ("develop --auto-bright (LibRaw's default brightening)", ["--auto-bright"]),
        ("develop --baseline-exposure (the DNG's BaselineExposure)", ["--baseline-exposure"]),
        (
            "develop --baseline-exposure --highlight-rolloff (highlights rolled off)",
            ["--baseline-exposure", "--highlight-rolloff"],
        ),
    ):
        png = folder / "dev.png"
        dev = _imageform(
            src, "develop", str(dng), "-o", str(png), "--force", "--demosaic", "menon", *extra
        )
        if dev.returncode != 0:
            rows.append([name, label, "not there: " + dev.stderr.strip().splitlines()[-1][:70]])
            continue
        rows.append([name, label, _chart_de(src, png, folder / "c.json")])
    if _libraw(dng, folder / "libraw.tif"):
        rows.append(
            [
                name,
                "LibRaw (rawpy, no_auto_bright, sRGB curve, AHD)",
                _chart_de(src, folder / "libraw.tif", folder / "c.json"),
            ]
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--src", action="append", default=[], help="NAME=PATH of a source tree")
    ap.add_argument("--width", type=int, default=1280)
    a = ap.parse_args()
    trees = [s.split("=", 1) for s in a.src] or [["this tree", str(ROOT / "src")]]
    rows: list[list[str]] = []
    for name, src in trees:
        with tempfile.TemporaryDirectory() as tmp:
            rows += run_tree(name, str(Path(src).resolve()), a.width, Path(tmp))
    from imageform import __version__

    print("# A simulated camera's DNG developed: the chart against the simulation\n")
    print(
        f"imageform {__version__} · built-in scene {a.width} px wide, seed 0 · "
        "Menon demosaicing, camera white balance, sRGB\n"
    )
    print("| tree | image | chart mean ΔE00 (24 patches, to D65 values) |")
    print("|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
