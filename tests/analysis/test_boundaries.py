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


# --- issue 16, second pass: every case asserts the error type and the parameter's name ---


def _one_line(info: pytest.ExceptionInfo[BaseException]) -> str:
    msg = str(info.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    return msg


@pytest.mark.parametrize(
    "h", [np.array([0, 20], dtype=object), np.array(["0", "20"]), np.array([0 + 1j, 20])]
)
def test_segment_hsv_ranges_object_string_complex_arrays(h: object) -> None:
    with pytest.raises(InvalidInputError, match=r"\bh\b") as info:
        segment_hsv(np.full((8, 8, 3), 0.5), h, (0.0, 1.0), (0.0, 1.0))  # type: ignore[arg-type]
    _one_line(info)


def test_zero_length_stain_vector_never_gives_nan() -> None:
    """A stain vector of length 0 has no direction: refused by name everywhere it can enter
    (issue 16: it gave NaN angles and NaN images)."""
    from imageform.analysis import stain_concentrations, synthetic_stain_image

    zero = np.array([[0.0, 0.0, 0.0], H_E[1]])
    with pytest.raises(InvalidInputError, match="stains"):
        synthetic_stain_image((8, 8), stains=zero)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="stain_matrix"):
        stain_concentrations(np.full((4, 4, 3), 0.5), zero)
    with pytest.raises(InvalidInputError, match=r"\bv\b"):
        stain_angle(H_E[0], [0.0, 0.0, 0.0])
    with pytest.raises(InvalidInputError, match="stain_matrix"):
        MacenkoStains(zero, np.array([1.0, 1.0]))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"i0": (np.nan, 1.0, 1.0)}, "i0"),
        ({"i0": (1 + 1j, 1.0, 1.0)}, "i0"),
        ({"i0": (1.0, 1.0)}, "i0"),
        ({"n_total": float("nan")}, "n_total"),
        ({"n_total": float("inf")}, "n_total"),
        ({"base": "2"}, "base"),
        ({"method": "svd"}, "method"),
    ],
)
def test_macenko_stains_fields_validated(kwargs: dict, name: str) -> None:
    with pytest.raises(InvalidInputError, match=name) as info:
        MacenkoStains(H_E, np.array([1.5, 1.2]), **kwargs)
    _one_line(info)


def test_macenko_stains_fields_normalised() -> None:
    s = MacenkoStains(H_E, np.array([1.5, 1.2]), np.int64(3), np.array([0.9, 0.9, 0.9]))
    assert s.i0 == (0.9, 0.9, 0.9) and s.n_pixels == 3 and isinstance(s.n_pixels, int)


@pytest.mark.parametrize(
    "source",
    [
        {"stain_matrix": H_E, "max_concentrations": [1.0, 1.0]},
        np.full((2, 3), np.nan),
        H_E,
    ],
)
def test_macenko_normalize_source_not_stains(source: object) -> None:
    """NaN or misshaped stains cannot become a MacenkoStains (validated in __post_init__),
    and anything else given as ``source`` is a TypeError naming it: never a LinAlgError."""
    img = synthetic_stain_image((32, 32), rng=0).image
    with pytest.raises(TypeError, match="source"):
        macenko_normalize(img, img, source=source)  # type: ignore[arg-type]
    for matrix in (np.full((2, 3), np.nan), H_E[:, :2], np.vstack([H_E, H_E])):
        with pytest.raises(InvalidInputError, match="stain_matrix"):
            MacenkoStains(matrix, np.array([1.0, 1.0]))


@pytest.mark.parametrize(
    "target", [np.ones((4, 4, 3), dtype=bool), np.zeros((4, 4, 3), dtype=np.int64), "nofile.json"]
)
def test_normalize_targets_reported_as_target(target: object) -> None:
    """The target image is checked under its own name, not as ``image`` (issue 16)."""
    from imageform.analysis import reinhard_normalize

    img = synthetic_stain_image((32, 32), rng=0).image
    for fn in (reinhard_normalize, macenko_normalize):
        with pytest.raises(InvalidInputError, match="target") as info:
            fn(img, target)
        assert "image" not in _one_line(info).split("target")[0]
    with pytest.raises(TypeError, match="target"):
        reinhard_normalize(img, None)


@pytest.mark.parametrize("bad", [float("inf"), 1e308, float("nan"), 10**30])
@pytest.mark.parametrize("name", ["rows", "cols"])
def test_chart_patches_counts_inf_huge(name: str, bad: object) -> None:
    from imageform.analysis import chart_patches, synthetic_chart_image

    with pytest.raises(InvalidInputError, match=name) as info:
        chart_patches(synthetic_chart_image(patch=6, gap=2), **{name: bad})
    _one_line(info)


@pytest.mark.parametrize("name", ["margin", "max_std"])
def test_chart_patches_no_usable_patch_names_the_knobs(name: str) -> None:
    from imageform.analysis import chart_patches, synthetic_chart_image

    with pytest.raises(InvalidInputError, match=name) as info:
        chart_patches(synthetic_chart_image(patch=6, gap=2), **{name: 0.0})
    _one_line(info)


