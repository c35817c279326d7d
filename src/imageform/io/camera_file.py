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
from datetime import UTC, date, datetime
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from imageform._files import atomic_write
from imageform.errors import InvalidInputError, UnknownOptionError

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
        object.__setattr__(self, "std", MappingProxyType(_check_std(dict(self.std), "std")))

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


class _Reader:
    """Checks values of one file; every message names the file and the key."""

    def __init__(self, where: str) -> None:
        self.where = where

    def fail(self, key: str, problem: str) -> InvalidInputError:
        return InvalidInputError(f"{self.where}: {key}: {problem}")

    def number(self, value: Any, key: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise self.fail(key, f"expected a number, got {_show(value)}")
        v = float(value)
        if not math.isfinite(v):
            raise self.fail(key, f"expected a finite number, got {value}")
        return v

    def positive(self, value: Any, key: str, what: str = "") -> float:
        v = self.number(value, key)
        if v <= 0:
            raise self.fail(key, f"expected {what or 'a number'} > 0, got {value:g}")
        return v

    def count(self, value: Any, key: str, *, minimum: int = 0) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise self.fail(key, f"expected an integer >= {minimum}, got {_show(value)}")
        return int(value)

    def text(self, value: Any, key: str) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"expected a string, got {_show(value)}")
        return value

    def vector(self, value: Any, key: str, n: int = 3) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(key, f"expected a list of {n} numbers, got {_show(value)}")
        return tuple(self.number(v, f"{key}[{i}]") for i, v in enumerate(value))

    def matrix(self, value: Any, key: str) -> np.ndarray:
        if not isinstance(value, list) or len(value) != 3:
            raise self.fail(key, f"expected 3 rows of 3 numbers, got {_show(value)}")
        return np.array([self.vector(row, f"{key}[{i}]") for i, row in enumerate(value)])

    def table(self, data: Mapping[str, Any], name: str) -> dict[str, Any]:
        value = data.get(name, {})
        if not isinstance(value, dict):
            raise self.fail(name, f"expected a table [{name}], got {_show(value)}")
        return value

    def known(self, table: Mapping[str, Any], valid: tuple[str, ...], where: str) -> None:
        unknown = [k for k in table if k not in valid]
        if unknown:
            raise UnknownOptionError(
                f"{self.where}: unknown key(s) {', '.join(where + k for k in unknown)}; "
                f"valid{' in [' + where[:-1] + ']' if where else ''}: {', '.join(valid)}"
            )


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


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
    r = _Reader(str(p))
    versioned = "format" in data or "version" in data
    cf = _read_v1(data, r) if versioned else _read_legacy(data, r)
    return replace(cf, path=p)


def _read_v1(data: dict[str, Any], r: _Reader) -> CameraFile:
    fmt = data.get("format")
    if fmt != CAMERA_FILE_FORMAT:
        raise r.fail("format", f"expected {CAMERA_FILE_FORMAT!r}, got {_show(fmt)}")
    if "version" not in data:
        raise r.fail("version", "missing (the format version, 1)")
    version = r.count(data["version"], "version", minimum=1)
    if version > CAMERA_FILE_VERSION:
        raise r.fail(
            "version",
            f"version {version} is newer than this imageform reads ({CAMERA_FILE_VERSION}); "
            "upgrade imageform",
        )
    r.known(data, _TOP, "")
    tables = {name: r.table(data, name) for name in _TABLES}
    for name, valid in _TABLES.items():
        r.known(tables[name], valid, name + ".")
    intr = tables["intrinsics"]
    missing = [k for k in ("fx", "fy", "cx", "cy") if k not in intr]
    if missing:
        raise r.fail("intrinsics", f"missing {', '.join(missing)} (pixels)")
    image = tables["image"]
    if image and not ("width" in image and "height" in image):
        raise r.fail("image", "expected both width and height (pixels)")
    dist = dict(tables["distortion"])
    if dist and "model" not in dist:
        raise r.fail("distortion.model", f"missing; valid: {', '.join(DISTORTION_MODELS)}")
    pose = tables["pose"]
    if pose and "t" not in pose:
        raise r.fail("pose.t", "missing (world-to-camera translation)")
    if pose and "R" not in pose and "rvec" not in pose:
        raise r.fail("pose", "expected the rotation as R (3 x 3) or rvec (radians)")
    prov = _provenance(tables["provenance"], r)
    return _build(intr, image, dist, pose, tables["std"], prov, version, r, "")


