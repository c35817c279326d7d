"""The public names of imageform.simulate (removing one must be a deliberate act)."""

from __future__ import annotations

import numpy as np
import pytest

import imageform.simulate as sim
from imageform.errors import InvalidInputError

PUBLIC = {
    "SCENE_SCHEMA",
    "STAGE_KINDS",
    "WORLD_UP",
    "CameraConfig",
    "ColorCheckerTruth",
    "PatchMeasurements",
    "RenderOutput",
    "Scene",
    "SceneConfig",
    "SceneObject",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "VanishingTruth",
    "apply_color_correction",
    "default_scene",
    "fit_color_correction",
    "load_scene",
    "render_scene",
    "simulate",
}


def test_public_names() -> None:
    assert set(sim.__all__) == PUBLIC
    assert all(hasattr(sim, n) for n in PUBLIC)


def test_render_twin_path_matches_kernel_path(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = sim.default_scene().resized(48)
    fast = sim.render_scene(scene)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = sim.render_scene(scene)
    np.testing.assert_array_equal(fast.object_index, plain.object_index)
    np.testing.assert_allclose(fast.rate, plain.rate, rtol=1e-9, atol=1e-9 * fast.rate.max())
    np.testing.assert_allclose(fast.depth, plain.depth, rtol=1e-9)


def test_fit_color_correction_errors() -> None:
    from imageform.errors import DegenerateConfigurationError, InvalidInputError

    with pytest.raises(InvalidInputError, match=r"shape \(N, 3\)"):
        sim.fit_color_correction(np.ones((4, 2)), np.ones((4, 2)))
    with pytest.raises(DegenerateConfigurationError, match="independent colours"):
        sim.fit_color_correction(np.ones((5, 3)), np.ones((5, 3)))
    rng = np.random.default_rng(0)
    C = rng.uniform(0, 1, (24, 3))
    M = rng.normal(size=(3, 3))
    np.testing.assert_allclose(sim.fit_color_correction(C, C @ M), M, atol=1e-12)


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.uint8])
def test_color_correction_dtypes(dtype: type) -> None:
    rng = np.random.default_rng(1)
    C = rng.uniform(0, 1, (24, 3))
    C32 = C.astype(np.float32)
    M = sim.fit_color_correction(C32, C32 @ np.eye(3, dtype=np.float32))
    assert M.dtype == np.float32
    img: np.ndarray = (rng.uniform(0, 1, (4, 5, 3)) * (255 if dtype == np.uint8 else 1)).astype(
        dtype
    )
    out = sim.apply_color_correction(img, 2 * np.eye(3))
    assert out.dtype == (np.float64 if dtype == np.float64 else np.float32)
    ref = img / 255.0 if dtype == np.uint8 else img
    np.testing.assert_allclose(out, 2 * ref, rtol=1e-6)
    with pytest.raises(InvalidInputError, match=r"\(3, 3\) matrix"):
        sim.apply_color_correction(img, np.eye(2))
