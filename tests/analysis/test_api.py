"""API surface of imageform.analysis: removing a name is deliberate (``imageform batch``
calls these with these signatures)."""

from __future__ import annotations

import importlib
import inspect

import imageform.analysis as analysis

NAMES = {
    "segment_hsv",
    "HsvSegmentation",
    "overlay_mask",
    "mask_iou",
    "EmptyMaskWarning",
    "reinhard_normalize",
    "reinhard_stats",
    "ReinhardStats",
    "macenko_normalize",
    "macenko_stains",
    "MacenkoStains",
    "optical_density",
    "stain_concentrations",
    "stain_angle",
    "fit_color_correction",
    "ColorCorrection",
    "correction_report",
    "CorrectionReport",
    "chart_patches",
    "ChartPatches",
    "ChartWarning",
    "root_polynomial_terms",
    "CORRECTION_METHODS",
    "synthetic_endoscopy_image",
    "synthetic_stain_image",
    "synthetic_chart_image",
    "synthetic_shading_scene",
}


def test_public_names() -> None:
    assert set(analysis.__all__) >= NAMES
    for name in analysis.__all__:
        assert hasattr(analysis, name)
    for mod in ("segmentation", "reinhard", "macenko", "harmonize", "synthetic"):
        m = importlib.import_module(f"imageform.analysis.{mod}")
        for name in m.__all__:
            assert hasattr(m, name)


def test_signatures_used_by_batch() -> None:
    p = inspect.signature(analysis.segment_hsv).parameters
    assert list(p)[:4] == ["image", "h", "s", "v"]
    for kw in ("opencv_ranges", "open_radius", "close_radius", "min_area"):
        assert p[kw].kind is inspect.Parameter.KEYWORD_ONLY
    assert list(inspect.signature(analysis.reinhard_normalize).parameters)[:2] == [
        "image",
        "target",
    ]
    assert list(inspect.signature(analysis.macenko_normalize).parameters)[:2] == ["image", "target"]
    assert list(inspect.signature(analysis.fit_color_correction).parameters)[:4] == [
        "measured",
        "reference",
        "method",
        "degree",
    ]
    assert list(inspect.signature(analysis.chart_patches).parameters)[:3] == [
        "image",
        "rows",
        "cols",
    ]
    for cls in (analysis.ReinhardStats, analysis.MacenkoStains, analysis.ColorCorrection):
        assert callable(cls.from_json) and callable(cls.to_json)
