"""
Section 8: colour spaces
========================

RGB is what devices store; HSV separates hue from brightness; CIE Lab is built so that equal
distances look roughly equally different; chromaticity diagrams show which colours an RGB space
can reach (its gamut); Y'CbCr splits luma from chroma for compression; gamma encoding spends
the codes where the eye is sensitive.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.color import convert, gamut_area, gamut_triangle, spectral_locus

pixel = np.array([200, 50, 50], dtype=np.uint8)
for space in ("hsv", "lab", "ycbcr"):
    print(space, np.round(convert(pixel, "srgb", space), 3))

# %%
# The CIE 1931 xy diagram: the spectral locus and the gamuts of three RGB spaces.

locus = spectral_locus()
fig, ax = plt.subplots(figsize=(5, 5))
ax.plot(locus.chromaticities[:, 0], locus.chromaticities[:, 1], "k-", lw=1)
for name, colour in (("srgb", "tab:blue"), ("display_p3", "tab:orange"), ("rec2020", "tab:green")):
    tri = gamut_triangle(name)
    ax.fill(
        tri[:, 0], tri[:, 1], fill=False, ec=colour, label=f"{name} (area {gamut_area(name):.3f})"
    )
ax.set_xlabel("x")
ax.set_ylabel("y")
ax.set_aspect("equal")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()

# %%
# Gamma: the sRGB encoding curve against linear light.

from imageform.color import linear_to_srgb

lin = np.linspace(0, 1, 256)
fig, ax = plt.subplots(figsize=(4.5, 3.5))
ax.plot(lin, linear_to_srgb(lin), label="sRGB encoding")
ax.plot(lin, lin, "k--", lw=1, label="linear")
ax.set_xlabel("linear light")
ax.set_ylabel("encoded value")
ax.legend()
fig.tight_layout()
plt.show()
