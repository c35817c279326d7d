"""Numba kernels of the line-segment detector (region growing, rectangles, alignment counts).

The plain twins live in :mod:`imageform.geometry.line_segments` as slow pure-Python loops used
only by the tests on small images (``_grow_regions_py``); the kernels are the reference-sized
path. See that module for the algorithm (von Gioi et al., LSD, IPOL 2012).
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["grow_regions", "rect_alignment_counts", "region_rectangles"]

# Compile time (a first ``imageform simulate`` compiles all three): every np.empty signature
# and every ``**`` overload is a compilation of its own (20-120 ms each), so the work arrays
# are rows of one array of the same np.empty signature as the result, and squares are
# products (``x ** 2`` is ``x * x`` bit for bit). min/max stay: written as conditional
# expressions they cost more compile time (each is two more blocks) than the overloads.


@njit
def _angle_diff(a: float, b: float) -> float:  # pragma: no cover - numba
    d = a - b
    while d <= -math.pi:
        d += 2.0 * math.pi
    while d > math.pi:
        d -= 2.0 * math.pi
    return abs(d)


@njit
def grow_regions(angle, order, tau, min_size):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Label 8-connected regions of pixels aligned with the region's running mean angle.

    A pixel joins when its level-line angle is within ``tau`` of that angle; regions are
    seeded in ``order`` (decreasing gradient). NaN angles are NOTDEF. Regions smaller than
    ``min_size`` are discarded (label -1 stays on their pixels as 'used').
    """
    H, W = angle.shape
    # np.empty and fill loops: each np.zeros / np.full signature is one more compilation
    labels = np.empty((H, W), dtype=np.int32)
    used = np.empty((H, W), dtype=np.bool_)
    for y in range(H):
        for x in range(W):
            labels[y, x] = -1
            used[y, x] = False
    stacks = np.empty((2, H * W), dtype=np.int32)  # labels' np.empty signature
    stack_y = stacks[0]
    stack_x = stacks[1]
    n_regions = 0
    for s in range(order.shape[0]):
        idx = order[s]
        y0 = idx // W
        x0 = idx - y0 * W
        if used[y0, x0] or math.isnan(angle[y0, x0]):
            continue
        # grow
        reg_angle = angle[y0, x0]
        sx = math.cos(reg_angle)
        sy = math.sin(reg_angle)
        used[y0, x0] = True
        stack_y[0] = y0
        stack_x[0] = x0
        size = 1
        head = 0
        while head < size:
            cy = stack_y[head]
            cx = stack_x[head]
            head += 1
            for dy in range(-1, 2):
                yy = cy + dy
                if yy < 0 or yy >= H:
                    continue
                for dx in range(-1, 2):
                    xx = cx + dx
                    if xx < 0 or xx >= W or used[yy, xx]:
                        continue
                    a = angle[yy, xx]
                    if math.isnan(a):
                        continue
                    if _angle_diff(a, reg_angle) <= tau:
                        used[yy, xx] = True
                        stack_y[size] = yy
                        stack_x[size] = xx
                        size += 1
                        sx += math.cos(a)
                        sy += math.sin(a)
                        reg_angle = math.atan2(sy, sx)
        if size >= min_size:
            for k in range(size):
                labels[stack_y[k], stack_x[k]] = n_regions
            n_regions += 1
    return labels, n_regions


