"""ColorChecker detection in uncropped photographs: imageform vs colour-checker-detection.

Cases (tests/analysis/chart_cases.py): a rendered ColorChecker Classic composited into a
REAL Kodak photograph (``../shared/data/kodak``) with a random perspective (tilt up to 40
degrees), any in-plane rotation, 10-60 % of the frame width, an illuminant cast, vignetting
and a light ramp, blur, noise and JPEG compression; one case in five has 1-3 patches
covered by a textured crop of another photograph.

Measures, per method:

- **detected**: a chart was returned; **correct** (imageform): every patch centre within
  1/6 of the patch pitch of the truth; the centre error in pitches (median, 95th percentile);
- **patch ΔE00**: CIEDE2000 between each measured patch mean and the true patch colour (as
  lit, before blur/noise/JPEG), over the patches not occluded and not flagged: the median
  over cases of the per-case median, and of the per-case maximum. The peer returns no
  centres, so a peer detection is **correct** when its per-case median ΔE00 is below 5;
- **false charts**: charts returned on the 24 Kodak photographs themselves (no chart);
- time per image (median), and imageform on a 6-megapixel photograph (case 0 upscaled 4x).

colour-checker-detection (PyPI, colour-science) is the peer when importable; install it
aside, e.g. ``pip install --no-deps --target /tmp/ccd-peer colour-checker-detection`` and
``PYTHONPATH=/tmp/ccd-peer`` (it needs OpenCV and colour-science, both test dependencies).

Run from the project root::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_chart_detect.py [--cases 120] [--out FILE]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402
from imageform.analysis import (  # noqa: E402
    ChartWarning,
    detect_colorchecker,
    measure_chart_patches,
)
from imageform.color.convert import convert  # noqa: E402
from imageform.color.delta_e import delta_e  # noqa: E402
from tests.analysis.chart_cases import chart_case, kodak_images  # noqa: E402

DATA = ROOT.parent / "shared" / "data"


def _de(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    la = convert(np.clip(a, 0, 1), "srgb", "lab")
    lb = convert(np.clip(b, 0, 1), "srgb", "lab")
    return np.asarray(delta_e(la, lb))


def _ours(img: np.ndarray) -> tuple[object, float]:
    t0 = time.perf_counter()
    det = detect_colorchecker(img)
    dt = time.perf_counter() - t0
    if not det.found:
        return None, dt
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ChartWarning)
        pat = measure_chart_patches(img, det)
    return (det, pat), dt


def _peer() -> object:
    try:
        import colour_checker_detection as ccd
    except ImportError:
        return None
    return ccd


def _peer_run(ccd: object, img: np.ndarray) -> tuple[np.ndarray | None, float]:
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = ccd.detect_colour_checkers_segmentation(img.astype(np.float32) / 255.0)  # type: ignore[attr-defined]
    except Exception:
        out = ()
    dt = time.perf_counter() - t0
    return (np.asarray(out[0], dtype=np.float64) if len(out) else None), dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, default=120)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--small", type=int, default=25, help="extra cases with tiny charts")
    args = ap.parse_args()
    bgs = kodak_images(DATA)
    ccd = _peer()
    rows_ours: list[dict[str, float]] = []
    rows_peer: list[dict[str, float]] = []
    detect_colorchecker(chart_case(bgs, 0).image)  # numba warm-up (not timed)
    seeds = [(s, (0.1, 0.6)) for s in range(args.cases)]
    seeds += [(1000 + s, (0.06, 0.1)) for s in range(args.small)]
    for seed, span in seeds:
        case = chart_case(bgs, seed, width=span)
        res, dt = _ours(case.image)
        r: dict[str, float] = {
            "t": dt,
            "occ": float(case.occluded.any()),
            "pitch": case.pitch,
            "tiny": float(seed >= 1000),
        }
        if res is not None:
            det, pat = res
            err = np.linalg.norm(det.centers - case.centres, axis=1) / case.pitch
            use = pat.valid & ~case.occluded
            de = _de(pat.means[use], case.patches[use]) if use.any() else np.array([np.nan])
            r.update(
                det=1.0,
                err=float(err.max()),
                de_med=float(np.median(de)),
                de_max=float(np.max(de)),
                ok=float(err.max() < 1 / 6),
                flagged=float((~pat.valid & case.occluded).sum() / max(case.occluded.sum(), 1)),
            )
        else:
            r.update(det=0.0, ok=0.0)
        rows_ours.append(r)
        if ccd is not None:
            sw, dtp = _peer_run(ccd, case.image)
            p: dict[str, float] = {
                "t": dtp,
                "occ": float(case.occluded.any()),
                "pitch": case.pitch,
                "tiny": float(seed >= 1000),
            }
            if sw is not None and sw.shape == (24, 3):
                use = ~case.occluded
                de = _de(sw[use], case.patches[use])
                p.update(
                    det=1.0,
                    de_med=float(np.median(de)),
                    de_max=float(np.max(de)),
                    ok=float(np.median(de) < 5),
                )
            else:
                p.update(det=0.0, ok=0.0)
            rows_peer.append(p)
        print(seed, r, file=sys.stderr)
    # false charts on the Kodak photographs themselves
    false_ours = 0
    neg_times: list[float] = []
    false_peer = 0
    for img in bgs:
        u8 = np.round(img * 255).astype(np.uint8)
        res_neg, dt_neg = _ours(u8)
        false_ours += res_neg is not None
        neg_times.append(dt_neg)
        if ccd is not None:
            false_peer += _peer_run(ccd, u8)[0] is not None
    # a 6-megapixel photograph
    from PIL import Image

    big_case = chart_case(bgs, 0)  # 2048 x 3072 once upscaled
    hgt, wid = big_case.image.shape[:2]
    big = np.asarray(Image.fromarray(big_case.image).resize((4 * wid, 4 * hgt), Image.BICUBIC))
    times, mtimes = [], []
    for _ in range(5):
        t0 = time.perf_counter()
        det_big = detect_colorchecker(big)
        t1 = time.perf_counter()
        measure_chart_patches(big, det_big)
        times.append(t1 - t0)
        mtimes.append(time.perf_counter() - t1)
    big_err = float(
        np.max(np.linalg.norm(det_big.centers - (big_case.centres * 4 + 1.5), axis=1))
        / (4 * big_case.pitch)
    )

    def summary(name: str, rows: list[dict[str, float]], false: int, subset: str) -> list[object]:
        n = len(rows)
        det = [r for r in rows if r["det"]]
        errs = [r["err"] for r in det if "err" in r]
        de_med = [r["de_med"] for r in det if np.isfinite(r.get("de_med", np.nan))]
        de_max = [r["de_max"] for r in det if np.isfinite(r.get("de_max", np.nan))]
        f = lambda v, q: f"{np.percentile(v, q):.3f}" if len(v) else "-"  # noqa: E731
        return [
            name,
            subset,
            n,
            f"{100 * len(det) / n:.1f}",
            f"{100 * sum(r['ok'] for r in rows) / n:.1f}",
            f(errs, 50),
            f(errs, 95),
            f(de_med, 50),
            f(de_max, 50),
            f"{false}/24",
            f"{1000 * np.median([r['t'] for r in rows]):.0f}",
        ]

    cols = [
        "method",
        "cases",
        "n",
        "detected %",
        "correct %",
        "centre err median (pitch)",
        "centre err p95 (pitch)",
        "patch ΔE00 median",
        "patch ΔE00 max (median case)",
        "false charts on Kodak",
        "time ms (median)",
    ]
    table = []
    all_rows = {
        "imageform detect_colorchecker": rows_ours,
        "colour-checker-detection segmentation": rows_peer,
    }
    for name, rows, false in (
        ("imageform detect_colorchecker", rows_ours, false_ours),
        ("colour-checker-detection segmentation", rows_peer, false_peer),
    ):
        if not rows:
            continue
        main_rows = [r for r in rows if not r["tiny"]]
        table.append(summary(name, main_rows, false, "all (width 10-60 %)"))
        rows = main_rows
        occ = [r for r in rows if r["occ"]]
        if occ:
            table.append(summary(name, occ, false, "with occluded patches"))
        small = [r for r in rows if r["pitch"] < 20]
        if small:
            table.append(summary(name, small, false, "pitch < 20 px"))
        tiny = [r for r in all_rows[name] if r["tiny"]]
        if tiny:
            table.append(summary(name, tiny, false, "tiny: width 6-10 % (0.5-1.3 % of the area)"))
    occ_flag = [r["flagged"] for r in rows_ours if r["occ"] and r["det"] and not r["tiny"]]
    import imageform

    peer_ver = getattr(ccd, "__version__", "not installed")
    text = (
        header("ColorChecker detection in photographs (bench_chart_detect.py)")
        + f"\nimageform {imageform.__version__}; colour-checker-detection {peer_ver} "
        "(detect_colour_checkers_segmentation, default settings). "
        f"{args.cases} cases, Kodak backgrounds (768 x 512), see the script's docstring.\n\n"
        + markdown_table(cols, table)
        + f"\nOccluded patches flagged (not valid) by measure_chart_patches: "
        f"{100 * float(np.mean(occ_flag)) if occ_flag else float('nan'):.0f} % "
        f"(mean over the {len(occ_flag)} detected cases with occlusion).\n"
        f"\nNo chart (the 24 Kodak photographs): detect_colorchecker median "
        f"{1000 * float(np.median(neg_times)):.0f} ms to refuse (a 768 x 512 photograph without "
        "a chart is searched twice: at full resolution, then 2x upsampled for tiny charts).\n"
        f"\n{big.shape[1]} x {big.shape[0]} uint8 photograph (case 0 upscaled 4x, bicubic): "
        f"detect_colorchecker median {1000 * float(np.median(times)):.0f} ms over 5 runs, "
        f"measure_chart_patches {1000 * float(np.median(mtimes)):.0f} ms; max centre error "
        f"{big_err:.3f} pitch.\n"
    )
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
