"""imageform.sensor: colour filter arrays, demosaicing (and, elsewhere, noise, ADC, shutter)."""

# CFA and demosaicing (issue 5a)
from imageform.sensor.cfa import CFA_PATTERNS, cfa_masks, cfa_pattern, mosaic
from imageform.sensor.demosaic import DEMOSAIC_METHODS, demosaic

__all__ = [
    "CFA_PATTERNS",
    "DEMOSAIC_METHODS",
    "cfa_masks",
    "cfa_pattern",
    "demosaic",
    "mosaic",
]
