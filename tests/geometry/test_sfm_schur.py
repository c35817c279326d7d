"""Structure from motion's faster paths: bundle adjustment's numba kernels against their
array twins and the dense reduced camera system, descriptor matching from one matrix product
against the two-product path it replaced and OpenCV's brute-force matcher, on real C3VD SIFT
descriptors (tests/data/endo, CC BY 4.0)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform._backend import numba_enabled
from imageform.errors import InvalidInputError
from imageform.geometry import bundle_adjust, detect_features, match_features
from imageform.geometry import sfm as sfm_mod
from imageform.geometry.rotations import rvec_to_matrix

ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"
PATHS = [False, pytest.param(True, marks=pytest.mark.skipif(not numba_enabled(), reason="numba"))]


def _views(seed: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Views (camera, point) of 40 points in 6 cameras, one point seen twice in camera 2."""
    rng = np.random.default_rng(seed)
    nc, npt = 6, 40
    cam: list[int] = []
    pt: list[int] = []
    for p in range(npt):
        k = int(rng.integers(1, nc + 1))
        cam += rng.choice(nc, k, replace=False).tolist()
        pt += [p] * k
    p2 = pt[cam.index(2)]
    cam.append(2)  # a track that holds a frame twice
    pt.append(p2)
    order = rng.permutation(len(cam))
    return np.array(cam)[order], np.array(pt)[order], nc, npt


@pytest.mark.parametrize("kernel", PATHS)
def test_reduced_camera_system_is_the_dense_product(kernel: bool) -> None:
    cam, pt, nc, npt = _views(0)
    rng = np.random.default_rng(1)
    W = rng.normal(size=(cam.size, 6, 3))
    Vinv = rng.normal(size=(npt, 3, 3))
    Vinv = Vinv @ Vinv.transpose(0, 2, 1) + np.eye(3)
    Y = W @ Vinv[pt]
    # the definition: W V^-1 W^T with W (6 nc, 3 npt) dense, V^-1 block diagonal
    Wd = np.zeros((6 * nc, 3 * npt))
    for o in range(cam.size):
        Wd[6 * cam[o] : 6 * cam[o] + 6, 3 * pt[o] : 3 * pt[o] + 3] += W[o]
    Vd = np.zeros((3 * npt, 3 * npt))
    for p in range(npt):
        Vd[3 * p : 3 * p + 3, 3 * p : 3 * p + 3] = Vinv[p]
    want = Wd @ Vd @ Wd.T
    got = sfm_mod._camera_pairs(cam, pt, nc, npt, chunk=7, kernel=kernel)(Y, W)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    np.testing.assert_allclose(got, got.T, rtol=0, atol=1e-12 * np.abs(want).max())
    # no free camera, no view: an empty system
    none = sfm_mod._camera_pairs(np.zeros(0, np.int64), np.zeros(0, np.int64), 0, 3, kernel=kernel)
    assert none(np.zeros((0, 6, 3)), np.zeros((0, 6, 3))).shape == (0, 0)


def _problem(lens: bool) -> tuple[tuple[Any, ...], Any]:
    """A bundle adjustment of 5 cameras and 80 points, perturbed, camera 0 fixed."""
    rng = np.random.default_rng(2)
    K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
    n, m = 5, 80
    R = np.stack([np.asarray(rvec_to_matrix([0.02 * i, 0.05 * i, 0])) for i in range(n)])
    t = np.array([[-0.2 * i, 0.01 * i, 0] for i in range(n)], float)
    X = rng.uniform([-1, -1, 4], [1, 1, 6], (m, 3))
    keep = rng.random((n, m)) < 0.8
    ci, pi = np.nonzero(keep)
    Xc = np.einsum("mij,mj->mi", R[ci], X[pi]) + t[ci]
    uv = (Xc @ K.T)[:, :2] / Xc[:, 2:] + rng.normal(0, 0.3, (ci.size, 2))
    R0 = np.stack([np.asarray(rvec_to_matrix([0.01, 0.01, -0.01])) @ r for r in R])
    R0[0] = R[0]
    t0 = t + rng.normal(0, 0.01, t.shape) * (np.arange(n) > 0)[:, None]
    X0 = X + rng.normal(0, 0.02, X.shape)
    fixed = np.arange(n) == 0
    A = np.eye(2) + rng.normal(0, 0.3, (ci.size, 2, 2)) if lens else None
    return (K, R0, t0, X0, ci, pi, uv, fixed, 2.0), A


