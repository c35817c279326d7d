"""imageform.io._tiff_ifd: a raw file's header read without tifffile, to tifffile's values."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from imageform.io import raw as R
from imageform.io import write_dng
from imageform.io._tiff_ifd import Unusual, read_header

CM = np.array([[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]])


def _tifffile_header(path: Path, opcodes: bool = True) -> object:
    """:func:`imageform.io.raw._dng_header` as it was: every IFD parsed by tifffile."""
    import tifffile

    with tifffile.TiffFile(path) as tf:
        return R._header_of(tf, opcodes=opcodes)


def _same(a: object, b: object) -> None:
    """The two headers' values are equal, arrays and opcodes' fields included."""
    assert repr(type(a)) == repr(type(b))
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys()
        for k in a:
            _same(a[k], b[k])
    elif isinstance(a, list | tuple):
        assert isinstance(b, list | tuple) and len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    elif hasattr(a, "__dataclass_fields__"):
        for k in a.__dataclass_fields__:
            _same(getattr(a, k), getattr(b, k))
    else:
        assert a == b


def _opcode_list(*ops: tuple[int, bytes]) -> bytes:
    out = struct.pack(">I", len(ops))
    for op, params in ops:
        out += struct.pack(">IIII", op, 0x01030000, 0, len(params)) + params
    return out


def _gain_map(plane: int = 0) -> bytes:
    """A GainMap opcode's parameters (DNG 1.3, opcode 9): a 2 x 2 map of one plane."""
    area = struct.pack(">8I", 0, 0, 64, 96, plane, 1, 2, 2)
    grid = struct.pack(">II", 2, 2) + struct.pack(">4d", 1.0, 1.0, 0.0, 0.0) + struct.pack(">I", 1)
    return area + grid + struct.pack(">4f", 1.0, 1.1, 1.2, 1.3)


def _subifd_dng(path: Path, *, bigtiff: bool = False, byteorder: str = "<") -> Path:
    """A DNG laid out as converters write it: IFD 0 a preview with the colour tags, the raw
    image in a SubIFD with ActiveArea, a LinearizationTable of 2000 entries and OpcodeLists."""
    import tifffile

    rational = [v for x in CM.ravel() for v in (round(x * 10000), 10000)]
    ifd0 = [
        (50706, 1, 4, (1, 4, 0, 0), True),
        (50708, 2, 0, "Some Camera  ", True),
        (50721, 10, 9, tuple(rational), True),
        (50722, 10, 9, tuple(rational), True),
        (50778, 3, 1, 17, True),
        (50779, 3, 1, 21, True),
        (50727, 5, 3, (11, 10, 1, 1, 9, 10), True),
        (50730, 10, 1, (-1, 2), True),
        (50729, 5, 2, (3127, 10000, 3290, 10000), True),
    ]
    raw_tags = [
        (33421, 3, 2, (2, 2), True),
        (33422, 1, 4, (0, 1, 1, 2), True),
        (50829, 4, 4, (3, 5, 61, 93), True),
        (50712, 3, 2000, tuple(range(2000)), True),
        (51008, 7, 0, _opcode_list((4, struct.pack(">II", 0, 0))), True),
        (51009, 7, 0, _opcode_list((9, _gain_map())), True),
        (51022, 7, 0, _opcode_list((3, struct.pack(">7d", 0.1, 0, 0, 0, 0, 0.5, 0.5))), True),
    ]
    data = np.arange(64 * 96, dtype=np.uint16).reshape(64, 96) % 1999
    with tifffile.TiffWriter(path, bigtiff=bigtiff, byteorder=byteorder) as tw:
        tw.write(np.zeros((16, 24, 3), np.uint8), photometric="rgb", subifds=1, subfiletype=1,
                 extratags=ifd0)  # fmt: skip
        tw.write(data, photometric=32803, subfiletype=0, extratags=raw_tags)
    return path


@pytest.mark.parametrize("byteorder", ["<", ">"])
def test_a_subifd_dng_reads_as_tifffile_reads_it(tmp_path: Path, byteorder: str) -> None:
    """Colour tags (rationals, the model's ASCII with its spaces, illuminants), the raw
    SubIFD's opcodes, ActiveArea's offset, size and origin, the data's end: tifffile's
    values, both byte orders; the header is read without tifffile."""
    path = _subifd_dng(tmp_path / "sub.dng", byteorder=byteorder)
    first = read_header(path)  # no Unusual: the own reader takes it
    assert first.pages is not None and len(first.pages) == 1
    for opcodes in (True, False):
        ours = R._dng_header(path, opcodes=opcodes)
        _same(ours, _tifffile_header(path, opcodes))
    colour, found, end = R._dng_header(path)
    assert colour["model"] == "Some Camera" and end > 0
    assert found[4:7] == ((1, 1), (58, 88), None)  # offset, size, no origin (linearized)


def test_write_dng_files_read_as_tifffile_reads_them(tmp_path: Path) -> None:
    """write_dng's DNGs (one IFD, FixVignetteRadial in OpcodeList3, BaselineExposure)."""
    m = np.random.default_rng(0).integers(64, 4095, (40, 60)).astype(np.uint16)
    plain = write_dng(tmp_path / "a.dng", m, black_level=64, white_level=4095, color_matrix=CM)
    vig = write_dng(tmp_path / "b.dng", m, black_level=64, white_level=4095, color_matrix=CM,
                    baseline_exposure_ev=1.5,
                    fix_vignette_radial=(0.1, 0.02, 0, 0, 0, 0.5, 0.5))  # fmt: skip
    for path in (plain, vig):
        read_header(path)
        _same(R._dng_header(path), _tifffile_header(path))


def test_bigtiff_and_odd_files_are_left_to_tifffile(tmp_path: Path) -> None:
    """A BigTIFF, a tag it uses outside the file, an IFD of no tag: Unusual, and the header
    then is tifffile's; a file that is no TIFF has no header."""
    big = _subifd_dng(tmp_path / "big.dng", bigtiff=True)
    with pytest.raises(Unusual):
        read_header(big)
    _same(R._dng_header(big), _tifffile_header(big))
    # ColorMatrix1's value offset pointed past the end of the file
    path = _subifd_dng(tmp_path / "odd.dng")
    data = bytearray(path.read_bytes())
    n = struct.unpack("<H", data[struct.unpack("<I", data[4:8])[0] :][:2])[0]
    at = struct.unpack("<I", data[4:8])[0] + 2
    for i in range(n):
        code = struct.unpack("<H", data[at + 12 * i : at + 12 * i + 2])[0]
        if code == 50721:
            data[at + 12 * i + 8 : at + 12 * i + 12] = struct.pack("<I", len(data) + 100)
    path.write_bytes(bytes(data))
    with pytest.raises(Unusual):
        read_header(path)
    _same(R._dng_header(path), _tifffile_header(path))  # tifffile skips the tag
    empty = tmp_path / "empty.dng"
    empty.write_bytes(b"II*\x00\x08\x00\x00\x00\x00\x00\x00\x00\x00\x00")
    with pytest.raises(Unusual):
        read_header(empty)
    assert R._dng_header(tmp_path / "missing.dng") == ({}, R._NO_OPCODES, 0)
    (tmp_path / "x.dng").write_bytes(b"not a tiff at all")
    assert R._dng_header(tmp_path / "x.dng") == ({}, R._NO_OPCODES, 0)
