"""triangulate_points does not stop a batch for one point with parallel rays (issue 28)."""

from __future__ import annotations

import numpy as np

from imageform.geometry import triangulate_points


def test_parallel_rays_do_not_stop_the_batch() -> None:
    K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
    P1 = K @ np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = K @ np.hstack([np.eye(3), np.array([[-0.1], [0.0], [0.0]])])
    X = np.array([[0.1, 0.2, 2.0], [0.0, 0.0, 3.0], [-0.2, 0.1, 4.0]])

    def proj(P: np.ndarray, Y: np.ndarray) -> np.ndarray:
        h = np.hstack([Y, np.ones((len(Y), 1))]) @ P.T
        return h[:, :2] / h[:, 2:]

    uv = np.stack([proj(P1, X), proj(P2, X)])
    uv[1, 1] = uv[0, 1]  # the same pixel in both views: the rays of point 1 are parallel
    res = triangulate_points(np.stack([P1, P2]), uv)
    np.testing.assert_allclose(res.points[[0, 2]], X[[0, 2]], atol=1e-6)
    assert res.valid[0] and res.valid[2]
