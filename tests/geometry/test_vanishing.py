"""Vanishing points, the horizon, perspective type and intrinsics from vanishing points."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import (
    camera_rotation,
    focal_from_vanishing_points,
    horizon_line,
    intrinsics_from_vanishing_points,
    lines_from_segments,
    perspective_type,
    project_points,
    rvec_to_matrix,
    vanishing_point,
    vanishing_point_from_lines,
)

K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])


def test_lecture_vanishing_point() -> None:
    """Lecture: K = [[500,0,320],[0,500,240],[0,0,1]], d = (1, 0, 2) -> (570, 240)."""
    np.testing.assert_allclose(vanishing_point(K, [1.0, 0.0, 2.0]), [570.0, 240.0, 1.0])


def test_direction_parallel_to_image_plane_is_ideal() -> None:
    v = vanishing_point(K, [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(v, [0.0, 1.0, 0.0])
    assert np.isfinite(v).all()


def test_opposite_directions_same_point() -> None:
    np.testing.assert_allclose(
        vanishing_point(K, [1.0, 2.0, 3.0]), vanishing_point(K, [-1.0, -2.0, -3.0])
    )


def test_vanishing_point_zero_direction() -> None:
    with pytest.raises(InvalidInputError, match="non-zero"):
        vanishing_point(K, [0.0, 0.0, 0.0])


@settings(max_examples=40, deadline=None)
@given(
    offsets=st.lists(
        st.lists(st.floats(-5, 5, allow_nan=False), min_size=3, max_size=3), min_size=2, max_size=6
    )
)
def test_vanishing_point_independent_of_line_position(offsets: list[list[float]]) -> None:
    """Parallel 3-D lines anywhere in front of the camera meet at K R d."""
    R = rvec_to_matrix([0.1, -0.2, 0.05])
    t = np.array([0.0, 0.0, 20.0])
    d = np.array([0.3, -0.1, 1.0])
    segs = []
    for o in offsets:
        p0 = np.asarray(o)
        X = np.stack([p0, p0 + 3.0 * d])
        uv, valid = project_points(X, K, R, t)
        assert valid.all()
        segs.append(uv)
    segs_a = np.asarray(segs)
    lengths = np.linalg.norm(segs_a[:, 1] - segs_a[:, 0], axis=1)
    if lengths.min() < 1e-3:
        return
    lines = lines_from_segments(segs_a)
    # every projected line passes through the predicted vanishing point
    v = vanishing_point(K, d, R)
    np.testing.assert_allclose(lines @ v, 0.0, atol=1e-6)
    # two image lines at a clear angle: the least-squares point is the vanishing point
    # (3-D lines whose plane contains the camera centre image onto the same line)
    cosines = np.abs(lines[:, :2] @ lines[:, :2].T)
    if cosines.min() < np.cos(0.02):
        est = vanishing_point_from_lines(lines)
        np.testing.assert_allclose(est, v, rtol=1e-6, atol=1e-6)


def test_horizon_level_camera_through_principal_point() -> None:
    line = horizon_line(K, np.eye(3))
    np.testing.assert_allclose(line @ [320.0, 240.0, 1.0], 0.0, atol=1e-12)
    np.testing.assert_allclose(line, [0.0, 1.0, -240.0])


def test_tilting_up_moves_horizon_down() -> None:
    rows = []
    for pitch_deg in (0.0, 5.0, 10.0, 20.0):
        line = horizon_line(K, camera_rotation(pitch=np.deg2rad(pitch_deg)))
        rows.append(-(line[0] * 320 + line[2]) / line[1])  # v at the image centre column
    assert np.all(np.diff(rows) > 0)
    # tan law: v = cy + f tan(pitch)
    assert rows[2] == pytest.approx(240 + 500 * np.tan(np.deg2rad(10.0)))


def test_horizon_is_vanishing_line_of_ground_directions() -> None:
    R = camera_rotation(pitch=0.2, yaw=0.4, roll=0.1)
    line = horizon_line(K, R)
    for d in ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]):
        v = vanishing_point(K, d, R)
        assert abs(line @ v) < 1e-9


def test_horizon_at_infinity_looking_straight_down() -> None:
    R = camera_rotation(pitch=-np.pi / 2)
    np.testing.assert_allclose(horizon_line(K, R), [0.0, 0.0, 1.0], atol=1e-12)


def test_perspective_types() -> None:
    axes = np.eye(3)
    assert perspective_type(axes) == 1
    assert perspective_type(axes, camera_rotation(pitch=0.0, yaw=0.5)) == 2
    assert perspective_type(axes, camera_rotation(pitch=0.3, yaw=0.5)) == 3
    with pytest.raises(InvalidInputError, match=r"\(N, 3\)"):
        perspective_type(np.zeros(3))


def test_intrinsics_from_three_orthogonal_vps() -> None:
    Kt = np.array([[900.0, 0, 610], [0, 900, 350], [0, 0, 1]])
    R = camera_rotation(pitch=0.35, yaw=0.6, roll=0.05)
    vps = [vanishing_point(Kt, d, R) for d in np.eye(3)]
    np.testing.assert_allclose(intrinsics_from_vanishing_points(*vps), Kt, rtol=1e-9)
    f = focal_from_vanishing_points(vps[0], vps[2], [610.0, 350.0])
    assert float(f) == pytest.approx(900.0)


def test_intrinsics_from_vps_degenerate() -> None:
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        intrinsics_from_vanishing_points([0.0, 0.0], [1.0, 1.0], [2.0, 2.0])
    with pytest.raises(DegenerateConfigurationError, match="acute"):
        intrinsics_from_vanishing_points([0.0, 0.0], [100.0, 0.0], [10.0, 1.0])
    with pytest.raises(DegenerateConfigurationError, match="infinity"):
        intrinsics_from_vanishing_points([1.0, 0.0, 0.0], [100.0, 0.0], [10.0, 1.0])
    with pytest.raises(DegenerateConfigurationError, match="orthogonal"):
        focal_from_vanishing_points([400.0, 240.0], [500.0, 240.0], [320.0, 240.0])


def test_vp_from_lines_parallel_gives_ideal_point() -> None:
    lines = lines_from_segments([[[0, 0], [1, 0]], [[0, 1], [1, 1]], [[0, 5], [3, 5]]])
    v = vanishing_point_from_lines(lines)
    assert v[2] == 0.0
    np.testing.assert_allclose(np.abs(v[:2]), [1.0, 0.0])


def test_vp_from_noisy_lines_weighted() -> None:
    rng = np.random.default_rng(2)
    v = np.array([900.0, -300.0])
    starts = rng.uniform(0, 640, size=(40, 2))
    ends = starts + (v - starts) * rng.uniform(0.2, 0.5, size=(40, 1))
    ends += rng.normal(scale=0.3, size=ends.shape)
    segs = np.stack([starts, ends], axis=1)
    lines = lines_from_segments(segs)
    w = np.linalg.norm(ends - starts, axis=1)
    est = vanishing_point_from_lines(lines, weights=w)
    assert np.linalg.norm(est[:2] - v) < 15.0
    with pytest.raises(InvalidInputError, match="weight"):
        vanishing_point_from_lines(lines, weights=-w)
    with pytest.raises(InvalidInputError, match="N >= 2"):
        vanishing_point_from_lines(lines[:1])
