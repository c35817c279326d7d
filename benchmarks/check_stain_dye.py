"""Stain path: run time on a whole slide region; stains under an ink wash; margin dye vs DAB.

Three parts, each printing Markdown tables (see ``benchmarks/results/stain-dye-2026-11-30k.md``):

``--speed IMAGE --target TARGET``
    Run time of the Macenko stain path on one slide image (OpenSlide's CMU-1-Small-Region,
    an Aperio SVS of 2220 x 2967 pixels at 0.499 um): ``estimate_background`` on the
    image, ``macenko_stains`` (default mask), ``macenko_normalize`` with the stains given,
    and ``imageform stain-normalize IMAGE --target TARGET`` run in this process (reading,
    the mask on the sample with the file's pixel size, the estimate, the transform and
    writing a PNG). Medians of ``--repeat`` runs after a warm-up, in interleaved rounds of
    each ``--src`` (``name=path``: a source tree of imageform, each in a process of its own).

``--pairs DIR``
    smujiang/WSIPenMarkingRemoval's patch pairs (``*_clean.png`` / ``*_inked.png``, a
    blue wash over the whole inked scan): Macenko with ``mask="auto"`` on the inked scan
    against the clean scan (stain vector angles, the worse of the two, and the relative
    error of the two maximum concentrations), and the share of tissue kept.

``--ihc DIR`` / ``--he DIR``
    Tiles with DAB (Ki67) and H&E thumbnails: the default mask's share of the tissue kept
    and what it keeps of the margin dye (see ``check_stain_artefacts.py``).

Run from the repository root with ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:.``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _median_times(fns: dict[str, Any], repeat: int) -> dict[str, float]:
    """Median wall and CPU (this process's) seconds of each callable, after a warm-up."""
    out = {}
    for name, fn in fns.items():
        fn()  # warm-up
        ts, cs = [], []
        for _ in range(repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            ts.append(time.perf_counter() - t0)
            cs.append(time.process_time() - c0)
        out[name] = statistics.median(ts)
        out[f"{name} [CPU]"] = statistics.median(cs)
    return out


def _speed_child(image: str, target: str, repeat: int) -> None:
    """Print one JSON line of median seconds for the current imageform (``--speed-child``)."""
    import json

    from imageform import analysis
    from imageform.cli import main
    from imageform.io import read_image

    img = np.asarray(read_image(image), dtype=np.float32) / np.float32(255.0)
    tgt = analysis.macenko_stains(np.asarray(read_image(target)))
    src = analysis.macenko_stains(img)
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "out.png")
        argv = ["stain-normalize", image, "--target", target, "-o", out, "--force"]
        fns = {
            "estimate_background (whole image)": lambda: analysis.estimate_background(img),
            "macenko_stains (whole image, mask auto)": lambda: analysis.macenko_stains(img),
            "macenko_normalize (stains given)": lambda: analysis.macenko_normalize(
                img, tgt, source=src
            ),
            "imageform stain-normalize (in process)": lambda: main(argv),
        }
        devnull = open(os.devnull, "w")  # noqa: SIM115
        old = sys.stdout
        sys.stdout = devnull
        try:
            times = _median_times(fns, repeat)
        finally:
            sys.stdout = old
            devnull.close()
    print(json.dumps(times))


def _speed(args: argparse.Namespace) -> None:
    import json

    from benchmarks._common import header, markdown_table

    srcs = [s.split("=", 1) for s in args.src]
    runs: dict[str, list[dict[str, float]]] = {name: [] for name, _ in srcs}
    for _ in range(args.rounds):
        for name, path in srcs:
            env = {**os.environ, "PYTHONPATH": f"{path}:{Path(__file__).resolve().parents[1]}"}
            cmd = [sys.executable, __file__, "--speed-child", args.speed, "--target", args.target]
            cmd += ["--repeat", str(args.repeat)]
            res = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            runs[name].append(json.loads(res.stdout.strip().splitlines()[-1]))
    print(header("Stain path run time"))
    print()
    first = runs[srcs[0][0]][0]
    rows = []
    for part in first:
        row: list[Any] = [part]
        meds = []
        for name, _ in srcs:
            med = statistics.median(r[part] for r in runs[name])
            meds.append(med)
            row.append(f"{med:.3f}")
        row.append(f"{meds[0] / meds[-1]:.2f}x")
        rows.append(row)
    cols = ["part"] + [f"{name} (s)" for name, _ in srcs] + [f"{srcs[0][0]} / {srcs[-1][0]}"]
    print(markdown_table(cols, rows))
    print()
    print(
        f"Medians over {args.rounds} interleaved rounds of the per-round median of "
        f"{args.repeat} runs (after a warm-up); image {Path(args.speed).name}, target "
        f"{Path(args.target).name}. [CPU]: the process's CPU time (time.process_time), less "
        "sensitive than the wall time to other processes on a shared machine."
    )


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _angle(a: Any, b: Any) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a.stain_matrix[i], b.stain_matrix[i]) for i in range(2))


