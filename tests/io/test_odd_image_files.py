"""TIFF sample types past uint16 and int32, and pixel sizes past 100 µm.

- **uint32** (a photon counter's, a stitched mosaic's or a label image's samples) was shown
  by ``imageform info`` as ``uint32`` and refused by ``read_image`` ("unsupported sample type
  uint32"). It is read as a signed integer is: float64 holding each stored number exactly.
- **complex** samples (SampleFormat 5 and 6: rioxarray's ``cint16.tif``, a radar's SLC, a
  Fourier transform) passed ``info`` as ``complex64`` and were refused by ``read_image`` as an
  "unsupported sample type"; both now refuse them in one line saying what to save instead.
  64-bit integers (no float64 holds them all) likewise.
- **float16** was shown by ``info`` as ``float16``; ``read_image`` widens it to float32.
- **Pixel sizes** from resolution tags in centimetres were read under 100 µm only; an X-ray
  detector's 139-200 µm pixels or a macro camera's are read now, below 1000 µm (libvips
  writes 10 px/cm, 1000 µm, to a file of unknown resolution), but a screen's 72 or 96 dpi
  converted to centimetres is still no pixel size. ImageJ's ``unit=mm`` and OME's
  ``PhysicalSizeXUnit="mm"`` (an X-ray's calibration) were not read at all.

The reference for the values is the array tifffile wrote and reads back.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_info, pixel_size_um, read_image

tifffile = pytest.importorskip("tifffile")
RNG = np.random.default_rng(20261201)


@pytest.mark.parametrize("channels", [1, 3])
def test_uint32_is_read_as_the_stored_numbers(tmp_path: Path, channels: int) -> None:
    a = RNG.integers(0, 2**32 - 1, (6, 9, channels), endpoint=True, dtype=np.uint64)
    a = a.astype(np.uint32)
    a[0, :2, 0] = (0, 2**32 - 1)  # float32 would round 4294967295 to 4294967296
    p = tmp_path / "u32.tif"
    tifffile.imwrite(p, a if channels == 3 else a[..., 0], photometric=
                     "rgb" if channels == 3 else "minisblack")  # fmt: skip
    got = read_image(p)
    assert got.dtype == np.float64 and got.shape == a.shape
    np.testing.assert_array_equal(got, a.astype(np.float64))
    np.testing.assert_array_equal(got, tifffile.imread(p).reshape(a.shape).astype(np.float64))
    assert image_info(p) == (9, 6, channels, "float64", "tiff")


def test_uint32_info_and_colour_commands(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    counts = (np.arange(32 * 32, dtype=np.uint32) * 3_000_000).reshape(32, 32)
    p = tmp_path / "counts.tif"
    tifffile.imwrite(p, counts)
    assert main(["info", str(p), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["dtype"], summary["stored_dtype"]) == ("float64", "uint32")
    assert main(["info", str(p)]) == 0
    assert "float64 (stored uint32: read as the numbers)" in capsys.readouterr().out
    out = tmp_path / "o.png"
    assert main(["convert", str(p), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "holds uint32 samples (numbers, 0 to 3.069e+09" in err, err
    assert err.count("\n") == 1 and not out.exists()
    stack = tmp_path / "stack.tif"  # a stack's listing says the same
    tifffile.imwrite(
        stack, np.stack([counts] * 4), photometric="minisblack", metadata={"axes": "ZYX"}
    )
    assert main(["info", str(stack)]) == 0
    listed = capsys.readouterr().out
    assert "4 images (4 z-planes)" in listed
    assert "float64 (stored uint32: read as the numbers)" in listed


def _patch_sample_format(p: Path, value: int) -> None:
    """Set the first page's SampleFormat (one SHORT, stored in its IFD entry) to ``value``."""
    with tifffile.TiffFile(p) as tif:
        tag = tif.pages[0].tags["SampleFormat"]
        offset, order = tag.valueoffset, tif.byteorder
    data = bytearray(p.read_bytes())
    data[offset : offset + 2] = value.to_bytes(2, "little" if order == "<" else "big")
    p.write_bytes(bytes(data))


@pytest.mark.parametrize(
    ("dtype", "stored", "fmt"),
    [(np.complex64, "float32", 6), (np.complex128, "float64", 6), (np.int32, "int16", 5)],
)
def test_complex_samples_are_refused_in_one_line(
    tmp_path: Path, dtype: type, stored: str, fmt: int, capsys: pytest.CaptureFixture[str]
) -> None:
    """A complex int16 is written as int32 and its SampleFormat set to 5 (tifffile writes no
    complex integers; it reads them as complex64, as rioxarray's cint16.tif)."""
    p = tmp_path / "c.tif"
    a = (RNG.normal(size=(8, 8)) + 1j * RNG.normal(size=(8, 8))).astype(np.complex64)
    tifffile.imwrite(p, a.astype(dtype) if fmt == 6 else np.zeros((8, 8), np.int32))
    if fmt == 5:
        _patch_sample_format(p, 5)
        assert tifffile.imread(p).dtype == np.complex64
    what = f"a TIFF of complex {stored} samples (SampleFormat {fmt}"
    for reader in (read_image, image_info):
        with pytest.raises(InvalidInputError, match=r"complex number is not an image") as e:
            reader(p)
        assert what in str(e.value) and "numpy.abs" in str(e.value) and "\n" not in str(e.value)
    assert main(["info", str(p)]) == 1
    err = capsys.readouterr().err
    assert what in err and err.count("\n") == 1


