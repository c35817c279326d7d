"""A small CMYK ICC profile, written here, for CMYK JPEG test files (no CMYK profile ships).

ICC.1:2001-04 (version 2.1): an output (``prtr``) profile of data colour space ``CMYK`` and
PCS ``XYZ``, with ``desc``, ``wtpt``, ``cprt`` and an ``A2B0`` tag of type ``mft2`` (lut16,
sec. 6.5.8): identity input and output tables and a 3-point grid per ink (81 nodes). The
device it describes is not the naive ``(1 - C)(1 - K)`` sRGB encoding but inks of limited
density acting on linear light, ``R = (1 - 0.9 C)(1 - 0.95 K)`` (likewise G with M, B with
Y), then sRGB's primaries adapted to D50 by Bradford (IEC 61966-2-1 with ICC.1 annex E), so
that a conversion through the profile is told apart from the naive one by tens of codes.
"""

from __future__ import annotations

import itertools
import struct

import numpy as np

__all__ = ["cmyk_profile"]

#: Linear sRGB to XYZ adapted to D50 (Bradford), the matrix of sRGB's ICC profiles.
_SRGB_D50 = np.array(
    [
        [0.4360747, 0.3850649, 0.1430804],
        [0.2225045, 0.7168786, 0.0606169],
        [0.0139322, 0.0971045, 0.7141733],
    ]
)
_D50 = (0.9642, 1.0, 0.8249)


def _s15(v: float) -> bytes:
    return struct.pack(">i", round(v * 65536))


def _pad(b: bytes) -> bytes:
    return b + b"\0" * (-len(b) % 4)


def cmyk_profile(description: str = "imageform test CMYK") -> bytes:
    """Return the bytes of the CMYK profile described in the module's docstring."""
    text = description.encode("ascii") + b"\0"
    desc = b"desc" + b"\0" * 4 + struct.pack(">I", len(text)) + text
    desc += b"\0" * 8 + b"\0" * 3 + b"\0" * 67  # no Unicode, no ScriptCode description
    wtpt = b"XYZ " + b"\0" * 4 + b"".join(_s15(v) for v in _D50)
    cprt = b"text" + b"\0" * 4 + b"No copyright, use freely\0"
    grid = 3
    head = b"mft2" + b"\0" * 4 + bytes([4, 3, grid, 0])
    head += b"".join(_s15(v) for v in (1, 0, 0, 0, 1, 0, 0, 0, 1))
    head += struct.pack(">HH", 2, 2)
    in_tables = struct.pack(">HH", 0, 65535) * 4
    nodes: list[int] = []
    levels = np.linspace(0.0, 1.0, grid)
    for c, m, y, k in itertools.product(levels, repeat=4):  # the first ink varies slowest
        rgb = np.array([1 - 0.9 * c, 1 - 0.9 * m, 1 - 0.9 * y]) * (1 - 0.95 * k)
        xyz = _SRGB_D50 @ rgb
        nodes.extend(round(min(v, 1.99997) * 32768) for v in xyz)  # u1Fixed15
    clut = struct.pack(f">{len(nodes)}H", *nodes)
    out_tables = struct.pack(">HH", 0, 65535) * 3
    a2b0 = head + in_tables + clut + out_tables
    tags = [(b"desc", desc), (b"wtpt", wtpt), (b"cprt", cprt), (b"A2B0", a2b0)]
    offset = 128 + 4 + 12 * len(tags)
    table, body = b"", b""
    for sig, data in tags:
        table += sig + struct.pack(">II", offset + len(body), len(data))
        body += _pad(data)
    size = offset + len(body)
    header = struct.pack(">I", size) + b"\0" * 4 + bytes([2, 0x10, 0, 0]) + b"prtrCMYKXYZ "
    header += struct.pack(">6H", 2026, 11, 29, 0, 0, 0) + b"acsp" + b"\0" * 4 + b"\0" * 4
    header += b"\0" * 8 + b"\0" * 8 + b"\0" * 4 + b"".join(_s15(v) for v in _D50)
    header += b"\0" * 4 + b"\0" * 16 + b"\0" * 28
    assert len(header) == 128
    return header + struct.pack(">I", len(tags)) + table + body
