"""Stain separation and normalisation in optical density (Macenko et al. 2009).

Bright-field microscopy obeys Beer-Lambert: the optical density of each RGB channel,
:math:`OD = -\\log_{10}(I / I_0)`, is linear in the stain concentrations,
:math:`OD = C S` with one row of ``S`` per stain. Macenko's method finds the two stain
vectors as the extreme directions of the tissue's OD cloud in its principal plane and
rescales the concentrations to a target's.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from imageform._validate import as_float, as_int, as_matrix, as_real, check_option, format_shape
from imageform.analysis._arrays import exact_quantile, image_in, is_dask, read_json, write_json
from imageform.analysis._guard import count, real_array, unit_rows
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "MIN_INTENSITY",
    "TRANSPARENT_RULES",
    "MacenkoStains",
    "macenko_normalize",
    "macenko_stains",
    "optical_density",
    "stain_angle",
    "stain_concentrations",
]

#: Default floor of intensities before the logarithm: the smallest non-zero 8-bit code.
MIN_INTENSITY = 1.0 / 255.0


def optical_density(image: object, *, min_intensity: float = MIN_INTENSITY) -> Any:
    """Optical density per channel: :math:`OD = -\\log_{10}(\\max(I, I_{min}) / I_0)`, I₀ = 1.

    ``I`` is the encoded value in [0, 1] read as transmitted intensity (as Macenko and
    Ruifrok do with 8-bit scans). A pixel of 0 has unbounded OD; it is read as
    ``min_intensity`` (default 1/255, the smallest non-zero 8-bit code) — an explicit,
    documented floor.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB, uint8/uint16, or Dask (computed lazily).

    Returns
    -------
    array, shape (..., 3)

    Source: Ruifrok & Johnston 2001, eq. (1); Macenko et al. 2009, sec. 2.

    >>> optical_density(np.array([0.1, 0.5, 0.01])).round(6).tolist()
    [1.0, 0.30103, 2.0]
    """
    rgb = image_in(image)
    min_intensity = as_real(min_intensity, "min_intensity")
    if not 0.0 < min_intensity <= 1.0:
        raise InvalidInputError(f"expected min_intensity in (0, 1], got {min_intensity!r}")
    floor = rgb.dtype.type(min_intensity)
    if is_dask(rgb):
        import dask.array as da

        return -da.log10(da.maximum(rgb, floor))
    return -np.log10(np.maximum(rgb, floor))


def stain_angle(u: object, v: object) -> float:
    """Angle in degrees between two stain (OD) vectors: :math:`\\arccos(\\hat u \\cdot \\hat v)`.

    >>> round(stain_angle([1, 0, 0], [1, 1, 0]), 6)
    45.0
    """
    a = real_array(u, "u", (3,))
    b = real_array(v, "v", (3,))
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    for name, n in (("u", na), ("v", nb)):
        if not n > 0.0:
            raise InvalidInputError(f"expected {name} as a non-zero stain vector, got length 0")
        if not np.isfinite(n):
            raise InvalidInputError(f"expected {name} with a finite length, got {n:g}")
    c = (a / na) @ (b / nb)
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


@dataclass(frozen=True)
class MacenkoStains:
    """Stain matrix (rows: first and second stain, unit OD vectors) and the 99th-percentile
    concentration of each stain (``max_concentrations``)."""

    stain_matrix: np.ndarray
    max_concentrations: np.ndarray
    n_pixels: int = 0

    def __post_init__(self) -> None:
        """Two finite stain vectors of non-zero length, two finite concentrations."""
        s = real_array(self.stain_matrix, "stain_matrix", (2, 3))
        unit_rows(s, "stain_matrix")
        m = real_array(self.max_concentrations, "max_concentrations", (2,))
        object.__setattr__(self, "stain_matrix", s)
        object.__setattr__(self, "max_concentrations", m)
        object.__setattr__(self, "n_pixels", count(self.n_pixels, "n_pixels"))

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (``kind: "macenko_stains"``)."""
        write_json(
            path,
            {
                "kind": "macenko_stains",
                "stain_matrix": np.asarray(self.stain_matrix).tolist(),
                "max_concentrations": np.asarray(self.max_concentrations).tolist(),
                "n_pixels": int(self.n_pixels),
            },
        )

    @classmethod
    def from_json(cls, path: str | Path) -> MacenkoStains:
        """Load stains saved by :meth:`to_json`."""
        d = read_json(path, "macenko_stains")
        try:
            s = as_matrix(d["stain_matrix"], "stain_matrix", (2, 3), batch=False)
            m = np.asarray(d["max_concentrations"], dtype=np.float64)
            n = int(d.get("n_pixels", 0))
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed Macenko stains in {path}: {exc}") from exc
        if m.shape != (2,):
            raise InvalidInputError(f"expected 2 max_concentrations in {path}, got {m.shape}")
        return cls(np.asarray(s, dtype=np.float64), m, n)