@pytest.mark.skipif(not numba_enabled(), reason="numba")
@pytest.mark.parametrize("lens", [False, True])
def test_normal_equations_kernel_matches_the_array_path(lens: bool) -> None:
    (K, R, t, X, ci, pi, uv, fixed, delta), A = _problem(lens)
    for iters, tol in ((1, 1e-12), (20, 1e-9)):
        a = sfm_mod._schur_lm(K, R, t, X, ci, pi, uv, fixed, delta, iters, A=A, kernel=False)
        k = sfm_mod._schur_lm(K, R, t, X, ci, pi, uv, fixed, delta, iters, A=A, kernel=True)
        for x, y in zip(a, k, strict=True):
            np.testing.assert_allclose(y, x, rtol=0, atol=tol * max(1.0, np.abs(x).max()))


@pytest.mark.parametrize("kernel", PATHS)
def test_focal_length_refined_with_the_poses(kernel: bool) -> None:
    """Noiseless views of a 500 px camera, started at 650 px: 500 px found, the views fit.

    The focal length's derivative (u - c) / f against central differences of the
    projection, then both paths (numba and arrays) find the same f.
    """
    (K, R, t, X, ci, pi, _, fixed, _), _ = _problem(False)
    Xc = np.einsum("mij,mj->mi", R[ci], X[pi]) + t[ci]
    uv = (Xc @ K.T)[:, :2] / Xc[:, 2:]  # the perturbed scene's exact views
    h = 1e-3
    Kp, Km = K.copy(), K.copy()
    Kp[:2, :2] *= (500 + h) / 500
    Km[:2, :2] *= (500 - h) / 500
    num = ((Xc @ Kp.T)[:, :2] / Xc[:, 2:] - (Xc @ Km.T)[:, :2] / Xc[:, 2:]) / (2 * h)
    np.testing.assert_allclose(num, (uv - K[:2, 2]) / 500, rtol=0, atol=1e-9)
    K0 = K.copy()
    K0[:2, :2] *= 1.3
    R1, t1, X1, K1, _ = sfm_mod._schur_lm(
        K0, R, t, X, ci, pi, uv, fixed, 0.0, 100, kernel=kernel, focal=True
    )
    assert K1[0, 0] == pytest.approx(500.0, rel=1e-4) and K1[1, 1] == K1[0, 0]
    np.testing.assert_array_equal(K1[:2, 2], K[:2, 2])  # the principal point held
    Xc1 = np.einsum("mij,mj->mi", R1[ci], X1[pi]) + t1[ci]
    assert np.abs((Xc1 @ K1.T)[:, :2] / Xc1[:, 2:] - uv).max() < 1e-3
    # without focal: K returned as given, and the views do not fit
    R2, t2, X2, K2, _ = sfm_mod._schur_lm(K0, R, t, X, ci, pi, uv, fixed, 0.0, 100, kernel=kernel)
    np.testing.assert_array_equal(K2, K0)
    Xc2 = np.einsum("mij,mj->mi", R2[ci], X2[pi]) + t2[ci]
    assert np.abs((Xc2 @ K0.T)[:, :2] / Xc2[:, 2:] - uv).max() > 0.1


def _old_match(a: np.ndarray, b: np.ndarray, ratio: float = 0.8) -> np.ndarray:
    """``match_features`` before: the mutual check from a second product ``b a^T``."""
    a, b = a.astype(np.float32), b.astype(np.float32)
    na, nb = (a * a).sum(1), (b * b).sum(1)
    d2 = a @ b.T
    d2 *= -2.0
    d2 += nb[None, :]
    rows = np.arange(a.shape[0])
    best = np.argmin(d2, axis=1)
    d1 = np.maximum(d2[rows, best] + na, 0.0)
    d2[rows, best] = np.inf
    d2nd = np.maximum(d2.min(axis=1) + na, 0.0)
    keep = d1 < (ratio * ratio) * d2nd
    back = b @ a.T
    back *= -2.0
    back += na[None, :]
    keep &= np.argmin(back, axis=1)[best] == rows
    idx = np.flatnonzero(keep)
    return np.column_stack([idx, best[idx]]).astype(np.int64)


