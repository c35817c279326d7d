"""Defocus: disc point-spread functions and depth-dependent blur from the circle of confusion.

Geometric optics: a point off the plane of focus images as a uniform disc whose diameter is
the circle of confusion (:func:`imageform.optics.circle_of_confusion`). Spatially varying
blur is applied by *layers*: the image is blurred with discs at a ladder of radii and each
pixel takes the linear interpolation between the two layers that bracket its own radius
(a gather approximation that ignores occlusion at depth edges).

Images are NumPy ``(H, W)`` or ``(H, W, C)``; uint8/uint16 read as full range; borders
are reflected (``mode="reflect"`` in :mod:`scipy.signal`'s sense, by padding).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from imageform import _deprecate
from imageform._backend import to_numpy
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_image,
    as_int,
    as_real_array,
    check_positive,
    check_real_values,
    describe,
    finite_result,
    format_shape,
    memory_limit,
)
from imageform.errors import InvalidInputError
from imageform.optics.depth_of_field import circle_of_confusion

__all__ = ["blur_by_radius", "defocus_blur", "defocus_radius_px", "disc_kernel"]

_SUPERSAMPLE = 16
#: The most layers :func:`blur_by_radius` convolves (each one is a full-image convolution).
_MAX_LAYERS = 4096


def _kernel_bytes(radius: float) -> float:
    """Count the bytes :func:`disc_kernel` allocates for ``radius``.

    The sub-pixel grid's booleans and two float64 temporaries of ``(16 m)²`` with
    ``m = 2⌈R⌉ + 1``.
    """
    x = (2.0 * math.ceil(radius) + 1.0) * _SUPERSAMPLE
    return x * x * 17.0  # inf, not OverflowError, beyond the float range


def _check_blur_radius(radius: float, shape: tuple[int, ...], names: str) -> None:
    """Refuse a blur radius whose disc kernel or FFT convolution would not fit in memory.

    The kernel, or the padded FFT convolution of an image of ``shape`` (H, W, C), must fit
    :func:`memory_limit`; ``names`` says which arguments made the radius.
    """
    p = math.ceil(radius) if math.isfinite(radius) else math.inf
    h, w = shape[0], shape[1]
    c = shape[2] if len(shape) > 2 else 1
    need = max(
        _kernel_bytes(radius) if p < math.inf else math.inf,
        (h + 2.0 * p) * (w + 2.0 * p) * c * 16.0 * 3.0,
    )
    limit = memory_limit()
    if not need <= limit:
        raise InvalidInputError(
            f"{names}: a blur radius of {radius:.3g} px would need {need / 2**30:.3g} GiB, "
            f"more than the {limit / 2**30:.1f} GiB allowed (IMAGEFORM_MAX_MEMORY)"
        )


def disc_kernel(radius: float) -> np.ndarray:
    r"""Return a normalised uniform-disc PSF of ``radius`` pixels, anti-aliased by pixel coverage.

    .. math::

        h(i, j) = \frac{|\mathrm{pixel}_{ij} \cap \{r \le R\}|}
                       {\sum_{kl} |\mathrm{pixel}_{kl} \cap \{r \le R\}|}

    Coverage is integrated on a 16 × 16 sub-pixel grid; ``radius = 0`` gives the identity
    ``[[1.0]]``. Shape ``(2 ⌈R⌉ + 1, 2 ⌈R⌉ + 1)``; sums to 1.

    Examples
    --------
    >>> disc_kernel(0).tolist()
    [[1.0]]
    >>> k = disc_kernel(3.0); k.shape, round(float(k.sum()), 12)
    ((7, 7), 1.0)
    """
    r = check_positive(radius, "radius (pixels)", allow_zero=True)
    _check_blur_radius(r, (1, 1), "radius")
    if r == 0:
        return np.ones((1, 1))
    n = math.ceil(r)
    sub = (np.arange(_SUPERSAMPLE) + 0.5) / _SUPERSAMPLE - 0.5
    coords = (np.arange(-n, n + 1)[:, None] + sub[None, :]).ravel()
    inside = (coords[:, None] ** 2 + coords[None, :] ** 2) <= r * r
    m = 2 * n + 1
    cover = inside.reshape(m, _SUPERSAMPLE, m, _SUPERSAMPLE).mean(axis=(1, 3))
    if cover.sum() == 0:  # radius below the sub-pixel grid: all light in the centre pixel
        cover[n, n] = 1.0
    return cover / cover.sum()


def _prep(image: Any) -> tuple[np.ndarray, bool]:
    arr = np.asarray(to_numpy(as_image(image, "image", channels=None)))
    if arr.ndim not in (2, 3) or 0 in arr.shape:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (H, W, C), non-empty, got {format_shape(arr.shape)}"
        )
    gray = arr.ndim == 2
    return (arr[..., None] if gray else arr), gray


def _convolve(img: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``img (H, W, C)`` convolved with ``kernel`` with reflected borders, same size."""
    if kernel.shape == (1, 1):
        return img.copy()
    from scipy.signal import fftconvolve  # imported on use, not with imageform.optics

    p = kernel.shape[0] // 2
    if min(img.shape[:2]) > p:
        padded = np.pad(img, ((p, p), (p, p), (0, 0)), mode="reflect")
    else:
        padded = np.pad(img, ((p, p), (p, p), (0, 0)), mode="symmetric")
    out = fftconvolve(padded, kernel[..., None].astype(img.dtype), mode="valid", axes=(0, 1))
    return out.astype(img.dtype, copy=False)


