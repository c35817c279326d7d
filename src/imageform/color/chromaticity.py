r"""Chromaticity coordinates xy and u'v', the spectral locus and the visible region.

.. math:: x = \frac{X}{X+Y+Z},\ y = \frac{Y}{X+Y+Z};\qquad
          u' = \frac{4x}{-2x + 12y + 3},\ v' = \frac{9y}{-2x + 12y + 3}

(CIE 015:2018 eqs. 7.4 and 8.1-8.2). The spectral locus is the chromaticity of monochromatic
stimuli from the colour-matching functions; closed by the purple line it bounds the region of
all physically realisable chromaticities.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, NamedTuple

import array_api_compat
import numpy as np
import numpy.typing as npt

from imageform import _deprecate
from imageform._backend import device_of, namespace, reads_values, to_numpy
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_bool,
    as_points_strict,
    as_real,
    as_real_ndarray,
    check_name,
    describe,
)
from imageform.errors import InvalidInputError

__all__ = [
    "CHROMATICITY_COORDS",
    "SpectralLocus",
    "check_in_locus",
    "in_locus",
    "polygon_area",
    "spectral_locus",
    "uv_prime_to_xy",
    "visible_area",
    "xy_to_uv_prime",
    "xy_to_xyz",
    "xyz_to_uv_prime",
    "xyz_to_xy",
]

#: Chromaticity diagrams: CIE 1931 ``"xy"`` and CIE 1976 UCS ``"uv"`` (u', v').
CHROMATICITY_COORDS = ("xy", "uv")
#: Default locus range: 380-780 nm (beyond, the 1 nm CMF chromaticities wander by < 1e-3 in
#: the red corner and the violet end hardly moves; CIE 015:2018 §7.2 integrates 360-830 nm).
LOCUS_RANGE = (380.0, 780.0)


@chunkwise(1)
def xyz_to_xy(xyz: ArrayLike, white: str | ArrayLike = "D65") -> Array:
    """Chromaticity ``(x, y)`` of XYZ, shape (..., 3) -> (..., 2).

    Black (X + Y + Z = 0) has no chromaticity; it gets the white's, as
    :func:`imageform.color.xyz_to_xyy` does (CIE 015:2018 eq. 7.4).

    Examples
    --------
    >>> [round(float(v), 4) for v in xyz_to_xy([0.95047, 1.0, 1.08883])]
    [0.3127, 0.329]
    """
    from imageform.color.cielab import xyz_to_xyy

    return xyz_to_xyy(xyz, white)[..., :2]


@chunkwise(1)
def xy_to_uv_prime(xy: ArrayLike) -> Array:
    r"""CIE 1976 UCS :math:`(u', v')` from :math:`(x, y)`, shape (..., 2).

    .. math:: u' = \frac{4x}{-2x + 12y + 3},\quad v' = \frac{9y}{-2x + 12y + 3}

    Source: CIE 015:2018 eqs. 8.1-8.2.

    Examples
    --------
    >>> [round(float(v), 4) for v in xy_to_uv_prime([0.3127, 0.3290])]
    [0.1978, 0.4683]
    """
    p = as_points_strict(xy, "xy", 2)
    xp = namespace(p)
    x, y = p[..., 0], p[..., 1]
    d = -2.0 * x + 12.0 * y + 3.0
    return xp.stack([4.0 * x / d, 9.0 * y / d], axis=-1)


@chunkwise(1)
def uv_prime_to_xy(uv: ArrayLike) -> Array:
    r"""Invert :func:`xy_to_uv_prime` (CIE 015:2018 eq. 8.3).

    :math:`x = 9u'/(6u' - 16v' + 12)`, :math:`y = 4v'/(6u' - 16v' + 12)`.

    Examples
    --------
    >>> [round(float(v), 4) for v in uv_prime_to_xy([0.19783, 0.46832])]
    [0.3127, 0.329]
    """
    p = as_points_strict(uv, "uv", 2)
    xp = namespace(p)
    u, v = p[..., 0], p[..., 1]
    d = 6.0 * u - 16.0 * v + 12.0
    return xp.stack([9.0 * u / d, 4.0 * v / d], axis=-1)


@chunkwise(1)
def xyz_to_uv_prime(xyz: ArrayLike, white: str | ArrayLike = "D65") -> Array:
    """:math:`(u', v')` of XYZ, shape (..., 3) -> (..., 2) (black gets the white's).

    Examples
    --------
    >>> [round(float(v), 4) for v in xyz_to_uv_prime([0.95047, 1.0, 1.08883])]
    [0.1978, 0.4683]
    """
    return xy_to_uv_prime(xyz_to_xy(xyz, white))


@lru_cache(maxsize=16)
def _locus(observer: str, coords: str, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    from imageform.spectral.data import cmfs

    c = cmfs(int(observer)).trim(lo, hi)
    xyz = c.values
    xy = xyz[:, :2] / xyz.sum(axis=1, keepdims=True)
    pts = xy if coords == "xy" else np.asarray(xy_to_uv_prime(xy))
    wl, pts = c.wavelengths.copy(), np.asarray(pts, dtype=np.float64)
    wl.setflags(write=False)
    pts.setflags(write=False)
    return wl, pts


class SpectralLocus(NamedTuple):
    """The result of :func:`spectral_locus` (read-only arrays)."""

    #: Wavelengths, shape (N,), nm.
    wavelengths: np.ndarray
    #: Chromaticities (x, y) or (u', v'), shape (N, 2).
    chromaticities: np.ndarray


@_deprecate.parameters(positional=("observer", "coords", "wavelength_range"))
def spectral_locus(
    *,
    observer: int = 2,
    coords: str = "xy",
    wavelength_range: tuple[float, float] = LOCUS_RANGE,
) -> SpectralLocus:
    r"""Wavelengths (N,) and chromaticities (N, 2) of the spectral locus at 1 nm.

    From the CIE colour-matching functions (CIE 015:2018 Tables 4-5):
    :math:`x(\lambda) = \bar x/(\bar x + \bar y + \bar z)`. Every parameter is
    keyword-only: ``observer`` (2 or 10), ``coords`` (``"xy"`` or ``"uv"``) and the
    ``wavelength_range`` (nm).

    Examples
    --------
    >>> wl, xy = spectral_locus()
    >>> [round(float(v), 4) for v in xy[wl == 520][0]]
    [0.0743, 0.8338]
    """
    c = check_name(coords, CHROMATICITY_COORDS, "chromaticity diagram", "coords")
    o = check_name(str(observer), ("2", "10"), "observer")
    rng = as_real_ndarray(wavelength_range, "wavelength_range")
    if rng.shape != (2,):
        raise InvalidInputError(
            f"expected wavelength_range as (lo, hi) in nm, got {describe(wavelength_range)}"
        )
    lo, hi = float(rng[0]), float(rng[1])
    if not lo < hi:
        raise InvalidInputError(f"expected a wavelength range lo < hi, got {wavelength_range}")
    return SpectralLocus(*_locus(o, c, lo, hi))


def polygon_area(vertices: npt.ArrayLike) -> float:
    r"""Compute the area of a simple polygon by the shoelace formula.

    :math:`A = \tfrac12 |\sum_i (x_i y_{i+1} - x_{i+1} y_i)|`.

    Examples
    --------
    >>> polygon_area([[0, 0], [1, 0], [0, 1]])
    0.5
    """
    v = as_real_ndarray(vertices, "vertices")
    if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
        raise InvalidInputError(f"expected vertices of shape (N >= 3, 2), got {v.shape}")
    if np.abs(v).max() > 1e100:
        raise InvalidInputError(
            f"expected vertices within ±1e100 (the area would overflow), got {np.abs(v).max():g}"
        )
    x, y = v[:, 0], v[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)))


@_deprecate.parameters(positional=("observer",))
def visible_area(coords: str = "xy", *, observer: int = 2) -> float:
    """Compute the area bounded by the spectral locus and the purple line.

    ``observer`` is keyword-only.

    Examples
    --------
    >>> round(visible_area("xy"), 4)
    0.3342
    """
    return polygon_area(spectral_locus(observer=observer, coords=coords).chromaticities)


#: Slabs crossed by more edges than this are tested apart on NumPy (the jagged red end).
_LIGHT_EDGES = 2


@lru_cache(maxsize=16)
def _polygon_slabs(
    vertices: bytes, n: int, dtype: str
) -> tuple[np.ndarray, tuple[np.ndarray, ...], np.ndarray, tuple[np.ndarray, ...]]:
    """Tabulate the edges each horizontal slab of a polygon crosses, in ``dtype`` (cached).

    Returns the distinct vertex ordinates ``v`` (sorted), the tables (len(v) + 1, K) of
    ``x1, y1, x2 - x1, y2 - y1`` of the edges crossed by row ``searchsorted(v, y,
    side="right")`` (padded with ``x1`` NaN, ``y1 = 0``, ``x2 - x1 = 0``, ``y2 - y1 = 1``:
    an intersection at NaN, right of no point, not even ``x = -inf``), each row's count and
    the tables cut to their first :data:`_LIGHT_EDGES` columns. For ``v[k-1] <= y < v[k]``
    a vertex ordinate ``y1`` has ``y1 > y`` exactly when ``y1 > v[k-1]``, so the edges with
    ``(y1 > y) != (y2 > y)`` are the same for every ``y`` of the slab; below ``v[0]`` and
    from ``v[-1]`` on none are.
    """
    dt = np.dtype(dtype)
    poly = np.frombuffer(vertices, dtype=np.float64).reshape(n, 2).astype(dt)
    x1, y1 = poly[:, 0], poly[:, 1]
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    dy = y2 - y1
    params = np.stack([x1, y1, x2 - x1, dy])  # dy != 0 on every crossing edge
    v = np.unique(y1)
    cross = np.zeros((v.size + 1, n), dtype=bool)
    cross[1:] = (y1 > v[:, None]) != (y2 > v[:, None])
    counts = cross.sum(axis=1)
    k = max(int(counts.max()), 1)
    table = np.empty((4, v.size + 1, k), dtype=dt)
    table[...] = np.array([np.nan, 0, 0, 1], dtype=dt)[:, None, None]
    for r in np.flatnonzero(counts):
        table[:, r, : counts[r]] = params[:, cross[r]]
    light = tuple(np.ascontiguousarray(t[:, : min(k, _LIGHT_EDGES)]) for t in table)
    for a in (v, table, counts, *light):
        a.setflags(write=False)
    return v, tuple(table), counts, light


def _crossings(x: Any, y: Any, edges: Any, xp: Any) -> Any:
    """Count the slab's edges (4 x (N, K)) right of each point (N,): ``x < x1 + (y - y1) dx/dy``.

    The same expression, in the same order and dtype, as a test of every edge.
    """
    x1, y1, dx, dy = edges
    xint = x1 + (y[:, None] - y1) * dx / dy
    if xp is np:
        return np.count_nonzero(x[:, None] < xint, axis=-1)
    return xp.sum(xp.astype(x[:, None] < xint, xp.int32), axis=-1)


def _host_view(a: Any) -> np.ndarray | None:
    """Return ``a`` as a NumPy array when that is free (NumPy, PyTorch on the CPU), else None."""
    if isinstance(a, np.ndarray):
        return a
    if array_api_compat.is_torch_array(a) and a.device.type == "cpu":
        import torch

        if not torch.compiler.is_compiling():
            return np.asarray(a.detach().numpy())
    return None


def _points_in_polygon(pts: Any, poly: np.ndarray, xp: Any) -> Any:
    r"""Even-odd ray casting, vectorised over points (a point on an edge may fall either way).

    A point :math:`(x, y)` is inside when an odd number of edges
    :math:`(x_1, y_1)\text{-}(x_2, y_2)` have :math:`(y_1 > y) \ne (y_2 > y)` and
    :math:`x < x_1 + (y - y_1)(x_2 - x_1)/(y_2 - y_1)`, both in the points' dtype. Only the
    edges of the point's horizontal slab (:func:`_polygon_slabs`, found by bisection) can
    pass the first test, so only they are evaluated, by the same formula: the answers of a
    test of every edge in O(log M + K) per point instead of O(M) (K: the edges of a slab,
    2 to 4 over most of the spectral locus, up to 54 in its jagged red end).
    """
    flat = xp.reshape(pts, (-1, 2))
    v, table, counts, light = _polygon_slabs(
        np.ascontiguousarray(poly, dtype=np.float64).tobytes(),
        poly.shape[0],
        str(pts.dtype).rsplit(".", 1)[-1],
    )
    host = _host_view(flat)
    if host is not None:
        x, y = host[:, 0], host[:, 1]
        row = np.searchsorted(v, y, side="right")
        n = _crossings(x, y, [np.take(t, row, axis=0) for t in light], np)
        many = np.flatnonzero(counts[row] > light[0].shape[1])  # the crowded slabs' points
        if many.size:
            n[many] = _crossings(x[many], y[many], [t[row[many]] for t in table], np)
        n = xp.asarray(n, device=device_of(pts))
    else:  # a device (or array-api-strict): every point against the widest slab's K edges
        dev = device_of(pts)
        x, y = flat[:, 0], xp.asarray(flat[:, 1], copy=True)  # contiguous for searchsorted
        row = xp.searchsorted(xp.asarray(np.array(v), device=dev), y, side="right")
        # the slabs' edges a few columns at a time: (N, G) temporaries of at most
        # _DEVICE_BLOCK values, not (N, K) ones (K = 54 for the 2° observer's xy)
        edges = xp.asarray(_slab_edges(table), device=dev)  # (len(v) + 1, K, 4)
        k_all = edges.shape[1]
        step = max(1, min(k_all, _DEVICE_BLOCK // max(int(row.shape[0]), 1)))
        n = xp.zeros(row.shape, dtype=xp.int32, device=dev)
        for k in range(0, k_all, step):
            got = xp.take(edges[:, k : min(k + step, k_all), :], row, axis=0)  # (N, G, 4)
            xint = got[:, :, 0] + (y[:, None] - got[:, :, 1]) * got[:, :, 2] / got[:, :, 3]
            n = n + xp.sum(xp.astype(x[:, None] < xint, xp.int32), axis=1)
    return xp.reshape(n, pts.shape[:-1]) % 2 == 1


#: Values per temporary of the device path of :func:`_points_in_polygon` (points x edges).
_DEVICE_BLOCK = 1 << 18


def _slab_edges(table: tuple[np.ndarray, ...]) -> np.ndarray:
    """Stack the slab tables into one (rows, K, 4) array: ``x1, y1, x2 - x1, y2 - y1`` last."""
    return np.ascontiguousarray(np.stack(table, axis=-1))


@chunkwise(1)
def in_locus(points: ArrayLike, coords: str = "xy", *, observer: int = 2) -> Array:
    """Test where chromaticities lie inside the spectral locus (physically realisable).

    Parameters
    ----------
    points : array_like, shape (..., 2)
        xy or u'v' chromaticities (any Array-API array; the result is of the same kind).
    coords : {"xy", "uv"}
        CIE 1931 ``xy`` or CIE 1976 UCS ``u'v'``.
    observer : {2, 10}, keyword-only
        The standard observer whose spectral locus bounds the region.

    Returns
    -------
    bool array, shape (...)

    Examples
    --------
    >>> in_locus([[0.3127, 0.3290], [0.7, 0.7]]).tolist()
    [True, False]
    """
    xp = namespace(points)
    p = as_points_strict(points, "points", 2, xp=xp)
    return _points_in_polygon(
        p, spectral_locus(observer=observer, coords=coords).chromaticities, xp
    )


def check_in_locus(points: ArrayLike, coords: str = "xy", *, observer: int = 2) -> Array:
    """``points`` as an array, raising :class:`InvalidInputError` if any lies outside the locus.

    An explicit check: it reads the answer on the host whatever the array's device (on a GPU
    it waits for the device once); :func:`in_locus` gives the mask without reading it.
    """
    xp = namespace(points)
    p = as_points_strict(points, "points", 2, xp=xp)
    _refuse_outside_locus(p, coords, observer, xp, explicit=True)
    return p


def _refuse_outside_locus(p: Any, coords: str, observer: int, xp: Any, *, explicit: bool) -> None:
    if not (explicit or reads_values(p)):  # implicit check on a device: not read
        return
    ok = in_locus(p, coords, observer=observer)
    if not bool(xp.all(ok)):
        pn, okn = to_numpy(p), to_numpy(ok)
        bad = pn[~okn][0]
        name = "(x, y)" if coords == "xy" else "(u', v')"
        raise InvalidInputError(
            f"chromaticity {name} = ({bad[0]:.4g}, {bad[1]:.4g}) lies outside the spectral "
            f"locus ({int(np.count_nonzero(~okn))} of {okn.size} points): no real colour has it"
        )


@chunkwise(1)
def xy_to_xyz(
    xy: ArrayLike, Y: float = 1.0, *, check_locus: bool = True, observer: int = 2
) -> Array:
    r"""XYZ of a chromaticity at luminance ``Y``: :math:`X = xY/y,\ Z = (1 - x - y)Y/y`.

    With ``check_locus`` (default) a chromaticity outside the spectral locus raises
    :class:`InvalidInputError`: no real colour has it (CIE 015:2018 §7.3). On device arrays
    (a GPU; docs/design.md, "Devices") neither the locus nor ``y > 0`` is read: a point
    outside gets the formula's value and ``y = 0`` gives inf (:func:`check_in_locus` is the
    explicit check).

    Examples
    --------
    >>> xy_to_xyz([0.31271, 0.32902]).round(5).tolist()
    [0.95043, 1.0, 1.0889]
    """
    xp = namespace(xy)
    p = as_points_strict(xy, "xy", 2, xp=xp)
    Y = as_real(Y, "Y", nonnegative=True)
    if as_bool(check_locus, "check_locus"):
        _refuse_outside_locus(p, "xy", observer, xp, explicit=False)
    if any_value(p[..., 1] <= 0, xp):
        raise InvalidInputError("expected y > 0 (y = 0 has no finite XYZ)")
    x, y = p[..., 0], p[..., 1]
    Yf = float(Y)
    return xp.stack([x * Yf / y, xp.full_like(x, Yf), (1.0 - x - y) * Yf / y], axis=-1)
