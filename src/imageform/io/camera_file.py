"""The one camera file: a versioned TOML description of a camera, read and written here only.

Every command that estimates a camera writes this file (``imageform calibrate``, ``imageform
pose``) and every command that uses one reads it (``project``, ``undistort``, ``pose``,
``triangulate``, ``vanishing``), honouring every field. The schema, an example and the
reading rules are in docs/camera-file.md. In short::

    format = "imageform-camera"     # required marker
    version = 1                     # required; a newer version is refused
    [image]        width, height                      (pixels)
    [intrinsics]   fx, fy, cx, cy, skew, image_plane  (pixels; fx, fy > 0)
    [distortion]   model = "none" | "brown_conrady" | "kannala_brandt" | "division", coefficients
    [pose]         R (3 x 3 rows) or rvec (radians), t  (world to camera: X_cam = R X_world + t)
    [std]          standard deviations, same names as above
    [provenance]   imageform_version, date (UTC), command, rms_px, views_used, images, ...

Files written by earlier imageform versions (keys ``fx fy cx cy skew width height k1 k2 p1 p2
k3 ... rvec/R t`` at the top level or in ``[camera]``, plus the ``[calibration]`` table of
``CalibrationResult.to_toml``) are read too, with the same checks.

The module imports :mod:`imageform.geometry` only when a camera is built, so importing
:mod:`imageform.io` stays cheap.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._files import atomic_write
from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    from imageform.geometry import CalibrationResult, Camera

__all__ = [
    "CAMERA_FILE_FORMAT",
    "CAMERA_FILE_VERSION",
    "DISTORTION_MODELS",
    "CameraFile",
    "Provenance",
    "distortion_name",
    "read_camera",
    "write_camera",
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
_TOP = ("format", "version", *_TABLES)
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
    """

    camera: Camera
    has_pose: bool = False
    std: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    provenance: Provenance = field(default_factory=Provenance)
    version: int = CAMERA_FILE_VERSION
    path: Path | None = None

    def __post_init__(self) -> None:
        from imageform.geometry import Camera

        if not isinstance(self.camera, Camera):
            raise InvalidInputError(
                f"expected camera to be an imageform.geometry.Camera, got "
                f"{type(self.camera).__name__}"
            )
        from imageform.io._camera_read import check_std

        object.__setattr__(self, "std", MappingProxyType(check_std(dict(self.std), "std")))

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
        """The camera file of a :func:`~imageform.geometry.calibrate_camera` result.

        K, the Brown-Conrady coefficients, the image size, the standard deviations of every
        intrinsic parameter (0 for fixed ones) and the RMS, views used and fixed parameters.
        No pose: a calibration has one per view.
        """
        from imageform.geometry import Camera

        width, height = result.image_size
        size = (int(width), int(height)) if min(result.image_size) > 0 else None
        camera = Camera(result.K, image_size=size, distortion=result.distortion)
        prov = Provenance(
            command=command,
            rms_px=float(result.rms),
            views_used=len(result.rvecs),
            images=tuple(str(i) for i in images),
            fixed=tuple(result.fixed),
        )
        std = {k: float(v) for k, v in result.std.items() if math.isfinite(v)}
        return cls(camera, False, std, prov)

    def with_pose(self, R: Any, t: Any, **provenance: Any) -> CameraFile:
        """The same camera with the pose ``X_cam = R X_world + t``; pose standard deviations
        are dropped, provenance fields replaced by ``provenance``."""
        from imageform.geometry import Camera

        c = self.camera
        cam = Camera(c.K, R, t, c.image_size, c.image_plane, c.distortion)
        std = {k: v for k, v in self.std.items() if k not in ("rvec", "t")}
        return replace(
            self, camera=cam, has_pose=True, std=std, provenance=replace(Provenance(), **provenance)
        )


