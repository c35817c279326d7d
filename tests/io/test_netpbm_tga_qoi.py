"""Netpbm (PBM, PGM, PPM, PAM: P1-P7), TGA and QOI read; PGM/PPM written; a BMP's embedded
ICC profile (BITMAPV5HEADER) as its declared colour space.

Each file is made here: by Pillow, OpenCV, or by hand (the bytes the Netpbm pages describe,
netpbm.sourceforge.net/doc/pgm.html, pam.html), and the values imageform reads are checked
against Pillow's, OpenCV's and imageio's decoding of the same file. Pillow and imageio scale
a maxval other than 255 / 65535 to the full range; OpenCV returns the stored numbers, which
``round(v / maxval * 65535)`` turns into the same values.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_color_space, image_info, read_image, write_image

RNG = np.random.default_rng(20261130)
RGB8 = (RNG.random((5, 7, 3)) * 255).astype(np.uint8)
GREY16 = (RNG.random((6, 9)) * 65535).astype(np.uint16)


def _cv2(path: Path) -> np.ndarray:
    cv2 = pytest.importorskip("cv2")
    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert a is not None, f"OpenCV cannot decode {path}"
    if a.ndim == 2:
        return a[..., None]
    return a[..., [2, 1, 0, 3]] if a.shape[2] == 4 else a[..., ::-1]


def _pillow(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        a = np.asarray(im.convert("L") if im.mode == "1" else im)
    return a[..., None] if a.ndim == 2 else a


def _scaled(v: np.ndarray, maxval: int, top: int) -> np.ndarray:
    return np.rint(v.astype(np.float64) / maxval * top)


# ---------------------------------------------------------------- Netpbm: written by peers


def test_pgm_ppm_written_by_pillow_and_opencv_read_as_they_read_them(tmp_path: Path) -> None:
    cv2 = pytest.importorskip("cv2")
    Image.fromarray(RGB8).save(tmp_path / "pil.ppm")
    Image.fromarray(RGB8[..., 0]).save(tmp_path / "pil.pgm")
    cv2.imwrite(str(tmp_path / "cv16.pgm"), GREY16)  # 16-bit depth map: maxval 65535
    rgb16 = (RNG.random((4, 6, 3)) * 65535).astype(np.uint16)
    cv2.imwrite(str(tmp_path / "cv16.ppm"), rgb16[..., ::-1])
    assert np.array_equal(read_image(tmp_path / "pil.ppm"), RGB8)
    assert np.array_equal(read_image(tmp_path / "pil.pgm"), RGB8[..., :1])
    got = read_image(tmp_path / "cv16.pgm")
    assert got.dtype == np.uint16 and np.array_equal(got, GREY16[..., None])
    assert np.array_equal(got, _cv2(tmp_path / "cv16.pgm"))
    assert np.array_equal(read_image(tmp_path / "cv16.ppm"), rgb16)
    for name in ("pil.ppm", "pil.pgm", "cv16.pgm"):  # Pillow: 16-bit grey as mode I
        assert np.array_equal(read_image(tmp_path / name), _pillow(tmp_path / name)), name
    info = image_info(tmp_path / "cv16.ppm")
    assert (info.width, info.height, info.channels, info.dtype, info.format) == (
        6, 4, 3, "uint16", "netpbm")  # fmt: skip


def test_pam_written_by_opencv(tmp_path: Path) -> None:
    """OpenCV writes a PAM's samples in the array's order, with no TUPLTYPE, and reads them
    back so (no BGR swap, unlike its PPM); depth 3 is read as RGB, as Netpbm's tools read it."""
    cv2 = pytest.importorskip("cv2")
    cv2.imwrite(str(tmp_path / "c.pam"), RGB8)
    assert b"TUPLTYPE" not in (tmp_path / "c.pam").read_bytes()[:80]
    assert np.array_equal(read_image(tmp_path / "c.pam"), RGB8)
    assert np.array_equal(read_image(tmp_path / "c.pam"), cv2.imread(str(tmp_path / "c.pam"), -1))


# ---------------------------------------------------------------- Netpbm: every kind by hand