@functools.cache
def _endo_descriptors(contrast: float) -> list[np.ndarray]:
    pytest.importorskip("cv2")
    from imageform.geometry import field_of_view_mask
    from imageform.io import read_image

    frames = [np.asarray(read_image(ENDO / f"c3vdv3_f{i:03d}.jpg")) for i in (0, 8, 16, 24)]
    mask = field_of_view_mask(frames)
    return [detect_features(f, mask=mask, contrast_threshold=contrast).descriptors for f in frames]


@pytest.mark.parametrize("contrast", [0.01, 0.005])
def test_one_product_matches_as_the_two_did_on_real_sift(contrast: float) -> None:
    """SIFT's descriptors are integers of norm about 512: every distance is exact in float32
    and the column-wise nearest of one product is the row-wise nearest of the other."""
    desc = _endo_descriptors(contrast)
    assert all(np.array_equal(d, np.round(d)) for d in desc)
    assert max(float(np.max((d * d).sum(1))) for d in desc) < 2.0**24
    for i, j in ((0, 1), (0, 2), (1, 3), (2, 3)):
        got = match_features(desc[i], desc[j])
        assert got.shape[0] > 30
        assert np.array_equal(got, _old_match(desc[i], desc[j]))
        assert np.array_equal(
            match_features(desc[j], desc[i], ratio=0.6), _old_match(desc[j], desc[i], 0.6)
        )


def test_matches_are_opencv_brute_force_ratio_and_cross_check() -> None:
    """A peer: ``cv2.BFMatcher`` (L2), Lowe's ratio on its two nearest, and the mutual check
    as the nearest of ``b`` in ``a``."""
    cv2 = pytest.importorskip("cv2")
    a, b = _endo_descriptors(0.01)[:2]
    bf = cv2.BFMatcher(cv2.NORM_L2)
    back = {m.queryIdx: m.trainIdx for m in bf.match(b, a)}
    want = {
        (m.queryIdx, m.trainIdx)
        for m, n in bf.knnMatch(a, b, k=2)
        if m.distance < 0.8 * n.distance and back[m.trainIdx] == m.queryIdx
    }
    got = {(int(i), int(j)) for i, j in match_features(a, b)}
    assert len(got) > 50
    # the same set but for a match on the ratio's edge (OpenCV's distances in float32 roots)
    assert len(got ^ want) <= 0.005 * len(got)


def test_match_features_bad_inputs() -> None:
    a = np.zeros((5, 8), np.float32)
    with pytest.raises(InvalidInputError):
        match_features(a[0], a)
    with pytest.raises(InvalidInputError):
        match_features(a, np.full((5, 8), np.nan))
    with pytest.raises(InvalidInputError):
        match_features(a, a, ratio=0.0)
    assert match_features(a[:1], a).shape == (0, 2)


def test_bundle_adjust_bad_inputs() -> None:
    (K, R, t, X, ci, pi, uv, _, _), _ = _problem(False)
    with pytest.raises(InvalidInputError, match="pt_idx"):
        bundle_adjust(K, R, t, X, ci, np.where(pi == 0, X.shape[0], pi), uv)
    with pytest.raises(InvalidInputError, match="cam_idx"):
        bundle_adjust(K, R, t, X, ci - 1, pi, uv)
    with pytest.raises(InvalidInputError, match="cam_idx"):
        bundle_adjust(K, R, t, X, ci.astype(float), pi, uv)
    with pytest.raises(InvalidInputError, match=r"uv \(M, 2\)"):
        bundle_adjust(K, R, t, X, ci, pi, uv[:-1])
    with pytest.raises(InvalidInputError, match=r"K \(3, 3\)"):
        bundle_adjust(K[:2], R, t, X, ci, pi, uv)
    with pytest.raises(InvalidInputError, match=r"t \(n, 3\)"):
        bundle_adjust(K, R, t[:-1], X, ci, pi, uv)


