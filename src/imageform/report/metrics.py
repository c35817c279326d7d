"""metrics.json: the numbers of a simulation report as plain JSON, each quantity once.

Every key is always present (``null`` where the scene has no such part); units are in the
names (``_s`` seconds, ``_px`` pixels, ``_deg``, ``_db``, ``_K``, ``_m``, ``_dn``,
``_e``); docs/simulate-report.md defines every field, its unit and where it comes from.
Layout (version :data:`METRICS_VERSION`)::

    metrics_version, scene_name, image_size_px {width, height},
    simulation_time_s, step_times_s {step: seconds},
    exposure_time_s, illuminant_cct_K, illuminant_duv, white_balance_gains,
    color_correction_matrix,
    colorchecker       {snr_stage, delta_e00_mean, delta_e00_max,
                        patches [{name, lab_truth, lab_measured, delta_e00, reading,
                                  snr_luminance_db, xy {stage: [x, y]}}]},
    vanishing          {vanishing_point_px, horizon_px, detected_vanishing_point_px,
                        detected_horizon_px, vanishing_point_error_px,
                        horizon_angle_error_deg},
    photon_transfer    {exposure_times_s, photons, mean_dn, var_dn2, dark_mean_dn,
                        dark_var_dn2, fit {system_gain_dn_per_e, read_noise_e, ...}},
    top_view           {camera_center_m, frustum_depth_m, frustum_far_corners_m,
                        optical_axis_end_m, quads_m {name: corners}, world_up, view_right,
                        view_ahead},
    stages             [{index, name, title, description, kind, white_level_dn, shape, dtype,
                         file, raw_file}],
    other_metrics      any other number of SimulationResult.metrics,
    config, notes

A number of :attr:`SimulationResult.metrics <imageform.simulate.SimulationResult.metrics>`
that has its place above (:data:`PLACED_METRICS`) is written there only, never twice.
NaN and infinities are written as ``null`` (strict JSON).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError

__all__ = [
    "METRICS_KEYS",
    "METRICS_VERSION",
    "PLACED_METRICS",
    "SUMMARY_KEYS",
    "to_json_value",
]

#: The layout's version (2: one name per quantity, units in the names).
METRICS_VERSION = 2
#: The top-level keys of metrics.json, in order.
METRICS_KEYS = (
    "metrics_version",
    "scene_name",
    "image_size_px",
    "simulation_time_s",
    "step_times_s",
    "exposure_time_s",
    "illuminant_cct_K",
    "illuminant_duv",
    "white_balance_gains",
    "color_correction_matrix",
    "colorchecker",
    "vanishing",
    "photon_transfer",
    "top_view",
    "stages",
    "other_metrics",
    "config",
    "notes",
)
#: The simulator's numbers that metrics.json gives at the top level (same name).
TOP_LEVEL_METRICS = (
    "simulation_time_s",
    "step_times_s",
    "exposure_time_s",
    "illuminant_cct_K",
    "illuminant_duv",
    "white_balance_gains",
    "color_correction_matrix",
)
#: Every key of ``SimulationResult.metrics`` that has its own place in metrics.json (the
#: per-patch lists become the patches' ``delta_e00`` and ``snr_luminance_db``).
PLACED_METRICS = (
    *TOP_LEVEL_METRICS,
    "delta_e00_per_patch",
    "delta_e00_mean",
    "delta_e00_max",
    "snr_luminance_db_per_patch",
    "vanishing_point_error_px",
    "horizon_angle_error_deg",
)
#: The headline numbers (``ReportPaths.summary``, ``imageform simulate --json``): each is a
#: field of metrics.json with the same name and value.
SUMMARY_KEYS = (
    "simulation_time_s",
    "delta_e00_mean",
    "delta_e00_max",
    "vanishing_point_error_px",
    "system_gain_dn_per_e",
)


def to_json_value(value: Any, where: str = "metrics") -> Any:
    """Return ``value`` as plain JSON types.

    Arrays and tuples become lists, NumPy scalars Python numbers, paths strings, NaN and infinities
    ``None``; anything else is an error naming where it sits.

    Examples
    --------
    >>> to_json_value({"a": np.array([1.5, np.nan]), "b": (np.int64(2), Path("x"))})
    {'a': [1.5, None], 'b': [2, 'x']}
    """
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, np.ndarray):
        return to_json_value(value.tolist(), where)
    if isinstance(value, np.generic):
        return to_json_value(value.item(), where)
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, dict):
        return {str(k): to_json_value(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_json_value(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if type(value).__module__.startswith("torch") and hasattr(value, "detach"):
        return to_json_value(value.detach().cpu().numpy(), where)  # a tensor as its values
    raise InvalidInputError(
        f"expected value as JSON-serialisable numbers, strings, lists or dicts, got "
        f"{type(value).__name__} at {where}"[:200]
    )
