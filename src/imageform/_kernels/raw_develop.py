r"""Numba kernels of raw development (:func:`imageform.io.develop`): two passes, float32.

- :func:`balance_mosaic`: digital numbers to the white-balanced, clipped mosaic in one pass,
  :math:`\min(\max((DN - B_s)\,k_s, 0), 1)` with :math:`k_s = g_s / (W - B_s)` per photosite
  of the 2x2 tile (linearisation and white balance fused: no float64 copy of the mosaic).
- :func:`render_rgb`: demosaiced camera RGB to the encoded output in one pass: the 3x3 matrix
  (camera RGB to the output space's linear RGB, adaptation included), clipping to [0, 1] and
  the transfer function from a table sampled uniformly in :math:`\sqrt{x}` (65,537 entries,
  linear interpolation: within 1e-6 of the exact curve for sRGB, and for pure power laws,
  whose slope at 0 is infinite, within 2e-6; ``tests/io/test_raw_fast.py``).

Serial loops over rows (numba compiles them in a fraction of a parallel kernel's time; at
24 Mpx each pass is a few hundred milliseconds on one core).
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["LUT_SIZE", "balance_mosaic", "quantize", "render_rgb"]

#: Intervals of the transfer table (in sqrt(x)).
LUT_SIZE = 65536


@njit(error_model="numpy")
def balance_mosaic(mosaic, black, scale, out):  # type: ignore[no-untyped-def]
    """``out[i, j] = clip((mosaic[i, j] - black[i % 2, j % 2]) * scale[i % 2, j % 2], 0, 1)``."""
    h, w = mosaic.shape
    for i in range(h):
        b0 = black[i & 1, 0]
        b1 = black[i & 1, 1]
        s0 = scale[i & 1, 0]
        s1 = scale[i & 1, 1]
        for j in range(w):
            if j & 1:
                v = (np.float32(mosaic[i, j]) - b1) * s1
            else:
                v = (np.float32(mosaic[i, j]) - b0) * s0
            out[i, j] = min(max(v, np.float32(0)), np.float32(1))


@njit(error_model="numpy")
def render_rgb(cam, m, lut, encode, out):  # type: ignore[no-untyped-def]
    """``out = T(clip(cam @ m.T, 0, 1))`` per pixel; T from ``lut`` when ``encode``."""
    h, w, _ = cam.shape
    n = lut.shape[0] - 1
    fn = np.float32(n)
    for i in range(h):
        for j in range(w):
            r = cam[i, j, 0]
            g = cam[i, j, 1]
            b = cam[i, j, 2]
            for c in range(3):
                v = m[c, 0] * r + m[c, 1] * g + m[c, 2] * b
                v = min(max(v, np.float32(0)), np.float32(1))
                if encode:
                    u = np.sqrt(v) * fn
                    k = min(int(u), n - 1)
                    f = u - np.float32(k)
                    v = lut[k] + f * (lut[k + 1] - lut[k])
                out[i, j, c] = v


@njit(error_model="numpy")
def quantize(src, top, out):  # type: ignore[no-untyped-def]
    """``out = round(src * top)`` for ``src`` in [0, 1] (flat arrays; ``out`` an integer type).

    Rounds half up (``src * top + 0.5`` truncated, exact for non-negative values), which
    differs from ``numpy.rint`` (half to even) only on exact halves.
    """
    half = np.float32(0.5)
    for i in range(src.shape[0]):
        out[i] = src[i] * top + half
