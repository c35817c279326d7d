"""EMVA 1288 characterisation: the photon-transfer curve and what it reveals.

A real sensor is measured by recording pairs of flat fields (and pairs of dark frames) at
increasing exposure. Differencing a pair removes the fixed pattern; half the variance of the
difference is the temporal noise. The photon-transfer curve, temporal variance against mean
signal (both dark-corrected), is a straight line of slope ``K`` (the system gain, DN/e⁻)
up to saturation; the dark variance extrapolated to zero exposure gives the read noise.
:func:`simulate_photon_transfer` runs that measurement on a :class:`SensorModel`;
:func:`fit_photon_transfer` recovers the parameters.

Source: EMVA Standard 1288, Release 4.0 Linear (2021), §§4–6 (eqs. 9, 29–35).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    as_shape,
    check_electrons,
    check_positive,
    check_rng,
    describe,
    finite_result,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.sensor.model import PLANCK, SPEED_OF_LIGHT, SensorModel, photons_per_pixel
from imageform.sensor.noise import QUANTIZATION_NOISE_DN

__all__ = [
    "EmvaResult",
    "PhotonTransferData",
    "fit_photon_transfer",
    "simulate_photon_transfer",
]


@dataclass(frozen=True)
class PhotonTransferData:
    """Per exposure time: mean photons per pixel, mean and temporal variance of flats and darks.

    Mean and temporal variance are in DN and DN², of the flat fields and of the dark frames.
    All arrays have shape ``(n,)``.
    """

    exposure_times: np.ndarray
    photons: np.ndarray
    mean_dn: np.ndarray
    var_dn: np.ndarray
    dark_mean_dn: np.ndarray
    dark_var_dn: np.ndarray


@dataclass(frozen=True)
class EmvaResult:
    """Parameters recovered from a photon-transfer measurement.

    ``system_gain`` K (DN/e⁻); ``read_noise`` σ_d0 (e⁻, temporal dark noise at zero
    exposure, NaN when it is below the quantisation noise); ``quantum_efficiency`` η;
    ``dark_current`` (e⁻/s); ``saturation_dn`` μ_y.sat and ``saturation_capacity``
    μ_e.sat (e⁻); ``fit_points``: how many exposures the gain fit used.
    """

    system_gain: float
    read_noise: float
    quantum_efficiency: float
    dark_current: float
    saturation_dn: float
    saturation_capacity: float
    fit_points: int


def _pair_stats(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    a = a.astype(np.float64)
    b = b.astype(np.float64)
    return float(0.5 * (a.mean() + b.mean())), float(0.5 * np.var(a - b))


def simulate_photon_transfer(
    sensor: SensorModel,
    *,
    irradiance: float,
    wavelength_nm: float,
    exposure_times: ArrayLike,
    rng: RNGLike,
    shape: tuple[int, int] = (64, 64),
    channel: int = 0,
) -> PhotonTransferData:
    r"""Record flat-field and dark pairs at each exposure time, EMVA 1288 style.

    .. math::

        \mu_y = \tfrac12(\bar y_A + \bar y_B),\quad
        \sigma_y^2 = \tfrac12 \operatorname{var}(y_A - y_B)

    Parameters
    ----------
    sensor : SensorModel
        The sensor measured.
    irradiance : float
        Uniform monochromatic irradiance on the sensor (W/m²).
    wavelength_nm : float
        Wavelength of the light (nm), for the photon count and the quantum efficiency.
    exposure_times : array (n,)
        Seconds, ``>= 0``.
    rng : int, numpy.random.Generator or None
        The temporal noise source (SPEC 7): an int seeds a new Generator.
    shape : (H, W)
        Size of the simulated region of interest.
    channel : int
        Which output channel to analyse.

    Notes
    -----
    Source: EMVA 1288 4.0, §6.1 (photon-transfer method, varying exposure time) and
    eqs. (29)–(30).

    Examples
    --------
    >>> from imageform.sensor import cmos_preset
    >>> d = simulate_photon_transfer(cmos_preset(), irradiance=0.05, wavelength_nm=550,
    ...                              exposure_times=[1e-3], rng=0, shape=(8, 8))
    >>> d.mean_dn.shape
    (1,)
    """
    if not isinstance(sensor, SensorModel):
        raise TypeError(f"expected sensor as a SensorModel, got {describe(sensor)}")
    e = check_positive(irradiance, "irradiance (W/m²)", allow_zero=True)
    times = as_real_array(exposure_times, "exposure_times (s)", ndim=(0, 1), nonnegative=True)
    times = times.ravel()
    if times.size < 1:
        raise InvalidInputError("expected exposure_times: finite, >= 0 seconds, at least one")
    if times.size > _MAX_EXPOSURES:
        raise InvalidInputError(
            f"expected at most {_MAX_EXPOSURES} exposure_times, got {times.size}"
        )
    ch = as_int(channel, "channel")
    if not 0 <= ch < sensor.n_channels:
        raise InvalidInputError(f"expected channel in [0, {sensor.n_channels - 1}], got {ch}")
    h, w = as_shape(shape, "shape (H, W)", 2, copies=12 * sensor.n_channels)
    sensor.quantum_efficiency(wavelength_nm)  # checks wavelength_nm before anything runs
    t_max = float(times.max())
    lam = float(wavelength_nm) * 1e-9
    mp_max = finite_result(
        "the photon count",
        lambda: e * sensor.pixel_area * t_max * lam / (PLANCK * SPEED_OF_LIGHT),
        irradiance=e,
        exposure_times=t_max,
        wavelength_nm=lam * 1e9,
    )
    check_electrons(mp_max, "irradiance, exposure_times and wavelength_nm")
    gen = as_rng(check_rng(rng))
    flat = np.full((h, w), e)
    dark = np.zeros((h, w))
    rows: list[tuple[float, float, float, float, float]] = []
    for t in times:
        frames = [
            sensor.capture(
                img,
                exposure_time=float(t),
                rng=gen,
                quantity="irradiance",
                wavelength_nm=wavelength_nm,
            )[..., ch]
            for img in (flat, flat, dark, dark)
        ]
        mu, var = _pair_stats(frames[0], frames[1])
        mu_d, var_d = _pair_stats(frames[2], frames[3])
        mp = float(
            photons_per_pixel(e, wavelength_nm, pixel_area=sensor.pixel_area, exposure_time=t)
        )
        rows.append((mp, mu, var, mu_d, var_d))
    arr = np.asarray(rows)
    return PhotonTransferData(
        exposure_times=times,
        photons=arr[:, 0],
        mean_dn=arr[:, 1],
        var_dn=arr[:, 2],
        dark_mean_dn=arr[:, 3],
        dark_var_dn=arr[:, 4],
    )


#: The most exposure times :func:`simulate_photon_transfer` records (four frames each).
_MAX_EXPOSURES = 100_000

_PTC_FIELDS = ("exposure_times", "photons", "mean_dn", "var_dn", "dark_mean_dn", "dark_var_dn")


def _check_data(data: object) -> dict[str, np.ndarray]:
    """Check the arrays of a :class:`PhotonTransferData`: 1-D, finite, all of one length."""
    if not isinstance(data, PhotonTransferData):
        raise TypeError(f"expected data as a PhotonTransferData, got {describe(data)}")
    arrays = {f: as_real_array(getattr(data, f), f"data.{f}", ndim=1) for f in _PTC_FIELDS}
    n = {a.size for a in arrays.values()}
    if len(n) != 1:
        sizes = ", ".join(f"{k} {v.size}" for k, v in arrays.items())
        raise InvalidInputError(f"expected data's arrays of one length, got {sizes}")
    return arrays


def fit_photon_transfer(data: PhotonTransferData, *, fit_fraction: float = 0.7) -> EmvaResult:
    r"""Recover system gain, read noise, QE, dark current and saturation from a PTC.

    .. math::

        \sigma_y^2 - \sigma_{y,dark}^2 = K (\mu_y - \mu_{y,dark}),\qquad
        \mu_y - \mu_{y,dark} = K \eta\, \mu_p

        \sigma_{y,dark}^2(t) = K^2 (\sigma_{d0}^2 + \mu_I t) + \sigma_q^2

    Saturation is the exposure of largest temporal variance (EMVA 1288 4.0, §6.5); the gain
    and responsivity are fitted by least squares over the points from above zero up to
    ``fit_fraction`` (70 %) of the saturation signal (§6.3, eq. 31); the read noise is the
    zero-exposure intercept of the dark variance against exposure time, with the
    quantisation noise ``σ_q² = 1/12`` DN² removed (§6.2, eq. 33 and §7.1).

    Raises
    ------
    DegenerateConfigurationError
        Fewer than two usable points below saturation, or fewer than two exposure times.

    Examples
    --------
    >>> from imageform.sensor import cmos_preset
    >>> s = cmos_preset(prnu=0.0)
    >>> d = simulate_photon_transfer(s, irradiance=0.05, wavelength_nm=550,
    ...     exposure_times=np.linspace(0, 4e-3, 12), rng=1, shape=(48, 48))
    >>> r = fit_photon_transfer(d)
    >>> abs(r.system_gain / s.system_gain - 1) < 0.05
    True
    """
    arrays = _check_data(data)
    ff = as_real(fit_fraction, "fit_fraction", positive=True, maximum=1.0)
    t = arrays["exposure_times"]
    if t.size < 2 or np.unique(t).size < 2:
        raise DegenerateConfigurationError(
            "a photon-transfer fit needs at least two different exposure times"
        )
    with np.errstate(all="ignore"):
        sig = arrays["mean_dn"] - arrays["dark_mean_dn"]
        var = arrays["var_dn"] - arrays["dark_var_dn"]
    i_sat = int(np.argmax(arrays["var_dn"]))
    sat_sig = sig[i_sat]
    use = (sig > 0) & (sig <= ff * sat_sig)
    if int(use.sum()) < 2:
        raise DegenerateConfigurationError(
            f"only {int(use.sum())} exposures lie between zero and {ff:.0%} of saturation "
            "(fit_fraction); record more exposure times below saturation"
        )
    k, _ = np.polyfit(sig[use], var[use], 1)
    if k <= 0:
        raise DegenerateConfigurationError(f"photon-transfer slope is not positive ({k:.3g})")
    mp = data.photons[use]
    responsivity = float(np.dot(mp, sig[use]) / np.dot(mp, mp)) if np.any(mp > 0) else math.nan
    icpt_d = float(np.polyfit(t, data.dark_var_dn, 1)[1])
    dark_mean_slope = float(np.polyfit(t, data.dark_mean_dn, 1)[0])
    temporal = icpt_d - QUANTIZATION_NOISE_DN**2
    read = math.sqrt(temporal) / k if temporal > 0 else math.nan
    return EmvaResult(
        system_gain=float(k),
        read_noise=float(read),
        quantum_efficiency=responsivity / float(k),
        dark_current=dark_mean_slope / float(k),
        saturation_dn=float(data.mean_dn[i_sat]),
        saturation_capacity=float(sat_sig / k),
        fit_points=int(use.sum()),
    )
