"""More correlated-colour-temperature methods.

McCamy (1992), Hernández-Andrés (1999), Ohno (2013).

Selected through :func:`imageform.color.xy_to_cct` (``method="mccamy1992"``,
``"hernandez1999"``, ``"ohno2013"``) or called directly. McCamy's and Hernández-Andrés'
are closed-form approximations of the CCT only (their Duv is Robertson's); Ohno's searches
the Planckian locus computed from the CIE 1931 colour-matching functions and gives CCT
and Duv.
"""

from __future__ import annotations

import functools

import numpy as np

from imageform import _deprecate
from imageform._typing import Array, ArrayLike
from imageform._validate import as_points, as_real, as_real_ndarray, check_magnitude
from imageform.errors import InvalidInputError

__all__ = [
    "OHNO2013_RANGE",
    "cct_to_uv_ohno2013",
    "planckian_uv",
    "uv_to_cct_ohno2013",
    "xy_to_cct_hernandez1999",
    "xy_to_cct_mccamy1992",
]

# Its methods are in :data:`imageform.color.XY_TO_CCT_METHODS`, the one registry of
# :func:`imageform.color.xy_to_cct`; this module's tuple of three names is deprecated.
__getattr__ = _deprecate.module_getattr(
    "imageform.color.cct_methods",
    {
        "XY_TO_CCT_METHODS": (
            "imageform.color.XY_TO_CCT_METHODS (all five methods)",
            _deprecate.Lazy("imageform.color.cct", "XY_TO_CCT_METHODS"),
        )
    },
)

#: CCT range (K) of the Planckian table of :func:`uv_to_cct_ohno2013`.
OHNO2013_RANGE = (1000.0, 100000.0)
#: Temperatures :func:`planckian_uv` computes (K): below 50 K every visible term of Planck's
#: law underflows to 0 (0/0); above 1e15 K the point is its limit (0.180064, 0.263521) to 1e-10
#: and beyond ~1e280 K the sums overflow.
_PLANCK_RANGE = (50.0, 1e15)

# Second radiation constant (m K), CIE 15:2004 (ITS-90 value used in colorimetry).
_C2 = 1.4388e-2


def _xy(xy: object) -> np.ndarray:
    return np.asarray(as_points(xy, "xy", 2), dtype=np.float64)


def xy_to_cct_mccamy1992(xy: ArrayLike) -> Array:
    r"""CCT by McCamy's cubic in the epicentre slope (1992).

    .. math:: n = \frac{x - 0.3320}{y - 0.1858},\qquad
        T = -449 n^3 + 3525 n^2 - 6823.3 n + 5520.33

    Accurate to about 2 K between 2856 K and 6504 K on the Planckian locus; rougher
    outside (no Duv, no range check: it is a fit, not a search).

    Parameters
    ----------
    xy : array_like, shape (..., 2)
        CIE 1931 chromaticities.

    Returns
    -------
    ndarray, shape (...)
        Kelvin.

    Notes
    -----
    Source: C. S. McCamy, "Correlated color temperature as an explicit function of
    chromaticity coordinates", Color Res. Appl. 17(2), 1992, pp. 142-144, eq. (3); the
    erratum in Color Res. Appl. 18(2), 1993, p. 150.

    Examples
    --------
    >>> round(float(xy_to_cct_mccamy1992([0.31270, 0.32900])), 5)  # colour-science: 6505.08059
    6505.08059
    """
    a = _xy(xy)
    n = (a[..., 0] - 0.3320) / (a[..., 1] - 0.1858)
    return ((-449.0 * n + 3525.0) * n - 6823.3) * n + 5520.33


