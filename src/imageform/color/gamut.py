r"""RGB gamuts: triangles in xy and u'v', area and coverage, gamut tests and gamut mapping.

Area and coverage are of the visible region; gamut mapping is clipping, or hue-preserving
chroma reduction in CIELAB LCh.

The gamut triangle of an RGB space has its primaries' chromaticities as vertices
(:data:`imageform.color.RGB_SPACES`). *Area ratio* is the triangle's area over the area of
the visible region (spectral locus closed by the purple line); *coverage* is the area of the
triangle's intersection with the visible region over the visible area — they differ for
spaces whose primaries lie outside the locus (ProPhoto) and are equal otherwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from imageform._backend import device_of, namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_int, as_points_strict, as_real, check_name, describe
from imageform.color.chromaticity import (
    polygon_area,
    spectral_locus,
    visible_area,
    xy_to_uv_prime,
)
from imageform.color.rgb_spaces import RGB_SPACES, RGBSpace, rgb_space
from imageform.errors import InvalidInputError

__all__ = [
    "GAMUT_MAPPING_METHODS",
    "GamutFigures",
    "gamut_area",
    "gamut_coverage",
    "gamut_figures",
    "gamut_map",
    "gamut_triangle",
    "in_gamut",
]

#: ``"clip"``: clip linear RGB per channel (changes hue); ``"lch_chroma"``: keep CIELAB L*
#: (clamped to [0, 100]) and hue, reduce chroma to the gamut boundary (bisection).
GAMUT_MAPPING_METHODS = ("clip", "lch_chroma")
_KINDS = ("xyz", "xy", "linear_rgb")


def gamut_triangle(space: str | RGBSpace = "srgb", coords: str = "xy") -> np.ndarray:
    """Return the primaries' chromaticities, shape (3, 2), in ``"xy"`` or ``"uv"`` (u', v').

    Examples
    --------
    >>> gamut_triangle("srgb").tolist()
    [[0.64, 0.33], [0.3, 0.6], [0.15, 0.06]]
    """
    c = check_name(coords, ("xy", "uv"), "chromaticity diagram", "coords")
    tri = np.array(rgb_space(space).primaries_xy, dtype=np.float64)
    return tri if c == "xy" else np.asarray(xy_to_uv_prime(tri))


def gamut_area(space: str | RGBSpace = "srgb", coords: str = "xy") -> float:
    """Area of the gamut triangle in the xy or u'v' diagram.

    Examples
    --------
    >>> round(gamut_area("srgb"), 5)
    0.11205
    """
    return polygon_area(gamut_triangle(space, coords))


def _ccw(poly: np.ndarray) -> np.ndarray:
    x, y = poly[:, 0], poly[:, 1]
    signed = np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)
    return poly if signed > 0 else poly[::-1]


def _clip_polygon(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: ``subject`` (any simple polygon) clipped by convex ``clip`` (CCW)."""
    out = list(subject)
    n = len(clip)
    for i in range(n):
        a, b = clip[i], clip[(i + 1) % n]
        edge = b - a

        def side(p: np.ndarray, a: np.ndarray = a, edge: np.ndarray = edge) -> float:
            return float(edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0]))

        inp, out = out, []
        if not inp:
            break
        prev = inp[-1]
        for cur in inp:
            sc, sp = side(cur), side(prev)
            if sc >= 0:
                if sp < 0:
                    out.append(prev + (cur - prev) * (sp / (sp - sc)))
                out.append(cur)
            elif sp >= 0:
                out.append(prev + (cur - prev) * (sp / (sp - sc)))
            prev = cur
    return np.array(out).reshape(-1, 2)


