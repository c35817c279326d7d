"""detect_horizon: the visible horizon of sea, lake and plain photographs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry import HorizonResult, detect_horizon

ROOT = Path(__file__).resolve().parents[2]
KODAK = ROOT.parent / "shared" / "data" / "kodak"


def _seascape(
    roll_deg: float,
    row: float = 130.0,
    *,
    size: tuple[int, int] = (400, 300),
    seed: int = 0,
    clutter: bool = True,
) -> tuple[np.ndarray, tuple[float, float]]:
    """Sky over sea with the horizon through ``(cx, row)`` at ``roll_deg`` (right end higher: +).

    The sky pales towards the horizon and holds soft clouds; the sea is darker, with wave
    streaks; two boats (a hull across the horizon and a mast standing above it) and noise.
    Returns the image and the horizon's rows at the first and last columns.
    """
    from scipy import ndimage

    w, h = size
    rng = np.random.default_rng(seed)
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    cx = (w - 1) / 2
    t = math.tan(math.radians(roll_deg))
    horizon = row - t * (uu - cx)  # the horizon's row at each column
    above = vv < horizon
    d = (horizon - vv) / h  # height above the horizon, over the image height
    sky = np.stack([0.55 + 0.25 * np.clip(1 - d, 0, 1), 0.7 + 0.15 * d, 0.92 + 0 * d], -1)
    sea = np.stack([0.12 + 0 * d, 0.25 + 0 * d, 0.38 + 0 * d], -1)
    waves = ndimage.gaussian_filter(rng.normal(0, 1, (h, w)), (1.2, 2.5))
    sea = sea + 0.04 * waves[..., None] / waves.std()
    img = np.where(above[..., None], sky, sea)
    if clutter:
        clouds = ndimage.gaussian_filter(rng.normal(0, 1, (h, w)), 12.0)
        clouds = np.clip(clouds / clouds.std() - 0.5, 0, None) * 0.12
        img = img + np.where(above, clouds * (d > 0.12), 0.0)[..., None]
        # a boat on the horizon: dark hull across it, a thin mast above it
        for u0, hull in ((int(0.3 * w), 0.06), (int(0.72 * w), 0.03)):
            r0 = round(row - t * (u0 - cx))
            img[r0 - int(0.02 * h) : r0 + int(0.02 * h), u0 : u0 + int(hull * w)] = 0.1
            img[r0 - int(0.12 * h) : r0, u0 + 3 : u0 + 5] = 0.2
    img = img + rng.normal(0, 0.01, img.shape)
    rows = (row + t * cx, row - t * (w - 1 - cx))
    return np.clip(img, 0.0, 1.0), rows


@pytest.mark.parametrize("roll_deg", [0.0, 4.0, -9.0, 20.0])
def test_synthetic_seascape_horizon_and_roll(roll_deg: float) -> None:
    img, rows = _seascape(roll_deg)
    res = detect_horizon(img)
    assert isinstance(res, HorizonResult) and res.found, res.reason
    np.testing.assert_allclose(res.rows, rows, atol=1.5)
    assert math.degrees(res.roll) == pytest.approx(roll_deg, abs=0.3)
    a, b, c = res.line  # type: ignore[misc]
    assert b > 0 and a * a + b * b == pytest.approx(1.0)
    # the line is the one the rows say: a u + b v + c = 0 at both edges
    assert a * 0 + b * res.rows[0] + c == pytest.approx(0.0, abs=1e-9)
    assert 0.5 < res.confidence <= 1.0 and res.reason == ""


def test_roll_follows_the_camera() -> None:
    # the same scene rolled by +7 degrees: the roll found changes by 7 degrees
    base = detect_horizon(_seascape(0.0, seed=3)[0])
    turned = detect_horizon(_seascape(7.0, seed=3)[0])
    assert base.found and turned.found
    assert math.degrees(turned.roll - base.roll) == pytest.approx(7.0, abs=0.3)


def test_half_size_gives_the_same_line() -> None:
    img, rows = _seascape(5.0, size=(800, 600), row=260.0)
    full = detect_horizon(img)
    half = detect_horizon(img[::2, ::2])
    assert full.found and half.found
    np.testing.assert_allclose(full.rows, rows, atol=2.0)
    # a pixel u of the half-size image is u' = 2 u + 0.5 of the full one
    np.testing.assert_allclose(2 * half.rows + 0.5, full.rows, atol=3.0)


def test_step_edge_is_placed_between_the_rows() -> None:
    # rows 0-49 sky, 50-119 sea: the boundary is at v = 49.5
    img = np.where(np.arange(120.0)[:, None] < 50, 0.8, 0.3) * np.ones((1, 160))
    res = detect_horizon(img)
    assert res.found
    np.testing.assert_allclose(res.rows, [49.5, 49.5], atol=0.1)
    assert res.roll == pytest.approx(0.0, abs=1e-3)


def test_grey_and_rgb_agree() -> None:
    img, _ = _seascape(3.0, clutter=False)
    rgb = detect_horizon(img)
    grey = detect_horizon(img.mean(-1))
    assert rgb.found and grey.found
    np.testing.assert_allclose(grey.rows, rgb.rows, atol=1.0)


def _infrared_sea(
    roll_deg: float, row: float = 110.0, *, seed: int = 0
) -> tuple[np.ndarray, tuple[float, float]]:
    """A thermal camera's frame of a coast with surf (384 x 288, one channel, low contrast).

    As in InfML-HDD's frames: the sky brightens steadily towards the horizon (0.0025 per
    row), the sea is brighter still and brightens towards the camera, and long bright surf
    lines, parallel to the horizon and sharper than it, run across the frame below it.
    Returns the image and the horizon's rows at the first and last columns.
    """
    from scipy import ndimage

    w, h = 384, 288
    rng = np.random.default_rng(seed)
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    cx = (w - 1) / 2
    t = math.tan(math.radians(roll_deg))
    d = vv - (row - t * (uu - cx))  # distance below the horizon (rows)
    img = np.where(d < 0, 0.52 + 0.0025 * d, 0.535 + 0.002 * d)
    for k, off in enumerate((12, 26, 44, 68, 96, 128, 165)):
        along = 0.75 + 0.25 * np.tanh(8 * ndimage.gaussian_filter1d(rng.normal(0, 1, w), 15))
        img += 0.07 * np.clip(2.0 + 0.6 * k - np.abs(d - off), 0, 1) * along[None, :]
    waves = ndimage.gaussian_filter(rng.normal(0, 1, (h, w)), (1.0, 4.0))
    img += np.where(d > 0, 0.006 * waves / waves.std(), 0.0)
    img = ndimage.gaussian_filter(img, 0.8) + rng.normal(0, 0.002, (h, w))
    return np.clip(img, 0.0, 1.0), (row + t * cx, row - t * (w - 1 - cx))


@pytest.mark.parametrize(("roll_deg", "seed"), [(0.0, 0), (0.0, 2), (2.0, 0), (-3.0, 1)])
def test_infrared_sea_frame_horizon(roll_deg: float, seed: int) -> None:
    # the detector of 2026-11-29 put the horizon on the first surf line, 10 px below it
    # (seed 0: better covered than the hazier horizon), or 17 px above it (seed 2: the sky's
    # steady brightening taken for a band of haze); the horizon is now the line that parts
    # smooth sky from textured sea, and a steady gradient above it is no sky onset
    img, rows = _infrared_sea(roll_deg, seed=seed)
    res = detect_horizon(img)
    assert res.found, res.reason
    np.testing.assert_allclose(res.rows, rows, atol=1.5)
    assert math.degrees(res.roll) == pytest.approx(roll_deg, abs=0.3)


def _facade(seed: int = 0) -> np.ndarray:
    """A building seen square on: storeys, windows and pillars, over a pavement."""
    rng = np.random.default_rng(seed)
    img = np.full((300, 400, 3), 0.75)
    img[:40] = (0.6, 0.75, 0.95)  # sky above the roof
    for r in range(60, 240, 45):
        for c in range(20, 380, 50):
            img[r : r + 28, c : c + 30] = (0.2, 0.25, 0.3)
    for c in range(10, 400, 100):
        img[40:260, c : c + 6] = 0.5
    img[260:] = 0.4
    return np.clip(img + rng.normal(0, 0.01, img.shape), 0, 1)


def _mountains(seed: int = 0) -> np.ndarray:
    """A jagged skyline: no straight, level edge."""
    rng = np.random.default_rng(seed)
    w, h = 400, 300
    ridge = 120 + np.cumsum(rng.normal(0, 4, w))
    ridge = ridge - ridge.mean() + 130 + 40 * np.sin(np.arange(w) / 37.0)
    vv = np.arange(h)[:, None]
    img = np.where((vv < ridge)[..., None], [0.6, 0.75, 0.95], [0.35, 0.3, 0.25])
    return np.clip(img + rng.normal(0, 0.01, img.shape), 0, 1)


@pytest.mark.parametrize(
    "make",
    [
        lambda: np.full((120, 160), 0.5),
        lambda: np.random.default_rng(1).uniform(0, 1, (200, 300, 3)),
        _facade,
        _mountains,
    ],
    ids=["flat", "noise", "facade", "mountains"],
)
def test_scenes_without_a_horizon_are_not_found(make: object) -> None:
    res = detect_horizon(make())  # type: ignore[operator]
    assert not res.found
    assert res.line is None and np.isnan(res.roll) and np.isnan(res.rows).all()
    assert res.confidence == 0.0 and res.reason and "\n" not in res.reason


def _roof_line(kind: str, seed: int = 0) -> np.ndarray:
    """A flat roof against a clear sky: the straight sky line of a building, not a horizon.

    ``"angled"``: a wall seen at an angle, its roof line running at 25 degrees across the
    whole frame (perspective) with upright pillars rising from it; ``"beside"``: a plain wall
    over 70 % of the width, its level roof line continued by the sky down to bushes on the
    right.
    """
    rng = np.random.default_rng(seed)
    h, w = 300, 400
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    img = np.empty((h, w, 3))
    img[:] = (0.6, 0.75, 0.95)
    if kind == "angled":
        wall = vv >= 150 - math.tan(math.radians(25.0)) * (uu - 200)
        img[wall] = (0.8, 0.7, 0.55)
        for c in range(40, 400, 95):
            img[(uu >= c) & (uu < c + 10) & wall] = (0.55, 0.5, 0.42)
    else:
        img[(vv >= 110) & (uu < 280)] = (0.8, 0.7, 0.55)
        img[vv >= 240 + 8 * np.sin(uu / 7.0) + 5 * np.sin(uu / 3.1)] = (0.3, 0.4, 0.2)
    return np.clip(img + rng.normal(0, 0.01, img.shape), 0, 1)


@pytest.mark.parametrize(
    ("kind", "why"),
    [("angled", "upright straight edges below it"), ("beside", "the sky's color on both sides")],
)
def test_a_flat_roof_against_the_sky_is_not_a_horizon(kind: str, why: str) -> None:
    # the roof line is straight, covered by an edge along 70-100 % of the frame and has
    # smooth sky above it: what tells it from a horizon is the building below it (upright
    # edges rising from it) or the sky continuing below it beside the building
    res = detect_horizon(_roof_line(kind))
    assert not res.found and res.line is None
    assert why in res.reason


def _kodak(i: int) -> np.ndarray:
    from imageform.io import read_image

    path = KODAK / f"kodim{i:02d}.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    return np.asarray(read_image(path))


def test_kodak_sea_horizon_against_its_annotation() -> None:
    # kodim06 (768 x 512): the sea meets the far coast at v = 136.2 at u = 598 and 138.3 at
    # u = 767, read by eye on enlarged crops (benchmarks/check_horizon_natural.py); left of
    # u = 570 the coast hides it, so the rows at the edges are that line extended:
    # 128.8 at u = 0, 138.3 at u = 767
    res = detect_horizon(_kodak(6))
    assert res.found, res.reason
    np.testing.assert_allclose(res.rows, [128.8, 138.3], atol=0.025 * 512)
    assert abs(math.degrees(res.roll)) < 1.5


@pytest.mark.parametrize("i", [1, 8, 13, 18, 23])
def test_kodak_without_a_horizon(i: int) -> None:
    # a facade, a street of houses, a mountain stream, a woman before a metal sculpture (a
    # straight edge of it against the foliage, with upright edges below it, was taken for a
    # horizon before the roof-line tests), parrots
    assert not detect_horizon(_kodak(i)).found


@pytest.mark.parametrize(
    ("image", "kw", "match"),
    [
        (np.zeros((40, 50, 4)), {}, "image"),
        (np.zeros(50), {}, "image"),
        (np.zeros((10, 50)), {}, "at least 16 x 16"),
        (np.full((40, 50), np.nan), {}, "finite|NaN|nan"),
        (np.zeros((40, 50), dtype=np.int32), {}, "uint8"),
        (np.zeros((40, 50)), {"max_roll": 0.0}, "max_roll"),
        (np.zeros((40, 50)), {"max_roll": math.radians(85.0)}, "max_roll"),
        (np.zeros((40, 50)), {"max_roll": math.nan}, "max_roll"),
    ],
)
def test_bad_input(image: np.ndarray, kw: dict[str, float], match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        detect_horizon(image, **kw)


def test_uint8_and_float_agree() -> None:
    img, _ = _seascape(2.0)
    as8 = np.round(img * 255).astype(np.uint8)
    a, b = detect_horizon(img), detect_horizon(as8)
    assert a.found and b.found
    np.testing.assert_allclose(a.rows, b.rows, atol=0.5)


@pytest.mark.parametrize("as_uint8", [False, True])
def test_a_hazy_low_contrast_horizon_is_found(as_uint8: bool) -> None:
    # the seascape washed out towards a pale haze, a 40th of its contrast left (the sea's step
    # under the horizon is 0.02, within _SAME: before the stretch the sky's color was taken
    # to lie on both sides of it and nothing was found); 8-bit keeps 8 grey levels of it
    img, rows = _seascape(4.0)
    hazy = 0.8 + (img - 0.8) / 40.0
    if as_uint8:
        hazy = np.round(hazy * 255).astype(np.uint8)
    res = detect_horizon(hazy)
    assert res.found, res.reason
    np.testing.assert_allclose(res.rows, rows, atol=1.0)
    assert math.degrees(res.roll) == pytest.approx(4.0, abs=0.3)


@pytest.mark.parametrize(
    "make",
    [
        lambda: 0.5 + np.random.default_rng(1).normal(0.0, 0.01, (240, 320)),
        lambda: 0.4 + 0.05 * _facade(),
        lambda: 0.4 + 0.05 * _mountains(),
    ],
    ids=["flat-noise", "facade", "mountains"],
)
def test_low_contrast_scenes_without_a_horizon_are_not_found(make: object) -> None:
    # stretched (their grey levels span less than a quarter of the range) and still refused;
    # the facade at a 20th of its contrast was a false horizon before the stretch
    res = detect_horizon(make())  # type: ignore[operator]
    assert not res.found and res.reason


def test_the_stretch_leaves_normal_contrast_alone() -> None:
    from imageform.geometry.horizon_detection import _stretch_low_contrast

    img, _ = _seascape(0.0)
    out, gain = _stretch_low_contrast(img)
    assert out is img and gain == 1.0  # not stretched: bit-identical answers
    low = 0.3 + 0.1 * img
    out, gain = _stretch_low_contrast(low)
    lo, hi = np.percentile(out.mean(-1), (1.0, 99.0))
    assert (lo, hi) == pytest.approx((0.1, 0.9), abs=1e-9)
    assert gain == pytest.approx(
        8.0 / (np.percentile(img.mean(-1), 99) - np.percentile(img.mean(-1), 1))
    )


@pytest.mark.parametrize("levels", [1, 3, 8])
def test_a_quantised_smooth_sky_is_not_a_horizon(levels: int) -> None:
    # a smooth gradient over a few 8-bit codes: stretched, its contours between codes are
    # straight, level and sharp; the edge floor stays the input's (one code is no edge)
    v = np.arange(240.0)[:, None] * np.ones((1, 320))
    res = detect_horizon(np.round(120 + levels * v / 239).astype(np.uint8))
    assert not res.found and res.reason
