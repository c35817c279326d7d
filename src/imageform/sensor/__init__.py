"""imageform.sensor — sensor model, noise, shutter, CCD/CMOS presets, EMVA 1288."""

from __future__ import annotations

# --- sensor model, noise, shutter, presets, EMVA 1288 (branch `sensor`) ---------------------
from imageform.sensor.emva import (
    EmvaResult,
    PhotonTransferData,
    fit_photon_transfer,
    simulate_photon_transfer,
)
from imageform.sensor.model import SensorModel, photons_per_pixel
from imageform.sensor.noise import (
    QUANTISATION_NOISE_DN,
    FixedPattern,
    emva_snr,
    fixed_pattern,
    temporal_noise_dn,
)
from imageform.sensor.presets import (
    CCD_VS_CMOS,
    ComparisonRow,
    ccd_preset,
    cmos_preset,
    comparison_table,
)
from imageform.sensor.shutter import (
    rolling_shutter_points,
    rolling_shutter_skew,
    row_start_times,
    shutter_capture,
)

__all__ = [  # branch `sensor` names; the CFA/demosaic branch adds its own
    "CCD_VS_CMOS",
    "QUANTISATION_NOISE_DN",
    "ComparisonRow",
    "EmvaResult",
    "FixedPattern",
    "PhotonTransferData",
    "SensorModel",
    "ccd_preset",
    "cmos_preset",
    "comparison_table",
    "emva_snr",
    "fit_photon_transfer",
    "fixed_pattern",
    "photons_per_pixel",
    "rolling_shutter_points",
    "rolling_shutter_skew",
    "row_start_times",
    "shutter_capture",
    "simulate_photon_transfer",
    "temporal_noise_dn",
]
# --- end of branch `sensor` block -------------------------------------------------------------
