"""ColorChecker detection in uncropped photographs (imageform.analysis.chart_detect).

Cases: a rendered chart composited into REAL Kodak photographs (tests/analysis/
chart_cases.py: perspective, any rotation, illuminant cast, uneven light, blur, noise, JPEG,
occluded patches); the benchmark (benchmarks/bench_chart_detect.py) runs 120 of them against
colour-checker-detection.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from imageform._kernels.chart import (
    flat_gradient_numba,
    flat_gradient_numpy,
    lmeds_best_numba,
    lmeds_best_numpy,
    region_moments_numba,
    region_moments_numpy,
    upsample2_numba,
    upsample2_numpy,
)
from imageform.analysis import (
    ChartDetection,
    ChartNotFoundError,
    ChartPhoto,
    ChartWarning,
    chart_patches,
    detect_colorchecker,
    fit_color_correction,
    measure_chart_patches,
    synthetic_chart_image,
    synthetic_chart_photo,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from imageform.color.convert import convert
from imageform.color.delta_e import delta_e
from imageform.errors import ImageformError, InvalidInputError
from tests.analysis.chart_cases import chart_case, kodak_images

REF = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0


def _de(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.asarray(delta_e(convert(np.clip(a, 0, 1), "srgb", "lab"), convert(b, "srgb", "lab")))


@pytest.fixture(scope="module")
def kodak(shared_data: Path) -> list[np.ndarray]:
    return kodak_images(shared_data)


@pytest.mark.parametrize("seed", [0, 2, 3, 5, 7, 11, 13, 17, 19, 23])
def test_detects_chart_in_real_photographs(kodak: list[np.ndarray], seed: int) -> None:
    case = chart_case(kodak, seed)
    det = detect_colorchecker(case.image)
    err = np.linalg.norm(det.centers - case.centres, axis=1)
    assert err.max() < case.pitch / 6, (seed, err.max(), case.pitch, case.params)
    assert det.score > 0.9


def test_no_chart_in_kodak_photographs(kodak: list[np.ndarray]) -> None:
    for img in kodak[::3]:
        det = detect_colorchecker(np.round(img * 255).astype(np.uint8))
        assert not det.found
        msg = det.reason
        assert msg and "\n" not in msg and len(msg) < 200


def test_not_found_is_a_result_and_measuring_it_raises() -> None:
    # docs/conventions.md "Not found": the detector answers found=False with the reason
    flat = np.full((200, 300, 3), 0.5)
    det = detect_colorchecker(flat)
    assert not det.found and "flat square region" in det.reason
    assert np.isnan(det.centers).all() and det.centers.shape == (24, 2)
    assert det.quads.shape == (24, 4, 2) and np.isnan(det.homography).all()
    assert not det.segmented.any() and not det.outliers.any()
    assert np.isnan(det.score) and np.isnan(det.rotation)
    d = det.to_dict()
    assert d["found"] is False and d["centers"] is None and d["reason"] == det.reason
    small = detect_colorchecker(np.full((8, 300, 3), 0.5))
    assert not small.found and "too small" in small.reason
    # what needs the chart raises ChartNotFoundError (an ImageformError), one line
    assert issubclass(ChartNotFoundError, ImageformError)
    with pytest.raises(ChartNotFoundError, match=r"^no ColorChecker found in the image: 0 flat"):
        measure_chart_patches(flat, det)
    # a found=False record is checked like a found one; NaN only when not found
    with pytest.raises(InvalidInputError, match="homography contains NaN"):
        ChartDetection(
            det.homography,
            det.corners,
            det.centers,
            det.quads,
            det.segmented,
            det.outliers,
            1.0,
            0.0,
            found=True,
        )


def test_occluded_patches_are_flagged(kodak: list[np.ndarray]) -> None:
    case = chart_case(kodak, 4, occlude=3)
    det = detect_colorchecker(case.image)
    assert np.linalg.norm(det.centers - case.centres, axis=1).max() < case.pitch / 6
    with pytest.warns(ChartWarning, match="missing"):
        pat = measure_chart_patches(case.image, det)
    assert not pat.valid[case.occluded].any()
    assert pat.valid[~case.occluded].sum() >= 19


@pytest.mark.parametrize("rotation", [0.0, 90.0, 180.0, -90.0, 135.0])
def test_orientation_from_colours(rotation: float) -> None:
    photo = synthetic_chart_photo(rotation=rotation, tilt=0.0, width=0.4, rng=5)
    det = detect_colorchecker(photo.image)
    assert np.linalg.norm(det.centers - photo.centers, axis=1).max() < 1.0
    diff = (det.rotation - rotation + 180.0) % 360.0 - 180.0
    assert abs(diff) < 2.0
    # corners: top-left of the upright chart is nearest the dark-skin patch (0)
    assert np.argmin(np.linalg.norm(det.corners - det.centers[0], axis=1)) == 0


def test_patch_means_match_the_truth_within_half_delta_e() -> None:
    # the bar: patch means within 0.5 CIEDE2000 of the chart's own colours
    photo = synthetic_chart_photo(tilt=30.0, width=0.5, shading=0.0, noise=0.01, rng=2)
    det = detect_colorchecker(photo.image)
    pat = measure_chart_patches(photo.image, det)
    assert pat.valid.all()
    de = _de(pat.means, photo.patches)
    assert np.median(de) < 0.5 and de.max() < 1.0


def test_measure_matches_chart_patches_on_a_cropped_chart() -> None:
    # a chart that fills the frame, padded with a dark border: the two samplers agree
    chart = synthetic_chart_image(patch=40, gap=8, background=0.06)
    img = np.pad(chart, ((60, 60), (80, 80), (0, 0)), constant_values=0.3)
    det = detect_colorchecker(img)
    ours = measure_chart_patches(img, det)
    theirs = chart_patches(chart)
    assert np.abs(ours.means - theirs.means).max() < 1e-6
    assert np.abs(ours.means - REF).max() < 1e-6
    assert det.rotation == pytest.approx(0.0, abs=0.5)
    # the centres are the patch centres (pixel-centre convention): cell 48, patch at 4 + 60
    assert det.centers[0] == pytest.approx([80 + 4 + 19.5, 60 + 4 + 19.5], abs=0.2)


def test_correction_from_a_photograph_with_a_cast() -> None:
    photo = synthetic_chart_photo(cast=(1.0, 0.8, 0.6), shading=0.0, noise=0.005, rng=8)
    det = detect_colorchecker(photo.image)
    pat = measure_chart_patches(photo.image, det)
    corr = fit_color_correction(pat, REF)
    before = _de(pat.means, REF)
    after = _de(np.clip(corr.apply(pat.means), 0, 1), REF)
    assert np.mean(before) > 5 and np.mean(after) < 2.5


def test_custom_reference_and_validation() -> None:
    photo = synthetic_chart_photo(rng=4)
    with pytest.raises(InvalidInputError, match="reference"):
        detect_colorchecker(photo.image, reference=np.ones((23, 3)))
    with pytest.raises(InvalidInputError, match="reference"):
        detect_colorchecker(photo.image, reference=np.full((24, 3), 2.0))
    with pytest.raises(InvalidInputError, match="shape"):
        detect_colorchecker(np.zeros((40, 40)))
    with pytest.raises(InvalidInputError, match="min_score"):
        detect_colorchecker(photo.image, min_score=2.0)
    with pytest.raises(TypeError, match="ChartDetection"):
        measure_chart_patches(photo.image, "chart")  # type: ignore[arg-type]
    # a grey "reference" cannot be recognised: no chart matches it
    assert not detect_colorchecker(photo.image, reference=np.full((24, 3), 0.5)).found


def test_detection_to_dict_and_checks() -> None:
    det = detect_colorchecker(synthetic_chart_photo(rng=6).image)
    d = det.to_dict()
    assert len(d["centers"]) == 24 and len(d["quads"][0]) == 4
    assert d["found"] is True and d["reason"] == "" and len(d["segmented"]) == 24
    with pytest.raises(InvalidInputError, match="segmented"):
        ChartDetection(
            det.homography,
            det.corners,
            det.centers,
            det.quads,
            np.ones(23, bool),
            det.outliers,
            1.0,
            0.0,
        )


def test_patches_outside_the_frame_are_missing() -> None:
    photo = synthetic_chart_photo(width=0.5, tilt=0.0, rotation=0.0, rng=9)
    det = detect_colorchecker(photo.image)
    moved = ChartDetection(
        det.homography,
        det.corners,
        det.centers,
        det.quads - [det.quads[:, :, 0].min() + 5000, 0],
        det.segmented,
        det.outliers,
        det.score,
        det.rotation,
    )
    with pytest.raises(InvalidInputError, match="no usable chart patch"):
        measure_chart_patches(photo.image, moved)


def test_kernels_match_their_twins() -> None:
    rng = np.random.default_rng(0)
    img = rng.uniform(0, 1, (37, 53, 3)).astype(np.float32)
    taps = np.array([0.1, 0.2, 0.4, 0.2, 0.1], dtype=np.float32)
    a = flat_gradient_numba(img, taps)
    b = flat_gradient_numpy(img, taps.astype(np.float64))
    assert np.abs(a - b).max() < 1e-5
    labels = rng.integers(0, 6, (37, 53)).astype(np.int32)
    assert np.allclose(region_moments_numba(labels, 5), region_moments_numpy(labels, 5))


def test_upsample_is_scipys_bilinear_zoom_to_the_bit() -> None:
    from scipy import ndimage

    rng = np.random.default_rng(1)
    for shape in [(1, 1, 3), (1, 6, 3), (5, 1, 3), (37, 53, 3)]:
        img = rng.uniform(0, 1, shape).astype(np.float32)
        want = ndimage.zoom(img, (2, 2, 1), order=1, grid_mode=True, mode="nearest")
        assert np.array_equal(upsample2_numba(img), want)
        assert np.array_equal(upsample2_numpy(img), want)
    # 8-bit values and their block means, the detector's working images
    img = (rng.integers(0, 256, (20, 30, 3)) / np.float32(255)).astype(np.float32)
    want = ndimage.zoom(img, (2, 2, 1), order=1, grid_mode=True, mode="nearest")
    assert np.array_equal(upsample2_numba(img), want)


def test_least_median_kernel_picks_the_twins_subset() -> None:
    from imageform.analysis.chart_detect import _lab_from_linear, _lmeds_subsets, _xyz_white

    rng = np.random.default_rng(2)
    for _ in range(60):
        m = int(rng.integers(14, 25))
        ref = rng.uniform(0.02, 0.9, (m, 3))
        meas = np.clip(ref @ (np.eye(3) + 0.2 * rng.random((3, 3))) / 2, 0, 1)
        meas += rng.normal(0, 0.005, meas.shape)
        bad = int(rng.integers(0, 6))
        meas[:bad] = rng.random((bad, 3))  # spoiled patches (glare, an occluder)
        x = np.c_[meas, np.ones(m)]
        lab, sub, to_xyz = _lab_from_linear(ref), _lmeds_subsets(m), _xyz_white()
        a = lmeds_best_numba(x, ref, lab, sub, to_xyz)
        b = lmeds_best_numpy(x, ref, lab, sub, to_xyz)
        # the same subset, or the same patches drawn in another order (a tie to rounding)
        assert a == b or sorted(sub[a]) == sorted(sub[b])


def test_no_numpy_warnings_from_a_photograph_with_degenerate_lattices(shared_data: Path) -> None:
    # kodim08's facade grows lattices whose last refit is degenerate (a vanishing line
    # through the cells): the search sets them aside without NumPy's RuntimeWarnings
    from imageform.io import read_image

    img = np.asarray(read_image(shared_data / "kodak" / "kodim08.png"))[..., :3]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        det = detect_colorchecker(img)
    assert not det.found


def _off_reference(seed: int) -> np.ndarray:
    """The Classic's colours with its 18 colour patches moved (a chart printed off them)."""
    ref = np.asarray(COLORCHECKER_SRGB8, float) / 255
    gen = np.random.default_rng(seed)
    ref[:18] = np.clip(ref[:18] + gen.normal(0, 0.2, (18, 3)), 0, 1)
    return ref


