"""Homogeneous coordinates, lines through points, intersections and the cross-ratio.

A point ``(x, y)`` is the homogeneous vector ``(x, y, 1)`` up to scale; ``w = 0`` is a point
at infinity (a direction). A line ``l = (a, b, c)`` holds the points with ``a x + b y + c = 0``.
The line through two points and the intersection of two lines are both cross products
(Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., Result 2.2 and 2.4).
"""

from __future__ import annotations

import functools
from typing import Any, Literal, NamedTuple

from imageform import _deprecate
from imageform._backend import common_device, linalg, namespace, sign_of
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    MAX_MAGNITUDE,
    any_value,
    as_float_bounded,
    as_points_bounded,
    as_real,
    check_bounded,
    check_option,
    shape_text,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "Dehomogenized",
    "are_collinear",
    "cross_ratio",
    "from_homogeneous",
    "from_homogeneous_masked",
    "intersect_lines",
    "line_through",
    "to_homogeneous",
]


def _any_dim(points: ArrayLike, name: str, n_min: int, xp: Any) -> Array:
    """Points ``(..., n)`` with ``n >= n_min`` (the shape checked before the values)."""
    p = as_float_bounded(points, name, xp=xp, finite=False)
    if p.ndim < 1 or not n_min <= p.shape[-1] <= 1 << 16:
        raise InvalidInputError(
            f"expected {name} of shape (..., n) with n >= {n_min}, got {shape_text(p)}"
        )
    check_bounded(p, name, xp)
    return p


def to_homogeneous(points: ArrayLike, w: float = 1.0) -> Array:
    """Append a homogeneous coordinate: ``(..., n)`` → ``(..., n + 1)``.

    Parameters
    ----------
    points : array_like, shape (..., n)
        Euclidean points (any n ≥ 1), or directions when ``w = 0``.
    w : float
        The appended coordinate; ``1`` for points, ``0`` for directions (points at infinity).

    Returns
    -------
    array, shape (..., n + 1)

    Examples
    --------
    >>> to_homogeneous([60.0, -20.0])
    array([ 60., -20.,   1.])
    """
    wv = as_real(w, "w", minimum=-MAX_MAGNITUDE, maximum=MAX_MAGNITUDE)
    xp = namespace(points)
    p = _any_dim(points, "points", 1, xp)
    ones = xp.full((*p.shape[:-1], 1), wv, dtype=p.dtype, device=getattr(p, "device", None))
    return xp.concat((p, ones), axis=-1)


class Dehomogenized(NamedTuple):
    """Result of :func:`from_homogeneous_masked`: Euclidean points and which are finite.

    ``points`` is ``(..., n)`` with NaN where ``valid`` is False (``w = 0``, at infinity).
    """

    points: Array
    valid: Array


def _dehomogenize(points: ArrayLike, at_infinity: str) -> Dehomogenized:
    check_option(at_infinity, ("raise", "nan"), "at_infinity policy")
    xp = namespace(points)
    p = _any_dim(points, "homogeneous points", 2, xp)
    w = p[..., -1:]
    finite = w[..., 0] != 0
    if at_infinity == "raise" and any_value(~finite, xp):
        n_inf = int(xp.sum(xp.astype(~finite, xp.int64)))
        raise DegenerateConfigurationError(
            f"{n_inf} of the points have w = 0 (at infinity) and no Euclidean coordinates; "
            "pass at_infinity='nan' to get NaN, or use from_homogeneous_masked for a mask"
        )
    safe_w = xp.where(w != 0, w, 1.0)
    out = p[..., :-1] / safe_w
    out = xp.where(w != 0, out, float("nan"))
    return Dehomogenized(out, finite)


def _return_mask_shim(fn: Any) -> Any:
    """``from_homogeneous(..., return_mask=True)`` (deprecated) -> from_homogeneous_masked."""

    @functools.wraps(fn)
    def wrapper(points: ArrayLike, **kwargs: Any) -> Any:
        if "return_mask" in kwargs:
            flag = kwargs.pop("return_mask")
            _deprecate.warn(
                "imageform.geometry.from_homogeneous(return_mask=...)",
                "use from_homogeneous_masked(points) for (points, valid), "
                "from_homogeneous(points, at_infinity='nan') for the points alone",
            )
            if flag:
                return _dehomogenize(points, kwargs.get("at_infinity", "raise"))
        return fn(points, **kwargs)

    return wrapper


