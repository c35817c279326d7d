"""Charts with a mark inside every patch, and the rules that keep such searches honest.

Chart software draws on the chart it found (PlantCV's ``detect_color_card`` puts a dot, an
outline and the patch's number on each; benchmarks/results/chart-fresh-2026-11-30b.md), and
charts carry labels: each patch is then a flat ring around its mark, which the moments test
of square regions rejects. :func:`_filled_holes` fills such rings; a filled region around a
whole group of flat regions (the background around a small chart) is dropped, a lattice
accepted only by the colour homography needs half the patches segmented, and no window is
scored through a homography that no camera can produce.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import ndimage

from imageform._colormath import srgb_decode
from imageform.analysis import (
    ChartPhoto,
    ChartWarning,
    detect_colorchecker,
    measure_chart_patches,
    synthetic_chart_photo,
)
from imageform.analysis import chart_detect as cd
from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from imageform.color.convert import convert
from imageform.color.delta_e import delta_e

REF_LIN = srgb_decode(np, np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0)


def _pitch(centers: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(np.diff(centers.reshape(4, 6, 2), axis=1), axis=2)))


def _dotted(seed: int, radius: float) -> tuple[np.ndarray, ChartPhoto]:
    rng = np.random.default_rng([92, seed])
    p = synthetic_chart_photo(
        width=rng.uniform(0.4, 0.6),
        tilt=rng.uniform(0.0, 25.0),
        rotation=rng.uniform(-180.0, 180.0),
        shading=0.0,
        noise=0.005,
        cast=rng.uniform(0.7, 1.0, 3),
        rng=rng,
    )
    img = p.image.copy()
    vv, uu = np.mgrid[: img.shape[0], : img.shape[1]]
    for cu, cv in p.centers:  # a cyan dot on the centre of every patch, as PlantCV draws
        img[np.hypot(uu - cu, vv - cv) < radius * _pitch(p.centers)] = [0.1, 0.9, 0.9]
    return img, p


@pytest.mark.parametrize("seed", range(8))
def test_chart_with_a_dot_on_every_patch(seed: int) -> None:
    """Found where it is (before: "no 4x6 lattice", or a false chart on the clutter beside it,
    seed 6, accepted by the colour homography), and measured by the patches' clean part."""
    img, p = _dotted(seed, 0.15)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChartWarning)  # not through the colour homography
        det = detect_colorchecker(img)
    assert det.found, det.reason
    assert det.score >= 0.9
    err = np.linalg.norm(det.centers - p.centers, axis=1).max() / _pitch(p.centers)
    assert err < 0.25
    pat = measure_chart_patches(img, det)
    assert pat.valid.all()
    lab_m = convert(np.clip(pat.means, 0, 1), "srgb", "lab")
    lab_t = convert(np.clip(p.patches, 0, 1), "srgb", "lab")
    assert np.asarray(delta_e(lab_m, lab_t)).max() < 1.0
    assert np.all(pat.used < 0.9)  # the dots were left out


