"""Projection models besides the pinhole: orthographic, weak perspective, cone-beam X-ray.

- **Orthographic** (microscopy, telecentric lenses): rays parallel to the optical axis,
  ``u = s_x X_c + c_x``; depth does not change size. Matrix form
  ``P = [[s_x, 0, 0, c_x], [0, s_y, 0, c_y], [0, 0, 0, 1]] [R | t; 0 1]`` (affine camera,
  Hartley & Zisserman §6.3.1).
- **Weak perspective** (scaled orthographic): every point is scaled by one reference depth
  ``Z₀``, ``u = f_x X_c / Z₀ + c_x``; exact when the object's depth range is small against
  ``Z₀`` (H&Z §6.3.1).
- **Cone-beam X-ray**: a point source, the object, and a flat detector at the
  source-to-detector distance (SDD). It is a pinhole with the source as centre and
  ``f = SDD``; an object at the source-to-object distance (SOD) is magnified by
  ``M = SDD / SOD`` (Bushberg et al., *The Essential Physics of Medical Imaging*, ch. 7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform._backend import common_device, device_of, namespace
from imageform._typing import Array, ArrayLike, FloatArray
from imageform._validate import (
    MAX_MAGNITUDE,
    any_value,
    as_matrix_bounded,
    as_points_bounded,
    as_real,
    check_image_size,
    check_K,
    check_rotation,
    real_pair,
    shape_text,
)
from imageform.errors import InvalidInputError
from imageform.geometry.camera import Projection, project_points

__all__ = [
    "ConeBeamGeometry",
    "orthographic_matrix",
    "orthographic_project",
    "weak_perspective_matrix",
    "weak_perspective_project",
]


def _world_to_cam(
    points: ArrayLike, R: ArrayLike | None, t: ArrayLike | None, K: ArrayLike | None = None
) -> tuple[Any, Array]:
    xp = namespace(points, R, t, K)
    X = as_points_bounded(points, "points", 3, xp=xp, device=common_device(points, R, t, K))
    if R is not None:
        Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=X.dtype, device=device_of(X))
        check_rotation(Rm, "R", xp=xp)
        X = X @ xp.matrix_transpose(Rm)
    if t is not None:
        X = X + as_points_bounded(t, "t", 3, xp=xp, dtype=X.dtype, device=device_of(X))
    return xp, X


def orthographic_project(
    points: ArrayLike,
    scale: float | tuple[float, float] = 1.0,
    principal_point: tuple[float, float] = (0.0, 0.0),
    R: ArrayLike | None = None,
    t: ArrayLike | None = None,
) -> Array:
    """Orthographic projection ``u = s_x X_c + c_x``, ``v = s_y Y_c + c_y``.

    ``scale`` is pixels per world unit (for a microscope: magnification / pixel pitch).
    Every point images, whatever its depth (no ``z > 0`` condition: parallel rays).

    Examples
    --------
    A 40× objective on a 6.5 µm-pitch camera: 40 / 6.5 px per µm.

    >>> orthographic_project([[13.0, 0.0, 2.0], [13.0, 0.0, 50.0]], 40 / 6.5).round(6)
    array([[80.,  0.],
           [80.,  0.]])
    """
    sx, sy = real_pair(scale, "scale", positive=True, scalar_ok=True)
    cx, cy = real_pair(principal_point, "principal_point")
    xp, X = _world_to_cam(points, R, t)
    return xp.stack((sx * X[..., 0] + cx, sy * X[..., 1] + cy), axis=-1)


def orthographic_matrix(
    scale: float | tuple[float, float] = 1.0, principal_point: tuple[float, float] = (0.0, 0.0)
) -> FloatArray:
    """Build the 3×4 affine camera of :func:`orthographic_project` (last row ``(0, 0, 0, 1)``).

    Examples
    --------
    >>> orthographic_matrix(2.0, (10.0, 5.0))
    array([[ 2.,  0.,  0., 10.],
           [ 0.,  2.,  0.,  5.],
           [ 0.,  0.,  0.,  1.]])
    """
    sx, sy = real_pair(scale, "scale", positive=True, scalar_ok=True)
    cx, cy = real_pair(principal_point, "principal_point")
    return np.array([[sx, 0, 0, cx], [0, sy, 0, cy], [0, 0, 0, 1.0]], dtype=np.float64)


def weak_perspective_project(
    points: ArrayLike,
    K: ArrayLike,
    R: ArrayLike | None = None,
    t: ArrayLike | None = None,
    *,
    depth: float | None = None,
) -> Array:
    r"""Weak-perspective projection with one reference depth ``Z₀`` for all points.

    .. math:: u = f_x X_c / Z_0 + s\, Y_c / Z_0 + c_x, \quad v = f_y Y_c / Z_0 + c_y

    ``Z₀`` defaults to the mean camera-frame depth of the points (over the last point
    axis). ``Z₀ <= 0`` raises: the object is not in front of the camera.

    Examples
    --------
    >>> K = [[100, 0, 0], [0, 100, 0], [0, 0, 1]]
    >>> weak_perspective_project([[3.0, -1.0, 4.0], [3.0, -1.0, 6.0]], K)   # Z0 = 5
    array([[ 60., -20.],
           [ 60., -20.]])
    """
    xp, X = _world_to_cam(points, R, t, K)
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=X.dtype, device=device_of(X))
    check_K(Km, xp)
    if depth is None:
        if X.ndim >= 2 and X.shape[-2] == 0:
            raise InvalidInputError(
                "expected points with at least one point for the mean depth Z0 (or pass "
                "depth=), got shape " + shape_text(X)
            )
        z0 = xp.mean(X[..., 2], axis=-1, keepdims=True) if X.ndim >= 2 else X[..., 2]
    else:
        d = as_real(depth, "depth", positive=True, maximum=MAX_MAGNITUDE)
        z0 = xp.asarray(d, dtype=X.dtype, device=device_of(X))
    if any_value(~(z0 > 0), xp):
        raise InvalidInputError("weak perspective needs a reference depth Z0 > 0 (object in front)")
    x = X[..., 0] / z0
    y = X[..., 1] / z0
    k = Km / Km[..., 2:3, 2:3]
    u = k[..., 0, 0] * x + k[..., 0, 1] * y + k[..., 0, 2]
    v = k[..., 1, 1] * y + k[..., 1, 2]
    return xp.stack((u, v), axis=-1)


def weak_perspective_matrix(K: ArrayLike, depth: float) -> FloatArray:
    """Build the 3×4 camera ``K [[1,0,0,0],[0,1,0,0],[0,0,0,Z₀]]`` (camera frame in, pixels out).

    Examples
    --------
    >>> weak_perspective_matrix([[100, 0, 0], [0, 100, 0], [0, 0, 1]], 5.0)
    array([[100.,   0.,   0.,   0.],
           [  0., 100.,   0.,   0.],
           [  0.,   0.,   0.,   5.]])
    """
    z0 = as_real(depth, "depth", positive=True, maximum=MAX_MAGNITUDE)
    Km = np.asarray(as_matrix_bounded(K, "K", (3, 3), batch=False), dtype=np.float64)
    return Km @ np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, z0]])


@dataclass(frozen=True)
class ConeBeamGeometry:
    """A point X-ray source, a flat detector, and the object in between.

    Coordinates: the source at the origin, z towards the detector (the camera frame with
    the source as pinhole). ``source_to_detector`` (SDD) and ``source_to_object`` (SOD) in
    mm; ``pixel_pitch`` of the detector in mm; ``detector_shape`` = (columns, rows).
    The image is the shadow on the detector: a pinhole projection with ``f = SDD``.

    Examples
    --------
    A chest radiograph: SDD = 1800 mm, the patient's mid-plane at SOD = 1600 mm.

    >>> g = ConeBeamGeometry(1800.0, 1600.0, 0.15, (2800, 2800))
    >>> g.magnification
    1.125
    >>> round(g.object_pixel_size, 6)        # mm at the object plane
    0.133333
    >>> g.penumbra(1.2)                      # geometric unsharpness of a 1.2 mm focal spot
    0.15
    """

    source_to_detector: float
    source_to_object: float
    pixel_pitch: float
    detector_shape: tuple[int, int]
    principal_point: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        """Check the distances (object between source and detector), pitch and detector."""
        sdd = as_real(self.source_to_detector, "source_to_detector", positive=True, maximum=1e50)
        sod = as_real(self.source_to_object, "source_to_object", positive=True, maximum=1e50)
        pitch = as_real(self.pixel_pitch, "pixel_pitch", positive=True, maximum=1e50)
        if sod > sdd:
            raise InvalidInputError(
                f"expected source_to_object <= source_to_detector (the object between source "
                f"and detector), got source_to_object {sod:g} > source_to_detector {sdd:g}"
            )
        if sdd / pitch > MAX_MAGNITUDE or sdd / sod > MAX_MAGNITUDE:
            raise InvalidInputError(
                f"expected source_to_detector / pixel_pitch and / source_to_object <= "
                f"{MAX_MAGNITUDE:g}, got source_to_detector {sdd:g}, pixel_pitch {pitch:g}, "
                f"source_to_object {sod:g}"
            )
        object.__setattr__(self, "source_to_detector", sdd)
        object.__setattr__(self, "source_to_object", sod)
        object.__setattr__(self, "pixel_pitch", pitch)
        object.__setattr__(
            self, "detector_shape", check_image_size(self.detector_shape, "detector_shape")
        )
        if self.principal_point is not None:
            object.__setattr__(
                self, "principal_point", real_pair(self.principal_point, "principal_point")
            )

    @property
    def magnification(self) -> float:
        """``M = SDD / SOD`` for an object at the source-to-object distance."""
        return float(self.source_to_detector) / float(self.source_to_object)

    @property
    def object_pixel_size(self) -> float:
        """Detector pixel pitch referred to the object plane, ``pitch / M`` (mm)."""
        return float(self.pixel_pitch) / self.magnification

    def penumbra(self, focal_spot_size: float) -> float:
        """Geometric unsharpness ``U = F (SDD - SOD) / SOD`` at the detector (mm)."""
        f = as_real(focal_spot_size, "focal_spot_size", positive=True, maximum=MAX_MAGNITUDE)
        return f * (self.source_to_detector - self.source_to_object) / self.source_to_object

    @property
    def K(self) -> FloatArray:
        """Detector 'intrinsics': ``f = SDD / pitch`` pixels, principal point at the centre."""
        w, h = self.detector_shape
        cx, cy = (
            self.principal_point if self.principal_point is not None else ((w - 1) / 2, (h - 1) / 2)
        )
        f = self.source_to_detector / self.pixel_pitch
        return np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])

    @property
    def fan_angle(self) -> float:
        """Full cone angle across the detector width (radians)."""
        w, _ = self.detector_shape
        return 2.0 * math.atan(w * self.pixel_pitch / 2.0 / self.source_to_detector)

    def project(self, points: ArrayLike) -> Projection:
        """Detector pixels of points ``(..., 3)`` in the source frame (mm); NaN behind it."""
        return project_points(points, self.K)
