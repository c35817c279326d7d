"""A raw file's TIFF header, read with :mod:`struct`: the tags raw reading uses, not tifffile.

:func:`imageform.io.raw.read_raw` reads a DNG's (or a TIFF-based raw's) colour tags, opcode
lists and the end of its raw image's data before LibRaw decodes it. tifffile's ``TiffFile``
parses every tag of the IFDs it opens and builds a page and its attributes: a millisecond or
two a DNG, three to five times this reader's time, and its import in a fresh process
(``raw-small-2026-12-01g.md``). :func:`read_header` reads IFD 0 and its SubIFDs (TIFF 6.0,
section 2; the DNG specification 1.4.0.0, chapter 3) and decodes only the tags raw reading
looks at (:data:`WANTED`), into objects that answer as tifffile's ``TiffPage`` does where
:mod:`imageform.io.raw` and :mod:`imageform.io._dng_opcodes` ask (``tags`` with ``in``,
``[code].value``, ``.dtype``, ``valueof``, ``get``; ``dataoffsets``, ``databytecounts``,
``pages``), with tifffile's values: a BYTE, UNDEFINED tag's as bytes, ASCII as tifffile decodes
it, one value unwrapped from its tuple except for the tags tifffile keeps as tuples.

Anything this reader does not take exactly as tifffile does raises :class:`Unusual`, and the
caller reads the file with tifffile instead: BigTIFF, a tag it uses with an unknown type, a
value outside the file or of more than 1024 rationals, an IFD of no or too many tags, a SubIFD
offset outside the file, NDPI's 64-bit extension, a compression whose byte counts tifffile
would estimate.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["WANTED", "Unusual", "read_header"]


class Unusual(Exception):
    """The header is not one this reader takes exactly as tifffile does: use tifffile."""


#: struct formats of the TIFF field types (tifffile's ``TIFF.DATA_FORMATS``).
_FORMATS = {
    1: (1, "B"),
    2: (1, "s"),
    3: (1, "H"),
    4: (1, "I"),
    5: (2, "I"),
    6: (1, "b"),
    7: (1, "B"),
    8: (1, "h"),
    9: (1, "i"),
    10: (2, "i"),
    11: (1, "f"),
    12: (1, "d"),
    13: (1, "I"),
    16: (1, "Q"),
    17: (1, "q"),
    18: (1, "Q"),
}
#: Tags whose value tifffile keeps as a tuple even of one value (``TIFF.TAG_TUPLE``).
_TUPLE = frozenset((273, 279, 282, 283, 324, 325, 330, 338, 513, 514, 530, 531, 34736, 50838))

#: The tags decoded (and checked) when the IFD is read: those :mod:`imageform.io.raw` and
#: :mod:`imageform.io._dng_opcodes` look at in a header. NewSubfileType, Compression,
#: PhotometricInterpretation, the strips' and tiles' offsets and byte counts, SubIFDs, the
#: JPEG interchange format's, DNGVersion, UniqueCameraModel, LinearizationTable, the colour
#: tags, ActiveArea, OpcodeList1-3, NDPI's marker.
WANTED = frozenset(
    (254, 259, 262, 273, 279, 324, 325, 330, 513, 514)
    + (50706, 50708, 50712, 50721, 50722, 50723, 50724, 50727, 50729, 50730)
    + (50778, 50779, 50829, 51008, 51009, 51022, 65420)
)
#: TIFF's Compression codes whose missing byte counts tifffile estimates.
_ESTIMATED = (2, 3, 4)


class Tag:
    """One tag: ``code``, ``dtype`` (the TIFF field type), ``count``, ``value``."""

    __slots__ = ("code", "count", "dtype", "value")

    def __init__(self, code: int, dtype: int, count: int, value: Any) -> None:
        self.code = code
        self.dtype = dtype
        self.count = count
        self.value = value


class Tags:
    """An IFD's decoded tags by code (the first of a code, as tifffile keeps it)."""

    __slots__ = ("_tags",)

    def __init__(self, tags: dict[int, Tag]) -> None:
        self._tags = tags

    def __contains__(self, code: object) -> bool:
        return code in self._tags

    def __getitem__(self, code: int) -> Tag:
        return self._tags[code]

    def get(self, code: int, default: Any = None) -> Any:
        """Return the tag of ``code``, else ``default``."""
        return self._tags.get(code, default)

    def valueof(self, code: int, default: Any = None) -> Any:
        """Return the value of the tag of ``code``, else ``default``."""
        tag = self._tags.get(code)
        return default if tag is None else tag.value


class Ifd:
    """One IFD: its ``tags``, ``dataoffsets``, ``databytecounts`` and SubIFDs (``pages``)."""

    __slots__ = ("databytecounts", "dataoffsets", "pages", "tags")

    def __init__(self, tags: Tags, pages: list[Ifd] | None) -> None:
        self.tags = tags
        self.pages = pages
        # tifffile's choice: the tiles', else the strips', else the JPEG interchange format's
        self.dataoffsets = _first(tags, (324, 273, 513))
        self.databytecounts = _first(tags, (325, 279, 514))


