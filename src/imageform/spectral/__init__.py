"""imageform.spectral: spectra, observers, cone fundamentals, illuminants, reflectance sets.

The tables live in ``imageform/spectral/data/*.csv`` with their sources in the headers.
"""

from imageform.spectral.data import (
    CAMERAS,
    COLORCHECKER_PATCHES,
    ILLUMINANT_TABLES,
    LED_SPECTRA,
    TABLES,
    camera_sensitivities,
    cmfs,
    colorchecker_published_xyy,
    colorchecker_reflectances,
    cone_fundamentals,
    illuminant_table,
    led_spectrum,
    load_table,
    luminous_efficiency,
    table_source,
)
from imageform.spectral.illuminants import (
    blackbody_spectrum,
    daylight_spectrum,
    daylight_spectrum_from_xy,
    illuminant,
    planck,
    planckian_cct,
)
from imageform.spectral.integrate import (
    INTEGRATION_METHODS,
    KM_PHOTOPIC,
    KM_SCOTOPIC,
    integration_weights,
    luminance,
    observer_functions,
    spectrum_to_camera_rgb,
    spectrum_to_lms,
    spectrum_to_xyz,
)
from imageform.spectral.spectrum import EXTRAPOLATION_METHODS, INTERPOLATION_METHODS, Spectrum

__all__ = [
    "CAMERAS",
    "COLORCHECKER_PATCHES",
    "EXTRAPOLATION_METHODS",
    "ILLUMINANT_TABLES",
    "INTEGRATION_METHODS",
    "INTERPOLATION_METHODS",
    "KM_PHOTOPIC",
    "KM_SCOTOPIC",
    "LED_SPECTRA",
    "TABLES",
    "Spectrum",
    "blackbody_spectrum",
    "camera_sensitivities",
    "cmfs",
    "colorchecker_published_xyy",
    "colorchecker_reflectances",
    "cone_fundamentals",
    "daylight_spectrum",
    "daylight_spectrum_from_xy",
    "illuminant",
    "illuminant_table",
    "integration_weights",
    "led_spectrum",
    "load_table",
    "luminance",
    "luminous_efficiency",
    "observer_functions",
    "planck",
    "planckian_cct",
    "spectrum_to_camera_rgb",
    "spectrum_to_lms",
    "spectrum_to_xyz",
    "table_source",
]
