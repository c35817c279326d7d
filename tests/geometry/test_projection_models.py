"""Orthographic, weak-perspective and cone-beam X-ray projection."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry import (
    ConeBeamGeometry,
    orthographic_matrix,
    orthographic_project,
    project_points,
    weak_perspective_matrix,
    weak_perspective_project,
)


def test_orthographic_ignores_depth_and_matches_matrix() -> None:
    X = np.array([[1.0, 2.0, 3.0], [1.0, 2.0, -30.0]])
    uv = orthographic_project(X, (2.0, 3.0), (10.0, 20.0))
    np.testing.assert_allclose(uv, [[12.0, 26.0], [12.0, 26.0]])
    P = orthographic_matrix((2.0, 3.0), (10.0, 20.0))
    h = np.c_[X, np.ones(2)] @ P.T
    np.testing.assert_allclose(h[:, :2] / h[:, 2:], uv)


def test_weak_perspective_approaches_perspective_far_away() -> None:
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    rng = np.random.default_rng(30)
    obj = rng.uniform(-0.05, 0.05, size=(50, 3))
    for distance, tol in ((2.0, 1.0), (50.0, 0.05)):
        X = obj + [0.0, 0.0, distance]
        err = np.abs(weak_perspective_project(X, K) - project_points(X, K).uv).max()
        assert err < tol
    P = weak_perspective_matrix(K, 2.0)
    h = np.c_[obj + [0, 0, 2.0], np.ones(50)] @ P.T
    np.testing.assert_allclose(
        h[:, :2] / h[:, 2:], weak_perspective_project(obj + [0, 0, 2.0], K, depth=2.0)
    )
    with pytest.raises(InvalidInputError, match="Z0 > 0"):
        weak_perspective_project([[0.0, 0.0, -1.0]], K)


def test_cone_beam_magnification_and_projection() -> None:
    """Bushberg: M = SID / SOD; an object at the isocentre images magnified by M."""
    g = ConeBeamGeometry(1000.0, 800.0, 0.2, (1024, 1024))
    assert g.magnification == pytest.approx(1.25)
    # a 10 mm object at SOD spans 12.5 mm = 62.5 pixels on the detector
    uv = g.project([[-5.0, 0.0, 800.0], [5.0, 0.0, 800.0]]).uv
    assert uv[1, 0] - uv[0, 0] == pytest.approx(62.5)
    assert g.object_pixel_size == pytest.approx(0.16)
    assert g.penumbra(1.0) == pytest.approx(0.25)
    assert np.degrees(g.fan_angle) == pytest.approx(2 * np.degrees(np.arctan(102.4 / 1000)))
    assert not bool(g.project([0.0, 0.0, -10.0]).valid)


def test_cone_beam_bad() -> None:
    with pytest.raises(InvalidInputError, match="between source and detector"):
        ConeBeamGeometry(500.0, 800.0, 0.2, (10, 10))
    with pytest.raises(InvalidInputError, match="pixel_pitch > 0"):
        ConeBeamGeometry(1000.0, 800.0, 0.0, (10, 10))
    with pytest.raises(InvalidInputError, match="scale > 0"):
        orthographic_project([[0.0, 0.0, 1.0]], -1.0)
