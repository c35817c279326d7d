"""The lecture's camera-geometry worked examples, computed by imageform.geometry."""

from __future__ import annotations

import numpy as np

from imageform.geometry import (
    Camera,
    Intrinsics,
    horizon_line,
    intrinsic_matrix,
    project_points,
    projected_size,
    vanishing_point,
)
from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]


def _building_pixels() -> float:
    cam = Camera(
        Intrinsics.from_physical(focal_length_mm=50.0, pixel_pitch_um=5.0, image_size=(6000, 4000))
    )
    top, bottom = cam.project([[0.0, -15.0, 100.0], [0.0, 15.0, 100.0]]).uv
    return float(bottom[1] - top[1])


def _point() -> tuple[float, float]:
    uv = project_points([3.0, -1.0, 5.0], intrinsic_matrix(100, 100, 0, 0)).uv
    return float(uv[0]), float(uv[1])


def _vp() -> tuple[float, float]:
    v = vanishing_point([[500, 0, 320], [0, 500, 240], [0, 0, 1]], [1.0, 0.0, 2.0])
    return float(v[0]), float(v[1])


def _horizon_level() -> float:
    line = horizon_line([[500, 0, 320], [0, 500, 240], [0, 0, 1]], np.eye(3))
    return float(-line[2] / line[1])


EXAMPLES: list[WorkedExample] = [
    WorkedExample(
        "pinhole",
        "A 30 m building 100 m away, f = 50 mm: height of its image?",
        "h = f H / Z",
        lambda: projected_size(30.0, 100.0, focal_length=50.0),
        15.0,
        "mm",
    ),
    WorkedExample(
        "pinhole",
        "... and in pixels at a 5 µm pixel pitch (through a Camera)?",
        "h_px = h / pitch = f H / (Z pitch)",
        _building_pixels,
        3000.0,
        "px",
        tol=1e-6,
    ),
    WorkedExample(
        "pinhole",
        "A 20 m building 80 m away, f = 35 mm: height of its image?",
        "h = f H / Z",
        lambda: projected_size(20.0, 80.0, focal_length=35.0),
        8.75,
        "mm",
    ),
    WorkedExample(
        "projection",
        "Project P = (3, -1, 5) with f = 100 px (principal point at the origin)",
        "(u, v) = (f X / Z, f Y / Z)",
        _point,
        (60.0, -20.0),
        "px",
    ),
    WorkedExample(
        "vanishing points",
        "K = [[500,0,320],[0,500,240],[0,0,1]], direction d = (1, 0, 2): vanishing point?",
        "v ~ K d",
        _vp,
        (570.0, 240.0),
        "px",
    ),
    WorkedExample(
        "vanishing points",
        "Same K, level camera: at which row is the horizon?",
        "l ~ K^-T R n, n = up",
        _horizon_level,
        240.0,
        "px (row)",
    ),
]
