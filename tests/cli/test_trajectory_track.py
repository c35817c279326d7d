"""simulate --trajectory writes a video and its truth; track reads the video (issue 27).

The composition a surgical-navigation user runs: render a calibration board along a camera
path through the whole chain, then track it with the camera file the simulation wrote, and
compare the poses with the truth written beside the video.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main

pytest.importorskip("av")
pytest.importorskip("matplotlib")

ROOT = Path(__file__).resolve().parents[2]


def _scene(tmp_path: Path) -> Path:
    """The calibration-board example at 320 x 240 without its extra views."""
    text = (ROOT / "examples" / "scenes" / "calibration_board.toml").read_text()
    text = text.split("\n[[views]]")[0]
    for a, b in (
        ("width = 640", "width = 320"),
        ("height = 480", "height = 240"),
        ("supersampling = 2", "supersampling = 1"),
        ("fx_px = 560.0", "fx_px = 280.0"),
        ("fy_px = 555.0", "fy_px = 277.5"),
        ("cx_px = 322.0", "cx_px = 161.0"),
        ("cy_px = 236.0", "cy_px = 118.0"),
    ):
        text = text.replace(a, b)
    path = tmp_path / "board.toml"
    path.write_text(text)
    return path


def _path(tmp_path: Path, n: int = 3) -> Path:
    rows = ["time_s,eye_x,eye_y,eye_z,target_x,target_y,target_z"]
    for i in range(n):
        a = 0.3 * i
        rows.append(f"{i / 10:.3f},{0.06 * math.sin(a):.4f},-0.28,{0.04 * math.cos(a):.4f},0,0,0")
    path = tmp_path / "path.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_simulate_a_path_then_track_it(tmp_path: Path) -> None:
    from imageform.geometry import rvec_to_matrix
    from imageform.io import open_video

    scene, traj = _scene(tmp_path), _path(tmp_path)
    video = tmp_path / "clip.mp4"
    args = ["simulate", "--scene", str(scene), "-o", str(tmp_path / "sim")]
    assert main([*args, "--trajectory", str(traj), "--video", str(video)]) == 0
    truth = _rows(tmp_path / "clip.mp4.poses.csv")
    with open_video(video) as v:
        assert v.info.fps == pytest.approx(10) and len(list(v)) == 3
    poses = tmp_path / "poses.csv"
    camera = tmp_path / "sim" / "camera.toml"
    args = ["track", str(video), "--camera", str(camera), "--board", "checkerboard:9x6"]
    assert main([*args, "--square", "20mm", "-o", str(poses)]) == 0
    got = _rows(poses)
    assert [r["found"] for r in got] == ["1"] * 3
    for a, b in zip(got, truth, strict=True):
        ta = np.array([float(a[k]) for k in ("tx", "ty", "tz")])
        tb = np.array([float(b[k]) for k in ("tx", "ty", "tz")])
        assert np.linalg.norm(ta - tb) < 0.01 * np.linalg.norm(tb), (ta, tb)
        Ra = np.asarray(rvec_to_matrix([float(a[k]) for k in ("rx", "ry", "rz")]))
        Rb = np.asarray(rvec_to_matrix([float(b[k]) for k in ("rx", "ry", "rz")]))
        angle = math.degrees(math.acos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1)))
        assert angle < 1.5, angle


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("time,eye_x\n0,1\n", "the header needs time_s"),
        ("time_s,rx,ry,rz,tx,ty,tz\n0,0,0,0,0,0,1\n0,0,0,0,0,0,1\n", "must increase"),
        ("time_s,rx,ry,rz,tx,ty,tz\n0,0,0,x,0,0,1\n", "line 2: expected numbers"),
        ("time_s,rx,ry,rz,tx,ty,tz\n", "has no rows"),
    ],
)
def test_bad_trajectories(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, words: str
) -> None:
    traj = tmp_path / "path.csv"
    traj.write_text(text)
    video = tmp_path / "clip.mp4"
    args = ["simulate", "--scene", str(_scene(tmp_path)), "-o", str(tmp_path / "sim")]
    assert main([*args, "--trajectory", str(traj), "--video", str(video)]) == 1
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1, err
    assert not video.exists() and not (tmp_path / "sim").exists()


def test_trajectory_and_video_go_together(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["simulate", "-o", str(tmp_path / "s"), "--video", str(tmp_path / "v.mp4")]) == 2
    assert "go together" in capsys.readouterr().err
