"""Rotations: cross-checked against SciPy (Euler, quaternions) and OpenCV (Rodrigues)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import (
    axis_rotation,
    camera_rotation,
    euler_to_matrix,
    is_rotation,
    look_at,
    matrix_to_euler,
    matrix_to_quaternion,
    matrix_to_rvec,
    quaternion_to_matrix,
    rvec_to_matrix,
)

ORDERS = ["xyz", "xzy", "yxz", "zyx", "XYZ", "ZYX", "YXZ", "zxz", "xyx", "ZXZ", "YZY"]


@pytest.mark.parametrize("order", ORDERS)
def test_euler_matches_scipy(order: str) -> None:
    """Cross-check: SciPy's Rotation.from_euler uses the same lower/upper-case convention."""
    rng = np.random.default_rng(3)
    a = rng.uniform(-1.2, 1.2, size=(64, 3))
    if order[0].lower() == order[2].lower():
        a[:, 1] = rng.uniform(0.2, 2.9, size=64)
    R = euler_to_matrix(a, order)
    np.testing.assert_allclose(R, Rotation.from_euler(order, a).as_matrix(), atol=1e-14)
    back = matrix_to_euler(R, order)
    np.testing.assert_allclose(back, a, atol=1e-12)


def test_euler_gimbal_lock_round_trip() -> None:
    a = np.array([0.3, np.pi / 2, -0.4])
    R = euler_to_matrix(a, "XYZ")
    np.testing.assert_allclose(euler_to_matrix(matrix_to_euler(R, "XYZ"), "XYZ"), R, atol=1e-12)


@pytest.mark.parametrize("order", ["xy", "xxz", "xYz", 3, "abc"])
def test_bad_euler_order(order: object) -> None:
    with pytest.raises(InvalidInputError, match="Euler order"):
        euler_to_matrix([0.0, 0.0, 0.0], order)  # type: ignore[arg-type]


def test_axis_rotation_right_handed() -> None:
    np.testing.assert_allclose(axis_rotation("x", np.pi / 2) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(axis_rotation("y", np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    with pytest.raises(InvalidInputError, match="axis"):
        axis_rotation("w", 0.1)


def test_rodrigues_matches_opencv() -> None:
    """Cross-check against cv2.Rodrigues in both directions on random vectors."""
    rng = np.random.default_rng(4)
    for _ in range(50):
        r = rng.normal(size=3) * rng.uniform(0, 1.0)
        np.testing.assert_allclose(rvec_to_matrix(r), cv2.Rodrigues(r)[0], atol=1e-14)
        R = rvec_to_matrix(r)
        np.testing.assert_allclose(matrix_to_rvec(R), cv2.Rodrigues(R)[0].ravel(), atol=1e-10)


def test_rvec_near_pi_and_zero() -> None:
    for r in ([np.pi - 1e-10, 0, 0], [0, 0, np.pi], [1e-12, 0, 0], [0.0, 0.0, 0.0]):
        R = rvec_to_matrix(r)
        np.testing.assert_allclose(rvec_to_matrix(matrix_to_rvec(R)), R, atol=1e-12)


def test_quaternion_matches_scipy() -> None:
    rng = np.random.default_rng(5)
    q = rng.normal(size=(100, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    R = quaternion_to_matrix(q)
    # SciPy stores (x, y, z, w)
    np.testing.assert_allclose(R, Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix(), atol=1e-14)
    back = matrix_to_quaternion(R)
    same = np.where(q[:, :1] < 0, -q, q)
    np.testing.assert_allclose(back, same, atol=1e-12)


def test_zero_quaternion() -> None:
    with pytest.raises(InvalidInputError, match="zero quaternion"):
        quaternion_to_matrix([0.0, 0.0, 0.0, 0.0])


def test_rotation_checks() -> None:
    assert not bool(is_rotation(np.diag([1.0, 1.0, -1.0])))
    assert not bool(is_rotation(np.eye(3) * 1.01))
    assert bool(is_rotation(rvec_to_matrix([0.3, 0.2, 0.1])))
    with pytest.raises(InvalidInputError, match="reflection"):
        matrix_to_rvec(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInputError, match="rotation matrix"):
        matrix_to_quaternion(np.eye(3) * 2.0)
    with pytest.raises(InvalidInputError, match=r"expected R of shape \(\.\.\., 3, 3\)"):
        matrix_to_quaternion(np.eye(2))


def test_camera_rotation_pitch_up_and_yaw_right() -> None:
    R = camera_rotation(pitch=np.deg2rad(20))
    axis = R.T @ [0.0, 0.0, 1.0]  # optical axis in the world (y down)
    assert axis[1] < 0  # tilted up
    R = camera_rotation(pitch=0.0, yaw=np.deg2rad(20))
    assert (R.T @ [0.0, 0.0, 1.0])[0] > 0  # turned right
    assert bool(is_rotation(camera_rotation(0.3, -0.2, 0.9)))


def test_look_at_axes() -> None:
    eye = np.array([2.0, -1.0, -3.0])
    target = np.array([0.0, 0.0, 0.0])
    R, t = look_at(eye, target)
    assert bool(is_rotation(R))
    np.testing.assert_allclose(R @ target + t, [0, 0, np.linalg.norm(eye)], atol=1e-12)
    np.testing.assert_allclose(-R.T @ t, eye, atol=1e-12)
    # world up (0, -1, 0) maps to the image's up, -y: its camera y component is negative
    assert (R @ [0.0, -1.0, 0.0])[1] < 0


def test_look_at_degenerate() -> None:
    with pytest.raises(DegenerateConfigurationError, match="parallel"):
        look_at([0.0, 0.0, 0.0], [0.0, -5.0, 0.0])
    with pytest.raises(DegenerateConfigurationError, match="coincide"):
        look_at([1.0, 1.0, 1.0], [1.0, 1.0, 1.0])


@settings(max_examples=80, deadline=None)
@given(st.lists(st.floats(-3, 3, allow_nan=False), min_size=3, max_size=3))
def test_rvec_matrix_orthonormal_property(r: list[float]) -> None:
    R = rvec_to_matrix(r)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-13)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-13)
    np.testing.assert_allclose(rvec_to_matrix(matrix_to_rvec(R)), R, atol=1e-11)


def test_float32_rotations() -> None:
    R = rvec_to_matrix(np.array([0.1, 0.2, 0.3], dtype=np.float32))
    assert R.dtype == np.float32
    assert matrix_to_quaternion(R).dtype == np.float32
