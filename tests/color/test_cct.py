"""Tests of imageform.color.cct: Robertson (1968), the CIE daylight locus, Duv."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color.cct import (
    ROBERTSON_1968,
    cct_to_xy,
    uv1960_to_xy,
    xy_to_cct,
    xy_to_uv1960,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np

# CIE 15:2004 Table T.3 (2° observer) and §3.1: A is 2856 K, D65 about 6504 K, D50 about
# 5003 K (nominal 6500/5000 K times 1.4388/1.4380).
XY_A = (0.44757, 0.40745)
XY_D65 = (0.31272, 0.32903)
XY_D50 = (0.34567, 0.35850)


def test_illuminant_a_and_d65_cct_cie15() -> None:
    """CIE 15:2004: A = 2856 K, D65 ≈ 6504 K; Robertson's interpolation is good to ~1 K."""
    cct, duv = xy_to_cct(XY_A)
    assert float(cct) == pytest.approx(2856.0, abs=1.0)
    assert abs(float(duv)) < 1e-4  # A is a Planckian radiator
    cct, duv = xy_to_cct(XY_D65)
    assert float(cct) == pytest.approx(6504.0, abs=2.0)
    assert float(duv) == pytest.approx(0.0032, abs=2e-4)  # daylight lies above the locus


def test_robertson_table_rows_are_reproduced() -> None:
    """Wyszecki & Stiles Table 1(3.11): at each tabulated temperature the locus is (u_i, v_i)."""
    mired = ROBERTSON_1968[1:, 0]
    xy = cct_to_xy(1.0e6 / mired)
    np.testing.assert_allclose(xy_to_uv1960(xy), ROBERTSON_1968[1:, 1:3], atol=1e-12)


def test_daylight_locus_cie15() -> None:
    """CIE 15:2004 eq. (3.3)-(3.4) at the D65/D50 temperatures vs Table T.3 (5 decimals; the
    table is computed from the tabulated SPDs, so the locus agrees to about 1e-4)."""
    t65 = 6500 * 1.4388 / 1.4380
    t50 = 5000 * 1.4388 / 1.4380
    np.testing.assert_allclose(cct_to_xy(t65, method="daylight"), XY_D65, atol=1e-4)
    np.testing.assert_allclose(cct_to_xy(t50, method="daylight"), XY_D50, atol=2e-4)
    cct, _ = xy_to_cct(cct_to_xy(t65, method="daylight"), method="daylight")
    assert float(cct) == pytest.approx(t65, abs=1e-8)


def test_uv1960_round_trip_and_value() -> None:
    """CIE 1960 UCS of D65 (CIE 15:2004 §8.1 formula)."""
    uv = xy_to_uv1960(XY_D65)
    np.testing.assert_allclose(uv, [0.19783, 0.31222], atol=1e-5)
    np.testing.assert_allclose(uv1960_to_xy(uv), XY_D65, atol=1e-15)


@settings(max_examples=50, deadline=None)
@given(st.floats(1700.0, 40000.0), st.floats(-0.02, 0.02))
def test_robertson_round_trip(cct: float, duv: float) -> None:
    """xy_to_cct(cct_to_xy(T, Duv)) ≈ (T, Duv): Robertson's forward (linear in mired along the
    locus) and inverse (distance ratio) interpolations differ by at most ~2e-5 relative."""
    t2, d2 = xy_to_cct(cct_to_xy(cct, duv))
    assert float(t2) == pytest.approx(cct, rel=3e-5)
    assert float(d2) == pytest.approx(duv, abs=1e-7)


def test_cross_check_colour_science_robertson_and_daylight() -> None:
    """Cross-check: colour-science 0.4.7 implements the same table and interpolation."""
    colour = pytest.importorskip("colour")
    rng = np.random.default_rng(0)
    T = rng.uniform(1700, 50000, 500)
    D = rng.uniform(-0.02, 0.02, 500)
    xy = cct_to_xy(T, D)
    ref_uv = colour.temperature.CCT_to_uv_Robertson1968(np.stack([T, D], -1))
    np.testing.assert_allclose(xy_to_uv1960(xy), ref_uv, atol=1e-12)
    cct, duv = xy_to_cct(xy)
    ref = colour.temperature.uv_to_CCT_Robertson1968(ref_uv)
    np.testing.assert_allclose(cct, ref[:, 0], rtol=1e-10)
    np.testing.assert_allclose(duv, ref[:, 1], atol=1e-12)
    Td = rng.uniform(4000, 25000, 200)
    np.testing.assert_allclose(
        cct_to_xy(Td, method="daylight"), colour.temperature.CCT_to_xy_CIE_D(Td), atol=1e-12
    )


def test_shapes_and_dtypes() -> None:
    xy = cct_to_xy(np.full((2, 3), 5000.0))
    assert xy.shape == (2, 3, 2)
    cct, _duv = xy_to_cct(xy.astype(np.float32))
    assert cct.shape == (2, 3) and cct.dtype == np.float32
    np.testing.assert_allclose(cct, 5000.0, rtol=1e-4)


def test_backends(xp_name: str) -> None:
    xy = np.array([XY_A, XY_D65, XY_D50])
    cct, duv = xy_to_cct(to_backend(xy, xp_name))
    ref_c, ref_d = xy_to_cct(xy)
    np.testing.assert_allclose(to_np(cct), ref_c, rtol=1e-12)
    np.testing.assert_allclose(to_np(duv), ref_d, atol=1e-14)
    back = cct_to_xy(to_backend(ref_c, xp_name), to_backend(ref_d, xp_name))
    np.testing.assert_allclose(to_np(back), cct_to_xy(ref_c, ref_d), atol=1e-14)


def test_bad_inputs() -> None:
    with pytest.raises(InvalidInputError, match="outside the range of the robertson1968"):
        cct_to_xy(1000.0)
    with pytest.raises(InvalidInputError, match=r"outside the range of the daylight method"):
        cct_to_xy(3000.0, method="daylight")
    with pytest.raises(InvalidInputError, match="takes no duv"):
        cct_to_xy(6500.0, 0.01, method="daylight")
    with pytest.raises(InvalidInputError, match="outside the range of Robertson"):
        xy_to_cct([0.6, 0.38])  # redder than 1667 K
    with pytest.raises(InvalidInputError, match="outside the daylight locus"):
        xy_to_cct(XY_A, method="daylight")
    with pytest.raises(UnknownOptionError, match="'daylight', 'hernandez1999', 'mccamy1992'"):
        xy_to_cct(XY_D65, method="mccamy")
    with pytest.raises(InvalidInputError, match="NaN"):
        xy_to_cct([np.nan, 0.3])
    with pytest.raises(InvalidInputError, match=r"shape \(\.\.\., 2\)"):
        xy_to_cct([0.3, 0.3, 0.4])
