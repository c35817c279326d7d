r"""CIE XYZ to xyY, CIELAB (L*a*b*), CIELCh (L*C*h_ab) and CIELUV (L*u*v*), and back.

XYZ is scaled so that the reference white has Y = 1 (docs/conventions.md); L* is in [0, 100]; hue
angles are degrees in [0, 360). The reference white is the ``white=`` parameter: an
illuminant name (``"D65"``, CIE 15:2004), an RGB space name (``"srgb"``: the white its
standard writes), an ``(x, y)`` pair or an ``(X, Y, Z)`` triple (see
:func:`imageform.color.whitepoints.resolve_white`).

Constants follow CIE 15:2004 clause 8.2 in their exact rational form:
:math:`\delta = 6/29`, so the cube-root threshold is :math:`\delta^3 = 216/24389` and the
linear segment is :math:`t / (3\delta^2) + 4/29 = (841/108) t + 16/116`.
"""

from __future__ import annotations

import math
from typing import Any

from imageform._backend import constant, namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image_strict

from .whitepoints import named_white

__all__ = [
    "lab_to_lch",
    "lab_to_xyz",
    "lch_to_lab",
    "luv_to_xyz",
    "xyy_to_xyz",
    "xyz_to_lab",
    "xyz_to_luv",
    "xyz_to_xyy",
]

# CIE 15:2004, clause 8.2.1 (eq. 8.3-8.5): f(t) = t^(1/3) for t > (6/29)^3, else
# (841/108) t + 4/29. Written with δ = 6/29.
_DELTA = 6.0 / 29.0
_EPS = _DELTA**3  # 216/24389 = 0.008856...
_LIN_SLOPE = 1.0 / (3.0 * _DELTA**2)  # 841/108
_LIN_OFFSET = 4.0 / 29.0  # = 16/116
_KAPPA = 116.0 * _LIN_SLOPE  # 24389/27 = 903.296..., L* = κ Y/Yn below ε


def _white_arr(white: Any, observer: int, like: Any) -> Any:
    xp = namespace(like)
    return constant(named_white(white, observer), like, xp)


def _f(xp: Any, t: Any) -> Any:
    cube = xp.pow(xp.clip(t, min=_EPS), 1.0 / 3.0)  # below ε the branch is unused
    return xp.where(t > _EPS, cube, _LIN_SLOPE * t + _LIN_OFFSET)


def _f_inv(xp: Any, u: Any) -> Any:
    return xp.where(u > _DELTA, u * u * u, (u - _LIN_OFFSET) / _LIN_SLOPE)


def _xyz_to_lab(xp: Any, xyz: Any, w: Any) -> Any:
    f = _f(xp, xyz / w)
    fx, fy, fz = f[..., 0], f[..., 1], f[..., 2]
    return xp.stack([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)], axis=-1)


def _lab_to_xyz(xp: Any, lab: Any, w: Any) -> Any:
    fy = (lab[..., 0] + 16.0) / 116.0
    fx = fy + lab[..., 1] / 500.0
    fz = fy - lab[..., 2] / 200.0
    return _f_inv(xp, xp.stack([fx, fy, fz], axis=-1)) * w


@chunkwise(1)
def xyz_to_lab(xyz: ArrayLike, white: str | ArrayLike = "D65", *, observer: int = 2) -> Array:
    r"""CIE XYZ to CIELAB.

    .. math::
        L^* = 116 f(Y/Y_n) - 16, \quad a^* = 500 [f(X/X_n) - f(Y/Y_n)], \quad
        b^* = 200 [f(Y/Y_n) - f(Z/Z_n)]

    with :math:`f(t) = t^{1/3}` for :math:`t > (6/29)^3`, else :math:`(841/108) t + 4/29`.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        Tristimulus values, Y = 1 at the reference white.
    white : str or sequence of float
        Reference white, see the module docstring. ``"D65"`` is CIE 15:2004's D65; pass
        ``white="srgb"`` for the IEC sRGB white (0.3127, 0.3290), which maps sRGB white to
        exactly a* = b* = 0 (:func:`imageform.color.convert` does this by default).
    observer : {2, 10}
        Observer of a named illuminant.

    Returns
    -------
    array, shape (..., 3)
        L* in [0, 100] for Y in [0, Yn]; a*, b* unbounded.

    Notes
    -----
    Source: CIE 15:2004, clause 8.2.1, eq. (8.3)-(8.5).

    Examples
    --------
    >>> xyz_to_lab([0.18, 0.18, 0.18], white="E").round(4).tolist()
    [49.4961, 0.0, 0.0]
    """
    x = as_image_strict(xyz, "XYZ", range_check=False)
    xp = namespace(x)
    return _xyz_to_lab(xp, x, _white_arr(white, observer, x))


