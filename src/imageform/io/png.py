"""PNG of any bit depth through libpng (imagecodecs).

The codec behind :mod:`imageform.io` for PNG, also usable on its own for integer arrays.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform._validate import as_path, shorten
from imageform.errors import InvalidInputError

__all__ = ["read_png", "write_png"]


def read_png(path: str | Path) -> np.ndarray:
    """Read a PNG as stored: uint8 or uint16, ``(H, W, C)`` with C in 1..4 (alpha kept).

    Palette images come back as RGB (RGBA with transparency). See
    :func:`imageform.io.read_image` for the alpha rule, orientation and pixel limit.
    """
    from imageform.io.image_io import read_image

    if as_path(path, "path").suffix.lower() != ".png":
        raise InvalidInputError(f"expected path as a .png file, got {shorten(path)}")
    return read_image(path, alpha="keep")


def write_png(path: str | Path, image: np.ndarray) -> None:
    """Write a uint8 or uint16 array ``(H, W)`` or ``(H, W, C)``, C in 1..4, as PNG (atomic).

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.png")
    >>> write_png(p, np.array([[[0, 1000, 65535]]], np.uint16))
    >>> read_png(p).tolist()
    [[[0, 1000, 65535]]]
    """
    from imageform.io.image_io import write_image

    a = np.asarray(image)
    if a.dtype not in (np.uint8, np.uint16):
        raise InvalidInputError(f"expected image as uint8 or uint16 for PNG, got {a.dtype}")
    if as_path(path, "path").suffix.lower() != ".png":
        raise InvalidInputError(f"expected path as a .png file name, got {shorten(path)}")
    write_image(path, a)