def distortion_name(model: Any) -> str:
    """The camera-file name of a distortion model object (``none`` for None).

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
        f"expected a BrownConrady, KannalaBrandt or DivisionModel distortion, got {name}"
    )


# ---------------------------------------------------------------- reading


def read_camera(path: str | Path) -> CameraFile:
    """Read a camera file (the versioned format, or a file from an earlier imageform).

    Parameters
    ----------
    path : str or Path
        A TOML camera file (docs/camera-file.md).

    Returns
    -------
    CameraFile
        ``camera`` (an :class:`imageform.geometry.Camera` with K, R, t, image_size,
        image_plane and distortion), ``has_pose``, ``std``, ``provenance``, ``version``.

    Raises
    ------
    InvalidInputError
        A missing file, invalid TOML, a missing or ill-typed key, ``fx`` or ``fy`` not a
        finite number > 0, a pose that is not a rotation, a newer version; one line naming
        the file and the key.
    UnknownOptionError
        An unknown key or distortion model (the valid ones are listed).

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "cam.toml"
    >>> _ = p.write_text("fx = 500\\nfy = 500\\ncx = 320\\ncy = 240\\nk1 = -0.1\\n")
    >>> cf = read_camera(p)
    >>> cf.camera.K[0].tolist(), cf.distortion_model, cf.has_pose, cf.version
    ([500.0, 0.0, 320.0], 'brown_conrady', False, 0)
    """
    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"camera file {p} does not exist")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidInputError(f"cannot read camera file {p}: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{p}: not valid TOML: {exc}") from None
    from imageform.io._camera_read import parse

    return replace(parse(data, str(p)), path=p)


# ---------------------------------------------------------------- writing


def _toml_value(value: Any) -> str:
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, datetime):
        return value.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    v = float(value)
    if not math.isfinite(v):
        raise InvalidInputError(f"cannot write a non-finite number ({v}) to a camera file")
    return repr(v)


def _toml_string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def camera_file_text(cf: CameraFile) -> str:
    """The TOML text of a camera file (what :func:`write_camera` writes)."""
    from imageform.geometry import matrix_to_rvec

    cam = cf.camera
    K = np.asarray(cam.K, dtype=np.float64)
    lines = [
        "# imageform camera file (docs/camera-file.md). World to camera: X_cam = R X_world + t;",
        "# pixels (u, v) = (column, row), the centre of the top-left pixel at (0, 0).",
        f"format = {_toml_string(CAMERA_FILE_FORMAT)}",
        f"version = {CAMERA_FILE_VERSION}",
    ]
    if cam.image_size is not None:
        lines += ["", "[image]", f"width = {cam.image_size[0]}", f"height = {cam.image_size[1]}"]
    lines += ["", "[intrinsics]"]
    for name, v in (("fx", K[0, 0]), ("fy", K[1, 1]), ("cx", K[0, 2]), ("cy", K[1, 2])):
        lines.append(f"{name} = {_toml_value(v)}")
    lines.append(f"skew = {_toml_value(K[0, 1])}")
    if cam.image_plane != "virtual":
        lines.append(f"image_plane = {_toml_string(cam.image_plane)}")
    model = distortion_name(cam.distortion)
    lines += ["", "[distortion]", f"model = {_toml_string(model)}"]
    if cam.distortion is not None:
        values = dict(zip(DISTORTION_MODELS[model], cam.distortion.coeffs, strict=True))
        for name, v in values.items():
            if name in _ALWAYS.get(model, ()) or model != "brown_conrady" or v != 0:
                lines.append(f"{name} = {_toml_value(v)}")
    if cf.has_pose:
        R = np.asarray(cam.R, dtype=np.float64)
        rvec = np.asarray(matrix_to_rvec(R), dtype=np.float64)
        lines += [
            "",
            "[pose]",
            f"# the same rotation as a Rodrigues vector (radians): rvec = {_toml_value(rvec)}",
            "R = [",
            *(f"  {_toml_value(row)}," for row in R),
            "]",
            f"t = {_toml_value(np.asarray(cam.t, dtype=np.float64))}",
        ]
    if cf.std:
        lines += ["", "[std]"]
        lines += [f"{name} = {_toml_value(v)}" for name, v in cf.std.items()]
    prov = cf.provenance
    lines += ["", "[provenance]"]
    for name in _TABLES["provenance"]:
        v = getattr(prov, name)
        if v is None or v == ():
            continue
        line = f"{name} = {_toml_value(list(v) if isinstance(v, tuple) else v)}"
        if len(line) > 96 and isinstance(v, tuple):  # one item per line
            line = f"{name} = [\n" + "".join(f"  {_toml_value(i)},\n" for i in v) + "]"
        lines.append(line)
    return "\n".join(lines) + "\n"


def write_camera(
    path: str | Path,
    camera: CameraFile | Camera,
    *,
    has_pose: bool | None = None,
    std: Mapping[str, Any] | None = None,
    provenance: Provenance | None = None,
) -> Path:
    """Write a camera file atomically (a temporary sibling renamed at the end).

    Parameters
    ----------
    path : str or Path
        The ``.toml`` file to write (overwritten; callers decide about ``--force``).
    camera : CameraFile or Camera
        What to write; a bare :class:`~imageform.geometry.Camera` is wrapped, its pose
        written only with ``has_pose=True``.
    has_pose, std, provenance : optional
        Replace those fields of ``camera``.

    Returns
    -------
    Path
        ``path``. ``provenance.imageform_version`` and ``provenance.date`` are filled in
        with this imageform and the current UTC time when not given.

    Examples
    --------
    >>> import tempfile
    >>> from imageform.geometry import Camera, BrownConrady
    >>> cam = Camera([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]], image_size=(640, 480),
    ...              distortion=BrownConrady(k1=-0.1))
    >>> p = write_camera(Path(tempfile.mkdtemp()) / "cam.toml", cam)
    >>> back = read_camera(p)
    >>> back.camera.distortion == cam.distortion, back.camera.image_size
    (True, (640, 480))
    """
    from imageform import __version__

    cf = camera if isinstance(camera, CameraFile) else CameraFile(camera)
    if has_pose is not None:
        cf = replace(cf, has_pose=bool(has_pose))
    if std is not None:
        cf = replace(cf, std=dict(std))
    prov = provenance if provenance is not None else cf.provenance
    prov = replace(
        prov,
        imageform_version=prov.imageform_version or __version__,
        date=prov.date or datetime.now(UTC).replace(microsecond=0),
    )
    text = camera_file_text(replace(cf, provenance=prov))
    final = Path(path)
    atomic_write(final, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return final
