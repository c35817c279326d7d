"""Deprecated: the simulator's colour-correction helpers, now :mod:`imageform.analysis`'s.

imageform has one colour-correction fit, :func:`imageform.analysis.fit_color_correction`,
whose matrix applies to row vectors (``rgb @ matrix.T``). The simulator's camera-RGB-to-
linear-sRGB matrix is that fit on linear values::

    corr = fit_color_correction(measured, target, transfer="linear", saturation=None)
    corrected = corr.apply(image)  # image @ corr.matrix.T

The two functions here keep their old orientation (``target ≈ measured @ M``, i.e.
``M = corr.matrix.T``) for one release and warn.
"""

from __future__ import annotations

import numpy as np

from imageform import _deprecate
from imageform._validate import as_float, as_matrix
from imageform.analysis.harmonize import ChartPatches, ColorCorrection
from imageform.analysis.harmonize import fit_color_correction as _fit
from imageform.errors import InvalidInputError

__all__ = ["apply_color_correction", "fit_color_correction"]


def _as_patches(values: np.ndarray, missing: np.ndarray) -> ChartPatches:
    zeros = np.zeros(values.shape[0], dtype=bool)
    return ChartPatches(values, np.zeros_like(values), zeros, missing)


def _fit_matrix(measured: np.ndarray, target: np.ndarray) -> np.ndarray:
    C = np.asarray(as_float(measured, "measured", finite=False), dtype=np.float64)
    T = np.asarray(as_float(target, "target", finite=False), dtype=np.float64)
    if C.ndim != 2 or C.shape[1] != 3 or T.shape != C.shape:
        raise InvalidInputError(
            f"expected measured and target of shape (N, 3), got {C.shape} and {T.shape}"
        )
    missing = ~(np.all(np.isfinite(C), axis=1) & np.all(np.isfinite(T), axis=1))
    corr = _fit(
        _as_patches(C, missing),
        _as_patches(T, missing),
        "linear",
        transfer="linear",
        saturation=None,
    )
    M = np.ascontiguousarray(corr.matrix.T)
    dtype = np.result_type(np.asarray(measured).dtype, np.asarray(target).dtype, np.float32)
    return np.asarray(M, dtype=dtype if dtype == np.float32 else np.float64)


def fit_color_correction(measured: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Fit the 3×3 M with ``target ≈ measured @ M`` (NaN rows left out); deprecated.

    ``M`` is ``fit_color_correction(measured, target, transfer="linear",
    saturation=None).matrix.T`` (:func:`imageform.analysis.fit_color_correction`).
    """
    _deprecate.warn(
        "imageform.simulate.fit_color_correction",
        "use imageform.analysis.fit_color_correction(measured, target, transfer='linear', "
        "saturation=None), whose .matrix applies as rgb @ matrix.T (the transpose of this M)",
    )
    return _fit_matrix(measured, target)


def apply_color_correction(image: np.ndarray, M: np.ndarray) -> np.ndarray:
    """Return ``image @ M`` for a linear image ``(..., 3)``; deprecated.

    Use :meth:`imageform.analysis.ColorCorrection.apply` (``transfer="linear"``), which
    computes ``image @ matrix.T`` with ``matrix = M.T``.
    """
    _deprecate.warn(
        "imageform.simulate.apply_color_correction",
        "use the ColorCorrection returned by imageform.analysis.fit_color_correction"
        "(..., transfer='linear'): corr.apply(image)",
    )
    Mm = np.asarray(as_matrix(M, "M", (3, 3), batch=False), dtype=np.float64)
    corr = ColorCorrection("linear", 1, Mm.T, transfer="linear")
    return np.asarray(corr.apply(image))


_ADVICE = "use imageform.analysis.fit_color_correction(..., transfer='linear') and its .apply"
fit_color_correction.__deprecated__ = _ADVICE  # type: ignore[attr-defined]
apply_color_correction.__deprecated__ = _ADVICE  # type: ignore[attr-defined]
