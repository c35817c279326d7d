"""What a PNG's gAMA/cHRM chunks declare, and CMYK JPEGs read through their ICC profile.

PNG: PngSuite's gamma files (tests/data/pngsuite, file gammas 0.35 to 2.5) and chunks written
here; the transfer by hand from the PNG specification's formula (3rd ed. sec. 13.13: the light a
sample ``V`` means is ``V ** (1 / g)``, ``g`` the gAMA value / 100000) and sRGB's encoding
(IEC 61966-2-1) by colour-science. CMYK: a CMYK JPEG carrying the small CMYK profile of
``benchmarks/_cmyk_icc.py``; peer: LittleCMS through Pillow's ImageCms.
"""

from __future__ import annotations

import io
import json
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from benchmarks._cmyk_icc import cmyk_profile
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import DeclaredColorSpace, icc_profile, image_color_space, read_image

SUITE = Path(__file__).resolve().parents[1] / "data" / "pngsuite"


def _chunk(kind: bytes, body: bytes) -> bytes:
    crc = struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    return struct.pack(">I", len(body)) + kind + body + crc


def _png(*chunks: tuple[bytes, bytes]) -> bytes:
    """A 2 x 2 RGB PNG with ``chunks`` (kind, body) right after IHDR."""
    import imagecodecs

    png = bytes(imagecodecs.png_encode(np.full((2, 2, 3), 128, np.uint8)))
    return png[:33] + b"".join(_chunk(k, b) for k, b in chunks) + png[33:]


def _gama(g: float) -> tuple[bytes, bytes]:
    return b"gAMA", struct.pack(">I", round(g * 100000))


def _chrm(*xy: float) -> tuple[bytes, bytes]:
    return b"cHRM", struct.pack(">8I", *(round(v * 100000) for v in xy))


_P3 = (0.3127, 0.329, 0.68, 0.32, 0.265, 0.69, 0.15, 0.06)
_ADOBE = (0.3127, 0.329, 0.64, 0.33, 0.21, 0.71, 0.15, 0.06)


@pytest.mark.parametrize(
    ("name", "expected", "text"),
    [
        ("g03n2c08", None, "gAMA 0.35, no cHRM (sRGB primaries)"),
        ("g04n2c08", "srgb", "gAMA 0.45, no cHRM (sRGB primaries)"),  # within 5 % of 1/2.2
        ("g05n0g16", None, "gAMA 0.55, no cHRM (sRGB primaries)"),
        ("g10n2c08", "linear_srgb", "gAMA 1, no cHRM (sRGB primaries)"),
        ("g25n2c08", None, "gAMA 2.5, no cHRM (sRGB primaries)"),
        (
            "ccwn2c08",
            "linear_srgb",
            "gAMA 1, cHRM white (0.3127, 0.3290), red (0.6400, 0.3300), green (0.3000, 0.6000), "
            "blue (0.1500, 0.0600)",
        ),
    ],
)
def test_pngsuite_gamma_files_declare_their_gamma(
    name: str, expected: str | None, text: str
) -> None:
    assert image_color_space(SUITE / f"{name}.png") == DeclaredColorSpace(
        expected, "png-gama", text
    )


def test_pngsuite_pixels_stay_as_stored() -> None:
    """read_image never converts: the samples are libpng's (OpenCV's decoding), gAMA aside."""
    import cv2

    for name in ("g03n2c08", "g10n2c08", "g25n2c08"):
        ref = cv2.imread(str(SUITE / f"{name}.png"), cv2.IMREAD_UNCHANGED)[..., ::-1]
        np.testing.assert_array_equal(read_image(SUITE / f"{name}.png"), ref)


def test_gamma_one_converts_as_the_png_formula_says() -> None:
    """g10n2c08 (gAMA 1.0) to sRGB: ``V ** (1 / 1.0)`` encoded by sRGB's curve, by hand."""
    import colour

    from imageform.color import convert

    v = read_image(SUITE / "g10n2c08.png") / 255.0
    space = image_color_space(SUITE / "g10n2c08.png").name
    assert space == "linear_srgb"
    got = np.asarray(convert(v, space, "srgb"))
    gamma = 1.0
    light = v ** (1.0 / gamma)  # PNG 3rd ed. sec. 13.13
    np.testing.assert_allclose(got, colour.models.eotf_inverse_sRGB(light), atol=1e-6)
    # a mid-grey sample 0.5 means half the light: sRGB code 0.7354 (IEC 61966-2-1)
    assert float(np.asarray(convert(np.full((1, 1, 3), 0.5), space, "srgb"))[0, 0, 0]) == (
        pytest.approx(1.055 * 0.5 ** (1 / 2.4) - 0.055, abs=1e-6)
    )


