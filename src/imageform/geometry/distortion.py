"""Lens distortion models on normalised image coordinates, and projection with distortion.

All models act on normalised image coordinates ``(x, y) = (X/Z, Y/Z)`` of shape ``(..., 2)``,
as OpenCV does: ``distort`` maps ideal (pinhole) coordinates to distorted ones, ``undistort``
inverts it, iteratively where no closed form exists, with ``max_iter`` and ``tol``, and
returns :class:`Undistorted` ``(xy, valid)``: ``valid`` marks the points that converged (the
others come back as NaN, never as a silent best guess).

- :class:`BrownConrady` — radial ``k1, k2, k3`` (optionally rational ``k4, k5, k6``) and
  tangential ``p1, p2`` (Brown 1966; Conrady 1919; OpenCV's ``calib3d`` model and order).
- :class:`DivisionModel` — ``x_u = x_d / (1 + k1 r_d² + k2 r_d⁴)`` (Fitzgibbon 2001).
- :class:`KannalaBrandt` — the equidistant fisheye polynomial ``θ_d = θ (1 + k1 θ² + …)``
  (Kannala & Brandt 2006; OpenCV's ``cv::fisheye``).

Barrel distortion (``k1 < 0`` for Brown-Conrady) pulls points towards the centre;
pincushion (``k1 > 0``) pushes them out.

Functions are Array-API generic (NumPy, PyTorch, array-api-strict ...); NumPy inputs of at
least :data:`NUMBA_MIN_POINTS` points run numba kernels from
:mod:`imageform._kernels.distortion`.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass
from typing import Any, NamedTuple

import numpy as np

from imageform._backend import common_device, namespace, to_numpy, use_numba
from imageform._dask import is_dask_array
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_float_bounded,
    as_int,
    as_matrix_bounded,
    as_points_bounded,
    as_real,
    check_rotation,
)
from imageform.errors import InvalidInputError
from imageform.geometry._distortion_xp import (
    bc_distort_xp,
    bc_undistort_xp,
    default_tol,
    division_distort_xp,
    division_undistort_xp,
    kb_distort_xp,
    kb_undistort_xp,
)
from imageform.geometry._results import Projection

__all__ = [
    "NUMBA_MIN_POINTS",
    "BrownConrady",
    "DistortionModel",
    "DivisionModel",
    "KannalaBrandt",
    "Undistorted",
    "project_points_distorted",
]

#: NumPy inputs with at least this many points use the numba kernels.
NUMBA_MIN_POINTS = 4096

DistortionModel = Any  # BrownConrady | DivisionModel | KannalaBrandt (structural)


class Undistorted(NamedTuple):
    """Result of ``undistort``: ideal coordinates and which of them are trustworthy.

    ``xy`` is ``(..., 2)`` with NaN where ``valid`` is False (the inverse did not converge,
    or the model is not invertible there).
    """

    xy: Any
    valid: Any


def _dask_in(xy: Any) -> tuple[Any, Any]:
    """Dask points checked for shape ``(..., 2)`` (values are checked per chunk)."""
    if xy.ndim < 1 or int(xy.shape[-1]) != 2:
        raise InvalidInputError(f"expected xy of shape (..., 2), got {tuple(xy.shape)}")
    dtype = np.float32 if xy.dtype == np.float32 else np.float64
    return xy.rechunk({xy.ndim - 1: -1}), dtype


def _dask_points(fn: Any, xy: Any) -> Any:
    """``fn`` (NumPy ``(..., 2)`` -> ``(..., 2)``) chunk-wise on Dask points."""
    xy, dtype = _dask_in(xy)
    return xy.map_blocks(fn, dtype=dtype)


def _dask_pair(fn: Any, xy: Any) -> Undistorted:
    """``fn`` (NumPy -> ``(points (..., 2), mask (...))``) chunk-wise on Dask points."""
    xy, dtype = _dask_in(xy)
    pts = xy.map_blocks(lambda b: fn(b)[0], dtype=dtype)
    ok = xy.map_blocks(lambda b: fn(b)[1], drop_axis=xy.ndim - 1, dtype=bool)
    return Undistorted(pts, ok)


def _check_coeffs(obj: Any) -> None:
    for name, v in zip(obj.__dataclass_fields__, astuple(obj), strict=True):
        # |k| <= 1e6: a larger coefficient has no lens behind it, and r^6 k overflows
        as_real(v, name, minimum=-1e6, maximum=1e6)


def _iter_args(max_iter: int, tol: float | None, xp: Any, dtype: Any) -> tuple[int, float]:
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    t = default_tol(xp, dtype) if tol is None else as_real(tol, "tol", positive=True, maximum=1.0)
    return int(max_iter), t


def _cuda_geometry() -> Any:
    """:mod:`imageform._cuda.geometry` (imports no GPU library by itself)."""
    from imageform._cuda import geometry

    return geometry


def _numba_points(kernel: str, xy: Any, coeffs: tuple[float, ...], *newton: Any) -> Any:
    """Run the points kernel ``kernel`` of :mod:`imageform._kernels.distortion` on NumPy ``xy``.

    ``newton``: none for a forward model (the distorted points come back), ``(max_iter, tol)``
    for an inverse (:class:`Undistorted`, with the kernel's convergence flags).
    """
    from imageform._kernels import distortion as kernels

    shape = tuple(xy.shape)
    flat = np.ascontiguousarray(np.asarray(xy).reshape(-1, 2))
    out = np.empty_like(flat)
    run = getattr(kernels, kernel)
    if not newton:
        run(flat, np.asarray(coeffs), out)
        return out.reshape(shape)
    ok = np.empty(flat.shape[0], dtype=np.bool_)
    run(flat, np.asarray(coeffs), *newton, out, ok)
    return Undistorted(out.reshape(shape), ok.reshape(shape[:-1]))


@dataclass(frozen=True)
class BrownConrady:
    r"""Brown-Conrady radial-tangential distortion, OpenCV's order and rational extension.

    .. math::

        r^2 = x^2 + y^2, \quad
        \rho = \frac{1 + k_1 r^2 + k_2 r^4 + k_3 r^6}{1 + k_4 r^2 + k_5 r^4 + k_6 r^6}

        x_d = x\rho + 2 p_1 x y + p_2 (r^2 + 2x^2), \quad
        y_d = y\rho + p_1 (r^2 + 2y^2) + 2 p_2 x y

    Source: D. C. Brown, "Decentering distortion of lenses", Photogramm. Eng. 32 (1966);
    OpenCV ``calib3d`` documentation (``distCoeffs = (k1, k2, p1, p2, k3, k4, k5, k6)``).
    ``k1 < 0`` is barrel distortion, ``k1 > 0`` pincushion.

    Examples
    --------
    >>> BrownConrady(k1=-0.2).distort([0.5, 0.0]).round(6).tolist()
    [0.475, 0.0]
    """

    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    k3: float = 0.0
    k4: float = 0.0
    k5: float = 0.0
    k6: float = 0.0

    def __post_init__(self) -> None:
        """Check that every coefficient is a real within ±1e6."""
        _check_coeffs(self)

    @property
    def coeffs(self) -> tuple[float, ...]:
        """``(k1, k2, p1, p2, k3, k4, k5, k6)`` as floats (OpenCV's ``distCoeffs`` order)."""
        # the fields read directly: dataclasses.astuple deep-copies each one (a dozen Python
        # calls in every distortion call on a GPU, whose host time is the call's)
        return (
            float(self.k1),
            float(self.k2),
            float(self.p1),
            float(self.p2),
            float(self.k3),
            float(self.k4),
            float(self.k5),
            float(self.k6),
        )

    @classmethod
    def from_opencv(cls, dist_coeffs: ArrayLike) -> BrownConrady:
        """From OpenCV's 4, 5 or 8 ``distCoeffs`` ``(k1, k2, p1, p2[, k3[, k4, k5, k6]])``."""
        d = np.asarray(
            to_numpy(as_float_bounded(dist_coeffs, "dist_coeffs", xp=np, dtype=np.float64)),
            dtype=np.float64,
        ).ravel()
        if d.size not in (4, 5, 8):
            raise InvalidInputError(
                f"expected dist_coeffs as 4, 5 or 8 OpenCV distortion coefficients, got {d.size}"
            )
        return cls(*(float(v) for v in d))

    def distort(self, xy: ArrayLike) -> Array:
        """Distort ideal normalised coordinates ``(..., 2)``; see the class docstring."""
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_points(lambda b: self.distort(b), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        if _cuda_geometry().on_cuda(arr):  # one fused CUDA kernel (imageform._cuda.geometry)
            out = _cuda_geometry().distort(xp.reshape(arr, (-1, 2)), self.coeffs)
            if out is not None:  # None: the kernels are unusable here
                return xp.reshape(out, tuple(arr.shape))
        if use_numba(arr, min_size=2 * NUMBA_MIN_POINTS):
            return _numba_points("brown_conrady_distort", arr, self.coeffs)
        return bc_distort_xp(arr, self.coeffs, xp)

    def undistort(self, xy: ArrayLike, max_iter: int = 20, tol: float | None = None) -> Undistorted:
        """Invert :meth:`distort` by Newton's method: :class:`Undistorted` ``(xy, valid)``.

        Starts from ``x = x_d`` and stops when ``|distort(x) - x_d| <= tol (1 + |x_d|)`` in
        both coordinates (``tol`` defaults to 64 ulp of the dtype). A point is *valid* (converged)
        only if, in addition, the Jacobian of the model is positive there (the model is
        invertible at the solution, inside its valid radius); other points are NaN.

        Examples
        --------
        >>> xy, ok = BrownConrady(k1=-0.2).undistort([0.475, 0.0])
        >>> round(float(xy[0]), 12), bool(ok)
        (0.5, True)
        """
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_pair(lambda b: self.undistort(b, max_iter, tol), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        it, t = _iter_args(max_iter, tol, xp, arr.dtype)
        if _cuda_geometry().on_cuda(arr):  # one CUDA kernel, at most max_iter Newton steps
            shape = tuple(arr.shape)
            res = _cuda_geometry().undistort(xp.reshape(arr, (-1, 2)), self.coeffs, it, t)
            if res is not None:  # None: the kernels are unusable here
                return Undistorted(xp.reshape(res[0], shape), xp.reshape(res[1], shape[:-1]))
        if use_numba(arr, min_size=2 * NUMBA_MIN_POINTS):
            return _numba_points("brown_conrady_undistort", arr, self.coeffs, it, t)
        return Undistorted(*bc_undistort_xp(arr, self.coeffs, xp, it, t))


@dataclass(frozen=True)
class DivisionModel:
    r"""Fitzgibbon's division model, with an optional second coefficient.

    .. math::

        \mathbf{x}_u = \frac{\mathbf{x}_d}{1 + k_1 r_d^2 + k_2 r_d^4}, \quad
        r_d = \lVert \mathbf{x}_d \rVert

    Undistortion is closed form; distortion solves ``r_d = r_u (1 + k1 r_d² + k2 r_d⁴)``
    for the root on the branch continuous with the centre (NaN where none exists, e.g.
    ``1 - 4 k1 r_u² < 0`` for ``k2 = 0``). ``k1 < 0`` is barrel distortion.
    Source: A. W. Fitzgibbon, "Simultaneous linear estimation of multiple view geometry
    and lens distortion", CVPR 2001, eq. (3).

    Examples
    --------
    >>> xy, ok = DivisionModel(k1=-0.2).undistort([0.5, 0.0])
    >>> round(float(xy[0]), 6)
    0.526316
    """

    k1: float = 0.0
    k2: float = 0.0

    def __post_init__(self) -> None:
        """Check that every coefficient is a real within ±1e6."""
        _check_coeffs(self)

    @property
    def coeffs(self) -> tuple[float, ...]:
        """``(k1, k2)`` as floats."""
        return (float(self.k1), float(self.k2))

    def distort(self, xy: ArrayLike, max_iter: int = 30, tol: float | None = None) -> Array:
        """Distort ideal coordinates ``(..., 2)``; NaN where no distorted point exists."""
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_points(lambda b: self.distort(b, max_iter, tol), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        it, t = _iter_args(max_iter, tol, xp, arr.dtype)
        out, _ = division_distort_xp(arr, self.coeffs, xp, it, t)
        return out

    def undistort(self, xy: ArrayLike, max_iter: int = 30, tol: float | None = None) -> Undistorted:
        """Closed-form undistortion; ``valid`` is False where ``1 + k1 r² + k2 r⁴ <= 0``.

        ``max_iter`` and ``tol`` are accepted for a uniform interface and unused.
        """
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_pair(lambda b: self.undistort(b, max_iter, tol), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        _iter_args(max_iter, tol, xp, arr.dtype)
        return Undistorted(*division_undistort_xp(arr, self.coeffs, xp))


@dataclass(frozen=True)
class KannalaBrandt:
    r"""Kannala-Brandt fisheye model (OpenCV ``cv::fisheye``).

    .. math::

        r = \lVert (x, y) \rVert,\ \theta = \arctan r,\
        \theta_d = \theta (1 + k_1\theta^2 + k_2\theta^4 + k_3\theta^6 + k_4\theta^8),\
        (x_d, y_d) = \frac{\theta_d}{r} (x, y)

    Source: J. Kannala and S. S. Brandt, "A generic camera model and calibration method for
    conventional, wide-angle, and fish-eye lenses", IEEE TPAMI 28(8), 2006, eq. (6);
    OpenCV fisheye module documentation. Undistortion solves for ``θ`` by Newton's method
    and is valid only for ``0 <= θ < π/2`` where the polynomial increases.

    Examples
    --------
    >>> KannalaBrandt().distort([1.0, 0.0]).round(6).tolist()  # θ_d = atan(1) = π/4
    [0.785398, 0.0]
    """

    k1: float = 0.0
    k2: float = 0.0
    k3: float = 0.0
    k4: float = 0.0

    def __post_init__(self) -> None:
        """Check that every coefficient is a real within ±1e6."""
        _check_coeffs(self)

    @property
    def coeffs(self) -> tuple[float, ...]:
        """``(k1, k2, k3, k4)`` as floats (the order of OpenCV fisheye coefficients)."""
        return tuple(float(v) for v in astuple(self))

    def distort(self, xy: ArrayLike) -> Array:
        """Distort ideal normalised coordinates ``(..., 2)``."""
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_points(lambda b: self.distort(b), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        if use_numba(arr, min_size=2 * NUMBA_MIN_POINTS):
            return _numba_points("kannala_brandt_distort", arr, self.coeffs)
        return kb_distort_xp(arr, self.coeffs, xp)

    def undistort(self, xy: ArrayLike, max_iter: int = 20, tol: float | None = None) -> Undistorted:
        """Invert :meth:`distort`: :class:`Undistorted` ``(xy, valid)``, NaN where not valid.

        Examples
        --------
        >>> xy, ok = KannalaBrandt(k1=0.1).undistort([0.8, 0.0])
        >>> bool(ok), round(float(KannalaBrandt(k1=0.1).distort(xy)[0]), 12)
        (True, 0.8)
        """
        if is_dask_array(xy):  # pointwise: lazily, one task per chunk
            return _dask_pair(lambda b: self.undistort(b, max_iter, tol), xy)
        xp = namespace(xy)
        arr = as_points_bounded(xy, "xy", 2, xp=xp)
        it, t = _iter_args(max_iter, tol, xp, arr.dtype)
        if use_numba(arr, min_size=2 * NUMBA_MIN_POINTS):
            return _numba_points("kannala_brandt_undistort", arr, self.coeffs, it, t)
        return Undistorted(*kb_undistort_xp(arr, self.coeffs, xp, it, t))


def _check_model(distortion: object) -> None:
    if distortion is not None and not isinstance(
        distortion, BrownConrady | DivisionModel | KannalaBrandt
    ):
        raise InvalidInputError(
            "expected distortion to be BrownConrady, DivisionModel, KannalaBrandt or None, "
            f"got {type(distortion).__name__}"
        )


def _project_xp(points: Any, K: Any, R: Any, t: Any, distortion: Any, xp: Any) -> tuple[Any, Any]:
    """Plain twin of the fused kernel: camera frame, divide, distort, apply K."""
    cam = points @ xp.matrix_transpose(R) + t
    z = cam[..., 2]
    valid = z > 0.0
    safe_z = xp.where(valid, z, xp.ones_like(z))
    xy = cam[..., :2] / safe_z[..., None]
    if distortion is not None:
        xy = distortion.distort(xy)
    x, y = xy[..., 0], xy[..., 1]
    u = K[0, 0] * x + K[0, 1] * y + K[0, 2]
    v = K[1, 1] * y + K[1, 2]
    nan = xp.full_like(u, float("nan"))
    uv = xp.stack([xp.where(valid, u, nan), xp.where(valid, v, nan)], axis=-1)
    return uv, valid


def project_points_distorted(
    points: ArrayLike, K: ArrayLike, R: ArrayLike, t: ArrayLike, distortion: DistortionModel | None
) -> Projection:
    r"""Project world points through ``[R | t]``, a distortion model and ``K`` to pixels.

    .. math::

        \mathbf{X}_c = R\mathbf{X} + \mathbf{t},\quad
        (x, y) = (X_c / Z_c,\ Y_c / Z_c),\quad
        (x_d, y_d) = \mathrm{distort}(x, y),\quad
        (u, v, 1)^T = K (x_d, y_d, 1)^T

    Parameters
    ----------
    points : array (..., 3)
        World points (row vectors).
    K : array (3, 3)
        Intrinsics (upper triangular; the skew ``K[0, 1]`` is honoured).
    R : array (3, 3)
        World-to-camera rotation (checked orthonormal, det +1).
    t : array (3,)
        World-to-camera translation.
    distortion : BrownConrady, DivisionModel, KannalaBrandt or None
        The lens model on normalised coordinates.

    Returns
    -------
    Projection
        ``uv`` (..., 2): pixel coordinates, NaN where ``valid`` is False; ``valid`` (...)
        bool: ``Z_c > 0``, points at or behind the camera are never projected.

    Notes
    -----
    Pinhole projection as in Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., eq. (6.8),
    followed by the distortion model; the same composition as OpenCV's ``projectPoints``
    (which ignores skew and mirrors points behind the camera). Large NumPy inputs with
    :class:`BrownConrady` run one fused numba kernel
    (:func:`imageform._kernels.project_distort.project_brown_conrady`); CUDA arrays (PyTorch,
    CuPy) with :class:`BrownConrady` or no distortion one fused CUDA kernel
    (:mod:`imageform._cuda.geometry`).

    Examples
    --------
    >>> K = [[500.0, 0, 320], [0, 500, 240], [0, 0, 1]]
    >>> uv, ok = project_points_distorted([[0.5, 0, 1]], K, np.eye(3), [0, 0, 0],
    ...                                   BrownConrady(k1=-0.2))
    >>> uv.round(6).tolist(), ok.tolist()
    ([[557.5, 240.0]], [True])
    """
    xp = namespace(points, K, R, t)
    dev = common_device(points, K, R, t)
    pts = as_points_bounded(points, "points", 3, xp=xp, device=dev)
    Km = as_matrix_bounded(K, "K", (3, 3), xp=xp, dtype=pts.dtype, batch=False, device=dev)
    Rm = as_matrix_bounded(R, "R", (3, 3), xp=xp, dtype=pts.dtype, batch=False, device=dev)
    check_rotation(Rm, "R", xp=xp)
    tv = as_points_bounded(t, "t", 3, xp=xp, dtype=pts.dtype, device=dev)
    if tv.ndim != 1:
        raise InvalidInputError(f"expected t of shape (3,), got {tuple(tv.shape)}")
    _check_model(distortion)
    if (distortion is None or isinstance(distortion, BrownConrady)) and _cuda_geometry().on_cuda(
        pts, Km, Rm, tv
    ):  # one fused CUDA kernel (imageform._cuda.geometry)
        shape = tuple(pts.shape)
        coeffs = distortion.coeffs if distortion is not None else (0.0,) * 8
        res = _cuda_geometry().project(xp.reshape(pts, (-1, 3)), Km, Rm, tv, coeffs)
        if res is not None:  # None: the kernels are unusable here
            uv, valid = res
            return Projection(xp.reshape(uv, (*shape[:-1], 2)), xp.reshape(valid, shape[:-1]))
    if (
        isinstance(distortion, BrownConrady)
        and use_numba(pts, min_size=3 * NUMBA_MIN_POINTS)
        and pts.dtype == np.float64
    ):
        from imageform._kernels.project_distort import project_brown_conrady

        shape = tuple(pts.shape)
        uv, valid = project_brown_conrady(
            pts.reshape(-1, 3), Km, Rm, tv, np.asarray(distortion.coeffs)
        )
        return Projection(uv.reshape(*shape[:-1], 2), valid.reshape(shape[:-1]))
    return Projection(*_project_xp(pts, Km, Rm, tv, distortion, xp))
