"""field_of_view_mask, still_mask and highlight_mask: an endoscope's aperture, overlays and
highlights.

Synthetic frames with a known aperture, caption and highlight, and the real colonoscopy
frames of tests/data/endo (C3VD v3, CC BY 4.0; README there)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry import (
    detect_features,
    field_of_view_mask,
    highlight_mask,
    still_mask,
)

cv2 = pytest.importorskip("cv2")

_ONE: Any = 1  # not a bool
_HALF: Any = 1.5  # not an integer
ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"
#: the ten frames 0, 4, ..., 36 (the folder also has 40, 48 and 56, for every 8th frame)
FIRST_TEN = [ENDO / f"c3vdv3_f{i:03d}.jpg" for i in range(0, 40, 4)]


def _endo_frames() -> list[np.ndarray]:
    from imageform.io import read_image

    return [np.asarray(read_image(p)) for p in FIRST_TEN]


def _scope_video(n: int = 6) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Frames of a moving texture seen through a round aperture, with a fixed caption.

    Returns the frames, the aperture and the caption's box (both boolean images)."""
    h, w = 120, 160
    rng = np.random.default_rng(3)
    paper = cv2.GaussianBlur(rng.random((h, w + 10 * n)).astype(np.float32), (0, 0), 2.0)
    paper = (40 + 180 * (paper - paper.min()) / np.ptp(paper)).astype(np.uint8)
    yy, xx = np.mgrid[:h, :w]
    aperture = (xx - 80) ** 2 + (yy - 60) ** 2 < 55**2
    caption = np.zeros((h, w), bool)
    caption[50:60, 60:100] = True  # burned-in text inside the aperture
    frames = []
    for i in range(n):
        f = np.where(aperture, paper[:, 10 * i : 10 * i + w], 0).astype(np.uint8)
        f[caption] = np.where((xx[caption] // 3) % 2 == 0, 250, 30)
        f[3:9, 3:40] = 255  # text in the black corner
        frames.append(np.repeat(f[..., None], 3, axis=2))
    return frames, aperture, caption


def test_aperture_caption_and_margin() -> None:
    frames, aperture, caption = _scope_video()
    m = field_of_view_mask(frames, margin=4)
    assert m.dtype == bool and m.shape == aperture.shape
    assert not np.any(m & ~aperture)  # the black border and its text are out
    assert not np.any(m & caption)  # the caption never changes: out
    # the margin: nothing within 4 px of the aperture's edge or of the caption
    near = cv2.dilate((~aperture | caption).astype(np.uint8), np.ones((7, 7), np.uint8)) > 0
    assert not np.any(m & near)
    assert m[60, 40] and m[20, 80]  # the scene stays
    # the caption stays without the overlay test, and with a single frame
    assert field_of_view_mask(frames, margin=0, overlays=False)[55, 70]
    assert field_of_view_mask(frames[0], margin=0)[55, 70]


def test_a_still_camera_keeps_its_scene() -> None:
    """Frames that never change: no overlay can be told apart, the aperture stays whole."""
    frames, aperture, _ = _scope_video(1)
    m = field_of_view_mask(frames * 4, margin=0)
    assert np.array_equal(m, aperture)


def test_a_dark_lumen_in_the_middle_is_scene() -> None:
    frames, aperture, _ = _scope_video(3)
    for f in frames:
        f[45:75, 65:95] = 2  # a dark hole in the middle of every frame
    m = field_of_view_mask(frames, margin=0, overlays=False)
    assert m[60, 80] and np.array_equal(m, aperture)


def test_real_colonoscopy_aperture() -> None:
    """C3VD's Olympus octagon: the black corners out, the middle in, 8 px off the edge."""
    frames = _endo_frames()
    assert len(frames) == 10
    m = field_of_view_mask(frames)
    h, w = m.shape
    assert (h, w) == (448, 445)
    assert not m[:20, :20].any() and not m[-20:, -20:].any()  # the octagon's corners
    assert m[h // 2, w // 2] and m[h // 2, 20] and m[20, w // 2]
    assert 0.84 < m.mean() < 0.9
    # SIFT at the endoscope's contrast: keypoints on the aperture's edge without the mask,
    # none there with it
    edge = cv2.dilate((~field_of_view_mask(frames, margin=0)).astype(np.uint8), np.ones((9, 9)))
    f = frames[0]
    free = detect_features(f, contrast_threshold=0.01)
    on_edge = edge[np.round(free.xy[:, 1]).astype(int), np.round(free.xy[:, 0]).astype(int)] > 0
    assert on_edge.sum() >= 10
    kept = detect_features(f, contrast_threshold=0.01, mask=m)
    assert not np.any(
        edge[np.round(kept.xy[:, 1]).astype(int), np.round(kept.xy[:, 0]).astype(int)]
    )


def test_contrast_threshold_on_endoscopic_tissue() -> None:
    """OpenCV's default SIFT contrast keeps a few tens of keypoints on the tissue; 0.01 many."""
    frames = _endo_frames()
    m = field_of_view_mask(frames)
    default = len(detect_features(frames[0], mask=m))
    low = len(detect_features(frames[0], mask=m, contrast_threshold=0.01))
    assert default < 50 and low > 4 * max(default, 1)
    bad: Any
    for bad in (0.0, -0.1, 1.5, float("nan"), "0.01"):
        with pytest.raises(InvalidInputError, match="contrast_threshold"):
            detect_features(frames[0], contrast_threshold=bad)


def test_highlights() -> None:
    frame = np.zeros((30, 40, 3), np.uint8)
    frame[:] = (255, 120, 90)  # saturated red tissue: not a highlight
    frame[10:13, 20:23] = (250, 248, 252)  # a highlight
    m = highlight_mask(frame, grow=2)
    assert m.dtype == bool and m.shape == (30, 40)
    assert m[11, 21] and m[9, 19] and not m[0, 0]
    assert int(highlight_mask(frame, grow=0).sum()) == 9
    # floats in [0, 1], uint16, grey, RGBA
    assert np.array_equal(highlight_mask(frame / 255.0, grow=2), m)
    assert np.array_equal(highlight_mask(frame.astype(np.uint16) * 257, grow=2), m)
    rgba = np.concatenate([frame, np.zeros((30, 40, 1), np.uint8)], axis=2)
    assert np.array_equal(highlight_mask(rgba, grow=2), m)
    grey = frame.mean(axis=2)
    assert highlight_mask(grey, grow=0).sum() == 9
    # real frames: a few thousandths of the image, in the aperture
    shares = [highlight_mask(f).mean() for f in _endo_frames()]
    assert 0.001 < float(np.mean(shares)) < 0.02


def _jpeg(frame: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok
    return np.asarray(cv2.imdecode(buf, cv2.IMREAD_UNCHANGED))


def test_overlay_mask_finds_the_caption_the_corner_text_and_the_rim() -> None:
    frames, aperture, caption = _scope_video(10)
    m = still_mask(frames, margin=0)
    assert m.dtype == bool and m.shape == aperture.shape
    # the caption's stripes (edges) and the corner's text's outline, the aperture's rim
    assert m[caption].mean() > 0.5
    assert m[2:10, 2:41].any()
    # the black just outside the aperture (its inside moves with the texture)
    rim = ~aperture & (cv2.dilate(aperture.astype(np.uint8), np.ones((3, 3))) > 0)
    assert m[rim].mean() > 0.5
    # nothing of the moving texture away from them
    far = cv2.dilate((m | ~aperture).astype(np.uint8), np.ones((3, 3))) == 0
    assert far.sum() > 0.5 * aperture.sum()
    inner = cv2.erode(aperture.astype(np.uint8), np.ones((9, 9))) > 0
    assert not np.any(m & inner & ~cv2.dilate(caption.astype(np.uint8), np.ones((5, 5))) > 0)
    # the margin grows it by a disc
    grown = still_mask(frames, margin=3)
    assert np.array_equal(grown, cv2.dilate(m.astype(np.uint8), _disc(3)) > 0)


def _disc(r: int) -> np.ndarray:
    yy, xx = np.mgrid[-r : r + 1, -r : r + 1]
    return (xx**2 + yy**2 <= r * r + r).astype(np.uint8)


def test_field_of_view_mask_takes_out_a_caption_compressed_with_the_video() -> None:
    """JPEG at quality 75 moves the caption's pixels by more than ``still`` (0.004): the
    old rule alone keeps most of its edges; still_mask's regions inside the aperture go."""
    frames, _, caption = _scope_video(10)
    coded = [_jpeg(f, 75) for f in frames]
    grey = np.asarray(coded[0], np.float32).mean(axis=2) / 255
    box = np.ones((3, 3), np.uint8)
    edges = caption & ((cv2.dilate(grey, box) - cv2.erode(grey, box)) >= 0.1)
    assert edges.sum() > 50
    kept = field_of_view_mask(coded, margin=0)
    assert kept[edges].mean() < 0.3
    assert kept[60, 40] and kept[20, 80]  # the scene stays
    # fewer than 8 frames: the old rule alone, as before
    old_rule = field_of_view_mask(coded[:7], margin=0)
    assert old_rule[edges].mean() > 0.5


def test_overlay_mask_through_a_video_codec() -> None:
    """The caption compressed with each frame (JPEG at quality 85): still most of it."""
    frames, _, caption = _scope_video(10)
    coded = [_jpeg(f, 85) for f in frames]
    assert still_mask(coded, margin=0)[caption].mean() > 0.4
    assert still_mask(coded, margin=0, still=0.001)[caption].mean() < 0.1


def test_overlay_mask_says_nothing_without_motion_or_frames() -> None:
    frames, _, _ = _scope_video(10)
    # fewer than min_frames, or a camera that stands still (its noise alone changes it)
    assert not still_mask(frames[:7]).any()
    assert still_mask(frames[:7], min_frames=7).any()
    rng = np.random.default_rng(0)
    still = [
        np.clip(frames[0] + rng.normal(0, s, frames[0].shape), 0, 255).astype(np.uint8)
        for s in (3.0,) * 10
    ]
    assert not still_mask(still).any()
    assert not still_mask([frames[0]] * 10).any()
    # the real colonoscopy frames: their octagon's rim, nothing in the middle
    endo = _endo_frames()
    m = still_mask(endo)
    h, w = m.shape
    assert not m[h // 4 : 3 * h // 4, w // 4 : 3 * w // 4].any()


def test_a_few_pixels_still_by_chance_are_no_overlay() -> None:
    # the first 8 frames of the room's walk at 320 x 240 (tests/workflows/
    # test_reconstruct.py's): at the focus of expansion, on the facade's mirrored seam, 22
    # edge pixels stay within 0.02 (one region); an overlay holds hundreds
    # (benchmarks/results/still-mask-2026-12-03a.md)
    from tests import sfm_scenes

    k = np.array([[240.0, 0, 159.5], [0, 240.0, 119.5], [0, 0, 1]])
    rng = np.random.default_rng(5)
    frames = [sfm_scenes.render(k, p, (320, 240), rng=rng) for p in sfm_scenes.poses(16)[:8]]
    assert not still_mask(frames).any()
    assert still_mask(frames, min_area=16, margin=0).sum() == 0
    # the same frames with a caption: found as before
    burned = [sfm_scenes.burn_in(f) for f in frames]
    assert still_mask(burned, margin=0).sum() > 1000


def test_overlay_mask_inputs_are_untouched_and_forms_agree() -> None:
    frames, _, _ = _scope_video(10)
    before = [f.copy() for f in frames]
    m = still_mask(frames)
    assert all(np.array_equal(a, b) for a, b in zip(frames, before, strict=True))
    assert np.array_equal(still_mask(np.stack(frames)), m)
    assert np.array_equal(still_mask([f[..., 0] for f in frames]), m)
    assert np.array_equal(still_mask([f / 255.0 for f in frames]), m)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: field_of_view_mask([]), "at least one frame"),
        (lambda: field_of_view_mask([np.zeros((9, 9)), np.zeros((8, 9))]), "one size"),
        (lambda: field_of_view_mask([np.zeros((9, 9), np.uint8)]), "black frames"),
        (lambda: field_of_view_mask([np.full((9, 9), 99, np.uint8)], margin=9), "margin"),
        (lambda: field_of_view_mask([np.ones((9, 9))], dark=0), "dark"),
        (lambda: field_of_view_mask([np.ones((9, 9))], margin=-1), "margin"),
        (lambda: field_of_view_mask([np.ones((9, 9))], overlays=_ONE), "overlays"),
        (lambda: field_of_view_mask([np.full((9, 9), np.nan)]), "NaN"),
        (lambda: field_of_view_mask([np.array(["a"])]), "numbers"),
        (lambda: still_mask([]), "at least one frame"),
        (lambda: still_mask(np.zeros((9, 9))), "list of frames"),
        (lambda: still_mask([np.zeros((9, 9)), np.zeros((8, 9))]), "one size"),
        (lambda: still_mask([np.ones((9, 9))] * 8, still=-1), "still"),
        (lambda: still_mask([np.ones((9, 9))] * 8, edge=0), "edge"),
        (lambda: still_mask([np.ones((9, 9))] * 8, margin=-1), "margin"),
        (lambda: still_mask([np.ones((9, 9))] * 8, min_area=0), "min_area"),
        (lambda: still_mask([np.ones((9, 9))] * 8, min_frames=2), "min_frames"),
        (lambda: still_mask([np.full((9, 9), np.nan)] * 8), "NaN"),
        (lambda: highlight_mask(np.ones((4, 4)), value=0), "value"),
        (lambda: highlight_mask(np.ones((4, 4)), saturation=2), "saturation"),
        (lambda: highlight_mask(np.ones((4, 4)), grow=_HALF), "grow"),
        (lambda: highlight_mask(np.ones((4, 4, 5))), "image"),
    ],
)
def test_errors(call: object, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()  # type: ignore[operator]


def test_frame_sharpness_is_the_variance_of_the_four_neighbour_laplacian() -> None:
    from imageform.geometry import frame_sharpness

    frame = _endo_frames()[0]
    g = frame[..., :3].astype(np.float64) / 255.0 @ np.array([0.299, 0.587, 0.114])
    lap = g[:-2, 1:-1] + g[2:, 1:-1] + g[1:-1, :-2] + g[1:-1, 2:] - 4.0 * g[1:-1, 1:-1]
    assert frame_sharpness(frame) == pytest.approx(lap.var(), rel=1e-4)


@pytest.mark.parametrize("length", [3, 9])
def test_blurred_frames_finds_real_frames_with_motion_blur_added(length: int) -> None:
    from imageform.geometry import blurred_frames, field_of_view_mask, frame_sharpness

    frames = _endo_frames()
    fov = field_of_view_mask(frames)
    assert not blurred_frames(frames, fov).any()
    # a horizontal motion of `length` px during the exposure: a line kernel
    k = np.zeros((length, length), np.float32)
    k[length // 2] = 1.0 / length
    blurred = [cv2.filter2D(f, -1, k) if i in (3, 7) else f for i, f in enumerate(frames)]
    assert np.flatnonzero(blurred_frames(blurred, fov)).tolist() == [3, 7]
    # 3 px: the sharpness falls to 0.38 of the frame's (measured: 0.376), 9 px to 0.17
    drop = frame_sharpness(blurred[3], fov) / frame_sharpness(frames[3], fov)
    assert drop < (0.4 if length == 3 else 0.2)


def test_blurred_frames_bad_input() -> None:
    from imageform.geometry import blurred_frames, frame_sharpness

    frames = [np.full((8, 8), 0.5)] * 4
    with pytest.raises(InvalidInputError, match="ratio"):
        blurred_frames(frames, ratio=1.0)
    with pytest.raises(InvalidInputError, match="window"):
        blurred_frames(frames, window=0)
    with pytest.raises(InvalidInputError, match="mask of the frame's size"):
        frame_sharpness(frames[0], np.ones((4, 4)))
    with pytest.raises(InvalidInputError, match="sequence of frames"):
        blurred_frames(None)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match=r"images\[1\]"):
        blurred_frames([frames[0], "a"])
    assert blurred_frames(frames[:2]).tolist() == [False, False]
    assert frame_sharpness(frames[0], np.zeros((8, 8))) == 0.0
