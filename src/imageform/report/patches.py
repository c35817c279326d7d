"""ColorChecker patches of a simulation.

CIEDE2000 against the ground truth, the lecture's reading of each difference, and the luminance
signal-to-noise ratio of each patch.

One measurement, :func:`imageform.simulate.truth.measure_colorchecker`, gives these numbers
to the simulator and to the report: a result from :func:`imageform.simulate.simulate`
carries it (``SimulationResult.patches``); for any other result the report measures the
stage images the same way, so every number in a figure can be traced to pixels.
"""

from __future__ import annotations

import numpy as np

from imageform.report._checks import check_result
from imageform.simulate.result import PatchMeasurements, SimulationResult, Stage
from imageform.simulate.truth import measure_colorchecker, patch_windows

__all__ = ["PatchMeasurements", "measure_patches", "patch_windows", "snr_stage"]


def snr_stage(result: SimulationResult) -> Stage:
    """Return the stage the patch SNR is measured on.

    The last three-channel ``"linear"`` stage (the simulator's ``color_corrected``: linear sRGB
    before encoding), else the final stage.
    """
    check_result(result)
    for s in reversed(result.stages):
        if s.kind == "linear" and s.image.ndim == 3 and s.image.shape[-1] == 3:
            return s
    return result.stages[-1]


def _stage_linear(stage: Stage) -> np.ndarray:
    """Return the stage as linear RGB ``(H, W, 3)`` (a grey stage repeated to three channels)."""
    from imageform.color.transfer import srgb_to_linear

    a = np.asarray(stage.image, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.shape[-1] == 1:
        a = np.repeat(a, 3, axis=-1)
    if stage.kind == "srgb":
        a = np.asarray(srgb_to_linear(np.clip(a, 0.0, 1.0)))
    return a[..., :3]


def measure_patches(result: SimulationResult) -> PatchMeasurements | None:
    """Measure the ColorChecker of ``result`` (``None`` without a ColorChecker).

    ``result.patches`` when the simulator measured it; otherwise
    :func:`~imageform.simulate.truth.measure_colorchecker` on the final (``"srgb"``) stage,
    decoded to linear sRGB, for colour, and on :func:`snr_stage` for noise: ΔE00 of each
    patch window's mean against ``lab_d65`` (CIE 142-2001), and
    ``snr_luminance_db = 20 log10(mean(Y) / std(Y))`` of the window's luminance
    (ISO 15739:2013 §6).
    """
    check_result(result)
    cc = result.colorchecker
    if cc is None:
        return None
    if result.patches is not None:
        return result.patches
    s_stage = snr_stage(result)
    return measure_colorchecker(
        _stage_linear(result.stages[-1]), _stage_linear(s_stage), cc, snr_stage=s_stage.name
    )
