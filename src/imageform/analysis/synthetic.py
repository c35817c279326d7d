"""Labelled synthetic images for testing and demonstrating the analysis tools.

Each generator is seeded (keyword-only ``rng``, SPEC 7: an int seed, a NumPy Generator or
None) and returns the ground truth with the image: an endoscopy-like frame with its tissue
mask, an H&E mixture with its stain vectors (Beer-Lambert), a colour chart image, and a
two-material scene under a shading gradient.
"""

from __future__ import annotations

import functools
import numbers
from typing import Any, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._colormath import hsv_to_rgb, srgb_decode, srgb_encode
from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike
from imageform._validate import (
    as_float,
    as_int,
    as_real,
    as_reals,
    as_size,
    check_memory,
    check_nonzero_rows,
    format_shape,
    real_array,
)
from imageform.errors import InvalidInputError

__all__ = [
    "COLORCHECKER_SRGB8",
    "MACENKO_REFERENCE_EOSIN",
    "MACENKO_REFERENCE_HEMATOXYLIN",
    "MACENKO_REFERENCE_MAX_CONCENTRATIONS",
    "RUIFROK_DAB",
    "RUIFROK_EOSIN",
    "RUIFROK_HEMATOXYLIN",
    "LabeledImage",
    "StainMixture",
    "synthetic_chart_image",
    "synthetic_endoscopy_image",
    "synthetic_he_tile",
    "synthetic_shading_scene",
    "synthetic_stain_image",
]

# Optical-density stain vectors (R, G, B), before normalisation to unit length.
# Source: A. C. Ruifrok & D. A. Johnston, "Quantification of histochemical staining by
# color deconvolution", Anal. Quant. Cytol. Histol. 23(4), 2001, p. 294 (H&E, H DAB).
RUIFROK_HEMATOXYLIN = (0.65, 0.70, 0.29)
RUIFROK_EOSIN = (0.07, 0.99, 0.11)
RUIFROK_DAB = (0.27, 0.57, 0.78)

# The reference H&E stain vectors (unit ln-OD vectors) and 99th-percentile concentrations
# of Macenko's reference code, measured on a real H&E slide.
# Source: github.com/mitkovetta/staining-normalization, normalizeStaining.m (HERef,
# maxCRef); the same values in HEnorm_python and torchstain.
MACENKO_REFERENCE_HEMATOXYLIN = (0.5626, 0.7201, 0.4062)
MACENKO_REFERENCE_EOSIN = (0.2159, 0.8012, 0.5581)
MACENKO_REFERENCE_MAX_CONCENTRATIONS = (1.9705, 1.0308)

# The 24 patches of the ColorChecker as 8-bit sRGB (row by row, dark skin .. black).
# Source: X-Rite, "ColorChecker Classic" sRGB values (post-November 2014 formulation,
# D50 -> D65 Bradford), as published by X-Rite. Approximate reflectances rendered for a
# synthetic chart: a reference for tests, not a measurement standard.
COLORCHECKER_SRGB8 = (
    (115, 82, 68),
    (194, 150, 130),
    (98, 122, 157),
    (87, 108, 67),
    (133, 128, 177),
    (103, 189, 170),
    (214, 126, 44),
    (80, 91, 166),
    (193, 90, 99),
    (94, 60, 108),
    (157, 188, 64),
    (224, 163, 46),
    (56, 61, 150),
    (70, 148, 73),
    (175, 54, 60),
    (231, 199, 31),
    (187, 86, 149),
    (8, 133, 161),
    (243, 243, 242),
    (200, 200, 200),
    (160, 160, 160),
    (122, 122, 121),
    (85, 85, 85),
    (52, 52, 52),
)


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], scale: float) -> np.ndarray:
    """Smooth noise in [-1, 1]: Gaussian-filtered white noise, normalised."""
    from scipy import ndimage

    n = ndimage.gaussian_filter(rng.standard_normal(shape), scale)
    return n / np.max(np.abs(n))


class LabeledImage(NamedTuple):
    """A synthetic image and its ground-truth mask."""

    #: Encoded sRGB in [0, 1], shape (H, W, 3), float64.
    image: np.ndarray
    #: The true segmentation, bool, shape (H, W).
    mask: np.ndarray


