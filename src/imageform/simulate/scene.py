"""A scene to simulate: planar objects, the light, the camera, lens, sensor and processing.

:func:`load_scene` reads a TOML file, a TOML string or a dict, validates it against
:data:`~imageform.simulate.schema.SCENE_SCHEMA` and returns a frozen :class:`Scene`;
:func:`default_scene` is the built-in scene (``scenes/default.toml`` in the package).
The world frame is z-up (the ground is ``z = 0``); lengths are metres.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import tomllib
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._files import not_a_regular_file
from imageform._validate import as_int, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry.camera import Camera
from imageform.sensor.model import SensorModel
from imageform.simulate.config import (
    WORLD_UP,
    CameraConfig,
    CheckerboardConfig,
    ColorCheckerConfig,
    GroundConfig,
    IlluminantConfig,
    ImageConfig,
    ObjectConfig,
    PlaneConfig,
    SceneConfig,
)
from imageform.simulate.textures import load_texture, resolve_path
from imageform.simulate.validation import _Ctx, one_line, validate_scene_dict
from imageform.spectral.spectrum import Spectrum

if TYPE_CHECKING:
    from imageform.simulate.measured_sensor import MeasuredCamera

__all__ = ["Scene", "SceneObject", "default_scene", "load_scene"]

_DEFAULT_TOML = Path(__file__).with_name("scenes") / "default.toml"


@dataclass(frozen=True)
class SceneObject:
    """A planar object: ``kind``, ``name``, its world ``corners`` ``(4, 3)`` and typed ``config``.

    The corners are top-left, top-right, bottom-right, bottom-left as seen from the front; the
    config is the :class:`~imageform.simulate.config.ObjectConfig` of its kind.
    """

    kind: str
    name: str
    corners: np.ndarray
    config: ObjectConfig = field(compare=False)

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

    @property
    def params(self) -> dict[str, Any]:
        """Deprecated: the object's keys as a dict; use the typed :attr:`config`."""
        warnings.warn(
            "SceneObject.params is deprecated: use the typed SceneObject.config",
            DeprecationWarning,
            stacklevel=2,
        )
        return dataclasses.asdict(self.config)


