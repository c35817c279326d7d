"""numba kernel of :func:`imageform.geometry.find_essential_matrix` (see ``ransac``)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import (
    _F_ORTHO,
    _OPTS,
    _copy3,
    _epi_row,
    _fro_unit,
    _nullspace,
    _project_e,
    _refine_e,
    _refit_e,
    _sample,
    _score,
    _select,
    _support_count,
    _to_f,
    _trials_needed,
)

__all__ = ["essential_estimate"]

# ---- 5-point: polynomials in (x, y, z) up to degree 3, monomials as in geometry._minimal
_CUBICS = [(3, 0, 0), (2, 1, 0), (2, 0, 1), (1, 2, 0), (1, 1, 1)]
_CUBICS += [(1, 0, 2), (0, 3, 0), (0, 2, 1), (0, 1, 2), (0, 0, 3)]
_BASIS = [(2, 0, 0), (1, 1, 0), (1, 0, 1), (0, 2, 0), (0, 1, 1)]
_BASIS += [(0, 0, 2), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)]
_INDEX = {m: i for i, m in enumerate(_CUBICS + _BASIS)}
_LIN = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)]


def _add(a: tuple[int, ...], b: tuple[int, ...]) -> tuple[int, int, int]:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


#: linear x linear -> index among the 10 monomials of degree <= 2 (``_BASIS``)
_LL = np.array([[_INDEX[_add(a, b)] - 10 for b in _LIN] for a in _LIN], dtype=np.int64)
#: (degree <= 2 monomial i) x linear -> index among all 20
_QL = np.array([[_INDEX[_add(a, b)] for b in _LIN] for a in _BASIS], dtype=np.int64)
#: x times each basis monomial, as an index among all 20
_XB = np.array([_INDEX[_add((1, 0, 0), b)] for b in _BASIS], dtype=np.int64)
#: a fixed rotation mixing the null-space basis (as ``geometry._minimal._MIX``)
_MIX = np.ascontiguousarray(np.linalg.qr(np.random.default_rng(20041).normal(size=(4, 4)))[0])


@njit(**_OPTS)
def _mul_ll(a, b, s, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``out (10) += s a (4) * b (4)`` (linear x linear polynomials)."""
    for p in range(4):
        if a[p] != 0.0:
            for q in range(4):
                out[_LL[p, q]] += s * a[p] * b[q]


