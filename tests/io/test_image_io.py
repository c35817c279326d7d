"""imageform.io images: one rule for shape, alpha, orientation and memory; round trips;
corrupt, truncated and oversized files refused from their header in one line."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.io import image_files, image_info, read_image, read_png, write_image, write_png

RNG = np.random.default_rng(40)


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_png_round_trip(tmp_path: Path, channels: int, dtype: type) -> None:
    a = RNG.integers(0, np.iinfo(dtype).max + 1, (7, 9, channels)).astype(dtype)
    write_png(tmp_path / "a.png", a)
    b = read_png(tmp_path / "a.png")
    assert b.dtype == dtype
    np.testing.assert_array_equal(b, a)


def test_png_16bit_cross_check_opencv(tmp_path: Path) -> None:
    # Cross-check: OpenCV reads our 16-bit PNG identically (BGR order), and we read its.
    cv2 = pytest.importorskip("cv2")
    a = RNG.integers(0, 65536, (6, 5, 3)).astype(np.uint16)
    write_png(tmp_path / "a.png", a)
    np.testing.assert_array_equal(
        cv2.imread(str(tmp_path / "a.png"), cv2.IMREAD_UNCHANGED), a[..., ::-1]
    )
    cv2.imwrite(str(tmp_path / "b.png"), a[..., ::-1])  # OpenCV uses adaptive row filters
    np.testing.assert_array_equal(read_png(tmp_path / "b.png"), a)


def test_grey_is_one_channel_in_every_format(tmp_path: Path) -> None:
    from PIL import Image

    g = RNG.integers(0, 256, (5, 4)).astype(np.uint8)
    Image.fromarray(g).save(tmp_path / "g.png")
    Image.fromarray(g).save(tmp_path / "g.jpg", quality=100)
    write_image(tmp_path / "g.tif", g)
    np.save(tmp_path / "g.npy", g)
    for name in ("g.png", "g.tif", "g.npy", "g.jpg"):
        a = read_image(tmp_path / name)
        assert a.shape == (5, 4, 1) and a.dtype == np.uint8, name
        if name != "g.jpg":
            np.testing.assert_array_equal(a[..., 0], g)


def test_png_8bit_read_by_pillow_and_palette(tmp_path: Path) -> None:
    from PIL import Image

    a = RNG.integers(0, 256, (5, 4, 3)).astype(np.uint8)
    Image.fromarray(a).save(tmp_path / "p.png")
    np.testing.assert_array_equal(read_image(tmp_path / "p.png"), a)
    pal = Image.fromarray(a).quantize(8)
    pal.save(tmp_path / "pal.png")
    np.testing.assert_array_equal(read_image(tmp_path / "pal.png"), np.asarray(pal.convert("RGB")))


def test_alpha_rule(tmp_path: Path) -> None:
    """Opaque alpha is dropped; any transparency is refused unless dropped or kept."""
    from PIL import Image

    rgba = RNG.integers(0, 256, (4, 4, 4)).astype(np.uint8)
    rgba[..., 3] = 255
    write_png(tmp_path / "opaque.png", rgba)
    assert read_image(tmp_path / "opaque.png").shape == (4, 4, 3)
    rgba[0, 0, 3] = 10
    write_png(tmp_path / "t.png", rgba)
    with pytest.raises(InvalidInputError, match=r"t\.png has transparent pixels \(1 with"):
        read_image(tmp_path / "t.png")
    np.testing.assert_array_equal(read_image(tmp_path / "t.png", alpha="drop"), rgba[..., :3])
    np.testing.assert_array_equal(read_image(tmp_path / "t.png", alpha="keep"), rgba)
    la = np.stack([rgba[..., 0], rgba[..., 3]], -1)  # grey + alpha follows the same rule
    Image.fromarray(la, "LA").save(tmp_path / "la.png")
    with pytest.raises(InvalidInputError, match="transparent"):
        read_image(tmp_path / "la.png")
    assert read_image(tmp_path / "la.png", alpha="drop").shape == (4, 4, 1)
    pal = Image.fromarray(rgba[..., :3]).quantize(4)
    pal.info["transparency"] = 0
    pal.save(tmp_path / "palt.png", transparency=0)  # palette transparency: the same rule
    with pytest.raises(InvalidInputError, match="transparent"):
        read_image(tmp_path / "palt.png")
    with pytest.raises(UnknownOptionError, match="alpha handling"):
        read_image(tmp_path / "t.png", alpha="blend")
    write_image(tmp_path / "t.tif", rgba)  # TIFF: an extra sample is alpha, the same rule
    with pytest.raises(InvalidInputError, match="transparent"):
        read_image(tmp_path / "t.tif")
    np.save(tmp_path / "cmyk.npy", rgba)  # .npy has no alpha: four channels come back
    assert read_image(tmp_path / "cmyk.npy").shape == (4, 4, 4)


def test_exif_orientation_applied(tmp_path: Path) -> None:
    from PIL import Image

    a = np.zeros((8, 16, 3), np.uint8)
    a[:, :8] = 255  # white on the left of the stored pixels
    exif = Image.Exif()
    exif[0x0112] = 6  # viewer rotates 90 degrees clockwise
    Image.fromarray(a).save(tmp_path / "o.jpg", exif=exif.tobytes(), quality=100)
    Image.fromarray(a).save(tmp_path / "o.png", exif=exif.tobytes())
    for name in ("o.jpg", "o.png"):
        b = read_image(tmp_path / name)
        assert b.shape == (16, 8, 3), name  # upright: taller than wide
        assert b[:8].mean() > 200 and b[8:].mean() < 50, name  # left became top


def test_float_quantisation_and_no_silent_clipping(tmp_path: Path) -> None:
    assert write_image(tmp_path / "q.png", np.array([[[0.0, 0.5, 1.0]]]), bit_depth=8) == (8, 0)
    assert read_image(tmp_path / "q.png").tolist() == [[[0, 128, 255]]]
    with pytest.raises(InvalidInputError, match=r"1 values outside \[0, 1\].*--out-of-range"):
        write_image(tmp_path / "r.png", np.array([[[0.0, 1.2, 1.0]]]))
    assert not (tmp_path / "r.png").exists()
    w = write_image(tmp_path / "r.png", np.array([[[0.0, 1.2, -1.0]]]), out_of_range="clip")
    assert w.out_of_range == 2 and read_image(tmp_path / "r.png").tolist() == [[[0, 255, 0]]]
    with pytest.warns(DeprecationWarning, match="out_of_range"):
        write_image(tmp_path / "r2.png", np.array([[[1.5, 0, 0]]]), clip=True)
    with pytest.raises(InvalidInputError, match="NaN"):
        write_image(tmp_path / "s.png", np.array([[[0.0, np.nan, 1.0]]]))
    with pytest.raises(InvalidInputError, match="bit_depth 8 or 16"):
        write_image(tmp_path / "s.png", np.zeros((2, 2, 3)), bit_depth=12)
    with pytest.raises(InvalidInputError, match="JPEG holds 8 bits"):
        write_image(tmp_path / "s.jpg", np.zeros((2, 2, 3), np.uint16))
    with pytest.raises(InvalidInputError, match="JPEG has no alpha"):
        write_image(tmp_path / "s.jpg", np.zeros((2, 2, 4)))
    # 16-bit data written as 8 bits is rescaled, not cut
    write_image(tmp_path / "d.png", np.array([[65535, 32896, 0]], np.uint16), bit_depth=8)
    assert read_image(tmp_path / "d.png")[..., 0].tolist() == [[255, 128, 0]]


def test_tiff_and_npy_exact(tmp_path: Path) -> None:
    a = RNG.normal(size=(4, 5, 3)).astype(np.float32) * 50
    write_image(tmp_path / "a.tif", a)
    np.testing.assert_array_equal(read_image(tmp_path / "a.tif"), a)
    write_image(tmp_path / "a.npy", a.astype(np.float64))
    np.testing.assert_array_equal(read_image(tmp_path / "a.npy"), a.astype(np.float64))
    write_image(
        tmp_path / "b.tif", np.clip(a / 100 + 0.5, 0, 1), bit_depth=16
    )  # integer on request
    assert read_image(tmp_path / "b.tif").dtype == np.uint16


def test_pixel_limit_checked_from_the_header(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    a = np.zeros((30, 40, 3), np.uint8)
    for name in ("a.png", "a.jpg", "a.tif", "a.npy"):
        write_image(tmp_path / name, a)
        assert image_info(tmp_path / name)[:3] == (40, 30, 3)
        with pytest.raises(InvalidInputError, match=r"40 x 30 = 1200 px, above the limit of 1000"):
            read_image(tmp_path / name, max_pixels=1000)
        monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "1199")
        with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_PIXELS"):
            read_image(tmp_path / name)
        monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "1200")
        assert read_image(tmp_path / name).shape == (30, 40, 3)
        monkeypatch.delenv("IMAGEFORM_MAX_PIXELS")


def test_npy_header_is_not_trusted(tmp_path: Path) -> None:
    p = tmp_path / "big.npy"
    with p.open("wb") as fh:  # a header promising 12000 x 12000 x 3 float64, and no data
        np.lib.format.write_array_header_1_0(
            fh, {"descr": "<f8", "fortran_order": False, "shape": (12000, 12000, 3)}
        )
    with pytest.raises(InvalidInputError, match="above the limit"):
        read_image(p)
    with pytest.raises(InvalidInputError, match="truncated"):
        read_image(p, max_pixels=10**9)
    for name in ("empty.npy", "empty.jpg", "empty.png", "empty.tif"):
        (tmp_path / name).write_bytes(b"")
        with pytest.raises(InvalidInputError, match=rf"cannot read .*{name}: an empty file \(0"):
            read_image(tmp_path / name)
        with pytest.raises(InvalidInputError, match=rf"{name}: an empty file"):
            image_info(tmp_path / name)
    np.save(tmp_path / "obj.npy", np.array([[1, None]], dtype=object), allow_pickle=True)
    with pytest.raises(InvalidInputError, match="object arrays"):
        read_image(tmp_path / "obj.npy")


@pytest.mark.parametrize("name", ["a.png", "a.jpg", "a.tif"])
def test_truncated_and_corrupt_files(tmp_path: Path, name: str) -> None:
    a = RNG.integers(0, 256, (64, 64, 3)).astype(np.uint8)
    write_image(tmp_path / name, a)
    data = (tmp_path / name).read_bytes()
    cut = tmp_path / ("cut" + Path(name).suffix)
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidInputError, match=rf"cannot read {cut}") as info:
        read_image(cut)
    assert "\n" not in str(info.value)
    junk = tmp_path / ("junk" + Path(name).suffix)
    junk.write_bytes(b"not an image at all")
    with pytest.raises(InvalidInputError, match="cannot read"):
        read_image(junk)


def test_errors(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match=r"unknown image file type '\.avif'"):
        read_image(tmp_path / "a.avif")
    # an output name says what can be written, not the read-only formats alone (.webp, .dcm)
    with pytest.raises(InvalidInputError) as info:
        write_image(tmp_path / "out.txt", np.zeros((2, 2)))
    assert str(info.value).endswith(
        "and writes .png, .jpg, .jpeg, .tif, .tiff, .npy, .pgm, .ppm, .pfm"
    )
    assert not (tmp_path / "out.txt").exists()
    with pytest.raises(InvalidInputError, match="does not exist"):
        read_image(tmp_path / "missing.png")
    (tmp_path / "dir.png").mkdir()
    with pytest.raises(InvalidInputError, match="is a folder"):
        read_image(tmp_path / "dir.png")
    (tmp_path / "fake.png").write_bytes(b"not a png")
    with pytest.raises(InvalidInputError, match="not a PNG"):
        read_image(tmp_path / "fake.png")
    with pytest.raises(InvalidInputError, match="uint8 or uint16"):
        write_png(tmp_path / "x.png", np.zeros((2, 2, 3), np.int32))
    with pytest.raises(InvalidInputError, match="1 to 4 channels"):
        write_image(tmp_path / "x.png", np.zeros((2, 2, 5)))
    with pytest.raises(InvalidInputError, match="expected a file path"):
        read_image(None)  # type: ignore[arg-type]


def test_write_is_atomic(tmp_path: Path) -> None:
    """A failed write leaves the previous file and no temporary behind."""
    p = tmp_path / "a.png"
    write_image(p, np.zeros((2, 2, 3)))
    before = p.read_bytes()
    with pytest.raises(InvalidInputError):
        write_image(p, np.full((2, 2, 3), 2.0))
    assert p.read_bytes() == before and os.listdir(tmp_path) == ["a.png"]


def test_quantising_by_bands_is_the_whole_image_rule(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 25: a large image is quantised a band of rows at a time (bounded temporaries):
    the same samples, the same clip count, and the same refusal as in one piece."""
    import imageform.io.image_io as image_io

    monkeypatch.setattr(image_io, "_QUANTISE_BAND", 5 * 7 * 3)  # bands of 5 rows
    rng = np.random.default_rng(4)
    a = rng.uniform(-0.1, 1.1, (23, 7, 3))
    a[0, 0] = -0.4 / 255, 1 + 0.4 / 255, 1 + 0.6 / 255  # within half a code (8 bits) and not
    for bits, dtype in ((8, np.uint8), (16, np.uint16)):
        top = 2**bits - 1
        n = int(np.count_nonzero((a < -0.5 / top) | (a > 1 + 0.5 / top)))
        written = write_image(tmp_path / f"a{bits}.png", a, bit_depth=bits, out_of_range="clip")
        assert written.out_of_range == n
        expect = np.round(np.clip(a, 0, 1) * top).astype(dtype)
        np.testing.assert_array_equal(read_image(tmp_path / f"a{bits}.png"), expect)
    n8 = int(np.count_nonzero((a < -0.5 / 255) | (a > 1 + 0.5 / 255)))
    with pytest.raises(InvalidInputError, match=rf"^{n8} values outside \[0, 1\] \(min -0\.0"):
        write_image(tmp_path / "e.png", a, out_of_range="error")
    assert not (tmp_path / "e.png").exists()
    nan = a.copy()
    nan[20, 3, 1] = np.nan
    with pytest.raises(InvalidInputError, match="contains NaN or inf"):
        write_image(tmp_path / "n.png", nan, out_of_range="clip")


