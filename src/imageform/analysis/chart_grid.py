"""Patch values of a colour chart cropped to fill the frame.

:class:`ChartPatches` and :func:`chart_patches` (the grid sampler), and the
:class:`ChartWarning` both chart samplers raise. Below :mod:`~imageform.analysis.harmonize`
(which fits corrections to the patches), :mod:`~imageform.analysis.chart_detect` (which
measures them in photographs) and
:mod:`~imageform.analysis.chart_input` (which picks the sampler), so that the fit can take
chart images without a module cycle; :mod:`imageform.analysis.harmonize` re-exports all three.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import as_int, as_real, describe, format_shape, real_array
from imageform.analysis._arrays import image_in, is_dask
from imageform.errors import ImageformWarning, InvalidInputError

__all__ = ["ChartPatches", "ChartWarning", "chart_patches"]


class ChartWarning(ImageformWarning):
    """Chart patches were saturated or missing and are left out of the fit."""


@dataclass(frozen=True)
class ChartPatches:
    """Patch statistics of a chart image (row by row).

    Encoded sRGB ``means`` (N, 3), the per-patch ``std`` (N, 3), which patches are ``saturated``
    or ``missing``, and ``used`` (N,): the share of each patch's sampled pixels that went into
    its mean (all 1 by default: every pixel did; under 1 where
    :func:`~imageform.analysis.measure_chart_patches` left out pixels of a mark over the patch).
    """

    means: np.ndarray
    std: np.ndarray
    saturated: np.ndarray
    missing: np.ndarray
    used: np.ndarray = field(default_factory=lambda: np.ones(0))

    def __post_init__(self) -> None:
        """``means`` and ``std`` of shape (N, 3), the flags booleans of shape (N,)."""
        means = real_array(self.means, "means", (None, 3), finite=False)
        n = means.shape[0]
        std = real_array(self.std, "std", (None, 3), finite=False)
        if std.shape[0] != n:
            raise InvalidInputError(
                f"expected means and std with the same number of patches, got {n} and "
                f"{std.shape[0]}"
            )
        object.__setattr__(self, "means", means)
        object.__setattr__(self, "std", std)
        for name in ("saturated", "missing"):
            flag = getattr(self, name)
            arr = np.asarray(flag) if not isinstance(flag, str | bytes) else None
            if arr is None or arr.dtype != np.bool_ or arr.shape != (n,):
                raise InvalidInputError(
                    f"expected {name} as booleans of shape ({n},), got {describe(flag)}"
                )
            object.__setattr__(self, name, arr)
        for name, arr in (("means", means), ("std", std)):
            bad = ~np.all(np.isfinite(arr), axis=1) & ~self.missing
            if bad.any():
                raise InvalidInputError(
                    f"{name} has NaN or inf in patch(es) {np.flatnonzero(bad).tolist()[:8]} "
                    "not marked missing"
                )
        if np.any(std < 0):
            raise InvalidInputError(f"expected std >= 0, got min {float(np.nanmin(std)):g}")
        used = real_array(self.used, "used", (None,))
        if used.size == 0 and n:  # the default: every pixel of every patch
            used = np.ones(n)
        if used.shape != (n,):
            raise InvalidInputError(f"expected used of shape ({n},), got {describe(self.used)}")
        if np.any(used < 0) or np.any(used > 1):
            raise InvalidInputError(f"expected used in [0, 1], got {describe(self.used)}")
        object.__setattr__(self, "used", used)

    @property
    def valid(self) -> np.ndarray:
        """Patches usable for a fit: neither saturated nor missing."""
        return np.asarray(~self.saturated & ~self.missing)


#: Robust sigmas (1.4826 x the median absolute deviation, per channel) within which a pixel
#: agrees with its patch's dominant colour, and the least such tolerance (encoded [0, 1]
#: units, about 5 / 255: a flat rendered patch has no spread at all).
_CLEAN_SIGMAS, _CLEAN_FLOOR = 4.0, 0.02


def _kept_median(px: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Per-channel median (..., 1, 3) of the pixels (..., N, 3) where ``keep`` (..., N).

    ``np.nanmedian`` of the pixels with the others NaN, the same values (the middle one, or
    the mean of the middle two), from one sort instead of masked arrays; NaN where none is
    kept.
    """
    srt = np.sort(np.where(keep[..., None], px, np.inf), axis=-2)
    n = keep.sum(axis=-1)[..., None, None]
    lo = np.broadcast_to(np.maximum(n - 1, 0) // 2, (*px.shape[:-2], 1, px.shape[-1]))
    hi = np.broadcast_to(n // 2, lo.shape)
    hi = np.minimum(hi, px.shape[-2] - 1)
    mid = (np.take_along_axis(srt, lo, axis=-2) + np.take_along_axis(srt, hi, axis=-2)) / 2
    return np.where(n > 0, mid, np.nan)


def _clean_pixels(px: np.ndarray) -> np.ndarray:
    """Mask of the pixels (..., N, 3) that agree with their patch's dominant colour.

    The per-channel median of the pixels and their spread (1.4826 x the median absolute
    deviation, at least ``_CLEAN_FLOOR / _CLEAN_SIGMAS``) give the dominant colour; pixels more
    than ``_CLEAN_SIGMAS`` spreads from it in any channel (a label, a pen stroke, a sticker, a
    reflection, a finger over part of the patch) are left out, and the median and spread are
    taken again over the rest (twice). The median belongs to the clean part as long as the
    marks cover under half the pixels. Leading axes are separate patches.
    """
    keep = np.ones(px.shape[:-1], dtype=bool)
    for _ in range(2):
        if keep.all():
            med = np.median(px, axis=-2, keepdims=True)
            mad = 1.4826 * np.median(np.abs(px - med), axis=-2, keepdims=True)
        else:
            med = _kept_median(px, keep)
            mad = 1.4826 * _kept_median(np.abs(px - med), keep)
        tol = np.maximum(_CLEAN_SIGMAS * mad, _CLEAN_FLOOR)
        keep = (np.abs(px - med) <= tol).all(axis=-1)
    return np.asarray(keep)


def chart_patches(
    image: ArrayLike,
    rows: int = 4,
    cols: int = 6,
    *,
    margin: float = 0.25,
    max_std: float = 0.04,
    saturation: float = 1.0,
    max_saturated_fraction: float = 0.01,
) -> ChartPatches:
    """Mean encoded sRGB of each patch of a chart that fills the frame.

    Assumption: the image is cropped to the chart so that a ``rows × cols`` grid of equal
    cells covers it (one patch per cell, the ColorChecker's 4 × 6 by default). The central
    ``1 - 2 margin`` of each cell is averaged, away from patch edges and gaps.

    A patch is **missing** when its sampled region is not flat (any channel's standard
    deviation above ``max_std``: the grid misses the patch, an edge or the surround runs
    through it), and **saturated** when more than ``max_saturated_fraction`` of its pixels
    reach ``saturation`` in some channel (clipped by the sensor). Both raise a
    :class:`ChartWarning` naming the patches; :func:`fit_color_correction` leaves them out.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB (floats, uint8, uint16) or Dask (the cells are reduced by Dask).
    rows, cols : int
        The grid of patches that fills the frame (4 × 6 for the ColorChecker Classic).
    margin : float, keyword-only
        Fraction of each cell left out on every side, in [0, 0.5).
    max_std : float, keyword-only
        Largest per-channel standard deviation (encoded, [0, 1] scale) of a flat patch.
    saturation : float, keyword-only
        The clipping level (encoded, [0, 1] scale).
    max_saturated_fraction : float, keyword-only
        Fraction of a patch's pixels at ``saturation`` above which it is saturated.

    Returns
    -------
    ChartPatches

    Examples
    --------
    >>> from imageform.analysis import synthetic_chart_image
    >>> p = chart_patches(synthetic_chart_image())
    >>> (p.means[0] * 255).round(3).tolist(), bool(p.valid.all())
    ([115.0, 82.0, 68.0], True)
    """
    rgb = image_in(image)
    if rgb.ndim != 3:
        raise InvalidInputError(
            f"expected image of shape (H, W, 3), got {format_shape(tuple(rgb.shape))}"
        )
    rows = as_int(rows, "rows", minimum=1)
    cols = as_int(cols, "cols", minimum=1)
    margin = as_real(margin, "margin")
    max_std = as_real(max_std, "max_std", nonnegative=True)
    saturation = as_real(saturation, "saturation", positive=True)
    max_saturated_fraction = as_real(
        max_saturated_fraction, "max_saturated_fraction", minimum=0.0, maximum=1.0
    )
    hgt, wid = int(rgb.shape[0]), int(rgb.shape[1])
    if rows < 1 or cols < 1 or hgt < 2 * rows or wid < 2 * cols:
        raise InvalidInputError(
            f"expected rows, cols >= 1 with at least 2 pixels per cell, got {rows}x{cols} "
            f"for an image of {hgt}x{wid}"
        )
    if not 0.0 <= margin < 0.5:
        raise InvalidInputError(f"expected margin in [0, 0.5), got {margin!r}")
    means, stds, sat = [], [], []
    for i in range(rows):
        for j in range(cols):
            y0, y1 = hgt * i / rows, hgt * (i + 1) / rows
            x0, x1 = wid * j / cols, wid * (j + 1) / cols
            dy, dx = (y1 - y0) * margin, (x1 - x0) * margin
            ya, yb = int(np.ceil(y0 + dy)), max(int(np.floor(y1 - dy)), int(np.ceil(y0 + dy)) + 1)
            xa, xb = int(np.ceil(x0 + dx)), max(int(np.floor(x1 - dx)), int(np.ceil(x0 + dx)) + 1)
            cell = rgb[ya:yb, xa:xb].reshape((-1, 3)).astype(np.float64)
            means.append(cell.mean(axis=0))
            stds.append(cell.std(axis=0))
            sat.append((cell >= saturation).any(axis=1).mean())
    if is_dask(rgb):
        import dask

        means, stds, sat = dask.compute(means, stds, sat)
    m, sd = np.asarray(means), np.asarray(stds)
    saturated = np.asarray(sat) > max_saturated_fraction
    missing = np.asarray((sd > max_std).any(axis=1))
    bad = {"saturated": np.flatnonzero(saturated), "missing": np.flatnonzero(missing)}
    if not (~saturated & ~missing).any():
        raise InvalidInputError(
            f"no usable chart patch in the {rows}x{cols} grid: {bad['saturated'].size} "
            f"saturated (>= saturation={saturation:g}), {bad['missing'].size} missing (std > "
            f"max_std={max_std:g} with margin={margin:g}); does the chart fill the frame?"
        )
    for what, idx in bad.items():
        if idx.size:
            warnings.warn(
                f"chart_patches: {idx.size} {what} patch(es) {idx.tolist()} (0-based, row by "
                "row) will be left out of a fit",
                ChartWarning,
                stacklevel=2,
            )
    return ChartPatches(m, sd, saturated, missing)
