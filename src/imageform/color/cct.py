"""Correlated colour temperature (CCT) and Duv: Robertson (1968) and the CIE daylight locus.

- :func:`xy_to_cct` — CIE 1931 ``xy`` to ``(CCT, Duv)``; Robertson's method interpolates
  between his 31 isotemperature lines (table below, no colour-matching functions needed);
  ``"daylight"`` inverts the CIE daylight locus.
- :func:`cct_to_xy` — ``(CCT, Duv)`` to ``xy`` on (or off, by Duv) the Planckian locus, or on the
  CIE daylight locus (the chromaticity of the D illuminants).

Duv is the signed distance from the Planckian locus in the CIE 1960 UCS ``(u, v)`` along the
isotemperature line, positive above the locus (greenish), negative below (pinkish), as in
ANSI C78.377. McCamy (1992), Hernández-Andrés (1999) and Ohno (2013) are in
:mod:`imageform.color.cct_methods`, selectable here by ``method=``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform import _deprecate
from imageform._backend import device_of, is_dask_namespace, namespace, reads_values, to_numpy
from imageform._colormath import DAYLIGHT_HIGH as _DAYLIGHT_HIGH
from imageform._colormath import DAYLIGHT_LOW as _DAYLIGHT_LOW
from imageform._colormath import DAYLIGHT_RANGE as _DAYLIGHT_RANGE
from imageform._colormath import daylight_x as _daylight_x
from imageform._colormath import daylight_xy as _daylight_xy
from imageform._colormath import uv1960_from_xy as _uv_from_xy
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_float_strict,
    as_int,
    as_points_strict,
    check_name,
)
from imageform.color.cct_methods import (
    uv_to_cct_ohno2013,
    xy_to_cct_hernandez1999,
    xy_to_cct_mccamy1992,
)
from imageform.errors import InvalidInputError

__all__ = [
    "CCT_TO_XY_METHODS",
    "ROBERTSON_1968",
    "XY_TO_CCT_METHODS",
    "cct_to_xy",
    "uv1960_to_xy",
    "xy_to_cct",
    "xy_to_uv1960",
]

# How far (in x) beyond an end of the daylight locus xy_to_cct(method="daylight") still takes
# a chromaticity, as that end: rounding (one ulp is 5.6e-17 at x = 0.38), not a colour.
DAYLIGHT_X_TOLERANCE = 1e-9

#: Robertson (1968) isotemperature lines: reciprocal megakelvin (mired), CIE 1960 u, v of the
#: Planckian locus and the slope t of the isotemperature line. Wyszecki & Stiles (1982),
#: Color Science, 2nd ed., Table 1(3.11); u at 325 mired corrected from 0.24702 to 0.24792
#: (B. Lindbloom; the smooth run of the column confirms it).
ROBERTSON_1968 = np.array(
    [
        (0, 0.18006, 0.26352, -0.24341),
        (10, 0.18066, 0.26589, -0.25479),
        (20, 0.18133, 0.26846, -0.26876),
        (30, 0.18208, 0.27119, -0.28539),
        (40, 0.18293, 0.27407, -0.30470),
        (50, 0.18388, 0.27709, -0.32675),
        (60, 0.18494, 0.28021, -0.35156),
        (70, 0.18611, 0.28342, -0.37915),
        (80, 0.18740, 0.28668, -0.40955),
        (90, 0.18880, 0.28997, -0.44278),
        (100, 0.19032, 0.29326, -0.47888),
        (125, 0.19462, 0.30141, -0.58204),
        (150, 0.19962, 0.30921, -0.70471),
        (175, 0.20525, 0.31647, -0.84901),
        (200, 0.21142, 0.32312, -1.0182),
        (225, 0.21807, 0.32909, -1.2168),
        (250, 0.22511, 0.33439, -1.4512),
        (275, 0.23247, 0.33904, -1.7298),
        (300, 0.24010, 0.34308, -2.0637),
        (325, 0.24792, 0.34655, -2.4681),
        (350, 0.25591, 0.34951, -2.9641),
        (375, 0.26400, 0.35200, -3.5814),
        (400, 0.27218, 0.35407, -4.3633),
        (425, 0.28039, 0.35577, -5.3762),
        (450, 0.28863, 0.35714, -6.7262),
        (475, 0.29685, 0.35823, -8.5955),
        (500, 0.30505, 0.35907, -11.324),
        (525, 0.31320, 0.35968, -15.628),
        (550, 0.32129, 0.36011, -23.325),
        (575, 0.32931, 0.36038, -40.770),
        (600, 0.33724, 0.36051, -116.45),
    ]
)
ROBERTSON_1968.setflags(write=False)

# Robertson's table spans 0-600 mired: CCT from 1e6/600 = 1666.7 K to infinity.
_ROBERTSON_MIN_CCT = 1.0e6 / 600.0


def _xy_from_uv(xp: Any, u: Any, v: Any) -> Any:
    d = 2.0 * u - 8.0 * v + 4.0
    return xp.stack([3.0 * u / d, 2.0 * v / d], axis=-1)


@chunkwise(1)
def xy_to_uv1960(xy: ArrayLike) -> Array:
    r"""CIE 1931 ``xy`` to CIE 1960 UCS ``uv``.

    .. math:: u = \frac{4x}{-2x + 12y + 3},\quad v = \frac{6y}{-2x + 12y + 3}

    Parameters
    ----------
    xy : array_like, shape (..., 2)
        CIE 1931 chromaticity coordinates.

    Returns
    -------
    array, shape (..., 2)

    References
    ----------
    CIE 15:2004, §8.1 (the 1960 UCS; v = 2/3 v').

    Examples
    --------
    >>> [round(float(c), 5) for c in xy_to_uv1960([0.31271, 0.32902])]
    [0.19783, 0.31222]
    """
    xp = namespace(xy)
    a = as_points_strict(xy, "xy", 2, xp=xp)
    u, v = _uv_from_xy(xp, a)
    return xp.stack([u, v], axis=-1)


@chunkwise(1)
def uv1960_to_xy(uv: ArrayLike) -> Array:
    r"""CIE 1960 UCS ``uv`` to CIE 1931 ``xy``.

    .. math:: x = \frac{3u}{2u - 8v + 4},\quad y = \frac{2v}{2u - 8v + 4}

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        CIE 1960 UCS chromaticity coordinates.

    Returns
    -------
    array, shape (..., 2)

    Examples
    --------
    >>> [round(float(c), 5) for c in uv1960_to_xy([0.19783, 0.31222])]
    [0.31271, 0.32902]
    """
    xp = namespace(uv)
    a = as_points_strict(uv, "uv", 2, xp=xp)
    return _xy_from_uv(xp, a[..., 0], a[..., 1])


def _table(xp: Any, like: Any) -> tuple[Any, Any, Any, Any, Any, Any]:
    t = xp.asarray(ROBERTSON_1968.copy(), dtype=like.dtype, device=device_of(like))
    r, u, v, s = t[:, 0], t[:, 1], t[:, 2], t[:, 3]
    length = xp.sqrt(1.0 + s * s)
    return r, u, v, s, 1.0 / length, s / length


def _robertson_inverse(xp: Any, xy: Any) -> tuple[Any, Any]:
    u, v = _uv_from_xy(xp, xy)
    r, ut, vt, _, du, dv = _table(xp, xy)
    # signed distance of (u, v) from each isotemperature line (Wyszecki & Stiles, eq. 3(3.11))
    d = (v[..., None] - vt) * du - (u[..., None] - ut) * dv  # (..., 31)
    neg = d <= 0
    outside = (d[..., 0] < 0) | ~xp.any(neg[..., 1:], axis=-1)
    if any_value(outside, xp):
        raise InvalidInputError(
            "xy outside the range of Robertson's method (CCT 1667 K to infinity)"
        )
    # first line j >= 1 on the far side: the point lies between lines j-1 and j
    idx = xp.arange(31, device=device_of(xy))
    first = xp.argmax(xp.astype(neg[..., 1:], xp.int8), axis=-1) + 1
    onehot_j = xp.astype(idx == first[..., None], xy.dtype)
    onehot_i = xp.astype(idx == (first - 1)[..., None], xy.dtype)

    def pick(arr: Any, onehot: Any) -> Any:
        return xp.sum(arr * onehot, axis=-1)

    di, dj = pick(d, onehot_i), pick(d, onehot_j)
    f = di / (di - dj)
    mired = pick(r, onehot_i) + f * (pick(r, onehot_j) - pick(r, onehot_i))
    cct = 1.0e6 / mired
    uL = pick(ut, onehot_i) + f * (pick(ut, onehot_j) - pick(ut, onehot_i))
    vL = pick(vt, onehot_i) + f * (pick(vt, onehot_j) - pick(vt, onehot_i))
    ddu = pick(du, onehot_i) + f * (pick(du, onehot_j) - pick(du, onehot_i))
    ddv = pick(dv, onehot_i) + f * (pick(dv, onehot_j) - pick(dv, onehot_i))
    n = xp.sqrt(ddu * ddu + ddv * ddv)
    duv = -((u - uL) * ddu + (v - vL) * ddv) / n
    if not reads_values(outside):  # on a device: NaN where out of range, never a read-back
        cct, duv = _nan_where(xp, outside, cct), _nan_where(xp, outside, duv)
    return cct, duv


def _nan_where(xp: Any, bad: Any, x: Any) -> Any:
    """``x`` with NaN where ``bad``: a device array's refusal (docs/design.md, "Devices")."""
    return xp.where(bad, xp.asarray(math.nan, dtype=x.dtype, device=device_of(x)), x)


def _robertson_forward(xp: Any, cct: Any, duv: Any) -> Any:
    r, ut, vt, _, du, dv = _table(xp, cct)
    mired = 1.0e6 / cct
    idx = xp.arange(30, device=device_of(cct))
    # segment i with r_i <= mired < r_{i+1} (the last segment includes 600 mired)
    lower = xp.sum(xp.astype(mired[..., None] >= r[1:30], xp.int64), axis=-1)
    oh_i = xp.astype(idx == lower[..., None], cct.dtype)

    def seg(arr: Any) -> tuple[Any, Any]:
        return xp.sum(arr[:30] * oh_i, axis=-1), xp.sum(arr[1:] * oh_i, axis=-1)

    r0, r1 = seg(r)
    f = (mired - r0) / (r1 - r0)
    (u0, u1), (v0, v1) = seg(ut), seg(vt)
    (a0, a1), (b0, b1) = seg(du), seg(dv)
    uL, vL = u0 + f * (u1 - u0), v0 + f * (v1 - v0)
    ddu, ddv = a0 + f * (a1 - a0), b0 + f * (b1 - b0)
    n = xp.sqrt(ddu * ddu + ddv * ddv)
    return _xy_from_uv(xp, uL - duv * ddu / n, vL - duv * ddv / n)


def _check_cct_range(xp: Any, cct: Any, lo: float, hi: float, method: str) -> Any:
    """Raise for a CCT outside ``[lo, hi]`` (host); on a device, the CCT with NaN there."""
    if not reads_values(cct):
        return _nan_where(xp, (cct < lo) | (cct > hi), cct)
    if any_value(cct < lo, xp) or any_value(cct > hi, xp):
        bad = float(xp.min(cct)) if any_value(cct < lo, xp) else float(xp.max(cct))
        raise InvalidInputError(
            f"CCT {bad:g} K outside the range of the {method} method ({lo:g} K to {hi:g} K)"
        )
    return cct


def cct_to_xy(
    cct: ArrayLike,
    duv: ArrayLike = 0.0,
    *,
    method: Literal["robertson1968", "daylight"] = "robertson1968",
) -> Array:
    r"""Chromaticity ``xy`` of a correlated colour temperature (and Duv).

    ``"robertson1968"``: the point at ``cct`` on the Planckian locus, interpolated linearly
    in mired between Robertson's isotemperature lines, then moved by ``duv`` along the
    isotemperature line in the CIE 1960 UCS (positive above the locus).
    ``"daylight"``: the CIE daylight locus,

    .. math::
        x_D = a_3 \frac{10^9}{T^3} + a_2 \frac{10^6}{T^2} + a_1 \frac{10^3}{T} + a_0,\quad
        y_D = -3.000 x_D^2 + 2.870 x_D - 0.275

    (``duv`` must be 0; the daylight locus lies about 0.003 above the Planckian locus).

    Parameters
    ----------
    cct : array_like, shape (...)
        Kelvin; Robertson: 1666.7 K (600 mired) or above; daylight: 4000 K to 25000 K.
    duv : array_like, shape (...)
        Distance from the Planckian locus (broadcast against ``cct``).
    method : {"robertson1968", "daylight"}
        The Planckian locus (Robertson's isotemperature lines) or the CIE daylight locus.

    Returns
    -------
    array, shape (..., 2)

    References
    ----------
    A. R. Robertson (1968), J. Opt. Soc. Am. 58(11), 1528-1535; Wyszecki & Stiles (1982),
    §3.11. CIE 15:2004, eqs. (3.3)-(3.4) (daylight locus).

    Examples
    --------
    D65 is daylight at 6500 K x 1.4388/1.4380 (the revised c2) = 6503.6 K:

    >>> [round(float(c), 4) for c in cct_to_xy(6500 * 1.4388 / 1.4380, method="daylight")]
    [0.3127, 0.3291]
    """
    m = check_name(method, CCT_TO_XY_METHODS, "CCT method")
    xp = namespace(cct, duv)
    T = as_float_strict(cct, "cct", xp=xp)
    D = as_float_strict(duv, "duv", xp=xp, dtype=T.dtype, device=device_of(T))
    if not is_dask_namespace(xp) and any_value(xp.abs(D) > 1.0, xp):
        raise InvalidInputError("expected |duv| <= 1 (a distance in CIE 1960 uv)")
    try:
        T, D = xp.broadcast_arrays(T, D)
    except ValueError:
        raise InvalidInputError(
            f"expected cct and duv of broadcastable shapes, got {tuple(T.shape)} and "
            f"{tuple(D.shape)}"
        ) from None
    return CCT_TO_XY_METHODS[m](xp, T, D)


def _cct_to_xy_daylight(xp: Any, T: Any, D: Any) -> Any:
    if any_value(D != 0, xp):
        raise InvalidInputError("the daylight method takes no duv (the locus is a curve)")
    T = _check_cct_range(xp, T, *_DAYLIGHT_RANGE, "daylight")
    if not reads_values(D):
        T = _nan_where(xp, D != 0, T)
    return _daylight_xy(xp, T)


def _cct_to_xy_robertson(xp: Any, T: Any, D: Any) -> Any:
    T = _check_cct_range(xp, T, _ROBERTSON_MIN_CCT, math.inf, "robertson1968")
    if not reads_values(D):
        D = _nan_where(xp, xp.abs(D) > 1.0, D)
    return _robertson_forward(xp, T, D)


#: The methods of :func:`cct_to_xy`, each name mapped to its implementation
#: ``f(xp, cct, duv) -> xy`` (read-only): the Planckian locus (Robertson 1968) and the CIE
#: daylight locus.
CCT_TO_XY_METHODS: MappingProxyType[str, Callable[[Any, Any, Any], Any]] = MappingProxyType(
    {"robertson1968": _cct_to_xy_robertson, "daylight": _cct_to_xy_daylight}
)


def xy_to_cct(
    xy: ArrayLike,
    *,
    method: Literal[
        "robertson1968", "daylight", "mccamy1992", "hernandez1999", "ohno2013"
    ] = "robertson1968",
    iterations: int = 20,
) -> tuple[Array, Array]:
    r"""Correlated colour temperature and Duv of chromaticities ``xy``.

    ``"robertson1968"``: with the signed distances
    :math:`d_j = ((v - v_j) - t_j (u - u_j))/\sqrt{1 + t_j^2}` of ``(u, v)`` from the
    isotemperature lines, the point lies between lines ``i`` and ``j = i + 1`` where the sign
    changes, and

    .. math:: \frac{1}{T} = \frac{1}{T_i} + \frac{d_i}{d_i - d_j}
        \left(\frac{1}{T_j} - \frac{1}{T_i}\right)

    ``"daylight"``: the temperature whose CIE daylight-locus ``x_D`` equals ``x`` (Newton on
    the cubic in :math:`1/T`); Duv is measured from the Planckian locus as always.

    Parameters
    ----------
    xy : array_like, shape (..., 2)
        CIE 1931 chromaticities; Robertson covers 1667 K to infinity; daylight 4000-25000 K.
    method : {"robertson1968", "daylight", "mccamy1992", "hernandez1999", "ohno2013"}
        The last three are in :mod:`imageform.color.cct_methods` (NumPy results; the two
        closed-form fits return Robertson's Duv, Ohno's its own).
    iterations : int
        Newton steps of the daylight inversion (converges to 1e-12 K in < 10), 1 to 1000.
        The daylight method takes ``x`` between the locus ends (25000 K and 4000 K); an
        ``x`` at most 1e-9 (``DAYLIGHT_X_TOLERANCE``) beyond an end, from rounding, is taken
        as that end (4000 K or 25000 K); farther out it raises.

    Returns
    -------
    cct, duv : arrays, shape (...)

    References
    ----------
    A. R. Robertson (1968), J. Opt. Soc. Am. 58(11), 1528-1535; CIE 15:2004, eq. (3.3).

    Examples
    --------
    CIE illuminant A (2856 K by definition) and D65 (about 6504 K):

    >>> cct, duv = xy_to_cct([0.44757, 0.40745])
    >>> round(float(cct)), round(float(duv), 4)
    (2856, 0.0)
    >>> round(float(xy_to_cct([0.31271, 0.32902])[0]))
    6503
    """
    m = check_name(method, XY_TO_CCT_METHODS, "CCT method")
    n_iter = as_int(iterations, "iterations", minimum=1, maximum=1000)
    xp = namespace(xy)
    a = as_points_strict(xy, "xy", 2, xp=xp)
    return XY_TO_CCT_METHODS[m](xp, a, n_iter)


def _xy_to_cct_robertson(xp: Any, a: Any, n_iter: int) -> tuple[Any, Any]:
    return _robertson_inverse(xp, a)


def _xy_to_cct_ohno(xp: Any, a: Any, n_iter: int) -> tuple[Any, Any]:
    # CCT and Duv from the Planckian locus of the 1931 CMFs (NumPy)
    cct, duv = uv_to_cct_ohno2013(xy_to_uv1960(np.asarray(to_numpy(a), dtype=np.float64)))
    return cct, duv


def _closed_form(fit: Callable[[Any], Any]) -> Callable[[Any, Any, int], tuple[Any, Any]]:
    """Make a closed-form CCT fit (NumPy) a method, with Robertson's Duv."""

    def method(xp: Any, a: Any, n_iter: int) -> tuple[Any, Any]:
        _, duv = _robertson_inverse(xp, a)
        return fit(np.asarray(to_numpy(a), dtype=np.float64)), duv

    method.__name__ = method.__qualname__ = f"_closed_form_{fit.__name__}"
    return method


def _xy_to_cct_daylight(xp: Any, a: Any, n_iter: int) -> tuple[Any, Any]:
    cct, duv = _robertson_inverse(xp, a)
    x = a[..., 0]
    lo_x = float(_daylight_x(np, np.asarray(_DAYLIGHT_RANGE[1])))
    hi_x = float(_daylight_x(np, np.asarray(_DAYLIGHT_RANGE[0])))
    tol = DAYLIGHT_X_TOLERANCE
    off_locus = (x < lo_x - tol) | (x > hi_x + tol)
    if any_value(off_locus, xp):
        raise InvalidInputError(
            f"expected xy on the daylight locus, got x outside the daylight locus (x from "
            f"{lo_x:.5f} at 25000 K to {hi_x:.5f} at 4000 K)"
        )
    # an x within the tolerance outside an end (rounding) is the end itself
    x = xp.clip(x, lo_x, hi_x)
    T = xp.clip(cct, 4000.0, 25000.0)  # start from Robertson's estimate, inside the domain
    for _ in range(n_iter):
        s = 1.0 / T
        c = xp.astype(T <= 7000.0, T.dtype)
        lo, hi = _DAYLIGHT_LOW, _DAYLIGHT_HIGH
        dx_ds = c * ((3 * lo[0] * s + 2 * lo[1]) * s + lo[2]) + (1 - c) * (
            (3 * hi[0] * s + 2 * hi[1]) * s + hi[2]
        )
        s = s - (_daylight_x(xp, T) - x) / dx_ds
        T = 1.0 / s
    if not reads_values(off_locus):  # on a device: NaN off the locus, never a read-back
        T = _nan_where(xp, off_locus, T)
    return T, duv


#: The methods of :func:`xy_to_cct`, each name mapped to its implementation
#: ``f(xp, xy, iterations) -> (cct, duv)`` (read-only): Robertson (1968), the inverse of the
#: CIE daylight locus, and the three of :mod:`imageform.color.cct_methods`.
XY_TO_CCT_METHODS: MappingProxyType[str, Callable[[Any, Any, int], tuple[Any, Any]]] = (
    MappingProxyType(
        {
            "robertson1968": _xy_to_cct_robertson,
            "daylight": _xy_to_cct_daylight,
            "mccamy1992": _closed_form(xy_to_cct_mccamy1992),
            "hernandez1999": _closed_form(xy_to_cct_hernandez1999),
            "ohno2013": _xy_to_cct_ohno,
        }
    )
)

__getattr__ = _deprecate.module_getattr(
    "imageform.color.cct", {"CCT_METHODS": ("CCT_TO_XY_METHODS", CCT_TO_XY_METHODS)}
)
