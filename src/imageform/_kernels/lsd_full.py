"""Numba kernels of the full LSD line segment detector (von Gioi et al., IPOL 2012).

A line-by-line port of the reference implementation ``lsd.c`` version 1.6 (Rafael Grompone
von Gioi, AGPL reference code published with the IPOL article; this is an independent
re-implementation of the published algorithm, not a copy of that file): Gaussian sub-sampling,
the 2x2 gradient with its pseudo-ordering in 1024 bins, region growing, the rectangle
approximation, the density refinement (region regrown with an adapted tolerance, then shrunk
by radius), the a-contrario NFA and the rectangle improvement.

The plain twins are the same functions run by the interpreter: every function here is a
numba dispatcher, so ``f.py_func`` is the interpreted twin, and the whole pipeline runs
interpreted under ``NUMBA_DISABLE_JIT=1`` (the tests compare both on small images).

Rectangles are float64 arrays of 12 entries: ``x1, y1, x2, y2, width, x, y, theta, dx, dy,
prec, p`` (end points of the central line, width, centre, direction angle and its cosine /
sine, angle tolerance in radians and the probability ``p = prec / pi``). Coordinates: x is the
column, y the row, the origin at the centre of pixel (0, 0).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._kernels.jit import njit

__all__ = [
    "NOTDEF",
    "gaussian_sampler",
    "ll_angle",
    "lsd",
    "nfa",
    "rect_nfa",
    "region_grow",
]

NOTDEF = -1024.0  # the level-line angle of pixels with a too small gradient
_M_3_2_PI = 4.71238898038
_M_2_PI = 6.28318530718
_JIT: dict[str, Any] = {"error_model": "numpy"}


@njit(**_JIT)
def _sampler_taps(n_out, size, scale, sigma, h):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Compute one axis of :func:`gaussian_sampler`: weights and source indices per sample.

    For each of ``n_out`` output samples its ``2 h + 1`` normalised Gaussian weights
    (centred on ``i / scale``) and their source indices in ``[0, size)`` with the symmetric
    (mirror) boundary.
    """
    n = 1 + 2 * h
    k = np.empty((n_out, n))
    src = np.empty((n_out, n), dtype=np.int64)
    dbl = 2 * size
    for o in range(n_out):
        pos = o / scale
        c = math.floor(pos + 0.5)
        mean = h + pos - c
        s = 0.0
        for i in range(n):
            v = (i - mean) / sigma
            k[o, i] = math.exp(-0.5 * v * v)
            s += k[o, i]
        for i in range(n):
            k[o, i] /= s
            j = c - h + i
            while j < 0:
                j += dbl
            while j >= dbl:
                j -= dbl
            if j >= size:
                j = dbl - 1 - j
            src[o, i] = j
    return k, src


