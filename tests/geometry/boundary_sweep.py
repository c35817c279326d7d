"""A boundary sweep of :mod:`imageform.geometry` (issue 16): every public callable and public
method, called with malformed values one parameter at a time, the outcome classified.

Run as a module for the counts (``--full`` adds the slow callables' every parameter)::

    PYTHONPATH=src python -m tests.geometry.boundary_sweep [--list CLASS] [--only NAME]

Outcomes (the contract of issue 16):

- ``ok``: a result with no NaN/inf outside what a ``valid`` mask marks, or a clean error:
  an :class:`~imageform.errors.ImageformError` or ``TypeError`` in one line of at most 200
  characters naming the parameter;
- ``raw``: any other exception (numpy's IndexError, LinAlgError, OverflowError ...);
- ``nan``: a result holding NaN or inf that no mask explains (or an object or string
  array where numbers belong);
- ``warning``: a warning that is not an :class:`~imageform.errors.ImageformWarning`
  (RuntimeWarning, ComplexWarning ...);
- ``message``: a clean error type whose message is multi-line or over 200 characters;
- ``unnamed``: a clean error type whose message does not name the parameter (a
  ``DegenerateConfigurationError`` or ``ConvergenceError`` is about the data as a whole
  and need not);
- ``timeout``: the call ran past the time guard.

Every call runs in this process under a time guard (``signal.setitimer``) with
``IMAGEFORM_MAX_MEMORY`` set low, inside a temporary working directory.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import os
import signal
import sys
import tempfile
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

__all__ = ["CASES", "Outcome", "baseline_failures", "classify", "malformed", "run_sweep"]

OK_CLASSES = ("ok",)
FAIL_CLASSES = ("raw", "nan", "warning", "message", "unnamed", "timeout")


class _Timeout(BaseException):
    """Raised by the time guard (a BaseException so that no ``except Exception`` eats it)."""


@contextlib.contextmanager
def _time_guard(seconds: float) -> Iterator[None]:
    if seconds <= 0 or not hasattr(signal, "setitimer"):
        yield
        return

    def handler(signum: int, frame: object) -> None:
        raise _Timeout

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


# ---------------------------------------------------------------------------------------
# valid inputs


def _fixtures() -> dict[str, Any]:
    from imageform.geometry import (
        BrownConrady,
        Camera,
        checkerboard_points,
        project_points,
        rvec_to_matrix,
    )

    rng = np.random.default_rng(0)
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    R = rvec_to_matrix(np.array([0.1, -0.2, 0.05]))
    t = np.array([0.1, -0.2, 5.0])
    pts3 = rng.uniform(-1.0, 1.0, (12, 3))
    uv = project_points(pts3, K, R, t).uv
    board = checkerboard_points((5, 4), 0.1)
    poses = [(0.2, -0.1, 0.0), (-0.25, 0.2, 0.1), (0.1, 0.3, -0.1), (-0.3, -0.2, 0.05)]
    img_pts = [
        project_points(board, K, rvec_to_matrix(np.array(r)), np.array([-0.2, -0.15, 1.0])).uv
        for r in poses
    ]
    grey = np.zeros((48, 64))
    grey[10:38, 12:52] = 1.0
    grey = grey * 0.8 + 0.1
    rgb = np.repeat(grey[..., None], 3, axis=-1)
    yy, xx = np.mgrid[0:60, 0:80]
    board_img = (((xx // 12) + (yy // 12)) % 2).astype(np.float64) * 0.8 + 0.1
    corners = np.array([[24.0, 24.0], [36.0, 24.0], [24.0, 36.0]]) + 0.3
    P1 = K @ np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = K @ np.hstack([R, t[:, None]])
    X = pts3 + np.array([0.0, 0.0, 6.0])
    x1 = X[:, :2] / X[:, 2:] * 800 + [320, 240]
    Xc = X @ R.T + t
    x2 = Xc[:, :2] / Xc[:, 2:] * 800 + [320, 240]
    map_uv = np.stack(np.meshgrid(np.arange(64.0), np.arange(48.0)), axis=-1) + 0.25
    return {
        "K": K,
        "R": R,
        "t": t,
        "pts3": pts3,
        "uv": uv,
        "board": board,
        "img_pts": img_pts,
        "grey": grey,
        "rgb": rgb,
        "board_img": board_img,
        "corners": corners,
        "Ps": np.stack([P1, P2]),
        "x12": np.stack([x1, x2]),
        "map_uv": map_uv,
        "dist": BrownConrady(k1=-0.1, k2=0.01),
        "camera": Camera(K, R, t, image_size=(640, 480)),
        "q": np.array([0.9, 0.1, -0.2, 0.3]) / np.linalg.norm([0.9, 0.1, -0.2, 0.3]),
    }


@dataclasses.dataclass(frozen=True)
class Case:
    """One public callable: a factory giving the callable (a bound method needs its
    instance) and the valid keyword arguments it is swept around."""

    name: str
    make: Callable[[dict[str, Any]], Callable[..., Any]]
    kwargs: Callable[[dict[str, Any]], dict[str, Any]]
    slow: bool = False
    skip: tuple[str, ...] = ()  # parameters not swept
    #: parameters whose NaN passes through to the result by design (``fill=nan`` marks
    #: pixels with no source; a NaN pixel of an image is resampled as NaN)
    nan_ok: tuple[str, ...] = ()


def _g(name: str) -> Callable[[dict[str, Any]], Callable[..., Any]]:
    def make(fx: dict[str, Any]) -> Callable[..., Any]:
        import imageform.geometry as geo

        obj: Any = geo
        for part in name.split("."):
            obj = getattr(obj, part)
        return obj  # type: ignore[no-any-return]

    return make


def _m(cls_fixture: Callable[[dict[str, Any]], Any], method: str) -> Any:
    return lambda fx: getattr(cls_fixture(fx), method)


def _intr(fx: dict[str, Any]) -> Any:
    from imageform.geometry import Intrinsics

    return Intrinsics(800.0, 810.0, 320.0, 240.0, image_size=(640, 480))


def _cone(fx: dict[str, Any]) -> Any:
    from imageform.geometry import ConeBeamGeometry

    return ConeBeamGeometry(1000.0, 500.0, 0.2, (64, 48))


def _calres(fx: dict[str, Any]) -> Any:
    from imageform.geometry import calibrate_camera

    return calibrate_camera([fx["board"]] * 4, fx["img_pts"], (640, 480))


def _segments(fx: dict[str, Any]) -> Any:
    from imageform.geometry import LineSegments

    e = np.array([[[0.0, 0.0], [50.0, 1.0]], [[3.0, 0.0], [4.0, 40.0]], [[0.0, 5.0], [30, 35]]])
    return LineSegments(e, np.ones(3), -np.ones(3))


def _board_result(fx: dict[str, Any]) -> Any:
    from imageform.geometry import CheckerboardResult

    return CheckerboardResult(True, np.arange(12.0).reshape(6, 2), pattern_size=(3, 2))


def _cases() -> list[Case]:
    c = Case
    return [
        # --- functions --------------------------------------------------------------------
        c(
            "apply_homography",
            _g("apply_homography"),
            lambda f: {"H": np.eye(3) + 0.01, "points": f["uv"]},
        ),
        c("are_collinear", _g("are_collinear"), lambda f: {"points": f["uv"][:3], "tol": 1e-9}),
        c("axis_rotation", _g("axis_rotation"), lambda f: {"axis": "x", "angle": 0.3}),
        c(
            "backproject",
            _g("backproject"),
            lambda f: {"uv": f["uv"], "K": f["K"], "R": f["R"], "image_plane": "virtual"},
        ),
        c(
            "calibrate_camera",
            _g("calibrate_camera"),
            lambda f: {
                "object_points": [f["board"]] * 4,
                "image_points": f["img_pts"],
                "image_size": (640, 480),
                "skew": False,
                "fix": (),
                "K_init": f["K"],
                "distortion_init": None,
                "method": "auto",
                "max_iter": 30,
                "tol": 1e-10,
            },
            slow=True,
        ),
        c(
            "camera_rotation",
            _g("camera_rotation"),
            lambda f: {"pitch": 0.1, "yaw": 0.2, "roll": 0.3},
        ),
        c(
            "checkerboard_points",
            _g("checkerboard_points"),
            lambda f: {"pattern_size": (5, 4), "square_size": 0.1},
        ),
        c(
            "cross_ratio",
            _g("cross_ratio"),
            lambda f: {"a": [0.0, 0.0], "b": [1.0, 1.0], "c": [2.0, 2.0], "d": [4.0, 4.0]},
        ),
        c(
            "decompose_projection_matrix",
            _g("decompose_projection_matrix"),
            lambda f: {"P": f["Ps"][1]},
        ),
        c(
            "detect_line_segments",
            _g("detect_line_segments"),
            lambda f: {
                "image": f["grey"],
                "sigma": 0.6,
                "angle_tolerance": 0.39,
                "min_length": 10.0,
                "log10_eps": 0.0,
                "min_density": 0.7,
            },
            slow=True,
        ),
        c(
            "detect_vanishing_points",
            _g("detect_vanishing_points"),
            lambda f: {
                "image": None,
                "segments": _segments(f),
                "image_size": (64, 48),
                "angle_threshold": 0.035,
                "n_candidates": 6,
                "max_trials": 50,
                "infinity_factor": 20.0,
                "rng": 0,
            },
            slow=True,
        ),
        c(
            "estimate_homography",
            _g("estimate_homography"),
            lambda f: {"src": f["uv"][:6], "dst": f["uv"][:6] * 1.1 + 3},
        ),
        c(
            "estimate_projection_matrix",
            _g("estimate_projection_matrix"),
            lambda f: {"points_3d": f["pts3"], "points_2d": f["uv"]},
        ),
        c(
            "euler_to_matrix",
            _g("euler_to_matrix"),
            lambda f: {"angles": [0.1, 0.2, 0.3], "order": "xyz"},
        ),
        c(
            "find_checkerboard",
            _g("find_checkerboard"),
            lambda f: {
                "image": f["board_img"],
                "pattern_size": (4, 3),
                "refine": True,
                "sigma": None,
                "half_window": 3,
                "max_iter": 30,
                "tol": 1e-3,
                "method": "symmetric",
            },
            slow=True,
        ),
        c(
            "find_checkerboards",
            _g("find_checkerboards"),
            lambda f: {"images": [f["board_img"]], "pattern_size": (4, 3), "names": ["a"]},
            slow=True,
        ),
        c(
            "focal_from_vanishing_points",
            _g("focal_from_vanishing_points"),
            lambda f: {
                "v1": [1000.0, 240.0],
                "v2": [-400.0, 240.0],
                "principal_point": [320.0, 240.0],
            },
        ),
        c(
            "from_homogeneous",
            _g("from_homogeneous"),
            lambda f: {"points": [[1.0, 2.0, 2.0]], "at_infinity": "raise"},
        ),
        c(
            "from_homogeneous_masked",
            _g("from_homogeneous_masked"),
            lambda f: {"points": [[1.0, 2.0, 2.0]]},
        ),
        c("horizon_line", _g("horizon_line"), lambda f: {"K": f["K"], "R": f["R"], "up": "-y"}),
        c(
            "intersect_lines",
            _g("intersect_lines"),
            lambda f: {"l1": [1.0, 0.0, -1.0], "l2": [0.0, 1.0, -2.0]},
        ),
        c(
            "intrinsic_matrix",
            _g("intrinsic_matrix"),
            lambda f: {"fx": 800.0, "fy": 800.0, "cx": 320.0, "cy": 240.0, "skew": 0.0},
        ),
        c(
            "intrinsics_from_vanishing_points",
            _g("intrinsics_from_vanishing_points"),
            lambda f: _vp3(f),
        ),
        c("is_rotation", _g("is_rotation"), lambda f: {"R": f["R"], "atol": 1e-6}),
        c("line_through", _g("line_through"), lambda f: {"p": [0.0, 0.0], "q": [1.0, 2.0]}),
        c(
            "lines_from_segments",
            _g("lines_from_segments"),
            lambda f: {"segments": [[[0.0, 0.0], [1.0, 2.0]], [[3.0, 1.0], [2.0, 5.0]]]},
        ),
        c(
            "look_at",
            _g("look_at"),
            lambda f: {"eye": [0.0, 0.0, -5.0], "target": [0.0, 0.0, 0.0], "up": (0.0, -1.0, 0.0)},
        ),
        c("matrix_to_euler", _g("matrix_to_euler"), lambda f: {"R": f["R"], "order": "xyz"}),
        c("matrix_to_quaternion", _g("matrix_to_quaternion"), lambda f: {"R": f["R"]}),
        c("matrix_to_rvec", _g("matrix_to_rvec"), lambda f: {"R": f["R"]}),
        c(
            "orthographic_matrix",
            _g("orthographic_matrix"),
            lambda f: {"scale": 2.0, "principal_point": (1.0, 2.0)},
        ),
        c(
            "orthographic_project",
            _g("orthographic_project"),
            lambda f: {
                "points": f["pts3"],
                "scale": 2.0,
                "principal_point": (1.0, 2.0),
                "R": f["R"],
                "t": f["t"],
            },
        ),
        c(
            "perspective_type",
            _g("perspective_type"),
            lambda f: {"directions": [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], "R": f["R"], "tol": 1e-9},
        ),
        c(
            "project_points",
            _g("project_points"),
            lambda f: {
                "points": f["pts3"],
                "K": f["K"],
                "R": f["R"],
                "t": f["t"],
                "image_plane": "virtual",
            },
        ),
        c(
            "project_points_distorted",
            _g("project_points_distorted"),
            lambda f: {
                "points": f["pts3"],
                "K": f["K"],
                "R": f["R"],
                "t": f["t"],
                "distortion": f["dist"],
            },
        ),
        c(
            "projected_size",
            _g("projected_size"),
            lambda f: {"size": 1.0, "depth": 10.0, "focal_length": 0.05},
        ),
        c(
            "projection_matrix",
            _g("projection_matrix"),
            lambda f: {"K": f["K"], "R": f["R"], "t": f["t"]},
        ),
        c("quaternion_to_matrix", _g("quaternion_to_matrix"), lambda f: {"q": f["q"]}),
        c(
            "refine_corners",
            _g("refine_corners"),
            lambda f: {
                "image": f["board_img"],
                "corners": f["corners"],
                "half_window": 3,
                "max_iter": 30,
                "tol": 1e-3,
            },
        ),
        c(
            "refine_corners_symmetric",
            _g("refine_corners_symmetric"),
            lambda f: {
                "image": f["board_img"],
                "corners": f["corners"],
                "half_window": 3,
                "max_iter": 30,
                "tol": 1e-3,
            },
        ),
        c(
            "remap_bilinear",
            _g("remap_bilinear"),
            lambda f: {"image": f["rgb"], "map_uv": f["map_uv"], "fill": 0.0},
            nan_ok=("image", "fill"),
        ),
        c("rvec_to_matrix", _g("rvec_to_matrix"), lambda f: {"rvec": [0.1, 0.2, 0.3]}),
        c(
            "solve_pnp",
            _g("solve_pnp"),
            lambda f: {
                "object_points": f["pts3"],
                "image_points": f["uv"],
                "K": f["K"],
                "distortion": None,
                "refine": True,
                "max_iter": 20,
            },
        ),
        c(
            "solve_pnp_ransac",
            _g("solve_pnp_ransac"),
            lambda f: {
                "object_points": f["pts3"],
                "image_points": f["uv"],
                "K": f["K"],
                "distortion": None,
                "threshold": 2.0,
                "confidence": 0.99,
                "max_trials": 50,
                "rng": 0,
                "max_iter": 20,
            },
            slow=True,
        ),
        c("to_homogeneous", _g("to_homogeneous"), lambda f: {"points": f["uv"], "w": 1.0}),
        c(
            "triangulate_points",
            _g("triangulate_points"),
            lambda f: {
                "projection_matrices": f["Ps"],
                "image_points": f["x12"],
                "refine": True,
                "sigma": 1.0,
                "max_iter": 20,
            },
        ),
        c(
            "undistort_image",
            _g("undistort_image"),
            lambda f: {
                "image": f["rgb"],
                "K": _small_K(),
                "distortion": f["dist"],
                "new_K": None,
                "out_shape": (40, 50),
                "fill": 0.0,
            },
            nan_ok=("image", "fill"),
        ),
        c(
            "undistortion_map",
            _g("undistortion_map"),
            lambda f: {"shape": (40, 50), "K": _small_K(), "distortion": f["dist"], "new_K": None},
        ),
        c(
            "unproject",
            _g("unproject"),
            lambda f: {
                "uv": f["uv"],
                "depth": np.full(12, 5.0),
                "K": f["K"],
                "R": f["R"],
                "t": f["t"],
                "image_plane": "virtual",
            },
        ),
        c(
            "vanishing_point",
            _g("vanishing_point"),
            lambda f: {"K": f["K"], "direction": [1.0, 0.0, 1.0], "R": f["R"]},
        ),
        c(
            "vanishing_point_from_lines",
            _g("vanishing_point_from_lines"),
            lambda f: {
                "lines": [[1.0, 0.0, -1.0], [0.0, 1.0, -2.0], [1.0, 1.0, -3.0]],
                "weights": [1.0, 1.0, 1.0],
            },
        ),
        c(
            "weak_perspective_matrix",
            _g("weak_perspective_matrix"),
            lambda f: {"K": f["K"], "depth": 5.0},
        ),
        c(
            "weak_perspective_project",
            _g("weak_perspective_project"),
            lambda f: {"points": f["pts3"], "K": f["K"], "R": f["R"], "t": f["t"], "depth": None},
        ),
        # --- classes and their public methods -------------------------------------------
        c(
            "BrownConrady",
            _g("BrownConrady"),
            lambda f: {
                "k1": -0.1,
                "k2": 0.01,
                "p1": 0.001,
                "p2": 0.0,
                "k3": 0.0,
                "k4": 0.0,
                "k5": 0.0,
                "k6": 0.0,
            },
        ),
        c(
            "BrownConrady.from_opencv",
            _g("BrownConrady.from_opencv"),
            lambda f: {"dist_coeffs": [-0.1, 0.01, 0.0, 0.0, 0.0]},
        ),
        c(
            "BrownConrady.distort",
            _m(lambda f: f["dist"], "distort"),
            lambda f: {"xy": f["uv"] / 1000},
        ),
        c(
            "BrownConrady.undistort",
            _m(lambda f: f["dist"], "undistort"),
            lambda f: {"xy": f["uv"] / 1000, "max_iter": 20, "tol": None},
        ),
        c("DivisionModel", _g("DivisionModel"), lambda f: {"k1": -0.1, "k2": 0.01}),
        c(
            "DivisionModel.distort",
            _m(lambda f: _div(), "distort"),
            lambda f: {"xy": f["uv"] / 1000, "max_iter": 30, "tol": None},
        ),
        c(
            "DivisionModel.undistort",
            _m(lambda f: _div(), "undistort"),
            lambda f: {"xy": f["uv"] / 1000, "max_iter": 30, "tol": None},
        ),
        c(
            "KannalaBrandt",
            _g("KannalaBrandt"),
            lambda f: {"k1": 0.01, "k2": 0.0, "k3": 0.0, "k4": 0.0},
        ),
        c(
            "KannalaBrandt.distort",
            _m(lambda f: _kb(), "distort"),
            lambda f: {"xy": f["uv"] / 1000},
        ),
        c(
            "KannalaBrandt.undistort",
            _m(lambda f: _kb(), "undistort"),
            lambda f: {"xy": f["uv"] / 1000, "max_iter": 20, "tol": None},
        ),
        c(
            "Camera",
            _g("Camera"),
            lambda f: {
                "K": f["K"],
                "R": f["R"],
                "t": f["t"],
                "image_size": (640, 480),
                "image_plane": "virtual",
                "distortion": f["dist"],
            },
        ),
        c(
            "Camera.from_projection_matrix",
            _g("Camera.from_projection_matrix"),
            lambda f: {"P": f["Ps"][1], "image_size": (640, 480)},
        ),
        c(
            "Camera.look_at",
            _g("Camera.look_at"),
            lambda f: {
                "K": f["K"],
                "eye": [0.0, 0.0, -5.0],
                "target": [0.0, 0.0, 0.0],
                "up": (0.0, -1.0, 0.0),
                "image_size": (640, 480),
            },
        ),
        c(
            "Camera.world_to_camera",
            _m(lambda f: f["camera"], "world_to_camera"),
            lambda f: {"points": f["pts3"]},
        ),
        c("Camera.project", _m(lambda f: f["camera"], "project"), lambda f: {"points": f["pts3"]}),
        c(
            "Camera.undistort_pixels",
            _m(lambda f: _dcam(f), "undistort_pixels"),
            lambda f: {"uv": f["uv"]},
        ),
        c(
            "Camera.backproject",
            _m(lambda f: f["camera"], "backproject"),
            lambda f: {"uv": f["uv"]},
        ),
        c(
            "Camera.unproject",
            _m(lambda f: f["camera"], "unproject"),
            lambda f: {"uv": f["uv"], "depth": np.full(12, 5.0)},
        ),
        c("Camera.in_image", _m(lambda f: f["camera"], "in_image"), lambda f: {"uv": f["uv"]}),
        c(
            "Intrinsics",
            _g("Intrinsics"),
            lambda f: {
                "fx": 800.0,
                "fy": 810.0,
                "cx": 320.0,
                "cy": 240.0,
                "skew": 0.0,
                "image_size": (640, 480),
            },
        ),
        c(
            "Intrinsics.from_matrix",
            _g("Intrinsics.from_matrix"),
            lambda f: {"K": f["K"], "image_size": (640, 480)},
        ),
        c(
            "Intrinsics.from_physical",
            _g("Intrinsics.from_physical"),
            lambda f: {
                "focal_length_mm": 0.05,
                "pixel_pitch_um": 3.45,
                "image_size": (640, 480),
                "principal_point": None,
            },
        ),
        c(
            "Intrinsics.from_sensor",
            _g("Intrinsics.from_sensor"),
            lambda f: {
                "focal_length_mm": 0.05,
                "sensor_size_mm": (6.4, 4.8),
                "image_size": (640, 480),
            },
        ),
        c(
            "Intrinsics.from_fov",
            _g("Intrinsics.from_fov"),
            lambda f: {"fov_x": 1.0, "image_size": (640, 480)},
        ),
        c("Intrinsics.scaled", _m(_intr, "scaled"), lambda f: {"factor": 0.5}),
        c(
            "ConeBeamGeometry",
            _g("ConeBeamGeometry"),
            lambda f: {
                "source_to_detector": 1000.0,
                "source_to_object": 500.0,
                "pixel_pitch": 0.2,
                "detector_shape": (64, 48),
                "principal_point": None,
            },
        ),
        c("ConeBeamGeometry.penumbra", _m(_cone, "penumbra"), lambda f: {"focal_spot_size": 0.4}),
        c("ConeBeamGeometry.project", _m(_cone, "project"), lambda f: {"points": f["pts3"] * 10}),
        c(
            "LineSegments",
            _g("LineSegments"),
            lambda f: {
                "endpoints": _segments(f).endpoints,
                "widths": np.ones(3),
                "log10_nfa": -np.ones(3),
            },
        ),
        c(
            "CheckerboardResult",
            _g("CheckerboardResult"),
            lambda f: {
                "found": True,
                "corners": np.arange(12.0).reshape(6, 2),
                "reason": "",
                "pattern_size": (3, 2),
                "status": None,
                "sigma": None,
            },
        ),
        c("CheckerboardResult.grid", _m(_board_result, "grid"), lambda f: {}),
        # Not swept: CalibrationResult.to_toml/from_toml (deprecated: their DeprecationWarning
        # is the intended outcome) and the NamedTuple results (Pose, Projection, PnPResult,
        # ...): plain records returned by the functions above, not validated.
    ]


def _small_K() -> np.ndarray:
    return np.array([[60.0, 0.0, 25.0], [0.0, 60.0, 20.0], [0.0, 0.0, 1.0]])


def _div() -> Any:
    from imageform.geometry import DivisionModel

    return DivisionModel(-0.1, 0.01)


def _kb() -> Any:
    from imageform.geometry import KannalaBrandt

    return KannalaBrandt(0.01)


def _dcam(f: dict[str, Any]) -> Any:
    from imageform.geometry import Camera

    return Camera(f["K"], f["R"], f["t"], image_size=(640, 480), distortion=f["dist"])


def _vp3(f: dict[str, Any]) -> dict[str, Any]:
    K, R = f["K"], f["R"]
    v = (K @ R).T  # columns of K R: the vanishing points of the world axes
    return {"v1": v[0], "v2": v[1], "v3": v[2]}


CASES = _cases()

# ---------------------------------------------------------------------------------------
# malformed values


def _torch_scalar(value: float) -> Any:
    try:
        import torch
    except ImportError:  # pragma: no cover
        return np.float64(value)
    return torch.tensor(value)


def malformed(valid: Any) -> list[tuple[str, Any]]:
    """Malformed (or boundary) stand-ins for a parameter whose valid value is ``valid``."""
    out: list[tuple[str, Any]] = [
        ("None", None),
        ("nan", math.nan),
        ("inf", math.inf),
        ("-inf", -math.inf),
        ("huge", 1e300),
        ("1e308", 1e308),
        ("negative", -1),
        ("zero", 0),
        ("tiny", 1e-300),
        ("bool", True),
        ("string", "abc"),
        ("complex", 1 + 2j),
        ("object", object()),
        ("np.int64", np.int64(3)),
        ("np.float64", np.float64(2.5)),
        ("int>int64", 2**70),
        ("torch0d", _torch_scalar(1.0)),
        ("empty", np.empty((0,))),
        ("empty2d", np.empty((0, 0))),
        ("wrong-shape", np.zeros((2, 7, 5))),
        ("tuple1", (5,)),
        ("tuple3", (5, 6, 7)),
        ("tuple(0,0)", (0, 0)),
        ("tuple-inf", (math.inf, 5)),
    ]
    arr = None
    if isinstance(valid, np.ndarray | list | tuple) and not isinstance(valid, str):
        with contextlib.suppress(Exception):
            a = np.asarray(valid)
            if a.dtype.kind in "fiu" and a.size:
                arr = a.astype(np.float64)
    if arr is not None:
        nan = arr.copy()
        nan.flat[0] = np.nan
        out += [
            ("arr-nan", nan),
            ("arr-inf", np.where(np.arange(arr.size).reshape(arr.shape) == 0, np.inf, arr)),
            ("arr-huge", arr * 1e300 + 1e300),
            ("arr-neg", -np.abs(arr) - 1),
            ("arr-zero", np.zeros_like(arr)),
            ("arr-complex", arr + 1j),
            ("arr-object", arr.astype(object)),
            ("arr-string", arr.astype(str)),
            ("arr-bool", arr > arr.mean()),
            ("arr-int", np.round(arr).astype(np.int64)),
            ("arr-empty", np.empty((0, *arr.shape[1:]))),
            ("arr-extra-dim", arr[..., None]),
            ("arr-last+1", np.concatenate([arr, arr[..., :1]], axis=-1) if arr.ndim else arr),
            ("arr-flat", arr.ravel()),
            ("arr-list", arr.tolist()),
            ("arr-float32", arr.astype(np.float32)),
            ("arr-torch", _torch_array(arr)),
        ]
    return out


def _torch_array(arr: np.ndarray) -> Any:
    try:
        import torch
    except ImportError:  # pragma: no cover
        return arr
    return torch.from_numpy(arr.copy())


# ---------------------------------------------------------------------------------------
# classification


@dataclasses.dataclass(frozen=True)
class Outcome:
    case: str
    param: str
    value: str
    kind: str
    detail: str


def _np(x: Any) -> Any:
    if type(x).__module__.startswith("torch"):
        with contextlib.suppress(Exception):
            return x.detach().cpu().numpy()
    return x


def _nonfinite(x: Any, depth: int = 0) -> bool:
    """Whether a result holds NaN/inf that no ``valid`` mask or ``found=False`` explains."""
    if depth > 4 or x is None or isinstance(x, str | bool):
        return False
    if type(x).__module__.startswith("torch"):
        with contextlib.suppress(Exception):
            x = x.detach().cpu().numpy()
    if isinstance(x, float | np.floating):
        return not math.isfinite(float(x))
    if isinstance(x, np.ndarray):
        if x.dtype.kind in "fc":
            return not bool(np.all(np.isfinite(x)))
        return x.dtype.kind in "OUS"  # an object or string array is no numeric result
    if dataclasses.is_dataclass(x) or hasattr(x, "_fields"):
        fields = (
            {f.name: getattr(x, f.name) for f in dataclasses.fields(x)}
            if dataclasses.is_dataclass(x)
            else x._asdict()
        )
        fields = {k: _np(v) for k, v in fields.items()}
        if fields.get("found") is False:
            return False
        valid = fields.get("valid")
        for k, v in fields.items():
            if k in ("valid", "inliers", "std", "std_poses", "rms", "covariance"):
                continue
            if valid is not None and isinstance(v, np.ndarray) and v.dtype.kind == "f":
                vm = np.asarray(valid, bool)
                with contextlib.suppress(ValueError):
                    while vm.ndim < v.ndim:
                        vm = vm[..., None]
                    bad = ~np.isfinite(v) & np.broadcast_to(vm, v.shape)
                    if bad.any():
                        return True
                    continue
            if k == "log10_nfa" and isinstance(v, np.ndarray) and v.dtype.kind == "f":
                v = np.where(v == -np.inf, 0.0, v)  # an NFA below float range
            if _nonfinite(v, depth + 1):
                return True
        return False
    if isinstance(x, list | tuple):
        return any(_nonfinite(v, depth + 1) for v in x[:50])
    return False


def _names(message: str, param: str) -> bool:
    low = message.lower()
    keys = {param.lower(), param.lower().replace("_", " "), param.lower().replace("_", "-")}
    return any(k in low for k in keys)


def classify(
    case: str,
    param: str,
    label: str,
    fn: Callable[[], Any],
    guard: float,
    nan_ok: bool = False,
) -> Outcome:
    """Call ``fn`` under the time guard and classify what happened."""
    from imageform.errors import (
        ConvergenceError,
        DegenerateConfigurationError,
        ImageformError,
        ImageformWarning,
    )

    def out(kind: str, detail: str) -> Outcome:
        return Outcome(case, param, label, kind, detail.replace("\n", "\\n")[:300])

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _time_guard(guard):
                result = fn()
        except _Timeout:
            return out("timeout", f"> {guard} s")
        except (ImageformError, TypeError) as exc:
            if not isinstance(exc, ImageformError) and type(exc) is not TypeError:
                return out("raw", f"{type(exc).__name__}: {exc}")
            msg = str(exc)
            stray = [w for w in caught if not issubclass(w.category, ImageformWarning)]
            if stray:
                return out("warning", f"{stray[0].category.__name__}: {stray[0].message}")
            if "\n" in msg or len(msg) > 200:
                return out("message", f"{type(exc).__name__}: {msg}")
            # a degenerate configuration or a solver that did not converge is about the
            # data as a whole: its message names the cause, not one parameter
            whole = isinstance(exc, DegenerateConfigurationError | ConvergenceError)
            if not whole and not _names(msg, param):
                return out("unnamed", f"{type(exc).__name__}: {msg}")
            return out("ok", f"{type(exc).__name__}: {msg}")
        except Exception as exc:
            return out("raw", f"{type(exc).__name__}: {exc}")
        stray = [w for w in caught if not issubclass(w.category, ImageformWarning)]
        if stray:
            return out("warning", f"{stray[0].category.__name__}: {stray[0].message}")
        if _nonfinite(result) and not (nan_ok and label in ("nan", "arr-nan", "arr-inf")):
            return out("nan", f"{type(result).__name__} holds NaN/inf")
        return out("ok", "result")


def baseline_failures() -> list[str]:
    """The cases whose *valid* keyword arguments do not give a clean result (a sweep around
    an invalid baseline would test nothing)."""
    out = []
    old_cwd = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            fx = _fixtures()
            for case in CASES:
                if case.slow:
                    # one call first, unguarded: numba compiles there (seconds per kernel on
                    # a cold cache), not under the guard, as in run_sweep
                    with warnings.catch_warnings(), contextlib.suppress(Exception):
                        warnings.simplefilter("ignore")
                        case.make(fx)(**case.kwargs(fx))
                o = classify(case.name, "-", "valid", lambda c=case: c.make(fx)(**c.kwargs(fx)), 60)
                if o.kind != "ok" or o.detail != "result":
                    out.append(f"{case.name}: {o.kind} {o.detail}")
        finally:
            os.chdir(old_cwd)
    return out


def run_sweep(
    *,
    full: bool = True,
    only: str | None = None,
    guard: float = 20.0,
    sample: int | None = None,
    seed: int = 0,
) -> list[Outcome]:
    """Run the sweep; ``sample`` draws that many (parameter, value) pairs per callable
    (seeded) instead of all; ``full=False`` skips the slow callables."""
    from imageform.errors import DegenerateConfigurationError  # noqa: F401 - import check

    rng = np.random.default_rng(seed)
    old_env = os.environ.get("IMAGEFORM_MAX_MEMORY")
    os.environ["IMAGEFORM_MAX_MEMORY"] = "1G"
    old_cwd = os.getcwd()
    outcomes: list[Outcome] = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            os.chdir(tmp)
            fx = _fixtures()
            for case in CASES:
                if only is not None and case.name != only:
                    continue
                if case.slow and not full and only is None:
                    continue
                fn = case.make(fx)
                base = case.kwargs(fx)
                # one valid call first, unguarded: numba compiles there, not under the guard
                # (that the valid calls succeed is :func:`baseline_failures`'s business)
                with warnings.catch_warnings(), contextlib.suppress(Exception):
                    warnings.simplefilter("ignore")
                    fn(**base)
                pairs = [
                    (p, lab, val)
                    for p, v in base.items()
                    if p not in case.skip
                    for lab, val in malformed(v)
                ]
                if sample is not None and len(pairs) > sample:
                    idx = rng.choice(len(pairs), sample, replace=False)
                    pairs = [pairs[i] for i in sorted(idx)]
                for p, lab, val in pairs:
                    kwargs = dict(base)
                    kwargs[p] = val
                    outcomes.append(
                        classify(
                            case.name,
                            p,
                            lab,
                            lambda kw=kwargs, f=fn: f(**kw),
                            guard,
                            p in case.nan_ok,
                        )
                    )
    finally:
        os.chdir(old_cwd)
        if old_env is None:
            os.environ.pop("IMAGEFORM_MAX_MEMORY", None)
        else:
            os.environ["IMAGEFORM_MAX_MEMORY"] = old_env
    return outcomes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", help="one callable, e.g. Camera.unproject")
    ap.add_argument("--list", nargs="*", default=None, help="print the outcomes of these kinds")
    ap.add_argument("--quick", action="store_true", help="skip the slow callables")
    ap.add_argument("--guard", type=float, default=20.0, help="seconds per call")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    outcomes = run_sweep(full=not args.quick, only=args.only, guard=args.guard)
    counts = Counter(o.kind for o in outcomes)
    if args.list is not None:
        kinds = set(args.list) or set(FAIL_CLASSES)
        for o in outcomes:
            if o.kind in kinds:
                print(f"{o.kind:8s} {o.case}({o.param}={o.value}): {o.detail[:220]}")
    n_cases = len({o.case for o in outcomes})
    print(
        f"{len(outcomes)} calls over {n_cases} callables in {time.perf_counter() - t0:.1f} s: "
        + ", ".join(f"{k} {counts.get(k, 0)}" for k in (*OK_CLASSES, *FAIL_CLASSES))
    )
    return 1 if any(counts.get(k) for k in FAIL_CLASSES) else 0


if __name__ == "__main__":
    sys.exit(main())
