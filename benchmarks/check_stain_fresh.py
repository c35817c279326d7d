"""Stain separation and normalisation on a fresh set of real tiles: torchstain, H&E angles, output.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_fresh.py TILE_DIR \\
        [--target PATH] [--png DIR] [--cli]
    # Vahadane's convergence and stability (SPAMS' columns where spams-bin is importable)
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_fresh.py \\
        tests/data/stain --vahadane

``TILE_DIR`` holds real tiles (PNG, JPEG or TIFF, RGB or RGBA). None of them is in the
repository, and none comes from the repositories of ``check_stain_real.py`` and
``check_stain_artefacts.py`` (torchstain, HEnorm_python, StainTools, TIAToolbox, HistoQC,
scikit-image). They were split by repository, before anything was run on them, into a
tuning half and a held-out half; the held-out half was run once, with the final code.

Tuning half (22 tiles, ``/tmp/stainfresh/tune``):

- histolab/histolab (Apache-2.0), commit 202a8bca: ``tests/fixtures/tiles/``
  ``high-nuclei-score-level0``, ``medium-nuclei-score-level0``, ``low-nuclei-score-level0``
  (fat), ``very-low-nuclei-score-level0`` (pale eosin only), ``tissue-level0-4302-10273-4814-
  10785``, ``tissue-level2-1784-6289-5880-10386``, ``tissue-level2-4640-4649-8736-8746``,
  ``medium-nuclei-score-green-pen-level1`` (green ink), ``high-nuclei-score-red-pen-level1``
  (red ink, a fold), ``almost-white-2`` (glass, a sliver of tissue), ``high-nuclei-score-
  level2`` (tissue edge, glass) (all ``.png``); ``tests/fixtures/pil-images-rgb/
  tcga-lung-rgb.png`` (the target) and ``diagnostic-slide-thumb-rgb.png`` (a slide
  thumbnail ringed in red, green and black ink); TCGA H&E;
- nadeemlab/DeepLIIF (Apache-2.0 with the Commons Clause), commit eab8bddd:
  ``Datasets/Sample_Dataset/test_cli/22_2.png``, ``34_3``, ``6_2``, ``799_2`` and the left
  halves (512 x 512) of ``test_cli_input2_noseg/Bladder1.png`` and ``Lung1.png``: Ki67 IHC
  (hematoxylin + DAB);
- khtao/StainNet (no licence file), ``assets/3_color_net_neg23570_ori.png`` and
  ``_target.png`` (commit 94c20b31; cervical cytology, two scanners) and ``source.jpg``
  (commit 48209b35; an H&E JPEG, 256 x 256).

Held-out half (15 tiles, ``/tmp/stainfresh/heldout``, SHA-256 frozen before the first run):

- deroneriksson/python-wsi-preprocessing (Apache-2.0), commit c82dcaff,
  ``docs/wsi-preprocessing-in-python/images/``: ``TUPAC-TR-002-tile-r34-c34-x33793-y33799-
  w1024-h1024.png`` (4d98ed87...), ``TUPAC-TR-002-tile-r35-c37-x36865-y34823-w1024-h1024.png``
  (2ab15897...), slide thumbnails with glass ``pink-and-purple-slide.png`` (fb166983...),
  ``purple-slide.png`` (a3cf7811...), ``424-rgb.png`` (c8f7f636...), ``21-rgb.png`` (pale;
  f76c7ed7...), ``498-rgb.png`` (dd52d3c3...), ``127-rgb.png`` (a label strip; 74c9408f...);
- jnkather/ColorDeconvolutionMatlab (MIT), commit 43622984: ``Tumor_CD31_HiRes.png``
  (4ffe8bc1...) and ``Tumor_CD31_LoRes.png`` (8448f972...): CD31 IHC (hematoxylin + DAB);
- DigitalSlideArchive/HistomicsTK (Apache-2.0), commit 1ebc3109:
  ``docs/examples/example_data/L1.png`` (837ffc99...);
- xtarx/StainGAN (no licence file), branch gh-pages, commit 86c84f69: ``img/
  BAS_unnormalized_A.jpg`` (b851b3cd...), ``_B.jpg`` (e972fbf8...), ``_C.jpg``
  (ebb04927...), ``FAN_HoEoTp_A.jpg`` (1676a2dd...): JPEG mosaics of tiles from several
  scanners and stainings.

A second held-out set, for ``benchmarks/results/stain-ihc-2026-11-30e.md`` (6 Ki67 IHC
tiles, ``/tmp/stainihc/ihc_heldout``, SHA-256 frozen before the first run): 512 x 512 crops
on the diagonal of petebankhead/2022-qupath-cell-detection (commit 4632a17d; OpenSlide's
freely distributable test slide OS-2, no licence file in the repository)
``images/OS-2-ndpi.ome.tif`` (rows/columns k = 0-3: 4d5c76c4..., 93281091..., e4c8818e...,
13304a8a...) and ``images/OS-2-vsi.ome.tif`` (k = 0-1: d050b8e8..., 18b77855...).

Per tile, with imageform's defaults (``mask="auto"``, ``i0="auto"``): the I0 it estimates
and whether from glass; the share of the glass rule's tissue that ``tissue_mask`` keeps;
the worst angle between imageform's and torchstain 1.4.1's stain vectors at the same I0 =
240/255, with ``mask="none"`` (the algorithm alone), with the default mask and with
``tissue_mask(dark=False)`` (the pen rule alone: IHC's dense DAB is the dark rule's); the angle
of the first and second vector to the usual references (hematoxylin and eosin of
Macenko's reference code, DAB of Ruifrok and Johnston for IHC tiles); the share of
tissue pixels with a concentration below -0.1 (ln OD units); the normalised tile's mean
colour over its tissue to the target's (CIEDE2000 of the mean L*a*b*, imageform and
torchstain with Io = 240, alpha = 1, beta = 0.15; before: the tile itself); the mean
CIEDE2000 between the two normalised tiles; what comes out wrong: NaN, pixels above 1 in
any channel (negative concentrations: brighter than the target's glass, clipped to white
when written; torchstain clips them), tissue pixels that turn green or
blue (the pen rule's flags of the output that the input does not have: a stain vector
fitted to the wrong colours renders tissue in a colour no H&E has); Vahadane's angle to
Macenko's vectors; the angle between the tile's stain vectors and those of the tile
JPEG-compressed at quality 75. ``--png DIR`` writes, per tile, the tile, its tissue mask
(artefacts red, glass dark), imageform's and torchstain's normalised tiles side by side.
``--cli`` also runs ``imageform stain-normalize`` and ``imageform chunked stain-normalize``
on the first three tiles and reports the largest difference to the API's output.
"""

