"""Shipped tables: present in the package, sources named, shapes and published landmarks."""

from __future__ import annotations

from importlib import resources

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.spectral import (
    COLORCHECKER_PATCHES,
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


def test_tables_ship_inside_the_package() -> None:
    """The CSVs are package data (importlib.resources), small, each with a source header."""
    folder = resources.files("imageform.spectral").joinpath("data")
    total = 0
    for name in TABLES.values():
        f = folder.joinpath(name)
        assert f.is_file(), name
        text = f.read_text("utf-8")
        total += len(text.encode())
        assert text.startswith("# source: "), name
    assert total < 2_000_000
    assert "CIE 015:2018" in table_source("D65")
    assert "Stockman & Sharpe (2000)" in table_source("cones_ss2")


def test_cmfs_published_values() -> None:
    """CIE 015:2018 Table 4 (2°): x̄, ȳ, z̄ at 555 nm = 0.5120501, 1.0, 0.005749999.
    (The 10° table is checked through the D65 white point in test_integrate.)"""
    c2 = cmfs(2).interpolate([555]).values[0]
    assert c2 == pytest.approx([0.5120501, 1.0, 0.005749999], abs=1e-7)
    assert cmfs("10").labels[1] == "y_bar_10" or cmfs("10").shape == (471, 3)
    assert cmfs(2).range == (360.0, 830.0) and cmfs(2).interval == 1.0
    with pytest.raises(UnknownOptionError, match="valid: '10', '2'"):
        cmfs(4)


def test_luminous_efficiency_peaks() -> None:
    """CIE: V(λ) = 1 at 555 nm, V'(λ) = 1 at 507 nm."""
    assert luminous_efficiency().interpolate([555]).values[0] == pytest.approx(1.0, abs=1e-6)
    assert luminous_efficiency("scotopic").peak_wavelength() == 507.0
    with pytest.raises(UnknownOptionError):
        luminous_efficiency("mesopic")


def test_cone_fundamentals() -> None:
    """Stockman & Sharpe (2000) energy-based fundamentals: peak-normalised, L > M > S peaks."""
    c = cone_fundamentals()
    assert c.labels == ("l_bar", "m_bar", "s_bar")
    assert np.allclose(c.values.max(axis=0), 1.0, atol=1e-3)
    lp, mp, sp = c.peak_wavelength()
    assert 565 < lp < 572 and 538 < mp < 546 and 438 < sp < 446


def test_illuminants_and_leds() -> None:
    for name in ("A", "D50", "D65"):  # normalised to 100 at 560 nm (CIE 015 Table 1)
        s = illuminant_table(name)
        assert s.interpolate([560]).values[0] == pytest.approx(100.0, abs=0.05)
    assert illuminant_table("fl2").name == "CIE F2" and illuminant_table("F11").values.min() >= 0
    with pytest.raises(InvalidInputError, match="valid: 'A'"):
        illuminant_table("F7")
    assert len(LED_SPECTRA) == 9
    led = led_spectrum("led-b3")
    assert led.values.min() >= 0 and 440 < led.peak_wavelength() < 460  # blue pump peak
    with pytest.raises(InvalidInputError, match="unknown LED"):
        led_spectrum("LED-X")


def test_reflectances_and_camera() -> None:
    r = colorchecker_reflectances()
    assert r.shape == (36, 24) and r.labels == COLORCHECKER_PATCHES
    assert r.values.min() > 0 and r.values.max() < 1
    cam = camera_sensitivities()
    assert cam.labels == ("red", "green", "blue")
    assert (
        cam["blue"].peak_wavelength()
        < cam["green"].peak_wavelength()
        < cam["red"].peak_wavelength()
    )
    assert colorchecker_published_xyy("xrite2014").shape == (24, 3)
    with pytest.raises(UnknownOptionError):
        colorchecker_published_xyy("ohta")
    with pytest.raises(UnknownOptionError, match="spectral table"):
        load_table("cie2006")
    with pytest.raises(InvalidInputError, match="not a wavelength table"):
        load_table("colorchecker_published")


def test_tables_match_colour_science() -> None:
    """Cross-check (colour-science 0.4.7, the transcription source): values identical."""
    colour = pytest.importorskip("colour")
    ref = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    assert np.allclose(cmfs(2).values, ref.values, atol=1e-10)
    ref = colour.SDS_ILLUMINANTS["D65"]
    assert np.allclose(illuminant_table("D65").values, ref.values, atol=1e-10)


def test_read_table_gives_any_shipped_table() -> None:
    """read_table: comments, columns, numeric values and first-column labels of a CSV."""
    from imageform.spectral import read_table

    cvd = read_table("cvd_machado2009")
    assert cvd.comments[0].startswith("source: Machado, Oliveira & Fernandes (2009)")
    assert cvd.columns == (
        "deficiency",
        "severity",
        *(f"m{i}{j}" for i in range(3) for j in range(3)),
    )
    assert cvd.labels[:2] == ("protan", "protan") and set(cvd.labels) == {
        "protan",
        "deutan",
        "tritan",
    }
    # Machado et al. (2009), protanomaly at severity 0.1, first row of the matrix
    assert cvd.values[1, :4].tolist() == [0.1, 0.856167, 0.182038, -0.038205]
    assert cvd.values.shape == (33, 10) and not cvd.values.flags.writeable
    viridis = read_table("viridis")  # all columns numeric: values keep the first column
    assert viridis.columns == ("r", "g", "b")
    assert viridis.values[0].tolist() == [0.267004, 0.004874, 0.329415]
    # a wavelength table reads the same as load_table
    d65 = read_table("D65")
    np.testing.assert_array_equal(d65.values[:, 1], load_table("D65").values)
    assert read_table("D65").values is d65.values  # cached, read-only
    with pytest.raises(UnknownOptionError, match="unknown spectral table 'd66'"):
        read_table("d66")
