"""The camera file's measured-camera tables: ``[sensor]``, ``[optics]`` and ``[color]``.

``[sensor]`` is the EMVA 1288 noise model, ``[optics]`` the lens's blur and ``[color]`` the
colour model; each table is optional.

Each table is a small frozen dataclass (:class:`CameraSensor`, :class:`CameraOptics`,
:class:`CameraColor`) whose fields are the table's keys, with the units in their names;
every field is checked when the dataclass is built (from a file or from Python), with
one-line errors naming the table and the key. ``None`` marks a key that is absent (the
simulator then keeps its own value). The schema is in docs/camera-file.md.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np

from imageform._validate import describe
from imageform.errors import UnknownOptionError
from imageform.io._camera_toml import Reader, _show, toml_value

__all__ = [
    "CCM_TARGETS",
    "OPTICS_MODELS",
    "CameraColor",
    "CameraOptics",
    "CameraSensitivity",
    "CameraSensor",
    "as_table",
    "table_lines",
]

#: Blur models of ``[optics] model``.
OPTICS_MODELS: tuple[str, ...] = ("diffraction", "gaussian", "zernike", "mtf50")
#: What ``[color] ccm`` maps white-balanced camera RGB to (``ccm_to``).
CCM_TARGETS: tuple[str, ...] = ("linear_srgb", "xyz")
# Bayer patterns (imageform.sensor.CFA_PATTERNS; repeated so that importing io stays cheap,
# checked equal in tests/io/test_camera_tables.py).
_CFA = ("RGGB", "BGGR", "GRBG", "GBRG")


def _reader(r: Reader | None, owner: str) -> Reader:
    if r is not None and not isinstance(r, Reader):
        raise TypeError(f"expected r as the camera file's Reader (or None), got {describe(r)}")
    return r if r is not None else Reader(owner)


def _nonneg(r: Reader, value: Any, key: str) -> float:
    v = r.number(value, key)
    if v < 0:
        raise r.fail(key, f"expected a number >= 0, got {v:g}")
    return v


#: The Nyquist frequency of the pixel grid (cycles/pixel): the largest MTF50 a file may give.
#: An MTF50 lies below the sampling frequency: a pixel's own aperture (a square of 100 % fill
#: factor, MTF sinc(f)) halves the contrast at 0.60 cycles/pixel, beyond Nyquist (0.5), so a
#: sharp sensor without an anti-aliasing filter can measure MTF50 above 0.5; its MTF is 0 at
#: 1 cycle/pixel.
_SAMPLING_CY_PER_PX = 1.0


def _mtf50(r: Reader, value: Any, key: str) -> float:
    v = r.positive(value, key)
    if not v < _SAMPLING_CY_PER_PX:
        raise r.fail(
            key,
            f"expected an MTF50 in (0, 1) cycles/pixel (below the sampling frequency), got {v:.4g}",
        )
    return v


def _fraction(r: Reader, value: Any, key: str, *, zero: bool = True) -> float:
    v = r.number(value, key)
    if not ((v >= 0 if zero else v > 0) and v <= 1):
        raise r.fail(key, f"expected a fraction in {'[0' if zero else '(0'}, 1], got {v:g}")
    return v


def _int(r: Reader, value: Any, key: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise r.fail(key, f"expected an integer in [{lo}, {hi}], got {_show(value)}")
    return int(value)


def _list(value: Any) -> Any:
    """Tuples and arrays as lists (what TOML gives), anything else unchanged."""
    if isinstance(value, (tuple, np.ndarray)):
        return [_list(v) for v in value]
    if isinstance(value, list):
        return [_list(v) for v in value]
    return value


def _numbers(r: Reader, value: Any, key: str, *, minimum: int = 1) -> tuple[float, ...]:
    value = _list(value)
    if not isinstance(value, list) or len(value) < minimum:
        raise r.fail(key, f"expected a list of at least {minimum} numbers, got {_show(value)}")
    return tuple(r.number(v, f"{key}[{i}]") for i, v in enumerate(value))


def _zones(r: Reader, value: Any, k: str) -> tuple[tuple[tuple[float, ...], ...], ...]:
    """Check ``zernike_zones``: rows x cols (at most 16 each, equal rows) of Noll lists."""
    key = k + "zernike_zones"
    rows = _list(value)
    if not isinstance(rows, list) or not 1 <= len(rows) <= 16:
        raise r.fail(key, f"expected 1 to 16 rows of zones, got {_show(rows)}")
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, list) or not 1 <= len(row) <= 16:
            raise r.fail(f"{key}[{i}]", f"expected 1 to 16 zones, got {_show(row)}")
        if len(row) != len(rows[0]):
            raise r.fail(f"{key}[{i}]", f"expected {len(rows[0])} zones as row 0, got {len(row)}")
        zones = tuple(_numbers(r, z, f"{key}[{i}][{j}]") for j, z in enumerate(row))
        if max(len(z) for z in zones) > 66:
            raise r.fail(f"{key}[{i}]", "expected at most 66 Noll terms per zone")
        out.append(zones)
    return tuple(out)


class _Table:
    """The shared part of the three tables: the table's name, checks, and conversions."""

    TABLE: ClassVar[str] = ""

    def _check(self, r: Reader) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __post_init__(self) -> None:
        self._check(Reader(type(self).__name__))

    @classmethod
    def from_table(cls, table: Mapping[str, Any], r: Reader | None = None) -> Any:
        """Build the dataclass of a TOML table (a mapping of key to value).

        Unknown keys are refused, listing the valid ones; errors name ``r``'s file, the table
        and the key.
        """
        rr = _reader(r, cls.__name__)
        if not isinstance(table, Mapping):
            raise rr.fail(cls.TABLE, f"expected a table [{cls.TABLE}], got {_show(table)}")
        valid = tuple(f.name for f in fields(cls))  # type: ignore[arg-type]
        rr.known(table, valid, cls.TABLE + ".")
        obj = cls.__new__(cls)
        for name in valid:
            object.__setattr__(obj, name, table.get(name))
        obj._check(rr)
        return obj

    def to_dict(self) -> dict[str, Any]:
        """Return the keys that are set (not None), lists for sequences: the TOML table."""
        out: dict[str, Any] = {}
        for f in fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if v is not None:
                out[f.name] = v.to_dict() if isinstance(v, _Table) else _list(v)
        return out


