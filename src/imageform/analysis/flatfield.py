r"""Shading (flat-field, vignetting) correction: the inverse of :mod:`imageform.optics.vignetting`.

An image of a uniform scene is not uniform: the lens's natural and mechanical vignetting, an
uneven illumination (a microscope's lamp, an endoscope's LED) and the pixels' own gains
multiply the scene by a smooth **flat field** ``F``; an offset, the **dark field** ``D``
(dark current, a fluorescent background), adds to it:

.. math::

    I_i(x) = B_i\, F(x) + D(x) + S_i(x)

with ``B_i`` the brightness of image ``i`` (its *baseline*) and ``S_i`` the scene's own
structure. The correction divides it out (Peng et al. 2017, eq. 1; Model & Burkhardt 2001):

.. math::

    \hat I(x) = \frac{I(x) - D(x)}{F(x) / \overline{F}}

- :func:`correct_flatfield`: the correction, with a measured (prospective: an image of a
  uniform slide or target) or estimated flat field.
- :func:`estimate_flatfield`: the retrospective estimate of BaSiC (Peng et al., *Nature
  Communications* 8, 14836, 2017) from a stack of images of varied content (the tiles of a
  slide, the frames of a time-lapse): the stack is a low-rank smooth part ``B_i F + D`` plus a
  sparse residual, the flat field smooth through an L1 penalty on its DCT coefficients, solved
  by the inexact augmented Lagrange multiplier method, reweighted.
- :func:`estimate_vignetting`: a quick estimate from one frame (a photograph; an
  endoscope's frame with ``mask="auto"``, its field of view: the black surround would break
  the fit) by a robust fit of the radial polynomial ``1 + a_1 r^2 + a_2 r^4 + a_3 r^6``
  (Goldman, *IEEE TPAMI* 32(12), 2010) to the heavily smoothed frame: it cannot tell a
  scene that darkens towards the corners (or, in a colonoscope, brightens towards its
  rim) from vignetting.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from imageform._backend import to_numpy
from imageform._typing import ArrayLike
from imageform._validate import (
    as_image,
    as_int,
    as_real,
    as_real_array,
    as_reals,
    check_real_values,
    describe,
    format_shape,
)
from imageform.errors import InvalidInputError

__all__ = [
    "FlatfieldEstimate",
    "correct_flatfield",
    "estimate_flatfield",
    "estimate_vignetting",
]

#: Side of the square BaSiC fits at (its ``working_size``; Peng et al. 2017, Methods).
WORKING_SIZE = 128


@dataclass(frozen=True)
class FlatfieldEstimate:
    """A flat field and dark field estimated from images.

    Attributes
    ----------
    flatfield : ndarray (H, W) or (H, W, C), float64
        The relative gain of every pixel, mean 1 (per channel).
    darkfield : ndarray, same shape
        The additive offset, in the units the images were read in (uint8 / uint16 as
        fractions of full range, floats as given); zeros when it was not estimated.
    baseline : ndarray (N,) or (N, C)
        Each image's brightness ``B_i`` (``I_i = B_i F + D + residual``): the mean of its
        smooth part (``estimate_vignetting``: the one frame's).
    converged : bool
        Every fit met its tolerance (``tol`` of the ALM, ``reweight_tol`` of the reweighting)
        before its iteration limit.
    iterations : int
        ALM iterations run, over every reweighting and channel (IRLS iterations of the
        radial fit).
    method : str
        ``"basic"`` or ``"radial"``.
    mask : ndarray (H, W) of bool or None
        The pixels the field was fitted to (``estimate_vignetting(mask=...)``: an
        endoscope's field of view); the flat field is mean 1 over them, and :meth:`correct`
        leaves the pixels outside as they are. None: every pixel.
    """

    flatfield: np.ndarray
    darkfield: np.ndarray
    baseline: np.ndarray
    converged: bool
    iterations: int
    method: str
    mask: np.ndarray | None = None

    def correct(self, image: ArrayLike) -> np.ndarray:
        """Return ``image`` corrected with this flat field and dark field.

        Examples
        --------
        >>> est = estimate_vignetting(np.full((32, 48), 0.5))
        >>> est.correct(np.full((32, 48), 0.5)).shape
        (32, 48)
        """
        return correct_flatfield(image, self.flatfield, self.darkfield, mask=self.mask)


# ------------------------------------------------------------------ the correction


def _field(value: ArrayLike, name: str, *, positive: bool) -> np.ndarray:
    """Return a flat or dark field as float64 (H, W) or (H, W, C), checked finite (and > 0)."""
    raw_dtype = getattr(value, "dtype", None)
    arr = as_real_array(value, name, ndim=(2, 3), check=False)
    if not positive and raw_dtype in (np.uint8, np.uint16):  # a dark frame read as an image
        arr = arr / np.iinfo(raw_dtype).max
    if not arr.size:
        raise InvalidInputError(f"expected {name} with pixels, got shape {format_shape(arr.shape)}")
    check_real_values(arr, name)
    if positive and (lo := float(arr.min())) <= 0:
        raise InvalidInputError(
            f"expected {name} > 0 everywhere (a relative gain), got min {lo:g}: a flat field "
            "with zeros has no inverse; crop or mask those pixels"
        )
    return arr


def _check_field_shape(image_shape: tuple[int, ...], field: np.ndarray, name: str) -> None:
    ok = tuple(field.shape[:2]) == tuple(image_shape[:2]) and (
        field.ndim == 2 or (len(image_shape) == 3 and field.shape[2] == image_shape[2])
    )
    if not ok:
        raise InvalidInputError(
            f"expected {name} of the image's size (H, W) or (H, W, C): image "
            f"{format_shape(image_shape)}, {name} {format_shape(field.shape)}"
        )


def correct_flatfield(
    image: ArrayLike,
    flatfield: ArrayLike,
    darkfield: ArrayLike | None = None,
    *,
    mask: ArrayLike | None = None,
) -> np.ndarray:
    r"""Divide an image by its flat field after subtracting its dark field.

    .. math::

        \hat I = \frac{I - D}{F / \overline{F}}

    The flat field is normalised to its mean (per channel), so the correction keeps the
    image's mean brightness and a flat field from any source (a measured frame of a uniform
    slide, its counts as stored) can be given as is.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)
        uint8 / uint16 (read as fractions of full range, as everywhere in imageform) or floats
        in any scale (counts as floats are fine: the correction is linear).
    flatfield : array_like (H, W) or (H, W, C)
        The relative gain, > 0 everywhere; (H, W) applies to every channel.
    darkfield : array_like, optional
        The offset, in the image's units after reading: a uint8 / uint16 dark frame is read
        as the image is (a fraction of full range, counts / 65535 for uint16), floats as
        given; (H, W) or (H, W, C).
    mask : array_like (H, W) of bool, optional
        The pixels to correct (an endoscope's field of view): the flat field is normalised
        to its mean over them, and the pixels outside are returned as they are (read as the
        image is), neither divided nor zeroed: the flat field means nothing there (a black
        surround, burned-in text), and dividing would only amplify its noise.

    Returns
    -------
    ndarray
        The image's shape; float32 for uint8, uint16 and float32 input, else float64. Values
        are not clipped (a corrected pixel can exceed 1).

    Notes
    -----
    NaN and inf in the image (masked or saturated pixels) propagate to the same pixels of the
    result; the flat and dark fields must be finite, the flat field > 0.

    Raises
    ------
    InvalidInputError
        Shapes that differ, a flat field with a value <= 0, NaN or inf in the flat or dark
        field, an image that is not (H, W) or (H, W, C), a mask that is not booleans of the
        image's size or that is False everywhere.

    Examples
    --------
    >>> flat = np.array([[0.5, 1.0, 1.5]])            # mean 1: the edges 50 % off
    >>> correct_flatfield(np.array([[0.2, 0.4, 0.6]]), flat).round(6).tolist()
    [[0.4, 0.4, 0.4]]
    """
    shape = getattr(image, "shape", None)
    flat = _field(flatfield, "flatfield", positive=True)
    dark = None if darkfield is None else _field(darkfield, "darkfield", positive=False)
    if isinstance(shape, tuple):  # an array: its shape before any of its values is read
        _image_dims(shape)
        _check_field_shape(shape, flat, "flatfield")
        if dark is not None:
            _check_field_shape(shape, dark, "darkfield")
    img = np.asarray(
        to_numpy(as_image(image, "image", channels=None, finite=False, range_check=False))
    )
    _image_dims(img.shape)
    _check_field_shape(img.shape, flat, "flatfield")
    if dark is not None:
        _check_field_shape(img.shape, dark, "darkfield")
    if mask is None:
        gain = flat / flat.mean(axis=(0, 1))
    else:
        keep = _as_mask(mask, img.shape)
        gain = flat / flat[keep].mean(axis=0)
    if img.ndim == 3 and gain.ndim == 2:
        gain = gain[..., None]
    out = img.astype(np.float64)
    if dark is not None:
        out = out - (dark[..., None] if img.ndim == 3 and dark.ndim == 2 else dark)
    with np.errstate(invalid="ignore"):  # inf - inf in a masked pixel: NaN, as documented
        out = out / gain
    if mask is not None:
        out[~keep] = img[~keep]
    return out.astype(img.dtype, copy=False)


def _as_mask(mask: object, shape: tuple[int, ...]) -> np.ndarray:
    """Return ``mask`` as a bool (H, W) array of the image's size with a True pixel."""
    try:
        m = to_numpy(mask)
    except (TypeError, ValueError):  # a ragged list, an object that is no array
        raise InvalidInputError(f"expected mask as booleans (H, W), got {describe(mask)}") from None
    if m.dtype != np.bool_:
        raise InvalidInputError(
            f"expected mask as booleans (True where the pixels count), got {describe(mask)}; "
            "give mask > 0 for an image of 0 and 255"
        )
    if m.shape != tuple(shape[:2]):
        raise InvalidInputError(
            f"expected mask of the image's size {format_shape(tuple(shape[:2]))}, got "
            f"{format_shape(m.shape)}"
        )
    if not m.any():
        raise InvalidInputError("expected mask with a True pixel, got False everywhere")
    return m


def _image_dims(shape: tuple[int, ...]) -> None:
    if len(shape) not in (2, 3) or 0 in shape:
        raise InvalidInputError(f"expected image (H, W) or (H, W, C), got {format_shape(shape)}")


# ------------------------------------------------------------------ BaSiC


def _stack(images: object) -> np.ndarray:
    """Return the images as float64 (N, H, W, C): at least 2, one shape, finite, >= 0."""
    if getattr(images, "ndim", None) == 0:
        raise InvalidInputError(
            f"expected images as a stack (N, H, W[, C]) or a sequence of images, got "
            f"{describe(images)}"
        )
    if isinstance(images, np.ndarray | Sequence) and not isinstance(images, str | bytes):
        items: list[Any] = list(images)
    elif hasattr(images, "shape") and hasattr(images, "__len__"):  # a tensor, a Dask array
        items = [images[i] for i in range(len(images))]  # type: ignore[index]
    else:
        raise InvalidInputError(
            f"expected images as a stack (N, H, W[, C]) or a sequence of images, got "
            f"{describe(images)}"
        )
    if len(items) < 2:
        raise InvalidInputError(
            f"expected at least 2 images of varied content, got {len(items)}; for one frame "
            "use estimate_vignetting (a radial fit)"
        )
    shapes = [tuple(getattr(im, "shape", np.shape(im))) for im in items]
    for i, s in enumerate(shapes):
        if len(s) not in (2, 3) or 0 in s:
            raise InvalidInputError(
                f"expected images (H, W) or (H, W, C), got images[{i}] of shape {format_shape(s)}"
            )
        if s != shapes[0]:
            raise InvalidInputError(
                f"expected images of one shape, got {format_shape(shapes[0])} (images[0]) and "
                f"{format_shape(s)} (images[{i}])"
            )
    out = []
    for i, im in enumerate(items):
        name = f"images[{i}]"
        a = np.asarray(to_numpy(as_image(im, name, channels=None, range_check=False)))
        a = a.astype(np.float64, copy=False)
        lo = float(a.min())
        if lo < 0:
            raise InvalidInputError(
                f"expected {name} >= 0 (intensities), got min {lo:g}; add the offset back or "
                "clip it before estimating the flat field"
            )
        out.append(a if a.ndim == 3 else a[..., None])
    stack = np.stack(out)
    if not np.any(stack > 0):
        raise InvalidInputError("expected images with light, got all zeros")
    return stack


def _dct2(a: np.ndarray) -> np.ndarray:
    from scipy.fft import dctn

    return np.asarray(dctn(a, type=2, norm="ortho", axes=(-2, -1)))


def _idct2(a: np.ndarray) -> np.ndarray:
    from scipy.fft import idctn

    return np.asarray(idctn(a, type=2, norm="ortho", axes=(-2, -1)))


def _shrink(x: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """Soft thresholding, the proximal map of ``t |x|_1``."""
    return x - np.clip(x, -t, t)


def _resize(a: np.ndarray, shape: tuple[int, int], order: int) -> np.ndarray:
    """Resize the last two axes of ``a`` to ``shape`` (pixel-centre grid; smoothed when shrunk)."""
    from scipy import ndimage

    h, w = a.shape[-2:]
    if (h, w) == shape:
        return a.copy()
    zh, zw = shape[0] / h, shape[1] / w
    lead = (0.0,) * (a.ndim - 2)
    sig = (*lead, max(0.0, (1 / zh - 1) / 2), max(0.0, (1 / zw - 1) / 2))
    if any(s > 0 for s in sig):  # anti-aliasing as skimage.transform.resize
        a = ndimage.gaussian_filter(a, sig, mode="mirror")
    return np.asarray(
        ndimage.zoom(
            a, (*(1.0,) * (a.ndim - 2), zh, zw), order=order, mode="nearest", grid_mode=True
        )
    )


@dataclass
class _Alm:
    smooth: np.ndarray  # (n, m) the low-rank part B_i F + D
    residual: np.ndarray  # (n, m)
    offset: np.ndarray  # (m,) the dark field
    coeff: np.ndarray  # (n,)
    iterations: int
    converged: bool


def _inexact_alm(
    d: np.ndarray,
    shape: tuple[int, int],
    lam: float,
    lam_dark: float,
    weight: np.ndarray,
    *,
    darkfield: bool,
    tol: float,
    max_iter: int,
) -> _Alm:
    """One BaSiC fit of ``d`` (n images, m = p q pixels) by the inexact ALM.

    The L1-regularised decomposition of Peng et al. 2017 (Methods, eqs. 3-7), as their
    reference implementation iterates it: the flat field's DCT coefficients ``W`` and the
    sparse residual ``E`` each updated once per iteration (soft thresholding), then the
    per-image coefficients and (``darkfield``) the dark field, then the multiplier ``Y``
    and the penalty ``mu`` (times 1.5, at most 1e7 times its start).
    """
    p, q = shape
    n, m = d.shape
    norm_two = float(np.linalg.norm(d, 2))
    mu = 12.5 / norm_two
    mu_bar = mu * 1e7
    rho = 1.5
    ent1, ent2 = 1.0, 10.0
    d_norm = float(np.linalg.norm(d))
    y = np.zeros_like(d)
    e = np.zeros_like(d)
    w_hat = np.zeros((p, q))
    coeff = np.ones(n)
    offset = np.zeros(m)
    b1_up = float(d.min())
    b1_offset = 0.0
    converged = False
    it = 0
    flat = _idct2(w_hat).ravel()
    while it < max_iter:
        it += 1
        flat = _idct2(w_hat).ravel()
        a = coeff[:, None] * flat[None, :] + offset[None, :]
        temp = ((d - a - e + y / mu) / ent1).mean(axis=0).reshape(p, q)
        w_hat = _shrink(w_hat + _dct2(temp), lam / (ent1 * mu))
        flat = _idct2(w_hat).ravel()
        a = coeff[:, None] * flat[None, :] + offset[None, :]
        e = _shrink(e + (d - a - e + y / mu) / ent1, weight / (ent1 * mu))
        r1 = d - e
        total = float(r1.mean())
        coeff = np.maximum(r1.mean(axis=1) / total if total != 0 else np.ones(n), 0.0)
        if darkfield:
            offset, b1_offset = _dark_update(r1, flat, coeff, shape, lam_dark / (ent2 * mu), b1_up)
        z = d - a - e
        y = y + mu * z
        mu = min(mu * rho, mu_bar)
        if float(np.linalg.norm(z)) / d_norm < tol:
            converged = True
            break
    offset = offset + b1_offset * flat
    return _Alm(a, e, offset, coeff, it, converged)


def _dark_update(
    r1: np.ndarray,
    flat: np.ndarray,
    coeff: np.ndarray,
    shape: tuple[int, int],
    thresh: float,
    b1_up: float,
) -> tuple[np.ndarray, float]:
    """Run the dark-field step of the reference implementation (Peng et al. 2017, Methods).

    The offset ``B1`` is the least-squares fit of the images' bright-minus-dark contrast
    against their coefficients (bounded to [0, min(D) / mean F]); the rest of the offset is
    made smooth (shrunk in the DCT domain) and sparse (shrunk in the pixel domain).
    """
    valid = np.flatnonzero(coeff < 1)
    mean_flat = float(flat.mean())
    if valid.size == 0:
        return np.zeros_like(flat), 0.0
    rv = r1[valid]
    hi = flat > mean_flat - 1e-6
    lo = flat < mean_flat + 1e-6
    b1_coeff = (rv[:, hi].mean(axis=1) - rv[:, lo].mean(axis=1)) / float(r1.mean())
    k = valid.size
    cv = coeff[valid]
    t1, t2, t3, t4 = (
        float((cv**2).sum()),
        float(cv.sum()),
        float(b1_coeff.sum()),
        float((cv * b1_coeff).sum()),
    )
    t5 = t2 * t3 - k * t4
    b1 = 0.0 if t5 == 0 else (t1 * t3 - t2 * t4) / t5
    b1 = max(b1, 0.0)
    if mean_flat > 0:
        b1 = min(b1, b1_up / mean_flat)
    b_offset = b1 * mean_flat - b1 * flat
    a1_offset = rv.mean(axis=0) - cv.mean() * flat
    a1_offset = a1_offset - a1_offset.mean()
    off = a1_offset - b_offset
    off = _idct2(_shrink(_dct2(off.reshape(shape)), thresh)).ravel()
    off = _shrink(off, thresh)
    return off + b_offset, b1


def _basic_channel(
    d: np.ndarray,
    shape: tuple[int, int],
    *,
    darkfield: bool,
    smoothness: float | None,
    smoothness_darkfield: float | None,
    sort_intensity: bool,
    tol: float,
    max_iter: int,
    max_reweightings: int,
    reweight_tol: float,
    epsilon: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, bool]:
    """Run BaSiC on one channel at working size: (shading, dark, coefficients, its, ok)."""
    p, q = shape
    n = d.shape[0]
    mean_img = d.mean(axis=0)
    mean_img = mean_img / mean_img.mean()
    scale = float(np.abs(_dct2(mean_img)).sum()) / 400.0
    lam = scale * 0.5 if smoothness is None else smoothness
    lam_dark = scale * 0.2 if smoothness_darkfield is None else smoothness_darkfield
    data = np.sort(d, axis=0) if sort_intensity else d
    data = data.reshape(n, p * q)
    weight = np.ones_like(data)
    last_flat = np.ones(p * q)
    last_dark: np.ndarray | None = None
    total_its = 0
    ok = True
    settled = False
    for _ in range(max_reweightings):
        fit = _inexact_alm(
            data, shape, lam, lam_dark, weight, darkfield=darkfield, tol=tol, max_iter=max_iter
        )
        total_its += fit.iterations
        ok = ok and fit.converged
        per_image = fit.smooth.mean(axis=1, keepdims=True)
        e_norm = fit.residual / (per_image + 1e-6)
        weight = 1.0 / (np.abs(e_norm) + epsilon)
        weight = weight * weight.size / weight.sum()
        temp = fit.smooth.mean(axis=0) - fit.offset
        flat = temp / temp.mean()
        dark = fit.offset
        mad_flat = float(np.abs(flat - last_flat).sum() / np.abs(last_flat).sum())
        if last_dark is None:
            mad_dark = 0.0 if not darkfield else math.inf
        else:
            diff = float(np.abs(dark - last_dark).sum())
            mad_dark = 0.0 if diff < 1e-7 else diff / max(float(np.abs(last_dark).sum()), 1e-6)
        last_flat, last_dark = flat, dark
        if max(mad_flat, mad_dark) <= reweight_tol:
            settled = True
            break
    shading = (fit.smooth.mean(axis=0) - fit.offset).reshape(p, q)
    return shading, fit.offset.reshape(p, q), fit.coeff, total_its, ok and settled


def estimate_flatfield(
    images: ArrayLike | Sequence[ArrayLike],
    *,
    darkfield: bool = False,
    smoothness: float | None = None,
    smoothness_darkfield: float | None = None,
    sort_intensity: bool = False,
    working_size: int = WORKING_SIZE,
    max_iter: int = 500,
    tol: float = 1e-6,
    max_reweightings: int = 10,
    reweight_tol: float = 1e-3,
) -> FlatfieldEstimate:
    r"""Estimate the flat field (and dark field) of a stack of images by BaSiC.

    The stack, resized to ``working_size`` squared and sorted pixel by pixel
    (``sort_intensity``), is split into a smooth low-rank part and a sparse residual
    (Peng et al. 2017, eqs. 3-5):

    .. math::

        \min_{W, E}\ \|W\|_1 + \lambda_S \|E\|_{1,w}
        \quad\text{s.t.}\quad I_i = B_i\,\mathcal{D}^{-1}(W) + D + E_i

    with ``W`` the flat field's 2-D DCT coefficients (their L1 norm makes it smooth), ``E``
    the scene, weighted by ``w = 1 / (|E| / \overline{I_i} + 0.1)`` and reweighted until the
    flat field changes by less than ``reweight_tol`` (mean absolute change), each fit the
    inexact augmented Lagrange multiplier method (Lin, Chen & Ma 2010) stopped at
    ``||I - A - E||_F / ||I||_F < tol``. The regularisation weights default to the reference
    MATLAB code's rule (``BaSiC.m``): ``smoothness = 0.5 s``, ``smoothness_darkfield = 0.2 s``,
    ``s = ||DCT(mean image / its mean)||_1 / 400``; its Python port PyBaSiC (whose results
    BaSiCPy ships as reference) uses ``smoothness_darkfield = 0.1 s``, basicpy 2.0
    ``0.05 s``, and the flat field depends on it by a few percent. Colour stacks are
    corrected channel by channel.

    Parameters
    ----------
    images : array_like (N, H, W) or (N, H, W, C), or a sequence of N images
        N >= 2 images of one shape and of varied content (tiles, frames), non-negative; uint8 /
        uint16 as fractions of full range, floats in any scale.
    darkfield : bool
        Also estimate the dark field (dim fluorescence); else it is zero.
    smoothness, smoothness_darkfield : float, optional
        The paper's ``lambda_F`` and ``lambda_D`` (larger: smoother); default the MATLAB
        code's rule above.
    sort_intensity : bool
        Sort every pixel's values over the stack before the fit, as the reference MATLAB
        implementation does (better for tiles; turn off for a time-lapse whose baseline
        matters per frame).
    working_size : int
        Side of the square the stack is resized to (the paper's 128).
    max_iter, tol : int, float
        The ALM's iteration limit and stopping tolerance (500, 1e-6 as the reference).
    max_reweightings, reweight_tol : int, float
        The reweighting's limit and tolerance (10, 1e-3).

    Returns
    -------
    FlatfieldEstimate
        ``flatfield`` (H, W[, C]) mean 1, ``darkfield``, ``baseline`` (N[, C]),
        ``converged``, ``iterations``, ``method="basic"``.

    Raises
    ------
    InvalidInputError
        Fewer than 2 images, shapes that differ, NaN or inf, negative values, all zeros, bad
        parameters.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> y, x = np.mgrid[0:64, 0:64] / 63.0
    >>> flat = 1.2 - 0.4 * ((x - 0.5) ** 2 + (y - 0.5) ** 2)
    >>> scenes = 0.3 + 0.5 * (rng.random((40, 64, 64)) > 0.97)  # sparse bright objects
    >>> est = estimate_flatfield(scenes * flat)
    >>> bool(np.abs(est.flatfield - flat / flat.mean()).max() < 0.02)
    True
    """
    darkfield = bool(darkfield)
    sort_intensity = bool(sort_intensity)
    lam = None if smoothness is None else as_real(smoothness, "smoothness", minimum=0)
    lam_d = (
        None
        if smoothness_darkfield is None
        else as_real(smoothness_darkfield, "smoothness_darkfield", minimum=0)
    )
    size = as_int(working_size, "working_size", minimum=8, maximum=4096)
    iters = as_int(max_iter, "max_iter", minimum=1, maximum=100_000)
    tol_ = as_real(tol, "tol", minimum=0)
    rw = as_int(max_reweightings, "max_reweightings", minimum=1, maximum=1000)
    rw_tol = as_real(reweight_tol, "reweight_tol", minimum=0)
    stack = _stack(images)
    _, h, w, c = stack.shape
    work = (min(size, h), min(size, w))
    flats, darks, base = [], [], []
    total_its = 0
    ok = True
    for ch in range(c):
        small = _resize(stack[..., ch], work, order=1)
        shading, dark, coeff, its, conv = _basic_channel(
            small,
            work,
            darkfield=darkfield,
            smoothness=lam,
            smoothness_darkfield=lam_d,
            sort_intensity=sort_intensity,
            tol=tol_,
            max_iter=iters,
            max_reweightings=rw,
            reweight_tol=rw_tol,
            epsilon=0.1,
        )
        total_its += its
        ok = ok and conv
        flat_full = _resize(shading, (h, w), order=3)
        flat_full = flat_full / flat_full.mean()
        if float(flat_full.min()) <= 0:
            flat_full = np.maximum(flat_full, 1e-6 * float(np.abs(flat_full).max()))
        dark_full = _resize(dark, (h, w), order=3) if darkfield else np.zeros((h, w))
        flats.append(flat_full)
        darks.append(dark_full)
        flat_small = shading / shading.mean()
        if sort_intensity:  # the coefficients follow the sorted order: measure each image
            base.append(np.median((small - dark[None]) / flat_small[None], axis=(1, 2)))
        else:
            base.append(coeff * float(shading.mean()))
    flatfield = np.stack(flats, axis=-1)
    dark_arr = np.stack(darks, axis=-1)
    baseline = np.stack(base, axis=-1)
    grey = _input_is_grey(images)
    if grey:
        flatfield, dark_arr, baseline = flatfield[..., 0], dark_arr[..., 0], baseline[..., 0]
    return FlatfieldEstimate(flatfield, dark_arr, baseline, ok, total_its, "basic")


def _input_is_grey(images: object) -> bool:
    """Say whether the images are (H, W) each (the results then drop the channel axis)."""
    shape = getattr(images, "shape", None)
    if shape is not None:
        return len(shape) == 3
    first = next(iter(images))  # type: ignore[call-overload]
    return len(getattr(first, "shape", np.shape(first))) == 2


# ------------------------------------------------------------------ one frame


def _radial_basis(
    u: np.ndarray, v: np.ndarray, center: tuple[float, float], half_diag: float, degree: int
) -> np.ndarray:
    """Columns 1, r², r⁴, ... at the points ``(u, v)`` (full-frame pixels; r over half_diag)."""
    r2 = ((u - center[0]) ** 2 + (v - center[1]) ** 2).ravel() / half_diag**2
    return np.stack([np.ones_like(r2)] + [r2**k for k in range(1, degree + 1)], axis=1)


def _robust_fit(
    basis: np.ndarray, target: np.ndarray, max_iter: int
) -> tuple[np.ndarray, float, int, bool]:
    """Tukey-biweight IRLS of ``target ≈ basis @ coef``: (coef, robust scale, its, converged)."""
    wts = np.ones_like(target)
    coef = np.zeros(basis.shape[1])
    scale = 0.0
    for it in range(1, max_iter + 1):
        sw = np.sqrt(wts)
        new, *_ = np.linalg.lstsq(basis * sw[:, None], target * sw, rcond=None)
        res = target - basis @ new
        scale = 1.4826 * float(np.median(np.abs(res - np.median(res)))) + 1e-12
        u = res / (4.685 * scale)
        wts = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
        done = bool(np.allclose(new, coef, rtol=1e-6, atol=1e-9))
        coef = new
        if done:
            return coef, scale, it, True
    return coef, scale, max_iter, False


def estimate_vignetting(
    image: ArrayLike,
    *,
    degree: int = 2,
    center: tuple[float, float] | Literal["mask"] | None = None,
    fit_center: bool = False,
    smoothing: float = 0.05,
    max_iter: int = 50,
    mask: ArrayLike | Literal["auto"] | None = None,
) -> FlatfieldEstimate:
    r"""Estimate a radial flat field (vignetting) from one frame by a robust polynomial fit.

    The frame, as luminance (the channels' mean), is shrunk to at most 128 pixels a side and
    smoothed by a Gaussian of ``smoothing`` times its diagonal (the model is smoothed alike, so
    the blur biases nothing); then

    .. math::

        F(r) = 1 + a_1 r^2 + a_2 r^4 + \dots + a_k r^{2k}

    (Goldman 2010, eq. 3; ``k = degree``, ``r`` over the half-diagonal from ``center``) is
    fitted times a brightness by iteratively reweighted least squares with Tukey's biweight
    (``c = 4.685`` robust sigmas), so bright or dark objects weigh little. Only the shading
    that is radial and smooth is found; a scene that darkens towards the corners is taken
    for vignetting. For tiles or frames of varied content prefer :func:`estimate_flatfield`.

    With a ``mask`` (an endoscope's field of view: its aperture without the black surround),
    only the pixels inside count: the shrinking and the smoothing are normalised by the
    mask's own (normalised convolution, Knutsson & Westin 1993: ``G * (m I) / G * m``, the
    model alike, so the black surround darkens nothing), and the fit runs on the working
    pixels wholly inside the mask. The flat field is then defined over the whole frame: the
    polynomial inside the mask's largest radius, held at its value there beyond it (the
    black corners, where a polynomial extrapolated would go to zero or below).

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)
        One frame (uint8 / uint16 / floats), non-negative.
    degree : int
        Number of even powers (1 to 6).
    center : (c_u, c_v) or "mask", optional
        The optical center (column, row) in pixels; ``"mask"``: the center of the mask's
        bounding box (an endoscope's aperture, centred on its optical axis); default the
        image center.
    fit_center : bool
        Search the center too (a 9 x 9 grid over the middle 40 % of the frame, the smallest
        robust residual), for an off-axis lamp or a decentred lens.
    smoothing : float
        Gaussian sigma as a fraction of the diagonal (0 to 0.5).
    max_iter : int
        IRLS iterations at most.
    mask : array_like (H, W) of bool or "auto", optional
        The pixels to fit, True inside (boolean: give ``m > 0`` for an image of 0 and 255);
        ``"auto"``: an endoscope's field of view found in the frame by
        :func:`imageform.geometry.field_of_view_mask` (its largest bright region, holes
        filled, 8 pixels off its edge). None: every pixel (the results are those without
        a mask).

    Returns
    -------
    FlatfieldEstimate
        ``flatfield`` (H, W) mean 1 (over the mask; one field for every channel),
        ``darkfield`` zeros, ``baseline`` (1,) the frame's brightness, ``method="radial"``,
        ``mask`` the mask used (its :meth:`~FlatfieldEstimate.correct` leaves the pixels
        outside as they are).

    Raises
    ------
    InvalidInputError
        A frame that is not (H, W) or (H, W, C), negative or all zeros; parameters out of
        range; a mask that is not booleans of the frame's size, or too small to fit (fewer
        than 16 of the working grid's pixels wholly inside); a fit whose flat field is <= 0
        somewhere (inside the mask).

    References
    ----------
    D. B. Goldman, "Vignette and exposure calibration and compensation", IEEE TPAMI 32(12),
    2010. H. Knutsson and C.-F. Westin, "Normalized and differential convolution", CVPR 1993.

    Examples
    --------
    >>> from imageform.optics import cos4_falloff
    >>> rng = np.random.default_rng(1)
    >>> fall = cos4_falloff((96, 128), focal_length_px=150.0)
    >>> est = estimate_vignetting(0.6 * fall + rng.normal(0, 0.01, fall.shape))
    >>> bool(np.abs(est.flatfield - fall / fall.mean()).max() < 0.02)
    True

    An endoscope's frame: the scene inside a round aperture, black around it.

    >>> yy, xx = np.mgrid[:96, :128]
    >>> inside = (xx - 63.5) ** 2 + (yy - 47.5) ** 2 < 45**2
    >>> frame = np.where(inside, 0.6 * fall, 0.0)
    >>> est = estimate_vignetting(frame, mask=inside)
    >>> true = fall[inside] / fall[inside].mean()
    >>> bool(np.abs(est.flatfield[inside] - true).max() < 0.01)
    True
    """
    deg = as_int(degree, "degree", minimum=1, maximum=6)
    its = as_int(max_iter, "max_iter", minimum=1, maximum=10_000)
    sm = as_real(smoothing, "smoothing", minimum=0, maximum=0.5)
    fit_center = bool(fit_center)
    shape = getattr(image, "shape", None)
    if isinstance(shape, tuple):
        _image_dims(shape)
    if isinstance(center, str) and center != "mask":
        raise InvalidInputError(
            f"expected center as (c_u, c_v), 'mask' or None, got {describe(center)}"
        )
    if isinstance(mask, str) and mask != "auto":
        raise InvalidInputError(
            f"expected mask as booleans (H, W), 'auto' or None, got {describe(mask)}"
        )
    if isinstance(center, str) and mask is None:
        raise InvalidInputError("center='mask' takes the mask's center: give a mask too")
    if isinstance(shape, tuple) and mask is not None and not isinstance(mask, str):
        _as_mask_shape(mask, shape)
    img = np.asarray(to_numpy(as_image(image, "image", channels=None, range_check=False)))
    _image_dims(img.shape)
    lum = img.astype(np.float64)
    if lum.ndim == 3:
        lum = lum.mean(axis=2)
    lo = float(lum.min())
    if lo < 0:
        raise InvalidInputError(f"expected image >= 0 (intensities), got min {lo:g}")
    if not np.any(lum > 0):
        raise InvalidInputError("expected an image with light, got all zeros")
    h, w = lum.shape
    keep: np.ndarray | None = None
    if isinstance(mask, str):
        from imageform.geometry import field_of_view_mask

        keep = field_of_view_mask(img)
    elif mask is not None:
        keep = _as_mask(mask, lum.shape)
    if center is None:
        cu, cv = (w - 1) / 2, (h - 1) / 2
    elif isinstance(center, str):
        assert keep is not None
        rows, cols = np.flatnonzero(keep.any(axis=1)), np.flatnonzero(keep.any(axis=0))
        cu, cv = (cols[0] + cols[-1]) / 2, (rows[0] + rows[-1]) / 2
    else:
        cu, cv = as_reals(center, "center", 2)
    s = min(1.0, WORKING_SIZE / max(h, w))
    work = (max(2, round(h * s)), max(2, round(w * s)))
    sigma = sm * math.hypot(*work)

    def smooth(a: np.ndarray) -> np.ndarray:
        from scipy import ndimage

        return np.asarray(ndimage.gaussian_filter(a, sigma, mode="reflect")) if sigma else a

    if keep is None:
        small = smooth(_resize(lum, work, order=1))
        cover: np.ndarray | None = None
        norm = np.ones(work)
        use = np.ones(work[0] * work[1], dtype=bool)
    else:
        # normalised convolution: shrink and smooth m I and m, divide (the model alike)
        cover = np.clip(_resize(keep.astype(np.float64), work, order=1), 0.0, 1.0)
        norm = smooth(cover)
        use = ((cover > 0.999) & (norm > 1e-6)).ravel()
        if int(use.sum()) < 16:
            raise InvalidInputError(
                f"expected a mask that covers more of the frame: {int(keep.sum())} pixels "
                f"leave {int(use.sum())} of the {work[1]} x {work[0]} working grid's pixels "
                "wholly inside (16 needed)"
            )
        small = smooth(_resize(np.where(keep, lum, 0.0), work, order=1)) / np.maximum(norm, 1e-12)
    half_diag = math.hypot(w / 2, h / 2)
    # the working grid's pixel centres in full-frame pixels (u + 0.5) / s - 0.5
    vw, uw = np.mgrid[0 : work[0], 0 : work[1]].astype(np.float64)
    uw = (uw + 0.5) * (w / work[1]) - 0.5
    vw = (vw + 0.5) * (h / work[0]) - 0.5

    def fit(c: tuple[float, float]) -> tuple[np.ndarray, float, int, bool]:
        # the model smoothed as the frame was (smoothing is linear): no bias from the blur
        basis = _radial_basis(uw, vw, c, half_diag, deg)
        if cover is None:
            cols = [smooth(b.reshape(work)).ravel() for b in basis.T]
            return _robust_fit(np.stack(cols, axis=1), small.ravel(), its)
        cols = [
            (smooth(b.reshape(work) * cover) / np.maximum(norm, 1e-12)).ravel()[use]
            for b in basis.T
        ]
        return _robust_fit(np.stack(cols, axis=1), small.ravel()[use], its)

    best = (cu, cv)
    coef, scale, n_it, ok = fit(best)
    if fit_center:
        for fu in np.linspace(0.3, 0.7, 9):
            for fv in np.linspace(0.3, 0.7, 9):
                cand = (float(fu * (w - 1)), float(fv * (h - 1)))
                c2, s2, n2, ok2 = fit(cand)
                n_it += n2
                if s2 < scale:
                    best, coef, scale, ok = cand, c2, s2, ok2
    vf, uf = np.mgrid[0:h, 0:w].astype(np.float64)
    if keep is None:
        field = (_radial_basis(uf, vf, best, half_diag, deg) @ coef).reshape(h, w)
        if float(coef[0]) <= 0 or float(field.min()) <= 0:
            raise InvalidInputError(
                "the radial fit gave a flat field <= 0 somewhere (a frame dark at its center "
                "or corners: an endoscope's black surround?); give a lower degree, a mask (an "
                "endoscope's field of view: mask='auto', --mask auto) or a measured flat field"
            )
        brightness = float(field.mean())
    else:
        # the polynomial up to the mask's largest radius, held there beyond it
        r = np.hypot(uf - best[0], vf - best[1])
        r_max = float(r[keep].max())
        scale_r = np.minimum(r, r_max) / r
        scale_r[r == 0] = 1.0
        uc = best[0] + (uf - best[0]) * scale_r
        vc = best[1] + (vf - best[1]) * scale_r
        field = (_radial_basis(uc, vc, best, half_diag, deg) @ coef).reshape(h, w)
        if float(coef[0]) <= 0 or float(field[keep].min()) <= 0 or float(field.min()) <= 0:
            raise InvalidInputError(
                "the radial fit gave a flat field <= 0 inside the mask (a frame dark at its "
                "center?); give a lower degree or a measured flat field"
            )
        brightness = float(field[keep].mean())
    return FlatfieldEstimate(
        field / brightness,
        np.zeros((h, w)),
        np.array([brightness]),
        ok,
        n_it,
        "radial",
        keep,
    )


def _as_mask_shape(mask: object, shape: tuple[int, ...]) -> None:
    """Refuse a mask whose shape (read before its values) is not the image's (H, W)."""
    mshape = getattr(mask, "shape", None)
    if isinstance(mshape, tuple) and tuple(mshape) != tuple(shape[:2]):
        raise InvalidInputError(
            f"expected mask of the image's size {format_shape(tuple(shape[:2]))}, got "
            f"{format_shape(tuple(mshape))}"
        )
