r"""numba kernels of the checkerboard detector, each with a plain NumPy/SciPy twin.

- :func:`smooth_saddle_numba` / :func:`smooth_saddle_numpy`: separable Gaussian smoothing
  (edges replicated, the taps of :func:`gaussian_weights`) and the saddle response
  ``I_uv² - I_uu I_vv`` by central differences.
- :func:`local_maxima_numba` / :func:`local_maxima_numpy`: pixels above a threshold and not
  below any pixel of their ``(2 r + 1)²`` window.
- :func:`sample_bilinear_numba` / :func:`sample_bilinear_numpy`: bilinear samples, edges
  replicated.
- :func:`refine_corners_numba` / :func:`refine_corners_numpy`: sub-pixel corner refinement
  (gradient-orthogonality least squares), below.

The refinement (Förstner & Gülch 1987; the iteration of OpenCV's ``cornerSubPix``): around
the current estimate ``q`` a ``(2 h + 1)²`` patch is resampled bilinearly (edge pixels
replicated), central-difference gradients ``g_p`` are weighted by
``w_p = exp(-(x_p/h_x)²) exp(-(y_p/h_y)²)`` and the update solves

.. math::

    \Big(\sum_p w_p\, g_p g_p^\top\Big)\, q' = \sum_p w_p\, g_p g_p^\top\, p ,

i.e. the point ``q'`` to which every gradient in the window is orthogonal. It stops after
``max_iter`` iterations or when the step is ``<= eps``; a point that ends farther than the
half-window from its start keeps its start (as OpenCV does), and the returned ``status``
says which (0 converged, 1 ``max_iter`` reached, 2 singular normal matrix, 3 left the image,
4 moved farther than the half window — start kept).

The kernels are compiled without ``parallel``: at the detector's image sizes each call is a
few milliseconds and threads cost more than they give on a shared machine; parallelism
belongs across views. Agreement with the twins is tested (tests/geometry/
test_checkerboard_kernels.py): refinement 1e-9 px, smoothing 1e-6, response 1e-4 of its
peak, the same local maxima, samples 1e-12.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit

__all__ = [
    "corner_window_weights",
    "gaussian_weights",
    "local_maxima_numba",
    "local_maxima_numpy",
    "refine_corners_numba",
    "refine_corners_numpy",
    "sample_bilinear_numba",
    "sample_bilinear_numpy",
    "smooth_saddle_numba",
    "smooth_saddle_numpy",
]


def corner_window_weights(hx: int, hy: int) -> NDArray[np.float64]:
    """Return the ``(2 hy + 1, 2 hx + 1)`` Gaussian window ``exp(-(x/hx)²) exp(-(y/hy)²)``."""
    y = np.arange(-hy, hy + 1, dtype=np.float64) / hy
    x = np.arange(-hx, hx + 1, dtype=np.float64) / hx
    return np.exp(-(y**2))[:, None] * np.exp(-(x**2))[None, :]


@njit(fastmath=False)
def refine_corners_numba(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    hx: int,
    hy: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # pragma: no cover - numba-compiled
    """Refine ``corners`` (N, 2) in ``(u, v)``; returns the refined corners and a status."""
    n = corners.shape[0]
    height, width = image.shape
    out = corners.copy()
    status = np.zeros(n, dtype=np.int64)
    ww = 2 * hx + 1
    wh = 2 * hy + 1
    mask = np.empty((wh, ww))
    for i in range(wh):
        y = (i - hy) / hy
        for j in range(ww):
            x = (j - hx) / hx
            mask[i, j] = np.exp(-y * y) * np.exp(-x * x)
    eps2 = eps * eps
    for k in range(n):
        patch = np.empty((wh + 2, ww + 2))
        cx = corners[k, 0]
        cy = corners[k, 1]
        sx = cx
        sy = cy
        st = 1
        if not (np.isfinite(cx) and np.isfinite(cy)):  # nothing to refine from
            status[k] = 2
            continue
        for _ in range(max_iter):
            # bilinear resampling of the (wh+2, ww+2) patch centred on (cx, cy); the centre
            # is clamped in float before int(): beyond the clamp every sample is an edge
            # pixel either way, and int() of a value beyond int64 is undefined
            fx = np.floor(min(max(cx, -hx - 2.0), width + hx + 1.0))
            fy = np.floor(min(max(cy, -hy - 2.0), height + hy + 1.0))
            ax = cx - fx
            ay = cy - fy
            x0 = int(fx) - hx - 1
            y0 = int(fy) - hy - 1
            for i in range(wh + 2):
                ya = min(max(y0 + i, 0), height - 1)
                yb = min(max(y0 + i + 1, 0), height - 1)
                for j in range(ww + 2):
                    xa = min(max(x0 + j, 0), width - 1)
                    xb = min(max(x0 + j + 1, 0), width - 1)
                    patch[i, j] = (1.0 - ay) * ((1.0 - ax) * image[ya, xa] + ax * image[ya, xb]) + (
                        ay * ((1.0 - ax) * image[yb, xa] + ax * image[yb, xb])
                    )
            a = 0.0
            b = 0.0
            c = 0.0
            bb1 = 0.0
            bb2 = 0.0
            for i in range(wh):
                py = i - hy
                for j in range(ww):
                    m = mask[i, j]
                    gx = patch[i + 1, j + 2] - patch[i + 1, j]
                    gy = patch[i + 2, j + 1] - patch[i, j + 1]
                    gxx = gx * gx * m
                    gxy = gx * gy * m
                    gyy = gy * gy * m
                    px = j - hx
                    a += gxx
                    b += gxy
                    c += gyy
                    bb1 += gxx * px + gxy * py
                    bb2 += gxy * px + gyy * py
            det = a * c - b * b
            if not abs(det) > 2.220446049250313e-16**2:  # NaN too
                st = 2
                break
            nx = cx + (c * bb1 - b * bb2) / det
            ny = cy + (-b * bb1 + a * bb2) / det
            if not (np.isfinite(nx) and np.isfinite(ny)):  # stop on NaN/inf: start kept
                cx = sx
                cy = sy
                st = 2
                break
            step = (nx - cx) ** 2 + (ny - cy) ** 2
            cx = nx
            cy = ny
            if cx < 0 or cx >= width or cy < 0 or cy >= height:
                st = 3
                break
            if step <= eps2:
                st = 0
                break
        if abs(cx - sx) > hx or abs(cy - sy) > hy:
            cx = sx
            cy = sy
            st = 4
        out[k, 0] = cx
        out[k, 1] = cy
        status[k] = st
    return out, status


def refine_corners_numpy(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    hx: int,
    hy: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Plain NumPy twin of :func:`refine_corners_numba` (all corners at once)."""
    height, width = image.shape
    n = corners.shape[0]
    mask = corner_window_weights(hx, hy)
    py, px = np.mgrid[-hy : hy + 1, -hx : hx + 1].astype(np.float64)
    oy = np.arange(-hy - 1, hy + 2)
    ox = np.arange(-hx - 1, hx + 2)
    cur = corners.astype(np.float64).copy()
    start = cur.copy()
    status = np.ones(n, dtype=np.int64)
    active: NDArray[np.bool_] = np.all(np.isfinite(cur), axis=1)  # non-finite: nothing to refine
    status[~active] = 2
    eps2 = eps * eps
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        c = cur[idx]
        # clamped before the integer cast, as in the kernel (no sample changes)
        lo = np.array([-hx - 2.0, -hy - 2.0])
        hi = np.array([width + hx + 1.0, height + hy + 1.0])
        f = np.floor(np.clip(c, lo, hi))
        ax = (c[:, 0] - f[:, 0])[:, None, None]
        ay = (c[:, 1] - f[:, 1])[:, None, None]
        ys = f[:, 1].astype(np.int64)[:, None] + oy[None, :]
        xs = f[:, 0].astype(np.int64)[:, None] + ox[None, :]
        ya = np.clip(ys, 0, height - 1)[:, :, None]
        yb = np.clip(ys + 1, 0, height - 1)[:, :, None]
        xa = np.clip(xs, 0, width - 1)[:, None, :]
        xb = np.clip(xs + 1, 0, width - 1)[:, None, :]
        patch = (1.0 - ay) * ((1.0 - ax) * image[ya, xa] + ax * image[ya, xb]) + ay * (
            (1.0 - ax) * image[yb, xa] + ax * image[yb, xb]
        )
        gx = patch[:, 1:-1, 2:] - patch[:, 1:-1, :-2]
        gy = patch[:, 2:, 1:-1] - patch[:, :-2, 1:-1]
        gxx = gx * gx * mask
        gxy = gx * gy * mask
        gyy = gy * gy * mask
        a = gxx.sum(axis=(1, 2))
        b = gxy.sum(axis=(1, 2))
        cc = gyy.sum(axis=(1, 2))
        bb1 = (gxx * px + gxy * py).sum(axis=(1, 2))
        bb2 = (gxy * px + gyy * py).sum(axis=(1, 2))
        det = a * cc - b * b
        singular = ~(np.abs(det) > np.finfo(np.float64).eps ** 2)  # NaN too
        safe = np.where(singular, 1.0, det)
        with np.errstate(all="ignore"):
            nx = c[:, 0] + (cc * bb1 - b * bb2) / safe
            ny = c[:, 1] + (-b * bb1 + a * bb2) / safe
        bad = ~singular & ~(np.isfinite(nx) & np.isfinite(ny))  # stop on NaN: start kept
        cur[idx[bad]] = start[idx[bad]]
        singular |= bad
        step = (nx - c[:, 0]) ** 2 + (ny - c[:, 1]) ** 2
        moved = ~singular
        cur[idx[moved], 0] = nx[moved]
        cur[idx[moved], 1] = ny[moved]
        outside = moved & ((nx < 0) | (nx >= width) | (ny < 0) | (ny >= height))
        done = moved & ~outside & (step <= eps2)
        status[idx[singular]] = 2
        status[idx[outside]] = 3
        status[idx[done]] = 0
        active[idx[singular | outside | done]] = False
    with np.errstate(invalid="ignore"):
        far = (np.abs(cur[:, 0] - start[:, 0]) > hx) | (np.abs(cur[:, 1] - start[:, 1]) > hy)
    cur[far] = start[far]
    status[far] = 4
    return cur, status


