"""HSV tissue segmentation (the lecture's endoscopy case study), overlays and IoU.

Thresholds on hue, saturation and value, a hue range that may wrap through red (0°/360°),
then morphological clean-up: opening and closing with a disc, and removal of connected
components smaller than ``min_area`` pixels. Works in memory (NumPy) and lazily on Dask
arrays (the clean-up runs chunk-wise with an overlap wide enough to make it exact).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform._backend import use_numba
from imageform._colormath import rgb_to_hsv
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_reals,
    check_memory,
    describe,
    dtype_kind,
    format_shape,
)
from imageform.analysis._arrays import image_in, is_dask
from imageform.errors import DegenerateConfigurationError, ImageformWarning, InvalidInputError

__all__ = [
    "LECTURE_OPENCV",
    "EmptyMaskWarning",
    "HsvSegmentation",
    "disc",
    "mask_iou",
    "overlay_mask",
    "segment_hsv",
]


#: The lecture's endoscopy thresholds in OpenCV 8-bit units: H, S, V (low, high).
LECTURE_OPENCV = ((0.0, 20.0), (30.0, 255.0), (80.0, 255.0))


class EmptyMaskWarning(ImageformWarning):
    """A segmentation selected no pixel (check the thresholds and their units)."""


@dataclass(frozen=True)
class HsvSegmentation:
    """Result of :func:`segment_hsv`: the mask and what was applied to get it.

    ``h`` is in degrees (``h[0] > h[1]`` wraps through 0°), ``s`` and ``v`` in [0, 1],
    whatever units the caller used. ``raw_mask`` is the thresholded mask before clean-up.
    ``mask`` and ``raw_mask`` are Dask arrays when the image was.
    """

    mask: Any
    raw_mask: Any
    h: tuple[float, float]
    s: tuple[float, float]
    v: tuple[float, float]
    open_radius: int
    close_radius: int
    min_area: int

    @property
    def fraction(self) -> float:
        """Fraction of pixels in the mask (tissue fraction); computes a Dask mask."""
        return float(self.mask.mean())

    @property
    def wraps(self) -> bool:
        """True when the hue range wraps through 0° (red)."""
        return self.h[0] > self.h[1]


def disc(radius: int) -> np.ndarray:
    """Boolean disc structuring element of ``radius`` pixels: ``x² + y² <= r²``.

    Examples
    --------
    >>> disc(1).astype(int).tolist()
    [[0, 1, 0], [1, 1, 1], [0, 1, 0]]
    """
    return _disc(as_int(radius, "radius", minimum=0), "radius")


def _disc(r: int, name: str) -> np.ndarray:
    """:func:`disc` of a checked radius; refuses (naming ``name``) one that cannot fit."""
    # the int grids of np.mgrid (2 x 8 bytes) and the boolean result, per element
    check_memory(float(2 * r + 1) ** 2 * 17, name, f"a disc of radius {r}")
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    return np.asarray(x * x + y * y <= r * r)


def _pair(
    value: object, name: str, lo: float, hi: float, unit: str, cv_max: float | None = None
) -> tuple[float, float]:
    try:
        n = len(value)  # type: ignore[arg-type]
    except TypeError:
        n = -1
    if isinstance(value, str | bytes) or n != 2:
        raise InvalidInputError(f"expected {name} as a (low, high) pair, got {describe(value)}")
    if dtype_kind(value) not in "iuf":  # no object, string, complex or bool arrays
        raise InvalidInputError(f"expected {name} as two real numbers, got {describe(value)}")
    a, b = (as_real(v, name) for v in value)  # type: ignore[attr-defined]
    for v in (a, b):
        if not (math.isfinite(v) and lo <= v <= hi):
            # S and V of 30:255 are OpenCV's 8-bit codes, given without opencv_ranges
            cv = cv_max is not None and all(lo <= x <= cv_max for x in (a, b))
            hint = f"; OpenCV's 0 to {cv_max:g} codes with opencv_ranges=True" if cv else ""
            raise InvalidInputError(
                f"expected {name} bounds in [{lo:g}, {hi:g}] ({unit}), got {describe(value)}{hint}"
            )
    return a, b


def _threshold(
    rgb: np.ndarray, h: tuple[float, float], s: tuple[float, float], v: tuple[float, float]
) -> np.ndarray:
    if use_numba(rgb):  # the colour module's kernel, for any size: chunks = whole image
        from imageform._kernels import color_simple

        hsv, _ = color_simple.srgb_to_hsv(rgb)
    else:
        hsv = rgb_to_hsv(np, rgb)
    hue, sat, val = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    lo, hi = hue >= h[0], hue <= h[1]
    in_h = (lo & hi) if h[0] <= h[1] else (lo | hi)  # wrap: [h0, 360) ∪ [0, h1]
    return np.asarray(in_h & (sat >= s[0]) & (sat <= s[1]) & (val >= v[0]) & (val <= v[1]))


def _clean(mask: np.ndarray, open_radius: int, close_radius: int, min_area: int) -> np.ndarray:
    """Apply an opening, a closing, then remove 8-connected components below ``min_area``.

    Erosions treat the outside of the image as foreground (``border_value=1``), dilations
    as background, so tissue touching the frame is not eaten away from the border.
    """
    from scipy import ndimage

    out = mask
    if open_radius > 0:
        d = _disc(open_radius, "open_radius")
        out = ndimage.binary_dilation(ndimage.binary_erosion(out, d, border_value=1), d)
    if close_radius > 0:
        d = _disc(close_radius, "close_radius")
        out = ndimage.binary_erosion(ndimage.binary_dilation(out, d), d, border_value=1)
    if min_area > 1 and out.any():
        labels, n = ndimage.label(out, structure=np.ones((3, 3), dtype=bool))
        areas = np.bincount(labels.ravel(), minlength=n + 1)
        keep = areas >= min_area
        keep[0] = False
        out = keep[labels]
    return np.asarray(out, dtype=bool)


def segment_hsv(
    image: ArrayLike,
    h: tuple[float, float] | None = None,
    s: tuple[float, float] | None = None,
    v: tuple[float, float] | None = None,
    *,
    opencv_ranges: bool = False,
    open_radius: int = 2,
    close_radius: int = 2,
    min_area: int = 64,
) -> HsvSegmentation:
    r"""Tissue mask from hue, saturation and value thresholds, cleaned up morphologically.

    .. math::
        M = [H \in [h_0, h_1]] \wedge [s_0 \le S \le s_1] \wedge [v_0 \le V \le v_1],
        \qquad [h_0, h_1] = [h_0, 360) \cup [0, h_1] \text{ when } h_0 > h_1,

    then :math:`M \leftarrow (M \ominus D_o) \oplus D_o` (opening with a disc of radius
    ``open_radius``), :math:`M \leftarrow (M \oplus D_c) \ominus D_c` (closing), and
    8-connected components of fewer than ``min_area`` pixels are removed.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB in [0, 1], uint8 or uint16; or a Dask array of that shape.
    h, s, v : (float, float)
        Inclusive ranges. Hue in degrees [0, 360], S and V in [0, 1] by default; with
        ``opencv_ranges=True`` OpenCV's 8-bit units: H in [0, 180], S and V in [0, 255].
        ``h[0] > h[1]`` wraps through red (340:20 degrees, 170:10 in OpenCV units).
        ``None`` takes the lecture's case study, H ∈ [0, 20], S ∈ [30, 255],
        V ∈ [80, 255] in OpenCV units (0°..40°, 30/255..1, 80/255..1), whichever units
        the other ranges are given in.
    opencv_ranges : bool
        Read ``h``, ``s``, ``v`` in OpenCV's units (``cv2.COLOR_RGB2HSV`` on uint8).
    open_radius, close_radius : int
        Disc radii of the opening and closing (0 skips the step).
    min_area : int
        Components smaller than this (pixels, 8-connectivity) are removed (0 or 1 keeps
        all).

    Returns
    -------
    HsvSegmentation
        ``mask`` (bool, shape (H, W)) and the thresholds as applied (degrees, unit ranges).

    Notes
    -----
    OpenCV stores H/2 rounded to an integer, so its test ``H_cv <= 20`` accepts hues below
    41°; here hue is continuous and ``h=(0, 20)`` in OpenCV units means 0°..40° exactly.
    Where S = 0 the hue is undefined and reads 0° (red): keep ``s[0] > 0``.
    A mask that comes out empty raises :class:`EmptyMaskWarning` (NumPy input only: a
    Dask mask is not computed here).

    Dask: thresholds run chunk-wise; the clean-up runs with ``map_overlap`` of depth
    ``2 open_radius + 2 close_radius + min_area`` — a component smaller than ``min_area``
    cannot reach further than that, so the result equals the in-memory one exactly as
    long as every chunk is at least that deep (Dask rechunks otherwise).

    Source: the lecture's endoscopy case study (OpenCV thresholds); morphology as in
    Gonzalez & Woods, *Digital Image Processing*, 4th ed., sec. 9.3 (opening/closing).

    Examples
    --------
    >>> img = np.zeros((40, 40, 3)); img[10:30, 10:30] = (0.8, 0.3, 0.3)
    >>> seg = segment_hsv(img, (0, 20), (30, 255), (80, 255), opencv_ranges=True)
    >>> int(seg.mask.sum()), round(seg.fraction, 4)
    (388, 0.2425)
    """
    rgb = image_in(image)
    if rgb.ndim != 3:
        raise InvalidInputError(
            f"expected image of shape (H, W, 3), got {format_shape(tuple(rgb.shape))}"
        )
    if opencv_ranges:
        h, s, v = (LECTURE_OPENCV[i] if r is None else r for i, r in enumerate((h, s, v)))
        hh = _pair(h, "h", 0.0, 180.0, "OpenCV hue units")
        ss = _pair(s, "s", 0.0, 255.0, "OpenCV units")
        vv = _pair(v, "v", 0.0, 255.0, "OpenCV units")
        hh = (hh[0] * 2.0, hh[1] * 2.0)
        ss = (ss[0] / 255.0, ss[1] / 255.0)
        vv = (vv[0] / 255.0, vv[1] / 255.0)
    else:
        h = (2.0 * LECTURE_OPENCV[0][0], 2.0 * LECTURE_OPENCV[0][1]) if h is None else h
        s = (LECTURE_OPENCV[1][0] / 255, LECTURE_OPENCV[1][1] / 255) if s is None else s
        v = (LECTURE_OPENCV[2][0] / 255, LECTURE_OPENCV[2][1] / 255) if v is None else v
        hh = _pair(h, "h", 0.0, 360.0, "degrees")
        ss = _pair(s, "s", 0.0, 1.0, "unit range", 255.0)
        vv = _pair(v, "v", 0.0, 1.0, "unit range", 255.0)
    for name, (a, b) in (("s", ss), ("v", vv)):
        if a > b:
            raise InvalidInputError(f"expected {name} low <= high, got {a:g} > {b:g}")
    radii = []
    for name, val in (
        ("open_radius", open_radius),
        ("close_radius", close_radius),
        ("min_area", min_area),
    ):
        if isinstance(val, bool) or not isinstance(val, int | np.integer) or val < 0:
            raise InvalidInputError(f"expected {name} as an integer >= 0, got {describe(val)}")
        radii.append(int(val))
    ro, rc, area = radii
    for name, r in (("open_radius", ro), ("close_radius", rc)):
        check_memory(float(2 * r + 1) ** 2 * 17, name, f"a disc of radius {r}")
    if is_dask(rgb):
        raw = rgb.map_blocks(_threshold, hh, ss, vv, drop_axis=2, dtype=bool)
        depth = 2 * ro + 2 * rc + area
        if depth == 0:
            mask = raw
        else:
            # dask refuses an overlap deeper than the array; deeper than that changes nothing
            depth_ax = {ax: min(depth, int(n)) for ax, n in enumerate(raw.shape)}
            mask = raw.map_overlap(
                _clean,
                depth=depth_ax,
                boundary="none",
                dtype=bool,
                open_radius=ro,
                close_radius=rc,
                min_area=area,
            )
    else:
        raw = _threshold(rgb, hh, ss, vv)
        mask = _clean(raw, ro, rc, area)
        if not mask.any():
            warnings.warn(
                f"segment_hsv: empty mask (h={hh} degrees, s={ss}, v={vv}; "
                f"{int(raw.sum())} pixels before clean-up); check the ranges and their units",
                EmptyMaskWarning,
                stacklevel=2,
            )
    return HsvSegmentation(mask, raw, hh, ss, vv, ro, rc, area)


def _mask_in(mask: object, name: str) -> Any:
    m: Any = mask if is_dask(mask) else np.asarray(mask)
    if m.ndim != 2:
        raise InvalidInputError(f"expected {name} of shape (H, W), got {format_shape(m.shape)}")
    if np.dtype(m.dtype) != np.bool_:
        raise InvalidInputError(f"expected {name} as a boolean array, got dtype {m.dtype}")
    return m


def overlay_mask(
    image: ArrayLike,
    mask: ArrayLike,
    color: tuple[float, float, float] = (0.0, 1.0, 0.0),
    alpha: float = 0.4,
) -> Array:
    r"""Blend ``color`` over the masked pixels: :math:`I' = (1 - \alpha M) I + \alpha M c`.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB (floats in [0, 1], uint8, uint16, or Dask).
    mask : array_like of bool, shape (H, W)
        The pixels to tint.
    color : (float, float, float)
        Encoded sRGB in [0, 1].
    alpha : float
        Opacity in [0, 1].

    Returns
    -------
    array, shape (H, W, 3)
        Floats in [0, 1] (float32 for integer input); Dask when the image was.

    Examples
    --------
    >>> img = np.full((2, 2, 3), 0.5); m = np.array([[True, False], [False, False]])
    >>> overlay_mask(img, m, (1.0, 0.0, 0.0), 0.5)[0, 0].tolist()
    [0.75, 0.25, 0.25]
    """
    rgb = image_in(image)
    m = _mask_in(mask, "mask")
    if tuple(m.shape) != tuple(rgb.shape[:-1]):
        raise InvalidInputError(
            f"expected mask of shape {format_shape(rgb.shape[:-1])}, got {format_shape(m.shape)}"
        )
    a = as_real(alpha, "alpha")
    if not 0.0 <= a <= 1.0:
        raise InvalidInputError(f"expected alpha in [0, 1], got {a:g}")
    c = np.asarray(as_reals(color, "color", 3), dtype=rgb.dtype)
    if not np.all((c >= 0) & (c <= 1)):
        raise InvalidInputError(f"expected color as 3 values in [0, 1], got {describe(color)}")
    w = m[..., None].astype(rgb.dtype) * rgb.dtype.type(a)
    return rgb * (1 - w) + w * c


def mask_iou(a: ArrayLike, b: ArrayLike) -> float:
    r"""Intersection over union of two boolean masks: :math:`|A \cap B| / |A \cup B|`.

    Two empty masks have no IoU: :class:`DegenerateConfigurationError`.

    Source: Jaccard index (P. Jaccard, 1901); the usual segmentation score.

    Examples
    --------
    >>> mask_iou(np.array([[True, True], [False, False]]), np.array([[True, False], [True, False]]))
    0.3333333333333333
    """
    ma, mb = _mask_in(a, "a"), _mask_in(b, "b")
    if tuple(ma.shape) != tuple(mb.shape):
        raise InvalidInputError(
            f"expected masks a and b of the same shape, got {format_shape(ma.shape)} and "
            f"{format_shape(mb.shape)}"
        )
    inter = (ma & mb).sum()
    union = (ma | mb).sum()
    if is_dask(inter) or is_dask(union):
        import dask

        inter, union = dask.compute(inter, union)
    if int(union) == 0:
        raise DegenerateConfigurationError("IoU of two empty masks is undefined")
    return float(inter) / float(union)