def gamut_coverage(
    space: str | RGBSpace = "srgb", coords: str = "xy", *, observer: int = 2
) -> float:
    r"""Percentage of the visible region (spectral locus, 380-780 nm) the gamut covers.

    .. math:: \mathrm{coverage} = 100\,\frac{A(T \cap V)}{A(V)}

    with :math:`T` the triangle and :math:`V` the visible region (Sutherland-Hodgman clipping).

    Examples
    --------
    >>> round(gamut_coverage("srgb"), 1)
    33.5
    """
    tri = _ccw(gamut_triangle(space, coords))
    locus = spectral_locus(observer=observer, coords=coords).chromaticities
    inter = _clip_polygon(locus, tri)
    a = polygon_area(inter) if len(inter) >= 3 else 0.0
    return 100.0 * a / visible_area(coords, observer=observer)


@dataclass(frozen=True)
class GamutFigures:
    """Areas and coverage of one RGB space in both diagrams (coverage in %)."""

    space: str
    area_xy: float
    area_uv: float
    coverage_xy: float
    coverage_uv: float
    area_ratio_xy: float
    area_ratio_uv: float

    def __post_init__(self) -> None:
        """Check the space name and make every figure a non-negative real."""
        if not isinstance(self.space, str):
            raise TypeError(f"expected space as a colour space name, got {describe(self.space)}")
        for f in fields(self)[1:]:
            object.__setattr__(
                self, f.name, as_real(getattr(self, f.name), f.name, nonnegative=True)
            )

    def as_dict(self) -> dict[str, Any]:
        """Return the fields as a dict (for JSON output)."""
        return dict(self.__dict__)


def gamut_figures(spaces: Sequence[str] = ("srgb", "display_p3", "rec2020")) -> list[GamutFigures]:
    """:class:`GamutFigures` for each named space (what ``imageform gamut`` prints).

    Examples
    --------
    >>> [round(f.coverage_uv, 1) for f in gamut_figures(["srgb"])]
    [33.2]
    """
    if isinstance(spaces, str) or not isinstance(spaces, Sequence):
        raise TypeError(f"expected spaces as a list of RGB space names, got {describe(spaces)}")
    resolved = []
    for i, s in enumerate(spaces):
        try:
            resolved.append(rgb_space(s))
        except (InvalidInputError, TypeError) as exc:  # say which entry of spaces
            raise type(exc)(f"spaces[{i}]: {exc}"[:200]) from None
    out = []
    vxy, vuv = visible_area("xy"), visible_area("uv")
    for sp in resolved:
        axy, auv = gamut_area(sp, "xy"), gamut_area(sp, "uv")
        out.append(
            GamutFigures(
                sp.name,
                axy,
                auv,
                gamut_coverage(sp, "xy"),
                gamut_coverage(sp, "uv"),
                100.0 * axy / vxy,
                100.0 * auv / vuv,
            )
        )
    return out


@chunkwise(1)
def in_gamut(
    values: ArrayLike,
    space: str | RGBSpace = "srgb",
    *,
    kind: str = "xyz",
    tol: float = 1e-9,
) -> Array:
    r"""Test where colours lie inside an RGB space's gamut.

    ``kind="xyz"`` (shape (..., 3), white Y = 1): linear RGB of the space in
    :math:`[-\mathrm{tol}, 1 + \mathrm{tol}]`; ``kind="linear_rgb"``: the same test on given
    linear RGB; ``kind="xy"`` (shape (..., 2)): chromaticity inside the primaries' triangle
    (any luminance).

    Examples
    --------
    >>> in_gamut([[0.4, 0.4, 0.4], [0.1, 0.5, 0.9]]).tolist()
    [True, False]
    >>> in_gamut([[0.3127, 0.329], [0.17, 0.797]], kind="xy").tolist()
    [True, False]
    """
    k = check_name(kind, _KINDS, "gamut test kind")
    tol = as_real(tol, "tol", nonnegative=True, allow_inf=True)
    sp = rgb_space(space)
    xp = namespace(values)
    if k == "xy":
        p = as_points_strict(values, "values (xy)", 2, xp=xp)
        tri = gamut_triangle(sp)
        # barycentric test (closed triangle, tolerance tol): lam = M^-1 (p - a)
        a, b, c = tri
        minv = np.linalg.inv(np.array([b - a, c - a]).T)
        d = p - _const(a, p, xp)
        lam = d @ _const(minv.T, p, xp)
        l0 = 1.0 - lam[..., 0] - lam[..., 1]
        return (lam[..., 0] >= -tol) & (lam[..., 1] >= -tol) & (l0 >= -tol)
    v = as_points_strict(values, f"values ({k})", 3, xp=xp)
    rgb = v if k == "linear_rgb" else v @ _const(np.linalg.inv(sp.matrix_to_xyz()).T, v, xp)
    return xp.all((rgb >= -tol) & (rgb <= 1.0 + tol), axis=-1)


