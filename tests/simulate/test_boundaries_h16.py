"""Issue 16 in the simulator: typed stage arguments, validated dataclasses, bounded kernels,
render-time errors that name the scene key and line, and scene paths kept relative."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from imageform.simulate import (
    SimulationResult,
    Stage,
    VanishingTruth,
    apply_color_correction,
    fit_color_correction,
    load_scene,
    render_scene,
    simulate,
    stages,
    truth,
)
from imageform.simulate.materials import reflectance_spectrum, scene_irradiance
from imageform.simulate.render import pixel_rays
from imageform.simulate.schema import Field
from imageform.simulate.textures import resolve_path
from imageform.simulate.validation import find_line, validate_scene_dict

BASE = 'name = "tiny"\n[render]\nwidth = 32\nheight = 18\n'
NO_CHART = '[processing]\ncolor_correction = "none"\n'


def _one_line(exc: BaseException, *names: str) -> None:
    msg = str(exc)
    assert "\n" not in msg and len(msg) <= 200, msg
    for name in names:
        assert name in msg, (name, msg)


@pytest.fixture(scope="module")
def tiny():  # type: ignore[no-untyped-def]
    return load_scene(BASE + NO_CHART)


# ---- the simulator's colour correction with complex input (never cut to the real part)


@pytest.mark.parametrize("which", ["measured", "target"])
def test_fit_color_correction_refuses_complex(which: str) -> None:
    good = np.full((24, 3), 0.4) + np.arange(72).reshape(24, 3) / 100
    args = {"measured": good, "target": good}
    args[which] = good + 1e-3j
    with pytest.warns(DeprecationWarning), pytest.raises(InvalidInputError) as info:
        fit_color_correction(args["measured"], args["target"])
    _one_line(info.value, which)


@pytest.mark.parametrize("which", ["image", "M"])
def test_apply_color_correction_refuses_complex(which: str) -> None:
    args = {"image": np.full((4, 5, 3), 0.5), "M": np.eye(3)}
    args[which] = args[which] + 1e-3j
    with pytest.warns(DeprecationWarning), pytest.raises(InvalidInputError) as info:
        apply_color_correction(args["image"], args["M"])
    _one_line(info.value, which)


# ---- the typed config: a section built in code is checked like one read from a file


@pytest.mark.parametrize(
    ("section", "key", "value", "name"),
    [
        ("camera", "fx_px", -500.0, "camera.fx_px"),
        ("lens", "f_number", 1e308, "lens.f_number"),
        ("lens", "f_number", complex(2.8, 1.0), "lens.f_number"),
        ("lens", "lateral_ca", (1.0, float("nan"), 1.0), "lens.lateral_ca[1]"),
        ("render", "supersampling", 100000, "render.supersampling"),
        ("render", "width", float("inf"), "render.width"),
        ("illuminant", "illuminance_lux", float("nan"), "illuminant.illuminance_lux"),
        ("sensor", "bit_depth", 10**30, "sensor.bit_depth"),
        ("processing", "demosaic", "x" * 1000, "processing.demosaic"),
    ],
)
def test_config_dataclasses_validate(
    tiny, section: str, key: str, value: object, name: str
) -> None:  # type: ignore[no-untyped-def]
    cfg = getattr(tiny.config, section)
    with pytest.raises((InvalidInputError, TypeError)) as info:
        dataclasses.replace(cfg, **{key: value})
    _one_line(info.value, name)


def test_config_dataclasses_keep_valid_values(tiny) -> None:  # type: ignore[no-untyped-def]
    lens = dataclasses.replace(tiny.config.lens, f_number=np.float64(4.0))
    assert lens.f_number == 4.0 and type(lens.f_number) is float
    render = dataclasses.replace(tiny.config.render, width=np.int64(40))
    assert render.width == 40 and type(render.width) is int


# ---- bounds before anything is computed


def test_diffraction_kernel_bounded_before_computing() -> None:
    # f/1000 at 3.45 um pixels: a 12177-sample PSF (minutes, gigabytes) is refused at once
    with pytest.raises(InvalidInputError) as info:
        stages.diffraction_psf_kernel(
            stages.DIFFRACTION_BANDS[2], f_number=1000.0, pixel_pitch=3.45e-6
        )
    _one_line(info.value, "f_number")


def test_render_bounded_by_the_memory_limit(tiny, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "64K")
    with pytest.raises(InvalidInputError, match="GiB allowed"):
        render_scene(tiny)


def test_scene_size_bounded_by_the_memory_estimate() -> None:
    text = 'name = "big"\n[render]\nwidth = 200000\nheight = 200000\n'
    with pytest.raises(InvalidInputError) as info:
        load_scene(text)
    _one_line(info.value, "render.width", "line 3")


# ---- errors that arise at render time name the scene key and its line


@pytest.mark.parametrize(
    ("extra", "cls", "match"),
    [
        # the default color_correction needs a chart the scene lacks: the key is a default
        ("", InvalidInputError, r"processing\.color_correction \(scene string, default\)"),
        (
            '[processing]\nwhite_balance = "colorchecker"\ncolor_correction = "none"\n',
            InvalidInputError,
            r"processing\.white_balance \(scene string, line 6\)",
        ),
        (
            NO_CHART + "[lens]\nf_number = 1000\ndiffraction = true\n",
            InvalidInputError,
            r"scene key lens \(scene string, line 7\).*diffraction kernel",
        ),
    ],
)
def test_render_time_errors_name_key_and_line(extra: str, cls: type, match: str) -> None:
    scene = load_scene(BASE + extra)
    with pytest.raises(cls, match=match) as info:
        simulate(scene, rng=0)
    assert "\n" not in str(info.value) and len(str(info.value)) <= 200


def test_black_scene_names_exposure_key() -> None:
    scene = load_scene(
        'name = "black"\n[render]\nwidth = 32\nheight = 18\nbackground_reflectance = 0.0\n'
        + NO_CHART
    )
    with pytest.raises(InvalidInputError, match=r"sensor\.exposure_time_s \(scene string"):
        simulate(scene, rng=0)


def test_huge_chart_renders_without_index_error() -> None:
    # a chart 900 km wide fills the view: the run is finite (no IndexError)
    scene = load_scene(
        BASE + NO_CHART + '[[objects]]\ntype = "colorchecker"\ncenter_m = [0, 0, 2]\n'
        "normal = [0, -1, 0]\nwidth_m = 9e5\n"
    )
    res = simulate(scene, rng=0)
    assert np.isfinite(res.stages[-1].image).all()


def test_huge_chart_fitted_names_the_key() -> None:
    scene = load_scene(
        BASE + '[[objects]]\ntype = "colorchecker"\ncenter_m = [0, 0, 2]\nnormal = [0, 0, -1]\n'
        "width_m = 9e5\n"
    )
    with pytest.raises((InvalidInputError, DegenerateConfigurationError)) as info:
        simulate(scene, rng=0)
    _one_line(info.value, "processing.color_correction")


# ---- scene paths stay relative to the scene file


def test_result_holds_paths_relative_to_the_scene(tmp_path: Path) -> None:
    from imageform.io import write_image

    (tmp_path / "tex").mkdir()
    write_image(tmp_path / "tex" / "t.png", np.full((8, 12, 3), 128, dtype=np.uint8))
    (tmp_path / "spd.csv").write_text("nm,power\n380,1\n780,1\n")
    scene_file = tmp_path / "s.toml"
    scene_file.write_text(
        BASE
        + NO_CHART
        + '[illuminant]\ntype = "file"\nfile = "spd.csv"\n'
        + '[[objects]]\ntype = "image"\npath = "tex/t.png"\ncenter_m = [0, 0, 0]\nwidth_m = 0.05\n'
    )
    res = simulate(load_scene(scene_file), rng=0)
    assert res.config["objects"][0]["path"] == "tex/t.png"
    assert res.config["illuminant"]["file"] == "spd.csv"
    assert str(tmp_path) not in json.dumps(res.config, default=str)


# ---- typed stage arguments: a TypeError naming the parameter, never an AttributeError


@pytest.mark.parametrize("bad", [None, 0, "abc", object()])
def test_stage_arguments_typed(tiny, bad: object) -> None:  # type: ignore[no-untyped-def]
    r = render_scene(tiny)
    cfg = tiny.config
    calls = {
        "rendered": lambda: stages.apply_lens(bad, tiny.camera, cfg.lens, 1.0),  # type: ignore[arg-type]
        "camera": lambda: stages.apply_lens(r, bad, cfg.lens, 1.0),  # type: ignore[arg-type]
        "lens": lambda: stages.apply_lens(r, tiny.camera, bad, 1.0),  # type: ignore[arg-type]
        "config": lambda: stages.exposure_time(r.rate, bad, tiny.sensor),  # type: ignore[arg-type]
        "sensor": lambda: stages.normalize_raw(np.zeros((4, 4)), bad, 0.01),  # type: ignore[arg-type]
        "encoded": lambda: stages.decode_output(bad, "srgb"),  # type: ignore[arg-type]
        "obj": lambda: truth.colorchecker_truth(bad, tiny.camera),  # type: ignore[arg-type]
        "ground": lambda: truth.rails_truth(bad, tiny.camera),  # type: ignore[arg-type]
        "truth": lambda: truth.patch_means(np.zeros((4, 4, 3)), bad),  # type: ignore[arg-type]
        "v": lambda: truth.vanishing_errors(bad),  # type: ignore[arg-type]
        "spd": lambda: truth.light_cct(bad),  # type: ignore[arg-type]
        "illuminant": lambda: scene_irradiance(bad, 100.0, np.arange(400.0, 700.0)),  # type: ignore[arg-type]
    }
    for name, call in calls.items():
        with pytest.raises((TypeError, InvalidInputError)) as info:
            call()
        assert not isinstance(info.value, AttributeError)
        _one_line(info.value, name)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: pixel_rays(None, np.zeros(2), np.zeros(2)), "camera"),  # type: ignore[arg-type]
        (lambda: stages.correct_lens_shading(np.ones((6, 8, 3)), np.zeros((6, 8))), "falloff"),
        (lambda: stages.correct_lens_shading(np.ones((6, 8, 3)), np.ones((6, 9))), "falloff"),
        (lambda: stages.demosaic_raw(np.full((8, 8), 0.3), "x" * 500, "bilinear"), "cfa"),
        (lambda: stages.demosaic_raw(np.full((8, 8), np.nan), "RGGB", "bilinear"), "normalized"),
        (lambda: stages.balance_white(np.ones((4, 4, 3)), "x" * 500), "method"),
        (lambda: stages.normalize_raw(np.zeros((4, 4)), None, float("nan")), "sensor"),
        (lambda: stages.encode_output("abc", "srgb", "srgb"), "linear_srgb"),  # type: ignore[arg-type]
        (lambda: stages.WhiteBalanced(np.ones((2, 2, 3)), np.array([1.0, np.nan, 1.0])), "gains"),
        (lambda: stages.ColorCorrected(np.ones((2, 2, 3)), np.eye(3) + 1j), "matrix"),
        (lambda: reflectance_spectrum("not a patch"), "value"),
        (lambda: reflectance_spectrum(float("inf")), "value"),
        (lambda: scene_irradiance(None, 100.0, np.arange(5.0)[::-1]), "illuminant"),  # type: ignore[arg-type]
        (lambda: find_line(True, ("a",)), "text"),  # type: ignore[arg-type]
        (lambda: validate_scene_dict(None), "data"),  # type: ignore[arg-type]
        (lambda: resolve_path("x" * 5000, None), "path"),
        (lambda: resolve_path("missing.png", 0), "base"),  # type: ignore[arg-type]
        (lambda: load_scene("x" * 100_000), "source"),
        (lambda: load_scene(None), "source"),  # type: ignore[arg-type]
        (lambda: Field("float", float("nan"), "a value"), "default"),
        (
            lambda: Stage("raw", "Raw", "the raw image", np.zeros((2, 2)), "raw", None, np.nan),
            "seconds",
        ),
        (
            lambda: VanishingTruth(np.array([1.0, np.inf, 1.0]), np.array([0.0, 1.0, -3.0])),
            "vanishing_point",
        ),
        (lambda: VanishingTruth(np.array([1.0, 2.0, 1.0]), np.array([0.0, 1.0j, -3.0])), "horizon"),
    ],
)
def test_named_refusals(call, name: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises((TypeError, InvalidInputError, UnknownOptionError)) as info:
        call()
    _one_line(info.value, name)


def test_simulation_result_validates(tiny) -> None:  # type: ignore[no-untyped-def]
    ok = SimulationResult(stages=(), camera=tiny.camera, image_size=(np.int64(8), 6))
    assert ok.image_size == (8, 6)
    for key, value in [("image_size", (8.0, float("inf"))), ("world_up", (0.0, float("nan"), 1.0))]:
        with pytest.raises(InvalidInputError) as info:
            dataclasses.replace(ok, **{key: value})
        _one_line(info.value, key)


def test_delta_e_patches_missing_rows_only_whole() -> None:
    rgb = np.full((24, 3), 0.3)
    lab = np.full((24, 3), 50.0)
    rgb[3] = np.nan  # a patch not measured: its ΔE00 is NaN, the others finite
    de = truth.delta_e_patches(rgb, lab)
    assert np.isnan(de[3]) and np.isfinite(np.delete(de, 3)).all()
    rgb[5, 1] = np.nan  # half a colour is malformed
    with pytest.raises(InvalidInputError) as info:
        truth.delta_e_patches(rgb, lab)
    _one_line(info.value, "linear_srgb")


# ---- scene-file errors: one line, never the file's content


@pytest.mark.parametrize(
    ("extra", "names"),
    [
        ("[sensor]\nfoo = 1\n", ("sensor.foo", "line 6", "more")),
        ('[[objects]]\ntype = "ground"\ncenter_m = [0, 0, 0]\nfoo = 1\n', ("objects[0].foo",)),
        ('[illuminant]\nname = "' + "x" * 100_000 + '"\n', ("illuminant.name", "line 6")),
        ("[camera]\nt_m = [0, 0, " + "9" * 5000 + "]\n", ("TOML",)),
        ('[processing]\noutput_space = "' + "x" * 100_000 + '"\n', ("processing.output_space",)),
    ],
)
def test_scene_errors_one_line_without_content(extra: str, names: tuple[str, ...]) -> None:
    with pytest.raises(InvalidInputError) as info:
        load_scene(BASE + extra)
    _one_line(info.value, *names)
    assert "x" * 80 not in str(info.value) and "9" * 80 not in str(info.value)


def test_rail_count_bounded() -> None:
    # 10**18 rails: one pass over the ground's rays each, would render for ever
    text = (
        BASE
        + '[[objects]]\ntype = "ground"\ncenter_m = [0, 0, 0]\nrail_count = 1000000000000000000\n'
    )
    with pytest.raises(InvalidInputError) as info:
        load_scene(text)
    _one_line(info.value, "objects[0].rail_count", "line 8")
