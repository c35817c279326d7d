"""draw_pose_overlay (track --overlay): the full camera model, nothing behind the camera."""

from __future__ import annotations

import numpy as np

from imageform.geometry import BoardPose, BrownConrady, Camera
from imageform.io import Plan
from imageform.report.overlays import _AXES, _PLAN, draw_pose_overlay

K = np.array([[400.0, 0, 159.5], [0, 400.0, 119.5], [0, 0, 1]])
T = np.array([0.0, 0.0, 500.0])  # the board's origin 500 units ahead, facing the camera


def _pose(found: bool = True) -> BoardPose:
    nan3 = np.full(3, np.nan)
    return BoardPose(
        found,
        np.zeros(3) if found else nan3,
        T if found else nan3,
        np.eye(3) if found else np.full((3, 3), np.nan),
        0.1 if found else np.nan,
        np.zeros((0, 2)),
        np.zeros((0, 3)),
        "frame" if found else "none",
    )


def _has(image: np.ndarray, colour: tuple[int, int, int], u: float, v: float, r: int = 2) -> bool:
    ui, vi = round(u), round(v)
    patch = image[max(vi - r, 0) : vi + r + 1, max(ui - r, 0) : ui + r + 1]
    return bool(np.any(np.all(patch == colour, axis=-1)))


def test_plan_and_axes_where_the_camera_sees_them() -> None:
    frame = np.full((240, 320, 3), 60, np.uint8)
    keep = frame.copy()
    plan = Plan(
        np.array([[-100.0, 50, 0], [100, 50, 0], [40, -40, 0]]),
        polylines=(np.array([0, 1]),),
        singles=np.array([2]),
    )
    out = draw_pose_overlay(frame, _pose(), K, plan=plan, axis_length=60.0)
    np.testing.assert_array_equal(frame, keep)  # the input is never drawn on
    cam = Camera(K, np.eye(3), T)
    mid = np.asarray(cam.project([[0.0, 50, 0]]).uv)[0]  # the cut's middle
    assert _has(out, _PLAN, *mid)
    ring = np.asarray(cam.project([[40.0, -40, 0]]).uv)[0] + [5, 0]  # the target's ring
    assert _has(out, _PLAN, *ring)
    for i, colour in enumerate(_AXES[:2]):  # x and y; z points along the optical axis
        tip = np.asarray(cam.project([np.eye(3)[i] * 55]).uv)[0]
        assert _has(out, colour, *tip)
    far = np.ones((240, 320), bool)
    far[60:180, 76:244] = False  # nothing drawn away from the board
    np.testing.assert_array_equal(out[far], keep[far])


def test_nothing_behind_the_camera_is_drawn() -> None:
    """A target behind the camera and a cut through the camera's plane: only what is ahead."""
    frame = np.zeros((240, 320, 3), np.uint8)
    behind = np.array([[60.0, 0, -700]])  # z_cam = -200: a pinhole would put it at u = 39.5
    cut = np.array([[0.0, -20, 0], [0.0, -20, -1000]])  # from the board to 500 behind the eye
    plan = Plan(np.vstack([behind, cut]), polylines=(np.array([1, 2]),), singles=np.array([0]))
    out = draw_pose_overlay(frame, _pose(), K, plan=plan, axis_length=1e-3)
    assert not _has(out, _PLAN, 39.5, 119.5, r=8)
    yellow = np.all(out == _PLAN, axis=-1)
    vs, us = np.nonzero(yellow)
    assert yellow.any()
    # the piece ahead runs from the board's point (159.5, 103.5) upwards, out of the frame
    assert np.all(np.abs(us - 159.5) < 3) and vs.max() <= 106


def test_distortion_bends_the_plan_and_a_lost_board_gets_the_label_only() -> None:
    frame = np.full((240, 320, 3), 60, np.uint8)
    plan = Plan(np.array([[-140.0, 100, 0], [140, 100, 0]]), polylines=(np.array([0, 1]),))
    cam = BrownConrady(k1=-0.3)
    flat = draw_pose_overlay(frame, _pose(), K, plan=plan, axis_length=1e-3)
    bent = draw_pose_overlay(frame, _pose(), K, cam, plan=plan, axis_length=1e-3)
    rows = lambda im, u: np.nonzero(np.all(im[:, u] == _PLAN, axis=-1))[0].mean()  # noqa: E731
    # barrel distortion pulls the line's ends towards the centre more than its middle
    assert abs(rows(bent, 160) - rows(flat, 160)) < abs(rows(bent, 60) - rows(flat, 60))
    lost = draw_pose_overlay(frame, _pose(False), K, plan=plan, label="frame 7  board not found")
    changed = np.any(lost != frame, axis=-1)
    assert changed[:21].any() and not changed[22:].any()
