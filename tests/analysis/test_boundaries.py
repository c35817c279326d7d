"""Issue 16: the analysis tools refuse malformed input in one line naming the parameter."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.analysis import (
    ChartPatches,
    ColorCorrection,
    MacenkoStains,
    ReinhardStats,
    correction_report,
    macenko_normalize,
    root_polynomial_terms,
    segment_hsv,
    stain_angle,
)
from imageform.analysis.synthetic import synthetic_stain_image
from imageform.errors import DegenerateConfigurationError, InvalidInputError

H_E = np.array([[0.65, 0.70, 0.29], [0.07, 0.99, 0.11]])


@pytest.mark.parametrize(
    "bad",
    [np.array([1 + 1j, 0, 0]), np.array([1, 0, 0], dtype=object), "abc", None, [0.0, 0.0, 0.0]],
)
def test_stain_angle_refuses(bad: object) -> None:
    with pytest.raises(InvalidInputError, match=r"\bu\b") as info:
        stain_angle(bad, [1.0, 0.0, 0.0])
    assert "\n" not in str(info.value)


def test_stain_angle_numpy_scalars_and_value() -> None:
    assert stain_angle(np.array([1, 0, 0], dtype=np.int64), [1.0, 1.0, 0.0]) == pytest.approx(45.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mean": (50.0, 0.0), "std": (1.0, 1.0, 1.0)}, "mean"),
        ({"mean": (50.0, 0.0, 0.0), "std": (1.0, -1.0, 1.0)}, r"std\[1\] >= 0"),
        ({"mean": (50.0, np.nan, 0.0), "std": (1.0, 1.0, 1.0)}, "mean"),
        ({"mean": (50.0, 1j, 0.0), "std": (1.0, 1.0, 1.0)}, "mean"),
    ],
)
def test_reinhard_stats_validated(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        ReinhardStats(n_pixels=10, **kwargs)


def test_reinhard_stats_numpy_integers() -> None:
    s = ReinhardStats((50, 0, 0), (1.0, 1.0, 1.0), np.int64(7))
    assert s.n_pixels == 7 and isinstance(s.n_pixels, int)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("affine", 1, np.eye(3)), "correction method"),
        (("linear", 1, np.full((3, 3), np.nan)), "matrix"),
        (("linear", 1, np.eye(3) + 1j), "matrix"),
        (("linear", 1, np.eye(4)), "matrix"),
        (("root_polynomial", 5, np.eye(3)), "degree"),
    ],
)
def test_color_correction_validated(args: tuple, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        ColorCorrection(*args)


def test_color_correction_apply_refuses_complex() -> None:
    c = ColorCorrection("linear", 1, np.eye(3))
    with pytest.raises(InvalidInputError, match="image"):
        c.apply(np.full((2, 2, 3), 0.5 + 0.1j))


def test_correction_report_type_error() -> None:
    a = np.full((3, 3), 0.5)
    with pytest.raises(TypeError, match="correction"):
        correction_report(a, a, None)  # type: ignore[arg-type]


def test_chart_patches_validated() -> None:
    with pytest.raises(InvalidInputError, match="saturated"):
        ChartPatches(np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(3, bool), np.zeros(2, bool))


@pytest.mark.parametrize("degree", [0, -5, 4, 2.0])
def test_root_polynomial_degree(degree: object) -> None:
    with pytest.raises(InvalidInputError, match="degree"):
        root_polynomial_terms(np.ones(3), degree)  # type: ignore[arg-type]


def test_root_polynomial_fourth_channel() -> None:
    with pytest.raises(InvalidInputError, match="rgb"):
        root_polynomial_terms(np.ones(4), 2)


@pytest.mark.parametrize(
    ("matrix", "maxc", "match"),
    [
        (np.full((2, 3), np.nan), [1.0, 1.0], "stain_matrix"),
        (np.array([[0.0, 0.0, 0.0], [0.07, 0.99, 0.11]]), [1.0, 1.0], "zero"),
        (H_E, [np.nan, 1.0], "max_concentrations"),
        (H_E[:1], [1.0, 1.0], "stain_matrix"),
    ],
)
def test_macenko_stains_validated(matrix: object, maxc: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        MacenkoStains(matrix, np.asarray(maxc))  # type: ignore[arg-type]


def test_macenko_normalize_singular_source() -> None:
    img = synthetic_stain_image((32, 32), rng=0).image
    src = MacenkoStains(np.vstack([H_E[0], H_E[0]]), np.array([1.0, 1.0]))
    with pytest.raises(DegenerateConfigurationError, match="singular"):
        macenko_normalize(img, img, source=src)
    with pytest.raises(TypeError, match="source"):
        macenko_normalize(img, img, source="stains.json")  # type: ignore[arg-type]


@pytest.mark.parametrize("h", [("0", "20"), (1j, 20), (0,), "ab"])
def test_segment_hsv_ranges(h: object) -> None:
    img = np.full((8, 8, 3), 0.5)
    with pytest.raises(InvalidInputError, match=r"\bh\b"):
        segment_hsv(img, h, (0.0, 1.0), (0.0, 1.0))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rows": float("inf")}, "rows"),
        ({"cols": "6"}, "cols"),
        ({"patch": 1j}, "patch"),
        ({"gap": None}, "gap"),
        ({"background": float("inf")}, "background"),
    ],
)
def test_synthetic_chart_scalars(kwargs: dict, match: str) -> None:
    from imageform.analysis import synthetic_chart_image

    with pytest.raises(InvalidInputError, match=match):
        synthetic_chart_image(**kwargs)


def test_synthetic_shapes_bounded() -> None:
    from imageform.analysis import synthetic_stain_image

    with pytest.raises(InvalidInputError, match="shape"):
        synthetic_stain_image((10**9, 10**9))
    assert synthetic_stain_image((np.int64(8), 8)).image.shape == (8, 8, 3)


@pytest.mark.parametrize("name", ["rows", "cols", "margin", "max_std", "saturation"])
def test_chart_patches_scalars(name: str) -> None:
    from imageform.analysis import chart_patches, synthetic_chart_image

    with pytest.raises(InvalidInputError, match=name):
        chart_patches(synthetic_chart_image(patch=6, gap=2), **{name: "1"})


def test_report_functions_name_result() -> None:
    from imageform.report.figures_geometry import top_view_data
    from imageform.report.patches import measure_patches

    for fn in (measure_patches, top_view_data):
        with pytest.raises(TypeError, match="result"):
            fn(None)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (
            lambda: __import__("imageform.analysis.segmentation", fromlist=["x"]).disc(
                float("nan")
            ),
            "radius",
        ),
        (
            lambda: __import__("imageform.analysis.segmentation", fromlist=["x"]).disc(10**9),
            "radius",
        ),
        (lambda: segment_hsv(np.full((4, 4, 3), 0.5), open_radius=10**9), "open_radius"),
        (lambda: synthetic_stain_image((8, 8), noise=-1.0), "noise"),
        (lambda: synthetic_stain_image((8, 8), noise=None), "noise"),
        (
            lambda: ChartPatches(np.zeros((0, 3)), np.zeros((2, 3)), np.zeros(0, bool), None),
            "means",
        ),
    ],
)
def test_fuzz_findings_fixed(call: object, name: str) -> None:
    """Fuzz findings of issue 16: each names its parameter in one line."""
    with pytest.raises(InvalidInputError, match=rf"\b{name}\b") as info:
        call()  # type: ignore[operator]
    assert "\n" not in str(info.value) and len(str(info.value)) <= 200


@pytest.mark.parametrize("alpha", ["abc", None, 1 + 1j, [0.5]])
def test_overlay_mask_alpha_named(alpha: object) -> None:
    from imageform.analysis import overlay_mask

    with pytest.raises(InvalidInputError, match="alpha"):
        overlay_mask(np.full((2, 2, 3), 0.5), np.ones((2, 2), bool), alpha=alpha)  # type: ignore[arg-type]
