"""Batched minimal and linear solvers of epipolar geometry (no input checks: callers check).

- :func:`f8` normalised 8-point (Hartley 1997), :func:`f7` 7-point (cubic in the pencil),
  :func:`e5` 5-point essential matrix (Nister 2004, solved by the action matrix of
  Stewenius, Engels & Nister 2006), :func:`sampson_sq` the Sampson error.

Internal to :mod:`imageform.geometry`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imageform.geometry._robust_core import hartley

__all__ = ["e5", "epipolar_rows", "f7", "f8", "null_space", "rank2", "sampson_sq"]

F64 = NDArray[np.float64]


def epipolar_rows(p1: F64, p2: F64) -> F64:
    """Rows ``x2 ⊗ x1`` (..., N, 9) of the linear system ``x2ᵀ F x1 = 0`` (F row-major)."""
    h1 = np.concatenate([p1, np.ones(p1.shape[:-1] + (1,))], axis=-1)
    h2 = np.concatenate([p2, np.ones(p2.shape[:-1] + (1,))], axis=-1)
    return (h2[..., :, None] * h1[..., None, :]).reshape(*p1.shape[:-1], 9)


def null_space(A: F64) -> F64:
    """Return an orthonormal basis (B, n, n - m) of the null space of each full-rank ``A``.

    ``A`` is (B, m, n), m < n; the basis comes from the complete QR of ``Aᵀ`` (cheaper than
    the SVD, as exact).
    """
    m = A.shape[-2]
    return np.linalg.qr(np.swapaxes(A, -1, -2), mode="complete")[0][..., m:]


def rank2(F: F64) -> F64:
    """Nearest rank-2 matrix (Frobenius), batched."""
    U, s, Vt = np.linalg.svd(F)
    s[..., 2] = 0.0
    return (U * s[..., None, :]) @ Vt


def f8(p1: F64, p2: F64, w: F64 | None = None) -> F64:
    """Estimate fundamental matrices (B, 3, 3) from (B, N >= 8, 2) pairs by the 8-point algorithm.

    The normalised 8-point algorithm (Hartley 1997; H&Z Algorithm 11.1); optional per-point
    weights ``w``.
    """
    n1, T1 = hartley(p1)
    n2, T2 = hartley(p2)
    A = epipolar_rows(n1, n2)
    if w is not None:
        A = A * w[..., None]
    f = np.linalg.eigh(np.swapaxes(A, -1, -2) @ A)[1][..., 0]
    Fn = rank2(f.reshape(*f.shape[:-1], 3, 3))
    F = np.swapaxes(T2, -1, -2) @ Fn @ T1
    return F / np.linalg.norm(F, axis=(-2, -1), keepdims=True)


# det(a F1 + (1 - a) F2) at a = 0, 1, -1, 2 -> cubic coefficients (c0, c1, c2, c3)
_VAND_INV = np.linalg.inv(np.vander(np.array([0.0, 1.0, -1.0, 2.0]), 4, increasing=True))


def f7(p1: F64, p2: F64) -> tuple[F64, NDArray[np.intp]]:
    """Up to three fundamental matrices per 7-point sample (B, 7, 2).

    The null space of the 7 x 9 system is a pencil ``F = a F1 + (1 - a) F2``; ``det F = 0``
    is a cubic in ``a`` whose real roots are the solutions (H&Z sec. 11.1.2). Returns the
    matrices (M, 3, 3), unit Frobenius norm, and the sample each comes from (M,).
    """
    n1, T1 = hartley(p1)
    n2, T2 = hartley(p2)
    A = epipolar_rows(n1, n2)
    Nul = null_space(A)  # (B, 9, 2)
    F1 = Nul[:, :, 1].reshape(-1, 3, 3)
    F2 = Nul[:, :, 0].reshape(-1, 3, 3)
    alphas = np.array([0.0, 1.0, -1.0, 2.0])
    dets = np.linalg.det(
        alphas[None, :, None, None] * F1[:, None] + (1 - alphas)[None, :, None, None] * F2[:, None]
    )
    c = dets @ _VAND_INV.T  # (B, 4): c0 + c1 a + c2 a² + c3 a³
    B = c.shape[0]
    scale = np.max(np.abs(c), axis=1)
    lead_ok = np.abs(c[:, 3]) > 1e-10 * scale
    comp = np.zeros((B, 3, 3))
    c3 = np.where(lead_ok, c[:, 3], 1.0)
    comp[:, 0, :] = -c[:, 2::-1] / c3[:, None]
    comp[:, 1, 0] = comp[:, 2, 1] = 1.0
    roots = np.linalg.eigvals(comp)
    real = (np.abs(roots.imag) <= 1e-8 * (1 + np.abs(roots.real))) & lead_ok[:, None]
    src, k = np.nonzero(real)
    a = roots.real[src, k]
    Fn = a[:, None, None] * F1[src] + (1 - a)[:, None, None] * F2[src]
    F = np.swapaxes(T2[src], -1, -2) @ Fn @ T1[src]
    F = F / np.linalg.norm(F, axis=(-2, -1), keepdims=True)
    return F, src


def sampson_sq(F: F64, p1: F64, p2: F64) -> F64:
    r"""Squared Sampson distances (..., N) of pairs (N, 2) under ``F`` (..., 3, 3).

    .. math:: d^2 = \frac{(x_2^T F x_1)^2}{(F x_1)_1^2 + (F x_1)_2^2 + (F^T x_2)_1^2
              + (F^T x_2)_2^2}

    (H&Z eq. 11.9), the first-order geometric error in the units of the points.
    """
    h1 = np.concatenate([p1, np.ones((p1.shape[0], 1))], axis=-1)
    h2 = np.concatenate([p2, np.ones((p2.shape[0], 1))], axis=-1)
    Fx1 = np.tensordot(F, h1, axes=([-1], [1]))  # (..., 3, N)
    Ftx2 = np.tensordot(np.swapaxes(F, -1, -2), h2, axes=([-1], [1]))
    num = np.einsum("...in,ni->...n", Fx1, h2)
    den = Fx1[..., 0, :] ** 2 + Fx1[..., 1, :] ** 2 + Ftx2[..., 0, :] ** 2 + Ftx2[..., 1, :] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return num * num / den


# ---- 5-point: polynomial arithmetic in (x, y, z) up to degree 3 -------------------------
_CUBICS = [
    (3, 0, 0),
    (2, 1, 0),
    (2, 0, 1),
    (1, 2, 0),
    (1, 1, 1),
    (1, 0, 2),
    (0, 3, 0),
    (0, 2, 1),
    (0, 1, 2),
    (0, 0, 3),
]
_BASIS = [
    (2, 0, 0),
    (1, 1, 0),
    (1, 0, 1),
    (0, 2, 0),
    (0, 1, 1),
    (0, 0, 2),
    (1, 0, 0),
    (0, 1, 0),
    (0, 0, 1),
    (0, 0, 0),
]
_MONO = _CUBICS + _BASIS
_IDX = {m: i for i, m in enumerate(_MONO)}
_PROD = np.zeros((20, 20, 20))
for _i, _a in enumerate(_MONO):
    for _j, _b in enumerate(_MONO):
        _m = (_a[0] + _b[0], _a[1] + _b[1], _a[2] + _b[2])
        if sum(_m) <= 3:
            _PROD[_i, _j, _IDX[_m]] = 1.0
_LIN = [_IDX[m] for m in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)]]
_QUAD = list(range(10, 20))
# products of (linear x linear) -> quadratic (16, 10) and (quadratic x linear) -> cubic (40, 20)
_T_LL = _PROD[np.ix_(_LIN, _LIN, _QUAD)].reshape(16, 10)
_T_QL = _PROD[np.ix_(_QUAD, _LIN, list(range(20)))].reshape(40, 20)
# multiplication by x of each basis monomial, as an index into _MONO
_XB = [_IDX[(b[0] + 1, b[1], b[2])] for b in _BASIS]


def _constraints(L: F64) -> F64:
    """Build the ten cubics (B, 10, 20) from the linear entries ``L`` (B, 3, 3, 4) of ``E``."""
    B = L.shape[0]
    # E Eᵀ (B, 3, 3, 10): sum_k E_ik E_jk
    eet = np.einsum("bikp,bjkq->bijpq", L, L).reshape(B, 3, 3, 16) @ _T_LL
    tr = eet[:, 0, 0] + eet[:, 1, 1] + eet[:, 2, 2]  # (B, 10)
    eete = np.einsum("bikp,bkjq->bijpq", eet, L).reshape(B, 3, 3, 40) @ _T_QL
    tre = np.einsum("bp,bijq->bijpq", tr, L).reshape(B, 3, 3, 40) @ _T_QL
    trace_rows = (2.0 * eete - tre).reshape(B, 9, 20)
    # det E = sum_j E_0j cof_0j, cofactors from the rows 1 and 2 (quadratics)
    c = np.einsum("bp,bq->bpq", L[:, 1, 1], L[:, 2, 2]) - np.einsum(
        "bp,bq->bpq", L[:, 1, 2], L[:, 2, 1]
    )
    c1 = np.einsum("bp,bq->bpq", L[:, 1, 2], L[:, 2, 0]) - np.einsum(
        "bp,bq->bpq", L[:, 1, 0], L[:, 2, 2]
    )
    c2 = np.einsum("bp,bq->bpq", L[:, 1, 0], L[:, 2, 1]) - np.einsum(
        "bp,bq->bpq", L[:, 1, 1], L[:, 2, 0]
    )
    cof = np.stack([c, c1, c2], axis=1).reshape(B, 3, 16) @ _T_LL  # (B, 3, 10)
    det = np.einsum("bjp,bjq->bpq", cof, L[:, 0]).reshape(B, 40) @ _T_QL
    return np.concatenate([det[:, None], trace_rows], axis=1)


def e5(q1: F64, q2: F64) -> tuple[F64, NDArray[np.intp]]:
    """Essential matrices from 5 normalised correspondences (B, 5, 2) per sample.

    ``E = x X + y Y + z Z + W`` over the null space of the 5 x 9 system; the ten cubic
    constraints ``det E = 0`` and ``2 E Eᵀ E - tr(E Eᵀ) E = 0`` (Nister 2004, eqs. 1-2) are
    reduced by Gauss-Jordan elimination on the ten cubic monomials, and the solutions are the
    eigenvectors of the 10 x 10 action matrix of multiplication by ``x`` on the basis
    ``{x², xy, xz, y², yz, z², x, y, z, 1}`` (Stewenius, Engels & Nister 2006). Returns the
    real solutions (M, 3, 3) with unit Frobenius norm and the sample each comes from (M,).
    """
    A = epipolar_rows(q1, q2)  # (B, 5, 9)
    Bn = A.shape[0]
    # X, Y, Z, W (B, 4, 9), mixed by a fixed rotation: the parametrisation E = xX + yY + zZ + W
    # misses a solution with no W component, which a structured input (pure translation)
    # can make exact in the QR basis
    basis = _MIX @ np.swapaxes(null_space(A), 1, 2)
    # linear polynomial of each E entry: coefficients of x, y, z, 1 (B, 3, 3, 4)
    L = np.moveaxis(basis, 1, 2).reshape(Bn, 3, 3, 4)
    M = _constraints(L)
    with np.errstate(all="ignore"):
        try:
            C = np.linalg.solve(M[:, :, :10], M[:, :, 10:])  # cubic_i = -C_i . basis
        except np.linalg.LinAlgError:
            C = np.stack([_lstsq(m[:, :10], m[:, 10:]) for m in M])
    act = np.zeros((Bn, 10, 10))
    for j in range(10):
        t = _XB[j]
        if t < 10:
            act[:, j, :] = -C[:, t, :]
        else:
            act[:, j, t - 10] = 1.0
    ok = np.all(np.isfinite(act), axis=(1, 2))
    act[~ok] = 0.0
    w, v = np.linalg.eig(act)
    real = (np.abs(w.imag) <= 1e-8 * (1 + np.abs(w.real))) & ok[:, None]
    src, k = np.nonzero(real)
    vec = v[src, :, k].real  # (M, 10)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = w.real[src, k]
        y = vec[:, 7] / vec[:, 9]
        z = vec[:, 8] / vec[:, 9]
    coef = np.stack([x, y, z, np.ones_like(x)], axis=-1)  # (M, 4)
    Es = np.einsum("mk,mkj->mj", coef, basis[src]).reshape(-1, 3, 3)
    Es = Es / np.linalg.norm(Es, axis=(-2, -1), keepdims=True)
    good = np.all(np.isfinite(Es), axis=(-2, -1))
    return Es[good], src[good]


_MIX = np.linalg.qr(np.random.default_rng(20041).normal(size=(4, 4)))[0]


def _lstsq(a: F64, b: F64) -> F64:
    return np.asarray(np.linalg.lstsq(a, b, rcond=None)[0], dtype=np.float64)
