"""The typed scene configuration: one frozen dataclass per section of a scene file.

:func:`imageform.simulate.load_scene` validates the TOML once against
:data:`~imageform.simulate.schema.SCENE_SCHEMA` (every default filled in, units converted)
and builds a :class:`SceneConfig` from it; the simulator's stages read these typed fields,
never the raw dict. Each dataclass's fields are the schema keys of its section, with the
same names and units (``focus_distance_m``, ``exposure_time_s``), so
:meth:`SceneConfig.to_dict` gives the validated description back.

The world frame of a scene is z up (:data:`WORLD_UP`; the ground is ``z = 0``), lengths in
metres; the camera frame is imageform's (x right, y down, z forward, ``X_cam = R X + t``).

:class:`CameraConfig` is also the seam to :class:`imageform.geometry.Camera`:
:meth:`CameraConfig.from_camera` describes a calibrated camera (K, R, t, distortion) as a
scene's camera section and :meth:`CameraConfig.to_camera` builds the camera the renderer
uses, so a camera read from a file can be rendered through
(:meth:`imageform.simulate.Scene.with_camera`).
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imageform import _deprecate
from imageform._validate import as_real, check_image_size, check_option, finite_result
from imageform.errors import InvalidInputError
from imageform.geometry.camera import Camera
from imageform.geometry.distortion import BrownConrady, DivisionModel, KannalaBrandt
from imageform.geometry.rotations import look_at
from imageform.sensor.model import SensorModel
from imageform.simulate.schema import DISTORTION_COEFFICIENTS, SCENE_SCHEMA
from imageform.simulate.validation import check_section

__all__ = [
    "WORLD_UP",
    "CameraConfig",
    "CheckerboardConfig",
    "ColorCheckerConfig",
    "DistortionConfig",
    "GroundConfig",
    "IlluminantConfig",
    "ImageConfig",
    "LensConfig",
    "ObjectConfig",
    "PlaneConfig",
    "ProcessingConfig",
    "RenderConfig",
    "SceneConfig",
    "SensorConfig",
    "ViewConfig",
]

#: The simulator's world up axis: z (the ground is the plane z = 0). Named wherever the
#: world meets code with another convention (``horizon_line(..., up=WORLD_UP)``, the report's
#: top view, :class:`imageform.simulate.SimulationResult`'s ``world_up``).
WORLD_UP: tuple[float, float, float] = (0.0, 0.0, 1.0)

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
#: A reflectance: a spectrally flat factor in [0, 1] or a ColorChecker patch name.
Reflectance = float | str


def _build(cls: Any, data: dict[str, Any]) -> Any:
    """``cls(**data)`` for exactly the dataclass's fields (the schema keys)."""
    names = [f.name for f in dataclasses.fields(cls)]
    missing = [n for n in names if n not in data]
    extra = [k for k in data if k not in names]
    if missing or extra:
        raise InvalidInputError(
            f"{cls.__name__}: expected the keys {names}, missing {missing}, unknown {extra}"
        )
    return cls(**data)


@dataclass(frozen=True)
class RenderConfig:
    """``[render]``: image size (pixels), supersampling and the background reflectance.

    ``supersampling`` S (S x S rays per pixel) and the reflectance seen where no object is hit.
    """

    width: int
    height: int
    supersampling: int
    background_reflectance: Reflectance

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[render]`` keys (issue 16)."""
        check_section(self, SCENE_SCHEMA["render"], "render")


@dataclass(frozen=True)
class IlluminantConfig:
    """``[illuminant]``: how the light's spectrum is given and ``illuminance_lux`` on every surface.

    ``type``: a CIE ``name``, a blackbody or daylight ``temperature_K``, or a CSV ``file``.
    ``temperature_K`` is ``None`` for a CIE or file light.
    """

    type: str
    name: str
    temperature_K: float | None
    file: str | None
    illuminance_lux: float

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[illuminant]`` keys."""
        check_section(self, SCENE_SCHEMA["illuminant"], "illuminant")


