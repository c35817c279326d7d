"""Reading a camera file: every key checked, one-line errors naming the file and the key.

The internals of :func:`imageform.io.read_camera`; the schema is in docs/camera-file.md.
"""

from __future__ import annotations

import math
from dataclasses import replace
from datetime import UTC, date, datetime
from typing import Any, Literal

import numpy as np

from imageform.errors import UnknownOptionError
from imageform.io._camera_model import (
    _CLASSES,
    _LEGACY_CALIBRATION,
    _LEGACY_KEYS,
    _TABLES,
    _TOP,
    CAMERA_FILE_FORMAT,
    CAMERA_FILE_VERSION,
    DISTORTION_MODELS,
    CameraFile,
    Provenance,
    Reader,
    _nonneg,
    check_std,
    distortion_name,
)
from imageform.io._camera_toml import _show, short_list

__all__ = ["parse"]


def parse(data: dict[str, Any], where: str) -> CameraFile:
    """Build the camera file of parsed TOML ``data`` (``where`` names it in messages)."""
    r = Reader(where)
    versioned = "format" in data or "version" in data
    return _read_v1(data, r) if versioned else _read_legacy(data, r)


def _read_v1(data: dict[str, Any], r: Reader) -> CameraFile:
    fmt = data.get("format")
    if fmt != CAMERA_FILE_FORMAT:
        hint = (
            " (a stereo camera file, as stereo-calibrate writes it: read_stereo_camera reads "
            "it; each camera is one of its [left] and [right] tables)"
            if fmt == "imageform-stereo"
            else ""
        )
        raise r.fail("format", f"expected {CAMERA_FILE_FORMAT!r}, got {_show(fmt)}{hint}")
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
    cf = _build(intr, image, dist, pose, tables["std"], prov, version, r, "")
    from imageform.io._camera_tables import CameraColor, CameraOptics, CameraSensor

    measured: dict[str, Any] = {}
    for name, cls in (("sensor", CameraSensor), ("optics", CameraOptics), ("color", CameraColor)):
        if name in data:
            measured[name] = cls.from_table(r.table(data, name), r)
    return replace(cf, **measured) if measured else cf


def _read_legacy(data: dict[str, Any], r: Reader) -> CameraFile:
    """Read files of imageform before the versioned format.

    Keys at the top level or in ``[camera]``; ``[calibration]`` with ``rms`` and ``views``.
    """
    cal = data.get("calibration", {})
    if "camera" in data:
        cam = data["camera"]
        if not isinstance(cam, dict):
            raise r.fail("camera", f"expected a table [camera], got {_show(cam)}")
        rest = [k for k in data if k not in ("camera", "calibration")]
        if rest:
            raise UnknownOptionError(
                f"{r.where}: unknown key(s) {short_list(rest, 40)} beside [camera]; valid: camera, "
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
            f"{r.where}: unknown key(s) {short_list([prefix + k for k in unknown], 40)}; "
            f"valid: {short_list(_LEGACY_KEYS, 40)} (or a version-1 file: "
            f'format = "{CAMERA_FILE_FORMAT}", version = {CAMERA_FILE_VERSION})'
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


def _build(
    intr: dict[str, Any],
    image: dict[str, Any],
    dist: dict[str, Any],
    pose: dict[str, Any],
    std: dict[str, Any],
    prov: Provenance,
    version: int,
    r: Reader,
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
    std_checked = check_std(dict(std), "std", r)
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


def _check_rotation(R: np.ndarray, key: str, r: Reader) -> None:
    err = float(np.max(np.abs(R @ R.T - np.eye(3))))
    if err > 1e-6:
        raise r.fail(key, f"expected a rotation matrix (R Rᵀ = I), max |R Rᵀ - I| = {err:.3g}")
    det = float(np.linalg.det(R))
    if abs(det - 1.0) > 1e-5:
        raise r.fail(key, f"expected a proper rotation (det R = +1), got det R = {det:.6g}")


def _provenance(table: dict[str, Any], r: Reader) -> Provenance:
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
