"""CIELAB / LCh / xyY / CIELUV: gold values, colour-science cross-checks, round trips."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.color import (
    lab_to_lch,
    lab_to_xyz,
    lch_to_lab,
    luv_to_xyz,
    resolve_white,
    whitepoint_xy,
    xyy_to_xyz,
    xyz_to_lab,
    xyz_to_luv,
    xyz_to_xyy,
)
from imageform.errors import InvalidInputError
from tests.helpers import to_backend, to_np


def test_gold_white_and_black() -> None:
    # Gold (CIE 15:2004 clause 8.2.1 by definition): the white is L* = 100, a* = b* = 0;
    # black is L* = 0; the linear segment meets the cube root at Y/Yn = (6/29)^3 (L* = 8).
    for w in ("D65", "D50", "A", "F11"):
        np.testing.assert_allclose(xyz_to_lab(resolve_white(w), w), [100, 0, 0], atol=1e-12)
        np.testing.assert_allclose(xyz_to_luv(resolve_white(w), w), [100, 0, 0], atol=1e-12)
    np.testing.assert_allclose(xyz_to_lab(np.zeros(3)), [0, 0, 0], atol=1e-12)
    t = (6 / 29) ** 3
    assert float(xyz_to_lab([t, t, t], "E")[0]) == pytest.approx(8.0, abs=1e-12)


def test_gold_lindbloom_lab() -> None:
    # Gold: Lindbloom's "XYZ to Lab" equations, L* for Y = 0.18 (mid grey) = 49.496 (116
    # * 0.18^(1/3) - 16), and Y = 0.5 -> 76.0693; a*, b* 0 for neutral under E.
    np.testing.assert_allclose(xyz_to_lab([0.18] * 3, "E"), [49.4961, 0, 0], atol=5e-5)
    np.testing.assert_allclose(xyz_to_lab([0.5] * 3, "E"), [76.0693, 0, 0], atol=5e-5)


@pytest.mark.parametrize("white", ["D65", "D50", "A"])
def test_cross_check_colour_science(white: str) -> None:
    # Cross-check (colour-science 0.4.7) with the same white xy: agreement to 1e-9 in float64.
    colour = pytest.importorskip("colour")
    rng = np.random.default_rng(3)
    xyz = rng.uniform(0, 1, (500, 3))
    xyz[:10] *= 0.005  # hit the linear segment
    xy = whitepoint_xy(white)
    np.testing.assert_allclose(xyz_to_lab(xyz, white), colour.XYZ_to_Lab(xyz, xy), atol=1e-9)
    np.testing.assert_allclose(xyz_to_luv(xyz, white), colour.XYZ_to_Luv(xyz, xy), atol=1e-9)
    lab = colour.XYZ_to_Lab(xyz, xy)
    np.testing.assert_allclose(lab_to_xyz(lab, white), colour.Lab_to_XYZ(lab, xy), atol=1e-12)
    np.testing.assert_allclose(lab_to_lch(lab), colour.Lab_to_LCHab(lab), atol=1e-9)
    np.testing.assert_allclose(xyz_to_xyy(xyz), colour.XYZ_to_xyY(xyz), atol=1e-12)


xyz_strategy = arrays(np.float64, (3,), elements=st.floats(0.0, 1.2))


@settings(max_examples=100, deadline=None)
@given(xyz=xyz_strategy)
def test_round_trips(xyz: np.ndarray) -> None:
    np.testing.assert_allclose(lab_to_xyz(xyz_to_lab(xyz)), xyz, atol=1e-12)
    if xyz[1] > 1e-3:  # Luv and xyY lose X, Z where Y = 0: only physical colours invert
        np.testing.assert_allclose(luv_to_xyz(xyz_to_luv(xyz)), xyz, atol=1e-9)
        np.testing.assert_allclose(xyy_to_xyz(xyz_to_xyy(xyz)), xyz, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(lab=arrays(np.float64, (3,), elements=st.floats(-120, 120)))
def test_lch_round_trip(lab: np.ndarray) -> None:
    lch = lab_to_lch(lab)
    assert 0 <= lch[2] < 360
    np.testing.assert_allclose(lch_to_lab(lch), lab, atol=1e-9)


def test_black_conventions() -> None:
    xyy = xyz_to_xyy(np.zeros(3), "D65")
    np.testing.assert_allclose(xyy, [*whitepoint_xy("D65"), 0.0], atol=1e-12)
    np.testing.assert_allclose(xyy_to_xyz(xyy), 0.0)
    np.testing.assert_allclose(xyz_to_luv(np.zeros(3)), 0.0)
    np.testing.assert_allclose(luv_to_xyz(np.zeros(3)), 0.0)


def test_dtypes_and_shapes() -> None:
    x = np.full((2, 3, 3), 0.3, dtype=np.float32)
    assert xyz_to_lab(x).dtype == np.float32
    assert xyz_to_lab(x).shape == (2, 3, 3)
    assert xyz_to_lab(x.astype(np.float64)).dtype == np.float64


def test_backends(xp_name: str) -> None:
    rng = np.random.default_rng(4)
    xyz = rng.uniform(0, 1, (8, 3))
    for f, g in ((xyz_to_lab, lab_to_xyz), (xyz_to_luv, luv_to_xyz)):
        fwd = to_np(f(to_backend(xyz, xp_name), "D50"))
        np.testing.assert_allclose(fwd, f(xyz, "D50"), atol=1e-10)
        back = to_np(g(to_backend(fwd, xp_name), "D50"))
        np.testing.assert_allclose(back, xyz, atol=1e-10)


def test_errors() -> None:
    with pytest.raises(InvalidInputError, match=r"3 channels"):
        xyz_to_lab(np.zeros((4, 2)))
    with pytest.raises(InvalidInputError, match="NaN"):
        xyz_to_lab([np.nan, 0, 0])
