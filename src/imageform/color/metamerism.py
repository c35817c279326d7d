r"""Metamerism: spectra that differ but look the same, constructed and measured.

Integration to tristimulus values is linear, :math:`t = W^\mathsf{T} r` with
:math:`W_{\lambda c} = S(\lambda)\,\bar c(\lambda)\,\Delta\lambda` (``M`` wavelengths, 3
channels). Every spectrum :math:`b` in the null space of :math:`W^\mathsf{T}` is a *metameric
black* (Wyszecki 1958; Cohen & Kappauf 1982, "Metameric color stimuli, fundamental metamers,
and Wyszecki's metameric blacks", Am. J. Psychol. 95:537-564): adding it changes the spectrum
but not :math:`t`. :func:`metamer` projects smooth cosines onto that null space,

.. math:: b = (I - W (W^\mathsf{T} W)^{-1} W^\mathsf{T})\, d,

and takes the largest step :math:`r' = r + \tau b` that keeps the result physically valid
(non-negative; reflectance within [0, 1]).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from imageform import _deprecate
from imageform._validate import as_bool, as_int, as_real, check_name
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.spectral.integrate import (
    integration_weights,
    observer_functions,
    resolve_illuminant,
    spectrum_to_xyz,
)
from imageform.spectral.spectrum import Spectrum

__all__ = [
    "are_metamers",
    "match_with_primaries",
    "metamer",
    "metamerism_index",
    "tristimulus",
]

_KINDS = ("reflectance", "light")


def _check(s: object, name: str) -> Spectrum:
    if not isinstance(s, Spectrum) or s.values.ndim != 1:
        raise InvalidInputError(f"expected {name} as a single-curve Spectrum, got {s!r:.80}")
    return s


def _setup(
    spectrum: Spectrum, observer: int | str, illuminant: str | Spectrum | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(grid, weights W (M, 3), r on the grid) for the CIE 015 1 nm summation."""
    f = observer_functions(observer)
    ill = resolve_illuminant(illuminant)
    grid, w = integration_weights(f, illuminant=ill, method="cie015")
    # reflectances extend by their end values (CIE 015 §7.2.2); lights are zero outside
    ext = "zero" if ill is None else "constant"
    r = spectrum.interpolate(grid, method="linear", extrapolate=ext).values
    return grid, w, r


@_deprecate.parameters(positional=("observer", "illuminant"))
def tristimulus(
    spectrum: Spectrum, *, observer: int | str = 2, illuminant: str | Spectrum | None = "D65"
) -> np.ndarray:
    r"""Raw tristimulus sums :math:`W^\mathsf{T} r` (CIE 015 1 nm grid), shape (3,).

    ``observer`` 2, 10 (CIE XYZ) or ``"cones"`` (Stockman & Sharpe LMS); ``observer`` and
    ``illuminant`` are keyword-only. Unnormalised: the quantity whose equality defines a
    metameric match.

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> t = tristimulus(colorchecker_reflectances()["red"])
    >>> round(float(t[1] / tristimulus(colorchecker_reflectances()["white 9.5 (.05 D)"])[1]), 4)
    0.1288
    """
    _, w, r = _setup(_check(spectrum, "spectrum"), observer, illuminant)
    return np.asarray(r @ w)


@_deprecate.parameters(positional=("observer", "illuminant"))
def are_metamers(
    s1: Spectrum,
    s2: Spectrum,
    *,
    observer: int | str = 2,
    illuminant: str | Spectrum | None = "D65",
    tol: float = 1e-6,
    spectral_tol: float = 1e-9,
) -> bool:
    r"""Tell whether two *different* spectra give the same responses (metamers).

    The responses are those of ``observer`` under ``illuminant`` (keyword-only;
    ``illuminant=None``: the spectra are lights).

    Match: :math:`\max_c |t_{1c} - t_{2c}| / t_{\mathrm{white},Y} <` ``tol`` (relative to the
    white's Y, so the scale is that of XYZ with white Y = 1). Different: spectral RMS on the
    integration grid > ``spectral_tol``.

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> r = colorchecker_reflectances()["neutral 5 (.70 D)"]
    >>> are_metamers(r, metamer(r))
    True
    """
    a, b = _check(s1, "s1"), _check(s2, "s2")
    tol = as_real(tol, "tol", nonnegative=True, allow_inf=True)
    spectral_tol = as_real(spectral_tol, "spectral_tol", nonnegative=True, allow_inf=True)
    _, w, r1 = _setup(a, observer, illuminant)
    _, _, r2 = _setup(b, observer, illuminant)
    scale = float(np.max(w.sum(axis=0)))
    match = np.max(np.abs((r1 - r2) @ w)) / scale < tol
    differ = float(np.sqrt(np.mean((r1 - r2) ** 2))) > spectral_tol
    return bool(match and differ)


