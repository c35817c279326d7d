"""Numba kernels for lens distortion on normalised image coordinates.

Each kernel works on a C-contiguous ``(N, 2)`` array and has a plain Array-API twin in
:mod:`imageform.geometry.distortion` (the ``_*_xp`` functions); ``tests/geometry`` checks
that both agree (forward to 1e-14, inverse to 1e-12 in normalised units for float64).

Coefficient vectors follow OpenCV's order: Brown-Conrady ``(k1, k2, p1, p2, k3, k4, k5,
k6)``, Kannala-Brandt ``(k1, k2, k3, k4)``.

The points run on numba's threads through :func:`imageform._kernels.jit.run_tasks` (serial
``nogil`` kernels over a range of points), not ``parallel=True`` loops: numba's parallel
lowering cost about a second of CPU per kernel on a first run (the simulator's
``brown_conrady_undistort``).
"""

from __future__ import annotations

import math

import numpy as np

from imageform._kernels.jit import njit, run_tasks

__all__ = [
    "bc_distort_point",
    "bc_distort_xy",
    "bc_undistort_xy",
    "brown_conrady_distort",
    "brown_conrady_undistort",
    "kannala_brandt_distort",
    "kannala_brandt_undistort",
]


@njit(inline="always")
def bc_distort_xy(
    x: float,
    y: float,
    k1: float,
    k2: float,
    p1: float,
    p2: float,
    k3: float,
    k4: float,
    k5: float,
    k6: float,
) -> tuple[float, float]:
    """Brown-Conrady forward model for one point, the coefficients as scalars.

    The one statement of the model's arithmetic: the CPU kernels inline it (through
    :func:`bc_distort_point`) and the CUDA kernels compile its Python function as a device
    function (:mod:`imageform._cuda.geometry`).
    """
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    radial = (1.0 + k1 * r2 + k2 * r4 + k3 * r6) / (1.0 + k4 * r2 + k5 * r4 + k6 * r6)
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return xd, yd


@njit(inline="always")
def bc_distort_point(x: float, y: float, c: np.ndarray) -> tuple[float, float]:
    """Brown-Conrady forward model for one point (OpenCV's rational model)."""
    return bc_distort_xy(x, y, c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7])


@njit(inline="always")
def bc_undistort_xy(
    xd: float,
    yd: float,
    k1: float,
    k2: float,
    p1: float,
    p2: float,
    k3: float,
    k4: float,
    k5: float,
    k6: float,
    max_iter: int,
    tol: float,
) -> tuple[float, float, bool]:
    """Newton's method on ``distort(x) - x_d = 0`` from ``x = x_d`` for one point.

    At most ``max_iter`` steps (a fixed bound: no data-dependent loop beyond it); stops when
    ``|distort(x) - x_d| <= tol (1 + |x_d|)`` in both coordinates. Returns ``(x, y, ok)``,
    NaN and False where it did not converge or the model's Jacobian is not positive there.
    Shared by the CPU kernel :func:`brown_conrady_undistort` and the CUDA kernel.
    """
    x = xd
    y = yd
    lim = tol * (1.0 + math.sqrt(xd * xd + yd * yd))
    done = False
    det = 1.0
    b = 1.0
    for _ in range(max_iter + 1):
        r2 = x * x + y * y
        r4 = r2 * r2
        r6 = r4 * r2
        a = 1.0 + k1 * r2 + k2 * r4 + k3 * r6
        b = 1.0 + k4 * r2 + k5 * r4 + k6 * r6
        rad = a / b
        da = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r4
        db = k4 + 2.0 * k5 * r2 + 3.0 * k6 * r4
        drad = (da * b - a * db) / (b * b)
        fx = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd
        fy = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd
        j11 = rad + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x
        j12 = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y
        j22 = rad + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x
        det = j11 * j22 - j12 * j12
        if abs(fx) <= lim and abs(fy) <= lim:
            done = True
            break
        if det == 0.0 or not math.isfinite(det):
            break
        x = x - (j22 * fx - j12 * fy) / det
        y = y - (j11 * fy - j12 * fx) / det
    if done and det > 0.0 and b > 0.0:
        return x, y, True
    return math.nan, math.nan, False