@pytest.mark.parametrize("maxval", [1, 3, 100, 254, 255])
def test_8bit_maxval_scaled_as_pillow_and_imageio_scale_it(tmp_path: Path, maxval: int) -> None:
    v = RNG.integers(0, maxval + 1, (5, 8)).astype(np.uint8)
    p = tmp_path / f"m{maxval}.pgm"
    p.write_bytes(b"P5\n8 5\n%d\n" % maxval + v.tobytes())
    got = read_image(p)
    assert got.dtype == np.uint8
    assert np.array_equal(got[..., 0], _scaled(v, maxval, 255))
    assert np.array_equal(got, _pillow(p))
    iio = pytest.importorskip("imageio.v3")
    assert np.array_equal(got[..., 0], iio.imread(p))
    assert np.array_equal(got, np.rint(_cv2(p) / maxval * 255))  # OpenCV: stored numbers


@pytest.mark.parametrize("maxval", [256, 1023, 4095, 65534, 65535])
def test_16bit_maxval_scaled_to_uint16(tmp_path: Path, maxval: int) -> None:
    v = RNG.integers(0, maxval + 1, (4, 6, 3)).astype(np.uint16)
    v[0, 0] = maxval
    p = tmp_path / f"m{maxval}.ppm"
    p.write_bytes(b"P6 6 4 %d\n" % maxval + v.astype(">u2").tobytes())
    got = read_image(p)
    assert got.dtype == np.uint16 and got[0, 0, 0] == 65535
    assert np.array_equal(got, _scaled(v, maxval, 65535))
    assert np.array_equal(got, np.rint(_cv2(p).astype(np.float64) / maxval * 65535))
    grey = tmp_path / f"m{maxval}.pgm"
    grey.write_bytes(b"P5 6 4 %d\n" % maxval + v[..., 0].astype(">u2").tobytes())
    assert np.array_equal(read_image(grey), _pillow(grey))  # Pillow's mode I, 0..65535


def test_plain_pgm_ppm_pbm_with_comments(tmp_path: Path) -> None:
    v = RNG.integers(0, 1000, (3, 4, 3))
    rows = "\n".join(" ".join(str(x) for x in r.ravel()) for r in v)
    ppm = tmp_path / "plain.ppm"
    ppm.write_text(f"P3\n# made by hand\n4 3 # size\n999\n{rows}\n")
    assert np.array_equal(read_image(ppm), _scaled(v, 999, 65535))
    assert np.array_equal(read_image(ppm), np.rint(_cv2(ppm) / 999 * 65535))
    pgm = tmp_path / "plain.pgm"
    pgm.write_text("P2 4 3 15\n" + "\n".join(" ".join(str(x % 16) for x in r[:, 0]) for r in v))
    assert np.array_equal(read_image(pgm), _pillow(pgm))
    bits = RNG.integers(0, 2, (5, 11))
    pbm = tmp_path / "plain.pbm"  # plain PBM: whitespace between digits is optional
    pbm.write_text("P1\n11 5\n" + "\n".join("".join(str(b) for b in r) for r in bits) + "\n")
    assert np.array_equal(read_image(pbm)[..., 0], (1 - bits) * 255)  # 1 is black
    assert np.array_equal(read_image(pbm), _pillow(pbm))


def test_raw_pbm_rows_padded_to_a_byte(tmp_path: Path) -> None:
    bits = RNG.integers(0, 2, (6, 13)).astype(bool)
    Image.fromarray(bits).save(tmp_path / "b.pbm")  # Pillow: P4
    assert (tmp_path / "b.pbm").read_bytes()[:2] == b"P4"
    got = read_image(tmp_path / "b.pbm")
    assert np.array_equal(got[..., 0], bits.astype(np.uint8) * 255)
    assert np.array_equal(got, _pillow(tmp_path / "b.pbm"))
    assert np.array_equal(got, _cv2(tmp_path / "b.pbm"))


