"""HSV, HSL and HSI from encoded RGB, and hue helpers that wrap around 0/360.

All three take *encoded* RGB in [0, 1] (as the lecture and OpenCV do: these are
perceptual re-arrangements of the display values, not colorimetric spaces). Hue is in
degrees [0, 360); saturation, value, lightness and intensity in [0, 1].

**Undefined hue.** When the colour is achromatic (S = 0: R = G = B) the hue is undefined.
imageform returns H = 0 there (as OpenCV, scikit-image and ``colorsys`` do) and offers
:func:`hue_undefined_mask` to find those pixels; never threshold hue without it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._backend import common_device, device_of, namespace
from imageform._colormath import hexcone_hue as _hue
from imageform._colormath import hsv_to_rgb as _hsv_to_srgb
from imageform._colormath import rgb_to_hsv as _srgb_to_hsv
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_float_strict, as_image_strict, as_real
from imageform.errors import InvalidInputError

__all__ = [
    "hsi_to_srgb",
    "hsl_to_srgb",
    "hsv_to_srgb",
    "hue_difference",
    "hue_distance",
    "hue_in_range",
    "hue_undefined_mask",
    "srgb_to_hsi",
    "srgb_to_hsl",
    "srgb_to_hsv",
]


def _srgb_to_hsl(xp: Any, rgb: Any) -> Any:
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    mx = xp.maximum(xp.maximum(r, g), b)
    mn = xp.minimum(xp.minimum(r, g), b)
    delta = mx - mn
    light = (mx + mn) / 2.0
    den = 1.0 - xp.abs(2.0 * light - 1.0)
    s = xp.where(den == 0, 0.0, delta / xp.where(den == 0, 1.0, den))
    return xp.stack([_hue(xp, r, g, b, mx, delta), s, light], axis=-1)


def _hsl_to_srgb(xp: Any, hsl: Any) -> Any:
    h, s, light = hsl[..., 0], hsl[..., 1], hsl[..., 2]
    a = s * xp.minimum(light, 1.0 - light)
    out = []
    for n in (0.0, 8.0, 4.0):
        k = xp.remainder(n + h / 30.0, 12.0)
        t = xp.clip(xp.minimum(k - 3.0, 9.0 - k), -1.0, 1.0)
        out.append(light - a * t)
    return xp.stack(out, axis=-1)


def _srgb_to_hsi(xp: Any, rgb: Any) -> Any:
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    i = (r + g + b) / 3.0
    mn = xp.minimum(xp.minimum(r, g), b)
    s = xp.where(i == 0, 0.0, 1.0 - mn / xp.where(i == 0, 1.0, i))
    # θ = atan2(√3 (G - B), 2R - G - B): the same angle as G&W's arccos form, without its
    # division by zero and with full precision near 0° and 180°.
    h = xp.atan2(math.sqrt(3.0) * (g - b), 2.0 * r - g - b) * (180.0 / math.pi)
    h = xp.where(h < 0, h + 360.0, h)
    h = xp.where(h >= 360.0, h - 360.0, h)
    h = xp.where(s == 0, 0.0, h)
    return xp.stack([h, s, i], axis=-1)


def _hsi_to_srgb(xp: Any, hsi: Any) -> Any:
    h, s, i = hsi[..., 0], hsi[..., 1], hsi[..., 2]
    # Gonzalez & Woods, eq. (6-20)..(6-30), sector by sector (RG, GB, BR).
    sector = xp.floor(h / 120.0)
    hh = (h - 120.0 * sector) * (math.pi / 180.0)
    x = i * (1.0 - s)
    y = i * (1.0 + s * xp.cos(hh) / xp.cos(math.pi / 3.0 - hh))
    z = 3.0 * i - (x + y)
    r = xp.where(sector == 0, y, xp.where(sector == 1, x, z))
    g = xp.where(sector == 0, z, xp.where(sector == 1, y, x))
    b = xp.where(sector == 0, x, xp.where(sector == 1, z, y))
    return xp.stack([r, g, b], axis=-1)


def _rgb_in(image: object) -> tuple[Any, Any]:
    x = as_image_strict(image, "sRGB image")
    return namespace(x), x


@chunkwise(1)
def srgb_to_hsv(image: ArrayLike) -> Array:
    r"""Convert encoded RGB to HSV (hexcone model).

    .. math::
        V = \max(R,G,B), \; S = (V - \min) / V, \;
        H = 60° \times \begin{cases} (G-B)/\Delta & V = R \\ (B-R)/\Delta + 2 & V = G
        \\ (R-G)/\Delta + 4 & V = B \end{cases} \bmod 360

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB in [0, 1], or uint8/uint16.

    Returns
    -------
    array, shape (..., 3)
        H in degrees [0, 360) (0 where S = 0, see :func:`hue_undefined_mask`), S and V in
        [0, 1].

    Notes
    -----
    Source: A. R. Smith, "Color gamut transform pairs", SIGGRAPH 1978.

    Examples
    --------
    >>> srgb_to_hsv([1.0, 0.5, 0.0]).round(6).tolist()
    [30.0, 1.0, 1.0]
    """
    xp, x = _rgb_in(image)
    return _srgb_to_hsv(xp, x)


@chunkwise(1)
def hsv_to_srgb(hsv: ArrayLike) -> Array:
    r"""Convert HSV to encoded RGB.

    :math:`f(n) = V - VS\max(0, \min(k, 4 - k, 1))`, :math:`k = (n + H/60) \bmod 6` for
    n = 5, 3, 1.

    Hue may be any real number (taken modulo 360).

    Examples
    --------
    >>> hsv_to_srgb([30.0, 1.0, 1.0]).round(6).tolist()
    [1.0, 0.5, 0.0]
    """
    x = as_image_strict(hsv, "HSV", range_check=False)
    return _hsv_to_srgb(namespace(x), x)


@chunkwise(1)
def srgb_to_hsl(image: ArrayLike) -> Array:
    r"""Convert encoded RGB to HSL (double hexcone).

    L = (max + min)/2, :math:`S = \Delta / (1 - |2L - 1|)`, H as in HSV.

    Source: A. R. Smith (1978); Joblove & Greenberg, "Color spaces for computer graphics",
    SIGGRAPH 1978.

    Examples
    --------
    >>> srgb_to_hsl([1.0, 0.5, 0.0]).round(6).tolist()
    [30.0, 1.0, 0.5]
    """
    xp, x = _rgb_in(image)
    return _srgb_to_hsl(xp, x)


@chunkwise(1)
def hsl_to_srgb(hsl: ArrayLike) -> Array:
    r"""Convert HSL to encoded RGB.

    :math:`f(n) = L - a \max(-1, \min(k - 3, 9 - k, 1))`, :math:`a = S \min(L, 1 - L)`,
    :math:`k = (n + H/30) \bmod 12` for n = 0, 8, 4.

    Examples
    --------
    >>> hsl_to_srgb([30.0, 1.0, 0.5]).round(6).tolist()
    [1.0, 0.5, 0.0]
    """
    x = as_image_strict(hsl, "HSL", range_check=False)
    return _hsl_to_srgb(namespace(x), x)


@chunkwise(1)
def srgb_to_hsi(image: ArrayLike) -> Array:
    r"""Convert encoded RGB to HSI (Gonzalez & Woods).

    .. math::
        I = \frac{R+G+B}{3}, \quad S = 1 - \frac{\min(R,G,B)}{I}, \quad
        H = \begin{cases}\theta & B \le G \\ 360° - \theta & B > G\end{cases}, \;
        \theta = \arccos \frac{\tfrac12[(R-G)+(R-B)]}{\sqrt{(R-G)^2+(R-B)(G-B)}}

    θ is computed as :math:`\operatorname{atan2}(\sqrt3 (G-B), 2R-G-B)`, the same angle.
    H = 0 where S = 0; S = 0 for black.

    Source: R. C. Gonzalez & R. E. Woods, *Digital Image Processing*, 4th ed., eq. (6-16)-(6-19).

    Examples
    --------
    >>> srgb_to_hsi([0.0, 1.0, 0.0]).round(6).tolist()
    [120.0, 1.0, 0.333333]
    """
    xp, x = _rgb_in(image)
    return _srgb_to_hsi(xp, x)


@chunkwise(1)
def hsi_to_srgb(hsi: ArrayLike) -> Array:
    """HSI to encoded RGB, sector by sector (Gonzalez & Woods eq. (6-20)-(6-30)).

    Hue must be in [0, 360). Not every HSI triple is an RGB colour in [0, 1]; nothing is
    clipped.

    Examples
    --------
    >>> hsi_to_srgb([120.0, 1.0, 1.0 / 3.0]).round(6).tolist()
    [0.0, 1.0, 0.0]
    """
    x = as_image_strict(hsi, "HSI", range_check=False)
    return _hsi_to_srgb(namespace(x), x)


# ---------------------------------------------------------------- hue helpers
@chunkwise(1)
def hue_undefined_mask(values: ArrayLike, *, atol: float = 0.0) -> Array:
    """Boolean mask of pixels whose hue is undefined: saturation (channel 1) ``<= atol``.

    Works for HSV, HSL and HSI arrays (saturation is channel 1 in all three).

    Parameters
    ----------
    values : array_like, shape (..., 3)
        HSV values with S in [0, 1] (as :func:`rgb_to_hsv` returns them).
    atol : float
        Saturations at or below this count as achromatic (noise on grey pixels makes hue
        meaningless long before S is exactly 0).

    Returns
    -------
    array of bool, shape (...)

    Examples
    --------
    >>> hue_undefined_mask([[0.0, 0.0, 0.5], [30.0, 0.2, 0.5]]).tolist()
    [True, False]
    """
    x = as_image_strict(values, "values", range_check=False)
    atol = as_real(atol, "atol", nonnegative=True)
    return x[..., 1] <= atol


@chunkwise(0)
def hue_difference(h1: ArrayLike, h2: ArrayLike) -> Array:
    r"""Signed hue difference ``h2 - h1`` wrapped to [-180, 180) degrees.

    .. math:: \Delta h = ((h_2 - h_1 + 180) \bmod 360) - 180

    Examples
    --------
    >>> float(hue_difference(350.0, 10.0))
    20.0
    """
    xp = namespace(h1, h2)
    a = as_float_strict(h1, "h1", xp=xp, integer="float64", device=common_device(h1, h2))
    b = as_float_strict(h2, "h2", xp=xp, dtype=a.dtype, device=device_of(a))
    try:
        np.broadcast_shapes(tuple(a.shape), tuple(b.shape))
    except ValueError:
        raise InvalidInputError(
            f"expected h1 and h2 of broadcastable shapes, got {tuple(a.shape)} and {tuple(b.shape)}"
        ) from None
    return xp.remainder(b - a + 180.0, 360.0) - 180.0


@chunkwise(0)
def hue_distance(h1: ArrayLike, h2: ArrayLike) -> Array:
    r"""Unsigned angular distance between hues in degrees, in [0, 180].

    .. math:: d = \min(|h_1 - h_2| \bmod 360,\; 360 - |h_1 - h_2| \bmod 360)

    Examples
    --------
    >>> float(hue_distance(350.0, 10.0))
    20.0
    """
    d = hue_difference(h1, h2)
    xp = namespace(d)
    return xp.abs(d)


@chunkwise(0)
def hue_in_range(hue: ArrayLike, start: float, stop: float) -> Array:
    """Mask of hues inside the arc from ``start`` to ``stop`` degrees, counter-clockwise.

    The arc may wrap around 0/360: ``hue_in_range(h, 340, 20)`` selects reds from 340° to
    20°. Both ends are inclusive; ``start == stop`` selects that single hue.

    Examples
    --------
    >>> hue_in_range([350.0, 10.0, 30.0, 180.0], 340, 20).tolist()
    [True, True, False, False]
    """
    h = as_float_strict(hue, "hue", integer="float64")
    xp = namespace(h)
    s = as_real(start, "start (a hue)") % 360.0
    e = as_real(stop, "stop (a hue)") % 360.0
    hm = xp.remainder(h, 360.0)
    if s <= e:
        return (hm >= s) & (hm <= e)
    return (hm >= s) | (hm <= e)
