"""The camera pipeline: the stages of :mod:`.stages` composed, every stage kept.

See :func:`simulate`.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from imageform._validate import as_bool
from imageform.errors import ImageformWarning, InvalidInputError
from imageform.simulate._rng import RNGLike, random_source
from imageform.simulate.config import GroundConfig
from imageform.simulate.render import render_scene
from imageform.simulate.result import (
    ColorCheckerTruth,
    PatchMeasurements,
    SceneQuad,
    SimulationResult,
    Stage,
    StageKind,
    VanishingTruth,
)
from imageform.simulate.scene import Scene, SceneObject, _at_key
from imageform.simulate.stages import (
    ColorCorrected,
    WhiteBalanced,
    apply_lens,
    balance_white,
    capture_raw,
    correct_color,
    correct_lens_shading,
    decode_output,
    demosaic_raw,
    encode_output,
    exposure_time,
    measure_photon_transfer,
    measured_color_matrix,
    measured_optics_blur,
    normalize_raw,
)
from imageform.simulate.truth import (
    colorchecker_truth,
    detect_vanishing,
    light_cct,
    measure_colorchecker,
    patch_means,
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


#: Each stage: (progress step, kind, title, description with the run's numbers as fields).
_STAGES: dict[str, tuple[str, StageKind, str, str]] = {
    "rendered": (
        "render",
        "linear",
        "Rendered scene",
        "Ray casting, {S}x{S} rays per pixel: electrons/s = FF A sum rho E QE lambda/(hc) "
        "/(4N^2), times cos^4(theta), through the lens distortion.",
    ),
    "optics": (
        "optics",
        "linear",
        "Lens: chromatic aberration and defocus",
        "Each channel scaled by its magnification (lateral colour); each pixel blurred by the "
        "disc of its circle of confusion c = (f/N)|d - s|/d f/(s - f).",
    ),
    "raw": (
        "sensor",
        "raw",
        "Raw sensor image",
        "Exposure {t_ms:.3g} ms: photo-electrons with shot, dark and read noise and fixed "
        "pattern, {cfa} mosaic, {bits}-bit ADC (K = {gain:.3g} DN/e-).",
    ),
    "demosaiced": (
        "demosaic",
        "linear",
        "Demosaiced camera RGB",
        "Black level and mean dark signal subtracted, scaled to [0, 1], {method} demosaicing.",
    ),
    "shading_corrected": (
        "isp",
        "linear",
        "Lens-shading correction",
        "Divided by the lens's cos^4 vignetting map (a flat-field correction).",
    ),
    "white_balanced": (
        "isp",
        "linear",
        "White balance",
        "{method}: each channel multiplied by its gain ({gains}).",
    ),
    "color_corrected": (
        "isp",
        "linear",
        "Colour correction",
        "Linear sRGB = camera RGB @ M, M (3x3) fitted by least squares on the ColorChecker "
        "patches against their D65 ground truth.",
    ),
    "output": (
        "isp",
        "srgb",
        "Output image",
        "{space} primaries, {tf} transfer function, clipped to [0, 1].",
    ),
}


class _Run:
    """The stages of a run as they are made, the time of each step, and the progress."""

    def __init__(self, progress: Progress | None) -> None:
        self.progress = progress
        self.done = 0.0
        self.seconds: dict[str, float] = {}
        self.stages: list[Stage] = []
        self.t0 = time.perf_counter()

    def report(self, step: str, fraction: float) -> None:
        if self.progress is not None:
            self.progress(step, float(min(1.0, fraction)))

    def tick(self, step: str, name: str) -> float:
        """End the step ``name`` (progress group ``step``): its time since the last tick."""
        dt = time.perf_counter() - self.t0
        self.seconds[name] = self.seconds.get(name, 0.0) + dt
        self.done = min(1.0, self.done + _WEIGHTS.get(step, 0.0))
        self.report(step, self.done)
        self.t0 = time.perf_counter()
        return dt

    def stage(
        self, name: str, image: np.ndarray, white_level: float | None = None, **fields: Any
    ) -> None:
        """Keep stage ``name`` (float images as float32) and end its step."""
        step, kind, title, text = _STAGES[name]
        kept = image if kind == "raw" else np.asarray(image, dtype=np.float32)
        dt = self.tick(step, name)
        self.stages.append(Stage(name, title, text.format(**fields), kept, kind, white_level, dt))


def _chart(scene: Scene) -> SceneObject | None:
    """Return the scene's first ColorChecker, checked against the options that need one."""
    proc = scene.config.processing
    checkers = [o for o in scene.objects if o.kind == "colorchecker"]
    if not checkers and "colorchecker" in (proc.color_correction, proc.white_balance):
        key = "color_correction" if proc.color_correction == "colorchecker" else "white_balance"
        with _at_key(scene, ("processing", key)):
            raise InvalidInputError(
                "'colorchecker' needs a colorchecker object in the scene; add one or set "
                f"{'none' if key == 'color_correction' else 'gray_world'!r}"
            )
    return checkers[0] if checkers else None


