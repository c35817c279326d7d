"""``characterize`` of a small lab set (issue 25): edges of different lengths.

At 160x120 the slanted-edge ROIs of the lab's edge image are cut to different lengths, so
each edge's SFR comes on its own frequency grid; characterize stacked them as they were and
failed with NumPy's "all input arrays must have the same shape". The curves are now put on
one grid (the coarsest) before the median.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from imageform.geometry import BrownConrady, Camera
from imageform.io import CameraFile
from imageform.simulate import render_lab_set
from imageform.workflows import characterize_camera

pytest.importorskip("rawpy")


def test_characterize_a_160x120_lab_set(tmp_path: Path) -> None:
    """The lab set of a calibrated-looking camera (fx 140 px, a Gaussian lens of 0.318 px)."""
    cam = Camera(
        [[140.0, 0, 79.5], [0, 140.0, 59.5], [0, 0, 1]],
        image_size=(160, 120),
        distortion=BrownConrady(k1=-0.12, k2=0.01),
    )
    cf = CameraFile(cam, optics={"model": "gaussian", "gaussian_sigma_px": 0.318})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lab = render_lab_set(cf, tmp_path / "lab", seed=0)
        result = characterize_camera(lab.folder)
    sh = result.sharpness
    assert sh is not None
    assert len(sh.angles_deg) >= 2
    assert sh.sfr.shape == (sh.frequency.size, len(sh.channels))
    assert np.all(np.isfinite(sh.sfr)) and sh.sfr[0] == pytest.approx(1.0, abs=1e-6)
    # the system MTF50 of a 0.318 px Gaussian times the pixel is about 0.4 cy/px
    assert all(0.3 < m < 0.5 for m in sh.mtf50)