@chunkwise(1)
def lab_to_xyz(lab: ArrayLike, white: str | ArrayLike = "D65", *, observer: int = 2) -> Array:
    r"""CIELAB to CIE XYZ; inverse of :func:`xyz_to_lab`.

    .. math::
        f_y = (L^* + 16)/116, \; f_x = f_y + a^*/500, \; f_z = f_y - b^*/200, \;
        X = X_n f^{-1}(f_x) \ldots

    with :math:`f^{-1}(u) = u^3` for :math:`u > 6/29`, else :math:`3 (6/29)^2 (u - 4/29)`.

    Source: CIE 15:2004, clause 8.2.1 (inverse given in its note 5).

    Examples
    --------
    >>> lab_to_xyz([50.0, 0.0, 0.0], white="E").round(6).tolist()
    [0.184187, 0.184187, 0.184187]
    """
    x = as_image_strict(lab, "Lab", range_check=False)
    xp = namespace(x)
    return _lab_to_xyz(xp, x, _white_arr(white, observer, x))


def _hue_deg(xp: Any, b: Any, a: Any) -> Any:
    h = xp.atan2(b, a) * (180.0 / math.pi)
    return xp.where(h < 0, h + 360.0, h)


def _lab_to_lch(xp: Any, lab: Any) -> Any:
    a, b = lab[..., 1], lab[..., 2]
    c = xp.sqrt(a * a + b * b)
    h = _hue_deg(xp, b, a)
    h = xp.where(h >= 360.0, h - 360.0, h)
    return xp.stack([lab[..., 0], c, h], axis=-1)


def _lch_to_lab(xp: Any, lch: Any) -> Any:
    h = lch[..., 2] * (math.pi / 180.0)
    c = lch[..., 1]
    return xp.stack([lch[..., 0], c * xp.cos(h), c * xp.sin(h)], axis=-1)


@chunkwise(1)
def lab_to_lch(lab: ArrayLike) -> Array:
    r"""CIELAB to CIELCh_ab: chroma and hue angle in degrees [0, 360).

    .. math:: C^*_{ab} = \sqrt{a^{*2} + b^{*2}}, \quad h_{ab} = \operatorname{atan2}(b^*, a^*)

    For :math:`C^* = 0` the hue is undefined; it is returned as 0 (atan2(0, 0)).

    Source: CIE 15:2004, clause 8.2.1.2, eq. (8.8)-(8.9).

    Examples
    --------
    >>> lab_to_lch([50.0, 0.0, 10.0]).round(6).tolist()
    [50.0, 10.0, 90.0]
    """
    x = as_image_strict(lab, "Lab", range_check=False)
    return _lab_to_lch(namespace(x), x)


@chunkwise(1)
def lch_to_lab(lch: ArrayLike) -> Array:
    r"""CIELCh_ab to CIELAB: :math:`a^* = C^* \cos h`, :math:`b^* = C^* \sin h`.

    Examples
    --------
    >>> lch_to_lab([50.0, 10.0, 180.0]).round(6).tolist()
    [50.0, -10.0, 0.0]
    """
    x = as_image_strict(lch, "LCh", range_check=False)
    return _lch_to_lab(namespace(x), x)


def _xyz_to_xyy(xp: Any, xyz: Any, w: Any) -> Any:
    s = xp.sum(xyz, axis=-1)
    zero = s == 0
    safe = xp.where(zero, 1.0, s)
    wx = w[0] / (w[0] + w[1] + w[2])
    wy = w[1] / (w[0] + w[1] + w[2])
    cx = xp.where(zero, wx * xp.ones_like(s), xyz[..., 0] / safe)
    cy = xp.where(zero, wy * xp.ones_like(s), xyz[..., 1] / safe)
    return xp.stack([cx, cy, xyz[..., 1]], axis=-1)


def _xyy_to_xyz(xp: Any, xyy: Any) -> Any:
    cx, cy, yy = xyy[..., 0], xyy[..., 1], xyy[..., 2]
    zero = cy == 0
    safe = xp.where(zero, 1.0, cy)
    x = xp.where(zero, 0.0, cx * yy / safe)
    z = xp.where(zero, 0.0, (1.0 - cx - cy) * yy / safe)
    return xp.stack([x, yy, z], axis=-1)


@chunkwise(1)
def xyz_to_xyy(xyz: ArrayLike, white: str | ArrayLike = "D65", *, observer: int = 2) -> Array:
    r"""CIE XYZ to chromaticity and luminance xyY.

    .. math:: x = X / (X + Y + Z), \quad y = Y / (X + Y + Z), \quad Y = Y

    Black (X + Y + Z = 0) has no chromaticity; it gets the chromaticity of ``white``
    (documented convention, as in Lindbloom's formulae), so that black round-trips.

    Source: CIE 15:2004, clause 7.3, eq. (7.3).

    Examples
    --------
    >>> xyz_to_xyy([0.95047, 1.0, 1.08883]).round(4).tolist()
    [0.3127, 0.329, 1.0]
    """
    x = as_image_strict(xyz, "XYZ", range_check=False)
    return _xyz_to_xyy(namespace(x), x, _white_arr(white, observer, x))


