"""
Practice question 2: why homogeneous coordinates?
=================================================

Pinhole projection divides by depth, so it is not a linear map of ``(X, Y, Z)``: doubling a
point's coordinates does not double its image. Written with an extra coordinate, the same
projection is one linear map ``K [R | t]`` followed by a single division at the end, which lets
rotations, translations and the intrinsics be chained as matrix products.
"""

import numpy as np

from imageform.geometry import from_homogeneous, intrinsic_matrix, project_points, to_homogeneous

K = intrinsic_matrix(100, 100, 0, 0)
p = np.array([3.0, -1.0, 5.0])
print("image of p:   ", project_points(p, K).uv)
print("image of 2 p: ", project_points(2 * p, K).uv, "(the same: not linear in p)")

# the linear part: K @ p in homogeneous form, then one division
ph = K @ p
print("K p =", ph, "-> divide by the last entry:", from_homogeneous(ph))
print("homogeneous p:", to_homogeneous(p))
