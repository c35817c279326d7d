"""``imageform depth``: a stereo pair and its stereo camera file to depth, disparity, points.

The rig file is written as ``imageform stereo-calibrate`` writes it
(``StereoCameraFile.from_calibration`` of a ``stereo_calibrate`` result, on exact
projections of a board seen by the rendered pair's two cameras); the pair is the ray-cast
scene of ``tests/stereo_scenes.py`` with known depth. The rendered-and-calibrated chain
(distortion, a rotated rig) is in ``tests/geometry/test_stereo_simulated.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.geometry import (
    checkerboard_points,
    project_points_distorted,
    rvec_to_matrix,
    stereo_calibrate,
)
from imageform.io import (
    StereoCameraFile,
    read_image,
    read_stereo_camera,
    write_image,
    write_stereo_camera,
)
from imageform.workflows._ply import read_points_ply

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from stereo_scenes import StereoScene, render_pair

W, H = 320, 240


def _rig(scene: StereoScene) -> StereoCameraFile:
    """The pair's rig calibrated from exact board projections (stereo-calibrate's file)."""
    K = np.array([[scene.f, 0, (W - 1) / 2], [0, scene.f, (H - 1) / 2], [0, 0, 1]])
    T = np.array([-scene.baseline, 0.0, 0.0])
    obj = checkerboard_points((9, 6), 60.0)
    views = [
        ([0.3, 0.1, 0], [-240, -150, 700]),
        ([-0.2, 0.3, 0.1], [-220, -160, 760]),
        ([0.1, -0.35, -0.1], [-260, -120, 720]),
        ([0.2, 0.2, 0.3], [-200, -180, 740]),
    ]
    uvl, uvr = [], []
    for r, t in views:
        Rk = np.asarray(rvec_to_matrix(r))
        uvl.append(project_points_distorted(obj, K, Rk, t, None)[0])
        uvr.append(project_points_distorted(obj, K, Rk, np.asarray(t) + T, None)[0])
    res = stereo_calibrate([obj] * 4, uvl, uvr, (W, H), fix=("k1", "k2", "p1", "p2", "k3"))
    return StereoCameraFile.from_calibration(res, command="imageform stereo-calibrate")


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, StereoScene]:
    scene = render_pair(W, H)
    d = tmp_path_factory.mktemp("depth")
    write_stereo_camera(d / "rig.toml", _rig(scene))
    write_image(d / "left.png", (scene.left * 255).round().astype(np.uint8))
    write_image(d / "right.png", (scene.right * 255).round().astype(np.uint8))
    return d, scene


def _line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_depth_disparity_and_points(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d, scene = files
    rig = read_stereo_camera(d / "rig.toml")
    assert abs(np.linalg.norm(rig.T) - scene.baseline) < 1e-6
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48"]
    out, ply = tmp_path / "z.tiff", tmp_path / "cloud.ply"
    assert main([*base, "-o", str(out), "--points", str(ply), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    z = np.asarray(read_image(out))[..., 0]
    assert z.dtype == np.float32 and z.shape == (H, W)
    ok = scene.visible & np.isfinite(z)
    assert ok.mean() > 0.75  # measured 83 % of all pixels
    rel = np.abs(z - scene.depth)[ok] / scene.depth[ok]
    assert np.median(rel) < 0.01 and np.mean(rel < 0.05) > 0.98  # measured 0.55 % median, 99.8 %
    assert summary["valid_fraction"] == pytest.approx(np.isfinite(z).mean())
    assert summary["n_points"] == int(np.isfinite(z).sum())
    cloud = read_points_ply(ply)
    assert set(cloud) == {"x", "y", "z", "red", "green", "blue"}
    assert cloud["z"].size == summary["n_points"]
    np.testing.assert_allclose(np.sort(cloud["z"]), np.sort(z[np.isfinite(z)]), rtol=1e-5)
    # --disparity: f B / Z
    dout = tmp_path / "d.npy"
    assert main([*base, "--disparity", "-o", str(dout)]) == 0
    disp = np.load(dout)
    fin = np.isfinite(disp)
    np.testing.assert_array_equal(fin, np.isfinite(z))
    np.testing.assert_allclose(disp[fin] * z[fin], scene.f * scene.baseline, rtol=1e-3)


def test_depth_refusals_write_nothing(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d, scene = files
    left, right, rig = str(d / "left.png"), str(d / "right.png"), str(d / "rig.toml")
    out = tmp_path / "z.tiff"
    ok = ["--camera", rig, "-o", str(out)]
    write_image(tmp_path / "small.png", np.zeros((100, 120), np.uint8))
    nan = np.asarray(scene.right, dtype=np.float32).copy()
    nan[5, 5] = np.nan
    np.save(tmp_path / "nan.npy", nan[..., None])
    vertical = read_stereo_camera(rig)
    from dataclasses import replace

    from imageform.geometry import Camera

    c = vertical.right.camera
    v_cam = Camera(c.K, c.R, [0.0, -60.0, 0.0], c.image_size, distortion=c.distortion)
    write_stereo_camera(tmp_path / "vertical.toml", replace(vertical, right=replace(
        vertical.right, camera=v_cam)))  # fmt: skip
    single = tmp_path / "single.toml"
    single.write_text("[intrinsics]\nfx = 400.0\nfy = 400.0\ncx = 160.0\ncy = 120.0\n")
    cases = [
        ([left, str(tmp_path / "small.png"), *ok], "small.png is 120 x 100 px"),
        ([left, str(tmp_path / "nan.npy"), *ok], "nan.npy"),
        ([left, left, *ok], "left and right are both"),
        ([left, right, *ok, "--block-size", "4"], "--block-size must be 3, 5 or 7"),
        ([left, right, *ok, "--p1", "20", "--p2", "10"], "--p2 (10) must exceed --p1 (20)"),
        ([left, right, *ok, "--points", str(tmp_path / "c.txt")], "give a .ply name"),
        ([left, right, "--camera", str(tmp_path / "vertical.toml"), "-o", str(out)], "vertically"),
        ([left, right, "--camera", str(single), "-o", str(out)], "single.toml"),
        ([left, right, "--camera", str(tmp_path / "none.toml"), "-o", str(out)], "none.toml"),
        ([left, right, "--camera", rig, "-o", str(tmp_path / "z.png")], "z.png"),
    ]
    for args, needle in cases:
        assert main(["depth", *args]) != 0, args
        line = _line(capsys)
        assert needle in line, (args, line)
        assert not out.exists() and not (tmp_path / "c.txt").exists()
    # the command line's own range check (a usage error, exit 2)
    assert main(["depth", left, right, *ok, "--num-disparities", "0"]) == 2
    assert "expected --num-disparities >= 1, got 0" in capsys.readouterr().err
    # a failure after the depth map is computed leaves neither output: --points is refused
    # by name first, so check an unwritable points folder instead
    bad_ply = tmp_path / "no-such-folder" / "c.ply"
    assert main(["depth", left, right, *ok, "--points", str(bad_ply)]) != 0
    capsys.readouterr()
    assert not out.exists() and not bad_ply.exists()
