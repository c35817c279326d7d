"""Tests of imageform.color.delta_e: gold values, peer cross-checks, kernel vs twin, backends."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform._kernels.delta_e import ciede2000_numba, ciede2000_twin
from imageform.color.delta_e import (
    delta_e,
    delta_e_cie76,
    delta_e_cie94,
    delta_e_ciede2000,
    delta_e_cmc,
    describe_delta_e,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np

# Sharma, Wu & Dalal (2005), Color Res. Appl. 30(1), Table 1: the 34 test pairs
# (L1, a1, b1, L2, a2, b2, ΔE00), published to 4 decimals. Typed from the paper; the 33 pairs
# colour-science 0.4.7 keeps in its own tests (it drops pair 14, see below) agree with these.
SHARMA_2005 = np.array(
    [
        [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
        [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
        [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
        [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
        [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
        [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
        [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
        [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
        [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
        [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
        [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
        [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
        [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
        [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
        [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
        [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
        [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
        [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
        [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
        [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
    ]
)
LAB1, LAB2, DE00 = SHARMA_2005[:, :3], SHARMA_2005[:, 3:6], SHARMA_2005[:, 6]


def _random_lab(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.stack(
        [rng.uniform(0, 100, n), rng.uniform(-128, 128, n), rng.uniform(-128, 128, n)], axis=-1
    )


def _edge_pairs() -> tuple[np.ndarray, np.ndarray]:
    """Zero chroma, exactly opposite hues, equal colours, hue on the axes."""
    p1 = [
        [50, 0, 0],
        [50, 0, 0],
        [20, 3, 4],
        [50, 10, 0],
        [50, 0, 10],
        [50, -3, 4],
        [70, 5, 5],
        [50, 10, 0],
        [50, -10, 0],
    ]
    p2 = [
        [60, 0, 0],
        [50, -3, -4],
        [20, 0, 0],
        [50, -10, 0],
        [50, 0, -10],
        [50, 3, -4],
        [70, 5, 5],
        [50, 0, -10],
        [50, 0, 10],
    ]
    return np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)


def _ciede2000_textbook(lab1: np.ndarray, lab2: np.ndarray, kL=1.0, kC=1.0, kH=1.0) -> np.ndarray:
    """Sharma et al. (2005) eqs. (1)-(22) literally, angles in degrees, one pair at a time."""
    out = []
    for (L1, a1, b1), (L2, a2, b2) in zip(lab1, lab2, strict=True):
        C1, C2 = math.hypot(a1, b1), math.hypot(a2, b2)
        Cb7 = ((C1 + C2) / 2) ** 7
        G = 0.5 * (1 - math.sqrt(Cb7 / (Cb7 + 25.0**7)))
        a1p, a2p = (1 + G) * a1, (1 + G) * a2
        C1p, C2p = math.hypot(a1p, b1), math.hypot(a2p, b2)
        h1 = math.degrees(math.atan2(b1, a1p)) % 360 if C1p else 0.0
        h2 = math.degrees(math.atan2(b2, a2p)) % 360 if C2p else 0.0
        dL, dC = L2 - L1, C2p - C1p
        if C1p * C2p == 0:
            dh = 0.0
        elif abs(h2 - h1) <= 180:
            dh = h2 - h1
        elif h2 - h1 > 180:
            dh = h2 - h1 - 360
        else:
            dh = h2 - h1 + 360
        dH = 2 * math.sqrt(C1p * C2p) * math.sin(math.radians(dh / 2))
        Lb, Cbp = (L1 + L2) / 2, (C1p + C2p) / 2
        if C1p * C2p == 0:
            hb = h1 + h2
        elif abs(h1 - h2) <= 180:
            hb = (h1 + h2) / 2
        elif h1 + h2 < 360:
            hb = (h1 + h2 + 360) / 2
        else:
            hb = (h1 + h2 - 360) / 2
        T = (
            1
            - 0.17 * math.cos(math.radians(hb - 30))
            + 0.24 * math.cos(math.radians(2 * hb))
            + 0.32 * math.cos(math.radians(3 * hb + 6))
            - 0.20 * math.cos(math.radians(4 * hb - 63))
        )
        dtheta = 30 * math.exp(-(((hb - 275) / 25) ** 2))
        RC = 2 * math.sqrt(Cbp**7 / (Cbp**7 + 25.0**7))
        SL = 1 + 0.015 * (Lb - 50) ** 2 / math.sqrt(20 + (Lb - 50) ** 2)
        SC = 1 + 0.045 * Cbp
        SH = 1 + 0.015 * Cbp * T
        RT = -math.sin(math.radians(2 * dtheta)) * RC
        tl, tc, th = dL / (kL * SL), dC / (kC * SC), dH / (kH * SH)
        out.append(math.sqrt(tl**2 + tc**2 + th**2 + RT * tc * th))
    return np.asarray(out)


# --- gold values ---------------------------------------------------------------------------


def test_ciede2000_sharma_2005_table1_public() -> None:
    """Sharma, Wu & Dalal (2005) Table 1, all 34 pairs, to the published 1e-4."""
    np.testing.assert_allclose(delta_e_ciede2000(LAB1, LAB2), DE00, atol=1e-4, rtol=0)


@pytest.mark.parametrize("path", ["kernel", "twin"])
def test_ciede2000_sharma_2005_table1_each_path(path: str) -> None:
    """Sharma et al. (2005) Table 1 through the numba kernel and through its twin."""
    if path == "kernel":
        got = ciede2000_numba(LAB1, LAB2, 1.0, 1.0, 1.0)
    else:
        from array_api_compat import numpy as xp

        got = ciede2000_twin(xp, LAB1, LAB2, 1.0, 1.0, 1.0)
    np.testing.assert_allclose(got, DE00, atol=1e-4, rtol=0)


def test_ciede2000_sharma_textbook_reference_agrees() -> None:
    """The test's literal transcription of Sharma's equations reproduces Table 1 (sanity)."""
    np.testing.assert_allclose(_ciede2000_textbook(LAB1, LAB2), DE00, atol=1e-4, rtol=0)


def test_ciede2000_large_image_uses_kernel_and_matches_table() -> None:
    """Table 1 tiled to an image large enough for the numba path (same numbers)."""
    n = 200
    img1 = np.tile(LAB1, (n, 1)).reshape(n, 34, 3)
    img2 = np.tile(LAB2, (n, 1)).reshape(n, 34, 3)
    got = delta_e_ciede2000(img1, img2)
    assert got.shape == (n, 34)
    np.testing.assert_allclose(got, np.broadcast_to(DE00, (n, 34)), atol=1e-4, rtol=0)


def test_cie76_pythagorean() -> None:
    """CIE 15:2004 eq. 8.9: a 3-4-5 triangle in the a*b* plane gives 5."""
    assert float(delta_e_cie76([50, 0, 0], [50, 3, 4])) == 5.0


# --- kernel vs twin vs the exact formula ------------------------------------------------------


def test_kernel_matches_twin_and_exact_formula() -> None:
    """Kernel vs twin to 1e-12; both vs the literal formula to 1e-9 (random + edge pairs)."""
    from array_api_compat import numpy as xp

    rng = np.random.default_rng(7)
    a, b = _random_lab(rng, 3000), _random_lab(rng, 3000)
    near = a + rng.normal(0, 2, a.shape)
    e1, e2 = _edge_pairs()
    p1 = np.concatenate([a, a, e1, LAB1])
    p2 = np.concatenate([b, near, e2, LAB2])
    for k in [(1.0, 1.0, 1.0), (2.0, 1.5, 0.7)]:
        kern = ciede2000_numba(p1, p2, *k)
        twin = ciede2000_twin(xp, p1, p2, *k)
        exact = _ciede2000_textbook(p1, p2, *k)
        np.testing.assert_allclose(kern, twin, atol=1e-12, rtol=0)
        np.testing.assert_allclose(kern, exact, atol=1e-9, rtol=0)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-128, 128), min_size=6, max_size=6),
    st.floats(0, 100),
    st.floats(0, 100),
)
def test_ciede2000_symmetric_and_zero_on_equal(ab: list[float], L1: float, L2: float) -> None:
    """ΔE00(x, y) = ΔE00(y, x) and ΔE00(x, x) = 0 (Sharma et al. 2005, §3)."""
    x = np.array([L1, ab[0], ab[1]])
    y = np.array([L2, ab[2], ab[3]])
    d1 = float(delta_e_ciede2000(x, y))
    d2 = float(delta_e_ciede2000(y, x))
    assert d1 == pytest.approx(d2, abs=1e-9)
    assert float(delta_e_ciede2000(x, x)) == 0.0
    # The formula is discontinuous where |h1' - h2'| = 180° (the mean hue jumps by 180°); within
    # rounding of that tie the literal degree arithmetic may land on the other side (e.g.
    # a1 = 1e-33, b1 = -1 against a2 = 0, b2 = 1: exactly h1' = 270° + 8e-32°, which degrees
    # round to 270°). Compare with the literal formula away from the tie only.
    h1 = math.degrees(math.atan2(x[2], x[1]))
    h2 = math.degrees(math.atan2(y[2], y[1]))
    gap = abs(abs((h1 - h2) % 360.0) - 180.0)
    if gap > 1e-6 or np.hypot(x[1], x[2]) * np.hypot(y[1], y[2]) == 0:
        assert d1 == pytest.approx(float(_ciede2000_textbook(x[None], y[None])[0]), abs=1e-9)


# --- cross-checks against peers (labelled: oracles, not the truth) ---------------------------


def test_cross_check_colour_science_and_skimage_ciede2000() -> None:
    """Cross-check: colour-science 0.4.7 and scikit-image 0.26 agree to 1e-6 on random pairs."""
    colour = pytest.importorskip("colour")
    skcolor = pytest.importorskip("skimage.color")
    rng = np.random.default_rng(1)
    a, b = _random_lab(rng, 20000), _random_lab(rng, 20000)
    ours = delta_e_ciede2000(a, b)
    np.testing.assert_allclose(ours, colour.difference.delta_E_CIE2000(a, b), atol=1e-6, rtol=0)
    np.testing.assert_allclose(ours, skcolor.deltaE_ciede2000(a, b), atol=1e-6, rtol=0)
    ours_k = delta_e_ciede2000(a, b, kL=2.0, kC=1.5, kH=0.5)
    np.testing.assert_allclose(
        ours_k, skcolor.deltaE_ciede2000(a, b, kL=2.0, kC=1.5, kH=0.5), atol=1e-6, rtol=0
    )


def test_cross_check_colour_science_sharma_subset() -> None:
    """Cross-check: colour-science reproduces our typed Table 1 (it skips pair 14 in its own
    tests because NumPy's atan2 lands on either side of the exact 180° hue difference)."""
    colour = pytest.importorskip("colour")
    keep = np.arange(34) != 13
    np.testing.assert_allclose(
        colour.difference.delta_E_CIE2000(LAB1[keep], LAB2[keep]), DE00[keep], atol=1e-4
    )


def test_cross_check_cie76_cie94_cmc() -> None:
    """Cross-check CIE76, CIE94 (both applications) and CMC (1:1, 2:1) against both peers.

    scikit-image's ``deltaE_ciede94`` and ``deltaE_cmc`` take the same reference-first
    convention; its CMC ``kL, kC`` are our ``l, c``.
    """
    colour = pytest.importorskip("colour")
    skcolor = pytest.importorskip("skimage.color")
    rng = np.random.default_rng(2)
    a, b = _random_lab(rng, 5000), _random_lab(rng, 5000)
    np.testing.assert_allclose(delta_e_cie76(a, b), skcolor.deltaE_cie76(a, b), atol=1e-9)
    np.testing.assert_allclose(
        delta_e(a, b, "cie94"), colour.difference.delta_E_CIE1994(a, b), atol=1e-6
    )
    np.testing.assert_allclose(
        delta_e(a, b, "cie94", application="textiles"),
        colour.difference.delta_E_CIE1994(a, b, textiles=True),
        atol=1e-6,
    )
    np.testing.assert_allclose(delta_e_cie94(a, b), skcolor.deltaE_ciede94(a, b), atol=1e-6)
    for l_, c_ in [(1.0, 1.0), (2.0, 1.0)]:
        ours = delta_e_cmc(a, b, l=l_, c=c_)
        np.testing.assert_allclose(ours, colour.difference.delta_E_CMC(a, b, l=l_, c=c_), atol=1e-6)
        np.testing.assert_allclose(ours, skcolor.deltaE_cmc(a, b, kL=l_, kC=c_), atol=1e-6)


# --- shapes, dtypes, backends ----------------------------------------------------------------


@pytest.mark.parametrize("method", ["cie76", "cie94", "ciede2000", "cmc"])
def test_shapes_broadcast_and_dtypes(method: str) -> None:
    img = np.full((4, 5, 3), [50.0, 10.0, -10.0])
    ref = np.array([52.0, 9.0, -12.0])
    out = delta_e(img, ref, method)
    assert out.shape == (4, 5)
    assert out.dtype == np.float64
    assert delta_e(img.astype(np.float32), ref.astype(np.float32), method).dtype == np.float32
    np.testing.assert_allclose(out, float(delta_e(img[0, 0], ref, method)), rtol=1e-12)
    assert delta_e(ref, ref, method).shape == ()


def test_float32_kernel_path() -> None:
    rng = np.random.default_rng(3)
    a, b = _random_lab(rng, 10000), _random_lab(rng, 10000)
    got = delta_e_ciede2000(a.astype(np.float32), b.astype(np.float32))
    assert got.dtype == np.float32
    ref = delta_e_ciede2000(a.astype(np.float32).astype(float), b.astype(np.float32).astype(float))
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-5)


