"""The scene schema: every key of a scene TOML file, its type, unit and default, and the checks.

A scene file is validated against :data:`SCENE_SCHEMA` once, at the boundary
(:func:`imageform.simulate.load_scene`). Errors name the key and, for a file or TOML string,
the line it is on (``tomllib`` gives no line numbers for values, so the key's line is found in
the text). Units are part of the key's name (``focus_distance_m``, ``exposure_time_s``); a
length, time or angle may also be written as a string with a unit (``"80 mm"``,
``"10 ms"``), converted to the key's unit; a unit of the wrong kind (``"80 ms"`` for a length)
is an error.
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass
from typing import Any

from imageform.color.rgb_spaces import RGB_SPACES
from imageform.color.transfer import TRANSFER_FUNCTIONS
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor.cfa import CFA_PATTERNS
from imageform.sensor.demosaic import DEMOSAIC_METHODS

__all__ = ["OBJECT_TYPES", "SCENE_SCHEMA", "Field", "find_line", "validate_scene_dict"]


@dataclass(frozen=True)
class Field:
    """One key of the schema: ``kind`` (``"float"``, ``"int"``, ``"str"``, ``"bool"``,
    ``"vec2"``, ``"vec3"``, ``"ivec2"``, ``"mat3"``, ``"reflectance"`` (a number in [0, 1] or
    a ColorChecker patch name), ``"float_or_auto"``), the physical ``dimension`` of a unit
    suffix (``"length"``, ``"time"``, ``"angle"`` or None), the ``default`` (None: optional,
    absent), the valid ``choices`` of a string, and a one-line ``doc``."""

    kind: str
    default: Any
    doc: str
    dimension: str | None = None
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    positive: bool = False


# Conversion of a unit to the key's base unit (m, s, rad ... deg is kept for *_deg keys).
_UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "nm": 1e-9},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
    "angle": {"deg": 1.0, "rad": 180.0 / math.pi},
}
# Base unit of each key suffix, as a factor from the dimension's SI unit.
_SUFFIX_SCALE = {"_m": 1.0, "_mm": 1e3, "_um": 1e6, "_s": 1.0, "_deg": 1.0}

_WB = ("gray_world", "white_patch", "shades_of_gray", "gray_edge", "colorchecker", "none")
OBJECT_TYPES: tuple[str, ...] = ("checkerboard", "colorchecker", "ground", "image", "plane")

_POSE = {
    "type": Field("str", None, "object kind", choices=OBJECT_TYPES),
    "name": Field("str", "", "label in the report (default: the type and its index)"),
    "centre_m": Field("vec3", None, "world position of the object's centre (m)", "length"),
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
        "supersampling": Field("int", 2, "rays per pixel along each axis (S x S)", minimum=1),
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
            6504.0,
            "colour temperature (K) for blackbody/daylight",
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
        "fx_px": Field("float", None, "focal length in pixels (overrides focal_length_mm)"),
        "fy_px": Field("float", None, "vertical focal length in pixels (default fx_px)"),
        "cx_px": Field("float", None, "principal point column (default (width - 1) / 2)"),
        "cy_px": Field("float", None, "principal point row (default (height - 1) / 2)"),
        "eye_m": Field("vec3", (0.0, -0.1, 0.05), "camera centre for look_at (m)", "length"),
        "target_m": Field("vec3", (0.0, 0.0, 0.0), "point looked at (m)", "length"),
        "up": Field("vec3", (0.0, 0.0, 1.0), "world up for look_at"),
        "R": Field("mat3", None, "world-to-camera rotation (replaces look_at, with t_m)"),
        "t_m": Field("vec3", None, "world-to-camera translation (m), X_cam = R X + t", "length"),
        "distortion": {
            "k1": Field("float", 0.0, "radial r^2 (k1 < 0 barrel)"),
            "k2": Field("float", 0.0, "radial r^4"),
            "p1": Field("float", 0.0, "tangential p1"),
            "p2": Field("float", 0.0, "tangential p2"),
            "k3": Field("float", 0.0, "radial r^6"),
        },
    },
    "lens": {
        "f_number": Field("float", 8.0, "aperture f-number N = f / D", minimum=0.5),
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
            "rail_count": Field("int", 2, "number of parallel rails", minimum=0),
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


# ---- locating keys in the TOML text ---------------------------------------------------------
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-\.\"' ]+?)\s*=")


def _split_key(k: str) -> tuple[str, ...]:
    return tuple(p.strip().strip("\"'") for p in k.split("."))


def find_line(text: str | None, path: tuple[Any, ...]) -> int | None:
    """1-based line of the key (or table) at ``path`` (e.g. ``("objects", 1, "squares")``) in
    TOML ``text``; None if not found. Array-of-tables entries count from 0.

    >>> find_line("a = 1\\n[camera]\\nf = 2\\n", ("camera", "f"))
    3
    """
    if not text:
        return None
    section: tuple[Any, ...] = ()
    counts: dict[tuple[str, ...], int] = {}
    for no, line in enumerate(text.splitlines(), 1):
        m = _HEADER.match(line)
        if m and "=" not in line.split("]")[0]:
            names = _split_key(m.group(2))
            if m.group(1) == "[[":
                counts[names] = counts.get(names, -1) + 1
                section = (*names, counts[names])
            else:
                section = names
            if section == tuple(path):
                return no
            continue
        k = _KEY.match(line)
        if k:
            full = (*section, *_split_key(k.group(1)))
            if full == tuple(path) or full[: len(path)] == tuple(path):
                return no
    return None


# ---- value checks ------------------------------------------------------------------------
class _Ctx:
    def __init__(self, text: str | None, origin: str) -> None:
        self.text = text
        self.origin = origin

    def where(self, path: tuple[Any, ...]) -> str:
        dotted = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in path)
        dotted = dotted.replace(".[", "[")
        line = find_line(self.text, path)
        at = f" ({self.origin}, line {line})" if line else f" ({self.origin})"
        return f"{dotted}{at}"

    def fail(self, path: tuple[Any, ...], msg: str, unknown: bool = False) -> None:
        cls = UnknownOptionError if unknown else InvalidInputError
        raise cls(f"scene key {self.where(path)}: {msg}")


def _quantity(v: str, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> float:
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([A-Za-zµ]+)\s*", v)
    if m is None or f.dimension is None:
        ctx.fail(path, f"expected a number, got {v!r}")
        raise AssertionError  # unreachable (for type checkers)
    num, unit = float(m.group(1)), m.group(2)
    table = _UNITS[f.dimension]
    if unit not in table:
        kinds = [d for d, t in _UNITS.items() if unit in t]
        got = f" (a {kinds[0]})" if kinds else ""
        ctx.fail(
            path, f"expected a {f.dimension} in one of {sorted(table)}, got unit {unit!r}{got}"
        )
    suffix = next((s for s in _SUFFIX_SCALE if key.endswith(s)), "")
    return num * table[unit] * _SUFFIX_SCALE.get(suffix, 1.0)


def _number(v: Any, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> float:
    if isinstance(v, bool):
        ctx.fail(path, f"expected a number, got {v!r}")
    if isinstance(v, str):
        return _quantity(v, f, key, path, ctx)
    if not isinstance(v, int | float) or not math.isfinite(v):
        ctx.fail(path, f"expected a finite number, got {v!r}")
    return float(v)


def _bounds(x: float, f: Field, path: tuple[Any, ...], ctx: _Ctx) -> None:
    if f.positive and x <= 0:
        ctx.fail(path, f"expected a value > 0, got {x:g}")
    if f.minimum is not None and x < f.minimum:
        ctx.fail(path, f"expected a value >= {f.minimum:g}, got {x:g}")
    if f.maximum is not None and x > f.maximum:
        ctx.fail(path, f"expected a value <= {f.maximum:g}, got {x:g}")


def _check_value(v: Any, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> Any:
    from imageform.spectral import COLORCHECKER_PATCHES

    kind = f.kind
    if kind == "str":
        if not isinstance(v, str):
            ctx.fail(path, f"expected a string, got {v!r}")
        if f.choices:
            key_ = v.strip().lower().replace("-", "_")
            valid = {c.lower(): c for c in f.choices}
            if key_ not in valid and v not in f.choices:
                ctx.fail(path, f"unknown value {v!r}; valid: {', '.join(f.choices)}", True)
            return valid.get(key_, v)
        return v
    if kind == "bool":
        if not isinstance(v, bool):
            ctx.fail(path, f"expected true or false, got {v!r}")
        return v
    if kind == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            ctx.fail(path, f"expected an integer, got {v!r}")
        _bounds(float(v), f, path, ctx)
        return int(v)
    if kind == "float_or_auto" and isinstance(v, str) and v.strip().lower() == "auto":
        return "auto"
    if kind in ("float", "float_or_auto"):
        x = _number(v, f, key, path, ctx)
        _bounds(x, f, path, ctx)
        return x
    if kind == "reflectance":
        if isinstance(v, str):
            if v not in COLORCHECKER_PATCHES:
                near = difflib.get_close_matches(v, COLORCHECKER_PATCHES, 3)
                ctx.fail(path, f"unknown ColorChecker patch {v!r}; close: {near}", True)
            return v
        x = _number(v, f, key, path, ctx)
        if not 0.0 <= x <= 1.0:
            ctx.fail(path, f"expected a reflectance in [0, 1], got {x:g}")
        return x
    n = {"vec2": 2, "vec3": 3, "ivec2": 2, "mat3": 3}[kind]
    if not isinstance(v, list) or len(v) != n:
        ctx.fail(
            path, f"expected a list of {n} {'rows' if kind == 'mat3' else 'numbers'}, got {v!r}"
        )
    if kind == "mat3":
        rows = []
        for r in v:
            if not isinstance(r, list) or len(r) != 3:
                ctx.fail(path, f"expected 3 rows of 3 numbers, got {v!r}")
            rows.append(tuple(_number(x, f, key, path, ctx) for x in r))
        return tuple(rows)
    if kind == "ivec2":
        if not all(isinstance(x, int) and not isinstance(x, bool) and x >= 2 for x in v):
            ctx.fail(path, f"expected two integers >= 2, got {v!r}")
        return tuple(int(x) for x in v)
    out = tuple(_number(x, f, key, path, ctx) for x in v)
    for x in out:
        _bounds(x, f, path, ctx)
    return out


def _table(data: Any, schema: dict[str, Any], path: tuple[Any, ...], ctx: _Ctx) -> dict[str, Any]:
    if not isinstance(data, dict):
        ctx.fail(path, f"expected a table, got {data!r:.60}")
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key not in schema:
            near = difflib.get_close_matches(key, list(schema), 1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            unit_hint = ""
            stem = re.sub(r"_(m|mm|um|cm|s|ms|us|deg|rad)$", "", key)
            same = [k for k in schema if re.sub(r"_(m|mm|um|s|deg|K|lux|px|e)$", "", k) == stem]
            if same and key not in same:
                unit_hint = f" (wrong unit? this key is {same[0]!r})"
            ctx.fail(
                (*path, key), f"unknown key{unit_hint}{hint}; valid: {', '.join(schema)}", True
            )
        f = schema[key]
        if isinstance(f, dict):
            out[key] = _table(value, f, (*path, key), ctx)
        else:
            out[key] = _check_value(value, f, key, (*path, key), ctx)
    for key, f in schema.items():
        if key in out:
            continue
        if isinstance(f, dict):
            out[key] = _table({}, f, (*path, key), ctx)
        else:
            out[key] = f.default
    return out


def validate_scene_dict(
    data: dict[str, Any], text: str | None = None, origin: str = "scene"
) -> dict[str, Any]:
    """Check a parsed scene against :data:`SCENE_SCHEMA`; return it with every default filled.

    Raises
    ------
    UnknownOptionError
        An unknown key or choice (with the valid ones and the line in ``text``).
    InvalidInputError
        A value of the wrong type, range or unit.

    >>> cfg = validate_scene_dict({"render": {"width": 320, "height": 180}})
    >>> cfg["render"]["supersampling"], cfg["lens"]["f_number"]
    (2, 8.0)
    """
    ctx = _Ctx(text, origin)
    if not isinstance(data, dict):
        raise InvalidInputError(f"expected a scene table (dict), got {type(data).__name__}")
    sections = {k: v for k, v in SCENE_SCHEMA.items() if k not in ("", "objects")}
    top = {**SCENE_SCHEMA[""], **sections, "objects": None}
    out: dict[str, Any] = {}
    for key in data:
        if key not in top:
            near = difflib.get_close_matches(key, list(top), 1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            ctx.fail((key,), f"unknown key{hint}; valid: {', '.join(top)}", True)
    for key, f in SCENE_SCHEMA[""].items():
        out[key] = _check_value(data[key], f, key, (key,), ctx) if key in data else f.default
    for sec, schema in sections.items():
        out[sec] = _table(data.get(sec, {}), schema, (sec,), ctx)
    objs = data.get("objects", [])
    if not isinstance(objs, list):
        ctx.fail(("objects",), "expected an array of tables ([[objects]])")
    out["objects"] = []
    for i, obj in enumerate(objs):
        if not isinstance(obj, dict) or "type" not in obj:
            ctx.fail(("objects", i), f"expected a table with a 'type' ({', '.join(OBJECT_TYPES)})")
        t = _check_value(obj["type"], _POSE["type"], "type", ("objects", i, "type"), ctx)
        checked = _table(obj, SCENE_SCHEMA["objects"][t], ("objects", i), ctx)
        if checked["centre_m"] is None:
            ctx.fail(("objects", i), "missing key 'centre_m' (the object's position, m)")
        if t == "image" and checked["path"] is None:
            ctx.fail(("objects", i), "missing key 'path' (the image file)")
        if not checked["name"]:
            checked["name"] = f"{t}{i}"
        out["objects"].append(checked)
    ill = out["illuminant"]
    if ill["type"] == "file" and ill["file"] is None:
        ctx.fail(("illuminant", "type"), "type 'file' needs the key 'file' (a CSV path)")
    cam = out["camera"]
    if (cam["R"] is None) != (cam["t_m"] is None):
        ctx.fail(("camera", "R" if cam["R"] is not None else "t_m"), "give both R and t_m")
    return out
