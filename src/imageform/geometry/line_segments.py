"""Straight line-segment detection: LSD-style gradient grouping with an a-contrario test.

``detect_line_segments`` runs the full LSD of :mod:`imageform.geometry.lsd` by default
(``method="lsd"``); the simplified detector described below stays as ``method="simple"``.

Algorithm (after von Gioi, Jakubowicz, Morel & Randall, "LSD: a Line Segment Detector",
IPOL 2012):

1. Grey image, Gaussian smoothing (σ = 0.6 px), the 2×2 gradient of LSD; each pixel's
   *level-line angle* ``atan2(g_x, -g_y)`` is the direction of the edge through it. Pixels
   with ``|∇I| < ρ = q / sin τ`` (q = 2 grey levels of 255) are NOTDEF.
2. Pixels are visited by decreasing gradient magnitude; each unused one seeds a *line-support
   region*: 8-connected neighbours whose level-line angle is within τ (22.5°) of the
   region's mean angle join it.
3. Each region is approximated by a rectangle: the magnitude-weighted centroid, the principal
   axis of inertia, and the extents of the region's pixels.
4. Validation: among the n pixels of the rectangle, k are aligned (within τ) with it. Under
   the a-contrario noise model each is aligned with probability p = τ/π, so the number of
   false alarms is ``NFA = (W H)^{5/2} · P[Binomial(n, p) ≥ k]``; the segment is kept when
   ``NFA ≤ ε`` (ε = 1: less than one false detection per image on noise).

Differences from LSD: no 0.8 down-scaling and no rectangle refinement step (regions whose
aligned-point density is below 0.7 are rejected instead of refined); enough for vanishing
point work on photographs, and measured on synthetic renders in the tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import array_api_compat
import numpy as np

from imageform._backend import to_numpy
from imageform._typing import ArrayLike, FloatArray
from imageform._validate import (
    MAX_MAGNITUDE,
    as_float_bounded,
    as_real,
    check_min_side,
    check_positive,
    describe,
    shape_text,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry._plumb_edges import grey as _grey

__all__ = ["LineSegments", "detect_line_segments"]

_Q = 2.0 / 255.0  # LSD's gradient quantisation bound, 2 grey levels of 255


def _host(v: object) -> object:
    """Convert a tensor to a NumPy array (segments live on the host); return anything else as is."""
    return to_numpy(v) if array_api_compat.is_torch_array(v) else v


@dataclass(frozen=True)
class LineSegments:
    """Detected segments: end points ``(N, 2, 2)`` as ``(u, v)`` pixels, widths and log10 NFA.

    ``lengths`` and ``lines`` (homogeneous, ``a² + b² = 1``) are derived.
    """

    endpoints: FloatArray
    widths: FloatArray
    log10_nfa: FloatArray

    def __post_init__(self) -> None:
        """Check the arrays (one width and NFA per segment) and keep float64 NumPy copies."""
        e = np.asarray(
            to_numpy(as_float_bounded(_host(self.endpoints), "endpoints", xp=np, dtype=np.float64))
        )
        if e.ndim != 3 or e.shape[1:] != (2, 2):
            raise InvalidInputError(f"expected endpoints of shape (N, 2, 2), got {shape_text(e)}")
        n = e.shape[0]
        out = {"endpoints": e}
        for name in ("widths", "log10_nfa"):
            v = np.asarray(
                to_numpy(
                    as_float_bounded(
                        _host(getattr(self, name)), name, xp=np, dtype=np.float64, finite=False
                    )
                )
            )
            if v.shape != (n,):
                raise InvalidInputError(
                    f"expected {name} of shape ({n},), one per segment of endpoints, got "
                    f"{shape_text(v)}"
                )
            out[name] = v
        lg = out["log10_nfa"]
        if np.isnan(lg).any() or (lg == np.inf).any():  # -inf: an NFA below float range
            raise InvalidInputError("expected log10_nfa without NaN or +inf")
        if not np.all(np.isfinite(out["widths"])) or np.any(out["widths"] < 0):
            raise InvalidInputError("expected widths finite and >= 0 (pixels)")
        for k, v in out.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        """Return the number of segments."""
        return int(self.endpoints.shape[0])

    @property
    def lengths(self) -> FloatArray:
        """Segment lengths ``(N,)`` in pixels."""
        d = self.endpoints[:, 1] - self.endpoints[:, 0]
        return np.hypot(d[:, 0], d[:, 1])

    @property
    def midpoints(self) -> FloatArray:
        """Segment midpoints ``(N, 2)``."""
        return 0.5 * (self.endpoints[:, 0] + self.endpoints[:, 1])

    @property
    def lines(self) -> FloatArray:
        """Homogeneous lines ``(N, 3)`` through the segments, normalised so ``a² + b² = 1``."""
        from imageform.geometry.vanishing import lines_from_segments

        return np.asarray(lines_from_segments(self.endpoints))


def _gradient(img: FloatArray) -> tuple[FloatArray, FloatArray]:
    """LSD's 2×2 gradient at the pixel's lower-right corner; level-line angle and magnitude."""
    a = img[:-1, :-1]
    b = img[:-1, 1:]
    c = img[1:, :-1]
    d = img[1:, 1:]
    gx = 0.5 * (b + d - a - c)
    gy = 0.5 * (c + d - a - b)
    mag = np.hypot(gx, gy)
    ang = np.arctan2(gx, -gy)
    out_a = np.full(img.shape, np.nan)
    out_m = np.zeros(img.shape)
    out_a[:-1, :-1] = ang
    out_m[:-1, :-1] = mag
    return out_a, out_m


def detect_line_segments(
    image: ArrayLike,
    *,
    method: Literal["lsd", "simple"] = "lsd",
    sigma: float = 0.6,
    angle_tolerance: float = math.radians(22.5),
    min_length: float | None = None,
    log10_eps: float = 0.0,
    min_density: float = 0.7,
) -> LineSegments:
    """Detect straight line segments in an image.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Grey or RGB; uint8/uint16 or floats in [0, 1].
    method : {"lsd", "simple"}
        ``"lsd"`` (default): the full LSD of von Gioi et al. (IPOL 2012), see
        :mod:`imageform.geometry.lsd` (0.8 Gaussian sub-sampling, pseudo-ordering, region
        growing, refinement, rectangle improvement, NFA). ``"simple"``: the earlier detector
        of this module's docstring (no sub-sampling, no refinement, no improvement).
    sigma : float
        ``"lsd"``: LSD's sigma_scale Σ (σ = Σ / 0.8 before the 0.8 sub-sampling; 0 skips
        both, as LSD's scale = 1). ``"simple"``: the Gaussian σ in pixels (0 disables it).
    angle_tolerance : float
        τ in radians: the region-growing and alignment tolerance.
    min_length : float, optional
        Shorter segments are dropped (pixels); default 0 for ``"lsd"``, 10 for ``"simple"``.
    log10_eps : float
        Keep segments with ``log10 NFA <= log10_eps`` (0: ε = 1 false alarm per image).
    min_density : float
        Minimum fraction of aligned pixels in a rectangle (LSD's 0.7).

    Returns
    -------
    LineSegments
        Sorted by decreasing length; end points are pixel-centre coordinates ``(u, v)``.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((64, 64)); img[:, 32:] = 1.0          # one vertical step edge
    >>> seg = detect_line_segments(img)
    >>> len(seg), bool(abs(seg.endpoints[0, 0, 0] - 31.5) < 0.6)
    (1, True)
    """
    from scipy import ndimage, stats  # imported on use: scipy.stats alone costs 0.2 s

    from imageform._kernels.lsd import grow_regions, rect_alignment_counts, region_rectangles

    if method not in ("lsd", "simple"):
        raise UnknownOptionError(
            f"unknown method {describe(method)} for detect_line_segments; valid: 'lsd', 'simple'"
        )
    if min_length is None:
        min_length = 0.0 if method == "lsd" else 10.0
    angle_tolerance = check_positive(angle_tolerance, "angle_tolerance")
    if not angle_tolerance < math.pi / 2:
        raise InvalidInputError(f"expected angle_tolerance < pi/2, got {angle_tolerance:g}")
    # a Gaussian wider than 1000 px blurs any image to a constant (its kernel alone
    # would be 8 sigma wide)
    sigma = as_real(sigma, "sigma", minimum=0.0, maximum=1000.0)
    min_length = as_real(min_length, "min_length", minimum=0.0, maximum=MAX_MAGNITUDE)
    log10_eps = as_real(log10_eps, "log10_eps", minimum=-1e6, maximum=1e6)
    min_density = as_real(min_density, "min_density", minimum=0.0, maximum=1.0)
    if method == "lsd" and min_density <= 0.0:
        raise InvalidInputError(f"expected min_density in (0, 1] for LSD, got {min_density:g}")
    if method == "lsd":
        return _detect_lsd(image, sigma, angle_tolerance, min_length, log10_eps, min_density)
    img = _grey(image)
    check_min_side(img.shape, 3)
    if sigma > 0:
        img = ndimage.gaussian_filter(img, sigma, mode="nearest")
    ang, mag = _gradient(img)
    rho = _Q / math.sin(angle_tolerance)
    ang[mag <= rho] = np.nan
    valid = ~np.isnan(ang)
    order = np.argsort(-mag, axis=None, kind="stable").astype(np.int64)
    order = order[valid.ravel()[order]]
    p = angle_tolerance / math.pi
    H, W = img.shape
    log_ntests = 2.5 * math.log10(W * H)
    # a region can only pass if even all its pixels aligned give NFA <= eps
    min_size = max(2, math.ceil((log_ntests - log10_eps) / -math.log10(p)))
    labels, n_regions = grow_regions(ang, order, angle_tolerance, min_size)
    if n_regions == 0:
        empty = np.zeros((0, 2, 2))
        return LineSegments(empty, np.zeros(0), np.zeros(0))
    rects = region_rectangles(labels, n_regions, mag)
    counts = rect_alignment_counts(rects, ang, angle_tolerance)
    n, k = counts[:, 0], counts[:, 1]
    log10_nfa = log_ntests + stats.binom.logsf(k - 1, n, p) / math.log(10.0)
    density = k / np.maximum(n, 1)
    theta = rects[:, 2]
    direction = np.stack((np.cos(theta), np.sin(theta)), axis=-1)
    centre = rects[:, :2]
    p0 = centre + rects[:, 3:4] * direction
    p1 = centre + rects[:, 4:5] * direction
    # the 2x2 gradient sits at the lower-right pixel corner: shift by half a pixel
    ends = np.stack((p0, p1), axis=1) + 0.5
    widths = rects[:, 6] - rects[:, 5] + 1.0
    lengths = np.hypot(*(ends[:, 1] - ends[:, 0]).T)
    keep = (log10_nfa <= log10_eps) & (density >= min_density) & (lengths >= min_length)
    order_out = np.argsort(-lengths[keep], kind="stable")
    return LineSegments(ends[keep][order_out], widths[keep][order_out], log10_nfa[keep][order_out])


def _detect_lsd(
    image: ArrayLike,
    sigma: float,
    angle_tolerance: float,
    min_length: float | None,
    log10_eps: float,
    min_density: float,
) -> LineSegments:
    from imageform.geometry.lsd import lsd_segments

    check_positive(sigma, "sigma", allow_zero=True)
    scale = 0.8 if sigma > 0 else 1.0
    ends, widths, log10_nfa = lsd_segments(
        image,
        scale=scale,
        sigma_scale=sigma if sigma > 0 else 0.6,
        angle_tolerance=angle_tolerance,
        log10_eps=log10_eps,
        density_th=min_density,
        min_length=0.0 if min_length is None else min_length,
    )
    order = np.argsort(-np.hypot(*(ends[:, 1] - ends[:, 0]).T), kind="stable")
    return LineSegments(ends[order], widths[order], log10_nfa[order])