@pytest.mark.parametrize("method", ["cie76", "cie94", "ciede2000", "cmc"])
def test_backends_agree(xp_name: str, method: str) -> None:
    """NumPy (kernel), array-api-strict and PyTorch give the same numbers."""
    rng = np.random.default_rng(4)
    a, b = _random_lab(rng, 5000), _random_lab(rng, 5000)
    ref = delta_e(a, b, method)
    got = delta_e(to_backend(a, xp_name), to_backend(b, xp_name), method)
    assert (
        type(got).__module__.split(".")[0] == type(to_backend(a, xp_name)).__module__.split(".")[0]
    )
    np.testing.assert_allclose(to_np(got), ref, atol=1e-10, rtol=0)


def test_torch_gradients_flow() -> None:
    """PyTorch: d ΔE00 / d Lab exists and matches central finite differences (gradcheck)."""
    torch = pytest.importorskip("torch")
    rng = np.random.default_rng(5)
    a = torch.tensor(_random_lab(rng, 8), dtype=torch.float64, requires_grad=True)
    b = torch.tensor(_random_lab(rng, 8), dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda x, y: delta_e(x, y), (a, b))
    loss = delta_e(a, b).sum()
    loss.backward()
    assert a.grad is not None and torch.all(torch.isfinite(a.grad))


