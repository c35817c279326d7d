"""Metamers: constructed ones really match (ΔXYZ < 1e-6) and really differ (RMS > 0.05)."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import (
    are_metamers,
    match_with_primaries,
    metamer,
    metamerism_index,
    tristimulus,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from imageform.spectral import (
    Spectrum,
    colorchecker_reflectances,
    illuminant,
    spectrum_to_lms,
    spectrum_to_xyz,
)

R = colorchecker_reflectances()
PATCHES = ["dark skin", "blue sky", "foliage", "orange", "neutral 5 (.70 D)", "cyan"]


def _rms(a: Spectrum, b: Spectrum) -> float:
    g = a.wavelengths
    return float(np.sqrt(np.mean((a.values - b.interpolate(g).values) ** 2)))


@pytest.mark.parametrize("patch", PATCHES)
@pytest.mark.parametrize("observer", [2, 10, "cones"])
def test_metamer_matches_and_differs(patch: str, observer: object) -> None:
    """The issue's criteria: ΔXYZ (or ΔLMS) < 1e-6 and spectral RMS > 0.05; physically
    valid: reflectance within [0, 1]."""
    r = R[patch]
    m = metamer(r, observer=observer)  # type: ignore[arg-type]
    assert m.values.min() >= 0.0 and m.values.max() <= 1.0
    assert _rms(m, r) > 0.05
    if observer == "cones":
        d = spectrum_to_lms(m) - spectrum_to_lms(r)
    else:
        d = spectrum_to_xyz(m, observer=observer) - spectrum_to_xyz(r, observer=observer)  # type: ignore[arg-type]
    assert np.max(np.abs(d)) < 1e-6
    assert are_metamers(r, m, observer=observer)  # type: ignore[arg-type]


def test_metamer_breaks_under_another_illuminant() -> None:
    """A metamer under D65 is (in general) not one under A: the metamerism index is > 0."""
    r = R["blue sky"]
    m = metamer(r)
    assert not are_metamers(r, m, observer=2, illuminant="A")
    assert metamerism_index(r, m, "D65", "A") > 0.5
    assert metamerism_index(r, m, "D65", "D65") == pytest.approx(0.0, abs=1e-9)
    assert metamerism_index(r, m, "D65", "F11", correct=False) > 0.5


def test_are_metamers_needs_different_spectra() -> None:
    r = R["orange"]
    assert not are_metamers(r, r)  # identical: an isomeric match, not metamerism
    assert not are_metamers(r, R["cyan"])


def test_light_metamer() -> None:
    """Lights (illuminant=None) need only non-negativity."""
    d65 = illuminant("D65").trim(380, 780)
    m = metamer(d65, observer=2, illuminant=None, kind="light")
    assert m.values.min() >= 0
    assert np.allclose(
        tristimulus(m, observer=2, illuminant=None),
        tristimulus(d65, observer=2, illuminant=None),
        rtol=1e-12,
    )
    assert are_metamers(d65, m, observer=2, illuminant=None)


def test_three_primaries_match_any_in_gamut_stimulus() -> None:
    """Grassmann: three independent primaries match any stimulus; inside their gamut the
    weights are all >= 0 and the mixture is a metamer of the target; a spectral 500 nm
    light (outside any three-primary gamut) needs a negative weight."""
    wl = np.arange(380.0, 781.0)
    prim = Spectrum.from_columns(
        wl, [np.exp(-0.5 * ((wl - c) / 12.0) ** 2) for c in (620.0, 530.0, 460.0)]
    )
    d65 = illuminant("D65")
    for patch in ("dark skin", "neutral 5 (.70 D)", "foliage"):
        light = (R[patch].interpolate(wl) * d65.interpolate(wl)) / 100.0
        w = match_with_primaries(light, prim)
        assert np.all(w > 0)
        mix = Spectrum(wl, prim.values @ w)
        assert are_metamers(light, mix, observer=2, illuminant=None)
    mono = Spectrum([499.0, 500.0, 501.0], [0.0, 1.0, 0.0])
    assert np.any(match_with_primaries(mono, prim) < 0)


def test_bad_input() -> None:
    r = R["orange"]
    with pytest.raises(InvalidInputError, match="reflectance with values in \\[0, 1\\]"):
        metamer(2 * r)
    with pytest.raises(InvalidInputError, match="single-curve Spectrum"):
        metamer(R)
    with pytest.raises(UnknownOptionError, match="spectrum kind"):
        metamer(r, kind="emission")
    with pytest.raises(InvalidInputError, match="strength"):
        metamer(r, strength=0)
    with pytest.raises(DegenerateConfigurationError, match="no valid metamer"):
        metamer(Spectrum([380.0, 780.0], [1.0, 1.0]))
    with pytest.raises(InvalidInputError, match="observer 2 or 10"):
        metamerism_index(r, r, observer="cones")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="shape \\(M, 3\\)"):
        match_with_primaries(r, r)
    wl = np.arange(380.0, 781.0)
    same = Spectrum.from_columns(wl, [np.ones_like(wl)] * 3)
    with pytest.raises(DegenerateConfigurationError, match="not independent"):
        match_with_primaries(r, same)