def _const(m: np.ndarray, like: Any, xp: Any) -> Any:
    """Make a NumPy constant in ``like``'s namespace, dtype and device."""
    return xp.asarray(np.asarray(m, dtype=np.float64), dtype=like.dtype, device=device_of(like))


@chunkwise(1)
def gamut_map(
    xyz: ArrayLike,
    space: str | RGBSpace = "srgb",
    *,
    method: str = "lch_chroma",
    iterations: int = 40,
) -> Array:
    """Map XYZ (white Y = 1) into an RGB space's gamut; returns linear RGB in [0, 1].

    ``"clip"`` clips each linear RGB channel to [0, 1] (simple; shifts hue and lightness).
    ``"lch_chroma"`` converts to CIELAB (white: the space's own), keeps the hue angle h and
    L* (clamped to [0, 100]), and reduces C* by bisection to the largest chroma in gamut
    (``iterations`` halvings: precision ``C / 2**iterations``); in-gamut colours are
    unchanged. This is the hue-preserving chroma reduction of Morovič (2008), *Color Gamut
    Mapping*, §10.2 ("HPMINDE along lines of constant L* and h").

    Examples
    --------
    >>> from imageform.color import linear_rgb_to_xyz
    >>> p3_green = linear_rgb_to_xyz([0.0, 1.0, 0.0], "display_p3")
    >>> [round(float(v), 3) for v in gamut_map(p3_green, "srgb")]
    [0.0, 0.966, 0.013]
    """
    from imageform.color.cielab import lab_to_lch, lab_to_xyz, lch_to_lab, xyz_to_lab

    m = check_name(method, GAMUT_MAPPING_METHODS, "gamut mapping method")
    sp = rgb_space(space)
    xp = namespace(xyz)
    v = as_points_strict(xyz, "xyz", 3, xp=xp)
    to_rgb_t = _const(np.linalg.inv(sp.matrix_to_xyz()).T, v, xp)
    rgb = v @ to_rgb_t
    if m == "clip":
        return xp.clip(rgb, 0.0, 1.0)
    iterations = as_int(iterations, "iterations", minimum=1, maximum=200)
    white = sp.white_xy
    lch = lab_to_lch(xyz_to_lab(v, white))
    inside = xp.all((rgb >= 0.0) & (rgb <= 1.0), axis=-1)
    L = xp.clip(lch[..., 0], 0.0, 100.0)
    h = lch[..., 2]

    def rgb_of(c: Any) -> Any:
        lab = lch_to_lab(xp.stack([L, c, h], axis=-1))
        return lab_to_xyz(lab, white) @ to_rgb_t

    lo = xp.zeros_like(L)
    hi = lch[..., 1]
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        r = rgb_of(mid)
        ok = xp.all((r >= -1e-12) & (r <= 1.0 + 1e-12), axis=-1)
        lo = xp.where(ok, mid, lo)
        hi = xp.where(ok, hi, mid)
    mapped = rgb_of(lo)
    # lo is in gamut to 1e-12 by construction: the clip below removes rounding only.
    mapped = xp.clip(mapped, 0.0, 1.0)
    return xp.where(inside[..., None], rgb, mapped)


def _names() -> tuple[str, ...]:
    return tuple(RGB_SPACES)