from __future__ import annotations

import argparse
import io
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff"}

#: Macenko's reference hematoxylin and eosin (HEnorm_python's HERef), Ruifrok's DAB.
REF_H = np.array([0.5626, 0.7201, 0.4062])
REF_E = np.array([0.2159, 0.8012, 0.5581])
REF_DAB = np.array([0.268, 0.570, 0.776])

#: Tiles whose second stain is DAB (hematoxylin + DAB IHC), by file-name prefix.
IHC = ("deepliif_", "kather_")


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _jpeg(img8: np.ndarray, quality: int = 75) -> np.ndarray:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img8).save(buf, "JPEG", quality=quality)
    buf.seek(0)
    with Image.open(buf) as im:
        return np.asarray(im.convert("RGB"))


def _u8(x: np.ndarray) -> np.ndarray:
    return np.clip(np.round(np.asarray(x, dtype=np.float64) * 255), 0, 255).astype(np.uint8)


def _lab(img8: np.ndarray) -> np.ndarray:
    from imageform.color import srgb8_to_lab

    return np.asarray(srgb8_to_lab(img8), dtype=np.float64)


def _de_mean(lab_a: np.ndarray, lab_b: np.ndarray) -> float:
    from imageform.color import delta_e_ciede2000

    return float(delta_e_ciede2000(lab_a, lab_b))


def _de_pixels(a8: np.ndarray, b8: np.ndarray) -> float:
    from imageform.color import delta_e_ciede2000

    return float(np.mean(delta_e_ciede2000(_lab(a8), _lab(b8))))


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a[i], b[i]) for i in range(2))


def _pen_flags(img8: np.ndarray, i0: np.ndarray) -> np.ndarray:
    """Green or blue pixels (the pen rule's per-pixel flags, no morphology)."""
    od = np.log(i0) - np.log(np.maximum(img8 / 255.0, 1 / 255))
    r, g, b = od[..., 0], od[..., 1], od[..., 2]
    return (r >= 0.3) & ((g < 0.5 * r) | ((b < 0.35 * r) & (g < 0.8 * r)))


