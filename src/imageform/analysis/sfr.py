r"""Slanted-edge spatial frequency response (ISO 12233 e-SFR) and slanted-edge ROI finding.

The e-SFR of ISO 12233 (2014/2017 editions, the "e-SFR" method, after Burns 2000) measures
the modulation transfer of a camera from one slightly slanted straight edge:

1. the edge location in each row is the centroid of the row's derivative (taps
   ``[-0.5, 0.5]``), recomputed once inside a Hamming window centred on the first fit;
2. a polynomial ``x = p(y)`` (a line by default, order 1; ISO 12233:2017 and Burns's
   ``sfrmat4``/``sfrmat5`` allow higher orders) is fitted to those locations by least squares;
3. every pixel's distance to the edge along its row, ``x - p(y)``, is binned in
   ``1/oversampling`` pixel (4x by default) and the pixel values averaged per bin: the
   super-resolved edge spread function (ESF) — possible because the slant spreads the
   rows' phases over the bin; a bin is ``cos(theta)/oversampling`` pixel along the edge
   normal and the frequencies are scaled by it (the cos correction of ISO 12233:2014 and
   ``sfrmat3``);
4. the line spread function (LSF) is the ESF's derivative (ISO's FIR ``[-0.5, 0, 0.5]``),
   multiplied by a Hamming window as long as the ESF array, centred on the LSF's centroid
   (zero beyond: ``sfrmat3`` centres the LSF in the array and windows the array);
5. the SFR is ``|DFT(LSF)|`` normalised by its value at zero frequency, divided by the
   derivative filter's own transfer (the "finite-difference correction",
   :math:`\mathrm{sinc}(2 f \Delta)` for the three-tap FIR, :math:`\mathrm{sinc}(f\Delta)`
   for two taps, with :math:`\mathrm{sinc}(x) = \sin(\pi x)/(\pi x)`, :math:`\Delta =
   1/\text{oversampling}` pixel), capped at 10 like ``sfrmat3``;
6. MTF50 and MTF10 are the lowest frequencies where the SFR falls to 0.5 and 0.1 (linear
   interpolation on the zero-padded DFT of the same windowed LSF).

Against ``sfrmat3`` on the same crop the SFR agrees at the DFT frequencies but for the
derivative correction, which ``sfrmat3``'s ``fir2fix`` evaluates one frequency sample too
high (``x = pi i / (N/2 + 2)`` at the sample ``i - 1``; here the FIR's exact transfer,
``sinc(2 k / N)`` at sample ``k``: about 0.1 % lower SFR near MTF50); and ``sfrmat3`` reads
MTF50 by linear interpolation between DFT samples ``q / (N cos theta)`` apart, which on
the convex part of a falling SFR reads high (0.5 % on its own 300 x 125 crops); the
zero-padded DFT here reads the windowed LSF's transform itself. On rendered edges of known
MTF both read within 0.5 %.

Frequencies are in **cycles/pixel along the edge normal** (multiply by the pixel pitch's
inverse for cycles/mm); Nyquist is 0.5. Colour images give R, G, B and the luminance record
``Y = 0.213 R + 0.715 G + 0.072 B`` (the ITU-R BT.709 weights as rounded in Burns's
``sfrmat3``-``sfrmat5``, implementations of the ISO 12233 e-SFR by one of its authors).
The pixel values must be linear in exposure (ISO applies the inverse OECF first): decode
gamma-encoded images before measuring.

:func:`find_slanted_edges` finds measurable edges in a photograph of dark squares on a light
background (or light squares on a dark one) turned a few degrees (the motif of the ISO
12233:2014 e-SFR chart and of most SFR charts), and :func:`render_slanted_edge` renders an
ideal edge of known ESF by supersampled area integration, to test the method.

References
----------
- ISO 12233:2017, *Photography - Electronic still picture imaging - Resolution and spatial
  frequency responses*: the edge-based SFR (e-SFR) method and its annex on the algorithm
  (the projection along the edge normal, i.e. the cos(theta) frequency correction; the
  polynomial edge fit of ``sfrmat4``/``sfrmat5`` follows the later editions).
- P. D. Burns, "Slanted-edge MTF for digital camera and scanner analysis", Proc. IS&T PICS
  Conference, 2000, pp. 135-138.
- P. D. Burns, ``sfrmat3``/``sfrmat5`` (reference MATLAB implementations of ISO 12233).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, Literal, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    check_memory,
    check_option,
    check_real_values,
    describe,
    format_shape,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "SFR_LUMINANCE_WEIGHTS",
    "SFRResult",
    "SlantedEdgeROI",
    "find_slanted_edges",
    "fit_gaussian_sigma",
    "mtf_crossing",
    "render_sfr_chart",
    "render_slanted_edge",
    "slanted_edge_sfr",
]

#: R, G, B weights of the luminance record (ITU-R BT.709 as rounded in ``sfrmat3``-``5``).
SFR_LUMINANCE_WEIGHTS: tuple[float, float, float] = (0.213, 0.715, 0.072)

_DERIVATIVES = ("central", "two_point")
#: find_slanted_edges thresholds the image at this many levels across its range (and its middle)
_N_LEVELS = 16
#: largest RMS distance (px) of a side's threshold crossings from a parabola through them
_MAX_BEND_RMS = 0.5
#: largest difference (deg) between the threshold fit's and the e-SFR's angle of a found edge
_MAX_ANGLE_GAP = 1.0
#: a dark shape whose bounding box is this many times longer one way is a rectangle
_RECTANGLE = 1.25
#: the sides of a dark shape seen along the rows (a vertical edge)
_VERTICAL = ("left", "right")
_MAX_CORRECTION = 10.0


class SFRResult(NamedTuple):
    """The e-SFR of one edge region (see :func:`slanted_edge_sfr`).

    Attributes
    ----------
    frequency : ndarray, shape (n,)
        Cycles/pixel along the edge normal, from 0 to 1 (the DFT grid of the ESF bins).
    sfr : ndarray, shape (n, k)
        The SFR of each channel (1 at zero frequency), finite-difference corrected.
    channels : tuple of str
        The ``k`` channel names: ``("Y",)`` for a grey image, ``("R", "G", "B", "Y")`` for RGB.
    mtf50, mtf10 : ndarray, shape (k,)
        Lowest frequency (cycles/pixel) where each SFR falls to 0.5 / 0.1 (NaN if it does not
        within 1 cycle/pixel).
    angle : float
        The edge's angle in degrees from the vertical (a vertical-ish edge) or from the
        horizontal (a horizontal-ish one), from the luminance fit; positive when the edge's
        column grows with the row (vertical) or its row grows with the column (horizontal).
    orientation : str
        ``"vertical"`` or ``"horizontal"``.
    edge : ndarray, shape (k, order + 1)
        Each channel's edge polynomial (``numpy.polyval`` order, highest power first), the
        edge's column as a function of the row for a vertical edge (row of column for a
        horizontal one), in ROI pixel coordinates (pixel centres at integers).
    esf : ndarray, shape (m, k)
        The oversampled edge spread functions (bins of ``1/oversampling`` pixel along the
        rows, ``cos(angle)/oversampling`` along the normal), over the distances the ROI's
        middle row reaches on its channel's own edge fit.
    lsf : ndarray, shape (m, k)
        The windowed line spread functions.
    oversampling : int
        Bins per pixel of ``esf``/``lsf``.
    rows_used : int
        Rows (along the edge) used after trimming to a whole number of phase cycles.
    """

    frequency: np.ndarray
    sfr: np.ndarray
    channels: tuple[str, ...]
    mtf50: np.ndarray
    mtf10: np.ndarray
    angle: float
    orientation: str
    edge: np.ndarray
    esf: np.ndarray
    lsf: np.ndarray
    oversampling: int
    rows_used: int

    def channel(self, name: str) -> np.ndarray:
        """Return the SFR curve of channel ``name`` (``"Y"``, ``"R"``, ``"G"`` or ``"B"``)."""
        if name not in self.channels:
            raise InvalidInputError(
                f"expected name as one of {self.channels}, got {describe(name)}"
            )
        return self.sfr[:, self.channels.index(name)]


class SlantedEdgeROI(NamedTuple):
    """A region of interest around one slanted edge (see :func:`find_slanted_edges`).

    ``x, y`` are the top-left pixel (column, row), ``width, height`` the size; ``angle`` is
    the edge's angle in degrees from the vertical (``orientation == "vertical"``) or the
    horizontal; ``side`` names the square's side (``"left"``, ``"right"``, ``"top"``,
    ``"bottom"``); ``center`` is the edge's midpoint ``(u, v)`` in image pixels.
    """

    x: int
    y: int
    width: int
    height: int
    angle: float
    orientation: str
    side: str
    center: tuple[float, float]

    @property
    def roi(self) -> tuple[int, int, int, int]:
        """``(x, y, width, height)``, as :func:`slanted_edge_sfr`'s ``roi``."""
        return (self.x, self.y, self.width, self.height)

    def crop(self, image: ArrayLike) -> np.ndarray:
        """Return the ROI's pixels of ``image`` (a view); the ROI must lie inside ``image``."""
        if image is None or isinstance(image, str | bytes):
            raise InvalidInputError(f"expected image as an array, got {describe(image)}")
        arr = np.asarray(image)
        if arr.dtype.kind not in "buif" or arr.ndim not in (2, 3):
            raise InvalidInputError(
                f"expected image as an (H, W) or (H, W, C) array of numbers, got {describe(image)}"
            )
        if self.y + self.height > arr.shape[0] or self.x + self.width > arr.shape[1]:
            raise InvalidInputError(
                f"expected image of at least {self.x + self.width}x{self.y + self.height} "
                f"pixels (width x height) for this ROI, got shape {format_shape(arr.shape)}"
            )
        return arr[self.y : self.y + self.height, self.x : self.x + self.width]


