r"""Lens distortion from the straight lines of one photograph (the plumb-line method).

A lens with radial distortion bends the images of straight scene lines; under the one-parameter
division model (Fitzgibbon 2001) a straight line becomes a circular arc. The correction that
makes the image's long edges straight again is the distortion, found without a calibration
board (Brown 1971's plumb-line idea; Alemán-Flores, Alvarez, Gomez & Santana-Cedrés, IPOL 2014;
Bukhari & Dailey, JMIV 2013).

Pipeline of :func:`estimate_distortion_from_lines`:

1. Edge points with sub-pixel position and gradient direction (Gaussian σ = 1 px, central
   differences, non-maximum suppression along the gradient, a parabola through the three
   magnitudes for the sub-pixel offset).
2. Edge contours, independent of the distortion (Bukhari & Dailey 2013 work on such
   contours): connected edge pixels of one polarity whose direction stays within a 45° sector,
   at least ``min_length`` long.
3. Consensus over the contours: each one's straightness error (RMS distance, in distorted
   pixels, to its own total least-squares line after correction) is computed on a grid of
   ``k``; ``k`` minimises the sum over contours of the truncated squared error
   ``min(e_i², τ²)`` weighted by the contour's points, so a curved object does not pull it.
4. Lines collinear after that correction (Alemán-Flores et al. 2014's distortion-aware
   Hough transform at that ``k``: sequential peaks, the points within ``tolerance`` pixels
   and 6° of each, cut into chains at gaps) join the contours (pieces of one line across
   gaps); the consensus is taken again within ±0.05 of ``k``, and the chains within τ there
   are the inliers.
5. Refinement: ``k`` (and with ``estimate_center=True`` the distortion centre) by
   bounded trust-region least squares (a soft-L1 loss of 1 px) on the distances of the
   inlier chains' points to their lines, measured in the distorted image to first order
   (Sampson: the corrected distance over ``|Jᵀ n|``, so squeezing the image does not pay);
   each line is the total least-squares fit at the current parameters (variable
   projection). Steps 4-5 are repeated twice more at the new ``k``.
6. Trust: ``k`` again on 200 bootstrap resamples of the chains (each chain's summed squared
   straightness error tabulated on a grid around ``k``); ``found`` needs their 90 % interval
   to exclude 0, be at most half as wide as ``|k|`` and stay inside the grid and ``k_range``.
   The chains, not their points, are the independent evidence: a scene edge that is not
   quite straight moves all its points together.

What it can measure: the bend of a line grows with its length squared; on 640 x 480
photographs whose straight edges are 100-250 px long, a 5-10 % corner displacement bends
them by a few tenths of a pixel, near the straightness of the edges themselves, and the
estimate is unreliable (``benchmarks/results/plumb-line-2026-11-29.md``) and ``found`` is
mostly False (``plumb-line-2026-11-29c.md``); long lines (a board, architecture across the
frame, a wide-angle lens's strong bend) give ``k`` to a few per cent.

Coordinates are normalised by the distance ``s`` from the image centre to a corner pixel's
centre, ``x = (u - c) / s``, so ``k`` has one meaning whatever the image size: a pixel at the
corner moves by ``1 / (1 + k) - 1`` of its radius (``k = -0.1``: 11 % outwards when
undistorted). The result's ``K`` carries ``s`` as its focal length: the focal length is not
known from straight lines, and ``undistort_image(img, res.K, res.distortion)`` keeps the scale at
the centre.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from imageform._typing import ArrayLike, FloatArray
from imageform._validate import as_bool, as_int, as_real, check_min_side, describe
from imageform.errors import (
    DegenerateConfigurationError,
    IllConditionedWarning,
    InvalidInputError,
)
from imageform.geometry._plumb_edges import contours as _contours
from imageform.geometry._plumb_edges import edge_points as _edge_points
from imageform.geometry._plumb_edges import grey as _grey
from imageform.geometry.distortion import DivisionModel

__all__ = ["PlumbLineResult", "estimate_distortion_from_lines"]

_THETA_BINS = 180  # 1 degree
_THETA_WINDOW = 3  # a point votes at its orientation +- 3 degrees
_RHO_BIN = 2.0  # pixels
_MAX_GAP = 6.0  # pixels: a chain is cut where its points are farther apart along the line
_ANGLE_TOL = math.radians(6.0)
#: a corner displacement below this many pixels, or a coefficient within 3 standard
#: deviations of 0, is reported as no distortion found
_NONE_PX = 1.0
#: the chain bootstrap: resamples of the chains, the grid of k searched (k +- _BOOT_SPAN), and
#: the widest 90 % interval, over |k1|, that is reported as found (chosen on the tune half of
#: benchmarks/check_plumb_reliability.py; benchmarks/results/plumb-line-2026-11-29c.md)
_BOOT = 200
_BOOT_STEP = 0.0025
_BOOT_SPAN = 0.2
_WIDTH = 0.5


@dataclass(frozen=True)
class PlumbLineResult:
    """Distortion estimated from straight lines (:func:`estimate_distortion_from_lines`).

    Attributes
    ----------
    distortion : DivisionModel
        The one-parameter division model on coordinates normalised by ``K``.
    K : ndarray, shape (3, 3)
        ``[[s, 0, cx], [0, s, cy], [0, 0, 1]]``: the distortion centre and the normalising
        scale ``s`` (the centre-to-corner distance, not a focal length).
    k1_std : float
        Standard deviation of ``k1`` from the refinement's Jacobian (points taken as
        independent: a lower bound).
    lines : tuple of ndarray, each (n_i, 2)
        The edge points ``(u, v)`` (distorted pixels) of each chain used.
    residual_px : float
        RMS distance of the lines' points to their straight lines after correction (pixels).
    residual_before_px : float
        The same without correction (k = 0, the same chains).
    max_displacement_px : float
        The largest distance a pixel of the image moves when undistorted (at a corner).
    found : bool
        True when the estimate is trustworthy: the chain bootstrap's 90 % interval
        ``k1_interval`` excludes 0, is at most half as wide as ``|k1|`` (the lines
        agree with each other, not only the points of one line) and lies within
        ``k1 +- 0.2`` and ``k_range``, and a pixel moves by 1 px or more. False when the
        distortion is indistinguishable from none or not measured well enough; also when
        ``k1`` stopped at an end of ``k_range`` (the lens bends more than the model says).
    image_size : (int, int)
        ``(width, height)``.
    k1_interval : (float, float)
        The 5th and 95th percentiles of ``k1`` over 200 bootstrap resamples of the chains
        (each resample's ``k1`` minimises the resampled chains' summed squared straightness
        error on a 0.0025 grid within ``k1 +- 0.2``; a fixed seed, so repeatable). The
        chains are the independent units: the spread of scene edges that are not quite
        straight, which ``k1_std`` does not see.
    """

    distortion: DivisionModel
    K: FloatArray
    k1_std: float
    lines: tuple[FloatArray, ...]
    residual_px: float
    residual_before_px: float
    max_displacement_px: float
    found: bool
    image_size: tuple[int, int]
    k1_interval: tuple[float, float] = (math.nan, math.nan)

    @property
    def k1(self) -> float:
        """The division coefficient ``k1`` (negative: barrel)."""
        return float(self.distortion.k1)

    @property
    def center(self) -> FloatArray:
        """The distortion centre ``(cx, cy)`` in pixels."""
        return np.asarray(self.K[:2, 2], dtype=np.float64)

    @property
    def corner_distortion(self) -> float:
        """Relative radial displacement of the farthest corner, ``r_u / r_d - 1``."""
        return float(_corner_ratio(self) - 1.0)


def _corner_ratio(res: PlumbLineResult) -> float:
    w, h = res.image_size
    corners = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], dtype=np.float64)
    r = np.hypot(*((corners - res.K[:2, 2]) / res.K[0, 0]).T).max()
    return 1.0 / (1.0 + res.k1 * r * r)


def _correct(
    x: FloatArray, k: float, tangent: FloatArray | None = None
) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    """Undistort normalised points (and carry tangents through the map's Jacobian)."""
    r2 = (x * x).sum(-1)
    d = 1.0 + k * r2
    xu = x / d[:, None]
    if tangent is None:
        return xu, d, None
    xt = (x * tangent).sum(-1)
    tu = tangent / d[:, None] - x * (2.0 * k * xt / (d * d))[:, None]
    return xu, d, tu


def _accumulate(
    xu: FloatArray, normal_angle: FloatArray, rho_max: float, weights: FloatArray | None = None
) -> FloatArray:
    """Hough votes ``(θ, ρ)``; each point votes at its orientation +- the window."""
    n_rho = int(2 * rho_max / _RHO_BIN) + 1
    base = np.round(normal_angle / math.pi * _THETA_BINS).astype(np.int64)
    acc = np.zeros(_THETA_BINS * n_rho)
    for off in range(-_THETA_WINDOW, _THETA_WINDOW + 1):
        tb = base + off
        th = tb * (math.pi / _THETA_BINS)
        rho = xu[:, 0] * np.cos(th) + xu[:, 1] * np.sin(th)
        tb_mod = tb % _THETA_BINS
        flip = (tb // _THETA_BINS) % 2 == 1  # θ + π: the same line with ρ negated
        rho = np.where(flip, -rho, rho)
        rb = np.round((rho + rho_max) / _RHO_BIN).astype(np.int64)
        ok = (rb >= 0) & (rb < n_rho)
        acc += np.bincount(
            tb_mod[ok] * n_rho + rb[ok],
            None if weights is None else weights[ok],
            minlength=acc.size,
        )
    return acc.reshape(_THETA_BINS, n_rho)


class _Setup:
    """The edge points in normalised coordinates and the image's geometry."""

    def __init__(self, pts: FloatArray, normals: FloatArray, center: FloatArray, s: float):
        self.pts = pts
        self.center = center
        self.s = s
        self.x = (pts - center) / s
        self.tangent = np.stack((-normals[:, 1], normals[:, 0]), axis=-1)

    def corrected(self, k: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Corrected points (pixels, rescaled to the distorted image's RMS radius), angles."""
        xu, d, tu = _correct(self.x, k, self.tangent)
        assert tu is not None
        r_d = np.sqrt((self.x**2).sum(-1).mean())
        r_u = np.sqrt((xu**2).sum(-1).mean())
        xu = xu * (r_d / r_u * self.s)
        ang = np.arctan2(tu[:, 0], -tu[:, 1]) % math.pi  # the normal's angle in [0, π)
        return xu, ang, d


def _chains(
    setup: _Setup, k: float, rho_max: float, tol: float, min_length: float, n_lines: int
) -> list[np.ndarray]:
    """Index arrays of the chains of collinear points at ``k`` (sequential Hough peaks)."""
    xu, ang, _ = setup.corrected(k)
    free = np.ones(len(xu), dtype=bool)
    out: list[np.ndarray] = []
    min_votes = max(5.0, 0.5 * min_length)
    acc = _accumulate(xu, ang, rho_max)
    n_rho = acc.shape[1]
    for _ in range(4 * n_lines):
        if len(out) >= n_lines:
            break
        best = int(np.argmax(acc))
        if acc.flat[best] < min_votes:
            break
        idx_free = np.nonzero(free)[0]
        tb, rb = divmod(best, n_rho)
        th = tb * math.pi / _THETA_BINS
        rho = rb * _RHO_BIN - rho_max
        n = np.array([math.cos(th), math.sin(th)])
        dist = xu[idx_free] @ n - rho
        dang = np.abs((ang[idx_free] - th + math.pi / 2) % math.pi - math.pi / 2)
        near = idx_free[(np.abs(dist) <= max(tol, _RHO_BIN)) & (dang <= _ANGLE_TOL)]
        used = np.zeros(len(xu), dtype=bool)
        used[idx_free[np.abs(dist) <= _RHO_BIN]] = True  # the peak's cell is used up
        acc.flat[best] = 0.0  # a peak of points that vote elsewhere too is not met again
        if len(near) >= 3:
            # refit the line to its points, recollect, then cut into chains at gaps
            p = xu[near]
            m = p.mean(0)
            _, _, vt = np.linalg.svd(p - m, full_matrices=False)
            n = vt[1]
            dist = (xu[idx_free] - m) @ n
            dang = np.abs(
                (ang[idx_free] - math.atan2(n[1], n[0]) + math.pi / 2) % math.pi - math.pi / 2
            )
            near = idx_free[(np.abs(dist) <= tol) & (dang <= _ANGLE_TOL)]
            used[near] = True
            t = (xu[near] - m) @ vt[0]
            order = np.argsort(t)
            t, near = t[order], near[order]
            cuts = np.nonzero(np.diff(t) > _MAX_GAP)[0] + 1
            for piece, tp in zip(np.split(near, cuts), np.split(t, cuts), strict=True):
                if len(piece) >= 3 and tp[-1] - tp[0] >= min_length:
                    out.append(piece)
        if used.any():
            free &= ~used
            gone = _accumulate(xu[used], ang[used], rho_max)
            acc -= gone
    return out


def _consensus(setup: _Setup, chains: list[np.ndarray], ks: FloatArray, tolerance: float) -> float:
    """Return the ``k`` of ``ks`` minimising the chains' truncated squared straightness error."""
    err = _chain_errors(setup, chains, ks)
    weight = np.array([len(c) for c in chains], dtype=np.float64)
    cost = (np.minimum(err * err, tolerance * tolerance) * weight).sum(1)
    return float(ks[int(np.argmin(cost))])


def _distinct(chains: list[np.ndarray]) -> list[np.ndarray]:
    """Return the chains without the points already in a longer one (a contour is a line too)."""
    taken: set[int] = set()
    out = []
    for c in sorted(chains, key=len, reverse=True):
        rest = np.array([i for i in c.tolist() if i not in taken], dtype=np.int64)
        if len(rest) >= 0.5 * len(c) and len(rest) >= 3:
            out.append(rest)
            taken.update(rest.tolist())
    return out


def _chain_errors(setup: _Setup, chains: list[np.ndarray], ks: FloatArray) -> FloatArray:
    """RMS straightness error (distorted pixels) of each chain at each ``k``: ``(len(ks), n)``."""
    idx = np.concatenate(chains)
    lab = np.repeat(np.arange(len(chains)), [len(c) for c in chains])
    cnt = np.bincount(lab).astype(np.float64)
    x = setup.x[idx]
    out = np.empty((len(ks), len(chains)))
    for j, k in enumerate(ks):
        res = _distances(x, float(k), lab, cnt) * setup.s
        out[j] = np.sqrt(np.bincount(lab, res * res) / cnt)
    return out


def _distances(x: FloatArray, k: float, lab: np.ndarray, cnt: FloatArray) -> FloatArray:
    r"""Distance of each point to its chain's line, in the distorted image (first order).

    The chain's line ``n·x_u = ρ`` is the total least-squares fit to the corrected points;
    the distance is ``(n·x_u - ρ) / |Jᵀ n|`` with ``J = ∂x_u/∂x_d`` (Sampson's first-order
    distance), so a correction that squeezes the image does not look straighter.
    """
    xu, d, _ = _correct(x, k)
    mx = np.bincount(lab, xu[:, 0]) / cnt
    my = np.bincount(lab, xu[:, 1]) / cnt
    dx, dy = xu[:, 0] - mx[lab], xu[:, 1] - my[lab]
    sxx = np.bincount(lab, dx * dx)
    syy = np.bincount(lab, dy * dy)
    sxy = np.bincount(lab, dx * dy)
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # the principal direction
    nx, ny = -np.sin(phi)[lab], np.cos(phi)[lab]
    xn = x[:, 0] * nx + x[:, 1] * ny
    # J = I / d - 2 k x xᵀ / d² (symmetric): Jᵀ n = n / d - 2 k (x·n) x / d²
    g = 2.0 * k * xn / (d * d)
    jx, jy = nx / d - g * x[:, 0], ny / d - g * x[:, 1]
    return (dx * nx + dy * ny) / np.hypot(jx, jy)


def _chain_bootstrap(
    setup: _Setup, chains: list[np.ndarray], k: float, bounds: tuple[float, float]
) -> tuple[float, float, bool]:
    """Return the 5th and 95th percentiles of ``k`` over bootstrap resamples of the chains.

    Each chain's sum of squared straightness errors is tabulated on a grid around ``k``; a
    resample (the chains drawn with replacement, a fixed seed) takes the grid's ``k`` that
    minimises its summed error. A resample's minimum at the grid's end stands for a ``k``
    beyond it: the third value says whether the interval lies inside the grid.
    """
    lo = max(bounds[0], k - _BOOT_SPAN)
    hi = min(bounds[1], k + _BOOT_SPAN)
    grid = np.arange(lo, hi + 1e-12, _BOOT_STEP)
    n = np.array([len(c) for c in chains], dtype=np.float64)
    sse = _chain_errors(setup, chains, grid) ** 2 * n  # (len(grid), chains)
    m = len(chains)
    rng = np.random.default_rng(0)
    counts = rng.multinomial(m, np.full(m, 1.0 / m), size=_BOOT).astype(np.float64)
    kb = grid[np.argmin(counts @ sse.T, axis=1)]
    q5, q95 = np.percentile(kb, [5.0, 95.0])
    inside = bool(grid[0] < q5 and q95 < grid[-1])
    return float(q5), float(q95), inside


def _refine(
    setup: _Setup,
    chains: list[np.ndarray],
    k0: float,
    bounds: tuple[float, float],
    estimate_center: bool,
    max_iter: int,
) -> tuple[float, FloatArray, float, int]:
    """Least squares on the inlier chains: ``(k, centre, k_std, nfev)``."""
    from scipy.optimize import least_squares

    idx = np.concatenate(chains)
    lab = np.repeat(np.arange(len(chains)), [len(c) for c in chains])
    cnt = np.bincount(lab).astype(np.float64)
    pts = setup.pts[idx]
    s = setup.s

    def residuals(p: FloatArray) -> FloatArray:
        c = p[1:3] * s + setup.center if estimate_center else setup.center
        return _distances((pts - c) / s, float(p[0]), lab, cnt) * s

    p0 = np.array([k0, 0.0, 0.0]) if estimate_center else np.array([k0])
    lo = [bounds[0], -0.25, -0.25] if estimate_center else [bounds[0]]
    hi = [bounds[1], 0.25, 0.25] if estimate_center else [bounds[1]]
    sol = least_squares(
        residuals,
        np.clip(p0, lo, hi),
        bounds=(lo, hi),
        loss="soft_l1",
        f_scale=1.0,
        max_nfev=max_iter * (len(p0) + 1),
    )
    if not np.isfinite(sol.x).all():  # pragma: no cover - least_squares keeps finite steps
        raise DegenerateConfigurationError("the distortion refinement diverged")
    r = sol.fun
    dof = max(len(r) - len(p0) - 2 * len(chains), 1)
    sigma2 = float(r @ r) / dof
    jtj = sol.jac.T @ sol.jac
    try:
        cov = np.linalg.inv(jtj) * sigma2
        k_std = float(math.sqrt(max(cov[0, 0], 0.0)))
    except np.linalg.LinAlgError:
        k_std = math.inf
    center = sol.x[1:3] * s + setup.center if estimate_center else setup.center
    return float(sol.x[0]), np.asarray(center, dtype=np.float64), k_std, int(sol.nfev)


def estimate_distortion_from_lines(
    image: ArrayLike,
    *,
    center: ArrayLike | None = None,
    estimate_center: bool = False,
    k_range: tuple[float, float] = (-0.9, 0.6),
    min_lines: int = 3,
    n_lines: int = 40,
    min_length: float | None = None,
    tolerance: float = 1.5,
    edge_threshold: float = 0.02,
    max_iter: int = 100,
) -> PlumbLineResult:
    r"""Estimate radial lens distortion from the straight lines of one image (plumb lines).

    The one-parameter division model (Fitzgibbon 2001) on coordinates normalised by the
    centre-to-corner distance ``s``,

    .. math::

        \mathbf{x}_u = \frac{\mathbf{x}_d}{1 + k_1 r_d^2}, \quad
        \mathbf{x} = (\mathbf{u} - \mathbf{c}) / s,

    maps a straight scene line's image (an arc) to a straight line; ``k1`` is the value that
    makes the image's long edges straightest: a consensus over the edge contours and the
    lines collinear after correction (a truncated squared straightness error; the lines
    from a distortion-aware Hough transform, Alemán-Flores et al. 2014) and least-squares
    refinement (see :mod:`imageform.geometry.plumb_line`).

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Grey or RGB; uint8/uint16 or floats in [0, 1].
    center : (cx, cy), optional
        Distortion centre in pixels (default the image centre, ``((W-1)/2, (H-1)/2)``).
    estimate_center : bool
        Refine the centre too (from one image it is weakly determined: keep the default
        unless the lines cover the image).
    k_range : (float, float)
        The range of ``k1``, ``-0.99 <= low < 0 < high <= 1`` (``r / (1 + k r²)`` stays
        monotonic to the corners for ``k <= 1``); corner displacements ``1/(1+k)-1``: the
        default -0.9 to 0.6 covers +900 % (a fisheye) to -37.5 %.
    min_lines : int
        Fewer straight-line chains than this raise :class:`DegenerateConfigurationError`.
    n_lines : int
        The most Hough lines extracted per pass (the 200 longest contours are used too).
    min_length : float, optional
        Shortest chain, pixels (default 5 % of the image diagonal, at least 20 px).
    tolerance : float
        Largest distance (pixels) of a point from its line when chains are collected.
    edge_threshold : float
        Gradient magnitude (image units per pixel, after a σ = 1 px Gaussian) an edge
        point needs.
    max_iter : int
        Iterations of the least-squares refinement.

    Returns
    -------
    PlumbLineResult
        ``distortion`` and ``K`` plug into :func:`~imageform.geometry.undistort_image`.

    Raises
    ------
    InvalidInputError
        If the image is not an (H, W) or (H, W, 3) image of at least 16 x 16 pixels, or an
        option is out of range.
    DegenerateConfigurationError
        If fewer than ``min_lines`` straight-line chains are found.

    Warns
    -----
    IllConditionedWarning
        ``k1`` stopped at an end of ``k_range``: a fisheye bends more than one division
        coefficient describes (calibrate it with a board and the Kannala-Brandt model).

    References
    ----------
    .. [1] A. W. Fitzgibbon, "Simultaneous linear estimation of multiple view geometry and
       lens distortion", CVPR 2001, eq. (3).
    .. [2] M. Alemán-Flores, L. Alvarez, L. Gomez, D. Santana-Cedrés, "Automatic Lens
       Distortion Correction Using One-Parameter Division Models", IPOL 4 (2014) 327-343.
    .. [3] F. Bukhari, M. N. Dailey, "Automatic radial distortion estimation from a single
       image", J. Math. Imaging Vis. 45 (2013) 31-45.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.geometry import DivisionModel
    >>> v, u = (np.mgrid[0:960, 0:1280] + 0.5) / 4 - 0.5     # 4 x 4 samples a pixel
    >>> s = np.hypot(159.5, 119.5)
    >>> x = np.stack(((u - 159.5) / s, (v - 119.5) / s), -1)
    >>> xu, _ = DivisionModel(k1=-0.1).undistort(x)      # where each pixel looks
    >>> uu, vv = xu[..., 0] * s + 159.5, xu[..., 1] * s + 119.5
    >>> board = (uu // 40 + vv // 40) % 2                # a checkerboard, barrel-distorted
    >>> img = board.reshape(240, 4, 320, 4).mean(axis=(1, 3))
    >>> res = estimate_distortion_from_lines(img)
    >>> round(res.k1, 3), res.found
    (-0.1, True)
    """
    img = _grey(image)
    h, w = img.shape
    check_min_side(img.shape, 16)
    estimate_center = as_bool(estimate_center, "estimate_center")
    pair = np.asarray(k_range, dtype=object)
    if pair.shape != (2,):
        raise InvalidInputError(
            f"expected k_range as two numbers (low, high), got {describe(k_range)}"
        )
    lo, hi = (as_real(v, "k_range", minimum=-0.99, maximum=1.0) for v in pair)
    if not lo < 0.0 < hi:
        raise InvalidInputError(f"expected k_range with low < 0 < high, got ({lo:g}, {hi:g})")
    min_lines = as_int(min_lines, "min_lines", minimum=1, maximum=10000)
    n_lines = as_int(n_lines, "n_lines", minimum=1, maximum=10000)
    diag = math.hypot(w, h)
    if min_length is None:
        min_length = max(20.0, 0.05 * diag)
    min_length = as_real(min_length, "min_length", minimum=3.0, maximum=1e6)
    tolerance = as_real(tolerance, "tolerance", positive=True, maximum=100.0)
    edge_threshold = as_real(edge_threshold, "edge_threshold", positive=True, maximum=10.0)
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=100000)
    c0 = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    if center is not None:
        c_arr = np.asarray(_center_pair(center), dtype=np.float64)
        c0 = c_arr
    s = float(math.hypot((w - 1) / 2.0, (h - 1) / 2.0))

    max_chains = 200
    pts, normals = _edge_points(img, edge_threshold)
    if len(pts) < 3 * min_lines:
        raise DegenerateConfigurationError(
            f"found {len(pts)} edge points; distortion from straight lines needs at least "
            f"{min_lines} long straight edges"
        )
    setup = _Setup(pts, normals, c0, s)
    rho_max = 2.0 * diag
    contours = _contours(pts, normals, (h, w), min_length)[:max_chains]
    fine = np.arange(lo, hi + 1e-12, 0.0025)
    chains: list[np.ndarray] = []
    k_std = math.inf
    k = 0.0
    if len(contours) >= min_lines:
        k = _consensus(setup, contours, fine, tolerance)
    for _ in range(3):
        # the contours and the lines collinear at k (pieces of a line joined across gaps)
        lines = _chains(setup, k, rho_max, tolerance, min_length, n_lines)
        cand = contours + lines
        if len(cand) < min_lines:
            break
        window = fine[np.abs(fine - k) <= 0.05 + 1e-12]
        k = _consensus(setup, cand, window, tolerance)
        e_at = _chain_errors(setup, cand, np.array([k]))[0]
        chains = _distinct([c for c, e in zip(cand, e_at, strict=True) if e <= tolerance])
        if len(chains) < min_lines:
            break
        k, c_new, k_std, _ = _refine(setup, chains, k, (lo, hi), estimate_center, max_iter)
        if estimate_center:
            setup = _Setup(pts, normals, c_new, s)
    if len(chains) < min_lines:
        raise DegenerateConfigurationError(
            f"found {len(chains)} straight-line chain(s) at least {min_length:.0f} px long; "
            f"distortion from straight lines needs at least {min_lines}"
        )
    e_after = _chain_errors(setup, chains, np.array([k]))[0]
    e_before = _chain_errors(setup, chains, np.array([0.0]))[0]
    n = np.array([len(c) for c in chains], dtype=np.float64)
    K = np.array([[s, 0.0, setup.center[0]], [0.0, s, setup.center[1]], [0.0, 0.0, 1.0]])
    res = PlumbLineResult(
        distortion=DivisionModel(k1=k),
        K=K,
        k1_std=k_std,
        lines=tuple(pts[c] for c in chains),
        residual_px=float(np.sqrt((e_after**2 * n).sum() / n.sum())),
        residual_before_px=float(np.sqrt((e_before**2 * n).sum() / n.sum())),
        max_displacement_px=0.0,
        found=False,
        image_size=(w, h),
    )
    ratio = _corner_ratio(res)
    corners = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], dtype=np.float64)
    r_px = float(np.hypot(*(corners - setup.center).T).max())
    disp = abs(ratio - 1.0) * r_px
    at_bound = min(k - lo, hi - k) < 0.0025  # the fit stopped at k_range's end
    if at_bound:
        warnings.warn(
            f"estimate_distortion_from_lines: k1 = {k:.4f} is at the end of k_range ({lo:g}, "
            f"{hi:g}): the lens bends more than one division coefficient describes (a "
            "fisheye); calibrate it with a board (calibrate_camera(model='kannala_brandt'))",
            IllConditionedWarning,
            stacklevel=2,
        )
    k_lo, k_hi, inside = _chain_bootstrap(setup, chains, k, (lo, hi))
    found = (
        not at_bound
        and disp >= _NONE_PX
        and inside  # no resampled fit ran off the searched range
        and k_lo * k_hi > 0.0  # the lines agree on the sign of the distortion
        and k_hi - k_lo <= _WIDTH * abs(k)  # ... and on its size
    )
    object.__setattr__(res, "k1_interval", (k_lo, k_hi))
    object.__setattr__(res, "max_displacement_px", float(disp))
    object.__setattr__(res, "found", bool(found))
    return res


def _center_pair(value: object) -> tuple[float, float]:
    """Return ``(cx, cy)`` as floats; raise for anything but two finite numbers."""
    arr = np.asarray(value, dtype=object)
    if arr.shape != (2,):
        raise InvalidInputError(f"expected center as (cx, cy), got {describe(value)}")
    return (
        as_real(arr[0], "center[0]", minimum=-1e6, maximum=1e6),
        as_real(arr[1], "center[1]", minimum=-1e6, maximum=1e6),
    )
