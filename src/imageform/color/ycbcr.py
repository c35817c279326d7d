r"""Y'CbCr (BT.601, BT.709, BT.2020): analog values and 8/10-bit code values.

The input is *encoded* R'G'B' in [0, 1] (the standards' E'R, E'G, E'B). The luma
coefficients Kr, Kb are those each standard writes; Kg = 1 - Kr - Kb:

.. math::
    E'_Y = K_r R' + K_g G' + K_b B', \quad
    E'_{Cb} = \frac{B' - E'_Y}{2 (1 - K_b)}, \quad
    E'_{Cr} = \frac{R' - E'_Y}{2 (1 - K_r)}

``signal_range`` chooses the output scale:

- ``"full"`` with ``bit_depth=None`` (default): the analog values, E'Y in [0, 1], E'Cb and E'Cr in
  [-0.5, 0.5].
- ``"full"`` with ``bit_depth=n``: full-range code values, :math:`D_Y = (2^n - 1) E'_Y`,
  :math:`D_C = (2^n - 1) E'_C + 2^{n-1}` (ITU-T H.273, eq. for VideoFullRangeFlag = 1;
  JPEG/JFIF uses n = 8 with BT.601 weights).
- ``"limited"`` (``bit_depth`` 8 unless given): studio range,
  :math:`D_Y = (219 E'_Y + 16) 2^{n-8}`, :math:`D_C = (224 E'_C + 128) 2^{n-8}`
  (BT.601-7 item 2.5.3, BT.709-6 item 4.6, BT.2020-2 Table 5).

Code values are returned as unrounded floats (so that round trips are exact); round and
cast them for storage (``np.round(d).astype(np.uint16)``). :func:`ycbcr_to_rgb` reads code
values as numbers of the given signal range, integer dtypes included (not divided by 255).
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform import _deprecate
from imageform._backend import namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_float_strict,
    as_image_strict,
    check_name,
    describe,
)
from imageform.errors import InvalidInputError

__all__ = [
    "YCBCR_STANDARDS",
    "rgb_to_ycbcr",
    "srgb_to_ycbcr",
    "ycbcr_to_rgb",
    "ycbcr_to_srgb",
]

#: Luma coefficients (Kr, Kb) as each standard writes them.
YCBCR_STANDARDS: MappingProxyType[str, tuple[float, float]] = MappingProxyType(
    {
        "bt601": (0.299, 0.114),  # ITU-R BT.601-7, item 2.5.1
        "bt709": (0.2126, 0.0722),  # ITU-R BT.709-6, Part 1, item 3.2
        "bt2020": (0.2627, 0.0593),  # ITU-R BT.2020-2, Table 4
    }
)
#: The signal ranges: "full" (0 ... 2^n - 1) and "limited" (studio: 16-235, 16-240 at 8 bits).
_RANGES = ("full", "limited")


def _coeffs(standard: str) -> tuple[str, float, float]:
    key = check_name(
        standard.replace(".", "") if isinstance(standard, str) else standard,
        YCBCR_STANDARDS,
        "Y'CbCr standard",
    )
    kr, kb = YCBCR_STANDARDS[key]
    return key, kr, kb


def _scale(signal_range: str, bits: int | None) -> tuple[float, float, float, float]:
    """(y_gain, y_offset, c_gain, c_offset) from analog to the requested scale."""
    rng = check_name(signal_range, _RANGES, "Y'CbCr signal_range")
    if bits is not None and (
        isinstance(bits, bool | np.bool_)
        or not isinstance(bits, int | np.integer)
        or bits not in (8, 10, 12)
    ):
        raise InvalidInputError(f"expected bit_depth 8, 10 or 12 (or None), got {describe(bits)}")
    if rng == "full":
        if bits is None:
            return 1.0, 0.0, 1.0, 0.0
        top = float(2**bits - 1)
        return top, 0.0, top, float(2 ** (bits - 1))
    n = 8 if bits is None else bits
    k = float(2 ** (n - 8))
    return 219.0 * k, 16.0 * k, 224.0 * k, 128.0 * k


def _check_codes(values: object, signal_range: str, bits: int | None) -> None:
    """Integer code values must fit ``bits`` (no wrap-around, no guessing of the scale)."""
    dt = getattr(values, "dtype", None)
    if dt is None or getattr(dt, "kind", "f") not in "iu":
        return
    if bits is None and signal_range == "full":
        raise InvalidInputError(
            f"integer ycbcr ({dt}) are code values: pass bit_depth=8 or bit_depth=10 (or floats)"
        )
    n = 8 if bits is None else bits
    xp = namespace(values)
    if math.prod(values.shape) and int(xp.max(values)) > 2**n - 1:  # type: ignore[attr-defined]
        raise InvalidInputError(
            f"ycbcr code values exceed the {n}-bit range (max {int(xp.max(values))} > {2**n - 1})"
        )


def _rgb_to_ycbcr(xp: Any, rgb: Any, kr: float, kb: float, sc: tuple[float, ...]) -> Any:
    kg = 1.0 - kr - kb
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    y = kr * r + kg * g + kb * b
    cb = (b - y) / (2.0 * (1.0 - kb))
    cr = (r - y) / (2.0 * (1.0 - kr))
    yg, yo, cg, co = sc
    return xp.stack([yg * y + yo, cg * cb + co, cg * cr + co], axis=-1)


def _ycbcr_to_rgb(xp: Any, ycc: Any, kr: float, kb: float, sc: tuple[float, ...]) -> Any:
    kg = 1.0 - kr - kb
    yg, yo, cg, co = sc
    y = (ycc[..., 0] - yo) / yg
    cb = (ycc[..., 1] - co) / cg
    cr = (ycc[..., 2] - co) / cg
    r = y + 2.0 * (1.0 - kr) * cr
    b = y + 2.0 * (1.0 - kb) * cb
    g = (y - kr * r - kb * b) / kg
    return xp.stack([r, g, b], axis=-1)


@_deprecate.parameters(renamed={"range": "signal_range", "bits": "bit_depth"})
@chunkwise(1)
def rgb_to_ycbcr(
    image: ArrayLike,
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    *,
    signal_range: Literal["full", "limited"] = "full",
    bit_depth: int | None = None,
) -> Array:
    """Convert encoded R'G'B' to Y'CbCr (analog or code values), see the module docstring.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded R'G'B' in [0, 1] or uint8/uint16.
    standard : {"bt601", "bt709", "bt2020"}
        Which luma coefficients (ITU-R BT.601, BT.709 or BT.2020).
    signal_range : {"full", "limited"}
        Full-range or limited ("studio", "narrow") code values; see the module docstring.
    bit_depth : {None, 8, 10, 12}
        Code values of this bit depth (bits per sample; ``bits`` is its deprecated name);
        None: analog values (``"full"``) or 8-bit codes (``"limited"``).

    Returns
    -------
    array, shape (..., 3)
        (Y', Cb, Cr) in the requested scale.

    Notes
    -----
    Source: ITU-R BT.601-7 items 2.5.1-2.5.3; BT.709-6 items 3.2-4.6; BT.2020-2 Tables 4-5;
    ITU-T H.273 (full range).

    Examples
    --------
    >>> ycc = rgb_to_ycbcr([1.0, 0.0, 0.0], "bt709", signal_range="limited", bit_depth=8)
    >>> ycc.round(2).tolist()
    [62.56, 102.34, 240.0]
    """
    _, kr, kb = _coeffs(standard)
    sc = _scale(signal_range, bit_depth)
    x = as_image_strict(image, "R'G'B' image")
    return _rgb_to_ycbcr(namespace(x), x, kr, kb, sc)


@_deprecate.parameters(renamed={"range": "signal_range", "bits": "bit_depth"})
@chunkwise(1)
def ycbcr_to_rgb(
    ycbcr: ArrayLike,
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    *,
    signal_range: Literal["full", "limited"] = "full",
    bit_depth: int | None = None,
) -> Array:
    """Y'CbCr (analog or code values) to encoded R'G'B'; inverse of :func:`rgb_to_ycbcr`.

    Integer code values (e.g. uint8, uint16 for 10-bit) are read as numbers, not rescaled.
    Codes outside the nominal range (footroom/headroom) give R'G'B' outside [0, 1]; nothing
    is clipped.

    Examples
    --------
    >>> ycbcr_to_rgb([235.0, 128.0, 128.0], "bt709", signal_range="limited").round(6).tolist()
    [1.0, 1.0, 1.0]
    """
    _, kr, kb = _coeffs(standard)
    sc = _scale(signal_range, bit_depth)
    _check_codes(ycbcr, signal_range, bit_depth)
    x = as_float_strict(ycbcr, "ycbcr", integer="float32")
    if x.ndim < 1 or x.shape[-1] != 3:
        raise InvalidInputError(
            f"expected ycbcr (Y'CbCr) with 3 channels on axis -1, got shape {tuple(x.shape)}"
        )
    return _ycbcr_to_rgb(namespace(x), x, kr, kb, sc)


@_deprecate.parameters(renamed={"range": "signal_range", "bits": "bit_depth"})
@chunkwise(1)
def srgb_to_ycbcr(
    image: ArrayLike,
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    *,
    signal_range: Literal["full", "limited"] = "full",
    bit_depth: int | None = None,
) -> Array:
    """sRGB-encoded values to Y'CbCr: :func:`rgb_to_ycbcr` applied to the sRGB values.

    This is what JPEG (BT.601, full range, 8 bits) and OpenCV's ``COLOR_RGB2YCrCb`` do with
    sRGB pixels (OpenCV orders the result Y, Cr, Cb: see :mod:`imageform.color.opencv`).

    Examples
    --------
    >>> srgb_to_ycbcr([1.0, 1.0, 1.0], bit_depth=8).round(6).tolist()
    [255.0, 128.0, 128.0]
    """
    return rgb_to_ycbcr(image, standard, signal_range=signal_range, bit_depth=bit_depth)


@_deprecate.parameters(renamed={"range": "signal_range", "bits": "bit_depth"})
@chunkwise(1)
def ycbcr_to_srgb(
    ycbcr: ArrayLike,
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    *,
    signal_range: Literal["full", "limited"] = "full",
    bit_depth: int | None = None,
) -> Array:
    """Y'CbCr to sRGB-encoded values; inverse of :func:`srgb_to_ycbcr`.

    Examples
    --------
    >>> ycbcr_to_srgb([0.5, 0.0, 0.0]).round(6).tolist()
    [0.5, 0.5, 0.5]
    """
    return ycbcr_to_rgb(ycbcr, standard, signal_range=signal_range, bit_depth=bit_depth)
