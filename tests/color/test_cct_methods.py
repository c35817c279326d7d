"""McCamy (1992), Hernández-Andrés (1999), Ohno (2013) CCT; the daylight method's ends.

Gold: colour-science 0.4.7's own test vectors (colour/temperature/tests/test_mccamy1992.py,
test_hernandez1999.py, test_ohno2013.py), copied here as numbers.
Peer: colour-science's implementations on random chromaticities around the locus.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imageform.color import xy_to_cct
from imageform.color.cct import _DAYLIGHT_RANGE, _daylight_x
from imageform.color.cct_methods import (
    cct_to_uv_ohno2013,
    planckian_uv,
    uv_to_cct_ohno2013,
    xy_to_cct_hernandez1999,
    xy_to_cct_mccamy1992,
)
from imageform.errors import InvalidInputError, UnknownOptionError


def test_mccamy1992_colour_science_vectors() -> None:
    xy = [[0.31270, 0.32900], [0.44757, 0.40745], [0.252520939374083, 0.252220883926284]]
    want = [6505.08059131, 2857.28961266, 19501.61953130]
    np.testing.assert_allclose(xy_to_cct_mccamy1992(xy), want, atol=1e-7)


def test_hernandez1999_colour_science_vectors() -> None:
    xy = [[0.31270, 0.32900], [0.44757, 0.40745], [0.244162248213914, 0.240333674758318]]
    want = [6500.74204318, 2790.64222533, 64448.11092565]  # the last one: the > 50000 K branch
    np.testing.assert_allclose(xy_to_cct_hernandez1999(xy), want, atol=1e-7)


def test_ohno2013_colour_science_vectors() -> None:
    uv = [[0.1978, 0.3122], [0.4328, 0.2883], [0.2927, 0.2722]]
    cct, duv = uv_to_cct_ohno2013(uv)
    # |Duv| >= 0.002 in all three: the parabolic solution
    np.testing.assert_allclose(
        cct, [6507.474788799616, 1041.678320000468, 2444.971818951083], atol=1e-6
    )
    np.testing.assert_allclose(
        duv, [0.003223346337596, -0.067378053475797, -0.084370641205118], atol=1e-9
    )
    back = cct_to_uv_ohno2013(
        [6507.47380460, 1041.68315360, 2452.15316417], [0.00322335, -0.06737802, -0.08437064]
    )
    np.testing.assert_allclose(
        back,
        [[0.19779997, 0.31219997], [0.43279885, 0.28830013], [0.29247364, 0.27215157]],
        atol=1e-7,
    )
    np.testing.assert_allclose(planckian_uv(6504), [0.2004280, 0.3103334], atol=1e-7)


def test_ohno2013_triangular_branch_on_the_locus() -> None:
    """On the locus (|Duv| < 0.002: the triangular solution) Ohno inverts the Planckian uv."""
    t = np.array([1500.0, 2856.0, 4000.0, 6504.0, 10000.0, 25000.0])
    cct, duv = uv_to_cct_ohno2013(planckian_uv(t))
    np.testing.assert_allclose(cct, t, rtol=2e-5)
    np.testing.assert_allclose(duv, 0.0, atol=1e-6)
    cct, duv = uv_to_cct_ohno2013(cct_to_uv_ohno2013(t, 0.001))
    np.testing.assert_allclose(cct, t, rtol=5e-5)
    np.testing.assert_allclose(duv, 0.001, atol=1e-6)


def test_cross_check_colour_science_random() -> None:
    temp = pytest.importorskip("colour.temperature")
    rng = np.random.default_rng(5)
    t = rng.uniform(2000, 20000, 40)
    d = rng.uniform(-0.02, 0.02, 40)
    uv = cct_to_uv_ohno2013(t, d)
    ref = np.array([temp.uv_to_CCT_Ohno2013(p) for p in uv])
    cct, duv = uv_to_cct_ohno2013(uv)
    np.testing.assert_allclose(cct, ref[:, 0], rtol=1e-9)
    np.testing.assert_allclose(duv, ref[:, 1], atol=1e-12)
    xy = (
        np.stack([3 * uv[:, 0], 2 * uv[:, 1]], axis=-1) / (2 * uv[:, 0] - 8 * uv[:, 1] + 4)[:, None]
    )
    np.testing.assert_allclose(xy_to_cct_mccamy1992(xy), temp.xy_to_CCT_McCamy1992(xy), rtol=1e-12)
    np.testing.assert_allclose(
        xy_to_cct_hernandez1999(xy), temp.xy_to_CCT_Hernandez1999(xy), rtol=1e-12
    )
    np.testing.assert_allclose(
        cct_to_uv_ohno2013(t, d),
        [temp.CCT_to_uv_Ohno2013([a, b]) for a, b in zip(t, d, strict=True)],
        atol=1e-12,
    )


@pytest.mark.parametrize("method", ["mccamy1992", "hernandez1999", "ohno2013"])
def test_selectable_through_xy_to_cct(method: str) -> None:
    """CIE illuminant A (2856 K) and D65 (6504 K), xy from CIE 15:2004 Table T.3."""
    cct, duv = xy_to_cct([[0.44757, 0.40745], [0.31271, 0.32902]], method=method)
    tol = {"mccamy1992": 3.0, "hernandez1999": 70.0, "ohno2013": 1.0}[method]
    np.testing.assert_allclose(cct, [2856.0, 6504.0], atol=tol)
    np.testing.assert_allclose(duv, [0.0, 0.0032], atol=2e-4)
    with pytest.raises(UnknownOptionError, match="CCT method"):
        xy_to_cct([0.3, 0.3], method="mccamy")


def test_ohno2013_bad_spacing() -> None:
    with pytest.raises(InvalidInputError, match="spacing > 1"):
        uv_to_cct_ohno2013([0.2, 0.3], spacing=1.0)
    # the ends of the table are inside; beyond them, an error naming the range
    t, _ = uv_to_cct_ohno2013(planckian_uv(np.array([1000.0, 100000.0])))
    np.testing.assert_allclose(t, [1000.0, 100000.0], rtol=1e-6)
    with pytest.raises(InvalidInputError, match="outside the range of the ohno2013 method"):
        uv_to_cct_ohno2013(planckian_uv(800.0))
    with pytest.raises(InvalidInputError, match="expected cct in"):
        planckian_uv(-1.0)


def test_daylight_accepts_the_ends_of_the_locus() -> None:
    """Issue 17: a point one ulp outside the locus' ends must not fail a whole batch."""
    lo_x = float(_daylight_x(np, np.asarray(_DAYLIGHT_RANGE[1])))
    hi_x = float(_daylight_x(np, np.asarray(_DAYLIGHT_RANGE[0])))
    xy = [[math.nextafter(lo_x, 0.0), 0.25], [math.nextafter(hi_x, 1.0), 0.38], [0.3127, 0.329]]
    cct, _ = xy_to_cct(xy, method="daylight")
    np.testing.assert_allclose(cct[:2], [25000.0, 4000.0], rtol=1e-9)
    with pytest.raises(InvalidInputError, match="outside the daylight locus"):
        xy_to_cct([[lo_x - 1e-6, 0.25]], method="daylight")