def _read_legacy(data: dict[str, Any], r: _Reader) -> CameraFile:
    """Files of imageform before the versioned format (keys at the top level or in
    ``[camera]``; ``[calibration]`` with ``rms`` and ``views``)."""
    cal = data.get("calibration", {})
    if "camera" in data:
        cam = data["camera"]
        if not isinstance(cam, dict):
            raise r.fail("camera", f"expected a table [camera], got {_show(cam)}")
        rest = [k for k in data if k not in ("camera", "calibration")]
        if rest:
            raise UnknownOptionError(
                f"{r.where}: unknown key(s) {', '.join(rest)} beside [camera]; valid: camera, "
                "calibration (a version-1 camera file starts with format = "
                f'"{CAMERA_FILE_FORMAT}" and version = {CAMERA_FILE_VERSION})'
            )
        prefix = "camera."
    else:
        cam = {k: v for k, v in data.items() if k != "calibration"}
        prefix = ""
    unknown = [k for k in cam if k not in _LEGACY_KEYS]
    if unknown:
        raise UnknownOptionError(
            f"{r.where}: unknown key(s) {', '.join(prefix + k for k in unknown)}; valid: "
            f"{', '.join(_LEGACY_KEYS)} (a version-1 camera file starts with format = "
            f'"{CAMERA_FILE_FORMAT}" and version = {CAMERA_FILE_VERSION})'
        )
    if not isinstance(cal, dict):
        raise r.fail("calibration", f"expected a table [calibration], got {_show(cal)}")
    r.known(cal, _LEGACY_CALIBRATION, "calibration.")
    missing = [k for k in ("fx", "fy", "cx", "cy") if k not in cam]
    if missing:
        raise r.fail(prefix.rstrip(".") or "camera", f"missing {', '.join(missing)} (pixels)")
    intr = {k: cam[k] for k in ("fx", "fy", "cx", "cy", "skew", "image_plane") if k in cam}
    image = {k: cam[k] for k in ("width", "height") if k in cam}
    if image and len(image) == 1:
        raise r.fail(prefix + "width", "expected both width and height (pixels)")
    coeffs = {k: cam[k] for k in cam if k[0] in "kp"}
    dist: dict[str, Any] = {}
    if "model" in cam or coeffs:
        dist = {"model": cam.get("model", "brown_conrady"), **coeffs}
    pose = {k: cam[k] for k in ("R", "rvec", "t") if k in cam}
    if ("R" in pose or "rvec" in pose) and "t" not in pose:
        pose["t"] = [0.0, 0.0, 0.0]
    if "t" in pose and "R" not in pose and "rvec" not in pose:
        pose["R"] = np.eye(3).tolist()
    prov = Provenance(
        rms_px=None
        if "rms" not in cal or (isinstance(cal["rms"], float) and math.isnan(cal["rms"]))
        else _nonneg(r, cal["rms"], "calibration.rms"),
        views_used=r.count(cal["views"], "calibration.views") if "views" in cal else None,
    )
    return _build(intr, image, dist, pose, {}, prov, 0, r, prefix)


def _nonneg(r: _Reader, value: Any, key: str) -> float:
    v = r.number(value, key)
    if v < 0:
        raise r.fail(key, f"expected a number >= 0, got {value:g}")
    return v