def _tile(
    name: str, img8: np.ndarray, target8: np.ndarray, peer_cls: type, png: Path | None
) -> dict[str, str]:
    from imageform.analysis import (
        macenko_normalize,
        macenko_stains,
        stain_concentrations,
        tissue_mask,
        vahadane_stains,
    )

    h, w, _ = img8.shape
    row: dict[str, str] = {"tile": name, "size": f"{w}x{h}"}
    try:
        st = macenko_stains(img8)
        row["I0"] = f"{np.mean(st.i0) * 255:.0f} {st.i0_source}"
        tm = tissue_mask(img8)
        glass_only = tissue_mask(img8, pen=False, dark=False)
        row["kept"] = f"{100 * tm.sum() / max(glass_only.sum(), 1):.1f}%"
        peer = peer_cls()
        peer.fit(img8, Io=240, alpha=1, beta=0.15)
        he = np.asarray(peer.HERef).T
        s_none = macenko_stains(img8, i0=240 / 255, mask="none").stain_matrix
        s_auto = macenko_stains(img8, i0=240 / 255).stain_matrix
        row["ts none"] = f"{_angle(s_none, he):.2f}"
        row["ts auto"] = f"{_angle(s_auto, he):.2f}"
        no_dark = tissue_mask(img8, glass=False, dark=False)
        s_nd = macenko_stains(img8, i0=240 / 255, mask=no_dark).stain_matrix
        row["ts nodark"] = f"{_angle(s_nd, he):.2f}"
        second = REF_DAB if name.startswith(IHC) else REF_E
        from imageform.analysis import stain_angle

        row["ref"] = (
            f"{stain_angle(st.stain_matrix[0], REF_H):.1f} / "
            f"{stain_angle(st.stain_matrix[1], second):.1f}"
            + (" DAB" if name.startswith(IHC) else "")
        )
        c = stain_concentrations(img8, st.stain_matrix, i0=np.asarray(st.i0))
        neg = (c[tm] < -0.1).any(axis=-1)
        row["C<-0.1"] = f"{100 * neg.mean():.1f}%" if tm.any() else "-"
        out = macenko_normalize(img8, target8)
        bad = int(np.isnan(out).sum())
        tgt = macenko_stains(target8)
        white = (np.asarray(out) > 1.0).any(axis=-1)
        out8 = _u8(out)
        ref_peer = peer_cls()
        ref_peer.fit(target8, Io=240, alpha=1, beta=0.15)
        theirs8 = np.asarray(
            ref_peer.normalize(img8, Io=240, alpha=1, beta=0.15, stains=False)[0]
        ).astype(np.uint8)
        t_mask = tissue_mask(target8)
        t_lab = _lab(target8)[t_mask].mean(axis=0)
        if tm.any():
            row["dE before"] = f"{_de_mean(_lab(img8)[tm].mean(axis=0), t_lab):.1f}"
            row["dE ours"] = f"{_de_mean(_lab(out8)[tm].mean(axis=0), t_lab):.1f}"
            row["dE ts"] = f"{_de_mean(_lab(theirs8)[tm].mean(axis=0), t_lab):.1f}"
        row["ours-ts"] = f"{_de_pixels(out8, theirs8):.2f}"
        garish = _pen_flags(out8, np.asarray(tgt.i0)) & ~_pen_flags(img8, np.asarray(st.i0))
        row["NaN"] = str(bad) if bad else "-"
        row[">I0"] = f"{100 * white.mean():.2f}%"
        row["green/blue"] = f"{100 * (garish & tm).sum() / max(tm.sum(), 1):.2f}%"
        vs = vahadane_stains(img8).stain_matrix
        row["vahadane"] = f"{_angle(vs, st.stain_matrix):.1f}"
        sj = macenko_stains(_jpeg(img8)).stain_matrix
        row["JPEG75"] = f"{_angle(sj, st.stain_matrix):.2f}"
        if png is not None:
            _panel(png / f"{name}.png", img8, tm, glass_only, out8, theirs8)
    except Exception as exc:  # a row, not a stop: the table reports failures
        row["I0"] = f"error: {type(exc).__name__}: {exc}"[:120]
    return row


