"""Spectrum: construction, interpolation (named methods), arithmetic, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.spectral import Spectrum


def test_construct_and_properties() -> None:
    s = Spectrum([400, 410, 420], [0.1, 0.2, 0.3], name="r")
    assert s.shape == (3,) and len(s) == 3 and s.range == (400.0, 420.0) and s.interval == 10.0
    assert "400-420 nm step 10" in repr(s)
    assert not s.values.flags.writeable  # frozen data
    m = Spectrum([400, 500], [[1, 2], [3, 4]], labels=("a", "b"))
    assert m["b"].values.tolist() == [2.0, 4.0]
    assert m[0].values.tolist() == [1.0, 3.0]
    assert Spectrum([400, 401, 405], [0, 1, 0]).interval is None


@pytest.mark.parametrize(
    ("wl", "vals", "match"),
    [
        ([400, 400, 410], [1, 2, 3], "strictly increasing"),
        ([410, 400, 420], [1, 2, 3], "strictly increasing"),
        ([400, 410], [1, 2, 3], "match 2 wavelengths"),
        ([400, np.nan], [1, 2], "NaN"),
        ([400, 410], [1, np.inf], "NaN or inf"),
        ([[400, 410]], [1, 2], "shape"),
    ],
)
def test_bad_construction(wl: object, vals: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        Spectrum(wl, vals)  # type: ignore[arg-type]


def test_bad_labels_and_column() -> None:
    with pytest.raises(InvalidInputError, match="labels"):
        Spectrum([400, 410], [[1, 2], [3, 4]], labels=("a",))
    with pytest.raises(InvalidInputError, match="unknown column 'c'"):
        Spectrum([400, 410], [[1, 2], [3, 4]], labels=("a", "b"))["c"]
    with pytest.raises(InvalidInputError, match="multi-curve"):
        Spectrum([400, 410], [1, 2])["a"]


def test_interpolation_methods() -> None:
    s = Spectrum([400, 500, 600, 700], [0.0, 1.0, 0.0, 1.0])
    assert s.interpolate([450], method="linear").values[0] == pytest.approx(0.5)
    assert s.interpolate([440], method="nearest").values[0] == 0.0
    assert s.interpolate([460], method="nearest").values[0] == 1.0
    # pchip never overshoots the data (keeps reflectances in [0, 1]); a cubic spline does
    grid = np.arange(400.0, 701.0)
    assert s.interpolate(grid, method="pchip").values.max() <= 1.0 + 1e-12
    assert s.interpolate(grid, method="cubic").values.max() > 1.0
    # nodes are reproduced exactly by every method
    for m in ("linear", "cubic", "pchip", "nearest"):
        assert np.allclose(s.interpolate(s.wavelengths, method=m).values, s.values, atol=1e-12)


def test_extrapolation() -> None:
    s = Spectrum([400, 500], [0.2, 0.4])
    assert s.interpolate([380, 520]).values.tolist() == [0.2, 0.4]  # CIE 015 §7.2.2
    assert s.interpolate([380, 450], extrapolate="zero").values.tolist() == pytest.approx([0, 0.3])
    with pytest.raises(InvalidInputError, match="outside the sampled range"):
        s.interpolate([380], extrapolate="error")
    with pytest.raises(UnknownOptionError, match="valid: 'cubic', 'linear'"):
        s.interpolate([450], method="spline")
    with pytest.raises(InvalidInputError, match="strictly increasing"):
        s.interpolate([450, 440])


def test_resample_and_trim() -> None:
    s = Spectrum([400, 500], [0.0, 1.0])
    r = s.resample(400, 500, 25)
    assert r.wavelengths.tolist() == [400, 425, 450, 475, 500]
    with pytest.raises(InvalidInputError, match="multiple"):
        s.resample(400, 500, 30)
    with pytest.raises(InvalidInputError, match="step > 0"):
        s.resample(400, 500, 0)
    assert s.resample(400, 500, 10).trim(420, 450).range == (420.0, 450.0)
    with pytest.raises(InvalidInputError, match="fewer than 2"):
        s.trim(401, 402)


def test_arithmetic() -> None:
    a = Spectrum([400, 500], [1.0, 2.0])
    b = Spectrum([400, 500], [3.0, 4.0])
    assert (a + b).values.tolist() == [4, 6]
    assert (b - a).values.tolist() == [2, 2]
    assert (1 - a).values.tolist() == [0, -1]
    assert (a * b).values.tolist() == [3, 8]
    assert (2 * a).values.tolist() == [2, 4]
    assert (b / a).values.tolist() == [3, 2]
    assert (-a).values.tolist() == [-1, -2]
    m = Spectrum([400, 500], [[1, 1, 1], [2, 2, 2]])
    assert (m * a).values.tolist() == [[1, 1, 1], [4, 4, 4]]
    with pytest.raises(InvalidInputError, match="different wavelength grids"):
        a + Spectrum([400, 510], [1, 1])
    with pytest.raises(InvalidInputError, match="division by zero"):
        a / Spectrum([400, 500], [0.0, 1.0])
    with pytest.raises(InvalidInputError, match="swap"):
        a * m
    with pytest.raises(TypeError):
        a + "x"  # type: ignore[operator]


def test_normalize_and_peak() -> None:
    s = Spectrum([500, 510, 520], [0.2, 0.8, 0.4])
    assert s.normalize().values.max() == 1.0
    assert s.normalize(510).values[1] == 1.0
    with pytest.raises(InvalidInputError, match="is 0"):
        Spectrum([500, 510], [0.0, 1.0]).normalize(500)
    # the parabola through three samples of a parabola recovers its vertex exactly
    wl = np.arange(500.0, 521.0, 5.0)
    p = Spectrum(wl, 1 - ((wl - 508.3) / 20) ** 2)
    assert p.peak_wavelength() == pytest.approx(508.3, abs=1e-9)
    plateau = Spectrum([500, 501, 502, 503], [0.9, 1, 1, 0.9])
    assert plateau.peak_wavelength() == 501.5


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=3, max_size=12), st.floats(0.1, 3.0))
def test_linear_interpolation_is_linear(vals: list[float], k: float) -> None:
    """Property: interpolation commutes with scaling; nodes reproduced."""
    wl = 400.0 + 10.0 * np.arange(len(vals))
    s = Spectrum(wl, vals)
    grid = np.linspace(wl[0], wl[-1], 37)
    assert np.allclose((k * s).interpolate(grid).values, k * s.interpolate(grid).values)
    assert np.allclose(s.interpolate(wl).values, vals)


def test_sprague() -> None:
    """Sprague reproduces polynomials up to degree 4 exactly inside the data and its nodes."""
    wl = np.arange(400.0, 501.0, 10.0)
    poly = 1e-8 * (wl - 430) ** 3 * (wl - 480) + 0.5
    s = Spectrum(wl, poly)
    grid = np.arange(420.0, 481.0, 1.0)
    want = 1e-8 * (grid - 430) ** 3 * (grid - 480) + 0.5
    assert np.allclose(s.interpolate(grid, method="sprague").values, want, atol=1e-12)
    assert np.allclose(s.interpolate(wl, method="sprague").values, poly, atol=1e-12)
    with pytest.raises(InvalidInputError, match="uniformly spaced"):
        Spectrum([400, 410, 430, 440, 450, 460], np.ones(6)).interpolate([405], method="sprague")


def test_sprague_cross_check_colour() -> None:
    colour = pytest.importorskip("colour")
    from imageform.spectral import colorchecker_reflectances

    r = colorchecker_reflectances()["blue sky"]
    grid = np.arange(380.0, 731.0, 1.0)
    ref = colour.SpragueInterpolator(r.wavelengths, r.values)(grid)
    assert np.allclose(r.interpolate(grid, method="sprague").values, ref, atol=1e-12)
