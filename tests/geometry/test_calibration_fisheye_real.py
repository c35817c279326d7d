"""Fisheye calibration on real views (tests/data/calibration-fisheye, Apache-2.0).

Sources of truth: a labelled cross-check, not the truth — OpenCV's ``cv2.fisheye.calibrate``
on the same corners gave K = (232.728, 234.459, 367.498, 365.442), k = (-0.028285, 0.023207,
-0.024457, 0.0059843) and an RMS of 0.400625 px (OpenCV 5.0 and 4.14 alike; recomputed from
its parameters), as imageform's ``calibrate_camera(model="kannala_brandt")``
(benchmarks/results/calibration-fisheye-2026-11-29.md); Brown-Conrady on the same corners
0.702 px (OpenCV's ``calibrateCamera`` the same).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from imageform.geometry import calibrate_camera, checkerboard_points
from imageform.geometry.checkerboard import find_checkerboard

DATA = Path(__file__).resolve().parents[1] / "data" / "calibration-fisheye"
BOARD = (7, 9)


@pytest.fixture(scope="module")
def views() -> tuple[list[np.ndarray], list[np.ndarray], list[str], tuple[int, int]]:
    z = np.load(DATA / "sweetiepie-corners.npz")
    corners = list(z["corners"])
    size = (int(z["image_size"][0]), int(z["image_size"][1]))
    return [checkerboard_points(BOARD, 1.0)] * len(corners), corners, list(z["names"]), size


@pytest.fixture(scope="module")
def fisheye(views: tuple) -> Any:
    objs, corners, _, size = views
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate_camera(objs, corners, size, model="kannala_brandt")


def test_real_fisheye_matches_opencv_published_run(fisheye: Any) -> None:
    np.testing.assert_allclose(
        fisheye.K[[0, 1, 0, 1], [0, 1, 2, 2]], [232.728, 234.459, 367.498, 365.442], atol=2e-3
    )
    np.testing.assert_allclose(
        fisheye.distortion.coeffs, [-0.028285, 0.023207, -0.024457, 0.0059843], atol=2e-6
    )
    assert abs(fisheye.rms - 0.400625) < 2e-6


def test_real_fisheye_beats_brown_conrady(views: tuple, fisheye: Any) -> None:
    objs, corners, _, size = views
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bc = calibrate_camera(objs, corners, size)
    assert abs(bc.rms - 0.701947) < 2e-6
    assert fisheye.rms < 0.6 * bc.rms


def test_real_fisheye_matches_opencv_now(views: tuple, fisheye: Any) -> None:
    cv2 = pytest.importorskip("cv2")
    objs, corners, _, size = views
    flags = 0
    for name in ("CALIB_RECOMPUTE_EXTRINSIC", "CALIB_FIX_SKEW"):
        flags |= int(getattr(cv2.fisheye, name, getattr(cv2, name, 0)))
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 300, 1e-15)
    try:
        _, K, D, _, _ = cv2.fisheye.calibrate(
            [o.reshape(1, -1, 3) for o in objs],
            [c.reshape(1, -1, 2) for c in corners],
            size,
            np.zeros((3, 3)),
            np.zeros((4, 1)),
            flags=flags,
            criteria=crit,
        )
    except cv2.error as exc:
        pytest.skip(f"cv2.fisheye.calibrate failed here: {str(exc).splitlines()[-1]}")
    np.testing.assert_allclose(fisheye.K, K, atol=1e-3)
    np.testing.assert_allclose(fisheye.distortion.coeffs, D.ravel(), atol=1e-6)


def test_real_curved_view_detected(views: tuple, fisheye: Any) -> None:
    """The committed view: found, its corners as committed, each within 1 px of the fit.

    The committed corners are the gradient refinement's (``method="gradient"``); the default
    point-symmetry refinement moves them by under 0.5 px.
    """
    _, corners, names, _ = views
    grey = np.asarray(Image.open(DATA / "sweetiepie-left0015.jpg").convert("L"))
    det = find_checkerboard(grey, BOARD, method="gradient")
    assert det.found
    k = names.index("left0015.jpg")
    np.testing.assert_allclose(np.asarray(det.corners), corners[k], atol=0.01)
    assert float(np.hypot(*fisheye.residuals[k].T).max()) < 1.0
    sym = find_checkerboard(grey, BOARD)
    assert sym.found
    assert float(np.hypot(*(np.asarray(sym.corners) - corners[k]).T).max()) < 0.5
