"""Shared support for the checkerboard tests: a board renderer and the OpenCV views.

Sources of truth:
- synthetic boards rendered here under a chosen homography (exact corner positions known);
- OpenCV 5.0 ``findChessboardCorners`` + ``cornerSubPix`` on OpenCV's own ``left*.jpg``
  views (a labelled cross-check with the tutorial's settings: winSize (11, 11), zeroZone
  (-1, -1), criteria EPS + COUNT, 30, 0.001), not the truth.
"""

from __future__ import annotations

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

__all__ = [
    "CRITERIA",
    "PATTERN",
    "VIEWS",
    "board_corners",
    "homography",
    "render_board",
    "render_board_through",
]

VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]
PATTERN = (9, 6)
CRITERIA = (3, 30, 0.001)  # cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001


def render_board(
    cols: int,
    rows: int,
    H: np.ndarray,
    shape: tuple[int, int],
    *,
    blur: float = 1.0,
    noise: float = 0.0,
    seed: int = 0,
    margin: float = 0.6,
    background: float = 0.35,
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
    edge positions to 1/S px: too coarse for a 0.05 px test.) The paper (0.85) reaches
    ``margin`` squares past the board, on a ``background`` of that level.
    """
    h, w = shape
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    Hinv = np.linalg.inv(H)
    W = Hinv[2, 0] * uu + Hinv[2, 1] * vv + Hinv[2, 2]
    X = (Hinv[0, 0] * uu + Hinv[0, 1] * vv + Hinv[0, 2]) / W
    Y = (Hinv[1, 0] * uu + Hinv[1, 1] * vv + Hinv[1, 2]) / W
    return _shade(X, Y, cols, rows, blur=blur, noise=noise, seed=seed, margin=margin,
                  background=background)  # fmt: skip


def _shade(
    X: np.ndarray,
    Y: np.ndarray,
    cols: int,
    rows: int,
    *,
    blur: float,
    noise: float,
    seed: int,
    margin: float = 0.6,
    background: float = 0.35,
) -> np.ndarray:
    """The board seen at board coordinates (X, Y) (in squares) per pixel; NaN is paper."""
    from scipy.special import erf

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
    on_paper = inside(-margin, cols + 1 + margin, X, gX) * inside(-margin, rows + 1 + margin, Y, gY)
    img = background + on_paper * (0.85 - background)
    img = on_board * checker + (1 - on_board) * img
    img = np.where(np.isfinite(img), img, background)
    if noise > 0:
        img = img + np.random.default_rng(seed).normal(0, noise, img.shape)
    return img


def render_board_through(
    camera: object,
    cols: int,
    rows: int,
    square: float,
    *,
    blur: float = 0.8,
    noise: float = 0.0,
    seed: int = 0,
) -> np.ndarray:
    """The board of :func:`~imageform.geometry.checkerboard_points` ``((cols, rows), square)``
    (world plane Z = 0, inner corner (c, r) at (c square, r square, 0)) seen through an
    :class:`~imageform.geometry.Camera`, lens distortion included: each pixel's ray (the
    camera's own undistortion) meets the plane at board coordinates that are shaded as in
    :func:`render_board`. Image of the camera's ``image_size``."""
    w, h = camera.image_size  # type: ignore[attr-defined]
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    xy = np.asarray(camera.undistort_pixels(np.stack([uu, vv], -1)))  # type: ignore[attr-defined]
    d = np.concatenate([xy, np.ones((h, w, 1))], -1)
    R, t = np.asarray(camera.R), np.asarray(camera.t)  # type: ignore[attr-defined]
    dw, o = d @ R, -R.T @ t  # world ray directions (rows: (Rᵀ d)ᵀ = dᵀ R) and the centre
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -o[2] / dw[..., 2]
        s = np.where(s > 0, s, np.nan)  # the plane behind the camera is not seen
    P = o + s[..., None] * dw
    return _shade(P[..., 0] / square + 1, P[..., 1] / square + 1, cols, rows,
                  blur=blur, noise=noise, seed=seed)  # fmt: skip


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