def xy_to_cct_hernandez1999(xy: ArrayLike) -> Array:
    r"""CCT by Hernández-Andrés, Lee & Romero's exponential fit (1999).

    .. math:: n = \frac{x - x_e}{y - y_e},\qquad
        T = A_0 + A_1 e^{-n/t_1} + A_2 e^{-n/t_2} + A_3 e^{-n/t_3}

    with :math:`x_e = 0.3366, y_e = 0.1735, A_0 = -949.86315, A_1 = 6253.80338,
    t_1 = 0.92159, A_2 = 28.70599, t_2 = 0.20039, A_3 = 0.00004, t_3 = 0.07125`
    (3000-50000 K) and, where that gives more than 50000 K, :math:`x_e = 0.3356,
    y_e = 0.1691, A_0 = 36284.48953, A_1 = 0.00228, t_1 = 0.07861, A_2 = 5.4535\cdot
    10^{-36}, t_2 = 0.01543` (50000 K to 8e5 K).

    Parameters
    ----------
    xy : array_like, shape (..., 2)
        CIE 1931 chromaticity coordinates.

    Returns
    -------
    ndarray, shape (...)
        Kelvin.

    Notes
    -----
    Source: J. Hernández-Andrés, R. L. Lee Jr., J. Romero, "Calculating correlated color
    temperatures across the entire gamut of daylight and skylight chromaticities",
    Appl. Opt. 38(27), 1999, pp. 5703-5709, eq. (3) and Table 1.

    Examples
    --------
    >>> round(float(xy_to_cct_hernandez1999([0.31270, 0.32900])), 5)  # colour-science
    6500.74204
    """
    a = _xy(xy)
    x, y = a[..., 0], a[..., 1]
    n = (x - 0.3366) / (y - 0.1735)
    t = (
        -949.86315
        + 6253.80338 * np.exp(-n / 0.92159)
        + 28.70599 * np.exp(-n / 0.20039)
        + 0.00004 * np.exp(-n / 0.07125)
    )
    n2 = (x - 0.3356) / (y - 0.1691)
    with np.errstate(over="ignore"):
        t2 = 36284.48953 + 0.00228 * np.exp(-n2 / 0.07861) + 5.4535e-36 * np.exp(-n2 / 0.01543)
    return np.where(t > 50000.0, t2, t)


@functools.lru_cache(maxsize=1)
def _cmf_1nm() -> tuple[np.ndarray, np.ndarray]:
    """CIE 1931 2° CMFs on 360-780 nm, 1 nm (ASTM E308's shape, colour-science's default).

    Cached and read-only: (wavelengths (M,), CMFs (M, 3)) shared by every call.
    """
    from imageform.spectral import cmfs

    c = cmfs(2)
    wl = np.asarray(c.wavelengths, dtype=np.float64)
    keep = (wl >= 360.0) & (wl <= 780.0)
    wl, cmf = wl[keep], np.asarray(c.values, dtype=np.float64)[keep]  # new arrays (a mask)
    wl.setflags(write=False)
    cmf.setflags(write=False)
    return wl, cmf


def planckian_uv(cct: ArrayLike) -> np.ndarray:
    r"""CIE 1960 ``(u, v)`` of a black body at ``cct`` kelvin (CIE 1931 2° observer).

    .. math:: X_i = \sum_\lambda \lambda^{-5} (e^{c_2/\lambda T} - 1)^{-1}
        \bar x_i(\lambda),\quad u = \frac{4X}{X + 15Y + 3Z},\;
        v = \frac{6Y}{X + 15Y + 3Z}

    summed over 360-780 nm at 1 nm, :math:`c_2 = 1.4388 \cdot 10^{-2}` m K.

    Source: Planck's law and CIE 15:2004, sec. 3.1 and 8.1 (c₂, CIE 1960 UCS).

    Examples
    --------
    >>> planckian_uv(6504).round(6).tolist()  # colour-science: [0.2004280, 0.3103334]
    [0.200428, 0.310333]
    """
    t = as_real_ndarray(cct, "cct")
    lo, hi = _PLANCK_RANGE
    if t.size and not (float(t.min()) >= lo and float(t.max()) <= hi):
        raise InvalidInputError(
            f"expected cct in [{lo:g}, {hi:g}] kelvin, "
            f"got {float(t.min()):.4g}..{float(t.max()):.4g}"
        )
    wl, cmf = _cmf_1nm()
    lam = wl * 1e-9
    with np.errstate(over="ignore"):
        spd = lam**-5 / np.expm1(_C2 / (lam * t.reshape(-1, 1)))  # (n, wl)
    xyz = spd @ cmf
    den = xyz[:, 0] + 15.0 * xyz[:, 1] + 3.0 * xyz[:, 2]
    uv = np.stack([4.0 * xyz[:, 0] / den, 6.0 * xyz[:, 1] / den], axis=-1)
    return uv.reshape((*t.shape, 2))


