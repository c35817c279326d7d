"""
Practice question 10: why Lab for colour differences?
=====================================================

Equal steps in RGB do not look equally different, while Lab was built so that Euclidean
distance tracks perceived difference. ``ΔE*ab`` below about 1 is not noticeable to most
observers; about 2.3 is a just-noticeable difference. CIEDE2000 corrects Lab's remaining
non-uniformities.
"""

import numpy as np

from imageform.color import convert, delta_e, describe_delta_e

a = np.array([0.50, 0.40, 0.30])
for step in (0.002, 0.01, 0.05):
    b = a + step
    lab_a, lab_b = convert(a, "srgb", "lab"), convert(b, "srgb", "lab")
    de76 = float(delta_e(lab_a, lab_b, "cie76"))
    de00 = float(delta_e(lab_a, lab_b))
    print(f"RGB step {step}: ΔE76 = {de76:.2f}, ΔE00 = {de00:.2f} ({describe_delta_e(de00)})")
