"""Palettes and palette_check: red-green fails where viridis and Okabe-Ito pass."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import OKABE_ITO, RED_GREEN, palette, palette_check, parse_colors, viridis
from imageform.errors import InvalidInputError, UnknownOptionError


def test_okabe_ito_and_viridis_data() -> None:
    """Okabe & Ito (2008): orange #E69F00, sky blue #56B4E9 ...; viridis endpoints as in
    matplotlib's _cm_listed (van der Walt & Smith 2015): #440154 and #FDE725."""
    assert OKABE_ITO["orange"] == "#E69F00" and len(OKABE_ITO) == 8
    v = viridis(256)
    assert np.allclose(v[0] * 255, [0x44, 0x01, 0x54], atol=0.5)
    assert np.allclose(v[-1] * 255, [0xFD, 0xE7, 0x25], atol=0.5)
    assert viridis(5).shape == (5, 3)


def test_cross_check_matplotlib_viridis() -> None:
    mpl = pytest.importorskip("matplotlib")
    assert np.allclose(viridis(256), np.asarray(mpl.colormaps["viridis"].colors), atol=1e-8)


def test_parse_colors() -> None:
    assert parse_colors("#fff, 000000").tolist() == [[1, 1, 1], [0, 0, 0]]
    assert parse_colors(["#E69F00"]).shape == (1, 3)
    assert parse_colors(np.array([[255, 0, 0]], np.uint8)).tolist() == [[1.0, 0.0, 0.0]]
    with pytest.raises(InvalidInputError, match="hex colour like"):
        parse_colors("#GG0000")
    with pytest.raises(InvalidInputError, match="hex colour"):
        parse_colors("#12345")
    with pytest.raises(InvalidInputError, match=r"\[0, 1\]"):
        parse_colors([[1.2, 0.0, 0.0]])


def test_red_green_fails_where_viridis_and_okabe_ito_pass() -> None:
    """The issue's demonstration at the default threshold ΔE00 = 10."""
    rg = palette_check(RED_GREEN)
    assert rg.passes["normal"] and not rg.passes["deutan"] and not rg.passes["protan"]
    assert rg.min_delta_e["deutan"] < 3.0  # the orange and the light green collapse
    for colors in (palette("okabe_ito"), palette("viridis", 5)):
        r = palette_check(colors)
        assert r.ok, r.min_delta_e
    d = rg.as_dict()
    assert d["ok"] is False and set(d["min_delta_e"]) == {"normal", "protan", "deutan", "tritan"}


def test_palette_check_matches_direct_computation() -> None:
    """min ΔE00 under normal vision equals the brute-force minimum over pairs."""
    from imageform.color.convert import convert
    from imageform.color.delta_e import delta_e_ciede2000

    cols = parse_colors("#E69F00,#56B4E9,#009E73")
    lab = np.asarray(convert(cols, "srgb", "lab"))
    pairs = [(0, 1), (0, 2), (1, 2)]
    want = min(float(delta_e_ciede2000(lab[i], lab[j])) for i, j in pairs)
    assert palette_check(cols).min_delta_e["normal"] == pytest.approx(want, abs=1e-12)


def test_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="at least 2 colours"):
        palette_check("#000000")
    with pytest.raises(UnknownOptionError, match="valid: 'okabe_ito', 'red_green', 'viridis'"):
        palette("jet")
    with pytest.raises(InvalidInputError, match="has 8 colours"):
        palette("okabe_ito", 9)
    with pytest.raises(InvalidInputError, match="1 <= n <= 256"):
        viridis(0)
    with pytest.raises(InvalidInputError, match="severity"):
        palette_check(RED_GREEN, severity=2)
