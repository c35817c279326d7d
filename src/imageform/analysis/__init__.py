"""imageform.analysis: applied colour analysis for biomedical images.

- HSV tissue segmentation (the lecture's endoscopy case study): :func:`segment_hsv`,
  :func:`overlay_mask`, :func:`mask_iou`.
- Stain normalisation for pathology: :func:`reinhard_normalize` (CIELAB statistics),
  :func:`macenko_normalize` (optical density, stain vectors by SVD); the tissue without
  glass, pen ink, black ink and dark folds, :func:`tissue_mask`.
- Colour harmonisation between devices from a chart: :func:`fit_color_correction`,
  :func:`chart_patches`, :func:`correction_report`; a ColorChecker found in an uncropped
  photograph by :func:`detect_colorchecker` and measured by :func:`measure_chart_patches`;
  :func:`sample_chart` takes either (cropped or photographed) and is how the fit,
  :func:`correction_report` and :func:`chart_white_balance` accept chart photographs.
- Sharpness as imaging labs measure it: the ISO 12233 slanted-edge e-SFR
  (:func:`slanted_edge_sfr`: MTF per channel, MTF50, MTF10) and the edges of a slanted-edge
  chart found by themselves (:func:`find_slanted_edges`), in :mod:`imageform.analysis.sfr`.
- Shading (flat-field, vignetting) correction: :func:`correct_flatfield` with a measured
  flat field, :func:`estimate_flatfield` (BaSiC, from a stack of tiles or frames),
  :func:`estimate_vignetting` (a robust radial fit to one frame).
- A camera's spectral sensitivities from its raw responses to a chart
  (:func:`estimate_camera_sensitivities`, in :mod:`imageform.analysis.sensitivity`).
- Labelled synthetic images to test them (:mod:`imageform.analysis.synthetic`).

Every tool accepts NumPy arrays (uint8/uint16/floats) and Dask arrays (lazy, chunk-wise,
with exact global statistics).
"""

from imageform.analysis._stain_methods import STAIN_NORMALIZATION_METHODS
from imageform.analysis.chart_detect import (
    ChartDetection,
    ChartNotFoundError,
    ChartPhoto,
    detect_colorchecker,
    measure_chart_patches,
    synthetic_chart_photo,
)
from imageform.analysis.chart_input import (
    CHART_LAYOUTS,
    COLORCHECKER_NEUTRALS,
    ChartSample,
    chart_white_balance,
    sample_chart,
)
from imageform.analysis.flatfield import (
    FlatfieldEstimate,
    correct_flatfield,
    estimate_flatfield,
    estimate_vignetting,
)
from imageform.analysis.harmonize import (
    CORRECTION_METHODS,
    ChartPatches,
    ChartWarning,
    ColorCorrection,
    CorrectionReport,
    chart_patches,
    correction_report,
    fit_color_correction,
    root_polynomial_terms,
)
from imageform.analysis.macenko import (
    STAIN_VECTOR_METHODS,
    BackgroundEstimate,
    MacenkoStains,
    background_intensity,
    estimate_background,
    macenko_normalize,
    macenko_stains,
    optical_density,
    stain_angle,
    stain_concentrations,
    vahadane_stains,
)
from imageform.analysis.reinhard import ReinhardStats, reinhard_normalize, reinhard_stats
from imageform.analysis.segmentation import (
    EmptyMaskWarning,
    HsvSegmentation,
    mask_iou,
    overlay_mask,
    segment_hsv,
)
from imageform.analysis.sensitivity import (
    SensitivityEstimate,
    estimate_camera_sensitivities,
    relative_qe,
)
from imageform.analysis.sfr import (
    SFR_LUMINANCE_WEIGHTS,
    SFRResult,
    SlantedEdgeROI,
    find_slanted_edges,
    fit_gaussian_sigma,
    mtf_crossing,
    render_sfr_chart,
    render_slanted_edge,
    slanted_edge_sfr,
)
from imageform.analysis.synthetic import (
    COLORCHECKER_SRGB8,
    LabeledImage,
    StainMixture,
    synthetic_chart_image,
    synthetic_endoscopy_image,
    synthetic_he_tile,
    synthetic_shading_scene,
    synthetic_stain_image,
)
from imageform.analysis.tissue import TISSUE_MASK_RULES, tissue_mask

__all__ = [
    "CHART_LAYOUTS",
    "COLORCHECKER_NEUTRALS",
    "COLORCHECKER_SRGB8",
    "CORRECTION_METHODS",
    "SFR_LUMINANCE_WEIGHTS",
    "STAIN_NORMALIZATION_METHODS",
    "STAIN_VECTOR_METHODS",
    "TISSUE_MASK_RULES",
    "BackgroundEstimate",
    "ChartDetection",
    "ChartNotFoundError",
    "ChartPatches",
    "ChartPhoto",
    "ChartSample",
    "ChartWarning",
    "ColorCorrection",
    "CorrectionReport",
    "EmptyMaskWarning",
    "FlatfieldEstimate",
    "HsvSegmentation",
    "LabeledImage",
    "MacenkoStains",
    "ReinhardStats",
    "SFRResult",
    "SensitivityEstimate",
    "SlantedEdgeROI",
    "StainMixture",
    "background_intensity",
    "chart_patches",
    "chart_white_balance",
    "correct_flatfield",
    "correction_report",
    "detect_colorchecker",
    "estimate_background",
    "estimate_camera_sensitivities",
    "estimate_flatfield",
    "estimate_vignetting",
    "find_slanted_edges",
    "fit_color_correction",
    "fit_gaussian_sigma",
    "macenko_normalize",
    "macenko_stains",
    "mask_iou",
    "measure_chart_patches",
    "mtf_crossing",
    "optical_density",
    "overlay_mask",
    "reinhard_normalize",
    "reinhard_stats",
    "relative_qe",
    "render_sfr_chart",
    "render_slanted_edge",
    "root_polynomial_terms",
    "sample_chart",
    "segment_hsv",
    "slanted_edge_sfr",
    "stain_angle",
    "stain_concentrations",
    "synthetic_chart_image",
    "synthetic_chart_photo",
    "synthetic_endoscopy_image",
    "synthetic_he_tile",
    "synthetic_shading_scene",
    "synthetic_stain_image",
    "tissue_mask",
    "vahadane_stains",
]
