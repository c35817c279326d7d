"""A scene to simulate: planar objects, the light, the camera, lens, sensor and processing.

:func:`load_scene` reads a TOML file, a TOML string or a dict, validates it against
:data:`~imageform.simulate.schema.SCENE_SCHEMA` and returns a frozen :class:`Scene`;
:func:`default_scene` is the built-in scene (``scenes/default.toml`` in the package).
The world frame is z-up (the ground is ``z = 0``); lengths are metres.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError
from imageform.geometry.camera import Camera
from imageform.geometry.distortion import BrownConrady
from imageform.geometry.rotations import look_at
from imageform.sensor.model import SensorModel
from imageform.sensor.presets import ccd_preset, cmos_preset
from imageform.simulate.files import load_texture, resolve_path
from imageform.simulate.validation import validate_scene_dict
from imageform.spectral.spectrum import Spectrum

__all__ = ["Scene", "SceneObject", "default_scene", "load_scene"]

_DEFAULT_TOML = Path(__file__).with_name("scenes") / "default.toml"


@dataclass(frozen=True)
class SceneObject:
    """A planar object: ``kind``, ``name``, its world ``corners`` ``(4, 3)`` (top-left,
    top-right, bottom-right, bottom-left as seen from the front) and its validated
    ``params`` (the schema keys of its type)."""

    kind: str
    name: str
    corners: np.ndarray
    params: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def origin(self) -> np.ndarray:
        """The top-left corner (texture coordinate ``(a, b) = (0, 0)``)."""
        return self.corners[0]

    @property
    def edge_right(self) -> np.ndarray:
        """Vector from the top-left to the top-right corner (``a`` from 0 to 1)."""
        return self.corners[1] - self.corners[0]

    @property
    def edge_down(self) -> np.ndarray:
        """Vector from the top-left to the bottom-left corner (``b`` from 0 to 1)."""
        return self.corners[3] - self.corners[0]


@dataclass(frozen=True)
class Scene:
    """A validated scene (see ``docs/simulate.md`` for every key).

    ``config`` is the validated description as plain data (every default filled in);
    the other fields are what the renderer needs, built from it.
    """

    name: str
    config: dict[str, Any] = field(compare=False)
    objects: tuple[SceneObject, ...]
    camera: Camera
    sensor: SensorModel
    illuminant: Spectrum
    base_dir: Path | None = None

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels."""
        r = self.config["render"]
        return int(r["width"]), int(r["height"])

    def with_changes(self, **sections: dict[str, Any]) -> Scene:
        """A copy with some keys of some sections replaced, re-validated.

        >>> s = default_scene().with_changes(render={"width": 160, "height": 90})
        >>> s.image_size
        (160, 90)
        """
        cfg = copy.deepcopy(self.config)
        for sec, changes in sections.items():
            if sec == "objects":
                cfg["objects"] = changes
            elif isinstance(cfg.get(sec), dict):
                cfg[sec].update(changes)
            else:
                cfg[sec] = changes
        return _build(_plain(cfg), None, "scene", self.base_dir)

    def resized(self, width: int, height: int | None = None) -> Scene:
        """The same view at another image size: intrinsics scaled with the image.

        The camera's pixel pitch (or ``fx_px``, ``fy_px``, ``cx_px``, ``cy_px``) is scaled by
        ``width / current width``; ``height`` defaults to keeping the aspect ratio. The
        sensor (pixel area, noise) is unchanged.

        >>> small = default_scene().resized(160)
        >>> small.image_size, round(float(small.camera.K[0, 0]), 3)
        ((160, 90), 71.429)
        """
        w0, h0 = self.image_size
        f = int(width) / w0
        h = int(height) if height is not None else max(2, round(h0 * f))
        cam = dict(self.config["camera"])
        changes: dict[str, Any] = {}
        if cam["fx_px"] is not None:
            changes["fx_px"] = cam["fx_px"] * f
            if cam["fy_px"] is not None:
                changes["fy_px"] = cam["fy_px"] * f
        else:
            pitch = cam["pixel_pitch_um"] or self.sensor.pixel_pitch * 1e6
            changes["pixel_pitch_um"] = pitch / f
        for key in ("cx_px", "cy_px"):
            if cam[key] is not None:
                changes[key] = (cam[key] + 0.5) * f - 0.5
        return self.with_changes(render={"width": int(width), "height": h}, camera=changes)


def _plain(cfg: Any) -> Any:
    """Validated config back to TOML-like data (tuples to lists, None dropped)."""
    if isinstance(cfg, dict):
        return {k: _plain(v) for k, v in cfg.items() if v is not None}
    if isinstance(cfg, tuple | list):
        return [_plain(v) for v in cfg]
    return cfg


