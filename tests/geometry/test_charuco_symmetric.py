"""ChArUco corners refined by point symmetry with the markers masked (detect_charuco's default).

Truth: ChArUco views rendered through a camera with distortion (test_charuco's
``_render_view``: each pixel's ray meets the board plane, the board image sampled there), then
blurred and noisy; the true corners are the board's corners projected by OpenCV's
``projectPoints``. The masked kernels are checked against their NumPy twins.
"""

from __future__ import annotations

import numpy as np
import pytest

import imageform.geometry.charuco as charuco
from imageform.errors import InvalidInputError
from imageform.geometry import CharucoBoard, detect_charuco

cv2 = pytest.importorskip("cv2")

from .test_charuco import _render_view  # noqa: E402

BOARD = CharucoBoard((9, 7), 20.0, 15.0, "6x6_250")
K = np.array([[700.0, 0, 322.0], [0, 705.0, 238.0], [0, 0, 1]])
DIST = np.array([-0.12, 0.05, 0.0, 0.0, 0.0])


def _views(
    n: int = 3, blur: float = 1.2, noise: float = 2.0
) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` rendered views (uint8) with their true corners (n_corners, 2)."""
    px = 64
    art = BOARD.image(px, margin_px=px)
    rng = np.random.default_rng(5)
    out = []
    for _ in range(n):
        rvec = np.array([rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.3, 0.3)])
        tvec = np.array([-90.0 + rng.uniform(-40, 40), -70.0 + rng.uniform(-30, 30), 330.0])
        img = _render_view(BOARD, art, px, K, DIST, rvec, tvec, (640, 480)).astype(np.float64)
        img = cv2.GaussianBlur(img, (0, 0), blur) + rng.normal(0, noise, img.shape)
        truth, _ = cv2.projectPoints(BOARD.corner_points(), rvec, tvec, K, DIST)
        out.append((np.clip(img + 0.5, 0, 255).astype(np.uint8), truth.reshape(-1, 2)))
    return out


def _errors(views: list[tuple[np.ndarray, np.ndarray]], method: str) -> np.ndarray:
    errs = []
    for img, truth in views:
        found = detect_charuco(img, BOARD, method=method)  # type: ignore[arg-type]
        errs.append(np.hypot(*(found.corners - truth[found.ids]).T))
    return np.concatenate(errs)


def test_symmetric_corners_nearer_the_truth_than_the_gradient_ones() -> None:
    """Three distorted, blurred (1.2 px), noisy views: the same 144 corners; median error
    0.133 -> 0.009 px, the largest 0.41 -> 0.15 px (measured)."""
    views = _views()
    ids = [detect_charuco(img, BOARD, method="gradient").ids.tolist() for img, _ in views]
    assert ids == [detect_charuco(img, BOARD).ids.tolist() for img, _ in views]
    grad, sym = _errors(views, "gradient"), _errors(views, "symmetric")
    assert grad.size == sym.size >= 100
    assert np.median(sym) < 0.015 and sym.max() < 0.2
    assert np.median(sym) < 0.1 * np.median(grad) and sym.max() < 0.5 * grad.max()


def test_the_marker_mask_matters(monkeypatch: pytest.MonkeyPatch) -> None:
    """The markers' bits are not point-symmetric: left in (no mask) they pull the corners
    several times farther off the truth than the gradient refinement."""
    views = _views(2)
    masked = _errors(views, "symmetric")
    monkeypatch.setattr(charuco, "_SYM_MASKED", False)
    plain = _errors(views, "symmetric")
    assert np.median(plain) > 4 * np.median(masked)


def test_the_mask_covers_the_markers_and_keeps_the_black_squares() -> None:
    """A fronto-parallel board, 40 px squares: the offsets on the two markers (grown by the
    guard band) are off, those in the black squares and the white margins near the corner on;
    the mask is point-symmetric."""
    s = 40.0
    hom = np.array([[s, 0.0, 10.0], [0.0, s, 10.0], [0.0, 0.0, 1.0]])  # squares to pixels
    ids = np.array([0])  # corner (row 0, col 0) at board (1, 1): pixel (50, 50)
    pred = np.array([[50.0, 50.0]])
    h = 30
    mask = charuco._marker_mask(BOARD, hom[None], pred, np.array([s]), pred, h, (400, 500))
    m = mask[0]
    assert ids.size == 1 and m.shape == (61, 61)
    assert (m == m[::-1, ::-1]).all()
    # white squares of (row, col) = (0, 1) and (1, 0); marker inset (1 - 0.75) / 2 = 0.125 sq
    # = 5 px, guard max(1 px, half the margin = 2.5 px): free within 2.5 px of the edges
    assert m[h - 20, h + 20] == 0 and m[h + 20, h - 20] == 0  # the markers' centres
    assert m[h - 10, h - 10] and m[h + 10, h + 10]  # the black squares
    assert m[h - 1, h + 20] and m[h + 20, h - 1]  # the white margins along the corner's edges
    assert not m[h - 4, h + 20]  # 3 px into the margin: the guard band


def test_kernel_and_twin_agree_on_masked_windows() -> None:
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_symmetric import (
        marker_mask_numba,
        marker_mask_numpy,
        refine_symmetric_numba,
        refine_symmetric_numpy,
    )

    rng = np.random.default_rng(0)
    m, h = 40, 12
    homs = np.tile(np.eye(3), (m, 1, 1))
    homs[:, 0, 0] = homs[:, 1, 1] = rng.uniform(15, 40, m)
    homs[:, 0, 1] = rng.uniform(-5, 5, m)
    homs[:, 2, :2] = rng.uniform(-1e-3, 1e-3, (m, 2))
    homs[:, :2, 2] = rng.uniform(0, 50, (m, 2))
    r, c = np.divmod(rng.integers(0, 48, m), 8)
    q = np.einsum("mij,mj->mi", homs, np.column_stack([c + 1.0, r + 1.0, np.ones(m)]))
    pred = q[:, :2] / q[:, 2:]
    start = pred + rng.uniform(-0.5, 0.5, (m, 2))
    hinv = np.ascontiguousarray(np.linalg.inv(homs))
    lo, guard = rng.uniform(-0.05, 0.15, m), rng.uniform(0.01, 0.1, m)
    args = (hinv, pred, start, lo, guard, h, 9, 7, 1, (240, 320))
    a, b = marker_mask_numba(*args), marker_mask_numpy(*args)
    assert a.tolist() == b.tolist() and 0.1 < a.mean() < 0.9
    # the masked refinement on a rendered view, float32 and float64
    (img, truth), *_ = _views(1)
    for dtype in (np.float32, np.float64):
        g = img.astype(dtype) / 255
        pts = truth[:40] + rng.uniform(-0.6, 0.6, (40, 2))
        mask = rng.uniform(size=(40, 2 * h + 1, 2 * h + 1)) > 0.3
        mask[3] = False  # nothing left: singular
        x, sx = refine_symmetric_numba(g, pts, h, 30, 1e-3, mask)
        y, sy = refine_symmetric_numpy(g, pts, h, 30, 1e-3, mask)
        assert sx.tolist() == sy.tolist() and sx[3] == 2 and x[3].tolist() == pts[3].tolist()
        assert np.abs(x - y).max() < 1e-9


def test_fused_kernel_and_twin_agree() -> None:
    """The ChArUco kernel (the mask made inside it, every window size in one call) against
    its twin (marker_mask_numpy, then refine_symmetric_numpy per window size), float64."""
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard_symmetric import (
        charuco_symmetric_numba,
        charuco_symmetric_numpy,
    )

    rng = np.random.default_rng(1)
    (img, truth), *_ = _views(1)
    g = img.astype(np.float64) / 255
    m = 40
    pred = truth[:m] + rng.uniform(-0.3, 0.3, (m, 2))
    start = pred + rng.uniform(-0.6, 0.6, (m, 2))
    start[5] = [2.0, 3.0]  # window past the image's corner: mostly masked
    start[6] = np.nan  # not finite: status 2, kept
    homs = np.tile(np.eye(3), (m, 1, 1))  # squares to pixels, the corner at pred
    homs[:, 0, 0] = homs[:, 1, 1] = rng.uniform(20, 40, m)
    homs[:, 0, 1] = rng.uniform(-4, 4, m)
    homs[:, 2, :2] = rng.uniform(-2e-3, 2e-3, (m, 2))
    homs[:, :2, 2] = pred - homs[:, :2, 0] * 3 - homs[:, :2, 1] * 2
    homs[:, :2, 2] += rng.uniform(-1, 1, (m, 2))
    hinv = np.linalg.inv(homs)
    lo, guard = rng.uniform(-0.05, 0.15, m), rng.uniform(0.01, 0.1, m)
    hs = rng.integers(3, 25, m)
    hs[7] = 1  # a 3 x 3 window
    args = (g, start, pred, hinv, lo, guard, hs, 9, 7, 1, 30, 1e-3)
    x, sx = charuco_symmetric_numba(*args)
    y, sy = charuco_symmetric_numpy(*args)
    assert sx.tolist() == sy.tolist() and sx[6] == 2 and np.isnan(x[6]).all()
    assert {0, 2}.issubset(set(sx.tolist()))
    ok = np.isfinite(x).all(axis=1)
    assert np.abs(x[ok] - y[ok]).max() < 1e-12
    none = charuco_symmetric_numba(g, start[:0], *args[2:])
    assert none[0].shape == (0, 2) and none[1].shape == (0,)


def test_gradient_and_symmetric_find_the_same_corners_in_a_real_view() -> None:
    """The RealSense crop of tests/data/charuco: the same ids, moved by less than 0.5 px."""
    from imageform.io import read_image

    from .test_charuco import REAL

    img = read_image(REAL / "realsense_calib_009_crop.png")[..., 0]
    board = CharucoBoard((7, 5), 30.0, 22.0, "4x4_50")
    a = detect_charuco(img, board, method="gradient")
    b = detect_charuco(img, board, method="symmetric")
    assert a.ids.tolist() == b.ids.tolist() and len(a) >= 20
    assert np.hypot(*(a.corners - b.corners).T).max() < 0.5


@pytest.mark.parametrize("method", ["Symmetric", "cornersubpix", None, 1])
def test_bad_method(method: object) -> None:
    with pytest.raises(InvalidInputError, match="method"):
        detect_charuco(BOARD.image(40, margin_px=20), BOARD, method=method)  # type: ignore[arg-type]


def test_bad_mask_shape_in_the_kernel() -> None:
    from imageform._kernels.checkerboard_symmetric import refine_symmetric_numpy

    with pytest.raises(ValueError, match="mask"):
        refine_symmetric_numpy(np.zeros((20, 20)), np.zeros((2, 2)), 3, 5, 1e-3, np.ones((2, 5, 5)))