def test_a_value_a_rounding_error_outside_is_not_clipped(tmp_path: Path) -> None:
    """A value outside [0, 1] by less than half a code has its own code: stored, not counted,
    not refused by out_of_range="error" (a Lab round trip gives -1.7e-7); half a code or more
    outside is (its code would be -1 or 256)."""
    tiny = np.array([[[-1.7e-7, 1 + 1e-6, 0.5]]], np.float32)
    for bits in (8, 16):
        w = write_image(tmp_path / f"t{bits}.png", tiny, bit_depth=bits, out_of_range="error")
        assert w.out_of_range == 0
        top = 2**bits - 1
        assert read_image(tmp_path / f"t{bits}.png").tolist() == [[[0, top, round(0.5 * top)]]]
    with pytest.raises(InvalidInputError, match=r"^1 values outside \[0, 1\]"):
        write_image(tmp_path / "h.png", np.array([[[-0.51 / 255, 0.0, 1.0]]]))


# ---------------------------------------------------------------- TIFF samples as they mean
# (the odd-files sweep, benchmarks/check_odd_files.py: palette TIFFs came back as their
# indices, bilevel TIFFs were refused, WhiteIsZero came back inverted)


def test_tiff_palette_is_read_through_its_colour_map(tmp_path: Path) -> None:
    import tifffile
    from PIL import Image

    index = RNG.integers(0, 256, (6, 9)).astype(np.uint8)
    colours8 = RNG.integers(0, 256, (3, 256)).astype(np.uint16)
    tifffile.imwrite(tmp_path / "p8.tif", index, photometric="palette", colormap=colours8 * 257)
    got = read_image(tmp_path / "p8.tif")
    assert got.dtype == np.uint8 and got.shape == (6, 9, 3)
    with Image.open(tmp_path / "p8.tif") as im:  # the peer: Pillow's palette TIFF
        assert np.array_equal(got, np.asarray(im.convert("RGB")))
    assert image_info(tmp_path / "p8.tif")[2:4] == (3, "uint8")
    colours16 = RNG.integers(0, 65536, (3, 256)).astype(np.uint16)  # 16-bit colours stay 16
    tifffile.imwrite(tmp_path / "p16.tif", index, photometric="palette", colormap=colours16)
    assert np.array_equal(read_image(tmp_path / "p16.tif"), colours16.T[index])
    assert image_info(tmp_path / "p16.tif")[2:4] == (3, "uint16")