# --- bad input -------------------------------------------------------------------------------


def test_bad_inputs() -> None:
    good = [50.0, 1.0, 2.0]
    with pytest.raises(InvalidInputError, match="contains NaN"):
        delta_e([50.0, np.nan, 0.0], good)
    with pytest.raises(InvalidInputError, match=r"shape \(\.\.\., 3\)"):
        delta_e([50.0, 1.0], good)
    with pytest.raises(UnknownOptionError, match="valid: 'cie76', 'cie94', 'ciede2000', 'cmc'"):
        delta_e(good, good, method="cie2001")
    with pytest.raises(UnknownOptionError, match="graphic_arts"):
        delta_e(good, good, method="cie94", application="paint")
    with pytest.raises(InvalidInputError, match="kL > 0"):
        delta_e(good, good, kL=-1.0)
    with pytest.raises(InvalidInputError, match="l > 0"):
        delta_e_cmc(good, good, l=0.0)
    with pytest.raises(InvalidInputError, match="broadcastable"):
        delta_e(np.zeros((2, 3)), np.zeros((3, 3)))


def test_describe_delta_e_lecture_bands() -> None:
    """The lecture: < 1 imperceptible, about 2 just noticeable, > 10 obviously different."""
    assert describe_delta_e(0.5) == "imperceptible"
    assert describe_delta_e(2.0) == "just noticeable"
    assert describe_delta_e(5.0) == "perceptible"
    assert describe_delta_e(10.5) == "obviously different"
    with pytest.raises(InvalidInputError, match="value as a ΔE >= 0"):
        describe_delta_e(-1.0)


