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

#: The hysteresis adds a 4-connected region of ink over tissue only where the cleaned ink
#: flags are at least this share of it. A marker stroke brings its flags (its dense ink, the
#: ink over glass): the doc's flat stroke, HistoQC's strokes. On IHC slides hematoxylin
#: without eosin reads as ink over tissue (17-45 % of DeepLIIF's Ki67 tiles' tissue), the
#: nuclei touch into large regions with few flags (nuclei under OD_G < 0.5 OD_R): grown,
#: they took 26-64 % of the tissue. Tuned on the tuning half of check_stain_fresh.py and
#: check_stain_artefacts.py: 0.01 keeps 86-89 % of two Ki67 tiles, 0.05 turns 3 more
#: green-ink cases of the tune half over 3 deg, 0.02 neither (but 3 more blue held-out).
_GROW_SHARE = 0.02


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


def _od(rgb: np.ndarray, log_i0: np.ndarray) -> np.ndarray:
    """Optical density ``ln(I0) - ln(max(I, floor))`` of a block (macenko's rule)."""
    return log_i0 - np.log(np.maximum(rgb, _FLOOR))


def _artefacts(rgb: np.ndarray, od: np.ndarray, p: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel flags of one block (``od``: its :func:`_od`): (artefact, ink over tissue)."""
    r, g, b = od[..., 0], od[..., 1], od[..., 2]
    bad = np.zeros(rgb.shape[:-1], dtype=bool)
    weak = np.zeros(rgb.shape[:-1], dtype=bool)
    if p["pen"]:
        strong = r >= p["pen_min_od"]
        green = g < _GREEN_RATIO * r
        blue = (b < _BLUE_RATIO * r) & (g < _BLUE_GREEN * r)
        bad |= strong & (green | blue)
        # ink over tissue; the pen flags are in it (OD_G < 0.5 OD_R implies OD_G < OD_R)
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


def pixel_artefacts(rgb: Any, i0v: np.ndarray, he: bool = False) -> Any:
    """Return the default artefact flags of single pixels (no neighbours: no morphology)."""
    p = {**DEFAULTS, "he": he}
    if is_dask(rgb):
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


def _grow(bad: np.ndarray, weak: np.ndarray, margin: int) -> np.ndarray:
    """Return the artefact flags cleaned, grown into ink over tissue and dilated.

    Flags without a flagged 8-neighbour are dropped (speckle); the ``weak`` regions that
    touch what is left are added where ink flags are at least ``_GROW_SHARE`` of them
    (hysteresis); the result grows by ``margin`` pixels.
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
        labels, count = ndimage.label(weak | core, structure=cross)
        size = np.bincount(labels.reshape(-1), minlength=count + 1)
        flags = np.bincount(labels[core & weak], minlength=count + 1)
        hit = np.flatnonzero(flags >= _GROW_SHARE * size)
        core |= np.isin(labels, hit[hit > 0])
    if weak.any() and core.any():
        core |= _stroke(core & weak, weak | core)
    if margin == 0:
        return core
    return ndimage.binary_dilation(core, structure=cross, iterations=margin)


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
    rgb: np.ndarray, log_i0: np.ndarray, p: dict[str, Any], glass: bool, beta: float
) -> np.ndarray:
    od = _od(rgb, log_i0)
    keep = ~_grow(*_artefacts(rgb, od, p), p["margin"])
    if glass:
        keep &= (od * od).sum(axis=-1) >= beta * beta
    return keep


#: The defaults of :func:`imageform.analysis.tissue_mask`'s thresholds.
DEFAULTS: dict[str, Any] = {
    "pen": True,
    "dark": True,
    "he": False,
    "pen_min_od": 0.3,
    "dark_luminance": _DARK_LUMA,
    "margin": 1,
}


def keep_mask(rgb: Any, i0v: np.ndarray, params: dict[str, Any], glass: bool, beta: float) -> Any:
    """Return the tissue mask of an image (NumPy or Dask) with a resolved I0."""
    log_i0 = np.log(i0v)
    if not is_dask(rgb):
        return _block(np.asarray(rgb), log_i0, params, glass, beta)
    reach = params["margin"] + 1 + (_STROKE_RADIUS + _STROKE_REACH if params["pen"] else 0)
    depth = dict.fromkeys((rgb.ndim - 3, rgb.ndim - 2), reach)
    whole = rgb.rechunk({rgb.ndim - 1: 3})

    def block(blk: np.ndarray) -> np.ndarray:
        keep = _block(blk, log_i0, params, glass, beta)
        return np.repeat(keep[..., None], 3, axis=-1)  # the block's shape: trimmed as is

    over = whole.map_overlap(
        block, depth={**depth, rgb.ndim - 1: 0}, boundary="none", dtype=bool, trim=True
    )
    return over[..., 0]
