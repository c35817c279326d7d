"""Calibration's faster paths against their references: the numba kernel of the normal
equations' blocks against its NumPy twin (``project_views`` and array products), the Schur
complement's step and statistics against the dense normal equations, the refinement with and
without the kernel, the padded batch of homographies against one ``estimate_homography`` per
view, and the views' one-pass check against the per-view checks."""

from __future__ import annotations

import numpy as np
import pytest

from imageform._backend import numba_enabled
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import calibrate_camera, checkerboard_points, estimate_homography
from imageform.geometry.calibration_refine import (
    COND_WARN,
    _statistics,
    normal_blocks,
    project_views,
    refine,
    schur_step,
)
from imageform.geometry.calibration_views import _views
from imageform.geometry.calibration_zhang import homographies, homographies_of

needs_numba = pytest.mark.skipif(not numba_enabled(), reason="numba")
COEFS = {
    "brown_conrady": [-0.2, 0.05, 1e-3, -2e-3, 0.01],
    "rational": [0.3, -0.1, 1e-3, -2e-3, 0.02, 0.5, -0.05, 0.01],
    "kannala_brandt": [0.05, -0.01, 0.003, -0.001],
}


def _scene(model: str, seed: int = 0, V: int = 5) -> tuple:
    """Globals, poses and the views' points (of different sizes, views interleaved)."""
    rng = np.random.default_rng(seed)
    g = np.array([800.0, 790.0, 320.0, 240.0, 0.5, *COEFS[model]])
    rv = rng.normal(0, 0.3, (V, 3))
    rv[0] = [1e-8, 0.0, 0.0]  # the series of Rodrigues' formula near 0
    tv = np.c_[rng.uniform(-0.3, 0.3, (V, 2)), rng.uniform(3, 5, V)]
    board = checkerboard_points((6, 5), 0.1)
    board[:, 2] = rng.normal(0, 0.05, len(board))  # a 3-D rig: every term of d cam / d rvec
    objs = [board[: 30 - 3 * k] for k in range(V)]
    obj = np.concatenate(objs)
    view = np.concatenate([np.full(len(o), k) for k, o in enumerate(objs)])
    order = rng.permutation(len(view))
    obj, view = obj[order], view[order]
    img = project_views(g, rv, tv, obj, view, model=model)[0] + rng.normal(0, 0.5, (len(obj), 2))
    return g, rv, tv, obj, img, view


@needs_numba
@pytest.mark.parametrize("model", list(COEFS))
def test_kernel_blocks_match_the_numpy_twin(model: str) -> None:
    g, rv, tv, obj, img, view = _scene(model)
    if model == "kannala_brandt":  # a point on the axis: the limit of θ_d / r
        rv[1] = [0.0, 0.0, 0.0]
        tv[1] = [0.0, 0.0, 4.0]
        obj[np.flatnonzero(view == 1)[0]] = 0.0
    r0, b0 = normal_blocks(g, rv, tv, obj, img, view, model=model, kernel=False)
    r1, b1 = normal_blocks(g, rv, tv, obj, img, view, model=model, kernel=True)
    np.testing.assert_allclose(r1, r0, rtol=0, atol=1e-12 * np.abs(r0).max())
    assert b0 is not None and b1 is not None
    for want, got in zip(b0, b1, strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    r2, none = normal_blocks(g, rv, tv, obj, img, view, model=model, jac=False, kernel=True)
    assert none is None
    np.testing.assert_array_equal(r2, r1)


@needs_numba
@pytest.mark.parametrize("model", ["rational", "kannala_brandt"])
def test_kernel_gives_inf_behind_the_camera(model: str) -> None:
    g, rv, tv, obj, img, view = _scene(model)
    tv[2, 2] = -tv[2, 2]  # view 2 behind the camera
    r0, _ = normal_blocks(g, rv, tv, obj, img, view, model=model, jac=False, kernel=False)
    r1, _ = normal_blocks(g, rv, tv, obj, img, view, model=model, jac=False, kernel=True)
    np.testing.assert_array_equal(np.isinf(r1), np.isinf(r0))
    assert np.all(np.isinf(r1[view == 2])) and np.all(np.isfinite(r1[view != 2]))


def _dense(blocks: tuple) -> tuple[np.ndarray, np.ndarray]:
    Ug, W, U, bg, bp = blocks
    n, V = Ug.shape[0], U.shape[0]
    A = np.zeros((n + 6 * V, n + 6 * V))
    A[:n, :n] = Ug
    for k in range(V):
        c = n + 6 * k
        A[:n, c : c + 6] = W[k]
        A[c : c + 6, :n] = W[k].T
        A[c : c + 6, c : c + 6] = U[k]
    return A, np.concatenate([bg, bp.ravel()])


@pytest.mark.parametrize("model", list(COEFS))
def test_schur_step_is_the_dense_solve(model: str) -> None:
    g, rv, tv, obj, img, view = _scene(model, seed=1)
    _, blocks = normal_blocks(g, rv, tv, obj, img, view, model=model, kernel=False)
    assert blocks is not None
    A, b = _dense(blocks)
    d = np.diag(A).copy()
    # the rational model's terms nearly share a factor: undamped, its system is too ill
    # conditioned for two solvers to agree
    for lam in (1e-3, 10.0) if model == "rational" else (1e-12, 1e-3, 10.0):
        want = np.linalg.solve(A + lam * np.diag(d), -b)
        sg, sp = schur_step(*blocks, lam)
        got = np.concatenate([sg, sp.ravel()])
        np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-9 * np.abs(want).max())


