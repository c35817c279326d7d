"""Shared pieces of the demosaicing kernels and their NumPy twins.

Every kernel works on an **RGGB-phased, reflect-padded** mosaic ``P`` of shape ``(Hp, Wp)``:
red at (even row, even column), blue at (odd, odd), green where ``row + column`` is odd.
:func:`imageform.sensor.demosaic.demosaic` builds ``P`` from any Bayer pattern by padding
with a phase-preserving mirror (``numpy.pad(..., mode="reflect")``, which mirrors about
the edge pixel, so pixel ``-k`` takes the value of pixel ``k``, which has the same colour).
Kernels return the ``(H, W, 3)`` window starting at padded row ``oy``, column ``ox``; values
within the method's radius of the padded array's edge are never read.

The NumPy twins compute the whole padded plane with :func:`shift` (``np.roll``; its
wrapped-around values stay inside the padding) and crop at the end.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["crop", "phase_masks", "shift"]


def shift(a: np.ndarray, dy: int, dx: int) -> np.ndarray:
    """``out[y, x] = a[y + dy, x + dx]`` (wrapping at the edges; callers pad enough)."""
    return np.roll(a, (-dy, -dx), axis=(0, 1))


def phase_masks(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Boolean masks of an RGGB plane: red, green-in-red-row, green-in-blue-row, blue."""
    y = (np.arange(shape[0]) % 2)[:, None]
    x = (np.arange(shape[1]) % 2)[None, :]
    return (y == 0) & (x == 0), (y == 0) & (x == 1), (y == 1) & (x == 0), (y == 1) & (x == 1)


def crop(full: Any, oy: int, ox: int, h: int, w: int) -> np.ndarray:
    """Return the ``(h, w, ...)`` window of ``full`` at ``(oy, ox)``, as a contiguous array."""
    return np.ascontiguousarray(full[oy : oy + h, ox : ox + w])
