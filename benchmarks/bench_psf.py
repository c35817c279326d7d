"""Diffraction PSFs (issue 18): FFT time for a 256-sample pupil and accuracy vs analytic MTF.

Targets: a 256 x 256 pupil's PSF at several wavelengths in well under a second; the
diffraction-limited MTF of a circular pupil within 1e-3 of Goodman eq. 6-31; the same pupil's
PSF within 1e-3 of its peak of prysm's matrix-DFT propagation (when prysm is installed).
Run from the repository root::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/bench_psf.py \\
        --out benchmarks/results/psf-2026-11-25.md

Prints (and with ``--out`` writes) Markdown tables: median milliseconds over ``--repeat``
runs, the FFT size, and the largest |MTF - analytic| up to the cut-off.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import math
import os
import platform
import sys
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script or as a module
from benchmarks._common import header, markdown_table, median_time  # noqa: E402
from imageform.optics import (  # noqa: E402
    diffraction_limited_mtf,
    diffraction_psf,
    mtf,
    polychromatic_psf,
    pupil_function,
)

WAVELENGTHS = [450e-9, 500e-9, 550e-9, 600e-9, 650e-9]
ABERRATED = {4: 40e-9, 6: 25e-9, 8: 30e-9, 11: 20e-9}


def _mtf_error(lam: float, fn: float, pitch: float, n_pupil: int) -> tuple[float, int]:
    h = diffraction_psf(wavelength=lam, f_number=fn, pixel_pitch=pitch, size=None, n_pupil=n_pupil)
    t = mtf(h, pixel_pitch=pitch)
    c = h.shape[0] // 2
    ref = diffraction_limited_mtf(t.fx[c:], wavelength=lam, f_number=fn)
    return float(np.abs(t.value[c, c:] - ref).max()), h.shape[0]


def bench_speed(repeat: int) -> str:
    rows = []
    for fn, pitch in [(4.0, 1.0e-6), (2.8, 0.7e-6), (8.0, 1.4e-6)]:
        q = 550e-9 * fn / pitch
        for n_pupil in (128, 256):
            one = median_time(
                lambda fn=fn, pitch=pitch, n_pupil=n_pupil: diffraction_psf(
                    ABERRATED,
                    wavelength=550e-9,
                    f_number=fn,
                    pixel_pitch=pitch,
                    size=64,
                    n_pupil=n_pupil,
                ),
                repeat=repeat,
            )
            poly = median_time(
                lambda fn=fn, pitch=pitch, n_pupil=n_pupil: polychromatic_psf(
                    ABERRATED,
                    wavelengths=WAVELENGTHS,
                    f_number=fn,
                    pixel_pitch=pitch,
                    size=64,
                    n_pupil=n_pupil,
                ),
                repeat=repeat,
            )
            rows.append(
                (
                    f"N = {fn:g}, pitch {pitch * 1e6:g} um (Q = {q:.2f} at 550 nm)",
                    n_pupil,
                    f"{one * 1e3:.1f}",
                    f"{poly * 1e3:.1f}",
                )
            )
    return "## Speed (64 x 64 PSF, defocus + astigmatism + coma + spherical)\n\n" + markdown_table(
        ["case", "pupil samples", "1 wavelength ms", "5 wavelengths ms"], rows
    )


def bench_accuracy() -> str:
    rows = []
    for lam in (450e-9, 550e-9, 650e-9):
        for fn, pitch in [(4.0, 1.0e-6), (2.8, 0.7e-6), (11.0, 1.4e-6)]:
            for n_pupil in (128, 256):
                err, m = _mtf_error(lam, fn, pitch, n_pupil)
                rows.append(
                    (
                        f"{lam * 1e9:.0f}",
                        f"{fn:g}",
                        f"{pitch * 1e6:g}",
                        f"{lam * fn / pitch:.2f}",
                        n_pupil,
                        m,
                        f"{err:.1e}"
                        + (" (Q < 2: aliased, expected)" if lam * fn < 2 * pitch else ""),
                    )
                )
    return (
        "## Accuracy: diffraction-limited MTF vs (2/pi)(acos x - x sqrt(1 - x^2))\n\n"
        "Largest error up to the cut-off along fx. Where Q < 2 the point-sampled PSF is\n"
        "undersampled and its DFT holds the MTF folded about Nyquist, so it cannot match the\n"
        "unaliased formula (this is sampling, not an error of the PSF).\n\n"
        + markdown_table(
            ["lambda nm", "N", "pitch um", "Q", "pupil samples", "FFT size", "max |MTF err|"],
            rows,
        )
    )


def bench_prysm() -> str:
    try:
        import pkg_resources  # noqa: F401
    except ImportError:  # prysm 0.21 reads its version through pkg_resources
        shim = types.ModuleType("pkg_resources")
        shim.get_distribution = lambda name: types.SimpleNamespace(  # type: ignore[attr-defined]
            version=importlib.metadata.version(name)
        )
        sys.modules["pkg_resources"] = shim
    try:
        from prysm.propagation import focus_fixed_sampling
    except ImportError:
        return "## prysm\n\nprysm is not installed: skipped.\n"
    from scipy import fft

    lam, fn, pitch, size, n_pupil = 550e-9, 4.0, 1e-6, 64, 256
    rows = []
    for name, coef in [("diffraction-limited", {}), ("aberrated", ABERRATED)]:
        h = diffraction_psf(coef, wavelength=lam, f_number=fn, pixel_pitch=pitch, size=size)
        q = lam * fn / pitch
        d = fft.next_fast_len(max(math.ceil(q * n_pupil), size + 1, 8)) / q
        p = pupil_function(coef, wavelength=lam, n_samples=d)
        ours = median_time(
            lambda coef=coef: diffraction_psf(
                coef, wavelength=lam, f_number=fn, pixel_pitch=pitch, size=size
            )
        )
        theirs = median_time(
            lambda p=p, d=d: focus_fixed_sampling(
                p, 10.0 / d, 10.0 * fn, lam * 1e6, pitch * 1e6, size
            )
        )
        e = focus_fixed_sampling(p, 10.0 / d, 10.0 * fn, lam * 1e6, pitch * 1e6, size)
        hp = np.abs(e) ** 2
        hp /= hp.sum()
        rows.append(
            (
                name,
                f"{ours * 1e3:.1f}",
                f"{theirs * 1e3:.1f}",
                f"{np.abs(h - hp).max() / h.max():.1e}",
            )
        )
    version = importlib.metadata.version("prysm")
    return (
        f"## Same pupil through prysm {version} (matrix DFT, focus_fixed_sampling)\n\n"
        "imageform: pupil build + FFT + crop; prysm: propagation of the given pupil only\n"
        "(its matrix DFT is cheaper for a small output). The two agree to rounding because\n"
        "both evaluate the same DFT at the same image points: the check is of the sampling\n"
        "(Q = lambda N / pitch), the centring and the normalisation, from prysm's own units.\n\n"
        + markdown_table(["pupil", "imageform ms", "prysm ms", "max |diff| / peak"], rows)
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", type=Path, default=None, help="also write the Markdown here")
    args = ap.parse_args()
    parts = [
        header("Diffraction PSF benchmark (issue 18)"),
        f"NumPy {np.__version__}, SciPy {importlib.metadata.version('scipy')}, "
        f"{platform.processor() or platform.machine()}; median of {args.repeat} runs. "
        f"Load average at start: {os.getloadavg()[0]:.1f} (a shared machine: times are "
        "upper bounds).",
        bench_speed(args.repeat),
        bench_accuracy(),
        bench_prysm(),
    ]
    text = "\n\n".join(parts) + "\n"
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
