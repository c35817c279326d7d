r"""The per-pixel colour formulas as scalar code, one source for the CUDA kernels and their twin.

Each function below maps the channels of one pixel (``a, b, c``) and the numbers of one
conversion step to the pixel's new channels; they are the scalar form of the Array-API
code of :mod:`imageform.color` (same formulas, same branches, same conventions for black,
zero chroma and NaN), with every literal written ``F(...)`` so that one source compiles
twice: ``F = float32`` keeps float32 pixels in float32 arithmetic on the GPU (the sRGB
curve, ``pow`` and ``atan2`` run at float32 speed), ``F = float64`` gives float64. The
costly operations (division, ``sqrt``, powers, cube root, ``exp``, ``sin``/``cos``) go
through helpers that are the exact operations in float64 and, in float32, the GPU's fast
approximations with their documented bounds, emulated at twice those bounds on the CPU twin
and the simulator (issue 29; the table above ``_EXACT``).

:func:`functions` compiles the source for a dtype and a target: ``"cuda"`` (numba CUDA
device functions; the kernels of :mod:`imageform._cuda.color` call them), ``"cpu"``
(``numba.njit``: the CPU twin, which compiles the same source with numba's CPU typing, so
the kernels' code is type-checked and run on machines without a GPU) or ``"python"``
(plain Python, for reading and debugging). NaN propagates as on the array path: every
clip here is written so that a NaN comparison keeps the NaN (``x if not x < lo else lo``),
never through ``min``/``max`` (CUDA's ``fmin``/``fmax`` drop NaN).

Sources: the docstrings of the public functions (IEC 61966-2-1, ITU-R BT.709/2020, ISO
22028-2, CIE 15:2004, Smith 1978, Gonzalez & Woods, CIE 116-1995, Clarke et al. 1984 (CMC),
Sharma, Wu & Dalal 2005 (CIEDE2000)).
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np

__all__ = ["NAMES", "SOURCE", "functions"]

# fmt: off
SOURCE = r'''
def _clip_lo(x, lo):
    return lo if x < lo else x


def _clip(x, lo, hi):
    if x < lo:
        return lo
    if x > hi:
        return hi
    return x


def _sdec(v):
    if v <= F(0.040449936):
        return v * F(1.0 / 12.92)
    return _pow24(_clip_lo((v + F(0.055)) * F(1.0 / 1.055), F(1e-30)))


def _senc(x):
    if x <= F(0.0031308):
        return x * F(12.92)
    return F(1.055) * _pow512(_clip_lo(x, F(1e-30))) - F(0.055)


def _gdec(v, g):
    return math.copysign(_powp(abs(v), g), v)


def _genc(x, g):
    return math.copysign(_powp(abs(x), F(1.0) / g), x)


def _btenc(x, alpha, beta):
    if x < beta:
        return F(4.5) * x
    return alpha * _powp(_clip_lo(x, F(1e-30)), F(0.45)) - (alpha - F(1.0))


def _btdec(v, alpha, beta):
    if v < F(4.5) * beta:
        return v / F(4.5)
    return _powp(_clip_lo((v + (alpha - F(1.0))) / alpha, F(1e-30)), F(1.0 / 0.45))


def _renc(x):
    if x < F(1.0 / 512.0):
        return F(16.0) * x
    return _powp(_clip_lo(x, F(1e-30)), F(1.0 / 1.8))


def _rdec(v):
    if v < F(16.0 / 512.0):
        return v / F(16.0)
    return _powp(_clip_lo(v, F(1e-30)), F(1.8))


def dec_srgb(a, b, c):
    return _sdec(a), _sdec(b), _sdec(c)


def enc_srgb(a, b, c):
    return _senc(a), _senc(b), _senc(c)


def dec_gamma(a, b, c, g):
    return _gdec(a, g), _gdec(b, g), _gdec(c, g)


def enc_gamma(a, b, c, g):
    return _genc(a, g), _genc(b, g), _genc(c, g)


def dec_bt(a, b, c, alpha, beta):
    return _btdec(a, alpha, beta), _btdec(b, alpha, beta), _btdec(c, alpha, beta)


def enc_bt(a, b, c, alpha, beta):
    return _btenc(a, alpha, beta), _btenc(b, alpha, beta), _btenc(c, alpha, beta)


def dec_romm(a, b, c):
    return _rdec(a), _rdec(b), _rdec(c)


def enc_romm(a, b, c):
    return _renc(a), _renc(b), _renc(c)


def matrix(a, b, c, m0, m1, m2, m3, m4, m5, m6, m7, m8):
    return (m0 * a + m1 * b + m2 * c, m3 * a + m4 * b + m5 * c, m6 * a + m7 * b + m8 * c)


def affine(a, b, c, m0, m1, m2, m3, m4, m5, m6, m7, m8, o0, o1, o2):
    return (
        m0 * a + m1 * b + m2 * c + o0,
        m3 * a + m4 * b + m5 * c + o1,
        m6 * a + m7 * b + m8 * c + o2,
    )


def gains(a, b, c, g0, g1, g2):
    return a * g0, b * g1, c * g2


def gains_clip(a, b, c, g0, g1, g2):
    return (
        _clip(a * g0, F(0.0), F(1.0)),
        _clip(b * g1, F(0.0), F(1.0)),
        _clip(c * g2, F(0.0), F(1.0)),
    )


def _flab(t):
    if t > F(216.0 / 24389.0):
        return _cbrt(t)
    return F(841.0 / 108.0) * t + F(4.0 / 29.0)


def _flab_inv(u):
    if u > F(6.0 / 29.0):
        return u * u * u
    return _div(u - F(4.0 / 29.0), F(841.0 / 108.0))


def xyz_lab(a, b, c, wx, wy, wz):
    fx = _flab(_divr(a, wx))
    fy = _flab(_divr(b, wy))
    fz = _flab(_divr(c, wz))
    return F(116.0) * fy - F(16.0), F(500.0) * (fx - fy), F(200.0) * (fy - fz)


def xyz_lab1(a, b, c):
    fx = _flab(a)
    fy = _flab(b)
    fz = _flab(c)
    return F(116.0) * fy - F(16.0), F(500.0) * (fx - fy), F(200.0) * (fy - fz)


def lab_xyz(a, b, c, wx, wy, wz):
    fy = _div(a + F(16.0), F(116.0))
    fx = fy + _div(b, F(500.0))
    fz = fy - _div(c, F(200.0))
    return _flab_inv(fx) * wx, _flab_inv(fy) * wy, _flab_inv(fz) * wz


def _hue_deg(y, x):
    h = math.atan2(y, x) * F(180.0 / math.pi)
    if h < F(0.0):
        h = h + F(360.0)
    return h


def lab_lch(a, b, c):
    h = _hue_deg(c, b)
    if h >= F(360.0):
        h = h - F(360.0)
    return a, math.sqrt(b * b + c * c), h


def lch_lab(a, b, c):
    h = c * F(math.pi / 180.0)
    return a, b * math.cos(h), b * math.sin(h)


def xyz_luv(a, b, c, wx, wy, wz):
    wn = wx + F(15.0) * wy + F(3.0) * wz
    un = F(4.0) * wx / wn
    vn = F(9.0) * wy / wn
    d = a + F(15.0) * b + F(3.0) * c
    L = F(116.0) * _flab(b / wy) - F(16.0)
    if d == F(0.0):
        return L, F(0.0), F(0.0)
    up = F(4.0) * a / d
    vp = F(9.0) * b / d
    return L, F(13.0) * L * (up - un), F(13.0) * L * (vp - vn)


def luv_xyz(a, b, c, wx, wy, wz):
    wn = wx + F(15.0) * wy + F(3.0) * wz
    un = F(4.0) * wx / wn
    vn = F(9.0) * wy / wn
    y = wy * _flab_inv((a + F(16.0)) / F(116.0))
    if a == F(0.0):
        return F(0.0), y, F(0.0)
    up = b / (F(13.0) * a) + un
    vp = c / (F(13.0) * a) + vn
    if vp == F(0.0):
        return F(0.0), y, F(0.0)
    return (
        y * F(9.0) * up / (F(4.0) * vp),
        y,
        y * (F(12.0) - F(3.0) * up - F(20.0) * vp) / (F(4.0) * vp),
    )


def xyz_xyy(a, b, c, wx, wy, wz):
    s = a + b + c
    if s == F(0.0):
        t = wx + wy + wz
        return wx / t, wy / t, b
    return a / s, b / s, b


def xyy_xyz(a, b, c):
    if b == F(0.0):
        return F(0.0), c, F(0.0)
    return a * c / b, c, (F(1.0) - a - b) * c / b


def swap(a, b, c):
    return c, b, a


def invert(a, b, c):
    return F(1.0) - a, F(1.0) - b, F(1.0) - c


def _hexcone_hue(r, g, b, mx, delta):
    if delta == F(0.0):
        return F(0.0)
    if mx == r:
        h = (g - b) / delta
    elif mx == g:
        h = (b - r) / delta + F(2.0)
    else:
        h = (r - g) / delta + F(4.0)
    h = h * F(60.0)
    if h < F(0.0):
        h = h + F(360.0)
    if h >= F(360.0):
        h = h - F(360.0)
    return h


def _max3(r, g, b):
    m = r if r >= g else g
    m = m if m >= b else b
    if r != r or g != g or b != b:
        return r + g + b
    return m


def _min3(r, g, b):
    m = r if r <= g else g
    m = m if m <= b else b
    if r != r or g != g or b != b:
        return r + g + b
    return m


def rgb_hsv(r, g, b):
    mx = _max3(r, g, b)
    delta = mx - _min3(r, g, b)
    s = F(0.0) if mx == F(0.0) else delta / mx
    return _hexcone_hue(r, g, b, mx, delta), s, mx


def hsv_rgb(h, s, v):
    k5 = (F(5.0) + h / F(60.0)) % F(6.0)
    k3 = (F(3.0) + h / F(60.0)) % F(6.0)
    k1 = (F(1.0) + h / F(60.0)) % F(6.0)
    t5 = _clip(k5 if k5 <= F(4.0) - k5 else F(4.0) - k5, F(0.0), F(1.0))
    t3 = _clip(k3 if k3 <= F(4.0) - k3 else F(4.0) - k3, F(0.0), F(1.0))
    t1 = _clip(k1 if k1 <= F(4.0) - k1 else F(4.0) - k1, F(0.0), F(1.0))
    return v - v * s * t5, v - v * s * t3, v - v * s * t1


def rgb_hsl(r, g, b):
    mx = _max3(r, g, b)
    mn = _min3(r, g, b)
    delta = mx - mn
    light = (mx + mn) / F(2.0)
    den = F(1.0) - abs(F(2.0) * light - F(1.0))
    s = F(0.0) if den == F(0.0) else delta / den
    return _hexcone_hue(r, g, b, mx, delta), s, light


def _hsl_f(n, h, light, a):
    k = (n + h / F(30.0)) % F(12.0)
    t = _clip(k - F(3.0) if k - F(3.0) <= F(9.0) - k else F(9.0) - k, F(-1.0), F(1.0))
    return light - a * t


def hsl_rgb(h, s, light):
    m = light if light <= F(1.0) - light else F(1.0) - light
    a = s * m
    return _hsl_f(F(0.0), h, light, a), _hsl_f(F(8.0), h, light, a), _hsl_f(F(4.0), h, light, a)


def rgb_hsi(r, g, b):
    i = (r + g + b) / F(3.0)
    mn = _min3(r, g, b)
    s = F(0.0) if i == F(0.0) else F(1.0) - mn / i
    h = math.atan2(F(math.sqrt(3.0)) * (g - b), F(2.0) * r - g - b) * F(180.0 / math.pi)
    if h < F(0.0):
        h = h + F(360.0)
    if h >= F(360.0):
        h = h - F(360.0)
    if s == F(0.0):
        h = F(0.0)
    return h, s, i


def hsi_rgb(h, s, i):
    sector = h // F(120.0)
    hh = (h - F(120.0) * sector) * F(math.pi / 180.0)
    x = i * (F(1.0) - s)
    y = i * (F(1.0) + s * math.cos(hh) / math.cos(F(math.pi / 3.0) - hh))
    z = F(3.0) * i - (x + y)
    if sector == F(0.0):
        return y, z, x
    if sector == F(1.0):
        return x, y, z
    return z, x, y


def _dh2(a1, b1, a2, b2, c1, c2):
    p = c1 * c2
    d = a1 * a2 + b1 * b2
    x = a1 * b2 - a2 * b1
    den = p + d
    if d >= F(0.0):
        if den > F(0.0):
            return _div(F(2.0) * x * x, den)
        return F(0.0)
    obtuse = F(2.0) * (p - d)
    return obtuse if obtuse > F(0.0) else F(0.0)


def de76(l1, a1, b1, l2, a2, b2):
    dl = l1 - l2
    da = a1 - a2
    db = b1 - b2
    return math.sqrt(dl * dl + da * da + db * db)


def de94(l1, a1, b1, l2, a2, b2, kl, kc, kh, k1, k2):
    c1 = _sqrt(a1 * a1 + b1 * b1)
    c2 = _sqrt(a2 * a2 + b2 * b2)
    dh2 = _dh2(a1, b1, a2, b2, c1, c2)
    tl = _div(l1 - l2, kl)
    tc = _div(c1 - c2, kc * (F(1.0) + k1 * c1))
    sh = kh * (F(1.0) + k2 * c1)
    return _sqrt(tl * tl + tc * tc + _div(dh2, sh * sh))


def decmc(l1, a1, b1, l2, a2, b2, ll, cc):
    c1 = _sqrt(a1 * a1 + b1 * b1)
    c2 = _sqrt(a2 * a2 + b2 * b2)
    dh2 = _dh2(a1, b1, a2, b2, c1, c2)
    h1 = _hue_deg(b1, a1)
    if h1 >= F(164.0) and h1 <= F(345.0):
        t = F(0.56) + abs(F(0.2) * _cosd(h1 + F(168.0)))
    else:
        t = F(0.36) + abs(F(0.4) * _cosd(h1 + F(35.0)))
    c14 = c1 * c1 * c1 * c1
    f = _sqrt(_div(c14, c14 + F(1900.0)))
    sl = F(0.511) if l1 < F(16.0) else _div(F(0.040975) * l1, F(1.0) + F(0.01765) * l1)
    sc = _div(F(0.0638) * c1, F(1.0) + F(0.0131) * c1) + F(0.638)
    sh = sc * (f * t + F(1.0) - f)
    tl = _div(l1 - l2, ll * sl)
    tc = _div(c1 - c2, cc * sc)
    return _sqrt(tl * tl + tc * tc + _div(dh2, sh * sh))


def _pow7(x):
    x2 = x * x
    return x2 * x2 * x2 * x


def de00(l1, a1, b1, l2, a2, b2, kl, kc, kh, tiny):
    c1 = _sqrt(a1 * a1 + b1 * b1)
    c2 = _sqrt(a2 * a2 + b2 * b2)
    cb7 = _pow7(F(0.5) * (c1 + c2))
    g1 = F(1.5) - F(0.5) * _r7(cb7)
    a1p = g1 * a1
    a2p = g1 * a2
    c1p = _sqrt(a1p * a1p + b1 * b1)
    c2p = _sqrt(a2p * a2p + b2 * b2)
    dl = l2 - l1
    dc = c2p - c1p
    pr = c1p * c2p
    dot = a1p * a2p + b1 * b2
    cross = a1p * b2 - a2p * b1
    low1 = b1 > F(0.0) or (b1 == F(0.0) and a1p > F(0.0))
    sgn = F(1.0) if (cross > F(0.0) or (cross == F(0.0) and low1)) else F(-1.0)
    acute = dot >= F(0.0)
    if acute:
        den = pr + dot
        dh = cross * _sqrt(_div(F(2.0), den)) if den > tiny else F(0.0)
    else:
        obt = F(2.0) * (pr - dot)
        dh = sgn * _sqrt(obt if obt > F(0.0) else F(0.0))
    i1 = _div(F(1.0), c1p) if c1p > tiny else F(0.0)
    i2 = _div(F(1.0), c2p) if c2p > tiny else F(0.0)
    u1x = a1p * i1
    u1y = b1 * i1
    u2x = a2p * i2
    u2y = b2 * i2
    if acute:
        vx = u1x + u2x
        vy = u1y + u2y
    else:
        vx = sgn * (u2y - u1y)
        vy = -sgn * (u2x - u1x)
    n2 = vx * vx + vy * vy
    if n2 > F(0.0):
        c, s = _unit(vx, vy, n2)
    else:
        c = F(1.0)
        s = F(0.0)
    c2_ = c * c - s * s
    s2_ = F(2.0) * c * s
    c3_ = c * c2_ - s * s2_
    s3_ = s * c2_ + c * s2_
    c4_ = c2_ * c2_ - s2_ * s2_
    s4_ = F(2.0) * c2_ * s2_
    t = (
        F(1.0)
        - F(0.17) * (c * F(C30) + s * F(S30))
        + F(0.24) * c2_
        + F(0.32) * (c3_ * F(C6) - s3_ * F(S6))
        - F(0.20) * (c4_ * F(C63) + s4_ * F(S63))
    )
    hb = _atan2d(s, c)
    if hb < F(0.0):
        hb = hb + F(360.0)
    x = _div(hb - F(275.0), F(25.0))
    dtheta = F(30.0 * math.pi / 180.0) * _exp(-(x * x))
    lb = F(0.5) * (l1 + l2) - F(50.0)
    lb2 = lb * lb
    sl = F(1.0) + _div(F(0.015) * lb2, _sqrt(F(20.0) + lb2))
    cbp = F(0.5) * (c1p + c2p)
    sc = F(1.0) + F(0.045) * cbp
    sh = F(1.0) + F(0.015) * cbp * t
    cbp7 = _pow7(cbp)
    rc = F(2.0) * _r7(cbp7)
    rt = -_sin(F(2.0) * dtheta) * rc
    tl = _div(dl, kl * sl)
    tc = _div(dc, kc * sc)
    th = _div(dh, kh * sh)
    return _sqrt(tl * tl + tc * tc + th * th + rt * tc * th)
'''
# fmt: on

#: The conversion steps (pixel -> pixel) the kernels compose, with their parameter counts.
NAMES: dict[str, int] = {
    "dec_srgb": 0,
    "enc_srgb": 0,
    "dec_gamma": 1,
    "enc_gamma": 1,
    "dec_bt": 2,
    "enc_bt": 2,
    "dec_romm": 0,
    "enc_romm": 0,
    "matrix": 9,
    "affine": 12,
    "gains": 3,
    "gains_clip": 3,
    "xyz_lab": 3,
    "xyz_lab1": 0,  # XYZ already divided by the white (color._fold_white)
    "lab_xyz": 3,
    "lab_lch": 0,
    "lch_lab": 0,
    "xyz_luv": 3,
    "luv_xyz": 3,
    "xyz_xyy": 3,
    "xyy_xyz": 0,
    "swap": 0,
    "invert": 0,
    "rgb_hsv": 0,
    "hsv_rgb": 0,
    "rgb_hsl": 0,
    "hsl_rgb": 0,
    "rgb_hsi": 0,
    "hsi_rgb": 0,
}

#: The colour differences (two pixels -> one number), with their parameter counts.
DELTA_E: dict[str, int] = {"de76": 0, "de94": 5, "decmc": 2, "de00": 4}

_CONSTANTS = {
    "C30": math.cos(math.radians(30.0)),
    "S30": math.sin(math.radians(30.0)),
    "C6": math.cos(math.radians(6.0)),
    "S6": math.sin(math.radians(6.0)),
    "C63": math.cos(math.radians(63.0)),
    "S63": math.sin(math.radians(63.0)),
}


def _function_names(source: str = SOURCE) -> list[str]:
    return [line[4 : line.index("(")] for line in source.splitlines() if line.startswith("def ")]


#: ``x ** p`` for ``x >= 0`` and ``p > 0`` (NaN and inf propagate), by dtype. float32:
#: ``exp(p log x)``, libdevice's ``expf``/``logf`` on a GPU, about a third of ``powf``'s
#: instructions for sm_90 (the sRGB->Lab kernel 800 -> 496 SASS instructions; no slow-path
#: call left in sRGB->linear); relative error a few 1e-7 for the bases the curves meet,
#: inside float32's tolerance. float64 keeps ``pow`` (its ``exp``/``log`` inline to more code
#: than ``pow``'s calls).
_POWP = {
    "float32": (
        "def _powp(x, p):\n"
        "    if x > F(0.0):\n"
        "        return math.exp(p * math.log(x))\n"
        "    return x * F(0.0)\n"  # 0 ** p = 0 (p > 0); NaN stays NaN
    ),
    "float64": "def _powp(x, p):\n    return math.pow(x, p)\n",
}

# The helpers the formulas above call for their costly operations (issue 29). float64: the
# exact operations (IEEE division and sqrt, libdevice's pow/exp/sin), so float64 kernels are
# what they were. float32: the GPU's fast approximations, each with a documented error bound
# (CUDA C++ Programming Guide, "Mathematical Functions", intrinsic functions; PTX ISA,
# ``lg2.approx``/``ex2.approx``/``div.approx``/``rsqrt.approx``/``sin.approx``), refined by
# one Newton step where a result feeds CIELAB (cube root, the sRGB decoding power):
#
# ================  ============================  ==========================================
# helper            GPU (float32)                 bound of the approximation
# ================  ============================  ==========================================
# ``_lg2(x)``       ``__nv_fast_log2f``           2^-22 absolute for x in [0.5, 2],
#                   (``lg2.approx.f32``)          else 2 ulp
# ``_ex2(x)``       ``__nv_exp2f``                2 ulp (full range)
#                   (``ex2.approx.f32``)
# ``_div(x, y)``    ``__nv_fast_fdividef``        2 ulp for 2^-126 <= |y| <= 2^126; 0 above
#                   (``div.approx.f32``)          (callers keep |y| below 2^126)
# ``_rsqrt(x)``     ``__nv_rsqrtf``               2 ulp
#                   (``rsqrt.approx.f32``)
# ``_sqrt(x)``      ``x * _rsqrt(x)``             3 ulp (0, inf and NaN returned as is)
# ``_exp(x)``       ``__nv_fast_expf``            2 + floor(|1.173 x|) ulp
# ``_sin(x)``       ``__nv_fast_sinf``            2^-21.41 absolute for x in [-pi, pi]
#                   (``sin.approx.f32``)          (callers' arguments: [0, pi/3])
# ``_cbrt(t)``      ``_ex2(_lg2(t) / 3)``, one    about 1 ulp after the step (its initial
#                   Newton step                   relative error ~7e-7 squares away)
# ``_pow24(u)``     ``u^2 z``, ``z = u^0.4`` by   about 2 ulp after the step
#                   ``_ex2``/``_lg2``, one Newton
#                   step on ``z^5 = u^2``
# ================  ============================  ==========================================
#
# The simulator runs Python, and the CPU twin numba's CPU target, neither of which has these
# instructions: there (``_EMULATED``) each approximation is the float64 result moved by twice
# its bound (an ulp bound read at its largest relative size, n ulp as n 2^-23 of the result),
# up or down by a fixed pattern of the argument, then rounded to float32, so the
# twin's float32 results carry at least the GPU's error and the twin tests
# (tests/backends/test_cuda_kernels.py) check the kernels' tolerance with it; the one-step
# refinements (``_cbrt``, ``_pow24``) are the same code on every target.
_EXACT = r"""
def _div(x, y):
    return x / y


