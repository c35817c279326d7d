"""The lecture's numbers on human colour vision and gamuts, computed from the shipped data.

Where the data and the lecture's rounded numbers differ, the example states what the data
gives and the tolerance says how far "about" stretches (docs/spectra-and-vision.md explains):

- rods peak near 507 nm: CIE 1951 V'(λ) peaks at 507 nm;
- L, M, S peak "about 560, 530, 420 nm": those are photopigment absorption maxima
  (microspectrophotometry, Bowmaker & Dartnall 1980: 564, 534, 420 nm). The Stockman & Sharpe
  (2000) cone fundamentals are measured at the cornea, through the lens and macular pigment,
  which absorb short wavelengths: in quantal units they peak at 566, 541 and 441 nm;
- "sRGB covers about 35 % of the visible colours": 33.5 % of the xy area (33.2 % in u'v').
"""

from __future__ import annotations

import numpy as np

from imageform.report.lecture import WorkedExample

__all__ = ["EXAMPLES"]


def _quantal_peaks() -> tuple[float, float, float]:
    from imageform.spectral import Spectrum, cone_fundamentals

    c = cone_fundamentals()
    q = Spectrum(c.wavelengths, c.values / c.wavelengths[:, None])  # energy -> quanta
    p = np.asarray(q.peak_wavelength())
    return float(p[0]), float(p[1]), float(p[2])


def _rod_peak() -> float:
    from imageform.spectral import luminous_efficiency

    return float(luminous_efficiency("scotopic").peak_wavelength())


def _photopic_peak() -> float:
    from imageform.spectral import luminous_efficiency

    return float(luminous_efficiency("photopic").peak_wavelength())


def _srgb_coverage() -> float:
    from imageform.color.gamut import gamut_coverage

    return gamut_coverage("srgb", "xy")


def _cct(name: str) -> float:
    from imageform.spectral import illuminant, planckian_cct, spectrum_to_xyz

    return planckian_cct(spectrum_to_xyz(illuminant(name), illuminant=None, method="astm_e308"))[0]


EXAMPLES: list[WorkedExample] = [
    WorkedExample(
        "vision",
        "Rods (scotopic vision) are most sensitive near which wavelength?",
        "argmax V'(λ), CIE 1951 scotopic",
        _rod_peak,
        507.0,
        "nm",
        tol=1.0,
    ),
    WorkedExample(
        "vision",
        "Photopic luminous efficiency V(λ) peaks at?",
        "argmax V(λ), CIE 1924",
        _photopic_peak,
        555.0,
        "nm",
        tol=1.0,
    ),
    WorkedExample(
        "vision",
        "L, M, S cones peak at about 560, 530, 420 nm? (data: corneal quantal "
        "fundamentals, shifted by lens and macular absorption)",
        "argmax l(λ)/λ, m(λ)/λ, s(λ)/λ, Stockman & Sharpe (2000) 2°",
        _quantal_peaks,
        (560.0, 530.0, 420.0),
        "nm",
        tol=25.0,
    ),
    WorkedExample(
        "gamut",
        "sRGB covers about 35 % of the visible chromaticities (xy area)?",
        "100 A(sRGB triangle ∩ locus) / A(locus 380-780 nm)",
        _srgb_coverage,
        35.0,
        "%",
        tol=2.0,
    ),
    WorkedExample(
        "illuminants",
        "CCT of CIE illuminant A?",
        "Planckian direct search on XYZ from the 5 nm table",
        lambda: _cct("A"),
        2856.0,
        "K",
        tol=2.0,
    ),
    WorkedExample(
        "illuminants",
        "CCT of CIE illuminant D65?",
        "Planckian direct search on XYZ from the 5 nm table",
        lambda: _cct("D65"),
        6504.0,
        "K",
        tol=2.0,
    ),
]
