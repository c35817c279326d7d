"""``imageform lens`` and ``imageform undistort``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.cli.optics_cmds import load_camera_toml, parse_length
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry.distortion import BrownConrady, KannalaBrandt


def test_lens_table(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["lens", "--focal", "50mm", "--f-number", "2.8", "--focus", "2m", "--coc", "0.03mm"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "1.877 m" in out and "2.140 m" in out and "29.812 m" in out
    assert "f/2.8 *" in out and "f/8" in out


def test_lens_json(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["lens", "--focal", "50mm", "--f-number", "8", "--focus", "20m", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert data["hyperfocal_m"] == pytest.approx(10.4667, abs=1e-4)  # 50 mm f/8 c 0.03 mm
    assert data["far_m"] is None  # beyond the hyperfocal distance: sharp to infinity
    assert len(data["table"]) == 9


def test_lens_object_inside_focal_length(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["lens", "--focal", "50mm", "--f-number", "2.8", "--focus", "30mm"])
    err = capsys.readouterr().err
    assert rc == 1 and "inside the focal length" in err and "virtual" in err


def test_lens_bad_units(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lens", "--focal", "50 parsecs", "--f-number", "2", "--focus", "2m"]) == 1
    assert "unknown unit" in capsys.readouterr().err


def test_parse_length() -> None:
    assert parse_length("0.03mm", "coc") == pytest.approx(3e-5)
    assert parse_length("2", "focus") == 2.0
    assert parse_length("35", "focal", default_unit="mm") == pytest.approx(0.035)
    with pytest.raises(InvalidInputError, match="with a unit"):
        parse_length("two metres", "focus")
    with pytest.raises(UnknownOptionError, match="valid: cm, ft"):
        parse_length("3furlongs", "focus")


def _write_camera(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_load_camera_toml(tmp_path: Path) -> None:
    cam = _write_camera(
        tmp_path / "c.toml", "fx = 500\nfy = 510\ncx = 320\ncy = 240\nk1 = -0.2\np2 = 0.001\n"
    )
    K, model = load_camera_toml(cam)
    assert K[0, 0] == 500 and K[1, 1] == 510 and K[0, 2] == 320
    assert model == BrownConrady(k1=-0.2, p2=0.001)
    fe = _write_camera(
        tmp_path / "f.toml",
        '[camera]\nmodel = "kannala-brandt"\nfx = 300\nfy = 300\ncx = 1\ncy = 1\nk1 = 0.01\n',
    )
    assert load_camera_toml(fe)[1] == KannalaBrandt(k1=0.01)
    bad = _write_camera(tmp_path / "b.toml", "fx = 1\nfy = 1\ncx = 0\ncy = 0\nk9 = 1\n")
    with pytest.raises(UnknownOptionError, match="unknown key"):
        load_camera_toml(bad)
    miss = _write_camera(tmp_path / "m.toml", "fx = 1\n")
    with pytest.raises(InvalidInputError, match="missing fy, cx, cy"):
        load_camera_toml(miss)
    wrong = _write_camera(
        tmp_path / "w.toml", 'model = "division"\nfx = 1\nfy = 1\ncx = 0\ncy = 0\np1 = 0.1\n'
    )
    with pytest.raises(InvalidInputError, match="not part of the division model"):
        load_camera_toml(wrong)


def test_undistort_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from PIL import Image

    rng = np.random.default_rng(0)
    img = (rng.random((48, 64, 3)) * 255).astype(np.uint8)
    src = tmp_path / "in.png"
    Image.fromarray(img).save(src)
    cam = _write_camera(
        tmp_path / "cam.toml", "fx = 60\nfy = 60\ncx = 31.5\ncy = 23.5\nk1 = -0.1\n"
    )
    out = tmp_path / "out.png"
    assert main(["undistort", str(src), str(out), "--camera", str(cam)]) == 0
    res = np.asarray(Image.open(out))
    assert res.shape == img.shape and res.dtype == np.uint8
    from imageform.geometry.undistort import undistort_image

    want = np.round(undistort_image(img, *load_camera_toml(cam)) * 255)
    np.testing.assert_array_equal(res, want.astype(np.uint8))
    # outputs never overwrite inputs; an existing output needs --force
    assert main(["undistort", str(src), str(src), "--camera", str(cam)]) == 1
    assert main(["undistort", str(src), str(out), "--camera", str(cam)]) == 1
    assert "--force" in capsys.readouterr().err
    assert main(["undistort", str(src), str(out), "--camera", str(cam), "--force", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == "BrownConrady"
    assert (
        main(
            ["undistort", str(tmp_path / "nope.png"), str(tmp_path / "x.png"), "--camera", str(cam)]
        )
        == 1
    )