class StainMixture(NamedTuple):
    """A synthetic stained slide and the stains that made it (:func:`synthetic_stain_image`)."""

    #: Transmitted light in (0, 1], shape (H, W, 3), float64.
    image: np.ndarray
    #: The unit-length optical-density vectors used (rows), shape (2, 3).
    stain_matrix: np.ndarray
    #: Stain concentrations per pixel, shape (H, W, 2).
    concentrations: np.ndarray


def _seed_first(fn: Any) -> Any:
    """Make the old calls (``synthetic_...(0, shape)``, ``seed=0``) warn and still work."""
    name = f"imageform.analysis.{fn.__name__}"

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        if "seed" in kwargs:
            if "rng" in kwargs:
                raise TypeError(f"{name}() got both seed= (deprecated) and rng=")
            _deprecate.warn(f"{name}(seed=...)", "use rng= instead")
            kwargs["rng"] = kwargs.pop("seed")
        if args and isinstance(args[0], numbers.Integral) and not isinstance(args[0], bool):
            if "rng" in kwargs:
                raise TypeError(f"{name}() got the seed twice (first argument and rng=)")
            _deprecate.warn(
                f"passing the seed first to {name}()",
                "pass it as rng=<seed> (the first parameter is now shape)",
            )
            kwargs["rng"] = args[0]
            args = args[1:]
        return fn(*args, **kwargs)

    return wrapper


@_seed_first
def synthetic_endoscopy_image(
    shape: tuple[int, int] = (256, 256), *, rng: RNGLike = 0
) -> LabeledImage:
    """Render an endoscopy-like frame and its tissue mask.

    Reddish/pink mucosa (hue 350°..12°, S 0.35..0.7) with smooth texture, a dark lumen
    (V < 0.15), specular highlights (S < 0.1, V ≈ 1), a bluish instrument (hue ≈ 210°)
    and a whitish mucus patch (S < 0.12), all under vignetting (V × 0.55 at the corners)
    and Gaussian noise (σ = 0.03). The mask is True on mucosa not covered by the rest.

    Returns
    -------
    LabeledImage
        ``image`` : ndarray (H, W, 3) float64, encoded sRGB in [0, 1]; ``mask`` : ndarray of
        bool (H, W), the true tissue mask.

    Examples
    --------
    >>> img, m = synthetic_endoscopy_image(rng=0)
    >>> img.shape, round(float(m.mean()), 3)
    ((256, 256, 3), 0.887)
    """
    hgt, wid = _shape(shape)
    if hgt < 32 or wid < 32:
        raise InvalidInputError(f"expected shape of at least (32, 32), got {shape}")
    gen = as_rng(rng)
    y, x = np.mgrid[0:hgt, 0:wid].astype(np.float64)
    yn, xn = (y - hgt / 2) / (hgt / 2), (x - wid / 2) / (wid / 2)
    # mucosa: hue wanders 350°..12° (through red), saturation 0.35..0.7
    hue = np.mod(1.0 + 11.0 * _smooth_noise(gen, (hgt, wid), hgt / 12), 360.0)
    sat = 0.525 + 0.175 * _smooth_noise(gen, (hgt, wid), hgt / 16)
    val = 0.85 + 0.1 * _smooth_noise(gen, (hgt, wid), hgt / 20)
    truth = np.ones((hgt, wid), dtype=bool)
    # dark lumen: an ellipse off centre
    cy, cx = gen.uniform(-0.3, 0.3, 2)
    lumen = ((yn - cy) / 0.28) ** 2 + ((xn - cx) / 0.2) ** 2 <= 1.0
    val = np.where(lumen, 0.08, val)
    truth &= ~lumen
    # bluish instrument: a bar from the lower-left corner
    inst = (np.abs((yn - 0.9) + 0.8 * (xn + 0.9)) < 0.12) & (xn < -0.2)
    hue, sat, val = (
        np.where(inst, 210.0, hue),
        np.where(inst, 0.35, sat),
        np.where(inst, 0.7, val),
    )
    truth &= ~inst
    # whitish mucus patch
    my, mx = gen.uniform(0.35, 0.6, 2) * gen.choice([-1, 1], 2)
    mucus = ((yn - my) / 0.12) ** 2 + ((xn - mx) / 0.18) ** 2 <= 1.0
    mucus &= ~inst & ~lumen
    sat, val = np.where(mucus, 0.06, sat), np.where(mucus, 0.92, val)
    truth &= ~mucus
    # specular highlights: small discs
    for _ in range(12):
        py, px = gen.uniform(0, hgt), gen.uniform(0, wid)
        r = gen.uniform(2.0, 5.0)
        spot = (y - py) ** 2 + (x - px) ** 2 <= r * r
        sat, val = np.where(spot, 0.03, sat), np.where(spot, 1.0, val)
        truth &= ~spot
    # vignetting on V (cos^4-like falloff to 0.55 at the corners), except the highlights
    vig = 1.0 - 0.45 * (xn**2 + yn**2) / 2.0
    val = np.where(val >= 1.0, val, val * vig)
    rgb = hsv_to_rgb(np, np.stack([hue, sat, val], axis=-1))
    rgb = rgb + gen.normal(0.0, 0.03, rgb.shape)
    return LabeledImage(np.clip(rgb, 0.0, 1.0), truth)


