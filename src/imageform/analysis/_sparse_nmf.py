"""Sparse non-negative matrix factorisation for Vahadane's stain separation (private).

Pure NumPy, used by :func:`imageform.analysis.macenko.vahadane_stains`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TOLERANCE", "lattice_rows", "objective", "sparse_nmf"]

#: Fibonacci hashing's multiplier (2**64 / golden ratio, odd: a bijection of 64-bit ints).
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)

#: Relative change of the dictionary per round below which :func:`sparse_nmf` stops.
TOLERANCE = 1e-7


def lattice_rows(index: np.ndarray, max_pixels: int, seed: int = 0) -> np.ndarray:
    """Return the positions (into ``index``) of at most ``max_pixels`` rows to factorise.

    ``index``: the flat pixel positions of the tissue, increasing. Every position of the
    image has a fixed key, ``(position + seed) * 0x9E3779B97F4A7C15 mod 2**64`` (Fibonacci
    hashing: distinct keys, spread evenly over the image like the golden-ratio lattice); the
    tissue pixels with the ``max_pixels`` smallest keys are kept. Leaving one pixel out of
    the mask changes at most one of them (a stride over the tissue pixels would shift them
    all).
    """
    n = index.shape[0]
    if n <= max_pixels:
        return np.arange(n)
    with np.errstate(over="ignore"):
        keys = (index.astype(np.uint64) + np.uint64(seed)) * _GOLDEN
    return np.sort(np.argpartition(keys, max_pixels - 1)[:max_pixels])


def _codes(x: np.ndarray, h: np.ndarray, lam: float) -> np.ndarray:
    """Exact minimiser over ``W >= 0`` of ``0.5 ||x_i - w_i H||^2 + lam ||w_i||_1``, per row.

    Two atoms: the minimum is at one of four faces of the orthant (both codes zero, one of
    them zero, both positive); each face's unconstrained minimiser is closed-form, and the
    best feasible one is the minimum (the problem is convex).
    """
    g = h @ h.T
    c = x @ h.T - lam
    d = np.maximum(np.diag(g), 1e-300)
    w1 = np.zeros_like(c)
    w1[:, 0] = np.maximum(c[:, 0] / d[0], 0.0)
    w2 = np.zeros_like(c)
    w2[:, 1] = np.maximum(c[:, 1] / d[1], 0.0)
    cands = [np.zeros_like(c), w1, w2]
    det = g[0, 0] * g[1, 1] - g[0, 1] * g[1, 0]
    if det > 1e-12 * d[0] * d[1]:
        both = c @ np.array([[g[1, 1], -g[0, 1]], [-g[1, 0], g[0, 0]]]) / det
        cands.append(np.where((both >= 0.0).all(axis=1, keepdims=True), both, 0.0))
    # f(w) = 0.5 w G w' - c w (up to a constant); the zero row is always feasible
    f = np.stack([0.5 * np.einsum("ij,jk,ik->i", w, g, w) - (w * c).sum(axis=1) for w in cands])
    best = np.argmin(f, axis=0)
    return np.choose(best[:, None], cands)


def _dictionary(a: np.ndarray, b: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Minimise ``0.5 tr(H' A H) - tr(B' H)`` over ``H >= 0``, rows of norm <= 1.

    Projected gradient (the projection onto the non-negative part of the unit ball: clip,
    then scale) on a 2 x 3 problem: cheap, run to convergence.
    """
    lh = float(np.linalg.eigvalsh(a)[-1])
    for _ in range(1000):
        prev = h
        h = np.maximum(h - (a @ h - b) / lh, 0.0)
        h = h / np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1.0)
        if float(np.max(np.abs(h - prev))) <= 1e-12:
            break
    return h


def sparse_nmf(
    x: np.ndarray, h: np.ndarray, lam: float, iterations: int, tol: float = TOLERANCE
) -> tuple[np.ndarray, np.ndarray, int]:
    """Block-coordinate minimisation of ``(1/2n) ||X - W H||^2 + (lam/n) ||W||_1``.

    The data term is averaged over pixels (as SPAMS does), so λ keeps its meaning
    whatever the number of pixels. Each round solves the codes ``W`` exactly (per pixel,
    :func:`_codes`) and then the dictionary ``H`` (:func:`_dictionary`); the objective
    never increases. Stops when the dictionary's relative change in a round,
    ``||H_k - H_{k-1}||_F / ||H_k||_F``, is below ``tol``, or after ``iterations`` rounds.
    Returns ``(W, H, rounds)``.
    """
    n = x.shape[0]
    w = _codes(x, h, lam)
    rounds = 0
    while rounds < iterations:
        rounds += 1
        a = w.T @ w / n
        if float(np.linalg.eigvalsh(a)[-1]) <= 0.0:
            break
        h_prev = h
        h = _dictionary(a, w.T @ x / n, h)
        w = _codes(x, h, lam)
        scale = max(float(np.linalg.norm(h)), 1e-300)
        if float(np.linalg.norm(h - h_prev)) / scale < tol:
            break
    return w, h, rounds


def objective(x: np.ndarray, h: np.ndarray, lam: float) -> float:
    """Return ``(1/2n) ||X - W H||^2 + (lam/n) ||W||_1`` at the best codes ``W`` for ``H``."""
    w = _codes(x, h, lam)
    r = x - w @ h
    return float(0.5 * (r * r).sum(axis=1).mean() + lam * w.sum(axis=1).mean())