def _first(tags: Tags, codes: tuple[int, ...]) -> Any:
    for code in codes:
        value = tags.valueof(code)
        if value is not None:
            return value
    return ()


def _ascii(raw: bytes) -> str | bytes:
    """Return an ASCII tag's value as tifffile does: trailing NULs cut, decoded, stripped."""
    raw = raw.rstrip(b"\x00")
    try:
        return raw.decode("utf-8").strip()
    except UnicodeDecodeError:
        try:
            return raw.decode("cp1252").strip()
        except UnicodeDecodeError:
            return raw


#: Bytes read at once from the start of the file: the IFDs and their values are there in
#: the DNGs seen (a read per tag costs more than the tag's decoding).
_HEAD = 1 << 16


class _Reader:
    def __init__(self, f: Any, size: int, order: str, head: bytes) -> None:
        self.f = f
        self.size = size
        self.order = order
        self.head = head

    def read_at(self, offset: int, n: int) -> bytes:
        if offset + n <= len(self.head):
            return self.head[offset : offset + n]
        self.f.seek(offset)
        data = self.f.read(n)
        if len(data) != n:
            raise Unusual("short read")
        return data

    def ifd(self, offset: int, *, subifds: bool) -> Ifd:
        order = self.order
        (n,) = struct.unpack(order + "H", self.read_at(offset, 2))
        if n == 0 or n > 4096:
            raise Unusual("an IFD of no or too many tags")
        block = self.read_at(offset + 2, 12 * n)
        tags: dict[int, Tag] = {}
        for code, dtype, count, field in struct.iter_unpack(order + "HHI4s", block):
            if code in tags or code not in WANTED:
                continue  # tifffile keeps a code's first tag; the others are not looked at
            tags[code] = self.tag(code, dtype, count, field)
        if 65420 in tags:
            raise Unusual("NDPI")  # tifffile reads such a file's offsets as 64-bit
        table = Tags(tags)
        if int(table.valueof(259, 1)) in _ESTIMATED:
            raise Unusual("byte counts tifffile may estimate")
        pages: list[Ifd] | None = None
        if subifds and 330 in tags:
            offsets = tags[330].value
            if not offsets or any(not 8 <= o < self.size for o in offsets):
                raise Unusual("a SubIFD offset outside the file")
            pages = [self.ifd(o, subifds=False) for o in offsets]
        return Ifd(table, pages)

    def tag(self, code: int, dtype: int, count: int, field: bytes) -> Tag:
        fmt = _FORMATS.get(dtype)
        if fmt is None:
            raise Unusual(f"tag {code} of type {dtype}")
        size = count * fmt[0] * struct.calcsize(fmt[1])
        if size > 4:
            (at,) = struct.unpack(self.order + "I", field)
            if at < 8 or at + size > self.size:
                raise Unusual(f"tag {code}'s value outside the file")
            data = self.read_at(at, size)
        else:
            data = field[:size]
        value: Any
        if dtype in (1, 7):  # BYTE, UNDEFINED
            value = data
        elif dtype == 2:
            value = _ascii(data)
        else:
            if count > 1024:  # tifffile reads these as an array (a rational's oddly)
                if fmt[0] != 1:
                    raise Unusual(f"tag {code} of {count} rationals")
                return Tag(code, dtype, count, np.frombuffer(data, self.order + fmt[1], count))
            value = struct.unpack(f"{self.order}{count * fmt[0]}{fmt[1]}", data)
            if len(value) == 1 and code not in _TUPLE:
                value = value[0]
        return Tag(code, dtype, count, value)


def read_header(path: Path) -> Ifd:
    """Return IFD 0 of a TIFF-based file, with its SubIFDs (``pages``).

    Raises :class:`Unusual` where tifffile should read it: BigTIFF, the cases of the
    module's docstring, and whatever fails here (tifffile then reads it, or says why not).
    """
    try:
        return _read_header(path)
    except Unusual:
        raise
    except Exception as exc:  # a short file, a tag of an odd value: tifffile's business
        raise Unusual(repr(exc)) from None


def _read_header(path: Path) -> Ifd:
    with open(path, "rb") as f:
        head = f.read(_HEAD)
        size = os.fstat(f.fileno()).st_size
        if len(head) < 8 or head[:4] not in (b"II*\x00", b"MM\x00*"):
            raise Unusual("not a classic TIFF")
        order = "<" if head[:2] == b"II" else ">"
        (first,) = struct.unpack(order + "I", head[4:8])
        if not 8 <= first < size:
            raise Unusual("IFD 0 outside the file")
        return _Reader(f, size, order, head).ifd(first, subifds=True)
