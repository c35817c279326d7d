"""imageform.sensor — CFAs and demosaicing, sensor model, noise, shutter, EMVA 1288.

Colour filter arrays and demosaicing, the sensor model, noise, shutter, CCD/CMOS presets,
EMVA 1288 photon transfer and characterisation from frame stacks.
"""

from __future__ import annotations

from imageform import _deprecate
from imageform.sensor.cfa import (
    CFA_PATTERNS,
    cfa_masks,
    cfa_pattern,
    equalize_cfa,
    mosaic,
    superpixel,
)
from imageform.sensor.demosaic import DEMOSAIC_METHODS, demosaic
from imageform.sensor.emva import (
    EmvaResult,
    PhotonTransferData,
    fit_photon_transfer,
    simulate_photon_transfer,
)
from imageform.sensor.emva_frames import (
    EmvaFrames,
    EmvaMeasurement,
    measure_emva,
    simulate_emva_frames,
)
from imageform.sensor.model import SensorModel, photons_per_pixel
from imageform.sensor.noise import (
    QUANTIZATION_NOISE_DN,
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

__all__ = [
    "CCD_VS_CMOS",
    "CFA_PATTERNS",
    "DEMOSAIC_METHODS",
    "QUANTIZATION_NOISE_DN",
    "ComparisonRow",
    "EmvaFrames",
    "EmvaMeasurement",
    "EmvaResult",
    "FixedPattern",
    "PhotonTransferData",
    "SensorModel",
    "ccd_preset",
    "cfa_masks",
    "cfa_pattern",
    "cmos_preset",
    "comparison_table",
    "demosaic",
    "emva_snr",
    "equalize_cfa",
    "fit_photon_transfer",
    "fixed_pattern",
    "measure_emva",
    "mosaic",
    "photons_per_pixel",
    "rolling_shutter_points",
    "rolling_shutter_skew",
    "row_start_times",
    "shutter_capture",
    "simulate_emva_frames",
    "simulate_photon_transfer",
    "superpixel",
    "temporal_noise_dn",
]

__getattr__ = _deprecate.module_getattr(
    "imageform.sensor", {"QUANTISATION_NOISE_DN": ("QUANTIZATION_NOISE_DN", QUANTIZATION_NOISE_DN)}
)
# --- end of branch `sensor` block -------------------------------------------------------------
