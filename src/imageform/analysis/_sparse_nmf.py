"""Sparse non-negative matrix factorisation for Vahadane's stain separation (private).

Pure NumPy, used by :func:`imageform.analysis.macenko.vahadane_stains`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sample_rows", "sparse_nmf"]


def sample_rows(flat: np.ndarray, max_pixels: int) -> np.ndarray:
    """Return a deterministic, evenly strided subsample of at most ``max_pixels`` rows."""
    if flat.shape[0] <= max_pixels:
        return flat
    idx = np.linspace(0, flat.shape[0] - 1, max_pixels).round().astype(np.int64)
    return flat[idx]


def sparse_nmf(
    x: np.ndarray, h: np.ndarray, lam: float, iterations: int, tol: float = 1e-7
) -> tuple[np.ndarray, np.ndarray]:
    """Alternating minimisation of ``0.5 ||X - W H||^2 + lam * n * ||W||_1`` (mean-scaled).

    The data term is averaged over pixels (as SPAMS does), so λ keeps its meaning
    whatever the number of pixels. Stops when no entry of H moves by more than ``tol``
    in a round.
    """
    n = x.shape[0]
    w = np.maximum(x @ np.linalg.pinv(h), 0.0)
    for _ in range(iterations):
        # W: FISTA steps, prox of lam*||.||_1 + indicator(W >= 0) is max(z - t*lam, 0)
        g = h @ h.T
        lw = max(float(np.linalg.eigvalsh(g)[-1]), 1e-12)
        xh = x @ h.T
        y, w_prev, t = w, w, 1.0
        for _ in range(10):
            w_new = np.maximum(y - (y @ g - xh) / lw - lam / lw, 0.0)
            t_new = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
            y = w_new + ((t - 1.0) / t_new) * (w_new - w_prev)
            w_prev, t = w_new, t_new
        w = w_prev
        # H: projected gradient on 0.5/n ||X - W H||^2 over {H >= 0, ||h_k|| <= 1}
        a = w.T @ w / n
        lh = float(np.linalg.eigvalsh(a)[-1])
        if lh <= 0.0:
            break
        b = w.T @ x / n
        h_prev = h
        for _ in range(5):
            h = np.maximum(h - (a @ h - b) / lh, 0.0)
            norms = np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1.0)
            h = h / norms
        if float(np.max(np.abs(h - h_prev))) < tol:
            break
    return w, h
