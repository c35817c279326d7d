"""The visible horizon on degraded photographs: haze, low contrast, dim, noise, blur, crops.

Run (once per source tree; ``--save`` keeps each photograph's answers, ``--table`` prints
the before/after tables from two such files)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_horizon_stress \\
        --data DIR --york YORK --split tune --save after-tune.json
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=/tmp/before/src:. python -m benchmarks.check_horizon_stress \\
        --data DIR --york YORK --split tune --save before-tune.json
    python -m benchmarks.check_horizon_stress --table before-tune.json after-tune.json

:func:`imageform.geometry.detect_horizon` on the photographs of
``check_horizon_natural.py``, each as it is and in the ten degraded versions of
``check_vp_stress.py`` (haze 1/5, contrast 1/20, dim 1/10, gamma 2.5, dim 1/8 + noise 2,
blur 2, noise 12, JPEG q20, crop 60 %, crop left 70 %; 8-bit, as a camera writes them):

- with a horizon: every ``--every``-th frame (sorted by name) of the Horizon-UAV clips of
  the split (``DIR/uav/images``, ``DIR/uav/label.csv``, as in ``check_horizon_natural.py``:
  JuroUhlar/etdh-horizon-detection @ 79c1905, even clips tuning, odd clips held out),
  scored against the annotated line (the larger distance at the left and right edges over
  the height, within 2 % of H); the crops move the line with them.
- Kodak's sea photographs (``../shared/data/kodak``; kodim06 and kodim12 tuning, kodim16
  held out; their hand-read truth is not in the repository): whether a degraded version
  gives the horizon the original gave (within 2 % of H; not for crops).
- without a horizon (a horizon found is a false one): every other York Urban photograph
  of the split (``YORK``: trocolit2/vanishing-point-detection @ d07ba01,
  ``resource/datasets/yorkurban/``; even-numbered tuning, odd held out: 0, 4, 8, ... and 1,
  5, 9, ...) and the Kodak images without a horizon of the split (``KODAK_NEG`` of
  ``check_horizon_natural.py``, every other one).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table
from benchmarks.check_horizon_natural import KODAK, KODAK_NEG, load, uav
from benchmarks.check_vp_stress import VERSIONS, version

KODAK_SEA = {"tune": ["06", "12"], "held": ["16"]}


def items(
    data: Path, york: Path, split: str, every: int
) -> list[tuple[str, Path, tuple[float, float] | None]]:
    """``(kind, path, truth rows)``: kind "uav", "kodak sea" (no truth) or "negative"."""
    out: list[tuple[str, Path, tuple[float, float] | None]] = []
    out += [("uav", p, t) for p, t, _ in uav(data, split)[::every]]
    out += [("kodak sea", KODAK / f"kodim{k}.png", None) for k in KODAK_SEA[split]]
    parity = 0 if split == "tune" else 1
    out += [("york", york / f"{k:03d}.jpg", None) for k in range(parity, 102, 4)]
    ks = KODAK_NEG[0::2] if split == "tune" else KODAK_NEG[1::2]
    out += [("kodak", KODAK / f"kodim{k}.png", None) for k in ks]
    return out


def measure(data: Path, york: Path, split: str, every: int) -> list[dict[str, Any]]:
    from imageform.geometry import detect_horizon

    recs: list[dict[str, Any]] = []
    its = items(data, york, split, every)
    for n, (kind, path, truth) in enumerate(its):
        rgb = load(path)
        for name in VERSIONS:
            arr, (x0, y0) = version(rgb, name, seed=n)
            t0 = time.perf_counter()
            res = detect_horizon(arr)
            dt = time.perf_counter() - t0
            rec: dict[str, Any] = {
                "kind": kind,
                "photo": path.name,
                "version": name,
                "size": [int(arr.shape[1]), int(arr.shape[0])],
                "rows": [float(r) for r in res.rows] if res.found else None,
                "reason": res.reason,
                "s": dt,
            }
            if truth is not None:
                w = rgb.shape[1]
                slope = (truth[1] - truth[0]) / (w - 1)
                left = truth[0] + slope * x0 - y0
                rec["truth"] = [left, left + slope * (arr.shape[1] - 1)]
            recs.append(rec)
        print(f"{n + 1}/{len(its)} {path.name}", flush=True)
    return recs


def _err(rows: list[float] | None, ref: list[float] | None, h: int) -> float:
    if ref is None:
        return float("nan")
    if rows is None:
        return float("inf")
    return 100.0 * max(abs(rows[0] - ref[0]), abs(rows[1] - ref[1])) / h


def tables(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> str:
    """The before/after tables of two ``--save`` files of the same photographs."""
    out = []
    rows = []
    for name in VERSIONS:
        cells: list[object] = [name]
        for recs in (before, after):
            u = [r for r in recs if r["kind"] == "uav" and r["version"] == name]
            e = [_err(r["rows"], r["truth"], r["size"][1]) for r in u]
            cells.append(f"{sum(x <= 2 for x in e)} / {sum(x < np.inf for x in e)} of {len(e)}")
        for recs in (before, after):
            base = {r["photo"]: r for r in recs if r["version"] == "original"}
            k = [r for r in recs if r["kind"] == "kodak sea" and r["version"] == name]
            if name.startswith("crop"):
                cells.append("-")
            else:
                same = sum(_err(r["rows"], base[r["photo"]]["rows"], r["size"][1]) <= 2 for r in k)
                found = sum(base[r["photo"]]["rows"] is not None for r in k)
                cells.append(f"{same} of {found}")
        for recs in (before, after):
            neg = [r for r in recs if r["kind"] in ("york", "kodak") and r["version"] == name]
            cells.append(f"{sum(r['rows'] is not None for r in neg)} of {len(neg)}")
        rows.append(tuple(cells))
    out.append(
        markdown_table(
            (
                "version",
                "UAV: within 2 % of H / found, before",
                "after",
                "Kodak sea: the original's horizon again, before",
                "after",
                "false horizons (York Urban + Kodak without one), before",
                "after",
            ),
            rows,
        )
    )
    fa = [
        f"{r['photo']} ({r['version']})"
        for r in after
        if r["kind"] in ("york", "kodak") and r["rows"] is not None
    ]
    out.append("False horizons, after: " + (", ".join(fa) or "none") + ".\n")
    b = {(r["photo"], r["version"]): r for r in before}
    changed = [r for r in after if r["rows"] != b[(r["photo"], r["version"])]["rows"]]
    orig = [r for r in changed if r["version"] == "original"]
    n_orig = sum(r["version"] == "original" for r in after)
    out.append(
        f"Answers (rows, exactly) changed: {len(orig)} of {n_orig} originals"
        + (" (" + ", ".join(r["photo"] for r in orig) + ")" if orig else "")
        + f"; {len(changed)} of {len(after)} calls in all.\n"
    )
    ta = {(r["photo"], r["version"]): r["s"] for r in after}
    ratio = [ta[k] / r["s"] for k, r in b.items() if r["s"] > 0]
    out.append(
        f"Time per call, after: median {1000 * np.median(list(ta.values())):.0f} ms; after / "
        f"before per call: median {np.median(ratio):.2f} (separate runs on a shared machine).\n"
    )
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("/tmp/horizon"))
    ap.add_argument("--york", type=Path, default=Path("/tmp/yorkurban"))
    ap.add_argument("--split", choices=("tune", "held"), default="tune")
    ap.add_argument("--every", type=int, default=6, help="every N-th UAV frame")
    ap.add_argument("--save", type=Path)
    ap.add_argument("--table", type=Path, nargs=2, metavar=("BEFORE", "AFTER"))
    args = ap.parse_args()
    if args.table is not None:
        before, after = (json.loads(p.read_text()) for p in args.table)
        print(header("The visible horizon on degraded photographs"))
        print(tables(before, after))
        return
    recs = measure(args.data, args.york, args.split, args.every)
    if args.save is not None:
        args.save.write_text(json.dumps(recs))
    print(tables(recs, recs))


if __name__ == "__main__":
    main()
