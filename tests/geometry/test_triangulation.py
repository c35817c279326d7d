"""Tests of imageform.geometry.triangulation (triangulate_points).

Sources of truth: synthetic cameras and points (noise-free → exact); a Monte-Carlo estimate
of the covariance; OpenCV 5.0 ``triangulatePoints`` (linear, two views) as a labelled
cross-check.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import triangulate_points
from imageform.geometry.calibration_refine import rodrigues
from tests.helpers import to_backend

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def cameras(V: int = 3) -> np.ndarray:
    Ps = []
    for v in range(V):
        R = rodrigues(np.array([[0.0, -0.15 * v, 0.02 * v]]))[0]
        C = np.array([1.0 * v, 0.1 * v, 0.0])
        Ps.append(K @ np.hstack([R, (-R @ C)[:, None]]))
    return np.stack(Ps)


def project(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    h = np.einsum("vij,mj->vmi", P[:, :, :3], X) + P[:, None, :, 3]
    return h[..., :2] / h[..., 2:]


def points(M: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-1, 2, M), rng.uniform(-1, 1, M), rng.uniform(6, 10, M)]


def test_noise_free_exact() -> None:
    P, X = cameras(3), points(40)
    res = triangulate_points(P, project(P, X))
    np.testing.assert_allclose(res.points, X, atol=1e-9)
    assert res.valid.all() and res.rms.max() < 1e-8
    assert res.covariance.shape == (40, 3, 3)
    lin = triangulate_points(P, project(P, X), refine=False)
    np.testing.assert_allclose(lin.points, X, atol=1e-8)


def test_refinement_reduces_reprojection_error() -> None:
    P, X = cameras(4), points(200, seed=1)
    uv = project(P, X) + np.random.default_rng(2).normal(0, 1.0, (4, 200, 2))
    lin = triangulate_points(P, uv, refine=False)
    ref = triangulate_points(P, uv)
    assert np.all(ref.rms <= lin.rms + 1e-12) and ref.rms.mean() < lin.rms.mean()


def test_covariance_matches_monte_carlo() -> None:
    P, X = cameras(2), points(1, seed=3)
    rng = np.random.default_rng(4)
    clean = project(P, X)
    est = np.stack(
        [
            triangulate_points(P, clean + rng.normal(0, 0.5, clean.shape)).points[0]
            for _ in range(400)
        ]
    )
    cov = triangulate_points(P, clean, sigma=0.5).covariance[0]
    np.testing.assert_allclose(np.sqrt(np.diag(np.cov(est.T))), np.sqrt(np.diag(cov)), rtol=0.15)


def test_missing_observations_as_nan() -> None:
    P, X = cameras(3), points(10, seed=5)
    uv = project(P, X)
    uv[0, :5] = np.nan  # view 0 misses the first five points
    res = triangulate_points(P, uv)
    np.testing.assert_allclose(res.points, X, atol=1e-9)


def test_cross_check_opencv_triangulate_points() -> None:
    cv2 = pytest.importorskip("cv2")
    P, X = cameras(2), points(50, seed=6)
    uv = project(P, X) + np.random.default_rng(7).normal(0, 0.3, (2, 50, 2))
    h = cv2.triangulatePoints(P[0], P[1], uv[0].T.copy(), uv[1].T.copy())
    cvX = (h[:3] / h[3]).T
    lin = triangulate_points(P, uv, refine=False)
    # both linear DLT; row scaling differs, so agreement to the noise level only
    np.testing.assert_allclose(lin.points, cvX, rtol=2e-3, atol=5e-3)
    h0 = cv2.triangulatePoints(P[0], P[1], *(project(P, X)[k].T.copy() for k in range(2)))
    np.testing.assert_allclose(
        triangulate_points(P, project(P, X)).points, (h0[:3] / h0[3]).T, atol=1e-7
    )


def test_point_behind_a_camera_is_invalid() -> None:
    P, X = cameras(2), points(3, seed=8)
    uv = project(P, X)
    Xb = np.array([[0.3, 0.2, -5.0]])  # behind both cameras: pixels still exist
    res = triangulate_points(P, np.concatenate([uv, project(P, Xb)], axis=1))
    assert res.valid.tolist() == [True, True, True, False]


def test_zero_and_small_baseline() -> None:
    """No baseline: no finite point (NaN, invalid); a tiny one: a huge depth uncertainty."""
    P = cameras(1)
    X = points(2, seed=10)
    res = triangulate_points(np.concatenate([P, P]), project(np.concatenate([P, P]), X))
    assert not res.valid.any() and np.isnan(res.points).all() and np.isinf(res.covariance).all()
    P2 = P.copy()
    P2[0, :, 3] -= K @ [1e-3, 0.0, 0.0]  # 1 mm baseline
    Ps = np.concatenate([P, P2])
    res = triangulate_points(Ps, project(Ps, X))
    sd = np.sqrt(np.diagonal(res.covariance, axis1=1, axis2=2))
    assert res.valid.all() and np.all(sd[:, 2] > 10.0)  # metres, at 6-10 m depth


@settings(max_examples=25, deadline=None)
@given(x=st.floats(-2, 2), y=st.floats(-2, 2), z=st.floats(2.0, 50.0), views=st.integers(2, 5))
def test_property_project_triangulate_round_trip(x: float, y: float, z: float, views: int) -> None:
    P = cameras(views)
    X = np.array([[x, y, z]])
    res = triangulate_points(P, project(P, X))
    np.testing.assert_allclose(res.points, X, rtol=1e-7, atol=1e-7)


def test_float32_in_float32_out() -> None:
    P, X = cameras(2), points(5, seed=11)
    res = triangulate_points(P, project(P, X).astype(np.float32))
    assert res.points.dtype == res.covariance.dtype == np.float32
    np.testing.assert_allclose(res.points, X, rtol=1e-4)


def test_backends(xp_name: str) -> None:
    P, X = cameras(2), points(5, seed=9)
    res = triangulate_points(to_backend(P, xp_name), to_backend(project(P, X), xp_name))
    np.testing.assert_allclose(res.points, X, atol=1e-8)


def test_bad_inputs() -> None:
    P, X = cameras(2), points(4)
    uv = project(P, X)
    with pytest.raises(InvalidInputError, match="same V"):
        triangulate_points(P, uv[:1])
    with pytest.raises(InvalidInputError, match="at least 2 views"):
        triangulate_points(P[:1], uv[:1])
    with pytest.raises(InvalidInputError, match="inf"):
        triangulate_points(P, np.where(uv > 0, np.inf, uv))
    bad = uv.copy()
    bad[1, 2] = np.nan
    with pytest.raises(DegenerateConfigurationError, match="fewer than 2 views"):
        triangulate_points(P, bad)
    with pytest.raises(DegenerateConfigurationError, match="singular"):
        triangulate_points(np.zeros((2, 3, 4)), uv)
    with pytest.raises(InvalidInputError, match="sigma"):
        triangulate_points(P, uv, sigma=0.0)
