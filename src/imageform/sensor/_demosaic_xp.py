"""Demosaicing for arrays other than NumPy: an Array-API path and a Dask path.

- :func:`demosaic_xp`: bilinear and Malvar-He-Cutler in any Array-API namespace (PyTorch
  on CPU or CUDA, CuPy, array-api-strict), with shifted-slice sums (no convolution), the
  same arithmetic, in the same order, as the numba kernels
  (:mod:`imageform._kernels.demosaic_bilinear`, :mod:`imageform._kernels.demosaic_malvar`),
  so the results equal the NumPy path. The phase-preserving mirror padding is built from
  slices and ``xp.flip``. Differentiable in PyTorch.
- :func:`demosaic_dask`: any method on a Dask mosaic, lazily, block by block with
  ``dask.array.overlap``: chunks are made even (every block then starts on the same CFA
  phase) and the overlap depth is the method's padding (its radius rounded up to even, so
  the extended blocks start on the phase too); no padding is added at the image edge, where
  the in-memory function's own mirror applies. Every pixel is computed from the same
  samples as in memory: the result equals the in-memory path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from imageform._backend import device_of

__all__ = ["XP_METHODS", "demosaic_dask", "demosaic_xp", "pad_reflect"]

#: Methods with a namespace-generic implementation.
XP_METHODS = ("bilinear", "malvar")

_RADIUS = {"bilinear": 1, "malvar": 2}


def pad_reflect(a: Any, top: int, bottom: int, left: int, right: int, xp: Any) -> Any:
    """``numpy.pad(a, ..., mode="reflect")`` on the last two axes (mirror about the edge)."""
    h, w = int(a.shape[-2]), int(a.shape[-1])
    if max(top, bottom) > h - 1 or max(left, right) > w - 1:
        raise ValueError("mosaic too small for the mirror padding of this method")
    parts = []
    if top:
        parts.append(xp.flip(a[..., 1 : top + 1, :], axis=-2))
    parts.append(a)
    if bottom:
        parts.append(xp.flip(a[..., h - 1 - bottom : h - 1, :], axis=-2))
    a = xp.concat(parts, axis=-2) if len(parts) > 1 else a
    parts = []
    if left:
        parts.append(xp.flip(a[..., 1 : left + 1], axis=-1))
    parts.append(a)
    if right:
        parts.append(xp.flip(a[..., w - 1 - right : w - 1], axis=-1))
    return xp.concat(parts, axis=-1) if len(parts) > 1 else a


def demosaic_xp(raw: Any, ry: int, rx: int, method: str, xp: Any) -> Any:
    """Demosaic a float mosaic ``(..., H, W)`` into RGB ``(..., H, W, 3)``.

    The red site is at ``(ry, rx)`` in the top-left cell; ``method`` in :data:`XP_METHODS`.
    """
    h, w = int(raw.shape[-2]), int(raw.shape[-1])
    r = _RADIUS[method]
    pad = r + (r % 2)
    P = pad_reflect(raw, pad + ry, pad, pad + rx, pad, xp)
    oy, ox = pad + ry, pad + rx

    def S(dy: int, dx: int) -> Any:
        return P[..., oy + dy : oy + dy + h, ox + dx : ox + dx + w]

    dev = device_of(raw)
    rows = xp.arange(h, device=dev) + oy
    cols = xp.arange(w, device=dev) + ox
    red_row = (rows % 2 == 0)[:, None]  # (h, 1)
    # red (blue) sites: even columns of red rows, odd columns of blue rows
    is_rb = (cols[None, :] % 2) == (rows[:, None] % 2)

    c = S(0, 0)
    s1h = S(0, -1) + S(0, 1)
    s1v = S(-1, 0) + S(1, 0)
    dg = S(-1, -1) + S(-1, 1) + S(1, -1) + S(1, 1)
    if method == "bilinear":
        g_rb = 0.25 * (s1h + s1v)
        hor = 0.5 * s1h
        o_rb = 0.25 * dg
        ver = 0.5 * s1v
    else:  # Malvar, He, Cutler (2004), the four filters as in the numba kernel
        s2h = S(0, -2) + S(0, 2)
        s2v = S(-2, 0) + S(2, 0)
        g_rb = (4.0 * c + 2.0 * (s1h + s1v) - (s2h + s2v)) * 0.125
        o_rb = (6.0 * c + 2.0 * dg - 1.5 * (s2h + s2v)) * 0.125
        base = 5.0 * c - dg
        hor = (base + 4.0 * s1h - s2h + 0.5 * s2v) * 0.125
        ver = (base + 4.0 * s1v - s2v + 0.5 * s2h) * 0.125
    bg = xp.where(is_rb, g_rb, c)
    bk = xp.where(is_rb, c, hor)  # the colour of this row (red in red rows)
    bo = xp.where(is_rb, o_rb, ver)  # the other one
    red = xp.where(red_row, bk, bo)
    blue = xp.where(red_row, bo, bk)
    return xp.stack([red, bg, blue], axis=-1)


def demosaic_dask(raw: Any, depth: int, block: Callable[[Any], Any], out_dtype: Any) -> Any:
    """Demosaic a Dask mosaic ``(..., H, W)`` lazily with ``block``.

    ``block`` is the in-memory function on a NumPy block ``(..., h, w)`` ->
    ``(..., h, w, 3)``; ``depth`` is even.
    """
    import dask.array as da
    import numpy as np

    nd = raw.ndim
    ax_h, ax_w = nd - 2, nd - 1
    x = raw.rechunk(
        {
            ax_h: _even_chunks(int(raw.shape[ax_h]), max(raw.chunks[ax_h]), depth),
            ax_w: _even_chunks(int(raw.shape[ax_w]), max(raw.chunks[ax_w]), depth),
        }
    )
    if x.numblocks[ax_h] == 1 and x.numblocks[ax_w] == 1:
        g = x
    else:
        dep = dict.fromkeys(range(nd), 0)
        dep[ax_h] = depth if x.numblocks[ax_h] > 1 else 0
        dep[ax_w] = depth if x.numblocks[ax_w] > 1 else 0
        g = da.overlap.overlap(x, depth=dep, boundary="none")
    y = g.map_blocks(
        block,
        new_axis=[nd],
        chunks=(*g.chunks, (3,)),
        dtype=out_dtype,
        meta=np.empty((0,) * (nd + 1), dtype=out_dtype),
    )
    if g is x:
        return y
    return da.overlap.trim_internal(y, {**dep, nd: 0}, boundary="none")


def _even_chunks(n: int, size: int, depth: int) -> tuple[int, ...]:
    """Return the chunks of an axis of length ``n``: even sizes, at least ``depth`` and 2.

    A short last chunk is merged into the one before so that every chunk holds the overlap
    depth.
    """
    size = max(size, depth, 2)
    size += size % 2
    chunks = [size] * (n // size)
    rem = n - size * len(chunks)
    if rem:
        if chunks and rem < depth:
            chunks[-1] += rem
        else:
            chunks.append(rem)
    return tuple(chunks) if chunks else (n,)
