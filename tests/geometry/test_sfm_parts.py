"""A sequence in two parts that no verified pair joins: the larger part is reconstructed.

``reconstruct_sequence`` makes one model from the pair with the most inliers. When that pair
lies in a small part of the sequence (a weak link cuts it off: Middlebury's temple ring,
16 views 23 degrees apart, whose start fell in 4 frames while pycolmap registered the other
10, ``benchmarks/check_sfm_fresh.py``), the model could not reach the rest. Here three
frames of a room papered with colour blobs (many matches: the start) come before seven
frames of the walk through the photographed room (no match between the two): the first
model registers the three; a second start among the frames it left out registers the seven,
and the larger model is returned, its poses the walk's.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imageform.geometry import reconstruct_sequence
from tests import sfm_scenes

pytest.importorskip("cv2")

K = np.array([[300.0, 0, 199.5], [0, 300.0, 149.5], [0, 0, 1]])
SIZE = (400, 300)


def _two_parts() -> tuple[list[np.ndarray], list]:
    blobs = [sfm_scenes.blobs(i) for i in range(6)]
    other, _ = sfm_scenes.sequence(K, 30, SIZE, photos=blobs)  # small steps: many inliers
    walk, truth = sfm_scenes.sequence(K, 8, SIZE)
    return other[:3] + walk[:7], truth[:7]


def test_the_larger_part_is_kept() -> None:
    frames, truth = _two_parts()
    rec = reconstruct_sequence(frames, K)
    assert rec.registered.tolist() == [False] * 3 + [True] * 7, rec.notes
    assert any("another start" in note and "registered 7" in note for note in rec.notes)
    R_est, t_est = rec.R[3:], rec.t[3:]
    for i, (R, _) in enumerate(truth):
        d = (R_est[i] @ R_est[0].T) @ (R @ truth[0][0].T).T
        angle = np.degrees(np.arccos(np.clip((np.trace(d) - 1) / 2, -1.0, 1.0)))
        assert angle < 2.0, (i, angle)
    C_est = np.array([-R.T @ t for R, t in zip(R_est, t_est, strict=True)])
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(C_est, C_true) < 0.01


def test_the_first_model_alone_before() -> None:
    """Without the second start (one model, as before): the three blob frames only."""
    from imageform.geometry.sfm import _reconstruct

    frames, _ = _two_parts()
    kw: dict[str, Any] = {"window": 3, "max_features": 4000, "ratio": 0.8, "rng": 0}
    kw |= {"threshold_px": 1.0, "masks": None, "contrast_threshold": 0.04, "cache": {}}
    rec = _reconstruct(frames, K, None, **kw, starts=None)
    assert rec.registered.tolist() == [True] * 3 + [False] * 7
