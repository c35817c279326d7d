"""ColorChecker detection on folders of photographs, before and after a change: what changed.

Runs :func:`imageform.analysis.detect_colorchecker` (default settings) on every image of
the folders given (a grey photograph is repeated into three channels, an alpha channel
dropped) and saves, per image, whether a chart was found, its score, the centre of patch 1
and whether it was mirrored. ``--table A.json B.json`` prints, per folder, how many were
found before and after and every image whose answer changed.

The photographs of chart-shape-2026-12-03a come from public repositories, not this one
(none states a licence; nothing is committed): riskiest/color_calibration at 4ca105ce
(``imgs/*``: a ColorChecker Classic on a chair under an orange lamp, ``input1*``, with
the repository's copies under other casts, and a DGK 3 x 6 chart, not a Classic, on a towel,
a floor, a basket and a doormat, ``1*``-``4*``, ``aa1*``), crystaldust/opencv-mcc-cc-test
at 08f52b87 (``build/*.png``: a SpyderCHECKR 24, not a Classic, and a cartoon) and
alexandresoaresilva/auto_color_calibration at 4b8f0812 (a Classic held before a webcam,
most of them mirrored; grey-scale photographs of it; two phone photographs).

Run from the project root (``SRC`` the ``src`` folder of the code to run)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=SRC:. python benchmarks/check_chart_shape.py \
        --save X.json FOLDER [FOLDER ...]
    python benchmarks/check_chart_shape.py --table before.json after.json
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np


def _run(folders: list[Path]) -> dict[str, dict[str, object]]:
    from imageform.analysis import detect_colorchecker
    from imageform.io import read_image

    rows: dict[str, dict[str, object]] = {}
    for folder in folders:
        for f in sorted(p for p in folder.iterdir() if p.is_file()):
            try:
                im = np.asarray(read_image(f, alpha="drop"))
            except Exception as exc:  # a file that is no image is reported and left
                print(f"{f.name}: not read ({str(exc)[:60]})")
                continue
            im = im.reshape(im.shape[0], im.shape[1], -1)
            im = im[..., :3] if im.shape[-1] >= 3 else np.repeat(im[..., :1], 3, axis=2)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = detect_colorchecker(im)
            row = {
                "folder": folder.name,
                "found": bool(d.found),
                "score": round(float(d.score), 3) if d.found else None,
                "patch1": np.round(d.centers[0], 1).tolist() if d.found else None,
                "mirrored": bool(d.mirrored),
            }
            rows[f"{folder.name}/{f.name}"] = row
            print(f.name, row, flush=True)
    return rows


def _table(fa: Path, fb: Path) -> None:
    a, b = json.loads(fa.read_text()), json.loads(fb.read_text())
    keys = [k for k in a if k in b]
    print("| folder | photographs | found, before | found, after | answers changed |")
    print("|---|---|---|---|---|")
    for folder in dict.fromkeys(a[k]["folder"] for k in keys):
        ks = [k for k in keys if a[k]["folder"] == folder]
        n_changed = sum(a[k] != b[k] for k in ks)
        print(
            f"| {folder} | {len(ks)} | {sum(a[k]['found'] for k in ks)} "
            f"| {sum(b[k]['found'] for k in ks)} | {n_changed} |"
        )
    print("\n| photograph | before | after |\n|---|---|---|")
    for k in keys:
        if a[k] != b[k]:
            print(f"| {k} | {_say(a[k])} | {_say(b[k])} |")


def _say(row: dict[str, object]) -> str:
    if not row["found"]:
        return "not found"
    mirrored = ", mirrored" if row["mirrored"] else ""
    return f"found, R² {row['score']}, patch 1 at {row['patch1']}{mirrored}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folders", type=Path, nargs="*")
    ap.add_argument("--save", type=Path)
    ap.add_argument("--table", type=Path, nargs=2)
    args = ap.parse_args()
    if args.table:
        _table(*args.table)
        return
    rows = _run(args.folders)
    if args.save:
        args.save.write_text(json.dumps(rows))


if __name__ == "__main__":
    main()
