"""numba kernel of :func:`imageform.geometry.find_homography` (see :mod:`._kernels.ransac`)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import (
    _ONCE,
    _OPTS,
    _PY_OPTS,
    _SPRT_DELTA0,
    _copy3,
    _fro_unit,
    _hartley,
    _inliers_out,
    _inv3,
    _lm,
    _mat3,
    _min_eigvec_psd,
    _null_partial,
    _nullspace,
    _same,
    _sample,
    _score,
    _score_sprt,
    _select,
    _shuffled,
    _sprt_params,
    _sq_h,
    _support_bound,
    _support_count_n,
    _trials_for,
)

__all__ = ["homography_estimate"]

#: The SPRT's cost of a 4-point hypothesis, in forward transfer errors (a sample check,
#: an 8 x 9 null vector: about 100); one hypothesis per sample (Matas & Chum 2008).
_H_TM = 100.0


# ---------------------------------------------------------------- homography
@njit(**_OPTS)
def _cross2(p, i, j, k):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    return (p[j, 0] - p[i, 0]) * (p[k, 1] - p[i, 1]) - (p[j, 1] - p[i, 1]) * (p[k, 0] - p[i, 0])


@njit(**_OPTS)
def _h_sample_good(sn, dn, idx):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """No three points collinear, every triangle of the 4 with the same orientation in both."""
    for t in range(4):
        i = idx[0 if t > 0 else 1]
        j = idx[1 if t > 1 else 2]
        k = idx[2 if t > 2 else 3]
        a = _cross2(sn, i, j, k)
        b = _cross2(dn, i, j, k)
        if abs(a) < 1e-9 or abs(b) < 1e-9 or (a > 0.0) != (b > 0.0):
            return False
    return True


@njit(**_OPTS)
def _h_rows(x, y, u, v, w, A, r):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Write the two DLT rows of ``(x, y) -> (u, v)`` (weight ``w``) into ``A[r], A[r + 1]``."""
    A[r, 0] = 0.0
    A[r, 1] = 0.0
    A[r, 2] = 0.0
    A[r, 3] = -x * w
    A[r, 4] = -y * w
    A[r, 5] = -w
    A[r, 6] = v * x * w
    A[r, 7] = v * y * w
    A[r, 8] = v * w
    A[r + 1, 0] = x * w
    A[r + 1, 1] = y * w
    A[r + 1, 2] = w
    A[r + 1, 3] = 0.0
    A[r + 1, 4] = 0.0
    A[r + 1, 5] = 0.0
    A[r + 1, 6] = -u * x * w
    A[r + 1, 7] = -u * y * w
    A[r + 1, 8] = -u * w


@njit(**_OPTS)
def _h_sample_rows(sn, dn, idx, A):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write the 8 x 9 DLT system of the 4 correspondences ``idx`` (normalised) into ``A``."""
    for k in range(4):
        i = idx[k]
        _h_rows(sn[i, 0], sn[i, 1], dn[i, 0], dn[i, 1], 1.0, A, 2 * k)


@njit(**_OPTS)
def _h_denorm(h, Tdi, Ts, Tmp, H):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    for a in range(3):
        for b in range(3):
            Tmp[a, b] = h[3 * a + b]
    _mat3(Tdi, Tmp, H)
    _mat3(H, Ts, Tmp)
    for a in range(3):
        for b in range(3):
            H[a, b] = Tmp[a, b]


@njit(**_OPTS)
def _block3(A, r, c, sg, xx, xy, x, yy, y, one):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write ``sg [[xx, xy, x], [xy, yy, y], [x, y, one]]`` at ``A[r:r+3, c:c+3]``.

    And its transpose at ``A[c:c+3, r:r+3]``.
    """
    v = (xx, xy, x, xy, yy, y, x, y, one)
    for a in range(3):
        for b in range(3):
            A[r + a, c + b] = sg * v[3 * a + b]
            A[c + b, r + a] = sg * v[3 * a + b]


