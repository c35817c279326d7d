"""The default tissue mask across image sizes: ink-marked pairs, IHC tiles, run time.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_scale.py \\
        TILE_DIR [--time TILE]

``TILE_DIR`` holds real tiles (PNG, JPEG or TIFF; none is in the repository):

- ``*_clean.png`` / ``*_inked.png`` pairs: the same tissue scanned before and after it was
  marked with ink (the inked tile's ink covers it). Per pair: the share of the clean tile's
  tissue (the glass rule's, ``tissue_mask(image, pen=False, dark=False)``) that the default
  ``tissue_mask`` keeps, the share of the inked tile it drops, and the worst angle between
  Macenko's stain vectors of the inked tile (``mask="none"``, ``mask="auto"``) and the clean
  tile's (``mask="none"``), each at its own I0 (the two scans' glass differ).
- other tiles: as ``benchmarks/check_stain_ihc_fresh.py`` (tissue kept, Macenko against
  torchstain 1.4.1 with and without the mask).

``--time TILE``: the median of 15 runs of ``tissue_mask(TILE)`` after one warm-up (ms).

``--levels TARGET``: Macenko normalisation of each image of ``TILE_DIR`` at several pixel
sizes against ``TARGET`` (a dense tile at full resolution), with the concentrations matched
by their 99th percentile (``reference="max"``) or their mean (``"mean"``). Each image is
area-averaged 2, 4 and 8 times (a slide's pyramid levels; an Aperio SVS also at its
scanner-made thumbnail, the second page). Per level: the CIEDE2000 between the mean tissue
colour (CIELAB, over ``tissue_mask``) of the output and of the full-resolution output, and
to the target's mean tissue colour. The same slide should come out the same at any level.

The held-out set of ``benchmarks/results/stain-scale-2026-11-30h.md`` (two repositories
nobody here used, their SHA-256 written down before anything ran on them, run once with
the final code and once with main's):

- smujiang/WSIPenMarkingRemoval (MIT), commit 8451813b, ``img_samples/``: every 7th of the
  56 ``7470963d..._pairs.jpg`` files in name order (8 files; 512 x 256, H&E, the clean scan
  left and the ink-marked scan right), cut into ``inkpair_<x>_<y>_clean.png`` and
  ``_inked.png``;
- wdoron/TissueAnalysis (no licence stated: used here, not copied), commit 21e14878,
  ``Example/analyisis/image.jpg`` (4096 x 4096 IHC, hematoxylin + DAB): whole
  (``wdihc_whole.png``) and four 512 x 512 tiles at rows 1536 and 2560, columns 2560 and
  3072 (``wdihc_r<row>c<col>.png``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table
from benchmarks.check_stain_ihc_fresh import FAMILIES, SUFFIXES, _read, _row

FAMILIES.setdefault("wdihc_", "IHC DAB")


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a[i], b[i]) for i in range(2))


def _pair(stem: str, clean: np.ndarray, inked: np.ndarray) -> list[str]:
    from imageform.analysis import macenko_stains, tissue_mask

    truth = tissue_mask(clean, pen=False, dark=False)
    kept = float((tissue_mask(clean) & truth).sum()) / max(int(truth.sum()), 1)
    dropped = 1.0 - float(tissue_mask(inked).mean())
    row = [stem, f"{100 * kept:.1f}%", f"{100 * dropped:.1f}%"]
    try:
        ref = macenko_stains(clean, mask="none").stain_matrix
    except Exception as exc:  # a row, not a stop
        return [*row, type(exc).__name__, "-"]
    for mask in ("none", "auto"):
        try:
            stains = macenko_stains(inked, mask=mask).stain_matrix
            row.append(f"{_angle(stains, ref):.2f}")
        except Exception as exc:  # a row, not a stop
            row.append(type(exc).__name__)
    return row


def _timing(path: Path) -> float:
    from imageform.analysis import tissue_mask

    img = _read(path)
    tissue_mask(img)
    runs = []
    for _ in range(15):
        t = time.perf_counter()
        tissue_mask(img)
        runs.append(time.perf_counter() - t)
    return 1e3 * float(np.median(runs))


def _down(img: np.ndarray, k: int) -> np.ndarray:
    """Area average of k x k pixels (in the encoded values, as a slide's pyramid)."""
    if k == 1:
        return img
    h, w = img.shape[0] // k, img.shape[1] // k
    blocks = img[: h * k, : w * k].astype(np.float64).reshape(h, k, w, k, 3)
    return np.round(blocks.mean(axis=(1, 3))).astype(np.uint8)


def _levels_of(path: Path) -> list[tuple[str, np.ndarray]]:
    if path.suffix.lower() == ".svs":
        import tifffile

        with tifffile.TiffFile(path) as tif:
            base, thumb = tif.pages[0].asarray(), tif.pages[1].asarray()
        levels = [(f"1/{k}", _down(base, k)) for k in (1, 2, 4, 8)]
        ratio = base.shape[1] / thumb.shape[1]
        return [*levels, (f"thumbnail 1/{ratio:.2f}", thumb)]
    img = _read(path)
    return [(f"1/{k}", _down(img, k)) for k in (1, 2, 4, 8)]


def _levels(paths: list[Path], target_path: Path) -> list[list[str]]:
    from imageform.analysis import macenko_normalize, macenko_stains, tissue_mask
    from imageform.color import delta_e_ciede2000, srgb8_to_lab

    def mean_lab(img8: np.ndarray, mask: np.ndarray) -> np.ndarray:
        return np.asarray(srgb8_to_lab(img8), dtype=np.float64)[mask].mean(axis=0)

    target = _read(target_path)
    tgt = macenko_stains(target)
    t_lab = mean_lab(target, tissue_mask(target))
    rows = []
    for p in paths:
        first: dict[str, np.ndarray] = {}
        for name, img in _levels_of(p):
            h, w, _ = img.shape
            row = [p.stem, name, f"{w}x{h}"]
            try:
                st = macenko_stains(img)
                mask = tissue_mask(img)
                row.append(f"{st.max_concentrations[0]:.2f} / {st.mean_concentrations[0]:.2f}")
                for ref in ("max", "mean"):
                    out = macenko_normalize(img, tgt, source=st, reference=ref)
                    out8 = np.clip(np.round(np.asarray(out) * 255), 0, 255).astype(np.uint8)
                    lab = mean_lab(out8, mask)
                    first.setdefault(ref, lab)
                    d0 = float(delta_e_ciede2000(lab, first[ref]))
                    row.append(f"{d0:.1f} / {float(delta_e_ciede2000(lab, t_lab)):.1f}")
            except Exception as exc:  # a row, not a stop
                row.append(f"{type(exc).__name__}: {exc}"[:80])
            rows.append(row)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tiles", type=Path)
    ap.add_argument("--time", type=Path, default=None)
    ap.add_argument("--levels", type=Path, default=None, metavar="TARGET")
    args = ap.parse_args()
    print(header("The default tissue mask across image sizes"))
    if args.levels is not None:
        files = sorted(p for p in args.tiles.iterdir() if p.suffix.lower() in {*SUFFIXES, ".svs"})
        cols = [
            "image",
            "level",
            "size",
            "hematoxylin: 99th percentile / mean",
            "reference max: dE00 to level 1/1's output / to target",
            "reference mean: dE00 to level 1/1's output / to target",
        ]
        print(f"\n## Pyramid levels ({args.tiles.name}) against {args.levels.name}\n")
        print(markdown_table(cols, _levels(files, args.levels)))
        return
    if args.time is not None:
        print(f"\ntissue_mask({args.time.name}): median of 15 runs {_timing(args.time):.1f} ms\n")
        return
    files = sorted(p for p in args.tiles.iterdir() if p.suffix.lower() in SUFFIXES)
    pairs = [p for p in files if p.stem.endswith("_clean")]
    rows = []
    for p in pairs:
        inked = p.with_name(p.name.replace("_clean", "_inked"))
        rows.append(_pair(p.stem[: -len("_clean")], _read(p), _read(inked)))
    if rows:
        cols = [
            "pair",
            "clean tile: tissue kept",
            "inked tile: dropped",
            "Macenko, inked vs clean: mask none (deg)",
            "mask auto (deg)",
        ]
        print(f"\n## Ink-marked pairs ({args.tiles.name})\n")
        print(markdown_table(cols, rows))
    rest = [p for p in files if not p.stem.endswith(("_clean", "_inked"))]
    if rest:
        cols = [
            "tile",
            "stain",
            "size",
            "I0 (of 255), from",
            "kept by tissue_mask (of the glass rule's tissue)",
            "kept, pen rule alone",
            "kept, dark rule alone",
            "Macenko to torchstain, I0 240, mask none (deg)",
            "same, mask auto (deg)",
        ]
        print(f"\n## Tiles ({args.tiles.name})\n")
        print(markdown_table(cols, [_row(p.stem, _read(p))[0] for p in rest]))


if __name__ == "__main__":
    main()
