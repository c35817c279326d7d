"""imageform.geometry — camera geometry: from a 3-D point to a pixel and back.

Conventions (``docs/conventions.md``): camera frame x right, y down, z forward;
``X_cam = R @ X_world + t``; ``P = K [R | t]``; pixel ``(u, v)`` = (column, row) with the
top-left pixel centre at (0, 0); points are row vectors ``(..., N, 3)``; points with
``z_cam <= 0`` are NaN with ``valid = False``.
"""

from imageform.geometry.camera import (
    Camera,
    Projection,
    backproject,
    decompose_projection_matrix,
    project_points,
    projection_matrix,
    unproject,
)
from imageform.geometry.homogeneous import (
    are_collinear,
    cross_ratio,
    from_homogeneous,
    intersect_lines,
    line_through,
    to_homogeneous,
)
from imageform.geometry.intrinsics import Intrinsics, intrinsic_matrix, projected_size
from imageform.geometry.rotations import (
    axis_rotation,
    camera_rotation,
    euler_to_matrix,
    is_rotation,
    look_at,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rvec,
    quaternion_to_matrix,
    rvec_to_matrix,
)

__all__ = [
    "Camera",
    "Intrinsics",
    "Projection",
    "are_collinear",
    "axis_rotation",
    "backproject",
    "camera_rotation",
    "cross_ratio",
    "decompose_projection_matrix",
    "euler_to_matrix",
    "from_homogeneous",
    "intersect_lines",
    "intrinsic_matrix",
    "is_rotation",
    "line_through",
    "look_at",
    "matrix_to_euler",
    "matrix_to_quaternion",
    "matrix_to_rvec",
    "project_points",
    "projected_size",
    "projection_matrix",
    "quaternion_to_matrix",
    "rvec_to_matrix",
    "to_homogeneous",
    "unproject",
]
