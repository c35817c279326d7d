"""Bilinear demosaicing: numba kernel and its NumPy twin (RGGB-phased padded input).

Each missing sample is the mean of its nearest same-colour neighbours: green at red/blue
sites from the 4 edge neighbours, red/blue at green sites from the 2 neighbours in the row
or column that holds them, red at blue (blue at red) from the 4 diagonal neighbours. This is
the convolution of the masked planes with ``[[0,1,0],[1,4,1],[0,1,0]]/4`` (green) and
``[[1,2,1],[2,4,2],[1,2,1]]/4`` (red, blue). Radius: 1 pixel.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from imageform._kernels.demosaic_common import crop, phase_masks, shift

__all__ = ["RADIUS", "bilinear_numba", "bilinear_numpy"]

RADIUS = 1


@njit(cache=True, parallel=True, fastmath=False)
def bilinear_numba(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    # Unit-stride row views indexed from 0 (vectorisable), the phase selects, then the three
    # results are interleaved into the output (as in demosaic_malvar).
    out = np.empty((h, w, 3), dtype=P.dtype)
    t = P.dtype.type
    q = t(0.25)
    half = t(0.5)
    # rows in chunks of 16, so that each chunk allocates its row buffers once
    for chunk in prange((h + 15) // 16):
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
    return out


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


@njit(cache=True, inline="always", error_model="numpy")
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


def _make_pairs(own_first: bool, k: int):  # type: ignore[no-untyped-def]
    """Row loop over pixel pairs (2q, 2q + 1), q in [1, q1), for one phase of the row:
    ``own_first``: the row's red (blue) site first, then green; ``k`` the channel of the
    row's own colour (0 red rows, 2 blue rows) as a compile-time constant. No selects and
    constant channel offsets, so LLVM vectorises the loop (interleaved loads and stores)."""
    kk = 2 - k

    def own_first_loop(u, c, d, o, q1):  # type: ignore[no-untyped-def]
        for q in range(1, q1):
            j = 2 * q
            cl, c0 = np.int32(c[j - 1]), np.int32(c[j])
            c1, c2 = np.int32(c[j + 1]), np.int32(c[j + 2])
            ul, u0, u1 = np.int32(u[j - 1]), np.int32(u[j]), np.int32(u[j + 1])
            dl, d0, d1 = np.int32(d[j - 1]), np.int32(d[j]), np.int32(d[j + 1])
            o[j, 1] = (cl + c1 + u0 + d0 + 2) >> 2
            o[j, k] = c0
            o[j, kk] = (ul + u1 + dl + d1 + 2) >> 2
            o[j + 1, 1] = c1
            o[j + 1, k] = (c0 + c2 + 1) >> 1
            o[j + 1, kk] = (u1 + d1 + 1) >> 1

    def green_first_loop(u, c, d, o, q1):  # type: ignore[no-untyped-def]
        for q in range(1, q1):
            j = 2 * q
            cl, c0 = np.int32(c[j - 1]), np.int32(c[j])
            c1, c2 = np.int32(c[j + 1]), np.int32(c[j + 2])
            u0, u1, u2 = np.int32(u[j]), np.int32(u[j + 1]), np.int32(u[j + 2])
            d0, d1, d2 = np.int32(d[j]), np.int32(d[j + 1]), np.int32(d[j + 2])
            o[j, 1] = c0
            o[j, k] = (cl + c1 + 1) >> 1
            o[j, kk] = (u0 + d0 + 1) >> 1
            o[j + 1, 1] = (c0 + c2 + u1 + d1 + 2) >> 2
            o[j + 1, k] = c1
            o[j + 1, kk] = (u0 + u2 + d0 + d2 + 2) >> 2

    return njit(cache=True, error_model="numpy")(own_first_loop if own_first else green_first_loop)


_PAIRS_OWN_R = _make_pairs(True, 0)
_PAIRS_OWN_B = _make_pairs(True, 2)
_PAIRS_GREEN_R = _make_pairs(False, 0)
_PAIRS_GREEN_B = _make_pairs(False, 2)


@njit(cache=True, parallel=True, error_model="numpy")
def bilinear_int_numba(raw: np.ndarray, ry: int, rx: int, out: np.ndarray) -> np.ndarray:
    # Unpadded mosaic (red at row % 2 == ry, column % 2 == rx); edges mirrored about the edge
    # pixel (index -1 reads 1, as numpy.pad(mode="reflect") in the float path).
    h, w = raw.shape
    q1 = w // 2 - 1  # pairs 1 .. q1 - 1 cover columns 2 .. 2 q1 - 1 (interior)
    for i in prange(h):
        up = i - 1 if i > 0 else 1
        dn = i + 1 if i < h - 1 else h - 2
        u = raw[up]
        c = raw[i]
        d = raw[dn]
        o = out[i]
        red_row = (i & 1) == ry
        k = 0 if red_row else 2
        par = rx if red_row else 1 - rx  # column parity of this row's red (blue) sites
        if par == 0 and red_row:
            _PAIRS_OWN_R(u, c, d, o, q1)
        elif par == 0:
            _PAIRS_OWN_B(u, c, d, o, q1)
        elif red_row:
            _PAIRS_GREEN_R(u, c, d, o, q1)
        else:
            _PAIRS_GREEN_B(u, c, d, o, q1)
        for j in (0, 1):
            if j < w:
                _px_int(
                    u,
                    c,
                    d,
                    o,
                    j - 1 if j > 0 else 1,
                    j,
                    j + 1 if j < w - 1 else w - 2,
                    (j & 1) == par,
                    k,
                )
        for j in range(max(2, 2 * q1), w):
            _px_int(u, c, d, o, j - 1, j, j + 1 if j < w - 1 else w - 2, (j & 1) == par, k)
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