@dataclass(frozen=True)
class CameraSensor(_Table):
    """``[sensor]``: a sensor's EMVA 1288 (release 4.0) model, every key optional.

    Attributes
    ----------
    system_gain_dn_per_e : float > 0
        Overall system gain K (DN per electron).
    read_noise_e : float >= 0
        Temporal dark noise sigma_d (electrons rms; EMVA's sigma_d includes quantisation
        only when measured so).
    dark_current_e_per_s : float >= 0
        Dark current (electrons per second).
    dsnu_e : float >= 0
        Dark-signal non-uniformity (electrons rms).
    prnu : float in [0, 1]
        Photo-response non-uniformity (a fraction of the signal, rms).
    full_well_e : float > 0
        Saturation capacity (electrons).
    bit_depth : int in [1, 32]
        ADC bits.
    black_level_dn : float >= 0
        Offset of a dark pixel (DN).
    quantum_efficiency : float in (0, 1]
        Peak effective quantum efficiency, as EMVA 1288 measures it (the fill factor and
        microlenses included); the simulator renders it with a fill factor of 1.
    pixel_pitch_um : float > 0
        Pixel pitch (micrometres).
    cfa : str
        Bayer pattern (``RGGB``, ``BGGR``, ``GRBG``, ``GBRG``).
    exposure_time_s : float > 0
        The exposure the sensor was characterised at (seconds).

    Examples
    --------
    >>> CameraSensor(system_gain_dn_per_e=0.5, read_noise_e=2.0).to_dict()
    {'system_gain_dn_per_e': 0.5, 'read_noise_e': 2.0}
    """

    TABLE: ClassVar[str] = "sensor"

    system_gain_dn_per_e: float | None = None
    read_noise_e: float | None = None
    dark_current_e_per_s: float | None = None
    dsnu_e: float | None = None
    prnu: float | None = None
    full_well_e: float | None = None
    bit_depth: int | None = None
    black_level_dn: float | None = None
    quantum_efficiency: float | None = None
    pixel_pitch_um: float | None = None
    cfa: str | None = None
    exposure_time_s: float | None = None

    def _check(self, r: Reader) -> None:
        k = "sensor."
        checks: dict[str, Any] = {
            "system_gain_dn_per_e": lambda v, n: r.positive(v, n, "a gain in DN/e-"),
            "read_noise_e": lambda v, n: _nonneg(r, v, n),
            "dark_current_e_per_s": lambda v, n: _nonneg(r, v, n),
            "dsnu_e": lambda v, n: _nonneg(r, v, n),
            "prnu": lambda v, n: _fraction(r, v, n),
            "full_well_e": lambda v, n: r.positive(v, n, "a capacity in electrons"),
            "bit_depth": lambda v, n: _int(r, v, n, 1, 32),
            "black_level_dn": lambda v, n: _nonneg(r, v, n),
            "quantum_efficiency": lambda v, n: _fraction(r, v, n, zero=False),
            "pixel_pitch_um": lambda v, n: r.positive(v, n, "a pitch in micrometres"),
            "exposure_time_s": lambda v, n: r.positive(v, n, "a time in seconds"),
        }
        for name, fn in checks.items():
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, fn(v, k + name))
        if self.cfa is not None:
            cfa = r.text(self.cfa, k + "cfa").strip().upper()
            if cfa not in _CFA:
                raise UnknownOptionError(
                    f"{r.where}: sensor.cfa: unknown CFA pattern {_show(self.cfa)}; "
                    f"valid: {', '.join(_CFA)}"
                )
            object.__setattr__(self, "cfa", cfa)


