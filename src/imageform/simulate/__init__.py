"""imageform.simulate: the scene-to-image simulator (scene, renderer, camera pipeline)."""

from imageform.simulate.pipeline import simulate
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
    "Scene",
    "SceneObject",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "VanishingTruth",
    "default_scene",
    "load_scene",
    "simulate",
]
