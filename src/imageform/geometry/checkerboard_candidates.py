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


def ring_test(
    smooth: NDArray[np.floating],
    xy: NDArray[np.float64],
    radius: float,
    min_contrast: float,
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """Four-sector test on a ring; returns (ok, edge directions (N, 2, 2), contrast)."""
    if use_numba(smooth):
        from imageform._kernels.checkerboard import ring_test_numba

        return ring_test_numba(
            smooth, np.ascontiguousarray(xy, dtype=np.float64), _ring_offsets(radius),
            float(min_contrast),
        )  # fmt: skip
    from imageform._kernels.checkerboard import ring_test_numpy

    return ring_test_numpy(smooth, xy, _ring_offsets(radius), float(min_contrast))


def _peak_offset(minus: NDArray, centre: NDArray, plus: NDArray) -> NDArray[np.float64]:
    """Vertex of the parabola through three samples (0 where it is not a maximum)."""
    curv = minus - 2.0 * centre + plus
    ok = curv < 0
    off = np.zeros(centre.shape)
    off[ok] = 0.5 * (minus[ok] - plus[ok]) / curv[ok]
    # a maximum sample has |offset| <= 1/2; ties on plateaus may give up to 1/2 exactly
    return off


def find_candidates(
    gray: NDArray[np.number],
    sigma: float,
    *,
    relative_threshold: float = 0.02,
    max_candidates: int = 300,
    scale: float = 1.0,
) -> Candidates:
    """Saddle-response maxima of ``gray / scale`` that pass the ring test.

    ``scale`` lets integer codes be read as they are (``uint8`` with ``scale=255`` gives the
    candidates of ``gray.astype(float32) / 255`` without making that array).
    """
    # O(1) checks (the image's values were checked by find_checkerboard; no extra pass)
    if not isinstance(gray, np.ndarray) or gray.ndim != 2 or gray.dtype.kind not in "fiu":
        raise InvalidInputError(f"expected gray as a 2-D real NumPy image, got {describe(gray)}")
    sigma = as_real(sigma, "sigma", positive=True, maximum=1000.0)
    relative_threshold = as_real(relative_threshold, "relative_threshold", minimum=0.0)
    max_candidates = as_int(max_candidates, "max_candidates", minimum=1, maximum=10**7)
    scale = as_real(scale, "scale", positive=True)
    from imageform._kernels.checkerboard import (
        gaussian_weights,
        refine_corners_numba,
        refine_corners_numpy,
        saddle_maxima_numba,
        saddle_maxima_numpy,
    )

    taps = gaussian_weights(sigma).astype(np.float32)
    if gray.dtype == np.float16:  # numba has no float16: the kernel works in float32 anyway
        gray = gray.astype(np.float32)
    fast = use_numba(gray)
    # float32 is ample for a detector (the refinement runs on the image as given): the
    # kernel reads gray as it is and works in float32 (no converted copy of the image)
    nms = max(2, round(1.5 * sigma))
    border = taps.size // 2 + 1
    if fast:
        # one compiled kernel per 8-bit or other image, not one per dtype and read-only flag
        # (each costs seconds of compilation on a first run): every value is converted to
        # float32 where the kernel reads it, so converting the image first gives the same bits
        gray = np.require(gray, np.uint8 if gray.dtype == np.uint8 else np.float32, ("C", "W"))
    smooth, peak, ys, xs, around = (saddle_maxima_numba if fast else saddle_maxima_numpy)(
        np.ascontiguousarray(gray), taps, nms, border, relative_threshold, np.float32(scale)
    )
    empty = Candidates(np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0), np.zeros(0))
    if not peak > 0.0:
        return empty
    keep = around[:, 1, 1] > relative_threshold * peak
    ys, xs, around = ys[keep], xs[keep], around[keep]
    if ys.size == 0:
        return empty
    r = around[:, 1, 1]
    order = np.argsort(-r, kind="stable")[:max_candidates]
    ys, xs, r, around = ys[order], xs[order], r[order], around[order]
    dx = _peak_offset(around[:, 1, 0], r, around[:, 1, 2])
    dy = _peak_offset(around[:, 0, 1], r, around[:, 2, 1])
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