@dataclass(frozen=True)
class CameraOptics(_Table):
    """``[optics]``: the lens's blur (its point-spread function), by ``model``.

    Attributes
    ----------
    model : str
        ``"diffraction"`` (the Airy pattern of a circular aperture at ``f_number``),
        ``"zernike"`` (that pupil with the ``zernike`` aberrations, at ``f_number``),
        ``"gaussian"`` (a Gaussian of ``gaussian_sigma_px``) or ``"mtf50"`` (the Gaussian
        whose system MTF50 is ``mtf50_cy_per_px``, what a slanted-edge measurement gives).
        Required.
    f_number : float > 0
        Aperture f-number N (required by ``diffraction`` and ``zernike``).
    focal_length_mm : float > 0
        Lens focal length (millimetres), optional.
    zernike : tuple of float
        Noll-indexed Zernike coefficients in waves (RMS-normalised), the first for j = 1
        (piston), ...; required by ``zernike``.
    zernike_zones : rows x cols x J nested lists of float
        Field-dependent aberrations: the Noll coefficients (waves, as ``zernike``) of each zone
        of a ``rows x cols`` grid over the image, row by row from the top (at most 16 x 16
        zones of 66 terms); the ``zernike`` model then uses them in place of ``zernike`` (one
        of the two is required).
    wavelength_nm : float > 0
        The wavelength the ``zernike`` coefficients (waves) refer to; required by
        ``zernike``.
    gaussian_sigma_px : float >= 0
        The Gaussian PSF's standard deviation (pixels); required by ``gaussian``.
    mtf50_cy_per_px : float or tuple of 3 floats, each in (0, 1)
        Measured MTF50 (cycles per pixel), one for all channels or one per R, G, B;
        required by ``mtf50``.

    Examples
    --------
    >>> CameraOptics(model="mtf50", mtf50_cy_per_px=0.25).to_dict()
    {'model': 'mtf50', 'mtf50_cy_per_px': 0.25}
    """

    TABLE: ClassVar[str] = "optics"

    model: str | None = None
    f_number: float | None = None
    focal_length_mm: float | None = None
    zernike: tuple[float, ...] | None = None
    zernike_zones: tuple[tuple[tuple[float, ...], ...], ...] | None = None
    wavelength_nm: float | None = None
    gaussian_sigma_px: float | None = None
    mtf50_cy_per_px: float | tuple[float, float, float] | None = None

    def _check(self, r: Reader) -> None:
        k = "optics."
        if self.model is None:
            raise r.fail(k + "model", f"missing; valid: {', '.join(OPTICS_MODELS)}")
        model = r.text(self.model, k + "model").strip().lower()
        if model not in OPTICS_MODELS:
            raise UnknownOptionError(
                f"{r.where}: optics.model: unknown optics model {_show(self.model)}; "
                f"valid: {', '.join(OPTICS_MODELS)}"
            )
        object.__setattr__(self, "model", model)
        for name in ("f_number", "focal_length_mm", "wavelength_nm"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, r.positive(v, k + name))
        if self.gaussian_sigma_px is not None:
            sigma = _nonneg(r, self.gaussian_sigma_px, k + "gaussian_sigma_px")
            object.__setattr__(self, "gaussian_sigma_px", sigma)
        if self.zernike is not None:
            z = _numbers(r, self.zernike, k + "zernike")
            if len(z) > 66:
                raise r.fail(k + "zernike", f"expected at most 66 Noll terms, got {len(z)}")
            object.__setattr__(self, "zernike", z)
        if self.zernike_zones is not None:
            object.__setattr__(self, "zernike_zones", _zones(r, self.zernike_zones, k))
        if self.mtf50_cy_per_px is not None:
            v = _list(self.mtf50_cy_per_px)
            key = k + "mtf50_cy_per_px"
            if isinstance(v, list):
                if len(v) != 3:
                    raise r.fail(key, f"expected a number or 3 numbers (R, G, B), got {_show(v)}")
                m: Any = tuple(_mtf50(r, x, f"{key}[{i}]") for i, x in enumerate(v))
            else:
                m = _mtf50(r, v, key)
            object.__setattr__(self, "mtf50_cy_per_px", m)
        if model == "zernike" and self.zernike is None and self.zernike_zones is not None:
            needs_z: tuple[str, ...] = ("f_number", "zernike_zones", "wavelength_nm")
        else:
            needs_z = ("f_number", "zernike", "wavelength_nm")
        needs = {
            "diffraction": ("f_number",),
            "zernike": needs_z,
            "gaussian": ("gaussian_sigma_px",),
            "mtf50": ("mtf50_cy_per_px",),
        }[model]
        missing = [n for n in needs if getattr(self, n) is None]
        if missing:
            raise r.fail(k + missing[0], f"missing (the {model} model needs {', '.join(needs)})")

    def mtf50_rgb(self) -> tuple[float, float, float] | None:
        """``mtf50_cy_per_px`` as three values (R, G, B), None when absent."""
        m = self.mtf50_cy_per_px
        if m is None:
            return None
        return (m, m, m) if isinstance(m, float) else m