def synthetic_he_tile(
    shape: tuple[int, int] = (256, 256),
    *,
    stains: tuple[tuple[float, float, float], ...] = (
        MACENKO_REFERENCE_HEMATOXYLIN,
        MACENKO_REFERENCE_EOSIN,
    ),
    max_concentration: tuple[float, float] = MACENKO_REFERENCE_MAX_CONCENTRATIONS,
    background: float = 0.3,
    nuclei: float = 0.2,
    i0: float = 240.0 / 255.0,
    blur: float = 0.7,
    noise: float = 1.5 / 255.0,
    rng: RNGLike = 0,
) -> StainMixture:
    """Render a bright-field H&E tile by Beer-Lambert in ln units, :math:`I = I_0 e^{-C S}`.

    It is closer to a scanned slide than :func:`synthetic_stain_image`.

    Glass (``background``, a fraction of the tile, :math:`C = 0`) around smooth tissue
    regions; in the tissue eosin varies smoothly (stroma, cytoplasm) over a faint
    hematoxylin counterstain in about half of it, and round nuclei (``nuclei``, a
    fraction of the tissue) carry hematoxylin with little eosin. The transmitted light
    is blurred (optics, Gaussian σ = ``blur`` px), noisy (Gaussian, ``noise``) and
    quantised to 8 bits.

    Returns
    -------
    StainMixture
        ``image`` : ndarray (H, W, 3) float64, multiples of 1/255 (``np.round(image * 255)``
        is the 8-bit scan); ``stain_matrix`` : (2, 3) unit ln-OD vectors;
        ``concentrations`` : (H, W, 2) in ln-OD units, zero on glass.

    Notes
    -----
    Source: Beer-Lambert with the reference stain vectors and concentrations of Macenko's
    reference code (:data:`MACENKO_REFERENCE_HEMATOXYLIN`, ``..._EOSIN``).

    Examples
    --------
    >>> tile = synthetic_he_tile((64, 64), rng=0)
    >>> bool((tile.concentrations.sum(axis=-1) == 0).mean() > 0.2), tile.image.dtype.name
    (True, 'float64')
    """
    from scipy import ndimage

    hgt, wid = _shape(shape)
    s = real_array(stains, "stains", (2, 3))
    norms = np.linalg.norm(s, axis=1, keepdims=True)
    if not np.all(norms > 0):
        raise InvalidInputError("expected stains as two non-zero (3,) stain vectors")
    mh, me = as_reals(max_concentration, "max_concentration", 2)
    if mh < 0 or me < 0:
        raise InvalidInputError(f"expected max_concentration >= 0, got ({mh:g}, {me:g})")
    background = as_real(background, "background", minimum=0.0, maximum=1.0)
    nuclei = as_real(nuclei, "nuclei", minimum=0.0, maximum=1.0)
    i0 = as_real(i0, "i0", positive=True)
    blur = as_real(blur, "blur", nonnegative=True, maximum=float(max(hgt, wid)))
    noise = as_real(noise, "noise", nonnegative=True)
    gen = as_rng(rng)
    s = s / norms
    field = _smooth_noise(gen, (hgt, wid), max(hgt, wid) / 10.0)
    tissue = field > np.quantile(field, float(background))
    c = np.zeros((hgt, wid, 2))
    eos = 0.5 + 0.5 * _smooth_noise(gen, (hgt, wid), 4.0)  # 0..1
    c[..., 1] = me * (0.15 + 0.7 * eos) * tissue
    c[..., 0] = mh * 0.1 * np.maximum(_smooth_noise(gen, (hgt, wid), 4.0), 0.0) * tissue
    # nuclei: discs of radius 3-6 px until they cover `nuclei` of the tissue
    yy, xx = np.mgrid[0:hgt, 0:wid]
    nuc = np.zeros((hgt, wid), bool)
    target = float(nuclei) * tissue.sum()
    for _ in range(10 * hgt * wid):
        if nuc.sum() >= target:
            break
        y, x = int(gen.integers(hgt)), int(gen.integers(wid))
        if not tissue[y, x]:
            continue
        r = gen.uniform(3.0, 6.0)
        disc = (yy - y) ** 2 + (xx - x) ** 2 <= r * r
        nuc |= disc & tissue
        c[disc & tissue, 0] = mh * gen.uniform(0.45, 0.95)
        c[disc & tissue, 1] *= 0.3
    img = float(i0) * np.exp(-(c @ s))
    if blur > 0:
        img = ndimage.gaussian_filter(img, (float(blur), float(blur), 0.0))
    img = img + gen.normal(0.0, float(noise), img.shape)
    img = np.clip(np.round(img * 255.0), 0.0, 255.0) / 255.0
    return StainMixture(img, s, c)


