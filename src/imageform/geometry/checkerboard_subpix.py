"""Sub-pixel corner refinement (OpenCV's ``cornerSubPix``) and the grey conversion.

Part of :mod:`imageform.geometry.checkerboard`; :func:`refine_corners` is public there.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform import _deprecate
from imageform._backend import to_numpy, use_numba
from imageform._colormath import luma_601_matmul
from imageform._typing import ArrayLike
from imageform._validate import (
    as_image,
    as_int,
    as_points_bounded,
    as_real,
    check_bounded,
    check_min_side,
    format_shape,
    size_pair,
)
from imageform.errors import InvalidInputError

__all__ = [
    "RefinedCorners",
    "as_gray",
    "block_mean",
    "gray_codes",
    "gray_from_codes",
    "grid_maps",
    "refine",
    "refine_corners",
    "refine_corners_symmetric",
    "refine_local_inside",
    "refine_symmetric",
    "refine_symmetric_inside",
    "refine_symmetric_pyramid",
    "room_to_border",
]

#: The largest refinement half-window (pixels): a (2h+1)^2 window per corner.
MAX_HALF_WINDOW = 1000


class RefinedCorners(NamedTuple):
    """Result of :func:`refine_corners`."""

    #: Refined positions (N, 2), float64.
    corners: NDArray[np.float64]
    #: Per corner (N,) int64: 0 converged, 1 ``max_iter`` reached, 2 flat window (singular),
    #: 3 left the image, 4 moved farther than the half window (start kept).
    status: NDArray[np.int64]


def as_gray(image: ArrayLike) -> NDArray[np.floating]:
    """Make a grey NumPy image (H, W): float32 for integer/float32 input, float64 for float64."""
    arr = as_image(image, "image", channels=None, range_check=False)
    # float32 (integer and float32 input) or float64 (float64 input): docs/conventions.md
    arr = np.asarray(to_numpy(arr))
    if arr.ndim == 3 and arr.shape[-1] == 1:
        arr = arr[..., 0]
    elif arr.ndim == 3 and arr.shape[-1] == 3:
        arr = luma_601_matmul(np, arr, arr.dtype)  # Rec. 601 luma (as OpenCV's cvtColor)
    elif arr.ndim != 2:
        raise InvalidInputError(
            "expected image of shape (H, W), (H, W, 1) or (H, W, 3), "
            f"got {format_shape(tuple(arr.shape))}"
        )
    # values beyond 1e30 overflow float32 and the squared gradients: no image holds them
    check_bounded(arr, "image", np, limit=1e30)
    check_min_side(arr.shape, 16)
    return arr


_SCALE = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}


def gray_codes(image: ArrayLike) -> tuple[NDArray[np.number], float, float]:
    """Return the grey image as stored, its scale and its span: ``(codes, scale, max - min)``.

    ``codes / scale`` is :func:`as_gray` (see :func:`gray_from_codes`) and the span is 0
    for a constant image. A NumPy ``uint8``/``uint16`` grey image (a camera frame) is
    returned as it is, with scale 255 or 65535 and its span from the integers (which need
    no finiteness check), so that no float copy of it is made unless needed; any other
    image goes through :func:`as_gray` (scale 1).
    """
    if (
        isinstance(image, np.ndarray)
        and image.dtype in _SCALE
        and (image.ndim == 2 or (image.ndim == 3 and image.shape[-1] == 1))
        and min(image.shape[:2]) >= 16
    ):
        raw = image[..., 0] if image.ndim == 3 else image
        scale = _SCALE[image.dtype]
        return raw, scale, float(int(raw.max()) - int(raw.min())) / scale
    gray = as_gray(image)
    return gray, 1.0, float(gray.max() - gray.min())


def gray_from_codes(codes: NDArray[np.number], scale: float) -> NDArray[np.floating]:
    """Return :func:`as_gray`'s image from :func:`gray_codes`' ``(codes, scale)``.

    The codes as they are for scale 1, else ``codes.astype(float32) / scale`` (bit for bit, in one
    pass).
    """
    if scale == 1.0:
        return codes  # type: ignore[return-value]
    gray = np.empty(codes.shape, dtype=np.float32)
    np.divide(codes, np.float32(scale), out=gray, dtype=np.float32)
    return gray


def _gray_and_corners(
    image: npt.ArrayLike, corners: npt.ArrayLike
) -> tuple[NDArray[np.floating], NDArray[np.float64]]:
    """Return the grey image and the (N, 2) float64 starts of a refinement, checked."""
    gray = as_gray(image)
    pts = np.asarray(
        to_numpy(as_points_bounded(corners, "corners", 2, dtype=None)), dtype=np.float64
    )
    if pts.ndim != 2:
        raise InvalidInputError(
            f"expected corners of shape (N, 2), got {format_shape(tuple(pts.shape))}"
        )
    return gray, pts


@_deprecate.parameters(renamed={"eps": "tol"})
def refine_corners(
    image: npt.ArrayLike,
    corners: npt.ArrayLike,
    *,
    half_window: int | tuple[int, int] = 11,
    max_iter: int = 30,
    tol: float = 1e-3,
) -> RefinedCorners:
    r"""Sub-pixel corner positions by gradient orthogonality (OpenCV's ``cornerSubPix``).

    Each corner ``q`` is moved to the point to which the image gradients ``g_p`` in a
    window around it are orthogonal, iterating on a bilinearly resampled window:

    .. math::

        q' = \Big(\sum_p w_p\, g_p g_p^\top\Big)^{-1} \sum_p w_p\, g_p g_p^\top\, p,
        \qquad w_p = e^{-(x_p/h_x)^2} e^{-(y_p/h_y)^2}

    with central-difference gradients, window offsets ``x_p ∈ [-h_x, h_x]``; it stops after
    ``max_iter`` iterations or when a step is ``<= tol`` pixels. A corner that ends more than
    the half window away from its start keeps its start (status 4), as in OpenCV.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, 3)
        Grey or RGB image (uint8, uint16 or floats of any scale).
    corners : array_like (N, 2)
        Starting positions ``(u, v)``, centre of the top-left pixel = (0, 0).
    half_window : int or (int, int)
        ``h`` or ``(h_x, h_y)``: the window is ``(2 h_y + 1) x (2 h_x + 1)`` pixels; OpenCV's
        ``winSize``. Must be smaller than half the square size of the board.
    max_iter : int
        Most iterations per corner.
    tol : float
        Stop when a step is at most ``tol`` pixels (``eps`` is its deprecated name); with
        ``max_iter``, OpenCV's ``TermCriteria(EPS + COUNT, max_iter, tol)``.

    Returns
    -------
    RefinedCorners
        ``corners`` : ndarray (N, 2) float64, the refined positions; ``status`` : ndarray
        (N,) int64, 0 converged, 1 ``max_iter`` reached, 2 flat window (singular), 3 left
        the image, 4 moved farther than the half window (start kept).

    Notes
    -----
    Förstner & Gülch (1987), "A fast operator for detection and precise location of distinct
    points, corners and centres of circular features"; the iteration, window weights and
    stopping rule of OpenCV's ``cornerSubPix`` (agrees with OpenCV 5.0 to 1e-4 px on its
    ``left*.jpg`` views, tested).

    Examples
    --------
    An ideal corner at (20.3, 19.6), rendered with exact pixel coverage and a lens blur
    (on a perfectly sharp corner the method, like OpenCV's, is biased by up to ~0.07 px):

    >>> import numpy as np
    >>> from scipy.ndimage import gaussian_filter
    >>> v, u = np.mgrid[0:40, 0:40] * 1.0
    >>> a = np.clip(u - 20.3 + 0.5, 0, 1)  # fraction of each pixel right of u = 20.3
    >>> b = np.clip(v - 19.6 + 0.5, 0, 1)  # ... below v = 19.6
    >>> img = gaussian_filter(a * b + (1 - a) * (1 - b), 1.5)
    >>> xy, status = refine_corners(img, [[19.0, 21.0]], half_window=5)
    >>> np.round(xy, 1), status
    (array([[20.3, 19.6]]), array([0]))
    """
    gray, pts = _gray_and_corners(image, corners)
    if isinstance(half_window, int | np.integer) and not isinstance(half_window, bool):
        hx = hy = as_int(half_window, "half_window", minimum=1, maximum=MAX_HALF_WINDOW)
    else:
        hx, hy = size_pair(half_window, "half_window")
        if max(hx, hy) > MAX_HALF_WINDOW:
            raise InvalidInputError(f"expected half_window <= {MAX_HALF_WINDOW}, got {(hx, hy)}")
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", nonnegative=True)
    return RefinedCorners(*refine(gray, pts, int(hx), int(hy), max_iter, float(tol)))


@_deprecate.parameters(renamed={"eps": "tol"})
def refine(
    gray: NDArray[np.floating],
    pts: NDArray[np.float64],
    hx: int,
    hy: int,
    max_iter: int,
    tol: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`refine_corners` on clean input (kernel or twin by :func:`use_numba`).

    ``tol`` (pixels; ``eps`` is its deprecated name) and ``max_iter`` are the stopping rule.
    """
    if pts.shape[0] == 0:
        return pts.copy(), np.zeros(0, dtype=np.int64)
    from imageform._kernels.checkerboard import refine_corners_numba, refine_corners_numpy

    kernel = refine_corners_numba if use_numba(gray) else refine_corners_numpy
    return kernel(np.ascontiguousarray(gray), np.ascontiguousarray(pts), hx, hy, max_iter, tol)


def refine_corners_symmetric(
    image: npt.ArrayLike,
    corners: npt.ArrayLike,
    *,
    half_window: int = 8,
    max_iter: int = 30,
    tol: float = 1e-3,
) -> RefinedCorners:
    r"""Sub-pixel checkerboard corners as centres of point symmetry (Schöps et al. 2020).

    A checkerboard corner ``q`` is the centre of a point symmetry of the board around it,
    ``I(q + d) = I(q - d)``, and stays one through any affine map (a view's local perspective)
    and any point-symmetric blur. Each corner is moved, by Gauss-Newton steps (at most one
    pixel each) on bilinear samples, to the minimum over ``q`` and a shading slope ``s`` of

    .. math::

        \sum_{|d| \le h} w(d)\, \big(I(q + d) - I(q - d) - 2\, s \cdot d\big)^2,
        \qquad w(d) = e^{-|d|^2 / (2 (h/2)^2)}

    over the integer offsets ``d`` of a round window of radius ``h`` (``half_window``). Unlike
    :func:`refine_corners` the window may take in the neighbouring corners (the whole board is
    point-symmetric about each of its corners under an affine map): larger windows average
    more pixels; lens distortion and strong perspective bound them (``find_checkerboard``
    uses 0.8 of the grid step). A window past the image's border reads replicated edge
    pixels, which are not point-symmetric (``find_checkerboard`` keeps such corners at
    :func:`refine_corners`' position). A corner of another pattern (an ``L``, a ``T``, a
    ChArUco corner beside its markers' bits) is not point-symmetric: use
    :func:`refine_corners` there (:func:`~imageform.geometry.detect_charuco` masks the
    markers out of the window).

    Parameters
    ----------
    image : array_like (H, W) or (H, W, 3)
        Grey or RGB image (uint8, uint16 or floats of any scale).
    corners : array_like (N, 2)
        Starting positions ``(u, v)`` (center of the top-left pixel = (0, 0)), within about
        ``h / 2`` of the corners.
    half_window : int
        Radius ``h`` of the round window (pixels), 2 to 1000.
    max_iter : int
        Most Gauss-Newton steps per corner.
    tol : float
        Stop when a step is at most ``tol`` pixels.

    Returns
    -------
    RefinedCorners
        ``corners`` : ndarray (N, 2) float64; ``status`` : ndarray (N,) int64, 0 converged,
        1 ``max_iter`` reached, 2 singular (a flat window or a straight edge: start kept),
        3 left the image, 4 moved farther than ``h`` (start kept).

    Notes
    -----
    Schöps, Larsson, Pollefeys & Sattler (2020), "Why having 10,000 parameters in your camera
    model is better than twelve", CVPR, sec. 4 (the symmetry cost; their local homography is
    left out, the shading slope added). On real calibration photographs the corners fit a
    camera model better than :func:`refine_corners`' and OpenCV's
    ``findChessboardCornersSB``'s (benchmarks/results/corner-refinement-2026-11-29i.md).

    Examples
    --------
    A blurred corner at (20.3, 19.6) of a sheared board, with a brightness gradient:

    >>> import numpy as np
    >>> from scipy.special import erf
    >>> v, u = np.mgrid[0:40, 0:40] * 1.0
    >>> x, y = u - 20.3 + 0.4 * (v - 19.6), v - 19.6  # the board's axes through the corner
    >>> img = 0.5 + 0.4 * erf(x / 2) * erf(y / 2) + 0.01 * u
    >>> xy, status = refine_corners_symmetric(img, [[19.0, 21.0]], half_window=6)
    >>> np.round(xy, 1), status
    (array([[20.3, 19.6]]), array([0]))
    """
    gray, pts = _gray_and_corners(image, corners)
    h = as_int(half_window, "half_window", minimum=2, maximum=MAX_HALF_WINDOW)
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    tol = as_real(tol, "tol", nonnegative=True)
    return RefinedCorners(*refine_symmetric(gray, pts, int(h), max_iter, float(tol)))


def room_to_border(points: NDArray[np.float64], h: int, w: int) -> NDArray[np.float64]:
    """Return each point's distance (px) to the nearest border of an ``h x w`` image.

    Pixel centres run from 0 to ``w - 1`` and ``h - 1``; ``points`` is ``(..., 2)`` as
    ``(u, v)``.
    """
    return np.minimum(
        np.minimum(points[..., 0], w - 1 - points[..., 0]),
        np.minimum(points[..., 1], h - 1 - points[..., 1]),
    )


def refine_symmetric_inside(
    gray: NDArray[np.floating],
    start: NDArray[np.float64],
    anchor: NDArray[np.float64],
    h: int,
    max_iter: int,
    tol: float,
    reach: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.intp]]:
    """:func:`refine_symmetric` of ``start`` where it can be trusted; elsewhere ``start`` kept.

    A corner whose window (radius ``h``) would reach past the image's border (replicated edge
    pixels are not the board's symmetry), whose step is singular or lost (status 2 or more),
    or that lands more than ``reach`` pixels from its ``anchor`` (a square's centre is a
    centre of symmetry too) keeps ``start``. Returns the corners, the symmetric step's status
    of each corner (0 where it was not run) and the indices of the corners it moved.
    """
    idx = np.flatnonzero(room_to_border(start, *gray.shape) >= h + 1)
    sym, sym_status = refine_symmetric(gray, np.ascontiguousarray(start[idx]), h, max_iter, tol)
    kept = (sym_status <= 1) & (np.hypot(*(sym - anchor[idx]).T) <= reach)
    out = start.copy()
    out[idx[kept]] = sym[kept]
    status = np.zeros(start.shape[0], dtype=np.int64)
    status[idx] = sym_status
    return out, status, idx[kept]