def stain_concentrations(
    image: object, stain_matrix: object, *, min_intensity: float = MIN_INTENSITY
) -> Any:
    """Colour deconvolution: least-squares concentrations :math:`C = OD\\, S^+`.

    Parameters
    ----------
    image : array_like, shape (..., 3)
    stain_matrix : array_like, shape (k, 3)
        One OD vector per stain (k = 2 or 3); with k = 3 this is Ruifrok's inversion.

    Returns
    -------
    array, shape (..., k)

    Source: Ruifrok & Johnston 2001, eq. (4)-(6); Macenko et al. 2009 (least squares).

    >>> S = np.array([[0.6, 0.8, 0.0], [0.0, 0.6, 0.8]])
    >>> img = 10.0 ** -(np.array([0.5, 0.25]) @ S)
    >>> stain_concentrations(img, S).round(6).tolist()
    [0.5, 0.25]
    """
    s = np.asarray(as_float(stain_matrix, "stain_matrix"), dtype=np.float64)
    if s.shape not in ((2, 3), (3, 3)):
        raise InvalidInputError(
            f"expected stain_matrix of shape (2, 3) or (3, 3), got {format_shape(s.shape)}"
        )
    od = optical_density(image, min_intensity=min_intensity)
    pinv = np.linalg.pinv(s).astype(od.dtype)  # (3, k)
    return od @ pinv


#: Rules for transparent (background) pixels: drop a pixel when ...
TRANSPARENT_RULES: MappingProxyType[str, str] = MappingProxyType(
    {
        "any_channel": "any channel's OD < beta (Macenko's reference code)",
        "norm": "the OD vector's length ||OD||_2 < beta (keeps pure stains of any hue)",
    }
)


def _fit(od: Any, beta: float, alpha: float, min_pixels: int, rule: str) -> tuple[np.ndarray, int]:
    """Stain matrix (2, 3) from OD pixels, NumPy or Dask (same formulas, same order)."""
    flat = od.reshape((-1, 3)).astype(np.float64)
    if rule == "any_channel":
        keep = (flat >= beta).all(axis=1)
    else:
        keep = (flat * flat).sum(axis=1) >= beta * beta
    w = keep.astype(np.float64)
    n = w.sum()
    lazy = is_dask(flat)
    if lazy:
        import dask

        n = dask.compute(n)[0]
    n = int(n)
    if n < min_pixels:
        raise DegenerateConfigurationError(
            f"Macenko: only {n} pixels have optical density >= beta={beta:g} "
            f"({TRANSPARENT_RULES[rule]} drops the others) "
            f"(need at least {min_pixels}); is there tissue in the image?"
        )
    # covariance of the kept OD vectors as sums (a reduction in Dask), then its eigenvectors
    s1 = (flat * w[:, None]).sum(axis=0)
    s2 = [(flat[:, i] * flat[:, j] * w).sum() for i in range(3) for j in range(i, 3)]
    if lazy:
        import dask

        s1, s2 = dask.compute(s1, s2)
    s1 = np.asarray(s1)
    mean = s1 / n
    m2 = np.empty((3, 3))
    k = 0
    for i in range(3):
        for j in range(i, 3):
            m2[i, j] = m2[j, i] = float(s2[k]) - n * mean[i] * mean[j]
            k += 1
    cov = m2 / (n - 1)
    _, vecs = np.linalg.eigh(cov)
    plane = vecs[:, [2, 1]]  # the two largest
    plane = plane * np.where(plane[0] < 0, -1.0, 1.0)  # point along +R (Macenko's code)
    proj = flat @ plane
    phi = np.arctan2(proj[:, 1], proj[:, 0])
    if lazy:
        phi_k = phi[keep]
        lo, hi = exact_quantile(phi_k, alpha), exact_quantile(phi_k, 100.0 - alpha)
    else:
        phi_k = phi[keep]
        lo, hi = (float(v) for v in np.percentile(phi_k, [alpha, 100.0 - alpha]))
    v_min = plane @ np.array([np.cos(lo), np.sin(lo)])
    v_max = plane @ np.array([np.cos(hi), np.sin(hi)])
    # hematoxylin first: the vector with the larger red OD component (Macenko's heuristic)
    stains = np.stack([v_min, v_max] if v_min[0] > v_max[0] else [v_max, v_min])
    return stains / np.linalg.norm(stains, axis=1, keepdims=True), n


