"""Vignetting: the natural cos⁴ law and mechanical vignetting by a lens barrel.

Field angle of pixel ``(u, v)``: ``tan θ = r / f_px`` with ``r`` its distance from the optical
center ``(c_u, c_v)`` in pixels and ``f_px`` the focal length in pixels: here the keyword-only
``focal_length_px`` is in **pixels** (the focal length divided by the pixel pitch, ``fx`` of K).
"""

from __future__ import annotations

import math

import numpy as np

from imageform import _deprecate
from imageform._backend import to_numpy
from imageform._typing import ArrayLike
from imageform._validate import (
    as_image,
    as_real_array,
    as_reals,
    as_shape,
    check_positive,
    check_real_values,
    finite_result,
    format_shape,
)
from imageform.errors import InvalidInputError

__all__ = [
    "apply_vignetting",
    "cos4_falloff",
    "field_angle",
    "mechanical_vignetting",
    "pupil_overlap_fraction",
]


# A focal length in pixels carries its unit in its name (docs/conventions.md: a bare
# focal_length is in metres); "focal_length" here was the 1.0 pass's name, now deprecated.
_RENAMED = {"focal_length": "focal_length_px", "centre": "center"}


@_deprecate.parameters(renamed=_RENAMED, positional=("focal_length_px", "center"))
def field_angle(
    shape: tuple[int, int], *, focal_length_px: float, center: tuple[float, float] | None = None
) -> np.ndarray:
    """Field angle θ (radians) of every pixel: ``θ = atan(r / f_px)``; shape ``(H, W)``.

    Parameters
    ----------
    shape : (H, W)
        Image size in pixels.
    focal_length_px : float, keyword-only
        Focal length in **pixels** (``fx``; ``focal_length`` is its deprecated name).
    center : (c_u, c_v), keyword-only, optional
        The optical center (column, row); default the image center ``((W-1)/2, (H-1)/2)``.

    Examples
    --------
    >>> round(float(field_angle((1, 3), focal_length_px=1.0)[0, 0]), 6)  # 1 px off, f = 1 px
    0.785398
    """
    h, w = as_shape(shape, "shape (H, W)", 2, itemsize=8, copies=6)
    f = check_positive(focal_length_px, "focal_length_px")
    cu, cv = ((w - 1) / 2, (h - 1) / 2) if center is None else as_reals(center, "center", 2)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    with np.errstate(over="ignore"):  # a far centre: r = inf gives θ = π/2
        return np.arctan(np.hypot(u - cu, v - cv) / f)


@_deprecate.parameters(renamed=_RENAMED, positional=("focal_length_px", "center"))
def cos4_falloff(
    shape: tuple[int, int], *, focal_length_px: float, center: tuple[float, float] | None = None
) -> np.ndarray:
    r"""Relative illumination of the natural vignetting law, ``cos⁴ θ``; shape ``(H, W)``.

    ``focal_length_px`` (keyword-only) is in pixels, ``center`` as in :func:`field_angle`.

    .. math::

        \frac{E(\theta)}{E(0)} = \cos^4\theta = \left(\frac{f^2}{f^2 + r^2}\right)^2

    One cosine from the obliquity of the pupil seen from the pixel, one from the tilt of the
    sensor, two from the inverse-square distance to the pupil. Source: E. Hecht, *Optics*,
    5th ed., §5.7.4 (cos⁴ law); S. F. Ray, *Applied Photographic Optics*, §23.

    Examples
    --------
    >>> f = cos4_falloff((1, 3), focal_length_px=1.0)  # the outer pixels are at 45°
    >>> round(float(f[0, 0]), 6), float(f[0, 1])
    (0.25, 1.0)
    """
    return np.cos(field_angle(shape, focal_length_px=focal_length_px, center=center)) ** 4


def pupil_overlap_fraction(
    pupil_radius: float, stop_radius: float, offset: ArrayLike
) -> np.ndarray:
    r"""Fraction of a circular pupil (radius ``a``) inside a circle of radius ``b`` at ``offset``.

    .. math::

        \frac{A(a, b, d)}{\pi a^2},\ A = a^2 \cos^{-1}\frac{d^2 + a^2 - b^2}{2da}
        + b^2 \cos^{-1}\frac{d^2 + b^2 - a^2}{2db}
        - \tfrac12\sqrt{(-d+a+b)(d+a-b)(d-a+b)(d+a+b)}

    (the area of intersection of two circles, Weisstein, MathWorld "Circle-Circle
    Intersection", eq. 14). 1 when the pupil lies inside, 0 when they do not overlap.

    Examples
    --------
    >>> round(float(pupil_overlap_fraction(1.0, 1.0, 1.0)), 6)
    0.391002
    """
    a = check_positive(pupil_radius, "pupil_radius")
    b = check_positive(stop_radius, "stop_radius")
    d = as_real_array(offset, "offset")
    return finite_result(
        "the overlap fraction",
        lambda: _overlap(a, b, np.abs(d)),
        pupil_radius=a,
        stop_radius=b,
    )