def gaussian_weights(sigma: float, truncate: float = 3.0) -> NDArray[np.float64]:
    """Normalised 1-D Gaussian taps ``exp(-x²/(2σ²))``, radius ``int(truncate σ + 0.5)``.

    The same taps as :func:`scipy.ndimage.gaussian_filter` with this ``truncate``.
    """
    radius = int(truncate * sigma + 0.5)
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-0.5 * (x / sigma) ** 2)
    return w / w.sum()


@njit(fastmath=False)
def smooth_saddle_numba(
    gray: NDArray[np.floating], taps: NDArray[np.floating]
) -> tuple[NDArray[np.floating], NDArray[np.floating]]:  # pragma: no cover - numba-compiled
    """Separable Gaussian (edges replicated) and the saddle response ``I_uv² - I_uu I_vv``.

    Computes in the dtype of ``gray`` (the detector passes float32: 5x faster than float64).
    """
    h, w = gray.shape
    r = taps.shape[0] // 2
    pad = np.empty((h + 2 * r, w + 2 * r), dtype=gray.dtype)
    for y in range(h + 2 * r):
        yy = min(max(y - r, 0), h - 1)
        for x in range(w + 2 * r):
            xx = min(max(x - r, 0), w - 1)
            pad[y, x] = gray[yy, xx]
    tmp = np.zeros((h + 2 * r, w), dtype=gray.dtype)
    for y in range(h + 2 * r):
        for k in range(2 * r + 1):
            wk = taps[k]
            for x in range(w):
                tmp[y, x] += wk * pad[y, x + k]
    smooth = np.zeros((h, w), dtype=gray.dtype)
    for y in range(h):
        for k in range(2 * r + 1):
            wk = taps[k]
            for x in range(w):
                smooth[y, x] += wk * tmp[y + k, x]
    resp = np.zeros((h, w), dtype=gray.dtype)
    for y in range(1, h - 1):
        for x in range(1, w - 1):
            s = smooth[y, x]
            ixx = smooth[y, x + 1] - 2.0 * s + smooth[y, x - 1]
            iyy = smooth[y + 1, x] - 2.0 * s + smooth[y - 1, x]
            ixy = 0.25 * (
                smooth[y + 1, x + 1]
                - smooth[y + 1, x - 1]
                - smooth[y - 1, x + 1]
                + smooth[y - 1, x - 1]
            )
            resp[y, x] = ixy * ixy - ixx * iyy
    return smooth, resp


