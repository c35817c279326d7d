"""Bayer colour filter arrays: pattern names, sampling masks and mosaicing.

A single-sensor camera puts one colour filter over each photosite, so each pixel measures
one of R, G, B. The Bayer array (B. E. Bayer, *Color imaging array*, US patent 3,971,065,
1976) tiles the sensor with a 2×2 cell holding one red, one blue and **two green** filters:
half the photosites are green. Bayer chose this because the eye's luminance (detail) signal
is mostly green: the luminance weights of Rec. 709 / sRGB are
:math:`Y = 0.2126 R + 0.7152 G + 0.0722 B`, so sampling green on a quincunx (checkerboard)
lattice, twice as dense as red and blue, gives the luminance the finest sampling, while the
eye's coarser colour (chrominance) resolution is served by red and blue on rectangular
lattices of half the density in each direction.

The four names say the colours of the 2×2 cell read row by row from the top-left pixel
(pixel centre ``(0, 0)``, docs/conventions.md):

======  ==============  ============
name    row 0           row 1
======  ==============  ============
RGGB    R G R G ...     G B G B ...
BGGR    B G B G ...     G R G R ...
GRBG    G R G R ...     B G B G ...
GBRG    G B G B ...     R G R G ...
======  ==============  ============

OpenCV names the same layouts by the colours of the second row's 2nd and 3rd pixel: an
RGGB mosaic is ``cv2.COLOR_BayerBG2RGB`` (alias ``COLOR_BayerRGGB2RGB``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._backend import device_of, namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image, as_shape, describe, format_shape, real_array
from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = ["CFA_PATTERNS", "cfa_masks", "cfa_pattern", "equalize_cfa", "mosaic", "superpixel"]

#: The Bayer patterns imageform knows, as the colours of the 2×2 cell read row by row.
CFA_PATTERNS: tuple[str, ...] = ("RGGB", "BGGR", "GRBG", "GBRG")

_CHANNEL = {"R": 0, "G": 1, "B": 2}


def cfa_pattern(pattern: object) -> str:
    """Validate a Bayer pattern name and return it in upper case.

    Parameters
    ----------
    pattern : str
        One of ``"RGGB"``, ``"BGGR"``, ``"GRBG"``, ``"GBRG"`` (case-insensitive).

    Returns
    -------
    str
        The canonical (upper-case) name.

    Raises
    ------
    UnknownOptionError
        If ``pattern`` is not one of the four names; the message lists them.

    Examples
    --------
    >>> cfa_pattern("rggb")
    'RGGB'
    """
    if not isinstance(pattern, str):
        raise UnknownOptionError(f"expected a CFA pattern name (str), got {describe(pattern)}")
    key = pattern.strip().upper()
    if key not in CFA_PATTERNS:
        names = ", ".join(repr(p) for p in CFA_PATTERNS)
        raise UnknownOptionError(f"unknown CFA pattern {describe(pattern, 30)}; valid: {names}")
    return key


def _red_offset(pattern: str) -> tuple[int, int]:
    """(row, column) of the red pixel in the 2×2 cell of a canonical pattern name."""
    i = pattern.index("R")
    return i // 2, i % 2


def _cell_channels(pattern: str) -> np.ndarray:
    """Return the 2×2 cell as channel indices (0 R, 1 G, 2 B)."""
    return np.array([_CHANNEL[c] for c in pattern], dtype=np.intp).reshape(2, 2)


def cfa_masks(shape: tuple[int, int], pattern: str = "RGGB") -> np.ndarray:
    r"""Boolean sampling masks of a Bayer array, one per channel.

    ``masks[y, x, c]`` is true where the photosite at row ``y``, column ``x`` has a filter
    of colour ``c`` (0 red, 1 green, 2 blue). Exactly one channel is true per pixel; the
    green mask covers half the pixels (see the module docstring for why).

    .. math::

        m_c(y, x) = [\,\mathrm{cell}(y \bmod 2,\, x \bmod 2) = c\,]

    Parameters
    ----------
    shape : tuple of int
        ``(H, W)``, each at least 1 (odd sizes cut the 2×2 cell at the right/bottom edge).
    pattern : str
        Bayer pattern name (:data:`CFA_PATTERNS`).

    Returns
    -------
    ndarray of bool, shape (H, W, 3)

    Notes
    -----
    Source: Bayer, US patent 3,971,065 (1976), fig. 6.

    Examples
    --------
    >>> m = cfa_masks((4, 6), "RGGB")
    >>> float(m[..., 1].mean()), bool(m[0, 0, 0]), bool(m[1, 1, 2])
    (0.5, True, True)
    """
    pattern = cfa_pattern(pattern)
    # the tiled int cell and the boolean masks (3 per pixel): 16 bytes a pixel
    h, w = as_shape(shape, "shape (H, W)", 2, itemsize=16)
    cell = _cell_channels(pattern)
    idx = np.tile(cell, ((h + 1) // 2, (w + 1) // 2))[:h, :w]
    return idx[..., None] == np.arange(3)


def mosaic(rgb: ArrayLike, pattern: str = "RGGB") -> Array:
    r"""Sample an RGB image through a Bayer colour filter array (the forward model).

    Each output pixel keeps the one channel its filter passes:

    .. math::

        \mathrm{raw}(y, x) = \sum_{c \in \{R,G,B\}} m_c(y, x)\, I_c(y, x)

    with :math:`m_c` from :func:`cfa_masks`. Half the pixels keep green, a quarter red,
    a quarter blue: green is sampled twice as densely because the luminance that carries
    image detail is mostly green (:math:`Y = 0.2126 R + 0.7152 G + 0.0722 B`, Rec. 709).

    Parameters
    ----------
    rgb : array, shape (..., H, W, 3)
        Image, channels last. uint8/uint16 are read as full-range values (/255, /65535,
        float32); floats keep their dtype.
    pattern : str
        ``"RGGB"`` (default), ``"BGGR"``, ``"GRBG"`` or ``"GBRG"``. Odd ``H`` or ``W`` are
        allowed: the 2×2 cell is cut at the bottom/right edge.

    Returns
    -------
    array, shape (..., H, W)
        The mosaic, same namespace and float dtype as the (converted) input.

    Raises
    ------
    InvalidInputError
        If ``rgb`` does not have 3 channels last or holds NaN/inf.
    UnknownOptionError
        If ``pattern`` is not a known Bayer pattern.

    Notes
    -----
    Source: Bayer, US patent 3,971,065 (1976).

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((2, 2, 3)); img[..., 0], img[..., 1], img[..., 2] = 0.9, 0.5, 0.1
    >>> mosaic(img, "RGGB").tolist()
    [[0.9, 0.5], [0.5, 0.1]]
    """
    pattern = cfa_pattern(pattern)
    shape: tuple[Any, ...] = tuple(getattr(rgb, "shape", None) or ())
    last = shape[-1] if shape and getattr(rgb, "ndim", 0) >= 1 else None
    if isinstance(last, int | np.integer) and last != 3:
        # refused before as_image reads the values (a misshaped 9 GB array took seconds)
        hint = "; an alpha channel? split it off (image[..., :3])" if last == 4 else ""
        raise InvalidInputError(
            f"expected rgb with 3 channels on axis -1, got shape {format_shape(shape)}{hint}"
        )
    xp = namespace(rgb)
    img = as_image(rgb, "rgb", channels=3, xp=xp)
    if img.ndim < 3:
        raise InvalidInputError(
            f"expected rgb of shape (..., H, W, 3), got {format_shape(tuple(img.shape))}"
        )
    h, w = int(img.shape[-3]), int(img.shape[-2])
    if h < 1 or w < 1:
        raise InvalidInputError(
            f"expected rgb with H, W >= 1, got {format_shape(tuple(img.shape))}"
        )
    masks = _as_xp(cfa_masks((h, w), pattern), xp, img)
    return xp.sum(img * masks, axis=-1)


def _as_xp(mask: np.ndarray, xp: Any, like: Any) -> Any:
    """Convert a NumPy bool mask to a float array of ``like``'s namespace, dtype and device."""
    dev = device_of(like)
    m = mask.astype(np.float64)
    arr = xp.asarray(m) if dev is None else xp.asarray(m, device=dev)
    return xp.astype(arr, like.dtype)


