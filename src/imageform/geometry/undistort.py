"""Image undistortion by inverse mapping with bilinear sampling.

For every pixel of the *output* (ideal, undistorted) image, the ideal normalised coordinate is
``K_new⁻¹ (u, v, 1)``; the distortion model moves it to where the lens put it, ``K`` maps that
to a source pixel, and the source image is sampled there bilinearly. This is the inverse-map
formulation of OpenCV's ``initUndistortRectifyMap`` + ``remap`` (which quantise the sampling
position to 1/32 pixel; this module does not).

NumPy images run numba kernels (a fused Brown-Conrady kernel, a remap kernel). Other
Array-API arrays (PyTorch, CuPy, array-api-strict) run the same arithmetic in their own
namespace and on their own device (:mod:`imageform.geometry._remap_xp`); Dask images are
undistorted lazily, block by block, each output block from the source window it needs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._backend import (
    common_device,
    constant,
    device_of,
    is_dask_namespace,
    is_numpy_namespace,
    namespace,
    reads_values,
    to_numpy,
    use_numba,
)
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    MAX_MAGNITUDE,
    as_bool,
    as_float_bounded,
    as_image,
    as_matrix_bounded,
    as_real,
    check_memory,
    format_shape,
    size_pair,
)
from imageform.errors import InvalidInputError
from imageform.geometry._remap_xp import map_grid, remap_dask, remap_xp
from imageform.geometry.distortion import BrownConrady, DistortionModel, _check_model

__all__ = ["remap_bilinear", "undistort_image", "undistortion_map"]


_INT_SCALE = {np.dtype(np.uint8): 1.0 / 255.0, np.dtype(np.uint16): 1.0 / 65535.0}


def _as_batch(image: Any) -> tuple[np.ndarray, tuple[int, ...], bool, float]:
    """Return the image as a C-contiguous ``(B, H, W, C)`` batch, its shape, 2-D flag and scale.

    The full shape, whether it was 2-D, and the scale to floats: uint8/uint16 NumPy images
    are kept as they are (the kernels sample them and scale by 1/255 or 1/65535, without a
    float copy of the image).
    """
    if isinstance(image, np.ndarray) and (
        image.dtype in _INT_SCALE or image.dtype in (np.float32, np.float64)
    ):
        arr = image
        scale = _INT_SCALE.get(arr.dtype, 1.0)
    else:
        arr = np.asarray(
            to_numpy(as_image(image, "image", channels=None, range_check=False, finite=False))
        )
        scale = 1.0
    if arr.ndim < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(arr.shape)}"
        )
    gray = arr.ndim == 2
    if gray:
        arr = arr[..., None]
    lead = arr.shape[:-3]
    h, w, c = arr.shape[-3:]
    return np.ascontiguousarray(arr.reshape(-1, h, w, c)), (*lead, h, w, c), gray, scale


def _out_dtype(batch: np.ndarray, keep: bool = False) -> Any:
    """Return the output dtype of ``batch``.

    float32 for uint8/uint16 images (as :func:`imageform._validate.as_image`) unless ``keep``
    (``keep_dtype=True``: their own dtype), else theirs.
    """
    return np.float32 if batch.dtype in _INT_SCALE and not keep else batch.dtype


def _keep_dtype(keep_dtype: object, image: Any, fill: float) -> tuple[bool, float]:
    """Tell whether the kernels write the image's integer dtype, and check ``fill``.

    The integer dtype is kept with ``keep_dtype=True`` on a uint8/uint16 NumPy image; ``fill``
    is then checked in its codes.
    """
    if not as_bool(keep_dtype, "keep_dtype"):
        return False, fill
    dtype = getattr(image, "dtype", None)
    if isinstance(image, np.ndarray) and dtype in _INT_SCALE:
        hi = float(np.iinfo(dtype).max)
        if math.isnan(fill) or not 0.0 <= fill <= hi:
            raise InvalidInputError(
                f"expected fill in [0, {hi:.0f}] (codes of the {dtype} output, keep_dtype=True),"
                f" got {fill!r}"
            )
        return True, fill
    if not isinstance(image, np.ndarray) and "int" in str(dtype):  # torch.uint8, a Dask uint8
        raise InvalidInputError(
            f"keep_dtype=True on integer images takes NumPy arrays, got {type(image).__name__}"
        )
    return False, fill  # float images keep their dtype anyway


def _kernel_args(batch: np.ndarray, keep: bool) -> tuple[Any, tuple[np.ndarray, np.ndarray, float]]:
    """Return the kernels' output dtype for ``batch`` and their last arguments.

    The arguments: the arithmetic's and the sample index's dtype carriers and the largest code
    (0 for float outputs); see :mod:`imageform._kernels.remap`.
    """
    out_dtype = np.dtype(_out_dtype(batch, keep))
    acc = np.empty(0, np.float64 if out_dtype == np.float64 else np.float32)
    kcar = np.empty(0, np.int32 if math.prod(batch.shape[1:]) < 2**31 - 1 else np.int64)
    hi = float(np.iinfo(out_dtype).max) if out_dtype.kind == "u" else 0.0
    return out_dtype, (acc, kcar, hi)


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


def _fill(fill: object) -> float:
    """Check the fill value: a finite real or NaN (to mark pixels with no source)."""
    try:
        if isinstance(fill, float | np.floating) and math.isnan(fill):
            return math.nan
    except TypeError:  # pragma: no cover
        pass
    return as_real(fill, "fill", minimum=-MAX_MAGNITUDE, maximum=MAX_MAGNITUDE)


def _same_kind(image: Any, map_uv: Any) -> None:
    """Refuse a Dask map_uv with an eager image.

    A Dask image with an eager map is the lazy path; the map is small.
    """
    lazy_map = hasattr(map_uv, "shape") and is_dask_namespace(namespace(map_uv))
    lazy_image = hasattr(image, "shape") and is_dask_namespace(namespace(image))
    if lazy_map and not lazy_image:
        raise InvalidInputError(
            f"expected a Dask image with a Dask map_uv, got a {type(image).__name__} image; "
            "pass map_uv.compute() (or a Dask image)"
        )


def remap_bilinear(
    image: ArrayLike, map_uv: ArrayLike, *, fill: float = 0.0, keep_dtype: bool = False
) -> Array:
    r"""Sample ``image`` at the source positions ``map_uv`` by bilinear interpolation.

    .. math::

        I'(i, j) = \sum_{a, b \in \{0, 1\}} w_a(u) w_b(v)\, I(\lfloor v \rfloor + b,
        \lfloor u \rfloor + a), \quad (u, v) = \mathrm{map}(i, j)

    Parameters
    ----------
    image : array (H, W) or (..., H, W, C)
        uint8/uint16 (read as full range) or floats (any range; NaN marks missing data and
        propagates to the output pixels that use it).
    map_uv : array (H', W', 2)
        Source ``(u, v)`` = (column, row) for every output pixel; pixel centres at integers.
    fill : float
        Value for positions outside ``[0, W-1] × [0, H-1]`` or NaN (a constant border, as
        OpenCV's ``BORDER_CONSTANT``; nothing is clamped), in the output's units.
    keep_dtype : bool
        8-bit in, 8-bit out (NumPy uint8/uint16 images): the result in the image's dtype,
        the interpolated code value rounded to the nearest integer (ties to even), as
        ``cv2.remap`` returns it; ``fill`` is then a code in ``[0, 255]`` (``[0, 65535]``).
        At most half a code from the float result times 255 (65535). Off by default: uint8
        and uint16 images give float32 in [0, 1]. Float images keep their dtype either way.

    Returns
    -------
    array (H', W') or (..., H', W', C), the image's float dtype (float32 for uint8/uint16
    unless ``keep_dtype``) and array kind (PyTorch in, PyTorch out on the same device,
    differentiable; Dask in, a lazy Dask array out).

    Notes
    -----
    NumPy images run a numba kernel: positions in the map's precision, the interpolation
    in float32 (float64 for float64 images), so a uint8, uint16 or float32 result is within
    1e-7 (relative) of the float64 reference. With ``keep_dtype`` on uint8 it equals OpenCV
    5's ``cv2.remap(image, map_uv, None, cv2.INTER_LINEAR)`` bit for bit wherever the four
    neighbours are inside the image (OpenCV's ``BORDER_CONSTANT`` also blends the border
    colour into the half pixel around the image; this function fills only outside
    ``[0, W-1] × [0, H-1]``).

    Examples
    --------
    >>> img = np.array([[0.0, 1.0], [2.0, 3.0]])
    >>> remap_bilinear(img, [[[0.5, 0.5]]]).tolist()
    [[1.5]]
    """
    fill = _fill(fill)
    keep, fill = _keep_dtype(keep_dtype, image, fill)
    _same_kind(image, map_uv)
    if hasattr(image, "shape") and math.prod(tuple(image.shape)) == 0:
        raise InvalidInputError(
            f"expected a non-empty image, got shape {format_shape(tuple(image.shape))}"
        )
    xp = namespace(image, map_uv)
    if is_dask_namespace(xp):
        return _remap_dask_public(image, map_uv, float(fill))
    if not is_numpy_namespace(xp):
        return _remap_generic(image, map_uv, float(fill), xp)
    batch, full_shape, gray, scale = _as_batch(image)
    if isinstance(map_uv, np.ndarray) and map_uv.dtype in (np.float32, np.float64):
        m = map_uv  # float32 maps are sampled as they are (no float64 copy)
    else:
        m = np.asarray(
            to_numpy(as_float_bounded(map_uv, "map_uv", xp=np, finite=False)), np.float64
        )
    if m.ndim != 3 or m.shape[-1] != 2:
        raise InvalidInputError(f"expected map_uv of shape (H, W, 2), got {format_shape(m.shape)}")
    check_memory(
        8.0 * m.shape[0] * m.shape[1] * max(1, math.prod(batch.shape[:1] + batch.shape[3:])),
        "map_uv",
        "the remapped image",
    )
    fill_v = float(fill)
    hw = (int(m.shape[0]), int(m.shape[1]))
    if use_numba(batch):
        from imageform._kernels.remap import pick

        out_dtype, last = _kernel_args(batch, keep)
        out = np.empty((batch.shape[0], *hw, batch.shape[-1]), dtype=out_dtype)
        kernel: Any = pick("remap", out.size)
        kernel(batch, np.ascontiguousarray(m), scale, fill_v, out, *last)
    elif keep:
        out = _rounded(
            _remap_bilinear_numpy(batch.astype(np.float64), m[..., 0], m[..., 1], fill_v),
            batch.dtype,
        )
    else:
        out = _remap_bilinear_numpy(_scaled(batch, scale), m[..., 0], m[..., 1], fill_v)
    out = out.reshape(*full_shape[:-3], *hw, full_shape[-1])
    return out[..., 0] if gray else out


def _rounded(values: np.ndarray, dtype: Any) -> np.ndarray:
    """Code values rounded to the nearest integer (ties to even) in ``dtype``'s range."""
    info = np.iinfo(dtype)
    return np.clip(np.rint(values), info.min, info.max).astype(dtype)