@dataclass(frozen=True)
class DistortionConfig:
    """``[camera.distortion]``: the lens distortion ``model`` and its coefficients.

    Those the model lacks are 0; see :data:`~imageform.simulate.schema.DISTORTION_COEFFICIENTS`.
    """

    model: str = "brown_conrady"
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0
    k4: float = 0.0
    k5: float = 0.0
    k6: float = 0.0

    def __post_init__(self) -> None:
        """Check for a known model and finite coefficients."""
        model = check_option(self.model, DISTORTION_COEFFICIENTS, "distortion model")
        object.__setattr__(self, "model", model)
        for key in ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"):
            object.__setattr__(self, key, as_real(getattr(self, key), key))

    def to_model(self) -> BrownConrady | DivisionModel | KannalaBrandt | None:
        """Return the :mod:`imageform.geometry.distortion` model (``None``: every coefficient 0).

        Examples
        --------
        >>> DistortionConfig(k1=-0.1).to_model()
        BrownConrady(k1=-0.1, k2=0.0, p1=0.0, p2=0.0, k3=0.0, k4=0.0, k5=0.0, k6=0.0)
        >>> DistortionConfig().to_model() is None
        True
        """
        keys = DISTORTION_COEFFICIENTS[self.model]
        coeffs = {k: getattr(self, k) for k in keys}
        if all(v == 0 for v in coeffs.values()):
            return None
        cls = {
            "brown_conrady": BrownConrady,
            "division": DivisionModel,
            "kannala_brandt": KannalaBrandt,
        }[self.model]
        return cls(**coeffs)

    @classmethod
    def from_model(cls, model: Any) -> DistortionConfig:
        """Return the section describing a distortion model (``None``: no distortion).

        Examples
        --------
        >>> DistortionConfig.from_model(KannalaBrandt(k1=0.1)).model
        'kannala_brandt'
        """
        if model is None:
            return cls()
        names = {
            BrownConrady: "brown_conrady",
            DivisionModel: "division",
            KannalaBrandt: "kannala_brandt",
        }
        name = names.get(type(model))
        if name is None:
            raise InvalidInputError(
                "expected model (the camera's distortion) as BrownConrady, DivisionModel, "
                f"KannalaBrandt or None, got {type(model).__name__}"
            )
        return cls(name, **{k: float(getattr(model, k)) for k in DISTORTION_COEFFICIENTS[name]})


