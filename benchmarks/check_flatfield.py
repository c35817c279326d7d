"""Shading correction on real images: BaSiC against its reference implementation and
basicpy, and known shadings multiplied into real photographs and H&E tiles.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_flatfield.py \\
        [--basic-data /tmp/flat/basicpy] [--basicpy /tmp/flat/venv/bin/python] [--reference-only]

1. Real microscopy stacks, BaSiC's demonstration data as BaSiCPy ships them (peng-lab/BaSiCPy
   ``data/*.npz`` at commit bbb6d9aa, MIT; fetched into ``--basic-data``, not committed;
   ``tests/data/flatfield/wsi_brain_64.npz`` is a committed 64-pixel subset): each stack
   resized to 128 x 128 as BaSiCPy's comparison notebook does, estimated with
   ``sort_intensity=True`` as the reference sorts, and compared with the reference flat
   field (``reference_results.npz``; RMS and max of ``ours / ref - 1`` after normalising both
   to mean 1), without and with the dark field. That reference is not the MATLAB code's
   output: BaSiCPy's notebook ``misc_notebooks/check_reference_implementation.ipynb``
   (deleted in c79b67c) computed it with PyBaSiC at commit f3fcf19, a line-for-line port of
   the MATLAB BaSiC whose default dark-field weight is ``lambda_D = 0.2 lambda_F = 0.1 s``
   where the MATLAB ``BaSiC.m`` (and ``estimate_flatfield``) use ``0.2 s``. The dark-field
   rows are therefore run twice: our defaults (MATLAB's), and "ref's lambda_D"
   (``smoothness_darkfield = 0.1 s``, ``s = ||DCT(mean image / its mean)||_1 / 400``). The
   wsi_brain reference was computed on an earlier version of its tiles (BaSiCPy commit
   c79b67c ``data/wsi_brain.npz``, darkest pixel 10 counts; the shipped tiles' is 655, and
   BaSiC bounds the dark field's offset by the darkest pixel): when
   ``--basic-data/wsi_brain_c79b67c.npz`` exists (``git show c79b67c:data/wsi_brain.npz``)
   those tiles are run too. "dark field max abs diff vs ref" is in the stack's counts (uint8
   for the time-lapses, uint16 for the brain tiles). "background CV" is the
   coefficient of variation over the field of the stack's per-pixel median (mostly
   background), before and after correction with our flat field. basicpy (below) is run
   alike (``fitting_mode="approximate"``, ``sort_intensity=True``, ``get_darkfield`` as the
   row, its own defaults otherwise) on the same 128-pixel stacks.
2. Known shadings: cos4 (``cos4_falloff``, f = 0.7 x the long side), cos4 times a mechanical
   vignette (``mechanical_vignetting``: pupil 1, barrel 1.1 at 0.8), and an off-centre
   LED-like lobe (0.3 + 0.7 exp(-d^2 / 2 (0.6 W)^2) around (0.7 W, 0.35 H)), multiplied in
   linear light into (a) the 18 landscape Kodak photographs (shared/data/kodak, 512 x 768,
   sRGB decoded, grey) and (b) 32 real H&E tiles of 64 x 64 cut from the two 256-pixel crops
   of tests/data/stain (torchstain MIT, tiatoolbox BSD-3; luminance). Error: RMS relative
   error of the recovered flat field after normalising means. "background CV": for the H&E
   tiles, the CV over the tile of the glass pixels (min channel > 0.8 before shading) of the
   tiatoolbox tiles, averaged, before and after correction. The single-frame
   ``estimate_vignetting`` is run on each Kodak photograph alone (median over the 20).
3. basicpy (2.0.0, its defaults: ``fitting_mode="approximate"``, no sorting, no dark field;
   ``working_size`` 128) run by ``--basicpy`` (a separate virtual environment; skipped when
   absent) on the same stacks: its error, and the RMS relative difference between its flat
   field and ours.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import estimate_flatfield, estimate_vignetting
from imageform.optics import cos4_falloff, mechanical_vignetting

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT.parent / "shared" / "data" / "kodak"
if not KODAK.is_dir():
    KODAK = Path("/work/shared/data/kodak")
STAIN = ROOT / "tests" / "data" / "stain"


def rms_rel(est: np.ndarray, true: np.ndarray) -> float:
    a, b = est / est.mean(), true / true.mean()
    return float(np.sqrt(np.mean((a / b - 1) ** 2)))


def max_rel(est: np.ndarray, true: np.ndarray) -> float:
    a, b = est / est.mean(), true / true.mean()
    return float(np.abs(a / b - 1).max())


def cv(a: np.ndarray) -> float:
    return float(a.std() / a.mean())


def pct(x: float) -> str:
    return f"{100 * x:.2f} %"


def shadings(shape: tuple[int, int]) -> dict[str, np.ndarray]:
    h, w = shape
    f = 0.7 * max(h, w)
    cos4 = cos4_falloff(shape, focal_length_px=f)
    mech = mechanical_vignetting(
        shape, focal_length_px=f, pupil_radius=1.0, barrel_radius=1.1, barrel_distance=0.8
    )
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    led = 0.3 + 0.7 * np.exp(-((u - 0.7 * w) ** 2 + (v - 0.35 * h) ** 2) / (2 * (0.6 * w) ** 2))
    return {"cos4": cos4, "cos4 x mechanical": cos4 * mech, "off-centre LED": led}


def srgb_to_linear(a: np.ndarray) -> np.ndarray:
    return np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4)


def kodak_stack() -> np.ndarray:
    from imageform.io import read_image

    out = []
    for p in sorted(KODAK.glob("kodim*.png")):
        img = read_image(p)
        if img.shape[:2] == (512, 768):
            out.append(srgb_to_linear(img.astype(np.float64) / 255).mean(axis=2))
    return np.stack(out)


def he_tiles() -> tuple[np.ndarray, np.ndarray]:
    """32 luminance tiles of 64 x 64 and their glass masks (tiatoolbox's glass; else none)."""
    from imageform.io import read_image

    tiles, masks = [], []
    for name in ("torchstain_target_crop.png", "tiatoolbox_colon_crop.png"):
        rgb = read_image(STAIN / name).astype(np.float64) / 255
        lin = srgb_to_linear(rgb)
        for i in range(4):
            for j in range(4):
                t = lin[64 * i : 64 * i + 64, 64 * j : 64 * j + 64]
                tiles.append(t.mean(axis=2))
                m = rgb[64 * i : 64 * i + 64, 64 * j : 64 * j + 64].min(axis=2) > 0.8
                masks.append(m if "tiatoolbox" in name else np.zeros_like(m))
    return np.stack(tiles), np.stack(masks)


def run_basicpy(python: str | None, stack: np.ndarray, **kw: object) -> tuple[np.ndarray, float]:
    """basicpy's flat field of ``stack`` in a separate interpreter, and its seconds."""
    if python is None:
        return np.full(stack.shape[1:], np.nan), float("nan")
    code = (
        "import json, sys, time, numpy as np\n"
        "from basicpy import BaSiC\n"
        "s = np.load(sys.argv[1]); kw = json.loads(sys.argv[2])\n"
        "b = BaSiC(**kw); t = time.perf_counter(); b.fit(s); dt = time.perf_counter() - t\n"
        "np.save(sys.argv[3], np.asarray(b.flatfield, dtype=np.float64)); print(dt)\n"
    )
    with tempfile.TemporaryDirectory() as tmp:
        src, dst = Path(tmp, "s.npy"), Path(tmp, "f.npy")
        np.save(src, stack.astype(np.float32))
        env = {**os.environ, "PYTHONPATH": ""}
        done = subprocess.run(
            [python, "-c", code, str(src), json.dumps(kw), str(dst)],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        )
        return np.load(dst), float(done.stdout.strip().splitlines()[-1])


def dct_scale(stack: np.ndarray) -> float:
    """BaSiC's ``s = ||DCT(mean image / its mean)||_1 / 400`` (the weights' scale)."""
    from scipy.fft import dctn

    m = stack.mean(axis=0)
    return float(np.abs(dctn(m / m.mean(), norm="ortho")).sum() / 400)


def reference_rows(data: Path, python: str | None) -> list[list[object]]:
    from skimage.transform import resize

    ref = np.load(data / "reference_results.npz", allow_pickle=True)
    rows: list[list[object]] = []
    runs = [
        (key, key, data / f"{key}.npz")
        for key in ("timelapse_brightfield", "timelapse_nanog", "timelapse_pu1", "wsi_brain")
    ]
    if (data / "wsi_brain_c79b67c.npz").exists():
        runs.append(("wsi_brain (c79b67c tiles)", "wsi_brain", data / "wsi_brain_c79b67c.npz"))
    for label, key, path in runs:
        raw = np.load(path)["images"]
        stack = np.array(
            [resize(a, (128, 128), order=1, mode="symmetric", preserve_range=True) for a in raw]
        ).astype(np.float64)
        r = ref[key].item()
        s = dct_scale(stack)
        for dark, lam_d, fitted in (
            (False, None, "flat"),
            (True, None, "flat + dark"),
            (True, 0.1 * s, "flat + dark, ref's lambda_D"),
        ):
            suffix = "" if dark else "-flatonly"
            t0 = time.perf_counter()
            est = estimate_flatfield(
                stack, darkfield=dark, sort_intensity=True, smoothness_darkfield=lam_d
            )
            dt = time.perf_counter() - t0
            g = r["flatfield" + suffix]
            if lam_d is None:  # basicpy once per setting of get_darkfield
                theirs, _ = run_basicpy(
                    python,
                    stack,
                    fitting_mode="approximate",
                    sort_intensity=True,
                    get_darkfield=dark,
                    working_size=128,
                )
            med = np.median(stack, axis=0)
            fixed = (med - (est.darkfield if dark else 0)) / est.flatfield
            dark_err = (
                f"{np.abs(est.darkfield - r['darkfield']).max():.1f} "
                f"(ref {r['darkfield'].min():.0f} to {r['darkfield'].max():.0f})"
                if dark
                else "-"
            )
            rows.append(
                [
                    label,
                    len(stack),
                    fitted,
                    f"{g.min() / g.mean():.2f}-{g.max() / g.mean():.2f}",
                    pct(rms_rel(est.flatfield, g)),
                    pct(max_rel(est.flatfield, g)),
                    dark_err,
                    f"{cv(med):.3f} -> {cv(fixed):.3f}",
                    "-" if python is None else pct(rms_rel(theirs, g)),
                    "-" if python is None else pct(rms_rel(est.flatfield, theirs)),
                    f"{est.iterations}{'' if est.converged else ' (limit)'}",
                    f"{dt:.1f}",
                ]
            )
            print(rows[-1], file=sys.stderr)
    return rows


def synthetic_rows(python: str | None) -> tuple[list[list[object]], list[list[object]]]:
    kodak = kodak_stack()
    he, glass = he_tiles()
    rows: list[list[object]] = []
    single: list[list[object]] = []
    for content, stack in (("Kodak photographs", kodak), ("H&E tiles", he)):
        for name, shade in shadings(stack.shape[1:]).items():
            shaded = stack * shade
            t0 = time.perf_counter()
            est = estimate_flatfield(shaded)
            dt = time.perf_counter() - t0
            fixed = shaded / est.flatfield
            if content == "H&E tiles":
                sel = glass.any(axis=(1, 2))
                cvs = [
                    (cv(s[m]), cv(f[m]))
                    for s, f, m in zip(shaded[sel], fixed[sel], glass[sel], strict=True)
                ]
                before, after = np.mean(cvs, axis=0)
                orig = np.mean([cv(s[m]) for s, m in zip(stack[sel], glass[sel], strict=True)])
                bg = f"{before:.3f} -> {after:.3f} (unshaded {orig:.3f})"
            else:
                bg = "-"
            theirs, their_dt = run_basicpy(python, shaded, working_size=128)
            rows.append(
                [
                    content,
                    len(stack),
                    name,
                    pct(rms_rel(np.ones_like(shade), shade)),
                    pct(rms_rel(est.flatfield, shade)),
                    bg,
                    "-" if python is None else pct(rms_rel(theirs, shade)),
                    "-" if python is None else pct(rms_rel(est.flatfield, theirs)),
                    f"{dt:.1f} / " + ("-" if python is None else f"{their_dt:.1f}"),
                ]
            )
            print(rows[-1], file=sys.stderr)
            if content == "Kodak photographs":
                errs = []
                for s in shaded:
                    try:
                        errs.append(rms_rel(estimate_vignetting(s).flatfield, shade))
                    except Exception:  # a refused fit counts as a failure
                        errs.append(float("nan"))
                e = np.array(errs)
                ok = np.isfinite(e)
                single.append(
                    [
                        name,
                        pct(rms_rel(np.ones_like(shade), shade)),
                        pct(float(np.median(e[ok]))) if ok.any() else "-",
                        pct(float(np.max(e[ok]))) if ok.any() else "-",
                        f"{int((~ok).sum())} of {len(e)}",
                    ]
                )
    return rows, single


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--basic-data", type=Path, default=Path("/tmp/flat/basicpy"))
    ap.add_argument("--basicpy", default="/tmp/flat/venv/bin/python")
    ap.add_argument(
        "--reference-only", action="store_true", help="only BaSiC's stacks against the reference"
    )
    args = ap.parse_args()
    python = args.basicpy if args.basicpy and Path(args.basicpy).exists() else None
    print(header("Shading correction: BaSiC on real stacks, known shadings, basicpy"))
    print(f"load average at start: {os.getloadavg()[0]:.1f}\n")
    if (args.basic_data / "reference_results.npz").exists():
        print("## BaSiC's data against the reference (PyBaSiC f3fcf19, the MATLAB port)\n")
        print(
            markdown_table(
                (
                    "stack",
                    "images",
                    "fitted",
                    "ref flat range",
                    "RMS vs ref",
                    "max vs ref",
                    "dark field max abs diff vs ref",
                    "background CV before -> after",
                    "RMS basicpy vs ref",
                    "ours vs basicpy",
                    "ALM iterations",
                    "seconds",
                ),
                reference_rows(args.basic_data, python),
            )
        )
    if args.reference_only:
        return
    rows, single = synthetic_rows(python)
    print("## Known shadings multiplied into real images (BaSiC, defaults)\n")
    print(
        markdown_table(
            (
                "content",
                "images",
                "shading",
                "RMS uncorrected",
                "RMS ours",
                "glass CV before -> after",
                "RMS basicpy",
                "ours vs basicpy",
                "seconds ours / basicpy",
            ),
            rows,
        )
    )
    print("## One photograph at a time (estimate_vignetting, defaults)\n")
    print(
        markdown_table(
            ("shading", "RMS uncorrected", "median RMS", "max RMS", "fits refused"), single
        )
    )


if __name__ == "__main__":
    main()
