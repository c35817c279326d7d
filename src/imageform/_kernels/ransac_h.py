"""numba kernel of :func:`imageform.geometry.find_homography` (see :mod:`._kernels.ransac`)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import (
    _OPTS,
    _copy3,
    _fro_unit,
    _hartley,
    _inv3,
    _lm,
    _mat3,
    _min_eigvec,
    _nullspace,
    _refine_support,
    _sample,
    _score,
    _select,
    _sq_h,
    _support_count,
    _trials_needed,
)

__all__ = ["homography_estimate"]


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
def _h_lsq(sn, dn, idx, m, Tdi, Ts, H):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Least-squares DLT on the selected correspondences (normalised coordinates) into ``H``."""
    AtA = np.zeros((9, 9))
    rows = np.empty((2, 9))
    for j in range(m):
        i = idx[j]
        _h_rows(sn[i, 0], sn[i, 1], dn[i, 0], dn[i, 1], 1.0, rows, 0)
        for r in range(2):
            for a in range(9):
                ra = rows[r, a]
                if ra != 0.0:
                    for b in range(9):
                        AtA[a, b] += ra * rows[r, b]
    V = np.empty((9, 9))
    h = np.empty(9)
    _min_eigvec(AtA, V, h)
    _h_denorm(h, Tdi, Ts, np.empty((3, 3)), H)


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64, float64, int64, uint64, int64, int64,"
    " float64, float64, float64[:, ::1])",
    **_OPTS,
)
def homography_estimate(s, d, thr, conf, max_trials, seed, mode, max_iter, factor, term, H_out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Robust homography ``d ~ H s``: RANSAC + LO, then LM on the refinement support.

    ``mode``: 0 forward, 1 symmetric transfer error, -1 no refinement. Writes ``H_out``
    (pixels, arbitrary scale) and returns the number of samples drawn, negated when no
    hypothesis had more than 4 inliers.
    """
    n = s.shape[0]
    thr2 = thr * thr
    all_idx = np.arange(n)
    sn = np.empty((n, 2))
    dn = np.empty((n, 2))
    Ts = np.empty((3, 3))
    Td = np.empty((3, 3))
    Tdi = np.empty((3, 3))
    _hartley(s, all_idx, n, sn, Ts)
    _hartley(d, all_idx, n, dn, Td)
    _inv3(Td, Tdi)
    state = np.empty(1, dtype=np.uint64)
    state[0] = seed
    idx = np.empty(4, dtype=np.int64)
    A = np.empty((8, 9))
    N = np.empty((1, 9))
    perm = np.empty(9, dtype=np.int64)
    Tmp = np.empty((3, 3))
    H = np.empty((3, 3))
    Hlo = np.empty((3, 3))
    best = np.zeros((3, 3))
    sel = np.empty(n, dtype=np.int64)
    best_sc = np.inf
    best_cnt = -1
    needed = float(max_trials)
    drawn = 0
    while drawn < min(needed, max_trials):
        _sample(state, n, np.int64(4), idx)
        drawn += 1
        if not _h_sample_good(sn, dn, idx):
            continue
        for k in range(4):
            i = idx[k]
            _h_rows(sn[i, 0], sn[i, 1], dn[i, 0], dn[i, 1], 1.0, A, 2 * k)
        if not _nullspace(A, np.int64(8), np.int64(8), np.int64(9), N, perm, 1e-10):
            continue
        _h_denorm(N[0], Tdi, Ts, Tmp, H)
        sc, cnt = _score(np.int64(0), H, s, d, thr2, best_sc)
        if cnt < 0 or not sc < best_sc:
            continue
        _copy3(H, best)
        best_sc = sc
        best_cnt = cnt
        if cnt > 4:
            # local optimisation: least squares on the inliers within 2, 1.5, 1 τ
            _copy3(H, Hlo)
            for mult in (2.0, 1.5, 1.0):
                m = _select(np.int64(0), Hlo, s, d, (mult * thr) ** 2, sel)
                if m < 5:
                    break
                _h_lsq(sn, dn, sel, m, Tdi, Ts, Hlo)
            sc2, cnt2 = _score(np.int64(0), Hlo, s, d, thr2, best_sc)
            if cnt2 >= 0 and sc2 < best_sc:
                _copy3(Hlo, best)
                best_sc = sc2
                best_cnt = cnt2
        m = _support_count(np.int64(0), best, s, d, thr, np.int64(2), term)
        needed = _trials_needed(m, n, np.int64(4), conf)
    if best_cnt < 4:
        return -drawn
    _copy3(best, H_out)
    if mode < 0 or best_cnt <= 4:
        return drawn
    # final: LM on the support (dof 2, at least 4 correspondences, 3 rounds)
    e_sum = 0.0
    for i in range(n):
        e = _sq_h(best, s, d, i)
        if e < thr2:
            e_sum += e
    wide = _refine_support(e_sum / best_cnt, thr, np.int64(2), factor)
    m = _select(np.int64(0), best, s, d, wide * wide, sel)
    sel2 = np.empty(n, dtype=np.int64)
    aux = np.empty((3, 3, 3))
    p1s = np.empty((n, 2))
    q = np.empty(9)
    for _ in range(3):
        # refit on sel: Hartley-normalise the selection, LM in normalised coordinates
        _hartley(s, sel, m, p1s, aux[0])
        _hartley(d, sel, m, p1s, aux[1])
        _inv3(aux[1], aux[2])
        _mat3(aux[1], best, Tmp)
        _inv3(aux[0], H)
        _mat3(Tmp, H, Hlo)
        _fro_unit(Hlo)
        for a in range(3):
            for b in range(3):
                q[3 * a + b] = Hlo[a, b]
        _lm(mode, q, s, d, sel, m, aux, max_iter)
        ok = True
        for a in range(9):
            ok &= math.isfinite(q[a])
        if ok:
            _h_denorm(q, aux[2], aux[0], Tmp, best)
        m2 = _select(np.int64(0), best, s, d, wide * wide, sel2)
        same = m2 == m
        if same:
            for k in range(m):
                if sel[k] != sel2[k]:
                    same = False
                    break
        if m2 < 4 or same:
            break
        m = m2
        for k in range(m):
            sel[k] = sel2[k]
    _copy3(best, H_out)
    return drawn