def test_tiff_bilevel_and_white_is_zero_match_pillow(tmp_path: Path) -> None:
    import tifffile
    from PIL import Image

    bits = RNG.random((5, 12)) > 0.5
    tifffile.imwrite(tmp_path / "bilevel.tif", bits)  # 1 bit per sample
    grey = (RNG.random((5, 12)) * 255).astype(np.uint8)
    tifffile.imwrite(tmp_path / "white0.tif", grey, photometric="miniswhite")
    for name in ("bilevel.tif", "white0.tif"):
        got = read_image(tmp_path / name)
        with Image.open(tmp_path / name) as im:
            assert np.array_equal(got[..., 0], np.asarray(im.convert("L"))), name
        assert got.dtype == np.uint8
    assert np.array_equal(read_image(tmp_path / "white0.tif")[..., 0], 255 - grey)
    assert image_info(tmp_path / "bilevel.tif").dtype == "uint8"


def test_tiff_of_fewer_bits_reads_as_stored(tmp_path: Path) -> None:
    # 10/12/14-bit samples are a sensor's numbers (DN): emva and characterize measure them as
    # such, so they are not rescaled (tifffile and scikit-image read them so too)
    import tifffile

    codes12 = RNG.integers(0, 4096, (4, 7, 3)).astype(np.uint16)
    tifffile.imwrite(tmp_path / "12.tif", codes12, bitspersample=12, photometric="rgb")
    got = read_image(tmp_path / "12.tif")
    assert got.dtype == np.uint16 and np.array_equal(got, codes12)
    assert np.array_equal(got, tifffile.imread(tmp_path / "12.tif"))
    # WhiteIsZero of 12 bits inverts within 12 bits: 4095 is black
    grey = codes12[..., 0]
    tifffile.imwrite(tmp_path / "w12.tif", grey, bitspersample=12, photometric="miniswhite")
    assert np.array_equal(read_image(tmp_path / "w12.tif")[..., 0], 4095 - grey)


