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
from imageform.analysis._arrays import image_in, is_dask
from imageform.analysis.macenko import MIN_INTENSITY, _resolve_i0
from imageform.errors import InvalidInputError

__all__ = ["TISSUE_MASK_RULES", "tissue_mask"]

#: The rules of :func:`tissue_mask`, each name mapped to what it drops (read-only).
TISSUE_MASK_RULES: MappingProxyType[str, str] = MappingProxyType(
    {
        "glass": "optical density ||OD||_2 < beta: glass, unstained (Macenko's transparent pixels)",
        "pen": "green, cyan and blue marker ink: OD_red >= pen_min_od and OD_green < "
        "0.5 OD_red (green ink) or OD_blue < 0.35 OD_red with OD_green < OD_red (blue ink); "
        "H&E and DAB absorb green at least half as much as red",
        "dark": "black ink, dark folds, debris: luminance < dark_luminance (HistoQC's dark "
        "tissue rule), or a neutral OD (max/min over the channels <= 1.5) with mean OD >= 1",
        "he": "H&E slides only (he=True; DAB is brown and hematoxylin + DAB grey): yellow, "
        "orange and brown margin dye and pigment, OD_blue > 1.2 OD_green with OD_blue >= "
        "pen_min_od; grey (label, slide edge, dirt), max/min of the ODs <= 1.25 with mean "
        "OD >= 0.3",
    }
)

#: Luma of encoded RGB (ITU-R BT.709 weights, as scikit-image's ``rgb2gray`` and HistoQC).
_LUMA = np.array([0.2125, 0.7154, 0.0721])

#: OD ratios of the pen rule: green ink absorbs red 2-9x more than green (HistoQC's green
#: marker: median OD_g/OD_r 0.27, 99th percentile 0.75 at the stroke's edge); on 18 H&E/IHC
#: tiles the 0.1st percentile of OD_g/OD_r is 0.55. Blue ink absorbs little blue
#: (OD_b/OD_r 0.11 on HistoQC's blue dot, hematoxylin 0.45-0.72).
_GREEN_RATIO = 0.5
_BLUE_RATIO = 0.35
_BLUE_GREEN = 0.8

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

#: Default luma of the dark rule (HistoQC: 0.15; 0.1 drops 1-3.5 % of dense nuclei).
_DARK_LUMA = 0.08


#: Ink over tissue and the ink's own spread (the pen rule's hysteresis): OD_G < OD_R, or
#: OD_B < 0.3 OD_R with OD_G < 0.9 OD_R, joined to a pen pixel. Green ink over a nucleus
#: reads OD_G/OD_R ~ 0.7, over eosin up to ~0.95 (H&E tissue: median 1.0-3.7); HistoQC's
#: blue ink OD_G/OD_R 0.5-0.83 (at most 0.22 % of the pixels of 18 real tiles pass the
#: blue test).
_WEAK_RATIO = 1.0
_WEAK_BLUE = 0.3


