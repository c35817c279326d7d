"""Numba kernel: batched Levenberg-Marquardt refinement of PnP poses.

One problem at a time per loop iteration, the problems on numba's threads through
:func:`imageform._kernels.jit.run_tasks` (a serial ``nogil`` kernel over a range of problems: a
``parallel=True`` ``prange`` cost seconds of CPU more to compile on a first ``imageform
pose``), no temporaries: the 6x6 normal equations are accumulated point by point. Same
algorithm, parametrisation (``R ← exp([δω]×) R``, ``t ← t + δt``), damping schedule and
cheirality rule as the plain twin :func:`imageform.geometry.pnp.refine_pose`; a test checks
agreement to 1e-9.
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit, run_tasks

__all__ = ["refine_pose_batch"]

#: Options of the helpers, which only compiled code calls: no Python wrapper and no C
#: callback is built, optimised and compiled to machine code for them (as ``ransac._OPTS``).
_OPTS = {"no_cfunc_wrapper": True, "no_cpython_wrapper": True}


@njit(**_OPTS)
def _cost(R, t, X, uv, K, w):  # type: ignore[no-untyped-def]  # pragma: no cover
    c = 0.0
    for i in range(X.shape[0]):
        if w[i] == 0.0:
            continue
        xc = R[0, 0] * X[i, 0] + R[0, 1] * X[i, 1] + R[0, 2] * X[i, 2] + t[0]
        yc = R[1, 0] * X[i, 0] + R[1, 1] * X[i, 1] + R[1, 2] * X[i, 2] + t[1]
        zc = R[2, 0] * X[i, 0] + R[2, 1] * X[i, 1] + R[2, 2] * X[i, 2] + t[2]
        if not zc > 0.0:
            return np.inf
        x, y = xc / zc, yc / zc
        du = K[0, 0] * x + K[0, 1] * y + K[0, 2] - uv[i, 0]
        dv = K[1, 1] * y + K[1, 2] - uv[i, 1]
        c += w[i] * (du * du + dv * dv)
    return c


@njit(**_OPTS)
def _rodrigues_left(d0, d1, d2, R, out):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Write ``exp([d]x) R`` into ``out``, in scalars.

    No temporaries, no matrix products: array expressions and slice copies cost seconds of
    compilation on a first run.
    """
    th2 = d0 * d0 + d1 * d1 + d2 * d2
    if th2 < 1e-12:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        th = math.sqrt(th2)
        a, b = math.sin(th) / th, (1.0 - math.cos(th)) / th2
    # E = I + a S + b S @ S, S = [d]x; S @ S = d d^T - |d|^2 I
    e00 = 1.0 + b * (d0 * d0 - th2)
    e11 = 1.0 + b * (d1 * d1 - th2)
    e22 = 1.0 + b * (d2 * d2 - th2)
    e01, e10 = -a * d2 + b * d0 * d1, a * d2 + b * d0 * d1
    e02, e20 = a * d1 + b * d0 * d2, -a * d1 + b * d0 * d2
    e12, e21 = -a * d0 + b * d1 * d2, a * d0 + b * d1 * d2
    for j in range(3):
        r0, r1, r2 = R[0, j], R[1, j], R[2, j]
        out[0, j] = e00 * r0 + e01 * r1 + e02 * r2
        out[1, j] = e10 * r0 + e11 * r1 + e12 * r2
        out[2, j] = e20 * r0 + e21 * r1 + e22 * r2


