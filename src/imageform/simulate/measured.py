"""A measured camera in the simulator: a camera file's ``[sensor]``, ``[optics]`` and
``[color]`` tables (docs/camera-file.md) turned into the simulator's sensor model, lens blur
and processing (:func:`apply_camera_file`; docs/simulate.md, "A measured camera").

The camera file overrides the scene: each key present replaces the scene's value; a key or
table absent leaves the scene's as it is (a file without these tables renders exactly as
before).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError
from imageform.io import CameraColor, CameraFile, CameraOptics, CameraSensor
from imageform.sensor.model import SensorModel

if TYPE_CHECKING:
    from imageform.simulate.scene import Scene

__all__ = [
    "MeasuredCamera",
    "apply_camera_file",
    "gaussian_sigma_for_mtf50",
    "measured_color_matrix",
    "measured_optics_blur",
    "measured_sensor",
]


@dataclass(frozen=True)
class MeasuredCamera:
    """The measured-camera tables a scene renders through (each None when absent)."""

    sensor: CameraSensor | None = None
    optics: CameraOptics | None = None
    color: CameraColor | None = None

    def __post_init__(self) -> None:
        """Each field None or its camera-file dataclass."""
        tables = (("sensor", CameraSensor), ("optics", CameraOptics), ("color", CameraColor))
        for name, cls in tables:
            v = getattr(self, name)
            if v is not None and not isinstance(v, cls):
                raise TypeError(f"expected {name} as a {cls.__name__} or None, got {describe(v)}")

    @property
    def empty(self) -> bool:
        """No table at all."""
        return self.sensor is None and self.optics is None and self.color is None


def measured_sensor(sensor: SensorModel, measured: MeasuredCamera | None) -> SensorModel:
    """The scene's sensor model with the camera file's ``[sensor]`` values (and the
    ``[color]`` spectral sensitivities) in place of its own.

    The EMVA 1288 system gain ``K`` is set through the analog gain, the preset's conversion
    gain and ADC range kept: :math:`G_{analog} = K\\, V_{ADC} / (G_{conv} (2^b - 1))`. The
    file's ``dsnu_e`` is the whole dark non-uniformity, so the preset's column offsets are
    removed. ``quantum_efficiency`` scales the QE curves to that peak; sensitivities given in
    ``[color]`` replace the curves' shape. ``exposure_time_s`` is not applied (the scene's
    exposure is a shooting setting).

    Raises
    ------
    InvalidInputError
        ``bit_depth`` above 16 (the simulator's ADC), or values the sensor model refuses
        (a black level above the ADC's range).
    """
    if measured is None:
        return sensor
    s, color = measured.sensor, measured.color
    changes: dict[str, Any] = {}
    if s is not None:
        table = {
            "read_noise_e": "read_noise",
            "dark_current_e_per_s": "dark_current",
            "dsnu_e": "dsnu",
            "prnu": "prnu",
            "full_well_e": "full_well",
            "black_level_dn": "black_level",
        }
        for key, name in table.items():
            if getattr(s, key) is not None:
                changes[name] = float(getattr(s, key))
        if s.pixel_pitch_um is not None:
            changes["pixel_pitch"] = s.pixel_pitch_um * 1e-6
        changes["column_fpn"] = 0.0
        bits = sensor.bit_depth
        if s.bit_depth is not None:
            if s.bit_depth > 16:
                raise InvalidInputError(
                    f"sensor.bit_depth: the simulator's ADC has at most 16 bits, got {s.bit_depth}"
                )
            bits = changes["bit_depth"] = int(s.bit_depth)
        if s.system_gain_dn_per_e is not None:
            changes["analog_gain"] = (
                s.system_gain_dn_per_e * sensor.adc_range / (sensor.conversion_gain * (2**bits - 1))
            )
    wl = np.asarray(sensor.qe_wavelengths, dtype=np.float64)
    curves = np.asarray(sensor.qe_curves, dtype=np.float64)
    peak = float(curves.max())
    qe_changed = False
    if color is not None and color.sensitivity is not None:
        w, v = color.sensitivity.to_array()
        step = float(np.min(np.diff(w)))
        wl = np.concatenate([[max(w[0] - step, 1.0)], w, [w[-1] + step]])
        curves = np.vstack([np.zeros(3), v, np.zeros(3)]).T
        curves = curves / curves.max() * peak
        qe_changed = True
    if color is not None and color.spectral_sensitivity is not None:
        from imageform.spectral import camera_sensitivities

        sens = camera_sensitivities(color.spectral_sensitivity)
        wl = np.asarray(sens.wavelengths, dtype=np.float64)
        curves = np.asarray(sens.values, dtype=np.float64).T
        curves = curves / curves.max() * peak
        qe_changed = True
    if s is not None and s.quantum_efficiency is not None:
        curves = curves / curves.max() * s.quantum_efficiency
        qe_changed = True
    if qe_changed:
        changes["qe_wavelengths"] = tuple(float(x) for x in wl)
        changes["qe_curves"] = tuple(tuple(float(x) for x in c) for c in curves)
    if not changes:
        return sensor
    try:
        return dataclasses.replace(sensor, **changes)
    except InvalidInputError as exc:
        raise InvalidInputError(f"camera file [sensor]: {exc}") from None


def _sub_box(f: float, n: int) -> float:
    """|MTF| of the mean of ``n`` point samples across a pixel at ``f`` cycles/pixel."""
    if f == 0:
        return 1.0
    return abs(math.sin(math.pi * f) / (n * math.sin(math.pi * f / n)))


def gaussian_sigma_for_mtf50(mtf50: float, *, supersampling: int = 0) -> float:
    """The Gaussian PSF's sigma (pixels) that gives a system MTF50 of ``mtf50`` (cycles per
    pixel).

    A Gaussian of sigma :math:`\\sigma` has :math:`\\mathrm{MTF}(f) = e^{-2\\pi^2\\sigma^2
    f^2}`, so on its own :math:`\\sigma = \\sqrt{\\ln 2 / (2\\pi^2)} / f_{50}`. A slanted-edge
    measurement also sees the pixel aperture: with ``supersampling`` S > 0 (the renderer's S
    point samples across each pixel, MTF :math:`|\\sin(\\pi f) / (S \\sin(\\pi f / S))|`) sigma
    is solved from :math:`e^{-2\\pi^2\\sigma^2 f_{50}^2}\\, \\mathrm{box}_S(f_{50}) = 1/2`; 0 when
    the pixel alone is already that blurred.

    Examples
    --------
    >>> round(gaussian_sigma_for_mtf50(0.25), 4)
    0.7496
    >>> round(gaussian_sigma_for_mtf50(0.25, supersampling=4), 4)
    0.6942
    """
    f = as_real(mtf50, "mtf50 (cycles/pixel)", positive=True)
    n = as_int(supersampling, "supersampling", minimum=0)
    box = _sub_box(f, n) if n else 1.0
    if box <= 0.5:
        return 0.0
    return math.sqrt(math.log(box / 0.5) / (2 * math.pi**2)) / f


#: Wavelengths (m) of the R, G, B channels for a Zernike PSF (the bands of
#: :data:`imageform.simulate.stages.DIFFRACTION_BANDS`, three per channel).
_ZERNIKE_BANDS = (
    (610e-9, 650e-9, 690e-9),
    (510e-9, 550e-9, 590e-9),
    (430e-9, 465e-9, 500e-9),
)


def measured_optics_blur(
    image: np.ndarray, optics: CameraOptics, *, pixel_pitch: float, supersampling: int
) -> np.ndarray:
    """``image (H, W, 3)`` (R, G, B, already integrated over each pixel by the renderer)
    blurred by the camera file's lens model, borders reflected, light kept >= 0.

    ``diffraction``: :func:`imageform.simulate.stages.diffraction_blur` at ``f_number``.
    ``zernike``: per channel the polychromatic PSF of the aberrated pupil
    (:func:`imageform.optics.polychromatic_psf`, coefficients in waves at ``wavelength_nm``
    turned into metres of optical path), point-sampled at ``pixel_pitch``. ``gaussian``:
    :func:`scipy.ndimage.gaussian_filter` of ``gaussian_sigma_px``. ``mtf50``: the Gaussian of
    :func:`gaussian_sigma_for_mtf50` for each channel's MTF50 (the pixel aperture of
    ``supersampling`` accounted for).
    """
    from scipy.ndimage import gaussian_filter

    img = np.asarray(image, dtype=np.float64)
    if img.ndim != 3 or img.shape[2] != 3:
        raise InvalidInputError(f"expected image as an (H, W, 3) array, got {describe(image)}")
    model = optics.model
    if model == "diffraction":
        from imageform.simulate.stages import diffraction_blur

        assert optics.f_number is not None
        return diffraction_blur(img, f_number=optics.f_number, pixel_pitch=pixel_pitch)
    out = np.empty_like(img)
    if model in ("gaussian", "mtf50"):
        if model == "gaussian":
            sigmas: tuple[float, ...] = (float(optics.gaussian_sigma_px or 0.0),) * 3
        else:
            rgb = optics.mtf50_rgb()
            assert rgb is not None
            sigmas = tuple(gaussian_sigma_for_mtf50(m, supersampling=supersampling) for m in rgb)
        for c in range(3):
            out[..., c] = (
                gaussian_filter(img[..., c], sigmas[c], mode="reflect", truncate=5.0)
                if sigmas[c] > 0
                else img[..., c]
            )
        return np.maximum(out, 0.0)
    # zernike
    from scipy.signal import fftconvolve

    from imageform.optics import polychromatic_psf

    assert optics.zernike is not None and optics.wavelength_nm is not None
    assert optics.f_number is not None
    coeffs = {j + 1: w * optics.wavelength_nm * 1e-9 for j, w in enumerate(optics.zernike)}
    rms_waves = math.sqrt(sum(w * w for w in optics.zernike[3:]))
    reach = 10 * 700e-9 * optics.f_number * (1 + 4 * rms_waves) / pixel_pitch
    half = min(64, max(2, math.ceil(reach)))
    size = 2 * half + 1
    for c, band in enumerate(_ZERNIKE_BANDS):
        kernel = polychromatic_psf(
            coeffs, wavelengths=band, f_number=optics.f_number, pixel_pitch=pixel_pitch, size=size
        )
        if min(img.shape[:2]) > half:
            padded = np.pad(img[..., c], half, mode="reflect")
        else:
            padded = np.pad(img[..., c], half, mode="symmetric")
        out[..., c] = fftconvolve(padded, kernel, mode="valid")
    return np.maximum(out, 0.0)


def measured_color_matrix(color: CameraColor) -> np.ndarray | None:
    """The simulator's colour-correction matrix ``M`` (``linear sRGB = camera RGB @ M``) of
    the file's ``ccm`` (``out = ccm @ rgb``): ``ccm.T``, or for ``ccm_to = "xyz"``
    :math:`(M_{XYZ \\to sRGB}\\, \\mathrm{ccm})^T`; None without a ``ccm``."""
    if color.ccm is None:
        return None
    ccm = np.asarray(color.ccm, dtype=np.float64)
    if color.ccm_to == "xyz":
        from imageform.color import xyz_to_linear_srgb

        to_srgb = np.asarray(xyz_to_linear_srgb(np.eye(3))).T  # columns: images of X, Y, Z
        ccm = to_srgb @ ccm
    return np.asarray(ccm.T)


def apply_camera_file(scene: Scene, camera_file: CameraFile) -> Scene:
    """``scene`` seen through a camera file: its geometry and its measured tables.

    Geometry: the file's K, distortion and image size, and its pose if it has one (else the
    scene's camera pose). ``[sensor]``: :func:`measured_sensor` (and ``cfa`` replaces
    ``sensor.cfa``). ``[optics]``: the file's blur (:func:`measured_optics_blur`) replaces the
    scene's lens blur (``lens.defocus`` and ``lens.diffraction`` off; ``f_number`` the file's
    when given). ``[color]``: ``white_balance`` gains replace ``processing.white_balance``,
    ``ccm`` replaces ``processing.color_correction``, sensitivities the sensor's QE curves.
    Values the file gives win over the scene's.

    Examples
    --------
    >>> from imageform.geometry import Camera
    >>> from imageform.simulate import default_scene
    >>> cam = Camera([[100.0, 0, 79.5], [0, 100.0, 59.5], [0, 0, 1]], image_size=(160, 120))
    >>> s = apply_camera_file(default_scene(), CameraFile(cam, sensor={"read_noise_e": 7.5}))
    >>> s.image_size, s.sensor.read_noise
    ((160, 120), 7.5)
    """
    from imageform.geometry import Camera
    from imageform.simulate.scene import Scene

    if not isinstance(scene, Scene):
        raise TypeError(f"expected scene as a Scene (load_scene), got {describe(scene)}")
    if not isinstance(camera_file, CameraFile):
        raise TypeError(
            f"expected camera_file as an imageform.io.CameraFile (read_camera), got "
            f"{describe(camera_file)}"
        )
    cam = camera_file.camera
    where = camera_file.path if camera_file.path is not None else "camera file"
    if cam.image_size is None:
        raise InvalidInputError(
            f"{where}: the camera file has no image size ([image] width, height) to render"
        )
    if not camera_file.has_pose:
        here = scene.camera
        cam = Camera(cam.K, here.R, here.t, cam.image_size, cam.image_plane, cam.distortion)
    measured = MeasuredCamera(camera_file.sensor, camera_file.optics, camera_file.color)
    fx = float(np.asarray(cam.K)[0, 0])
    focal_mm = None
    if camera_file.optics is not None:
        pitch = camera_file.sensor.pixel_pitch_um if camera_file.sensor is not None else None
        if camera_file.optics.focal_length_mm is not None:
            focal_mm = camera_file.optics.focal_length_mm
        elif pitch is not None:
            focal_mm = fx * pitch * 1e-3
    out = scene.with_camera(cam, focal_length_mm=focal_mm)
    changes: dict[str, Any] = {}
    if camera_file.sensor is not None and camera_file.sensor.cfa is not None:
        changes["sensor"] = {"cfa": camera_file.sensor.cfa}
    if camera_file.optics is not None:
        lens: dict[str, Any] = {"defocus": False, "diffraction": False}
        if camera_file.optics.f_number is not None:
            lens["f_number"] = camera_file.optics.f_number
        changes["lens"] = lens
    color = camera_file.color
    if color is not None:
        proc: dict[str, Any] = {}
        if color.white_balance is not None:
            proc["white_balance"] = "none"  # the file's gains are applied instead
        if color.ccm is not None:
            proc["color_correction"] = "none"  # the file's matrix is applied instead
        if proc:
            changes["processing"] = proc
    if changes:
        out = out.with_changes(**changes)
    if measured.empty:
        return out
    return out.with_measured(measured)
