"""Chart patches with marks over part of them are measured by the colour of their clean part.

Real charts carry labels and numbers printed on their patches, pen marks, stickers, a
reflection, a finger or a cable across a few patches (benchmarks/results/chart-real-2026-
11-29c.md: three public photographs whose every patch had a label or a drawn number; their
plain means were unusable). The marks here are drawn on rendered charts
(:func:`synthetic_chart_photo`, whose true patch colours are known) over 10-40 % of the
sampled square of eight patches: a sticker, a pen stroke, a two-letter label.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform.analysis import (
    ChartPatches,
    ChartWarning,
    detect_colorchecker,
    measure_chart_patches,
    synthetic_chart_photo,
)
from imageform.analysis.chart_detect import _quad_mask_bounds
from imageform.analysis.chart_grid import _clean_pixels
from imageform.color.convert import convert
from imageform.color.delta_e import delta_e
from imageform.errors import InvalidInputError

#: The stated accuracy: CIEDE2000 of a marked patch's measured colour to its true colour.
_MAX_DE00 = 1.0


def _photo(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng([91, seed])
    p = synthetic_chart_photo(
        width=rng.uniform(0.4, 0.6),
        tilt=rng.uniform(0.0, 25.0),
        rotation=rng.uniform(-180.0, 180.0),
        shading=0.0,
        noise=0.005,
        cast=rng.uniform(0.7, 1.0, 3),
        rng=rng,
    )
    return p.image, p.centers, p.patches


def _pitch(centers: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(np.diff(centers.reshape(4, 6, 2), axis=1), axis=2)))


def _mark(
    img: np.ndarray, centers: np.ndarray, patches: list[int], kind: str, share: float, seed: int
) -> np.ndarray:
    """Draw a mark over ``share`` of the sampled square (half side 0.25 pitch) of ``patches``."""
    out = img.copy()
    p = _pitch(centers)
    half = 0.25 * p
    vv, uu = np.mgrid[: img.shape[0], : img.shape[1]]
    rng = np.random.default_rng(seed)
    for k in patches:
        cu, cv = centers[k]
        du, dv = uu - cu, vv - cv
        if kind == "sticker":  # a square in a corner of the sampled square
            side = np.sqrt(share) * 2 * half
            m = (du >= -half - 3) & (du < -half + side) & (dv >= -half - 3) & (dv < -half + side)
            color = rng.uniform(0.0, 1.0, 3)
        elif kind == "line":  # a pen stroke through the patch, any direction
            a = rng.uniform(0.0, np.pi)
            across = np.abs(du * np.sin(a) - dv * np.cos(a))
            m = (across < share * half) & (np.hypot(du, dv) < 0.45 * p)
            color = np.array([0.05, 0.05, 0.6])
        else:  # a label: two rings ("00"), strokes thick enough to cover ``share``
            m = np.zeros(img.shape[:2], dtype=bool)
            for off in (-0.12, 0.12):
                r = np.hypot((du - off * p) / (0.1 * p), dv / (0.2 * p))
                m |= (r > 1.0 - 1.35 * share) & (r < 1.0)
            color = np.array([0.9, 0.1, 0.1])
        out[m] = color
    return out


def _de00(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lab_a = np.asarray(convert(np.clip(a, 0.0, 1.0), "srgb", "lab"))
    lab_b = np.asarray(convert(np.clip(b, 0.0, 1.0), "srgb", "lab"))
    return np.asarray(delta_e(lab_a, lab_b))


MARKED = [0, 3, 7, 10, 14, 18, 19, 23]


@pytest.mark.parametrize("kind", ["sticker", "line", "label"])
@pytest.mark.parametrize("share", [0.1, 0.25, 0.4])
def test_marked_patches_give_the_colour_of_their_clean_part(kind: str, share: float) -> None:
    """Every marked patch is measured within 1 ΔE00 of its true colour (was: all missing).

    At 40 % some may be flagged instead: through the perspective the mark covers more of the
    sampled square, and under ``min_clean`` (0.6) of it is left clean, or nearly half, and
    which of its two colours is the patch's is unknown.
    """
    seed = int(share * 100) + len(kind)
    img, centers, truth = _photo(seed)
    det = detect_colorchecker(img)  # the chart's geometry, from the unmarked photograph
    assert det.found
    marked = _mark(img, centers, MARKED, kind, share, seed)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ChartWarning)
        pat = measure_chart_patches(marked, det)
    assert not pat.saturated.any()
    assert not pat.missing[np.setdiff1d(np.arange(24), MARKED)].any()
    if share < 0.3:
        assert not pat.missing.any() and not caught
    else:
        assert np.all(pat.used[pat.missing] < 0.65)
    err = _de00(pat.means, truth)
    assert err[pat.valid].max() < _MAX_DE00, err[MARKED]
    clean = np.setdiff1d(np.arange(24), MARKED)
    assert np.all(pat.used[clean] > 0.98)
    assert np.all(pat.used[MARKED] < 1.0 - 0.5 * share)  # the mark's pixels were left out
    assert np.all(pat.used[MARKED] > 1.0 - share - 0.12)  # and little else
    # the plain means of the marked patches (min_clean=1: no pixel may be left out) are off
    with pytest.warns(ChartWarning, match="missing"):
        strict = measure_chart_patches(marked, det, min_clean=1.0)
    assert strict.missing[MARKED].all()


def test_unmarked_chart_measures_as_before() -> None:
    """Without marks the trimmed mean is the plain mean (the noise's tails only)."""
    img, _, truth = _photo(5)
    det = detect_colorchecker(img)
    pat = measure_chart_patches(img, det)
    assert np.all(pat.used > 0.99)
    assert _de00(pat.means, truth).max() < 0.5


def test_marks_on_a_detected_chart_are_not_outliers() -> None:
    """A chart found with marks on eight patches: they are measured, not flagged occluded."""
    img, centers, truth = _photo(3)
    marked = _mark(img, centers, MARKED, "label", 0.1, 3)
    det = detect_colorchecker(marked)
    assert det.found
    err = np.linalg.norm(det.centers - centers, axis=1).max() / _pitch(centers)
    assert err < 0.25
    assert not det.outliers.any()
    pat = measure_chart_patches(marked, det)
    assert pat.valid.all()
    assert _de00(pat.means, truth).max() < _MAX_DE00


def test_too_little_clean_area_is_flagged() -> None:
    """A patch with less than ``min_clean`` of it clean is missing, with a ChartWarning."""
    img, centers, _ = _photo(4)
    det = detect_colorchecker(img)
    marked = _mark(img, centers, [5, 9], "sticker", 0.4, 4)
    with pytest.warns(ChartWarning, match=r"missing patch\(es\) \[5, 9\]"):
        pat = measure_chart_patches(marked, det, min_clean=0.7)
    assert pat.missing.tolist() == [k in (5, 9) for k in range(24)]
    assert np.all(pat.used[[5, 9]] < 0.7)
    # a sampling square over an edge between two patches (two colours, about half each):
    # which is the patch's is unknown, so every patch is missing (min_clean at its default)
    shifted = detect_colorchecker(img)
    quads = shifted.quads + (shifted.centers[1] - shifted.centers[0]) / 2
    moved = type(shifted)(
        shifted.homography,
        shifted.corners,
        shifted.centers,
        quads,
        shifted.segmented,
        shifted.outliers,
        shifted.score,
        shifted.rotation,
    )
    with pytest.raises(InvalidInputError, match="no usable chart patch"):
        measure_chart_patches(img, moved)


def test_clean_pixels_spread_is_the_normal_consistent_mad() -> None:
    """The robust sigma is scipy's ``median_abs_deviation(scale="normal")``: 4 of them keep a
    normal sample's 99.99 %, and pixels of another colour are left out."""
    from scipy import stats

    rng = np.random.default_rng(0)
    px = rng.normal(0.5, 0.01, (20000, 3))
    mad = stats.median_abs_deviation(px, axis=0, scale="normal")
    assert np.allclose(1.4826 * np.median(np.abs(px - np.median(px, axis=0)), axis=0), mad, 1e-4)
    keep = _clean_pixels(px)
    assert keep.mean() > 0.999
    px[:6000] = [0.9, 0.1, 0.1]  # a red label over 30 %
    keep = _clean_pixels(px)
    assert not keep[:6000].any() and keep[6000:].mean() > 0.999
    assert _clean_pixels(np.full((10, 3), 0.3)).all()  # a flat rendered patch: no spread


def test_kept_median_is_numpys_nanmedian() -> None:
    """The median over the kept pixels is ``np.nanmedian`` with the others NaN, bit for bit
    (odd and even counts, ties, a patch with none kept: NaN)."""
    import warnings

    from imageform.analysis.chart_grid import _kept_median

    rng = np.random.default_rng(3)
    for trial in range(60):
        n = int(rng.integers(1, 50))
        px = rng.random((4, 2, n, 3))
        if trial % 2:
            px = np.round(px * 6) / 6  # ties
        keep = rng.random((4, 2, n)) < rng.uniform(0.0, 1.0)
        keep[0, 0] = False
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            want = np.nanmedian(np.where(keep[..., None], px, np.nan), axis=-2, keepdims=True)
        assert np.array_equal(_kept_median(px, keep), want, equal_nan=True)


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5, float("nan"), "half", None])
def test_min_clean_bad_input(bad: object) -> None:
    """``min_clean`` outside (0, 1] is one clear error."""
    img, _, _ = _photo(0)
    det = detect_colorchecker(img)
    with pytest.raises((InvalidInputError, TypeError), match="min_clean"):
        measure_chart_patches(img, det, min_clean=bad)  # type: ignore[arg-type]


