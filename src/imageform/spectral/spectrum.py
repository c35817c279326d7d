"""The :class:`Spectrum` type: sampled spectral data (SPDs, reflectances, sensitivities).

A spectrum is a strictly increasing wavelength grid in nanometres and values of shape ``(N,)``
(one curve) or ``(N, K)`` (K curves on one grid, e.g. the three colour-matching functions).
Resampling names its method; arithmetic requires identical grids (resample first) so that no
interpolation happens behind the caller's back.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from imageform._validate import (
    as_int,
    as_real,
    as_real_ndarray,
    check_memory,
    check_option,
    describe,
)
from imageform.errors import InvalidInputError

__all__ = ["EXTRAPOLATION_METHODS", "INTERPOLATION_METHODS", "Spectrum"]

#: Interpolation methods of :meth:`Spectrum.interpolate`.
INTERPOLATION_METHODS = ("linear", "cubic", "pchip", "nearest", "sprague")
#: What happens outside the sampled range: ``"constant"`` repeats the end values (CIE 015:2018
#: §7.2.2 recommendation), ``"zero"``, or ``"error"``.
EXTRAPOLATION_METHODS = ("constant", "zero", "error")


def _as_wavelengths(wl: npt.ArrayLike, min_size: int = 1, name: str = "wavelengths") -> np.ndarray:
    w = as_real_ndarray(wl, name, finite=False)
    if w.ndim != 1 or w.size < min_size:
        raise InvalidInputError(
            f"expected {name} of shape (N,) with N >= {min_size}, got {w.shape}"
        )
    if not np.all(np.isfinite(w)):
        raise InvalidInputError(f"{name} contain NaN or inf")
    if np.any(np.diff(w) <= 0):
        i = int(np.argmax(np.diff(w) <= 0))
        raise InvalidInputError(
            "expected strictly increasing wavelengths, got "
            f"{w[i]:g} nm followed by {w[i + 1]:g} nm at index {i}"
        )
    return w


# CIE 167:2005 Table 2 / Westland, Ripamonti & Cheung (2012) §5: Sprague (1880) boundary
# coefficients (÷ 209) that extend uniform data by two points at each end.
_SPRAGUE_C = np.array(
    [
        [884, -1960, 3033, -2648, 1080, -180],
        [508, -540, 488, -367, 144, -24],
        [-24, 144, -367, 488, -540, 508],
        [-180, 1080, -2648, 3033, -1960, 884],
    ],
    dtype=np.float64,
)
# Sprague's fifth-order polynomial coefficients (÷ 24) on p_{-2} .. p_{3}.
_SPRAGUE_A = np.array(
    [
        [0, 0, 24, 0, 0, 0],
        [2, -16, 0, 16, -2, 0],
        [-1, 16, -30, 16, -1, 0],
        [-9, 39, -70, 66, -33, 7],
        [13, -64, 126, -124, 61, -12],
        [-5, 25, -50, 50, -25, 5],
    ],
    dtype=np.float64,
)


def _sprague(x: np.ndarray, y: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Sprague (1880) interpolation of uniformly spaced ``y`` (N >= 6) at ``xi`` (in range).

    Linear in ``y``: built as the matrix ``S = L E`` (E extends the data by two points at each
    end, L holds the quintic's weights on p_{-2} .. p_{3}), then ``S @ y``.
    """
    n, m = len(x), len(xi)
    # the dense operator (m x (n + 4)) @ ((n + 4) x n) is bounded before it is built
    check_memory(8.0 * (n + 4) * (m + n), "wavelengths", "Sprague interpolation")
    h = x[1] - x[0]
    i = np.clip(np.floor((xi - x[0]) / h + 1e-12).astype(int), 0, n - 2)
    t = (xi - x[i]) / h
    w = (t[:, None] ** np.arange(6)[None, :]) @ _SPRAGUE_A / 24.0  # (M, 6)
    ext = np.zeros((n + 4, n))
    ext[:2, :6] = _SPRAGUE_C[:2] / 209.0
    ext[2 : n + 2] = np.eye(n)
    ext[n + 2 :, n - 6 :] = _SPRAGUE_C[2:] / 209.0
    lmat = np.zeros((m, n + 4))
    lmat[np.arange(m)[:, None], i[:, None] + np.arange(6)[None, :]] = w
    return np.asarray((lmat @ ext) @ y)


