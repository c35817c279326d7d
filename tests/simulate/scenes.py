"""Scene dicts shared by the simulate tests (small, fast renders)."""

from __future__ import annotations

from typing import Any

FX, FY, CX, CY = 560.0, 555.0, 322.0, 236.0
K1, K2 = -0.18, 0.03
SIZE = (640, 480)


def calibration_view(
    eye: tuple[float, float, float],
    up: tuple[float, float, float],
    target: tuple[float, float, float] = (0.0, 0.0, 0.0),
    supersampling: int = 2,
    noise: bool = True,
) -> dict[str, Any]:
    """A 9x6-inner-corner board (20 mm squares) at the origin, seen from ``eye``."""
    return {
        "name": "calibration view",
        "render": {
            "width": SIZE[0],
            "height": SIZE[1],
            "supersampling": supersampling,
            "background_reflectance": 0.3,
        },
        "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
        "camera": {
            "fx_px": FX,
            "fy_px": FY,
            "cx_px": CX,
            "cy_px": CY,
            "eye_m": list(eye),
            "target_m": list(target),
            "up": list(up),
            "distortion": {"k1": K1, "k2": K2},
        },
        "lens": {"defocus": False, "vignetting": "none", "f_number": 4.0},
        "sensor": {"noise": noise},
        "processing": {
            "demosaic": "malvar",
            "white_balance": "none",
            "color_correction": "none",
            "lens_shading_correction": False,
        },
        "objects": [
            {
                "type": "checkerboard",
                "center_m": [0.0, 0.0, 0.0],
                "normal": [0.0, -1.0, 0.0],
                "squares": [10, 7],
                "square_size_m": 0.02,
            }
        ],
    }


#: Eight views: camera position, world up and the point looked at (metres); the board
#: lands in different parts of the frame so that the distortion is seen out to the corners.
VIEWS = [
    ((0.0, -0.30, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.12, -0.28, 0.05), (0.0, 0.0, 1.0), (0.07, 0.0, 0.05)),
    ((-0.12, -0.28, -0.05), (0.1, 0.0, 1.0), (-0.07, 0.0, -0.05)),
    ((0.05, -0.27, 0.14), (0.0, 0.0, 1.0), (-0.07, 0.0, 0.05)),
    ((-0.08, -0.28, -0.12), (-0.15, 0.0, 1.0), (0.03, 0.0, -0.02)),
    ((0.15, -0.25, -0.08), (0.0, 0.0, 1.0), (-0.05, 0.0, 0.06)),
    ((-0.15, -0.26, 0.10), (0.2, 0.0, 1.0), (0.06, 0.0, -0.06)),
    ((0.08, -0.33, 0.08), (-0.3, 0.0, 1.0), (0.0, 0.0, 0.0)),
]


def rails_scene(width: int = 640, height: int = 360) -> dict[str, Any]:
    """Rails on a ground seen by an undistorted camera, looking down the track."""
    return {
        "name": "rails",
        "render": {"width": width, "height": height, "supersampling": 2},
        "illuminant": {"type": "daylight", "temperature_K": 6504.0},
        "camera": {
            "focal_length_mm": 1.0,
            "pixel_pitch_um": 2.0,
            "eye_m": [0.004, -0.06, 0.03],
            "target_m": [-0.01, 0.1, 0.0],
        },
        "lens": {"f_number": 8.0, "focus_distance_m": 0.1},
        # bilinear: Menon's and Malvar's zipper on thin diagonal rails breaks the LSD segments
        "processing": {"color_correction": "none", "demosaic": "bilinear"},
        # sleepers between the rails only, so that the rails' outer edges stay unbroken
        "objects": [
            {
                "type": "ground",
                "center_m": [0.0, 2.9, 0.0],
                "size_m": [0.3, 6.0],
                "rail_count": 2,
                "rail_width_m": 0.002,
                "sleeper_spacing_m": 0.01,
                "sleeper_length_m": 0.008,
            }
        ],
    }


def colorchecker_scene(width: int = 480, height: int = 320) -> dict[str, Any]:
    """A ColorChecker filling most of the frame under CIE illuminant A."""
    return {
        "name": "colorchecker under A",
        "render": {"width": width, "height": height, "supersampling": 2},
        "illuminant": {"type": "cie", "name": "A", "illuminance_lux": 1500.0},
        "camera": {"fx_px": 520.0, "eye_m": [0.0, -0.15, 0.0], "target_m": [0.0, 0.0, 0.0]},
        "lens": {"f_number": 4.0, "focus_distance_m": 0.15},
        "processing": {"white_balance": "gray_world", "color_correction": "colorchecker"},
        "objects": [{"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 0.12}],
    }
