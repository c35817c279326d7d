"""numba kernel of :func:`imageform.geometry.recover_pose` (the cheirality check)."""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit
from imageform._kernels.ransac import _OPTS, _PY_OPTS, _cheirality

__all__ = ["pose_from_essential"]


@njit(**_OPTS)
def _dlt_point(P2, x1, y1, x2, y2, S, X):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Homogeneous DLT point of ``P1 = [I | 0]``, ``P2`` into ``X`` (4), ``X[3] >= 0``.

    The right singular vector of the smallest singular value of the 4 x 4 DLT matrix
    ``A`` (H&Z sec. 12.2, no row scaling): the eigenvector of ``AᵀA`` of the smallest
    eigenvalue by inverse iteration from the closest points of the two rays (three steps;
    the eigenvalue gap is the squared ratio of the pixel noise to the image size; a shift of
    ``1e-13`` of the largest entry keeps exact data regular).
    """
    # rows of A: x1 P1₃ - P1₁, y1 P1₃ - P1₂, x2 P2₃ - P2₁, y2 P2₃ - P2₂
    A = np.empty((4, 4))
    A[0, 0], A[0, 1], A[0, 2], A[0, 3] = -1.0, 0.0, x1, 0.0
    A[1, 0], A[1, 1], A[1, 2], A[1, 3] = 0.0, -1.0, y1, 0.0
    for c in range(4):
        A[2, c] = x2 * P2[2, c] - P2[0, c]
        A[3, c] = y2 * P2[2, c] - P2[1, c]
    big = 0.0
    for i in range(4):
        for j in range(4):
            v = 0.0
            for k in range(4):
                v += A[k, i] * A[k, j]
            S[i, j] = v
            big = max(big, abs(v))
    # start: the point at unit depth on the first ray
    X[0], X[1], X[2], X[3] = x1, y1, 1.0, 1.0
    L = np.empty((4, 4))
    b = np.empty(4)
    for _ in range(3):
        for i in range(4):
            b[i] = X[i]
            for j in range(4):
                L[i, j] = S[i, j]
            L[i, i] += 1e-13 * big  # a shift: never singular, even on exact data
        # Gaussian elimination with partial pivoting
        for c in range(4):
            p = c
            for r in range(c + 1, 4):
                if abs(L[r, c]) > abs(L[p, c]):
                    p = r
            if p != c:
                for j in range(4):
                    L[c, j], L[p, j] = L[p, j], L[c, j]
                b[c], b[p] = b[p], b[c]
            piv = L[c, c]
            if piv == 0.0:
                piv = 1e-300 * max(big, 1e-300)
                L[c, c] = piv
            for r in range(c + 1, 4):
                f = L[r, c] / piv
                if f != 0.0:
                    for j in range(c, 4):
                        L[r, j] -= f * L[c, j]
                    b[r] -= f * b[c]
        for c in range(3, -1, -1):
            v = b[c]
            for j in range(c + 1, 4):
                v -= L[c, j] * X[j]
            X[c] = v / L[c, c]
        nrm = math.sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2] + X[3] * X[3])
        if not (nrm > 0.0 and math.isfinite(nrm)):
            X[0], X[1], X[2], X[3] = math.nan, math.nan, math.nan, math.nan
            return
        for i in range(4):
            X[i] /= nrm
    if X[3] < 0.0:
        for i in range(4):
            X[i] = -X[i]


@njit(
    "int64(float64[:, ::1], float64[:, ::1], float64[:, ::1], boolean[::1], float64,"
    " float64[:, ::1], float64[::1], float64[:, ::1], boolean[::1])",
    **_PY_OPTS,
    lazy=True,
)
def pose_from_essential(E, q1, q2, mask, dmax, R_out, t_out, X_out, good_out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """``recover_pose``'s NumPy path, compiled: the four ``(R, t)`` of ``E``, the cheirality vote.

    Writes the winner's ``R, t``, the DLT points ``X_out`` (N, 3; NaN where not good) and
    ``good_out``; returns the number of good points.
    """
    n = q1.shape[0]
    idx = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        if mask[i]:
            idx[m] = i
            m += 1
    U = np.empty((3, 3))
    Rs = np.empty((2, 3, 3))
    # np.int64(m): typed from its first assignment, m is Literal[int](0) until numba's type
    # inference reaches the loop's increment, and a kernel called with it is compiled for
    # that literal too (a whole second compilation of the cheirality vote, about a second)
    bi, bs, _ = _cheirality(E, q1, q2, idx, np.int64(m), dmax, U, Rs)
    for a in range(3):
        for b in range(3):
            R_out[a, b] = Rs[bi, a, b]
        t_out[a] = bs * U[a, 2]
    P2 = np.empty((3, 4))
    for a in range(3):
        for b in range(3):
            P2[a, b] = R_out[a, b]
        P2[a, 3] = t_out[a]
    S = np.empty((4, 4))
    X = np.empty(4)
    m = 0
    for i in range(n):
        _dlt_point(P2, q1[i, 0], q1[i, 1], q2[i, 0], q2[i, 1], S, X)
        z1 = X[2] / X[3]
        z2 = (P2[2, 0] * X[0] + P2[2, 1] * X[1] + P2[2, 2] * X[2] + P2[2, 3] * X[3]) / X[3]
        g = mask[i] and 0.0 < z1 < dmax and 0.0 < z2 < dmax
        good_out[i] = g
        if g:
            m += 1
            for c in range(3):
                X_out[i, c] = X[c] / X[3]
        else:
            for c in range(3):
                X_out[i, c] = math.nan
    return m
