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
- :func:`upsample2_numba` / :func:`upsample2_numpy`: the 2x bilinear upsample of an
  (H, W, C) float32 image that keeps pixel centres (output ``o`` samples the input at
  ``o / 2 - 0.25``; edges replicated), weights 3/4 and 1/4 summed in float64: the values of
  ``scipy.ndimage.zoom(img, (2, 2, 1), order=1, grid_mode=True, mode="nearest")``.
- :func:`lmeds_best_numba` / :func:`lmeds_best_numpy`: of the 6-patch subsets of a
  least-median-of-squares colour fit, the first whose affine fit (normal equations with a
  1e-9 ridge) has the least median CIELAB ΔE*ab (CIE 1976) over all patches; the kernel
  solves by Gaussian elimination with partial pivoting and leaves a subset as soon as half
  the patches are as far as the best median so far (its median cannot be less).

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
    "lmeds_best_numba",
    "lmeds_best_numpy",
    "region_moments_numba",
    "region_moments_numpy",
    "upsample2_numba",
    "upsample2_numpy",
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


@njit(fastmath=False)
def upsample2_numba(img: NDArray[np.float32]) -> NDArray[np.float32]:  # pragma: no cover
    """2x bilinear upsample keeping pixel centres (see the module)."""
    h, w, nc = img.shape
    out = np.empty((2 * h, 2 * w, nc), dtype=np.float32)
    for yo in range(2 * h):
        y = yo // 2
        y2 = max(y - 1, 0) if yo % 2 == 0 else min(y + 1, h - 1)
        for xo in range(2 * w):
            x = xo // 2
            x2 = max(x - 1, 0) if xo % 2 == 0 else min(x + 1, w - 1)
            for c in range(nc):
                a = 0.75 * np.float64(img[y, x, c]) + 0.25 * np.float64(img[y, x2, c])
                b = 0.75 * np.float64(img[y2, x, c]) + 0.25 * np.float64(img[y2, x2, c])
                out[yo, xo, c] = np.float32(0.75 * a + 0.25 * b)
    return out


def upsample2_numpy(img: NDArray[np.float32]) -> NDArray[np.float32]:
    """Twin of :func:`upsample2_numba`, one axis at a time."""
    out = np.asarray(img, dtype=np.float64)
    for axis in (0, 1):
        a = np.moveaxis(out, axis, 0)
        prev = np.concatenate([a[:1], a[:-1]])
        nxt = np.concatenate([a[1:], a[-1:]])
        up = np.empty((2 * a.shape[0], *a.shape[1:]))
        up[0::2] = 0.75 * a + 0.25 * prev
        up[1::2] = 0.75 * a + 0.25 * nxt
        out = np.moveaxis(up, 0, axis)
    return np.ascontiguousarray(out, dtype=np.float32)


_E0 = (6.0 / 29.0) ** 3
_E1 = 3.0 * (6.0 / 29.0) ** 2


