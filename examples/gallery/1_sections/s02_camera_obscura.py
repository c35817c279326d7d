"""
Section 2: the camera obscura
=============================

A dark room with a small hole in one wall is the oldest camera: light from each point of the
scene passes through the hole along one straight line, so the opposite wall receives an
inverted image. The smaller the hole, the sharper and the dimmer the image. imageform's
simulator renders this real, inverted image plane (``image_plane = "real"``) as well as the
upright virtual plane used everywhere else.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import Camera, intrinsic_matrix

K = intrinsic_matrix(200, 200, 160, 120)
points = np.array([[0.0, -0.5, 4.0], [0.0, 0.5, 4.0], [-0.6, 0.0, 4.0], [0.6, 0.0, 4.0]])
virtual = Camera(K, image_plane="virtual").project(points).uv
real = Camera(K, image_plane="real").project(points).uv
print("virtual (upright) image:\n", np.round(virtual, 2))
print("real (inverted) image on the back wall:\n", np.round(real, 2))

# %%
# The same four scene points, drawn where each image plane receives them: the real image is
# the virtual one turned by 180 degrees about the principal point.

fig, axes = plt.subplots(1, 2, figsize=(8, 3.2), sharey=True)
for ax, uv, title in ((axes[0], virtual, "virtual image plane"), (axes[1], real, "real (obscura)")):
    ax.plot(uv[:2, 0], uv[:2, 1], "o-", label="vertical bar")
    ax.plot(uv[2:, 0], uv[2:, 1], "s-", label="horizontal bar")
    ax.plot(uv[0, 0], uv[0, 1], "r*", ms=12, label="top of the bar")
    ax.set_xlim(0, 320)
    ax.set_ylim(240, 0)
    ax.set_title(title)
    ax.set_aspect("equal")
axes[0].legend(fontsize=8)
fig.tight_layout()
plt.show()