def test_pam_tuple_types(tmp_path: Path) -> None:
    def pam(name: str, depth: int, maxval: int, tupl: str, v: np.ndarray) -> Path:
        h, w = v.shape[:2]
        head = f"P7\nWIDTH {w}\nHEIGHT {h}\nDEPTH {depth}\nMAXVAL {maxval}\nTUPLTYPE {tupl}\n"
        raster = v.astype(">u2" if maxval > 255 else np.uint8).tobytes()
        (tmp_path / name).write_bytes(head.encode() + b"# c\nENDHDR\n" + raster)
        return tmp_path / name

    rgba = (RNG.random((3, 4, 4)) * 65535).astype(np.uint16)
    rgba[..., 3] = 65535
    p = pam("a.pam", 4, 65535, "RGB_ALPHA", rgba)
    assert np.array_equal(read_image(p), rgba[..., :3])  # opaque alpha dropped
    assert np.array_equal(read_image(p, alpha="keep"), rgba)
    rgba[0, 0, 3] = 0
    p = pam("t.pam", 4, 65535, "RGB_ALPHA", rgba)
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(p)
    bw = RNG.integers(0, 2, (3, 5))
    p = pam("bw.pam", 1, 1, "BLACKANDWHITE", bw)
    assert np.array_equal(read_image(p)[..., 0], bw * 255)  # PAM: 1 is white
    g = RNG.integers(0, 200, (3, 5))
    p = pam("g.pam", 1, 199, "GRAYSCALE", g)
    assert np.array_equal(read_image(p)[..., 0], _scaled(g, 199, 255))
    assert image_info(p).channels == 1
    with pytest.raises(InvalidInputError, match="a PAM of depth 5"):
        read_image(pam("m.pam", 5, 255, "", RNG.integers(0, 9, (2, 2, 5))))


def test_a_pgm_under_another_suffix_is_read_as_what_it_is(tmp_path: Path) -> None:
    p = tmp_path / "depth.png"
    p.write_bytes(b"P5 9 6 65535\n" + GREY16.astype(">u2").tobytes())
    assert np.array_equal(read_image(p)[..., 0], GREY16)


# ---------------------------------------------------------------- Netpbm: bad files


