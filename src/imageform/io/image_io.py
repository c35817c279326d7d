"""Read and write images for the CLI: 8/16-bit PNG, float TIFF (tifffile), NumPy .npy.

- PNG holds displayable encoded values: uint8 / uint16 code values. Writing floats
  quantises ``round(v * (2^bits - 1))``; values outside [0, 1] are an error unless
  ``clip=True`` (no silent clipping), NaN always.
- TIFF (``.tif``, ``.tiff``) holds any float array (float32 by default) or integers.
- ``.npy`` holds any array exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform._validate import check_option
from imageform.errors import InvalidInputError

from .png import read_png, write_png

__all__ = ["IMAGE_FORMATS", "image_format", "read_image", "write_image"]

#: File suffixes and their formats.
IMAGE_FORMATS = {".png": "png", ".tif": "tiff", ".tiff": "tiff", ".npy": "npy"}


def image_format(path: str | Path) -> str:
    """The format of ``path`` from its suffix ("png", "tiff", "npy"); others raise."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMAGE_FORMATS:
        valid = ", ".join(sorted(IMAGE_FORMATS))
        raise InvalidInputError(f"unknown image file type {suffix!r} of {path}; valid: {valid}")
    return IMAGE_FORMATS[suffix]


def read_image(path: str | Path) -> np.ndarray:
    """Read an image: PNG as uint8/uint16 (H, W, C); TIFF and .npy as stored.

    Grey PNGs come back with a channel axis of size 1.
    """
    p = Path(path)
    fmt = image_format(p)
    if not p.is_file():
        raise InvalidInputError(f"input file {p} does not exist")
    if fmt == "png":
        return read_png(p)
    if fmt == "npy":
        return np.load(p, allow_pickle=False)
    import tifffile

    return np.asarray(tifffile.imread(p))


def write_image(path: str | Path, image: np.ndarray, *, bits: int = 8, clip: bool = False) -> None:
    """Write ``image``; PNG quantises floats in [0, 1] to ``bits`` (8 or 16).

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.png")
    >>> write_image(p, np.array([[[0.0, 0.5, 1.0]]]), bits=16)
    >>> read_image(p).tolist()
    [[[0, 32768, 65535]]]
    """
    p = Path(path)
    fmt = image_format(p)
    a = np.asarray(image)
    if fmt == "npy":
        np.save(p, a, allow_pickle=False)
        return
    if fmt == "tiff":
        import tifffile

        rgb = a.ndim == 3 and a.shape[-1] == 3
        tifffile.imwrite(p, a, photometric="rgb" if rgb else "minisblack")
        return
    check_option(str(bits), ("8", "16"), "PNG bit depth")
    if a.dtype in (np.uint8, np.uint16):
        write_png(p, a)
        return
    if a.dtype.kind != "f":
        raise InvalidInputError(
            f"expected floats in [0, 1], uint8 or uint16 for PNG, got {a.dtype}"
        )
    if not np.all(np.isfinite(a)):
        raise InvalidInputError("image contains NaN or inf; PNG cannot store it")
    lo, hi = float(a.min()), float(a.max())
    if (lo < 0 or hi > 1) and not clip:
        raise InvalidInputError(
            f"values outside [0, 1] (min {lo:.4g}, max {hi:.4g}) cannot be stored in PNG; "
            "write .tif/.npy, or pass clip=True (--clip) to clip them"
        )
    top = 2**bits - 1
    q = np.round(np.clip(a, 0.0, 1.0) * top)
    write_png(p, q.astype(np.uint8 if bits == 8 else np.uint16))
