"""Diffraction point-spread functions: Zernike pupils, the Fraunhofer FFT, OTF and MTF.

Scalar Fraunhofer diffraction (Goodman, *Introduction to Fourier Optics*, 3rd ed., ch. 4
and 6): the amplitude spread function of an aberrated imaging system is the Fourier
transform of its pupil function, the intensity PSF its squared modulus, and the OTF the
Fourier transform of the intensity PSF (the normalised autocorrelation of the pupil).

Units: wavelengths, pixel pitches and Zernike coefficients in **metres** (SI, like the rest of
:mod:`imageform.optics`); spatial frequencies in **cycles/mm**. A Zernike coefficient is the
RMS wavefront error of its term over the pupil (Noll normalisation), as an optical path
difference in metres, so one aberrated lens gives fewer waves at longer wavelengths.

Arrays: the pupil's ``x`` runs along columns (axis 1) and ``y`` along rows (axis 0), with
``theta = atan2(y, x)``. A PSF of odd or even size ``n`` has the optical axis at pixel
``(n // 2, n // 2)``; no 180-degree image inversion is applied.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    check_memory,
    describe,
    finite_result,
    format_shape,
)
from imageform.errors import InvalidInputError

__all__ = [
    "TransferFunction",
    "diffraction_limited_mtf",
    "diffraction_psf",
    "field_psfs",
    "mtf",
    "noll_to_nm",
    "otf",
    "pixel_mtf",
    "polychromatic_psf",
    "psf_from_pupil",
    "pupil_function",
    "zernike",
    "zernike_defocus",
    "zernike_radial",
    "zernike_wavefront",
]


class TransferFunction(NamedTuple):
    """An optical transfer function on the PSF's DFT grid (zero frequency at the centre).

    ``fx`` (columns) and ``fy`` (rows) are the frequencies in cycles/mm; ``value[i, k]`` is
    the transfer at ``(fx[k], fy[i])``, normalised to 1 at zero frequency.
    """

    fx: np.ndarray
    fy: np.ndarray
    value: np.ndarray


# --- Zernike polynomials (Noll 1976) ------------------------------------------------------

#: The highest radial order evaluated: the explicit sum of :func:`zernike_radial` cancels
#: terms of alternating sign, off from the Legendre form :math:`R_n^0(\rho) =
#: P_{n/2}(2\rho^2 - 1)` by 7e-7 at n = 30, 2.5e-3 at n = 40 and 25 at n = 50 (measured);
#: beyond n = 30 it is refused rather than returned wrong.
MAX_ZERNIKE_ORDER = 30
#: The highest Noll index evaluated: the last term of row :data:`MAX_ZERNIKE_ORDER`.
MAX_NOLL_INDEX = (MAX_ZERNIKE_ORDER + 1) * (MAX_ZERNIKE_ORDER + 2) // 2


def _pupil_coords(rho: Any, theta: Any) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """``rho`` and ``theta`` as finite real arrays and their broadcast shape (bounded)."""
    r = as_real_array(rho, "rho")
    t = as_real_array(theta, "theta")
    try:
        shape = np.broadcast_shapes(r.shape, t.shape)
    except ValueError:
        raise InvalidInputError(
            f"expected rho and theta of shapes that broadcast, got {format_shape(r.shape)} "
            f"and {format_shape(t.shape)}"
        ) from None
    check_memory(8.0 * math.prod(shape) * 3, "rho and theta", "the polynomial")
    return r, t, shape


def noll_to_nm(j: int) -> tuple[int, int]:
    """Return the radial order ``n`` and azimuthal frequency ``m`` of Noll's ``j``-th Zernike term.

    Noll (1976), *J. Opt. Soc. Am.* 66, 207, Table I: terms are ordered by ``n``, then by
    ``|m|``; within a pair of equal ``|m| > 0`` the even ``j`` takes ``cos(m theta)`` (here
    ``m > 0``) and the odd ``j`` takes ``sin(|m| theta)`` (here ``m < 0``). Row ``n`` holds
    ``j`` from ``n(n+1)/2 + 1`` to ``(n+1)(n+2)/2``.

    Examples
    --------
    >>> [noll_to_nm(j) for j in (1, 2, 3, 4, 5, 6, 7, 8, 11, 22)]
    [(0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2), (3, -1), (3, 1), (4, 0), (6, 0)]
    """
    j = as_int(j, "j (Noll index)", minimum=1)
    n = int((math.isqrt(8 * j - 7) - 1) // 2)  # largest n with n(n+1)/2 < j
    while n * (n + 1) // 2 >= j:  # pragma: no cover - guards isqrt rounding
        n -= 1
    while (n + 1) * (n + 2) // 2 < j:  # pragma: no cover
        n += 1
    k = j - n * (n + 1) // 2 - 1  # position in row n, 0-based
    m_abs = 2 * ((k + 1) // 2) if n % 2 == 0 else 2 * (k // 2) + 1
    if m_abs == 0:
        return n, 0
    return n, (m_abs if j % 2 == 0 else -m_abs)


def zernike_radial(n: int, m: int, rho: ArrayLike) -> np.ndarray:
    r"""Evaluate the Zernike radial polynomial :math:`R_n^{|m|}(\rho)` (unnormalised, ``R(1) = 1``).

    .. math::

        R_n^{m}(\rho) = \sum_{s=0}^{(n-m)/2}
            \frac{(-1)^s (n-s)!}{s!\,(\tfrac{n+m}{2}-s)!\,(\tfrac{n-m}{2}-s)!}\,\rho^{n-2s}

    (Noll 1976, eq. 2; Born & Wolf, *Principles of Optics*, sec. 9.2.) ``n - |m|`` must be even
    and non-negative.

    Examples
    --------
    >>> zernike_radial(4, 0, np.array([0.0, 1.0])).tolist()   # 6 rho^4 - 6 rho^2 + 1
    [1.0, 1.0]
    """
    n = as_int(n, "n", minimum=0, maximum=MAX_ZERNIKE_ORDER)
    m = abs(as_int(m, "m", minimum=-n, maximum=n))
    if m > n or (n - m) % 2:
        raise InvalidInputError(f"expected n - |m| even and >= 0, got n = {n}, m = {m}")
    return _radial(n, m, as_real_array(rho, "rho"))


def _radial(n: int, m: int, r: np.ndarray, *, check: bool = True) -> np.ndarray:
    def total() -> np.ndarray:
        out = np.zeros_like(r)
        for s in range((n - m) // 2 + 1):
            c = (-1) ** s * math.factorial(n - s)
            c //= (
                math.factorial(s)
                * math.factorial((n + m) // 2 - s)
                * math.factorial((n - m) // 2 - s)
            )
            out = out + c * r ** (n - 2 * s)
        return out

    if not check:  # the caller checks the finished sum once (and ignores the warnings)
        return total()
    # rho far beyond the rim (the polynomial is defined on the unit disc) overflows
    return finite_result(f"the radial polynomial R_{n}^{m}", total, rho=r)


def zernike(j: int, rho: ArrayLike, theta: ArrayLike) -> np.ndarray:
    r"""Noll's ``j``-th Zernike polynomial, unit RMS over the unit disc.

    .. math::

        Z_j = \sqrt{n+1}\,R_n^0(\rho) \ (m = 0),\qquad
        Z_j = \sqrt{2(n+1)}\,R_n^{|m|}(\rho)\,
              \begin{cases}\cos m\theta & j\ \text{even}\\
                            \sin |m|\theta & j\ \text{odd}\end{cases}

    so that :math:`\frac{1}{\pi}\int_0^1\!\int_0^{2\pi} Z_j Z_{j'}\,\rho\,d\theta\,d\rho
    = \delta_{jj'}` (Noll 1976, eqs. 3-4). Named terms: 1 piston, 2-3 tilt, 4 defocus,
    5-6 astigmatism, 7-8 coma, 9-10 trefoil, 11 primary spherical, 22 secondary spherical.
    Any ``j >= 1`` is computed from the general formula.

    Parameters
    ----------
    j : int
        Noll index (>= 1).
    rho, theta : array_like
        Normalised pupil radius (1 at the rim) and azimuth in radians, broadcast together.

    Examples
    --------
    >>> round(float(zernike(4, 1.0, 0.0)), 6), round(float(zernike(4, 0.0, 0.0)), 6)
    (1.732051, -1.732051)
    """
    j = as_int(j, "j (Noll index)", minimum=1, maximum=MAX_NOLL_INDEX)
    r, t, _ = _pupil_coords(rho, theta)
    return _zernike(j, r, t)


def _zernike(j: int, r: np.ndarray, t: np.ndarray, *, check: bool = True) -> np.ndarray:
    n, m = noll_to_nm(j)
    radial = _radial(n, abs(m), r, check=check)
    if m == 0:
        return math.sqrt(n + 1) * radial * np.ones_like(t)
    ang = np.cos(m * t) if m > 0 else np.sin(-m * t)
    return math.sqrt(2 * (n + 1)) * radial * ang


def _coefficients(coefficients: Any) -> dict[int, float]:
    """``{j: c}`` from a mapping ``{j: c}`` or a sequence ``c[0] = c_1, c[1] = c_2, ...``."""
    if coefficients is None:
        return {}
    if isinstance(coefficients, Mapping):
        items = list(coefficients.items())
    else:
        if isinstance(coefficients, str | bytes):
            raise InvalidInputError(
                "expected coefficients as a mapping {Noll j: metres} or a sequence "
                f"(index 0 is j = 1), got {describe(coefficients)}"
            )
        arr = np.asarray(coefficients)
        if arr.ndim != 1 or arr.dtype.kind not in "iuf":
            raise InvalidInputError(
                "expected coefficients as a mapping {Noll j: metres} or a 1-D real sequence "
                f"(index 0 is j = 1), got {describe(coefficients)}"
            )
        items = [(i + 1, v) for i, v in enumerate(arr.tolist())]
    out: dict[int, float] = {}
    for j, c in items:
        jj = as_int(j, "coefficients key (Noll j)", minimum=1, maximum=MAX_NOLL_INDEX)
        out[jj] = out.get(jj, 0.0) + as_real(c, f"coefficients[{jj}] (metres RMS)")
    return out


def zernike_wavefront(
    coefficients: Mapping[int, float] | ArrayLike, rho: ArrayLike, theta: ArrayLike
) -> np.ndarray:
    r"""Compute the wavefront :math:`W(\rho, \theta) = \sum_j c_j Z_j(\rho, \theta)`.

    ``coefficients`` is a mapping ``{j: c_j}`` (Noll ``j``) or a sequence whose index 0 is
    ``j = 1``; ``W`` is in the coefficients' unit (metres in this module; each ``c_j`` is that
    term's RMS over the pupil, so the total RMS is :math:`\sqrt{\sum_{j>1} c_j^2}`).

    Examples
    --------
    >>> round(float(zernike_wavefront({4: 1e-7}, 1.0, 0.0)) * 1e9, 3)   # nm at the rim
    173.205
    """
    coef = _coefficients(coefficients)
    r, t, shape = _pupil_coords(rho, theta)

    def total() -> np.ndarray:
        out = np.zeros(shape)
        for j, c in sorted(coef.items()):
            if c != 0.0:
                out = out + c * _zernike(j, r, t, check=False)
        return out

    try:
        return finite_result("the wavefront", total, rho=r)
    except InvalidInputError:  # a term overflowed: name the coefficients too
        raise InvalidInputError(
            "the wavefront is out of the float range for these coefficients and rho"
        ) from None


def zernike_defocus(coc: ArrayLike, *, f_number: float) -> Array:
    r"""Return the Zernike defocus coefficient (Noll ``j = 4``) of a geometric blur circle.

    The coefficient is in metres RMS.

    A focusing error ``dz`` behind a lens of working f-number ``N`` adds the wavefront
    :math:`W_{020}\rho^2` with :math:`W_{020} = dz / (8 N^2)` (Goodman eq. 6-42 at the
    pupil's rim, paraxial); geometric optics images a point as a disc of diameter
    ``c = dz / N`` (the circle of confusion, :func:`imageform.optics.circle_of_confusion`).
    Since :math:`\rho^2 = (1 + Z_4/\sqrt{3}) / 2`, the Noll coefficient is

    .. math::

        c_4 = \frac{W_{020}}{2\sqrt{3}} = \frac{c}{16\sqrt{3}\,N}

    (piston dropped). ``coc`` in metres (scalar or array, >= 0); the sign of the defocus is
    lost in ``c``, and the PSF of ``+c_4`` and ``-c_4`` are mirror images anyway.

    Examples
    --------
    >>> round(zernike_defocus(30e-6, f_number=4) * 1e9, 2)   # 30 um blur at f/4: nm RMS
    270.63
    """
    fn = as_real(f_number, "f_number", positive=True)
    c = as_real_array(coc, "coc (metres)", nonnegative=True)
    out = c / (16 * math.sqrt(3) * fn)
    return float(out) if out.ndim == 0 else out


# --- pupil and PSF ------------------------------------------------------------------------


def _disc_grid(diameter: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return amplitude, rho and theta of a disc ``diameter`` samples wide on a square grid.

    The diameter is any real > 0; the disc is centred on a grid point of an even-sized square
    grid. Samples are in (1) or out (0) by their centre (``rho <= 1``): the discrete
    autocorrelation of a point-sampled disc matches the analytic MTF to ~2e-4 at 256
    samples, where an area-weighted (grey) rim is ten times worse (its ``sum a^2 < sum a``
    biases the zero-frequency normalisation by ~2/(3D)).
    """
    size = 2 * (math.ceil(diameter / 2) + 1)
    c = np.arange(size, dtype=np.float64) - size // 2
    y, x = c[:, None], c[None, :]
    rho = np.hypot(x, y) / (diameter / 2)
    return (rho <= 1.0).astype(np.float64), rho, np.arctan2(y, x)


def pupil_function(
    coefficients: Mapping[int, float] | ArrayLike | None = None,
    *,
    wavelength: float,
    n_samples: float = 256,
    aperture: ArrayLike | None = None,
) -> np.ndarray:
    r"""Return the complex pupil function :math:`P = A\,\exp(2\pi i\,W / \lambda)`.

    Goodman, *Introduction to Fourier Optics*, eq. 6-39 (the generalised pupil function):
    ``A`` is the aperture's amplitude transmission and ``W`` the wavefront aberration
    (optical path difference, metres) from :func:`zernike_wavefront`.

    Parameters
    ----------
    coefficients : mapping {j: metres} or sequence, optional
        Zernike coefficients (Noll index ``j``, RMS optical path difference in metres).
    wavelength : float
        Metres.
    n_samples : float
        Pupil diameter in samples for the default circular aperture (need not be whole;
        samples whose centre is within the rim are 1, others 0). The array is the smallest
        even square that holds the disc with a margin, its centre on sample
        ``(size // 2, size // 2)``.
    aperture : array (M, M), optional
        A given aperture (bool or transmission in [0, 1]) whose width spans the pupil's
        diameter; Zernike terms are evaluated with ``rho = 1`` at ``M / 2`` samples from
        sample ``(M // 2, M // 2)``. ``n_samples`` is then ignored.

    Returns
    -------
    complex array (M, M)

    Examples
    --------
    >>> p = pupil_function({4: 50e-9}, wavelength=550e-9, n_samples=64)
    >>> p.shape, p.dtype.name, bool(abs(abs(p[33, 33]) - 1) < 1e-12)
    ((66, 66), 'complex128', True)
    """
    lam = as_real(wavelength, "wavelength (m)", positive=True)
    coef = _coefficients(coefficients)
    if aperture is None:
        d = as_real(n_samples, "n_samples (pupil diameter in samples)", minimum=2.0)
        check_memory(16.0 * (d + 4) ** 2 * 4, "n_samples", "the pupil")
        amp, rho, theta = _disc_grid(d)
    else:
        amp = _as_aperture(aperture)
        m = amp.shape[0]
        c = np.arange(m, dtype=np.float64) - m // 2
        y, x = c[:, None], c[None, :]
        rho, theta = np.hypot(x, y) / (m / 2), np.arctan2(y, x)
    if not coef:
        return amp.astype(np.complex128)
    inside = amp > 0
    w = np.zeros_like(amp)
    w[inside] = zernike_wavefront(coef, rho[inside], theta[inside])
    return amp * np.exp((2j * np.pi / lam) * w)


def _as_aperture(aperture: Any) -> np.ndarray:
    a = np.asarray(aperture)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] < 2:
        raise InvalidInputError(
            f"expected aperture as a square 2-D array (M, M), got {describe(aperture)}"
        )
    if a.dtype.kind not in "biuf":
        raise InvalidInputError(
            f"expected aperture as bool or real transmission in [0, 1], got {describe(aperture)}"
        )
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 1:
        raise InvalidInputError("expected aperture transmission finite and within [0, 1]")
    if not a.any():
        raise InvalidInputError("expected aperture with some transmission, got all zeros")
    return a


