"""Folds against dense stain: what the tissue mask keeps and drops, and the stains after.

Run (once per source tree; ``--label`` names it in the table)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_fold.py \\
        DIR [DIR ...] [--label after] [--pen PEN_DIR]

Each ``DIR`` holds RGB images (png, jpeg, tif). Per image:

- **tissue kept**: of the pixels that ``tissue_mask(dark=False)`` keeps (glass and pen
  rules only; the hand-marked folds below left out), the share the default
  ``tissue_mask`` keeps. The dark rule is meant for black ink, folds and debris; on an image
  without them what it drops is stain.
- **folds removed**: of the hand-marked fold pixels, the share the default mask drops.
- **angle**: the worse of the two stain vectors (deg) between ``macenko_stains(mask="auto")``
  and ``macenko_stains`` on the reference mask (``tissue_mask(glass=False, dark=False,
  he="auto")``, the rules of ``mask="auto"`` but the dark rule, without the hand-marked
  folds and ink): what the dark rule changes in the stains, against the hand masks.

The hand-marked folds (``FOLDS``, made for this check; a straight fold across histolab's
``high-nuclei-score-red-pen-level1`` test tile, a tuning tile of the earlier checks, and
two slide thumbnails of
laurapurcaro-bit/FolDet, Apache-2.0, commit 2eb25201: ``Images/study 5.PNG`` saved as
``FolDet__study_5.png``, and the left panel of ``Images/CS_mod.PNG``, rows 45-700 and
columns 20-440, saved as ``FolDet__CS_orig.png``): boxes drawn by eye around each fold,
and in them the pixels darker than a luma threshold (the fold is the dark band in the
box). The red box and dotted line the figure draws over the second are left out of every
count (red pixels, dilated by 2).

``--pen DIR``: HistoQC's pen-marked thumbnails with their hand-drawn ink masks
(``<name>_mask.png``, as ``benchmarks/check_stain_artefacts.py``): the share of the ink
the default mask drops, and the tissue kept as above (the ink left out of it).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff"}
LUMA = np.array([0.2125, 0.7154, 0.0721])

#: Hand-marked folds: image stem -> (boxes (row0, row1, col0, col1), luma threshold).
FOLDS: dict[str, tuple[list[tuple[int, int, int, int]], float]] = {
    "FolDet__study_5": ([(215, 300, 190, 360), (418, 455, 335, 395), (365, 380, 283, 300)], 0.40),
    "FolDet__CS_orig": ([(148, 214, 63, 140)], 0.20),
    # a straight fold across a tuning tile taken as clean before (histolab's test image)
    "histolab_high-nuclei-score-red-pen-level1": (
        [
            (228, 274, 0, 64),
            (244, 288, 64, 128),
            (253, 300, 128, 192),
            (265, 312, 192, 256),
            (278, 330, 256, 320),
            (299, 347, 320, 384),
            (322, 364, 384, 448),
            (337, 383, 448, 512),
        ],
        0.20,
    ),
}


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _read_mask(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("L")) > 127


def _overlay(img8: np.ndarray) -> np.ndarray:
    """The figure's red drawing (pure red pixels, dilated by 2)."""
    from scipy import ndimage

    r, g, b = (img8[..., i].astype(int) for i in range(3))
    red = (r > 150) & (g < 90) & (b < 90) & (r - b > 100)
    return ndimage.binary_dilation(red, iterations=2) if red.any() else red


def _folds(name: str, img8: np.ndarray) -> np.ndarray:
    out = np.zeros(img8.shape[:2], dtype=bool)
    if name not in FOLDS:
        return out
    boxes, limit = FOLDS[name]
    luma = (img8 / 255.0) @ LUMA
    for r0, r1, c0, c1 in boxes:
        box = np.zeros_like(out)
        box[r0:r1, c0:c1] = True
        out |= box & (luma < limit)
    return out


def _angle(a: object, b: object) -> float:
    from imageform.analysis import stain_angle

    sa, sb = a.stain_matrix, b.stain_matrix  # type: ignore[attr-defined]
    return max(stain_angle(sa[i], sb[i]) for i in range(2))


def _pct(num: int, den: int) -> str:
    return "-" if den == 0 else f"{100.0 * num / den:.2f}%"


def _row(name: str, img8: np.ndarray, ink: np.ndarray | None) -> tuple[list[str], dict]:
    from imageform.analysis import macenko_stains, tissue_mask
    from imageform.errors import DegenerateConfigurationError

    skip = _overlay(img8)
    fold = _folds(name, img8) & ~skip
    bad = fold | skip | (ink if ink is not None else False)
    mask = tissue_mask(img8)
    ref = tissue_mask(img8, dark=False) & ~bad
    kept = int((mask & ref).sum())
    gone = int((fold & ~mask).sum())
    vals = {"kept": kept / max(int(ref.sum()), 1)}
    row = [name, f"{img8.shape[1]}x{img8.shape[0]}", _pct(kept, int(ref.sum()))]
    row.append(_pct(gone, int(fold.sum())))
    if ink is not None:
        row.append(_pct(int((ink & ~mask).sum()), int(ink.sum())))
    else:
        row.append("-")
    try:
        auto = macenko_stains(img8)
        ref_mask = tissue_mask(img8, glass=False, dark=False, he="auto") & ~bad
        truth = macenko_stains(img8, mask=ref_mask)
        vals["angle"] = _angle(auto, truth)
        row.append(f"{vals['angle']:.2f}")
    except DegenerateConfigurationError:
        row.append("refused")
    return row, vals


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", type=Path, nargs="+")
    ap.add_argument("--label", default="imageform")
    ap.add_argument("--pen", type=Path, default=None)
    args = ap.parse_args()
    print(header(f"Folds against dense stain ({args.label})"))
    cols = ["image", "size", "tissue kept", "folds removed", "ink removed", "angle (deg)"]
    for d in args.dirs:
        rows, kept, angles = [], [], []
        for p in sorted(d.iterdir()):
            if p.suffix.lower() not in SUFFIXES or p.stem.endswith("_mask"):
                continue
            row, vals = _row(p.stem, _read(p), None)
            rows.append(row)
            kept.append(vals["kept"])
            angles.extend([vals["angle"]] if "angle" in vals else [])
        print(f"\n### {d.name} ({args.label})\n")
        print(markdown_table(cols, rows))
        print(
            f"Tissue kept, worst / median: {100 * min(kept):.2f} / {100 * np.median(kept):.2f} %;"
            f" angle median / worst: {np.median(angles):.2f} / {max(angles):.2f} deg.\n"
        )
    if args.pen is not None:
        rows = []
        for p in sorted(args.pen.iterdir()):
            m = p.with_name(p.stem + "_mask.png")
            if p.suffix.lower() not in SUFFIXES or p.stem.endswith("_mask") or not m.exists():
                continue
            row, _ = _row(p.stem, _read(p), _read_mask(m))
            rows.append(row)
        print(f"\n### {args.pen.name}: hand-masked ink ({args.label})\n")
        print(markdown_table(cols, rows))


if __name__ == "__main__":
    main()