def test_statistics_are_the_dense_inverse_and_condition() -> None:
    g, rv, tv, obj, img, view = _scene("brown_conrady", seed=2)
    _, blocks = normal_blocks(g, rv, tv, obj, img, view, kernel=False)
    assert blocks is not None
    A, _ = _dense(blocks)
    d = np.sqrt(np.diag(A))
    An = A / np.outer(d, d)
    want = np.sqrt(np.diag(np.linalg.inv(An)) / d**2 * 0.25)
    std, cond = _statistics(blocks, 0.25 * 100, 100)
    np.testing.assert_allclose(std, want, rtol=1e-8)
    exact = np.linalg.cond(An)
    assert exact * (1 - 1e-9) <= cond < COND_WARN  # a bound above the condition number
    # a matrix that may be near singular: its condition number itself
    Ug, W, U, bg, bp = blocks
    Ug = Ug.copy()
    Ug[1] = Ug[0] * (1 + 1e-15)
    Ug[:, 1] = Ug[:, 0] * (1 + 1e-15)
    _, cond = _statistics((Ug, W, U, bg, bp), 1.0, 100)
    A, _ = _dense((Ug, W, U, bg, bp))
    d = np.sqrt(np.diag(A))
    assert cond == np.linalg.cond(A / np.outer(d, d))


@needs_numba
@pytest.mark.parametrize("model", list(COEFS))
def test_refinement_with_and_without_the_kernel(model: str) -> None:
    g, rv, tv, obj, img, view = _scene(model, seed=3)
    rng = np.random.default_rng(4)
    g0 = g * (1 + rng.normal(0, 1e-3, g.size))
    free = np.ones(g.size, bool)
    free[4] = False  # skew fixed
    a, b = (
        refine(
            g0, rv + 0.01, tv * 1.01, obj, img, view, free,
            max_iter=1000, tol=1e-10, model=model, kernel=kernel,
        )
        for kernel in (False, True)
    )  # fmt: skip
    assert a.n_iter == b.n_iter
    # the rational model stops somewhere along its long valley (hundreds of iterations): the
    # two paths' rounding moves that point by about 1e-8
    rtol = 1e-6 if model == "rational" else 1e-9
    np.testing.assert_allclose(b.globals_, a.globals_, rtol=rtol, atol=1e-12)
    np.testing.assert_allclose(b.residuals, a.residuals, rtol=0, atol=1e3 * rtol)
    np.testing.assert_allclose(b.std_globals, a.std_globals, rtol=1e3 * rtol)


