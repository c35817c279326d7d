"""Semi-global matching (``stereo_disparity``) and disparity to depth, against truth and OpenCV.

The pair is ray-cast with NumPy (``tests/stereo_scenes.py``: a slanted plane, a plane in
front of it and a sphere, textured with 3-D value noise, rendered by two rectified pinhole
cameras with known disparity). Figures quoted in the asserts were measured on it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from imageform._kernels import sgm
from imageform.errors import InvalidInputError
from imageform.geometry import _sgm_numpy as twin
from imageform.geometry import (
    disparity_to_depth,
    disparity_to_points,
    stereo_disparity,
    stereo_rectify,
)
from imageform.geometry import stereo_matching as sm
from imageform.geometry.stereo_matching import _grey, _match, _plane_fill

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from stereo_scenes import render_pair


@pytest.fixture(scope="module")
def scene():  # type: ignore[no-untyped-def]
    return render_pair()  # 320 x 240, disparities 18.7 to 34.8 px


@pytest.fixture(scope="module")
def small():  # type: ignore[no-untyped-def]
    return render_pair(96, 64, f=120.0, ss=2, seed=3)  # disparities 5.6 to 10.4 px


# ------------------------------------------------------------------- kernel and twin


@pytest.mark.parametrize(
    "args",
    [
        (0, 16, 5, 3, 96, False, 0.1, 1.0, 0, 1.0, True, False, 0.0, -1.0),
        (0, 16, 5, 3, 96, False, 0.1, 1.0, 0, 1.0, False, False, 0.0, -1.0),
        (-3, 21, 3, 2, 40, True, 0.05, 0.0, 20, 1.0, True, False, 0.0, -1.0),
        (2, 13, 7, 6, 200, True, 0.0, -1.0, 5, 2.0, False, False, 0.0, -1.0),
        (0, 16, 5, 3, 96, False, 0.1, 1.0, 0, 1.0, True, True, 2.5, -1.0),  # census threshold
        (-3, 21, 7, 6, 200, True, 0.05, 1.0, 5, 1.0, False, False, 0.7, -1.0),
        (0, 16, 5, 16, 64, False, 0.1, 1.0, 0, 1.0, True, False, 0.0, 4.0),  # graded census
        (-3, 21, 3, 5, 20, True, 0.05, 1.0, 5, 1.0, False, True, 0.7, 1.5),
        (2, 13, 5, 16, 64, False, 0.0, -1.0, 0, 1.0, True, False, 1.0, 0.0),
    ],
)
def test_kernels_and_twins_give_the_same_numbers(small, args) -> None:  # type: ignore[no-untyped-def]
    gl, gr = _grey(small.left, "left"), _grey(small.right, "right")
    r = args[2] // 2
    nbits = (args[2] ** 2 - 1) * (2 if args[13] >= 0 else 1)
    thr, step = np.float32(args[12]), np.float32(args[13])
    codes = sgm.census(gl, r, thr, step), twin.census(gl, r, thr, step)
    np.testing.assert_array_equal(*codes)
    assert int(codes[0].max()) < 2**nbits
    costs = [
        m.cost_volume(c, m.census(gr, r, thr, step), args[0], args[1], nbits)
        for m, c in ((sgm, codes[0]), (twin, codes[1]))
    ]
    np.testing.assert_array_equal(*costs)
    totals = [m.aggregate(costs[0], gl, args[3], args[4], args[5]) for m in (sgm, twin)]
    np.testing.assert_array_equal(*totals)
    # the fused kernel (rows selected as the second pass completes them) is select(aggregate)
    fused = sgm.match(
        costs[0], gl, args[3], args[4], args[5], args[0], args[6], args[7], None, args[10]
    )
    selected = [m.select(totals[0], args[0], args[6], args[7], args[10]) for m in (sgm, twin)]
    np.testing.assert_array_equal(fused, selected[0])
    np.testing.assert_array_equal(*selected)
    a = _match(sgm, gl, gr, *args[:2], args[2], *args[3:])
    b = _match(twin, gl, gr, *args[:2], args[2], *args[3:])
    np.testing.assert_array_equal(a, b)  # NaN where NaN, the same floats elsewhere
    assert 0.5 < np.isfinite(a).mean() < 1.0


@pytest.mark.parametrize("adaptive", [False, True])
def test_slanted_paths_kernel_and_twin_give_the_same_numbers(adaptive) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(5)
    h, w, n = 23, 41, 11
    cost = rng.integers(0, 60, (h, w, n)).astype(np.uint8)
    grey = rng.uniform(0, 255, (h, w)).astype(np.float32)
    slant = rng.integers(-700, 700, (4, h, w)).astype(np.int32)
    slant[:, rng.uniform(size=(h, w)) < 0.3] = 0  # whole and fractional shifts, and none
    slant[:, :, ::7] = (slant[:, :, ::7] // 256) * 256
    a = sgm.aggregate(cost, grey, 8, 32, adaptive, slant)
    np.testing.assert_array_equal(a, twin.aggregate(cost, grey, 8, 32, adaptive, slant))
    assert not np.array_equal(a, sgm.aggregate(cost, grey, 8, 32, adaptive))
    zero = np.zeros_like(slant)
    np.testing.assert_array_equal(
        sgm.aggregate(cost, grey, 8, 32, adaptive, zero), sgm.aggregate(cost, grey, 8, 32, adaptive)
    )
    total = np.empty(cost.shape, dtype=np.uint16)
    fused = sgm.match(cost, grey, 8, 32, adaptive, 0, 0.1, 1.0, total, True, slant)
    np.testing.assert_array_equal(fused, sgm.select(a, 0, 0.1, 1.0, True))


def test_a_path_shifted_by_the_slant() -> None:
    """``L(k - g)``: whole shifts move the vector, a fraction interpolates, _BIG beyond."""
    lp = np.array([16384, 10, 20, 40, 80, 16384], dtype=np.int16)
    out = np.empty(6, dtype=np.int16)
    assert sgm._shifted(lp, 256, out)[1:5].tolist() == [16384, 10, 20, 40]
    assert sgm._shifted(lp, -512, out)[1:5].tolist() == [40, 80, 16384, 16384]
    assert sgm._shifted(lp, 128, out)[1:5].tolist() == [8197, 15, 30, 60]
    got = twin._shifted(lp[None, 1:5].astype(np.int32), np.array([128]))
    assert got[0].tolist() == [8197, 15, 30, 60]


def test_slants_of_a_plane_and_none_across_a_step() -> None:
    h, w = 60, 80
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    d = (20.0 + 0.3 * x - 0.2 * y).astype(np.float32)
    s = sm._slants(d)
    assert s.shape == (4, h, w) and s.dtype == np.int32
    # a = 0.3, b = -0.2: the steps (1, 0), (1, 1), (0, 1), (-1, 1) change d by these / 256
    assert [int(np.median(v)) for v in s] == [77, 26, -51, -128]
    d[:, 40:] += 5.0  # an occluding edge: no plane fits a window across it
    s = sm._slants(d)
    assert (s[:, :, 37:43] == 0).all() and (s[0, :, 10:30] == 77).all()
    d[20:30, 10:20] = np.nan  # invalid pixels are left out of the fits
    assert (sm._slants(d)[0, 22:28, 22:30] == 77).all()


def test_slant_prior_on_the_rendered_pair(scene, small, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    band = np.zeros_like(scene.visible)
    band[:, 47:] = True
    ok = scene.visible & band

    def bad(d: np.ndarray) -> float:
        v = ok & np.isfinite(d)
        return float((np.abs(d - scene.disparity)[v] > 1).mean())

    d0 = stereo_disparity(scene.left, scene.right, num_disparities=48)
    d1 = stereo_disparity(scene.left, scene.right, num_disparities=48, slant_prior=True)
    # measured: 0.2 % of the pixels more than 1 px off before and after (a textured scene)
    assert bad(d1) < 0.01 and bad(d1) <= bad(d0) + 0.002
    assert np.isfinite(d1[ok]).mean() >= np.isfinite(d0[ok]).mean() - 0.01
    a = stereo_disparity(small.left, small.right, num_disparities=16, slant_prior=True)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    b = stereo_disparity(small.left, small.right, num_disparities=16, slant_prior=True)
    np.testing.assert_array_equal(a, b)


def test_the_public_call_without_numba_is_the_twin(
    small,  # type: ignore[no-untyped-def]
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    kws = [
        {"num_disparities": 16, "speckle_size": 10, "adaptive_p2": True},
        {"num_disparities": 16, "median_filter": True, "subpixel": "parabola"},
        {"num_disparities": 16, "census_step": None, "census_threshold": 1.0},
        {"num_disparities": 16, "block_size": 3, "census_step": 2.0},
    ]
    a = [stereo_disparity(small.left, small.right, **kw) for kw in kws]
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    b = [stereo_disparity(small.left, small.right, **kw) for kw in kws]
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


def test_left_right_check_is_opencvs() -> None:
    """Right pixels are claimed by unique winners (the lower sum wins; from the right end)."""
    n = 3
    rows = {5: [0, 50, 50], 4: [50, 50, 10], 3: [50, 50, 5], 2: [20, 50, 50]}

    def volume(rows):  # type: ignore[no-untyped-def]
        total = np.full((1, 6, n), 60, dtype=np.uint16)
        for x, r in rows.items():
            total[0, x] = r
        return total

    for m in (sgm, twin):
        # x = 4 (d = 2, sum 10) claims x_r = 2 first; x = 2 (d = 0, sum 20) lands there too
        d = m.select(volume(rows), 0, 0.1, 1.0)
        np.testing.assert_array_equal(d[0, 2:], [np.nan, 2, 2, 0])
        np.testing.assert_array_equal(m.select(volume(rows), 0, 0.1, 2.0)[0, 2:], [0, 2, 2, 0])
        np.testing.assert_array_equal(m.select(volume(rows), 0, 0.1, -1.0)[0, 2:], [0, 2, 2, 0])
        # with the lower sum, x = 2 takes x_r = 2 over: x = 4 is the one left out
        d = m.select(volume(rows | {2: [5, 50, 50]}), 0, 0.1, 1.0)
        np.testing.assert_array_equal(d[0, 2:], [0, 2, np.nan, 0])
        # sub-pixel 0.548 (the parabola through 11, 10, 30): floor 0 lands on x_r = 3, claimed
        # by x = 5 with d = 2 (2 away), ceil 1 on x_r = 2, claimed by x = 4 with d = 2 (1
        # away): one of the two is enough
        d = m.select(volume(rows | {3: [11, 10, 30], 5: [50, 50, 0]}), 0, 0.1, 1.0)
        np.testing.assert_allclose(d[0, 2:], [np.nan, 1 - 19 / 42, 2, 2], rtol=1e-6)
        assert np.isnan(d[0, :2]).all()  # the band where d = 2 leaves the right image
        # the equiangular V through 11, 10, 30: 1 - 19 / 40 (the same claims, the same check)
        d = m.select(volume(rows | {3: [11, 10, 30], 5: [50, 50, 0]}), 0, 0.1, 1.0, True)
        np.testing.assert_allclose(d[0, 2:], [np.nan, 1 - 19 / 40, 2, 2], rtol=1e-6)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 7])
def test_uniqueness_skips_the_winners_neighbours_at_every_winner(n) -> None:  # type: ignore[no-untyped-def]
    """The second best is the least sum more than 1 away from the winner, at the ends too.

    One column per (winner b, rival r): sum 100 at b, 104 at r, 200 elsewhere; with
    uniqueness 0.1 the rival makes the winner not unique exactly where ``|r - b| > 1``
    (104 * 0.9 < 100), as OpenCV's ``StereoSGBM`` (the kernel splits that search in two
    loops, below ``b - 1`` and above ``b + 1``).
    """
    cases = [(b, r) for b in range(n) for r in range(n) if r != b]
    if not cases:  # one disparity: every winner unique
        cases = [(0, 0)]
    w = len(cases) + n - 1  # the first n - 1 columns: the band outside the right image
    total = np.full((1, w, n), 200, dtype=np.uint16)
    for i, (b, r) in enumerate(cases):
        total[0, n - 1 + i, r] = 104
        total[0, n - 1 + i, b] = 100
    got = sgm.select(total, 0, 0.1, -1.0)
    np.testing.assert_array_equal(got, twin.select(total, 0, 0.1, -1.0))
    want = [np.nan] * (n - 1) + [np.nan if abs(r - b) > 1 else float(b) for b, r in cases]
    np.testing.assert_array_equal(np.round(got[0]), want)  # sub-pixel: within 0.5 of b
    fused = np.empty_like(got)
    srow = total[0].copy()
    claim, claim_cost = np.empty(w, np.int64), np.empty(w, np.int64)
    fused[0] = np.nan
    sgm._select_row(srow, fused[0], 0, 0.9, -1.0, claim, claim_cost, False)
    np.testing.assert_array_equal(fused, got)
    np.testing.assert_array_equal(srow, total[0])  # the sums left as they were


@pytest.mark.parametrize("x0", [-0.4, -0.25, -0.1, 0.0, 0.15, 0.3, 0.45])
def test_equiangular_fit_is_exact_on_a_v_and_the_parabola_is_not(x0) -> None:  # type: ignore[no-untyped-def]
    """Sums that grow linearly away from a sub-pixel ``x0`` (Shimizu & Okutomi's V): the
    equiangular fit puts ``d`` on it, the parabola nearer the whole pixel (unless x0 = 0)."""
    n = 9
    k = np.arange(n)
    true = 4 + x0
    total = np.round(1000 + 400 * np.abs(k - true)).astype(np.uint16)[None, None, :]
    total = np.repeat(total, n, axis=1)  # the last column is the one whose range fits
    for m in (sgm, twin):
        v = m.select(total, 0, 0.0, -1.0, True)[0, -1]
        par = m.select(total, 0, 0.0, -1.0, False)[0, -1]
        assert abs(v - true) < 2e-3
        if x0 != 0.0:
            assert abs(par - 4) < abs(true - 4) - 0.02  # pulled toward the whole pixel


def test_subpixel_option_of_the_public_call(scene) -> None:  # type: ignore[no-untyped-def]
    kw = {"num_disparities": 48}
    v = stereo_disparity(scene.left, scene.right, **kw)
    np.testing.assert_array_equal(
        v, stereo_disparity(scene.left, scene.right, subpixel="equiangular", **kw)
    )
    par = stereo_disparity(scene.left, scene.right, subpixel="parabola", **kw)
    both = np.isfinite(v) & np.isfinite(par) & scene.visible
    np.testing.assert_array_equal(np.round(v[both] - par[both]), 0)  # the same winners
    e_v = np.abs(v - scene.disparity)[both]
    e_p = np.abs(par - scene.disparity)[both]
    inl = (e_v < 1) & (e_p < 1)
    # measured on this pair: RMS of the errors within 1 px 0.187 px (V), 0.197 px (parabola)
    assert np.sqrt(np.mean(e_v[inl] ** 2)) < np.sqrt(np.mean(e_p[inl] ** 2))


def test_median_filter_is_opencvs_median_blur() -> None:
    """OpenCV's 3 x 3 ``medianBlur`` of its 16-bit map (StereoSGBM::compute), invalid below."""
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(7)
    d16 = rng.integers(0, 40 * 16, (37, 53)).astype(np.int16)  # disparities 0 to 40 in 16ths
    d16[rng.uniform(size=d16.shape) < 0.3] = -16  # invalid: (min_d - 1) * 16 with min_d 0
    d16[:8, :8] = -16  # a block of invalid pixels, at the border
    ref = cv2.medianBlur(d16, 3)
    disp = np.where(d16 < 0, np.nan, d16 / 16.0).astype(np.float32)
    for m in (sgm, twin):
        got = m.median3(disp)
        assert got.dtype == np.float32 and got.shape == disp.shape
        np.testing.assert_array_equal(np.isnan(got), ref < 0)
        np.testing.assert_array_equal(got[ref >= 0], ref[ref >= 0] / 16.0)


def test_speckle_filter_is_opencvs_filter_speckles() -> None:
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(5)
    d16 = (rng.integers(0, 6, (50, 70)) * 16).astype(np.int16)  # blobs of a few levels
    d16 = np.kron(d16[::5, ::5], np.ones((5, 5), dtype=np.int16))[:50, :70].copy()
    d16[rng.uniform(size=d16.shape) < 0.05] += 40  # isolated outliers
    ref = d16.copy()
    cv2.filterSpeckles(ref, -16, 30, 16)  # regions of <= 30 px within 1 px (16 sixteenths)
    disp = (d16 / 16.0).astype(np.float32)
    for m in (sgm, twin):
        got = disp.copy()
        m.speckles(got, 30, 1.0)
        np.testing.assert_array_equal(np.isnan(got), ref == -16)


# ------------------------------------------------------------------- accuracy


def test_rendered_pair_within_a_pixel_of_the_truth(scene) -> None:  # type: ignore[no-untyped-def]
    d = stereo_disparity(scene.left, scene.right, num_disparities=48)
    assert d.dtype == np.float32 and d.shape == scene.left.shape
    band = np.zeros_like(scene.visible)
    band[:, 47:] = True  # the first min + num - 1 columns are invalid by definition
    assert np.isnan(d[:, :47]).all()
    ok = scene.visible & band & np.isfinite(d)
    err = np.abs(d - scene.disparity)[ok]
    # measured: 99.8 % within 1 px, 99.9 % within 3 px, mean 0.18 px, density 99 %
    assert (err <= 1).mean() > 0.98
    assert (err <= 3).mean() > 0.99
    assert err.mean() < 0.3
    assert ok.sum() / (scene.visible & band).sum() > 0.9
    # occluded pixels (the left of the near plane and of the sphere) are mostly invalid
    occluded = ~scene.visible & band
    assert np.isnan(d[occluded]).mean() > 0.5  # measured 75 %


def test_agrees_with_opencv_stereo_sgbm(scene) -> None:  # type: ignore[no-untyped-def]
    cv2 = pytest.importorskip("cv2")
    l8 = (scene.left * 255).round().astype(np.uint8)
    r8 = (scene.right * 255).round().astype(np.uint8)
    ours = stereo_disparity(l8, r8, num_disparities=48, block_size=5)
    sgbm = cv2.StereoSGBM_create(
        0, 48, 5, P1=8 * 25, P2=32 * 25, disp12MaxDiff=1, uniquenessRatio=10,
        mode=cv2.STEREO_SGBM_MODE_HH,
    )  # fmt: skip
    ref = sgbm.compute(l8, r8).astype(np.float32) / 16.0
    ref[ref < 0] = np.nan
    both = np.isfinite(ours) & np.isfinite(ref)
    diff = np.abs(ours - ref)[both]
    # measured: both valid on 83 % of the pixels, 99.0 % of those within 1 px, mean 0.26 px
    assert both.mean() > 0.75
    assert (diff <= 1).mean() > 0.97
    assert diff.mean() < 0.4


def test_a_constant_shift_gives_that_disparity() -> None:
    rng = np.random.default_rng(1)
    right = rng.uniform(0, 1, (60, 120))
    for shift in (5, 12):
        d = stereo_disparity(np.roll(right, shift, axis=1), right, num_disparities=16)
        valid = d[:, 15:-2]  # off the census window's replicated border on the right
        assert np.isfinite(valid).all() and np.isnan(d[:, :15]).all()
        assert np.abs(valid - shift).max() < 0.7  # the sub-pixel vertex: within 0.7 px
        np.testing.assert_array_equal(np.round(valid), shift)
    # a negative range: the left image moved left
    d = stereo_disparity(np.roll(right, -4, axis=1), right, min_disparity=-8, num_disparities=8)
    assert np.isnan(d[:, -8:]).all()
    np.testing.assert_array_equal(np.round(d[:, 2:-8]), -4)


def test_swapped_and_mirrored_pair_gives_the_right_views_disparity(scene) -> None:  # type: ignore[no-untyped-def]
    d = stereo_disparity(scene.left, scene.right, num_disparities=48)
    # mirrored, the right image is the left one: the same disparity, at x_right = x - d
    dr = np.fliplr(stereo_disparity(np.fliplr(scene.right), np.fliplr(scene.left),
                                    num_disparities=48))  # fmt: skip
    ys, xs = np.nonzero(np.isfinite(d))
    v = dr[ys, xs - np.round(d[ys, xs]).astype(int)]
    found = np.isfinite(v)
    # measured: 91 % found there, 99.7 % of those within 1 px
    assert found.mean() > 0.85
    assert (np.abs(v[found] - d[ys, xs][found]) <= 1).mean() > 0.99


def test_grey_colour_and_integer_images(small) -> None:  # type: ignore[no-untyped-def]
    u8 = [(im * 255).round().astype(np.uint8) for im in (small.left, small.right)]
    ref = stereo_disparity(*u8, num_disparities=16)
    rgb = [np.repeat(im[..., None], 3, axis=2) for im in u8]
    np.testing.assert_array_equal(stereo_disparity(*rgb, num_disparities=16), ref)
    u16 = [im.astype(np.uint16) * 257 for im in u8]
    np.testing.assert_array_equal(stereo_disparity(*u16, num_disparities=16), ref)
    one = [im[..., None] for im in u8]
    np.testing.assert_array_equal(stereo_disparity(*one, num_disparities=16), ref)


def test_default_penalties(small) -> None:  # type: ignore[no-untyped-def]
    """p1 = a third of the code's bits ((block_size² - 1) // 3 plain, twice that graded)
    times cost_window² / q (q the least divisor keeping the block's largest sum within 191),
    p2 = 4 p1, or 32 p1 with the adaptive P2."""
    L, R = small.left, small.right
    cases = [(3, 2, None, 1), (5, 8, None, 1), (7, 16, None, 1), (3, 5, 4.0, 1)]
    cases += [(5, 16, 4.0, 1), (7, 16, 4.0, 1)]
    # cost_window 3: q = ceil(9 nbits / 191): 8 bits 1, 24 bits 2, 48 bits 3
    cases += [(3, 18, None, 3), (5, 8 * 9 // 2, None, 3), (5, 48, 4.0, 3), (7, 48, None, 3)]
    # cost_window 5 and 7 on 48 bits: q = 7 and 13
    cases += [(5, 16 * 25 // 7, 4.0, 5), (5, 16 * 49 // 13, 4.0, 7)]
    for bs, p1, step, cw in cases:
        for adaptive, p2 in ((False, 4 * p1), (True, 32 * p1)):
            kw = {"num_disparities": 16, "block_size": bs, "adaptive_p2": adaptive}
            kw["cost_window"] = cw
            ref = stereo_disparity(L, R, p1=p1, p2=p2, census_step=step, **kw)
            got = stereo_disparity(L, R, census_step=step, **kw)
            np.testing.assert_array_equal(got, ref)
    # the default window is 3
    np.testing.assert_array_equal(
        stereo_disparity(L, R, num_disparities=16),
        stereo_disparity(L, R, num_disparities=16, cost_window=3),
    )


def test_window_costs_twin_and_sums() -> None:
    """The kernel's block sums equal the twin's and round(box sum / q) of the pixel costs."""
    from scipy.ndimage import uniform_filter

    from imageform._kernels import sgm
    from imageform.geometry import _sgm_numpy as twin

    rng = np.random.default_rng(3)
    for h, w, r, div, lo, n in ((13, 17, 1, 3, -2, 9), (20, 30, 2, 7, 0, 16), (5, 4, 3, 13, 1, 5)):
        a = rng.uniform(0, 255, (h, w)).astype(np.float32)
        b = rng.uniform(0, 255, (h, w)).astype(np.float32)
        z, st = np.float32(0), np.float32(4)
        cl, cr = sgm.census(a, 2, z, st), sgm.census(b, 2, z, st)
        got = sgm.window_costs(cl, cr, lo, n, 48, r, div, np.empty((h, w, n), np.uint8))
        np.testing.assert_array_equal(got, twin.window_costs(cl, cr, lo, n, 48, r, div))
        raw = twin.cost_volume(cl, cr, lo, n, 48).astype(np.float64)
        m = 2 * r + 1
        box = uniform_filter(raw, (m, m, 1), mode="nearest") * m * m
        np.testing.assert_array_equal(got, np.floor(box / div + 0.5 + 1e-9))


@pytest.mark.parametrize(
    "shape",
    [(1, 1, 3, 0), (2, 3, 7, -5), (4, 2, 5, 3), (9, 11, 64, 20), (30, 40, 64, -70), (6, 5, 1, 0)],
)
@pytest.mark.parametrize("r", [1, 2, 3])
def test_window_costs_at_edge_sizes_are_the_twins(shape, r) -> None:  # type: ignore[no-untyped-def]
    """The block sums (one loop over each row's W x D values since 2026-12-01g) equal the twin's
    on images narrower and shorter than the block, disparity ranges partly or wholly outside
    the right image and one disparity, into an output filled with garbage before (every value
    written); the pixel costs of the same rows too (``_cost_row`` through ``cost_volume``)."""
    from imageform._kernels import sgm
    from imageform.geometry import _sgm_numpy as twin

    h, w, n, lo = shape
    rng = np.random.default_rng(h * 100 + w + r)
    for nbits, (cl, cr) in (
        (48, rng.integers(0, 2**48, (2, h, w)).astype(np.uint64)),
        (24, rng.integers(0, 2**24, (2, h, w)).astype(np.uint64)),
        (8, rng.integers(0, 2**8, (2, h, w)).astype(np.uint64)),
    ):
        div = max(1, -(-nbits * (2 * r + 1) ** 2 // 191))
        out = np.full((h, w, n), 77, dtype=np.uint8)
        got = sgm.window_costs(cl, cr, lo, n, nbits, r, div, out)
        assert got is out
        np.testing.assert_array_equal(got, twin.window_costs(cl, cr, lo, n, nbits, r, div))
        np.testing.assert_array_equal(
            sgm.cost_volume(cl, cr, lo, n, nbits), twin.cost_volume(cl, cr, lo, n, nbits)
        )


@pytest.mark.parametrize("adaptive", [False, True])
@pytest.mark.parametrize(
    "shape", [(1, 1, 1, 0), (2, 5, 2, 0), (7, 3, 9, -4), (19, 37, 16, 3), (31, 29, 64, 0)]
)
def test_the_plain_paths_are_the_slant_paths_with_no_slant(shape, adaptive) -> None:  # type: ignore[no-untyped-def]
    """Without a slant the sweeps run a loop of their own (2026-12-01g: the slant's branches
    cost the plain paths some 40 %); a zero slant runs the slant loop, the code of before,
    which must give the same sums and maps bit for bit (padded paths, edge sizes, one
    disparity, the fused selection with and without the left-right check)."""
    h, w, n, lo = shape
    rng = np.random.default_rng(h * 1000 + w * 10 + n)
    cost = rng.integers(0, 191, (h, w, n)).astype(np.uint8)
    grey = rng.uniform(0, 255, (h, w)).astype(np.float32)
    zero = np.zeros((4, h, w), dtype=np.int32)
    none = np.zeros((0, 1, 1), dtype=np.int32)
    for p1, p2 in ((8, 32), (48, 192), (48, 8000)):
        a = sgm.aggregate(cost, grey, p1, p2, adaptive)
        np.testing.assert_array_equal(a, sgm.aggregate(cost, grey, p1, p2, adaptive, zero))
        np.testing.assert_array_equal(a, twin.aggregate(cost, grey, p1, p2, adaptive))
        for lr, eq in ((1.0, True), (-1.0, False), (0.0, True)):
            t1 = np.empty(cost.shape, dtype=np.uint16)
            t2 = np.empty(cost.shape, dtype=np.uint16)
            m1 = sgm.match(cost, grey, p1, p2, adaptive, lo, 0.1, lr, t1, eq, none)
            m2 = sgm.match(cost, grey, p1, p2, adaptive, lo, 0.1, lr, t2, eq, zero)
            np.testing.assert_array_equal(m1, m2)
            np.testing.assert_array_equal(m1, twin.select(a, lo, 0.1, lr, eq))


def test_cost_window_averages_sensor_noise_on_a_board() -> None:
    """A fronto-parallel board (flat squares) seen by two cameras of independent noise: the
    pixel costs alone scatter the disparity inside the squares, the 3 x 3 block sums do not
    (benchmarks/check_stereo_webcam.py's real board pairs, webcam-1 11.84 % to 8.08 %)."""
    rng = np.random.default_rng(5)
    h, w, d, sq = 120, 200, 24, 20
    y, x = np.mgrid[0:h, 0 : w + d]
    board = np.where(((x // sq) + (y // sq)) % 2 == 0, 60.0, 190.0)
    right = board[:, d:] + rng.normal(0, 2.0, (h, w))
    left = board[:, :w] + rng.normal(0, 2.0, (h, w))  # x_right = x_left - d
    u8 = [np.clip(np.round(im), 0, 255).astype(np.uint8) for im in (left, right)]
    inner = (slice(10, h - 10), slice(48 + 10, w - 10))

    def bad(cw: int) -> float:
        disp = stereo_disparity(*u8, num_disparities=48, cost_window=cw, plane_fill=False)
        disp = disp[inner]
        return float(np.mean(~(np.abs(disp - d) <= 1)))  # invalid or more than 1 px off

    before, after = bad(1), bad(3)
    assert before > 0.05
    assert after < before / 3


def _slanted_board(seed: int, h: int = 120, w: int = 240, sq: int = 24):  # type: ignore[no-untyped-def]
    """A board slanted about its vertical axis: d = 20 + 0.12 x, flat squares, sensor noise."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    d = 20.0 + 0.12 * x

    def board(u: np.ndarray) -> np.ndarray:  # u: the board's own coordinate
        return np.where(((np.floor(u / sq) + np.floor(y / sq)) % 2) == 0, 60.0, 190.0)

    left = board(x) + rng.normal(0, 2.0, (h, w))
    # the right view sees the board point u at x_r = u - d(u): sample u for each x_r
    u = np.linspace(0, w + 60, 8 * (w + 60))
    xr = u - (20.0 + 0.12 * u)
    uu = np.interp(x, xr, u)
    right = board(uu) + rng.normal(0, 2.0, (h, w))
    u8 = [np.clip(np.round(im), 0, 255).astype(np.uint8) for im in (left, right)]
    return u8[0], u8[1], d


def test_plane_fill_takes_a_slanted_boards_plane_in_its_squares() -> None:
    """SGM's paths carry one disparity into a flat square (the fronto-parallel bias); the
    plane of the square's textured rim follows the slant (benchmarks/check_stereo_slant.py's
    board pairs)."""
    left, right, truth = _slanted_board(7)
    inner = (slice(10, -10), slice(64 + 10, -10))

    def bad(fill: bool) -> float:
        d = stereo_disparity(left, right, num_disparities=64, plane_fill=fill)
        return float(np.mean(~(np.abs(d - truth)[inner] <= 1)))  # invalid or > 1 px off

    before, after = bad(False), bad(True)
    assert before > 0.3  # measured 0.56
    assert after < before / 2  # measured 0.19


def test_plane_fill_fits_the_rim_and_leaves_a_rim_across_two_surfaces() -> None:
    h, w = 200, 300  # 2 % of the image: 1200 pixels
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    rng = np.random.default_rng(2)
    grey = rng.uniform(0, 255, (h, w)).astype(np.float32)  # texture everywhere ...
    grey[60:90, 100:140] = 128.0  # ... but a flat square (its 5 x 5 flat part 26 x 36)
    flat = (slice(62, 88), slice(102, 138))
    plane = (5.0 + 0.05 * x - 0.02 * y).astype(np.float32)
    disp = plane.copy()
    disp[flat] = 7.0  # the square given one disparity (fronto-parallel)
    disp[70:75, 110:115] = np.nan
    out = _plane_fill(disp, grey, 0, 16)
    np.testing.assert_allclose(out[flat], plane[flat], atol=1e-3)
    np.testing.assert_array_equal(np.delete(out, np.s_[62:88], 0), np.delete(disp, np.s_[62:88], 0))
    # the band: the first min + num - 1 columns stay as they were
    out = _plane_fill(disp, grey, 0, 120)
    assert np.array_equal(out[:, :119], disp[:, :119], equal_nan=True)
    np.testing.assert_allclose(out[62:88, 119:138], plane[62:88, 119:138], atol=1e-3)
    # a rim on two surfaces (a step of 6 px through the square): no plane fits 80 % of it
    two = np.where(x < 120, plane, plane + 6.0).astype(np.float32)
    two[flat] = 7.0
    np.testing.assert_array_equal(_plane_fill(two, grey, 0, 16), two)
    # a flat region over 2 % of the image is left alone (Middlebury Venus's background)
    big = grey.copy()
    big[50:100, 90:150] = 128.0
    disp[50:100, 90:150] = 7.0
    np.testing.assert_array_equal(_plane_fill(disp, big, 0, 16), disp)


def test_median_filter_fills_isolated_invalid_pixels(scene) -> None:  # type: ignore[no-untyped-def]
    d = stereo_disparity(scene.left, scene.right, num_disparities=48)
    m = stereo_disparity(scene.left, scene.right, num_disparities=48, median_filter=True)
    np.testing.assert_array_equal(m, twin.median3(d))  # the map's median, nothing else
    band = np.zeros_like(scene.visible)
    band[:, 47:] = True
    seen = scene.visible & band
    assert np.isfinite(m[seen]).mean() > np.isfinite(d[seen]).mean()  # measured 99.3 -> 99.7 %
    assert np.isnan(m[:, :47]).all()  # the band stays invalid


def test_uniqueness_and_lr_check_remove_pixels(scene) -> None:  # type: ignore[no-untyped-def]
    loose = stereo_disparity(scene.left, scene.right, num_disparities=48, uniqueness=0.0,
                             lr_check=None)  # fmt: skip
    strict = stereo_disparity(scene.left, scene.right, num_disparities=48, uniqueness=0.3)
    assert np.isfinite(strict).sum() < np.isfinite(loose).sum()
    both = np.isfinite(strict)
    np.testing.assert_array_equal(strict[both], loose[both])  # the checks only remove


# ------------------------------------------------------------------- vertical rigs


@pytest.mark.parametrize(
    "kw",
    [
        {"num_disparities": 48},
        {"min_disparity": -3, "num_disparities": 45, "block_size": 3, "adaptive_p2": True,
         "speckle_size": 20, "uniqueness": 0.05, "median_filter": True},
    ],
)  # fmt: skip
def test_vertical_pair_gives_the_transposed_disparity(scene, kw) -> None:  # type: ignore[no-untyped-def]
    """The rendered pair transposed is a vertical rig (the second camera below the first):
    its disparity along columns is the horizontal run's, transposed, bit for bit (NaN where
    NaN), within a pixel of the transposed truth."""
    d = stereo_disparity(scene.left, scene.right, **kw)
    dv = stereo_disparity(scene.left.T, scene.right.T, vertical=True, **kw)
    assert dv.shape == (320, 240) and dv.dtype == np.float32 and dv.flags.c_contiguous
    np.testing.assert_array_equal(dv, d.T)
    lo = kw.get("min_disparity", 0) + kw["num_disparities"] - 1
    assert np.isnan(dv[:lo]).all()  # the invalid band: the first rows, not columns
    ok = scene.visible.T & np.isfinite(dv)
    assert ok.mean() > 0.6
    assert np.mean(np.abs(dv - scene.disparity.T)[ok] < 1.0) > 0.97


def test_vertical_without_numba_is_the_twin(
    small,  # type: ignore[no-untyped-def]
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    kw = {"num_disparities": 16, "speckle_size": 10, "vertical": True}
    a = stereo_disparity(small.left.T, small.right.T, **kw)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    b = stereo_disparity(small.left.T, small.right.T, **kw)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, stereo_disparity(small.left, small.right, num_disparities=16,
                                                      speckle_size=10).T)  # fmt: skip


def test_vertical_depth_is_opencvs_reprojection() -> None:
    """A vertical rig's ``Q`` (``stereo_rectify``, as OpenCV's) takes ``d = y_top - y_bottom``:
    a point projected into both rectified cameras comes back from its row difference, and
    the depth map agrees with ``cv2.reprojectImageTo3D``."""
    cv2 = pytest.importorskip("cv2")
    K1 = np.array([[560.0, 0, 322], [0, 555, 236], [0, 0, 1]])
    K2 = np.array([[575.0, 0, 316], [0, 572, 241], [0, 0, 1]])
    R = cv2.Rodrigues(np.array([0.01, 0.05, 0.005]))[0]
    T = np.array([1.0, -50.0, 4.0])  # the second camera 50 mm below the first
    rect = stereo_rectify(K1, None, K2, None, (640, 480), R, T)
    assert rect.vertical
    X = np.array([30.0, -20.0, 900.0])  # in the first camera's frame
    p1 = rect.P1 @ np.append(rect.R1 @ X, 1.0)
    p2 = rect.P2 @ np.append(rect.R1 @ X, 1.0)
    (u1, v1), (u2, v2) = p1[:2] / p1[2], p2[:2] / p2[2]
    assert abs(u1 - u2) < 1e-9 and v1 - v2 > 0  # the same column; lower in the first image
    h = rect.Q @ np.array([u1, v1, v1 - v2, 1.0])
    np.testing.assert_allclose(rect.R1.T @ (h[:3] / h[3]), X, rtol=1e-9)
    d = np.random.default_rng(4).uniform(5, 60, (40, 30)).astype(np.float32)
    ref = cv2.reprojectImageTo3D(d, rect.Q.astype(np.float32))
    np.testing.assert_allclose(disparity_to_points(d, rect), ref, rtol=1e-4)
    np.testing.assert_allclose(disparity_to_depth(d, rect), ref[..., 2], rtol=1e-4)


# ------------------------------------------------------------------- depth and points


def test_depth_and_points_against_opencv_reproject() -> None:
    cv2 = pytest.importorskip("cv2")
    K1 = np.array([[560.0, 0, 322], [0, 555, 236], [0, 0, 1]])
    K2 = np.array([[575.0, 0, 316], [0, 572, 241], [0, 0, 1]])
    R = cv2.Rodrigues(np.array([0.01, 0.05, 0.005]))[0]
    T = np.array([-50.0, 1.0, 4.0])
    for zero in (True, False):
        rect = stereo_rectify(K1, None, K2, None, (640, 480), R, T, zero_disparity=zero)
        rng = np.random.default_rng(2)
        d = rng.uniform(5, 60, (48, 64)).astype(np.float32)
        d[3, 4] = np.nan
        ref = cv2.reprojectImageTo3D(np.nan_to_num(d, nan=0.0), rect.Q.astype(np.float32))
        pts = disparity_to_points(d, rect)
        assert pts.dtype == np.float32 and pts.shape == (48, 64, 3)
        fin = np.isfinite(d)
        np.testing.assert_allclose(pts[fin], ref[fin], rtol=1e-4)
        assert np.isnan(pts[3, 4]).all()
        z = disparity_to_depth(d, rect.Q)
        np.testing.assert_allclose(z[fin], ref[fin][:, 2], rtol=1e-4)
    # Z = f B / d on a zero-disparity rectification
    rect = stereo_rectify(K1, None, K2, None, (640, 480), R, T)
    B = np.linalg.norm(T)
    z = disparity_to_depth(np.array([[20.0, 0.0, -1.0, np.nan]]), rect)
    assert z.dtype == np.float64
    np.testing.assert_allclose(z[0, 0], rect.P1[0, 0] * B / 20.0, rtol=1e-9)
    assert np.isnan(z[0, 1:]).all()  # zero and negative disparity: no point in front


def test_depth_of_the_rendered_pair(scene) -> None:  # type: ignore[no-untyped-def]
    f, B = scene.f, scene.baseline
    c = (320 - 1) / 2.0
    Q = np.array([[1, 0, 0, -c], [0, 1, 0, -(240 - 1) / 2.0], [0, 0, 0, f], [0, 0, 1 / B, 0]])
    d = stereo_disparity(scene.left, scene.right, num_disparities=48)
    z = disparity_to_depth(d, Q)
    ok = scene.visible & np.isfinite(z)
    rel = np.abs(z - scene.depth)[ok] / scene.depth[ok]
    assert np.median(rel) < 0.01  # measured 0.56 %


# ------------------------------------------------------------------- bad input


def test_census_threshold_sets_a_bit_only_past_it() -> None:
    """A neighbour's bit: darker than the centre by more than the threshold (0: any darker)."""
    img = np.full((3, 3), 100.0, dtype=np.float32)
    img[0, 0], img[0, 1], img[0, 2], img[1, 0] = 99.0, 97.0, 98.0, 101.0
    for m in (sgm, twin):
        # bits from the top-left neighbour down to the bottom-right one, the centre skipped
        for thr, bits in ((0.0, "11100000"), (1.0, "01100000"), (2.0, "01000000")):
            code = int(m.census(img, 1, np.float32(thr), np.float32(-1))[1, 1])
            assert format(code, "08b") == bits, (m, thr)


def test_graded_census_sets_a_second_bit_past_the_step() -> None:
    """Graded: two bits a neighbour, darker than the centre by more than the threshold, and by
    more than the threshold + the step; Hamming distances 0, 1 or 2 a neighbour."""
    img = np.full((3, 3), 100.0, dtype=np.float32)
    img[0, 0], img[0, 1], img[0, 2], img[1, 0] = 99.0, 95.0, 97.5, 101.0
    for m in (sgm, twin):
        for thr, step, bits in (
            (0.0, 4.0, "1011100000000000"),
            (0.0, 2.0, "1011110000000000"),
            (1.0, 2.0, "0011100000000000"),
            (0.0, 0.0, "1111110000000000"),
        ):
            code = int(m.census(img, 1, np.float32(thr), np.float32(step))[1, 1])
            assert format(code, "016b") == bits, (m, thr, step)


def _flat_squares(shift: int = 9) -> tuple[np.ndarray, np.ndarray]:
    """A board of 24 px squares seen by two sensors, each with its own faint shading.

    The shading (smooth noise of 1.5 grey levels RMS, independent in the two views) is what
    a dim endoscope's board pairs show inside the squares (check_stereo_fresh.py, davinci).
    """
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(0)
    h, w = 120, 200
    yy, xx = np.mgrid[0:h, 0 : w + shift]
    board = gaussian_filter(np.where((xx // 24 + yy // 24) % 2 == 0, 60.0, 170.0), 1.0)

    def view(img: np.ndarray) -> np.ndarray:
        sh = gaussian_filter(rng.normal(0, 1, img.shape), 2.0)
        return np.clip(np.round(img + 1.5 * sh / sh.std()), 0, 255).astype(np.uint8)

    return view(board[:, :w]), view(board[:, shift : shift + w])


def test_census_threshold_matches_flat_squares_with_faint_shading() -> None:
    """The plain census scatters in flat squares (bits set by the sensors' own shading of a
    grey level or two); with a threshold the squares cost alike at every disparity and the
    paths carry their edges' disparity in. Measured: 31.9 % of pixels more than 1 px off,
    82.3 % valid, plain; none off and all valid from a threshold of 2; OpenCV's StereoSGBM
    (Birchfield-Tomasi costs, MODE_HH) 1.9 %."""
    cv2 = pytest.importorskip("cv2")
    left, right = _flat_squares()

    def scores(d: np.ndarray) -> tuple[float, float]:
        v = d[4:-4, 20:-4]  # off the invalid band and the replicated borders
        ok = np.isfinite(v)
        return float(ok.mean()), float(np.mean(np.abs(v[ok] - 9) > 1))

    # each pixel's cost alone, as matched (the plane fill would hide the scatter)
    one = {"num_disparities": 16, "cost_window": 1, "plane_fill": False}
    plain = scores(stereo_disparity(left, right, census_step=None, **one))
    assert plain[1] > 0.25 and plain[0] < 0.9
    for thr in (2, 4.0):
        dens, bad = scores(
            stereo_disparity(left, right, census_threshold=thr, census_step=None, **one)
        )
        assert dens > 0.99 and bad < 0.002, (thr, dens, bad)
    m = cv2.StereoSGBM_create(
        0, 16, 5, P1=200, P2=800, disp12MaxDiff=1, uniquenessRatio=10,
        mode=cv2.STEREO_SGBM_MODE_HH,
    )  # fmt: skip
    ref = m.compute(left, right).astype(np.float64) / 16
    ref[ref < 0] = np.nan
    assert 0.005 < scores(ref)[1] < 0.05  # OpenCV: 1.9 %
    # 0 is the plain census, bit for bit
    np.testing.assert_array_equal(
        stereo_disparity(left, right, num_disparities=16, census_threshold=0.0, census_step=None),
        stereo_disparity(left, right, num_disparities=16, census_step=None),
    )


def test_graded_census_is_the_default_and_matches_flat_squares() -> None:
    """The default graded census (step 4) on the flat squares with faint shading: the
    shading's bits weigh half. Measured: 3.8 % of pixels more than 1 px off and 96.5 % valid
    (plain census 31.9 % and 82.3 %)."""
    left, right = _flat_squares()
    d = stereo_disparity(left, right, num_disparities=16)
    v = d[4:-4, 20:-4]
    ok = np.isfinite(v)
    assert ok.mean() > 0.95 and np.mean(np.abs(v[ok] - 9) > 1) < 0.06
    np.testing.assert_array_equal(
        d, stereo_disparity(left, right, num_disparities=16, census_step=4)
    )
    # step 0: every cost and default penalty doubled, the plain census's map (with each
    # pixel's cost alone: the block sums' divisors of 24 and 48 bits differ, 2 and 3)
    np.testing.assert_array_equal(
        stereo_disparity(left, right, num_disparities=16, census_step=0.0, cost_window=1),
        stereo_disparity(left, right, num_disparities=16, census_step=None, cost_window=1),
    )
    # a 7 x 7 window's 48 bits fill the code: the plain census
    np.testing.assert_array_equal(
        stereo_disparity(left, right, num_disparities=16, block_size=7),
        stereo_disparity(left, right, num_disparities=16, block_size=7, census_step=None),
    )


def test_graded_census_keeps_faint_texture_a_threshold_drops() -> None:
    """Texture of some 2 grey levels RMS with sensor noise: a threshold of 4 loses it, the
    graded census (whose first bit keeps every difference) matches it almost as the plain one.
    Measured, > 1 px off: plain 0.8 %, graded 1.1 %, threshold 4 5.6 % (92.4 % valid)."""
    s = render_pair(160, 120, f=200.0, ss=2, seed=3)  # disparities 9.3 to 17.4 px
    rng = np.random.default_rng(1)

    def u8(x: np.ndarray) -> np.ndarray:
        v = 100 + 2 * (x - 0.5) / s.left.std() + rng.normal(0, 0.7, x.shape)
        return np.clip(np.round(v), 0, 255).astype(np.uint8)

    left, right = u8(s.left), u8(s.right)
    region = s.visible.copy()
    region[:, :32] = False

    def bad(step: float | None = 4.0, threshold: float = 0.0) -> float:
        d = stereo_disparity(
            left, right, num_disparities=32, census_step=step, census_threshold=threshold
        )
        ok = region & np.isfinite(d)
        assert ok.sum() > 0.9 * region.sum()
        return float(np.mean(np.abs(d - s.disparity)[ok] > 1))

    plain, graded = bad(None), bad()
    assert graded < 0.02 and graded < plain + 0.01, (plain, graded)
    assert bad(None, 4.0) > 2 * graded


def test_bad_input_is_refused_in_one_line(small) -> None:  # type: ignore[no-untyped-def]
    L, R = small.left, small.right
    bad = [
        ((L, R[:, :-1]), {}, "one size"),
        ((L, R), {"num_disparities": 0}, "num_disparities"),
        ((L, R), {"num_disparities": -16}, "num_disparities"),
        ((L, R), {"num_disparities": 16.0}, "num_disparities"),
        ((L, R), {"block_size": 4}, "block_size 3, 5 or 7"),
        ((L, R), {"block_size": 9}, "block_size 3, 5 or 7"),
        ((L, R), {"p1": 10, "p2": 10}, "p2 > p1"),
        ((L, R), {"p2": 9000}, "p2"),
        ((L, R), {"uniqueness": 1.0}, "uniqueness"),
        ((L, R), {"lr_check": -1.0}, "lr_check"),
        ((L, R), {"speckle_size": -1}, "speckle_size"),
        ((L, R), {"census_threshold": -1.0}, "census_threshold"),
        ((L, R), {"census_threshold": 300.0}, "census_threshold"),
        ((L, R), {"census_threshold": float("nan")}, "census_threshold"),
        ((L, R), {"census_step": -1.0}, "census_step"),
        ((L, R), {"census_step": 300.0}, "census_step"),
        ((L, R), {"census_step": float("nan")}, "census_step"),
        ((L, R), {"census_step": -1.0, "block_size": 7}, "census_step"),
        ((np.where(L > 0.5, np.nan, L), R), {}, "left"),
        ((L, np.full_like(R, np.inf)), {}, "right"),
        ((L[..., None].repeat(2, axis=2), R[..., None].repeat(2, axis=2)), {}, "grey"),
        ((L[None, None], R[None, None]), {}, "left"),
        (("left.png", R), {}, "left"),
    ]
    for args, kw, needle in bad:
        with pytest.raises(InvalidInputError) as info:
            stereo_disparity(*args, **kw)
        msg = str(info.value)
        assert needle in msg and "\n" not in msg, (kw, msg)
    with pytest.raises(TypeError):
        stereo_disparity(L, R, adaptive_p2="yes")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="vertical"):
        stereo_disparity(L, R, vertical="yes")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="median_filter"):
        stereo_disparity(L, R, median_filter="yes")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="plane_fill"):
        stereo_disparity(L, R, plane_fill=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="slant_prior"):
        stereo_disparity(L, R, slant_prior="yes")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="subpixel") as info:
        stereo_disparity(L, R, subpixel="cubic")  # type: ignore[arg-type]
    assert "\n" not in str(info.value)
    for d, Q, needle in (
        (np.ones((2, 2)), np.eye(3), "(4, 4)"),
        (np.ones(4), np.eye(4), "(H, W)"),
        (np.full((2, 2), np.inf), np.eye(4), "inf"),
        (np.ones((2, 2)), np.full((4, 4), np.nan), "finite"),
    ):
        for fn in (disparity_to_depth, disparity_to_points):
            with pytest.raises(InvalidInputError) as info:
                fn(d, Q)
            assert needle in str(info.value)


def _flat_square_scene() -> tuple[np.ndarray, np.ndarray, tuple[slice, slice], np.ndarray]:
    """Texture everywhere but a flat square (its 5 x 5 flat part 26 x 36), and a plane."""
    h, w = 200, 300
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    rng = np.random.default_rng(2)
    grey = rng.uniform(0, 255, (h, w)).astype(np.float32)
    grey[60:90, 100:140] = 128.0
    flat = (slice(62, 88), slice(102, 138))
    plane = (5.0 + 0.05 * x - 0.02 * y).astype(np.float32)
    return grey, plane, flat, rng.uniform(-2.0, 2.0, (h, w))


def test_plane_fill_refits_on_the_regions_own_disparities_near_the_plane(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A region matched 0.6 px off its rim's plane (a curved surface's faint texture) pulls
    the plane toward it; PLANE_REFIT = 0 gives the rim's plane as it was."""
    grey, plane, flat, _ = _flat_square_scene()
    disp = plane.copy()
    disp[flat] += 0.6
    out = _plane_fill(disp, grey, 0, 16)
    shift = float(np.mean(out[flat] - plane[flat]))
    assert 0.2 < shift < 0.6  # measured 0.42: the fit of the rim's and the square's pixels
    monkeypatch.setattr(sm, "PLANE_REFIT", 0)
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16)[flat], plane[flat], atol=1e-3)


def test_plane_fill_keeps_a_region_whose_faint_texture_the_plane_misplaces(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The square's faint texture (under 3 grey levels) is matched at 7 px, its rim says
    otherwise: warped by the plane the right image no longer fits the square's pixels, so
    the region keeps its matched disparities; without the right image the plane is taken."""
    grey, plane, flat, faint = _flat_square_scene()
    grey[60:90, 100:140] += faint[60:90, 100:140].astype(np.float32)
    right = np.roll(grey, -7, axis=1)  # every pixel at 7 px
    disp = plane.copy()
    disp[flat] = 7.0
    np.testing.assert_array_equal(_plane_fill(disp, grey, 0, 16, right), disp)
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16)[flat], plane[flat], atol=1e-3)
    monkeypatch.setattr(sm, "PLANE_PHOTO", np.inf)
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16, right)[flat], plane[flat], atol=1e-3)
    # a textureless square (noise alone, 7 px everywhere): the plane is taken
    noise = grey.copy()
    noise[60:90, 100:140] = 128.0
    flat_right = np.roll(noise, -7, axis=1)
    flat_right[60:90, 93:133] += faint[:30, :40].astype(np.float32)  # the right camera's noise
    monkeypatch.undo()
    np.testing.assert_allclose(
        _plane_fill(disp, noise, 0, 16, flat_right)[flat], plane[flat], atol=1e-3
    )


def test_plane_fill_keeps_a_region_whose_plane_would_hide_matched_texture(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A rim at 20 px about a square in a scene at 5 px: on the plane the square's left part
    lands on right pixels that textured pixels at 5 px claim (seen by the right camera), so
    the plane would stand in front of them; the region keeps its matched disparities."""
    grey, _, flat, _ = _flat_square_scene()
    disp = np.full(grey.shape, 5.0, dtype=np.float32)
    disp[57:93, 97:143] = 20.0  # the rim
    disp[flat] = 7.0
    np.testing.assert_array_equal(_plane_fill(disp, grey, 0, 16), disp)
    monkeypatch.setattr(sm, "PLANE_HIDE", np.inf)
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16)[flat], 20.0, atol=1e-3)


def test_plane_fill_keeps_a_recess_seen_past_nearer_surfaces(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Five flat squares on one plane, their rims on it within 0.05 px but for the first
    square's (within 0.9 px: a rim across an occluding edge), whose own matched disparities
    lie 1.5 px behind the plane (a recess under a bench): that square keeps them, the others
    take the plane; a rim as rough with the square's pixels in front, or PLANE_RECESS off,
    and the plane is taken."""
    h, w = 120, 330
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    rng = np.random.default_rng(5)
    grey = rng.uniform(0, 255, (h, w)).astype(np.float32)
    plane = (5.0 + 0.02 * x - 0.01 * y).astype(np.float32)
    disp = plane + rng.uniform(-0.05, 0.05, (h, w)).astype(np.float32)
    squares = [(slice(40, 70), slice(20 + 60 * i, 50 + 60 * i)) for i in range(5)]
    for sq in squares:
        grey[sq] = 128.0
    inner = [(slice(s.start + 2, s.stop - 2), slice(c.start + 2, c.stop - 2)) for s, c in squares]
    rough = (slice(34, 76), slice(14, 56))
    disp[rough] = plane[rough] + rng.uniform(-0.9, 0.9, (42, 42)).astype(np.float32)
    disp[inner[0]] = plane[inner[0]] - 1.5
    out = _plane_fill(disp, grey, 0, 16)
    np.testing.assert_array_equal(out[inner[0]], disp[inner[0]])
    for sq in inner[1:]:
        np.testing.assert_allclose(out[sq], plane[sq], atol=0.05)
    monkeypatch.setattr(sm, "PLANE_RECESS", (np.inf, 0.15, 0.25))
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16)[inner[0]], plane[inner[0]], atol=0.3)
    monkeypatch.undo()
    disp[inner[0]] = plane[inner[0]] + 1.5  # in front of the plane: no recess
    np.testing.assert_allclose(_plane_fill(disp, grey, 0, 16)[inner[0]], plane[inner[0]], atol=0.3)


def test_the_plane_fills_kernels_are_their_numpy_twins_to_the_bit(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The plane fill's sums, photometric spread and hidden share (numba kernels) give the
    same numbers as the NumPy code they replace (IMAGEFORM_DISABLE_NUMBA), bit for bit."""
    rng = np.random.default_rng(11)
    m, n = 7, 3000
    seg = rng.integers(0, m, n).astype(np.intp)
    xs, ys = rng.integers(0, 200, n).astype(np.intp), rng.integers(0, 90, n).astype(np.intp)
    z = (3.0 + 0.04 * xs - 0.02 * ys + rng.normal(0.0, 0.8, n)).astype(np.float32)
    grey = rng.uniform(0, 255, (90, 200)).astype(np.float32)
    right = np.roll(grey, -3, axis=1) + rng.normal(0, 2, grey.shape).astype(np.float32)
    disp = (5.0 + rng.uniform(-3.0, 3.0, grey.shape)).astype(np.float32)
    disp[rng.uniform(size=grey.shape) < 0.2] = np.nan
    lab = rng.integers(0, m, grey.shape).astype(np.int32)
    lab[rng.uniform(size=grey.shape) < 0.5] = 0
    take = rng.uniform(size=m) < 0.7

    def run() -> list[np.ndarray]:
        coef, fitted, weight = sm._fit_planes(seg, xs, ys, z, m, None, 3)
        refit, ok, w2 = sm._fit_planes(seg, xs, ys, z, m, coef, 2)
        plane = coef[seg, 0] * xs + coef[seg, 1] * ys + coef[seg, 2]
        photo = sm._photo_ratio(grey, right, ys, xs, z, plane, seg, m)
        hidden = sm._hidden_share(disp, lab, take, coef, m)
        return [coef, fitted, weight, refit, ok, w2, photo, hidden]

    a = run()
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    b = run()
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    grey2, plane2, _, faint = _flat_square_scene()
    d2 = plane2 + faint.astype(np.float32) * 0.1
    d2[::7, ::5] = np.nan
    r2 = np.roll(grey2, -5, axis=1)
    without = _plane_fill(d2, grey2, 0, 16, r2)
    monkeypatch.delenv("IMAGEFORM_DISABLE_NUMBA")
    np.testing.assert_array_equal(_plane_fill(d2, grey2, 0, 16, r2), without)


@pytest.mark.parametrize("r2", [1, 2, 9, 13])
def test_rim_labels_kernel_is_scipys_feature_transform(
    r2: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The plane fill's rim (each pixel's nearest region within sqrt(r2) px) from the numba
    kernel's discs is the rim of SciPy's feature transform (the NumPy twin), ties between
    equally near regions included (dense random labels make many)."""
    rng = np.random.default_rng(r2)
    for h, w, share in ((37, 61, 0.9), (50, 23, 0.6), (8, 9, 0.97)):
        lab = rng.integers(1, 6, (h, w)).astype(np.int32)
        lab[rng.uniform(size=(h, w)) < share] = 0
        a = sm._rim_labels(lab, r2)
        monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
        b = sm._rim_labels(lab, r2)
        monkeypatch.delenv("IMAGEFORM_DISABLE_NUMBA")
        np.testing.assert_array_equal(a, b)
    lab = np.zeros((7, 7), np.int32)
    lab[3, 0], lab[3, 6], lab[0, 3] = 1, 2, 3  # (3, 3) is 3 px from all three: the least column
    rim = sm._rim_labels(lab, 9)
    assert rim[3, 3] == 1 and rim[3, 5] == 2 and rim[1, 3] == 3 and rim[3, 0] == 0
    assert sm._rim_labels(lab, 1)[3, 3] == 0


def test_plane_write_kernel_is_its_numpy_twin() -> None:
    """The plane fill's last step (numba ``plane_write``) puts the taken regions' pixels inside
    the band on their planes, the numbers of the NumPy code it replaces, bit for bit."""
    from imageform._kernels import sgm

    rng = np.random.default_rng(5)
    h, w, m = 40, 70, 6
    disp = rng.uniform(0, 20, (h, w)).astype(np.float32)
    disp[rng.uniform(size=(h, w)) < 0.2] = np.nan
    lab = rng.integers(0, m, (h, w)).astype(np.int32)
    take = np.array([False, True, False, True, True, False])
    coef = rng.normal(0, 1, (m, 3)) * [0.1, 0.1, 10.0]
    x0, x1 = 9, 65
    got = sgm.plane_write(disp, lab, take, coef, x0, x1)
    want = disp.copy()
    sel = take[lab]
    sel[:, :x0] = False
    sel[:, x1:] = False
    yy, xx = np.nonzero(sel)
    k = lab[yy, xx]
    want[yy, xx] = (coef[k, 0] * xx + coef[k, 1] * yy + coef[k, 2]).astype(np.float32)
    np.testing.assert_array_equal(got, want)
    assert np.isnan(got[~sel]).sum() == np.isnan(disp[~sel]).sum()
    assert not np.array_equal(got[sel], disp[sel])
