"""Colour difference ΔE between CIELAB colours: CIE76, CIE94, CIEDE2000 and CMC l:c.

All four take two arrays of CIELAB values ``(..., 3)`` (L* in [0, 100]) that broadcast
against each other and return the difference ``(...)``. CIE94 and CMC are asymmetric: the
first argument is the *reference* (standard) colour, whose chroma and hue set the weights.

The lecture's reading of a ΔE (:func:`describe_delta_e`): below 1 imperceptible, about 2 just
noticeable, above 10 obviously different colours.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform._backend import common_device, namespace, use_numba
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_points_strict,
    as_real,
    check_magnitude,
    check_name,
    format_shape,
)
from imageform.color import _gpu
from imageform.errors import InvalidInputError

__all__ = [
    "DELTA_E_METHODS",
    "delta_e",
    "delta_e_cie76",
    "delta_e_cie94",
    "delta_e_ciede2000",
    "delta_e_cmc",
    "describe_delta_e",
]


# CIE 116-1995, Table 1: the parametric factors of the two reference applications.
_CIE94_APPLICATIONS = {
    "graphic_arts": (1.0, 0.045, 0.015),  # kL, K1, K2
    "textiles": (2.0, 0.048, 0.014),
}

#: Below this many pixels the NumPy path stays in NumPy (compilation/call overhead).
_NUMBA_MIN_SIZE = 4096

#: The parametric factors (kL, kC, kH, l, c) are taken in [1e-3, 1e3]: the published ones are
#: 1 and 2, and outside this band the quotients overflow or vanish.
FACTOR_RANGE = (1e-3, 1e3)


def check_positive(value: object, name: str) -> float:
    """Check a parametric factor within :data:`FACTOR_RANGE`."""
    v = as_real(value, name, positive=True)
    lo, hi = FACTOR_RANGE
    if not lo <= v <= hi:
        raise InvalidInputError(f"expected {name} in [{lo:g}, {hi:g}], got {v:g}")
    return v


def _prepare(lab1: object, lab2: object) -> tuple[Any, Any, Any]:
    xp = namespace(lab1, lab2)
    dev = common_device(lab1, lab2)
    a = as_points_strict(lab1, "lab1", 3, xp=xp, device=dev)
    b = as_points_strict(lab2, "lab2", 3, xp=xp, device=dev)
    check_magnitude(a, "lab1", xp)
    check_magnitude(b, "lab2", xp)
    dtype = xp.result_type(a.dtype, b.dtype)
    a = xp.astype(a, dtype, copy=False)
    b = xp.astype(b, dtype, copy=False)
    try:
        shape = np.broadcast_shapes(tuple(a.shape), tuple(b.shape))
    except ValueError as exc:
        raise InvalidInputError(
            f"expected lab1 and lab2 of broadcastable shapes, got "
            f"{format_shape(tuple(a.shape))} and {format_shape(tuple(b.shape))}"
        ) from exc
    if tuple(a.shape) != shape:
        a = xp.broadcast_to(a, shape)
    if tuple(b.shape) != shape:
        b = xp.broadcast_to(b, shape)
    return xp, a, b


def _chroma(xp: Any, lab: Any) -> Any:
    return xp.sqrt(lab[..., 1] ** 2 + lab[..., 2] ** 2)


def _delta_h_sq(xp: Any, a1: Any, b1: Any, a2: Any, b2: Any, C1: Any, C2: Any) -> Any:
    """ΔH² = Δa² + Δb² - ΔC², in the cancellation-free form 2x²/(p + d) or 2(p - d)."""
    p = C1 * C2
    d = a1 * a2 + b1 * b2
    x = a1 * b2 - a2 * b1
    den = p + d
    ok = den > 0
    acute = xp.where(ok, 2.0 * x * x / xp.where(ok, den, 1.0), 0.0)
    obtuse = 2.0 * (p - d)
    return xp.where(d >= 0, acute, xp.where(obtuse > 0, obtuse, 0.0))


@chunkwise(1)
def delta_e_cie76(lab1: ArrayLike, lab2: ArrayLike) -> Array:
    r"""CIE 1976 colour difference ΔE*ab: the Euclidean distance in CIELAB.

    .. math:: \Delta E^*_{ab} = \sqrt{(\Delta L^*)^2 + (\Delta a^*)^2 + (\Delta b^*)^2}

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        CIELAB colours (broadcastable against each other); finite.

    Returns
    -------
    array, shape (...)

    References
    ----------
    CIE 15:2004, Colorimetry, 3rd ed., §8.2.1 (eq. 8.9). This is the lecture's ΔE*.

    Examples
    --------
    >>> float(delta_e_cie76([50.0, 0.0, 0.0], [50.0, 3.0, 4.0]))
    5.0
    """
    on_gpu = _gpu.delta_e(lab1, lab2, "de76", ())  # CUDA arrays: one kernel
    if on_gpu is not None:
        return on_gpu
    xp, a, b = _prepare(lab1, lab2)
    d = a - b
    return xp.sqrt(xp.sum(d * d, axis=-1))


@chunkwise(1)
def delta_e_cie94(
    lab1: ArrayLike,
    lab2: ArrayLike,
    *,
    application: Literal["graphic_arts", "textiles"] = "graphic_arts",
    kL: float | None = None,
    kC: float = 1.0,
    kH: float = 1.0,
) -> Array:
    r"""CIE 1994 colour difference ΔE*94 (``lab1`` is the reference).

    .. math::
        \Delta E^*_{94} = \sqrt{\left(\frac{\Delta L^*}{k_L S_L}\right)^2
            + \left(\frac{\Delta C^*_{ab}}{k_C S_C}\right)^2
            + \left(\frac{\Delta H^*_{ab}}{k_H S_H}\right)^2},\quad
        S_L = 1,\ S_C = 1 + K_1 C^*_1,\ S_H = 1 + K_2 C^*_1

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        Reference and sample CIELAB colours; finite.
    application : {"graphic_arts", "textiles"}
        ``K1, K2`` = 0.045, 0.015 (graphic arts) or 0.048, 0.014 (textiles).
    kL : float, optional
        Lightness factor > 0; 1 for graphic arts, 2 for textiles when not given.
    kC, kH : float
        Chroma and hue factors > 0.

    Returns
    -------
    array, shape (...)

    References
    ----------
    CIE 116-1995, Industrial colour-difference evaluation, eqs. (1)-(4).

    Examples
    --------
    >>> round(float(delta_e_cie94([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485])), 3)
    1.395
    """
    key = check_name(application, _CIE94_APPLICATIONS, "CIE94 application")
    kl_default, K1, K2 = _CIE94_APPLICATIONS[key]
    kL_ = kl_default if kL is None else check_positive(kL, "kL")
    kC_ = check_positive(kC, "kC")
    kH_ = check_positive(kH, "kH")
    on_gpu = _gpu.delta_e(lab1, lab2, "de94", (kL_, kC_, kH_, K1, K2))
    if on_gpu is not None:
        return on_gpu
    xp, a, b = _prepare(lab1, lab2)
    C1 = _chroma(xp, a)
    C2 = _chroma(xp, b)
    dH2 = _delta_h_sq(xp, a[..., 1], a[..., 2], b[..., 1], b[..., 2], C1, C2)
    tl = (a[..., 0] - b[..., 0]) / kL_
    tc = (C1 - C2) / (kC_ * (1.0 + K1 * C1))
    sh = kH_ * (1.0 + K2 * C1)
    return xp.sqrt(tl * tl + tc * tc + dH2 / (sh * sh))


@chunkwise(1)
def delta_e_cmc(lab1: ArrayLike, lab2: ArrayLike, *, l: float = 2.0, c: float = 1.0) -> Array:
    r"""CMC l:c colour difference (``lab1`` is the reference).

    .. math::
        \Delta E_{CMC} = \sqrt{\left(\frac{\Delta L^*}{l S_L}\right)^2
            + \left(\frac{\Delta C^*_{ab}}{c S_C}\right)^2
            + \left(\frac{\Delta H^*_{ab}}{S_H}\right)^2}

    with :math:`S_L = 0.511` for :math:`L^*_1 < 16`, else
    :math:`0.040975 L^*_1/(1 + 0.01765 L^*_1)`;
    :math:`S_C = 0.0638 C_1/(1 + 0.0131 C_1) + 0.638`; :math:`S_H = S_C (F T + 1 - F)`,
    :math:`F = \sqrt{C_1^4/(C_1^4 + 1900)}`, :math:`T = 0.56 + |0.2\cos(h_1 + 168°)|` for
    :math:`164° \le h_1 \le 345°`, else :math:`0.36 + |0.4 \cos(h_1 + 35°)|`.

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        Reference and sample CIELAB colours; finite.
    l, c : float
        Lightness and chroma weights > 0: 2:1 for acceptability (default), 1:1 for
        perceptibility.

    Returns
    -------
    array, shape (...)

    References
    ----------
    Clarke, McDonald & Rigg (1984), J. Soc. Dyers Colour. 100, 128-132; BS 6923:1988.

    Examples
    --------
    >>> round(float(delta_e_cmc([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], l=1)), 4)
    1.7387
    """
    l_ = check_positive(l, "l")
    c_ = check_positive(c, "c")
    on_gpu = _gpu.delta_e(lab1, lab2, "decmc", (l_, c_))
    if on_gpu is not None:
        return on_gpu
    xp, a, b = _prepare(lab1, lab2)
    L1, a1, b1 = a[..., 0], a[..., 1], a[..., 2]
    C1 = _chroma(xp, a)
    C2 = _chroma(xp, b)
    dH2 = _delta_h_sq(xp, a1, b1, b[..., 1], b[..., 2], C1, C2)
    h1 = xp.atan2(b1, a1) * (180.0 / math.pi)
    h1 = xp.where(h1 < 0, h1 + 360.0, h1)
    rad = math.pi / 180.0
    T = xp.where(
        (h1 >= 164.0) & (h1 <= 345.0),
        0.56 + xp.abs(0.2 * xp.cos((h1 + 168.0) * rad)),
        0.36 + xp.abs(0.4 * xp.cos((h1 + 35.0) * rad)),
    )
    C14 = C1**4
    F = xp.sqrt(C14 / (C14 + 1900.0))
    SL = xp.where(L1 < 16.0, 0.511, 0.040975 * L1 / (1.0 + 0.01765 * L1))
    SC = 0.0638 * C1 / (1.0 + 0.0131 * C1) + 0.638
    SH = SC * (F * T + 1.0 - F)
    tl = (L1 - b[..., 0]) / (l_ * SL)
    tc = (C1 - C2) / (c_ * SC)
    return xp.sqrt(tl * tl + tc * tc + dH2 / (SH * SH))


@chunkwise(1)
def delta_e_ciede2000(
    lab1: ArrayLike, lab2: ArrayLike, *, kL: float = 1.0, kC: float = 1.0, kH: float = 1.0
) -> Array:
    r"""CIEDE2000 colour difference ΔE00.

    .. math::
        \Delta E_{00} = \sqrt{\left(\frac{\Delta L'}{k_L S_L}\right)^2
            + \left(\frac{\Delta C'}{k_C S_C}\right)^2
            + \left(\frac{\Delta H'}{k_H S_H}\right)^2
            + R_T \frac{\Delta C'}{k_C S_C}\frac{\Delta H'}{k_H S_H}}

    with :math:`a' = (1 + G) a^*`, the weights :math:`S_L, S_C, S_H = 1 + 0.015 \bar C' T`
    and the rotation term :math:`R_T = -\sin(2\Delta\theta) R_C` of Sharma et al. (2005),
    eqs. (1)-(22), including their conventions for hue differences of exactly 180° and for
    zero chroma. NumPy input runs a vectorised numba kernel (see
    :mod:`imageform._kernels.delta_e` for the rearrangement that avoids trigonometry on hue
    angles); other arrays (PyTorch, with gradients) run the same algebra in their namespace.

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        CIELAB colours (broadcastable); finite.
    kL, kC, kH : float
        Parametric factors > 0 (1 under the reference conditions of CIE 142-2001).

    Returns
    -------
    array, shape (...)
        float32 for float32 input, else float64.

    References
    ----------
    CIE 142-2001, Improvement to industrial colour-difference evaluation; G. Sharma, W. Wu,
    E. N. Dalal (2005), "The CIEDE2000 color-difference formula: implementation notes,
    supplementary test data, and mathematical observations", Color Res. Appl. 30(1), 21-30.

    Examples
    --------
    Pair 1 of Sharma et al. (2005), Table 1:

    >>> round(float(delta_e_ciede2000([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485])), 4)
    2.0425
    """
    kL_ = check_positive(kL, "kL")
    kC_ = check_positive(kC, "kC")
    kH_ = check_positive(kH, "kH")
    on_gpu = _gpu.delta_e(lab1, lab2, "de00", (kL_, kC_, kH_))
    if on_gpu is not None:
        return on_gpu
    xp, a, b = _prepare(lab1, lab2)
    # the kernels module (kernel and twin) imports numba: loaded on first use
    from imageform._kernels.delta_e import ciede2000_numba, ciede2000_twin

    if use_numba(a, b, min_size=3 * _NUMBA_MIN_SIZE):
        out = ciede2000_numba(a, b, kL_, kC_, kH_)
        return out.astype(a.dtype, copy=False)
    return ciede2000_twin(xp, a, b, kL_, kC_, kH_)


@chunkwise(1)
def delta_e(
    lab1: ArrayLike,
    lab2: ArrayLike,
    method: str = "ciede2000",
    *,
    kL: float | None = None,
    kC: float = 1.0,
    kH: float = 1.0,
    application: Literal["graphic_arts", "textiles"] = "graphic_arts",
    l: float = 2.0,
    c: float = 1.0,
) -> Array:
    r"""Colour difference between CIELAB colours by the named method.

    .. math:: \Delta E = f_{\text{method}}(L^*_1 a^*_1 b^*_1,\ L^*_2 a^*_2 b^*_2)

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        CIELAB colours (broadcastable); ``lab1`` is the reference for the asymmetric
        ``"cie94"`` and ``"cmc"``.
    method : {"ciede2000", "cie76", "cie94", "cmc"}
        See :func:`delta_e_ciede2000`, :func:`delta_e_cie76` (the lecture's ΔE*),
        :func:`delta_e_cie94`, :func:`delta_e_cmc`.
    kL, kC, kH : float
        Parametric factors of CIEDE2000 and CIE94 (``kL`` defaults to 1; 2 for CIE94
        textiles).
    application : {"graphic_arts", "textiles"}
        CIE94 only.
    l, c : float
        CMC only (2:1 acceptability by default).

    Returns
    -------
    array, shape (...)

    Examples
    --------
    >>> float(delta_e([50.0, 0.0, 0.0], [50.0, 3.0, 4.0], method="cie76"))
    5.0
    """
    m = check_name(method, DELTA_E_METHODS, "ΔE method")
    # every parameter is checked, also those the chosen method does not use
    if kL is not None:
        check_positive(kL, "kL")
    for value, name in ((kC, "kC"), (kH, "kH"), (l, "l"), (c, "c")):
        check_positive(value, name)
    check_name(application, _CIE94_APPLICATIONS, "CIE94 application")
    kw: dict[str, dict[str, Any]] = {
        "cie76": {},
        "cie94": {"application": application, "kL": kL, "kC": kC, "kH": kH},
        "cmc": {"l": l, "c": c},
        "ciede2000": {"kL": 1.0 if kL is None else kL, "kC": kC, "kH": kH},
    }
    return DELTA_E_METHODS[m](lab1, lab2, **kw[m])


def describe_delta_e(value: float) -> str:
    """Return the lecture's reading of a ΔE.

    The lecture: below 1 imperceptible, about 2 just noticeable, above 10 obviously different.
    The bands: ``ΔE < 1`` "imperceptible"; ``1 <= ΔE < 3`` "just noticeable" (around the JND
    of about 2); ``3 <= ΔE <= 10`` "perceptible"; ``ΔE > 10`` "obviously different".

    Examples
    --------
    >>> describe_delta_e(0.4), describe_delta_e(2.1), describe_delta_e(25.0)
    ('imperceptible', 'just noticeable', 'obviously different')
    """
    v = as_real(value, "value as a ΔE", nonnegative=True)
    if v < 1.0:
        return "imperceptible"
    if v < 3.0:
        return "just noticeable"
    if v <= 10.0:
        return "perceptible"
    return "obviously different"


#: The methods of :func:`delta_e`, each name mapped to its function (read-only).
DELTA_E_METHODS: MappingProxyType[str, Callable[..., Any]] = MappingProxyType(
    {
        "cie76": delta_e_cie76,
        "cie94": delta_e_cie94,
        "ciede2000": delta_e_ciede2000,
        "cmc": delta_e_cmc,
    }
)