@_deprecate.parameters(positional=("observer", "illuminant"))
def metamer(
    spectrum: Spectrum,
    *,
    observer: int | str = 2,
    illuminant: str | Spectrum | None = "D65",
    kind: Literal["reflectance", "light"] = "reflectance",
    strength: float = 0.95,
    max_frequency: int = 8,
) -> Spectrum:
    r"""Construct a physically valid spectrum, unlike ``spectrum``, with identical responses.

    Method: metameric blacks (module docstring). Candidate directions are cosines
    :math:`d = \cos(2\pi f (\lambda - \lambda_0)/(\lambda_1 - \lambda_0) + \varphi)` for
    :math:`f = 1..` ``max_frequency`` and :math:`\varphi \in \{0, \pi/2\}`, projected onto the
    null space; for each, the largest step :math:`\tau` keeping the result in [0, 1]
    (``kind="reflectance"``) or :math:`\ge 0` (``kind="light"``, capped at the spectrum's own
    peak) is found, and the candidate with the largest spectral RMS change
    :math:`\mathrm{strength}\cdot\tau\cdot\mathrm{rms}(b)` is returned.

    Parameters
    ----------
    spectrum : Spectrum, values (N,)
        A reflectance (within [0, 1]) or a light (non-negative).
    observer : 2, 10 or "cones", keyword-only
        Whose responses the metamer matches: the CIE 2° or 10° observer or the cone fundamentals.
    illuminant : str, Spectrum or None, keyword-only
        The light the match holds under (``None`` for lights).
    kind : {"reflectance", "light"}, keyword-only
        Keep the result in [0, 1] (a reflectance) or only non-negative (a light).
    strength : float in (0, 1]
        Fraction of the largest valid step.
    max_frequency : int, keyword-only
        Highest frequency of the cosine/sine basis the metameric black is built from.

    Returns
    -------
    Spectrum
        On the CIE 015 integration grid (1 nm within the observer's and illuminant's range).

    Raises
    ------
    DegenerateConfigurationError
        If the spectrum sits on its bounds everywhere a black could change it (e.g. a
        reflectance of 0 or 1 everywhere): no different valid metamer exists this way.

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz
    >>> r = colorchecker_reflectances()["blue sky"]
    >>> m = metamer(r)
    >>> bool(abs(spectrum_to_xyz(m) - spectrum_to_xyz(r)).max() < 1e-12)
    True
    """
    s = _check(spectrum, "spectrum")
    k = check_name(kind, _KINDS, "spectrum kind")
    strength = as_real(strength, "strength")
    if not 0.0 < strength <= 1.0:
        raise InvalidInputError(f"expected 0 < strength <= 1, got {strength}")
    max_frequency = as_int(max_frequency, "max_frequency", minimum=1)
    grid, w, r = _setup(s, observer, illuminant)
    if max_frequency > len(grid) // 2:
        raise InvalidInputError(
            f"expected max_frequency <= {len(grid) // 2} (half the {len(grid)} grid samples), "
            f"got {max_frequency}"
        )
    if np.any(r < 0) or (k == "reflectance" and np.any(r > 1)):
        raise InvalidInputError(
            f"expected a {k} with values in {'[0, 1]' if k == 'reflectance' else '[0, inf)'}, "
            f"got range [{r.min():.4g}, {r.max():.4g}]"
        )
    upper = np.ones_like(r) if k == "reflectance" else np.full_like(r, np.inf)
    cap = np.inf if k == "reflectance" else float(r.max())
    gram_inv = np.linalg.inv(w.T @ w)
    x = (grid - grid[0]) / (grid[-1] - grid[0])
    best: tuple[float, np.ndarray] = (0.0, np.zeros_like(r))
    for f in range(1, max_frequency + 1):
        for phase in (0.0, np.pi / 2):
            d = np.cos(2 * np.pi * f * x + phase)
            b = d - w @ (gram_inv @ (w.T @ d))
            b /= np.max(np.abs(b))
            for sign in (1.0, -1.0):
                bb = sign * b
                with np.errstate(divide="ignore", invalid="ignore"):
                    up = np.where(bb > 0, (upper - r) / bb, np.inf)
                    down = np.where(bb < 0, r / -bb, np.inf)
                tau = min(float(np.min(up)), float(np.min(down)), cap)
                rms = tau * float(np.sqrt(np.mean(bb**2)))
                if np.isfinite(rms) and rms > best[0]:
                    best = (rms, strength * tau * bb)
    if best[0] <= 1e-12:
        raise DegenerateConfigurationError(
            "no valid metamer: the spectrum sits on its bounds wherever a metameric black "
            "could change it"
        )
    out = np.clip(r + best[1], 0.0, upper)  # removes rounding below 1e-15 only
    return Spectrum(grid, out, name=f"metamer of {s.name or 'spectrum'}")


