"""Tests of the compiled robust estimators (imageform._kernels.ransac*, issue 28).

Sources of truth: the NumPy minimal solvers (geometry._minimal: the 7-point and 5-point
solutions on exact data), central differences (the homography's analytic Jacobian), and the
NumPy path of the estimators (``IMAGEFORM_DISABLE_NUMBA=1``): both exact on noise-free data
with outliers, and within a few percent of each other on noisy data. The compiled path draws
its samples from its own generator (seeded from ``rng``), so its results are not the NumPy
path's to the bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.geometry import (
    find_essential_matrix,
    find_fundamental_matrix,
    find_homography,
    rvec_to_matrix,
)
from imageform.geometry._minimal import e5, f7, sampson_sq

pytest.importorskip("numba")

K = np.array([[800.0, 0.0, 320.0], [0.0, 780.0, 240.0], [0.0, 0.0, 1.0]])


def _pair(seed: int, n: int, planar: bool = False):
    rng = np.random.default_rng(seed)
    R = np.asarray(rvec_to_matrix(rng.normal(0, 0.15, 3)))
    t = rng.normal(0, 1, 3)
    t /= np.linalg.norm(t)
    X = rng.uniform([-2, -1.5, 4], [2, 1.5, 8], (n, 3))
    if planar:
        X[:, 2] = 6.0 - 0.2 * X[:, 0] + 0.1 * X[:, 1]
    Y = X @ R.T + t
    return X[:, :2] / X[:, 2:], Y[:, :2] / Y[:, 2:], R, t


def _best(Fs: np.ndarray, G: np.ndarray) -> float:
    G = G / np.linalg.norm(G)
    return min(min(np.abs(F - G).max(), np.abs(F + G).max()) for F in Fs)


def test_5point_kernel_finds_what_the_numpy_solver_finds() -> None:
    from imageform._kernels.ransac_e import _e5

    out = np.empty((10, 3, 3))
    for s in range(40):
        q1, q2, R, t = _pair(s, 5)
        k = _e5(q1, q2, np.arange(5), out)
        ref, _ = e5(q1[None], q2[None])
        assert k == len(ref)
        tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
        assert _best(out[:k], tx @ R) < 1e-8
        for E in ref:
            assert _best(out[:k], E) < 1e-6


def test_7point_kernel_finds_what_the_numpy_solver_finds() -> None:
    from imageform._kernels.ransac_f import _f7

    Fs = np.empty((3, 3, 3))
    bufs = (np.empty((7, 2)), np.empty((7, 2)), np.empty((3, 3)), np.empty((3, 3)))
    for s in range(40):
        x1, x2, *_ = _pair(100 + s, 7)
        u1, u2 = x1 * 800 + 320, x2 * 800 + 240
        k = _f7(u1, u2, np.arange(7), *bufs, np.empty((7, 9)), np.empty((2, 9)),
                np.empty(9, np.int64), Fs, np.empty((3, 3, 3)))  # fmt: skip
        ref, _ = f7(u1[None], u2[None])
        assert k == len(ref)
        for F in ref:
            assert _best(Fs[:k], F) < 1e-7


@pytest.mark.parametrize("kind", [0, 1])
def test_homography_jacobian_matches_central_differences(kind: int) -> None:
    from imageform._kernels.ransac import _h_jac, _hartley, _residuals

    rng = np.random.default_rng(0)
    s = rng.uniform(0, 600, (30, 2))
    d = s * 1.1 + rng.normal(0, 1, (30, 2)) + 5
    idx = np.arange(30)
    aux = np.empty((3, 3, 3))
    scratch = np.empty((30, 2))
    _hartley(s, idx, 30, scratch, aux[0])
    _hartley(d, idx, 30, scratch, aux[1])
    aux[2] = np.linalg.inv(aux[1])
    q = np.eye(3).ravel() + rng.normal(0, 0.05, 9)
    M, T = np.empty((3, 3)), np.empty((3, 3))
    nr = 60 * (kind + 1)
    J = np.empty((nr, 9))
    _h_jac(kind, q, s, d, idx, 30, aux, M, T, J)
    rp, rn = np.empty(nr), np.empty(nr)
    for c in range(9):
        e = np.zeros(9)
        e[c] = 1e-6
        _residuals(kind, q + e, s, d, idx, 30, aux, M, T, rp)
        _residuals(kind, q - e, s, d, idx, 30, aux, M, T, rn)
        assert np.abs(J[:, c] - (rp - rn) / 2e-6).max() < 1e-6 * np.abs(J).max()


def _noisy(seed: int, planar: bool):
    x1, x2, *_ = _pair(seed, 150, planar)
    rng = np.random.default_rng(seed + 1)
    u1 = x1 @ K[:2, :2].T + K[:2, 2]
    u2 = x2 @ K[:2, :2].T + K[:2, 2]
    n1 = u1 + rng.normal(0, 0.5, u1.shape)
    n2 = u2 + rng.normal(0, 0.5, u2.shape)
    out = rng.random(150) < 0.3
    n2[out] = rng.uniform([0, 0], [640, 480], (int(out.sum()), 2))
    return u1, u2, n1, n2, out


def test_compiled_and_numpy_paths_agree_on_noisy_scenes(monkeypatch: pytest.MonkeyPatch) -> None:
    """Median errors of the true points over 6 scenes within 25 % of each other."""

    def errors() -> np.ndarray:
        out = []
        for s in range(6):
            u1, u2, n1, n2, _ = _noisy(s, True)
            Hm = find_homography(n1, n2, rng=s).H
            q = np.c_[u1, np.ones(len(u1))] @ Hm.T
            eh = np.sqrt(np.mean(np.sum((q[:, :2] / q[:, 2:] - u2) ** 2, -1)))
            u1, u2, n1, n2, _ = _noisy(50 + s, False)
            F = find_fundamental_matrix(n1, n2, rng=s).F
            E = find_essential_matrix(n1, n2, K, rng=s).E
            Ki = np.linalg.inv(K)
            ef = np.sqrt(np.mean(sampson_sq(F, u1, u2)))
            ee = np.sqrt(np.mean(sampson_sq(Ki.T @ E @ Ki, u1, u2)))
            out.append((eh, ef, ee))
        return np.median(np.array(out), axis=0)

    compiled = errors()
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = errors()
    assert np.all(compiled < 1.25 * plain), (compiled, plain)
    assert np.all(compiled < 0.5), compiled


def test_compiled_path_reproducible() -> None:
    _u1, _u2, n1, n2, _ = _noisy(3, False)
    a = find_essential_matrix(n1, n2, K, rng=7)
    b = find_essential_matrix(n1, n2, K, rng=7)
    assert np.array_equal(a.E, b.E) and a.trials == b.trials
    c = find_fundamental_matrix(n1, n2, rng=7)
    d = find_fundamental_matrix(n1, n2, rng=7)
    assert np.array_equal(c.F, d.F) and c.trials == d.trials


def test_sturm_roots_find_every_real_root_of_a_degree_10_polynomial() -> None:
    from imageform._kernels.ransac_e import _sturm_roots

    rng = np.random.default_rng(5)
    S, deg, out = np.empty((11, 11)), np.empty(11, np.int64), np.empty(10)
    for trial in range(30):
        real = np.sort(rng.uniform(-3, 3, 2 * (trial % 5 + 1)))  # 2 to 10 real roots
        c = np.poly(real)
        # the rest as complex pairs: x² + b x + 2 + k, b² < 4 (2 + k), no real roots
        for k in range(4 - trial % 5):
            c = np.polymul(c, [1.0, rng.uniform(-1, 1), 2.0 + k])
        n = _sturm_roots(np.ascontiguousarray(c[::-1]), np.int64(10), S, deg, out)
        assert n == len(real)
        np.testing.assert_allclose(np.sort(out[:n]), real, atol=1e-8)


def test_compiled_recover_pose_matches_the_numpy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform.geometry import recover_pose

    for s in range(4):
        _u1, _u2, n1, n2, _ = _noisy(200 + s, False)
        res = find_essential_matrix(n1, n2, K, rng=s)
        a = recover_pose(res.E, n1, n2, K, inliers=res.inliers)
        monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
        b = recover_pose(res.E, n1, n2, K, inliers=res.inliers)
        monkeypatch.delenv("IMAGEFORM_DISABLE_NUMBA")
        np.testing.assert_allclose(a.R, b.R, atol=1e-9)
        np.testing.assert_allclose(a.t, b.t, atol=1e-9)
        assert np.array_equal(a.inliers, b.inliers)
        np.testing.assert_allclose(a.points[a.inliers], b.points[b.inliers], rtol=1e-8)
        assert np.isnan(a.points[~a.inliers]).all()


def test_essential_refit_keeps_no_support_point_behind_a_camera() -> None:
    """The final E's support, less the points behind a camera, is what it was refitted on."""
    from imageform.geometry import recover_pose

    for s in range(3):
        _u1, _u2, n1, n2, out = _noisy(300 + s, False)
        res = find_essential_matrix(n1, n2, K, rng=s)
        pose = recover_pose(res.E, n1, n2, K, inliers=res.inliers, max_depth=1e9)
        # nearly all true inliers kept, and no more outliers than the band lets through
        assert (res.inliers & ~out).sum() >= 0.9 * (~out).sum()
        assert (pose.inliers & out).sum() <= 3


