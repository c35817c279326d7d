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

from imageform._kernels.demosaic_common import crop, phase_masks, shift
from imageform._kernels.jit import njit, run_tasks

__all__ = ["RADIUS", "malvar_numba", "malvar_numpy"]

RADIUS = 2


def malvar_numba(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Malvar-He-Cutler on an RGGB-phased padded mosaic (needs ``RADIUS`` pixels of padding).

    Rows in chunks of 16 on numba's threads (:func:`imageform._kernels.jit.run_tasks`: a
    serial ``nogil`` kernel, not a ``parallel=True`` one, whose parallel lowering cost about
    a second of CPU more on a first run).
    """
    out = np.empty((h, w, 3), dtype=P.dtype)
    run_tasks(_malvar_tasks, (h + 15) // 16, P, oy, ox, h, w, out)
    return out


@njit(nogil=True, fastmath=False)
def _malvar_tasks(
    task0: int, task1: int, P: np.ndarray, oy: int, ox: int, h: int, w: int, out: np.ndarray
) -> None:
    # Every filter is evaluated at every pixel of a row from unit-stride row views (loop
    # indices from 0, so no negative-index wraparound: LLVM can vectorise), the phase then
    # selects; the three results are interleaved into the output in a second loop.
    t = P.dtype.type
    c2, c4, c5, c6 = t(2.0), t(4.0), t(5.0), t(6.0)
    half, c15, eighth = t(0.5), t(1.5), t(0.125)
    # rows in chunks of 16, so that each chunk allocates its row buffers once
    for chunk in range(task0, task1):
        bg = np.empty(w, P.dtype)  # green
        bk = np.empty(w, P.dtype)  # the colour of this row (red in red rows)
        bo = np.empty(w, P.dtype)  # the other one
        for i in range(chunk * 16, min(h, chunk * 16 + 16)):
            y = i + oy
            u2 = P[y - 2, ox : ox + w]
            u1m = P[y - 1, ox - 1 : ox - 1 + w]
            u1 = P[y - 1, ox : ox + w]
            u1p = P[y - 1, ox + 1 : ox + 1 + w]
            d1m = P[y + 1, ox - 1 : ox - 1 + w]
            d1 = P[y + 1, ox : ox + w]
            d1p = P[y + 1, ox + 1 : ox + 1 + w]
            d2 = P[y + 2, ox : ox + w]
            cm2 = P[y, ox - 2 : ox - 2 + w]
            cm1 = P[y, ox - 1 : ox - 1 + w]
            c0 = P[y, ox : ox + w]
            cp1 = P[y, ox + 1 : ox + 1 + w]
            cp2 = P[y, ox + 2 : ox + 2 + w]
            red_row = y % 2 == 0
            rb_parity = 0 if red_row else 1  # column parity of the red (blue) sites of this row
            for j in range(w):
                c = c0[j]
                s1h = cm1[j] + cp1[j]
                s1v = u1[j] + d1[j]
                s2h = cm2[j] + cp2[j]
                s2v = u2[j] + d2[j]
                dg = u1m[j] + u1p[j] + d1m[j] + d1p[j]
                g_rb = (c4 * c + c2 * (s1h + s1v) - (s2h + s2v)) * eighth  # G at R/B
                o_rb = (c6 * c + c2 * dg - c15 * (s2h + s2v)) * eighth  # B at R, R at B
                base = c5 * c - dg
                hor = (base + c4 * s1h - s2h + half * s2v) * eighth  # neighbours left/right
                ver = (base + c4 * s1v - s2v + half * s2h) * eighth  # neighbours above/below
                is_rb = ((j + ox) & 1) == rb_parity
                bg[j] = g_rb if is_rb else c
                bk[j] = c if is_rb else hor
                bo[j] = o_rb if is_rb else ver
            o = out[i]
            k = 0 if red_row else 2
            for j in range(w):
                o[j, 1] = bg[j]
                o[j, k] = bk[j]
                o[j, 2 - k] = bo[j]


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