@njit(**_OPTS)
def _solve(M, g, x):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Solve ``M x = g`` into ``x`` (``M`` overwritten).

    Gaussian elimination with partial pivoting, as LAPACK's ``gesv`` (``np.linalg.solve``),
    without its compile cost.
    """
    n = g.shape[0]
    for i in range(n):
        x[i] = g[i]
    for c in range(n):
        p = c
        for r in range(c + 1, n):
            if abs(M[r, c]) > abs(M[p, c]):
                p = r
        if p != c:
            for k in range(n):
                M[c, k], M[p, k] = M[p, k], M[c, k]
            x[c], x[p] = x[p], x[c]
        piv = M[c, c]
        for r in range(c + 1, n):
            f = M[r, c] / piv
            if f != 0.0:
                for k in range(c + 1, n):
                    M[r, k] -= f * M[c, k]
                x[r] -= f * x[c]
    for c in range(n - 1, -1, -1):
        acc = x[c]
        for k in range(c + 1, n):
            acc -= M[c, k] * x[k]
        x[c] = acc / M[c, c]


def refine_pose_batch(
    R: np.ndarray,
    t: np.ndarray,
    X: np.ndarray,
    uv: np.ndarray,
    K: np.ndarray,
    w: np.ndarray,
    max_iter: int,
    tol: float,
    rms: np.ndarray,
) -> None:
    """Refine ``R (B, 3, 3)``, ``t (B, 3)`` in place; write the weighted RMS to ``rms (B,)``."""
    run_tasks(_refine_tasks, X.shape[0], R, t, X, uv, K, w, max_iter, tol, rms)


@njit(nogil=True)
def _refine_tasks(b0, b1, R, t, X, uv, K, w, max_iter, tol, rms):  # type: ignore[no-untyped-def]  # pragma: no cover
    # problems b0 .. b1 - 1; scratch allocated once, copies and fills in element loops (no
    # array expressions, slice assignments or .copy(): each costs compilation on a first run)
    N = X.shape[1]
    fx, s, fy = K[0, 0], K[0, 1], K[1, 1]
    Rb = np.empty((3, 3))
    tb = np.empty(3)
    Rn = np.empty((3, 3))
    tn = np.empty(3)
    A = np.empty((6, 6))
    M = np.empty((6, 6))
    g = np.empty(6)
    Ju = np.empty(6)
    Jv = np.empty(6)
    step = np.empty(6)
    for b in range(b0, b1):
        for j in range(3):
            tb[j] = t[b, j]
            for k in range(3):
                Rb[j, k] = R[b, j, k]
        cost = _cost(Rb, tb, X[b], uv[b], K, w[b])
        lam = 1e-3
        for _it in range(max_iter):
            for j in range(6):
                g[j] = 0.0
                for k in range(6):
                    A[j, k] = 0.0
            for i in range(N):
                wi = w[b, i]
                if wi == 0.0:
                    continue
                qx = Rb[0, 0] * X[b, i, 0] + Rb[0, 1] * X[b, i, 1] + Rb[0, 2] * X[b, i, 2]
                qy = Rb[1, 0] * X[b, i, 0] + Rb[1, 1] * X[b, i, 1] + Rb[1, 2] * X[b, i, 2]
                qz = Rb[2, 0] * X[b, i, 0] + Rb[2, 1] * X[b, i, 1] + Rb[2, 2] * X[b, i, 2]
                xc, yc, zc = qx + tb[0], qy + tb[1], qz + tb[2]
                iz = 1.0 / zc
                x, y = xc * iz, yc * iz
                ru = fx * x + s * y + K[0, 2] - uv[b, i, 0]
                rv = fy * y + K[1, 2] - uv[b, i, 1]
                a0, a1, a2 = fx * iz, s * iz, -(fx * x + s * y) * iz
                c1, c2 = fy * iz, -fy * y * iz
                # rotation part: q x du  (d cam/d δω = -[q]x)
                Ju[0] = qy * a2 - qz * a1
                Ju[1] = qz * a0 - qx * a2
                Ju[2] = qx * a1 - qy * a0
                Ju[3], Ju[4], Ju[5] = a0, a1, a2
                Jv[0] = qy * c2 - qz * c1
                Jv[1] = -qx * c2
                Jv[2] = qx * c1
                Jv[3], Jv[4], Jv[5] = 0.0, c1, c2
                for j in range(6):
                    g[j] += wi * (Ju[j] * ru + Jv[j] * rv)
                    for k in range(j, 6):
                        A[j, k] += wi * (Ju[j] * Ju[k] + Jv[j] * Jv[k])
            for j in range(6):
                for k in range(j):
                    A[j, k] = A[k, j]
            for j in range(6):
                for k in range(6):
                    M[j, k] = A[j, k]
                M[j, j] += lam * (A[j, j] if A[j, j] != 0.0 else 1.0)
            _solve(M, g, step)  # the step is minus the solution
            _rodrigues_left(-step[0], -step[1], -step[2], Rb, Rn)
            for j in range(3):
                tn[j] = tb[j] - step[3 + j]
            costn = _cost(Rn, tn, X[b], uv[b], K, w[b])
            if math.isfinite(costn) and costn <= cost:
                gain = cost - costn
                for j in range(3):
                    tb[j] = tn[j]
                    for k in range(3):
                        Rb[j, k] = Rn[j, k]
                done = gain <= tol * cost
                cost = costn
                lam = lam / 10.0
                if done:
                    break
            else:
                lam = lam * 10.0
                if lam >= 1e12:
                    break
        for j in range(3):
            t[b, j] = tb[j]
            for k in range(3):
                R[b, j, k] = Rb[j, k]
        wsum = 0.0
        for i in range(N):
            wsum += w[b, i]
        rms[b] = math.sqrt(cost / max(wsum, 1.0))