def _divr(x, y):
    return x / y


def _sqrt(x):
    return math.sqrt(x)


def _exp(x):
    return math.exp(x)


def _sin(x):
    return math.sin(x)


def _cbrt(t):
    return _powp(t, F(1.0 / 3.0))


def _pow512(x):
    return _powp(x, F(1.0 / 2.4))


def _cosd(d):
    return math.cos(d * F(math.pi / 180.0))


def _atan2d(y, x):
    return math.atan2(y, x) * F(180.0 / math.pi)


def _pow24(u):
    return _powp(u, F(2.4))


def _r7(c7):
    return math.sqrt(c7 / (c7 + F(6103515625.0)))


def _unit(x, y, n2):
    n = math.sqrt(n2)
    return x / n, y / n
"""

_DEVICE = r"""
def _lg2(x):
    return fast_log2f(x)


def _ex2(x):
    return exp2f(x)


def _div(x, y):
    return fast_fdividef(x, y)


def _rsqrt(x):
    return rsqrtf(x)


def _exp(x):
    return fast_expf(x)


def _sin(x):
    return fast_sinf(x)


def _cos(x):
    return fast_cosf(x)
"""

#: The libdevice functions of _DEVICE.
_LIBDEVICE = (
    "fast_log2f",
    "exp2f",
    "fast_fdividef",
    "rsqrtf",
    "fast_expf",
    "fast_sinf",
    "fast_cosf",
)

# twice each bound of the table above (relative, or absolute where marked), for the emulation
_BOUNDS = {
    "E_LG2_ABS": 2.0 * 2.0**-22,
    "E_LG2": 2.0 * 2.0**-22,  # 2 ulp of the result: at most 2^-22 of it
    "E_EX2": 2.0 * 2.0**-22,
    "E_DIV": 2.0 * 2.0**-22,
    "E_RSQ": 2.0 * 2.0**-22,
    "E_EXP": 2.0 * 2.0**-23,
    "E_SIN_ABS": 2.0 * 2.0**-21.41,
    "E_COS_ABS": 2.0 * 2.0**-21.19,
}

_EMULATED = r"""
def _flip(d):
    return 1.0 if (d * 4096.0) % 2.0 < 1.0 else -1.0


