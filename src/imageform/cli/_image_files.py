"""Minimal image reading and writing for the CLI (Pillow), until ``imageform.io`` lands.

8-bit files read as uint8, 16-bit greyscale as uint16; writing takes floats in [0, 1] and
stores 8 or 16 bits, rounding to the nearest code (values outside [0, 1] are an error,
never clipped silently).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["read_image", "write_image"]


def read_image(path: Path) -> np.ndarray:
    """Read ``path`` as ``(H, W)`` or ``(H, W, 3)`` uint8/uint16 (alpha dropped with an error)."""
    from PIL import Image

    if not path.is_file():
        raise InvalidInputError(f"input image {path} does not exist")
    try:
        with Image.open(path) as im:
            if im.mode in ("I;16", "I;16B", "I;16L"):
                return np.asarray(im, dtype=np.uint16)
            if im.mode in ("L", "RGB"):
                return np.asarray(im)
            if im.mode in ("RGBA", "LA"):
                raise InvalidInputError(
                    f"{path} has an alpha channel ({im.mode}); save it without alpha first"
                )
            if im.mode in ("P", "1", "CMYK", "YCbCr"):
                return np.asarray(im.convert("RGB"))
            raise InvalidInputError(f"{path}: unsupported image mode {im.mode}")
    except OSError as exc:
        raise InvalidInputError(f"cannot read {path} as an image: {exc}") from exc


def write_image(path: Path, image: np.ndarray, *, bits: int = 8) -> None:
    """Write floats in [0, 1] as an 8- or 16-bit image (16-bit only for greyscale PNG/TIFF)."""
    from PIL import Image

    arr = np.asarray(image, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError("image to write contains NaN or inf")
    lo, hi = float(arr.min()), float(arr.max())
    if lo < 0 or hi > 1:
        raise InvalidInputError(f"expected values in [0, 1] to write, got {lo:g}..{hi:g}")
    if bits == 16 and arr.ndim == 2:
        Image.fromarray(np.round(arr * 65535).astype(np.uint16)).save(path)
        return
    Image.fromarray(np.round(arr * 255).astype(np.uint8)).save(path)
