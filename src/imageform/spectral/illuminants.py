r"""Illuminants: Planck's law for any temperature, the CIE daylight series, the CIE tables.

Planck's law (CIE 015:2018 eq. 4.1, with the radiation constants of CODATA as CIE 015 writes
them, :math:`c_1 = 3.741771\times10^{-16}` W m², :math:`c_2 = 1.4388\times10^{-2}` m K):

.. math:: S(\lambda, T) = \frac{c_1}{\lambda^5}\,\frac{1}{e^{c_2/(\lambda T)} - 1}

Daylight (CIE 015:2018 §4.1.2, eqs. 4.3-4.5): :math:`S_D = S_0 + M_1 S_1 + M_2 S_2` with

.. math:: M_1 = \frac{-1.3515 - 1.7703 x_D + 5.9114 y_D}{0.0241 + 0.2562 x_D - 0.7341 y_D},\quad
          M_2 = \frac{0.0300 - 31.4424 x_D + 30.0717 y_D}{0.0241 + 0.2562 x_D - 0.7341 y_D}

and :math:`(x_D, y_D)` the chromaticity of the daylight, from the CCT by the CIE daylight
locus (CIE 015:2018 eqs. 4.3-4.4, the same formula as
:func:`imageform.color.cct.cct_to_xy` with ``method="daylight"``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from imageform._colormath import DAYLIGHT_RANGE, daylight_xy, uv1960_from_xy
from imageform._validate import as_bool, as_real, as_real_ndarray, check_positive, describe
from imageform.errors import InvalidInputError
from imageform.spectral.data import (
    ILLUMINANT_TABLES,
    LED_SPECTRA,
    illuminant_table,
    led_spectrum,
    load_table,
)
from imageform.spectral.spectrum import Spectrum

__all__ = [
    "C1",
    "C2",
    "PlanckianCCT",
    "blackbody_spectrum",
    "daylight_spectrum",
    "daylight_spectrum_from_xy",
    "illuminant",
    "planck",
    "planckian_cct",
]

C1 = 3.741771e-16  # W m², first radiation constant, CIE 015:2018 eq. 4.1 note
C2 = 1.4388e-2  # m K, second radiation constant as CIE 015:2018 uses it (ITS-90)

_DEFAULT_GRID = np.arange(300.0, 831.0, 1.0)

#: The domain of :func:`planck`: wavelengths 1e-3 nm to 1e12 nm, temperatures up to 1e12 K;
#: within it Planck's law is finite in float64 (beyond it, it would overflow to inf or NaN).
PLANCK_WAVELENGTH_RANGE = (1e-3, 1e12)
PLANCK_MAX_TEMPERATURE = 1e12


def _check_wavelengths_nm(lam: np.ndarray, name: str) -> None:
    lo, hi = PLANCK_WAVELENGTH_RANGE
    if lam.size and not (np.all(np.isfinite(lam)) and lam.min() >= lo and lam.max() <= hi):
        got = f"{np.min(lam):g}..{np.max(lam):g}"
        raise InvalidInputError(f"expected {name} in [{lo:g}, {hi:g}] nm, got values {got}")


def _temperature(temperature: object, name: str = "temperature") -> float:
    return as_real(temperature, f"{name} (K)", positive=True, maximum=PLANCK_MAX_TEMPERATURE)


def planck(wavelength_nm: npt.ArrayLike, temperature: float) -> np.ndarray:
    r"""Spectral radiant exitance of a black body, W m⁻² m⁻¹, at wavelengths in nm.

    .. math:: M_e(\lambda, T) = \frac{c_1}{\lambda^5}\,\frac{1}{e^{c_2/(\lambda T)} - 1}

    Source: CIE 015:2018 eq. 4.1 (Planck, 1901), constants as above.

    Parameters
    ----------
    wavelength_nm : array_like, shape (...)
        Wavelengths in nm, within ``PLANCK_WAVELENGTH_RANGE`` (1e-3 to 1e12 nm).
    temperature : float
        Temperature in kelvin, > 0 and <= 1e12 (``PLANCK_MAX_TEMPERATURE``): within these
        bounds the result is finite in float64.

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> round(float(planck(500.0, 5000.0) / planck(560.0, 5000.0)), 4)
    0.9487
    """
    t = _temperature(temperature)
    lam = as_real_ndarray(wavelength_nm, "wavelength_nm", finite=False)
    _check_wavelengths_nm(lam, "wavelength_nm")
    return _planck(lam, t)


def _planck(lam: np.ndarray, t: float) -> np.ndarray:
    m = lam * 1e-9
    with np.errstate(over="ignore", under="ignore"):
        return np.asarray(C1 / m**5 / np.expm1(C2 / (m * t)))


def blackbody_spectrum(
    temperature: float, wavelengths: npt.ArrayLike | None = None, *, normalize_at: float = 560.0
) -> Spectrum:
    """Return a black body as a :class:`Spectrum`, scaled to 100 at ``normalize_at`` nm.

    The default grid is 300-830 nm at 1 nm.

    Examples
    --------
    >>> round(float(blackbody_spectrum(2856).interpolate([400]).values[0]), 3)
    14.717
    """
    t = _temperature(temperature)
    if wavelengths is None:
        wl = _DEFAULT_GRID
    else:
        wl = as_real_ndarray(wavelengths, "wavelengths", ndim=1, min_size=1, finite=False)
        _check_wavelengths_nm(wl, "wavelengths")
    at = as_real(normalize_at, "normalize_at (nm)")
    _check_wavelengths_nm(np.array([at]), "normalize_at")
    s = _planck(wl, t)
    ref = float(_planck(np.array([at]), t)[0])
    with np.errstate(over="ignore", under="ignore"):
        out = 100.0 * s / ref if ref > 0 else np.full_like(s, np.inf)
    if not np.all(np.isfinite(out)):
        raise InvalidInputError(
            f"cannot scale a black body of temperature {t:g} K to 100 at normalize_at {at:g} nm: "
            "its exitance there underflows to 0 against the grid's; choose a closer normalize_at"
        )
    return Spectrum(wl, out, name=f"blackbody {t:g} K")


def daylight_spectrum(cct: float, *, round_m: bool = True) -> Spectrum:
    r"""CIE daylight illuminant at correlated colour temperature ``cct`` (4000-25000 K), 5 nm.

    :math:`S_D = S_0 + M_1 S_1 + M_2 S_2` (CIE 015:2018 eqs. 4.3-4.5). The nominal CCTs of
    D50 and D65 are 5000 and 6500 K on the 1931 scale of :math:`c_2`; on today's scale they
    are :math:`T \cdot 1.4388/1.4380` (5003 K, 6504 K). ``round_m=True`` rounds
    :math:`M_1, M_2` to three decimals as CIE 015:2018 §4.1.2 prescribes for the tabulated
    illuminants, which reproduces Table 1's D65 exactly.

    Examples
    --------
    >>> d65 = daylight_spectrum(6500 * 1.4388 / 1.4380)
    >>> round(float(d65.interpolate([560]).values[0]), 3)
    100.0
    """
    t = check_positive(cct, "cct (K)")
    round_m = as_bool(round_m, "round_m")
    lo, hi = DAYLIGHT_RANGE
    if not lo <= t <= hi:
        raise InvalidInputError(f"expected a daylight CCT in [{lo:g}, {hi:g}] K, got {t:g} K")
    xd, yd = (float(v) for v in daylight_xy(np, np.asarray(t, dtype=np.float64)))
    return _d_series(xd, yd, round_m, f"CIE daylight {t:g} K")


def daylight_spectrum_from_xy(xy: npt.ArrayLike, *, round_m: bool = True) -> Spectrum:
    r"""CIE D-series illuminant of chromaticity ``xy`` (300-830 nm, 5 nm).

    :math:`S_D = S_0 + M_1 S_1 + M_2 S_2` with :math:`M_1, M_2` from :math:`(x_D, y_D)`
    (CIE 015:2018 eq. 4.5), as colour-science's ``sd_CIE_illuminant_D_series`` computes it;
    ``round_m`` as in :func:`daylight_spectrum`. The CIE defines the series for
    chromaticities on the daylight locus (:func:`imageform.color.cct_to_xy` with
    ``method="daylight"``, 4000-25000 K); other ``xy`` give the spectrum of the same
    formula, whose chromaticity is not ``xy``.

    Parameters
    ----------
    xy : array_like, shape (2,)
        CIE 1931 chromaticity ``(x_D, y_D)``.
    round_m : bool
        Round :math:`M_1, M_2` to three decimals (CIE 015:2018 §4.1.2).

    Returns
    -------
    Spectrum
        Relative spectral power, 100 near 560 nm for daylight chromaticities.

    Examples
    --------
    >>> d65 = daylight_spectrum_from_xy([0.31272, 0.32903])
    >>> round(float(d65.interpolate([560]).values[0]), 3)
    100.0
    """
    round_m = as_bool(round_m, "round_m")
    v = as_real_ndarray(xy, "xy", finite=False)
    if v.shape != (2,) or not np.all(np.isfinite(v)):
        raise InvalidInputError(f"expected xy as two finite numbers, got {describe(xy)}")
    if not np.all(np.abs(v) <= 1e3):
        raise InvalidInputError(
            f"expected xy as a chromaticity (|x|, |y| <= 1000), got {describe(xy)}"
        )
    xd, yd = float(v[0]), float(v[1])
    if 0.0241 + 0.2562 * xd - 0.7341 * yd == 0.0:
        raise InvalidInputError(
            f"xy = ({xd:g}, {yd:g}) lies on 0.0241 + 0.2562 x - 0.7341 y = 0, where the CIE "
            "daylight weights M1, M2 are undefined"
        )
    return _d_series(xd, yd, round_m, f"CIE D series x={xd:.5f} y={yd:.5f}")


def _d_series(xd: float, yd: float, round_m: bool, name: str) -> Spectrum:
    """S0 + M1 S1 + M2 S2 (CIE 015:2018 eq. 4.5) at the daylight chromaticity (xd, yd)."""
    den = 0.0241 + 0.2562 * xd - 0.7341 * yd
    m1 = (-1.3515 - 1.7703 * xd + 5.9114 * yd) / den
    m2 = (0.0300 - 31.4424 * xd + 30.0717 * yd) / den
    if round_m:
        m1, m2 = round(m1, 3), round(m2, 3)
    b = load_table("daylight_basis")
    v = b.values[:, 0] + m1 * b.values[:, 1] + m2 * b.values[:, 2]
    return Spectrum(b.wavelengths, v, name=name)


def illuminant(name: str) -> Spectrum:
    """Return an illuminant by name.

    A CIE table (A, B, C, D50, D65, F2, F11), ``"E"`` (equal energy), a CIE LED (LED-B1 ...
    LED-V2), ``"D<cct>"`` (daylight series, e.g. ``"D75"`` is 7500 K on the 1931 scale, i.e.
    ``daylight_spectrum(7500 * 1.4388 / 1.4380)``), or ``"bb<T>"`` (black body at T kelvin,
    e.g. ``"bb3200"``).

    Examples
    --------
    >>> illuminant("d65").name
    'CIE D65'
    """
    return _lookup_illuminant(name, "name")


def _lookup_illuminant(value: object, name: str = "illuminant") -> Spectrum:
    """:func:`illuminant` of ``value``, the errors naming the caller's parameter ``name``.

    Examples
    --------
    >>> _lookup_illuminant("A", "test").name
    'CIE A'
    """
    if not isinstance(value, str):
        raise InvalidInputError(
            f"expected {name} as an illuminant name (str), got {describe(value)}"
        )
    key = value.strip().upper().replace("_", "-")
    if key.replace("FL", "F") in ILLUMINANT_TABLES:
        return illuminant_table(key)
    if key == "E":
        return Spectrum(_DEFAULT_GRID, np.full(_DEFAULT_GRID.shape, 100.0), name="CIE E")
    if key in LED_SPECTRA:
        return led_spectrum(key)
    if key.startswith("BB") and key[2:].replace(".", "", 1).isdigit():
        return blackbody_spectrum(float(key[2:]))
    if key.startswith("D") and key[1:].isdigit() and len(key) in (3, 4):
        return daylight_spectrum(float(key[1:]) * 100.0 * 1.4388 / 1.4380)
    valid = [*ILLUMINANT_TABLES, "E", f"{LED_SPECTRA[0]} ... {LED_SPECTRA[-1]}", "D<cct/100>"]
    raise InvalidInputError(
        f"unknown illuminant {describe(value, 30)} for {name}; valid: {', '.join(valid)}, bb<T>"
    )


class PlanckianCCT(NamedTuple):
    """The result of :func:`planckian_cct`."""

    #: Correlated colour temperature, K.
    cct: float
    #: Signed distance from the Planckian locus in CIE 1960 (u, v), positive above it.
    duv: float


def planckian_cct(xyz: npt.ArrayLike, *, observer: int = 2) -> PlanckianCCT:
    r"""CCT and Duv of one XYZ by direct search along the Planckian locus.

    The locus point :math:`(u_T, v_T)` (CIE 1960 UCS) of a black body at T is integrated from
    Planck's law and the CIE colour-matching functions (360-830 nm, 1 nm); the CCT minimises
    :math:`(u - u_T)^2 + (v - v_T)^2` over the mired scale 1e6/T in [10, 2000] (Brent).
    CIE 015:2018 §9.5 defines the CCT this way; this avoids Robertson's table interpolation
    (:func:`imageform.color.cct.xy_to_cct`) and is its reference. Duv is signed positive above
    the locus.

    Examples
    --------
    >>> t, duv = planckian_cct([1.09850, 1.0, 0.35585])  # CIE illuminant A
    >>> round(t)
    2856
    """
    from scipy.optimize import minimize_scalar

    from imageform.spectral.data import cmfs

    v = as_real_ndarray(xyz, "xyz", finite=False)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or not v.sum() > 0:
        raise InvalidInputError(
            f"expected xyz as one XYZ of shape (3,) with X+Y+Z > 0, got {describe(xyz)}"
        )
    c = cmfs(observer)
    wl = c.wavelengths

    def uv_of(t: float) -> np.ndarray:
        s = _planck(wl, t) @ c.values
        return np.stack(uv1960_from_xy(np, s[:2] / s.sum()))

    uv = np.stack(uv1960_from_xy(np, v[:2] / v.sum()))
    res = minimize_scalar(
        lambda m: float(np.sum((uv_of(1e6 / m) - uv) ** 2)),
        bounds=(10.0, 2000.0),
        method="bounded",
        options={"xatol": 1e-9},
    )
    t = 1e6 / float(res.x)
    d = uv - uv_of(t)
    tangent = uv_of(t * 1.0001) - uv_of(t)
    sign = 1.0 if tangent[0] * d[1] - tangent[1] * d[0] < 0 else -1.0
    return PlanckianCCT(t, sign * float(np.hypot(*d)))
