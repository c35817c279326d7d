"""A minimal PNG codec for 8- and 16-bit grey, grey+alpha, RGB and RGBA (no palette).

Pillow cannot write 16-bit RGB PNGs (and reads them as 8-bit), so imageform writes and
reads non-interlaced PNGs itself with :mod:`zlib` (PNG specification, ISO/IEC 15948:2004,
clauses 5-11: signature, IHDR, IDAT with per-row filters 0-4, IEND). Other PNGs
(palette, < 8 bits, interlaced) are read with Pillow, at 8 bits.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["read_png", "write_png"]

_SIG = b"\x89PNG\r\n\x1a\n"
_COLOR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> PNG colour type
_CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data))
        + kind
        + data
        + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def write_png(path: str | Path, image: np.ndarray) -> None:
    """Write a uint8 or uint16 image of shape (H, W) or (H, W, C), C in 1-4, as PNG.

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.png")
    >>> write_png(p, np.array([[[0, 1000, 65535]]], dtype=np.uint16))
    >>> read_png(p).tolist()
    [[[0, 1000, 65535]]]
    """
    a = np.asarray(image)
    if a.dtype not in (np.uint8, np.uint16):
        raise InvalidInputError(f"expected uint8 or uint16 for PNG, got dtype {a.dtype}")
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] not in _COLOR_TYPES or 0 in a.shape:
        raise InvalidInputError(f"expected a PNG image of shape (H, W, 1..4), got {a.shape}")
    h, w, c = a.shape
    depth = 8 if a.dtype == np.uint8 else 16
    rows = a.astype(">u2") if depth == 16 else a
    raw = np.zeros((h, 1 + w * c * (depth // 8)), np.uint8)  # filter byte 0 per row
    raw[:, 1:] = np.ascontiguousarray(rows).view(np.uint8).reshape(h, -1)
    ihdr = struct.pack(">IIBBBBB", w, h, depth, _COLOR_TYPES[c], 0, 0, 0)
    data = _SIG + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
    Path(path).write_bytes(data + _chunk(b"IEND", b""))


def _unfilter(raw: np.ndarray, h: int, stride: int, bpp: int) -> np.ndarray:
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.int32)
    for y in range(h):
        ftype = raw[y, 0]
        line = raw[y, 1:].astype(np.int32)
        if ftype == 0:
            cur = line
        elif ftype == 2:
            cur = (line + prev) & 0xFF
        else:  # 1 (sub), 3 (average), 4 (Paeth) depend on the left neighbour: per pixel
            cur = np.zeros(stride, np.int32)
            for i in range(stride):
                left = cur[i - bpp] if i >= bpp else 0
                up = prev[i]
                if ftype == 1:
                    pred = left
                elif ftype == 3:
                    pred = (left + up) >> 1
                elif ftype == 4:
                    ul = prev[i - bpp] if i >= bpp else 0
                    p = left + up - ul
                    pa, pb, pc = abs(p - left), abs(p - up), abs(p - ul)
                    pred = left if pa <= pb and pa <= pc else (up if pb <= pc else ul)
                else:
                    raise InvalidInputError(f"corrupt PNG: filter type {ftype}")
                cur[i] = (line[i] + pred) & 0xFF
        out[y] = cur
        prev = cur
    return out


def read_png(path: str | Path) -> np.ndarray:
    """Read a PNG as uint8 or uint16, shape (H, W, C) (C = 1 for grey).

    16-bit non-interlaced grey/GA/RGB/RGBA are decoded here (Pillow reads them as 8-bit);
    everything else via Pillow.
    """
    data = Path(path).read_bytes()
    if not data.startswith(_SIG):
        raise InvalidInputError(f"{path} is not a PNG file")
    pos, idat, hdr = 8, [], None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + n]
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + n
    if hdr is None:
        raise InvalidInputError(f"{path}: PNG without IHDR")
    w, h, depth, ctype, _, _, interlace = hdr
    if depth != 16 or ctype not in _CHANNELS or interlace:
        # 8-bit (any filter, fast) and exotic PNGs: Pillow, at 8 bits
        from PIL import Image

        with Image.open(path) as im:
            if im.mode in ("L", "LA", "RGB", "RGBA"):
                arr = np.asarray(im)
            else:
                arr = np.asarray(im.convert("RGBA" if "A" in im.mode else "RGB"))
        return arr[:, :, None] if arr.ndim == 2 else arr
    c = _CHANNELS[ctype]
    bpp = c * depth // 8
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8).reshape(h, 1 + w * bpp)
    px = _unfilter(raw, h, w * bpp, bpp)
    if depth == 16:
        return px.view(">u2").astype(np.uint16).reshape(h, w, c)
    return px.reshape(h, w, c)
