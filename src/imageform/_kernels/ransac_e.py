"""numba kernel of :func:`imageform.geometry.find_essential_matrix` (see ``ransac``)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import (
    _F_ORTHO,
    _MS_XK,
    _ONCE,
    _OPTS,
    _PY_OPTS,
    MAGSAC_K,
    _cheirality,
    _copy3,
    _epi_row,
    _finite3,
    _fro_unit,
    _in_front,
    _magsac,
    _magsac_loss,
    _mat3,
    _nullspace,
    _project_e,
    _rand,
    _rodrigues,
    _same,
    _sample,
    _select,
    _solve,
    _sq_f,
    _support,
    _support_count,
    _svd3,
    _to_f,
    _trials_needed,
)

__all__ = ["essential_estimate"]

#: The local optimisation (:func:`_local_opt`, MAGSAC++'s IRLS): at most this many rounds,
#: each one LM step on the current weights; it ends when a round moves ``E`` by less than
#: ``√_LO_TOL`` (Frobenius; ``E`` has unit norm). Rounds, not LM steps, matter: on
#: OpenSfM's Berlin pair 01-03 (235 matches, 1 px) 4 rounds of 5 LM steps left 2 of 10
#: seeds in a basin 0.7-1.2 degrees off, 10 rounds of one step none (issue: seed spread).
_LO_ROUNDS = 10
_LO_ITER = 1
_LO_TOL = 1e-12
#: A local optimisation gives up (it cannot win) when it comes this near (squared
#: Frobenius) to the model it has to beat, or when after ``_LO_CHECK`` rounds its score is
#: above ``_LO_BEHIND`` times that model's: another, worse basin. Pure speed: the runner-up
#: pool's optimisations cost 0.8 of 1.5 ms in benchmarks/bench_twoview.py's scenes
#: without this, 0.3 ms with it, and the Berlin results above are unchanged.
_SAME_BASIN = 1e-8
_LO_CHECK = 3
_LO_BEHIND = 1.05
#: The final least-squares refit (:func:`_refit_front`, after the IRLS): at most
#: ``_REFIT_ROUNDS`` rounds; it replaces the IRLS's ``E`` only when it stays in the IRLS's
#: basin (:func:`_final_score`): its MAGSAC++ score at most ``1 + _REFIT_TOL`` times the
#: IRLS's, and at least ``1 - _FRONT_TOL`` of the inliers in front of both cameras within
#: ``_MAX_DEPTH`` (what ``recover_pose`` keeps) that the IRLS's ``E`` has. The IRLS's
#: MAGSAC++ weights (below 1 for every residual above 0) are less efficient than plain
#: least squares under Gaussian noise: over 100 scenes of benchmarks/bench_twoview.py's
#: first setting (30 % outliers, σ = τ = 1 px) the median rotation error is 0.349 deg
#: without the refit, 0.314 with it; the refit raised the score by 0.94 % at most there
#: (median 0.21 %; Berlin's pairs 0.91 % at most). Unguarded, a pure rotation
#: (tests/geometry/test_sfm.py's pan, whose translation the data do not fix) lost the
#: inliers that ``recover_pose`` keeps within a score 1 % apart; with the count kept to 95 %
#: the two settings' medians are those of the unguarded refit (with the count kept whole,
#: 0.319 and 0.204 against 0.314 and 0.188 deg).
_REFIT_ROUNDS = 6
_REFIT_TOL = 0.01
_MAX_DEPTH = 50.0
_FRONT_TOL = 0.05
#: The final IRLS (:func:`_irls_front`): at most this many rounds of ``_IRLS_ITER`` LM steps.
_IRLS_ROUNDS = 10
_IRLS_ITER = 2
#: Runner-up hypotheses locally optimised before sampling stops (as the fundamental
#: matrix's, issue 26): with 8, every seed of the Berlin pair 01-03 at 1 px ends within
#: 0.45 degrees of the reference rotation; without, 2 of 10 end 1.3 to 2 degrees off.
_POOL = 8
#: SPRT (Matas & Chum 2008): the time of one 5-point sample in units of one Sampson
#: distance (about 14 µs / 10 ns), the mean number of models per sample, the prior
#: probability that a correspondence agrees with a bad model (updated from the rejected
#: models) and the weight of that prior in correspondences
_SPRT_T_M = 1000.0
_SPRT_M_S = 4.4
_SPRT_DELTA0 = 0.05
_SPRT_PRIOR = 200.0

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
#: a fixed rotation mixing the null-space basis (as ``geometry._minimal._MIX``)
_MIX = np.ascontiguousarray(np.linalg.qr(np.random.default_rng(20041).normal(size=(4, 4)))[0])
#: Nister's (2004) column order of the 20 monomials: the ten eliminated first (x³, y³, x²y,
#: xy², x²z, x², y²z, y², xyz, xy), then x (z², z, 1), y (z², z, 1), (z³, z², z, 1)
_NISTER = [(3, 0, 0), (0, 3, 0), (2, 1, 0), (1, 2, 0), (2, 0, 1), (2, 0, 0), (0, 2, 1)]
_NISTER += [(0, 2, 0), (1, 1, 1), (1, 1, 0), (1, 0, 2), (1, 0, 1), (1, 0, 0), (0, 1, 2)]
_NISTER += [(0, 1, 1), (0, 1, 0), (0, 0, 3), (0, 0, 2), (0, 0, 1), (0, 0, 0)]
#: column ``c`` of the reordered system is column ``_NORD[c]`` of ``_CUBICS + _BASIS``
_NORD = np.array([_INDEX[m] for m in _NISTER], dtype=np.int64)


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
def _sign_changes(S, deg, ns, x):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Sign changes of the Sturm sequence ``S[:ns]`` (degrees ``deg``) at ``x``."""
    count = 0
    last = 0.0
    for k in range(ns):
        v = _horner(S[k], deg[k], x)
        if v != 0.0:
            if last != 0.0 and (v > 0.0) != (last > 0.0):
                count += 1
            last = v
    return count