@njit(**_OPTS)
def _mul_ql(a, b, s, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``out (20) += s a (10) * b (4)`` (degree-2 x linear polynomials)."""
    for i in range(10):
        if a[i] != 0.0:
            for q in range(4):
                out[_QL[i, q]] += s * a[i] * b[q]


@njit(**_OPTS)
def _hessenberg(a, n):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Reduce ``a`` to upper Hessenberg form in place.

    Stabilised elementary similarity transforms (Wilkinson 1965; Numerical Recipes'
    ``elmhes``).
    """
    for m in range(1, n - 1):
        x = 0.0
        i = m
        for j in range(m, n):
            if abs(a[j, m - 1]) > abs(x):
                x = a[j, m - 1]
                i = j
        if i != m:
            for j in range(m - 1, n):
                a[i, j], a[m, j] = a[m, j], a[i, j]
            for j in range(n):
                a[j, i], a[j, m] = a[j, m], a[j, i]
        if x != 0.0:
            for i in range(m + 1, n):
                y = a[i, m - 1]
                if y != 0.0:
                    y /= x
                    a[i, m - 1] = y
                    for j in range(m, n):
                        a[i, j] -= y * a[m, j]
                    for j in range(n):
                        a[j, m] += y * a[j, i]
    for i in range(2, n):
        for j in range(i - 1):
            a[i, j] = 0.0


@njit(**_OPTS)
def _charpoly(h, n, P):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Coefficients (increasing powers) of ``det(λ I - h)`` into ``P[n]``, ``h`` Hessenberg.

    ``p_k = (λ - h_kk) p_{k-1} - Σ_{i<k} h_ik (Π_{j=i+1..k} h_j,j-1) p_{i-1}`` over the leading
    principal submatrices (Wilkinson 1965, ch. 7).
    """
    for k in range(n + 1):
        for d in range(n + 1):
            P[k, d] = 0.0
    P[0, 0] = 1.0
    for k in range(1, n + 1):
        kk = k - 1
        for d in range(k):
            P[k, d + 1] += P[k - 1, d]
            P[k, d] -= h[kk, kk] * P[k - 1, d]
        prod = 1.0
        for i in range(k - 1, 0, -1):
            prod *= h[i, i - 1]
            c = h[i - 1, kk] * prod
            if c != 0.0:
                for d in range(i):
                    P[k, d] -= c * P[i - 1, d]


@njit(**_OPTS)
def _horner(c, deg, x):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    v = c[deg]
    for i in range(deg - 1, -1, -1):
        v = v * x + c[i]
    return v


@njit(**_OPTS)
def _root_in(c, deg, dc, a, b, fa, tol):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Return the root of ``c`` in ``[a, b]``, a sign change (Newton, bisection safeguard)."""
    x = 0.5 * (a + b)
    for _ in range(80):
        f = _horner(c, deg, x)
        if f == 0.0:
            return x
        if (f > 0.0) == (fa > 0.0):
            a = x
            fa = f
        else:
            b = x
        df = _horner(dc, deg - 1, x)
        xn = x - f / df if df != 0.0 else 0.5 * (a + b)
        if not (a < xn < b):
            xn = 0.5 * (a + b)
        if abs(xn - x) <= tol * max(abs(xn), 1e-300):
            return xn
        x = xn
    return x


@njit(**_OPTS)
def _real_roots(c, deg, D, roots, crit):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Real roots of ``c`` (increasing powers, ``c[deg] ≠ 0``) into ``roots``; their number.

    Isolated between the real roots of the derivative (found the same way, from the
    derivative of order ``deg - 1`` down), inside the Cauchy bound; a root of even
    multiplicity (no sign change) is missed.
    """
    # Fujiwara's bound on the roots' moduli
    bound = 0.0
    for k in range(1, deg + 1):
        bound = max(bound, abs(c[deg - k] / c[deg]) ** (1.0 / k))
    bound = 2.0 * bound * (1.0 + 1e-12) + 1e-300
    # D[k] = k-th derivative
    for i in range(deg + 1):
        D[0, i] = c[i]
    for k in range(1, deg):
        for i in range(deg - k + 1):
            D[k, i] = (i + 1) * D[k - 1, i + 1]
    # the derivative of order deg - 1 is linear
    nc = 1
    crit[0] = -D[deg - 1, 0] / D[deg - 1, 1]
    for k in range(deg - 2, -1, -1):
        dg = deg - k
        nr = 0
        a = -bound
        fa = _horner(D[k], dg, a)
        for j in range(nc + 1):
            b = crit[j] if j < nc else bound
            if b <= a:
                continue
            b = min(b, bound)
            fb = _horner(D[k], dg, b)
            if fa == 0.0:
                roots[nr] = a
                nr += 1
            elif (fa > 0.0) != (fb > 0.0) and fb != 0.0:
                roots[nr] = _root_in(D[k], dg, D[k + 1], a, b, fa, 1e-15 if k == 0 else 1e-9)
                nr += 1
            a = b
            fa = fb
        if fa == 0.0:
            roots[nr] = a
            nr += 1
        for j in range(nr):
            crit[j] = roots[j]
        nc = nr
    return nc


@njit(**_OPTS)
def _e5(q1, q2, idx, Es):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Write the real essential matrices (unit norm) through 5 correspondences; their count.

    As ``geometry._minimal.e5``: ``E = x X + y Y + z Z + W`` over the null space of the
    5 x 9 system, the ten cubics ``det E = 0``, ``2 E Eᵀ E - tr(E Eᵀ) E = 0`` (Nister 2004),
    Gauss-Jordan on the cubic monomials, the action matrix of ``x`` on ``{x², xy, xz, y², yz,
    z², x, y, z, 1}`` (Stewenius, Engels & Nister 2006); its real eigenvalues ``x``, the
    eigenvectors giving ``y, z``.
    """
    A = np.empty((5, 9))
    for k in range(5):
        i = idx[k]
        _epi_row(q1[i, 0], q1[i, 1], q2[i, 0], q2[i, 1], 1.0, A[k])
    N = np.empty((4, 9))
    perm = np.empty(10, dtype=np.int64)
    if not _nullspace(A, np.int64(5), np.int64(5), np.int64(9), N, perm, 1e-12):
        return 0
    # orthonormal (Gram-Schmidt), then mixed by the fixed rotation
    for k in range(4):
        for j in range(k):
            d = 0.0
            for c in range(9):
                d += N[k, c] * N[j, c]
            for c in range(9):
                N[k, c] -= d * N[j, c]
        d = 0.0
        for c in range(9):
            d += N[k, c] * N[k, c]
        d = math.sqrt(d)
        for c in range(9):
            N[k, c] /= d
    basis = np.zeros((4, 9))
    for r in range(4):
        for k in range(4):
            for c in range(9):
                basis[r, c] += _MIX[r, k] * N[k, c]
    # L[e, p]: the linear polynomial (x, y, z, 1) of entry e = 3 i + j
    L = np.empty((9, 4))
    for e in range(9):
        for p in range(4):
            L[e, p] = basis[p, e]
    EEt = np.zeros((9, 10))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                _mul_ll(L[3 * i + k], L[3 * j + k], 1.0, EEt[3 * i + j])
    tr = np.empty(10)
    for c in range(10):
        tr[c] = EEt[0, c] + EEt[4, c] + EEt[8, c]
    M = np.zeros((10, 20))
    for i in range(3):
        for j in range(3):
            row = M[1 + 3 * i + j]
            for k in range(3):
                _mul_ql(EEt[3 * i + k], L[3 * k + j], 2.0, row)
            _mul_ql(tr, L[3 * i + j], -1.0, row)
    cof = np.zeros((3, 10))
    _mul_ll(L[4], L[8], 1.0, cof[0])
    _mul_ll(L[5], L[7], -1.0, cof[0])
    _mul_ll(L[5], L[6], 1.0, cof[1])
    _mul_ll(L[3], L[8], -1.0, cof[1])
    _mul_ll(L[3], L[7], 1.0, cof[2])
    _mul_ll(L[4], L[6], -1.0, cof[2])
    for j in range(3):
        _mul_ql(cof[j], L[j], 1.0, M[0])
    # Gauss-Jordan: M[:, :10] C = M[:, 10:] (partial pivoting)
    for c in range(10):
        p = c
        for r in range(c + 1, 10):
            if abs(M[r, c]) > abs(M[p, c]):
                p = r
        if not abs(M[p, c]) > 0.0:
            return 0
        if p != c:
            for j in range(20):
                M[c, j], M[p, j] = M[p, j], M[c, j]
        piv = 1.0 / M[c, c]
        for j in range(c, 20):
            M[c, j] *= piv
        for r in range(10):
            if r != c:
                f = M[r, c]
                if f != 0.0:
                    for j in range(c, 20):
                        M[r, j] -= f * M[c, j]
    act = np.zeros((10, 10))
    for j in range(10):
        t = _XB[j]
        if t < 10:
            for k in range(10):
                act[j, k] = -M[t, 10 + k]
        else:
            act[j, t - 10] = 1.0
    for r in range(10):
        for c in range(10):
            if not math.isfinite(act[r, c]):
                return 0
    h = np.empty((10, 10))
    for r in range(10):
        for c in range(10):
            h[r, c] = act[r, c]
    _hessenberg(h, 10)
    P = np.empty((11, 11))
    _charpoly(h, 10, P)
    D = np.empty((10, 11))
    xs = np.empty(10)
    crit = np.empty(10)
    nx = _real_roots(P[10], 10, D, xs, crit)
    Bm = np.empty((10, 10))
    v = np.empty((1, 10))
    out = 0
    for r in range(nx):
        x = xs[r]
        for a in range(10):
            for b in range(10):
                Bm[a, b] = act[a, b]
            Bm[a, a] -= x
        if not _nullspace(Bm, np.int64(10), np.int64(9), np.int64(10), v, perm, 0.0):
            continue
        y = v[0, 7] / v[0, 9]
        z = v[0, 8] / v[0, 9]
        E = Es[out]
        ok = True
        for e in range(9):
            val = x * basis[0, e] + y * basis[1, e] + z * basis[2, e] + basis[3, e]
            E[e // 3, e % 3] = val
            ok &= math.isfinite(val)
        if ok:
            _fro_unit(E)
            out += 1
    return out


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1],"
    " float64[:, ::1], float64, float64, int64, uint64, int64, float64, float64,"
    " float64[:, ::1])",
    **_OPTS,
)
def essential_estimate(  # type: ignore[no-untyped-def]  # pragma: no cover
    p1, p2, q1, q2, K1i, K2i, thr, conf, max_trials, seed, max_iter, factor, term, E_out
):
    """Robust ``E`` from pixels ``p1, p2`` (normalised ``q1, q2``): 5-point RANSAC + LO, LM.

    As ``twoview.find_essential_matrix``'s NumPy path: scored by the pixel Sampson distance
    of ``F = K2⁻ᵀ E K1⁻¹``; every new best locally optimised (LM over ``(R, t)``, 10
    iterations, on the correspondences within 2τ then τ); the best projected to an
    essential matrix and refined on its support. Writes ``E_out`` and returns the samples
    drawn, negated when no hypothesis had 5 inliers.
    """
    n = p1.shape[0]
    thr2 = thr * thr
    state = np.empty(1, dtype=np.uint64)
    state[0] = seed
    idx = np.empty(5, dtype=np.int64)
    Es = np.empty((10, 3, 3))
    F = np.empty((3, 3))
    best = np.zeros((3, 3))
    Elo = np.empty((3, 3))
    sel = np.empty(n, dtype=np.int64)
    best_sc = np.inf
    best_cnt = -1
    needed = float(max_trials)
    drawn = 0
    while drawn < min(needed, max_trials):
        _sample(state, n, np.int64(5), idx)
        drawn += 1
        k = _e5(q1, q2, idx, Es)
        for j in range(k):
            _to_f(Es[j], K1i, K2i, F)
            sc, cnt = _score(np.int64(_F_ORTHO), F, p1, p2, thr2, best_sc)
            if cnt < 0 or not sc < best_sc:
                continue
            _copy3(Es[j], best)
            best_sc = sc
            best_cnt = cnt
            if cnt > 5:
                _copy3(Es[j], Elo)
                for mult in (2.0, 1.0):
                    _to_f(Elo, K1i, K2i, F)
                    m = _select(np.int64(_F_ORTHO), F, p1, p2, (mult * thr) ** 2, sel)
                    if m < 6:
                        break
                    _refine_e(Elo, p1, p2, K1i, K2i, sel, m, np.int64(10))
                _to_f(Elo, K1i, K2i, F)
                sc2, cnt2 = _score(np.int64(_F_ORTHO), F, p1, p2, thr2, best_sc)
                if cnt2 >= 0 and sc2 < best_sc:
                    _copy3(Elo, best)
                    best_sc = sc2
                    best_cnt = cnt2
            _to_f(best, K1i, K2i, F)
            m = _support_count(np.int64(_F_ORTHO), F, p1, p2, thr, np.int64(1), term)
            needed = _trials_needed(m, n, np.int64(5), conf)
    if best_cnt < 5:
        return -drawn
    _project_e(best)
    _refit_e(best, p1, p2, K1i, K2i, thr, factor, max_iter)
    _copy3(best, E_out)
    return drawn