@_return_mask_shim
def from_homogeneous(
    points: ArrayLike,
    *,
    at_infinity: Literal["raise", "nan"] = "raise",
) -> Array:
    r"""Divide by the last coordinate: ``(..., n + 1)`` → ``(..., n)``.

    .. math:: (x_1, \dots, x_n, w) \mapsto (x_1 / w, \dots, x_n / w)

    A point with ``w = 0`` lies at infinity and has no Euclidean coordinates. It is never
    divided by zero silently: ``at_infinity="raise"`` (default) raises
    :class:`~imageform.errors.DegenerateConfigurationError`; ``at_infinity="nan"`` returns NaN
    for those points. :func:`from_homogeneous_masked` also returns the mask of finite points.

    Parameters
    ----------
    points : array_like, shape (..., n + 1)
        Homogeneous coordinates, the last one the scale ``w``.
    at_infinity : {"raise", "nan"}
        What a point at infinity (``w = 0``) gives: an error, or NaN coordinates.

    Returns
    -------
    array, shape (..., n)

    Examples
    --------
    >>> from_homogeneous([1140.0, 480.0, 2.0])
    array([570., 240.])
    >>> from_homogeneous([[1.0, 0.0, 0.0], [2.0, 4.0, 2.0]], at_infinity="nan")
    array([[nan, nan],
           [ 1.,  2.]])
    """
    return _dehomogenize(points, at_infinity).points


def from_homogeneous_masked(points: ArrayLike) -> Dehomogenized:
    r"""Divide by the last coordinate and say which points are finite.

    .. math:: (x_1, \dots, x_n, w) \mapsto (x_1 / w, \dots, x_n / w), \quad
        \mathrm{valid} = (w \ne 0)

    Points at infinity (``w = 0``) come back as NaN with ``valid`` False, never divided by
    zero.

    Parameters
    ----------
    points : array_like, shape (..., n + 1)
        Homogeneous coordinates, the last one the scale ``w``.

    Returns
    -------
    Dehomogenized
        ``points`` (..., n) and ``valid`` (...) bool.

    Examples
    --------
    >>> p, valid = from_homogeneous_masked([[1.0, 2.0, 0.0], [2.0, 4.0, 2.0]])
    >>> p.tolist(), valid.tolist()
    ([[nan, nan], [1.0, 2.0]], [False, True])
    """
    return _dehomogenize(points, "nan")


def _homog2(points: ArrayLike, name: str, xp: Any, device: Any = None) -> Array:
    """2-D points (..., 2) or homogeneous (..., 3) as homogeneous (..., 3)."""
    p = as_points_bounded(points, name, (2, 3), xp=xp, device=device)
    if p.shape[-1] == 2:
        ones = xp.ones((*p.shape[:-1], 1), dtype=p.dtype, device=getattr(p, "device", None))
        p = xp.concat((p, ones), axis=-1)
    return p


def line_through(p: ArrayLike, q: ArrayLike) -> Array:
    """Return the line through two image points, ``l = p × q``, normalised so ``a² + b² = 1``.

    Points are ``(..., 2)`` Euclidean or ``(..., 3)`` homogeneous (a point at infinity gives
    the line through ``p`` in that direction). With the normalisation, ``l · (x, y, 1)`` is
    the signed distance of ``(x, y)`` from the line. (Hartley & Zisserman, Result 2.4.)

    Raises
    ------
    DegenerateConfigurationError
        If ``p`` and ``q`` coincide (no unique line).

    Examples
    --------
    >>> line_through([0.0, 1.0], [1.0, 1.0])   # the line y = 1
    array([ 0.,  1., -1.])
    """
    xp = namespace(p, q)
    dev = common_device(p, q)
    hp, hq = _homog2(p, "p", xp, dev), _homog2(q, "q", xp, dev)
    hp, hq = xp.broadcast_arrays(hp, hq)
    line = linalg(xp).cross(hp, hq)
    norm = xp.sqrt(line[..., 0] ** 2 + line[..., 1] ** 2)
    if any_value(norm == 0, xp):
        raise DegenerateConfigurationError(
            "the two points p and q coincide: no unique line through them"
        )
    line = line / norm[..., None]
    # Fix the sign so the representation is unique: first non-zero of (a, b) positive.
    sign = xp.where(line[..., 0] != 0, sign_of(line[..., 0], xp), sign_of(line[..., 1], xp))
    return line * sign[..., None]


def intersect_lines(l1: ArrayLike, l2: ArrayLike) -> Array:
    """Intersection of two lines, ``x = l1 × l2``, in homogeneous form ``(..., 3)``.

    Parallel lines meet at a point at infinity (``w = 0``), returned as such and normalised
    to a unit direction; finite intersections are normalised to ``w = 1``.
    (Hartley & Zisserman, Result 2.2.)

    Raises
    ------
    DegenerateConfigurationError
        If the two lines are the same line.

    Examples
    --------
    >>> intersect_lines([1.0, 0.0, -2.0], [0.0, 1.0, -3.0])   # x = 2 and y = 3
    array([2., 3., 1.])
    >>> intersect_lines([0.0, 1.0, 0.0], [0.0, 1.0, -1.0])    # two horizontals
    array([1., 0., 0.])
    """
    xp = namespace(l1, l2)
    dev = common_device(l1, l2)
    a = as_points_bounded(l1, "l1", 3, xp=xp, device=dev)
    b = as_points_bounded(l2, "l2", 3, xp=xp, device=dev)
    a, b = xp.broadcast_arrays(a, b)
    x = linalg(xp).cross(a, b)
    return _normalize_homogeneous_point(x, xp, what="the two lines l1 and l2 are identical")


