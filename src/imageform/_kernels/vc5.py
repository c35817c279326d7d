r"""Numba kernels of the VC-5 decoder (SMPTE ST 2073, GoPro's GPR raw files).

The arithmetic of GoPro's reference decoder (github.com/gopro/gpr, ``source/lib/vc5_decoder``,
Apache-2.0 or MIT), reimplemented; :mod:`imageform.io._vc5` parses the bitstream around them.

- :func:`band_runs`: one highpass band, entropy coded with codebook 17: codewords of 1 to 26
  bits, most significant bit first, each a run of zeros or one companded magnitude followed by
  a sign bit (1: negative); runs cross row ends; a special codeword (run 0, value 1) ends the
  band. Codewords up to 12 bits are looked up in a table of 4,096 entries, longer ones by a
  search of the codebook in its order (what the reference's search finds for a prefix code).
- :func:`lowpass`: the lowpass band of the smallest wavelet, ``precision`` bits a coefficient,
  kept as a signed 16-bit value.
- :func:`inverse_spatial`: one level of the inverse 2-D wavelet (the 2-6 biorthogonal filter:
  even output :math:`(x_{-1} - x_{+1} + 4) \gg 3 + x_0 + h`, odd :math:`(x_{+1} - x_{-1} + 4) \gg
  3 + x_0 - h`, halved; one-sided 11/-4/1 and 5/4/-1 filters at the first and last row and
  column), vertical first, the highpass coefficients dequantised on the way
  (:math:`q\,(m + \lfloor 768\,m^3 / 255^3 \rfloor)`, the cubic companding undone, clamped to
  int16). A level with a prescale of 2 doubles instead of halving its horizontal output and
  clamps it to int16, the others clamp to [0, 16383] (``InvertSpatialQuant16s`` and
  ``InvertSpatialQuantDescale16s`` of ``inverse.c``).
- :func:`pack_bayer`: the four component arrays (G sum, R - G, B - G, G difference, 2048 the
  midpoint of the three differences) to the Bayer mosaic, each photosite clamped to 12 bits,
  through the decoder's log curve table (12 to 16 bits) and shifted down to the output depth.

Negative results of :func:`band_runs` and :func:`lowpass` are errors (:data:`ERR_TRUNCATED`,
...), named by :mod:`imageform.io._vc5`.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = [
    "ERR_BAND_END",
    "ERR_NO_CODEWORD",
    "ERR_RUN_OVERFLOW",
    "ERR_TRUNCATED",
    "FAST_BITS",
    "band_runs",
    "inverse_spatial",
    "lowpass",
    "pack_bayer",
]

#: The bitstream ends inside the band.
ERR_TRUNCATED = -1
#: Bits that are no codeword of the codebook.
ERR_NO_CODEWORD = -2
#: A run of zeros past the end of the band.
ERR_RUN_OVERFLOW = -3
#: The codeword after the band's last coefficient is no band-end marker.
ERR_BAND_END = -4

#: Codewords of up to this many bits are found by one table look-up.
FAST_BITS = 12


@njit(inline="always")
def _peek32(buf: np.ndarray, pos: int) -> int:
    """Return the 32 bits from bit ``pos`` of ``buf`` (big-endian, zero past its end + 5)."""
    b = pos >> 3
    x = (
        (np.int64(buf[b]) << 32)
        | (np.int64(buf[b + 1]) << 24)
        | (np.int64(buf[b + 2]) << 16)
        | (np.int64(buf[b + 3]) << 8)
        | np.int64(buf[b + 4])
    )
    return int((x >> (8 - (pos & 7))) & 0xFFFFFFFF)


@njit(inline="always")
def _codeword(
    buf: np.ndarray, pos: int, fast: np.ndarray, slow: np.ndarray
) -> tuple[int, int, int, int]:
    """Return (size, run, magnitude, sign) of the codeword at bit ``pos``; size 0: none.

    ``sign`` is the bit after the codeword (the sign of a magnitude; codewords have at most
    26 bits, so it is among the 32 read).
    """
    bits = _peek32(buf, pos)
    i = bits >> (32 - FAST_BITS)
    size = fast[i, 0]
    if size > 0:
        return size, fast[i, 1], fast[i, 2], (bits >> (31 - size)) & 1
    for k in range(slow.shape[0]):
        size = slow[k, 0]
        if (bits >> (32 - size)) == slow[k, 1]:
            return size, slow[k, 2], slow[k, 3], (bits >> (31 - size)) & 1
    return 0, 0, 0, 0


@njit(nogil=True, error_model="numpy")
def band_runs(
    buf: np.ndarray, pos: int, nbits: int, fast: np.ndarray, slow: np.ndarray, out: np.ndarray
) -> int:
    """Decode one run-length coded band into ``out`` (int16, (H, W)) from bit ``pos``.

    ``buf`` holds the bitstream (``nbits`` bits) and at least 5 zero bytes after it; ``fast``
    (4096 x 3: size, run, magnitude) and ``slow`` (n x 4: size, bits, run, magnitude) the
    codebook. Returns the bit after the band-end codeword, or a negative error code.
    """
    flat = out.ravel()
    total = flat.size
    index = 0
    while index < total:
        size, run, value, sign = _codeword(buf, pos, fast, slow)
        if size == 0:
            return ERR_NO_CODEWORD if pos + 26 <= nbits else ERR_TRUNCATED
        pos += size
        if value != 0:
            if sign == 1:
                value = -value
            pos += 1
        if pos > nbits:
            return ERR_TRUNCATED
        if run > total - index:
            return ERR_RUN_OVERFLOW
        for _ in range(run):
            flat[index] = value
            index += 1
    size, run, value, _ = _codeword(buf, pos, fast, slow)
    if size == 0:
        return ERR_NO_CODEWORD if pos + 26 <= nbits else ERR_TRUNCATED
    pos += size
    if pos > nbits:
        return ERR_TRUNCATED
    if run != 0 and value != 1:
        return ERR_BAND_END
    return pos


@njit(nogil=True, error_model="numpy")
def lowpass(buf: np.ndarray, pos: int, nbits: int, precision: int, out: np.ndarray) -> int:
    """Read ``out``'s coefficients (int16, (H, W)), ``precision`` bits each, from bit ``pos``.

    Returns the bit after the last, or :data:`ERR_TRUNCATED`.
    """
    flat = out.ravel()
    n = flat.size
    if pos + n * precision > nbits:
        return ERR_TRUNCATED
    for k in range(n):
        v = _peek32(buf, pos) >> (32 - precision)
        flat[k] = np.int16(np.uint16(v & 0xFFFF))
        pos += precision
    return pos


@njit(inline="always")
def _clamp16(v: int) -> int:
    return -32768 if v < -32768 else (32767 if v > 32767 else v)


@njit(inline="always")
def _dequantize(src: np.ndarray, q: int, dst: np.ndarray) -> None:
    """Undo the cubic companding of one row and multiply by the quantisation (int16)."""
    for c in range(src.shape[0]):
        v = np.int64(src[c])
        m = -v if v < 0 else v
        cubic = float(m)
        cubic *= m
        cubic *= m
        cubic *= 768.0
        cubic /= 16581375.0
        m = m + np.int64(cubic)
        if m != 0:
            m = q * m
        dst[c] = _clamp16(-m if v < 0 else m)


@njit(inline="always")
def _horizontal(
    low: np.ndarray, high: np.ndarray, out: np.ndarray, width: int, out_width: int, descale: int
) -> None:
    """Invert the horizontal wavelet of one row (``InvertHorizontal16s``/``Descale16s``)."""
    last = width - 1
    for c in range(width):
        if c == 0:
            even = (11 * low[0] - 4 * low[1] + low[2] + 4) >> 3
            odd = (5 * low[0] + 4 * low[1] - low[2] + 4) >> 3
        elif c == last:
            even = (5 * low[c] + 4 * low[c - 1] - low[c - 2] + 4) >> 3
            odd = (11 * low[c] - 4 * low[c - 1] + low[c - 2] + 4) >> 3
        else:
            even = ((low[c - 1] - low[c + 1] + 4) >> 3) + low[c]
            odd = ((low[c + 1] - low[c - 1] + 4) >> 3) + low[c]
        even += high[c]
        odd -= high[c]
        if descale < 0:  # no prescale: halved, clamped to 14 bits
            even >>= 1
            odd >>= 1
            even = 0 if even < 0 else (16383 if even > 16383 else even)
            odd = 0 if odd < 0 else (16383 if odd > 16383 else odd)
        else:
            even = _clamp16(even << descale)
            odd = _clamp16(odd << descale)
        out[2 * c] = even
        if 2 * c + 1 < out_width:
            out[2 * c + 1] = odd


@njit(nogil=True, error_model="numpy")
def inverse_spatial(
    ll: np.ndarray,
    lh: np.ndarray,
    hl: np.ndarray,
    hh: np.ndarray,
    q_lh: int,
    q_hl: int,
    q_hh: int,
    prescale: int,
    out: np.ndarray,
) -> None:
    """Invert one wavelet level: four (h, w) int16 bands to ``out`` (int16, up to (2h, 2w)).

    ``ll`` is used as decoded (the lowpass band is not quantised); ``lh``, ``hl`` and ``hh``
    are dequantised with ``q_lh``, ``q_hl``, ``q_hh``. ``prescale`` is the level's prescale
    shift from the bitstream (2: the descaling path). ``h`` and ``w`` are at least 3.
    """
    h, w = ll.shape
    out_h, out_w = out.shape
    descale = -1 if prescale <= 1 else (1 if prescale == 2 else 0)
    lines = np.empty((3, w), np.int32)  # lh rows r-1, r, r+1 dequantised
    hl_line = np.empty(w, np.int32)
    hh_line = np.empty(w, np.int32)
    even_low = np.empty(w, np.int32)
    odd_low = np.empty(w, np.int32)
    even_high = np.empty(w, np.int32)
    odd_high = np.empty(w, np.int32)
    for r in range(h):
        _dequantize(hl[r], q_hl, hl_line)
        _dequantize(hh[r], q_hh, hh_line)
        if r == 0:
            for k in range(3):
                _dequantize(lh[k], q_lh, lines[k])
        elif r < h - 1:  # rows r - 1, r, r + 1 of lh held
            _dequantize(lh[r + 1], q_lh, lines[(r + 1) % 3])
        if r == 0:
            a, b, c = 0, 1, 2
            for x in range(w):
                e = (11 * np.int32(ll[0, x]) - 4 * np.int32(ll[1, x]) + ll[2, x] + 4) >> 3
                o = (5 * np.int32(ll[0, x]) + 4 * np.int32(ll[1, x]) - ll[2, x] + 4) >> 3
                even_low[x] = _clamp16((e + hl_line[x]) >> 1)
                odd_low[x] = _clamp16((o - hl_line[x]) >> 1)
                e = (11 * lines[a, x] - 4 * lines[b, x] + lines[c, x] + 4) >> 3
                o = (5 * lines[a, x] + 4 * lines[b, x] - lines[c, x] + 4) >> 3
                even_high[x] = _clamp16((e + hh_line[x]) >> 1)
                odd_high[x] = _clamp16((o - hh_line[x]) >> 1)
        elif r == h - 1:
            a, b, c = (r - 2) % 3, (r - 1) % 3, r % 3
            for x in range(w):
                e = (5 * np.int32(ll[r, x]) + 4 * np.int32(ll[r - 1, x]) - ll[r - 2, x] + 4) >> 3
                o = (11 * np.int32(ll[r, x]) - 4 * np.int32(ll[r - 1, x]) + ll[r - 2, x] + 4) >> 3
                even_low[x] = _clamp16((e + hl_line[x]) >> 1)
                odd_low[x] = _clamp16((o - hl_line[x]) >> 1)
                e = (5 * lines[c, x] + 4 * lines[b, x] - lines[a, x] + 4) >> 3
                o = (11 * lines[c, x] - 4 * lines[b, x] + lines[a, x] + 4) >> 3
                even_high[x] = _clamp16((e + hh_line[x]) >> 1)
                odd_high[x] = _clamp16((o - hh_line[x]) >> 1)
        else:
            a, b, c = (r - 1) % 3, r % 3, (r + 1) % 3
            for x in range(w):
                up = np.int32(ll[r - 1, x])
                mid = np.int32(ll[r, x])
                down = np.int32(ll[r + 1, x])
                e = ((up - down + 4) >> 3) + mid
                o = ((down - up + 4) >> 3) + mid
                even_low[x] = _clamp16((e + hl_line[x]) >> 1)
                odd_low[x] = _clamp16((o - hl_line[x]) >> 1)
                e = ((lines[a, x] - lines[c, x] + 4) >> 3) + lines[b, x]
                o = ((lines[c, x] - lines[a, x] + 4) >> 3) + lines[b, x]
                even_high[x] = _clamp16((e + hh_line[x]) >> 1)
                odd_high[x] = _clamp16((o - hh_line[x]) >> 1)
        _horizontal(even_low, even_high, out[2 * r], w, out_w, descale)
        if 2 * r + 1 < out_h:
            _horizontal(odd_low, odd_high, out[2 * r + 1], w, out_w, descale)


@njit(nogil=True, error_model="numpy")
def pack_bayer(
    gs: np.ndarray,
    rg: np.ndarray,
    bg: np.ndarray,
    gd: np.ndarray,
    curve: np.ndarray,
    shift: int,
    rggb: bool,
    out: np.ndarray,
) -> None:
    """Pack the four (h, w) uint16 component arrays into ``out`` (uint16, (2h, 2w)), RGGB/GBRG."""
    h, w = gs.shape
    for r in range(h):
        for c in range(w):
            g = np.int32(gs[r, c])
            red = ((np.int32(rg[r, c]) - 2048) << 1) + g
            blue = ((np.int32(bg[r, c]) - 2048) << 1) + g
            d = np.int32(gd[r, c]) - 2048
            g1 = g + d
            g2 = g - d
            red = curve[0 if red < 0 else (4095 if red > 4095 else red)] >> shift
            blue = curve[0 if blue < 0 else (4095 if blue > 4095 else blue)] >> shift
            g1 = curve[0 if g1 < 0 else (4095 if g1 > 4095 else g1)] >> shift
            g2 = curve[0 if g2 < 0 else (4095 if g2 > 4095 else g2)] >> shift
            if rggb:
                out[2 * r, 2 * c] = red
                out[2 * r, 2 * c + 1] = g1
                out[2 * r + 1, 2 * c] = g2
                out[2 * r + 1, 2 * c + 1] = blue
            else:
                out[2 * r, 2 * c] = g1
                out[2 * r, 2 * c + 1] = blue
                out[2 * r + 1, 2 * c] = red
                out[2 * r + 1, 2 * c + 1] = g2
