"""Sensor noise: fixed-pattern maps and the EMVA 1288 linear noise model.

Temporal noise (photon shot noise, dark-current shot noise, read noise, quantisation) changes
from frame to frame; fixed-pattern noise (PRNU, DSNU, CMOS column offsets) is a property of
the chip and is the same in every frame, so its maps are drawn from the sensor's own
``fpn_seed``, never from the per-frame generator. (``fpn_seed`` stays an int, not an ``rng``:
it is the chip's identity, the same pattern every time the model is used.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._validate import as_real, as_shape, check_positive, check_rng, finite_result

__all__ = [
    "QUANTIZATION_NOISE_DN",
    "FixedPattern",
    "emva_snr",
    "fixed_pattern",
    "temporal_noise_dn",
]

#: Standard deviation of uniform quantization noise, ``1/√12`` DN (EMVA 1288 4.0, eq. 8).
QUANTIZATION_NOISE_DN = 1.0 / math.sqrt(12.0)

__getattr__ = _deprecate.module_getattr(
    "imageform.sensor.noise",
    {"QUANTISATION_NOISE_DN": ("QUANTIZATION_NOISE_DN", QUANTIZATION_NOISE_DN)},
)


@dataclass(frozen=True)
class FixedPattern:
    """Fixed-pattern maps of one chip for a frame of ``(H, W, C)`` pixels.

    ``gain`` multiplies the photo-electrons (``1 + PRNU`` per pixel); ``offset`` (electrons)
    holds the DSNU per pixel plus the CMOS column offsets, which are also kept alone in
    ``column`` ``(W,)``.
    """

    gain: np.ndarray
    offset: np.ndarray
    column: np.ndarray


@_deprecate.parameters(renamed={"seed": "rng"})
def fixed_pattern(
    shape: tuple[int, int, int], *, prnu: float, dsnu: float, column_fpn: float, rng: RNGLike
) -> FixedPattern:
    r"""Draw the fixed-pattern maps of a chip: Gaussian PRNU, DSNU and column offsets.

    .. math::

        g_{ijc} = 1 + \sigma_{PRNU} z_{ijc},\quad
        o_{ijc} = \sigma_{DSNU} z'_{ijc} + \sigma_{col} z''_j,\quad z \sim N(0, 1)

    ``prnu`` is a fraction (0.01 = 1 %), ``dsnu`` and ``column_fpn`` are electrons rms.
    ``rng`` (SPEC 7): an int seeds the draw together with the shape, so the same seed and
    shape always give the same chip; a Generator is drawn from (and advanced); None draws
    fresh entropy. Source: EMVA 1288 4.0, §4.2
    (DSNU, PRNU definitions); column FPN of column-parallel CMOS read-out (A. El Gamal and
    H. Eltoukhy, "CMOS image sensors", IEEE Circuits & Devices 21(3), 2005).

    Examples
    --------
    >>> fp = fixed_pattern((2, 3, 1), prnu=0.0, dsnu=0.0, column_fpn=0.0, rng=0)
    >>> bool((fp.gain == 1).all()), bool((fp.offset == 0).all())
    (True, True)
    """
    h, w, c = as_shape(shape, "shape (H, W, C)", 3, copies=4)
    p = check_positive(prnu, "prnu", allow_zero=True)
    d = check_positive(dsnu, "dsnu (e-)", allow_zero=True)
    col = check_positive(column_fpn, "column_fpn (e-)", allow_zero=True)
    gen = as_rng(check_rng(rng), mix=(h, w, c))

    def draw() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        gain = 1.0 + p * gen.standard_normal((h, w, c))
        cols = col * gen.standard_normal(w)
        offset = d * gen.standard_normal((h, w, c)) + cols[None, :, None]
        return gain, offset, cols

    gain, offset, cols = finite_result("the fixed pattern", draw, prnu=p, dsnu=d, column_fpn=col)
    return FixedPattern(gain=gain, offset=offset, column=cols)


def temporal_noise_dn(mean_electrons: float, *, system_gain: float, dark_noise_e: float) -> float:
    r"""Temporal noise of the digital signal (DN rms) by EMVA 1288's linear model.

    .. math::

        \sigma_y^2 = K^2 (\sigma_d^2 + \mu_e) + \sigma_q^2,\quad
        \sigma_q^2 = 1/12\ \mathrm{DN}^2

    Source: EMVA Standard 1288, Release 4.0 (2021), eq. (9).

    Examples
    --------
    >>> round(temporal_noise_dn(100.0, system_gain=0.5, dark_noise_e=2.0), 6)
    5.107184
    """
    k = check_positive(system_gain, "system_gain (DN/e-)")
    mu = check_positive(mean_electrons, "mean_electrons", allow_zero=True)
    sd = check_positive(dark_noise_e, "dark_noise_e", allow_zero=True)
    return float(
        finite_result(
            "the temporal noise",
            lambda: math.sqrt(k * k * (sd * sd + mu) + QUANTIZATION_NOISE_DN**2),
            system_gain=k,
            mean_electrons=mu,
            dark_noise_e=sd,
        )
    )


def emva_snr(
    photons: float, *, quantum_efficiency: float, dark_noise_e: float, system_gain: float
) -> float:
    r"""Signal-to-noise ratio of a linear camera at ``photons`` mean photons per pixel.

    .. math::

        \mathrm{SNR}(\mu_p) = \frac{\eta \mu_p}
        {\sqrt{\sigma_d^2 + \sigma_q^2 / K^2 + \eta \mu_p}}

    Source: EMVA Standard 1288, Release 4.0 (2021), eq. (13).

    Examples
    --------
    >>> round(emva_snr(1000, quantum_efficiency=0.5, dark_noise_e=5, system_gain=1), 4)
    21.8201
    """
    mp = check_positive(photons, "photons", allow_zero=True)
    eta = as_real(quantum_efficiency, "quantum_efficiency", positive=True, maximum=1.0)
    sd = check_positive(dark_noise_e, "dark_noise_e", allow_zero=True)
    k = check_positive(system_gain, "system_gain (DN/e-)")
    sig = eta * mp
    # K² underflows to 0 for K below ~1e-154: the quantisation term is then infinite and the
    # SNR its limit, 0 (and so when σ_d² overflows)
    quant = QUANTIZATION_NOISE_DN**2 / (k * k) if k * k > 0 else math.inf
    return float(
        finite_result(
            "the SNR",
            lambda: sig / math.sqrt(sd * sd + quant + sig),
            photons=mp,
            dark_noise_e=sd,
            system_gain=k,
        )
    )