def _conc(a: Any, b: Any) -> float:
    """The larger relative error of the two maximum concentrations of ``a`` against ``b``."""
    ma, mb = np.asarray(a.max_concentrations), np.asarray(b.max_concentrations)
    return float(np.max(np.abs(ma / mb - 1.0)))


def _try(fn: Any) -> Any:
    from imageform.errors import DegenerateConfigurationError

    try:
        return fn()
    except DegenerateConfigurationError:
        return None


def _fmt(v: float | None, spec: str = ".2f") -> str:
    return "refused" if v is None else format(v, spec)


def _summary(vals: list[float | None], n: int) -> str:
    got = [v for v in vals if v is not None]
    if not got:
        return f"- (refused {n})"
    return (
        f"{np.median(got):.2f} / {np.percentile(got, 90):.2f} / {max(got):.2f} ({len(got)} of {n})"
    )


def _pairs(folder: Path, label: str) -> None:
    from benchmarks._common import header, markdown_table
    from imageform.analysis import _tissue_rules as rules
    from imageform.analysis import macenko_stains

    rows, a_auto, c_auto, a_none, c_none = [], [], [], [], []
    pairs = sorted(folder.glob("*_clean.png"))
    n = 0
    for cp in pairs:
        clean, inked = _read(cp), _read(Path(str(cp).replace("_clean", "_inked")))
        ref = _try(lambda c=clean: macenko_stains(c, mask="none"))
        if ref is None:
            rows.append([cp.name[:-10], "clean scan refused", "", "", "", ""])
            continue
        n += 1
        f = inked.astype(np.float32) / np.float32(255.0)
        from imageform.analysis import estimate_background

        i0 = estimate_background(f).i0
        od = rules._od(f, np.log(i0))
        hi = rules._bright_end(f)
        ink = rules._wash_ink(od, np.log(i0), rules._flags(f, od, dict(rules.DEFAULTS))["pen"], hi)
        dens = float(np.median(np.linalg.norm(od[ink], axis=1))) if ink.any() else float("nan")
        auto = _try(lambda x=inked: macenko_stains(x))
        none = _try(lambda x=inked: macenko_stains(x, mask="none"))
        aa = None if auto is None else _angle(auto, ref)
        ca = None if auto is None else _conc(auto, ref)
        an = None if none is None else _angle(none, ref)
        cn = None if none is None else _conc(none, ref)
        a_auto.append(aa)
        c_auto.append(ca)
        a_none.append(an)
        c_none.append(cn)
        rows.append([cp.name[:-10], f"{dens:.2f}", _fmt(aa), _fmt(ca), _fmt(an), _fmt(cn)])
    print(header(f"Stains under an ink wash ({folder.name}, {len(pairs)} pairs), {label}"))
    print()
    print(
        markdown_table(
            [
                "pairs (clean scan measured)",
                "Macenko auto: angle median / 90th pct / worst (deg)",
                "auto: max concentration error median / 90th / worst",
                "Macenko mask none: angle",
                "none: max concentration error",
            ],
            [
                [
                    f"{len(pairs)} ({n})",
                    _summary(a_auto, n),
                    _summary(c_auto, n),
                    _summary(a_none, n),
                    _summary(c_none, n),
                ]
            ],
        )
    )
    print()
    print(
        markdown_table(
            [
                "pair",
                "ink over glass: median OD norm",
                "auto: angle (deg)",
                "auto: conc. error",
                "none: angle (deg)",
                "none: conc. error",
            ],
            rows,
        )
    )
    print()


def _edge_dye(img: np.ndarray, reach: int, share: float) -> np.ndarray:
    """The candidate rule: regions of the H&E rule's colours (brown or grey) by the glass.

    Pixels brown (OD_B > 1.2 OD_G, OD_B >= 0.3) or grey (max/min OD <= 1.25, mean OD >=
    0.3) whose 8-connected region has at least ``share`` of its pixels within ``reach``
    pixels (4-connected) of glass (||OD|| < 0.15): dye along the tissue's cut edge.
    """
    from scipy import ndimage

    from imageform.analysis import _tissue_rules as rules
    from imageform.analysis import estimate_background

    f = img.astype(np.float32) / np.float32(255.0)
    od = rules._od(f, np.log(estimate_background(f).i0))
    r, g, b = od[..., 0], od[..., 1], od[..., 2]
    lo = np.maximum(np.minimum(np.minimum(r, g), b), 1e-6)
    hi = np.maximum(np.maximum(r, g), b)
    col = ((b > 1.2 * g) & (b >= 0.3)) | ((hi <= 1.25 * lo) & ((r + g + b) / 3 >= 0.3))
    near = ndimage.binary_dilation(r * r + g * g + b * b < 0.15**2, iterations=reach)
    lab, n = ndimage.label(col, np.ones((3, 3), bool))
    size = np.bincount(lab.ravel(), minlength=n + 1)
    ok = np.bincount(lab[near].ravel(), minlength=n + 1) >= share * size
    ok[0] = False
    return ok[lab]


