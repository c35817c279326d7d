"""Camera resection: the 3×4 projection matrix from 3-D/2-D correspondences (normalised DLT).

Each correspondence ``X_i ↔ x_i`` gives two linear equations in the 12 entries of P
(``x_i × P X_i = 0``); six points in general position (not all on one plane) determine P
up to scale. The lecture's "linear least squares": stack them and take the singular vector
of the smallest singular value, after Hartley normalisation of both point sets (Hartley &
Zisserman Algorithm 7.1).
"""

from __future__ import annotations

from imageform._backend import common_device, linalg, namespace, sign_of
from imageform._typing import Array, ArrayLike
from imageform._validate import any_value, as_points_bounded
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry._normalize import similarity_normalization

__all__ = ["estimate_projection_matrix"]


def estimate_projection_matrix(points_3d: ArrayLike, points_2d: ArrayLike) -> Array:
    r"""Estimate the 3×4 camera matrix P with ``x ~ P X`` by the normalised DLT.

    .. math::
        \begin{pmatrix} \tilde X_i^T & 0^T & -u_i \tilde X_i^T \\
        0^T & \tilde X_i^T & -v_i \tilde X_i^T \end{pmatrix} p = 0

    P is returned scaled so that its third row's first three entries have unit norm and
    ``det P[:, :3] > 0``: then ``(P X̃)₃`` is the depth of ``X`` in front of the camera.
    Decompose it with :func:`~imageform.geometry.decompose_projection_matrix`.

    Parameters
    ----------
    points_3d : array_like, shape (..., N, 3)
        N >= 6 world points, not all coplanar.
    points_2d : array_like, shape (..., N, 2)
        Their pixels.

    Raises
    ------
    DegenerateConfigurationError
        If the 3-D points are coplanar (a plane does not determine P: use a homography) or
        the system is otherwise rank-deficient.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.geometry import project_points, projection_matrix
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = np.array([[0, 0, 5], [1, 0, 6], [0, 1, 5], [1, 1, 7], [-1, 0.5, 6], [0.3, -1, 8.0]])
    >>> P = estimate_projection_matrix(X, project_points(X, K).uv)
    >>> np.allclose(P, projection_matrix(K))
    True
    """
    xp = namespace(points_3d, points_2d)
    dev = common_device(points_3d, points_2d)
    X = as_points_bounded(points_3d, "points_3d", 3, xp=xp, device=dev)
    x = as_points_bounded(points_2d, "points_2d", 2, xp=xp, dtype=X.dtype, device=dev)
    if X.shape[:-1] != x.shape[:-1]:
        raise InvalidInputError(
            f"expected as many points_3d as points_2d, got {tuple(X.shape)} and {tuple(x.shape)}"
        )
    if X.ndim < 2 or X.shape[-2] < 6:
        raise InvalidInputError(
            f"expected at least 6 correspondences of shape (..., N, 3), got {tuple(X.shape)}"
        )
    centred = X - xp.mean(X, axis=-2, keepdims=True)
    sv3 = linalg(xp).svdvals(centred)
    if any_value(sv3[..., 2] <= 1e-9 * sv3[..., 0], xp):
        raise DegenerateConfigurationError(
            "the 3-D points are coplanar: a plane does not determine P (use estimate_homography)"
        )
    Xn, T3 = similarity_normalization(X, xp)
    xn, T2 = similarity_normalization(x, xp)
    ones = xp.ones_like(Xn[..., :1])
    Xh = xp.concat((Xn, ones), axis=-1)
    zero = xp.zeros_like(Xh)
    u, v = xn[..., 0:1], xn[..., 1:2]
    r1 = xp.concat((Xh, zero, -u * Xh), axis=-1)
    r2 = xp.concat((zero, Xh, -v * Xh), axis=-1)
    A = xp.concat((r1, r2), axis=-2)
    # full V when there are fewer equations than unknowns (N = 4 gives 8 x 9)
    _, sv, Vt = linalg(xp).svd(A, full_matrices=A.shape[-2] < A.shape[-1])
    if any_value(sv[..., 10] <= 1e-12 * sv[..., 0], xp):
        raise DegenerateConfigurationError("the correspondences do not determine a unique P")
    Pn = xp.reshape(Vt[..., -1, :], (*Vt.shape[:-2], 3, 4))
    P = linalg(xp).inv(T2) @ Pn @ T3
    m3 = xp.sqrt(xp.sum(P[..., 2, :3] ** 2, axis=-1))
    sign = sign_of(linalg(xp).det(P[..., :3]), xp)
    return P * (sign / m3)[..., None, None]
