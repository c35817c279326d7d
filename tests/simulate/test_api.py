"""The public names of imageform.simulate (removing one must be a deliberate act)."""

from __future__ import annotations

import numpy as np
import pytest

import imageform.simulate as sim

PUBLIC = {
    "SCENE_SCHEMA",
    "STAGE_KINDS",
    "ColorCheckerTruth",
    "RenderOutput",
    "Scene",
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