def _lg2(x):
    d = float(x)
    v = math.log2(d)
    if not abs(v) < 1e30:
        return F(v)
    e = E_LG2_ABS if d >= 0.5 and d <= 2.0 else E_LG2 * abs(v)
    return F(v + e * _flip(d))


def _ex2(x):
    d = float(x)
    return F(2.0**d * (1.0 + E_EX2 * _flip(d)))


def _div(x, y):
    n = float(x)
    d = float(y)
    if abs(d) > 2.0**126:
        return F(0.0) * x
    if d == 0.0:
        return F(n * math.copysign(math.inf, d))
    return F(n / d * (1.0 + E_DIV * _flip(n - d)))


def _rsqrt(x):
    d = float(x)
    if d == 0.0:
        return F(math.inf)
    return F(1.0 / math.sqrt(d) * (1.0 + E_RSQ * _flip(d)))


def _exp(x):
    d = float(x)
    k = 1.173 * abs(d)
    if not k < 1e30:  # NaN, +-inf
        return F(math.exp(d))
    return F(math.exp(d) * (1.0 + E_EXP * (2.0 + float(math.floor(k))) * _flip(d)))


def _sin(x):
    d = float(x)
    return F(math.sin(d) + E_SIN_ABS * _flip(d))


def _cos(x):
    d = float(x)
    return F(math.cos(d) + E_COS_ABS * _flip(d))