def _od_stats(od: np.ndarray, sel: np.ndarray) -> list[str]:
    """10th / 50th / 90th percentiles: angle to Ruifrok's DAB, OD_R/OD_G, OD_B/OD_G, ||OD||."""
    dab = np.array([0.268, 0.570, 0.776])
    dab = dab / np.linalg.norm(dab)
    o = od[sel].astype(np.float64)
    n = np.linalg.norm(o, axis=1)
    ang = np.degrees(np.arccos(np.clip(o @ dab / np.maximum(n, 1e-9), -1.0, 1.0)))
    g = np.maximum(o[:, 1], 1e-6)
    return [
        " / ".join(f"{v:.{d}f}" for v in np.percentile(x, [10, 50, 90]))
        for x, d in ((ang, 1), (o[:, 0] / g, 2), (o[:, 2] / g, 2), (n, 2))
    ]


def _dye(pen: Path, tiles: Path, reach: int, share: float) -> None:
    """HistoQC's small_pen_green: the margin dye the default mask keeps, against DAB."""
    from benchmarks._common import header, markdown_table
    from imageform.analysis import _tissue_rules as rules
    from imageform.analysis import estimate_background, macenko_stains, tissue_mask

    def od_of(img: np.ndarray) -> np.ndarray:
        f = img.astype(np.float32) / np.float32(255.0)
        return rules._od(f, np.log(estimate_background(f).i0))

    print(header("Margin dye (HistoQC's small_pen_green) against DAB (Ki67 tiles)"))
    print()
    rows = []
    angles = []
    for name in ("small_pen_green", "pen_green"):
        th = _read(pen / f"{name}.png")
        from PIL import Image

        with Image.open(pen / f"{name}_mask.png") as im:
            hand = np.asarray(im)
        hand = (hand[..., 0] if hand.ndim == 3 else hand) > 0
        ref = ~hand & tissue_mask(th, glass=False, pen=False, dark=False, he=True)
        if name == "pen_green":
            ref[400:500, 120:230] = False  # the blue dot, not in the hand mask
        best = macenko_stains(th, mask=ref)
        auto = tissue_mask(th, glass=False)
        od = od_of(th)
        absorbing = np.linalg.norm(od, axis=-1) >= 0.15
        dye = auto & ~ref & absorbing
        if name == "small_pen_green":
            rows.append(
                [f"{name}: kept by auto, not by the reference", int(dye.sum()), *_od_stats(od, dye)]
            )
            rows.append(
                [
                    f"{name}: the reference's tissue",
                    int((ref & absorbing).sum()),
                    *_od_stats(od, ref & absorbing),
                ]
            )
        edge = _edge_dye(th, reach, share)
        angles.append(
            [
                name,
                f"{_angle(macenko_stains(th), best):.1f}",
                f"{_angle(macenko_stains(th, mask=auto & ~edge), best):.1f}",
            ]
        )
    kept = []
    he_rows = []
    for p in sorted(tiles.iterdir()):
        if not p.name.startswith(("deepliif", "qupath")):
            he_rows.append(_he_row(p))
            continue
        img = _read(p)
        od = od_of(img)
        brown = (od[..., 2] > 1.2 * od[..., 1]) & (od[..., 2] >= 0.3)
        rows.append([f"{p.stem}: DAB (brown)", int(brown.sum()), *_od_stats(od, brown)])
        truth = tissue_mask(img, pen=False, dark=False)
        m = tissue_mask(img)
        edge = _edge_dye(img, reach, share)
        kept.append([p.stem, f"{m[truth].mean():.1%}", f"{(m & ~edge)[truth].mean():.1%}"])
    cols = [
        "pixels",
        "n",
        "angle to DAB (deg) 10/50/90",
        "OD_R/OD_G",
        "OD_B/OD_G",
        "OD norm",
    ]
    print(markdown_table(cols, rows))
    print()
    print(
        f"Candidate rule: brown or grey regions with >= {share:.0%} of their pixels "
        f"within {reach} px of glass dropped."
    )
    print()
    print(
        markdown_table(["thumbnail", "Macenko auto (deg)", "auto without edge dye (deg)"], angles)
    )
    print()
    print(markdown_table(["Ki67 tile", "kept, auto", "kept, auto without edge dye"], kept))
    print()
    cols = [
        "tile",
        "eosin's pink (of the absorbing pixels)",
        "tissue_mask(he=False): H / E to the reference (deg)",
        "he='auto': H / E (deg)",
        "he='auto' kept (of he=False's)",
    ]
    print(markdown_table(cols, he_rows))
    print()


