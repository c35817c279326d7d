"""Malvar-He-Cutler (2004) demosaicing: numba kernel and its NumPy twin.

Bilinear interpolation corrected by the Laplacian of the channel the pixel measured
(gains α = 1/2, β = 5/8, γ = 3/4 of the paper, eqs. 4-6), as the paper's four 5×5 filters
(fig. 2), each divided by 8:

- G at R/B: ``4 c + 2 (N + S + E + W) - (NN + SS + EE + WW)``;
- R at G in a red row (B at G in a blue row), neighbours of the wanted colour left/right:
  ``5 c + 4 (E + W) - (EE + WW + NE + NW + SE + SW) + (NN + SS) / 2``;
- the same transposed when the wanted colour is above/below;
- R at B (B at R): ``6 c + 2 (NE + NW + SE + SW) - 3/2 (NN + SS + EE + WW)``.

Source: H. S. Malvar, L.-W. He, R. Cutler, "High-quality linear interpolation for demosaicing
of Bayer-patterned color images", ICASSP 2004, vol. 3, pp. 485-488. Radius: 2 pixels.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from imageform._kernels.demosaic_common import crop, phase_masks, shift

__all__ = ["RADIUS", "malvar_numba", "malvar_numpy"]

RADIUS = 2


@njit(cache=True, parallel=True, fastmath=False)
def malvar_numba(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    out = np.empty((h, w, 3), dtype=P.dtype)
    t = P.dtype.type
    c2, c4, c5, c6 = t(2.0), t(4.0), t(5.0), t(6.0)
    half, c15, eighth = t(0.5), t(1.5), t(0.125)
    j_even = ox % 2  # first j whose padded column is even
    for i in prange(h):
        y = i + oy
        u2 = P[y - 2]
        u1 = P[y - 1]
        c0 = P[y]
        d1 = P[y + 1]
        d2 = P[y + 2]
        o = out[i]
        red_row = y % 2 == 0
        # red (red rows) or blue (blue rows) sites: even columns in red rows, odd in blue
        k = 0 if red_row else 2  # channel measured here
        for j in range((j_even if red_row else 1 - j_even), w, 2):
            x = j + ox
            c = c0[x]
            cross4 = u2[x] + d2[x] + c0[x - 2] + c0[x + 2]
            diag = u1[x - 1] + u1[x + 1] + d1[x - 1] + d1[x + 1]
            o[j, k] = c
            o[j, 1] = (c4 * c + c2 * (u1[x] + d1[x] + c0[x - 1] + c0[x + 1]) - cross4) * eighth
            o[j, 2 - k] = (c6 * c + c2 * diag - c15 * cross4) * eighth
        # green sites: the colour of this row comes from left/right, the other from above/below
        kh = 0 if red_row else 2
        for j in range((1 - j_even if red_row else j_even), w, 2):
            x = j + ox
            c = c0[x]
            diag = u1[x - 1] + u1[x + 1] + d1[x - 1] + d1[x + 1]
            base = c5 * c - diag
            h2 = c0[x - 2] + c0[x + 2]
            v2 = u2[x] + d2[x]
            o[j, 1] = c
            o[j, kh] = (base + c4 * (c0[x - 1] + c0[x + 1]) - h2 + half * v2) * eighth
            o[j, 2 - kh] = (base + c4 * (u1[x] + d1[x]) - v2 + half * h2) * eighth
    return out


def malvar_numpy(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Twin of :func:`malvar_numba`: the four filters as shifted sums, selected by phase."""

    def s(dy: int, dx: int) -> np.ndarray:
        return shift(P, dy, dx)

    cross1 = s(-1, 0) + s(1, 0) + s(0, -1) + s(0, 1)
    cross2 = s(-2, 0) + s(2, 0) + s(0, -2) + s(0, 2)
    diag = s(-1, -1) + s(-1, 1) + s(1, -1) + s(1, 1)
    g_at_rb = (4 * P + 2 * cross1 - cross2) / 8
    rb_at_br = (6 * P + 2 * diag - 1.5 * cross2) / 8
    hor = (
        5 * P - diag + 4 * (s(0, -1) + s(0, 1)) - (s(0, -2) + s(0, 2)) + 0.5 * (s(-2, 0) + s(2, 0))
    ) / 8
    ver = (
        5 * P - diag + 4 * (s(-1, 0) + s(1, 0)) - (s(-2, 0) + s(2, 0)) + 0.5 * (s(0, -2) + s(0, 2))
    ) / 8
    r_m, g1, g2, b_m = phase_masks(P.shape)
    r = np.select([r_m, g1, g2, b_m], [P, hor, ver, rb_at_br])
    g = np.where(g1 | g2, P, g_at_rb)
    b = np.select([r_m, g1, g2, b_m], [rb_at_br, ver, hor, P])
    return crop(np.stack([r, g, b], axis=-1).astype(P.dtype, copy=False), oy, ox, h, w)