def _scaled(batch: np.ndarray, scale: float) -> np.ndarray:
    """Scale an integer batch to float32 in [0, 1] (plain path; the kernels scale on the fly)."""
    if batch.dtype in _INT_SCALE:
        return batch.astype(np.float32) * np.float32(scale)
    return batch


def _inverse_k(Km: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    fx, s, cx, fy, cy = Km[0, 0], Km[0, 1], Km[0, 2], Km[1, 1], Km[1, 2]
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    return np.stack([x, y], axis=-1)


def _intrinsics(K: Any, new_K: Any) -> tuple[np.ndarray, np.ndarray]:
    """``K`` and ``new_K`` (default ``K``) as float64 ``(3, 3)``, checked upper triangular."""
    Km = np.asarray(to_numpy(as_matrix_bounded(K, "K", (3, 3), batch=False)), dtype=np.float64)
    Kn = (
        Km
        if new_K is None
        else np.asarray(
            to_numpy(as_matrix_bounded(new_K, "new_K", (3, 3), batch=False)), np.float64
        )
    )
    for name, M in (("K", Km), ("new_K", Kn)):
        if M[0, 0] == 0 or M[1, 1] == 0 or M[1, 0] != 0 or M[2].tolist() != [0.0, 0.0, 1.0]:
            raise InvalidInputError(
                f"expected {name} upper triangular with non-zero fx, fy and last row (0, 0, 1)"
            )
    return Km, Kn


def _intrinsics_on(K: Any, new_K: Any, xp: Any, device: Any) -> tuple[Any, Any]:
    """``K`` and ``new_K`` for a map computed in ``xp`` on ``device``.

    Host values (NumPy, lists, CPU tensors) are read and checked by :func:`_intrinsics`;
    device arrays stay where they are, as float64 ``xp`` matrices, unread (docs/design.md,
    "Devices").
    """
    if reads_values(K) and (new_K is None or reads_values(new_K)):
        return _intrinsics(K, new_K)
    Km = as_matrix_bounded(K, "K", (3, 3), batch=False, xp=xp, dtype=xp.float64, device=device)
    Kn = (
        Km
        if new_K is None
        else as_matrix_bounded(
            new_K, "new_K", (3, 3), batch=False, xp=xp, dtype=xp.float64, device=device
        )
    )
    return Km, Kn


def undistortion_map(
    shape: tuple[int, int],
    K: ArrayLike,
    distortion: DistortionModel,
    *,
    new_K: ArrayLike | None = None,
) -> Array:
    r"""Source pixel ``(u, v)`` in the distorted image for every pixel of the ideal image.

    .. math::

        (x, y, 1)^T = K_{new}^{-1} (u, v, 1)^T,\quad
        (u_s, v_s, 1)^T = K\,(\mathrm{distort}(x, y), 1)^T

    ``shape`` is the output ``(H, W)``; ``new_K`` defaults to ``K``. Returns ``(H, W, 2)``
    float64 (of ``K``'s array kind and device); NaN where the model has no distorted point.

    Examples
    --------
    >>> m = undistortion_map((3, 3), [[2.0, 0, 1], [0, 2, 1], [0, 0, 1]], None)
    >>> m[0, 0].tolist()
    [0.0, 0.0]
    """
    h, w = size_pair(shape, "shape (H, W)")
    check_memory(16.0 * h * w, "shape", f"a ({h}, {w}, 2) float64 map")
    xp = namespace(K, new_K)
    if not is_numpy_namespace(xp):
        dev = common_device(K, new_K)
        Km, Kn = _intrinsics_on(K, new_K, xp, dev)
        _check_model(distortion)
        return map_grid((0, h), (0, w), Km, Kn, distortion, xp, xp.float64, dev)
    Km, Kn = _intrinsics(K, new_K)
    _check_model(distortion)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    xy = _inverse_k(Kn, u, v)
    if distortion is not None:
        xy = np.asarray(distortion.distort(xy))
    us = Km[0, 0] * xy[..., 0] + Km[0, 1] * xy[..., 1] + Km[0, 2]
    vs = Km[1, 1] * xy[..., 1] + Km[1, 2]
    return np.stack([us, vs], axis=-1)


def undistort_image(
    image: ArrayLike,
    K: ArrayLike,
    distortion: DistortionModel,
    *,
    new_K: ArrayLike | None = None,
    out_shape: tuple[int, int] | None = None,
    fill: float = 0.0,
    keep_dtype: bool = False,
) -> Array:
    r"""Remove lens distortion from an image by inverse mapping and bilinear sampling.

    .. math::

        I_u(u, v) = I_d\big(K\,\mathrm{distort}(K_{new}^{-1}(u, v, 1)^T)\big)

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
        Value where the source position falls outside the image (in the output's units).
    keep_dtype : bool
        uint8/uint16 NumPy images: the result in their dtype, rounded to the nearest code
        (``fill`` a code then), as ``cv2.undistort`` returns it; see
        :func:`remap_bilinear`.

    Returns
    -------
    array
        The undistorted image, float (float32 for integer input unless ``keep_dtype``), of
        the input's array
        kind and device. A Dask image gives a lazy Dask array with the input's row and
        column chunks (for the default ``out_shape``): each output block is remapped from
        the source window it reads, and equals the in-memory result.

    Notes
    -----
    Equivalent to OpenCV's ``cv2.undistort`` (``initUndistortRectifyMap`` + ``remap`` with
    ``INTER_LINEAR``) up to OpenCV's 1/32-pixel quantisation of the sampling positions.
    Brown-Conrady on NumPy images runs one fused numba kernel (the source position of every
    output pixel computed in float64 where it is sampled, no map array); other models
    build the map (:func:`undistortion_map`) and remap it.

    Examples
    --------
    >>> img = np.zeros((5, 5)); img[2, 2] = 1.0
    >>> K = [[10.0, 0, 2], [0, 10, 2], [0, 0, 1]]
    >>> float(undistort_image(img, K, None)[2, 2])
    1.0
    """
    xp = namespace(image)
    batch_shape = tuple(int(n) for n in image.shape) if hasattr(image, "shape") else None
    if batch_shape is None:
        batch_shape = np.shape(np.asarray(image))
    if len(batch_shape) < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(batch_shape)}"
        )
    hw = batch_shape[:2] if len(batch_shape) == 2 else batch_shape[-3:-1]
    if math.prod(batch_shape) == 0:
        raise InvalidInputError(
            f"expected a non-empty image, got shape {format_shape(batch_shape)}"
        )
    fill = _fill(fill)
    keep, fill = _keep_dtype(keep_dtype, image, fill)
    out_hw = (
        (int(hw[0]), int(hw[1])) if out_shape is None else size_pair(out_shape, "out_shape (H, W)")
    )
    check_memory(
        16.0 * out_hw[0] * out_hw[1] * max(1, math.prod(batch_shape) // max(1, hw[0] * hw[1])),
        "out_shape",
        f"an undistorted image of {out_hw[0]} x {out_hw[1]} pixels",
    )
    if is_dask_namespace(xp):
        return _undistort_dask(image, K, distortion, new_K, out_hw, float(fill))
    # a lazy 3x3 K with an eager image: computed here (nine numbers), the image stays eager
    K, new_K = (
        np.asarray(k) if hasattr(k, "shape") and is_dask_namespace(namespace(k)) else k
        for k in (K, new_K)
    )
    if not is_numpy_namespace(xp):
        Km, Kn = _intrinsics_on(K, new_K, xp, device_of(image))
        _check_model(distortion)
        fused = _undistort_cuda(image, Km, Kn, distortion, out_hw, float(fill), xp)
        if fused is not None:
            return fused
        m = map_grid(
            (0, out_hw[0]), (0, out_hw[1]), Km, Kn, distortion, xp, xp.float64, device_of(image)
        )
        return _remap_generic(image, m, float(fill), xp)
    if isinstance(distortion, BrownConrady):
        batch, full_shape, gray, scale = _as_batch(image)
        if use_numba(batch):
            # fused kernel: source position and sampling in one pass (no (H, W, 2) map)
            from imageform._kernels.remap import pick

            Km, Kn = _intrinsics(K, new_K)
            out_dtype, last = _kernel_args(batch, keep)
            out = np.empty((batch.shape[0], *out_hw, batch.shape[-1]), dtype=out_dtype)
            coeffs = np.asarray(distortion.coeffs, dtype=np.float64)
            kernel: Any = pick("undistort", out.size)
            kernel(batch, Kn, Km, coeffs, scale, float(fill), out, *last)
            out = out.reshape(*full_shape[:-3], *out_hw, full_shape[-1])
            return out[..., 0] if gray else out
    m = undistortion_map(out_hw, K, distortion, new_K=new_K)
    return remap_bilinear(image, m, fill=fill, keep_dtype=keep)


def _undistort_cuda(
    image: Any, Km: Any, Kn: Any, distortion: Any, out_hw: tuple[int, int], fill: float, xp: Any
) -> Any:
    """:func:`undistort_image` of a float CUDA image, Brown-Conrady or none: one CUDA kernel.

    The source position of every output pixel is computed where it is sampled (no map);
    ``None`` when the kernel does not apply (other models, integer images, no CUDA).
    """
    from imageform._cuda import geometry as cuda_geometry

    if not (distortion is None or isinstance(distortion, BrownConrady)):
        return None
    if not cuda_geometry.on_cuda(image):
        return None
    img = as_image(image, "image", channels=None, xp=xp, range_check=False, finite=False)
    # host intrinsics: float64 device constants, uploaded once (imageform._backend.constant)
    like = xp.empty((0,), dtype=xp.float64, device=device_of(img))
    Km, Kn = (
        M
        if cuda_geometry.on_cuda(M, floats=False)
        else constant(np.asarray(M, np.float64), like, xp)
        for M in (Km, Kn)
    )
    gray = img.ndim == 2
    x = img[..., None] if gray else img
    *lead, h, w, c = (int(n) for n in x.shape)
    coeffs = distortion.coeffs if distortion is not None else None
    out = cuda_geometry.undistort_image(
        xp.reshape(x, (-1, h, w, c)), Kn, Km, coeffs, out_hw, float(fill)
    )
    if out is None:  # the kernels are unusable here
        return None
    out = xp.reshape(out, (*lead, out_hw[0], out_hw[1], c))
    return out[..., 0] if gray else out


def _remap_generic(image: Any, map_uv: Any, fill: float, xp: Any) -> Any:
    """remap_bilinear for non-NumPy Array-API arrays (same namespace and device out)."""
    img = as_image(image, "image", channels=None, xp=xp, range_check=False, finite=False)
    if device_of(img) != common_device(image, map_uv):  # a NumPy image, a device map
        img = xp.asarray(img, device=common_device(image, map_uv))
    if img.ndim < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(img.shape)}"
        )
    m = xp.asarray(map_uv, device=device_of(img))
    if m.ndim != 3 or m.shape[-1] != 2:
        raise InvalidInputError(f"expected map_uv of shape (H, W, 2), got {format_shape(m.shape)}")
    gray = img.ndim == 2
    x = img[..., None] if gray else img
    *lead, h, w, c = (int(n) for n in x.shape)
    from imageform._cuda import geometry as cuda_geometry

    out = None
    if cuda_geometry.on_cuda(x) and cuda_geometry.on_cuda(m):
        # one CUDA kernel (imageform._cuda.geometry); a float32 map is read as it is (its
        # positions are exact in float64: the same numbers, no conversion kernel); None when
        # the kernels are unusable here
        out = cuda_geometry.remap(xp.reshape(x, (-1, h, w, c)), m, fill)
    if out is None:
        m = xp.astype(m, xp.float64) if m.dtype != xp.float64 else m
        out = remap_xp(xp.reshape(x, (-1, h, w, c)), m, fill, xp)
    out = xp.reshape(out, (*lead, int(m.shape[0]), int(m.shape[1]), c))
    return out[..., 0] if gray else out


