"""The ``imageform`` command: lecture, project, exit codes and output safety."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from imageform.cli import main


def test_lecture_table_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lecture"]) == 0
    assert "570" in capsys.readouterr().out
    assert main(["lecture", "--json", "--topic", "vanishing"]) == 0
    result = json.loads(capsys.readouterr().out)
    rows = result["examples"]
    assert rows and all(r["agrees"] for r in rows) and result["all_agree"] is True
    assert main(["lecture", "--topic", "no such topic"]) == 2  # never an empty table
    assert "valid: pinhole" in capsys.readouterr().err


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("imageform ")


def test_project_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pts = tmp_path / "points.csv"
    pts.write_text("X,Y,Z\n3,-1,5\n0,0,-2\nnan,0,1\n1,,2\n")
    out = tmp_path / "uv.csv"
    assert main(["project", str(pts), "--fx", "100", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert {k: summary[k] for k in ("points", "valid", "output")} == {
        "points": 4,
        "valid": 1,
        "output": str(out),
    }
    assert summary["invalid"] == 3 and summary["not_finite"] == 2
    assert summary["behind_camera"] == 1
    lines = out.read_text().splitlines()
    assert lines[0] == "u,v,valid"
    assert [float(v) for v in lines[1].split(",")] == [60.0, -20.0, 1.0]
    for line in lines[2:]:  # behind the camera, NaN, an empty cell: nan with valid = 0
        u, v, ok = line.split(",")
        assert math.isnan(float(u)) and math.isnan(float(v)) and ok == "0"
    assert main(["project", str(pts), "--fx", "100", "-o", str(out), "--force"]) == 0
    assert "3 invalid" in capsys.readouterr().out
    # existing output needs --force; an input is never overwritten
    assert main(["project", str(pts), "--fx", "100", "--out", str(out)]) == 1
    assert "--force" in capsys.readouterr().err
    assert main(["project", str(pts), "--fx", "100", "--out", str(pts), "--force"]) == 1
    assert "also an input" in capsys.readouterr().err
    assert main(["project", str(pts), "--fx", "100", "--out", str(out), "--force"]) == 0


def test_project_camera_toml(tmp_path: Path) -> None:
    cam = tmp_path / "cam.toml"
    cam.write_text(
        "[camera]\nfx = 500\nfy = 500\ncx = 320\ncy = 240\nrvec = [0, 0, 0]\nt = [0, 0, 2]\n"
    )
    pts = tmp_path / "p.csv"
    pts.write_text("1,0,2\n")
    out = tmp_path / "o.csv"
    assert main(["project", str(pts), "--camera", str(cam), "--out", str(out)]) == 0
    assert out.read_text().splitlines()[1].startswith("445.0,240.0,1")


def test_project_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pts = tmp_path / "p.csv"
    pts.write_text("1,2\n")
    out = tmp_path / "o.csv"
    assert main(["project", str(pts), "--fx", "100", "--out", str(out)]) == 1
    assert "expected 3 columns" in capsys.readouterr().err
    cam = tmp_path / "cam.toml"
    cam.write_text("fx = 1\nfy = 1\ncx = 0\ncy = 0\nfocal = 3\n")
    pts.write_text("1,2,3\n")
    assert main(["project", str(pts), "--camera", str(cam), "--out", str(out)]) == 1
    assert "unknown key(s) focal; valid: fx, fy" in capsys.readouterr().err
    # physically meaningless focal lengths: refused at the boundary, nothing written
    for bad in (["--fx", "-500"], ["--fx", "0"], ["--fx", "500", "--fy", "-1"], ["--fx", "nan"]):
        assert main(["project", str(pts), *bad, "--out", str(out)]) == 2, bad
        assert "expected --f" in capsys.readouterr().err
    cam.write_text("fx = -500\nfy = 500\ncx = 0\ncy = 0\n")
    assert main(["project", str(pts), "--camera", str(cam), "--out", str(out)]) == 1
    assert "fx: expected a focal length in pixels > 0, got -500" in capsys.readouterr().err
    assert not out.exists()
    assert main(["project", str(pts), "--camera", str(cam), "--fx", "5", "-o", str(out)]) == 2
    assert "not both" in capsys.readouterr().err
    assert main(["project", str(pts), "--out", str(out)]) == 2  # no camera at all
    assert "--camera FILE or --fx" in capsys.readouterr().err
    assert main(["project", str(pts), "--no-such-flag"]) == 2
    assert main(["project", str(tmp_path / "missing.csv"), "--fx", "1", "--out", str(out)]) == 1


def test_vanishing_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import numpy as np
    from PIL import Image

    from imageform.geometry import camera_rotation
    from tests.geometry.scene_render import render_manhattan

    K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])
    img = render_manhattan(K, camera_rotation(0.25, 0.5, 0.03), np.zeros(3), seed=3)
    src = tmp_path / "scene.png"
    Image.fromarray((img * 255).round().astype(np.uint8)).save(src)
    out = tmp_path / "overlay.png"
    assert main(["vanishing", str(src), "--out", str(out), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["perspective"] == 3
    assert abs(payload["K"][0][0] - 700.0) < 21.0
    # how far resampling the segments moves the horizon: a share of the height, small here
    assert 0 < payload["horizon_spread"] < 0.005
    assert main(["vanishing", str(src)]) == 0
    said = capsys.readouterr().out
    assert "the horizon moves by ±" in said and "% of the height) when the points'" in said
    with Image.open(out) as ov:
        assert ov.size == (768, 512) and ov.mode == "RGB"
    # --max-size: segments from a copy half the size, the answers in the photograph's pixels
    assert main(["vanishing", str(src), "--max-size", "384", "--json"]) == 0
    small = json.loads(capsys.readouterr().out)
    assert small["perspective"] == 3 and abs(small["K"][0][0] - 700.0) < 21.0
    assert main(["vanishing", str(src), "--max-size", "8"]) == 2
    assert "--max-size" in capsys.readouterr().err
    assert main(["vanishing", str(src), "--out", str(out)]) == 1  # exists, no --force
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not an image")
    assert main(["vanishing", str(bad)]) == 1
    assert "cannot read" in capsys.readouterr().err
    # a flat image: the library answers "no vanishing point", the command still fails in one line
    blank = tmp_path / "blank.png"
    Image.fromarray(np.full((64, 96, 3), 128, np.uint8)).save(blank)
    assert main(["vanishing", str(blank)]) == 1
    err = capsys.readouterr().err.strip()
    assert err == "imageform: error: found 0 line segment(s); vanishing points need at least two"


def test_vanishing_principal_point_estimate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--principal-point estimate`` on a render whose principal point is 34 px off the
    centre: K's principal point is the three points' orthocentre, near the truth; on a level
    camera (two finite points) it stays at the centre and the text says why."""
    import numpy as np
    from PIL import Image

    from imageform.geometry import camera_rotation
    from tests.geometry.scene_render import render_manhattan

    Ko = np.array([[700.0, 0.0, 359.5], [0.0, 700.0, 279.5], [0.0, 0.0, 1.0]])
    img = render_manhattan(Ko, camera_rotation(0.25, 0.5, 0.03), np.zeros(3), seed=3)
    src = tmp_path / "scene.png"
    Image.fromarray((img * 255).round().astype(np.uint8)).save(src)
    assert main(["vanishing", str(src), "--principal-point", "estimate", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert math.hypot(payload["K"][0][2] - 359.5, payload["K"][1][2] - 279.5) < 4.0
    assert abs(payload["K"][0][0] - 700.0) < 7.0 and payload["K_note"] is None
    level = render_manhattan(Ko, camera_rotation(0.0, 0.6, 0.0), np.zeros(3), seed=4)
    Image.fromarray((level * 255).round().astype(np.uint8)).save(src)
    assert main(["vanishing", str(src), "--principal-point", "estimate"]) == 0
    text = capsys.readouterr().out
    assert "principal point (383.5, 255.5)" in text
    assert "note: the principal point is the image centre" in text


def test_horizon_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import numpy as np
    from PIL import Image

    from tests.geometry.test_horizon import _seascape

    img, rows = _seascape(6.0)
    src = tmp_path / "sea.png"
    Image.fromarray((img * 255).round().astype(np.uint8)).save(src)
    out = tmp_path / "overlay.png"
    assert main(["horizon", str(src), "--out", str(out), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["found"] is True
    assert abs(payload["roll_deg"] - 6.0) < 0.3
    assert max(abs(payload["rows"][0] - rows[0]), abs(payload["rows"][1] - rows[1])) < 1.5
    with Image.open(out) as ov:
        assert ov.size == (400, 300) and ov.mode == "RGB"
    # no horizon: exit 1 in one line, as `imageform chart` without a chart; nothing written
    blank = tmp_path / "blank.png"
    Image.fromarray(np.full((64, 96, 3), 128, np.uint8)).save(blank)
    none = tmp_path / "none.png"
    assert main(["horizon", str(blank), "-o", str(none)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no horizon found in the image: " in err[0]
    assert not none.exists()
    assert main(["horizon", str(src), "--max-roll-deg", "0"]) == 1
    assert "max" in capsys.readouterr().err


def test_vanishing_command_falls_back_to_the_visible_horizon(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a seascape rolled 20 degrees: no vanishing point gives its horizon (the library's
    # answer stays None), the command reports the visible one and says so
    import numpy as np
    from PIL import Image

    from imageform.geometry import detect_vanishing_points
    from tests.geometry.test_horizon import _seascape

    img, rows = _seascape(20.0)
    assert detect_vanishing_points(img).horizon is None
    src = tmp_path / "sea.png"
    Image.fromarray((img * 255).round().astype(np.uint8)).save(src)
    assert main(["vanishing", str(src), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["horizon_source"] == "visible (detect_horizon)"
    assert payload["horizon_spread"] is None  # measured for a horizon from points only
    a, b, c = payload["horizon"]
    assert abs(-c / b - rows[0]) < 2.0 and abs(-(a * 399 + c) / b - rows[1]) < 2.0
    assert main(["vanishing", str(src)]) == 0
    assert "the visible horizon (detect_horizon)" in capsys.readouterr().out