@njit(fastmath=False)
def lmeds_best_numba(
    x: NDArray[np.float64],
    ref: NDArray[np.float64],
    lab_ref: NDArray[np.float64],
    sub: NDArray[np.int64],
    to_xyz: NDArray[np.float64],
) -> int:  # pragma: no cover - numba-compiled
    """Index of the subset whose fit has the least median ΔE*ab over the m patches.

    ``x`` (m, 4) the patches' linear colours and 1, ``ref`` (m, 3) the references' linear
    colours, ``lab_ref`` (m, 3) their CIELAB, ``sub`` (T, k) the subsets (indices into the
    m patches), ``to_xyz`` (3, 3) linear sRGB -> XYZ over the white (a right-hand factor).
    """
    n_t, k = sub.shape
    m = x.shape[0]
    lo, hi = (m - 1) // 2, m // 2  # the middle of the sorted errors
    best_t, best = 0, np.inf
    a = np.empty((4, 4))
    b = np.empty((4, 3))
    err = np.empty(m)
    f = np.empty(3)
    for t in range(n_t):
        for i in range(4):
            for j in range(4):
                a[i, j] = 1e-9 if i == j else 0.0
            for c in range(3):
                b[i, c] = 0.0
        for q in range(k):
            r = sub[t, q]
            for i in range(4):
                for j in range(4):
                    a[i, j] += x[r, i] * x[r, j]
                for c in range(3):
                    b[i, c] += x[r, i] * ref[r, c]
        # Gaussian elimination with partial pivoting: a w = b, w (4, 3) into b
        for col in range(4):
            piv = col
            for i in range(col + 1, 4):
                if abs(a[i, col]) > abs(a[piv, col]):
                    piv = i
            if piv != col:
                for j in range(4):
                    a[col, j], a[piv, j] = a[piv, j], a[col, j]
                for c in range(3):
                    b[col, c], b[piv, c] = b[piv, c], b[col, c]
            for i in range(col + 1, 4):
                g = a[i, col] / a[col, col]
                for j in range(col, 4):
                    a[i, j] -= g * a[col, j]
                for c in range(3):
                    b[i, c] -= g * b[col, c]
        for col in range(3, -1, -1):
            for c in range(3):
                s = b[col, c]
                for j in range(col + 1, 4):
                    s -= a[col, j] * b[j, c]
                b[col, c] = s / a[col, col]
        n_far = 0
        for n in range(m):
            p0 = x[n, 0] * b[0, 0] + x[n, 1] * b[1, 0] + x[n, 2] * b[2, 0] + x[n, 3] * b[3, 0]
            p1 = x[n, 0] * b[0, 1] + x[n, 1] * b[1, 1] + x[n, 2] * b[2, 1] + x[n, 3] * b[3, 1]
            p2 = x[n, 0] * b[0, 2] + x[n, 1] * b[1, 2] + x[n, 2] * b[2, 2] + x[n, 3] * b[3, 2]
            p0 = min(max(p0, 0.0), 1.0)
            p1 = min(max(p1, 0.0), 1.0)
            p2 = min(max(p2, 0.0), 1.0)
            for c in range(3):
                v = p0 * to_xyz[0, c] + p1 * to_xyz[1, c] + p2 * to_xyz[2, c]
                f[c] = np.cbrt(v) if v > _E0 else v / _E1 + 4.0 / 29.0
            dl = 116.0 * f[1] - 16.0 - lab_ref[n, 0]
            da = 500.0 * (f[0] - f[1]) - lab_ref[n, 1]
            db = 200.0 * (f[1] - f[2]) - lab_ref[n, 2]
            e = np.sqrt(dl * dl + da * da + db * db)
            err[n] = e
            if e >= best:
                n_far += 1
                if n_far >= m - lo:  # the lower middle is >= best: so is the median
                    break
        if n_far >= m - lo:
            continue
        for i in range(1, m):  # insertion sort of the m errors
            v = err[i]
            j = i - 1
            while j >= 0 and err[j] > v:
                err[j + 1] = err[j]
                j -= 1
            err[j + 1] = v
        med = (err[lo] + err[hi]) / 2.0
        if med < best:
            best_t, best = t, med
    return best_t


def lmeds_best_numpy(
    x: NDArray[np.float64],
    ref: NDArray[np.float64],
    lab_ref: NDArray[np.float64],
    sub: NDArray[np.int64],
    to_xyz: NDArray[np.float64],
) -> int:
    """Twin of :func:`lmeds_best_numba` with batched NumPy (LAPACK's solve), every median."""
    xs, rs = x[sub], ref[sub]  # (T, k, 4), (T, k, 3)
    xt = np.swapaxes(xs, 1, 2)
    w = np.linalg.solve(xt @ xs + 1e-9 * np.eye(4), xt @ rs)  # (T, 4, 3)
    xyz = np.clip(np.matmul(x, w), 0.0, 1.0) @ to_xyz
    f = np.where(xyz > _E0, np.cbrt(xyz), xyz / _E1 + 4.0 / 29.0)
    lab = np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )
    d = lab - lab_ref[None]
    return int(np.argmin(np.median(np.sqrt((d * d).sum(axis=-1)), axis=1)))
