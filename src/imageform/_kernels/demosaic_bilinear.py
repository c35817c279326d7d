"""Bilinear demosaicing: numba kernel and its NumPy twin (RGGB-phased padded input).

Each missing sample is the mean of its nearest same-colour neighbours: green at red/blue
sites from the 4 edge neighbours, red/blue at green sites from the 2 neighbours in the row
or column that holds them, red at blue (blue at red) from the 4 diagonal neighbours. This is
the convolution of the masked planes with ``[[0,1,0],[1,4,1],[0,1,0]]/4`` (green) and
``[[1,2,1],[2,4,2],[1,2,1]]/4`` (red, blue). Radius: 1 pixel.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.demosaic_common import crop, phase_masks, shift
from imageform._kernels.jit import njit, parallel_pays, run_tasks

__all__ = ["RADIUS", "bilinear_int_numba", "bilinear_int_numpy", "bilinear_numba", "bilinear_numpy"]

RADIUS = 1


def bilinear_numba(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Bilinear demosaicing of an RGGB-phased padded mosaic (``RADIUS`` pixels of padding).

    Rows in chunks of 16 on numba's threads (:func:`imageform._kernels.jit.run_tasks`: a
    serial ``nogil`` kernel, not a ``parallel=True`` one, whose parallel lowering cost about
    a second of CPU more on a first run).
    """
    out = np.empty((h, w, 3), dtype=P.dtype)
    run_tasks(_bilinear_tasks, (h + 15) // 16, P, oy, ox, h, w, out)
    return out


@njit(nogil=True, fastmath=False)
def _bilinear_tasks(
    task0: int, task1: int, P: np.ndarray, oy: int, ox: int, h: int, w: int, out: np.ndarray
) -> None:  # pragma: no cover
    # Unit-stride row views indexed from 0 (vectorisable), the phase selects, then the three
    # results are interleaved into the output (as in demosaic_malvar).
    t = P.dtype.type
    q = t(0.25)
    half = t(0.5)
    # rows in chunks of 16, so that each chunk allocates its row buffers once
    for chunk in range(task0, task1):
        bg = np.empty(w, P.dtype)  # green
        bk = np.empty(w, P.dtype)  # the colour of this row (red in red rows)
        bo = np.empty(w, P.dtype)  # the other one
        for i in range(chunk * 16, min(h, chunk * 16 + 16)):
            y = i + oy
            u1m = P[y - 1, ox - 1 : ox - 1 + w]
            u1 = P[y - 1, ox : ox + w]
            u1p = P[y - 1, ox + 1 : ox + 1 + w]
            d1m = P[y + 1, ox - 1 : ox - 1 + w]
            d1 = P[y + 1, ox : ox + w]
            d1p = P[y + 1, ox + 1 : ox + 1 + w]
            cm1 = P[y, ox - 1 : ox - 1 + w]
            c0 = P[y, ox : ox + w]
            cp1 = P[y, ox + 1 : ox + 1 + w]
            red_row = y % 2 == 0
            rb_parity = 0 if red_row else 1
            for j in range(w):
                c = c0[j]
                s1h = cm1[j] + cp1[j]
                s1v = u1[j] + d1[j]
                dg = u1m[j] + u1p[j] + d1m[j] + d1p[j]
                is_rb = ((j + ox) & 1) == rb_parity
                bg[j] = q * (s1h + s1v) if is_rb else c
                bk[j] = c if is_rb else half * s1h
                bo[j] = q * dg if is_rb else half * s1v
            o = out[i]
            k = 0 if red_row else 2
            for j in range(w):
                o[j, 1] = bg[j]
                o[j, k] = bk[j]
                o[j, 2 - k] = bo[j]


def bilinear_numpy(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Twin of :func:`bilinear_numba`: masked planes convolved with the bilinear kernels."""
    r_m, g1, g2, b_m = phase_masks(P.shape)
    g_m = g1 | g2
    planes = []
    for m, cross, diag in ((r_m, 0.5, 0.25), (g_m, 0.25, 0.0), (b_m, 0.5, 0.25)):
        c = np.where(m, P, 0).astype(P.dtype)
        s = c.copy()
        s += cross * (shift(c, 0, -1) + shift(c, 0, 1) + shift(c, -1, 0) + shift(c, 1, 0))
        if diag:
            s += diag * (shift(c, -1, -1) + shift(c, -1, 1) + shift(c, 1, -1) + shift(c, 1, 1))
        planes.append(s)
    return crop(np.stack(planes, axis=-1), oy, ox, h, w)


# --- integer (uint8 / uint16 in and out) ----------------------------------------------------


@njit(inline="always", error_model="numpy")
def _px_int(u, c, d, o, jl, j, jr, is_rb, k):  # type: ignore[no-untyped-def]
    cc = np.int32(c[j])
    sh = np.int32(c[jl]) + np.int32(c[jr])
    sv = np.int32(u[j]) + np.int32(d[j])
    dg = np.int32(u[jl]) + np.int32(u[jr]) + np.int32(d[jl]) + np.int32(d[jr])
    g = ((sh + sv + 2) >> 2) if is_rb else cc
    own = cc if is_rb else ((sh + 1) >> 1)
    oth = ((dg + 2) >> 2) if is_rb else ((sv + 1) >> 1)
    o[j, 1] = g
    o[j, k] = own
    o[j, 2 - k] = oth


_U = np.uint32
_H = np.uint16  # uint8 sums: 4 x 255 + 2 fits


@njit(inline="always", error_model="numpy")
def _avg2(a, b):  # type: ignore[no-untyped-def]
    """Return ``(a + b + 1) >> 1`` of two unsigned samples as ``(a | b) - ((a ^ b) >> 1)``.

    (``a + b = 2 (a & b) + (a ^ b)`` and ``a | b = (a & b) + (a ^ b)``.) Written so, not as
    the sum: numba widens the sum to 64 bits and, where a sum feeds both a 2-mean and a
    4-mean, LLVM then keeps 64-bit lanes (about 2x slower); bit operations stay narrow.
    """
    return (a | b) - ((a ^ b) >> 1)


@njit(inline="always", error_model="numpy")
def _own_green(u, c, d, j):  # type: ignore[no-untyped-def]
    """Pixel ``j`` a red (blue) site, ``j + 1`` green: (own, green, other) of both (uint32)."""
    cl, c0, c1, c2 = _U(c[j - 1]), _U(c[j]), _U(c[j + 1]), _U(c[j + 2])
    ul, u0, u1 = _U(u[j - 1]), _U(u[j]), _U(u[j + 1])
    dl, d0, d1 = _U(d[j - 1]), _U(d[j]), _U(d[j + 1])
    g0 = (cl + c1 + u0 + d0 + _U(2)) >> _U(2)
    x0 = (ul + u1 + dl + d1 + _U(2)) >> _U(2)
    return c0, g0, x0, _avg2(c0, c2), c1, _avg2(u1, d1)


@njit(inline="always", error_model="numpy")
def _green_own(u, c, d, j):  # type: ignore[no-untyped-def]
    """Pixel ``j`` green, ``j + 1`` a red (blue) site: (own, green, other) of both (uint32)."""
    cl, c0, c1, c2 = _U(c[j - 1]), _U(c[j]), _U(c[j + 1]), _U(c[j + 2])
    u0, u1, u2 = _U(u[j]), _U(u[j + 1]), _U(u[j + 2])
    d0, d1, d2 = _U(d[j]), _U(d[j + 1]), _U(d[j + 2])
    g1 = (c0 + c2 + u1 + d1 + _U(2)) >> _U(2)
    x1 = (u0 + u2 + d0 + d2 + _U(2)) >> _U(2)
    return _avg2(cl, c1), c0, _avg2(u0, d0), c1, g1, x1


@njit(inline="always", error_model="numpy")
def _own_green8(u, c, d, j):  # type: ignore[no-untyped-def]
    """:func:`_own_green` of uint8 samples: 4-means in 16-bit lanes, 2-means :func:`_avg2`."""
    cl, c0, c1, c2 = _H(c[j - 1]), _H(c[j]), _H(c[j + 1]), _H(c[j + 2])
    ul, u0, u1 = _H(u[j - 1]), _H(u[j]), _H(u[j + 1])
    dl, d0, d1 = _H(d[j - 1]), _H(d[j]), _H(d[j + 1])
    g0 = (cl + c1 + u0 + d0 + _H(2)) >> _H(2)
    x0 = (ul + u1 + dl + d1 + _H(2)) >> _H(2)
    return c0, g0, x0, _avg2(c0, c2), c1, _avg2(u1, d1)


@njit(inline="always", error_model="numpy")
def _green_own8(u, c, d, j):  # type: ignore[no-untyped-def]
    """:func:`_green_own` of uint8 samples (as :func:`_own_green8`)."""
    cl, c0, c1, c2 = _H(c[j - 1]), _H(c[j]), _H(c[j + 1]), _H(c[j + 2])
    u0, u1, u2 = _H(u[j]), _H(u[j + 1]), _H(u[j + 2])
    d0, d1, d2 = _H(d[j]), _H(d[j + 1]), _H(d[j + 2])
    g1 = (c0 + c2 + u1 + d1 + _H(2)) >> _H(2)
    x1 = (u0 + u2 + d0 + d2 + _H(2)) >> _H(2)
    return _avg2(cl, c1), c0, _avg2(u0, d0), c1, g1, x1


def _make_rows(own_first: bool, red_row: bool, wide: bool):  # type: ignore[no-untyped-def]
    """Run the interior loop of one row phase: 2 pixels (6 output samples) per step.

    Six stores into the flat output row ``ov`` (the mosaic's dtype). uint8 (``wide``
    False): 4-means in 16-bit lanes; uint16: in 32-bit lanes. ``own_first``: the row's red
    (blue) site at even columns; ``red_row``: the own colour is red (channel 0). Constant
    channel order and no selects, so LLVM vectorises the loop.
    """
    if wide:
        pair = _own_green if own_first else _green_own
    else:
        pair = _own_green8 if own_first else _green_own8

    def rgb(own, g, oth):  # type: ignore[no-untyped-def]
        return (own, g, oth) if red_row else (oth, g, own)

    # a closure, inlined into the loop below (whose cache holds it): nothing to cache itself
    rgb_j = njit(inline="always", cache=False)(rgb)

    def loop(u, c, d, ov, n):  # type: ignore[no-untyped-def]
        for q in range(1, n):
            a0, a1, a2, b0, b1, b2 = pair(u, c, d, 2 * q)
            r0, g0, x0 = rgb_j(a0, a1, a2)
            r1, g1, x1 = rgb_j(b0, b1, b2)
            k = 6 * q  # ov: this row's samples (an offset here would stop vectorisation)
            ov[k] = r0
            ov[k + 1] = g0
            ov[k + 2] = x0
            ov[k + 3] = r1
            ov[k + 4] = g1
            ov[k + 5] = x1

    return njit(error_model="numpy")(loop)


_OWN_R8 = _make_rows(True, True, False)
_OWN_B8 = _make_rows(True, False, False)
_GREEN_R8 = _make_rows(False, True, False)
_GREEN_B8 = _make_rows(False, False, False)
_OWN_R16 = _make_rows(True, True, True)
_OWN_B16 = _make_rows(True, False, True)
_GREEN_R16 = _make_rows(False, True, True)
_GREEN_B16 = _make_rows(False, False, True)


@njit(nogil=True, error_model="numpy")
def _int_rows(i0, i1, raw, ry, rx, out, ov, n):  # type: ignore[no-untyped-def]
    # Rows i0 .. i1 - 1 of an unpadded mosaic (red at row % 2 == ry, column % 2 == rx); edges
    # mirrored about the edge pixel (index -1 reads 1, as numpy.pad(mode="reflect") in the
    # float path). ``ov``: the flat output; n = w // 2 - 1 (n < 2: the per-pixel loop only).
    h, w = raw.shape
    wide = raw.itemsize == 2
    for i in range(i0, i1):
        up = i - 1 if i > 0 else 1
        dn = i + 1 if i < h - 1 else h - 2
        u = raw[up]
        c = raw[i]
        d = raw[dn]
        o = out[i]
        red_row = (i & 1) == ry
        k = 0 if red_row else 2
        par = rx if red_row else 1 - rx  # column parity of this row's red (blue) sites
        if n > 1:
            orow = ov[i * 3 * w : (i + 1) * 3 * w]
            if wide:
                if par == 0 and red_row:
                    _OWN_R16(u, c, d, orow, n)
                elif par == 0:
                    _OWN_B16(u, c, d, orow, n)
                elif red_row:
                    _GREEN_R16(u, c, d, orow, n)
                else:
                    _GREEN_B16(u, c, d, orow, n)
            elif par == 0 and red_row:
                _OWN_R8(u, c, d, orow, n)
            elif par == 0:
                _OWN_B8(u, c, d, orow, n)
            elif red_row:
                _GREEN_R8(u, c, d, orow, n)
            else:
                _GREEN_B8(u, c, d, orow, n)
            lo, hi = 2, 2 * n
        else:
            lo, hi = w, w
        for j in range(lo):
            jl = j - 1 if j > 0 else 1
            jr = j + 1 if j < w - 1 else w - 2
            _px_int(u, c, d, o, jl, j, jr, (j & 1) == par, k)
        for j in range(max(hi, lo), w):
            jl = j - 1 if j > 0 else 1
            jr = j + 1 if j < w - 1 else w - 2
            _px_int(u, c, d, o, jl, j, jr, (j & 1) == par, k)


#: Mosaics of fewer pixels run the rows in the calling thread (waking threads costs more than
#: it gains there). On the idle 2-core machine two threads gain 1.3x at 96 x 96 and 1.6-2.3x
#: from 128 x 128 up. One compiled kernel serves both (:func:`imageform._kernels.jit.run_tasks`;
#: a ``parallel=True`` kernel and its serial twin were two compilations).
PARALLEL_MIN_PIXELS = 1 << 14


def bilinear_int_numba(
    raw: np.ndarray, ry: int, rx: int, out: np.ndarray, parallel: bool | None = None
) -> np.ndarray:
    """Demosaic a uint8/uint16 unpadded C-contiguous ``(H, W)`` mosaic bilinearly into ``out``.

    Red is at ``(ry, rx)``; ``out`` is ``(H, W, 3)``, same dtype, C-contiguous; integer
    means rounded half up (twin: :func:`bilinear_int_numpy`). The interior runs a
    vectorised loop of 2 pixels per step (any width; narrow lanes, one store per sample);
    the edge pixels the per-pixel loop.
    """
    h, w = raw.shape
    if parallel is None:
        parallel = parallel_pays(h * w, PARALLEL_MIN_PIXELS)
    args = (raw, ry, rx, out, out.reshape(-1), w // 2 - 1)
    run_tasks(_int_rows, h, *args, threads=None if parallel else 1)
    return out


def bilinear_int_numpy(raw: np.ndarray, ry: int, rx: int) -> np.ndarray:
    """Twin of :func:`bilinear_int_numba`: the exact (integer) bilinear means, rounded half up.

    ``floor(mean + 1/2)`` of the nearest same-colour code values, i.e. ``(a + b + 1) >> 1`` and
    ``(a + b + c + d + 2) >> 2``.
    """
    h, w = raw.shape
    pr = np.pad(raw.astype(np.int64), 1, mode="reflect")
    y = (np.arange(h) % 2 == ry)[:, None]
    x = (np.arange(w) % 2 == rx)[None, :]
    r_m, b_m = y & x, ~y & ~x
    g_m = ~(r_m | b_m)

    def at(dy: int, dx: int) -> np.ndarray:
        return pr[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w]

    c = at(0, 0)
    sh = at(0, -1) + at(0, 1)
    sv = at(-1, 0) + at(1, 0)
    dg = at(-1, -1) + at(-1, 1) + at(1, -1) + at(1, 1)
    cross, two_h, two_v, diag = (sh + sv + 2) >> 2, (sh + 1) >> 1, (sv + 1) >> 1, (dg + 2) >> 2
    # green rows: red row greens see red left/right; blue row greens see red above/below
    g_red_row = g_m & y
    red = np.where(r_m, c, np.where(b_m, diag, np.where(g_red_row, two_h, two_v)))
    blue = np.where(b_m, c, np.where(r_m, diag, np.where(g_red_row, two_v, two_h)))
    green = np.where(g_m, c, cross)
    return np.stack([red, green, blue], axis=-1).astype(raw.dtype)
