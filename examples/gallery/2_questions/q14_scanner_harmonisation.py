"""
Practice question 14: two scanners, two colours
===============================================

The same tissue scanned at two sites differs because of the light source and its spectrum, the
sensor's spectral sensitivities, the scanner's processing (white balance, gamma) and the
staining itself. One correction: scan the same colour chart on both, fit a colour correction
from site A's patches to site B's, and apply it to A's slides.
"""

import numpy as np

from imageform.analysis import fit_color_correction
from imageform.color import convert, delta_e
from imageform.spectral import colorchecker_published_xyy

rng = np.random.default_rng(0)
xyy = colorchecker_published_xyy()
reference = np.clip(convert(xyy, "xyy", "srgb"), 0, 1)  # site B: the chart as it should be
site_a = np.clip(reference**1.15 * [1.08, 0.97, 0.88] + rng.normal(0, 0.003, reference.shape), 0, 1)
fit = fit_color_correction(site_a, reference, saturation=None)
corrected = np.clip(fit.apply(site_a), 0, 1)
before = delta_e(convert(site_a, "srgb", "lab"), convert(reference, "srgb", "lab"))
after = delta_e(convert(corrected, "srgb", "lab"), convert(reference, "srgb", "lab"))
print(f"mean ΔE00 between the sites: {float(np.mean(before)):.2f} before the correction,")
print(f"{float(np.mean(after)):.2f} after it")