@functools.lru_cache(maxsize=4)
def _ohno_table(start: float, end: float, spacing: float) -> np.ndarray:
    """Tabulate (T, u, v) rows with T from ``start`` to ``end`` in geometric steps of ``spacing``.

    The steps are narrowed to 1 + (spacing - 1)/10 towards ``end`` (colour-science's cascade).
    """
    ti = [start, start + 1.0]
    nxt, step = start + 1.0, spacing
    lo, hi = OHNO2013_RANGE
    while (nxt := nxt * step) < end:
        ti.append(nxt)
        d = min(max((nxt - lo) / (hi - lo), 0.0), 1.0)
        step = spacing * (1.0 - d) + (1.0 + (spacing - 1.0) / 10.0) * d
    t = np.asarray([*ti, end - 1.0, end])
    table = np.concatenate([t[:, None], planckian_uv(t)], axis=1)
    table.setflags(write=False)
    return table


def uv_to_cct_ohno2013(
    uv: ArrayLike, *, spacing: float = 1.001, correction: bool = False
) -> tuple[Array, Array]:
    r"""CCT and Duv from CIE 1960 ``(u, v)`` by Ohno's combined method (2013/2014).

    A table of Planckian ``(T_i, u_i, v_i)`` (1000 K to 100000 K, geometric steps of
    ``spacing``) gives the nearest entry ``i`` and its neighbours, at distances
    :math:`d_{i-1}, d_i, d_{i+1}` from ``(u, v)``.

    Triangular solution (:math:`|D_{uv}| < 0.002`), with :math:`l` the distance between
    entries :math:`i \pm 1`:

    .. math:: x = \frac{d_{i-1}^2 - d_{i+1}^2 + l^2}{2l},\quad
        T = T_{i-1} + (T_{i+1} - T_{i-1})\frac{x}{l},\quad
        D_{uv} = \operatorname{sgn}(v - v_x)\sqrt{d_{i-1}^2 - x^2}

    Parabolic solution (otherwise): the parabola :math:`d(T) = aT^2 + bT + c` through
    the three distances gives :math:`T = -b/2a` and :math:`D_{uv} = \operatorname{sgn}
    (v - v_x)(aT^2 + bT + c)`.

    With the default table (0.1 % steps, narrowed towards 100000 K, as colour-science
    builds it) the interpolation error is at most 2.5e-6 relative (median 7e-7, measured
    on 2000-20000 K, Duv up to 0.02) and no correction is needed. Ohno's table has 1 %
    steps; his correction :math:`T \leftarrow 0.99991\,T` (``correction=True``,
    applied to both solutions) compensates its bias: with ``spacing=1.01`` the measured
    bias is +7e-5 to +8e-5 (median) and at most 1.2e-4, at most 5.8e-5 after the
    correction.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        CIE 1960 UCS chromaticities.
    spacing : float
        Ratio of consecutive table temperatures, > 1.
    correction : bool
        Multiply the CCT by 0.99991 (Ohno's correction for his 1 % table).

    Returns
    -------
    cct, duv : ndarrays, shape (...)

    Notes
    -----
    Source: Y. Ohno, "Practical use and calculation of CCT and Duv", LEUKOS 10(1), 2014,
    pp. 47-55 (CIE 2013 proceedings), eqs. (5)-(11).

    Examples
    --------
    >>> t, d = uv_to_cct_ohno2013([0.1978, 0.3122])  # colour-science: 6507.4748, 0.0032233
    >>> round(float(t), 2), round(float(d), 7)
    (6507.47, 0.0032233)
    """
    a = np.asarray(as_points(uv, "uv", 2), dtype=np.float64)
    check_magnitude(a, "uv")  # |uv| beyond 1e15 would overflow the squared distances
    step = as_real(spacing, "spacing")
    if not 1.0 < step <= 1.1:
        raise InvalidInputError(f"expected spacing > 1 and <= 1.1, got {step:g}")
    if step < 1.00001:  # the table would hold over 460,000 temperatures
        raise InvalidInputError(f"expected spacing >= 1.00001, got {step!r}")
    table = _ohno_table(*OHNO2013_RANGE, step)
    flat = a.reshape(-1, 2)
    cct = np.empty(flat.shape[0])
    duv = np.empty(flat.shape[0])
    n = table.shape[0]
    for s in range(0, flat.shape[0], 256):
        p = flat[s : s + 256]
        dist = np.hypot(table[None, :, 1] - p[:, 0:1], table[None, :, 2] - p[:, 1:2])
        i = np.clip(np.argmin(dist, axis=1), 1, n - 2)
        rows = np.arange(p.shape[0])
        tp, up, vp = table[i - 1].T
        t0 = table[i, 0]
        tn, un, vn = table[i + 1].T
        dp, d0, dn = dist[rows, i - 1], dist[rows, i], dist[rows, i + 1]
        ell = np.hypot(un - up, vn - vp)
        x = (dp**2 - dn**2 + ell**2) / (2.0 * ell)
        t_t = tp + (tn - tp) * (x / ell)
        vtx = vp + (vn - vp) * (x / ell)
        sign = np.sign(p[:, 1] - vtx)
        d_t = np.sqrt(np.maximum(dp**2 - x**2, 0.0)) * sign
        big = (tn - t0) * (tp - tn) * (t0 - tp)
        qa = (tp * (dn - d0) + t0 * (dp - dn) + tn * (d0 - dp)) / big
        qb = -(tp**2 * (dn - d0) + t0**2 * (dp - dn) + tn**2 * (d0 - dp)) / big
        qc = -(dp * (tn - t0) * t0 * tn + d0 * (tp - tn) * tp * tn + dn * (t0 - tp) * tp * t0) / big
        t_p = -qb / (2.0 * qa)
        d_p = (qa * t_p**2 + qb * t_p + qc) * sign
        use_p = np.abs(d_t) >= 0.002
        cct[s : s + 256] = np.where(use_p, t_p, t_t)
        duv[s : s + 256] = np.where(use_p, d_p, d_t)
    lo, hi = OHNO2013_RANGE
    out = ~((cct >= lo * (1 - 1e-9)) & (cct <= hi * (1 + 1e-9)))
    if correction:
        cct = cct * 0.99991
    if np.any(out):
        bad = flat[np.argmax(out)]
        raise InvalidInputError(
            f"uv ({bad[0]:.5g}, {bad[1]:.5g}) outside the range of the ohno2013 method "
            f"({lo:g} K to {hi:g} K)"
        )
    shape = a.shape[:-1]
    return cct.reshape(shape), duv.reshape(shape)