@njit(**_PY_OPTS)
def _sturm_roots(c, n, S, deg, roots):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Real roots of ``c[:n + 1]`` (increasing powers) into ``roots``; their number.

    Sturm's sequence ``p, p', -rem(p, p'), ...`` counts the real roots in an interval
    (Sturm 1835); bisection of the Fujiwara bound isolates each, then Newton's method with a
    bisection safeguard polishes it (as Nister 2004, sec. 3.3). A multiple root counts once;
    a leading coefficient below ``1e-14`` of the largest lowers the degree (roots near
    infinity dropped).
    """
    big = 0.0
    for i in range(n + 1):
        big = max(big, abs(c[i]))
    if not big > 0.0:
        return 0
    while n > 0 and abs(c[n]) <= 1e-14 * big:
        n -= 1
    if n < 1:
        return 0
    for i in range(n + 1):
        S[0, i] = c[i] / c[n]
    deg[0] = n
    for i in range(n):
        S[1, i] = (i + 1) * S[0, i + 1] / n
    deg[1] = n - 1
    ns = 2
    while deg[ns - 1] > 0:
        a = S[ns - 2]
        b = S[ns - 1]
        da = deg[ns - 2]
        db = deg[ns - 1]
        r = S[ns]
        for i in range(da + 1):
            r[i] = a[i]
        for k in range(da - db, -1, -1):  # long division: r = a mod b
            q = r[k + db] / b[db]
            for i in range(db + 1):
                r[k + i] -= q * b[i]
        dr = db - 1
        scale = 0.0
        for i in range(dr + 1):
            scale = max(scale, abs(r[i]))
        while dr >= 0 and abs(r[dr]) <= 1e-13 * scale:
            dr -= 1
        if dr < 0 or not scale > 0.0:
            break  # a multiple root: the sequence ends at the gcd
        inv = 1.0 / abs(r[dr])  # -(a mod b), scaled by a positive factor
        for i in range(dr + 1):
            r[i] = -r[i] * inv
        deg[ns] = dr
        ns += 1
    bound = 0.0
    for k in range(1, n + 1):
        bound = max(bound, abs(S[0, n - k]) ** (1.0 / k))
    bound = 2.0 * bound * (1.0 + 1e-12) + 1e-300
    # bisection: a stack of intervals (lo, hi, changes at lo, changes at hi)
    lo_s = np.empty(128)
    hi_s = np.empty(128)
    vlo_s = np.empty(128, dtype=np.int64)
    vhi_s = np.empty(128, dtype=np.int64)
    d0 = np.empty(n)
    for i in range(n):
        d0[i] = (i + 1) * S[0, i + 1]
    lo_s[0] = -bound
    hi_s[0] = bound
    vlo_s[0] = _sign_changes(S, deg, ns, -bound)
    vhi_s[0] = _sign_changes(S, deg, ns, bound)
    top = 1
    nr = 0
    while top > 0:
        top -= 1
        lo = lo_s[top]
        hi = hi_s[top]
        vlo = vlo_s[top]
        vhi = vhi_s[top]
        cnt = vlo - vhi
        if cnt <= 0:
            continue
        flo = _horner(S[0], n, lo)
        fhi = _horner(S[0], n, hi)
        if cnt == 1 and flo != 0.0 and fhi != 0.0 and (flo > 0.0) != (fhi > 0.0):
            roots[nr] = _root_in(S[0], n, d0, lo, hi, flo, 1e-15)
            nr += 1
            continue
        mid = 0.5 * (lo + hi)
        if hi - lo <= 1e-12 * max(abs(mid), 1.0) or top + 2 > 128:
            roots[nr] = mid  # a cluster (or a multiple root): one root
            nr += 1
            continue
        vm = _sign_changes(S, deg, ns, mid)
        lo_s[top] = lo
        hi_s[top] = mid
        vlo_s[top] = vlo
        vhi_s[top] = vm
        lo_s[top + 1] = mid
        hi_s[top + 1] = hi
        vlo_s[top + 1] = vm
        vhi_s[top + 1] = vhi
        top += 2
    return nr


@njit(**_PY_OPTS)
def _e5(q1, q2, idx, Es):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Write the real essential matrices (unit norm) through 5 correspondences; their count.

    ``E = x X + y Y + z Z + W`` over the null space of the 5 x 9 system and the ten cubics
    ``det E = 0``, ``2 E Eᵀ E - tr(E Eᵀ) E = 0`` (as ``geometry._minimal.e5``), solved by
    Nister's (2004) hidden variable: Gauss-Jordan elimination of ``x³, y³, x²y, xy², x²z,
    x², y²z, y², xyz, xy`` leaves three equations ``B(z) [x, y, 1]ᵀ = 0`` whose determinant
    is of degree 10 in ``z``; its real roots (Sturm sequences, :func:`_sturm_roots`) give
    ``z``, the null vector of ``B(z)`` gives ``x, y``.
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
    # Nister's column order; Gauss-Jordan on the ten eliminated monomials (partial pivoting)
    G = np.empty((10, 20))
    for r in range(10):
        for c in range(20):
            G[r, c] = M[r, _NORD[c]]
    for c in range(10):
        p = c
        for r in range(c + 1, 10):
            if abs(G[r, c]) > abs(G[p, c]):
                p = r
        if not abs(G[p, c]) > 0.0:
            return 0
        if p != c:
            for j in range(c, 20):
                G[c, j], G[p, j] = G[p, j], G[c, j]
        piv = 1.0 / G[c, c]
        for j in range(c + 1, 20):
            G[c, j] *= piv
        for r in range(10):
            if r != c:
                f = G[r, c]
                if f != 0.0:
                    for j in range(c + 1, 20):
                        G[r, j] -= f * G[c, j]
    # <k> = <e> - z<f>, <l> = <g> - z<h>, <m> = <i> - z<j> (rows 4-9): B(z) [x, y, 1]ᵀ = 0,
    # entries polynomials in z of degrees 3, 3, 4 (increasing powers)
    B = np.zeros((3, 3, 5))
    for q in range(3):
        a = G[4 + 2 * q, 10:]
        b = G[5 + 2 * q, 10:]
        for v in range(2):  # x (columns 10-12: z², z, 1), y (13-15)
            o = 3 * v
            B[q, v, 0] = a[o + 2]
            B[q, v, 1] = a[o + 1] - b[o + 2]
            B[q, v, 2] = a[o] - b[o + 1]
            B[q, v, 3] = -b[o]
        B[q, 2, 0] = a[9]  # 1 (columns 16-19: z³, z², z, 1)
        B[q, 2, 1] = a[8] - b[9]
        B[q, 2, 2] = a[7] - b[8]
        B[q, 2, 3] = a[6] - b[7]
        B[q, 2, 4] = -b[6]
    # det B(z): degree 10 (Nister 2004, eq. 26)
    P = np.zeros(11)
    t = np.empty(8)
    for c0 in range(3):
        c1 = (c0 + 1) % 3
        c2 = (c0 + 2) % 3
        # cofactor of B[0, c0]: B[1, c1] B[2, c2] - B[1, c2] B[2, c1]
        for d in range(8):
            t[d] = 0.0
        for u in range(5):
            for w in range(5):
                if u + w < 8:
                    t[u + w] += B[1, c1, u] * B[2, c2, w] - B[1, c2, u] * B[2, c1, w]
        for u in range(5):
            if B[0, c0, u] != 0.0:
                for w in range(8):
                    if u + w < 11:
                        P[u + w] += B[0, c0, u] * t[w]
    for d in range(11):
        if not math.isfinite(P[d]):
            return 0
    S = np.empty((11, 11))
    deg = np.empty(11, dtype=np.int64)
    zs = np.empty(10)
    nz = _sturm_roots(P, np.int64(10), S, deg, zs)
    Bz = np.empty((3, 3))
    out = 0
    for r in range(nz):
        z = zs[r]
        for q in range(3):
            for v in range(3):
                Bz[q, v] = _horner(B[q, v], np.int64(4), z)
        # [x, y, 1] ∝ the cross product of two rows of B(z) (the largest of the three)
        bx = 0.0
        by = 0.0
        b1 = 0.0
        best_n = 0.0
        for q in range(3):
            u = Bz[(q + 1) % 3]
            w = Bz[(q + 2) % 3]
            cx = u[1] * w[2] - u[2] * w[1]
            cy = u[2] * w[0] - u[0] * w[2]
            c1 = u[0] * w[1] - u[1] * w[0]
            nn = cx * cx + cy * cy + c1 * c1
            if nn > best_n:
                bx, by, b1, best_n = cx, cy, c1, nn
        if b1 == 0.0:
            continue
        x = bx / b1
        y = by / b1
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


@njit(**_OPTS)
def _parts(E, h1, h2, i, K1i, K2i):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``x₂ᵀ F x₁`` and the first two entries of ``F x₁`` and ``Fᵀ x₂``, ``F = K2⁻ᵀ E K1⁻¹``.

    From ``h = K⁻¹ x`` (rows ``i`` of ``h1, h2``); all five are linear in ``E``.
    """
    num = 0.0
    c0 = 0.0
    c1 = 0.0
    d0 = 0.0
    d1 = 0.0
    for r in range(3):
        a = E[r, 0] * h1[i, 0] + E[r, 1] * h1[i, 1] + E[r, 2] * h1[i, 2]
        b = E[0, r] * h2[i, 0] + E[1, r] * h2[i, 1] + E[2, r] * h2[i, 2]
        num += h2[i, r] * a
        c0 += K2i[r, 0] * a
        c1 += K2i[r, 1] * a
        d0 += K1i[r, 0] * b
        d1 += K1i[r, 1] * b
    return num, c0, c1, d0, d1


@njit(**_OPTS)
def _sampson_rt(E, h1, h2, m, K1i, K2i, sw, r):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the signed pixel Sampson distances of ``h1, h2`` under ``E``; their squared sum.

    ``h1, h2`` (m, 3) are ``K⁻¹ x``; each distance is multiplied by ``sw[i]`` (the square
    root of its weight); the sum is ``inf`` when not finite.
    """
    cost = 0.0
    for i in range(m):
        num, c0, c1, d0, d1 = _parts(E, h1, h2, i, K1i, K2i)
        v = sw[i] * num / math.sqrt(c0 * c0 + c1 * c1 + d0 * d0 + d1 * d1)
        r[i] = v
        cost += v * v
    return cost if math.isfinite(cost) else np.inf


@njit(**_OPTS)
def _e_of(R, t, E):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``E = [t]ₓ R``."""
    for b in range(3):
        E[0, b] = -t[2] * R[1, b] + t[1] * R[2, b]
        E[1, b] = t[2] * R[0, b] - t[0] * R[2, b]
        E[2, b] = -t[1] * R[0, b] + t[0] * R[1, b]


@njit(**_OPTS)
def _lm_e(E, p1, p2, K1i, K2i, idx, sw, m, max_iter):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Refine ``E`` in place: Levenberg-Marquardt over ``(R, t/‖t‖)``, analytic Jacobian.

    The pixel Sampson distances of ``idx[:m]``, each multiplied by ``sw[:m]`` (the square
    roots of the weights of a weighted least-squares fit), are minimised.

    The objective of ``twoview._refine_e`` (5 degrees of freedom), linearised at the current
    ``(R, t)`` each step: ``R ← exp([ω]ₓ) R``, ``t ← (t + β₁ b₁ + β₂ b₂)/‖·‖`` with ``b₁, b₂``
    orthonormal to ``t``, so ``∂E/∂ωₖ = [t]ₓ [eₖ]ₓ R = eₖ (Rᵀt)ᵀ - tₖ R`` and
    ``∂E/∂βⱼ = [bⱼ]ₓ R``; ``r = x₂ᵀFx₁ / ‖(Fx₁)₁,₂, (Fᵀx₂)₁,₂‖`` differentiated by the quotient
    rule. Damping ``λ diag(JᵀJ)`` (Marquardt 1963), ``λ`` ÷10 on success, ×10 otherwise;
    stops when a step gains less than ``1e-10`` of the cost. ``E`` is replaced (unit
    Frobenius norm) when the result is finite.
    """
    h1 = np.empty((m, 3))
    h2 = np.empty((m, 3))
    for k in range(m):
        i = idx[k]
        for a in range(3):
            h1[k, a] = K1i[a, 0] * p1[i, 0] + K1i[a, 1] * p1[i, 1] + K1i[a, 2]
            h2[k, a] = K2i[a, 0] * p2[i, 0] + K2i[a, 1] * p2[i, 1] + K2i[a, 2]
    U = np.empty((3, 3))
    V = np.empty((3, 3))
    sv = np.empty(3)
    S1 = np.empty((3, 3))
    S2 = np.empty((3, 3))
    _svd3(E, U, sv, V, S1, S2)
    R = np.empty((3, 3))
    t = np.empty(3)
    for a in range(3):
        for b in range(3):
            R[a, b] = U[a, 1] * V[b, 0] - U[a, 0] * V[b, 1] + U[a, 2] * V[b, 2]
        t[a] = U[a, 2]
    Ec = np.empty((3, 3))
    _e_of(R, t, Ec)
    r = np.empty(m)
    rn = np.empty(m)
    cost = _sampson_rt(Ec, h1, h2, m, K1i, K2i, sw, r)
    if not math.isfinite(cost):
        return
    dE = np.empty((5, 3, 3))
    J = np.empty((m, 5))
    A = np.empty((5, 5))
    Ad = np.empty((5, 5))
    g = np.empty(5)
    gd = np.empty(5)
    step = np.empty(5)
    Rn = np.empty((3, 3))
    tn = np.empty(3)
    Q = np.empty((3, 3))
    B = np.empty((2, 3))
    lam = 1e-3
    for _ in range(max_iter):
        # tangent basis of t
        k = 0
        if abs(t[1]) < abs(t[k]):
            k = 1
        if abs(t[2]) < abs(t[k]):
            k = 2
        e0 = 1.0 if k == 0 else 0.0
        e1 = 1.0 if k == 1 else 0.0
        e2 = 1.0 if k == 2 else 0.0
        B[0, 0] = t[1] * e2 - t[2] * e1
        B[0, 1] = t[2] * e0 - t[0] * e2
        B[0, 2] = t[0] * e1 - t[1] * e0
        nb = math.sqrt(B[0, 0] ** 2 + B[0, 1] ** 2 + B[0, 2] ** 2)
        for a in range(3):
            B[0, a] /= nb
        B[1, 0] = t[1] * B[0, 2] - t[2] * B[0, 1]
        B[1, 1] = t[2] * B[0, 0] - t[0] * B[0, 2]
        B[1, 2] = t[0] * B[0, 1] - t[1] * B[0, 0]
        rt0 = R[0, 0] * t[0] + R[1, 0] * t[1] + R[2, 0] * t[2]
        rt1 = R[0, 1] * t[0] + R[1, 1] * t[1] + R[2, 1] * t[2]
        rt2 = R[0, 2] * t[0] + R[1, 2] * t[1] + R[2, 2] * t[2]
        for c in range(3):
            for a in range(3):
                for b in range(3):
                    dE[c, a, b] = -t[c] * R[a, b]
            dE[c, c, 0] += rt0
            dE[c, c, 1] += rt1
            dE[c, c, 2] += rt2
        for j in range(2):
            _e_of(R, B[j], dE[3 + j])
        # Jacobian (quotient rule on r = num / den; num, c, d linear in E)
        for i in range(m):
            num, c0, c1, d0, d1 = _parts(Ec, h1, h2, i, K1i, K2i)
            den = math.sqrt(c0 * c0 + c1 * c1 + d0 * d0 + d1 * d1)
            ri = num / den
            for c in range(5):
                dnum, dc0, dc1, dd0, dd1 = _parts(dE[c], h1, h2, i, K1i, K2i)
                dden = (c0 * dc0 + c1 * dc1 + d0 * dd0 + d1 * dd1) / den
                J[i, c] = sw[i] * (dnum - ri * dden) / den
        for a in range(5):
            v = 0.0
            for i in range(m):
                v += J[i, a] * r[i]
            g[a] = v
            for b in range(a, 5):
                v = 0.0
                for i in range(m):
                    v += J[i, a] * J[i, b]
                A[a, b] = v
                A[b, a] = v
        improved = False
        gain = 0.0
        while lam < 1e10:
            for a in range(5):
                for b in range(5):
                    Ad[a, b] = A[a, b]
                d = A[a, a] if A[a, a] > 0.0 else 1.0
                Ad[a, a] += lam * d
                gd[a] = -g[a]
            if not _solve(Ad, gd, np.int64(5), step):
                lam *= 10.0
                continue
            _rodrigues(step[0], step[1], step[2], Q)
            _mat3(Q, R, Rn)
            nt = 0.0
            for a in range(3):
                tn[a] = t[a] + step[3] * B[0, a] + step[4] * B[1, a]
                nt += tn[a] * tn[a]
            nt = math.sqrt(nt)
            for a in range(3):
                tn[a] /= nt
            _e_of(Rn, tn, Ec)
            cn = _sampson_rt(Ec, h1, h2, m, K1i, K2i, sw, rn)
            if cn <= cost:
                gain = cost - cn
                cost = cn
                _copy3(Rn, R)
                for a in range(3):
                    t[a] = tn[a]
                for i in range(m):
                    r[i] = rn[i]
                lam = max(lam / 10.0, 1e-12)
                improved = True
                break
            lam *= 10.0
        _e_of(R, t, Ec)
        if not improved or gain <= 1e-10 * cost:
            break
    if _finite3(Ec):
        _fro_unit(Ec)
        _copy3(Ec, E)


@njit(**_OPTS)
def _weights(F, p1, p2, c, sel, sw):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Select the correspondences MAGSAC++ weighs under ``F``; write ``√weight``; their count.

    ``x = c e²`` with ``e`` the pixel Sampson distance and ``c = 1 / (2 σ_max²)``; the
    weight is :func:`~imageform._kernels.ransac._magsac`'s (0 beyond ``k σ_max``).
    """
    m = 0
    for i in range(p1.shape[0]):
        x = c * _sq_f(F, p1, p2, i)
        if x < _MS_XK:
            w = _magsac(x)[1]
            if w > 0.0:
                sel[m] = i
                sw[m] = math.sqrt(w)
                m += 1
    return m


@njit(**_ONCE)
def _local_opt(E, p1, p2, q1, q2, K1i, K2i, c, thr2, best_sc, ref, sel, sw, F, Elo):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Locally optimise ``E`` into ``Elo``; return its MAGSAC++ score and inlier count.

    MAGSAC++'s iteratively re-weighted least squares (Barath et al. 2020, sec. 3): each
    round weighs the correspondences by MAGSAC++ under the current ``E`` (:func:`_weights`)
    and takes one LM step over ``(R, t)`` on the weighted pixel Sampson distances
    (:func:`_lm_e`), for at most :data:`_LO_ROUNDS` rounds, until a round moves ``E`` by
    less than ``√_LO_TOL``. It gives up (count -1) when it nears ``ref``, the model it has
    to beat, or falls far behind it (:data:`_SAME_BASIN`, :data:`_LO_BEHIND`); the count is
    -1 too when the score is not better than ``best_sc``.
    """
    _copy3(E, Elo)
    prev = np.empty((3, 3))
    for r in range(_LO_ROUNDS):
        _to_f(Elo, K1i, K2i, F)
        if r == _LO_CHECK:  # far behind the model to beat: another basin, give up
            sc = _score_sprt(F, p1, p2, thr2, c, np.inf, np.int64(0), 1.0, 1.0, np.inf)[0]
            if sc > _LO_BEHIND * best_sc:
                return sc, np.int64(-1)
        m = _weights(F, p1, p2, c, sel, sw)
        if m < 6:
            break
        _copy3(Elo, prev)
        _lm_e(Elo, p1, p2, K1i, K2i, sel, sw, m, np.int64(_LO_ITER))
        d = 0.0
        e = 0.0
        f = 0.0
        for a in range(3):
            for b in range(3):
                d += (Elo[a, b] - prev[a, b]) ** 2
                e += (Elo[a, b] - ref[a, b]) ** 2
                f += (Elo[a, b] + ref[a, b]) ** 2
        if d < _LO_TOL:
            break
        if min(e, f) < _SAME_BASIN:  # on its way to the model it has to beat
            return np.inf, np.int64(-1)
    _to_f(Elo, K1i, K2i, F)
    sc, cnt, _, _ = _score_sprt(F, p1, p2, thr2, c, best_sc, np.int64(0), 1.0, 1.0, np.inf)
    return sc, cnt


@njit(**_ONCE)
def _irls_front(E, p1, p2, q1, q2, K1i, K2i, c, max_iter, rounds):  # type: ignore[no-untyped-def]  # pragma: no cover
    """MAGSAC++'s IRLS to convergence, in place, without the points behind a camera.

    Each round weighs every correspondence by MAGSAC++ under the current ``E``, drops the
    weighted ones that the factorisation of ``E`` chosen by the cheirality vote puts behind
    a camera (an outlier near its epipolar line by chance is behind one about half the
    time), and fits ``E`` by weighted LM over ``(R, t)``; it stops when a round moves ``E``
    by less than ``1e-7`` (Frobenius) or after ``rounds`` rounds.
    """
    n = p1.shape[0]
    sel = np.empty(n, dtype=np.int64)
    sw = np.empty(n)
    F = np.empty((3, 3))
    U = np.empty((3, 3))
    Rs = np.empty((2, 3, 3))
    prev = np.empty((3, 3))
    for _ in range(rounds):
        _to_f(E, K1i, K2i, F)
        m = _weights(F, p1, p2, c, sel, sw)
        if m < 5:
            return
        bi, bs, _ = _cheirality(E, q1, q2, sel, m, np.inf, U, Rs)
        R = Rs[bi]
        t0, t1, t2 = bs * U[0, 2], bs * U[1, 2], bs * U[2, 2]
        k = 0
        for j in range(m):
            i = sel[j]
            if _in_front(R, t0, t1, t2, q1[i, 0], q1[i, 1], q2[i, 0], q2[i, 1], np.inf):
                sel[k] = i
                sw[k] = sw[j]
                k += 1
        if k < 5:
            return
        _copy3(E, prev)
        _lm_e(E, p1, p2, K1i, K2i, sel, sw, k, min(max_iter, _IRLS_ITER))
        d = 0.0
        for a in range(3):
            for b in range(3):
                d += (E[a, b] - prev[a, b]) ** 2
        if d < 1e-14:
            return


@njit(**_ONCE)
def _refit_front(E, p1, p2, q1, q2, K1i, K2i, thr, factor, max_iter, rounds):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Refit ``E`` in place: LM on its refinement support, then in front of the cameras.

    First as ``_robust_core.refit_on_support`` (dof 1, at least 5): up to 3 rounds on the
    refinement support of the starting ``E`` (``3σ̂`` clipped to ``[τ, factor τ]``, ``σ̂``
    from its inliers), reselected with that bound after each refit. Then up to ``rounds``
    more, each on the support of the current ``E`` (its own ``σ̂``) less the correspondences
    that the factorisation of ``E`` chosen by the cheirality vote puts behind a camera (an
    outlier that lies near its epipolar line by chance is behind one about half the time),
    until the support no longer changes.
    """
    n = p1.shape[0]
    sel = np.empty(n, dtype=np.int64)
    sel2 = np.empty(n, dtype=np.int64)
    ones = np.ones(n)
    F = np.empty((3, 3))
    U = np.empty((3, 3))
    Rs = np.empty((2, 3, 3))
    _to_f(E, K1i, K2i, F)
    wide, m = _support(F, p1, p2, thr, factor, sel)
    if m < 5:
        return
    fixed = 3
    for _ in range(fixed + rounds):
        _lm_e(E, p1, p2, K1i, K2i, sel, ones, m, max_iter)
        _to_f(E, K1i, K2i, F)
        if fixed > 0:
            fixed -= 1
            k = _select(np.int64(_F_ORTHO), F, p1, p2, wide * wide, sel2)
            if k >= 5 and not _same(sel, m, sel2, k):
                m = k
                for j in range(m):
                    sel[j] = sel2[j]
                continue
            fixed = 0
        _, m2 = _support(F, p1, p2, thr, factor, sel2)
        bi, bs, _ = _cheirality(E, q1, q2, sel2, m2, np.inf, U, Rs)
        R = Rs[bi]
        t0, t1, t2 = bs * U[0, 2], bs * U[1, 2], bs * U[2, 2]
        k = 0
        for j in range(m2):
            i = sel2[j]
            if _in_front(R, t0, t1, t2, q1[i, 0], q1[i, 1], q2[i, 0], q2[i, 1], np.inf):
                sel2[k] = i
                k += 1
        if k < 5 or _same(sel, m, sel2, np.int64(k)):  # not Literal[int](0): one compilation
            break
        m = k
        for j in range(m):
            sel[j] = sel2[j]


@njit(**_ONCE)
def _final_score(E, p1, p2, q1, q2, K1i, K2i, thr2, c, sel, F):  # type: ignore[no-untyped-def]  # pragma: no cover
    """MAGSAC++ score of ``E`` and the number of its inliers that ``recover_pose`` keeps.

    The inliers (within ``τ``) in front of both cameras and nearer than 50 baselines
    (``recover_pose``'s ``max_depth``) for the factorisation that keeps the most.
    """
    _to_f(E, K1i, K2i, F)
    sc = _score_sprt(F, p1, p2, thr2, c, np.inf, np.int64(0), 1.0, 1.0, np.inf)[0]
    m = 0
    for i in range(p1.shape[0]):
        if _sq_f(F, p1, p2, i) < thr2:
            sel[m] = i
            m += 1
    U = np.empty((3, 3))
    Rs = np.empty((2, 3, 3))
    return sc, _cheirality(E, q1, q2, sel, m, _MAX_DEPTH, U, Rs)[2]


@njit(**_OPTS)
def _sprt_threshold(eps, delta):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Wald's decision threshold ``A`` of the SPRT that minimises the expected run time.

    ``A = K + log A`` with ``K = t_M C / m_S + 1``, ``C = (1 - δ) log((1 - δ)/(1 - ε)) +
    δ log(δ/ε)`` (Matas & Chum 2008, eqs. 2 and 7; fixed-point iteration).
    """
    C = (1.0 - delta) * math.log((1.0 - delta) / (1.0 - eps)) + delta * math.log(delta / eps)
    K = _SPRT_T_M * C / _SPRT_M_S + 1.0
    A = K
    for _ in range(10):
        A = K + math.log(A)
    return A


@njit(**_OPTS)
def _score_sprt(F, p1, p2, thr2, c, limit, start, lam_in, lam_out, A):  # type: ignore[no-untyped-def]  # pragma: no cover
    """MAGSAC++ score, inlier count and correspondences tested, from ``start`` on (cyclic).

    The score is the sum of MAGSAC++'s losses (:func:`~imageform._kernels.ransac._magsac`
    at ``x = c e²``, 1 for an outlier); the inliers are those within ``τ``. The count is -1
    when the score passes ``limit`` (cannot beat the best: the loss grows monotonically),
    -2 when the SPRT's likelihood ratio passes ``A`` (a bad model: each correspondence
    within ``τ`` multiplies it by ``δ/ε``, each beyond by ``(1-δ)/(1-ε)``).
    """
    n = p1.shape[0]
    sc = 0.0
    cnt = 0
    lam = 1.0
    i = start
    for j in range(n):
        e = _sq_f(F, p1, p2, i)
        sc += _magsac_loss(c * e)
        if e < thr2:
            cnt += 1
            lam *= lam_in
        else:
            lam *= lam_out
        if sc > limit:
            return sc, np.int64(-1), cnt, j + 1
        if lam > A:
            return sc, np.int64(-2), cnt, j + 1
        i += 1
        if i == n:
            i = 0
    return sc, np.int64(cnt), cnt, n


@njit(**_OPTS)
def _adopt(E, sc, cnt, p1, p2, q1, q2, K1i, K2i, c, thr2, best, best_sc, sel, sw, F, Elo):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Keep ``E`` (score ``sc``, ``cnt`` inliers) if it beats the best, then its local optimum.

    Returns the best's score and inlier count (``best`` holds the model).
    """
    best_cnt = np.int64(-1)
    ref = np.empty((3, 3))
    _copy3(best, ref)
    if sc < best_sc:
        _copy3(E, best)
        best_sc = sc
        best_cnt = cnt
    if cnt > 5:
        sc2, cnt2 = _local_opt(E, p1, p2, q1, q2, K1i, K2i, c, thr2, best_sc, ref, sel, sw, F, Elo)
        if cnt2 >= 0 and sc2 < best_sc:
            _copy3(Elo, best)
            best_sc = sc2
            best_cnt = cnt2
    if best_cnt < 0:  # unchanged: count the best's inliers again
        _to_f(best, K1i, K2i, F)
        best_cnt = _score_sprt(F, p1, p2, thr2, 0.0, np.inf, np.int64(0), 1.0, 1.0, np.inf)[1]
    return best_sc, best_cnt