def _white_kept(
    wb: WhiteBalanced, cc: ColorCorrected, img: np.ndarray
) -> tuple[WhiteBalanced, ColorCorrected, bool]:
    r"""Fold the fitted matrix's white shift into the white balance (the same output).

    A matrix :math:`M` fitted freely on the chart also corrects what the white balance
    left (grey world is biased by the scene's colours), so it does not keep white:
    :math:`\mathbf 1^T M \not\propto \mathbf 1^T`. With :math:`\mathbf u = \mathbf 1^T
    M^{-1}` (the balanced camera RGB that :math:`M` renders white), the gains
    :math:`\mathbf g' = \mathbf g / \mathbf u` and the matrix :math:`M' =
    \mathrm{diag}(\mathbf u)\, M` give the same output, :math:`(\mathbf c \odot \mathbf
    g') M' = (\mathbf c \odot \mathbf g) M`, and :math:`\mathbf 1^T M' = \mathbf 1^T`:
    the white balance alone decides what is grey, as in a camera, and a raw developer given
    the DNG's AsShotNeutral (:math:`1/\mathbf g'`) and ColorMatrix renders what the
    simulator does. The green gain stays 1 (the overall scale goes into :math:`M'`).
    Nothing changes when :math:`M` is the identity or :math:`\mathbf u` is not positive.
    """
    M = np.asarray(cc.matrix, dtype=np.float64)
    if np.allclose(M, np.eye(3)):
        return wb, cc, False
    try:
        u = np.ones(3) @ np.linalg.inv(M)
    except np.linalg.LinAlgError:
        return wb, cc, False
    if not (np.all(np.isfinite(u)) and np.all(u > 0)):
        return wb, cc, False
    u = u / u[1]  # green's gain kept
    gains = np.ravel(np.asarray(wb.gains, dtype=np.float64)) / u
    M2 = np.diag(u) @ M
    balanced = img * gains
    return WhiteBalanced(balanced, gains), ColorCorrected(np.asarray(cc.image), M2), True