@pytest.mark.parametrize("seed", [3, 6, 9])
def test_a_whole_chart_is_found_by_its_shape_below_min_score(seed: int) -> None:
    # against a reference its colours fit at R2 0.73-0.77 (under 0.8): every cell a flat
    # square, nothing on the lattice around it, its orientation still in its colours
    photo = synthetic_chart_photo(rng=1, tilt=20.0, rotation=30.0, width=0.4)
    ref = _off_reference(seed)
    with pytest.warns(ChartWarning, match="found by its shape"):
        det = detect_colorchecker(photo.image, reference=ref)
    assert det.found and 0.65 <= det.score < 0.8, det.score
    assert np.linalg.norm(det.centers - photo.centers, axis=1).max() < 1.0
    # the relief follows min_score: 0.15 under it
    strict = detect_colorchecker(photo.image, reference=ref, min_score=0.95)
    assert not strict.found and "colour fit R2" in strict.reason


@pytest.mark.parametrize("seed", [3, 9])
def test_two_charts_side_by_side_are_a_grid_not_a_chart_by_shape(seed: int) -> None:
    # an upright chart is found by its shape (one stray square beside it is clutter); the
    # same chart with its copy beside it, the lattice going on for 6 more columns, is not
    photo = synthetic_chart_photo(rng=1, tilt=0.0, rotation=0.0, width=0.3)
    ref = _off_reference(seed)
    with pytest.warns(ChartWarning, match="found by its shape"):
        det = detect_colorchecker(photo.image, reference=ref)
    assert det.found and det.score < 0.8
    assert np.linalg.norm(det.centers - photo.centers, axis=1).max() < 1.0
    c = photo.centers
    pitch = float(np.median(np.diff(c.reshape(4, 6, 2)[..., 0], axis=1)))
    u0, v0 = round(c[0, 0] - 0.5 * pitch), round(c[0, 1] - 0.5 * pitch)
    w, h = round(6 * pitch), round(4 * pitch)
    twin = photo.image.copy()
    twin[v0 : v0 + h, u0 - w : u0] = photo.image[v0 : v0 + h, u0 : u0 + w]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChartWarning)
        assert not detect_colorchecker(twin, reference=ref).found


