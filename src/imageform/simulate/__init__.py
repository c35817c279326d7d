"""imageform.simulate: the scene-to-image simulator (scene, renderer, camera pipeline).

A scene file is validated once into a typed :class:`SceneConfig` (:mod:`.config`); the
renderer (:mod:`.render`) and the camera's stages (:mod:`.stages`) turn it into images,
composed by :func:`simulate`. The world is z up (:data:`WORLD_UP`).
"""

from imageform.simulate.colorfit import apply_color_correction, fit_color_correction
from imageform.simulate.config import WORLD_UP, CameraConfig, SceneConfig
from imageform.simulate.dng import (
    simulated_baseline_exposure,
    simulated_color_matrix,
    simulated_vignette_opcode,
    write_simulated_dng,
)
from imageform.simulate.lab import LAB_FORMAT, LabSet, render_lab_set
from imageform.simulate.measured import apply_camera_file
from imageform.simulate.measured_sensor import MeasuredCamera
from imageform.simulate.pipeline import simulate
from imageform.simulate.render import RenderOutput, render_scene
from imageform.simulate.result import (
    STAGE_KINDS,
    ColorCheckerTruth,
    PatchMeasurements,
    SceneQuad,
    SimulationResult,
    Stage,
    VanishingTruth,
)
from imageform.simulate.scene import Scene, SceneObject, default_scene, load_scene
from imageform.simulate.schema import SCENE_SCHEMA
from imageform.simulate.stages import diffraction_psf_kernel, gaussian_sigma_for_mtf50
from imageform.simulate.trajectory import (
    MAX_TRAJECTORY_FRAMES,
    Trajectory,
    board_poses,
    read_trajectory,
    render_frames,
)

__all__ = [
    "LAB_FORMAT",
    "MAX_TRAJECTORY_FRAMES",
    "SCENE_SCHEMA",
    "STAGE_KINDS",
    "WORLD_UP",
    "CameraConfig",
    "ColorCheckerTruth",
    "LabSet",
    "MeasuredCamera",
    "PatchMeasurements",
    "RenderOutput",
    "Scene",
    "SceneConfig",
    "SceneObject",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "Trajectory",
    "VanishingTruth",
    "apply_camera_file",
    "apply_color_correction",
    "board_poses",
    "default_scene",
    "diffraction_psf_kernel",
    "fit_color_correction",
    "gaussian_sigma_for_mtf50",
    "load_scene",
    "read_trajectory",
    "render_frames",
    "render_lab_set",
    "render_scene",
    "simulate",
    "simulated_baseline_exposure",
    "simulated_color_matrix",
    "simulated_vignette_opcode",
    "write_simulated_dng",
]