@dataclass(frozen=True)
class CameraConfig:
    """``[camera]``: intrinsics, pose, ``image_plane`` and the lens ``distortion``.

    Intrinsics: ``focal_length_mm`` with the pixel pitch, or ``fx_px`` ... directly; pose:
    ``eye_m``/``target_m``/``up`` for look-at, or ``R`` and ``t_m``.

    ``focal_length_mm`` is also the lens's focal length for defocus; with ``fx_px`` given it
    does not set the intrinsics.
    """

    image_plane: str
    focal_length_mm: float
    pixel_pitch_um: float | None
    fx_px: float | None
    fy_px: float | None
    cx_px: float | None
    cy_px: float | None
    skew_px: float
    eye_m: Vec3
    target_m: Vec3
    up: Vec3
    R: Mat3 | None
    t_m: Vec3 | None
    distortion: DistortionConfig

    def __post_init__(self) -> None:
        """Check each field against the schema's ``[camera]`` keys.

        A negative ``fx_px`` would render a mirrored camera; ``distortion`` is a
        :class:`DistortionConfig`.
        """
        check_section(self, SCENE_SCHEMA["camera"], "camera")
        if not isinstance(self.distortion, DistortionConfig):
            raise TypeError(
                "expected camera.distortion as a DistortionConfig, got "
                f"{type(self.distortion).__name__}"
            )

    def to_camera(self, image_size: tuple[int, int], sensor_pixel_pitch_m: float) -> Camera:
        r"""Return the camera the renderer uses: K from the intrinsics, R and t from the pose.

        .. math:: f_x = f / p \ (\text{unless } f_x \text{ is given}),\quad f_y = f_x,\quad
            (c_x, c_y) = ((W - 1)/2, (H - 1)/2) \text{ by default}

        with ``p`` the ``pixel_pitch_um`` or else ``sensor_pixel_pitch_m``.

        Raises
        ------
        InvalidInputError
            A camera obscura (``image_plane = 'real'``) with lens distortion.
        """
        w, h = check_image_size(image_size, "image_size")
        # a pitch in metres: a complex, subnormal or absurd one is refused even when fx_px
        # makes it unused (it would otherwise be cut to its real part, or overflow f / p)
        p_m = as_real(sensor_pixel_pitch_m, "sensor_pixel_pitch_m", positive=True, maximum=1.0)
        if self.fx_px is not None:
            fx = float(self.fx_px)
        else:
            pitch = self.pixel_pitch_um * 1e-6 if self.pixel_pitch_um is not None else p_m
            fx = finite_result(
                "fx (focal length / pixel pitch)",
                lambda: self.focal_length_mm * 1e-3 / pitch,
                focal_length_mm=self.focal_length_mm,
                sensor_pixel_pitch_m=pitch,
            )
        fy = float(self.fy_px) if self.fy_px is not None else fx
        cx = float(self.cx_px) if self.cx_px is not None else (w - 1) / 2
        cy = float(self.cy_px) if self.cy_px is not None else (h - 1) / 2
        K = np.array([[fx, float(self.skew_px), cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        if self.R is not None and self.t_m is not None:
            R, t = np.asarray(self.R, float), np.asarray(self.t_m, float)
        else:
            R, t = look_at(np.asarray(self.eye_m), np.asarray(self.target_m), np.asarray(self.up))
        dist = self.distortion.to_model()
        if dist is not None and self.image_plane == "real":
            raise InvalidInputError(
                "camera.image_plane = 'real' (camera obscura) is a pinhole: remove "
                "camera.distortion"
            )
        return Camera(K, np.asarray(R), np.asarray(t), (w, h), self.image_plane, dist)  # type: ignore[arg-type]

    @classmethod
    def from_camera(cls, camera: Camera, *, focal_length_mm: float = 1.0) -> CameraConfig:
        """Return the camera section that renders through ``camera``.

        ``camera`` has K, R, t, a distortion and an image plane: the section holds the intrinsics as
        ``fx_px, fy_px, cx_px, cy_px, skew_px``, the pose as ``R`` and ``t_m``. ``focal_length_mm``
        is the lens's focal length (defocus only).

        The inverse of :meth:`to_camera`:

        Examples
        --------
        >>> cam = Camera([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]], t=[0, 0, 1],
        ...              image_size=(640, 480))
        >>> back = CameraConfig.from_camera(cam).to_camera((640, 480), 1e-6)
        >>> bool(np.array_equal(back.K, cam.K) and np.array_equal(back.t, cam.t))
        True
        """
        if not isinstance(camera, Camera):
            raise InvalidInputError(
                f"expected an imageform.geometry.Camera, got {type(camera).__name__}"
            )
        K = np.asarray(camera.K, dtype=np.float64)
        R = np.asarray(camera.R, dtype=np.float64)
        t = np.asarray(camera.t, dtype=np.float64)
        if not (np.all(np.isfinite(K)) and np.all(np.isfinite(R)) and np.all(np.isfinite(t))):
            raise InvalidInputError("expected a camera with finite K, R and t")
        if K[0, 0] <= 0 or K[1, 1] <= 0:
            raise InvalidInputError(
                f"expected positive focal lengths fx, fy, got {K[0, 0]:g}, {K[1, 1]:g}"
            )
        return cls(
            image_plane=str(camera.image_plane),
            focal_length_mm=as_real(focal_length_mm, "focal_length_mm", positive=True),
            pixel_pitch_um=None,
            fx_px=float(K[0, 0]),
            fy_px=float(K[1, 1]),
            cx_px=float(K[0, 2]),
            cy_px=float(K[1, 2]),
            skew_px=float(K[0, 1]),
            eye_m=(0.0, -0.1, 0.05),
            target_m=(0.0, 0.0, 0.0),
            up=WORLD_UP,
            R=tuple(tuple(float(x) for x in row) for row in R),  # type: ignore[arg-type]
            t_m=(float(t[0]), float(t[1]), float(t[2])),
            distortion=DistortionConfig.from_model(camera.distortion),
        )


@dataclass(frozen=True)
class LensConfig:
    """``[lens]``: aperture, focus, defocus blur, vignetting, lateral CA and diffraction.

    Aperture ``f_number``, ``focus_distance_m``, whether to blur by defocus, the natural
    ``vignetting``, the per-channel magnification ``lateral_ca``, whether to blur by
    ``diffraction`` (off by default) and the defocus ``psf``: ``"geometric"`` (the disc of
    the circle of confusion) or ``"wave"`` (the pupil's PSF with that defocus as its Zernike
    term, diffraction included).
    """

    f_number: float
    focus_distance_m: float
    defocus: bool
    vignetting: str
    lateral_ca: Vec3
    diffraction: bool = False
    psf: str = "geometric"

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[lens]`` keys."""
        check_section(self, SCENE_SCHEMA["lens"], "lens")


@dataclass(frozen=True)
class SensorConfig:
    """``[sensor]``: a preset, its spectral sensitivity, the CFA, the exposure, noise and overrides.

    The exposure is in seconds or ``"auto"``; noise is on or off; overrides of the preset's
    parameters (``None``: the preset's).
    """

    preset: str
    spectral_sensitivity: str
    peak_qe: float
    cfa: str
    exposure_time_s: float | str
    auto_exposure_level: float
    shutter: str | None
    noise: bool
    pixel_pitch_um: float | None
    fill_factor: float | None
    full_well_e: float | None
    read_noise_e: float | None
    dark_current_e_per_s: float | None
    dsnu_e: float | None
    prnu: float | None
    column_fpn_e: float | None
    conversion_gain_uV_per_e: float | None
    analog_gain: float | None
    bit_depth: int | None
    black_level_dn: float | None
    fpn_seed: int | None

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[sensor]`` keys."""
        check_section(self, SCENE_SCHEMA["sensor"], "sensor")

    def to_model(self) -> SensorModel:
        """Return the :class:`~imageform.sensor.SensorModel`: the preset (colour), overridden.

        The overrides are converted to SI units, and measured QE curves scaled to ``peak_qe``.
        """
        from imageform.sensor.presets import ccd_preset, cmos_preset

        base = (cmos_preset if self.preset == "cmos" else ccd_preset)(color=True)
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
            value = getattr(self, key)
            if value is not None:
                changes[name] = float(value) * scale
        if self.bit_depth is not None:
            changes["bit_depth"] = int(self.bit_depth)
        if self.fpn_seed is not None:
            changes["fpn_seed"] = int(self.fpn_seed)
        if self.shutter is not None:
            changes["shutter"] = self.shutter
        if self.spectral_sensitivity == "nikon_d5100":
            from imageform.spectral import camera_sensitivities

            sens = camera_sensitivities("nikon_d5100")
            vals = sens.values / sens.values.max() * float(self.peak_qe)
            changes["qe_wavelengths"] = tuple(float(w) for w in sens.wavelengths)
            changes["qe_curves"] = tuple(tuple(float(x) for x in vals[:, c]) for c in range(3))
            changes["name"] = f"{base.name}, Nikon D5100 spectral sensitivities"
        return dataclasses.replace(base, **changes)


@dataclass(frozen=True)
class ProcessingConfig:
    """``[processing]``: the camera's processing after the sensor.

    Demosaicing, lens-shading correction, white balance, colour correction, output space and
    transfer function.
    """

    demosaic: str
    lens_shading_correction: bool
    white_balance: str
    color_correction: str
    output_space: str
    transfer: str

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[processing]`` keys."""
        check_section(self, SCENE_SCHEMA["processing"], "processing")


#: ``centre_m``, the old name of the objects' ``center_m`` (issue 30), kept one release: the
#: constructors take it and ``.centre_m`` reads ``center_m`` (a DeprecationWarning); a scene
#: file's ``centre_m`` key is read by :func:`~imageform.simulate.validation.validate_scene_dict`.
_center_m = _deprecate.renamed_fields({"centre_m": "center_m"})


@_center_m
@dataclass(frozen=True)
class ObjectConfig:
    """The pose every ``[[objects]]`` entry has: ``type``, ``name``, ``center_m`` and orientation.

    ``center_m`` is in world coordinates, ``normal`` is the front face's normal and ``up`` the world
    direction of its top edge (``None``: z, or y for a horizontal object).
    """

    type: str
    name: str
    center_m: Vec3
    normal: Vec3
    up: Vec3 | None

    def __post_init__(self) -> None:
        """Check each field against the schema's keys of its ``type``; ``center_m`` is required."""
        schema = SCENE_SCHEMA["objects"]
        if not isinstance(self.type, str) or self.type not in schema:
            raise TypeError(f"expected type as one of {', '.join(schema)}, got {self.type!r:.40}")
        check_section(self, schema[self.type], "objects")
        if self.center_m is None:
            raise TypeError(
                "expected objects.center_m as 3 numbers (the object's position), got None"
            )


@_center_m
@dataclass(frozen=True)
class CheckerboardConfig(ObjectConfig):
    """A checkerboard: ``squares`` (columns, rows) of ``square_size_m``.

    A light border of ``margin_squares``, the two reflectances (the top-left square dark).
    """

    squares: tuple[int, int]
    square_size_m: float
    margin_squares: float
    dark_reflectance: Reflectance
    light_reflectance: Reflectance


@_center_m
@dataclass(frozen=True)
class ColorCheckerConfig(ObjectConfig):
    """A ColorChecker Classic (6 x 4 patches, BabelColor average spectra), ``width_m`` wide.

    It is 2/3 as tall, with the patches separated by ``gap_fraction`` of a cell of the frame.
    """

    width_m: float
    gap_fraction: float
    frame_reflectance: Reflectance


@_center_m
@dataclass(frozen=True)
class GroundConfig(ObjectConfig):
    """A ground of ``size_m`` (across, along) with rails and sleepers.

    ``rail_count`` rails run towards its top edge, with sleepers between them.
    """

    size_m: Vec2
    reflectance: Reflectance
    rail_count: int
    rail_gauge_m: float
    rail_width_m: float
    rail_reflectance: Reflectance
    sleeper_spacing_m: float
    sleeper_width_m: float
    sleeper_length_m: float
    sleeper_reflectance: Reflectance


@_center_m
@dataclass(frozen=True)
class ImageConfig(ObjectConfig):
    """A photograph (``path``, relative to the scene file) ``width_m`` wide."""

    path: str
    width_m: float


@_center_m
@dataclass(frozen=True)
class PlaneConfig(ObjectConfig):
    """A uniform rectangle of ``size_m`` (width, height)."""

    size_m: Vec2
    reflectance: Reflectance


_OBJECT_CLASSES: dict[str, type[ObjectConfig]] = {
    "checkerboard": CheckerboardConfig,
    "colorchecker": ColorCheckerConfig,
    "ground": GroundConfig,
    "image": ImageConfig,
    "plane": PlaneConfig,
}


@dataclass(frozen=True)
class ViewConfig:
    """An extra view of the scene (``[[views]]``): the same camera at another look-at pose.

    It looks from ``eye_m`` at ``target_m`` with ``up`` up. ``imageform simulate`` renders each one
    through the whole chain beside the main view (e.g. the views of a calibration board).
    """

    eye_m: Vec3
    target_m: Vec3
    up: Vec3

    def __post_init__(self) -> None:
        """Each field checked against the schema's ``[[views]]`` keys; ``eye_m`` required."""
        check_section(self, SCENE_SCHEMA["views"], "views")
        if self.eye_m is None:
            raise TypeError(
                "expected views.eye_m as 3 numbers (the view's camera centre), got None"
            )


@dataclass(frozen=True)
class SceneConfig:
    """A whole validated scene description, typed.

    ``name``, ``description``, one section dataclass per table, the extra ``views`` and the
    ``objects`` in file order.

    Built by :func:`imageform.simulate.load_scene`; :meth:`to_dict` gives the validated plain
    description (every default filled in) back.
    """

    name: str
    description: str
    render: RenderConfig
    illuminant: IlluminantConfig
    camera: CameraConfig
    lens: LensConfig
    sensor: SensorConfig
    processing: ProcessingConfig
    objects: tuple[ObjectConfig, ...] = field(default=())
    views: tuple[ViewConfig, ...] = field(default=())

    @classmethod
    def from_dict(cls, cfg: dict[str, Any]) -> SceneConfig:
        """Return the typed form of a validated description.

        The description is :func:`~imageform.simulate.validation.validate_scene_dict`'s output.
        """
        cam = dict(cfg["camera"])
        cam["distortion"] = _build(DistortionConfig, cam["distortion"])
        return cls(
            name=str(cfg["name"]),
            description=str(cfg["description"]),
            render=_build(RenderConfig, cfg["render"]),
            illuminant=_build(IlluminantConfig, cfg["illuminant"]),
            camera=_build(CameraConfig, cam),
            lens=_build(LensConfig, cfg["lens"]),
            sensor=_build(SensorConfig, cfg["sensor"]),
            processing=_build(ProcessingConfig, cfg["processing"]),
            objects=tuple(_build(_OBJECT_CLASSES[o["type"]], o) for o in cfg["objects"]),
            views=tuple(_build(ViewConfig, v) for v in cfg.get("views", ())),
        )

    def to_dict(self) -> dict[str, Any]:
        """Return the description as plain data (sections as dicts, objects as a list of dicts)."""
        out = dataclasses.asdict(self)
        out["objects"] = list(out["objects"])
        out["views"] = list(out["views"])
        return out

    def __getitem__(self, section: str) -> Any:
        """Return a section by name: deprecated dict access (``config["lens"]["f_number"]``).

        Use the attributes (``config.lens.f_number``).
        """
        warnings.warn(
            f"Scene.config[{section!r}] is deprecated: Scene.config is a typed SceneConfig; "
            f"use scene.config.{section} (or scene.config.to_dict())",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.to_dict()[section]
