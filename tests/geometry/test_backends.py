"""Array-API backends: array-api-strict and PyTorch give NumPy's numbers; gradients flow."""

from __future__ import annotations

import numpy as np
import pytest

from imageform import geometry as g
from tests.helpers import array_type, to_backend, to_np

K = np.array([[500.0, 2.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]])
R = g.rvec_to_matrix([0.1, -0.2, 0.3])
T = np.array([0.2, -0.1, 4.0])


def test_projection_same_numbers(xp_name: str) -> None:
    rng = np.random.default_rng(40)
    X = rng.uniform(-1, 1, size=(7, 3))
    X[3, 2] = -10.0  # behind the camera
    ref_uv, ref_valid = g.project_points(X, K, R, T)
    uv, valid = g.project_points(
        to_backend(X, xp_name),
        to_backend(K, xp_name),
        to_backend(R, xp_name),
        to_backend(T, xp_name),
    )
    assert isinstance(uv, array_type(xp_name))
    np.testing.assert_allclose(to_np(uv), ref_uv, atol=1e-12)
    np.testing.assert_array_equal(to_np(valid), ref_valid)


def test_numpy_parameters_with_foreign_points(xp_name: str) -> None:
    X = to_backend([[0.1, 0.2, 3.0]], xp_name)
    uv, _ = g.project_points(X, K, R, T)
    assert isinstance(uv, array_type(xp_name))


@pytest.mark.parametrize(
    "fn, args",
    [
        (g.to_homogeneous, ([[1.0, 2.0], [3.0, 4.0]],)),
        (g.rvec_to_matrix, ([0.1, 0.2, 0.3],)),
        (g.matrix_to_rvec, (R,)),
        (g.matrix_to_quaternion, (R,)),
        (g.quaternion_to_matrix, ([0.9, 0.1, 0.2, 0.3],)),
        (lambda a: g.euler_to_matrix(a, "ZYX"), ([0.1, 0.2, 0.3],)),
        (lambda a: g.matrix_to_euler(a, "xyz"), (R,)),
        (lambda P: g.decompose_projection_matrix(P)[0], (g.projection_matrix(K, R, T),)),
        (lambda P: g.decompose_projection_matrix(P)[1], (g.projection_matrix(K, R, T),)),
        (lambda k: g.vanishing_point(k, [1.0, 0.0, 2.0]), (K,)),
        (lambda k: g.horizon_line(k), (K,)),
        (
            lambda s: g.estimate_homography(s, s * 2.0 + 1.0),
            ([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.3, 0.7]],),
        ),
        (lambda uv: g.unproject(uv, 2.0, K, R, T), ([[100.0, 50.0]],)),
        (lambda uv: g.backproject(uv, K, R), ([[100.0, 50.0]],)),
    ],
)
def test_functions_same_numbers(xp_name: str, fn: object, args: tuple[object, ...]) -> None:
    ref = fn(*[np.asarray(a, dtype=float) for a in args])  # type: ignore[operator]
    out = fn(*[to_backend(a, xp_name) for a in args])  # type: ignore[operator]
    assert isinstance(out, array_type(xp_name))
    np.testing.assert_allclose(to_np(out), ref, atol=1e-10)


def test_estimate_projection_matrix_strict() -> None:
    rng = np.random.default_rng(41)
    X = rng.uniform(-1, 1, size=(10, 3))
    uv = g.project_points(X, K, R, T).uv
    ref = g.estimate_projection_matrix(X, uv)
    out = g.estimate_projection_matrix(
        to_backend(X, "array_api_strict"), to_backend(uv, "array_api_strict")
    )
    np.testing.assert_allclose(to_np(out), ref, atol=1e-10)


def test_torch_gradients_flow_through_projection() -> None:
    torch = pytest.importorskip("torch")
    X = torch.tensor([[0.3, -0.2, 2.0], [0.0, 0.0, -10.0]], dtype=torch.float64, requires_grad=True)
    Kt = torch.tensor(K, requires_grad=True)
    rvec = torch.tensor([0.1, -0.2, 0.3], dtype=torch.float64, requires_grad=True)
    uv, valid = g.project_points(X, Kt, g.rvec_to_matrix(rvec), torch.tensor(T))
    loss = torch.nansum(uv)
    loss.backward()
    assert valid.tolist() == [True, False]
    # finite gradients everywhere, zero for the point behind the camera
    assert (
        torch.isfinite(X.grad).all()
        and torch.isfinite(Kt.grad).all()
        and torch.isfinite(rvec.grad).all()
    )
    assert torch.all(X.grad[1] == 0)
    # d(u)/d(fx) = x = X_c / Z_c for the valid point
    Xc = g.rvec_to_matrix(rvec.detach().numpy()) @ X.detach().numpy()[0] + T
    assert float(Kt.grad[0, 0]) == pytest.approx(Xc[0] / Xc[2])


def test_torch_gradcheck_projection() -> None:
    torch = pytest.importorskip("torch")
    X = torch.tensor([[0.3, -0.2, 2.0], [0.1, 0.4, 3.0]], dtype=torch.float64, requires_grad=True)

    def f(pts: object) -> object:
        return g.project_points(pts, K, R, T).uv

    assert torch.autograd.gradcheck(f, (X,))


def test_float32_torch_stays_float32() -> None:
    torch = pytest.importorskip("torch")
    X = torch.zeros((2, 3), dtype=torch.float32) + torch.tensor([0.0, 0.0, 2.0])
    uv, _ = g.project_points(X, K)
    assert uv.dtype == torch.float32


def test_dask_projection_is_lazy_and_chunkwise() -> None:
    da = pytest.importorskip("dask.array")
    rng = np.random.default_rng(42)
    Xn = rng.uniform(-1, 1, size=(40_000, 3)) + [0, 0, 3]
    Xn[::9, 2] = -1.0
    X = da.from_array(Xn, chunks=(10_000, 3))
    uv, valid = g.project_points(X, K, R, T)
    assert isinstance(uv, da.Array) and uv.chunks[0] == X.chunks[0]
    ref_uv, ref_valid = g.project_points(Xn, K, R, T)
    np.testing.assert_allclose(uv.compute(), ref_uv, atol=1e-9)
    np.testing.assert_array_equal(valid.compute(), ref_valid)
