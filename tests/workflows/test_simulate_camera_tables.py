"""``imageform simulate --camera FILE`` with a camera file's [sensor], [optics] and [color]
(issue 18): the file overrides the scene, and the output camera.toml keeps the tables."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from imageform.cli import main
from imageform.geometry import Camera
from imageform.io import read_camera, write_camera

pytest.importorskip("matplotlib")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_simulate_camera_with_tables(tmp_path: Path) -> None:
    cam = Camera([[200.0, 0, 159.5], [0, 200.0, 89.5], [0, 0, 1]], image_size=(320, 180))
    path = write_camera(
        tmp_path / "cam.toml",
        cam,
        sensor={"system_gain_dn_per_e": 0.5, "read_noise_e": 4.0, "bit_depth": 14},
        optics={"model": "mtf50", "mtf50_cy_per_px": [0.3, 0.28, 0.25]},
        color={"white_balance": [1.9, 1.0, 1.6], "illuminant": "D65"},
    )
    out = tmp_path / "sim"
    assert main(["simulate", "--camera", str(path), "-o", str(out), "--json"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["white_balance_gains"] == [1.9, 1.0, 1.6]  # the file's, not gray world
    assert metrics["config"]["processing"]["white_balance"] == "none"
    assert metrics["config"]["lens"]["defocus"] is False  # [optics] replaces the lens blur
    used = read_camera(out / "camera.toml")
    given = read_camera(path)
    assert used.optics == given.optics
    # the file's sensor values, with the rest of the simulated sensor (issue 26: the truth
    # camera file describes the whole camera, for --lab)
    assert used.sensor is not None and given.sensor is not None
    assert used.sensor.to_dict().items() >= given.sensor.to_dict().items()
    assert used.sensor.pixel_pitch_um == 3.45 and used.sensor.cfa == "RGGB"
    assert used.color == given.color
    assert used.camera.image_size == (320, 180)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_simulate_lab_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam = Camera([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]], image_size=(320, 240))
    path = write_camera(tmp_path / "cam.toml", cam, sensor={"read_noise_e": 3.0})
    lab = tmp_path / "lab"
    args = ["simulate", "--camera", str(path), "--lab", str(lab), "-o", str(tmp_path / "sim")]
    assert main(args) == 0
    assert "lab set ->" in capsys.readouterr().out
    for sub in ("lab.toml", "emva.toml", "camera.toml", "checkerboard", "edge", "flats"):
        assert (lab / sub).exists(), sub
    assert read_camera(lab / "camera.toml").sensor == read_camera(path).sensor
    # a lab set is a folder output: made again only with --force, then replaced whole (it
    # was refused as "a folder; give a file name" even with --force)
    (lab / "old.txt").write_text("a file of the previous set")
    again = [*args[:-1], str(tmp_path / "sim2")]
    assert main(again) == 1
    assert f"output {lab} exists; pass --force" in capsys.readouterr().err
    assert main([*again, "--force"]) == 0
    capsys.readouterr()
    assert (lab / "lab.toml").is_file() and not (lab / "old.txt").exists()
    # --lab without --camera, and a folder of someone's files, are refused
    assert main(["simulate", "--lab", str(tmp_path / "x"), "-o", str(tmp_path / "s2")]) == 2
    assert "give --camera FILE" in capsys.readouterr().err
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "photo.png").write_bytes(b"")
    args = ["simulate", "--camera", str(path), "--lab", str(mine), "-o", str(tmp_path / "s3")]
    assert main([*args, "--force"]) == 1
    assert "exists and is not a lab set (no lab.toml)" in capsys.readouterr().err
    assert (mine / "photo.png").exists()