@pytest.mark.parametrize("dtype", [np.int64, np.uint64])
def test_64_bit_integers_are_refused_by_info_as_by_read(tmp_path: Path, dtype: type) -> None:
    p = tmp_path / "i64.tif"
    tifffile.imwrite(p, np.zeros((4, 4), dtype))
    for reader in (read_image, image_info):
        with pytest.raises(InvalidInputError, match=rf"a TIFF of {np.dtype(dtype)} samples"):
            reader(p)


def test_float16_info_says_what_read_image_returns(tmp_path: Path) -> None:
    p = tmp_path / "h.tif"
    tifffile.imwrite(p, np.full((4, 5), 0.5, np.float16))
    assert image_info(p).dtype == read_image(p).dtype.name == "float32"


def _res(p: Path, um: float, unit: str) -> Path:
    per = {"CENTIMETER": 1e4, "INCH": 25400.0, "MILLIMETER": 1e3}[unit]
    tifffile.imwrite(p, np.zeros((8, 8), np.uint16), resolution=(per / um, per / um),
                     resolutionunit=unit)  # fmt: skip
    return p


@pytest.mark.parametrize("um", [0.2282, 85.0, 139.0, 150.0, 200.0, 388.0])
def test_resolution_tags_in_centimetres_up_to_a_millimetre(tmp_path: Path, um: float) -> None:
    """A microscope's, an X-ray detector's (139, 150, 200 µm) and a binned panel's (388 µm)."""
    got = pixel_size_um(_res(tmp_path / "x.tif", um, "CENTIMETER"))
    assert got == pytest.approx((um, um), rel=1e-6)
    assert pixel_size_um(_res(tmp_path / "mm.tif", um, "MILLIMETER")) == pytest.approx((um, um))


@pytest.mark.parametrize(
    ("um", "unit"),
    [
        (25400 / 72, "CENTIMETER"),  # 72 dpi written in px/cm (photo software)
        (25400 / 96, "CENTIMETER"),  # 96 dpi
        (1000.0, "CENTIMETER"),  # libvips' 10 px/cm for an unknown resolution
        (10000.0, "CENTIMETER"),  # 1 px/cm
        (150.0, "INCH"),  # inches: every photograph's 72 or 300 dpi
        (25400 / 300, "INCH"),
    ],
)
def test_what_is_no_pixel_size_stays_unread(tmp_path: Path, um: float, unit: str) -> None:
    assert pixel_size_um(_res(tmp_path / "x.tif", um, unit)) is None


def test_imagej_and_ome_units_other_than_microns(tmp_path: Path) -> None:
    z = np.zeros((8, 8), np.uint16)
    ij = tmp_path / "ij.tif"  # ImageJ calibrated in mm: an X-ray's 0.15 mm
    tifffile.imwrite(ij, z, imagej=True, resolution=(1 / 0.15, 1 / 0.15), metadata={"unit": "mm"})
    assert pixel_size_um(ij) == pytest.approx((150.0, 150.0))
    inch = tmp_path / "inch.tif"  # ImageJ's unit=inch: a photograph's dpi
    tifffile.imwrite(inch, z, imagej=True, resolution=(72, 72), metadata={"unit": "inch"})
    assert pixel_size_um(inch) is None
    for unit, k in (("mm", 1e3), ("nm", 1e-3), ("µm", 1.0)):
        ome = tmp_path / f"o{k}.ome.tif"
        meta = {"PhysicalSizeX": 0.2, "PhysicalSizeY": 0.25}
        tifffile.imwrite(ome, z, metadata={**meta, "PhysicalSizeXUnit": unit,
                                           "PhysicalSizeYUnit": unit})  # fmt: skip
        assert pixel_size_um(ome) == pytest.approx((0.2 * k, 0.25 * k))
    zero = tmp_path / "zero.ome.tif"
    tifffile.imwrite(zero, z, metadata={"PhysicalSizeX": 0.0, "PhysicalSizeY": 0.0})
    assert pixel_size_um(zero) is None


