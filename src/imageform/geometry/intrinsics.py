r"""Intrinsic parameters: the calibration matrix K, physical units and fields of view.

.. math::
    K = \begin{pmatrix} f_x & s & c_x \\ 0 & f_y & c_y \\ 0 & 0 & 1 \end{pmatrix}

``fx = f / pitch_x`` and ``fy = f / pitch_y`` are the focal length in pixels, ``(cx, cy)`` the
principal point in pixels (centre of the top-left pixel at (0, 0)), ``s`` the skew
(Hartley & Zisserman eq. 6.10). Pinhole: a point ``(X, Y, Z)`` in the camera frame images
at ``x = f X / Z`` on the image plane (the lecture's similar triangles).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._backend import common_device, namespace, to_numpy
from imageform._typing import Array, ArrayLike, FloatArray
from imageform._validate import (
    MAX_MAGNITUDE,
    MAX_SIDE,
    any_value,
    as_float_bounded,
    as_matrix_bounded,
    as_real,
    check_image_size,
    check_K,
    check_positive,
    real_pair,
)
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = ["Intrinsics", "intrinsic_matrix", "projected_size"]


def intrinsic_matrix(
    fx: ArrayLike, fy: ArrayLike, cx: ArrayLike, cy: ArrayLike, skew: ArrayLike = 0.0
) -> Array:
    """Build the 3×3 calibration matrix K (batched if the parameters are arrays).

    ``fx`` and ``fy`` must be > 0 (zero makes K singular, a negative value mirrors the
    image): InvalidInputError otherwise.

    Examples
    --------
    >>> intrinsic_matrix(500, 500, 320, 240)
    array([[500.,   0., 320.],
           [  0., 500., 240.],
           [  0.,   0.,   1.]])
    """
    xp = namespace(fx, fy, cx, cy, skew)
    dev = common_device(fx, fy, cx, cy, skew)
    vals = [
        as_float_bounded(v, n, xp=xp, device=dev)
        for v, n in zip((fx, fy, cx, cy, skew), ("fx", "fy", "cx", "cy", "skew"), strict=True)
    ]
    dtype = xp.result_type(*vals)
    vals = [xp.astype(v, dtype) for v in vals]
    fx_, fy_, cx_, cy_, s_ = xp.broadcast_arrays(*vals)
    if any_value(fx_ == 0, xp) or any_value(fy_ == 0, xp):
        raise InvalidInputError("expected non-zero focal lengths fx, fy (K would be singular)")
    if any_value(fx_ < 0, xp) or any_value(fy_ < 0, xp):
        raise InvalidInputError(
            f"expected focal lengths fx > 0 and fy > 0, got fx min {float(xp.min(fx_)):g}, "
            f"fy min {float(xp.min(fy_)):g} (a negative focal length mirrors the image)"
        )
    zero, one = xp.zeros_like(fx_), xp.ones_like(fx_)
    rows = ((fx_, s_, cx_), (zero, fy_, cy_), (zero, zero, one))
    return xp.stack([xp.stack(r, axis=-1) for r in rows], axis=-2)


@_deprecate.parameters(positional=("focal_length",))
def projected_size(size: float, depth: float, *, focal_length: float) -> float:
    """Size of an object's image on the image plane by similar triangles, ``h = f H / Z``.

    Parameters
    ----------
    size, depth : float
        The object's size ``H`` and its distance ``Z`` from the camera, in one unit.
    focal_length : float, keyword-only
        The focal length ``f``, in any unit: ``h`` comes in that unit (all three lengths
        may also share one unit).

    Examples
    --------
    The lecture: a 30 m building 100 m away through a 50 mm lens images at 15 mm.

    >>> projected_size(30.0, 100.0, focal_length=50.0)
    15.0
    """
    h = check_positive(size, "size", allow_zero=True)
    z = check_positive(depth, "depth")
    f = check_positive(focal_length, "focal_length")
    return f * h / z


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels, optionally with the image size ``(width, height)``.

    Build from pixels (``Intrinsics(fx, fy, cx, cy)``), from physical units
    (:meth:`from_physical`: focal length in mm and pixel pitch in µm, the principal point at
    the image centre by default), or from a field of view (:meth:`from_fov`).

    Examples
    --------
    >>> cam = Intrinsics.from_physical(
    ...     focal_length_mm=50.0, pixel_pitch_um=5.0, image_size=(6000, 4000)
    ... )
    >>> cam.fx, cam.cx, cam.cy
    (10000.0, 2999.5, 1999.5)
    >>> round(math.degrees(cam.fov_x), 3)
    33.398
    """

    fx: float
    fy: float
    cx: float
    cy: float
    skew: float = 0.0
    image_size: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        """Check the parameters (bounded reals, positive focal lengths) and the image size."""
        for name in ("fx", "fy", "cx", "cy", "skew"):
            v = as_real(getattr(self, name), name, minimum=-MAX_MAGNITUDE, maximum=MAX_MAGNITUDE)
            object.__setattr__(self, name, v)
        if self.fx == 0 or self.fy == 0:
            raise InvalidInputError("expected non-zero focal lengths fx, fy (K would be singular)")
        if self.fx < 0 or self.fy < 0:
            raise InvalidInputError(
                f"expected focal lengths fx > 0 and fy > 0, got fx = {self.fx:g}, "
                f"fy = {self.fy:g} (a negative focal length mirrors the image)"
            )
        if self.image_size is not None:
            object.__setattr__(self, "image_size", check_image_size(self.image_size))

    @property
    def K(self) -> FloatArray:
        """The 3×3 calibration matrix (float64)."""
        return np.array([[self.fx, self.skew, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @classmethod
    def from_matrix(cls, K: ArrayLike, image_size: tuple[int, int] | None = None) -> Intrinsics:
        """From a 3×3 K with ``K[2] = (0, 0, 1)`` (scale it first if not)."""
        M = np.asarray(to_numpy(as_matrix_bounded(K, "K", (3, 3), batch=False)), dtype=np.float64)
        check_K(M, np, "K", positive=True)
        M = M / M[2, 2]
        return cls(M[0, 0], M[1, 1], M[0, 2], M[1, 2], M[0, 1], image_size)

    @classmethod
    @_deprecate.parameters(
        renamed={"focal_length": "focal_length_mm"},
        positional=("focal_length_mm", "pixel_pitch_um", "image_size", "principal_point"),
    )
    def from_physical(
        cls,
        *,
        focal_length_mm: float,
        pixel_pitch_um: float | tuple[float, float],
        image_size: tuple[int, int],
        principal_point: tuple[float, float] | None = None,
    ) -> Intrinsics:
        """From a lens focal length (mm) and a sensor pixel pitch (µm): ``fx = f / pitch``.

        ``focal_length_mm`` is in **millimetres** (``focal_length`` is its deprecated name:
        a bare ``focal_length`` is in metres in imageform, docs/conventions.md),
        ``pixel_pitch_um`` in micrometres (one value, or ``(x, y)``); every parameter is
        keyword-only.

        The principal point defaults to the image centre ``((w - 1) / 2, (h - 1) / 2)``
        (pixel-centre convention). The lecture: f = 50 mm at 5 µm pitch is 10 000 px, so
        a 15 mm image is 3000 px.
        """
        f = check_positive(focal_length_mm, "focal_length_mm")
        px, py = real_pair(pixel_pitch_um, "pixel_pitch_um", positive=True, scalar_ok=True)
        w, h = check_image_size(image_size)
        cx, cy = (
            real_pair(principal_point, "principal_point")
            if principal_point is not None
            else ((w - 1) / 2, (h - 1) / 2)
        )
        fx, fy = f * 1000.0 / px, f * 1000.0 / py
        if max(fx, fy) > MAX_MAGNITUDE:
            raise InvalidInputError(
                f"expected focal_length_mm / pixel_pitch_um <= {MAX_MAGNITUDE:g} pixels, got "
                f"{max(fx, fy):g} (focal_length_mm {f:g}, pixel_pitch_um ({px:g}, {py:g}))"
            )
        return cls(fx, fy, cx, cy, 0.0, (w, h))

    @classmethod
    @_deprecate.parameters(
        renamed={"focal_length": "focal_length_mm"},
        positional=("focal_length_mm", "sensor_size_mm", "image_size"),
    )
    def from_sensor(
        cls,
        *,
        focal_length_mm: float,
        sensor_size_mm: tuple[float, float],
        image_size: tuple[int, int],
    ) -> Intrinsics:
        """From a focal length (mm) and the sensor's active area (width, height) in mm.

        ``focal_length_mm`` in millimetres (``focal_length`` is its deprecated name); every
        parameter is keyword-only.
        """
        sw, sh = real_pair(sensor_size_mm, "sensor_size_mm (width, height)", positive=True)
        w, h = check_image_size(image_size)
        return cls.from_physical(
            focal_length_mm=focal_length_mm,
            pixel_pitch_um=(sw / w * 1000.0, sh / h * 1000.0),
            image_size=(w, h),
        )

    @classmethod
    def from_fov(cls, fov_x: float, image_size: tuple[int, int]) -> Intrinsics:
        """Square pixels, centred principal point, horizontal field of view ``fov_x`` (radians).

        ``fx = (w / 2) / tan(fov_x / 2)``.
        """
        fov = as_real(fov_x, "fov_x")
        if not 0 < fov < math.pi:
            raise InvalidInputError(f"expected 0 < fov_x < pi radians, got {fov:g}")
        w, h = check_image_size(image_size)
        f = (w / 2) / math.tan(fov / 2)
        if f > MAX_MAGNITUDE:
            raise InvalidInputError(f"expected fov_x giving fx <= {MAX_MAGNITUDE:g}, got {fov:g}")
        return cls(f, f, (w - 1) / 2, (h - 1) / 2, 0.0, (w, h))

    def _size(self) -> tuple[int, int]:
        if self.image_size is None:
            raise InvalidInputError("this needs image_size=(width, height)")
        return self.image_size

    @property
    def fov_x(self) -> float:
        r"""Horizontal field of view in radians across the full image width.

        .. math::
            \mathrm{FOV}_x = \arctan\frac{c_x + 1/2}{f_x} + \arctan\frac{w - 1/2 - c_x}{f_x}

        (the outer edges of the border pixels; ``2 arctan(w / 2 f)`` for a centred principal
        point).
        """
        w, _ = self._size()
        return math.atan((self.cx + 0.5) / self.fx) + math.atan((w - 0.5 - self.cx) / self.fx)

    @property
    def fov_y(self) -> float:
        """Vertical field of view in radians across the full image height."""
        _, h = self._size()
        return math.atan((self.cy + 0.5) / self.fy) + math.atan((h - 0.5 - self.cy) / self.fy)

    @property
    def fov_diagonal(self) -> float:
        """Diagonal field of view in radians (centred principal point, no skew assumed)."""
        w, h = self._size()
        if self.fx != self.fy:
            raise DegenerateConfigurationError(
                "the diagonal field of view needs square pixels (fx = fy)"
            )
        return 2.0 * math.atan(math.hypot(w, h) / (2.0 * self.fx))

    def scaled(self, factor: float) -> Intrinsics:
        """Intrinsics of the image resized by ``factor`` (pixel-centre convention kept)."""
        s = check_positive(factor, "factor")
        size = None
        if self.image_size is not None:
            w, h = self.image_size[0] * s, self.image_size[1] * s
            if not (0.5 <= w <= MAX_SIDE and 0.5 <= h <= MAX_SIDE):
                raise InvalidInputError(
                    f"expected factor giving an image of 1 to {MAX_SIDE} pixels a side, got "
                    f"factor {s:g} for image_size {self.image_size}"
                )
            size = (round(w), round(h))
        if s * max(abs(self.fx), abs(self.fy), abs(self.cx), abs(self.cy)) > MAX_MAGNITUDE:
            raise InvalidInputError(f"expected a factor <= {MAX_MAGNITUDE:g} / fx, got {s:g}")
        return Intrinsics(
            self.fx * s,
            self.fy * s,
            (self.cx + 0.5) * s - 0.5,
            (self.cy + 0.5) * s - 0.5,
            self.skew * s,
            size,
        )