def brown_conrady_distort(xy: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
    """Brown-Conrady forward model of every point of ``xy`` (N, 2) into ``out``."""
    run_tasks(_bc_distort, xy.shape[0], xy, c, out)


@njit(nogil=True)
def _bc_distort(
    i0: int, i1: int, xy: np.ndarray, c: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    for i in range(np.uint64(i0), np.uint64(i1)):  # unsigned: no wrap-around code
        xd, yd = bc_distort_point(xy[i, 0], xy[i, 1], c)
        out[i, 0] = xd
        out[i, 1] = yd


def brown_conrady_undistort(
    xyd: np.ndarray, c: np.ndarray, max_iter: int, tol: float, out: np.ndarray, ok: np.ndarray
) -> None:
    """Newton's method on ``distort(x) - x_d = 0`` from ``x = x_d``; NaN where it fails."""
    run_tasks(_bc_undistort, xyd.shape[0], xyd, c, max_iter, tol, out, ok)


@njit(nogil=True)
def _bc_undistort(
    i0: int,
    i1: int,
    xyd: np.ndarray,
    c: np.ndarray,
    max_iter: int,
    tol: float,
    out: np.ndarray,
    ok: np.ndarray,
) -> None:  # pragma: no cover
    k1, k2, p1, p2, k3, k4, k5, k6 = c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]
    for i in range(np.uint64(i0), np.uint64(i1)):  # unsigned: no wrap-around code
        x, y, good = bc_undistort_xy(
            xyd[i, 0], xyd[i, 1], k1, k2, p1, p2, k3, k4, k5, k6, max_iter, tol
        )
        out[i, 0] = x
        out[i, 1] = y
        ok[i] = good


def kannala_brandt_distort(xy: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
    """Kannala-Brandt forward model of every point of ``xy`` (N, 2) into ``out``."""
    run_tasks(_kb_distort, xy.shape[0], xy, c, out)


@njit(nogil=True)
def _kb_distort(
    i0: int, i1: int, xy: np.ndarray, c: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    k1, k2, k3, k4 = c[0], c[1], c[2], c[3]
    for i in range(np.uint64(i0), np.uint64(i1)):  # unsigned: no wrap-around code
        x = xy[i, 0]
        y = xy[i, 1]
        r = math.sqrt(x * x + y * y)
        th = math.atan(r)
        t2 = th * th
        thd = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
        s = thd / r if r > 0.0 else 1.0
        out[i, 0] = x * s
        out[i, 1] = y * s


def kannala_brandt_undistort(
    xyd: np.ndarray, c: np.ndarray, max_iter: int, tol: float, out: np.ndarray, ok: np.ndarray
) -> None:
    """Newton's method on ``θ (1 + k1 θ² + ...) = θ_d`` from ``θ = θ_d``."""
    run_tasks(_kb_undistort, xyd.shape[0], xyd, c, max_iter, tol, out, ok)


@njit(nogil=True)
def _kb_undistort(
    i0: int,
    i1: int,
    xyd: np.ndarray,
    c: np.ndarray,
    max_iter: int,
    tol: float,
    out: np.ndarray,
    ok: np.ndarray,
) -> None:  # pragma: no cover
    k1, k2, k3, k4 = c[0], c[1], c[2], c[3]
    half_pi = 0.5 * math.pi
    for i in range(np.uint64(i0), np.uint64(i1)):  # unsigned: no wrap-around code
        xd = xyd[i, 0]
        yd = xyd[i, 1]
        thd = math.sqrt(xd * xd + yd * yd)
        th = thd
        done = False
        dh = 1.0
        for _ in range(max_iter + 1):
            t2 = th * th
            h = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - thd
            dh = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)))
            if abs(h) <= tol * (1.0 + thd):
                done = True
                break
            if dh == 0.0 or not math.isfinite(dh):
                break
            th = th - h / dh
        if done and dh > 0.0 and 0.0 <= th < half_pi:
            s = math.tan(th) / thd if thd > 0.0 else 1.0
            out[i, 0] = xd * s
            out[i, 1] = yd * s
            ok[i] = True
        else:
            out[i, 0] = np.nan
            out[i, 1] = np.nan
            ok[i] = False
