"""The stereo camera file: two camera files in one TOML, the right one posed in the left's frame.

A stereo file holds the two cameras of a rig as the tables of the single-camera file
(docs/camera-file.md) under ``[left.*]`` and ``[right.*]``. The rig's frame is the left
camera's, so the left camera has no pose and the right camera's ``[right.pose]`` is the
relative pose of ``cv2.stereoCalibrate``: ``X_right = R X_left + T`` (``R``, ``t``), with its
standard deviations in ``[right.std]`` (``rvec``, ``t``). In short::

    format = "imageform-stereo"     # required marker
    version = 1                     # required; a newer version is refused
    [left.image] [left.intrinsics] [left.distortion] [left.std] [left.provenance]
    [right.image] [right.intrinsics] [right.distortion] [right.pose] [right.std] ...
    [provenance]   the rig's: imageform_version, date, command, rms_px (both cameras), ...

Every key of each camera is read with the rules of :func:`~imageform.io.read_camera`.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._files import atomic_write, check_writable
from imageform._validate import as_path, describe
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.io._camera_model import (
    _TABLES,
    CAMERA_FILE_FORMAT,
    CameraFile,
    Provenance,
    Reader,
    image_names,
    short_list,
)
from imageform.io.camera_file import _toml_string, _toml_value, camera_file_text

if TYPE_CHECKING:
    from imageform.geometry import StereoCalibrationResult

__all__ = [
    "STEREO_FILE_FORMAT",
    "STEREO_FILE_VERSION",
    "StereoCameraFile",
    "read_stereo_camera",
    "write_stereo_camera",
]

#: The value of the ``format`` key that marks a stereo camera file.
STEREO_FILE_FORMAT = "imageform-stereo"
#: The version this imageform writes (and the newest it reads).
STEREO_FILE_VERSION = 1
_SIDES = ("left", "right")


@dataclass(frozen=True)
class StereoCameraFile:
    """A stereo file's content: two camera files and the rig's provenance.

    Attributes
    ----------
    left : CameraFile
        The left camera, without a pose (the rig's frame is the left camera's).
    right : CameraFile
        The right camera, posed in the left camera's frame: ``X_right = R X_left + T``.
    provenance : Provenance
        The rig's: the command, the RMS of both cameras, the views used, the date.
    version : int
        The file's format version.
    path : Path or None
        The file it was read from.
    """

    left: CameraFile
    right: CameraFile
    provenance: Provenance = field(default_factory=Provenance)
    version: int = STEREO_FILE_VERSION
    path: Path | None = None

    def __post_init__(self) -> None:
        """Check both sides: two camera files, the left without a pose, the right with one."""
        for side in _SIDES:
            if not isinstance(getattr(self, side), CameraFile):
                raise InvalidInputError(
                    f"expected {side} to be an imageform.io.CameraFile, got "
                    f"{type(getattr(self, side)).__name__}"
                )
        if self.left.has_pose:
            raise InvalidInputError(
                "expected the left camera without a pose (the rig's frame is the left camera's)"
            )
        if not self.right.has_pose:
            raise InvalidInputError(
                "expected the right camera with its pose in the left camera's frame (R, T)"
            )

    @property
    def R(self) -> np.ndarray:
        """Rotation left to right camera, ``X_right = R X_left + T``."""
        return np.asarray(self.right.camera.R, dtype=np.float64)

    @property
    def T(self) -> np.ndarray:
        """Translation left to right camera (object-point units)."""
        return np.asarray(self.right.camera.t, dtype=np.float64)

    @property
    def std_rvec(self) -> np.ndarray | None:
        """Standard deviations of ``rvec(R)`` (radians), or None if not stored."""
        v = self.right.std.get("rvec")
        return None if v is None else np.asarray(v, dtype=np.float64)

    @property
    def std_T(self) -> np.ndarray | None:
        """Standard deviations of ``T``, or None if not stored."""
        v = self.right.std.get("t")
        return None if v is None else np.asarray(v, dtype=np.float64)

    @classmethod
    def from_calibration(
        cls,
        result: StereoCalibrationResult,
        *,
        images_left: tuple[str, ...] | list[str] = (),
        images_right: tuple[str, ...] | list[str] = (),
        command: str | None = None,
    ) -> StereoCameraFile:
        """Build the stereo file of a :func:`~imageform.geometry.stereo_calibrate` result."""
        from imageform.geometry import StereoCalibrationResult

        if not isinstance(result, StereoCalibrationResult):
            raise TypeError(
                "expected result as a StereoCalibrationResult (stereo_calibrate), "
                f"got {describe(result)}"
            )
        left = CameraFile.from_calibration(
            result.left, images=image_names(images_left, "images_left")
        )
        right = CameraFile.from_calibration(
            result.right, images=image_names(images_right, "images_right")
        )
        std = dict(right.std)
        std["rvec"] = tuple(float(v) for v in result.std_rvec)
        std["t"] = tuple(float(v) for v in result.std_T)
        right = replace(right.with_pose(result.R, result.T), std=std, provenance=right.provenance)
        prov = Provenance(
            command=command,
            rms_px=float(result.rms),
            views_used=int(result.per_view_rms.shape[0]),
            fixed=("intrinsics",) if result.fixed_intrinsics else (),
        )
        return cls(left, right, prov)


def _side_text(cf: CameraFile, side: str) -> list[str]:
    """Return the tables of a camera file under ``[side.*]`` (no format, version, comments)."""
    out: list[str] = []
    for line in camera_file_text(cf).splitlines():
        if line.startswith(("format =", "version =")) or (line.startswith("#") and not out):
            continue
        m = re.fullmatch(r"\[([\w.]+)\]", line)
        out.append(f"[{side}.{m.group(1)}]" if m else line)
    while out and not out[0]:
        out.pop(0)
    return out


def stereo_file_text(sf: StereoCameraFile) -> str:
    """Return the TOML text of a stereo file (what :func:`write_stereo_camera` writes)."""
    lines = [
        '# imageform stereo camera file (docs/camera-file.md, "Stereo rigs"): two camera',
        "# files; the rig frame is the left camera's: X_right = R X_left + T ([right.pose]).",
        f"format = {_toml_string(STEREO_FILE_FORMAT)}",
        f"version = {STEREO_FILE_VERSION}",
    ]
    for side in _SIDES:
        lines += ["", *_side_text(getattr(sf, side), side)]
    lines += ["", "[provenance]"]
    for name in _TABLES["provenance"]:
        v = getattr(sf.provenance, name)
        if v is None or v == ():
            continue
        lines.append(f"{name} = {_toml_value(list(v) if isinstance(v, tuple) else v)}")
    return "\n".join(lines) + "\n"


def write_stereo_camera(path: str | Path, stereo: StereoCameraFile) -> Path:
    """Write a stereo camera file atomically.

    Parameters
    ----------
    path : str or Path
        The ``.toml`` file to write (overwritten).
    stereo : StereoCameraFile
        What to write (``StereoCameraFile.from_calibration(result)`` for a
        :func:`~imageform.geometry.stereo_calibrate` result).

    Returns
    -------
    Path
        ``path``; the rig's ``provenance.imageform_version`` and ``date`` are filled in
        when not given.
    """
    from imageform import __version__

    final = check_writable(path, "path")
    if not isinstance(stereo, StereoCameraFile):
        raise InvalidInputError(
            f"expected stereo to be a StereoCameraFile, got {type(stereo).__name__}"
        )
    prov = replace(
        stereo.provenance,
        imageform_version=stereo.provenance.imageform_version or __version__,
        date=stereo.provenance.date or datetime.now(UTC).replace(microsecond=0),
    )
    text = stereo_file_text(replace(stereo, provenance=prov))
    atomic_write(final, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return final


def read_stereo_camera(path: str | Path) -> StereoCameraFile:
    """Read a stereo camera file (docs/camera-file.md, "Stereo rigs").

    Parameters
    ----------
    path : str or Path
        A TOML stereo file.

    Returns
    -------
    StereoCameraFile
        ``left``, ``right`` (CameraFile; ``right.camera.R, t`` are ``R, T``), ``R``,
        ``T``, ``std_rvec``, ``std_T``, ``provenance``.

    Raises
    ------
    InvalidInputError
        A missing file, invalid TOML, a wrong ``format``, a newer ``version``, a missing
        camera, a left camera with a pose or a right camera without one, and every error of
        :func:`~imageform.io.read_camera` in either camera (naming ``[left]``/``[right]``).
    UnknownOptionError
        An unknown key.
    """
    from imageform.io._camera_read import _provenance, parse

    p = as_path(path, "path")
    if not p.is_file():
        raise InvalidInputError(f"stereo camera file {p} does not exist")
    try:
        data: dict[str, Any] = tomllib.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InvalidInputError(
            f"{p} is not a stereo camera file: not text (the file is TOML, as "
            "imageform stereo-calibrate writes it)"
        ) from None
    except OSError as exc:
        raise InvalidInputError(f"cannot read stereo camera file {p}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{p}: not valid TOML: {exc}") from None
    r = Reader(str(p))
    fmt = data.get("format")
    if fmt != STEREO_FILE_FORMAT:
        hint = (
            " (a single camera's file, as calibrate writes, which read_camera reads; a stereo "
            "camera file is written by "
            "imageform stereo-calibrate, or stereo_calibrate and write_stereo_camera)"
            if fmt == CAMERA_FILE_FORMAT
            else ""
        )
        raise r.fail("format", f"expected {STEREO_FILE_FORMAT!r}, got {fmt!r}{hint}")
    if "version" not in data:
        raise r.fail("version", "missing (the format version, 1)")
    version = r.count(data["version"], "version", minimum=1)
    if version > STEREO_FILE_VERSION:
        raise r.fail(
            "version",
            f"version {version} is newer than this imageform reads ({STEREO_FILE_VERSION}); "
            "upgrade imageform",
        )
    unknown = [k for k in data if k not in ("format", "version", "provenance", *_SIDES)]
    if unknown:
        raise UnknownOptionError(
            f"{p}: unknown key(s) {short_list(unknown, 40)}; valid: format, version, left, right, "
            "provenance"
        )
    cams = {}
    for side in _SIDES:
        if side not in data:
            raise r.fail(side, f"missing (the {side} camera's tables [{side}.intrinsics] ...)")
        table = r.table(data, side)
        cams[side] = parse({"format": CAMERA_FILE_FORMAT, "version": 1, **table}, f"{p} [{side}]")
    prov_table = r.table(data, "provenance")
    r.known(prov_table, _TABLES["provenance"], "provenance.")
    prov = _provenance(prov_table, r)
    if cams["left"].has_pose:
        raise r.fail("left.pose", "the left camera defines the rig's frame: give no pose")
    if not cams["right"].has_pose:
        raise r.fail("right.pose", "missing (R, t: X_right = R X_left + T)")
    return StereoCameraFile(cams["left"], cams["right"], prov, version, p)
