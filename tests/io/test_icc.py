"""Tests of imageform.io.icc: ICC profiles read, named and embedded.

Profiles: the shipped ones (src/imageform/io/data/icc) and public-domain variants in
tests/data/icc (version 2 and 4, "compatible" profiles with a nudged red primary and
adjusted ``chad``, grey, DCI-P3, Wide Gamut). Peer: littleCMS through Pillow's ImageCms.
"""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import (
    DeclaredColorSpace,
    icc_profile,
    identify_icc,
    image_color_space,
    parse_icc,
    read_image,
    write_image,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "icc"

_EXPECTED = {
    "sRGB-v4.icc": "srgb",
    "sRGB-v2-micro.icc": "srgb",
    "sRGB-v2-nano.icc": "srgb",
    "DisplayP3-v4.icc": "display_p3",
    "DisplayP3Compat-v2-magic.icc": "display_p3",
    "DisplayP3Compat-v4.icc": "display_p3",
    "AdobeCompat-v4.icc": "adobe_rgb",
    "ProPhoto-v4.icc": "prophoto",
    "Rec2020-v4.icc": "rec2020",
    "Rec2020Compat-v2-magic.icc": "rec2020",
    "Rec709-v4.icc": "rec709",
    "DCI-P3-v4.icc": None,  # P3 primaries, the theatre white and gamma 2.6: not Display P3
    "WideGamutCompat-v2.icc": None,  # Adobe Wide Gamut RGB: not a space of imageform
    "sGrey-v4.icc": None,  # a grey profile
}


@pytest.mark.parametrize("name", sorted(_EXPECTED))
def test_profiles_are_named(name: str) -> None:
    prof = parse_icc((DATA / name).read_bytes())
    assert identify_icc(prof) == _EXPECTED[name]


@pytest.mark.parametrize(
    "space", ["srgb", "display_p3", "adobe_rgb", "prophoto", "rec2020", "rec709", "linear_srgb"]
)
def test_shipped_profiles_name_their_space(space: str) -> None:
    assert identify_icc(parse_icc(icc_profile(space))) == space


def test_profile_values_against_the_standards() -> None:
    """Native primaries and white of the version 4 profiles, after their ``chad``: the
    standards' chromaticities (IEC 61966-2-1, SMPTE EG 432-1, Adobe RGB (1998), ROMM,
    BT.2020) to 4 decimals; the sRGB curve's parameters of IEC 61966-2-1."""
    p3 = parse_icc((DATA / "DisplayP3-v4.icc").read_bytes())
    assert p3.version == (4, 2) and p3.color_space == "RGB" and p3.description == "sP3"
    np.testing.assert_allclose(p3.primaries_xy, [[0.68, 0.32], [0.265, 0.69], [0.15, 0.06]],
                               atol=2e-4)  # fmt: skip
    np.testing.assert_allclose(p3.white_xy, [0.3127, 0.3290], atol=2e-4)
    romm = parse_icc((DATA / "ProPhoto-v4.icc").read_bytes())
    np.testing.assert_allclose(romm.white_xy, [0.3457, 0.3585], atol=2e-4)
    np.testing.assert_allclose(romm.primaries_xy[0], [0.7347, 0.2653], atol=2e-4)
    srgb = parse_icc((DATA / "sRGB-v4.icc").read_bytes())
    x = np.array([0.0, 0.04045, 0.5, 1.0])
    want = np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)
    for curve in srgb.curves:  # type: ignore[union-attr]
        np.testing.assert_allclose(curve(x), want, atol=2e-5)  # type: ignore[operator]


