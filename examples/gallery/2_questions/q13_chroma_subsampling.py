"""
Practice question 13: chroma subsampling 4:2:0
==============================================

4:2:0 keeps luma at full resolution and one chroma sample (Cb, Cr) per 2x2 block: half the data
of full 4:4:4. The eye resolves brightness detail much better than colour detail, so the loss is
hard to see; the errors concentrate at sharp colour edges.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.color import subsample_round_trip, subsampling_delta_e

yy, xx = np.mgrid[0:96, 0:96] / 95.0
smooth = np.stack([xx, yy, 0.5 + 0.0 * xx], axis=-1)
edges = np.zeros((96, 96, 3))
edges[:, ::2] = [0.9, 0.1, 0.1]
edges[:, 1::2] = [0.1, 0.1, 0.9]
for name, img in (("smooth gradient", smooth), ("1-px colour stripes", edges)):
    de = subsampling_delta_e(img, "4:2:0")
    print(f"{name}: mean ΔE00 after 4:2:0 = {float(np.mean(de)):.2f}")

fig, axes = plt.subplots(1, 2, figsize=(7, 3.5))
axes[0].imshow(edges[:16, :16])
axes[0].set_title("stripes")
axes[1].imshow(np.clip(subsample_round_trip(edges, "4:2:0")[:16, :16], 0, 1))
axes[1].set_title("after 4:2:0")
for ax in axes:
    ax.axis("off")
fig.tight_layout()
plt.show()
