"""Array-API implementations of the distortion models (the plain twins of the kernels).

Private: inputs are validated floating arrays of shape ``(..., 2)`` in namespace ``xp``;
the Newton inverses stop early on host arrays and run ``max_iter`` steps on a device (no
read-back: a fixed iteration count);
coefficients are Python floats. Every function avoids in-place updates so that PyTorch
gradients flow through the forward models.
"""

from __future__ import annotations

import math
from typing import Any

from imageform._backend import reads_values

__all__ = [
    "bc_distort_xp",
    "bc_undistort_xp",
    "default_tol",
    "division_distort_xp",
    "division_undistort_xp",
    "kb_distort_xp",
    "kb_undistort_xp",
]


def default_tol(xp: Any, dtype: Any) -> float:
    """64 ulp of 1 in ``dtype``: 1.4e-14 for float64, 7.6e-6 for float32."""
    return 64.0 * float(xp.finfo(dtype).eps)


def _split(xy: Any) -> tuple[Any, Any]:
    return xy[..., 0], xy[..., 1]


def _nan_like(a: Any, xp: Any) -> Any:
    return xp.full_like(a, math.nan)


def bc_distort_xp(xy: Any, c: tuple[float, ...], xp: Any) -> Any:
    k1, k2, p1, p2, k3, k4, k5, k6 = c
    x, y = _split(xy)
    r2 = x * x + y * y
    r4 = r2 * r2 if (k2 or k3 or k5 or k6) else None
    r6 = r4 * r2 if (k3 or k6) else None
    radial = _terms(1.0, ((k1, r2), (k2, r4), (k3, r6)))  # zero terms left out: same numbers
    if k4 or k5 or k6:
        radial = radial / _terms(1.0, ((k4, r2), (k5, r4), (k6, r6)))
    if not (p1 or p2):
        return xp.stack([x * radial, y * radial], axis=-1)
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return xp.stack([xd, yd], axis=-1)


def _terms(c0: float, terms: tuple[tuple[float, Any], ...]) -> Any:
    """``c0 + c1 t1 + c2 t2 + ...`` left to right, the terms with ``c = 0`` left out.

    Adding an exact zero changes nothing (but the sign of a zero), so the result is the
    full sum's, with fewer operators on a device.
    """
    out: Any = c0
    for coef, t in terms:
        if coef:
            out = out + coef * t
    return out


def bc_undistort_xp(
    xyd: Any, c: tuple[float, ...], xp: Any, max_iter: int, tol: float
) -> tuple[Any, Any]:
    """Newton's method with the analytic Jacobian; see ``brown_conrady_undistort`` kernel."""
    k1, k2, p1, p2, k3, k4, k5, k6 = c
    # the rational and tangential terms only when their coefficients are not zero (the
    # same numbers: those terms are exact zeros), so a radial model runs fewer operators
    rational = bool(k4 or k5 or k6)
    tangential = bool(p1 or p2)
    xd, yd = _split(xyd)
    lim = tol * (1.0 + xp.sqrt(xd * xd + yd * yd))
    x, y = xd, yd
    done = xp.zeros_like(xd, dtype=xp.bool)
    det = xp.ones_like(xd)
    b: Any = 1.0
    for _ in range(max_iter + 1):
        r2 = x * x + y * y
        r4 = r2 * r2 if (k2 or k3 or rational) else None
        r6 = r4 * r2 if (k3 or k6) else None
        # 1 + k1 r² + k2 r⁴ + k3 r⁶ and its derivative in r², zero terms left out
        a = _terms(1.0, ((k1, r2), (k2, r4), (k3, r6)))
        da = _terms(k1, ((2.0 * k2, r2), (3.0 * k3, r4)))
        if rational:
            b = _terms(1.0, ((k4, r2), (k5, r4), (k6, r6)))
            rad = a / b
            drad = (da * b - a * _terms(k4, ((2.0 * k5, r2), (3.0 * k6, r4)))) / (b * b)
        else:
            rad, drad = a, da
        if tangential:
            fx = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd
            fy = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd
            j11 = rad + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x
            j12 = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y
            j22 = rad + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x
        else:
            fx = x * rad - xd
            fy = y * rad - yd
            j11 = rad + 2.0 * x * x * drad
            j12 = 2.0 * x * y * drad
            j22 = rad + 2.0 * y * y * drad
        det = j11 * j22 - j12 * j12
        done = done | ((xp.abs(fx) <= lim) & (xp.abs(fy) <= lim))
        if reads_values(done) and bool(xp.all(done)):  # early exit on the host only
            break
        x = xp.where(done, x, x - (j22 * fx - j12 * fy) / det)
        y = xp.where(done, y, y - (j11 * fy - j12 * fx) / det)
    ok = done & (det > 0.0)
    if rational:
        ok = ok & (b > 0.0)
    x = xp.where(ok, x, math.nan)
    y = xp.where(ok, y, math.nan)
    return xp.stack([x, y], axis=-1), ok


