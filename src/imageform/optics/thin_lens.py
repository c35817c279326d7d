"""The thin lens: Gaussian lens equation, magnification and f-number, in SI units (metres).

Every function takes the focal length as the keyword-only ``focal_length`` (metres), written
``f`` in the equations. Sign convention: *real is positive*. A converging lens has ``f > 0``;
a real object in front of the lens has ``d_o > 0``; a real image behind the lens (where a
sensor can sit) has ``d_i > 0``. An object inside the focal length (``d_o < f``) has no real
image: the rays leave the lens diverging and only appear to come from a *virtual*, upright,
magnified image on the object's side (``d_i < 0``, the magnifying-glass case).
:func:`thin_lens` raises for it unless ``allow_virtual=True``, when it returns that image
with ``virtual=True``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imageform import _deprecate
from imageform._validate import as_bool, as_real, check_positive, finite_result
from imageform.errors import InvalidInputError

__all__ = [
    "ThinLensSolution",
    "aperture_diameter",
    "f_number",
    "magnification",
    "thin_lens",
]


@dataclass(frozen=True)
class ThinLensSolution:
    """A solved thin lens: focal length, object and image distances (m), magnification.

    ``magnification`` is the lateral magnification ``m = -d_i / d_o`` (negative: inverted).
    ``virtual`` is True when the image is virtual (``d_i < 0``, object inside ``f``).
    """

    focal_length: float
    d_o: float
    d_i: float
    magnification: float
    virtual: bool

    f = _deprecate.renamed_property("focal_length", "imageform.optics.ThinLensSolution.f")

    def __post_init__(self) -> None:
        """Check the fields: finite reals (complex, NaN, inf, None refused by name)."""
        # issue 16: a solution holds finite reals (complex, NaN, inf, None refused by name)
        for name, kw in (
            ("focal_length", {"positive": True}),
            ("d_o", {"positive": True}),
            ("d_i", {}),
            ("magnification", {}),
        ):
            object.__setattr__(self, name, as_real(getattr(self, name), name, **kw))
        object.__setattr__(self, "virtual", as_bool(self.virtual, "virtual"))


def _number(value: object, name: str) -> float:
    return as_real(value, f"{name} (metres)")


def _virtual_error(f: float, d_o: float) -> InvalidInputError:
    with np.errstate(all="ignore"):
        d_i = float(np.float64(f) * d_o / (np.float64(d_o) - f))
    return InvalidInputError(
        f"object distance d_o = {d_o:g} m is inside the focal length (focal_length = {f:g} m): "
        "only a "
        f"virtual image forms (d_i = {d_i:g} m); move the object beyond f or pass "
        "allow_virtual=True"
    )


@_deprecate.parameters(renamed={"f": "focal_length"})
def thin_lens(
    *,
    focal_length: float | None = None,
    d_o: float | None = None,
    d_i: float | None = None,
    allow_virtual: bool = False,
) -> ThinLensSolution:
    r"""Solve the Gaussian thin-lens equation for whichever of ``f``, ``d_o``, ``d_i`` is missing.

    .. math::

        \frac{1}{f} = \frac{1}{d_o} + \frac{1}{d_i}, \qquad m = -\frac{d_i}{d_o}

    Parameters
    ----------
    focal_length, d_o, d_i : float
        Exactly two of them, in metres (real-is-positive convention, module docstring).
    allow_virtual : bool
        Return the virtual image (``d_i < 0``, ``virtual=True``) of an object inside the
        focal length instead of raising.

    Returns
    -------
    ThinLensSolution

    Raises
    ------
    InvalidInputError
        Not exactly two values; ``focal_length <= 0``; ``d_o <= 0``; an object at the focal
        plane (image at infinity); an object inside the focal length (virtual image) without
        ``allow_virtual``; a given ``d_i <= f`` or ``d_i < 0`` (no real object images there).

    Notes
    -----
    Source: E. Hecht, *Optics*, 5th ed., eq. (5.17) (Gaussian lens formula) and (5.24)
    (transverse magnification).

    Examples
    --------
    >>> s = thin_lens(focal_length=0.05, d_o=2.0)
    >>> round(s.d_i * 1000, 4), round(s.magnification, 5)
    (51.2821, -0.02564)
    """
    given = {
        k: v
        for k, v in (("focal_length", focal_length), ("d_o", d_o), ("d_i", d_i))
        if v is not None
    }
    if len(given) != 2:
        raise InvalidInputError(
            f"expected exactly two of focal_length, d_o, d_i, got {sorted(given) or 'none'}"
        )
    vals = {k: _number(v, k) for k, v in given.items()}
    if "focal_length" in vals and vals["focal_length"] <= 0:
        raise InvalidInputError(
            f"expected a converging lens, focal_length > 0 m, got {vals['focal_length']:g} "
            "(a diverging lens forms no real image)"
        )
    if "d_o" in vals and vals["d_o"] <= 0:
        raise InvalidInputError(f"expected an object in front of the lens, d_o > 0 m, got {d_o!r}")
    if "d_i" in vals and vals["d_i"] == 0:
        raise InvalidInputError("expected d_i != 0 m, got 0")

    if "d_i" not in vals:
        fv, do = vals["focal_length"], vals["d_o"]
        if do == fv:
            raise InvalidInputError(
                f"object at the focal plane (d_o = focal_length = {fv:g} m): the rays leave "
                "parallel and the image forms at infinity"
            )
        if do < fv and not allow_virtual:
            raise _virtual_error(fv, do)
        di = finite_result("d_i = f d_o / (d_o - f)", lambda: fv * do / (do - fv), **vals)
    elif "d_o" not in vals:
        fv, di = vals["focal_length"], vals["d_i"]
        if di < 0 and not allow_virtual:
            raise InvalidInputError(
                f"d_i = {di:g} m < 0 is a virtual image; pass allow_virtual=True to solve for "
                "the object inside the focal length that forms it"
            )
        if 0 < di <= fv:
            raise InvalidInputError(
                f"image distance d_i = {di:g} m is not beyond f (focal_length = {fv:g} m): no "
                "real object images there (a real image always lies beyond the focal length)"
            )
        do = finite_result("d_o = f d_i / (d_i - f)", lambda: fv * di / (di - fv), **vals)
    else:
        do, di = vals["d_o"], vals["d_i"]
        if di < 0 and not allow_virtual:
            raise InvalidInputError(
                f"d_i = {di:g} m < 0 is a virtual image; pass allow_virtual=True"
            )
        if di < 0 and -di <= do:
            raise InvalidInputError(
                f"a virtual image at d_i = {di:g} m must lie farther than the object "
                f"(d_o = {do:g} m) for a converging lens"
            )
        fv = finite_result("f = d_o d_i / (d_o + d_i)", lambda: do * di / (do + di), **vals)
    fv, do, di, m = finite_result("the thin-lens solution", lambda: (fv, do, di, -di / do), **vals)
    return ThinLensSolution(focal_length=fv, d_o=do, d_i=di, magnification=m, virtual=di < 0)


@_deprecate.parameters(renamed={"f": "focal_length"}, positional=("focal_length", "d_o"))
def magnification(*, focal_length: float, d_o: float, allow_virtual: bool = False) -> float:
    r"""Lateral magnification of an object at ``d_o`` through a thin lens of focal length ``f``.

    ``focal_length`` and ``d_o`` in metres, keyword-only.

    .. math::

        m = -\frac{d_i}{d_o} = \frac{f}{f - d_o}

    Negative values mean an inverted real image. Source: Hecht, *Optics*, 5th ed., eq. (5.24).

    Examples
    --------
    >>> round(magnification(focal_length=0.05, d_o=0.1), 12)  # object at 2f: life-size
    -1.0
    """
    return thin_lens(focal_length=focal_length, d_o=d_o, allow_virtual=allow_virtual).magnification


@_deprecate.parameters(
    renamed={"f": "focal_length"}, positional=("focal_length", "aperture_diameter")
)
def f_number(*, focal_length: float, aperture_diameter: float) -> float:
    r"""Return the f-number ``N = f / D`` of a lens with entrance-pupil diameter ``D`` (metres).

    ``focal_length`` and ``aperture_diameter`` in metres, keyword-only.

    .. math::

        N = \frac{f}{D}

    Source: Hecht, *Optics*, 5th ed., §5.3.3.

    Examples
    --------
    >>> round(f_number(focal_length=0.05, aperture_diameter=0.05 / 2.8), 12)
    2.8
    """
    fv = check_positive(focal_length, "focal_length (m)")
    d = check_positive(aperture_diameter, "aperture_diameter (m)")
    return float(
        finite_result("the f-number", lambda: fv / d, focal_length=fv, aperture_diameter=d)
    )


@_deprecate.parameters(renamed={"f": "focal_length"}, positional=("focal_length", "f_number"))
def aperture_diameter(*, focal_length: float, f_number: float) -> float:
    """Entrance-pupil diameter ``D = f / N`` (metres); ``focal_length`` in metres, keyword-only.

    Examples
    --------
    >>> round(aperture_diameter(focal_length=0.05, f_number=2.0), 6)
    0.025
    """
    fv = check_positive(focal_length, "focal_length (m)")
    n = check_positive(f_number, "f_number")
    return float(
        finite_result("the aperture diameter", lambda: fv / n, focal_length=fv, f_number=n)
    )
