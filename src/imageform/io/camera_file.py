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
    [sensor]       the EMVA 1288 noise model (optional; CameraSensor)
    [optics]       the lens's blur: diffraction, zernike, gaussian or mtf50 (optional)
    [color]        white balance, CCM, illuminant, spectral sensitivities (optional)

Files written by earlier imageform versions (keys ``fx fy cx cy skew width height k1 k2 p1 p2
k3 ... rvec/R t`` at the top level or in ``[camera]``, plus the ``[calibration]`` table of
``CalibrationResult.to_toml``) are read too, with the same checks.

The module imports :mod:`imageform.geometry` only when a camera is built, so importing
:mod:`imageform.io` stays cheap.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._files import atomic_write, check_writable
from imageform._validate import as_bool, as_path, describe
from imageform.io._camera_model import (
    _ALWAYS,
    _TABLES,
    CAMERA_FILE_FORMAT,
    CAMERA_FILE_VERSION,
    DISTORTION_MODELS,
    CameraFile,
    Provenance,
    distortion_name,
)
from imageform.io._camera_tables import (
    CCM_TARGETS,
    OPTICS_MODELS,
    CameraColor,
    CameraOptics,
    CameraSensitivity,
    CameraSensor,
)
from imageform.io._camera_toml import toml_string as _toml_string
from imageform.io._camera_toml import toml_value as _toml_value

if TYPE_CHECKING:
    from imageform.geometry import Camera

__all__ = [
    "CAMERA_FILE_FORMAT",
    "CAMERA_FILE_VERSION",
    "CCM_TARGETS",
    "DISTORTION_MODELS",
    "OPTICS_MODELS",
    "CameraColor",
    "CameraFile",
    "CameraOptics",
    "CameraSensitivity",
    "CameraSensor",
    "Provenance",
    "distortion_name",
    "read_camera",
    "write_camera",
]

# ---------------------------------------------------------------- reading


def read_camera(path: str | Path) -> CameraFile:
    r"""Read a camera file (the versioned format, or a file from an earlier imageform).

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
    >>> _ = p.write_text("fx = 500\nfy = 500\ncx = 320\ncy = 240\nk1 = -0.1\n")
    >>> cf = read_camera(p)
    >>> cf.camera.K[0].tolist(), cf.distortion_model, cf.has_pose, cf.version
    ([500.0, 0.0, 320.0], 'brown_conrady', False, 0)
    """
    from imageform.io._camera_toml import load_toml

    p = as_path(path, "path")
    data = load_toml(
        p, "camera file", "the TOML that imageform calibrate writes (docs/camera-file.md)"
    )
    from imageform.io._camera_read import parse

    return replace(parse(data, str(p)), path=p)


# ---------------------------------------------------------------- writing


def camera_file_text(cf: CameraFile) -> str:
    """Return the TOML text of a camera file (what :func:`write_camera` writes)."""
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
    from imageform.io._camera_tables import table_lines

    for table in (cf.sensor, cf.optics, cf.color):
        lines += table_lines(table)
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
    sensor: CameraSensor | Mapping[str, Any] | None = None,
    optics: CameraOptics | Mapping[str, Any] | None = None,
    color: CameraColor | Mapping[str, Any] | None = None,
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
    sensor, optics, color : CameraSensor, CameraOptics, CameraColor or mapping, optional
        The measured-camera tables ``[sensor]``, ``[optics]``, ``[color]`` (a mapping of a
        table's keys is checked as the dataclass); given, they replace those of ``camera``.

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

    final = check_writable(path, "path")
    cf = camera if isinstance(camera, CameraFile) else CameraFile(camera)
    if has_pose is not None:
        cf = replace(cf, has_pose=as_bool(has_pose, "has_pose"))
    if std is not None:
        if not isinstance(std, Mapping):
            raise TypeError(f"expected std as a mapping of name to value, got {describe(std)}")
        cf = replace(cf, std=dict(std))
    from imageform.io._camera_tables import as_table

    measured = {
        name: as_table(value, name)
        for name, value in (("sensor", sensor), ("optics", optics), ("color", color))
        if value is not None
    }
    if measured:
        cf = replace(cf, **measured)
    if provenance is not None and not isinstance(provenance, Provenance):
        raise TypeError(f"expected provenance as a Provenance, got {describe(provenance)}")
    prov = provenance if provenance is not None else cf.provenance
    prov = replace(
        prov,
        imageform_version=prov.imageform_version or __version__,
        date=prov.date or datetime.now(UTC).replace(microsecond=0),
    )
    text = camera_file_text(replace(cf, provenance=prov))
    atomic_write(final, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return final