def _build(
    intr: dict[str, Any],
    image: dict[str, Any],
    dist: dict[str, Any],
    pose: dict[str, Any],
    std: dict[str, Any],
    prov: Provenance,
    version: int,
    r: _Reader,
    prefix: str,
) -> CameraFile:
    from imageform.geometry import Camera, rvec_to_matrix
    from imageform.geometry import distortion as dmod

    ki = (lambda n: prefix + n) if version == 0 else (lambda n: "intrinsics." + n)
    fx = r.positive(intr["fx"], ki("fx"), "a focal length in pixels")
    fy = r.positive(intr["fy"], ki("fy"), "a focal length in pixels")
    cx, cy = r.number(intr["cx"], ki("cx")), r.number(intr["cy"], ki("cy"))
    skew = r.number(intr.get("skew", 0.0), ki("skew"))
    plane_name = r.text(intr.get("image_plane", "virtual"), ki("image_plane"))
    if plane_name not in ("virtual", "real"):
        raise r.fail(ki("image_plane"), f"expected 'virtual' or 'real', got {plane_name!r}")
    plane: Literal["virtual", "real"] = "real" if plane_name == "real" else "virtual"
    size = None
    if image:
        ks = (lambda n: prefix + n) if version == 0 else (lambda n: "image." + n)
        size = (
            r.count(image["width"], ks("width"), minimum=1),
            r.count(image["height"], ks("height"), minimum=1),
        )
    model = None
    if dist:
        kd = (lambda n: prefix + n) if version == 0 else (lambda n: "distortion." + n)
        name = r.text(dist["model"], kd("model")).strip().lower().replace("-", "_")
        if name not in DISTORTION_MODELS:
            raise UnknownOptionError(
                f"{r.where}: {kd('model')}: unknown distortion model {dist['model']!r}; "
                f"valid: {', '.join(DISTORTION_MODELS)}"
            )
        extra = [c for c in dist if c != "model" and c not in DISTORTION_MODELS[name]]
        if extra:
            raise r.fail(
                kd(extra[0]),
                f"not a coefficient of the {name} model "
                f"({', '.join(DISTORTION_MODELS[name]) or 'no coefficients'})",
            )
        coeffs = {c: r.number(v, kd(c)) for c, v in dist.items() if c != "model"}
        if name != "none":
            model = getattr(dmod, _CLASSES[name])(**coeffs)
            if plane != "virtual":
                raise r.fail(ki("image_plane"), "a camera with distortion needs 'virtual'")
    R, t = np.eye(3), np.zeros(3)
    if pose:
        kp = (lambda n: prefix + n) if version == 0 else (lambda n: "pose." + n)
        if "R" in pose and "rvec" in pose:
            raise r.fail(kp("R"), "give the rotation as R or rvec, not both")
        if "R" in pose:
            R = r.matrix(pose["R"], kp("R"))
            _check_rotation(R, kp("R"), r)
        else:
            R = np.asarray(rvec_to_matrix(np.array(r.vector(pose["rvec"], kp("rvec")))))
        t = np.array(r.vector(pose["t"], kp("t")))
    std_checked = _check_std(dict(std), "std", r)
    allowed = {"fx", "fy", "cx", "cy", "skew", *(DISTORTION_MODELS[distortion_name(model)])}
    if pose:
        allowed |= {"rvec", "t"}
    stray = [n for n in std_checked if n not in allowed]
    if stray:
        raise r.fail(
            "std." + stray[0], "a standard deviation of a parameter this camera does not have"
        )
    camera = Camera(
        np.array([[fx, skew, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]), R, t, size, plane, model
    )
    return CameraFile(camera, bool(pose), std_checked, prov, version)


def _check_rotation(R: np.ndarray, key: str, r: _Reader) -> None:
    err = float(np.max(np.abs(R @ R.T - np.eye(3))))
    if err > 1e-6:
        raise r.fail(key, f"expected a rotation matrix (R Rᵀ = I), max |R Rᵀ - I| = {err:.3g}")
    det = float(np.linalg.det(R))
    if abs(det - 1.0) > 1e-5:
        raise r.fail(key, f"expected a proper rotation (det R = +1), got det R = {det:.6g}")


def _check_std(std: dict[str, Any], where: str, r: _Reader | None = None) -> dict[str, Any]:
    rr = r if r is not None else _Reader("camera")
    out: dict[str, Any] = {}
    for name, value in std.items():
        key = f"{where}.{name}"
        if name not in _TABLES["std"]:
            raise UnknownOptionError(
                f"{rr.where}: unknown key(s) {key}; valid in [std]: {', '.join(_TABLES['std'])}"
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


def _provenance(table: dict[str, Any], r: _Reader) -> Provenance:
    def opt(key: str, fn: Any) -> Any:
        return fn(table[key], "provenance." + key) if key in table else None

    def strings(key: str) -> tuple[str, ...]:
        value = table.get(key, [])
        if not isinstance(value, list):
            raise r.fail("provenance." + key, f"expected a list of strings, got {_show(value)}")
        return tuple(r.text(v, f"provenance.{key}[{i}]") for i, v in enumerate(value))

    when = table.get("date")
    if when is not None:
        if isinstance(when, str):
            try:
                when = datetime.fromisoformat(when)
            except ValueError:
                raise r.fail("provenance.date", f"expected a date-time, got {when!r}") from None
        elif isinstance(when, date) and not isinstance(when, datetime):
            when = datetime(when.year, when.month, when.day, tzinfo=UTC)
        if not isinstance(when, datetime):
            raise r.fail("provenance.date", f"expected a date-time, got {_show(when)}")
        if when.tzinfo is None:
            when = when.replace(tzinfo=UTC)
    return Provenance(
        imageform_version=opt("imageform_version", r.text),
        date=when,
        command=opt("command", r.text),
        based_on=opt("based_on", r.text),
        rms_px=opt("rms_px", lambda v, k: _nonneg(r, v, k)),
        views_used=opt("views_used", r.count),
        points_used=opt("points_used", r.count),
        images=strings("images"),
        fixed=strings("fixed"),
    )


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
