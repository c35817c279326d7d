"""The scene schema: every key of a scene TOML file, its type, unit and default.

A scene file is validated against :data:`SCENE_SCHEMA` once, at the boundary
(:func:`imageform.simulate.load_scene`; the checks are in :mod:`.validation`). Units are part
of the key's name (``focus_distance_m``, ``exposure_time_s``); a length, time or angle may
also be written as a string with a unit (``"80 mm"``, ``"10 ms"``), converted to the key's
unit (:data:`UNITS`); a unit of the wrong kind (``"80 ms"`` for a length) is an error.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from imageform._units import LENGTH_UNITS
from imageform.color.rgb_spaces import RGB_SPACES
from imageform.color.transfer import TRANSFER_FUNCTIONS
from imageform.sensor.cfa import CFA_PATTERNS
from imageform.sensor.demosaic import DEMOSAIC_METHODS

__all__ = [
    "DEFAULT_LIGHT_TEMPERATURE_K",
    "DISTORTION_COEFFICIENTS",
    "DISTORTION_MODELS",
    "MAX_SUPERSAMPLING",
    "OBJECT_TYPES",
    "SCENE_SCHEMA",
    "UNITS",
    "Field",
]


@dataclass(frozen=True)
class Field:
    """One key of the schema: ``kind``, ``dimension``, ``default``, ``choices`` and ``doc``.

    ``kind`` (``"float"``, ``"int"``, ``"str"``, ``"bool"``, ``"vec2"``, ``"vec3"``, ``"ivec2"``,
    ``"mat3"``, ``"reflectance"`` (a number in [0, 1] or a ColorChecker patch name),
    ``"float_or_auto"``), the physical ``dimension`` of a unit suffix (``"length"``, ``"time"``,
    ``"angle"`` or None), the ``default`` (None: optional, absent), the valid ``choices`` of a
    string, and a one-line ``doc``.
    """

    kind: str
    default: Any
    doc: str
    dimension: str | None = None
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    positive: bool = False

    def __post_init__(self) -> None:
        """Check for a known ``kind`` and a finite, real numeric ``default`` (issue 16)."""
        from imageform._validate import as_real, describe
        from imageform.errors import InvalidInputError

        if self.kind not in _KINDS:
            raise InvalidInputError(
                f"expected kind as one of {', '.join(_KINDS)}, got {self.kind!r:.40}"
            )
        if not isinstance(self.doc, str):
            raise TypeError(f"expected doc as a string, got {describe(self.doc)}")
        if self.dimension is not None and not isinstance(self.dimension, str):
            raise TypeError(
                f"expected dimension as a str (or None), got {describe(self.dimension)}"
            )
        for bound in ("minimum", "maximum"):
            if getattr(self, bound) is not None:
                as_real(getattr(self, bound), bound)
        d = self.default
        if d is None or isinstance(d, str) or (self.kind == "bool" and isinstance(d, bool)):
            return
        if isinstance(d, tuple | list):
            rows = d if self.kind == "mat3" else (d,)
            for row in rows:
                for x in row if isinstance(row, tuple | list) else (row,):
                    as_real(x, "default")
            return
        as_real(d, "default")


#: The kinds of :class:`Field`.
_KINDS = (
    "float",
    "int",
    "str",
    "bool",
    "vec2",
    "vec3",
    "ivec2",
    "mat3",
    "reflectance",
    "float_or_auto",
)

# Conversion of a unit to the key's base unit (m, s, rad ... deg is kept for *_deg keys);
# lengths are imageform's one table of length units (imageform._units).
UNITS: Mapping[str, Mapping[str, float]] = MappingProxyType(
    {
        "length": LENGTH_UNITS,
        "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
        "angle": {"deg": 1.0, "rad": 180.0 / math.pi},
    }
)
# Base unit of each key suffix, as a factor from the dimension's SI unit.
_SUFFIX_SCALE = {"_m": 1.0, "_mm": 1e3, "_um": 1e6, "_s": 1.0, "_deg": 1.0}

_WB = ("gray_world", "white_patch", "shades_of_gray", "gray_edge", "colorchecker", "none")
OBJECT_TYPES: tuple[str, ...] = ("checkerboard", "colorchecker", "ground", "image", "plane")

#: Largest ``render.supersampling``: 16 x 16 = 256 rays per pixel (the render time grows
#: with S²; beyond this a box filter gains nothing visible).
MAX_SUPERSAMPLING = 16
#: Most rails on a ground (each is one pass over the ground's rays when rendering; 10**18
#: rails would render for ever).
MAX_RAILS = 64

#: Most ``[[views]]`` of one scene (each is a whole extra simulation).
MAX_VIEWS = 64
#: ``illuminant.temperature_K`` of a blackbody or daylight light when the key is absent.
DEFAULT_LIGHT_TEMPERATURE_K = 6504.0
#: The distortion models of ``camera.distortion.model`` and the coefficients each one has
#: (:mod:`imageform.geometry.distortion`: ``BrownConrady``, ``DivisionModel``,
#: ``KannalaBrandt``); a coefficient the model lacks must be absent or 0.
DISTORTION_COEFFICIENTS: dict[str, tuple[str, ...]] = {
    "brown_conrady": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "division": ("k1", "k2"),
    "kannala_brandt": ("k1", "k2", "k3", "k4"),
}
DISTORTION_MODELS: tuple[str, ...] = tuple(DISTORTION_COEFFICIENTS)

_POSE = {
    "type": Field("str", None, "object kind", choices=OBJECT_TYPES),
    "name": Field("str", "", "label in the report (default: the type and its index)"),
    "center_m": Field("vec3", None, "world position of the object's centre (m)", "length"),
    "normal": Field("vec3", (0.0, -1.0, 0.0), "front-face normal (towards the viewer)"),
    "up": Field("vec3", None, "world direction of the object's top edge (default z, or y)"),
}

#: The schema: section -> key -> Field; ``objects`` maps each object type to its keys.
SCENE_SCHEMA: dict[str, Any] = {
    "": {
        "name": Field("str", "scene", "the scene's name"),
        "description": Field("str", "", "free text shown in the report"),
    },
    "render": {
        "width": Field("int", 1280, "image width (pixels)", minimum=2),
        "height": Field("int", 720, "image height (pixels)", minimum=2),
        "supersampling": Field(
            "int",
            2,
            "rays per pixel along each axis (S x S)",
            minimum=1,
            maximum=MAX_SUPERSAMPLING,
        ),
        "background_reflectance": Field(
            "reflectance", 0.02, "flat reflectance seen where no object is hit"
        ),
    },
    "illuminant": {
        "type": Field(
            "str", "cie", "how the light is given", choices=("cie", "blackbody", "daylight", "file")
        ),
        "name": Field("str", "A", "CIE illuminant name (A, D50, D65, F2, F11, E, LED-B3 ...)"),
        "temperature_K": Field(
            "float",
            None,
            "colour temperature (K) of a blackbody/daylight light (default 6504)",
            minimum=1000.0,
            maximum=25000.0,
        ),
        "file": Field("str", None, "CSV file: wavelength (nm), relative power (two columns)"),
        "illuminance_lux": Field(
            "float", 1000.0, "illuminance on every surface (lx)", minimum=0.0, positive=True
        ),
    },
    "camera": {
        "image_plane": Field(
            "str",
            "virtual",
            "'real' is the camera obscura (inverted image)",
            choices=("virtual", "real"),
        ),
        "focal_length_mm": Field(
            "float", 1.0, "lens focal length (mm)", "length", minimum=0.0, positive=True
        ),
        "pixel_pitch_um": Field(
            "float",
            None,
            "pixel pitch (µm); default the sensor's",
            "length",
            minimum=0.0,
            positive=True,
        ),
        "fx_px": Field(
            "float", None, "focal length in pixels (overrides focal_length_mm)", positive=True
        ),
        "fy_px": Field(
            "float", None, "vertical focal length in pixels (default fx_px)", positive=True
        ),
        "cx_px": Field("float", None, "principal point column (default (width - 1) / 2)"),
        "cy_px": Field("float", None, "principal point row (default (height - 1) / 2)"),
        "skew_px": Field("float", 0.0, "skew K[0, 1] (pixels; 0 for square pixels)"),
        "eye_m": Field("vec3", (0.0, -0.1, 0.05), "camera centre for look_at (m)", "length"),
        "target_m": Field("vec3", (0.0, 0.0, 0.0), "point looked at (m)", "length"),
        "up": Field("vec3", (0.0, 0.0, 1.0), "world up for look_at"),
        "R": Field("mat3", None, "world-to-camera rotation (replaces look_at, with t_m)"),
        "t_m": Field("vec3", None, "world-to-camera translation (m), X_cam = R X + t", "length"),
        "distortion": {
            "model": Field(
                "str", "brown_conrady", "lens distortion model", choices=DISTORTION_MODELS
            ),
            "k1": Field("float", 0.0, "radial r^2 (k1 < 0 barrel); every model's first"),
            "k2": Field("float", 0.0, "radial r^4"),
            "p1": Field("float", 0.0, "tangential p1 (brown_conrady)"),
            "p2": Field("float", 0.0, "tangential p2 (brown_conrady)"),
            "k3": Field("float", 0.0, "radial r^6 (brown_conrady, kannala_brandt)"),
            "k4": Field("float", 0.0, "rational k4 (brown_conrady) or theta^9 (kannala_brandt)"),
            "k5": Field("float", 0.0, "rational k5 (brown_conrady)"),
            "k6": Field("float", 0.0, "rational k6 (brown_conrady)"),
        },
    },
    "lens": {
        "f_number": Field("float", 8.0, "aperture f-number N = f / D", minimum=0.5, maximum=1000.0),
        "focus_distance_m": Field(
            "float", 0.1, "distance in focus (m)", "length", minimum=0.0, positive=True
        ),
        "defocus": Field("bool", True, "blur by the circle of confusion of each pixel's depth"),
        "vignetting": Field("str", "cos4", "natural vignetting", choices=("cos4", "none")),
        "lateral_ca": Field(
            "vec3",
            (1.0, 1.0, 1.0),
            "magnification of R, G, B (lateral colour)",
            minimum=0.5,
            maximum=2.0,
        ),
        "diffraction": Field(
            "bool", False, "convolve each channel with the aperture's diffraction PSF (Airy)"
        ),
        "psf": Field(
            "str",
            "geometric",
            "defocus PSF: the geometric disc, or the wave-optics PSF of the pupil with the "
            "same defocus as a Zernike term (diffraction included)",
            choices=("geometric", "wave"),
        ),
    },
    "sensor": {
        "preset": Field("str", "cmos", "starting parameters", choices=("cmos", "ccd")),
        "spectral_sensitivity": Field(
            "str",
            "preset",
            "QE curves: the preset's or measured camera curves",
            choices=("preset", "nikon_d5100"),
        ),
        "peak_qe": Field(
            "float", 0.5, "peak QE of measured curves (nikon_d5100)", minimum=0.0, maximum=1.0
        ),
        "cfa": Field("str", "RGGB", "Bayer pattern", choices=CFA_PATTERNS),
        "exposure_time_s": Field(
            "float_or_auto",
            "auto",
            "seconds, or 'auto' (brightest pixels at auto_exposure_level)",
            "time",
            minimum=0.0,
        ),
        "auto_exposure_level": Field(
            "float", 0.6, "fraction of full well for 'auto'", minimum=0.01, maximum=1.0
        ),
        "shutter": Field(
            "str",
            None,
            "global or rolling (a static scene looks the same)",
            choices=("global", "rolling"),
        ),
        "noise": Field("bool", True, "shot, dark and read noise, FPN (false: mean signal)"),
        "pixel_pitch_um": Field(
            "float", None, "pixel pitch (µm)", "length", minimum=0.0, positive=True
        ),
        "fill_factor": Field(
            "float", None, "photosensitive fraction of the pixel", minimum=0.0, maximum=1.0
        ),
        "full_well_e": Field("float", None, "full-well capacity (e-)", minimum=0.0, positive=True),
        "read_noise_e": Field("float", None, "read noise (e- rms)", minimum=0.0),
        "dark_current_e_per_s": Field("float", None, "dark current (e-/s)", minimum=0.0),
        "dsnu_e": Field("float", None, "dark-signal non-uniformity (e- rms)", minimum=0.0),
        "prnu": Field("float", None, "photo-response non-uniformity (fraction)", minimum=0.0),
        "column_fpn_e": Field("float", None, "column offsets, CMOS (e- rms)", minimum=0.0),
        "conversion_gain_uV_per_e": Field(
            "float", None, "conversion gain (µV/e-)", minimum=0.0, positive=True
        ),
        "analog_gain": Field("float", None, "gain before the ADC", minimum=0.0, positive=True),
        "bit_depth": Field("int", None, "ADC bits", minimum=1, maximum=16),
        "black_level_dn": Field("float", None, "offset (DN)", minimum=0.0),
        "fpn_seed": Field("int", None, "seed of the chip's fixed pattern"),
    },
    "processing": {
        "demosaic": Field("str", "menon", "demosaicing method", choices=DEMOSAIC_METHODS),
        "lens_shading_correction": Field("bool", True, "divide out the vignetting map"),
        "white_balance": Field("str", "gray_world", "white-balance method", choices=_WB),
        "color_correction": Field(
            "str",
            "colorchecker",
            "3x3 matrix fitted on the chart",
            choices=("colorchecker", "none"),
        ),
        "output_space": Field("str", "srgb", "output RGB space", choices=tuple(RGB_SPACES)),
        "transfer": Field(
            "str",
            "space",
            "output encoding; 'space' = the space's own",
            choices=("space", *TRANSFER_FUNCTIONS),
        ),
    },
    "views": {
        "eye_m": Field("vec3", None, "camera centre of this extra view (m)", "length"),
        "target_m": Field("vec3", (0.0, 0.0, 0.0), "point looked at (m)", "length"),
        "up": Field("vec3", (0.0, 0.0, 1.0), "world up for look_at"),
    },
    "objects": {
        "checkerboard": {
            **_POSE,
            "squares": Field("ivec2", (8, 6), "squares (columns, rows); inner corners one fewer"),
            "square_size_m": Field(
                "float", 0.005, "side of a square (m)", "length", minimum=0.0, positive=True
            ),
            "margin_squares": Field("float", 1.0, "white border, in squares", minimum=0.0),
            "dark_reflectance": Field("reflectance", 0.03, "dark squares"),
            "light_reflectance": Field("reflectance", 0.85, "light squares and border"),
        },
        "colorchecker": {
            **_POSE,
            "width_m": Field(
                "float",
                0.0635,
                "chart width (m); height is 2/3 of it",
                "length",
                minimum=0.0,
                positive=True,
            ),
            "gap_fraction": Field(
                "float", 0.2, "black gap between patches (of a cell)", minimum=0.0, maximum=0.9
            ),
            "frame_reflectance": Field("reflectance", 0.03, "the chart's frame"),
        },
        "ground": {
            **_POSE,
            "normal": Field("vec3", (0.0, 0.0, 1.0), "ground normal (up)"),
            "size_m": Field("vec2", (0.2, 0.6), "extent across and along the rails (m)", "length"),
            "reflectance": Field("reflectance", 0.25, "the ground"),
            "rail_count": Field("int", 2, "number of parallel rails", minimum=0, maximum=MAX_RAILS),
            "rail_gauge_m": Field(
                "float", 0.0165, "distance between rails (m)", "length", minimum=0.0
            ),
            "rail_width_m": Field("float", 0.002, "rail width (m)", "length", minimum=0.0),
            "rail_reflectance": Field("reflectance", 0.8, "the rails"),
            "sleeper_spacing_m": Field(
                "float", 0.01, "distance between sleepers (0: none)", "length", minimum=0.0
            ),
            "sleeper_width_m": Field("float", 0.003, "sleeper width (m)", "length", minimum=0),
            "sleeper_length_m": Field("float", 0.012, "sleeper length (m)", "length", minimum=0),
            "sleeper_reflectance": Field("reflectance", 0.06, "the sleepers"),
        },
        "image": {
            **_POSE,
            "path": Field("str", None, "image file (relative to the scene file)"),
            "width_m": Field(
                "float",
                0.06,
                "width (m); height from the aspect ratio",
                "length",
                minimum=0.0,
                positive=True,
            ),
        },
        "plane": {
            **_POSE,
            "size_m": Field("vec2", (0.1, 0.1), "width, height (m)", "length"),
            "reflectance": Field("reflectance", 0.8, "uniform reflectance"),
        },
    },
}
