"""``imageform calibrate --partial``: views whose checkerboard is cut by the border are used.

Truth: views rendered analytically through a known camera with distortion
(``tests/geometry/checkerboard_support.render_board_through``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from imageform.cli import main

K_TRUE = np.array([[420.0, 0, 322.0], [0, 420.0, 236.0], [0, 0, 1]])


def _views(folder: Path) -> int:
    """Write 12 views of a 9 x 6 board through a wide-angle lens (k1 -0.25); return how many cut
    it at the border (the others show it whole)."""
    from scipy.spatial.transform import Rotation

    from imageform.geometry import BrownConrady, Camera, checkerboard_points
    from imageform.geometry import project_points_distorted as project
    from tests.geometry.checkerboard_support import render_board_through

    D = BrownConrady(-0.25, 0.07)
    rng = np.random.default_rng(7)
    mid = np.array([4.0, 2.5, 0.0])
    cut = 0
    for k in range(12):
        rot = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.radians([35, 35, 30])).as_matrix()
        far = k >= 4  # four boards in the middle, then boards off to a side
        u = rng.uniform(0.05, 0.95) if far else rng.uniform(0.4, 0.6)
        v = rng.uniform(0.05, 0.95) if far else rng.uniform(0.4, 0.6)
        ray = np.linalg.solve(K_TRUE, [u * 640, v * 480, 1.0])
        t = ray * rng.uniform(6.0, 8.0) - rot @ mid
        cam = Camera(K_TRUE, rot, t, (640, 480), distortion=D)
        img = render_board_through(cam, 9, 6, 1.0, blur=1.0, noise=0.01, seed=k)
        uv = np.asarray(project(checkerboard_points((9, 6)), K_TRUE, rot, t, D)[0])
        cut += bool(np.any((uv < 0) | (uv > [639, 479])))
        u8 = np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)
        Image.fromarray(u8).save(folder / f"view{k:02d}.png")
    return cut


def test_calibrate_partial_views(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without --partial the cut views are dropped; with it they are used with their parts'
    own labels, the table says which views are partial and how many corners each gave, and K
    and k1 come back near the truth (RMS under 0.1 px)."""
    cut = _views(tmp_path)
    assert cut >= 4
    pattern = str(tmp_path / "view*.png")
    base = ["calibrate", pattern, "--board", "9x6", "--json"]
    assert main([*base, "-o", str(tmp_path / "whole.toml")]) == 0
    whole = json.loads(capsys.readouterr().out)
    assert main([*base, "--partial", "-o", str(tmp_path / "part.toml")]) == 0
    part = json.loads(capsys.readouterr().out)
    assert part["views_partial"] >= 3 and whole["views_partial"] is None
    assert part["views_used"] == whole["views_used"] + part["views_partial"]
    partial_rows = [r for r in part["per_view"] if r["partial"] is not None]
    assert len(partial_rows) == part["views_partial"]
    for r in partial_rows:
        c, rr = r["partial"]
        assert r["points"] == c * rr >= 12 and c >= rr >= 3
    assert part["rms_px"] < 0.1
    fit = np.array([part["fx"], part["fy"], part["cx"], part["cy"]])
    np.testing.assert_allclose(fit, [420.0, 420.0, 322.0, 236.0], atol=0.3)
    assert abs(part["distortion"]["k1"] + 0.25) < 0.005
    # the table for a person
    assert main([*base[:-1], "--partial", "-o", str(tmp_path / "p2.toml")]) == 0
    text = capsys.readouterr().out
    assert "corners  part" in text and "partial " in text and "whole" in text
    assert f"({part['views_partial']} partial," in text


def test_calibrate_partial_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--partial is a checkerboard's: a ChArUco board is refused in one line (its views are
    used in part already)."""
    Image.fromarray(np.zeros((64, 64), np.uint8)).save(tmp_path / "a.png")
    argv = ["calibrate", str(tmp_path / "a.png"), "--board", "charuco:7x5", "--marker", "0.7"]
    assert main([*argv, "--partial", "-o", str(tmp_path / "c.toml")]) == 2
    assert "--partial is for a checkerboard --board" in capsys.readouterr().err
