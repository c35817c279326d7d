"""Tests of imageform.geometry.checkerboard: find_checkerboard and refine_corners.

OpenCV's views (cross-check with OpenCV 5.0), synthetic boards (exact truth), not-found
cases, dtypes, backends, bad input. Support: tests/geometry/checkerboard_support.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError
from imageform.geometry.checkerboard import (
    CheckerboardResult,
    find_checkerboard,
    refine_corners,
)
from tests.geometry.checkerboard_support import (
    CRITERIA,
    PATTERN,
    VIEWS,
    board_corners,
    homography,
    render_board,
)
from tests.helpers import to_backend

cv2 = pytest.importorskip("cv2")


# --------------------------------------------------------------------------- OpenCV views


@pytest.mark.parametrize("name", VIEWS)
def test_opencv_views_found_and_match_opencv(
    name: str,
    ours: dict[str, CheckerboardResult],
    opencv_corners: dict[str, np.ndarray],
    record_property: pytest.RecordProperty,
) -> None:
    """Cross-check with OpenCV: same order, median corner distance < 0.1 px (issue 6)."""
    res = ours[name]
    assert res.found, res.reason
    assert res.corners is not None and res.corners.shape == (54, 2)
    assert res.corners.dtype == np.float64
    d = np.linalg.norm(res.corners - opencv_corners[name], axis=1)
    record_property("median_px", float(np.median(d)))
    record_property("max_px", float(d.max()))
    print(f"{name}: median {np.median(d):.2e} px, max {d.max():.2e} px")
    assert np.median(d) < 0.1
    # same order as OpenCV: every corner is nearest to its OpenCV namesake
    assert d.max() < 0.1
    assert res.status is not None and np.all(res.status == 0)


def test_opencv_views_all_13_found(ours: dict[str, CheckerboardResult]) -> None:
    assert sum(r.found for r in ours.values()) == 13


def test_order_convention_on_opencv_views(ours: dict[str, CheckerboardResult]) -> None:
    """The documented rule: clockwise row -> column turn, dark first cell (9 + 6 is odd)."""
    for res in ours.values():
        g = res.grid()
        x, y = g[0, 1] - g[0, 0], g[1, 0] - g[0, 0]
        assert x[0] * y[1] - x[1] * y[0] > 0


def test_default_window_also_matches_opencv(
    views: dict[str, np.ndarray], opencv_corners: dict[str, np.ndarray]
) -> None:
    """With the automatic refinement window, still within 0.1 px of OpenCV (median)."""
    for name in ("left01.jpg", "left12.jpg"):
        res = find_checkerboard(views[name], PATTERN)
        assert res.found
        d = np.linalg.norm(res.corners - opencv_corners[name], axis=1)
        assert np.median(d) < 0.1


def test_refine_corners_matches_cornersubpix(views: dict[str, np.ndarray]) -> None:
    """Cross-check: refine_corners from OpenCV's start points = cornerSubPix to 1e-3 px."""
    img = views["left03.jpg"]
    ok, start = cv2.findChessboardCorners(img, PATTERN, None)
    assert ok
    ref = cv2.cornerSubPix(img, start.copy(), (11, 11), (-1, -1), CRITERIA).reshape(-1, 2)
    xy, status = refine_corners(img, start.reshape(-1, 2), half_window=11)
    assert np.abs(xy - ref).max() < 1e-3
    assert np.all(status == 0)


@pytest.mark.parametrize("k", [1, 2, 3])
def test_order_follows_the_board_under_image_rotation(views: dict[str, np.ndarray], k: int) -> None:
    """Rotating the image by k * 90° keeps the order (the rule is tied to the board)."""
    img = views["left01.jpg"]
    base = find_checkerboard(img, PATTERN).corners
    rot = find_checkerboard(np.ascontiguousarray(np.rot90(img, k)), PATTERN)
    assert rot.found
    h, w = img.shape
    u, v = base[:, 0], base[:, 1]
    # np.rot90 turns counter-clockwise: (u, v) -> (v, w-1-u) per quarter turn
    for _ in range(k):
        u, v = v, (w - 1) - u
        h, w = w, h
    assert np.abs(rot.corners - np.stack([u, v], axis=1)).max() < 0.05


