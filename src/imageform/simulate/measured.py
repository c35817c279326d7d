"""A measured camera in the simulator (:func:`apply_camera_file`).

A camera file's ``[sensor]``, ``[optics]`` and ``[color]`` tables (docs/camera-file.md) are
turned into the simulator's sensor model, lens blur and processing (docs/simulate.md, "A
measured camera").

The camera file overrides the scene: each key present replaces the scene's value; a key or
table absent leaves the scene's as it is (a file without these tables renders exactly as
before).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._validate import describe
from imageform.errors import InvalidInputError
from imageform.io import CameraFile
from imageform.simulate.measured_sensor import MeasuredCamera
from imageform.simulate.scene import Scene

__all__ = ["apply_camera_file"]


def apply_camera_file(scene: Scene, camera_file: CameraFile) -> Scene:
    """``scene`` seen through a camera file: its geometry and its measured tables.

    Geometry: the file's K, distortion and image size, and its pose if it has one (else the
    scene's camera pose). ``[sensor]``: :func:`measured_sensor` (and ``cfa`` replaces
    ``sensor.cfa``). ``[optics]``: the file's blur (:func:`measured_optics_blur`) replaces the
    scene's lens blur (``lens.defocus`` and ``lens.diffraction`` off; ``f_number`` the file's
    when given). ``[color]``: ``white_balance`` gains replace ``processing.white_balance``,
    ``ccm`` replaces ``processing.color_correction``, sensitivities the sensor's QE curves.
    Values the file gives win over the scene's.

    Examples
    --------
    >>> from imageform.geometry import Camera
    >>> from imageform.simulate import default_scene
    >>> cam = Camera([[100.0, 0, 79.5], [0, 100.0, 59.5], [0, 0, 1]], image_size=(160, 120))
    >>> s = apply_camera_file(default_scene(), CameraFile(cam, sensor={"read_noise_e": 7.5}))
    >>> s.image_size, s.sensor.read_noise
    ((160, 120), 7.5)
    """
    from imageform.geometry import Camera

    if not isinstance(scene, Scene):
        raise TypeError(f"expected scene as a Scene (load_scene), got {describe(scene)}")
    if not isinstance(camera_file, CameraFile):
        raise TypeError(
            f"expected camera_file as an imageform.io.CameraFile (read_camera), got "
            f"{describe(camera_file)}"
        )
    cam = camera_file.camera
    where = camera_file.path if camera_file.path is not None else "camera file"
    if cam.image_size is None:
        raise InvalidInputError(
            f"{where}: the camera file has no image size ([image] width, height) to render"
        )
    if not camera_file.has_pose:
        here = scene.camera
        cam = Camera(cam.K, here.R, here.t, cam.image_size, cam.image_plane, cam.distortion)
    measured = MeasuredCamera(camera_file.sensor, camera_file.optics, camera_file.color)
    fx = float(np.asarray(cam.K)[0, 0])
    focal_mm = None
    if camera_file.optics is not None:
        pitch = camera_file.sensor.pixel_pitch_um if camera_file.sensor is not None else None
        if camera_file.optics.focal_length_mm is not None:
            focal_mm = camera_file.optics.focal_length_mm
        elif pitch is not None:
            focal_mm = fx * pitch * 1e-3
    out = scene.with_camera(cam, focal_length_mm=focal_mm)
    changes: dict[str, Any] = {}
    if camera_file.sensor is not None and camera_file.sensor.cfa is not None:
        changes["sensor"] = {"cfa": camera_file.sensor.cfa}
    if camera_file.optics is not None:
        lens: dict[str, Any] = {"defocus": False, "diffraction": False, "psf": "geometric"}
        if camera_file.optics.f_number is not None:
            lens["f_number"] = camera_file.optics.f_number
        changes["lens"] = lens
    color = camera_file.color
    if color is not None:
        proc: dict[str, Any] = {}
        if color.white_balance is not None:
            proc["white_balance"] = "none"  # the file's gains are applied instead
        if color.ccm is not None:
            proc["color_correction"] = "none"  # the file's matrix is applied instead
        if proc:
            changes["processing"] = proc
    if changes:
        out = out.with_changes(**changes)
    if measured.empty:
        return out
    return out.with_measured(measured)
