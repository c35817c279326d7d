"""Distortion models: values, round trips, kernels vs twins, OpenCV cross-checks, errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError
from imageform.geometry._distortion_xp import bc_undistort_xp, kb_undistort_xp
from imageform.geometry.distortion import (
    BrownConrady,
    DivisionModel,
    KannalaBrandt,
    _project_xp,
    project_points_distorted,
)
from tests.helpers import to_backend, to_np

cv2 = pytest.importorskip("cv2")

# OpenCV tutorial calibration of the shared left*.jpg set (shared/data/README.md).
LEFT_K = np.array([[536.07345314, 0, 342.37046827], [0, 536.01636274, 235.53687064], [0, 0, 1.0]])
LEFT_D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
RATIONAL = BrownConrady(k1=0.1, k2=-0.05, p1=0.001, p2=-0.0005, k3=0.01, k4=0.2, k5=-0.02, k6=0.005)


def _grid(n: int = 41, lim: float = 0.6) -> np.ndarray:
    g = np.linspace(-lim, lim, n)
    return np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)


# -- values and physics ---------------------------------------------------------------------
def test_brown_conrady_value_by_hand() -> None:
    # x = 0.5, k1 = -0.2: r² = 0.25, factor 1 - 0.05 = 0.95 (Brown 1966 radial term)
    assert BrownConrady(k1=-0.2).distort([0.5, 0.0]).tolist() == pytest.approx([0.475, 0.0])


def test_tangential_terms_by_hand() -> None:
    # x = y = 0.1, p1 = 0.01: x_d = x + 2 p1 x y, y_d = y + p1 (r² + 2 y²)
    out = BrownConrady(p1=0.01).distort([0.1, 0.1])
    assert out.tolist() == pytest.approx([0.1 + 2e-4, 0.1 + 0.01 * 0.04], abs=1e-15)


@pytest.mark.parametrize("model", [BrownConrady(k1=-0.3), DivisionModel(k1=-0.3)])
def test_barrel_pulls_points_inwards(model: object) -> None:
    xy = _grid(11, 0.5)[1:]
    xd = np.asarray(model.distort(xy))  # type: ignore[attr-defined]
    r, rd = np.hypot(*xy.T), np.hypot(*xd.T)
    assert np.all(rd[r > 0] < r[r > 0])


@pytest.mark.parametrize("model", [BrownConrady(k1=0.3), DivisionModel(k1=0.3)])
def test_pincushion_pushes_points_outwards(model: object) -> None:
    xy = _grid(11, 0.5)
    xd = np.asarray(model.distort(xy))  # type: ignore[attr-defined]
    r, rd = np.hypot(*xy.T), np.hypot(*xd.T)
    assert np.all(rd[r > 0] > r[r > 0])


def test_division_single_parameter_closed_form() -> None:
    # r_d = (1 - sqrt(1 - 4 λ r_u²)) / (2 λ r_u) (Fitzgibbon 2001, solved for r_d)
    lam, ru = -0.2, 0.5
    want = (1 - np.sqrt(1 - 4 * lam * ru**2)) / (2 * lam * ru)
    assert DivisionModel(k1=lam).distort([ru, 0.0])[0] == pytest.approx(want, abs=1e-14)


def test_division_no_distorted_point_is_nan() -> None:
    # k1 > 0: r_u (1 + k1 r_d²) = r_d has no real root when 4 k1 r_u² > 1
    out = DivisionModel(k1=1.0).distort([[0.6, 0.0], [0.1, 0.0]])
    assert np.isnan(out[0]).all() and np.isfinite(out[1]).all()


def test_kannala_brandt_equidistant_identity() -> None:
    # with all k = 0, θ_d = θ = atan(r) (equidistant projection)
    out = KannalaBrandt().distort([[1.0, 0.0], [0.0, 0.0]])
    np.testing.assert_allclose(out, [[np.pi / 4, 0.0], [0.0, 0.0]], atol=1e-15)


# -- inverses and convergence report ----------------------------------------------------------
MODELS = [
    BrownConrady.from_opencv(LEFT_D),
    RATIONAL,
    BrownConrady(k1=0.2, p2=0.003),
    DivisionModel(k1=-0.25, k2=0.02),
    KannalaBrandt(0.05, -0.01, 0.002, -0.0005),
]


@pytest.mark.parametrize("model", MODELS, ids=lambda m: type(m).__name__)
def test_round_trip_grid(model: object) -> None:
    xy = _grid(41, 0.55)
    back, ok = model.undistort(model.distort(xy))  # type: ignore[attr-defined]
    assert ok.all()
    np.testing.assert_allclose(back, xy, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    x=st.floats(-0.5, 0.5),
    y=st.floats(-0.5, 0.5),
    k1=st.floats(-0.25, 0.25),
    k2=st.floats(-0.05, 0.05),
    p1=st.floats(-0.002, 0.002),
)
def test_round_trip_property(x: float, y: float, k1: float, k2: float, p1: float) -> None:
    m = BrownConrady(k1=k1, k2=k2, p1=p1)
    back, ok = m.undistort(m.distort(np.array([x, y])))
    assert bool(ok)
    np.testing.assert_allclose(back, [x, y], atol=1e-11)


@settings(max_examples=40, deadline=None)
@given(x=st.floats(-2, 2), y=st.floats(-2, 2), k1=st.floats(-0.05, 0.05))
def test_fisheye_round_trip_property(x: float, y: float, k1: float) -> None:
    m = KannalaBrandt(k1=k1)
    back, ok = m.undistort(m.distort(np.array([x, y])))
    assert bool(ok)
    np.testing.assert_allclose(back, [x, y], rtol=1e-10, atol=1e-12)


def test_undistort_reports_points_beyond_the_valid_radius() -> None:
    # k1 = -0.5: r (1 - 0.5 r²) peaks at r = sqrt(2/3) with r_d = 0.544; r_d = 0.7 has no preimage
    m = BrownConrady(k1=-0.5)
    xy, ok = m.undistort([[0.3, 0.0], [0.7, 0.0]])
    assert ok.tolist() == [True, False]
    assert np.isnan(xy[1]).all() and np.isfinite(xy[0]).all()


def test_undistort_max_iter_too_small_is_reported() -> None:
    xy, ok = BrownConrady.from_opencv(LEFT_D).undistort([[0.5, 0.4]], max_iter=1)
    assert not ok[0] and np.isnan(xy).all()


def test_fisheye_beyond_90_degrees_not_converged() -> None:
    # θ_d > the polynomial's maximum over [0, π/2) cannot be inverted to a finite (x, y)
    _, ok = KannalaBrandt(k1=-0.2).undistort([[2.5, 0.0]])
    assert not ok[0]


# -- OpenCV cross-checks (labelled: OpenCV is an oracle, not the truth) ------------------------
def test_cross_check_cv2_project_points_5_coeffs() -> None:
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(-1, 1, (2000, 2)), rng.uniform(2, 6, 2000)]
    rvec = np.array([0.1, -0.2, 0.05])
    R = cv2.Rodrigues(rvec)[0]
    t = np.array([0.1, -0.05, 0.3])
    uv, ok = project_points_distorted(pts, LEFT_K, R, t, BrownConrady.from_opencv(LEFT_D))
    ref = cv2.projectPoints(pts, rvec, t, LEFT_K, LEFT_D)[0].reshape(-1, 2)
    assert ok.all()
    np.testing.assert_allclose(uv, ref, atol=1e-9)


@pytest.mark.parametrize("n", [500, 50_000])  # twin path and numba path
def test_cross_check_cv2_project_points_rational(n: int) -> None:
    rng = np.random.default_rng(1)
    pts = np.c_[rng.uniform(-1, 1, (n, 2)), rng.uniform(2, 6, n)]
    uv, _ = project_points_distorted(pts, LEFT_K, np.eye(3), np.zeros(3), RATIONAL)
    ref = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), LEFT_K, np.array(RATIONAL.coeffs))[0]
    np.testing.assert_allclose(uv, ref.reshape(-1, 2), atol=1e-9)


@pytest.mark.parametrize("n", [200, 20_000])
def test_cross_check_cv2_undistort_points(n: int) -> None:
    rng = np.random.default_rng(2)
    m = BrownConrady.from_opencv(LEFT_D)
    xy = rng.uniform(-0.5, 0.5, (n, 2))
    xd = m.distort(xy)
    px = (xd * [LEFT_K[0, 0], LEFT_K[1, 1]] + LEFT_K[:2, 2])[:, None]
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-15)
    ref = cv2.undistortPoints(px, LEFT_K, LEFT_D, R=None, P=None, criteria=crit).reshape(-1, 2)
    ours, ok = m.undistort(xd)
    assert ok.all()
    np.testing.assert_allclose(ours, ref, atol=1e-10)
    np.testing.assert_allclose(ours, xy, atol=1e-12)


def test_cross_check_cv2_fisheye() -> None:
    rng = np.random.default_rng(3)
    m = KannalaBrandt(0.05, -0.01, 0.002, -0.0005)
    xy = rng.uniform(-1.5, 1.5, (5000, 2))
    d = np.array(m.coeffs)
    ref = cv2.fisheye.distortPoints(xy[:, None], np.eye(3), d).reshape(-1, 2)
    np.testing.assert_allclose(m.distort(xy), ref, atol=1e-12)
    ref_u = cv2.fisheye.undistortPoints(ref[:, None], np.eye(3), d).reshape(-1, 2)
    ours, ok = m.undistort(ref)
    assert ok.all()
    np.testing.assert_allclose(ours, ref_u, atol=1e-9)


# -- numba kernels against their plain twins --------------------------------------------------
def test_kernels_match_twins() -> None:
    import array_api_compat.numpy as xp

    from imageform._kernels.distortion import (
        brown_conrady_distort,
        brown_conrady_undistort,
        kannala_brandt_distort,
        kannala_brandt_undistort,
    )
    from imageform.geometry._distortion_xp import bc_distort_xp, kb_distort_xp

    xy = np.ascontiguousarray(_grid(31, 0.6))
    for model, fwd, inv, twin_f, twin_i in (
        (RATIONAL, brown_conrady_distort, brown_conrady_undistort, bc_distort_xp, bc_undistort_xp),
        (
            KannalaBrandt(0.05, -0.01, 0.002, 0.0),
            kannala_brandt_distort,
            kannala_brandt_undistort,
            kb_distort_xp,
            kb_undistort_xp,
        ),
    ):
        c = np.asarray(model.coeffs)
        out = np.empty_like(xy)
        fwd(xy, c, out)
        np.testing.assert_allclose(out, twin_f(xy, model.coeffs, xp), atol=1e-14)
        back = np.empty_like(xy)
        ok = np.empty(len(xy), bool)
        inv(out, c, 20, 1e-14, back, ok)
        tb, tok = twin_i(out, model.coeffs, xp, 20, 1e-14)
        assert (ok == tok).all()
        np.testing.assert_allclose(back, tb, atol=1e-12)


def test_fused_projection_kernel_matches_twin() -> None:
    import array_api_compat.numpy as xp

    from imageform._kernels.project_distort import project_brown_conrady

    rng = np.random.default_rng(4)
    pts = np.c_[rng.uniform(-2, 2, (3000, 2)), rng.uniform(-1, 5, 3000)]
    R = cv2.Rodrigues(np.array([0.2, 0.1, -0.3]))[0]
    t = np.array([0.0, 0.1, 0.5])
    K = LEFT_K.copy()
    K[0, 1] = 0.7  # skew is honoured
    uv, ok = project_brown_conrady(pts, K, R, t, np.asarray(RATIONAL.coeffs))
    tw, tok = _project_xp(pts, K, R, t, RATIONAL, xp)
    assert (ok == tok).all() and (~ok).any()
    np.testing.assert_allclose(uv[ok], tw[ok], atol=1e-9)
    assert np.isnan(uv[~ok]).all()


def test_numba_dispatch_equals_twin_for_public_api(monkeypatch: pytest.MonkeyPatch) -> None:
    xy = np.random.default_rng(5).uniform(-0.5, 0.5, (20_000, 2))
    m = BrownConrady.from_opencv(LEFT_D)
    fast = m.undistort(m.distort(xy))[0]
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    slow = m.undistort(m.distort(xy))[0]
    np.testing.assert_allclose(fast, slow, atol=1e-12)


# -- projection semantics ---------------------------------------------------------------------
@pytest.mark.parametrize("n", [3, 30_000])
def test_points_behind_camera_are_nan_not_mirrored(n: int) -> None:
    pts = np.tile([[0.1, 0.2, 2.0], [0.1, 0.2, -2.0], [0.0, 0.0, 0.0]], (n // 3, 1))
    uv, ok = project_points_distorted(pts, LEFT_K, np.eye(3), np.zeros(3), BrownConrady(k1=0.1))
    assert ok.reshape(-1, 3).tolist()[0] == [True, False, False]
    assert np.isnan(uv[1::3]).all() and np.isnan(uv[2::3]).all()


def test_projection_batch_shape_and_no_distortion() -> None:
    pts = np.random.default_rng(6).uniform(1, 2, (2, 5, 3))
    uv, ok = project_points_distorted(pts, LEFT_K, np.eye(3), np.zeros(3), None)
    assert uv.shape == (2, 5, 2) and ok.shape == (2, 5)
    want = pts[..., :2] / pts[..., 2:] * [LEFT_K[0, 0], LEFT_K[1, 1]] + LEFT_K[:2, 2]
    np.testing.assert_allclose(uv, want, atol=1e-12)


# -- shapes, dtypes, backends -----------------------------------------------------------------
def test_batch_shapes_and_dtypes() -> None:
    m = BrownConrady(k1=-0.1, p1=0.001)
    xy = np.random.default_rng(7).uniform(-0.4, 0.4, (3, 4, 2))
    assert m.distort(xy).shape == (3, 4, 2)
    back, ok = m.undistort(m.distort(xy))
    assert back.shape == (3, 4, 2) and ok.shape == (3, 4)
    f32 = m.distort(xy.astype(np.float32))
    assert f32.dtype == np.float32
    b32, ok32 = m.undistort(f32)
    assert b32.dtype == np.float32 and ok32.all()
    # float32 stops at a residual of 64 ulp (7.6e-6) × (1 + |x_d|); error = residual / J
    np.testing.assert_allclose(b32, xy, atol=3e-5)
    assert m.distort(np.array([1, 0])).dtype == np.float64  # integer coordinates → float64


@pytest.mark.parametrize("model", MODELS, ids=lambda m: type(m).__name__)
def test_backends(model: object, xp_name: str) -> None:
    xy = _grid(7, 0.4)
    ref = np.asarray(model.distort(xy))  # type: ignore[attr-defined]
    got = model.distort(to_backend(xy, xp_name))  # type: ignore[attr-defined]
    assert (
        type(got).__module__.split(".")[0] == type(to_backend(xy, xp_name)).__module__.split(".")[0]
    )
    np.testing.assert_allclose(to_np(got), ref, atol=1e-14)
    back, ok = model.undistort(got)  # type: ignore[attr-defined]
    assert to_np(ok).all()
    np.testing.assert_allclose(to_np(back), xy, atol=1e-12)


@pytest.mark.filterwarnings("ignore:torch.asarray")
def test_torch_gradient_flows_through_distort() -> None:
    torch = pytest.importorskip("torch")
    x = torch.tensor([[0.3, -0.2]], dtype=torch.float64, requires_grad=True)
    BrownConrady(k1=-0.2, p2=0.01).distort(x).sum().backward()
    assert x.grad is not None and torch.isfinite(x.grad).all()


# -- bad input --------------------------------------------------------------------------------
def test_bad_inputs() -> None:
    m = BrownConrady(k1=0.1)
    with pytest.raises(
        InvalidInputError, match=r"expected xy of shape \(\.\.\., 2\), got \(4, 3\)"
    ):
        m.distort(np.zeros((4, 3)))
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        m.distort([np.nan, 0.0])
    with pytest.raises(InvalidInputError, match="max_iter"):
        m.undistort([0.1, 0.1], max_iter=0)
    with pytest.raises(InvalidInputError, match="tol"):
        m.undistort([0.1, 0.1], tol=-1.0)
    with pytest.raises(InvalidInputError, match="k1 as a finite number"):
        BrownConrady(k1=float("inf"))
    with pytest.raises(InvalidInputError, match="4, 5 or 8"):
        BrownConrady.from_opencv([0.1, 0.2, 0.3])
    with pytest.raises(InvalidInputError, match="rotation"):
        project_points_distorted([[0, 0, 1.0]], LEFT_K, 2 * np.eye(3), np.zeros(3), m)
    with pytest.raises(InvalidInputError, match="BrownConrady, DivisionModel"):
        project_points_distorted([[0, 0, 1.0]], LEFT_K, np.eye(3), np.zeros(3), "barrel")


@pytest.mark.slow
def test_projection_speed_vs_cv2() -> None:
    """The issue's target, scaled to 10^6 points: >= 5x cv2.projectPoints, within 1e-9 px."""
    import time

    rng = np.random.default_rng(8)
    n = 1_000_000
    pts = np.c_[rng.uniform(-1, 1, (n, 2)), rng.uniform(2, 6, n)]
    model = BrownConrady.from_opencv(LEFT_D)
    project_points_distorted(pts[:50_000], LEFT_K, np.eye(3), np.zeros(3), model)  # JIT warm-up

    def best(fn) -> float:  # type: ignore[no-untyped-def]
        ts = []
        for _ in range(3):
            t0 = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t0)
        return min(ts)

    t_if = best(lambda: project_points_distorted(pts, LEFT_K, np.eye(3), np.zeros(3), model))
    t_cv = best(lambda: cv2.projectPoints(pts, np.zeros(3), np.zeros(3), LEFT_K, LEFT_D))
    uv, _ = project_points_distorted(pts, LEFT_K, np.eye(3), np.zeros(3), model)
    ref = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), LEFT_K, LEFT_D)[0].reshape(-1, 2)
    assert np.max(np.abs(uv - ref)) < 1e-9
    assert t_cv / t_if >= 5.0


@pytest.mark.parametrize("model", MODELS, ids=lambda m: type(m).__name__)
def test_dask_run(model: object) -> None:
    da = pytest.importorskip("dask.array")
    xy = _grid(21, 0.5)
    lazy = da.from_array(xy, chunks=(100, 2))
    out = model.distort(lazy)  # type: ignore[attr-defined]
    assert isinstance(out, da.Array)
    np.testing.assert_allclose(np.asarray(out), model.distort(xy), atol=1e-15)  # type: ignore[attr-defined]
    back, ok = model.undistort(out)  # type: ignore[attr-defined]
    assert isinstance(back, da.Array) and bool(np.asarray(ok).all())
    np.testing.assert_allclose(np.asarray(back), xy, atol=1e-12)