def test_info_prints_an_x_ray_pixel_size(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    p = _res(tmp_path / "xray.tif", 139.0, "CENTIMETER")
    assert main(["info", str(p)]) == 0
    assert "pixel size: 139 x 139 µm" in capsys.readouterr().out


def test_pages_of_different_sizes_are_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A plain multi-page TIFF whose pages differ (libtiff's ``multipage.tif``: a bilevel
    fax page, a 4-bit palette image, an 8-bit one) was read as its first page, the others
    silently left out (tifffile makes a series per page shape). It is refused as a stack is,
    naming the sizes, and ``frame=N`` reads page N; a reduced-resolution page (a thumbnail,
    NewSubfileType 1) is no image of its own."""
    p = tmp_path / "pages.tif"
    grey = RNG.integers(0, 256, (30, 20), dtype=np.uint8)
    rgb = RNG.integers(0, 256, (12, 16, 3), dtype=np.uint8)
    with tifffile.TiffWriter(p) as w:
        w.write(grey)
        w.write(rgb, photometric="rgb")
        w.write(grey[:10, :10])
    with pytest.raises(InvalidInputError, match=r"multi-page TIFF of 3 images of different si"):
        read_image(p)
    sizes = r"20 x 30 px, 1 channel\(s\), uint8; 16 x 12 px, 3 channel\(s\), uint8; 10 x 10"
    with pytest.raises(InvalidInputError, match=sizes):
        image_info(p)
    from imageform.io import image_frames

    assert image_frames(p) == (3, (("pages", 3),))
    np.testing.assert_array_equal(read_image(p, frame=0)[..., 0], grey)
    np.testing.assert_array_equal(read_image(p, frame=1), rgb)
    np.testing.assert_array_equal(read_image(p, frame=2)[..., 0], grey[:10, :10])
    assert image_info(p, frame=1) == (16, 12, 3, "uint8", "tiff")
    with pytest.raises(InvalidInputError, match=r"frame 3 is out of range: .* 3 images"):
        read_image(p, frame=3)
    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "3 images (3 pages), of different sizes or types (frame 0: 20 x 30 px" in out
    thumb = tmp_path / "thumb.tif"
    with tifffile.TiffWriter(thumb) as w:
        w.write(rgb, photometric="rgb")
        w.write(rgb[::4, ::4], photometric="rgb", subfiletype=1)
    np.testing.assert_array_equal(read_image(thumb), rgb)
    assert image_frames(thumb).total == 1


def _png_with_cicp(path: Path, cicp: bytes, *, gama: bool = True) -> Path:
    """An 8-bit RGB PNG with a cICP chunk (and a gAMA of 1.6 that cICP overrides)."""
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        crc = zlib.crc32(kind + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    rows = b"".join(b"\0" + bytes([40, 80, 120] * 4) for _ in range(3))
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 3, 8, 2, 0, 0, 0))
    if gama:
        data += chunk(b"gAMA", struct.pack(">I", 62500))
    data += chunk(b"cICP", cicp) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    path.write_bytes(data)
    return path


def test_png_cicp_overrides_the_other_colour_chunks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """libavif's ``kodim03_grayscale_cicp.png`` (cICP 1/4/0/1 beside gAMA 0.625 and cHRM) was
    described by its gAMA, which PNG 3rd ed. says to ignore when cICP is present; an HDR
    screenshot's cICP (BT.2020 primaries, PQ: 9/16/0/1) declared nothing."""
    from imageform.io import DeclaredColorSpace, image_color_space

    p3 = _png_with_cicp(tmp_path / "p3.png", bytes([12, 13, 0, 1]))
    assert image_color_space(p3) == DeclaredColorSpace(
        "display_p3", "png-cicp", "cICP primaries 12, transfer 13, matrix 0, full range 1"
    )
    np.testing.assert_array_equal(read_image(p3)[0, 0], [40, 80, 120])
    pq = _png_with_cicp(tmp_path / "pq.png", bytes([9, 16, 0, 1]), gama=False)
    assert image_color_space(pq).name is None and image_color_space(pq).source == "png-cicp"
    assert main(["info", str(pq)]) == 0
    out = capsys.readouterr().out
    assert "no space of imageform matches (cICP primaries 9, transfer 16" in out
    out_png = tmp_path / "o.png"
    assert main(["cvd", str(p3), "--type", "deutan", "-o", str(out_png)]) == 0
    assert "declares display_p3 in its PNG cICP chunk" in capsys.readouterr().err


def test_png_chunks_out_of_order_give_a_warning_not_a_stderr_line(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """libavif's ``circle-trns-before-plte.png`` (an RGB image with a suggested palette and
    tRNS before it): libpng printed "PNG warning: PLTE: out of place" onto stderr beside
    every command's output. The pixels are as stored; the note is a Python warning."""
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        crc = zlib.crc32(kind + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    rows = b"".join(b"\0" + bytes([10, 200, 30] * 5) for _ in range(2))
    p = tmp_path / "order.png"
    p.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 5, 2, 8, 2, 0, 0, 0))
        + chunk(b"tRNS", bytes(6)) + chunk(b"PLTE", bytes([10, 200, 30]))
        + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    )  # fmt: skip
    capfd.readouterr()
    with pytest.warns(UserWarning, match="PLTE: out of place"):
        got = read_image(p)
    assert capfd.readouterr().err == ""
    np.testing.assert_array_equal(got, np.broadcast_to([10, 200, 30], (2, 5, 3)))