"""

# float32 on every target: built on the primitives of _DEVICE or _EMULATED
_FAST = r"""
def _sqrt(x):
    if x > F(0.0) and x < F(math.inf):
        return x * _rsqrt(x)
    return x


def _cbrt(t):
    r = _ex2(_lg2(t) * F(1.0 / 3.0))
    r2 = r * r
    c = r - (r2 * r - t) * _div(F(1.0 / 3.0), r2)
    return c if c == c else r


def _pow24(u):
    z = _ex2(_lg2(u) * F(0.4))
    u2 = u * u
    z2 = z * z
    z4 = z2 * z2
    z = z - (z4 * z - u2) * _div(F(0.2), z4) if z4 < F(2.0**126) else z
    return u2 * z


def _pow512(x):
    y = _ex2(_lg2(x) * F(5.0 / 12.0))
    if x < F(2.0**20):
        x2 = x * x
        y2 = y * y
        y4 = y2 * y2
        y12 = y4 * y4 * y4
        y = y - (y12 - x2 * x2 * x) * _div(F(1.0 / 12.0) * y, y12)
    return y


def _cosd(d):
    if d > F(180.0):
        d = d - F(360.0)
    return _cos(d * F(math.pi / 180.0))


def _divr(x, y):
    r = _div(F(1.0), y)
    q = x * r
    return q + (x - q * y) * r


