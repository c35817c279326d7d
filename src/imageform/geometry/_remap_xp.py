"""Array-API and Dask paths of image remapping and undistortion.

- :func:`remap_xp`: bilinear sampling in any Array-API namespace (PyTorch, CuPy,
  array-api-strict ...) by gathering the four neighbours with ``xp.take`` on the flattened
  image; the same arithmetic as the NumPy twin in :mod:`imageform.geometry.undistort`, and
  differentiable in PyTorch with respect to the image and the map.
- :func:`undistort_dask`: undistortion of a Dask image block by block: for every output
  block the source positions are computed (from ``K``, ``new_K`` and the model: NumPy
  constants), the source window they need is cut from the Dask image (the "overlap" of a
  geometric warp is data-dependent, so it is a window per block rather than a fixed
  halo) and remapped in one task. Blocks equal the in-memory result exactly (the same
  NumPy/numba code runs on the window with shifted coordinates).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["map_grid", "remap_dask", "remap_xp"]


def map_grid(
    rows: tuple[int, int],
    cols: tuple[int, int],
    Km: np.ndarray,
    Kn: np.ndarray,
    distortion: Any,
    xp: Any,
    dtype: Any,
    device: Any = None,
) -> Any:
    """Source ``(u, v)`` for the output pixels ``rows[0]:rows[1]``, ``cols[0]:cols[1]``.

    ``Km`` and ``Kn`` are NumPy matrices (their entries become Python floats) or ``xp``
    arrays on ``device`` (their entries stay 0-d arrays there: nothing is read back).
    """
    v = xp.astype(xp.arange(rows[0], rows[1], device=device), dtype)[:, None]
    u = xp.astype(xp.arange(cols[0], cols[1], device=device), dtype)[None, :]
    v, u = xp.broadcast_arrays(v, u)
    fx, s, cx, fy, cy = _entries(Kn)
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    xy = xp.stack([x, y], axis=-1)
    if distortion is not None:
        xy = distortion.distort(xy)
    kfx, ks, kcx, kfy, kcy = _entries(Km)
    us = kfx * xy[..., 0] + ks * xy[..., 1] + kcx
    vs = kfy * xy[..., 1] + kcy
    return xp.stack([us, vs], axis=-1)


def _entries(M: Any) -> tuple[Any, ...]:
    """``fx, s, cx, fy, cy`` of a K: floats from NumPy, 0-d arrays (on their device) else."""
    idx = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2))
    if isinstance(M, np.ndarray):
        return tuple(float(M[i, j]) for i, j in idx)
    return tuple(M[i, j] for i, j in idx)


def remap_xp(img: Any, map_uv: Any, fill: float, xp: Any) -> Any:
    """Bilinear sampling of a ``(B, H, W, C)`` image at ``map_uv`` ``(H', W', 2)``."""
    b, h, w, c = (int(n) for n in img.shape)
    map_u, map_v = map_uv[..., 0], map_uv[..., 1]
    out_hw = tuple(int(n) for n in map_u.shape)
    inside = (map_u >= 0) & (map_u <= w - 1) & (map_v >= 0) & (map_v <= h - 1)
    zero = xp.zeros_like(map_u)
    u = xp.where(inside, map_u, zero)
    v = xp.where(inside, map_v, zero)
    x0f = xp.minimum(xp.floor(u), float(w - 1))
    y0f = xp.minimum(xp.floor(v), float(h - 1))
    x0 = xp.astype(x0f, xp.int64)
    y0 = xp.astype(y0f, xp.int64)
    x1 = xp.minimum(x0 + 1, w - 1)
    y1 = xp.minimum(y0 + 1, h - 1)
    flat = xp.reshape(img, (b, h * w, c))

    def at(yy: Any, xx: Any) -> Any:
        idx = xp.reshape(yy * w + xx, (-1,))
        return xp.reshape(xp.take(flat, idx, axis=1), (b, *out_hw, c))

    ax = xp.astype(u - x0f, img.dtype)[None, ..., None]
    ay = xp.astype(v - y0f, img.dtype)[None, ..., None]
    out = (
        (1 - ax) * (1 - ay) * at(y0, x0)
        + ax * (1 - ay) * at(y0, x1)
        + (1 - ax) * ay * at(y1, x0)
        + ax * ay * at(y1, x1)
    )
    fill_a = xp.full_like(out, float(fill))
    return xp.where(inside[None, ..., None], out, fill_a)


def remap_dask(
    img: Any,
    out_hw: tuple[int, int],
    block_map: Callable[[tuple[int, int], tuple[int, int]], np.ndarray],
    block_fn: Callable[[np.ndarray, tuple[int, int], tuple[int, int], tuple[int, int]], Any],
    out_chunks: tuple[tuple[int, ...], tuple[int, ...]],
) -> Any:
    """Lazy block-wise remap of a Dask image ``(..., H, W, C)``: one task per output block.

    ``block_map(rows, cols)`` is the NumPy source map ``(rh, cw, 2)`` of an output block (used
    here only to find the source window it reads); ``block_fn(window, rows, cols, (y0, x0))``
    computes the block from the NumPy source ``window`` whose top-left source pixel is
    ``(y0, x0)``, with the in-memory code.
    """
    import dask
    import dask.array as da

    *lead, h, w, c = (int(n) for n in img.shape)
    grid = []
    r0 = 0
    for rh in out_chunks[0]:
        row = []
        c0 = 0
        for cw in out_chunks[1]:
            rows, cols = (r0, r0 + rh), (c0, c0 + cw)
            (y0, y1), (x0, x1) = _window(block_map(rows, cols), h, w)
            src = img[..., y0:y1, x0:x1, :]
            part = dask.delayed(block_fn)(src, rows, cols, (y0, x0))
            row.append(da.from_delayed(part, shape=(*lead, rh, cw, c), dtype=img.dtype))
            c0 += cw
        grid.append(row)
        r0 += rh
    return _block_lead(grid)


def _block_lead(grid: list[list[Any]]) -> Any:
    import dask.array as da

    # da.block joins the innermost lists along the last axis, the outer along the one
    # before: move (H, W) last, join, move the channels back
    nd = grid[0][0].ndim
    perm = (*range(nd - 3), nd - 1, nd - 3, nd - 2)  # (..., C, H, W)
    inv = (*range(nd - 3), nd - 2, nd - 1, nd - 3)
    moved = [[da.transpose(b, perm) for b in row] for row in grid]
    return da.transpose(da.block(moved), inv)


def _window(m: np.ndarray, h: int, w: int) -> tuple[tuple[int, int], tuple[int, int]]:
    """Return the source rows/cols a block's map reads.

    Bilinear: floor and floor + 1, one pixel of slack each side; a one-pixel window when the
    block reads nothing (all fill).
    """
    u, v = m[..., 0], m[..., 1]
    ok = (u >= 0) & (u <= w - 1) & (v >= 0) & (v <= h - 1)
    if not np.any(ok):
        return (0, 1), (0, 1)
    uu, vv = u[ok], v[ok]
    x0 = max(0, math.floor(float(uu.min())) - 1)
    x1 = min(w, math.floor(float(uu.max())) + 3)
    y0 = max(0, math.floor(float(vv.min())) - 1)
    y1 = min(h, math.floor(float(vv.max())) + 3)
    return (y0, y1), (x0, x1)
