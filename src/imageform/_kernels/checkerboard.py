r"""numba kernels of the checkerboard detector, each with a plain NumPy/SciPy twin.

- :func:`saddle_maxima_numba` / :func:`saddle_maxima_numpy`: separable Gaussian smoothing
  (edges replicated, the taps of :func:`gaussian_weights`), the saddle response
  ``I_uv² - I_uu I_vv`` by central differences and its local maxima, in one pass (the twin
  is :func:`smooth_saddle_numpy` then :func:`local_maxima_numpy`: pixels above a threshold
  and not below any pixel of their ``(2 r + 1)²`` window).
- :func:`ring_test_numba` / :func:`ring_test_numpy`: the four-sector ring test and the edge
  directions of each candidate.
- :func:`neighbors_numba` / :func:`neighbors_numpy`: each candidate's grid neighbours along
  its edge directions.
- :func:`lattice_problem_numba` (twin: ``checkerboard_grid.lattice_problem``): the
  lattice checks of a grid.
- :func:`lattice_rectangle_numba` (twin: ``checkerboard_grid.label_lattice`` then
  ``grow_rectangle``): the lattice labels from a seed and the largest complete rectangle.
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
test_checkerboard_kernels.py): refinement 1e-9 px, smoothing 1e-6, the same local maxima
(response 1e-4 of its peak), the same ring-test verdicts (directions 1e-9), the same
neighbours and rectangles, samples 1e-12.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit

__all__ = [
    "SaddleMaxima",
    "corner_window_weights",
    "gaussian_weights",
    "lattice_problem_numba",
    "lattice_rectangle_numba",
    "local_maxima_numpy",
    "neighbors_numba",
    "neighbors_numpy",
    "refine_corners_numba",
    "refine_corners_numpy",
    "ring_test_numba",
    "ring_test_numpy",
    "saddle_maxima_numba",
    "saddle_maxima_numpy",
    "sample_bilinear_numba",
    "sample_bilinear_numpy",
    "smooth_saddle_numpy",
]


def corner_window_weights(hx: int, hy: int) -> NDArray[np.float64]:
    """Return the ``(2 hy + 1, 2 hx + 1)`` Gaussian window ``exp(-(x/hx)²) exp(-(y/hy)²)``."""
    y = np.arange(-hy, hy + 1, dtype=np.float64) / hy
    x = np.arange(-hx, hx + 1, dtype=np.float64) / hx
    return np.exp(-(y**2))[:, None] * np.exp(-(x**2))[None, :]


def refine_corners_numba(
    image: NDArray[np.floating],
    corners: NDArray[np.float64],
    hx: int,
    hy: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Refine ``corners`` (N, 2) in ``(u, v)``; returns the refined corners and a status.

    A float32 ``image`` is passed to the compiled kernel (:func:`_refine_corners`) beside an
    empty float64 one, a float64 image beside an empty float32 one: one compilation serves
    both (``characterize`` refines on both; each specialisation costs seconds on a first
    run). Other dtypes are read as float64.
    """
    if image.dtype == np.float32:
        return _refine_corners(image, _EMPTY64, True, corners, hx, hy, max_iter, eps)
    img64 = np.ascontiguousarray(image, dtype=np.float64)
    return _refine_corners(_EMPTY32, img64, False, corners, hx, hy, max_iter, eps)


_EMPTY32 = np.empty((0, 0), dtype=np.float32)
_EMPTY64 = np.empty((0, 0), dtype=np.float64)


