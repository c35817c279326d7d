"""One ArUco marker's pose: IPPE-square against the truth and OpenCV, and the flip ambiguity.

Frames are imageform's marker image warped by known poses (tests/video_scenes.marker_frame:
4x4 supersampled, blurred, with sensor noise); the truth is each frame's pose.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import (
    MarkerTracker,
    marker_points,
    rvec_to_matrix,
    solve_square_pose,
)
from tests import video_scenes

cv2 = pytest.importorskip("cv2")

K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
SIZE = (640, 360)
SIDE = 40.0


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))


def _corners(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    X = marker_points(SIDE) @ R.T + t
    return X[:, :2] / X[:, 2:] * K[0, 0] + K[:2, 2]


def _opencv(image: np.ndarray, subpix: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """OpenCV's pose of marker 7: ArucoDetector's corners, then SOLVEPNP_IPPE_SQUARE."""
    params = cv2.aruco.DetectorParameters()
    if subpix:
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50), params)
    corners, ids, _ = det.detectMarkers(image)
    if ids is None or 7 not in ids.ravel():
        return None
    c = corners[list(ids.ravel()).index(7)].reshape(4, 2)
    obj = marker_points(SIDE).astype(np.float32)
    _, rv, tv = cv2.solvePnP(obj, c, K, None, flags=cv2.SOLVEPNP_IPPE_SQUARE)
    return cv2.Rodrigues(rv)[0], tv.ravel()


def test_two_solutions_exact_and_as_opencv() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        rv = rng.normal(size=3)
        rv *= np.radians(rng.uniform(10, 60)) / np.linalg.norm(rv)
        R = np.diag([1.0, -1, -1]) @ np.asarray(rvec_to_matrix(rv))
        t = np.array([*rng.uniform(-40, 40, 2), rng.uniform(200, 600)])
        uv = _corners(R, t)
        ours = solve_square_pose(uv, SIDE, K, refine=False)
        assert np.abs(ours.R[0] - R).max() < 1e-9 and np.allclose(ours.tvec[0], t, atol=1e-7)
        assert ours.rms[0] < 1e-8 < ours.rms[1]
        _, rvs, tvs, _ = cv2.solvePnPGeneric(
            marker_points(SIDE), uv, K, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
        )
        # the same two poses (OpenCV's closed form, unrefined)
        for R_cv, t_cv in zip([cv2.Rodrigues(r)[0] for r in rvs], tvs, strict=True):
            k = int(np.argmin([_angle(R_cv, Ri) for Ri in ours.R]))
            assert np.abs(R_cv - ours.R[k]).max() < 1e-7
            assert np.allclose(t_cv.ravel(), ours.tvec[k], atol=1e-6 * np.linalg.norm(t))


def test_refined_pose_fits_noisy_corners_better_than_the_closed_form() -> None:
    rng = np.random.default_rng(1)
    R = np.diag([1.0, -1, -1]) @ np.asarray(rvec_to_matrix([0.4, 0.2, 0.1]))
    t = np.array([10.0, -5.0, 300.0])
    uv = _corners(R, t) + rng.normal(0, 0.3, (4, 2))
    closed = solve_square_pose(uv, SIDE, K, refine=False)
    refined = solve_square_pose(uv, SIDE, K)
    assert refined.rms[0] <= closed.rms[0] + 1e-12
    assert _angle(refined.R[0], R) < 3.0


def test_rendered_path_against_the_truth_and_opencv() -> None:
    truth = video_scenes.marker_poses(24)
    rng = np.random.default_rng(2)
    frames = [video_scenes.marker_frame(K, p, SIZE, noise=2.0, blur=0.7, rng=rng) for p in truth]
    tracker = MarkerTracker(7, SIDE, K, dictionary="4x4_50")
    ours, cv, cv_sub = [], [], []
    for (R, t), f in zip(truth, frames, strict=True):
        pose = tracker.update(f)
        assert pose.found and pose.corners == 4
        assert np.abs(pose.image_points - _corners(R, t)).max() < 0.4  # measured 0.21
        ours.append((np.linalg.norm(pose.tvec - t) / np.linalg.norm(t), _angle(pose.R, R)))
        for out, sub in ((cv, False), (cv_sub, True)):
            got = _opencv(f, sub)
            assert got is not None
            out.append((np.linalg.norm(got[1] - t) / np.linalg.norm(t), _angle(got[0], R)))
    o, c, s = np.array(ours), np.array(cv), np.array(cv_sub)
    # measured: ours median 0.35 % / 0.27 deg, worst 0.66 deg; OpenCV 1.07 % / 1.24 deg
    # (0.52 % / 0.30 deg with its CORNER_REFINE_SUBPIX)
    assert np.median(o[:, 0]) < 0.005 and np.median(o[:, 1]) < 0.5, o
    assert o[:, 1].max() < 1.5, o
    # no worse than OpenCV's detector (with or without its sub-pixel corners) + IPPE-square
    assert np.median(o[:, 1]) <= np.median(c[:, 1]) and np.median(o[:, 1]) <= np.median(s[:, 1])


def _near_frontal(n: int = 60) -> list[tuple[np.ndarray, np.ndarray]]:
    """Tilted 48 degrees, then settling to 6-10 degrees: a 30 px marker nearly face-on."""
    out = []
    for i in range(n):
        tilt = 40 * np.exp(-i / 4) + 8 + 2 * np.sin(i / 3)
        rv = np.array([0.6, 0.8, 0.0]) * np.radians(tilt)
        R = np.diag([1.0, -1, -1]) @ np.asarray(rvec_to_matrix(rv))
        out.append((R, np.array([20 * np.sin(i / 5), 10.0, 700.0])))
    return out


def test_continuity_keeps_the_right_solution_nearly_face_on() -> None:
    truth = _near_frontal()
    # each frame's mirrored pose: IPPE's other solution on the exact corners
    mirrors = [solve_square_pose(_corners(R, t), SIDE, K, refine=False).R[1] for R, t in truth]
    flips, worst = {}, {}
    for continuity in (True, False):
        tracker = MarkerTracker(7, SIDE, K, dictionary="4x4_50", continuity=continuity)
        rng = np.random.default_rng(3)
        n, errors = 0, []
        for (R, t), mirror in zip(truth, mirrors, strict=True):
            f = video_scenes.marker_frame(K, (R, t), SIZE, noise=4.0, blur=0.8, rng=rng)
            pose = tracker.update(f)
            assert pose.found
            n += _angle(pose.R, R) > _angle(pose.R, mirror)
            errors.append(_angle(pose.R, R))
        flips[continuity], worst[continuity] = n, max(errors)
    # measured: 9 frames flipped by the best fit alone (worst 22 deg), none by continuity
    assert flips[False] >= 3, flips  # the ambiguity bites on these frames
    assert flips[True] == 0 and worst[True] < 8.0, (flips, worst)


def test_frames_without_the_marker_are_missing() -> None:
    R, t = video_scenes.marker_poses(4)[1]
    frame = video_scenes.marker_frame(K, (R, t), SIZE)
    tracker = MarkerTracker(7, SIDE, K, dictionary="4x4_50")
    assert tracker.update(frame).found
    assert tracker.update(frame).searched == "box"
    blank = np.full_like(frame, 128)
    pose = tracker.update(blank)
    assert not pose.found and np.all(np.isnan(pose.rvec)) and np.isnan(pose.rms_px)
    # another marker of the dictionary is not this one
    other = MarkerTracker(8, SIDE, K, dictionary="4x4_50")
    assert not other.update(frame).found
    again = tracker.update(frame)
    assert again.found and again.searched == "frame"
    tracker.reset()
    assert tracker.update(frame).searched == "frame"


def test_smoothing_blends_the_poses() -> None:
    truth = video_scenes.marker_poses(12)
    a, b = truth[0], truth[3]
    fa = video_scenes.marker_frame(K, a, SIZE)
    fb = video_scenes.marker_frame(K, b, SIZE)
    tracker = MarkerTracker(7, SIDE, K, dictionary="4x4_50", smooth=0.5)
    p0 = tracker.update(fa)
    p1 = tracker.update(fb)
    raw = MarkerTracker(7, SIDE, K, dictionary="4x4_50").update(fb)
    assert np.allclose(p1.tvec, 0.5 * (p0.tvec + raw.tvec), atol=1e-3)


def test_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="4 finite corners"):
        solve_square_pose(np.zeros((3, 2)), SIDE, K)
    with pytest.raises(InvalidInputError, match="quadrilateral"):
        solve_square_pose([[0, 0], [1, 1], [2, 2], [0, 5]], SIDE, K)
    with pytest.raises(InvalidInputError, match="side"):
        solve_square_pose(_corners(np.eye(3), np.array([0, 0, 300.0])), -1.0, K)
    with pytest.raises(InvalidInputError, match="marker_id"):
        MarkerTracker(50, SIDE, K, dictionary="4x4_50")
    with pytest.raises(UnknownOptionError):
        MarkerTracker(0, SIDE, K, dictionary="9x9_5")
    with pytest.raises(InvalidInputError, match="frame"):
        MarkerTracker(0, SIDE, K).update(np.zeros(5))


def test_distorted_corners_are_undistorted_first() -> None:
    from imageform.geometry import BrownConrady, project_points_distorted

    lens = BrownConrady(k1=-0.3, k2=0.1)
    R = np.diag([1.0, -1, -1]) @ np.asarray(rvec_to_matrix([0.5, -0.3, 0.2]))
    t = np.array([60.0, 30.0, 250.0])
    uv = np.asarray(project_points_distorted(marker_points(SIDE), K, R, t, lens)[0])
    both = solve_square_pose(uv, SIDE, K, lens)
    assert np.abs(both.R[0] - R).max() < 1e-6 and np.allclose(both.tvec[0], t, atol=1e-4)
    plain = solve_square_pose(uv, SIDE, K)  # the lens ignored: a pose off the truth
    assert np.linalg.norm(plain.tvec[0] - t) > 1.0


def test_a_second_print_of_the_id_is_not_followed() -> None:
    """Marker 7 shaken 30-50 px a frame (out of its search box) with a larger print of id 7
    beside it from frame 4 on: the sighting nearest the previous frame's corners is kept
    (the largest, the rule without a previous frame, would follow the second print)."""
    from benchmarks.check_track_duplicates import K as K_BENCH
    from benchmarks.check_track_duplicates import second_print

    truth, frames = second_print(7)
    tracker = MarkerTracker(7, 30.0, K_BENCH, dictionary="4x4_50")
    for (R, t), f in zip(truth, frames, strict=True):
        pose = tracker.update(f)
        assert pose.found
        assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.02
        assert _angle(pose.R, R) < 2.0
    fresh = MarkerTracker(7, 30.0, K_BENCH, dictionary="4x4_50").update(frames[6])
    assert not fresh.found and fresh.searched == "ambiguous"  # no previous frame: no guess


def test_a_first_frame_with_the_id_twice_is_ambiguous_until_one_is_left() -> None:
    """Both prints of id 7 (30 mm and a misprinted 40 mm copy) in the first frames: each is
    a square of the code (IPPE fits both exactly), so the tracker gives no pose, says
    "ambiguous" and shows both sightings; once the copy is out of view the marker is found,
    then followed with the copy back in view."""
    from benchmarks.check_track_duplicates import K as K_BENCH
    from benchmarks.check_track_duplicates import second_print

    truth, frames = second_print(7)
    tracker = MarkerTracker(7, 30.0, K_BENCH, dictionary="4x4_50")
    for f in frames[5:7]:
        pose = tracker.update(f)
        assert not pose.found and pose.searched == "ambiguous"
        assert pose.image_points.shape == (8, 2) and np.isnan(pose.tvec).all()
        sides = np.linalg.norm(np.diff(pose.image_points.reshape(2, 4, 2), axis=1), axis=2)
        big, small = sorted(sides.mean(axis=1), reverse=True)
        assert abs(big / small - 4 / 3) < 0.15  # the two prints
    for k in (3, 4, 5):  # frame 3: the copy not printed yet; 4, 5: in view, followed
        pose = tracker.update(frames[k])
        assert pose.found and pose.searched != "ambiguous"
        assert np.linalg.norm(pose.tvec - truth[k][1]) / np.linalg.norm(truth[k][1]) < 0.02


def _tilted(deg: float, t: tuple[float, float, float] = (0.0, 0.0, 700.0)) -> tuple:
    """A marker facing the camera, tilted ``deg`` about the (0.6, 0.8) axis, at ``t``."""
    R = np.diag([1.0, -1, -1]) @ np.asarray(
        rvec_to_matrix(np.array([0.6, 0.8, 0.0]) * np.radians(deg))
    )
    return R, np.array(t)


def test_pick_fit_then_motion_prior_then_refusal() -> None:
    """The choice between two fitting poses (rules of _pick), on the numbers they see."""
    from imageform.geometry.marker_tracking import _pick, _Prior

    (Ra, ta), (Rb, tb) = _tilted(8.0), _tilted(-8.0)  # a tilt and its mirror, 16 deg apart
    R, t = np.stack([Ra, Rb]), np.stack([ta, tb])
    # the mirror fits far worse (over 4 x 0.1 + 1 px): the fit decides, whatever the prior
    assert _pick(np.array([0.1, 1.5]), R, t, 4, _Prior(Rb, tb, 1), True) == 0
    # both fit within the noise: the pose nearer the last one (a frame ago) is kept
    close = np.array([0.10, 0.11])
    assert _pick(close, R, t, 4, _Prior(Rb, tb, 1), True) == 1
    assert _pick(close, R, t, 4, _Prior(Ra, ta, 1), True) == 0
    # no previous pose and nothing in the fit: refused; without continuity, the better fit
    assert _pick(close, R, t, 4, None, True) is None
    assert _pick(close, R, t, 4, None, False) == 0
    # ... but a difference of fit beyond the noise (9 sigma^2 of the residuals) settles it:
    # 4 (0.3^2 - 0.1^2) = 0.32 >= 9 * max(4 * 0.1^2 / 2, 0.05^2) = 0.18
    assert _pick(np.array([0.1, 0.3]), R, t, 4, None, True) == 0
    assert _pick(np.array([0.1, 0.2]), R, t, 4, None, True) is None  # 0.12 < 0.18
    # the prior halfway between them separates nothing
    assert _pick(close, R, t, 4, _Prior(_tilted(0.0)[0], ta, 1), True) is None
    # the motion allowed grows with the frames since the last pose (sigma 5 deg x sqrt(gap)):
    # 16 deg from the mirror, 0 from the pose: cost 10.2 a frame later, 3.4 three frames
    # later (still apart), and no prior beyond five frames
    assert _pick(close, R, t, 4, _Prior(Ra, ta, 3), True) == 0
    assert _pick(close, R, t, 4, _Prior(Ra, ta, 6), True) is None
    # the translation counts too: two poses of one rotation at different places (two
    # sightings), told apart by where the last pose was
    R2, t2 = np.stack([Ra, Ra]), np.stack([ta, ta + [70.0, 0, 0]])
    assert _pick(close, R2, t2, 4, _Prior(Ra, ta + [68.0, 0, 0], 1), True) == 1
    assert _pick(close, R2, t2, 4, _Prior(Ra, ta + [2.0, 0, 0], 1), True) == 0
    # one pose in all but name (within 5 deg and 5 %): no choice to make
    R3, t3 = np.stack([Ra, _tilted(10.0)[0]]), np.stack([ta, ta])
    assert _pick(np.array([0.2, 0.1]), R3, t3, 4, None, True) == 1


def test_cold_starts_and_dropped_frames_never_flip() -> None:
    """Near-frontal frames (tilt 6-10 deg, 30 px), each given to a fresh tracker, or with
    every third frame blank: a pose is never the mirrored one. Measured (check_track_flips):
    cold starts 9 of 60 flipped before, 0 after (30 refused as ambiguous); dropped frames
    6 of 40 flipped before, 0 after (none refused)."""
    truth = _near_frontal()
    mirrors = [solve_square_pose(_corners(R, t), SIDE, K, refine=False).R[1] for R, t in truth]
    rng = np.random.default_rng(3)
    frames = [video_scenes.marker_frame(K, p, SIZE, noise=4.0, blur=0.8, rng=rng) for p in truth]
    flips = refused = found = 0
    for i in range(8, 40):  # the tilt settled to 6-10 degrees
        pose = MarkerTracker(7, SIDE, K, dictionary="4x4_50").update(frames[i])
        refused += pose.searched == "ambiguous"
        if pose.found:
            found += 1
            flips += _angle(pose.R, truth[i][0]) > _angle(pose.R, mirrors[i])
    assert flips == 0 and refused >= 12 and found >= 12, (flips, refused, found)  # 16, 16
    tracker = MarkerTracker(7, SIDE, K, dictionary="4x4_50")
    blank = np.full_like(frames[0], 128)
    flips = found = 0
    for i, f in enumerate(frames):
        if i % 3 == 2:
            assert not tracker.update(blank).found
            continue
        pose = tracker.update(f)
        found += pose.found
        flips += pose.found and _angle(pose.R, truth[i][0]) > _angle(pose.R, mirrors[i])
    assert flips == 0 and found == 40, (flips, found)
