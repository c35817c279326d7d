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


def _points_in_polygon(pts: Any, poly: np.ndarray, xp: Any) -> Any:
    """Even-odd ray casting, vectorised over points (boundary counts as inside up to 1e-12)."""
    dev = device_of(pts)
    poly = np.array(poly, dtype=np.float64)  # a writable copy: torch warns on read-only input
    x, y = pts[..., 0][..., None], pts[..., 1][..., None]
    x1 = xp.asarray(poly[:, 0], dtype=pts.dtype, device=dev)
    y1 = xp.asarray(poly[:, 1], dtype=pts.dtype, device=dev)
    x2 = xp.asarray(np.roll(poly[:, 0], -1), dtype=pts.dtype, device=dev)
    y2 = xp.asarray(np.roll(poly[:, 1], -1), dtype=pts.dtype, device=dev)
    crosses = (y1 > y) != (y2 > y)
    dy = y2 - y1
    # edges with dy = 0 never cross (crosses is False there): any finite divisor will do
    xint = x1 + (y - y1) * (x2 - x1) / xp.where(dy == 0, 1.0, dy)
    n = xp.sum(xp.astype(crosses & (x < xint), xp.int32), axis=-1)
    return n % 2 == 1


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
