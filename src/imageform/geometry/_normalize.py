"""Hartley normalisation: a similarity that centres points and scales them to mean distance √n."""

from __future__ import annotations

import math
from typing import Any

from imageform._backend import device_of
from imageform._typing import Array

__all__ = ["similarity_normalization"]


def similarity_normalization(points: Array, xp: Any) -> tuple[Array, Array]:
    """``T`` (``(..., n+1, n+1)``) with ``T x̃`` centred at 0 and mean distance ``√n``.

    Returns ``(normalised points (..., N, n), T)``; Hartley & Zisserman §4.4.4 (Algorithm 4.2).
    Coincident points (zero spread) give ``scale = 1``; the caller detects that degeneracy.
    """
    n = points.shape[-1]
    centre = xp.mean(points, axis=-2, keepdims=True)
    d = xp.sqrt(xp.sum((points - centre) ** 2, axis=-1))
    mean_d = xp.mean(d, axis=-1)
    s = xp.where(
        mean_d > 0,
        math.sqrt(n) / xp.where(mean_d > 0, mean_d, xp.ones_like(mean_d)),
        xp.ones_like(mean_d),
    )
    normed = (points - centre) * s[..., None, None]
    eye = xp.eye(n + 1, dtype=points.dtype, device=device_of(points))
    diag = xp.concat(
        (xp.broadcast_to(s[..., None], (*s.shape, n)), xp.ones_like(s[..., None])), axis=-1
    )
    T = eye * diag[..., None, :]
    shift = -centre[..., 0, :] * s[..., None]
    col = xp.concat((shift, xp.zeros_like(s[..., None])), axis=-1)
    last = xp.asarray([0.0] * n + [1.0], dtype=points.dtype, device=device_of(points))
    T = T + col[..., :, None] * last
    return normed, T
