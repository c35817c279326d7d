"""Homogeneous coordinates, lines, intersections, collinearity and the cross-ratio."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from imageform.geometry import (
    apply_homography,
    are_collinear,
    cross_ratio,
    from_homogeneous,
    from_homogeneous_masked,
    intersect_lines,
    line_through,
    to_homogeneous,
)


def test_to_from_homogeneous_round_trip_batch() -> None:
    rng = np.random.default_rng(0)
    p = rng.normal(size=(4, 5, 3))
    h = to_homogeneous(p)
    assert h.shape == (4, 5, 4)
    np.testing.assert_array_equal(h[..., 3], 1.0)
    np.testing.assert_allclose(from_homogeneous(h * 7.5), p, rtol=1e-15)


def test_to_homogeneous_direction() -> None:
    np.testing.assert_array_equal(to_homogeneous([1.0, 2.0], w=0.0), [1.0, 2.0, 0.0])


def test_from_homogeneous_at_infinity_raises_by_default() -> None:
    with pytest.raises(DegenerateConfigurationError, match="w = 0"):
        from_homogeneous([[1.0, 2.0, 0.0], [1.0, 1.0, 1.0]])


def test_from_homogeneous_at_infinity_nan_and_mask() -> None:
    out, finite = from_homogeneous_masked([[1.0, 2.0, 0.0], [2.0, 4.0, 2.0]])
    assert np.isnan(out[0]).all()
    np.testing.assert_array_equal(out[1], [1.0, 2.0])
    np.testing.assert_array_equal(finite, [False, True])
    nan_only = from_homogeneous([[1.0, 2.0, 0.0], [2.0, 4.0, 2.0]], at_infinity="nan")
    np.testing.assert_array_equal(nan_only, out)


def test_from_homogeneous_bad_policy() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'nan', 'raise'"):
        from_homogeneous([1.0, 1.0, 1.0], at_infinity="ignore")  # type: ignore[arg-type]


def test_dtype_float32_kept() -> None:
    p = np.ones((3, 2), dtype=np.float32)
    assert to_homogeneous(p).dtype == np.float32
    assert from_homogeneous(to_homogeneous(p)).dtype == np.float32


def test_integer_coordinates_compute_in_float64() -> None:
    assert to_homogeneous(np.array([3, -1])).dtype == np.float64


def test_line_through_and_signed_distance() -> None:
    line = line_through([0.0, 0.0], [4.0, 3.0])
    # a^2 + b^2 = 1: l . (x, y, 1) is the signed distance
    assert np.hypot(line[0], line[1]) == pytest.approx(1.0)
    assert abs(line @ [3.0, -4.0, 1.0]) == pytest.approx(5.0)


def test_line_through_coincident_points() -> None:
    with pytest.raises(DegenerateConfigurationError, match="coincide"):
        line_through([1.0, 1.0], [1.0, 1.0])


def test_intersection_of_parallel_lines_is_ideal_point() -> None:
    l1 = line_through([0.0, 0.0], [1.0, 1.0])
    l2 = line_through([0.0, 1.0], [1.0, 2.0])
    x = intersect_lines(l1, l2)
    assert x[2] == 0.0
    np.testing.assert_allclose(x[:2], [2**-0.5, 2**-0.5])


def test_intersection_identical_lines() -> None:
    with pytest.raises(DegenerateConfigurationError, match="identical"):
        intersect_lines([1.0, 2.0, 3.0], [2.0, 4.0, 6.0])


def test_intersection_batched() -> None:
    rng = np.random.default_rng(1)
    pts = rng.uniform(-10, 10, size=(50, 2))
    d1 = rng.normal(size=(50, 2))
    d2 = rng.normal(size=(50, 2))
    x = intersect_lines(line_through(pts, pts + d1), line_through(pts, pts + d2))
    np.testing.assert_allclose(x[:, :2], pts, atol=1e-9)


def test_collinear() -> None:
    assert bool(are_collinear([[0.0, 0.0], [1.0, 2.0], [2.0, 4.0], [-3.0, -6.0]]))
    assert not bool(are_collinear([[0.0, 0.0], [1.0, 2.0], [2.0, 4.001]]))
    batch = np.array([[[0, 0], [1, 1], [2, 2]], [[0, 0], [1, 0], [0, 1]]], dtype=float)
    np.testing.assert_array_equal(are_collinear(batch), [True, False])


def test_collinear_bad_shape() -> None:
    with pytest.raises(InvalidInputError, match=r"\(\.\.\., N, 2\)"):
        are_collinear([1.0, 2.0])


def test_cross_ratio_textbook_value() -> None:
    # equally spaced points 0, 1, 2, 3: CR = (2 * 2) / (1 * 3) = 4/3
    # (Hartley & Zisserman eq. 2.18 with |x_i x_j| signed distances)
    assert float(cross_ratio([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0])) == pytest.approx(
        4 / 3
    )


def test_cross_ratio_needs_collinear_points() -> None:
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        cross_ratio([0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 0.0])


def test_cross_ratio_bad_shape() -> None:
    with pytest.raises(InvalidInputError, match=r"expected a of shape \(\.\.\., 2\), got \(3,\)"):
        cross_ratio([0.0, 0.0, 1.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0])


def test_nan_rejected() -> None:
    with pytest.raises(InvalidInputError, match="NaN"):
        to_homogeneous([np.nan, 1.0])


_coords = st.floats(-50, 50, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    t=st.lists(st.floats(-20, 20), min_size=4, max_size=4, unique=True),
    h=st.lists(st.floats(-0.5, 0.5), min_size=8, max_size=8),
)
def test_cross_ratio_invariant_under_homography(t: list[float], h: list[float]) -> None:
    ts = np.sort(np.array(t))
    if np.min(np.diff(ts)) < 0.5:
        return
    origin, direction = np.array([1.0, 2.0]), np.array([0.6, 0.8])
    pts = origin + ts[:, None] * direction
    H = np.eye(3) + np.array([*h, 0.0]).reshape(3, 3) * np.array(
        [[1, 1, 1], [1, 1, 1], [0.01, 0.01, 0]]
    )
    if abs(np.linalg.det(H)) < 0.1:
        return
    mapped = apply_homography(H, pts)
    w = (np.c_[pts, np.ones(4)] @ H.T)[:, 2]
    if np.any(np.abs(w) < 0.05) or np.any(np.sign(w) != np.sign(w[0])):
        return  # the line crosses the vanishing line between the points: order changes
    before = float(cross_ratio(*pts))
    after = float(cross_ratio(*mapped))
    assert after == pytest.approx(before, rel=1e-7)
