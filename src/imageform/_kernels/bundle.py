"""numba kernels of bundle adjustment (``geometry.sfm._schur_lm``): the normal equations.

``normal_equations(...)`` sums each view's Jacobian blocks into the normal equations (``U``,
``V``, ``W``, the gradients); its twin is ``_schur_lm``'s array path.
``reduce_cameras(Y, W, start, views, cam, nc, S)`` adds to ``S`` (6 ``nc``, 6 ``nc``) the
matrix :math:`W V^{-1} W^T` of the Schur complement, from each view's blocks ``Y``
(:math:`W_o V_p^{-1}`) and ``W`` (M, 6, 3): for every point (its views ``views[start[p]:
start[p + 1]]``, ordered by camera), every two of its views ``a <= b`` add :math:`Y_a W_b^T`
to the block of their cameras, the lower half is then the upper's transpose; its twin is
:func:`imageform.geometry.sfm._camera_pairs`'s array path. ``tests/geometry/test_sfm_schur.py``
checks both against their twins and the reduced system against the dense product.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["normal_equations", "reduce_cameras"]


@njit(
    "void(float64[:, :, ::1], float64[:, :, ::1], int64[::1], int64[::1], int64[::1], int64,"
    " float64[:, ::1])",
    nogil=True,
    error_model="numpy",
    no_cfunc_wrapper=True,
    lazy=True,
)
def reduce_cameras(Y, W, start, views, cam, nc, S):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Add :math:`W V^{-1} W^T` to ``S``, symmetric (the module's docstring)."""
    for p in range(start.size - 1):
        for ia in range(start[p], start[p + 1]):
            a = views[ia]
            ra = 6 * cam[a]
            for ib in range(ia, start[p + 1]):
                b = views[ib]
                rb = 6 * cam[b]
                # two views of one point in one camera: the pair's transpose on the diagonal
                twin = ib != ia and ra == rb
                for i in range(6):
                    y0, y1, y2 = Y[a, i, 0], Y[a, i, 1], Y[a, i, 2]
                    for j in range(6):
                        v = y0 * W[b, j, 0] + y1 * W[b, j, 1] + y2 * W[b, j, 2]
                        S[ra + i, rb + j] += v
                        if twin:
                            S[ra + j, rb + i] += v
    for c in range(nc):
        for d in range(c + 1, nc):
            for i in range(6):
                for j in range(6):
                    S[6 * d + j, 6 * c + i] = S[6 * c + i, 6 * d + j]


@njit(
    "void(float64[:, ::1], float64[:, :, ::1], float64[:, ::1], float64[:, ::1], int64[::1],"
    " int64[::1], int64[::1], int64[::1], float64[:, ::1], float64[::1], float64[:, :, ::1],"
    " float64[:, :, ::1], float64[:, :, ::1], float64[:, ::1], float64[:, ::1],"
    " float64[:, :, ::1])",
    nogil=True,
    error_model="numpy",
    no_cfunc_wrapper=True,
    lazy=True,
)
def normal_equations(K, R, t, X, ci, pi, cs, hpos, res, w, A, U, V, gc, gp, Wo):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Add each view's blocks to the normal equations of bundle adjustment (``_schur_lm``).

    View ``o`` of point ``pi[o]`` in camera ``ci[o]`` (its free camera ``cs[o]`` and its row
    ``hpos[o]`` in ``Wo``, -1 when the camera is fixed), residual ``res[o]``, weight
    ``w[o]``, the lens's map ``A[o]`` (none when ``A`` is empty): its Jacobians :math:`J_X`
    (2 x 3) and :math:`J_c` (2 x 6, rotation then translation) add :math:`w J_X^T J_X` to
    ``V``, :math:`-w J_X^T r` to ``gp``, and for a free camera :math:`w J_c^T J_c` to ``U``,
    :math:`-w J_c^T r` to ``gc``, and :math:`w J_c^T J_X` is its ``Wo``. The twin is
    ``_schur_lm``'s array path.
    """
    fx, fy, sk = K[0, 0], K[1, 1], K[0, 1]
    lens = A.shape[0] > 0
    Jp = np.empty((2, 3))
    Jx = np.empty((2, 3))
    Jc = np.empty((2, 6))
    for o in range(ci.size):
        c = ci[o]
        p = pi[o]
        rx0 = R[c, 0, 0] * X[p, 0] + R[c, 0, 1] * X[p, 1] + R[c, 0, 2] * X[p, 2]
        rx1 = R[c, 1, 0] * X[p, 0] + R[c, 1, 1] * X[p, 1] + R[c, 1, 2] * X[p, 2]
        rx2 = R[c, 2, 0] * X[p, 0] + R[c, 2, 1] * X[p, 1] + R[c, 2, 2] * X[p, 2]
        x, y, z = rx0 + t[c, 0], rx1 + t[c, 1], rx2 + t[c, 2]
        if not abs(z) > 1e-9:
            z = 1e-9
        z2 = z * z
        j00, j01, j02 = fx / z, sk / z, -(fx * x + sk * y) / z2
        j10, j11, j12 = 0.0, fy / z, -fy * y / z2
        if lens:
            a00, a01, a10, a11 = A[o, 0, 0], A[o, 0, 1], A[o, 1, 0], A[o, 1, 1]
            Jp[0, 0] = a00 * j00 + a01 * j10
            Jp[0, 1] = a00 * j01 + a01 * j11
            Jp[0, 2] = a00 * j02 + a01 * j12
            Jp[1, 0] = a10 * j00 + a11 * j10
            Jp[1, 1] = a10 * j01 + a11 * j11
            Jp[1, 2] = a10 * j02 + a11 * j12
        else:
            Jp[0, 0], Jp[0, 1], Jp[0, 2] = j00, j01, j02
            Jp[1, 0], Jp[1, 1], Jp[1, 2] = j10, j11, j12
        for r in range(2):
            for j in range(3):
                Jx[r, j] = Jp[r, 0] * R[c, 0, j] + Jp[r, 1] * R[c, 1, j] + Jp[r, 2] * R[c, 2, j]
        wo = w[o]
        r0, r1 = res[o, 0], res[o, 1]
        for i in range(3):
            u0, u1 = wo * Jx[0, i], wo * Jx[1, i]
            for j in range(3):
                V[p, i, j] += u0 * Jx[0, j] + u1 * Jx[1, j]
            gp[p, i] -= u0 * r0 + u1 * r1
        q = hpos[o]
        if q < 0:
            continue
        cf = cs[o]
        # d/d omega: -Jp [RX]x
        for r in range(2):
            Jc[r, 0] = Jp[r, 2] * rx1 - Jp[r, 1] * rx2
            Jc[r, 1] = Jp[r, 0] * rx2 - Jp[r, 2] * rx0
            Jc[r, 2] = Jp[r, 1] * rx0 - Jp[r, 0] * rx1
            Jc[r, 3], Jc[r, 4], Jc[r, 5] = Jp[r, 0], Jp[r, 1], Jp[r, 2]
        for i in range(6):
            u0, u1 = wo * Jc[0, i], wo * Jc[1, i]
            for j in range(6):
                U[cf, i, j] += u0 * Jc[0, j] + u1 * Jc[1, j]
            for j in range(3):
                Wo[q, i, j] = u0 * Jx[0, j] + u1 * Jx[1, j]
            gc[cf, i] -= u0 * r0 + u1 * r1
