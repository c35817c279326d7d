# ruff: noqa: E501
"""One valid call per public callable, the base of the fuzz test (:mod:`tests.fuzz.runner`).

Every name :func:`tests.fuzz.runner.public_callables` finds must have an entry here
(``tests/fuzz/test_fuzz.py`` fails otherwise): ``call(...)`` with valid arguments (fixture
values by name: ``V("rgb")``, see :mod:`tests.fuzz.values`), ``method(<the class's entry>,
...)`` for a method, or ``Skip(reason)``. Entries marked ``TODO`` were drafted by
``python -m tests.fuzz.bootstrap`` and still need a valid call written by hand: each one
written widens the fuzz test.
"""

from __future__ import annotations

import numpy as np

from imageform.geometry import Camera, CharucoBoard, MarkerMap
from imageform.io import CameraColor, CameraFile, CameraOptics, icc_profile, parse_icc
from tests.fuzz.runner import C, Skip, call, method
from tests.fuzz.values import V

VALID: dict[str, C | Skip] = {
    "imageform.analysis.ChartPatches": call(
        np.full((2, 3), 0.5),
        np.full((2, 3), 0.01),
        np.zeros(2, dtype=bool),
        np.zeros(2, dtype=bool),
    ),
    "imageform.analysis.ColorCorrection": call("linear", 1, np.eye(3)),
    "imageform.analysis.CorrectionReport": call(
        np.array([3.0, 4.0]), np.array([1.0, 2.0]), np.array([True, True])
    ),
    "imageform.analysis.BackgroundEstimate": Skip(
        "a result dataclass built by estimate_background"
    ),
    "imageform.analysis.FlatfieldEstimate": Skip(
        "a result dataclass built by estimate_flatfield and estimate_vignetting"
    ),
    "imageform.analysis.HsvSegmentation": Skip("a result dataclass built by segment_hsv"),
    "imageform.analysis.LabeledImage": call(image=V("rgb"), mask=np.ones((6, 8), dtype=bool)),
    "imageform.analysis.MacenkoStains": call(
        np.array([[0.65, 0.70, 0.29], [0.07, 0.99, 0.11]]), np.array([1.5, 1.2])
    ),
    "imageform.analysis.ReinhardStats": call((50.0, 5.0, -5.0), (10.0, 4.0, 4.0), 100),
    "imageform.analysis.SensitivityEstimate": Skip(
        "a result dataclass built by estimate_camera_sensitivities"
    ),
    "imageform.analysis.StainMixture": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.analysis.chart_patches": call(V("chart")),
    "imageform.analysis.correct_flatfield": call(
        V("rgb"), np.full((6, 8), 0.8), mask=np.ones((6, 8), dtype=bool)
    ),
    "imageform.analysis.correction_report": call(V("rgb_chart"), V("rgb_chart"), V("correction")),
    "imageform.analysis.estimate_camera_sensitivities": call(
        np.linspace(0.1, 1.0, 72).reshape(24, 3), light="D65", smoothness=0.1
    ),
    "imageform.analysis.estimate_flatfield": call(
        np.linspace(0.1, 1.0, 3 * 16 * 16).reshape(3, 16, 16), max_reweightings=1
    ),
    "imageform.analysis.estimate_vignetting": call(
        V("rgb"), mask=np.ones((6, 8), dtype=bool), center="mask"
    ),
    "imageform.analysis.fit_color_correction": call(V("rgb_chart"), V("rgb_chart")),
    "imageform.analysis.macenko_normalize": call(V("stain"), V("stain")),
    "imageform.analysis.macenko_stains": call(image=V("rgb_big"), mask=None),  # noise: no tissue
    "imageform.analysis.mask_iou": call(np.eye(4, dtype=bool), np.eye(4, dtype=bool)),
    "imageform.analysis.optical_density": call(image=V("rgb")),
    "imageform.analysis.overlay_mask": call(image=V("rgb"), mask=np.ones((6, 8), dtype=bool)),
    "imageform.analysis.reinhard_normalize": call(image=V("rgb"), target=V("rgb")),
    "imageform.analysis.reinhard_stats": call(image=V("rgb")),
    "imageform.analysis.root_polynomial_terms": call(rgb=V("rgb4"), degree=1),
    "imageform.analysis.segment_hsv": call(image=V("rgb")),
    "imageform.analysis.segmentation.disc": call(radius=2),
    "imageform.analysis.stain_angle": call(
        np.array([0.65, 0.70, 0.29]), np.array([0.07, 0.99, 0.11])
    ),
    "imageform.analysis.stain_concentrations": call(
        V("stain"), np.array([[0.65, 0.70, 0.29], [0.07, 0.99, 0.11]])
    ),
    "imageform.analysis.synthetic_chart_image": call(),
    "imageform.analysis.synthetic_endoscopy_image": call(),
    "imageform.analysis.synthetic_shading_scene": call(),
    "imageform.analysis.synthetic_stain_image": call(),
    "imageform.analysis.tissue_mask": call(image=V("rgb"), pixel_size_um=0.5),
    "imageform.batch.BatchReport": call("white_balance", (V("job_result"),)),
    "imageform.batch.BatchReport.count": method(V("batch_report"), status="done"),
    "imageform.batch.BatchReport.to_dict": method(V("batch_report")),
    "imageform.batch.ChunkedResult": Skip(
        "a result record of process_chunked (fuzzed through process_chunked)"
    ),
    "imageform.batch.Job": call(V("png_file"), V("tmpfile_png")),
    "imageform.batch.JobResult": call(V("png_file"), V("tmpfile_png"), "done"),
    "imageform.batch.chunked.open_lazy": call(V("tiff_file")),
    "imageform.batch.plan_jobs": call(V("png_glob"), V("tmpdir")),
    "imageform.batch.print_summary": call(V("batch_report")),
    "imageform.batch.process_chunked": call(
        V("tiff_file"), V("tmpfile_tif"), "white_balance", chunk=16, tile=16, num_workers=1
    ),
    "imageform.batch.run_batch": Skip(
        "starts a scheduler and worker processes for a folder of files (slow; tested in tests/batch)"
    ),
    "imageform.batch.run_job": call("white_balance", V("png_file"), V("tmpfile_png")),
    "imageform.cli.main": Skip(
        "the command line (reads sys.argv, exits): fuzzed through files, not here"
    ),
    "imageform.cli.root": Skip("the typer app: tested through the command line"),
    "imageform.color.BrettelPlanes": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.color.GamutFigures": call("srgb", 0.11, 0.18, 0.35, 0.33, 0.5, 0.4),
    "imageform.color.LinearLightComparison": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.color.PaletteCheck": Skip("a result dataclass built by check_palette"),
    "imageform.color.PaletteCheck.as_dict": method(V("palette_check")),
    "imageform.color.RGBSpace": call(
        "test", ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06)), (0.3127, 0.3290), "srgb", "test"
    ),
    "imageform.color.SpectralLocus": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.color.SubsampledChroma": call(luma=V("gray"), chroma=np.full((3, 4, 2), 0.1)),
    "imageform.color.WhiteBalanceResult": call(image=V("rgb"), gains=np.array([1.0, 1.1, 0.9])),
    "imageform.color.adobe_rgb_to_linear": call(values=V("rgb4")),
    "imageform.color.are_metamers": call(s1=V("spectrum"), s2=V("spectrum")),
    "imageform.color.bgr_to_srgb": call(image=V("rgb")),
    "imageform.color.brettel_planes": call(deficiency="protan"),
    "imageform.color.cct_to_xy": call(cct=5000.0),
    "imageform.color.check_in_locus": call(V("xy")),
    "imageform.color.chroma_subsample": call(ycbcr=V("rgb")),
    "imageform.color.chroma_upsample": call(luma=V("gray"), chroma=np.full((3, 4, 2), 0.1)),
    "imageform.color.chromatic_adaptation": call(xyz=V("xyz"), src_white="D65", dst_white="A"),
    "imageform.color.chromatic_adaptation_matrix": call(src_white="D65", dst_white="A"),
    "imageform.color.cmy_to_cmyk": call(cmy=V("rgb4")),
    "imageform.color.cmy_to_srgb": call(cmy=V("rgb4")),
    "imageform.color.cmyk_to_cmy": call(cmyk=np.full((4, 4), 0.25)),
    "imageform.color.cmyk_to_srgb": call(cmyk=np.full((4, 4), 0.25)),
    "imageform.color.convert": call(image=V("rgb"), src="srgb", dst="lab"),
    "imageform.color.srgb8_to_lab": call(V("rgb_u8")),
    "imageform.color.convert.Edge": Skip(
        "a graph edge of the colour-conversion registry (internal record)"
    ),
    "imageform.color.cvd_matrix": call(deficiency="protan"),
    "imageform.color.decode": call(values=V("rgb4")),
    "imageform.color.delta_e": call(lab1=V("lab"), lab2=V("lab")),
    "imageform.color.delta_e_cie76": call(lab1=V("lab"), lab2=V("lab")),
    "imageform.color.delta_e_cie94": call(lab1=V("lab"), lab2=V("lab")),
    "imageform.color.delta_e_ciede2000": call(lab1=V("lab"), lab2=V("lab")),
    "imageform.color.delta_e_cmc": call(lab1=V("lab"), lab2=V("lab")),
    "imageform.color.describe_delta_e": call(value=1.0),
    "imageform.color.downsample": call(image=V("rgb"), factor=2),
    "imageform.color.encode": call(values=V("rgb4")),
    "imageform.color.estimate_illuminant": call(image=V("rgb"), mask=np.ones((6, 8), dtype=bool)),
    "imageform.color.from_opencv": call(V("rgb_u8"), "bgr"),
    "imageform.color.gamma_to_linear": call(values=V("rgb4")),
    "imageform.color.gamut_area": call(),
    "imageform.color.gamut_coverage": call(),
    "imageform.color.gamut_figures": call(),
    "imageform.color.gamut_map": call(xyz=V("xyz")),
    "imageform.color.gamut_triangle": call(),
    "imageform.color.gray_to_srgb": call(np.full((6, 8, 1), 0.5)),
    "imageform.color.hsi_to_srgb": call(hsi=V("rgb4")),
    "imageform.color.hsl_to_srgb": call(hsl=V("rgb4")),
    "imageform.color.hsv_to_srgb": call(hsv=V("rgb4")),
    "imageform.color.hue_difference": call(h1=np.array([10.0, 200.0]), h2=np.array([350.0, 20.0])),
    "imageform.color.hue_distance": call(h1=np.array([10.0, 200.0]), h2=np.array([350.0, 20.0])),
    "imageform.color.hue_in_range": call(hue=np.array([10.0, 200.0]), start=10.0, stop=200.0),
    "imageform.color.hue_undefined_mask": call(values=V("rgb4")),
    "imageform.color.in_gamut": call(values=V("rgb4")),
    "imageform.color.in_locus": call(points=V("points2")),
    "imageform.color.lab_to_lch": call(lab=V("lab")),
    "imageform.color.lab_to_xyz": call(lab=V("lab")),
    "imageform.color.lch_to_lab": call(lch=V("lab")),
    "imageform.color.linear_light_error": call(image=V("rgb")),
    "imageform.color.linear_rgb_to_xyz": call(rgb=V("rgb4")),
    "imageform.color.linear_srgb_to_luminance": call(image=V("rgb")),
    "imageform.color.linear_srgb_to_xyz": call(rgb=V("rgb4")),
    "imageform.color.linear_to_adobe_rgb": call(values=V("rgb4")),
    "imageform.color.linear_to_gamma": call(values=V("rgb4")),
    "imageform.color.linear_to_prophoto": call(values=V("rgb4")),
    "imageform.color.linear_to_rec2020": call(values=V("rgb4")),
    "imageform.color.linear_to_rec709": call(values=V("rgb4")),
    "imageform.color.linear_to_srgb": call(values=V("rgb4")),
    "imageform.color.luv_to_xyz": call(luv=V("lab")),
    "imageform.color.machado_matrix": call(deficiency="protan"),
    "imageform.color.match_with_primaries": call(target=V("spectrum"), primaries=V("spectrum3")),
    "imageform.color.mean_linear_light": call(image=V("rgb")),
    "imageform.color.metamer": call(spectrum=V("spectrum")),
    "imageform.color.metamerism_index": call(s1=V("spectrum"), s2=V("spectrum")),
    "imageform.color.palette": call("okabe_ito"),
    "imageform.color.palette_check": call(colors="#ff0000,#00ff00,#0000ff"),
    "imageform.color.parse_colors": call(colors="#ff0000,#00ff00,#0000ff"),
    "imageform.color.path": call(src="srgb", dst="lab"),
    "imageform.color.polygon_area": call(vertices=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])),
    "imageform.color.prophoto_to_linear": call(values=V("rgb4")),
    "imageform.color.rec2020_to_linear": call(values=V("rgb4")),
    "imageform.color.rec709_to_linear": call(values=V("rgb4")),
    "imageform.color.resolve_white": call(white="D65"),
    "imageform.color.rgb_space": call(space="srgb"),
    "imageform.color.rgb_to_xyz_matrix": call(),
    "imageform.color.rgb_to_ycbcr": call(image=V("rgb")),
    "imageform.color.simulate_cvd": call(image=V("rgb"), deficiency="protan"),
    "imageform.color.space_name": call(name="srgb"),
    "imageform.color.spectral_locus": call(),
    "imageform.color.srgb_to_bgr": call(image=V("rgb")),
    "imageform.color.srgb_to_cmy": call(image=V("rgb")),
    "imageform.color.srgb_to_cmyk": call(image=V("rgb")),
    "imageform.color.srgb_to_gray": call(image=V("rgb")),
    "imageform.color.srgb_to_hsi": call(image=V("rgb")),
    "imageform.color.srgb_to_hsl": call(image=V("rgb")),
    "imageform.color.srgb_to_hsv": call(image=V("rgb")),
    "imageform.color.srgb_to_linear": call(values=V("rgb4")),
    "imageform.color.srgb_to_ycbcr": call(image=V("rgb")),
    "imageform.color.subsample_round_trip": call(image=V("rgb")),
    "imageform.color.subsampling_delta_e": call(image=V("rgb")),
    "imageform.color.to_opencv": call(V("rgb"), "bgr"),
    "imageform.color.tristimulus": call(spectrum=V("spectrum")),
    "imageform.color.uv1960_to_xy": call(uv=V("uv")),
    "imageform.color.uv_prime_to_xy": call(uv=V("uv")),
    "imageform.color.viridis": call(),
    "imageform.color.visible_area": call(),
    "imageform.color.white_balance": call(image=V("rgb"), mask=np.ones((6, 8), dtype=bool)),
    "imageform.color.white_balance.white_balance_gains": call(image=V("rgb")),
    "imageform.color.white_balance.apply_white_balance_gains": call(
        image=V("rgb"), gains=(1.1, 1.0, 0.9)
    ),
    "imageform.color.whitepoint_xy": call(name="D65"),
    "imageform.color.whitepoint_xyz": call(name="D65"),
    "imageform.color.xy_to_cct": call(xy=V("xy")),
    "imageform.color.xy_to_uv1960": call(xy=V("xy")),
    "imageform.color.xy_to_uv_prime": call(xy=V("xy")),
    "imageform.color.xy_to_xyz": call(xy=V("xy")),
    "imageform.color.xy_to_xyz_white": call((0.3127, 0.3290)),
    "imageform.color.xyy_to_xyz": call(xyy=V("xyz")),
    "imageform.color.xyz_to_lab": call(xyz=V("xyz")),
    "imageform.color.xyz_to_linear_rgb": call(xyz=V("xyz")),
    "imageform.color.xyz_to_linear_srgb": call(xyz=V("xyz")),
    "imageform.color.xyz_to_luv": call(xyz=V("xyz")),
    "imageform.color.xyz_to_rgb_matrix": call(),
    "imageform.color.xyz_to_uv_prime": call(xyz=V("xyz")),
    "imageform.color.xyz_to_xy": call(xyz=V("xyz")),
    "imageform.color.xyz_to_xyy": call(xyz=V("xyz")),
    "imageform.color.ycbcr_to_rgb": call(ycbcr=V("rgb")),
    "imageform.color.ycbcr_to_srgb": call(ycbcr=V("rgb")),
    "imageform.geometry.BrownConrady": call(),
    "imageform.geometry.BrownConrady.from_opencv": call(dist_coeffs=np.zeros(5)),
    "imageform.geometry.CalibrationResult": Skip(
        "a result dataclass built by calibrate_camera (its methods are fuzzed on a fixture)"
    ),
    "imageform.geometry.CalibrationResult.from_fit": Skip(
        "an internal constructor from the refinement's RefineOutput (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.CalibrationResult.from_toml": call(V("calibration_toml")),
    "imageform.geometry.CalibrationResult.to_toml": method(
        V("calibration"), path=V("tmpfile_toml")
    ),
    "imageform.geometry.Camera": call(K=V("K")),
    "imageform.geometry.Camera.from_projection_matrix": call(P=V("P")),
    "imageform.geometry.Camera.in_image": method(V("camera"), uv=V("uv")),
    "imageform.geometry.Camera.look_at": call(
        V("K"), np.array([0.0, 0.0, -5.0]), np.zeros(3), (0.0, -1.0, 0.0), (8, 6)
    ),
    "imageform.geometry.ArucoDictionary": call(
        "tiny", 3, np.array([[[1, 0, 1], [0, 1, 0], [1, 1, 0]]], np.uint8), 0
    ),
    "imageform.geometry.ArucoMarkers": Skip("a result dataclass built by detect_aruco_markers"),
    "imageform.geometry.CharucoBoard": call((5, 7), 30.0, 24.0, "4x4_50"),
    "imageform.geometry.CharucoCorners": Skip("a result dataclass built by detect_charuco"),
    "imageform.geometry.CheckerboardResult": call(True, np.zeros((6, 2)), "", (3, 2)),
    "imageform.geometry.ConeBeamGeometry": call(1.0, 0.5, 1e-4, (64, 48)),
    "imageform.geometry.DecomposedProjection": call(K=V("K"), R=V("R"), t=V("t")),
    "imageform.geometry.Dehomogenized": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.geometry.DivisionModel": call(),
    "imageform.geometry.ImagePlane": Skip("a typing.Literal alias, not a callable"),
    "imageform.geometry.Intrinsics": call(fx=500.0, fy=500.0, cx=4.0, cy=3.0),
    "imageform.geometry.Intrinsics.from_fov": call(fov_x=1.0, image_size=(8, 6)),
    "imageform.geometry.Intrinsics.from_matrix": call(K=V("K")),
    "imageform.geometry.Intrinsics.from_physical": call(
        focal_length_mm=0.05, pixel_pitch_um=3.0, image_size=(8, 6)
    ),
    "imageform.geometry.Intrinsics.from_sensor": call(
        focal_length_mm=0.05, sensor_size_mm=(6.4, 4.8), image_size=(8, 6)
    ),
    "imageform.geometry.KannalaBrandt": call(),
    "imageform.geometry.LineSegments": call(
        np.array([[[0.0, 0.0], [10.0, 1.0]], [[0.0, 5.0], [10.0, 4.0]]]), np.ones(2), -np.ones(2)
    ),
    "imageform.geometry.PnPResult": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.geometry.Pose": call(R=V("R"), t=V("t")),
    "imageform.geometry.Projection": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.geometry.RefinedCorners": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.geometry.TriangulationResult": Skip(
        "a result NamedTuple (no validation of its own)"
    ),
    "imageform.geometry.Undistorted": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.geometry.PlumbLineResult": Skip(
        "a result dataclass built by estimate_distortion_from_lines"
    ),
    "imageform.geometry.VanishingPointResult": Skip(
        "a result dataclass built by detect_vanishing_points"
    ),
    "imageform.geometry.aruco_dictionary": call("4x4_50"),
    "imageform.geometry.aruco_marker_image": call(0, "4x4_50", size_px=24, border_bits=1),
    "imageform.geometry.apply_homography": call(H=V("H"), points=V("points2")),
    "imageform.geometry.are_collinear": call(points=V("points2")),
    "imageform.geometry.axis_rotation": call(axis="x", angle=0.3),
    "imageform.geometry.backproject": call(uv=V("uv"), K=V("K")),
    "imageform.geometry.calibrate_camera": call(V("stereo_objs"), V("stereo_left"), (640, 480)),
    "imageform.geometry.calibration_refine.RefineOutput": Skip(
        "an internal record of the calibration refinement (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_refine.global_names": call("kannala_brandt"),
    "imageform.geometry.calibration_refine.normal_blocks": Skip(
        "an internal step of calibrate_camera on its packed parameter vector (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_refine.project_views": Skip(
        "an internal step of calibrate_camera on its packed parameter vector (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_refine.refine": Skip(
        "an internal step of calibrate_camera on its packed parameter vector (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_refine.schur_step": Skip(
        "an internal step of calibrate_camera on its normal equations' blocks (fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_zhang.centre_intrinsics": Skip(
        "an internal step of calibrate_camera (homographies of views; fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_zhang.dlt_init": call([V("points3")], [V("points3_uv")]),
    "imageform.geometry.calibration_zhang.homographies": call(V("stereo_objs"), V("stereo_left")),
    "imageform.geometry.calibration_zhang.homographies_of": Skip(
        "an internal step of calibrate_camera on views it checked (fuzzed through homographies)"
    ),
    "imageform.geometry.calibration_zhang.poses_from_homographies": Skip(
        "an internal step of calibrate_camera (homographies of views; fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.calibration_zhang.zhang_intrinsics": Skip(
        "an internal step of calibrate_camera (homographies of views; fuzzed through calibrate_camera)"
    ),
    "imageform.geometry.camera_rotation": call(pitch=0.1),
    "imageform.geometry.checkerboard_candidates.Candidates": Skip(
        "an internal record of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_candidates.find_candidates": call(gray=V("gray"), sigma=1.0),
    "imageform.geometry.checkerboard_candidates.ring_test": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.cell_parity_ok": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.grow_rectangle": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.label_lattice": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.lattice_problem": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.lattice_problem_numpy": Skip(
        "the NumPy twin of an internal step of the checkerboard detector (fuzzed through "
        "find_checkerboard with IMAGEFORM_DISABLE_NUMBA)"
    ),
    "imageform.geometry.checkerboard_grid.lattice_rectangle": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_grid.neighbors": Skip(
        "an internal step of the checkerboard detector (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_points": call(pattern_size=(4, 3)),
    "imageform.geometry.checkerboard_subpix.as_gray": call(image=V("rgb_big")),
    "imageform.geometry.checkerboard_subpix.block_mean": Skip(
        "an internal step of find_checkerboard's symmetric method on large windows, on its "
        "clean grey image (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.gray_codes": call(image=V("rgb_big")),
    "imageform.geometry.checkerboard_subpix.gray_from_codes": Skip(
        "an internal step of the checkerboard detector on gray_codes' output (fuzzed through "
        "find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.grid_maps": Skip(
        "an internal step of find_checkerboard's symmetric method on its clean corner grid "
        "(fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.refine": Skip(
        "an internal numba step of refine_corners (fuzzed through refine_corners)"
    ),
    "imageform.geometry.checkerboard_subpix.refine_local_inside": Skip(
        "an internal step of find_checkerboard's symmetric method on clean input (fuzzed "
        "through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.refine_symmetric": Skip(
        "an internal numba step of refine_corners_symmetric (fuzzed through it)"
    ),
    "imageform.geometry.checkerboard_subpix.refine_symmetric_inside": Skip(
        "an internal step of find_checkerboard's symmetric method on clean input (fuzzed "
        "through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.refine_symmetric_pyramid": Skip(
        "an internal step of find_checkerboard's symmetric method on large windows, on clean "
        "input (fuzzed through find_checkerboard)"
    ),
    "imageform.geometry.checkerboard_subpix.room_to_border": Skip(
        "an internal step on clean corner arrays of find_checkerboard (fuzzed through it)"
    ),
    "imageform.geometry.cross_ratio": call(
        a=np.array([1.0, 2.0]),
        b=np.array([2.0, 3.0]),
        c=np.array([3.0, 4.0]),
        d=np.array([4.0, 5.0]),
    ),
    "imageform.geometry.decompose_projection_matrix": call(P=V("P")),
    "imageform.geometry.detect_line_segments": call(image=V("rgb")),
    "imageform.geometry.detect_vanishing_points": call(
        segments=V("segments"), image_size=(16, 12), max_trials=50
    ),
    "imageform.geometry.estimate_distortion_from_lines": call(V("board_grey"), min_lines=1),
    "imageform.geometry.estimate_homography": call(
        V("uv"), np.array([[3.1, 4.2], [5.3, 6.4], [8.6, 3.1], [10.25, 7.5]])
    ),
    "imageform.geometry.estimate_projection_matrix": call(V("points3"), V("points3_uv")),
    "imageform.geometry.euler_to_matrix": call(angles=np.array([0.1, 0.2, 0.3]), order="xyz"),
    "imageform.geometry.detect_aruco_markers": call(V("rgb_big"), "4x4_50", min_side_px=8.0),
    "imageform.geometry.identify_aruco_dictionary": call(V("rgb_big"), min_markers=2),
    "imageform.geometry.detect_charuco": call(
        V("rgb_big"), CharucoBoard((5, 7), 30.0, 24.0, "4x4_50"), min_markers=2
    ),
    "imageform.geometry.find_checkerboard": call(image=V("rgb_big"), pattern_size=(4, 3)),
    "imageform.geometry.find_checkerboards": call(images=[V("rgb_big")], pattern_size=(4, 3)),
    "imageform.geometry.checkerboard.set_pattern_size": call(sizes=[(9, 6), None, (9, 6)]),
    "imageform.geometry.focal_from_vanishing_points": call(
        np.array([600.0, 3.0]), np.array([-400.0, 3.0]), np.array([4.0, 3.0])
    ),
    "imageform.geometry.from_homogeneous": call(points=V("points3")),
    "imageform.geometry.from_homogeneous_masked": call(points=V("points3")),
    "imageform.geometry.horizon_line": call(K=V("K")),
    "imageform.geometry.intersect_lines": call(
        l1=np.array([1.0, 0.0, -2.0]), l2=np.array([0.0, 1.0, -3.0])
    ),
    "imageform.geometry.intrinsic_matrix": call(fx=500.0, fy=500.0, cx=4.0, cy=3.0),
    "imageform.geometry.intrinsics_from_vanishing_points": call(
        np.array([600.0, -200.0]), np.array([-500.0, -200.0]), np.array([50.0, 1500.0])
    ),
    "imageform.geometry.is_rotation": call(R=V("R")),
    "imageform.geometry.line_through": call(np.array([0.0, 0.0]), np.array([1.0, 2.0])),
    "imageform.geometry.lines_from_segments": call(
        np.array([[[0.0, 0.0], [10.0, 1.0]], [[0.0, 5.0], [10.0, 4.0]]])
    ),
    "imageform.geometry.look_at": call(eye=(0.0, 0.0, -5.0), target=V("rgb")),
    "imageform.geometry.matrix_to_euler": call(R=V("R"), order="xyz"),
    "imageform.geometry.matrix_to_quaternion": call(R=V("R")),
    "imageform.geometry.matrix_to_rvec": call(R=V("R")),
    "imageform.geometry.orthographic_matrix": call(),
    "imageform.geometry.orthographic_project": call(points=V("points3")),
    "imageform.geometry.perspective_type": call(directions=np.eye(3)),
    "imageform.geometry.project_points": call(points=V("points3"), K=V("K")),
    "imageform.geometry.project_points_distorted": call(
        points=V("points3"), K=V("K"), R=V("R"), t=V("t"), distortion=V("brown")
    ),
    "imageform.geometry.projected_size": call(size=1.0, depth=4.0, focal_length=0.05),
    "imageform.geometry.projection_matrix": call(K=V("K")),
    "imageform.geometry.quaternion_to_matrix": call(q=np.array([1.0, 0.0, 0.0, 0.0])),
    "imageform.geometry.refine_corners": call(image=V("rgb_big"), corners=V("uv")),
    "imageform.geometry.refine_corners_symmetric": call(image=V("rgb_big"), corners=V("uv")),
    "imageform.geometry.remap_bilinear": call(image=V("rgb"), map_uv=np.zeros((6, 8, 2))),
    "imageform.geometry.rvec_to_matrix": call(rvec=V("rvec")),
    "imageform.geometry.solve_pnp": call(V("points3"), V("points3_uv"), V("K")),
    "imageform.geometry.solve_pnp_ransac": call(
        V("points3"), V("points3_uv"), V("K"), max_trials=50
    ),
    "imageform.geometry.to_homogeneous": call(points=V("points3")),
    "imageform.geometry.triangulate_points": call(V("P_stack"), V("pts_stack")),
    "imageform.geometry.undistort_image": call(image=V("rgb"), K=V("K"), distortion=V("brown")),
    "imageform.geometry.undistortion_map": call(shape=(6, 8), K=V("K"), distortion=V("brown")),
    "imageform.geometry.unproject": call(uv=V("uv"), depth=V("depth"), K=V("K")),
    "imageform.geometry.vanishing_point": call(K=V("K"), direction=np.array([0.0, 0.0, 1.0])),
    "imageform.geometry.vanishing_point_from_lines": call(lines=V("lines")),
    "imageform.geometry.weak_perspective_matrix": call(K=V("K"), depth=4.0),
    "imageform.geometry.weak_perspective_project": call(points=V("points3"), K=V("K")),
    "imageform.io.CameraColor": call(white_balance=(2.0, 1.0, 1.5), illuminant="D65"),
    "imageform.io.CameraColor.from_table": call({"ccm": [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]}),
    "imageform.io.CameraColor.to_dict": method(call(white_balance=(2.0, 1.0, 1.5))),
    "imageform.io.CameraFile": call(camera=V("camera")),
    "imageform.io.CameraFile.from_calibration": call(V("calibration")),
    "imageform.io.CameraOptics": call(model="mtf50", mtf50_cy_per_px=0.3),
    "imageform.io.CameraOptics.from_table": call({"model": "diffraction", "f_number": 4.0}),
    "imageform.io.CameraOptics.mtf50_rgb": method(call(model="mtf50", mtf50_cy_per_px=0.3)),
    "imageform.io.CameraOptics.to_dict": method(call(model="gaussian", gaussian_sigma_px=1.0)),
    "imageform.io.CameraSensitivity": call(
        wavelengths_nm=(450.0, 550.0, 650.0),
        r=(0.0, 0.2, 1.0),
        g=(0.2, 1.0, 0.2),
        b=(1.0, 0.2, 0.0),
    ),
    "imageform.io.CameraSensitivity.from_table": call(
        {"wavelengths_nm": [450, 650], "r": [0, 1], "g": [1, 1], "b": [1, 0]}
    ),
    "imageform.io.CameraSensitivity.to_array": method(
        call(wavelengths_nm=(450.0, 650.0), r=(0.0, 1.0), g=(1.0, 1.0), b=(1.0, 0.0))
    ),
    "imageform.io.CameraSensitivity.to_dict": method(
        call(wavelengths_nm=(450.0, 650.0), r=(0.0, 1.0), g=(1.0, 1.0), b=(1.0, 0.0))
    ),
    "imageform.io.CameraSensor": call(read_noise_e=2.0, system_gain_dn_per_e=0.5),
    "imageform.io.CameraSensor.from_table": call({"read_noise_e": 2.0, "cfa": "RGGB"}),
    "imageform.io.CameraSensor.to_dict": method(call(read_noise_e=2.0)),
    "imageform.io.DeclaredColorSpace": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.DicomInfo": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.ExifCamera": Skip("a result dataclass (no validation of its own)"),
    "imageform.io.ExifCamera.describe": Skip("a result dataclass's text (no arguments)"),
    "imageform.io.IccProfile": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.ImageFrames": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.ImageInfo": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.Provenance": call(),
    "imageform.io.WrittenImage": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.io.camera_file.distortion_name": call(None),
    "imageform.io.dicom_info": call(V("dicom_file")),
    "imageform.io.dicom_window": call(np.array([-1000.0, 40.0, 1000.0]), 40.0, 400.0),
    "imageform.io.exif_camera": call(V("png_file")),
    "imageform.io.icc_profile": call(space="display_p3"),
    "imageform.io.identify_icc": call(parse_icc(icc_profile("display_p3"))),
    "imageform.io.image_color_space": call(V("png_file")),
    "imageform.io.image_files": call(V("png_dir")),
    "imageform.io.image_format": call(path=V("tmpfile_png")),
    "imageform.io.image_frames": call(V("tiff_file")),
    "imageform.io.image_info": call(V("png_file"), frame=0),
    "imageform.io.max_pixels": call(),
    "imageform.io.pixel_size_um": call(V("png_file")),
    "imageform.io.read_camera": call(V("camera_file")),
    "imageform.io.read_dicom": call(V("dicom_file"), frame=0, window="auto"),
    "imageform.io.read_image": call(V("png_file"), frame=0),
    "imageform.io.read_png": call(V("png_file")),
    "imageform.io.parse_icc": call(icc_profile("adobe_rgb")),
    "imageform.io.write_camera": call(path=V("tmpfile_png"), camera=V("camera")),
    "imageform.io.write_image": call(path=V("tmpfile_png"), image=V("rgb")),
    "imageform.io.write_png": call(V("tmpfile_png"), V("rgb_u8")),
    "imageform.optics.ChromaticFocalLengths": Skip(
        "a result NamedTuple (no validation of its own)"
    ),
    "imageform.optics.DepthOfField": call(2.0, 1.5, 3.0, 30.0),
    "imageform.optics.ThinLensSolution": call(0.05, 2.0, 0.0513, 0.0256, False),
    "imageform.optics.aperture_diameter": call(focal_length=0.05, f_number=2.8),
    "imageform.optics.apply_vignetting": call(image=V("rgb"), falloff=np.full((6, 8), 0.8)),
    "imageform.optics.axial_chromatic_aberration": call(
        V("rgb"),
        np.full((6, 8), 3.0),
        focal_lengths=(0.0502, 0.05, 0.0499),
        f_number=2.8,
        focus=2.0,
        pixel_pitch=2e-6,
    ),
    "imageform.optics.axial_chromatic_blur_diameters": call(
        np.array([1.0, 2.0, 3.0]), focal_lengths=(0.0502, 0.05, 0.0499), f_number=2.8, focus=2.0
    ),
    "imageform.optics.blur_by_radius": call(image=V("rgb"), radius_px=np.full((6, 8), 1.0)),
    "imageform.optics.chromatic_focal_lengths": call(focal_length=0.05, abbe_number=60.0),
    "imageform.optics.circle_of_confusion": call(
        depth=V("depth"), focal_length=0.05, f_number=2.8, focus=2.0
    ),
    "imageform.optics.cos4_falloff": call(shape=(6, 8), focal_length_px=0.05),
    "imageform.optics.defocus_blur": call(
        image=V("rgb"), depth=4.0, focal_length=0.05, f_number=2.8, focus=2.0, pixel_pitch=5e-6
    ),
    "imageform.optics.defocus_radius_px": call(
        depth=V("depth"), focal_length=0.05, f_number=2.8, focus=2.0, pixel_pitch=5e-6
    ),
    "imageform.optics.depth_of_field": call(focal_length=0.05, f_number=2.8, focus=2.0, coc=3e-5),
    "imageform.optics.disc_kernel": call(radius=2),
    "imageform.optics.f_number": call(focal_length=0.05, aperture_diameter=0.01),
    "imageform.optics.field_angle": call(shape=(6, 8), focal_length_px=0.05),
    "imageform.optics.hyperfocal_distance": call(focal_length=0.05, f_number=2.8, coc=3e-5),
    "imageform.optics.lateral_chromatic_aberration": call(V("rgb"), (1.001, 1.0, 0.999)),
    "imageform.optics.magnification": call(focal_length=0.05, d_o=2.0),
    "imageform.optics.mechanical_vignetting": call(
        shape=(6, 8),
        focal_length_px=0.05,
        pupil_radius=1.0,
        barrel_radius=1.2,
        barrel_distance=0.5,
    ),
    "imageform.optics.pupil_overlap_fraction": call(1.0, 1.2, np.array([0.0, 0.5, 1.0])),
    "imageform.optics.spherical_aberration": call(
        image=V("rgb"), focal_length=0.05, f_number=2.8, pixel_pitch=5e-6, sa_coefficient=0.1
    ),
    "imageform.optics.spherical_blur_radius": call(
        focal_length=0.05, f_number=2.8, sa_coefficient=0.1
    ),
    "imageform.optics.thin_lens": call(focal_length=0.05, d_o=2.0),
    "imageform.report.ReportPaths": Skip(
        "a result record of write_report (fuzzed through write_report)"
    ),
    "imageform.report.chromaticity_plot.planckian_locus": call(
        temperatures=np.array([3000.0, 5000.0])
    ),
    "imageform.report.plot_chromaticity_diagram": call(),
    "imageform.report.display.raw_to_uint16": call(image=V("rgb")),
    "imageform.report.display.stage_display_image": call(image=V("rgb"), kind="linear"),
    "imageform.report.figures_color.photon_transfer_summary": call(result=V("result")),
    "imageform.report.figures_color.plot_delta_e": call(V("patch_measurements")),
    "imageform.report.figures_color.plot_patch_chromaticity": call(result=V("result")),
    "imageform.report.figures_color.plot_patch_snr": call(V("patch_measurements")),
    "imageform.report.figures_color.plot_photon_transfer": Skip(
        "draws the photon-transfer summary dict built by the report (fuzzed through write_report)"
    ),
    "imageform.report.figures_color.truth_xy": call(V("patch_measurements")),
    "imageform.report.figures_geometry.image_corner_pixels": call(width=8, height=6),
    "imageform.report.figures_geometry.plot_top_view": Skip(
        "draws the dict of top_view_data(result) (fuzzed through top_view_data and write_report)"
    ),
    "imageform.report.figures_geometry.top_view_axes": call(V("R"), (0.0, 0.0, 1.0)),
    "imageform.report.figures_geometry.top_view_data": call(result=V("result")),
    "imageform.report.figures_geometry.top_view_project": Skip(
        "projects with the dict of top_view_data(result) (fuzzed through top_view_data)"
    ),
    "imageform.report.figures_geometry.vanishing_overlay": call(
        result=V("result"), display=V("rgb")
    ),
    "imageform.report.figures_geometry.vanishing_summary": call(result=V("result")),
    "imageform.report.html_parts.Markup": Skip("markupsafe.Markup re-exported: a str subclass"),
    "imageform.report.html_parts.e": call(text="hello"),
    "imageform.report.html_parts.figure": call(b"\x89PNG", "alt", "caption"),
    "imageform.report.html_parts.figure_png": Skip(
        "renders a matplotlib figure object to PNG bytes (no fuzzable value)"
    ),
    "imageform.report.html_parts.img_tag": call(b"\x89PNG", "alt"),
    "imageform.report.html_parts.json_block": call({"a": 1}, "summary"),
    "imageform.report.html_parts.note": call(text="hello"),
    "imageform.report.html_parts.page": call("title", "sub", [("a", "A")], "<p>x</p>"),
    "imageform.report.html_parts.section": call("id", "title", "<p>x</p>"),
    "imageform.report.html_parts.table": call(["a", "b"], [[1, 2]]),
    "imageform.report.lecture.WorkedExample": Skip(
        "a record holding a callable, built by the lecture module (its values are checked by tests/report)"
    ),
    "imageform.report.lecture.WorkedExample.agrees": method(V("worked_example")),
    "imageform.report.lecture.WorkedExample.computed": method(V("worked_example")),
    "imageform.report.lecture.WorkedExample.expected_values": method(V("worked_example")),
    "imageform.report.lecture.all_examples": call(),
    "imageform.report.lecture.lecture_topics": call(),
    "imageform.report.metrics.to_json_value": call(value=1.0),
    "imageform.report.overlays.draw_vanishing_overlay": Skip(
        "draws a VanishingPointResult (fuzzed through detect_vanishing_points and the vanishing workflow)"
    ),
    "imageform.report.overlays.draw_vanishing_truth_overlay": call(
        V("rgb_big"), np.array([20.0, 10.0])
    ),
    "imageform.report.patches.measure_patches": call(result=V("result")),
    "imageform.report.patches.patch_windows": call(V("cc_truth"), 36, 64),
    "imageform.report.patches.snr_stage": call(result=V("result")),
    "imageform.report.write_report": call(result=V("result"), out_dir=V("tmpdir")),
    "imageform.sensor.ComparisonRow": call("aspect", "ccd", "cmos"),
    "imageform.sensor.EmvaFrames": Skip(
        "a record built by simulate_emva_frames (fuzzed through measure_emva)"
    ),
    "imageform.sensor.EmvaMeasurement": Skip("a result dataclass built by measure_emva"),
    "imageform.sensor.EmvaResult": Skip("a result dataclass built by fit_photon_transfer"),
    "imageform.sensor.FixedPattern": Skip("a result dataclass built by fixed_pattern"),
    "imageform.sensor.PhotonTransferData": Skip(
        "a record built by measure_photon_transfer (fuzzed through fit_photon_transfer)"
    ),
    "imageform.sensor.SensorModel": call(),
    "imageform.sensor.ccd_preset": call(),
    "imageform.sensor.cfa_masks": call(shape=(6, 8)),
    "imageform.sensor.cfa_pattern": call(pattern="RGGB"),
    "imageform.sensor.cmos_preset": call(),
    "imageform.sensor.comparison_table": call(),
    "imageform.sensor.demosaic": call(raw=V("gray")),
    "imageform.sensor.emva_snr": call(
        1000.0, quantum_efficiency=0.6, dark_noise_e=3.0, system_gain=0.5
    ),
    "imageform.sensor.fit_photon_transfer": call(V("photon_data")),
    "imageform.sensor.fixed_pattern": call((6, 8, 3), prnu=0.01, dsnu=1.0, column_fpn=0.5, rng=0),
    "imageform.sensor.measure_emva": call(
        V("emva_flats"), V("emva_darks"), V("emva_times"), photons=V("emva_photons")
    ),
    "imageform.sensor.mosaic": call(rgb=V("rgb")),
    "imageform.sensor.superpixel": call(np.full((4, 6), 0.5), "RGGB"),
    "imageform.sensor.equalize_cfa": call(np.full((4, 6), 0.5), "RGGB"),
    "imageform.sensor.photons_per_pixel": call(
        irradiance=1.0, wavelength_nm=550.0, pixel_area=1e-11, exposure_time=0.01
    ),
    "imageform.sensor.rolling_shutter_points": call(
        points_uv=V("uv"), velocity_uv=(10.0, 0.0), line_time=1e-5
    ),
    "imageform.sensor.rolling_shutter_skew": call(velocity=10.0, line_time=1e-5),
    "imageform.sensor.row_start_times": call(rows=6, mode="rolling", line_time=1e-5),
    "imageform.sensor.shutter_capture": Skip(
        "takes a render callable of time (no fuzzable value; tested in tests/sensor)"
    ),
    "imageform.sensor.simulate_emva_frames": call(
        sensor=V("sensor"),
        irradiance=1.0,
        wavelength_nm=550.0,
        exposure_times=np.array([0.0, 0.001]),
        rng=0,
        shape=(6, 8),
    ),
    "imageform.sensor.simulate_photon_transfer": call(
        sensor=V("sensor"),
        irradiance=1.0,
        wavelength_nm=550.0,
        exposure_times=np.array([0.001, 0.002, 0.004]),
        rng=0,
    ),
    "imageform.sensor.temporal_noise_dn": call(1000.0, system_gain=0.5, dark_noise_e=3.0),
    "imageform.simulate.CameraConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.CameraConfig.from_camera": call(camera=V("camera")),
    "imageform.simulate.CameraConfig.to_camera": method(
        V("camera_config"), image_size=(64, 36), sensor_pixel_pitch_m=2e-6
    ),
    "imageform.simulate.ColorCheckerTruth": Skip("a result dataclass built by colorchecker_truth"),
    "imageform.simulate.PatchMeasurements": Skip(
        "a result dataclass built by measure_colorchecker"
    ),
    "imageform.simulate.RenderOutput": Skip("a result dataclass built by render_scene"),
    "imageform.simulate.Scene": Skip(
        "built by load_scene/default_scene (its methods are fuzzed on a fixture)"
    ),
    "imageform.simulate.Scene.resized": method(V("scene"), width=32),
    "imageform.simulate.Scene.view": Skip(
        "the fixture scene (default_scene) has no [[views]]: fuzzed through scene files"
    ),
    "imageform.simulate.Scene.with_camera": method(V("scene"), camera=V("camera")),
    "imageform.simulate.Scene.with_changes": method(V("scene"), lens={"f_number": 4.0}),
    "imageform.simulate.Scene.with_measured": method(V("scene"), measured=None),
    "imageform.simulate.SceneConfig": Skip("a scene file parsed (fuzzed through scene files)"),
    "imageform.simulate.SceneConfig.from_dict": Skip(
        "takes validate_scene_dict output; fuzzed through load_scene and validate_scene_dict"
    ),
    "imageform.simulate.SceneConfig.to_dict": method(V("scene_config")),
    "imageform.simulate.SceneObject": Skip(
        "a scene object built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.SceneQuad": call(name="D65", corners=V("uv")),
    "imageform.simulate.SimulationResult": call(stages=(), camera=V("camera"), image_size=(8, 6)),
    "imageform.simulate.SimulationResult.stage": method(V("result"), name="raw"),
    "imageform.simulate.Stage": call("raw", "Raw", "the raw image", V("gray"), "raw"),
    "imageform.simulate.VanishingTruth": call(
        np.array([4.0, 3.0, 1.0]), np.array([0.0, 1.0, -3.0])
    ),
    "imageform.simulate.apply_color_correction": call(V("rgb"), np.eye(3)),
    "imageform.simulate.budget.available_memory_bytes": call(),
    "imageform.simulate.budget.estimate_memory_bytes": call(width=8, height=6),
    "imageform.simulate.budget.format_bytes": call(n=5),
    "imageform.simulate.config.CheckerboardConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.ColorCheckerConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.DistortionConfig": call(),
    "imageform.simulate.config.DistortionConfig.from_model": call(V("brown")),
    "imageform.simulate.config.GroundConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.IlluminantConfig": call("blackbody", "light", 3000.0, None, 500.0),
    "imageform.simulate.config.ImageConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.LensConfig": call(2.8, 2.0, False, "cos4", (1.0, 1.0, 1.0)),
    "imageform.simulate.config.ObjectConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.PlaneConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.ProcessingConfig": call(
        "menon", True, "gray_world", "none", "srgb", "srgb"
    ),
    "imageform.simulate.config.RenderConfig": call(32, 18, 1, 0.2),
    "imageform.simulate.config.SensorConfig": Skip(
        "a scene-file section built by the scene parser (fuzzed through scene files)"
    ),
    "imageform.simulate.config.SensorConfig.to_model": method(V("sensor_config")),
    "imageform.simulate.config.ViewConfig": call(
        (0.0, 0.0, -2.0), (0.0, 0.0, 0.0), (0.0, -1.0, 0.0)
    ),
    "imageform.simulate.default_scene": call(),
    "imageform.simulate.fit_color_correction": call(V("rgb_chart"), V("rgb_chart")),
    "imageform.simulate.load_scene": call('name = "tiny"\n[render]\nwidth = 32\nheight = 18\n'),
    "imageform.simulate.materials.electron_rates": Skip(
        "an internal step of render_scene on its reflectance table (fuzzed through render_scene)"
    ),
    "imageform.simulate.materials.reflectance_spectrum": call(value=1.0),
    "imageform.simulate.materials.scene_irradiance": call(
        V("spectrum"), 500.0, np.arange(400.0, 701.0, 10.0)
    ),
    "imageform.simulate.materials.texture_basis": call(),
    "imageform.simulate.render.load_texture": call(V("png_file_str"), None),
    "imageform.simulate.render.pixel_rays": call(
        V("camera"), np.array([0.0, 4.0]), np.array([0.0, 3.0])
    ),
    "imageform.simulate.render.raycast_quads_numpy": Skip(
        "an internal step of render_scene on its quad table (fuzzed through render_scene)"
    ),
    "imageform.simulate.render_scene": call(scene=V("scene")),
    "imageform.simulate.schema.Field": call("float", 1.0, "a value"),
    "imageform.simulate.simulate": call(scene=V("scene")),
    "imageform.simulate.LabSet": Skip("a result record of render_lab_set"),
    "imageform.simulate.MeasuredCamera": call(),
    "imageform.simulate.apply_camera_file": call(
        V("scene"),
        CameraFile(
            Camera([[60.0, 0, 31.5], [0, 60.0, 23.5], [0, 0, 1]], image_size=(64, 48)),
            sensor={"read_noise_e": 4.0},
            optics={"model": "gaussian", "gaussian_sigma_px": 1.0},
        ),
    ),
    "imageform.simulate.gaussian_sigma_for_mtf50": call(0.25, supersampling=2),
    "imageform.simulate.measured_sensor.measured_sensor": call(V("sensor"), None),
    "imageform.simulate.render_lab_set": Skip(
        "renders eleven scenes and writes a folder of PNGs (tens of seconds); its checks are "
        "in tests/workflows/test_lab_set.py"
    ),
    "imageform.simulate.stages.measured_color_matrix": call(
        CameraColor(ccm=((1.2, -0.1, -0.1), (-0.1, 1.2, -0.1), (0.0, -0.2, 1.2)))
    ),
    "imageform.simulate.stages.measured_optics_blur": call(
        V("rgb"),
        CameraOptics(model="gaussian", gaussian_sigma_px=1.0),
        pixel_pitch=2e-6,
        supersampling=2,
    ),
    "imageform.simulate.stages.ColorCorrected": call(image=V("rgb"), matrix=np.eye(3)),
    "imageform.simulate.stages.Encoded": call(image=V("rgb"), transfer="srgb"),
    "imageform.simulate.stages.WhiteBalanced": call(
        image=V("rgb"), gains=np.array([1.0, 1.1, 0.9])
    ),
    "imageform.simulate.stages.apply_lens": call(
        V("render_output"), V("camera"), V("lens_config"), 4.0
    ),
    "imageform.simulate.stages.balance_white": call(image=V("rgb"), method="gray_world"),
    "imageform.simulate.stages.capture_raw": Skip(
        "an internal stage of simulate (takes a Generator; fuzzed through simulate)"
    ),
    "imageform.simulate.stages.correct_color": call(image=V("rgb"), method="gray_world"),
    "imageform.simulate.stages.correct_lens_shading": call(
        image=V("rgb"), falloff=np.full((6, 8), 0.8)
    ),
    "imageform.simulate.stages.decode_output": call(V("encoded"), "srgb"),
    "imageform.simulate.stages.demosaic_raw": call(np.full((8, 8), 0.3), "rggb", "bilinear"),
    "imageform.simulate.stages.encode_output": call(
        linear_srgb=V("rgb"), space="srgb", transfer="srgb"
    ),
    "imageform.simulate.stages.exposure_time": call(
        np.full((6, 8, 3), 1000.0), V("sensor_config"), V("sensor")
    ),
    "imageform.simulate.stages.measure_photon_transfer": Skip(
        "an internal stage of simulate (takes a Generator; fuzzed through simulate)"
    ),
    "imageform.simulate.stages.normalize_raw": call(
        raw=V("gray"), sensor=V("sensor"), exposure_time_s=0.01
    ),
    "imageform.simulate.textures.resolve_path": call("in.png", V("png_dir")),
    "imageform.simulate.truth.colorchecker_truth": call(V("colorchecker_obj"), V("camera")),
    "imageform.simulate.truth.delta_e_patches": call(np.full((24, 3), 0.3), np.full((24, 3), 50.0)),
    "imageform.simulate.truth.detect_vanishing": Skip(
        "runs detect_vanishing_points on a rendered image (slow; fuzzed through detect_vanishing_points)"
    ),
    "imageform.simulate.truth.light_cct": call(V("spectrum")),
    "imageform.simulate.truth.measure_colorchecker": Skip(
        "an internal stage of simulate on its rendered images (fuzzed through simulate)"
    ),
    "imageform.simulate.truth.patch_means": call(np.full((36, 64, 3), 0.3), V("cc_truth")),
    "imageform.simulate.truth.patch_stats": call(np.full((36, 64, 3), 0.3), V("cc_truth")),
    "imageform.simulate.truth.rails_truth": call(V("ground_obj"), V("camera")),
    "imageform.simulate.truth.vanishing_errors": call(V("vanishing_truth")),
    "imageform.simulate.truth.xy_of_linear_srgb": call(rgb=V("rgb4")),
    "imageform.simulate.validation.find_line": call(
        text="a = 1\n[camera]\nf = 2\n", path=("camera", "f")
    ),
    "imageform.simulate.validation.validate_scene_dict": call(
        {"name": "tiny", "render": {"width": 32, "height": 18}}
    ),
    "imageform.spectral.DataTable": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.spectral.IntegrationWeights": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.spectral.PlanckianCCT": Skip("a result NamedTuple (no validation of its own)"),
    "imageform.spectral.Spectrum": call(
        np.arange(400.0, 701.0, 100.0), np.array([0.1, 0.5, 0.7, 0.3]), name="s"
    ),
    "imageform.spectral.Spectrum.allclose": method(V("spectrum"), other=V("spectrum")),
    "imageform.spectral.Spectrum.from_columns": call(
        np.arange(400.0, 701.0, 100.0),
        [np.array([0.1, 0.5, 0.7, 0.3]), np.array([0.2, 0.2, 0.2, 0.2])],
    ),
    "imageform.spectral.Spectrum.interpolate": method(
        V("spectrum"), wavelengths=np.arange(400.0, 701.0, 5.0)
    ),
    "imageform.spectral.Spectrum.normalize": method(V("spectrum")),
    "imageform.spectral.Spectrum.peak_wavelength": method(V("spectrum")),
    "imageform.spectral.Spectrum.resample": method(
        V("spectrum"), start=400.0, stop=700.0, step=5.0
    ),
    "imageform.spectral.Spectrum.trim": method(V("spectrum"), start=400.0, stop=700.0),
    "imageform.spectral.blackbody_spectrum": call(temperature=5000.0),
    "imageform.spectral.camera_sensitivities": call(),
    "imageform.spectral.cmfs": call(),
    "imageform.spectral.colorchecker_published_xyy": call(),
    "imageform.spectral.colorchecker_reflectances": call(),
    "imageform.spectral.cone_fundamentals": call(),
    "imageform.spectral.daylight_spectrum": call(cct=5000.0),
    "imageform.spectral.daylight_spectrum_from_xy": call(np.array([0.3127, 0.3290])),
    "imageform.spectral.illuminant": call(name="D65"),
    "imageform.spectral.illuminant_table": call(name="D65"),
    "imageform.spectral.integration_weights": call(V("spectrum3"), illuminant=V("spectrum")),
    "imageform.spectral.led_spectrum": call(),
    "imageform.spectral.load_table": call("cmf_2"),
    "imageform.spectral.luminance": call(spectrum=V("spectrum")),
    "imageform.spectral.luminous_efficiency": call(),
    "imageform.spectral.observer_functions": call(),
    "imageform.spectral.planck": call(wavelength_nm=550.0, temperature=5000.0),
    "imageform.spectral.planckian_cct": call(np.array([0.95047, 1.0, 1.08883])),
    "imageform.spectral.read_table": call("cmf_2"),
    "imageform.spectral.resolve_illuminant": call(illuminant="D65"),
    "imageform.spectral.spectrum_to_camera_rgb": call(spectrum=V("spectrum")),
    "imageform.spectral.spectrum_to_lms": call(spectrum=V("spectrum")),
    "imageform.spectral.spectrum_to_xyz": call(spectrum=V("spectrum")),
    "imageform.spectral.table_source": call("cmf_2"),
    "imageform.workflows.Input": call(name="D65", help="help"),
    "imageform.workflows.Options": call(),
    "imageform.workflows.Options.fields": call(),
    "imageform.workflows.Options.types": call(),
    "imageform.workflows.Output": call(help="help"),
    "imageform.workflows.Result": call(summary="summary"),
    "imageform.workflows.Run": call(V("tmpdir")),
    "imageform.workflows.Workflow": Skip(
        "a registry record built by the workflows modules (fuzzed through get_workflow/execute)"
    ),
    "imageform.workflows.Workflow.make_options": method(V("workflow")),
    "imageform.workflows.calibration.CalibrateOptions": call(board="9x6"),
    "imageform.workflows.calibration.CalibrateOptions.fields": call(),
    "imageform.workflows.calibration.CalibrateOptions.types": call(),
    "imageform.workflows.calibration.UndistortOptions": call(camera=V("camera_file")),
    "imageform.workflows.calibration.UndistortOptions.fields": call(),
    "imageform.workflows.calibration.UndistortOptions.types": call(),
    "imageform.workflows.calibration.board_hint": call("9x6"),
    "imageform.workflows.calibration.board_reading": call("charuco:7x5"),
    "imageform.workflows.calibration.is_auto_board": call("auto"),
    "imageform.workflows.calibration.parse_board": call("9x6"),
    "imageform.workflows.choice_names": call(choices=("a", "b")),
    "imageform.workflows.color.ConvertOptions": call(),
    "imageform.workflows.color.ConvertOptions.fields": call(),
    "imageform.workflows.color.ConvertOptions.types": call(),
    "imageform.workflows.color.CvdOptions": call(deficiency="protan"),
    "imageform.workflows.color.CvdOptions.fields": call(),
    "imageform.workflows.color.CvdOptions.types": call(),
    "imageform.workflows.color.DeltaEOptions": call(),
    "imageform.workflows.color.DeltaEOptions.fields": call(),
    "imageform.workflows.color.DeltaEOptions.types": call(),
    "imageform.workflows.color.GamutOptions": call(),
    "imageform.workflows.color.GamutOptions.fields": call(),
    "imageform.workflows.color.GamutOptions.types": call(),
    "imageform.workflows.color.PaletteCheckOptions": call(),
    "imageform.workflows.color.PaletteCheckOptions.fields": call(),
    "imageform.workflows.color.PaletteCheckOptions.types": call(),
    "imageform.workflows.color.WhiteBalanceOptions": call(),
    "imageform.workflows.color.WhiteBalanceOptions.fields": call(),
    "imageform.workflows.color.WhiteBalanceOptions.types": call(),
    "imageform.workflows.execute": call("white_balance", image=V("png_file"), out=V("tmpfile_png")),
    "imageform.workflows.flag_of": Skip(
        "takes a dataclasses.Field of an Options class (no fuzzable value)"
    ),
    "imageform.workflows.geometry.PoseOptions": call(),
    "imageform.workflows.geometry.PoseOptions.fields": call(),
    "imageform.workflows.geometry.PoseOptions.types": call(),
    "imageform.workflows.geometry.ProjectOptions": call(fx=500.0),
    "imageform.workflows.geometry.ProjectOptions.fields": call(),
    "imageform.workflows.geometry.ProjectOptions.types": call(),
    "imageform.workflows.geometry.TriangulateOptions": call(),
    "imageform.workflows.geometry.TriangulateOptions.fields": call(),
    "imageform.workflows.geometry.TriangulateOptions.types": call(),
    "imageform.workflows.get_workflow": call("white_balance"),
    "imageform.workflows.lecture.LectureOptions": call(),
    "imageform.workflows.lecture.LectureOptions.fields": call(),
    "imageform.workflows.lecture.LectureOptions.types": call(),
    "imageform.workflows.normalize_choice": call("a", ("a", "b"), "thing"),
    "imageform.workflows.optics.LensOptions": call(focal="50mm", f_number=2.8, focus=2.0),
    "imageform.workflows.optics.LensOptions.fields": call(),
    "imageform.workflows.optics.LensOptions.types": call(),
    "imageform.workflows.run_file": Skip(
        "runs a workflow on files with an Options instance (fuzzed through execute)"
    ),
    "imageform.workflows.simulate.SimulateOptions": call(),
    "imageform.workflows.simulate.SimulateOptions.fields": call(),
    "imageform.workflows.simulate.SimulateOptions.types": call(),
    "imageform.workflows.vanishing.VanishingOptions": call(),
    "imageform.workflows.vanishing.VanishingOptions.fields": call(),
    "imageform.workflows.vanishing.VanishingOptions.types": call(),
}

#: Non-finite results that are the documented answer, not garbage: ``(callable, parameter,
#: kind) -> why``. The runner reports them as ok with the reason.
DOCUMENTED_NONFINITE: dict[tuple[str, str, str], str] = {
    ("imageform.geometry.disparity_to_depth", "disparity", "nan"): (
        "NaN marks the invalid pixels of a disparity map (stereo_disparity's), as documented"
    ),
    ("imageform.geometry.disparity_to_depth", "disparity", "zero"): (
        "a zero disparity puts the point at infinity on a zero-disparity rig: NaN, as documented"
    ),
    ("imageform.geometry.disparity_to_depth", "disparity", "negative"): (
        "a negative disparity puts the point behind the cameras: NaN, as documented"
    ),
    ("imageform.geometry.disparity_to_depth", "rectification", "negative"): (
        "a Q that puts positive disparities behind the cameras: NaN for all, as documented"
    ),
    ("imageform.geometry.disparity_to_points", "disparity", "nan"): (
        "NaN marks the invalid pixels of a disparity map (stereo_disparity's), as documented"
    ),
    ("imageform.geometry.disparity_to_points", "disparity", "zero"): (
        "a zero disparity puts the point at infinity on a zero-disparity rig: NaN, as documented"
    ),
    ("imageform.geometry.disparity_to_points", "disparity", "negative"): (
        "a negative disparity puts the point behind the cameras: NaN, as documented"
    ),
    ("imageform.geometry.disparity_to_points", "rectification", "negative"): (
        "a Q that puts positive disparities behind the cameras: NaN for all, as documented"
    ),
    ("imageform.analysis.mtf_crossing", "mtf", "huge"): (
        "a curve that never falls to the level has no crossing: NaN (SFRResult.mtf10 relies on it)"
    ),
    ("imageform.optics.depth_of_field", "coc", "huge"): (
        "focus beyond the hyperfocal distance: the far limit is infinite"
    ),
    ("imageform.optics.depth_of_field", "f_number", "huge"): (
        "focus beyond the hyperfocal distance: the far limit is infinite"
    ),
    ("imageform.optics.lateral_chromatic_aberration", "fill", "nan"): (
        "fill=NaN marks the pixels sampled from outside the image, as documented"
    ),
    ("imageform.sensor.measure_emva", "photons", "none"): (
        "without photon counts the quantum efficiency and what derives from it are unknown: NaN"
    ),
}

#: Calls of a second or more each (matplotlib figures, whole simulations, report folders):
#: in the slow run only.
SLOW: frozenset[str] = frozenset(
    {
        "imageform.report.plot_chromaticity_diagram",
        "imageform.report.write_report",
        "imageform.simulate.simulate",
        "imageform.simulate.render_scene",
        "imageform.report.figures_color.plot_patch_chromaticity",
        # seconds per call (a bundle adjustment, RANSAC, LSD, a sparse NMF, a Dask graph or a
        # whole workflow): fuzzed by the full run only
        "imageform.geometry.stereo_calibrate",
        "imageform.geometry.calibrate_camera",
        "imageform.geometry.lsd_segments",
        "imageform.geometry.find_essential_matrix",
        "imageform.geometry.find_fundamental_matrix",
        "imageform.geometry.find_homography",
        "imageform.geometry.solve_pnp_ransac",
        "imageform.analysis.vahadane_stains",
        "imageform.batch.process_chunked",
        "imageform.workflows.execute",
    }
)

# methods: the instance is built from the class's own entry above
VALID.update(
    {
        "imageform.analysis.ColorCorrection.apply": method(
            VALID["imageform.analysis.ColorCorrection"], image=V("rgb")
        ),
        "imageform.analysis.ColorCorrection.to_json": method(
            VALID["imageform.analysis.ColorCorrection"], path=V("tmpfile_png")
        ),
        "imageform.analysis.CorrectionReport.summary": method(
            VALID["imageform.analysis.CorrectionReport"]
        ),
        "imageform.analysis.MacenkoStains.to_json": method(
            VALID["imageform.analysis.MacenkoStains"], path=V("tmpfile_png")
        ),
        "imageform.analysis.ReinhardStats.to_json": method(
            VALID["imageform.analysis.ReinhardStats"], path=V("tmpfile_png")
        ),
        "imageform.geometry.BrownConrady.distort": method(
            VALID["imageform.geometry.BrownConrady"], xy=V("xy")
        ),
        "imageform.geometry.BrownConrady.undistort": method(
            VALID["imageform.geometry.BrownConrady"], xy=V("xy")
        ),
        "imageform.geometry.Camera.backproject": method(
            VALID["imageform.geometry.Camera"], uv=V("uv")
        ),
        "imageform.geometry.Camera.project": method(
            VALID["imageform.geometry.Camera"], points=V("points3")
        ),
        "imageform.geometry.Camera.undistort_pixels": method(
            VALID["imageform.geometry.Camera"], uv=V("uv")
        ),
        "imageform.geometry.Camera.unproject": method(
            VALID["imageform.geometry.Camera"], uv=V("uv"), depth=V("depth")
        ),
        "imageform.geometry.Camera.world_to_camera": method(
            VALID["imageform.geometry.Camera"], points=V("points3")
        ),
        "imageform.geometry.DivisionModel.distort": method(
            VALID["imageform.geometry.DivisionModel"], xy=V("xy")
        ),
        "imageform.geometry.DivisionModel.undistort": method(
            VALID["imageform.geometry.DivisionModel"], xy=V("xy")
        ),
        "imageform.geometry.Intrinsics.scaled": method(
            VALID["imageform.geometry.Intrinsics"], factor=2
        ),
        "imageform.geometry.KannalaBrandt.distort": method(
            VALID["imageform.geometry.KannalaBrandt"], xy=V("xy")
        ),
        "imageform.geometry.KannalaBrandt.undistort": method(
            VALID["imageform.geometry.KannalaBrandt"], xy=V("xy")
        ),
        "imageform.io.CameraFile.with_pose": method(
            VALID["imageform.io.CameraFile"], R=V("R"), t=V("t")
        ),
        "imageform.sensor.SensorModel.dynamic_range_db": method(
            VALID["imageform.sensor.SensorModel"]
        ),
        "imageform.sensor.SensorModel.fixed_pattern": method(
            VALID["imageform.sensor.SensorModel"], height=6, width=8
        ),
        "imageform.sensor.SensorModel.frame_readout_time": method(
            VALID["imageform.sensor.SensorModel"], rows=6
        ),
        "imageform.sensor.SensorModel.quantum_efficiency": method(
            VALID["imageform.sensor.SensorModel"], wavelength_nm=550.0
        ),
        "imageform.simulate.config.DistortionConfig.to_model": method(
            VALID["imageform.simulate.config.DistortionConfig"]
        ),
        "imageform.workflows.Options.check": method(VALID["imageform.workflows.Options"]),
        "imageform.workflows.Options.paths": method(
            VALID["imageform.workflows.Options"], kind="linear"
        ),
        "imageform.workflows.calibration.UndistortOptions.check": method(
            VALID["imageform.workflows.calibration.UndistortOptions"]
        ),
        "imageform.workflows.calibration.UndistortOptions.paths": method(
            VALID["imageform.workflows.calibration.UndistortOptions"], kind="linear"
        ),
        "imageform.workflows.color.ConvertOptions.check": method(
            VALID["imageform.workflows.color.ConvertOptions"]
        ),
        "imageform.workflows.color.ConvertOptions.check_used": method(
            VALID["imageform.workflows.color.ConvertOptions"]
        ),
        "imageform.workflows.color.ConvertOptions.params": method(
            VALID["imageform.workflows.color.ConvertOptions"]
        ),
        "imageform.workflows.color.ConvertOptions.paths": method(
            VALID["imageform.workflows.color.ConvertOptions"], kind="linear"
        ),
        "imageform.workflows.color.CvdOptions.check": method(
            VALID["imageform.workflows.color.CvdOptions"]
        ),
        "imageform.workflows.color.CvdOptions.paths": method(
            VALID["imageform.workflows.color.CvdOptions"], kind="linear"
        ),
        "imageform.workflows.color.DeltaEOptions.check": method(
            VALID["imageform.workflows.color.DeltaEOptions"]
        ),
        "imageform.workflows.color.DeltaEOptions.paths": method(
            VALID["imageform.workflows.color.DeltaEOptions"], kind="linear"
        ),
        "imageform.workflows.color.GamutOptions.check": method(
            VALID["imageform.workflows.color.GamutOptions"]
        ),
        "imageform.workflows.color.GamutOptions.names": method(
            VALID["imageform.workflows.color.GamutOptions"]
        ),
        "imageform.workflows.color.GamutOptions.paths": method(
            VALID["imageform.workflows.color.GamutOptions"], kind="linear"
        ),
        "imageform.workflows.color.PaletteCheckOptions.check": method(
            VALID["imageform.workflows.color.PaletteCheckOptions"]
        ),
        "imageform.workflows.color.PaletteCheckOptions.paths": method(
            VALID["imageform.workflows.color.PaletteCheckOptions"], kind="linear"
        ),
        "imageform.workflows.color.WhiteBalanceOptions.check": method(
            VALID["imageform.workflows.color.WhiteBalanceOptions"]
        ),
        "imageform.workflows.color.WhiteBalanceOptions.params": method(
            VALID["imageform.workflows.color.WhiteBalanceOptions"]
        ),
        "imageform.workflows.color.WhiteBalanceOptions.paths": method(
            VALID["imageform.workflows.color.WhiteBalanceOptions"], kind="linear"
        ),
        "imageform.workflows.geometry.PoseOptions.check": method(
            VALID["imageform.workflows.geometry.PoseOptions"]
        ),
        "imageform.workflows.geometry.PoseOptions.paths": method(
            VALID["imageform.workflows.geometry.PoseOptions"], kind="linear"
        ),
        "imageform.workflows.geometry.TriangulateOptions.check": method(
            VALID["imageform.workflows.geometry.TriangulateOptions"]
        ),
        "imageform.workflows.geometry.TriangulateOptions.paths": method(
            VALID["imageform.workflows.geometry.TriangulateOptions"], kind="linear"
        ),
        "imageform.workflows.lecture.LectureOptions.check": method(
            VALID["imageform.workflows.lecture.LectureOptions"]
        ),
        "imageform.workflows.lecture.LectureOptions.paths": method(
            VALID["imageform.workflows.lecture.LectureOptions"], kind="linear"
        ),
        "imageform.workflows.simulate.SimulateOptions.check": method(
            VALID["imageform.workflows.simulate.SimulateOptions"]
        ),
        "imageform.workflows.simulate.SimulateOptions.paths": method(
            VALID["imageform.workflows.simulate.SimulateOptions"], kind="linear"
        ),
        "imageform.workflows.vanishing.VanishingOptions.check": method(
            VALID["imageform.workflows.vanishing.VanishingOptions"]
        ),
        "imageform.workflows.vanishing.VanishingOptions.paths": method(
            VALID["imageform.workflows.vanishing.VanishingOptions"], kind="linear"
        ),
    }
)

# names added after the first table (two-view geometry, LSD, stereo, Zernike PSF, stain and CCT methods, workflows)
VALID.update(
    {
        "imageform.workflows.analysis.FitCorrectionOptions": call(),
        "imageform.workflows.analysis.HarmonizeOptions": call(correction=V("correction_json")),
        "imageform.workflows.analysis.SegmentOptions": call(),
        "imageform.workflows.analysis.StainNormalizeOptions": call(target=V("png_file")),
        "imageform.workflows.sensor.DemosaicOptions": call(),
        "imageform.workflows.sensor.MosaicOptions": call(),
        "imageform.workflows.emva.EmvaOptions": call(fit_fraction=0.6, spatial_index=2),
        "imageform.workflows.stereo.StereoCalibrateOptions": call(board="9x6"),
        "imageform.workflows.stereo.DepthOptions": call(camera=V("stereo_file")),
        "imageform.workflows.stereo.DepthOptions.fields": call(),
        "imageform.workflows.stereo.DepthOptions.types": call(),
        "imageform.workflows.analysis.FitCorrectionOptions.fields": call(),
        "imageform.workflows.analysis.FitCorrectionOptions.types": call(),
        "imageform.workflows.analysis.HarmonizeOptions.fields": call(),
        "imageform.workflows.analysis.HarmonizeOptions.types": call(),
        "imageform.workflows.analysis.SegmentOptions.fields": call(),
        "imageform.workflows.analysis.SegmentOptions.types": call(),
        "imageform.workflows.analysis.StainNormalizeOptions.fields": call(),
        "imageform.workflows.analysis.StainNormalizeOptions.types": call(),
        "imageform.workflows.sensor.DemosaicOptions.fields": call(),
        "imageform.workflows.sensor.DemosaicOptions.types": call(),
        "imageform.workflows.sensor.MosaicOptions.fields": call(),
        "imageform.workflows.sensor.MosaicOptions.types": call(),
        "imageform.workflows.emva.EmvaOptions.fields": call(),
        "imageform.workflows.emva.EmvaOptions.types": call(),
        "imageform.workflows.stereo.StereoCalibrateOptions.fields": call(),
        "imageform.workflows.stereo.StereoCalibrateOptions.types": call(),
        "imageform.analysis.background_intensity": call(image=V("rgb")),
        "imageform.analysis.estimate_background": call(image=V("rgb")),
        "imageform.analysis.synthetic_he_tile": call((32, 32)),
        "imageform.analysis.vahadane_stains": call(image=V("stain"), iterations=20, max_pixels=500),
        "imageform.batch.batch_options": call("white_balance", {}),
        "imageform.batch.batch_workflow": call("white_balance"),
        "imageform.color.cct_methods.cct_to_uv_ohno2013": call(cct=5000.0, duv=0.002),
        "imageform.color.cct_methods.planckian_uv": call(cct=5000.0),
        "imageform.color.cct_methods.uv_to_cct_ohno2013": call(
            uv=np.array([[0.2105, 0.3226], [0.2, 0.31]])
        ),
        "imageform.color.cct_methods.xy_to_cct_hernandez1999": call(xy=V("xy")),
        "imageform.color.cct_methods.xy_to_cct_mccamy1992": call(xy=V("xy")),
        "imageform.geometry.EssentialResult": Skip(
            "a result NamedTuple (no validation of its own)"
        ),
        "imageform.geometry.FundamentalResult": Skip(
            "a result NamedTuple (no validation of its own)"
        ),
        "imageform.geometry.HomographyResult": Skip(
            "a result NamedTuple (no validation of its own)"
        ),
        "imageform.geometry.RelativePose": Skip("a result NamedTuple (no validation of its own)"),
        "imageform.geometry.StereoRectification": Skip(
            "a result NamedTuple (no validation of its own)"
        ),
        "imageform.geometry.TwoViewPoints": Skip("a result NamedTuple (no validation of its own)"),
        "imageform.geometry.StereoCalibrationResult": Skip(
            "a result dataclass built by stereo_calibrate (its method is fuzzed on a fixture)"
        ),
        "imageform.geometry.StereoCalibrationResult.rectify": method(V("stereo_result"), alpha=0.0),
        "imageform.geometry.essential_5point": call(V("pts1_5"), V("pts2_5")),
        "imageform.geometry.find_essential_matrix": call(V("pts1"), V("pts2"), V("K")),
        "imageform.geometry.find_fundamental_matrix": call(V("pts1"), V("pts2")),
        "imageform.geometry.find_homography": call(
            V("uv"), np.array([[3.1, 4.2], [5.3, 6.4], [8.6, 3.1], [10.25, 7.5], [4.0, 9.0]])[:4]
        ),
        "imageform.geometry.fundamental_7point": call(V("pts1_7"), V("pts2_7")),
        "imageform.geometry.fundamental_8point": call(V("pts1"), V("pts2")),
        "imageform.geometry.lsd_segments": call(V("gray")),
        "imageform.geometry.recover_pose": call(V("E"), V("pts1"), V("pts2"), V("K")),
        "imageform.geometry.rectification_map": call(V("K"), V("brown"), V("R"), V("P"), (8, 6)),
        "imageform.geometry.solve_pnp_batch": call(V("points3"), V("points3_uv"), V("K")),
        "imageform.geometry.stereo_calibrate": call(
            V("stereo_objs"), V("stereo_left"), V("stereo_right"), (640, 480)
        ),
        "imageform.geometry.stereo_rectify": call(
            V("K"), V("brown"), V("K"), V("brown"), (8, 6), V("R"), np.array([-0.1, 0.0, 0.0])
        ),
        "imageform.geometry.stereo_disparity": call(
            V("gray"),
            V("gray"),
            num_disparities=4,
            block_size=3,
            census_threshold=1.0,
            cost_window=5,
            slant_prior=True,
        ),
        "imageform.geometry.disparity_to_depth": call(
            np.array([[8.0, 4.0, 2.0], [1.0, 16.0, 8.0]]),
            np.array([[1, 0, 0, -1.0], [0, 1, 0, -0.5], [0, 0, 0, 400.0], [0, 0, 0.01, 0]]),
        ),
        "imageform.geometry.disparity_to_points": call(
            np.array([[8.0, 4.0, 2.0], [1.0, 16.0, 8.0]]),
            np.array([[1, 0, 0, -1.0], [0, 1, 0, -0.5], [0, 0, 0, 400.0], [0, 0, 0.01, 0]]),
        ),
        "imageform.geometry.triangulate_two_view": call(V("P"), V("P2"), V("pts1"), V("pts2")),
        "imageform.io.StereoCameraFile": Skip(
            "a file record built by StereoCameraFile.from_calibration or read_stereo_camera (fuzzed there)"
        ),
        "imageform.io.StereoCameraFile.from_calibration": call(V("stereo_result")),
        "imageform.io.read_stereo_camera": call(V("stereo_file")),
        "imageform.io.write_stereo_camera": call(V("tmpfile_toml"), V("stereo_file_obj")),
        "imageform.optics.TransferFunction": Skip("a result NamedTuple (no validation of its own)"),
        "imageform.optics.diffraction_limited_mtf": call(
            np.array([0.0, 50.0, 200.0]), wavelength=550e-9, f_number=4.0
        ),
        "imageform.optics.diffraction_psf": call(
            wavelength=550e-9, f_number=4.0, pixel_pitch=2e-6, size=16, n_pupil=64
        ),
        "imageform.optics.field_psfs": call(
            np.array([[[0.0, 0.0, 0.0, 0.05], [0.0, 0.0, 0.0, 0.1]]]),
            wavelength=550e-9,
            f_number=4.0,
            pixel_pitch=2e-6,
            size=16,
            n_pupil=64,
        ),
        "imageform.optics.mtf": call(V("psf"), pixel_pitch=2e-6),
        "imageform.optics.noll_to_nm": call(4),
        "imageform.optics.otf": call(V("psf"), pixel_pitch=2e-6),
        "imageform.optics.pixel_mtf": call(np.array([0.0, 50.0, 200.0]), pixel_pitch=2e-6),
        "imageform.optics.polychromatic_psf": call(
            wavelengths=np.array([450e-9, 550e-9, 650e-9]),
            f_number=4.0,
            pixel_pitch=2e-6,
            size=16,
            n_pupil=64,
        ),
        "imageform.optics.psf_from_pupil": call(np.ones((16, 16), dtype=complex), pad_to=32),
        "imageform.optics.pupil_function": call(
            np.array([0.0, 0.0, 0.0, 0.05]), wavelength=550e-9, n_samples=32
        ),
        "imageform.optics.zernike": call(4, np.array([0.0, 0.5, 1.0]), np.array([0.0, 1.0, 2.0])),
        "imageform.optics.zernike_defocus": call(3e-5, f_number=4.0),
        "imageform.optics.zernike_radial": call(2, 0, np.array([0.0, 0.5, 1.0])),
        "imageform.optics.zernike_wavefront": call(
            np.array([0.0, 0.0, 0.0, 0.1]), np.array([0.0, 0.5, 1.0]), np.array([0.0, 1.0, 2.0])
        ),
        "imageform.simulate.stages.diffraction_blur": call(
            V("rgb"), f_number=4.0, pixel_pitch=2e-6
        ),
        "imageform.simulate.stages.wave_defocus_blur": call(
            np.full((8, 8, 3), 0.5), 1.0, f_number=4.0, pixel_pitch=3e-6
        ),
        "imageform.simulate.diffraction_psf_kernel": call(
            (450e-9, 550e-9, 650e-9), f_number=4.0, pixel_pitch=2e-6
        ),
        "imageform.analysis.ColorCorrection.from_json": call(V("correction_json")),
        "imageform.analysis.MacenkoStains.from_json": call(V("macenko_json")),
        "imageform.analysis.ReinhardStats.from_json": call(V("reinhard_json")),
    }
)

# their methods
VALID.update(
    {
        "imageform.workflows.analysis.FitCorrectionOptions.check": method(
            VALID["imageform.workflows.analysis.FitCorrectionOptions"]
        ),
        "imageform.workflows.analysis.FitCorrectionOptions.check_output": method(
            VALID["imageform.workflows.analysis.FitCorrectionOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.analysis.FitCorrectionOptions.paths": method(
            VALID["imageform.workflows.analysis.FitCorrectionOptions"], "output"
        ),
        "imageform.workflows.analysis.HarmonizeOptions.check": method(
            VALID["imageform.workflows.analysis.HarmonizeOptions"]
        ),
        "imageform.workflows.analysis.HarmonizeOptions.check_output": method(
            VALID["imageform.workflows.analysis.HarmonizeOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.analysis.HarmonizeOptions.paths": method(
            VALID["imageform.workflows.analysis.HarmonizeOptions"], "output"
        ),
        "imageform.workflows.analysis.SegmentOptions.check": method(
            VALID["imageform.workflows.analysis.SegmentOptions"]
        ),
        "imageform.workflows.analysis.SegmentOptions.check_output": method(
            VALID["imageform.workflows.analysis.SegmentOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.analysis.SegmentOptions.paths": method(
            VALID["imageform.workflows.analysis.SegmentOptions"], "output"
        ),
        "imageform.workflows.analysis.StainNormalizeOptions.check": method(
            VALID["imageform.workflows.analysis.StainNormalizeOptions"]
        ),
        "imageform.workflows.analysis.StainNormalizeOptions.check_output": method(
            VALID["imageform.workflows.analysis.StainNormalizeOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.analysis.StainNormalizeOptions.paths": method(
            VALID["imageform.workflows.analysis.StainNormalizeOptions"], "output"
        ),
        "imageform.workflows.sensor.DemosaicOptions.check": method(
            VALID["imageform.workflows.sensor.DemosaicOptions"]
        ),
        "imageform.workflows.sensor.DemosaicOptions.check_output": method(
            VALID["imageform.workflows.sensor.DemosaicOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.sensor.DemosaicOptions.paths": method(
            VALID["imageform.workflows.sensor.DemosaicOptions"], "output"
        ),
        "imageform.workflows.sensor.MosaicOptions.check": method(
            VALID["imageform.workflows.sensor.MosaicOptions"]
        ),
        "imageform.workflows.sensor.MosaicOptions.check_output": method(
            VALID["imageform.workflows.sensor.MosaicOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.sensor.MosaicOptions.paths": method(
            VALID["imageform.workflows.sensor.MosaicOptions"], "output"
        ),
        "imageform.workflows.emva.EmvaOptions.check": method(
            VALID["imageform.workflows.emva.EmvaOptions"]
        ),
        "imageform.workflows.emva.EmvaOptions.check_output": method(
            VALID["imageform.workflows.emva.EmvaOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.emva.EmvaOptions.paths": method(
            VALID["imageform.workflows.emva.EmvaOptions"], "output"
        ),
        "imageform.workflows.stereo.DepthOptions.check": method(
            VALID["imageform.workflows.stereo.DepthOptions"]
        ),
        "imageform.workflows.stereo.DepthOptions.check_output": method(
            VALID["imageform.workflows.stereo.DepthOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.stereo.DepthOptions.paths": method(
            VALID["imageform.workflows.stereo.DepthOptions"], "output"
        ),
        "imageform.workflows.stereo.StereoCalibrateOptions.check": method(
            VALID["imageform.workflows.stereo.StereoCalibrateOptions"]
        ),
        "imageform.workflows.stereo.StereoCalibrateOptions.check_output": method(
            VALID["imageform.workflows.stereo.StereoCalibrateOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.stereo.StereoCalibrateOptions.paths": method(
            VALID["imageform.workflows.stereo.StereoCalibrateOptions"], "output"
        ),
        "imageform.workflows.stereo.StereoCalibrateOptions.square_mm": method(
            VALID["imageform.workflows.stereo.StereoCalibrateOptions"]
        ),
        "imageform.workflows.Options.check_output": method(
            VALID["imageform.workflows.Options"], V("tmpfile_png")
        ),
        "imageform.workflows.calibration.CalibrateOptions.check_output": method(
            VALID["imageform.workflows.calibration.CalibrateOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.calibration.UndistortOptions.check_output": method(
            VALID["imageform.workflows.calibration.UndistortOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.ConvertOptions.check_output": method(
            VALID["imageform.workflows.color.ConvertOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.CvdOptions.check_output": method(
            VALID["imageform.workflows.color.CvdOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.DeltaEOptions.check_output": method(
            VALID["imageform.workflows.color.DeltaEOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.GamutOptions.check_output": method(
            VALID["imageform.workflows.color.GamutOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.PaletteCheckOptions.check_output": method(
            VALID["imageform.workflows.color.PaletteCheckOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.color.WhiteBalanceOptions.check_output": method(
            VALID["imageform.workflows.color.WhiteBalanceOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.geometry.PoseOptions.check_output": method(
            VALID["imageform.workflows.geometry.PoseOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.geometry.ProjectOptions.check_output": method(
            VALID["imageform.workflows.geometry.ProjectOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.geometry.TriangulateOptions.check_output": method(
            VALID["imageform.workflows.geometry.TriangulateOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.lecture.LectureOptions.check_output": method(
            VALID["imageform.workflows.lecture.LectureOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.optics.LensOptions.check_output": method(
            VALID["imageform.workflows.optics.LensOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.simulate.SimulateOptions.check_output": method(
            VALID["imageform.workflows.simulate.SimulateOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.vanishing.VanishingOptions.check_output": method(
            VALID["imageform.workflows.vanishing.VanishingOptions"], V("tmpfile_png")
        ),
    }
)

# methods of classes whose entry is above
VALID.update(
    {
        "imageform.color.GamutFigures.as_dict": method(VALID["imageform.color.GamutFigures"]),
        "imageform.color.RGBSpace.matrix_to_xyz": method(VALID["imageform.color.RGBSpace"]),
        "imageform.geometry.CharucoBoard.corner_points": method(
            VALID["imageform.geometry.CharucoBoard"]
        ),
        "imageform.geometry.CharucoBoard.image": method(
            VALID["imageform.geometry.CharucoBoard"], square_px=20, margin_px=4
        ),
        "imageform.geometry.CharucoBoard.marker_points": method(
            VALID["imageform.geometry.CharucoBoard"]
        ),
        "imageform.geometry.CharucoCorners.object_points": Skip(
            "a method of a result dataclass built by detect_charuco (no arguments)"
        ),
        "imageform.geometry.CharucoBoard.marker_squares": method(
            VALID["imageform.geometry.CharucoBoard"]
        ),
        "imageform.geometry.CheckerboardResult.grid": method(
            VALID["imageform.geometry.CheckerboardResult"]
        ),
        "imageform.geometry.ConeBeamGeometry.penumbra": method(
            VALID["imageform.geometry.ConeBeamGeometry"], 1e-3
        ),
        "imageform.geometry.ConeBeamGeometry.project": method(
            VALID["imageform.geometry.ConeBeamGeometry"],
            np.array([[0.0, 0.0, 0.5], [0.01, 0.02, 0.6]]),
        ),
        "imageform.sensor.SensorModel.capture": method(
            VALID["imageform.sensor.SensorModel"],
            np.full((6, 8, 1), 100.0),
            exposure_time=0.01,
            rng=0,
        ),
        "imageform.sensor.SensorModel.mean_electrons": method(
            VALID["imageform.sensor.SensorModel"], np.full((6, 8, 1), 100.0), exposure_time=0.01
        ),
        "imageform.sensor.SensorModel.normalise": method(
            VALID["imageform.sensor.SensorModel"], np.full((6, 8), 300.0)
        ),
        "imageform.sensor.SensorModel.normalize": method(
            VALID["imageform.sensor.SensorModel"], np.full((6, 8), 300.0)
        ),
        "imageform.workflows.Run.file": Skip(
            "needs a Run inside execute (its outputs object): fuzzed through execute"
        ),
        "imageform.workflows.Run.folder": Skip(
            "needs a Run inside execute (its outputs object): fuzzed through execute"
        ),
        "imageform.workflows.Run.note": method(VALID["imageform.workflows.Run"], text="a note"),
        "imageform.workflows.calibration.CalibrateOptions.check": method(
            VALID["imageform.workflows.calibration.CalibrateOptions"]
        ),
        "imageform.workflows.calibration.CalibrateOptions.paths": method(
            VALID["imageform.workflows.calibration.CalibrateOptions"], "output"
        ),
        "imageform.workflows.calibration.CalibrateOptions.marker_mm": method(
            call(board="charuco:7x5", square="30mm", marker="22mm")
        ),
        "imageform.workflows.calibration.CalibrateOptions.square_mm": method(
            VALID["imageform.workflows.calibration.CalibrateOptions"]
        ),
        "imageform.workflows.geometry.ProjectOptions.check": method(
            VALID["imageform.workflows.geometry.ProjectOptions"]
        ),
        "imageform.workflows.geometry.ProjectOptions.paths": method(
            VALID["imageform.workflows.geometry.ProjectOptions"], "output"
        ),
        "imageform.workflows.optics.LensOptions.check": method(
            VALID["imageform.workflows.optics.LensOptions"]
        ),
        "imageform.workflows.optics.LensOptions.lengths": method(
            VALID["imageform.workflows.optics.LensOptions"]
        ),
        "imageform.workflows.optics.LensOptions.paths": method(
            VALID["imageform.workflows.optics.LensOptions"], "output"
        ),
    }
)


# Names added by the last merges (sharpness, raw files, the report's JPEG displays).
def _edge() -> np.ndarray:
    from imageform.analysis import render_slanted_edge

    return np.asarray(render_slanted_edge((64, 48), angle_deg=5.0, sigma=0.8))


VALID.update(
    {
        "imageform.analysis.render_slanted_edge": call((64, 48), angle=5.0, sigma=0.8),
        "imageform.analysis.slanted_edge_sfr": call(_edge()),
        "imageform.analysis.render_sfr_chart": call((120, 160), grid=(1, 2), angle=5.0),
        "imageform.analysis.find_slanted_edges": call(np.full((64, 64), 0.8)),
        "imageform.analysis.mtf_crossing": call(
            np.linspace(0.0, 1.0, 11), np.linspace(1.0, 0.0, 11), 0.5
        ),
        "imageform.analysis.fit_gaussian_sigma": call(
            np.linspace(0.0, 0.5, 11), np.exp(-(np.linspace(0.0, 0.5, 11) ** 2)), angle_deg=5.0
        ),
        "imageform.analysis.SFRResult": Skip("a result dataclass built by slanted_edge_sfr"),
        "imageform.analysis.SFRResult.channel": Skip("a method of a result dataclass"),
        "imageform.analysis.SlantedEdgeROI": Skip("a result dataclass built by find_slanted_edges"),
        "imageform.analysis.SlantedEdgeROI.crop": Skip("a method of a result dataclass"),
        "imageform.io.Development": Skip("a result dataclass built by develop"),
        "imageform.io.Development.to_integer": Skip("a method of a result dataclass"),
        "imageform.io.RawImage": Skip("a result dataclass built by read_raw"),
        "imageform.io.develop": Skip("needs a raw file and the raw extra (tests/io/test_raw.py)"),
        "imageform.io.read_raw": Skip("needs a raw file and the raw extra (tests/io/test_raw.py)"),
        "imageform.io.write_dng": Skip("writes a file; its checks: tests/io/test_raw.py"),
        "imageform.report.html_parts.page_jpeg": call(np.full((6, 8, 3), 128, dtype=np.uint8)),
        "imageform.simulate.simulated_baseline_exposure": Skip("takes a whole SimulationResult"),
        "imageform.simulate.simulated_color_matrix": Skip("takes a whole SimulationResult"),
        "imageform.simulate.simulated_vignette_opcode": Skip(
            "takes a whole Scene; its law: tests/io/test_raw.py"
        ),
        "imageform.simulate.write_simulated_dng": Skip("takes a whole SimulationResult"),
        "imageform.workflows.raw.DevelopOptions": call(),
        "imageform.workflows.raw.DevelopOptions.fields": call(),
        "imageform.workflows.raw.DevelopOptions.types": call(),
        "imageform.workflows.sharpness.SfrOptions": call(),
        "imageform.workflows.sharpness.SfrOptions.fields": call(),
        "imageform.workflows.sharpness.SfrOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.workflows.raw.DevelopOptions.check": method(
            VALID["imageform.workflows.raw.DevelopOptions"]
        ),
        "imageform.workflows.raw.DevelopOptions.check_output": method(
            VALID["imageform.workflows.raw.DevelopOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.raw.DevelopOptions.paths": method(
            VALID["imageform.workflows.raw.DevelopOptions"], "output"
        ),
        "imageform.workflows.sharpness.SfrOptions.check": method(
            VALID["imageform.workflows.sharpness.SfrOptions"]
        ),
        "imageform.workflows.sharpness.SfrOptions.check_output": method(
            VALID["imageform.workflows.sharpness.SfrOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.sharpness.SfrOptions.paths": method(
            VALID["imageform.workflows.sharpness.SfrOptions"], "output"
        ),
        "imageform.workflows.sharpness.SfrOptions.region": method(
            VALID["imageform.workflows.sharpness.SfrOptions"]
        ),
        "imageform.workflows.sharpness.SfrOptions.pitch_mm": method(
            VALID["imageform.workflows.sharpness.SfrOptions"]
        ),
    }
)

# the ColorChecker detector (imageform.analysis.chart_detect) and imageform chart
VALID.update(
    {
        "imageform.analysis.ChartDetection": Skip(
            "a result dataclass built by detect_colorchecker"
        ),
        "imageform.analysis.ChartDetection.to_dict": method(V("chart_detection")),
        "imageform.analysis.ChartPhoto": Skip("a result NamedTuple (no validation of its own)"),
        "imageform.analysis.detect_colorchecker": call(V("chart_photo")),
        "imageform.analysis.measure_chart_patches": call(V("chart_photo"), V("chart_detection")),
        "imageform.analysis.synthetic_chart_photo": call(shape=(64, 96), width=0.5),
        # chart images given directly to the fit and the white balance (sample_chart)
        "imageform.analysis.ChartSample": Skip("a result dataclass built by sample_chart"),
        "imageform.analysis.ChartSample.to_dict": Skip("a method of a result dataclass"),
        "imageform.analysis.sample_chart": call(V("chart")),
        "imageform.analysis.chart_white_balance": call(V("chart")),
        "imageform.workflows.chart.ChartOptions": call(),
        "imageform.workflows.chart.ChartOptions.fields": call(),
        "imageform.workflows.chart.ChartOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.workflows.chart.ChartOptions.check": method(
            VALID["imageform.workflows.chart.ChartOptions"]
        ),
        "imageform.workflows.chart.ChartOptions.check_output": method(
            VALID["imageform.workflows.chart.ChartOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.chart.ChartOptions.paths": method(
            VALID["imageform.workflows.chart.ChartOptions"], "output"
        ),
    }
)

# imageform characterize (issue 18): the measurement dataclasses are results; the folder
# boundary (empty, missing, unreadable, half a part) is tested in tests/workflows/test_characterize.py
VALID.update(
    {
        "imageform.workflows.CameraCharacterization": Skip(
            "a result dataclass built by characterize_camera"
        ),
        "imageform.workflows.CameraCharacterization.camera_file": Skip(
            "a method of a result dataclass"
        ),
        "imageform.workflows.CameraCharacterization.summary": Skip(
            "a method of a result dataclass"
        ),
        "imageform.workflows.ColorMeasurement": Skip(
            "a result dataclass built by characterize_camera"
        ),
        "imageform.workflows.GeometryMeasurement": Skip(
            "a result dataclass built by characterize_camera"
        ),
        "imageform.workflows.NoiseMeasurement": Skip(
            "a result dataclass built by characterize_camera"
        ),
        "imageform.workflows.SharpnessMeasurement": Skip(
            "a result dataclass built by characterize_camera"
        ),
        "imageform.workflows.characterize_camera": Skip(
            "needs a lab folder (render_lab_set, seconds); its refusals (no folder, an empty "
            "one, unreadable images, half a part) are tested in tests/workflows/test_characterize.py"
        ),
        "imageform.analysis.relative_qe": call(V("spectrum")),
        "imageform.workflows.characterize.CharacterizeOptions": call(),
        "imageform.workflows.characterize.CharacterizeOptions.fields": call(),
        "imageform.workflows.characterize.CharacterizeOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.workflows.characterize.CharacterizeOptions.check": method(
            VALID["imageform.workflows.characterize.CharacterizeOptions"]
        ),
        "imageform.workflows.characterize.CharacterizeOptions.check_output": method(
            VALID["imageform.workflows.characterize.CharacterizeOptions"], V("tmpdir")
        ),
        "imageform.workflows.characterize.CharacterizeOptions.paths": method(
            VALID["imageform.workflows.characterize.CharacterizeOptions"], "output"
        ),
    }
)

# --- issue 27 (video, tracking), 28 (structure from motion) ---------------------------------
_K_TRACK = np.array([[600.0, 0.0, 200.0], [0.0, 600.0, 250.0], [0.0, 0.0, 1.0]])
_BOARD_TRACK = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
VALID.update(
    {
        "imageform.geometry.BoardPose": Skip("a result dataclass built by BoardTracker.update"),
        "imageform.geometry.BoardTracker": call(_BOARD_TRACK, _K_TRACK),
        "imageform.geometry.MarkerTracker": call(7, 40.0, _K_TRACK, dictionary="4x4_50"),
        "imageform.geometry.SquarePoses": Skip("a result NamedTuple built by solve_square_pose"),
        "imageform.geometry.marker_points": call(40.0),
        "imageform.geometry.MarkerMap": call(
            [0, 1],
            [
                [[0.0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]],
                [[20.0, 0, 0], [30, 0, 0], [30, 10, 0], [20, 10, 0]],
            ],
            "4x4_50",
        ),
        "imageform.geometry.grid_marker_map": call((3, 2), 30.0, 10.0, dictionary="4x4_50"),
        "imageform.geometry.MarkerMapTracker": call(
            MarkerMap(
                np.array([0, 1]),
                np.array(
                    [
                        [[0.0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]],
                        [[20.0, 0, 0], [30, 0, 0], [30, 10, 0], [20, 10, 0]],
                    ]
                ),
                "4x4_50",
            ),
            _K_TRACK,
        ),
        "imageform.io.read_marker_map": Skip(
            "reads a marker map file (its doctest, tests/geometry/test_marker_map.py)"
        ),
        "imageform.io.write_marker_map": call(
            V("tmpfile_png"),
            MarkerMap(
                np.array([3]), np.array([[[0.0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]]])
            ),
        ),
        "imageform.workflows.track.track_map_path": call("markers:tool.toml"),
        "imageform.geometry.solve_square_pose": call(
            [[180.0, 230.0], [220.0, 230.0], [220.0, 270.0], [180.0, 270.0]], 40.0, _K_TRACK
        ),
        "imageform.geometry.Features": Skip("a result dataclass built by detect_features"),
        "imageform.geometry.Reconstruction": Skip(
            "a result dataclass built by reconstruct_sequence"
        ),
        "imageform.geometry.bundle_adjust": Skip(
            "refines a whole reconstruction's poses and points (tests/geometry/test_sfm.py)"
        ),
        "imageform.geometry.detect_features": Skip(
            "needs the reconstruct extra (OpenCV's SIFT); tests/geometry/test_sfm.py"
        ),
        "imageform.geometry.field_of_view_mask": call(
            [np.pad(np.full((12, 12), 120, np.uint8), 4)] * 3, margin=1
        ),
        "imageform.geometry.still_mask": call(
            [np.pad(np.full((12, 12), 120, np.uint8), 4)] * 8, margin=1
        ),
        "imageform.geometry.highlight_mask": call(np.full((8, 8, 3), 250, np.uint8)),
        "imageform.geometry.frame_sharpness": call(np.full((8, 8, 3), 120, np.uint8)),
        "imageform.geometry.blurred_frames": call([np.full((8, 8), 0.5)] * 4),
        "imageform.geometry.match_features": call(
            np.linspace(0.0, 1.0, 40, dtype=np.float32).reshape(5, 8),
            np.linspace(0.0, 1.0, 40, dtype=np.float32).reshape(5, 8),
        ),
        "imageform.geometry.reconstruct_sequence": Skip(
            "structure from motion over many frames, minutes a call (tests/geometry/test_sfm.py)"
        ),
        "imageform.io.Frame": Skip("a record yielded by VideoReader"),
        "imageform.io.Interlacing": Skip("a record built by detect_interlacing"),
        "imageform.io.Interlacing.describe": Skip("a method of a record"),
        "imageform.io.detect_interlacing": call([np.full((8, 6), 90, np.uint8)] * 4),
        "imageform.io.split_fields": call(np.zeros((6, 4, 3), np.uint8), "bottom"),
        "imageform.io.field_camera_matrix": call(_K_TRACK, "bottom"),
        "imageform.io.deinterlace": call(np.zeros((6, 4, 3), np.uint8), "linear"),
        "imageform.io.VideoInfo": Skip("a record built by VideoReader"),
        "imageform.io.Plan": Skip("a record built by read_plan"),
        "imageform.io.VideoReader": Skip("reads a video or a device (tests/io/test_video.py)"),
        "imageform.io.VideoReader.close": Skip("a method of a reader of files"),
        "imageform.io.VideoWriter": Skip("writes a video file (tests/io/test_video.py)"),
        "imageform.io.VideoWriter.close": Skip("a method of a writer of files"),
        "imageform.io.VideoWriter.write": Skip("a method of a writer of files"),
        "imageform.io.open_video": Skip("reads a video or a device (tests/io/test_video.py)"),
        "imageform.io.read_plan": Skip("reads a plan file (its doctest, tests/workflows)"),
        "imageform.report.draw_pose_overlay": Skip(
            "draws a BoardTracker result on a frame (tests/workflows/test_track.py)"
        ),
        "imageform.simulate.Trajectory": Skip("a record built by read_trajectory"),
        "imageform.simulate.board_poses": Skip("takes a whole Scene and a Trajectory"),
        "imageform.simulate.read_trajectory": Skip(
            "reads a trajectory file (tests/cli/test_trajectory_track.py)"
        ),
        "imageform.simulate.render_frames": Skip("a whole simulation per frame"),
        "imageform.workflows.track.parse_track_board": call("charuco:7x5"),
        "imageform.workflows.track.TrackOptions": call(
            camera="cam.toml", board="9x6", square="30mm"
        ),
        "imageform.workflows.track.TrackOptions.fields": call(),
        "imageform.workflows.track.TrackOptions.types": call(),
        "imageform.workflows.reconstruct.ReconstructOptions": call(camera="cam.toml"),
        "imageform.workflows.reconstruct.ReconstructOptions.fields": call(),
        "imageform.workflows.reconstruct.ReconstructOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.geometry.BoardTracker.reset": method(VALID["imageform.geometry.BoardTracker"]),
        "imageform.geometry.MarkerTracker.reset": method(VALID["imageform.geometry.MarkerTracker"]),
        "imageform.geometry.MarkerMapTracker.reset": method(
            VALID["imageform.geometry.MarkerMapTracker"]
        ),
        "imageform.geometry.MarkerMapTracker.update": method(
            VALID["imageform.geometry.MarkerMapTracker"], _BOARD_TRACK.image(20, margin_px=10)
        ),
        "imageform.geometry.MarkerTracker.update": method(
            VALID["imageform.geometry.MarkerTracker"], _BOARD_TRACK.image(20, margin_px=10)
        ),
        "imageform.geometry.MarkerTracker.choose": Skip(
            "takes a SquarePoses from solve_square_pose (tests/geometry/test_marker_tracking.py)"
        ),
        "imageform.geometry.BoardTracker.update": method(
            VALID["imageform.geometry.BoardTracker"], _BOARD_TRACK.image(20, margin_px=10)
        ),
        "imageform.workflows.track.TrackOptions.check": method(
            VALID["imageform.workflows.track.TrackOptions"]
        ),
        "imageform.workflows.track.TrackOptions.check_output": method(
            VALID["imageform.workflows.track.TrackOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.track.TrackOptions.paths": method(
            VALID["imageform.workflows.track.TrackOptions"], "output"
        ),
        "imageform.workflows.reconstruct.ReconstructOptions.check": method(
            VALID["imageform.workflows.reconstruct.ReconstructOptions"]
        ),
        "imageform.workflows.reconstruct.ReconstructOptions.check_output": method(
            VALID["imageform.workflows.reconstruct.ReconstructOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.reconstruct.ReconstructOptions.paths": method(
            VALID["imageform.workflows.reconstruct.ReconstructOptions"], "output"
        ),
    }
)
VALID.update(
    {
        "imageform.analysis.FlatfieldEstimate.correct": Skip(
            "a method of a result record built by the estimators; correct_flatfield is fuzzed"
        ),
        "imageform.workflows.flatfield.FlatfieldOptions": call(method="basic"),
        "imageform.workflows.flatfield.FlatfieldOptions.fields": call(),
        "imageform.workflows.flatfield.FlatfieldOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.workflows.flatfield.FlatfieldOptions.check": method(
            VALID["imageform.workflows.flatfield.FlatfieldOptions"]
        ),
        "imageform.workflows.flatfield.FlatfieldOptions.check_output": method(
            VALID["imageform.workflows.flatfield.FlatfieldOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.flatfield.FlatfieldOptions.paths": method(
            VALID["imageform.workflows.flatfield.FlatfieldOptions"], "output"
        ),
    }
)
# the visible horizon of natural scenes (detect_horizon, imageform horizon)
VALID.update(
    {
        "imageform.geometry.detect_horizon": call(image=V("rgb_big")),
        "imageform.geometry.HorizonResult": Skip("a result dataclass built by detect_horizon"),
        "imageform.workflows.vanishing.HorizonOptions": call(),
        "imageform.workflows.vanishing.HorizonOptions.fields": call(),
        "imageform.workflows.vanishing.HorizonOptions.types": call(),
    }
)
VALID.update(
    {
        "imageform.workflows.vanishing.HorizonOptions.check": method(
            VALID["imageform.workflows.vanishing.HorizonOptions"]
        ),
        "imageform.workflows.vanishing.HorizonOptions.check_output": method(
            VALID["imageform.workflows.vanishing.HorizonOptions"], V("tmpfile_png")
        ),
        "imageform.workflows.vanishing.HorizonOptions.paths": method(
            VALID["imageform.workflows.vanishing.HorizonOptions"], kind="linear"
        ),
    }
)