def test_trials_needed_kernel_equals_the_numpy_twin() -> None:
    """``_kernels.ransac._trials_needed`` mirrors ``_robust_core.trials_needed`` exactly."""
    from imageform._kernels.ransac import _trials_needed
    from imageform.geometry._robust_core import trials_needed

    for n in (7, 50, 200, 10_000):
        for n_inl in sorted({0, 1, n // 3, n // 2, n - 1, n}):
            for s in (4, 5, 7):
                for conf in (0.5, 0.99, 0.999, 1 - 1e-9):
                    assert _trials_needed(n_inl, n, s, conf) == trials_needed(n_inl, n, s, conf)


def test_support_bound_kernel_equals_the_numpy_twin() -> None:
    """``_support_bound`` (early exit, any width and factor) is ``refine_support`` to the bit."""
    from imageform._kernels.ransac import _refine_support, _support_bound
    from imageform.geometry._robust_core import refine_support

    rng = np.random.default_rng(0)
    for _ in range(300):
        thr = float(rng.uniform(0.1, 5.0))
        dof = int(rng.integers(1, 3))
        m = float(rng.uniform(0.0, 0.7)) * thr * thr
        width, factor = float(rng.uniform(2.0, 5.0)), float(rng.uniform(1.5, 4.0))
        ref = refine_support(np.array([m]), thr, dof, width, factor)
        assert _support_bound(m, thr, dof, factor, width, 100) == ref
        assert _refine_support(m, thr, dof, 2.0) == refine_support(np.array([m]), thr, dof)


def test_min_eigvec_psd_matches_eigh() -> None:
    """Inverse iteration on the Cholesky factor: the eigenvector of the smallest eigenvalue,
    also for exact (rank-deficient) and near-degenerate least-squares matrices."""
    from imageform._kernels.ransac import _min_eigvec_psd

    rng = np.random.default_rng(1)
    for t in range(200):
        m = int(rng.integers(9, 120))
        X = rng.normal(size=(m, 9)) * rng.uniform(0.01, 10.0, 9)
        if t % 3 == 0:  # a null vector, up to a little noise
            X[:, 0] = X[:, 1:] @ rng.normal(size=8) + rng.normal(size=m) * 10 ** rng.uniform(
                -12, -3
            )
        A = X.T @ X
        out = np.empty(9)
        _min_eigvec_psd(A.copy(), np.empty((9, 9)), np.empty(9), np.empty(9), np.empty((9, 9)), out)
        w, V = np.linalg.eigh(A)
        assert _best(out[None], V[:, 0]) < 1e-8 * max(1.0, w[-1] / max(w[1] - w[0], 1e-300))


def test_fundamental_kernel_exact_with_the_outliers_first() -> None:
    """The SPRT verifies the correspondences in a random order: outliers listed first (a good
    hypothesis would fail the test on the first ones) still give the exact F."""
    x1, x2, R, t = _pair(7, 120)
    u1, u2 = x1 @ K[:2, :2].T + K[:2, 2], x2 @ K[:2, :2].T + K[:2, 2]
    tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    Ki = np.linalg.inv(K)
    Ft = Ki.T @ tx @ R @ Ki
    rng = np.random.default_rng(3)
    for i in range(48):  # outliers at least 5 px from their epipolar line
        while True:
            u2[i] = rng.uniform([0, 0], [640, 480])
            if sampson_sq(Ft, u1[i : i + 1], u2[i : i + 1])[0] > 25.0:
                break
    res = find_fundamental_matrix(u1, u2, rng=1)
    assert _best(res.F[None], Ft) < 1e-9
    assert np.array_equal(res.inliers, np.arange(120) >= 48) and res.rms < 1e-9


def test_oriented_epipolar_constraint_keeps_true_samples_and_drops_a_point_behind() -> None:
    """``ransac_f._oriented`` (Chum, Werner & Matas 2004): the true F passes every sample of
    points in front of both cameras; a sample with one correspondence whose point in image 1
    is moved to the epipole's other side along its epipolar line (``x1' = 2 e1 - x1``, a
    point in front of one camera and behind the other) fails, although it satisfies
    ``x2ᵀ F x1' = 0`` exactly."""
    from imageform._kernels.ransac_f import _oriented

    rng = np.random.default_rng(3)
    R, _ = np.linalg.qr(np.eye(3) + 0.05 * rng.normal(size=(3, 3)))
    R *= np.sign(np.linalg.det(R))
    t = np.array([0.5, 0.1, 0.05])
    X = np.column_stack([rng.uniform(-1, 1, 40), rng.uniform(-1, 1, 40), rng.uniform(4, 8, 40)])

    def proj(P: np.ndarray) -> np.ndarray:
        h = P @ K.T
        return h[:, :2] / h[:, 2:]

    tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
    Ki = np.linalg.inv(K)
    F = Ki.T @ tx @ R @ Ki
    F /= np.linalg.norm(F)
    p1, p2 = proj(X), proj(X @ R.T + t)
    idx = np.arange(40, dtype=np.int64)
    for k in range(0, 35, 7):
        assert _oriented(F, p1, p2, idx[k:], 7)
        assert _oriented(-F, p1, p2, idx[k:], 7)  # the sign of F does not matter
    e1 = np.linalg.svd(F)[2][-1]
    e1 = e1[:2] / e1[2]
    q1 = p1.copy()
    q1[3] = 2.0 * e1 - p1[3]
    h1, h2 = np.append(q1[3], 1.0), np.append(p2[3], 1.0)
    assert abs(h2 @ F @ h1) < 1e-9 * np.linalg.norm(h1) * np.linalg.norm(h2)
    assert _oriented(F, p1, p2, idx, 7)
    assert not _oriented(F, q1, p2, idx, 7)


def test_homography_refit_linear_start_is_intact() -> None:
    """The refit's linear DLT fits hand LM an intact start: with no LM iteration at all the
    kernel's H is the least-squares fit of the noisy inliers (before, its output aliased the
    denormalisation's scratch and LM had to climb back from a corrupted H)."""
    from imageform._kernels.ransac_h import homography_estimate
    from imageform.geometry import _robust_core as rc

    x1, x2, _, _ = _pair(5, 150, planar=True)
    u1, u2 = x1 @ K[:2, :2].T + K[:2, 2], x2 @ K[:2, :2].T + K[:2, 2]
    rng = np.random.default_rng(2)
    n2 = u2 + rng.normal(0.0, 0.5, u2.shape)
    n2[:50] = rng.uniform([0, 0], [640, 480], (50, 2))
    for mode in (0, 1):
        H = np.empty((3, 3))
        inl = np.empty(150, dtype=bool)
        rms = np.empty(1)
        drawn = homography_estimate(
            np.ascontiguousarray(u1), np.ascontiguousarray(n2), 3.0, 0.999, 2000,
            rc.kernel_seed(0), mode, 0, rc.REFINE_FACTOR, rc.TERMINATION_FACTOR,
            rc.H_SUPPORT_WIDTH, H, inl, rms,
        )  # fmt: skip
        assert drawn > 0
        q = np.c_[u1, np.ones(150)] @ H.T
        err = np.sqrt(np.mean(np.sum((q[:, :2] / q[:, 2:] - u2) ** 2, -1)))
        assert err < 0.3 and inl[50:].mean() > 0.95
