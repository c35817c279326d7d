"""Hartley normalisation: a similarity that centres points and scales them to mean distance √n."""

from __future__ import annotations

import math
from typing import Any

from imageform._typing import Array

__all__ = ["similarity_normalization"]


def similarity_normalization(
    points: Array, xp: Any, *, mask: Array | None = None
) -> tuple[Array, Array]:
    """``T`` (``(..., n+1, n+1)``) with ``T x̃`` centred at 0 and mean distance ``√n``.

    Returns ``(normalised points (..., N, n), T)``; Hartley & Zisserman §4.4.4 (Algorithm 4.2).
    Coincident points (zero spread) give ``scale = 1``; the caller detects that degeneracy.

    ``mask`` (bool, ``(..., N)``) marks the points of each set in a padded batch: the centre and
    the mean distance are those of the marked points alone, and the padding comes back as
    zeros (so that it adds nothing to a DLT system built from the normalised points).
    """
    n = points.shape[-1]
    if mask is None:
        centre = xp.mean(points, axis=-2, keepdims=True)
        d = xp.sqrt(xp.sum((points - centre) ** 2, axis=-1))
        mean_d = xp.mean(d, axis=-1)
        centred = points - centre
    else:
        w = xp.astype(mask, points.dtype)[..., None]
        count = xp.sum(w, axis=-2)
        centre = xp.sum(points * w, axis=-2, keepdims=True) / count[..., None]
        centred = (points - centre) * w
        mean_d = xp.sum(xp.sqrt(xp.sum(centred * centred, axis=-1)), axis=-1) / count[..., 0]
    s = xp.where(
        mean_d > 0,
        math.sqrt(n) / xp.where(mean_d > 0, mean_d, xp.ones_like(mean_d)),
        xp.ones_like(mean_d),
    )
    normed = centred * s[..., None, None]
    # T = [[s I, -s c], [0, 1]], entry by entry (one stack: cheaper than products of eyes)
    shift = -centre[..., 0, :] * s[..., None]
    zero, one = xp.zeros_like(s), xp.ones_like(s)
    rows = [[s if j == i else zero for j in range(n)] + [shift[..., i]] for i in range(n)]
    entries = [e for row in rows for e in row] + [zero] * n + [one]
    T = xp.reshape(xp.stack(entries, axis=-1), (*s.shape, n + 1, n + 1))
    return normed, T