@dataclass(frozen=True)
class CameraSensitivity(_Table):
    """``[color.sensitivity]``: estimated spectral sensitivities, R, G, B.

    The curves are on ``wavelengths_nm`` (strictly increasing, > 0; values >= 0, relative).
    """

    TABLE: ClassVar[str] = "color.sensitivity"

    wavelengths_nm: tuple[float, ...] | None = None
    r: tuple[float, ...] | None = None
    g: tuple[float, ...] | None = None
    b: tuple[float, ...] | None = None

    def _check(self, rd: Reader) -> None:
        k = "color.sensitivity."
        for name in ("wavelengths_nm", "r", "g", "b"):
            if getattr(self, name) is None:
                raise rd.fail(k + name, "missing (wavelengths_nm, r, g, b: lists of numbers)")
            vals = _numbers(rd, getattr(self, name), k + name, minimum=2)
            if name != "wavelengths_nm" and min(vals) < 0:
                raise rd.fail(k + name, f"expected values >= 0, got a minimum of {min(vals):g}")
            object.__setattr__(self, name, vals)
        wl = self.wavelengths_nm
        assert wl is not None
        if wl[0] <= 0 or any(b <= a for a, b in itertools.pairwise(wl)):
            raise rd.fail(k + "wavelengths_nm", "expected strictly increasing values > 0")
        for name in ("r", "g", "b"):
            if len(getattr(self, name)) != len(wl):
                raise rd.fail(
                    k + name,
                    f"expected {len(wl)} values (one per wavelength), "
                    f"got {len(getattr(self, name))}",
                )
        if max(max(self.r or ()), max(self.g or ()), max(self.b or ())) <= 0:
            raise rd.fail(k + "r", "expected some sensitivity > 0, got all zeros")

    def to_array(self) -> tuple[np.ndarray, np.ndarray]:
        """(wavelengths (n,), values (n, 3))."""
        return np.array(self.wavelengths_nm), np.array([self.r, self.g, self.b], dtype=float).T


