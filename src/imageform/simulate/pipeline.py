"""The camera pipeline: render, optics, sensor, ISP; every stage kept (:func:`simulate`)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError
from imageform.simulate.colorfit import apply_color_correction, fit_color_correction
from imageform.simulate.render import RenderOutput, render_scene
from imageform.simulate.result import SceneQuad, SimulationResult, Stage
from imageform.simulate.scene import Scene
from imageform.simulate.truth import (
    colorchecker_truth,
    delta_e_patches,
    detect_vanishing,
    patch_means,
    patch_stats,
    rails_truth,
    xy_of_linear_srgb,
)

__all__ = ["simulate"]

Progress = Callable[[str, float], Any]

# Share of the run's time each step takes on the default scene (drives the progress bar).
_WEIGHTS = {
    "render": 0.44,
    "optics": 0.08,
    "sensor": 0.05,
    "demosaic": 0.1,
    "isp": 0.02,  # each of the four ISP steps
    "vanishing": 0.2,
    "photon_transfer": 0.05,
}


class _Clock:
    def __init__(self, progress: Progress | None) -> None:
        self.progress = progress
        self.done = 0.0
        self.seconds: dict[str, float] = {}
        self.t0 = time.perf_counter()

    def start(self) -> None:
        self.t0 = time.perf_counter()

    def tick(self, step: str, name: str) -> float:
        dt = time.perf_counter() - self.t0
        self.seconds[name] = self.seconds.get(name, 0.0) + dt
        self.done = min(1.0, self.done + _WEIGHTS.get(step, 0.0))
        self.report(step, self.done)
        self.t0 = time.perf_counter()
        return dt

    def report(self, step: str, fraction: float) -> None:
        if self.progress is not None:
            self.progress(step, float(min(1.0, fraction)))


def _auto_exposure(rate: np.ndarray, scene: Scene) -> float:
    s = scene.config["sensor"]
    if s["exposure_time_s"] != "auto":
        return float(s["exposure_time_s"])
    bright = float(np.percentile(rate.max(axis=-1), 99.5))
    if bright <= 0:
        raise InvalidInputError("the scene is black: auto exposure has nothing to measure")
    return float(s["auto_exposure_level"]) * scene.sensor.full_well / bright


def _sensor(mean_e: np.ndarray, scene: Scene, t: float, seed: int) -> np.ndarray:
    """Mean electrons (H, W, 3) -> mosaicked raw DN (H, W) uint16."""
    from imageform.sensor.cfa import cfa_masks

    sensor = scene.sensor
    if scene.config["sensor"]["noise"]:
        dn = sensor.capture(mean_e, exposure_time=t, rng=np.random.default_rng(seed))
    else:
        e = np.minimum(mean_e, sensor.full_well) + sensor.dark_current * t
        analog = sensor.system_gain * e + sensor.black_level
        dn = np.clip(np.floor(analog + 0.5), 0, sensor.max_dn).astype(np.uint16)
    masks = cfa_masks(mean_e.shape[:2], scene.config["sensor"]["cfa"])
    return np.asarray((dn * masks).sum(axis=-1), dtype=np.uint16)


def _white_balance(img: np.ndarray, method: str, cc_rgb: np.ndarray | None) -> tuple[Any, Any]:
    from imageform.color import white_balance

    if method == "none":
        return img, np.ones(3)
    if method == "colorchecker":
        if cc_rgb is None:
            raise InvalidInputError("white_balance = 'colorchecker' needs a colorchecker object")
        neutral = cc_rgb[19:23]  # neutral 8, 6.5, 5, 3.5 (white may clip, black is noisy)
        gains = np.nanmean(neutral[:, 1:2] / neutral, axis=0)
        return img * gains, gains
    res = white_balance(img, method, transfer="linear", normalize="green")
    return np.asarray(res.image), np.asarray(res.gains)


def _encode(lin_srgb: np.ndarray, space: str, transfer: str) -> tuple[np.ndarray, str]:
    from imageform.color import RGB_SPACES, encode, linear_srgb_to_xyz, xyz_to_linear_rgb

    lin = lin_srgb if space == "srgb" else xyz_to_linear_rgb(linear_srgb_to_xyz(lin_srgb), space)
    tf = RGB_SPACES[space].transfer if transfer == "space" else transfer
    clipped = np.clip(np.asarray(lin), 0.0, 1.0)  # the display range: an explicit ISP step
    return np.asarray(encode(clipped, tf)), tf


def _decode_to_linear_srgb(out: np.ndarray, space: str, tf: str) -> np.ndarray:
    from imageform.color import decode, linear_rgb_to_xyz, xyz_to_linear_srgb

    lin = np.asarray(decode(out, tf))
    return lin if space == "srgb" else np.asarray(xyz_to_linear_srgb(linear_rgb_to_xyz(lin, space)))


def _optics(r: RenderOutput, scene: Scene) -> np.ndarray:
    from imageform.optics import blur_by_radius, defocus_radius_px, lateral_chromatic_aberration

    lens, cam = scene.config["lens"], scene.camera
    img = r.rate
    mags = tuple(lens["lateral_ca"])
    if any(m != 1.0 for m in mags):
        K = np.asarray(cam.K)
        shifted = lateral_chromatic_aberration(
            img, mags, centre=(float(K[0, 2]), float(K[1, 2])), fill=np.nan
        )
        # a channel shrunk by m < 1 samples outside the frame at the border: keep the
        # unshifted value there (the lens would have imaged light from beyond the frame)
        img = np.where(np.isnan(shifted), img, shifted)
    if lens["defocus"]:
        f = scene.config["camera"]["focal_length_mm"] * 1e-3
        # the pitch at which the lens's image is sampled: f / fx (the camera's pixels)
        pitch = f / float(np.asarray(cam.K)[0, 0])
        rad = defocus_radius_px(
            r.depth,
            f=f,
            f_number=lens["f_number"],
            focus=lens["focus_distance_m"],
            pixel_pitch=pitch,
        )
        if float(np.max(rad)) >= 0.25:
            img = blur_by_radius(img, rad, step=0.5, max_layers=12)
            # the FFT convolution leaves round-off of ~1e-13 around zero; light is >= 0
            img = np.maximum(img, 0.0)
    return np.asarray(img)


def simulate(scene: Scene, *, progress: Progress | None = None, seed: int = 0) -> SimulationResult:
    """Run a scene through the whole chain and keep every stage.

    Stages, in order: ``rendered`` (ray-cast mean photo-electrons per second, camera RGB,
    with distortion and cos⁴ vignetting), ``optics`` (lateral chromatic aberration and
    depth-dependent defocus), ``raw`` (photons to electrons, shot/dark/read noise, FPN,
    CFA mosaic, ADC), ``demosaiced``, ``shading_corrected`` (the vignetting map divided
    out, if enabled), ``white_balanced``, ``color_corrected`` (3×3 matrix fitted on the
    ColorChecker, linear sRGB) and ``output`` (encoded, kind ``"srgb"``).

    Parameters
    ----------
    scene : Scene
        From :func:`load_scene` or :func:`default_scene`.
    progress : callable, optional
        ``progress(step_name, fraction_done)``: called as the run proceeds, with the
        fraction of the whole run done (non-decreasing, 1.0 at the end).
    seed : int
        Seed of the temporal noise and of the vanishing-point RANSAC.

    Returns
    -------
    SimulationResult
        ``metrics`` holds: ``delta_e00_per_patch``, ``delta_e00_mean``, ``delta_e00_max``
        (output image vs the D65 ground truth), ``snr_db_per_patch`` (luminance of the
        colour-corrected stage), ``vanishing_point_error_px``, ``horizon_angle_error_deg``,
        ``exposure_time_s``, ``white_balance_gains``, ``color_correction_matrix``,
        ``stage_seconds`` and ``total_seconds``.

    >>> from imageform.simulate import default_scene
    >>> res = simulate(default_scene().resized(160))
    >>> res.stages[-1].kind, res.stages[-1].image.shape
    ('srgb', (90, 160, 3))
    """
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"expected a Scene (load_scene), got {type(scene).__name__}")
    t_start = time.perf_counter()
    cfg, cam, sensor = scene.config, scene.camera, scene.sensor
    proc = cfg["processing"]
    checkers = [o for o in scene.objects if o.kind == "colorchecker"]
    if not checkers and "colorchecker" in (proc["color_correction"], proc["white_balance"]):
        raise InvalidInputError(
            "processing.color_correction / white_balance = 'colorchecker' needs a colorchecker "
            "object in the scene; set them to 'none' / 'gray_world'"
        )
    clock = _Clock(progress)
    stages: list[Stage] = []

    def add(
        name: str,
        title: str,
        desc: str,
        image: np.ndarray,
        kind: str,
        step: str,
        white: float | None = None,
    ) -> None:
        dt = clock.tick(step, name)
        stages.append(Stage(name, title, desc, image, kind, white, dt))  # type: ignore[arg-type]

    w8 = _WEIGHTS["render"]
    r = render_scene(scene, progress=lambda f: clock.report("render", f * w8))
    S = cfg["render"]["supersampling"]
    add(
        "rendered",
        "Rendered scene",
        f"Ray casting, {S}x{S} rays per pixel: electrons/s = FF A sum rho E QE lambda/(hc) "
        f"/(4N^2), times cos^4(theta), through the lens distortion.",
        r.rate.astype(np.float32),
        "linear",
        "render",
    )

    optical = _optics(r, scene)
    add(
        "optics",
        "Lens: chromatic aberration and defocus",
        "Each channel scaled by its magnification (lateral colour); each pixel blurred by the "
        "disc of its circle of confusion c = (f/N)|d - s|/d f/(s - f).",
        optical.astype(np.float32),
        "linear",
        "optics",
    )

    t_exp = _auto_exposure(optical, scene)
    raw = _sensor(optical * t_exp, scene, t_exp, seed)
    add(
        "raw",
        "Raw sensor image",
        f"Exposure {t_exp * 1e3:.3g} ms: photo-electrons with shot, dark and read noise and "
        f"fixed pattern, {cfg['sensor']['cfa']} mosaic, {sensor.bit_depth}-bit ADC "
        f"(K = {sensor.system_gain:.3g} DN/e-).",
        raw,
        "raw",
        "sensor",
        float(sensor.max_dn),
    )

    from imageform.sensor.demosaic import demosaic

    dark_dn = sensor.system_gain * sensor.dark_current * t_exp
    norm = (raw.astype(np.float64) - sensor.black_level - dark_dn) / (
        sensor.max_dn - sensor.black_level
    )
    cam_rgb = np.asarray(
        demosaic(norm, cfg["sensor"]["cfa"], proc["demosaic"], allow_odd=True), dtype=np.float64
    )
    add(
        "demosaiced",
        "Demosaiced camera RGB",
        f"Black level and mean dark signal subtracted, scaled to [0, 1], "
        f"{proc['demosaic']} demosaicing.",
        cam_rgb.astype(np.float32),
        "linear",
        "demosaic",
    )

    img = cam_rgb
    if proc["lens_shading_correction"] and cfg["lens"]["vignetting"] != "none":
        img = img / r.falloff[..., None]
        add(
            "shading_corrected",
            "Lens-shading correction",
            "Divided by the lens's cos^4 vignetting map (a flat-field correction).",
            img.astype(np.float32),
            "linear",
            "isp",
        )

    truth = colorchecker_truth(checkers[0], cam) if checkers else None
    cc_before = patch_means(img, truth) if truth is not None else None
    balanced, gains = _white_balance(img, proc["white_balance"], cc_before)
    add(
        "white_balanced",
        "White balance",
        f"{proc['white_balance']}: each channel multiplied by its gain "
        f"({', '.join(f'{g:.3g}' for g in np.ravel(gains))}).",
        np.asarray(balanced, dtype=np.float32),
        "linear",
        "isp",
    )

    from imageform.color import xyz_to_linear_srgb
    from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

    target = np.asarray(xyz_to_linear_srgb(spectrum_to_xyz(colorchecker_reflectances(), "D65")))
    M = np.eye(3)
    cc_wb = patch_means(balanced, truth) if truth is not None else None
    if proc["color_correction"] == "colorchecker" and cc_wb is not None:
        M = fit_color_correction(cc_wb, target)
    corrected = apply_color_correction(balanced, M)
    add(
        "color_corrected",
        "Colour correction",
        "Linear sRGB = camera RGB @ M, M (3x3) fitted by least squares on the ColorChecker "
        "patches against their D65 ground truth.",
        corrected.astype(np.float32),
        "linear",
        "isp",
    )

    out, tf = _encode(corrected, proc["output_space"], proc["transfer"])
    add(
        "output",
        "Output image",
        f"{proc['output_space']} primaries, {tf} transfer function, clipped to [0, 1].",
        out.astype(np.float32),
        "srgb",
        "isp",
    )

    metrics: dict[str, Any] = {
        "exposure_time_s": t_exp,
        "white_balance_gains": [float(g) for g in np.ravel(gains)],
        "color_correction_matrix": M.tolist(),
    }
    patch_xy: dict[str, np.ndarray] = {}
    if truth is not None and cc_before is not None and cc_wb is not None:
        patch_xy = {
            "before_white_balance": xy_of_linear_srgb(cc_before),
            "after_white_balance": xy_of_linear_srgb(cc_wb),
            "after_color_correction": xy_of_linear_srgb(patch_means(corrected, truth)),
        }
        measured = patch_means(_decode_to_linear_srgb(out, proc["output_space"], tf), truth)
        de = delta_e_patches(measured, truth.lab_d65)
        lum = corrected @ np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 / sRGB luminance
        mean, std = patch_stats(lum, truth)
        with np.errstate(divide="ignore", invalid="ignore"):
            snr = 20 * np.log10(mean[:, 0] / std[:, 0])
        metrics |= {
            "delta_e00_per_patch": [float(x) for x in de],
            "delta_e00_mean": float(np.nanmean(de)),
            "delta_e00_max": float(np.nanmax(de)),
            "snr_db_per_patch": [float(x) for x in snr],
        }

    vanishing = None
    grounds = [o for o in scene.objects if o.kind == "ground" and o.params["rail_count"] > 0]
    if grounds:
        vanishing, verr = detect_vanishing(out, rails_truth(grounds[0], cam), seed=seed)
        metrics |= verr
    clock.tick("vanishing", "vanishing_points")

    ptc = _photon_transfer(sensor, seed)
    clock.tick("photon_transfer", "photon_transfer")
    metrics["stage_seconds"] = {k: float(v) for k, v in clock.seconds.items()}
    metrics["total_seconds"] = float(time.perf_counter() - t_start)
    clock.report("done", 1.0)
    return SimulationResult(
        stages=tuple(stages),
        camera=cam,
        image_size=scene.image_size,
        quads=tuple(SceneQuad(o.name, o.corners.copy()) for o in scene.objects),
        colorchecker=truth,
        patch_xy=patch_xy,
        vanishing=vanishing,
        photon_transfer=ptc,
        metrics=metrics,
        scene_name=scene.name,
        config=_jsonable(cfg),
    )


def _photon_transfer(sensor: Any, seed: int) -> Any:
    """EMVA 1288 photon transfer of the green channel at 550 nm, dark to beyond saturation."""
    from imageform.sensor.emva import simulate_photon_transfer
    from imageform.sensor.model import photons_per_pixel

    irradiance = 0.05  # W/m²
    per_s = float(
        photons_per_pixel(irradiance, 550.0, pixel_area=sensor.pixel_area, exposure_time=1.0)
    )
    qe = float(sensor.quantum_efficiency(550.0)[1]) * sensor.fill_factor
    t_sat = sensor.full_well / max(per_s * qe, 1e-300)
    times = t_sat * np.geomspace(1e-3, 1.3, 20)
    return simulate_photon_transfer(
        sensor,
        irradiance=irradiance,
        wavelength_nm=550.0,
        exposure_times=times,
        rng=seed,
        shape=(48, 48),
        channel=1,
    )


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, tuple | list):
        return [_jsonable(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
