"""imageform.color: colour spaces, the conversion graph, transfer functions, white points.

Conventions (DESIGN.md): channels-last ``(..., 3)`` arrays; encoded RGB in [0, 1]; XYZ with
Y = 1 at the reference white; L* in [0, 100]; hue in degrees [0, 360).
"""

from imageform.color.cielab import (
    lab_to_lch,
    lab_to_xyz,
    lch_to_lab,
    luv_to_xyz,
    xyy_to_xyz,
    xyz_to_lab,
    xyz_to_luv,
    xyz_to_xyy,
)
from imageform.color.rgb_spaces import (
    RGB_SPACES,
    RGBSpace,
    linear_rgb_to_xyz,
    linear_srgb_to_xyz,
    rgb_to_xyz_matrix,
    xyz_to_linear_rgb,
    xyz_to_linear_srgb,
    xyz_to_rgb_matrix,
)
from imageform.color.transfer import (
    ADOBE_RGB_GAMMA,
    TRANSFER_FUNCTIONS,
    adobe_rgb_to_linear,
    decode,
    encode,
    gamma_to_linear,
    linear_to_adobe_rgb,
    linear_to_gamma,
    linear_to_prophoto,
    linear_to_rec709,
    linear_to_rec2020,
    linear_to_srgb,
    prophoto_to_linear,
    rec709_to_linear,
    rec2020_to_linear,
    srgb_to_linear,
)
from imageform.color.whitepoints import (
    OBSERVERS,
    WHITEPOINTS_XY,
    resolve_white,
    whitepoint_xy,
    whitepoint_xyz,
    xy_to_xyz_white,
)

__all__ = [
    "ADOBE_RGB_GAMMA",
    "OBSERVERS",
    "RGB_SPACES",
    "TRANSFER_FUNCTIONS",
    "WHITEPOINTS_XY",
    "RGBSpace",
    "adobe_rgb_to_linear",
    "decode",
    "encode",
    "gamma_to_linear",
    "lab_to_lch",
    "lab_to_xyz",
    "lch_to_lab",
    "linear_rgb_to_xyz",
    "linear_srgb_to_xyz",
    "linear_to_adobe_rgb",
    "linear_to_gamma",
    "linear_to_prophoto",
    "linear_to_rec709",
    "linear_to_rec2020",
    "linear_to_srgb",
    "luv_to_xyz",
    "prophoto_to_linear",
    "rec709_to_linear",
    "rec2020_to_linear",
    "resolve_white",
    "rgb_to_xyz_matrix",
    "srgb_to_linear",
    "whitepoint_xy",
    "whitepoint_xyz",
    "xy_to_xyz_white",
    "xyy_to_xyz",
    "xyz_to_lab",
    "xyz_to_linear_rgb",
    "xyz_to_linear_srgb",
    "xyz_to_luv",
    "xyz_to_rgb_matrix",
    "xyz_to_xyy",
]

# ---- names from the colour-difference / adaptation / white-balance work (3b) go below ----