def psf_from_pupil(pupil: ArrayLike, *, pad_to: int) -> np.ndarray:
    r"""Compute the intensity PSF of ``pupil`` zero-padded to ``pad_to`` samples (Fraunhofer FFT).

    .. math::

        h[k, l] = \frac{1}{M^2}\Big|\sum_{p, q} P[p, q]\,
                  e^{-2\pi i (kp + lq)/M}\Big|^2,\qquad M = \text{pad\_to}

    (Goodman, eq. 6-13: the coherent impulse response is the Fourier transform of the
    pupil). By Parseval the sum of ``h`` equals :math:`\sum |P|^2`, the transmitted energy,
    so the PSF is *not* renormalised here. If the pupil is ``D`` samples wide, the image
    sample spacing is :math:`\lambda N D / M = \lambda N / Q` with ``Q = M / D`` (``Q >= 2``
    samples the PSF at or above Nyquist). The optical axis is at ``(M // 2, M // 2)``.

    Examples
    --------
    >>> h = psf_from_pupil(pupil_function(wavelength=5e-7, n_samples=32), pad_to=128)
    >>> h.shape, float(h.sum())   # the 797 samples of a 32-sample disc (pi 16^2 = 804.2)
    ((128, 128), 797.0)
    """
    p = np.asarray(pupil)
    if p.ndim != 2 or p.dtype.kind not in "biufc":
        raise InvalidInputError(f"expected pupil as a 2-D numeric array, got {describe(pupil)}")
    size = as_int(pad_to, "pad_to", minimum=max(p.shape))
    check_memory(16.0 * size * size * 2, "pad_to", "the padded pupil")
    from scipy import fft  # imported on use, not with imageform.optics

    field = fft.fft2(p.astype(np.complex128), s=(size, size))
    h = (field.real**2 + field.imag**2) / (size * size)
    return fft.fftshift(h)


