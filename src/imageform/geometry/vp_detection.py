"""Vanishing points, the orthogonal triplet, K and the horizon found in a photograph.

Pipeline: line segments (:func:`~imageform.geometry.detect_line_segments`) → sequential
RANSAC over pairs of segments (a hypothesis ``v = l_i × l_j`` is scored by the total length of
segments pointing at it within an angle) with a least-squares refit on the inliers
(:func:`~imageform.geometry.vanishing_point_from_lines`) → among the candidates, the triplet
most consistent with three orthogonal scene directions (a "Manhattan world", Coughlan &
Yuille 1999): K from the orthocentre and ``f² = -(v₁ - p)·(v₂ - p)`` when all three are
finite (Caprile & Torre 1990), from two finite ones and a principal point at the image centre
otherwise → the vertical direction (the one closest to the image's y axis) and the horizon
``l ~ K⁻ᵀ d_vertical``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._typing import ArrayLike, FloatArray
from imageform._validate import as_int, as_real, check_positive, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry._checks import check_image_size, check_rng
from imageform.geometry.line_segments import LineSegments, detect_line_segments
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
        the orthogonal triplet (or pair) when one was found.
    labels : (N,)
        For each segment, the index of its vanishing point, or -1.
    segments : LineSegments
    K : (3, 3) or None
        Intrinsics from the vanishing points (square pixels, zero skew), if determined.
    vertical : int or None
        Index of the vertical vanishing point (the direction closest to the image's y axis).
    horizon : (3,) or None
        The horizon ``(a, b, c)``, ``a u + b v + c = 0``, ``a² + b² = 1``.
    perspective : int
        How many of the vanishing points are finite (1, 2 or 3 point perspective), with
        "finite" meaning within ``infinity_factor`` image diagonals of the image centre.
    scores : (M,)
        Total length of the segments supporting each vanishing point (pixels).
    """

    vanishing_points: FloatArray
    labels: np.ndarray
    segments: LineSegments
    K: FloatArray | None
    vertical: int | None
    horizon: FloatArray | None
    perspective: int
    scores: FloatArray


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


def _triplet_K(
    vps: list[FloatArray], centre: FloatArray, diag: float, far: float
) -> FloatArray | None:
    finite = [v for v in vps if v[2] != 0 and np.hypot(*(v[:2] - centre)) < far]
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


@_deprecate.parameters(renamed={"seed": "rng"})
def detect_vanishing_points(
    image: ArrayLike | None = None,
    *,
    segments: LineSegments | None = None,
    image_size: tuple[int, int] | None = None,
    angle_threshold: float = math.radians(2.0),
    n_candidates: int = 6,
    iterations: int = 600,
    infinity_factor: float = 20.0,
    rng: RNGLike = 0,
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
    iterations : int
        RANSAC hypotheses per candidate.
    infinity_factor : float
        A point farther than this many image diagonals from the centre counts as at infinity.
    rng : int, numpy.random.Generator or None
        RANSAC's random source (SPEC 7): an int seeds a new Generator (reproducible by
        default, ``rng=0``), a Generator is used as is, None draws fresh entropy.

    Raises
    ------
    InvalidInputError
        If neither or both of ``image`` and ``segments`` are given.
    DegenerateConfigurationError
        If fewer than two line segments are found.
    """
    if (image is None) == (segments is None):
        raise InvalidInputError("give either an image or segments (with image_size)")
    if segments is None:
        arr = np.asarray(image)
        if arr.ndim not in (2, 3):
            raise InvalidInputError(f"expected an (H, W) or (H, W, 3) image, got {arr.shape}")
        segments = detect_line_segments(arr)
        image_size = (arr.shape[1], arr.shape[0])
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
    iterations = as_int(iterations, "iterations", minimum=1, maximum=10**7)
    infinity_factor = as_real(infinity_factor, "infinity_factor", positive=True, maximum=1e50)
    if len(segments) < 2:
        raise DegenerateConfigurationError(
            f"found {len(segments)} line segment(s); vanishing points need at least two"
        )
    w, h = image_size
    centre = np.array([(w - 1) / 2, (h - 1) / 2])
    diag = math.hypot(w, h)
    far = infinity_factor * diag
    cands = _ransac_candidates(
        segments, as_rng(check_rng(rng)), n_candidates, angle_threshold, iterations
    )
    cands = [(_normalise(v, far), inl, sc) for v, inl, sc in cands]
    best: tuple[float, tuple[int, ...], FloatArray | None] = (-1.0, (), None)
    for r in (3, 2):
        for combo in itertools.combinations(range(len(cands)), r):
            trial = [cands[i][0] for i in combo]
            K = _triplet_K(trial, centre, diag, far) if r == 3 else None
            if r == 3 and K is None:
                continue
            score = sum(cands[i][2] for i in combo)
            if score > best[0]:
                best = (score, combo, K)
        if best[1]:
            break
    combo, K = best[1], best[2]
    if not combo:
        combo = tuple(range(min(1, len(cands))))
    vps = np.array([cands[i][0] for i in combo]) if combo else np.zeros((0, 3))
    scores = np.array([cands[i][2] for i in combo])
    labels = np.full(len(segments), -1, dtype=np.int64)
    for j, i in enumerate(combo):
        labels[cands[i][1] & (labels < 0)] = j
    vertical: int | None = None
    horizon: FloatArray | None = None
    if K is not None and len(vps):
        dirs = np.linalg.solve(K, vps.T).T
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        vertical = int(np.argmax(np.abs(dirs[:, 1])))
        up = dirs[vertical] * (-1.0 if dirs[vertical, 1] > 0 else 1.0)  # image up is -y
        horizon = np.asarray(horizon_line(K, None, up))
    elif len(vps) >= 2:
        # without K: the vertical point is the one most in line with the image's columns
        tilt = []
        for v in vps:
            d = v[:2] - centre * v[2]
            tilt.append(abs(d[1]) / max(np.hypot(*d), 1e-300))
        vertical = int(np.argmax(tilt))
    finite = sum(1 for v in vps if v[2] != 0 and np.hypot(*(v[:2] - centre)) < far)
    return VanishingPointResult(
        vanishing_points=vps,
        labels=labels,
        segments=segments,
        K=K,
        vertical=vertical,
        horizon=horizon,
        perspective=int(finite),
        scores=scores,
    )
