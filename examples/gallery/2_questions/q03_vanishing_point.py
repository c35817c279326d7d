"""
Practice question 3: a vanishing point from K and a direction
=============================================================

With ``K`` = [[500, 0, 320], [0, 500, 240], [0, 0, 1]], where do lines along ``d = (1, 0, 2)``
vanish? ``v = K (d_x / d_z, d_y / d_z, 1) = K (0.5, 0, 1) = (570, 240)``.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import Camera, vanishing_point

K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
v = vanishing_point(K, [1.0, 0.0, 2.0])
print("vanishing point:", np.round(v[:2], 6))

# %%
# Points ever farther along the direction approach it.

cam = Camera(K)
s = np.geomspace(1, 1e4, 60)[:, None]
fig, ax = plt.subplots(figsize=(6, 4))
for start in ([-1.0, 0.5, 2.0], [0.0, -0.5, 2.0], [1.0, 1.0, 3.0]):
    uv = cam.project(np.array(start) + s * np.array([1.0, 0.0, 2.0])).uv
    ax.plot(uv[:, 0], uv[:, 1], ".-", ms=3)
ax.plot(v[0], v[1], "r*", ms=14, label="v = (570, 240)")
ax.set_xlim(0, 640)
ax.set_ylim(480, 0)
ax.legend()
fig.tight_layout()
plt.show()
