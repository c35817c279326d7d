r"""CMY and CMYK: the subtractive complements of encoded RGB, as the lecture defines them.

.. math::
    (C, M, Y) = (1 - R, 1 - G, 1 - B); \quad K = \min(C, M, Y); \quad
    C' = \frac{C - K}{1 - K}, \; M' = \frac{M - K}{1 - K}, \; Y' = \frac{Y - K}{1 - K}

(pure black, K = 1, has C' = M' = Y' = 0). This is the device-independent textbook
conversion ("K added as the lecture explains"); real presses use ICC profiles with
under-colour removal and ink limits, which this does not model.
"""

from __future__ import annotations

from typing import Any

from imageform._backend import namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image_strict

__all__ = [
    "cmy_to_cmyk",
    "cmy_to_srgb",
    "cmyk_to_cmy",
    "cmyk_to_srgb",
    "srgb_to_cmy",
    "srgb_to_cmyk",
]


def _cmy_to_cmyk(xp: Any, cmy: Any) -> Any:
    k = xp.minimum(xp.minimum(cmy[..., 0], cmy[..., 1]), cmy[..., 2])
    den = 1.0 - k
    black = den == 0
    safe = xp.where(black, 1.0, den)
    chans = [xp.where(black, 0.0, (cmy[..., i] - k) / safe) for i in range(3)]
    return xp.stack([*chans, k], axis=-1)


def _cmyk_to_cmy(xp: Any, cmyk: Any) -> Any:
    k = cmyk[..., 3:4]
    return cmyk[..., :3] * (1.0 - k) + k


@chunkwise(1)
def srgb_to_cmy(image: ArrayLike) -> Array:
    """Convert encoded RGB to CMY: :math:`(C, M, Y) = 1 - (R, G, B)`.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB in [0, 1] or uint8/uint16.

    Returns
    -------
    array, shape (..., 3)

    Notes
    -----
    Source: the lecture (CMY = 1 - RGB); Gonzalez & Woods, 4th ed., eq. (6-5).

    Examples
    --------
    >>> srgb_to_cmy([1.0, 0.25, 0.0]).tolist()
    [0.0, 0.75, 1.0]
    """
    x = as_image_strict(image, "sRGB image")
    return 1.0 - x


@chunkwise(1)
def cmy_to_srgb(cmy: ArrayLike) -> Array:
    """CMY to encoded RGB: :math:`(R, G, B) = 1 - (C, M, Y)`.

    Examples
    --------
    >>> cmy_to_srgb([0.0, 0.75, 1.0]).tolist()
    [1.0, 0.25, 0.0]
    """
    x = as_image_strict(cmy, "CMY")
    return 1.0 - x


@chunkwise(1)
def cmy_to_cmyk(cmy: ArrayLike) -> Array:
    r"""CMY to CMYK with K = min(C, M, Y) and the remaining inks rescaled by 1/(1 - K).

    .. math:: K = \min(C, M, Y), \quad C' = (C - K)/(1 - K) \ldots

    Returns shape (..., 4). Source: the lecture; Gonzalez & Woods, 4th ed., eq. (6-6)-(6-9).

    Examples
    --------
    >>> cmy_to_cmyk([0.5, 0.75, 1.0]).tolist()
    [0.0, 0.5, 1.0, 0.5]
    """
    x = as_image_strict(cmy, "CMY")
    return _cmy_to_cmyk(namespace(x), x)


@chunkwise(1)
def cmyk_to_cmy(cmyk: ArrayLike) -> Array:
    """CMYK to CMY: :math:`C = C'(1 - K) + K` (and likewise M, Y).

    Examples
    --------
    >>> cmyk_to_cmy([0.0, 0.5, 1.0, 0.5]).tolist()
    [0.5, 0.75, 1.0]
    """
    x = as_image_strict(cmyk, "CMYK", channels=4)
    return _cmyk_to_cmy(namespace(x), x)


@chunkwise(1)
def srgb_to_cmyk(image: ArrayLike) -> Array:
    """Convert encoded RGB to CMYK (via CMY), shape (..., 4).

    Examples
    --------
    >>> srgb_to_cmyk([0.0, 0.0, 0.0]).tolist()
    [0.0, 0.0, 0.0, 1.0]
    """
    x = as_image_strict(image, "sRGB image")
    return _cmy_to_cmyk(namespace(x), 1.0 - x)


@chunkwise(1)
def cmyk_to_srgb(cmyk: ArrayLike) -> Array:
    """CMYK to encoded RGB: :math:`R = (1 - C')(1 - K)` (and likewise G, B).

    Examples
    --------
    >>> cmyk_to_srgb([0.0, 0.5, 1.0, 0.5]).tolist()
    [0.5, 0.25, 0.0]
    """
    x = as_image_strict(cmyk, "CMYK", channels=4)
    return 1.0 - _cmyk_to_cmy(namespace(x), x)
