"""Fixtures of the geometry tests: OpenCV's chessboard views and detections on them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.geometry.checkerboard import CheckerboardResult, find_checkerboard
from tests.geometry.checkerboard_support import CRITERIA, PATTERN, VIEWS


@pytest.fixture(scope="session")
def views(shared_data: Path) -> dict[str, np.ndarray]:
    """OpenCV's 13 left*.jpg views, uint8 grey (skips without the shared data or cv2)."""
    cv2 = pytest.importorskip("cv2")
    folder = shared_data / "opencv-left"
    out = {}
    for name in VIEWS:
        img = cv2.imread(str(folder / name), cv2.IMREAD_GRAYSCALE)
        assert img is not None, name
        out[name] = img
    return out


@pytest.fixture(scope="session")
def opencv_corners(views: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Cross-check reference: OpenCV 5.0 findChessboardCorners + cornerSubPix (tutorial)."""
    cv2 = pytest.importorskip("cv2")
    out = {}
    for name, img in views.items():
        ok, c = cv2.findChessboardCorners(img, PATTERN, None)
        assert ok, name
        out[name] = cv2.cornerSubPix(img, c, (11, 11), (-1, -1), CRITERIA).reshape(-1, 2)
    return out


@pytest.fixture(scope="session")
def ours(views: dict[str, np.ndarray]) -> dict[str, CheckerboardResult]:
    """imageform's detections on the views, with OpenCV's refinement (gradients, window 11)."""
    return {
        name: find_checkerboard(img, PATTERN, half_window=11, method="gradient")
        for name, img in views.items()
    }