@njit(**_OPTS)
def _h_lsq(sn, dn, idx, m, Tdi, Ts, H, buf):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Least-squares DLT on the selected correspondences (normalised coordinates) into ``H``.

    ``AᵀA`` of the DLT rows of :func:`_h_rows` from moments: with ``p = (x, y, 1)``,
    ``AᵀA = [[P, 0, -U], [0, P, -V], [-U, -V, S]]``, ``P = Σ p pᵀ``, ``U = Σ u p pᵀ``,
    ``V = Σ v p pᵀ``, ``S = Σ (u² + v²) p pᵀ`` (24 sums per correspondence instead of
    162 products). ``buf`` (5, 9, 9) scratch.
    """
    P = np.zeros(6)
    U = np.zeros(6)
    V = np.zeros(6)
    S = np.zeros(6)
    for j in range(m):
        i = idx[j]
        x, y = sn[i, 0], sn[i, 1]
        u, v = dn[i, 0], dn[i, 1]
        q2 = u * u + v * v
        mo = (x * x, x * y, x, y * y, y, 1.0)
        for k in range(6):
            P[k] += mo[k]
            U[k] += u * mo[k]
            V[k] += v * mo[k]
            S[k] += q2 * mo[k]
    A = buf[0]
    for a in range(3):
        for b in range(3):
            A[a, 3 + b] = 0.0
            A[3 + b, a] = 0.0
    # the offsets as np.int64: literal ints would compile _block3 once per pair of literals
    o0, o3, o6 = np.int64(0), np.int64(3), np.int64(6)
    _block3(A, o0, o0, 1.0, P[0], P[1], P[2], P[3], P[4], P[5])
    _block3(A, o3, o3, 1.0, P[0], P[1], P[2], P[3], P[4], P[5])
    _block3(A, o6, o6, 1.0, S[0], S[1], S[2], S[3], S[4], S[5])
    _block3(A, o0, o6, -1.0, U[0], U[1], U[2], U[3], U[4], U[5])
    _block3(A, o3, o6, -1.0, V[0], V[1], V[2], V[3], V[4], V[5])
    h = buf[4, 0]
    _min_eigvec_psd(A, buf[1], buf[4, 1], buf[4, 2], buf[2], h)
    _h_denorm(h, Tdi, Ts, buf[3], H)


@njit(**_ONCE)
def _h_local_opt(H, s, d, sn, dn, Tdi, Ts, thr, sel, buf, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """LO-RANSAC: least-squares DLT on the inliers within 2, 1.5, 1 τ of the previous fit."""
    _copy3(H, out)
    for mult in (2.0, 1.5, 1.0):
        m = _select(np.int64(0), out, s, d, (mult * thr) ** 2, sel)
        if m < 5:
            break
        _h_lsq(sn, dn, sel, m, Tdi, Ts, out, buf)


@njit(**_ONCE)
def _h_refit(best, s, d, sn, dn, Tdi, Ts, thr, factor, width, n_inl, mode, max_iter, buf):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Refit ``best`` in place on its refinement support (dof 2, at least 4, 3 rounds).

    The support is ``width σ̂`` clipped to ``[τ, factor τ]`` (``_robust_core.refit_on_support``
    with the homography's ``width``); least-squares DLT fits until it stops changing (at
    most 3), then Levenberg-Marquardt on the forward (``mode`` 0) or symmetric (1) transfer
    error, again until the support stops changing (at most 3 rounds).
    """
    n = s.shape[0]
    thr2 = thr * thr
    e_sum = 0.0
    for i in range(n):
        e = _sq_h(best, s, d, i)
        if e < thr2:
            e_sum += e
    wide = _support_bound(e_sum / n_inl, thr, np.int64(2), factor, width, np.int64(100))
    w2 = wide * wide
    sel = np.empty(n, dtype=np.int64)
    sel2 = np.empty(n, dtype=np.int64)
    m = _select(np.int64(0), best, s, d, w2, sel)
    Hl = np.empty((3, 3))  # not buf[3]: _h_lsq denormalises through buf[3]
    for _ in range(3):  # cheap linear fits first: LM then starts next to its minimum
        if m < 5:
            break
        _h_lsq(sn, dn, sel, m, Tdi, Ts, Hl, buf)
        _copy3(Hl, best)
        m2 = _select(np.int64(0), best, s, d, w2, sel2)
        if m2 < 4 or _same(sel, m, sel2, m2):
            break
        m = m2
        for k in range(m):  # a loop: a slice copy compiles a shape check (seconds)
            sel[k] = sel2[k]
    aux = np.empty((3, 3, 3))
    scratch = np.empty((n, 2))
    Tmp = np.empty((3, 3))
    Hn = np.empty((3, 3))
    q = np.empty(9)
    for _ in range(3):
        # Hartley-normalise the selection, LM in normalised coordinates
        _hartley(s, sel, m, scratch, aux[0])
        _hartley(d, sel, m, scratch, aux[1])
        _inv3(aux[1], aux[2])
        _mat3(aux[1], best, Tmp)
        _inv3(aux[0], Hn)
        _mat3(Tmp, Hn, q.reshape((3, 3)))
        _fro_unit(q.reshape((3, 3)))
        _lm(mode, q, s, d, sel, m, aux, max_iter)
        ok = True
        for a in range(9):
            ok &= math.isfinite(q[a])
        if ok:
            _h_denorm(q, aux[2], aux[0], Tmp, best)
        m2 = _select(np.int64(0), best, s, d, w2, sel2)
        if m2 < 4 or _same(sel, m, sel2, m2):
            break
        m = m2
        for k in range(m):  # a loop: a slice copy compiles a shape check (seconds)
            sel[k] = sel2[k]


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64, float64, int64, uint64, int64, int64,"
    " float64, float64, float64, float64[:, ::1], boolean[::1], float64[::1])",
    **_PY_OPTS,
)
def homography_estimate(  # type: ignore[no-untyped-def]
    src,
    dst,
    thr,
    conf,
    max_trials,
    seed,
    mode,
    max_iter,
    factor,
    term,
    width,
    H_out,
    inl_out,
    rms_out,
):  # pragma: no cover
    """Robust homography ``d ~ H s``: RANSAC + LO, then LM on the refinement support.

    ``mode``: 0 forward, 1 symmetric transfer error, -1 no refinement; ``factor``,
    ``width``: the refinement support (:func:`_h_refit`); ``term``: the factor of the
    support whose inlier ratio sets the adaptive sample count. Writes ``H_out`` (pixels,
    ``H[2, 2] = 1`` unless near 0, then unit norm), its inliers (within ``τ`` of the forward
    transfer error) in ``inl_out`` (N,) and their RMS in ``rms_out[0]``, and returns the
    number of samples drawn, negated when no hypothesis had more than 4 inliers.
    """
    n = src.shape[0]
    thr2 = thr * thr
    state = np.empty(1, dtype=np.uint64)
    state[0] = seed
    order = _shuffled(state, n)
    s = np.empty((n, 2))
    d = np.empty((n, 2))
    for i in range(n):
        s[i, 0], s[i, 1] = src[order[i], 0], src[order[i], 1]
        d[i, 0], d[i, 1] = dst[order[i], 0], dst[order[i], 1]
    all_idx = np.arange(n)
    sn = np.empty((n, 2))
    dn = np.empty((n, 2))
    Ts = np.empty((3, 3))
    Td = np.empty((3, 3))
    Tdi = np.empty((3, 3))
    _hartley(s, all_idx, n, sn, Ts)
    _hartley(d, all_idx, n, dn, Td)
    _inv3(Td, Tdi)
    idx = np.empty(4, dtype=np.int64)
    A = np.empty((8, 9))
    N = np.empty((1, 9))
    perm = np.empty(9, dtype=np.int64)
    Tmp = np.empty((3, 3))
    H = np.empty((3, 3))
    Hlo = np.empty((3, 3))
    best = np.zeros((3, 3))
    sel = np.empty(n, dtype=np.int64)
    buf = np.empty((5, 9, 9))
    best_sc = np.inf
    best_cnt = -1
    # the SPRT (as the fundamental matrix's kernel): off until a best hypothesis gives ε
    sprt = False
    delta = _SPRT_DELTA0
    rej_frac = 0.0
    rej_n = 0
    log_in = 0.0
    log_out = 0.0
    log_a = np.inf
    a_pass = 1.0
    eps = 0.0
    needed = float(max_trials)
    drawn = 0
    while drawn < min(needed, max_trials):
        _sample(state, n, np.int64(4), idx)
        drawn += 1
        if not _h_sample_good(sn, dn, idx):
            continue
        _h_sample_rows(sn, dn, idx, A)
        if not _null_partial(A, np.int64(8), N):
            _h_sample_rows(sn, dn, idx, A)
            if not _nullspace(A, np.int64(8), np.int64(8), np.int64(9), N, perm, 1e-10):
                continue
        _h_denorm(N[0], Tdi, Ts, Tmp, H)
        if sprt:
            sc, cnt, tested, seen = _score_sprt(
                np.int64(0), H, s, d, thr2, best_sc, log_in, log_out, log_a
            )
            if cnt == -2:  # rejected by the SPRT: δ from the rejected hypotheses
                rej_frac += seen / tested
                rej_n += 1
                if rej_n % 16 == 0:
                    delta = min(max(rej_frac / rej_n, 1e-3), 0.5 * eps)
                    log_in, log_out, log_a, a_pass = _sprt_params(eps, delta, _H_TM, 1.0)
        else:
            sc, cnt = _score(np.int64(0), H, s, d, thr2, best_sc)
        if cnt < 0 or not sc < best_sc:
            continue
        if cnt / n > 2.0 * delta and cnt / n < 0.999:
            eps = cnt / n
            sprt = True
            log_in, log_out, log_a, a_pass = _sprt_params(eps, delta, _H_TM, 1.0)
        _copy3(H, best)
        best_sc = sc
        best_cnt = cnt
        if cnt > 4:
            _h_local_opt(H, s, d, sn, dn, Tdi, Ts, thr, sel, buf, Hlo)
            sc2, cnt2 = _score(np.int64(0), Hlo, s, d, thr2, best_sc)
            if cnt2 >= 0 and sc2 < best_sc:
                _copy3(Hlo, best)
                best_sc = sc2
                best_cnt = cnt2
        # σ̂ of the count to 1e-8 (32 bisections): the count, not the bound, matters here
        m = _support_count_n(np.int64(0), best, s, d, thr, np.int64(2), term, np.int64(32))
        needed = _trials_for(math.pow(m / n, 4.0) * a_pass, conf) if m < n else 0.0
    if best_cnt < 4:
        return -drawn
    if mode >= 0 and best_cnt > 4:
        _h_refit(best, s, d, sn, dn, Tdi, Ts, thr, factor, width, best_cnt, mode, max_iter, buf)
    nrm = 0.0
    for a in range(3):
        for b in range(3):
            nrm += best[a, b] * best[a, b]
    scale = best[2, 2] if abs(best[2, 2]) > 1e-12 * math.sqrt(nrm) else math.sqrt(nrm)
    for a in range(3):
        for b in range(3):
            H_out[a, b] = best[a, b] / scale
    _inliers_out(np.int64(0), H_out, s, d, thr2, order, inl_out, rms_out)
    return drawn
