"""Edge points and edge contours for :mod:`imageform.geometry.plumb_line` (internal).

``grey`` reads the image (``grey_levels`` without its checks), ``edge_points`` finds sub-pixel
edge points with their gradient directions, ``contours`` groups them into connected contours
of one direction sector.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._colormath import luma_601
from imageform._typing import ArrayLike, FloatArray
from imageform._validate import INTEGER_SCALE, as_image
from imageform.errors import InvalidInputError

__all__ = ["contours", "edge_points", "grey", "grey_levels"]


def grey(image: ArrayLike) -> FloatArray:
    """Grey float64 of a grey or RGB image (Rec. 601 luma of RGB), as :func:`as_image` scales.

    The one reading of an image for the line detectors (``lsd_segments``,
    ``detect_line_segments`` and the plumb line); the luma is
    :func:`imageform._colormath.luma_601` (channel by channel).
    """
    arr = np.asarray(image)
    if arr.ndim == 2:
        img = as_image(arr[..., None], "image", channels=1)[..., 0]
    elif arr.ndim == 3 and arr.shape[-1] == 3:
        img = luma_601(np, as_image(arr, "image"))
    elif arr.ndim == 3 and arr.shape[-1] == 1:
        img = as_image(arr, "image", channels=1)[..., 0]
    else:
        raise InvalidInputError(
            f"expected a grey (H, W) or RGB (H, W, 3) image, got shape {arr.shape}"
        )
    return np.asarray(img, dtype=np.float64)


def grey_levels(image: ArrayLike) -> FloatArray | None:
    """Grey levels 0-255 (float64) of a grey or RGB image, without :func:`grey`'s checks.

    For code that only decides something from an image that :func:`grey` reads later (and
    refuses, if it must, with its message): the full range of ``uint8`` / ``uint16`` (as
    :func:`~imageform._validate.as_image` takes it) or floats in [0, 1] mapped to 0-255, in
    float64 throughout, then :func:`~imageform._colormath.luma_601` of RGB. ``None`` for a
    shape or dtype that :func:`grey` refuses; NaN, inf and out-of-range values come back as
    they are.

    Examples
    --------
    >>> grey_levels(np.array([[0, 128, 255]], np.uint8)).tolist()
    [[0.0, 128.0, 255.0]]
    >>> grey_levels(np.zeros((2, 2, 4))) is None
    True
    """
    arr = np.asarray(image)
    if arr.ndim == 3 and arr.shape[-1] == 1:
        arr = arr[..., 0]
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[-1] == 3)):
        return None
    if str(arr.dtype) in INTEGER_SCALE:  # as as_image names them (not a byte-swapped one)
        full = INTEGER_SCALE[str(arr.dtype)]
    elif np.issubdtype(arr.dtype, np.floating):
        full = 1.0
    else:
        return None
    levels = arr.astype(np.float64) * (255.0 / full)
    return luma_601(np, levels) if levels.ndim == 3 else levels


def edge_points(img: FloatArray, threshold: float) -> tuple[FloatArray, FloatArray]:
    """Sub-pixel edge points ``(N, 2)`` ``(u, v)`` and unit gradient directions ``(N, 2)``."""
    from scipy import ndimage

    g = ndimage.gaussian_filter(img, 1.0, mode="nearest")
    gy, gx = np.gradient(g)
    mag = np.hypot(gx, gy)
    cand = mag > threshold
    cand[:3] = cand[-3:] = False
    cand[:, :3] = cand[:, -3:] = False
    v, u = np.nonzero(cand)
    m0 = mag[v, u]
    nx, ny = gx[v, u] / m0, gy[v, u] / m0
    plus = ndimage.map_coordinates(mag, [v + ny, u + nx], order=1)
    minus = ndimage.map_coordinates(mag, [v - ny, u - nx], order=1)
    keep = (m0 >= plus) & (m0 > minus)
    m0, plus, minus = m0[keep], plus[keep], minus[keep]
    u, v, nx, ny = u[keep], v[keep], nx[keep], ny[keep]
    curv = minus - 2.0 * m0 + plus
    off = np.where(curv < 0, 0.5 * (minus - plus) / np.where(curv < 0, curv, -1.0), 0.0)
    off = np.clip(off, -0.5, 0.5)
    pts = np.stack((u + off * nx, v + off * ny), axis=-1)
    return pts, np.stack((nx, ny), axis=-1)


def contours(
    pts: FloatArray, normals: FloatArray, shape: tuple[int, int], min_length: float
) -> list[np.ndarray]:
    """Index arrays of the edge contours: connected edge pixels of one polarity and direction.

    The gradient direction (signed: the two sides of a thin bar are two contours) is cut into
    16 sectors of 45 degrees overlapping by half, so that an arc turning by up to 22.5 degrees
    lies whole in one; each sector's edge pixels, closed over one-pixel gaps, are labelled
    (8-connected). Longest first, a contour is kept when it is ``min_length`` long and at
    most half of its points belong to a contour kept before.
    """
    from scipy import ndimage

    h, w = shape
    iu = np.clip(np.round(pts[:, 0]).astype(np.int64), 0, w - 1)
    iv = np.clip(np.round(pts[:, 1]).astype(np.int64), 0, h - 1)
    ang = np.arctan2(normals[:, 1], normals[:, 0]) % (2 * math.pi)
    step = math.pi / 8
    cands: list[np.ndarray] = []
    for j in range(16):
        sel = np.nonzero(((ang - j * step) % (2 * math.pi)) < 2 * step)[0]
        if len(sel) < 3:
            continue
        mask = np.zeros((h, w), dtype=bool)
        mask[iv[sel], iu[sel]] = True
        lab, n = ndimage.label(ndimage.binary_closing(mask) | mask, structure=np.ones((3, 3)))
        if n == 0:
            continue
        ids = lab[iv[sel], iu[sel]]
        order = np.argsort(ids, kind="stable")
        bounds = np.searchsorted(ids[order], np.arange(1, n + 2))
        for a in range(n):
            members = sel[order[bounds[a] : bounds[a + 1]]]
            if len(members) < max(3, 0.8 * min_length):
                continue
            p = pts[members]
            if np.hypot(*np.ptp(p, axis=0)) >= min_length:
                cands.append(members)
    cands.sort(key=len, reverse=True)
    taken = np.zeros(len(pts), dtype=bool)
    out = []
    for c in cands:
        if taken[c].mean() <= 0.5:
            out.append(c[~taken[c]])
            taken[c] = True
    return out