def blur_by_radius(
    image: ArrayLike,
    radius_px: ArrayLike,
    *,
    step: float = 0.5,
    max_layers: int = 48,
    kernel: Callable[[float], np.ndarray] | None = None,
) -> np.ndarray:
    r"""Blur each pixel with a disc PSF of its own radius (pixels), by layered interpolation.

    .. math::

        I'(p) = (1 - w)\,(I * h_{r_k})(p) + w\,(I * h_{r_{k+1}})(p),\quad
        r_k \le R(p) \le r_{k+1},\ w = \frac{R(p) - r_k}{r_{k+1} - r_k}

    Parameters
    ----------
    image : array (H, W) or (H, W, C)
        The all-in-focus image.
    radius_px : float or array (H, W) or (H, W, C)
        Disc radius per pixel (and per channel, if it has a channel axis), ``>= 0``.
    step : float
        Spacing of the radius ladder in pixels (more layers are not made than ``max_layers``).
    max_layers : int, keyword-only
        Largest number of blur radii in the ladder (the step widens to keep within it).
    kernel : callable, optional, keyword-only
        ``kernel(radius) -> (k, k)`` PSF of unit sum, odd ``k``, used in place of
        :func:`disc_kernel` (e.g. the wave-optics PSF of the same defocus:
        :func:`imageform.simulate.stages.wave_defocus_blur`).

    Returns
    -------
    array, the image's shape and float dtype.

    Examples
    --------
    >>> img = np.zeros((9, 9)); img[4, 4] = 1.0
    >>> out = blur_by_radius(img, 2.0)
    >>> round(float(out.sum()), 9), round(float(out[4, 4]), 4)
    (1.0, 0.0793)
    """
    img, gray = _prep(image)
    r = as_real_array(radius_px, "radius_px", check=False)
    h, w, c = img.shape
    if r.ndim != 0 and r.shape not in ((h, w), (h, w, c)):
        raise InvalidInputError(
            f"expected radius_px scalar, ({h}, {w}) or ({h}, {w}, {c}), got {format_shape(r.shape)}"
        )
    check_real_values(r, "radius_px (pixels)", nonnegative=True)
    st = check_positive(step, "step (pixels)")
    layers = as_int(max_layers, "max_layers", minimum=1, maximum=_MAX_LAYERS)
    if r.ndim == 0:
        r = np.full((h, w, 1), float(r))
    elif r.shape == (h, w):
        r = r[..., None]
    lo, hi = float(r.min()), float(r.max())
    _check_blur_radius(hi, img.shape, "radius_px")
    q = (hi - lo) / st  # may be inf for a tiny step: then max_layers applies
    n = max(2, layers if q >= layers else min(layers, math.ceil(q) + 1))
    ladder = np.linspace(lo, hi, n) if hi > lo else np.array([lo, lo])
    rb = np.broadcast_to(r, img.shape)
    out = np.zeros_like(img)
    if kernel is not None and not callable(kernel):
        raise TypeError(f"expected kernel as a callable radius -> PSF, got {describe(kernel)}")
    make = disc_kernel if kernel is None else kernel
    prev = _convolve(img, make(float(ladder[0])))
    for k in range(1, len(ladder)):
        cur = _convolve(img, make(float(ladder[k]))) if ladder[k] != ladder[k - 1] else prev
        span = ladder[k] - ladder[k - 1]
        below = ladder[k - 1]
        sel = (rb >= below) & ((rb <= ladder[k]) if k == len(ladder) - 1 else (rb < ladder[k]))
        wgt = np.clip((rb - below) / span, 0.0, 1.0) if span > 0 else np.zeros_like(rb)
        out = np.where(sel, (1 - wgt) * prev + wgt * cur, out)
        prev = cur
    out = out.astype(img.dtype, copy=False)
    return out[..., 0] if gray else out