@pytest.mark.parametrize("space", ["display_p3", "adobe_rgb", "rec2020"])
def test_embedded_profiles_agree_with_littlecms(space: str) -> None:
    """littleCMS (Pillow's ImageCms) converting through the embedded profile to sRGB
    (relative colorimetric) and imageform's ``convert`` agree within one 8-bit code
    value on every colour inside sRGB's gamut (spaces with sRGB's white: no adaptation)."""
    from PIL import Image, ImageCms

    from imageform.color import convert

    a = (np.random.default_rng(0).random((48, 48, 3)) * 255).astype(np.uint8)
    src = ImageCms.ImageCmsProfile(io.BytesIO(icc_profile(space)))
    t = ImageCms.buildTransform(src, ImageCms.createProfile("sRGB"), "RGB", "RGB")
    lcms = np.asarray(ImageCms.applyTransform(Image.fromarray(a), t)).astype(float)
    ours = np.asarray(convert(a / 255.0, space, "srgb"))
    inside = np.all((ours > 0) & (ours < 1), axis=-1)
    assert inside.mean() > 0.3
    diff = np.abs(np.round(ours * 255) - lcms)[inside]
    assert diff.max() <= 1 and diff.mean() < 0.05


def test_prophoto_agrees_with_littlecms_after_bradford() -> None:
    """ProPhoto's white is D50: littleCMS's relative colorimetric intent adapts it to
    sRGB's D65 (Bradford, as ICC.1 annex E); imageform joins spaces without adaptation
    (docs/color-spaces.md), so the peer check adapts explicitly."""
    from PIL import Image, ImageCms

    from imageform.color import chromatic_adaptation, convert, rgb_space

    a = (np.random.default_rng(1).random((48, 48, 3)) * 255).astype(np.uint8)
    src = ImageCms.ImageCmsProfile(io.BytesIO(icc_profile("prophoto")))
    t = ImageCms.buildTransform(src, ImageCms.createProfile("sRGB"), "RGB", "RGB")
    lcms = np.asarray(ImageCms.applyTransform(Image.fromarray(a), t)).astype(float)
    xyz = np.asarray(convert(a / 255.0, "prophoto", "xyz"))
    d50, d65 = rgb_space("prophoto").white_xy, rgb_space("srgb").white_xy
    ours = np.asarray(convert(chromatic_adaptation(xyz, d50, d65), "xyz", "srgb"))
    inside = np.all((ours > 0) & (ours < 1), axis=-1)
    diff = np.abs(np.round(ours * 255) - lcms)[inside]
    assert inside.mean() > 0.1 and diff.max() <= 2 and diff.mean() < 0.3


@pytest.mark.parametrize("suffix", ["png", "jpg", "tif"])
@pytest.mark.parametrize("space", ["display_p3", "adobe_rgb", "prophoto", "linear_srgb"])
def test_written_images_declare_their_space(tmp_path: Path, suffix: str, space: str) -> None:
    a = np.random.default_rng(2).random((6, 7, 3))
    p = tmp_path / f"a.{suffix}"
    write_image(p, a, color_space=space, bit_depth=16 if suffix == "tif" else None)
    got = image_color_space(p)
    assert got.name == space and got.source == "icc"
    back = read_image(p)
    assert back.shape == (6, 7, 3)
    if suffix == "png":  # the pixels are untouched by the chunk
        np.testing.assert_array_equal(back, np.round(a * 255).astype(np.uint8))


def test_srgb_and_grey_write_no_profile(tmp_path: Path) -> None:
    p = tmp_path / "a.png"
    write_image(p, np.full((2, 2, 3), 0.5), color_space="srgb")
    assert image_color_space(p) == DeclaredColorSpace(None, "none", "")
    g = tmp_path / "g.png"
    write_image(g, np.full((2, 2), 0.5), color_space="display_p3")  # grey: no RGB profile
    assert image_color_space(g).name is None


