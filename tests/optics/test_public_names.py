"""Public names of the optics, sensor-model and distortion modules (removing one is deliberate)."""

from __future__ import annotations

import importlib

import pytest

PUBLIC = {
    "imageform.optics": {
        "ChromaticFocalLengths",
        "DepthOfField",
        "ThinLensSolution",
        "aperture_diameter",
        "apply_vignetting",
        "axial_chromatic_aberration",
        "axial_chromatic_blur_diameters",
        "blur_by_radius",
        "chromatic_focal_lengths",
        "circle_of_confusion",
        "cos4_falloff",
        "defocus_blur",
        "defocus_radius_px",
        "depth_of_field",
        "disc_kernel",
        "f_number",
        "field_angle",
        "hyperfocal_distance",
        "lateral_chromatic_aberration",
        "magnification",
        "mechanical_vignetting",
        "pupil_overlap_fraction",
        "spherical_aberration",
        "spherical_blur_radius",
        "thin_lens",
    },
    "imageform.geometry.distortion": {
        "NUMBA_MIN_POINTS",
        "BrownConrady",
        "DistortionModel",
        "DivisionModel",
        "KannalaBrandt",
        "Undistorted",
        "project_points_distorted",
    },
    "imageform.geometry.undistort": {"remap_bilinear", "undistort_image", "undistortion_map"},
}

SENSOR_MODEL_NAMES = {
    "CCD_VS_CMOS",
    "QUANTIZATION_NOISE_DN",
    "ComparisonRow",
    "EmvaResult",
    "FixedPattern",
    "PhotonTransferData",
    "SensorModel",
    "ccd_preset",
    "cmos_preset",
    "comparison_table",
    "emva_snr",
    "fit_photon_transfer",
    "fixed_pattern",
    "photons_per_pixel",
    "rolling_shutter_points",
    "rolling_shutter_skew",
    "row_start_times",
    "shutter_capture",
    "simulate_photon_transfer",
    "temporal_noise_dn",
}


@pytest.mark.parametrize("module", sorted(PUBLIC))
def test_public_names(module: str) -> None:
    mod = importlib.import_module(module)
    assert set(mod.__all__) == PUBLIC[module]
    for name in mod.__all__:
        assert hasattr(mod, name), name


def test_sensor_model_names_exported() -> None:
    mod = importlib.import_module("imageform.sensor")
    assert set(mod.__all__) >= SENSOR_MODEL_NAMES  # the CFA/demosaic branch adds its own
    for name in SENSOR_MODEL_NAMES:
        assert hasattr(mod, name), name