def test_radial_lens_derivatives_against_central_differences() -> None:
    """COLMAP's SIMPLE_RADIAL (``_radial``): the lens's map A, d/df and d/dk1 as the
    projection's central differences (a point's and a pose's derivatives go through A)."""
    (K, R, t, X, ci, pi, _, _, _), _ = _problem(False)
    k1 = -0.2

    def project(K: np.ndarray, k1: float, X: np.ndarray) -> np.ndarray:
        p, _ = sfm_mod._project_obs(K, R[ci], t[ci], X[pi])
        return sfm_mod._radial(K, k1, p)[0]

    _, A, du_df, du_dk = sfm_mod._radial(K, k1, sfm_mod._project_obs(K, R[ci], t[ci], X[pi])[0])
    h = 1e-6
    num_k = (project(K, k1 + h, X) - project(K, k1 - h, X)) / (2 * h)
    np.testing.assert_allclose(du_dk, num_k, rtol=0, atol=1e-6 * np.abs(du_dk).max())
    hf = 1e-3
    Kp, Km = K.copy(), K.copy()
    Kp[:2, :2] *= (K[0, 0] + hf) / K[0, 0]
    Km[:2, :2] *= (K[0, 0] - hf) / K[0, 0]
    num_f = (project(Kp, k1, X) - project(Km, k1, X)) / (2 * hf)
    np.testing.assert_allclose(du_df, num_f, rtol=0, atol=1e-8)
    # d u / d X = A (d pinhole / d X): every view of point 0, each coordinate
    views = np.flatnonzero(pi == 0)
    Xc = np.einsum("mij,mj->mi", R[ci], X[pi]) + t[ci]
    for j in range(3):
        Xp, Xm = X.copy(), X.copy()
        Xp[0, j] += 1e-6
        Xm[0, j] -= 1e-6
        num = (project(K, k1, Xp) - project(K, k1, Xm))[views] / 2e-6
        for v, o in enumerate(views):
            x, y, z = Xc[o]
            f = K[0, 0]
            Jp = np.array([[f / z, 0, -f * x / z**2], [0, f / z, -f * y / z**2]]) @ R[ci[o]]
            np.testing.assert_allclose(A[o] @ Jp[:, j], num[v], rtol=0, atol=1e-6)


@pytest.mark.parametrize("kernel", PATHS)
def test_focal_length_and_radial_term_refined_with_the_poses(kernel: bool) -> None:
    """Views through a barrel lens (k1 -0.2, 500 px), started at 650 px and k1 0: both
    found (the views fit to 1e-3 px); the bound refuses a k1 that folds the image."""
    (K, R, t, X, ci, pi, _, fixed, _), _ = _problem(False)
    p, _ = sfm_mod._project_obs(K, R[ci], t[ci], X[pi])
    uv = sfm_mod._radial(K, -0.2, p)[0]
    K0 = K.copy()
    K0[:2, :2] *= 1.3
    R1, t1, X1, K1, k1 = sfm_mod._schur_lm(
        K0, R, t, X, ci, pi, uv, fixed, 0.0, 200, kernel=kernel, focal=True, radial=0.0
    )
    assert K1[0, 0] == pytest.approx(500.0, rel=1e-5) and k1 == pytest.approx(-0.2, abs=1e-5)
    np.testing.assert_array_equal(K1[:2, 2], K[:2, 2])
    p1, _ = sfm_mod._project_obs(K1, R1[ci], t1[ci], X1[pi])
    assert np.abs(sfm_mod._radial(K1, k1, p1)[0] - uv).max() < 1e-3
    # k1 alone (f held at the truth) converges too
    *_, k1b = sfm_mod._schur_lm(K, R, t, X, ci, pi, uv, fixed, 0.0, 200, kernel=kernel, radial=0.1)
    assert k1b == pytest.approx(-0.2, abs=1e-5)
    # the farthest view's normalised radius: |k1| r^2 <= 0.3 holds any step
    xo = (uv - K[:2, 2]) / 500.0
    r2max = float(np.max(np.sum(xo * xo, axis=1)))
    uv_far = sfm_mod._radial(K, -0.9 / r2max, p)[0]  # a lens beyond the bound
    *_, k1c = sfm_mod._schur_lm(
        K, R, t, X, ci, pi, uv_far, fixed, 0.0, 50, kernel=kernel, radial=0.0
    )
    xf = (uv_far - K[:2, 2]) / 500.0
    assert abs(k1c) * float(np.max(np.sum(xf * xf, axis=1))) <= 0.3 + 1e-12