# --------------------------------------------------------------------------- synthetic


@pytest.mark.parametrize(
    ("cols", "rows", "angle", "tilt"),
    [(9, 6, 0.2, 0.0), (9, 6, 2.5, 0.07), (7, 5, -0.4, 0.08), (8, 5, 1.0, -0.07)],
)
def test_synthetic_board_accuracy(cols: int, rows: int, angle: float, tilt: float) -> None:
    """Rendered board, known corners: found, order per the convention, error < 0.05 px."""
    H = homography(34.0, (320.0, 240.0), angle, tilt, cols, rows)
    img = render_board(cols, rows, H, (480, 640), blur=1.0, noise=0.005)
    truth = board_corners(cols, rows, H)
    assert np.all(truth > 20) and np.all(truth < [620, 460])  # the whole board in view
    res = find_checkerboard(img, (cols, rows))
    assert res.found, res.reason
    g = truth.reshape(rows, cols, 2)
    if (cols + rows) % 2 == 1:
        # dark first cell: the rendered order, or its 180° turn if H mirrors
        x, y = g[0, 1] - g[0, 0], g[1, 0] - g[0, 0]
        assert x[0] * y[1] - x[1] * y[0] > 0
        expected = truth
    else:
        # symmetric colours: the first row is the upper one
        expected = (g if g[-1, 0, 1] >= g[0, 0, 1] else g[::-1, ::-1]).reshape(-1, 2)
    err = np.linalg.norm(res.corners - expected, axis=1)
    assert err.max() < 0.05, err.max()


@settings(max_examples=6, deadline=None)
@given(
    angle=st.floats(-np.pi, np.pi),
    tilt=st.floats(-0.08, 0.08),
    square=st.floats(22.0, 40.0),
)
def test_synthetic_board_property(angle: float, tilt: float, square: float) -> None:
    """Any in-plane angle, moderate perspective: found, corners within 0.05 px of truth."""
    H = homography(square, (320.0, 240.0), angle, tilt, 9, 6)
    truth = board_corners(9, 6, H)
    if not (np.all(truth > 25) and np.all(truth < [615, 455])):
        return
    img = render_board(9, 6, H, (480, 640), blur=1.2)
    res = find_checkerboard(img, (9, 6))
    assert res.found, res.reason
    assert np.linalg.norm(res.corners - truth, axis=1).max() < 0.05


def test_synthetic_small_squares_use_another_scale() -> None:
    """Squares of 12 px: the default scale list still finds the board."""
    H = homography(12.0, (160.0, 120.0), 0.3, 0.0, 9, 6)
    img = render_board(9, 6, H, (240, 320), blur=0.8)
    res = find_checkerboard(img, (9, 6))
    assert res.found, res.reason
    assert np.linalg.norm(res.corners - board_corners(9, 6, H), axis=1).max() < 0.1


# --------------------------------------------------------------------------- not found


def test_crop_without_full_board_is_not_found(views: dict[str, np.ndarray]) -> None:
    img = views["left01.jpg"][:, :400]  # cuts the right part of the board
    res = find_checkerboard(img, PATTERN)
    assert not res.found
    assert res.corners is None
    assert "not fully visible" in res.reason


@pytest.mark.parametrize("pattern", [(8, 6), (9, 5), (10, 7), (10, 6)])
def test_wrong_pattern_size_is_not_found(views: dict[str, np.ndarray], pattern: tuple) -> None:
    """Never a wrong grid: a sub-grid of a larger board is refused (OpenCV does the same)."""
    res = find_checkerboard(views["left01.jpg"], pattern)
    assert not res.found
    assert res.corners is None
    assert res.reason


