"""WebP, BMP and GIF read through Pillow by the one image rule: shape, alpha, orientation,
pixel limit from the header, ICC profile; animated files refused in one line. Each file is
made here (Pillow, or the bytes of a BMP written out by hand for what Pillow does not write:
4-bit, RLE, top-down); OpenCV (its own BMP decoder, libwebp) is the peer."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_color_space, image_info, read_image, write_image

RNG = np.random.default_rng(77)
RGB = (RNG.random((5, 7, 3)) * 255).astype(np.uint8)


def _cv2_rgb(path: Path) -> np.ndarray:
    cv2 = pytest.importorskip("cv2")
    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert a is not None, f"OpenCV cannot decode {path}"
    if a.ndim == 2:
        return a[..., None]
    return a[..., [2, 1, 0, 3]] if a.shape[2] == 4 else a[..., ::-1]


# ---------------------------------------------------------------- BMP


def _bmp(
    index_rows: np.ndarray,
    palette: np.ndarray,
    *,
    bits: int,
    compression: int = 0,
    top_down: bool = False,
    size: tuple[int, int] | None = None,
) -> bytes:
    """A palette BMP (BITMAPINFOHEADER): ``index_rows`` (H, W) stored as ``bits`` per pixel,
    uncompressed (0), RLE8 (1) or RLE4 (2); rows bottom-up unless ``top_down``."""
    h, w = index_rows.shape
    rows = index_rows if top_down else index_rows[::-1]
    if compression == 0:
        body = b""
        for r in rows:
            if bits == 8:
                line = bytes(r.astype(np.uint8))
            else:  # 4 bits: two pixels a byte, the first in the high nibble
                pad = np.append(r, 0) if len(r) % 2 else r
                line = bytes((pad[0::2] << 4 | pad[1::2]).astype(np.uint8))
            body += line + b"\0" * (-len(line) % 4)
    else:  # encoded mode, one run per pixel, then end of line; end of bitmap
        body = b""
        for r in rows:
            for v in r:
                body += bytes([1, int(v) if compression == 1 else int(v) << 4 | int(v)])
            body += b"\0\0"
        body += b"\0\1"
    width, height = size or (w, h)
    pal = b"".join(bytes([b, g, r, 0]) for r, g, b in palette)
    offset = 14 + 40 + len(pal)
    info = struct.pack(
        "<IiiHHIIiiII", 40, width, -height if top_down else height, 1, bits, compression,
        len(body), 2835, 2835, len(palette), 0,
    )  # fmt: skip
    head = b"BM" + struct.pack("<IHHI", offset + len(body), 0, 0, offset)
    return head + info + pal + body


PALETTE = (RNG.random((16, 3)) * 255).astype(np.uint8)
INDEX = RNG.integers(0, 16, (5, 7))


@pytest.mark.parametrize(
    ("bits", "compression", "top_down"),
    [(4, 0, False), (8, 0, False), (8, 0, True), (4, 0, True), (8, 1, False), (4, 2, False)],
)
def test_palette_bmp_is_rgb_through_its_palette_as_opencv_reads_it(
    tmp_path: Path, bits: int, compression: int, top_down: bool
) -> None:
    """4 and 8 bits, RLE8 and RLE4, bottom-up and top-down (negative height)."""
    path = tmp_path / "scan.bmp"
    path.write_bytes(_bmp(INDEX, PALETTE, bits=bits, compression=compression, top_down=top_down))
    got = read_image(path)
    assert got.shape == (5, 7, 3) and got.dtype == np.uint8
    assert np.array_equal(got, PALETTE[INDEX])  # row 0 is the top row either way
    assert np.array_equal(got, _cv2_rgb(path))
    assert image_info(path) == (7, 5, 3, "uint8", "bmp")


@pytest.mark.parametrize("mode", ["1", "L", "RGB", "RGBA"])
def test_bmp_of_1_8_24_and_32_bits(tmp_path: Path, mode: str) -> None:
    src = {
        "1": RGB[..., 0] > 128,
        "L": RGB[..., 0],
        "RGB": RGB,
        "RGBA": np.dstack([RGB, np.full(RGB.shape[:2], 255, np.uint8)]),
    }[mode]
    path = tmp_path / "old microscope.bmp"
    Image.fromarray(src).save(path)
    got = read_image(path)
    want = _cv2_rgb(path)
    if mode == "1":
        assert set(np.unique(got)) <= {0, 255}  # bilevel as 0/255, as a bilevel TIFF
    assert got.shape == want.shape[:2] + (min(want.shape[2], 3),)
    assert np.array_equal(got, want[..., : got.shape[2]])
    assert image_info(path).channels == got.shape[2]


def test_bmp_header_over_the_pixel_limit_is_refused_before_decoding(tmp_path: Path) -> None:
    """A 60000 x 60000 header over 20 bytes of pixels: the limit from the header, one line."""
    path = tmp_path / "bomb.bmp"
    path.write_bytes(_bmp(INDEX, PALETTE, bits=8, size=(60_000, 60_000)))
    with pytest.raises(InvalidInputError, match=r"60000 x 60000 = 3600 Mpx, above the limit"):
        read_image(path)
    small = tmp_path / "small.bmp"
    Image.fromarray(RGB).save(small)
    with pytest.raises(InvalidInputError, match="above the limit of 20 px"):
        read_image(small, max_pixels=20)
    assert read_image(small, max_pixels=35).shape == (5, 7, 3)


def test_truncated_or_corrupt_bmp_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "cut.bmp"
    Image.fromarray(RGB).save(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 40])
    with pytest.raises(InvalidInputError, match=r"cannot read .*cut\.bmp") as err:
        read_image(path)
    assert "\n" not in str(err.value)
    path.write_bytes(data[:30])  # the header cut inside
    with pytest.raises(InvalidInputError, match=r"cannot read .*cut\.bmp"):
        image_info(path)


# ---------------------------------------------------------------- GIF


def test_single_frame_gif_through_its_palette_and_transparency_by_the_alpha_rule(
    tmp_path: Path,
) -> None:
    pal = Image.fromarray(RGB).convert("P", palette=Image.Palette.ADAPTIVE, colors=32)
    index = np.asarray(pal)
    colours = np.array((pal.getpalette() or [])[: 3 * 32], np.uint8).reshape(-1, 3)
    path = tmp_path / "opaque.gif"
    pal.save(path)
    assert np.array_equal(read_image(path), colours[index])
    assert image_info(path) == (7, 5, 3, "uint8", "gif")

    clear = tmp_path / "clear.gif"
    pal.save(clear, transparency=int(index[0, 0]))
    assert image_info(clear).channels == 4  # as read, before the alpha rule
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(clear)
    kept = read_image(clear, alpha="keep")
    assert kept.shape == (5, 7, 4)
    assert np.array_equal(kept[..., 3] == 0, index == index[0, 0])
    assert np.array_equal(read_image(clear, alpha="drop"), colours[index])


@pytest.mark.parametrize("fmt", ["GIF", "WEBP"])
def test_animated_gif_or_webp_is_refused_in_one_line(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / f"clip.{fmt.lower()}"
    frames = [Image.fromarray(np.roll(RGB, 2 * k, axis=1)) for k in range(3)]
    frames[0].save(path, format=fmt, save_all=True, append_images=frames[1:])
    name = {"GIF": "GIF", "WEBP": "WebP"}[fmt]
    for read in (read_image, image_info):
        with pytest.raises(InvalidInputError, match=f"an animated {name} of 3 frames") as err:
            read(path)
        assert "\n" not in str(err.value)
    assert main(["info", str(path)]) == 0  # lists its frames (tests/io/test_frames.py)


# ---------------------------------------------------------------- WebP


def test_lossless_and_lossy_webp_as_libwebp_decodes_them(tmp_path: Path) -> None:
    lossless, lossy = tmp_path / "a.webp", tmp_path / "b.webp"
    Image.fromarray(RGB).save(lossless, lossless=True)
    Image.fromarray(RGB).save(lossy, quality=80)
    assert np.array_equal(read_image(lossless), RGB)
    assert np.array_equal(read_image(lossy), _cv2_rgb(lossy))
    assert image_info(lossy) == (7, 5, 3, "uint8", "webp")


def test_webp_alpha_follows_the_alpha_rule(tmp_path: Path) -> None:
    rgba = np.dstack([RGB, np.full(RGB.shape[:2], 255, np.uint8)])
    opaque = tmp_path / "opaque.webp"
    Image.fromarray(rgba).save(opaque, lossless=True)
    assert read_image(opaque).shape == (5, 7, 3)  # an opaque alpha channel is dropped
    rgba[0, 0, 3] = 0
    clear = tmp_path / "clear.webp"
    Image.fromarray(rgba).save(clear, lossless=True, exact=True)
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(clear)
    assert np.array_equal(read_image(clear, alpha="keep"), rgba)
    assert np.array_equal(read_image(clear, alpha="drop"), RGB)


def test_webp_exif_orientation_is_applied_and_info_gives_the_upright_size(
    tmp_path: Path,
) -> None:
    exif = Image.Exif()
    exif[0x0112] = 6
    path = tmp_path / "phone.webp"
    Image.fromarray(RGB).save(path, lossless=True, exif=exif)
    got = read_image(path)
    assert got.shape == (7, 5, 3)
    assert np.array_equal(got, np.rot90(RGB, -1))  # 6: turn 90 degrees clockwise
    assert image_info(path)[:2] == (5, 7)


def test_webp_icc_profile_names_its_color_space(tmp_path: Path) -> None:
    from imageform.io.icc import embedded_profile

    path = tmp_path / "p3.webp"
    Image.fromarray(RGB).save(path, lossless=True, icc_profile=embedded_profile("display_p3"))
    assert image_color_space(path)[:2] == ("display_p3", "icc")
    plain = tmp_path / "plain.gif"
    Image.fromarray(RGB).save(plain)
    assert image_color_space(plain) == (None, "none", "")


def test_webp_bmp_gif_are_read_not_written(tmp_path: Path) -> None:
    for suffix, name in ((".webp", "WebP"), (".bmp", "BMP"), (".gif", "GIF")):
        with pytest.raises(InvalidInputError, match=f"reads {name} but does not write it"):
            write_image(tmp_path / f"out{suffix}", RGB)
        assert not list(tmp_path.iterdir())


def test_commands_read_webp_bmp_gif(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for name in ("in.webp", "in.bmp", "in.gif"):
        Image.fromarray(RGB).save(tmp_path / name, lossless=True)  # (WebP's; BMP, GIF ignore it)
        out = tmp_path / f"{name}.tif"
        assert main(["convert", str(tmp_path / name), "--to", "lab", "-o", str(out)]) == 0
        assert read_image(out).shape == (5, 7, 3)
        assert main(["info", str(tmp_path / name)]) == 0
    assert "in.gif: gif, 7 x 5 px, 3 channel(s), uint8" in capsys.readouterr().out


# ---------------------------------------------------------------- TIFF stacks, upright size


def test_tiff_stack_is_refused_saying_what_it_holds_in_plain_words(tmp_path: Path) -> None:
    """It said "expected one image (H, W) or (H, W, C), got axes QYXS of shape ..."."""
    import tifffile

    pages = tmp_path / "pages.tif"
    tifffile.imwrite(pages, np.stack([RGB, RGB[::-1], RGB]))
    with pytest.raises(InvalidInputError) as err:
        read_image(pages)
    text = str(err.value)
    assert "a stack of 3 images of 7 x 5 px (3 pages)" in text
    assert "axes" not in text and "QYXS" not in text and "\n" not in text
    hyper = tmp_path / "timelapse.ome.tif"
    tifffile.imwrite(hyper, np.zeros((4, 2, 6, 8), np.uint16), metadata={"axes": "TZYX"})
    with pytest.raises(InvalidInputError, match=r"8 images of 8 x 6 px \(4 time points x 2 z-pl"):
        image_info(hyper)
    assert main(["info", str(hyper)]) == 0  # lists its 8 images (tests/io/test_frames.py)


@pytest.mark.parametrize("suffix", [".jpg", ".png", ".tif", ".webp"])
def test_info_gives_the_upright_size_and_the_stored_one(
    tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A phone's portrait stored on its side (EXIF 6): info said 7 x 5, read_image 5 x 7."""
    import json

    exif = Image.Exif()
    exif[0x0112] = 6
    path = tmp_path / f"portrait{suffix}"
    Image.fromarray(RGB).save(path, exif=exif, lossless=True)  # lossless: WebP's, others ignore it
    h, w = read_image(path).shape[:2]
    assert (h, w) == (7, 5)
    assert image_info(path)[:2] == (w, h)
    assert main(["info", str(path), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert (got["width"], got["height"]) == (5, 7)
    assert (got["stored_width"], got["stored_height"], got["exif_orientation"]) == (7, 5, 6)
    assert main(["info", str(path)]) == 0
    text = capsys.readouterr().out
    assert "5 x 7 px" in text and "stored 7 x 5 px" in text


@pytest.mark.parametrize("suffix", [".webp", ".heic"])
def test_a_command_writing_a_read_only_format_names_no_temporary_file(
    tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """It said "write .out.heic.21644-f323a388.part.png, .jpg or .tif" (the atomic write's
    temporary name); refused before anything is read now, saying the format is read only."""
    src = tmp_path / "in.png"
    write_image(src, RGB)
    out = tmp_path / f"out{suffix}"
    assert main(["cvd", str(src), "--type", "deutan", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    name = {".webp": "WebP", ".heic": "HEIF"}[suffix]
    assert f"cvd writes an image: imageform reads {name} but does not write it" in err
    assert ".part" not in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.png"]


def test_bmp_header_promising_more_rows_than_the_file_holds_is_refused_before_decoding(
    tmp_path: Path,
) -> None:
    """8000 x 8000 within the pixel limit, over 40 bytes of rows: refused from the sizes,
    without allocating the 64 MB image (one line)."""
    path = tmp_path / "short.bmp"
    path.write_bytes(_bmp(INDEX, PALETTE, bits=8, size=(8000, 8000)))
    with pytest.raises(InvalidInputError, match=r"the file is truncated \(\d+ bytes, its header"):
        read_image(path)


@pytest.mark.parametrize(
    ("suffix", "channels"), [(".jpg", 1), (".jpg", 3), (".bmp", 1), (".bmp", 3), (".webp", 3)]
)
def test_pillow_decodes_are_writeable(tmp_path: Path, suffix: str, channels: int) -> None:
    """Pillow's array is read-only; read_image's is not, as a PNG's: numba compiles every
    kernel again for a read-only array (a JPEG's first undistort after cache --warm)."""
    path = tmp_path / f"im{suffix}"
    Image.fromarray(RGB[..., 0] if channels == 1 else RGB).save(path)
    a = np.asarray(read_image(path))
    assert a.flags.writeable and a.shape[-1] == channels
