"""Homography (normalised DLT) and camera resection, cross-checked against OpenCV."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import (
    apply_homography,
    decompose_projection_matrix,
    estimate_homography,
    estimate_projection_matrix,
    intrinsic_matrix,
    project_points,
    projection_matrix,
    rvec_to_matrix,
)


def random_h(rng: np.random.Generator) -> np.ndarray:
    H = np.eye(3) + rng.normal(scale=0.2, size=(3, 3)) * [[1, 1, 50], [1, 1, 50], [1e-3, 1e-3, 0]]
    return H / H[2, 2]


def test_homography_matches_opencv_findhomography() -> None:
    """Cross-check: cv2.findHomography (method 0 = least squares on all points)."""
    rng = np.random.default_rng(20)
    for _ in range(20):
        H = random_h(rng)
        src = rng.uniform(0, 640, size=(30, 2))
        dst = apply_homography(H, src) + rng.normal(scale=0.2, size=(30, 2))
        ours = estimate_homography(src, dst)
        ref = cv2.findHomography(src, dst, 0)[0]
        # compare by the mapping they define (both fit the same noisy data)
        np.testing.assert_allclose(
            apply_homography(ours, src), apply_homography(ref, src), atol=0.05
        )
        np.testing.assert_allclose(apply_homography(ours, src), apply_homography(H, src), atol=0.5)


def test_homography_exact_four_points_and_batch() -> None:
    rng = np.random.default_rng(21)
    H = random_h(rng)
    src = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 80.0], [0.0, 80.0]])
    np.testing.assert_allclose(
        estimate_homography(src, apply_homography(H, src)), H, rtol=1e-9, atol=1e-12
    )
    Hs = np.stack([random_h(rng) for _ in range(5)])
    srcs = rng.uniform(0, 100, size=(5, 8, 2))
    dsts = np.stack([apply_homography(Hs[i], srcs[i]) for i in range(5)])
    np.testing.assert_allclose(estimate_homography(srcs, dsts), Hs, rtol=1e-7, atol=1e-9)


def test_homography_collinear_detected() -> None:
    src = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0], [4.0, 4.0]])
    with pytest.raises(DegenerateConfigurationError, match="collinear"):
        estimate_homography(src, src + 1.0)
    four = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    with pytest.raises(DegenerateConfigurationError, match="three of the four"):
        estimate_homography(four, four * 2.0)


def test_homography_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="at least 4"):
        estimate_homography(np.zeros((3, 2)), np.zeros((3, 2)))
    with pytest.raises(InvalidInputError, match="same shape"):
        estimate_homography(np.zeros((5, 2)), np.zeros((6, 2)))
    with pytest.raises(InvalidInputError, match=r"expected H of shape"):
        apply_homography(np.eye(2), [[1.0, 2.0]])


def test_apply_homography_to_vanishing_line_is_nan() -> None:
    H = np.array([[1.0, 0, 0], [0, 1, 0], [1.0, 0, 0]])  # maps x = 0 to infinity
    out = apply_homography(H, [[0.0, 5.0], [1.0, 1.0]])
    assert np.isnan(out[0]).all()
    np.testing.assert_allclose(out[1], [1.0, 1.0])


def test_resection_recovers_camera() -> None:
    rng = np.random.default_rng(22)
    K = intrinsic_matrix(820.0, 800.0, 330.0, 250.0, 2.0)
    R = rvec_to_matrix([0.2, -0.1, 0.3])
    t = np.array([0.1, -0.3, 6.0])
    X = rng.uniform(-1, 1, size=(20, 3))
    uv = project_points(X, K, R, t).uv
    P = estimate_projection_matrix(X, uv)
    np.testing.assert_allclose(
        P / P[2, 3], projection_matrix(K, R, t) / t[2], rtol=1e-8, atol=1e-10
    )
    Kd, Rd, td = decompose_projection_matrix(P)
    np.testing.assert_allclose(Kd, K, rtol=1e-7)
    np.testing.assert_allclose(Rd, R, atol=1e-9)
    np.testing.assert_allclose(td, t, atol=1e-8)
    # depth convention: third row of P X is the depth in front of the camera
    depth = (np.c_[X, np.ones(20)] @ P.T)[:, 2]
    np.testing.assert_allclose(depth, (X @ R.T + t)[:, 2], rtol=1e-8)


def test_resection_noisy_least_squares() -> None:
    rng = np.random.default_rng(23)
    K = intrinsic_matrix(800.0, 800.0, 320.0, 240.0)
    R = rvec_to_matrix([0.1, 0.2, 0.0])
    t = np.array([0.0, 0.0, 5.0])
    X = rng.uniform(-1, 1, size=(200, 3))
    uv = project_points(X, K, R, t).uv + rng.normal(scale=0.5, size=(200, 2))
    Kd, _, _ = decompose_projection_matrix(estimate_projection_matrix(X, uv))
    np.testing.assert_allclose(np.diag(Kd)[:2], [800.0, 800.0], rtol=0.02)


def test_resection_coplanar_detected() -> None:
    rng = np.random.default_rng(24)
    X = np.c_[rng.uniform(-1, 1, size=(10, 2)), np.zeros(10)]
    uv = project_points(X, intrinsic_matrix(500, 500, 0, 0), t=[0.0, 0.0, 4.0]).uv
    with pytest.raises(DegenerateConfigurationError, match="coplanar"):
        estimate_projection_matrix(X, uv)


def test_resection_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="at least 6"):
        estimate_projection_matrix(np.zeros((5, 3)), np.zeros((5, 2)))
    with pytest.raises(InvalidInputError, match="as many"):
        estimate_projection_matrix(np.zeros((7, 3)), np.zeros((6, 2)))
    with pytest.raises(InvalidInputError, match="NaN"):
        estimate_projection_matrix(np.full((7, 3), np.nan), np.zeros((7, 2)))


def test_masked_normalization_is_each_sets_own() -> None:
    """A padded batch normalised with its mask: each set as alone, the padding zero."""
    from imageform._backend import namespace
    from imageform.geometry._normalize import similarity_normalization

    rng = np.random.default_rng(3)
    sizes = np.array([5, 9, 4])
    sets = [rng.normal(size=(n, 2)) * 50 + 300 for n in sizes]
    mask = np.arange(9)[None, :] < sizes[:, None]
    padded = np.zeros((3, 9, 2))
    padded[mask] = np.concatenate(sets)
    xp = namespace(padded)
    normed, T = similarity_normalization(padded, xp, mask=mask)
    for k, p in enumerate(sets):
        own, T_own = similarity_normalization(p, xp)
        np.testing.assert_array_equal(normed[k, : sizes[k]], own)
        np.testing.assert_array_equal(T[k], T_own)
        assert np.all(normed[k, sizes[k] :] == 0)
        # Hartley's normalisation: centred, mean distance sqrt(2)
        np.testing.assert_allclose(own.mean(axis=0), 0, atol=1e-13)
        np.testing.assert_allclose(np.linalg.norm(own, axis=1).mean(), np.sqrt(2), rtol=1e-14)