def _atan2d(y, x):
    # atan2 in degrees from an odd polynomial of degree 15 on [0, 1] (fitted to atan, at most
    # 3.7e-8 rad; 1.1e-7 rad in float32) of min/max(|x|, |y|), the octant by comparisons;
    # measured with _div emulated at twice its bound: at most 3.4e-5 degrees, the rounding of
    # results near 180 (2 ulp there; atan2f's result in degrees rounds the same way), tested
    # against 6e-5 (tests/backends/test_cuda_kernels.APPROX_CASES). CIEDE2000's mean hue
    # only (a unit vector): its hue enters through exp(-((h - 275) / 25)^2), whose slope is
    # below 0.04 per degree; the hues that are outputs (LCh, CMC's h1 near its 164-degree
    # switch) keep atan2f
    ax = abs(x)
    ay = abs(y)
    big = ax >= ay
    mx = ax if big else ay
    mn = ay if big else ax
    q = _div(mn, mx)
    t = q * q
    p = F(-0.004054524776386532)
    p = p * t + F(0.021862862488943646)
    p = p * t + F(-0.05591230064987116)
    p = p * t + F(0.09642206656295985)
    p = p * t + F(-0.1390863952908401)
    p = p * t + F(0.19946569594994384)
    p = p * t + F(-0.3332986142344047)
    p = p * t + F(0.9999993358962369)
    r = p * q
    if not big:
        r = F(math.pi / 2.0) - r
    if x < F(0.0):
        r = F(math.pi) - r
    if y < F(0.0):
        r = -r
    return r * F(180.0 / math.pi)


