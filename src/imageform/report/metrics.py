"""metrics.json: the numbers of a simulation report as plain JSON.

Layout (every key always present; ``null`` where the scene has no such part)::

    scene_name, image_size {width, height},
    summary {total_seconds, mean_delta_e00, max_delta_e00, vanishing_point_error_px,
             system_gain_dn_per_e},
    stages [{index, name, title, description, kind, seconds, white_level, shape, dtype,
             file, raw_file}],
    metrics            the pipeline's own numbers (SimulationResult.metrics), unchanged,
    colorchecker       {snr_stage, patches [{name, lab_truth, lab_measured, delta_e00, reading,
                        snr_db, xy {stage: [x, y]}}]},
    patch_xy           {stage: [[x, y] * 24]},
    top_view           {camera_center, frustum_depth_m, frustum_far_corners, optical_axis_end,
                        quads {name: corners}},
    vanishing          {vanishing_point, horizon, detected_vanishing_point, detected_horizon,
                        error_px},
    photon_transfer    {exposure_times_s, photons, mean_dn, var_dn2, dark_mean_dn,
                        dark_var_dn2, fit {system_gain_dn_per_e, read_noise_e, ...}},
    config, notes

NaN and infinities are written as ``null`` (strict JSON).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["METRICS_KEYS", "SUMMARY_KEYS", "to_json_value"]

#: The top-level keys of metrics.json.
METRICS_KEYS = (
    "scene_name",
    "image_size",
    "summary",
    "stages",
    "metrics",
    "colorchecker",
    "patch_xy",
    "top_view",
    "vanishing",
    "photon_transfer",
    "config",
    "notes",
)
#: The keys of metrics.json's ``summary``.
SUMMARY_KEYS = (
    "total_seconds",
    "mean_delta_e00",
    "max_delta_e00",
    "vanishing_point_error_px",
    "system_gain_dn_per_e",
)


def to_json_value(value: Any, where: str = "metrics") -> Any:
    """``value`` as plain JSON types: arrays and tuples become lists, NumPy scalars Python
    numbers, paths strings, NaN and infinities ``None``; anything else is an error naming
    where it sits.

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
    raise InvalidInputError(
        f"expected JSON-serialisable numbers, strings, lists or dicts at {where}, "
        f"got {type(value).__name__}"
    )
