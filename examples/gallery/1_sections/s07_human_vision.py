"""
Section 7: human vision and colour perception
=============================================

The retina's three cone types (L, M, S) sample the spectrum with broad, overlapping
sensitivities peaking near 570, 543 and 442 nm; every colour we see is three numbers. Missing
or shifted cones make colour-vision deficiency, which imageform simulates (Machado 2009).
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.color import simulate_cvd
from imageform.spectral import cone_fundamentals

cones = cone_fundamentals()
peaks = cones.wavelengths[np.argmax(cones.values, axis=0)]
print("cone peaks (nm, energy units):", peaks)

fig, ax = plt.subplots(figsize=(6, 3.5))
for i, (name, colour) in enumerate(zip("LMS", ("tab:red", "tab:green", "tab:blue"), strict=True)):
    ax.plot(cones.wavelengths, cones.values[:, i], color=colour, label=name)
ax.set_xlabel("wavelength (nm)")
ax.set_ylabel("relative sensitivity")
ax.legend()
fig.tight_layout()
plt.show()

# %%
# A palette as seen with normal vision and simulated for the three dichromacies.

palette = np.array(
    [[[0.85, 0.1, 0.1], [0.1, 0.6, 0.1], [0.1, 0.3, 0.85], [0.95, 0.8, 0.1], [0.6, 0.2, 0.7]]]
)
fig, axes = plt.subplots(4, 1, figsize=(5, 4))
for ax, kind in zip(axes, ("normal", "protan", "deutan", "tritan"), strict=True):
    img = palette if kind == "normal" else simulate_cvd(palette, kind, clip=True)
    ax.imshow(img, interpolation="nearest")
    ax.set_title(kind, fontsize=9)
    ax.axis("off")
fig.tight_layout()
plt.show()
