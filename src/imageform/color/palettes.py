"""Palettes (viridis, Okabe-Ito) and a colour-vision-deficiency check of a palette.

:func:`palette_check` reports the smallest pairwise CIEDE2000 difference among a palette's
colours for normal vision and as simulated for protan, deutan and tritan dichromats
(:func:`imageform.color.simulate_cvd`). A palette whose colours must be told apart (a
categorical map, a legend) fails where that smallest difference drops below a threshold.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from types import MappingProxyType
from typing import Any

import numpy as np

from imageform._backend import device_of, to_numpy
from imageform._typing import ArrayLike
from imageform._validate import as_image_strict, as_int, as_real, check_name, describe
from imageform.errors import InvalidInputError

__all__ = [
    "OKABE_ITO",
    "PALETTES",
    "RED_GREEN",
    "PaletteCheck",
    "palette",
    "palette_check",
    "parse_colors",
    "viridis",
]

#: Okabe & Ito (2008), *Color Universal Design (CUD): how to make figures and presentations
#: that are friendly to colorblind people*, J*Fly; the eight colours as hex sRGB.
OKABE_ITO: MappingProxyType[str, str] = MappingProxyType(
    {
        "black": "#000000",
        "orange": "#E69F00",
        "sky_blue": "#56B4E9",
        "bluish_green": "#009E73",
        "yellow": "#F0E442",
        "blue": "#0072B2",
        "vermillion": "#D55E00",
        "reddish_purple": "#CC79A7",
    }
)
#: A red-yellow-green diverging map (ColorBrewer RdYlGn, 5 classes; Harrower & Brewer 2003):
#: the kind of map that fails for deutan and protan observers.
RED_GREEN: tuple[str, ...] = ("#D7191C", "#FDAE61", "#FFFFBF", "#A6D96A", "#1A9641")
PALETTES = ("viridis", "okabe_ito", "red_green")


@lru_cache(maxsize=1)
def _viridis() -> np.ndarray:
    from imageform.spectral.data import read_table

    arr = np.array(read_table("viridis").values)
    arr.setflags(write=False)
    return arr


def viridis(n: int = 256) -> np.ndarray:
    """``n`` colours of viridis (van der Walt & Smith 2015), evenly spaced, encoded sRGB (n, 3).

    Examples
    --------
    >>> viridis(2).round(4).tolist()
    [[0.267, 0.0049, 0.3294], [0.9932, 0.9062, 0.1439]]
    """
    if isinstance(n, bool | np.bool_) or not isinstance(n, int | np.integer) or not 1 <= n <= 256:
        raise InvalidInputError(f"expected 1 <= n <= 256 viridis colours, got {n!r}")
    idx = np.round(np.linspace(0, 255, int(n))).astype(int)
    return np.array(_viridis()[idx])


def parse_colors(colors: str | Sequence[str] | ArrayLike) -> np.ndarray:
    """Parse colours into encoded sRGB floats (n, 3).

    Hex strings (``"#E69F00"``, ``"E69F00"``, ``"#E90"``), one comma-separated string, or an
    array of shape (n, 3) (floats in [0, 1] or uint8).

    Examples
    --------
    >>> parse_colors("#E69F00,#56B4E9").round(4).tolist()
    [[0.902, 0.6235, 0.0], [0.3373, 0.7059, 0.9137]]
    """
    if isinstance(colors, str):
        colors = [c for c in colors.split(",") if c.strip()]
    if isinstance(colors, Sequence) and colors and all(isinstance(c, str) for c in colors):
        out = []
        for c in colors:
            h = str(c).strip().removeprefix("#")
            if len(h) == 3:
                h = "".join(ch * 2 for ch in h)
            if len(h) != 6 or any(ch not in "0123456789abcdefABCDEF" for ch in h):
                raise InvalidInputError(
                    f"expected a hex colour like '#E69F00' in colors, got {describe(c, 30)}"
                )
            out.append([int(h[i : i + 2], 16) / 255.0 for i in (0, 2, 4)])
        return np.array(out)
    if device_of(colors) is not None:  # a report on the host: one explicit copy of n colours
        colors = to_numpy(colors)
    arr = np.asarray(as_image_strict(colors, "colors"), dtype=np.float64)
    if arr.ndim != 2:
        raise InvalidInputError(f"expected colors of shape (n, 3), got {arr.shape}")
    if np.any(arr < 0) or np.any(arr > 1):
        raise InvalidInputError("expected colors as encoded sRGB in [0, 1]")
    return arr


def palette(name: str, n: int | None = None) -> np.ndarray:
    """Return a named palette as encoded sRGB (n, 3).

    ``viridis`` (n evenly spaced, default 8), ``okabe_ito`` (the first n of 8), ``red_green``
    (ColorBrewer RdYlGn, 5).

    Examples
    --------
    >>> palette("okabe_ito", 2).round(3).tolist()
    [[0.0, 0.0, 0.0], [0.902, 0.624, 0.0]]
    """
    key = check_name(name, PALETTES, "palette", "name")
    if n is not None:
        n = as_int(n, "n", minimum=1)
    if key == "viridis":
        return viridis(8 if n is None else n)
    colors = list(OKABE_ITO.values()) if key == "okabe_ito" else list(RED_GREEN)
    k = len(colors) if n is None else n
    if not 1 <= k <= len(colors):
        raise InvalidInputError(f"palette {key!r} has {len(colors)} colours, asked for {n}")
    return parse_colors(colors[:k])


@dataclass(frozen=True)
class PaletteCheck:
    """Result of :func:`palette_check`: per condition, the smallest pairwise ΔE00 and its pair.

    ``conditions`` are ``"normal"``, ``"protan"``, ``"deutan"``, ``"tritan"``.
    """

    colors: np.ndarray
    min_delta_e: dict[str, float]
    closest_pair: dict[str, tuple[int, int]]
    threshold: float
    simulated: dict[str, np.ndarray] = field(repr=False)

    @property
    def passes(self) -> dict[str, bool]:
        """Per condition: whether the smallest difference is at least the threshold."""
        return {k: v >= self.threshold for k, v in self.min_delta_e.items()}

    @property
    def ok(self) -> bool:
        """True when every condition passes."""
        return all(self.passes.values())

    def as_dict(self) -> dict[str, Any]:
        """Return the report as a JSON-ready dict (closest pairs as lists)."""
        return {
            "threshold": self.threshold,
            "min_delta_e": self.min_delta_e,
            "closest_pair": {k: list(v) for k, v in self.closest_pair.items()},
            "passes": self.passes,
            "ok": self.ok,
        }


def palette_check(
    colors: str | Sequence[str] | ArrayLike,
    *,
    threshold: float = 10.0,
    method: str = "machado2009",
    severity: float = 1.0,
) -> PaletteCheck:
    r"""Smallest pairwise CIEDE2000 difference of a palette, normal and under each deficiency.

    .. math:: d_c = \min_{i<j} \Delta E_{00}\big(\mathrm{Lab}(\mathrm{sim}_c(p_i)),
              \mathrm{Lab}(\mathrm{sim}_c(p_j))\big)

    The simulated colours (:func:`imageform.color.simulate_cvd`, ``method``, ``severity``)
    are clipped to the sRGB cube (``clip=True``), as a display would show them; Lab is CIELAB
    D65 from sRGB. A condition passes when :math:`d_c \ge` ``threshold`` (default 10: a
    difference readily named, not just noticed; choose your own).

    Returns
    -------
    PaletteCheck

    Examples
    --------
    >>> r = palette_check(palette("okabe_ito"))
    >>> {k: round(v, 1) for k, v in r.min_delta_e.items()}
    {'normal': 21.7, 'protan': 12.2, 'deutan': 11.6, 'tritan': 10.9}
    >>> palette_check(RED_GREEN).passes["deutan"]
    False
    """
    from imageform.color.convert import convert
    from imageform.color.cvd import CVD_DEFICIENCIES, simulate_cvd
    from imageform.color.delta_e import delta_e_ciede2000

    threshold = as_real(threshold, "threshold", nonnegative=True)
    rgb = parse_colors(colors)
    if rgb.shape[0] > 4096:
        raise InvalidInputError(
            f"expected colors with at most 4096 colours (pairwise ΔE), got {rgb.shape[0]}"
        )
    if rgb.shape[0] < 2:
        raise InvalidInputError(f"expected at least 2 colours to compare, got {rgb.shape[0]}")
    i, j = np.triu_indices(rgb.shape[0], 1)
    mins: dict[str, float] = {}
    pairs: dict[str, tuple[int, int]] = {}
    sims: dict[str, np.ndarray] = {}
    for cond in ("normal", *CVD_DEFICIENCIES):
        sim = rgb if cond == "normal" else simulate_cvd(rgb, cond, severity, method, clip=True)
        lab = np.asarray(convert(sim, "srgb", "lab"))
        de = np.asarray(delta_e_ciede2000(lab[i], lab[j]))
        k = int(np.argmin(de))
        mins[cond], pairs[cond], sims[cond] = float(de[k]), (int(i[k]), int(j[k])), sim
    return PaletteCheck(rgb, mins, pairs, float(threshold), sims)
