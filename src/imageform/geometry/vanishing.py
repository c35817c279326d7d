"""Vanishing points, the horizon, perspective type, and intrinsics from vanishing points.

Parallel scene lines with direction ``d`` (world frame) meet in the image at the vanishing
point ``v ~ K R d`` — independent of where the lines are (Hartley & Zisserman §8.6.1,
Result 8.20). A direction parallel to the image plane (``(R d)_z = 0``) vanishes at
infinity: it is returned as a homogeneous point with ``w = 0``, never divided by zero.
A plane with normal ``n`` has the vanishing line ``l ~ K⁻ᵀ R n`` (Result 8.22); the horizon
is the vanishing line of the ground plane, whose normal is the world's up direction.
"""

from __future__ import annotations

import math
from typing import Any

from imageform._backend import common_device, device_of, linalg, namespace, sign_of
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    any_value,
    as_float_bounded,
    as_matrix_bounded,
    as_points_bounded,
    as_real,
    check_rotation,
    describe,
    format_shape,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry.homogeneous import _normalize_homogeneous_point, line_through

__all__ = [
    "UP_AXES",
    "focal_from_vanishing_points",
    "horizon_line",
    "intrinsics_from_vanishing_points",
    "lines_from_segments",
    "perspective_type",
    "vanishing_point",
    "vanishing_point_from_lines",
]


def _k_r(
    K: ArrayLike, R: ArrayLike | None, xp: Any, dtype: Any = None, device: Any = None
) -> tuple[Array, Array]:
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=dtype, device=device)
    from imageform.geometry.camera import _check_K

    _check_K(Km, xp)
    if R is None:
        Rm = xp.eye(3, dtype=Km.dtype, device=device_of(Km))
    else:
        Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=Km.dtype, device=device_of(Km))
        check_rotation(Rm, "R", xp=xp)
    return Km, Rm


def vanishing_point(K: ArrayLike, direction: ArrayLike, R: ArrayLike | None = None) -> Array:
    """Vanishing point of the scene direction ``d``: ``v ~ K R d``, homogeneous ``(..., 3)``.

    Finite vanishing points are scaled to ``w = 1`` (so ``v[..., :2]`` are pixels); a
    direction parallel to the image plane gives a point at infinity ``(dx, dy, 0)`` with a
    unit image direction. ``d`` and ``-d`` give the same point.

    Parameters
    ----------
    K : array_like, shape (..., 3, 3)
        Intrinsic matrix.
    direction : array_like, shape (..., 3)
        Scene direction (world frame when ``R`` is given, else camera frame); not zero.
    R : array_like, shape (..., 3, 3), optional
        World-to-camera rotation; ``None``: ``direction`` is in the camera frame.

    Examples
    --------
    The lecture: K = [[500, 0, 320], [0, 500, 240], [0, 0, 1]], d = (1, 0, 2).

    >>> vanishing_point([[500, 0, 320], [0, 500, 240], [0, 0, 1]], [1, 0, 2])
    array([570., 240.,   1.])
    >>> vanishing_point([[500, 0, 320], [0, 500, 240], [0, 0, 1]], [1, 0, 0])
    array([1., 0., 0.])
    """
    xp = namespace(K, direction, R)
    d = as_points_bounded(direction, "direction", 3, xp=xp, device=common_device(K, direction, R))
    Km, Rm = _k_r(K, R, xp, d.dtype, device_of(d))
    if any_value(xp.sum(d * d, axis=-1) == 0, xp):
        raise InvalidInputError("expected a non-zero direction")
    dc = d @ xp.matrix_transpose(Rm) if d.ndim >= 1 else d
    v = dc @ xp.matrix_transpose(Km)
    return _normalize_homogeneous_point(v, xp, what="zero direction")


