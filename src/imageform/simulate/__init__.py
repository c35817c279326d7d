"""imageform.simulate: the scene-to-image simulator (scene, renderer, camera pipeline)."""

from imageform.simulate.result import (
    STAGE_KINDS,
    ColorCheckerTruth,
    SceneQuad,
    SimulationResult,
    Stage,
    VanishingTruth,
)

__all__ = [
    "STAGE_KINDS",
    "ColorCheckerTruth",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "VanishingTruth",
]
