r"""numba kernels of the colour-chart detector (:mod:`imageform.analysis.chart_detect`).

Each kernel has a plain NumPy/SciPy twin.

- :func:`flat_gradient_numba` / :func:`flat_gradient_numpy`: the colour gradient magnitude
  :math:`\sqrt{\sum_c (S_x * G * I_c)^2 + (S_y * G * I_c)^2} / 8` of an (H, W, 3) image:
  separable Gaussian ``taps``, then the 3 × 3 Sobel operator (divided by 8: a unit-slope
  ramp gives 1), edges replicated.
- :func:`block_mean_numba` / :func:`block_mean_numpy`: the mean of ``f × f`` pixel blocks
  (any input dtype, divided by ``scale``: 255 for uint8), the detector's working image.
- :func:`region_moments_numba` / :func:`region_moments_numpy`: per label ``1..n`` of a label
  image, the pixel count and the sums of ``u, v, u², v², u v`` (``u`` the column).

Serial (no ``parallel``): a megapixel is a few milliseconds. Agreement with the twins is
tested in tests/analysis/test_chart_detect.py.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit

__all__ = [
    "block_mean_numba",
    "block_mean_numpy",
    "flat_gradient_numba",
    "flat_gradient_numpy",
    "region_moments_numba",
    "region_moments_numpy",
]


@njit(fastmath=False)
def flat_gradient_numba(
    img: NDArray[np.float32], taps: NDArray[np.float32]
) -> NDArray[np.float32]:  # pragma: no cover - numba-compiled
    """Colour gradient magnitude of the Gaussian-smoothed image (see the module)."""
    h, w, nc = img.shape
    r = taps.shape[0] // 2
    out = np.zeros((h, w), dtype=np.float32)
    tmp = np.empty((h, w), dtype=np.float32)
    sm = np.empty((h, w), dtype=np.float32)
    for c in range(nc):
        for y in range(h):
            for x in range(w):
                acc = np.float32(0.0)
                for k in range(2 * r + 1):
                    xx = min(max(x + k - r, 0), w - 1)
                    acc += taps[k] * img[y, xx, c]
                tmp[y, x] = acc
        for y in range(h):
            for x in range(w):
                acc = np.float32(0.0)
                for k in range(2 * r + 1):
                    yy = min(max(y + k - r, 0), h - 1)
                    acc += taps[k] * tmp[yy, x]
                sm[y, x] = acc
        for y in range(h):
            y0, y1 = max(y - 1, 0), min(y + 1, h - 1)
            for x in range(w):
                x0, x1 = max(x - 1, 0), min(x + 1, w - 1)
                gx = (
                    sm[y0, x1]
                    - sm[y0, x0]
                    + 2.0 * (sm[y, x1] - sm[y, x0])
                    + sm[y1, x1]
                    - sm[y1, x0]
                )
                gy = (
                    sm[y1, x0]
                    - sm[y0, x0]
                    + 2.0 * (sm[y1, x] - sm[y0, x])
                    + sm[y1, x1]
                    - sm[y0, x1]
                )
                out[y, x] += gx * gx + gy * gy
    for y in range(h):
        for x in range(w):
            out[y, x] = np.sqrt(out[y, x]) / np.float32(8.0)
    return out


def flat_gradient_numpy(
    img: NDArray[np.floating], taps: NDArray[np.floating]
) -> NDArray[np.float64]:
    """Twin of :func:`flat_gradient_numba` with :func:`scipy.ndimage.correlate1d`."""
    from scipy import ndimage

    total = np.zeros(img.shape[:2])
    for c in range(img.shape[2]):
        ch = np.asarray(img[..., c], dtype=np.float64)
        sm = ndimage.correlate1d(ch, taps, axis=1, mode="nearest")
        sm = ndimage.correlate1d(sm, taps, axis=0, mode="nearest")
        gx = ndimage.sobel(sm, axis=1, mode="nearest")
        gy = ndimage.sobel(sm, axis=0, mode="nearest")
        total += gx * gx + gy * gy
    return np.sqrt(total) / 8.0


@njit(fastmath=False)
def region_moments_numba(
    labels: NDArray[np.integer], n: int
) -> NDArray[np.float64]:  # pragma: no cover - numba-compiled
    """(n, 6): count, sum u, sum v, sum u², sum v², sum u v of labels 1..n."""
    h, w = labels.shape
    m = np.zeros((n, 6))
    for y in range(h):
        for x in range(w):
            lab = labels[y, x]
            if lab <= 0:
                continue
            row = m[lab - 1]
            row[0] += 1.0
            row[1] += x
            row[2] += y
            row[3] += x * x
            row[4] += y * y
            row[5] += x * y
    return m


def region_moments_numpy(labels: NDArray[np.integer], n: int) -> NDArray[np.float64]:
    """Twin of :func:`region_moments_numba` with :func:`numpy.bincount`."""
    h, w = labels.shape
    yy, xx = np.mgrid[0:h, 0:w]
    flat = labels.ravel()
    xs, ys = xx.ravel().astype(np.float64), yy.ravel().astype(np.float64)
    cols = [np.ones_like(xs), xs, ys, xs * xs, ys * ys, xs * ys]
    return np.stack([np.bincount(flat, c, n + 1)[1:] for c in cols], axis=1)


@njit(fastmath=False)
def block_mean_numba(
    img: NDArray[np.generic], f: int, scale: float
) -> NDArray[np.float32]:  # pragma: no cover - numba-compiled
    """(H // f, W // f, C) means of f x f blocks of ``img`` divided by ``scale``."""
    h, w, nc = img.shape
    h2, w2 = h // f, w // f
    out = np.zeros((h2, w2, nc), dtype=np.float32)
    norm = 1.0 / (f * f * scale)
    for y in range(h2 * f):
        yo = y // f
        for x in range(w2 * f):
            xo = x // f
            for c in range(nc):
                out[yo, xo, c] += img[y, x, c]
    for yo in range(h2):
        for xo in range(w2):
            for c in range(nc):
                out[yo, xo, c] = np.float32(out[yo, xo, c] * norm)
    return out


def block_mean_numpy(img: NDArray[np.generic], f: int, scale: float) -> NDArray[np.float64]:
    """Twin of :func:`block_mean_numba` by reshaping."""
    h, w, nc = img.shape
    h2, w2 = h // f, w // f
    a = np.asarray(img[: h2 * f, : w2 * f], dtype=np.float64)
    return a.reshape(h2, f, w2, f, nc).mean(axis=(1, 3)) / scale