def _he_row(p: Path) -> list[str]:
    """A tile without DAB: its eosin share, Macenko's H and E against Macenko's reference
    vectors with the mask without and with ``he="auto"`` ("-" where the code has none).
    """
    from imageform.analysis import _tissue_rules as rules
    from imageform.analysis import macenko_stains, stain_angle, tissue_mask
    from imageform.analysis.synthetic import (
        MACENKO_REFERENCE_EOSIN,
        MACENKO_REFERENCE_HEMATOXYLIN,
    )
    from imageform.errors import InvalidInputError

    img = _read(p)
    f = img.astype(np.float32) / np.float32(255.0)
    from imageform.analysis import estimate_background

    od = rules._od(f, np.log(estimate_background(f).i0))
    r, g, b = od[..., 0], od[..., 1], od[..., 2]
    ab = r * r + g * g + b * b >= 0.15**2
    pink = ab & (r < 0.5 * g) & (b < 0.8 * g)

    def he_angles(mask: np.ndarray) -> str:
        st = _try(lambda: macenko_stains(img, mask=mask))
        if st is None:
            return "refused"
        s = np.asarray(st.stain_matrix)
        h = stain_angle(s[0], MACENKO_REFERENCE_HEMATOXYLIN)
        e = stain_angle(s[1], MACENKO_REFERENCE_EOSIN)
        return f"{h:.1f} / {e:.1f}"

    off = tissue_mask(img, glass=False)
    row = [p.stem, f"{pink.sum() / max(int(ab.sum()), 1):.1%}", he_angles(off)]
    try:
        on = tissue_mask(img, glass=False, he="auto")
    except InvalidInputError:
        return [*row, "-", "-"]
    return [*row, he_angles(on), f"{(on & off).sum() / max(int(off.sum()), 1):.2%}"]


def _heldout(folder: Path, label: str) -> None:
    """Fresh images: a wash or not, the default mask's tissue kept, Macenko's stains."""
    from benchmarks._common import header, markdown_table
    from imageform.analysis import macenko_stains, tissue_mask

    print(header(f"Held-out images ({folder.name}), {label}"))
    print()
    rows = []
    for p in sorted(folder.iterdir()):
        img = _read(p)
        from imageform.analysis import _tissue_rules as rules
        from imageform.analysis import estimate_background

        f = img.astype(np.float32) / np.float32(255.0)
        washed = rules._washed(rules._bright_end(f), np.log(estimate_background(f).i0))
        truth = tissue_mask(img, pen=False, dark=False)
        kept = tissue_mask(img)[truth].mean()
        st = _try(lambda x=img: macenko_stains(x))
        sm = "refused" if st is None else str(np.round(np.asarray(st.stain_matrix), 4).tolist())
        mc = "" if st is None else str(np.round(np.asarray(st.max_concentrations), 4).tolist())
        rows.append([p.name, "yes" if washed else "no", f"{kept:.2%}", sm, mc])
    cols = ["image", "wash", "tissue kept", "Macenko auto: stain matrix", "max concentrations"]
    print(markdown_table(cols, rows))
    print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--speed", help="slide image to time the stain path on")
    ap.add_argument("--speed-child", help=argparse.SUPPRESS)
    ap.add_argument("--target", help="target image for --speed")
    ap.add_argument("--src", action="append", default=[], help="name=path of a source tree")
    ap.add_argument("--pairs", type=Path, help="folder of *_clean.png / *_inked.png pairs")
    ap.add_argument("--label", default="after", help="what the run is (after, main...)")
    ap.add_argument("--dye", type=Path, help="HistoQC's pen folder (small_pen_green.png ...)")
    ap.add_argument("--tiles", type=Path, help="tuning tiles with the Ki67 ones, for --dye")
    ap.add_argument("--reach", type=int, default=3, help="--dye: the candidate's reach (px)")
    ap.add_argument("--share", type=float, default=0.8, help="--dye: the candidate's share")
    ap.add_argument("--heldout", type=Path, help="folder of fresh images")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    if args.speed_child:
        _speed_child(args.speed_child, args.target, args.repeat)
        return
    if args.pairs:
        _pairs(args.pairs, args.label)
    if args.dye:
        _dye(args.dye, args.tiles, args.reach, args.share)
    if args.heldout:
        _heldout(args.heldout, args.label)
    if args.speed:
        if not args.src:
            args.src = ["after=src"]
        _speed(args)


if __name__ == "__main__":
    main()
