"""
Section 3: the pinhole camera model
===================================

The pinhole maps a scene point ``(X, Y, Z)`` in camera coordinates to ``x = f X / Z`` and
``y = f Y / Z``. Size in the image falls as one over the distance: a 30 m building 100 m away,
seen with f = 50 mm, is 15 mm tall on the sensor, and 3000 pixels at a 5 µm pitch.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import projected_size

print("image height (mm):", projected_size(30.0, 100.0, focal_length=50.0))
print("in pixels at 5 µm:", projected_size(30.0, 100.0, focal_length=50.0) / 5e-3)

# %%
# Doubling the distance halves the image: the image size against the distance, for three
# focal lengths.

depth = np.linspace(20, 400, 200)
fig, ax = plt.subplots(figsize=(6, 3.5))
for f in (24.0, 50.0, 135.0):
    ax.plot(depth, [projected_size(30.0, z, focal_length=f) for z in depth], label=f"f = {f:g} mm")
ax.set_xlabel("distance Z (m)")
ax.set_ylabel("image of a 30 m object (mm)")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
plt.show()
