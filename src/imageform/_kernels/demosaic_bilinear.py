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
    out = np.empty((h, w, 3), dtype=P.dtype)
    q = P.dtype.type(0.25)
    half = P.dtype.type(0.5)
    for i in prange(h):
        y = i + oy
        up = P[y - 1]
        row = P[y]
        dn = P[y + 1]
        o = out[i]
        # columns whose padded index is even, then odd (no per-pixel branch)
        j0 = ox % 2  # first j with (j + ox) even
        if y % 2 == 0:  # R G R G ...
            for j in range(j0, w, 2):  # red sites
                x = j + ox
                o[j, 0] = row[x]
                o[j, 1] = q * (row[x - 1] + row[x + 1] + up[x] + dn[x])
                o[j, 2] = q * (up[x - 1] + up[x + 1] + dn[x - 1] + dn[x + 1])
            for j in range(1 - j0, w, 2):  # green in a red row
                x = j + ox
                o[j, 0] = half * (row[x - 1] + row[x + 1])
                o[j, 1] = row[x]
                o[j, 2] = half * (up[x] + dn[x])
        else:  # G B G B ...
            for j in range(j0, w, 2):  # green in a blue row
                x = j + ox
                o[j, 0] = half * (up[x] + dn[x])
                o[j, 1] = row[x]
                o[j, 2] = half * (row[x - 1] + row[x + 1])
            for j in range(1 - j0, w, 2):  # blue sites
                x = j + ox
                o[j, 0] = q * (up[x - 1] + up[x + 1] + dn[x - 1] + dn[x + 1])
                o[j, 1] = q * (row[x - 1] + row[x + 1] + up[x] + dn[x])
                o[j, 2] = row[x]
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
