"""What real files from image-format test suites (image-rs/image-tiff, google/wuffs) broke,
each reproduced by a file written here (``benchmarks/results/odd-files-2026-11-30h.md``).

- A 10-bit RGB TIFF (libtiff's ``flower-rgb-contig-10.tif``) read as colours: its samples,
  0-1023 in uint16, were taken as fractions of 65535, and ``convert --to lab`` gave L* 0.4
  for a photograph whose 8-bit twin has L* 39. Colour commands now read 2**bits - 1 as white
  (``imageform chunked`` too); ``read_image`` keeps the stored numbers.
- A PNG whose eXIf chunk is not EXIF (wuffs' ``artificial-png/exif.png``): ``info`` and
  ``convert`` refused the whole file ("not a TIFF file"), and libpng's "eXIf: invalid" came
  as a second line on stderr. The pixels are read, the block is ignored, libpng's line is a
  warning.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import read_image

RNG = np.random.default_rng(3)


def _tiff_bits(path: Path, codes: np.ndarray, bits: int, tiled: bool = False) -> Path:
    import tifffile

    kw = {"tile": (16, 16)} if tiled else {}
    tifffile.imwrite(path, codes, bitspersample=bits, photometric="rgb", **kw)
    return path


@pytest.mark.parametrize("bits", [10, 12, 14])
def test_fewer_bits_than_their_container_are_read_as_colours_to_full_scale(
    tmp_path: Path, bits: int
) -> None:
    import colour
    import tifffile

    top = (1 << bits) - 1
    codes = np.round(RNG.random((16, 16, 3)) * top).astype(np.uint16)
    src = _tiff_bits(tmp_path / "in.tif", codes, bits)
    assert read_image(src).max() <= top  # the reader keeps the stored numbers (DN)
    out = tmp_path / "lab.tif"
    assert main(["convert", str(src), "--to", "lab", "-o", str(out)]) == 0
    lab = tifffile.imread(out)
    xyz = colour.RGB_to_XYZ(codes / top, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=True)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    np.testing.assert_allclose(lab, colour.XYZ_to_Lab(xyz, d65), atol=0.05)


def test_chunked_reads_fewer_bits_as_convert_does(tmp_path: Path) -> None:
    import tifffile

    codes = np.round(RNG.random((32, 32, 3)) * 1023).astype(np.uint16)
    src = _tiff_bits(tmp_path / "in.tif", codes, 10, tiled=True)
    one, chunked = tmp_path / "one.tif", tmp_path / "chunked.tif"
    assert main(["convert", str(src), "--to", "lab", "-o", str(one)]) == 0
    assert main(["chunked", "convert", str(src), "--to", "lab", "-o", str(chunked)]) == 0
    np.testing.assert_allclose(tifffile.imread(chunked), tifffile.imread(one), atol=1e-3)


def test_white_balance_of_a_12_bit_tiff_keeps_its_grey_grey(tmp_path: Path) -> None:
    codes = np.full((8, 8, 3), 2048, np.uint16)  # mid grey of 12 bits
    codes[..., 0] = 1800
    src = _tiff_bits(tmp_path / "in.tif", codes, 12)
    out = tmp_path / "wb.png"
    assert main(["white-balance", str(src), "-o", str(out)]) == 0
    got = read_image(out)
    assert got.dtype == np.uint16
    assert np.ptp(got[0, 0]) <= 1 and got.mean() > 0.3 * 65535  # not 16 times too dark


def _png_with_chunk(kind: bytes, data: bytes) -> bytes:
    def chunk(k: bytes, d: bytes) -> bytes:
        return struct.pack(">I", len(d)) + k + d + struct.pack(">I", zlib.crc32(k + d))

    ihdr = struct.pack(">IIBBBBB", 2, 2, 8, 0, 0, 0, 0)  # 2 x 2 grey, 8-bit
    idat = zlib.compress(b"\0\x10\x20\0\x30\x40")
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(kind, data)
        + chunk(b"IDAT", idat)
        + chunk(b"IEND", b"")
    )


def test_a_png_whose_exif_chunk_is_junk_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "junk exif.png"
    src.write_bytes(_png_with_chunk(b"eXIf", b"LoremIpsum dolor sit amet"))
    np.testing.assert_array_equal(read_image(src)[..., 0], [[16, 32], [48, 64]])
    assert main(["info", str(src)]) == 0
    capsys.readouterr()
    out = tmp_path / "lab.tif"
    assert main(["convert", str(src), "--to", "lab", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert all(line.startswith("imageform: warning:") for line in err.splitlines()), err


def test_chunked_reads_a_big_endian_16_bit_tiff_in_its_byte_order(tmp_path: Path) -> None:
    """libtiff's ``rgb-3c-16b.tiff`` ("MM", uncompressed strips): ``chunked`` read its 16-bit
    samples byte-swapped, a Lab ΔE of 160 from ``convert``'s, with exit 0."""
    import tifffile

    codes = (RNG.random((24, 20, 3)) * 65535).astype(np.uint16)
    src = tmp_path / "big.tif"
    tifffile.imwrite(src, codes, byteorder=">", photometric="rgb")
    one, chunked = tmp_path / "one.tif", tmp_path / "chunked.tif"
    assert main(["convert", str(src), "--to", "lab", "-o", str(one)]) == 0
    assert main(["chunked", "convert", str(src), "--to", "lab", "-o", str(chunked)]) == 0
    np.testing.assert_allclose(tifffile.imread(chunked), tifffile.imread(one), atol=1e-3)


@pytest.mark.parametrize(
    ("photometric", "kw", "what"),
    [
        ("ycbcr", {"subsampling": (2, 2), "compression": "zlib"}, "YCbCr"),
        ("separated", {}, "CMYK"),
    ],
)
def test_chunked_refuses_a_tiff_it_cannot_read_as_rgb_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], photometric: str, kw: dict, what: str
) -> None:
    """libtiff's ``ycbcr-cat.tif``, ``off_luv24.tif``, ``smallliz.tif``: an "unexpected"
    NotImplementedError, ValueError or Jpeg8Error from inside the block computation."""
    import tifffile

    a = (RNG.random((32, 32, 4 if photometric == "separated" else 3)) * 255).astype(np.uint8)
    src = tmp_path / "odd.tif"
    tifffile.imwrite(src, a, photometric=photometric, **kw)
    out = tmp_path / "out.tif"
    assert main(["chunked", "convert", str(src), "--to", "lab", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and what in err[0] and "unexpected" not in err[0], err
    assert not out.exists()


def test_batch_leaves_nothing_in_the_temporary_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every ``imageform batch`` run left dask's ``dask-scratch-space`` (its lock files) in
    the temporary folder: the local cluster now works in a folder of its own, removed."""
    import tempfile

    from imageform.io import write_image

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    monkeypatch.setattr(tempfile, "tempdir", None)  # read TMPDIR again
    src = tmp_path / "a.png"
    write_image(src, np.full((8, 8, 3), 0.5))
    out = tmp_path / "out"
    argv = ["batch", "convert", str(src), "-o", str(out), "--to", "lab", "--suffix", ".tif"]
    argv += ["--workers", "1"]
    assert main(argv) == 0
    assert list(out.glob("*.tif"))
    assert not list(scratch.iterdir()), list(scratch.iterdir())