@pytest.mark.parametrize(
    ("chunks", "expected"),
    [
        ((_gama(1 / 2.2),), ("srgb", "png-gama")),
        (
            (_gama(0.45455), _chrm(0.3127, 0.329, 0.64, 0.33, 0.3, 0.6, 0.15, 0.06)),
            ("srgb", "png-gama"),
        ),
        ((_gama(0.45455), _chrm(*_P3)), ("display_p3", "png-gama")),
        ((_gama(256 / 563), _chrm(*_ADOBE)), ("adobe_rgb", "png-gama")),  # Adobe's 563/256
        ((_gama(1.0), _chrm(*_P3)), ("linear_display_p3", "png-gama")),
        ((_chrm(*_P3),), ("display_p3", "png-chrm")),  # no gAMA: sRGB's curve
        ((_gama(0.5),), (None, "png-gama")),  # 10 % from 1/2.2: not sRGB's
        (  # ProPhoto's primaries with D65 and a 2.2 curve: no space of imageform's
            (_gama(0.45455), _chrm(0.3127, 0.329, 0.7347, 0.2653, 0.1596, 0.8404, 0.0366, 0.0001)),
            (None, "png-gama"),
        ),
    ],
)
def test_gama_and_chrm_name_a_space(
    tmp_path: Path, chunks: tuple[tuple[bytes, bytes], ...], expected: tuple[object, str]
) -> None:
    p = tmp_path / "c.png"
    p.write_bytes(_png(*chunks))
    got = image_color_space(p)
    assert (got.name, got.source) == expected


def test_srgb_and_iccp_take_precedence_over_gama(tmp_path: Path) -> None:
    """PNG 3rd ed.: with iCCP or sRGB present, gAMA and cHRM are ignored."""
    p = tmp_path / "s.png"
    p.write_bytes(_png((b"sRGB", b"\0"), _gama(1.0), _chrm(*_P3)))
    assert image_color_space(p) == DeclaredColorSpace("srgb", "png-srgb", "")
    body = b"icc\0\0" + zlib.compress(icc_profile("display_p3"))
    p.write_bytes(_png((b"iCCP", body), _gama(1.0)))
    assert image_color_space(p).name == "display_p3"
    assert image_color_space(p).source == "icc"


@pytest.mark.parametrize(
    "chunks",
    [
        (_gama(0.0),),  # gAMA 0: invalid, ignored as libpng ignores it
        (_chrm(0.3127, 0.0, 0.64, 0.33, 0.3, 0.6, 0.15, 0.06),),  # a zero y: ignored
    ],
)
def test_unusable_chunks_declare_nothing(
    tmp_path: Path, chunks: tuple[tuple[bytes, bytes], ...]
) -> None:
    p = tmp_path / "bad.png"
    p.write_bytes(_png(*chunks))
    assert image_color_space(p) == DeclaredColorSpace(None, "none", "")
    assert read_image(p).shape == (2, 2, 3)


def test_a_short_gama_chunk_is_one_line(tmp_path: Path) -> None:
    p = tmp_path / "short.png"
    p.write_bytes(_png((b"gAMA", b"\0\1")))
    with pytest.raises(InvalidInputError, match=r"cannot read .*short.png: Truncated gAMA chunk$"):
        image_color_space(p)


