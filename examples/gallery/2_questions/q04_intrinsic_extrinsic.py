"""
Practice question 4: intrinsic against extrinsic parameters
===========================================================

Intrinsics (``K``: focal lengths in pixels, principal point, skew) belong to the camera and
its lens; extrinsics (``R``, ``t``) say where the camera is. Moving the camera changes only the
extrinsics: ``K`` recovered from the projection matrix stays the same.
"""

import numpy as np

from imageform.geometry import (
    decompose_projection_matrix,
    intrinsic_matrix,
    look_at,
    projection_matrix,
)

K = intrinsic_matrix(800, 790, 330, 250)
for eye in ([0.0, 0.0, -5.0], [4.0, -1.0, -3.0]):
    pose = look_at(eye=eye, target=[0.0, 0.0, 0.0])
    P = projection_matrix(K, pose.R, pose.t)
    K2, R2, t2 = decompose_projection_matrix(P)[:3]
    print(f"camera at {eye}: K recovered {np.allclose(K2, K)}, t = {np.round(t2, 3)}")
