"""EMVA 1288 characterisation from frame stacks, as a lab measures a camera.

:func:`measure_emva` takes, for each exposure time, a stack of ``L >= 2`` flat-field frames
and a stack of ``L >= 2`` dark frames (raw digital numbers of one channel) and returns the
EMVA 1288 parameters: system gain, temporal dark noise, quantum efficiency (when the photon
counts are known), saturation, the SNR curve, dynamic range, DSNU, PRNU and dark current.
:func:`simulate_emva_frames` records such stacks from a :class:`SensorModel` (shot, dark and
read noise, DSNU/PRNU fixed pattern, full well, ADC), so every step can be checked against
the parameters the frames were made with.

Temporal statistics come from the first two frames of a stack (the pair method); spatial
statistics (DSNU, PRNU) from the average of the whole stack, its residual temporal variance
removed. Source: EMVA Standard 1288, Release 4.0 Linear (2021); the formulas follow the
standard's reference implementation, ``emva1288`` 1.0.2 (``Data1288``, ``Results1288``),
which ``benchmarks/bench_emva.py`` runs on the same frames.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    as_shape,
    check_electrons,
    check_memory,
    check_positive,
    check_rng,
    describe,
    finite_result,
    format_shape,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.sensor.model import PLANCK, SPEED_OF_LIGHT, SensorModel, photons_per_pixel
from imageform.sensor.noise import QUANTIZATION_NOISE_DN

__all__ = ["EmvaFrames", "EmvaMeasurement", "measure_emva", "simulate_emva_frames"]

#: The floor EMVA 1288 R4.0 puts on the dark temporal variance (DN²): below it the dark
#: noise is hidden by the quantisation and ``σ_d`` is reported as an upper limit.
DARK_VARIANCE_FLOOR_DN2 = 0.24

#: The most exposure times one measurement takes.
_MAX_EXPOSURES = 10_000


@dataclass(frozen=True)
class EmvaFrames:
    """Frame stacks of an EMVA 1288 measurement (what :func:`simulate_emva_frames` records).

    ``flats`` and ``darks``: uint16 ``(n, L, H, W)``, ``L`` frames per exposure time;
    ``exposure_times`` (s) and ``photons`` (mean photons per pixel during each exposure):
    ``(n,)``.
    """

    exposure_times: np.ndarray
    photons: np.ndarray
    flats: np.ndarray
    darks: np.ndarray


@dataclass(frozen=True)
class EmvaMeasurement:
    """EMVA 1288 parameters measured from frame stacks (see :func:`measure_emva`).

    Attributes
    ----------
    system_gain : float
        ``K`` (DN/e⁻).
    dark_noise : float
        Temporal dark noise ``σ_d`` (e⁻), the quantisation noise removed.
    dark_noise_dn : float
        ``σ_y.dark`` (DN), floored at ``sqrt(0.24)`` DN.
    dark_noise_upper_limit : bool
        True when the floor applied: ``dark_noise`` is then an upper limit.
    quantum_efficiency, responsivity : float
        ``η`` and ``R = K η`` (DN/photon); NaN without photon counts.
    saturation_dn : float
        ``μ_y.sat``: the mean grey value (DN, dark not subtracted) at the saturation point,
        the exposure of largest temporal variance.
    saturation_capacity, saturation_photons : float
        ``μ_e.sat = η μ_p.sat`` (e⁻), the linear signal at the saturation point (above the
        clip by the pixels' spread), and ``μ_p.sat`` (photons; NaN without photon counts).
    saturated : bool
        The temporal variance peaks before the last exposure (else the series never
        reached saturation and the saturation values are lower bounds).
    sensitivity_threshold : float
        Absolute sensitivity threshold ``μ_e.min`` (e⁻), where the SNR is 1.
    snr_max, dynamic_range : float
        ``sqrt(μ_e.sat)`` and ``μ_e.sat / μ_e.min``; also in dB (``20 log10``) and bits
        (``log2``).
    dsnu, dsnu_dn : float
        Dark-signal non-uniformity ``DSNU_1288`` (e⁻ and DN); NaN when the corrected spatial
        variance is negative (below the measurement's noise).
    prnu : float
        Photo-response non-uniformity ``PRNU_1288`` (%).
    dark_current, dark_current_var : float
        Dark current (e⁻/s) from the slope of the dark mean, and from the slope of the dark
        variance, against exposure time.
    spatial_index : int
        The exposure whose stacks gave DSNU and PRNU (the one nearest 50 % of saturation).
    fit_points : int
        How many exposures the gain fit used (0 … 70 % of saturation).
    exposure_times, photons, mean_dn, var_dn, dark_mean_dn, dark_var_dn : ndarray (n,)
        The photon-transfer data: per exposure the pair mean and temporal variance of the
        flats and of the darks (photons NaN when not given).
    signal_electrons, snr_measured, snr_model : ndarray (n,)
        The SNR curve: ``μ_e`` per exposure, the measured SNR ``(μ_y - μ_y.dark) / σ_y``
        and the model's (eq. 13 of :func:`emva_snr`) at the same ``μ_e``.
    """

    system_gain: float
    dark_noise: float
    dark_noise_dn: float
    dark_noise_upper_limit: bool
    quantum_efficiency: float
    responsivity: float
    saturation_dn: float
    saturation_capacity: float
    saturation_photons: float
    saturated: bool
    sensitivity_threshold: float
    snr_max: float
    snr_max_db: float
    dynamic_range: float
    dynamic_range_db: float
    dynamic_range_bits: float
    dsnu: float
    dsnu_dn: float
    prnu: float
    dark_current: float
    dark_current_var: float
    spatial_index: int
    fit_points: int
    exposure_times: np.ndarray
    photons: np.ndarray
    mean_dn: np.ndarray
    var_dn: np.ndarray
    dark_mean_dn: np.ndarray
    dark_var_dn: np.ndarray
    signal_electrons: np.ndarray
    snr_measured: np.ndarray
    snr_model: np.ndarray


# -- simulation ---------------------------------------------------------------------------


def simulate_emva_frames(
    sensor: SensorModel,
    *,
    irradiance: float,
    wavelength_nm: float,
    exposure_times: ArrayLike,
    rng: RNGLike,
    frames: int = 2,
    shape: tuple[int, int] = (64, 64),
    channel: int = 0,
) -> EmvaFrames:
    """Record ``frames`` flat fields and ``frames`` dark frames at each exposure time.

    Every frame is a full :meth:`SensorModel.capture` of a uniform monochromatic irradiance
    (flats) or of darkness (darks): photon and dark-current shot noise, read noise and
    quantisation change from frame to frame; the PRNU and DSNU of the chip (``fpn_seed``)
    are the same in all of them.

    Parameters
    ----------
    sensor : SensorModel
        The sensor measured.
    irradiance : float
        Uniform irradiance on the sensor (W/m²), ``>= 0``.
    wavelength_nm : float
        Wavelength of the light (nm), for the photon count and the quantum efficiency.
    exposure_times : array (n,)
        Seconds, ``>= 0``.
    rng : int, numpy.random.Generator or None
        The temporal noise source (SPEC 7): an int seeds a new Generator.
    frames : int
        Frames per stack ``L``, ``>= 2`` (two make the temporal pair; more sharpen DSNU and
        PRNU).
    shape : (H, W)
        Size of the region of interest.
    channel : int
        Which output channel to keep.

    Returns
    -------
    EmvaFrames
        uint16 stacks ``(n, L, H, W)`` and the mean photons per pixel of each exposure
        (EMVA 1288 4.0, eq. 2).

    Examples
    --------
    >>> from imageform.sensor import cmos_preset
    >>> f = simulate_emva_frames(cmos_preset(), irradiance=0.05, wavelength_nm=550,
    ...                          exposure_times=[0.0, 1e-3], rng=0, shape=(8, 8))
    >>> f.flats.shape, f.flats.dtype.name
    ((2, 2, 8, 8), 'uint16')
    """
    if not isinstance(sensor, SensorModel):
        raise TypeError(f"expected sensor as a SensorModel, got {describe(sensor)}")
    e = check_positive(irradiance, "irradiance (W/m²)", allow_zero=True)
    times = as_real_array(exposure_times, "exposure_times (s)", ndim=(0, 1), nonnegative=True)
    times = times.ravel()
    if not 1 <= times.size <= _MAX_EXPOSURES:
        raise InvalidInputError(f"expected 1 to {_MAX_EXPOSURES} exposure_times, got {times.size}")
    n_frames = as_int(frames, "frames (per stack)", minimum=2, maximum=100_000)
    ch = as_int(channel, "channel")
    if not 0 <= ch < sensor.n_channels:
        raise InvalidInputError(f"expected channel in [0, {sensor.n_channels - 1}], got {ch}")
    h, w = as_shape(shape, "shape (H, W)", 2, copies=8 * n_frames * sensor.n_channels)
    check_memory(
        2.0 * 2 * times.size * n_frames * h * w,
        "exposure_times, frames and shape",
        f"{times.size} x 2 stacks of {n_frames} frames of {h} x {w}",
    )
    sensor.quantum_efficiency(wavelength_nm)  # checks wavelength_nm before anything runs
    lam = float(wavelength_nm) * 1e-9
    t_max = float(times.max())
    mp_max = finite_result(
        "the photon count",
        lambda: e * sensor.pixel_area * t_max * lam / (PLANCK * SPEED_OF_LIGHT),
        irradiance=e,
        exposure_times=t_max,
        wavelength_nm=wavelength_nm,
    )
    check_electrons(mp_max, "irradiance and exposure_times")
    gen = as_rng(check_rng(rng))
    flats = np.empty((times.size, n_frames, h, w), dtype=np.uint16)
    darks = np.empty_like(flats)
    flat = np.full((n_frames, h, w), e)
    dark = np.zeros((n_frames, h, w))
    for i, t in enumerate(times):
        for out, img in ((flats, flat), (darks, dark)):
            out[i] = sensor.capture(
                img,
                exposure_time=float(t),
                rng=gen,
                quantity="irradiance",
                wavelength_nm=wavelength_nm,
            )[..., ch]
    photons = np.array(
        [
            float(
                photons_per_pixel(e, wavelength_nm, pixel_area=sensor.pixel_area, exposure_time=t)
            )
            for t in times
        ]
    )
    return EmvaFrames(exposure_times=times, photons=photons, flats=flats, darks=darks)


# -- measurement --------------------------------------------------------------------------


def _stacks(value: object, name: str) -> list[np.ndarray]:
    """``value`` as a list of real ``(L, H, W)`` stacks, ``L >= 2``, finite."""
    if isinstance(value, np.ndarray):
        if value.ndim != 4:
            raise InvalidInputError(
                f"expected {name} as stacks of shape (n, L, H, W), got an array of shape "
                f"{format_shape(value.shape)}"
            )
        items: Sequence[Any] = list(value)
    elif isinstance(value, Sequence) and not isinstance(value, str | bytes):
        items = value
    else:
        raise InvalidInputError(
            f"expected {name} as a sequence of (L, H, W) frame stacks, got {describe(value)}"
        )
    out = []
    for i, s in enumerate(items):
        arr = np.asarray(s) if isinstance(s, np.ndarray) else s
        if getattr(arr, "dtype", None) is not None and arr.dtype.kind in "iu":
            if arr.ndim != 3:
                raise InvalidInputError(
                    f"expected {name}[{i}] a stack of shape (L, H, W), got "
                    f"{format_shape(arr.shape)}"
                )
            stack = arr
        else:
            stack = as_real_array(s, f"{name}[{i}]", ndim=3)
        if stack.shape[0] < 2:
            raise InvalidInputError(
                f"expected at least 2 frames in {name}[{i}], got {stack.shape[0]}"
            )
        if stack.shape[1] * stack.shape[2] < 2:
            raise InvalidInputError(
                f"expected {name}[{i}] frames of at least 2 pixels, got "
                f"{format_shape(stack.shape[1:])}"
            )
        out.append(stack)
    return out


def _pair(stack: np.ndarray) -> tuple[float, float]:
    r"""Mean and temporal variance of the first two frames (EMVA 1288 4.0, pair method).

    .. math::

        \mu_y = \tfrac12(\mu_A + \mu_B),\quad
        \sigma_y^2 = \tfrac12\,\overline{[(y_A - y_B) - (\mu_A - \mu_B)]^2}
    """
    a = stack[0].astype(np.float64)
    b = stack[1].astype(np.float64)
    d = a - b
    return float(0.5 * (a.mean() + b.mean())), float(0.5 * np.mean((d - d.mean()) ** 2))


def _spatial(stack: np.ndarray) -> tuple[float, float]:
    r"""Mean of the stack average and its spatial variance, temporal noise removed.

    .. math::

        \langle y\rangle = \frac1L\sum_l y[l],\quad
        s^2_{y} = s^2_{y.measured} - \sigma^2_{y.stack}/L

    with ``s²_y.measured`` the spatial variance (``ddof=1``) of ``⟨y⟩`` and
    ``σ²_y.stack`` the mean over pixels of the temporal variance (``ddof=1``) of the stack.
    """
    s = stack.astype(np.float64)
    n = s.shape[0]
    avg = s.mean(axis=0)
    stack_var = float(s.var(axis=0, ddof=1).mean())
    return float(avg.mean()), float(avg.var(ddof=1)) - stack_var / n


def _fit_origin(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of ``y = m x`` (a line through the origin)."""
    return float(np.dot(x, y) / np.dot(x, x))


def measure_emva(
    flats: ArrayLike,
    darks: ArrayLike,
    exposure_times: ArrayLike,
    *,
    photons: ArrayLike | None = None,
    fit_fraction: float = 0.7,
    spatial_index: int | None = None,
) -> EmvaMeasurement:
    r"""EMVA 1288 (Release 4.0 Linear) characterisation from flat-field and dark stacks.

    For each exposure time ``t_i``, ``flats[i]`` and ``darks[i]`` are stacks of ``L >= 2``
    raw frames ``(L, H, W)`` (digital numbers of one channel, a uniformly lit region of
    interest). From the first two frames of each stack (the pair method)

    .. math::

        \mu_y = \tfrac12(\mu_A + \mu_B),\qquad
        \sigma_y^2 = \tfrac12\,\overline{[(y_A - y_B) - (\mu_A - \mu_B)]^2}

    and the same for the darks (``μ_y.dark``, ``σ²_y.dark``). Then:

    - saturation: the exposure of largest ``σ²_y`` (the maximum of the photon-transfer curve);
      ``μ_e.sat = η μ_p.sat``, the linear signal at that exposure (without photon counts,
      ``μ_p`` is taken proportional to the exposure time: ``μ_e.sat = t_sat · r / K`` with
      ``r`` the slope of ``μ_y - μ_y.dark`` against ``t`` in the gain fit's range);
    - system gain ``K``: least-squares slope through the origin of
      ``σ²_y - σ²_y.dark`` against ``μ_y - μ_y.dark`` over the exposures from 0 to
      ``fit_fraction`` (70 %) of the saturation signal; responsivity ``R`` likewise of
      ``μ_y - μ_y.dark`` against ``μ_p``, and ``η = R / K``;
    - temporal dark noise: ``σ²_y.dark`` extrapolated to zero exposure (linear fit against
      ``t``; with two distinct times, the value at the shorter), floored at 0.24 DN², and
      ``σ_d = sqrt(σ²_y.dark - 1/12) / K`` (quantisation noise removed);
    - SNR: measured ``(μ_y - μ_y.dark) / σ_y``; model
      ``μ_e / sqrt(σ_d² + σ_q²/K² + μ_e)`` (eq. 13); ``SNR_max = sqrt(μ_e.sat)``;
    - absolute sensitivity threshold, the signal where the model's SNR is 1:
      ``μ_e.min = ½ + sqrt(¼ + σ²_y.dark / K²)``; dynamic range
      ``DR = μ_e.sat / μ_e.min`` (``20 log10 DR`` dB, ``log2 DR`` bits);
    - DSNU and PRNU from the stacks at ``spatial_index`` (default: the exposure nearest
      50 % of the saturation signal): the average ``⟨y⟩`` of the ``L`` frames, its spatial
      variance corrected for the temporal noise left in it,
      ``s²_y = s²_y.measured - σ²_y.stack / L``; ``DSNU = s_y.dark / K`` (e⁻),
      ``PRNU = sqrt(s²_y - s²_y.dark) / (μ_y - μ_y.dark)`` (×100 %);
    - dark current: slope of ``μ_y.dark`` against ``t``, over ``K`` (e⁻/s); and of
      ``σ²_y.dark``, over ``K²``.

    Parameters
    ----------
    flats, darks : sequence of array (L, H, W), or array (n, L, H, W)
        One stack per exposure time, ``L >= 2`` frames each (``L`` may differ between
        stacks), all frames of one size.
    exposure_times : array (n,)
        Seconds, ``>= 0``; at least two different ones.
    photons : array (n,), optional
        Mean photons per pixel of each flat exposure (``μ_p``, EMVA 1288 eq. 2): gives the
        quantum efficiency and ``μ_p.sat``.
    fit_fraction : float
        Upper end of the gain fit as a fraction of the saturation signal, in ``(0, 1]``.
    spatial_index : int, optional
        Which exposure's stacks give DSNU and PRNU.

    Returns
    -------
    EmvaMeasurement

    Raises
    ------
    DegenerateConfigurationError
        Fewer than two exposures with signal below ``fit_fraction`` of saturation, or a
        photon-transfer slope that is not positive.

    Notes
    -----
    Source: EMVA Standard 1288, Release 4.0 Linear (2021): the linear model and SNR (§2),
    the photon-transfer method (§6), dark current (§7), spatial non-uniformity with the
    ``σ²_y.stack / L`` correction (§8). The gain, QE, dark-noise and DSNU/PRNU formulas
    are those of the reference implementation ``emva1288`` 1.0.2, checked against it in
    ``benchmarks/bench_emva.py``; its threshold is the approximation
    ``μ_e.min ≈ σ_y.dark / K + ½`` of the exact root used here.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.sensor import cmos_preset
    >>> s = cmos_preset(full_well=4000.0)
    >>> f = simulate_emva_frames(s, irradiance=0.02, wavelength_nm=550,
    ...     exposure_times=np.linspace(0, 0.03, 16), rng=3, shape=(32, 32))
    >>> m = measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)
    >>> abs(m.system_gain / s.system_gain - 1) < 0.05
    True
    """
    fl = _stacks(flats, "flats")
    dk = _stacks(darks, "darks")
    times = as_real_array(exposure_times, "exposure_times (s)", ndim=1, nonnegative=True)
    n = times.size
    if len(fl) != n or len(dk) != n:
        raise InvalidInputError(
            f"expected one flat and one dark stack per exposure time ({n}), got {len(fl)} "
            f"flats and {len(dk)} darks"
        )
    sizes = {s.shape[1:] for s in (*fl, *dk)}
    if len(sizes) > 1:
        raise InvalidInputError(
            "expected flats and darks frames of one size, got "
            + ", ".join(format_shape(s) for s in sorted(sizes))
        )
    if np.unique(times).size < 2:
        raise DegenerateConfigurationError(
            "an EMVA 1288 measurement needs at least two different exposure_times"
        )
    if photons is None:
        mp = np.full(n, math.nan)
    else:
        mp = as_real_array(photons, "photons (per pixel)", ndim=1, nonnegative=True)
        if mp.size != n:
            raise InvalidInputError(
                f"expected photons with one value per exposure time ({n}), got {mp.size}"
            )
    ff = as_real(fit_fraction, "fit_fraction", positive=True, maximum=1.0)
    if spatial_index is not None:
        si_given = as_int(spatial_index, "spatial_index")
        if not 0 <= si_given < n:
            raise InvalidInputError(f"expected spatial_index in [0, {n - 1}], got {si_given}")

    flat_stats = np.array([_pair(s) for s in fl])
    dark_stats = np.array([_pair(s) for s in dk])
    mu_y, var_y = flat_stats[:, 0], flat_stats[:, 1]
    mu_d, var_d = dark_stats[:, 0], dark_stats[:, 1]
    sig = mu_y - mu_d
    tvar = var_y - var_d

    i_sat = int(np.argmax(var_y))
    sat_sig = float(sig[i_sat])
    before = times <= times[i_sat]  # the exposures up to saturation, in any given order
    use = (sig <= ff * sat_sig) & before
    signal = use & (sig > 0)
    if int(signal.sum()) < 2:
        raise DegenerateConfigurationError(
            f"only {int(signal.sum())} exposures lie between zero and {ff:.0%} of saturation "
            "(fit_fraction); record more exposure times below saturation"
        )
    k = _fit_origin(sig[use], tvar[use])
    if not k > 0:
        raise DegenerateConfigurationError(f"photon-transfer slope is not positive ({k:.3g})")
    if photons is not None and np.any(mp[use] > 0):
        resp = _fit_origin(mp[use], sig[use])
    else:
        resp = math.nan
    eta = resp / k

    distinct = np.unique(times).size
    if distinct > 2:
        var_d0 = float(np.polyfit(times, var_d, 1)[1])
    else:
        var_d0 = float(var_d[int(np.argmin(times))])
    floored = var_d0 < DARK_VARIANCE_FLOOR_DN2
    var_d0 = max(var_d0, DARK_VARIANCE_FLOOR_DN2)
    sigma_d = math.sqrt(var_d0 - QUANTIZATION_NOISE_DN**2) / k
    dark_mean_slope = float(np.polyfit(times, mu_d, 1)[0])
    dark_var_slope = float(np.polyfit(times, var_d, 1)[0])

    # μ_e.sat = η μ_p.sat: the linear signal at the saturation exposure (not the clipped
    # mean there); without photon counts, the exposure time stands for μ_p (one irradiance)
    if math.isfinite(eta):
        mu_e_sat = eta * float(mp[i_sat])
    else:
        mu_e_sat = _fit_origin(times[use], sig[use]) * float(times[i_sat]) / k
    q2 = QUANTIZATION_NOISE_DN**2 / (k * k)
    mu_e_min = 0.5 + math.sqrt(0.25 + var_d0 / (k * k))
    dr = mu_e_sat / mu_e_min

    with np.errstate(divide="ignore", invalid="ignore"):
        mu_e = eta * mp if photons is not None and math.isfinite(eta) else sig / k
        snr_meas = np.where(var_y > 0, sig / np.sqrt(np.maximum(var_y, 0)), math.nan)
        snr_model = mu_e / np.sqrt(sigma_d**2 + q2 + np.maximum(mu_e, 0.0))

    if spatial_index is None:
        si = int(np.argmin(np.where(before, np.abs(sig - 0.5 * sat_sig), np.inf)))
    else:
        si = si_given
    mu_50, s2_50 = _spatial(fl[si])
    mu_dark, s2_dark = _spatial(dk[si])
    dsnu_dn = math.sqrt(s2_dark) if s2_dark >= 0 else math.nan
    prnu_var = s2_50 - s2_dark
    prnu = (
        100.0 * math.sqrt(prnu_var) / (mu_50 - mu_dark)
        if prnu_var >= 0 and mu_50 > mu_dark
        else math.nan
    )

    def db(x: float) -> float:
        return 20.0 * math.log10(x) if x > 0 else math.nan

    return EmvaMeasurement(
        system_gain=k,
        dark_noise=sigma_d,
        dark_noise_dn=math.sqrt(var_d0),
        dark_noise_upper_limit=bool(floored),
        quantum_efficiency=float(eta),
        responsivity=float(resp),
        saturation_dn=float(mu_y[i_sat]),
        saturation_capacity=mu_e_sat,
        saturation_photons=float(mp[i_sat]),
        saturated=i_sat < n - 1,
        sensitivity_threshold=mu_e_min,
        snr_max=math.sqrt(mu_e_sat) if mu_e_sat > 0 else math.nan,
        snr_max_db=db(math.sqrt(mu_e_sat)) if mu_e_sat > 0 else math.nan,
        dynamic_range=dr,
        dynamic_range_db=db(dr),
        dynamic_range_bits=math.log2(dr) if dr > 0 else math.nan,
        dsnu=dsnu_dn / k,
        dsnu_dn=dsnu_dn,
        prnu=prnu,
        dark_current=dark_mean_slope / k,
        dark_current_var=dark_var_slope / (k * k),
        spatial_index=si,
        fit_points=int(use.sum()),
        exposure_times=times,
        photons=mp,
        mean_dn=mu_y,
        var_dn=var_y,
        dark_mean_dn=mu_d,
        dark_var_dn=var_d,
        signal_electrons=np.asarray(mu_e, dtype=np.float64),
        snr_measured=snr_meas,
        snr_model=np.asarray(snr_model, dtype=np.float64),
    )