@pytest.mark.parametrize(
    ("data", "said"),
    [
        (b"P5\n8 5\n255\n" + bytes(39), "truncated (39 raster bytes, 40 needed)"),
        (b"P6 2 2 65535\n" + bytes(23), "truncated"),
        (b"P4 9 2\n" + bytes(3), "truncated"),
        (b"P2 2 2 10\n1 2 3", "truncated (3 of 4 samples)"),
        (b"P1 3 1\n0 1", "truncated"),
        (b"P5 2 1 100\n" + bytes([5, 101]), "a sample of 101 above its maxval 100"),
        (b"P5 2 1 0\n\0\0", "maxval 0 outside 1 to 65535"),
        (b"P5 2 1 70000\n\0\0", "maxval 70000"),
        (b"P5 0 1 255\n", "empty"),
        (b"P5 x 1 255\n\0", "corrupt Netpbm header"),
        (b"P5 2", "corrupt Netpbm header"),
        (b"P2 2 1 9\n1 z", "corrupt plain PGM raster"),
        (b"P1 2 1\n02", "not 0 or 1"),
        (b"P7\nWIDTH 2\nHEIGHT 1\n", "no ENDHDR"),
        (b"P7\nWIDTH 2\nENDHDR\n", "WIDTH, HEIGHT, DEPTH and MAXVAL are needed"),
    ],
)
def test_bad_netpbm_files_are_one_line(
    tmp_path: Path, data: bytes, said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    p = tmp_path / "bad.pgm"
    p.write_bytes(data)
    with pytest.raises(InvalidInputError, match=said.replace("(", r"\(").replace(")", r"\)")):
        read_image(p)
    out = tmp_path / "out.tif"
    assert main(["convert", str(p), "--to", "lab", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and sorted(q.name for q in tmp_path.iterdir()) == ["bad.pgm"]


def test_pixel_limit_checked_from_the_header(tmp_path: Path) -> None:
    p = tmp_path / "huge.pgm"
    p.write_bytes(b"P5 100000 100000 255\n" + bytes(10))  # 10 Gpx promised, 10 bytes held
    with pytest.raises(InvalidInputError, match="above the limit"):
        read_image(p)
    assert image_info(p).width == 100000


# ---------------------------------------------------------------- PGM / PPM written


def test_pgm_ppm_written_8_and_16_bits(tmp_path: Path) -> None:
    cv2 = pytest.importorskip("cv2")
    assert write_image(tmp_path / "a.ppm", RGB8).bit_depth == 8
    assert np.array_equal(_cv2(tmp_path / "a.ppm"), RGB8)
    assert np.array_equal(_pillow(tmp_path / "a.ppm"), RGB8)
    assert write_image(tmp_path / "d.pgm", GREY16).bit_depth == 16
    assert np.array_equal(cv2.imread(str(tmp_path / "d.pgm"), cv2.IMREAD_UNCHANGED), GREY16)
    assert write_image(tmp_path / "f.pgm", np.array([[0.0, 0.5, 1.0]]), bit_depth=16) == (16, 0)
    assert read_image(tmp_path / "f.pgm").ravel().tolist() == [0, 32768, 65535]
    with pytest.raises(InvalidInputError, match="PPM holds RGB images, this one is grey; write"):
        write_image(tmp_path / "g.ppm", GREY16)
    with pytest.raises(InvalidInputError, match="PGM holds grey images, this one is RGB; write"):
        write_image(tmp_path / "g.pgm", RGB8)
    with pytest.raises(InvalidInputError, match="Netpbm has no colour profile"):
        write_image(tmp_path / "p.ppm", RGB8, color_space="display_p3")
    for name, kind in (("x.pbm", "PBM"), ("x.pam", "PAM"), ("x.pnm", "PNM")):
        with pytest.raises(InvalidInputError, match=f"reads {kind} but does not write it"):
            write_image(tmp_path / name, RGB8)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["a.ppm", "d.pgm", "f.pgm"]


# ---------------------------------------------------------------- TGA, QOI


def test_tga_and_qoi_read_as_pillow_reads_them(tmp_path: Path) -> None:
    rgba = np.dstack([RGB8, np.full(RGB8.shape[:2], 255, np.uint8)])
    rgba[1, 2, 3] = 10
    for name, arr, kw in (
        ("plain.tga", RGB8, {}),
        ("rle.tga", RGB8, {"compression": "tga_rle"}),
        ("grey.tga", RGB8[..., 0], {}),
        ("a.qoi", RGB8, {}),
        ("alpha.qoi", rgba, {}),
        ("alpha.tga", rgba, {}),
    ):
        Image.fromarray(arr).save(tmp_path / name, **kw)
        got = read_image(tmp_path / name, alpha="keep")
        assert np.array_equal(got, _pillow(tmp_path / name)), name
        assert np.array_equal(got, arr.reshape(got.shape)), name
        assert image_info(tmp_path / name).format == name[-3:]
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(tmp_path / "alpha.qoi")


@pytest.mark.parametrize("name", ["t.tga", "t.qoi"])
def test_truncated_tga_and_qoi_are_one_line(
    tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    full = tmp_path / f"full{name[1:]}"
    Image.fromarray(RGB8).save(full)
    p = tmp_path / name
    p.write_bytes(full.read_bytes()[:30])
    with pytest.raises(InvalidInputError, match=name):
        read_image(p)
    assert main(["info", str(p)]) in (0, 1)  # a TGA's header may still be whole
    assert main(["convert", str(p), "--to", "lab", "-o", str(tmp_path / "o.tif")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "o.tif").exists()


# ---------------------------------------------------------------- the commands


def test_info_and_convert_of_pgm_ppm_tga_qoi(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cv2 = pytest.importorskip("cv2")
    cv2.imwrite(str(tmp_path / "in.ppm"), RGB8[..., ::-1])
    cv2.imwrite(str(tmp_path / "depth.pgm"), GREY16)
    Image.fromarray(RGB8).save(tmp_path / "in.tga")
    Image.fromarray(RGB8).save(tmp_path / "in.qoi")
    for name in ("in.ppm", "in.tga", "in.qoi"):
        out = tmp_path / f"{name}.tif"
        assert main(["convert", str(tmp_path / name), "--to", "lab", "-o", str(out)]) == 0
        assert main(["convert", str(out), "--from", "lab", "--to", "srgb", "-o",
                     str(tmp_path / f"{name}.back.png")]) == 0  # fmt: skip
        back = read_image(tmp_path / f"{name}.back.png")
        assert np.abs(back.astype(int) - RGB8).max() <= 1
        assert main(["info", str(tmp_path / name)]) == 0
    assert main(["info", str(tmp_path / "depth.pgm")]) == 0
    text = capsys.readouterr().out
    assert "depth.pgm: netpbm, 9 x 6 px, 1 channel(s), uint16" in text
    assert "in.qoi: qoi, 7 x 5 px, 3 channel(s), uint8" in text
    out = tmp_path / "out.ppm"
    assert main(["convert", str(tmp_path / "in.tga"), "--to", "srgb", "-o", str(out)]) == 0
    assert np.array_equal(read_image(out), RGB8)
    assert main(["convert", str(tmp_path / "in.tga"), "--to", "display_p3", "-o",
                 str(tmp_path / "p3.ppm")]) == 1  # fmt: skip
    assert "Netpbm has no colour profile to declare display_p3" in capsys.readouterr().err
    assert not (tmp_path / "p3.ppm").exists()


# ---------------------------------------------------------------- BMP ICC profile


def _bmp_v5(rgb: np.ndarray, profile: bytes, *, cs_type: bytes = b"DEBM", cut: int = 0) -> bytes:
    """A 24-bit bottom-up BMP with a BITMAPV5HEADER and its ICC profile after the pixels."""
    h, w, _ = rgb.shape
    stride = (w * 3 + 3) // 4 * 4
    rows = b"".join(rgb[y, :, ::-1].tobytes().ljust(stride, b"\0") for y in range(h - 1, -1, -1))
    profile_at = 124 + len(rows)  # from the V5 header's start
    v5 = struct.pack("<IiiHHIIiiII", 124, w, h, 1, 24, 0, len(rows), 2835, 2835, 0, 0)
    v5 += (
        bytes(16) + cs_type + bytes(36 + 12) + struct.pack("<IIII", 4, profile_at, len(profile), 0)
    )
    assert len(v5) == 124
    body = v5 + rows + profile
    data = b"BM" + struct.pack("<IHHI", 14 + len(body), 0, 0, 14 + 124) + body
    return data[: len(data) - cut] if cut else data


def test_bmp_embedded_icc_profile_is_its_declared_space(tmp_path: Path) -> None:
    from imageform.io.icc import icc_profile

    p3 = tmp_path / "p3.bmp"
    p3.write_bytes(_bmp_v5(RGB8, icc_profile("display_p3")))
    assert image_color_space(p3).name == "display_p3"
    assert image_color_space(p3).source == "icc"
    assert np.array_equal(read_image(p3), RGB8)
    assert np.array_equal(read_image(p3), _pillow(p3))
    assert np.array_equal(read_image(p3), _cv2(p3))
    plain = tmp_path / "srgb.bmp"  # LCS_sRGB: nothing embedded, untagged as before
    plain.write_bytes(_bmp_v5(RGB8, b"", cs_type=b"BGRs"))
    assert image_color_space(plain) == (None, "none", "")
    cut = tmp_path / "cut.bmp"
    cut.write_bytes(_bmp_v5(RGB8, icc_profile("display_p3"), cut=100))
    with pytest.raises(InvalidInputError, match=r"embedded ICC profile .* past the file's end"):
        image_color_space(cut)


def test_convert_from_auto_reads_a_bmp_profile(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.io.icc import icc_profile

    p3 = tmp_path / "p3.bmp"
    p3.write_bytes(_bmp_v5(RGB8, icc_profile("display_p3")))
    out = tmp_path / "o.png"
    assert main(["convert", str(p3), "--to", "srgb", "-o", str(out), "--out-of-range", "clip"]) == 0
    assert "(display_p3) ->" in capsys.readouterr().out
