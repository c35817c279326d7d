"""ColorChecker detection's time, before and after a change, with the answers compared.

Runs :func:`imageform.analysis.detect_colorchecker` (default settings) on:

- the 24 Kodak photographs (``../shared/data/kodak``: no chart; every lattice of flat
  regions in them is searched, as printed and mirrored: the slow case);
- ``--cases`` rendered charts composited into them (tests/analysis/chart_cases.py: random
  perspective, rotation, size, cast, shading, blur, noise, JPEG, some patches occluded);
- the real photographs of ``tests/data/chart-real`` (charts with glare, a shadow, a
  Passport), and each of them under a strong light with a camera's highlight shoulder
  (linear light times (1, 0.55, 0.22), then ``1 - exp(-2 x)`` after scaling its 99.5th
  percentile to 0.9: a tungsten lamp on a camera without white balance).

and saves, per image, whether a chart was found, its score, patch centres, outliers and
reason, and the time (``time.thread_time``, the best of ``--repeat`` calls). ``--table A.json
B.json`` prints the comparison: how many answers changed (found, score to 1e-9, centres to
1e-6 px) and the time per group (median and sum), B over A.

Run from the project root (``SRC`` is the ``src`` folder of the code to time)::

    OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=1 PYTHONPATH=SRC:. python \
        benchmarks/check_chart_speed.py --save X.json [--cases 40] [--repeat 1]
    python benchmarks/check_chart_speed.py --table before.json after.json
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
REAL = ROOT / "tests" / "data" / "chart-real"


def _tungsten(img: np.ndarray) -> np.ndarray:
    from imageform._colormath import srgb_decode, srgb_encode

    lin = srgb_decode(np, img.astype(np.float64) / 255.0) * np.array([1.0, 0.55, 0.22])
    lin = lin / np.percentile(lin.max(axis=2), 99.5) * 0.9
    lin = 1.0 - np.exp(-2.0 * lin)
    return np.asarray(np.round(srgb_encode(np, np.clip(lin, 0, 1)) * 255), dtype=np.uint8)


def _images(n_cases: int) -> list[tuple[str, str, np.ndarray]]:
    from imageform.io import read_image
    from tests.analysis.chart_cases import chart_case, kodak_images

    kodak = kodak_images(DATA)
    out = [
        ("kodak, no chart", f"kodim{i + 1:02d}", np.round(k * 255).astype(np.uint8))
        for i, k in enumerate(kodak)
    ]
    out += [("rendered chart", f"case{s:03d}", chart_case(kodak, s).image) for s in range(n_cases)]
    for f in sorted(REAL.glob("*.jpg")):
        im = np.asarray(read_image(f))[..., :3]
        im = im if im.dtype == np.uint8 else np.round(np.asarray(im) * 255).astype(np.uint8)
        out.append(("real chart", f.stem, im))
        out.append(("real chart, tungsten + shoulder", f.stem, _tungsten(im)))
    return out


def _run(n_cases: int, repeat: int) -> list[dict[str, object]]:
    from imageform.analysis import detect_colorchecker

    rows = []
    for group, name, img in _images(n_cases):
        best = np.inf
        for _ in range(repeat):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t = time.thread_time()
                d = detect_colorchecker(img)
                best = min(best, time.thread_time() - t)
        rows.append(
            {
                "group": group,
                "name": name,
                "found": bool(d.found),
                "score": float(d.score),
                "centers": np.asarray(d.centers, np.float64).tolist(),
                "reason": d.reason,
                "mirrored": bool(d.mirrored),
                "seconds": best,
            }
        )
        print(f"{group:32s} {name:28s} {d.found!s:5s} {best:6.2f} s {d.reason[:60]}", flush=True)
    return rows


def _same(a: dict[str, object], b: dict[str, object]) -> bool:
    if a["found"] != b["found"] or a["mirrored"] != b["mirrored"]:
        return False
    if not a["found"]:
        return a["reason"] == b["reason"]
    ca, cb = np.asarray(a["centers"]), np.asarray(b["centers"])
    return bool(
        abs(float(a["score"]) - float(b["score"])) < 1e-9 and np.allclose(ca, cb, atol=1e-6)  # type: ignore[arg-type]
    )


def _table(fa: Path, fb: Path) -> None:
    a, b = json.loads(fa.read_text()), json.loads(fb.read_text())
    ra = {(r["group"], r["name"]): r for r in a["rows"]}
    rb = {(r["group"], r["name"]): r for r in b["rows"]}
    keys = [k for k in ra if k in rb]
    print(f"before: {a['meta']}\n\nafter: {b['meta']}\n")
    print(
        "| images | n | found, before | found, after | answers changed "
        "| s / image before (median) | after | after / before, sum |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for group in dict.fromkeys(k[0] for k in keys):
        ks = [k for k in keys if k[0] == group]
        ta = np.array([ra[k]["seconds"] for k in ks])
        tb = np.array([rb[k]["seconds"] for k in ks])
        changed = [k[1] for k in ks if not _same(ra[k], rb[k])]
        print(
            f"| {group} | {len(ks)} | {sum(ra[k]['found'] for k in ks)} "
            f"| {sum(rb[k]['found'] for k in ks)} | {len(changed)}"
            f"{' (' + ', '.join(changed) + ')' if changed else ''} "
            f"| {np.median(ta):.2f} | {np.median(tb):.2f} | {tb.sum() / ta.sum():.2f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--save", type=Path)
    ap.add_argument("--table", type=Path, nargs=2)
    args = ap.parse_args()
    if args.table:
        _table(*args.table)
        return
    sys.path.insert(0, str(ROOT))
    import imageform

    rows = _run(args.cases, args.repeat)
    meta = (
        f"imageform from {Path(imageform.__file__).parent}; Python {platform.python_version()}, "
        f"NumPy {np.__version__}; {platform.machine()}; thread time, best of {args.repeat}"
    )
    if args.save:
        args.save.write_text(json.dumps({"meta": meta, "rows": rows}))


if __name__ == "__main__":
    main()