def _dask_image(image: Any) -> tuple[Any, bool]:
    img = as_image(image, "image", channels=None, range_check=False, finite=False)
    if img.ndim < 2:
        raise InvalidInputError(
            f"expected image of shape (H, W) or (..., H, W, C), got {format_shape(img.shape)}"
        )
    gray = img.ndim == 2
    return (img[..., None] if gray else img), gray


def _remap_dask_public(image: Any, map_uv: Any, fill: float) -> Any:
    """remap_bilinear on a Dask image: per block of the map, its source window."""
    img, gray = _dask_image(image)
    m = np.asarray(map_uv, dtype=np.float64)  # a Dask map is computed (it is (H', W', 2))
    if m.ndim != 3 or m.shape[-1] != 2:
        raise InvalidInputError(f"expected map_uv of shape (H, W, 2), got {format_shape(m.shape)}")
    chunks = _out_chunks(img, (m.shape[0], m.shape[1]))

    def block_map(rows: tuple[int, int], cols: tuple[int, int]) -> np.ndarray:
        return m[rows[0] : rows[1], cols[0] : cols[1]]

    def block_fn(win: np.ndarray, rows: Any, cols: Any, origin: tuple[int, int]) -> np.ndarray:
        local = block_map(rows, cols) - np.array([origin[1], origin[0]], dtype=np.float64)
        return np.asarray(remap_bilinear(win, local, fill=fill))

    out = remap_dask(img, (m.shape[0], m.shape[1]), block_map, block_fn, chunks)
    return out[..., 0] if gray else out


