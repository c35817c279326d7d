"""Radiance HDR (RGBE) images, read without a codec library.

The format (Greg Ward, "Real Pixels", Graphics Gems II, 1991, and Radiance's ``color.c`` and
``header.c``): a text header starting ``#?RADIANCE`` (or another ``#?`` program name), lines
of ``VARIABLE=value`` (``FORMAT=32-bit_rle_rgbe``; ``EXPOSURE=``, ``PRIMARIES=`` ...) up to an
empty line, then a resolution line, ``-Y H +X W`` for the usual top-to-bottom rows of
left-to-right pixels (the eight orders of ``[-+]Y H [-+]X W`` and ``[-+]X W [-+]Y H`` are all
read), then the scanlines: 4 bytes a pixel, a mantissa each for R, G, B and a shared exponent
``E``, either flat, in Radiance's old run-length form (a pixel ``1, 1, 1, n`` repeats the one
before it ``n << shift`` times), or in the new one (a scanline of width 8 to 32767 that starts
``2, 2, W >> 8, W & 255``, then each of the four components run-length coded on its own:
a count above 128 repeats the next byte ``count - 128`` times, else that many bytes follow).

A pixel means ``(m + 0.5) * 2**(E - 136)`` for each mantissa ``m`` and 0 where ``E`` is 0
(Radiance's ``colr_color``): linear values, float32. OpenCV's reader (Bruce Walter's
``rgbe.c``) leaves out the ``+ 0.5``: the two differ by half a mantissa step,
``0.5 * 2**(E - 136)``, exactly. The header's ``EXPOSURE`` is not divided out (as OpenCV and
imageio): the values are the file's.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from imageform.errors import UnreadableFileError

_RESOLUTION = re.compile(rb"\A([-+])([XY]) +(\d{1,9}) +([-+])([XY]) +(\d{1,9})\s*\Z")


def is_hdr(head: bytes) -> bool:
    """Whether a file's first bytes are a Radiance header (``#?RADIANCE``, ``#?RGBE`` ...)."""
    return head.startswith((b"#?RADIANCE", b"#?RGBE"))


class Header:
    """A Radiance header: the image's width and height, its scanline order, raster offset."""

    def __init__(self, width: int, height: int, axes: tuple[bytes, ...], offset: int) -> None:
        self.width, self.height, self.axes, self.offset = width, height, axes, offset


def header(data: bytes, path: Path) -> Header:
    """Parse the text header and resolution line; one line if they are not a Radiance file's."""
    if not is_hdr(data):
        raise UnreadableFileError(path, "not a Radiance HDR file (no #?RADIANCE header)")
    end = data.find(b"\n\n", 0, 1 << 16)
    if end < 0:
        raise UnreadableFileError(path, "corrupt Radiance header (no empty line ending it)")
    for line in data[:end].split(b"\n")[1:]:
        key, _, value = line.partition(b"=")
        if key.strip() == b"FORMAT" and value.strip() != b"32-bit_rle_rgbe":
            what = value.strip().decode("ascii", "replace")[:30]
            raise UnreadableFileError(
                path, f"a Radiance file of FORMAT={what}; imageform reads 32-bit_rle_rgbe (RGB)"
            )
    stop = data.find(b"\n", end + 2, end + 2 + 64)
    m = _RESOLUTION.match(data[end + 2 : stop]) if stop > 0 else None
    if m is None or m.group(2) == m.group(5):
        raise UnreadableFileError(path, "corrupt Radiance resolution line (expected -Y H +X W)")
    s1, a1, n1, s2, a2, n2 = m.groups()
    width, height = (int(n2), int(n1)) if a1 == b"Y" else (int(n1), int(n2))
    if width == 0 or height == 0:
        raise UnreadableFileError(path, f"a Radiance image of {width} x {height} px holds nothing")
    return Header(width, height, (s1 + a1, s2 + a2), stop + 1)


#: Rec. 709's primaries (x, y of R, G, B), and Radiance's default ``STDPRIMS`` (``color.h``:
#: "CCIR-709" as Radiance states it, green at x 0.290 where Rec. 709 has 0.300; its white,
#: 1/3, 1/3, is the equal-energy one). Both are read as ``linear_srgb``: RGB (1, 1, 1) is
#: white either way, and a file without a PRIMARIES line means Radiance's.
_REC709 = (0.640, 0.330, 0.300, 0.600, 0.150, 0.060)
_STDPRIMS = (0.640, 0.330, 0.290, 0.600, 0.150, 0.060)


def declared(data: bytes, path: Path) -> tuple[str | None, str]:
    """Return the space a Radiance header declares, and how it says so.

    ``linear_srgb`` unless its ``PRIMARIES=`` line names primaries other than Rec. 709's or
    Radiance's standard ones (then None, the line quoted).
    """
    header(data, path)  # refuses what is no Radiance file
    end = data.find(b"\n\n")
    for line in data[:end].split(b"\n"):
        key, _, value = line.partition(b"=")
        if key.strip() != b"PRIMARIES":
            continue
        try:
            xy = [float(v) for v in value.split()]
        except ValueError:
            xy = []
        text = value.strip().decode("ascii", "replace")[:80]
        for primaries in (_REC709, _STDPRIMS):
            if len(xy) == 8 and all(
                abs(a - b) < 0.005 for a, b in zip(xy[:6], primaries, strict=True)
            ):
                return "linear_srgb", f"linear RGB, PRIMARIES={text}"
        return None, f"linear RGB of PRIMARIES={text}, no space of imageform"
    return "linear_srgb", "linear RGB, Rec. 709 primaries (no PRIMARIES line)"