def test_correction_report_and_chart_patches_validated() -> None:
    from imageform.analysis import CorrectionReport

    ok = np.array([True, True])
    for bad, name in (
        (np.array([np.nan, 1.0]), "delta_e_before"),
        (np.array([1 + 1j, 1.0]), "delta_e_before"),
        (np.array([-1.0, 1.0]), "delta_e_before"),
        (np.array([1.0]), "delta_e_before"),
    ):
        with pytest.raises(InvalidInputError, match=name):
            CorrectionReport(bad, np.array([1.0, 2.0]), ok)
    with pytest.raises(InvalidInputError, match="valid"):
        CorrectionReport(np.ones(2), np.ones(2), np.ones(2))
    # NaN is allowed where a patch is not valid; a summary needs one valid patch
    r = CorrectionReport(np.array([np.nan, 2.0]), np.array([np.nan, 1.0]), np.array([False, True]))
    assert r.summary()["mean_after"] == 1.0
    with pytest.raises(DegenerateConfigurationError, match="valid"):
        CorrectionReport(np.ones(1), np.ones(1), np.zeros(1, bool)).summary()
    with pytest.raises(InvalidInputError, match="std"):
        ChartPatches(
            np.zeros((2, 3)), np.full((2, 3), np.inf), np.zeros(2, bool), np.zeros(2, bool)
        )
    with pytest.raises(InvalidInputError, match="std"):
        ChartPatches(np.zeros((2, 3)), -np.ones((2, 3)), np.zeros(2, bool), np.zeros(2, bool))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (
            lambda: __import__("imageform.analysis").analysis.background_intensity(
                np.full((4, 4, 3), 0.5), percentile=None
            ),
            "percentile",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.background_intensity(
                np.full((4, 4, 3), 0.5), min_background=1j
            ),
            "min_background",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.vahadane_stains(
                np.full((4, 4, 3), 0.5), lam=[0.1]
            ),
            "lam",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.vahadane_stains(
                np.full((4, 4, 3), 0.5), min_pixels=float("inf")
            ),
            "min_pixels",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.mtf_crossing(
                [0.0, 1j], [1.0, 0.0], 0.5
            ),
            "frequency",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.mtf_crossing(
                [0.0, 1.0], ["1", "0"], 0.5
            ),
            "mtf",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.mtf_crossing(
                [0.0, np.nan], [1.0, 0.0], 0.5
            ),
            "frequency",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.mtf_crossing(
                [0.0, 1.0], [1.0, 0.0], -1.0
            ),
            "level",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.find_slanted_edges(np.zeros((0, 64))),
            "image",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.find_slanted_edges(
                np.full((64, 64), 0.8), min_angle=1e308
            ),
            "min_angle",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.find_slanted_edges(
                np.full((64, 64, 3), 0.8), weights="abc"
            ),
            "weights",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.slanted_edge_sfr(np.zeros((64, 48))),
            "image",
        ),
        (
            lambda: __import__("imageform.analysis").analysis.slanted_edge_sfr(
                np.zeros((64, 48, 3)), weights=[1j, 0, 0]
            ),
            "weights",
        ),
    ],
)
def test_second_pass_fuzz_findings(call: object, name: str) -> None:
    from imageform.errors import ImageformError

    with pytest.raises((ImageformError, TypeError), match=rf"\b{name}\b") as info:
        call()  # type: ignore[operator]
    _one_line(info)


def test_long_min_pixels_message_stays_one_short_line() -> None:
    from imageform.analysis import macenko_stains

    img = synthetic_stain_image((32, 32), rng=0).image
    with pytest.raises(DegenerateConfigurationError, match="min_pixels") as info:
        macenko_stains(img, min_pixels=10**30)
    _one_line(info)


def test_render_sfr_chart_grid_bounded() -> None:
    """A grid of 10**30 squares was a loop of 10**30 iterations (a fuzz timeout): the grid
    is bounded by the image (at most one square per 4 x 4 pixels)."""
    from imageform.analysis import render_sfr_chart

    with pytest.raises(InvalidInputError, match=r"grid\[0\]") as info:
        render_sfr_chart((120, 160), grid=(10**30, 2))
    _one_line(info)
    assert render_sfr_chart((16, 16), grid=(np.int64(4), 4), supersampling=1).shape == (16, 16)


def test_vahadane_iterations_bounded() -> None:
    """A huge iteration count could run for ever on a tile that does not converge."""
    from imageform.analysis import vahadane_stains

    with pytest.raises(InvalidInputError, match="iterations") as info:
        vahadane_stains(synthetic_stain_image((16, 16), rng=0).image, iterations=10**30)
    _one_line(info)


@pytest.mark.parametrize("image", [None, "abc", 1j, np.zeros((5, 5)), np.zeros((8, 8), object)])
def test_slanted_edge_roi_crop_refuses(image: object) -> None:
    """A crop of a scalar raised IndexError; a crop beyond the image returned an empty or
    cut array without a word."""
    from imageform.analysis import SlantedEdgeROI

    roi = SlantedEdgeROI(2, 3, 10, 12, 5.0, "vertical", "left", (7.0, 9.0))
    with pytest.raises(InvalidInputError, match="image") as info:
        roi.crop(image)
    _one_line(info)
    assert roi.crop(np.zeros((15, 12, 3))).shape == (12, 10, 3)
