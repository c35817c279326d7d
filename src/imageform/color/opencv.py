"""OpenCV's colour conventions, by name: read and write them to compare with OpenCV code.

imageform's own arrays are RGB, floats, H in degrees [0, 360), L* in [0, 100]. OpenCV's
``cvtColor`` differs in ways that silently break ported code (docs/opencv-pitfalls.md):

================  ==========================================================================
``"bgr"``         channel order B, G, R (``cv2.imread`` returns BGR)
``"hsv8"``        uint8 HSV: H/2 in [0, 180), S and V x 255 (``COLOR_RGB2HSV`` on uint8)
``"hsv8_full"``   uint8 HSV: H x 255/360 in [0, 256) (``COLOR_RGB2HSV_FULL``)
``"lab8"``        uint8 Lab: L* x 255/100, a* + 128, b* + 128 (``COLOR_RGB2Lab`` on uint8)
``"ycrcb8"``      uint8 Y, Cr, Cb order, full range, offset 128 (``COLOR_RGB2YCrCb``)
``"ycrcb"``       float Y, Cr, Cb order, offset 0.5 (``COLOR_RGB2YCrCb`` on float32)
================  ==========================================================================

:func:`to_opencv` turns imageform values into OpenCV's layout (rounding to uint8 where
OpenCV does); :func:`from_opencv` reads OpenCV's layout back into imageform's.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any

from imageform._backend import namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_float_strict,
    as_image_strict,
    check_name,
)
from imageform.errors import InvalidInputError

__all__ = ["OPENCV_CONVENTIONS", "bgr_to_srgb", "from_opencv", "srgb_to_bgr", "to_opencv"]

#: Convention names accepted by :func:`to_opencv` / :func:`from_opencv`, with the imageform
#: space each one is a layout of (read-only).
OPENCV_CONVENTIONS: MappingProxyType[str, str] = MappingProxyType(
    {
        "bgr": "srgb",
        "hsv8": "hsv",
        "hsv8_full": "hsv",
        "lab8": "lab",
        "ycrcb8": "ycbcr",
        "ycrcb": "ycbcr",
    }
)


def _flip(xp: Any, x: Any) -> Any:
    return xp.stack([x[..., 2], x[..., 1], x[..., 0]], axis=-1)


@chunkwise(1)
def srgb_to_bgr(image: ArrayLike) -> Array:
    """Reverse the channel order RGB -> BGR (values unchanged).

    Examples
    --------
    >>> srgb_to_bgr([1.0, 0.5, 0.0]).tolist()
    [0.0, 0.5, 1.0]
    """
    x = as_image_strict(image, "sRGB image")
    return _flip(namespace(x), x)


@chunkwise(1)
def bgr_to_srgb(image: ArrayLike) -> Array:
    """Reverse the channel order BGR -> RGB (``cv2.imread`` output to imageform's order).

    Examples
    --------
    >>> bgr_to_srgb([0.0, 0.5, 1.0]).tolist()
    [1.0, 0.5, 0.0]
    """
    x = as_image_strict(image, "BGR image")
    return _flip(namespace(x), x)


def _round_u8(xp: Any, x: Any) -> Any:
    # OpenCV saturates (rounds half to even, then clips) when it writes 8-bit values.
    return xp.astype(xp.clip(xp.round(x), 0, 255), xp.uint8)


@chunkwise(1)
def to_opencv(values: ArrayLike, convention: str) -> Array:
    """Convert imageform values (float, RGB order, degrees) to OpenCV's layout ``convention``.

    Parameters
    ----------
    values : array_like, shape (..., 3)
        ``bgr``: encoded sRGB; ``hsv8*``: HSV (H degrees, S, V in [0, 1]);
        ``lab8``: CIELAB; ``ycrcb*``: full-range analog Y'CbCr (Y' in [0, 1], Cb, Cr in
        [-0.5, 0.5], as :func:`imageform.color.srgb_to_ycbcr` returns by default).
    convention : str
        A key of :data:`OPENCV_CONVENTIONS`.

    Returns
    -------
    array, shape (..., 3)
        uint8 for the ``*8`` conventions (rounded and saturated as OpenCV does), else float.

    Notes
    -----
    Source: OpenCV 4.x/5.x documentation, "Color conversions" (imgproc module).

    Examples
    --------
    >>> to_opencv([200.0, 0.5, 1.0], "hsv8").tolist()
    [100, 128, 255]
    >>> to_opencv([60.0, -10.0, 20.0], "lab8").tolist()
    [153, 118, 148]
    """
    conv = check_name(convention, OPENCV_CONVENTIONS, "OpenCV convention")
    x = as_float_strict(values, "values", integer="float32")
    if x.ndim < 1 or x.shape[-1] != 3:
        raise InvalidInputError(
            f"expected values with 3 channels on axis -1, got shape {tuple(x.shape)}"
        )
    xp = namespace(x)
    h, a, b = x[..., 0], x[..., 1], x[..., 2]
    if conv == "bgr":
        return _flip(xp, x)
    if conv == "hsv8":
        return _round_u8(xp, xp.stack([h / 2.0, a * 255.0, b * 255.0], axis=-1))
    if conv == "hsv8_full":
        return _round_u8(xp, xp.stack([h * (255.0 / 360.0), a * 255.0, b * 255.0], axis=-1))
    if conv == "lab8":
        return _round_u8(xp, xp.stack([h * (255.0 / 100.0), a + 128.0, b + 128.0], axis=-1))
    if conv == "ycrcb8":
        return _round_u8(xp, xp.stack([h * 255.0, b * 255.0 + 128.0, a * 255.0 + 128.0], axis=-1))
    return xp.stack([h, b + 0.5, a + 0.5], axis=-1)  # ycrcb (float)


@chunkwise(1)
def from_opencv(values: ArrayLike, convention: str) -> Array:
    """OpenCV's layout ``convention`` back to imageform values (float, RGB order, degrees).

    uint8 input is read as OpenCV's code values (not divided by 255 first). The result is
    float32 for integer input.

    Examples
    --------
    >>> from_opencv([100.0, 128.0, 255.0], "hsv8").round(4).tolist()
    [200.0, 0.502, 1.0]
    >>> from_opencv([153, 118, 148], "lab8").round(3).tolist()
    [60.0, -10.0, 20.0]
    """
    conv = check_name(convention, OPENCV_CONVENTIONS, "OpenCV convention")
    x = as_float_strict(values, "values", integer="float32")
    if x.ndim < 1 or x.shape[-1] != 3:
        raise InvalidInputError(
            f"expected values with 3 channels on axis -1, got shape {tuple(x.shape)}"
        )
    xp = namespace(x)
    p, q, r = x[..., 0], x[..., 1], x[..., 2]
    if conv == "bgr":
        return _flip(xp, x)
    if conv == "hsv8":
        return xp.stack([p * 2.0, q / 255.0, r / 255.0], axis=-1)
    if conv == "hsv8_full":
        return xp.stack([p * (360.0 / 255.0), q / 255.0, r / 255.0], axis=-1)
    if conv == "lab8":
        return xp.stack([p * (100.0 / 255.0), q - 128.0, r - 128.0], axis=-1)
    if conv == "ycrcb8":
        return xp.stack([p / 255.0, (r - 128.0) / 255.0, (q - 128.0) / 255.0], axis=-1)
    return xp.stack([p, r - 0.5, q - 0.5], axis=-1)  # ycrcb (float)
