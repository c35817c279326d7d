"""
Practice question 12: which colour space for which job?
=======================================================

(a) Endoscopic tissue segmentation: HSV (or Lab), since hue thresholds survive brightness
changes along the scope. (b) JPEG: Y'CbCr, whose chroma can be subsampled. (c) Stain
reproducibility: Lab with ΔE00, perceptually uniform and device independent.
"""

import numpy as np

from imageform.analysis import synthetic_endoscopy_image
from imageform.color import convert

scene = synthetic_endoscopy_image((128, 128), rng=1)
hsv = convert(scene.image, "srgb", "hsv")
dim = convert(scene.image * 0.5, "srgb", "hsv")
print(
    "hue changes when the light halves (deg, median):",
    round(float(np.median(np.abs(hsv[..., 0] - dim[..., 0]))), 3),
)
print(
    "RGB changes by (median):", round(float(np.median(np.abs(scene.image - scene.image * 0.5))), 3)
)