def simulate(
    scene: Scene,
    *,
    progress: Progress | None = None,
    rng: RNGLike = None,
    seed: int | None = None,
    measure: bool = True,
) -> SimulationResult:
    """Run a scene through the whole chain and keep every stage.

    Stages, in order: ``rendered`` (ray-cast mean photo-electrons per second, camera RGB,
    with distortion and cos⁴ vignetting), ``optics`` (lateral chromatic aberration and
    depth-dependent defocus), ``raw`` (photons to electrons, shot/dark/read noise, FPN,
    CFA mosaic, ADC), ``demosaiced``, ``shading_corrected`` (the vignetting map divided
    out, if enabled), ``white_balanced``, ``color_corrected`` (3×3 matrix fitted on the
    ColorChecker, linear sRGB) and ``output`` (encoded, kind ``"srgb"``); each is a function
    of :mod:`imageform.simulate.stages`.

    Parameters
    ----------
    scene : Scene
        From :func:`load_scene` or :func:`default_scene`.
    progress : callable, optional
        ``progress(step_name, fraction_done)``: called as the run proceeds, with the
        fraction of the whole run done (non-decreasing, 1.0 at the end).
    rng : int, numpy.random.Generator or None
        The random numbers of the sensor noise, the vanishing-point RANSAC and the
        photon-transfer measurement (SPEC 7). An int seed ``s`` starts each of them from
        ``default_rng(s)`` (the same pixels as the former ``seed=s``); a Generator is drawn
        from in turn; None: fresh entropy (a different run each time).
    seed : int, optional
        Deprecated alias of ``rng`` (an int); removed in the next release.
    measure : bool
        Measure the result (the ColorChecker patches, the vanishing points and the horizon,
        the sensor's photon transfer). False renders the stages only: the frames of a video
        along a trajectory, where the measurements would cost about as much as the
        rendering; ``patches``, ``vanishing`` and ``photon_transfer`` are then None.

    Returns
    -------
    SimulationResult
        ``patches`` holds the ColorChecker measurement; ``metrics`` the numbers, each once,
        with its unit in its name (``docs/simulate-report.md`` lists them):
        ``delta_e00_per_patch``, ``delta_e00_mean``, ``delta_e00_max`` (output vs the D65
        ground truth), ``snr_luminance_db_per_patch`` (luminance of the colour-corrected
        stage), ``vanishing_point_error_px``, ``horizon_angle_error_deg``,
        ``illuminant_cct_K``, ``illuminant_duv``, ``exposure_time_s``,
        ``white_balance_gains``, ``color_correction_matrix``, ``step_times_s`` and
        ``simulation_time_s`` (the run's wall time).

    Warns
    -----
    ImageformWarning
        A ColorChecker patch without noise (``sensor.noise = false``, or a flat patch):
        its SNR is infinite, ``inf`` in ``snr_luminance_db_per_patch`` and ``null`` in
        ``metrics.json``.

    Examples
    --------
    >>> from imageform.simulate import default_scene
    >>> res = simulate(default_scene().resized(160), rng=0)
    >>> res.stages[-1].kind, res.stages[-1].image.shape
    ('srgb', (90, 160, 3))
    """
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"expected a Scene (load_scene), got {type(scene).__name__}")
    measure = as_bool(measure, "measure")  # NumPy's bools too
    if progress is not None and not callable(progress):
        raise TypeError(
            f"expected progress as a callable progress(step, fraction) or None, got "
            f"{type(progress).__name__}"
        )
    source = random_source(rng, seed, "simulate")
    t_start = time.perf_counter()
    cfg, sensor, proc = scene.config, scene.sensor, scene.config.processing
    chart = _chart(scene)
    run = _Run(progress)

    w8 = _WEIGHTS["render"]
    with _at_key(scene, ("render",)):
        r = render_scene(scene, progress=lambda f: run.report("render", f * w8))
    run.stage("rendered", r.rate, S=cfg.render.supersampling)
    with _at_key(scene, ("lens",)):
        optical = apply_lens(r, scene.camera, cfg.lens, cfg.camera.focal_length_mm)
    measured = scene.measured
    if measured is not None and measured.optics is not None:
        with _at_key(scene, ("lens",)):
            optical = measured_optics_blur(
                optical,
                measured.optics,
                pixel_pitch=sensor.pixel_pitch,
                supersampling=cfg.render.supersampling,
            )
    run.stage("optics", optical)
    with _at_key(scene, ("sensor", "exposure_time_s")):
        t_exp = exposure_time(optical, cfg.sensor, sensor)
    with _at_key(scene, ("sensor",)):
        raw = capture_raw(optical * t_exp, sensor, cfg.sensor, t_exp, source.for_step())
    run.stage(
        "raw",
        raw,
        float(sensor.max_dn),
        t_ms=t_exp * 1e3,
        cfa=cfg.sensor.cfa,
        bits=sensor.bit_depth,
        gain=sensor.system_gain,
    )
    with _at_key(scene, ("processing", "demosaic")):
        img = demosaic_raw(normalize_raw(raw, sensor, t_exp), cfg.sensor.cfa, proc.demosaic)
    run.stage("demosaiced", img, method=proc.demosaic)
    if proc.lens_shading_correction and cfg.lens.vignetting != "none":
        img = correct_lens_shading(img, r.falloff)
        run.stage("shading_corrected", img)
    truth = colorchecker_truth(chart, scene.camera) if chart is not None else None
    cc_before = patch_means(img, truth) if truth is not None else None
    color = measured.color if measured is not None else None
    wb_method = proc.white_balance
    if color is not None and color.white_balance is not None:
        fixed = np.asarray(color.white_balance, dtype=np.float64)
        wb, wb_method = WhiteBalanced(img * fixed, fixed), "camera file"
    else:
        with _at_key(scene, ("processing", "white_balance")):
            wb = balance_white(img, proc.white_balance, cc_before)
    cc_wb = patch_means(wb.image, truth) if truth is not None else None
    matrix = None
    if color is not None:
        matrix = measured_color_matrix(color)
    if matrix is not None:
        cc = ColorCorrected(wb.image @ matrix, matrix)
    else:
        with _at_key(scene, ("processing", "color_correction")):
            cc = correct_color(wb.image, proc.color_correction, cc_wb)
        folded = False
        if wb_method != "camera file":  # a camera file's fixed gains stay as they are
            wb, cc, folded = _white_kept(wb, cc, img)
        if folded:
            wb_method = f"{wb_method}, refined by the chart's matrix (which keeps white)"
            cc_wb = patch_means(wb.image, truth) if truth is not None else None
    gains = ", ".join(f"{g:.3g}" for g in np.ravel(wb.gains))
    run.stage("white_balanced", wb.image, method=wb_method, gains=gains)
    run.stage("color_corrected", cc.image)
    with _at_key(scene, ("processing", "output_space")):
        out = encode_output(cc.image, proc.output_space, proc.transfer)
    run.stage("output", out.image, space=proc.output_space, tf=out.transfer)

    cct, duv = light_cct(scene.illuminant)
    metrics: dict[str, Any] = {
        "exposure_time_s": t_exp,
        "illuminant_cct_K": cct,
        "illuminant_duv": duv,
        "white_balance_gains": [float(g) for g in np.ravel(wb.gains)],
        "color_correction_matrix": cc.matrix.tolist(),
    }
    patches, patch_xy = None, {}
    vanishing, ptc = None, None
    if measure and truth is not None and cc_before is not None and cc_wb is not None:
        lin_out = decode_output(out, proc.output_space)
        patches = measure_colorchecker(lin_out, cc.image, truth, snr_stage="color_corrected")
        patch_xy = _patch_chromaticities(truth, cc_before, cc_wb, cc.image)
        metrics |= _patch_metrics(patches)
        flat = np.flatnonzero(np.isposinf(patches.snr_luminance_db))
        if flat.size:
            warnings.warn(
                f"simulate: {flat.size} ColorChecker patch(es) have σ = 0 (no noise, or a window "
                "of one pixel): their "
                "SNR is infinite (null in metrics.json); set sensor.noise = true for a "
                "measured SNR",
                ImageformWarning,
                stacklevel=2,
            )
    run.tick("isp", "colorchecker")
    if measure:
        vanishing, errors = _vanishing(scene, out.image, source.int_seed())
        metrics |= errors
        run.tick("vanishing", "vanishing_points")
        ptc = measure_photon_transfer(sensor, source.for_step())
        run.tick("photon_transfer", "photon_transfer")
    metrics["step_times_s"] = {k: float(v) for k, v in run.seconds.items()}
    metrics["simulation_time_s"] = float(time.perf_counter() - t_start)
    run.report("done", 1.0)
    return SimulationResult(
        stages=tuple(run.stages),
        camera=scene.camera,
        image_size=scene.image_size,
        quads=tuple(SceneQuad(o.name, o.corners.copy()) for o in scene.objects),
        colorchecker=truth,
        patch_xy=patch_xy,
        vanishing=vanishing,
        photon_transfer=ptc,
        metrics=metrics,
        scene_name=scene.name,
        config=_jsonable(cfg.to_dict()),
        patches=patches,
    )


