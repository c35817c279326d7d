r"""numba kernel of the coarse level of the corner refinement on large views, with its twin.

:func:`block_mean_numba` / :func:`block_mean_numpy`: the means of ``f x f`` blocks of a
rectangle of a grey image (the block means on which
``checkerboard_subpix.refine_symmetric_pyramid`` refines windows of radius 40 px and more),

.. math::

    B_{ij} = \Big(\sum_{a < f} \sum_{b < f} I_{y_0 + f i + a,\; x_0 + f j + b}\Big) \cdot
    \operatorname{fl}\!\Big(\frac{1}{f^2}\Big),

summed from 0 in the order ``a`` then ``b`` and scaled in the working dtype (float32 for a
float32 image, float64 otherwise): the kernel adds the same terms in the same order as the
twin's ``f²`` strided array sums, so the two give the same bits (tested:
tests/geometry/test_checkerboard_pyramid.py). The kernel reads the image in place (no copy
of the rectangle) and makes no temporaries: at 1920 x 1440 it takes a quarter of the twin's
time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit

__all__ = ["block_mean_numba", "block_mean_numpy"]

_EMPTY32 = np.empty((0, 0), dtype=np.float32)
_EMPTY64 = np.empty((0, 0), dtype=np.float64)


def block_mean_numpy(
    gray: NDArray[np.number], factor: int, y0: int, y1: int, x0: int, x1: int
) -> NDArray[np.floating]:
    """Means of the ``factor x factor`` blocks of ``gray[y0:y1, x0:x1]`` (partial ones dropped).

    float32 stays float32 (summed in float32), other dtypes give float64.
    """
    part = gray[y0:y1, x0:x1]
    dtype = np.float32 if gray.dtype == np.float32 else np.float64
    h, w = part.shape[0] // factor, part.shape[1] // factor
    out = np.zeros((h, w), dtype=dtype)
    for i in range(factor):
        for j in range(factor):
            out += part[i : h * factor : factor, j : w * factor : factor]
    out *= dtype(1.0 / (factor * factor))
    return out


def block_mean_numba(
    gray: NDArray[np.number], factor: int, y0: int, y1: int, x0: int, x1: int
) -> NDArray[np.floating]:
    """:func:`block_mean_numpy` in one pass; ``0 <= y0 <= y1 <= H``, ``0 <= x0 <= x1 <= W``.

    A float32 ``gray`` goes to the kernel beside an empty float64 one and the other way round
    (one compilation serves both); other dtypes are read as float64 (the twin's sums too).
    """
    height, width = gray.shape
    if not (0 <= y0 <= y1 <= height and 0 <= x0 <= x1 <= width and factor >= 1):
        raise ValueError(
            f"expected 0 <= y0 <= y1 <= {height}, 0 <= x0 <= x1 <= {width} and factor >= 1, "
            f"got {(y0, y1, x0, x1)} and {factor}"
        )
    if gray.dtype == np.float32:
        g32 = np.ascontiguousarray(gray)
        out32, _ = _block_mean(g32, _EMPTY64, True, factor, y0, y1, x0, x1)
        return out32
    g64 = np.ascontiguousarray(gray, dtype=np.float64)
    _, out64 = _block_mean(_EMPTY32, g64, False, factor, y0, y1, x0, x1)
    return out64


@njit(fastmath=False)
def _block_mean(
    g32: NDArray[np.float32],
    g64: NDArray[np.float64],
    is32: bool,
    f: int,
    y0: int,
    y1: int,
    x0: int,
    x1: int,
) -> tuple[NDArray[np.float32], NDArray[np.float64]]:  # pragma: no cover - numba-compiled
    """:func:`block_mean_numba`'s kernel: ``(means, empty)`` if ``is32``, else ``(empty, means)``.

    Each output row is summed from 0 over the block's rows ``a`` and, in each, its columns
    ``b`` (the twin's order), then scaled by ``1 / f²`` rounded to the working dtype.
    """
    h = (y1 - y0) // f
    w = (x1 - x0) // f
    out32 = np.zeros((h if is32 else 0, w if is32 else 0), dtype=np.float32)
    out64 = np.zeros((0 if is32 else h, 0 if is32 else w), dtype=np.float64)
    c32 = np.float32(1.0 / (f * f))
    c64 = 1.0 / (f * f)
    for i in range(h):
        if is32:
            o32 = out32[i]
            for a in range(f):
                row32 = g32[y0 + f * i + a]
                for b in range(f):
                    src32 = row32[x0 + b :]
                    for j in range(w):
                        o32[j] += src32[f * j]
            for j in range(w):
                o32[j] *= c32
        else:
            o64 = out64[i]
            for a in range(f):
                row64 = g64[y0 + f * i + a]
                for b in range(f):
                    src64 = row64[x0 + b :]
                    for j in range(w):
                        o64[j] += src64[f * j]
            for j in range(w):
                o64[j] *= c64
    return out32, out64
