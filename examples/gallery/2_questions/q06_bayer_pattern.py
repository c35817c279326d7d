"""
Practice question 6: the Bayer pattern
======================================

A Bayer colour filter array repeats a 2x2 tile of one red, two green and one blue filter. Green
gets twice the samples because the eye's luminance sensitivity peaks in the green, so most of
the perceived detail is sampled there.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.sensor import cfa_masks

masks = cfa_masks((8, 8), "RGGB")
print(
    "share of R, G, B sites:",
    masks.reshape(-1, 3).mean(axis=0) if masks.shape[-1] == 3 else masks.mean(axis=(1, 2)),
)

tile = masks.astype(float) if masks.shape[-1] == 3 else np.moveaxis(masks, 0, -1).astype(float)
fig, ax = plt.subplots(figsize=(3.5, 3.5))
ax.imshow(tile, interpolation="nearest")
ax.set_title("RGGB, 8x8 pixels")
ax.axis("off")
fig.tight_layout()
plt.show()
