"""Shading correction on real images: BaSiC against its reference implementation and
basicpy, known shadings multiplied into real photographs, H&E tiles and an endoscope's frames.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_flatfield.py \\
        [--basic-data /tmp/flat/basicpy] [--basicpy /tmp/flat/venv/bin/python] [--reference-only]
        [--video /tmp/flatmask/c3vdv3_prev.mp4] [--every 8] [--main-src DIR] [--endo-only]

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
4. An endoscope's frames (``--endo-only`` prints these tables alone): a colonoscope's real
   frames, every ``--every``-th of C3VD v3's preview clip (``--video``: ``git show
   ad9391d:assets/aligned_prev_final.mp4`` of github.com/DurrLab/C3VDv3, CC BY 4.0; its
   colour panel, the first 445 columns, read with ``av``; without the clip the 13 frames of
   tests/data/endo), sRGB decoded, grey. The octagonal aperture in black corners breaks the
   unmasked fit. Known shadings multiplied in linear light: cos4 and cos4 x mechanical as in
   2, and an LED-like lobe ``0.3 + 0.7 exp(-d^2 / 2 (0.5 R)^2)``, ``R`` the aperture's
   radius, centred on the aperture or 0.25 R right and 0.15 R up of it. "mask auto": the
   field of view ``field_of_view_mask`` finds in the shaded frame re-encoded as 8-bit sRGB
   (what a camera delivers; the default 8 px margin). Errors inside the unshaded frame's
   field of view: "RMS" of the recovered flat field against the shading multiplied in (the
   frame's own illumination falloff and scene count as error: they are unknown), and "RMS of
   est / est unshaded", the flat field divided by the same fit's on the unshaded frame (the
   frame's own part divided out: how well the added shading is recovered). The frames as
   filmed: the estimated flat field's range, and whether dividing it out evens the tissue's
   brightness: the medians of five rings of equal area from the aperture's center out (their
   max / min) and the CV, before and after; each frame's own fit and one fit to the mean of
   all frames. No truth is known for these.
5. ``--main-src DIR`` (a ``src`` tree, e.g. ``git archive main src``): the Kodak photographs,
   as photographed and under the shadings of 2, fitted by ``estimate_vignetting`` (no mask)
   here and by that tree in a subprocess, the flat fields compared bit for bit.
"""

from __future__ import annotations

import argparse
import itertools
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


def linear_to_srgb(a: np.ndarray) -> np.ndarray:
    a = np.clip(a, 0.0, 1.0)
    return np.where(a <= 0.0031308, 12.92 * a, 1.055 * a ** (1 / 2.4) - 0.055)


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


# ------------------------------------------------------------------ endoscope frames

ENDO = ROOT / "tests" / "data" / "endo"


def endo_frames(video: Path | None, every: int, width: int = 445) -> tuple[list[np.ndarray], str]:
    """The colonoscope's frames, RGB uint8: every ``every``-th of the clip, or the committed."""
    from imageform.io import read_image

    if video is not None and video.exists():
        import av

        frames = []
        with av.open(str(video)) as box:
            for i, f in enumerate(box.decode(video=0)):
                if i % every == 0:
                    frames.append(np.ascontiguousarray(f.to_ndarray(format="rgb24")[:, :width]))
        return frames, f"{video.name}, every {every}th frame ({len(frames)} frames)"
    files = sorted(ENDO.glob("c3vdv3_f*.jpg"))
    return [read_image(p) for p in files], f"tests/data/endo ({len(files)} frames)"


def endo_shadings(shape: tuple[int, int], fov: np.ndarray) -> dict[str, np.ndarray]:
    """cos4, cos4 x mechanical (as :func:`shadings`), an LED lobe on the aperture and off it."""
    h, w = shape
    rows, cols = np.flatnonzero(fov.any(axis=1)), np.flatnonzero(fov.any(axis=0))
    cu, cv_ = (cols[0] + cols[-1]) / 2, (rows[0] + rows[-1]) / 2
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    big = float(np.hypot(u - cu, v - cv_)[fov].max())

    def lobe(du: float, dv: float) -> np.ndarray:
        d2 = (u - cu - du * big) ** 2 + (v - cv_ - dv * big) ** 2
        return 0.3 + 0.7 * np.exp(-d2 / (2 * (0.5 * big) ** 2))

    out = dict(shadings(shape))
    del out["off-centre LED"]
    out["LED on the aperture's center"] = lobe(0.0, 0.0)
    out["LED off center (0.25 R, -0.15 R)"] = lobe(0.25, -0.15)
    return out