def _shape(shape: object) -> tuple[int, int]:
    """``(height, width)``: two integers in [1, 16384], within the memory limit."""
    hgt, wid = as_size(shape, "shape", minimum=1, maximum=16384)
    check_memory(hgt * wid * 3 * 8 * 8.0, "shape", f"a {hgt}x{wid} synthetic image")
    return hgt, wid


@_seed_first
def synthetic_stain_image(
    shape: tuple[int, int] = (128, 128),
    stains: tuple[tuple[float, float, float], ...] = (RUIFROK_HEMATOXYLIN, RUIFROK_EOSIN),
    max_concentration: tuple[float, float] = (1.2, 0.8),
    noise: float = 0.002,
    *,
    rng: RNGLike = 0,
) -> StainMixture:
    """Render a two-stain mixture by Beer-Lambert: :math:`I = 10^{-C S}` (I₀ = 1).

    A third of the pixels holds the first stain only, a third the second only, a
    quarter both, the rest is faintly stained background (OD < 0.1).

    Returns
    -------
    StainMixture
        ``image`` : ndarray (H, W, 3) float64 in (0, 1]; ``stain_matrix`` : ndarray (2, 3),
        the unit-length optical-density vectors used (rows); ``concentrations`` : ndarray
        (H, W, 2).

    Notes
    -----
    Source: Ruifrok & Johnston 2001 (stain vectors, Beer-Lambert model).

    Examples
    --------
    >>> img, S, C = synthetic_stain_image(rng=0)
    >>> S.round(3).tolist()[0]
    [0.651, 0.701, 0.29]
    """
    gen = as_rng(rng)
    s = real_array(stains, "stains", (None, 3))
    if s.shape[0] not in (2, 3):
        raise InvalidInputError(
            f"expected stains of shape (2, 3) or (3, 3), got {format_shape(s.shape)}"
        )
    check_nonzero_rows(s, "stains")  # a zero-length stain vector has no direction (NaN image)
    mc = np.asarray(as_float(max_concentration, "max_concentration"), dtype=np.float64)
    if mc.shape != (s.shape[0],) or np.any(mc < 0):
        raise InvalidInputError(
            f"expected max_concentration as {s.shape[0]} values >= 0, got shape {mc.shape}"
        )
    s = s / np.linalg.norm(s, axis=1, keepdims=True)
    hgt, wid = _shape(shape)
    shape = (hgt, wid)
    noise = as_real(noise, "noise", nonnegative=True)
    kind = gen.choice(4, size=(hgt, wid), p=[1 / 3, 1 / 3, 1 / 4, 1 - 1 / 3 - 1 / 3 - 1 / 4])
    c = gen.uniform(0.15, 1.0, (hgt, wid, 2)) * np.asarray(max_concentration)
    c[kind == 0, 1] = 0.0
    c[kind == 1, 0] = 0.0
    c[kind == 3] = gen.uniform(0.0, 0.04, (int((kind == 3).sum()), 2))
    od = c @ s
    img = 10.0 ** (-od) + gen.normal(0.0, noise, od.shape)
    return StainMixture(np.clip(img, 1 / 255, 1.0), s, c)