def _panel(
    path: Path,
    img8: np.ndarray,
    tm: np.ndarray,
    glass_only: np.ndarray,
    out8: np.ndarray,
    theirs8: np.ndarray,
) -> None:
    from PIL import Image

    over = img8.copy()
    over[~glass_only] = (over[~glass_only] * 0.4).astype(np.uint8)
    art = glass_only & ~tm
    over[art] = (255, 0, 0)
    strip = np.concatenate([img8, over, out8, theirs8], axis=1)
    im = Image.fromarray(strip)
    im.thumbnail((1600, 400))
    path.parent.mkdir(parents=True, exist_ok=True)
    im.save(path)


def _cli(paths: list[Path], target: Path) -> list[list[str]]:
    """The CLI's output against the API's on a few tiles (8-bit codes)."""
    from imageform.analysis import macenko_normalize

    rows = []
    exe = [sys.executable, "-m", "imageform"]
    tgt = _read(target)
    with tempfile.TemporaryDirectory() as tmp:
        for p in paths:
            img = _read(p)
            src = Path(tmp) / (p.stem + "_in.png")
            from PIL import Image

            Image.fromarray(img).save(src)
            api = _u8(macenko_normalize(img, tgt))
            out = Path(tmp) / (p.stem + "_cli.png")
            r = subprocess.run(
                [*exe, "stain-normalize", str(src), "-o", str(out), "--target", str(target)],
                capture_output=True,
                text=True,
                check=False,
            )
            d_cli = int(np.abs(_read(out).astype(int) - api).max()) if r.returncode == 0 else -1
            tif = Path(tmp) / (p.stem + ".tif")
            Image.fromarray(img).save(tif)
            zout = Path(tmp) / (p.stem + "_chunked.tif")
            r2 = subprocess.run(
                [
                    *exe,
                    "chunked",
                    "stain-normalize",
                    str(tif),
                    "-o",
                    str(zout),
                    "--target",
                    str(target),
                    "--chunk",
                    "256",
                    "--tile",
                    "256",
                ],
                capture_output=True,
                text=True,
                check=False,
            )
            d_ch = -1
            if r2.returncode == 0:
                import tifffile

                d_ch = int(np.abs(tifffile.imread(zout)[..., :3].astype(int) - api).max())
            rows.append(
                [
                    p.stem,
                    str(d_cli) if r.returncode == 0 else f"rc {r.returncode}: {r.stderr[-80:]}",
                    str(d_ch) if r2.returncode == 0 else f"rc {r2.returncode}: {r2.stderr[-80:]}",
                ]
            )
    return rows


COLUMNS = {
    "tile": "tile",
    "size": "size",
    "I0": "I0 (of 255), from",
    "kept": "tissue_mask kept (of the glass rule's)",
    "ts none": "angle to torchstain, I0 240, mask none (deg)",
    "ts auto": "same, mask auto (deg)",
    "ts nodark": "same, mask tissue_mask(dark=False) (deg)",
    "ref": "first / second vector to reference H / E or DAB (deg)",
    "C<-0.1": "tissue with C < -0.1",
    "dE before": "dE00 to target, before",
    "dE ours": "dE00 to target, imageform",
    "dE ts": "dE00 to target, torchstain",
    "ours-ts": "dE00 imageform vs torchstain",
    "NaN": "NaN",
    ">I0": "output above 1 (clipped when saved)",
    "green/blue": "tissue turned green/blue",
    "vahadane": "Vahadane to Macenko (deg)",
    "JPEG75": "JPEG 75 moves stains (deg)",
}


