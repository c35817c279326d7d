"""Vanishing points, the orthogonal triplet, K and the horizon found in a photograph.

Pipeline: line segments (:func:`~imageform.geometry.detect_line_segments`) → sequential
RANSAC over pairs of segments (a hypothesis ``v = l_i × l_j`` is scored by the total length of
segments pointing at it within an angle) with a least-squares refit on the inliers
(:func:`~imageform.geometry.vanishing_point_from_lines`) → among the candidates, the triplet
most consistent with three orthogonal scene directions (a "Manhattan world", Coughlan &
Yuille 1999) → K → the vertical direction (the one closest to the image's y axis) and the
horizon ``l ~ K⁻ᵀ d_vertical``.

K, by default (``principal_point="center"``): the principal point at the image centre (or
where the caller puts it) and the focal length that makes the set's directions
``K⁻¹ vᵢ`` most nearly orthogonal (least squares over the pairs; for two finite points
``f² = -(v₁ - p)·(v₂ - p)``, Caprile & Torre 1990); a set whose directions stay more than
``orthogonality_tolerance`` from orthogonal is not a Manhattan set and is passed over. With
``principal_point="orthocenter"``, three finite points give the principal point as their
triangle's orthocentre (Caprile & Torre), the textbook construction, which on real photographs
moves far with a weakly supported third point: on OpenCV's 13 checkerboard photographs
(undistorted, known f = 536 px; ``benchmarks/check_vp_real.py``, a view without K counting
as an infinite error) the median focal-length error is 129 % with the orthocentre, 6.5 % with
the centre and 2.4 % with the calibrated principal point (23 px from the centre)
(``benchmarks/results/vp-real-2026-11-29f.md``).

Three finite points that fix K must be mutually orthogonal for a principal point near the
one assumed: their orthocentre (where the three pairwise estimates
``f² = -(vᵢ - p)·(vⱼ - p)`` agree) must not lie outside ``_PP_BOX`` of the image's width and
height of it along an axis by more than ``_PP_SIGNIFICANT`` times the spread that resampling
the points' segments gives it there (an offset that the segments' scatter explains is not an
inconsistency). Otherwise the focal length rests on the two best-supported points (when the
third has at most ``_PAIR_CLEAR`` of the second's support; ``K_note`` says so) or ``K`` is
None with ``K_reason``: on York Urban photographs two facades at 71 degrees gave f +47 %.
``principal_point="estimate"`` (opt-in) takes the orthocentre of three such consistent,
well-supported points as the principal point where resampling their segments moves it by
at most ``_PP_SPREAD`` of the image's height and the focal length there by at most
``_K_MAX_SPREAD``; otherwise the centre, with ``K_note`` saying why.

A photograph of low contrast (haze, fog, a dim room, underexposure: less than 64 grey levels
of 255 between its 1st and 99th percentiles) is stretched to the full range before LSD,
whose gradient threshold (5.2 levels per pixel) its edges fall below; any other photograph
is read as it is, and its segments are bit-identical
(:func:`~imageform.geometry.lsd._stretch_low_contrast`). ``horizon_spread`` says how far
resampling the points' segments moves the horizon, as a share of the height.

K is given only where the evidence holds it (two finite points fix a focal length whatever
the scene, and nothing in the pair says whether their directions are orthogonal): a finite
point that fixes ``f`` needs ``_K_MIN_SEGMENTS`` segments and ``_K_MIN_SUPPORT`` image
diagonals of them (weaker points stay in the set, out of the fit), resampling the points'
segments may move ``f`` by ``_K_MAX_SPREAD`` at most, and ``f`` lies within
``_F_PLAUSIBLE`` image diagonals; otherwise ``K`` is None with ``K_reason``.
"""

from __future__ import annotations

