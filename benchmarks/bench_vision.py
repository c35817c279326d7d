"""CVD simulation and spectral integration: imageform vs colour-science.

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_vision.py [--size 1024] [--repeat 5]

Machado 2009 deutan (severity 1) on an encoded sRGB image (decode, matrix, encode) and the
24 ColorChecker reflectances to XYZ under D65. Prints a Markdown table (median seconds,
ratio to colour-science, max difference); commit it under benchmarks/results/.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from benchmarks._common import header, markdown_table, median_time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    import colour

    from imageform.color import simulate_cvd
    from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

    img = np.random.default_rng(0).random((args.size, args.size, 3))

    def ours_cvd() -> np.ndarray:
        return np.asarray(simulate_cvd(img, "deutan", 1.0, "machado2009"))

    def colour_cvd() -> np.ndarray:
        m = colour.blindness.CVD_MATRICES_MACHADO2010["Deuteranomaly"][1.0]
        lin = colour.cctf_decoding(img, "sRGB")
        return np.asarray(colour.cctf_encoding(colour.algebra.vecmul(m, lin), "sRGB"))

    r = colorchecker_reflectances()
    cmf = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    msds = colour.MultiSpectralDistributions(r.values, r.wavelengths)

    def ours_xyz() -> np.ndarray:
        return spectrum_to_xyz(r, illuminant="D65", interpolation="sprague")

    def colour_xyz() -> np.ndarray:
        return np.asarray(colour.msds_to_XYZ(msds, cmf, d65, method="Integration")) / 100

    rows = []
    for task, ours, peer in (
        (f"Machado deutan, {args.size}² sRGB", ours_cvd, colour_cvd),
        ("24 ColorChecker spectra → XYZ (D65)", ours_xyz, colour_xyz),
    ):
        t_o = median_time(ours, repeat=args.repeat)
        t_p = median_time(peer, repeat=args.repeat)
        diff = float(
            np.max(np.abs(np.asarray(ours()).reshape(-1, 3) - np.asarray(peer()).reshape(-1, 3)))
        )
        rows.append([task, f"{t_o:.4f}", f"{t_p:.4f}", f"{t_p / t_o:.2f}x", f"{diff:.1e}"])
    print(header("imageform vision vs colour-science"))
    print(
        markdown_table(["task", "imageform (s)", "colour-science (s)", "speed-up", "max |Δ|"], rows)
    )


if __name__ == "__main__":
    main()
