r"""Checkerboard corner candidates: saddle response, non-maximum suppression, ring test.

Private helpers of :mod:`imageform.geometry.checkerboard`; they take a clean float64
grey image ``(H, W)``.

1. **Saddle response.** The image is smoothed with a Gaussian of standard deviation
   ``sigma`` and its Hessian ``H`` is taken by central differences. At an X-junction (the
   meeting point of four squares) the smoothed intensity is a saddle, so

   .. math::  s(u, v) = -\det H = I_{uv}^2 - I_{uu} I_{vv}

   is large and positive there, and near zero on edges and flat areas (the "saddle point"
   detector of Lucchese & Mitra 2002; Chen & Zhang 2005, eq. 3).
2. **Non-maximum suppression** in a ``(2 r + 1)²`` window keeps local maxima above a
   fraction of the strongest response.
3. **Ring test** (after Geiger et al. 2012, sec. III-A, and the "ChESS" ring of Bennett &
   Lasenby 2014): the smoothed image sampled on a circle around the candidate must cross its
   mid level exactly four times (dark, bright, dark, bright sectors). L-corners, T-junctions,
   edges, blobs and noise fail. The four crossing angles give the two edge directions of the
   corner, used to find its grid neighbours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imageform._backend import use_numba
from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError

__all__ = ["Candidates", "find_candidates", "ring_test"]

#: Number of samples on the ring of the ring test.
RING_SAMPLES = 32


@dataclass(frozen=True)
class Candidates:
    """Corner candidates that passed the ring test.

    ``xy`` (N, 2) positions ``(u, v)``; ``dirs`` (N, 2, 2) the two unit edge directions;
    ``response`` (N,) saddle response; ``contrast`` (N,) ring max - min.
    """

    xy: NDArray[np.float64]
    dirs: NDArray[np.float64]
    response: NDArray[np.float64]
    contrast: NDArray[np.float64]


def _ring_offsets(radius: float) -> NDArray[np.float64]:
    ang = 2.0 * np.pi * np.arange(RING_SAMPLES) / RING_SAMPLES
    return np.stack([radius * np.cos(ang), radius * np.sin(ang)], axis=1)


def _bilinear(img: NDArray[np.floating], x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray:
    # the kernels module imports numba: loaded on first use, not with imageform.geometry
    from imageform._kernels.checkerboard import sample_bilinear_numba, sample_bilinear_numpy

    fn = sample_bilinear_numba if use_numba(img) else sample_bilinear_numpy
    return fn(img, np.ascontiguousarray(x), np.ascontiguousarray(y))


def ring_test(
    smooth: NDArray[np.floating],
    xy: NDArray[np.float64],
    radius: float,
    min_contrast: float,
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """Four-sector test on a ring; returns (ok, edge directions (N, 2, 2), contrast)."""
    n = xy.shape[0]
    off = _ring_offsets(radius)
    vals = _bilinear(
        smooth, xy[:, None, 0] + off[None, :, 0], xy[:, None, 1] + off[None, :, 1]
    )  # (N, S)
    lo = vals.min(axis=1)
    hi = vals.max(axis=1)
    contrast = hi - lo
    mid = 0.5 * (lo + hi)
    bright = vals > mid[:, None]
    change = bright != np.roll(bright, -1, axis=1)  # crossing between sample k and k+1
    ok = (change.sum(axis=1) == 4) & (contrast >= min_contrast)
    dirs = np.zeros((n, 2, 2))
    idx = np.flatnonzero(ok)
    if idx.size:
        # crossing angles, linearly interpolated between the two samples
        k = np.nonzero(change[idx])[1].reshape(-1, 4)  # (M, 4) sorted sample indices
        rows = np.arange(idx.size)[:, None]
        v0 = vals[idx][rows, k] - mid[idx][:, None]
        v1 = vals[idx][rows, (k + 1) % RING_SAMPLES] - mid[idx][:, None]
        frac = v0 / (v0 - v1)
        theta = 2.0 * np.pi * (k + frac) / RING_SAMPLES
        # every sector must span at least two samples: rejects noise flips
        span = np.diff(np.concatenate([k, k[:, :1] + RING_SAMPLES], axis=1), axis=1)
        wide = np.all(span >= 2, axis=1)
        u = np.stack([np.cos(theta), np.sin(theta)], axis=2)  # (M, 4, 2)
        d1 = u[:, 0] - u[:, 2]
        d2 = u[:, 1] - u[:, 3]
        d1 /= np.linalg.norm(d1, axis=1, keepdims=True)
        d2 /= np.linalg.norm(d2, axis=1, keepdims=True)
        dirs[idx, 0] = d1
        dirs[idx, 1] = d2
        # the two edges must not be (nearly) parallel
        sin_between = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        ok[idx] = wide & (sin_between > 0.3)
    return ok, dirs, contrast


def _peak_offset(minus: NDArray, centre: NDArray, plus: NDArray) -> NDArray[np.float64]:
    """Vertex of the parabola through three samples (0 where it is not a maximum)."""
    curv = minus - 2.0 * centre + plus
    ok = curv < 0
    off = np.zeros(centre.shape)
    off[ok] = 0.5 * (minus[ok] - plus[ok]) / curv[ok]
    # a maximum sample has |offset| <= 1/2; ties on plateaus may give up to 1/2 exactly
    return off


def find_candidates(
    gray: NDArray[np.floating],
    sigma: float,
    *,
    relative_threshold: float = 0.02,
    max_candidates: int = 300,
) -> Candidates:
    """Saddle-response maxima of ``gray`` that pass the ring test."""
    # O(1) checks (the image's values were checked by find_checkerboard; no extra pass)
    if not isinstance(gray, np.ndarray) or gray.ndim != 2 or gray.dtype.kind not in "fiu":
        raise InvalidInputError(f"expected gray as a 2-D real NumPy image, got {describe(gray)}")
    sigma = as_real(sigma, "sigma", positive=True, maximum=1000.0)
    relative_threshold = as_real(relative_threshold, "relative_threshold", minimum=0.0)
    max_candidates = as_int(max_candidates, "max_candidates", minimum=1, maximum=10**7)
    from imageform._kernels.checkerboard import (
        gaussian_weights,
        local_maxima_numba,
        local_maxima_numpy,
        refine_corners_numba,
        refine_corners_numpy,
        smooth_saddle_numba,
        smooth_saddle_numpy,
    )

    taps = gaussian_weights(sigma).astype(np.float32)
    fast = use_numba(gray)
    # float32 is ample for a detector (the refinement runs on the float64 image)
    g32 = gray.astype(np.float32)
    smooth, resp = (smooth_saddle_numba if fast else smooth_saddle_numpy)(g32, taps)
    empty = Candidates(np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0), np.zeros(0))
    peak = float(resp.max())
    if not peak > 0.0:
        return empty
    nms = max(2, round(1.5 * sigma))
    border = taps.size // 2 + 1
    ys, xs = (local_maxima_numba if fast else local_maxima_numpy)(
        resp, nms, relative_threshold * peak, border
    )
    if ys.size == 0:
        return empty
    r = resp[ys, xs]
    order = np.argsort(-r, kind="stable")[:max_candidates]
    ys, xs, r = ys[order], xs[order], r[order]
    dx = _peak_offset(resp[ys, xs - 1], r, resp[ys, xs + 1])
    dy = _peak_offset(resp[ys - 1, xs], r, resp[ys + 1, xs])
    xy = np.stack([xs + dx, ys + dy], axis=1).astype(np.float64)
    # contrast scale of the image from a subsample (robust to a few hot pixels)
    lo, hi = np.percentile(smooth[::8, ::8], [1.0, 99.0])
    min_contrast = 0.15 * float(hi - lo)
    ok, dirs, contrast = ring_test(smooth, xy, 2.5 * sigma, min_contrast)
    xy, r, dirs, contrast = xy[ok], r[ok], dirs[ok], contrast[ok]
    # The response peak of a skewed corner lies up to ~sigma off the junction: a few
    # gradient-orthogonality steps on the smoothed image centre each survivor, so that the
    # ring (read again there) gives the edge directions through the junction itself.
    # A survivor whose centred ring fails keeps its first position and directions.
    h = max(2, round(1.5 * sigma))
    kernel = refine_corners_numba if fast else refine_corners_numpy
    moved, status = kernel(smooth, np.ascontiguousarray(xy), h, h, 5, 0.05)
    ok2, dirs2, contrast2 = ring_test(smooth, moved, 2.5 * sigma, min_contrast)
    use = ok2 & (status != 4)
    xy = np.where(use[:, None], moved, xy)
    dirs = np.where(use[:, None, None], dirs2, dirs)
    contrast = np.where(use, contrast2, contrast)
    ok = np.ones(xy.shape[0], dtype=bool)
    return Candidates(xy[ok], dirs[ok], r[ok].astype(np.float64), contrast[ok])