def test_chart_patches_used_validated() -> None:
    """``ChartPatches.used`` defaults to all pixels, and is checked for shape and range."""
    z = np.zeros((2, 3))
    flags = np.zeros(2, dtype=bool)
    assert ChartPatches(z, z, flags, flags).used.tolist() == [1.0, 1.0]
    assert ChartPatches(z, z, flags, flags, np.array([0.5, 1.0])).used.tolist() == [0.5, 1.0]
    with pytest.raises(InvalidInputError, match="used"):
        ChartPatches(z, z, flags, flags, np.ones(3))
    with pytest.raises(InvalidInputError, match="used"):
        ChartPatches(z, z, flags, flags, np.array([0.5, 1.5]))
    with pytest.raises(InvalidInputError, match="used"):
        ChartPatches(z, z, flags, flags, np.array([0.5, np.nan]))


def test_real_labelled_chart_is_found_and_measured_by_its_fills() -> None:
    """A rendered Classic with a label "A1".."F4" on every patch (tests/data/chart-real, MIT).

    Before: "no 4x6 lattice of flat patches", and every patch's plain mean off by the label.
    Now found on the patches' dominant colours (upright), every patch within 1 ΔE00 of its
    fill (its most frequent pixel value), the labels left out.
    """
    from pathlib import Path

    from PIL import Image

    path = Path(__file__).resolve().parents[1] / "data" / "chart-real"
    img = np.asarray(Image.open(path / "jtvd-square_pattern-half.png").convert("RGB"))
    det = detect_colorchecker(img)
    assert det.found and det.score >= 0.9
    assert abs(det.rotation) < 2.0
    pat = measure_chart_patches(img, det)
    assert pat.valid.all()
    fills = []
    for q in det.quads:
        sv, su, m = _quad_mask_bounds(q, *img.shape[:2])
        vals, counts = np.unique(img[sv, su][m], axis=0, return_counts=True)
        fills.append(vals[counts.argmax()] / 255.0)
    assert _de00(pat.means, np.asarray(fills)).max() < _MAX_DE00
    assert np.all(pat.used < 0.95)  # every patch's label was left out
    with pytest.raises(InvalidInputError, match="no usable chart patch"):
        measure_chart_patches(img, det, min_clean=1.0)  # no pixel may be left out
