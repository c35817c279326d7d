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
