"""One-off developer script: export the spectral tables imageform ships to CSV.

Run once (not in tests) from the repository root::

    python tools/extract_spectral_tables.py

colour-science (BSD-3-Clause) carries transcriptions of the standard tables; this script
writes them to ``src/imageform/spectral/data/*.csv`` with a header naming the original source.
The library reads the CSVs with :mod:`imageform.spectral.data` and never imports colour-science.

CSV layout: lines starting with ``#`` are comments (source, units, licence); the first other line
is the column header (``wavelength_nm,<names>``); then one row per wavelength.
"""

from __future__ import annotations

from pathlib import Path

import colour
import numpy as np

OUT = Path(__file__).resolve().parents[1] / "src" / "imageform" / "spectral" / "data"
VIA = f"transcribed via colour-science {colour.__version__} (BSD-3-Clause)"


def write(name: str, wl: np.ndarray, cols: dict[str, np.ndarray], source: str, note: str) -> None:
    lines = [f"# source: {source}", f"# {VIA}", f"# {note}"]
    lines.append(",".join(["wavelength_nm", *cols]))
    for i, w in enumerate(wl):
        vals = [f"{float(c[i]):.10g}" for c in cols.values()]
        lines.append(",".join([f"{float(w):g}", *vals]))
    (OUT / name).write_text("\n".join(lines) + "\n", encoding="utf-8")


def msds(name: str, obj: object, source: str, note: str) -> None:
    write(
        name, obj.wavelengths, {k: obj.values[:, i] for i, k in enumerate(obj.labels)}, source, note
    )  # type: ignore[attr-defined]


