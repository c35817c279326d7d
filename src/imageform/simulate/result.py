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

import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from imageform import _deprecate
from imageform._validate import as_real, as_reals, as_size, describe
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry.camera import Camera
from imageform.sensor.emva import PhotonTransferData
from imageform.simulate.config import WORLD_UP

__all__ = [
    "STAGE_KINDS",
    "ColorCheckerTruth",
    "PatchMeasurements",
    "SceneQuad",
    "SimulationResult",
    "Stage",
    "VanishingTruth",
]

StageKind = Literal["linear", "raw", "srgb"]
STAGE_KINDS: tuple[str, ...] = ("linear", "raw", "srgb")


@dataclass(frozen=True)
class Stage:
    """One step of the chain, in order.

    ``name`` (a slug used for file names, e.g. ``"radiance"``, ``"raw"``, ``"demosaiced"``),
    ``title`` and ``description`` (one sentence saying what the stage did, with the formula where
    there is one), ``image`` (a NumPy array, see the module docstring for ``kind``), ``white_level``
    (raw stages only), and ``seconds`` (the time the stage took).
    """

    name: str
    title: str
    description: str
    image: np.ndarray
    kind: StageKind
    white_level: float | None = None
    seconds: float = 0.0

    def __post_init__(self) -> None:
        """Check the names are strings, ``seconds`` finite and ``>= 0``, ``image`` an array.

        ``white_level`` is finite and ``> 0`` (or None); an unknown ``kind`` is the report's to
        refuse, naming the stage.
        """
        for key in ("name", "title", "description"):
            if not isinstance(getattr(self, key), str):
                raise TypeError(f"expected {key} as a string, got {describe(getattr(self, key))}")
        if not hasattr(self.image, "shape") or not hasattr(self.image, "dtype"):
            raise TypeError(f"expected image as an array, got {describe(self.image)}")
        object.__setattr__(self, "seconds", as_real(self.seconds, "seconds", nonnegative=True))
        if self.white_level is not None:
            wl = as_real(self.white_level, "white_level", positive=True)
            object.__setattr__(self, "white_level", wl)


@dataclass(frozen=True)
class SceneQuad:
    """A planar object of the scene as the report's top view draws it.

    ``name`` and its four world corners ``corners`` of shape ``(4, 3)`` (metres, world frame).
    """

    name: str
    corners: np.ndarray


@_deprecate.renamed_fields({"centres_uv": "centers_uv"})
@dataclass(frozen=True)
class ColorCheckerTruth:
    """The 24 ColorChecker patches: names, ground-truth CIELAB, centres and sampling radius.

    ``names`` (24,), ``lab_d65`` (24, 3) the ground-truth CIELAB under D65 (2°), ``centers_uv``
    (24, 2) the patch centres in the image (pixels) and ``sample_radius_px`` the radius of the
    square window sampled around each centre.
    """

    names: tuple[str, ...]
    lab_d65: np.ndarray
    centers_uv: np.ndarray
    sample_radius_px: float


