"""Loaders for the spectral tables shipped in ``imageform/spectral/data/`` (CSV).

Each CSV names its source in ``#`` header lines (CIE 015:2018 tables, Stockman & Sharpe (2000),
BabelColor, NPL camera sensitivities); :func:`table_source` returns them. The tables were
exported once by ``tools/extract_spectral_tables.py``; nothing is downloaded at run time.
"""

from __future__ import annotations

from functools import cache, lru_cache
from importlib import resources
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from imageform._validate import check_name, check_option, describe
from imageform.errors import InvalidInputError
from imageform.spectral.spectrum import Spectrum

__all__ = [
    "CAMERAS",
    "COLORCHECKER_PATCHES",
    "ILLUMINANT_TABLES",
    "LED_SPECTRA",
    "TABLES",
    "DataTable",
    "camera_sensitivities",
    "cmfs",
    "colorchecker_published_xyy",
    "colorchecker_reflectances",
    "cone_fundamentals",
    "illuminant_table",
    "led_spectrum",
    "load_table",
    "luminous_efficiency",
    "read_table",
    "table_source",
]

#: The shipped CSV tables by key.
TABLES = MappingProxyType(
    {
        "cmf_2": "cmf_cie1931_2deg.csv",
        "cmf_10": "cmf_cie1964_10deg.csv",
        "cones_ss2": "cones_stockman_sharpe_2deg.csv",
        "v_photopic": "vlambda_photopic.csv",
        "v_scotopic": "vlambda_scotopic.csv",
        "A": "illuminant_A.csv",
        "B": "illuminant_B.csv",
        "C": "illuminant_C.csv",
        "D50": "illuminant_D50.csv",
        "D65": "illuminant_D65.csv",
        "F2": "illuminant_F2.csv",
        "F11": "illuminant_F11.csv",
        "daylight_basis": "daylight_basis.csv",
        "led": "led_cie2018.csv",
        "colorchecker": "colorchecker_babelcolor_average.csv",
        "colorchecker_published": "colorchecker_published_xyY_d50.csv",
        "nikon_d5100": "camera_nikon_d5100_npl.csv",
        "viridis": "viridis.csv",
        "cvd_machado2009": "cvd_machado2009.csv",
    }
)
#: Tabulated CIE illuminants (CIE 015:2018 Tables 1 and 10.1; B: CIE 15.2:1986 Table 1.1;
#: C: CIE 15:2004 Table T.1).
ILLUMINANT_TABLES = ("A", "B", "C", "D50", "D65", "F2", "F11")
#: CIE 015:2018 Table 11 white-LED illuminants.
LED_SPECTRA = (
    "LED-B1",
    "LED-B2",
    "LED-B3",
    "LED-B4",
    "LED-B5",
    "LED-BH1",
    "LED-RGB1",
    "LED-V1",
    "LED-V2",
)
#: Measured camera sensitivities shipped.
CAMERAS = ("nikon_d5100",)


def _text(filename: str) -> str:
    return resources.files("imageform.spectral").joinpath("data", filename).read_text("utf-8")


@cache
def _parse(key: str) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray, tuple[str, ...]]:
    """(comments, column names, numeric array, first-column strings) of a table."""
    lines = _text(TABLES[key]).splitlines()
    comments = tuple(ln[1:].strip() for ln in lines if ln.startswith("#"))
    body = [ln for ln in lines if ln and not ln.startswith("#")]
    header = tuple(body[0].split(","))
    rows = [ln.split(",") for ln in body[1:]]
    first = tuple(r[0] for r in rows)
    if header[0] in ("wavelength_nm", "r"):
        arr = np.array([[float(v) for v in r] for r in rows])
    else:
        arr = np.array([[float(v) for v in r[1:]] for r in rows])
    arr.setflags(write=False)
    return comments, header, arr, first


class DataTable(NamedTuple):
    """A shipped CSV table as read.

    ``comments`` (its ``#`` header lines: source and notes), ``columns`` (the column names),
    ``values`` (the numeric columns, read-only float64; every column when the first is
    numeric, else all but the first) and ``labels`` (the first column's entries as strings).
    """

    comments: tuple[str, ...]
    columns: tuple[str, ...]
    values: np.ndarray
    labels: tuple[str, ...]


def read_table(key: str) -> DataTable:
    """Read any shipped table by its key in :data:`TABLES`.

    This includes those that are not wavelength tables (the viridis colour map, the Machado
    et al. (2009) CVD matrices); :func:`load_table` gives a wavelength table as a
    :class:`Spectrum`.

    Examples
    --------
    >>> t = read_table("cvd_machado2009")
    >>> t.columns[:3], t.labels[0], t.values.shape
    (('deficiency', 'severity', 'm00'), 'protan', (33, 10))
    """
    k = (
        key
        if isinstance(key, str) and key in TABLES
        else check_name(key, TABLES, "spectral table", "key")
    )
    return DataTable(*_parse(k))


def table_source(key: str) -> str:
    """Return the header (source and notes) of a shipped table.

    Examples
    --------
    >>> table_source("cmf_2").startswith("source: CIE 015:2018")
    True
    """
    k = (
        key
        if isinstance(key, str) and key in TABLES
        else check_name(key, TABLES, "spectral table", "key")
    )
    return "\n".join(_parse(k)[0])


