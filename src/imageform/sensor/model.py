"""A linear image-sensor model in the sense of EMVA 1288, with fixed-pattern noise and an ADC.

The signal chain of one pixel, for one exposure of ``t`` seconds:

1. photons on the pixel area ``μ_p`` (from spectral or monochromatic irradiance, or given);
2. mean photo-electrons ``μ_e = FF · Σ_λ QE_c(λ) μ_p(λ)``, times the pixel's PRNU gain;
3. photon shot noise: ``Poisson(μ_e)``; dark current: ``Poisson(I_dark t)``;
4. saturation at the full-well capacity;
5. read noise ``N(0, σ_read²)``, DSNU and CMOS column offsets (electrons);
6. system gain ``K = G_conv · G_analog · (2^b - 1) / V_ADC`` (DN/e⁻), black level, and an
   ``b``-bit ADC that rounds and saturates at ``0`` and ``2^b - 1``.

Saturation at full well and at the ADC's range is physics, not a repair; everything else is
linear. Source: EMVA Standard 1288, Release 4.0 (2021), §2 (the linear camera model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    as_shape,
    check_electrons,
    check_memory,
    check_option,
    check_positive,
    check_real_values,
    check_rng,
    describe,
    finite_result,
    format_shape,
)
from imageform.errors import InvalidInputError
from imageform.sensor.noise import FixedPattern, fixed_pattern

__all__ = ["PLANCK", "SPEED_OF_LIGHT", "SensorModel", "photons_per_pixel"]

#: Planck constant, J s (exact, SI 2019 definition).
PLANCK = 6.62607015e-34
#: Speed of light in vacuum, m/s (exact, SI definition).
SPEED_OF_LIGHT = 299792458.0

#: What a signal given to :meth:`SensorModel.capture` holds (its ``quantity=``).
_QUANTITIES = ("electrons", "photons", "irradiance")


def _positive_field(obj: object, name: str, *, allow_zero: bool = False) -> None:
    check_positive(getattr(obj, name), name, allow_zero=allow_zero)


def photons_per_pixel(
    irradiance: ArrayLike, wavelength_nm: float, *, pixel_area: float, exposure_time: float
) -> np.ndarray:
    r"""Mean photons reaching a pixel: irradiance × area × time over the photon energy.

    .. math::

        \mu_p = \frac{E A t \lambda}{h c}

    ``irradiance`` in W/m², ``pixel_area`` in m², ``exposure_time`` in s. Source: EMVA 1288
    4.0, eq. (2).

    Examples
    --------
    >>> round(float(photons_per_pixel(1e-3, 550, pixel_area=25e-12, exposure_time=1e-3)), 2)
    69.22
    """
    lam = check_positive(wavelength_nm, "wavelength_nm") * 1e-9
    a = check_positive(pixel_area, "pixel_area (m²)")
    t = check_positive(exposure_time, "exposure_time (s)", allow_zero=True)
    e = as_real_array(irradiance, "irradiance (W/m²)")
    return finite_result(
        "the photon count",
        lambda: e * a * t * lam / (PLANCK * SPEED_OF_LIGHT),
        irradiance=e,
        wavelength_nm=lam * 1e9,
        pixel_area=a,
        exposure_time=t,
    )


@dataclass(frozen=True)
class SensorModel:
    """Parameters of an image sensor; :meth:`capture` turns light into digital numbers.

    Lengths in metres, times in seconds, charges in electrons (e⁻), voltages in volts.

    Attributes
    ----------
    name : str
    architecture : {"cmos", "ccd"}
    shutter : {"global", "rolling"}
    pixel_pitch : float
        Pixel pitch (m).
    fill_factor : float
        Photosensitive fraction of the pixel area, ``0 < FF <= 1`` (microlenses raise it).
    qe_wavelengths : tuple of float
        Wavelengths (nm) at which the quantum-efficiency curves are sampled, increasing.
    qe_curves : tuple of tuple of float
        One QE curve per output channel (``C`` curves, values in [0, 1]).
    full_well : float
        Full-well capacity (e⁻).
    conversion_gain : float
        Sense-node conversion gain (V/e⁻), e.g. ``60e-6``.
    adc_range : float
        Input range of the ADC (V).
    analog_gain : float
        Programmable gain before the ADC (the "ISO" setting), ``>= 1`` typically.
    bit_depth : int
        ADC resolution (1 … 16 bits).
    black_level : float
        Offset added before the ADC (DN).
    dark_current : float
        Mean dark current (e⁻/s per pixel).
    read_noise : float
        Temporal read noise (e⁻ rms).
    dsnu, prnu, column_fpn : float
        Dark-signal non-uniformity (e⁻ rms), photo-response non-uniformity (fraction) and
        column offsets of column-parallel CMOS read-out (e⁻ rms).
    line_time : float
        Time between the read-out of consecutive rows (s); a rolling shutter starts each row
        this much later than the one above.
    power : float
        Typical power consumption (W), for the CCD/CMOS comparison.
    fpn_seed : int
        Seed of the chip's fixed pattern (the same chip in every frame). An int on purpose,
        not an ``rng``: it is part of the chip's identity, drawn again identically each time.

    Examples
    --------
    >>> s = SensorModel(conversion_gain=50e-6, adc_range=1.0, bit_depth=12)
    >>> round(s.system_gain, 5)  # DN per electron
    0.20475
    """

    name: str = "sensor"
    architecture: str = "cmos"
    shutter: str = "rolling"
    pixel_pitch: float = 3.45e-6
    fill_factor: float = 1.0
    qe_wavelengths: tuple[float, ...] = (550.0,)
    qe_curves: tuple[tuple[float, ...], ...] = ((0.6,),)
    full_well: float = 10000.0
    conversion_gain: float = 60e-6
    adc_range: float = 1.0
    analog_gain: float = 1.0
    bit_depth: int = 12
    black_level: float = 64.0
    dark_current: float = 5.0
    read_noise: float = 3.0
    dsnu: float = 1.0
    prnu: float = 0.01
    column_fpn: float = 0.0
    line_time: float = 10e-6
    power: float = 0.5
    fpn_seed: int = 0

    def __post_init__(self) -> None:
        """Check every parameter: options by name, gains and noise levels real and in range."""
        if not isinstance(self.name, str):
            raise InvalidInputError(f"expected name as a str, got {describe(self.name)}")
        check_option(self.architecture, ("cmos", "ccd"), "sensor architecture")
        check_option(self.shutter, ("global", "rolling"), "shutter")
        for name in ("pixel_pitch", "full_well", "conversion_gain", "adc_range", "analog_gain"):
            _positive_field(self, name)
        for name in ("black_level", "dark_current", "read_noise", "dsnu", "prnu"):
            _positive_field(self, name, allow_zero=True)
        for name in ("column_fpn", "line_time", "power"):
            _positive_field(self, name, allow_zero=True)
        ff = as_real(self.fill_factor, "fill_factor")
        if not 0 < ff <= 1:
            raise InvalidInputError(f"expected 0 < fill_factor <= 1, got {ff:g}")
        # NumPy integers are integers: stored as int so that 2**bit_depth stays exact
        bits = as_int(self.bit_depth, "bit_depth (an int in 1..16)", minimum=1, maximum=16)
        object.__setattr__(self, "bit_depth", bits)
        object.__setattr__(self, "fpn_seed", as_int(self.fpn_seed, "fpn_seed", minimum=0))
        if self.black_level >= self.max_dn:
            raise InvalidInputError(
                f"expected black_level below the ADC's largest code {self.max_dn} "
                f"(bit_depth {bits}), got {self.black_level:g}"
            )
        wl = as_real_array(self.qe_wavelengths, "qe_wavelengths (nm)", ndim=1, positive=True)
        if wl.size < 1 or np.any(np.diff(wl) <= 0):
            raise InvalidInputError("expected qe_wavelengths a non-empty increasing sequence (nm)")
        qe = as_real_array(self.qe_curves, "qe_curves", check=False)
        if qe.ndim != 2 or qe.shape[1] != wl.size or qe.shape[0] < 1:
            raise InvalidInputError(
                f"expected qe_curves of shape (C, {wl.size}) (one value per qe_wavelengths), "
                f"got {format_shape(qe.shape)}"
            )
        check_real_values(qe, "qe_curves")
        if not np.all((qe >= 0) & (qe <= 1)):
            raise InvalidInputError("expected quantum efficiencies (qe_curves) in [0, 1]")
        finite_result(
            "the system gain",
            lambda: self.system_gain,
            conversion_gain=self.conversion_gain,
            analog_gain=self.analog_gain,
            adc_range=self.adc_range,
        )
        finite_result("the pixel area", lambda: self.pixel_area, pixel_pitch=self.pixel_pitch)

    # -- derived quantities ---------------------------------------------------------------
    @property
    def n_channels(self) -> int:
        """Number of output channels (QE curves)."""
        return len(self.qe_curves)

    @property
    def max_dn(self) -> int:
        """Largest ADC code, ``2^b - 1``."""
        return int(2**self.bit_depth - 1)

    @property
    def system_gain(self) -> float:
        r"""Overall system gain ``K`` (DN/e⁻), EMVA 1288's ``K``.

        .. math:: K = G_{conv}\, G_{analog}\, \frac{2^b - 1}{V_{ADC}}
        """
        return self.conversion_gain * self.analog_gain * self.max_dn / self.adc_range

    @property
    def pixel_area(self) -> float:
        """Pixel area ``p²`` (m²)."""
        return self.pixel_pitch**2

    def quantum_efficiency(self, wavelength_nm: float) -> np.ndarray:
        """QE of every channel at ``wavelength_nm`` (linear interpolation), shape ``(C,)``.

        Examples
        --------
        >>> s = SensorModel(qe_wavelengths=(500.0, 600.0), qe_curves=((0.4, 0.6),))
        >>> s.quantum_efficiency(550.0).tolist()
        [0.5]
        """
        lam = check_positive(wavelength_nm, "wavelength_nm")
        wl = np.asarray(self.qe_wavelengths, dtype=np.float64)
        if wl.size > 1 and not wl[0] <= lam <= wl[-1]:
            raise InvalidInputError(
                f"wavelength_nm {lam:g} nm is outside the QE curves' range {wl[0]:g}-{wl[-1]:g} nm"
            )
        return np.array(
            [np.interp(lam, wl, np.asarray(c, dtype=np.float64)) for c in self.qe_curves]
        )

    def fixed_pattern(self, height: int, width: int) -> FixedPattern:
        """Make the chip's fixed-pattern maps for a ``(height, width)`` frame from ``fpn_seed``."""
        col = self.column_fpn if self.architecture == "cmos" else 0.0
        h = as_int(height, "height", minimum=1)
        w = as_int(width, "width", minimum=1)
        as_shape((h, w, self.n_channels), "height and width", 3, copies=4)
        return fixed_pattern(
            (h, w, self.n_channels),
            prnu=self.prnu,
            dsnu=self.dsnu,
            column_fpn=col,
            rng=self.fpn_seed,
        )

    # -- light to electrons ---------------------------------------------------------------
    @_deprecate.parameters(renamed={"input": "quantity"})
    def mean_electrons(
        self,
        signal: ArrayLike,
        *,
        exposure_time: float,
        quantity: str = "electrons",
        wavelength_nm: float | None = None,
    ) -> np.ndarray:
        r"""Mean photo-electrons per pixel and channel, ``(..., H, W, C)``, before any noise.

        ``quantity`` says what ``signal`` holds:

        - ``"electrons"``: mean photo-electrons, ``(..., H, W, C)`` (returned as is);
        - ``"photons"``: mean photons on the pixel area during the exposure — monochromatic
          ``(..., H, W)`` with ``wavelength_nm``, or per wavelength bin ``(..., H, W, L)``
          on ``qe_wavelengths``;
        - ``"irradiance"``: W/m² at ``wavelength_nm`` ``(..., H, W)``, or spectral
          irradiance W m⁻² nm⁻¹ ``(..., H, W, L)`` on ``qe_wavelengths`` (integrated with
          the trapezoidal rule).

        .. math:: \mu_{e,c} = FF \sum_\lambda QE_c(\lambda)\, \mu_p(\lambda)
        """
        t = check_positive(exposure_time, "exposure_time (s)", allow_zero=True)
        kind = check_option(quantity, _QUANTITIES, "signal quantity")
        if wavelength_nm is not None:  # checked even where unused: never cut to a real part
            wavelength_nm = check_positive(wavelength_nm, "wavelength_nm")
        arr = as_real_array(signal, "signal", check=False)
        if kind == "electrons":
            if arr.ndim < 3 or arr.shape[-1] != self.n_channels:
                raise InvalidInputError(
                    f"expected signal (electrons) of shape (..., H, W, {self.n_channels}), got "
                    f"{format_shape(arr.shape)}"
                )
        elif wavelength_nm is not None:
            if arr.ndim < 2:
                raise InvalidInputError(
                    f"expected signal (monochromatic {kind}) of shape (..., H, W), "
                    f"got {format_shape(arr.shape)}"
                )
        elif arr.ndim < 3 or arr.shape[-1] != len(self.qe_wavelengths):
            raise InvalidInputError(
                f"expected signal (spectral {kind}) of shape (..., H, W, "
                f"{len(self.qe_wavelengths)}) on qe_wavelengths, got {format_shape(arr.shape)}; "
                "pass wavelength_nm for monochromatic light"
            )
        # the result (C channels a pixel) and one temporary of the signal's size
        check_memory(
            8.0 * arr.size * (self.n_channels + 1) * 2,
            "signal",
            f"the mean electrons of a signal of shape {format_shape(arr.shape)}",
        )
        check_real_values(arr, f"signal ({kind})")
        if arr.size and float(arr.min()) < 0:
            raise InvalidInputError(
                f"expected a non-negative signal ({kind}), got min {float(arr.min()):g}"
            )
        return finite_result(
            "the mean electrons",
            lambda: self._mean_electrons(arr, t, kind, wavelength_nm),
            signal=arr,
            exposure_time=t,
            wavelength_nm=wavelength_nm,
        )

    def _mean_electrons(
        self, arr: np.ndarray, t: float, kind: str, wavelength_nm: float | None
    ) -> np.ndarray:
        """:meth:`mean_electrons` on a checked signal."""
        if kind == "electrons":
            return arr
        ff = self.fill_factor
        if wavelength_nm is not None:
            qe = self.quantum_efficiency(wavelength_nm)
            mp = (
                arr
                if kind == "photons"
                # photons_per_pixel's arithmetic, in its order (same rounding)
                else arr
                * self.pixel_area
                * t
                * (float(wavelength_nm) * 1e-9)
                / (PLANCK * SPEED_OF_LIGHT)
            )
            return ff * mp[..., None] * qe
        wl = np.asarray(self.qe_wavelengths, dtype=np.float64)
        qe = np.asarray(self.qe_curves, dtype=np.float64)  # (C, L)
        if kind == "photons":
            return ff * arr @ qe.T
        if wl.size < 2:
            raise InvalidInputError("spectral irradiance needs QE curves on >= 2 wavelengths")
        weights = np.zeros(wl.size)  # trapezoidal-rule weights (nm) on the QE grid
        weights[:-1] += np.diff(wl) / 2
        weights[1:] += np.diff(wl) / 2
        photon_energy = PLANCK * SPEED_OF_LIGHT / (wl * 1e-9)  # J per photon
        per_bin = arr * (weights * self.pixel_area * t / photon_energy)  # photons per bin
        return ff * per_bin @ qe.T

    # -- electrons to digital numbers -------------------------------------------------------
    @_deprecate.parameters(renamed={"input": "quantity"})
    def capture(
        self,
        signal: ArrayLike,
        *,
        exposure_time: float,
        rng: RNGLike,
        quantity: str = "electrons",
        wavelength_nm: float | None = None,
    ) -> np.ndarray:
        r"""Simulate one exposure: shot, dark and read noise, FPN, gain, black level, ADC.

        .. math::

            y = \mathrm{clip}_{[0, 2^b - 1]}\Big(\mathrm{round}\big(K\,[\min(
            \mathcal{P}(g \mu_e) + \mathcal{P}(I_d t),\ Q_{FW}) + o + n_r] + y_0\big)\Big)

        Parameters
        ----------
        signal : array
            See :meth:`mean_electrons` for the shapes of each ``quantity``.
        exposure_time : float
            Seconds, ``>= 0``.
        rng : int, numpy.random.Generator or None
            The per-frame temporal noise source (SPEC 7: an int seeds a new Generator, a
            Generator is used and advanced, None draws fresh entropy).
        quantity : {"electrons", "photons", "irradiance"}
            What ``signal`` holds.
        wavelength_nm : float, optional
            For monochromatic photons or irradiance.

        Returns
        -------
        uint16 array (..., H, W, C)
            Raw digital numbers.

        Notes
        -----
        Source: EMVA 1288 4.0, §2, eqs. (1)–(9).

        Examples
        --------
        >>> s = SensorModel(read_noise=0, dark_current=0, dsnu=0, prnu=0, black_level=0)
        >>> s.capture(np.full((1, 2, 1), 0.0), exposure_time=0.01, rng=0).ravel().tolist()
        [0, 0]
        """
        mu = self.mean_electrons(
            signal, exposure_time=exposure_time, quantity=quantity, wavelength_nm=wavelength_nm
        )
        if mu.ndim < 3:
            raise InvalidInputError(
                f"expected signal of shape (..., H, W, C), got {format_shape(mu.shape)}"
            )
        # the fixed pattern (two maps) and the noise draws: about six frames of mu's size
        check_memory(6.0 * mu.nbytes, "signal", f"a capture of shape {format_shape(mu.shape)}")
        gen = as_rng(check_rng(rng))
        h, w = mu.shape[-3], mu.shape[-2]
        if h < 1 or w < 1:
            raise InvalidInputError(
                f"expected signal with H, W >= 1, got shape {format_shape(mu.shape[:-1])}"
            )
        fp = self.fixed_pattern(h, w)
        t = float(exposure_time)
        lam = mu * fp.gain
        if lam.size:
            lo, hi = float(lam.min()), float(lam.max())
            check_electrons(hi, "signal and exposure_time")
            if lo < 0:  # a large PRNU draws gains below zero: no light is collected there
                lam = np.maximum(lam, 0.0)
        check_electrons(self.dark_current * t, "dark_current × exposure_time")
        electrons = gen.poisson(lam).astype(np.float64)
        if self.dark_current > 0 and t > 0:
            electrons += gen.poisson(self.dark_current * t, size=mu.shape)
        electrons = np.minimum(electrons, self.full_well)  # full-well saturation (physics)
        electrons += fp.offset
        if self.read_noise > 0:
            electrons += self.read_noise * gen.standard_normal(mu.shape)
        analog = self.system_gain * electrons + self.black_level
        dn = np.clip(np.floor(analog + 0.5), 0, self.max_dn)  # the ADC's range (physics)
        return dn.astype(np.uint16)

    def normalize(self, dn: ArrayLike) -> np.ndarray:
        r"""Raw DN to floats: black level subtracted, white (``2^b - 1``) mapped to 1.

        .. math:: \frac{y - y_0}{(2^b - 1) - y_0}

        Values below the black level stay negative (noise is not clipped).

        Examples
        --------
        >>> SensorModel(black_level=64, bit_depth=12).normalize([64, 4095]).tolist()
        [0.0, 1.0]
        """
        arr = as_real_array(dn, "dn")
        return (arr - self.black_level) / (self.max_dn - self.black_level)

    normalise = _deprecate.renamed(normalize, "imageform.sensor.SensorModel.normalise")

    def frame_readout_time(self, rows: int) -> float:
        """Time to read ``rows`` rows, ``rows × line_time`` (s).

        Examples
        --------
        >>> round(SensorModel(line_time=10e-6).frame_readout_time(1080), 6)
        0.0108
        """
        n = as_int(rows, "rows", minimum=1)
        return float(finite_result("the read-out time", lambda: n * self.line_time, rows=n))

    def dynamic_range_db(self) -> float:
        r"""Dynamic range ``20 log10(Q_FW / σ_read)`` (dB); ``inf`` without read noise.

        .. math:: DR = 20 \log_{10}(Q_{FW} / \sigma_{read})

        Examples
        --------
        >>> round(SensorModel(full_well=10000, read_noise=2.0).dynamic_range_db(), 2)
        73.98
        """
        return (
            math.inf if self.read_noise == 0 else 20 * math.log10(self.full_well / self.read_noise)
        )
