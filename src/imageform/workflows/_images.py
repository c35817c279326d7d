"""Options and helpers every image-reading or image-writing workflow shares.

The out-of-range policy lives here, once: integer outputs (PNG, JPEG, and TIFF with
``--bits``) cannot hold values outside [0, 1]; by default they are clipped and a note says
how many (``--out-of-range error`` refuses instead); float outputs (TIFF, ``.npy``) keep every
value as computed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._spec import Options, Run, option

__all__ = ["ImageIn", "ImageOut", "read", "write"]


@dataclass(frozen=True, kw_only=True)
class ImageIn(Options):
    """How input images are read."""

    alpha: str = option(
        "reject",
        help="Transparent pixels in an input: reject, drop (ignore the alpha channel) or keep.",
        choices=("reject", "drop", "keep"),
    )
    max_pixels: int | None = option(
        None,
        help="Refuse input images with more pixels (default 100 Mpx, or IMAGEFORM_MAX_PIXELS).",
        metavar="N",
    )


@dataclass(frozen=True, kw_only=True)
class ImageOut(Options):
    """How output images are written."""

    bits: int | None = option(
        None,
        help="Bits per sample of PNG output (8 or 16; JPEG: 8) or of an integer TIFF; "
        "default: 16 for 16-bit input, else 8 (TIFF: float32).",
        metavar="8|16",
    )
    out_of_range: str = option(
        "clip",
        help="Values outside [0, 1] in integer output: clip (with a note) or error.",
        choices=("clip", "error"),
    )
    clip: bool = option(False, help="Same as --out-of-range clip.", hidden=True)

    def check(self) -> None:
        super().check()
        if self.bits is not None and self.bits not in (8, 16):
            raise InvalidInputError(f"expected --bits 8 or 16, got {self.bits}")
        if self.clip:
            object.__setattr__(self, "out_of_range", "clip")


def read(path: Path, opts: Any, *, alpha: str | None = None) -> Any:
    """Read ``path`` with the options' alpha rule and pixel limit (an :class:`ImageIn`)."""
    from imageform.io import read_image

    return read_image(
        path,
        alpha=str(alpha or getattr(opts, "alpha", "reject")),
        max_pixels=getattr(opts, "max_pixels", None),
    )


def write(run: Run, path: Path, image: Any, opts: Any, *, like: Any = None) -> int:
    """Write ``image`` (floats in [0, 1] or integers) to the output ``path``; return the clip count.

    The options' bits and out-of-range policy (an :class:`ImageOut`) apply; the count is how many
    values lay outside [0, 1] in an integer output (each clipped, noted once).

    ``like`` is the input array whose depth the output keeps (uint16 in, 16-bit PNG out).
    TIFF output is float32 unless ``--bits`` asks for integers; ``.npy`` keeps the dtype.
    """
    import numpy as np

    from imageform.io import image_format, write_image

    fmt = image_format(path)
    bits = getattr(opts, "bits", None)
    policy = getattr(opts, "out_of_range", "clip")
    a = np.asarray(image)
    if fmt in ("png", "jpeg") and bits is None:
        bits = 16 if like is not None and np.asarray(like).dtype == np.uint16 else 8
        if fmt == "jpeg":
            bits = 8
    if fmt == "tiff" and bits is None and a.dtype.kind == "f":
        a = a.astype(np.float32, copy=False)
    written = write_image(run.file(path), a, bits=bits, out_of_range=policy)
    if written.out_of_range:
        run.note(
            f"note: {written.out_of_range} values outside [0, 1] were clipped to fit the "
            f"{written.bits}-bit {path.name}; write .tif or .npy to keep them "
            "(--out-of-range error refuses instead)"
        )
    return written.out_of_range
