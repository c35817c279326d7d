"""imageform.simulate: the scene-to-image simulator (scene, renderer, camera pipeline)."""

from imageform.simulate.colorfit import apply_color_correction, fit_color_correction
from imageform.simulate.pipeline import simulate
from imageform.simulate.render import RenderOutput, render_scene
from imageform.simulate.result import (
    STAGE_KINDS,
    ColorCheckerTruth,
    SceneQuad,
    SimulationResult,
    Stage,
    VanishingTruth,
)
from imageform.simulate.scene import Scene, SceneObject, default_scene, load_scene
from imageform.simulate.schema import SCENE_SCHEMA

__all__ = [
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
]