def _max_conc(od: Any, stains: np.ndarray, percentile: float) -> np.ndarray:
    c = od.reshape((-1, 3)).astype(np.float64) @ np.linalg.pinv(stains)
    if is_dask(c):
        return np.array([exact_quantile(c[:, i], percentile) for i in range(2)])
    return np.percentile(c, percentile, axis=0)


def macenko_stains(
    image: object,
    *,
    beta: float = 0.15,
    alpha: float = 1.0,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    transparent: str = "any_channel",
) -> MacenkoStains:
    """Estimate the two stain vectors and their maximum concentrations (Macenko 2009).

    1. :math:`OD = -\\log_{10}(I / I_0)`; keep pixels with OD > β in every channel.
    2. Eigenvectors of the covariance of the kept OD: the plane of the two largest.
    3. Angle of each projected pixel, :math:`\\varphi = \\operatorname{atan2}(t_2, t_1)`;
       the α-th and (100-α)-th percentiles of φ give the extreme stain vectors
       :math:`v = V(\\cos\\varphi, \\sin\\varphi)^T`, the one with larger red OD first
       (hematoxylin).
    4. Concentrations :math:`C = OD\\, S^+` (least squares, all pixels); their 99th
       percentile per stain is the robust maximum.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats), or Dask: the covariance
        is a reduction and the percentiles are exact two-pass Dask quantiles, so the result
        equals the in-memory one.
    beta : float
        OD threshold for transparent (background) pixels (0.15 in the paper).
    alpha : float
        Percentile (in %) for the robust extreme angles (1 in the paper).
    max_percentile : float
        Percentile of concentrations taken as the maximum (99 in the paper).
    min_pixels : int
        Fewer kept pixels raise :class:`DegenerateConfigurationError` (no tissue).
    min_intensity : float
        Floor of intensities before the logarithm (see :func:`optical_density`).
    transparent : {"any_channel", "norm"}
        Which pixels count as transparent: ``"any_channel"`` drops a pixel when any
        channel's OD is below β (Macenko's reference code); ``"norm"`` when
        :math:`\\lVert OD \\rVert_2 < \\beta`. Stains that barely absorb in one channel
        (Ruifrok's eosin, OD 0.07 in red) lose their pure pixels under ``"any_channel"``
        and the estimated vector moves towards the other stain; use ``"norm"`` there.

    Returns
    -------
    MacenkoStains

    Source: M. Macenko et al., "A method for normalizing histology slides for quantitative
    analysis", ISBI 2009, pp. 1107-1110, sec. 2 and Fig. 1.

    >>> from imageform.analysis.synthetic import synthetic_stain_image
    >>> img, S, _ = synthetic_stain_image(rng=0)
    >>> est = macenko_stains(img, transparent="norm")
    >>> [round(stain_angle(est.stain_matrix[i], S[i]), 1) for i in range(2)]
    [0.4, 0.3]
    """
    for name, val, lo, hi in (
        ("beta", beta, 0.0, 10.0),
        ("alpha", alpha, 0.0, 50.0),
        ("max_percentile", max_percentile, 0.0, 100.0),
    ):
        if not lo <= as_real(val, name) <= hi:
            raise InvalidInputError(f"expected {name} in [{lo:g}, {hi:g}], got {val!r}")
    min_pixels = as_int(min_pixels, "min_pixels", minimum=0)
    rule = check_option(transparent, TRANSPARENT_RULES, "transparent-pixel rule")
    od = optical_density(image, min_intensity=min_intensity)
    stains, n = _fit(od, float(beta), float(alpha), max(min_pixels, 2), rule)
    maxc = _max_conc(od, stains, float(max_percentile))
    return MacenkoStains(stains, maxc, n)


