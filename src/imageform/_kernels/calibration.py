"""numba kernel of camera calibration's refinement (``geometry.calibration_refine``).

``calib_blocks(model, g, rvecs, tvecs, obj, img, view, jac, r, Ug, W, U, bg, bp)``: in one pass
over every view's points, the residuals ``r`` (M, 2) (projected minus observed pixels) and,
with ``jac``, the blocks of the normal equations :math:`J^T J`, :math:`J^T r` of the
Levenberg-Marquardt refinement: ``Ug`` (n, n) of the global parameters ``g`` (``fx, fy, cx,
cy, skew`` and the model's coefficients, all of them), each view's 6 x 6 pose block ``U``
(V, 6, 6) (``rvec`` then ``t``), their cross blocks ``W`` (V, n, 6) (globals by pose), and the
gradients ``bg`` (n,), ``bp`` (V, 6). ``model``: 0 Brown-Conrady ``(k1, k2, p1, p2, k3)``,
1 rational ``(k1, k2, p1, p2, k3, k4, k5, k6)``, 2 Kannala-Brandt ``(k1 ... k4)``; for models
1 and 2 a point at or behind the camera has residual ``inf``. Its twin is
``calibration_refine``'s NumPy path (``project_views`` and the blocks summed by array
products); ``tests/geometry/test_calibration_kernel.py`` checks one against the other.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["calib_blocks"]


@njit(
    "void(int64, float64[::1], float64[:, ::1], float64[:, ::1], float64[:, ::1],"
    " float64[:, ::1], int64[::1], boolean, float64[:, ::1], float64[:, ::1],"
    " float64[:, :, ::1], float64[:, :, ::1], float64[::1], float64[:, ::1])",
    nogil=True,
    error_model="numpy",
    no_cfunc_wrapper=True,
    lazy=True,
)
def calib_blocks(model, g, rvecs, tvecs, obj, img, view, jac, r, Ug, W, U, bg, bp):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Residuals and normal-equation blocks of the calibration (the module's docstring)."""
    V = rvecs.shape[0]
    ng = g.size
    nc = ng - 5
    fx, fy, cx, cy, sk = g[0], g[1], g[2], g[3], g[4]
    # each view's rotation and R G, G = d rvec's exponential map (Gallego & Yezzi 2015)
    Rv = np.empty((V, 3, 3))
    RG = np.empty((V, 3, 3))
    G = np.empty((3, 3))
    for k in range(V):
        a0, a1, a2 = rvecs[k, 0], rvecs[k, 1], rvecs[k, 2]
        th2 = a0 * a0 + a1 * a1 + a2 * a2
        small = th2 < 1e-12
        if small:
            a = 1.0 - th2 / 6.0
            b = 0.5 - th2 / 24.0
        else:
            th = np.sqrt(th2)
            a = np.sin(th) / th
            b = (1.0 - np.cos(th)) / (th * th)
        # K = [r]x; R = I + a K + b K K
        kx = ((0.0, -a2, a1), (a2, 0.0, -a0), (-a1, a0, 0.0))
        for i in range(3):
            for j in range(3):
                kk = kx[i][0] * kx[0][j] + kx[i][1] * kx[1][j] + kx[i][2] * kx[2][j]
                Rv[k, i, j] = (1.0 if i == j else 0.0) + a * kx[i][j] + b * kk
        if small:
            for i in range(3):
                for j in range(3):
                    G[i, j] = 1.0 if i == j else 0.0
        else:
            rr = (a0, a1, a2)
            for i in range(3):
                for j in range(3):
                    # (Rᵀ - I) [r]x
                    s = 0.0
                    for m in range(3):
                        s += (Rv[k, m, i] - (1.0 if m == i else 0.0)) * kx[m][j]
                    G[i, j] = (rr[i] * rr[j] + s) / th2
        for i in range(3):
            for j in range(3):
                RG[k, i, j] = Rv[k, i, 0] * G[0, j] + Rv[k, i, 1] * G[1, j] + Rv[k, i, 2] * G[2, j]
    if jac:
        Ug[:, :] = 0.0
        W[:, :, :] = 0.0
        U[:, :, :] = 0.0
        bg[:] = 0.0
        bp[:, :] = 0.0
    dxk = np.zeros(max(nc, 1))
    dyk = np.zeros(max(nc, 1))
    J0 = np.empty(ng)
    J1 = np.empty(ng)
    P0 = np.empty(6)
    P1 = np.empty(6)
    for m in range(obj.shape[0]):
        k = view[m]
        X0, X1, X2 = obj[m, 0], obj[m, 1], obj[m, 2]
        q0 = Rv[k, 0, 0] * X0 + Rv[k, 0, 1] * X1 + Rv[k, 0, 2] * X2
        q1 = Rv[k, 1, 0] * X0 + Rv[k, 1, 1] * X1 + Rv[k, 1, 2] * X2
        q2 = Rv[k, 2, 0] * X0 + Rv[k, 2, 1] * X1 + Rv[k, 2, 2] * X2
        c0, c1, c2 = q0 + tvecs[k, 0], q1 + tvecs[k, 1], q2 + tvecs[k, 2]
        iz = 1.0 / c2
        x, y = c0 * iz, c1 * iz
        r2 = x * x + y * y
        a11 = a12 = a22 = 0.0
        if model == 2:  # Kannala-Brandt
            k1, k2, k3, k4 = g[5], g[6], g[7], g[8]
            rad = np.sqrt(r2)
            at0 = rad < 1e-8
            rs = 1.0 if at0 else rad
            th = np.arctan(rad)
            t2 = th * th
            poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))
            s = 1.0 if at0 else th * poly / rs
            xd, yd = s * x, s * y
            if jac:
                t3 = th * t2
                p0 = t3 / rs
                p1 = t3 * t2 / rs
                p2 = t3 * t2 * t2 / rs
                p3 = t3 * t2 * t2 * t2 / rs
                dxk[0], dxk[1], dxk[2], dxk[3] = x * p0, x * p1, x * p2, x * p3
                dyk[0], dyk[1], dyk[2], dyk[3] = y * p0, y * p1, y * p2, y * p3
                dpoly = 1.0 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
                ds = 2.0 * (k1 - 1.0 / 3.0) if at0 else (dpoly / (1.0 + r2) - s) / r2
                a11 = s + ds * x * x
                a12 = ds * x * y
                a22 = s + ds * y * y
        else:
            k1, k2, p1, p2, k3 = g[5], g[6], g[7], g[8], g[9]
            r4 = r2 * r2
            r6 = r4 * r2
            num = 1.0 + k1 * r2 + k2 * r4 + k3 * r6
            if model == 1:  # rational
                k4, k5, k6 = g[10], g[11], g[12]
                iden = 1.0 / (1.0 + k4 * r2 + k5 * r4 + k6 * r6)
                rad = num * iden
            else:
                rad = num
            xd = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
            yd = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
            if jac:
                if model == 1:
                    d0, d1, d2 = r2 * iden, r4 * iden, r6 * iden
                    dxk[0], dxk[1], dxk[4] = x * d0, x * d1, x * d2
                    dyk[0], dyk[1], dyk[4] = y * d0, y * d1, y * d2
                    e0, e1, e2 = -rad * r2 * iden, -rad * r4 * iden, -rad * r6 * iden
                    dxk[5], dxk[6], dxk[7] = x * e0, x * e1, x * e2
                    dyk[5], dyk[6], dyk[7] = y * e0, y * e1, y * e2
                    drad = (
                        k1 + 2 * k2 * r2 + 3 * k3 * r4 - rad * (k4 + 2 * k5 * r2 + 3 * k6 * r4)
                    ) * iden
                else:
                    dxk[0], dxk[1], dxk[4] = x * r2, x * r4, x * r6
                    dyk[0], dyk[1], dyk[4] = y * r2, y * r4, y * r6
                    drad = k1 + 2 * k2 * r2 + 3 * k3 * r4
                dxk[2], dxk[3] = 2 * x * y, r2 + 2 * x * x
                dyk[2], dyk[3] = r2 + 2 * y * y, 2 * x * y
                a11 = rad + 2 * x * x * drad + 2 * p1 * y + 6 * p2 * x
                a12 = 2 * x * y * drad + 2 * p1 * x + 2 * p2 * y
                a22 = rad + 2 * y * y * drad + 6 * p1 * y + 2 * p2 * x
        u = fx * xd + sk * yd + cx
        v = fy * yd + cy
        if model != 0 and not c2 > 0.0:  # no image at or behind the camera: the step fails
            u = np.inf
            v = np.inf
        e0 = u - img[m, 0]
        e1 = v - img[m, 1]
        r[m, 0] = e0
        r[m, 1] = e1
        if not jac:
            continue
        # d(u, v)/d globals
        J0[0], J0[1], J0[2], J0[3], J0[4] = xd, 0.0, 1.0, 0.0, yd
        J1[0], J1[1], J1[2], J1[3], J1[4] = 0.0, yd, 0.0, 1.0, 0.0
        for j in range(nc):
            J0[5 + j] = fx * dxk[j] + sk * dyk[j]
            J1[5 + j] = fy * dyk[j]
        # d(u, v)/d cam = Kp A Pz
        b00 = fx * a11 + sk * a12
        b01 = fx * a12 + sk * a22
        b10 = fy * a12
        b11 = fy * a22
        xz, yz = x * iz, y * iz
        j00, j01, j02 = b00 * iz, b01 * iz, -(b00 * xz + b01 * yz)
        j10, j11, j12 = b10 * iz, b11 * iz, -(b10 * xz + b11 * yz)
        # d cam / d rvec = -[R X]x (R G)
        for j in range(3):
            m0, m1, m2 = RG[k, 0, j], RG[k, 1, j], RG[k, 2, j]
            d0 = q2 * m1 - q1 * m2
            d1 = q0 * m2 - q2 * m0
            d2 = q1 * m0 - q0 * m1
            P0[j] = j00 * d0 + j01 * d1 + j02 * d2
            P1[j] = j10 * d0 + j11 * d1 + j12 * d2
        P0[3], P0[4], P0[5] = j00, j01, j02
        P1[3], P1[4], P1[5] = j10, j11, j12
        for i in range(ng):
            g0, g1 = J0[i], J1[i]
            for j in range(i, ng):
                Ug[i, j] += g0 * J0[j] + g1 * J1[j]
            for j in range(6):
                W[k, i, j] += g0 * P0[j] + g1 * P1[j]
            bg[i] += g0 * e0 + g1 * e1
        for i in range(6):
            h0, h1 = P0[i], P1[i]
            for j in range(i, 6):
                U[k, i, j] += h0 * P0[j] + h1 * P1[j]
            bp[k, i] += h0 * e0 + h1 * e1
    if jac:
        for i in range(ng):
            for j in range(i):
                Ug[i, j] = Ug[j, i]
        for k in range(V):
            for i in range(6):
                for j in range(i):
                    U[k, i, j] = U[k, j, i]
