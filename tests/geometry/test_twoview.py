"""Tests of the robust two-view geometry: robust.py, twoview.py, relative_pose.py, pnp_batch.py.

Sources of truth: synthetic scenes (noise-free → exact to 1e-9); the algebraic properties
the papers state (rank 2 of F, the 7-point's one or three real roots, E's singular values
(1, 1, 0) and Nister's trace constraint ``2 E Eᵀ E - tr(E Eᵀ) E = 0``). OpenCV 5.0
(findHomography, findFundamentalMat, findEssentialMat, recoverPose, triangulatePoints) is a
labelled cross-check on the same noisy, outlier-laden data: median errors no worse.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError, ImageformError, InvalidInputError
from imageform.geometry import (
    essential_5point,
    find_essential_matrix,
    find_fundamental_matrix,
    find_homography,
    fundamental_7point,
    fundamental_8point,
    project_points,
    recover_pose,
    rvec_to_matrix,
    solve_pnp,
    solve_pnp_batch,
    triangulate_two_view,
)
from imageform.geometry._minimal import sampson_sq

K = np.array([[800.0, 0.0, 320.0], [0.0, 780.0, 240.0], [0.0, 0.0, 1.0]])
W, H = 640, 480


def skew(t: np.ndarray) -> np.ndarray:
    return np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]], dtype=float)


def proj(X: np.ndarray, R: np.ndarray, t: np.ndarray, Km: np.ndarray = K) -> np.ndarray:
    h = (X @ R.T + t) @ Km.T
    return h[:, :2] / h[:, 2:]


def scene(seed: int, n: int = 120, outliers: float = 0.0, sigma: float = 0.0, planar: bool = False):
    """Points seen by two cameras (the first at the origin), noisy pixels, outlier mask."""
    rng = np.random.default_rng(seed)
    R = np.asarray(rvec_to_matrix(rng.normal(0, 0.15, 3)))
    t = rng.normal(0, 1, 3) * [1.0, 0.5, 0.3]
    t /= np.linalg.norm(t)
    X = np.empty((0, 3))
    while len(X) < n:
        Y = rng.uniform([-3, -2, 4], [3, 2, 10], (4 * n, 3))
        if planar:
            Y[:, 2] = 6.0 - 0.2 * Y[:, 0] + 0.1 * Y[:, 1]
        u1, u2 = proj(Y, np.eye(3), np.zeros(3)), proj(Y, R, t)
        ok = np.all((u1 >= 0) & (u1 < [W, H]) & (u2 >= 0) & (u2 < [W, H]), axis=1)
        X = np.concatenate([X, Y[ok & ((Y @ R.T + t)[:, 2] > 0.5)]])[:n]
    u1, u2 = proj(X, np.eye(3), np.zeros(3)), proj(X, R, t)
    n1 = u1 + rng.normal(0, sigma, u1.shape)
    n2 = u2 + rng.normal(0, sigma, u2.shape)
    out = np.zeros(n, dtype=bool)
    out[: round(outliers * n)] = True
    n2[out] = rng.uniform([0, 0], [W, H], (int(out.sum()), 2))
    return X, R, t, u1, u2, n1, n2, out


def same_up_to_sign(A: np.ndarray, B: np.ndarray) -> float:
    A, B = A / np.linalg.norm(A), B / np.linalg.norm(B)
    return float(min(np.abs(A - B).max(), np.abs(A + B).max()))


def true_F(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    Ki = np.linalg.inv(K)
    return Ki.T @ skew(t) @ R @ Ki


def angle_deg(R1: np.ndarray, R2: np.ndarray) -> float:
    """Angle of R1ᵀ R2 (degrees), accurate near 0 (``‖R1 - R2‖_F = 2√2 sin(θ/2)``)."""
    return float(np.degrees(2 * np.arcsin(min(1.0, np.linalg.norm(R1 - R2) / (2 * np.sqrt(2))))))


def transfer_rms(Hm: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> float:
    q = np.c_[u1, np.ones(len(u1))] @ Hm.T
    return float(np.sqrt(np.mean(np.sum((q[:, :2] / q[:, 2:] - u2) ** 2, -1))))


# ---------------------------------------------------------------- homography
def test_homography_exact_with_outliers() -> None:
    _X, R, t, u1, u2, _n1, n2, out = scene(1, outliers=0.3, planar=True)
    n2 = np.where(out[:, None], n2, u2)
    res = find_homography(u1, n2)
    normal = np.array([0.2, -0.1, 1.0]) / 6.0  # the plane n·X = 1 of the scene
    Ht = K @ (R + np.outer(t, normal)) @ np.linalg.inv(K)
    assert same_up_to_sign(res.H, Ht) < 1e-9
    assert res.H[2, 2] == pytest.approx(1.0)
    assert np.array_equal(res.inliers, ~out)
    assert res.rms < 1e-9


def test_homography_reproducible_and_rng_changes_samples() -> None:
    *_, n1, n2, _ = scene(2, outliers=0.4, sigma=0.5, planar=True)
    a, b = find_homography(n1, n2, rng=5), find_homography(n1, n2, rng=5)
    assert np.array_equal(a.H, b.H) and a.trials == b.trials
    g = np.random.default_rng(0)
    assert find_homography(n1, n2, rng=g).H.shape == (3, 3)


@pytest.mark.parametrize("refine", ["symmetric", "forward"])
def test_homography_no_worse_than_opencv(refine: str) -> None:
    cv2 = pytest.importorskip("cv2")
    ours, theirs = [], []
    for s in range(8):
        _X, _R, _t, u1, u2, n1, n2, _out = scene(
            100 + s, n=150, outliers=0.3, sigma=1.0, planar=True
        )

        cv2.setRNGSeed(s)
        theirs.append(transfer_rms(cv2.findHomography(n1, n2, cv2.RANSAC, 3.0)[0], u1, u2))
        ours.append(transfer_rms(find_homography(n1, n2, refine=refine, rng=s).H, u1, u2))
    assert np.median(ours) <= np.median(theirs)


def test_homography_bad_inputs() -> None:
    p = np.random.default_rng(0).uniform(0, 100, (10, 2))
    with pytest.raises(InvalidInputError, match="same length"):
        find_homography(p, p[:9])
    with pytest.raises(InvalidInputError, match="at least 4"):
        find_homography(p[:3], p[:3])
    q = p.copy()
    q[2, 0] = np.nan
    with pytest.raises(InvalidInputError, match="src"):
        find_homography(q, p)
    with pytest.raises(InvalidInputError, match="shape"):
        find_homography(p[None], p[None])
    with pytest.raises(InvalidInputError, match="confidence"):
        find_homography(p, p, confidence=1.0)
    with pytest.raises(InvalidInputError, match="threshold"):
        find_homography(p, p, threshold=-1.0)
    with pytest.raises(ImageformError, match="refine"):
        find_homography(p, p, refine="gold")
    with pytest.raises(DegenerateConfigurationError, match="no homography"):
        # every source point the same: no sample determines a homography
        find_homography(np.ones((30, 2)), np.random.default_rng(1).uniform(0, 600, (30, 2)))


# ---------------------------------------------------------------- fundamental
def test_8point_exact() -> None:
    _X, R, t, u1, u2, *_ = scene(3, n=30)
    F = fundamental_8point(u1, u2)
    assert same_up_to_sign(F, true_F(R, t)) < 1e-9
    assert np.linalg.norm(F) == pytest.approx(1.0)
    assert abs(np.linalg.det(F)) < 1e-15


def test_7point_one_or_three_solutions() -> None:
    """H&Z sec. 11.1.2: det(a F1 + (1-a) F2) = 0 is a cubic: 1 or 3 real roots, the truth among
    them, each rank 2 and through the 7 points. Some seeds give three real roots."""
    counts = set()
    for s in range(20):
        _X, R, t, u1, u2, *_ = scene(200 + s, n=7)
        Fs = fundamental_7point(u1, u2)
        counts.add(Fs.shape[0])
        assert Fs.shape[0] in (1, 3)
        assert min(same_up_to_sign(F, true_F(R, t)) for F in Fs) < 1e-8
        for F in Fs:
            assert abs(np.linalg.det(F / np.linalg.norm(F))) < 1e-12
            assert np.sqrt(sampson_sq(F, u1, u2)).max() < 1e-7
    assert counts == {1, 3}


def test_7point_matches_opencv() -> None:
    cv2 = pytest.importorskip("cv2")
    for s in range(10):
        _X, _R, _t, u1, u2, *_ = scene(300 + s, n=7)
        ours = fundamental_7point(u1, u2)
        theirs = cv2.findFundamentalMat(u1, u2, cv2.FM_7POINT)[0].reshape(-1, 3, 3)
        assert len(ours) == len(theirs)
        for F in theirs:  # OpenCV's roots agree to ~3e-6 (ours match the truth to 1e-8)
            assert min(same_up_to_sign(F, G) for G in ours) < 1e-5


def test_find_fundamental_exact_with_outliers() -> None:
    _X, R, t, u1, u2, _n1, n2, out = scene(4, outliers=0.3)
    res = find_fundamental_matrix(u1, np.where(out[:, None], n2, u2))
    assert same_up_to_sign(res.F, true_F(R, t)) < 1e-9
    assert np.array_equal(res.inliers[~out], np.ones((~out).sum(), bool))
    assert res.rms < 1e-9


def test_fundamental_no_worse_than_opencv() -> None:
    cv2 = pytest.importorskip("cv2")
    ours, theirs = [], []
    for s in range(8):
        _X, _R, _t, u1, u2, n1, n2, _out = scene(400 + s, n=150, outliers=0.3, sigma=1.0)
        cv2.setRNGSeed(s)
        Fc = cv2.findFundamentalMat(n1, n2, cv2.FM_RANSAC, 1.0, 0.999)[0][:3]
        theirs.append(np.sqrt(np.mean(sampson_sq(Fc, u1, u2))))
        Fi = find_fundamental_matrix(n1, n2, threshold=1.0, rng=s).F
        ours.append(np.sqrt(np.mean(sampson_sq(Fi, u1, u2))))
    assert np.median(ours) <= np.median(theirs)


def _fundamental_errors(seeds: range) -> np.ndarray:
    """RMS Sampson distance (px) of the true points under the F found on the noisy scenes
    of benchmarks/bench_twoview.py (200 points, 30 % outliers, σ = 1 px, τ = 1 px); the
    scenes the second camera does not see (seed 515 of the first 1000) are left out."""
    from benchmarks.bench_twoview import scene as bench_scene

    out = []
    for s in seeds:
        try:
            sc = bench_scene(2000 + s, 200, 0.3, 1.0, planar=False)
        except ValueError:
            continue
        F = find_fundamental_matrix(sc["n1"], sc["n2"], threshold=1.0, rng=s).F
        out.append(np.sqrt(np.mean(sampson_sq(F, sc["u1"], sc["u2"]))))
    return np.asarray(out)


def test_fundamental_worst_case_near_the_best_over_seeds() -> None:
    """Issue 26: on noisy scenes (σ = τ) a minimal sample of inliers scores worse than a
    model already optimised into a wrong basin and was never optimised: seed 29 ended at
    1.15 px where the median is 0.29 px. LO-RANSAC's Sampson-weighted refits on 3τ then 2τ,
    and the runner-up hypotheses optimised before sampling stops, bring the worst of 100
    scenes under 1 px."""
    err = _fundamental_errors(range(100))
    assert np.median(err) < 0.35
    assert err.max() < 1.0, (int(np.argmax(err)), float(err.max()))


@pytest.mark.slow
def test_fundamental_worst_case_near_the_best_over_1000_seeds() -> None:
    """The same over 1000 scenes (before: 7 of the first 300 above 1 px, up to 1.84 px).

    Issue 28: about 4 s since the compiled estimators; it never ended before because the
    scene of seed 515 looped for ever (the second camera sees none of its points): that
    scene is left out and seed 1000 taken instead, so 1000 scenes are checked.
    """
    err = _fundamental_errors(range(1001))
    assert len(err) == 1000
    assert np.median(err) < 0.35
    assert err.max() < 1.0, (int(np.argmax(err)), float(err.max()))


def test_fundamental_bad_inputs() -> None:
    p = np.random.default_rng(0).uniform(0, 100, (10, 2))
    with pytest.raises(InvalidInputError, match="at least 8"):
        fundamental_8point(p[:7], p[:7])
    with pytest.raises(InvalidInputError, match="exactly 7"):
        fundamental_7point(p, p)
    with pytest.raises(InvalidInputError, match="same length"):
        find_fundamental_matrix(p, p[:9])
    with pytest.raises(InvalidInputError, match="max_trials"):
        find_fundamental_matrix(p, p, max_trials=0)


# ---------------------------------------------------------------- essential
def test_5point_contains_truth_with_essential_properties() -> None:
    Ki = np.linalg.inv(K)
    for s in range(10):
        _X, R, t, u1, u2, *_ = scene(500 + s, n=5)
        q1 = (np.c_[u1, np.ones(5)] @ Ki.T)[:, :2]
        q2 = (np.c_[u2, np.ones(5)] @ Ki.T)[:, :2]
        Es = essential_5point(q1, q2)
        assert 0 < len(Es) <= 10 and len(Es) % 2 == 0
        assert min(same_up_to_sign(E, skew(t) @ R) for E in Es) < 1e-9
        for E in Es:
            # Nister (2004) eq. 2 and the singular values (1, 1, 0)/sqrt(2) at unit norm
            assert np.abs(2 * E @ E.T @ E - np.trace(E @ E.T) * E).max() < 1e-9
            np.testing.assert_allclose(np.linalg.svd(E)[1], [2**-0.5, 2**-0.5, 0], atol=1e-9)
            h1, h2 = np.c_[q1, np.ones(5)], np.c_[q2, np.ones(5)]
            assert np.abs(np.einsum("ni,ij,nj->n", h2, E, h1)).max() < 1e-9


def test_find_essential_exact_with_outliers_and_two_cameras() -> None:
    K2 = np.array([[900.0, 0.0, 300.0], [0.0, 910.0, 250.0], [0.0, 0.0, 1.0]])
    X, R, t, u1, _, _n1, n2, out = scene(6, outliers=0.3)
    u2 = proj(X, R, t, K2)
    n2 = np.where(out[:, None], n2, u2)
    res = find_essential_matrix(u1, n2, K, K2)
    assert same_up_to_sign(res.E, skew(t) @ R) < 1e-9
    np.testing.assert_allclose(np.linalg.svd(res.E)[1], [2**-0.5, 2**-0.5, 0], atol=1e-12)
    assert res.inliers[~out].all()
    pose = recover_pose(res.E, u1, n2, K, K2, inliers=res.inliers)
    assert angle_deg(pose.R, R) < 1e-7
    np.testing.assert_allclose(pose.t, t, atol=1e-9)
    assert pose.inliers.sum() == (~out).sum()
    np.testing.assert_allclose(pose.points[~out], X[~out] / 1.0, atol=1e-8)  # |t| = 1


def test_essential_and_pose_no_worse_than_opencv() -> None:
    cv2 = pytest.importorskip("cv2")
    ours, theirs = [], []
    for s in range(8):
        _X, R, _t, _u1, _u2, n1, n2, _out = scene(600 + s, n=150, outliers=0.3, sigma=1.0)
        cv2.setRNGSeed(s)
        Ec, mc = cv2.findEssentialMat(n1, n2, K, cv2.RANSAC, 0.999, 1.0)
        _, Rc, _, _ = cv2.recoverPose(Ec[:3], n1, n2, K, mask=mc.copy())
        theirs.append(angle_deg(Rc, R))
        res = find_essential_matrix(n1, n2, K, threshold=1.0, rng=s)
        ours.append(angle_deg(recover_pose(res.E, n1, n2, K, inliers=res.inliers).R, R))
    assert np.median(ours) <= np.median(theirs)


def _wide_scene(
    seed: int, n: int = 200, inlier_ratio: float = 0.4, sigma: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A wide-baseline pair: the second camera orbits the cloud by 25-35 degrees.

    Pixels by the library's ``project_points``; ``inlier_ratio`` of the correspondences
    true (Gaussian noise ``sigma`` px in both images), the rest uniform in the second image.
    """
    rng = np.random.default_rng(seed)
    axis = np.array([rng.normal(0, 0.2), 1.0, rng.normal(0, 0.2)])
    R = np.asarray(rvec_to_matrix(np.radians(rng.uniform(25, 35)) * axis / np.linalg.norm(axis)))
    c = np.array([0.0, 0.0, 6.0])
    t = c - R @ c  # the second camera looks at the cloud's centre
    X = np.empty((0, 3))
    while len(X) < n:
        Y = c + rng.uniform([-2.5, -2, -1.5], [2.5, 2, 1.5], (4 * n, 3))
        u1, u2 = project_points(Y, K).uv, project_points(Y, K, R, t).uv
        ok = np.all((u1 >= 0) & (u1 < [W, H]) & (u2 >= 0) & (u2 < [W, H]), axis=1)
        X = np.concatenate([X, Y[ok]])[:n]
    n1 = project_points(X, K).uv + rng.normal(0, sigma, (n, 2))
    n2 = project_points(X, K, R, t).uv + rng.normal(0, sigma, (n, 2))
    out = np.ones(n, dtype=bool)
    out[: round(inlier_ratio * n)] = False
    n2[out] = rng.uniform([0, 0], [W, H], (int(out.sum()), 2))
    return R, t / np.linalg.norm(t), n1, n2, out


