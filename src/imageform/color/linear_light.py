"""Decode before any linear operation: averaging and resizing in linear light.

Encoded sRGB values are not proportional to light. Averaging them (what a naive resize,
blur or mean does) darkens mixtures: black and white averaged as codes give 0.5, which
*displays* as 21.4 % of white's light, while the true half-and-half mixture (what the eye
sees from a distance, what a lens blur does) is 50 % of the light, encoded 0.735.

The lecture's rule, made easy: :func:`mean_linear_light` and :func:`downsample` decode,
operate, re-encode; :func:`linear_light_error` shows how wrong the encoded-value way is.

Examples
--------
>>> float(mean_linear_light([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]], axis=0)[0]).__round__(4)
0.7354
"""

from __future__ import annotations

from typing import Any, NamedTuple

from imageform._backend import namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import as_bool, as_image_strict, as_int, check_name
from imageform.errors import InvalidInputError

from .transfer import TRANSFER_FUNCTIONS, _decode_clean, _encode_clean

__all__ = ["LinearLightComparison", "downsample", "linear_light_error", "mean_linear_light"]


def mean_linear_light(
    image: ArrayLike, axis: int | tuple[int, ...] | None = None, *, transfer: str = "srgb"
) -> Array:
    r"""Mean of encoded values computed in linear light, returned encoded.

    .. math:: \bar V = \mathrm{enc}\Big(\frac1N \sum_i \mathrm{dec}(V_i)\Big)

    Parameters
    ----------
    image : array_like, shape (..., C)
        Encoded values (any channel count).
    axis : int or tuple of int or None
        Axes to average over (None: all).
    transfer : str
        The transfer function of the encoding (:data:`imageform.color.TRANSFER_FUNCTIONS`).

    Notes
    -----
    Source: the lecture ("decode before any linear operation"); IEC 61966-2-1 for the curve.

    Examples
    --------
    >>> float(mean_linear_light([0.0, 1.0]).round(4))
    0.7354
    """
    name = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    x = as_image_strict(image, "image", channels=None)
    if axis is None:
        axes: tuple[int, ...] = tuple(range(x.ndim))
    else:
        items = axis if isinstance(axis, tuple) else (axis,)
        axes = tuple(as_int(a, "axis", minimum=-x.ndim, maximum=x.ndim - 1) for a in items)
        axis = axes if isinstance(axis, tuple) else axes[0]
    if any(x.shape[a] == 0 for a in axes):
        raise InvalidInputError(
            f"expected a non-empty image along the averaged axes, got shape {tuple(x.shape)}"
        )
    xp = namespace(x)
    return _encode_clean(xp, xp.mean(_decode_clean(xp, x, name), axis=axis), name)


def _box(xp: Any, x: Any, f: int) -> Any:
    *lead, h, w, c = x.shape
    h2, w2 = h // f, w // f
    x = x[..., : h2 * f, : w2 * f, :]
    x = xp.reshape(x, (*lead, h2, f, w2, f, c))
    return xp.mean(xp.mean(x, axis=-2), axis=-3)


def downsample(
    image: ArrayLike, factor: int, *, linear_light: bool = True, transfer: str = "srgb"
) -> Array:
    """Shrink an image by an integer ``factor`` with a box filter (mean of f x f blocks).

    With ``linear_light=True`` (the right way) the blocks are averaged in linear light;
    ``False`` averages the encoded values (what most resizers do; shown for comparison).
    Rows/columns that do not fill a whole block are dropped.

    Parameters
    ----------
    image : array_like, shape (..., H, W, C)
        The image; encoded as ``transfer`` says unless ``linear_light`` is False.
    factor : int
        Block size, >= 1.
    linear_light : bool, keyword-only
        Average in linear light (decode, average, encode); False averages the codes.
    transfer : str, keyword-only
        The image's transfer function (one of :data:`TRANSFER_FUNCTIONS`).

    Returns
    -------
    array, shape (..., H // factor, W // factor, C)

    Examples
    --------
    >>> import numpy as np
    >>> checker = np.indices((2, 2)).sum(0)[..., None] % 2 * np.ones(3)  # black/white
    >>> float(downsample(checker, 2)[0, 0, 0].round(4)), float(downsample(checker, 2,
    ...     linear_light=False)[0, 0, 0])
    (0.7354, 0.5)
    """
    name = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    factor = as_int(factor, "factor", minimum=1)
    linear_light = as_bool(linear_light, "linear_light")
    x = as_image_strict(image, "image", channels=None)
    if x.ndim < 3:
        raise InvalidInputError(f"expected an image of shape (..., H, W, C), got {tuple(x.shape)}")
    if x.shape[-3] < factor or x.shape[-2] < factor:
        raise InvalidInputError(
            f"expected factor <= the image's height and width: image {tuple(x.shape)} is "
            f"smaller than one {factor}x{factor} block"
        )
    xp = namespace(x)
    if not linear_light:
        return _box(xp, x, factor)
    return _encode_clean(xp, _box(xp, _decode_clean(xp, x, name), factor), name)


class LinearLightComparison(NamedTuple):
    """Result of :func:`linear_light_error`."""

    right: Any  #: downsampled in linear light (encoded)
    wrong: Any  #: downsampled as encoded values
    max_error: float  #: max |wrong - right| in encoded units (0-1)
    mean_error: float  #: mean |wrong - right|


def linear_light_error(
    image: ArrayLike, factor: int = 2, *, transfer: str = "srgb"
) -> LinearLightComparison:
    """Downsample both ways and report the error of averaging encoded values.

    Examples
    --------
    >>> import numpy as np
    >>> checker = np.indices((4, 4)).sum(0)[..., None] % 2 * np.ones(3)
    >>> round(linear_light_error(checker).max_error, 4)
    0.2354
    """
    right = downsample(image, factor, transfer=transfer)
    wrong = downsample(image, factor, linear_light=False, transfer=transfer)
    xp = namespace(right)
    err = xp.abs(wrong - right)
    return LinearLightComparison(right, wrong, float(xp.max(err)), float(xp.mean(err)))