@njit(fastmath=False)
def _refine_corners(
    image32: NDArray[np.float32],
    image64: NDArray[np.float64],
    is32: bool,
    corners: NDArray[np.float64],
    hx: int,
    hy: int,
    max_iter: int,
    eps: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # pragma: no cover - numba-compiled
    """:func:`refine_corners_numba`'s kernel: ``image32`` if ``is32``, else ``image64``.

    The values are used as float64 either way: the same numbers.
    """
    n = corners.shape[0]
    height, width = image32.shape if is32 else image64.shape
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
    patch = np.empty((wh + 2, ww + 2))
    # rows of the patch interpolated along u only: patch row i blends rows i and i + 1
    # (the clamped image rows y0 + i and y0 + i + 1), so each image row is read once
    hrow = np.empty((wh + 3, ww + 2))
    xcol = np.empty(ww + 3, dtype=np.int64)
    for k in range(n):
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
            # the dtype tested outside the row loops (inside them, 1.17x the time)
            if is32:
                _blend_rows(image32, x0, y0, ax, hrow, xcol)
            else:
                _blend_rows(image64, x0, y0, ax, hrow, xcol)
            for i in range(wh + 2):
                for j in range(ww + 2):
                    patch[i, j] = (1.0 - ay) * hrow[i, j] + ay * hrow[i + 1, j]
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


@njit(fastmath=False, inline="always")  # inlined: as a call, 1.03x the time
def _blend_rows(
    image: NDArray[np.floating],
    x0: int,
    y0: int,
    ax: float,
    hrow: NDArray[np.float64],
    xcol: NDArray[np.int64],
) -> None:  # pragma: no cover - numba-compiled
    """Blend image rows ``y0 + i`` (clamped) along u at ``x0 + j + ax`` into ``hrow[i, j]``.

    :func:`_refine_corners`'s rows (``hrow`` is ``(wh + 3, ww + 2)``; ``xcol`` holds
    ``ww + 3`` column indices), edge pixels replicated, for a float32 or a float64 image (read
    as float64: the same numbers). A window inside the image is read contiguously, without
    clamping (the same numbers).
    """
    height, width = image.shape
    wh = hrow.shape[0] - 3
    ww = hrow.shape[1] - 2
    bx = 1.0 - ax
    if x0 >= 0 and x0 + ww + 2 <= width - 1:
        for i in range(wh + 3):
            r = image[min(max(y0 + i, 0), height - 1), x0 : x0 + ww + 3]
            hr = hrow[i]
            for j in range(ww + 2):
                hr[j] = bx * r[j] + ax * r[j + 1]
        return
    for j in range(ww + 3):
        xcol[j] = min(max(x0 + j, 0), width - 1)
    for i in range(wh + 3):
        r = image[min(max(y0 + i, 0), height - 1)]
        hr = hrow[i]
        for j in range(ww + 2):
            hr[j] = bx * r[xcol[j]] + ax * r[xcol[j + 1]]


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


#: ``(smooth, peak, ys, xs, values)`` of :func:`saddle_maxima_numba` and its twin: the smoothed
#: image, the largest response, the maxima's rows and columns and their 3 x 3 neighbourhoods.
SaddleMaxima = tuple[
    NDArray[np.floating], float, NDArray[np.int64], NDArray[np.int64], NDArray[np.floating]
]


def saddle_maxima_numba(
    gray: NDArray[np.number],
    taps: NDArray[np.floating],
    radius: int,
    border: int,
    relative: float,
    scale: float | np.floating,
) -> SaddleMaxima:
    """Smoothing, saddle response and its local maxima in one pass over the image.

    ``gray`` is passed to the compiled kernel (:func:`_saddle_maxima`) beside an empty array
    of the other kind, 8-bit or not, so that one compilation serves the 8-bit images
    (``calibrate``) and the float32 ones (``characterize``): each specialisation costs
    seconds of compilation on a first run. A ``border`` under 1 is taken as 1: the response
    is 0 on the outer pixel ring, never above the threshold of a ``relative`` >= 0 (the same
    maxima and peak).
    """
    border = max(int(border), 1)  # the kernel reads each tested pixel's left neighbour
    if gray.dtype == np.uint8:
        other = np.empty((0, 0), dtype=taps.dtype)
        return _saddle_maxima(gray, other, True, taps, radius, border, relative, scale)
    u8 = np.empty((0, 0), dtype=np.uint8)
    return _saddle_maxima(u8, gray, False, taps, radius, border, relative, scale)


@njit(fastmath=False)
def _saddle_maxima(
    gray8: NDArray[np.uint8],
    grayf: NDArray[np.number],
    is8: bool,
    taps: NDArray[np.floating],
    radius: int,
    border: int,
    relative: float,
    scale: float | np.floating,
) -> SaddleMaxima:  # pragma: no cover - numba-compiled
    """:func:`saddle_maxima_numba`'s kernel: ``gray`` is ``gray8`` if ``is8`` else ``grayf``.

    The image read is ``gray / scale`` in the dtype of ``taps`` (``gray`` as given: uint8
    codes with ``scale`` 255 give, bit for bit, the values of ``gray.astype(float32) / 255``
    without that array). The smoothed image is the separable Gaussian of
    :func:`smooth_saddle_numpy` (edges replicated) and the response ``I_uv² - I_uu I_vv``
    its central second differences (0 on the outer pixel ring), in the dtype of ``taps``,
    with the operations of the twin in its order. The response is never stored whole: it
    is computed row by row into a ring of ``2 radius + 1`` rows, and the maxima of the
    ``(2 radius + 1)²`` windows (the rule of :func:`local_maxima_numpy`, pixels at least
    ``border`` from the edge) are taken from the ring as soon as their window is complete;
    the horizontal pass lives in a ring of ``len(taps)`` rows. Only the smoothed image is
    allocated whole (each full-size temporary costs its page faults, which at 640 x 480
    cost more than the arithmetic).

    Returns ``(smooth, peak, ys, xs, values)``: ``peak`` the largest response (0 when none
    is positive) and, in row-major order, every maximum above ``relative`` times the peak
    (kept against the running peak, so possibly some more: the caller applies the final
    threshold), with its 3 x 3 neighbourhood ``values`` ``(M, 3, 3)`` for the sub-pixel
    peak.
    """
    h, w = gray8.shape if is8 else grayf.shape
    r = taps.shape[0] // 2
    n = 2 * r + 1
    dt = taps.dtype
    smooth = np.empty((h, w), dtype=dt)
    hring = np.empty((n, w), dtype=dt)  # horizontal pass, row y at y % n
    row = np.empty(w + 2 * r, dtype=dt)
    nr = 2 * radius + 1
    rring = np.zeros((nr, w), dtype=dt)  # response, row y at y % nr
    wrows = np.empty(nr, dtype=np.int64)  # ring rows of a window
    nwords = (w + 7) // 8
    flag = np.zeros(8 * nwords, dtype=np.uint8)
    words = flag.view(np.uint64)
    rel = min(relative, 1.0)
    ys = np.empty(1024, dtype=np.int64)
    xs = np.empty(1024, dtype=np.int64)
    vals = np.empty((1024, 3, 3), dtype=dt)
    count = 0
    # the peak: the largest response is a maximum of its window, found below, unless it lies
    # within ``border`` of the edge, where no maximum is sought: that frame is scanned here
    peak = 0.0
    next_h = 0  # next row of the horizontal pass
    for y in range(h + radius + 1):
        if y < h:
            # horizontal pass up to row y + r (clamped): the window of smooth row y
            last = min(y + r, h - 1)
            while next_h <= last:
                if is8:  # converted to the working dtype
                    for x in range(w):
                        row[x + r] = gray8[next_h, x]
                else:
                    for x in range(w):
                        row[x + r] = grayf[next_h, x]
                for x in range(w):
                    # one division, correctly rounded in the working dtype whatever the
                    # type of scale (a float32 quotient computed in float64 rounds the same)
                    row[x + r] = row[x + r] / scale
                for x in range(r):
                    row[x] = row[r]
                    row[w + r + x] = row[w + r - 1]
                out = hring[next_h % n]
                w0 = taps[0]
                for x in range(w):
                    out[x] = w0 * row[x]
                # the taps four at a time, added in their order (the same sums, bit for bit;
                # a quarter of the loads and stores of ``out``)
                k = 1
                while k + 3 < n:
                    wa, wb, wc, wz = taps[k], taps[k + 1], taps[k + 2], taps[k + 3]
                    ra, rb, rc, rd = row[k:], row[k + 1 :], row[k + 2 :], row[k + 3 :]
                    for x in range(w):
                        out[x] = out[x] + wa * ra[x] + wb * rb[x] + wc * rc[x] + wz * rd[x]
                    k += 4
                while k < n:
                    wa = taps[k]
                    ra = row[k:]
                    for x in range(w):
                        out[x] += wa * ra[x]
                    k += 1
                next_h += 1
            # vertical pass: smooth row y
            srow = smooth[y]
            w0 = taps[0]
            src = hring[max(y - r, 0) % n]
            for x in range(w):
                srow[x] = w0 * src[x]
            k = 1
            while k + 3 < n:  # four rows at a time, as the horizontal pass
                sa = hring[min(max(y + k - r, 0), h - 1) % n]
                sb = hring[min(max(y + k + 1 - r, 0), h - 1) % n]
                sc = hring[min(max(y + k + 2 - r, 0), h - 1) % n]
                sd = hring[min(max(y + k + 3 - r, 0), h - 1) % n]
                wa, wb, wc, wz = taps[k], taps[k + 1], taps[k + 2], taps[k + 3]
                for x in range(w):
                    srow[x] = srow[x] + wa * sa[x] + wb * sb[x] + wc * sc[x] + wz * sd[x]
                k += 4
            while k < n:
                wa = taps[k]
                src = hring[min(max(y + k - r, 0), h - 1) % n]
                for x in range(w):
                    srow[x] += wa * src[x]
                k += 1
        # response row y - 1 (its three smooth rows exist now); rows 0 and h - 1 stay 0
        yr = y - 1
        if 0 <= yr < h:
            o = rring[yr % nr]
            if yr == 0 or yr == h - 1:
                o[:] = 0.0
            else:
                a = smooth[yr - 1]
                b = smooth[yr]
                c = smooth[yr + 1]
                o[0] = 0.0
                o[w - 1] = 0.0
                for x in range(1, w - 1):
                    s = b[x]
                    ixx = b[x + 1] - 2.0 * s + b[x - 1]
                    iyy = c[x] - 2.0 * s + a[x]
                    ixy = 0.25 * (c[x + 1] - c[x - 1] - a[x + 1] + a[x - 1])
                    o[x] = ixy * ixy - ixx * iyy
            # the frame where no maximum is sought still counts for the peak
            if yr < border or yr >= h - border:
                for x in range(w):
                    if o[x] > peak:
                        peak = o[x]
            else:
                for x in range(min(border, w)):
                    if o[x] > peak:
                        peak = o[x]
                for x in range(max(w - border, 0), w):
                    if o[x] > peak:
                        peak = o[x]
        # maxima of row yc = yr - radius: its window rows yc - radius .. yr are in the ring
        yc = yr - radius
        if yc < border or yc >= h - border:
            continue
        cur = rring[yc % nr]
        above = rring[(yc - 1) % nr]
        below = rring[(yc + 1) % nr]
        # the running threshold (a lower one than the final): the running peak itself is
        # always looked at, so that it ends as the true peak
        thr = rel * peak
        # branch-free first test (above the threshold, not below its 4 neighbours) into
        # bytes read 8 at a time, then the whole window for the few that pass; on views
        # that start at the row's first tested pixel, indexed from 0 (an index that may be
        # negative is wrapped around per element, which keeps the loop from vectorising)
        cl = cur[border - 1 :]
        c0 = cur[border:]
        cr = cur[border + 1 :]
        ab = above[border:]
        be = below[border:]
        fl = flag[border:]
        for i in range(w - 2 * border):
            v = c0[i]
            fl[i] = np.uint8((v > thr) & (v >= cl[i]) & (v >= cr[i]) & (v >= ab[i]) & (v >= be[i]))
        y_lo = max(yc - radius, 0)
        y_hi = min(yc + radius + 1, h)
        for i in range(y_hi - y_lo):
            wrows[i] = (y_lo + i) % nr
        for wd in range(nwords):
            if words[wd] == 0:
                continue
            for x in range(max(8 * wd, border), min(8 * wd + 8, w - border)):
                if flag[x] == 0:
                    continue
                v = cur[x]
                keep = True
                x_lo = max(x - radius, 0)
                x_hi = min(x + radius + 1, w)
                for i in range(y_hi - y_lo):
                    rr = rring[wrows[i]]
                    for xx in range(x_lo, x_hi):
                        if rr[xx] > v:
                            keep = False
                            break
                    if not keep:
                        break
                if not keep:
                    continue
                if v > peak:
                    peak = v
                if count == ys.shape[0]:
                    ys2 = np.empty(2 * count, dtype=np.int64)
                    xs2 = np.empty(2 * count, dtype=np.int64)
                    vals2 = np.empty((2 * count, 3, 3), dtype=dt)
                    # element loops, not slice copies: numba 0.68 compiles an f-string
                    # shape message for each array-to-slice copy (seconds on a first run)
                    for i in range(count):
                        ys2[i] = ys[i]
                        xs2[i] = xs[i]
                        for j in range(3):
                            for jj in range(3):
                                vals2[i, j, jj] = vals[i, j, jj]
                    ys, xs, vals = ys2, xs2, vals2
                ys[count] = yc
                xs[count] = x
                for j in range(3):
                    vals[count, 0, j] = above[x - 1 + j]
                    vals[count, 1, j] = cur[x - 1 + j]
                    vals[count, 2, j] = below[x - 1 + j]
                count += 1
    return smooth, peak, ys[:count].copy(), xs[:count].copy(), vals[:count].copy()


def saddle_maxima_numpy(
    gray: NDArray[np.number],
    taps: NDArray[np.floating],
    radius: int,
    border: int,
    relative: float,
    scale: float | np.floating,
) -> SaddleMaxima:
    """Plain twin of :func:`saddle_maxima_numba`: all maxima above ``relative`` times the peak."""
    smooth, resp = smooth_saddle_numpy(gray.astype(taps.dtype) / taps.dtype.type(scale), taps)
    peak = max(float(resp.max()), 0.0)
    ys, xs = local_maxima_numpy(resp, radius, relative * peak, border)
    iy = ys[:, None, None] + np.arange(-1, 2)[None, :, None]
    ix = xs[:, None, None] + np.arange(-1, 2)[None, None, :]
    return smooth, peak, ys, xs, resp[iy, ix]


def smooth_saddle_numpy(
    gray: NDArray[np.floating], taps: NDArray[np.floating]
) -> tuple[NDArray[np.floating], NDArray[np.floating]]:
    """Separable Gaussian (edges replicated) and the saddle response (scipy.ndimage)."""
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


def local_maxima_numpy(
    resp: NDArray[np.floating], radius: int, threshold: float, border: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pixels ``> threshold`` and ``>=`` all others in their window (scipy maximum_filter)."""
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
    uf = u.ravel()
    vf = v.ravel()
    out = np.empty(uf.size)
    for k in range(uf.size):
        out[k] = _bilinear_clamped(image, uf[k], vf[k])
    return out.reshape(u.shape)


@njit(fastmath=False, inline="always")
def _bilinear_clamped(
    image: NDArray[np.floating], x: float, y: float
) -> float:  # pragma: no cover - numba-compiled
    """Bilinear sample of ``image`` at ``(x, y)``, edges replicated (inlined by its callers)."""
    h, w = image.shape
    x = min(max(x, 0.0), w - 1.0)
    y = min(max(y, 0.0), h - 1.0)
    x0 = min(int(np.floor(x)), w - 2) if w > 1 else 0
    y0 = min(int(np.floor(y)), h - 2) if h > 1 else 0
    ax = x - x0
    ay = y - y0
    x1 = min(x0 + 1, w - 1)
    y1 = min(y0 + 1, h - 1)
    return (1.0 - ay) * ((1.0 - ax) * image[y0, x0] + ax * image[y0, x1]) + ay * (
        (1.0 - ax) * image[y1, x0] + ax * image[y1, x1]
    )


def sample_bilinear_numpy(
    image: NDArray[np.floating], u: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Plain twin of :func:`sample_bilinear_numba` (scipy.ndimage.map_coordinates, order 1)."""
    from scipy import ndimage

    vals = ndimage.map_coordinates(
        np.asarray(image, dtype=np.float64), [v.ravel(), u.ravel()], order=1, mode="nearest"
    )
    return vals.reshape(u.shape)


@njit(fastmath=False)
def ring_test_numba(
    smooth: NDArray[np.floating],
    xy: NDArray[np.float64],
    offsets: NDArray[np.float64],
    min_contrast: float,
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:  # pragma: no cover
    """Run the ring test of ``checkerboard_candidates.ring_test`` on each point of ``xy`` (N, 2).

    ``offsets`` (S, 2) are the ring's sample offsets. Per point: the bilinear samples
    (edges replicated, as :func:`sample_bilinear_numba`), their mid level
    ``(min + max) / 2``, the crossings of the mid level between consecutive samples; a
    point passes with exactly four crossings, contrast ``max - min >= min_contrast``, every
    sector at least two samples wide and edge directions (the lines through opposite
    crossings, interpolated linearly) not within ``asin 0.3`` of parallel. The same
    operations in the same order as the twin. Returns ``(ok, dirs (N, 2, 2), contrast)``.
    """
    n = xy.shape[0]
    ns = offsets.shape[0]
    h, w = smooth.shape
    ok = np.zeros(n, dtype=np.bool_)
    dirs = np.zeros((n, 2, 2))
    contrast = np.empty(n)
    vals = np.empty(ns)
    ks = np.empty(4, dtype=np.int64)
    theta = np.empty(4)
    # the ring's extent: a point whose ring lies inside the image, away from its last row
    # and column, is sampled without the clamps (which change nothing there)
    reach = 0.0
    for s in range(ns):
        reach = max(reach, abs(offsets[s, 0]), abs(offsets[s, 1]))
    for p in range(n):
        px = xy[p, 0]
        py = xy[p, 1]
        if (
            px - reach >= 1.0
            and px + reach <= w - 3.0
            and py - reach >= 1.0
            and py + reach <= h - 3.0
        ):
            for s in range(ns):
                x = px + offsets[s, 0]
                y = py + offsets[s, 1]
                x0 = int(np.floor(x))
                y0 = int(np.floor(y))
                ax = x - x0
                ay = y - y0
                vals[s] = (1.0 - ay) * (
                    (1.0 - ax) * smooth[y0, x0] + ax * smooth[y0, x0 + 1]
                ) + ay * ((1.0 - ax) * smooth[y0 + 1, x0] + ax * smooth[y0 + 1, x0 + 1])
        else:
            for s in range(ns):
                vals[s] = _bilinear_clamped(smooth, px + offsets[s, 0], py + offsets[s, 1])
        lo = vals[0]
        hi = vals[0]
        for s in range(1, ns):
            lo = min(lo, vals[s])
            hi = max(hi, vals[s])
        contrast[p] = hi - lo
        mid = 0.5 * (lo + hi)
        count = 0
        for s in range(ns):
            s1 = s + 1 if s + 1 < ns else 0
            if (vals[s] > mid) != (vals[s1] > mid):
                if count < 4:
                    ks[count] = s
                count += 1
        if count != 4 or not contrast[p] >= min_contrast:
            continue
        wide = True
        for i in range(4):
            k = ks[i]
            nxt = ks[i + 1] if i < 3 else ks[0] + ns
            if nxt - k < 2:
                wide = False
            v0 = vals[k] - mid
            v1 = vals[k + 1 if k + 1 < ns else 0] - mid
            frac = v0 / (v0 - v1)
            theta[i] = 2.0 * np.pi * (k + frac) / ns
        d1x = np.cos(theta[0]) - np.cos(theta[2])
        d1y = np.sin(theta[0]) - np.sin(theta[2])
        d2x = np.cos(theta[1]) - np.cos(theta[3])
        d2y = np.sin(theta[1]) - np.sin(theta[3])
        n1 = np.sqrt(d1x * d1x + d1y * d1y)
        n2 = np.sqrt(d2x * d2x + d2y * d2y)
        d1x /= n1
        d1y /= n1
        d2x /= n2
        d2y /= n2
        dirs[p, 0, 0] = d1x
        dirs[p, 0, 1] = d1y
        dirs[p, 1, 0] = d2x
        dirs[p, 1, 1] = d2y
        ok[p] = wide and abs(d1x * d2y - d1y * d2x) > 0.3
    return ok, dirs, contrast


@njit(fastmath=False)
def neighbors_numba(
    xy: NDArray[np.float64],
    dirs: NDArray[np.float64],
    min_dist: float,
    k_nearest: int,
    cos_tol: float,
) -> NDArray[np.int64]:  # pragma: no cover - numba-compiled
    """Neighbour table ``(N, 2, 2)`` of ``checkerboard_grid.neighbors``, by brute force.

    ``[a, k, s]`` is the nearest point ``b`` among the ``k_nearest`` nearest of ``a`` that
    lies farther than ``min_dist``, within ``acos(cos_tol)`` of ``(+d_k, -d_k)[s]`` (``a``'s
    edge direction ``k``) and has an edge direction of its own along the joining vector;
    -1 when none. Links that are not mutual are dropped. Equal distances are taken in index
    order (the twin takes them in its k-d tree's order: only exact ties can differ).
    """
    n = xy.shape[0]
    out = np.full((n, 2, 2), -1, dtype=np.int64)
    if n < 2:
        return out
    kq = min(n, k_nearest + 1) - 1  # others considered
    d2 = np.empty(n)
    near = np.empty(kq)  # the kq smallest squared distances so far, ascending
    best = np.empty(4, dtype=np.int64)
    best_d = np.empty(4)
    for a in range(n):
        xa = xy[a, 0]
        ya = xy[a, 1]
        for b in range(n):
            dx = xy[b, 0] - xa
            dy = xy[b, 1] - ya
            d2[b] = dx * dx + dy * dy
        d2[a] = np.inf
        # the kq-th smallest squared distance (insertion into a short sorted list: most
        # points are farther than the current kq-th and cost one comparison)
        near[:] = np.inf
        for b in range(n):
            v = d2[b]
            if v < near[kq - 1]:
                i = kq - 1
                while i > 0 and near[i - 1] > v:
                    near[i] = near[i - 1]
                    i -= 1
                near[i] = v
        limit = near[kq - 1]
        best[:] = -1
        best_d[:] = np.inf
        for b in range(n):
            if not d2[b] <= limit:  # not among the kq nearest (ties at the limit are)
                continue
            dx = xy[b, 0] - xa
            dy = xy[b, 1] - ya
            d = np.sqrt(d2[b])
            if not d > min_dist:
                continue
            ux = dx / d
            uy = dy / d
            e0 = abs(ux * dirs[b, 0, 0] + uy * dirs[b, 0, 1])
            e1 = abs(ux * dirs[b, 1, 0] + uy * dirs[b, 1, 1])
            if not max(e0, e1) > cos_tol:
                continue
            for k in range(2):
                along = ux * dirs[a, k, 0] + uy * dirs[a, k, 1]
                for s in range(2):
                    if (along if s == 0 else -along) > cos_tol and d < best_d[2 * k + s]:
                        best_d[2 * k + s] = d
                        best[2 * k + s] = b
        for i in range(4):
            out[a, i // 2, i % 2] = best[i]
    # keep mutual links only: b must list a among its own neighbours
    keep = np.zeros((n, 2, 2), dtype=np.bool_)
    for a in range(n):
        for k in range(2):
            for s in range(2):
                b = out[a, k, s]
                if b < 0:
                    continue
                for k2 in range(2):
                    for s2 in range(2):
                        if out[b, k2, s2] == a:
                            keep[a, k, s] = True
    for a in range(n):
        for k in range(2):
            for s in range(2):
                if not keep[a, k, s]:
                    out[a, k, s] = -1
    return out


def ring_test_numpy(
    smooth: NDArray[np.floating],
    xy: NDArray[np.float64],
    offsets: NDArray[np.float64],
    min_contrast: float,
) -> tuple[NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64]]:
    """Plain NumPy twin of :func:`ring_test_numba` (all points at once)."""
    n = xy.shape[0]
    ns = offsets.shape[0]
    vals = sample_bilinear_numpy(
        smooth, xy[:, None, 0] + offsets[None, :, 0], xy[:, None, 1] + offsets[None, :, 1]
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
        v1 = vals[idx][rows, (k + 1) % ns] - mid[idx][:, None]
        frac = v0 / (v0 - v1)
        theta = 2.0 * np.pi * (k + frac) / ns
        # every sector must span at least two samples: rejects noise flips
        span = np.diff(np.concatenate([k, k[:, :1] + ns], axis=1), axis=1)
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


def neighbors_numpy(
    xy: NDArray[np.float64],
    dirs: NDArray[np.float64],
    min_dist: float,
    k_nearest: int,
    cos_tol: float,
) -> NDArray[np.int64]:
    """Plain twin of :func:`neighbors_numba` (the k nearest from a k-d tree)."""
    n = xy.shape[0]
    out = np.full((n, 2, 2), -1, dtype=np.int64)
    if n < 2:
        return out
    from scipy.spatial import cKDTree

    kq = min(n, k_nearest + 1)
    dist, idx = cKDTree(xy).query(xy, k=kq)
    dist, idx = dist[:, 1:], idx[:, 1:]  # drop self
    dx = xy[idx, 0] - xy[:, None, 0]
    dy = xy[idx, 1] - xy[:, None, 1]
    safe = np.where(dist > 0, dist, np.inf)
    ux, uy = dx / safe, dy / safe
    # the candidate b must have an edge along the joining vector (shared edge)
    db = dirs[idx]  # (N, K, 2, 2)
    shared = (
        np.maximum(
            np.abs(ux * db[..., 0, 0] + uy * db[..., 0, 1]),
            np.abs(ux * db[..., 1, 0] + uy * db[..., 1, 1]),
        )
        > cos_tol
    )
    usable = shared & (dist > min_dist)
    rows = np.arange(n)
    for k in range(2):
        along = ux * dirs[:, None, k, 0] + uy * dirs[:, None, k, 1]
        for s, sign in enumerate((1.0, -1.0)):
            d = np.where(usable & (sign * along > cos_tol), dist, np.inf)
            best = np.argmin(d, axis=1)
            found = np.isfinite(d[rows, best])
            out[found, k, s] = idx[rows, best][found]
    # keep mutual links only: b must list a among its own neighbours
    flat = out.reshape(n, 4)
    b = np.where(flat >= 0, flat, 0)
    mutual = np.any(flat[b] == np.arange(n)[:, None, None], axis=2)
    flat[~mutual] = -1
    return out


@njit(fastmath=False)
def lattice_rectangle_numba(
    seed: int,
    dirs: NDArray[np.float64],
    nbr: NDArray[np.int64],
    xy: NDArray[np.float64],
    max_hops: int,
    max_error: float,
) -> NDArray[np.int64]:  # pragma: no cover - numba-compiled
    """``checkerboard_grid.label_lattice`` then ``grow_rectangle``, in one kernel.

    The breadth-first lattice labels of the component of ``seed`` (the same walk, in the
    same order, with the same oriented bases and conflict rule), then the largest complete
    rectangle grown from the 3 x 3 block around ``(0, 0)``, one full row or column at a
    time, each new point within ``max_error`` grid steps of its linear prediction. Returns
    the node indices ``(n_i, n_j)``; ``(0, 0)`` when the 3 x 3 block is incomplete.
    """
    n = xy.shape[0]
    m = max_hops + 2  # labels reach |i| + |j| <= max_hops; the growth looks one further
    size = 2 * m + 1
    node_at = np.full((size, size), -1, dtype=np.int64)  # [i + m, j + m]
    ci = np.zeros(n, dtype=np.int64)
    cj = np.zeros(n, dtype=np.int64)
    seen = np.zeros(n, dtype=np.bool_)
    basis = np.empty((n, 4))
    queue = np.empty(n, dtype=np.int64)
    seen[seed] = True
    node_at[m, m] = seed
    basis[seed, 0] = dirs[seed, 0, 0]
    basis[seed, 1] = dirs[seed, 0, 1]
    basis[seed, 2] = dirs[seed, 1, 0]
    basis[seed, 3] = dirs[seed, 1, 1]
    queue[0] = seed
    head = 0
    tail = 1
    while head < tail:
        a = queue[head]
        head += 1
        eix = basis[a, 0]
        eiy = basis[a, 1]
        ejx = basis[a, 2]
        ejy = basis[a, 3]
        ia = ci[a]
        ja = cj[a]
        if abs(ia) + abs(ja) >= max_hops:
            continue
        for k in range(2):
            vx = dirs[a, k, 0]
            vy = dirs[a, k, 1]
            for s in range(2):
                b = nbr[a, k, s]
                if b < 0 or seen[b]:
                    continue
                sign = 1.0 if s == 0 else -1.0
                di = sign * (vx * eix + vy * eiy)
                dj = sign * (vx * ejx + vy * ejy)
                if abs(di) >= abs(dj):
                    ni = ia + (1 if di > 0 else -1)
                    nj = ja
                else:
                    ni = ia
                    nj = ja + (1 if dj > 0 else -1)
                if node_at[ni + m, nj + m] >= 0:
                    continue
                p0x = dirs[b, 0, 0]
                p0y = dirs[b, 0, 1]
                p1x = dirs[b, 1, 0]
                p1y = dirs[b, 1, 1]
                c0 = p0x * eix + p0y * eiy
                c1 = p1x * eix + p1y * eiy
                if abs(c0) >= abs(c1):
                    bix, biy, bjx, bjy, cc = p0x, p0y, p1x, p1y, c0
                else:
                    bix, biy, bjx, bjy, cc = p1x, p1y, p0x, p0y, c1
                si = 1.0 if cc >= 0 else -1.0
                sj = 1.0 if bjx * ejx + bjy * ejy >= 0 else -1.0
                seen[b] = True
                ci[b] = ni
                cj[b] = nj
                node_at[ni + m, nj + m] = b
                basis[b, 0] = si * bix
                basis[b, 1] = si * biy
                basis[b, 2] = sj * bjx
                basis[b, 3] = sj * bjy
                queue[tail] = b
                tail += 1
    for i in range(-1, 2):
        for j in range(-1, 2):
            if node_at[i + m, j + m] < 0:
                return np.zeros((0, 0), dtype=np.int64)
    limit2 = max_error * max_error
    i0, i1, j0, j1 = -1, 1, -1, 1
    grew = True
    while grew:
        grew = False
        # a new row i1 + 1 (predicted from rows i1, i1 - 1), then i0 - 1, over j0 .. j1
        for side in range(2):
            inew = i1 + 1 if side == 0 else i0 - 1
            step = -1 if side == 0 else 1
            fits = abs(inew) < m
            j = j0
            while fits and j <= j1:
                bn = node_at[inew + m, j + m]
                if bn < 0:
                    fits = False
                    break
                bl = node_at[inew + step + m, j + m]
                bp = node_at[inew + 2 * step + m, j + m]
                step2 = (xy[bl, 0] - xy[bp, 0]) ** 2 + (xy[bl, 1] - xy[bp, 1]) ** 2
                err2 = (xy[bn, 0] - 2.0 * xy[bl, 0] + xy[bp, 0]) ** 2 + (
                    xy[bn, 1] - 2.0 * xy[bl, 1] + xy[bp, 1]
                ) ** 2
                if not err2 < limit2 * step2:
                    fits = False
                j += 1
            if fits:
                if side == 0:
                    i1 += 1
                else:
                    i0 -= 1
                grew = True
        # then a new column j1 + 1, then j0 - 1, over the (grown) rows i0 .. i1
        for side in range(2):
            jnew = j1 + 1 if side == 0 else j0 - 1
            step = -1 if side == 0 else 1
            fits = abs(jnew) < m
            i = i0
            while fits and i <= i1:
                bn = node_at[i + m, jnew + m]
                if bn < 0:
                    fits = False
                    break
                bl = node_at[i + m, jnew + step + m]
                bp = node_at[i + m, jnew + 2 * step + m]
                step2 = (xy[bl, 0] - xy[bp, 0]) ** 2 + (xy[bl, 1] - xy[bp, 1]) ** 2
                err2 = (xy[bn, 0] - 2.0 * xy[bl, 0] + xy[bp, 0]) ** 2 + (
                    xy[bn, 1] - 2.0 * xy[bl, 1] + xy[bp, 1]
                ) ** 2
                if not err2 < limit2 * step2:
                    fits = False
                i += 1
            if fits:
                if side == 0:
                    j1 += 1
                else:
                    j0 -= 1
                grew = True
    out = np.empty((i1 - i0 + 1, j1 - j0 + 1), dtype=np.int64)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            out[i - i0, j - j0] = node_at[i + m, j + m]
    return out


@njit(fastmath=False)
def lattice_problem_numba(
    grid: NDArray[np.float64], max_bend: float
) -> tuple[int, float, float]:  # pragma: no cover - numba-compiled
    """Run the checks of ``checkerboard_grid.lattice_problem`` on ``grid`` (R, C, 2), in order.

    Returns ``(code, a, b)``: 0 a consistent lattice; 1 (rows) or 3 (columns) a second
    difference not below ``max_bend`` times the spacing, ``a`` the largest ratio; 2 (rows)
    or 4 (columns) consecutive steps whose ratio leaves (0.5, 2), ``a``-``b`` the ratio's
    range; 5 cells not convex with one orientation. NaN propagates into ``a``, ``b``.
    """
    nr, nc = grid.shape[0], grid.shape[1]
    for axis in range(2):
        # axis 0: along each row (over columns); axis 1: along each column (over rows)
        n_along = nc if axis == 0 else nr
        n_lines = nr if axis == 0 else nc
        if n_along < 3:
            continue
        ok = True
        worst = -np.inf
        nan = False
        for line in range(n_lines):
            for k in range(n_along - 2):
                if axis == 0:
                    ax_, ay_ = grid[line, k, 0], grid[line, k, 1]
                    bx, by = grid[line, k + 1, 0], grid[line, k + 1, 1]
                    cx, cy = grid[line, k + 2, 0], grid[line, k + 2, 1]
                else:
                    ax_, ay_ = grid[k, line, 0], grid[k, line, 1]
                    bx, by = grid[k + 1, line, 0], grid[k + 1, line, 1]
                    cx, cy = grid[k + 2, line, 0], grid[k + 2, line, 1]
                sx = cx - 2.0 * bx + ax_
                sy = cy - 2.0 * by + ay_
                second = np.sqrt(sx * sx + sy * sy)
                dx = cx - ax_
                dy = cy - ay_
                spacing = 0.5 * np.sqrt(dx * dx + dy * dy)
                ratio = second / spacing
                if not ratio < max_bend:
                    ok = False
                if np.isnan(ratio):
                    nan = True
                elif ratio > worst:
                    worst = ratio
        if not ok:
            return 1 + 2 * axis, np.nan if nan else worst, 0.0
        lo = np.inf
        hi = -np.inf
        nan = False
        for line in range(n_lines):
            prev = 0.0
            for k in range(n_along - 1):
                if axis == 0:
                    dx = grid[line, k + 1, 0] - grid[line, k, 0]
                    dy = grid[line, k + 1, 1] - grid[line, k, 1]
                else:
                    dx = grid[k + 1, line, 0] - grid[k, line, 0]
                    dy = grid[k + 1, line, 1] - grid[k, line, 1]
                step = np.sqrt(dx * dx + dy * dy)
                if k > 0:
                    jump = step / prev
                    if not (jump > 0.5 and jump < 2.0):
                        ok = False
                    if np.isnan(jump):
                        nan = True
                    else:
                        lo = min(lo, jump)
                        hi = max(hi, jump)
                prev = step
        if not ok:
            if nan:
                return 2 + 2 * axis, np.nan, np.nan
            return 2 + 2 * axis, lo, hi
    positive = True
    negative = True
    for i in range(nr - 1):
        for j in range(nc - 1):
            p00x, p00y = grid[i, j, 0], grid[i, j, 1]
            p01x, p01y = grid[i, j + 1, 0], grid[i, j + 1, 1]
            p10x, p10y = grid[i + 1, j, 0], grid[i + 1, j, 1]
            p11x, p11y = grid[i + 1, j + 1, 0], grid[i + 1, j + 1, 1]
            for t in range(4):
                if t == 0:
                    ax_, ay_, bx, by = p01x - p00x, p01y - p00y, p11x - p01x, p11y - p01y
                elif t == 1:
                    ax_, ay_, bx, by = p11x - p01x, p11y - p01y, p10x - p11x, p10y - p11y
                elif t == 2:
                    ax_, ay_, bx, by = p10x - p11x, p10y - p11y, p00x - p10x, p00y - p10y
                else:
                    ax_, ay_, bx, by = p00x - p10x, p00y - p10y, p01x - p00x, p01y - p00y
                turn = ax_ * by - ay_ * bx
                if not turn > 0:
                    positive = False
                if not turn < 0:
                    negative = False
    if not (positive or negative):
        return 5, 0.0, 0.0
    return 0, 0.0, 0.0
