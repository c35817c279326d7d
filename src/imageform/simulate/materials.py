r"""From spectra to electrons: the camera equation per material, precomputed once.

Every surface is Lambertian and receives the scene illuminance ``E_v`` (lux) from the
illuminant's spectral power distribution :math:`S(\lambda)`, scaled to

.. math:: E(\lambda) = S(\lambda)\, \frac{E_v}{K_m \sum_\lambda S V \Delta\lambda}
    \quad [\mathrm{W\,m^{-2}\,nm^{-1}}],\qquad K_m = 683\ \mathrm{lm/W}.

Its radiance is :math:`L = \rho E / \pi`, and the image irradiance on the axis of a lens
of f-number N is :math:`E_s = \pi L / (4 N^2) = \rho E / (4 N^2)` (the camera equation for
a distant object; Smith, *Modern Optical Engineering*, 4th ed., §8.5; the off-axis
:math:`\cos^4\theta` is applied per ray by the renderer). The mean photo-electrons per
second of channel c in a pixel of area A and fill factor FF are

.. math:: \dot e_c = FF\, A \sum_\lambda \frac{\rho(\lambda) E(\lambda)}{4 N^2}\,
    QE_c(\lambda)\, \frac{\lambda}{h c}\, \Delta\lambda

on a 1 nm grid over the sensor's QE range (trapezoidal weights). The QE curves,
reflectances and the illuminant are linearly interpolated onto that grid (constant beyond
their ends, CIE 015:2018 §7.2.2).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from imageform._validate import as_real, check_type, describe, real_array
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor.model import PLANCK, SPEED_OF_LIGHT, SensorModel
from imageform.spectral import (
    COLORCHECKER_PATCHES,
    colorchecker_reflectances,
    luminous_efficiency,
    spectrum_to_xyz,
)
from imageform.spectral.integrate import KM_PHOTOPIC
from imageform.spectral.spectrum import Spectrum

__all__ = ["electron_rates", "reflectance_spectrum", "scene_irradiance", "texture_basis"]


def _trapezoid(wl: np.ndarray) -> np.ndarray:
    w = np.zeros(wl.size)
    if wl.size == 1:
        return np.ones(1)
    w[:-1] += np.diff(wl) / 2
    w[1:] += np.diff(wl) / 2
    return w


def scene_irradiance(illuminant: Spectrum, illuminance_lux: float, wl: np.ndarray) -> np.ndarray:
    r"""Spectral irradiance (W m⁻² nm⁻¹) on the grid ``wl`` giving ``illuminance_lux``.

    .. math:: E(\lambda) = S(\lambda) E_v / (K_m \textstyle\sum S V \Delta\lambda)

    Examples
    --------
    >>> from imageform.spectral import illuminant
    >>> wl = np.arange(360.0, 831.0, 1.0)
    >>> E = scene_irradiance(illuminant("E"), 683.0, wl)  # 683 lx of equal energy
    >>> round(float(E[0]) * float(luminous_efficiency().interpolate(wl).values.sum()), 3)
    1.0
    """
    check_type(illuminant, Spectrum, "illuminant")
    illuminance_lux = as_real(illuminance_lux, "illuminance_lux", nonnegative=True)
    wl = real_array(wl, "wl", ndim=1, min_size=1)
    if wl[0] <= 0 or (wl.size > 1 and not np.all(np.diff(wl) > 0)):
        raise InvalidInputError(
            f"expected wl as positive, strictly increasing wavelengths (nm), got {describe(wl)}"
        )
    fine = np.arange(360.0, 831.0, 1.0)
    s_fine = illuminant.interpolate(fine).values
    v = luminous_efficiency("photopic").interpolate(fine).values
    lum = KM_PHOTOPIC * float(np.sum(s_fine * v))  # 1 nm steps
    s = illuminant.interpolate(wl).values
    return np.asarray(s * (illuminance_lux / lum))


def electron_rates(
    reflectances: np.ndarray,
    wl_reflectance: np.ndarray,
    illuminant: Spectrum,
    illuminance_lux: float,
    sensor: SensorModel,
    f_number: float,
) -> np.ndarray:
    """Mean photo-electrons per second ``(M, C)`` of M Lambertian reflectances ``(L, M)``.

    See the module docstring for the equation.

    Examples
    --------
    >>> from imageform.sensor import cmos_preset
    >>> r = electron_rates(np.ones((2, 1)), np.array([300.0, 900.0]),
    ...                    Spectrum([300.0, 900.0], [1.0, 1.0]), 1000.0,
    ...                    cmos_preset(color=True), 4.0)
    >>> r.shape, bool(r[0, 1] > r[0, 0])
    ((1, 3), True)
    """
    qe_wl = np.asarray(sensor.qe_wavelengths, dtype=np.float64)
    wl = np.arange(qe_wl[0], qe_wl[-1] + 0.5, 1.0) if qe_wl.size > 1 else qe_wl
    qe = np.stack([np.interp(wl, qe_wl, c) for c in np.asarray(sensor.qe_curves, float)])
    rho = Spectrum(wl_reflectance, reflectances).interpolate(wl).values
    rho = rho.reshape(wl.size, -1)
    E = scene_irradiance(illuminant, illuminance_lux, wl)
    photons_per_joule = wl * 1e-9 / (PLANCK * SPEED_OF_LIGHT)
    k = sensor.fill_factor * sensor.pixel_area / (4.0 * f_number**2)
    weight = k * _trapezoid(wl) * E * photons_per_joule  # (L,)
    return np.asarray((rho * weight[:, None]).T @ qe.T)


def reflectance_spectrum(value: float | str) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelengths, values)`` of a flat reflectance or a named ColorChecker patch.

    Examples
    --------
    >>> wl, r = reflectance_spectrum(0.5)
    >>> float(r.min()), float(r.max())
    (0.5, 0.5)
    """
    cc = colorchecker_reflectances()
    if isinstance(value, str):
        if value not in COLORCHECKER_PATCHES:
            raise UnknownOptionError(
                f"unknown ColorChecker patch {describe(value, 30)} for value (a reflectance "
                "in [0, 1] or a patch name such as 'dark skin')"
            )
        return cc.wavelengths, cc.values[:, COLORCHECKER_PATCHES.index(value)]
    rho = as_real(value, "value", minimum=0.0, maximum=1.0)
    return cc.wavelengths, np.full(cc.wavelengths.shape, rho)


def texture_basis() -> tuple[np.ndarray, np.ndarray]:
    r"""Return three non-negative reflectance spectra ``B`` ``(L, 3)`` with ``ρ(λ) ≈ B rgb``.

    For a linear-sRGB colour: the textured surface's reflectance is recovered from its pixel.

    Fitted per wavelength by non-negative least squares to the 24 ColorChecker spectra and
    their linear sRGB under D65: :math:`\min_{b_\lambda \ge 0} \|C b_\lambda -
    \rho_\lambda\|`, ``C`` (24, 3) (Lawson & Hanson, *Solving Least Squares Problems*,
    1974, ch. 23).

    Examples
    --------
    >>> wl, B = texture_basis()
    >>> B.shape, bool(B.min() >= 0)
    ((36, 3), True)
    """
    from imageform.color import xyz_to_linear_srgb

    cc = colorchecker_reflectances()
    rgb = np.asarray(xyz_to_linear_srgb(spectrum_to_xyz(cc, illuminant="D65")))
    B = np.stack([nnls(rgb, cc.values[i])[0] for i in range(cc.values.shape[0])])
    return cc.wavelengths, B