def rms_in(est: np.ndarray, true: np.ndarray, m: np.ndarray) -> float:
    a, b = est[m] / est[m].mean(), true[m] / true[m].mean()
    return float(np.sqrt(np.mean((a / b - 1) ** 2)))


def endo_rows(video: Path | None, every: int) -> tuple[str, list[list[object]], list[list[object]]]:
    from imageform.errors import InvalidInputError
    from imageform.geometry import field_of_view_mask

    frames, what = endo_frames(video, every)
    lums = [srgb_to_linear(f.astype(np.float64) / 255).mean(axis=2) for f in frames]
    fovs = [field_of_view_mask(f) for f in frames]
    options: dict[str, dict[str, object]] = {
        "no mask": {},
        "mask auto": {"mask": True},
        "mask auto, fit_center": {"mask": True, "fit_center": True},
    }

    def fit(lum: np.ndarray, m: np.ndarray, kw: dict[str, object]) -> np.ndarray | None:
        kw = {**kw, "mask": m} if kw.get("mask") else kw
        try:
            return estimate_vignetting(lum, **kw).flatfield  # type: ignore[arg-type]
        except InvalidInputError:
            return None

    plain = {
        label: [fit(lum, m, kw) for lum, m in zip(lums, fovs, strict=True)]
        for label, kw in options.items()
    }
    rows: list[list[object]] = []
    for name, shade in endo_shadings(lums[0].shape, fovs[0]).items():
        runs: dict[str, list[float]] = {}
        refused: dict[str, int] = {}
        for i, (lum, m) in enumerate(zip(lums, fovs, strict=True)):
            shaded = lum * shade
            # the field of view found in the frame as a camera would deliver it (sRGB, 8 bits)
            m_s = field_of_view_mask(np.round(255 * linear_to_srgb(shaded)).astype(np.uint8))
            for label, kw in options.items():
                est = fit(shaded, m_s, kw)
                if est is None:
                    refused[label] = refused.get(label, 0) + 1
                    continue
                runs.setdefault(label, []).append(rms_in(est, shade, m))
                p = plain[label][i]
                if p is not None:
                    runs.setdefault(label + " / plain", []).append(rms_in(est / p, shade, m))
        for label in ("no mask", "mask auto", "mask auto, fit_center"):
            e = np.array(runs.get(label, []))
            r = np.array(runs.get(label + " / plain", []))
            rows.append(
                [
                    name,
                    label,
                    pct(float(np.median([rms_in(np.ones_like(shade), shade, m) for m in fovs]))),
                    pct(float(np.median(e))) if e.size else "-",
                    pct(float(np.max(e))) if e.size else "-",
                    pct(float(np.median(r))) if r.size else "-",
                    pct(float(np.max(r))) if r.size else "-",
                    f"{refused.get(label, 0)} of {len(frames)}",
                ]
            )
            print(rows[-1], file=sys.stderr)
    # the frames as filmed: what is estimated, and whether dividing it out evens the tissue
    own: list[list[object]] = []
    plain_est = [estimate_vignetting(lum, mask=m) for lum, m in zip(lums, fovs, strict=True)]
    mean_lum = np.mean(lums, axis=0)
    fov_all = field_of_view_mask(frames)
    mean_est = estimate_vignetting(mean_lum, mask=fov_all)
    for label, ests in (
        ("each frame's own fit", plain_est),
        ("one fit to the frames' mean", [mean_est] * len(frames)),
    ):
        ranges, rings_b, rings_a, cv_b, cv_a = [], [], [], [], []
        for lum, m, fe in zip(lums, fovs, ests, strict=True):
            f = fe.flatfield[m] / fe.flatfield[m].mean()
            ranges.append((f.min(), f.max()))
            fixed = fe.correct(lum)
            sel = m if fe.mask is None else m & fe.mask
            rb, ra = ring_medians(lum, sel), ring_medians(fixed, sel)
            rings_b.append(rb.max() / rb.min())
            rings_a.append(ra.max() / ra.min())
            cv_b.append(cv(lum[sel]))
            cv_a.append(cv(fixed[sel]))
        lo, hi = np.median(ranges, axis=0)
        own.append(
            [
                label,
                f"{lo:.2f}-{hi:.2f}",
                f"{np.median(rings_b):.2f} -> {np.median(rings_a):.2f}",
                f"{np.median(cv_b):.3f} -> {np.median(cv_a):.3f}",
            ]
        )
        print(own[-1], file=sys.stderr)
    return what, rows, own


