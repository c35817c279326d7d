r"""numba kernels of the robust two-view estimators (``imageform.geometry.robust``, ``.twoview``).

One kernel per model runs the whole estimate in compiled code: the hypothesise-and-verify
loop (minimal samples, minimal solver, MSAC score), the local optimisation of every new best
hypothesis (LO-RANSAC, Chum, Matas & Kittler 2003), the adaptive trial count, and the final
least-squares refinement on the refinement support (Levenberg-Marquardt, as the NumPy twins
in ``imageform.geometry``):

- :func:`homography_estimate`: 4-point DLT (Gauss-Jordan null vector of the 8 x 9 system in
  Hartley-normalised coordinates), the sample rejected before solving when three of its
  points are collinear or the four do not keep their orientation (a homography of a plane
  seen from its front keeps the sign of every triangle; OpenCV's USAC ``isSampleGood``),
  forward transfer error.
- :func:`fundamental_estimate`: 7-point (the cubic ``det(α F1 + (1 - α) F2) = 0``, roots in
  closed form), Sampson distance, Sampson-weighted 8-point refits as local optimisation,
  the runner-up pool of issue 26.
- :func:`essential_estimate`: 5-point (Nister 2004; the ten cubic constraints reduced by
  Gauss-Jordan elimination, the action matrix of multiplication by ``x`` as in Stewenius,
  Engels & Nister 2006), its real eigenvalues the real roots of its characteristic
  polynomial (Hessenberg form, then the roots isolated between those of the polynomial's
  derivatives), the eigenvectors by Gauss-Jordan elimination; Sampson distance in pixels,
  scored by MAGSAC++'s marginalised loss (:func:`_magsac`), its IRLS as the local
  optimisation and as the final fit (Barath et al. 2020), and a runner-up pool.

Speed comes from more than compiled loops: no allocation per hypothesis; the
partial-evaluation bail-out of the score (``Σ min(e², τ²)`` grows monotonically, so the
evaluation of a hypothesis stops as soon as it exceeds the score it has to beat: the
hypothesis could not be kept, the result is exactly that of a full evaluation); for H and F,
Wald's sequential probability ratio test (:func:`_score_sprt`, Matas & Chum 2008), which
rejects most bad hypotheses after a dozen or two correspondences (verified in a random
order, as the test assumes), the adaptive count allowing for the good ones it rejects;
null spaces of the minimal systems by partial pivoting (:func:`_null_partial`, complete
pivoting as the fallback); least-squares fits by inverse iteration on a Cholesky factor
(:func:`_min_eigvec_psd`) instead of Jacobi sweeps, and the homography's ``AᵀA`` from 24
moments per correspondence (issue 28).

The random samples come from a SplitMix64 generator seeded from the caller's
``numpy.random.Generator`` (one draw), so a given ``rng`` gives the same result every time.
All kernels take float64 arrays only, one explicit signature each, cached
(:mod:`imageform._kernels.jit`); ``error_model="numpy"`` (a division by zero gives inf or
NaN, tested for where it matters).
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit

__all__: list[str] = []

#: Options of a kernel called only from compiled code: neither the wrapper that Python calls
#: nor a C callback (``no_cpython_wrapper``, ``no_cfunc_wrapper``) is built, optimised and
#: compiled to machine code for it (a sixth of a cold compilation). Calling such a kernel
#: from Python crashes the interpreter: one that Python (a test) calls takes ``_PY_OPTS``.
_OPTS = {
    "nogil": True,
    "error_model": "numpy",
    "no_cfunc_wrapper": True,
    "no_cpython_wrapper": True,
}
#: Options of a kernel called from Python: the estimators, and the helpers the tests call.
_PY_OPTS = {"nogil": True, "error_model": "numpy", "no_cfunc_wrapper": True}
#: A helper with one call site in one kernel: typed inside its caller (numba's IR inlining),
#: one compilation less, and its code not optimised and compiled to machine code once more
#: at its own level (a called kernel is, inside every caller).
_ONCE = {**_OPTS, "inline": "always"}

#: The SPRT's initial ``δ``, the inlier ratio of a bad hypothesis (then the mean of the
#: rejected ones'; :func:`_score_sprt`).
_SPRT_DELTA0 = 0.05

# LM residual kinds
_H_FORWARD = 0
_H_SYMMETRIC = 1
_F_ORTHO = 2


# ---------------------------------------------------------------- random samples
@njit(**_OPTS)
def _rand(state):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """SplitMix64 (Steele, Lea & Flood 2014): the next 64-bit value of ``state`` (uint64[1])."""
    z = state[0] + np.uint64(0x9E3779B97F4A7C15)
    state[0] = z
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(**_OPTS)
def _sample(state, n, s, idx):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``s`` distinct indices in ``[0, n)`` into ``idx``."""
    for k in range(s):
        while True:
            r = np.int64(_rand(state) % np.uint64(n))
            ok = True
            for j in range(k):
                if idx[j] == r:
                    ok = False
                    break
            if ok:
                idx[k] = r
                break


