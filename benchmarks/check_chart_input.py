"""Chart photographs given directly to the colour-correction fit and the white balance,
against the same photographs cropped to the chart (issue 17).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_chart_input.py [N]

Cases: ``tests/analysis/chart_cases.py`` (a rendered ColorChecker composited into the Kodak
photographs: perspective up to 40 degrees, any rotation, 10-60 % of the frame width,
illuminant cast, uneven light, blur, noise, JPEG; no occlusion), the first N seeds (40 by
default). The cropped chart is the same photograph straightened through the TRUE chart
homography into a 4 x 6 grid of 40-pixel cells (``tests/analysis/test_chart_input.py``).

Per case: ``sample_chart``'s layout on each image; the CIEDE2000 between the chart's
patches corrected by the correction fitted on the photograph and by the one fitted on the
crop (mean and max over the 24 patches; 3 x 3 and root-polynomial degree 2), both fitted to
the ColorChecker's published values; the largest relative difference of the white-balance
gains; the time of ``fit_color_correction(photo, reference)`` (detection included).
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import (
    ChartWarning,
    chart_white_balance,
    fit_color_correction,
    sample_chart,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from tests.analysis.chart_cases import chart_case, kodak_images
from tests.analysis.test_chart_input import _de, rectified_crop

REF = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0


def main(n: int = 40) -> None:
    kodak = kodak_images(Path("../shared/data"))
    rows, worst = [], {"lin": 0.0, "rp": 0.0, "wb": 0.0}
    means = {"lin": [], "rp": [], "wb": [], "t": []}
    fails = 0
    for seed in range(n):
        case = chart_case(kodak, seed, occlude=0)
        crop = rectified_crop(case.image, case.centres)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ChartWarning)
                t0 = time.perf_counter()
                lin_p = fit_color_correction(case.image, REF)
                t = time.perf_counter() - t0
                layouts = (sample_chart(case.image).layout, sample_chart(crop).layout)
                x = sample_chart(crop).patches.means
                lin_c = fit_color_correction(crop, REF)
                rp_p = fit_color_correction(case.image, REF, "root_polynomial", 2)
                rp_c = fit_color_correction(crop, REF, "root_polynomial", 2)
                g_p = chart_white_balance(case.image).gains
                g_c = chart_white_balance(crop).gains
        except Exception as exc:  # a chart not found: counted, shown
            fails += 1
            rows.append([seed, "-", "-", "-", "-", "-", f"{type(exc).__name__}", ""])
            continue
        d_lin = _de(lin_p.apply(x), lin_c.apply(x))
        d_rp = _de(rp_p.apply(x), rp_c.apply(x))
        wb = float(np.abs(g_p / g_c - 1).max())
        for k, v in (("lin", d_lin.mean()), ("rp", d_rp.mean()), ("wb", wb)):
            worst[k] = max(worst[k], float(v))
            means[k].append(float(v))
        means["t"].append(t)
        p = case.params
        rows.append(
            [
                seed,
                "/".join(layouts),
                f"{d_lin.mean():.3f} / {d_lin.max():.3f}",
                f"{d_rp.mean():.3f} / {d_rp.max():.3f}",
                f"{100 * wb:.3f}",
                f"{t * 1000:.0f}",
                f"w {p['width']:.2f} tilt {p['tilt']:.0f} rot {p['rotation']:.0f}",
                f"blur {p['blur']:.1f} noise {p['noise']:.3f} q{int(p['jpeg_quality'])}",
            ]
        )
    print(header("Chart photographs vs the same photographs cropped (issue 17)"))
    cols = [
        "seed",
        "layout photo/crop",
        "ΔE00 3x3 mean / max",
        "ΔE00 root-poly mean / max",
        "WB gains max diff %",
        "fit ms",
        "pose",
        "image",
    ]
    print(markdown_table(cols, rows))
    print()
    ok = n - fails
    print(
        f"{ok} of {n} charts found. Mean over cases of the per-case mean ΔE00: 3x3 "
        f"{np.mean(means['lin']):.3f} (worst {worst['lin']:.3f}), root-polynomial "
        f"{np.mean(means['rp']):.3f} (worst {worst['rp']:.3f}); white-balance gains "
        f"{100 * np.mean(means['wb']):.3f} % (worst {100 * worst['wb']:.3f} %); fit on the "
        f"photograph {1000 * np.median(means['t']):.0f} ms median (detection included)."
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
