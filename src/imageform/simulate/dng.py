"""The simulated camera's raw mosaic as a DNG file (docs/raw.md).

What a raw developer (LibRaw, darktable, RawTherapee) needs to develop it as the simulator's camera
would.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imageform._files import check_writable
from imageform.errors import InvalidInputError
from imageform.simulate.result import SimulationResult
from imageform.simulate.scene import Scene

__all__ = ["simulated_color_matrix", "write_simulated_dng"]


def simulated_color_matrix(result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    r"""Return the simulated camera's DNG colour description: ``(color_matrix, as_shot_neutral)``.

    The simulator white-balances camera RGB with gains :math:`\mathbf g` and maps it to
    linear sRGB with the fitted matrix :math:`M` (``image @ M``), so camera RGB to CIE XYZ
    (D65) is :math:`A = S\,M^T \mathrm{diag}(\mathbf g)` with :math:`S` the sRGB-to-XYZ
    matrix (IEC 61966-2-1). DNG's ColorMatrix1 is its inverse :math:`C = A^{-1}` (XYZ to
    camera, CalibrationIlluminant1 D65) and AsShotNeutral is :math:`1/\mathbf g`, scaled
    to a largest component of 1.
    """
    from imageform.color import rgb_to_xyz_matrix

    if not isinstance(result, SimulationResult):
        raise InvalidInputError(
            f"expected a SimulationResult (simulate), got {type(result).__name__}"
        )
    g = np.asarray(result.metrics["white_balance_gains"], np.float64)
    M = np.asarray(result.metrics["color_correction_matrix"], np.float64)
    A = np.asarray(rgb_to_xyz_matrix("srgb"), np.float64) @ M.T @ np.diag(g)
    neutral = 1.0 / g
    return np.linalg.inv(A), neutral / neutral.max()


def write_simulated_dng(result: SimulationResult, scene: Scene, path: str | Path) -> Path:
    """Write the ``raw`` stage of ``result`` (the simulation of ``scene``) as a DNG file.

    Written by :func:`imageform.io.write_dng` with the sensor's black and white levels, its CFA
    pattern and :func:`simulated_color_matrix`.

    An odd image size loses its last row or column (a DNG Bayer tile is 2x2).
    """
    from imageform.io import write_dng

    check_writable(path, "path")
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"expected a Scene (load_scene), got {type(scene).__name__}")
    cm, neutral = simulated_color_matrix(result)
    raw = np.asarray(result.stage("raw").image)
    h, w = raw.shape[0] // 2 * 2, raw.shape[1] // 2 * 2
    sensor = scene.sensor
    return write_dng(
        path,
        raw[:h, :w],
        cfa_pattern=scene.config.sensor.cfa,
        black_level=float(round(sensor.black_level)),
        white_level=float(sensor.max_dn),
        color_matrix=cm,
        as_shot_neutral=neutral,
        calibration_illuminant="D65",
        camera_model="imageform simulated camera",
    )
