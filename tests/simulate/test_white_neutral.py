"""The simulator's colour matrix keeps white neutral (issue 26).

The matrix fitted on the scene's ColorChecker is a free least-squares fit: a white-balanced
grey came out 2.36 CIEDE2000 from D65 white (default scene, 20.8 at 160 x 90), so a raw
developer given the DNG's AsShotNeutral (the white balance) and ColorMatrix rendered the
simulator's DNG with another white than the simulator's own output. The matrix's white
shift now goes into the white-balance gains (the same output): the matrix keeps white.
"""

from __future__ import annotations

import numpy as np

from imageform.color import delta_e_ciede2000, linear_srgb_to_xyz, xyz_to_lab


def _white_error(rgb: np.ndarray) -> float:
    """CIEDE2000 of a linear sRGB colour (scaled to Y = 1) from the D65 white."""
    y = float(np.asarray(linear_srgb_to_xyz(rgb))[1])
    lab = xyz_to_lab(np.asarray(linear_srgb_to_xyz(rgb)) / y, white="D65")
    return float(delta_e_ciede2000(lab, np.array([100.0, 0.0, 0.0])))


def test_white_balanced_grey_lands_on_d65() -> None:
    from imageform.simulate import default_scene, simulate, simulated_color_matrix

    res = simulate(default_scene().resized(160), rng=0)
    M = np.asarray(res.metrics["color_correction_matrix"])
    assert _white_error(np.ones(3) @ M) < 0.05  # was 2.36 (a free least-squares fit)
    # the DNG's colour description: camera RGB of the neutral (AsShotNeutral) -> XYZ
    cm, neutral = simulated_color_matrix(res)
    xyz = np.linalg.solve(cm, neutral)
    lab = xyz_to_lab(xyz / xyz[1], white="D65")
    assert float(delta_e_ciede2000(lab, np.array([100.0, 0.0, 0.0]))) < 0.05


def test_the_white_shift_goes_into_the_gains_the_output_unchanged() -> None:
    from imageform.simulate.pipeline import _white_kept
    from imageform.simulate.stages import ColorCorrected, WhiteBalanced

    rng = np.random.default_rng(3)
    img = rng.uniform(0.05, 1.0, (8, 9, 3))
    g = np.array([1.8, 1.0, 1.3])
    M = np.array([[1.5, -0.3, 0.0], [-0.4, 1.6, -0.5], [0.0, -0.2, 1.4]])  # white shifted
    wb, cc, folded = _white_kept(WhiteBalanced(img * g, g), ColorCorrected((img * g) @ M, M), img)
    assert folded and wb.gains[1] == 1.0
    np.testing.assert_allclose(wb.image @ cc.matrix, (img * g) @ M, rtol=1e-12)
    s = np.ones(3) @ cc.matrix
    np.testing.assert_allclose(s, s[0], rtol=1e-12)
    same = _white_kept(WhiteBalanced(img, np.ones(3)), ColorCorrected(img, np.eye(3)), img)
    assert same[2] is False  # no matrix: nothing to fold
