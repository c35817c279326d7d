"""RGB spaces: derived matrices against the standards' printed matrices and colour-science."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import (
    RGB_SPACES,
    linear_rgb_to_xyz,
    linear_srgb_to_xyz,
    resolve_white,
    rgb_to_xyz_matrix,
    xyz_to_linear_rgb,
    xyz_to_linear_srgb,
    xyz_to_rgb_matrix,
)
from imageform.color.rgb_spaces import RGBSpace, _npm
from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np


def test_srgb_matrix_gold_iec() -> None:
    # Gold: IEC 61966-2-1:1999 clause 5.2 prints the matrix to 4 decimals.
    iec = [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
    np.testing.assert_allclose(rgb_to_xyz_matrix("srgb"), iec, atol=5e-5)
    # and its inverse, clause 5.3: the standard inverts its *rounded* matrix, so the exact
    # inverse differs by up to 3.7e-4 (R row): tolerance 5e-4.
    iec_inv = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]
    np.testing.assert_allclose(xyz_to_rgb_matrix("srgb"), iec_inv, atol=5e-4)


def test_derivation_reproduces_lindbloom() -> None:
    # Gold: Lindbloom, "RGB/XYZ Matrices" (brucelindbloom.com), sRGB with his D65 white
    # XYZ (0.95047, 1, 1.08883), printed to 7 decimals.
    w = np.array([0.95047, 1.0, 1.08883])
    xy_w = (w[0] / w.sum(), w[1] / w.sum())
    m = _npm(RGB_SPACES["srgb"].primaries_xy, xy_w)
    lind = [
        [0.4124564, 0.3575761, 0.1804375],
        [0.2126729, 0.7151522, 0.0721750],
        [0.0193339, 0.1191920, 0.9503041],
    ]
    np.testing.assert_allclose(m, lind, atol=5e-8)


def test_adobe_matrix_gold() -> None:
    # Gold: Adobe RGB (1998) Color Image Encoding v2005-05, clause 4.3.4.1 (4 decimals).
    adobe = [[0.5767, 0.1856, 0.1882], [0.2974, 0.6273, 0.0753], [0.0270, 0.0707, 0.9911]]
    # The spec derives it from its white XYZ rounded to (0.9505, 1, 1.0891); from the exact xy
    # (0.3127, 0.3290) the Z row differs by 2.4e-4: tolerance 3e-4.
    np.testing.assert_allclose(rgb_to_xyz_matrix("adobe_rgb"), adobe, atol=3e-4)


@pytest.mark.parametrize(
    ("ours", "theirs"),
    [
        ("srgb", "sRGB"),
        ("adobe_rgb", "Adobe RGB (1998)"),
        ("display_p3", "Display P3"),
        ("rec2020", "ITU-R BT.2020"),
        ("prophoto", "ProPhoto RGB"),
        ("rec709", "ITU-R BT.709"),
    ],
)
def test_cross_check_colour_science(ours: str, theirs: str) -> None:
    # Cross-check: colour.normalised_primary_matrix on the same primaries and white (1e-12).
    colour = pytest.importorskip("colour")
    cs = colour.RGB_COLOURSPACES[theirs]
    np.testing.assert_allclose(np.array(RGB_SPACES[ours].primaries_xy), cs.primaries, atol=0)
    np.testing.assert_allclose(RGB_SPACES[ours].white_xy, cs.whitepoint, atol=0)
    ref = colour.normalised_primary_matrix(cs.primaries, cs.whitepoint)
    np.testing.assert_allclose(rgb_to_xyz_matrix(ours), ref, atol=1e-12)


@pytest.mark.parametrize("space", list(RGB_SPACES))
def test_white_maps_to_white(space: str) -> None:
    xyz = linear_rgb_to_xyz(np.ones(3), space)
    np.testing.assert_allclose(xyz, resolve_white(space), atol=1e-12)
    np.testing.assert_allclose(xyz_to_linear_rgb(xyz, space), np.ones(3), atol=1e-12)


def test_round_trip_and_shapes() -> None:
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (4, 5, 3))
    y = linear_srgb_to_xyz(x)
    assert y.shape == (4, 5, 3)
    np.testing.assert_allclose(xyz_to_linear_srgb(y), x, atol=1e-12)
    assert linear_srgb_to_xyz(x.astype(np.float32)).dtype == np.float32


def test_backends(xp_name: str) -> None:
    rng = np.random.default_rng(2)
    x = rng.uniform(0, 1, (6, 3))
    got = to_np(linear_srgb_to_xyz(to_backend(x, xp_name)))
    np.testing.assert_allclose(got, linear_srgb_to_xyz(x), atol=1e-12)


def test_errors() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'adobe_rgb'"):
        rgb_to_xyz_matrix("srgbx")
    with pytest.raises(InvalidInputError, match="alpha"):
        linear_srgb_to_xyz(np.zeros((2, 2, 4)))
    bad = RGBSpace("bad", ((0.1, 0.1), (0.2, 0.2), (0.3, 0.3)), (0.3127, 0.329), "srgb", "-")
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        rgb_to_xyz_matrix(bad)


def test_rgb_space_by_name_and_alias() -> None:
    from imageform.color import RGB_SPACES, rgb_space

    assert rgb_space("srgb") is RGB_SPACES["srgb"]
    for alias, key in (
        ("Display-P3", "display_p3"),
        ("p3", "display_p3"),
        ("Adobe-RGB-1998", "adobe_rgb"),
        ("BT.2020", "rec2020"),
        ("ROMM", "prophoto"),
    ):
        assert rgb_space(alias) is RGB_SPACES[key], alias
    custom = RGBSpace("mine", ((0.7, 0.3), (0.2, 0.7), (0.15, 0.05)), (0.3127, 0.329), "srgb", "-")
    assert rgb_space(custom) is custom
    with pytest.raises(UnknownOptionError, match="unknown RGB space 'cmyk'; valid: "):
        rgb_space("cmyk")
