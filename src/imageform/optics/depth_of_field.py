"""Depth of field, hyperfocal distance and the circle of confusion of a thin lens (metres).

Distances are measured from the lens (thin-lens model, object side); every function takes the
focal length as the keyword-only ``focal_length`` (m), written ``f`` in the equations. ``coc``
is the largest acceptable blur-spot *diameter* on the sensor (0.03 mm is the usual value for
35 mm film).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from imageform import _deprecate
from imageform._backend import namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import as_float, as_real, check_positive, finite_result
from imageform.errors import InvalidInputError

__all__ = [
    "DepthOfField",
    "circle_of_confusion",
    "depth_of_field",
    "hyperfocal_distance",
]


def _lens(f: float, n: float) -> tuple[float, float]:
    return check_positive(f, "focal_length (m)"), check_positive(n, "f_number")


def _focus(focus: float, f: float) -> float:
    s = check_positive(focus, "focus distance (m)")
    if s <= f:
        raise InvalidInputError(
            f"expected focus beyond focal_length, got focus {s:g} m <= focal_length {f:g} m: "
            "a thin lens cannot focus a real image of a point inside its focal length"
        )
    return s


@_deprecate.parameters(
    renamed={"f": "focal_length"}, positional=("focal_length", "f_number", "coc")
)
def hyperfocal_distance(*, focal_length: float, f_number: float, coc: float) -> float:
    r"""Hyperfocal distance: focused there, everything from ``H/2`` to infinity is sharp.

    .. math::

        H = \frac{f^2}{N c} + f

    Parameters
    ----------
    focal_length : float, keyword-only
        Focal length ``f`` (m).
    f_number : float, keyword-only
        ``N = f / D``.
    coc : float, keyword-only
        Acceptable circle-of-confusion diameter on the sensor (m).

    Notes
    -----
    Source: S. F. Ray, *Applied Photographic Optics*, 3rd ed., §6.3; Wikipedia "Hyperfocal
    distance" (definition 1).

    Examples
    --------
    >>> h = hyperfocal_distance(focal_length=0.050, f_number=8, coc=0.03e-3)  # 50 mm f/8
    >>> round(h, 2)
    10.47
    """
    fv, n = _lens(focal_length, f_number)
    c = check_positive(coc, "coc (circle of confusion, m)")
    return float(
        finite_result(
            "the hyperfocal distance",
            lambda: fv * fv / (n * c) + fv,
            focal_length=fv,
            f_number=n,
            coc=c,
        )
    )


@dataclass(frozen=True)
class DepthOfField:
    """Near and far limits of acceptable sharpness (m); ``far`` is ``inf`` beyond ``H``."""

    focus: float
    near: float
    far: float
    hyperfocal: float

    def __post_init__(self) -> None:
        """Check the distances: finite (far may be inf), near <= focus <= far."""
        # issue 16: finite distances (> 0; near >= 0), near <= focus <= far; far is inf exactly when
        # focused at or beyond the hyperfocal distance
        for name in ("focus", "hyperfocal"):
            object.__setattr__(self, name, as_real(getattr(self, name), name, positive=True))
        object.__setattr__(self, "near", as_real(self.near, "near", nonnegative=True))
        far = as_real(self.far, "far", positive=True, allow_inf=True)
        object.__setattr__(self, "far", far)
        if not self.near <= self.focus <= far:
            raise InvalidInputError(
                f"expected near <= focus <= far, got near {self.near:g}, focus {self.focus:g}, "
                f"far {far:g} (m)"
            )
        if math.isinf(far) != (self.focus >= self.hyperfocal):
            raise InvalidInputError(
                f"expected far = inf exactly when focus >= hyperfocal, got far {far:g}, focus "
                f"{self.focus:g}, hyperfocal {self.hyperfocal:g} (m)"
            )

    @property
    def total(self) -> float:
        """``far - near`` (``inf`` when ``far`` is infinite)."""
        return self.far - self.near

    @property
    def in_front(self) -> float:
        """Depth of field in front of the focus distance, ``focus - near``."""
        return self.focus - self.near

    @property
    def behind(self) -> float:
        """Depth of field behind the focus distance, ``far - focus``."""
        return self.far - self.focus


@_deprecate.parameters(
    renamed={"f": "focal_length"}, positional=("focal_length", "f_number", "focus", "coc")
)
def depth_of_field(
    *, focal_length: float, f_number: float, focus: float, coc: float
) -> DepthOfField:
    r"""Near and far limits of the depth of field of a thin lens.

    ``focal_length``, ``focus`` (the distance ``s``) and ``coc`` in metres; every parameter is
    keyword-only.

    .. math::

        D_n = \frac{s (H - f)}{H + s - 2f}, \qquad
        D_f = \frac{s (H - f)}{H - s}\ (s < H), \quad D_f = \infty\ (s \ge H)

    with ``s`` the focus distance and ``H`` the :func:`hyperfocal_distance`. At ``D_n`` and
    ``D_f`` the :func:`circle_of_confusion` equals ``coc`` exactly.

    Source: Wikipedia "Depth of field", §"Derivation of the DOF formulae" (exact thin-lens
    forms); S. F. Ray, *Applied Photographic Optics*, 3rd ed., §6.3.

    Examples
    --------
    >>> d = depth_of_field(focal_length=0.050, f_number=2.8, focus=2.0, coc=0.03e-3)
    >>> round(d.near, 3), round(d.far, 3)  # DOFMaster: 1.88 m - 2.14 m
    (1.877, 2.14)
    """
    fv, n = _lens(focal_length, f_number)
    s = _focus(focus, fv)
    h = hyperfocal_distance(focal_length=fv, f_number=n, coc=coc)
    near = finite_result(
        "the near limit", lambda: s * (h - fv) / (h + s - 2 * fv), focus=s, hyperfocal=h
    )
    far = (
        finite_result("the far limit", lambda: s * (h - fv) / (h - s), focus=s, hyperfocal=h)
        if s < h
        else math.inf
    )
    return DepthOfField(focus=s, near=near, far=far, hyperfocal=h)


@_deprecate.parameters(renamed={"f": "focal_length"})
def circle_of_confusion(
    depth: ArrayLike, *, focal_length: float, f_number: float, focus: float
) -> Array:
    r"""Blur-spot diameter on the sensor (m) of a point at ``depth`` when focused at ``focus``.

    .. math::

        c(d) = \frac{f}{N} \cdot \frac{|d - s|}{d} \cdot \frac{f}{s - f}

    Parameters
    ----------
    depth : float or array (...)
        Distances of the points from the lens (m), ``> 0``; ``inf`` is allowed (the limit
        ``f² / (N (s - f))``).
    focal_length, f_number, focus : float, keyword-only
        Focal length ``f`` (m), f-number, focus distance ``s > f`` (m).

    Returns
    -------
    float or array (...), same namespace and dtype as ``depth``.

    Notes
    -----
    Source: Wikipedia "Circle of confusion", §"Determining a circle of confusion diameter
    from the object field"; the aperture diameter is ``A = f / N``.

    Examples
    --------
    >>> c = circle_of_confusion(4.0, focal_length=0.05, f_number=2.0, focus=2.0)
    >>> round(float(c) * 1e3, 6)
    0.320513
    """
    fv, n = _lens(focal_length, f_number)
    s = _focus(focus, fv)
    scalar = isinstance(depth, int | float)
    xp = namespace(depth)
    d = as_float(depth, "depth", xp=xp, finite=False)
    if bool(xp.any(xp.isnan(d))) or bool(xp.any(d <= 0)):
        raise InvalidInputError("expected depth > 0 m (inf allowed), got a NaN or value <= 0")
    k = finite_result(
        "the circle of confusion at infinity f²/(N (s - f))",
        lambda: fv * fv / (n * (s - fv)),
        focal_length=fv,
        f_number=n,
        focus=s,
    )
    infinite = xp.isinf(d)
    safe = xp.where(infinite, xp.ones_like(d), d)
    c = xp.where(infinite, xp.full_like(d, k), k * xp.abs(safe - s) / safe)
    return float(c) if scalar else c