@pytest.mark.parametrize(
    ("photometric", "what"),
    [("separated", "CMYK"), ("cielab", "CIELab"), ("ycbcr", "YCbCr (not JPEG-compressed)")],
)
def test_tiff_that_is_not_rgb_is_refused(tmp_path: Path, photometric: str, what: str) -> None:
    import tifffile

    channels = 4 if photometric == "separated" else 3
    a = (RNG.random((4, 6, channels)) * 255).astype(np.uint8)
    extra = {"subsampling": (1, 1)} if photometric == "ycbcr" else {}
    tifffile.imwrite(tmp_path / "c.tif", a, photometric=photometric, **extra)
    with pytest.raises(InvalidInputError, match=rf"c\.tif: a {re.escape(what)}.*TIFF") as err:
        read_image(tmp_path / "c.tif")
    assert "\n" not in str(err.value)


def test_jpeg_tiff_in_ycbcr_is_read_as_rgb(tmp_path: Path) -> None:
    import tifffile
    from PIL import Image

    rgb = np.zeros((16, 16, 3), np.uint8)
    rgb[..., 0] = 200  # a saturated red: Y, Cb, Cr read as RGB would not be red
    tifffile.imwrite(tmp_path / "j.tif", rgb, photometric="rgb", compression="jpeg")
    got = read_image(tmp_path / "j.tif")
    with Image.open(tmp_path / "j.tif") as im:
        assert np.abs(got.astype(int) - np.asarray(im.convert("RGB"))).max() <= 2


