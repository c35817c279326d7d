"""The typed scene configuration: built once from the TOML, the schema's keys exactly, the
camera seam to imageform.geometry.Camera, and what validation refuses (lights, distortion
models, images too large for the machine)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import BrownConrady, Camera, DivisionModel, KannalaBrandt
from imageform.simulate import (
    SCENE_SCHEMA,
    WORLD_UP,
    CameraConfig,
    SceneConfig,
    budget,
    config,
    default_scene,
    load_scene,
)
from imageform.simulate.schema import DISTORTION_COEFFICIENTS, Field

SECTIONS = {
    "render": config.RenderConfig,
    "illuminant": config.IlluminantConfig,
    "camera": config.CameraConfig,
    "lens": config.LensConfig,
    "sensor": config.SensorConfig,
    "processing": config.ProcessingConfig,
}
OBJECTS = {
    "checkerboard": config.CheckerboardConfig,
    "colorchecker": config.ColorCheckerConfig,
    "ground": config.GroundConfig,
    "image": config.ImageConfig,
    "plane": config.PlaneConfig,
}


def _names(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def test_dataclasses_have_exactly_the_schema_keys() -> None:
    top = [k for k, v in SCENE_SCHEMA[""].items() if isinstance(v, Field)]
    assert _names(SceneConfig)[: len(top)] == top
    for section, cls in SECTIONS.items():
        assert _names(cls) == list(SCENE_SCHEMA[section]), section
    assert _names(config.DistortionConfig) == list(SCENE_SCHEMA["camera"]["distortion"])
    for kind, cls in OBJECTS.items():
        assert _names(cls) == list(SCENE_SCHEMA["objects"][kind]), kind


def test_typed_config_round_trips_the_validated_description() -> None:
    s = default_scene()
    cfg = s.config
    assert isinstance(cfg, SceneConfig) and dataclasses.is_dataclass(cfg)
    assert cfg.render.width == 1280 and cfg.lens.f_number == 4.0
    assert cfg.camera.distortion.k1 == -0.12 and cfg.processing.demosaic == "menon"
    assert [type(o).__name__ for o in cfg.objects] == [
        "GroundConfig",
        "ColorCheckerConfig",
        "CheckerboardConfig",
    ]
    assert SceneConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.render.width = 3  # type: ignore[misc]
    # the objects carry their typed config
    assert s.objects[0].config is cfg.objects[0]


def test_dict_access_is_deprecated_but_works() -> None:
    s = default_scene()
    with pytest.warns(DeprecationWarning, match=r"scene\.config\.lens"):
        assert s.config["lens"]["f_number"] == 4.0
    with pytest.warns(DeprecationWarning, match="SceneObject.config"):
        assert s.objects[1].params["width_m"] == s.config.objects[1].width_m  # type: ignore[attr-defined]


def test_world_is_z_up() -> None:
    assert WORLD_UP == (0.0, 0.0, 1.0)
    ground = default_scene().objects[0]
    n = np.cross(ground.edge_right, ground.edge_down)
    assert np.allclose(-n / np.linalg.norm(n), WORLD_UP)  # the ground faces up


# ---- the camera seam ------------------------------------------------------------------------
def _camera(distortion: object = None, plane: str = "virtual") -> Camera:
    """A calibrated-looking camera (skewed K, distortion) over the default scene's objects."""
    K = [[410.0, 0.5, 161.0], [0.0, 405.0, 118.5], [0.0, 0.0, 1.0]]
    pose = Camera.look_at(K, [0.03, -0.12, 0.06], [0.0, 0.05, 0.01], up=WORLD_UP)
    return Camera(K, pose.R, pose.t, (320, 240), plane, distortion)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "distortion",
    [
        None,
        BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01, k4=0.02, k5=0.0, k6=0.01),
        DivisionModel(k1=-0.1, k2=0.01),
        KannalaBrandt(k1=0.05, k2=-0.01, k3=0.002, k4=-1e-4),
    ],
)
def test_camera_config_round_trips_a_camera(distortion: object) -> None:
    cam = _camera(distortion)
    cfg = CameraConfig.from_camera(cam, focal_length_mm=2.0)
    back = cfg.to_camera((320, 240), 1e-6)
    np.testing.assert_array_equal(back.K, cam.K)
    np.testing.assert_array_equal(back.R, cam.R)
    np.testing.assert_array_equal(back.t, cam.t)
    assert back.image_size == cam.image_size and back.distortion == cam.distortion
    assert cfg.focal_length_mm == 2.0 and cfg.skew_px == 0.5


def test_scene_with_camera_renders_through_it() -> None:
    cam = _camera(BrownConrady(k1=-0.15, k2=0.02))
    scene = default_scene().with_camera(cam)
    assert scene.image_size == (320, 240)
    np.testing.assert_array_equal(scene.camera.K, cam.K)
    np.testing.assert_array_equal(scene.camera.R, cam.R)
    np.testing.assert_array_equal(scene.camera.t, cam.t)
    assert scene.camera.distortion == cam.distortion
    # the camera is described by the scene's own keys (validated like a file) ...
    d = scene.config.to_dict()["camera"]
    assert d["fx_px"] == 410.0 and d["skew_px"] == 0.5 and d["distortion"]["k1"] == -0.15
    assert scene.config.camera.focal_length_mm == default_scene().config.camera.focal_length_mm
    # ... and the renderer sees through it: each object is drawn where the camera projects
    # it (the object hit by the ray of the pixel at its projected centre)
    from imageform.simulate import render_scene

    out = render_scene(scene.with_changes(render={"supersampling": 1}))
    for index, obj in enumerate(scene.objects):
        centre = obj.origin + 0.5 * obj.edge_right + 0.5 * obj.edge_down
        u, v = np.asarray(cam.project(centre[None]).uv)[0]
        if 0 <= u < 319.5 and 0 <= v < 239.5:
            assert out.object_index[round(v), round(u)] == index, obj.name