def _r7(c7):
    return _rsqrt(F(1.0) + _div(F(6103515625.0), c7))


def _unit(x, y, n2):
    r = _rsqrt(n2)
    return x * r, y * r
"""


def _prelude(dtype: str, target: str) -> str:
    """Return the helpers' source for ``dtype`` and ``target`` (GPU or emulated float32)."""
    if dtype == "float64":
        return _POWP[dtype] + _EXACT
    if target == "cuda":
        from imageform._cuda._launch import simulated

        if not simulated():
            return _POWP[dtype] + _DEVICE + _FAST
    return _POWP[dtype] + _EMULATED + _FAST


@cache
def functions(dtype: str, target: str) -> dict[str, Any]:
    """Compile :data:`SOURCE` for ``dtype`` (``"float32"``/``"float64"``) and ``target``.

    ``target``: ``"cuda"`` (numba CUDA device functions), ``"cpu"`` (``numba.njit``, the
    CPU twin) or ``"python"``. Returns ``{name: function}``; the functions call each other
    through the namespace they were compiled in, so each target's functions call their own.
    """
    F = np.float32 if dtype == "float32" else np.float64
    ns: dict[str, Any] = {"math": math, "F": F, **_CONSTANTS, **_BOUNDS}
    source = _prelude(dtype, target) + SOURCE
    if "fast_log2f" in source:
        from numba.cuda import libdevice

        found = {name: getattr(libdevice, name, None) for name in _LIBDEVICE}
        if all(found.values()):
            ns.update(found)
        else:  # a numba CUDA target without one of them: the exact operations
            source = _POWP[dtype] + _EXACT + SOURCE
    exec(compile(source, f"<imageform._cuda.scalar {dtype}>", "exec"), ns)
    names = _function_names(source)
    if target == "python":
        return {n: ns[n] for n in names}
    if target == "cuda":
        from imageform._cuda._launch import cuda

        wrap = cuda().jit(device=True)
    else:
        import numba

        wrap = numba.njit(inline="always")
    # compile in definition order: a function's callees are defined (and wrapped) above it,
    # and the wrapped object replaces the Python one in the namespace its callers read
    for n in names:
        ns[n] = wrap(ns[n])
    return {n: ns[n] for n in names}