# --- input ----------------------------------------------------------------------------------


def _as_image(image: Any, name: str = "image") -> np.ndarray:
    """Return a float64 image (H, W) or (H, W, 3) (a (H, W, 1) is squeezed); refuse the rest."""
    if image is None or isinstance(image, str | bytes):
        raise InvalidInputError(
            f"expected {name} as a 2-d or (H, W, 3) array, got {describe(image)}"
        )
    arr = np.asarray(image)
    if arr.dtype.kind not in "uif":
        raise InvalidInputError(
            f"expected {name} of integer or float pixels, got {describe(image)}"
        )
    if arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[:, :, 0]
    if arr.ndim not in (2, 3) or (arr.ndim == 3 and arr.shape[2] != 3) or arr.size == 0:
        raise InvalidInputError(
            f"expected {name} of shape (H, W) or (H, W, 3), non-empty, got {describe(image)}"
        )
    out = arr.astype(np.float64)
    if not np.isfinite(out).all():
        raise InvalidInputError(f"{name} contains NaN or inf")
    return out


def _crop(img: np.ndarray, roi: Any) -> np.ndarray:
    if roi is None:
        return img
    try:
        vals = [int(v) for v in roi]
        ok = len(vals) == 4 and all(float(v) == int(v) for v in roi)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InvalidInputError(
            f"expected roi as 4 integers (x, y, width, height), got {describe(roi)}"
        )
    x, y, w, h = vals
    H, W = img.shape[:2]
    if x < 0 or y < 0 or w < 1 or h < 1 or x + w > W or y + h > H:
        raise InvalidInputError(
            f"expected roi (x, y, width, height) inside the {W}x{H} image, got {tuple(vals)}"
        )
    return img[y : y + h, x : x + w]


def _weights(weights: object) -> np.ndarray:
    """Return the R, G, B luminance weights: 3 finite real numbers."""
    w = as_real_array(weights, "weights", ndim=1, check=False)
    if w.shape != (3,):
        raise InvalidInputError(f"expected weights as 3 finite numbers, got {describe(weights)}")
    check_real_values(w, "weights")
    return w


def _luminance(img: np.ndarray, weights: Any) -> np.ndarray:
    if img.ndim == 2:
        return img
    w = np.asarray(weights, dtype=np.float64)
    return np.tensordot(img, w, axes=([2], [0]))


# --- the e-SFR steps ------------------------------------------------------------------------


def _hamming_rows(n: int, mids: np.ndarray) -> np.ndarray:
    """Return one Hamming window of ``n`` samples per centre in ``mids`` (a row each).

    ``0.54 + 0.46 cos(pi (k - mid) / w)`` with ``w`` the larger distance to an end
    (``sfrmat3``'s ``ahamming``), 0.08 beyond.
    """
    k = np.arange(n, dtype=np.float64)
    wid = np.maximum(np.maximum(mids, n - 1 - mids), 1.0)
    arg = np.clip((k[None, :] - mids[:, None]) / wid[:, None], -1.0, 1.0)
    return np.asarray(0.54 + 0.46 * np.cos(np.pi * arg))


def _row_centroids(a: np.ndarray, windows: np.ndarray | None) -> np.ndarray:
    """Edge location per row: the centroid of ``a[:, j+1] - a[:, j]`` (at ``j + 0.5``)."""
    d = np.diff(a, axis=1)
    if windows is not None:
        d = d * windows
    x = np.arange(d.shape[1], dtype=np.float64) + 0.5
    s = d.sum(axis=1)
    sign = np.sign(s.sum()) or 1.0
    d = d * sign
    s = s * sign
    with np.errstate(invalid="ignore", divide="ignore"):
        c = (d * x).sum(axis=1) / s
    return np.asarray(c)


def _fit_edge(a: np.ndarray, order: int) -> np.ndarray:
    """Polynomial ``x = p(y)`` through the per-row centroids, refined inside Hamming windows."""
    rows = np.arange(a.shape[0], dtype=np.float64)
    c = _row_centroids(a, None)
    if not np.isfinite(c).all():
        raise DegenerateConfigurationError(
            "no edge found in image (or its roi): a row has no contrast"
        )
    p = _polyfit(rows, c, order)
    n = a.shape[1] - 1
    win = _hamming_rows(n, np.polyval(p, rows) - 0.5)
    c2 = _row_centroids(a, win)
    if np.isfinite(c2).all():
        p = _polyfit(rows, c2, order)
    return np.asarray(p)


def _polyfit(x: np.ndarray, y: np.ndarray, order: int) -> np.ndarray:
    """``numpy.polyfit(x, y, order)``; a line by its closed form (the same to ~1e-15)."""
    if order != 1:
        return np.asarray(np.polyfit(x, y, order))
    xm, ym = float(x.mean()), float(y.mean())
    dx = x - xm
    b = float(dx @ (y - ym)) / float(dx @ dx)
    return np.array([b, ym - b * xm])


def _project(a: np.ndarray, p: np.ndarray, q: int, cos_ref: float) -> np.ndarray:
    """ESF: pixel values averaged in bins of ``1/q`` pixel of distance to the edge along the rows.

    As in ISO 12233 and ``sfrmat3``, the distance is taken along the row, ``x - p(y)``: a
    row's pixels then fall ``q`` bins apart with one sub-bin phase, and the rows' phases
    (``q p(y)`` modulo 1) cover the bin evenly over a whole number of phase cycles. (Binning
    the distance along the normal, ``(x - p(y)) cos(theta)``, steps ``q cos(theta)`` bins per
    pixel: at some angles the phases bunch within the bins and bias the SFR by several
    percent, e.g. +6 % at 14 deg.) A bin is ``cos_ref / q`` pixel along the normal; on a
    curved edge each row's distance is scaled by ``cos(theta(y)) / cos_ref``. The bins are
    those the middle row reaches (the ends seen by about half of the rows), empty bins
    interpolated.
    """
    h, w = a.shape
    rows = np.arange(h, dtype=np.float64)
    xe = np.polyval(p, rows)
    cols = np.arange(w, dtype=np.float64)
    d = cols[None, :] - xe[:, None]
    if len(p) > 2:  # a curved edge: the local normal distance, in units of the reference
        slope = np.polyval(np.polyder(p), rows)
        d = d * (np.cos(np.arctan(slope)) / cos_ref)[:, None]
    idx = np.rint(d * q).astype(np.int64)
    mid = (h - 1) // 2
    lo = int(idx[mid, 0])
    hi = int(idx[mid, -1])
    if hi - lo < 4 * q:
        raise DegenerateConfigurationError(
            f"the image (or its roi) is too narrow across the edge: {(hi - lo) / q:.1f} px "
            "across it; widen it or centre the edge"
        )
    keep = (idx >= lo) & (idx <= hi)
    b = idx[keep] - lo
    counts = np.bincount(b, minlength=hi - lo + 1).astype(np.float64)
    sums = np.bincount(b, weights=a[keep], minlength=hi - lo + 1)
    full = counts > 0
    if full.sum() < 0.75 * counts.size:
        raise DegenerateConfigurationError(
            f"too few edge phases in image: {int((~full).sum())} of {counts.size} ESF bins "
            "are empty; tilt the edge 2-10 deg or use more rows"
        )
    k = np.arange(counts.size, dtype=np.float64)
    esf = np.interp(k, k[full], sums[full] / counts[full])
    return esf