def test_ohno2013_correction_for_the_one_percent_table() -> None:
    """Ohno's 0.99991 compensates the bias of a 1 % table (measured +7e-5 .. +8e-5 median)."""
    t = np.geomspace(2000, 20000, 30)
    for d in (0.0005, 0.005, 0.02):  # triangular, parabolic, parabolic
        uv = cct_to_uv_ohno2013(t, d)
        raw, _ = uv_to_cct_ohno2013(uv, spacing=1.01)
        cor, _ = uv_to_cct_ohno2013(uv, spacing=1.01, correction=True)
        np.testing.assert_allclose(cor, raw * 0.99991, rtol=1e-15)
        assert 5e-5 < np.median(raw / t - 1) < 1e-4
        assert np.max(np.abs(cor / t - 1)) < np.max(np.abs(raw / t - 1))
        fine, _ = uv_to_cct_ohno2013(uv)
        assert np.max(np.abs(fine / t - 1)) < 5e-6  # measured 2.5e-6 at most


def test_cached_cmfs_are_read_only_and_shared() -> None:
    """The 1 nm CIE 1931 2° table of planckian_uv: one read-only pair, 360-780 nm."""
    from imageform.color.cct_methods import _cmf_1nm
    from imageform.spectral import cmfs

    wl, cmf = _cmf_1nm()
    assert _cmf_1nm()[0] is wl and _cmf_1nm()[1] is cmf
    assert not wl.flags.writeable and not cmf.flags.writeable
    assert wl.shape == (421,) and cmf.shape == (421, 3) and (wl[0], wl[-1]) == (360.0, 780.0)
    np.testing.assert_array_equal(cmf, cmfs(2).values[:421])  # the table starts at 360 nm
    with pytest.raises(ValueError, match="read-only"):
        cmf[0, 0] = 1.0
    # CIE 015:2018 Table 4: ybar(555 nm) = 1.0
    assert cmf[195, 1] == pytest.approx(1.0, abs=1e-6)