def test_a_chart_of_other_colours_is_not_found_by_its_shape() -> None:
    # the same whole, isolated lattice against unrelated colours: its shape is not enough
    photo = synthetic_chart_photo(rng=1, tilt=20.0, rotation=30.0, width=0.4)
    ref = np.random.default_rng(0).uniform(0.05, 0.95, (24, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChartWarning)
        det = detect_colorchecker(photo.image, reference=ref)
    assert not det.found


def test_against_colour_checker_detection(kodak: list[np.ndarray]) -> None:
    ccd = pytest.importorskip("colour_checker_detection")
    case = chart_case(kodak, 1, occlude=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        peer = ccd.detect_colour_checkers_segmentation(case.image.astype(np.float32) / 255)
    det = detect_colorchecker(case.image)
    ours = measure_chart_patches(case.image, det)
    assert np.median(_de(ours.means, case.patches)) < 2.0
    if len(peer):  # the peer's swatches, same order, agree with ours
        assert np.median(_de(np.asarray(peer[0], float), ours.means)) < 3.0


def test_cli_chart(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``imageform chart``: JSON, overlay, CSV (read back by fit-correction), correction
    (read by harmonize); a photograph without a chart exits 1 with one line."""
    import json

    from imageform.cli import main
    from imageform.io import read_image, write_image

    photo = synthetic_chart_photo(cast=(1.0, 0.85, 0.7), rng=3)
    src = tmp_path / "photo.png"
    write_image(src, np.round(photo.image * 255).astype(np.uint8))
    out, ov, csv, corr = (tmp_path / n for n in ("c.json", "ov.png", "p.csv", "corr.json"))
    argv = ["chart", str(src), "-o", str(out), "--overlay", str(ov), "--csv", str(csv)]
    assert main([*argv, "--correction", str(corr), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["mean_after"] < 1.5 < res["mean_before"]
    data = json.loads(out.read_text())
    assert data["kind"] == "colorchecker" and len(data["chart"]["centers"]) == 24
    assert np.abs(np.asarray(data["chart"]["centers"]) - photo.centers).max() < 1.0
    assert read_image(ov).shape == photo.image.shape
    assert main(["fit-correction", str(csv), "-o", str(tmp_path / "c2.json")]) == 0
    fixed = tmp_path / "fixed.png"
    assert main(["harmonize", str(src), "-o", str(fixed), "--correction", str(corr)]) == 0
    capsys.readouterr()
    blank = tmp_path / "blank.png"
    write_image(blank, np.full((64, 96, 3), 128, np.uint8))
    assert main(["chart", str(blank), "-o", str(tmp_path / "x.json")]) == 1
    err = capsys.readouterr().err.strip()
    assert "no ColorChecker found" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("seed", [1, 3])
def test_tiny_chart_found_on_the_upsample(seed: int) -> None:
    # patch pitch about 7-8 pixels, blurred: missed at full resolution, found 2x upsampled
    photo = synthetic_chart_photo(width=0.07, tilt=30.0, blur=1.2, noise=0.01, rng=seed)
    pitch = np.linalg.norm(photo.centers[1] - photo.centers[0])
    det = detect_colorchecker(photo.image)
    assert np.linalg.norm(det.centers - photo.centers, axis=1).max() < pitch / 6


@pytest.mark.parametrize(("rotation", "seed"), [(0.0, 5), (90.0, 7), (200.0, 9)])
def test_mirrored_chart_is_found_and_said_so(rotation: float, seed: int) -> None:
    # a webcam's mirrored preview shows the chart with its columns reversed (12 of the
    # tuning photographs of benchmarks/results/chart-fresh-2026-12-01e.md): no rotation of
    # the printed chart matches its colours, the mirrored search does
    photo = synthetic_chart_photo(rotation=rotation, tilt=20.0, width=0.4, rng=seed)
    img = np.ascontiguousarray(photo.image[:, ::-1])
    truth = np.c_[img.shape[1] - 1 - photo.centers[:, 0], photo.centers[:, 1]]
    printed_only = detect_colorchecker(img, mirrored=False)
    assert not printed_only.found and "R2" in printed_only.reason
    det = detect_colorchecker(img)
    assert det.found and det.mirrored and det.to_dict()["mirrored"] is True
    assert np.linalg.norm(det.centers - truth, axis=1).max() < 1.0
    assert np.linalg.det(det.homography[:2, :2]) < 0
    pat = measure_chart_patches(img, det)
    assert np.median(_de(pat.means, photo.patches)) < 1.0
    # the chart as printed is found as such, and is not a mirrored chart
    upright = detect_colorchecker(photo.image)
    assert upright.found and not upright.mirrored
    mirrored_only = detect_colorchecker(photo.image, mirrored=True)
    assert not mirrored_only.found and "R2" in mirrored_only.reason
    with pytest.raises(InvalidInputError, match="mirrored"):
        detect_colorchecker(photo.image, mirrored="yes")  # type: ignore[arg-type]


def _passport_layout(photo: ChartPhoto) -> np.ndarray:
    """The photograph's upright chart with its first and third rows reversed (the layout of
    the ColorChecker Passports in two public repositories' photographs)."""
    img = np.array(photo.image)
    c = np.asarray(photo.centers).reshape(4, 6, 2)
    half = int(0.4 * np.median(np.diff(c[0, :, 0])))
    src = img.copy()
    for row in (0, 2):
        for col in range(6):
            (u, v), (u2, v2) = np.round(c[row, col]).astype(int), np.round(c[row, 5 - col])
            v2, u2 = int(v2), int(u2)
            img[v - half : v + half, u - half : u + half] = src[
                v2 - half : v2 + half, u2 - half : u2 + half
            ]
    return img


def test_greys_in_reverse_are_not_a_mirrored_chart() -> None:
    # a chart whose first and third rows are reversed and its grey row not: read as a
    # mirrored Classic, its white patch would be the black one, and the affine fit (a 3 x 3
    # matrix and an offset) fits the inverted greys, the rows but one, at R2 0.99 (a
    # ColorChecker Passport in chart-fresh-2026-12-01e's tuning half); a camera maps
    # lightness monotonically, so the greys must descend as the reference's do
    photo = synthetic_chart_photo(rotation=0.0, tilt=0.0, width=0.5, shading=0.0, rng=4)
    img = _passport_layout(photo)
    det = detect_colorchecker(img)
    if det.found:  # not as a Classic: its greys in the right order
        assert det.centers[18, 0] < det.centers[23, 0]
        assert np.linalg.norm(det.centers - photo.centers, axis=1).max() < 1.0
    # the layout is found with its own reference (the cells' colours, row by row)
    ref = REF.reshape(4, 6, 3).copy()
    ref[[0, 2]] = ref[[0, 2], ::-1]
    own = detect_colorchecker(img, reference=ref.reshape(24, 3))
    assert own.found and not own.mirrored
    assert np.linalg.norm(own.centers - photo.centers, axis=1).max() < 1.0