def test_commands_read_a_gamma_png_as_it_declares(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o.tif"
    assert main(["convert", str(SUITE / "g10n2c08.png"), "-o", str(out), "--to", "lab",
                 "--json"]) == 0  # fmt: skip
    assert json.loads(capsys.readouterr().out)["from"] == "linear_srgb"
    g10 = str(SUITE / "g10n2c08.png")  # its uint8 codes are linear light / 255 (they were refused)
    assert main(["delta-e", g10, g10, "--json"]) == 0
    said = json.loads(capsys.readouterr().out)
    assert (said["spaces"], said["mean"]) == (["linear_srgb", "linear_srgb"], 0.0)
    assert main(["segment", g10, "-o", str(tmp_path / "mask.png")]) == 0
    assert main(["cvd", g10, "--type", "deutan", "-o", str(tmp_path / "cvd.png")]) == 0
    assert main(["convert", str(SUITE / "g03n2c08.png"), "-o", str(out), "--to", "lab",
                 "--force"]) == 0  # fmt: skip
    err = capsys.readouterr().err
    assert "declares gAMA 0.35, no cHRM (sRGB primaries) in its PNG chunks" in err
    assert "read as srgb (--from overrides)" in err
    assert main(["info", str(SUITE / "g25n2c08.png")]) == 0
    assert "PNG chunks no space of imageform matches (gAMA 2.5" in capsys.readouterr().out


# ---------------------------------------------------------------- CMYK JPEG


def _cmyk_jpeg(path: Path, profile: bytes | None) -> np.ndarray:
    """Write flat CMYK patches as a JPEG (Pillow: Adobe's inverted CMYK, APP14); return them."""
    from PIL import Image

    inks = np.array(
        [(255, 0, 0, 0), (0, 255, 0, 0), (0, 0, 255, 0), (0, 0, 0, 128), (64, 128, 192, 32)],
        np.uint8,
    )
    a = np.repeat(np.repeat(inks[None], 16, axis=0), 16, axis=1)  # 16 x 80, 16-px patches
    kw = {"icc_profile": profile} if profile is not None else {}
    Image.fromarray(a, "CMYK").save(path, quality=100, **kw)
    return inks


def test_cmyk_jpeg_with_a_profile_is_converted_through_it(tmp_path: Path) -> None:
    from PIL import Image, ImageCms

    p = tmp_path / "cmyk.jpg"
    profile = cmyk_profile()
    _cmyk_jpeg(p, profile)
    assert b"Adobe" in p.read_bytes()[:2000]  # APP14: the inverted convention
    got = read_image(p)
    with Image.open(p) as im:
        src = ImageCms.ImageCmsProfile(io.BytesIO(profile))
        ref = ImageCms.profileToProfile(im, src, ImageCms.createProfile("sRGB"), outputMode="RGB")
        naive = np.asarray(im.convert("RGB"))
    np.testing.assert_array_equal(got, np.asarray(ref))
    assert int(np.abs(got.astype(int) - naive).max()) > 40  # not the naive conversion
    # the profile's own model by hand: full cyan lets 10 % of red's light through, sRGB code
    # 1.055 * 0.1 ** (1 / 2.4) - 0.055 = 0.3492 (89 of 255); LittleCMS's 3-point grid and
    # perceptual intent within 3 codes
    centre = got[8, 8::16].astype(int)
    assert abs(centre[0, 0] - 89) <= 3 and centre[0, 1] >= 250 and centre[0, 2] >= 250
    assert image_color_space(p) == DeclaredColorSpace(
        "srgb", "icc", "imageform test CMYK (CMYK, read as sRGB)"
    )


def test_cmyk_jpeg_without_a_profile_stays_naive_and_upright(tmp_path: Path) -> None:
    """No profile: ``(1 - C)(1 - K)``; Adobe's inverted inks come back the right way round."""
    p = tmp_path / "plain.jpg"
    inks = _cmyk_jpeg(p, None)
    got = read_image(p)[8, 8::16].astype(float)
    c = inks.astype(float) / 255
    expected = 255 * (1 - c[:, :3]) * (1 - c[:, 3:])
    np.testing.assert_allclose(got, expected, atol=3)  # cyan (0, 255, 255), not red
    assert image_color_space(p) == DeclaredColorSpace(None, "none", "")


def test_cmyk_jpeg_with_a_corrupt_profile_is_one_line(tmp_path: Path) -> None:
    p = tmp_path / "bad.jpg"
    broken = bytearray(cmyk_profile())
    broken[128:132] = struct.pack(">I", 4000)  # a tag table far beyond the profile
    _cmyk_jpeg(p, bytes(broken))
    with pytest.raises(InvalidInputError, match="its CMYK ICC profile cannot be applied"):
        read_image(p)


def test_cmyk_jpeg_with_an_rgb_profile_is_read_naively(tmp_path: Path) -> None:
    """An RGB profile cannot describe CMYK samples: it is ignored by the reader."""
    p = tmp_path / "rgbprof.jpg"
    _cmyk_jpeg(p, icc_profile("display_p3"))
    q = tmp_path / "plain.jpg"
    _cmyk_jpeg(q, None)
    np.testing.assert_array_equal(read_image(p), read_image(q))
