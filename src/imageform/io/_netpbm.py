"""Netpbm images (PBM, PGM, PPM: P1-P6; PAM: P7), read and written without a codec library.

The format (netpbm.sourceforge.net/doc/pbm.html, pgm.html, ppm.html, pam.html): a magic
``P1``-``P7``, then width, height and (PGM, PPM) a maxval as ASCII decimals separated by
whitespace, ``#`` comments to the end of a line anywhere in that header, one whitespace
character, then the raster: ASCII decimals (P1, P2, P3), one byte per sample for a maxval
below 256 else two, most significant first (P5, P6, P7), or bits packed eight to a byte
with rows padded to a byte (P4). In PBM 1 is black; in PAM's BLACKANDWHITE 1 is white.

A sample ``v`` means the intensity ``v / maxval`` (pgm.html: "each gray value is ... between
0 and the specified maxval"). :func:`read` returns maxval 255 and 65535 as stored (uint8,
uint16), bilevel images as 0/255, and any other maxval scaled to the full range of its
container, ``round(v / maxval * (2**n - 1))`` with ``n`` 8 below 256 and 16 above (what
Pillow and imageio return; OpenCV returns the stored numbers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform.errors import UnreadableFileError

#: The Netpbm magic numbers, their names, and samples per pixel (PAM's from its header).
MAGIC = {b"P1": ("PBM", 1), b"P2": ("PGM", 1), b"P3": ("PPM", 3), b"P4": ("PBM", 1),
         b"P5": ("PGM", 1), b"P6": ("PPM", 3), b"P7": ("PAM", 0)}  # fmt: skip
_SPACE = b" \t\n\v\f\r"
#: PAM tuple types imageform reads: (channels, bilevel).
_TUPLTYPES = {b"BLACKANDWHITE": (1, True), b"GRAYSCALE": (1, False), b"RGB": (3, False),
              b"BLACKANDWHITE_ALPHA": (2, True), b"GRAYSCALE_ALPHA": (2, False),
              b"RGB_ALPHA": (4, False)}  # fmt: skip


def is_netpbm(head: bytes) -> bool:
    """Whether a file's first bytes are a Netpbm header (``P1``-``P7`` and whitespace)."""
    return len(head) >= 3 and head[:2] in MAGIC and head[2:3] in _SPACE


class Header:
    """A Netpbm header: kind (``P1``...), width, height, channels, maxval, raster offset."""

    def __init__(
        self,
        kind: bytes,
        width: int,
        height: int,
        channels: int,
        maxval: int,
        offset: int,
        bilevel: bool,
        has_alpha: bool,
    ) -> None:
        self.kind, self.width, self.height, self.channels = kind, width, height, channels
        self.maxval, self.offset, self.bilevel, self.has_alpha = maxval, offset, bilevel, has_alpha

    @property
    def dtype(self) -> str:
        """The sample type :func:`read` returns."""
        return "uint16" if self.maxval > 255 else "uint8"

    @property
    def name(self) -> str:
        return MAGIC[self.kind][0]


def _tokens(data: bytes, pos: int, count: int, p: Path) -> tuple[list[int], int]:
    """Read ``count`` ASCII decimals from ``pos``, skipping whitespace and ``#`` comments.

    Returns them and the position just past the last one's digits.
    """
    out: list[int] = []
    n = len(data)
    while len(out) < count:
        while pos < n and (data[pos] in _SPACE or data[pos] == 0x23):
            if data[pos] == 0x23:  # a comment, to the end of its line
                end = data.find(b"\n", pos)
                pos = n if end < 0 else end + 1
            else:
                pos += 1
        start = pos
        while pos < n and 0x30 <= data[pos] <= 0x39:
            pos += 1
        if pos == start or pos - start > 9:
            raise UnreadableFileError(p, "corrupt Netpbm header")
        out.append(int(data[start:pos]))
    return out, pos


def _pam_header(data: bytes, p: Path) -> Header:
    fields: dict[bytes, bytes] = {}
    pos = 3
    while True:
        end = data.find(b"\n", pos)
        if end < 0:
            raise UnreadableFileError(p, "corrupt PAM header (no ENDHDR)")
        line = data[pos:end].strip()
        pos = end + 1
        if not line or line.startswith(b"#"):
            continue
        if line == b"ENDHDR":
            break
        key, _, value = line.partition(b" ")
        if key == b"TUPLTYPE" and key in fields:  # several TUPLTYPE lines: joined
            fields[key] += b" " + value.strip()
        else:
            fields[key] = value.strip()
    try:
        width, height = int(fields[b"WIDTH"]), int(fields[b"HEIGHT"])
        depth, maxval = int(fields[b"DEPTH"]), int(fields[b"MAXVAL"])
    except (KeyError, ValueError):
        raise UnreadableFileError(
            p, "corrupt PAM header (WIDTH, HEIGHT, DEPTH and MAXVAL are needed)"
        ) from None
    tupltype = fields.get(b"TUPLTYPE", b"")
    known = _TUPLTYPES.get(tupltype)
    if known is None:  # no or another tuple type: grey or RGB, with alpha, by its depth
        if tupltype and not 1 <= depth <= 4:
            raise UnreadableFileError(
                p, f"a PAM of tuple type {tupltype.decode('latin-1')[:40]!r} and depth {depth}"
            )
        known = ({1: 1, 2: 2, 3: 3, 4: 4}.get(depth, depth), False)
    channels, bilevel = known
    if channels != depth or not 1 <= depth <= 4:
        raise UnreadableFileError(p, f"a PAM of depth {depth}; imageform reads 1 to 4 samples")
    if bilevel and maxval != 1:
        raise UnreadableFileError(p, f"a PAM BLACKANDWHITE image of maxval {maxval} (not 1)")
    return Header(b"P7", width, height, channels, maxval, pos, bilevel, depth in (2, 4))


