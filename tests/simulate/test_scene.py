"""Scene description: schema validation (errors name the key and the line), loading, examples."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.simulate import SCENE_SCHEMA, Scene, default_scene, load_scene
from imageform.simulate.schema import Field
from imageform.simulate.validation import find_line

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples" / "scenes").glob("*.toml"))
DEFAULT_TOML = ROOT / "src" / "imageform" / "simulate" / "scenes" / "default.toml"

GOOD = """name = "t"
[render]
width = 64
height = 48

[camera]
focal_length_mm = 1.0

[[objects]]
type = "plane"
center_m = [0.0, 0.0, 0.0]

[[objects]]
type = "checkerboard"
center_m = [0.0, 0.0, 0.0]
squares = [6, 4]
"""


def test_load_string_dict_and_path_agree(tmp_path: Path) -> None:
    p = tmp_path / "s.toml"
    p.write_text(GOOD)
    a, b = load_scene(GOOD), load_scene(p)
    import tomllib

    c = load_scene(tomllib.loads(GOOD))
    for s in (a, b, c):
        assert isinstance(s, Scene) and s.image_size == (64, 48)
        assert [o.kind for o in s.objects] == ["plane", "checkerboard"]
    np.testing.assert_array_equal(a.objects[1].corners, c.objects[1].corners)
    assert load_scene(str(p)).name == "t"


def test_unknown_key_names_the_key_and_its_line() -> None:
    bad = GOOD.replace("squares = [6, 4]", "squares = [6, 4]\nsquare_sise_m = 0.01")
    with pytest.raises(
        UnknownOptionError,
        match=r"objects\[1\]\.square_sise_m .*line 17.*"
        r"did you mean 'square_size_m'",
    ):
        load_scene(bad)


def test_unknown_section_key_line() -> None:
    bad = GOOD.replace("focal_length_mm = 1.0", "focal_length_mm = 1.0\nfocal = 2")
    with pytest.raises(UnknownOptionError, match=r"camera\.focal .*line 8"):
        load_scene(bad)


def test_wrong_unit_in_the_key_name() -> None:
    bad = GOOD.replace("focal_length_mm = 1.0", "focal_length_m = 0.001")
    with pytest.raises(
        UnknownOptionError,
        match=r"line 7.*wrong unit\? this key is "
        r"'focal_length_mm'",
    ):
        load_scene(bad)


def test_unit_strings_convert_and_wrong_units_are_named() -> None:
    s = load_scene(GOOD.replace("focal_length_mm = 1.0", 'focal_length_mm = "1500 um"'))
    assert s.config.camera.focal_length_mm == pytest.approx(1.5)
    s = load_scene(GOOD + '\n[sensor]\nexposure_time_s = "10 ms"\n')
    assert s.config.sensor.exposure_time_s == pytest.approx(0.01)
    with pytest.raises(
        InvalidInputError,
        match=r"camera\.focal_length_mm .*line 7.*expected a "
        r"length.*got unit 'ms' \(a time\)",
    ):
        load_scene(GOOD.replace("focal_length_mm = 1.0", 'focal_length_mm = "2 ms"'))


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("width = 64", 'width = "64"', r"render\.width .*line 3.*expected an integer"),
        ("width = 64", "width = 0", r"render\.width .*expected a value >= 2"),
        ('type = "plane"', 'type = "sphere"', r"objects\[0\]\.type .*valid: checkerboard"),
        ("squares = [6, 4]", "squares = [6]", r"squares .*expected a list of 2"),
        ("focal_length_mm = 1.0", "focal_length_mm = -1.0", r"expected a value > 0"),
        ("focal_length_mm = 1.0", "focal_length_mm = true", r"expected a number"),
    ],
)
def test_bad_values(old: str, new: str, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        load_scene(GOOD.replace(old, new))


def test_bad_choices_list_the_valid_ones() -> None:
    with pytest.raises(UnknownOptionError, match=r"processing\.demosaic .*valid: .*menon"):
        load_scene({"processing": {"demosaic": "magic"}})
    with pytest.raises(UnknownOptionError, match=r"unknown ColorChecker patch 'reddish'"):
        load_scene(
            {"objects": [{"type": "plane", "center_m": [0, 0, 0], "reflectance": "reddish"}]}
        )


def test_missing_files_and_keys(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="scene file not found"):
        load_scene(tmp_path / "nope.toml")
    with pytest.raises(InvalidInputError, match=r"file not found: .*missing\.png"):
        load_scene(
            {
                "objects": [
                    {"type": "image", "center_m": [0, 0, 0], "path": str(tmp_path / "missing.png")}
                ]
            }
        )
    with pytest.raises(InvalidInputError, match=r"file not found: .*spd\.csv"):
        load_scene({"illuminant": {"type": "file", "file": str(tmp_path / "spd.csv")}})
    with pytest.raises(InvalidInputError, match=r"objects\[0\].*missing key 'center_m'"):
        load_scene({"objects": [{"type": "plane"}]})
    with pytest.raises(InvalidInputError, match="needs the key 'file'"):
        load_scene({"illuminant": {"type": "file"}})
    with pytest.raises(InvalidInputError, match="TOML syntax error"):
        load_scene("name = \n")
    with pytest.raises(InvalidInputError, match="expected source as a TOML path"):
        load_scene(3)  # type: ignore[arg-type]


def test_camera_options() -> None:
    with pytest.raises(InvalidInputError, match="give both R and t_m"):
        load_scene({"camera": {"R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}})
    s = load_scene(
        {
            "camera": {
                "R": [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
                "t_m": [0, 0, 0.2],
                "fx_px": 300.0,
                "cx_px": 10.0,
            }
        }
    )
    np.testing.assert_allclose(np.asarray(s.camera.K)[0], [300.0, 0.0, 10.0])
    with pytest.raises(InvalidInputError, match=r"camera obscura.*remove camera\.distortion"):
        load_scene({"camera": {"image_plane": "real", "distortion": {"k1": -0.1}}})


def test_illuminant_kinds(tmp_path: Path) -> None:
    assert load_scene({"illuminant": {"type": "blackbody", "temperature_K": 3200}}).illuminant
    d = load_scene({"illuminant": {"type": "daylight", "temperature_K": 5000}}).illuminant
    assert "5000" in d.name
    with pytest.raises(InvalidInputError, match="4000-25000 K"):
        load_scene({"illuminant": {"type": "daylight", "temperature_K": 3000}})
    f = tmp_path / "spd.csv"
    f.write_text("# wavelength_nm,power\n400,1\n500,2\n600,3\n700,4\n")
    il = load_scene({"illuminant": {"type": "file", "file": str(f)}}).illuminant
    assert il.values.tolist() == [1.0, 2.0, 3.0, 4.0]


def test_find_line_tables_and_arrays() -> None:
    assert find_line(GOOD, ("render",)) == 2
    assert find_line(GOOD, ("objects", 1)) == 13
    assert find_line(GOOD, ("objects", 1, "squares")) == 16
    assert find_line(None, ("render",)) is None


def test_default_scene_is_the_packaged_toml() -> None:
    a, b = default_scene(), load_scene(DEFAULT_TOML)
    assert a.config == b.config and a.image_size == (1280, 720)
    kinds = sorted(o.kind for o in a.objects)
    assert kinds == ["checkerboard", "colorchecker", "ground"]
    assert a.config.illuminant.name == "A" and a.config.illuminant.temperature_K is None


def test_with_changes_revalidates() -> None:
    s = default_scene().with_changes(render={"width": 100, "height": 50})
    assert s.image_size == (100, 50)
    with pytest.raises(InvalidInputError):
        default_scene().with_changes(render={"width": -1})


def _keys(schema: dict, out: set[str]) -> set[str]:
    for k, v in schema.items():
        if isinstance(v, Field):
            out.add(k)
        else:
            if k:
                out.add(k)
            _keys(v, out)
    return out


def test_docs_describe_every_key() -> None:
    text = (ROOT / "docs" / "simulate.md").read_text()
    missing = [k for k in sorted(_keys(SCENE_SCHEMA, set())) if f"`{k}`" not in text]
    assert not missing, missing


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_load(path: Path) -> None:
    if "kodak" in path.read_text() and not (ROOT.parent / "shared" / "data").is_dir():
        pytest.skip("reference data not found")
    s = load_scene(path)
    assert s.objects and re.fullmatch(r"[\w \-]+", s.name)


@given(st.floats(0.01, 1000.0), st.sampled_from([("mm", 1.0), ("cm", 10.0), ("m", 1000.0)]))
@settings(max_examples=25, deadline=None)
def test_unit_strings_convert_lengths(value: float, unit: tuple[str, float]) -> None:
    from imageform.simulate.validation import validate_scene_dict

    name, to_mm = unit
    cfg = validate_scene_dict({"camera": {"focal_length_mm": f"{value!r} {name}"}})
    assert cfg["camera"]["focal_length_mm"] == pytest.approx(value * to_mm, rel=1e-12)


def test_the_memory_estimate_counts_textures(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 25: a 10000^2 texture made simulate peak at 9.7 GB although the 1280x720 render
    fit the budget. The textures count (from their headers, before any is decoded)."""
    from imageform.io import write_image

    write_image(tmp_path / "tex.png", np.zeros((1000, 1000, 3), np.uint8))
    scene = {
        "render": {"width": 64, "height": 48},
        "objects": [{"type": "image", "center_m": [0, 0, 0], "path": str(tmp_path / "tex.png")}],
    }
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "64MiB")  # the render alone: 1.4 MB
    with pytest.raises(InvalidInputError) as err:
        load_scene(scene)
    msg = str(err.value)
    assert "objects[0] (image0): its 1000x1000 texture and the 64x48 render need about" in msg
    assert msg.endswith("(IMAGEFORM_MAX_MEMORY)") and "\n" not in msg
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "256MiB")
    assert load_scene(scene).objects[0].name == "image0"