@dataclass(frozen=True)
class Scene:
    """A validated scene (see ``docs/simulate.md`` for every key).

    ``config`` is the typed description (:class:`~imageform.simulate.config.SceneConfig`,
    every default filled in); the other fields are what the renderer needs, built from it
    once: the objects' world corners, the :class:`~imageform.geometry.Camera`, the
    :class:`~imageform.sensor.SensorModel` and the illuminant's spectrum. The world is z up
    (:data:`~imageform.simulate.config.WORLD_UP`).
    """

    name: str
    config: SceneConfig = field(compare=False)
    objects: tuple[SceneObject, ...]
    camera: Camera
    sensor: SensorModel
    illuminant: Spectrum
    base_dir: Path | None = None
    #: The measured camera's tables (a camera file's [sensor], [optics], [color]) the scene
    #: renders through (:func:`imageform.simulate.apply_camera_file`); None: the scene's own.
    measured: Any = field(default=None, compare=False)

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels."""
        r = self.config.render
        return int(r.width), int(r.height)

    def with_changes(self, **sections: dict[str, Any] | list[dict[str, Any]]) -> Scene:
        """Return a copy with some keys of some sections replaced, re-validated.

        Examples
        --------
        >>> s = default_scene().with_changes(render={"width": 160, "height": 90})
        >>> s.image_size
        (160, 90)
        """
        cfg = self.config.to_dict()
        for sec, changes in sections.items():
            if sec == "objects":
                cfg["objects"] = changes
            elif isinstance(cfg.get(sec), dict) and isinstance(changes, dict):
                cfg[sec].update(changes)
            else:
                cfg[sec] = changes
        origin = _where(self).origin
        return _build(_plain(cfg), None, origin, self.base_dir, self.measured)

    def with_measured(self, measured: MeasuredCamera | None) -> Scene:
        """Return the same scene rendered through a measured camera's tables.

        ``measured`` is a :class:`imageform.simulate.measured.MeasuredCamera`, or None for the
        scene's own sensor and processing: the sensor model is rebuilt with them. Kept by
        :meth:`with_changes`, :meth:`view` and :meth:`resized`; see
        :func:`imageform.simulate.apply_camera_file`.
        """
        from imageform.simulate.measured_sensor import MeasuredCamera

        if measured is not None and not isinstance(measured, MeasuredCamera):
            raise TypeError(
                f"expected measured as a MeasuredCamera or None, got {describe(measured)}"
            )
        cfg = _plain(self.config.to_dict())
        return _build(cfg, None, _where(self).origin, self.base_dir, measured)

    def with_camera(self, camera: Camera, *, focal_length_mm: float | None = None) -> Scene:
        """Return the same scene seen through ``camera``, re-validated.

        ``camera`` is an :class:`imageform.geometry.Camera`: K, R, t, distortion, image plane.

        The image size is the camera's ``image_size``; the camera section becomes
        :meth:`~imageform.simulate.config.CameraConfig.from_camera` of ``camera``
        (``focal_length_mm``, the lens's focal length for defocus, defaults to the scene's).
        The scene's ``camera`` is then ``camera`` itself (the same K, R, t and distortion).

        Examples
        --------
        >>> from imageform.geometry import Camera
        >>> cam = Camera([[100.0, 0, 79.5], [0, 100.0, 59.5], [0, 0, 1]],
        ...              t=[0.0, 0.0, 0.3], image_size=(160, 120))
        >>> default_scene().with_camera(cam).image_size
        (160, 120)
        """
        if not isinstance(camera, Camera):
            raise InvalidInputError(
                f"expected an imageform.geometry.Camera, got {type(camera).__name__}"
            )
        if camera.image_size is None:
            raise InvalidInputError(
                "expected a camera with an image_size (width, height) to render, got None"
            )
        f = self.config.camera.focal_length_mm if focal_length_mm is None else focal_length_mm
        cam_cfg = CameraConfig.from_camera(camera, focal_length_mm=f)
        w, h = camera.image_size
        cam = dataclasses.asdict(cam_cfg)
        return self.with_changes(render={"width": int(w), "height": int(h)}, camera=cam)

    def view(self, index: int) -> Scene:
        """Return the scene seen from its extra view ``index`` (``[[views]]``), without extra views.

        The same camera (intrinsics, distortion, sensor) at that view's look-at pose.

        Examples
        --------
        >>> s = default_scene().with_changes(views=[{"eye_m": [0.0, -0.2, 0.05]}])
        >>> [round(float(v), 3) for v in s.view(0).camera.center]
        [0.0, -0.2, 0.05]
        """
        views = self.config.views
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(views):
            raise InvalidInputError(
                f"expected a view index 0..{len(views) - 1}, got {index!r}"
                if views
                else "this scene has no [[views]]"
            )
        v = views[index]
        pose = {"eye_m": list(v.eye_m), "target_m": list(v.target_m), "up": list(v.up)}
        return self.with_changes(camera={**pose, "R": None, "t_m": None}, views=[])

    def resized(self, width: int, height: int | None = None) -> Scene:
        """Return the same view at another image size: intrinsics scaled with the image.

        The camera's pixel pitch (or ``fx_px``, ``fy_px``, ``cx_px``, ``cy_px``) is scaled by
        ``width / current width``; ``height`` defaults to keeping the aspect ratio. The
        sensor (pixel area, noise) is unchanged.

        Examples
        --------
        >>> small = default_scene().resized(160)
        >>> small.image_size, round(float(small.camera.K[0, 0]), 3)
        ((160, 90), 71.429)
        """
        width = as_int(width, "width", minimum=1)
        height = None if height is None else as_int(height, "height", minimum=1)
        w0, h0 = self.image_size
        f = width / w0
        h = height if height is not None else max(2, round(h0 * f))
        cam = self.config.camera
        changes: dict[str, Any] = {}
        if cam.fx_px is not None:
            changes["fx_px"] = cam.fx_px * f
            if cam.fy_px is not None:
                changes["fy_px"] = cam.fy_px * f
        else:
            pitch = cam.pixel_pitch_um or self.sensor.pixel_pitch * 1e6
            changes["pixel_pitch_um"] = pitch / f
        for key in ("cx_px", "cy_px"):
            value = getattr(cam, key)
            if value is not None:
                changes[key] = (value + 0.5) * f - 0.5
        if cam.skew_px:
            changes["skew_px"] = cam.skew_px * f
        return self.with_changes(render={"width": int(width), "height": h}, camera=changes)


def _where(scene: Scene) -> _Ctx:
    """Where ``scene`` came from: its file (or string) and text, to name a key's line."""
    ctx = getattr(scene, "_where", None)
    return ctx if isinstance(ctx, _Ctx) else _Ctx(None, "scene")