def header(data: bytes, p: Path) -> Header:
    """Parse the header at the start of ``data`` (the file's bytes, or its first ones)."""
    kind = data[:2]
    if not is_netpbm(data[:3]):
        raise UnreadableFileError(p, "not a Netpbm file")
    if kind == b"P7":
        h = _pam_header(data, p)
    else:
        pbm = kind in (b"P1", b"P4")
        values, pos = _tokens(data, 2, 2 if pbm else 3, p)
        width, height = values[0], values[1]
        maxval = 1 if pbm else values[2]
        if kind != b"P1":  # one whitespace character, then the raster
            if pos >= len(data) or data[pos] not in _SPACE:
                raise UnreadableFileError(p, "corrupt Netpbm header")
            pos += 1
        h = Header(kind, width, height, MAGIC[kind][1], maxval, pos, pbm, False)
    if h.width <= 0 or h.height <= 0:
        raise UnreadableFileError(p, f"the image is empty ({h.width} x {h.height} px)")
    if not 1 <= h.maxval <= 65535:
        raise UnreadableFileError(p, f"maxval {h.maxval} outside 1 to 65535")
    return h


def _scale(v: np.ndarray, maxval: int) -> np.ndarray:
    """Scale samples of ``maxval`` to uint8 (maxval < 256) or uint16, white at the top."""
    if maxval in (255, 65535):
        return v.astype(np.uint8 if maxval == 255 else np.uint16)
    top = 255 if maxval < 256 else 65535
    out = np.rint(v.astype(np.float64) / maxval * top)
    return out.astype(np.uint8 if top == 255 else np.uint16)


def read(p: Path, data: bytes) -> tuple[np.ndarray, bool]:
    """Decode a Netpbm file's bytes: ``(H, W, C)`` array and whether its last channel is alpha."""
    h = header(data, p)
    w, ht, c = h.width, h.height, h.channels
    n = w * ht * c
    raster = memoryview(data)[h.offset :]
    if h.kind in (b"P1", b"P2", b"P3"):  # plain: ASCII decimals (P1: digits, spaces optional)
        text = bytes(raster)
        if h.kind == b"P1":
            text = b" ".join(text.split())  # comments are not allowed in a plain raster
            digits = np.frombuffer(text.replace(b" ", b""), np.uint8)
            if digits.size < n:
                raise UnreadableFileError(p, f"the file is truncated ({digits.size} of {n} pixels)")
            if np.any((digits[:n] != 0x30) & (digits[:n] != 0x31)):
                raise UnreadableFileError(p, "corrupt plain PBM raster (not 0 or 1)")
            v = (digits[:n] - 0x30).astype(np.uint32)
        else:
            try:
                v = np.array(text.split()[:n], dtype=np.uint32)
            except (ValueError, OverflowError):
                raise UnreadableFileError(p, f"corrupt plain {h.name} raster") from None
            if v.size < n:
                raise UnreadableFileError(p, f"the file is truncated ({v.size} of {n} samples)")
    elif h.kind == b"P4":
        stride = (w + 7) // 8
        if len(raster) < stride * ht:
            raise UnreadableFileError(
                p, f"the file is truncated ({len(raster)} raster bytes, {stride * ht} needed)"
            )
        packed = np.frombuffer(raster[: stride * ht], np.uint8).reshape(ht, stride)
        v = np.unpackbits(packed, axis=1)[:, :w].astype(np.uint32)
    else:
        size = 1 if h.maxval < 256 else 2
        if len(raster) < n * size:
            raise UnreadableFileError(
                p, f"the file is truncated ({len(raster)} raster bytes, {n * size} needed)"
            )
        v = np.frombuffer(raster[: n * size], np.uint8 if size == 1 else ">u2").astype(np.uint32)
    if h.bilevel:
        v = v.reshape(ht, w, c)
        grey = v[..., :1] if h.kind == b"P7" else 1 - v[..., :1]  # PBM: 1 is black
        if np.any(v[..., :1] > 1):
            raise UnreadableFileError(p, "a bilevel sample above 1")
        out = (grey * 255).astype(np.uint8)
        if c == 2:  # BLACKANDWHITE_ALPHA: alpha of maxval 1 too
            out = np.concatenate([out, (np.minimum(v[..., 1:], 1) * 255).astype(np.uint8)], -1)
        return out, c == 2
    if v.size and int(v.max()) > h.maxval:
        raise UnreadableFileError(p, f"a sample of {int(v.max())} above its maxval {h.maxval}")
    return _scale(v, h.maxval).reshape(ht, w, c), h.has_alpha


def encode(a: np.ndarray) -> bytes:
    """Encode uint8 or uint16 ``a`` as a binary PGM (P5, one channel) or PPM (P6, three)."""
    channels = a.shape[2] if a.ndim == 3 else 1
    kind = b"P5" if channels == 1 else b"P6"
    maxval = 255 if a.dtype == np.uint8 else 65535
    raster = a.astype(">u2").tobytes() if maxval == 65535 else a.tobytes()
    return b"%s\n%d %d\n%d\n" % (kind, a.shape[1], a.shape[0], maxval) + raster
