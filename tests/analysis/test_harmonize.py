"""Colour harmonisation between two devices from a colour chart.

Simulated devices: device B renders the ColorChecker's published sRGB values; device A
sees the same chart through a cross-talk matrix, an exposure and a tone change (linear
light), the lecture's question 14 setting. Peer cross-check: colour-science's
``matrix_colour_correction_Finlayson2015`` (same least squares, same expansion).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.analysis import (
    ChartWarning,
    ColorCorrection,
    chart_patches,
    correction_report,
    fit_color_correction,
    root_polynomial_terms,
    synthetic_chart_image,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from imageform.color.transfer import _srgb_decode, _srgb_encode
from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError

CROSSTALK = np.array([[0.85, 0.12, 0.03], [0.08, 0.80, 0.12], [0.02, 0.15, 0.83]])


def device_a(srgb: np.ndarray, exposure: float = 0.8, tone: float = 1.1) -> np.ndarray:
    """Device A: cross-talk, exposure and a tone curve in linear light, sRGB-encoded."""
    lin = _srgb_decode(np, np.asarray(srgb, dtype=np.float64))
    return np.asarray(_srgb_encode(np, exposure * np.clip(lin @ CROSSTALK.T, 0, None) ** tone))


REF = np.asarray(COLORCHECKER_SRGB8, float) / 255


@pytest.fixture(scope="module")
def charts() -> tuple[np.ndarray, np.ndarray]:
    chart_b = synthetic_chart_image()
    return device_a(chart_b), chart_b


def test_chart_patches_exact_on_synthetic(charts) -> None:  # type: ignore[no-untyped-def]
    _, chart_b = charts
    p = chart_patches(chart_b)
    np.testing.assert_allclose(p.means, REF, atol=1e-12)
    assert p.valid.all() and p.std.max() < 1e-12


@pytest.mark.parametrize(
    ("method", "degree", "max_mean_after"),
    [("linear", 1, 2.0), ("root_polynomial", 2, 1.5), ("root_polynomial", 3, 1.2)],
)
def test_correction_reduces_delta_e(charts, method, degree, max_mean_after) -> None:  # type: ignore[no-untyped-def]
    chart_a, chart_b = charts
    pa, pb = chart_patches(chart_a), chart_patches(chart_b)
    corr = fit_color_correction(pa, pb, method, degree)
    rep = correction_report(pa, pb, corr)
    s = rep.summary()
    print(
        f"{method} deg {degree}: ΔE00 mean {s['mean_before']:.2f} -> {s['mean_after']:.2f}, "
        f"max {s['max_before']:.2f} -> {s['max_after']:.2f}"
    )
    assert s["mean_before"] > 7.0  # the two devices disagree visibly
    assert s["mean_after"] < max_mean_after  # measured 1.60 / 1.23 / 0.92
    assert rep.delta_e_after.shape == (24,)


def test_held_out_colours_improve(charts) -> None:  # type: ignore[no-untyped-def]
    """Generalisation: fit on the chart, score on colours not on it."""
    chart_a, chart_b = charts
    corr = fit_color_correction(chart_patches(chart_a), chart_patches(chart_b), "root_polynomial")
    test = np.random.default_rng(7).uniform(0.1, 0.9, (200, 3))
    s = correction_report(device_a(test), test, corr).summary()
    print(f"held-out: ΔE00 mean {s['mean_before']:.2f} -> {s['mean_after']:.2f}")
    assert s["mean_after"] < 0.5 * s["mean_before"]


def test_exact_recovery_of_a_linear_device() -> None:
    lin = _srgb_decode(np, REF)
    a = _srgb_encode(np, lin @ CROSSTALK.T)
    corr = fit_color_correction(a, REF)
    np.testing.assert_allclose(corr.matrix, np.linalg.inv(CROSSTALK), atol=1e-10)
    assert correction_report(a, REF, corr).delta_e_after.max() < 1e-6


def test_cross_check_colour_science_finlayson2015() -> None:
    """Peer: colour-science computes the same least-squares matrix (linear inputs)."""
    colour = pytest.importorskip("colour")
    a = device_a(REF)
    lin_a, lin_b = _srgb_decode(np, a), _srgb_decode(np, REF)
    for degree in (1, 2, 3):
        ours = fit_color_correction(a, REF, "root_polynomial", degree).matrix
        theirs = colour.characterisation.matrix_colour_correction_Finlayson2015(
            lin_a, lin_b, degree=degree, root_polynomial_expansion=True
        )
        # same terms, possibly in another order: compare the corrected values
        ref_terms = colour.characterisation.polynomial_expansion_Finlayson2015(
            lin_a, degree=degree, root_polynomial_expansion=True
        )
        np.testing.assert_allclose(
            root_polynomial_terms(lin_a, degree) @ ours.T, ref_terms @ theirs.T, atol=1e-8
        )


@given(arrays(np.float64, (5, 3), elements=st.floats(0.0, 1.0)), st.floats(0.05, 20.0))
def test_root_polynomial_exposure_invariance(rgb: np.ndarray, k: float) -> None:
    """Finlayson et al. 2015: every root-polynomial term scales linearly with exposure."""
    for degree in (1, 2, 3):
        np.testing.assert_allclose(
            root_polynomial_terms(k * rgb, degree),
            k * root_polynomial_terms(rgb, degree),
            rtol=1e-9,
            atol=1e-12,
        )


def test_json_round_trip(tmp_path: Path, charts) -> None:  # type: ignore[no-untyped-def]
    chart_a, chart_b = charts
    corr = fit_color_correction(
        chart_patches(chart_a), chart_patches(chart_b), "root_polynomial", 3
    )
    p = tmp_path / "corr.json"
    corr.to_json(p)
    back = ColorCorrection.from_json(p)
    assert back.method == "root_polynomial" and back.degree == 3 and back.n_patches == 24
    assert back.transfer == "srgb"
    np.testing.assert_array_equal(back.matrix, corr.matrix)


@pytest.mark.parametrize("dtype", ["uint8", "uint16", "float32"])
def test_apply_dtypes_and_chunked(charts, dtype: str) -> None:  # type: ignore[no-untyped-def]
    da = pytest.importorskip("dask.array")
    chart_a, chart_b = charts
    corr = fit_color_correction(chart_patches(chart_a), chart_patches(chart_b), "linear")
    if dtype.startswith("uint"):
        x = np.round(chart_a * np.iinfo(dtype).max).astype(dtype)
    else:
        x = chart_a.astype(dtype)
    out = corr.apply(x)
    assert out.dtype == np.float32 and out.shape == x.shape
    lazy = corr.apply(da.from_array(x, chunks=(50, 70, 3)))  # 3 x 3 chunks
    assert isinstance(lazy, da.Array)
    np.testing.assert_allclose(lazy.compute(), out, atol=1e-6)
    p_lazy = chart_patches(da.from_array(x, chunks=(50, 70, 3)))
    np.testing.assert_allclose(p_lazy.means, chart_patches(x).means, atol=1e-7)
    assert np.allclose(corr.apply(x, clip=True).max(), min(float(out.max()), 1.0))


def test_saturated_and_missing_patches(charts) -> None:  # type: ignore[no-untyped-def]
    chart_a, chart_b = charts
    img = chart_a.copy()
    img[3:27, 3:27] = 1.0  # patch 0 clipped by the sensor
    img[33:57, 40:50] = 0.0  # patch 7 half covered (a missing / misaligned patch)
    with pytest.warns(ChartWarning) as rec:
        pa = chart_patches(img)
    msgs = " | ".join(str(w.message) for w in rec)
    assert "saturated patch(es) [0]" in msgs and "missing patch(es) [7]" in msgs
    assert pa.valid.sum() == 22
    corr = fit_color_correction(pa, chart_patches(chart_b))
    assert corr.n_patches == 22


def test_saturated_values_in_arrays_warn() -> None:
    a = device_a(REF)
    a[18] = 1.0  # white patch clipped
    with pytest.warns(ChartWarning, match=r"saturated patch\(es\) \[18\]"):
        corr = fit_color_correction(a, REF)
    assert corr.n_patches == 23


def test_chart_not_filling_the_frame() -> None:
    padded = np.pad(synthetic_chart_image(), ((60, 60), (90, 90), (0, 0)), constant_values=0.05)
    with pytest.warns(ChartWarning, match="missing"):
        p = chart_patches(padded)
    assert p.missing.sum() > 6
    with pytest.raises(InvalidInputError, match="no usable chart patch"):
        chart_patches(np.random.default_rng(0).uniform(0, 1, (60, 90, 3)))


def test_bad_input() -> None:
    a = device_a(REF)
    with pytest.raises(UnknownOptionError, match="'linear', 'root_polynomial'"):
        fit_color_correction(a, REF, "cubic")
    with pytest.raises(InvalidInputError, match=r"degree in \(1, 2, 3\)"):
        fit_color_correction(a, REF, "root_polynomial", 4)
    with pytest.raises(InvalidInputError, match="same shape"):
        fit_color_correction(a[:20], REF)
    with pytest.raises(InvalidInputError, match=r"shape \(N, 3\)"):
        fit_color_correction(a[:, :2], REF[:, :2])
    with pytest.raises(InvalidInputError, match="NaN"):
        fit_color_correction(np.where(np.arange(24)[:, None] == 3, np.nan, a), REF)
    with pytest.raises(DegenerateConfigurationError, match="13 terms per channel but only 8"):
        fit_color_correction(a[:8], REF[:8], "root_polynomial", 3)
    grey = np.repeat(np.linspace(0.1, 0.9, 10)[:, None], 3, axis=1)
    with pytest.raises(DegenerateConfigurationError, match="rank-deficient"):
        fit_color_correction(grey, grey)
    with pytest.raises(InvalidInputError, match="at least 2 pixels per cell"):
        chart_patches(np.zeros((6, 6, 3)))


def test_report_summary_skips_flagged_patches(charts) -> None:  # type: ignore[no-untyped-def]
    chart_a, chart_b = charts
    img = chart_a.copy()
    img[33:57, 40:50] = 0.0  # patch 7 misaligned
    with pytest.warns(ChartWarning, match="missing"):
        pa = chart_patches(img)
    pb = chart_patches(chart_b)
    rep = correction_report(pa, pb, fit_color_correction(pa, pb))
    assert not rep.valid[7] and rep.valid.sum() == 23
    assert rep.summary()["max_after"] == pytest.approx(rep.delta_e_after[rep.valid].max())


# -- linear patch values (the simulator's camera RGB -> linear sRGB fit) ---------------------
def test_linear_transfer_recovers_row_vector_matrix(tmp_path: Path) -> None:
    """``transfer="linear"``: no decoding; the matrix applies to row vectors,
    ``reference = measured @ matrix.T`` (docs/conventions.md), recovered exactly."""
    rng = np.random.default_rng(0)
    C = rng.uniform(0, 1, (24, 3))
    M = rng.normal(size=(3, 3))
    corr = fit_color_correction(C, C @ M.T, transfer="linear", saturation=None)
    assert corr.transfer == "linear" and corr.n_patches == 24
    np.testing.assert_allclose(corr.matrix, M, atol=1e-12)
    img = rng.uniform(0, 2, (4, 5, 3))  # linear light may exceed 1
    np.testing.assert_allclose(corr.apply(img), img @ M.T, atol=1e-12)
    corr.to_json(tmp_path / "lin.json")
    back = ColorCorrection.from_json(tmp_path / "lin.json")
    assert back.transfer == "linear"
    np.testing.assert_array_equal(back.apply(img), corr.apply(img))


def test_linear_transfer_saturation_none_keeps_bright_patches() -> None:
    rng = np.random.default_rng(1)
    C = rng.uniform(0.05, 1.1, (12, 3))  # linear camera RGB above 1 is not clipped
    with pytest.warns(ChartWarning, match="saturated"):
        assert fit_color_correction(C, 0.5 * C, transfer="linear").n_patches < 12
    assert fit_color_correction(C, 0.5 * C, transfer="linear", saturation=None).n_patches == 12


def test_linear_transfer_missing_rows_and_errors() -> None:
    """Non-finite rows are left out through ChartPatches(missing=...); bad input raises."""
    from imageform.analysis import ChartPatches

    rng = np.random.default_rng(2)
    C = rng.uniform(0, 1, (10, 3))
    M = rng.normal(size=(3, 3))
    C[3] = np.nan
    missing = ~np.isfinite(C).all(axis=1)
    flags = np.zeros(10, dtype=bool)
    pa = ChartPatches(C, np.zeros_like(C), flags, missing)
    pb = ChartPatches(C @ M.T, np.zeros_like(C), flags, missing)
    corr = fit_color_correction(pa, pb, transfer="linear", saturation=None)
    assert corr.n_patches == 9
    np.testing.assert_allclose(corr.matrix, M, atol=1e-12)
    with pytest.raises(InvalidInputError, match=r"shape \(N, 3\)"):
        fit_color_correction(np.ones((4, 2)), np.ones((4, 2)), transfer="linear")
    with pytest.raises(DegenerateConfigurationError, match="independent colours"):
        fit_color_correction(np.ones((5, 3)), np.ones((5, 3)), transfer="linear", saturation=None)
    with pytest.raises(UnknownOptionError, match="'linear', 'srgb'"):
        fit_color_correction(C[:3], C[:3], transfer="gamma")


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.uint8])
def test_linear_apply_dtypes(dtype: type) -> None:
    """float32 stays float32, float64 stays float64, uint8 is read as full range (float32)."""
    rng = np.random.default_rng(1)
    corr = ColorCorrection("linear", 1, 2 * np.eye(3), transfer="linear")
    img = (rng.uniform(0, 1, (4, 5, 3)) * (255 if dtype == np.uint8 else 1)).astype(dtype)
    out = corr.apply(img)
    assert out.dtype == (np.float64 if dtype == np.float64 else np.float32)
    ref = img / 255.0 if dtype == np.uint8 else img
    np.testing.assert_allclose(out, 2 * ref, rtol=1e-6)