#: Axis names ``horizon_line``'s ``up`` accepts, and their unit vectors.
UP_AXES: dict[str, tuple[float, float, float]] = {
    "+x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}


def _up_vector(up: ArrayLike | str) -> ArrayLike:
    if not isinstance(up, str):
        return up
    key = up.strip().lower()
    key = key if key[:1] in "+-" else "+" + key
    if key not in UP_AXES:
        from imageform.errors import UnknownOptionError

        raise UnknownOptionError(
            f"unknown up axis {describe(up)}; valid: {', '.join(UP_AXES)} (or a 3-vector)"
        )
    return UP_AXES[key]


def horizon_line(K: ArrayLike, R: ArrayLike | None = None, up: ArrayLike | str = "-y") -> Array:
    """Return the horizon: vanishing line ``l ~ K⁻ᵀ R n`` of planes perpendicular to ``up``.

    Returned as ``(a, b, c)`` with ``a u + b v + c = 0``, normalised to ``a² + b² = 1``
    (then ``l · (u, v, 1)`` is a signed distance in pixels) and ``b >= 0`` (horizon of an
    upright camera: ``v = -(a u + c) / b``). A camera looking straight along ``up`` has its
    horizon at infinity: the line at infinity ``(0, 0, 1)`` is returned.

    A level camera's horizon passes through the principal point; tilting the camera up
    moves the horizon down the image (larger v).

    Parameters
    ----------
    K : array_like, shape (..., 3, 3)
        Intrinsic matrix.
    R : array_like, shape (..., 3, 3), optional
        World-to-camera rotation; ``None``: the world is the camera frame.
    up : str or array_like, shape (..., 3)
        The world's up direction, in world coordinates: an axis name (``"+z"``, ``"-y"``,
        ...; ``"z"`` is ``"+z"``) or a vector. imageform has no world frame of its own, so
        the default is the camera frame's up, ``"-y"`` (x right, y down, z forward), right
        when ``R`` is None or the world is y-down. A world with another up axis names it:
        the simulator's world is z-up (``imageform.simulate.WORLD_UP``, ``up="+z"``).

    Examples
    --------
    >>> K = [[500, 0, 320], [0, 500, 240], [0, 0, 1]]
    >>> horizon_line(K)            # level camera: v = 240
    array([   0.,    1., -240.])

    The same camera in a z-up world (looking along +y: rows of R are x, -z, y):

    >>> horizon_line(K, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], up="+z")
    array([   0.,    1., -240.])
    """
    up = _up_vector(up)
    xp = namespace(K, R, up)
    n = as_points_bounded(up, "up", 3, xp=xp, device=common_device(K, R, up))
    Km, Rm = _k_r(K, R, xp, n.dtype, device_of(n))
    if any_value(xp.sum(n * n, axis=-1) == 0, xp):
        raise InvalidInputError("expected a non-zero up direction")
    nc = n @ xp.matrix_transpose(Rm)
    # K^{-T} m for upper-triangular K: solve K^T l = m
    l = linalg(xp).solve(xp.matrix_transpose(Km), nc[..., None])[..., 0]
    ab = xp.sqrt(l[..., 0] ** 2 + l[..., 1] ** 2)
    scale = xp.sqrt(xp.sum(l * l, axis=-1))
    at_inf = ab <= 8 * xp.finfo(l.dtype).eps * scale
    ab_safe = xp.where(at_inf, 1.0, ab)
    sign = xp.where(l[..., 1] != 0, sign_of(l[..., 1], xp), sign_of(l[..., 0], xp))
    sign = xp.where(sign == 0, 1.0, sign)
    finite = l * (sign / ab_safe)[..., None]
    inf_line = xp.zeros_like(l) + xp.asarray([0.0, 0.0, 1.0], dtype=l.dtype, device=device_of(l))
    return xp.where(at_inf[..., None], inf_line, finite) + 0.0


def perspective_type(
    directions: ArrayLike, R: ArrayLike | None = None, *, tol: float = 1e-9
) -> int:
    """One-, two- or three-point perspective: how many scene directions vanish in the image.

    A direction has a finite vanishing point unless it is parallel to the image plane
    (``|(R d)_z| <= tol ‖d‖``). For a box-like scene with three orthogonal directions: a camera
    looking along one of them sees one-point perspective, one whose image plane is parallel
    to one of them (e.g. a level camera and vertical edges) two-point, any other three-point.

    Parameters
    ----------
    directions : array_like, shape (N, 3)
        Scene directions in the world frame (typically the three axes of a building or room).
    R : array_like, shape (3, 3), optional
        World-to-camera rotation.
    tol : float, keyword-only
        A direction with ``|d_z|`` (camera frame, unit length) at or below this is parallel to
        the image plane (its vanishing point is at infinity).

    Returns
    -------
    int
        The number of finite vanishing points (1, 2 or 3 for three independent directions).

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.geometry import camera_rotation
    >>> perspective_type(np.eye(3))                                   # looking down a corridor
    1
    >>> perspective_type(np.eye(3), camera_rotation(pitch=0.0, yaw=0.6))   # level, turned
    2
    >>> perspective_type(np.eye(3), camera_rotation(pitch=0.3, yaw=0.6))   # tilted up too
    3
    """
    xp = namespace(directions, R)
    D = as_points_bounded(directions, "directions", 3, xp=xp)
    if D.ndim != 2:
        raise InvalidInputError(f"expected directions of shape (N, 3), got {tuple(D.shape)}")
    Rm = (
        xp.eye(3, dtype=D.dtype, device=device_of(D))
        if R is None
        else as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=D.dtype, batch=False)
    )
    if R is not None:
        check_rotation(Rm, "R", xp=xp)
    tol = as_real(tol, "tol", nonnegative=True, maximum=1e6)
    norms = xp.sqrt(xp.sum(D * D, axis=-1))
    if any_value(norms == 0, xp):
        raise InvalidInputError("expected non-zero directions")
    dz = (D @ xp.matrix_transpose(Rm))[..., 2]
    return int(xp.sum(xp.astype(xp.abs(dz) > tol * norms, xp.int64)))