def _labels(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lab, n = ndimage.label(mask)
    rows = []
    for k in range(1, n + 1):
        vv, uu = np.nonzero(lab == k)
        rows.append([uu.mean(), vv.mean(), uu.var() + 1 / 12, vv.var() + 1 / 12, len(uu)])
    return lab, np.asarray(rows)


def test_filled_holes_of_a_ring_and_not_of_a_frame() -> None:
    """A square ring (side 21, a 7 x 7 hole) fills to the whole square: area 441, fill ratio
    1 (a uniform square's variance is s^2/12); a frame around 2 x 3 holes of 12 x 14 (1008
    of its 1925-pixel outline: over half) is not filled; a plain square has no holes."""
    mask = np.zeros((80, 120), dtype=bool)
    mask[10:31, 10:31] = True
    mask[17:24, 17:24] = False  # the ring
    mask[10:31, 50:71] = True  # a plain square
    frame = np.zeros_like(mask)
    frame[40:75, 40:95] = True
    for r in range(2):
        for c in range(3):
            frame[44 + 16 * r : 44 + 16 * r + 12, 44 + 17 * c : 44 + 17 * c + 14] = False
    lab, mom = _labels(mask | frame)
    rows = cd._filled_holes(lab, np.arange(1, len(mom) + 1), mom, 1e9)
    assert rows.shape == (1, 7)
    cx, cy, area, sxx, syy, sxy, fill = rows[0]
    assert (cx, cy, area) == (20.0, 20.0, 441.0)
    assert sxx == pytest.approx(21**2 / 12) and syy == pytest.approx(21**2 / 12)
    assert sxy == pytest.approx(0.0) and fill == pytest.approx(1.0)
    # the same ring over max_area is not kept
    assert len(cd._filled_holes(lab, np.arange(1, len(mom) + 1), mom, 400.0)) == 0


def test_a_filled_region_around_several_regions_is_dropped() -> None:
    """A filled square of side 30 centred at (50, 50) holding one dot (found at two
    thresholds: two rows 1 px apart) is kept; holding two patches 10 px apart, dropped."""
    s2 = 30.0**2 / 12
    filled = np.array([[50.0, 50.0, 900.0, s2, s2, 0.0, 1.0]])
    dot = np.array([[50.0, 50.0, 50.0, 4.0, 4.0, 0.0, 1.0], [51.0, 50.0, 60.0, 4.0, 4.0, 0, 1]])
    two = np.array([[45.0, 50.0, 100.0, 8.0, 8.0, 0.0, 1.0], [55.0, 50.0, 100.0, 8, 8, 0, 1]])
    far = np.array([[95.0, 50.0, 100.0, 8.0, 8.0, 0.0, 1.0], [5.0, 50.0, 100.0, 8, 8, 0, 1]])
    assert len(cd._hold_at_most_one(filled, dot)) == 1
    assert len(cd._hold_at_most_one(filled, two)) == 0
    assert len(cd._hold_at_most_one(filled, far)) == 1  # outside: 45 px > sqrt(3 * 75)
    assert len(cd._hold_at_most_one(filled, np.zeros((0, 7)))) == 1


def test_plausible_view() -> None:
    """A scaled chart, and one seen in strong perspective (the far edge at 40 % of the near
    one: patch areas 0.4^3 apart at most), are views; a homography whose vanishing line
    crosses the chart and a perspective with patches over 40x apart in area are not."""
    scale = np.diag([30.0, 30.0, 1.0])
    scale[:2, 2] = 100.0
    assert cd._plausible_view(scale)
    persp = scale @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.3, 1.0]])
    areas = cd._cell_area(persp, cd._GRID.astype(np.float64))
    # w runs from 1 to 1.9 over the patch centres: areas 1.9^3 apart (over a whole patch, a
    # little more)
    assert areas.max() / areas.min() == pytest.approx(1.9**3, rel=0.03)
    assert cd._plausible_view(persp)
    crossing = scale @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -0.5, 1.0]])
    assert not cd._plausible_view(crossing)  # w = 0 at row 2
    steep = scale @ np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]])
    areas = cd._cell_area(steep, cd._GRID.astype(np.float64))
    assert areas.max() / areas.min() > cd._MAX_AREA_RATIO
    assert not cd._plausible_view(steep)


def test_colour_homography_needs_half_the_patches_segmented() -> None:
    """The colour homography scores a window only when at least 12 of its cells were seen as
    flat squares on the lattice; the affine fit scores it from 6."""
    p = synthetic_chart_photo(rng=3)
    det = detect_colorchecker(p.image)
    assert det.found
    h = det.homography
    work = np.asarray(p.image, dtype=np.float32)
    keys = cd._GRID.astype(np.float64)
    for n, shading, scored in ((24, True, True), (11, True, False), (11, False, True)):
        win = cd._best_window(work, h, keys[:n], REF_LIN, shading=shading)
        assert (win is not None) == scored, (n, shading)
        if scored:
            assert win is not None and win[0] > 0.95