def _raw_plane(raw: object, name: str = "raw") -> np.ndarray:
    """Return a 2-D mosaic of at least one whole 2x2 cell as float64."""
    arr = real_array(raw, name, ndim=2)
    if arr.shape[0] < 2 or arr.shape[1] < 2:
        raise InvalidInputError(
            f"expected {name} with at least 2 x 2 photosites, got shape {format_shape(arr.shape)}"
        )
    return arr


def superpixel(raw: ArrayLike, pattern: str = "RGGB") -> np.ndarray:
    r"""Return each 2x2 cell of a Bayer mosaic as one camera-RGB pixel (half size).

    .. math:: \mathbf{c}[i, j] = \big(R,\ \tfrac{1}{2}(G_1 + G_2),\ B\big)
        \text{ of the cell } (2i..2i{+}1,\ 2j..2j{+}1)

    The "superpixel" development of dcraw (``-h``, half size): every value is a measured one,
    so colours are not mixed across neighbouring photosites (used to measure a chart's
    patches on a raw file). An odd last row or column is dropped.

    Parameters
    ----------
    raw : array_like, shape (H, W)
        The mosaic (linear, black subtracted).
    pattern : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The colours of the 2x2 cell read row by row (:data:`CFA_PATTERNS`).

    Returns
    -------
    ndarray, shape (H // 2, W // 2, 3), float64

    Examples
    --------
    >>> superpixel(np.array([[0.4, 0.2], [0.3, 0.1]]), "RGGB").tolist()
    [[[0.4, 0.25, 0.1]]]
    """
    pat = cfa_pattern(pattern)
    arr = _raw_plane(raw)
    h, w = (arr.shape[0] // 2) * 2, (arr.shape[1] // 2) * 2
    m = arr[:h, :w]
    out = np.zeros((h // 2, w // 2, 3))
    count = np.zeros(3)
    for k, ch in enumerate(pat):
        dy, dx = divmod(k, 2)
        c = _CHANNEL[ch]
        out[..., c] += m[dy::2, dx::2]
        count[c] += 1
    return out / count


def equalize_cfa(raw: ArrayLike, pattern: str = "RGGB") -> np.ndarray:
    r"""Return a mosaic of a neutral target with every photosite mapped onto the greens' levels.

    Each of the four photosites ``k`` of the 2x2 cell is mapped affinely so that its dark and
    light levels (5th and 95th percentiles :math:`p_5^k, p_{95}^k`) land on the greens'
    (:math:`g_5, g_{95}`, the green photosites' percentiles averaged):

    .. math:: x' = g_5 + (x - p_5^k)\,\frac{g_{95} - g_5}{p_{95}^k - p_5^k}

    so that the CFA's pattern vanishes on a grey target and the mosaic is one full-resolution
    grey image: how a slanted edge's sharpness is measured on a raw file without demosaicing
    (ISO 12233:2017 measures one colour record; a neutral edge balanced this way keeps every
    photosite's sampling). A photosite with no contrast (:math:`p_{95}^k - p_5^k \le 10^{-9}`)
    is left as it is.

    Parameters
    ----------
    raw : array_like, shape (H, W)
        The mosaic of a neutral (grey) target.
    pattern : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The colours of the 2x2 cell read row by row.

    Returns
    -------
    ndarray, shape (H, W), float64

    Examples
    --------
    >>> raw = np.tile([[0.2, 0.4], [0.4, 0.8]], (4, 4)) * np.repeat([1.0, 2.0], 4)[None, :]
    >>> out = equalize_cfa(raw, "RGGB")
    >>> bool(np.allclose(out[:, ::2], out[:, 1::2]) and np.allclose(out[::2], out[1::2]))
    True
    """
    pat = cfa_pattern(pattern)
    out = np.array(_raw_plane(raw), dtype=np.float64)
    ref = [out[dy::2, dx::2] for dy, dx in ((0, 0), (0, 1), (1, 0), (1, 1))]
    greens = [r for r, ch in zip(ref, pat, strict=True) if ch == "G"]
    g_lo = float(np.mean([np.percentile(g, 5) for g in greens]))
    g_hi = float(np.mean([np.percentile(g, 95) for g in greens]))
    for k in range(4):
        dy, dx = divmod(k, 2)
        site = out[dy::2, dx::2]
        lo, hi = float(np.percentile(site, 5)), float(np.percentile(site, 95))
        if hi - lo > 1e-9:
            out[dy::2, dx::2] = g_lo + (site - lo) * (g_hi - g_lo) / (hi - lo)
    return out