def _vahadane(name: str, img: np.ndarray) -> list[str]:
    """Vahadane's convergence and stability on one tile (``--vahadane``)."""
    from imageform.analysis import macenko_stains, optical_density, stain_angle, vahadane_stains
    from imageform.analysis._sparse_nmf import lattice_rows, sparse_nmf

    def worst(a: np.ndarray, b: np.ndarray) -> float:
        return max(stain_angle(a[i], b[i]) for i in range(2))

    def unit(h: np.ndarray) -> np.ndarray:
        h = h / np.linalg.norm(h, axis=1, keepdims=True)
        return h[::-1] if h[0, 0] < h[1, 0] else h

    od = optical_density(img, i0=240 / 255).reshape(-1, 3)
    where = np.flatnonzero((od * od).sum(axis=1) >= 0.15**2)
    start = np.maximum(macenko_stains(img, i0=240 / 255).stain_matrix, 0.0)
    x = od[where[lattice_rows(where, 20_000)]]
    rounds = sparse_nmf(x, start, 0.1, 100_000)[2]
    est = vahadane_stains(img, mask=None).stain_matrix
    capped = worst(vahadane_stains(img, mask=None, iterations=10_000).stain_matrix, est)
    mask = np.ones(img.shape[:2], dtype=bool)
    mask.reshape(-1)[where[lattice_rows(where, 20_000)[0]]] = False
    one = worst(vahadane_stains(img, mask=mask).stain_matrix, est)
    fits = [
        unit(sparse_nmf(od[where[lattice_rows(where, 20_000, s)]], start, 0.1, 1000)[1])
        for s in (0, 1, 2)
    ]
    seeds = max(worst(fits[0], f) for f in fits[1:])
    every = {"max_pixels": 10**7}
    auto_all = vahadane_stains(img, **every)
    none_all = vahadane_stains(img, mask=None, **every)
    moved = worst(auto_all.stain_matrix, none_all.stain_matrix)
    row = [name, str(where.size), str(none_all.n_pixels - auto_all.n_pixels), str(rounds)]
    row += [f"{capped:.4f}", f"{one:.4f}", f"{seeds:.2f}", f"{moved:.2f}"]
    try:
        import spams  # StainTools' engine; not a dependency
    except ImportError:
        return [*row, "-", "-"]
    theirs = []
    for m in ("auto", None):
        keep = (od * od).sum(axis=1) >= 0.15**2
        if m == "auto":
            from imageform.analysis import tissue_mask

            keep &= tissue_mask(img, i0=240 / 255, glass=False).reshape(-1)
        d = spams.trainDL(
            np.asfortranarray(od[keep].T),
            K=2,
            lambda1=0.1,
            mode=2,
            modeD=0,
            posAlpha=True,
            posD=True,
            verbose=False,
            numThreads=1,
            iter=3000,
            batchsize=512,
        )
        theirs.append(unit(np.asarray(d).T))
    ours = vahadane_stains(img, i0=240 / 255, mask=None, **every).stain_matrix
    return [*row, f"{worst(theirs[1], ours):.2f}", f"{worst(theirs[0], theirs[1]):.2f}"]


VAHADANE_COLUMNS = [
    "tile",
    "tissue pixels",
    "left out by the default mask",
    "rounds to convergence (20 000 pixels)",
    "10x the round cap moves (deg)",
    "one factorised pixel masked moves (deg)",
    "3 lattices (seeds) of 20 000: worst spread (deg)",
    "default mask vs none, every pixel (deg)",
    "SPAMS trainDL (3000 rounds) to ours, every pixel, no mask (deg)",
    "SPAMS: default mask vs none (deg)",
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tiles", type=Path)
    ap.add_argument("--target", type=Path, default=None)
    ap.add_argument("--png", type=Path, default=None)
    ap.add_argument("--cli", action="store_true")
    ap.add_argument("--vahadane", action="store_true")
    args = ap.parse_args()
    paths = sorted(p for p in args.tiles.iterdir() if p.suffix.lower() in SUFFIXES)
    if args.vahadane:
        rows = [_vahadane(p.stem, _read(p)) for p in paths]
        print(header("Vahadane's sparse NMF: convergence and stability"))
        print(markdown_table(VAHADANE_COLUMNS, rows))
        return
    from torchstain.numpy.normalizers import NumpyMacenkoNormalizer

    target_path = args.target or next(p for p in paths if "tcga-lung" in p.stem)
    target = _read(target_path)
    rows = []
    for p in paths:
        r = _tile(p.stem, _read(p), target, NumpyMacenkoNormalizer, args.png)
        rows.append([r.get(k, "-") for k in COLUMNS])
        print(" | ".join(rows[-1]), file=sys.stderr, flush=True)
    print(header("Stain separation and normalisation on fresh real tiles"))
    print(f"{len(paths)} tiles from {args.tiles.name}/, target {target_path.name}.\n")
    print(markdown_table(list(COLUMNS.values()), rows))
    if args.cli:
        print("\nCLI against the API (largest difference, 8-bit codes):\n")
        cli = _cli(paths[:3], target_path)
        print(markdown_table(["tile", "stain-normalize", "chunked stain-normalize"], cli))


if __name__ == "__main__":
    main()
