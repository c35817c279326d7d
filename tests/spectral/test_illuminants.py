"""Planck's law, the CIE daylight series, named illuminants, direct-search CCT."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.spectral import (
    blackbody_spectrum,
    daylight_spectrum,
    illuminant,
    illuminant_table,
    planck,
    planckian_cct,
    spectrum_to_xyz,
)


def test_planck_wien_peak() -> None:
    """Wien's displacement law: λ_max T = 2.897771955e-3 m K (CODATA 2018); with CIE's c2
    = 1.4388e-2 m K the peak is c2 / 4.965114231744276 / T."""
    t = 5000.0
    wl = np.linspace(560.0, 600.0, 40001)
    peak = wl[np.argmax(planck(wl, t))]
    assert peak == pytest.approx(1.4388e-2 / 4.965114231744276 / t * 1e9, abs=2e-3)


def test_illuminant_a_from_planck() -> None:
    """CIE 015:2018 eq. 4.2: A is a Planckian radiator at 2848 K with c2 = 1.435e-2 m K, i.e.
    2856 K with c2 = 1.4388e-2 m K. Our black body reproduces Table 1 to its 5 digits."""
    a = illuminant_table("A")
    t = 2848.0 * 1.4388 / 1.435
    bb = blackbody_spectrum(t, a.wavelengths)
    assert np.allclose(bb.values, a.values, rtol=2e-4)


def test_daylight_reproduces_d65_and_d50_tables() -> None:
    """CIE 015:2018 §4.1.2: D65 from S0 + M1 S1 + M2 S2 with M rounded to 3 decimals matches
    Table 1 to the table's precision (±0.005 after rounding to 2-3 decimals)."""
    d65 = daylight_spectrum(6500 * 1.4388 / 1.4380)
    tab = illuminant_table("D65")
    assert np.allclose(d65.interpolate(tab.wavelengths).values, tab.values, atol=0.06)
    d50 = daylight_spectrum(5000 * 1.4388 / 1.4380)
    tab = illuminant_table("D50")
    assert np.allclose(d50.interpolate(tab.wavelengths).values, tab.values, atol=0.06)


def test_daylight_cross_check_colour() -> None:
    """Cross-check against colour-science's sd_CIE_illuminant_D_series at 7500 K."""
    colour = pytest.importorskip("colour")
    xy = colour.temperature.CCT_to_xy_CIE_D(7500 * 1.4388 / 1.4380)
    ref = colour.sd_CIE_illuminant_D_series(xy)
    ours = daylight_spectrum(7500 * 1.4388 / 1.4380)
    assert np.allclose(ours.interpolate(ref.wavelengths).values, ref.values, atol=0.05)


def test_named_illuminants() -> None:
    assert illuminant("D65").name == "CIE D65"
    assert illuminant("E").values.std() == 0
    assert illuminant("D75").name.startswith("CIE daylight 75")
    assert illuminant("bb3200").name == "blackbody 3200 K"
    assert illuminant("LED-B1").values.max() > 0
    with pytest.raises(InvalidInputError, match="unknown illuminant 'tungsten' for name; valid: A"):
        illuminant("tungsten")
    with pytest.raises(InvalidInputError, match="illuminant name"):
        illuminant(65)  # type: ignore[arg-type]


def test_bad_temperatures() -> None:
    with pytest.raises(InvalidInputError, match="temperature"):
        planck(500.0, -1.0)
    with pytest.raises(InvalidInputError, match=r"wavelength_nm in \[0.001, 1e\+12\] nm"):
        planck([0.0, 500.0], 5000.0)
    with pytest.raises(InvalidInputError, match=r"\[4000, 25000\]"):
        daylight_spectrum(3000)


