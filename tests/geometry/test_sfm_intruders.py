"""Frames that do not belong to a sequence are left out of its reconstruction.

``reconstruct_sequence``'s fallbacks (a frame's keypoints matched directly to its
neighbours' points, then the pose of a verified pair scaled by as few as 6 points) register
frames whose tracks are short; a frame of another scene must not be registered by them (a
false pose is worse than a missing one). The intruders: a Kodak photograph (one that is not
on the room's walls, and three that are, tiled there: a repeated texture), a Kodak photograph
carrying the same burned-in text overlay as the true frames (its only matches to them on the
overlay), and, among real colonoscopy frames (tests/data/endo, C3VD v3, CC BY 4.0), a Kodak
photograph and a mirrored frame (the same tissue, no camera sees it so). A copy of a true
frame shifted by a few pixels (a crop) is a view of the scene and is registered.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from imageform.geometry import field_of_view_mask, reconstruct_sequence
from tests import sfm_scenes

cv2 = pytest.importorskip("cv2")

ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"
K = np.array([[300.0, 0, 199.5], [0, 300.0, 149.5], [0, 0, 1]])


def _kodak(folder: Path, i: int, size: tuple[int, int]) -> np.ndarray:
    from imageform.io import read_image

    im = np.asarray(read_image(folder / "kodak" / f"kodim{i:02d}.png"))[..., :3]
    return np.asarray(cv2.resize(im, size, interpolation=cv2.INTER_AREA))


def _angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def _check_walk(rec: object, true_idx: list[int], truth: list, deg: float = 2.0) -> None:
    """The true frames registered, within ``deg`` degrees and 1 % of the path of the truth."""
    R_est, t_est = rec.R, rec.t  # type: ignore[attr-defined]
    assert rec.registered[true_idx].all(), rec.notes  # type: ignore[attr-defined]
    f0 = true_idx[0]
    for i, (R, _) in zip(true_idx, truth, strict=True):
        d = (R_est[i] @ R_est[f0].T) @ (R @ truth[0][0].T).T
        assert _angle_deg(d) < deg, (i, _angle_deg(d))
    C_est = np.array([-R_est[i].T @ t_est[i] for i in true_idx])
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(C_est, C_true) < 0.01


@pytest.mark.parametrize(
    "photo",
    [
        pytest.param(3, id="unrelated"),
        pytest.param(8, id="tiled-on-the-near-wall"),
        pytest.param(1, id="tiled-on-the-far-wall"),
        pytest.param(21, id="tiled-on-the-right-wall"),
    ],
)
def test_a_photograph_in_the_walk_is_left_out(shared_data: Path, photo: int) -> None:
    # the room's walls carry Kodak 1, 8, 13, 21, 23 and 5 (sfm_scenes), tiled mirrored:
    # Kodak 3 shares nothing with them, the others a wall's texture. Kodak 1 and 21 have a
    # verified pair with a frame of the walk (frames 8 and 2), and the pose of that pair,
    # scaled by 7 points, put the photograph more than 3 steps of the walk off its
    # neighbours (frames 3 and 5): registered before the scale had to keep the camera near them
    frames, truth = sfm_scenes.sequence(K, 8, (400, 300))
    seq = [*frames[:4], _kodak(shared_data, photo, (400, 300)), *frames[4:]]
    rec = reconstruct_sequence(seq, K, max_features=2000)
    assert not rec.registered[4], rec.notes
    _check_walk(rec, [0, 1, 2, 3, 5, 6, 7, 8], truth)


def test_photographs_sharing_only_a_burned_in_overlay_are_left_out(shared_data: Path) -> None:
    # the overlay (the same text at the same place in every frame) is the photographs' only
    # match to the walk: still_mask finds it (it stands still while the walk moves) and
    # no keypoint is taken there, so the photographs match nothing and the walk is the
    # walk without its text
    frames, truth = sfm_scenes.sequence(K, 8, (400, 300))
    photos = [_kodak(shared_data, i, (400, 300)) for i in (3, 20)]
    seq = [sfm_scenes.burn_in(f) for f in [*frames, *photos]]
    rec = reconstruct_sequence(seq, K, max_features=2000)
    assert not rec.registered[8:].any(), rec.notes
    assert any("stands still while the camera moves" in n for n in rec.notes), rec.notes
    # the text and its margin cover 43 % of every frame (its top half): the walk is made of
    # the rest, its last frames 1.7-2.3 degrees off the truth on an AVX-512 machine (0.2-0.4
    # for the walk without text; as much with the top half masked by hand), under 2 on others
    _check_walk(rec, list(range(8)), truth, deg=3.0)


def test_the_overlay_is_found_on_the_walk_and_nothing_without_it() -> None:
    from imageform.geometry import still_mask

    frames, _ = sfm_scenes.sequence(K, 8, (400, 300))
    assert not still_mask(frames).any()
    burned = [sfm_scenes.burn_in(f) for f in frames]
    m = still_mask(burned, margin=0)
    # the white letters (255 in every channel of every frame, where the scene is not white)
    text = np.all(burned[0] == 255, axis=2) & np.all(
        [np.all(b == 255, axis=2) for b in burned], axis=0
    )
    text &= ~np.all(frames[0] == 255, axis=2)
    assert text.sum() > 500
    # most of the letters, nothing below the six lines of text
    assert m[text].mean() > 0.6, m[text].mean()
    assert not m[150:].any()


@pytest.mark.xfail(
    strict=False,
    reason="without still_mask (overlays=False) the fallbacks may register a photograph: "
    "its letters match the walk's along the text's lines, a translation an essential matrix "
    "fits (frame 8 by the pose of its pair with frame 2 on an AMD EPYC, 2026-12-02)",
)
def test_without_the_still_mask_the_fallbacks_leave_the_photographs_out(
    shared_data: Path,
) -> None:
    frames, truth = sfm_scenes.sequence(K, 8, (400, 300))
    photos = [_kodak(shared_data, i, (400, 300)) for i in (3, 20)]
    seq = [sfm_scenes.burn_in(f) for f in [*frames, *photos]]
    rec = reconstruct_sequence(seq, K, max_features=2000, overlays=False)
    assert not rec.registered[8:].any(), rec.notes
    _check_walk(rec, list(range(8)), truth)


def _endo() -> tuple[list[np.ndarray], object]:
    from imageform.io import read_camera, read_image

    cam = read_camera(ENDO / "camera.toml").camera
    return [np.asarray(read_image(ENDO / f"c3vdv3_f{i:03d}.jpg")) for i in range(0, 57, 8)], cam


@pytest.mark.slow
def test_a_photograph_and_a_mirrored_frame_among_colonoscopy_frames_are_left_out(
    shared_data: Path,
) -> None:
    frames, cam = _endo()
    h, w = frames[0].shape[:2]
    mask = field_of_view_mask(frames)  # the true frames' aperture
    mirrored = np.ascontiguousarray(frames[6][:, ::-1])
    seq = [*frames[:4], _kodak(shared_data, 3, (w, h)), *frames[4:], mirrored]
    rec = reconstruct_sequence(
        seq,
        cam.K,  # type: ignore[attr-defined]
        cam.distortion,  # type: ignore[attr-defined]
        masks=mask,
        contrast_threshold=0.01,
    )
    assert not rec.registered[4] and not rec.registered[9], rec.notes
    assert rec.registered[[0, 1, 2, 3, 5, 6, 7, 8]].all(), rec.notes
    true_idx = [0, 1, 2, 3, 5, 6, 7, 8]
    # consecutive true frames turn 0.3 to 3.5 degrees (test_sfm_endo.py): the photograph
    # between frames 3 and 5 has not split them
    for i, j in itertools.pairwise(true_idx):
        assert _angle_deg(rec.R[j] @ rec.R[i].T) < 6.0, (i, j)


@pytest.mark.slow
def test_a_shifted_copy_of_a_colonoscopy_frame_is_registered_beside_it() -> None:
    frames, cam = _endo()
    h, w = frames[0].shape[:2]
    mask = field_of_view_mask(frames)
    # the last frame cropped 3 px to the left and 2 px down: the same view, a few pixels
    # off (the principal point's shift, a rotation of about 1 degree)
    shift = np.array([[1, 0, 3], [0, 1, -2]], np.float32)
    copy = np.asarray(cv2.warpAffine(frames[7], shift, (w, h)))
    rec = reconstruct_sequence(
        [*frames, copy],
        cam.K,  # type: ignore[attr-defined]
        cam.distortion,  # type: ignore[attr-defined]
        masks=mask,
        contrast_threshold=0.01,
    )
    assert rec.registered.all(), rec.notes
    assert _angle_deg(rec.R[8] @ rec.R[7].T) < 2.0