def _gold_rotation_error(
    R: np.ndarray, t: np.ndarray, n1: np.ndarray, n2: np.ndarray, out: np.ndarray
) -> float:
    """Rotation error of the gold standard: E refined (LM, Sampson) on the true inliers."""
    from imageform.geometry.twoview import _essential_from_rt, _normalised, _refine_e

    a, b = n1[~out], n2[~out]
    E = _refine_e(_essential_from_rt(R, t), _normalised(a, K), _normalised(b, K), K, K, a, b, 100)
    return angle_deg(recover_pose(E, n1, n2, K, inliers=~out).R, R)


def _seed_errors(scene_seed: int, seeds: range) -> tuple[np.ndarray, float]:
    R, t, n1, n2, out = _wide_scene(scene_seed)
    errs = []
    for s in seeds:
        res = find_essential_matrix(n1, n2, K, rng=s)
        errs.append(angle_deg(recover_pose(res.E, n1, n2, K, inliers=res.inliers).R, R))
    return np.array(errs), _gold_rotation_error(R, t, n1, n2, out)


def test_essential_hardly_depends_on_the_seed_on_a_wide_baseline_pair() -> None:
    """40 % inliers, 1 px noise, 10 seeds: one model, near the gold standard's accuracy.

    Before MAGSAC++'s IRLS (main at 68c1e6f) the seeds of scenes 1, 2 and 5 spread over
    0.15, 0.29 and 0.11 degrees and the median of worst / gold over the six scenes was
    1.25; with it the largest spread is 0.023 degrees and the median 0.89.
    """
    worst_over_gold = []
    for sc in range(6):
        errs, gold = _seed_errors(sc, range(10))
        assert errs.max() - errs.min() < 0.05, (sc, errs)
        assert errs.max() < gold + 0.3, (sc, errs, gold)
        worst_over_gold.append(errs.max() / gold)
    assert np.median(worst_over_gold) < 1.2, worst_over_gold


