"""Tests of imageform.geometry.pnp (solve_pnp) and pnp_ransac (solve_pnp_ransac).

Sources of truth: synthetic poses (noise-free → exact); OpenCV 5.0 ``solvePnP``
(SOLVEPNP_ITERATIVE) on the same noisy points as a labelled cross-check.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import solve_pnp, solve_pnp_ransac
from imageform.geometry.calibration_refine import rodrigues
from imageform.geometry.distortion import BrownConrady, project_points_distorted
from imageform.geometry.pnp import _refine_pose_np, refine_pose
from tests.helpers import to_backend

K = np.array([[800.0, 0.0, 320.0], [0.0, 790.0, 240.0], [0.0, 0.0, 1.0]])


def make(B: int, N: int, seed: int = 0, planar: bool = False, noise: float = 0.0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (B, N, 3))
    if planar:
        X[..., 2] = 0.0
    rv = rng.normal(0, 0.5, (B, 3))
    t = np.c_[rng.uniform(-0.5, 0.5, (B, 2)), rng.uniform(4, 8, B)]
    R = rodrigues(rv)
    cam = X @ np.swapaxes(R, 1, 2) + t[:, None]
    uv = cam[..., :2] / cam[..., 2:] * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]
    return X, uv + rng.normal(0, noise, uv.shape), R, t


@pytest.mark.parametrize("planar", [False, True])
def test_noise_free_batch_is_exact(planar: bool) -> None:
    X, uv, R, t = make(50, 12, planar=planar)
    res = solve_pnp(X, uv, K)
    np.testing.assert_allclose(res.R, R, atol=1e-9)
    np.testing.assert_allclose(res.tvec, t, atol=1e-8)
    assert res.valid.all() and res.rms.max() < 1e-6
    lin = solve_pnp(X, uv, K, refine=False)
    np.testing.assert_allclose(lin.tvec, t, atol=1e-8)


def test_batch_shapes() -> None:
    X, uv, _R, _t = make(6, 10)
    res = solve_pnp(X.reshape(2, 3, 10, 3), uv.reshape(2, 3, 10, 2), K)
    assert res.rvec.shape == (2, 3, 3) and res.R.shape == (2, 3, 3, 3)
    assert res.rms.shape == (2, 3) and res.inliers.shape == (2, 3, 10)
    one = solve_pnp(X[0], uv[0], K)
    assert one.tvec.shape == (3,) and one.valid.shape == ()


def test_cross_check_opencv_solvepnp_with_noise() -> None:
    cv2 = pytest.importorskip("cv2")
    X, uv, _R, _t = make(20, 30, seed=2, noise=0.5)
    res = solve_pnp(X, uv, K)
    for b in range(20):
        ok, rv, tv = cv2.solvePnP(X[b], uv[b], K, None, flags=cv2.SOLVEPNP_ITERATIVE)
        assert ok
        np.testing.assert_allclose(res.rvec[b], rv.ravel(), atol=1e-6)
        np.testing.assert_allclose(res.tvec[b], tv.ravel(), atol=1e-5)


def test_with_distortion() -> None:
    d = BrownConrady(k1=-0.2, k2=0.05, p1=0.001)
    X, _uv, R, t = make(1, 20, seed=4)
    uv, _ = project_points_distorted(X[0], K, R[0], t[0], d)
    res = solve_pnp(X[0], uv, K, d)
    np.testing.assert_allclose(res.tvec, t[0], atol=1e-8)


def test_cheirality_never_a_mirrored_pose() -> None:
    """Points whose pixels come from a camera *behind* them: the pose found must be in front."""
    X, uv, _R, _t = make(30, 15, seed=7, noise=1.0)
    res = solve_pnp(X, uv, K)
    cam = np.einsum("bij,bnj->bni", res.R, X) + res.tvec[:, None]
    assert np.all(cam[..., 2][res.valid] > 0)
    # a mirrored problem: flip the points through the camera centre -> depth negative
    Xm = -X[:1]
    Xm[..., 2] -= 0.0
    bad = solve_pnp(Xm, uv[:1], K)
    cam = np.einsum("bij,bnj->bni", bad.R, Xm) + bad.tvec[:, None]
    assert (not bool(bad.valid[0])) or np.all(cam[..., 2] > 0)


def test_kernel_matches_numpy_twin() -> None:
    X, uv, _R, _t = make(40, 20, seed=9, noise=0.7)
    lin = solve_pnp(X, uv, K, refine=False)
    w = np.ones(X.shape[:2])
    w[:, :3] = 0.0
    Rk, tk, rk = refine_pose(lin.R.copy(), lin.tvec.copy(), X, uv, K, w, 20)
    Rn, tn, rn = _refine_pose_np(lin.R.copy(), lin.tvec.copy(), X, uv, K, w, 20, 1e-8)
    np.testing.assert_allclose(Rk, Rn, atol=1e-9)
    np.testing.assert_allclose(tk, tn, atol=1e-9)
    np.testing.assert_allclose(rk, rn, rtol=1e-9)


@settings(max_examples=25, deadline=None)
@given(
    rv=st.lists(st.floats(-1.2, 1.2), min_size=3, max_size=3),
    tz=st.floats(3.0, 20.0),
)
def test_property_round_trip(rv: list[float], tz: float) -> None:
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (12, 3))
    R = rodrigues(np.asarray([rv]))[0]
    t = np.array([0.1, -0.2, tz])
    cam = X @ R.T + t
    uv = cam[:, :2] / cam[:, 2:] * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]
    res = solve_pnp(X, uv, K)
    np.testing.assert_allclose(res.R, R, atol=1e-7)
    np.testing.assert_allclose(res.tvec, t, atol=1e-6 * tz)


def test_ransac_rejects_outliers() -> None:
    X, uv, _R, t = make(1, 60, seed=11, noise=0.3)
    X, uv = X[0], uv[0].copy()
    rng = np.random.default_rng(1)
    out = rng.choice(60, 18, replace=False)
    uv[out] += rng.uniform(30, 80, (18, 2)) * rng.choice([-1, 1], (18, 2))
    res = solve_pnp_ransac(X, uv, K, threshold=2.0)
    assert not res.inliers[out].any() and res.inliers.sum() >= 40
    np.testing.assert_allclose(res.tvec, t[0], atol=0.02)
    plain = solve_pnp(X, uv, K)
    assert np.abs(plain.tvec - t[0]).max() > np.abs(res.tvec - t[0]).max()


def test_ransac_planar() -> None:
    X, uv, _R, t = make(1, 30, seed=12, planar=True)
    uv = uv[0].copy()
    uv[:5] += 40.0
    res = solve_pnp_ransac(X[0], uv, K)
    assert res.inliers.sum() == 25 and bool(res.valid)
    np.testing.assert_allclose(res.tvec, t[0], atol=1e-8)


def test_backends(xp_name: str) -> None:
    X, uv, _R, t = make(3, 10, seed=13)
    res = solve_pnp(to_backend(X, xp_name), to_backend(uv, xp_name), to_backend(K, xp_name))
    np.testing.assert_allclose(res.tvec, t, atol=1e-8)


def test_float32_and_int_inputs() -> None:
    X, uv, _R, t = make(2, 10, seed=14)
    res = solve_pnp(X.astype(np.float32), uv.astype(np.float32), K)
    np.testing.assert_allclose(res.tvec, t, atol=1e-3)
    assert res.tvec.dtype == res.R.dtype == res.rms.dtype == np.float32  # float32 in, out
    res = solve_pnp(np.round(X * 1000).astype(int), uv, K)  # integers: float64
    assert res.tvec.dtype == np.float64


def test_bad_inputs() -> None:
    X, uv, _R, _t = make(1, 10)
    with pytest.raises(InvalidInputError, match="same leading shape"):
        solve_pnp(X[0], uv[0, :9], K)
    with pytest.raises(InvalidInputError, match=r"upper.triangular"):
        solve_pnp(X[0], uv[0], K.T)
    with pytest.raises(InvalidInputError, match="NaN"):
        solve_pnp(np.full((10, 3), np.nan), uv[0], K)
    with pytest.raises(DegenerateConfigurationError, match="at least 6 points"):
        solve_pnp(X[0, :5], uv[0, :5], K)
    Xp = X[0].copy()
    Xp[:, 2] = 0
    with pytest.raises(DegenerateConfigurationError, match="at least 4 points"):
        solve_pnp(Xp[:3], uv[0, :3], K)
    line = np.c_[np.linspace(0, 1, 10), np.zeros(10), np.zeros(10)]
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        solve_pnp(line, uv[0], K)
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        solve_pnp_ransac(line, uv[0], K)
    with pytest.raises(InvalidInputError, match="distortion"):
        solve_pnp(X[0], uv[0], K, distortion="k1")
    with pytest.raises(InvalidInputError, match="one problem"):
        solve_pnp_ransac(X, uv, K)
    with pytest.raises(InvalidInputError, match="confidence"):
        solve_pnp_ransac(X[0], uv[0], K, confidence=1.0)
    with pytest.raises(InvalidInputError, match="threshold"):
        solve_pnp_ransac(X[0], uv[0], K, threshold=-1.0)
