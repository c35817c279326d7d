r"""Tissue and artefact mask of a bright-field slide: glass, pen ink, dark folds and black ink.

Stain estimation assumes that every absorbing pixel holds the two stains. Marker ink is a
third absorber (a flat green mark covering 0.5-5 % of a tile turns a Macenko stain vector
by 26-27°), and black ink and dark folds pile up at the dark end of the optical-density
cloud. :func:`tissue_mask` keeps the pixels that hold stained tissue, by one documented
rule per artefact, each from the practice of slide quality control (HistoQC, HistomicsTK,
the deep-histopath filters) with thresholds measured on real slides (HistoQC's pen-marked
thumbnails with their hand-drawn masks; 18 public H&E/IHC tiles).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform._typing import Array, ArrayLike
from imageform._validate import as_int, as_real, describe, format_shape
from imageform.analysis._arrays import image_in
from imageform.analysis._tissue_rules import keep_mask
from imageform.analysis.macenko import BackgroundEstimate, _resolve_i0
from imageform.errors import InvalidInputError

__all__ = ["TISSUE_MASK_RULES", "tissue_mask"]

#: The rules of :func:`tissue_mask`, each name mapped to what it drops (read-only).
TISSUE_MASK_RULES: MappingProxyType[str, str] = MappingProxyType(
    {
        "glass": "optical density ||OD||_2 < beta: glass, unstained (Macenko's transparent pixels)",
        "pen": "green, cyan and blue marker ink: OD_red >= pen_min_od and OD_green < "
        "0.5 OD_red (green ink) or OD_blue < 0.25 OD_red with OD_green < 0.8 OD_red (blue "
        "ink); H&E and DAB absorb green at least half as much as red. By shape, as IHC's "
        "hematoxylin and cytology's cytoplasm can have blue ink's colour: the flags and the "
        "ink over tissue (OD_green < OD_red) around them form a region, ink where flags are "
        ">= 2 % of it and it is a stroke (long and thin, straight or curved, at most 3 "
        "holes), large and thick, >= 5 % green ink (>= 1024 pixels) or >= 85 % flags with "
        "no hole (>= 512 pixels); a straight stroke of flags takes the ink over tissue 3 "
        "pixels around it; flags with OD_green < 0.4 OD_red are ink anywhere; else stain "
        "(nuclei, cells and their nets). Over the stroke: a 7 x 7 window with >= 35 % ink "
        "over tissue or ink and 8 % ink is ink, with a pixel around it. Ink over the whole "
        "image (a wash: the 99th percentile of each channel tinted, ln(I_B/I_R) or "
        "ln(I_G/I_R) >= 0.2, and ink-coloured by the ratios above): the region rules are left "
        "out; a pixel whose OD across the ink's direction (its flags' median direction) is "
        "under 0.15 is ink or glass, the rest tissue under the ink",
        "dark": "black ink, folds, debris: luma < dark_luminance (HistoQC's dark tissue "
        "rule), or a neutral OD (max/min over the channels <= 1.5) with mean OD >= 1; black "
        "ink where its region (with the paler rim: luma < 2 dark_luminance, or neutral with "
        "mean OD >= 0.5) is neutral (half its dark flags) and a stroke or its flags large: "
        "the dense DAB of IHC nuclei is a blob; black ink (mostly neutral with mean OD >= "
        "2.5) a stroke from 3.5 times as long as wide; a grey region of at most 24 pixels by "
        "the glass is a speck of dye. Folds, on an image that holds eosin (he='auto''s "
        "test): two layers of the section, so both stains (Ruifrok's H and E vectors) at "
        "least twice the median of the absorbing pixels; a region where half the flags are "
        "so is a fold when dark (the mean luma of those < 3 dark_luminance) and a stroke, "
        "large or dense (their mean ||OD|| >= twice the absorbing pixels' 90th percentile). "
        "A dark stroke of one stain (dense nuclei, collagen) is tissue, unless half its dark "
        "flags absorb red as much as green (OD_G < 1.05 OD_R, OD_B < 0.55 OD_R): blue ink. "
        "Lengths and areas "
        "scale with pixel_size_um (0.5 um per pixel: as given), a stroke's length with the "
        "image's shorter side under 512 pixels",
        "he": "H&E slides only (he=True; DAB is brown and hematoxylin + DAB grey): yellow, "
        "orange and brown margin dye and pigment, OD_blue > 1.2 OD_green with OD_blue >= "
        "pen_min_od; grey (label, slide edge, dirt), max/min of the ODs <= 1.25 with mean "
        "OD >= 0.3. he='auto' (the stain estimators' mask 'auto'): on an image where at "
        "least 5 % of the absorbing pixels are eosin's pink (OD_red < 0.5 OD_green, "
        "OD_blue < 0.8 OD_green)",
    }
)


def tissue_mask(
    image: ArrayLike,
    *,
    glass: bool = True,
    pen: bool = True,
    dark: bool = True,
    he: bool | Literal["auto"] = False,
    i0: Literal["auto"] | float | ArrayLike | BackgroundEstimate = "auto",
    beta: float = 0.15,
    pen_min_od: float = 0.3,
    dark_luminance: float = 0.08,
    margin: int = 1,
    pixel_size_um: float | None = None,
) -> Array:
    r"""Pixels of stained tissue: True where a pixel is neither glass nor an artefact.

    With :math:`OD = \ln(I_0 / \max(I, 1/255))` per channel (:math:`I_0` from the glass,
    :func:`~imageform.analysis.estimate_background`, or given) the rules
    (:data:`TISSUE_MASK_RULES`) are:

    - **glass** (``glass``): :math:`\lVert OD\rVert_2 < \beta` is glass or unstained, as
      Macenko's transparent pixels and the Otsu-on-OD tissue masks of CLAM and TIAToolbox
      (a fixed β: a tile can be all tissue, where Otsu would split it).
    - **pen** (``pen``): marker ink is a dye that is neither hematoxylin, eosin nor DAB;
      all three absorb green at least half as much as red, while green and cyan ink
      absorbs red and transmits green, :math:`OD_G < 0.5\, OD_R`, and blue ink transmits
      blue, :math:`OD_B < 0.25\, OD_R` with :math:`OD_G < 0.8\, OD_R` (HistoQC's blue
      ink: a median 0.12, 95th percentile 0.24; IHC's hematoxylin, without eosin, reaches
      0.28); with :math:`OD_R \ge` ``pen_min_od`` (pale pink pixels have small, noisy
      ratios). Colour alone cannot tell blue ink from IHC's hematoxylin without eosin
      (OpenSlide's OS-2 Ki67 nuclei reach OD_B 0.2 OD_R) or from cytology's cyanophilic
      cytoplasm; shape can: a marker's stroke is long and thin, nuclei and cells are
      blobs and their nets have holes. The cleaned flags and the ink over tissue touching
      them (:math:`OD_G < OD_R`, or :math:`OD_B < 0.3\, OD_R` with
      :math:`OD_G < 0.9\, OD_R`; joined across one pixel, 4-connected) form regions; a
      region is ink where the flags are at least 2 % of it and it is a stroke - straight
      (second moments: at least 24 pixels long and 4.5 times as long as wide) or curved
      (its area over twice its largest inscribed radius at least 24 and 12 times that
      width), with at most 3 holes -, or large (16 384 pixels and a tenth of the image, at
      least 24 thick), or holds 5 % green ink (1024 pixels or more), or 85 % flags without
      a hole (512 pixels or more: a dot of ink). Flags that form a straight stroke by
      themselves (a stroke across touching stain joins its net) take the ink over tissue
      3 pixels around them; flags with :math:`OD_G < 0.4\, OD_R` (green ink; no stain
      of the tuning tiles) are ink anywhere. The other flags are the slide's stain. Inside
      a stroke, pale ink over eosin reads as tissue and dense blue or green ink over eosin
      as hematoxylin, and a few such pixels, dense, tilt the stain plane; so a 7 × 7
      window where at least 35 % of the pixels are ink over tissue or ink and 8 % are ink
      is ink as a whole, with one pixel around it. Ink laid over the whole image (a
      wash: each channel's 99th percentile, the glass under the ink, is tinted,
      :math:`\ln(I_B/I_R)` or :math:`\ln(I_G/I_R) \ge 0.2`, and its OD is ink's by the
      ratios above) makes every pixel ink over something, one region: there the region
      rules are left out. Ink is one absorber, so by Beer-Lambert its OD is a multiple of
      one direction :math:`u` however thick it is (the median direction of the flags with
      the lowest :math:`OD_G/OD_R`), and :math:`\lVert OD - (OD\cdot u)\,u\rVert` is the
      tissue's: under 0.15 (β) a pixel is ink over glass, otherwise tissue under the ink
      (smujiang/WSIPenMarkingRemoval's 48 blue-washed patches: 8.2 % of the tissue kept
      before, 85.1 % now, at the median). The stain estimators' ``mask="auto"`` subtract the
      ink's OD (each pixel holds it; the ink over glass nearby gives it) or, under dense
      ink, drop every pixel (:func:`~imageform.analysis.macenko_stains`). Red ink is
      eosin's colour and is not found (as in HistoQC, which needs a model of its own for
      it). Tuned on spent tiles (``benchmarks/check_stain_ihc_fresh.py``,
      ``check_stain_artefacts.py``).
    - **dark** (``dark``): black ink, folds and debris: luma :math:`0.2125R + 0.7154G +
      0.0721B <` ``dark_luminance`` of the encoded values (HistoQC's dark-tissue rule, at
      0.15 there: 0.08 here, as 0.1-0.15 drops 1-3.5 % of the dense nuclei of real tiles),
      or a neutral OD, :math:`\max_c OD_c \le 1.5 \min_c OD_c` with mean OD ≥ 1 (black
      ink over tissue; stains are tinted, hematoxylin's OD spans 2.4x). Dense DAB +
      hematoxylin is near-neutral too, but as blobs: the flags are black ink where
      their region (8-connected, with its paler rim: luma below twice
      ``dark_luminance`` or a neutral OD with mean OD ≥ 0.5) is neutral (at least half
      its dark flags by the neutral rule) and a stroke as above (6 times as long as wide
      when curved; no hole test: ink holds paler pixels), or where the flags of a region
      are large. **Folds** (on an image that holds eosin, by ``he="auto"``'s test): a
      fold is the section lying over itself, two layers or more of the same tissue, so
      darker *and* holding both stains at least twice (Kothari et al. 2013 and Bautista &
      Yagi 2010 find folds as pixels both darker and more saturated than the tissue). A
      pixel is fold-coloured where its hematoxylin and eosin, :math:`C = (S^\top S)^{-1}
      S^\top OD` with Ruifrok & Johnston's H and E vectors as :math:`S`, are both at
      least twice their medians over the absorbing pixels (:math:`\lVert OD\rVert \ge
      0.15`); a dark region (as above, with the fold-coloured pixels) where at least half
      the flags are fold-coloured is a fold when it is dark (the mean luma of those pixels
      under 3 ``dark_luminance``) and a stroke, large, or dense (their mean
      :math:`\lVert OD\rVert` at least twice the 90th percentile of the absorbing
      pixels': a fold on a slide thumbnail is a blob). A dark stroke of one stain - a
      chain of dense nuclei, a band of dense collagen - is tissue (the stroke test alone
      took it for a fold: 12 % of a fresh tile's tissue), unless half its dark pixels have
      :math:`OD_G < 1.05\,OD_R` and :math:`OD_B < 0.55\,OD_R`: dense blue ink over
      tissue (hematoxylin absorbs green more: 1.08 by Ruifrok's vector). On an image without eosin
      (IHC, where DAB reads as both stains) folds are not looked for; a pale fold (two
      layers of pale tissue) is not found either: the same stains, denser, do not turn
      the stain vectors.
    - **he** (``he``, off by default; ``"auto"``: where the image holds eosin): H&E
      slides only. Yellow, orange and brown margin
      dye and pigment, :math:`OD_B > 1.2\, OD_G` (H&E absorb green more than blue), and
      grey (a label, the slide's edge, dirt): :math:`\max_c OD_c \le 1.25 \min_c OD_c`
      with mean OD ≥ 0.3. DAB is brown and hematoxylin + DAB grey: off for IHC.

    Black ink is denser than any stain and neutral: a dark region where at least half the
    flags are neutral with mean OD ≥ 2.8 (HistoQC's black pen over tissue: 3.0-3.4; dense
    DAB, tinted or below 2.6) is a stroke from 3.5 times as long as wide. A dark region of
    at most 24 pixels with its rim (smaller than a nucleus), grey (half its flags by the
    neutral rule) and within 3 pixels of glass (:math:`\lVert OD\rVert < 0.15`) is a speck
    of the margin's dye or dirt.

    A flag without a flagged neighbour (8-connected) is dropped as speckle, the artefacts
    grow by ``margin`` pixels (4-connected), which takes the stroke's blended rim with it.

    **Scale.** The shape rules' lengths (24 pixels) and areas (16 384, 1024, 512, 24 and
    4 pixels) are those of a 512-pixel tile at 0.5 µm per pixel (tuned on 224-2000 pixel
    tiles at 0.25-0.5 µm and slide thumbnails). With the pixel size known (``pixel_size_um``, µm)
    the lengths scale by :math:`s = 0.5 / p` and the areas by :math:`s^2`, with
    :math:`s` within [0.25, 8]. A stroke's length test is also at most the image's shorter
    side over 512 times the tile's (a stroke across a small crop is cut short by its edges:
    0.5 % of a 224-pixel crop is a stroke 31 pixels long; the image's size says nothing of
    its nuclei's, so widths and areas stay). A 512-pixel tile, or a larger image, without
    ``pixel_size_um`` is scaled as before.

    Parameters
    ----------
    image : array_like, shape (..., H, W, 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats in [0, 1]) or Dask
        (lazy; the morphology and the regions' shapes are read 48 pixels and more across
        chunk edges: a region that reaches further may be judged otherwise; a wash of ink
        is found chunk by chunk).
    glass, pen, dark : bool
        Which rules apply (``he`` below).
    i0 : "auto" or float or sequence of 3 floats or BackgroundEstimate
        Incident light, as in :func:`~imageform.analysis.macenko_stains` (an
        :func:`~imageform.analysis.estimate_background` of this image: not estimated
        again).
    beta : float
        OD norm below which a pixel is glass (ln units, 0.15 as Macenko).
    pen_min_od : float
        The least red OD of ink, in [0, 10].
    he : bool or "auto"
        Also the H&E-only rules (brown dye, grey); ``"auto"``: on an image that holds
        eosin (at least 5 % of its absorbing pixels eosin's pink, :math:`OD_R < 0.5\,OD_G`
        and :math:`OD_B < 0.8\,OD_G`; IHC's hematoxylin and DAB are not), as the stain
        estimators' ``mask="auto"`` does. Each image of a batch alone; a Dask array as one.
    dark_luminance : float
        Luma below which a pixel is dark, in [0, 1].
    margin : int
        Pixels the artefact flags grow by, in [0, 64].
    pixel_size_um : float, optional
        Pixel size :math:`p` in micrometres (µm per pixel at the specimen, > 0; a slide's
        "mpp"), when known: the TIFF readers of
        :mod:`imageform.batch` give it (OME ``PhysicalSizeX``, Aperio ``MPP``) and
        ``imageform stain`` passes it on. None: the image's size alone sets the scale.

    Returns
    -------
    ndarray or dask array of bool, shape (..., H, W)

    Raises
    ------
    InvalidInputError
        Not an RGB image, a parameter out of range.

    Notes
    -----
    Sources: A. Janowczyk et al., "HistoQC: an open-source quality control tool for digital
    pathology slides", JCO Clin. Cancer Inform. 3, 2019 (pen markings, dark tissue at luma
    0.15, its configuration ``config.ini``); S. Kothari et al., "Eliminating tissue-fold
    artifacts in histopathological whole-slide images for improved image-based prediction
    of cancer grade", J. Pathol. Inform. 4:22, 2013, and P. A. Bautista & Y. Yagi,
    "Improving the visualization and detection of tissue folds in whole slide images
    through color enhancement", J. Pathol. Inform. 1:25, 2010 (folds darker and more
    saturated than the tissue: saturation less intensity); A. C. Ruifrok & D. A.
    Johnston, "Quantification of histochemical staining by color deconvolution", Anal.
    Quant. Cytol. Histol. 23, 2001 (the H and E vectors); HistomicsTK
    ``saliency.tissue_detection`` (thresholding the hematoxylin channel to get rid of green
    marker); the deep-histopath pen filters (red, green and blue ink by RGB thresholds);
    Macenko et al. 2009 (β).

    Examples
    --------
    >>> tile = np.full((40, 40, 3), (0.55, 0.25, 0.55))    # hematoxylin-eosin purple
    >>> tile[:, :10] = (0.94, 0.94, 0.94)                   # glass
    >>> tile[28:, 20:] = (0.25, 0.7, 0.6)                   # green marker
    >>> tile[4:7, 12:] = (0.05, 0.05, 0.04)                 # a black ink stroke
    >>> m = tissue_mask(tile, i0=0.94, margin=0)
    >>> int(m.sum()), bool(m[15, 15]), bool(m[32, 30]), bool(m[5, 30]), bool(m[0, 0])
    (816, True, False, False, False)

    A short black stroke on a small crop (0.5 % of it) and a dense brown DAB nucleus of the
    same size beside it: the stroke is ink, the nucleus stain.

    >>> crop = np.full((224, 224, 3), (0.75, 0.55, 0.7))    # H&E
    >>> crop[100:108, 40:71] = (0.03, 0.03, 0.03)            # black ink, 31 x 8
    >>> crop[60:75, 150:165] = (0.16, 0.06, 0.04)            # dense DAB, 15 x 15
    >>> m = tissue_mask(crop, i0=0.94, margin=0)
    >>> bool(m[104, 55]), bool(m[67, 157]), bool(m[20, 20])
    (False, True, True)
    """
    rgb = image_in(image, nonempty=True)
    if rgb.ndim < 3:
        raise InvalidInputError(
            f"expected image of shape (..., H, W, 3), got {format_shape(tuple(rgb.shape))}"
        )
    flags: dict[str, Any] = {}
    for name, val in (("glass", glass), ("pen", pen), ("dark", dark), ("he", he)):
        if name == "he" and isinstance(val, str) and val.strip().lower() == "auto":
            flags[name] = "auto"
            continue
        if not isinstance(val, bool | np.bool_):
            also = " or 'auto'" if name == "he" else ""
            raise InvalidInputError(f"expected {name} as True or False{also}, got {describe(val)}")
        flags[name] = bool(val)
    beta = as_real(beta, "beta", minimum=0.0, maximum=10.0)
    params: dict[str, Any] = {
        "pen": flags["pen"],
        "dark": flags["dark"],
        "he": flags["he"],
        "pen_min_od": as_real(pen_min_od, "pen_min_od", minimum=0.0, maximum=10.0),
        "dark_luminance": as_real(dark_luminance, "dark_luminance", minimum=0.0, maximum=1.0),
        "margin": as_int(margin, "margin", minimum=0, maximum=64),
        "mpp": None
        if pixel_size_um is None
        else as_real(pixel_size_um, "pixel_size_um", minimum=1e-3, maximum=1e4),
    }
    return keep_mask(rgb, _resolve_i0(rgb, i0), params, flags["glass"], float(beta))
