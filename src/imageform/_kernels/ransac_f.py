"""numba kernel of :func:`imageform.geometry.find_fundamental_matrix` (see ``ransac``)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import (
    _F_ORTHO,
    _ONCE,
    _OPTS,
    _PY_OPTS,
    _SPRT_DELTA0,
    _copy3,
    _epi_row,
    _f8,
    _fro_unit,
    _hartley,
    _inliers_out,
    _mat3,
    _mat3_tn,
    _null_partial,
    _nullspace,
    _rank2,
    _refit_f,
    _sample,
    _sampson_parts,
    _score,
    _score_sprt,
    _shuffled,
    _sprt_params,
    _support_count_n,
    _trials_for,
    _trials_needed,
)

__all__ = ["fundamental_estimate"]

#: Multiples of τ of the local optimisation's Sampson-weighted 8-point refits (as
#: ``twoview._LO_STEPS``).
_LO_STEPS = (3.0, 2.0, 2.0, 2.0)


@njit(**_OPTS)
def _cubic_roots(c0, c1, c2, c3, roots):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Real roots of ``c0 + c1 a + c2 a² + c3 a³`` (``c3 ≠ 0``) into ``roots``; their number.

    Closed form (trigonometric for three real roots, Cardano for one), then two Newton steps.
    """
    b = c2 / c3
    c = c1 / c3
    d = c0 / c3
    p = c - b * b / 3.0
    q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d
    disc = q * q / 4.0 + p * p * p / 27.0
    k = 0
    if disc > 0.0:
        sq = math.sqrt(disc)
        u = -q / 2.0 + sq
        v = -q / 2.0 - sq
        u = math.copysign(abs(u) ** (1.0 / 3.0), u)
        v = math.copysign(abs(v) ** (1.0 / 3.0), v)
        roots[0] = u + v - b / 3.0
        k = 1
    elif p == 0.0:
        roots[0] = -b / 3.0
        k = 1
    else:
        r = math.sqrt(-p / 3.0)
        arg = min(max(3.0 * q / (2.0 * p * r), -1.0), 1.0)
        phi = math.acos(arg)
        for j in range(3):
            roots[j] = 2.0 * r * math.cos(phi / 3.0 - 2.0 * math.pi * j / 3.0) - b / 3.0
        k = 3
    for j in range(k):
        a = roots[j]
        for _ in range(2):
            f = ((a + b) * a + c) * a + d
            df = (3.0 * a + 2.0 * b) * a + c
            if df != 0.0:
                a -= f / df
        roots[j] = a
    return k


@njit(**_OPTS)
def _det3(A):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    return (
        A[0, 0] * (A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1])
        - A[0, 1] * (A[1, 0] * A[2, 2] - A[1, 2] * A[2, 0])
        + A[0, 2] * (A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0])
    )


@njit(**_OPTS)
def _pencil_det(N, a, M):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """``det(a F1 + (1 - a) F2)`` of the null vectors ``N[1], N[0]`` (``M`` scratch)."""
    for r in range(3):
        for c in range(3):
            M[r, c] = a * N[1, 3 * r + c] + (1.0 - a) * N[0, 3 * r + c]
    return _det3(M)