@njit
def region_rectangles(labels, n_regions, mag):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Per region: the magnitude-weighted centroid, principal direction and extents.

    Returns ``rects`` (n, 7): cx, cy, theta (line direction), l_min, l_max, w_min, w_max,
    coordinates of pixel centres (u = column, v = row).
    """
    H, W = labels.shape
    # the per-region sums: rows of one array of rects' np.empty signature (and fill loops, as
    # in grow_regions)
    acc = np.empty((10, n_regions))
    sw, sx, sy, ixx, iyy, ixy = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5]
    cx, cy, dirx, diry = acc[6], acc[7], acc[8], acc[9]
    for r in range(n_regions):
        sw[r] = sx[r] = sy[r] = ixx[r] = iyy[r] = ixy[r] = 0.0
    for y in range(H):
        for x in range(W):
            r = labels[y, x]
            if r >= 0:
                w = mag[y, x]
                sw[r] += w
                sx[r] += w * x
                sy[r] += w * y
    for r in range(n_regions):  # element loops, not array expressions (compiled seconds longer)
        cx[r] = sx[r] / sw[r]
        cy[r] = sy[r] / sw[r]
    for y in range(H):
        for x in range(W):
            r = labels[y, x]
            if r >= 0:
                w = mag[y, x]
                dx = x - cx[r]
                dy = y - cy[r]
                ixx[r] += w * dy * dy
                iyy[r] += w * dx * dx
                ixy[r] -= w * dx * dy
    rects = np.empty((n_regions, 7))  # every entry written below
    for r in range(n_regions):
        # smallest eigenvalue's eigenvector of [[ixx, ixy], [ixy, iyy]] is the line direction
        d = ixx[r] - iyy[r]
        lam = 0.5 * (ixx[r] + iyy[r] - math.sqrt(d * d + 4.0 * (ixy[r] * ixy[r])))
        if abs(ixx[r]) > abs(iyy[r]):
            theta = math.atan2(lam - ixx[r], ixy[r])
        else:
            theta = math.atan2(ixy[r], lam - iyy[r])
        dirx[r] = math.cos(theta)
        diry[r] = math.sin(theta)
        rects[r, 0] = cx[r]
        rects[r, 1] = cy[r]
        rects[r, 2] = theta
        rects[r, 3] = 1e300
        rects[r, 4] = -1e300
        rects[r, 5] = 1e300
        rects[r, 6] = -1e300
    for y in range(H):
        for x in range(W):
            r = labels[y, x]
            if r >= 0:
                dx = x - cx[r]
                dy = y - cy[r]
                l = dx * dirx[r] + dy * diry[r]
                w = -dx * diry[r] + dy * dirx[r]
                rects[r, 3] = min(rects[r, 3], l)
                rects[r, 4] = max(rects[r, 4], l)
                rects[r, 5] = min(rects[r, 5], w)
                rects[r, 6] = max(rects[r, 6], w)
    return rects


@njit
def rect_alignment_counts(rects, angle, tau):  # type: ignore[no-untyped-def]  # pragma: no cover
    """For each rectangle: (n pixels whose centre lies inside, k of them aligned within tau).

    'Aligned' compares the pixel's level-line angle with the rectangle's direction modulo pi
    (a line segment has no polarity at this stage; the region grew with one polarity).
    """
    H, W = angle.shape
    n = rects.shape[0]
    out = np.empty((n, 2), dtype=np.int64)  # every entry written below
    for r in range(n):
        cx, cy, th = rects[r, 0], rects[r, 1], rects[r, 2]
        l0, l1 = rects[r, 3] - 0.5, rects[r, 4] + 0.5
        w0, w1 = rects[r, 5] - 0.5, rects[r, 6] + 0.5
        c = math.cos(th)
        s = math.sin(th)
        # bounding box of the rectangle (scalars: no small arrays to compile)
        x00, x01 = l0 * c - w0 * s + cx, l0 * c - w1 * s + cx
        x10, x11 = l1 * c - w0 * s + cx, l1 * c - w1 * s + cx
        y00, y01 = l0 * s + w0 * c + cy, l0 * s + w1 * c + cy
        y10, y11 = l1 * s + w0 * c + cy, l1 * s + w1 * c + cy
        xa = max(0, math.floor(min(min(x00, x01), min(x10, x11))))
        xb = min(W - 1, math.ceil(max(max(x00, x01), max(x10, x11))))
        ya = max(0, math.floor(min(min(y00, y01), min(y10, y11))))
        yb = min(H - 1, math.ceil(max(max(y00, y01), max(y10, y11))))
        total = 0
        aligned = 0
        for y in range(ya, yb + 1):
            for x in range(xa, xb + 1):
                dx = x - cx
                dy = y - cy
                l = dx * c + dy * s
                w = -dx * s + dy * c
                if l0 <= l <= l1 and w0 <= w <= w1:
                    total += 1
                    a = angle[y, x]
                    if not math.isnan(a):
                        d = _angle_diff(a, th)
                        if d <= tau or math.pi - d <= tau:
                            aligned += 1
        out[r, 0] = total
        out[r, 1] = aligned
    return out