def _artefacts(
    rgb: np.ndarray, log_i0: np.ndarray, p: dict[str, Any]
) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel flags of one block: (artefact, ink over tissue), before the morphology."""
    od = log_i0 - np.log(np.maximum(rgb, MIN_INTENSITY))
    r, g, b = od[..., 0], od[..., 1], od[..., 2]
    bad = np.zeros(rgb.shape[:-1], dtype=bool)
    weak = np.zeros(rgb.shape[:-1], dtype=bool)
    if p["pen"]:
        strong = r >= p["pen_min_od"]
        green = g < _GREEN_RATIO * r
        blue = (b < _BLUE_RATIO * r) & (g < _BLUE_GREEN * r)
        bad |= strong & (green | blue)
        weak = strong & ((g < _WEAK_RATIO * r) | ((b < _WEAK_BLUE * r) & (g < 0.9 * r)))
    if p.get("he", False):
        lo = np.maximum(od.min(axis=-1), 1e-6)
        grey = (od.max(axis=-1) <= _GREY_RATIO * lo) & (od.mean(axis=-1) >= _GREY_OD)
        bad |= ((b > _BROWN_RATIO * g) & (b >= p["pen_min_od"])) | grey
    if p["dark"]:
        luma = rgb @ _LUMA
        lo = np.maximum(od.min(axis=-1), 1e-6)
        neutral = (od.max(axis=-1) <= _NEUTRAL_RATIO * lo) & (od.mean(axis=-1) >= _NEUTRAL_OD)
        bad |= (luma < p["dark_luminance"]) | neutral
    return bad, weak


def _pixel_artefacts(rgb: Any, i0v: np.ndarray, he: bool = False) -> Any:
    """Return the default artefact flags of single pixels (no neighbours: no morphology)."""
    p = {"pen": True, "dark": True, "he": he, "pen_min_od": 0.3, "dark_luminance": _DARK_LUMA}
    if is_dask(rgb):
        return rgb.map_blocks(
            lambda b: _artefacts(b, np.log(i0v), p)[0], drop_axis=rgb.ndim - 1, dtype=bool
        )
    return _artefacts(np.asarray(rgb), np.log(i0v), p)[0]


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


def _grow(bad: np.ndarray, weak: np.ndarray, margin: int) -> np.ndarray:
    """Return the artefact flags cleaned, grown into ink over tissue and dilated.

    Flags without a flagged 8-neighbour are dropped (speckle); the ``weak`` regions that
    touch what is left are added (hysteresis); the result grows by ``margin`` pixels.
    """
    from scipy import ndimage

    if bad.ndim < 2 or not bad.any():
        return bad
    cross = _cross(bad.ndim)
    square = np.zeros((3,) * bad.ndim, dtype=np.uint8)
    square[(1,) * (bad.ndim - 2) + (slice(None), slice(None))] = 1
    n = ndimage.convolve(bad.astype(np.uint8), square, mode="constant")
    core = bad & (n >= 2)
    if weak.any() and core.any():
        labels, _ = ndimage.label(weak | core, structure=cross)
        hit = np.unique(labels[core])
        core |= np.isin(labels, hit[hit > 0])
    if margin == 0:
        return core
    return ndimage.binary_dilation(core, structure=cross, iterations=margin)


def _block(
    rgb: np.ndarray, log_i0: np.ndarray, p: dict[str, Any], glass: bool, beta: float
) -> np.ndarray:
    keep = ~_grow(*_artefacts(rgb, log_i0, p), p["margin"])
    if glass:
        od = log_i0 - np.log(np.maximum(rgb, MIN_INTENSITY))
        keep &= (od * od).sum(axis=-1) >= beta * beta
    return keep


def tissue_mask(
    image: ArrayLike,
    *,
    glass: bool = True,
    pen: bool = True,
    dark: bool = True,
    he: bool = False,
    i0: Literal["auto"] | float | ArrayLike = "auto",
    beta: float = 0.15,
    pen_min_od: float = 0.3,
    dark_luminance: float = 0.08,
    margin: int = 1,
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
      blue, :math:`OD_B < 0.35\, OD_R` with :math:`OD_G < 0.8\, OD_R`; with
      :math:`OD_R \ge` ``pen_min_od`` (pale pink pixels have small, noisy ratios). Ink
      over tissue adds the tissue's OD: the flags grow (hysteresis, 4-connected) into the
      touching pixels with :math:`OD_G < OD_R`, or :math:`OD_B < 0.3\, OD_R` with
      :math:`OD_G < 0.9\, OD_R`. Red ink is eosin's colour and is not found (as in
      HistoQC, which needs a model of its own for it).
    - **dark** (``dark``): black ink, folds and debris: luma :math:`0.2125R + 0.7154G +
      0.0721B <` ``dark_luminance`` of the encoded values (HistoQC's dark-tissue rule, at
      0.15 there: 0.08 here, as 0.1-0.15 drops 1-3.5 % of the dense nuclei of real tiles),
      or a neutral OD, :math:`\max_c OD_c \le 1.5 \min_c OD_c` with mean OD ≥ 1 (black
      ink over tissue; stains are tinted, hematoxylin's OD spans 2.4x). On IHC, dense
      hematoxylin + DAB is near-neutral and can be dropped: ``dark=False`` there.
    - **he** (``he``, off by default): H&E slides only. Yellow, orange and brown margin
      dye and pigment, :math:`OD_B > 1.2\, OD_G` (H&E absorb green more than blue), and
      grey (a label, the slide's edge, dirt): :math:`\max_c OD_c \le 1.25 \min_c OD_c`
      with mean OD ≥ 0.3. DAB is brown and hematoxylin + DAB grey: off for IHC.

    A flag without a flagged neighbour (8-connected) is dropped as speckle, the rest grow
    by ``margin`` pixels (4-connected), which takes the stroke's blended rim with it.

    Parameters
    ----------
    image : array_like, shape (..., H, W, 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats in [0, 1]) or Dask
        (lazy; the rules are per pixel and the morphology reads ``margin + 1`` pixels
        across chunk edges).
    glass, pen, dark : bool
        Which rules apply (``he`` below).
    i0 : "auto" or float or sequence of 3 floats
        Incident light, as in :func:`~imageform.analysis.macenko_stains`.
    beta : float
        OD norm below which a pixel is glass (ln units, 0.15 as Macenko).
    pen_min_od : float
        The least red OD of ink, in [0, 10].
    he : bool
        Also the H&E-only rules (brown dye, grey).
    dark_luminance : float
        Luma below which a pixel is dark, in [0, 1].
    margin : int
        Pixels the artefact flags grow by, in [0, 64].

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
    0.15, its configuration ``config.ini``); HistomicsTK ``saliency.tissue_detection``
    (thresholding the hematoxylin channel to get rid of green marker); the deep-histopath
    pen filters (red, green and blue ink by RGB thresholds); Macenko et al. 2009 (β).

    Examples
    --------
    >>> tile = np.full((8, 8, 3), (0.55, 0.25, 0.55))      # hematoxylin-eosin purple
    >>> tile[:, :2] = (0.94, 0.94, 0.94)                    # glass
    >>> tile[5:, 4:] = (0.25, 0.7, 0.6)                     # green marker
    >>> tile[:2, 6:] = (0.05, 0.05, 0.04)                   # black ink
    >>> m = tissue_mask(tile, i0=0.94, margin=0)
    >>> int(m.sum()), bool(m[3, 3]), bool(m[6, 6]), bool(m[0, 7]), bool(m[0, 0])
    (32, True, False, False, False)
    """
    rgb = image_in(image, nonempty=True)
    if rgb.ndim < 3:
        raise InvalidInputError(
            f"expected image of shape (..., H, W, 3), got {format_shape(tuple(rgb.shape))}"
        )
    flags = {}
    for name, val in (("glass", glass), ("pen", pen), ("dark", dark), ("he", he)):
        if not isinstance(val, bool | np.bool_):
            raise InvalidInputError(f"expected {name} as True or False, got {describe(val)}")
        flags[name] = bool(val)
    beta = as_real(beta, "beta", minimum=0.0, maximum=10.0)
    params: dict[str, Any] = {
        "pen": flags["pen"],
        "dark": flags["dark"],
        "he": flags["he"],
        "pen_min_od": as_real(pen_min_od, "pen_min_od", minimum=0.0, maximum=10.0),
        "dark_luminance": as_real(dark_luminance, "dark_luminance", minimum=0.0, maximum=1.0),
        "margin": as_int(margin, "margin", minimum=0, maximum=64),
    }
    log_i0 = np.log(_resolve_i0(rgb, i0))
    if not is_dask(rgb):
        return _block(np.asarray(rgb), log_i0, params, flags["glass"], float(beta))
    depth = dict.fromkeys((rgb.ndim - 3, rgb.ndim - 2), params["margin"] + 1)
    whole = rgb.rechunk({rgb.ndim - 1: 3})

    def block(blk: np.ndarray) -> np.ndarray:
        keep = _block(blk, log_i0, params, flags["glass"], float(beta))
        return np.repeat(keep[..., None], 3, axis=-1)  # the block's shape: trimmed as is

    over = whole.map_overlap(
        block, depth={**depth, rgb.ndim - 1: 0}, boundary="none", dtype=bool, trim=True
    )
    return over[..., 0]
