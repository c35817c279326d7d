"""``find_checkerboard(..., partial=True)``: the part of a board cut by the image's border.

Truth: boards rendered analytically (``checkerboard_support``: under a homography, or through
a lens with distortion and an endoscope's round field of view), so every corner's position
and its board label are known; OpenCV's ``left*.jpg`` views for the whole board, which must
come back bit for bit as without ``partial``.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry import find_checkerboard
from imageform.geometry.checkerboard import CheckerboardResult
from tests.geometry.checkerboard_support import (
    PATTERN,
    VIEWS,
    board_corners,
    homography,
    render_board,
)

#: The eight labellings of a square lattice onto itself (quarter turns and mirrorings).
TURNS = [np.array(m) for m in ([[1, 0], [0, 1]], [[0, -1], [1, 0]], [[-1, 0], [0, -1]],
                               [[0, 1], [-1, 0]], [[1, 0], [0, -1]], [[-1, 0], [0, 1]],
                               [[0, 1], [1, 0]], [[0, -1], [-1, 0]])]  # fmt: skip


def labels_agree(res: CheckerboardResult, truth: np.ndarray, board: tuple[int, int]) -> bool:
    """Whether one lattice isometry (turn or mirroring, then a shift) maps every corner's label
    in the part to the label of the true corner nearest to it."""
    assert res.corners is not None
    near = ((res.corners[:, None] - truth[None]) ** 2).sum(-1).argmin(1)
    ij = np.stack([near % board[0], near // board[0]], 1)
    k = np.arange(len(res.corners))
    ab = np.stack([k % res.pattern_size[0], k // res.pattern_size[0]], 1)
    return any(len(np.unique(ij - ab @ R.T, axis=0)) == 1 for R in TURNS)


@pytest.mark.parametrize(
    ("center", "angle", "tilt"),
    [((60, 240), 0.2, 0.0), ((600, 100), -0.4, 0.05), ((320, 455), 0.1, -0.05)],
)
def test_a_board_cut_by_the_border(center: tuple[float, float], angle: float, tilt: float) -> None:
    """A 9 x 6 board cut by the left, right or bottom border: not found whole; the part found
    is a lattice of the board (labels consistent), its corners within 0.1 px of the truth (the
    rows near the border, whose refinement window would reach past it, left out)."""
    H = homography(32.0, center, angle, tilt, *PATTERN)
    img = render_board(*PATTERN, H, (480, 640), blur=1.0, noise=0.01, seed=3)
    truth = board_corners(*PATTERN, H)
    assert not find_checkerboard(img, PATTERN).found
    res = find_checkerboard(img, PATTERN, partial=True)
    assert res.found and res.partial, res.reason
    cols, rows = res.pattern_size
    assert cols >= rows >= 3 and cols * rows >= 12 and cols * rows < 54
    assert res.corners is not None and res.corners.shape == (cols * rows, 2)
    assert labels_agree(res, truth, PATTERN)
    err = np.sqrt(((res.corners[:, None] - truth[None]) ** 2).sum(-1)).min(1)
    assert err.max() < 0.1, err.max()
    # the module's order for the part's size: rows along the longer side, clockwise
    g = res.grid()
    x, y = g[0, 1] - g[0, 0], g[1, 0] - g[0, 0]
    assert x[0] * y[1] - x[1] * y[0] > 0


def test_a_whole_board_is_returned_as_without_partial(views: dict[str, np.ndarray]) -> None:
    """On OpenCV's views (and a rendered whole board) partial=True changes nothing: the same
    corners bit for bit, the same status and scale, partial False."""
    H = homography(30.0, (320, 240), 0.2, 0.02, *PATTERN)
    images = [views[n] for n in VIEWS[:4]] + [render_board(*PATTERN, H, (480, 640))]
    for img in images:
        a = find_checkerboard(img, PATTERN)
        b = find_checkerboard(img, PATTERN, partial=True)
        assert a.found and b.found and not b.partial and not a.partial
        assert a.corners is not None and b.corners is not None
        assert np.array_equal(a.corners, b.corners) and a.pattern_size == b.pattern_size
        assert np.array_equal(a.status, b.status) and a.sigma == b.sigma


def test_too_little_of_the_board_is_not_found() -> None:
    """Two rows of corners in view (or 3 x 3: 9 corners) are too few: found=False, with the
    reason for the whole board and for its part; no board at all likewise."""
    H = homography(32.0, (60, -70), 0.0, 0.0, *PATTERN)  # only the bottom two rows inside
    img = render_board(*PATTERN, H, (480, 640), blur=1.0, noise=0.01)
    res = find_checkerboard(img, PATTERN, partial=True)
    assert not res.found and not res.partial and res.corners is None
    assert res.pattern_size == PATTERN and "no part of it" in res.reason
    H3 = homography(32.0, (-60, -10), 0.0, 0.0, 5, 5)  # a 5 x 5 board, 3 x 3 corners inside
    small = render_board(5, 5, H3, (480, 640), blur=1.0)
    assert not find_checkerboard(small, (5, 5), partial=True).found
    blank = np.random.default_rng(0).uniform(0.4, 0.6, (240, 320))
    assert not find_checkerboard(blank, PATTERN, partial=True).found


def test_a_grid_larger_than_the_board_is_refused() -> None:
    """A whole 9 x 6 board asked as 5 x 4 with partial=True: its lattice is larger than the
    board in either orientation, so it is no part of it (a wrong pattern_size is not hidden)."""
    H = homography(30.0, (320, 240), 0.2, 0.02, *PATTERN)
    res = find_checkerboard(render_board(*PATTERN, H, (480, 640)), (5, 4), partial=True)
    assert not res.found and "larger than the pattern" in res.reason


def test_a_round_field_of_view() -> None:
    """A board cut by an endoscope's round field of view (dark outside a circle of 330 px,
    a Kannala-Brandt lens): the rows whose windows take in the dark surround are left out (here
    a corner came out 4.6 px off without that), the others lie within 0.3 px of the truth."""
    from scipy.special import erf

    from imageform.geometry import (
        Camera,
        KannalaBrandt,
        checkerboard_points,
        project_points_distorted,
        rvec_to_matrix,
    )
    from tests.geometry.checkerboard_support import render_board_through

    K = np.array([[400.0, 0, 390.0], [0, 400.0, 280.0], [0, 0, 1]])
    D = KannalaBrandt(-0.091, -0.0161, 0.0198, -0.022)
    R = np.asarray(rvec_to_matrix([-0.481, 0.163, -0.125]))
    t = np.array([-10.09, 1.18, 8.39])  # the board to the left, past the field's edge
    cam = Camera(K, R, t, (768, 576), distortion=D)
    img = render_board_through(cam, *PATTERN, 1.0, blur=1.0, noise=0.01, seed=5)
    vv, uu = np.mgrid[0:576, 0:768].astype(float)
    mask = 0.5 * (1 - erf((np.hypot(uu - 390.0, vv - 280.0) - 330.0) / 1.5))
    u8 = np.round(np.clip(0.03 + (img - 0.03) * mask, 0, 1) * 255).astype(np.uint8)
    truth = np.asarray(project_points_distorted(checkerboard_points(PATTERN), K, R, t, D)[0])
    res = find_checkerboard(u8, PATTERN, partial=True)
    assert res.found and res.partial, res.reason
    assert labels_agree(res, truth, PATTERN)
    err = np.sqrt(((res.corners[:, None] - truth[None]) ** 2).sum(-1)).min(1)  # type: ignore[index]
    assert err.max() < 0.3, err.max()
    with pytest.MonkeyPatch.context() as mp:  # the asymmetry check is what leaves them out
        mp.setattr("imageform.geometry.checkerboard.PARTIAL_ASYMMETRY", np.inf)
        loose = find_checkerboard(u8, PATTERN, partial=True)
    assert loose.found and loose.corners is not None
    off = np.sqrt(((loose.corners[:, None] - truth[None]) ** 2).sum(-1)).min(1)
    assert off.max() > 2.0, off.max()


def test_bad_input() -> None:
    """partial must be a bool, needs the board's size, and a result cannot be partial and not
    found."""
    img = np.zeros((64, 64))
    with pytest.raises(InvalidInputError, match="partial"):
        find_checkerboard(img, PATTERN, partial="yes")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="needs the board's pattern_size"):
        find_checkerboard(img, "auto", partial=True)
    with pytest.raises(InvalidInputError, match="partial False when found is False"):
        CheckerboardResult(False, None, "none", (9, 6), partial=True)
    with pytest.raises(InvalidInputError, match="partial"):
        CheckerboardResult(True, np.zeros((12, 2)), "", (4, 3), partial=1.5)  # type: ignore[arg-type]


def test_parts_labelled_in_their_own_lattice_calibrate_exactly() -> None:
    """Zhang's start and the refinement take views of different numbers of points, and a
    part's own labels (a shift, a quarter turn, a mirroring of the board's) are absorbed by
    its pose: exact projections of three whole views and four parts so labelled give back K
    and the distortion to 1e-6."""
    from imageform.geometry import (
        BrownConrady,
        calibrate_camera,
        checkerboard_points,
        project_points_distorted,
        rvec_to_matrix,
    )

    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    D = BrownConrady(k1=-0.2, k2=0.05)
    board = checkerboard_points((9, 6), 25.0)
    poses = [([0.3, 0.1, 0.0], [-100, -60, 400]), ([-0.2, 0.3, 0.1], [-90, -70, 400]),
             ([0.1, -0.35, -0.1], [-110, -50, 390]), ([0.4, 0.3, 0.3], [-80, -90, 450]),
             ([-0.3, -0.2, 0.2], [-60, -80, 420]), ([0.2, -0.4, -0.3], [-120, -40, 410]),
             ([0.35, 0.25, -0.2], [-70, -75, 380])]  # fmt: skip
    grid = board.reshape(6, 9, 3)
    parts = [slice(None), slice(None), slice(None),
             (slice(0, 4), slice(2, 9)), (slice(1, 6), slice(0, 5)),
             (slice(2, 6), slice(3, 7)), (slice(0, 3), slice(0, 9))]  # fmt: skip
    relabel = [None, None, None, "shift", "turn", "mirror", "turn+mirror"]
    objs, pts = [], []
    for (r, t), part, how in zip(poses, parts, relabel, strict=True):
        R = np.asarray(rvec_to_matrix(r))
        sub = grid if part == slice(None) else grid[part]
        uv = np.asarray(project_points_distorted(sub.reshape(-1, 3), K, R, t, D)[0])
        rows, cols = sub.shape[:2]
        own = checkerboard_points((cols, rows), 25.0).reshape(rows, cols, 3)
        if how is not None and "turn" in how:  # the part's rows are the board's columns
            own = checkerboard_points((rows, cols), 25.0).reshape(cols, rows, 3)
            own = np.rot90(own, 1, axes=(0, 1))
        if how is not None and "mirror" in how:
            own = own[:, ::-1]
        objs.append(own.reshape(-1, 3) if how is not None else sub.reshape(-1, 3))
        pts.append(uv)
    assert len({len(p) for p in pts}) > 1  # views of different sizes
    res = calibrate_camera(objs, pts, (640, 480))
    np.testing.assert_allclose(res.K, K, atol=1e-6)
    np.testing.assert_allclose(res.distortion.coeffs[:2], [-0.2, 0.05], atol=1e-6)
    assert res.rms < 1e-6


def test_a_set_with_partial_views(views: dict[str, np.ndarray]) -> None:
    """find_checkerboards passes partial on: a cut view gives its part and no warning."""
    import warnings

    from imageform.geometry import find_checkerboards

    H = homography(32.0, (60, 240), 0.2, 0.0, *PATTERN)
    cut = np.round(render_board(*PATTERN, H, (480, 640), blur=1.0) * 255).astype(np.uint8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = find_checkerboards([views[VIEWS[0]], cut], PATTERN, partial=True)
    assert [r.found for r in res] == [True, True] and [r.partial for r in res] == [False, True]
