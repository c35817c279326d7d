"""The pinhole camera: projection, back-projection and the 3×4 projection matrix.

Conventions (docs/conventions.md): ``X_cam = R @ X_world + t``; camera centre ``C = -Rᵀ t``;
``P = K [R | t]``; pixel ``(u, v)`` = (column, row) with the top-left pixel centre at (0, 0).

Points at or behind the camera (``z_cam <= 0``) have no image: they come back as NaN with
``valid = False``. OpenCV's ``projectPoints`` and kornia mirror them into the image
silently; a wrong-side point there looks like a valid one.

Image planes: ``"virtual"`` (the default, in front of the pinhole, upright image, the
convention of every computer-vision text) and ``"real"`` (behind the pinhole at distance f,
where a camera obscura or a sensor sees it: the image is inverted, ``u' = 2 cx - u``,
``v' = 2 cy - v`` for zero skew).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

import numpy as np

from imageform._backend import (
    common_device,
    constant,
    device_of,
    linalg,
    namespace,
    reads_values,
    sign_of,
    use_numba,
)
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_float_bounded,
    as_matrix_bounded,
    as_points_bounded,
    check_image_size,
    check_option,
    check_rotation,
    format_shape,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry._results import Projection
from imageform.geometry.intrinsics import Intrinsics

__all__ = [
    "Camera",
    "DecomposedProjection",
    "ImagePlane",
    "Projection",
    "backproject",
    "decompose_projection_matrix",
    "project_points",
    "projection_matrix",
    "unproject",
]

ImagePlane = Literal["virtual", "real"]
_PLANES = ("virtual", "real")
#: Above this many points a single-camera NumPy projection runs the numba kernel.
_KERNEL_MIN_POINTS = 20_000


class DecomposedProjection(NamedTuple):
    """Result of :func:`decompose_projection_matrix`: ``P = λ K [R | t]``."""

    #: Intrinsics (3, 3), ``K[2, 2] = 1``, positive focal lengths.
    K: Array
    #: World-to-camera rotation (3, 3), ``det R = +1``.
    R: Array
    #: World-to-camera translation (3,).
    t: Array


def _plane_K(K: Array, plane: str, xp: Any) -> Array:
    """Return the calibration matrix of the chosen image plane.

    On the real plane (behind the pinhole) the image is inverted about the principal point:
    ``u' = cx - (fx x + s y)``, ``v' = cy - fy y``, i.e. fx, fy and s change sign.
    """
    if plane == "virtual":
        return K
    return K * constant(_REAL_PLANE_SIGN, K, xp)


def _prepare(
    points: ArrayLike,
    K: ArrayLike,
    R: ArrayLike | None,
    t: ArrayLike | None,
) -> tuple[Any, Array, Array, Array, Array]:
    xp = namespace(points, K, R, t)
    X = as_points_bounded(
        points, "points", 3, xp=xp, finite=False, device=common_device(points, K, R, t)
    )
    dev = device_of(X)
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=X.dtype, device=dev)
    _check_K(Km, xp)
    if R is None:  # constants: uploaded once per device (no kernel per call on a GPU)
        Rm = constant(_EYE3, X, xp)
    else:
        Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=X.dtype, device=dev)
        check_rotation(Rm, "R", xp=xp)
    tv = (
        constant(_ZERO3, X, xp)
        if t is None
        else as_points_bounded(t, "t", 3, xp=xp, dtype=X.dtype, device=dev)
    )
    return xp, X, Km, Rm, tv


_EYE3 = np.eye(3)
_REAL_PLANE_SIGN = np.array([[-1.0, -1.0, 1.0], [-1.0, -1.0, 1.0], [1.0, 1.0, 1.0]])
_ZERO3 = np.zeros(3)


def _check_K(K: Array, xp: Any) -> None:
    if not reads_values(K):  # a device K is not read: build no comparisons (no kernels)
        return
    if (
        any_value(K[..., 2, 0] != 0, xp)
        or any_value(K[..., 2, 1] != 0, xp)
        or any_value(K[..., 1, 0] != 0, xp)
    ):
        raise InvalidInputError("expected an upper-triangular K with last row (0, 0, k33)")
    if any_value(K[..., 0, 0] * K[..., 1, 1] * K[..., 2, 2] == 0, xp):
        raise InvalidInputError("K is singular (fx, fy or K[2, 2] is zero)")


def _project_xp(
    X: Array, K: Array, R: Array, t: Array, xp: Any, *, identity: bool = False
) -> tuple[Array, Array]:
    """Array-API twin of the numba kernel; broadcasts K, R, t over leading dimensions.

    ``identity``: R and t were not given (camera-frame points), so the ``(N, 3) x (3, 3)``
    product, a full pass over the points, is skipped.
    """
    if identity:
        Xc = X
    else:
        # rows with inf give NaN in the product; they are masked out below: silence NumPy
        with np.errstate(invalid="ignore"):
            Xc = X @ xp.matrix_transpose(R) + t[..., None, :] if X.ndim >= 2 else R @ X + t
    # A point is valid when 0 < z < inf and its pixel coordinates are finite: the same as
    # "z > 0 and X_c finite" except that a finite point whose projection overflows is
    # invalid too. No isfinite over (N, 3) (PyTorch runs it as several passes) and every
    # pass on contiguous (N,) vectors: ``w - w == 0`` is the finiteness test, K is divided
    # by K[2, 2] (9 numbers) rather than u and v (2N).
    with np.errstate(invalid="ignore", over="ignore"):  # inf rows are masked out below
        return _pixels(Xc, K, X.ndim, xp)


def _pixels(Xc: Array, K: Array, ndim: int, xp: Any) -> tuple[Array, Array]:
    z = Xc[..., 2]
    front = (z > 0) & (z < math.inf)
    zs = xp.where(front, z, 1.0)  # no division by zero; gradients stay finite
    x = Xc[..., 0] / zs
    y = Xc[..., 1] / zs
    k = K / K[..., 2:3, 2:3]
    kb = k[..., None, :, :] if (ndim >= 2 and K.ndim > 2) else k
    u = kb[..., 0, 0] * x + kb[..., 0, 1] * y + kb[..., 0, 2]
    v = kb[..., 1, 1] * y + kb[..., 1, 2]
    valid = front & (u - u == 0) & (v - v == 0)
    uv = xp.stack((xp.where(valid, u, math.nan), xp.where(valid, v, math.nan)), axis=-1)
    return uv, valid


def project_points(
    points: ArrayLike,
    K: ArrayLike,
    R: ArrayLike | None = None,
    t: ArrayLike | None = None,
    *,
    image_plane: ImagePlane = "virtual",
) -> Projection:
    r"""Project world points to pixels, ``(u, v, 1)ᵀ ~ K (R X + t)``.

    .. math::
        x = X_c / Z_c,\; y = Y_c / Z_c, \quad
        u = f_x x + s\, y + c_x, \quad v = f_y y + c_y

    with ``(X_c, Y_c, Z_c) = R X + t`` (Hartley & Zisserman eq. 6.11). The skew ``s`` is
    honoured (OpenCV's ``projectPoints`` ignores ``K[0, 1]``).

    Parameters
    ----------
    points : array_like, shape (..., N, 3) or (..., 3)
        World points (camera frame when ``R`` and ``t`` are omitted).
    K : array_like, shape (..., 3, 3)
        Intrinsic matrix (positive focal lengths; checked).
    R : array_like, shape (..., 3, 3), optional
        World-to-camera rotation (orthonormal, det +1; checked).
    t : array_like, shape (..., 3), optional
        World-to-camera translation (camera frame = ``R X + t``).
    image_plane : {"virtual", "real"}
        ``"real"`` gives the inverted image of a camera obscura.

    Returns
    -------
    Projection
        ``uv`` ``(..., N, 2)`` with NaN where ``valid`` is False: points with ``z_cam <= 0``
        are never projected as if in front; points with NaN/inf coordinates, and finite
        points whose pixel coordinates overflow the dtype, are invalid too.

    Preconditions: ``K`` upper-triangular and non-singular. NumPy input of a single camera
    with more than 20 000 points runs a parallel numba kernel (same numbers); CUDA arrays of
    a single camera one CUDA kernel (:mod:`imageform._cuda.geometry`).

    Examples
    --------
    The lecture: P = (3, -1, 5) with f = 100 px (principal point at the origin).

    >>> uv, valid = project_points([3.0, -1.0, 5.0], [[100, 0, 0], [0, 100, 0], [0, 0, 1]])
    >>> uv, bool(valid)
    (array([ 60., -20.]), True)
    >>> project_points([0.0, 0.0, -1.0], [[100, 0, 0], [0, 100, 0], [0, 0, 1]]).uv
    array([nan, nan])
    """
    plane = check_option(image_plane, _PLANES, "image plane")
    xp, X, Km, Rm, tv = _prepare(points, K, R, t)
    Km = _plane_K(Km, plane, xp)
    if X.ndim == 2 and Km.ndim == 2 and Rm.ndim == 2 and tv.ndim == 1:
        from imageform._cuda import geometry as cuda_geometry

        if cuda_geometry.on_cuda(X, Km, Rm, tv):  # one CUDA kernel (pinhole)
            res = cuda_geometry.project(X, Km, Rm, tv, None)
            if res is not None:  # None: the kernels are unusable here
                return Projection(*res)
    if (
        X.ndim == 2
        and Km.ndim == 2
        and Rm.ndim == 2
        and tv.ndim == 1
        and X.shape[0] >= _KERNEL_MIN_POINTS
        and use_numba(X, Km, Rm, tv)
    ):
        from imageform._kernels.project import project_pinhole

        k = Km / Km[2, 2]
        return Projection(*project_pinhole(X, k, Rm, tv))
    return Projection(*_project_xp(X, Km, Rm, tv, xp, identity=R is None and t is None))


def projection_matrix(
    K: ArrayLike, R: ArrayLike | None = None, t: ArrayLike | None = None
) -> Array:
    """Build the 3×4 camera matrix ``P = K [R | t]``.

    P has 12 entries but is defined up to scale: 11 degrees of freedom (5 intrinsic: fx, fy,
    cx, cy, skew; 6 extrinsic: 3 rotation, 3 translation), Hartley & Zisserman §6.1.

    Examples
    --------
    >>> projection_matrix([[100, 0, 0], [0, 100, 0], [0, 0, 1]], t=[0, 0, 5])
    array([[100.,   0.,   0.,   0.],
           [  0., 100.,   0.,   0.],
           [  0.,   0.,   1.,   5.]])
    """
    xp = namespace(K, R, t)
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, device=common_device(K, R, t))
    dev = device_of(Km)
    Rm = (
        xp.eye(3, dtype=Km.dtype, device=dev)
        if R is None
        else as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=Km.dtype, device=dev)
    )
    if R is not None:
        check_rotation(Rm, "R", xp=xp)
    tv = (
        xp.zeros(3, dtype=Km.dtype, device=dev)
        if t is None
        else as_points_bounded(t, "t", 3, xp=xp, dtype=Km.dtype, device=dev)
    )
    batch = np.broadcast_shapes(tuple(Rm.shape[:-2]), tuple(tv.shape[:-1]))
    Rm = xp.broadcast_to(Rm, (*batch, 3, 3))
    tcol = xp.broadcast_to(tv[..., None], (*batch, 3, 1))
    Rt = xp.concat((Rm, tcol), axis=-1)
    return Km @ Rt


def decompose_projection_matrix(P: ArrayLike) -> DecomposedProjection:
    """Split ``P = λ K [R | t]`` into K (``K[2, 2] = 1``, positive focal lengths), R, t.

    RQ decomposition of the left 3×3 block ``M = K R`` (Hartley & Zisserman §6.2.4); the
    overall sign of P is chosen so that ``det R = +1``, then the signs of K's diagonal are
    made positive (``K D · D R`` with ``D = diag(±1)``), and ``t = K⁻¹ p₄ / λ``.

    Raises
    ------
    DegenerateConfigurationError
        If the left 3×3 block is singular (a camera at infinity, not a finite pinhole).

    Examples
    --------
    >>> P = projection_matrix([[500, 0, 320], [0, 500, 240], [0, 0, 1]], t=[1.0, 2.0, 3.0])
    >>> K, R, t = decompose_projection_matrix(2.0 * P)
    >>> K.round(9) + 0.0, t.round(9) + 0.0
    (array([[500.,   0., 320.],
           [  0., 500., 240.],
           [  0.,   0.,   1.]]), array([1., 2., 3.]))
    """
    xp = namespace(P)
    Pm = as_matrix_bounded(P, "P", (3, 4), xp=xp)
    M = Pm[..., :3]
    det = linalg(xp).det(M)
    scale = xp.max(xp.abs(M), axis=(-2, -1))
    if any_value(xp.abs(det) <= 1e-12 * scale**3, xp):
        raise DegenerateConfigurationError(
            "the left 3x3 block of P is singular: not a finite projective camera"
        )
    sgn = sign_of(det, xp)[..., None, None]
    Pm = Pm * sgn
    M = Pm[..., :3]
    # RQ via QR of the row-reversed transpose.
    Mf = xp.flip(M, axis=-2)
    Q, U = linalg(xp).qr(xp.matrix_transpose(Mf))
    Kq = xp.flip(xp.flip(xp.matrix_transpose(U), axis=-2), axis=-1)
    Rq = xp.flip(xp.matrix_transpose(Q), axis=-2)
    d = sign_of(xp.stack((Kq[..., 0, 0], Kq[..., 1, 1], Kq[..., 2, 2]), axis=-1), xp)
    Kq = Kq * d[..., None, :]
    Rq = Rq * d[..., :, None]
    lam = Kq[..., 2, 2]
    K = Kq / lam[..., None, None]
    t = linalg(xp).solve(Kq, Pm[..., 3:])[..., 0]
    # exact zeros below the diagonal (RQ leaves rounding there)
    mask = xp.asarray(
        [[1.0, 1.0, 1.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]], dtype=K.dtype, device=device_of(K)
    )
    return DecomposedProjection(K * mask + 0.0, Rq, t)  # + 0.0: no negative zeros


def _Kinv_apply(uv: Array, K: Array, xp: Any) -> Array:
    """``K⁻¹ (u, v, 1)`` for upper-triangular K, ``(..., 3)``."""
    k = K / K[..., 2:3, 2:3]
    fx, s, cx = k[..., 0, 0], k[..., 0, 1], k[..., 0, 2]
    fy, cy = k[..., 1, 1], k[..., 1, 2]
    if uv.ndim >= 2 and K.ndim > 2:
        fx, s, cx, fy, cy = (v[..., None] for v in (fx, s, cx, fy, cy))
    y = (uv[..., 1] - cy) / fy
    x = (uv[..., 0] - cx - s * y) / fx
    return xp.stack((x, y, xp.ones_like(x)), axis=-1)


def backproject(
    uv: ArrayLike, K: ArrayLike, R: ArrayLike | None = None, *, image_plane: ImagePlane = "virtual"
) -> Array:
    """Return unit ray directions through pixels, in the world frame (``Rᵀ K⁻¹ (u, v, 1)``).

    The ray starts at the camera centre ``C = -Rᵀ t`` (not needed here: directions only).

    Examples
    --------
    >>> backproject([320.0, 240.0], [[500, 0, 320], [0, 500, 240], [0, 0, 1]])
    array([0., 0., 1.])
    """
    plane = check_option(image_plane, _PLANES, "image plane")
    xp = namespace(uv, K, R)
    p = as_points_bounded(uv, "uv", 2, xp=xp, device=common_device(uv, K, R))
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=p.dtype, device=device_of(p))
    _check_K(Km, xp)
    Km = _plane_K(Km, plane, xp)
    d = _Kinv_apply(p, Km, xp)
    if R is not None:
        Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=p.dtype, device=device_of(p))
        check_rotation(Rm, "R", xp=xp)
        d = d @ Rm  # row vectors: (Rᵀ d)ᵀ = dᵀ R
    return d / xp.sqrt(xp.sum(d * d, axis=-1, keepdims=True))


def unproject(
    uv: ArrayLike,
    depth: ArrayLike,
    K: ArrayLike,
    R: ArrayLike | None = None,
    t: ArrayLike | None = None,
    *,
    image_plane: ImagePlane = "virtual",
) -> Array:
    """World points that image at ``uv`` with camera-frame depth ``z_cam = depth``.

    ``X_cam = depth · K⁻¹ (u, v, 1)``, ``X_world = Rᵀ (X_cam - t)``; the inverse of
    :func:`project_points` for ``depth > 0`` (checked).

    Examples
    --------
    >>> unproject([60.0, -20.0], 5.0, [[100, 0, 0], [0, 100, 0], [0, 0, 1]])
    array([ 3., -1.,  5.])
    """
    plane = check_option(image_plane, _PLANES, "image plane")
    xp = namespace(uv, depth, K, R, t)
    p = as_points_bounded(uv, "uv", 2, xp=xp, device=common_device(uv, depth, K, R, t))
    dev = device_of(p)
    z = as_float_bounded(depth, "depth", xp=xp, dtype=p.dtype, device=dev)
    try:
        np.broadcast_shapes(tuple(z.shape), tuple(p.shape[:-1]))
    except ValueError:
        raise InvalidInputError(
            f"expected depth broadcasting to uv's points {format_shape(tuple(p.shape[:-1]))}, "
            f"got shape {format_shape(tuple(z.shape))}"
        ) from None
    if any_value(~(z > 0), xp):
        raise InvalidInputError("expected depth > 0 (points in front of the camera)")
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=p.dtype, device=dev)
    _check_K(Km, xp)
    Km = _plane_K(Km, plane, xp)
    Xc = _Kinv_apply(p, Km, xp) * z[..., None]
    if t is not None:
        Xc = Xc - as_points_bounded(t, "t", 3, xp=xp, dtype=p.dtype, device=dev)
    if R is not None:
        Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=p.dtype, device=dev)
        check_rotation(Rm, "R", xp=xp)
        Xc = Xc @ Rm
    return Xc


def _identity_like(K: Array) -> Array:
    xp = namespace(K)
    return xp.eye(3, dtype=K.dtype, device=device_of(K))


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: intrinsics K, pose (R, t) world-to-camera, optional image size.

    ``X_cam = R @ X_world + t``; ``P = K [R | t]``. K's focal lengths must be positive
    (``fx, fy > 0`` after scaling ``K[2, 2]`` to 1; InvalidInputError otherwise). The
    methods call the public pure functions of this module. ``image_plane="real"`` models
    the camera obscura: the image behind the pinhole, inverted.

    Examples
    --------
    >>> cam = Camera(K=[[500, 0, 320], [0, 500, 240], [0, 0, 1]], t=[0, 0, 2])
    >>> cam.center
    array([ 0.,  0., -2.])
    >>> cam.project([[1.0, 0.0, 2.0], [0.0, 0.0, -3.0]])
    Projection(uv=array([[445., 240.],
           [ nan,  nan]]), valid=array([ True, False]))
    """

    K: Array  # 3x3 (an Intrinsics is accepted and converted)
    R: Array = field(default_factory=lambda: np.eye(3))
    t: Array = field(default_factory=lambda: np.zeros(3))
    image_size: tuple[int, int] | None = None
    image_plane: ImagePlane = "virtual"
    #: Lens distortion on normalised coordinates (BrownConrady, DivisionModel, KannalaBrandt).
    distortion: Any = None

    def __post_init__(self) -> None:
        """Check K, R, t, the image size and plane and the distortion model."""
        K = self.K.K if isinstance(self.K, Intrinsics) else self.K
        if isinstance(self.K, Intrinsics) and self.image_size is None:
            object.__setattr__(self, "image_size", self.K.image_size)
        xp = namespace(K, self.R, self.t)
        Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, batch=False)
        _check_K(Km, xp)
        fx, fy = float(Km[0, 0] / Km[2, 2]), float(Km[1, 1] / Km[2, 2])
        if not (fx > 0 and fy > 0):
            raise InvalidInputError(
                f"expected focal lengths fx > 0 and fy > 0 in K, got fx = {fx:g}, fy = {fy:g} "
                "(a negative focal length mirrors the image; the inverted image of a camera "
                "obscura is image_plane='real')"
            )
        Rm = as_matrix_bounded(self.R, "R", (3, 3), xp=xp, batch=False, dtype=Km.dtype)
        check_rotation(Rm, "R", xp=xp)
        tv = as_points_bounded(self.t, "t", 3, xp=xp, dtype=Km.dtype)
        if tv.ndim != 1:
            raise InvalidInputError(f"expected t of shape (3,), got {tuple(tv.shape)}")
        object.__setattr__(self, "K", Km / Km[2, 2])
        object.__setattr__(self, "R", Rm)
        object.__setattr__(self, "t", tv)
        object.__setattr__(
            self, "image_plane", check_option(self.image_plane, _PLANES, "image plane")
        )
        if self.image_size is not None:
            object.__setattr__(self, "image_size", check_image_size(self.image_size))
        if self.distortion is not None:
            from imageform.geometry.distortion import _check_model

            _check_model(self.distortion)
            if self.image_plane != "virtual":
                raise InvalidInputError("a distorted camera needs image_plane='virtual'")

    # -- constructors --------------------------------------------------------------------
    @classmethod
    def from_projection_matrix(
        cls, P: ArrayLike, image_size: tuple[int, int] | None = None
    ) -> Camera:
        """Camera of a finite 3×4 projection matrix (see :func:`decompose_projection_matrix`)."""
        K, R, t = decompose_projection_matrix(P)
        return cls(K, R, t, image_size)

    @classmethod
    def look_at(
        cls,
        K: ArrayLike | Intrinsics,
        eye: ArrayLike,
        target: ArrayLike,
        up: ArrayLike = (0.0, -1.0, 0.0),
        image_size: tuple[int, int] | None = None,
    ) -> Camera:
        """Place a camera at ``eye`` looking at ``target`` (:func:`~imageform.geometry.look_at`)."""
        from imageform.geometry.rotations import look_at

        R, t = look_at(eye, target, up)
        return cls(K, R, t, image_size)

    # -- properties ----------------------------------------------------------------------
    @property
    def intrinsics(self) -> Intrinsics:
        """K as an :class:`Intrinsics` (NumPy cameras)."""
        return Intrinsics.from_matrix(np.asarray(self.K), self.image_size)

    @property
    def center(self) -> Array:
        """Camera centre in the world, ``C = -Rᵀ t``."""
        xp = namespace(self.R, self.t)
        return 0.0 - xp.matrix_transpose(self.R) @ self.t  # 0.0 - x: no negative zeros

    @property
    def image_plane_K(self) -> Array:
        """The calibration matrix of the chosen image plane (3×3).

        ``K`` itself for ``image_plane="virtual"``; for ``"real"`` (behind the pinhole, the
        image inverted about the principal point: ``u' = cx - (fx x + s y)``,
        ``v' = cy - fy y``) K with fx, fy and s negated. ``P = image_plane_K [R | t]``.
        """
        return _plane_K(self.K, self.image_plane, namespace(self.K))

    @property
    def projection_matrix(self) -> Array:
        """``P = K [R | t]`` (3×4; for ``image_plane="real"`` the inverted image's K)."""
        return projection_matrix(self.image_plane_K, self.R, self.t)

    # -- maps ----------------------------------------------------------------------------
    def world_to_camera(self, points: ArrayLike) -> Array:
        """``X_cam = R X + t`` for points ``(..., 3)``."""
        xp = namespace(points, self.R)
        X = as_points_bounded(points, "points", 3, xp=xp)
        R = xp.asarray(self.R, dtype=X.dtype, device=device_of(X))
        return X @ xp.matrix_transpose(R) + xp.asarray(self.t, dtype=X.dtype, device=device_of(X))

    def project(self, points: ArrayLike) -> Projection:
        """Project world points; see :func:`project_points` (NaN + ``valid`` for z ≤ 0).

        With a ``distortion`` model the normalised coordinates are distorted before K
        (:func:`~imageform.geometry.project_points_distorted`).
        """
        if self.distortion is not None:
            from imageform.geometry.distortion import project_points_distorted

            return Projection(
                *project_points_distorted(points, self.K, self.R, self.t, self.distortion)
            )
        return project_points(points, self.K, self.R, self.t, image_plane=self.image_plane)

    def undistort_pixels(self, uv: ArrayLike) -> Array:
        """Ideal (undistorted) normalised coordinates ``(..., 2)`` of distorted pixels.

        NaN where the distortion model's inverse did not converge. Without a distortion
        model this is ``K⁻¹ (u, v, 1)``.
        """
        xp = namespace(uv, self.K)
        p = as_points_bounded(uv, "uv", 2, xp=xp)
        K = xp.asarray(self.K, dtype=p.dtype, device=device_of(p))
        xy = _Kinv_apply(p, K, xp)[..., :2]
        if self.distortion is None:
            return xy
        ideal, ok = self.distortion.undistort(xy)
        return xp.where(ok[..., None], ideal, float("nan"))

    def backproject(self, uv: ArrayLike) -> Array:
        """Return unit world-frame directions of rays through pixels ``uv`` (from ``center``)."""
        if self.distortion is not None:
            return backproject(self.undistort_pixels(uv), _identity_like(self.K), self.R)
        return backproject(uv, self.K, self.R, image_plane=self.image_plane)

    def unproject(self, uv: ArrayLike, depth: ArrayLike) -> Array:
        """World points imaged at ``uv`` with camera-frame depth ``depth`` (> 0)."""
        if self.distortion is not None:
            xy = self.undistort_pixels(uv)
            return unproject(xy, depth, _identity_like(self.K), self.R, self.t)
        return unproject(uv, depth, self.K, self.R, self.t, image_plane=self.image_plane)

    def in_image(self, uv: ArrayLike) -> Array:
        """Whether pixel coordinates fall inside the image (pixel-centre convention).

        Inside means ``-0.5 <= u < w - 0.5`` and ``-0.5 <= v < h - 0.5``; NaN is outside.
        """
        if self.image_size is None:
            raise InvalidInputError("in_image needs the camera's image_size")
        xp = namespace(uv)
        p = as_points_bounded(uv, "uv", 2, xp=xp, finite=False)
        w, h = self.image_size
        return (
            (p[..., 0] >= -0.5)
            & (p[..., 0] < w - 0.5)
            & (p[..., 1] >= -0.5)
            & (p[..., 1] < h - 0.5)
        )
