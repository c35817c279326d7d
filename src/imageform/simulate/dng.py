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

__all__ = [
    "simulated_baseline_exposure",
    "simulated_color_matrix",
    "simulated_vignette_opcode",
    "write_simulated_dng",
]


def _gains_and_matrix(result: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """Return the simulator's white-balance gains and colour matrix from ``result``."""
    if not isinstance(result, SimulationResult):
        raise InvalidInputError(
            f"expected a SimulationResult (simulate), got {type(result).__name__}"
        )
    g = np.asarray(result.metrics["white_balance_gains"], np.float64)
    M = np.asarray(result.metrics["color_correction_matrix"], np.float64)
    return g, M


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

    g, M = _gains_and_matrix(result)
    A = np.asarray(rgb_to_xyz_matrix("srgb"), np.float64) @ M.T @ np.diag(g)
    neutral = 1.0 / g
    return np.linalg.inv(A), neutral / neutral.max()


def simulated_baseline_exposure(result: SimulationResult) -> float:
    r"""Return the DNG BaselineExposure (stops) that makes a developer render as the simulator.

    A raw developer normalises the colour matrix so that white-balanced camera white, with
    the smallest gain 1, is the output's white (dcraw/LibRaw's ``cam_xyz_coeff``, Adobe's DNG
    SDK). The simulator's gains :math:`\mathbf g` (green 1) and fitted matrix :math:`M`
    carry the exposure's scale instead: a balanced white :math:`k\mathbf 1` becomes
    :math:`k\,s\,\mathbf 1` with :math:`s` the common column sum of :math:`M` (which keeps
    white, :math:`\mathbf 1^T M = s\,\mathbf 1^T`), where the developer gives
    :math:`k / \min \mathbf g`. The ratio is :math:`s \min \mathbf g`, so
    :math:`EV = \log_2(s \min \mathbf g)` (DNG specification 1.4.0.0, BaselineExposure:
    the stops by which the default rendering should be brightened). 0 where :math:`M` does
    not keep white (no single factor renders every colour the simulator's way).
    """
    g, M = _gains_and_matrix(result)
    s = np.ones(3) @ M
    if not (np.all(s > 0) and np.allclose(s, s[1], rtol=1e-6) and np.all(g > 0)):
        return 0.0
    return float(np.log2(s[1] * g.min()))


def simulated_vignette_opcode(scene: Scene, shape: tuple[int, int]) -> np.ndarray | None:
    r"""Return the DNG FixVignetteRadial parameters of the simulator's lens-shading correction.

    The simulator divides the demosaiced image by the cos⁴ falloff
    :math:`1/(1 + x^2 + y^2)^2` of each pixel's ray (:math:`(x, y)` its normalised, undistorted
    image coordinates). Without distortion the gain is exactly DNG's polynomial,
    :math:`(1 + \rho^2)^2 = 1 + 2a\,r^2 + a^2 r^4` with :math:`a = (R/f)^2`; with it, the
    five coefficients :math:`k_0..k_4` are the least-squares fit of the gain over the
    ``shape`` (H, W) of the written mosaic in powers of :math:`r^2` (:math:`r` the distance from
    the principal point over the distance :math:`R` to the farthest corner, pixel centres at
    half-integers as the DNG SDK counts). Returns ``(k0, k1, k2, k3, k4, cx, cy)``, or None
    where the scene has no vignetting or does not correct it.
    """
    from imageform.simulate.render import _pixel_rays

    cfg = scene.config
    if cfg.lens.vignetting != "cos4" or not cfg.processing.lens_shading_correction:
        return None
    h, w = shape
    K = np.asarray(scene.camera.K, dtype=np.float64)
    cx, cy = (K[0, 2] + 0.5) / w, (K[1, 2] + 0.5) / h
    radius = float(np.hypot(max(cy * h, h - cy * h), max(cx * w, w - cx * w)))
    step = max(1, min(h, w) // 64)  # a 64-point lattice along the short side is plenty
    vv, uu = np.mgrid[0:h:step, 0:w:step].astype(np.float64)
    xy = _pixel_rays(scene.camera, uu.ravel(), vv.ravel())
    gain = (1.0 + np.sum(xy**2, axis=1)) ** 2
    r2 = ((vv.ravel() + 0.5 - cy * h) ** 2 + (uu.ravel() + 0.5 - cx * w) ** 2) / radius**2
    ok = np.isfinite(gain)
    basis = np.stack([r2[ok] ** (i + 1) for i in range(5)], axis=1)
    k = np.linalg.lstsq(basis, gain[ok] - 1.0, rcond=None)[0]
    return np.array([*k, cx, cy])


def write_simulated_dng(result: SimulationResult, scene: Scene, path: str | Path) -> Path:
    """Write the ``raw`` stage of ``result`` (the simulation of ``scene``) as a DNG file.

    Written by :func:`imageform.io.write_dng` with the sensor's black and white levels, its CFA
    pattern, :func:`simulated_color_matrix`, :func:`simulated_baseline_exposure` (the
    brightening a developer must apply to render what the simulator rendered) and, where the
    simulator corrects the lens's vignetting, :func:`simulated_vignette_opcode` (an
    OpcodeList3 FixVignetteRadial that :func:`imageform.io.develop` and Adobe's readers apply).

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
        baseline_exposure_ev=round(simulated_baseline_exposure(result), 6),
        fix_vignette_radial=simulated_vignette_opcode(scene, (h, w)),
    )