def test_cmyk_jpeg_info_counts_the_channels_read(tmp_path: Path) -> None:
    from PIL import Image

    Image.new("CMYK", (5, 4), (10, 20, 30, 40)).save(tmp_path / "cmyk.jpg")
    assert image_info(tmp_path / "cmyk.jpg").channels == read_image(tmp_path / "cmyk.jpg").shape[2]


# ---------------------------------------------------------------- the bytes choose the decoder


def test_a_file_is_read_as_what_it_holds_not_its_suffix(tmp_path: Path) -> None:
    """A PNG or TIFF named .jpg went through Pillow as a JPEG: 16-bit RGB came back as 8 bits,
    transparency slipped past the alpha rule, a TIFF's orientation was applied twice."""
    import tifffile
    from PIL import Image

    rgb16 = RNG.integers(0, 65536, (5, 7, 3)).astype(np.uint16)
    write_image(tmp_path / "deep.png", rgb16)
    (tmp_path / "deep.jpg").write_bytes((tmp_path / "deep.png").read_bytes())
    got = read_image(tmp_path / "deep.jpg")
    assert got.dtype == np.uint16 and np.array_equal(got, rgb16)
    assert image_info(tmp_path / "deep.jpg") == (7, 5, 3, "uint16", "png")

    rgba = np.dstack([rgb16[..., :3] // 257, np.full((5, 7), 255)]).astype(np.uint8)
    rgba[0, 0, 3] = 0
    Image.fromarray(rgba).save(tmp_path / "alpha.jpg", format="PNG")
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(tmp_path / "alpha.jpg")

    stored = RNG.integers(0, 256, (6, 10, 3)).astype(np.uint8)
    exif = Image.Exif()
    exif[0x0112] = 6
    Image.fromarray(stored).save(tmp_path / "turned.tif", exif=exif)
    (tmp_path / "turned.jpg").write_bytes((tmp_path / "turned.tif").read_bytes())
    upright = read_image(tmp_path / "turned.tif")
    assert upright.shape == (10, 6, 3)
    assert np.array_equal(read_image(tmp_path / "turned.jpg"), upright)
    tifffile.imwrite(tmp_path / "t.tif", stored)  # and a JPEG named .png reads as the JPEG
    Image.fromarray(stored).save(tmp_path / "photo.png", format="JPEG", quality=90)
    Image.fromarray(stored).save(tmp_path / "photo.jpg", format="JPEG", quality=90)
    assert np.array_equal(read_image(tmp_path / "photo.png"), read_image(tmp_path / "photo.jpg"))


@pytest.mark.parametrize("fmt", ["GIF", "WEBP", "BMP"])
@pytest.mark.parametrize("suffix", [".png", ".jpg", ".tif"])
def test_a_gif_webp_or_bmp_under_another_suffix_reads_as_what_it_holds(
    tmp_path: Path, fmt: str, suffix: str
) -> None:
    """These were refused naming what they held; they are read now, by their bytes."""
    from PIL import Image

    path = tmp_path / f"image{suffix}"
    Image.new("RGB", (4, 3), (200, 10, 10)).save(path, format=fmt, lossless=True)
    assert image_info(path) == (4, 3, 3, "uint8", fmt.lower())
    assert read_image(path)[0, 0].tolist() == [200, 10, 10]


@pytest.mark.parametrize("suffix", [".png", ".jpg", ".tif", ".webp"])
def test_a_format_imageform_does_not_read_is_named_under_any_suffix(
    tmp_path: Path, suffix: str
) -> None:
    from PIL import Image, features

    if not features.check("avif"):
        pytest.skip("this Pillow writes no AVIF")
    path = tmp_path / f"image{suffix}"
    Image.new("RGB", (4, 3), (200, 10, 10)).save(path, format="AVIF")
    for read in (read_image, image_info):
        with pytest.raises(InvalidInputError, match="holds an AVIF image") as err:
            read(path)
        assert "\n" not in str(err.value) and str(path) in str(err.value)


# ---------------------------------------------------------------- libpng's own words, and tRNS


def _png_with_ihdr(path: Path, byte: int, value: int) -> None:
    """Rewrite one byte of a PNG's IHDR (the offset in the file) and its CRC."""
    import struct
    import zlib

    data = bytearray(path.read_bytes())
    data[byte] = value
    crc = zlib.crc32(bytes(data[12:29])) & 0xFFFFFFFF  # "IHDR" and its 13 bytes
    data[29:33] = struct.pack(">I", crc)
    path.write_bytes(bytes(data))


def test_interlaced_png_is_read_without_libpng_on_stderr(tmp_path: Path) -> None:
    """libpng printed 'PNG warning: Interlace handling should be turned on ...' onto stderr
    for every interlaced PNG (PngSuite s01i3p01), a second line beside a command's one. Run
    as a program: what imagecodecs prints is not what pytest's capture sees."""
    import subprocess
    import sys

    path = tmp_path / "adam7.png"
    write_image(path, np.array([[[200, 30, 90]]], np.uint8))  # 1 x 1: Adam7's pass 1 only
    _png_with_ihdr(path, 28, 1)  # the interlace method
    assert read_image(path).tolist() == [[[200, 30, 90]]]
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root / "src")}
    done = subprocess.run(
        [sys.executable, "-m", "imageform", "vanishing", str(path)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 1
    assert done.stderr.strip().splitlines() == [
        "imageform: error: expected an image of at least 3 x 3 pixels, got 1 x 1"
    ]


def test_png_header_that_libpng_refuses_is_refused_first(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """RGB at 4 bits (PngSuite xd3n2c08): libpng printed two warnings before its error."""
    path = tmp_path / "rgb4.png"
    write_image(path, np.zeros((2, 2, 3), np.uint8))
    _png_with_ihdr(path, 24, 4)  # the bit depth
    for read in (read_image, image_info):
        with pytest.raises(InvalidInputError, match=r"rgb4\.png: corrupt PNG header"):
            read(path)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("mode", "transparency", "channels"),
    [("P", 0, 4), ("RGB", (0, 0, 0), 4), ("L", 0, 2)],
)
def test_png_info_counts_trns_as_the_alpha_it_reads_as(
    tmp_path: Path, mode: str, transparency: object, channels: int
) -> None:
    from PIL import Image

    a = RNG.integers(0, 256, (4, 5, 3)).astype(np.uint8)
    a[0, 0] = 0
    img = Image.fromarray(a).convert(mode)
    img.save(tmp_path / "t.png", transparency=transparency)
    assert read_image(tmp_path / "t.png", alpha="keep").shape[2] == channels
    assert image_info(tmp_path / "t.png").channels == channels


@pytest.mark.parametrize(
    ("layout", "words"),
    [
        ("contig", "a TIFF of 7 samples per pixel"),  # YXS
        ("separate", "a TIFF of 7 samples per pixel"),  # SYX (planar)
        ("pages", "a stack of 7 images of 10 x 8 px (7 pages)"),  # QYX
        ("ome", "a stack of 7 images of 10 x 8 px (7 channels)"),  # CYX
    ],
)
def test_tiff_of_more_than_four_channels_is_refused_alike_by_info_and_read(
    tmp_path: Path, layout: str, words: str
) -> None:
    """7 bands of a multispectral camera: images are grey or RGB (+ alpha), 1 to 4 channels
    (docs/conventions.md); image_info says what read_image does, in the same line."""
    import tifffile

    a = RNG.integers(0, 65535, (8, 10, 7)).astype(np.uint16)
    p = tmp_path / ("b.ome.tif" if layout == "ome" else "b.tif")
    if layout == "contig":
        tifffile.imwrite(p, a, photometric="minisblack", planarconfig="contig")
    elif layout == "separate":
        tifffile.imwrite(p, np.moveaxis(a, -1, 0), photometric="minisblack",
                         planarconfig="separate")  # fmt: skip
    elif layout == "pages":
        tifffile.imwrite(p, np.moveaxis(a, -1, 0), photometric="minisblack")
    else:
        tifffile.imwrite(p, np.moveaxis(a, -1, 0), metadata={"axes": "CYX"})
    with pytest.raises(InvalidInputError) as info_err:
        image_info(p)
    with pytest.raises(InvalidInputError) as read_err:
        read_image(p)
    assert str(info_err.value) == str(read_err.value)
    assert words in str(read_err.value)
    assert "\n" not in str(read_err.value)


def test_a_stack_of_narrow_grey_pages_is_not_read_as_colour(tmp_path: Path) -> None:
    """Two 3-px-wide grey pages (QYX) once came back as one 2 x 8 image of 3 channels."""
    import tifffile

    p = tmp_path / "narrow.tif"
    tifffile.imwrite(p, RNG.integers(0, 255, (2, 8, 3)).astype(np.uint8),
                     photometric="minisblack")  # fmt: skip
    with pytest.raises(InvalidInputError, match="a stack of 2 images of 3 x 8 px"):
        read_image(p)
    with pytest.raises(InvalidInputError, match="a stack of 2 images of 3 x 8 px"):
        image_info(p)


def test_pillow_decodes_in_threads_at_once_and_alike(tmp_path: Path) -> None:
    """Reads in threads give the serial arrays, and two decodes run at the same time.

    Both threads must reach Pillow's decoding (``ImageFile.load``) together: a barrier there
    waits for the two. Under a lock held through the decoding it would time out.
    """
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from PIL import Image, ImageFile

    paths = []
    for k in range(8):
        a = (RNG.random((40, 60, 3)) * 255).astype(np.uint8)
        path = tmp_path / (f"{k}.jpg" if k % 2 else f"{k}.webp")
        Image.fromarray(a).save(path, quality=90)
        paths.append(path)
    serial = [read_image(p) for p in paths]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(read_image, paths))
    for s, t in zip(serial, threaded, strict=True):
        np.testing.assert_array_equal(s, t)

    barrier = threading.Barrier(2, timeout=10)
    original = ImageFile.ImageFile.load

    def load(self: ImageFile.ImageFile) -> object:
        barrier.wait()  # BrokenBarrierError if the other thread cannot get here
        return original(self)

    ImageFile.ImageFile.load = load  # type: ignore[method-assign]
    try:
        with ThreadPoolExecutor(2) as pool:
            both = list(pool.map(read_image, paths[1:4:2]))
    finally:
        ImageFile.ImageFile.load = original  # type: ignore[method-assign]
    for got, want in zip(both, serial[1:4:2], strict=True):
        np.testing.assert_array_equal(got, want)


def test_image_files_natural_order_hidden_and_other_files_left_out(tmp_path: Path) -> None:
    # a camera or a video export numbers its files Cam1 ... Cam10: 2 comes before 10
    for name in ("Cam10.PNG", "Cam2.jpg", "cam1.tif", "x.dcm", "notes.txt", ".Cam3.png"):
        (tmp_path / name).write_bytes(b"")
    (tmp_path / "sub.png").mkdir()  # a folder named like an image is not one
    assert [p.name for p in image_files(tmp_path)] == ["cam1.tif", "Cam2.jpg", "Cam10.PNG", "x.dcm"]
    assert [p.name for p in image_files(str(tmp_path))] == [p.name for p in image_files(tmp_path)]


def test_image_files_refuses_a_file_or_a_folder_without_images(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("x")
    with pytest.raises(InvalidInputError, match=r"holds no images \(.*\.png") as info:
        image_files(tmp_path)
    assert "\n" not in str(info.value)
    with pytest.raises(InvalidInputError, match="expected a folder of images"):
        image_files(tmp_path / "notes.txt")
    with pytest.raises(InvalidInputError, match="expected a folder of images"):
        image_files(tmp_path / "missing")
