"""Rotations: Euler angles with a named order, Rodrigues vectors, quaternions, look-at.

All functions are batched over leading dimensions and work on any Array-API array.
Rotation matrices map world to camera coordinates when used as a camera's ``R``
(``X_cam = R @ X_world + t``, docs/conventions.md). Angles are radians.

Euler orders follow SciPy's ``Rotation.from_euler`` spelling: lower-case ``"xyz"`` is
*extrinsic* (about the fixed axes x, then y, then z: ``R = Rz @ Ry @ Rx``), upper-case
``"XYZ"`` is *intrinsic* (about the moving axes: ``R = Rx @ Ry @ Rz``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

from imageform._backend import common_device, device_of, linalg, namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_float_bounded,
    as_matrix_bounded,
    as_points_bounded,
    as_real,
    check_rotation,
    describe,
    det3,
    format_shape,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "Pose",
    "axis_rotation",
    "camera_rotation",
    "euler_to_matrix",
    "is_rotation",
    "look_at",
    "matrix_to_euler",
    "matrix_to_quaternion",
    "matrix_to_rvec",
    "quaternion_to_matrix",
    "rvec_to_matrix",
]

_AXES = {"x": 0, "y": 1, "z": 2}


def _check_order(order: object) -> str:
    if (
        not isinstance(order, str)
        or len(order) != 3
        or not (order.islower() or order.isupper())
        or any(c.lower() not in _AXES for c in order)
        or order[0].lower() == order[1].lower()
        or order[1].lower() == order[2].lower()
    ):
        raise InvalidInputError(
            f"expected an Euler order of three axes from 'xyz' (lower-case extrinsic, "
            f"upper-case intrinsic, no axis twice in a row), e.g. 'xyz' or 'ZYX'; got "
            f"{describe(order)}"
        )
    return order


def axis_rotation(axis: str, angle: ArrayLike) -> Array:
    r"""Rotation by ``angle`` (radians) about the coordinate axis ``"x"``, ``"y"`` or ``"z"``.

    .. math::
        R_x(\theta) = \begin{pmatrix}1&0&0\\0&\cos\theta&-\sin\theta\\
        0&\sin\theta&\cos\theta\end{pmatrix}

    and cyclically for y and z (right-handed, counter-clockwise looking down the axis).

    Examples
    --------
    >>> axis_rotation("z", 0.5 * 3.141592653589793).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    if not isinstance(axis, str) or axis not in _AXES:
        raise InvalidInputError(f"expected axis 'x', 'y' or 'z', got {describe(axis)}")
    xp = namespace(angle)
    return _axis_rotation(_AXES[axis], _as_angle(angle, xp), xp)


def _as_angle(angle: ArrayLike, xp: Any, name: str = "angle") -> Array:
    return as_float_bounded(angle, name, xp=xp)


def _axis_rotation(i: int, a: Array, xp: Any) -> Array:
    c, s = xp.cos(a), xp.sin(a)
    one, zero = xp.ones_like(a), xp.zeros_like(a)
    if i == 0:
        rows = ((one, zero, zero), (zero, c, -s), (zero, s, c))
    elif i == 1:
        rows = ((c, zero, s), (zero, one, zero), (-s, zero, c))
    else:
        rows = ((c, -s, zero), (s, c, zero), (zero, zero, one))
    return xp.stack([xp.stack(r, axis=-1) for r in rows], axis=-2)


