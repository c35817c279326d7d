"""The camera file's model: constants, :class:`CameraFile`, :class:`Provenance`, shared checks.

The checks are those of values that reading and building share (internal to
:mod:`imageform.io`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from datetime import datetime
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import as_bool, as_int, as_real, describe
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.io._camera_toml import Reader, short_list

if TYPE_CHECKING:
    from imageform.geometry.distortion import DistortionModel

if TYPE_CHECKING:
    from imageform.geometry import CalibrationResult, Camera
    from imageform.io._camera_tables import CameraColor, CameraOptics, CameraSensor

__all__ = [
    "CAMERA_FILE_FORMAT",
    "CAMERA_FILE_VERSION",
    "DISTORTION_MODELS",
    "CameraFile",
    "Provenance",
    "Reader",
    "check_std",
    "distortion_name",
]

#: The value of the ``format`` key that marks a camera file.
CAMERA_FILE_FORMAT = "imageform-camera"
#: The version this imageform writes (and the newest it reads).
CAMERA_FILE_VERSION = 1
#: Distortion models by name, with their coefficients in the library's (OpenCV's) order.
DISTORTION_MODELS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "none": (),
        "brown_conrady": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
        "kannala_brandt": ("k1", "k2", "k3", "k4"),
        "division": ("k1", "k2"),
    }
)
_CLASSES = {
    "brown_conrady": "BrownConrady",
    "kannala_brandt": "KannalaBrandt",
    "division": "DivisionModel",
}
# coefficients always written for a model (the others only when non-zero)
_ALWAYS = {"brown_conrady": ("k1", "k2", "p1", "p2", "k3")}

_TABLES: dict[str, tuple[str, ...]] = {
    "image": ("width", "height"),
    "intrinsics": ("fx", "fy", "cx", "cy", "skew", "image_plane"),
    "distortion": ("model", "k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"),
    "pose": ("R", "rvec", "t"),
    "std": ("fx", "fy", "cx", "cy", "skew", "k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2")
    + ("rvec", "t"),
    "provenance": (
        "imageform_version",
        "date",
        "command",
        "based_on",
        "rms_px",
        "views_used",
        "points_used",
        "images",
        "fixed",
    ),
}
#: The optional measured-camera tables (imageform.io._camera_tables), each one dataclass.
_MEASURED = ("sensor", "optics", "color")
_TOP = ("format", "version", *_TABLES, *_MEASURED)
_LEGACY_KEYS = ("fx", "fy", "cx", "cy", "skew", "width", "height", "image_plane", "model") + (
    "k1",
    "k2",
    "k3",
    "k4",
    "k5",
    "k6",
    "p1",
    "p2",
    "rvec",
    "R",
    "t",
)
_LEGACY_CALIBRATION = ("rms", "views")


@dataclass(frozen=True)
class Provenance:
    """Where a camera came from (every field optional).

    Attributes
    ----------
    imageform_version : str
        The imageform that wrote the file.
    date : datetime
        When it was written (UTC).
    command : str
        The command that estimated the camera (``imageform calibrate --board 9x6 ...``).
    based_on : str
        The camera file it was derived from (``imageform pose`` keeps the intrinsics of one).
    rms_px : float
        RMS reprojection error of the estimate, in pixels.
    views_used, points_used : int
        Views (images) and point correspondences the estimate used.
    images : tuple of str
        Names of the images used.
    fixed : tuple of str
        Parameters held fixed during the estimate.
    """

    imageform_version: str | None = None
    date: datetime | None = None
    command: str | None = None
    based_on: str | None = None
    rms_px: float | None = None
    views_used: int | None = None
    points_used: int | None = None
    images: tuple[str, ...] = ()
    fixed: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("imageform_version", "command", "based_on"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, str):
                raise TypeError(f"expected {name} as a str (or None), got {describe(value)}")
        if self.date is not None and not isinstance(self.date, datetime):
            raise TypeError(f"expected date as a datetime (or None), got {describe(self.date)}")
        if self.rms_px is not None:
            object.__setattr__(self, "rms_px", as_real(self.rms_px, "rms_px", nonnegative=True))
        for name in ("views_used", "points_used"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, as_int(value, name, minimum=0))
        for name in ("images", "fixed"):
            value = getattr(self, name)
            if not isinstance(value, tuple | list) or not all(isinstance(v, str) for v in value):
                raise TypeError(f"expected {name} as a tuple of str, got {describe(value)}")
            object.__setattr__(self, name, tuple(value))


@dataclass(frozen=True)
class CameraFile:
    """A camera file's content: the camera, whether its pose is known, uncertainties, origin.

    Attributes
    ----------
    camera : Camera
        K, pose (R, t; identity and zero when ``has_pose`` is False), ``image_size``,
        ``image_plane`` and ``distortion`` (None for the model ``none``).
    has_pose : bool
        The file gives a pose (world to camera). Commands that need one refuse a camera
        without it.
    std : mapping
        Standard deviations by parameter name (``fx``, ``k1``, ... floats; ``rvec``, ``t``
        3-tuples); 0 marks a parameter held fixed.
    provenance : Provenance
    version : int
        The file's format version (0 for a file from before the versioned format).
    path : Path or None
        The file it was read from.
    sensor : CameraSensor or None
        ``[sensor]``: the EMVA 1288 noise model (None when the file has no such table).
    optics : CameraOptics or None
        ``[optics]``: the lens's blur model.
    color : CameraColor or None
        ``[color]``: white balance, colour-correction matrix, spectral sensitivities.

    A mapping of a table's keys is accepted for ``sensor``, ``optics`` and ``color``.
    """

    camera: Camera
    has_pose: bool = False
    std: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    provenance: Provenance = field(default_factory=Provenance)
    version: int = CAMERA_FILE_VERSION
    path: Path | None = None
    sensor: CameraSensor | None = None
    optics: CameraOptics | None = None
    color: CameraColor | None = None

    def __post_init__(self) -> None:
        from imageform.geometry import Camera

        if not isinstance(self.camera, Camera):
            raise InvalidInputError(
                f"expected camera to be an imageform.geometry.Camera, got "
                f"{type(self.camera).__name__}"
            )
        if not isinstance(self.std, Mapping):
            raise TypeError(f"expected std as a mapping of name to value, got {describe(self.std)}")
        if not isinstance(self.provenance, Provenance):
            raise TypeError(f"expected provenance as a Provenance, got {describe(self.provenance)}")
        if self.path is not None:
            if isinstance(self.path, bytes) or not isinstance(self.path, str | os.PathLike):
                raise TypeError(
                    f"expected path as a file name (or None), got {describe(self.path)}"
                )
            object.__setattr__(self, "path", Path(self.path))
        object.__setattr__(self, "std", MappingProxyType(check_std(dict(self.std), "std")))
        object.__setattr__(self, "has_pose", as_bool(self.has_pose, "has_pose"))
        object.__setattr__(
            self, "version", as_int(self.version, "version", minimum=0, maximum=CAMERA_FILE_VERSION)
        )
        from imageform.io._camera_tables import as_table

        for name in _MEASURED:
            object.__setattr__(self, name, as_table(getattr(self, name), name))

    @property
    def distortion_model(self) -> str:
        """The distortion model's name in the file (``none``, ``brown_conrady`` ...)."""
        return distortion_name(self.camera.distortion)

    @classmethod
    def from_calibration(
        cls,
        result: CalibrationResult,
        *,
        images: tuple[str, ...] | list[str] = (),
        command: str | None = None,
    ) -> CameraFile:
        """Build the camera file of a :func:`~imageform.geometry.calibrate_camera` result.

        K, the Brown-Conrady coefficients, the image size, the standard deviations of every
        intrinsic parameter (0 for fixed ones) and the RMS, views used and fixed parameters.
        No pose: a calibration has one per view.
        """
        from imageform.geometry import CalibrationResult, Camera

        if not isinstance(result, CalibrationResult):
            raise TypeError(
                f"expected result as a CalibrationResult (calibrate_camera), got {describe(result)}"
            )
        width, height = result.image_size
        size = (int(width), int(height)) if min(result.image_size) > 0 else None
        camera = Camera(result.K, image_size=size, distortion=result.distortion)
        prov = Provenance(
            command=command,
            rms_px=float(result.rms),
            views_used=len(result.rvecs),
            images=image_names(images, "images"),
            fixed=tuple(result.fixed),
        )
        std = {k: float(v) for k, v in result.std.items() if math.isfinite(v)}
        return cls(camera, False, std, prov)

    def with_pose(self, R: ArrayLike, t: ArrayLike, **provenance: Any) -> CameraFile:
        """Return the same camera with the pose ``X_cam = R X_world + t``.

        Pose standard deviations are dropped, provenance fields replaced by ``provenance``.
        """
        from imageform.geometry import Camera

        c = self.camera
        cam = Camera(c.K, R, t, c.image_size, c.image_plane, c.distortion)
        std = {k: v for k, v in self.std.items() if k not in ("rvec", "t")}
        return replace(
            self, camera=cam, has_pose=True, std=std, provenance=replace(Provenance(), **provenance)
        )