def _normalize_homogeneous_point(x: Array, xp: Any, *, what: str) -> Array:
    """Scale to ``w = 1`` where finite, to a unit direction (sign-fixed) where ``w = 0``."""
    norm = xp.sqrt(xp.sum(x * x, axis=-1))
    if any_value(norm == 0, xp):
        raise DegenerateConfigurationError(what)
    # Relative test: w is "zero" when it is at rounding level compared with (x, y).
    tiny = xp.abs(x[..., 2]) <= 8 * xp.finfo(x.dtype).eps * norm
    w = xp.where(tiny, 1.0, x[..., 2])
    finite_pt = x / w[..., None]
    dnorm = xp.sqrt(x[..., 0] ** 2 + x[..., 1] ** 2)
    dnorm = xp.where(dnorm == 0, 1.0, dnorm)
    sign = xp.where(x[..., 0] != 0, sign_of(x[..., 0], xp), sign_of(x[..., 1], xp))
    ideal = xp.stack(
        (x[..., 0] * sign / dnorm, x[..., 1] * sign / dnorm, xp.zeros_like(dnorm)), axis=-1
    )
    ideal = ideal + 0.0  # no negative zeros in the output
    return xp.where(tiny[..., None], ideal, finite_pt)


def are_collinear(points: ArrayLike, *, tol: float = 1e-9) -> Array:
    """Whether the points of each set lie on one line.

    Points ``(..., N, 2)`` are collinear when the smallest singular value of the centred
    ``N × 2`` matrix is at most ``tol`` times the largest (scale-free). Three points
    ``(..., 3, 2)`` use the determinant of their homogeneous 3×3 matrix, the lecture's test
    ``det[p1 p2 p3] = 0``, relative to the triangle's scale.

    Returns
    -------
    bool array, shape (...)

    Examples
    --------
    >>> bool(are_collinear([[0.0, 0.0], [1.0, 1.0], [3.0, 3.0]]))
    True
    >>> bool(are_collinear([[0.0, 0.0], [1.0, 1.0], [3.0, 3.1]]))
    False
    """
    tol = as_real(tol, "tol", nonnegative=True, maximum=1e6)
    xp = namespace(points)
    p = as_points_bounded(points, "points", 2, xp=xp)
    if p.ndim < 2 or p.shape[-2] < 2:
        raise InvalidInputError(
            f"expected points of shape (..., N, 2) with N >= 2, got {tuple(p.shape)}"
        )
    centred = p - xp.mean(p, axis=-2, keepdims=True)
    s = linalg(xp).svdvals(centred)
    return s[..., -1] <= tol * xp.where(s[..., 0] == 0, 1.0, s[..., 0])


def cross_ratio(a: ArrayLike, b: ArrayLike, c: ArrayLike, d: ArrayLike) -> Array:
    r"""Cross-ratio of four collinear points, invariant under any projective transformation.

    .. math:: \mathrm{CR}(a, b; c, d) = \frac{|ac| \, |bd|}{|bc| \, |ad|}

    with signed distances along the common line (Hartley & Zisserman §2.5, eq. 2.18 in the
    ``{x1, x2; x3, x4}`` form with ``|x_i x_j| = det[x_i, x_j]`` of 2-vectors). Points are
    ``(..., 2)``; collinearity is the caller's precondition and is checked.

    Examples
    --------
    >>> float(cross_ratio([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]))
    1.3333333333333333
    """
    xp = namespace(a, b, c, d)
    dev = common_device(a, b, c, d)
    pa, pb, pc, pd = (
        as_points_bounded(v, n, 2, xp=xp, device=dev)
        for v, n in zip((a, b, c, d), "abcd", strict=True)
    )
    pa, pb, pc, pd = xp.broadcast_arrays(pa, pb, pc, pd)
    stacked = xp.stack((pa, pb, pc, pd), axis=-2)
    if any_value(~are_collinear(stacked, tol=1e-6), xp):
        raise DegenerateConfigurationError(
            "cross_ratio needs four collinear points a, b, c, d; they are not collinear"
        )
    # Signed positions along the unit direction from a to d (a = d leaves it undefined).
    dvec = pd - pa
    dnorm = xp.sqrt(xp.sum(dvec * dvec, axis=-1, keepdims=True))
    if any_value(dnorm == 0, xp):
        raise DegenerateConfigurationError("cross_ratio is undefined: a = d")
    t = xp.sum((stacked - pa[..., None, :]) * (dvec / dnorm)[..., None, :], axis=-1)
    ta, tb, tc, td = t[..., 0], t[..., 1], t[..., 2], t[..., 3]
    den = (tc - tb) * (td - ta)
    if any_value(den == 0, xp):
        raise DegenerateConfigurationError("cross_ratio is undefined: b = c")
    return ((tc - ta) * (td - tb)) / den