def sds(name: str, objs: dict[str, object], source: str, note: str) -> None:
    wl = next(iter(objs.values())).wavelengths  # type: ignore[attr-defined]
    cols = {}
    for k, sd in objs.items():
        assert np.array_equal(sd.wavelengths, wl), k  # type: ignore[attr-defined]
        cols[k] = sd.values  # type: ignore[attr-defined]
    write(name, wl, cols, source, note)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    C = colour.MSDS_CMFS
    msds(
        "cmf_cie1931_2deg.csv",
        C["CIE 1931 2 Degree Standard Observer"],
        "CIE 015:2018 Table 4 / CIE S 014-1 (CIE 1931 2 degree standard observer), 1 nm",
        "columns x_bar, y_bar, z_bar; dimensionless",
    )
    msds(
        "cmf_cie1964_10deg.csv",
        C["CIE 1964 10 Degree Standard Observer"],
        "CIE 015:2018 Table 5 / CIE S 014-1 (CIE 1964 10 degree standard observer), 1 nm",
        "columns x_bar_10, y_bar_10, z_bar_10; dimensionless",
    )
    msds(
        "cones_stockman_sharpe_2deg.csv",
        C["Stockman & Sharpe 2 Degree Cone Fundamentals"],
        "Stockman & Sharpe (2000), Vision Res. 40:1711-1737; CVRL 2 degree energy-based "
        "cone fundamentals (linear, peak-normalised), 1 nm",
        "columns l_bar, m_bar, s_bar; each normalised to a peak of 1",
    )
    L = colour.SDS_LEFS
    sds(
        "vlambda_photopic.csv",
        {"V": L["CIE 1924 Photopic Standard Observer"]},
        "CIE 1924 photopic luminous efficiency V(lambda); CIE 018:2019 / ISO 23539, 1 nm",
        "peak 1 at 555 nm; K_m = 683 lm/W",
    )
    sds(
        "vlambda_scotopic.csv",
        {"V_prime": L["CIE 1951 Scotopic Standard Observer"]},
        "CIE 1951 scotopic luminous efficiency V'(lambda); CIE 018:2019 / ISO 23539, 1 nm",
        "peak 1 at 507 nm; K'_m = 1700 lm/W",
    )
    I = colour.SDS_ILLUMINANTS
    for key, fname, src in (
        ("A", "illuminant_A.csv", "CIE 015:2018 Table 1 (CIE standard illuminant A), 5 nm"),
        ("D50", "illuminant_D50.csv", "CIE 015:2018 Table 1/2 (CIE illuminant D50), 5 nm"),
        ("D65", "illuminant_D65.csv", "CIE 015:2018 Table 1 (CIE standard illuminant D65), 5 nm"),
        ("FL2", "illuminant_F2.csv", "CIE 015:2018 Table 10.1 (illuminant F2 / FL2), 5 nm"),
        ("FL11", "illuminant_F11.csv", "CIE 015:2018 Table 10.1 (illuminant F11 / FL11), 5 nm"),
    ):
        note = "relative spectral power" + (", 100 at 560 nm" if key[0] != "F" else "")
        sds(fname, {key: I[key]}, src, note)
    from colour.colorimetry.datasets.illuminants.sds_d_illuminant_series import (
        SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as B,
    )

    sds(
        "daylight_basis.csv",
        {k: B[k] for k in ("S0", "S1", "S2")},
        "CIE 015:2018 Table 6 (components S0, S1, S2 of daylight), 5 nm",
        "S_D(lambda) = S0 + M1 S1 + M2 S2 (CIE 015:2018 eq. 4.3)",
    )
    sds(
        "led_cie2018.csv",
        {
            k: I[k]
            for k in (
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
        },
        "CIE 015:2018 Table 11 (typical white-LED illuminants LED-B1..LED-V2), 5 nm",
        "relative spectral power as tabulated (not normalised at 560 nm)",
    )
    cc = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    sds(
        "colorchecker_babelcolor_average.csv",
        dict(cc),
        "Pascale, D. (2006) BabelColor ColorChecker average reflectances "
        "(ColorChecker_RGB_and_spectra.xls, 30 charts pre-2009), 10 nm",
        "spectral reflectance factor in [0, 1]; columns are the 24 patches in chart order",
    )
    m = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    msds(
        "camera_nikon_d5100_npl.csv",
        m,
        "Darrodi, Finlayson, Goodman, Mackiewicz (2015) JOSA A 32(3):381-391, NPL measured "
        "camera spectral sensitivities, Nikon D5100, 5 nm",
        "columns red, green, blue; relative sensitivities",
    )
    # Published chromaticities under D50 (X-Rite / BabelColor), xyY as colour-science holds them.
    lines = [
        "# source: BabelColor (Pascale 2006) ColorChecker average, published L*a*b* D50 2 degree "
        "(ColorChecker_RGB_and_spectra.xls), stored as xyY; and X-Rite ColorChecker Classic "
        "published values after November 2014 (xyY D50)",
        f"# {VIA}",
        "# Y in [0, 1]; white point D50 (x, y) = (0.34570291, 0.3585386) as the tables use",
        "patch,babel_x,babel_y,babel_Y,xrite2014_x,xrite2014_y,xrite2014_Y",
    ]
    a = colour.CCS_COLOURCHECKERS["BabelColor Average"].data
    b = colour.CCS_COLOURCHECKERS["ColorChecker24 - After November 2014"].data
    for (k, v), w in zip(a.items(), b.values(), strict=True):
        lines.append(",".join([k, *(f"{float(t):.8g}" for t in (*v, *w))]))
    (OUT / "colorchecker_published_xyY_d50.csv").write_text(
        "\n".join(lines) + "\n", encoding="utf-8"
    )
    # Machado, Oliveira & Fernandes (2009) pre-computed CVD matrices (linear RGB).
    mm = colour.blindness.CVD_MATRICES_MACHADO2010
    lines = [
        "# source: Machado, Oliveira & Fernandes (2009) IEEE TVCG 15(6):1291-1298, "
        "supplementary table of pre-computed matrices (severity 0.0-1.0 step 0.1)",
        f"# {VIA}",
        "# 3x3 matrices applied to linear RGB column vectors, row-major m00..m22",
        "deficiency,severity," + ",".join(f"m{i}{j}" for i in range(3) for j in range(3)),
    ]
    for key, short in (
        ("Protanomaly", "protan"),
        ("Deuteranomaly", "deutan"),
        ("Tritanomaly", "tritan"),
    ):
        for sev, mat in mm[key].items():
            vals = ",".join(f"{float(v):.6f}" for v in np.asarray(mat).ravel())
            lines.append(f"{short},{sev:.1f},{vals}")
    (OUT / "cvd_machado2009.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    # viridis from matplotlib (CC0: van der Walt & Smith, 2015)
    from matplotlib import colormaps

    vir = colormaps["viridis"].colors
    lines = [
        "# source: viridis colour map, S. van der Walt and N. Smith (2015), CC0; matplotlib "
        "_cm_listed.py, 256 entries",
        "# encoded sRGB in [0, 1]",
        "r,g,b",
    ] + [",".join(f"{c:.8f}" for c in rgb) for rgb in vir]
    (OUT / "viridis.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