def test_png_srgb_chunk_and_exif(tmp_path: Path) -> None:
    from PIL import Image

    p = tmp_path / "s.png"
    p.write_bytes(_png_with_chunk(b"sRGB", b"\x00"))  # rendering intent 0
    assert image_color_space(p) == DeclaredColorSpace("srgb", "png-srgb", "")
    j = tmp_path / "a.jpg"
    exif = Image.Exif()  # a camera JPEG in Adobe RGB mode: uncalibrated + DCF index R03
    exif.get_ifd(0x8769).update({0xA001: 0xFFFF, 0xA005: {0x0001: "R03"}})
    Image.new("RGB", (4, 4)).save(j, exif=exif)
    assert image_color_space(j) == DeclaredColorSpace("adobe_rgb", "exif", "")
    exif = Image.Exif()
    exif.get_ifd(0x8769)[0xA001] = 1
    Image.new("RGB", (4, 4)).save(j, exif=exif)
    assert image_color_space(j) == DeclaredColorSpace("srgb", "exif", "")


def _png_with_chunk(kind: bytes, body: bytes) -> bytes:
    import zlib

    import imagecodecs

    png = imagecodecs.png_encode(np.zeros((2, 2, 3), np.uint8))
    chunk = struct.pack(">I", len(body)) + kind + body
    chunk += struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    return png[:33] + chunk + png[33:]


def test_unknown_profile_keeps_its_description(tmp_path: Path) -> None:
    from PIL import Image

    j = tmp_path / "w.jpg"
    Image.new("RGB", (4, 4)).save(j, icc_profile=(DATA / "WideGamutCompat-v2.icc").read_bytes())
    assert image_color_space(j) == DeclaredColorSpace(None, "icc", "AWGC")


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (b"", "not an ICC profile"),
        (b"\0" * 200, "not an ICC profile"),
        ("text", "as bytes"),
    ],
)
def test_bad_profiles(data: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        parse_icc(data)  # type: ignore[arg-type]


def test_truncated_profile_is_one_error() -> None:
    good = icc_profile("display_p3")
    with pytest.raises(InvalidInputError, match="ICC profile"):
        parse_icc(good[:200])


def test_bad_arguments() -> None:
    with pytest.raises(InvalidInputError, match="no ICC profile is shipped for lab"):
        icc_profile("lab")
    with pytest.raises(InvalidInputError, match="expected profile, an IccProfile"):
        identify_icc("srgb")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="no such file"):
        image_color_space("/nonexistent/x.png")


def test_npy_declares_nothing(tmp_path: Path) -> None:
    p = tmp_path / "a.npy"
    np.save(p, np.zeros((2, 2, 3)))
    assert image_color_space(p) == DeclaredColorSpace(None, "none", "")


def test_encoded_space_names_the_profile_of_a_development() -> None:
    from imageform.io.icc import encoded_space

    assert encoded_space("display_p3", "srgb") == "display_p3"
    assert encoded_space("prophoto", "prophoto") == "prophoto"
    assert encoded_space("srgb", "rec709") == "rec709"  # LibRaw's default output
    assert encoded_space("srgb", "linear") == "linear_srgb"
    assert encoded_space("display_p3", "linear") is None  # no shipped linear P3 profile
    assert encoded_space("prophoto", "srgb") is None


@pytest.mark.parametrize(
    ("args", "want"),
    [
        ([], None),
        (["--space", "display-p3"], "display_p3"),
        (["--space", "prophoto"], "prophoto"),
        (["--transfer", "rec709"], "rec709"),
    ],
)
def test_develop_tags_its_output(tmp_path: Path, args: list[str], want: str | None) -> None:
    """A raw developed into Display P3 or ProPhoto was written untagged: every viewer (and
    the next imageform command) took it for sRGB."""
    pytest.importorskip("rawpy")
    from imageform.cli import main
    from imageform.io import write_dng

    rng = np.random.default_rng(3)
    mosaic = (rng.random((32, 48)) * 3000 + 200).astype(np.uint16)
    dng = write_dng(tmp_path / "a.dng", mosaic, white_level=4095, color_matrix=np.eye(3))
    out = tmp_path / "a.png"
    assert main(["develop", str(dng), "-o", str(out), *args]) == 0
    assert image_color_space(out).name == want
