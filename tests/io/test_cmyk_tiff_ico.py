"""CMYK TIFFs read through their embedded CMYK ICC profile; ICO read as its largest image.

CMYK: TIFFs written here by tifffile (8 and 16 bits, with alpha, without a profile) carrying
the small CMYK profile of ``benchmarks/_cmyk_icc.py``; the peer is LittleCMS through Pillow's
ImageCms (``profileToProfile`` to its built-in sRGB, perceptual), the conversion the CMYK JPEG
reader makes. ICO: icons written by Pillow with several sizes; the peer is Pillow's own
reading of the largest entry.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageCms

from benchmarks._cmyk_icc import cmyk_profile
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_color_space, image_info, read_image, write_image

tifffile = pytest.importorskip("tifffile")
RNG = np.random.default_rng(20261130)
INKS = RNG.integers(0, 256, (6, 9, 4)).astype(np.uint8)


def _littlecms(inks: np.ndarray) -> np.ndarray:
    src = ImageCms.ImageCmsProfile(io.BytesIO(cmyk_profile()))
    out = ImageCms.profileToProfile(Image.fromarray(inks, "CMYK"), src,
                                    ImageCms.createProfile("sRGB"), outputMode="RGB")  # fmt: skip
    return np.asarray(out)


def test_cmyk_tiff_with_a_profile_is_srgb_through_it(tmp_path: Path) -> None:
    p = tmp_path / "cmyk.tif"
    tifffile.imwrite(p, INKS, photometric="separated", iccprofile=cmyk_profile())
    want = _littlecms(INKS)
    got = read_image(p)
    np.testing.assert_array_equal(got, want)
    naive = ((255 - INKS[..., :3].astype(int)) * (255 - INKS[..., 3:].astype(int)) / 255).round()
    assert np.abs(got - naive).max() > 10  # the profile, not (1 - C)(1 - K)
    assert image_info(p) == (9, 6, 3, "uint8", "tiff")
    declared = image_color_space(p)
    assert declared.name == "srgb" and "CMYK, read as sRGB" in declared.description


def test_16_bit_cmyk_tiff_and_its_alpha(tmp_path: Path) -> None:
    p = tmp_path / "cmyk16.tif"
    tifffile.imwrite(p, INKS.astype(np.uint16) * 257, photometric="separated",
                     iccprofile=cmyk_profile())  # fmt: skip
    got = read_image(p)
    assert got.dtype == np.uint16
    assert np.abs(got / 257 - _littlecms(INKS)).max() <= 0.5  # 16 bits: within half an 8-bit code
    alpha = np.full((6, 9, 1), 255, np.uint8)
    alpha[0, 0] = 0
    q = tmp_path / "cmyka.tif"
    tifffile.imwrite(q, np.concatenate([INKS, alpha], -1), photometric="separated",
                     extrasamples=["unassalpha"], iccprofile=cmyk_profile())  # fmt: skip
    assert image_info(q).channels == 4
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(q)
    kept = read_image(q, alpha="keep")
    np.testing.assert_array_equal(kept[..., :3], _littlecms(INKS))
    np.testing.assert_array_equal(kept[..., 3], alpha[..., 0])


def test_cmyk_tiff_without_a_profile_is_still_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    p = tmp_path / "bare.tif"
    tifffile.imwrite(p, INKS, photometric="separated")
    with pytest.raises(InvalidInputError, match=r"a CMYK \(separated, no CMYK ICC profile\) TIFF"):
        read_image(p)
    out = tmp_path / "o.png"
    assert main(["convert", str(p), "-o", str(out)]) == 1
    assert capsys.readouterr().err.count("\n") == 1 and not out.exists()
    broken = bytearray(cmyk_profile())
    broken[128:132] = (4000).to_bytes(4, "big")  # a tag table far beyond the profile
    q = tmp_path / "broken.tif"
    tifffile.imwrite(q, INKS, photometric="separated", iccprofile=bytes(broken))
    with pytest.raises(InvalidInputError, match="its CMYK ICC profile cannot be applied"):
        read_image(q)


def test_cli_convert_of_a_cmyk_tiff(tmp_path: Path) -> None:
    p = tmp_path / "cmyk.tif"
    tifffile.imwrite(p, INKS, photometric="separated", iccprofile=cmyk_profile())
    out = tmp_path / "o.png"
    assert main(["convert", str(p), "-o", str(out)]) == 0  # --from auto: srgb, declared
    np.testing.assert_array_equal(read_image(out), _littlecms(INKS))


# ---------------------------------------------------------------- ICO


def test_ico_is_read_as_its_largest_image(tmp_path: Path) -> None:
    big = RNG.integers(0, 256, (48, 48, 4)).astype(np.uint8)
    big[..., 3] = 255
    p = tmp_path / "app.ico"
    Image.fromarray(big, "RGBA").save(p, sizes=[(16, 16), (32, 32), (48, 48)])
    assert image_info(p) == (48, 48, 4, "uint8", "ico")  # the header's RGBA
    got = read_image(p)  # opaque: alpha dropped
    assert got.shape == (48, 48, 3)
    with Image.open(p) as im:
        im.size = (48, 48)  # Pillow's way to pick an entry
        want = np.asarray(im.convert("RGBA"))[..., :3]
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(got, big[..., :3])


def test_ico_with_transparency_follows_the_alpha_rule_and_bad_icons_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rgba = RNG.integers(0, 256, (16, 16, 4)).astype(np.uint8)
    p = tmp_path / "t.ico"
    Image.fromarray(rgba, "RGBA").save(p)
    with pytest.raises(InvalidInputError, match="transparent pixels"):
        read_image(p)
    np.testing.assert_array_equal(read_image(p, alpha="keep"), rgba)
    cut = tmp_path / "cut.ico"
    cut.write_bytes(p.read_bytes()[:30])
    wrong = tmp_path / "wrong.ico"
    wrong.write_bytes(b"not an icon at all" * 4)
    for bad in (cut, wrong):
        with pytest.raises(InvalidInputError) as err:
            read_image(bad)
        assert "\n" not in str(err.value)
        assert main(["info", str(bad)]) == 1
        assert "Traceback" not in capsys.readouterr().err
    with pytest.raises(InvalidInputError, match="reads ICO but does not write it"):
        write_image(tmp_path / "o.ico", rgba)