import copy
import itertools
import math
from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike, FloatArray
from imageform._validate import (
    as_int,
    as_real,
    check_image_size,
    check_positive,
    check_rng,
    describe,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry.line_segments import LineSegments, detect_line_segments
from imageform.geometry.lsd import _grey255, _stretch_low_contrast
from imageform.geometry.vanishing import (
    focal_from_vanishing_points,
    horizon_line,
    intrinsics_from_vanishing_points,
    vanishing_point_from_lines,
)

__all__ = ["VanishingPointResult", "detect_vanishing_points"]


@dataclass(frozen=True)
class VanishingPointResult:
    """What :func:`detect_vanishing_points` found.

    Attributes
    ----------
    vanishing_points : (M, 3)
        Homogeneous vanishing points (``w = 1`` finite, ``w = 0`` at infinity), M <= 3,
        the orthogonal triplet (or pair) when one was found; M = 0 when the image shows
        none (fewer than two line segments, or no point they support).
    labels : (N,)
        For each segment, the index of its vanishing point, or -1.
    segments : LineSegments
    K : (3, 3) or None
        Intrinsics from the vanishing points (square pixels, zero skew), if determined.
    vertical : int or None
        Index of the vertical vanishing point (the direction closest to the image's y axis);
        None when the two points found are both horizontal (the horizon then comes from
        their cross product, the vertical direction), when, without K, no point's segments
        run nearer the image's columns than its rows, or when the horizon is the visible one
        of open water and no point lies near the image's columns.
    horizon : (3,) or None
        The horizon ``(a, b, c)``, ``a u + b v + c = 0``, ``a² + b² = 1``: from K and the
        vertical point, from a level camera's vertical and horizontal points, or, when no
        vanishing point gives it, the visible horizon of open water (the highest long
        near-horizontal line across the frame).
    perspective : int
        How many of the vanishing points are finite (1, 2 or 3 point perspective), with
        "finite" meaning within ``infinity_factor`` image diagonals of the image centre.
    scores : (M,)
        Total length of the segments supporting each vanishing point (pixels).
    K_reason : str or None
        Why ``K`` is None (one line, beginning "not determined: "): no points, fewer than two
        finite ones, no orthogonal set, points too weakly supported, a focal length that
        resampling the segments moves too far, or one no camera lens has. None when ``K``
        is determined.
    focal_spread : float or None
        How far resampling the vanishing points' segments moves the focal length (the
        half-width of the central 68 % of ``log f`` over 64 resamples, about its relative
        standard deviation; 0.01 is ±1 %), for the set a focal length was fitted to; None
        when none was.
    K_note : str or None
        A remark on a ``K`` that was given (one line): the focal length rests on the two
        best-supported points alone (three finite points whose orthocentre is far from the
        principal point: not mutually orthogonal), or, with ``principal_point="estimate"``,
        why the principal point is the image centre after all. None otherwise.
    horizon_spread : float or None
        How far resampling the vanishing points' segments moves the horizon, as a share of
        the image's height (0.01 is 1 % of H): each point's segments drawn with replacement
        64 times, the points, the focal length and the horizon refitted by the same rules;
        the larger, over the image's left and right edges, of the half-width of the central
        68 % of the horizon's row there (about a standard deviation; York Urban scores a
        horizon by the larger of its two edge errors over H). ``inf`` when fewer than half
        of the resamples give a horizon (``null`` in JSON). None when the horizon does not
        come from vanishing points (none found, or the visible horizon of open water).
    """

    vanishing_points: FloatArray
    labels: np.ndarray
    segments: LineSegments
    K: FloatArray | None
    vertical: int | None
    horizon: FloatArray | None
    perspective: int
    scores: FloatArray
    K_reason: str | None = None
    focal_spread: float | None = None
    K_note: str | None = None
    horizon_spread: float | None = None


def _angles_to(v: FloatArray, mids: FloatArray, dirs: FloatArray) -> FloatArray:
    """Angle between each segment's direction and the line from its midpoint to ``v``.

    ``v`` is ``(H, 3)`` hypotheses; returns ``(H, N)`` radians in [0, π/2].
    """
    d = v[:, None, :2] - mids[None, :, :] * v[:, None, 2:3]
    dn = np.hypot(d[..., 0], d[..., 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(d[..., 0] * dirs[None, :, 0] + d[..., 1] * dirs[None, :, 1]) / dn
    cos = np.where(dn > 0, cos, 1.0)
    return np.arccos(np.clip(cos, 0.0, 1.0))


def _normalise(v: FloatArray, scale: float) -> FloatArray:
    """Scale finite points to ``w = 1``; turn points at infinity into unit directions.

    Points at infinity (``|w|`` at rounding level of ``|(x, y)| / scale``) become a unit
    direction ``(dx, dy, 0)`` with a canonical sign.
    """
    v = np.asarray(v, dtype=np.float64)
    n = float(np.hypot(v[0], v[1]))
    if abs(v[2]) * scale > 1e-12 * max(n, 1e-300):
        return v / v[2]
    sign = 1.0 if (v[0] > 0 or (v[0] == 0 and v[1] >= 0)) else -1.0
    return np.array([sign * v[0] / n, sign * v[1] / n, 0.0])


def _ransac_candidates(
    seg: LineSegments, rng: np.random.Generator, n_candidates: int, threshold: float, iters: int
) -> list[tuple[FloatArray, np.ndarray, float]]:
    lines = seg.lines
    mids = seg.midpoints
    d = seg.endpoints[:, 1] - seg.endpoints[:, 0]
    lengths = np.hypot(d[:, 0], d[:, 1])
    dirs = d / lengths[:, None]
    remaining = np.ones(len(seg), dtype=bool)
    out: list[tuple[FloatArray, np.ndarray, float]] = []
    for _ in range(n_candidates):
        idx = np.flatnonzero(remaining)
        if idx.size < 2:
            break
        prob = lengths[idx] / lengths[idx].sum()
        a = rng.choice(idx, size=iters, p=prob)
        b = rng.choice(idx, size=iters, p=prob)
        ok = a != b
        hyp = np.cross(lines[a[ok]], lines[b[ok]])
        nz = np.linalg.norm(hyp, axis=1) > 0
        hyp = hyp[nz]
        if hyp.shape[0] == 0:
            break
        ang = _angles_to(hyp, mids[idx], dirs[idx])
        score = (ang < threshold) @ lengths[idx]
        best = hyp[int(np.argmax(score))]
        inl = np.zeros(len(seg), dtype=bool)
        inl[idx] = _angles_to(best[None], mids[idx], dirs[idx])[0] < threshold
        for _ in range(3):  # least-squares refits on the inliers
            if inl.sum() < 2:
                break
            best = np.asarray(vanishing_point_from_lines(lines[inl], weights=lengths[inl]))
            new = np.zeros(len(seg), dtype=bool)
            new[idx] = _angles_to(best[None], mids[idx], dirs[idx])[0] < threshold
            if np.array_equal(new, inl) or new.sum() < 2:
                break
            inl = new
        sc = float(lengths[inl].sum())
        if inl.sum() < 2 or sc <= 0:
            break
        out.append((best, inl, sc))
        remaining &= ~inl
    return out


def _segments_within(arr: np.ndarray, max_size: int | None) -> LineSegments:
    """Return the segments of ``arr``, found on a copy at most ``max_size`` px on its long side.

    The copy (grey, as LSD reads the image) is Gaussian-filtered (σ = 0.5 / scale, as
    :func:`detect_horizon`'s working image) and linearly interpolated with pixel centres
    aligned (``grid_mode``); its end
    points map back as ``u = (u' + 0.5) / sₓ - 0.5`` (``v`` likewise) and the widths by the
    mean scale.
    """
    if max_size is None:
        return detect_line_segments(arr)
    h, w = arr.shape[:2]
    scale = max_size / max(h, w)
    if scale >= 1.0:
        return detect_line_segments(arr)
    from scipy import ndimage

    sigma = 0.5 / scale
    a = ndimage.gaussian_filter(_grey255(arr), sigma, mode="nearest")
    small = ndimage.zoom(a, scale, order=1, mode="nearest", grid_mode=True)
    seg = detect_line_segments(small / 255.0)  # grey in [0, 1], as LSD reads floats
    sx, sy = small.shape[1] / w, small.shape[0] / h
    ends = seg.endpoints.copy()
    ends[..., 0] = (ends[..., 0] + 0.5) / sx - 0.5
    ends[..., 1] = (ends[..., 1] + 0.5) / sy - 0.5
    return LineSegments(ends, seg.widths * 2.0 / (sx + sy), seg.log10_nfa)


def _is_finite(v: FloatArray, ref: FloatArray, far: float) -> bool:
    """Whether the homogeneous point ``v`` is finite: ``w != 0`` and within ``far`` of ``ref``."""
    return bool(v[2] != 0 and np.hypot(*(v[:2] / v[2] - ref)) < far)


def _directions(vps: list[FloatArray], pp: FloatArray, f: FloatArray) -> FloatArray:
    """Return the unit directions ``K⁻¹ v`` of the points for each focal length in ``f``.

    Shape ``(F, M, 3)`` for ``F`` focal lengths and ``M`` points.
    """
    v = np.asarray(vps, dtype=np.float64)
    a = v[:, :2] - pp[None, :] * v[:, 2:3]
    d = np.empty((len(f), len(v), 3))
    d[..., 0] = a[None, :, 0]
    d[..., 1] = a[None, :, 1]
    d[..., 2] = f[:, None] * v[None, :, 2]
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _manhattan_K(
    vps: list[FloatArray],
    support: list[float],
    pp: FloatArray,
    diag: float,
    far: float,
    tol: float,
) -> FloatArray | None:
    """Return K with principal point ``pp`` making the points' directions most nearly orthogonal.

    The focal length minimises ``Σ sᵢ sⱼ (dᵢ·dⱼ)²`` over the pairs, each weighted by the
    product of its points' support ``s`` (a weakly supported point moves it little; a
    log-spaced search over
    ``[0.15, 10]`` image diagonals, refined by golden section); None when fewer than two
    points are finite, when the minimum lies at the search's ends, or when a pair stays more
    than ``tol`` (radians) from orthogonal.
    """
    finite = [v for v in vps if _is_finite(v, pp, far)]
    if len(finite) < 2:
        return None
    pairs = list(itertools.combinations(range(len(vps)), 2))
    wts = [support[i] * support[j] for i, j in pairs]

    def cost(f: FloatArray) -> FloatArray:
        d = _directions(vps, pp, f)
        terms = [
            wt * np.einsum("fk,fk->f", d[:, i], d[:, j]) ** 2
            for wt, (i, j) in zip(wts, pairs, strict=True)
        ]
        return np.sum(terms, axis=0)

    lo, hi = math.log(0.15 * diag), math.log(10 * diag)
    grid = np.linspace(lo, hi, 241)
    c = cost(np.exp(grid))
    k = int(np.argmin(c))
    if k in (0, len(grid) - 1):
        return None
    a, b = grid[k - 1], grid[k + 1]
    g = (math.sqrt(5) - 1) / 2
    for _ in range(40):  # golden section on log f
        x1, x2 = b - g * (b - a), a + g * (b - a)
        c1, c2 = cost(np.exp([x1, x2]))
        if c1 < c2:
            b = x2
        else:
            a = x1
    f = math.exp((a + b) / 2)
    d = _directions(vps, pp, np.array([f]))[0]
    if any(abs(float(d[i] @ d[j])) > math.sin(tol) for i, j in pairs):
        return None
    return np.array([[f, 0.0, pp[0]], [0.0, f, pp[1]], [0.0, 0.0, 1.0]])


def _refit_batch(
    lines: FloatArray, weights: FloatArray, counts: FloatArray, far: float
) -> FloatArray:
    """Return the least-squares vanishing points of resampled line sets, ``(B, 3)``.

    ``counts`` ``(B, n)`` says how often each of the ``n`` lines is drawn in each of ``B``
    resamples; each point minimises ``Σ countᵢ wᵢ (lᵢ · v)²`` over unit ``v`` in Hartley-
    normalised coordinates (as :func:`~imageform.geometry.vanishing_point_from_lines`,
    the normalisation that of the full set), then finite points are scaled to ``w = 1``.
    """
    L = lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]
    foot = -L[:, 2:3] * L[:, :2]
    c = foot.mean(axis=0)
    spread = float(np.mean(np.hypot(*(foot - c).T)))
    s = spread / math.sqrt(2.0) if spread > 0 else 1.0
    Ln = np.stack([L[:, 0], L[:, 1], (L[:, 2] + L[:, 0] * c[0] + L[:, 1] * c[1]) / s], axis=1)
    M = np.einsum("bi,ij,ik->bjk", counts * weights[None, :], Ln, Ln)
    vn = np.linalg.eigh(M)[1][:, :, 0]
    v = np.stack([vn[:, 0] * s + c[0] * vn[:, 2], vn[:, 1] * s + c[1] * vn[:, 2], vn[:, 2]], 1)
    return _normalise_rows(v, far)


def _normalise_rows(v: FloatArray, scale: float) -> FloatArray:
    """:func:`_normalise` of each row of ``v`` ``(B, 3)``, the same arithmetic, vectorised."""
    n = np.hypot(v[:, 0], v[:, 1])
    fin = np.abs(v[:, 2]) * scale > 1e-12 * np.maximum(n, 1e-300)
    out = np.zeros_like(v)
    out[fin] = v[fin] / v[fin, 2:3]
    inf = ~fin
    sign = np.where((v[inf, 0] > 0) | ((v[inf, 0] == 0) & (v[inf, 1] >= 0)), 1.0, -1.0)
    out[inf, 0] = sign * v[inf, 0] / n[inf]
    out[inf, 1] = sign * v[inf, 1] / n[inf]
    return out


def _focal_grid(
    vps: FloatArray,
    support: list[float],
    pp: FloatArray,
    diag: float,
    near: float | None = None,
) -> FloatArray:
    """Return the focal length fitted to each of ``B`` sets of points ``(B, M, 3)``.

    The cost of :func:`_manhattan_K` on its log-spaced grid, refined by a parabola through
    the grid's three lowest values; NaN where the minimum lies at the grid's ends. With
    ``near`` (a focal length), the grid is the part of that grid within a factor 1.65 of it
    (``log f ± 0.5``; the same spacing): a minimum farther out is NaN too.
    """
    lo, hi = math.log(0.15 * diag), math.log(10 * diag)
    grid = np.linspace(lo, hi, 241)
    if near is not None:
        grid = grid[np.abs(grid - math.log(near)) <= 0.5]
        if len(grid) < 3:
            return np.full(len(vps), np.nan)
    f = np.exp(grid)
    a = vps[:, :, :2] - pp[None, None, :] * vps[:, :, 2:3]  # (B, M, 2)
    d = np.empty((vps.shape[0], len(f), vps.shape[1], 3))
    d[..., :2] = a[:, None, :, :]
    d[..., 2] = f[None, :, None] * vps[:, None, :, 2]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    cost = np.zeros(d.shape[:2])
    for i, j in itertools.combinations(range(vps.shape[1]), 2):
        cost += support[i] * support[j] * np.einsum("bfk,bfk->bf", d[:, :, i], d[:, :, j]) ** 2
    k = np.argmin(cost, axis=1)
    out = np.full(len(k), np.nan)
    ok = (k > 0) & (k < len(grid) - 1)
    rows = np.flatnonzero(ok)
    c0, c1, c2 = cost[rows, k[ok] - 1], cost[rows, k[ok]], cost[rows, k[ok] + 1]
    den = c0 - 2 * c1 + c2
    step = np.where(den > 0, 0.5 * (c0 - c2) / np.where(den > 0, den, 1.0), 0.0)
    out[rows] = np.exp(grid[k[ok]] + np.clip(step, -1.0, 1.0) * (grid[1] - grid[0]))
    return out


#: A finite vanishing point fixes a focal length only when at least this many segments, of
#: at least this total length (image diagonals), support it: a landscape's rocks or dunes
#: have pairs of points a few short segments meet by chance (f -75 % on a real photograph).
_K_MIN_SEGMENTS = 12
_K_MIN_SUPPORT = 0.6
#: K is left undetermined when resampling the points' segments moves ``f`` by more than this
#: (the half-width of the central 68 % of ``log f``), or finds no ``f`` in this share of
#: the resamples: on the York Urban photographs the sets resampling moved by a few per cent
#: were the ones whose focal length was off by tens of per cent
#: (``benchmarks/results/vp-real-2026-11-29c.md``).
_K_MAX_SPREAD = 0.025
_K_MAX_FAIL = 0.2
#: The focal lengths (image diagonals) taken as a camera's: a 13 to 260 mm-equivalent lens.
_F_PLAUSIBLE = (0.3, 6.0)
#: Three finite points are taken as mutually orthogonal unless their orthocentre (the
#: principal point that would make them so, Caprile & Torre 1990) lies farther than this share
#: of the image's width or height from the principal point assumed, by more than
#: ``_PP_SIGNIFICANT`` times the spread that resampling their segments gives it along that
#: axis; the same box bounds the principal point that ``principal_point="estimate"`` takes
#: from them. On York Urban's tuning half, the triplets outside it were those with f off by
#: +7 to +47 % (``benchmarks/results/vp-real-2026-11-29e.md``).
_PP_BOX = 0.2
#: ... the offset must exceed this many times the orthocentre's spread (the half-width of the
#: central 68 % of its coordinate over resamples of the segments, about a standard deviation)
#: along the axis where it leaves the box: an offset that resampling explains is not an
#: inconsistency (OpenCV's left12.jpg, f +3.3 %: 107 px below the centre, ±47 px;
#: ``benchmarks/results/vp-real-2026-11-29f.md``).
_PP_SIGNIFICANT = 3.0
#: ... and the focal length then rests on the two best-supported points alone when the third
#: has at most this share of the second's support (otherwise K is left open).
_PAIR_CLEAR = 0.5
#: ``principal_point="estimate"`` takes the orthocentre only where resampling the points'
#: segments moves it by at most this share of the image's height, and the focal length there
#: by at most ``_K_MAX_SPREAD`` (a point far out, or one near the principal point, leaves
#: them loose: on York Urban's tuning half a triplet with a point 0.2 image diagonal from the
#: centre gave f -13 % at its orthocentre).
_PP_SPREAD = 0.05


def _resampled_points(
    seg: LineSegments, members: list[np.ndarray], far: float, rng: np.random.Generator
) -> list[FloatArray]:
    """Refit each point on ``_N_RESAMPLES`` resamples of its segments: ``(B, 3)`` each.

    A point's supporting segments (``members``, one mask a point) are drawn with
    replacement, each weighted by its length, as the fit weighs them.
    """
    lengths = np.hypot(*(seg.endpoints[:, 1] - seg.endpoints[:, 0]).T)
    lines = seg.lines
    pts = []
    for m in members:
        idx = np.flatnonzero(m)
        n = len(idx)
        counts = rng.multinomial(n, np.full(n, 1.0 / n), size=_N_RESAMPLES).astype(np.float64)
        pts.append(_refit_batch(lines[idx], lengths[idx], counts, far))
    return pts


def _orthocenter_resamples(
    seg: LineSegments, members: list[np.ndarray], far: float, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    """Return three points' orthocentre and ``log f`` there over resamples of their segments.

    Each point's supporting segments are drawn with replacement ``_N_RESAMPLES`` times and
    the point refitted (as :func:`_focal_spread`); returns the resamples' orthocentres
    ``(B, 2)`` (NaN where a point went to infinity or the three became collinear) and
    ``log f`` at each (NaN where the triangle is not acute: no focal length there).
    """
    pts = _resampled_points(seg, members, far, rng)
    found = np.full((_N_RESAMPLES, 2), np.nan)
    focal = np.full(_N_RESAMPLES, np.nan)
    for b in range(_N_RESAMPLES):
        tri = [p[b] for p in pts]
        if any(v[2] == 0 for v in tri):
            continue
        o = _orthocenter(*tri)
        if o is None:
            continue
        found[b] = o
        a = [v[:2] / v[2] - o for v in tri]
        f2 = -np.mean([a[0] @ a[1], a[1] @ a[2], a[0] @ a[2]])
        if f2 > 0:
            focal[b] = 0.5 * math.log(f2)
    return found, focal


def _half_width(x: FloatArray) -> FloatArray:
    """Half the width of the central 68 % of the rows of ``x`` without NaN, per column.

    Infinite where fewer than half of the rows are left (about a standard deviation).
    """
    x = x.reshape(len(x), -1)
    ok = np.all(np.isfinite(x), axis=1)
    if ok.sum() < len(x) // 2:
        return np.full(x.shape[1], math.inf)
    q16, q84 = np.percentile(x[ok], [16.0, 84.0], axis=0)
    return np.asarray((q84 - q16) / 2, dtype=np.float64)


def _orthocenter_spread(
    seg: LineSegments, members: list[np.ndarray], far: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Return how far resampling three points' segments moves their orthocentre and its f.

    Over :func:`_orthocenter_resamples` with an acute triangle: the larger over ``x`` and
    ``y`` of the half-width of the central 68 % of the orthocentre's coordinate (pixels) and
    that of ``log f`` there, or infinities when fewer than half of the resamples have one. A
    point far out, or one near the principal point, leaves them loosely fixed.
    """
    found, focal = _orthocenter_resamples(seg, members, far, rng)
    found[~np.isfinite(focal)] = np.nan
    return float(np.max(_half_width(found))), float(_half_width(focal)[0])


def _orthocenter(a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray | None:
    """Return the orthocentre of the triangle of three finite homogeneous points, or None.

    The intersection of the altitudes from ``a`` (perpendicular to ``c - b``) and from
    ``b`` (perpendicular to ``c - a``): the principal point for which the three points'
    directions are mutually orthogonal (Caprile & Torre 1990; Hartley & Zisserman Example
    8.27), whether or not the triangle is acute. None when the points are collinear.
    """
    p, q, r = (np.asarray(v[:2], dtype=np.float64) / v[2] for v in (a, b, c))
    A = np.array([r - q, r - p])
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    if abs(det) <= 1e-12 * float(np.sum(A * A)):
        return None
    rhs = np.array([(r - q) @ p, (r - p) @ q])
    return np.asarray(np.linalg.solve(A, rhs), dtype=np.float64)


def _spread_text(spread: float, fail: float) -> str:
    """``"±4.1 %"``, or how often no focal length was found at all."""
    if fail > _K_MAX_FAIL or not math.isfinite(spread):
        return f"so far that {100 * fail:.0f} % of the resamples have none"
    return f"±{100 * spread:.1f} %"


#: Resamples of each point's segments for the focal length's spread (:func:`_focal_spread`).
_N_RESAMPLES = 64


def _focal_spread(
    seg: LineSegments,
    members: list[np.ndarray],
    support: list[float],
    pp: FloatArray,
    diag: float,
    far: float,
    rng: np.random.Generator,
) -> tuple[float, float]:
    """Return how far resampling the points' segments moves the focal length.

    Each point's supporting segments are drawn with replacement (``_N_RESAMPLES`` times),
    each point refitted, the focal length refitted to the set; returns the half-width of
    the central 68 % of ``log f`` (about the relative standard deviation of ``f``) and the
    share of resamples with no focal length at all (the fit's minimum at the search's end).
    A point that two or three segments converge on by chance moves far with a resample
    that leaves one out; one that a building's hundred edges converge on does not.
    """
    pts = _resampled_points(seg, members, far, rng)
    f = _focal_grid(np.stack(pts, axis=1), support, pp, diag)
    ok = np.isfinite(f)
    if ok.sum() < 3:
        return math.inf, 1.0 - ok.mean()
    q16, q84 = np.percentile(np.log(f[ok]), [16.0, 84.0])
    return float((q84 - q16) / 2), float(1.0 - ok.mean())


#: The longest focal length (image diagonals; a 35 mm-equivalent 86 mm lens) that
#: :func:`_orthogonal_for_some_f` tries for a set with fewer than two finite points: their
#: orthogonality does not fix ``f``, and at a long enough ``f`` any finite point would pass.
_ONE_FINITE_F = 2.0


#: A point whose segments run nearer the image's columns than its rows (the length-weighted
#: mean |cos| of their angle to the columns at least cos 45°) can be the vertical direction.
_UPRIGHT = math.cos(math.radians(45.0))


def _orthogonal_for_some_f(
    vps: list[FloatArray], pp: FloatArray, diag: float, far: float, tol: float
) -> bool:
    """Whether some focal length makes the points' directions pairwise orthogonal within tol.

    A set of vanishing points belongs to orthogonal scene directions only if, for some focal
    length ``f`` (square pixels, zero skew, principal point ``pp``), every pair of
    directions ``K⁻¹ vᵢ`` is within ``tol`` (radians) of perpendicular (Hartley &
    Zisserman §8.8: ``vᵢᵀ ω vⱼ = 0``). This is the check the focal-length fit of
    :func:`_manhattan_K` makes, for the sets it cannot fit: with fewer than two finite
    points ``f`` is not determined, but the set still has to be orthogonal: two points at
    infinity need perpendicular image directions (three never are), a finite point with
    points at infinity needs ``(v - p) ⟂ d`` (and, with two of them, ``v`` at ``p``: the
    optical axis) up to ``tol``, at a focal length up to ``_ONE_FINITE_F`` image diagonals.
    With two finite points it refuses a pair with ``(v₁ - p)·(v₂ - p) > 0`` (an acute angle
    at ``p``: no ``f`` makes them orthogonal). ``f`` is searched log-spaced from 0.15 image
    diagonals (to 10 with two finite points, the range of the fit); points beyond ``far``
    count as at infinity.
    """
    pts = []
    for v in vps:
        v = np.asarray(v, dtype=np.float64)
        pts.append(v if _is_finite(v, pp, far) else np.array([v[0], v[1], 0.0]))
    longest = 10.0 if sum(p[2] != 0 for p in pts) >= 2 else _ONE_FINITE_F
    f = np.exp(np.linspace(math.log(0.15 * diag), math.log(longest * diag), 241))
    d = _directions(pts, pp, f)  # (F, M, 3)
    worst = np.zeros(len(f))
    for i, j in itertools.combinations(range(len(pts)), 2):
        worst = np.maximum(worst, np.abs(np.einsum("fk,fk->f", d[:, i], d[:, j])))
    return bool(worst.min() <= math.sin(tol))


def _join(p: FloatArray, q: FloatArray, normal: FloatArray) -> tuple[FloatArray, float] | None:
    """Return the line through points ``p`` and ``q`` and its cosine to ``normal``.

    The line ``p x q`` scaled to a unit normal and turned so that its normal points along
    ``normal`` (a unit vector), with that normal's dot product with ``normal``; None when
    the points coincide (no line).
    """
    join = np.cross(p, q)
    n = math.hypot(join[0], join[1])
    if n == 0:
        return None
    join = np.asarray(join / n, dtype=np.float64)
    c = float(join[:2] @ normal)
    return (join, c) if c >= 0 else (-join, -c)


def _level_horizon(
    vps: FloatArray, vertical: int, pp: FloatArray, far: float, scores: FloatArray
) -> FloatArray | None:
    """Return the horizon without K, from the vertical point and the horizontal ones.

    The horizon is the polar of the vertical point under the image of the absolute conic,
    ``l ~ K⁻ᵀ d`` for the vertical direction ``d``; with square pixels and zero skew its
    normal is parallel to ``v - p`` (the vertical point seen from the principal point ``p``)
    whatever the focal length, and for a vertical point at infinity in image direction
    ``d``, to ``d``. Only its offset needs f, and a finite horizontal point fixes that, as
    the horizontal points lie on the horizon: the wall seen by a level camera (verticals
    and one horizontal direction), a building whose K was left open. With two horizontal
    points, their join when its normal is within 5 degrees of ``v - p`` (None when not: the
    points do not belong together). The second may lie at infinity or beyond ``far``: the
    join is then the line through the finite one along the other's direction (as with K,
    :func:`_anchor_horizon`), taken when that point's segments (``scores``, their total
    length) outweigh the vertical point's and the join is within 5 degrees of ``v - p``:
    the horizon's direction then rests on the better-supported of the two directions (the
    simulator's railway: posts 0.3 image diagonal long put the vertical point 0.51 degree
    off the column through ``p``; the sleepers' far point, 3.2 diagonals, 0.16). Otherwise
    the finite point alone fixes the offset.
    A point too weak to fix a focal length still fixes the horizon's offset. A finite
    vertical point must lie above or below the frame, nearer the column through ``p`` than
    the row (a railway's rails run steeply towards a point on the horizon, inside the frame).
    """
    v = vps[vertical]
    d = v[:2] - pp * v[2]
    nd = math.hypot(d[0], d[1])
    finite = [p for i, p in enumerate(vps) if i != vertical and _is_finite(p, pp, far)]
    others = [i for i in range(len(vps)) if i != vertical and not _is_finite(vps[i], pp, far)]
    if nd == 0 or not finite:
        return None
    if v[2] != 0 and (abs(d[1]) < abs(d[0]) or abs(d[1]) < pp[1] + 1.0):
        # a finite "vertical" point beside the principal point or inside the frame's rows
        # is a horizontal direction whose segments run steeply (a railway's two rails)
        return None
    a, b = d / nd
    if b < 0:
        a, b = -a, -b
    level = math.cos(math.radians(5.0))
    if len(finite) == 2:
        j = _join(finite[0], finite[1], np.array([a, b]))
        if j is None or j[1] < level:
            return None
        return j[0] if j[0][1] > 0 else -j[0]
    if len(others) == 1 and scores[others[0]] > scores[vertical]:
        j = _join(finite[0], vps[others[0]], np.array([a, b]))
        if j is not None and j[1] >= level:
            return j[0] if j[0][1] > 0 else -j[0]
    u, w = finite[0][0] / finite[0][2], finite[0][1] / finite[0][2]
    return np.array([a, b, -(a * u + b * w)])


#: The visible horizon of a level camera (:func:`_visible_horizon`): its segments within this
#: angle of the image rows, within this distance of one line (pixels, at least; or this share
#: of the diagonal), spanning at least this share of the image width.
_SEA_TILT = math.radians(15.0)
_SEA_TOL, _SEA_TOL_DIAG = 1.5, 0.002
_SEA_SPAN = 0.6
#: ... and whose segments cover at least this share of the width, and half the best run's.
_SEA_COVER = 0.2
#: Only where the near-vertical segments (within ``_SEA_TILT`` of the columns) add up to at
#: most this share of the near-horizontal ones' length: open water shows no verticals.
_SEA_VERTICAL = 0.25
#: Segments within this share of the height from the frame's top or bottom are left out.
_SEA_EDGE = 0.01


def _visible_horizon(
    seg: LineSegments, members: np.ndarray, width: int, height: int
) -> FloatArray | None:
    """Return the horizon seen as a line in the image (a sea or lake horizon), or None.

    A level camera over open water sees one horizontal direction (the horizon, the wave
    crests, parallel in the image: their point at infinity) and no vertical one, so no
    vanishing point gives the horizon; but the horizon is in the picture: the farthest
    water meets the sky along the image line ``v = c_y - f tan(pitch)`` (rolled with the
    camera), which is the vanishing line of the water plane itself, and all of the water is
    below it. So it is the highest collinear run of the near-horizontal ``members`` segments
    (within ``_SEA_TILT`` of the rows, all endpoints within ``_SEA_TOL`` px of one line,
    refitted by total least squares on the endpoints weighted by length) that spans
    ``_SEA_SPAN`` of the image width and whose segments cover ``_SEA_COVER`` of it and
    half of what the best-covered run covers (wave crests nearer the camera can span the
    width too, lower down; chance alignments of clutter cover little of it). The runs are
    grown from the ten longest segments. Only where the near-vertical segments add up to at
    most ``_SEA_VERTICAL`` of the near-horizontal ones: a facade seen square on (verticals
    and horizontals both parallel in the image) has long horizontal runs too, and its
    horizon is not one of them.
    """
    every = seg.endpoints[:, 1] - seg.endpoints[:, 0]
    size = np.hypot(every[:, 0], every[:, 1])
    steep = np.abs(every[:, 0]) <= np.tan(_SEA_TILT) * np.abs(every[:, 1])
    level = np.abs(every[:, 1]) <= np.tan(_SEA_TILT) * np.abs(every[:, 0])
    if size[steep].sum() > _SEA_VERTICAL * size[level].sum():
        return None  # a built scene (a facade seen square on): its lines are not a horizon
    ends = seg.endpoints[members]
    d = ends[:, 1] - ends[:, 0]
    length = np.hypot(d[:, 0], d[:, 1])
    flat = np.abs(d[:, 1]) <= np.tan(_SEA_TILT) * np.abs(d[:, 0])
    # the frame's own top and bottom edges (a scanned or letterboxed frame) are no horizon
    edge = max(3.0, _SEA_EDGE * height)
    flat &= ~np.all(ends[..., 1] < edge, axis=1) & ~np.all(ends[..., 1] > height - 1 - edge, axis=1)
    ends, d, length = ends[flat], d[flat], length[flat]
    if len(ends) == 0:
        return None
    tol = max(_SEA_TOL, _SEA_TOL_DIAG * math.hypot(width, height))
    runs: list[tuple[float, float, FloatArray]] = []  # (row at the centre, coverage, line)
    for i in np.argsort(-length)[:10]:
        line = np.asarray(seg.lines[members][flat][i], dtype=np.float64)
        for _ in range(2):
            n = line[:2] / math.hypot(line[0], line[1])
            off = line[2] / math.hypot(line[0], line[1])
            dist = np.abs(ends @ n + off)  # (k, 2)
            group = np.all(dist <= tol, axis=1)
            pts = ends[group].reshape(-1, 2)
            wts = np.repeat(length[group], 2)
            mean = (wts[:, None] * pts).sum(0) / wts.sum()
            cov = ((pts - mean) * wts[:, None]).T @ (pts - mean)
            normal = np.linalg.eigh(cov)[1][:, 0]
            line = np.array([normal[0], normal[1], -(normal @ mean)])
        along = pts @ np.array([-line[1], line[0]])
        if along.max() - along.min() >= _SEA_SPAN * width and abs(line[1]) > 0:
            row = -(line[0] * (width - 1) / 2 + line[2]) / line[1]
            runs.append((float(row), float(length[group].sum()), line))
    if not runs:
        return None
    need = max(_SEA_COVER * width, 0.5 * max(r[1] for r in runs))
    covered = [r for r in runs if r[1] >= need]
    if not covered:
        return None
    top = min(covered, key=lambda r: r[0])[2]
    sign = -1.0 if top[1] < 0 else 1.0
    return np.asarray(sign * top / math.hypot(top[0], top[1]), dtype=np.float64)


def _anchor_horizon(line: FloatArray, horizontal: list[FloatArray]) -> FloatArray:
    """Put the horizon through the horizontal vanishing points themselves.

    ``line`` is the horizon from K (``K⁻ᵀ up``), which moves with any error of K's principal
    point (a principal point assumed at the centre but 12 px below it moves the horizon 12
    px). The horizontal points lie on the horizon whatever K is: through two of them the
    horizon is their join; through one (finite) it keeps ``line``'s direction. A join more
    than 10 degrees from ``line`` (points that do not belong together) is not used.
    """
    if len(horizontal) >= 2:
        j = _join(horizontal[0], horizontal[1], line[:2])
        if j is not None and j[1] > math.cos(math.radians(10.0)):
            return j[0]
    finite = [v for v in horizontal if v[2] != 0]
    if len(finite) == 1:
        u, v = finite[0][0] / finite[0][2], finite[0][1] / finite[0][2]
        return np.array([line[0], line[1], -(line[0] * u + line[1] * v)])
    return line


def _horizon_with_K(K: FloatArray, vps: FloatArray) -> tuple[int | None, FloatArray]:
    """Return the vertical point's index (None: both points horizontal) and the horizon.

    The vertical direction is the one of ``K⁻¹ vᵢ`` (with two points, and their cross
    product, the third Manhattan direction) nearest the image's y axis; the horizon is
    ``K⁻ᵀ up`` put through the horizontal points (:func:`_anchor_horizon`).
    """
    dirs = np.linalg.solve(K, vps.T).T
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    cand = dirs
    if len(dirs) == 2:  # the third Manhattan direction, which no detected point shows
        third = np.cross(dirs[0], dirs[1])
        cand = np.vstack([dirs, third / np.linalg.norm(third)])
    k = int(np.argmax(np.abs(cand[:, 1])))
    vertical = k if k < len(vps) else None  # None: both points are horizontal
    up = cand[k] * (-1.0 if cand[k, 1] > 0 else 1.0)  # image up is -y
    horizon = _anchor_horizon(
        np.asarray(horizon_line(K, None, up)), [vps[i] for i in range(len(vps)) if i != k]
    )
    return vertical, horizon


def _horizons_with_K(pp: FloatArray, focal: FloatArray, pts: FloatArray) -> FloatArray:
    """:func:`_horizon_with_K` for ``B`` sets of points ``(B, M, 3)``, vectorised: ``(B, 3)``.

    K has square pixels, zero skew, the principal point ``pp`` and the focal lengths
    ``focal`` ``(B,)``; ``K⁻¹ v`` and ``K⁻ᵀ up`` in closed form. NaN rows where ``focal``
    is NaN.
    """
    px, py = float(pp[0]), float(pp[1])
    f = focal[:, None]
    B, M = pts.shape[:2]
    dirs = np.stack(
        [
            (pts[..., 0] - px * pts[..., 2]) / f,
            (pts[..., 1] - py * pts[..., 2]) / f,
            pts[..., 2],
        ],
        axis=-1,
    )
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    cand = dirs
    if M == 2:
        third = np.cross(dirs[:, 0], dirs[:, 1])
        third /= np.linalg.norm(third, axis=-1, keepdims=True)
        cand = np.concatenate([dirs, third[:, None]], axis=1)
    with np.errstate(invalid="ignore"):
        k = np.argmax(np.nan_to_num(np.abs(cand[..., 1]), nan=-1.0), axis=1)
    up = cand[np.arange(B), k]
    up *= np.where(up[:, 1] > 0, -1.0, 1.0)[:, None]
    line = np.stack(
        [up[:, 0] / focal, up[:, 1] / focal, up[:, 2] - (px * up[:, 0] + py * up[:, 1]) / focal],
        axis=-1,
    )
    line /= np.hypot(line[:, 0], line[:, 1])[:, None]
    out = line.copy()
    level = math.cos(math.radians(10.0))
    for kk in np.unique(k):
        rows = np.flatnonzero(k == kk)
        horiz = [i for i in range(M) if i != kk]
        done = np.zeros(len(rows), dtype=bool)
        if len(horiz) >= 2:  # the join of two horizontal points, within 10 degrees
            j = np.cross(pts[rows, horiz[0]], pts[rows, horiz[1]])
            n = np.hypot(j[:, 0], j[:, 1])
            with np.errstate(invalid="ignore", divide="ignore"):
                j /= n[:, None]
                c = np.einsum("bk,bk->b", j[:, :2], line[rows, :2])
            j *= np.where(c < 0, -1.0, 1.0)[:, None]
            done = (n > 0) & (np.abs(c) > level)
            out[rows[done]] = j[done]
        hp = pts[rows][:, horiz]  # (b, H, 3)
        finite = hp[..., 2] != 0
        one = ~done & (finite.sum(axis=1) == 1)
        if one.any():
            which = np.argmax(finite[one], axis=1)
            v = hp[one][np.arange(int(one.sum())), which]
            u, w = v[:, 0] / v[:, 2], v[:, 1] / v[:, 2]
            a, b = line[rows[one], 0], line[rows[one], 1]
            out[rows[one]] = np.stack([a, b, -(a * u + b * w)], axis=-1)
    return out


def _horizon_spread(
    seg: LineSegments,
    members: list[np.ndarray],
    fixing: list[int],
    support: list[float],
    K: FloatArray | None,
    vertical: int | None,
    pp: FloatArray,
    size: tuple[int, int],
    diag: float,
    far: float,
    rng: np.random.Generator,
) -> float:
    """Return how far resampling the points' segments moves the horizon (share of the height).

    Each point's segments are drawn with replacement ``_N_RESAMPLES`` times and the point
    refitted (:func:`_resampled_points`, as for the focal length's spread); with ``K``, the
    focal length is refitted to the points at ``fixing`` (principal point kept,
    :func:`_focal_grid`, within a factor 1.65 of K's) and the horizon is
    :func:`_horizon_with_K`'s (:func:`_horizons_with_K`); without, the
    level camera's (:func:`_level_horizon`, the vertical point kept). Returns the larger,
    over the image's first and last columns, of the half-width of the central 68 % of the
    horizon's row there, over the height; ``inf`` when fewer than half the resamples give
    a horizon. It costs a median 4 % of the call on York Urban's photographs, 640 x 480
    (``benchmarks/results/vp-stress-2026-12-01g.md``).
    """
    w, h = size
    sup = np.asarray(support, dtype=np.float64)
    pts = np.stack(_resampled_points(seg, members, far, rng), axis=1)  # (B, M, 3)
    focal = np.full(len(pts), np.nan)
    if K is not None and len(fixing) >= 2:
        sub = [support[i] for i in fixing]
        focal = _focal_grid(pts[:, fixing], sub, K[:2, 2], diag, near=float(K[0, 0]))
    if K is not None:
        lines = _horizons_with_K(K[:2, 2], focal, pts)
    else:
        lines = np.full((len(pts), 3), np.nan)
        for b, vps in enumerate(pts):
            line = None if vertical is None else _level_horizon(vps, vertical, pp, far, sup)
            if line is not None:
                lines[b] = line
    with np.errstate(invalid="ignore", divide="ignore"):
        den = np.where(np.abs(lines[:, 1]) > 1e-12, lines[:, 1], np.nan)
        rows = np.stack([-lines[:, 2] / den, -(lines[:, 0] * (w - 1) + lines[:, 2]) / den], axis=-1)
    return float(np.max(_half_width(rows))) / h


def _principal_point(value: str | ArrayLike) -> tuple[str, FloatArray | None]:
    """``("center" | "orthocenter" | "estimate" | "given", position or None)`` from the argument.

    ``"centre"`` and ``"orthocentre"`` are deprecated spellings (a DeprecationWarning).
    """
    if isinstance(value, str):
        if value in ("centre", "orthocentre"):
            new = value.replace("centre", "center")
            _deprecate.warn(
                f"principal_point={value!r}", f"use principal_point={new!r}", stacklevel=5
            )
            value = new
        if value in ("center", "orthocenter", "estimate"):
            return value, None
        raise InvalidInputError(
            f"unknown principal_point {describe(value)}; valid: 'center', 'estimate', "
            "'orthocenter' or (u, v)"
        )
    try:
        pp = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(
            "expected principal_point 'center', 'estimate', 'orthocenter' or (u, v), got "
            + describe(value)
        ) from None
    if pp.shape != (2,) or not np.all(np.isfinite(pp)):
        raise InvalidInputError(
            f"expected principal_point as two finite numbers (u, v), got shape {pp.shape}"
        )
    return "given", pp


def _triplet_K(
    vps: list[FloatArray], centre: FloatArray, diag: float, far: float
) -> FloatArray | None:
    finite = [v for v in vps if _is_finite(v, centre, far)]
    try:
        if len(finite) == 3:
            K = intrinsics_from_vanishing_points(*finite)
        elif len(finite) == 2:
            f = float(focal_from_vanishing_points(finite[0], finite[1], centre))
            K = np.array([[f, 0, centre[0]], [0, f, centre[1]], [0, 0, 1.0]])
        else:
            return None
    except DegenerateConfigurationError:
        return None
    f = K[0, 0]
    if not (0.15 * diag <= f <= 10 * diag) or np.hypot(*(K[:2, 2] - centre)) > 0.3 * diag:
        return None
    return K


def _check_triplet(
    cands: list[tuple[FloatArray, np.ndarray, float]],
    fixing: list[int],
    K: FloatArray,
    pp: FloatArray,
    size: tuple[int, int],
    diag: float,
    far: float,
    tol: float,
    seg: LineSegments,
    rng: np.random.Generator,
    estimate: bool,
) -> tuple[FloatArray | None, list[int], str | None, str | None]:
    """Check three finite points that fix K against their orthocentre.

    Returns ``(K, fixing, note, reason)``. With the principal point ``p`` fixed, each pair
    of finite orthogonal points gives ``f² = -(vᵢ - p)·(vⱼ - p)``, and the three estimates
    agree only when ``p`` is the triangle's orthocentre (Caprile & Torre 1990). A
    least-squares ``f`` over the three pairs always exists; the orthocentre says whether the
    points can be orthogonal at all for a principal point near ``p``: where it lies outside
    the box of ``_PP_BOX`` of the image's width and height around ``p`` along an axis, by
    more than ``_PP_SIGNIFICANT`` times the spread that resampling the segments (``seg``,
    ``rng``) gives it along that axis, they are not (two facades at 71 degrees, or a point
    from clutter). The focal length then rests on the two best-supported points alone, when
    the third has at most ``_PAIR_CLEAR`` of the second's support (``note`` says so), or
    ``K`` is None with ``reason``. With ``estimate`` and an orthocentre inside the box that
    resampling moves little, ``K`` takes it as its principal point (``f`` the root of the
    mean of the three estimates); otherwise ``note`` says why the principal point stays at
    ``p``.
    """
    w, h = size
    tri = [i for i in fixing if _is_finite(cands[i][0], pp, far)]
    if len(tri) < 3:
        note = (
            f"the principal point is the image centre: estimating it needs three finite, "
            f"well-supported vanishing points, and {len(tri)} fix K here"
            if estimate
            else None
        )
        return K, fixing, note, None
    o = _orthocenter(*(cands[i][0] for i in tri))
    members = [cands[i][1] for i in tri]
    box = _PP_BOX * np.array([w, h], dtype=np.float64)
    inside = o is not None and bool(np.all(np.abs(o - pp) <= box))
    spread = np.full(2, math.inf)
    if o is not None and not inside:
        # outside the box: an inconsistency only where resampling does not explain it
        spread = _half_width(_orthocenter_resamples(seg, members, far, copy.deepcopy(rng))[0])
        off = np.abs(o - pp)
        if not np.any((off > box) & (off > _PP_SIGNIFICANT * spread)):
            note = None
            if estimate:
                note = (
                    f"the principal point is the image centre: the points' orthocentre "
                    f"({o[0]:.0f}, {o[1]:.0f}) is more than {100 * _PP_BOX:.0f} % of the "
                    f"image's width or height from it"
                )
            return K, fixing, note, None
    if inside:
        if not estimate:
            return K, fixing, None, None
        loose, loose_f = _orthocenter_spread(seg, members, far, rng)
        if loose > _PP_SPREAD * min(w, h) or loose_f > _K_MAX_SPREAD:
            note = (
                f"the principal point is the image centre: resampling the points' segments "
                f"moves their orthocentre by ±{loose:.0f} px and the focal length there by "
                f"±{100 * loose_f:.1f} % (at most {100 * _PP_SPREAD:g} % of the image's "
                f"height and {100 * _K_MAX_SPREAD:g} %)"
            )
            return K, fixing, note, None
        try:
            Ko = np.asarray(intrinsics_from_vanishing_points(*(cands[i][0] for i in tri)))
        except DegenerateConfigurationError:
            note = (
                "the principal point is the image centre: the three points' triangle is not "
                "acute (no focal length at their orthocentre)"
            )
            return K, fixing, note, None
        return Ko, fixing, None, None
    where = (
        "their orthocentre is at infinity (collinear points)"
        if o is None
        else (
            f"their orthocentre ({o[0]:.0f}, {o[1]:.0f}) is {o[0] - pp[0]:+.0f}, "
            f"{o[1] - pp[1]:+.0f} px from the principal point, more than "
            f"{100 * _PP_BOX:.0f} % of the image's width or height and {_PP_SIGNIFICANT:g} "
            f"times what resampling the segments moves it by (±{spread[0]:.0f}, "
            f"±{spread[1]:.0f} px)"
        )
    )
    ranked = sorted(tri, key=lambda i: -cands[i][2])
    if cands[ranked[2]][2] > _PAIR_CLEAR * cands[ranked[1]][2]:
        reason = (
            f"not determined: the three finite vanishing points are not mutually orthogonal "
            f"({where}), and no pair of them is clearly better supported than the others"
        )
        return None, fixing, None, reason
    pair = [i for i in fixing if i != ranked[2]]
    K2 = _manhattan_K([cands[i][0] for i in pair], [cands[i][2] for i in pair], pp, diag, far, tol)
    if K2 is None:
        reason = (
            f"not determined: the three finite vanishing points are not mutually orthogonal "
            f"({where}), and the two best-supported ones give no focal length"
        )
        return None, fixing, None, reason
    note = (
        f"f from the two best-supported points alone: the three finite points are not "
        f"mutually orthogonal ({where})"
    )
    if estimate:
        note += "; the principal point is the image centre"
    return K2, pair, note, None


@_deprecate.parameters(renamed={"seed": "rng", "iterations": "max_trials"})
def detect_vanishing_points(
    image: ArrayLike | None = None,
    *,
    segments: LineSegments | None = None,
    image_size: tuple[int, int] | None = None,
    angle_threshold: float = math.radians(2.0),
    n_candidates: int = 6,
    max_trials: int = 600,
    infinity_factor: float = 20.0,
    rng: RNGLike = 0,
    principal_point: str | ArrayLike = "center",
    orthogonality_tolerance: float = math.radians(3.5),
    max_size: int | None = None,
) -> VanishingPointResult:
    """Find the vanishing points of a photograph, its orthogonal triplet, K and the horizon.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3), optional
        The photograph (segments are detected with default settings).
    segments : LineSegments, optional
        Pre-detected segments instead of ``image`` (then ``image_size=(W, H)`` is needed).
    image_size : (int, int), optional
        ``(width, height)`` of the photograph the ``segments`` come from.
    angle_threshold : float
        A segment supports a vanishing point when the line from its midpoint to the point is
        within this angle of the segment (radians).
    n_candidates : int
        How many vanishing points sequential RANSAC extracts before the triplet search.
    max_trials : int
        RANSAC hypotheses per candidate (``iterations`` is its deprecated name).
    infinity_factor : float
        A point farther than this many image diagonals from the centre counts as at infinity.
    rng : int, numpy.random.Generator or None
        RANSAC's random source (SPEC 7): an int seeds a new Generator (reproducible by
        default, ``rng=0``), a Generator is used as is, None draws fresh entropy.
    principal_point : {"center", "estimate", "orthocenter"} or (u, v)
        Where K's principal point is: the image centre (default), the given pixel position
        (a calibrated camera's), ``"estimate"``: the orthocentre of three finite,
        well-supported, mutually consistent vanishing points where it lies within 20 % of
        the image's size of the centre and resampling the segments moves it and the focal
        length there little, the centre otherwise (``K_note`` says why), or
        ``"orthocenter"``: the orthocentre of any three finite points (Caprile & Torre 1990,
        unguarded; unstable on real photographs, see the module docstring). With a fixed
        principal point, the focal length is the one that makes the chosen points'
        directions most nearly orthogonal; three finite points whose orthocentre lies
        farther than 20 % of the image's width or height from it, by more than 3 times
        what resampling the segments moves it by along that axis, are not taken as
        orthogonal (f from the best-supported pair, or no K).
    orthogonality_tolerance : float
        With a fixed principal point: a set of vanishing points whose directions stay
        farther than this from orthogonal (radians) is not taken as a Manhattan set.
    max_size : int, optional
        With ``image``: detect the segments on a copy whose long side is at most this many
        pixels (Gaussian pre-filter σ = 0.5 / scale, then linear interpolation), scaled back
        to the image's pixels; everything else (K, the horizon) is in the image's pixels.
        None (default): the image as given. On 58 photographs enlarged two times, 18 got a
        K rather than 27 at their own size, 22 with ``max_size=1600``; on 103 held-out 6 Mpx
        photographs, ``max_size=1600`` gave K for 88 and none off by more than 20 % (95 and
        5 without; ``benchmarks/results/vp-fresh-2026-11-30g.md``).

    Returns
    -------
    VanishingPointResult
        The orthogonal triplet (or pair), the segments' labels, K when two or more of the
        points are finite, the vertical point and the horizon. An image with no vanishing
        point to find (fewer than two line segments, a flat image, segments that support no
        common point) is not an error: ``vanishing_points`` is then ``(0, 3)``, ``scores``
        ``(0,)``, every label -1, ``K``, ``vertical`` and ``horizon`` None and
        ``perspective`` 0.

    Notes
    -----
    Measured on real photographs (``benchmarks/check_vp_real.py``): OpenCV's 13 checkerboard
    views (``left*.jpg``, undistorted with their published calibration, f = 536 px; the
    board's two directions and the room's), median focal-length error 6.5 % with the
    default principal point at the centre (11 of 13 views given K, a view without K counting
    as infinite), 6.3 % with ``"estimate"``, 2.4 % given the calibrated one, 129 % with the
    orthocentre. On York Urban's held-out frames (51, f known): 3.4 % at the centre, 3.0 %
    with ``"estimate"`` (``benchmarks/results/vp-real-2026-11-29f.md``). On the same
    held-out frames degraded (``benchmarks/results/vp-stress-2026-12-01g.md``), the
    low-contrast stretch takes the horizon within 2 % of the height from 0 to 20 of 51 at a
    20th of the contrast (the original: 19) and from 9 to 22 at a tenth of the brightness, f
    within 5 % from 0 to 24 and from 2 to 27 (the original: 25); versions not stretched are
    unchanged.

    Raises
    ------
    InvalidInputError
        If neither or both of ``image`` and ``segments`` are given, or an option is out of
        range.

    Examples
    --------
    >>> import numpy as np
    >>> res = detect_vanishing_points(np.full((120, 160), 0.5))  # a flat image: no lines
    >>> res.vanishing_points.shape, len(res.segments), res.K, res.horizon, res.perspective
    ((0, 3), 0, None, None, 0)
    """
    if (image is None) == (segments is None):
        raise InvalidInputError("give either an image or segments (with image_size)")
    if max_size is not None:
        max_size = as_int(max_size, "max_size", minimum=16, maximum=10**6)
    if segments is None:
        arr = np.asarray(image)
        if arr.ndim not in (2, 3):
            raise InvalidInputError(f"expected an (H, W) or (H, W, 3) image, got {arr.shape}")
        image_size = (arr.shape[1], arr.shape[0])
        # a hazy, dim or underexposed photograph's edges fall below LSD's gradient threshold
        segments = _segments_within(_stretch_low_contrast(arr), max_size)
    elif image_size is None:
        raise InvalidInputError("segments need image_size=(width, height)")
    elif not isinstance(segments, LineSegments):
        raise TypeError(
            "expected segments as a LineSegments (from detect_line_segments), got "
            + describe(segments)
        )
    image_size = check_image_size(image_size)
    angle_threshold = check_positive(angle_threshold, "angle_threshold")
    n_candidates = as_int(n_candidates, "n_candidates", minimum=1, maximum=1000)
    max_trials = as_int(max_trials, "max_trials", minimum=1, maximum=10**7)
    infinity_factor = as_real(infinity_factor, "infinity_factor", positive=True, maximum=1e50)
    tol = as_real(orthogonality_tolerance, "orthogonality_tolerance", positive=True, maximum=1.5)
    pp_mode, pp_given = _principal_point(principal_point)
    w, h = image_size
    centre = np.array([(w - 1) / 2, (h - 1) / 2])
    pp = centre if pp_given is None else pp_given
    diag = math.hypot(w, h)
    far = infinity_factor * diag
    gen = as_rng(check_rng(rng))
    cands = _ransac_candidates(segments, gen, n_candidates, angle_threshold, max_trials)
    cands = [(_normalise(v, far), inl, sc) for v, inl, sc in cands]
    best: tuple[float, tuple[int, ...], FloatArray | None] = (-1.0, (), None)
    # the set holds the best-supported point (a scene's dominant direction is one of its
    # Manhattan directions): sets of weak points only are where chance alignments agree
    support = [c[2] for c in cands]
    top = int(np.argmax(support)) if cands else -1
    ranked = np.argsort(support, kind="stable")[::-1].tolist()
    first_two = tuple(sorted(ranked[:2]))
    # how near the image's columns each point's segments run (length-weighted mean |cos|)
    span = segments.endpoints[:, 1] - segments.endpoints[:, 0]
    size = np.hypot(span[:, 0], span[:, 1])
    upright = [float(np.abs(span[c[1], 1]).sum() / max(size[c[1]].sum(), 1e-300)) for c in cands]
    weak = [c[2] < _K_MIN_SUPPORT * diag or int(c[1].sum()) < _K_MIN_SEGMENTS for c in cands]
    skipped_weak = False
    for r in (3, 2):
        for combo in itertools.combinations(range(len(cands)), r):
            if top not in combo:
                continue
            if r == 2 and combo != first_two and max(upright[i] for i in combo) < _UPRIGHT:
                # a pair past the second-best point holds a vertical direction: two
                # horizontal ones orthogonal by chance are common in clutter (sand ripples)
                continue
            trial = [cands[i][0] for i in combo]
            if pp_mode == "orthocenter":
                K = _triplet_K(trial, centre, diag, far) if r == 3 else None
            else:
                K = _manhattan_K(trial, [cands[i][2] for i in combo], pp, diag, far, tol)
            if (
                r == 3
                and K is None
                and (pp_mode == "orthocenter" or sum(_is_finite(v, pp, far) for v in trial) >= 2)
            ):
                continue  # fitted and refused (or not fitted: the orthocentre needs three)
            if K is None and (
                combo != tuple(sorted(ranked[:r]))
                or not _orthogonal_for_some_f(trial, pp, diag, far, tol)
            ):
                # no focal length makes these directions orthogonal; or, with none fitted,
                # they are not the best-supported points (a loose check: f is unknown)
                continue
            score = sum(cands[i][2] for i in combo)
            if score > best[0]:
                best = (score, combo, K)
        if best[1]:
            break
    combo, K = best[1], best[2]
    if not combo:  # no orthogonal set: the two best-supported points, without K
        combo = tuple(sorted(np.argsort([-c[2] for c in cands], kind="stable")[:2].tolist()))
    vps = np.array([cands[i][0] for i in combo]) if combo else np.zeros((0, 3))
    scores = np.array([cands[i][2] for i in combo])
    labels = np.full(len(segments), -1, dtype=np.int64)
    for j, i in enumerate(combo):
        labels[cands[i][1] & (labels < 0)] = j
    fixing = list(combo)
    if K is not None and any(weak[i] and _is_finite(cands[i][0], pp, far) for i in combo):
        # a point too weakly supported to fix a focal length is kept in the set but left
        # out of the fit (a corridor's third point, met by nine segments at half size,
        # moved f by +78 %): f from the well-supported points, if they fix one
        fixing = [i for i in combo if not weak[i]]
        K = None
        if pp_mode != "orthocenter" and sum(_is_finite(cands[i][0], pp, far) for i in fixing) >= 2:
            K = _manhattan_K(
                [cands[i][0] for i in fixing], [cands[i][2] for i in fixing], pp, diag, far, tol
            )
        skipped_weak = K is None
    note: str | None = None
    refused: str | None = None
    if K is not None and pp_mode != "orthocenter":
        K, fixing, note, refused = _check_triplet(
            cands,
            fixing,
            K,
            pp,
            (w, h),
            diag,
            far,
            tol,
            segments,
            # a copy of the generator: the focal length's resamples draw as without it
            copy.deepcopy(gen),
            pp_mode == "estimate",
        )
    reason: str | None = refused
    spread: float | None = None
    if K is not None:
        members = [cands[i][1] for i in fixing]
        spread, fail = _focal_spread(
            segments, members, [cands[i][2] for i in fixing], K[:2, 2], diag, far, gen
        )
        ratio = float(K[0, 0]) / diag
        if fail > _K_MAX_FAIL or spread > _K_MAX_SPREAD:
            reason = (
                f"not determined: resampling the vanishing points' segments moves the focal "
                f"length by {_spread_text(spread, fail)} (more than "
                f"{100 * _K_MAX_SPREAD:.1f} %): the points converge too loosely to fix it "
                f"(f would be {K[0, 0]:.0f} px)"
            )
        elif not _F_PLAUSIBLE[0] <= ratio <= _F_PLAUSIBLE[1]:
            reason = (
                f"not determined: f = {K[0, 0]:.0f} px is {ratio:.2f} image diagonals, outside "
                f"{_F_PLAUSIBLE[0]}-{_F_PLAUSIBLE[1]} (a 13-260 mm-equivalent lens)"
            )
        if reason is not None:
            K = None
    elif refused is not None:
        pass
    elif not combo:
        reason = "not determined: no vanishing points"
    elif sum(_is_finite(v, pp, far) for v in vps) < 2:
        reason = (
            "not determined: fewer than two of the points are finite (one-point perspective, "
            "or verticals parallel with one horizontal direction): the focal length is open"
        )
    elif skipped_weak:
        reason = (
            f"not determined: the points that would fix it are weakly supported (fewer than "
            f"{_K_MIN_SEGMENTS} segments or less than {_K_MIN_SUPPORT:g} image diagonal of "
            f"them): chance convergences in texture fix some f whatever the scene"
        )
    else:
        reason = (
            "not determined: no focal length makes the points found orthogonal (not a "
            "Manhattan scene?)"
        )
    vertical: int | None = None
    horizon: FloatArray | None = None
    tilt: list[float] = []
    if K is not None and len(vps):
        vertical, horizon = _horizon_with_K(K, vps)
    elif len(vps) >= 2:
        # without K: the vertical point is the one whose segments are most in line with the
        # image's columns (length-weighted mean |cos| of their angle to the columns). The
        # direction from the image centre to the point says the same for a point far
        # from the centre, nothing for one near it: the central point of a hall, just
        # above the centre, was taken for the vertical one of a rolled camera.
        ends = segments.endpoints[:, 1] - segments.endpoints[:, 0]
        size = np.hypot(ends[:, 0], ends[:, 1])
        for j, v in enumerate(vps):
            mine = labels == j
            if size[mine].sum() > 0:
                tilt.append(float(np.abs(ends[mine, 1]).sum() / size[mine].sum()))
            else:
                d = v[:2] - centre * v[2]
                tilt.append(abs(d[1]) / max(np.hypot(*d), 1e-300))
        vertical = int(np.argmax(tilt))
        if tilt[vertical] < _UPRIGHT:
            vertical = None  # no point's segments run nearer the columns than the rows
        else:
            horizon = _level_horizon(vps, vertical, pp, far, scores)
    horizon_spread: float | None = None
    if horizon is not None:
        horizon_spread = _horizon_spread(
            segments,
            [cands[i][1] for i in combo],
            [combo.index(i) for i in fixing] if K is not None else [],
            [cands[i][2] for i in combo],
            K,
            vertical,
            pp,
            (w, h),
            diag,
            far,
            gen,
        )
    if horizon is None and len(vps):
        # no vanishing point gives the horizon: a level camera over open water sees it
        sea = _visible_horizon(segments, np.ones(len(segments), dtype=bool), w, h)
        if sea is not None:
            horizon = sea
            if vertical is not None and tilt[vertical] < math.cos(_SEA_TILT):
                vertical = None  # the point taken for vertical is not near the columns
    finite = sum(1 for v in vps if _is_finite(v, centre, far))
    return VanishingPointResult(
        vanishing_points=vps,
        labels=labels,
        segments=segments,
        K=K,
        vertical=vertical,
        horizon=horizon,
        perspective=int(finite),
        scores=scores,
        K_reason=reason,
        focal_spread=spread,
        K_note=note if K is not None else None,
        horizon_spread=horizon_spread,
    )