def _as_finite_vps(v: ArrayLike, name: str, xp: Any, like: Any = None, device: Any = None) -> Array:
    dtype = None if like is None else like.dtype
    dev = device_of(like) if like is not None else device
    p = as_points_bounded(v, name, (2, 3), xp=xp, dtype=dtype, device=dev)
    if p.shape[-1] == 3:
        if any_value(p[..., 2] == 0, xp):
            raise DegenerateConfigurationError(
                f"{name} is at infinity; this needs finite vanishing points"
            )
        p = p[..., :2] / p[..., 2:]
    return p


def focal_from_vanishing_points(v1: ArrayLike, v2: ArrayLike, principal_point: ArrayLike) -> Array:
    """Focal length (pixels) from the vanishing points of two orthogonal directions.

    With square pixels and zero skew, ``(v1 - p) · (v2 - p) = -f²`` for orthogonal
    directions (Hartley & Zisserman §8.8, from ``v1ᵀ ω v2 = 0``).

    Returns a 0-d (or batch) array of the inputs' namespace.

    Raises
    ------
    DegenerateConfigurationError
        If ``(v1 - p) · (v2 - p) >= 0``: the points cannot come from orthogonal directions
        seen by this principal point.

    Examples
    --------
    >>> float(focal_from_vanishing_points([820, 240], [-180, 240], [320, 240]))
    500.0
    """
    xp = namespace(v1, v2, principal_point)
    a = _as_finite_vps(v1, "v1", xp, device=common_device(v1, v2, principal_point))
    b = _as_finite_vps(v2, "v2", xp, a)
    p = as_points_bounded(
        principal_point, "principal_point", 2, xp=xp, dtype=a.dtype, device=device_of(a)
    )
    f2 = -xp.sum((a - p) * (b - p), axis=-1)
    if any_value(f2 <= 0, xp):
        raise DegenerateConfigurationError(
            "(v1 - p)·(v2 - p) >= 0: these vanishing points are not of orthogonal directions "
            "for this principal point"
        )
    return xp.sqrt(f2)


def intrinsics_from_vanishing_points(v1: ArrayLike, v2: ArrayLike, v3: ArrayLike) -> Array:
    """K (square pixels, zero skew) from the vanishing points of three orthogonal directions.

    The principal point is the orthocentre of the triangle ``v1 v2 v3`` and
    ``f² = -(v1 - p)·(v2 - p)`` (Caprile & Torre 1990; Hartley & Zisserman Example 8.27).
    The triangle must be acute (every angle < 90°). ``f`` is the root of the mean of the
    three estimates of ``f²``. Returns a ``(3, 3)`` array of the inputs' namespace.

    Raises
    ------
    DegenerateConfigurationError
        If a vanishing point is at infinity, the points are collinear, or the triangle is not
        acute.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.geometry import camera_rotation, vanishing_point
    >>> K = np.array([[800.0, 0, 640], [0, 800, 360], [0, 0, 1]])
    >>> R = camera_rotation(pitch=0.4, yaw=0.7)
    >>> vps = [vanishing_point(K, d, R) for d in np.eye(3)]
    >>> intrinsics_from_vanishing_points(*vps).round(6) + 0.0
    array([[800.,   0., 640.],
           [  0., 800., 360.],
           [  0.,   0.,   1.]])
    """
    xp = namespace(v1, v2, v3)
    a = _as_finite_vps(v1, "v1", xp, device=common_device(v1, v2, v3))
    b = _as_finite_vps(v2, "v2", xp, a)
    c = _as_finite_vps(v3, "v3", xp, a)
    if a.ndim != 1 or b.ndim != 1 or c.ndim != 1:
        raise InvalidInputError("expected three single vanishing points of shape (2,) or (3,)")
    # orthocentre: intersection of the altitudes from a and b, the 2x2 system
    # [c - b; c - a] p = [(c - b)·a; (c - a)·b] solved by Cramer's rule
    r1, r2 = c - b, c - a
    det = r1[0] * r2[1] - r1[1] * r2[0]
    norm2 = xp.sum(r1 * r1) + xp.sum(r2 * r2)
    if any_value(xp.abs(det) <= 1e-12 * norm2, xp):
        raise DegenerateConfigurationError("the three vanishing points v1, v2, v3 are collinear")
    s1, s2 = xp.sum(r1 * a), xp.sum(r2 * b)
    p = xp.stack([(s1 * r2[1] - r1[1] * s2) / det, (r1[0] * s2 - s1 * r2[0]) / det])
    f2 = xp.stack([-xp.sum((x - p) * (y - p)) for x, y in ((a, b), (b, c), (a, c))])
    if any_value(f2 <= 0, xp):
        raise DegenerateConfigurationError(
            "the triangle of vanishing points v1, v2, v3 is not acute: not three orthogonal "
            "directions"
        )
    f = xp.sqrt(xp.mean(f2))
    zero, one = xp.zeros_like(f), xp.ones_like(f)
    return xp.stack(
        [xp.stack([f, zero, p[0]]), xp.stack([zero, f, p[1]]), xp.stack([zero, zero, one])]
    )


