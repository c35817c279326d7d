r"""A VC-5 decoder (SMPTE ST 2073) for the raw images of GoPro's GPR files (DNG Compression 9).

A GPR file is a DNG whose raw image (one tile, usually the whole image) is a VC-5 bitstream,
the wavelet codec of GoPro's reference SDK (github.com/gopro/gpr, Apache-2.0 or MIT, whose
decoder this one follows exactly: ``source/lib/vc5_decoder`` and ``vc5_common``). The
bitstream is a sequence of 32-bit big-endian segments, a signed 16-bit tag and a 16-bit value
(a negative tag: an optional segment), after the start marker ``VC-5``:

- the header: ImageWidth (20), ImageHeight (21), ChannelCount (12, four for a raw image),
  ImageFormat (84, 4: a raw image), PatternWidth/Height (106/107, 2x2), ComponentsPerSample
  (108), MaxBitsPerComponent (102), each at most once;
- per channel, ten subbands: ChannelNumber (62), SubbandNumber (48), LowpassPrecision (35),
  Quantization (53), PrescaleShift (109, two bits per wavelet level, level 0 in bits 15-14),
  then the subband in a codeblock (tag 0x6000 with the size in its low byte and value): the
  lowpass band of the third wavelet (subband 0) as ``LowpassPrecision``-bit values, or a
  highpass band run-length coded with codebook 17 (:mod:`imageform._kernels.vc5`), each
  padded to 32 bits;
- chunks that carry nothing for decoding: sections (tags 0x2000-0x27FF), the unique image
  identifier (0x4004) and other optional small chunks (skipped by their size).

Each channel is a 3-level wavelet pyramid of one of the four Bayer components (half the
image's width and height): subbands 1-3 belong to level 3, 4-6 to level 2, 7-9 to level 1;
a level's four bands inverted give the lowpass band of the level below, level 1's the
component array. The four component arrays (G sum, R - G, B - G, G difference) become the
Bayer mosaic through GoPro's log curve, :math:`65535\,(113^{x/4095} - 1)/112` for 12-bit
:math:`x`, at 14 bits for an RGGB CFA (what GoPro's SDK writes into the DNG it converts a GPR
to, WhiteLevel 16383) and 12 bits in GBRG order for any other.

:func:`decode` is the entry point; a bitstream it cannot decode raises :class:`Vc5Error`
with a one-line reason.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

__all__ = ["Vc5Error", "decode", "log_curve"]


class Vc5Error(ValueError):
    """A VC-5 bitstream that cannot be decoded; the message says why, in one line."""


#: Codebook 17 of GoPro's SDK (``vc5_common/table17.inc``): (bits, code, run, magnitude),
#: in the order the reference decoder searches it (by size). Run 0, magnitude 1 ends a band.
# fmt: off
CODEBOOK_17 = (
    (1, 0x0, 1, 0), (2, 0x2, 1, 1), (3, 0x7, 1, 2), (5, 0x19, 1, 3), (6, 0x30, 1, 4),
    (6, 0x36, 1, 5), (7, 0x6F, 1, 8), (7, 0x63, 1, 6), (7, 0x69, 12, 0), (7, 0x6B, 1, 7),
    (8, 0xD1, 20, 0), (8, 0xD4, 1, 9), (8, 0xDC, 1, 10), (9, 0x189, 1, 11), (9, 0x18A, 32, 0),
    (9, 0x1A0, 1, 12), (9, 0x1AB, 1, 13), (10, 0x377, 1, 18), (10, 0x310, 1, 14),
    (10, 0x316, 1, 15), (10, 0x343, 60, 0), (10, 0x354, 1, 16), (10, 0x375, 1, 17),
    (11, 0x623, 1, 19), (11, 0x684, 1, 20), (11, 0x685, 100, 0), (11, 0x6AB, 1, 21),
    (11, 0x6EC, 1, 22), (12, 0xDDB, 1, 29), (12, 0xC5C, 1, 24), (12, 0xC5E, 1, 25),
    (12, 0xC44, 1, 23), (12, 0xD55, 1, 26), (12, 0xDD1, 1, 27), (12, 0xDD3, 1, 28),
    (13, 0x1BB5, 1, 35), (13, 0x188B, 1, 30), (13, 0x18BB, 1, 31), (13, 0x18BF, 180, 0),
    (13, 0x1AA8, 1, 32), (13, 0x1BA0, 1, 33), (13, 0x1BA5, 320, 0), (13, 0x1BA4, 1, 34),
    (14, 0x3115, 1, 36), (14, 0x3175, 1, 37), (14, 0x317D, 1, 38), (14, 0x3553, 1, 39),
    (14, 0x3768, 1, 40), (15, 0x6E87, 1, 46), (15, 0x6ED3, 1, 47), (15, 0x62E8, 1, 42),
    (15, 0x62F8, 1, 43), (15, 0x6228, 1, 41), (15, 0x6AA4, 1, 44), (15, 0x6E85, 1, 45),
    (16, 0xC453, 1, 48), (16, 0xC5D3, 1, 49), (16, 0xC5F3, 1, 50), (16, 0xDDA4, 1, 53),
    (16, 0xDD08, 1, 51), (16, 0xDD0C, 1, 52), (17, 0x1BB4B, 1, 61), (17, 0x1BB4A, 1, 60),
    (17, 0x18BA5, 1, 55), (17, 0x18BE5, 1, 56), (17, 0x1AA95, 1, 57), (17, 0x1AA97, 1, 58),
    (17, 0x188A4, 1, 54), (17, 0x1BA13, 1, 59), (18, 0x31748, 1, 62), (18, 0x317C8, 1, 63),
    (18, 0x35528, 1, 64), (18, 0x3552C, 1, 65), (18, 0x37424, 1, 66), (18, 0x37434, 1, 67),
    (18, 0x37436, 1, 68), (19, 0x62294, 1, 69), (19, 0x62E92, 1, 70), (19, 0x62F92, 1, 71),
    (19, 0x6AA52, 1, 72), (19, 0x6AA5A, 1, 73), (19, 0x6E86A, 1, 75), (19, 0x6E86E, 1, 76),
    (19, 0x6E84A, 1, 74), (20, 0xC452A, 1, 77), (20, 0xC5D27, 1, 78), (20, 0xC5F26, 1, 79),
    (20, 0xD54A6, 1, 80), (20, 0xD54B6, 1, 81), (20, 0xDD096, 1, 82), (20, 0xDD0D6, 1, 83),
    (20, 0xDD0DE, 1, 84), (21, 0x188A56, 1, 85), (21, 0x18BA4D, 1, 86), (21, 0x18BE4E, 1, 87),
    (21, 0x18BE4F, 1, 88), (21, 0x1AA96E, 1, 89), (21, 0x1BA12E, 1, 90), (21, 0x1BA12F, 1, 91),
    (21, 0x1BA1AF, 1, 92), (21, 0x1BA1BF, 1, 93), (22, 0x37435D, 1, 99), (22, 0x37437D, 1, 100),
    (22, 0x317498, 1, 94), (22, 0x35529C, 1, 95), (22, 0x35529D, 1, 96), (22, 0x3552DE, 1, 97),
    (22, 0x3552DF, 1, 98), (23, 0x62E933, 1, 102), (23, 0x62295D, 1, 101),
    (23, 0x6AA53D, 1, 103), (23, 0x6AA53F, 1, 105), (23, 0x6AA53E, 1, 104),
    (23, 0x6E86B9, 1, 106), (23, 0x6E86F8, 1, 107), (24, 0xD54A79, 1, 111),
    (24, 0xC5D265, 1, 109), (24, 0xC452B8, 1, 108), (24, 0xDD0D71, 1, 113),
    (24, 0xD54A78, 1, 110), (24, 0xDD0D70, 1, 112), (24, 0xDD0DF2, 1, 114),
    (24, 0xDD0DF3, 1, 115), (25, 0x188A5F6, 1, 225), (25, 0x188A5F5, 1, 189),
    (25, 0x188A5F4, 1, 188), (25, 0x188A5F3, 1, 203), (25, 0x188A5F2, 1, 202),
    (25, 0x188A5F1, 1, 197), (25, 0x188A5F0, 1, 207), (25, 0x188A5EF, 1, 169),
    (25, 0x188A5EE, 1, 223), (25, 0x188A5ED, 1, 159), (25, 0x188A5AA, 1, 235),
    (25, 0x188A5E3, 1, 152), (25, 0x188A5DF, 1, 192), (25, 0x188A589, 1, 179),
    (25, 0x188A5DD, 1, 201), (25, 0x188A578, 1, 172), (25, 0x188A5E0, 1, 149),
    (25, 0x188A588, 1, 178), (25, 0x188A5D6, 1, 120), (25, 0x188A5DB, 1, 219),
    (25, 0x188A5E1, 1, 150), (25, 0x188A587, 1, 127), (25, 0x188A59A, 1, 211),
    (25, 0x188A5C4, 1, 125), (25, 0x188A5EC, 1, 158), (25, 0x188A586, 1, 247),
    (25, 0x188A573, 1, 238), (25, 0x188A59C, 1, 163), (25, 0x188A5C8, 1, 228),
    (25, 0x188A5FB, 1, 183), (25, 0x188A5A1, 1, 217), (25, 0x188A5EB, 1, 168),
    (25, 0x188A5A8, 1, 122), (25, 0x188A584, 1, 128), (25, 0x188A5D2, 1, 249),
    (25, 0x188A599, 1, 187), (25, 0x188A598, 1, 186), (25, 0x188A583, 1, 136),
    (25, 0x18BA4C9, 1, 181), (25, 0x188A5D0, 1, 255), (25, 0x188A594, 1, 230),
    (25, 0x188A582, 1, 135), (25, 0x188A5CB, 1, 233), (25, 0x188A5D8, 1, 222),
    (25, 0x188A5E7, 1, 145), (25, 0x188A581, 1, 134), (25, 0x188A5EA, 1, 167),
    (25, 0x188A5A9, 1, 248), (25, 0x188A5A6, 1, 209), (25, 0x188A580, 1, 243),
    (25, 0x188A5A0, 1, 216), (25, 0x188A59D, 1, 164), (25, 0x188A5C3, 1, 140),
    (25, 0x188A57F, 1, 157), (25, 0x188A5C0, 1, 239), (25, 0x188A5DE, 1, 191),
    (25, 0x188A5D4, 1, 251), (25, 0x188A57E, 1, 156), (25, 0x188A5C2, 1, 139),
    (25, 0x188A592, 1, 242), (25, 0x188A5CD, 1, 133), (25, 0x188A57D, 1, 162),
    (25, 0x188A5A3, 1, 213), (25, 0x188A5E8, 1, 165), (25, 0x188A5A2, 1, 212),
    (25, 0x188A57C, 1, 227), (25, 0x188A58E, 1, 198), (25, 0x188A5B3, 1, 236),
    (25, 0x188A5B2, 1, 234), (25, 0x188A5B1, 1, 117), (25, 0x188A5B0, 1, 215),
    (25, 0x188A5AF, 1, 124), (25, 0x188A5AE, 1, 123), (25, 0x188A5AD, 1, 254),
    (25, 0x188A5AC, 1, 253), (25, 0x188A5AB, 1, 148), (25, 0x188A5DA, 1, 218),
    (25, 0x188A5E4, 1, 146), (25, 0x188A5E5, 1, 147), (25, 0x188A5D9, 1, 224),
    (25, 0x188A5B5, 1, 143), (25, 0x188A5BC, 1, 184), (25, 0x188A5BD, 1, 185),
    (25, 0x188A5E9, 1, 166), (25, 0x188A5CC, 1, 132), (25, 0x188A585, 1, 129),
    (25, 0x188A5D3, 1, 250), (25, 0x188A5E2, 1, 151), (25, 0x188A595, 1, 119),
    (25, 0x188A596, 1, 193), (25, 0x188A5B8, 1, 176), (25, 0x188A590, 1, 245),
    (25, 0x188A5C9, 1, 229), (25, 0x188A5A4, 1, 206), (25, 0x188A5E6, 1, 144),
    (25, 0x188A5A5, 1, 208), (25, 0x188A5CE, 1, 137), (25, 0x188A5BF, 1, 241),
    (25, 0x188A572, 1, 237), (25, 0x188A59B, 1, 190), (25, 0x188A5BE, 1, 240),
    (25, 0x188A5C7, 1, 131), (25, 0x188A5CA, 1, 232), (25, 0x188A5D5, 1, 252),
    (25, 0x188A57B, 1, 171), (25, 0x188A58D, 1, 205), (25, 0x188A58C, 1, 204),
    (25, 0x188A58B, 1, 118), (25, 0x188A58A, 1, 214), (25, 0x18BA4C8, 1, 180),
    (25, 0x188A5C5, 1, 126), (25, 0x188A5FA, 1, 182), (25, 0x188A5BB, 1, 175),
    (25, 0x188A5C1, 1, 141), (25, 0x188A5CF, 1, 138), (25, 0x188A5B9, 1, 177),
    (25, 0x188A5B6, 1, 153), (25, 0x188A597, 1, 194), (25, 0x188A5FE, 1, 160),
    (25, 0x188A5D7, 1, 121), (25, 0x188A5BA, 1, 174), (25, 0x188A591, 1, 246),
    (25, 0x188A5C6, 1, 130), (25, 0x188A5DC, 1, 200), (25, 0x188A57A, 1, 170),
    (25, 0x188A59F, 1, 221), (25, 0x188A5F9, 1, 196), (25, 0x188A5B4, 1, 142),
    (25, 0x188A5A7, 1, 210), (25, 0x188A58F, 1, 199), (25, 0x188A5FD, 1, 155),
    (25, 0x188A5B7, 1, 154), (25, 0x188A593, 1, 244), (25, 0x188A59E, 1, 220),
    (25, 0x188A5F8, 1, 195), (25, 0x188A5FF, 1, 161), (25, 0x188A5FC, 1, 231),
    (25, 0x188A579, 1, 173), (25, 0x188A5F7, 1, 226), (26, 0x3114BA2, 1, 116),
    (26, 0x3114BA3, 0, 1),
)
# fmt: on

_START_MARKER = 0x56432D35  # "VC-5"
_HEADER_TAGS = {20: "ImageWidth", 21: "ImageHeight", 12: "ChannelCount", 14: "SubbandCount"}
_HEADER_TAGS |= {84: "ImageFormat", 106: "PatternWidth", 107: "PatternHeight"}
_HEADER_TAGS |= {108: "ComponentsPerSample", 102: "MaxBitsPerComponent"}
_IMAGE_FORMAT_RAW = 4
_SUBBANDS = 10
#: wavelet (0: the largest) and band (0 lowpass, 1 LH, 2 HL, 3 HH) of each subband
_SUBBAND_WAVELET = (2, 2, 2, 2, 1, 1, 1, 0, 0, 0)
_SUBBAND_BAND = (0, 1, 2, 3, 1, 2, 3, 1, 2, 3)


@functools.cache
def _codebook() -> tuple[np.ndarray, np.ndarray]:
    """Return codebook 17 as the kernels' tables: the 12-bit look-up table and the rest.

    Cached and, unlike imageform's other cached arrays, writable (never written): numba types
    a read-only array apart, so read-only tables would compile the kernels a second time.
    """
    from imageform._kernels.vc5 import FAST_BITS

    fast = np.zeros((1 << FAST_BITS, 3), np.int64)
    slow = []
    for size, code, run, value in CODEBOOK_17:
        if size <= FAST_BITS:
            lo = code << (FAST_BITS - size)
            hi = (code + 1) << (FAST_BITS - size)
            empty = fast[lo:hi, 0] == 0  # the first codeword the search meets wins
            fast[lo:hi][empty] = (size, run, value)
        else:
            slow.append((size, code, run, value))
    return fast, np.array(slow, np.int64)


@functools.cache
def log_curve() -> np.ndarray:
    r"""Return GoPro's decoder log curve: 12-bit codes to 16-bit linear values (uint16, 4096).

    :math:`\lfloor\mathrm{float32}(65535\,(113^{i/4095} - 1)/112)\rfloor`, capped at 65535,
    computed as ``SetupDecoderLogCurve`` of GoPro's ``vc5_common/logcurve.c`` does (in double
    precision, stored as a float, truncated). Cached and writable, as :func:`_codebook`'s
    tables (a kernel's argument): never write to it.
    """
    i = np.arange(4096, dtype=np.float64)
    out = (65535.0 * (np.power(113.0, i / 4095.0) - 1.0) / 112.0).astype(np.float32)
    return np.minimum(out.astype(np.int64), 65535).astype(np.uint16)


def _dims(size: int) -> list[int]:
    """Return the widths (or heights) of the three wavelet levels of a channel of ``size``."""
    out = []
    for _ in range(3):
        size = (size + 1) // 2
        out.append(size)
    return out


class _Channel:
    """One channel's wavelet pyramid being decoded: bands, quantisations, which are done."""

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = width, height
        widths, heights = _dims(width), _dims(height)
        self.bands = [
            [np.zeros((heights[k], widths[k]), np.int16) for _ in range(4)] for k in range(3)
        ]
        self.quant = [[0, 0, 0, 0] for _ in range(3)]
        self.valid = [0, 0, 0]


_ERRORS = {
    -1: "the bitstream ends inside subband {s} of channel {c} (the tile is truncated)",
    -2: "subband {s} of channel {c} holds bits that are no codeword of VC-5 codebook 17",
    -3: "a run of zeros goes past the end of subband {s} of channel {c}",
    -4: "subband {s} of channel {c} does not end with the band-end codeword",
}


def _invert(ch: _Channel, level: int, prescale: int, out: np.ndarray) -> None:
    """Invert wavelet ``level`` of a channel into ``out`` (the level below's lowpass band)."""
    from imageform._kernels.vc5 import inverse_spatial

    ll, lh, hl, hh = ch.bands[level]
    h, w = ll.shape
    if h < 3 or w < 3:
        raise Vc5Error(f"a wavelet band of {w}x{h} coefficients is too small to invert (3x3)")
    q = ch.quant[level]
    inverse_spatial(ll, lh, hl, hh, q[1], q[2], q[3], prescale, out)


def decode(data: bytes, *, rggb: bool = True) -> np.ndarray:
    """Decode one VC-5 bitstream of a raw image to its Bayer mosaic (uint16, (H, W)).

    ``rggb``: the DNG's CFA is RGGB (14-bit RGGB output, as GoPro's SDK decodes it); else 12-bit
    values in GBRG order. Raises :class:`Vc5Error` for a bitstream it cannot decode.
    """
    from imageform._kernels.vc5 import band_runs, lowpass, pack_bayer

    n = len(data) // 4
    if n < 1:
        raise Vc5Error("the tile holds no VC-5 bitstream (under 4 bytes)")
    words = np.frombuffer(data, ">u4", count=n).astype(np.int64)
    buf = np.zeros(len(data) + 8, np.uint8)
    buf[: len(data)] = np.frombuffer(data, np.uint8)
    nbits = 8 * len(data)
    if int(words[0]) != _START_MARKER:
        raise Vc5Error("the tile does not start with the VC-5 start marker")
    fast, slow = _codebook()
    header: dict[int, int] = {}
    header_done = False
    channels: list[_Channel] = []
    count = 0
    channel = subband = 0
    precision, quant = 16, 0
    prescale = [0, 0, 0]
    at = 1  # the next segment, in 32-bit words
    while True:
        if at >= n:
            raise Vc5Error(
                f"the bitstream ends before the last subband (at subband {subband} of channel "
                f"{channel}): the tile is truncated or corrupt"
            )
        word = int(words[at])
        at += 1
        tag = word >> 16
        tag = tag - 65536 if tag >= 32768 else tag
        value = word & 0xFFFF
        svalue = value - 65536 if value >= 32768 else value
        optional = tag < 0
        tag = -tag if optional else tag
        is_header = False
        codeblock = False
        chunk = 0
        if tag in _HEADER_TAGS and tag != 14:
            is_header = True
            if not optional and (header_done or tag in header):  # optional: just updated
                raise Vc5Error(f"a misplaced or repeated header parameter {_HEADER_TAGS[tag]}")
            header[tag] = value  # unsigned, as the reference's DIMENSION and counts
        elif tag == 48:
            subband = value
        elif tag == 53:
            quant = value
        elif tag == 35:
            if not 8 <= svalue <= 32:
                raise Vc5Error(f"a lowpass precision of {svalue} bits (VC-5 allows 8 to 32)")
            precision = svalue
        elif tag == 62:
            channel = value
        elif tag == 101:
            pass  # BitsPerComponent: the output's depth does not depend on it
        elif tag == 109:
            prescale = [(value >> (14 - 2 * k)) & 3 for k in range(3)]
        elif tag in (104, 105):
            raise Vc5Error("ChannelWidth/ChannelHeight in a VC-5 Part 3 (image format) bitstream")
        else:
            if tag & 0x6000:
                chunk = value + (((tag & 0xFF) << 16) if tag & 0x2000 else 0)
            if tag & 0x6000 == 0x6000:
                codeblock = True
            elif tag in (0x4001, 0x4002, 0x4004) or (tag & 0x6000 == 0x4000 and optional):
                at += chunk  # component transform/permutation, image identifier, vendor data
            elif tag == 0x4003:
                raise Vc5Error("a 16-bit inverse component transform (not implemented by VC-5)")
            elif tag & 0x2000:
                pass  # a section header or other large chunk: its payload is read as segments
            elif not optional:
                raise Vc5Error(f"an unknown required VC-5 tag {tag}")
        if not is_header and not header_done:
            header_done = True
            channels, count = _allocate(header)
        if codeblock:
            if not 0 <= channel < count or not 0 <= subband < _SUBBANDS:
                raise Vc5Error(f"a codeblock of channel {channel}, subband {subband}")
            ch = channels[channel]
            level, band = _SUBBAND_WAVELET[subband], _SUBBAND_BAND[subband]
            target = ch.bands[level][band]
            pos = 32 * at
            if subband == 0:
                end = lowpass(buf, pos, nbits, precision, target)
            else:
                end = band_runs(buf, pos, nbits, fast, slow, target)
                ch.quant[level][band] = quant
            if end < 0:
                raise Vc5Error(_ERRORS[int(end)].format(s=subband, c=channel))
            at = (int(end) + 31) // 32
            ch.valid[level] |= 1 << band
            if ch.valid[level] == 15 and level > 0:
                _invert(ch, level, prescale[level], ch.bands[level - 1][0])
                ch.valid[level - 1] |= 1
            subband += 1
            if subband == _SUBBANDS:
                channel += 1
                subband = 0
        if header_done and not is_header and all(c.valid[0] == 15 for c in channels):
            break
    arrays = []
    for ch in channels:
        out = np.zeros((ch.height, ch.width), np.int16)
        _invert(ch, 0, prescale[0], out)
        arrays.append(out.view(np.uint16))
    h, w = channels[0].height, channels[0].width
    mosaic = np.empty((2 * h, 2 * w), np.uint16)
    pack_bayer(*arrays, log_curve(), 2 if rggb else 4, rggb, mosaic)
    return mosaic


def _allocate(header: dict[int, int]) -> tuple[list[_Channel], int]:
    """Return the channels the bitstream's header describes (a 2x2 raw image of 4 channels)."""
    missing = [name for tag, name in _HEADER_TAGS.items() if tag in (20, 21, 12, 84, 106, 107)]
    missing = [name for name in missing if _tag_of(name) not in header]
    if missing:
        raise Vc5Error(f"the VC-5 header lacks {', '.join(missing)}")
    if header[84] != _IMAGE_FORMAT_RAW or (header[106], header[107]) != (2, 2):
        raise Vc5Error(
            f"a VC-5 image of format {header[84]} with a {header[106]}x{header[107]} pattern "
            "(only raw images, format 4, of 2x2 Bayer patterns are decoded)"
        )
    if header[12] != 4:
        raise Vc5Error(f"a raw VC-5 image of {header[12]} channels (a Bayer image has 4)")
    width, height = header[20], header[21]
    if width <= 0 or height <= 0 or width % 2 or height % 2:
        raise Vc5Error(f"a VC-5 image of {width}x{height} (only even sizes are decoded)")
    return [_Channel(width // 2, height // 2) for _ in range(4)], 4


def _tag_of(name: str) -> int:
    return next(tag for tag, n in _HEADER_TAGS.items() if n == name)


def decoded_tiles(page: Any, fh: Any) -> np.ndarray:
    """Return the raw image of a DNG page whose tiles or strips are VC-5 (Compression 9).

    ``page`` is tifffile's page, ``fh`` its open file handle. Each tile is one bitstream;
    tiles are placed on the image's grid and cut to its size. :class:`Vc5Error` when a tile
    cannot be decoded (the message names the tile when there are several).
    """
    rggb = _is_rggb(page)
    height, width = int(page.imagelength), int(page.imagewidth)
    offsets, counts = page.dataoffsets, page.databytecounts
    if page.is_tiled:
        tile_h, tile_w = int(page.tilelength), int(page.tilewidth)
    else:
        tile_h, tile_w = int(page.rowsperstrip), width
    across = -(-width // tile_w)
    out = np.zeros((height, width), np.uint16)
    for k, (offset, size) in enumerate(zip(offsets, counts, strict=True)):
        fh.seek(int(offset))
        data = fh.read(int(size))
        if len(data) < int(size):
            raise Vc5Error(
                f"the file ends inside its VC-5 tile {k} ({len(data)} of {int(size)} bytes)"
            )
        try:
            tile = decode(data, rggb=rggb)
        except Vc5Error as exc:
            if len(offsets) == 1:
                raise
            raise Vc5Error(f"tile {k}: {exc}") from None
        top, left = (k // across) * tile_h, (k % across) * tile_w
        if top >= height or left >= width:
            continue
        part = tile[: min(tile_h, height - top), : min(tile_w, width - left)]
        out[top : top + part.shape[0], left : left + part.shape[1]] = part
    return out


def _is_rggb(page: Any) -> bool:
    """Return whether a DNG page's CFA is RGGB (GoPro's SDK decodes it at 14 bits then)."""
    dims = tuple(int(v) for v in np.ravel(page.tags.valueof(33421, (2, 2))))
    pattern = page.tags.valueof(33422, b"\x00\x01\x01\x02")
    codes = list(pattern) if isinstance(pattern, bytes | bytearray) else [int(v) for v in pattern]
    return dims == (2, 2) and codes[:4] == [0, 1, 1, 2]