def _kb_poly(th: Any, c: tuple[float, ...]) -> tuple[Any, Any]:
    k1, k2, k3, k4 = c
    t2 = th * th
    h = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
    dh = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)))
    return h, dh


def kb_distort_xp(xy: Any, c: tuple[float, ...], xp: Any) -> Any:
    x, y = _split(xy)
    r = xp.sqrt(x * x + y * y)
    thd, _ = _kb_poly(xp.atan(r), c)
    pos = r > 0.0
    safe_r = xp.where(pos, r, 1.0)
    s = xp.where(pos, thd / safe_r, 1.0)
    return xp.stack([x * s, y * s], axis=-1)


def kb_undistort_xp(
    xyd: Any, c: tuple[float, ...], xp: Any, max_iter: int, tol: float
) -> tuple[Any, Any]:
    xd, yd = _split(xyd)
    thd = xp.sqrt(xd * xd + yd * yd)
    th = thd
    done = xp.zeros_like(thd, dtype=xp.bool)
    dh = xp.ones_like(thd)
    for _ in range(max_iter + 1):
        h, dh = _kb_poly(th, c)
        h = h - thd
        done = done | (xp.abs(h) <= tol * (1.0 + thd))
        if reads_values(done) and bool(xp.all(done)):  # early exit on the host only
            break
        th = xp.where(done, th, th - h / dh)
    ok = done & (dh > 0.0) & (th >= 0.0) & (th < math.pi / 2)
    pos = thd > 0.0
    safe_th = xp.where(ok, th, 0.0)
    safe_thd = xp.where(pos, thd, 1.0)
    s = xp.where(pos, xp.tan(safe_th) / safe_thd, 1.0)
    s = xp.where(ok, s, math.nan)
    return xp.stack([xd * s, yd * s], axis=-1), ok


def division_undistort_xp(xyd: Any, c: tuple[float, ...], xp: Any) -> tuple[Any, Any]:
    """Undistort in closed form ``x_u = x_d / (1 + k1 r_d² + k2 r_d⁴)``; invalid if divisor ≤ 0."""
    k1, k2 = c
    xd, yd = _split(xyd)
    r2 = xd * xd + yd * yd
    den = 1.0 + k1 * r2 + k2 * r2 * r2
    ok = den > 0.0
    safe = xp.where(ok, den, 1.0)
    x = xp.where(ok, xd / safe, math.nan)
    y = xp.where(ok, yd / safe, math.nan)
    return xp.stack([x, y], axis=-1), ok


def division_distort_xp(
    xy: Any, c: tuple[float, ...], xp: Any, max_iter: int, tol: float
) -> tuple[Any, Any]:
    """Solve ``r_d = r_u (1 + k1 r_d² + k2 r_d⁴)`` for the root nearest the centre.

    Newton's method from ``r_d = r_u``; a root is accepted when the map ``r_d → r_u`` is
    increasing there (``d r_u / d r_d > 0``), i.e. on the branch continuous with the centre.
    """
    k1, k2 = c
    x, y = _split(xy)
    ru = xp.sqrt(x * x + y * y)
    rd = ru
    done = xp.zeros_like(ru, dtype=xp.bool)
    for _ in range(max_iter + 1):
        rd2 = rd * rd
        g = rd - ru * (1.0 + k1 * rd2 + k2 * rd2 * rd2)
        dg = 1.0 - ru * (2.0 * k1 * rd + 4.0 * k2 * rd2 * rd)
        done = done | (xp.abs(g) <= tol * (1.0 + ru))
        if reads_values(done) and bool(xp.all(done)):  # early exit on the host only
            break
        rd = xp.where(done, rd, rd - g / dg)
    rd2 = rd * rd
    den = 1.0 + k1 * rd2 + k2 * rd2 * rd2
    # d r_u / d r_d = (den - r_d * d den/d r_d) / den²  > 0 on the valid branch
    slope = den - rd * (2.0 * k1 * rd + 4.0 * k2 * rd2 * rd)
    ok = done & (den > 0.0) & (slope > 0.0) & (rd >= 0.0)
    pos = ru > 0.0
    safe_ru = xp.where(pos, ru, 1.0)
    s = xp.where(pos, rd / safe_ru, 1.0)
    s = xp.where(ok, s, math.nan)
    return xp.stack([x * s, y * s], axis=-1), ok
