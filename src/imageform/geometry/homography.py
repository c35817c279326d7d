"""Planar homographies: estimation by the normalised DLT and application to points.

A homography ``H`` maps ``x' ~ H x`` between two images of a plane (or two views of a
rotating camera). Four correspondences, no three collinear, determine it (8 degrees of
freedom); more are fitted by least squares on the algebraic error after Hartley
normalisation (Hartley & Zisserman Algorithm 4.2).
"""

from __future__ import annotations

from itertools import combinations
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform._backend import common_device, device_of, linalg, namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import any_value
from imageform._validate import as_matrix_bounded as as_matrix
from imageform._validate import as_points_bounded as as_points
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry._normalize import similarity_normalization
from imageform.geometry.homogeneous import are_collinear, from_homogeneous

__all__ = ["apply_homography", "estimate_homography"]

F64 = NDArray[np.float64]


def _check_pairs(src: Array, dst: Array, n_min: int) -> None:
    if src.shape != dst.shape:
        raise InvalidInputError(
            f"expected src and dst of the same shape, got {tuple(src.shape)} and {tuple(dst.shape)}"
        )
    if src.ndim < 2 or src.shape[-2] < n_min:
        raise InvalidInputError(
            f"expected at least {n_min} correspondences of shape (..., N, {src.shape[-1]}), "
            f"got {tuple(src.shape)}"
        )


def _check_not_collinear(p: Array, name: str, xp: Any) -> None:
    if any_value(are_collinear(p, tol=1e-9), xp):
        raise DegenerateConfigurationError(f"the {name} points are collinear: no unique homography")
    if p.shape[-2] == 4:
        for idx in combinations(range(4), 3):
            tri = xp.stack([p[..., i, :] for i in idx], axis=-2)
            if any_value(are_collinear(tri, tol=1e-9), xp):
                raise DegenerateConfigurationError(
                    f"three of the four {name} points are collinear: no unique homography"
                )


def estimate_homography(src: ArrayLike, dst: ArrayLike) -> Array:
    r"""Homography ``H`` with ``dst ~ H src`` by the normalised DLT.

    .. math::
        \begin{pmatrix} 0^T & -\tilde x_i^T & y'_i \tilde x_i^T \\
        \tilde x_i^T & 0^T & -x'_i \tilde x_i^T \end{pmatrix} h = 0

    stacked for all correspondences, solved by SVD after normalising both point sets
    (Hartley & Zisserman Algorithm 4.2), then de-normalised and scaled to ``H[2, 2] = 1``
    (or unit Frobenius norm if ``H[2, 2] = 0``).

    Parameters
    ----------
    src, dst : array_like, shape (..., N, 2)
        N >= 4 corresponding points.

    Raises
    ------
    DegenerateConfigurationError
        If the points are collinear (or, for N = 4, three of them are), or the system is
        rank-deficient for another reason.

    Examples
    --------
    >>> src = [[0, 0], [1, 0], [1, 1], [0, 1]]
    >>> dst = [[10, 20], [12, 20], [12, 23], [10, 23]]
    >>> estimate_homography(src, dst).round(9) + 0.0
    array([[ 2.,  0., 10.],
           [ 0.,  3., 20.],
           [ 0.,  0.,  1.]])
    """
    xp = namespace(src, dst)
    s = as_points(src, "src", 2, xp=xp)
    d = as_points(dst, "dst", 2, xp=xp, dtype=s.dtype)
    _check_pairs(s, d, 4)
    _check_not_collinear(s, "source (src)", xp)
    _check_not_collinear(d, "destination (dst)", xp)
    sn, Ts = similarity_normalization(s, xp)
    dn, Td = similarity_normalization(d, xp)
    H, sv = _normalized_dlt(sn, Ts, dn, Td, xp.ones_like(sn[..., 0]), xp)
    if any_value(sv[..., 7] <= 1e-12 * sv[..., 0], xp):
        raise DegenerateConfigurationError(
            "the correspondences do not determine a unique homography"
        )
    return H


