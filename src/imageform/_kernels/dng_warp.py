"""Numba kernel of the DNG WarpRectilinear opcode (:func:`imageform.io._dng_opcodes.apply_stage3`).

:func:`warp_rows` is :func:`imageform.io._dng_opcodes.warp_source_positions` followed by
:func:`imageform.io._dng_opcodes.bicubic_sample`, one output pixel at a time (the NumPy
functions are the reference the tests hold it to): the source position of the Adobe DNG SDK's
``dng_filter_warp``, clamped to the image, Keys' bicubic kernel (a = -0.75) at the fraction
floored to 1/32 pixel (its 32 weights worked out once), 4 x 4 taps with the edge pixels
repeated, the result clamped to [0, 1].
Run on numba's threads by :func:`imageform._kernels.jit.run_tasks`, a row per task.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["warp_rows"]


@njit(nogil=True)
def _keys(t):  # type: ignore[no-untyped-def]
    t = abs(t)
    if t < 1.0:
        return (1.25 * t - 2.25) * t * t + 1.0
    if t < 2.0:
        return ((-0.75 * t + 3.75) * t - 6.0) * t + 3.0
    return 0.0


@njit(nogil=True)
def warp_rows(r0, r1, src, out, coef, geometry):  # type: ignore[no-untyped-def]
    """Warp output rows ``r0 .. r1 - 1`` of ``out`` (H, W, C float32) from ``src`` (same shape).

    ``coef`` (planes, 6) float64: ``kr0..kr3, kt0, kt1`` per plane (one row: every plane).
    ``geometry`` float64: the offset of the image's first pixel in the opcode's image (rows,
    columns), that image's height and width, the centre (row, column) and the radius ``R``.
    """
    h, w, nc = src.shape
    dt, dl, full_h, full_w, cy, cx, radius = (
        geometry[0], geometry[1], geometry[2], geometry[3], geometry[4], geometry[5], geometry[6]
    )  # fmt: skip
    # the normalised weights of the 32 fractions (the kernel is the same for rows and columns)
    table = np.empty((32, 4))
    for k in range(32):
        fk = k / 32.0
        total_k = 0.0
        for t in range(4):
            table[k, t] = _keys(t - 1 - fk)
            total_k += table[k, t]
        for t in range(4):
            table[k, t] /= total_k
    wr = np.empty(4)
    wc = np.empty(4)
    for i in range(r0, r1):
        y = (i + dt - cy) / radius
        for j in range(w):
            x = (j + dl - cx) / radius
            r2 = min(x * x + y * y, 1.0)
            for p in range(nc):
                if p > 0 and coef.shape[0] == 1:  # the same position as plane 0's
                    pass
                else:
                    k = coef[min(p, coef.shape[0] - 1)]
                    f = k[0] + r2 * (k[1] + r2 * (k[2] + r2 * k[3]))
                    ty = k[4] * (r2 + 2.0 * y * y) + 2.0 * k[5] * x * y
                    tx = k[5] * (r2 + 2.0 * x * x) + 2.0 * k[4] * x * y
                    sr = min(max(cy + radius * (y * f + ty), 0.0), full_h - 1.0) - dt
                    sc = min(max(cx + radius * (x * f + tx), 0.0), full_w - 1.0) - dl
                    sr = min(max(sr, 0.0), h - 1.0)
                    sc = min(max(sc, 0.0), w - 1.0)
                    fr0 = math.floor(sr)
                    fc0 = math.floor(sc)
                    kr = math.floor((sr - fr0) * 32.0)  # the fraction in 32nds
                    kc = math.floor((sc - fc0) * 32.0)
                    ir = int(fr0)
                    ic = int(fc0)
                    for t in range(4):
                        wr[t] = table[kr, t]
                        wc[t] = table[kc, t]
                total = 0.0
                for a in range(4):
                    rr = min(max(ir + a - 1, 0), h - 1)
                    row = 0.0
                    for b in range(4):
                        cc = min(max(ic + b - 1, 0), w - 1)
                        row += wc[b] * src[rr, cc, p]
                    total += wr[a] * row
                out[i, j, p] = min(max(total, 0.0), 1.0)