def _truncated(path: Path, row: int, rows: int) -> UnreadableFileError:
    return UnreadableFileError(path, f"the file is truncated (scanline {row} of {rows})")


def _scanlines(
    data: bytes, offset: int, length: int, count: int, path: Path, out: np.ndarray | None
) -> None:
    """Walk ``count`` scanlines of ``length`` RGBE pixels; decode them into ``out`` if given.

    ``out``: uint8 ``(count, length, 4)``, or None to step over the scanlines only (what
    :func:`check_size` can afford): a new-style run-length scanline a run at a time, a flat
    one as ``length`` pixels at once (a pixel at a time only where it holds Radiance's old
    runs). A corrupt run or a file that ends early is one line naming the scanline.
    """
    pos, size = offset, len(data)
    buf = np.frombuffer(data, np.uint8)
    for row in range(count):
        head = data[pos : pos + 4]
        if len(head) < 4:
            raise _truncated(path, row, count)
        if 8 <= length <= 0x7FFF and head[0] == 2 and head[1] == 2 and not head[2] & 0x80:
            if (head[2] << 8) | head[3] != length:
                raise UnreadableFileError(
                    path, f"corrupt scanline {row}: its length is not the image's width"
                )
            pos += 4
            for c in range(4):
                x = 0
                while x < length:
                    if pos >= size:
                        raise _truncated(path, row, count)
                    n = data[pos]
                    run = n > 128
                    n = n - 128 if run else n
                    if n == 0 or x + n > length:
                        raise UnreadableFileError(path, f"corrupt run in scanline {row}")
                    if pos + 1 + (1 if run else n) > size:
                        raise _truncated(path, row, count)
                    if out is not None:
                        out[row, x : x + n, c] = buf[pos + 1] if run else buf[pos + 1 : pos + 1 + n]
                    pos += 2 if run else 1 + n
                    x += n
            continue
        px = buf[pos : pos + 4 * min(length, max(size - pos, 0) // 4)].reshape(-1, 4)
        if not ((px[:, 0] == 1) & (px[:, 1] == 1) & (px[:, 2] == 1)).any():
            if len(px) < length:
                raise _truncated(path, row, count)
            if out is not None:
                out[row] = px
            pos += 4 * length
            continue
        x, shift = 0, 0
        while x < length:  # Radiance's old runs (1, 1, 1, n: repeat the pixel before)
            p4 = data[pos : pos + 4]
            if len(p4) < 4:
                raise _truncated(path, row, count)
            pos += 4
            if p4[0] == 1 and p4[1] == 1 and p4[2] == 1:
                n = p4[3] << shift
                if x == 0 or x + n > length:
                    raise UnreadableFileError(path, f"corrupt run in scanline {row}")
                if out is not None:
                    out[row, x : x + n] = out[row, x - 1]
                x, shift = x + n, shift + 8
            else:
                if out is not None:
                    out[row, x] = buf[pos - 4 : pos]
                x, shift = x + 1, 0


def check_size(head: Header, data: bytes, path: Path) -> None:
    """Refuse, in one line, a file whose scanlines end before the image does (or are corrupt).

    The scanlines are stepped over, not decoded (:func:`_scanlines` without ``out``). A header
    alone, or a file cut in its last scanline, says which scanline it ends in, as
    :func:`read` does.
    """
    count, length = (
        (head.height, head.width) if head.axes[0][1:] == b"Y" else (head.width, head.height)
    )
    _scanlines(data, head.offset, length, count, path, None)


def read(path: Path, data: bytes) -> np.ndarray:
    """Decode a Radiance HDR file's bytes as float32 ``(H, W, 3)``, linear, top row first."""
    head = header(data, path)
    (o1, o2) = head.axes
    count, length = (head.height, head.width) if o1[1:] == b"Y" else (head.width, head.height)
    rgbe = np.empty((count, length, 4), np.uint8)
    _scanlines(data, head.offset, length, count, path, rgbe)
    e = rgbe[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(np.float32(1.0), e - 136), 0).astype(np.float32)
    rgb = (rgbe[..., :3].astype(np.float32) + np.float32(0.5)) * scale[..., None]
    if o1[1:] == b"X":  # scanlines are columns: (X, Y) -> (Y, X)
        rgb = np.swapaxes(rgb, 0, 1)
        o1, o2 = o2, o1
    if o1 == b"+Y":  # the first scanline is the bottom one
        rgb = rgb[::-1]
    if o2 == b"-X":  # pixels from right to left
        rgb = rgb[:, ::-1]
    return np.ascontiguousarray(rgb, dtype=np.float32)