@njit(**_PY_OPTS)
def _oriented(F, p1, p2, idx, m):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Whether the sample ``idx[:m]`` satisfies the oriented epipolar constraint of ``F``.

    Chum, Werner & Matas (2004), "Epipolar geometry estimation via RANSAC benefits from
    the oriented epipolar constraint", ICPR: points in front of both cameras give
    ``Fᵀ x2 ∼ e × x1`` with one sign for all correspondences (``e`` the epipole,
    ``F e = 0``, here the largest cross product of two rows of ``F``). A hypothesis from
    an outlier-free sample satisfies it; :func:`fundamental_estimate` drops the others
    before scoring them (as OpenCV's USAC does for F).
    """
    best = -1.0
    e0 = e1 = e2 = 0.0
    for a, b in ((0, 1), (0, 2), (1, 2)):
        c0 = F[a, 1] * F[b, 2] - F[a, 2] * F[b, 1]
        c1 = F[a, 2] * F[b, 0] - F[a, 0] * F[b, 2]
        c2 = F[a, 0] * F[b, 1] - F[a, 1] * F[b, 0]
        nn = c0 * c0 + c1 * c1 + c2 * c2
        if nn > best:
            best = nn
            e0, e1, e2 = c0, c1, c2
    pos = False
    neg = False
    for k in range(m):
        i = idx[k]
        x1, y1, x2, y2 = p1[i, 0], p1[i, 1], p2[i, 0], p2[i, 1]
        l0 = F[0, 0] * x2 + F[1, 0] * y2 + F[2, 0]
        l1 = F[0, 1] * x2 + F[1, 1] * y2 + F[2, 1]
        l2 = F[0, 2] * x2 + F[1, 2] * y2 + F[2, 2]
        s = l0 * (e1 - e2 * y1) + l1 * (e2 * x1 - e0) + l2 * (e0 * y1 - e1 * x1)
        pos |= s > 0.0
        neg |= s < 0.0
    return not (pos and neg)


@njit(**_PY_OPTS)
def _f7(p1, p2, idx, xs1, xs2, T1, T2, A, N, perm, Fs, W):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the one to three fundamental matrices (pixels, unit norm) of a 7-point sample.

    As ``geometry._minimal.f7``: the pencil ``a F1 + (1 - a) F2`` of the null space of the
    7 x 9 system (Hartley-normalised), ``det = 0`` a cubic in ``a`` (H&Z sec. 11.1.2).
    ``W`` (3, 3, 3) scratch (no allocation per sample).
    """
    _hartley(p1, idx, np.int64(7), xs1, T1)
    _hartley(p2, idx, np.int64(7), xs2, T2)
    for k in range(7):
        _epi_row(xs1[k, 0], xs1[k, 1], xs2[k, 0], xs2[k, 1], 1.0, A[k])
    if not _null_partial(A, np.int64(7), N):
        for k in range(7):
            _epi_row(xs1[k, 0], xs1[k, 1], xs2[k, 0], xs2[k, 1], 1.0, A[k])
        if not _nullspace(A, np.int64(7), np.int64(7), np.int64(9), N, perm, 1e-10):
            return 0
    M = W[0]
    Tmp = W[1]
    roots = W[2, 0]
    # det at a = 0, 1, -1, 2 -> cubic coefficients (inverse Vandermonde, increasing powers)
    d0 = _pencil_det(N, 0.0, M)
    d1 = _pencil_det(N, 1.0, M)
    dm = _pencil_det(N, -1.0, M)
    d2 = _pencil_det(N, 2.0, M)
    c0 = d0
    c1 = -d0 / 2.0 + d1 - dm / 3.0 - d2 / 6.0
    c2 = -d0 + d1 / 2.0 + dm / 2.0
    c3 = d0 / 2.0 - d1 / 2.0 - dm / 6.0 + d2 / 6.0
    scale = max(max(abs(c0), abs(c1)), max(abs(c2), abs(c3)))
    if not abs(c3) > 1e-10 * scale:
        return 0
    k = _cubic_roots(c0, c1, c2, c3, roots)
    out = 0
    for j in range(k):
        a = roots[j]
        for r in range(3):
            for c in range(3):
                M[r, c] = a * N[1, 3 * r + c] + (1.0 - a) * N[0, 3 * r + c]
        _mat3(M, T1, Tmp)
        _mat3_tn(T2, Tmp, Fs[out])
        _fro_unit(Fs[out])
        ok = True
        for r in range(3):
            for c in range(3):
                ok &= math.isfinite(Fs[out, r, c])
        if ok:
            out += 1
    return out


@njit(**_ONCE)
def _local_opt(F, p1, p2, thr, sel, w, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Sampson-weighted 8-point refits on the correspondences within 3τ, 2τ, 2τ, 2τ."""
    _copy3(F, out)
    n = p1.shape[0]
    for mult in _LO_STEPS:
        bound = (mult * thr) ** 2
        m = 0
        wsum = 0.0
        for i in range(n):
            num, den = _sampson_parts(out, p1, p2, i)
            if num * num < bound * den:
                sel[m] = i
                w[m] = 1.0 / math.sqrt(den)
                wsum += w[m]
                m += 1
        if m < 8:
            break
        wmean = wsum / m
        for k in range(m):
            w[k] /= wmean
        _f8(p1, p2, sel, np.int64(m), w, out)  # not Literal[int](0): one compilation


@njit(**_OPTS)
def _adopt(F, sc, cnt, p1, p2, thr, best, best_sc, best_cnt, sel, w, Flo):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Keep ``F`` (MSAC score ``sc``, ``cnt`` inliers) if it beats the best, then LO.

    LO-RANSAC (:func:`_local_opt`) when ``F`` has more than 7 inliers, its result kept when
    it scores better still. Returns the best's score and inlier count.
    """
    if sc < best_sc:
        _copy3(F, best)
        best_sc = sc
        best_cnt = cnt
    if cnt > 7:
        _local_opt(F, p1, p2, thr, sel, w, Flo)
        sc2, cnt2 = _score(np.int64(_F_ORTHO), Flo, p1, p2, thr * thr, best_sc)
        if cnt2 >= 0 and sc2 < best_sc:
            _copy3(Flo, best)
            best_sc = sc2
            best_cnt = cnt2
    return best_sc, best_cnt


@njit(**_OPTS)
def _needed(best, p1, p2, thr, term, conf, a_pass):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Adaptive sample count from the inlier ratio ``ε`` within the support of ``best``.

    ``log(1 - p) / log(1 - ε⁷ a_pass)``, ``a_pass`` the probability that the SPRT keeps a
    good hypothesis (1 without it).
    """
    n = p1.shape[0]
    m = _support_count_n(np.int64(_F_ORTHO), best, p1, p2, thr, np.int64(1), term, np.int64(32))
    if a_pass >= 1.0:
        return _trials_needed(m, n, np.int64(7), conf)
    if m >= n:
        return 0.0
    return _trials_for(math.pow(m / n, 7.0) * a_pass, conf)


#: The SPRT's costs (Matas & Chum 2008): a 7-point hypothesis costs about 200 Sampson
#: distances (a 7-point solve about 1 µs, a distance about 5 ns), 2 hypotheses per sample
#: on average (1 or 3).
_TM = 200.0
_MS = 2.0


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64, float64, int64, uint64, int64, int64,"
    " float64, float64, float64[:, ::1], boolean[::1], float64[::1])",
    **_PY_OPTS,
)
def fundamental_estimate(  # type: ignore[no-untyped-def]
    q1, q2, thr, conf, max_trials, seed, pool, max_iter, factor, term, F_out, inl_out, rms_out
):  # pragma: no cover
    """Robust ``F`` (``x2ᵀ F x1 = 0``): 7-point RANSAC + SPRT + LO + runner-up pool, then LM.

    As ``twoview.find_fundamental_matrix``'s NumPy path (``_robust_core.ransac`` with
    ``pool``): every hypothesis that beats the best is locally optimised; the ``pool`` best
    of the others are kept and locally optimised before sampling stops, sampling going on
    when that improves the best and the adaptive count asks for more. Hypotheses that fail
    the oriented epipolar constraint on their own sample (:func:`_oriented`) are dropped
    unscored (the NumPy path scores them: same result, more time). Beyond it,
    hypotheses are verified with Wald's SPRT (:func:`._kernels.ransac._score_sprt`) once a
    best hypothesis gives ``ε`` (its inlier ratio before LO: that of a hypothesis from an
    outlier-free sample), ``δ`` the mean inlier ratio seen in the rejected ones; the
    correspondences are verified in a random order (a permuted copy), as the test assumes,
    and the adaptive count allows for the good hypotheses it rejects. Writes ``F_out``
    (rank 2, refined, unit norm), its inliers (Sampson distance within ``τ``) in ``inl_out``
    (N,) and their RMS in ``rms_out[0]``, and returns the samples drawn, negated when no
    hypothesis had 8 inliers.
    """
    n = q1.shape[0]
    thr2 = thr * thr
    state = np.empty(1, dtype=np.uint64)
    state[0] = seed
    order = _shuffled(state, n)
    p1 = np.empty((n, 2))
    p2 = np.empty((n, 2))
    for i in range(n):
        p1[i, 0], p1[i, 1] = q1[order[i], 0], q1[order[i], 1]
        p2[i, 0], p2[i, 1] = q2[order[i], 0], q2[order[i], 1]
    idx = np.empty(7, dtype=np.int64)
    xs1 = np.empty((7, 2))
    xs2 = np.empty((7, 2))
    T1 = np.empty((3, 3))
    T2 = np.empty((3, 3))
    A = np.empty((7, 9))
    N = np.empty((2, 9))
    perm = np.empty(9, dtype=np.int64)
    Fs = np.empty((3, 3, 3))
    W = np.empty((3, 3, 3))
    best = np.zeros((3, 3))
    Flo = np.empty((3, 3))
    sel = np.empty(n, dtype=np.int64)
    w = np.empty(n)
    pool_F = np.empty((max(pool, 1), 3, 3))
    pool_sc = np.empty(max(pool, 1))
    n_pool = 0
    best_sc = np.inf
    best_cnt = np.int64(-1)  # not Literal[int](-1): _adopt compiles once
    # SPRT state: off until a best hypothesis gives ε
    sprt = False
    eps = 0.0
    delta = _SPRT_DELTA0
    rej_frac = 0.0
    rej_n = 0
    log_in = 0.0
    log_out = 0.0
    log_a = np.inf
    a_pass = 1.0
    needed = float(max_trials)
    drawn = 0
    while True:
        while drawn < min(needed, max_trials):
            _sample(state, n, np.int64(7), idx)
            drawn += 1
            k = _f7(p1, p2, idx, xs1, xs2, T1, T2, A, N, perm, Fs, W)
            for j in range(k):
                F = Fs[j]
                if not _oriented(F, p1, p2, idx, np.int64(7)):
                    continue
                limit = pool_sc[pool - 1] if (pool > 0 and n_pool == pool) else np.inf
                limit = max(limit, best_sc)
                if sprt:
                    sc, cnt, tested, seen = _score_sprt(
                        np.int64(_F_ORTHO), F, p1, p2, thr2, limit, log_in, log_out, log_a
                    )
                    if cnt == -2:  # rejected by the SPRT: δ from the rejected hypotheses
                        rej_frac += seen / tested
                        rej_n += 1
                        if rej_n % 64 == 0:
                            delta = min(max(rej_frac / rej_n, 1e-3), 0.5 * eps)
                            log_in, log_out, log_a, a_pass = _sprt_params(eps, delta, _TM, _MS)
                else:
                    sc, cnt = _score(np.int64(_F_ORTHO), F, p1, p2, thr2, limit)
                if cnt < 0:
                    continue
                if sc < best_sc:
                    if cnt / n > 2.0 * delta and cnt / n < 0.999:
                        eps = cnt / n
                        sprt = True
                        log_in, log_out, log_a, a_pass = _sprt_params(eps, delta, _TM, _MS)
                    best_sc, best_cnt = _adopt(
                        F, sc, cnt, p1, p2, thr, best, best_sc, best_cnt, sel, w, Flo
                    )
                    needed = _needed(best, p1, p2, thr, term, conf, a_pass)
                elif pool > 0:
                    # insert into the pool (sorted by score, the pool best first)
                    pos = n_pool
                    while pos > 0 and pool_sc[pos - 1] > sc:
                        pos -= 1
                    if pos < pool:
                        last = min(n_pool, pool - 1)
                        for q in range(last, pos, -1):
                            pool_sc[q] = pool_sc[q - 1]
                            _copy3(pool_F[q - 1], pool_F[q])
                        pool_sc[pos] = sc
                        _copy3(F, pool_F[pos])
                        n_pool = min(n_pool + 1, pool)
        if n_pool == 0:
            break
        before = best_sc
        for r in range(n_pool):
            F = pool_F[r]
            sc, cnt = _score(np.int64(_F_ORTHO), F, p1, p2, thr2, np.inf)
            best_sc, best_cnt = _adopt(
                F, sc, cnt, p1, p2, thr, best, best_sc, best_cnt, sel, w, Flo
            )
        n_pool = 0
        needed = _needed(best, p1, p2, thr, term, conf, a_pass)
        if best_sc >= before or drawn >= min(needed, max_trials):
            break
    if best_cnt < 8:
        return -drawn
    _rank2(best)
    _refit_f(best, p1, p2, thr, factor, max_iter)
    _fro_unit(best)
    _copy3(best, F_out)
    _inliers_out(np.int64(_F_ORTHO), best, p1, p2, thr2, order, inl_out, rms_out)
    return drawn
