"""xy, u'v', the spectral locus and the visible region."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color import (
    check_in_locus,
    in_locus,
    polygon_area,
    spectral_locus,
    uv_prime_to_xy,
    visible_area,
    xy_to_uv_prime,
    xyz_to_uv_prime,
    xyz_to_xy,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np


def test_d65_uv_prime() -> None:
    """CIE 015:2018 Table T.3: D65 (2°) x, y = 0.31271, 0.32902; u', v' = 0.19783, 0.46832."""
    uv = xy_to_uv_prime([0.31271, 0.32902])
    assert uv == pytest.approx([0.19783, 0.46832], abs=2e-5)  # inputs rounded to 5 decimals
    assert uv_prime_to_xy(uv) == pytest.approx([0.31271, 0.32902], abs=1e-12)


def test_xyz_to_xy_and_black() -> None:
    assert xyz_to_xy([0.5, 0.5, 0.0]) == pytest.approx([0.5, 0.5])
    # black has no chromaticity: it gets the white's (as xyz_to_xyy does)
    assert xyz_to_xy([0.0, 0.0, 0.0], "D65") == pytest.approx([0.31271, 0.32902], abs=1e-5)
    assert xyz_to_uv_prime([[0.95047, 1.0, 1.08883]]).shape == (1, 2)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.05, 0.7), st.floats(0.05, 0.8))
def test_uv_round_trip(x: float, y: float) -> None:
    assert uv_prime_to_xy(xy_to_uv_prime([x, y])) == pytest.approx([x, y], abs=1e-12)


def test_backends(xp_name: str) -> None:
    xy = np.array([[0.3127, 0.329], [0.64, 0.33]])
    got = xy_to_uv_prime(to_backend(xy, xp_name))
    assert np.allclose(to_np(got), xy_to_uv_prime(xy), atol=1e-15)


def test_spectral_locus_values() -> None:
    """CIE 015:2018 Table 4 chromaticities: 520 nm (0.07430, 0.83380), 700 nm
    (0.73469, 0.26531), 450 nm (0.15664, 0.01771)."""
    wl, xy = spectral_locus()
    for w, want in (
        (520, (0.07430, 0.83380)),
        (700, (0.73469, 0.26531)),
        (450, (0.15664, 0.01771)),
    ):
        assert xy[wl == w][0] == pytest.approx(want, abs=1e-4)
    _, xy10 = spectral_locus(observer=10, coords="uv")
    assert xy10.shape == (401, 2)
    with pytest.raises(UnknownOptionError):
        spectral_locus(coords="lab")
    with pytest.raises(InvalidInputError, match="lo < hi"):
        spectral_locus(wavelength_range=(700, 400))


def test_visible_area_and_polygon() -> None:
    assert polygon_area([[0, 0], [2, 0], [2, 1], [0, 1]]) == 2.0
    assert 0.33 < visible_area("xy") < 0.34 and 0.19 < visible_area("uv") < 0.20
    with pytest.raises(InvalidInputError, match="N >= 3"):
        polygon_area([[0, 0], [1, 1]])


def test_in_locus() -> None:
    pts = np.array([[0.3127, 0.329], [0.7, 0.7], [0.08, 0.83], [0.05, 0.05]])
    assert in_locus(pts).tolist() == [True, False, True, False]
    assert in_locus(xy_to_uv_prime(pts), "uv").tolist() == [True, False, True, False]
    # every sRGB primary is real; Rec. 2020's are on the locus; ProPhoto's blue is not
    assert in_locus([[0.64, 0.33], [0.3, 0.6], [0.15, 0.06]]).all()
    assert not in_locus([[0.0366, 0.0001]])[0]
    with pytest.raises(InvalidInputError, match="outside the spectral locus"):
        check_in_locus([[0.3127, 0.329], [0.7, 0.7]])
    with pytest.raises(InvalidInputError, match="shape"):
        in_locus([0.3, 0.3, 0.3])


def test_xy_to_xyz_refuses_colours_outside_the_locus() -> None:
    from imageform.color import xy_to_xyz

    assert xy_to_xyz([0.31271, 0.32902], 0.5)[1] == 0.5
    assert xy_to_xyz([[0.64, 0.33], [0.3, 0.6]]).shape == (2, 3)
    with pytest.raises(InvalidInputError, match=r"\(0.8, 0.8\) lies outside the spectral locus"):
        xy_to_xyz([0.8, 0.8])
    assert xy_to_xyz([0.8, 0.8], check_locus=False)[0] == pytest.approx(1.0)
    with pytest.raises(InvalidInputError, match="Y >= 0"):
        xy_to_xyz([0.3, 0.3], -1.0)
    with pytest.raises(InvalidInputError, match="y > 0"):
        xy_to_xyz([0.3, 0.0], check_locus=False)


def test_dtypes() -> None:
    xy32 = np.array([[0.3127, 0.329]], dtype=np.float32)
    assert xy_to_uv_prime(xy32).dtype == np.float32
    assert uv_prime_to_xy(xy_to_uv_prime(xy32)).dtype == np.float32
    assert xy_to_uv_prime(np.array([[1, 2]], dtype=np.int64)).dtype == np.float64
    with pytest.raises(InvalidInputError, match="NaN"):
        xy_to_uv_prime([np.nan, 0.3])
