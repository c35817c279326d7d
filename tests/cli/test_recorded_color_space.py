"""A TIFF that ``imageform convert`` writes in a space without an ICC profile says which.

``imageform info`` of ``convert --to lab``'s float TIFF said "not declared (read as sRGB)":
Lab has no ICC profile to embed. The space is recorded under ``imageform_color_space`` in the
ImageDescription JSON tifffile writes (``{"shape": [...]}``), which ``image_color_space``,
``info`` and ``--from auto`` read back; any other description declares nothing, as before.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tifffile

from imageform.cli import main
from imageform.color import convert
from imageform.errors import InvalidInputError
from imageform.io import DeclaredColorSpace, image_color_space, read_image, write_image


@pytest.fixture
def rgb_png(tmp_path: Path) -> Path:
    a = np.random.default_rng(7).integers(0, 256, (12, 16, 3)).astype(np.uint8)
    write_image(tmp_path / "in.png", a)
    return tmp_path / "in.png"


def _json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    assert main([*argv, "--json"]) == 0, capsys.readouterr().err
    out: dict[str, Any] = json.loads(capsys.readouterr().out)
    return out


def test_info_names_the_lab_tiff_convert_wrote(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lab = tmp_path / "lab.tif"
    done = _json(["convert", str(rgb_png), "-o", str(lab), "--to", "lab"], capsys)
    assert done["color_space_recorded"] is True and done["icc_profile_written"] is False
    with tifffile.TiffFile(lab) as tif:  # tifffile's own JSON, with one key more
        assert tif.shaped_metadata == ({"shape": [12, 16, 3], "imageform_color_space": "lab"},)
        assert 34675 not in tif.pages.first.tags  # no ICC profile
    info = _json(["info", str(lab)], capsys)
    assert (info["color_space"], info["color_space_source"]) == ("lab", "tiff-description")
    assert main(["info", str(lab)]) == 0
    text = capsys.readouterr().out
    assert "colour space: lab (recorded by imageform in the TIFF's description)" in text
    assert "not declared" not in text
    assert image_color_space(lab) == DeclaredColorSpace("lab", "tiff-description", "")
    # the values are what they were: Lab, float32
    np.testing.assert_allclose(
        read_image(lab), convert(read_image(rgb_png), "srgb", "lab"), atol=1e-4
    )


def test_from_auto_reads_the_recorded_space_back(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The docs' round trip without ``--from lab``, on a Kodak photograph: every code back."""
    src = shared_data / "kodak" / "kodim23.png"
    lab, back = tmp_path / "lab.tif", tmp_path / "back.png"
    assert main(["convert", str(src), "-o", str(lab), "--from", "srgb", "--to", "lab"]) == 0
    capsys.readouterr()
    assert main(["convert", str(lab), "-o", str(back), "--to", "srgb", "--json"]) == 0
    out, err = capsys.readouterr()
    assert (json.loads(out)["from"], json.loads(out)["declared"]) == ("lab", "lab")
    assert "declares lab in its TIFF description (written by imageform)" in err
    assert np.array_equal(read_image(back), read_image(src))


@pytest.mark.parametrize(("space", "recorded"), [("xyz", "xyz"), ("hsv", "hsv")])
def test_other_spaces_without_a_profile_are_recorded(
    space: str, recorded: str, rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"{space}.tif"
    assert _json(["convert", str(rgb_png), "-o", str(out), "--to", space], capsys)[
        "color_space_recorded"
    ]
    assert image_color_space(out).name == recorded


def test_rgb_outputs_are_unchanged(
    rgb_png: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A wide RGB space still carries its ICC profile alone; sRGB and ``.npy`` carry nothing."""
    p3 = tmp_path / "p3.tif"
    done = _json(["convert", str(rgb_png), "-o", str(p3), "--to", "display-p3"], capsys)
    assert done["icc_profile_written"] is True and done["color_space_recorded"] is False
    assert image_color_space(p3).source == "icc"
    with tifffile.TiffFile(p3) as tif:
        assert tif.shaped_metadata == ({"shape": [12, 16, 3]},)
    srgb = tmp_path / "s.tif"
    done = _json(["convert", str(rgb_png), "-o", str(srgb), "--to", "srgb"], capsys)
    assert not done["icc_profile_written"] and not done["color_space_recorded"]
    assert image_color_space(srgb) == DeclaredColorSpace(None, "none", "")
    npy = tmp_path / "lab.npy"
    assert not _json(["convert", str(rgb_png), "-o", str(npy), "--to", "lab"], capsys)[
        "color_space_recorded"
    ]


@pytest.mark.parametrize(
    "description",
    [
        '{"shape": [4, 5, 3]}',  # tifffile's own
        '{"color_space": "lab"}',  # another program's key
        '{"imageform_color_space": "not-a-space"}',
        '{"imageform_color_space": 3}',
        '["imageform_color_space", "lab"]',
        "imageform_color_space: lab",  # text
        '<?xml version="1.0"?><OME imageform_color_space="lab"/>',
        '{"imageform_color_space": "lab"',  # cut short
    ],
)
def test_other_descriptions_declare_nothing(description: str, tmp_path: Path) -> None:
    p = tmp_path / "other.tif"
    a = np.zeros((4, 5, 3), np.float32)
    tifffile.imwrite(p, a, photometric="rgb", description=description, metadata=None)
    assert image_color_space(p) == DeclaredColorSpace(None, "none", "")
    assert main(["info", str(p)]) == 0


def test_an_icc_profile_comes_first(tmp_path: Path) -> None:
    from imageform.io import icc_profile

    p = tmp_path / "both.tif"
    tifffile.imwrite(
        p,
        np.zeros((4, 5, 3), np.float32),
        photometric="rgb",
        iccprofile=icc_profile("display_p3"),
        metadata={"imageform_color_space": "lab"},
    )
    assert image_color_space(p).name == "display_p3"


def test_write_image_records_for_tiff_and_refuses_for_png(tmp_path: Path) -> None:
    xyz = np.full((2, 3, 3), 0.4, np.float32)
    write_image(tmp_path / "x.tif", xyz, color_space="XYZ")
    assert image_color_space(tmp_path / "x.tif").name == "xyz"
    write_image(tmp_path / "lin.tif", xyz, color_space="linear_rec2020")
    assert image_color_space(tmp_path / "lin.tif").name == "linear_rec2020"
    with pytest.raises(InvalidInputError):
        write_image(tmp_path / "x.png", xyz, color_space="lab")
    assert not (tmp_path / "x.png").exists()
    with pytest.raises(InvalidInputError, match="color_space"):
        write_image(tmp_path / "y.tif", xyz, color_space="labx")