def metamerism_index(
    s1: Spectrum,
    s2: Spectrum,
    reference: str | Spectrum = "D65",
    test: str | Spectrum = "A",
    *,
    observer: int = 2,
    correct: bool = True,
) -> float:
    r"""Compute the special metamerism index (change in illuminant).

    The index is CIEDE2000 under the test illuminant.

    CIE 015:2018 §9.2.2 / CIE 80 (1989): the colour difference of a pair under a test
    illuminant. If the pair does not match exactly under the reference, ``correct=True``
    applies the multiplicative correction :math:`X'_2 = X_2\,X_{1,r}/X_{2,r}` (per channel)
    before the difference. Lab white: the test illuminant (Y = 1).

    Examples
    --------
    >>> from imageform.spectral import colorchecker_reflectances
    >>> r = colorchecker_reflectances()["neutral 5 (.70 D)"]
    >>> round(metamerism_index(r, metamer(r), "D65", "D65"), 9)
    0.0
    """
    from imageform.color.cielab import xyz_to_lab
    from imageform.color.delta_e import delta_e_ciede2000

    a, b = _check(s1, "s1"), _check(s2, "s2")
    correct = as_bool(correct, "correct")
    if str(observer) not in ("2", "10"):
        raise InvalidInputError(f"expected observer 2 or 10, got {observer!r}")
    if test is None:
        raise TypeError("expected test as an illuminant name or a Spectrum, got None")
    tst = resolve_illuminant(test, name="test")
    ref = resolve_illuminant(reference, name="reference")
    x1t = spectrum_to_xyz(a, illuminant=tst, observer=observer)
    x2t = spectrum_to_xyz(b, illuminant=tst, observer=observer)
    if correct:
        x1r = spectrum_to_xyz(a, illuminant=ref, observer=observer)
        x2r = spectrum_to_xyz(b, illuminant=ref, observer=observer)
        if np.any(x2r == 0):
            raise DegenerateConfigurationError("s2 has a zero tristimulus value: cannot correct")
        x2t = x2t * x1r / x2r
    ones = Spectrum(tst.wavelengths, np.ones(len(tst))) if tst is not None else None
    white = spectrum_to_xyz(ones, illuminant=tst, observer=observer) if ones is not None else None
    lab1 = xyz_to_lab(x1t, white, observer=observer)
    lab2 = xyz_to_lab(x2t, white, observer=observer)
    return float(delta_e_ciede2000(lab1, lab2))


@_deprecate.parameters(positional=("observer",))
def match_with_primaries(
    target: Spectrum, primaries: Spectrum, *, observer: int | str = 2
) -> np.ndarray:
    r"""Weights of three primary lights whose mixture matches a target light, shape (3,).

    The additive match :math:`\sum_i w_i\,W^\mathsf{T} p_i = W^\mathsf{T} t` is a 3x3 linear
    system (Grassmann's laws): three independent primaries match *any* stimulus, but only
    stimuli inside the primaries' gamut get all :math:`w_i \ge 0`; outside, a primary would
    have to be added to the target side (a negative weight), as in the colour-matching
    experiments of Wright and Guild. The mixture :math:`\sum w_i p_i` is a metamer of the
    target: its spectrum differs, its responses do not.

    Parameters
    ----------
    target : Spectrum, values (N,)
        A light (e.g. ``illuminant * reflectance``).
    primaries : Spectrum, values (M, 3)
        The three primary lights.
    observer : 2, 10 or "cones", keyword-only
        Whose responses are matched.

    Examples
    --------
    >>> import numpy as np
    >>> wl = np.arange(380.0, 781.0)
    >>> bumps = [np.exp(-0.5 * ((wl - c) / 15) ** 2) for c in (610, 540, 450)]
    >>> prim = Spectrum.from_columns(wl, bumps)
    >>> w = match_with_primaries(Spectrum(wl, np.ones_like(wl)), prim)
    >>> bool(np.all(w > 0))
    True
    """
    t = _check(target, "target")
    if (
        not isinstance(primaries, Spectrum)
        or primaries.values.ndim != 2
        or primaries.values.shape[1] != 3
    ):
        raise InvalidInputError("expected primaries as a Spectrum with values of shape (M, 3)")
    grid, w, _ = _setup(t, observer, None)
    rt = t.interpolate(grid, extrapolate="zero").values
    p = primaries.interpolate(grid, extrapolate="zero").values
    a = w.T @ p
    if abs(np.linalg.det(a)) < 1e-12 * np.linalg.norm(a) ** 3:
        raise DegenerateConfigurationError("the primaries are not independent for this observer")
    return np.asarray(np.linalg.solve(a, w.T @ rt))