def test_essential_numpy_twin_as_robust_to_the_seed(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    errs, gold = _seed_errors(3, range(5))
    assert errs.max() - errs.min() < 0.05 and errs.max() < gold + 0.3, (errs, gold)


@pytest.mark.parametrize("numba", [True, False])
def test_essential_final_fit_is_least_squares_on_its_support(
    numba: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """σ = τ: the result is the plain Sampson LM fit of its own refinement support.

    After MAGSAC++'s IRLS (which chooses the basin) the final fit is the unweighted
    least-squares one on the correspondences within ``3σ̂`` (``τ`` to ``2τ``) in front of
    the cameras: refitting that support from the result moves it by nothing (a fixed
    point). The IRLS's own result is not one (its weights are below 1), and 0.349 against
    0.314 degrees median over benchmarks/bench_twoview.py's 100 scenes was its cost.
    """
    from imageform.geometry import _robust_core
    from imageform.geometry.twoview import _in_front, _normalised, _refine_e

    if not numba:
        monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    Ki = np.linalg.inv(K)
    for sc in (0, 1, 2):
        R, _t, n1, n2, _out = _wide_scene(40 + sc, inlier_ratio=0.7, sigma=1.0)
        res = find_essential_matrix(n1, n2, K, threshold=1.0, rng=sc)
        E = np.asarray(res.E, np.float64)
        e = sampson_sq(Ki.T @ E @ Ki, n1, n2)
        wide = _robust_core.refine_support(e[e < 1.0], 1.0, 1)
        q1, q2 = _normalised(n1, K), _normalised(n2, K)
        sel = (e < wide * wide) & _in_front(E, q1, q2, e < wide * wide)
        E2 = _refine_e(E, q1[sel], q2[sel], K, K, n1[sel], n2[sel], 50)
        moved = min(np.linalg.norm(E2 - E), np.linalg.norm(E2 + E))
        assert moved < 1e-4, (sc, moved)
        assert angle_deg(recover_pose(E, n1, n2, K, inliers=res.inliers).R, R) < 1.0


def test_magsac_weight_is_the_loss_derivative_over_the_residual() -> None:
    """MAGSAC++'s IRLS weight is ``ρ'(r) / r`` of its loss (Barath et al. 2020, eq. 12)."""
    from imageform.geometry._robust_core import magsac

    r = np.linspace(0.05, 2.95, 59)  # residuals within the reach 3 τ (τ = 1)
    h = 1e-6
    loss, w = magsac(r**2, 1.0)
    dloss = (magsac((r + h) ** 2, 1.0)[0] - magsac((r - h) ** 2, 1.0)[0]) / (2 * h)
    ratio = dloss / r / w
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-5)
    assert np.all(np.diff(loss) > 0) and np.all(np.diff(w) < 0)
    l_out, w_out = magsac(np.array([9.0, 100.0]), 1.0)
    np.testing.assert_array_equal(l_out, [1.0, 1.0])
    np.testing.assert_array_equal(w_out, [0.0, 0.0])
    np.testing.assert_allclose(magsac(np.array([0.0]), 1.0)[1], [1.0])


def test_recover_pose_matches_opencv_on_same_E() -> None:
    cv2 = pytest.importorskip("cv2")
    for s in range(5):
        _X, _R, _t, _u1, _u2, n1, n2, _out = scene(700 + s, outliers=0.2, sigma=0.5)
        cv2.setRNGSeed(s)
        Ec, mc = cv2.findEssentialMat(n1, n2, K, cv2.RANSAC, 0.999, 1.0)
        Ec = Ec[:3]
        n_cv, Rc, tc, _mask_cv = cv2.recoverPose(Ec, n1, n2, K, mask=mc.copy())
        pose = recover_pose(Ec, n1, n2, K, inliers=mc.ravel().astype(bool))
        np.testing.assert_allclose(pose.R, Rc, atol=1e-9)
        np.testing.assert_allclose(pose.t, tc.ravel(), atol=1e-9)
        assert int(pose.inliers.sum()) == n_cv
        assert np.isnan(pose.points[~pose.inliers]).all()


def test_recover_pose_cheirality_picks_the_one_in_front() -> None:
    """Of the four factorisations, three put the points behind a camera (H&Z result 9.19)."""
    _X, R, t, u1, u2, *_ = scene(8, n=40)
    for E in (skew(t) @ R, -skew(t) @ R, 3.0 * skew(t) @ R):
        pose = recover_pose(E, u1, u2, K)
        assert angle_deg(pose.R, R) < 1e-7 and np.allclose(pose.t, t, atol=1e-9)
        assert pose.inliers.all()
        assert (pose.points[:, 2] > 0).all()


def test_essential_bad_inputs() -> None:
    p = np.random.default_rng(0).uniform(0, 100, (10, 2))
    with pytest.raises(InvalidInputError, match="K1"):
        find_essential_matrix(p, p, [[800, 0, 320], [0, -800, 240], [0, 0, 1]])
    with pytest.raises(InvalidInputError, match="K2"):
        find_essential_matrix(p, p, K, np.eye(2))
    with pytest.raises(InvalidInputError, match="exactly 5"):
        essential_5point(p, p)
    with pytest.raises(InvalidInputError, match="inliers"):
        recover_pose(np.eye(3), p, p, K, inliers=np.ones(9, bool))
    with pytest.raises(InvalidInputError, match="E"):
        recover_pose(np.eye(2), p, p, K)


# ---------------------------------------------------------------- triangulation
@pytest.mark.parametrize("method", ["linear", "midpoint", "optimal"])
def test_triangulate_two_view_exact(method: str) -> None:
    X, R, t, u1, u2, *_ = scene(9, n=50)
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    P2 = K @ np.c_[R, t]
    res = triangulate_two_view(P1, P2, u1, u2, method=method)
    np.testing.assert_allclose(res.points, X, atol=1e-9 * 10)
    assert res.valid.all()


def test_triangulate_linear_matches_opencv_and_optimal_is_consistent() -> None:
    cv2 = pytest.importorskip("cv2")
    X, R, t, _u1, _u2, n1, n2, _ = scene(10, n=200, sigma=1.0)
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    P2 = K @ np.c_[R, t]
    Xc = cv2.triangulatePoints(P1, P2, n1.T, n2.T)
    lin = triangulate_two_view(P1, P2, n1, n2, method="linear")
    np.testing.assert_allclose(lin.points, (Xc[:3] / Xc[3]).T, rtol=1e-9, atol=1e-9)
    opt = triangulate_two_view(P1, P2, n1, n2, method="optimal")

    # the optimal point reprojects onto corrected pixels that satisfy x2ᵀ F x1 = 0: its
    # reprojection error is never larger than the linear point's (both 2-view errors)
    def reproj(Y: np.ndarray) -> np.ndarray:
        return np.sum((proj(Y, np.eye(3), np.zeros(3)) - n1) ** 2 + (proj(Y, R, t) - n2) ** 2, -1)

    assert np.median(reproj(opt.points)) <= np.median(reproj(lin.points)) * (1 + 1e-9)
    err = lambda Y: np.median(np.linalg.norm(Y - X, axis=-1))  # noqa: E731
    assert err(opt.points) <= 1.05 * err((Xc[:3] / Xc[3]).T)


def test_triangulate_optimal_is_the_maximum_likelihood_point() -> None:
    """Lindstrom's correction + DLT equals the minimiser of the two-view reprojection error
    (imageform's triangulate_points: DLT then LM), H&Z sec. 12.5."""
    from imageform.geometry import triangulate_points

    _X, R, t, _u1, _u2, n1, n2, _ = scene(11, n=100, sigma=1.0)
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    P2 = K @ np.c_[R, t]
    opt = triangulate_two_view(P1, P2, n1, n2, method="optimal")
    ml = triangulate_points(np.stack([P1, P2]), np.stack([n1, n2]), max_iter=50)
    np.testing.assert_allclose(opt.points, ml.points, atol=1e-5)


def test_triangulate_behind_camera_invalid_and_bad_inputs() -> None:
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    P2 = K @ np.c_[np.eye(3), [-1.0, 0, 0]]
    Xb = np.array([[0.1, 0.2, -5.0]])
    h1, h2 = Xb @ P1[:, :3].T + P1[:, 3], Xb @ P2[:, :3].T + P2[:, 3]
    res = triangulate_two_view(
        P1, P2, h1[:, :2] / h1[:, 2:], h2[:, :2] / h2[:, 2:], method="linear"
    )
    np.testing.assert_allclose(res.points, Xb, atol=1e-9)
    assert not res.valid[0]
    with pytest.raises(ImageformError, match="triangulation method"):
        triangulate_two_view(P1, P2, [[1.0, 2.0]], [[1.0, 2.0]], method="best")
    with pytest.raises(InvalidInputError, match="P1"):
        triangulate_two_view(np.eye(3), P2, [[1.0, 2.0]], [[1.0, 2.0]])
    with pytest.raises(InvalidInputError, match="same length"):
        triangulate_two_view(P1, P2, [[1.0, 2.0]], [[1.0, 2.0], [3.0, 4.0]])


# ---------------------------------------------------------------- batched PnP
def _pnp_batch(B: int, N: int, seed: int, noise: float = 0.0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (B, N, 3))
    f = rng.uniform(400, 1500, B)
    Ks = np.zeros((B, 3, 3))
    Ks[:, 0, 0], Ks[:, 1, 1] = f, f * rng.uniform(0.95, 1.05, B)
    Ks[:, 0, 1] = rng.uniform(-1, 1, B)
    Ks[:, 0, 2], Ks[:, 1, 2], Ks[:, 2, 2] = rng.uniform(250, 390, B), rng.uniform(200, 280, B), 1.0
    R = np.asarray(rvec_to_matrix(rng.normal(0, 0.4, (B, 3))))
    t = np.c_[rng.uniform(-0.5, 0.5, (B, 2)), rng.uniform(4, 8, B)]
    h = np.einsum("bij,bnj->bni", Ks, X @ np.swapaxes(R, 1, 2) + t[:, None])
    uv = h[..., :2] / h[..., 2:]
    return X, uv + rng.normal(0, noise, uv.shape), Ks, R, t


def test_pnp_batch_exact_with_a_K_per_problem() -> None:
    X, uv, Ks, R, t = _pnp_batch(40, 10, 0)
    res = solve_pnp_batch(X, uv, Ks)
    np.testing.assert_allclose(res.R, R, atol=1e-9)
    np.testing.assert_allclose(res.tvec, t, atol=1e-9)
    assert res.valid.all() and res.rms.max() < 1e-9
    # batch shape (4, 10) with K broadcast (4, 10, 3, 3)
    res2 = solve_pnp_batch(
        X.reshape(4, 10, 10, 3), uv.reshape(4, 10, 10, 2), Ks.reshape(4, 10, 3, 3)
    )
    assert res2.R.shape == (4, 10, 3, 3) and res2.inliers.shape == (4, 10, 10)


def test_pnp_batch_equals_solve_pnp_per_problem_with_noise() -> None:
    X, uv, Ks, _R, _t = _pnp_batch(6, 20, 1, noise=0.5)
    res = solve_pnp_batch(X, uv, Ks)
    for b in range(6):
        one = solve_pnp(X[b], uv[b], Ks[b])
        np.testing.assert_allclose(res.tvec[b], one.tvec, atol=1e-7)
        np.testing.assert_allclose(res.rms[b], one.rms, rtol=1e-7)


def test_pnp_batch_cross_check_opencv() -> None:
    cv2 = pytest.importorskip("cv2")
    X, uv, Ks, R, t = _pnp_batch(5, 20, 2, noise=0.5)
    Ks[:, 0, 1] = 0.0  # OpenCV's pinhole has no skew
    h = np.einsum("bij,bnj->bni", Ks, X @ np.swapaxes(R, 1, 2) + t[:, None])
    uv = h[..., :2] / h[..., 2:] + np.random.default_rng(3).normal(0, 0.5, uv.shape)
    res = solve_pnp_batch(X, uv, Ks)
    for b in range(5):
        _ok, _rv, tv = cv2.solvePnP(X[b], uv[b], Ks[b], None, flags=cv2.SOLVEPNP_ITERATIVE)
        np.testing.assert_allclose(res.tvec[b], tv.ravel(), atol=1e-5)


def test_pnp_batch_bad_inputs() -> None:
    X, uv, Ks, _R, _t = _pnp_batch(3, 8, 4)
    with pytest.raises(InvalidInputError, match="K of shape"):
        solve_pnp_batch(X, uv, Ks[:2])
    bad = Ks.copy()
    bad[1, 1, 0] = 3.0
    with pytest.raises(InvalidInputError, match="problem 1"):
        solve_pnp_batch(X, uv, bad)
    with pytest.raises(InvalidInputError, match="same leading shape"):
        solve_pnp_batch(X, uv[:, :7], Ks)
    uv[0, 0, 0] = np.nan
    with pytest.raises(InvalidInputError, match="image_points"):
        solve_pnp_batch(X, uv, Ks)


def test_pnp_batch_float32_in_float32_out() -> None:
    X, uv, Ks, _R, t = _pnp_batch(3, 8, 5)
    res = solve_pnp_batch(X.astype(np.float32), uv.astype(np.float32), Ks)
    assert res.tvec.dtype == np.float32 and res.R.dtype == np.float32
    np.testing.assert_allclose(res.tvec, t, atol=1e-4)


def test_float32_in_float32_out() -> None:
    _X, R, t, u1, u2, *_ = scene(12, n=60)
    a, b = u1.astype(np.float32), u2.astype(np.float32)
    assert find_homography(a, a + 1).H.dtype == np.float32
    assert find_fundamental_matrix(a, b).F.dtype == np.float32
    assert fundamental_8point(a, b).dtype == np.float32
    res = find_essential_matrix(a, b, K)
    assert res.E.dtype == np.float32
    pose = recover_pose(res.E, a, b, K)
    assert pose.R.dtype == pose.t.dtype == pose.points.dtype == np.float32
    assert angle_deg(pose.R.astype(float), R) < 0.05
    P1 = K @ np.c_[np.eye(3), np.zeros(3)]
    assert triangulate_two_view(P1, K @ np.c_[R, t], a, b).points.dtype == np.float32
    # float64 stays float64, and lists compute in float64
    assert find_homography(u1.tolist(), (u1 + 1).tolist()).H.dtype == np.float64


# ---------------------------------------------------------------- RANSAC internals
@pytest.mark.parametrize(
    ("s", "counts"),
    [
        (4, [3, 5, 9, 13, 17, 34, 72]),
        (7, [4, 8, 20, 33, 54, 163, 588]),
        (8, [5, 9, 26, 44, 78, 272, 1177]),
    ],
)
def test_trials_needed_matches_hartley_zisserman_table_4_3(s: int, counts: list[int]) -> None:
    """H&Z 2nd ed. Table 4.3: samples for p = 0.99 at 5, 10, 20, 25, 30, 40, 50 % outliers."""
    import math

    from imageform.geometry._robust_core import trials_needed

    for e, want in zip([5, 10, 20, 25, 30, 40, 50], counts, strict=True):
        assert math.ceil(trials_needed(100 - e, 100, s, 0.99)) == want


@pytest.mark.parametrize(("dof", "sigma", "tau"), [(1, 1.0, 1.0), (1, 0.5, 1.0), (2, 1.4, 3.0)])
def test_refine_support_recovers_the_noise_from_truncated_residuals(
    dof: int, sigma: float, tau: float
) -> None:
    from imageform.geometry._robust_core import REFINE_FACTOR, refine_support

    e2 = np.sum(np.random.default_rng(0).normal(0, sigma, (200_000, dof)) ** 2, axis=1)
    got = refine_support(e2[e2 < tau * tau], tau, dof)
    want = min(max(3 * sigma, tau), REFINE_FACTOR * tau)
    assert got == pytest.approx(want, rel=0.02)
    assert refine_support(np.zeros(10), tau, dof) == tau  # exact data keep the threshold


def test_homography_on_real_sift_matches_on_par_with_opencv(shared_data: Path) -> None:
    """Kodak images matched (SIFT) with a copy warped by a known homography: real matching
    outliers, known truth. Cross-check: cv2.findHomography(RANSAC) on the same matches."""
    cv2 = pytest.importorskip("cv2")
    sift = cv2.SIFT_create(nfeatures=800)
    rng = np.random.default_rng(0)
    ours, theirs = [], []
    for k in (1, 5, 9, 13, 17, 21):
        im = cv2.imread(str(shared_data / "kodak" / f"kodim{k:02d}.png"), cv2.IMREAD_GRAYSCALE)
        h, w = im.shape
        corners = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=np.float32)
        moved = (corners + rng.uniform(-0.12, 0.12, (4, 2)) * [w, h]).astype(np.float32)
        Ht = cv2.getPerspectiveTransform(corners, moved)
        im2 = cv2.warpPerspective(im, Ht, (w, h))
        k1, d1 = sift.detectAndCompute(im, None)
        k2, d2 = sift.detectAndCompute(im2, None)
        pairs = cv2.BFMatcher().knnMatch(d1, d2, k=2)
        good = [m for m, m2 in pairs if m.distance < 0.85 * m2.distance]
        p1 = np.array([k1[g.queryIdx].pt for g in good])
        p2 = np.array([k2[g.trainIdx].pt for g in good])
        grid = np.stack(np.meshgrid(np.linspace(0, w - 1, 10), np.linspace(0, h - 1, 10)), -1)
        grid = grid.reshape(-1, 2)
        truth = cv2.perspectiveTransform(grid[None], Ht)[0]
        cv2.setRNGSeed(0)
        Hc = cv2.findHomography(p1, p2, cv2.RANSAC, 3.0)[0]
        theirs.append(transfer_rms(Hc, grid, truth))
        ours.append(transfer_rms(find_homography(p1, p2, threshold=3.0).H, grid, truth))
    # on 6 images the medians differ by sampling luck (0.106 against 0.102 px here); on all
    # 24 images with noise, benchmarks/bench_twoview.py --kodak measures 0.887x OpenCV's error
    assert np.median(ours) <= 1.1 * np.median(theirs)
    assert max(ours) < 1.0