def _out_chunks(img: Any, out_hw: tuple[int, int]) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Return the input's row/column chunks if the output has its size, else the same chunk size."""
    res = []
    for axis, n in ((-3, out_hw[0]), (-2, out_hw[1])):
        ch = img.chunks[axis]
        if sum(ch) == n:
            res.append(tuple(ch))
        else:
            size = max(ch)
            res.append(tuple(min(size, n - i) for i in range(0, n, size)))
    return res[0], res[1]


def _undistort_dask(
    image: Any, K: Any, distortion: Any, new_K: Any, out_hw: tuple[int, int], fill: float
) -> Any:
    """undistort_image on a Dask image: each output block from the source window it reads."""
    from array_api_compat import numpy as cnp

    img, gray = _dask_image(image)
    Km, Kn = _intrinsics(K, new_K)
    _check_model(distortion)
    chunks = _out_chunks(img, out_hw)

    def block_map(rows: tuple[int, int], cols: tuple[int, int]) -> np.ndarray:
        return np.asarray(map_grid(rows, cols, Km, Kn, distortion, cnp, np.float64))

    def block_fn(win: np.ndarray, rows: Any, cols: Any, origin: tuple[int, int]) -> np.ndarray:
        # the same in-memory function on the window: shift K by the window's origin and
        # new_K by the block's, so that local pixels map to the same source pixels
        Ks = Km.copy()
        Ks[0, 2] -= origin[1]
        Ks[1, 2] -= origin[0]
        Kb = Kn.copy()
        Kb[0, 2] -= cols[0]
        Kb[1, 2] -= rows[0]
        shape = (rows[1] - rows[0], cols[1] - cols[0])
        return np.asarray(
            undistort_image(win, Ks, distortion, new_K=Kb, out_shape=shape, fill=fill)
        )

    out = remap_dask(img, out_hw, block_map, block_fn, chunks)
    return out[..., 0] if gray else out
