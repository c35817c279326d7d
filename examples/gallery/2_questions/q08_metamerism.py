"""
Practice question 8: metamerism
===============================

Two different spectra that give the same three cone (or CIE XYZ) responses look identical: they
are metamers. Displays rely on it: three primaries mixed in the right amounts match the
response to almost any spectrum, without reproducing the spectrum itself.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.color import are_metamers, metamer
from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

patches = colorchecker_reflectances()
index = 1
original = patches.__class__(patches.wavelengths, patches.values[:, index])
twin = metamer(original)
print("same XYZ under D65:", are_metamers(original, twin))
print("XYZ:", np.round(spectrum_to_xyz(original), 5), np.round(spectrum_to_xyz(twin), 5))

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(original.wavelengths, original.values, label="ColorChecker patch")
ax.plot(twin.wavelengths, twin.values, label="a metamer")
ax.set_xlabel("wavelength (nm)")
ax.set_ylabel("reflectance")
ax.legend()
fig.tight_layout()
plt.show()
