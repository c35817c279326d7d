"""``imageform lens`` and ``imageform undistort``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform._units import parse_length
from imageform.cli import main
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry.distortion import BrownConrady, KannalaBrandt
from imageform.io import read_camera


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
    """Lengths go through the one unit table; a bad value is bad usage (exit 2)."""
    assert main(["lens", "--focal", "50 parsecs", "--f-number", "2", "--focus", "2m"]) == 2
    assert "unknown unit 'parsecs' for --focal" in capsys.readouterr().err
    assert main(["lens", "--focal", "-50mm", "--f-number", "2", "--focus", "2m"]) == 2
    assert "expected --focal > 0" in capsys.readouterr().err
    assert main(["lens", "--focal", "50mm", "--f-number", "0", "--focus", "2m"]) == 2
    assert "expected --f-number > 0" in capsys.readouterr().err
    assert main(["lens", "--focal", "50mm", "--f-number", "2", "--focus", "inf"]) == 2
    assert "finite" in capsys.readouterr().err
    # the same lengths in other units give the same table
    assert main(["lens", "--focal", "5cm", "--f-number", "8", "--focus", "2000mm", "--json"]) == 0
    a = json.loads(capsys.readouterr().out)
    assert main(["lens", "--focal", "50", "--f-number", "8", "--focus", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == a


def test_parse_length() -> None:
    assert parse_length("0.03mm", "coc") == pytest.approx(3e-5)
    assert parse_length("2", "focus") == 2.0
    assert parse_length("35", "focal", default_unit="mm") == pytest.approx(0.035)
    with pytest.raises(InvalidInputError, match="with a unit"):
        parse_length("two metres", "focus")
    with pytest.raises(UnknownOptionError, match="valid: m, cm, mm"):
        parse_length("3furlongs", "focus")


def _write_camera(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


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
    assert main(["undistort", str(src), "-o", str(out), "--camera", str(cam)]) == 0
    res = np.asarray(Image.open(out))
    assert res.shape == img.shape and res.dtype == np.uint8
    from imageform.geometry.undistort import undistort_image

    cf = read_camera(cam)
    assert cf.camera.distortion == BrownConrady(k1=-0.1)
    want = np.round(undistort_image(img, np.asarray(cf.camera.K), cf.camera.distortion) * 255)
    np.testing.assert_array_equal(res, want.astype(np.uint8))
    # outputs never overwrite inputs; an existing output needs --force
    assert main(["undistort", str(src), "-o", str(src), "--camera", str(cam)]) == 1
    assert main(["undistort", str(src), "-o", str(out), "--camera", str(cam)]) == 1
    assert "--force" in capsys.readouterr().err
    args = ["undistort", str(src), "-o", str(out), "--camera", str(cam), "--force", "--json"]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["model"] == "brown_conrady"
    assert (
        main(["undistort", str(tmp_path / "nope.png"), "-o", str(tmp_path / "x.png"),
              "--camera", str(cam)])
        == 1
    )  # fmt: skip


def test_undistort_any_model_and_camera_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A fisheye camera file undistorts with its own model; --camera-out writes the camera of
    the output (same K, no distortion); an image of another size is refused."""
    from imageform.geometry.undistort import undistort_image
    from imageform.io import read_image

    img = np.random.default_rng(1).random((40, 50, 1)).astype(np.float32)
    src = tmp_path / "in.npy"
    np.save(src, img)
    cam = _write_camera(
        tmp_path / "fe.toml",
        'format = "imageform-camera"\nversion = 1\n[image]\nwidth = 50\nheight = 40\n'
        "[intrinsics]\nfx = 40\nfy = 41\ncx = 24.5\ncy = 19.5\n"
        '[distortion]\nmodel = "kannala_brandt"\nk1 = 0.05\nk2 = -0.01\n',
    )
    out, cam_out = tmp_path / "out.npy", tmp_path / "flat.toml"
    args = ["undistort", str(src), "-o", str(out), "--camera", str(cam), "--camera-out"]
    assert main([*args, str(cam_out)]) == 0
    want = undistort_image(img, read_camera(cam).camera.K, KannalaBrandt(0.05, -0.01))
    np.testing.assert_array_equal(read_image(out), want)
    flat = read_camera(cam_out)
    assert flat.camera.distortion is None and flat.camera.image_size == (50, 40)
    np.testing.assert_array_equal(np.asarray(flat.camera.K), np.asarray(read_camera(cam).camera.K))
    np.save(src, img[:30])
    assert main([*args, str(cam_out), "--force"]) == 1
    assert "is for 50 x 40 px images" in capsys.readouterr().err