def lines_from_segments(segments: ArrayLike) -> Array:
    """Homogeneous lines ``(..., N, 3)`` through segments ``(..., N, 2, 2)`` of ``(u, v)`` ends."""
    xp = namespace(segments)
    s = as_points_bounded(segments, "segments", 2, xp=xp)
    if s.ndim < 2 or s.shape[-2] != 2:
        raise InvalidInputError(f"expected segments of shape (..., 2, 2), got {tuple(s.shape)}")
    try:
        return line_through(s[..., 0, :], s[..., 1, :])
    except DegenerateConfigurationError:
        raise DegenerateConfigurationError(
            "segments holds a segment of zero length (its two ends coincide): no line through it"
        ) from None


def vanishing_point_from_lines(lines: ArrayLike, weights: ArrayLike | None = None) -> Array:
    """Least-squares vanishing point of many image lines, homogeneous ``(3,)``.

    Minimises ``Σ wᵢ (lᵢ · v)²`` over unit ``v`` (the smallest right singular vector of the
    stacked, normalised lines), after a similarity that centres and scales the lines'
    closest points to the origin (Hartley normalisation), so the answer does not depend on
    pixel units. With ``a² + b² = 1`` lines, ``lᵢ · v`` is the distance of a finite ``v``
    to line i. Finite results have ``w = 1``; near-parallel lines give ``w = 0``.

    Parameters
    ----------
    lines : array_like, shape (N, 3)
        N >= 2 lines ``(a, b, c)`` (e.g. from :func:`lines_from_segments`).
    weights : array_like, shape (N,), optional
        Non-negative weights (e.g. segment lengths).

    Examples
    --------
    >>> L = lines_from_segments([[[0, 0], [2, 1]], [[0, 2], [2, 2]], [[0, 4], [2, 3]]])
    >>> vanishing_point_from_lines(L).round(9) + 0.0
    array([4., 2., 1.])
    """
    xp = namespace(lines, weights)
    L = as_points_bounded(lines, "lines", 3, xp=xp)
    if L.ndim != 2 or L.shape[0] < 2:
        raise InvalidInputError(f"expected lines of shape (N, 3) with N >= 2, got {tuple(L.shape)}")
    ab = xp.sqrt(L[:, 0] ** 2 + L[:, 1] ** 2)
    if any_value(ab == 0, xp):
        raise InvalidInputError(
            "expected lines with (a, b) != (0, 0): a line at infinity has no direction"
        )
    L = L / ab[:, None]
    # closest points of each line to the origin: -c (a, b)
    foot = -L[:, 2:3] * L[:, :2]
    centre = xp.mean(foot, axis=0)
    spread = xp.mean(xp.sqrt(xp.sum((foot - centre) ** 2, axis=-1)))
    s = xp.where(spread > 0, spread / math.sqrt(2.0), 1.0)
    # point transform x' = (x - centre) / s  ->  line transform l' = T^{-T} l
    a, b, c = L[:, 0], L[:, 1], L[:, 2]
    c2 = (c + a * centre[0] + b * centre[1]) / s
    Ln = xp.stack((a, b, c2), axis=-1)
    if weights is not None:
        w = as_float_bounded(weights, "weights", xp=xp, dtype=L.dtype)
        w = xp.reshape(w, (-1,))
        if w.shape[0] != L.shape[0] or any_value(w < 0, xp):
            raise InvalidInputError(
                f"expected weights: one non-negative weight per line ({L.shape[0]}), got "
                f"shape {format_shape(tuple(w.shape))}"
            )
        Ln = Ln * xp.sqrt(w)[:, None]
    _, _, Vt = linalg(xp).svd(Ln, full_matrices=Ln.shape[0] < 3)  # 2 lines: need the full V
    vn = Vt[-1, :]
    v = xp.stack((vn[0] * s + centre[0] * vn[2], vn[1] * s + centre[1] * vn[2], vn[2]))
    return _normalize_homogeneous_point(v, xp, what="no vanishing point")
