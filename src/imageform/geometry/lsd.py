r"""LSD, the a-contrario line segment detector (von Gioi, Jakubowicz, Morel & Randall).

The full algorithm of "LSD: a Line Segment Detector", Image Processing On Line 2 (2012)
35-55 (and IEEE TPAMI 32(4), 2010), as its reference code ``lsd.c`` 1.6 runs it; the numba
kernels are in :mod:`imageform._kernels.lsd_full`.

1. **Gaussian sub-sampling** to ``scale = 0.8`` of the size, with a Gaussian of
   :math:`\sigma = \Sigma / s` (``sigma_scale`` :math:`\Sigma = 0.6`), cut where it falls to
   :math:`10^{-3}` of its peak, re-centred on each output sample, mirror boundary.
2. **Gradient** by the 2x2 masks at each pixel's lower-right corner,
   :math:`g_x = (B + D - A - C)/2`, :math:`g_y = (C + D - A - B)/2`, level-line angle
   :math:`\operatorname{atan2}(g_x, -g_y)`; pixels with
   :math:`|\nabla I| \le \rho = q / \sin\tau` (``q = 2`` grey levels of 255) are undefined.
3. **Pseudo-ordering**: pixels binned by gradient norm into 1024 bins, visited from the
   largest bin down.
4. **Region growing**: each unused pixel seeds a line-support region, the 8-connected pixels
   whose level-line angle is within :math:`\tau = 22.5°` of the region's running mean angle.
5. **Rectangle approximation**: the gradient-weighted centre of mass, the principal axis of
   inertia, and the extents along and across it (width at least 1).
6. **Refinement**: when fewer than ``density_th = 0.7`` of the rectangle's area are region
   pixels, the region is regrown from its seed with a tolerance of twice the angles' standard
   deviation near the seed, then shrunk (radius times 0.75) until it is dense enough.
7. **Validation**: a rectangle of ``n`` pixels with ``k`` aligned within :math:`\tau` has
   :math:`\mathrm{NFA} = N_T \sum_{i \ge k} \binom{n}{i} p^i (1-p)^{n-i}`, ``p = τ/π``,
   with :math:`N_T = 11\,(NM)^{5/2}` tests on an N x M (sub-sampled) image: :math:`(NM)^{5/2}`
   rectangles times the 11 precisions that the improvement step may try (von Gioi et al.
   2012, section 2.7). A segment is kept when :math:`\mathrm{NFA} \le \varepsilon`,
   ``log10 ε = 0``: on noise, less than one false detection per image on average.
8. **Rectangle improvement** before that test: finer precisions (p / 2, five times), thinner
   rectangles, each side moved in, finer precisions again; the best NFA is kept.

End points are returned in the input image's pixel-centre coordinates (the 2x2 gradient's
half-pixel offset added back, then divided by the scale), as LSD and OpenCV return them.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._typing import ArrayLike, FloatArray
from imageform._validate import as_bool, as_int, as_real, check_min_side, check_positive
from imageform.errors import InvalidInputError
from imageform.geometry._plumb_edges import grey, grey_levels

__all__ = ["lsd_segments"]


def _grey255(image: ArrayLike) -> FloatArray:
    """Grey float64 in [0, 255]: uint8 grey is used as is (exact, as OpenCV reads it)."""
    arr = np.asarray(image)
    if arr.dtype == np.uint8 and arr.ndim == 2:
        return arr.astype(np.float64)
    if arr.dtype == np.uint8 and arr.ndim == 3 and arr.shape[-1] == 1:
        return arr[..., 0].astype(np.float64)
    return grey(arr) * 255.0


#: :func:`_stretch_low_contrast`: an image whose grey levels (0-255, as LSD reads them) between
#: these percentiles span less than ``_STRETCH_RANGE`` levels is stretched to the full range.
_STRETCH_PERCENTILES = (1.0, 99.0)
_STRETCH_RANGE = 64.0


def _stretch_low_contrast(image: ArrayLike) -> np.ndarray:
    """Return a low-contrast image stretched to the full grey range; others as they are.

    LSD leaves a pixel out when its gradient is at most ``ρ = q / sin τ`` (``q = 2`` grey
    levels of 255, 5.2 levels per pixel): the edges of a hazy, foggy, dim or underexposed
    photograph fall below it, and with them the segments. Where the grey image (as
    :func:`lsd_segments` reads it, 0-255) spans less than ``_STRETCH_RANGE`` levels between
    its 1st and 99th percentiles ``lo`` and ``hi``, it is returned as grey floats in [0, 1],
    ``clip((g - lo) / (hi - lo), 0, 1)`` (a percentile stretch); otherwise (any photograph
    of normal contrast, or a flat image) ``image`` itself is returned, so that the segments
    found on it are bit-identical. The percentiles are those of every ``s``-th pixel of
    every ``s``-th row, ``s`` the smallest step leaving at most 2¹⁴ of them (the test costs
    well under 1 % of a vanishing-point search).
    """
    arr = np.asarray(image)
    if arr.ndim not in (2, 3) or arr.shape[0] < 1 or arr.shape[1] < 1:
        return arr
    step = max(1, math.ceil(math.sqrt(arr.shape[0] * arr.shape[1] / 16384.0)))
    # the grey levels LSD reads, without its checks: this only decides
    sample = grey_levels(arr[::step, ::step])
    if sample is None or not np.isfinite(sample).all():
        return arr  # not an image the stretch is for (LSD's own checks say what it is)
    lo, hi = (float(x) for x in np.percentile(sample, _STRETCH_PERCENTILES))
    if not 0.0 < hi - lo < _STRETCH_RANGE:
        return arr
    return np.clip((_grey255(arr) - lo) / (hi - lo), 0.0, 1.0)


def lsd_segments(
    image: ArrayLike,
    *,
    scale: float = 0.8,
    sigma_scale: float = 0.6,
    angle_tolerance: float = math.radians(22.5),
    quant: float = 2.0,
    log10_eps: float = 0.0,
    density_th: float = 0.7,
    n_bins: int = 1024,
    min_length: float = 0.0,
    validate: bool = True,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """LSD line segments (see the module docstring for the algorithm and its source).

    Parameters
    ----------
    image : array_like, shape (H, W), (H, W, 1) or (H, W, 3)
        uint8 grey is read as 0-255 codes as is; other inputs go through imageform's image
        conventions (uint8/uint16 full range, floats in [0, 1], RGB to Rec. 601 luma).
    scale : float
        Sub-sampling factor in (0, 1]; 1 skips the Gaussian filter too (as LSD does).
    sigma_scale : float
        Σ: the Gaussian's σ is ``sigma_scale / scale`` (in input pixels).
    angle_tolerance : float
        τ in radians, in (0, π/2).
    quant : float
        Gradient quantisation error bound in grey levels of 255 (ρ = quant / sin τ).
    log10_eps : float
        log10 of ε, the expected number of false detections per image (0: ε = 1).
    density_th : float
        Minimum density of region pixels in a rectangle, in (0, 1].
    n_bins : int
        Bins of the gradient pseudo-ordering.
    min_length : float
        Segments shorter than this (input pixels) are dropped afterwards (LSD: 0).
    validate : bool
        True: LSD's rectangle improvement and NFA test. False keeps every refined region
        without computing its NFA (NaN), as OpenCV's default ``LSD_REFINE_STD`` does: more
        and longer output, but no a-contrario guarantee (it detects segments in noise).

    Returns
    -------
    endpoints : ndarray, shape (N, 2, 2)
        ``(u, v)`` end points, pixel-centre coordinates, in detection order.
    widths : ndarray, shape (N,)
        Rectangle widths in input pixels.
    log10_nfa : ndarray, shape (N,)
        log10 of each segment's NFA (all <= ``log10_eps``; NaN without ``validate``).
    """
    from imageform._kernels.lsd_full import lsd

    scale = as_real(scale, "scale")
    if not 0.0 < scale <= 1.0:
        raise InvalidInputError(f"expected scale in (0, 1], got {scale!r}")
    # the Gaussian's kernel is about 7 sigma wide: bounded like find_checkerboard's sigma
    as_real(sigma_scale, "sigma_scale", positive=True, maximum=1000.0 * scale)
    check_positive(angle_tolerance, "angle_tolerance")
    if not angle_tolerance < math.pi / 2:
        raise InvalidInputError(
            f"expected angle_tolerance < pi/2 (radians), got {angle_tolerance!r}"
        )
    check_positive(quant, "quant", allow_zero=True)
    density_th = as_real(density_th, "density_th")
    if not 0.0 < density_th <= 1.0:
        raise InvalidInputError(f"expected density_th in (0, 1], got {density_th!r}")
    n_bins = as_int(n_bins, "n_bins", minimum=1, maximum=10**7)
    min_length = check_positive(min_length, "min_length", allow_zero=True)
    log10_eps = as_real(log10_eps, "log10_eps")
    img = _grey255(image)
    check_min_side(img.shape, 3)
    if not np.isfinite(img).all():
        raise InvalidInputError("expected a finite image, got NaN or infinite values")
    out = lsd(
        np.ascontiguousarray(img),
        float(scale),
        float(sigma_scale),
        float(quant),
        math.degrees(float(angle_tolerance)),
        -float(log10_eps),
        float(density_th),
        int(n_bins),
        as_bool(validate, "validate"),
    )
    ends = out[:, :4].reshape(-1, 2, 2)
    widths = out[:, 4]
    log10_nfa = -out[:, 6]
    if min_length > 0:
        keep = np.hypot(*(ends[:, 1] - ends[:, 0]).T) >= min_length
        ends, widths, log10_nfa = ends[keep], widths[keep], log10_nfa[keep]
    return ends, widths, log10_nfa
