"""Image undistortion by inverse mapping with bilinear sampling.

For every pixel of the *output* (ideal, undistorted) image, the ideal normalised coordinate is
``K_new⁻¹ (u, v, 1)``; the distortion model moves it to where the lens put it, ``K`` maps that
to a source pixel, and the source image is sampled there bilinearly. This is the inverse-map
formulation of OpenCV's ``initUndistortRectifyMap`` + ``remap`` (which quantise the sampling
position to 1/32 pixel; this module does not).

NumPy in, NumPy out (images are not Array-API generic here); a numba kernel does the sampling.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._backend import to_numpy, use_numba
from imageform._validate import as_image, as_matrix, format_shape
from imageform.errors import InvalidInputError
from imageform.geometry.distortion import DistortionModel, _check_model

__all__ = ["remap_bilinear", "undistort_image", "undistortion_map"]


def _as_batch(image: Any) -> tuple[np.ndarray, tuple[int, ...], bool]:
    arr = np.asarray(
        to_numpy(as_image(image, "image", channels=None, range_check=False, finite=False))
    )
    if arr.ndim < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(arr.shape)}"
        )
    gray = arr.ndim == 2
    if gray:
        arr = arr[..., None]
    lead = arr.shape[:-3]
    h, w, c = arr.shape[-3:]
    return np.ascontiguousarray(arr.reshape(-1, h, w, c)), (*lead, h, w, c), gray


def _remap_bilinear_numpy(
    img: np.ndarray, map_u: np.ndarray, map_v: np.ndarray, fill: float
) -> np.ndarray:
    """Plain twin of :func:`imageform._kernels.remap.remap_bilinear` (batch ``(B, H, W, C)``)."""
    _, h, w, _ = img.shape
    inside = (map_u >= 0) & (map_u <= w - 1) & (map_v >= 0) & (map_v <= h - 1)
    u = np.where(inside, map_u, 0.0)
    v = np.where(inside, map_v, 0.0)
    x0 = np.minimum(np.floor(u).astype(np.intp), w - 1)
    y0 = np.minimum(np.floor(v).astype(np.intp), h - 1)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    ax = (u - x0)[None, ..., None]
    ay = (v - y0)[None, ..., None]
    out = (
        (1 - ax) * (1 - ay) * img[:, y0, x0]
        + ax * (1 - ay) * img[:, y0, x1]
        + (1 - ax) * ay * img[:, y1, x0]
        + ax * ay * img[:, y1, x1]
    )
    out = np.where(inside[None, ..., None], out, fill)
    return out.astype(img.dtype, copy=False)


def remap_bilinear(image: Any, map_uv: Any, *, fill: float = 0.0) -> np.ndarray:
    """Sample ``image`` at the source positions ``map_uv`` by bilinear interpolation.

    .. math::

        I'(i, j) = \\sum_{a, b \\in \\{0, 1\\}} w_a(u) w_b(v)\\, I(\\lfloor v \\rfloor + b,
        \\lfloor u \\rfloor + a), \\quad (u, v) = \\mathrm{map}(i, j)

    Parameters
    ----------
    image : array (H, W) or (..., H, W, C)
        uint8/uint16 (read as full range) or floats (any range; NaN marks missing data and
        propagates to the output pixels that use it).
    map_uv : array (H', W', 2)
        Source ``(u, v)`` = (column, row) for every output pixel; pixel centres at integers.
    fill : float
        Value for positions outside ``[0, W-1] × [0, H-1]`` or NaN (a constant border, as
        OpenCV's ``BORDER_CONSTANT``; nothing is clamped).

    Returns
    -------
    array (H', W') or (..., H', W', C), the image's float dtype.

    >>> img = np.array([[0.0, 1.0], [2.0, 3.0]])
    >>> remap_bilinear(img, [[[0.5, 0.5]]]).tolist()
    [[1.5]]
    """
    batch, full_shape, gray = _as_batch(image)
    m = np.asarray(to_numpy(map_uv), dtype=np.float64)
    if m.ndim != 3 or m.shape[-1] != 2:
        raise InvalidInputError(f"expected map_uv of shape (H, W, 2), got {format_shape(m.shape)}")
    fill_v = float(fill)
    map_u = np.ascontiguousarray(m[..., 0])
    map_v = np.ascontiguousarray(m[..., 1])
    if use_numba(batch):
        from imageform._kernels.remap import remap_bilinear as kernel

        out = np.empty((batch.shape[0], *map_u.shape, batch.shape[-1]), dtype=batch.dtype)
        kernel(batch, map_u, map_v, fill_v, out)
    else:
        out = _remap_bilinear_numpy(batch, map_u, map_v, fill_v)
    out = out.reshape(*full_shape[:-3], *map_u.shape, full_shape[-1])
    return out[..., 0] if gray else out


def _inverse_k(Km: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    fx, s, cx, fy, cy = Km[0, 0], Km[0, 1], Km[0, 2], Km[1, 1], Km[1, 2]
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    return np.stack([x, y], axis=-1)


def undistortion_map(
    shape: tuple[int, int],
    K: Any,
    distortion: DistortionModel,
    *,
    new_K: Any = None,
) -> np.ndarray:
    """Source pixel ``(u, v)`` in the distorted image for every pixel of the ideal image.

    .. math::

        (x, y, 1)^T = K_{new}^{-1} (u, v, 1)^T,\\quad
        (u_s, v_s, 1)^T = K\\,(\\mathrm{distort}(x, y), 1)^T

    ``shape`` is the output ``(H, W)``; ``new_K`` defaults to ``K``. Returns ``(H, W, 2)``
    float64; NaN where the model has no distorted point.

    >>> m = undistortion_map((3, 3), [[2.0, 0, 1], [0, 2, 1], [0, 0, 1]], None)
    >>> m[0, 0].tolist()
    [0.0, 0.0]
    """
    h, w = (int(shape[0]), int(shape[1]))
    if h < 1 or w < 1:
        raise InvalidInputError(f"expected a positive output shape (H, W), got {shape!r}")
    Km = np.asarray(to_numpy(as_matrix(K, "K", (3, 3), batch=False)), dtype=np.float64)
    Kn = (
        Km
        if new_K is None
        else np.asarray(to_numpy(as_matrix(new_K, "new_K", (3, 3), batch=False)), np.float64)
    )
    for name, M in (("K", Km), ("new_K", Kn)):
        if M[0, 0] == 0 or M[1, 1] == 0 or M[1, 0] != 0 or M[2].tolist() != [0.0, 0.0, 1.0]:
            raise InvalidInputError(
                f"expected {name} upper triangular with non-zero fx, fy and last row (0, 0, 1)"
            )
    _check_model(distortion)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    xy = _inverse_k(Kn, u, v)
    if distortion is not None:
        xy = np.asarray(distortion.distort(xy))
    us = Km[0, 0] * xy[..., 0] + Km[0, 1] * xy[..., 1] + Km[0, 2]
    vs = Km[1, 1] * xy[..., 1] + Km[1, 2]
    return np.stack([us, vs], axis=-1)


def undistort_image(
    image: Any,
    K: Any,
    distortion: DistortionModel,
    *,
    new_K: Any = None,
    out_shape: tuple[int, int] | None = None,
    fill: float = 0.0,
) -> np.ndarray:
    """Remove lens distortion from an image by inverse mapping and bilinear sampling.

    .. math::

        I_u(u, v) = I_d\\big(K\\,\\mathrm{distort}(K_{new}^{-1}(u, v, 1)^T)\\big)

    Parameters
    ----------
    image : array (H, W) or (..., H, W, C)
        The distorted image (uint8/uint16 full range, or floats).
    K : array (3, 3)
        Intrinsics of the distorted image.
    distortion : BrownConrady, DivisionModel or KannalaBrandt
        The lens model on normalised coordinates.
    new_K : array (3, 3), optional
        Intrinsics of the output (default ``K``: same focal length and centre).
    out_shape : (H, W), optional
        Output size (default: the input's).
    fill : float
        Value where the source position falls outside the image.

    Returns
    -------
    array
        The undistorted image, float (float32 for integer input).

    Notes
    -----
    Equivalent to OpenCV's ``cv2.undistort`` (``initUndistortRectifyMap`` + ``remap`` with
    ``INTER_LINEAR``) up to OpenCV's 1/32-pixel quantisation of the sampling positions.

    >>> img = np.zeros((5, 5)); img[2, 2] = 1.0
    >>> K = [[10.0, 0, 2], [0, 10, 2], [0, 0, 1]]
    >>> float(undistort_image(img, K, None)[2, 2])
    1.0
    """
    batch_shape = np.shape(to_numpy(image))
    if len(batch_shape) < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(batch_shape)}"
        )
    hw = batch_shape[:2] if len(batch_shape) == 2 else batch_shape[-3:-1]
    shape = hw if out_shape is None else out_shape
    m = undistortion_map((int(shape[0]), int(shape[1])), K, distortion, new_K=new_K)
    return remap_bilinear(image, m, fill=fill)
