"""Private image reading/writing for the ``mosaic`` and ``demosaic`` commands.

A stop-gap until :mod:`imageform.io` lands (the lead merges them): 8/16-bit PNG (and
other formats pillow reads) through pillow, float arrays through ``.npy``. Values follow
docs/conventions.md: uint8/uint16 are full-range encoded values, read as floats in [0, 1].
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["read_image", "write_image"]

_BITS = {8: np.uint8, 16: np.uint16}


def read_image(path: Path) -> tuple[np.ndarray, int | None]:
    """Read ``path``; returns (array, bit depth or None for float ``.npy``).

    PNG/TIFF/... come back as uint8 or uint16 arrays of shape (H, W) or (H, W, 3); ``.npy``
    as stored (floats in [0, 1], or uint8/uint16).
    """
    if not path.is_file():
        raise InvalidInputError(f"input {path} does not exist")
    if path.suffix.lower() == ".npy":
        arr = np.load(path, allow_pickle=False)
        bits = {np.dtype(np.uint8): 8, np.dtype(np.uint16): 16}.get(arr.dtype)
        return arr, bits
    if path.suffix.lower() == ".png":  # imageform's codec keeps 16-bit colour PNGs
        from imageform.io.png import read_png

        png = read_png(path)
        if png.shape[-1] in (2, 4):
            raise InvalidInputError(f"{path} has an alpha channel; save it without alpha")
        data = png[..., 0] if png.shape[-1] == 1 else png
        return data, 8 if data.dtype == np.uint8 else 16
    from PIL import Image

    with Image.open(path) as im:
        mode = im.mode
        if mode in ("I;16", "I;16B", "I;16L", "I"):
            arr = np.asarray(im, dtype=np.int64)
            if arr.min() < 0 or arr.max() > 65535:
                raise InvalidInputError(f"{path}: 32-bit integer image, expected 8 or 16 bits")
            return arr.astype(np.uint16), 16
        if mode == "L":
            return np.asarray(im, dtype=np.uint8), 8
        if mode in ("RGB", "RGBA", "P", "LA"):
            return np.asarray(im.convert("RGB"), dtype=np.uint8), 8
        raise InvalidInputError(f"{path}: unsupported image mode {mode!r}; use PNG or .npy")


def write_image(path: Path, image: np.ndarray, bits: int | None) -> None:
    """Write floats in [0, 1] to ``path``: ``.npy`` as float32, else a PNG of ``bits`` bits.

    Values outside [0, 1] raise for integer output (the caller decides whether to clip).
    """
    if path.suffix.lower() == ".npy":
        np.save(path, image.astype(np.float32, copy=False))
        return
    if path.suffix.lower() != ".png":
        raise InvalidInputError(f"output {path}: expected a .png or .npy file name")
    bits = 8 if bits is None else bits
    if bits not in _BITS:
        raise InvalidInputError(f"expected 8 or 16 bits for PNG output, got {bits}")
    lo, hi = float(image.min()), float(image.max())
    if lo < 0.0 or hi > 1.0:
        raise InvalidInputError(
            f"values span [{lo:.4g}, {hi:.4g}], outside [0, 1] for a {bits}-bit PNG; "
            "pass --clip or write .npy"
        )
    scale = 255.0 if bits == 8 else 65535.0
    data = np.round(image * scale).astype(_BITS[bits])
    from PIL import Image

    if data.ndim == 2 or bits == 8:
        im = Image.fromarray(data)  # uint8 (H, W) -> L, uint16 -> I;16, uint8 (H, W, 3) -> RGB
    else:  # pillow cannot write 48-bit RGB PNG: imageform's own encoder
        from imageform.io.png import write_png

        write_png(path, data)
        return
    im.save(path)
