r"""Hamilton-Adams (1997) edge-directed demosaicing: numba kernel and its NumPy twin.

Green at a red (blue) site is interpolated along the direction of the smaller gradient,
the gradient combining the green first difference and the red (blue) second difference:

.. math::

    \Delta_H = |G_{x-1} - G_{x+1}| + |2 C_x - C_{x-2} - C_{x+2}|, \qquad
    \hat G_H = \frac{G_{x-1} + G_{x+1}}{2} + \frac{2 C_x - C_{x-2} - C_{x+2}}{4}

(and the same vertically; the mean of both when :math:`\Delta_H = \Delta_V`). Red and
blue then follow the completed green: at green sites the colour difference is averaged
from the two neighbours that hold the colour; at blue (red) sites the diagonal with the
smaller gradient :math:`|C_{NW} - C_{SE}| + |2 G - G_{NW} - G_{SE}|` is used.

Source: J. F. Hamilton Jr., J. E. Adams Jr., "Adaptive color plane interpolation in single
sensor color electronic camera", US patent 5,629,734 (1997). Radius: 3 pixels.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.demosaic_common import crop, phase_masks, shift
from imageform._kernels.jit import njit, run_tasks

__all__ = ["RADIUS", "hamilton_adams_numba", "hamilton_adams_numpy"]

RADIUS = 3


@njit(nogil=True, fastmath=False)
def _green(
    t0: int, t1: int, P: np.ndarray, y0: int, x0: int, x1: int, G: np.ndarray
) -> None:  # pragma: no cover
    # rows y0 + t0 .. y0 + t1 - 1
    for y in range(y0 + t0, y0 + t1):
        c0 = P[y]
        u1 = P[y - 1]
        d1 = P[y + 1]
        u2 = P[y - 2]
        d2 = P[y + 2]
        for x in range(x0, x1):
            c = c0[x]
            if (x + y) % 2 == 1:
                G[y, x] = c
                continue
            lh = 2.0 * c - c0[x - 2] - c0[x + 2]
            lv = 2.0 * c - u2[x] - d2[x]
            dh = abs(c0[x - 1] - c0[x + 1]) + abs(lh)
            dv = abs(u1[x] - d1[x]) + abs(lv)
            gh = 0.5 * (c0[x - 1] + c0[x + 1]) + 0.25 * lh
            gv = 0.5 * (u1[x] + d1[x]) + 0.25 * lv
            if dh < dv:
                G[y, x] = gh
            elif dv < dh:
                G[y, x] = gv
            else:
                G[y, x] = 0.5 * (gh + gv)


@njit(nogil=True, fastmath=False)
def _chroma(
    i0: int, i1: int, P: np.ndarray, G: np.ndarray, oy: int, ox: int, w: int, out: np.ndarray
) -> None:  # pragma: no cover
    # output rows i0 .. i1 - 1
    for i in range(i0, i1):
        y = i + oy
        red_row = y % 2 == 0
        for j in range(w):
            x = j + ox
            c = P[y, x]
            g = G[y, x]
            out[i, j, 1] = g
            if (x + y) % 2 == 1:  # green site
                hor = g + 0.5 * (P[y, x - 1] - G[y, x - 1] + P[y, x + 1] - G[y, x + 1])
                ver = g + 0.5 * (P[y - 1, x] - G[y - 1, x] + P[y + 1, x] - G[y + 1, x])
                if red_row:
                    out[i, j, 0] = hor
                    out[i, j, 2] = ver
                else:
                    out[i, j, 0] = ver
                    out[i, j, 2] = hor
            else:  # red or blue site: the other colour from the diagonals
                a, b = P[y - 1, x - 1], P[y + 1, x + 1]
                e, f = P[y - 1, x + 1], P[y + 1, x - 1]
                ga, gb = G[y - 1, x - 1], G[y + 1, x + 1]
                ge, gf = G[y - 1, x + 1], G[y + 1, x - 1]
                dn = abs(a - b) + abs(2.0 * g - ga - gb)
                dp = abs(e - f) + abs(2.0 * g - ge - gf)
                vn = 0.5 * (a + b) + 0.5 * (2.0 * g - ga - gb)
                vp = 0.5 * (e + f) + 0.5 * (2.0 * g - ge - gf)
                if dn < dp:
                    o = vn
                elif dp < dn:
                    o = vp
                else:
                    o = 0.5 * (vn + vp)
                if red_row:
                    out[i, j, 0] = c
                    out[i, j, 2] = o
                else:
                    out[i, j, 0] = o
                    out[i, j, 2] = c


def hamilton_adams_numba(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Hamilton-Adams on an RGGB-phased padded mosaic (needs ``RADIUS`` pixels of padding).

    Both passes run their rows on numba's threads (:func:`imageform._kernels.jit.run_tasks`:
    serial ``nogil`` kernels, not ``parallel=True`` ones, whose parallel lowering cost about
    two seconds of CPU more on a first run).
    """
    G = np.empty_like(P)
    run_tasks(_green, h + 2, P, oy - 1, ox - 1, ox + w + 1, G)
    out = np.empty((h, w, 3), dtype=P.dtype)
    run_tasks(_chroma, h, P, G, oy, ox, w, out)
    return out


def hamilton_adams_numpy(P: np.ndarray, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Twin of :func:`hamilton_adams_numba` with whole-plane array operations."""

    def s(a: np.ndarray, dy: int, dx: int) -> np.ndarray:
        return shift(a, dy, dx)

    r_m, g1, g2, b_m = phase_masks(P.shape)
    g_m = g1 | g2
    lh = 2 * P - s(P, 0, -2) - s(P, 0, 2)
    lv = 2 * P - s(P, -2, 0) - s(P, 2, 0)
    dh = np.abs(s(P, 0, -1) - s(P, 0, 1)) + np.abs(lh)
    dv = np.abs(s(P, -1, 0) - s(P, 1, 0)) + np.abs(lv)
    gh = 0.5 * (s(P, 0, -1) + s(P, 0, 1)) + 0.25 * lh
    gv = 0.5 * (s(P, -1, 0) + s(P, 1, 0)) + 0.25 * lv
    G = np.select([g_m, dh < dv, dv < dh], [P, gh, gv], 0.5 * (gh + gv))
    D = P - G  # colour difference, meaningful at red/blue sites
    hor = G + 0.5 * (s(D, 0, -1) + s(D, 0, 1))
    ver = G + 0.5 * (s(D, -1, 0) + s(D, 1, 0))
    dn = np.abs(s(P, -1, -1) - s(P, 1, 1)) + np.abs(2 * G - s(G, -1, -1) - s(G, 1, 1))
    dp = np.abs(s(P, -1, 1) - s(P, 1, -1)) + np.abs(2 * G - s(G, -1, 1) - s(G, 1, -1))
    vn = 0.5 * (s(P, -1, -1) + s(P, 1, 1)) + 0.5 * (2 * G - s(G, -1, -1) - s(G, 1, 1))
    vp = 0.5 * (s(P, -1, 1) + s(P, 1, -1)) + 0.5 * (2 * G - s(G, -1, 1) - s(G, 1, -1))
    other = np.select([dn < dp, dp < dn], [vn, vp], 0.5 * (vn + vp))
    r = np.select([r_m, g1, g2], [P, hor, ver], other)
    b = np.select([b_m, g1, g2], [P, ver, hor], other)
    return crop(np.stack([r, G, b], axis=-1).astype(P.dtype, copy=False), oy, ox, h, w)
