"""imageform.geometry — camera geometry: from a 3-D point to a pixel and back.

Conventions (``docs/conventions.md``): camera frame x right, y down, z forward;
``X_cam = R @ X_world + t``; ``P = K [R | t]``; pixel ``(u, v)`` = (column, row) with the
top-left pixel centre at (0, 0); points are row vectors ``(..., N, 3)``; points with
``z_cam <= 0`` are NaN with ``valid = False``.
"""

from imageform.geometry.aruco import (
    ARUCO_DICTIONARIES,
    ArucoDictionary,
    ArucoMarkers,
    aruco_dictionary,
    aruco_marker_image,
    detect_aruco_markers,
    identify_aruco_dictionary,
)
from imageform.geometry.calibration import (
    CalibrationResult,
    calibrate_camera,
    checkerboard_points,
)
from imageform.geometry.camera import (
    Camera,
    DecomposedProjection,
    ImagePlane,
    Projection,
    backproject,
    decompose_projection_matrix,
    project_points,
    projection_matrix,
    unproject,
)
from imageform.geometry.charuco import CharucoBoard, CharucoCorners, detect_charuco
from imageform.geometry.checkerboard import (
    CheckerboardNotFoundWarning,
    CheckerboardResult,
    find_checkerboard,
    find_checkerboards,
)
from imageform.geometry.checkerboard_subpix import (
    RefinedCorners,
    refine_corners,
    refine_corners_symmetric,
)
from imageform.geometry.distortion import (
    BrownConrady,
    DistortionModel,
    DivisionModel,
    KannalaBrandt,
    Undistorted,
    project_points_distorted,
)
from imageform.geometry.dlt import estimate_projection_matrix
from imageform.geometry.frame_masks import (
    blurred_frames,
    field_of_view_mask,
    frame_sharpness,
    highlight_mask,
    still_mask,
)
from imageform.geometry.homogeneous import (
    Dehomogenized,
    are_collinear,
    cross_ratio,
    from_homogeneous,
    from_homogeneous_masked,
    intersect_lines,
    line_through,
    to_homogeneous,
)
from imageform.geometry.homography import apply_homography, estimate_homography
from imageform.geometry.horizon_detection import HorizonResult, detect_horizon
from imageform.geometry.intrinsics import Intrinsics, intrinsic_matrix, projected_size
from imageform.geometry.line_segments import LineSegments, detect_line_segments
from imageform.geometry.lsd import lsd_segments
from imageform.geometry.marker_map import MarkerMap, MarkerMapTracker, grid_marker_map
from imageform.geometry.marker_tracking import (
    MarkerTracker,
    SquarePoses,
    marker_points,
    solve_square_pose,
)
from imageform.geometry.plumb_line import PlumbLineResult, estimate_distortion_from_lines
from imageform.geometry.pnp import PnPResult, solve_pnp
from imageform.geometry.pnp_batch import solve_pnp_batch
from imageform.geometry.pnp_ransac import solve_pnp_ransac
from imageform.geometry.projection_models import (
    ConeBeamGeometry,
    orthographic_matrix,
    orthographic_project,
    weak_perspective_matrix,
    weak_perspective_project,
)
from imageform.geometry.relative_pose import (
    RelativePose,
    TwoViewPoints,
    recover_pose,
    triangulate_two_view,
)
from imageform.geometry.robust import HomographyResult, find_homography
from imageform.geometry.rotations import (
    Pose,
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
from imageform.geometry.sfm import (
    Features,
    Reconstruction,
    bundle_adjust,
    detect_features,
    match_features,
    reconstruct_sequence,
)
from imageform.geometry.stereo import (
    StereoCalibrationResult,
    StereoRectification,
    rectification_map,
    stereo_calibrate,
    stereo_rectify,
)
from imageform.geometry.stereo_matching import (
    disparity_to_depth,
    disparity_to_points,
    stereo_disparity,
)
from imageform.geometry.tracking import BoardPose, BoardTracker
from imageform.geometry.triangulation import TriangulationResult, triangulate_points
from imageform.geometry.twoview import (
    EssentialResult,
    FundamentalResult,
    essential_5point,
    find_essential_matrix,
    find_fundamental_matrix,
    fundamental_7point,
    fundamental_8point,
)
from imageform.geometry.undistort import remap_bilinear, undistort_image, undistortion_map
from imageform.geometry.vanishing import (
    focal_from_vanishing_points,
    horizon_line,
    intrinsics_from_vanishing_points,
    lines_from_segments,
    perspective_type,
    vanishing_point,
    vanishing_point_from_lines,
)
from imageform.geometry.vp_detection import VanishingPointResult, detect_vanishing_points

__all__ = [
    "ARUCO_DICTIONARIES",
    "ArucoDictionary",
    "ArucoMarkers",
    "BoardPose",
    "BoardTracker",
    "BrownConrady",
    "CalibrationResult",
    "Camera",
    "CharucoBoard",
    "CharucoCorners",
    "CheckerboardNotFoundWarning",
    "CheckerboardResult",
    "ConeBeamGeometry",
    "DecomposedProjection",
    "Dehomogenized",
    "DistortionModel",
    "DivisionModel",
    "EssentialResult",
    "Features",
    "FundamentalResult",
    "HomographyResult",
    "HorizonResult",
    "ImagePlane",
    "Intrinsics",
    "KannalaBrandt",
    "LineSegments",
    "MarkerMap",
    "MarkerMapTracker",
    "MarkerTracker",
    "PlumbLineResult",
    "PnPResult",
    "Pose",
    "Projection",
    "Reconstruction",
    "RefinedCorners",
    "RelativePose",
    "SquarePoses",
    "StereoCalibrationResult",
    "StereoRectification",
    "TriangulationResult",
    "TwoViewPoints",
    "Undistorted",
    "VanishingPointResult",
    "apply_homography",
    "are_collinear",
    "aruco_dictionary",
    "aruco_marker_image",
    "axis_rotation",
    "backproject",
    "blurred_frames",
    "bundle_adjust",
    "calibrate_camera",
    "camera_rotation",
    "checkerboard_points",
    "cross_ratio",
    "decompose_projection_matrix",
    "detect_aruco_markers",
    "detect_charuco",
    "detect_features",
    "detect_horizon",
    "detect_line_segments",
    "detect_vanishing_points",
    "disparity_to_depth",
    "disparity_to_points",
    "essential_5point",
    "estimate_distortion_from_lines",
    "estimate_homography",
    "estimate_projection_matrix",
    "euler_to_matrix",
    "field_of_view_mask",
    "find_checkerboard",
    "find_checkerboards",
    "find_essential_matrix",
    "find_fundamental_matrix",
    "find_homography",
    "focal_from_vanishing_points",
    "frame_sharpness",
    "from_homogeneous",
    "from_homogeneous_masked",
    "fundamental_7point",
    "fundamental_8point",
    "grid_marker_map",
    "highlight_mask",
    "horizon_line",
    "identify_aruco_dictionary",
    "intersect_lines",
    "intrinsic_matrix",
    "intrinsics_from_vanishing_points",
    "is_rotation",
    "line_through",
    "lines_from_segments",
    "look_at",
    "lsd_segments",
    "marker_points",
    "match_features",
    "matrix_to_euler",
    "matrix_to_quaternion",
    "matrix_to_rvec",
    "orthographic_matrix",
    "orthographic_project",
    "perspective_type",
    "project_points",
    "project_points_distorted",
    "projected_size",
    "projection_matrix",
    "quaternion_to_matrix",
    "reconstruct_sequence",
    "recover_pose",
    "rectification_map",
    "refine_corners",
    "refine_corners_symmetric",
    "remap_bilinear",
    "rvec_to_matrix",
    "solve_pnp",
    "solve_pnp_batch",
    "solve_pnp_ransac",
    "solve_square_pose",
    "stereo_calibrate",
    "stereo_disparity",
    "stereo_rectify",
    "still_mask",
    "to_homogeneous",
    "triangulate_points",
    "triangulate_two_view",
    "undistort_image",
    "undistortion_map",
    "unproject",
    "vanishing_point",
    "vanishing_point_from_lines",
    "weak_perspective_matrix",
    "weak_perspective_project",
]