@njit(**_OPTS)
def _pool_insert(E, sc, pool_E, pool_sc, n_pool):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Insert ``E`` (score ``sc``) into the pool sorted by score; return the pool's size."""
    size = pool_sc.shape[0]
    pos = n_pool
    while pos > 0 and pool_sc[pos - 1] > sc:
        pos -= 1
    if pos >= size:
        return n_pool
    last = min(n_pool, size - 1)
    for q in range(last, pos, -1):
        pool_sc[q] = pool_sc[q - 1]
        _copy3(pool_E[q - 1], pool_E[q])
    pool_sc[pos] = sc
    _copy3(E, pool_E[pos])
    return min(n_pool + 1, size)


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1],"
    " float64[:, ::1], float64, float64, int64, uint64, int64, float64, float64, float64,"
    " float64[:, ::1])",
    **_PY_OPTS,
    lazy=True,
)
def essential_estimate(  # type: ignore[no-untyped-def]  # pragma: no cover
    p1, p2, q1, q2, K1i, K2i, thr, conf, max_trials, seed, max_iter, factor, term, reach, E_out
):
    """Robust ``E`` from pixels ``p1, p2`` (normalised ``q1, q2``): 5-point RANSAC, MAGSAC++.

    As ``twoview.find_essential_matrix``'s NumPy path: each hypothesis scored by MAGSAC++'s
    loss of the pixel Sampson distance of ``F = K2⁻ᵀ E K1⁻¹`` (:func:`_score_sprt`,
    ``k σ_max = reach τ``); every new best, and before sampling stops the :data:`_POOL`
    best of the others, locally optimised (:func:`_local_opt`, MAGSAC++'s IRLS); sampling
    goes on when the pool improves the best and the count asks for more; the best projected
    to an essential matrix and refitted by the IRLS in front of the cameras
    (:func:`_irls_front`), then by least squares on its refinement support (``3σ̂`` within
    ``[τ, factor τ]``) in front of the cameras (:func:`_refit_front`), kept when it stays
    in the IRLS's basin (:func:`_final_score`, :data:`_REFIT_TOL`, :data:`_FRONT_TOL`).
    Each hypothesis is verified from a random correspondence on and rejected early by
    Wald's SPRT (``ε`` the best model's inlier ratio within ``τ``, ``δ``
    that of the rejected ones); the adaptive count ``log(1 - p) / log(1 - ε_s⁵ (1 - 1/A))``
    (``ε_s`` the best model's support, ``term`` τ wide) allows for the good models the SPRT
    rejects (Matas & Chum 2008, sec. 4). Writes ``E_out`` and returns the samples drawn,
    negated when no hypothesis had 5 inliers.
    """
    n = p1.shape[0]
    thr2 = thr * thr
    # MAGSAC++: k σ_max = reach τ, x = e² / (2 σ_max²) = c e²
    sigma_max = reach * thr / MAGSAC_K
    c = 1.0 / (2.0 * sigma_max * sigma_max)
    sw = np.empty(n)
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
    # SPRT: off (A = inf) until a best model gives ε
    delta = _SPRT_DELTA0
    seen_in = _SPRT_DELTA0 * _SPRT_PRIOR
    seen = _SPRT_PRIOR
    eps = 0.0
    A = np.inf
    lam_in = 1.0
    lam_out = 1.0
    pool_E = np.empty((max(_POOL, 1), 3, 3))
    pool_sc = np.empty(max(_POOL, 1))
    n_pool = 0
    while True:
        while drawn < min(needed, max_trials):
            _sample(state, n, np.int64(5), idx)
            drawn += 1
            k = _e5(q1, q2, idx, Es)
            for j in range(k):
                _to_f(Es[j], K1i, K2i, F)
                start = np.int64(_rand(state) % np.uint64(n))
                limit = best_sc
                if _POOL > 0:
                    limit = max(best_sc, pool_sc[_POOL - 1] if n_pool == _POOL else np.inf)
                sc, cnt, c_in, tested = _score_sprt(
                    F, p1, p2, thr2, c, limit, start, lam_in, lam_out, A
                )
                if cnt < 0:  # rejected (a bad model): its agreement estimates δ
                    seen_in += c_in
                    seen += tested
                    continue
                if not sc < best_sc:
                    if _POOL > 0 and cnt > 5:
                        n_pool = _pool_insert(Es[j], sc, pool_E, pool_sc, n_pool)
                    continue
                best_sc, best_cnt = _adopt(
                    Es[j],
                    sc,
                    cnt,
                    p1,
                    p2,
                    q1,
                    q2,
                    K1i,
                    K2i,
                    c,
                    thr2,
                    best,
                    best_sc,
                    sel,
                    sw,
                    F,
                    Elo,
                )
                _to_f(best, K1i, K2i, F)
                m = _support_count(np.int64(_F_ORTHO), F, p1, p2, thr, np.int64(1), term)
                # the SPRT's design from the best model (ε) and the rejected ones (δ)
                delta = min(max(seen_in / seen, 1e-4), 0.5)
                eps = best_cnt / n
                if eps > 1.5 * delta and eps < 1.0:
                    A = _sprt_threshold(eps, delta)
                    lam_in = delta / eps
                    lam_out = (1.0 - delta) / (1.0 - eps)
                else:
                    A = np.inf
                # a good model passes the SPRT with probability about 1 - 1/A (Wald)
                needed = _trials_needed(m, n, np.int64(5), conf)
                if math.isfinite(A) and math.isfinite(needed) and needed > 0.0:
                    pg = (m / n) ** 5
                    keep = 1.0 - 1.0 / A
                    if pg * keep < 1.0:
                        needed = math.log1p(-conf) / math.log1p(-pg * keep)
        if n_pool == 0:
            break
        before = best_sc
        for r in range(n_pool):
            _to_f(pool_E[r], K1i, K2i, F)
            sc, cnt, _, _ = _score_sprt(F, p1, p2, thr2, c, np.inf, np.int64(0), 1.0, 1.0, np.inf)
            best_sc, best_cnt = _adopt(
                pool_E[r],
                sc,
                cnt,
                p1,
                p2,
                q1,
                q2,
                K1i,
                K2i,
                c,
                thr2,
                best,
                best_sc,
                sel,
                sw,
                F,
                Elo,
            )
        n_pool = 0
        if not best_sc < before:
            break
        _to_f(best, K1i, K2i, F)
        m = _support_count(np.int64(_F_ORTHO), F, p1, p2, thr, np.int64(1), term)
        needed = _trials_needed(m, n, np.int64(5), conf)
        if drawn >= min(needed, max_trials):
            break
    if best_cnt < 5:
        return -drawn
    _project_e(best)
    _irls_front(best, p1, p2, q1, q2, K1i, K2i, c, max_iter, np.int64(_IRLS_ROUNDS))
    # then least squares on the refinement support in front of the cameras, kept when it
    # stays in the IRLS's basin (its MAGSAC++ score within _REFIT_TOL of the IRLS's)
    _copy3(best, Elo)
    _refit_front(Elo, p1, p2, q1, q2, K1i, K2i, thr, factor, max_iter, np.int64(_REFIT_ROUNDS))
    sc0, f0 = _final_score(best, p1, p2, q1, q2, K1i, K2i, thr2, c, sel, F)
    sc1, f1 = _final_score(Elo, p1, p2, q1, q2, K1i, K2i, thr2, c, sel, F)
    if sc1 <= (1.0 + _REFIT_TOL) * sc0 and f1 >= (1.0 - _FRONT_TOL) * f0:
        _copy3(Elo, best)
    _copy3(best, E_out)
    return drawn
