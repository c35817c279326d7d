r"""Integration of spectra: XYZ (CIE 015 or ASTM E308), cone LMS, camera RGB, luminance.

For a reflectance :math:`R` under an illuminant :math:`S` with colour-matching functions
:math:`\bar x, \bar y, \bar z` (CIE 015:2018 eq. 7.1-7.3):

.. math:: X = k \sum_\lambda S(\lambda) R(\lambda) \bar x(\lambda)\,\Delta\lambda,\qquad
          k = \frac{1}{\sum_\lambda S(\lambda)\bar y(\lambda)\,\Delta\lambda}

so the perfect reflecting diffuser has Y = 1 (docs/conventions.md: XYZ with white Y = 1;
CIE 015 writes k = 100/..., Y = 100). A light source (``illuminant=None``) is integrated as
:math:`X = k\sum S \bar x \Delta\lambda` with Y = 1 for the source itself, or absolutely with
:math:`k = K_m = 683` lm W⁻¹ (``absolute=True``).

The two methods:

- ``"cie015"`` (CIE 015:2018 §7.2): everything on the observer's 1 nm grid, within the range
  the illuminant covers; the sample is interpolated (method named) and extended beyond its
  range by its end values (§7.2.2).
- ``"astm_e308"`` (ASTM E308-22 §7.3, summation at the measurement interval): the functions are
  sampled at the sample's own uniform interval; beyond the sample's range its end values
  repeat, which is what E308's weights fold into the end wavelengths. E308's Tables 5-6
  (weights for 10/20 nm data computed with Lagrange interpolation) are not shipped, so at
  10 nm this differs from E308 Table 5 by a bandpass-free interpolation error of
  typically < 0.1 ΔE00 on the ColorChecker (tested).
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._validate import as_bool, check_memory, check_option, describe
from imageform.errors import InvalidInputError
from imageform.spectral.data import (
    camera_sensitivities,
    cmfs,
    cone_fundamentals,
    luminous_efficiency,
)
from imageform.spectral.illuminants import _lookup_illuminant
from imageform.spectral.spectrum import Spectrum

__all__ = [
    "INTEGRATION_METHODS",
    "KM_PHOTOPIC",
    "KM_SCOTOPIC",
    "OBSERVER_NAMES",
    "IntegrationWeights",
    "integration_weights",
    "luminance",
    "observer_functions",
    "resolve_illuminant",
    "spectrum_to_camera_rgb",
    "spectrum_to_lms",
    "spectrum_to_xyz",
]

KM_PHOTOPIC = 683.0  # lm/W, maximum photopic luminous efficacy, CIE 015:2018 §7.1 / BIPM SI
KM_SCOTOPIC = 1700.0  # lm/W, maximum scotopic luminous efficacy, CIE 015:2018 §7.1 note
INTEGRATION_METHODS = ("cie015", "astm_e308")
#: Observer names for :func:`observer_functions`: 2 / 10 (CIE CMFs), "cones" (Stockman-Sharpe).
OBSERVER_NAMES = ("2", "10", "cones")


def observer_functions(observer: int | str | Spectrum = 2) -> Spectrum:
    """Return the three sensitivity curves of an observer.

    CIE 1931 2° (``2``), CIE 1964 10° (``10``) or the Stockman & Sharpe (2000) 2° cone
    fundamentals (``"cones"``, alias ``"lms"``).

    Examples
    --------
    >>> observer_functions("cones").labels
    ('l_bar', 'm_bar', 's_bar')
    """
    if isinstance(observer, Spectrum):
        if observer.values.ndim != 2 or observer.values.shape[1] != 3:
            raise InvalidInputError(
                f"expected observer functions of shape (N, 3), got {observer.shape}"
            )
        return observer
    if isinstance(observer, bool | np.bool_) or not isinstance(observer, int | np.integer | str):
        raise TypeError(f"expected observer as 2, 10 or 'cones', got {describe(observer)}")
    key = str(observer).strip().lower().removesuffix("deg").removesuffix("°")
    key = {"lms": "cones", "ss2": "cones", "stockman_sharpe": "cones"}.get(key, key)
    key = check_option(key, OBSERVER_NAMES, "observer")
    return cone_fundamentals() if key == "cones" else cmfs(int(key))


def resolve_illuminant(
    illuminant: str | Spectrum | None, *, name: str = "illuminant"
) -> Spectrum | None:
    """Resolve an ``illuminant`` argument to a :class:`Spectrum`.

    A name is looked up with :func:`~imageform.spectral.illuminant`, a single-curve Spectrum
    is returned as it is, and ``None`` (a light source measured on its own, no illuminant)
    stays ``None``. ``name`` (keyword-only) is the parameter the errors name (a caller's
    ``test`` ...).

    Examples
    --------
    >>> resolve_illuminant("D65").name
    'CIE D65'
    >>> resolve_illuminant(None) is None
    True
    """
    if not (illuminant is None or isinstance(illuminant, Spectrum | str)):
        raise TypeError(
            f"expected {name} as an illuminant name, a Spectrum or None, got {describe(illuminant)}"
        )
    if illuminant is None or isinstance(illuminant, Spectrum):
        if isinstance(illuminant, Spectrum) and illuminant.values.ndim != 1:
            raise InvalidInputError(
                f"expected {name} as a single-curve illuminant, got {illuminant.shape}"
            )
        return illuminant
    return _lookup_illuminant(illuminant, name)


def _as_spectrum(s: object, name: str) -> Spectrum:
    if not isinstance(s, Spectrum):
        raise InvalidInputError(f"expected {name} as a Spectrum, got {describe(s)}")
    return s


@lru_cache(maxsize=64)
def _grid(lo: float, hi: float, step: float) -> np.ndarray:
    """Return the integration grid (cached, read-only: :func:`integration_weights` hands it out)."""
    n = int(np.floor((hi - lo) / step + 1e-9))
    grid = lo + step * np.arange(n + 1, dtype=np.float64)
    grid.setflags(write=False)
    return grid


class IntegrationWeights(NamedTuple):
    """The result of :func:`integration_weights`."""

    #: The integration grid, shape (M,), nm.
    wavelengths: np.ndarray
    #: :math:`W_{\lambda,c}`, shape (M, 3).
    weights: np.ndarray


@_deprecate.parameters(positional=("illuminant",))
def integration_weights(
    functions: Spectrum,
    *,
    illuminant: Spectrum | None,
    method: str = "cie015",
    sample: Spectrum | None = None,
) -> IntegrationWeights:
    r"""Return the grid and weights :math:`W_{\lambda,c} = S(\lambda) f_c(\lambda)\Delta\lambda`.

    Returns ``IntegrationWeights(wavelengths (M,), weights (M, 3))``:
    ``X_c = sum_l R(l) W_{l,c}``. ``illuminant`` (keyword-only; ``None`` for a light) is
    interpolated linearly (CIE 015:2018 §7.2.1 for the D series); ``sample`` fixes the
    interval for ``"astm_e308"``.
    """
    m = check_option(method, INTEGRATION_METHODS, "integration method")
    functions = observer_functions(_as_spectrum(functions, "functions"))  # checks (N, 3)
    illuminant = resolve_illuminant(illuminant)
    if sample is not None:
        _as_spectrum(sample, "sample")
    lo, hi = functions.range
    if illuminant is not None:
        lo, hi = max(lo, illuminant.range[0]), min(hi, illuminant.range[1])
        if not hi > lo:
            raise InvalidInputError(
                f"expected an illuminant overlapping the functions' {functions.range[0]:g}-"
                f"{functions.range[1]:g} nm, got {illuminant.range[0]:g}-{illuminant.range[1]:g} nm"
            )
    if m == "cie015":
        step = 1.0
        lo = float(np.ceil(lo))
    else:
        if sample is None or sample.interval is None:
            raise InvalidInputError("ASTM E308 summation needs a uniformly sampled spectrum")
        step = sample.interval
        first = sample.wavelengths[0]
        lo = first + step * np.ceil((lo - first) / step - 1e-9)
    # the grid and its (M, 3) weights are bounded before they are built
    check_memory(min(64.0 * ((hi - lo) / step + 1.0), 2.0**80), "functions", "the integration grid")
    return IntegrationWeights(*_weights(functions, illuminant, float(lo), float(hi), float(step)))


@lru_cache(maxsize=128)
def _weights(
    functions: Spectrum, illuminant: Spectrum | None, lo: float, hi: float, step: float
) -> tuple[np.ndarray, np.ndarray]:
    # cached per (immutable) Spectrum object: the shipped tables are shared objects
    grid = _grid(lo, hi, step)
    f = functions.interpolate(grid, extrapolate="error").values
    s = (
        np.ones_like(grid)
        if illuminant is None
        else illuminant.interpolate(grid, extrapolate="error").values
    )
    w = f * (s * step)[:, None]
    w.setflags(write=False)
    return grid, w


def _integrate(
    spectrum: Spectrum,
    functions: Spectrum,
    illuminant: Spectrum | None,
    method: str,
    interpolation: str,
) -> tuple[np.ndarray, np.ndarray]:
    """(values (..., 3), white (3,)): raw sums for the sample and for the perfect white."""
    grid, w = integration_weights(functions, illuminant=illuminant, method=method, sample=spectrum)
    r = spectrum.interpolate(grid, method=interpolation, extrapolate="constant").values
    out = r.T @ w if r.ndim == 2 else r @ w
    return out, w.sum(axis=0)


@_deprecate.parameters(positional=("illuminant",))
def spectrum_to_xyz(
    spectrum: Spectrum,
    *,
    illuminant: str | Spectrum | None = "D65",
    observer: int | str = 2,
    method: str = "cie015",
    interpolation: str = "linear",
    absolute: bool = False,
) -> np.ndarray:
    r"""CIE XYZ of a reflectance under an illuminant, or of a light (``illuminant=None``).

    .. math:: X = \frac{\sum S R \bar x\,\Delta\lambda}{\sum S \bar y\,\Delta\lambda}

    Parameters
    ----------
    spectrum : Spectrum, values (N,) or (N, K)
        Reflectance factors (or a spectral power distribution when ``illuminant is None``).
    illuminant : str, Spectrum or None, keyword-only
        Name (see :func:`imageform.spectral.illuminant`) or spectrum.
    observer : 2, 10
        CIE 1931 2° or CIE 1964 10° standard observer.
    method : {"cie015", "astm_e308"}
        CIE 015 summation on the observer's 1 nm grid, or ASTM E308 summation at the
        sample's own interval (see the module docstring).
    interpolation : str
        How the sample is interpolated onto the integration grid (``Spectrum.interpolate``).
    absolute : bool
        For lights only: :math:`k = K_m = 683` lm/W instead of Y = 1.

    Returns
    -------
    ndarray, shape (3,) or (K, 3)
        XYZ with the perfect white (or the light) at Y = 1.

    Notes
    -----
    Source: CIE 015:2018 §7.1-7.2, eqs. 7.1-7.3; ASTM E308-22 §7.3.

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> xyz = spectrum_to_xyz(colorchecker_reflectances()["white 9.5 (.05 D)"])
    >>> round(float(xyz[1]), 4)
    0.9123
    """
    s = _as_spectrum(spectrum, "spectrum")
    absolute = as_bool(absolute, "absolute")
    f = observer_functions(observer)
    if str(observer).strip().lower() in ("cones", "lms"):
        raise InvalidInputError("spectrum_to_xyz needs observer 2 or 10; use spectrum_to_lms")
    ill = resolve_illuminant(illuminant)
    out, white = _integrate(s, f, ill, method, interpolation)
    if ill is None:
        if absolute:
            return np.asarray(out * KM_PHOTOPIC)
        if np.any(out[..., 1] == 0):
            raise InvalidInputError("the light has zero luminance; cannot normalise to Y = 1")
        return np.asarray(out / (out[..., 1:2] if out.ndim == 2 else out[1]))
    if absolute:
        raise InvalidInputError("absolute=True applies to lights (illuminant=None) only")
    return np.asarray(out / white[1])


@_deprecate.parameters(positional=("illuminant",))
def spectrum_to_lms(
    spectrum: Spectrum,
    *,
    illuminant: str | Spectrum | None = "D65",
    method: str = "cie015",
    interpolation: str = "linear",
) -> np.ndarray:
    r"""Cone excitations L, M, S (Stockman & Sharpe 2000, 2°) of a reflectance or a light.

    Under an illuminant each cone is normalised to the perfect white (von Kries):
    :math:`L = \sum S R \bar l / \sum S \bar l`; a light (``illuminant=None``) gives the raw
    sums :math:`\sum S \bar l \Delta\lambda` (input units × nm).

    Returns
    -------
    ndarray, shape (3,) or (K, 3)

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> [round(float(v), 3) for v in spectrum_to_lms(colorchecker_reflectances()["red"])]
    [0.141, 0.073, 0.046]
    """
    s = _as_spectrum(spectrum, "spectrum")
    ill = resolve_illuminant(illuminant)
    out, white = _integrate(s, cone_fundamentals(), ill, method, interpolation)
    return np.asarray(out if ill is None else out / white)


@_deprecate.parameters(positional=("illuminant",))
def spectrum_to_camera_rgb(
    spectrum: Spectrum,
    *,
    illuminant: str | Spectrum | None = "D65",
    camera: str | Spectrum = "nikon_d5100",
    method: str = "cie015",
    interpolation: str = "linear",
) -> np.ndarray:
    r"""Raw camera RGB of a reflectance (or light) through measured spectral sensitivities.

    Under an illuminant, normalised so the perfect white has G = 1 (not white balanced):
    :math:`c = \sum S R \bar c / \sum S \bar g`.

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> rgb = spectrum_to_camera_rgb(colorchecker_reflectances()["white 9.5 (.05 D)"])
    >>> round(float(rgb[1]), 3)
    0.907
    """
    s = _as_spectrum(spectrum, "spectrum")
    sens = camera if isinstance(camera, Spectrum) else camera_sensitivities(camera)
    sens = observer_functions(sens)  # checks the shape (N, 3)
    ill = resolve_illuminant(illuminant)
    out, white = _integrate(s, sens, ill, method, interpolation)
    return np.asarray(out if ill is None else out / white[1])


def luminance(spectrum: Spectrum, *, scotopic: bool = False) -> float | np.ndarray:
    r"""Compute photopic or scotopic luminance.

    Photopic: :math:`K_m \int S V \mathrm{d}\lambda`; scotopic:
    :math:`K'_m \int S V' \mathrm{d}\lambda`.

    With spectral radiance in W sr⁻¹ m⁻² nm⁻¹ the result is in cd m⁻² (photopic,
    :math:`K_m = 683` lm/W) or scotopic cd m⁻² (:math:`K'_m = 1700` lm/W); CIE 015:2018 §7.1.
    Summed on the V-function's 1 nm grid (sample interpolated linearly, zero outside).

    Examples
    --------
    >>> import numpy as np
    >>> flat = Spectrum(np.arange(360.0, 831.0), np.full(471, 0.01))
    >>> round(float(luminance(flat)), 2)
    729.83
    """
    s = _as_spectrum(spectrum, "spectrum")
    scotopic = as_bool(scotopic, "scotopic")
    v = luminous_efficiency("scotopic" if scotopic else "photopic")
    r = s.interpolate(v.wavelengths, extrapolate="zero").values
    km = KM_SCOTOPIC if scotopic else KM_PHOTOPIC
    out = km * (r.T @ v.values if r.ndim == 2 else r @ v.values) * 1.0
    return float(out) if np.ndim(out) == 0 else np.asarray(out)
