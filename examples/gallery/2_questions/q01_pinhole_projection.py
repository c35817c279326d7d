"""
Practice question 1: projecting a point through a pinhole
=========================================================

A point at camera coordinates (3, -1, 5) is seen by a pinhole camera whose focal length is
100 px and whose principal point is the image origin. Where does it land in the image?

The pinhole model divides by depth: ``u = f X / Z`` and ``v = f Y / Z``. With ``f = 100``,
``(X, Y, Z) = (3, -1, 5)`` gives ``(60, -20)``.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import intrinsic_matrix, project_points

K = intrinsic_matrix(100, 100, 0, 0)
uv = project_points([3.0, -1.0, 5.0], K).uv
print("image point (u, v):", np.round(uv, 6))

# %%
# The same ray, seen from above (x, z) and from the side (y, z): the image plane sits at
# z = f, and the point's image is where the ray from the centre of projection crosses it.

fig, axes = plt.subplots(1, 2, figsize=(8, 3.2))
for ax, i, name in ((axes[0], 0, "x"), (axes[1], 1, "y")):
    p = [3.0, -1.0][i]
    ax.plot([0, 5], [0, p], "k--", lw=1)
    ax.plot([5], [p], "o", label="point")
    ax.axvline(1.0, color="0.6", lw=1)  # the image plane at z = 1 (normalised: f = 1)
    ax.plot([1.0], [p / 5], "s", label=f"image: {name} = {100 * p / 5:.0f} px")
    ax.set_xlabel("z (depth)")
    ax.set_ylabel(name)
    ax.legend(loc="best", fontsize=8)
fig.tight_layout()
plt.show()
