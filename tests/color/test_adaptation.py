"""Tests of imageform.color.adaptation: gold matrices, peer cross-checks, properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color.adaptation import (
    CAT_MATRICES,
    chromatic_adaptation,
    chromatic_adaptation_matrix,
)
from imageform.color.whitepoints import whitepoint_xyz
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np

METHODS = sorted(CAT_MATRICES)
# Lindbloom, "Chromatic Adaptation" (brucelindbloom.com): his D65 and D50 whites and the
# D65 -> D50 matrices, printed to 7 decimals.
LB_D65 = (0.95047, 1.0, 1.08883)
LB_D50 = (0.96422, 1.0, 0.82521)
LB_BRADFORD = [
    [1.0478112, 0.0228866, -0.0501270],
    [0.0295424, 0.9904844, -0.0170491],
    [-0.0092345, 0.0150436, 0.7521316],
]
LB_VON_KRIES = [
    [1.0160803, 0.0552297, -0.0521326],
    [0.0060666, 0.9955661, -0.0012235],
    [0.0000000, 0.0000000, 0.7578869],
]
LB_XYZ_SCALING = [
    [1.0144665, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 0.7578869],
]


@pytest.mark.parametrize(
    ("method", "gold"),
    [("bradford", LB_BRADFORD), ("von_kries", LB_VON_KRIES), ("xyz_scaling", LB_XYZ_SCALING)],
)
def test_lindbloom_d65_to_d50_matrices(method: str, gold: list[list[float]]) -> None:
    """Lindbloom's published D65 -> D50 matrices, to his 7 decimals."""
    M = chromatic_adaptation_matrix(LB_D65, LB_D50, method)
    np.testing.assert_allclose(M, gold, atol=5e-8)


@pytest.mark.parametrize("method", METHODS)
def test_white_maps_to_white_and_inverse(method: str) -> None:
    """Complete adaptation maps the source white onto the destination white; the reverse
    matrix is the inverse (the von Kries model, Fairchild ch. 9)."""
    ws, wd = whitepoint_xyz("A"), whitepoint_xyz("D65")
    np.testing.assert_allclose(chromatic_adaptation(ws, "A", "D65", method), wd, atol=1e-12)
    M = chromatic_adaptation_matrix("A", "D65", method)
    Mi = chromatic_adaptation_matrix("D65", "A", method)
    np.testing.assert_allclose(M @ Mi, np.eye(3), atol=1e-12)


def test_degree_of_adaptation() -> None:
    """CIE 159:2004: D = 0 is no adaptation (identity); D interpolates the gains linearly."""
    np.testing.assert_allclose(
        chromatic_adaptation_matrix("A", "D65", "cat02", degree=0.0), np.eye(3), atol=1e-15
    )
    full = chromatic_adaptation_matrix("A", "D65", "cat02")
    half = chromatic_adaptation_matrix("A", "D65", "cat02", degree=0.5)
    np.testing.assert_allclose(half, 0.5 * (full + np.eye(3)), atol=1e-14)


@pytest.mark.parametrize(
    ("method", "peer"),
    [
        ("xyz_scaling", "XYZ Scaling"),
        ("von_kries", "Von Kries"),
        ("bradford", "Bradford"),
        ("cat02", "CAT02"),
        ("cat16", "CAT16"),
    ],
)
def test_cross_check_colour_science(method: str, peer: str) -> None:
    """Cross-check: colour-science 0.4.7 matrix_chromatic_adaptation_VonKries (same model)."""
    colour = pytest.importorskip("colour")
    ws, wd = whitepoint_xyz("F2"), whitepoint_xyz("D50", observer=10)
    ref = colour.adaptation.matrix_chromatic_adaptation_VonKries(ws, wd, transform=peer)
    np.testing.assert_allclose(chromatic_adaptation_matrix(ws, wd, method), ref, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.0, 1.5), min_size=3, max_size=3), st.sampled_from(METHODS))
def test_round_trip(xyz: list[float], method: str) -> None:
    there = chromatic_adaptation(xyz, "D65", "F11", method)
    back = chromatic_adaptation(there, "F11", "D65", method)
    np.testing.assert_allclose(back, xyz, atol=1e-12)


def test_shapes_dtypes_backends(xp_name: str) -> None:
    rng = np.random.default_rng(0)
    img = rng.uniform(0, 1, (4, 5, 3))
    ref = chromatic_adaptation(img, "D65", "D50")
    assert ref.shape == (4, 5, 3) and ref.dtype == np.float64
    assert chromatic_adaptation(img.astype(np.float32), "D65", "D50").dtype == np.float32
    got = chromatic_adaptation(to_backend(img, xp_name), "D65", "D50")
    np.testing.assert_allclose(to_np(got), ref, atol=1e-14)


def test_bad_inputs() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'bradford', 'cat02'"):
        chromatic_adaptation_matrix("D65", "D50", "sharp")
    with pytest.raises(InvalidInputError, match=r"D in \[0, 1\]"):
        chromatic_adaptation_matrix("D65", "D50", degree=1.5)
    with pytest.raises(UnknownOptionError, match="unknown white"):
        chromatic_adaptation_matrix("D66", "D50")
    with pytest.raises(InvalidInputError, match="NaN"):
        chromatic_adaptation([np.nan, 1.0, 1.0], "D65", "D50")
    with pytest.raises(InvalidInputError, match=r"shape \(\.\.\., 3\)"):
        chromatic_adaptation([1.0, 1.0], "D65", "D50")