def test_padded_homographies_are_each_views_own() -> None:
    rng = np.random.default_rng(5)
    board = checkerboard_points((7, 5), 1.0)
    objs, imgs = [], []
    for k, n in enumerate((35, 20, 4, 9, 35)):
        H = np.array([[50.0, 3, 100 + k], [2, 45, 80], [1e-3, 2e-3, 1]])
        H[:2, :2] += rng.normal(0, 5, (2, 2))
        o = board[rng.permutation(35)[:n]] if n != 4 else board[[0, 6, 28, 34]]
        p = o[:, :2] @ H[:2, :2].T + H[:2, 2]
        p = p / (o[:, :2] @ H[2, :2] + 1)[:, None] + rng.normal(0, 0.1, (n, 2))
        objs.append(o)
        imgs.append(p)
    got = homographies_of(objs, imgs)
    for k, (o, i) in enumerate(zip(objs, imgs, strict=True)):
        want = np.asarray(estimate_homography(o[:, :2], i))
        np.testing.assert_allclose(got[k], want, rtol=1e-9, atol=1e-12 * np.abs(want).max())
    np.testing.assert_allclose(homographies(objs, imgs), got, rtol=0, atol=0)
    # a view whose points are collinear is refused as alone
    objs[1] = np.c_[np.arange(6.0), np.arange(6.0), np.zeros(6)]
    imgs[1] = objs[1][:, :2] * 10
    with pytest.raises(DegenerateConfigurationError) as alone:
        estimate_homography(objs[1][:, :2], imgs[1])
    with pytest.raises(DegenerateConfigurationError) as batch:
        homographies_of(objs, imgs)
    assert str(batch.value) == str(alone.value)


def test_views_checked_in_one_pass_as_one_by_one() -> None:
    obj = checkerboard_points((4, 3))
    img = obj[:, :2] * 10.0
    objs, imgs = _views([obj, obj[:5]], [img, img[:5]])
    assert objs[0] is obj and imgs[1].shape == (5, 2)
    bad = img.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InvalidInputError, match=r"image_points\[1\] contains NaN"):
        _views([obj, obj], [img, bad])
    with pytest.raises(InvalidInputError, match=r"within"):
        _views([obj, obj * 1e101], [img, img])
    # a list of lists, float32: the per-view path, the same arrays
    o2, i2 = _views([obj.tolist()], [img.astype(np.float32)])
    np.testing.assert_array_equal(o2[0], obj)
    assert i2[0].dtype == np.float64


@needs_numba
def test_calibration_with_and_without_the_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    """The whole calibration, the kernel's path against the NumPy path, on views of OpenCV's
    sample board sizes (a synthetic camera with Brown-Conrady distortion)."""
    from imageform.geometry import BrownConrady, project_points_distorted, rvec_to_matrix
    from imageform.geometry import calibration_refine as cr

    rng = np.random.default_rng(6)
    obj = checkerboard_points((9, 6), 25.0)
    K = np.array([[800.0, 0, 320], [0, 810, 240], [0, 0, 1]])
    uv = []
    for _ in range(8):
        r = rng.normal(0, 0.35, 3)
        t = np.array([-100.0, -60.0, 450.0]) + rng.normal(0, 20, 3)
        p = project_points_distorted(obj, K, rvec_to_matrix(r), t, BrownConrady(k1=-0.2, k2=0.1))
        uv.append(np.asarray(p[0]) + rng.normal(0, 0.2, (len(obj), 2)))
    a = calibrate_camera([obj] * 8, uv, (640, 480))
    real = cr.refine
    monkeypatch.setattr(
        "imageform.geometry.calibration.refine", lambda *a, **k: real(*a, **k, kernel=False)
    )
    b = calibrate_camera([obj] * 8, uv, (640, 480))
    np.testing.assert_allclose(a.K, b.K, rtol=1e-9)
    np.testing.assert_allclose(a.distortion.coeffs, b.distortion.coeffs, rtol=1e-7, atol=1e-12)
    assert a.rms == pytest.approx(b.rms, rel=1e-9)