def _normalized_dlt(
    sn: Array, Ts: Array, dn: Array, Td: Array, one: Array, xp: Any
) -> tuple[Array, Array]:
    """``H`` (..., 3, 3) of :func:`estimate_homography`, unchecked, and the DLT's singular values.

    ``sn, dn`` are the normalised point sets and ``Ts, Td`` their similarities
    (:func:`similarity_normalization`); ``one`` (..., N) is 1 for a point and 0 for the
    padding of a batch, whose zero rows leave ``AᵀA``, and so the singular values and the null
    vector, as they are.
    """
    x, y = sn[..., 0], sn[..., 1]
    u, v = dn[..., 0], dn[..., 1]
    zero = xp.zeros_like(x)
    r1 = xp.stack((zero, zero, zero, -x, -y, -one, v * x, v * y, v), axis=-1)
    r2 = xp.stack((x, y, one, zero, zero, zero, -u * x, -u * y, -u), axis=-1)
    A = xp.concat((r1, r2), axis=-2)
    # full V when there are fewer equations than unknowns (N = 4 gives 8 x 9)
    _, sv, Vt = linalg(xp).svd(A, full_matrices=A.shape[-2] < A.shape[-1])
    Hn = xp.reshape(Vt[..., -1, :], (*Vt.shape[:-2], 3, 3))
    H = linalg(xp).inv(Td) @ Hn @ Ts
    h22 = H[..., 2, 2]
    fro = xp.sqrt(xp.sum(H * H, axis=(-2, -1)))
    tiny = xp.abs(h22) <= 1e-12 * fro
    scale = xp.where(tiny, fro, h22)
    return H / scale[..., None, None], sv


#: A view whose points are this close to one line (smallest over largest singular value of
#: the centred points), or whose DLT system is this close to rank 7, is solved on its own by
#: :func:`estimate_homography` (which refuses it, or solves it, as alone).
_SUSPECT = 1e-6


def _homographies_padded(src: F64, dst: F64, sizes: NDArray[np.intp]) -> F64:
    """``H_k`` (V, 3, 3) with ``dst_k ~ H_k src_k`` for views padded to ``(V, N, 2)``.

    :func:`estimate_homography`'s normalised DLT of every view in one batch, each view
    normalised over its first ``sizes[k]`` points (the rest is padding). The views must be
    clean, finite and of at least 4 points each (the caller checks them). A view of 4 points,
    or of nearly collinear points, or with a nearly rank-deficient system (:data:`_SUSPECT`),
    or a non-finite result, is solved on its own by :func:`estimate_homography`, so that it is
    refused with the same message as alone.
    """
    xp = namespace(src, dst)
    mask = np.arange(src.shape[1])[None, :] < sizes[:, None]
    sn, Ts = similarity_normalization(src, xp, mask=mask)
    dn, Td = similarity_normalization(dst, xp, mask=mask)
    # nearly collinear points (the padding's zero rows leave the singular values as they are)
    ps = np.linalg.svd(np.stack((sn, dn)), compute_uv=False)
    flat = np.any(ps[..., -1] <= _SUSPECT * np.where(ps[..., 0] == 0, 1.0, ps[..., 0]), axis=0)
    Hb, sv = _normalized_dlt(sn, Ts, dn, Td, mask.astype(np.float64), xp)
    H = np.asarray(Hb, dtype=np.float64)
    alone = (
        flat | (sizes == 4) | (sv[:, 7] <= _SUSPECT * sv[:, 0]) | ~np.all(np.isfinite(H), (1, 2))
    )
    for k in np.flatnonzero(alone):
        n = int(sizes[k])
        H[k] = np.asarray(estimate_homography(src[k, :n], dst[k, :n]), dtype=np.float64)
    return H


def apply_homography(H: ArrayLike, points: ArrayLike) -> Array:
    """Map points ``(..., N, 2)`` through ``H``: ``x' = (H x̃)₁₂ / (H x̃)₃``.

    Points that map to infinity (``(H x̃)₃ = 0``, on the line ``H``'s vanishing line) come
    back as NaN (never a division by zero); use :func:`from_homogeneous` on
    ``to_homogeneous(points) @ H.T`` for their homogeneous images.

    Examples
    --------
    >>> H = [[2, 0, 10], [0, 3, 20], [0, 0, 1]]
    >>> apply_homography(H, [[1.0, 1.0], [0.5, 0.0]])
    array([[12., 23.],
           [11., 20.]])
    """
    xp = namespace(H, points)
    p = as_points(points, "points", 2, xp=xp, device=common_device(points, H))
    Hm = as_matrix(H, "H", (3, 3), xp=xp, dtype=p.dtype, device=device_of(p))
    if any_value(xp.all(Hm == 0), xp):
        raise InvalidInputError("expected a non-zero H (a zero matrix maps every point nowhere)")
    ones = xp.ones((*p.shape[:-1], 1), dtype=p.dtype, device=device_of(p))
    ph = xp.concat((p, ones), axis=-1) @ xp.matrix_transpose(Hm)
    return from_homogeneous(ph, at_infinity="nan")