def refine_symmetric(
    gray: NDArray[np.floating],
    pts: NDArray[np.float64],
    h: int,
    max_iter: int,
    tol: float,
    mask: NDArray[np.bool_] | None = None,
    half: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`refine_corners_symmetric` on clean input (kernel or twin by :func:`use_numba`).

    ``mask`` (N, 2h+1, 2h+1), optional: per corner, the window's offsets ``d`` to use (a pair
    ``(q + d, q - d)`` is left out when either offset is masked off). ``half``: the kernel
    sums each pair once (the same steps but for the rounding, faster).
    """
    if pts.shape[0] == 0:
        return pts.copy(), np.zeros(0, dtype=np.int64)
    from imageform._kernels.checkerboard_symmetric import (
        refine_symmetric_numba,
        refine_symmetric_numpy,
    )

    kernel = refine_symmetric_numba if use_numba(gray) else refine_symmetric_numpy
    g, p = np.ascontiguousarray(gray), np.ascontiguousarray(pts)
    return kernel(g, p, h, max_iter, tol, mask, half)


def _lagrange_powers(nodes: int, at: int) -> NDArray[np.float64]:
    """Return the power coefficients (nodes, 3) of the Lagrange basis on unit-spaced nodes.

    ``B[k, a]`` is the coefficient of ``s^a`` in the basis polynomial of node ``k`` of
    ``nodes`` (2 or 3) nodes, the origin at node ``at``.
    """
    z = np.arange(nodes, dtype=np.float64) - at
    out = np.zeros((nodes, 3))
    for k in range(nodes):
        poly = np.array([1.0])
        for j in range(nodes):
            if j != k:
                poly = np.convolve(poly, np.array([1.0, -z[j]]) / (z[k] - z[j]))
        out[k, : poly.size] = poly[::-1]
    return out


@lru_cache(maxsize=64)
def _stencil(n: int) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Return the Lagrange bases (n, m, 3) and node indices (n, m) of a grid side of ``n``.

    Each of the ``n`` corners of a side takes the ``m = min(3, n)`` nearest nodes (the corner
    in the middle but at the ends), its basis from :func:`_lagrange_powers`. The same for
    every board of that side: kept (read-only), computed once per side length.
    """
    m = min(3, n)
    start = np.clip(np.arange(n) - 1, 0, n - m)
    basis = np.stack([_lagrange_powers(m, int(at)) for at in np.arange(n) - start])
    nodes = start[:, None] + np.arange(m)[None]
    basis.flags.writeable = False
    nodes.flags.writeable = False
    return basis, nodes


