"""``imageform white-balance``: a bad value is named by the flag the user typed.

The command line said "expected Minkowski p >= 1, got 0.5" for ``--p 0.5``, "CCT 100 K
outside the range of the robertson1968 method" for ``--cct 100`` and "illuminant: unknown
white 'Q' for illuminant; valid: ..., (x, y) or (X, Y, Z)" for ``--illuminant Q`` (exit 1,
after reading the image): the library's words. The options now carry the library's bounds,
so the command refuses such a value first, as a usage error naming ``--p``, ``--sigma``,
``--cct`` or ``--illuminant`` (exit 2; ``imageform batch`` and ``imageform chunked`` alike);
the library keeps its own parameter names.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.workflows.color import WhiteBalanceOptions

ILLUMINANTS = (
    "A, B, C, D50, D55, D65, D75, E, F2, F7, F11, srgb, rec709, adobe_rgb, display_p3, "
    "rec2020, prophoto"
)


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--method", "shades-of-gray", "--p", "0.5"], "expected --p >= 1, got 0.5"),
        (["--method", "shades-of-gray", "--p", "1e9"], "expected --p <= 10000, got 1e+09"),
        (["--method", "gray-edge", "--sigma", "-1"], "expected --sigma >= 0, got -1"),
        (["--method", "grayness-index", "--sigma", "2000"], "expected --sigma <= 1000, got 2000"),
        (["--method", "manual", "--cct", "100"], "expected --cct >= 1666.67, got 100"),
        (
            ["--method", "manual", "--illuminant", "Q"],
            f"unknown --illuminant 'Q'; valid: an illuminant or RGB space name ({ILLUMINANTS})",
        ),
        (["--method", "white-patch", "--percentile", "150"], "expected --percentile <= 100"),
        (
            ["--method", "pca", "--percentile", "80"],
            "expected --percentile in (0, 50] for --method pca",
        ),
    ],
)
@pytest.mark.parametrize("how", ["single", "batch", "chunked"])
def test_a_bad_value_names_its_flag(
    extra: list[str], words: str, how: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if how == "chunked" and "--percentile" in extra:
        pytest.skip("chunked processing takes no --percentile (no white patch)")
    if how == "chunked" and "--sigma" in extra:
        pytest.skip("chunked processing takes no --sigma (no grey edge)")
    out = tmp_path / ("out" if how == "batch" else "o.png")
    head = {"single": [], "batch": ["batch"], "chunked": ["chunked"]}[how]
    given = f"{tmp_path}/*.png" if how == "batch" else str(tmp_path / "in.tif")
    # the input does not exist: the options are refused before it is looked at
    assert main([*head, "white-balance", given, "-o", str(out), *extra]) == 2
    command = " ".join(["imageform", *head, "white-balance"])
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"{command}: error: {words}"), line
    assert not out.exists()


def test_the_library_keeps_its_own_names() -> None:
    from imageform.color import white_balance

    img = np.full((4, 4, 3), 0.5)
    with pytest.raises(InvalidInputError, match=r"^expected Minkowski p >= 1, got 0.5$"):
        white_balance(img, "shades_of_gray", p=0.5)
    with pytest.raises(InvalidInputError, match=r"^unknown white 'Q' for illuminant; valid: "):
        white_balance(img, "manual", illuminant="Q")  # was "illuminant: unknown ... illuminant"
    with pytest.raises(InvalidInputError, match="CCT 100 K outside the range"):
        white_balance(img, "manual", cct=100.0)


def _bounds(name: str) -> tuple[float | None, float | None]:
    (f,) = [f for f in dataclasses.fields(WhiteBalanceOptions) if f.name == name]
    return f.metadata["minimum"], f.metadata["maximum"]


def test_the_options_bounds_are_the_library_s() -> None:
    """The command refuses exactly what the library refuses: no value is refused by one and
    taken by the other."""
    from imageform.color import cct_to_xy, white_balance
    from imageform.color.white_balance import MAX_MINKOWSKI_P, MAX_SIGMA

    assert _bounds("p") == (1.0, MAX_MINKOWSKI_P)
    assert _bounds("sigma") == (0.0, MAX_SIGMA)
    lowest, top = _bounds("cct")
    assert top is None and lowest is not None
    cct_to_xy(lowest)  # Robertson's lowest line, 600 mired, is taken
    with pytest.raises(InvalidInputError, match="outside the range"):
        cct_to_xy(np.nextafter(lowest, 0.0))
    img = np.full((4, 4, 3), 0.5)
    white_balance(img, "gray_world", p=MAX_MINKOWSKI_P, sigma=MAX_SIGMA)  # both checked
    assert WhiteBalanceOptions(p=MAX_MINKOWSKI_P, sigma=MAX_SIGMA, cct=lowest).cct == lowest


@pytest.mark.parametrize("name", ["D50", "d65", "F11", "display-p3", "ProPhoto"])
def test_every_listed_illuminant_is_taken(name: str) -> None:
    assert WhiteBalanceOptions(method="manual", illuminant=name).illuminant == name


def test_chunked_help_names_only_what_it_streams(capsys: pytest.CaptureFixture[str]) -> None:
    """``chunked white-balance --p`` is shades-of-gray's alone (gray-edge is not streamed)."""
    assert main(["chunked", "white-balance", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "--p FLOAT shades-of-gray: Minkowski norm p" in text
    assert "gray-edge" not in text


@pytest.mark.parametrize("how", ["single", "chunked"])
def test_a_white_outside_the_gamut_is_said(
    how: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """1666.67 K is Robertson's lowest white but lies outside sRGB: one line says so and where
    sRGB's whites begin (it said the image's estimate had an empty channel)."""
    import tifffile

    src = tmp_path / "in.tif"
    tifffile.imwrite(src, np.full((8, 8, 3), 128, np.uint8), photometric="rgb")
    out = tmp_path / "o.tif"
    head = ["chunked"] if how == "chunked" else []
    args = [*head, "white-balance", str(src), "-o", str(out), "--method", "manual"]
    assert main([*args, "--cct", "1666.67"]) == 1
    (line,) = capsys.readouterr().err.splitlines()
    assert "1666.67 K lies outside srgb's gamut" in line and "from 1900 K" in line, line
    assert not out.exists()
    assert main([*args, "--cct", "1900"]) == 0


def _clipped_photo(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """A grey world tinted 0.5/0.4/0.3 in linear light with two clipped highlights."""
    from imageform.color import convert
    from imageform.io import write_image

    rng = np.random.default_rng(2)
    lin = rng.random((128, 128, 3)) * [0.5, 0.4, 0.3]
    lin[:40, :40] = [1.0, 1.0, 0.9]
    lin[100:, 100:] = 1.0
    img = (np.clip(convert(lin, "linear_srgb", "srgb"), 0, 1) * 255).round().astype(np.uint8)
    path = tmp_path / "clip.png"
    write_image(path, img)
    return path, lin


def _gains(capsys: pytest.CaptureFixture[str]) -> np.ndarray:
    import json

    return np.asarray(json.loads(capsys.readouterr().out)["gains"])


def test_mask_leaves_the_clipped_highlights_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--mask unclipped and a mask image give the light of the kept pixels (the tint's
    0.8/1/1.33 gains); without a mask the highlights pull the gains towards white."""
    from imageform.io import write_image

    src, _ = _clipped_photo(tmp_path)
    out = tmp_path / "o.png"
    args = ["white-balance", str(src), "-o", str(out), "--json", "--force"]
    truth = np.array([0.5, 0.4, 0.3]).mean() / np.array([0.5, 0.4, 0.3])
    assert main(args) == 0
    plain = _gains(capsys)
    assert main([*args, "--mask", "unclipped"]) == 0
    unclipped = _gains(capsys)
    np.testing.assert_allclose(unclipped, truth, rtol=0.01)
    assert np.abs(plain - truth).max() > 5 * np.abs(unclipped - truth).max()
    m = np.zeros((128, 128), np.uint8)
    m[40:100, :] = 255  # rows holding no highlight
    write_image(tmp_path / "m.png", m)
    assert main([*args, "--mask", str(tmp_path / "m.png")]) == 0
    np.testing.assert_allclose(_gains(capsys), truth, rtol=0.02)  # 7680 noisy 8-bit pixels
    assert main([*args, "--mask", "FOV"]) == 0  # no black surround: about every pixel
    capsys.readouterr()


@pytest.mark.parametrize(
    ("extra", "code", "words"),
    [
        (["--mask", "nope.png"], 1, "--mask nope.png is no file"),
        (["--method", "manual", "--cct", "3000", "--mask", "unclipped"], 2, "--mask goes with"),
        (["--method", "chart", "--mask", "fov"], 2, "--mask goes with"),
    ],
)
def test_bad_masks(
    extra: list[str], code: int, words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.io import write_image

    src, _ = _clipped_photo(tmp_path)
    out = tmp_path / "o.png"
    assert main(["white-balance", str(src), "-o", str(out), *extra]) == code
    (line,) = capsys.readouterr().err.splitlines()
    assert words in line, line
    assert not out.exists()
    small = tmp_path / "small.png"
    write_image(small, np.full((8, 8), 255, np.uint8))
    assert main(["white-balance", str(src), "-o", str(out), "--mask", str(small)]) == 1
    assert "is 8 x 8 px, the image 128 x 128 px" in capsys.readouterr().err


def test_chart_method_reads_the_files_own_space(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--method chart`` on an Adobe RGB file decodes the patches with Adobe RGB's curve and
    keeps the profile (it decoded them as sRGB: gains 0.7746/1.4028 for 0.7778/1.4); a
    ``--chart`` file in another space is refused, nothing written."""
    import json

    from imageform.analysis import synthetic_chart_photo
    from imageform.color import convert, encode
    from imageform.io import image_color_space, write_image

    photo = synthetic_chart_photo(cast=(1.0, 1.0, 1.0), shading=0.0, noise=0.0, rng=3).image
    cast = np.array([0.9, 0.7, 0.5])
    lin = np.clip(np.asarray(convert(photo, "srgb", "linear_adobe_rgb")) * cast, 0, 1)
    src = tmp_path / "adobe.tif"
    write_image(src, np.asarray(encode(lin, "adobe_rgb"), np.float32), color_space="adobe_rgb")
    out = tmp_path / "out.tif"
    assert main(["white-balance", str(src), "--method", "chart", "-o", str(out), "--json"]) == 0
    gains = np.array(json.loads(capsys.readouterr().out)["gains"])
    np.testing.assert_allclose(gains / gains[1], cast[1] / cast, rtol=2e-3)
    assert image_color_space(out).name == "adobe_rgb"
    other = tmp_path / "srgb.png"
    write_image(other, photo)
    bad = tmp_path / "bad.tif"
    args = ["white-balance", str(src), "--method", "chart", "--chart", str(other)]
    assert main([*args, "-o", str(bad)]) == 1
    err = capsys.readouterr().err.strip()
    assert "declares srgb, IMAGE declares adobe_rgb: convert one" in err
    assert len(err.splitlines()) == 1 and not bad.exists()