def test_transposed_pattern_size_orders_by_columns(views: dict[str, np.ndarray]) -> None:
    """(6, 9) describes the same board: the same corners, rows now of 6 points."""
    a = find_checkerboard(views["left01.jpg"], (9, 6))
    b = find_checkerboard(views["left01.jpg"], (6, 9))
    assert a.found and b.found
    assert b.grid().shape == (9, 6, 2)
    d = np.linalg.norm(b.corners[:, None] - a.corners[None], axis=2).min(axis=1)
    assert d.max() < 1e-6


def test_blank_image_not_found() -> None:
    res = find_checkerboard(np.full((100, 120), 0.5), (9, 6))
    assert not res.found and "constant" in res.reason


def test_noise_image_not_found() -> None:
    rng = np.random.default_rng(1)
    res = find_checkerboard(rng.random((240, 320)), (9, 6))
    assert not res.found and res.reason


def test_grid_accessor_raises_when_not_found() -> None:
    res = find_checkerboard(np.full((100, 120), 0.5), (9, 6))
    with pytest.raises(InvalidInputError, match="no checkerboard"):
        res.grid()


# --------------------------------------------------------------------------- dtypes, backends


@pytest.fixture(scope="module")
def synthetic() -> tuple[np.ndarray, np.ndarray]:
    H = homography(30.0, (200.0, 150.0), 0.25, 0.05, 7, 5)
    return render_board(7, 5, H, (300, 400), blur=1.0), board_corners(7, 5, H)


@pytest.mark.parametrize("kind", ["float64", "float32", "uint8", "uint16", "rgb", "hw1"])
def test_dtypes_and_channels(kind: str, synthetic: tuple[np.ndarray, np.ndarray]) -> None:
    img, truth = synthetic
    if kind == "float32":
        img = img.astype(np.float32)
    elif kind == "uint8":
        img = np.round(img * 255).astype(np.uint8)
    elif kind == "uint16":
        img = np.round(img * 65535).astype(np.uint16)
    elif kind == "rgb":
        img = np.repeat(img[..., None], 3, axis=2)
    elif kind == "hw1":
        img = img[..., None]
    res = find_checkerboard(img, (7, 5))
    assert res.found, res.reason
    assert res.corners.dtype == np.float64
    assert np.linalg.norm(res.corners - truth, axis=1).max() < 0.05


def test_float_scale_does_not_matter(synthetic: tuple[np.ndarray, np.ndarray]) -> None:
    img, _ = synthetic
    a = find_checkerboard(img, (7, 5))
    b = find_checkerboard(img * 255.0, (7, 5))
    assert np.abs(a.corners - b.corners).max() < 1e-6


def test_array_backends(xp_name: str, synthetic: tuple[np.ndarray, np.ndarray]) -> None:
    """torch / array-api-strict images are accepted (detection runs on NumPy)."""
    img, truth = synthetic
    res = find_checkerboard(to_backend(img, xp_name), (7, 5))
    assert res.found
    assert isinstance(res.corners, np.ndarray)
    assert np.linalg.norm(res.corners - truth, axis=1).max() < 0.05