def test_cct_of_a_and_d65() -> None:
    """CIE 015:2018 §4.1: CCT of illuminant A = 2856 K, of D65 = 6504 K (within 2 K), by the
    direct Planckian search and by Robertson (1968) (imageform.color.cct), from the tables'
    XYZ by both summation methods."""
    from imageform.color.cct import xy_to_cct

    for name, want in (("A", 2856.0), ("D65", 6504.0)):
        for method in ("cie015", "astm_e308"):
            xyz = spectrum_to_xyz(illuminant(name), illuminant=None, method=method)
            assert planckian_cct(xyz)[0] == pytest.approx(want, abs=2.0)
            cct, _ = xy_to_cct(xyz[:2] / xyz.sum())
            assert float(cct) == pytest.approx(want, abs=2.0)
    # Duv of A is 0 (a Planckian radiator); D65 lies above the locus (Duv ≈ +0.0032)
    assert planckian_cct(spectrum_to_xyz(illuminant("A"), illuminant=None))[1] == pytest.approx(
        0, abs=2e-5
    )
    assert planckian_cct(spectrum_to_xyz(illuminant("D65"), illuminant=None))[1] == pytest.approx(
        0.0032, abs=2e-4
    )
    with pytest.raises(InvalidInputError, match="X\\+Y\\+Z > 0"):
        planckian_cct([0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    "xy", [(0.31272, 0.32903), (0.34567, 0.35850), (0.29902, 0.31485), (0.38, 0.38)]
)
@pytest.mark.parametrize("round_m", [True, False])
def test_daylight_from_xy_equals_colour_science(xy: tuple[float, float], round_m: bool) -> None:
    """CIE 015:2018 eq. 4.5 from a chromaticity, as colour-science's
    sd_CIE_illuminant_D_series computes it (same basis table, same M rounding): equal."""
    colour = pytest.importorskip("colour")
    from imageform.spectral import daylight_spectrum_from_xy

    ref = colour.sd_CIE_illuminant_D_series(np.array(xy), M1_M2_rounding=round_m)
    ours = daylight_spectrum_from_xy(xy, round_m=round_m)
    np.testing.assert_array_equal(ours.wavelengths, ref.wavelengths)
    np.testing.assert_allclose(ours.values, ref.values, rtol=1e-14, atol=0)


def test_daylight_spectrum_is_the_d_series_at_the_daylight_locus() -> None:
    """daylight_spectrum(T) = daylight_spectrum_from_xy(cct_to_xy(T, method="daylight"))."""
    from imageform.color import cct_to_xy
    from imageform.spectral import daylight_spectrum_from_xy

    for t in (4000.0, 5003.0, 6504.0, 7000.0, 9300.0, 25000.0):
        xy = np.asarray(cct_to_xy(t, method="daylight"))
        np.testing.assert_array_equal(
            daylight_spectrum(t).values, daylight_spectrum_from_xy(xy).values
        )


def test_daylight_from_xy_bad_input() -> None:
    from imageform.spectral import daylight_spectrum_from_xy

    for bad in ([0.3], [0.3, np.nan], "xy", [[0.3, 0.3]]):
        with pytest.raises(InvalidInputError, match=r"expected xy as (two finite|real) numbers"):
            daylight_spectrum_from_xy(bad)  # type: ignore[arg-type]
    # 0.0241 + 0.2562 x - 0.7341 y = 0 at x = 0, y = 0.0241 / 0.7341
    with pytest.raises(InvalidInputError, match="M1, M2 are undefined"):
        daylight_spectrum_from_xy([0.0, 0.0241 / 0.7341])


@pytest.mark.parametrize(
    ("name", "xy"),
    # CIE 15:2004 Table T.3 (C) and CIE 15.2:1986 Table 1.1 / Wyszecki & Stiles (B), 2° observer
    [("C", (0.31006, 0.31616)), ("B", (0.34842, 0.35161))],
)
def test_illuminants_b_and_c_chromaticities(name: str, xy: tuple[float, float]) -> None:
    s = illuminant(name)
    assert s.name == f"CIE {name}"
    for method in ("cie015", "astm_e308"):
        xyz = spectrum_to_xyz(s, illuminant=None, method=method)
        np.testing.assert_allclose(xyz[:2] / xyz.sum(), xy, atol=6e-5)


def test_illuminants_b_and_c_cross_check_colour() -> None:
    colour = pytest.importorskip("colour")
    for name in "BC":
        ref = colour.SDS_ILLUMINANTS[name]
        ours = illuminant(name)
        np.testing.assert_array_equal(ours.wavelengths, ref.wavelengths)
        np.testing.assert_allclose(ours.values, ref.values, rtol=1e-12)
        # CCT: B about 4874 K, C about 6774 K (CIE 15:2004 Table T.3 / Wyszecki & Stiles)
    from imageform.color.cct import xy_to_cct

    for name, want in (("B", 4874.0), ("C", 6774.0)):
        xyz = spectrum_to_xyz(illuminant(name), illuminant=None)
        assert float(xy_to_cct(xyz[:2] / xyz.sum(), method="ohno2013")[0]) == pytest.approx(
            want, abs=5
        )
