"""``imageform convert``: files in, files out, errors with exit code 1."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.color import convert
from imageform.io import read_image, write_image


@pytest.fixture
def rgb_png(tmp_path: Path) -> Path:
    a = np.random.default_rng(50).integers(0, 256, (12, 16, 3)).astype(np.uint8)
    write_image(tmp_path / "in.png", a)
    return tmp_path / "in.png"


def test_convert_to_lab_tiff_and_back(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "lab.tif"
    assert (
        main(["convert", str(rgb_png), "-o", str(out), "--from", "srgb", "--to", "lab", "--json"])
        == 0
    )
    payload = json.loads(capsys.readouterr().out)
    assert payload["path"] == ["srgb_to_linear", "linear_srgb_to_xyz", "xyz_to_lab"]
    lab = read_image(out)
    assert lab.dtype == np.float32
    np.testing.assert_allclose(lab, convert(read_image(rgb_png), "srgb", "lab"), atol=1e-4)
    back = tmp_path / "back.png"
    assert (
        main(["convert", str(out), "-o", str(back), "--from", "lab", "--to", "srgb", "--clip"]) == 0
    )
    np.testing.assert_array_equal(read_image(back), read_image(rgb_png))


def test_a_lab_round_trip_stores_every_value_without_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/color-spaces.md's round trip on a photograph: the values float rounding brings
    back a hair outside [0, 1] (-1.7e-7) keep their own codes, so --out-of-range error
    passes, no clip note is printed, and the 16-bit codes are the photograph's x 257 (within
    one code: Lab is stored as float32)."""
    photo = tmp_path / "photo.png"
    rng = np.random.default_rng(3)
    a = rng.integers(0, 256, (64, 64, 3)).astype(np.uint8)
    a[:8] = 0  # black and white, where the round trip strays outside
    a[8:16] = 255
    write_image(photo, a)
    lab, back = tmp_path / "lab.tif", tmp_path / "back.png"
    assert main(["convert", str(photo), "-o", str(lab), "--from", "srgb", "--to", "lab"]) == 0
    lab_values = np.asarray(read_image(lab))
    from imageform.color import convert as _convert

    raw = np.asarray(_convert(lab_values, "lab", "srgb"))
    assert raw.min() < 0 or raw.max() > 1  # the rounding strays the rule is about
    capsys.readouterr()
    args = ["convert", str(lab), "-o", str(back), "--from", "lab", "--to", "srgb"]
    assert main([*args, "--bit-depth", "16", "--out-of-range", "error"]) == 0
    assert "clipped" not in capsys.readouterr().err
    diff = np.abs(read_image(back).astype(np.int64) - a.astype(np.int64) * 257)
    assert diff.max() <= 1


def test_16bit_png_and_ycbcr_params(rgb_png: Path, tmp_path: Path) -> None:
    out = tmp_path / "p3.png"
    assert (
        main(["convert", str(rgb_png), "-o", str(out), "--to", "display_p3", "--bit-depth", "16"])
        == 0
    )
    assert read_image(out).dtype == np.uint16
    ycc = tmp_path / "ycc.npy"
    args = [
        "convert",
        str(rgb_png),
        "-o",
        str(ycc),
        "--to",
        "ycbcr",
        "--standard",
        "bt709",
        "--range",
        "limited",
        "--code-bits",
        "10",
    ]
    assert main(args) == 0
    assert read_image(ycc)[..., 0].min() >= 64 and read_image(ycc)[..., 0].max() <= 940