def smooth_saddle_numpy(
    gray: NDArray[np.floating], taps: NDArray[np.floating]
) -> tuple[NDArray[np.floating], NDArray[np.floating]]:
    """Plain twin of :func:`smooth_saddle_numba` (scipy.ndimage separable correlation)."""
    from scipy import ndimage

    taps = taps.astype(gray.dtype)
    tmp = ndimage.correlate1d(gray, taps, axis=1, mode="nearest")
    s = ndimage.correlate1d(tmp, taps, axis=0, mode="nearest")
    resp = np.zeros_like(s)
    c = s[1:-1, 1:-1]
    ixx = s[1:-1, 2:] - 2.0 * c + s[1:-1, :-2]
    iyy = s[2:, 1:-1] - 2.0 * c + s[:-2, 1:-1]
    ixy = 0.25 * (s[2:, 2:] - s[2:, :-2] - s[:-2, 2:] + s[:-2, :-2])
    resp[1:-1, 1:-1] = ixy * ixy - ixx * iyy
    return s, resp


@njit(fastmath=False)
def local_maxima_numba(
    resp: NDArray[np.floating], radius: int, threshold: float, border: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:  # pragma: no cover - numba-compiled
    """Rows and columns of pixels ``> threshold`` and ``>=`` all others in their window."""
    h, w = resp.shape
    ys = []
    xs = []
    for y in range(border, h - border):
        for x in range(border, w - border):
            v = resp[y, x]
            if v <= threshold:
                continue
            # quick rejection by the 4-neighbours before the full window
            if resp[y, x - 1] > v or resp[y, x + 1] > v or resp[y - 1, x] > v or resp[y + 1, x] > v:
                continue
            keep = True
            for yy in range(max(y - radius, 0), min(y + radius + 1, h)):
                for xx in range(max(x - radius, 0), min(x + radius + 1, w)):
                    if resp[yy, xx] > v:
                        keep = False
                        break
                if not keep:
                    break
            if keep:
                ys.append(y)
                xs.append(x)
    return np.array(ys, dtype=np.int64), np.array(xs, dtype=np.int64)


def local_maxima_numpy(
    resp: NDArray[np.floating], radius: int, threshold: float, border: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Plain twin of :func:`local_maxima_numba` (scipy.ndimage.maximum_filter)."""
    from scipy import ndimage

    local_max = ndimage.maximum_filter(resp, size=2 * radius + 1, mode="nearest")
    mask = (resp >= local_max) & (resp > threshold)
    mask[:border] = False
    mask[resp.shape[0] - border :] = False
    mask[:, :border] = False
    mask[:, resp.shape[1] - border :] = False
    ys, xs = np.nonzero(mask)
    return ys.astype(np.int64), xs.astype(np.int64)


@njit(fastmath=False)
def sample_bilinear_numba(
    image: NDArray[np.floating], u: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:  # pragma: no cover - numba-compiled
    """Bilinear samples of ``image`` at ``(u, v)`` (any equal shapes), edges replicated."""
    h, w = image.shape
    uf = u.ravel()
    vf = v.ravel()
    out = np.empty(uf.size)
    for k in range(uf.size):
        x = min(max(uf[k], 0.0), w - 1.0)
        y = min(max(vf[k], 0.0), h - 1.0)
        x0 = min(int(np.floor(x)), w - 2) if w > 1 else 0
        y0 = min(int(np.floor(y)), h - 2) if h > 1 else 0
        ax = x - x0
        ay = y - y0
        x1 = min(x0 + 1, w - 1)
        y1 = min(y0 + 1, h - 1)
        out[k] = (1.0 - ay) * ((1.0 - ax) * image[y0, x0] + ax * image[y0, x1]) + ay * (
            (1.0 - ax) * image[y1, x0] + ax * image[y1, x1]
        )
    return out.reshape(u.shape)


def sample_bilinear_numpy(
    image: NDArray[np.floating], u: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Plain twin of :func:`sample_bilinear_numba` (scipy.ndimage.map_coordinates, order 1)."""
    from scipy import ndimage

    vals = ndimage.map_coordinates(
        np.asarray(image, dtype=np.float64), [v.ravel(), u.ravel()], order=1, mode="nearest"
    )
    return vals.reshape(u.shape)
