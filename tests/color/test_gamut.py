"""Gamut triangles, area, coverage, in_gamut, gamut mapping."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color import (
    gamut_area,
    gamut_coverage,
    gamut_figures,
    gamut_map,
    gamut_triangle,
    in_gamut,
    lab_to_lch,
    linear_rgb_to_xyz,
    visible_area,
    xyz_to_lab,
    xyz_to_rgb_matrix,
)
from imageform.errors import InvalidInputError, UnknownOptionError


def test_triangle_areas_from_primaries() -> None:
    """Shoelace on the standards' primaries: sRGB 0.11205, Display P3 0.15200, Rec. 2020
    0.2118665, Adobe RGB 0.15115 (xy; exact arithmetic on the published chromaticities)."""
    assert gamut_area("srgb") == pytest.approx(0.11205, abs=1e-12)
    assert gamut_area("display-p3") == pytest.approx(0.152, abs=1e-12)
    assert gamut_area("rec2020") == pytest.approx(0.2118665, abs=1e-12)
    assert gamut_area("adobe_rgb") == pytest.approx(0.15115, abs=1e-12)
    assert gamut_triangle("srgb", "uv").shape == (3, 2)


def test_srgb_covers_about_a_third() -> None:
    """The lecture says ~35 %; the data give 33.5 % (xy) and 33.2 % (u'v')."""
    assert gamut_coverage("srgb", "xy") == pytest.approx(33.5, abs=0.1)
    assert gamut_coverage("srgb", "uv") == pytest.approx(33.2, abs=0.1)
    c = [gamut_coverage(s) for s in ("srgb", "display_p3", "rec2020")]
    assert c[0] < c[1] < c[2] < 100


def test_coverage_vs_area_ratio() -> None:
    """Inside the locus, coverage = area ratio; ProPhoto's imaginary primaries make the
    ratio exceed the coverage."""
    for f in gamut_figures(["srgb", "prophoto"]):
        if f.space == "sRGB":
            assert f.coverage_xy == pytest.approx(f.area_ratio_xy, abs=1e-9)
        else:
            assert f.area_ratio_xy > f.coverage_xy
    assert gamut_figures(["srgb"])[0].area_xy / visible_area("xy") * 100 == pytest.approx(
        33.5, abs=0.1
    )


def test_in_gamut() -> None:
    p3_green = linear_rgb_to_xyz([0.0, 1.0, 0.0], "display_p3")
    assert not in_gamut(p3_green, "srgb") and in_gamut(p3_green, "display_p3")
    assert in_gamut(p3_green, "rec2020")
    assert in_gamut([[0.3127, 0.329], [0.17, 0.797], [0.7, 0.29]], kind="xy").tolist() == [
        True,
        False,
        False,
    ]
    assert in_gamut([[0.5, 0.5, 1.2]], kind="linear_rgb").tolist() == [False]
    with pytest.raises(UnknownOptionError, match="gamut test kind"):
        in_gamut([0.1, 0.1, 0.1], kind="lab")
    with pytest.raises(UnknownOptionError, match="RGB space"):
        in_gamut([0.1, 0.1, 0.1], "ntsc")


def test_gamut_mapping() -> None:
    rng = np.random.default_rng(0)
    rgb2020 = rng.random((200, 3))
    xyz = linear_rgb_to_xyz(rgb2020, "rec2020")
    inside = in_gamut(xyz, "srgb")
    for method in ("clip", "lch_chroma"):
        out = gamut_map(xyz, "srgb", method=method)
        assert out.min() >= 0 and out.max() <= 1
        # in-gamut colours are untouched
        want = xyz[inside] @ xyz_to_rgb_matrix("srgb").T
        assert np.allclose(out[inside], want, atol=1e-12)
    # hue-preserving: L* and h kept, C* reduced (for L* within [0, 100])
    out = gamut_map(xyz, "srgb", method="lch_chroma")
    lch_in = np.asarray(lab_to_lch(xyz_to_lab(xyz, (0.3127, 0.329))))
    lch_out = np.asarray(lab_to_lch(xyz_to_lab(linear_rgb_to_xyz(out, "srgb"), (0.3127, 0.329))))
    ok = ~inside & (lch_in[:, 0] <= 100) & (lch_out[:, 1] > 1)
    dh = (lch_out[ok, 2] - lch_in[ok, 2] + 180) % 360 - 180
    assert np.max(np.abs(lch_out[ok, 0] - lch_in[ok, 0])) < 1e-6
    assert np.max(np.abs(dh)) < 1e-6
    assert np.all(lch_out[ok, 1] <= lch_in[ok, 1] + 1e-9)
    # the mapped colour sits on the boundary: a little more chroma leaves the gamut
    clip_hue = np.asarray(
        lab_to_lch(
            xyz_to_lab(linear_rgb_to_xyz(gamut_map(xyz, method="clip"), "srgb"), (0.3127, 0.329))
        )
    )
    assert (
        np.max(np.abs((clip_hue[ok, 2] - lch_in[ok, 2] + 180) % 360 - 180)) > 1.0
    )  # clipping shifts hue


def test_gamut_map_bad_input() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'clip', 'lch_chroma'"):
        gamut_map([0.1, 0.2, 0.3], method="compress")
    with pytest.raises(InvalidInputError, match="iterations"):
        gamut_map([0.1, 0.2, 0.3], iterations=0)
    with pytest.raises(InvalidInputError, match="shape"):
        gamut_map([0.1, 0.2])


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-0.3, 1.3), min_size=3, max_size=3))
def test_lch_mapping_is_idempotent(rgb2020: list[float]) -> None:
    """Property: a mapped colour is in gamut, so mapping it again leaves it unchanged."""
    xyz = linear_rgb_to_xyz(np.array(rgb2020), "rec2020")
    once = gamut_map(xyz, "srgb")
    assert in_gamut(once, kind="linear_rgb")
    twice = gamut_map(linear_rgb_to_xyz(once, "srgb"), "srgb")
    assert np.allclose(twice, once, atol=1e-9)