def _target(target: object, **kw: Any) -> MacenkoStains:
    if isinstance(target, MacenkoStains):
        return target
    if target is None:
        raise TypeError("expected target as an image, MacenkoStains or a JSON path, got None")
    if isinstance(target, str | Path):
        return MacenkoStains.from_json(target)
    return macenko_stains(target, **kw)


def _reconstruct(
    od: np.ndarray, pinv_src: np.ndarray, scale: np.ndarray, stains_t: np.ndarray
) -> np.ndarray:
    c = od.astype(np.float64) @ pinv_src * scale
    return np.asarray(10.0 ** (-(c @ stains_t)), dtype=od.dtype)


def macenko_normalize(
    image: object,
    target: object,
    *,
    source: MacenkoStains | None = None,
    beta: float = 0.15,
    alpha: float = 1.0,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    transparent: str = "any_channel",
) -> Any:
    """Re-render ``image`` with ``target``'s stain vectors and concentration range.

    .. math:: C = OD\\,S_s^+, \\quad C' = C \\,\\frac{C^{99}_t}{C^{99}_s}, \\quad
        I' = I_0\\, 10^{-C' S_t}

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB (uint8/uint16/floats) or Dask (statistics as exact reductions, the
        transform chunk-wise).
    target : array_like or MacenkoStains or path
        Target image, its :class:`MacenkoStains`, or a JSON file saved by
        :meth:`MacenkoStains.to_json`.
    source : MacenkoStains, optional
        Precomputed stains of ``image``.
    beta, alpha, max_percentile, min_pixels, min_intensity, transparent
        As in :func:`macenko_stains` (used for the image and for a target image).

    Returns
    -------
    array, shape (..., 3)
        Transmitted intensity in (0, 1] for non-negative concentrations (negative
        least-squares concentrations can give values above 1; nothing is clipped).

    Source: Macenko et al. 2009, sec. 2 (normalisation step).

    >>> from imageform.analysis.synthetic import synthetic_stain_image
    >>> a, _, _ = synthetic_stain_image(max_concentration=(0.6, 1.0), rng=0)
    >>> b, _, _ = synthetic_stain_image(rng=1)
    >>> out = macenko_normalize(a, b)
    >>> ratio = macenko_stains(out).max_concentrations / macenko_stains(b).max_concentrations
    >>> np.round(ratio, 2).tolist()
    [1.0, 0.99]
    """
    kw: dict[str, Any] = {
        "beta": beta,
        "alpha": alpha,
        "max_percentile": max_percentile,
        "min_pixels": min_pixels,
        "min_intensity": min_intensity,
        "transparent": transparent,
    }
    if source is not None and not isinstance(source, MacenkoStains):
        raise TypeError(f"expected source as MacenkoStains or None, got {type(source).__name__}")
    tgt = _target(target, **kw)
    od = optical_density(image, min_intensity=min_intensity)
    src = macenko_stains(image, **kw) if source is None else source
    for name, st in (("source", src), ("target", tgt)):
        if np.any(np.asarray(st.max_concentrations) <= 0):
            raise DegenerateConfigurationError(
                f"Macenko: {name} max concentrations "
                f"{np.round(np.asarray(st.max_concentrations), 4).tolist()} are not positive"
            )
    scale = np.asarray(tgt.max_concentrations) / np.asarray(src.max_concentrations)
    sv = np.linalg.svd(np.asarray(src.stain_matrix, dtype=np.float64), compute_uv=False)
    if not sv[-1] > 1e-6 * sv[0]:
        raise DegenerateConfigurationError(
            "Macenko: source stain_matrix is singular (its two stain vectors are parallel)"
        )
    pinv_src = np.linalg.pinv(np.asarray(src.stain_matrix))
    args = (pinv_src, scale, np.asarray(tgt.stain_matrix, dtype=np.float64))
    if is_dask(od):
        return od.map_blocks(_reconstruct, *args, dtype=od.dtype)
    return _reconstruct(od, *args)
