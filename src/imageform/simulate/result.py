"""What a simulation run returns: every stage's image, the ground truth and the measurements.

This module is the contract between the renderer/pipeline (:mod:`imageform.simulate`) and the
report writer (:mod:`imageform.report`): the pipeline fills a :class:`SimulationResult`, the
report reads it. Nothing here computes; it only names and documents the fields.

Stage kinds (how a report turns the array into something to look at):

- ``"linear"``: linear-light RGB (or a single channel), any non-negative scale; display by
  scaling a high percentile to 1 and applying the sRGB transfer function.
- ``"raw"``: a sensor image in digital numbers ``(H, W)``, integer or float, with
  ``Stage.white_level`` the largest code; display as grey, scaled by ``white_level``.
- ``"srgb"``: encoded sRGB in [0, 1], ``(H, W, 3)``; display as is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from imageform.geometry.camera import Camera
from imageform.sensor.emva import PhotonTransferData

__all__ = [
    "STAGE_KINDS",
    "ColorCheckerTruth",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "VanishingTruth",
]

StageKind = Literal["linear", "raw", "srgb"]
STAGE_KINDS: tuple[str, ...] = ("linear", "raw", "srgb")


@dataclass(frozen=True)
class Stage:
    """One step of the chain, in order: ``name`` (a slug used for file names, e.g.
    ``"radiance"``, ``"raw"``, ``"demosaiced"``), ``title`` and ``description`` (one sentence
    saying what the stage did, with the formula where there is one), ``image`` (a NumPy array,
    see the module docstring for ``kind``), ``white_level`` (raw stages only), and
    ``seconds`` (the time the stage took)."""

    name: str
    title: str
    description: str
    image: np.ndarray
    kind: StageKind
    white_level: float | None = None
    seconds: float = 0.0


@dataclass(frozen=True)
class SceneQuad:
    """A planar object of the scene as the report's top view draws it: ``name`` and its four
    world corners ``corners`` of shape ``(4, 3)`` (metres, world frame)."""

    name: str
    corners: np.ndarray


@dataclass(frozen=True)
class ColorCheckerTruth:
    """The 24 ColorChecker patches: ``names`` (24,), ``lab_d65`` (24, 3) the ground-truth CIELAB
    under D65 (2°), ``centres_uv`` (24, 2) the patch centres in the image (pixels) and
    ``sample_radius_px`` the radius of the square window sampled around each centre."""

    names: tuple[str, ...]
    lab_d65: np.ndarray
    centres_uv: np.ndarray
    sample_radius_px: float


@dataclass(frozen=True)
class VanishingTruth:
    """The rails' true vanishing point (homogeneous ``(3,)``, pixels) and the true horizon
    line (homogeneous ``(3,)``, ``a u + b v + c = 0``); ``detected_*`` what the detector found
    on the output image (``None`` when it found nothing)."""

    vanishing_point: np.ndarray
    horizon: np.ndarray
    detected_vanishing_point: np.ndarray | None = None
    detected_horizon: np.ndarray | None = None


@dataclass(frozen=True)
class SimulationResult:
    """Everything a run produced.

    - ``stages``: the chain in order (scene radiance ... encoded output); ``stages[-1]`` is the
      final ``"srgb"`` image.
    - ``camera``: the camera that rendered the scene (pose, intrinsics, distortion);
      ``image_size`` ``(width, height)``.
    - ``quads``: the scene's planar objects, for the top view with the camera frustum.
    - ``colorchecker``: patch ground truth and positions (``None`` if the scene has none);
      ``patch_xy``: chromaticity xy of every patch at named stages, e.g.
      ``{"before_white_balance": (24, 2), "after_white_balance": (24, 2),
      "after_color_correction": (24, 2)}``.
    - ``vanishing``: true and detected vanishing point and horizon (``None`` without rails).
    - ``photon_transfer``: the sensor's simulated photon-transfer measurement.
    - ``metrics``: JSON-serialisable numbers (ΔE00 per patch and their mean/max, SNR per patch
      in dB, vanishing-point error in px, timings...), written as metrics.json.
    - ``scene_name``, ``config``: the scene's name and its validated description as a plain
      dict (echoed into the report).
    """

    stages: tuple[Stage, ...]
    camera: Camera
    image_size: tuple[int, int]
    quads: tuple[SceneQuad, ...] = ()
    colorchecker: ColorCheckerTruth | None = None
    patch_xy: dict[str, np.ndarray] = field(default_factory=dict)
    vanishing: VanishingTruth | None = None
    photon_transfer: PhotonTransferData | None = None
    metrics: dict[str, Any] = field(default_factory=dict)
    scene_name: str = "scene"
    config: dict[str, Any] = field(default_factory=dict)

    def stage(self, name: str) -> Stage:
        """The stage called ``name``; ``KeyError`` listing the names if there is none."""
        for s in self.stages:
            if s.name == name:
                return s
        raise KeyError(f"no stage {name!r}; stages: {[s.name for s in self.stages]}")
