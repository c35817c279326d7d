"""
Section 4: homogeneous coordinates and the camera matrix
========================================================

Appending a 1 to every point turns the pinhole's division by depth into one matrix product
followed by a single division: ``λ p = K [R | t] X``. ``K`` holds the intrinsic parameters
(focal lengths in pixels, principal point, skew); ``R`` and ``t`` the camera's pose. Moving the
camera changes ``R`` and ``t`` only.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import Camera, intrinsic_matrix, look_at, projection_matrix

K = intrinsic_matrix(500, 500, 320, 240)
pose = look_at(eye=[3.0, -2.0, -4.0], target=[0.0, 0.0, 0.0])
P = projection_matrix(K, pose.R, pose.t)
print("P = K [R | t] =\n", np.round(P, 2))

corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
homogeneous = np.c_[corners, np.ones(8)] @ P.T
uv_by_matrix = homogeneous[:, :2] / homogeneous[:, 2:]
uv = Camera(K, pose.R, pose.t).project(corners).uv
print("same pixels by P and by Camera.project:", np.allclose(uv, uv_by_matrix))

# %%
# The cube's twelve edges in the image.

edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(corners[i] != corners[j]) == 1]
fig, ax = plt.subplots(figsize=(5, 4))
for i, j in edges:
    ax.plot(uv[[i, j], 0], uv[[i, j], 1], "k-")
ax.set_xlim(0, 640)
ax.set_ylim(480, 0)
ax.set_aspect("equal")
ax.set_title("a cube through K [R | t]")
fig.tight_layout()
plt.show()
