"""CIEDE2000 colour difference: a numba kernel and its plain Array-API twin.

Both compute the CIEDE2000 formula of Sharma, Wu & Dalal (2005), eqs. (1)-(22), rearranged so
that the hue terms need no trigonometry on hue angles:

- ``ΔH'`` from the cross and dot products of the two ``(a', b*)`` vectors:
  ``ΔH' = 2 sqrt(C1' C2') sin(Δh'/2)``; with ``p = C1'C2'``, ``d = a1'a2' + b1 b2`` and
  ``x = a1'b2 - a2'b1`` (so ``d = p cos Δh'``, ``x = p sin Δh'``) this is
  ``x sqrt(2 / (p + d))`` where ``d >= 0`` and ``±sqrt(2 (p - d))`` where ``d < 0``; each form is
  free of cancellation on its side (the kernel writes the first as ``2 x sqrt(p) / |v|`` with
  the bisector ``v`` below, ``|v|² = 2 p (p + d)``, to share its division).
- the mean hue ``h̄'`` as the direction of the bisector of the two unit hue vectors (their sum
  where ``Δh'`` is acute, the normal of their difference where it is obtuse, which is exact at
  ``|Δh'| = 180°`` where Sharma's rule takes ``(h1' + h2')/2``, i.e. ``min(h1', h2') + 90°``).
- ``T`` from ``cos h̄'``, ``sin h̄'`` by the multiple-angle identities (no sine/cosine calls).
- ``Δθ`` needs ``h̄'`` in degrees: one ``atan2``, ``exp`` and ``sin`` per pixel. The numba kernel
  evaluates them with branch-free polynomials (atan: least-squares fit of degree 11 in ``z²`` on
  ``|z| <= tan(π/8)``, max error 2.2e-16; exp: Taylor of degree 14 on ``y/256`` then 8 squarings;
  sin: Taylor of degree 17 on ``[0, π/3]``) so that LLVM vectorises the loop; the twin calls the
  library's ``atan2``, ``exp`` and ``sin``. They agree to about 1e-12 (tested).
- the polynomial helpers allow FMA contraction (``fastmath={"contract"}``; LLVM inlines them
  and keeps their flags), the main body does not: a fused ``a1'b2 - a2'b1`` would not be
  exactly 0 for exactly opposite hues (Sharma's pair 14);
- the kernel folds the divisions by ``S_L``, ``S_C``, ``S_H`` and ``R_C``'s denominator into one
  reciprocal: square roots and divisions dominate its cost once the loop is vectorised.

The twin is the reference for the kernel and the path for non-NumPy arrays (PyTorch gradients
flow through it). Inputs here are clean float arrays of shape ``(..., 3)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._kernels.jit import njit, run_tasks

__all__ = ["ciede2000_numba", "ciede2000_twin"]

# 25**7 (Sharma et al. 2005, eq. 4 and 21).
_P25_7 = 6103515625.0
_DEG = 180.0 / math.pi
# cos/sin of the phase constants of T (Sharma et al. 2005, eq. 15): 30°, 6°, 63°.
_C30, _S30 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
_C6, _S6 = math.cos(math.radians(6.0)), math.sin(math.radians(6.0))
_C63, _S63 = math.cos(math.radians(63.0)), math.sin(math.radians(63.0))
_TAN_PI_8 = math.tan(math.pi / 8.0)
_PI = math.pi
_PI_2 = math.pi / 2.0
_PI_4 = math.pi / 4.0

# atan(z)/z as a polynomial in w = z², |z| <= tan(π/8); least-squares fit (numpy
# Polynomial.fit, degree 11, 20001 points); max |error| of z*poly(z²) - atan(z): 2.2e-16.
_ATAN_COEF = (
    0.9999999999999999,
    -0.3333333333334519,
    0.20000000001359527,
    -0.14285714358616897,
    0.11111113483515318,
    -0.0909095838783691,
    0.07692967399225735,
    -0.06672191289388155,
    0.05907969294866549,
    -0.05290493377166837,
    0.0440740832785468,
    -0.024169231107551214,
)
_A0, _A1, _A2, _A3, _A4, _A5, _A6, _A7, _A8, _A9, _A10, _A11 = _ATAN_COEF


@njit(error_model="numpy", fastmath={"contract"})
def _atan2_deg(y: float, x: float) -> float:  # pragma: no cover - numba
    """atan2(y, x) in degrees in [0, 360), branch-free polynomial."""
    ax = abs(x)
    ay = abs(y)
    mx = max(ax, ay)
    mn = min(ax, ay)
    big = mn > _TAN_PI_8 * mx
    # z = t or (t - 1)/(t + 1) with t = mn/mx: one division either way
    num = mn - mx if big else mn
    den = mn + mx if big else mx
    z = num / den if den > 0.0 else 0.0
    base = _PI_4 if big else 0.0
    w = z * z
    p = _A11
    p = p * w + _A10
    p = p * w + _A9
    p = p * w + _A8
    p = p * w + _A7
    p = p * w + _A6
    p = p * w + _A5
    p = p * w + _A4
    p = p * w + _A3
    p = p * w + _A2
    p = p * w + _A1
    p = p * w + _A0
    a = base + z * p
    a = _PI_2 - a if ay > ax else a
    a = _PI - a if x < 0.0 else a
    a = 2.0 * _PI - a if y < 0.0 else a
    return a * _DEG


@njit(error_model="numpy", fastmath={"contract"})
def _exp_neg(y: float) -> float:  # pragma: no cover - numba
    """exp(y) for y in [-130, 0]: Taylor on y/256 (degree 14), then 8 squarings."""
    r = y * (1.0 / 256.0)
    p = 1.0 / 87178291200.0
    p = p * r + 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    p = p * r + 1.0
    p = p * r + 1.0
    for _ in range(8):
        p = p * p
    return p


@njit(error_model="numpy", fastmath={"contract"})
def _sin_small(x: float) -> float:  # pragma: no cover - numba
    """sin(x) for x in [0, π/3]: Taylor series to x**17 (error < 3e-17)."""
    x2 = x * x
    p = 1.0 / 355687428096000.0
    p = p * x2 - 1.0 / 1307674368000.0
    p = p * x2 + 1.0 / 6227020800.0
    p = p * x2 - 1.0 / 39916800.0
    p = p * x2 + 1.0 / 362880.0
    p = p * x2 - 1.0 / 5040.0
    p = p * x2 + 1.0 / 120.0
    p = p * x2 - 1.0 / 6.0
    p = p * x2 + 1.0
    return x * p


@njit(inline="always", error_model="numpy")
def _de00(
    L1: float,
    a1: float,
    b1: float,
    L2: float,
    a2: float,
    b2: float,
    ikL: float,
    ikC: float,
    ikH: float,
) -> float:  # pragma: no cover - numba
    C1 = math.sqrt(a1 * a1 + b1 * b1)
    C2 = math.sqrt(a2 * a2 + b2 * b2)
    Cb = 0.5 * (C1 + C2)
    Cb3 = Cb * Cb * Cb
    Cb7 = Cb3 * Cb3 * Cb
    g1 = 1.5 - 0.5 * math.sqrt(Cb7 / (Cb7 + _P25_7))  # 1 + G, eq. (4)
    a1p = g1 * a1
    a2p = g1 * a2
    C1p = math.sqrt(a1p * a1p + b1 * b1)
    C2p = math.sqrt(a2p * a2p + b2 * b2)
    dL = L2 - L1
    dC = C2p - C1p
    pr = C1p * C2p
    dot = a1p * a2p + b1 * b2
    cross = a1p * b2 - a2p * b1
    # sign of Δh': +1 when h2' lies counter-clockwise of h1' (or exactly opposite with h1' < 180°)
    low1 = (b1 > 0.0) or (b1 == 0.0 and a1p > 0.0)
    sgn = 1.0 if (cross > 0.0 or (cross == 0.0 and low1)) else -1.0
    acute = dot >= 0.0
    # bisector of the unit hue vectors, scaled by C1' C2' (a zero chroma gets weight 1 so
    # that the other hue is the mean, Sharma's rule for C1' C2' = 0)
    w1 = C2p if C2p > 0.0 else 1.0
    w2 = C1p if C1p > 0.0 else 1.0
    vx = w1 * a1p + w2 * a2p if acute else sgn * (w2 * b2 - w1 * b1)
    vy = w1 * b1 + w2 * b2 if acute else -sgn * (w2 * a2p - w1 * a1p)
    n = math.sqrt(vx * vx + vy * vy)
    inv = 1.0 / n if n > 0.0 else 0.0
    c = vx * inv if n > 0.0 else 1.0
    s = vy * inv
    # ΔH' = x sqrt(2/(p + d)) = 2 x sqrt(p)/|v| (acute, |v|² = 2p(p + d)) or ±sqrt(2(p - d))
    # (obtuse): each side free of cancellation, one sqrt and no division of its own
    sq = math.sqrt(pr if acute else max(2.0 * (pr - dot), 0.0))
    dH = 2.0 * cross * sq * inv if acute else sgn * sq
    c2 = c * c - s * s
    s2 = 2.0 * c * s
    c3 = c * c2 - s * s2
    s3 = s * c2 + c * s2
    c4 = c2 * c2 - s2 * s2
    s4 = 2.0 * c2 * s2
    T = (
        1.0
        - 0.17 * (c * _C30 + s * _S30)
        + 0.24 * c2
        + 0.32 * (c3 * _C6 - s3 * _S6)
        - 0.20 * (c4 * _C63 + s4 * _S63)
    )
    hb = _atan2_deg(s, c)
    x = (hb - 275.0) * (1.0 / 25.0)
    dtheta_rad = (30.0 / _DEG) * _exp_neg(-(x * x))
    Lb = 0.5 * (L1 + L2) - 50.0
    Lb2 = Lb * Lb
    sl = math.sqrt(20.0 + Lb2)
    SLn = sl + 0.015 * Lb2  # S_L = SLn / sl
    Cbp = 0.5 * (C1p + C2p)
    SC = 1.0 + 0.045 * Cbp
    SH = 1.0 + 0.015 * Cbp * T
    Cbp3 = Cbp * Cbp * Cbp
    Cbp7 = Cbp3 * Cbp3 * Cbp
    E = Cbp7 + _P25_7  # R_C = 2 sqrt(Cbp7 E) / E
    # one division for 1/S_L, 1/S_C, 1/S_H and 1/E
    r = 1.0 / (SLn * SC * SH * E)
    RC = 2.0 * math.sqrt(Cbp7 * E) * (SLn * SC * SH) * r
    RT = -_sin_small(2.0 * dtheta_rad) * RC
    tl = dL * ikL * sl * (SC * SH * E) * r
    tc = dC * ikC * (SLn * SH * E) * r
    th = dH * ikH * (SLn * SC * E) * r
    return math.sqrt(tl * tl + tc * tc + th * th + RT * tc * th)


_BLOCK = 2048


@njit(error_model="numpy")
def _ciede2000_block(
    lab1: np.ndarray,
    lab2: np.ndarray,
    out: np.ndarray,
    start: int,
    stop: int,
    ikL: float,
    ikC: float,
    ikH: float,
) -> None:  # pragma: no cover - numba
    m = stop - start
    buf = np.empty((6, m))
    L1 = buf[0]
    A1 = buf[1]
    B1 = buf[2]
    L2 = buf[3]
    A2 = buf[4]
    B2 = buf[5]
    # de-interleave into planar buffers so that the arithmetic loop vectorises
    for j in range(m):
        L1[j] = lab1[start + j, 0]
        A1[j] = lab1[start + j, 1]
        B1[j] = lab1[start + j, 2]
        L2[j] = lab2[start + j, 0]
        A2[j] = lab2[start + j, 1]
        B2[j] = lab2[start + j, 2]
    res = out[start:stop]
    for j in range(m):
        res[j] = _de00(L1[j], A1[j], B1[j], L2[j], A2[j], B2[j], ikL, ikC, ikH)


@njit(error_model="numpy", nogil=True)
def _ciede2000_tasks(
    t0: int,
    t1: int,
    lab1: np.ndarray,
    lab2: np.ndarray,
    out: np.ndarray,
    ikL: float,
    ikC: float,
    ikH: float,
) -> None:  # pragma: no cover - numba
    """Blocks ``t0 .. t1 - 1`` of :data:`_BLOCK` pixels (a task of :func:`jit.run_tasks`).

    A serial ``nogil`` kernel run on numba's threads, not a ``parallel=True`` ``prange``:
    numba's parallel lowering (and its gufunc) cost seconds of CPU more to compile on a first
    ``imageform delta-e``, and one compiled kernel serves small inputs too (one
    specialisation: ``ciede2000_numba`` passes C-contiguous float64 arrays only).
    """
    n = out.shape[0]
    for bi in range(t0, t1):
        start = bi * _BLOCK
        _ciede2000_block(lab1, lab2, out, start, min(start + _BLOCK, n), ikL, ikC, ikH)


def ciede2000_numba(
    lab1: np.ndarray, lab2: np.ndarray, kL: float, kC: float, kH: float
) -> np.ndarray:
    """CIEDE2000 of two float64 arrays of the same shape ``(..., 3)`` (numba kernel)."""
    shape = lab1.shape[:-1]
    p1 = np.ascontiguousarray(lab1, dtype=np.float64).reshape(-1, 3)
    p2 = np.ascontiguousarray(lab2, dtype=np.float64).reshape(-1, 3)
    out = np.empty(p1.shape[0], dtype=np.float64)
    nblocks = (out.shape[0] + _BLOCK - 1) // _BLOCK
    run_tasks(_ciede2000_tasks, nblocks, p1, p2, out, 1.0 / kL, 1.0 / kC, 1.0 / kH)
    return out.reshape(shape)


def ciede2000_twin(xp: Any, lab1: Any, lab2: Any, kL: float, kC: float, kH: float) -> Any:
    """CIEDE2000 of two arrays of shape ``(..., 3)`` in namespace ``xp`` (the kernel's twin)."""
    L1, a1, b1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    L2, a2, b2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]
    C1 = xp.sqrt(a1 * a1 + b1 * b1)
    C2 = xp.sqrt(a2 * a2 + b2 * b2)
    Cb = 0.5 * (C1 + C2)
    Cb7 = Cb**7
    g1 = 1.5 - 0.5 * xp.sqrt(Cb7 / (Cb7 + _P25_7))
    a1p = g1 * a1
    a2p = g1 * a2
    C1p = xp.sqrt(a1p * a1p + b1 * b1)
    C2p = xp.sqrt(a2p * a2p + b2 * b2)
    dL = L2 - L1
    dC = C2p - C1p
    pr = C1p * C2p
    dot = a1p * a2p + b1 * b2
    cross = a1p * b2 - a2p * b1
    low1 = (b1 > 0) | ((b1 == 0) & (a1p > 0))
    sgn = xp.where((cross > 0) | ((cross == 0) & low1), 1.0, xp.full_like(L1, -1.0))
    acute = dot >= 0
    den = pr + dot
    # below sqrt(smallest normal) the reciprocals would overflow; there ΔH' <= 2 sqrt(C1'C2')
    # is below 1e-76 (float64), and a chroma that small is treated as zero (Sharma's rule)
    tiny = float(xp.finfo(L1.dtype).smallest_normal) ** 0.5
    den_ok = den > tiny
    dh_acute = xp.where(den_ok, cross * xp.sqrt(2.0 / xp.where(den_ok, den, 1.0)), 0.0)
    obt = 2.0 * (pr - dot)
    dh_obtuse = sgn * xp.sqrt(xp.where(obt > 0, obt, 0.0))
    dH = xp.where(acute, dh_acute, dh_obtuse)
    i1 = xp.where(C1p > tiny, 1.0 / xp.where(C1p > tiny, C1p, 1.0), 0.0)
    i2 = xp.where(C2p > tiny, 1.0 / xp.where(C2p > tiny, C2p, 1.0), 0.0)
    u1x, u1y, u2x, u2y = a1p * i1, b1 * i1, a2p * i2, b2 * i2
    vx = xp.where(acute, u1x + u2x, sgn * (u2y - u1y))
    vy = xp.where(acute, u1y + u2y, -sgn * (u2x - u1x))
    n2 = vx * vx + vy * vy
    n_ok = n2 > 0
    n = xp.sqrt(xp.where(n_ok, n2, 1.0))
    c = xp.where(n_ok, vx / n, 1.0)
    s = xp.where(n_ok, vy / n, 0.0)
    c2 = c * c - s * s
    s2 = 2.0 * c * s
    c3 = c * c2 - s * s2
    s3 = s * c2 + c * s2
    c4 = c2 * c2 - s2 * s2
    s4 = 2.0 * c2 * s2
    T = (
        1.0
        - 0.17 * (c * _C30 + s * _S30)
        + 0.24 * c2
        + 0.32 * (c3 * _C6 - s3 * _S6)
        - 0.20 * (c4 * _C63 + s4 * _S63)
    )
    hb = xp.atan2(s, c) * _DEG
    hb = xp.where(hb < 0, hb + 360.0, hb)
    x = (hb - 275.0) / 25.0
    dtheta_rad = (30.0 / _DEG) * xp.exp(-(x * x))
    Lb = 0.5 * (L1 + L2) - 50.0
    Lb2 = Lb * Lb
    SL = 1.0 + 0.015 * Lb2 / xp.sqrt(20.0 + Lb2)
    Cbp = 0.5 * (C1p + C2p)
    SC = 1.0 + 0.045 * Cbp
    SH = 1.0 + 0.015 * Cbp * T
    Cbp7 = Cbp**7
    RC = 2.0 * xp.sqrt(Cbp7 / (Cbp7 + _P25_7))
    RT = -xp.sin(2.0 * dtheta_rad) * RC
    tl = dL / (kL * SL)
    tc = dC / (kC * SC)
    th = dH / (kH * SH)
    return xp.sqrt(tl * tl + tc * tc + th * th + RT * tc * th)