def load_table(key: str, name: str = "") -> Spectrum:
    """Load a shipped wavelength table as a :class:`Spectrum` (one curve or K labelled curves).

    Spectra are immutable (read-only arrays), so one cached object per table is shared.
    """
    k = (
        key
        if isinstance(key, str) and key in TABLES
        else check_name(key, TABLES, "spectral table", "key")
    )
    if not isinstance(name, str):
        raise TypeError(f"expected name as a display name (str), got {describe(name)}")
    return _load_table(k, name)


@lru_cache(maxsize=64)
def _load_table(k: str, name: str) -> Spectrum:
    _, header, arr, _ = _parse(k)
    if header[0] != "wavelength_nm":
        raise InvalidInputError(f"table {k!r} is not a wavelength table")
    labels = header[1:]
    if len(labels) == 1:
        return Spectrum(arr[:, 0], arr[:, 1], name=name or labels[0])
    return Spectrum(arr[:, 0], arr[:, 1:], name=name or k, labels=labels)


def cmfs(observer: int | str = 2) -> Spectrum:
    r"""CIE colour-matching functions :math:`\bar x, \bar y, \bar z`, 360-830 nm at 1 nm.

    ``observer`` 2 (CIE 1931) or 10 (CIE 1964); source CIE 015:2018 Tables 4-5.

    Examples
    --------
    >>> round(float(cmfs(2).interpolate([555]).values[0, 1]), 6)
    1.0
    """
    obs = str(observer).removesuffix("deg").removesuffix("°")
    key = check_option(obs, ("2", "10"), "observer")
    name = "CIE 1931 2°" if key == "2" else "CIE 1964 10°"
    return load_table(f"cmf_{key}", name)


def luminous_efficiency(kind: str = "photopic") -> Spectrum:
    """CIE photopic V(λ) (1924, 360-830 nm) or scotopic V'(λ) (1951, 380-780 nm), 1 nm.

    Examples
    --------
    >>> luminous_efficiency("scotopic").peak_wavelength()
    507.0
    """
    k = check_name(kind, ("photopic", "scotopic"), "luminous efficiency", "kind")
    return load_table("v_photopic" if k == "photopic" else "v_scotopic", f"V {k}")


def cone_fundamentals() -> Spectrum:
    """Stockman & Sharpe (2000) 2° cone fundamentals L, M, S (energy units, peak 1), 1 nm.

    Examples
    --------
    >>> [round(float(p)) for p in cone_fundamentals().peak_wavelength()]
    [570, 543, 442]
    """
    return load_table("cones_ss2", "Stockman & Sharpe 2°")


def illuminant_table(name: str) -> Spectrum:
    """Return a tabulated CIE illuminant, 5 nm.

    A, D50, D65 (100 at 560 nm); B, C (the old CIE daylight simulators, as tabulated: 102.8
    and 105.3 at 560 nm); F2, F11 (relative).

    Examples
    --------
    >>> illuminant_table("C").name
    'CIE C'
    """
    if not isinstance(name, str):
        raise TypeError(f"expected name as an illuminant table name (str), got {describe(name)}")
    key = name.strip().upper().replace("FL", "F")
    if key not in ILLUMINANT_TABLES:
        raise InvalidInputError(
            f"unknown illuminant table {describe(name, 30)} for name; "
            f"valid: {', '.join(map(repr, ILLUMINANT_TABLES))}"
        )
    return load_table(key, f"CIE {key}")


def led_spectrum(name: str = "LED-B3") -> Spectrum:
    """Return a CIE 015:2018 Table 11 white-LED spectrum (LED-B1 ... LED-V2), 5 nm."""
    if not isinstance(name, str):
        raise TypeError(f"expected name as an LED spectrum name (str), got {describe(name)}")
    key = name.strip().upper().replace("_", "-")
    if key not in LED_SPECTRA:
        raise InvalidInputError(
            f"unknown LED spectrum {describe(name, 30)} for name; "
            f"valid: {', '.join(map(repr, LED_SPECTRA))}"
        )
    return load_table("led")[key]


def camera_sensitivities(camera: str = "nikon_d5100") -> Spectrum:
    """Measured RGB spectral sensitivities of a camera (NPL, Darrodi et al. 2015), 5 nm."""
    key = check_option(camera, CAMERAS, "camera")
    return load_table(key, "Nikon D5100 (NPL)")


def colorchecker_reflectances() -> Spectrum:
    """Return the 24 ColorChecker reflectances (BabelColor average, 380-730 nm, 10 nm), (36, 24)."""
    return load_table("colorchecker", "ColorChecker (BabelColor average)")


#: Names of the 24 ColorChecker patches in chart order.
COLORCHECKER_PATCHES: tuple[str, ...] = tuple(_parse("colorchecker")[1][1:])


def colorchecker_published_xyy(table: str = "babelcolor") -> np.ndarray:
    """Return the published ColorChecker xyY under D50 (2°), shape (24, 3), Y in [0, 1].

    ``"babelcolor"``: BabelColor average (Pascale 2006), published as L*a*b* D50 and computed
    by BabelColor from the same average spectra shipped here; ``"xrite2014"``: X-Rite's values
    for charts made after November 2014.
    """
    t = check_option(table, ("babelcolor", "xrite2014"), "ColorChecker table")
    arr = _parse("colorchecker_published")[2]
    return np.array(arr[:, :3] if t == "babelcolor" else arr[:, 3:])
