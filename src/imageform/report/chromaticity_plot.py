"""The chromaticity diagram: horseshoe in locus colours, gamut triangles, Planckian locus.

matplotlib is imported inside :func:`plot_chromaticity_diagram` (the optional ``plot`` extra:
``pip install imageform[plot]``).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import (
    as_bool,
    as_int,
    as_real_ndarray,
    check_memory,
    check_name,
    describe,
)
from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["CCT_TICKS", "planckian_locus", "plot_chromaticity_diagram"]

#: The finest horseshoe grid :func:`plot_chromaticity_diagram` draws (``resolution``² points).
MAX_RESOLUTION = 4000

#: The coolest black body :func:`planckian_locus` takes (K): below it the CIE integral of
#: Planck's law underflows (the chromaticity has long reached the red end of the locus).
MIN_TEMPERATURE = 100.0

#: Temperatures (K) marked on the Planckian locus.
CCT_TICKS = (1500.0, 2000.0, 2856.0, 4000.0, 5000.0, 6500.0, 10000.0)


def planckian_locus(
    temperatures: Sequence[float] | np.ndarray, coords: str = "xy", *, observer: int = 2
) -> np.ndarray:
    """Return the chromaticities (N, 2) of black bodies, integrated from Planck's law.

    Planck's law (CIE 015:2018 eq. 4.1) is integrated with the CIE colour-matching functions.

    Examples
    --------
    >>> [round(float(v), 4) for v in planckian_locus([2856.0])[0]]
    [0.4475, 0.4074]
    """
    from imageform.color.chromaticity import xy_to_uv_prime

    c = check_name(coords, ("xy", "uv"), "chromaticity diagram", "coords")
    temps = as_real_ndarray(temperatures, "temperatures", ndim=(0, 1)).ravel()
    if temps.size and (temps.min() < MIN_TEMPERATURE or temps.max() > 1e6):
        raise InvalidInputError(
            f"expected temperatures in [{MIN_TEMPERATURE:g}, 1e6] K, got "
            f"{temps.min():g}..{temps.max():g}"
        )
    # the standard observers' values are cached; anything else is checked where it was
    known = type(observer) is int and observer in (2, 10)
    planck = _planck_xy if known else _planck_xy.__wrapped__
    xy = np.array([planck(float(t), observer) for t in temps]).reshape(-1, 2)
    return xy if c == "xy" else np.asarray(xy_to_uv_prime(xy))


@functools.lru_cache(maxsize=1024)
def _planck_xy(temperature: float, observer: Any) -> tuple[float, float]:
    """Return the xy of one black body (cached: every report draws the same temperatures)."""
    from imageform.spectral.illuminants import blackbody_spectrum
    from imageform.spectral.integrate import spectrum_to_xyz

    xyz = spectrum_to_xyz(
        blackbody_spectrum(temperature, np.arange(360.0, 831.0)),
        illuminant=None,
        observer=observer,
    )
    return float(xyz[0] / xyz.sum()), float(xyz[1] / xyz.sum())


@functools.lru_cache(maxsize=4)
def _horseshoe_image(coords: str, n: int) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """RGBA image of the visible region, each point in its (brightest in-gamut) sRGB colour.

    Computed once per process for each (coords, n) and returned read-only.
    """
    from matplotlib.path import Path as MplPath

    from imageform.color.chromaticity import spectral_locus, uv_prime_to_xy
    from imageform.color.rgb_spaces import xyz_to_rgb_matrix
    from imageform.color.transfer import linear_to_srgb

    ext = (0.0, 0.8, 0.0, 0.9) if coords == "xy" else (0.0, 0.65, 0.0, 0.65)
    xs = np.linspace(ext[0], ext[1], n)
    ys = np.linspace(ext[2], ext[3], n)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx, gy], axis=-1)
    # matplotlib's point-in-polygon (compiled) instead of imageform.color.in_locus (numpy,
    # points x edges): ~30x faster here, and a picture does not mind the boundary pixels
    locus = spectral_locus(coords=coords).chromaticities
    inside = MplPath(locus, closed=False).contains_points(pts.reshape(-1, 2)).reshape(n, n)
    xy = pts if coords == "xy" else np.asarray(uv_prime_to_xy(pts))
    y = np.where(xy[..., 1] > 1e-6, xy[..., 1], 1e-6)
    xyz = np.stack([xy[..., 0] / y, np.ones_like(y), (1 - xy[..., 0] - xy[..., 1]) / y], -1)
    rgb = xyz @ xyz_to_rgb_matrix("srgb").T
    # Display only: out-of-gamut chromaticities are shown desaturated towards white and
    # scaled to the brightest displayable value (a picture cannot show them).
    rgb = rgb - np.minimum(rgb.min(axis=-1, keepdims=True), 0.0)
    rgb = rgb / np.max(rgb, axis=-1, keepdims=True)
    img = np.concatenate([np.asarray(linear_to_srgb(rgb)), inside[..., None] * 1.0], axis=-1)
    img = np.clip(img, 0.0, 1.0)
    img.flags.writeable = False
    return img, ext


def plot_chromaticity_diagram(
    spaces: Sequence[str] = ("srgb", "display_p3", "rec2020"),
    *,
    coords: str = "xy",
    points: ArrayLike | None = None,
    point_labels: Sequence[str] | None = None,
    planckian: bool = True,
    observer: int = 2,
    resolution: int = 300,
    ax: Axes | None = None,
    path: str | Path | None = None,
) -> Figure:
    """Draw the CIE 1931 xy (or 1976 u'v') chromaticity diagram; returns the Figure.

    The spectral locus (CIE 015:2018 CMFs) is filled with approximate colours (display only:
    outside sRGB they are desaturated), wavelengths are marked every 20 nm from 460 to 620 nm,
    each RGB space's gamut triangle is drawn, the Planckian locus carries CCT ticks, and
    user ``points`` (shape (n, 2) in the same coordinates) are plotted.

    Parameters
    ----------
    spaces : sequence of str
        Names of RGB spaces (``imageform.color.RGB_SPACES``) whose gamuts are drawn.
    coords : {"xy", "uv"}, keyword-only
        CIE 1931 ``xy`` or CIE 1976 UCS ``u'v'``.
    points : array_like (n, 2), optional
        Chromaticities to mark, in ``coords``.
    point_labels : sequence of str, optional
        One label per point.
    planckian : bool, keyword-only
        Draw the Planckian locus with CCT ticks.
    observer : {2, 10}, keyword-only
        The standard observer of the spectral locus.
    resolution : int, keyword-only
        Samples per axis of the filled background.
    ax : matplotlib Axes, optional
        Draw into these axes (default: a new figure).
    path : str or Path, optional
        Where to save the figure (PNG, SVG or PDF, by the suffix).

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> fig = plot_chromaticity_diagram(["srgb"], points=[[0.3127, 0.3290]])
    >>> len(fig.axes)
    1
    """
    from imageform.color.chromaticity import spectral_locus
    from imageform.color.gamut import gamut_triangle
    from imageform.color.rgb_spaces import rgb_space

    # every argument is checked before matplotlib is imported (seconds on a cold start)
    if path is not None:
        from imageform._files import check_writable

        check_writable(path, "path")
    c = check_name(coords, ("xy", "uv"), "chromaticity diagram", "coords")
    n_grid = as_int(resolution, "resolution", minimum=2, maximum=MAX_RESOLUTION)
    # the grid's points, xyz, rgb and the RGBA picture: about 16 float64 values per point
    check_memory(16.0 * 8 * n_grid * n_grid, "resolution", f"a {n_grid}x{n_grid} diagram")
    if isinstance(spaces, str | bytes) or not isinstance(spaces, Iterable):
        raise TypeError(f"expected spaces as a sequence of RGB space names, got {describe(spaces)}")
    space_objs = [rgb_space(s) for s in spaces]
    as_bool(planckian, "planckian")
    pts = None
    if points is not None:
        pts = as_real_ndarray(points, "points", last=2)
        pts = pts.reshape(-1, 2)
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - the plot extra is installed in tests
        raise InvalidInputError("plotting needs matplotlib: pip install 'imageform[plot]'") from exc
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.5, 6.5))
    else:
        from matplotlib.axes import Axes

        if not isinstance(ax, Axes):
            raise TypeError(f"expected ax as matplotlib Axes (or None), got {describe(ax)}")
        fig = ax.figure  # type: ignore[assignment]
    img, ext = _horseshoe_image(c, n_grid)
    ax.imshow(img, origin="lower", extent=ext, interpolation="bilinear")
    wl, locus = spectral_locus(observer=observer, coords=c)
    closed = np.vstack([locus, locus[:1]])
    ax.plot(closed[:, 0], closed[:, 1], color="k", lw=1.0)
    for w in range(460, 621, 20):
        p = locus[np.argmin(np.abs(wl - w))]
        ax.annotate(f"{w}", p, textcoords="offset points", xytext=(4, 2), fontsize=7)
    styles = ["-", "--", "-.", ":"]
    for i, sp in enumerate(space_objs):
        tri = gamut_triangle(sp, c)
        t = np.vstack([tri, tri[:1]])
        ax.plot(t[:, 0], t[:, 1], styles[i % 4], color="k", lw=1.2, label=sp.name)
    if planckian:
        temps = np.geomspace(1000.0, 25000.0, 60)
        pl = planckian_locus(temps, c, observer=observer)
        ax.plot(pl[:, 0], pl[:, 1], color="0.25", lw=1.0, label="Planckian locus")
        ticks = planckian_locus(CCT_TICKS, c, observer=observer)
        ax.plot(ticks[:, 0], ticks[:, 1], "o", ms=2.5, color="0.25")
        for t_k, p in zip(CCT_TICKS, ticks, strict=True):
            ax.annotate(f"{t_k:g} K", p, textcoords="offset points", xytext=(3, -9), fontsize=6)
    if pts is not None:
        ax.plot(pts[:, 0], pts[:, 1], "o", mfc="w", mec="k", ms=5, label="points")
        for lab, p in zip(point_labels or [], pts, strict=False):
            ax.annotate(lab, p, textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.set_xlabel("x" if c == "xy" else "u'")
    ax.set_ylabel("y" if c == "xy" else "v'")
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=7)
    ax.set_title(
        f"CIE {'1931 xy' if c == 'xy' else '1976 u′v′'} chromaticity diagram ({observer}° observer)"
    )
    if path is not None:
        fig.savefig(path, dpi=150, bbox_inches="tight")
    return fig
