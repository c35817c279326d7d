"""Checkerboard corner candidates: saddle response, non-maximum suppression, ring test.

Private helpers of :mod:`imageform.geometry.checkerboard`; they take a clean float64
grey image ``(H, W)``.

1. **Saddle response.** The image is smoothed with a Gaussian of standard deviation
   ``sigma`` and its Hessian ``H`` is taken by central differences. At an X-junction (the
   meeting point of four squares) the smoothed intensity is a saddle, so

   .. math::  s(u, v) = -\\det H = I_{uv}^2 - I_{uu} I_{vv}

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
from scipy import ndimage

__all__ = ["Candidates", "find_candidates", "saddle_response"]

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


def saddle_response(
    smooth: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``I_uv² - I_uu I_vv`` of an already smoothed image, by central differences."""
    s = smooth
    ixx = np.zeros_like(s)
    iyy = np.zeros_like(s)
    ixy = np.zeros_like(s)
    ixx[:, 1:-1] = s[:, 2:] - 2.0 * s[:, 1:-1] + s[:, :-2]
    iyy[1:-1, :] = s[2:, :] - 2.0 * s[1:-1, :] + s[:-2, :]
    ixy[1:-1, 1:-1] = 0.25 * (s[2:, 2:] - s[2:, :-2] - s[:-2, 2:] + s[:-2, :-2])
    return ixy * ixy - ixx * iyy  # type: ignore[no-any-return]


def _ring_offsets(radius: float) -> NDArray[np.float64]:
    ang = 2.0 * np.pi * np.arange(RING_SAMPLES) / RING_SAMPLES
    return np.stack([radius * np.cos(ang), radius * np.sin(ang)], axis=1)


def _bilinear(img: NDArray[np.float64], x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray:
    return ndimage.map_coordinates(img, [y.ravel(), x.ravel()], order=1, mode="nearest").reshape(
        x.shape
    )


def ring_test(
    smooth: NDArray[np.float64],
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


def find_candidates(
    gray: NDArray[np.float64],
    sigma: float,
    *,
    relative_threshold: float = 0.02,
    max_candidates: int = 600,
) -> Candidates:
    """Saddle-response maxima of ``gray`` that pass the ring test."""
    smooth = ndimage.gaussian_filter(gray, sigma, mode="nearest", truncate=3.0)
    resp = saddle_response(smooth)
    nms = max(2, round(1.5 * sigma))
    peak = float(resp.max()) if resp.size else 0.0
    empty = Candidates(np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0), np.zeros(0))
    if not peak > 0.0:
        return empty
    local_max = ndimage.maximum_filter(resp, size=2 * nms + 1, mode="constant", cval=0.0)
    border = int(np.ceil(3 * sigma)) + 1
    mask = (resp == local_max) & (resp > relative_threshold * peak)
    mask[:border] = False
    mask[-border:] = False
    mask[:, :border] = False
    mask[:, -border:] = False
    ys, xs = np.nonzero(mask)
    if ys.size == 0:
        return empty
    r = resp[ys, xs]
    order = np.argsort(-r)[:max_candidates]
    ys, xs, r = ys[order], xs[order], r[order]
    # sub-pixel peak of the response by a separable quadratic fit (start for the grid search)
    h, w = resp.shape
    xm, xp_ = np.clip(xs - 1, 0, w - 1), np.clip(xs + 1, 0, w - 1)
    ym, yp = np.clip(ys - 1, 0, h - 1), np.clip(ys + 1, 0, h - 1)
    dx_den = resp[ys, xm] - 2 * r + resp[ys, xp_]
    dy_den = resp[ym, xs] - 2 * r + resp[yp, xs]
    dx = np.where(dx_den < 0, 0.5 * (resp[ys, xm] - resp[ys, xp_]) / np.where(dx_den < 0, dx_den, -1), 0)
    dy = np.where(dy_den < 0, 0.5 * (resp[ym, xs] - resp[yp, xs]) / np.where(dy_den < 0, dy_den, -1), 0)
    xy = np.stack([xs + np.clip(dx, -0.5, 0.5), ys + np.clip(dy, -0.5, 0.5)], axis=1).astype(float)
    # ring test on the image smoothed at a fraction of sigma (keeps small squares readable)
    lo, hi = np.percentile(gray, [1.0, 99.0])
    min_contrast = 0.15 * float(hi - lo)
    ok, dirs, contrast = ring_test(smooth, xy, 2.5 * sigma, min_contrast)
    return Candidates(xy[ok], dirs[ok], r[ok], contrast[ok])