def _patch_chromaticities(
    truth: ColorCheckerTruth, before: np.ndarray, balanced: np.ndarray, corrected: np.ndarray
) -> dict[str, np.ndarray]:
    """Chromaticity xy of the patch means (read as linear sRGB) at three steps."""
    return {
        "before_white_balance": xy_of_linear_srgb(before),
        "after_white_balance": xy_of_linear_srgb(balanced),
        "after_color_correction": xy_of_linear_srgb(patch_means(corrected, truth)),
    }


def _vanishing(
    scene: Scene, output: np.ndarray, seed: int
) -> tuple[VanishingTruth | None, dict[str, Any]]:
    """Return the first railed ground's true and detected vanishing point and horizon, and errors.

    Nothing without rails.
    """
    grounds = [
        o for o in scene.objects if isinstance(o.config, GroundConfig) and o.config.rail_count
    ]
    if not grounds:
        return None, {}
    return detect_vanishing(
        output, rails_truth(grounds[0], scene.camera), camera=scene.camera, rng=seed
    )


def _patch_metrics(m: PatchMeasurements) -> dict[str, Any]:
    """Return the ColorChecker's numbers of ``metrics`` (the same arrays as ``m``)."""
    return {
        "delta_e00_per_patch": [float(x) for x in m.delta_e00],
        "delta_e00_mean": m.delta_e00_mean,
        "delta_e00_max": m.delta_e00_max,
        "snr_luminance_db_per_patch": [float(x) for x in m.snr_luminance_db],
    }


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, tuple | list):
        return [_jsonable(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