def ring_medians(lum: np.ndarray, m: np.ndarray, n: int = 5) -> np.ndarray:
    """Median of ``lum`` in ``n`` rings of equal area over the mask, from its center out."""
    rows, cols = np.flatnonzero(m.any(axis=1)), np.flatnonzero(m.any(axis=0))
    cu, cv_ = (cols[0] + cols[-1]) / 2, (rows[0] + rows[-1]) / 2
    v, u = np.mgrid[0 : m.shape[0], 0 : m.shape[1]]
    r = np.hypot(u - cu, v - cv_)[m]
    edges = np.quantile(r, np.linspace(0, 1, n + 1))
    val = lum[m]
    return np.array([np.median(val[(r >= a) & (r <= b)]) for a, b in itertools.pairwise(edges)])


def kodak_unchanged(main_src: Path | None) -> list[list[object]]:
    """Kodak photographs: estimate_vignetting(mask=None) here and in ``main_src``, bit for bit."""
    if main_src is None or not main_src.is_dir():
        return []
    kodak = kodak_stack()
    cases = {"as photographed": np.ones(kodak.shape[1:]), **shadings(kodak.shape[1:])}
    code = (
        "import sys, numpy as np\n"
        "from imageform.analysis import estimate_vignetting\n"
        "d = np.load(sys.argv[1]); out = {}\n"
        "for k in d.files:\n"
        "    try: out[k] = estimate_vignetting(d[k]).flatfield\n"
        "    except Exception as e: out[k] = np.array(str(e))\n"
        "np.savez(sys.argv[2], **out)\n"
    )
    rows: list[list[object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        src, dst = Path(tmp, "in.npz"), Path(tmp, "out.npz")
        items = {f"{n}|{i}": k * s for n, s in cases.items() for i, k in enumerate(kodak)}
        np.savez(src, **items)
        env = {**os.environ, "PYTHONPATH": str(main_src)}
        subprocess.run([sys.executable, "-c", code, str(src), str(dst)], env=env, check=True)
        theirs = np.load(dst)
        for n in cases:
            same = refused = 0
            keys = [k for k in items if k.startswith(n + "|")]
            for k in keys:
                t = theirs[k]
                try:
                    ours = estimate_vignetting(items[k]).flatfield
                except Exception:  # refused here: the same only if refused there too
                    refused += 1
                    same += int(t.dtype.kind == "U")
                    continue
                same += int(t.dtype.kind == "f" and np.array_equal(ours, t))
            rows.append([n, len(keys), f"{same} of {len(keys)}", refused])
            print(rows[-1], file=sys.stderr)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--basic-data", type=Path, default=Path("/tmp/flat/basicpy"))
    ap.add_argument("--basicpy", default="/tmp/flat/venv/bin/python")
    ap.add_argument(
        "--reference-only", action="store_true", help="only BaSiC's stacks against the reference"
    )
    ap.add_argument(
        "--video",
        type=Path,
        default=Path("/tmp/flatmask/c3vdv3_prev.mp4"),
        help="C3VD v3's preview clip (else the committed frames of tests/data/endo)",
    )
    ap.add_argument("--every", type=int, default=8, help="every Nth frame of --video")
    ap.add_argument("--main-src", type=Path, default=None, help="a src/ tree to compare against")
    ap.add_argument("--endo-only", action="store_true", help="only the endoscope's tables")
    args = ap.parse_args()
    python = args.basicpy if args.basicpy and Path(args.basicpy).exists() else None
    if args.endo_only:
        print(header("Shading correction: an endoscope's frames, with a field-of-view mask"))
    else:
        print(header("Shading correction: BaSiC on real stacks, known shadings, basicpy"))
    print(f"load average at start: {os.getloadavg()[0]:.1f}\n")
    if args.endo_only:
        endo_tables(args)
        return
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
    endo_tables(args)


def endo_tables(args: argparse.Namespace) -> None:
    what, rows, own = endo_rows(args.video, args.every)
    print(f"## An endoscope's frames: known shadings multiplied in ({what})\n")
    print(
        markdown_table(
            (
                "shading",
                "estimate_vignetting",
                "RMS uncorrected",
                "median RMS",
                "max RMS",
                "median RMS of est / est unshaded",
                "max RMS of est / est unshaded",
                "fits refused",
            ),
            rows,
        )
    )
    print(f"## An endoscope's frames as filmed ({what}, mask auto)\n")
    print(
        markdown_table(
            (
                "flat field",
                "range in the field of view (median)",
                "ring medians max / min, before -> after",
                "CV in the field of view, before -> after",
            ),
            own,
        )
    )
    same = kodak_unchanged(args.main_src)
    if same:
        print(f"## Kodak photographs, mask=None: this tree against --main-src {args.main_src}\n")
        print(
            markdown_table(
                ("shading", "photographs", "flat fields bit-identical", "refused here"), same
            )
        )


if __name__ == "__main__":
    main()
