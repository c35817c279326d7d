"""Through the command line, no hand edits: a simulated calibration session calibrates back to
the simulator's own camera file, and that file renders the scene again (--camera)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import read_camera

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "scenes" / "calibration_board.toml"


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("roundtrip")
    sim = tmp / "sim"
    assert main(["simulate", "--scene", str(SCENE), "-o", str(sim), "--json"]) == 0
    cam = tmp / "cam.toml"
    pattern = str(sim / "views" / "*.png")
    assert main(["calibrate", pattern, "--board", "9x6", "--square", "20mm", "-o", str(cam)]) == 0
    return sim, cam


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_simulate_then_calibrate_gives_back_the_truth_camera(session: tuple[Path, Path]) -> None:
    sim, cam = session
    truth, est = read_camera(sim / "camera.toml"), read_camera(cam)
    assert len(list((sim / "views").glob("view-*.png"))) == 8
    # field by field
    assert est.camera.image_size == truth.camera.image_size == (640, 480)
    assert est.distortion_model == truth.distortion_model == "brown_conrady"
    Kt, Ke = np.asarray(truth.camera.K), np.asarray(est.camera.K)
    for (i, j), name in (((0, 0), "fx"), ((1, 1), "fy"), ((0, 2), "cx"), ((1, 2), "cy")):
        assert abs(Ke[i, j] / Kt[i, j] - 1) < 0.005, (name, Ke[i, j], Kt[i, j])
    # measured: fx -0.012 %, fy -0.015 %, cx +0.075 %, cy -0.032 %, k1 +1.40 % (docs below)
    k1t, k1e = truth.camera.distortion.k1, est.camera.distortion.k1
    assert abs(k1e / k1t - 1) < 0.02, (k1e, k1t)
    assert truth.has_pose and not est.has_pose  # a calibration gives no pose of its own
    assert truth.provenance.command == "imageform simulate"
    assert est.provenance.command.startswith("imageform calibrate")
    assert est.provenance.views_used == 8


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_the_docs_show_what_this_session_gives(session: tuple[Path, Path]) -> None:
    """docs/tracking.md prints this calibration's line and docs/simulate.md its errors against
    the truth: a newcomer running the commands sees the same (they had gone stale when the
    corner refinement changed)."""
    sim, cam = session
    truth, est = read_camera(sim / "camera.toml").camera, read_camera(cam).camera
    Kt, Ke = np.asarray(truth.K), np.asarray(est.K)
    where = {"fx": (0, 0), "fy": (1, 1), "cx": (0, 2), "cy": (1, 2)}
    tracking = (ROOT / "docs" / "tracking.md").read_text()
    line = re.search(r"^RMS [\d.]+ px over 8 views; fx ([\d.]+) .*$", tracking, re.MULTILINE)
    assert line is not None
    for name, (i, j) in where.items():
        shown = re.search(rf"{name} ([\d.]+)", line.group(0))
        assert shown is not None and abs(float(shown.group(1)) - Ke[i, j]) < 6e-4, name
    simulate = " ".join((ROOT / "docs" / "simulate.md").read_text().split())
    shown_pct = re.search(r"`cam.toml` then matches `sim/camera.toml` \(([^)]*)\)", simulate)
    assert shown_pct is not None
    pct = dict(re.findall(r"(fx|fy|cx|cy|k1) ([−+-][\d.]+) %", shown_pct.group(1)))
    for name, (i, j) in where.items():
        assert abs(float(pct[name].replace("−", "-")) - 100 * (Ke[i, j] / Kt[i, j] - 1)) < 6e-4
    k1 = 100 * (est.distortion.k1 / truth.distortion.k1 - 1)
    assert abs(float(pct["k1"].replace("−", "-")) - k1) < 6e-3


def test_the_calibrated_file_renders_the_scene_again(
    session: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sim, cam = session
    scene = tmp_path / "one_view.toml"  # the board scene without its extra views
    text = SCENE.read_text()
    scene.write_text(text[: text.index("\n[[views]]")])
    out = tmp_path / "again"
    capsys.readouterr()
    args = ["simulate", "--scene", str(scene), "--camera", str(cam), "-o", str(out), "--json"]
    assert main(args) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["camera_file_in"] == str(cam)
    used, est, truth = (read_camera(p) for p in (out / "camera.toml", cam, sim / "camera.toml"))
    # the calibrated intrinsics and distortion, at the scene's pose (the file has none)
    np.testing.assert_allclose(np.asarray(used.camera.K), np.asarray(est.camera.K), rtol=1e-12)
    assert used.camera.distortion == est.camera.distortion
    np.testing.assert_allclose(np.asarray(used.camera.R), np.asarray(truth.camera.R), atol=1e-12)


def test_camera_file_without_image_size_is_refused(
    session: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, cam = session
    text = cam.read_text()
    start = text.index("[image]")
    end = text.index("[", start + 1)
    bare = tmp_path / "bare.toml"
    bare.write_text(text[:start] + text[end:])
    assert main(["simulate", "--camera", str(bare), "-o", str(tmp_path / "o")]) == 1
    assert "no image size" in capsys.readouterr().err
    assert not (tmp_path / "o").exists() and not list(tmp_path.glob(".o.*"))


def test_force_replaces_only_a_simulation_folder(
    session: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sim, _ = session
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("years of work")
    assert main(["simulate", "-o", str(mine), "--force"]) == 1
    assert "not an imageform simulate output" in capsys.readouterr().err
    assert (mine / "chapter1.tex").read_text() == "years of work"
    copy = tmp_path / "copy"
    shutil.copytree(sim, copy)
    assert main(["simulate", "-o", str(copy)]) == 1  # exists: needs --force
    assert "--force" in capsys.readouterr().err
