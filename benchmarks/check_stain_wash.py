"""Ink over a whole patch, HistoQC's small green-marked thumbnail, pale blue ink over eosin.

Run (each part with its own folder; any may be left out)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_wash.py \\
        [--pairs PAIR_DIR] [--pen PEN_DIR --tiles TILE_DIR] [--clean DIR ...] \\
        [--heldout THUMB_DIR]

None of the images is in the repository (one pair is: ``tests/data/stain``).

1. ``--pairs``: ``*_clean.png`` / ``*_inked.png`` pairs, the same H&E tissue scanned clean
   and after blue ink was laid over the whole patch (smujiang/WSIPenMarkingRemoval, MIT,
   commit 8451813b, ``img_samples/*_pairs.jpg``: 512 x 256, the clean scan left). Per pair:
   the clean scan's glass share (the glass rule, ``tissue_mask(clean, pen=False,
   dark=False)``, is the truth: the scans are registered, to a pixel or two), the share of
   its tissue the default ``tissue_mask`` of the inked scan keeps, the share of its glass
   the inked scan's mask calls tissue (ink over glass; misregistration included), whether
   the inked scan is a wash (``_tissue_rules._washed``, "-" where the code has none) and
   Macenko (``mask="auto"``) on the inked scan against the clean scan's (``mask="none"``),
   each at its own I0, or the error it raised.
2. ``--pen`` and ``--tiles`` (``benchmarks/check_stain_artefacts.py``'s folders):
   (a) how many of the clean tiles, HistoQC's thumbnails and the 270 ink and fold bands of
   that script are a wash (none: their masks are the same as before, by construction);
   (b) HistoQC's ``small_pen_green`` thumbnail, Macenko with ``mask="auto"`` 34.1 deg from
   the script's reference (the stains without the hand-masked ink and without the H&E
   rules' brown dye and grey): the angle against that reference with the mask cut to the
   reference's pixels, without the brown dye (the H&E rule's colour), and the reference's
   own angle when the slide's top edge (its first 6 rows, a grey-pink strip) is left out;
   (c) the two held-out blue cases over 3 deg (``tiatoolbox_kather1``, 2 and 5 %): the
   band's pixels by rule (pen flags, ink over tissue, dark), the stroke windows' share of
   ink over tissue (35 % needed) and the band kept, for the tune and held-out halves.
3. ``--clean`` (repeatable): how many of a folder's images are a wash (none: their masks
   are as before; ``check_stain_ihc_fresh.py``'s tuning tiles).
4. ``--heldout``: pen-annotated slide thumbnails with their annotation masks
   (MSKCC-Computational-Pathology/PenAnnotationExtractor, MIT, commit 83a91207,
   ``data/thumbnails/thumbnail_NNNNN.jpg`` and ``data/annotations/resized/labels_rs_NNNNN.png``
   for NNNNN = 5, 15, ..., 315; the label's red pixels, R = 255 and G < 128, are the region a
   pathologist drew around with the pen). The pen stroke is the region's outline: the
   band within 6 pixels of it (the region dilated minus eroded by 6); per thumbnail the
   share of the band's absorbing pixels (the glass rule's) that ``tissue_mask`` drops, the
   share of the glass rule's tissue it keeps inside the region (eroded by 15 pixels: no
   ink) and outside it (dilated by 15), whether it is a wash, and Macenko with
   ``mask="auto"`` and ``None`` against Macenko on the glass rule's pixels without the band
   (dilated by 4 more: the stroke's rim). Ink the pathologist drew elsewhere (labels,
   dots, other strokes) is not in the label: "outside" holds it. ``--ring N``: the band is
   the ring N pixels wide outside the region instead (and "outside" starts 15 + N pixels
   out): the label's edge is the stroke's inner edge, the stroke lies outside it (seen
   after the held-out run: ``stain-wash-2026-11-30j.md``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff"}


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.analysis import stain_angle

    return max(stain_angle(a[i], b[i]) for i in range(2))


def _stains(img: np.ndarray, mask: object) -> np.ndarray:
    from imageform.analysis import macenko_stains

    return np.asarray(macenko_stains(img, mask=mask).stain_matrix)


def _washed(img: np.ndarray) -> str:
    """Whether the code at hand calls an image a wash ("-": it has no such rule)."""
    try:
        from imageform.analysis._tissue_rules import _bright_end, _washed
    except ImportError:
        return "-"
    from imageform.analysis import estimate_background

    rgb = img.astype(np.float64) / 255.0
    hi = _bright_end(rgb)
    return "yes" if _washed(hi, np.log(estimate_background(img).i0)) else "no"


def _pct(v: float) -> str:
    return "-" if np.isnan(v) else f"{v:.1%}"


def _try_angle(img: np.ndarray, mask: object, ref: np.ndarray) -> str:
    try:
        return f"{_angle(_stains(img, mask), ref):.2f}"
    except Exception as exc:  # a cell, not a stop
        return type(exc).__name__


def pairs(folder: Path) -> None:
    from imageform.analysis import tissue_mask

    rows, kept, false_all, false_glassy, errors, ran = [], [], [], [], 0, []
    for p in sorted(folder.glob("*_clean.png")):
        clean, inked = _read(p), _read(p.with_name(p.name.replace("_clean", "_inked")))
        truth = tissue_mask(clean, pen=False, dark=False)
        keep = tissue_mask(inked)
        k = float(keep[truth].mean())
        f = float(keep[~truth].mean()) if (~truth).any() else float("nan")
        glass = float((~truth).mean())
        kept.append(k)
        false_all.append(f)
        if glass >= 0.3:
            false_glassy.append(f)
        try:
            ref = _stains(clean, "none")
        except Exception as exc:  # a row, not a stop
            ang = f"clean: {type(exc).__name__}"
        else:
            ang = _try_angle(inked, "auto", ref)
            errors += not ang[0].isdigit()
            if ang[0].isdigit():
                ran.append(float(ang))
        name = p.stem[: -len("_clean")]
        rows.append([name, f"{glass:.0%}", f"{k:.1%}", f"{f:.1%}", _washed(inked), ang])
    cols = [
        "pair",
        "clean scan: glass",
        "inked: tissue kept (of the clean scan's)",
        "inked: glass called tissue",
        "wash",
        "Macenko auto, inked vs clean (deg)",
    ]
    kv, fa, fg = np.array(kept), np.array(false_all), np.array(false_glassy)
    print(f"\n## Ink over the whole patch ({folder.name}, {len(rows)} pairs)\n")
    print(
        markdown_table(
            [
                "pairs",
                "tissue kept: median / 10th pct",
                "under 50 % kept",
                "glass called tissue: median (all)",
                "same, pairs with >= 30 % glass: median / worst",
                "Macenko auto refused",
                "Macenko auto where it ran: median / least / worst (deg)",
            ],
            [
                [
                    str(len(rows)),
                    f"{np.median(kv):.1%} / {np.percentile(kv, 10):.1%}",
                    str(int((kv < 0.5).sum())),
                    f"{np.nanmedian(fa):.1%}",
                    f"{np.median(fg):.1%} / {fg.max():.1%} ({fg.size})" if fg.size else "-",
                    f"{errors} of {len(rows)}",
                    f"{np.median(ran):.1f} / {min(ran):.1f} / {max(ran):.1f}" if ran else "-",
                ]
            ],
        )
    )
    print()
    print(markdown_table(cols, rows))


def artefacts(pen: Path, tiles: Path) -> None:
    from benchmarks import check_stain_artefacts as art
    from imageform.analysis import tissue_mask

    inks = art._ink(pen)
    imgs = {
        p.stem: art._crop(_read(p)) for p in sorted(tiles.iterdir()) if p.suffix.lower() in SUFFIXES
    }
    n, washed = 0, 0
    for name in ("pen_green", "small_pen_green", "pen_black", "pen_red", "small_pen_red"):
        n += 1
        washed += _washed(_read(pen / f"{name}.png")) == "yes"
    for img8 in imgs.values():
        n += 1
        washed += _washed(img8) == "yes"
        for k, frac in enumerate(art.COVERAGES):
            band = art._band(img8.shape[:2], frac, seed=k)
            for t in inks.values():
                for half in t:
                    n += 1
                    washed += _washed(art._inked(img8, band, half, seed=k)) == "yes"
            n += 1
            washed += _washed(art._folded(img8, band)) == "yes"
    print("\n## (a) Washes among check_stain_artefacts.py's images\n")
    print(
        markdown_table(
            ["images (thumbnails, clean tiles, ink and fold bands)", "a wash"],
            [[str(n), str(washed)]],
        )
    )

    thumb = _read(pen / "small_pen_green.png")
    hand = art._read_mask(pen / "small_pen_green_mask.png")
    ref = ~hand & tissue_mask(thumb, glass=False, pen=False, dark=False, he=True)
    best = _stains(thumb, ref)
    auto = tissue_mask(thumb, glass=False)
    from imageform.analysis import estimate_background

    od = np.log(estimate_background(thumb).i0) - np.log(np.maximum(thumb / 255.0, 1 / 255))
    brown = (od[..., 2] > 1.2 * od[..., 1]) & (od[..., 2] >= 0.3)
    top = np.zeros(hand.shape, dtype=bool)
    top[:6] = True
    no_top = _stains(thumb, ref & ~top)
    rows = [
        ["mask auto (the table's 34.1)", f"{_angle(_stains(thumb, auto), best):.1f}"],
        ["mask he", f"{_angle(_stains(thumb, 'he'), best):.1f}"],
        [
            "mask auto, cut to the reference's pixels",
            f"{_angle(_stains(thumb, auto & ref), best):.1f}",
        ],
        [
            "mask auto without the brown-dye colour",
            f"{_angle(_stains(thumb, auto & ~brown), best):.1f}",
        ],
        ["hand-masked ink kept by mask auto (pixels)", str(int((auto & hand).sum()))],
        ["kept by auto, not by the reference (pixels)", str(int((auto & ~ref).sum()))],
        ["the reference without the top 6 rows, to the reference", f"{_angle(no_top, best):.1f}"],
        ["mask he, to that reference", f"{_angle(_stains(thumb, 'he'), no_top):.1f}"],
        ["mask auto, to that reference", f"{_angle(_stains(thumb, auto), no_top):.1f}"],
    ]
    print("\n## (b) small_pen_green: what turns Macenko (deg, to the reference)\n")
    print(markdown_table(["variant", "value"], rows))

    from imageform.analysis import _tissue_rules as rules

    img8 = imgs.get("tiatoolbox_kather1")
    if img8 is None:
        return
    rows = []
    for k, frac in enumerate(art.COVERAGES):
        band = art._band(img8.shape[:2], frac, seed=k)
        clean = _stains(img8, "none")
        for i, half in enumerate(("tune", "held-out")):
            marked = art._inked(img8, band, inks["blue"][i], seed=k)
            rgb = marked / 255.0
            i0 = estimate_background(marked).i0
            flags = rules._flags(rgb, rules._od(rgb, np.log(i0)), dict(rules.DEFAULTS))
            keep = tissue_mask(marked, glass=False)
            bad = flags["pen"] | flags["dark"]
            from scipy import ndimage

            share = ndimage.uniform_filter(
                (flags["weak"] | bad).astype(np.float32), 7, mode="constant"
            )
            rows.append(
                [
                    f"{frac:.1%}",
                    half,
                    str(int(band.sum())),
                    str(int((flags["pen"] & band).sum())),
                    str(int((flags["weak"] & band).sum())),
                    str(int((flags["dark"] & band).sum())),
                    f"{np.median(share[band]):.0%}",
                    f"{keep[band].mean():.1%}",
                    f"{_angle(_stains(marked, 'auto'), clean):.2f}",
                ]
            )
    print("\n## (c) Blue ink over tiatoolbox_kather1 (a 224-pixel crop of eosin-rich tissue)\n")
    cols = [
        "coverage",
        "ink half",
        "band pixels",
        "pen flags",
        "ink over tissue",
        "dark flags",
        "7x7 share of flags or ink over tissue (median)",
        "band kept",
        "Macenko auto to clean (deg)",
    ]
    print(markdown_table(cols, rows))


def heldout(folder: Path, ring: int = 0) -> None:
    from scipy import ndimage

    from imageform.analysis import tissue_mask

    rows, band_drop, inside, outside, d_auto, d_none = [], [], [], [], [], []
    for p in sorted(folder.glob("thumbnail_*.jpg")):
        img = _read(p)
        lab = _read(p.with_name(p.name.replace("thumbnail_", "labels_rs_").replace(".jpg", ".png")))
        region = (lab[..., 0] == 255) & (lab[..., 1] < 128)
        truth = tissue_mask(img, pen=False, dark=False)
        keep = tissue_mask(img)
        if ring:  # the ink outside the region: a ring ``ring`` pixels wide
            band = ndimage.binary_dilation(region, iterations=ring) & ~region
        else:
            band = ndimage.binary_dilation(region, iterations=6) & ~ndimage.binary_erosion(
                region, iterations=6
            )
        inner = ndimage.binary_erosion(region, iterations=15) & truth
        outer = ~ndimage.binary_dilation(region, iterations=15 + ring) & truth
        absorbing = band & truth
        drop = 1.0 - float(keep[absorbing].mean()) if absorbing.any() else float("nan")
        k_in = float(keep[inner].mean()) if inner.any() else float("nan")
        k_out = float(keep[outer].mean()) if outer.any() else float("nan")
        band_drop.append(drop)
        inside.append(k_in)
        outside.append(k_out)
        ref_mask = truth & ~ndimage.binary_dilation(band, iterations=4)
        try:
            ref = _stains(img, ref_mask)
        except Exception as exc:  # a row, not a stop
            rows.append(
                [
                    p.stem,
                    f"{region.mean():.1%}",
                    _pct(drop),
                    _pct(k_in),
                    _pct(k_out),
                    _washed(img),
                    type(exc).__name__,
                    "-",
                ]
            )
            continue
        a_auto = _try_angle(img, "auto", ref)
        a_none = _try_angle(img, None, ref)
        for s, out in ((a_auto, d_auto), (a_none, d_none)):
            out.append(float(s) if s[0].isdigit() else float("nan"))
        rows.append(
            [
                p.stem,
                f"{region.mean():.1%}",
                _pct(drop),
                _pct(k_in),
                _pct(k_out),
                _washed(img),
                a_auto,
                a_none,
            ]
        )
    bd, ki, ko = np.array(band_drop), np.array(inside), np.array(outside)
    da, dn = np.array(d_auto), np.array(d_none)
    what = f", the ring {ring} pixels outside the region" if ring else ""
    print(f"\n## Held-out: pen-annotated thumbnails ({folder.name}, {len(rows)}{what})\n")
    summary = [
        [
            str(len(rows)),
            f"{np.nanmedian(bd):.1%} / {np.nanmin(bd):.1%}",
            f"{np.nanmedian(ki):.1%} / {np.nanmin(ki):.1%}",
            f"{np.nanmedian(ko):.1%} / {np.nanmin(ko):.1%}",
            f"{np.nanmedian(da):.2f} / {np.nanmax(da):.2f} / {int((da > 3).sum())}",
            f"{np.nanmedian(dn):.2f} / {np.nanmax(dn):.2f} / {int((dn > 3).sum())}",
        ]
    ]
    print(
        markdown_table(
            [
                "thumbnails",
                "outline band dropped: median / least",
                "tissue kept inside: median / least",
                "tissue kept outside: median / least",
                "Macenko auto: median / worst / over 3 deg",
                "no mask: median / worst / over 3 deg",
            ],
            summary,
        )
    )
    print()
    cols = [
        "thumbnail",
        "annotated region",
        "outline band dropped",
        "tissue kept inside",
        "tissue kept outside",
        "wash",
        "Macenko auto (deg)",
        "no mask (deg)",
    ]
    print(markdown_table(cols, rows))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=Path, default=None)
    ap.add_argument("--pen", type=Path, default=None)
    ap.add_argument("--tiles", type=Path, default=None)
    ap.add_argument("--heldout", type=Path, default=None)
    ap.add_argument("--clean", type=Path, action="append", default=[])
    ap.add_argument("--ring", type=int, default=0)
    args = ap.parse_args()
    print(header("Ink over a whole patch, a green-marked thumbnail, blue ink over eosin"))
    if args.pairs is not None:
        pairs(args.pairs)
    if args.pen is not None and args.tiles is not None:
        artefacts(args.pen, args.tiles)
    if args.clean:
        rows = []
        for folder in args.clean:
            files = [p for p in sorted(folder.iterdir()) if p.suffix.lower() in SUFFIXES]
            rows.append(
                [folder.name, str(len(files)), str(sum(_washed(_read(p)) == "yes" for p in files))]
            )
        print("\n## (a) Washes among clean tiles\n")
        print(markdown_table(["folder", "images", "a wash"], rows))
    if args.heldout is not None:
        heldout(args.heldout, args.ring)


if __name__ == "__main__":
    main()
