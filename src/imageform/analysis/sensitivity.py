r"""A camera's spectral sensitivities, estimated from a photograph of a colour chart.

The raw (linear, black-subtracted) response of channel ``k`` to patch ``p`` under a light
``E`` is the sum over wavelength of reflectance times light times sensitivity:

.. math:: c_{pk} = \sum_j R_p(\lambda_j)\, E(\lambda_j)\, S_k(\lambda_j)\, \Delta\lambda
    \quad\Longleftrightarrow\quad c_k = A\, s_k,\ A = R\, \mathrm{diag}(E)\, \Delta\lambda

With 24 smooth reflectances the matrix ``A`` has an effective rank near 8 for 31 unknowns,
so the problem is ill-posed; real sensitivities are smooth and non-negative. Following
Finlayson, Hordley & Hubel (1998), each channel is the non-negative minimiser of the data
misfit plus a penalty on its second differences,

.. math:: \hat s_k = \arg\min_{s \ge 0}\ \lVert A s - c_k\rVert^2
    + \mu_k \lVert D_2 s\rVert^2,

with one weight :math:`\mu` for all channels, in units of
:math:`\operatorname{tr}(A^TA)/\operatorname{tr}(D_2^TD_2)` (0.1 by default: on simulated
charts with 0-2 % noise it gave the smallest errors of the weights tried, 1e-5 to 1), or chosen
per channel by generalised cross-validation (Golub, Heath & Wahba, 1979) on the unconstrained
problem, which undersmooths noisy charts (measured in the tests):
:math:`\mathrm{GCV}(\mu) = P \lVert (I - H_\mu) c\rVert^2 / \operatorname{tr}(I - H_\mu)^2`,
:math:`H_\mu = A (A^T A + \mu D_2^T D_2)^{-1} A^T`.

The exposure is unknown, so the sensitivities are found up to one common factor: they are
returned scaled to a largest value of 1 (the ratios between channels are kept: they carry
the camera's white balance).

References
----------
G. D. Finlayson, S. Hordley, P. M. Hubel, "Recovering device sensitivities with quadratic
programming", Proc. IS&T/SID 6th Color Imaging Conference, 90-95, 1998.
G. H. Golub, M. Heath, G. Wahba, "Generalized cross-validation as a method for choosing a
good ridge parameter", Technometrics 21(2):215-223, 1979.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import as_bool, as_real, describe, real_array
from imageform.errors import ImageformError, InvalidInputError
from imageform.spectral import Spectrum, colorchecker_reflectances, illuminant

__all__ = ["SensitivityEstimate", "estimate_camera_sensitivities", "relative_qe"]


@dataclass(frozen=True)
class SensitivityEstimate:
    r"""Estimated spectral sensitivities.

    ``sensitivities``: a :class:`~imageform.spectral.Spectrum` with values (N, 3) (R, G, B),
    largest value 1; ``scale``: the factor that multiplied them (the camera's response per
    unit of the returned sensitivities); ``smoothness`` (3,): the chosen weights
    :math:`\mu_k` (relative to :math:`\operatorname{tr}(A^TA)/\operatorname{tr}(D^TD)`);
    ``predicted`` (P, 3): the chart's responses the estimate gives (on the input's scale);
    ``relative_rms`` (3,): the misfit per channel, RMS over the patches relative to the
    channel's RMS response.
    """

    sensitivities: Spectrum
    scale: float
    smoothness: np.ndarray
    predicted: np.ndarray
    relative_rms: np.ndarray


def _second_difference(n: int) -> np.ndarray:
    d = np.zeros((n - 2, n))
    i = np.arange(n - 2)
    d[i, i], d[i, i + 1], d[i, i + 2] = 1.0, -2.0, 1.0
    return d


def _gcv_weight(a: np.ndarray, d: np.ndarray, c: np.ndarray) -> float:
    """Return the ridge weight (relative units) minimising generalised cross-validation."""
    ata, dtd = a.T @ a, d.T @ d
    unit = float(np.trace(ata) / np.trace(dtd))
    p = a.shape[0]
    best, best_mu = np.inf, 1e-3
    for rel in np.logspace(-3, 1, 41):
        mu = rel * unit
        try:
            inv = np.linalg.solve(ata + mu * dtd, a.T)
        except np.linalg.LinAlgError:
            continue
        h = a @ inv
        resid = c - h @ c
        denom = (p - float(np.trace(h))) ** 2
        if denom <= 1e-12:
            continue
        score = p * float(resid @ resid) / denom
        if score < best:
            best, best_mu = score, float(rel)
    return best_mu


def estimate_camera_sensitivities(
    camera_rgb: ArrayLike,
    reflectances: Spectrum | None = None,
    *,
    light: str | Spectrum = "D65",
    wavelengths: ArrayLike | None = None,
    smoothness: float | ArrayLike | Literal["gcv"] = 0.1,
    nonnegative: bool = True,
) -> SensitivityEstimate:
    r"""Estimate a camera's R, G, B spectral sensitivities from its raw responses to a chart.

    Parameters
    ----------
    camera_rgb : array_like, shape (P, 3)
        Linear raw responses (black level subtracted, not white-balanced, no colour
        matrix) to the ``P`` patches, e.g. the patch means of a raw ColorChecker photograph;
        any scale (the exposure is unknown).
    reflectances : Spectrum, values (M, P), optional
        The patches' reflectances; default the ColorChecker's 24
        (:func:`imageform.spectral.colorchecker_reflectances`, in its patch order).
    light : str or Spectrum, keyword-only
        The light the chart was photographed under (a name for
        :func:`imageform.spectral.illuminant`, or a spectrum).
    wavelengths : array_like, optional, keyword-only
        The wavelengths (nm) of the estimate; default 400 to 700 nm in 10 nm steps.
    smoothness : float, sequence of 3 floats or "gcv", keyword-only
        The weights :math:`\mu_k` in units of :math:`\operatorname{tr}(A^TA) /
        \operatorname{tr}(D^TD)`, or ``"gcv"``: chosen per channel by generalised
        cross-validation.
    nonnegative : bool, keyword-only
        Constrain the sensitivities to be >= 0 (non-negative least squares).

    Returns
    -------
    SensitivityEstimate

    Raises
    ------
    InvalidInputError
        Misshaped or non-finite responses, fewer than 6 patches, responses that are all zero
        or negative in a channel, or reflectances that do not match the patches.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.spectral import (camera_sensitivities, colorchecker_reflectances,
    ...                                 spectrum_to_camera_rgb)
    >>> rgb = spectrum_to_camera_rgb(colorchecker_reflectances(), illuminant="D65")  # (24, 3)
    >>> est = estimate_camera_sensitivities(rgb, light="D65")
    >>> [int(w) for w in est.sensitivities.peak_wavelength()]  # R, G, B peaks (nm)
    [605, 535, 462]
    >>> [int(w) for w in camera_sensitivities().peak_wavelength()]  # the measured ones
    [594, 530, 461]
    """
    refl = colorchecker_reflectances() if reflectances is None else reflectances
    if not isinstance(refl, Spectrum):
        raise InvalidInputError(f"expected reflectances as a Spectrum, got {describe(refl)}")
    if refl.values.ndim != 2:
        raise InvalidInputError(
            f"expected reflectances with values (M, P), got shape {refl.values.shape}"
        )
    n_patches = refl.values.shape[1]
    rgb = real_array(camera_rgb, "camera_rgb", (n_patches, 3))
    if n_patches < 6:
        raise InvalidInputError(f"expected at least 6 patches in camera_rgb, got {n_patches}")
    if np.any(np.max(rgb, axis=0) <= 0):
        k = int(np.argmin(np.max(rgb, axis=0)))
        raise InvalidInputError(f"camera_rgb channel {k} has no positive response")
    if wavelengths is None:
        wl = np.arange(400.0, 701.0, 10.0)
    else:
        wl = real_array(wavelengths, "wavelengths", (None,))
        if wl.size < 5 or np.any(np.diff(wl) <= 0) or wl[0] < 300 or wl[-1] > 1100:
            raise InvalidInputError(
                "expected wavelengths as >= 5 increasing values within 300-1100 nm, got "
                f"{describe(wavelengths)}"
            )
    if not isinstance(light, str | Spectrum):
        raise InvalidInputError(f"expected light as a name or a Spectrum, got {describe(light)}")
    if isinstance(light, str):
        try:
            spd = illuminant(light)
        except ImageformError:
            raise InvalidInputError(
                f"unknown light {describe(light)}; expected an illuminant name such as D65 or A"
            ) from None
    else:
        spd = light
    e = spd.interpolate(wl).values
    if e.ndim != 1 or not np.all(np.isfinite(e)) or np.any(e < 0) or not np.any(e > 0):
        raise InvalidInputError("expected light as one non-negative spectrum")
    c_scale = float(np.max(np.abs(rgb)))
    rgb = rgb / c_scale  # any exposure scale, up to 1e308, is solved at unit scale
    r = refl.interpolate(wl).values.T  # (P, N)
    step = np.gradient(wl)
    a = r * (e * step)[None, :]
    a_scale = float(np.max(a))
    a = a / a_scale
    nonneg = as_bool(nonnegative, "nonnegative")
    d = _second_difference(wl.size)
    unit = float(np.trace(a.T @ a) / np.trace(d.T @ d))
    if isinstance(smoothness, str) and smoothness == "gcv":
        mus = np.array([_gcv_weight(a, d, rgb[:, k]) for k in range(3)])
    else:
        if smoothness is None or isinstance(smoothness, str | bytes):
            raise InvalidInputError(
                f"expected smoothness as a positive number, 3 numbers or 'gcv', got "
                f"{describe(smoothness)}"
            )
        vals = np.atleast_1d(np.asarray(smoothness, dtype=object))
        if vals.ndim != 1 or vals.size not in (1, 3):
            raise InvalidInputError(
                f"expected smoothness as one number or 3, got {describe(smoothness)}"
            )
        mus = np.array(
            [as_real(m, "smoothness", positive=True, maximum=1e12) for m in np.resize(vals, 3)]
        )
    s = np.zeros((wl.size, 3))
    for k in range(3):
        lhs = np.vstack([a, np.sqrt(mus[k] * unit) * d])
        rhs = np.concatenate([rgb[:, k], np.zeros(d.shape[0])])
        if nonneg:
            from scipy.optimize import nnls

            s[:, k] = nnls(lhs, rhs, maxiter=50 * wl.size)[0]
        else:
            s[:, k] = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    predicted = a @ s
    rms_c = np.sqrt(np.mean(rgb**2, axis=0))
    rel = np.sqrt(np.mean((predicted - rgb) ** 2, axis=0)) / rms_c
    peak = float(np.max(s))
    if not peak > 0:
        raise InvalidInputError("camera_rgb gives no positive sensitivity")
    return SensitivityEstimate(
        Spectrum(wl, s / peak),
        peak / a_scale * c_scale,
        mus,
        predicted * c_scale,
        rel,
    )


def relative_qe(sensitivities: Spectrum) -> tuple[np.ndarray, np.ndarray]:
    r"""Return the relative quantum efficiencies of estimated spectral sensitivities.

    The efficiencies are for photon counting, largest 1; the sensitivities are in energy units
    (response per unit of spectral power).

    A photosite counts photons, :math:`N(\lambda) = E(\lambda)\,\lambda / (h c)`, so the
    response per unit power is :math:`S(\lambda) \propto \mathrm{QE}(\lambda)\,\lambda`
    and :math:`\mathrm{QE}(\lambda) \propto S(\lambda) / \lambda`.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.spectral import Spectrum
    >>> wl, qe = relative_qe(Spectrum(np.array([400.0, 800.0]), np.array([[1, 1, 1], [1, 1, 2.0]])))
    >>> qe[:, 2].tolist()
    [1.0, 1.0]
    """
    if not isinstance(sensitivities, Spectrum):
        raise TypeError(f"expected sensitivities as a Spectrum, got {describe(sensitivities)}")
    wl = np.asarray(sensitivities.wavelengths, dtype=np.float64)
    qe = np.asarray(sensitivities.values, dtype=np.float64).reshape(len(wl), -1) / wl[:, None]
    peak = float(qe.max()) if qe.size else 0.0
    if not peak > 0.0:
        raise InvalidInputError("sensitivities: expected a positive value somewhere, got none")
    return wl, qe / peak


# ---------------------------------------------------------------- the whole
