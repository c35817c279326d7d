"""Transfer functions: standard values, continuity at breakpoints, round trips, dtypes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color import (
    TRANSFER_FUNCTIONS,
    decode,
    encode,
    gamma_to_linear,
    linear_to_srgb,
    srgb_to_linear,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np


def test_srgb_gold_iec() -> None:
    # Gold: IEC 61966-2-1:1999 eq. (5)-(9): 1.0 -> 1.0, 0 -> 0, linear segment slope 12.92,
    # and the breakpoint 0.0031308 encodes to 0.04045 (to the standard's 5 decimals).
    assert float(srgb_to_linear(1.0)) == pytest.approx(1.0, abs=1e-15)
    assert float(srgb_to_linear(0.0)) == 0.0
    assert float(linear_to_srgb(0.0031308)) == pytest.approx(0.04045, abs=5e-6)
    assert float(srgb_to_linear(0.02)) == pytest.approx(0.02 / 12.92, abs=1e-15)
    # uint8 code 128 -> ((128/255 + 0.055)/1.055)^2.4 (the formula, evaluated)
    v = 128 / 255
    assert float(srgb_to_linear(np.uint8(128))) == pytest.approx(
        ((v + 0.055) / 1.055) ** 2.4, rel=1e-6
    )


def test_srgb_pieces_meet() -> None:
    t = 0.0031308
    below = float(linear_to_srgb(np.nextafter(t, 0)))
    above = float(linear_to_srgb(np.nextafter(t, 1)))
    assert abs(above - below) < 1e-7  # IEC's rounded constants leave a 1e-8-size step


def test_cross_check_colour_science() -> None:
    # Cross-check (colour-science 0.4.7): same definitions, agreement to 1e-12 in float64.
    colour = pytest.importorskip("colour")
    rng = np.random.default_rng(0)
    v = rng.uniform(0, 1, 1000)
    np.testing.assert_allclose(srgb_to_linear(v), colour.models.eotf_sRGB(v), atol=1e-12)
    np.testing.assert_allclose(linear_to_srgb(v), colour.models.eotf_inverse_sRGB(v), atol=1e-12)
    np.testing.assert_allclose(decode(v, "rec709"), colour.models.oetf_inverse_BT709(v), atol=1e-9)
    np.testing.assert_allclose(encode(v, "rec709"), colour.models.oetf_BT709(v), atol=1e-12)
    np.testing.assert_allclose(
        decode(v, "prophoto"), colour.models.cctf_decoding(v, "ProPhoto RGB"), atol=1e-12
    )
    # colour's BT.2020 default is the 10-bit (709-rounded) alpha/beta; with
    # is_12_bits_system=True it uses 1.0993/0.0181; ours are BT.2020-2's exact values.
    np.testing.assert_allclose(
        encode(v, "rec2020"), colour.models.oetf_BT2020(v, is_12_bits_system=True), atol=2e-5
    )
    np.testing.assert_allclose(
        decode(v, "adobe_rgb"), colour.models.gamma_function(v, 563 / 256), atol=1e-12
    )


def test_lecture_gamma_22() -> None:
    # The lecture: display gamma 2.2; mid-grey 0.5 encodes 0.5^2.2 = 0.2176 linear.
    assert float(gamma_to_linear(0.5)) == pytest.approx(0.5**2.2, rel=1e-12)
    assert float(gamma_to_linear(0.5, gamma=1.8)) == pytest.approx(0.5**1.8, rel=1e-12)


@pytest.mark.parametrize("name", TRANSFER_FUNCTIONS)
@settings(max_examples=50, deadline=None)
@given(v=st.floats(-0.5, 1.45, allow_nan=False))
def test_round_trip(name: str, v: float) -> None:
    back = float(decode(encode(v, name), name))
    assert back == pytest.approx(v, abs=1e-12, rel=1e-12)


@pytest.mark.parametrize("name", TRANSFER_FUNCTIONS)
def test_monotone_and_no_nan_outside_unit(name: str) -> None:
    v = np.linspace(-1, 2, 3001)
    for f in (decode, encode):
        out = f(v, name)
        assert np.all(np.isfinite(out))
        assert np.all(np.diff(out) > 0)


def test_dtypes() -> None:
    v = np.linspace(0, 1, 11)
    assert srgb_to_linear(v.astype(np.float32)).dtype == np.float32
    assert srgb_to_linear(v).dtype == np.float64
    assert srgb_to_linear(np.arange(256, dtype=np.uint8)).dtype == np.float32
    assert srgb_to_linear(np.arange(0, 65536, 257, dtype=np.uint16)).dtype == np.float32


def test_backends(xp_name: str) -> None:
    v = np.linspace(-0.1, 1.1, 25)
    for name in TRANSFER_FUNCTIONS:
        got = to_np(decode(to_backend(v, xp_name), name))
        np.testing.assert_allclose(got, decode(v, name), atol=1e-12)
        got = to_np(encode(to_backend(v, xp_name), name))
        np.testing.assert_allclose(got, encode(v, name), atol=1e-12)


def test_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="0-255"):
        srgb_to_linear(np.array([0.0, 128.0, 255.0]))
    with pytest.raises(InvalidInputError, match="NaN"):
        srgb_to_linear(np.array([0.0, np.nan]))
    with pytest.raises(UnknownOptionError, match="valid: 'adobe_rgb'"):
        decode(0.5, "srgbb")
    with pytest.raises(InvalidInputError, match="gamma > 0"):
        gamma_to_linear(0.5, gamma=0)
    with pytest.raises(InvalidInputError, match="int32"):
        srgb_to_linear(np.array([1, 2], dtype=np.int32))