def test_numba_and_plain_twins_agree_end_to_end(
    monkeypatch: pytest.MonkeyPatch, views: dict[str, np.ndarray]
) -> None:
    """IMAGEFORM_DISABLE_NUMBA=1 (plain twins) gives the same corners to 1e-6 px."""
    img = views["left05.jpg"]
    fast = find_checkerboard(img, PATTERN)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = find_checkerboard(img, PATTERN)
    assert fast.found and plain.found
    assert np.abs(fast.corners - plain.corners).max() < 1e-6


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("image", "match"),
    [
        (np.zeros((2, 20, 20, 3)), r"expected image of shape \(H, W\)"),
        (np.zeros((20, 20, 2)), r"expected image of shape \(H, W\)"),
        (np.zeros((8, 40)), "at least 16 x 16"),
        (np.zeros(40), r"expected image of shape"),
        (np.zeros((20, 20), dtype=np.int32), "uint8, uint16 or floats"),
        ("left01.jpg", "numeric array"),
    ],
)
def test_bad_images(image: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        find_checkerboard(image, (9, 6))  # type: ignore[arg-type]


def test_nan_image() -> None:
    img = np.zeros((40, 40))
    img[3, 4] = np.nan
    with pytest.raises(InvalidInputError, match="NaN"):
        find_checkerboard(img, (3, 3))


@pytest.mark.parametrize(
    "pattern", [(1, 6), (9, 1), (9,), (9, 6, 2), (9.0, 6), (True, 6), 9, "9x6"]
)
def test_bad_pattern_size(pattern: object) -> None:
    with pytest.raises(InvalidInputError, match="pattern_size"):
        find_checkerboard(np.zeros((40, 40)), pattern)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"sigma": 0.0}, "sigma"),
        ({"sigma": float("nan")}, "sigma"),
        ({"half_window": 0}, "half_window"),
        ({"max_iter": 0}, "max_iter"),
        ({"tol": -1.0}, "tol"),
    ],
)
def test_bad_options(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        find_checkerboard(np.zeros((40, 40)), (3, 3), **kwargs)


def test_refine_corners_bad_input() -> None:
    img = np.zeros((40, 40))
    with pytest.raises(InvalidInputError, match=r"corners of shape \(\.\.\., 2\)"):
        refine_corners(img, np.zeros((3, 3)))
    with pytest.raises(InvalidInputError, match="NaN"):
        refine_corners(img, [[np.nan, 1.0]])
    with pytest.raises(InvalidInputError, match="half_window"):
        refine_corners(img, [[1.0, 1.0]], half_window=0)


def test_refine_corners_flat_window_status() -> None:
    """A flat window has no gradients: status 2, the start is kept."""
    xy, status = refine_corners(np.full((40, 40), 0.5), [[20.0, 20.0]], half_window=5)
    assert status.tolist() == [2]
    assert xy.tolist() == [[20.0, 20.0]]


def test_public_surface() -> None:
    """Removing a public name is a deliberate act."""
    import imageform.geometry.checkerboard as mod

    assert sorted(mod.__all__) == [
        "CheckerboardNotFoundWarning",
        "CheckerboardResult",
        "find_checkerboard",
        "find_checkerboards",
        "refine_corners",
        "refine_corners_symmetric",
        "set_pattern_size",
    ]
    res = find_checkerboard(np.full((40, 40), 0.5), (3, 3))
    with pytest.raises(AttributeError):
        res.found = True  # type: ignore[misc]  # frozen


def test_square_pattern_first_corner_nearest_top_left() -> None:
    """6 x 6 (symmetric in every way): the documented tie-break, smallest u + v first."""
    H = homography(30.0, (200.0, 160.0), 2.0, 0.03, 6, 6)
    img = render_board(6, 6, H, (320, 400), blur=1.0)
    truth = board_corners(6, 6, H)
    res = find_checkerboard(img, (6, 6))
    assert res.found, res.reason
    first = res.corners[0]
    assert first.sum() == pytest.approx(truth.sum(axis=1).min(), abs=0.1)
    # every corner is a true corner, and the turn from row to column is clockwise
    assert np.linalg.norm(res.corners[:, None] - truth[None], axis=2).min(axis=1).max() < 0.05
    g = res.grid()
    x, y = g[0, 1] - g[0, 0], g[1, 0] - g[0, 0]
    assert x[0] * y[1] - x[1] * y[0] > 0


def test_unrefined_and_explicit_sigma(synthetic: tuple[np.ndarray, np.ndarray]) -> None:
    img, truth = synthetic
    raw = find_checkerboard(img, (7, 5), refine=False)
    assert raw.found and raw.status is None
    assert np.linalg.norm(raw.corners - truth, axis=1).max() < 1.0
    fine = find_checkerboard(img, (7, 5), sigma=1.5, half_window=5)
    assert fine.found and fine.sigma == 1.5
    assert np.linalg.norm(fine.corners - truth, axis=1).max() < 0.05