@_deprecate.parameters(renamed={"f": "focal_length"})
def defocus_radius_px(
    depth: ArrayLike, *, focal_length: float, f_number: float, focus: float, pixel_pitch: float
) -> Array:
    r"""Radius in pixels of the defocus disc of points at ``depth``: half the CoC over the pitch.

    ``depth``, ``focal_length``, ``focus`` and ``pixel_pitch`` in metres.

    .. math::

        R_{px}(d) = \frac{c(d)}{2 p}

    Examples
    --------
    >>> r = defocus_radius_px(4.0, focal_length=0.05, f_number=2, focus=2, pixel_pitch=5e-6)
    >>> round(float(r), 3)
    32.051
    """
    p = check_positive(pixel_pitch, "pixel_pitch (m)")
    coc = circle_of_confusion(depth, focal_length=focal_length, f_number=f_number, focus=focus)
    return finite_result(
        "the defocus radius", lambda: coc / (2 * p), pixel_pitch=p, depth=depth, f_number=f_number
    )


@_deprecate.parameters(renamed={"f": "focal_length"})
def defocus_blur(
    image: ArrayLike,
    depth: ArrayLike,
    *,
    focal_length: float,
    f_number: float,
    focus: float,
    pixel_pitch: float,
    step: float = 0.5,
) -> np.ndarray:
    r"""Depth-dependent defocus: each pixel blurred by the disc of its circle of confusion.

    .. math::

        I' = \mathrm{blur}\big(I, R_{px}(d)\big),\quad
        R_{px}(d) = \frac{1}{2p} \frac{f}{N} \frac{|d - s|}{d} \frac{f}{s - f}

    Parameters
    ----------
    image : array (H, W) or (H, W, C)
        The all-in-focus image.
    depth : float or array (H, W)
        Distance of the scene point seen at each pixel (m).
    focal_length, f_number, focus, pixel_pitch : float
        Focal length (m), f-number, focus distance (m), sensor pixel pitch (m).
    step : float, keyword-only
        Spacing of the blur radii in pixels (see :func:`blur_by_radius`).

    Notes
    -----
    Source: geometric defocus with the thin-lens CoC (Wikipedia "Circle of confusion");
    layered rendering as in :func:`blur_by_radius`.

    Examples
    --------
    >>> img = np.zeros((21, 21)); img[10, 10] = 1.0
    >>> out = defocus_blur(img, 2.0, focal_length=0.05, f_number=2, focus=2.0, pixel_pitch=5e-6)
    >>> float(out[10, 10])  # in focus: unchanged
    1.0
    """
    img, _ = _prep(image)
    d = as_real_array(depth, "depth", check=False)
    if d.ndim not in (0, 2) or (d.ndim == 2 and d.shape != img.shape[:2]):
        raise InvalidInputError(
            f"expected depth scalar or of shape {img.shape[:2]}, got {format_shape(d.shape)}"
        )
    r = defocus_radius_px(
        d, focal_length=focal_length, f_number=f_number, focus=focus, pixel_pitch=pixel_pitch
    )
    _check_blur_radius(
        float(np.max(r)), img.shape, "depth, focal_length, f_number, focus and pixel_pitch"
    )
    return blur_by_radius(image, r, step=step)
