"""Stain vectors with pen marks, black ink and folds: tissue_mask against no mask, real ink.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_artefacts.py \\
        TILE_DIR PEN_DIR [--methods macenko,vahadane]

``TILE_DIR`` holds the clean real tiles of ``benchmarks/check_stain_real.py`` (not in the
repository; its docstring names their sources). ``PEN_DIR`` holds HistoQC's pen-marked slide
thumbnails with their hand-drawn ink masks (choosehappy/HistoQC, Clear BSD licence,
``histoqc/data/pen/1k_version/pen_green.png``, ``pen_black.png``, ``pen_red.png`` and their
``*_mask.png``, ``histoqc/data/models/pen_markings_he/pen_green.png`` and ``pen_red.png``
with their masks saved as ``small_pen_green.png``, ``small_pen_green_mask.png``,
``small_pen_red.png``, ``small_pen_red_mask.png``; commit b795612).

1. Detection on HistoQC's thumbnails: the share of the hand-masked ink that
   ``tissue_mask`` drops, and of the rest that the glass rule keeps that it keeps.
2. Stain vectors on HistoQC's two green-marked H&E thumbnails: the angle (worse of H and E)
   between the stains estimated without the annotated ink (the hand mask, the blue dot the
   annotator left out, and the brown margin dye and grey label strip by the H&E rules) and
   with every pixel (``mask=None``), ``mask="auto"`` or ``mask="he"``.
3. Real ink on clean tiles: ink transmittance sampled from HistoQC's hand-masked ink
   (green, blue - the blue dot of ``pen_green.png`` -, black and red, each pixel divided by
   the slide's glass), split at the median column of each stroke into a tune half (left)
   and a held-out half (right), multiplies a band across each clean tile (Beer-Lambert: ink over
   tissue), covering 0.5, 2 or 5 % of it; and a fold: a band where the tissue's OD is
   tripled. The stroke is at least 8 pixels wide, cut short to its coverage. The angle
   between the marked tile's stains (no mask, ``mask="auto"``) and the clean tile's, and
   with the mask also to the clean tile's without the band (the tissue under the ink is
   lost to any mask: the best a mask can do); the share of the band's pixels the mask
   drops (the ideal column for the first method only). Tiles are cut to at most 512 x 512
   (the centre) to keep Vahadane's run time down. The summary: median / worst / cases over
   3 deg per ink and half.
4. Clean tiles: the share of what the glass rule keeps that ``tissue_mask`` keeps, and the
   angle between the stains with ``mask="auto"`` and ``mask=None``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff"}
COVERAGES = (0.005, 0.02, 0.05)


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _read_mask(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("L")) > 0


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a[i], b[i]) for i in range(2))


def _stains(img: np.ndarray, method: str, mask: object) -> np.ndarray:
    from imageform.analysis import STAIN_VECTOR_METHODS

    return np.asarray(STAIN_VECTOR_METHODS[method](img, mask=mask).stain_matrix)


def _halves(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ink pixels split at the median column of the slide: (tune half, held-out half)."""
    keep = (t < 0.9).any(axis=1)  # the pale rim included, glass-coloured pixels not
    t, x = np.clip(t[keep], 0.0, 1.0), x[keep]
    mid = np.median(x)
    return t[x < mid], t[x >= mid]


