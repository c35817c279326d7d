"""Colour formulas on clean arrays that more than one package needs (internal, core layer).

A documented internal module: the colour package wraps these formulas in its validated
public functions (:func:`imageform.color.srgb_to_linear`, :func:`imageform.color.srgb_to_hsv`,
:func:`imageform.color.cct_to_xy`, :func:`imageform.color.xy_to_uv1960` ...), and the
packages below or beside it that need the same numbers on arrays they have already validated
import them from here instead of from the colour package's internals:

- :mod:`imageform.spectral` — the CIE daylight locus (D-series illuminants) and the CIE 1960
  UCS (:func:`imageform.spectral.planckian_cct`); spectral sits below colour in the layers;
- :mod:`imageform.analysis` — the sRGB curve and the HSV hexcone on image blocks;
- :mod:`imageform.geometry` and :mod:`imageform.io` — the Rec. 601 luma of the detectors'
  and matchers' grey images (:func:`luma_601`, :func:`luma_601_matmul`).

Every function takes the array namespace ``xp`` first and arrays that are already checked
(shape, dtype, finiteness); nothing here validates, and nothing imports a domain package.
Constants are written as their standards write them, with the source beside them.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "DAYLIGHT_HIGH",
    "DAYLIGHT_LOW",
    "DAYLIGHT_RANGE",
    "LUMA_601",
    "SRGB_A",
    "SRGB_ENC_THRESHOLD",
    "SRGB_GAMMA",
    "SRGB_LIN_THRESHOLD",
    "SRGB_SLOPE",
    "daylight_x",
    "daylight_xy",
    "hexcone_hue",
    "hsv_to_rgb",
    "luma_601",
    "luma_601_matmul",
    "pos_pow",
    "rgb_to_hsv",
    "srgb_decode",
    "srgb_encode",
    "uv1960_from_xy",
]

# ---------------------------------------------------------------- the sRGB curve
# IEC 61966-2-1:1999, clause 5.2 (eq. 5) and 5.3 (eq. 8): the sRGB curve.
SRGB_A = 0.055
SRGB_GAMMA = 2.4
SRGB_SLOPE = 12.92
SRGB_LIN_THRESHOLD = 0.0031308  # linear-side breakpoint, IEC 61966-2-1 eq. (8)
# Encoded-side breakpoint derived from the forward function: 12.92 * 0.0031308 = 0.040449936
# (the standard rounds it to 0.04045; the derived value makes the two pieces invertible).
SRGB_ENC_THRESHOLD = SRGB_SLOPE * SRGB_LIN_THRESHOLD


def pos_pow(xp: Any, x: Any, p: float) -> Any:
    """``x ** p`` for the branch where x is above a breakpoint > 1e-30.

    Elements below are clipped to 1e-30 (their branch is unused): no NaN from a negative
    base, and gradients stay finite, in one pass (a ``where`` on ``x > 0`` took three).
    """
    return xp.pow(xp.clip(x, min=1e-30), p)


def srgb_decode(xp: Any, v: Any) -> Any:
    r"""Decode sRGB to linear light (IEC 61966-2-1:1999 eq. 5-6); no clipping.

    :math:`L = V/12.92` below the breakpoint, :math:`((V + 0.055)/1.055)^{2.4}` above.
    """
    hi = pos_pow(xp, (v + SRGB_A) / (1.0 + SRGB_A), SRGB_GAMMA)
    return xp.where(v <= SRGB_ENC_THRESHOLD, v / SRGB_SLOPE, hi)


def srgb_encode(xp: Any, lin: Any) -> Any:
    r"""Encode linear light to sRGB (IEC 61966-2-1:1999 eq. 8-9); no clipping.

    :math:`V = 12.92 L` for :math:`L \le 0.0031308`, :math:`1.055 L^{1/2.4} - 0.055` above.
    """
    hi = (1.0 + SRGB_A) * pos_pow(xp, lin, 1.0 / SRGB_GAMMA) - SRGB_A
    return xp.where(lin <= SRGB_LIN_THRESHOLD, lin * SRGB_SLOPE, hi)


# ---------------------------------------------------------------- the HSV hexcone
def hexcone_hue(xp: Any, r: Any, g: Any, b: Any, mx: Any, delta: Any) -> Any:
    """Hexcone hue in degrees from RGB, max and chroma (delta); 0 where delta = 0."""
    zero = delta == 0
    d = xp.where(zero, 1.0, delta)
    hr = (g - b) / d
    hg = (b - r) / d + 2.0
    hb = (r - g) / d + 4.0
    h = xp.where(mx == r, hr, xp.where(mx == g, hg, hb)) * 60.0
    h = xp.where(h < 0, h + 360.0, h)
    h = xp.where(h >= 360.0, h - 360.0, h)
    return xp.where(zero, 0.0, h)


def rgb_to_hsv(xp: Any, rgb: Any) -> Any:
    """Convert RGB ``(..., 3)`` to HSV (A. R. Smith, "Color gamut transform pairs", SIGGRAPH 1978).

    V = max, S = (max - min)/max (0 where max = 0), H the hexcone hue in degrees.
    """
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    mx = xp.maximum(xp.maximum(r, g), b)
    mn = xp.minimum(xp.minimum(r, g), b)
    delta = mx - mn
    s = xp.where(mx == 0, 0.0, delta / xp.where(mx == 0, 1.0, mx))
    return xp.stack([hexcone_hue(xp, r, g, b, mx, delta), s, mx], axis=-1)


def hsv_to_rgb(xp: Any, hsv: Any) -> Any:
    r"""Convert HSV ``(..., 3)`` to RGB (hue taken modulo 360).

    :math:`f(n) = V - VS\max(0, \min(k, 4 - k, 1))`, :math:`k = (n + H/60) \bmod 6` for
    n = 5, 3, 1.
    """
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    # the "k" formulation: f(n) = V - V S max(0, min(k, 4 - k, 1)), k = (n + H/60) mod 6
    out = []
    for n in (5.0, 3.0, 1.0):
        k = xp.remainder(n + h / 60.0, 6.0)
        t = xp.clip(xp.minimum(k, 4.0 - k), 0.0, 1.0)
        out.append(v - v * s * t)
    return xp.stack(out, axis=-1)


# ---------------------------------------------------------------- Rec. 601 luma
# ITU-R BT.601-7, section 2.5.1: Y' = 0.299 R' + 0.587 G' + 0.114 B' (the grey of OpenCV's
# cvtColor and of the lecture).
LUMA_601 = (0.299, 0.587, 0.114)


def luma_601(xp: Any, rgb: Any) -> Any:
    r"""Rec. 601 luma of ``rgb (..., C)``, C >= 3, channel by channel, in the input's scale.

    .. math:: Y' = 0.299 R' + 0.587 G' + 0.114 B'

    (ITU-R BT.601-7, section 2.5.1), summed left to right as written, with the weights as
    Python floats: a float32 input stays float32, an integer one becomes float64. Channels
    after the third (alpha) are ignored. Not the bits of :func:`luma_601_matmul`.

    Examples
    --------
    >>> import numpy as np
    >>> float(luma_601(np, np.array([200.0, 100.0, 50.0])))
    124.2
    """
    w = LUMA_601
    return rgb[..., 0] * w[0] + rgb[..., 1] * w[1] + rgb[..., 2] * w[2]


def luma_601_matmul(xp: Any, rgb: Any, weights_dtype: Any = None) -> Any:
    r"""Rec. 601 luma of ``rgb (..., 3)`` as one product ``rgb @ w``, ``w`` = :data:`LUMA_601`.

    The same formula as :func:`luma_601` with the matrix product's summation (and the result
    dtype of ``rgb`` with ``w`` in ``weights_dtype``, float64 by default): its bits differ
    from :func:`luma_601`'s in the last place, so each caller keeps the form it had.
    ``rgb`` must have exactly 3 channels.

    Examples
    --------
    >>> import numpy as np
    >>> float(luma_601_matmul(np, np.array([200.0, 100.0, 50.0])))
    124.2
    >>> luma_601_matmul(np, np.array([[255, 0, 0]], np.uint8)).dtype
    dtype('float64')
    """
    w = xp.asarray(LUMA_601, dtype=xp.float64 if weights_dtype is None else weights_dtype)
    return rgb @ w


# ---------------------------------------------------------------- CIE chromaticity
# CIE 15:2004 eq. (3.3): the daylight locus is defined from 4000 K to 25000 K, with one cubic
# in 1/T below 7000 K and another above.
DAYLIGHT_RANGE = (4000.0, 25000.0)
DAYLIGHT_LOW = (-4.6070e9, 2.9678e6, 0.09911e3, 0.244063)  # 4000 K <= T <= 7000 K
DAYLIGHT_HIGH = (-2.0064e9, 1.9018e6, 0.24748e3, 0.237040)  # 7000 K < T <= 25000 K


def daylight_x(xp: Any, cct: Any) -> Any:
    r"""Return :math:`x_D` of the CIE daylight locus at ``cct`` (CIE 15:2004 eq. 3.3).

    :math:`x_D = a_3 10^9/T^3 + a_2 10^6/T^2 + a_1 10^3/T + a_0`, coefficients
    :data:`DAYLIGHT_LOW` up to 7000 K, :data:`DAYLIGHT_HIGH` above; ``cct`` in kelvin, not
    range-checked.
    """
    s = 1.0 / cct
    lo = DAYLIGHT_LOW
    hi = DAYLIGHT_HIGH
    x_lo = ((lo[0] * s + lo[1]) * s + lo[2]) * s + lo[3]
    x_hi = ((hi[0] * s + hi[1]) * s + hi[2]) * s + hi[3]
    return xp.where(cct <= 7000.0, x_lo, x_hi)


def daylight_xy(xp: Any, cct: Any) -> Any:
    r"""Return the chromaticity ``(..., 2)`` of the CIE daylight locus at ``cct``.

    :func:`daylight_x` and :math:`y_D = -3.000 x_D^2 + 2.870 x_D - 0.275`.
    """
    x = daylight_x(xp, cct)
    # CIE 15:2004 eq. (3.4)
    y = -3.000 * x * x + 2.870 * x - 0.275
    return xp.stack([x, y], axis=-1)


def uv1960_from_xy(xp: Any, xy: Any) -> tuple[Any, Any]:
    r"""Convert ``xy (..., 2)`` to CIE 1960 UCS ``(u, v)`` (CIE 15:2004 §8.1).

    :math:`u = 4x/(-2x + 12y + 3)`, :math:`v = 6y/(-2x + 12y + 3)`.
    """
    x, y = xy[..., 0], xy[..., 1]
    d = -2.0 * x + 12.0 * y + 3.0
    return 4.0 * x / d, 6.0 * y / d