def _lsf(esf: np.ndarray, derivative: str) -> np.ndarray:
    if derivative == "central":
        lsf = np.empty_like(esf)
        lsf[1:-1] = 0.5 * (esf[2:] - esf[:-2])
        lsf[0] = lsf[1]
        lsf[-1] = lsf[-2]
    else:
        lsf = np.diff(esf)
    s = lsf.sum()
    if s == 0:
        raise DegenerateConfigurationError("no edge found in image (or its roi): the ESF is flat")
    lsf = lsf * np.sign(s)
    pos = np.clip(lsf, 0.0, None)
    mid = float((pos * np.arange(lsf.size)).sum() / pos.sum())
    return np.asarray(lsf * _lsf_window(lsf.size, mid))


def _lsf_window(n: int, mid: float) -> np.ndarray:
    """Return the LSF's Hamming window: the array's length, centred on the LSF's centroid.

    ``0.54 + 0.46 cos(2 pi (k - mid) / (n - 1))`` for ``|k - mid| <= (n - 1) / 2``, 0 beyond:
    ``sfrmat3`` (and ``sfrmat5`` with its Hamming option) shifts the LSF so that its centre
    is the array's middle, which drops the samples that leave the array, and windows it with
    a symmetric Hamming window over the array (``ahamming(nn, (nn + 1) / 2)``), as ISO
    12233:2017's e-SFR windows the LSF centred on itself. Its width does not grow when the
    edge lies off the ROI's middle (a window reaching the far end then tapers the LSF's long
    tail less and lowered MTF50 by 0.6 % on ``sfrmat3``'s own edge crops).
    """
    k = np.arange(n, dtype=np.float64)
    half = max((n - 1) / 2.0, 1.0)
    arg = (k - mid) / half
    return np.where(np.abs(arg) <= 1.0, 0.54 + 0.46 * np.cos(np.pi * np.clip(arg, -1, 1)), 0.0)


def _spectrum(
    lsf: np.ndarray, q: int, derivative: str, nfft: int, cos_ref: float
) -> tuple[np.ndarray, np.ndarray]:
    """Return the frequencies (cycles/pixel along the normal) and corrected SFR of ``lsf``.

    ``lsf`` has bins of ``cos_ref / q`` pixel along the normal; the DFT has ``nfft`` points.
    """
    spec = np.abs(np.fft.rfft(lsf, n=nfft))
    f = np.fft.rfftfreq(nfft, d=cos_ref / q)
    sfr = spec / spec[0]
    step = 2.0 if derivative == "central" else 1.0
    transfer = np.sinc(step * f * cos_ref / q)
    sfr = sfr / np.maximum(np.abs(transfer), 1.0 / _MAX_CORRECTION)
    sel = f <= 1.0 + 1e-12
    return f[sel], sfr[sel]


def mtf_crossing(frequency: ArrayLike, mtf: ArrayLike, level: float) -> float:
    r"""Return the lowest frequency where a falling MTF reaches ``level`` (linear interpolation).

    ``mtf_crossing(f, m, 0.5)`` is MTF50: the first ``i`` with ``m[i+1] <= level < m[i]``
    gives :math:`f_i + (f_{i+1} - f_i)(m_i - \text{level})/(m_i - m_{i+1})`; NaN if the curve
    never falls to ``level``.

    Examples
    --------
    >>> round(mtf_crossing([0.0, 0.1, 0.2], [1.0, 0.6, 0.4], 0.5), 6)
    0.15
    """
    f = as_real_array(frequency, "frequency", ndim=1, check=False)
    m = as_real_array(mtf, "mtf", ndim=1, check=False)
    if m.shape != f.shape or not f.size:
        raise InvalidInputError(
            "expected frequency and mtf as non-empty 1-d arrays of one length, got "
            f"{describe(f)} and {describe(m)}"
        )
    check_real_values(f, "frequency")
    check_real_values(m, "mtf")
    lv = as_real(level, "level", minimum=0.0, maximum=1.0)
    below = np.nonzero(m <= lv)[0]
    below = below[below > 0]
    if below.size == 0:
        return math.nan
    i = int(below[0])
    m0, m1 = m[i - 1], m[i]
    t = (m0 - lv) / (m0 - m1) if m0 != m1 else 0.0
    return float(f[i - 1] + t * (f[i] - f[i - 1]))


def fit_gaussian_sigma(frequency: ArrayLike, sfr: ArrayLike, *, angle_deg: float = 0.0) -> float:
    r"""Fit the Gaussian PSF sigma (pixels) to a measured SFR, the pixel aperture included.

    The model is the Gaussian's MTF times the square pixel's aperture taken across an edge
    at ``angle_deg`` from the pixel grid,

    .. math:: M_\sigma(f) = e^{-2\pi^2\sigma^2 f^2}\,
        \lvert\operatorname{sinc}(f\cos\theta)\,\operatorname{sinc}(f\sin\theta)\rvert,

    and :math:`\sigma \in [0, 10]` minimises :math:`\sum_i w_i (M_\sigma(f_i) - s_i)^2` over
    the finite samples with :math:`0 < f_i \le 0.5` cy/px (up to Nyquist), the weights
    :math:`w_i = 1` where :math:`s_i > 0.1` and :math:`10^{-3}` elsewhere (the noisy tail
    counts little). The Gaussian's MTF is the Fourier transform of its PSF; the pixel
    aperture's is the sinc of a unit box (ISO 12233:2017, annex D; Burns, "Slanted-edge MTF
    for digital camera and scanner analysis", PICS 2000).

    Parameters
    ----------
    frequency : array_like, shape (n,)
        Spatial frequency in cycles per pixel (e.g. :attr:`SFRResult.frequency`).
    sfr : array_like, shape (n,)
        The measured SFR of one channel at those frequencies (NaN samples are skipped).
    angle_deg : float, keyword-only
        The edge's angle from the pixel grid in degrees (:attr:`SFRResult.angle`).

    Returns
    -------
    float
        Sigma in pixels.

    Examples
    --------
    >>> f = np.linspace(0.0, 0.5, 51)
    >>> box = np.abs(np.sinc(f * np.cos(np.radians(5.0))) * np.sinc(f * np.sin(np.radians(5.0))))
    >>> s = np.exp(-2 * np.pi**2 * 0.8**2 * f**2) * box
    >>> round(fit_gaussian_sigma(f, s, angle_deg=5.0), 3)
    0.8
    """
    from scipy.optimize import minimize_scalar

    freq = as_real_array(frequency, "frequency", ndim=1, check=False)
    curve = as_real_array(sfr, "sfr", ndim=1, check=False)
    if curve.shape != freq.shape:
        raise InvalidInputError(
            "expected frequency and sfr as 1-d arrays of one length, got "
            f"{describe(freq)} and {describe(curve)}"
        )
    check_real_values(freq, "frequency")
    t = math.radians(as_real(angle_deg, "angle_deg", minimum=-90.0, maximum=90.0))
    with np.errstate(invalid="ignore"):
        keep = (freq > 0) & (freq <= 0.5) & np.isfinite(curve)
    if not keep.any():
        raise InvalidInputError(
            "expected sfr with a finite value at a frequency in (0, 0.5] cy/px, got none"
        )
    f, s = freq[keep], curve[keep]
    box = np.abs(np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t)))
    w = (s > 0.1).astype(float) + 1e-3

    def cost(sigma: float) -> float:
        model = np.exp(-2.0 * np.pi**2 * sigma**2 * f**2) * box
        return float(np.sum(w * (model - s) ** 2))

    r = minimize_scalar(cost, bounds=(0.0, 10.0), method="bounded", options={"xatol": 1e-5})
    return float(r.x)