def _unit(v: np.ndarray, what: str) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if n == 0:
        raise InvalidInputError(f"{what} must be a non-zero vector")
    return v / n


def _object_frame(p: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (right, down, normal) of an object from its normal and up hint."""
    n = _unit(np.asarray(p["normal"], float), f"{p['name']}: normal")
    if p["up"] is not None:
        up = _unit(np.asarray(p["up"], float), f"{p['name']}: up")
    else:
        up = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    right = np.cross(up, n)
    if np.linalg.norm(right) < 1e-9:
        raise InvalidInputError(f"{p['name']}: 'up' is parallel to the normal")
    right = right / np.linalg.norm(right)
    up_in = np.cross(n, right)
    return right, -up_in, n


def _object_size(kind: str, p: dict[str, Any], base: Path | None) -> tuple[float, float]:
    if kind == "checkerboard":
        c, r = p["squares"]
        m = 2 * p["margin_squares"]
        return (c + m) * p["square_size_m"], (r + m) * p["square_size_m"]
    if kind == "colorchecker":
        return p["width_m"], p["width_m"] * 2.0 / 3.0
    if kind == "image":
        tex = load_texture(p["path"], base)
        return p["width_m"], p["width_m"] * tex.shape[0] / tex.shape[1]
    return float(p["size_m"][0]), float(p["size_m"][1])


def _objects(cfg: dict[str, Any], base: Path | None) -> tuple[SceneObject, ...]:
    out = []
    for p in cfg["objects"]:
        kind = p["type"]
        right, down, _ = _object_frame(p)
        w, h = _object_size(kind, p, base)
        c = np.asarray(p["centre_m"], float)
        tl = c - right * w / 2 - down * h / 2
        corners = np.stack([tl, tl + right * w, tl + right * w + down * h, tl + down * h])
        out.append(SceneObject(kind, p["name"], corners, p))
    return tuple(out)


def _sensor(cfg: dict[str, Any]) -> SensorModel:
    s = cfg["sensor"]
    base = (cmos_preset if s["preset"] == "cmos" else ccd_preset)(color=True)
    changes: dict[str, Any] = {}
    table = {
        "fill_factor": ("fill_factor", 1.0),
        "full_well_e": ("full_well", 1.0),
        "read_noise_e": ("read_noise", 1.0),
        "dark_current_e_per_s": ("dark_current", 1.0),
        "dsnu_e": ("dsnu", 1.0),
        "prnu": ("prnu", 1.0),
        "column_fpn_e": ("column_fpn", 1.0),
        "conversion_gain_uV_per_e": ("conversion_gain", 1e-6),
        "analog_gain": ("analog_gain", 1.0),
        "black_level_dn": ("black_level", 1.0),
        "pixel_pitch_um": ("pixel_pitch", 1e-6),
    }
    for key, (name, scale) in table.items():
        if s[key] is not None:
            changes[name] = float(s[key]) * scale
    if s["bit_depth"] is not None:
        changes["bit_depth"] = int(s["bit_depth"])
    if s["fpn_seed"] is not None:
        changes["fpn_seed"] = int(s["fpn_seed"])
    if s["shutter"] is not None:
        changes["shutter"] = s["shutter"]
    if s["spectral_sensitivity"] == "nikon_d5100":
        from imageform.spectral import camera_sensitivities

        sens = camera_sensitivities("nikon_d5100")
        vals = sens.values / sens.values.max() * float(s["peak_qe"])
        changes["qe_wavelengths"] = tuple(float(w) for w in sens.wavelengths)
        changes["qe_curves"] = tuple(tuple(float(x) for x in vals[:, c]) for c in range(3))
        changes["name"] = f"{base.name}, Nikon D5100 spectral sensitivities"
    return replace(base, **changes)


def _illuminant(cfg: dict[str, Any], base: Path | None) -> Spectrum:
    from imageform.spectral import blackbody_spectrum, daylight_spectrum, illuminant

    il = cfg["illuminant"]
    if il["type"] == "cie":
        return illuminant(il["name"])
    if il["type"] == "blackbody":
        return blackbody_spectrum(il["temperature_K"])
    if il["type"] == "daylight":
        if not 4000 <= il["temperature_K"] <= 25000:
            raise InvalidInputError(
                f"illuminant.temperature_K: the CIE daylight series covers 4000-25000 K, "
                f"got {il['temperature_K']:g}"
            )
        return daylight_spectrum(il["temperature_K"])
    path = resolve_path(il["file"], base)
    rows: list[list[float]] = []
    for no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        cells = [c.strip() for c in line.replace(";", ",").split(",")]
        try:
            values = [float(c) for c in cells]
        except ValueError as exc:
            if not rows:  # a header line
                continue
            raise InvalidInputError(
                f"illuminant file {path}, line {no}: not numbers: {line!r}"
            ) from exc
        if len(values) != 2:
            raise InvalidInputError(
                f"illuminant file {path}, line {no}: expected two columns (nm, power), "
                f"got {len(values)}"
            )
        rows.append(values)
    if len(rows) < 2:
        raise InvalidInputError(f"illuminant file {path}: expected at least two rows (nm, power)")
    arr = np.asarray(rows)
    return Spectrum(arr[:, 0], arr[:, 1], name=Path(path).name)


def _camera(cfg: dict[str, Any], sensor: SensorModel) -> Camera:
    c = cfg["camera"]
    w, h = int(cfg["render"]["width"]), int(cfg["render"]["height"])
    if c["fx_px"] is not None:
        fx = float(c["fx_px"])
    else:
        pitch = (
            c["pixel_pitch_um"] * 1e-6 if c["pixel_pitch_um"] is not None else sensor.pixel_pitch
        )
        fx = c["focal_length_mm"] * 1e-3 / pitch
    fy = float(c["fy_px"]) if c["fy_px"] is not None else fx
    cx = float(c["cx_px"]) if c["cx_px"] is not None else (w - 1) / 2
    cy = float(c["cy_px"]) if c["cy_px"] is not None else (h - 1) / 2
    K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    if c["R"] is not None:
        R, t = np.asarray(c["R"], float), np.asarray(c["t_m"], float)
    else:
        R, t = look_at(np.asarray(c["eye_m"]), np.asarray(c["target_m"]), np.asarray(c["up"]))
    d = c["distortion"]
    dist = BrownConrady(d["k1"], d["k2"], d["p1"], d["p2"], d["k3"])
    has = any(v != 0 for v in dist.coeffs)
    if has and c["image_plane"] == "real":
        raise InvalidInputError(
            "camera.image_plane = 'real' (camera obscura) is a pinhole: remove camera.distortion"
        )
    return Camera(K, np.asarray(R), np.asarray(t), (w, h), c["image_plane"], dist if has else None)


def _build(data: dict[str, Any], text: str | None, origin: str, base: Path | None) -> Scene:
    cfg = validate_scene_dict(data, text, origin)
    sensor = _sensor(cfg)
    camera = _camera(cfg, sensor)
    if cfg["lens"]["focus_distance_m"] * 1e3 <= cfg["camera"]["focal_length_mm"]:
        raise InvalidInputError("lens.focus_distance_m must exceed the focal length")
    return Scene(
        name=str(cfg["name"]),
        config=cfg,
        objects=_objects(cfg, base),
        camera=camera,
        sensor=sensor,
        illuminant=_illuminant(cfg, base),
        base_dir=base,
    )


def load_scene(source: str | Path | dict[str, Any]) -> Scene:
    """Read and validate a scene: a TOML file path, a TOML string or a dict.

    Paths inside the scene (image textures, illuminant files) are relative to the file's
    folder (or the working folder for a string or dict).

    Raises
    ------
    InvalidInputError
        A missing file, a TOML syntax error, or a key of the wrong type, range or unit; the
        message names the key and the line.
    UnknownOptionError
        An unknown key or choice, with the valid ones.

    >>> s = load_scene('name = "tiny"\\n[render]\\nwidth = 160\\nheight = 90\\n')
    >>> s.name, s.image_size
    ('tiny', (160, 90))
    """
    if isinstance(source, dict):
        return _build(copy.deepcopy(source), None, "scene dict", None)
    if isinstance(source, Path) or (
        isinstance(source, str) and "\n" not in source and "=" not in source
    ):
        path = Path(source)
        if not path.is_file():
            raise InvalidInputError(f"scene file not found: {str(path)!r}")
        text = path.read_text(encoding="utf-8")
        origin, base = str(path), path.resolve().parent
    elif isinstance(source, str):
        text, origin, base = source, "scene string", None
    else:
        raise InvalidInputError(
            f"expected a TOML path, a TOML string or a dict, got {type(source).__name__}"
        )
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{origin}: TOML syntax error: {exc}") from exc
    return _build(data, text, origin, base)


def default_scene() -> Scene:
    """The built-in scene: a ColorChecker and a checkerboard standing on a ground with rails,
    under tungsten light (CIE A), seen by an endoscope-like camera at 1280x720.

    >>> default_scene().image_size
    (1280, 720)
    """
    return load_scene(_DEFAULT_TOML)