def cct_to_uv_ohno2013(cct: ArrayLike, duv: ArrayLike = 0.0) -> np.ndarray:
    r"""CIE 1960 ``(u, v)`` at ``cct`` kelvin, ``duv`` off the Planckian locus (Ohno 2014).

    .. math:: (u, v) = (u_0 - D_{uv} \sin\theta,\; v_0 + D_{uv} \cos\theta),\quad
        \theta = \operatorname{atan2}(v_0 - v_1, u_0 - u_1)

    with :math:`(u_0, v_0)` the Planckian point at T and :math:`(u_1, v_1)` at
    T + 0.01 K.

    Source: Ohno 2014, LEUKOS 10(1), eqs. (12)-(15).

    Examples
    --------
    >>> cct_to_uv_ohno2013(6507.4738046, 0.00322335).round(7).tolist()  # colour-science
    [0.1978, 0.3122]
    """
    t = as_real_ndarray(cct, "cct")
    d = as_real_ndarray(duv, "duv")
    if d.size and float(np.abs(d).max()) > 1.0:
        raise InvalidInputError(f"expected |duv| <= 1, got max {float(np.abs(d).max()):.4g}")
    try:
        t, d = np.broadcast_arrays(t, d)
    except ValueError:
        raise InvalidInputError(
            f"expected cct and duv of broadcastable shapes, got {t.shape} and {d.shape}"
        ) from None
    uv0 = planckian_uv(t)
    uv1 = planckian_uv(t + 0.01)
    du, dv = (uv0 - uv1)[..., 0], (uv0 - uv1)[..., 1]
    h = np.hypot(du, dv)
    return np.stack([uv0[..., 0] - d * dv / h, uv0[..., 1] + d * du / h], axis=-1)