def _edge_stages(
    img: np.ndarray, lum: np.ndarray, q: int, order: int, deriv: str
) -> tuple[str, int, float, list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """Run the e-SFR up to the LSFs (steps 1-4 of the module's list), each channel then Y.

    Returns the orientation, the rows used, ``cos(theta)`` of the luminance fit, and per
    plane (R, G, B, Y, or Y alone) the edge polynomial, the ESF and the windowed LSF; raises
    DegenerateConfigurationError where the e-SFR cannot measure the region.
    """
    gy, gx = np.abs(np.diff(lum, axis=0)).mean(), np.abs(np.diff(lum, axis=1)).mean()
    orientation = "vertical" if gx >= gy else "horizontal"
    if orientation == "horizontal":
        img = np.swapaxes(img, 0, 1)
        lum = lum.T
    h, wid = lum.shape
    if h < 8 or wid < 8:
        raise InvalidInputError(
            f"expected an ROI of at least 8 pixels along and across the edge, got {h} x {wid}"
        )
    planes = [lum] if img.ndim == 2 else [img[:, :, 0], img[:, :, 1], img[:, :, 2], lum]
    p_lum = _fit_edge(lum, order)
    slope = float(np.polyval(np.polyder(p_lum), (h - 1) / 2.0))
    if abs(slope) * h < 1.0:
        raise DegenerateConfigurationError(
            f"the edge in image is too close to {orientation}: it moves {abs(slope) * h:.2f} px "
            f"over {h} rows (needs >= 1); tilt it 2-10 deg"
        )
    rows_used = h
    if order == 1:  # a whole number of phase cycles (sfrmat3)
        rows_used = max(8, min(h, round(math.floor(abs(slope) * h) / abs(slope))))
    cos_ref = math.cos(math.atan(slope))  # the ESF bins are cos_ref / q px along the normal
    fits, esfs = [], []
    for a in planes:
        a = a[:rows_used]
        p = _fit_edge(a, order)
        esfs.append(_project(a, p, q, cos_ref))
        fits.append(p)
    m = min(e.size for e in esfs)
    esfs = [e[:m] for e in esfs]
    lsfs = [_lsf(e, deriv) for e in esfs]
    return orientation, rows_used, cos_ref, fits, esfs, lsfs


def slanted_edge_sfr(
    image: ArrayLike,
    roi: Sequence[int] | None = None,
    *,
    oversampling: int = 4,
    edge_order: int = 1,
    derivative: Literal["central", "two_point"] = "central",
    weights: Sequence[float] = SFR_LUMINANCE_WEIGHTS,
) -> SFRResult:
    r"""ISO 12233 e-SFR of one slanted edge (the slanted-edge MTF of Burns 2000).

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Linear pixel values (any real dtype). The region must hold one straight edge between
        two flat areas, turned a few degrees (2-10 deg is best) from the vertical or the
        horizontal; which one is found from the gradients.
    roi : (x, y, width, height), optional
        The region of ``image`` to measure (column, row of its top-left pixel); default all.
    oversampling : int
        ESF bins per pixel (ISO: 4).
    edge_order : int
        Order of the polynomial fitted to the per-row edge locations: 1 (a line, ISO
        12233:2014 and ``sfrmat3``) up to 5 (ISO 12233:2017 and ``sfrmat5`` allow a curved
        edge, for lens distortion). Only a line trims the rows to a whole number of phase
        cycles.
    derivative : {"central", "two_point"}
        The ESF derivative: ISO's ``[-0.5, 0, 0.5]`` (transfer
        :math:`\mathrm{sinc}(2 f / q)`) or ``[-0.5, 0.5]`` (transfer
        :math:`\mathrm{sinc}(f / q)`), ``q`` the oversampling; the SFR is divided by it.
    weights : 3 floats
        R, G, B weights of the luminance record of an RGB image.

    Returns
    -------
    SFRResult
        Frequencies in cycles/pixel (0 to 1), the SFR per channel, MTF50, MTF10, the edge
        angle and fit, the ESF and LSF.

    Notes
    -----
    With the edge ``x = p(y)`` and :math:`\theta = \arctan p'(y_\mathrm{mid})`, each pixel's
    distance to the edge along its row, :math:`x - p(y)`, is binned in :math:`\mathrm{round}(q
    (x - p(y)))` (on a curved edge scaled by :math:`\cos\theta(y)/\cos\theta`); a bin is
    :math:`\cos\theta / q` pixel along the normal. The ESF is the mean pixel value per bin,
    the LSF its windowed derivative, and

    .. math:: \mathrm{SFR}(f_k) = \frac{|\sum_n \mathrm{LSF}_n e^{-2\pi i k n / N}|}
              {|\sum_n \mathrm{LSF}_n|} \Big/ D(f_k), \qquad f_k = \frac{k q}{N \cos\theta},

    with :math:`D` the derivative's transfer (ISO 12233:2017 e-SFR; Burns 2000). The
    :math:`1/\cos\theta` frequency scale is the correction of ISO 12233:2014 and
    ``sfrmat3``; binning along the row (as they do) keeps a row's pixels exactly ``q`` bins
    apart, where binning the normal distance would bunch the phases at some angles. The ESF
    binning (a box of :math:`\cos\theta/q` pixel along the normal) is not corrected, as in
    ISO: it lowers the SFR by :math:`\mathrm{sinc}(f\cos\theta/q)`, at most 2.6 % at
    Nyquist for ``q = 4``. Angles where :math:`q\tan\theta` is close to an integer (14.0
    deg for ``q = 4``) spread the phases poorly, as in every e-SFR.

    Examples
    --------
    >>> edge = render_slanted_edge((64, 64), angle_deg=5.0, sigma=0.8)
    >>> r = slanted_edge_sfr(edge)
    >>> r.channels, round(float(r.mtf50[0]), 3), round(r.angle, 2)
    (('Y',), 0.22, 5.0)
    """
    img = _crop(_as_image(image), roi)
    q = as_int(oversampling, "oversampling", minimum=1, maximum=16)
    order = as_int(edge_order, "edge_order", minimum=1, maximum=5)
    deriv = check_option(derivative, _DERIVATIVES, "derivative")
    w = _weights(weights)

    lum = _luminance(img, w)
    orientation, rows_used, cos_ref, fits, esfs, lsfs = _edge_stages(img, lum, q, order, deriv)
    names: tuple[str, ...] = ("Y",) if img.ndim == 2 else ("R", "G", "B", "Y")
    nfft = lsfs[0].size
    fine = max(8 * nfft, 4096)
    freq = np.empty(0)
    curves, m50, m10 = [], [], []
    for lsf in lsfs:
        freq, s = _spectrum(lsf, q, deriv, nfft, cos_ref)
        ff, sf = _spectrum(lsf, q, deriv, fine, cos_ref)
        curves.append(s)
        m50.append(mtf_crossing(ff, sf, 0.5))
        m10.append(mtf_crossing(ff, sf, 0.1))
    # the angle (and hence the edge) from the luminance fit of the rows used
    angle = math.degrees(math.atan(float(np.polyval(np.polyder(fits[-1]), (rows_used - 1) / 2))))
    return SFRResult(
        frequency=freq,
        sfr=np.stack(curves, axis=1),
        channels=names,
        mtf50=np.asarray(m50),
        mtf10=np.asarray(m10),
        angle=angle,
        orientation=orientation,
        edge=np.stack(fits),
        esf=np.stack(esfs, axis=1),
        lsf=np.stack([x[: min(len(y) for y in lsfs)] for x in lsfs], axis=1),
        oversampling=q,
        rows_used=rows_used,
    )


# --- synthetic edges ------------------------------------------------------------------------


def _gauss_esf(sigma: float) -> Callable[[np.ndarray], np.ndarray]:
    from scipy.special import ndtr

    if sigma == 0:
        return lambda d: (d >= 0).astype(np.float64)
    return lambda d: np.asarray(ndtr(d / sigma))


@_deprecate.parameters(renamed={"angle": "angle_deg"})
def render_slanted_edge(
    shape: Sequence[int],
    *,
    angle_deg: float = 5.0,
    sigma: float = 0.0,
    esf: Callable[[np.ndarray], np.ndarray] | None = None,
    low: float = 0.2,
    high: float = 0.8,
    center: Sequence[float] | None = None,
    orientation: str = "vertical",
    supersampling: int = 16,
) -> np.ndarray:
    r"""Render an ideal slanted edge of known ESF, integrated over each pixel's area.

    The edge passes through ``center`` (``(u, v)``, default the image centre) at ``angle_deg``
    degrees (``angle`` is its deprecated name) from the vertical (``orientation="vertical"``:
    dark on the left, light on the right) or the horizontal (dark above). A point at signed
    distance ``d`` (pixels, along the normal, towards the light side) has the value
    ``low + (high - low) ESF(d)``: with ``esf=None``, :math:`\mathrm{ESF}(d) = \Phi(d/\sigma)`
    (a Gaussian PSF of standard deviation ``sigma`` pixels, MTF
    :math:`e^{-2\pi^2\sigma^2 f^2}`; a step when ``sigma`` is 0). Each pixel averages
    ``supersampling``\ :sup:`2` points, so the image's MTF along the normal is the ESF's times
    the pixel aperture's,
    :math:`\mathrm{sinc}(f\cos\theta)\,\mathrm{sinc}(f\sin\theta)`.

    Examples
    --------
    >>> render_slanted_edge((4, 6), angle_deg=0.0).round(2)[0].tolist()
    [0.2, 0.2, 0.2, 0.8, 0.8, 0.8]
    """
    if not isinstance(shape, Sequence) or len(shape) != 2:
        raise InvalidInputError(f"expected shape as (height, width), got {describe(shape)}")
    h = as_int(shape[0], "shape[0]", minimum=1)
    w = as_int(shape[1], "shape[1]", minimum=1)
    th = math.radians(as_real(angle_deg, "angle_deg", minimum=-45.0, maximum=45.0))
    sg = as_real(sigma, "sigma", nonnegative=True)
    lo, hi = as_real(low, "low"), as_real(high, "high")
    ori = check_option(orientation, ("vertical", "horizontal"), "orientation")
    s = as_int(supersampling, "supersampling", minimum=1, maximum=64)
    if ori == "horizontal":
        h, w = w, h
    check_memory(8.0 * h * w * s * s * 3, "shape", "the supersampled edge")
    if center is None:
        cu, cv = (w - 1) / 2.0, (h - 1) / 2.0
    else:
        if isinstance(center, str | bytes) or not hasattr(center, "__iter__"):
            raise InvalidInputError(f"expected center as (u, v), got {describe(center)}")
        c = [as_real(v, "center") for v in center]
        if len(c) != 2:
            raise InvalidInputError(f"expected center as (u, v), got {describe(center)}")
        cu, cv = (c[0], c[1]) if ori == "vertical" else (c[1], c[0])
    if esf is not None and not callable(esf):
        raise TypeError(
            f"expected esf as a function of the distance (or None), got {describe(esf)}"
        )
    f = esf if esf is not None else _gauss_esf(sg)
    off = (np.arange(s) + 0.5) / s - 0.5
    u = (np.arange(w)[:, None] + off[None, :]).ravel()
    v = (np.arange(h)[:, None] + off[None, :]).ravel()
    d = (u[None, :] - cu) * math.cos(th) - (v[:, None] - cv) * math.sin(th)
    val = np.asarray(f(d), dtype=np.float64).reshape(h, s, w, s).mean(axis=(1, 3))
    out = lo + (hi - lo) * val
    return out.T.copy() if ori == "horizontal" else out


@_deprecate.parameters(renamed={"angle": "angle_deg"})
def render_sfr_chart(
    shape: Sequence[int] = (240, 320),
    *,
    grid: Sequence[int] = (2, 3),
    side: float | None = None,
    angle_deg: float = 5.0,
    sigma: float = 0.8,
    low: float = 0.2,
    high: float = 0.8,
    supersampling: int = 8,
) -> np.ndarray:
    r"""Render a slanted-edge chart: ``grid = (rows, columns)`` dark squares on a light background.

    Each square is turned ``angle_deg`` degrees (clockwise as displayed; ``angle`` is its
    deprecated name), blurred by a Gaussian PSF of ``sigma`` pixels and integrated over each
    pixel's area.

    The squares (side ``side`` pixels, default 45 % of a grid cell) are centred in the cells
    of a regular grid over the image. A square's blurred indicator is exact: in the square's
    own axes ``(s, t)`` the isotropic Gaussian is separable, so a square of half-side ``a``
    gives :math:`[\Phi(\tfrac{s+a}{\sigma}) - \Phi(\tfrac{s-a}{\sigma})]
    [\Phi(\tfrac{t+a}{\sigma}) - \Phi(\tfrac{t-a}{\sigma})]`; away from the corners its
    edges have the MTF of :func:`render_slanted_edge` with the same ``sigma``.

    Examples
    --------
    >>> render_sfr_chart((60, 80), grid=(1, 1)).shape
    (60, 80)
    """
    from scipy.special import ndtr

    if not isinstance(shape, Sequence) or len(shape) != 2:
        raise InvalidInputError(f"expected shape as (height, width), got {describe(shape)}")
    h = as_int(shape[0], "shape[0]", minimum=8)
    w = as_int(shape[1], "shape[1]", minimum=8)
    if not isinstance(grid, Sequence) or len(grid) != 2:
        raise InvalidInputError(f"expected grid as (rows, columns), got {describe(grid)}")
    # at most one square per 4 x 4 pixels: the loop below runs once per square
    gr = as_int(grid[0], "grid[0]", minimum=1, maximum=max(1, h // 4))
    gc = as_int(grid[1], "grid[1]", minimum=1, maximum=max(1, w // 4))
    th = math.radians(as_real(angle_deg, "angle_deg", minimum=-45.0, maximum=45.0))
    sg = as_real(sigma, "sigma", positive=True)
    lo, hi = as_real(low, "low"), as_real(high, "high")
    s = as_int(supersampling, "supersampling", minimum=1, maximum=32)
    cell = min(h / gr, w / gc)
    sd = 0.45 * cell if side is None else as_real(side, "side", positive=True)
    check_memory(8.0 * h * w * s * s * 4, "shape", "the supersampled chart")
    off = (np.arange(s) + 0.5) / s - 0.5
    u_all = (np.arange(w)[:, None] + off[None, :]).ravel()
    v_all = (np.arange(h)[:, None] + off[None, :]).ravel()
    c, sn = math.cos(th), math.sin(th)
    a = sd / 2.0
    reach = a * math.sqrt(2.0) + 8.0 * sg + 1.0  # beyond it the square's blur is < 1e-15
    dark = np.zeros((h * s, w * s))
    for i in range(gr):
        for j in range(gc):
            cu = (j + 0.5) * w / gc - 0.5
            cv = (i + 0.5) * h / gr - 0.5
            cs = (np.abs(u_all - cu) <= reach).nonzero()[0]
            rs = (np.abs(v_all - cv) <= reach).nonzero()[0]
            if cs.size == 0 or rs.size == 0:
                continue
            u = u_all[cs][None, :] - cu
            v = v_all[rs][:, None] - cv
            ss = u * c + v * sn
            tt = -u * sn + v * c
            dark[rs[0] : rs[-1] + 1, cs[0] : cs[-1] + 1] += (
                ndtr((ss + a) / sg) - ndtr((ss - a) / sg)
            ) * (ndtr((tt + a) / sg) - ndtr((tt - a) / sg))
    val = dark.reshape(h, s, w, s).mean(axis=(1, 3))
    return np.asarray(hi - (hi - lo) * val)


# --- finding slanted edges in a chart ---------------------------------------------------------


def _subpixel_side(
    g: np.ndarray, t: float, lines: np.ndarray, first: np.ndarray, step: int
) -> np.ndarray:
    """Return the threshold crossing along each line (row of ``g``) next to index ``first``.

    ``first`` is the first dark pixel seen walking in direction ``step``.
    """
    n = g.shape[1]
    k = first - step  # the light neighbour
    inside = (k >= 0) & (k < n)
    kk = np.clip(k, 0, n - 1)
    a, b = g[lines, kk], g[lines, first]
    den = a - b
    frac = np.where(den != 0, (a - t) / np.where(den != 0, den, 1.0), 0.5)
    out = np.where(inside, kk + step * np.clip(frac, 0.0, 1.0), first.astype(np.float64))
    return np.asarray(out, dtype=np.float64)


Components = list[tuple[int, int, np.ndarray]]


def _components_at(
    g: np.ndarray, t: float, msz: int, *, kernel: bool | None = None, border: bool = False
) -> tuple[Components, Components]:
    """Components of ``g < t`` and of ``g > t`` at least ``msz`` px across, off the border.

    With ``border`` the components that touch the image's border instead (at least ``msz``
    px across).

    Returns the dark and the light components, ``(r0, c0, mask)`` each: the top-left pixel
    in ``g`` and the mask over its bounding box (4-connected labelling), in the order of
    their first pixels. The numba kernel :func:`imageform._kernels.components.level_runs`
    labels both in one scan where numba imports (``kernel=None``), else its twin, scipy's
    ``ndimage.label`` and ``find_objects`` on each.
    """
    H, W = g.shape
    if kernel is None:
        from imageform._backend import have_numba

        kernel = have_numba()
    out: list[Components] = []
    if kernel:
        from imageform._kernels.components import level_runs, paint_runs

        for runs, comp, boxes in level_runs(np.ascontiguousarray(g, dtype=np.float64), float(t)):
            r0, r1, c0, c1 = boxes.T
            off = (r0 > 0) & (c0 > 0) & (r1 < H) & (c1 < W)
            ok = (~off if border else off) & (np.minimum(r1 - r0, c1 - c0) >= msz)
            sel = np.nonzero(ok)[0]
            masks = paint_runs(runs, comp, sel, boxes) if sel.size else []
            out.append([(int(r0[k]), int(c0[k]), mk) for k, mk in zip(sel, masks, strict=True)])
        return out[0], out[1]
    from scipy import ndimage

    for part in (g < t, g > t):
        labels, _n = ndimage.label(part)
        found: Components = []
        for lab, sl in enumerate(ndimage.find_objects(labels), start=1):
            if sl is None:
                continue
            r0, r1, c0, c1 = sl[0].start, sl[0].stop, sl[1].start, sl[1].stop
            touches = r0 == 0 or c0 == 0 or r1 == H or c1 == W
            if touches != border or min(r1 - r0, c1 - c0) < msz:
                continue
            found.append((r0, c0, labels[r0:r1, c0:c1] == lab))
        out.append(found)
    return out[0], out[1]


def _pick_levels(
    g: np.ndarray, found: Sequence[tuple[float, int, int, np.ndarray]]
) -> list[tuple[float, int, int, np.ndarray]]:
    """Each component of ``found`` (``(t, r0, c0, mask)``) once, at its best level.

    A component seen at several levels (the same bounding box within 2 px) is kept at the
    level ``t`` nearest the middle of its grey and its surround's (:func:`_component_greys`,
    measured where it is first seen: they hardly move with the level).
    """
    comps: dict[tuple[int, int], list[list[Any]]] = {}  # by box corner / 8: score, t, r0, ...
    out: list[list[Any]] = []
    for t, r0, c0, m in found:
        bx = (r0, c0, r0 + m.shape[0], c0 + m.shape[1])
        near = [
            e
            for i in (r0 // 8 - 1, r0 // 8, r0 // 8 + 1)
            for j in (c0 // 8 - 1, c0 // 8, c0 // 8 + 1)
            for e in comps.get((i, j), [])
        ]
        for entry in sorted(near, key=lambda e: e[6]):  # the first seen first, as a list
            e0, e1, e2, e3 = entry[5]
            if (
                abs(e0 - r0) <= 2
                and abs(e1 - c0) <= 2
                and abs(e2 - bx[2]) <= 2
                and abs(e3 - bx[3]) <= 2
            ):
                score = _offset(t, entry[4])
                if score < entry[0]:
                    entry[:4] = [score, t, (r0, c0), m]
                    entry[5] = bx
                break
        else:
            greys = _component_greys(g, m, r0, c0)
            entry = [_offset(t, greys), t, (r0, c0), m, greys, bx, len(out)]
            comps.setdefault((r0 // 8, c0 // 8), []).append(entry)
            out.append(entry)
    return [(e[1], e[2][0], e[2][1], e[3]) for e in out]


def find_slanted_edges(
    image: ArrayLike,
    *,
    min_angle: float = 2.0,
    max_angle: float = 10.0,
    min_size: int = 20,
    roi_length: float = 0.5,
    roi_width: int | None = None,
    weights: Sequence[float] = SFR_LUMINANCE_WEIGHTS,
) -> list[SlantedEdgeROI]:
    """Find measurable slanted edges in a photograph of squares darker or lighter than around.

    The image is thresholded halfway between its 2nd and 98th percentiles, then at 15 levels
    evenly spaced between them (a chart's square often sits on a grey surround of its own among
    other patches, and only a level between the square's two greys separates it); at each level,
    each dark connected component (4-connected labelling: a numba kernel, or scipy's) that does
    not touch the border, is at least ``min_size`` pixels across and fills at least 60 % of its
    bounding box is taken as a square. Its four sides are fitted by least squares through the
    sub-pixel threshold crossings of the middle half of its rows (left, right sides) and columns
    (top, bottom); a side whose crossings stray more than 0.5 px RMS from a parabola through
    them (a notch, a corner, another shape joined to it) is skipped. A side whose angle from the
    vertical/horizontal is within ``[min_angle, max_angle]`` degrees gets an ROI centred on its
    midpoint, ``roi_length`` of the side long (the middle part, away from the corners; longer,
    up to 80 % of the side, where the edge would not cross one whole pixel along it, else the
    side is skipped; shorter where the edge would drift across more than half the ROI's width)
    and ``roi_width`` pixels across (default: 60 % of the side, at most 64; a rectangle, its
    bounding box 1.25 times longer one way, has its sides' lengths from its area and aspect);
    ROIs that leave the image, or in which a row (column) crosses the threshold more than once
    (another square inside; each pixel is first the median of itself and its neighbours on
    the two adjacent lines, so that a speck or a noise spike one line tall is no edge), are
    dropped. A component seen at several levels (same bounding box
    within 2 px) is fitted once, at the level nearest the middle of its grey and its surround's;
    of the ROIs that several components give on one edge, the one whose level is nearest the
    middle of the edge's two greys is kept. Light squares on a darker surround are searched the
    same way in the negated image (the light components of each level), and their ROIs join the
    dark squares' (``side`` names the light square's side); an edge found from both sides is
    kept once. A kept ROI must hold one edge, which the e-SFR measures: each line across it
    crosses the levels 1/4 and 3/4 of the way between the ROI's 5th and 95th percentiles once
    (ISO 12233 wants uniform areas on both sides of the edge), and :func:`slanted_edge_sfr`
    accepts it and finds the edge within 1 deg of the threshold fit. If no square gives an edge
    and the whole image passes that test with an angle in range, the image is taken as an edge
    crop (the input of ``sfrmat``) and returned as one ROI (its ``side`` names the side of the
    dark area the edge bounds). If that fails too, the shapes that touch the image's border
    (an edge across the whole field: an X-ray detector's edge phantom, IEC 62220-1-1, or a
    knife edge; the squares' search skips them) give the straight runs of their outlines, as
    a wedge's below, one ROI per edge line (the longest).

    A dark component that fills less than 60 % of its bounding box (a wedge, such as the
    blades of the ISO 12233:2017/2023 chart's pinwheels) is no square: its outline seen from
    each side is cut where it jumps (another part of the shape takes over) into straight
    runs, and each run long enough for an ROI of ``min_size`` pixels along it, less 20 % at
    each end, is taken as a square's side of that length (the same fit, tests and ROI).

    Returns
    -------
    list of SlantedEdgeROI
        Sorted by row then column of their centres.

    Examples
    --------
    >>> from imageform.analysis import render_slanted_edge
    >>> img = np.full((120, 120), 0.8)
    >>> img[30:90, 30:90] = 0.2
    >>> find_slanted_edges(img)  # an upright square: no slanted edge
    []
    """
    img = _as_image(image)
    lo_a = as_real(min_angle, "min_angle", nonnegative=True, maximum=40.0)
    hi_a = as_real(max_angle, "max_angle", minimum=lo_a, maximum=40.0)
    msz = as_int(min_size, "min_size", minimum=8)
    frac = as_real(roi_length, "roi_length", positive=True, maximum=0.9)
    rw = None if roi_width is None else as_int(roi_width, "roi_width", minimum=8)
    g = _luminance(img, _weights(weights))
    p2, p98 = np.percentile(g, [2.0, 98.0])
    if p98 - p2 <= 0:
        return []
    # the midpoint first (a two-tone chart), then levels across the whole range: a square on a
    # grey surround of its own, among other patches, separates only between its two greys
    levels = [0.5 * (p2 + p98)]
    levels += list(p2 + (p98 - p2) * (np.arange(1, _N_LEVELS) / _N_LEVELS))
    best: list[tuple[float, SlantedEdgeROI]] = []
    # dark squares on a light surround, then light squares on a dark one: the same search in
    # the negated image (-g < -t where g > t); the tests below do not depend on the polarity
    per_level = [_components_at(g, t, msz) for t in levels]  # (dark, light) at each level
    for k, gg, lv in ((0, g, levels), (1, -g, [-t for t in levels])):
        # each component once, at the level nearest the middle of its two greys (a two-tone
        # square is seen at every level, a square on a grey surround at several)
        seen = [(t, *c) for t, cs in zip(lv, per_level, strict=True) for c in cs[k]]
        comps = _pick_levels(gg, seen)
        for t, r0, c0, m in comps:
            hh, ww = m.shape
            if m.sum() < 0.6 * hh * ww:  # not a square: the straight runs of its outline
                rois = _outline_rois(gg, m, t, (r0, c0), msz, hi_a, frac, rw)
            else:
                # a rectangle's sides (a box 1.25 times longer one way than the other): sqrt(area)
                # scaled by the box's aspect; a square's: sqrt(area)
                side = math.sqrt(float(m.sum()))
                aspect = hh / ww if max(hh, ww) >= _RECTANGLE * min(hh, ww) else 1.0
                tall = side * math.sqrt(aspect), side / math.sqrt(aspect)
                found_sides = [
                    _side_roi(gg, o, t, (r0, c0), name, tall if name in _VERTICAL else tall[::-1],
                              frac, rw)
                    for name, o in _outlines(m).items()
                ]  # fmt: skip
                rois = [r for r in found_sides if r is not None]
            for roi in rois:
                if lo_a <= abs(roi.angle) <= hi_a and _clean(gg, t, roi):
                    _keep(best, roi, _level_offset(gg, roi, t))
    found = [roi for _score, roi in best if _measurable(g, roi, img)]
    if not found:  # an edge crop (sfrmat's input): the whole image as one ROI
        whole = _whole_image_edge(g, img)
        if whole is not None and lo_a <= abs(whole.angle) <= hi_a:
            found = [whole]
    if not found:  # an edge across the field (an X-ray edge phantom): shapes on the border
        # the middle and the quartiles: an edge across the field is one contrast, with no
        # grey surround of its own to separate (what the 16 levels are for)
        found = _border_edges(g, img, [levels[0], levels[4], levels[12]], msz, lo_a, hi_a, frac, rw)
    found.sort(key=lambda r: (round(r.center[1]), r.center[0]))
    return found


def _border_edges(
    g: np.ndarray,
    img: np.ndarray,
    levels: Sequence[float],
    msz: int,
    lo_a: float,
    hi_a: float,
    frac: float,
    rw: int | None,
) -> list[SlantedEdgeROI]:
    """ROIs on the straight runs of the outlines of shapes that touch the image's border.

    An edge across the whole field (an X-ray detector's edge phantom, IEC 62220-1-1; a knife
    edge over half the frame) bounds shapes that touch the border, which the search for
    squares skips. Their outlines are cut into straight runs as a wedge's are
    (:func:`_outline_rois`), with the same tests; of the ROIs on one line (noise and the
    levels split an edge's outline into several runs) the longest is kept.
    """
    cands: list[tuple[int, float, SlantedEdgeROI]] = []
    per_level = [_components_at(g, t, msz, border=True) for t in levels]
    for k, gg, lv in ((0, g, levels), (1, -g, [-t for t in levels])):
        seen = [(t, *c) for t, cs in zip(lv, per_level, strict=True) for c in cs[k]]
        for t, r0, c0, m in _pick_levels(gg, seen):
            for roi in _outline_rois(gg, m, t, (r0, c0), msz, hi_a, frac, rw):
                if lo_a <= abs(roi.angle) <= hi_a and _clean(gg, t, roi):
                    along = roi.height if roi.orientation == "vertical" else roi.width
                    cands.append((along, _level_offset(gg, roi, t), roi))
    out: list[SlantedEdgeROI] = []
    for _along, _score, roi in sorted(cands, key=lambda c: (-c[0], c[1])):
        if not any(_on_line(o, roi) for o in out) and _measurable(g, roi, img):
            out.append(roi)
    return out


def _on_line(a: SlantedEdgeROI, b: SlantedEdgeROI) -> bool:
    """Whether ``b`` lies on ``a``'s edge line.

    One orientation, angles within 2 deg, and ``b``'s centre off ``a``'s line by less than a
    quarter of the narrower ROI's width (the levels place a blurred edge's crossings a few
    pixels apart; a second edge that near could not be measured in either ROI).
    """
    if a.orientation != b.orientation or abs(a.angle - b.angle) > 2.0:
        return False
    i = 0 if a.orientation == "vertical" else 1  # across the edge: u for a vertical one
    wa, wb = (a.width, b.width) if i == 0 else (a.height, b.height)
    slope = math.tan(math.radians(a.angle))
    across = a.center[i] + slope * (b.center[1 - i] - a.center[1 - i])
    off = abs(b.center[i] - across) * math.cos(math.radians(a.angle))
    return off <= max(3.0, 0.25 * min(wa, wb))


def _outline(m: np.ndarray, name: str, kernel: bool | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Return the lines of mask ``m`` with a dark pixel and the first one seen from ``name``.

    The lines are rows for ``left``/``right``, columns for ``top``/``bottom``; the numba
    kernel :func:`imageform._kernels.components.outline` where numba imports
    (``kernel=None``), else ``argmax`` over the lines (its twin).
    """
    if kernel is None:
        from imageform._backend import have_numba

        kernel = have_numba()
    if kernel:
        from imageform._kernels.components import outline

        first = outline(m)[("left", "right", "top", "bottom").index(name)]
        lines = np.nonzero(first >= 0)[0]
        return lines, first[lines]
    mm = m if name in ("left", "right") else m.T
    lines = np.nonzero(mm.any(axis=1))[0]
    sub = mm[lines]
    if name in ("left", "top"):
        return lines, np.argmax(sub, axis=1)
    return lines, sub.shape[1] - 1 - np.argmax(sub[:, ::-1], axis=1)


def _outlines(m: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """:func:`_outline` of ``m`` from each of the four sides (one pass of the kernel)."""
    from imageform._backend import have_numba

    if not have_numba():
        return {name: _outline(m, name, False) for name in ("left", "right", "top", "bottom")}
    from imageform._kernels.components import outline

    out = {}
    for name, first in zip(("left", "right", "top", "bottom"), outline(m), strict=True):
        lines = np.nonzero(first >= 0)[0]
        out[name] = (lines, first[lines])
    return out


def _side_roi(
    g: np.ndarray,
    m: np.ndarray | tuple[np.ndarray, np.ndarray],
    t: float,
    origin: tuple[int, int],
    name: str,
    side: float | tuple[float, float],
    frac: float,
    rw: int | None,
) -> SlantedEdgeROI | None:
    """Return the ROI on side ``name`` of a component (its mask ``m`` or its :func:`_outline`).

    ``side`` is the side's length, or its length and the shape's extent across it (a
    rectangle's other side): the ROI is ``frac`` of the first long and 60 % of the second
    wide (at most 64 px), and no longer than lets the edge drift across half its width.
    """
    vertical = name in ("left", "right")
    gg = g if vertical else g.T
    o_line, o_across = origin if vertical else origin[::-1]
    lines, first_all = _outline(m, name) if isinstance(m, np.ndarray) else m
    n = lines.size
    cut = slice(int(0.25 * n), int(np.ceil(0.75 * n)))
    sel, first = lines[cut], first_all[cut]
    if sel.size < 4:
        return None
    step = 1 if name in ("left", "top") else -1
    pos = _subpixel_side(gg, t, sel + o_line, first + o_across, step)
    yl = (sel + o_line).astype(np.float64)
    # a straight (or gently bent, by distortion) edge: a corner, a notch or another shape
    # merged with the square leaves crossings off any smooth curve
    if sel.size >= 6:
        bend = pos - np.polyval(np.polyfit(yl, pos, 2), yl)
        if float(np.sqrt(np.mean(bend**2))) > _MAX_BEND_RMS:
            return None
    b, a = _polyfit(yl, pos, 1)
    angle = math.degrees(math.atan(b))
    mid_line = 0.5 * (lines[0] + lines[-1]) + o_line
    mid_across = a + b * mid_line
    along, across = (side, side) if isinstance(side, float | int) else side
    width = rw if rw is not None else max(16, min(64, round(0.6 * across)))
    # a long side at a steep angle: the edge would run from one side of the ROI to the other
    # (an X-ray edge phantom across the field); keep it within the middle half of the width
    length = max(8, min(round(frac * along), math.floor(0.5 * width / max(abs(b), 1e-9))))
    # the e-SFR needs the edge to cross at least one pixel along the ROI (a phase cycle)
    need = math.ceil(1.0 / max(abs(b), 1e-9)) + 2
    if need > length:
        if need > 0.8 * along:
            return None
        length = need
    l0 = round(mid_line - (length - 1) / 2.0)
    a0 = round(mid_across - (width - 1) / 2.0)
    H, W = g.shape if vertical else g.shape[::-1]
    if l0 < 0 or a0 < 0 or l0 + length > H or a0 + width > W:
        return None
    if vertical:
        return SlantedEdgeROI(
            a0, l0, width, length, angle, "vertical", name, (mid_across, mid_line)
        )
    return SlantedEdgeROI(l0, a0, length, width, angle, "horizontal", name, (mid_line, mid_across))


def _clean(g: np.ndarray, t: float, roi: SlantedEdgeROI) -> bool:
    """One crossing of the level ``t`` per line across the edge inside the ROI.

    Each pixel is first replaced by the median of itself and its neighbours on the two
    adjacent lines (along the edge): a speck of dust, a hot pixel or a noise spike one line
    tall is no second edge, where another edge, a glyph or a line along the edge (several
    lines long) still crosses the level.
    """
    a = g[roi.y : roi.y + roi.height, roi.x : roi.x + roi.width]
    if roi.orientation == "horizontal":
        a = a.T
    if a.shape[0] >= 3:  # the median of three: max(min(p, q), min(max(p, q), r))
        p, q, r = a[:-2], a[1:-1], a[2:]
        mid = np.maximum(np.minimum(p, q), np.minimum(np.maximum(p, q), r))
        a = np.concatenate((a[:1], mid, a[-1:]))
    d = a < t
    changes = np.count_nonzero(np.diff(d.astype(np.int8), axis=1), axis=1)
    return bool((changes == 1).all())


def _component_greys(g: np.ndarray, m: np.ndarray, r0: int, c0: int) -> tuple[float, float]:
    """Return a component's grey and its surround's (NaN, NaN where they cannot be told).

    The greys are the medians of ``g`` inside the component's mask ``m`` (top-left pixel
    ``r0, c0``) and over the rest of its bounding box grown by a tenth of its size (at
    least 2 pixels; every ``step``-th pixel of a large box).
    """
    H, W = g.shape
    hh, ww = m.shape
    pad = max(2, round(0.1 * max(hh, ww)))
    a0, a1 = max(0, r0 - pad), min(H, r0 + hh + pad)
    b0, b1 = max(0, c0 - pad), min(W, c0 + ww + pad)
    box = g[a0:a1, b0:b1]
    inside = np.zeros(box.shape, dtype=bool)
    inside[r0 - a0 : r0 - a0 + hh, c0 - b0 : c0 - b0 + ww] = m
    step = max(1, math.isqrt(box.size // 40000))  # medians of a large shape: a subsample
    box, inside = box[::step, ::step], inside[::step, ::step]
    if inside.all() or not inside.any():
        return math.nan, math.nan
    return float(np.median(box[inside])), float(np.median(box[~inside]))


def _offset(t: float, greys: tuple[float, float]) -> float:
    """How far ``t`` is from the middle of two greys ``(lo, hi)``, in units of their difference.

    0: halfway, 0.5: at either grey; infinite when ``hi`` is not above ``lo`` (or NaN).
    """
    lo, hi = greys
    if not hi > lo:
        return math.inf
    return abs(t - 0.5 * (lo + hi)) / (hi - lo)


def _level_offset(g: np.ndarray, roi: SlantedEdgeROI, t: float) -> float:
    """How far ``t`` is from the middle of the ROI's two greys, in units of their difference.

    The greys are the ROI's 5th and 95th percentiles; 0 is a threshold halfway between them
    (where the crossings sit on the edge itself), 0.5 one at either grey.
    """
    a = g[roi.y : roi.y + roi.height, roi.x : roi.x + roi.width]
    lo, hi = np.percentile(a, [5.0, 95.0])
    if hi <= lo:
        return math.inf
    return float(abs(t - 0.5 * (lo + hi)) / (hi - lo))


def _keep(best: list[tuple[float, SlantedEdgeROI]], roi: SlantedEdgeROI, score: float) -> None:
    """Add ``roi`` to ``best`` unless an ROI on the same edge has a better (lower) score.

    Two ROIs are on one edge when they have one orientation and their centres are closer
    than a quarter of the shorter ROI's length along the edge.
    """
    along = roi.height if roi.orientation == "vertical" else roi.width
    for i, (sc, other) in enumerate(best):
        o_along = other.height if other.orientation == "vertical" else other.width
        if other.orientation != roi.orientation:
            continue
        du = roi.center[0] - other.center[0]
        dv = roi.center[1] - other.center[1]
        if math.hypot(du, dv) < 0.25 * min(along, o_along):
            if score < sc:
                best[i] = (score, roi)
            return
    best.append((score, roi))


def _measurable(g: np.ndarray, roi: SlantedEdgeROI, img: np.ndarray | None = None) -> bool:
    """Whether the ROI holds one edge the e-SFR measures, at the threshold fit's angle.

    ``g`` is the luminance, ``img`` the image (RGB: each channel is fitted and projected on
    its own, as :func:`slanted_edge_sfr` does, so a channel without the edge, or one whose
    edge crosses too few phases in the rows the luminance keeps, fails the ROI).

    One edge: every line across it crosses the levels a quarter and three quarters of the
    way between the ROI's two greys (its 5th and 95th percentiles) once, so that no other
    edge, or part of one, lies in the ROI (ISO 12233 wants uniform areas on both sides).

    The e-SFR locates the edge by the centroids of the rows' derivatives, not by a threshold;
    on a straight edge both agree within a fraction of a degree. A ROI the e-SFR refuses
    (too few phases, too narrow) or where the two angles differ by more than 1 deg (a glyph,
    a rounded shape) is not a slanted edge.
    """
    a = roi.crop(g)
    lo, hi = np.percentile(a, [5.0, 95.0])
    for level in (lo + 0.25 * (hi - lo), lo + 0.75 * (hi - lo)):
        if not _clean(g, level, roi):
            return False
    try:  # the e-SFR's steps up to the LSF (its spectrum is not needed here)
        planes = a if img is None else roi.crop(img)
        orientation, _r, _c, fits, _e, _l = _edge_stages(planes, a, 4, 1, "central")
    except (DegenerateConfigurationError, InvalidInputError):
        return False
    angle = math.degrees(math.atan(float(fits[-1][0])))
    return orientation == roi.orientation and abs(angle - roi.angle) <= _MAX_ANGLE_GAP


def _whole_image_edge(g: np.ndarray, img: np.ndarray | None = None) -> SlantedEdgeROI | None:
    """Return the whole image as one ROI if it is a crop around one slanted edge, else None.

    The e-SFR's own fit gives the orientation and angle; :func:`_measurable`'s test then
    checks that every line crosses between the two greys once. ``side`` names the side of
    the dark area the edge bounds (``"right"``: dark on the left of a vertical edge).
    """
    H, W = g.shape
    if min(H, W) < 8:
        return None
    try:
        r = slanted_edge_sfr(g)
    except DegenerateConfigurationError:
        return None
    vertical = r.orientation == "vertical"
    p = r.edge[-1]
    mid = (H - 1) / 2.0 if vertical else (W - 1) / 2.0
    across = float(np.polyval(p, mid))
    if vertical:
        dark_first = g[:, : W // 2].mean() < g[:, W // 2 :].mean()
        side = "right" if dark_first else "left"
        center = (across, mid)
    else:
        dark_first = g[: H // 2].mean() < g[H // 2 :].mean()
        side = "bottom" if dark_first else "top"
        center = (mid, across)
    roi = SlantedEdgeROI(0, 0, W, H, r.angle, r.orientation, side, center)
    return roi if _measurable(g, roi, img) else None


def _outline_rois(
    g: np.ndarray,
    m: np.ndarray,
    t: float,
    origin: tuple[int, int],
    min_len: int,
    max_angle: float,
    frac: float,
    rw: int | None,
) -> list[SlantedEdgeROI]:
    """ROIs on the straight, near-axis runs of a dark shape's outline seen from each side.

    For a shape that is not a square (the blades of the ISO 12233:2017/2023 e-SFR chart's
    pinwheels, a wedge, a bar): the first dark pixel of each line seen from the left (right,
    top, bottom) traces the outline; it is cut where it jumps by more than
    ``1.5 + tan(max_angle)`` pixels between lines (another part of the shape takes over).
    Each run long enough for an ROI of ``min_len`` lines (``frac`` of the run; shorter runs
    are mostly glyphs' strokes) is trimmed by 20 % at each end (the corners) and treated as
    a square's side of that length (:func:`_side_roi`: the sub-pixel crossings, the
    straightness test, the ROI).
    """
    out: list[SlantedEdgeROI] = []
    jump = 1.5 + math.tan(math.radians(max_angle))
    if max(m.shape) * frac < min_len:  # no run can be long enough
        return out
    for name, (lines, first) in _outlines(m).items():
        if lines.size < min_len:
            continue
        cut = np.nonzero((np.abs(np.diff(first)) > jump) | (np.diff(lines) > 1))[0] + 1
        for run in np.split(np.arange(lines.size), cut):
            if run.size * frac < min_len:  # an ROI shorter than min_len: a glyph's stroke
                continue
            k = int(0.2 * run.size)
            part = run[k : run.size - k]
            roi = _side_roi(
                g, (lines[part], first[part]), t, origin, name, float(run.size), frac, rw
            )
            if roi is not None:
                out.append(roi)
    return out
