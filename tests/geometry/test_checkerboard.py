"""Tests of imageform.geometry.checkerboard (find_checkerboard, refine_corners).

Sources of truth:
- synthetic boards rendered here under a chosen homography (exact corner positions known);
- OpenCV 5.0 ``findChessboardCorners`` + ``cornerSubPix`` on OpenCV's own ``left*.jpg``
  views (a labelled cross-check with the tutorial's settings: winSize (11, 11), zeroZone
  (-1, -1), criteria EPS + COUNT, 30, 0.001), not the truth.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError
from imageform.geometry.checkerboard import (
    CheckerboardNotFoundWarning,
    CheckerboardResult,
    find_checkerboard,
    find_checkerboards,
    refine_corners,
)
from tests.helpers import to_backend

cv2 = pytest.importorskip("cv2")

VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]
PATTERN = (9, 6)
CRITERIA = (3, 30, 0.001)  # cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001


# --------------------------------------------------------------------------- helpers


def render_board(
    cols: int,
    rows: int,
    H: np.ndarray,
    shape: tuple[int, int],
    *,
    blur: float = 1.0,
    noise: float = 0.0,
    seed: int = 0,
) -> np.ndarray:
    """A board of (cols+1) x (rows+1) squares seen through homography ``H``, blurred.

    Board coordinates (X, Y) in squares; inner corner (c, r) is at (c + 1, r + 1); square
    (i, j) = (floor X, floor Y) is dark when i + j is even, so the first cell (between inner
    corners 0, 1, cols, cols+1) is dark. ``H`` maps (X, Y, 1) to image (u, v, w), pixel
    centres at integers.

    Rendered analytically: each edge is a Gaussian-blurred step (σ² = blur² + 1/12, the
    optics plus the pixel's box), ``erf(d / (σ √2))`` of the signed image distance ``d`` to
    the nearest grid line (first order in the homography). A checker corner is then
    ``0.5 + 0.5 erf(d_x) erf(d_y)``, exact for a blurred corner and point-symmetric about it,
    so the true corner is where an unbiased detector must land. (Supersampling quantises
    edge positions to 1/S px: too coarse for a 0.05 px test.)
    """
    from scipy.special import erf

    h, w = shape
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    Hinv = np.linalg.inv(H)
    W = Hinv[2, 0] * uu + Hinv[2, 1] * vv + Hinv[2, 2]
    X = (Hinv[0, 0] * uu + Hinv[0, 1] * vv + Hinv[0, 2]) / W
    Y = (Hinv[1, 0] * uu + Hinv[1, 1] * vv + Hinv[1, 2]) / W
    gX = np.hypot(*np.gradient(X))  # board units per pixel across a line X = const
    gY = np.hypot(*np.gradient(Y))
    sig = np.sqrt(blur**2 + 1.0 / 12.0) * np.sqrt(2.0)

    def soft(d_board: np.ndarray, g: np.ndarray) -> np.ndarray:
        return erf(d_board / g / sig)  # type: ignore[no-any-return]

    nX, nY = np.round(X), np.round(Y)
    cx = (-1.0) ** nX * soft(X - nX, gX)  # +1 on even columns (just right of an even line)
    cy = (-1.0) ** nY * soft(Y - nY, gY)
    checker = 0.475 - 0.375 * cx * cy  # dark (0.1) where floor X + floor Y is even

    def inside(lo: float, hi: float, V: np.ndarray, g: np.ndarray) -> np.ndarray:
        return 0.25 * (1 + soft(V - lo, g)) * (1 + soft(hi - V, g))

    on_board = inside(0, cols + 1, X, gX) * inside(0, rows + 1, Y, gY)
    on_paper = inside(-0.6, cols + 1.6, X, gX) * inside(-0.6, rows + 1.6, Y, gY)
    img = 0.35 + on_paper * (0.85 - 0.35)
    img = on_board * checker + (1 - on_board) * img
    if noise > 0:
        img = img + np.random.default_rng(seed).normal(0, noise, img.shape)
    return img


def board_corners(cols: int, rows: int, H: np.ndarray) -> np.ndarray:
    """Exact image positions of the inner corners, row by row."""
    r, c = np.mgrid[1 : rows + 1, 1 : cols + 1]
    P = np.stack([c.ravel(), r.ravel(), np.ones(c.size)], axis=1) @ H.T
    return P[:, :2] / P[:, 2:]


def homography(
    square: float, centre: tuple[float, float], angle: float, tilt: float, cols: int, rows: int
) -> np.ndarray:
    """Board -> image: scale, rotate by ``angle``, perspective ``tilt``, centre the board."""
    c, s = np.cos(angle), np.sin(angle)
    T0 = np.array([[1, 0, -(cols + 1) / 2], [0, 1, -(rows + 1) / 2], [0, 0, 1.0]])
    A = np.array([[square * c, -square * s, 0], [square * s, square * c, 0], [0, 0, 1.0]])
    P = np.array([[1, 0, 0], [0, 1, 0], [tilt / square, 0.3 * tilt / square, 1.0]])
    T1 = np.array([[1, 0, centre[0]], [0, 1, centre[1]], [0, 0, 1.0]])
    return T1 @ P @ A @ T0


@pytest.fixture(scope="module")
def views(shared_data: Path) -> dict[str, np.ndarray]:
    folder = shared_data / "opencv-left"
    out = {}
    for name in VIEWS:
        img = cv2.imread(str(folder / name), cv2.IMREAD_GRAYSCALE)
        assert img is not None, name
        out[name] = img
    return out


@pytest.fixture(scope="module")
def opencv_corners(views: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Cross-check reference: OpenCV 5.0 findChessboardCorners + cornerSubPix (tutorial)."""
    out = {}
    for name, img in views.items():
        ok, c = cv2.findChessboardCorners(img, PATTERN, None)
        assert ok, name
        out[name] = cv2.cornerSubPix(img, c, (11, 11), (-1, -1), CRITERIA).reshape(-1, 2)
    return out


@pytest.fixture(scope="module")
def ours(views: dict[str, np.ndarray]) -> dict[str, CheckerboardResult]:
    return {name: find_checkerboard(img, PATTERN, half_window=11) for name, img in views.items()}


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
        ({"eps": -1.0}, "eps"),
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


# --------------------------------------------------------------------------- sets of views


def test_find_checkerboards_on_the_opencv_set(views: dict[str, np.ndarray]) -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: every view has the board
        res = find_checkerboards(list(views.values()), PATTERN, names=list(views))
    assert [r.found for r in res] == [True] * 13


def test_find_checkerboards_warns_for_views_without_board(views: dict[str, np.ndarray]) -> None:
    imgs = [views["left01.jpg"], views["left01.jpg"][:, ::-1] * 0 + 128, views["left02.jpg"]]
    with pytest.warns(CheckerboardNotFoundWarning, match=r"1 of 3 views: blank.png \(the image"):
        res = find_checkerboards(imgs, PATTERN, names=["a.png", "blank.png", "c.png"])
    assert [r.found for r in res] == [True, False, True]


def test_find_checkerboards_different_sizes(views: dict[str, np.ndarray]) -> None:
    imgs = [views["left01.jpg"], views["left02.jpg"][:240, :320]]
    with pytest.raises(InvalidInputError, match=r"one size.*view 1 of 320 x 240 px"):
        find_checkerboards(imgs, PATTERN)


@pytest.mark.parametrize(
    ("images", "match"),
    [
        ([], "at least one image"),
        (np.zeros((3, 40, 40)), "list or tuple of images"),
        ([np.zeros((40, 40)), np.zeros((40, 40, 2))], r"view 1: expected image of shape"),
        ([np.zeros((40, 40)), "not-an-image.jpg"], r"view 1: expected a numeric array"),
    ],
)
def test_find_checkerboards_bad_sets(images: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        find_checkerboards(images, (3, 3))  # type: ignore[arg-type]


def test_find_checkerboards_names_length() -> None:
    with pytest.raises(InvalidInputError, match="2 names"):
        find_checkerboards([np.zeros((40, 40))] * 2, (3, 3), names=["a"])