_NAMES = "wavelength, f_number and pixel_pitch"


def _check_sampling(
    lam: float, f_number: float, pitch: float, size: int | None, n_pupil: float, names: str
) -> None:
    """Refuse, before any integer is formed, a sampling whose padded pupil would not fit.

    ``Q = lambda N / pitch`` sets the FFT size (about ``Q n_pupil``, or ``k (size + 1)`` with
    ``k = 2 / Q`` when ``Q < 2``); its ``(M, D)`` complex rows must fit the memory limit.
    """
    with np.errstate(all="ignore"):
        q = np.float64(lam) * f_number / pitch
        k = 1.0 if q >= 2 else 2.0 / q
        n_pad = max(q * k * n_pupil, k * ((size or 0) + 1), 8.0)
        n_bytes = 32.0 * n_pad * (n_pad / (q * k) + 4)
    check_memory(
        float(n_bytes),
        names,
        f"the padded pupil (Q = lambda N / pitch = {float(q):.3g})",
    )


def _sampled_psf(
    pupil_of: Any,
    lam: float,
    f_number: float,
    pitch: float,
    size: int | None,
    n_pupil: float,
    fixed_diameter: int | None,
) -> np.ndarray:
    """PSF of ``size`` pixels at ``pitch`` (unit sum). See :func:`diffraction_psf`."""
    from scipy import fft

    q = lam * f_number / pitch  # samples per lambda N: FFT size / pupil diameter
    k = 1 if q >= 2 else math.ceil(2 / q)  # oversample the image plane when Q < 2
    qk = q * k
    want = 0 if size is None else k * (size + 1)
    if fixed_diameter is None:
        n_pad = fft.next_fast_len(max(math.ceil(qk * n_pupil), want, 8))
        diameter = n_pad / qk  # exact: the FFT grid spacing is pitch / k
        step = 1.0
    else:
        n_pad = fft.next_fast_len(max(round(qk * fixed_diameter), want, fixed_diameter + 2))
        diameter = fixed_diameter
        step = n_pad / (qk * fixed_diameter)  # fine-grid samples per (pitch / k)
    c = n_pad // 2
    if step == 1.0 and size is not None:
        # pruned FFT: transform the pupil's rows, keep the output columns, then those columns
        check_memory(16.0 * n_pad * (diameter + 4) * 2, "pixel_pitch", "the padded pupil")
        freq = ((np.arange(size) - size // 2) * k) % n_pad  # unshifted DFT indices
        rows = fft.fft(pupil_of(diameter), n=n_pad, axis=1)[:, freq]
        field = fft.fft(rows, n=n_pad, axis=0)[freq, :]
        out = field.real**2 + field.imag**2
        return out / out.sum()
    h = psf_from_pupil(pupil_of(diameter), pad_to=n_pad)
    n_out = (n_pad // k if step == 1.0 else int(n_pad / (k * step))) if size is None else size
    idx = (np.arange(n_out) - n_out // 2) * (k * step) + c
    if step == 1.0:
        ii = idx.astype(np.int64)
        ii = ii[(ii >= 0) & (ii < n_pad)] if size is None else ii
        out = h[np.ix_(ii, ii)]
    else:
        from scipy.ndimage import map_coordinates

        yy, xx = np.meshgrid(idx, idx, indexing="ij")
        out = np.clip(map_coordinates(h, [yy, xx], order=3, mode="grid-wrap"), 0.0, None)
    return out / out.sum()


def diffraction_psf(
    coefficients: Mapping[int, float] | ArrayLike | None = None,
    *,
    wavelength: float,
    f_number: float,
    pixel_pitch: float,
    size: int | None = 64,
    n_pupil: int = 256,
    aperture: ArrayLike | None = None,
) -> np.ndarray:
    r"""Compute the diffraction PSF of an (aberrated) circular pupil, sampled at ``pixel_pitch``.

    The pupil function (:func:`pupil_function`) is Fourier transformed
    (:func:`psf_from_pupil`). An FFT of ``M`` samples over a pupil ``D`` samples wide gives
    image samples :math:`\Delta = \lambda N D / M`, so the padding ratio must be

    .. math::

        Q = \frac{M}{D} = \frac{\lambda N}{\Delta}

    (Goodman, sec. 4.2 and 6.2; :math:`\lambda N` is the image-space scale of the pupil's
    Fourier transform, :math:`f / D = N`). **Approach: the pupil is sized to the FFT.** ``M``
    is the next fast FFT length at or above ``Q n_pupil`` (and the output size), and the
    circular aperture is drawn ``D = M / Q`` samples wide (``D >= n_pupil``, not necessarily
    whole), so the FFT grid spacing *equals* ``pixel_pitch`` exactly and no image-plane
    resampling is done (only the ``size`` output rows and columns are transformed: the
    pupil's rows first, then the kept columns). When ``Q < 2`` (pixels coarser than the
    Nyquist spacing :math:`\lambda N / 2`), the PSF is computed on a grid ``k = ceil(2/Q)``
    times finer and point-sampled every ``k``-th sample. A given ``aperture`` array keeps its
    own width ``D = M_a``; the PSF is then computed at the nearest FFT spacing and resampled
    to ``pixel_pitch`` with cubic splines (accurate to about 1e-3 of the peak when Q >= 2).

    The PSF is point-sampled (no pixel-area integration: multiply the MTF by the pixel
    aperture's sinc for that), normalised to unit sum over the returned array, and has the
    optical axis at pixel ``(size // 2, size // 2)``.

    Parameters
    ----------
    coefficients : mapping {j: metres} or sequence, optional
        Zernike coefficients (Noll ``j``), RMS optical path difference in metres.
    wavelength, f_number, pixel_pitch : float
        Wavelength (m), working f-number ``N`` (image-space, ``f / D``) and the image-plane
        sample spacing (m).
    size : int or None
        Output width in pixels (square); ``None`` returns the whole FFT period.
    n_pupil : int
        Minimum pupil diameter in samples (accuracy of the pupil's rim and of aberrations).
    aperture : array (M, M), optional
        A given aperture instead of the circle (see :func:`pupil_function`).

    Returns
    -------
    array (size, size), float64, sums to 1.

    Examples
    --------
    >>> h = diffraction_psf(wavelength=550e-9, f_number=4, pixel_pitch=1e-6, size=33)
    >>> h.shape, round(float(h.sum()), 12), bool(h.argmax() == 16 * 33 + 16)
    ((33, 33), 1.0, True)
    """
    lam = as_real(wavelength, "wavelength (m)", positive=True)
    fn = as_real(f_number, "f_number", positive=True)
    pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    n = None if size is None else as_int(size, "size (pixels)", minimum=1, maximum=1 << 14)
    n_p = as_int(n_pupil, "n_pupil (samples)", minimum=8, maximum=1 << 14)
    coef = _coefficients(coefficients)
    if aperture is None:
        _check_sampling(lam, fn, pitch, n, n_p, _NAMES)

        def pupil_of(d: float) -> np.ndarray:
            return pupil_function(coef, wavelength=lam, n_samples=d)

        return _sampled_psf(pupil_of, lam, fn, pitch, n, n_p, None)
    amp = _as_aperture(aperture)
    _check_sampling(lam, fn, pitch, n, max(n_p, amp.shape[0]), _NAMES)

    def given(d: float) -> np.ndarray:
        return pupil_function(coef, wavelength=lam, aperture=amp)

    return _sampled_psf(given, lam, fn, pitch, n, n_p, amp.shape[0])


def polychromatic_psf(
    coefficients: Mapping[int, float] | ArrayLike | None = None,
    *,
    wavelengths: Sequence[float] | np.ndarray,
    weights: Sequence[float] | np.ndarray | None = None,
    f_number: float,
    pixel_pitch: float,
    size: int = 64,
    n_pupil: int = 256,
    aperture: ArrayLike | None = None,
) -> np.ndarray:
    r"""Compute a polychromatic PSF: the weighted sum of unit-sum monochromatic PSFs.

    .. math::

        h = \frac{\sum_i w_i\, h_{\lambda_i}}{\sum_i w_i}

    (incoherent superposition; Goodman sec. 6.1.2). ``weights`` (default equal) are the
    relative detected energies per wavelength, e.g. the source spectrum times the channel's
    sensitivity times the wavelength step. The Zernike coefficients are optical path
    differences (metres), the same for every wavelength. Returns ``(size, size)``, unit sum.

    Examples
    --------
    >>> h = polychromatic_psf(wavelengths=[450e-9, 550e-9, 650e-9], f_number=4,
    ...                       pixel_pitch=1e-6, size=33)
    >>> round(float(h.sum()), 12)
    1.0
    """
    lams = as_real_array(wavelengths, "wavelengths (m)", ndim=(0, 1), positive=True).ravel()
    if lams.size == 0:
        raise InvalidInputError("expected wavelengths as one or more values in metres, got none")
    w = (
        np.ones_like(lams)
        if weights is None
        else as_real_array(weights, "weights", ndim=(0, 1), nonnegative=True).ravel()
    )
    if w.shape != lams.shape:
        raise InvalidInputError(
            f"expected weights with one value per wavelength ({lams.size}), got {w.size}"
        )
    if w.sum() <= 0:
        raise InvalidInputError("expected weights finite, >= 0 and not all zero")
    n = as_int(size, "size (pixels)", minimum=1, maximum=1 << 14)
    fn = as_real(f_number, "f_number", positive=True)
    pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    n_p = as_int(n_pupil, "n_pupil (samples)", minimum=8, maximum=1 << 14)
    names = "wavelengths, f_number and pixel_pitch"  # the extremes bound every wavelength
    _check_sampling(float(lams.max()), fn, pitch, n, n_p, names)
    _check_sampling(float(lams.min()), fn, pitch, n, n_p, names)
    out = np.zeros((n, n))
    for lam, wi in zip(lams.tolist(), w.tolist(), strict=True):
        if wi > 0:
            out += wi * diffraction_psf(
                coefficients,
                wavelength=lam,
                f_number=f_number,
                pixel_pitch=pixel_pitch,
                size=n,
                n_pupil=n_pupil,
                aperture=aperture,
            )
    return out / out.sum()


def field_psfs(
    coefficients: ArrayLike,
    *,
    wavelength: float,
    f_number: float,
    pixel_pitch: float,
    size: int = 64,
    n_pupil: int = 256,
) -> np.ndarray:
    """Field-dependent PSFs by zones: one PSF per zone of a grid of field positions.

    ``coefficients`` has shape ``(rows, cols, J)``: the Zernike coefficients (metres,
    index 0 is Noll ``j = 1``) of each zone of the image, row by row from the top. Returns
    ``(rows, cols, size, size)``, each PSF of unit sum (see :func:`diffraction_psf`). An
    image is then blurred zone by zone (tiled convolution), the usual approximation of an
    isoplanatic patch per zone (Goodman sec. 6.1).

    Examples
    --------
    >>> c = np.zeros((2, 3, 8)); c[..., 3] = 40e-9; c[1, 2, 7] = 80e-9   # defocus; coma
    >>> field_psfs(c, wavelength=550e-9, f_number=4, pixel_pitch=1e-6, size=17).shape
    (2, 3, 17, 17)
    """
    c = np.asarray(coefficients)
    if c.ndim != 3 or c.dtype.kind not in "iuf" or c.shape[2] < 1:
        raise InvalidInputError(
            "expected coefficients of shape (rows, cols, J) in metres (index 0 is Noll j = 1), "
            f"got {describe(coefficients)}"
        )
    n = as_int(size, "size (pixels)", minimum=1, maximum=1 << 14)
    rows, cols = c.shape[:2]
    check_memory(8.0 * rows * cols * n * n, "coefficients", "the field PSFs")
    out = np.empty((rows, cols, n, n))
    for i in range(rows):
        for k in range(cols):
            out[i, k] = diffraction_psf(
                c[i, k],
                wavelength=wavelength,
                f_number=f_number,
                pixel_pitch=pixel_pitch,
                size=n,
                n_pupil=n_pupil,
            )
    return out


# --- transfer functions -------------------------------------------------------------------


def otf(psf: ArrayLike, *, pixel_pitch: float) -> TransferFunction:
    r"""Compute the optical transfer function of a sampled PSF, frequencies in cycles/mm.

    .. math::

        \mathrm{OTF}(f_x, f_y) = \frac{\sum_{k,l} h[k,l]\, e^{-2\pi i (f_x x_l + f_y y_k)}}
                                       {\sum_{k,l} h[k,l]}

    with pixel ``(n // 2, n // 2)`` as the origin (Goodman eq. 6-28), on the DFT grid
    :math:`f = j / (n\,\Delta)`, shifted so that zero frequency is at ``(n // 2, n // 2)``.

    Examples
    --------
    >>> t = otf(diffraction_psf(wavelength=5e-7, f_number=4, pixel_pitch=5e-7, size=32),
    ...         pixel_pitch=5e-7)
    >>> float(t.value[16, 16].real), round(float(t.fx[17]), 3)   # 1 / (32 * 0.0005 mm)
    (1.0, 62.5)
    """
    h = as_real_array(psf, "psf", ndim=2, check=False)
    if h.size == 0:
        raise InvalidInputError(f"expected psf as a non-empty 2-D array, got {describe(psf)}")
    pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    total = h.sum()
    if not np.isfinite(total) or total == 0:
        raise InvalidInputError("expected psf with a finite, nonzero sum")
    from scipy import fft

    value = fft.fftshift(fft.fft2(fft.ifftshift(h))) / total
    pitch_mm = pitch * 1e3
    fy = fft.fftshift(fft.fftfreq(h.shape[0], d=pitch_mm))
    fx = fft.fftshift(fft.fftfreq(h.shape[1], d=pitch_mm))
    return TransferFunction(fx, fy, value)


def mtf(psf: ArrayLike, *, pixel_pitch: float) -> TransferFunction:
    r"""Compute the modulation transfer function :math:`|\mathrm{OTF}|` (1 at zero frequency).

    Frequencies in cycles/mm, on the grid of :func:`otf`.

    Examples
    --------
    >>> t = mtf(diffraction_psf(wavelength=5e-7, f_number=4, pixel_pitch=5e-7, size=None),
    ...         pixel_pitch=5e-7)
    >>> c = t.value.shape[0] // 2
    >>> bool(abs(t.value[c, c + 40] - diffraction_limited_mtf(t.fx[c + 40], wavelength=5e-7,
    ...      f_number=4)) < 1e-3)
    True
    """
    t = otf(psf, pixel_pitch=pixel_pitch)
    return TransferFunction(t.fx, t.fy, np.abs(t.value))


def diffraction_limited_mtf(
    frequency: ArrayLike, *, wavelength: float, f_number: float
) -> np.ndarray:
    r"""Compute the MTF of an aberration-free circular pupil (incoherent light).

    .. math::

        \mathrm{MTF}(\nu) = \frac{2}{\pi}\left(\arccos x - x\sqrt{1 - x^2}\right),
        \quad x = \frac{\nu}{\nu_c},\ \nu_c = \frac{1}{\lambda N}

    and 0 for :math:`x \ge 1` (Goodman eq. 6-31). ``frequency`` in cycles/mm (its absolute
    value is used), ``wavelength`` in metres.

    Examples
    --------
    >>> float(diffraction_limited_mtf(0.0, wavelength=5e-7, f_number=4))
    1.0
    >>> round(float(diffraction_limited_mtf(250.0, wavelength=5e-7, f_number=4)), 4)
    0.391
    """
    lam = as_real(wavelength, "wavelength (m)", positive=True)
    fn = as_real(f_number, "f_number", positive=True)
    nu = np.abs(as_real_array(frequency, "frequency (cycles/mm)"))
    cutoff_mm = finite_result(
        "lambda N (the cutoff period)", lambda: lam * 1e3 * fn, wavelength=lam, f_number=fn
    )
    x = np.clip(nu * cutoff_mm, 0.0, 1.0)  # lambda in mm
    return (2 / np.pi) * (np.arccos(x) - x * np.sqrt(1 - x * x))


def pixel_mtf(frequency: ArrayLike, *, pixel_pitch: float, fill_factor: float = 1.0) -> np.ndarray:
    r"""Compute the MTF of a square pixel aperture (uniform response over its active area).

    .. math::

        \mathrm{MTF}_{pix}(\nu) = |\mathrm{sinc}(\nu\, a)|,\qquad
        a = p \sqrt{F},\ \mathrm{sinc}(t) = \frac{\sin \pi t}{\pi t}

    along one axis, for pixels of pitch ``p`` whose active area is a centred square holding
    the fraction ``F`` (the fill factor) of the pixel (Goodman sec. 6.3; Boreman, *Modulation
    Transfer Function in Optical and Electro-Optical Systems*, ch. 2). ``frequency`` in
    cycles/mm, ``pixel_pitch`` in metres. The system MTF is the product of the optics' and
    the pixel's.

    Examples
    --------
    >>> round(float(pixel_mtf(250.0, pixel_pitch=2e-6)), 4)   # Nyquist: 2 / pi
    0.6366
    """
    pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    ff = as_real(fill_factor, "fill_factor", positive=True, maximum=1.0)
    nu = as_real_array(frequency, "frequency (cycles/mm)")
    return finite_result(
        "the pixel MTF",
        lambda: np.abs(np.sinc(nu * pitch * 1e3 * math.sqrt(ff))),
        frequency=nu,
        pixel_pitch=pitch,
    )
