"""API surface of imageform.color (the conversion half): removing a name is deliberate."""

from __future__ import annotations

import imageform.color as color

CONVERSION_NAMES = {
    "convert",
    "path",
    "space_name",
    "SPACES",
    "EDGES",
    "RGB_SPACES",
    "RGBSpace",
    "WHITEPOINTS_XY",
    "OBSERVERS",
    "TRANSFER_FUNCTIONS",
    "YCBCR_STANDARDS",
    "OPENCV_CONVENTIONS",
    "GRAY_METHODS",
    "whitepoint_xy",
    "whitepoint_xyz",
    "resolve_white",
    "rgb_to_xyz_matrix",
    "xyz_to_rgb_matrix",
    "srgb_to_linear",
    "linear_to_srgb",
    "linear_srgb_to_xyz",
    "xyz_to_linear_srgb",
    "xyz_to_lab",
    "lab_to_xyz",
    "lab_to_lch",
    "lch_to_lab",
    "xyz_to_luv",
    "luv_to_xyz",
    "xyz_to_xyy",
    "xyy_to_xyz",
    "srgb_to_hsv",
    "hsv_to_srgb",
    "srgb_to_hsl",
    "hsl_to_srgb",
    "srgb_to_hsi",
    "hsi_to_srgb",
    "srgb_to_ycbcr",
    "ycbcr_to_srgb",
    "srgb_to_cmy",
    "cmy_to_srgb",
    "cmy_to_cmyk",
    "cmyk_to_cmy",
    "srgb_to_gray",
    "gray_to_srgb",
    "srgb_to_bgr",
    "bgr_to_srgb",
    "to_opencv",
    "from_opencv",
    "hue_undefined_mask",
    "hue_distance",
    "hue_in_range",
    "mean_linear_light",
    "downsample",
    "linear_light_error",
}


def test_names_exported() -> None:
    missing = CONVERSION_NAMES - set(color.__all__)
    assert not missing, missing
    for name in color.__all__:
        assert hasattr(color, name), name


def test_every_edge_names_a_public_function() -> None:
    for e in color.EDGES:
        assert e.function in color.__all__, (e.src, e.dst, e.function)
        assert callable(getattr(color, e.function))