@contextlib.contextmanager
def _at_key(scene: Scene, path: tuple[Any, ...]) -> Iterator[None]:
    """Run a step of the simulation of ``scene``, naming the scene key ``path`` in its errors.

    An error it raises about the scene's values names the scene key ``path`` and its line in the
    scene file (issue 16: errors that arise at render time point at the file like those found when
    it is read).
    """
    try:
        yield
    except (InvalidInputError, DegenerateConfigurationError) as exc:
        msg = str(exc)
        if msg.startswith("scene key"):
            raise
        raise type(exc)(one_line(f"scene key {_where(scene).where(path)}: {msg}")) from None


def _plain(cfg: Any) -> Any:
    """Convert a validated config back to TOML-like data (tuples to lists, None dropped)."""
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


def _object_frame(o: ObjectConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the unit vectors (right, down, normal) of an object from its normal and up hint."""
    n = _unit(np.asarray(o.normal, float), f"{o.name}: normal")
    if o.up is not None:
        up = _unit(np.asarray(o.up, float), f"{o.name}: up")
    else:
        up = np.asarray(WORLD_UP) if abs(n[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    right = np.cross(up, n)
    if np.linalg.norm(right) < 1e-9:
        raise InvalidInputError(f"{o.name}: 'up' is parallel to the normal")
    right = right / np.linalg.norm(right)
    up_in = np.cross(n, right)
    return right, -up_in, n


def _object_size(o: ObjectConfig, base: Path | None) -> tuple[float, float]:
    if isinstance(o, CheckerboardConfig):
        c, r = o.squares
        m = 2 * o.margin_squares
        return (c + m) * o.square_size_m, (r + m) * o.square_size_m
    if isinstance(o, ColorCheckerConfig):
        return o.width_m, o.width_m * 2.0 / 3.0
    if isinstance(o, ImageConfig):
        tex = load_texture(o.path, base)
        return o.width_m, o.width_m * tex.shape[0] / tex.shape[1]
    assert isinstance(o, GroundConfig | PlaneConfig)
    return float(o.size_m[0]), float(o.size_m[1])


#: Bytes a texture pixel costs while a scene is loaded and rendered (the decoded samples, the
#: float64 encoded and linear copies and their temporaries): issue 25 measured 9.7 GB for a
#: 10000^2 texture.
TEXTURE_BYTES_PER_PIXEL = 100


def _check_texture_memory(cfg: SceneConfig, base: Path | None) -> None:
    """Refuse, before any texture is read, a scene whose render and textures exceed the budget.

    The render's own estimate (:func:`~imageform.simulate.budget.estimate_memory_bytes`) plus
    :data:`TEXTURE_BYTES_PER_PIXEL` per texture pixel (from the files' headers), against the
    memory budget (``IMAGEFORM_MAX_MEMORY``).
    """
    from imageform._validate import memory_limit
    from imageform.io import image_info
    from imageform.simulate.budget import estimate_memory_bytes, format_bytes

    textures = []
    for i, o in enumerate(cfg.objects):
        if isinstance(o, ImageConfig):
            info = image_info(resolve_path(o.path, base))
            textures.append((i, o, info.width, info.height))
    if not textures:
        return
    w, h = cfg.render.width, cfg.render.height
    need = estimate_memory_bytes(w, h)
    need += sum(tw * th * TEXTURE_BYTES_PER_PIXEL for _, _, tw, th in textures)
    budget = memory_limit()
    if need > budget:
        i, o, tw, th = max(textures, key=lambda t: t[2] * t[3])
        raise InvalidInputError(
            f"objects[{i}] ({o.name}): its {tw}x{th} texture and the {w}x{h} render need about "
            f"{format_bytes(need)}, more than the memory budget of {format_bytes(budget)} "
            "(IMAGEFORM_MAX_MEMORY)"
        )


def _objects(cfg: SceneConfig, base: Path | None) -> tuple[SceneObject, ...]:
    _check_texture_memory(cfg, base)
    out = []
    for o in cfg.objects:
        right, down, _ = _object_frame(o)
        w, h = _object_size(o, base)
        c = np.asarray(o.center_m, float)
        tl = c - right * w / 2 - down * h / 2
        corners = np.stack([tl, tl + right * w, tl + right * w + down * h, tl + down * h])
        out.append(SceneObject(o.type, o.name, corners, o))
    return tuple(out)


def _illuminant(il: IlluminantConfig, base: Path | None) -> Spectrum:
    from imageform.spectral import blackbody_spectrum, daylight_spectrum, illuminant

    if il.type == "cie":
        return illuminant(il.name)
    if il.type in ("blackbody", "daylight"):
        assert il.temperature_K is not None  # filled in by validation
        if il.type == "blackbody":
            return blackbody_spectrum(il.temperature_K)
        if not 4000 <= il.temperature_K <= 25000:
            raise InvalidInputError(
                f"illuminant.temperature_K: the CIE daylight series covers 4000-25000 K, "
                f"got {il.temperature_K:g}"
            )
        return daylight_spectrum(il.temperature_K)
    assert il.file is not None  # validation requires it for type 'file'
    path = resolve_path(il.file, base)
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


def _build(
    data: dict[str, Any], text: str | None, origin: str, base: Path | None, measured: Any = None
) -> Scene:
    cfg = SceneConfig.from_dict(validate_scene_dict(data, text, origin))
    ctx = _Ctx(text, origin)

    def at(path: tuple[str, ...], make: Callable[[], Any]) -> Any:
        """``make()``; an error it raises names the scene key and line (issue 16)."""
        try:
            return make()
        except InvalidInputError as exc:
            if str(exc).startswith("scene key"):
                raise
            raise type(exc)(one_line(f"scene key {ctx.where(path)}: {exc}")) from None

    sensor = at(("sensor",), cfg.sensor.to_model)
    if measured is not None:
        from imageform.simulate.measured_sensor import measured_sensor

        sensor = measured_sensor(sensor, measured)
    camera = at(
        ("camera",),
        lambda: cfg.camera.to_camera((cfg.render.width, cfg.render.height), sensor.pixel_pitch),
    )
    if cfg.lens.focus_distance_m * 1e3 <= cfg.camera.focal_length_mm:
        ctx.fail(
            ("lens", "focus_distance_m"),
            f"expected more than the focal length ({cfg.camera.focal_length_mm:g} mm), got "
            f"{cfg.lens.focus_distance_m:g} m",
        )
    scene = Scene(
        name=cfg.name,
        config=cfg,
        objects=at(("objects",), lambda: _objects(cfg, base)),
        camera=camera,
        sensor=sensor,
        illuminant=at(("illuminant",), lambda: _illuminant(cfg.illuminant, base)),
        base_dir=base,
        measured=measured,
    )
    object.__setattr__(scene, "_where", ctx)  # not a field: for errors at render time
    return scene


def load_scene(source: str | Path | dict[str, Any]) -> Scene:
    r"""Read and validate a scene: a TOML file path, a TOML string or a dict.

    Paths inside the scene (image textures, illuminant files) are relative to the file's
    folder (or the working folder for a string or dict).

    Raises
    ------
    InvalidInputError
        A missing file, a TOML syntax error, or a key of the wrong type, range or unit; the
        message names the key and the line.
    UnknownOptionError
        An unknown key or choice, with the valid ones.

    Examples
    --------
    >>> s = load_scene('name = "tiny"\n[render]\nwidth = 160\nheight = 90\n')
    >>> s.name, s.image_size
    ('tiny', (160, 90))
    """
    if isinstance(source, dict):
        return _build(copy.deepcopy(source), None, "scene dict", None)
    if isinstance(source, Path) or (
        isinstance(source, str) and "\n" not in source and "=" not in source
    ):
        path = Path(source)
        try:
            found = path.is_file()
        except OSError as exc:  # a name too long for the file system
            raise InvalidInputError(
                f"source: cannot use {describe(str(source), 60)} as a scene file: {exc.strerror}"
            ) from None
        if not found:
            kind = not_a_regular_file(path)
            if kind is not None:
                raise InvalidInputError(f"scene file (source) {describe(str(source), 120)} {kind}")
            raise InvalidInputError(f"scene file not found (source): {describe(str(source), 120)}")
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            raise InvalidInputError(
                f"scene file {describe(str(path), 100)} is not UTF-8 text (byte {exc.start}); "
                "save it as UTF-8 TOML"
            ) from None
        except OSError as exc:
            raise InvalidInputError(
                f"cannot read scene file {describe(str(path), 100)}: {exc.strerror}"
            ) from None
        origin, base = str(path), path.resolve().parent
    elif isinstance(source, str):
        text, origin, base = source, "scene string", None
    else:
        raise InvalidInputError(
            f"expected source as a TOML path, a TOML string or a dict, got {type(source).__name__}"
        )
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError) as exc:  # ValueError: a 5000-digit integer
        raise InvalidInputError(one_line(f"{origin}: TOML syntax error: {exc}")) from None
    return _build(data, text, origin, base)


def default_scene() -> Scene:
    """Return the built-in scene: a ColorChecker and a checkerboard on a ground with rails.

    They stand under tungsten light (CIE A), seen by an endoscope-like camera at 1280x720.

    Examples
    --------
    >>> default_scene().image_size
    (1280, 720)
    """
    return load_scene(_DEFAULT_TOML)
