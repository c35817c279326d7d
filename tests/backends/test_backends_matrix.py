"""Backend matrix: every public geometry and colour function on NumPy, array-api-strict,
PyTorch (CPU) and Dask, compared with the NumPy result (issue 9, "Array API").

Each case calls one public function with representative inputs converted to the backend
under test and checks that the result is the same kind of array (same library, same device,
same dtype) and holds NumPy's numbers to the stated tolerance. :data:`EXCLUDED` lists every
public name of ``imageform.geometry`` and ``imageform.color`` that is not in the matrix, with
the reason; :func:`test_every_public_function_is_covered` keeps the two lists complete.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from imageform import color as c
from imageform import geometry as g
from tests.helpers import array_type, to_backend, to_np

BACKENDS = ("numpy", "array_api_strict", "torch", "dask")

# ---------------------------------------------------------------- representative inputs
_rng = np.random.default_rng(9)
RGB = _rng.uniform(0.05, 0.95, size=(4, 6, 3))
LIN = c.srgb_to_linear(RGB)
XYZ = c.linear_srgb_to_xyz(LIN)
LAB = c.xyz_to_lab(XYZ)
LAB2 = c.xyz_to_lab(c.linear_srgb_to_xyz(c.srgb_to_linear(_rng.uniform(0.05, 0.95, (4, 6, 3)))))
HSV = c.srgb_to_hsv(RGB)
HUE1 = _rng.uniform(0, 360, size=(5,))
HUE2 = _rng.uniform(0, 360, size=(5,))
XY = c.xyz_to_xy(XYZ)
UV1960 = c.xy_to_uv1960(XY)
UVP = c.xy_to_uv_prime(XY)
YCC = c.srgb_to_ycbcr(RGB)
CMY = c.srgb_to_cmy(RGB)
CMYK = c.srgb_to_cmyk(RGB)
GRAY = _rng.uniform(0.05, 0.95, size=(4, 6))
IMG8 = _rng.uniform(0.05, 0.95, size=(8, 8, 3))

K = np.array([[500.0, 2.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]])
RVEC = np.array([0.1, -0.2, 0.3])
R = g.rvec_to_matrix(RVEC)
T = np.array([0.2, -0.1, 4.0])
PTS3 = _rng.uniform(-1, 1, size=(7, 3))
PTS2 = _rng.uniform(-1, 1, size=(7, 2))
UV = _rng.uniform(0, 600, size=(7, 2))
XYN = _rng.uniform(-0.4, 0.4, size=(7, 2))
SQ = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.3, 0.7]])
HOM = np.array([[1.1, 0.1, 3.0], [0.05, 0.9, -2.0], [1e-3, 2e-3, 1.0]])
LINES = np.array([[1.0, 0.2, -3.0], [0.1, 1.0, -2.0], [1.0, -1.0, 0.5]])
SEGS = np.array([[0.0, 0.0, 10.0, 1.0], [0.0, 5.0, 10.0, 5.5], [0.0, 9.0, 10.0, 9.7]]).reshape(
    3, 2, 2
)
QUAT = np.array([0.9, 0.1, 0.2, 0.3]) / np.linalg.norm([0.9, 0.1, 0.2, 0.3])
VPS = (np.array([900.0, 250.0]), np.array([-300.0, 230.0]), np.array([310.0, 9000.0]))
BC = g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01)
KB = g.KannalaBrandt(k1=0.05, k2=-0.01)
DIV = g.DivisionModel(k1=-0.1)
KSMALL = np.array([[8.0, 0.0, 3.5], [0.0, 8.0, 3.5], [0.0, 0.0, 1.0]])


@dataclass
class Case:
    """One call: ``fn(*args)`` with the array ``args`` converted to the backend."""

    name: str
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    atol: float = 1e-10
    #: backend -> reason, for backends this case does not run on.
    skip: dict[str, str] = field(default_factory=dict)
    #: which outputs of a tuple result are arrays to compare (None: the whole result).
    pick: Callable[[Any], Any] | None = None
    #: the functions of the public API this case covers (default: ``name``).
    covers: tuple[str, ...] = ()
    #: whether the result is an array of the input's kind (False: numbers only are compared).
    same_kind: bool = True


def _first(r: Any) -> Any:
    return r[0]


CASES: list[Case] = [
    # ---- colour: transfer functions
    *[
        Case(n, getattr(c, n), (RGB,))
        for n in (
            "srgb_to_linear",
            "linear_to_srgb",
            "adobe_rgb_to_linear",
            "linear_to_adobe_rgb",
            "prophoto_to_linear",
            "linear_to_prophoto",
            "rec709_to_linear",
            "linear_to_rec709",
            "rec2020_to_linear",
            "linear_to_rec2020",
            "gamma_to_linear",
            "linear_to_gamma",
            "srgb_to_hsv",
            "srgb_to_hsl",
            "srgb_to_hsi",
            "srgb_to_cmy",
            "srgb_to_cmyk",
            "srgb_to_gray",
            "srgb_to_bgr",
            "bgr_to_srgb",
            "srgb_to_ycbcr",
            "rgb_to_ycbcr",
            "linear_srgb_to_luminance",
            "linear_srgb_to_xyz",
            "linear_rgb_to_xyz",
            "hue_undefined_mask",
        )
    ],
    Case("decode", lambda x: c.decode(x, "rec2020"), (RGB,)),
    Case("encode", lambda x: c.encode(x, "srgb"), (RGB,)),
    Case("hsv_to_srgb", c.hsv_to_srgb, (HSV,)),
    Case("hsl_to_srgb", c.hsl_to_srgb, (c.srgb_to_hsl(RGB),)),
    Case("hsi_to_srgb", c.hsi_to_srgb, (c.srgb_to_hsi(RGB),), atol=1e-9),
    Case("hue_difference", c.hue_difference, (HUE1, HUE2)),
    Case("hue_distance", c.hue_distance, (HUE1, HUE2)),
    Case("hue_in_range", lambda h: c.hue_in_range(h, 300.0, 40.0), (HUE1,)),
    Case("cmy_to_srgb", c.cmy_to_srgb, (CMY,)),
    Case("cmy_to_cmyk", c.cmy_to_cmyk, (CMY,)),
    Case("cmyk_to_cmy", c.cmyk_to_cmy, (CMYK,)),
    Case("cmyk_to_srgb", c.cmyk_to_srgb, (CMYK,)),
    Case("gray_to_srgb", c.gray_to_srgb, (GRAY[..., None],)),
    Case("ycbcr_to_srgb", c.ycbcr_to_srgb, (YCC,)),
    Case("ycbcr_to_rgb", c.ycbcr_to_rgb, (YCC,)),
    Case("xyz_to_linear_srgb", c.xyz_to_linear_srgb, (XYZ,)),
    Case("xyz_to_linear_rgb", lambda x: c.xyz_to_linear_rgb(x, "display_p3"), (XYZ,)),
    Case("xyz_to_lab", c.xyz_to_lab, (XYZ,)),
    Case("lab_to_xyz", c.lab_to_xyz, (LAB,)),
    Case("xyz_to_luv", c.xyz_to_luv, (XYZ,)),
    Case("luv_to_xyz", c.luv_to_xyz, (c.xyz_to_luv(XYZ),)),
    Case("lab_to_lch", c.lab_to_lch, (LAB,)),
    Case("lch_to_lab", c.lch_to_lab, (c.lab_to_lch(LAB),)),
    Case("xyz_to_xyy", c.xyz_to_xyy, (XYZ,)),
    Case("xyy_to_xyz", c.xyy_to_xyz, (c.xyz_to_xyy(XYZ),)),
    Case("xyz_to_xy", c.xyz_to_xy, (XYZ,)),
    Case("xyz_to_uv_prime", c.xyz_to_uv_prime, (XYZ,)),
    Case("xy_to_uv_prime", c.xy_to_uv_prime, (XY,)),
    Case("uv_prime_to_xy", c.uv_prime_to_xy, (UVP,)),
    Case("xy_to_uv1960", c.xy_to_uv1960, (XY,)),
    Case("uv1960_to_xy", c.uv1960_to_xy, (UV1960,)),
    Case("xy_to_xyz", lambda x: c.xy_to_xyz(x, check_locus=False), (XY,)),
    Case("xy_to_cct", c.xy_to_cct, (XY[0],), atol=1e-6, pick=_first),
    Case("cct_to_xy", c.cct_to_xy, (np.array([2856.0, 4000.0, 6504.0]),), atol=1e-9),
    Case("in_locus", c.in_locus, (XY,)),
    Case("check_in_locus", c.check_in_locus, (XY,)),
    Case("in_gamut", c.in_gamut, (XYZ,)),
    Case("gamut_map", c.gamut_map, (XYZ * 1.3,), atol=1e-8),
    Case(
        "chromatic_adaptation",
        lambda x: c.chromatic_adaptation(x, "D65", "D50"),
        (XYZ,),
    ),
    Case("convert", lambda x: c.convert(x, "srgb", "lab"), (RGB,), atol=1e-9),
    Case("from_opencv", lambda x: c.from_opencv(x * 200, "lab8"), (RGB,)),
    Case("to_opencv", lambda x: c.to_opencv(x, "hsv8"), (HSV,)),
    Case("simulate_cvd", lambda x: c.simulate_cvd(x, "deuteranomaly", 0.6), (RGB,)),
    Case("delta_e", c.delta_e, (LAB, LAB2), atol=1e-9),
    Case("delta_e_cie76", c.delta_e_cie76, (LAB, LAB2)),
    Case("delta_e_cie94", c.delta_e_cie94, (LAB, LAB2)),
    Case("delta_e_ciede2000", c.delta_e_ciede2000, (LAB, LAB2), atol=1e-9),
    Case("delta_e_cmc", c.delta_e_cmc, (LAB, LAB2)),
    Case("chroma_subsample", lambda x: c.chroma_subsample(x)[1], (YCC,)),
    Case(
        "chroma_upsample",
        lambda x: c.chroma_upsample(x[..., 0], c.chroma_subsample(x)[1]),
        (YCC,),
    ),
    Case("subsample_round_trip", c.subsample_round_trip, (IMG8,)),
    Case("subsampling_delta_e", c.subsampling_delta_e, (IMG8,), atol=1e-9),
    Case("downsample", lambda x: c.downsample(x, 2), (IMG8,)),
    Case("mean_linear_light", c.mean_linear_light, (IMG8,)),
    Case("linear_light_error", lambda x: c.linear_light_error(x).right, (IMG8,)),
    Case("estimate_illuminant", c.estimate_illuminant, (RGB,)),
    Case(
        "white_balance",
        lambda x: c.white_balance(x, "shades_of_gray", p=4.0).image,
        (RGB,),
    ),
    Case(
        "palette_check",
        lambda x: np.asarray(list(c.palette_check(x).min_delta_e.values())),
        (RGB[0],),
        atol=1e-9,
        same_kind=False,  # a report: Python floats and NumPy colours, whatever the input
    ),
    # ---- geometry
    Case("to_homogeneous", g.to_homogeneous, (PTS2,)),
    Case("from_homogeneous", g.from_homogeneous, (PTS3 + [0, 0, 2],)),
    Case(
        "from_homogeneous_masked",
        g.from_homogeneous_masked,
        (PTS3 * [1, 1, 0] + [0, 0, 1] * (np.arange(7) % 2)[:, None],),  # some at infinity
        pick=lambda r: r.points,
    ),
    Case("line_through", g.line_through, (PTS2, PTS2 + [0.5, 0.1])),
    Case("intersect_lines", g.intersect_lines, (LINES, LINES[[1, 2, 0]])),
    Case("are_collinear", g.are_collinear, (PTS2[:3],)),
    Case(
        "cross_ratio",
        g.cross_ratio,
        (np.array([0.0, 0]), np.array([1.0, 0]), np.array([3.0, 0]), np.array([7.0, 0])),
    ),
    Case("apply_homography", g.apply_homography, (HOM, PTS2)),
    Case("estimate_homography", lambda s: g.estimate_homography(s, s * 2.0 + 1.0), (SQ,)),
    Case("estimate_projection_matrix", g.estimate_projection_matrix, (PTS3 * 3, UV), atol=1e-8),
    Case("rvec_to_matrix", g.rvec_to_matrix, (RVEC,)),
    Case("matrix_to_rvec", g.matrix_to_rvec, (R,)),
    Case("matrix_to_quaternion", g.matrix_to_quaternion, (R,)),
    Case("quaternion_to_matrix", g.quaternion_to_matrix, (QUAT,)),
    Case("euler_to_matrix", lambda a: g.euler_to_matrix(a, "ZYX"), (RVEC,)),
    Case("matrix_to_euler", lambda m: g.matrix_to_euler(m, "xyz"), (R,)),
    Case("axis_rotation", lambda a: g.axis_rotation("y", a), (RVEC,)),
    Case("is_rotation", g.is_rotation, (R,)),
    Case("look_at", lambda e, t: g.look_at(e, t)[0], (T, PTS3[0])),
    Case("intrinsic_matrix", g.intrinsic_matrix, tuple(np.array(v) for v in (5.0, 6, 1, 2))),
    Case("projection_matrix", g.projection_matrix, (K, R, T)),
    Case(
        "decompose_projection_matrix",
        lambda p: g.decompose_projection_matrix(p)[0],
        (g.projection_matrix(K, R, T),),
    ),
    Case("project_points", lambda *a: g.project_points(*a).uv, (PTS3 + [0, 0, 3], K, R, T)),
    Case("backproject", g.backproject, (UV, K, R)),
    Case("unproject", lambda uv, d: g.unproject(uv, d, K, R, T), (UV, PTS3[:, 2] + 3)),
    Case("orthographic_project", g.orthographic_project, (PTS3,)),
    Case("weak_perspective_project", g.weak_perspective_project, (PTS3 + [0, 0, 3], K)),
    Case("vanishing_point", lambda k: g.vanishing_point(k, [1.0, 0.0, 2.0]), (K,)),
    Case("horizon_line", g.horizon_line, (K,)),
    Case("vanishing_point_from_lines", g.vanishing_point_from_lines, (LINES,), atol=1e-9),
    Case("lines_from_segments", g.lines_from_segments, (SEGS,)),
    Case(
        "focal_from_vanishing_points",
        g.focal_from_vanishing_points,
        (VPS[0], VPS[1], np.array([320.0, 240.0])),
    ),
    Case("intrinsics_from_vanishing_points", g.intrinsics_from_vanishing_points, VPS, atol=1e-8),
    Case("BrownConrady.distort", BC.distort, (XYN,)),
    Case("BrownConrady.undistort", lambda x: BC.undistort(x)[0], (BC.distort(XYN),), atol=1e-9),
    Case("KannalaBrandt.distort", KB.distort, (XYN,)),
    Case("KannalaBrandt.undistort", lambda x: KB.undistort(x)[0], (KB.distort(XYN),), atol=1e-9),
    Case("DivisionModel.distort", DIV.distort, (XYN,), atol=1e-9),
    Case("DivisionModel.undistort", lambda x: DIV.undistort(x)[0], (XYN,)),
    Case(
        "project_points_distorted",
        lambda *a: g.project_points_distorted(*a, BC)[0],
        (PTS3 + [0, 0, 3], K, R, T),
    ),
    Case("undistortion_map", lambda k: g.undistortion_map((5, 7), k, BC), (KSMALL,)),
    Case("remap_bilinear", g.remap_bilinear, (IMG8, g.undistortion_map((8, 8), KSMALL, BC))),
    Case("undistort_image", lambda im: g.undistort_image(im, KSMALL, BC), (IMG8,)),
    Case(
        "undistort_image[kannala_brandt]",
        lambda im: g.undistort_image(im, KSMALL, KB),
        (IMG8,),
        covers=("undistort_image",),
    ),
]

#: Public names that are not in the matrix, and why.
EXCLUDED: dict[str, str] = {
    # estimation routines documented as NumPy-only (iterative solvers on host, small inputs)
    "calibrate_camera": "estimation, NumPy-only by design (Zhang + LM refinement on host)",
    "solve_pnp": "estimation, NumPy-only by design",
    "solve_pnp_ransac": "estimation, NumPy-only by design",
    "triangulate_points": "estimation, NumPy-only by design",
    "srgb8_to_lab": "8-bit tables, NumPy uint8 only by design (convert takes other arrays)",
    "find_homography": "robust estimation (RANSAC + LM), NumPy-only by design",
    "find_fundamental_matrix": "robust estimation (RANSAC + LM), NumPy-only by design",
    "find_essential_matrix": "robust estimation (RANSAC + LM), NumPy-only by design",
    "fundamental_7point": "minimal solver on host, NumPy-only by design",
    "fundamental_8point": "linear solver on host, NumPy-only by design",
    "essential_5point": "minimal solver on host, NumPy-only by design",
    "recover_pose": "estimation (cheirality test), NumPy-only by design",
    "triangulate_two_view": "estimation, NumPy-only by design",
    "solve_pnp_batch": "estimation, NumPy-only by design",
    "stereo_calibrate": "estimation (joint LM over two cameras), NumPy-only by design",
    "stereo_rectify": "small matrices from a calibration, NumPy-only by design",
    "rectification_map": "builds NumPy maps for remap_bilinear, NumPy-only by design",
    "stereo_disparity": "semi-global matching in numba kernels (NumPy twins), NumPy-only by design",
    "disparity_to_depth": "a depth map from a NumPy disparity map and Q, NumPy-only by design",
    "disparity_to_points": "a point map from a NumPy disparity map and Q, NumPy-only by design",
    "find_checkerboard": "image detector, NumPy-only by design",
    "detect_horizon": "image detector (Hough, LSD, region statistics), NumPy-only by design",
    "find_checkerboards": "image detector, NumPy-only by design",
    "detect_aruco_markers": "image detector, NumPy-only by design",
    "solve_square_pose": "estimation (IPPE-square + LM on four corners), NumPy-only by design",
    "marker_points": "a marker's four corners in its own frame: a constant, NumPy",
    "grid_marker_map": "a marker map's corners (a layout of constants): NumPy",
    "identify_aruco_dictionary": "image detector, NumPy-only by design",
    "brettel_planes": "the Brettel model's constant planes for a deficiency (NumPy)",
    "detect_charuco": "image detector, NumPy-only by design",
    "aruco_dictionary": "a lookup by name: returns NumPy tables",
    "aruco_marker_image": "prints a uint8 marker image (NumPy)",
    "refine_corners": "checkerboard corner refinement, NumPy-only by design",
    "refine_corners_symmetric": "checkerboard corner refinement, NumPy-only by design",
    "detect_features": "image detector (OpenCV's SIFT), NumPy-only by design",
    "field_of_view_mask": "a mask from a video's frames (OpenCV components), NumPy-only",
    "still_mask": "a keypoint mask from a video's frames (OpenCV morphology), NumPy-only",
    "highlight_mask": "a keypoint mask of one frame (OpenCV dilation), NumPy-only",
    "frame_sharpness": "a scalar per video frame (OpenCV Laplacian on the host), NumPy-only",
    "blurred_frames": "a frame selection from frame_sharpness's scalars, NumPy-only",
    "match_features": "descriptor matching on host, NumPy-only by design",
    "bundle_adjust": "estimation (scipy's sparse least squares), NumPy-only by design",
    "reconstruct_sequence": "structure from motion over image files, NumPy-only by design",
    "detect_line_segments": "LSD detector, NumPy-only by design",
    "lsd_segments": "LSD with every parameter, NumPy-only by design",
    "detect_vanishing_points": "VP detector, NumPy-only by design",
    "estimate_distortion_from_lines": "plumb-line distortion from an image, NumPy-only by design",
    # no array input: built from names/parameters; they return NumPy constants
    "checkerboard_points": "no array input (pattern size -> NumPy grid)",
    "camera_rotation": "no array input (Python float angles)",
    "orthographic_matrix": "no array input (Python floats -> NumPy matrix)",
    "weak_perspective_matrix": "returns a NumPy constant matrix from K and a float depth",
    "projected_size": "scalar formula on Python floats",
    "perspective_type": "returns a Python int (a classification, not an array)",
    "chromatic_adaptation_matrix": "whites by name or (x, y): a NumPy constant matrix",
    "cvd_matrix": "no array input (deficiency name -> NumPy matrix)",
    "machado_matrix": "no array input (deficiency name -> NumPy matrix)",
    "rgb_to_xyz_matrix": "no array input (space name -> NumPy matrix)",
    "rgb_space": "no array input (space name -> RGBSpace record)",
    "xyz_to_rgb_matrix": "no array input (space name -> NumPy matrix)",
    "resolve_white": "no array input (white name / tuple -> NumPy XYZ)",
    "whitepoint_xy": "no array input (name -> Python floats)",
    "whitepoint_xyz": "no array input (name -> NumPy XYZ)",
    "xy_to_xyz_white": "no array input (tuple -> NumPy XYZ)",
    "gamut_area": "no array input (space name -> float)",
    "gamut_coverage": "no array input (space name -> float)",
    "gamut_figures": "no array input (space names -> records)",
    "gamut_triangle": "no array input (space name -> NumPy vertices)",
    "spectral_locus": "no array input (observer -> NumPy tables)",
    "visible_area": "no array input (observer -> float)",
    "polygon_area": "geometry of a few vertices -> Python float",
    "palette": "no array input (palette name -> NumPy colours)",
    "viridis": "no array input (n -> NumPy colours)",
    "parse_colors": "parses colour strings (hex, names) -> NumPy",
    "describe_delta_e": "a Python float -> a sentence",
    "path": "conversion-graph query (space names -> edge list)",
    "space_name": "a space name -> its canonical spelling",
    "are_metamers": "Spectrum objects (NumPy-backed spectral module)",
    "match_with_primaries": "Spectrum objects (NumPy-backed spectral module)",
    "metamer": "Spectrum objects (NumPy-backed spectral module)",
    "metamerism_index": "Spectrum objects (NumPy-backed spectral module)",
    "tristimulus": "Spectrum objects (NumPy-backed spectral module)",
}

_NO_STRICT_DASK_INPUT = "not applicable"


def _result(case: Case, out: Any) -> Any:
    return case.pick(out) if case.pick is not None else out


def _dtype_name(x: Any) -> str:
    return str(x.dtype).rsplit(".", 1)[-1]


@pytest.mark.parametrize("backend", BACKENDS[1:])
@pytest.mark.parametrize("case", CASES, ids=[cs.name for cs in CASES])
def test_same_kind_and_numbers(case: Case, backend: str) -> None:
    if backend not in ("torch", "dask", "array_api_strict"):
        pytest.skip(backend)
    if backend in case.skip:
        pytest.skip(case.skip[backend])
    if backend == "torch":
        pytest.importorskip("torch")
    if backend == "dask":
        pytest.importorskip("dask.array")
    ref = _result(case, case.fn(*case.args))
    out = _result(case, case.fn(*[to_backend(a, backend) for a in case.args]))
    ref_np = np.asarray(ref)
    got = to_np(out)
    assert got.shape == ref_np.shape
    if case.same_kind:
        assert isinstance(out, array_type(backend)), type(out)
        if backend == "torch":
            assert out.device.type == "cpu"
        assert _dtype_name(out) == ref_np.dtype.name
    np.testing.assert_allclose(got, ref_np, atol=case.atol, rtol=1e-12, equal_nan=True)


@pytest.mark.parametrize(
    "case",
    [cs for cs in CASES if cs.name in ("srgb_to_linear", "xyz_to_lab", "project_points")],
    ids=lambda cs: cs.name,
)
def test_float32_stays_float32(case: Case) -> None:
    torch = pytest.importorskip("torch")
    out = case.fn(*[to_backend(a, "torch", "float32") for a in case.args])
    out = _result(case, out)
    assert out.dtype == torch.float32


def test_every_public_function_is_covered() -> None:
    covered = set()
    for cs in CASES:
        covered.update(cs.covers or (cs.name.split(".")[0].split("[")[0],))
    public = {n for m in (c, g) for n in m.__all__ if inspect.isfunction(getattr(m, n))}
    missing = public - covered - set(EXCLUDED)
    assert not missing, f"public functions neither in the matrix nor excluded: {sorted(missing)}"
    stale = set(EXCLUDED) - public
    assert not stale, f"excluded names that are not public functions: {sorted(stale)}"
    assert not (covered & set(EXCLUDED) & public)


@pytest.mark.parametrize("backend", ["numpy", "array_api_strict", "torch"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_values_are_refused_on_every_backend(backend: str, bad: float) -> None:
    # the finiteness check is a min/max reduction (NaN propagates through both by the
    # standard); every backend must still refuse NaN and either infinity, wherever it sits
    if backend == "torch":
        pytest.importorskip("torch")
    from imageform.errors import InvalidInputError

    for pos in [(0, 0, 0), (3, 5, 2), (2, 1, 1)]:
        rgb = RGB.copy()
        rgb[pos] = bad
        with pytest.raises(InvalidInputError, match="NaN or inf"):
            c.convert(to_backend(rgb, backend), "srgb", "lab")
        pts = PTS3.copy()
        pts[pos[0], pos[2] % 2] = bad
        with pytest.raises(InvalidInputError, match="NaN or inf"):
            g.to_homogeneous(to_backend(pts[:, :2], backend))
