"""Stain vectors by sparse non-negative matrix factorisation (Vahadane et al. 2016).

The optical density of the tissue pixels, one row per pixel, is factorised as

.. math:: \\min_{W \\ge 0,\\, H \\ge 0,\\, \\lVert h_k \\rVert_2 \\le 1}
    \\tfrac12 \\lVert OD - W H \\rVert_F^2 + \\lambda \\lVert W \\rVert_1

with ``H`` (2, 3) the stain vectors and ``W`` (n, 2) the concentrations: non-negative
(stains absorb, concentrations are amounts) and sparse (a pixel is mostly one stain).
Solved here in NumPy by alternating projected (proximal) gradient steps — FISTA on ``W``
with the non-negative soft threshold, a projected gradient step on ``H`` onto the
non-negative unit ball — started from Macenko's vectors; the reference implementation
(Vahadane's MATLAB code, StainTools) uses SPAMS' online dictionary learning on the same
objective with λ = 0.1.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._validate import as_int, describe
from imageform.analysis._arrays import image_in, is_dask
from imageform.analysis.macenko import (
    MIN_INTENSITY,
    MacenkoStains,
    _base,
    _check_params,
    _count,
    _fit,
    _keep_mask,
    _max_conc,
    _resolve_i0,
    optical_density,
)
from imageform.errors import InvalidInputError

__all__ = ["vahadane_stains"]


def _sample(flat: np.ndarray, max_pixels: int) -> np.ndarray:
    """A deterministic, evenly strided subsample of at most ``max_pixels`` rows."""
    if flat.shape[0] <= max_pixels:
        return flat
    idx = np.linspace(0, flat.shape[0] - 1, max_pixels).round().astype(np.int64)
    return flat[idx]


def _sparse_nmf(
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


def vahadane_stains(
    image: object,
    *,
    lam: float = 0.1,
    beta: float = 0.15,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    i0: object = "auto",
    base: str = "e",
    max_pixels: int = 20_000,
    iterations: int = 200,
) -> MacenkoStains:
    """Estimate two stain vectors by sparse non-negative factorisation (Vahadane 2016).

    1. :math:`OD = -\\ln(I / I_0)` (:math:`I_0` as in
       :func:`~imageform.analysis.macenko_stains`); tissue pixels are those with
       :math:`\\lVert OD \\rVert_2 \\ge \\beta` (Vahadane's code thresholds luminance;
       the OD norm is the same idea in OD units).
    2. Sparse NMF of the tissue OD (an even subsample of at most ``max_pixels``):
       :math:`\\min \\tfrac{1}{2n}\\lVert OD - WH\\rVert_F^2 + \\tfrac{\\lambda}{n}
       \\lVert W\\rVert_1` with :math:`W, H \\ge 0`, :math:`\\lVert h_k\\rVert_2 \\le 1`,
       started from Macenko's vectors.
    3. Rows of ``H`` normalised, hematoxylin (larger red OD) first; the concentrations
       and their 99th percentile as in Macenko (least squares over all pixels), so the
       result normalises with :func:`~imageform.analysis.macenko_normalize`.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats) or Dask (the tissue
        pixels are gathered into memory, at most ``max_pixels`` of them are used).
    lam : float
        Sparsity weight λ (0.1 in the paper and StainTools), per pixel.
    beta : float
        Tissue threshold on the OD norm, in ``base``'s units.
    max_percentile, min_pixels, min_intensity, i0, base
        As in :func:`~imageform.analysis.macenko_stains`.
    max_pixels : int
        Tissue pixels used by the factorisation (an evenly strided subsample).
    iterations : int
        At most this many alternating (W, H) rounds (they stop when H moves by less than
        1e-7; 20-60 rounds on H&E tiles).

    Returns
    -------
    MacenkoStains
        With ``method = "vahadane"``.

    Source: A. Vahadane et al., "Structure-preserving color normalization and sparse stain
    separation for histological images", IEEE Trans. Med. Imaging 35(8), 2016,
    pp. 1962-1971, eq. (3)-(4) (λ = 0.1).

    >>> from imageform.analysis import stain_angle, synthetic_stain_image
    >>> img, S, _ = synthetic_stain_image(rng=0)
    >>> est = vahadane_stains(img)
    >>> [bool(stain_angle(est.stain_matrix[i], S[i]) < 1.0) for i in range(2)]
    [True, True]
    """
    _check_params(beta, 1.0, max_percentile)
    if not 0.0 <= float(lam) <= 10.0:
        raise InvalidInputError(f"expected lam in [0, 10], got {describe(lam)}")
    max_pixels = as_int(max_pixels, "max_pixels")
    iterations = as_int(iterations, "iterations")
    if max_pixels < 2 or iterations < 1:
        raise InvalidInputError(
            f"expected max_pixels >= 2 and iterations >= 1, got {max_pixels} and {iterations}"
        )
    key = _base(base)
    rgb = image_in(image)
    i0v = _resolve_i0(rgb, i0)
    od = optical_density(rgb, min_intensity=min_intensity, i0=i0v, base=key)
    flat: Any = od.reshape((-1, 3)).astype(np.float64)
    keep = _keep_mask(flat, float(beta), "norm")
    n = _count(keep, float(beta), max(int(min_pixels), 2), "norm", "Vahadane")
    h0, _ = _fit(od, float(beta), 1.0, max(int(min_pixels), 2), "norm")
    tissue = flat[keep]
    if is_dask(tissue):
        tissue = tissue.compute()
    x = _sample(np.asarray(tissue), max_pixels)
    _, h = _sparse_nmf(x, np.maximum(h0, 0.0), float(lam), iterations)
    norms = np.linalg.norm(h, axis=1, keepdims=True)
    if np.any(norms == 0.0):
        h = h0  # a stain vanished (one-stain tile): keep Macenko's
        norms = np.linalg.norm(h, axis=1, keepdims=True)
    h = h / norms
    if h[0, 0] < h[1, 0]:
        h = h[::-1]
    maxc = _max_conc(od, h, float(max_percentile))
    i0t = (float(i0v[0]), float(i0v[1]), float(i0v[2]))
    return MacenkoStains(h.copy(), maxc, n, i0t, key, "vahadane", int(np.prod(rgb.shape[:-1])))