def euler_to_matrix(angles: ArrayLike, order: str) -> Array:
    """Rotation matrix from three Euler angles applied in the named ``order``.

    ``angles[..., i]`` is the angle about axis ``order[i]``. Extrinsic (lower-case):
    ``R = R_{order[2]} R_{order[1]} R_{order[0]}``; intrinsic (upper-case):
    ``R = R_{order[0]} R_{order[1]} R_{order[2]}``. Matches SciPy's
    ``Rotation.from_euler(order, angles).as_matrix()``.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        Radians.
    order : str
        e.g. ``"xyz"``, ``"ZYX"``, ``"zxz"``.

    Examples
    --------
    >>> R = euler_to_matrix([0.0, 0.0, 3.141592653589793 / 2], "xyz")
    >>> (R @ [1.0, 0.0, 0.0]).round(12) + 0.0
    array([0., 1., 0.])
    """
    order = _check_order(order)
    xp = namespace(angles)
    a = as_points_bounded(angles, "angles", 3, xp=xp)
    mats = [_axis_rotation(_AXES[c.lower()], a[..., i], xp) for i, c in enumerate(order)]
    if order.islower():
        return mats[2] @ mats[1] @ mats[0]
    return mats[0] @ mats[1] @ mats[2]


def matrix_to_euler(R: ArrayLike, order: str) -> Array:
    """Return the Euler angles ``(..., 3)`` of a rotation in the named order.

    The inverse of :func:`euler_to_matrix`.

    Tait–Bryan orders (three different axes) give the middle angle in ``[-π/2, π/2]``;
    proper Euler orders (``"zxz"`` ...) give it in ``[0, π]``. At gimbal lock the first
    angle is set to 0 and the third absorbs the rotation (documented convention).

    Examples
    --------
    >>> ang = matrix_to_euler(euler_to_matrix([0.1, -0.2, 0.3], "ZYX"), "ZYX")
    >>> ang.round(12)
    array([ 0.1, -0.2,  0.3])
    """
    order = _check_order(order)
    xp = namespace(R)
    M = as_matrix_bounded(R, "R", (3, 3), xp=xp)
    check_rotation(M, "R", xp=xp)
    intrinsic = order.isupper()
    seq = order.lower()
    if not intrinsic:  # extrinsic abc == intrinsic CBA with angles reversed
        seq = seq[::-1]
    i, j, k = (_AXES[c] for c in seq)
    if i == k:  # proper Euler: i j i
        k_ = 3 - i - j
        sgn = 1.0 if (i, j) in ((0, 1), (1, 2), (2, 0)) else -1.0
        b = xp.acos(xp.clip(M[..., i, i], -1.0, 1.0))
        sb = xp.sin(b)
        lock = xp.abs(sb) < 1e-9
        a = xp.atan2(M[..., j, i], -sgn * M[..., k_, i])
        c = xp.atan2(M[..., i, j], sgn * M[..., i, k_])
        # gimbal lock: a = 0, c takes the whole rotation about the (common) axis i
        c_lock = xp.atan2(sgn * M[..., k_, j], M[..., j, j])
        c_lock = xp.where(M[..., i, i] < 0, -c_lock, c_lock)
        a = xp.where(lock, xp.zeros_like(a), a)
        c = xp.where(lock, c_lock, c)
    else:  # Tait-Bryan: R = Ri(a) Rj(b) Rk(c)
        sgn = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
        sb = sgn * M[..., i, k]
        b = xp.asin(xp.clip(sb, -1.0, 1.0))
        lock = xp.abs(xp.abs(sb) - 1.0) < 1e-9
        a = xp.atan2(-sgn * M[..., j, k], M[..., k, k])
        c = xp.atan2(-sgn * M[..., i, j], M[..., i, i])
        c_lock = xp.atan2(sgn * M[..., k, j], M[..., j, j])
        a = xp.where(lock, xp.zeros_like(a), a)
        c = xp.where(lock, c_lock, c)
    out = xp.stack((a, b, c), axis=-1)
    if not intrinsic:
        out = xp.flip(out, axis=-1)
    return out