def test_the_old_bits_flag_still_works_with_a_note(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--bits`` is the deprecated spelling of ``--bit-depth`` (issue 30): hidden, one note."""
    out = tmp_path / "p3.png"
    assert (
        main(["convert", str(rgb_png), "-o", str(out), "--to", "display_p3", "--bits", "16"]) == 0
    )
    assert read_image(out).dtype == np.uint16
    err = capsys.readouterr().err
    assert err.count("--bits is deprecated") == 1 and "use --bit-depth" in err
    assert main(["convert", "--help"]) == 0
    assert "--bits" not in capsys.readouterr().out
    both = ["convert", str(rgb_png), "-o", str(out), "--bits", "16", "--bit-depth", "8"]
    assert main([*both, "--force"]) == 2
    assert "--bit-depth or the deprecated --bits, not both" in capsys.readouterr().err


def test_errors(rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["convert", str(rgb_png), "-o", str(tmp_path / "lab.png"), "--to", "lab"]) == 1
    assert "do not fit an integer image" in capsys.readouterr().err
    assert main(["convert", str(rgb_png), "-o", str(rgb_png), "--to", "hsv"]) == 1
    assert "also an input" in capsys.readouterr().err
    assert main(["convert", str(rgb_png), "-o", str(tmp_path / "x.npy"), "--to", "labx"]) == 2
    assert "valid:" in capsys.readouterr().err  # bad usage: exit 2, the valid names listed
    (tmp_path / "exists.npy").write_bytes(b"")
    assert main(["convert", str(rgb_png), "-o", str(tmp_path / "exists.npy"), "--to", "hsv"]) == 1
    assert "--force" in capsys.readouterr().err
    rgba = tmp_path / "rgba.png"
    write_image(rgba, np.zeros((4, 4, 4), np.uint8))
    assert main(["convert", str(rgba), "-o", str(tmp_path / "a.npy"), "--to", "hsv"]) == 1
    assert "transparent pixels" in capsys.readouterr().err
    assert (
        main(
            ["convert", str(rgba), "-o", str(tmp_path / "a.npy"), "--to", "hsv", "--alpha", "keep"]
        )
        == 0
    )
    assert read_image(tmp_path / "a.npy").shape == (4, 4, 4)


def test_convert_reads_the_space_the_file_declares(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A phone's photograph in Display P3 carries its ICC profile: read as sRGB its
    saturated colours land several dE00 off. ``--from auto`` (the default) reads the
    profile, says so in one note, and ``--from`` still overrides; ``--to display_p3``
    embeds the profile, so the next command reads it back."""
    a = read_image(rgb_png)
    p3 = tmp_path / "p3.png"
    write_image(p3, a, color_space="display_p3")  # the same codes, declared Display P3
    lab = tmp_path / "lab.tif"
    assert main(["convert", str(p3), "-o", str(lab), "--to", "lab", "--json"]) == 0
    out = capsys.readouterr()
    payload = json.loads(out.out)
    assert payload["from"] == "display_p3" and payload["declared"] == "display_p3"
    assert "declares display_p3 in its ICC profile" in out.err
    np.testing.assert_allclose(read_image(lab), convert(a, "display_p3", "lab"), atol=1e-4)
    plain = tmp_path / "plain.tif"
    assert main(["convert", str(p3), "-o", str(plain), "--to", "lab", "--from", "srgb"]) == 0
    assert "declares" not in capsys.readouterr().err
    from imageform.color import delta_e_ciede2000

    de = np.asarray(delta_e_ciede2000(read_image(lab), read_image(plain)))
    assert float(de.max()) > 5.0  # what reading it as sRGB cost
    # the way back: sRGB -> Display P3 (tagged) -> sRGB (read as tagged)
    tagged = tmp_path / "tagged.png"
    assert main(["convert", str(rgb_png), "-o", str(tagged), "--to", "display_p3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["icc_profile_written"] is True
    back = tmp_path / "back.png"
    assert main(["convert", str(tagged), "-o", str(back), "--bit-depth", "8"]) == 0
    diff = np.abs(read_image(back).astype(int) - a.astype(int))
    assert np.median(diff) <= 1


def test_convert_auto_grey_and_unknown_profiles(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from PIL import Image

    grey = tmp_path / "g.png"
    write_image(grey, np.linspace(0, 1, 12).reshape(3, 4))
    assert main(["convert", str(grey), "-o", str(tmp_path / "g.tif"), "--to", "lab"]) == 0
    wide = tmp_path / "wide.jpg"
    profile = Path(__file__).resolve().parents[1] / "data" / "icc" / "WideGamutCompat-v2.icc"
    Image.new("RGB", (4, 4), (200, 30, 40)).save(wide, icc_profile=profile.read_bytes())
    capsys.readouterr()
    assert main(["convert", str(wide), "-o", str(tmp_path / "w.tif"), "--to", "lab"]) == 0
    err = capsys.readouterr().err
    assert "ICC profile imageform does not recognise (AWGC); read as srgb" in err


def test_white_balance_keeps_the_input_s_profile(rgb_png: Path, tmp_path: Path) -> None:
    from imageform.io import image_color_space

    p3 = tmp_path / "p3.png"
    write_image(p3, read_image(rgb_png), color_space="display_p3")
    out = tmp_path / "wb.png"
    assert main(["white-balance", str(p3), "-o", str(out)]) == 0
    assert image_color_space(out).name == "display_p3"
    plain = tmp_path / "wb_plain.png"
    assert main(["white-balance", str(rgb_png), "-o", str(plain)]) == 0
    assert image_color_space(plain).name is None


def test_white_balance_manual_and_percentile_usage(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The docs' manual line without its --cct, or a percentile over 100: usage errors that name
    the command's flags (not 'illuminant= or cct=', the Python keywords), nothing written."""
    out = tmp_path / "wb.png"
    base = ["white-balance", str(rgb_png), "-o", str(out)]
    for extra, needle, code in (
        (["--method", "manual"], "--method manual takes one of --cct KELVIN", 1),
        (["--method", "manual", "--cct", "3200", "--illuminant", "A"], "one of --cct", 1),
        (["--method", "white-patch", "--percentile", "150"], "expected --percentile <= 100", 2),
    ):
        assert main([*base, *extra]) == code, extra
        assert needle in capsys.readouterr().err
    assert not out.exists()
    assert main([*base, "--method", "manual", "--cct", "3200"]) == 0


@pytest.mark.parametrize("name", ["convert", "white-balance", "cvd", "mosaic"])
def test_a_16_bit_jpeg_is_refused_first_by_its_own_name(
    name: str, rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """-o x.jpg --bit-depth 16 named the writer's temporary file ('.x.jpg.123-ab.part.png')."""
    extra = ["--type", "deutan"] if name == "cvd" else []
    out = tmp_path / "x.jpg"
    assert main([name, str(rgb_png), "-o", str(out), "--bit-depth", "16", *extra]) == 1
    err = capsys.readouterr().err
    assert "JPEG holds 8 bits per sample: --bit-depth 16 needs a .png or .tif output" in err
    assert ".part" not in err and not out.exists()


def test_info_says_what_a_file_holds(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from PIL import Image

    p3 = tmp_path / "p3.png"
    write_image(p3, read_image(rgb_png), color_space="display_p3")
    assert main(["info", str(p3), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert (got["format"], got["width"], got["height"], got["channels"], got["dtype"]) == (
        "png", 16, 12, 3, "uint8")  # fmt: skip
    assert (got["color_space"], got["color_space_source"], got["description"]) == (
        "display_p3", "icc", "sP3")  # fmt: skip
    j = tmp_path / "turned.jpg"
    exif = Image.Exif()
    exif[0x0112] = 6
    Image.new("RGB", (8, 4)).save(j, exif=exif)
    assert main(["info", str(j)]) == 0
    out = capsys.readouterr().out
    assert "not declared (read as sRGB)" in out and "EXIF orientation 6" in out
    assert main(["info", str(tmp_path / "missing.png")]) == 1
    assert main(["info", str(tmp_path / "a.txt")]) == 1


def test_chart_reads_a_photograph_in_the_space_it_declares(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ColorChecker photographed and saved in Display P3 (its profile embedded), as a
    phone saves it: its patch means are brought to sRGB before the comparison with the
    chart's sRGB values, so it measures as the sRGB photograph does; read as sRGB it
    measured several dE00 worse."""
    from imageform.analysis import synthetic_chart_photo

    photo = synthetic_chart_photo(rng=1, noise=0.0)
    srgb = np.clip(photo.image, 0, 1)
    a, b = tmp_path / "srgb.png", tmp_path / "p3.png"
    write_image(a, srgb, bit_depth=16)
    p3 = np.clip(np.asarray(convert(srgb, "srgb", "display_p3")), 0, 1)
    write_image(b, p3, bit_depth=16, color_space="display_p3")
    res = {}
    for name, path, extra in (("srgb", a, []), ("p3", b, []), ("as-srgb", b, ["--from", "srgb"])):
        out = tmp_path / f"{name}.json"
        assert main(["chart", str(path), "-o", str(out), "--json", *extra]) == 0
        res[name] = json.loads(capsys.readouterr().out)
    from imageform.color import delta_e_ciede2000

    def means(name: str) -> np.ndarray:
        payload = json.loads((tmp_path / f"{name}.json").read_text())
        return np.asarray(convert(np.asarray(payload["patches"]["means_srgb"]), "srgb", "lab"))

    assert res["p3"]["mean_before"] == pytest.approx(res["srgb"]["mean_before"], abs=0.05)
    same = np.asarray(delta_e_ciede2000(means("srgb"), means("p3")))
    wrong = np.asarray(delta_e_ciede2000(means("srgb"), means("as-srgb")))
    assert same.max() < 0.1 and wrong.mean() > 2.0, (same.max(), wrong.mean())
    assert json.loads((tmp_path / "p3.json").read_text())["image_space"] == "display_p3"


def test_info_of_a_raw_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("rawpy")
    from imageform.io import write_dng

    mosaic = (np.random.default_rng(4).random((16, 24)) * 3000 + 200).astype(np.uint16)
    dng = write_dng(tmp_path / "a.dng", mosaic, black_level=64, white_level=4095,
                    color_matrix=np.eye(3), cfa_pattern="GRBG")  # fmt: skip
    assert main(["info", str(dng), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert (got["format"], got["width"], got["height"], got["cfa_pattern"]) == (
        "raw", 24, 16, "GRBG")  # fmt: skip
    assert got["white_level"] == 4095 and np.allclose(got["black_level"], 64)


@pytest.mark.parametrize("suffix", [".crw", ".kdc", ".raw", ".gpr", ".3fr", ".mrw"])
def test_info_of_older_raw_suffixes(
    suffix: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`info` reads every raw suffix LibRaw reads (a Canon CRW, a Kodak .raw and a GoPro GPR
    of public repositories were 'unknown image file type' while `develop` read them), and
    a file of such a suffix that is no raw gives develop's one line, not the image reader's."""
    pytest.importorskip("rawpy")
    from imageform.io import write_dng

    mosaic = (np.random.default_rng(5).random((16, 24)) * 3000 + 200).astype(np.uint16)
    raw = write_dng(tmp_path / f"a{suffix}", mosaic, black_level=64, white_level=4095,
                    color_matrix=np.eye(3))  # fmt: skip
    assert main(["info", str(raw), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["format"] == "raw"
    junk = tmp_path / f"junk{suffix}"
    junk.write_bytes(b"\x00" * 4096)
    assert main(["info", str(junk)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a raw file LibRaw can read" in err, err


@pytest.mark.parametrize("name", ["photo.png", "photo.jpg", "photo.cr2"])
def test_develop_names_an_ordinary_image(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`develop` of a PNG (under any suffix) says it is a developed image, in one line, and
    writes nothing: it said "not a raw file LibRaw can read (LibRawFileUnsupportedError)"."""
    pytest.importorskip("rawpy")
    from PIL import Image

    src = tmp_path / name
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(src, format="PNG")
    out = tmp_path / "out.png"
    assert main(["develop", str(src), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "it is a PNG image, not a camera raw file" in err, err
    assert not out.exists()