def test_camera_obscura_and_bad_cameras() -> None:
    cam = _camera(plane="real")
    assert default_scene().with_camera(cam).camera.image_plane == "real"
    with pytest.raises(InvalidInputError, match="image_size"):
        default_scene().with_camera(Camera(np.eye(3)))
    with pytest.raises(InvalidInputError, match=r"expected an imageform\.geometry\.Camera"):
        default_scene().with_camera("cam.toml")  # type: ignore[arg-type]
    # a mirrored camera cannot even be made (imageform.geometry.Camera refuses fx <= 0)
    with pytest.raises(InvalidInputError, match="fx > 0"):
        Camera([[-400.0, 0, 160], [0, 400.0, 120], [0, 0, 1]], image_size=(320, 240))


# ---- what validation refuses ------------------------------------------------------------------
def test_distortion_model_coefficients() -> None:
    s = load_scene({"camera": {"distortion": {"model": "division", "k1": -0.1}}})
    assert s.camera.distortion == DivisionModel(k1=-0.1)
    s = load_scene({"camera": {"distortion": {"model": "kannala_brandt", "k4": 1e-3}}})
    assert s.camera.distortion == KannalaBrandt(k4=1e-3)
    text = '[camera]\n[camera.distortion]\nmodel = "division"\nk1 = -0.1\np1 = 0.01\n'
    with pytest.raises(
        InvalidInputError,
        match=r"camera\.distortion\.p1 \(scene string, line 5\): the division model has no p1; "
        r"its coefficients: k1, k2",
    ):
        load_scene(text)
    with pytest.raises(UnknownOptionError, match="valid: brown_conrady, division"):
        load_scene({"camera": {"distortion": {"model": "fisheye"}}})
    assert set(DISTORTION_COEFFICIENTS) == {"brown_conrady", "division", "kannala_brandt"}


def test_temperature_belongs_to_blackbody_and_daylight() -> None:
    assert load_scene({"illuminant": {"type": "blackbody"}}).config.illuminant.temperature_K == 6504
    with pytest.raises(
        InvalidInputError,
        match=r"illuminant\.temperature_K \(scene string, line 4\): applies to type 'blackbody' "
        r"or 'daylight', not 'cie'",
    ):
        load_scene('[illuminant]\ntype = "cie"\nname = "A"\ntemperature_K = 6504\n')


def test_supersampling_has_a_limit() -> None:
    with pytest.raises(InvalidInputError, match=r"render\.supersampling .*line 3.*<= 16"):
        load_scene("[render]\nwidth = 64\nsupersampling = 17\n")


def test_an_image_too_large_for_memory_is_refused_with_the_estimate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    if budget.available_memory_bytes() is not None:  # this machine, as it is: refused
        with pytest.raises(InvalidInputError, match=r"render\.width .* of memory"):
            load_scene({"render": {"width": 10**6, "height": 10**6}})  # 450 TB
    monkeypatch.setattr(  # the same on any machine: 16 GB available
        "imageform.simulate.validation.available_memory_bytes", lambda: 16_000_000_000
    )
    text = "[render]\nwidth = 200000\nheight = 150000\n"
    with pytest.raises(InvalidInputError) as err:
        load_scene(text)
    msg = str(err.value)
    assert msg.startswith("scene key render.width (scene string, line 2): a 200000x150000")
    assert "needs about 13500 GB of memory" in msg and "the 16 GB this machine has" in msg
    assert "\n" not in msg


def test_the_memory_limit_follows_the_machine(monkeypatch: pytest.MonkeyPatch) -> None:
    # 1280x720 needs 0.41 GB: refused with 0.4 GB available, accepted with 0.5 GB
    monkeypatch.setattr("imageform.simulate.validation.available_memory_bytes", lambda: 400_000_000)
    with pytest.raises(InvalidInputError, match=r"415 MB of memory .* the 400 MB"):
        default_scene()
    monkeypatch.setattr("imageform.simulate.validation.available_memory_bytes", lambda: 500_000_000)
    assert default_scene().image_size == (1280, 720)
    monkeypatch.setattr("imageform.simulate.validation.available_memory_bytes", lambda: None)
    assert load_scene({"render": {"width": 10**6, "height": 10**6}}).image_size == (10**6, 10**6)


def test_available_memory_reads_the_machine(tmp_path) -> None:  # type: ignore[no-untyped-def]
    have = budget.available_memory_bytes()
    assert have is None or have > 0
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal: 100 kB\nMemAvailable:    2048 kB\n")
    assert budget._meminfo_available(meminfo) == 2048 * 1024
    assert budget._meminfo_available(tmp_path / "none") is None
    (tmp_path / "memory.max").write_text("1000000\n")
    (tmp_path / "memory.current").write_text("250000\n")
    assert budget._cgroup_available(tmp_path) == 750000
    (tmp_path / "memory.max").write_text("max\n")
    assert budget._cgroup_available(tmp_path) is None


@given(st.integers(2, 50_000), st.integers(2, 50_000))
@settings(max_examples=30, deadline=None)
def test_memory_estimate_grows_with_the_pixels(w: int, h: int) -> None:
    assert budget.estimate_memory_bytes(w, h) == w * h * budget.BYTES_PER_PIXEL
    assert budget.estimate_memory_bytes(w + 1, h) > budget.estimate_memory_bytes(w, h)


def test_no_warning_from_loading_and_resizing() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        default_scene().resized(160).with_changes(lens={"defocus": False})
