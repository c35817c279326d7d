"""``imageform calibrate / pose / triangulate``: outputs, tables, bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.cli.calibration_cmds import parse_board, parse_length_mm
from imageform.errors import InvalidInputError
from imageform.geometry import CalibrationResult
from imageform.geometry.calibration_refine import rodrigues

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def test_calibrate_opencv_left(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pattern = str(shared_data / "opencv-left" / "left0[1-6].jpg")
    out, plot = tmp_path / "cam.toml", tmp_path / "err.png"
    code = main(
        ["calibrate", pattern, "--board", "9x6", "--square", "25mm", "--out", str(out),
         "--plot", str(plot)]
    )  # fmt: skip
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "left03.jpg" in captured.out and "RMS" in captured.out
    assert plot.stat().st_size > 1000
    cal = CalibrationResult.from_toml(out)
    assert 500 < cal.K[0, 0] < 570 and cal.image_size == (640, 480)
    # output exists now: refused without --force
    assert main(["calibrate", pattern, "--board", "9x6", "--out", str(out)]) == 1
    assert "--force" in capsys.readouterr().err
    assert (
        main(["calibrate", pattern, "--board", "9x6", "--out", str(out), "--force", "--json"]) == 0
    )
    summary = json.loads(capsys.readouterr().out)
    assert summary["views_used"] == 6 and len(summary["per_view"]) == 6


def test_calibrate_bad_input(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "cam.toml")
    assert main(["calibrate", str(tmp_path / "*.jpg"), "--board", "9x6", "--out", out]) == 1
    assert "no files match" in capsys.readouterr().err
    bad = tmp_path / "bad.jpg"
    bad.write_bytes(b"not an image")
    assert main(["calibrate", str(bad), "--board", "9x6", "--out", out]) == 1
    assert "cannot read" in capsys.readouterr().err
    # no board: the pattern size is wrong for every view
    one = str(shared_data / "opencv-left" / "left01.jpg")
    assert main(["calibrate", one, "--board", "7x7", "--out", out]) == 1
    err = capsys.readouterr().err
    assert "no 7x7 checkerboard found" in err and "warning" in err
    # images of different sizes
    from PIL import Image

    small = tmp_path / "small.png"
    Image.open(one).resize((320, 240)).save(small)
    assert main(["calibrate", one, str(small), "--board", "9x6", "--out", out]) == 1
    assert "one size" in capsys.readouterr().err
    assert main(["calibrate", one, "--board", "nine", "--out", out]) == 1
    assert "COLSxROWS" in capsys.readouterr().err
    # one view: too few for the full model
    copy = tmp_path / "only.jpg"
    shutil.copy(one, copy)
    code = main(["calibrate", str(copy), "--board", "9x6", "--out", out])
    err = capsys.readouterr().err
    assert code == 0 and "only 1 view" in err


def test_parsers() -> None:
    assert parse_board("9x6") == (9, 6)
    assert parse_length_mm("2.5cm") == 25.0 and parse_length_mm("1in") == 25.4
    assert parse_length_mm("30") == 30.0
    with pytest.raises(InvalidInputError, match="unit"):
        parse_length_mm("25 furlongs")
    with pytest.raises(InvalidInputError, match="COLSxROWS"):
        parse_board("1x6")


def _camera_toml(path: Path, rvec: list[float], t: list[float]) -> None:
    path.write_text(
        f"[camera]\nfx = 800.0\nfy = 800.0\ncx = 320.0\ncy = 240.0\nrvec = {rvec}\nt = {t}\n"
    )


def _row(a: np.ndarray, b: np.ndarray) -> str:
    return ",".join(repr(float(v)) for v in (*a, *b))


def test_pose_and_triangulate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (20, 3)) + [0, 0, 6]
    poses = [([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]), ([0.0, -0.15, 0.0], [-1.0, 0.0, 0.1])]
    uvs = []
    for rv, t in poses:
        cam = X @ rodrigues(np.array([rv]))[0].T + t
        uvs.append(cam[:, :2] / cam[:, 2:] * 800 + [320, 240])
    cam_toml = tmp_path / "cam.toml"
    _camera_toml(cam_toml, *poses[0])
    pts = tmp_path / "pairs.csv"
    pts.write_text("X,Y,Z,u,v\n" + "\n".join(_row(a, b) for a, b in zip(X, uvs[1], strict=True)))
    out = tmp_path / "posed.toml"
    assert (
        main(["pose", "--camera", str(cam_toml), "--points", str(pts), "--out", str(out), "--json"])
        == 0
    )
    s = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(s["t"], poses[1][1], atol=1e-8)
    assert s["valid"] and s["inliers"] == 20
    assert main(["pose", "--camera", str(cam_toml), "--points", str(pts), "--ransac"]) == 0
    assert "20/20 inliers" in capsys.readouterr().out
    # triangulate with the camera written by `pose`
    obs = tmp_path / "obs.csv"
    obs.write_text("\n".join(_row(a, b) for a, b in zip(uvs[0], uvs[1], strict=True)))
    res_csv = tmp_path / "X.csv"
    cams = ["--camera", str(cam_toml), "--camera", str(out)]
    code = main(["triangulate", *cams, "--points", str(obs), "--out", str(res_csv)])
    assert code == 0, capsys.readouterr().err
    got = np.loadtxt(res_csv, delimiter=",", skiprows=1)
    np.testing.assert_allclose(got[:, :3], X, atol=1e-7)
    assert got[:, 7].all()


def test_pose_triangulate_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam_toml = tmp_path / "cam.toml"
    _camera_toml(cam_toml, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    pts = tmp_path / "p.csv"
    pts.write_text("1,2,3,4\n")
    assert main(["pose", "--camera", str(cam_toml), "--points", str(pts)]) == 1
    assert "5 columns" in capsys.readouterr().err
    pts.write_text("0,0,5,320,240\n1,0,5,480,240\n0,1,5,320,400\n")
    assert main(["pose", "--camera", str(cam_toml), "--points", str(pts)]) == 1
    assert "at least 4 points" in capsys.readouterr().err
    obs = tmp_path / "obs.csv"
    obs.write_text("1,2,3,4\n")
    out = str(tmp_path / "X.csv")
    assert main(["triangulate", "--camera", str(cam_toml), "--points", str(obs), "--out", out]) == 1
    assert "2 columns" in capsys.readouterr().err