def camera_rotation(pitch: float, yaw: float = 0.0, roll: float = 0.0) -> Array:
    """World-to-camera rotation of a camera turned by the lecture's pitch, yaw and roll.

    A level camera (all angles 0) looks along world +z with world y pointing down, like the
    camera frame. The camera is first *yawed* about the vertical y axis (positive turns it
    to the right), then *pitched* about its new x axis (positive tilts it **up**), then
    *rolled* about its new optical axis z (positive turns the camera clockwise seen from
    behind it; the image content turns counter-clockwise). With y down, a rotation
    about x by a positive angle lifts the optical axis towards -y, i.e. up, so the camera's
    orientation is ``R_cw = R_y(yaw) R_x(pitch) R_z(roll)`` (intrinsic Y-X-Z) and the
    returned world-to-camera rotation is ``R = R_cwᵀ``.

    Examples
    --------
    >>> import numpy as np
    >>> R = camera_rotation(pitch=np.deg2rad(10))
    >>> (R.T @ [0.0, 0.0, 1.0]).round(4)   # optical axis in the world: up is -y
    array([ 0.    , -0.1736,  0.9848])
    """
    angles = [yaw, pitch, roll]
    xp = namespace(*angles)
    arrs = [_as_angle(v, xp, n) for v, n in zip(angles, ("yaw", "pitch", "roll"), strict=True)]
    shapes = {tuple(v.shape) for v in arrs}
    if len(shapes) != 1:
        raise InvalidInputError(
            "expected yaw, pitch and roll of one shape, got "
            + ", ".join(format_shape(tuple(v.shape)) for v in arrs)
        )
    a = xp.stack(arrs, axis=-1)
    return xp.matrix_transpose(euler_to_matrix(a, "YXZ"))


def rvec_to_matrix(rvec: ArrayLike) -> Array:
    r"""Rotation matrix from an axis-angle (Rodrigues) vector, as OpenCV's ``Rodrigues``.

    .. math:: R = I + \frac{\sin\theta}{\theta} [r]_\times
              + \frac{1 - \cos\theta}{\theta^2} [r]_\times^2, \quad \theta = \|r\|

    Small angles use the Taylor series of the coefficients (no division by zero).

    Examples
    --------
    >>> rvec_to_matrix([0.0, 0.0, 3.141592653589793 / 2]).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    xp = namespace(rvec)
    r = as_points_bounded(rvec, "rvec", 3, xp=xp)
    theta2 = xp.sum(r * r, axis=-1)
    theta = xp.sqrt(theta2)
    small = theta2 < 1e-8
    safe = xp.where(small, xp.ones_like(theta), theta)
    a = xp.where(small, 1.0 - theta2 / 6.0, xp.sin(safe) / safe)
    b = xp.where(small, 0.5 - theta2 / 24.0, (1.0 - xp.cos(safe)) / (safe * safe))
    K = _skew(r, xp)
    eye = xp.eye(3, dtype=r.dtype, device=device_of(r))
    return eye + a[..., None, None] * K + b[..., None, None] * (K @ K)


def _skew(v: Array, xp: Any) -> Array:
    z = xp.zeros_like(v[..., 0])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return xp.stack(
        (
            xp.stack((z, -w, y), axis=-1),
            xp.stack((w, z, -x), axis=-1),
            xp.stack((-y, x, z), axis=-1),
        ),
        axis=-2,
    )


def matrix_to_rvec(R: ArrayLike) -> Array:
    """Axis-angle (Rodrigues) vector of a rotation, ``‖r‖ = θ ∈ [0, π]``.

    Computed through the unit quaternion (robust for every angle, including θ near π, where
    the ``(R - Rᵀ)/2 sin θ`` formula breaks down).

    Examples
    --------
    >>> matrix_to_rvec(rvec_to_matrix([0.1, -0.2, 0.3])).round(12)
    array([ 0.1, -0.2,  0.3])
    """
    q = matrix_to_quaternion(R)
    xp = namespace(q)
    w = q[..., 0]
    v = q[..., 1:]
    s = xp.sqrt(xp.sum(v * v, axis=-1))
    theta = 2.0 * xp.atan2(s, w)
    small = s < 1e-8
    safe = xp.where(small, xp.ones_like(s), s)
    # theta / s -> 2 / w as s -> 0 (w = 1 there since w >= 0 by construction)
    factor = xp.where(small, 2.0 / xp.where(w == 0, xp.ones_like(w), w), theta / safe)
    return v * factor[..., None]


def quaternion_to_matrix(q: ArrayLike) -> Array:
    r"""Rotation matrix from a quaternion ``(w, x, y, z)`` (scalar first, Hamilton product).

    The quaternion is normalised first; a zero quaternion raises.

    .. math::
        R = \begin{pmatrix}
        1-2(y^2+z^2) & 2(xy-wz) & 2(xz+wy)\\
        2(xy+wz) & 1-2(x^2+z^2) & 2(yz-wx)\\
        2(xz-wy) & 2(yz+wx) & 1-2(x^2+y^2)\end{pmatrix}

    Examples
    --------
    >>> c = 2 ** -0.5
    >>> quaternion_to_matrix([c, 0.0, 0.0, c]).round(12) + 0.0   # 90° about z
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    xp = namespace(q)
    qq = as_points_bounded(q, "q (quaternion)", 4, xp=xp)
    n = xp.sqrt(xp.sum(qq * qq, axis=-1, keepdims=True))
    if any_value(n == 0, xp):
        raise InvalidInputError("q: a zero quaternion does not represent a rotation")
    qq = qq / n
    w, x, y, z = qq[..., 0], qq[..., 1], qq[..., 2], qq[..., 3]
    rows = (
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )
    return xp.stack([xp.stack(r, axis=-1) for r in rows], axis=-2)


