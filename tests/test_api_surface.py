"""The public API: removing a name from ``__all__`` must be a deliberate act (update this list)."""

from __future__ import annotations

import importlib

import pytest

PUBLIC = {
    "imageform": {
        "DegenerateConfigurationError",
        "ImageformError",
        "InvalidInputError",
        "UnknownOptionError",
        "__version__",
        "errors",
        "geometry",
    },
    "imageform.batch": {
        "CHUNKED_COMMANDS",
        "COMMANDS",
        "BatchCommand",
        "BatchReport",
        "ChunkedResult",
        "Job",
        "JobResult",
        "get_command",
        "plan_jobs",
        "print_summary",
        "process_chunked",
        "run_batch",
        "run_job",
    },
    "imageform.geometry": {
        "CalibrationResult",
        "PnPResult",
        "TriangulationResult",
        "calibrate_camera",
        "checkerboard_points",
        "solve_pnp",
        "solve_pnp_ransac",
        "triangulate_points",
        "Camera",
        "ConeBeamGeometry",
        "ImagePlane",
        "Intrinsics",
        "Projection",
        "apply_homography",
        "are_collinear",
        "axis_rotation",
        "backproject",
        "camera_rotation",
        "cross_ratio",
        "decompose_projection_matrix",
        "estimate_homography",
        "estimate_projection_matrix",
        "euler_to_matrix",
        "focal_from_vanishing_points",
        "from_homogeneous",
        "horizon_line",
        "intersect_lines",
        "intrinsic_matrix",
        "intrinsics_from_vanishing_points",
        "is_rotation",
        "line_through",
        "lines_from_segments",
        "look_at",
        "matrix_to_euler",
        "matrix_to_quaternion",
        "matrix_to_rvec",
        "orthographic_matrix",
        "orthographic_project",
        "perspective_type",
        "project_points",
        "projected_size",
        "projection_matrix",
        "quaternion_to_matrix",
        "rvec_to_matrix",
        "to_homogeneous",
        "unproject",
        "vanishing_point",
        "vanishing_point_from_lines",
        "weak_perspective_matrix",
        "weak_perspective_project",
    },
}


@pytest.mark.parametrize("module", sorted(PUBLIC))
def test_public_names_kept(module: str) -> None:
    mod = importlib.import_module(module)
    missing = PUBLIC[module] - set(mod.__all__)
    assert not missing, f"{module} lost public names {sorted(missing)}"
    for name in mod.__all__:
        assert hasattr(mod, name), f"{module}.__all__ lists {name} but it is not defined"