@chunkwise(1)
def xyy_to_xyz(xyy: ArrayLike) -> Array:
    """Chromaticity xyY to CIE XYZ: :math:`X = xY/y`, :math:`Z = (1 - x - y) Y / y`.

    Rows with y = 0 give X = Z = 0 (their Y must be 0 for a physical colour).

    Source: CIE 15:2004, clause 7.3.

    Examples
    --------
    >>> xyy_to_xyz([0.3127, 0.3290, 1.0]).round(6).tolist()
    [0.950456, 1.0, 1.089058]
    """
    x = as_image_strict(xyy, "xyY", range_check=False)
    return _xyy_to_xyz(namespace(x), x)


def _uv_prime(xp: Any, xyz: Any) -> tuple[Any, Any, Any]:
    d = xyz[..., 0] + 15.0 * xyz[..., 1] + 3.0 * xyz[..., 2]
    zero = d == 0
    safe = xp.where(zero, 1.0, d)
    return 4.0 * xyz[..., 0] / safe, 9.0 * xyz[..., 1] / safe, zero


def _xyz_to_luv(xp: Any, xyz: Any, w: Any) -> Any:
    wn = w[0] + 15.0 * w[1] + 3.0 * w[2]
    un, vn = 4.0 * w[0] / wn, 9.0 * w[1] / wn
    up, vp, zero = _uv_prime(xp, xyz)
    fy = _f(xp, xyz[..., 1] / w[1])
    L = 116.0 * fy - 16.0
    u = xp.where(zero, 0.0, 13.0 * L * (up - un))
    v = xp.where(zero, 0.0, 13.0 * L * (vp - vn))
    return xp.stack([L, u, v], axis=-1)


def _luv_to_xyz(xp: Any, luv: Any, w: Any) -> Any:
    wn = w[0] + 15.0 * w[1] + 3.0 * w[2]
    un, vn = 4.0 * w[0] / wn, 9.0 * w[1] / wn
    L = luv[..., 0]
    Y = w[1] * _f_inv(xp, (L + 16.0) / 116.0)
    zero = L == 0
    safe = xp.where(zero, 1.0, 13.0 * L)
    up = luv[..., 1] / safe + un
    vp = luv[..., 2] / safe + vn
    vzero = vp == 0
    vsafe = xp.where(vzero, 1.0, vp)
    X = xp.where(zero | vzero, 0.0, Y * 9.0 * up / (4.0 * vsafe))
    Z = xp.where(zero | vzero, 0.0, Y * (12.0 - 3.0 * up - 20.0 * vp) / (4.0 * vsafe))
    return xp.stack([X, Y, Z], axis=-1)


@chunkwise(1)
def xyz_to_luv(xyz: ArrayLike, white: str | ArrayLike = "D65", *, observer: int = 2) -> Array:
    r"""CIE XYZ to CIELUV.

    .. math::
        L^* = 116 f(Y/Y_n) - 16, \quad u^* = 13 L^* (u' - u'_n), \quad
        v^* = 13 L^* (v' - v'_n), \quad
        u' = \frac{4X}{X + 15Y + 3Z}, \; v' = \frac{9Y}{X + 15Y + 3Z}

    Black (X + 15Y + 3Z = 0) gives u* = v* = 0.

    Source: CIE 15:2004, clause 8.2.2, eq. (8.14)-(8.18).

    Examples
    --------
    >>> xyz_to_luv([0.18, 0.18, 0.18], white="E").round(4).tolist()
    [49.4961, 0.0, 0.0]
    """
    x = as_image_strict(xyz, "XYZ", range_check=False)
    return _xyz_to_luv(namespace(x), x, _white_arr(white, observer, x))


@chunkwise(1)
def luv_to_xyz(luv: ArrayLike, white: str | ArrayLike = "D65", *, observer: int = 2) -> Array:
    r"""CIELUV to CIE XYZ; inverse of :func:`xyz_to_luv` (L* = 0 gives black).

    .. math::
        u' = u^*/(13 L^*) + u'_n, \; v' = v^*/(13 L^*) + v'_n, \;
        X = Y \frac{9u'}{4v'}, \; Z = Y \frac{12 - 3u' - 20v'}{4v'}

    Source: CIE 15:2004, clause 8.2.2 (inverted).

    Examples
    --------
    >>> luv_to_xyz([50.0, 0.0, 0.0], white="E").round(6).tolist()
    [0.184187, 0.184187, 0.184187]
    """
    x = as_image_strict(luv, "Luv", range_check=False)
    return _luv_to_xyz(namespace(x), x, _white_arr(white, observer, x))
