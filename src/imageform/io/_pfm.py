"""PFM (Portable Float Map) images, read and written without a codec library.

The format (Paul Debevec's HDRShop page, www.pauldebevec.com/Research/HDR/PFM/, which the
Middlebury stereo benchmark uses for its disparity maps): a magic ``PF`` (RGB, three samples
a pixel) or ``Pf`` (grey, one), whitespace, the width and the height as ASCII decimals, whitespace,
a scale as an ASCII real, one whitespace character, then the raster: 4-byte IEEE floats,
interleaved, **rows from the bottom of the image to its top**. The scale's sign is the byte
order: negative little-endian, positive big-endian; its magnitude is a scale factor the
format leaves to the application: :func:`read` returns the stored numbers, as Pillow does
(OpenCV 4.x divides them by the magnitude; the two agree on the usual ``-1.0`` / ``1.0``, which
the Middlebury files and the writers of OpenCV and :func:`encode` use). Middlebury marks
unknown disparities as ``inf``: non-finite samples are read as they are.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from imageform.errors import UnreadableFileError

#: The magic, width, height and scale, then the one whitespace character before the raster.
_HEADER = re.compile(rb"\A(P[Ff])\s+(\d{1,9})\s+(\d{1,9})\s+([-+]?[0-9.]+(?:[eE][-+]?\d+)?)\s")


def is_pfm(head: bytes) -> bool:
    """Whether a file's first bytes are a PFM header (``PF`` or ``Pf`` and whitespace)."""
    return len(head) >= 3 and head[:2] in (b"PF", b"Pf") and head[2:3].isspace()


class Header:
    """A PFM header: width, height, channels, byte order (``<`` or ``>``), raster offset."""

    def __init__(self, width: int, height: int, channels: int, order: str, offset: int) -> None:
        self.width, self.height, self.channels = width, height, channels
        self.order, self.offset = order, offset

    @property
    def raster_bytes(self) -> int:
        """The bytes the raster takes: 4 per sample."""
        return self.width * self.height * self.channels * 4


def header(data: bytes, path: Path) -> Header:
    """Parse a PFM header from the file's first bytes; one line if it is not one."""
    m = _HEADER.match(data[:256])
    if m is None:
        raise UnreadableFileError(
            path, "corrupt PFM header (expected PF or Pf, width, height and scale)"
        )
    kind, w, h, scale_text = m.groups()
    width, height = int(w), int(h)
    try:
        scale = float(scale_text)
    except ValueError:
        scale = math.nan
    if width == 0 or height == 0:
        raise UnreadableFileError(path, f"a PFM of {width} x {height} px holds no image")
    if not math.isfinite(scale) or scale == 0:
        raise UnreadableFileError(
            path, f"a PFM scale of {scale_text.decode('ascii', 'replace')!r} (expected a "
            "non-zero number: its sign is the byte order)"
        )  # fmt: skip
    channels = 3 if kind == b"PF" else 1
    return Header(width, height, channels, "<" if scale < 0 else ">", m.end())


def check_size(head: Header, size: int, path: Path) -> None:
    """Refuse a file of fewer bytes than its header promises, in one line."""
    need = head.offset + head.raster_bytes
    if size < need:
        raise UnreadableFileError(
            path, f"the file is truncated ({size} bytes, its header promises {need})"
        )


def read(path: Path, data: bytes) -> np.ndarray:
    """Decode a PFM file's bytes as float32 ``(H, W, C)``, top row first."""
    head = header(data, path)
    check_size(head, len(data), path)
    raster = np.frombuffer(data, dtype=f"{head.order}f4", count=head.raster_bytes // 4,
                           offset=head.offset)  # fmt: skip
    image = raster.reshape(head.height, head.width, head.channels)[::-1]  # bottom row first
    return np.ascontiguousarray(image, dtype=np.float32)


def encode(a: np.ndarray) -> bytes:
    """Encode ``a`` (H, W) or (H, W, 1) as ``Pf``, (H, W, 3) as ``PF``: little-endian float32.

    The scale is ``-1.0`` (little-endian, factor 1), rows from the bottom up, as OpenCV and
    the Middlebury tools write them.
    """
    channels = a.shape[2] if a.ndim == 3 else 1
    kind = b"Pf" if channels == 1 else b"PF"
    rows = np.ascontiguousarray(a.reshape(a.shape[0], a.shape[1], channels)[::-1], dtype="<f4")
    return b"%s\n%d %d\n-1.0\n" % (kind, a.shape[1], a.shape[0]) + rows.tobytes()