@njit(**_OPTS)
def _inliers_out(kind, M, p1, p2, thr2, order, inl_out, rms_out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the inliers of ``M`` and their RMS error (NaN without any).

    Into ``inl_out`` in the caller's order (``p1[i]`` is its ``order[i]``) and ``rms_out[0]``.
    """
    s = 0.0
    cnt = 0
    for i in range(p1.shape[0]):
        e = _sq(kind, M, p1, p2, i)
        ok = e < thr2
        inl_out[order[i]] = ok
        if ok:
            s += e
            cnt += 1
    rms_out[0] = math.sqrt(s / cnt) if cnt > 0 else np.nan


@njit(**_OPTS)
def _shuffled(state, n):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Return a random permutation of ``range(n)`` (Fisher-Yates).

    The verification order that the SPRT (:func:`_score_sprt`) assumes, whatever the order
    of the input.
    """
    order = np.arange(n)
    for i in range(n - 1, 0, -1):
        j = np.int64(_rand(state) % np.uint64(i + 1))
        order[i], order[j] = order[j], order[i]
    return order


@njit(**_PY_OPTS)
def _trials_needed(n_inl, n, s, conf):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``imageform.geometry._robust_core.trials_needed`` (a test pins the two equal)."""
    eps = n_inl / n
    if eps >= 1.0:
        return 0.0
    if eps <= 0.0:
        return np.inf
    return _trials_for(math.pow(eps, float(s)), conf)  # as Python: C pow, not powi


@njit(**_OPTS)
def _trials_for(p_good, conf):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``log(1 - p) / log(1 - p_good)``: samples for one good one with probability ``conf``."""
    denom = math.log1p(-p_good)
    if denom == 0.0:
        return np.inf
    return math.log1p(-conf) / denom


# ---------------------------------------------------------------- small linear algebra
@njit(**_PY_OPTS)
def _hartley(p, idx, m, out, T):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Hartley-normalise the points ``p[idx[:m]]`` into ``out (m, 2)``, ``T (3, 3)``."""
    cx = 0.0
    cy = 0.0
    for k in range(m):
        cx += p[idx[k], 0]
        cy += p[idx[k], 1]
    cx /= m
    cy /= m
    d = 0.0
    for k in range(m):
        dx = p[idx[k], 0] - cx
        dy = p[idx[k], 1] - cy
        d += math.sqrt(dx * dx + dy * dy)
    d /= m
    sc = math.sqrt(2.0) / d if d > 0 else 1.0
    for k in range(m):
        out[k, 0] = (p[idx[k], 0] - cx) * sc
        out[k, 1] = (p[idx[k], 1] - cy) * sc
    for a in range(3):
        for b in range(3):
            T[a, b] = 0.0
    T[0, 0] = sc
    T[1, 1] = sc
    T[0, 2] = -cx * sc
    T[1, 2] = -cy * sc
    T[2, 2] = 1.0


@njit(**_OPTS)
def _mat3(A, B, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(**_OPTS)
def _mat3_tn(A, B, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``out = Aᵀ B``."""
    for i in range(3):
        for j in range(3):
            out[i, j] = A[0, i] * B[0, j] + A[1, i] * B[1, j] + A[2, i] * B[2, j]


@njit(**_OPTS)
def _copy3(A, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, j]


@njit(**_OPTS)
def _finite3(A):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Whether every entry of the 3 x 3 ``A`` is finite (a refit that failed is not kept)."""
    ok = True
    for i in range(3):
        for j in range(3):
            ok &= math.isfinite(A[i, j])
    return ok


@njit(**_OPTS)
def _inv3(A, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    c00 = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    c01 = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    c02 = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    det = A[0, 0] * c00 + A[0, 1] * c01 + A[0, 2] * c02
    inv = 1.0 / det
    out[0, 0] = c00 * inv
    out[1, 0] = c01 * inv
    out[2, 0] = c02 * inv
    out[0, 1] = (A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]) * inv
    out[1, 1] = (A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]) * inv
    out[2, 1] = (A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]) * inv
    out[0, 2] = (A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]) * inv
    out[1, 2] = (A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]) * inv
    out[2, 2] = (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]) * inv


@njit(**_OPTS)
def _fro_unit(M):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    s = 0.0
    for i in range(3):
        for j in range(3):
            s += M[i, j] * M[i, j]
    s = math.sqrt(s)
    for i in range(3):
        for j in range(3):
            M[i, j] /= s


@njit(**_OPTS)
def _jacobi(A, V):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Eigen-decompose the symmetric ``A`` (m, m) in place by cyclic Jacobi rotations.

    ``A`` ends diagonal (the eigenvalues), ``V``'s columns the eigenvectors (Golub & Van
    Loan, *Matrix Computations*, sec. 8.5).
    """
    m = A.shape[0]
    for i in range(m):
        for j in range(m):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(60):
        off = 0.0
        dia = 0.0
        for p in range(m):
            dia += A[p, p] * A[p, p]
            for q in range(p + 1, m):
                off += A[p, q] * A[p, q]
        if off <= 1e-32 * dia or off == 0.0:
            break
        for p in range(m - 1):
            for q in range(p + 1, m):
                apq = A[p, q]
                if apq == 0.0:
                    continue
                theta = (A[q, q] - A[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(m):
                    akp = A[k, p]
                    akq = A[k, q]
                    A[k, p] = c * akp - s * akq
                    A[k, q] = s * akp + c * akq
                for k in range(m):
                    apk = A[p, k]
                    aqk = A[q, k]
                    A[p, k] = c * apk - s * aqk
                    A[q, k] = s * apk + c * aqk
                for k in range(m):
                    vkp = V[k, p]
                    vkq = V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq


@njit(**_OPTS)
def _min_eigvec(A, V, out):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Write the eigenvector of the smallest eigenvalue of the symmetric ``A`` (destroyed)."""
    _jacobi(A, V)
    k = 0
    for i in range(1, A.shape[0]):
        if A[i, i] < A[k, k]:
            k = i
    for i in range(A.shape[0]):
        out[i] = V[i, k]


@njit(**_PY_OPTS)
def _min_eigvec_psd(A, L, x, y, V, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the eigenvector of the smallest eigenvalue of the symmetric PSD ``A`` (m, m).

    Inverse iteration (Golub & Van Loan sec. 8.2.2) on the Cholesky factor ``L`` of
    ``A + μ I`` (``μ = 1e-13 tr A``, which keeps an exact-data ``A`` of rank ``m - 1``
    factorisable): a few triangular solves where the smallest eigenvalue is well separated,
    which it is for a least-squares fit on many points (a few hundred flops against the
    tens of thousands of a Jacobi sweep). Falls back to :func:`_min_eigvec` (``A``
    destroyed) when the factorisation fails or 30 steps do not converge. ``x, y`` (m,) and
    ``V`` (m, m) scratch.
    """
    m = A.shape[0]
    tr = 0.0
    for i in range(m):
        tr += A[i, i]
    ok = tr > 0.0 and math.isfinite(tr)
    mu = 1e-13 * tr
    for j in range(m):
        if not ok:
            break
        sj = A[j, j] + mu
        for k in range(j):
            sj -= L[j, k] * L[j, k]
        if not sj > 0.0:
            ok = False
            break
        dj = math.sqrt(sj)
        L[j, j] = dj
        for i in range(j + 1, m):
            v = A[i, j]
            for k in range(j):
                v -= L[i, k] * L[j, k]
            L[i, j] = v / dj
    if ok:
        ok = False
        for i in range(m):  # start: the uniform unit vector
            x[i] = 1.0 / math.sqrt(m)
        for _ in range(30):
            for i in range(m):  # L z = x (z in y), then Lᵀ y = z
                v = x[i]
                for k in range(i):
                    v -= L[i, k] * y[k]
                y[i] = v / L[i, i]
            for i in range(m - 1, -1, -1):
                v = y[i]
                for k in range(i + 1, m):
                    v -= L[k, i] * y[k]
                y[i] = v / L[i, i]
            nrm = 0.0
            dot = 0.0
            for i in range(m):
                nrm += y[i] * y[i]
                dot += y[i] * x[i]
            nrm = math.sqrt(nrm)
            if not (nrm > 0.0 and math.isfinite(nrm)):
                break
            sgn = 1.0 / nrm if dot >= 0.0 else -1.0 / nrm
            diff = 0.0
            for i in range(m):
                yi = y[i] * sgn
                diff = max(diff, abs(yi - x[i]))
                x[i] = yi
            if diff < 1e-14:
                ok = True
                break
    if ok:
        for i in range(m):
            out[i] = x[i]
    else:
        _min_eigvec(A, V, out)


@njit(**_OPTS)
def _svd3(M, U, s, V, A, W):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``M = U diag(s) Vᵀ`` with ``U, V`` rotations, ``s`` descending (from ``MᵀM``).

    ``A, W`` are (3, 3) scratch. The third column of ``U`` is ``u₁ x u₂`` (exact for rank 2).
    """
    _mat3_tn(M, M, A)
    _jacobi(A, W)
    # order the eigenvalues descending
    o0, o1, o2 = 0, 1, 2
    if A[o0, o0] < A[o1, o1]:
        o0, o1 = o1, o0
    if A[o1, o1] < A[o2, o2]:
        o1, o2 = o2, o1
    if A[o0, o0] < A[o1, o1]:
        o0, o1 = o1, o0
    order = (o0, o1, o2)
    for c in range(3):
        o = order[c]
        s[c] = math.sqrt(max(A[o, o], 0.0))
        for i in range(3):
            V[i, c] = W[i, o]
    # V a rotation
    det = (
        V[0, 0] * (V[1, 1] * V[2, 2] - V[1, 2] * V[2, 1])
        - V[0, 1] * (V[1, 0] * V[2, 2] - V[1, 2] * V[2, 0])
        + V[0, 2] * (V[1, 0] * V[2, 1] - V[1, 1] * V[2, 0])
    )
    if det < 0.0:
        for i in range(3):
            V[i, 2] = -V[i, 2]
    for c in range(2):
        nrm = 0.0
        for i in range(3):
            U[i, c] = M[i, 0] * V[0, c] + M[i, 1] * V[1, c] + M[i, 2] * V[2, c]
            nrm += U[i, c] * U[i, c]
        nrm = math.sqrt(nrm)
        if nrm > 0.0:
            for i in range(3):
                U[i, c] /= nrm
    if s[1] <= 1e-300:  # rank 1: any unit vector orthogonal to u1
        a0, a1, a2 = 1.0, 0.0, 0.0
        if abs(U[0, 0]) > 0.6:
            a0, a1 = 0.0, 1.0
        d = a0 * U[0, 0] + a1 * U[1, 0] + a2 * U[2, 0]
        v0, v1, v2 = a0 - d * U[0, 0], a1 - d * U[1, 0], a2 - d * U[2, 0]
        nrm = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        U[0, 1], U[1, 1], U[2, 1] = v0 / nrm, v1 / nrm, v2 / nrm
    U[0, 2] = U[1, 0] * U[2, 1] - U[2, 0] * U[1, 1]
    U[1, 2] = U[2, 0] * U[0, 1] - U[0, 0] * U[2, 1]
    U[2, 2] = U[0, 0] * U[1, 1] - U[1, 0] * U[0, 1]


@njit(**_OPTS)
def _nullspace(A, nr, m, nc, N, perm, tol):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the ``nc - m`` null vectors of ``A[:nr, :nc]`` (rank ``m``) as rows of ``N``.

    Gauss-Jordan elimination with complete pivoting (``A`` destroyed); the vectors are not
    orthonormal. False when a pivot is below ``tol`` times the largest entry (rank deficient:
    a degenerate sample).
    """
    big = 0.0
    for i in range(nr):
        for j in range(nc):
            big = max(big, abs(A[i, j]))
    tol = tol * big
    for j in range(nc):
        perm[j] = j
    for r in range(m):
        best = 0.0
        pi = r
        pj = r
        for i in range(r, nr):
            for j in range(r, nc):
                a = abs(A[i, j])
                if a > best:
                    best = a
                    pi = i
                    pj = j
        if not best > tol:
            return False
        if pi != r:
            for j in range(nc):
                A[r, j], A[pi, j] = A[pi, j], A[r, j]
        if pj != r:
            for i in range(nr):
                A[i, r], A[i, pj] = A[i, pj], A[i, r]
            perm[r], perm[pj] = perm[pj], perm[r]
        piv = 1.0 / A[r, r]
        for j in range(r, nc):
            A[r, j] *= piv
        for i in range(nr):
            if i != r:
                f = A[i, r]
                if f != 0.0:
                    for j in range(r, nc):
                        A[i, j] -= f * A[r, j]
    for k in range(nc - m):
        for j in range(nc):
            N[k, j] = 0.0
        N[k, perm[m + k]] = 1.0
        for i in range(m):
            N[k, perm[i]] = -A[i, m + k]
    return True


@njit(**_OPTS)
def _null_partial(A, m, N):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Write the null space of ``A[:m, :9]`` (rank ``m``) as the rows of ``N`` (9 - m, 9).

    Gaussian elimination with partial pivoting on the first ``m`` columns, then back
    substitution with the last ``9 - m`` unknowns set to the unit vectors: a third of the
    work of :func:`_nullspace`'s complete pivoting, which the caller falls back to on False
    (a pivot below ``1e-10`` of the largest entry: the first ``m`` columns are nearly
    dependent). ``A`` destroyed.
    """
    big = 0.0
    for i in range(m):
        for j in range(9):
            big = max(big, abs(A[i, j]))
    tol = 1e-10 * big
    for c in range(m):
        p = c
        for i in range(c + 1, m):
            if abs(A[i, c]) > abs(A[p, c]):
                p = i
        if not abs(A[p, c]) > tol:
            return False
        if p != c:
            for j in range(c, 9):
                A[c, j], A[p, j] = A[p, j], A[c, j]
        inv = 1.0 / A[c, c]
        for i in range(c + 1, m):
            f = A[i, c] * inv
            if f != 0.0:
                for j in range(c + 1, 9):
                    A[i, j] -= f * A[c, j]
    for k in range(9 - m):
        for j in range(m, 9):
            N[k, j] = 1.0 if j == m + k else 0.0
        for i in range(m - 1, -1, -1):
            v = -A[i, m + k]
            for j in range(i + 1, m):
                v -= A[i, j] * N[k, j]
            N[k, i] = v / A[i, i]
    return True


@njit(**_OPTS)
def _solve(A, b, n, x):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Solve ``A[:n, :n] x = b[:n]`` (Gaussian elimination, partial pivoting; ``A, b`` destroyed).

    False when singular.
    """
    for c in range(n):
        p = c
        for i in range(c + 1, n):
            if abs(A[i, c]) > abs(A[p, c]):
                p = i
        if not abs(A[p, c]) > 0.0:
            return False
        if p != c:
            for j in range(n):
                A[c, j], A[p, j] = A[p, j], A[c, j]
            b[c], b[p] = b[p], b[c]
        for i in range(c + 1, n):
            f = A[i, c] / A[c, c]
            if f != 0.0:
                for j in range(c, n):
                    A[i, j] -= f * A[c, j]
                b[i] -= f * b[c]
    for i in range(n - 1, -1, -1):
        v = b[i]
        for j in range(i + 1, n):
            v -= A[i, j] * x[j]
        x[i] = v / A[i, i]
    return True


@njit(**_OPTS)
def _rodrigues(w0, w1, w2, R):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``R = exp([w]ₓ)`` (Rodrigues' formula, series near 0)."""
    th2 = w0 * w0 + w1 * w1 + w2 * w2
    if th2 < 1e-12:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        th = math.sqrt(th2)
        a, b = math.sin(th) / th, (1.0 - math.cos(th)) / th2
    R[0, 0] = 1.0 + b * (w0 * w0 - th2)
    R[1, 1] = 1.0 + b * (w1 * w1 - th2)
    R[2, 2] = 1.0 + b * (w2 * w2 - th2)
    R[0, 1] = -a * w2 + b * w0 * w1
    R[1, 0] = a * w2 + b * w0 * w1
    R[0, 2] = a * w1 + b * w0 * w2
    R[2, 0] = -a * w1 + b * w0 * w2
    R[1, 2] = -a * w0 + b * w1 * w2
    R[2, 1] = a * w0 + b * w1 * w2


# ---------------------------------------------------------------- errors and scores
@njit(**_OPTS)
def _sq_h(H, s, d, i):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Squared forward transfer error of correspondence ``i`` (inf at infinity)."""
    x, y = s[i, 0], s[i, 1]
    w = H[2, 0] * x + H[2, 1] * y + H[2, 2]
    u = (H[0, 0] * x + H[0, 1] * y + H[0, 2]) / w - d[i, 0]
    v = (H[1, 0] * x + H[1, 1] * y + H[1, 2]) / w - d[i, 1]
    e = u * u + v * v
    return e if e == e else np.inf


@njit(**_OPTS)
def _sampson_parts(F, p1, p2, i):  # type: ignore[no-untyped-def]  # pragma: no cover
    x1, y1, x2, y2 = p1[i, 0], p1[i, 1], p2[i, 0], p2[i, 1]
    a0 = F[0, 0] * x1 + F[0, 1] * y1 + F[0, 2]
    a1 = F[1, 0] * x1 + F[1, 1] * y1 + F[1, 2]
    a2 = F[2, 0] * x1 + F[2, 1] * y1 + F[2, 2]
    b0 = F[0, 0] * x2 + F[1, 0] * y2 + F[2, 0]
    b1 = F[0, 1] * x2 + F[1, 1] * y2 + F[2, 1]
    num = x2 * a0 + y2 * a1 + a2
    den = a0 * a0 + a1 * a1 + b0 * b0 + b1 * b1
    return num, den


@njit(**_OPTS)
def _sq_f(F, p1, p2, i):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    num, den = _sampson_parts(F, p1, p2, i)
    e = num * num / den
    return e if e == e else np.inf


@njit(**_OPTS)
def _sq(kind, M, p1, p2, i):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    if kind <= _H_SYMMETRIC:
        return _sq_h(M, p1, p2, i)
    return _sq_f(M, p1, p2, i)


@njit(**_OPTS)
def _score(kind, M, p1, p2, thr2, limit):  # type: ignore[no-untyped-def]  # pragma: no cover
    """MSAC score ``Σ min(e², τ²)`` and the inlier count; stops (count -1) above ``limit``."""
    sc = 0.0
    cnt = 0
    for i in range(p1.shape[0]):
        e = _sq(kind, M, p1, p2, i)
        if e < thr2:
            sc += e
            cnt += 1
        else:
            sc += thr2
        if sc > limit:
            return sc, -1
    return sc, cnt


@njit(**_OPTS)
def _score_sprt(kind, M, p1, p2, thr2, limit, log_in, log_out, log_a):  # type: ignore[no-untyped-def]  # pragma: no cover
    """:func:`_score` with Wald's sequential probability ratio test (SPRT).

    Randomised RANSAC of Matas & Chum (2008), "Randomized RANSAC with sequential
    probability ratio test", PAMI 30(10): while the correspondences are verified, the log
    likelihood ratio of "a bad model" against "a good model" grows by ``log_in =
    log(δ/ε)`` for an inlier and ``log_out = log((1 - δ)/(1 - ε))`` for an outlier (``ε``
    the inlier ratio of a good model, ``δ`` that of a bad one); the model is rejected as
    soon as it exceeds ``log A``, after a dozen correspondences for most bad models where
    the MSAC bound needs most of them. A good model is rejected with probability about
    ``1/A``. Returns ``(score, inliers, verified, inliers seen)``: ``inliers`` is -1 when
    the score exceeds ``limit``, -2 when the test rejects the model.
    """
    sc = 0.0
    cnt = 0
    lam = 0.0
    n = p1.shape[0]
    for i in range(n):
        e = _sq(kind, M, p1, p2, i)
        if e < thr2:
            sc += e
            cnt += 1
            lam += log_in
        else:
            sc += thr2
            lam += log_out
            if lam > log_a:
                return sc, -2, i + 1, cnt
        if sc > limit:
            return sc, -1, i + 1, cnt
    return sc, cnt, n, cnt


@njit(**_OPTS)
def _sprt_a(eps, delta, t_m, m_s):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Decision threshold ``log A`` of the SPRT (Matas & Chum 2008, eq. 13).

    ``A* = t_M C / m_S + 1 + log A*`` (iterated from ``A₀ = t_M C / m_S + 1``), ``C = (1 -
    δ) log((1 - δ)/(1 - ε)) + δ log(δ/ε)``; ``t_M`` the time of a hypothesis in units of
    one correspondence's verification, ``m_S`` the hypotheses per sample.
    """
    c = (1.0 - delta) * math.log((1.0 - delta) / (1.0 - eps)) + delta * math.log(delta / eps)
    a0 = t_m * c / m_s + 1.0
    a = a0
    for _ in range(10):
        a = a0 + math.log(a)
    return math.log(a)


@njit(**_OPTS)
def _sprt_params(eps, delta, t_m, m_s):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``(log(δ/ε), log((1-δ)/(1-ε)), log A, 1 - 1/A)`` of the SPRT (:func:`_sprt_a`)."""
    log_a = _sprt_a(eps, delta, t_m, m_s)
    return (
        math.log(delta / eps),
        math.log((1.0 - delta) / (1.0 - eps)),
        log_a,
        1.0 - math.exp(-log_a),
    )


@njit(**_OPTS)
def _select(kind, M, p1, p2, bound2, idx):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the indices of the correspondences with squared error below ``bound2``; count."""
    m = 0
    for i in range(p1.shape[0]):
        if _sq(kind, M, p1, p2, i) < bound2:
            idx[m] = i
            m += 1
    return m


# ---------------------------------------------------------------- Levenberg-Marquardt
@njit(**_OPTS)
def _f_build(q, aux, F, T):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``F = T2ᵀ (U diag(1, σ, 0) Vᵀ) T1``, ``U = exp([q₀₋₂]ₓ) U0``, ``V = exp([q₃₋₅]ₓ) V0``.

    ``aux``: ``T1, T2, U0, V0`` (Bartoli & Sturm 2004's orthonormal representation).
    """
    T1, T2, U0, V0 = aux[0], aux[1], aux[2], aux[3]
    R = np.empty((3, 3))
    U = np.empty((3, 3))
    V = np.empty((3, 3))
    _rodrigues(q[0], q[1], q[2], R)
    _mat3(R, U0, U)
    _rodrigues(q[3], q[4], q[5], R)
    _mat3(R, V0, V)
    for a in range(3):
        for b in range(3):
            R[a, b] = U[a, 0] * V[b, 0] + q[6] * U[a, 1] * V[b, 1]
    _mat3(R, T1, U)
    _mat3_tn(T2, U, F)


@njit(**_OPTS)
def _h_setup(kind, q, aux, M, Mi):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Fill ``M`` from the row-major ``q`` (``Mi``: its inverse, for the symmetric error).

    Returns the normalised -> pixel scales ``(sd, ss)`` of ``dst`` and ``src`` (``aux``:
    ``Ts, Td``).
    """
    for a in range(3):
        for b in range(3):
            M[a, b] = q[3 * a + b]
    if kind == _H_SYMMETRIC:
        _inv3(M, Mi)
    return 1.0 / aux[1, 0, 0], 1.0 / aux[0, 0, 0]


@njit(**_OPTS)
def _h_point(aux, p1, p2, i):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Correspondence ``i`` in Hartley-normalised coordinates: ``(x, y)`` source, ``(u, v)``."""
    Ts, Td = aux[0], aux[1]
    return (
        Ts[0, 0] * p1[i, 0] + Ts[0, 2],
        Ts[1, 1] * p1[i, 1] + Ts[1, 2],
        Td[0, 0] * p2[i, 0] + Td[0, 2],
        Td[1, 1] * p2[i, 1] + Td[1, 2],
    )


@njit(**_PY_OPTS)
def _residuals(kind, q, p1, p2, idx, m, aux, M, T, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Residuals of the selected correspondences at parameters ``q``; False if not finite.

    ``aux``: H: ``Ts, Td, Tdi``; F: ``T1, T2, U0, V0``.
    ``M, T`` (3, 3) scratch.
    """
    if kind <= _H_SYMMETRIC:
        sd, ss = _h_setup(kind, q, aux, M, T)
        k = 0
        for j in range(m):
            x, y, u, v = _h_point(aux, p1, p2, idx[j])
            w = M[2, 0] * x + M[2, 1] * y + M[2, 2]
            out[k] = ((M[0, 0] * x + M[0, 1] * y + M[0, 2]) / w - u) * sd
            out[k + 1] = ((M[1, 0] * x + M[1, 1] * y + M[1, 2]) / w - v) * sd
            k += 2
            if kind == _H_SYMMETRIC:
                w = T[2, 0] * u + T[2, 1] * v + T[2, 2]
                out[k] = ((T[0, 0] * u + T[0, 1] * v + T[0, 2]) / w - x) * ss
                out[k + 1] = ((T[1, 0] * u + T[1, 1] * v + T[1, 2]) / w - y) * ss
                k += 2
        n_out = k
    else:  # _F_ORTHO
        _f_build(q, aux, M, T)
        for j in range(m):
            num, den = _sampson_parts(M, p1, p2, idx[j])
            out[j] = num / math.sqrt(den)
        n_out = m
    for k in range(n_out):  # noqa: SIM110 - compiled: a plain loop
        if not math.isfinite(out[k]):
            return False
    return True


@njit(**_PY_OPTS)
def _h_jac(kind, q, p1, p2, idx, m, aux, M, Mi, J):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Analytic Jacobian of the homography residuals of :func:`_residuals` (row-major ``M``).

    Forward: ``∂(a/w)/∂M₀ⱼ = xⱼ/w``, ``∂(a/w)/∂M₂ⱼ = -a xⱼ/w²``; backward through
    ``∂M⁻¹/∂M_kl = -M⁻¹ E_kl M⁻¹``: ``∂r/∂M_kl = -(M⁻ᵀ α)_k (M⁻¹ y)_l`` with ``α`` the
    gradient of the residual in the first row / third row of ``M⁻¹`` (H&Z sec. 4.2.2).
    """
    sd, ss = _h_setup(kind, q, aux, M, Mi)
    k = 0
    for j in range(m):
        x, y, u, v = _h_point(aux, p1, p2, idx[j])
        xa = M[0, 0] * x + M[0, 1] * y + M[0, 2]
        xb = M[1, 0] * x + M[1, 1] * y + M[1, 2]
        w = M[2, 0] * x + M[2, 1] * y + M[2, 2]
        iw = sd / w
        for c in range(9):
            J[k, c] = 0.0
            J[k + 1, c] = 0.0
        J[k, 0] = x * iw
        J[k, 1] = y * iw
        J[k, 2] = iw
        J[k, 6] = -x * iw * xa / w
        J[k, 7] = -y * iw * xa / w
        J[k, 8] = -iw * xa / w
        J[k + 1, 3] = x * iw
        J[k + 1, 4] = y * iw
        J[k + 1, 5] = iw
        J[k + 1, 6] = -x * iw * xb / w
        J[k + 1, 7] = -y * iw * xb / w
        J[k + 1, 8] = -iw * xb / w
        k += 2
        if kind == _H_SYMMETRIC:
            c0 = Mi[0, 0] * u + Mi[0, 1] * v + Mi[0, 2]
            e0 = Mi[1, 0] * u + Mi[1, 1] * v + Mi[1, 2]
            f0 = Mi[2, 0] * u + Mi[2, 1] * v + Mi[2, 2]
            for r in range(2):
                # α: gradient of the residual in the rows 0 / 1 and 2 of M⁻¹ (times y)
                a0 = ss / f0 if r == 0 else 0.0
                a1 = ss / f0 if r == 1 else 0.0
                a2 = -ss * (c0 if r == 0 else e0) / (f0 * f0)
                for kk in range(3):
                    g = Mi[0, kk] * a0 + Mi[1, kk] * a1 + Mi[2, kk] * a2
                    J[k + r, 3 * kk] = -g * c0
                    J[k + r, 3 * kk + 1] = -g * e0
                    J[k + r, 3 * kk + 2] = -g * f0
            k += 2


@njit(**_OPTS)
def _n_res(kind, m):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    if kind == _H_FORWARD:
        return 2 * m
    if kind == _H_SYMMETRIC:
        return 4 * m
    return m


@njit(**_OPTS)
def _lm(kind, q, p1, p2, idx, m, aux, max_iter):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Minimise the squared residuals over ``q`` (in place) by Levenberg-Marquardt.

    As ``imageform.geometry._robust_core.levenberg_marquardt``: central-difference Jacobian,
    damping ``λ D`` with ``D`` the diagonal of ``JᵀJ`` (Marquardt 1963), ``λ`` divided by 10
    on a successful step, multiplied by 10 otherwise; stops when a step gains less than
    ``1e-12`` of the cost (``1e-8`` for the homography, whose analytic Jacobian and linear
    start leave it within that of its minimum after one or two steps: a relative cost
    change of ``1e-8`` moves the transfer error by about ``1e-4 σ``).
    """
    npar = q.shape[0]
    nr = _n_res(kind, m)
    r = np.empty(nr)
    rn = np.empty(nr)
    rp = np.empty(nr)
    J = np.empty((nr, npar))
    A = np.empty((npar, npar))
    Ad = np.empty((npar, npar))
    g = np.empty(npar)
    gd = np.empty(npar)
    step = np.empty(npar)
    qn = np.empty(npar)
    M = np.empty((3, 3))
    T = np.empty((3, 3))
    if not _residuals(kind, q, p1, p2, idx, m, aux, M, T, r):
        return
    cost = 0.0
    for k in range(nr):
        cost += r[k] * r[k]
    lam = 1e-3
    tol = 1e-8 if kind <= _H_SYMMETRIC else 1e-12
    for _ in range(max_iter):
        if kind <= _H_SYMMETRIC:
            _h_jac(kind, q, p1, p2, idx, m, aux, M, T, J)
        else:  # central differences (F, E)
            for c in range(npar):
                h = 1e-6 * max(1.0, abs(q[c]))
                for k in range(npar):
                    qn[k] = q[k]
                qn[c] = q[c] + h
                ok = _residuals(kind, qn, p1, p2, idx, m, aux, M, T, rp)
                qn[c] = q[c] - h
                ok &= _residuals(kind, qn, p1, p2, idx, m, aux, M, T, rn)
                for k in range(nr):
                    J[k, c] = (rp[k] - rn[k]) / (2.0 * h) if ok else 0.0
        for a in range(npar):
            g[a] = 0.0
            for k in range(nr):
                g[a] += J[k, a] * r[k]
            for b in range(a, npar):
                v = 0.0
                for k in range(nr):
                    v += J[k, a] * J[k, b]
                A[a, b] = v
                A[b, a] = v
        improved = False
        gain = 0.0
        while lam < 1e10:
            for a in range(npar):
                for b in range(npar):
                    Ad[a, b] = A[a, b]
                d = A[a, a] if A[a, a] > 0.0 else 1.0
                Ad[a, a] += lam * d
                gd[a] = -g[a]
            if not _solve(Ad, gd, npar, step):
                lam *= 10.0
                continue
            for a in range(npar):
                qn[a] = q[a] + step[a]
            cn = np.inf
            if _residuals(kind, qn, p1, p2, idx, m, aux, M, T, rn):
                cn = 0.0
                for k in range(nr):
                    cn += rn[k] * rn[k]
            if math.isfinite(cn) and cn <= cost:
                gain = cost - cn
                for a in range(npar):
                    q[a] = qn[a]
                for k in range(nr):
                    r[k] = rn[k]
                cost = cn
                lam = max(lam / 10.0, 1e-12)
                improved = True
                break
            lam *= 10.0
        if not improved or gain <= tol * max(cost, 1e-300):
            break


# ---------------------------------------------------------------- refinement support
@njit(**_OPTS)
def _chi2_cdf(c, k):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    if k == 1:
        return math.erf(math.sqrt(c / 2.0))
    if k == 2:
        return -math.expm1(-c / 2.0)
    if k == 3:
        return math.erf(math.sqrt(c / 2.0)) - math.sqrt(2.0 * c / math.pi) * math.exp(-c / 2.0)
    return 1.0 - math.exp(-c / 2.0) * (1.0 + c / 2.0)


@njit(**_PY_OPTS)
def _refine_support(mean_sq, threshold, dof, factor):  # type: ignore[no-untyped-def]  # pragma: no cover
    """As ``imageform.geometry._robust_core.refine_support`` from the inliers' mean ``e²``."""
    return _support_bound(mean_sq, threshold, dof, factor, 3.0, np.int64(100))


@njit(**_PY_OPTS)
def _support_bound(mean_sq, threshold, dof, factor, width, iters):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``width σ̂`` clipped to ``[τ, factor τ]``, ``σ̂`` by ``iters`` bisections (log scale).

    The bracket ``[1e-12 τ, 1e6 τ]`` is 41.4 wide in ``log σ``: 32 bisections give
    ``σ̂`` to 1e-8 (enough for a count), 100 to the last bit. The loop ends early, with
    the same result, once a step leaves the bracket unchanged (every later step would too).
    """
    m = mean_sq
    t2 = threshold * threshold
    if not math.isfinite(m) or m <= 0.0:
        return threshold
    if m >= t2 * dof / (dof + 2.0) * (1.0 - 1e-9):
        return threshold * factor
    a, b = 1e-12 * threshold, 1e6 * threshold
    for _ in range(iters):
        mid = math.sqrt(a * b)
        c = t2 / (mid * mid)
        lo = _chi2_cdf(c, dof)
        ms = (
            mid * mid * dof * _chi2_cdf(c, np.int64(dof + 2)) / lo
            if lo > 0
            else t2 * dof / (dof + 2.0)
        )
        a0, b0 = a, b
        if ms < m:
            a = mid
        else:
            b = mid
        if a == a0 and b == b0:
            break
    sigma = math.sqrt(a * b)
    return min(max(width * sigma, threshold), factor * threshold)


# ---------------------------------------------------------------- MAGSAC++ (sigma-consensus)
#: MAGSAC++ (Barath, Noskova, Ivashechkin & Matas 2020, "MAGSAC++, a fast, reliable and
#: accurate robust estimator", CVPR): the noise ``σ`` of an inlier is unknown, uniform on
#: ``[0, σ_max]``, and a residual ``r`` is marginalised over it. With ``ρ = 4`` degrees of
#: freedom (a correspondence's four coordinates, as the paper), ``k = 3.64`` (the 0.99
#: quantile of the χ distribution with 4 degrees of freedom) and ``x = r² / (2 σ_max²)``,
#: the loss (the paper's eq. 11, up to a constant factor) and the weight of its iteratively
#: re-weighted least squares (eq. 12, ``ρ'(r)/r``) are, for ``x < k²/2``,
#:
#:     loss(x)   ∝ γ(5/2, x) + x (Γ(3/2, x) - Γ(3/2, k²/2)),
#:     weight(x) ∝ Γ(3/2, x) - Γ(3/2, k²/2),
#:
#: with ``γ``, ``Γ`` the lower and upper incomplete gamma functions, and beyond ``k σ_max``
#: the loss is constant and the weight 0. Both are scaled here to 1 (the loss at ``k σ_max``,
#: the weight at ``r = 0``): the loss of an outlier is 1, as a truncated quadratic's at its
#: threshold. Closed forms: ``Γ(3/2, x) = (√π/2) erfc(√x) + √x e⁻ˣ``, ``γ(5/2, x) = Γ(5/2) -
#: (3/2) Γ(3/2, x) - x^{3/2} e⁻ˣ``.
MAGSAC_K = 3.64
_MS_XK = MAGSAC_K * MAGSAC_K / 2.0


def _upper_g15(x: float) -> float:
    return 0.5 * math.sqrt(math.pi) * math.erfc(math.sqrt(x)) + math.sqrt(x) * math.exp(-x)


_MS_GK = _upper_g15(_MS_XK)
_MS_G0 = 0.5 * math.sqrt(math.pi) - _MS_GK
_MS_LK = 0.75 * math.sqrt(math.pi) - 1.5 * _MS_GK - _MS_XK**1.5 * math.exp(-_MS_XK)


#: :func:`_magsac`'s loss tabulated on ``[0, k²/2]`` (``_MS_STEPS`` intervals), for the
#: score of every hypothesis (:func:`_magsac_loss`: linear interpolation, within 1e-7).
_MS_STEPS = 4096


def _magsac_py(x: float) -> float:
    sx = math.sqrt(x)
    ex = math.exp(-x)
    g = 0.5 * math.sqrt(math.pi) * math.erfc(sx) + sx * ex
    low = 0.75 * math.sqrt(math.pi) - 1.5 * g - x * sx * ex
    return (low + x * (g - _MS_GK)) / _MS_LK


_MS_TABLE = np.array([_magsac_py(_MS_XK * i / _MS_STEPS) for i in range(_MS_STEPS + 1)] + [1.0])
_MS_PER_X = _MS_STEPS / _MS_XK


@njit(**_OPTS)
def _magsac_loss(x):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """:func:`_magsac`'s loss at ``x`` from the table (1 beyond ``k σ_max``)."""
    if not x < _MS_XK:
        return 1.0
    u = x * _MS_PER_X
    i = int(u)
    return _MS_TABLE[i] + (u - i) * (_MS_TABLE[i + 1] - _MS_TABLE[i])


@njit(**_OPTS)
def _magsac(x):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """MAGSAC++'s loss and IRLS weight at ``x = r² / (2 σ_max²)``, each scaled to 1 (above)."""
    if not x < _MS_XK:
        return 1.0, 0.0
    sx = math.sqrt(x)
    ex = math.exp(-x)
    g = 0.5 * math.sqrt(math.pi) * math.erfc(sx) + sx * ex
    low = 0.75 * math.sqrt(math.pi) - 1.5 * g - x * sx * ex
    return (low + x * (g - _MS_GK)) / _MS_LK, (g - _MS_GK) / _MS_G0


# ---------------------------------------------------------------- epipolar helpers
@njit(**_OPTS)
def _rank2(F):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Replace ``F`` by the nearest rank-2 matrix (Frobenius norm).

    ``F (I - v vᵀ)``, ``v`` the eigenvector of ``FᵀF``'s smallest eigenvalue.
    """
    A = np.empty((3, 3))
    V = np.empty((3, 3))
    v = np.empty(3)
    _mat3_tn(F, F, A)
    _min_eigvec(A, V, v)
    for i in range(3):
        fv = F[i, 0] * v[0] + F[i, 1] * v[1] + F[i, 2] * v[2]
        for j in range(3):
            F[i, j] -= fv * v[j]


@njit(**_OPTS)
def _epi_row(x1, y1, x2, y2, w, row):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the row ``w (x2 ⊗ x1)`` of ``x2ᵀ F x1 = 0`` (F row-major)."""
    row[0] = w * x2 * x1
    row[1] = w * x2 * y1
    row[2] = w * x2
    row[3] = w * y2 * x1
    row[4] = w * y2 * y1
    row[5] = w * y2
    row[6] = w * x1
    row[7] = w * y1
    row[8] = w


@njit(**_OPTS)
def _f8(p1, p2, idx, m, w, F):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Weighted normalised 8-point fit on ``idx[:m]`` (weights ``w[:m]``) into ``F``, unit norm."""
    n1 = np.empty((m, 2))
    n2 = np.empty((m, 2))
    T1 = np.empty((3, 3))
    T2 = np.empty((3, 3))
    _hartley(p1, idx, m, n1, T1)
    _hartley(p2, idx, m, n2, T2)
    AtA = np.zeros((9, 9))
    row = np.empty(9)
    for k in range(m):
        _epi_row(n1[k, 0], n1[k, 1], n2[k, 0], n2[k, 1], w[k], row)
        for a in range(9):
            ra = row[a]
            for b in range(a, 9):
                AtA[a, b] += ra * row[b]
    for a in range(9):
        for b in range(a):
            AtA[a, b] = AtA[b, a]
    V = np.empty((9, 9))
    f = np.empty(9)
    _min_eigvec_psd(AtA, np.empty((9, 9)), np.empty(9), np.empty(9), V, f)
    Fn = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            Fn[a, b] = f[3 * a + b]
    _rank2(Fn)
    Tmp = np.empty((3, 3))
    _mat3(Fn, T1, Tmp)
    _mat3_tn(T2, Tmp, F)
    _fro_unit(F)


@njit(**_OPTS)
def _to_f(E, K1i, K2i, F):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``F = K2⁻ᵀ E K1⁻¹``."""
    T = np.empty((3, 3))
    _mat3(E, K1i, T)
    _mat3_tn(K2i, T, F)


@njit(**_OPTS)
def _refine_f(F, p1, p2, idx, m, max_iter):  # type: ignore[no-untyped-def]  # pragma: no cover
    """LM on the Sampson distances of ``idx[:m]`` over ``F``'s orthonormal representation.

    As ``imageform.geometry.twoview._refine_f``; ``F`` replaced when the result is finite.
    """
    aux = np.empty((4, 3, 3))
    nb = np.empty((m, 2))
    _hartley(p1, idx, m, nb, aux[0])
    _hartley(p2, idx, m, nb, aux[1])
    Ti1 = np.empty((3, 3))
    Ti2 = np.empty((3, 3))
    T = np.empty((3, 3))
    Fn = np.empty((3, 3))
    _inv3(aux[0], Ti1)
    _inv3(aux[1], Ti2)
    _mat3(F, Ti1, T)
    _mat3_tn(Ti2, T, Fn)  # T2⁻ᵀ F T1⁻¹
    s = np.empty(3)
    _svd3(Fn, aux[2], s, aux[3], T, Ti1)
    q = np.zeros(7)
    q[6] = s[1] / s[0]
    _lm(np.int64(_F_ORTHO), q, p1, p2, idx, m, aux, max_iter)
    _f_build(q, aux, Fn, T)
    if _finite3(Fn):
        _fro_unit(Fn)
        _copy3(Fn, F)


@njit(**_OPTS)
def _svd_uv(E, U, V):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``U``, ``V`` of ``E = U diag(s) Vᵀ`` (rotations; the singular values are not kept)."""
    s = np.empty(3)
    A = np.empty((3, 3))
    W = np.empty((3, 3))
    _svd3(E, U, s, V, A, W)


@njit(**_OPTS)
def _project_e(E):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Nearest essential matrix ``U diag(1, 1, 0) Vᵀ`` (unit Frobenius norm), in place."""
    U = np.empty((3, 3))
    V = np.empty((3, 3))
    _svd_uv(E, U, V)
    for a in range(3):
        for b in range(3):
            E[a, b] = U[a, 0] * V[b, 0] + U[a, 1] * V[b, 1]
    _fro_unit(E)


@njit(**_OPTS)
def _support(F, p1, p2, thr, factor, sel):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Select the refinement support (``_robust_core.refine_support``, dof 1) of ``F``.

    Returns the support's bound and the number of selected correspondences.
    """
    thr2 = thr * thr
    e_sum = 0.0
    cnt = 0
    for i in range(p1.shape[0]):
        e = _sq_f(F, p1, p2, i)
        if e < thr2:
            e_sum += e
            cnt += 1
    wide = _refine_support(e_sum / cnt if cnt > 0 else 0.0, thr, np.int64(1), factor)
    return wide, _select(np.int64(_F_ORTHO), F, p1, p2, wide * wide, sel)


@njit(**_ONCE)
def _support_count(kind, M, p1, p2, thr, dof, factor):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Count the correspondences within the refinement support of ``M``.

    The support is ``_robust_core.refine_support``'s: ``3σ̂`` between ``τ`` and
    ``factor τ``, ``σ̂`` from the truncated mean squared error of the inliers. It counts the
    inliers the noise model expects, not only those within ``τ``: with ``τ`` near ``σ``,
    a third of the true inliers lie beyond ``τ``, and an adaptive count from the inliers
    within ``τ`` alone draws several times the samples that the true inlier ratio asks for.
    """
    return _support_count_n(kind, M, p1, p2, thr, dof, factor, np.int64(100))


@njit(**_OPTS)
def _support_count_n(kind, M, p1, p2, thr, dof, factor, iters):  # type: ignore[no-untyped-def]  # pragma: no cover
    """:func:`_support_count` with ``σ̂`` from ``iters`` bisections (:func:`_support_bound`)."""
    thr2 = thr * thr
    e_sum = 0.0
    cnt = 0
    n = p1.shape[0]
    for i in range(n):
        e = _sq(kind, M, p1, p2, i)
        if e < thr2:
            e_sum += e
            cnt += 1
    wide = _support_bound(e_sum / cnt if cnt > 0 else 0.0, thr, dof, factor, 3.0, iters)
    w2 = wide * wide
    m = 0
    for i in range(n):
        if _sq(kind, M, p1, p2, i) < w2:
            m += 1
    return m


@njit(**_OPTS)
def _same(sel, m, sel2, m2):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    if m != m2:
        return False
    for k in range(m):  # noqa: SIM110 - compiled: a plain loop
        if sel[k] != sel2[k]:
            return False
    return True


@njit(**_OPTS)
def _refit_f(F, p1, p2, thr, factor, max_iter):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``_robust_core.refit_on_support`` for F (dof 1, at least 8, 3 rounds), in place."""
    n = p1.shape[0]
    sel = np.empty(n, dtype=np.int64)
    sel2 = np.empty(n, dtype=np.int64)
    wide, m = _support(F, p1, p2, thr, factor, sel)
    for _ in range(3):
        _refine_f(F, p1, p2, sel, m, max_iter)
        m2 = _select(np.int64(_F_ORTHO), F, p1, p2, wide * wide, sel2)
        if m2 < 8 or _same(sel, m, sel2, m2):
            break
        m = m2
        for k in range(m):
            sel[k] = sel2[k]


# ---------------------------------------------------------------- the cheirality vote
# (of ransac_e.essential_estimate and relative_pose.pose_from_essential: here, not in
# ransac_e, so that recover_pose does not compile the essential matrix's estimator)
@njit(**_OPTS)
def _candidates(E, U, Rs):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``Rs[0] = U W Vᵀ``, ``Rs[1] = U Wᵀ Vᵀ`` from ``E = U diag(s) Vᵀ``; ``t = ±U[:, 2]``.

    ``W = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]``, ``U, V`` rotations (H&Z result 9.19).
    """
    V = np.empty((3, 3))
    _svd_uv(E, U, V)
    for a in range(3):
        for b in range(3):
            # columns of U W: (u2, -u1, u3); of U Wᵀ: (-u2, u1, u3)
            Rs[0, a, b] = U[a, 1] * V[b, 0] - U[a, 0] * V[b, 1] + U[a, 2] * V[b, 2]
            Rs[1, a, b] = -U[a, 1] * V[b, 0] + U[a, 0] * V[b, 1] + U[a, 2] * V[b, 2]


@njit(**_OPTS)
def _in_front(R, t0, t1, t2, x1, y1, x2, y2, dmax):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Whether a correspondence is in front of both cameras, nearer than ``dmax``.

    The depths of the two rays' closest points, ``λ₂ x̃₂ ≈ λ₁ R x̃₁ + t`` by least squares.
    """
    a0 = R[0, 0] * x1 + R[0, 1] * y1 + R[0, 2]
    a1 = R[1, 0] * x1 + R[1, 1] * y1 + R[1, 2]
    a2 = R[2, 0] * x1 + R[2, 1] * y1 + R[2, 2]
    aa = a0 * a0 + a1 * a1 + a2 * a2
    ab = a0 * x2 + a1 * y2 + a2
    bb = x2 * x2 + y2 * y2 + 1.0
    at = a0 * t0 + a1 * t1 + a2 * t2
    bt = x2 * t0 + y2 * t1 + t2
    det = aa * bb - ab * ab
    z1 = (ab * bt - bb * at) / det
    z2 = (aa * bt - ab * at) / det
    return 0.0 < z1 < dmax and 0.0 < z2 < dmax


@njit(**_OPTS)
def _cheirality(E, q1, q2, idx, m, dmax, U, Rs):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Choose the ``(R, t)`` of ``E`` with the most of ``idx[:m]`` in front of both cameras.

    Returns ``(which R, sign of t, count)``; ``U, Rs`` receive the factorisation
    (:func:`_candidates`).
    """
    _candidates(E, U, Rs)
    best = -1
    bi = 0
    bs = 1.0
    for ri in range(2):
        R = Rs[ri]
        for sg in (1.0, -1.0):
            t0, t1, t2 = sg * U[0, 2], sg * U[1, 2], sg * U[2, 2]
            cnt = 0
            for k in range(m):
                i = idx[k]
                if _in_front(R, t0, t1, t2, q1[i, 0], q1[i, 1], q2[i, 0], q2[i, 1], dmax):
                    cnt += 1
            if cnt > best:
                best = cnt
                bi = ri
                bs = sg
    return bi, bs, best
