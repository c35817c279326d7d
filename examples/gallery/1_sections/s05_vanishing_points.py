"""
Section 5: perspective and vanishing points
===========================================

Parallel lines in the scene meet in the image at the vanishing point of their common
direction ``d``: ``v = K (d_x / d_z, d_y / d_z, 1)``. All horizontal directions vanish on one
line, the horizon. With ``K`` = [[500, 0, 320], [0, 500, 240], [0, 0, 1]] the direction
(1, 0, 2) vanishes at (570, 240), on the horizon at the principal point's height.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import Camera, horizon_line, vanishing_point

K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
d = np.array([1.0, 0.0, 2.0])
v = vanishing_point(K, d)
print("vanishing point of (1, 0, 2):", np.round(v, 6))
a, b, c = horizon_line(K, np.eye(3))
print("horizon: v =", round(float(-c / b), 6), "px for every u")

# %%
# Five parallel rails on the ground (y = 1 m below the camera), going along ``d``: their
# images converge on the vanishing point, which lies on the horizon.

cam = Camera(K)
fig, ax = plt.subplots(figsize=(6, 4.5))
for x0 in np.linspace(-3, 3, 5):
    s = np.linspace(0.5, 60, 100)[:, None]
    rail = np.array([x0 - 2.0, 1.0, 1.0]) + s * d
    uv = cam.project(rail).uv
    ax.plot(uv[:, 0], uv[:, 1], "-", color="0.3")
ax.axhline(-c / b, color="tab:blue", lw=1, label="horizon")
ax.plot(*v, "r*", ms=14, label="vanishing point")
ax.set_xlim(0, 640)
ax.set_ylim(480, 0)
ax.set_aspect("equal")
ax.legend(loc="lower left")
fig.tight_layout()
plt.show()