@dataclass(frozen=True, eq=False)
class Spectrum:
    """Sampled spectral data on a strictly increasing wavelength grid (nm).

    Parameters
    ----------
    wavelengths : array_like, shape (N,)
        Strictly increasing wavelengths in nanometres.
    values : array_like, shape (N,) or (N, K)
        One curve or K curves sampled at ``wavelengths``.
    name : str
        A label for reports.
    labels : tuple of str
        Names of the K columns (e.g. ``("x_bar", "y_bar", "z_bar")``); empty for one curve.

    Examples
    --------
    >>> s = Spectrum([400, 500, 600], [0.1, 0.5, 0.3])
    >>> round(float(s.interpolate([450], method="linear").values[0]), 12)
    0.3
    >>> float((2 * s).values[1])
    1.0
    """

    wavelengths: np.ndarray
    values: np.ndarray
    name: str = ""
    labels: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        """Validate and freeze the wavelengths, values and labels."""
        w = _as_wavelengths(self.wavelengths, 1)
        v = np.array(as_real_ndarray(self.values, "values", finite=False), copy=True)
        if v.ndim not in (1, 2) or v.shape[0] != w.shape[0]:
            raise InvalidInputError(
                f"expected values of shape ({w.shape[0]},) or ({w.shape[0]}, K) to match "
                f"{w.shape[0]} wavelengths, got {v.shape}"
            )
        if not np.all(np.isfinite(v)):
            raise InvalidInputError("spectral values contain NaN or inf")
        if not isinstance(self.name, str):
            raise TypeError(f"expected name as a str, got {describe(self.name)}")
        if isinstance(self.labels, str) or not isinstance(self.labels, Sequence):
            raise TypeError(f"expected labels as a tuple of str, got {describe(self.labels)}")
        labels = tuple(self.labels)
        if not all(isinstance(lab, str) for lab in labels):
            raise TypeError(f"expected labels as a tuple of str, got {describe(self.labels)}")
        if labels and (v.ndim != 2 or len(labels) != v.shape[1]):
            raise InvalidInputError(
                f"expected {v.shape[1] if v.ndim == 2 else 0} labels, got {len(labels)}"
            )
        w.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "wavelengths", w)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "labels", labels)

    # ---- basic properties -------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of :attr:`values`."""
        return tuple(self.values.shape)

    @property
    def range(self) -> tuple[float, float]:
        """First and last wavelength (nm)."""
        return float(self.wavelengths[0]), float(self.wavelengths[-1])

    @property
    def interval(self) -> float | None:
        """The sampling interval (nm) if uniform, else ``None``."""
        d = np.diff(self.wavelengths)
        return float(d[0]) if np.allclose(d, d[0], rtol=0, atol=1e-9) else None

    def __len__(self) -> int:
        """Return the number of wavelengths."""
        return int(self.wavelengths.shape[0])

    def __repr__(self) -> str:
        """Return a one-line summary: name, wavelength grid and values shape."""
        lo, hi = self.range
        step = self.interval
        grid = f"{lo:g}-{hi:g} nm" + (f" step {step:g}" if step else " (irregular)")
        return f"Spectrum({self.name or 'unnamed'!r}, {grid}, values {self.shape})"

    def __getitem__(self, label: str | int) -> Spectrum:
        """One column by label or index, as a single-curve spectrum."""
        if self.values.ndim != 2:
            raise InvalidInputError("indexing by column needs a multi-curve spectrum (N, K)")
        if isinstance(label, str):
            if label not in self.labels:
                raise InvalidInputError(
                    f"unknown column {label!r}; valid: {', '.join(map(repr, self.labels))}"
                )
            i = self.labels.index(label)
        else:
            i = as_int(
                label, "label", minimum=-self.values.shape[1], maximum=self.values.shape[1] - 1
            )
        name = self.labels[i] if self.labels else f"{self.name}[{i}]"
        return Spectrum(self.wavelengths, self.values[:, i], name=name)

    def peak_wavelength(self) -> float | np.ndarray:
        """Wavelength (nm) of the maximum of each curve.

        A unique sampled maximum is refined by the parabola through it and its neighbours;
        a plateau of equal maxima (tables rounded to a few digits) gives the plateau's centre.

        Examples
        --------
        >>> round(Spectrum([500, 510, 520], [0.2, 0.9, 0.4]).peak_wavelength(), 2)
        510.83
        """
        v = self.values if self.values.ndim == 2 else self.values[:, None]
        x = self.wavelengths
        out = np.empty(v.shape[1])
        for k in range(v.shape[1]):
            y = v[:, k]
            top = np.flatnonzero(y == y.max())
            i = int(top[0])
            if top.size > 1:
                out[k] = float(np.mean(x[top]))
            elif 0 < i < len(x) - 1 and self.interval is not None:
                y0, y1, y2 = y[i - 1], y[i], y[i + 1]
                den = y0 - 2 * y1 + y2
                out[k] = x[i] + (0.5 * (y0 - y2) / den * self.interval if den else 0.0)
            else:
                out[k] = x[i]
        return float(out[0]) if self.values.ndim == 1 else out

    # ---- resampling -------------------------------------------------------------------
    def interpolate(
        self,
        wavelengths: npt.ArrayLike,
        *,
        method: str = "linear",
        extrapolate: str = "constant",
    ) -> Spectrum:
        """Resample the spectrum at new wavelengths, with the interpolation method named.

        ``"linear"`` is piecewise linear; ``"cubic"`` a natural-free not-a-knot cubic spline
        (SciPy ``CubicSpline``); ``"pchip"`` shape-preserving (no overshoot: keeps a
        reflectance inside [0, 1]); ``"nearest"`` nearest sample; ``"sprague"`` the
        fifth-order Sprague (1880) polynomial CIE 167:2005 recommends for uniformly spaced
        spectral data (>= 6 uniform samples; two points extended at each end with CIE 167's
        coefficients; exact for polynomials up to degree 4). Outside the sampled range:
        ``extrapolate="constant"`` repeats the end values (CIE 015:2018 §7.2.2), ``"zero"``
        gives 0, ``"error"`` raises.
        """
        m = check_option(method, INTERPOLATION_METHODS, "interpolation method")
        e = check_option(extrapolate, EXTRAPOLATION_METHODS, "extrapolation method (extrapolate)")
        w = _as_wavelengths(np.atleast_1d(as_real_ndarray(wavelengths, "wavelengths")), 1)
        x, y = self.wavelengths, self.values
        lo, hi = x[0], x[-1]
        outside = (w < lo) | (w > hi)
        if e == "error" and np.any(outside):
            raise InvalidInputError(
                f"wavelengths {w.min():g}-{w.max():g} nm reach outside the sampled range "
                f"{lo:g}-{hi:g} nm of {self.name or 'the spectrum'}"
            )
        wc = np.clip(w, lo, hi)
        if m == "linear":
            yy = (
                np.interp(wc, x, y)
                if y.ndim == 1
                else np.stack([np.interp(wc, x, y[:, k]) for k in range(y.shape[1])], axis=1)
            )
        elif m == "sprague":
            if self.interval is None or len(x) < 6:
                raise InvalidInputError(
                    "Sprague interpolation needs uniformly spaced data with >= 6 samples"
                )
            yy = _sprague(x, y, wc)
        elif m == "nearest":
            j = np.clip(np.searchsorted(x, wc), 1, len(x) - 1)
            j = np.where(np.abs(x[j - 1] - wc) <= np.abs(x[j] - wc), j - 1, j)
            yy = y[j]
        else:
            from scipy.interpolate import CubicSpline, PchipInterpolator

            f = CubicSpline(x, y, axis=0) if m == "cubic" else PchipInterpolator(x, y, axis=0)
            yy = f(wc)
        yy = np.array(yy, dtype=np.float64)
        if e == "zero" and np.any(outside):
            yy[outside] = 0.0
        return Spectrum(w, yy, name=self.name, labels=self.labels)

    def resample(
        self,
        start: float,
        stop: float,
        step: float,
        *,
        method: str = "linear",
        extrapolate: str = "constant",
    ) -> Spectrum:
        """Resample the spectrum on the uniform grid ``start, start + step, ..., stop`` (nm).

        Examples
        --------
        >>> Spectrum([400, 500], [0.0, 1.0]).resample(400, 500, 25).values.tolist()
        [0.0, 0.25, 0.5, 0.75, 1.0]
        """
        start = as_real(start, "start")
        stop = as_real(stop, "stop")
        step = as_real(step, "step", positive=True)
        if not stop > start:
            raise InvalidInputError(f"expected start < stop, got start {start:g}, stop {stop:g}")
        count = (stop - start) / step
        # the grid's memory is bounded before it is built (8 bytes a sample, x2 for the result)
        check_memory(
            min(16.0 * (count + 1) * max(1, self.values.size // len(self)), 2.0**80),
            "the grid start..stop by step",
        )
        n = round(count)
        if not np.isclose(start + n * step, stop):
            raise InvalidInputError(
                f"expected (stop - start) = {stop - start:g} to be a multiple of step {step:g}"
            )
        grid = start + step * np.arange(n + 1, dtype=np.float64)
        return self.interpolate(grid, method=method, extrapolate=extrapolate)

    def trim(self, start: float, stop: float) -> Spectrum:
        """Keep samples with ``start <= wavelength <= stop`` (``-inf`` / ``inf`` for no bound)."""
        start = as_real(start, "start", allow_inf=True)
        stop = as_real(stop, "stop", allow_inf=True)
        keep = (self.wavelengths >= start) & (self.wavelengths <= stop)
        if keep.sum() < 2:
            raise InvalidInputError(f"fewer than 2 samples within {start:g}-{stop:g} nm")
        return Spectrum(self.wavelengths[keep], self.values[keep], self.name, self.labels)

    def normalize(self, at: float | str = "peak") -> Spectrum:
        """Scaled so the value at ``at`` nm (linear interpolation) or the peak is 1."""
        if isinstance(at, str):
            if at != "peak":
                raise InvalidInputError(
                    f"expected at as a wavelength (nm) or 'peak', got {at!r:.40}"
                )
            ref = np.max(self.values, axis=0)
        else:
            nm = as_real(at, "at")
            lo, hi = self.range
            if not lo <= nm <= hi:
                raise InvalidInputError(
                    f"expected at within the sampled range {lo:g}-{hi:g} nm, got {nm:g}"
                )
            ref = self.interpolate([nm], extrapolate="error").values[0]
        if np.any(ref == 0):
            raise InvalidInputError(f"cannot normalise: the value at {at} is 0")
        return Spectrum(self.wavelengths, self.values / ref, self.name, self.labels)

    # ---- arithmetic -------------------------------------------------------------------
    def _other(self, other: Any, op: str) -> np.ndarray | float:
        if isinstance(other, Spectrum):
            if other.wavelengths.shape != self.wavelengths.shape or not np.allclose(
                other.wavelengths, self.wavelengths, rtol=0, atol=1e-9
            ):
                raise InvalidInputError(
                    f"cannot {op} spectra on different wavelength grids "
                    f"({self!r} and {other!r}); resample one onto the other first"
                )
            v = other.values
            if v.ndim == 1 and self.values.ndim == 2:
                v = v[:, None]
            elif v.ndim == 2 and self.values.ndim == 1:
                raise InvalidInputError(
                    f"cannot {op} a single curve with a multi-curve spectrum on the left; "
                    "swap the operands"
                )
            return v
        if isinstance(other, int | float | np.floating | np.integer):
            return float(other)
        return NotImplemented

    def _binary(self, other: Any, op: str, f: Any) -> Spectrum:
        v = self._other(other, op)
        if v is NotImplemented:
            return NotImplemented
        if isinstance(v, float) and not np.isfinite(v):
            raise InvalidInputError(f"cannot {op} by {v}: expected a finite number")
        with np.errstate(divide="raise", invalid="raise", over="raise"):
            try:
                out = f(self.values, v)
            except FloatingPointError as exc:
                what = "overflow" if "overflow" in str(exc) else "division by zero"
                raise InvalidInputError(f"cannot {op}: {what}") from exc
        return Spectrum(self.wavelengths, out, self.name, self.labels)

    def __add__(self, other: Any) -> Spectrum:
        """Add a spectrum on the same grid or a real scalar."""
        return self._binary(other, "add", np.add)

    def __radd__(self, other: Any) -> Spectrum:
        """Add to a real scalar (``other + self``)."""
        return self._binary(other, "add", np.add)

    def __sub__(self, other: Any) -> Spectrum:
        """Subtract a spectrum on the same grid or a real scalar."""
        return self._binary(other, "subtract", np.subtract)

    def __rsub__(self, other: Any) -> Spectrum:
        """Subtract from a real scalar (``other - self``)."""
        return self._binary(other, "subtract", lambda a, b: b - a)

    def __mul__(self, other: Any) -> Spectrum:
        """Multiply by a spectrum on the same grid or a real scalar."""
        return self._binary(other, "multiply", np.multiply)

    def __rmul__(self, other: Any) -> Spectrum:
        """Multiply by a real scalar on the left (``other * self``)."""
        return self._binary(other, "multiply", np.multiply)

    def __truediv__(self, other: Any) -> Spectrum:
        """Divide by a spectrum on the same grid or a real scalar."""
        return self._binary(other, "divide", np.divide)

    def __neg__(self) -> Spectrum:
        """Negate the values, same grid, name and labels."""
        return Spectrum(self.wavelengths, -self.values, self.name, self.labels)

    def allclose(self, other: Spectrum, *, atol: float = 1e-12) -> bool:
        """Tell whether ``other`` has the same grid and values within ``atol``."""
        if not isinstance(other, Spectrum):
            raise TypeError(f"expected other as a Spectrum, got {describe(other)}")
        atol = as_real(atol, "atol", nonnegative=True)
        return bool(
            self.wavelengths.shape == other.wavelengths.shape
            and np.allclose(self.wavelengths, other.wavelengths, rtol=0, atol=1e-9)
            and self.values.shape == other.values.shape
            and np.allclose(self.values, other.values, rtol=0, atol=atol)
        )

    @classmethod
    def from_columns(
        cls,
        wavelengths: npt.ArrayLike,
        columns: Sequence[npt.ArrayLike],
        *,
        labels: Sequence[str] = (),
        name: str = "",
    ) -> Spectrum:
        """K curves on one grid from K sequences."""
        if isinstance(columns, str | bytes) or not isinstance(columns, Sequence) or not columns:
            raise InvalidInputError(
                f"expected columns as a non-empty sequence of arrays, got {describe(columns)}"
            )
        cols = [as_real_ndarray(c, f"columns[{i}]", ndim=1) for i, c in enumerate(columns)]
        if len({c.shape for c in cols}) != 1:
            raise InvalidInputError(
                f"expected columns of equal length, got lengths {[len(c) for c in cols]}"
            )
        if isinstance(labels, str) or not isinstance(labels, Sequence):
            raise TypeError(f"expected labels as a sequence of str, got {describe(labels)}")
        return cls(
            as_real_ndarray(wavelengths, "wavelengths"), np.stack(cols, 1), name, tuple(labels)
        )