def _ink(pen: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Transmittance of real ink pixels (hand-masked, divided by the slide's glass), split
    into the left (tune) and right (held-out) half of each stroke."""
    out = {}
    for name in ("pen_green", "pen_black", "pen_red"):
        img = _read(pen / f"{name}.png").astype(np.float64)
        m = _read_mask(pen / f"{name}_mask.png")
        glass = np.median(img[~m & (img.min(axis=-1) > 200)], axis=0)
        out[name.split("_")[1]] = _halves(img[m] / glass, np.nonzero(m)[1])
    img = _read(pen / "pen_green.png").astype(np.float64)
    crop = img[400:500, 120:230]  # the blue dot
    glass = np.median(img[img.min(axis=-1) > 200], axis=0)
    sel = crop[..., 2] > crop[..., 0] + 40
    cols = np.broadcast_to(np.arange(120, 230), crop.shape[:2])
    out["blue"] = _halves(crop[sel] / glass, cols[sel])
    return {k: out[k] for k in ("green", "blue", "black", "red")}


def _band(shape: tuple[int, int], frac: float, seed: int, width: float = 8.0) -> np.ndarray:
    """A slanted stroke covering ``frac`` of the tile, at least ``width`` pixels wide (a
    marker's stroke is 0.5-1 mm, wider at any magnification), cut short to ``frac``."""
    h, w = shape
    gen = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    ang = gen.uniform(0.2, 1.3)
    cx, cy = w * gen.uniform(0.3, 0.7), h * gen.uniform(0.3, 0.7)
    across = (xx - cx) * np.sin(ang) - (yy - cy) * np.cos(ang)
    along = (xx - cx) * np.cos(ang) + (yy - cy) * np.sin(ang)
    half = max(float(np.quantile(np.abs(across), frac)), width / 2)
    stroke = np.abs(across) <= half
    reach = np.quantile(np.abs(along[stroke]), min(frac * h * w / stroke.sum(), 1.0))
    return stroke & (np.abs(along) <= reach)


def _inked(img8: np.ndarray, band: np.ndarray, ink: np.ndarray, seed: int) -> np.ndarray:
    gen = np.random.default_rng(seed)
    t = ink[gen.integers(0, ink.shape[0], int(band.sum()))]
    out = img8.astype(np.float64)
    out[band] *= t
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def _folded(img8: np.ndarray, band: np.ndarray) -> np.ndarray:
    out = img8.astype(np.float64) / 240.0
    out[band] = np.minimum(out[band], 1.0) ** 3  # three layers of the same tissue
    return np.clip(np.round(out * 240.0), 0, 255).astype(np.uint8)


def _crop(img8: np.ndarray, size: int = 512) -> np.ndarray:
    h, w, _ = img8.shape
    y, x = max((h - size) // 2, 0), max((w - size) // 2, 0)
    return img8[y : y + size, x : x + size]


def main() -> None:
    from imageform.analysis import tissue_mask

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tiles", type=Path)
    ap.add_argument("pen", type=Path)
    ap.add_argument(
        "--methods", default="macenko,vahadane", help="stain estimators, comma-separated"
    )
    args = ap.parse_args()
    tiles = {
        p.stem: _crop(_read(p))
        for p in sorted(args.tiles.iterdir())
        if p.suffix.lower() in SUFFIXES
    }
    methods = tuple(args.methods.split(","))
    print(header("Stain vectors with pen marks, black ink and folds"))

    rows = []
    for name in ("pen_green", "small_pen_green", "pen_black", "pen_red", "small_pen_red"):
        thumb = _read(args.pen / f"{name}.png")
        hand = _read_mask(args.pen / f"{name}_mask.png")
        auto = tissue_mask(thumb)
        glass = tissue_mask(thumb, pen=False, dark=False)
        row = [name, f"{hand.mean():.1%}", f"{1 - auto[hand].mean():.1%}"]
        row.append(f"{auto[glass & ~hand].mean():.1%}")
        if name.endswith("pen_green"):
            ref_mask = ~hand & tissue_mask(thumb, glass=False, pen=False, dark=False, he=True)
            if name == "pen_green":
                ref_mask[400:500, 120:230] = False  # the blue dot, not in the hand mask
            for method in methods:
                best = _stains(thumb, method, ref_mask)
                for mask in (None, "auto", "he"):
                    row.append(f"{_angle(_stains(thumb, method, mask), best):.1f}")
        else:
            row += ["-"] * (3 * len(methods))
        rows.append(row)
    print("\n## HistoQC's pen-marked thumbnails (real ink, hand-drawn masks)\n")
    cols = [
        "thumbnail",
        "ink (hand mask)",
        "ink dropped by tissue_mask",
        "rest kept (of the glass rule's)",
        *(f"{m.capitalize()}: {k} (deg)" for m in methods for k in ("no mask", "auto", "he")),
    ]
    print(markdown_table(cols, rows))

    inks = _ink(args.pen)
    rows = []
    angles: dict[tuple[str, str], list[float]] = {}
    kinds = [
        (m, k, r)
        for i, m in enumerate(methods)
        for k, r in (("none", "clean"), ("auto", "clean"), ("auto", "ideal"))[: 3 - min(i, 1)]
    ]
    for name, img8 in tiles.items():
        clean = {m: _stains(img8, m, "none") for m in methods}
        for k, frac in enumerate(COVERAGES):
            band = _band(img8.shape[:2], frac, seed=k)
            ideal = {methods[0]: _stains(img8, methods[0], ~band)}
            cases = {
                f"{ink} {half}": _inked(img8, band, t[i], seed=k)
                for ink, t in inks.items()
                for i, half in enumerate(("tune", "held-out"))
            }
            cases["fold"] = _folded(img8, band)
            for case, marked in cases.items():
                keep = tissue_mask(marked, glass=False)
                row = [name, case, f"{frac:.1%}", f"{1 - keep[band].mean():.1%}"]
                for method, mask, which in kinds:
                    ref = ideal if which == "ideal" else clean
                    try:
                        a = _angle(_stains(marked, method, mask), ref[method])
                    except Exception as exc:  # a row, not a stop
                        row.append(type(exc).__name__)
                        continue
                    angles.setdefault((case, f"{method} {mask} {which}"), []).append(a)
                    row.append(f"{a:.2f}")
                rows.append(row)
    print("\n## Real ink and a fold on clean tiles (stain angle, deg)\n")
    summary = []
    for case in dict.fromkeys(r[1] for r in rows):
        line = [case]
        for m, use, ref_name in kinds:
            v = np.array(angles.get((case, f"{m} {use} {ref_name}"), [np.nan]))
            line.append(f"{np.median(v):.2f} / {v.max():.2f} / {int((v > 3).sum())} of {v.size}")
        summary.append(line)
    heads = {
        ("none", "clean"): "no mask, to the clean tile",
        ("auto", "clean"): "mask auto, to the clean tile",
        ("auto", "ideal"): "mask auto, to the clean tile without the band",
    }
    cols = ["artefact"] + [f"{m.capitalize()}: {heads[k, r]}" for m, k, r in kinds]
    print(
        "Median / worst / cases over 3 deg, over the tiles and the coverages (tune: ink "
        "from the left half of each hand-masked stroke, held-out: the right half):\n"
    )
    print(markdown_table(cols, summary))
    print()
    cols = ["tile", "artefact", "coverage", "band dropped by the mask"] + [
        f"{m.capitalize()}: {k}{' vs ideal' if r == 'ideal' else ''}" for m, k, r in kinds
    ]
    print(markdown_table(cols, rows))

    rows = []
    for name, p in sorted((p.stem, p) for p in args.tiles.iterdir() if p.suffix in SUFFIXES):
        img8 = _read(p)
        glass = tissue_mask(img8, pen=False, dark=False)
        kept = tissue_mask(img8)[glass].mean()
        moved = [_angle(_stains(img8, m, "auto"), _stains(img8, m, "none")) for m in methods]
        rows.append([name, f"{kept:.2%}", *(f"{v:.3f}" for v in moved)])
    print("\n## Clean tiles (whole): tissue kept, stains moved by the mask\n")
    cols = [
        "tile",
        "kept by tissue_mask, of the glass rule's",
        *(f"{m.capitalize()}: auto vs none (deg)" for m in methods),
    ]
    print(markdown_table(cols, rows))


if __name__ == "__main__":
    main()
