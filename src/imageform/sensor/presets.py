"""CCD and CMOS sensor presets reflecting the classic CCD-versus-CMOS comparison.

The comparison (read-out, speed, noise, power, shutter, uniformity ...) follows D. Litwiller,
"CCD vs. CMOS: facts and fiction", *Photonics Spectra*, January 2001, Table 1, as taught in
the lecture: a CCD moves each charge packet across the chip to one output amplifier (slow,
low noise, very uniform, power-hungry, global shutter with interline transfer); a CMOS sensor
converts charge to voltage in every pixel and digitises column by column (fast, low power,
more fixed-pattern noise, rolling shutter by default). The numbers in the presets are
representative of each class, not of one datasheet.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from imageform._validate import as_bool, as_int
from imageform.sensor.model import SensorModel

__all__ = [
    "CCD_VS_CMOS",
    "QE_WAVELENGTHS_NM",
    "ComparisonRow",
    "ccd_preset",
    "cmos_preset",
    "comparison_table",
]

#: Wavelength grid of the preset QE curves, 400–700 nm every 10 nm.
QE_WAVELENGTHS_NM: tuple[float, ...] = tuple(float(x) for x in range(400, 701, 10))


def _qe(peak_nm: float, width_nm: float, peak_qe: float) -> tuple[float, ...]:
    wl = np.asarray(QE_WAVELENGTHS_NM)
    return tuple(float(v) for v in peak_qe * np.exp(-0.5 * ((wl - peak_nm) / width_nm) ** 2))


def _curves(color: bool, scale: float) -> tuple[tuple[float, ...], ...]:
    if not color:
        return (_qe(550.0, 110.0, 0.70 * scale),)
    # Gaussian stand-ins for the R, G, B filter × silicon responses of a Bayer sensor.
    return (
        _qe(600.0, 35.0, 0.45 * scale),
        _qe(535.0, 40.0, 0.55 * scale),
        _qe(460.0, 30.0, 0.45 * scale),
    )


def ccd_preset(*, color: bool = False, **changes: Any) -> SensorModel:
    """Return a scientific interline CCD: large pixels, low noise, uniform, global shutter, slow.

    ``changes`` override fields (``dataclasses.replace``).

    Examples
    --------
    >>> s = ccd_preset()
    >>> s.architecture, s.shutter, s.read_noise
    ('ccd', 'global', 4.0)
    """
    color = as_bool(color, "color")
    base = SensorModel(
        name="CCD (interline transfer)",
        architecture="ccd",
        shutter="global",
        pixel_pitch=6.45e-6,
        fill_factor=0.9,  # interline CCD with microlenses
        qe_wavelengths=QE_WAVELENGTHS_NM,
        qe_curves=_curves(color, 0.9),
        full_well=18000.0,
        conversion_gain=10e-6,
        adc_range=0.2,
        bit_depth=14,
        black_level=100.0,
        dark_current=1.0,
        read_noise=4.0,
        dsnu=0.5,
        prnu=0.005,
        column_fpn=0.0,
        line_time=65e-6,  # ~15 frames/s for 1000 rows through one output amplifier
        power=1.5,
    )
    return replace(base, **changes)


def cmos_preset(*, color: bool = False, **changes: Any) -> SensorModel:
    """Return a CMOS active-pixel sensor: column-parallel ADCs, fast, low power, rolling shutter.

    Examples
    --------
    >>> s = cmos_preset()
    >>> s.architecture, s.shutter, round(s.system_gain, 4)
    ('cmos', 'rolling', 0.3276)
    """
    color = as_bool(color, "color")
    base = SensorModel(
        name="CMOS (active pixel, column ADCs)",
        architecture="cmos",
        shutter="rolling",
        pixel_pitch=3.45e-6,
        fill_factor=0.6,  # per-pixel transistors take area
        qe_wavelengths=QE_WAVELENGTHS_NM,
        qe_curves=_curves(color, 1.0),
        full_well=10500.0,
        conversion_gain=80e-6,
        adc_range=1.0,
        bit_depth=12,
        black_level=64.0,
        dark_current=5.0,
        read_noise=6.0,
        dsnu=2.0,
        prnu=0.015,
        column_fpn=2.0,
        line_time=7.5e-6,  # ~130 frames/s for 1000 rows
        power=0.3,
    )
    return replace(base, **changes)


@dataclass(frozen=True)
class ComparisonRow:
    """One row of the CCD-versus-CMOS table: the aspect and each technology's answer."""

    aspect: str
    ccd: str
    cmos: str


#: The lecture's comparison (after Litwiller 2001, Table 1).
CCD_VS_CMOS: tuple[ComparisonRow, ...] = (
    ComparisonRow(
        "readout",
        "charge packets shifted to one output amplifier",
        "charge to voltage in each pixel; column-parallel ADCs",
    ),
    ComparisonRow("speed", "moderate (serial read-out)", "high (parallel read-out, windowing)"),
    ComparisonRow("noise", "low", "moderate (more fixed-pattern noise: column FPN, PRNU)"),
    ComparisonRow("uniformity", "high", "low to moderate"),
    ComparisonRow("power", "high (several clock voltages)", "low (single low voltage)"),
    ComparisonRow(
        "shutter",
        "global (interline / frame transfer)",
        "rolling by default; global costs a storage node",
    ),
    ComparisonRow("fill factor", "high", "moderate (transistors in the pixel)"),
    ComparisonRow(
        "integration", "camera electronics off-chip", "ADC, timing and processing on-chip"
    ),
)


def comparison_table(rows: int = 1000) -> list[dict[str, str]]:
    """Return the comparison table with the presets' numbers for a sensor of ``rows`` rows.

    Examples
    --------
    >>> t = comparison_table()
    >>> [r["aspect"] for r in t][:3]
    ['readout', 'speed', 'noise']
    """
    rows = as_int(rows, "rows", minimum=1)
    ccd, cmos = ccd_preset(), cmos_preset()
    out = [{"aspect": r.aspect, "ccd": r.ccd, "cmos": r.cmos} for r in CCD_VS_CMOS]
    numbers = {
        "speed": lambda s: f"{1 / s.frame_readout_time(rows):.0f} frames/s at {rows} rows",
        "noise": lambda s: (
            f"read {s.read_noise:g} e-, DSNU {s.dsnu:g} e-, PRNU {100 * s.prnu:g} %, "
            f"column FPN {s.column_fpn:g} e-"
        ),
        "power": lambda s: f"{s.power:g} W",
        "shutter": lambda s: s.shutter,
    }
    for row in out:
        fn = numbers.get(row["aspect"])
        if fn is not None:
            row["ccd"] += f" [{fn(ccd)}]"
            row["cmos"] += f" [{fn(cmos)}]"
    return out