@dataclass(frozen=True)
class PatchMeasurements:
    """The ColorChecker measured on a run's images, one row per patch (24).

    - ``names``; ``lab_truth`` and ``lab_measured`` (CIELAB, D65 white) and ``delta_e00``
      (CIEDE2000 between them; NaN for a patch outside the image);
    - ``readings``: the lecture's words for each ΔE00 (``"not measured"`` where NaN);
    - ``snr_luminance_db``: ``20 log10(mean(Y) / std(Y))`` of the luminance
      ``Y = 0.2126 R + 0.7152 G + 0.0722 B`` of the pixels in the patch window on stage
      ``snr_stage`` (``inf`` for a noise-free window, NaN outside the image or for a black
      patch);
    - ``truth_srgb``: the ground truth as encoded sRGB, clipped to [0, 1] (for display).

    Computed by :func:`imageform.simulate.truth.measure_colorchecker`.
    """

    names: tuple[str, ...]
    lab_truth: np.ndarray
    lab_measured: np.ndarray
    delta_e00: np.ndarray
    readings: tuple[str, ...]
    snr_luminance_db: np.ndarray
    snr_stage: str
    truth_srgb: np.ndarray

    @property
    def delta_e00_mean(self) -> float:
        """Mean ΔE00 over the measured patches (NaN if none was measured)."""
        d = self.delta_e00[np.isfinite(self.delta_e00)]
        return float(d.mean()) if d.size else float("nan")

    @property
    def delta_e00_max(self) -> float:
        """Largest ΔE00 over the measured patches (NaN if none was measured)."""
        d = self.delta_e00[np.isfinite(self.delta_e00)]
        return float(d.max()) if d.size else float("nan")

    @property
    def mean_delta_e00(self) -> float:
        """Deprecated: :attr:`delta_e00_mean`."""
        warnings.warn(
            "PatchMeasurements.mean_delta_e00 is deprecated: use delta_e00_mean",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.delta_e00_mean

    @property
    def max_delta_e00(self) -> float:
        """Deprecated: :attr:`delta_e00_max`."""
        warnings.warn(
            "PatchMeasurements.max_delta_e00 is deprecated: use delta_e00_max",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.delta_e00_max

    @property
    def snr_db(self) -> np.ndarray:
        """Deprecated: :attr:`snr_luminance_db` (the one SNR the report gives)."""
        warnings.warn(
            "PatchMeasurements.snr_db is deprecated: use snr_luminance_db",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.snr_luminance_db


def _homogeneous(value: object, name: str) -> np.ndarray:
    """Return a finite real homogeneous 3-vector (a point or a line) as float64."""
    if value is None or isinstance(value, str | bytes | bool):
        raise InvalidInputError(f"expected {name} as 3 numbers, got {describe(value)}")
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise InvalidInputError(f"expected {name} as 3 real numbers, got {describe(value)}")
    if arr.shape != (3,):
        raise InvalidInputError(f"expected {name} as a homogeneous 3-vector, got shape {arr.shape}")
    arr = arr.astype(np.float64)
    if not np.all(np.isfinite(arr)) or not np.any(arr):
        raise InvalidInputError(f"expected {name} finite and non-zero, got {arr.tolist()}")
    return arr


@dataclass(frozen=True)
class VanishingTruth:
    """The rails' true vanishing point and horizon line, and what the detector found.

    The vanishing point is homogeneous ``(3,)`` (pixels), the horizon line homogeneous ``(3,)``
    (``a u + b v + c = 0``); ``detected_*`` what the detector found on the output image (``None``
    when it found nothing).
    """

    vanishing_point: np.ndarray
    horizon: np.ndarray
    detected_vanishing_point: np.ndarray | None = None
    detected_horizon: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Check each line or point is a finite homogeneous 3-vector.

        ``None`` is allowed for a detection that found nothing.
        """
        for key in ("vanishing_point", "horizon", "detected_vanishing_point", "detected_horizon"):
            value = getattr(self, key)
            if value is None and key.startswith("detected"):
                continue
            object.__setattr__(self, key, _homogeneous(value, key))


@dataclass(frozen=True)
class SimulationResult:
    """Everything a run produced.

    - ``stages``: the chain in order (scene radiance ... encoded output); ``stages[-1]`` is the
      final ``"srgb"`` image.
    - ``camera``: the camera that rendered the scene (pose, intrinsics, distortion);
      ``image_size`` ``(width, height)``.
    - ``quads``: the scene's planar objects, for the top view with the camera frustum.
    - ``colorchecker``: patch ground truth and positions (``None`` if the scene has none);
      ``patches``: the patches measured on the run's images (ΔE00, SNR; ``None`` when the
      result carries no measurement: the report then measures the final stage itself);
      ``patch_xy``: chromaticity xy of every patch at named stages, e.g.
      ``{"before_white_balance": (24, 2), "after_white_balance": (24, 2),
      "after_color_correction": (24, 2)}``.
    - ``vanishing``: true and detected vanishing point and horizon (``None`` without rails).
    - ``photon_transfer``: the sensor's simulated photon-transfer measurement.
    - ``metrics``: JSON-serialisable numbers, named with their unit (ΔE00 per patch and
      their mean/max, ``snr_luminance_db_per_patch``, ``vanishing_point_error_px``,
      ``illuminant_cct_K``, ``step_times_s``, ``simulation_time_s`` ...; the simulator's
      keys are listed in ``docs/simulate-report.md``); the report writes each into
      metrics.json once.
    - ``scene_name``, ``config``: the scene's name and its validated description as a plain
      dict (echoed into the report).
    - ``world_up``: the world's up direction (world coordinates) that the report's top view
      looks down along; the simulator's world is z up, ``(0, 0, 1)``.
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
    patches: PatchMeasurements | None = None
    world_up: tuple[float, float, float] = WORLD_UP

    def __post_init__(self) -> None:
        """Check the fields: ``camera``, ``image_size``, ``world_up`` and ``stages`` (issue 16).

        ``camera`` a Camera, ``image_size`` two positive integers, ``world_up`` a finite non-zero
        3-vector, ``stages`` Stage objects; ``colorchecker``, ``vanishing``,
        ``photon_transfer`` and ``patches`` None or their record type.
        """
        for name, kind in (
            ("colorchecker", ColorCheckerTruth),
            ("vanishing", VanishingTruth),
            ("photon_transfer", PhotonTransferData),
            ("patches", PatchMeasurements),
        ):
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                raise TypeError(
                    f"expected {name} as a {kind.__name__} (or None), got {describe(value)}"
                )
        if not isinstance(self.camera, Camera):
            raise TypeError(
                f"expected camera as an imageform.geometry.Camera, got {describe(self.camera)}"
            )
        w, h = as_size(self.image_size, "image_size (width, height)")
        object.__setattr__(self, "image_size", (w, h))
        up = as_reals(self.world_up, "world_up", 3)
        if not any(up):
            raise InvalidInputError("expected world_up as a non-zero direction, got (0, 0, 0)")
        object.__setattr__(self, "world_up", up)
        stages = tuple(self.stages) if isinstance(self.stages, tuple | list) else None
        if stages is None or not all(isinstance(s, Stage) for s in stages):
            raise TypeError(f"expected stages as a tuple of Stage, got {describe(self.stages)}")
        object.__setattr__(self, "stages", stages)

    def stage(self, name: str) -> Stage:
        """Return the stage called ``name``.

        Raises
        ------
        UnknownOptionError
            No stage is called ``name`` (the message lists the stages, in order).
        """
        for s in self.stages:
            if s.name == name:
                return s
        if not isinstance(name, str):
            raise TypeError(f"expected name as a stage name (str), got {describe(name)}")
        names = ", ".join(repr(s.name) for s in self.stages)
        raise UnknownOptionError(f"unknown stage {describe(name, 30)} for name; valid: {names}")
