"""Grey from colour: Rec. 601 luma on encoded values, Rec. 709 luminance on linear light.

Two different quantities share the name "grey":

- **luma** :math:`Y' = 0.299 R' + 0.587 G' + 0.114 B'` — a weighted sum of the *encoded*
  values with BT.601's weights. This is the lecture's formula and OpenCV's
  ``COLOR_RGB2GRAY``.
- **relative luminance** :math:`Y = 0.2126 R + 0.7152 G + 0.0722 B` — the same sum of
  *linear* values with BT.709 / sRGB weights; it is the Y of CIE XYZ and the physically
  right brightness. ``method="rec709"`` computes Y and re-encodes it with the sRGB curve,
  so that both methods return encoded grey values comparable with each other.

Grey images have a channel axis of size 1: shape (..., 1).
"""

from __future__ import annotations

from typing import Any, Literal

from imageform._backend import namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image_strict, check_name

from .transfer import _srgb_decode, _srgb_encode

__all__ = [
    "GRAY_METHODS",
    "gray_to_srgb",
    "linear_srgb_to_luminance",
    "srgb_to_gray",
]

# ITU-R BT.601-7, item 2.5.1 (luma weights, as the lecture states them).
_REC601 = (0.299, 0.587, 0.114)
# ITU-R BT.709-6, Part 1, item 3.2 (= the Y row of the sRGB matrix to 4 decimals).
_REC709 = (0.2126, 0.7152, 0.0722)

#: Methods of :func:`srgb_to_gray`.
GRAY_METHODS: tuple[str, ...] = ("rec601", "rec709")


def _weighted(x: Any, w: tuple[float, float, float]) -> Any:
    return w[0] * x[..., 0:1] + w[1] * x[..., 1:2] + w[2] * x[..., 2:3]


def _srgb_to_gray(xp: Any, x: Any, method: str) -> Any:
    if method == "rec601":
        return _weighted(x, _REC601)
    return _srgb_encode(xp, _weighted(_srgb_decode(xp, x), _REC709))


def _gray_to_srgb(xp: Any, g: Any) -> Any:
    return xp.concat([g, g, g], axis=-1)


@chunkwise(1)
def srgb_to_gray(image: ArrayLike, method: Literal["rec601", "rec709"] = "rec601") -> Array:
    r"""Convert encoded sRGB to an encoded grey image, shape (..., 1).

    .. math::
        \text{rec601:}\; Y' = 0.299 R' + 0.587 G' + 0.114 B' \qquad
        \text{rec709:}\; Y' = \mathrm{enc}(0.2126 R + 0.7152 G + 0.0722 B)

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded sRGB in [0, 1] or uint8/uint16.
    method : {"rec601", "rec709"}
        Luma of encoded values (the lecture, OpenCV) or luminance of linear values.

    Returns
    -------
    array, shape (..., 1)

    Notes
    -----
    Source: ITU-R BT.601-7 item 2.5.1; ITU-R BT.709-6 item 3.2; IEC 61966-2-1 (the curve).

    Examples
    --------
    >>> srgb_to_gray([1.0, 0.0, 0.0]).tolist()
    [0.299]
    >>> round(float(srgb_to_gray([1.0, 0.0, 0.0], "rec709")[0]), 4)
    0.4984
    """
    m = check_name(method, GRAY_METHODS, "grey method")
    x = as_image_strict(image, "sRGB image")
    return _srgb_to_gray(namespace(x), x, m)


@chunkwise(1)
def gray_to_srgb(gray: ArrayLike) -> Array:
    """Convert a grey image (..., 1) to sRGB (..., 3) by repeating the value (R = G = B).

    Examples
    --------
    >>> gray_to_srgb([0.5]).tolist()
    [0.5, 0.5, 0.5]
    """
    x = as_image_strict(gray, "gray", channels=1)
    return _gray_to_srgb(namespace(x), x)


@chunkwise(1)
def linear_srgb_to_luminance(image: ArrayLike) -> Array:
    """Relative luminance Y of linear sRGB, shape (..., 1): the Y of CIE XYZ.

    .. math:: Y = 0.2126 R + 0.7152 G + 0.0722 B

    Source: ITU-R BT.709-6, Part 1, item 3.2.

    Examples
    --------
    >>> linear_srgb_to_luminance([0.0, 1.0, 0.0]).tolist()
    [0.7152]
    """
    x = as_image_strict(image, "linear sRGB image", range_check=False)
    return _weighted(x, _REC709)