def grid_maps(grid: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return each corner's local map of the board from its grid neighbours.

    ``grid`` (R, C, 2): the corners, row by row. Per corner, the polynomial of degree at most
    2 in each board coordinate (``s`` along a row, ``t`` along a column, in squares, the corner
    at 0) through the 3 x 3 corners around it (the nearest 3 x 3 block at the board's edge, 2
    nodes along a side of 2 corners), less the corner: ``coef`` (R*C, 3, 3, 2) with
    ``coef[k, a, b]`` the pixel offset's coefficient of ``s^a t^b``, and the inverse of its
    linear part ``linv`` (R*C, 2, 2) (NaN where singular).
    """
    rows, cols, _ = grid.shape
    br, ri = _stencil(rows)  # (R, nr, 3), (R, nr)
    bc, ci = _stencil(cols)  # (C, nc, 3), (C, nc)
    sten = grid[ri[:, None, :, None], ci[None, :, None, :]]  # (R, C, nr, nc, 2)
    sten = sten - grid[:, :, None, None, :]
    # coef[r, c, a, b] = sum_{l, k} bc[c, k, a] br[r, l, b] sten[r, c, l, k]
    coef = np.einsum("cka,rlb,rclkx->rcabx", bc, br, sten).reshape(-1, 3, 3, 2)
    coef[:, 0, 0] = 0.0
    lin = np.stack([coef[:, 1, 0], coef[:, 0, 1]], -1)  # (N, 2, 2): columns dF/ds, dF/dt
    det = lin[:, 0, 0] * lin[:, 1, 1] - lin[:, 0, 1] * lin[:, 1, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        linv = (
            np.stack(
                [
                    np.stack([lin[:, 1, 1], -lin[:, 0, 1]], -1),
                    np.stack([-lin[:, 1, 0], lin[:, 0, 0]], -1),
                ],
                1,
            )
            / np.where(det != 0, det, np.nan)[:, None, None]
        )
    return linv, coef


def refine_local_inside(
    gray: NDArray[np.floating],
    start: NDArray[np.float64],
    anchor: NDArray[np.float64],
    grid: NDArray[np.float64],
    h: int,
    max_iter: int,
    tol: float,
    reach: float,
    min_bend: float = 0.0,
    extent: float = np.inf,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.intp]]:
    """:func:`refine_symmetric_inside` with each window taken through its corner's grid map.

    ``grid`` (R, C, 2) gives the maps (:func:`grid_maps`; ``start`` is its corners, row by
    row). A map's bend ``b`` is the largest offset of its non-linear part on the window's rim
    (radius ``h + 1/2``); that part is scaled by ``1 - min_bend / b`` (a soft threshold: a map
    bent by less than ``min_bend`` pixels is not used, one bent by more is used less its
    first ``min_bend`` pixels, so that a corner's refinement changes continuously with the
    bend). Only the corners bent by more than ``min_bend`` are refined; they and the others
    keep ``start`` where the map is singular, where the window through the map would reach
    past the image's border, where the step is singular or lost or lands farther than
    ``reach`` from ``anchor``. Offsets whose board coordinates pass ``extent`` squares are
    left out of the window. Returns the corners, the step's status of each corner (0 where
    it was not run) and the indices of the corners it moved.
    """
    from imageform._kernels.checkerboard_local import refine_local_numba, refine_local_numpy

    idx, linv, coef = _local_selection(gray.shape, start, grid, h, min_bend)
    out = start.copy()
    status = np.zeros(start.shape[0], dtype=np.int64)
    if idx.size == 0:
        return out, status, idx
    kernel = refine_local_numba if use_numba(gray) else refine_local_numpy
    sym, sym_status = kernel(
        np.ascontiguousarray(gray),
        np.ascontiguousarray(start[idx]),
        np.ascontiguousarray(linv[idx]),
        np.ascontiguousarray(coef[idx]),
        h,
        max_iter,
        tol,
        extent,
    )
    kept = (sym_status <= 1) & (np.hypot(*(sym - anchor[idx]).T) <= reach)
    out[idx[kept]] = sym[kept]
    status[idx] = sym_status
    return out, status, idx[kept]


def _local_selection(
    shape: tuple[int, ...],
    start: NDArray[np.float64],
    grid: NDArray[np.float64],
    h: int,
    min_bend: float,
) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]]:
    """:func:`refine_local_inside`'s corners to refine and every corner's map, bend scaled.

    Returns the indices of the corners bent by more than ``min_bend`` whose window through
    the map stays inside an image of ``shape`` (H, W), and the maps' ``linv`` (N, 2, 2; 0
    where singular) and ``coef`` (N, 3, 3, 2; the non-linear part scaled by the soft
    threshold).
    """
    linv, coef = grid_maps(grid)
    ok = np.all(np.isfinite(linv.reshape(-1, 4)), axis=1)
    linv = np.where(ok[:, None, None], linv, 0.0)
    ang = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)
    d = (h + 0.5) * np.stack([np.cos(ang), np.sin(ang)], -1)  # (32, 2): both signs of d
    x = np.einsum("kij,aj->kai", linv, d)  # (N, 32, 2) on the board
    bend = np.zeros(x.shape)
    for a in range(3):
        for b in range(3):
            if a + b >= 2:
                bend += coef[:, None, a, b, :] * (x[..., 0:1] ** a * x[..., 1:2] ** b)
    size = np.linalg.norm(bend, axis=-1).max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(ok & (size > min_bend), 1.0 - min_bend / size, 0.0)
    coef = coef.copy()
    for a in range(3):
        for b in range(3):
            if a + b >= 2:
                coef[:, a, b] *= scale[:, None]
    # the window's reach through the map: its radius and the bend left (the polynomial
    # bulges little inside a window of less than a square)
    room = room_to_border(start, shape[0], shape[1])
    idx = np.flatnonzero((scale > 0) & (room >= h + 1.0 + size * scale))
    return idx, linv, coef


def block_mean(
    gray: NDArray[np.floating],
    factor: int,
    region: tuple[int, int, int, int] | None = None,
) -> NDArray[np.floating]:
    """Return the means of ``factor x factor`` blocks of ``gray`` (a last partial block dropped).

    ``region`` ``(y0, y1, x0, x1)``, optional: the blocks of ``gray[y0:y1, x0:x1]``, read in
    place (a slice would be copied to be contiguous for the kernel). Pixel ``(i, j)`` of the
    result is centred on ``(x0 + factor j + (factor - 1) / 2, y0 + factor i + (factor - 1) /
    2)`` of ``gray``; float32 stays float32 (summed in float32), other dtypes give float64.
    """
    from imageform._kernels.checkerboard_pyramid import block_mean_numba, block_mean_numpy

    y0, y1, x0, x1 = (0, gray.shape[0], 0, gray.shape[1]) if region is None else region
    kernel = block_mean_numba if use_numba(gray) else block_mean_numpy
    return kernel(gray, factor, y0, y1, x0, x1)


def refine_symmetric_pyramid(
    gray: NDArray[np.floating],
    start: NDArray[np.float64],
    anchor: NDArray[np.float64],
    shape: tuple[int, int],
    h: int,
    max_iter: int,
    tol: float,
    reach: float,
    min_bend: float,
    extent: float,
    factor: int,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.intp]]:
    r""":func:`refine_symmetric_inside` then :func:`refine_local_inside`, coarse to fine.

    For a large window (radius ``h`` of 40 px and more: squares of 50 px and more) both
    refinements are run on the ``factor x factor`` block means of the board's part of
    ``gray`` (windows of radius ``h / factor``, ``factor²`` times fewer samples), and one
    Gauss-Newton step of :func:`refine_symmetric` at full resolution (radius ``h``) takes
    each corner from the coarse symmetric position ``q_c`` to ``q_f``; a corner refined
    through its grid map gets the shift its map gave on the block means,

    .. math::

        q = q_f + (q_{c,\mathrm{map}} - q_c),

    the corner selection (room to the border, bend, reach from ``anchor``) being that of the
    two full-resolution steps. The full-resolution step brings the symmetric corner to
    within about 0.01 px of its converged position (OpenCV's 13 views upscaled to 1920 x
    1440: largest difference to the two full-resolution refinements 0.016 px with factor
    2), at a quarter of their cost. ``shape`` is the grid's (R, C); returns as
    :func:`refine_symmetric_inside` (the status is the coarse steps').
    """
    height, width = gray.shape
    f = factor
    out = start.copy()
    status = np.zeros(start.shape[0], dtype=np.int64)
    idx = np.flatnonzero(room_to_border(start, height, width) >= h + 1)
    if idx.size == 0:
        return out, status, idx
    # the block means of the board's part: every window, through its map too, with room
    pad = 2.0 * h + reach + 2.0 * f
    x0 = max(0, int(np.floor(start[idx, 0].min() - pad)))
    y0 = max(0, int(np.floor(start[idx, 1].min() - pad)))
    x1 = min(width, int(np.ceil(start[idx, 0].max() + pad)) + 1)
    y1 = min(height, int(np.ceil(start[idx, 1].max() + pad)) + 1)
    small = block_mean(gray, f, (y0, y1, x0, x1))
    off = np.array([x0 + 0.5 * (f - 1), y0 + 0.5 * (f - 1)])
    hc = max(2, round(h / f))
    coarse, c_status = refine_symmetric(
        small, (start[idx] - off) / f, hc, max_iter, tol / f, half=True
    )
    coarse = coarse * f + off
    ok = (c_status <= 1) & (np.hypot(*(coarse - anchor[idx]).T) <= reach)
    sel = idx[ok]
    base = start.copy()
    base[sel] = coarse[ok]
    status[idx] = c_status
    if sel.size:
        fine, f_status = refine_symmetric(
            gray, np.ascontiguousarray(base[sel]), h, 1, tol, half=True
        )
        good = (f_status <= 1) & (np.hypot(*(fine - anchor[sel]).T) <= reach)
        out[sel] = np.where(good[:, None], fine, base[sel])
    lidx, linv, coef = _local_selection((height, width), out, out.reshape(*shape, 2), h, min_bend)
    if lidx.size == 0:
        return out, status, sel
    from imageform._kernels.checkerboard_local import refine_local_numba, refine_local_numpy

    kernel = refine_local_numba if use_numba(small) else refine_local_numpy
    local, l_status = kernel(
        np.ascontiguousarray(small),
        np.ascontiguousarray((base[lidx] - off) / f),
        np.ascontiguousarray(linv[lidx] * f),
        np.ascontiguousarray(coef[lidx] / f),
        hc,
        max_iter,
        tol / f,
        extent,
    )
    moved = out[lidx] + (local * f + off - base[lidx])
    kept = (l_status <= 1) & (np.hypot(*(moved - anchor[lidx]).T) <= reach)
    out[lidx[kept]] = moved[kept]
    status[lidx] = l_status
    return out, status, np.union1d(sel, lidx[kept])