def _overlap(a: float, b: float, d: np.ndarray) -> np.ndarray:
    """:func:`pupil_overlap_fraction` on checked values (``d >= 0``)."""
    full = d <= b - a
    none = d >= a + b
    inner = d <= a - b  # stop entirely inside the pupil
    ds = np.where(full | none | inner | (d == 0), 1.0, d)
    ca = np.clip((ds**2 + a * a - b * b) / (2 * ds * a), -1.0, 1.0)
    cb = np.clip((ds**2 + b * b - a * a) / (2 * ds * b), -1.0, 1.0)
    prod = (-ds + a + b) * (ds + a - b) * (ds - a + b) * (ds + a + b)
    lens = a * a * np.arccos(ca) + b * b * np.arccos(cb) - 0.5 * np.sqrt(np.maximum(prod, 0.0))
    frac = lens / (math.pi * a * a)
    frac = np.where(inner, (b * b) / (a * a), frac)
    frac = np.where(full, 1.0, np.where(none, 0.0, frac))
    return frac


@_deprecate.parameters(renamed=_RENAMED, positional=("focal_length_px",))
def mechanical_vignetting(
    shape: tuple[int, int],
    *,
    focal_length_px: float,
    pupil_radius: float,
    barrel_radius: float,
    barrel_distance: float,
    center: tuple[float, float] | None = None,
) -> np.ndarray:
    r"""Relative illumination when a lens barrel clips the oblique beam; shape ``(H, W)``.

    At field angle θ the beam that fills the aperture stop (radius ``a = pupil_radius``) is
    displaced by ``d = L tan θ`` where it passes the barrel's opening (radius
    ``b = barrel_radius``) a distance ``L = barrel_distance`` from the stop; the transmitted
    fraction is the overlap of the two circles (:func:`pupil_overlap_fraction`).

    .. math::

        V(\theta) = \frac{A(a, b, L\tan\theta)}{\pi a^2}

    ``focal_length_px`` is in pixels and ``center`` as in :func:`field_angle`; the other lengths
    in one unit (e.g. metres). Source: S. F. Ray, *Applied Photographic Optics*, §23
    ("mechanical vignetting"); geometry of the oblique beam.

    Examples
    --------
    >>> v = mechanical_vignetting((1, 3), focal_length_px=1.0, pupil_radius=1, barrel_radius=1,
    ...                           barrel_distance=1)
    >>> round(float(v[0, 0]), 6), float(v[0, 1])
    (0.391002, 1.0)
    """
    L = check_positive(barrel_distance, "barrel_distance", allow_zero=True)
    a = check_positive(pupil_radius, "pupil_radius")
    b = check_positive(barrel_radius, "barrel_radius")
    theta = field_angle(shape, focal_length_px=focal_length_px, center=center)
    names = {"pupil_radius": a, "barrel_radius": b, "barrel_distance": L}
    d = finite_result("the beam offset L tan θ", lambda: L * np.tan(theta), **names)
    return np.asarray(finite_result("the vignetting", lambda: _overlap(a, b, d), **names))


def apply_vignetting(image: ArrayLike, falloff: ArrayLike) -> np.ndarray:
    """Multiply an image ``(H, W)`` or ``(H, W, C)`` by a relative-illumination map ``(H, W)``.

    Examples
    --------
    >>> fall = cos4_falloff((1, 3), focal_length_px=1.0)
    >>> apply_vignetting(np.ones((1, 3)), fall).round(12).tolist()
    [[0.25, 1.0, 0.25]]
    """
    f = as_real_array(falloff, "falloff", check=False)

    def check_shapes(shape: tuple[int, ...]) -> None:
        if len(shape) not in (2, 3) or tuple(shape[:2]) != f.shape:
            raise InvalidInputError(
                f"expected image (H, W[, C]) and falloff (H, W), got {format_shape(shape)} "
                f"and falloff {format_shape(f.shape)}"
            )

    shape = getattr(image, "shape", None)
    if isinstance(shape, tuple):  # an array: its shape before any of its values is read
        check_shapes(shape)
    img = np.asarray(to_numpy(as_image(image, "image", channels=None)))
    check_shapes(img.shape)
    check_real_values(f, "falloff")
    f = f.astype(img.dtype, copy=False)
    return finite_result(
        "image × falloff", lambda: img * (f if img.ndim == 2 else f[..., None]), falloff=f
    )
