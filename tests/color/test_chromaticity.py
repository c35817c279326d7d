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


def _in_polygon_every_edge(pts: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """The test of every edge that in_locus ran before its slab table (the reference)."""
    x1, y1 = poly[:, 0].astype(pts.dtype), poly[:, 1].astype(pts.dtype)
    x2, y2 = np.roll(x1, -1), np.roll(y1, -1)
    x, y = pts[..., 0][..., None], pts[..., 1][..., None]
    crosses = (y1 > y) != (y2 > y)
    dy = y2 - y1
    xint = x1 + (y - y1) * (x2 - x1) / np.where(dy == 0, 1.0, dy).astype(pts.dtype)
    return np.sum((crosses & (x < xint)).astype(np.int32), axis=-1) % 2 == 1


def _locus_probes(poly: np.ndarray, dtype: type, seed: int = 0) -> np.ndarray:
    """Random points, the vertices, points on the edges and a hair off them, the red corner."""
    rng = np.random.default_rng(seed)
    p = poly.astype(dtype)
    q = np.roll(p, -1, axis=0)
    i = rng.integers(0, len(p), 4000)
    on = p[i] + (q[i] - p[i]) * rng.uniform(0, 1, (4000, 1))
    return np.concatenate(
        [
            rng.uniform(-0.05, 0.9, (6000, 2)),
            p,
            on,
            on + rng.normal(0, 1e-7, on.shape),
            p[300:].mean(axis=0) + rng.uniform(-3e-3, 3e-3, (4000, 2)),  # the jagged red end
            [[0.7347, 0.2653], [-1e30, 0.3], [1e30, 0.3], [0.3, -1e30], [0.3, 1e30]],
        ]
    ).astype(dtype)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize(("coords", "observer"), [("xy", 2), ("uv", 2), ("xy", 10), ("uv", 10)])
def test_in_locus_answers_as_every_edge(coords: str, observer: int, dtype: type) -> None:
    """The slab table gives the answers of the test of every edge, boundary points included."""
    poly = spectral_locus(observer=observer, coords=coords).chromaticities
    pts = _locus_probes(poly, dtype)
    want = _in_polygon_every_edge(pts, poly)
    assert 0 < want.sum() < want.size
    got = in_locus(pts, coords, observer=observer)
    np.testing.assert_array_equal(got, want)
    grid = pts[:4096].reshape(16, 16, 16, 2)  # any leading shape, a single point
    np.testing.assert_array_equal(
        in_locus(grid, coords, observer=observer), want[:4096].reshape(16, 16, 16)
    )
    assert in_locus(pts[0], coords, observer=observer) == want[0]


@pytest.mark.parametrize("backend", ["torch", "array_api_strict"])
def test_in_locus_backends_answer_as_numpy(backend: str) -> None:
    """PyTorch (its host path) and array-api-strict (the device path) agree with NumPy."""
    poly = spectral_locus().chromaticities
    for dtype in (np.float64, np.float32):
        pts = _locus_probes(poly, dtype, seed=1)
        got = in_locus(to_backend(pts, backend, np.dtype(dtype).name))
        np.testing.assert_array_equal(to_np(got), _in_polygon_every_edge(pts, poly))


@pytest.mark.parametrize("block", [1 << 18, 1, 1 << 30])
def test_in_locus_device_path_answers_as_numpy(monkeypatch: pytest.MonkeyPatch, block: int) -> None:
    """The device path (every point against the widest slab), run on CPU tensors, agrees:
    the slab's edges in columns of (N, G) temporaries of at most ``block`` values (G from 1
    to all 54; memory bounded: 990 -> 31 MiB for 400401 points, locus-device-2026-12-01a.md)."""
    torch = pytest.importorskip("torch")
    from imageform.color import chromaticity

    poly = spectral_locus().chromaticities
    pts = _locus_probes(poly, np.float32, seed=2)
    xp = chromaticity.namespace(torch.zeros(1))
    monkeypatch.setattr(chromaticity, "_host_view", lambda a: None)
    monkeypatch.setattr(chromaticity, "_DEVICE_BLOCK", block)
    got = chromaticity._points_in_polygon(torch.from_numpy(pts), poly, xp)
    np.testing.assert_array_equal(got.numpy(), _in_polygon_every_edge(pts, poly))


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