@dataclass(frozen=True)
class CameraColor(_Table):
    """``[color]``: the camera's colour model, every key optional.

    Attributes
    ----------
    ccm : 3 x 3 tuple of float
        Colour-correction matrix (rows) applied to white-balanced, linear camera RGB (column
        vectors: ``out = ccm @ rgb``), giving ``ccm_to``.
    ccm_to : str
        ``"linear_srgb"`` (default when ``ccm`` is given: linear sRGB, D65 white) or
        ``"xyz"`` (CIE XYZ, Y = 1 for the white).
    white_balance : tuple of 3 floats > 0
        Gains applied to camera R, G, B before the ``ccm``.
    illuminant : str
        The light the ``white_balance`` and ``ccm`` were measured under (an
        :func:`imageform.spectral.illuminant` name: ``D65``, ``A``, ``F11`` ...).
    spectral_sensitivity : str
        A shipped camera table (:data:`imageform.spectral.CAMERAS`: ``nikon_d5100``).
    sensitivity : CameraSensitivity
        Estimated sensitivities (``[color.sensitivity]``); not with ``spectral_sensitivity``.

    Examples
    --------
    >>> CameraColor(white_balance=(2.0, 1.0, 1.5), illuminant="D65").to_dict()
    {'white_balance': [2.0, 1.0, 1.5], 'illuminant': 'D65'}
    """

    TABLE: ClassVar[str] = "color"

    ccm: tuple[tuple[float, float, float], ...] | None = None
    ccm_to: str | None = None
    white_balance: tuple[float, float, float] | None = None
    illuminant: str | None = None
    spectral_sensitivity: str | None = None
    sensitivity: CameraSensitivity | None = None

    def _check(self, r: Reader) -> None:
        k = "color."
        if self.ccm is not None:
            m = r.matrix(_list(self.ccm), k + "ccm")
            object.__setattr__(self, "ccm", tuple(tuple(float(x) for x in row) for row in m))
            if self.ccm_to is None:
                object.__setattr__(self, "ccm_to", "linear_srgb")
        if self.ccm_to is not None:
            to = r.text(self.ccm_to, k + "ccm_to").strip().lower()
            if to not in CCM_TARGETS:
                raise UnknownOptionError(
                    f"{r.where}: color.ccm_to: unknown target {_show(self.ccm_to)}; "
                    f"valid: {', '.join(CCM_TARGETS)}"
                )
            if self.ccm is None:
                raise r.fail(k + "ccm_to", "given without a ccm")
            object.__setattr__(self, "ccm_to", to)
        if self.white_balance is not None:
            wb = r.vector(_list(self.white_balance), k + "white_balance")
            if min(wb) <= 0:
                raise r.fail(k + "white_balance", f"expected 3 gains > 0, got {list(wb)}")
            object.__setattr__(self, "white_balance", wb)
        if self.illuminant is not None:
            name = r.text(self.illuminant, k + "illuminant").strip()
            from imageform.spectral import illuminant

            try:
                illuminant(name)
            except Exception as exc:  # the spectral module's own one-line message
                raise r.fail(k + "illuminant", str(exc)[:150]) from None
            object.__setattr__(self, "illuminant", name)
        if self.spectral_sensitivity is not None:
            from imageform.spectral import CAMERAS

            name = r.text(self.spectral_sensitivity, k + "spectral_sensitivity").strip().lower()
            if name not in CAMERAS:
                raise UnknownOptionError(
                    f"{r.where}: color.spectral_sensitivity: unknown camera table "
                    f"{_show(self.spectral_sensitivity)}; valid: {', '.join(CAMERAS)} "
                    "(or a [color.sensitivity] table)"
                )
            object.__setattr__(self, "spectral_sensitivity", name)
        if self.sensitivity is not None:
            s = self.sensitivity
            if not isinstance(s, CameraSensitivity):
                if not isinstance(s, Mapping):
                    raise r.fail(
                        k + "sensitivity",
                        f"expected a table [color.sensitivity], got {_show(s)}",
                    )
                s = CameraSensitivity.from_table(s, r)
            object.__setattr__(self, "sensitivity", s)
            if self.spectral_sensitivity is not None:
                raise r.fail(
                    k + "sensitivity",
                    "give spectral_sensitivity (a shipped table) or [color.sensitivity], not both",
                )


_CLASSES: dict[str, Any] = {"sensor": CameraSensor, "optics": CameraOptics, "color": CameraColor}


def as_table(value: Any, name: str) -> Any:
    """``value`` (None, the table's dataclass, or a mapping of its keys) as the dataclass.

    Examples
    --------
    >>> as_table({"read_noise_e": 2}, "sensor").read_noise_e
    2.0
    """
    cls = _CLASSES[name]
    if value is None or isinstance(value, cls):
        return value
    if isinstance(value, Mapping):
        return cls.from_table(value, Reader(name))
    raise TypeError(
        f"expected {name} as a {cls.__name__} or a mapping of its keys, got {describe(value)}"
    )


def _value(value: Any) -> str:
    return toml_value(value)


def table_lines(table: Any) -> list[str]:
    """Return the TOML lines of one table.

    A blank line, the header, the keys; sub-tables after.
    """
    if table is None:
        return []
    data = table.to_dict()
    lines = ["", f"[{table.TABLE}]"]
    subs: list[Any] = []
    for name, v in data.items():
        sub = getattr(table, name)
        if isinstance(sub, _Table):
            subs.append(sub)
        elif name == "ccm":
            lines += ["ccm = [", *(f"  {_value(row)}," for row in v), "]"]
        else:
            line = f"{name} = {_value(v)}"
            if len(line) > 96 and isinstance(v, list):
                line = f"{name} = [\n" + "".join(f"  {_value(i)},\n" for i in v) + "]"
            lines.append(line)
    for sub in subs:
        lines += table_lines(sub)
    return lines
