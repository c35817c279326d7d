r"""White balance by diagonal (von Kries) gains in linear light.

Every method estimates the colour of the illuminant :math:`e = (e_R, e_G, e_B)` in *linear*
RGB and divides it out:

.. math:: \rho'_c = g_c \rho_c,\qquad g_c = \frac{\bar e}{e_c},\quad
    \bar e = \tfrac13 (e_R + e_G + e_B)

(``normalize="mean"``, the lecture's grey world: every channel is scaled so that its average
equals the average grey; ``normalize="green"`` keeps green fixed, :math:`g_c = e_G/e_c`).
Encoded input (sRGB by default) is decoded first and re-encoded after, so the gains act on
light, not on code values.

Estimators (van de Weijer, Gevers & Gijsenij 2007 unify them as
:math:`e_c \propto (\int |\partial^n \rho_{c,\sigma}|^p)^{1/p}`):

- ``"gray_world"`` — :math:`e_c = \mathrm{mean}(\rho_c)` (Buchsbaum 1980).
- ``"white_patch"`` — :math:`e_c` = the ``percentile`` of :math:`\rho_c` (max-RGB at 100;
  Land's retinex white patch, a high percentile resists clipped highlights and noise).
- ``"shades_of_gray"`` — :math:`e_c = (\mathrm{mean}\,\rho_c^p)^{1/p}`, ``p >= 1``
  (Finlayson & Trezzi 2004; p = 1 is grey world, p -> inf is max-RGB).
- ``"gray_edge"`` — :math:`e_c = (\mathrm{mean}\,|\nabla G_\sigma * \rho_c|^p)^{1/p}` (van de
  Weijer et al. 2007, first order).
- ``"grayness_index"`` — the grey pixels (Yang, Gao & Li 2015; Qian et al. 2019): a grey
  surface under the light :math:`e` has :math:`\rho_c = e_c s(x)`, so its log contrast
  :math:`\Delta \log \rho_c = \Delta \log s` is the same in every channel whatever the light.
  The index is

  .. math:: \mathrm{GI}(x) = \left\| \left(\Delta \log \rho_R - \Delta \log \rho_G,\;
      \Delta \log \rho_B - \Delta \log \rho_G\right)(x) \right\|_2

  (:math:`\Delta`: the 5-point Laplacian after a Gaussian blur of ``sigma`` pixels), averaged
  over a 7 x 7 window of candidates; the candidates have no channel within 5 % of its maximum
  or below 0.2 % of it (clipped, black or masked; their Laplacian stencil too) and some
  contrast. The estimate is the sum of the ``percentile`` % of the image's pixels (0.1 % by
  default) with the smallest index, :math:`e_c = \sum_{x \in S} \rho_c(x)`. Green stands
  where Qian et al. take the luminance :math:`R + G + B`: a diagonal cast then moves no
  pixel's index, so the same pixels are chosen under any light and the estimate follows the
  cast exactly.
- ``"pca"`` — Cheng, Prasad & Brown (2014): the pixels ordered by their projection
  :math:`\rho(x) \cdot \bar\rho` on the mean colour; of the candidates (as above, unclipped),
  the ``percentile`` % darkest and the ``percentile`` % brightest of the image's pixels (3.5 %
  each by default) form :math:`S`, and :math:`e` is the leading eigenvector of
  :math:`\sum_{x \in S} \rho(x) \rho(x)^T` (not centred: the light's line passes through
  black), of unit length.
- ``"manual"`` — the linear RGB of a known illuminant: a white point (name, ``(x, y)`` or
  ``XYZ``) or a correlated colour temperature on the Planckian locus.

Which to use (``benchmarks/results/illuminant-real-2026-11-29g.md``, 37 photographs with a
ColorChecker, the truth from its grey patches): no method is best on every set; max-RGB had
the smallest mean and median error, every method took the 34 degree cast of the
machine-vision photographs to 2.3-6.3 degrees, and on phone JPEGs (balanced by the phone) the
photograph as it came was often as close as any estimate. ``gray_world`` stays the default.

``mask`` (H, W) keeps the pixels to measure the light by, as the colour-constancy sets do
(the chart and the clipped pixels left out): the means and the percentile are over the kept
pixels, ``gray_edge`` blurs by a normalised convolution (:math:`G * (\rho m) / G * m`) and
keeps a derivative when its whole stencil is kept, and ``grayness_index`` and ``pca`` take
their candidates among the kept pixels. Clipped highlights pull every estimator towards
their own colour (``benchmarks/results/illuminant-fresh-2026-11-30g.md``); the library does
not guess the sensor's saturation, the caller masks it.

Dask images are balanced lazily: the estimate is a Dask reduction over the whole image (a
mean, a Minkowski mean, or for ``"white_patch"`` an exact percentile from
:func:`dask.array.topk` of the ``n - floor((n - 1) q / 100)`` largest values per channel;
``"grayness_index"`` and ``"pca"`` rank their pixels with :func:`dask.array.topk` too),
the image is decoded, scaled and re-encoded chunk-wise, and nothing is computed until
``.compute()``; a zero channel estimate then raises at compute time.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._backend import constant, device_of, is_dask_namespace, namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_bool,
    as_image_strict,
    as_int,
    as_real,
    as_real_array,
    check_name,
    check_nonempty,
    check_result_array,
    describe,
)
from imageform.color.rgb_spaces import xyz_to_linear_rgb
from imageform.color.transfer import TRANSFER_FUNCTIONS, _kernel_step, decode, encode
from imageform.color.whitepoints import resolve_white, xy_to_xyz_white
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "WHITE_BALANCE_ALIASES",
    "WHITE_BALANCE_METHODS",
    "WhiteBalanceResult",
    "apply_white_balance_gains",
    "estimate_illuminant",
    "white_balance",
    "white_balance_gains",
]

#: Largest Minkowski norm ``p``: beyond it ``x**p`` underflows to 0 for most pixels < 1 and
#: the estimate is the maximum anyway (``p = inf`` is the ``max_rgb`` method).
MAX_MINKOWSKI_P = 1e4
#: Largest ``sigma`` (pixels) of the grey-edge derivative filter (bounds the kernel size).
MAX_SIGMA = 1000.0
#: Largest white balance gain :func:`apply_white_balance_gains` takes: real gains are a few
#: units (a tungsten-lit blue channel about 3); a million is an error, not a gain.
MAX_GAIN = 1e6
#: Other spellings of :data:`WHITE_BALANCE_METHODS` (British, and ``max_rgb``: a white
#: patch at the 100th percentile), each mapped to its method (read-only).
WHITE_BALANCE_ALIASES: MappingProxyType[str, str] = MappingProxyType(
    {
        "grey_world": "gray_world",
        "max_rgb": "white_patch",
        "shades_of_grey": "shades_of_gray",
        "grey_edge": "gray_edge",
        "greyness_index": "grayness_index",
    }
)
_ALIASES = WHITE_BALANCE_ALIASES


class _WhiteBalanceResult(NamedTuple):
    image: Any
    gains: Any


class WhiteBalanceResult(_WhiteBalanceResult):
    """``(image, gains)``: the balanced image and the per-channel gains applied in linear light.

    The image has the same encoding as the input; the gains have shape ``(..., 3)`` (one
    triple per image of a batch). Built by hand, both must be real and finite.
    """

    __slots__ = ()

    def __new__(cls, image: Any, gains: Any) -> WhiteBalanceResult:
        """Build the result, refusing a non-real or non-finite ``image`` or ``gains``."""
        check_result_array(image, "image")
        check_result_array(gains, "gains")
        return super().__new__(cls, image, gains)


#: ``percentile`` when not given, per method (99 for the others' white patch).
_DEFAULT_PERCENTILE = {
    "max_rgb": 100.0,
    "grayness_index": 0.1,
    "greyness_index": 0.1,
    "pca": 3.5,
}


def _method(method: str, percentile: float | None) -> tuple[str, float]:
    valid = (*WHITE_BALANCE_METHODS, *_ALIASES)
    key = check_name(method, valid, "white-balance method")
    if percentile is None:
        percentile = _DEFAULT_PERCENTILE.get(key, 99.0)
    return _ALIASES.get(key, key), as_real(percentile, "percentile")


def _flat(xp: Any, lin: Any) -> Any:
    """(..., H, W, C) -> (..., H*W, C)."""
    shape = tuple(lin.shape)
    return xp.reshape(lin, (*shape[:-3], shape[-3] * shape[-2], shape[-1]))


def _percentile(xp: Any, lin: Any, q: float, w: Any = None, kept: Any = None) -> Any:
    """Per-channel percentile over pixels, linear interpolation (NumPy's default).

    With a mask (``w`` 0/1, ``kept`` the NumPy count of kept pixels per image), the
    percentile of the kept pixels: the others are set to minus infinity, so that they sort
    first, and the position is moved past them.
    """
    n = lin.shape[-3] * lin.shape[-2]
    if w is None:
        return _sorted_at(xp, lin, (n - 1) * q / 100.0)
    x = xp.where(w[..., None] > 0, lin, -math.inf)
    kept = np.asarray(kept)
    if kept.ndim == 0 or np.all(kept == kept.flat[0]):
        k = int(kept.flat[0])
        return _sorted_at(xp, x, (n - k) + (k - 1) * q / 100.0)
    batch = tuple(lin.shape[:-3])
    per = [
        _sorted_at(xp, x[i], (n - int(kept[i])) + (int(kept[i]) - 1) * q / 100.0)
        for i in np.ndindex(batch)
    ]
    return xp.reshape(xp.stack(per, axis=0), (*batch, 3))


def _sorted_at(xp: Any, lin: Any, pos: float) -> Any:
    """Per channel, the value at fractional position ``pos`` of the pixels sorted."""
    if is_dask_namespace(xp):
        return _sorted_at_dask(lin, pos)
    s = xp.sort(_flat(xp, lin), axis=-2)
    n = s.shape[-2]
    lo = math.floor(pos)
    hi = min(lo + 1, n - 1)
    frac = pos - lo
    return s[..., lo, :] * (1.0 - frac) + s[..., hi, :] * frac


def _sorted_at_dask(lin: Any, pos: float) -> Any:
    """Compute the exact percentile of a Dask image from one ``topk`` reduction.

    The sorted values at ``lo`` and ``lo + 1`` are the ``(n - lo)``-th and
    ``(n - lo - 1)``-th largest.
    """
    import dask.array as da

    shape = tuple(lin.shape)
    n = shape[-3] * shape[-2]
    flat = da.reshape(lin, (*shape[:-3], n, 3), merge_chunks=True)
    lo = math.floor(pos)
    hi = min(lo + 1, n - 1)
    frac = pos - lo
    top = da.topk(flat, n - lo, axis=-2)  # largest first
    return top[..., n - lo - 1, :] * (1.0 - frac) + top[..., n - hi - 1, :] * frac


def _gauss_smooth(xp: Any, x: Any, sigma: float, axis: int) -> Any:
    """Gaussian blur along ``axis`` (-3 rows or -2 columns), edges replicated."""
    radius = max(1, math.ceil(3.0 * sigma))
    return _smooth(
        xp, x, [math.exp(-0.5 * (k / sigma) ** 2) for k in range(-radius, radius + 1)], axis
    )


def _smooth(xp: Any, x: Any, w: list[float], axis: int) -> Any:
    """Filter along ``axis`` (-3 rows or -2 columns) with symmetric weights, edges replicated.

    ``w`` has an odd length and is normalised to sum 1.
    """
    radius = len(w) // 2
    if is_dask_namespace(xp):
        return _smooth_dask(x, w, axis, radius)
    tot = sum(w)
    n = x.shape[axis]
    first = x[..., :1, :, :] if axis == -3 else x[..., :1, :]
    last = x[..., n - 1 :, :, :] if axis == -3 else x[..., n - 1 :, :]
    pad = xp.concat([first] * radius + [x] + [last] * radius, axis=axis)
    out = xp.zeros_like(x)
    for i, wi in enumerate(w):
        if axis == -3:
            out = out + (wi / tot) * pad[..., i : i + n, :, :]
        else:
            out = out + (wi / tot) * pad[..., i : i + n, :]
    return out


def _smooth_dask(x: Any, w: list[float], axis: int, radius: int) -> Any:
    """:func:`_smooth` of a Dask array, block by block with an overlap of ``radius``.

    Each block is filtered by the in-memory :func:`_smooth` (the same sums in the same order,
    so the values equal the eager path's) on the block grown by its neighbours' pixels,
    replicated at the image's edges (``boundary="nearest"``). Shifting and adding whole
    padded arrays instead, as the in-memory path does, splits the chunks at every shift: a
    grayness index of a 48 x 60 image took a minute to compute.
    """
    import dask.array as da

    ax = x.ndim + axis

    def block(b: Any) -> Any:
        return _smooth(namespace(b), b, w, axis)

    if x.shape[ax] <= radius:  # shorter than the overlap: the axis in one block
        return x.rechunk({ax: -1}).map_blocks(block, dtype=x.dtype)
    if min(x.chunks[ax]) < radius:  # map_overlap needs blocks at least as deep as the overlap
        x = x.rechunk({ax: max(radius, max(x.chunks[ax]))})
    depth = {i: (radius if i == ax else 0) for i in range(x.ndim)}
    bnd = {i: ("nearest" if i == ax else "none") for i in range(x.ndim)}
    return da.map_overlap(block, x, depth=depth, boundary=bnd, dtype=x.dtype, trim=True)


def _blur(xp: Any, x: Any, sigma: float) -> Any:
    return _gauss_smooth(xp, _gauss_smooth(xp, x, sigma, -3), sigma, -2)


def _interior(xp: Any, fn: Callable[[Any], Any], x: Any, channels: bool) -> Any:
    """Apply ``fn``, a 3 x 3 stencil giving the interior pixels, to ``x``.

    ``x`` is (..., H, W, C) (``channels``) or (..., H, W); ``fn(x)`` is (..., H - 2, W - 2[, C]).

    On Dask, ``fn`` runs block by block on each block grown by one pixel (``map_overlap``; the
    same sums, so the eager values) and the image's one-pixel rim is cut off at the end.
    Slicing whole arrays by one pixel instead cut every chunk boundary into three chunks (a
    1024 x 1024 grayness index in 16 chunks ran on 100, at 3.4 x the eager time).
    """
    if not is_dask_namespace(xp):
        return fn(x)
    import dask.array as da

    rows = x.ndim - (3 if channels else 2)
    axes = (rows, rows + 1)
    if min(x.shape[a] for a in axes) < 3:
        return fn(x)  # no interior pixel: the whole-array slices
    depth = {i: (1 if i in axes else 0) for i in range(x.ndim)}
    bnd = {i: ("nearest" if i in axes else "none") for i in range(x.ndim)}
    full = da.map_overlap(
        fn, x, depth=depth, boundary=bnd, trim=False, chunks=x.chunks, dtype=x.dtype
    )
    return full[(..., slice(1, -1), slice(1, -1)) + ((slice(None),) if channels else ())]


def _gray_edge(xp: Any, lin: Any, p: float, sigma: float, w: Any = None) -> Any:
    x = lin
    if sigma > 0 and w is None:
        x = _blur(xp, x, sigma)
    elif sigma > 0:
        # normalised convolution: a kept pixel's blur is the weighted mean of the kept pixels
        # about it, so that the left-out ones (a chart set to black, clipped highlights) do
        # not bleed into it and make edges of their own
        den = _blur(xp, w[..., None], sigma)
        x = _blur(xp, x * w[..., None], sigma) / xp.where(den > 0, den, 1.0)
    mag = _interior(xp, _gradient_magnitude, x, True)
    if w is not None:  # a derivative is kept when its whole stencil is
        w = _interior(xp, _stencil_product, w, False)
    return _minkowski(xp, mag, p, w)


def _gradient_magnitude(x: Any) -> Any:
    """Central-difference gradient magnitude of (..., H, W, C) on the interior pixels."""
    gy = (x[..., 2:, 1:-1, :] - x[..., :-2, 1:-1, :]) * 0.5
    gx = (x[..., 1:-1, 2:, :] - x[..., 1:-1, :-2, :]) * 0.5
    return namespace(x).sqrt(gx * gx + gy * gy)


def _stencil_product(w: Any) -> Any:
    """Multiply (..., H, W) over each interior pixel's 5-point stencil."""
    return (
        w[..., 1:-1, 1:-1]
        * w[..., :-2, 1:-1]
        * w[..., 2:, 1:-1]
        * w[..., 1:-1, :-2]
        * w[..., 1:-1, 2:]
    )


def _stencil_all(ok: Any) -> Any:
    """Whether a (..., H, W) boolean is true over each interior pixel's 5-point stencil."""
    return (
        ok[..., 1:-1, 1:-1]
        & ok[..., :-2, 1:-1]
        & ok[..., 2:, 1:-1]
        & ok[..., 1:-1, :-2]
        & ok[..., 1:-1, 2:]
    )


def _laplacian(x: Any) -> Any:
    """Take the 5-point Laplacian of (..., H, W, C) on the interior pixels."""
    return (
        x[..., :-2, 1:-1, :]
        + x[..., 2:, 1:-1, :]
        + x[..., 1:-1, :-2, :]
        + x[..., 1:-1, 2:, :]
        - 4.0 * x[..., 1:-1, 1:-1, :]
    )


def _pixel_mean(xp: Any, x: Any) -> Any:
    """Per-channel mean over the pixel axes of (..., H, W, C).

    NumPy and Dask accumulate in float64 and return the input's dtype: a float32 sum over
    the strided pixel axis is a running sum (no pairwise summation), whose relative error
    grows with the pixel count (4e-5 on a random 4K image) and would make the in-memory and the
    chunked paths disagree. Other namespaces use their own ``mean``.
    """
    if is_dask_namespace(xp):  # a reduction over the pixel axes, no reshape of the chunks
        return xp.mean(x, axis=(-3, -2), dtype=np.float64).astype(x.dtype)
    if isinstance(x, np.ndarray):
        return np.mean(_flat(np, x), axis=-2, dtype=np.float64).astype(x.dtype)
    return xp.mean(_flat(xp, x), axis=-2)


def _masked_mean(xp: Any, x: Any, w: Any) -> Any:
    """Per-channel mean over the pixels of (..., H, W, C) whose weight ``w`` (..., H, W) is 1.

    ``w`` is None (every pixel) or 0/1 in ``x``'s dtype: the mean over all pixels of
    ``x w`` divided by the share of pixels kept (both means accumulated as
    :func:`_pixel_mean` does), 0 where no pixel is kept.
    """
    if w is None:
        return _pixel_mean(xp, x)
    share = _pixel_mean(xp, w[..., None])
    return _pixel_mean(xp, x * w[..., None]) / xp.where(share > 0, share, 1.0)


def _minkowski(xp: Any, x: Any, p: float, w: Any = None) -> Any:
    if p == 1.0:
        return _masked_mean(xp, x, w)
    return _masked_mean(xp, x**p, w) ** (1.0 / p)


def _manual(xp: Any, like: Any, illuminant: Any, cct: float | None, space: str) -> Any:
    if (illuminant is None) == (cct is None):
        raise InvalidInputError("the manual method takes exactly one of illuminant= or cct=")
    if cct is not None:
        from imageform.color.cct import cct_to_xy

        xyz = xy_to_xyz_white([float(v) for v in cct_to_xy(float(cct))])
    else:
        xyz = resolve_white(illuminant, name="illuminant")
    rgb = np.asarray([float(v) for v in xyz_to_linear_rgb(xyz, space)], dtype=np.float64)
    if not np.all(rgb > 0):
        raise InvalidInputError(_outside_gamut(rgb, cct, illuminant, space))
    # a constant: uploaded once per device and dtype (no copy, no stream sync per call)
    e = constant(rgb, like, xp)
    return xp.broadcast_to(e, (*tuple(like.shape[:-3]), 3))


def _outside_gamut(rgb: np.ndarray, cct: float | None, illuminant: Any, space: str) -> str:
    """Say that a manual white lies outside ``space``'s gamut, and where its whites begin.

    A Planckian white below about 1900 K has a negative blue in linear sRGB (its chromaticity
    lies outside the triangle of sRGB's primaries), so no positive gain maps it to grey.
    """
    from imageform.color.cct import cct_to_xy

    names = ("red", "green", "blue")
    bad = " and ".join(names[i] for i in range(3) if not rgb[i] > 0)
    what = f"the Planckian white of {cct:g} K" if cct is not None else "the illuminant"
    verb = "are" if " and " in bad else "is"
    msg = (
        f"{what} lies outside {space}'s gamut (its {bad} {verb} not positive in linear "
        f"{space}): no gain balances it"
    )
    if cct is None:
        return msg

    def inside(t: float) -> bool:
        xyz = xy_to_xyz_white([float(v) for v in cct_to_xy(t)])
        return bool(np.all(np.asarray(xyz_to_linear_rgb(xyz, space), dtype=np.float64) > 0))

    lo, hi = float(cct), 25000.0
    if not inside(hi):
        return msg
    for _ in range(40):  # bisection on the locus: the lowest CCT whose white the space holds
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if inside(mid) else (mid, hi)
    return f"{msg}; {space} holds the Planckian whites from {np.ceil(hi):.0f} K"


def _check_estimate(e: np.ndarray, why: str = "an empty channel?") -> np.ndarray:
    if not np.all(e > 0):
        raise DegenerateConfigurationError(
            f"the image's illuminant estimate {np.round(e, 6).tolist()!s:.60} has a zero (or "
            f"negative) channel: no gain balances it ({why})"
        )
    return e


def _why_zero(method: str, percentile: float) -> str:
    """Say why a method's estimate can have an empty channel, for :func:`_check_estimate`."""
    if method == "white_patch" and percentile < 50.0:
        return f"the {percentile:g}th percentile of a channel is black: take a higher percentile"
    return "an empty channel?"


def _check_params(
    method: str,
    percentile: float,
    p: float,
    sigma: float,
    illuminant: Any = None,
    cct: float | None = None,
) -> None:
    """Every parameter is checked, also those the chosen method does not use."""
    percentile = as_real(percentile, "percentile")
    if not 0.0 <= percentile <= 100.0:
        raise InvalidInputError(f"expected percentile in [0, 100], got {percentile:g}")
    if method == "pca" and not 0.0 < percentile <= 50.0:  # two sets of that share each
        raise InvalidInputError(
            "expected percentile in (0, 50] for pca (the share of darkest and of brightest "
            f"pixels, Cheng et al. 2014: 3.5), got {percentile:g}"
        )
    p = as_real(p, "Minkowski p", minimum=1.0, maximum=MAX_MINKOWSKI_P)
    sigma = as_real(sigma, "sigma", nonnegative=True, maximum=MAX_SIGMA)
    if cct is not None:
        as_real(cct, "cct (K)", positive=True)
    if illuminant is not None:
        resolve_white(illuminant, name="illuminant")  # "unknown white 'Q' for illuminant ..."


def _linear(image: object, transfer: str, channel_axis: int) -> tuple[Any, Any, str]:
    tname = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    axis = as_int(channel_axis, "channel_axis")
    if axis != -1:  # images are channels-last everywhere (docs/conventions.md)
        _deprecate.warn(
            "channel_axis=",
            "move the channels last first (numpy.moveaxis(image, axis, -1))",
            stacklevel=4,
        )
    try:
        img = as_image_strict(image, "image", channels=3, channel_axis=axis)
    except InvalidInputError as exc:
        if axis == -1 or "channels on axis" not in str(exc):
            raise
        raise InvalidInputError(
            f"expected image with 3 channels on axis channel_axis={axis}, got {describe(image)}"
        ) from None
    check_nonempty(img, "image")
    if img.ndim < 3:
        raise InvalidInputError(
            f"expected an image of shape (..., H, W, 3), got shape {tuple(img.shape)}"
        )
    xp = namespace(img)
    lin = img if tname == "linear" else decode(img, tname)
    return xp, lin, tname


def estimate_illuminant(
    image: ArrayLike,
    method: str = "gray_world",
    *,
    transfer: str = "srgb",
    percentile: float | None = None,
    p: float = 6.0,
    sigma: float = 1.0,
    illuminant: str | ArrayLike | None = None,
    cct: float | None = None,
    space: str = "srgb",
    mask: ArrayLike | None = None,
    channel_axis: int = -1,
) -> Array:
    r"""Estimate the illuminant's colour in linear RGB from an image (see the module notes).

    .. math:: e_c = \left(\mathrm{mean}_x\,|\partial^n \rho_{c,\sigma}(x)|^p\right)^{1/p}

    Parameters
    ----------
    image : array_like, shape (..., H, W, 3)
        RGB image encoded with ``transfer`` (uint8/uint16 read as full range).
    method : {"gray_world", "white_patch", "shades_of_gray", "gray_edge", "grayness_index", \
"pca", "manual"}
        ``"grey_world"``, ``"max_rgb"``, ``"shades_of_grey"``, ``"grey_edge"``,
        ``"greyness_index"`` also accepted.
    transfer : str
        Encoding of ``image`` (``"srgb"``, ``"linear"`` ..., see
        :data:`imageform.color.TRANSFER_FUNCTIONS`).
    percentile : float, optional
        ``white_patch``: percentile in [0, 100]; 99 by default, 100 (the maximum) for
        ``"max_rgb"``. ``grayness_index``: the percent of the image's pixels taken as grey
        (0.1). ``pca``: the percent of the pixels taken at each end, darkest and brightest
        (3.5).
    p : float
        ``shades_of_gray`` / ``gray_edge``: Minkowski norm, ``p >= 1``.
    sigma : float
        ``gray_edge`` / ``grayness_index``: Gaussian scale in pixels, ``>= 0``.
    illuminant, cct :
        ``manual``: a white (name, ``(x, y)``, ``XYZ``) or a CCT in kelvin (Planckian locus,
        Robertson 1968, from 1667 K).
    space : str
        ``manual``: the RGB space of the image (its primaries convert the white to RGB).
    mask : array_like of bool, shape (H, W) or (..., H, W), optional
        The pixels to measure the light by (True); the others (a colour chart, clipped
        highlights, a frame) are left out of every estimate: of the means and the percentile,
        of ``gray_edge``'s blur (a normalised convolution) and of its derivatives (a
        derivative whose stencil touches a left-out pixel), of the candidates of
        ``grayness_index`` and ``pca``. The colour-constancy sets' convention: the chart and
        the pixels at the sensor's saturation in some channel left out, e.g.
        ``mask=raw.max(axis=-1) < saturation``. None: every pixel.
    channel_axis : int
        Deprecated (removed in imageform 0.3.0): images are channels-last everywhere; move
        the channels last first (``numpy.moveaxis(image, axis, -1)``).

    Returns
    -------
    array, shape (..., 3)
        Linear RGB of the illuminant (not normalised; ``pca``: of unit length).

    Raises
    ------
    DegenerateConfigurationError
        ``grayness_index`` / ``pca``: no pixel is a candidate (a flat, clipped or black
        image): nothing to measure the light by. ``mask`` keeps no pixel.
    InvalidInputError
        ``mask`` is not booleans of the image's height and width.

    References
    ----------
    G. Buchsbaum (1980), J. Franklin Inst. 310(1), 1-26; E. H. Land (1977), Sci. Am. 237(6);
    G. D. Finlayson, E. Trezzi (2004), CIC 12, 37-41; J. van de Weijer, T. Gevers,
    A. Gijsenij (2007), IEEE TIP 16(9), 2207-2214; K.-F. Yang, S.-B. Gao, Y.-J. Li (2015),
    CVPR, 2254-2263 (grey pixels); Y. Qian, J.-K. Kämäräinen, J. Nikkanen, J. Matas (2019),
    CVPR, 8062-8070 (the grayness index); D. Cheng, D. K. Prasad, M. S. Brown (2014),
    JOSA A 31(5), 1049-1058 (PCA); S. D. Hordley, G. D. Finlayson (2006), JOSA A 23(5),
    1008-1020 (the angular error).

    Examples
    --------
    >>> import numpy as np
    >>> img = np.ones((2, 2, 3)) * [0.4, 0.5, 0.6]
    >>> estimate_illuminant(img, transfer="linear").round(6).tolist()
    [0.4, 0.5, 0.6]
    """
    m, percentile = _method(method, percentile)
    _check_params(m, percentile, p, sigma, illuminant, cct)
    xp, lin, _ = _linear(image, transfer, channel_axis)
    return _estimate(xp, lin, m, percentile, p, sigma, illuminant, cct, space, mask)


def _estimate(
    xp: Any,
    lin: Any,
    m: str,
    percentile: float,
    p: float,
    sigma: float,
    illuminant: Any,
    cct: float | None,
    space: str,
    mask: Any = None,
) -> Any:
    extra = {} if mask is None or m == "manual" else _weights(xp, lin, mask)
    return WHITE_BALANCE_METHODS[m](
        xp,
        lin,
        percentile=percentile,
        p=p,
        sigma=sigma,
        illuminant=illuminant,
        cct=cct,
        space=space,
        **extra,
    )


def _weights(xp: Any, lin: Any, mask: Any) -> dict[str, Any]:
    """Check ``mask`` against the image; its 0/1 weights in the image's namespace, and counts.

    The mask is booleans (or 0/1) of shape (H, W), or (..., H, W) broadcasting to the
    image's batch; an image of a batch with no pixel kept is refused.
    """
    shape = tuple(lin.shape[:-1])
    try:
        mk = np.asarray(mask)
    except (TypeError, ValueError):  # not an array NumPy can read: refused below
        mk = None
    if mk is None or mk.dtype.kind not in "biu" or mk.ndim < 2 or mk.ndim > len(shape):
        raise InvalidInputError(
            f"expected mask as booleans of shape (H, W) = {shape[-2:]}, got {describe(mask)}"
        )
    try:
        mk = np.broadcast_to(mk != 0, shape)
    except ValueError:
        raise InvalidInputError(
            f"expected mask of shape (H, W) = {shape[-2:]} (or the image's batch), got "
            f"shape {mk.shape}"
        ) from None
    kept = mk.sum(axis=(-2, -1))
    if not np.all(kept > 0):
        raise DegenerateConfigurationError(
            "mask keeps no pixel of the image (of an image of the batch): nothing to measure "
            "the light by"
        )
    w = np.ascontiguousarray(mk, dtype=np.dtype(str(lin.dtype).split(".")[-1]))
    if is_dask_namespace(xp):
        import dask.array as da

        return {"w": da.from_array(w, chunks=lin.chunks[:-1]), "kept": kept}
    return {"w": xp.asarray(w, device=device_of(lin)), "kept": kept}


def _est_gray_world(xp: Any, lin: Any, *, w: Any = None, **_: Any) -> Any:
    return _masked_mean(xp, lin, w)


def _est_white_patch(
    xp: Any, lin: Any, *, percentile: float, w: Any = None, kept: Any = None, **_: Any
) -> Any:
    return _percentile(xp, lin, float(percentile), w, kept)


def _est_shades_of_gray(xp: Any, lin: Any, *, p: float, w: Any = None, **_: Any) -> Any:
    return _minkowski(xp, lin, float(p), w)


def _est_gray_edge(xp: Any, lin: Any, *, p: float, sigma: float, w: Any = None, **_: Any) -> Any:
    if lin.shape[-3] < 3 or lin.shape[-2] < 3:
        raise InvalidInputError("gray_edge needs an image of at least 3 x 3 pixels")
    return _gray_edge(xp, lin, float(p), float(sigma), w)


#: ``grayness_index``: a pixel with a channel at or above this fraction of that channel's
#: largest value in the image is clipped (or nearly), and is not a candidate.
GI_CLIP = 0.95
#: ``grayness_index``: a pixel with a channel at or below this fraction of that channel's
#: largest value is too dark for its log contrast to mean anything (noise, quantisation).
GI_DARK = 2e-3
#: ``grayness_index``: least absolute Laplacian of the log image (some channel) of a pixel
#: with contrast; a flat pixel is grey by the index whatever its colour, and is left out.
GI_MIN_CONTRAST = 1e-4
#: ``grayness_index``: side of the square window the index is averaged over (Qian et al.).
GI_WINDOW = 7
#: ``pca``: power iterations for the leading eigenvector of the 3 x 3 moment matrix (its
#: second eigenvalue is a small fraction of the first for a real image: converged long before).
_PCA_ITERATIONS = 60


def _unclipped(xp: Any, lin: Any, w: Any = None) -> tuple[Any, Any]:
    """Find the pixels with no channel clipped nor black, and each channel's floor.

    Clipped and black are :data:`GI_CLIP` and :data:`GI_DARK` of each channel's largest value
    (so that channel gains do not change them); the floor is ``GI_DARK`` of the largest
    value, at least the dtype's smallest normal number.
    """
    top = xp.max(lin if w is None else lin * w[..., None], axis=(-3, -2), keepdims=True)
    tiny = float(np.finfo(np.dtype(str(lin.dtype).split(".")[-1])).tiny)
    ok = xp.all((lin > GI_DARK * top) & (lin < GI_CLIP * top), axis=-1)
    if w is not None:
        ok = ok & (w > 0)
    return ok, xp.maximum(GI_DARK * top, tiny)


def _log_laplacian(xp: Any, lin: Any, sigma: float, w: Any = None) -> tuple[Any, Any]:
    """Return the Laplacian of the smoothed log image on the interior pixels, and candidates.

    A candidate has no channel clipped or too dark in its stencil, and some contrast.
    """
    ok, floor = _unclipped(xp, lin, w)
    x = xp.log(xp.maximum(lin, floor))
    if sigma > 0:
        x = _gauss_smooth(xp, _gauss_smooth(xp, x, sigma, -3), sigma, -2)
    lap = _interior(xp, _laplacian, x, True)
    # a candidate's whole stencil is unclipped: next to a clipped or black pixel (a masked
    # region) the Laplacian measures the floor, not the surface
    ok = _interior(xp, _stencil_all, ok, False) & (xp.max(xp.abs(lap), axis=-1) >= GI_MIN_CONTRAST)
    return lap, ok


def _grayness_index(xp: Any, lin: Any, q: float, sigma: float, w: Any = None) -> Any:
    lap, ok = _log_laplacian(xp, lin, sigma, w)
    d_r = lap[..., 0] - lap[..., 1]
    d_b = lap[..., 2] - lap[..., 1]
    w = xp.astype(ok, lap.dtype)[..., None]
    gi = xp.sqrt(d_r * d_r + d_b * d_b)[..., None]
    box = [1.0] * GI_WINDOW
    num = _smooth(xp, _smooth(xp, gi * w, box, -3), box, -2)
    den = _smooth(xp, _smooth(xp, w, box, -3), box, -2)
    gi = xp.where(ok, num[..., 0] / xp.maximum(den[..., 0], 1e-12), math.inf)
    sel = ok & (gi <= _kth_smallest(xp, gi, q)[..., None, None])
    return _pixel_mean(xp, lin[..., 1:-1, 1:-1, :] * xp.astype(sel, lin.dtype)[..., None])


def _kth_smallest(xp: Any, x: Any, q: float) -> Any:
    """Per image of (..., H, W): the k-th smallest value, k = ceil(q % of H W) (at least 1)."""
    shape = tuple(x.shape)
    n = shape[-2] * shape[-1]
    flat = xp.reshape(x, (*shape[:-2], n))
    k = min(n, max(1, math.ceil(q / 100.0 * n)))
    if is_dask_namespace(xp):
        import dask.array as da

        return -da.topk(-flat, k, axis=-1)[..., k - 1]
    return xp.sort(flat, axis=-1)[..., k - 1]


def _pca(xp: Any, lin: Any, q: float, w: Any = None) -> Any:
    ok, _ = _unclipped(xp, lin, w)
    mean = _pixel_mean(xp, lin * xp.astype(ok, lin.dtype)[..., None])
    t = xp.sum(lin * mean[..., None, None, :], axis=-1)  # projection on the mean colour
    lo = _kth_smallest(xp, xp.where(ok, t, math.inf), q)
    hi = -_kth_smallest(xp, xp.where(ok, -t, math.inf), q)
    sel = ok & ((t <= lo[..., None, None]) | (t >= hi[..., None, None]))
    x = _flat(xp, lin * xp.astype(sel, lin.dtype)[..., None])
    # the 3 x 3 second-moment matrix of the selected pixels (not centred: the line of the
    # light passes through black), in float64 as the means are
    m = xp.stack(
        [_pixel_mean(xp, (x * x[..., c : c + 1])[..., None, :, :]) for c in range(3)], axis=-2
    )
    if is_dask_namespace(xp):
        return _power_iteration_dask(m, mean)
    return _power_iteration(xp, m, mean)


def _power_iteration(xp: Any, m: Any, v: Any) -> Any:
    """Iterate ``v`` (..., 3) towards the leading eigenvector of ``m`` (..., 3, 3)."""
    for _ in range(_PCA_ITERATIONS):
        v = xp.sum(m * v[..., None, :], axis=-1)
        v = v / xp.maximum(xp.sqrt(xp.sum(v * v, axis=-1, keepdims=True)), 1e-300)
    return v


def _power_iteration_dask(m: Any, v: Any) -> Any:
    """:func:`_power_iteration` of Dask arrays in one task per batch block.

    The 60 iterations on the lazy 3 x 3 matrices made 689 graph layers (2.5 s to build for
    one image); each block runs the in-memory loop instead (the same arithmetic).
    """
    m = m.rechunk({m.ndim - 2: -1, m.ndim - 1: -1})
    v = v[..., None, :].rechunk({v.ndim - 1: -1, v.ndim: -1})  # (..., 1, 3): m's axes

    def block(mb: Any, vb: Any) -> Any:
        return _power_iteration(namespace(mb), mb, vb[..., 0, :])[..., None, :]

    return m.map_blocks(block, v, chunks=v.chunks, dtype=v.dtype)[..., 0, :]


def _est_grayness_index(
    xp: Any, lin: Any, *, percentile: float, sigma: float, w: Any = None, **_: Any
) -> Any:
    if lin.shape[-3] < 3 or lin.shape[-2] < 3:
        raise InvalidInputError("grayness_index needs an image of at least 3 x 3 pixels")
    e = _grayness_index(xp, lin, float(percentile), float(sigma), w)
    if not is_dask_namespace(xp) and any_value(~(xp.max(e, axis=-1) > 0), xp):
        raise DegenerateConfigurationError(
            "grayness_index: no pixel of the image has contrast without a clipped or black "
            "channel (a flat, clipped or dark image), so no grey pixel to measure the light "
            "by; use gray_world"
        )
    return e


def _est_pca(xp: Any, lin: Any, *, percentile: float, w: Any = None, **_: Any) -> Any:
    e = _pca(xp, lin, float(percentile), w)
    if not is_dask_namespace(xp) and any_value(~(xp.max(e, axis=-1) > 0), xp):
        raise DegenerateConfigurationError(
            "pca: no pixel of the image without a clipped or black channel to measure the "
            "light by; use gray_world"
        )
    return e


def _est_manual(
    xp: Any, lin: Any, *, illuminant: Any, cct: float | None, space: str, **_: Any
) -> Any:
    return _manual(xp, lin, illuminant, cct, space)


#: The methods of :func:`white_balance` and :func:`estimate_illuminant`, each name mapped to
#: its illuminant estimator ``f(xp, linear_image, *, percentile, p, sigma, illuminant, cct,
#: space) -> (..., 3)`` (read-only). ``"grey_world"``, ``"max_rgb"``, ``"shades_of_grey"``,
#: ``"grey_edge"`` and ``"greyness_index"`` are accepted as aliases
#: (:data:`WHITE_BALANCE_ALIASES`).
WHITE_BALANCE_METHODS: MappingProxyType[str, Callable[..., Any]] = MappingProxyType(
    {
        "gray_world": _est_gray_world,
        "white_patch": _est_white_patch,
        "shades_of_gray": _est_shades_of_gray,
        "gray_edge": _est_gray_edge,
        "grayness_index": _est_grayness_index,
        "pca": _est_pca,
        "manual": _est_manual,
    }
)


def white_balance(
    image: ArrayLike,
    method: str = "gray_world",
    *,
    transfer: str = "srgb",
    normalize: str = "mean",
    percentile: float | None = None,
    p: float = 6.0,
    sigma: float = 1.0,
    illuminant: str | ArrayLike | None = None,
    cct: float | None = None,
    space: str = "srgb",
    clip: bool = False,
    mask: ArrayLike | None = None,
    channel_axis: int = -1,
) -> WhiteBalanceResult:
    r"""White-balance an image: estimate the illuminant, divide it out in linear light.

    .. math:: \rho'_c = \frac{\bar e}{e_c}\,\rho_c \quad(\text{normalize="mean"}),\qquad
        \rho'_c = \frac{e_G}{e_c}\,\rho_c \quad(\text{normalize="green"})

    Parameters
    ----------
    image : array_like, shape (..., H, W, 3)
        RGB image encoded with ``transfer`` (uint8/uint16 read as full range).
    method : str
        See :func:`estimate_illuminant` (``"gray_world"``, the lecture's method, by default).
    transfer : str
        Encoding of the input and of the output (``"linear"`` for linear images).
    normalize : {"mean", "green"}
        Keep the mean grey of the illuminant (the lecture's grey world) or the green channel.
    percentile, p, sigma, illuminant, cct, space :
        Method parameters, see :func:`estimate_illuminant`.
    clip : bool
        Clip the balanced linear values to [0, 1] before encoding (only when asked: the gains
        can push highlights above 1).
    mask : array_like of bool, shape (H, W) or (..., H, W), optional
        The pixels the light is estimated from (see :func:`estimate_illuminant`); the gains
        apply to every pixel.
    channel_axis : int
        Deprecated (removed in imageform 0.3.0): images are channels-last everywhere; move
        the channels last first (``numpy.moveaxis(image, axis, -1)``).

    Returns
    -------
    WhiteBalanceResult
        ``(image, gains)``: the balanced image in the input's encoding (float; float32 for
        integer input) and the gains, shape ``(..., 3)``.

    Raises
    ------
    DegenerateConfigurationError
        When a channel's estimate is zero (e.g. an all-black channel): no gain exists.

    References
    ----------
    See :func:`estimate_illuminant`.

    Examples
    --------
    Grey world on a linear image with channel means 0.4, 0.5, 0.6 (mean 0.5):

    >>> import numpy as np
    >>> img = np.ones((2, 2, 3)) * [0.4, 0.5, 0.6]
    >>> out, gains = white_balance(img, transfer="linear")
    >>> gains.round(4).tolist(), out[0, 0].round(6).tolist()
    ([1.25, 1.0, 0.8333], [0.5, 0.5, 0.5])
    """
    m, percentile = _method(method, percentile)
    norm = check_name(normalize, ("mean", "green"), "gain normalisation", "normalize")
    _check_params(m, percentile, p, sigma, illuminant, cct)
    xp, lin, tname = _linear(image, transfer, channel_axis)
    gains = _gains(xp, lin, m, norm, percentile, p, sigma, illuminant, cct, space, mask)
    out = _apply(xp, lin, gains, tname, as_bool(clip, "clip"))
    return WhiteBalanceResult._make((out, gains))  # from checked input: no second pass


def _gains(
    xp: Any,
    lin: Any,
    m: str,
    norm: str,
    percentile: Any,
    p: float,
    sigma: float,
    illuminant: Any,
    cct: float | None,
    space: str,
    mask: Any = None,
) -> Any:
    e = _estimate(xp, lin, m, percentile, p, sigma, illuminant, cct, space, mask)
    why = _why_zero(m, float(percentile))
    if is_dask_namespace(xp):
        e = e.map_blocks(_check_estimate, why, dtype=e.dtype)  # lazily: raises at compute
    elif any_value(~(e > 0), xp):
        _check_estimate(np.asarray(e), why)
    ref = xp.mean(e, axis=-1, keepdims=True) if norm == "mean" else e[..., 1:2]
    return ref / e


def _apply(xp: Any, lin: Any, gains: Any, tname: str, clip: bool) -> Any:
    out = lin * gains[..., None, None, :]
    if clip:
        out = xp.clip(out, 0.0, 1.0)
    if tname != "linear":
        out = encode(out, tname)
    return out


def white_balance_gains(
    image: ArrayLike,
    method: str = "gray_world",
    *,
    transfer: str = "srgb",
    normalize: str = "mean",
    percentile: float | None = None,
    p: float = 6.0,
    sigma: float = 1.0,
    illuminant: str | ArrayLike | None = None,
    cct: float | None = None,
    space: str = "srgb",
    mask: ArrayLike | None = None,
) -> Array:
    """Return the gains :func:`white_balance` finds for ``image`` (not applied).

    With :func:`apply_white_balance_gains`, the same as :func:`white_balance`, a band of rows at a
    time (the ``imageform white-balance`` command: bounded memory). Internal.
    """
    m, percentile = _method(method, percentile)
    norm = check_name(normalize, ("mean", "green"), "gain normalisation", "normalize")
    _check_params(m, percentile, p, sigma, illuminant, cct)
    a = image if isinstance(image, np.ndarray) else None
    if a is None or a.ndim != 3 or a.shape[0] < 2:
        xp, lin, _ = _linear(image, transfer, -1)
        return _gains(xp, lin, m, norm, percentile, p, sigma, illuminant, cct, space, mask)
    # the linear image made a band of rows at a time (the same values: decoding is pixel by
    # pixel), so that decoding's float64 temporaries never span the whole image
    rows = max(1, 2**20 // max(a.shape[1], 1))
    lin = None
    for r0 in range(0, a.shape[0], rows):
        xp, band, _ = _linear(a[r0 : r0 + rows], transfer, -1)
        if lin is None:
            lin = np.empty(a.shape, dtype=band.dtype)
        lin[r0 : r0 + rows] = band
    return _gains(xp, lin, m, norm, percentile, p, sigma, illuminant, cct, space, mask)


def apply_white_balance_gains(
    image: ArrayLike, gains: ArrayLike, *, transfer: str = "srgb"
) -> Array:
    """Apply ``gains`` (from :func:`white_balance_gains`) as :func:`white_balance` does.

    ``gains`` is ``(..., 3)`` positive finite numbers (one triple per image of a batch).
    """
    from imageform.color import _gpu

    tname = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    # a CUDA image and 3 host gains: one kernel
    on_gpu = _gpu.gains(image, gains, _kernel_step(tname, True), _kernel_step(tname, False))
    if on_gpu is not None:
        return on_gpu
    xp, lin, tname = _linear(image, transfer, -1)
    g = as_real_array(gains, "gains", positive=True)
    if g.ndim < 1 or g.shape[-1] != 3:
        raise InvalidInputError(
            f"expected gains as 3 positive numbers (R, G, B), got {describe(gains)}"
        )
    if float(g.max()) > MAX_GAIN:
        raise InvalidInputError(
            f"expected gains <= {MAX_GAIN:g} (a white balance gain), got {float(g.max()):g}"
        )
    return _apply(xp, lin, xp.asarray(g, dtype=lin.dtype, device=device_of(lin)), tname, False)
