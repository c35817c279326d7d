"""Issue 16: scene files and render_scene refuse hostile input in one line with key and line."""

from __future__ import annotations

from pathlib import Path

import pytest

from imageform.errors import InvalidInputError
from imageform.simulate import load_scene, render_scene

BASE = 'name = "tiny"\n[render]\nwidth = 32\nheight = 18\n'


def test_not_utf8_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_bytes(b'name = "t\xff\xfe"\n')
    with pytest.raises(InvalidInputError, match=r"bad\.toml.*not UTF-8") as info:
        load_scene(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ("[lens]\nf_number = 1e308\n", r"lens\.f_number \(scene string, line 6\).*<= 1000"),
        ("[camera]\nfx_px = -500.0\n", r"camera\.fx_px \(scene string, line 6\).*> 0"),
        (
            '[[objects]]\ntype = "colorchecker"\ncenter_m = [0, 0, 2]\nnormal = [0, 0, -1]\n'
            "width_m = 1e300\n",
            r"objects\[0\]\.width_m \(scene string, line 9\).*within",
        ),
    ],
)
def test_scene_bounds(extra: str, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        load_scene(BASE + extra)


def test_supersampling_bounded() -> None:
    text = BASE.replace("height = 18\n", "height = 18\nsupersampling = 100000\n")
    with pytest.raises(InvalidInputError, match=r"render\.supersampling.*<= 16"):
        load_scene(text)


def test_values_never_echoed_whole() -> None:
    with pytest.raises(InvalidInputError) as info:
        load_scene(BASE + '[lens]\nf_number = "' + "y" * 100_000 + '"\n')
    assert len(str(info.value)) < 200 and "lens.f_number" in str(info.value)


def test_render_scene_type_and_chunk() -> None:
    with pytest.raises(TypeError, match="scene"):
        render_scene(None)  # type: ignore[arg-type]
    scene = load_scene(BASE)
    with pytest.raises(InvalidInputError, match="rows_per_chunk"):
        render_scene(scene, rows_per_chunk=-1)
    import numpy as np

    out = render_scene(scene, rows_per_chunk=np.int64(7))
    assert out.rate.shape == (18, 32, 3)


def test_flat_patch_snr_not_silent() -> None:
    import numpy as np

    from imageform.errors import ImageformWarning
    from imageform.simulate import default_scene, simulate

    scene = default_scene().resized(96).with_changes(sensor={"noise": False})
    with pytest.warns(ImageformWarning, match="SNR is infinite"):
        res = simulate(scene, rng=0)
    assert np.isposinf(res.metrics["snr_luminance_db_per_patch"]).any()


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ("[lens]\nfocus_distance_m = 0.0001\n", r"lens\.focus_distance_m \(scene string, line 6\)"),
        (
            '[illuminant]\ntype = "file"\nfile = "nope.csv"\n',
            r"illuminant \(scene string, line 5\)",
        ),
    ],
)
def test_build_errors_name_key_and_line(extra: str, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        load_scene(BASE + extra)
