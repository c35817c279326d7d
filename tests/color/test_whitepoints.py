"""White points: CIE 15:2004 Table T.3 values, XYZ derivation, the white= argument forms."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import WHITEPOINTS_XY, resolve_white, whitepoint_xy, whitepoint_xyz
from imageform.errors import InvalidInputError, UnknownOptionError

NAMES = ["A", "B", "C", "D50", "D55", "D65", "D75", "E", "F2", "F7", "F11"]


def test_table_has_every_listed_illuminant_for_both_observers() -> None:
    for obs in (2, 10):
        assert sorted(WHITEPOINTS_XY[obs]) == sorted(NAMES)


@pytest.mark.parametrize(
    ("name", "observer", "xy"),
    [
        # Gold: CIE 15:2004, Table T.3 (five decimals as printed).
        ("A", 2, (0.44757, 0.40745)),
        ("D65", 2, (0.31271, 0.32902)),
        ("D50", 2, (0.34567, 0.35850)),
        ("D65", 10, (0.31382, 0.33100)),
        ("F11", 10, (0.38541, 0.37123)),
        # illuminants B and C (issue 26: in the spectral tables, not in this one)
        ("B", 2, (0.34842, 0.35161)),
        ("C", 2, (0.31006, 0.31616)),
        ("B", 10, (0.34980, 0.35270)),
        ("C", 10, (0.31039, 0.31905)),
    ],
)
def test_gold_cie15(name: str, observer: int, xy: tuple[float, float]) -> None:
    assert whitepoint_xy(name, observer=observer) == pytest.approx(xy, abs=5e-6)


@pytest.mark.parametrize("observer", [2, 10])
def test_cross_check_colour_science(observer: int) -> None:
    # Cross-check (colour-science 0.4.7, CCS_ILLUMINANTS). colour rounds several 2° values
    # to four decimals (D65 0.3127, 0.3290; FL11 y 0.3769 vs CIE 15 0.37713): tolerance 3e-4.
    colour = pytest.importorskip("colour")
    key = (
        "CIE 1931 2 Degree Standard Observer"
        if observer == 2
        else ("CIE 1964 10 Degree Standard Observer")
    )
    for name in NAMES:
        cname = "FL" + name[1:] if name.startswith("F") else name
        ref = colour.CCS_ILLUMINANTS[key][cname]
        assert whitepoint_xy(name, observer=observer) == pytest.approx(tuple(ref), abs=3e-4)


def test_xyz_has_unit_y_and_matches_xy() -> None:
    for name in NAMES:
        xyz = whitepoint_xyz(name)
        assert xyz[1] == 1.0
        x, y = whitepoint_xy(name)
        assert xyz[0] / xyz.sum() == pytest.approx(x, abs=1e-12)
        assert xyz[1] / xyz.sum() == pytest.approx(y, abs=1e-12)


def test_names_are_forgiving_and_unknown_lists_valid() -> None:
    assert whitepoint_xy("d65") == whitepoint_xy("D65")
    assert whitepoint_xy("FL11") == whitepoint_xy("F11")
    with pytest.raises(UnknownOptionError, match="valid: 'A', 'B', 'C', 'D50'"):
        whitepoint_xy("D66")
    with pytest.raises(UnknownOptionError, match="observer"):
        whitepoint_xy("D65", observer=5)


def test_resolve_white_forms() -> None:
    np.testing.assert_allclose(resolve_white("D65"), whitepoint_xyz("D65"))
    np.testing.assert_allclose(resolve_white("srgb"), [0.3127 / 0.329, 1, 0.3583 / 0.329])
    np.testing.assert_allclose(resolve_white((0.3127, 0.329)), resolve_white("srgb"))
    np.testing.assert_allclose(resolve_white([0.9, 1.0, 1.1]), [0.9, 1.0, 1.1])
    with pytest.raises(UnknownOptionError, match="unknown white 'nope'"):
        resolve_white("nope")
    with pytest.raises(InvalidInputError, match="Y > 0"):
        resolve_white([1.0, 0.0, 1.0])
    with pytest.raises(InvalidInputError, match="y > 0"):
        resolve_white([0.3, 0.0])


@pytest.mark.parametrize("observer", [2, 10])
@pytest.mark.parametrize("name", ["B", "C"])
def test_b_and_c_as_lab_whites(name: str, observer: int) -> None:
    """``xyz_to_lab(x, "C")`` raised (issue 26); the white maps to L* = 100, and a colour
    agrees with colour-science's Lab under the same white."""
    from imageform.color import lab_to_xyz, xyz_to_lab

    white = whitepoint_xyz(name, observer=observer)
    np.testing.assert_allclose(xyz_to_lab(white, name, observer=observer), [100, 0, 0], atol=1e-9)
    colour = pytest.importorskip("colour")
    key = (
        "CIE 1931 2 Degree Standard Observer"
        if observer == 2
        else ("CIE 1964 10 Degree Standard Observer")
    )
    xyz = np.array([0.2, 0.15, 0.4])
    ref = colour.XYZ_to_Lab(xyz, colour.CCS_ILLUMINANTS[key][name])
    np.testing.assert_allclose(xyz_to_lab(xyz, name, observer=observer), ref, atol=1e-6)
    np.testing.assert_allclose(lab_to_xyz(ref, name, observer=observer), xyz, atol=1e-9)


@pytest.mark.parametrize("name", ["B", "C"])
def test_b_and_c_match_their_spectra(name: str) -> None:
    """The tabulated white is the chromaticity of the illuminant's own spectrum (the spectral
    table imageform ships, both observers)."""
    from imageform.color import xyz_to_xy
    from imageform.spectral import illuminant, spectrum_to_xyz

    for observer in (2, 10):
        xyz = spectrum_to_xyz(illuminant(name), illuminant=None, observer=observer)
        xy = tuple(np.asarray(xyz_to_xy(xyz)).tolist())
        # measured within 7e-5 (the spectra at 5 nm, the table from 1 nm data)
        assert xy == pytest.approx(whitepoint_xy(name, observer=observer), abs=1e-4)