@njit(**_JIT)
def gaussian_sampler(img, scale, sigma_scale):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Gaussian filter and sub-sample by ``scale`` (LSD's ``gaussian_sampler``).

    sigma = sigma_scale / scale when scale < 1; the kernel is cut where it falls below 1e-3
    of its peak, re-centred on each output sample (fine offset x / scale - round), with a
    symmetric (mirror) boundary. Separable: x first, then y.
    """
    ysize, xsize = img.shape
    nx = math.ceil(xsize * scale)
    ny = math.ceil(ysize * scale)
    sigma = sigma_scale / scale if scale < 1.0 else sigma_scale
    h = math.ceil(sigma * math.sqrt(2.0 * 3.0 * math.log(10.0)))
    n = 1 + 2 * h
    # x pass: per output column, its kernel and source columns
    kx, jx = _sampler_taps(nx, xsize, scale, sigma, h)
    aux = np.empty((ysize, nx))
    for y in range(ysize):
        for x in range(nx):
            acc = 0.0
            for i in range(n):
                acc += img[y, jx[x, i]] * kx[x, i]
            aux[y, x] = acc
    # y pass
    ky, jy = _sampler_taps(ny, ysize, scale, sigma, h)
    out = np.zeros((ny, nx))
    for y in range(ny):
        for i in range(n):
            w = ky[y, i]
            src = jy[y, i]
            for x in range(nx):
                out[y, x] += aux[src, x] * w
    return out


@njit(**_JIT)
def ll_angle(img, threshold, n_bins):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Level-line angles, gradient norms and the pseudo-ordered list of pixels.

    The gradient of pixel (x, y) uses the 2x2 block with (x, y) at its upper-left corner:
    ``gx = (B + D - A - C) / 2``, ``gy = (C + D - A - B) / 2``, angle ``atan2(gx, -gy)``;
    pixels with norm <= ``threshold`` (and the last row and column) are NOTDEF. The
    pseudo-ordering sorts pixels into ``n_bins`` bins of norm, from the largest bin down,
    keeping within a bin the reference's visiting order (x outer, y inner).

    Returns ``angles, modgrad, list_x, list_y`` (the list holds the defined pixels only).
    """
    ny, nx = img.shape
    angles = np.full((ny, nx), NOTDEF)
    modgrad = np.zeros((ny, nx))
    max_grad = 0.0
    n_def = 0
    for x in range(nx - 1):
        for y in range(ny - 1):
            com1 = img[y + 1, x + 1] - img[y, x]
            com2 = img[y, x + 1] - img[y + 1, x]
            gx = com1 + com2
            gy = com1 - com2
            norm = math.sqrt((gx * gx + gy * gy) / 4.0)
            modgrad[y, x] = norm
            if norm > threshold:
                angles[y, x] = math.atan2(gx, -gy)
                n_def += 1
                if norm > max_grad:
                    max_grad = norm
    list_x = np.empty(n_def, dtype=np.int32)
    list_y = np.empty(n_def, dtype=np.int32)
    if n_def == 0:
        return angles, modgrad, list_x, list_y
    counts = np.zeros(n_bins + 1, dtype=np.int64)
    for x in range(nx - 1):
        for y in range(ny - 1):
            if angles[y, x] != NOTDEF:
                b = int(modgrad[y, x] * n_bins / max_grad)
                if b >= n_bins:
                    b = n_bins - 1
                counts[n_bins - 1 - b + 1] += 1  # reversed bins: largest first
    for b in range(n_bins):
        counts[b + 1] += counts[b]
    for x in range(nx - 1):
        for y in range(ny - 1):
            if angles[y, x] != NOTDEF:
                b = int(modgrad[y, x] * n_bins / max_grad)
                if b >= n_bins:
                    b = n_bins - 1
                r = n_bins - 1 - b
                k = counts[r]
                counts[r] += 1
                list_x[k] = x
                list_y[k] = y
    return angles, modgrad, list_x, list_y


@njit(**_JIT)
def _isaligned(x, y, angles, theta, prec):  # type: ignore[no-untyped-def]  # pragma: no cover
    a = angles[y, x]
    if a == NOTDEF:
        return False
    theta -= a
    if theta < 0.0:
        theta = -theta
    if theta > _M_3_2_PI:
        theta -= _M_2_PI
        if theta < 0.0:
            theta = -theta
    return theta <= prec


@njit(**_JIT)
def _angle_diff(a, b):  # type: ignore[no-untyped-def]  # pragma: no cover
    a -= b
    while a <= -math.pi:
        a += _M_2_PI
    while a > math.pi:
        a -= _M_2_PI
    return -a if a < 0.0 else a


@njit(**_JIT)
def _angle_diff_signed(a, b):  # type: ignore[no-untyped-def]  # pragma: no cover
    a -= b
    while a <= -math.pi:
        a += _M_2_PI
    while a > math.pi:
        a -= _M_2_PI
    return a


@njit(**_JIT)
def nfa(n, k, p, log_nt):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``-log10 NFA`` with ``NFA = NT * sum_{i>=k} C(n, i) p^i (1 - p)^(n - i)``.

    The binomial tail is summed from its first term until the bound on the remaining terms
    is below 10 % of the result (LSD's ``nfa``); log-gamma by ``math.lgamma``.
    """
    if n == 0 or k == 0:
        return -log_nt
    if n == k:
        return -log_nt - n * math.log10(p)
    p_term = p / (1.0 - p)
    log1term = (
        math.lgamma(n + 1.0)
        - math.lgamma(k + 1.0)
        - math.lgamma(n - k + 1.0)
        + k * math.log(p)
        + (n - k) * math.log(1.0 - p)
    )
    term = math.exp(log1term)
    if term < 1e-300:  # the reference's double_equal(term, 0)
        if k > n * p:
            return -log1term / math.log(10.0) - log_nt
        return -log_nt
    bin_tail = term
    for i in range(k + 1, n + 1):
        bin_term = (n - i + 1) / i
        mult_term = bin_term * p_term
        term *= mult_term
        bin_tail += term
        if bin_term < 1.0:
            err = term * ((1.0 - mult_term ** (n - i + 1)) / (1.0 - mult_term) - 1.0)
            if err < 0.1 * abs(-math.log10(bin_tail) - log_nt) * bin_tail:
                break
    return -math.log10(bin_tail) - log_nt


@njit(**_JIT)
def _inter_low(x, x1, y1, x2, y2):  # type: ignore[no-untyped-def]  # pragma: no cover
    if x1 == x2 or abs(x1 - x2) <= 100.0 * 2.220446049250313e-16 * max(abs(x1), abs(x2)):
        return min(y1, y2)
    return y1 + (x - x1) * (y2 - y1) / (x2 - x1)


@njit(**_JIT)
def _inter_hi(x, x1, y1, x2, y2):  # type: ignore[no-untyped-def]  # pragma: no cover
    if x1 == x2 or abs(x1 - x2) <= 100.0 * 2.220446049250313e-16 * max(abs(x1), abs(x2)):
        return max(y1, y2)
    return y1 + (x - x1) * (y2 - y1) / (x2 - x1)


@njit(**_JIT)
def rect_nfa(rec, angles, log_nt):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Compute the ``-log10 NFA`` of a rectangle.

    It counts the pixels whose centres lie inside it (LSD's rectangle iterator, column by
    column) and how many are aligned with its direction within prec.
    """
    ny, nx = angles.shape
    x1, y1, x2, y2, width = rec[0], rec[1], rec[2], rec[3], rec[4]
    theta, dx, dy, prec, p = rec[7], rec[8], rec[9], rec[10], rec[11]
    hw = width / 2.0
    cx = np.empty(4)
    cy = np.empty(4)
    cx[0] = x1 - dy * hw
    cy[0] = y1 + dx * hw
    cx[1] = x2 - dy * hw
    cy[1] = y2 + dx * hw
    cx[2] = x2 + dy * hw
    cy[2] = y2 - dx * hw
    cx[3] = x1 + dy * hw
    cy[3] = y1 - dx * hw
    if x1 < x2 and y1 <= y2:
        off = 0
    elif x1 >= x2 and y1 < y2:
        off = 1
    elif x1 > x2 and y1 >= y2:
        off = 2
    else:
        off = 3
    vx0, vy0 = cx[off % 4], cy[off % 4]
    vx1, vy1 = cx[(off + 1) % 4], cy[(off + 1) % 4]
    vx2, vy2 = cx[(off + 2) % 4], cy[(off + 2) % 4]
    vx3, vy3 = cx[(off + 3) % 4], cy[(off + 3) % 4]
    pts = np.int64(0)  # not the literal 0: nfa would also be compiled for Literal[int](0)
    alg = np.int64(0)
    x = math.ceil(vx0) - 1
    y = math.ceil(vy0)
    ye = -1.7976931348623157e308
    while True:
        # ri_inc
        if not (x > vx2):
            y += 1
        while y > ye and not (x > vx2):
            x += 1
            if x > vx2:
                break
            if x < vx3:
                ys = _inter_low(float(x), vx0, vy0, vx3, vy3)
            else:
                ys = _inter_low(float(x), vx3, vy3, vx2, vy2)
            if x < vx1:
                ye = _inter_hi(float(x), vx0, vy0, vx1, vy1)
            else:
                ye = _inter_hi(float(x), vx1, vy1, vx2, vy2)
            y = math.ceil(ys)
        if x > vx2:
            break
        if x >= 0 and y >= 0 and x < nx and y < ny:
            pts += 1
            if _isaligned(x, y, angles, theta, prec):
                alg += 1
    return nfa(pts, alg, p, log_nt)


@njit(**_JIT)
def region_grow(x, y, angles, reg_x, reg_y, used, prec):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Grow a region of 8-connected pixels aligned within ``prec`` with the running mean angle.

    It grows from the seed (x, y) and marks the pixels used. Returns ``(size, reg_angle)``.
    """
    ny, nx = angles.shape
    reg_x[0] = x
    reg_y[0] = y
    size = 1
    reg_angle = angles[y, x]
    sumdx = math.cos(reg_angle)
    sumdy = math.sin(reg_angle)
    used[y, x] = 1
    i = 0
    while i < size:
        rx = reg_x[i]
        ry = reg_y[i]
        for xx in range(rx - 1, rx + 2):
            if xx < 0 or xx >= nx:
                continue
            for yy in range(ry - 1, ry + 2):
                if yy < 0 or yy >= ny or used[yy, xx] == 1:
                    continue
                if _isaligned(xx, yy, angles, reg_angle, prec):
                    used[yy, xx] = 1
                    reg_x[size] = xx
                    reg_y[size] = yy
                    size += 1
                    a = angles[yy, xx]
                    sumdx += math.cos(a)
                    sumdy += math.sin(a)
                    reg_angle = math.atan2(sumdy, sumdx)
        i += 1
    return size, reg_angle


@njit(**_JIT)
def _region2rect(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Compute the rectangle of a region.

    Its gradient-weighted centre of mass, the principal axis of inertia (oriented like the
    region's angle), and the extents along and across it.
    """
    x = 0.0
    y = 0.0
    s = 0.0
    for i in range(size):
        w = modgrad[reg_y[i], reg_x[i]]
        x += reg_x[i] * w
        y += reg_y[i] * w
        s += w
    x /= s
    y /= s
    ixx = 0.0
    iyy = 0.0
    ixy = 0.0
    for i in range(size):
        w = modgrad[reg_y[i], reg_x[i]]
        ddx = reg_x[i] - x
        ddy = reg_y[i] - y
        ixx += ddy * ddy * w
        iyy += ddx * ddx * w
        ixy -= ddx * ddy * w
    lam = 0.5 * (ixx + iyy - math.sqrt((ixx - iyy) * (ixx - iyy) + 4.0 * ixy * ixy))
    theta = math.atan2(lam - ixx, ixy) if abs(ixx) > abs(iyy) else math.atan2(ixy, lam - iyy)
    if _angle_diff(theta, reg_angle) > prec:
        theta += math.pi
    dx = math.cos(theta)
    dy = math.sin(theta)
    l_min = 0.0
    l_max = 0.0
    w_min = 0.0
    w_max = 0.0
    for i in range(size):
        ddx = reg_x[i] - x
        ddy = reg_y[i] - y
        lv = ddx * dx + ddy * dy
        wv = -ddx * dy + ddy * dx
        if lv > l_max:
            l_max = lv
        if lv < l_min:
            l_min = lv
        if wv > w_max:
            w_max = wv
        if wv < w_min:
            w_min = wv
    rec[0] = x + l_min * dx
    rec[1] = y + l_min * dy
    rec[2] = x + l_max * dx
    rec[3] = y + l_max * dy
    rec[4] = max(w_max - w_min, 1.0)
    rec[5] = x
    rec[6] = y
    rec[7] = theta
    rec[8] = dx
    rec[9] = dy
    rec[10] = prec
    rec[11] = p


@njit(**_JIT)
def _density(size, rec):  # type: ignore[no-untyped-def]  # pragma: no cover
    return size / (math.hypot(rec[0] - rec[2], rec[1] - rec[3]) * rec[4])


@njit(**_JIT)
def _reduce_region_radius(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec, used, density_th):  # type: ignore[no-untyped-def]  # pragma: no cover
    density = _density(size, rec)
    if density >= density_th:
        return True, size
    xc = float(reg_x[0])
    yc = float(reg_y[0])
    rad1 = math.hypot(xc - rec[0], yc - rec[1])
    rad2 = math.hypot(xc - rec[2], yc - rec[3])
    rad = max(rad1, rad2)
    while density < density_th:
        rad *= 0.75
        i = 0
        while i < size:
            if math.hypot(xc - reg_x[i], yc - reg_y[i]) > rad:
                used[reg_y[i], reg_x[i]] = 0
                reg_x[i] = reg_x[size - 1]
                reg_y[i] = reg_y[size - 1]
                size -= 1
            else:
                i += 1
        if size < 2:
            return False, size
        _region2rect(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec)
        density = _density(size, rec)
    return True, size


@njit(**_JIT)
def _refine(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec, used, angles, density_th):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Refine a region as LSD does.

    A region whose rectangle is less than ``density_th`` full is regrown from its seed with a
    tolerance adapted to the angles near the seed, then shrunk.
    """
    if _density(size, rec) >= density_th:
        return True, size
    xc = reg_x[0]
    yc = reg_y[0]
    ang_c = angles[yc, xc]
    s = 0.0
    s_sum = 0.0
    n = 0
    for i in range(size):
        used[reg_y[i], reg_x[i]] = 0
        if math.hypot(xc - reg_x[i], yc - reg_y[i]) < rec[4]:
            d = _angle_diff_signed(angles[reg_y[i], reg_x[i]], ang_c)
            s += d
            s_sum += d * d
            n += 1
    mean_angle = s / n
    tau = 2.0 * math.sqrt(max((s_sum - 2.0 * mean_angle * s) / n + mean_angle * mean_angle, 0.0))
    size, reg_angle = region_grow(xc, yc, angles, reg_x, reg_y, used, tau)
    if size < 2:
        return False, size
    _region2rect(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec)
    if _density(size, rec) < density_th:
        return _reduce_region_radius(
            reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec, used, density_th
        )
    return True, size


@njit(**_JIT)
def _copy12(dst, src):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``dst[:] = src`` for two rectangles, as an element loop.

    numba 0.68 compiles an array-to-slice copy with its shape-mismatch message (an f-string:
    ``str``, ``join``, ``repr``), about 5 s of CPU on a first ``imageform vanishing``.
    """
    for i in range(12):
        dst[i] = src[i]


@njit(**_JIT)
def _rect_improve(rec, angles, log_nt, log_eps):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Improve a rectangle as LSD does (``rec`` is updated in place).

    Finer precisions, thinner, each side thinner, finer again; the best -log10 NFA is kept.
    """
    delta = 0.5
    delta_2 = delta / 2.0
    log_nfa = rect_nfa(rec, angles, log_nt)
    if log_nfa > log_eps:
        return log_nfa
    r = rec.copy()
    for _ in range(5):
        r[11] /= 2.0
        r[10] = r[11] * math.pi
        v = rect_nfa(r, angles, log_nt)
        if v > log_nfa:
            log_nfa = v
            _copy12(rec, r)
    if log_nfa > log_eps:
        return log_nfa
    _copy12(r, rec)
    for _ in range(5):
        if r[4] - delta >= 0.5:
            r[4] -= delta
            v = rect_nfa(r, angles, log_nt)
            if v > log_nfa:
                _copy12(rec, r)
                log_nfa = v
    if log_nfa > log_eps:
        return log_nfa
    for sign in (1.0, -1.0):
        _copy12(r, rec)
        for _ in range(5):
            if r[4] - delta >= 0.5:
                r[0] += sign * -r[9] * delta_2
                r[1] += sign * r[8] * delta_2
                r[2] += sign * -r[9] * delta_2
                r[3] += sign * r[8] * delta_2
                r[4] -= delta
                v = rect_nfa(r, angles, log_nt)
                if v > log_nfa:
                    _copy12(rec, r)
                    log_nfa = v
        if log_nfa > log_eps:
            return log_nfa
    _copy12(r, rec)
    for _ in range(5):
        r[11] /= 2.0
        r[10] = r[11] * math.pi
        v = rect_nfa(r, angles, log_nt)
        if v > log_nfa:
            log_nfa = v
            _copy12(rec, r)
    return log_nfa


@njit(**_JIT)
def _detect(angles, modgrad, list_x, list_y, prec, p, log_nt, log_eps, density_th, validate):  # type: ignore[no-untyped-def]  # pragma: no cover
    ny, nx = angles.shape
    used = np.zeros((ny, nx), dtype=np.uint8)
    reg_x = np.empty(nx * ny, dtype=np.int32)
    reg_y = np.empty(nx * ny, dtype=np.int32)
    min_reg_size = int(-log_nt / math.log10(p))
    out = np.empty((256, 7))
    n_out = 0
    rec = np.empty(12)
    for s in range(list_x.shape[0]):
        x = list_x[s]
        y = list_y[s]
        if used[y, x] == 1 or angles[y, x] == NOTDEF:
            continue
        size, reg_angle = region_grow(x, y, angles, reg_x, reg_y, used, prec)
        if size < min_reg_size:
            continue
        _region2rect(reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec)
        ok, size = _refine(
            reg_x, reg_y, size, modgrad, reg_angle, prec, p, rec, used, angles, density_th
        )
        if not ok:
            continue
        if validate:
            log_nfa = _rect_improve(rec, angles, log_nt, log_eps)
            if log_nfa <= log_eps:
                continue
        else:  # OpenCV's LSD_REFINE_STD: every refined region, no NFA computed
            log_nfa = math.nan
        if n_out == out.shape[0]:
            grown = np.empty((2 * n_out, 7))
            for i in range(n_out):  # element loops: see _copy12
                for j in range(7):
                    grown[i, j] = out[i, j]
            out = grown
        out[n_out, 0] = rec[0] + 0.5
        out[n_out, 1] = rec[1] + 0.5
        out[n_out, 2] = rec[2] + 0.5
        out[n_out, 3] = rec[3] + 0.5
        out[n_out, 4] = rec[4]
        out[n_out, 5] = rec[11]
        out[n_out, 6] = log_nfa
        n_out += 1
    return out[:n_out].copy()


@njit(**_JIT)
def lsd(img, scale, sigma_scale, quant, ang_th, log_eps, density_th, n_bins, validate=True):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Run the LSD pipeline on a grey float64 image with values in [0, 255].

    Returns ``(n, 7)``: ``x1, y1, x2, y2, width, p, -log10 NFA`` per segment, in the input
    image's pixel-centre coordinates (x column, y row). ``validate=False`` skips the
    rectangle improvement and the NFA test (as OpenCV's default ``LSD_REFINE_STD`` does) and
    reports NaN for the NFA.
    """
    work = gaussian_sampler(img, scale, sigma_scale) if scale != 1.0 else img
    prec = math.pi * ang_th / 180.0
    p = ang_th / 180.0
    rho = quant / math.sin(prec)
    angles, modgrad, list_x, list_y = ll_angle(work, rho, n_bins)
    ny, nx = angles.shape
    log_nt = 5.0 * (math.log10(nx) + math.log10(ny)) / 2.0 + math.log10(11.0)
    out = _detect(angles, modgrad, list_x, list_y, prec, p, log_nt, log_eps, density_th, validate)
    if scale != 1.0:
        for i in range(out.shape[0]):
            for j in range(5):
                out[i, j] /= scale
    return out
