"""Demosaicing: full RGB from a Bayer mosaic.

:func:`demosaic` validates the mosaic once, pads it with a **phase-preserving mirror** and
dispatches to one of the methods in :data:`DEMOSAIC_METHODS`. Each method is a numba kernel
in ``imageform._kernels.demosaic_*`` with a plain NumPy twin (used when
``IMAGEFORM_DISABLE_NUMBA=1``). Arrays of other libraries are computed through NumPy on the
host and converted back.

Borders. A demosaicing filter near the image edge needs samples outside the image. Padding
the mosaic with ``mode="reflect"`` (mirror about the edge pixel: pixel ``-k`` takes the
value of pixel ``k``) keeps the colour of every mirrored sample right, because ``k`` and
``-k`` have the same parity. Padding that repeats the edge pixel (``"symmetric"``,
``"nearest"``) or zero-padding puts, e.g., green values where the filter expects red; that
is the border artefact of colour-demosaicing's issue #8. The padding is also shifted by the
pattern's red offset so that every kernel sees an RGGB phase.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from imageform._backend import (
    device_of,
    is_dask_namespace,
    is_numpy_namespace,
    namespace,
    to_numpy,
    use_numba,
)
from imageform._typing import Array, ArrayLike
from imageform._validate import as_bool, as_image, check_memory, check_option, format_shape
from imageform.errors import InvalidInputError
from imageform.sensor._demosaic_xp import XP_METHODS, demosaic_dask, demosaic_xp
from imageform.sensor.cfa import _red_offset, cfa_pattern

__all__ = ["DEMOSAIC_METHODS", "demosaic"]

#: Demosaicing methods, fastest first; ``"menon"`` is the default, ``"menon_soft"`` the best.
DEMOSAIC_METHODS: tuple[str, ...] = (
    "bilinear",
    "malvar",
    "hamilton_adams",
    "menon",
    "menon_soft",
)

_Kernel = Callable[[np.ndarray, int, int, int, int], np.ndarray]


def _kernels(method: str, numba: bool) -> tuple[_Kernel, int]:
    """(kernel, radius) for a method; imports lazily so numba compiles on first use."""
    if method == "bilinear":
        from imageform._kernels import demosaic_bilinear as m

        return (m.bilinear_numba if numba else m.bilinear_numpy), m.RADIUS
    if method == "malvar":
        from imageform._kernels import demosaic_malvar as m2

        return (m2.malvar_numba if numba else m2.malvar_numpy), m2.RADIUS
    if method == "hamilton_adams":
        from imageform._kernels import demosaic_hamilton_adams as m3

        return (m3.hamilton_adams_numba if numba else m3.hamilton_adams_numpy), m3.RADIUS
    from imageform._kernels import demosaic_menon as m4

    if method == "menon_soft":
        return (m4.menon_soft_numba if numba else m4.menon_soft_numpy), m4.RADIUS
    return (m4.menon_numba if numba else m4.menon_numpy), m4.RADIUS


def _as_raw(raw: ArrayLike, xp: Any) -> Any:
    """Return the mosaic as a float array of shape (..., H, W).

    Colour images are rejected (by shape, before any pass over the values).
    """
    shape = tuple(getattr(raw, "shape", ()) or ())
    if len(shape) >= 3 and shape[-1] != 1:
        raise InvalidInputError(
            f"expected raw as a single-channel raw mosaic (H, W) or (..., H, W, 1), got "
            f"{format_shape(shape)} with {shape[-1]} channels; a batch needs raw[..., None]"
        )
    arr = as_image(raw, "raw", channels=None, xp=xp)
    shape = tuple(arr.shape)
    if arr.ndim == 2:
        return arr
    if arr.ndim >= 3 and shape[-1] == 1:
        return arr[..., 0]
    if arr.ndim >= 3:
        raise InvalidInputError(
            f"expected raw as a single-channel raw mosaic (H, W) or (..., H, W, 1), got "
            f"{format_shape(shape)} with {shape[-1]} channels; a batch needs raw[..., None]"
        )
    raise InvalidInputError(
        f"expected a raw mosaic of shape (H, W) or (..., H, W, 1), got {format_shape(shape)}"
    )


def demosaic(
    raw: ArrayLike,
    pattern: str = "RGGB",
    method: str = "menon",
    *,
    clip: bool = False,
    allow_odd: bool = False,
    keep_dtype: bool = False,
) -> Array:
    r"""Reconstruct a full RGB image from a Bayer colour-filter-array mosaic.

    Every pixel of the mosaic measured one colour (:func:`imageform.sensor.mosaic`); the
    other two are interpolated. The methods, from fastest to best:

    - ``"bilinear"``: the mean of the nearest samples of each colour, i.e. the masked
      planes convolved with
      :math:`K_G = \tfrac14\begin{bmatrix}0&1&0\\1&4&1\\0&1&0\end{bmatrix}`,
      :math:`K_{R,B} = \tfrac14\begin{bmatrix}1&2&1\\2&4&2\\1&2&1\end{bmatrix}`.
    - ``"malvar"``: bilinear plus a Laplacian correction from the measured colour,
      :math:`\hat G = \hat G_{bl} + \alpha \Delta_R` (Malvar, He, Cutler, ICASSP 2004,
      eqs. 4-6; α = 1/2, β = 5/8, γ = 3/4).
    - ``"hamilton_adams"``: edge-directed green (interpolation along the smaller of
      :math:`|G_{x-1} - G_{x+1}| + |2 C_x - C_{x-2} - C_{x+2}|` and its vertical twin),
      then colour differences (Hamilton & Adams, US patent 5,629,734, 1997).
    - ``"menon"``: directional filtering with a posteriori decision and the refinement step
      (Menon, Andriani, Calvagno, IEEE TIP 16(1), 2007, eqs. 3-9 and sec. IV).
    - ``"menon_soft"``: ``"menon"`` with a soft green decision, the horizontal and vertical
      estimates blended with weights :math:`\delta_V^2 : \delta_H^2` (an imageform
      variant; about 0.7 dB better than ``"menon"`` on Kodak at the same speed).

    Parameters
    ----------
    raw : array, shape (H, W) or (..., H, W, 1)
        The mosaic. uint8/uint16 are read as full-range values (/255, /65535) and computed
        in float32; float32 and float64 keep their dtype. ``H, W >= 2`` and even: a raw
        frame is made of whole 2×2 Bayer cells, so an odd size usually means a crop or a
        mis-sized buffer and raises, unless ``allow_odd=True`` (then the cell is cut at the
        bottom/right edge). NaN/inf are rejected.
    pattern : str
        Bayer pattern of the top-left 2×2 cell: ``"RGGB"`` (default), ``"BGGR"``,
        ``"GRBG"``, ``"GBRG"``.
    method : str
        One of :data:`DEMOSAIC_METHODS`; default ``"menon"``.
    clip : bool
        Clip the result to [0, 1]. Off by default: the interpolating filters of Malvar,
        Hamilton-Adams and Menon overshoot slightly at sharp edges (no silent clipping).
    allow_odd : bool
        Accept odd heights/widths (see ``raw``).
    keep_dtype : bool
        8-bit in, 8-bit out: a uint8/uint16 NumPy mosaic gives uint8/uint16 RGB (``method``
        ``"bilinear"`` only), computed in integers: each interpolated value is the exact
        mean of its 2 or 4 neighbours rounded half up, ``(a + b + 1) >> 1``,
        ``(a + b + c + d + 2) >> 2`` (as OpenCV's ``COLOR_Bayer*2RGB``, whose ``BayerBG``
        is imageform's ``"RGGB"``), so it is within half a code of the float result times
        255 (65535; plus the float32 rounding of the float path, < 0.01 code), and within
        one code of it rounded (they differ only at ties). Float input keeps
        its dtype anyway.

    Returns
    -------
    array, shape (..., H, W, 3)
        RGB, float32 for integer and float32 input, float64 for float64 input; same
        array namespace and device as ``raw``. NumPy runs numba kernels. Other Array-API
        arrays (PyTorch CPU/CUDA, CuPy ...) run ``"bilinear"`` and ``"malvar"`` in their own
        namespace, on their device (differentiable in PyTorch), equal to the NumPy path;
        the other methods are computed on the host through NumPy and moved back (not
        differentiable). CUDA arrays that record no gradient run ``"bilinear"`` and
        ``"malvar"`` as one CUDA kernel (:mod:`imageform._cuda.demosaic`; the mirror and the
        clipping fused, the same filters). A Dask mosaic gives a lazy Dask array: blocks
        with an even overlap (chunks made even so that every block keeps the CFA phase), each
        demosaiced in memory and trimmed, equal to the in-memory result; values are
        validated when the blocks are computed.

    Raises
    ------
    InvalidInputError
        If ``raw`` is not a single-channel mosaic, is smaller than 2×2, has an odd size
        (without ``allow_odd``), holds NaN/inf, or
        has an integer dtype other than uint8/uint16.
    UnknownOptionError
        If ``pattern`` or ``method`` is unknown (the valid names are listed).

    Notes
    -----
    Borders are reconstructed from a phase-preserving mirror padding (see the module
    docstring), so edge pixels are interpolated by the same filter as interior pixels.
    On the 24 Kodak images (RGGB, CPSNR with a 10-pixel crop) the methods reach
    30.25 (bilinear), 35.79 (malvar), 37.04 (hamilton_adams), 39.31 (menon) and 40.03 dB
    (menon_soft); see ``docs/demosaicing.md`` and ``benchmarks/results``.

    Examples
    --------
    A flat grey mosaic stays flat grey with every method:

    >>> import numpy as np
    >>> rgb = demosaic(np.full((4, 6), 0.25), "RGGB", "menon")
    >>> rgb.shape, float(rgb[2, 3, 0]), rgb.dtype.name
    ((4, 6, 3), 0.25, 'float64')
    """
    pattern = cfa_pattern(pattern)
    method = check_option(method, DEMOSAIC_METHODS, "demosaicing method")
    clip = as_bool(clip, "clip")
    allow_odd = as_bool(allow_odd, "allow_odd")
    if as_bool(keep_dtype, "keep_dtype") and getattr(raw, "dtype", None) in (np.uint8, np.uint16):
        return _demosaic_int(raw, pattern, method, allow_odd)
    xp = namespace(raw)
    if is_dask_namespace(xp):
        return _demosaic_dask(raw, pattern, method, clip, allow_odd)
    arr = _as_raw(raw, xp)
    shape = tuple(arr.shape)
    h, w = int(shape[-2]), int(shape[-1])
    if h < 2 or w < 2:
        raise InvalidInputError(
            f"expected a raw mosaic of at least 2x2 pixels (one full Bayer cell), "
            f"got {format_shape(shape)}"
        )
    if (h % 2 or w % 2) and not allow_odd:
        raise InvalidInputError(
            f"expected a raw mosaic of whole 2x2 Bayer cells (even height and width), got "
            f"{format_shape(shape)}; pass allow_odd=True to demosaic a cut cell at the edge"
        )
    if not is_numpy_namespace(xp) and method in XP_METHODS:
        ry, rx = _red_offset(pattern)
        from imageform._cuda import geometry as cuda_geometry

        if min(h, w) >= 4 and cuda_geometry.on_cuda(arr):
            # one CUDA kernel, the mirror and the clipping fused (imageform._cuda.demosaic)
            from imageform._cuda.demosaic import demosaic as demosaic_cuda

            out = demosaic_cuda(xp.reshape(arr, (-1, h, w)), ry, rx, method, clip)
            if out is not None:  # None: the kernels are unusable here
                return xp.reshape(out, (*shape[:-2], h, w, 3))
        out = demosaic_xp(arr, ry, rx, method, xp)
        return xp.clip(out, 0.0, 1.0) if clip else out
    # the RGB result, the padded mosaic and the kernels' planes: about 8 float64 mosaics
    n_bytes = 8.0 * 8.0 * math.prod(shape)
    check_memory(n_bytes, "raw", f"demosaicing a mosaic of shape {format_shape(shape)}")
    a = to_numpy(arr)
    numba = use_numba(a)
    kernel, radius = _kernels(method, numba)
    pad = radius + (radius % 2)  # even: the mirror then keeps the RGGB phase
    ry, rx = _red_offset(pattern)
    flat = a.reshape((-1, h, w))
    results = [
        kernel(
            np.pad(flat[k], ((pad + ry, pad), (pad + rx, pad)), mode="reflect"),
            pad + ry,
            pad + rx,
            h,
            w,
        )
        for k in range(flat.shape[0])
    ]
    res = results[0] if len(results) == 1 else np.stack(results)
    res = res.reshape((*shape[:-2], h, w, 3))
    if clip:
        np.clip(res, 0.0, 1.0, out=res)
    if is_numpy_namespace(xp):
        return res
    dev = device_of(arr)
    return xp.asarray(res) if dev is None else xp.asarray(res, device=dev)


def _demosaic_int(raw: Any, pattern: str, method: str, allow_odd: bool) -> np.ndarray:
    """uint8/uint16 in and out (``keep_dtype=True``): the integer bilinear kernel."""
    if method != "bilinear":
        raise InvalidInputError(
            f"keep_dtype=True on a {raw.dtype} mosaic runs method='bilinear' only, got {method!r}"
        )
    if not isinstance(raw, np.ndarray):
        raise InvalidInputError(
            f"keep_dtype=True on integer mosaics takes NumPy arrays, got {type(raw).__name__}"
        )
    from imageform._kernels import demosaic_bilinear as m

    shape = tuple(raw.shape)
    if raw.ndim >= 3 and shape[-1] == 1:
        raw, shape = raw[..., 0], shape[:-1]
    if raw.ndim < 2 or min(shape[-2:]) < 2:
        raise InvalidInputError(
            f"expected a raw mosaic of shape (H, W) or (..., H, W, 1) of at least 2x2 pixels, "
            f"got {format_shape(tuple(raw.shape))}"
        )
    h, w = shape[-2:]
    if (h % 2 or w % 2) and not allow_odd:
        raise InvalidInputError(
            f"expected a raw mosaic of whole 2x2 Bayer cells (even height and width), got "
            f"{format_shape(shape)}; pass allow_odd=True to demosaic a cut cell at the edge"
        )
    ry, rx = _red_offset(pattern)
    flat = np.ascontiguousarray(raw).reshape((-1, h, w))
    res = np.empty((flat.shape[0], h, w, 3), raw.dtype)
    numba = use_numba(flat)
    for k in range(flat.shape[0]):
        if numba:
            m.bilinear_int_numba(flat[k], ry, rx, res[k])
        else:
            res[k] = m.bilinear_int_numpy(flat[k], ry, rx)
    return res.reshape((*shape[:-2], h, w, 3))


def _demosaic_dask(raw: Any, pattern: str, method: str, clip: bool, allow_odd: bool) -> Any:
    """Lazy demosaicing of a Dask mosaic (shape checks now, values per block)."""
    shape = tuple(int(n) for n in raw.shape)
    if len(shape) >= 3 and shape[-1] == 1:
        raw = raw[..., 0]
        shape = shape[:-1]
    elif len(shape) != 2:
        _as_raw(np.zeros(shape[-3:] if len(shape) >= 3 else shape), namespace())  # raises
    if raw.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        raise InvalidInputError(
            f"expected a uint8, uint16, float32 or float64 raw mosaic, got dtype {raw.dtype}"
        )
    h, w = shape[-2:]
    if h < 2 or w < 2 or ((h % 2 or w % 2) and not allow_odd):
        demosaic(np.zeros((h, w)), pattern, method, allow_odd=allow_odd)  # raises the message
    _, radius = _kernels(method, False)
    depth = radius + (radius % 2)
    out_dtype = np.float64 if raw.dtype == np.float64 else np.float32

    def block(b: np.ndarray) -> np.ndarray:
        x = b[..., None] if b.ndim > 2 else b  # a batch of mosaics takes a trailing axis
        return np.asarray(demosaic(x, pattern, method, clip=clip, allow_odd=allow_odd))

    return demosaic_dask(raw, depth, block, out_dtype)
