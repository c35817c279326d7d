"""ColorCheckers under the light of real photographs: glare over a corner, a shadow across.

Found on real photographs of ColorChecker Classic charts (benchmarks/check_chart_real.py):
glare over four patches at once and a hard shadow across the chart made the detector
answer "not found" where OpenCV's mcc found the chart. The cases here reproduce the two
properties on rendered charts (:func:`synthetic_chart_photo`, random clutter, no shading of
its own): a bright additive blob (a reflection of a lamp) centred between patches 7, 8, 13
and 14, and the linear light under one side of a line through patches 2 and 21 scaled by
0.2 (a shadow's edge).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform._colormath import srgb_decode, srgb_encode
from imageform.analysis import ChartWarning, detect_colorchecker, synthetic_chart_photo


def _chart(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng([31, seed])
    p = synthetic_chart_photo(
        width=rng.uniform(0.35, 0.55),
        tilt=rng.uniform(0.0, 30.0),
        rotation=rng.uniform(-180.0, 180.0),
        shading=0.0,
        noise=0.005,
        cast=rng.uniform(0.7, 1.0, 3),
        rng=rng,
    )
    return p.image, p.centers


def _pitch(centres: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(np.diff(centres.reshape(4, 6, 2), axis=1), axis=2)))


def _glare(img: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Add a white reflection (90 % at its centre, sigma 1 pitch) over patches 7, 8, 13, 14."""
    cu, cv = centres[[7, 8, 13, 14]].mean(axis=0)
    vv, uu = np.mgrid[: img.shape[0], : img.shape[1]]
    g = np.exp(-((uu - cu) ** 2 + (vv - cv) ** 2) / (2 * _pitch(centres) ** 2))
    return img + (1.0 - img) * 0.9 * g[..., None]


def _shadow(img: np.ndarray, centres: np.ndarray, depth: float = 0.2) -> np.ndarray:
    """Scale the linear light on one side of the line through patches 2 and 21 by ``depth``."""
    (au, av), (bu, bv) = centres[2], centres[21]
    vv, uu = np.mgrid[: img.shape[0], : img.shape[1]]
    side = (bu - au) * (vv - av) - (bv - av) * (uu - au) > 0
    lin = srgb_decode(np, img) * np.where(side, depth, 1.0)[..., None]
    return np.asarray(srgb_encode(np, lin))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_glare_over_four_patches(seed: int) -> None:
    """The four patches under the glare mask one another in the leave-one-out tests (each
    fit without one of them still holds three): the chart was not found (3 of these 4; R2
    0.72-0.75 on real photographs). The least-median fit finds it and flags the glare."""
    img, centres = _chart(seed)
    det = detect_colorchecker(_glare(img, centres))
    assert det.found, det.reason
    assert np.linalg.norm(det.centers - centres, axis=1).max() < _pitch(centres) / 6
    assert det.outliers[[7, 8, 13, 14]].sum() >= 2
    assert det.outliers.sum() <= 6


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_shadow_across_the_chart(seed: int) -> None:
    """A shadow's edge across the chart: no affine colour map fits both sides (R2 0.2-0.5,
    not found). The colour homography with a light per patch finds it, says so, and places
    the patches."""
    img, centres = _chart(seed)
    with pytest.warns(ChartWarning, match="uneven"):
        det = detect_colorchecker(_shadow(img, centres))
    assert det.found, det.reason
    assert np.linalg.norm(det.centers - centres, axis=1).max() < _pitch(centres) / 6
    # the rotation comes from the colours, not the brightness: the corner at patch 0
    assert np.argmin(np.linalg.norm(det.corners - det.centers[0], axis=1)) == 0


def test_even_light_says_nothing() -> None:
    """The fallback is only for charts the affine fit refuses: no warning otherwise."""
    img, _ = _chart(0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChartWarning)
        det = detect_colorchecker(img)
    assert det.found and not det.outliers.any()


def test_shadow_over_a_grey_card_is_not_a_chart() -> None:
    """A light per patch must not turn a lattice of unrelated colours into a chart: a
    4 x 6 lattice of random colours, half in shadow, is not found."""
    rng = np.random.default_rng(5)
    img = np.full((240, 360, 3), 0.12)
    cols = rng.uniform(0.05, 0.95, (24, 3))
    centres = np.zeros((24, 2))
    for k in range(24):
        r, c = divmod(k, 6)
        v0, u0 = 40 + 40 * r, 40 + 48 * c
        img[v0 : v0 + 32, u0 : u0 + 38] = cols[k]
        centres[k] = (u0 + 18.5, v0 + 15.5)
    shaded = _shadow(img, centres)
    assert not detect_colorchecker(shaded).found


@pytest.mark.parametrize("seed", [0, 1, 3])
def test_chart_cut_by_the_frame_beside_stray_squares(seed: int) -> None:
    """The frame cuts through the last column of patches, and two flat squares lie on the
    lattice beside the chart (left of row 1, above column 2; a hand and a cup beside a real
    chart did this). The windows tried used to stop at the lattice's extent, which the
    strays widened: the window through the cut column was never tried (not found, R2 0.33
    on the real photograph)."""
    p = synthetic_chart_photo(width=0.5, tilt=0.0, rotation=0.0, shading=0.0, noise=0.005, rng=seed)
    img = p.image.copy()
    c = p.centers.reshape(4, 6, 2)
    pitch = float(np.median(np.diff(c[..., 0], axis=1)))
    half = int(0.42 * pitch)
    strays = (
        ((c[1, 0, 0] - pitch, c[1, 0, 1]), (0.8, 0.3, 0.2)),
        ((c[0, 2, 0], c[0, 2, 1] - pitch), (0.2, 0.5, 0.8)),
    )
    for (cu, cv), colour in strays:
        img[int(cv) - half : int(cv) + half + 1, int(cu) - half : int(cu) + half + 1] = colour
    cut = int(c[:, 5, 0].mean() - 0.25 * pitch)
    det = detect_colorchecker(np.ascontiguousarray(img[:, :cut]))
    assert det.found, det.reason
    inside = np.arange(24) % 6 < 5
    err = np.linalg.norm(det.centers - p.centers, axis=1)[inside]
    assert err.max() < pitch / 6


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_small_chart_in_a_large_photograph(seed: int) -> None:
    """A chart of 23-24 px per patch in a 3200 x 2400 frame (a phone photograph of a chart
    on a cluttered desk, shrunk): block-averaged 4 x 4 to 1024 px it was 6 px per patch and
    merged into its surround (not found in 6 of 6); the search now looks once more at twice
    the resolution."""
    from scipy import ndimage

    rng = np.random.default_rng([33, seed])
    p = synthetic_chart_photo(
        shape=(480, 640),
        width=0.25,
        tilt=rng.uniform(0.0, 30.0),
        rotation=rng.uniform(-180.0, 180.0),
        noise=0.005,
        rng=rng,
    )
    smooth = rng.uniform(0.1, 0.9, (12, 16, 3))
    big = ndimage.zoom(smooth, (200, 200, 1), order=3, grid_mode=True, mode="nearest")
    big = np.clip(big, 0.0, 1.0)
    big[900:1380, 1200:1840] = p.image
    centres = p.centers + [1200, 900]
    det = detect_colorchecker(big)
    assert det.found, det.reason
    assert np.linalg.norm(det.centers - centres, axis=1).max() < _pitch(centres) / 6
