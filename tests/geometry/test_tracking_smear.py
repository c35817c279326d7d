"""BoardTracker: the coarse-copy search for a smeared checkerboard, left out while in vain."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from imageform.geometry import BoardTracker
from tests.geometry.checkerboard_support import homography, render_board

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def _soft(seed: int) -> np.ndarray:
    """A 480 x 640 frame without a board, soft all over (a webcam's: blurred texture)."""
    noise = np.random.default_rng(seed).normal(0.5, 0.2, (480, 640))
    return np.clip(ndimage.gaussian_filter(noise, 3.0) * 4.0 - 1.5, 0.0, 1.0)


def _smeared() -> np.ndarray:
    """An 8 x 6 board smeared 25 px along the rows: found on a coarser copy only."""
    H = homography(32.0, (320.0, 240.0), 0.35, 0.0, 8, 6)
    return ndimage.uniform_filter1d(render_board(8, 6, H, (480, 640), blur=1.0), 25, axis=1)


def _sharp() -> np.ndarray:
    H = homography(32.0, (320.0, 240.0), 0.1, 0.0, 8, 6)
    return render_board(8, 6, H, (480, 640), blur=1.0)


@pytest.fixture
def searches(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The frames (1-based, as counted by ``frame``) on which the coarser copies were searched."""
    import imageform.geometry.checkerboard as cb

    seen: list[int] = []
    blurred = cb._blurred

    def counted(*args: object) -> object:
        seen.append(0)
        return blurred(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(cb, "_blurred", counted)
    return seen


def test_the_search_is_left_out_after_patience_and_retried(searches: list[int]) -> None:
    """Soft frames without a board: the coarser copies are searched on each of the first
    _SMEAR_PATIENCE (15) frames, then on one in _SMEAR_RETRY (10): 17 searches in 40 frames;
    a board found (sharp, at full resolution) starts the count again: each frame searches."""
    import imageform.geometry.checkerboard as cb
    from imageform.geometry import tracking

    assert (tracking._SMEAR_PATIENCE, tracking._SMEAR_RETRY) == (15, 10)
    frame = _soft(0)
    assert cb._smear_possible(cb._Gray(*cb.gray_codes(frame)[:2]))
    tracker = BoardTracker((8, 6), K, square=25.0)
    for _ in range(40):
        assert not tracker.update(frame).found
    assert len(searches) == 17
    assert tracker.update(_sharp()).found
    searches.clear()
    for _ in range(5):
        assert not tracker.update(frame).found
    assert len(searches) == 6  # the first frame twice: the last board's box, then whole


def test_a_smeared_board_is_found_on_a_retry_frame(searches: list[int]) -> None:
    """After 15 soft frames in vain, a smeared board is missed on a frame whose search is
    left out and found on the next retry frame; with the search never left out (patience
    past the clip) it is found at once, and every frame before it is the same."""
    from imageform.geometry import tracking

    soft, board = _soft(1), _smeared()
    clip = [soft] * 16 + [board] * 9
    tracker = BoardTracker((8, 6), K, square=25.0)
    poses = [tracker.update(f) for f in clip]
    # frames 17-25: quiet 2..10; the 10th (frame 25) is a retry
    assert [p.found for p in poses[16:]] == [False] * 8 + [True]
    tracking._SMEAR_PATIENCE, saved = 10**9, tracking._SMEAR_PATIENCE
    try:
        tracker = BoardTracker((8, 6), K, square=25.0)
        always = [tracker.update(f) for f in clip]
    finally:
        tracking._SMEAR_PATIENCE = saved
    assert all(p.found for p in always[16:])
    assert not any(p.found for p in always[:16] + poses[:16])


def test_a_board_seen_smeared_every_frame_is_tracked_as_before(searches: list[int]) -> None:
    """Frames whose board is found (here on the coarser copies) keep the count at zero: the
    poses are bit-identical with the search never left out."""
    from imageform.geometry import tracking

    clip = [_smeared()] * 3 + [_soft(2)] * 2 + [_smeared()] * 2

    def run() -> list[object]:
        tracker = BoardTracker((8, 6), K, square=25.0)
        return [tracker.update(f) for f in clip]

    poses = run()
    tracking._SMEAR_PATIENCE, saved = 10**9, tracking._SMEAR_PATIENCE
    try:
        always = run()
    finally:
        tracking._SMEAR_PATIENCE = saved
    for a, b in zip(poses, always, strict=True):
        assert a.found == b.found and a.searched == b.searched  # type: ignore[attr-defined]
        np.testing.assert_array_equal(a.image_points, b.image_points)  # type: ignore[attr-defined]
    assert [p.found for p in poses] == [True] * 3 + [False] * 2 + [True] * 2  # type: ignore[attr-defined]