def distortion_name(model: DistortionModel | None) -> str:
    """Return the camera-file name of a distortion model object (``none`` for None).

    Examples
    --------
    >>> from imageform.geometry import KannalaBrandt
    >>> distortion_name(KannalaBrandt(k1=0.1)), distortion_name(None)
    ('kannala_brandt', 'none')
    """
    if model is None:
        return "none"
    name = type(model).__name__
    for key, cls in _CLASSES.items():
        if cls == name:
            return key
    raise InvalidInputError(
        f"expected model as a BrownConrady, KannalaBrandt or DivisionModel distortion, got {name}"
    )


def _nonneg(r: Reader, value: Any, key: str) -> float:
    v = r.number(value, key)
    if v < 0:
        raise r.fail(key, f"expected a number >= 0, got {value:g}")
    return v


def image_names(images: object, name: str) -> tuple[str, ...]:
    """Convert a list or tuple of image paths (str or path-like) to a tuple of str."""
    if not isinstance(images, list | tuple) or not all(
        isinstance(i, str | os.PathLike) for i in images
    ):
        raise TypeError(f"expected {name} as a list of image paths, got {describe(images)}")
    return tuple(str(i) for i in images)


def check_std(std: dict[str, Any], where: str, r: Reader | None = None) -> dict[str, Any]:
    rr = r if r is not None else Reader("camera")
    out: dict[str, Any] = {}
    for name, value in std.items():
        key = f"{where}.{name}"
        if name not in _TABLES["std"]:
            raise UnknownOptionError(
                f"{rr.where}: unknown key(s) {short_list([key], 40)}; "
                f"valid in [std]: {short_list(_TABLES['std'], 90)}"
            )
        if name in ("rvec", "t"):
            seq = list(value) if isinstance(value, (list, tuple, np.ndarray)) else value
            vals = rr.vector(seq, key)
            if any(v < 0 for v in vals):
                raise rr.fail(key, f"expected standard deviations >= 0, got {list(vals)}")
            out[name] = vals
        else:
            out[name] = _nonneg(rr, value, key)
    return out
