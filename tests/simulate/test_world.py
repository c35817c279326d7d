"""One world convention at the boundary: the simulator's world is z up (WORLD_UP) and says
so to the library, whose horizon_line takes the world's up axis by name or vector (its
default is the camera frame's up, -y). The simulator's horizon and the library's agree."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import UnknownOptionError
from imageform.geometry import Camera, horizon_line, vanishing_point
from imageform.simulate import WORLD_UP, default_scene, load_scene
from imageform.simulate.truth import rails_truth
from tests.simulate.scenes import rails_scene

K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])


def _on_line(line: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Signed distances (pixels) of points ``uv`` from ``a u + b v + c = 0``, a² + b² = 1."""
    return uv @ line[:2] + line[2]


def test_up_axis_names() -> None:
    R = Camera.look_at(K, [0.0, -1.0, 0.5], [0.0, 1.0, 0.0], up=WORLD_UP).R
    z = horizon_line(K, R, up=WORLD_UP)
    for name in ("+z", "z", "Z", " +z "):
        np.testing.assert_array_equal(horizon_line(K, R, up=name), z)
    np.testing.assert_array_equal(horizon_line(K), horizon_line(K, None, "-y"))
    np.testing.assert_array_equal(horizon_line(K), horizon_line(K, np.eye(3), (0.0, -1.0, 0.0)))
    with pytest.raises(UnknownOptionError, match=r"unknown up axis 'up'; valid: \+x, -x"):
        horizon_line(K, R, up="up")


def test_simulator_horizon_is_the_librarys_in_the_z_up_world() -> None:
    scene = default_scene()
    ground = next(o for o in scene.objects if o.kind == "ground")
    cam = scene.camera
    truth = rails_truth(ground, cam)
    library = horizon_line(cam.K, cam.R, up="+z")
    np.testing.assert_allclose(truth.horizon, library, atol=1e-12)
    # every horizontal direction vanishes on it (library's vanishing_point, pinhole K)
    for d in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.3, -2.0, 0.0]):
        v = np.asarray(vanishing_point(cam.K, d, cam.R))
        assert abs(library @ v) < 1e-9 * max(1.0, float(np.linalg.norm(v[:2])))
    # the y-down default is not this world's horizon: the convention must be named
    wrong = horizon_line(cam.K, cam.R)
    assert not np.allclose(wrong, library, atol=1e-3)


def test_the_rails_vanishing_point_lies_on_the_horizon() -> None:
    scene = load_scene(rails_scene())
    ground = scene.objects[0]
    truth = rails_truth(ground, scene.camera)
    vp = truth.vanishing_point / truth.vanishing_point[2]
    assert abs(truth.horizon @ vp) < 1e-9
    np.testing.assert_allclose(
        truth.horizon, horizon_line(scene.camera.K, scene.camera.R, up=WORLD_UP), atol=1e-12
    )


@given(
    yaw=st.floats(-3.1, 3.1),
    pitch=st.floats(-1.2, 1.2),
    roll=st.floats(-0.5, 0.5),
    far=st.lists(
        st.tuples(st.floats(-50, 50), st.floats(-50, 50)).filter(lambda p: np.hypot(*p) > 0.1),
        min_size=1,
        max_size=5,
    ),
)
@settings(max_examples=50, deadline=None)
def test_points_at_eye_height_image_on_the_z_up_horizon(
    yaw: float, pitch: float, roll: float, far: list[tuple[float, float]]
) -> None:
    # a world point as high as the camera centre is seen along a horizontal ray: its image
    # lies on the horizon of the z-up world, whatever the camera's heading, tilt and roll
    eye = np.array([0.2, -0.4, 1.5])
    d = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), np.sin(pitch)])
    base = Camera.look_at(K, eye, eye + d, up=WORLD_UP)
    c, s = np.cos(roll), np.sin(roll)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.asarray(base.R)
    cam = Camera(K, R, -R @ eye)
    X = np.array([[eye[0] + x, eye[1] + y, eye[2]] for x, y in far])
    proj = cam.project(X)
    uv = np.asarray(proj.uv)[np.asarray(proj.valid)]
    line = np.asarray(horizon_line(K, R, up="+z"))
    if line[2] == 1.0 and not line[:2].any():  # looking straight up or down: no horizon
        return
    scale = 1.0 + np.abs(uv).max() if uv.size else 1.0
    assert np.all(np.abs(_on_line(line, uv)) < 1e-7 * scale)


def test_simulator_names_its_up_axis_when_it_calls_horizon_line() -> None:
    # every call of horizon_line inside imageform.simulate passes `up=` explicitly
    root = Path(__file__).resolve().parents[2] / "src" / "imageform" / "simulate"
    calls = 0
    for path in root.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "horizon_line":
                calls += 1
                assert any(k.arg == "up" for k in node.keywords), path.name
    assert calls >= 1