def synthetic_chart_image(
    srgb: ArrayLike | None = None,
    rows: int = 4,
    cols: int = 6,
    patch: int = 24,
    gap: int = 6,
    background: float = 0.05,
) -> np.ndarray:
    """Render a chart image that fills the frame: ``rows × cols`` flat patches on a dark surround.

    Parameters
    ----------
    srgb : array_like, shape (rows*cols, 3), optional
        Encoded sRGB patch values in [0, 1] (row by row); default the ColorChecker
        (:data:`COLORCHECKER_SRGB8` / 255).
    rows, cols : int
        The grid of patches.
    patch : int
        Side of each square patch in pixels.
    gap : int
        Width in pixels of the surround between patches and around the grid.
    background : float
        Encoded grey level of the surround, in [0, 1].

    Returns
    -------
    ndarray, shape (rows*(patch+gap), cols*(patch+gap), 3), float64

    Examples
    --------
    >>> synthetic_chart_image().shape
    (120, 180, 3)
    """
    rows = as_int(rows, "rows", minimum=1, maximum=1000)
    cols = as_int(cols, "cols", minimum=1, maximum=1000)
    patch = as_int(patch, "patch", minimum=1, maximum=10_000)
    gap = as_int(gap, "gap", minimum=0, maximum=10_000)
    background = as_real(background, "background", minimum=0.0, maximum=1.0)
    check_memory(rows * (patch + gap) * cols * (patch + gap) * 24.0, "patch", "the chart image")
    vals = (
        np.asarray(COLORCHECKER_SRGB8, float) / 255
        if srgb is None
        else np.asarray(as_float(srgb, "srgb"), dtype=np.float64)
    )
    if vals.shape != (rows * cols, 3):
        raise InvalidInputError(f"expected srgb of shape ({rows * cols}, 3), got {vals.shape}")
    cell = patch + gap
    img = np.full((rows * cell, cols * cell, 3), background)
    for i in range(rows):
        for j in range(cols):
            y0, x0 = i * cell + gap // 2, j * cell + gap // 2
            img[y0 : y0 + patch, x0 : x0 + patch] = vals[i * cols + j]
    return img


@_seed_first
def synthetic_shading_scene(
    shape: tuple[int, int] = (128, 192),
    shading: tuple[float, float] = (1.0, 0.2),
    *,
    rng: RNGLike = 0,
) -> LabeledImage:
    """Red blobs on a yellow-green background under a left-to-right illumination ramp.

    The illumination multiplies *linear* light from ``shading[0]`` at the left edge to
    ``shading[1]`` at the right (a shadow), then the image is sRGB-encoded.

    Returns
    -------
    LabeledImage
        ``image`` : ndarray (H, W, 3) float64, encoded sRGB; ``mask`` : ndarray of bool
        (H, W), the red objects.

    Examples
    --------
    >>> img, m = synthetic_shading_scene(rng=0)
    >>> img.shape, bool(m.any())
    ((128, 192, 3), True)
    """
    gen = as_rng(rng)
    hgt, wid = _shape(shape)
    shape = (hgt, wid)
    y, x = np.mgrid[0:hgt, 0:wid].astype(np.float64)
    truth = np.zeros((hgt, wid), dtype=bool)
    for k in range(8):
        cy = gen.uniform(0.2, 0.8) * hgt
        cx = (k + 0.5) / 8 * wid
        r = gen.uniform(0.07, 0.12) * hgt
        truth |= (y - cy) ** 2 + (x - cx) ** 2 <= r * r
    red = np.array([0.78, 0.22, 0.2])
    bg = np.array([0.62, 0.66, 0.3])
    enc = np.where(truth[..., None], red, bg) + 0.02 * _smooth_noise(gen, shape, 3.0)[..., None]
    lin = srgb_decode(np, np.clip(enc, 0, 1))
    if isinstance(shading, str | bytes) or not hasattr(shading, "__len__") or len(shading) != 2:
        raise InvalidInputError(f"expected shading as 2 numbers, got {shading!r:.60}")
    lo, hi = (as_real(v, "shading", nonnegative=True) for v in shading)
    ramp = np.linspace(lo, hi, wid)[None, :, None]
    out = srgb_encode(np, lin * ramp) + gen.normal(0, 0.004, lin.shape)
    return LabeledImage(np.clip(out, 0.0, 1.0), truth)
