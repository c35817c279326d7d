"""The colour-correction matrix: camera RGB to linear sRGB, fitted on the ColorChecker."""

from __future__ import annotations

import numpy as np

from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = ["apply_color_correction", "fit_color_correction"]


def fit_color_correction(measured: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The 3×3 matrix M with ``target ≈ measured @ M`` in the least-squares sense.

    .. math:: M = \\arg\\min_M \\|C M - T\\|_F^2 = (C^T C)^{-1} C^T T

    where the rows of C ``(N, 3)`` are the measured (white-balanced) camera RGB of N patches
    and the rows of T their ground-truth linear sRGB. NaN rows (patches outside the image)
    are left out.

    Source: G. D. Finlayson, M. Mackiewicz, A. Hurlbert, "Color correction using
    root-polynomial regression", IEEE TIP 24(5), 2015, eq. (2) (the linear 3×3 case).

    Raises
    ------
    DegenerateConfigurationError
        With fewer than 3 usable patches or a rank-deficient C.

    >>> C = np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
    >>> (fit_color_correction(C, 2 * C).round(12) + 0.0).tolist()[0]
    [2.0, 0.0, 0.0]
    """
    C = np.asarray(measured, dtype=np.float64)  # the fit itself runs in float64
    T = np.asarray(target, dtype=np.float64)
    if C.ndim != 2 or C.shape[1] != 3 or T.shape != C.shape:
        raise InvalidInputError(
            f"expected measured and target of shape (N, 3), got {C.shape} and {T.shape}"
        )
    ok = np.all(np.isfinite(C), axis=1) & np.all(np.isfinite(T), axis=1)
    if ok.sum() < 3 or np.linalg.matrix_rank(C[ok]) < 3:
        raise DegenerateConfigurationError(
            f"a colour-correction fit needs >= 3 patches of independent colours, "
            f"got {int(ok.sum())} usable"
        )
    M, *_ = np.linalg.lstsq(C[ok], T[ok], rcond=None)
    dtype = np.result_type(np.asarray(measured).dtype, np.asarray(target).dtype, np.float32)
    return np.asarray(M, dtype=dtype if dtype == np.float32 else np.float64)


def apply_color_correction(image: np.ndarray, M: np.ndarray) -> np.ndarray:
    r"""``image @ M`` for a linear image ``(..., 3)`` (row-vector convention, DESIGN.md).

    .. math:: \mathbf{c}' = \mathbf{c}\, M

    uint8/uint16 images are read as full range (float32); float32 stays float32, float64
    stays float64.

    >>> apply_color_correction(np.ones((1, 1, 3)), 2 * np.eye(3)).tolist()
    [[[2.0, 2.0, 2.0]]]
    """
    from imageform._validate import as_image

    img = np.asarray(as_image(image, "image", range_check=False))
    Mm = np.asarray(M, dtype=np.float64)
    if Mm.shape != (3, 3):
        raise InvalidInputError(f"expected a (3, 3) matrix M, got {Mm.shape}")
    return np.asarray(img @ Mm.astype(img.dtype))
