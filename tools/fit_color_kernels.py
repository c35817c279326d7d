"""Fit the polynomial seeds of the float32 sRGB -> CIELAB kernel (_kernels/color_lab.py).

Each seed minimises the maximum *relative* error on its interval by Lawson's algorithm
(iteratively reweighted least squares, which converges to the minimax fit; Lawson 1961,
see Rice & Usow 1968). Run it to reproduce the coefficients typed in the kernel:

    python tools/fit_color_kernels.py

- ``_DEC``: p(u) ~ u^0.8 on u = sqrt(w) in [0.3, 1], w = (v + 0.055) / 1.055 in [0.09, 1], so that
  the sRGB decode w^2.4 = w^2 * p(sqrt(w)) (IEC 61966-2-1 power branch; one square root).
- ``_CBL``: q(s) ~ s^(2/3) on s = sqrt(t), t in [epsilon, 1.2] (CIE 15 cube-root branch), the seed
  that one Halley step y <- y (y^3 + 2t) / (2y^3 + t) refines to float32 rounding.
"""

from __future__ import annotations

import numpy as np


def lawson(fn, lo: float, hi: float, deg: int, n: int = 200_001, iters: int = 200):  # type: ignore[no-untyped-def]
    """Coefficients (highest power first) and max relative error of the minimax fit."""
    x = np.linspace(lo, hi, n)
    y = fn(x)
    v = np.vander(x, deg + 1)
    w = np.full(n, 1.0 / n)
    for _ in range(iters):
        sw = np.sqrt(w)
        c, *_ = np.linalg.lstsq(v / y[:, None] * sw[:, None], sw, rcond=None)
        e = np.abs(v @ c / y - 1.0)
        w = w * e
        w /= w.sum()
    return c, float(e.max())


def main() -> None:
    eps = (6 / 29) ** 3
    dec, e_dec = lawson(lambda u: u**0.8, np.sqrt(0.09), 1.0, 7)
    cbl, e_cbl = lawson(lambda s: s ** (2 / 3), np.sqrt(eps * 0.999), np.sqrt(1.2), 4)
    print(f"_DEC (u^0.8, max rel. error {e_dec:.2e}):", ", ".join(f"{c:.8f}" for c in dec))
    print(f"_CBL (s^(2/3), max rel. error {e_cbl:.2e}):", ", ".join(f"{c:.8f}" for c in cbl))


if __name__ == "__main__":
    main()