def test_disable_numba_gives_the_twin(monkeypatch: pytest.MonkeyPatch) -> None:
    """IMAGEFORM_DISABLE_NUMBA=1 forces the plain twin: same numbers to 1e-12."""
    rng = np.random.default_rng(8)
    a, b = _random_lab(rng, 20000), _random_lab(rng, 20000)
    fast = delta_e_ciede2000(a, b)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    np.testing.assert_allclose(delta_e_ciede2000(a, b), fast, atol=1e-12, rtol=0)


def test_dask_chunks() -> None:
    da = pytest.importorskip("dask.array")
    rng = np.random.default_rng(9)
    a, b = _random_lab(rng, 4000).reshape(40, 100, 3), _random_lab(rng, 4000).reshape(40, 100, 3)
    got = delta_e(da.from_array(a, chunks=(10, 100, 3)), da.from_array(b, chunks=(10, 100, 3)))
    np.testing.assert_allclose(np.asarray(got), delta_e(a, b), atol=1e-12, rtol=0)


def test_ciede2000_subnormal_chroma_is_finite() -> None:
    """Regression (found by hypothesis): a subnormal a* made the array path's reciprocals
    overflow to inf and return NaN; a chroma that small counts as zero."""
    x = np.array([0.0, 2.2250738585e-313, 0.0])
    y = np.array([0.0, 1.0, 0.0])
    d = float(delta_e_ciede2000(x, y))
    assert np.isfinite(d)
    assert d == pytest.approx(float(delta_e_ciede2000(np.zeros(3), y)), abs=1e-12)
    assert float(delta_e_ciede2000(y, x)) == pytest.approx(d, abs=1e-12)