def matrix_to_quaternion(R: ArrayLike) -> Array:
    """Return the unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of a rotation matrix.

    Shepperd's (1978) method: the largest of ``4w², 4x², 4y², 4z²`` picks the branch,
    so no branch divides by a small number.

    Examples
    --------
    >>> matrix_to_quaternion(rvec_to_matrix([0.0, 0.0, 3.141592653589793 / 2])).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    xp = namespace(R)
    M = as_matrix_bounded(R, "R", (3, 3), xp=xp)
    check_rotation(M, "R", xp=xp)
    m00, m11, m22 = M[..., 0, 0], M[..., 1, 1], M[..., 2, 2]
    tr = m00 + m11 + m22
    cands = xp.stack((tr, m00, m11, m22), axis=-1)
    best = xp.argmax(cands, axis=-1)

    # four branches, each well-conditioned where it is chosen
    def norm_sqrt(v: Array) -> Array:
        return xp.sqrt(xp.clip(v, 1e-300, None))

    s0 = 2.0 * norm_sqrt(1.0 + tr)
    q0 = xp.stack(
        (
            0.25 * s0,
            (M[..., 2, 1] - M[..., 1, 2]) / s0,
            (M[..., 0, 2] - M[..., 2, 0]) / s0,
            (M[..., 1, 0] - M[..., 0, 1]) / s0,
        ),
        axis=-1,
    )
    s1 = 2.0 * norm_sqrt(1.0 + m00 - m11 - m22)
    q1 = xp.stack(
        (
            (M[..., 2, 1] - M[..., 1, 2]) / s1,
            0.25 * s1,
            (M[..., 0, 1] + M[..., 1, 0]) / s1,
            (M[..., 0, 2] + M[..., 2, 0]) / s1,
        ),
        axis=-1,
    )
    s2 = 2.0 * norm_sqrt(1.0 + m11 - m00 - m22)
    q2 = xp.stack(
        (
            (M[..., 0, 2] - M[..., 2, 0]) / s2,
            (M[..., 0, 1] + M[..., 1, 0]) / s2,
            0.25 * s2,
            (M[..., 1, 2] + M[..., 2, 1]) / s2,
        ),
        axis=-1,
    )
    s3 = 2.0 * norm_sqrt(1.0 + m22 - m00 - m11)
    q3 = xp.stack(
        (
            (M[..., 1, 0] - M[..., 0, 1]) / s3,
            (M[..., 0, 2] + M[..., 2, 0]) / s3,
            (M[..., 1, 2] + M[..., 2, 1]) / s3,
            0.25 * s3,
        ),
        axis=-1,
    )
    b = best[..., None]
    q = xp.where(b == 0, q0, xp.where(b == 1, q1, xp.where(b == 2, q2, q3)))
    q = q / xp.sqrt(xp.sum(q * q, axis=-1, keepdims=True))
    return xp.where(q[..., :1] < 0, -q, q)


def is_rotation(R: ArrayLike, *, atol: float = 1e-6) -> Array:
    """Whether each matrix is a proper rotation: ``R Rᵀ = I`` and ``det R = +1`` within ``atol``.

    Examples
    --------
    >>> bool(is_rotation([[1.0, 0, 0], [0, 1, 0], [0, 0, -1]]))   # a reflection
    False
    """
    xp = namespace(R)
    M = as_matrix_bounded(R, "R", (3, 3), xp=xp)
    eye = xp.eye(3, dtype=M.dtype, device=device_of(M))
    atol = as_real(atol, "atol", nonnegative=True, maximum=1.0)
    orth = xp.max(xp.abs(M @ xp.matrix_transpose(M) - eye), axis=(-2, -1)) <= atol
    det = xp.abs(det3(M) - 1.0) <= max(atol, 10 * atol)
    return orth & det


class Pose(NamedTuple):
    """A world-to-camera pose, ``X_cam = R @ X_world + t`` (the result of :func:`look_at`)."""

    #: Rotation (..., 3, 3).
    R: Array
    #: Translation (..., 3).
    t: Array


def look_at(eye: ArrayLike, target: ArrayLike, up: ArrayLike = (0.0, -1.0, 0.0)) -> Pose:
    """World-to-camera ``(R, t)`` of a camera at ``eye`` looking at ``target``.

    The camera's z axis points from ``eye`` to ``target``; its y axis points *down*, i.e.
    opposite to the world ``up`` direction projected onto the image plane; x = y × z points
    right (camera frame of docs/conventions.md). ``t = -R @ eye``.

    The default ``up = (0, -1, 0)`` suits a world whose y axis points down like the camera's;
    for a z-up world pass ``up=(0, 0, 1)``.

    Raises
    ------
    DegenerateConfigurationError
        If ``eye == target`` or the viewing direction is parallel to ``up``.

    Examples
    --------
    >>> R, t = look_at([0.0, 0.0, -5.0], [0.0, 0.0, 0.0])
    >>> R + 0.0
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    >>> t + 0.0
    array([0., 0., 5.])
    """
    xp = namespace(eye, target, up)
    dev = common_device(eye, target, up)
    e = as_points_bounded(eye, "eye", 3, xp=xp, device=dev)
    tg = as_points_bounded(target, "target", 3, xp=xp, dtype=e.dtype, device=dev)
    u = as_points_bounded(up, "up", 3, xp=xp, dtype=e.dtype, device=dev)
    z = tg - e
    zn = xp.sqrt(xp.sum(z * z, axis=-1, keepdims=True))
    if any_value(zn == 0, xp):
        raise DegenerateConfigurationError("look_at: eye and target coincide")
    z = z / zn
    down = -u
    x = linalg(xp).cross(down, z)
    xn = xp.sqrt(xp.sum(x * x, axis=-1, keepdims=True))
    un = xp.sqrt(xp.sum(u * u, axis=-1, keepdims=True))
    if any_value(xn <= 1e-12 * un, xp):
        raise DegenerateConfigurationError(
            "look_at: the viewing direction is parallel to 'up'; choose another up vector"
        )
    x = x / xn
    y = linalg(xp).cross(z, x)
    R = xp.stack((x, y, z), axis=-2)
    t = -(R @ e[..., None])[..., 0]
    return Pose(R, t)
