"""``--deinterlace`` of imageform track and reconstruct: fields of an interlaced clip, bad input."""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.geometry import Camera
from imageform.io import write_camera, write_image
from tests import video_scenes

pytest.importorskip("cv2")

SIZE = (640, 360)
K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"
BOARD = ["--board", "charuco:7x5", "--square", "30mm", "--marker", "22mm"]
BOARD += ["--dictionary", "5x5_100", "--fps", "25"]


def _weave(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    rows = np.arange(first.shape[0]) % 2 == 0
    return np.where(rows[:, None, None], first, second)


@pytest.fixture(scope="module")
def interlaced(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list]:
    """Eight frames woven top field first from 16 renders (a circle in 16 fields)."""
    folder = tmp_path_factory.mktemp("interlaced")
    camera = write_camera(folder / "camera.toml", Camera(K, image_size=SIZE))
    tex, origin = video_scenes.board_texture()
    truth = video_scenes.poses(16)
    rng = np.random.default_rng(2)
    fields = [video_scenes.render(tex, origin, K, p, SIZE, rng=rng) for p in truth]
    frames = folder / "frames"
    frames.mkdir()
    for k in range(8):
        write_image(frames / f"f{k:02d}.png", _weave(fields[2 * k], fields[2 * k + 1]))
    return frames, camera, truth


def _poses(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def _t_error(row: dict[str, str], truth: tuple[np.ndarray, np.ndarray]) -> float:
    t = np.array([float(row[k]) for k in ("tx", "ty", "tz")])
    return float(np.linalg.norm(t - truth[1]) / np.linalg.norm(truth[1]))


def test_track_auto_tracks_the_fields(
    interlaced: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frames, camera, truth = interlaced
    out = tmp_path / "poses.csv"
    args = ["track", str(frames), "--camera", str(camera), *BOARD, "-o", str(out), "--json"]
    assert main(args) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["deinterlace"]["method"] == "fields"
    assert summary["deinterlace"]["field_order"] == "top"
    assert summary["deinterlace"]["found"]["interlaced"] is True
    assert "interlaced, top field first" in captured.err
    assert "tracking fields at 50 per second" in captured.err
    rows = _poses(out)
    assert len(rows) == 16 and all(r["found"] == "1" for r in rows)
    times = [float(r["time_s"]) for r in rows]
    np.testing.assert_allclose(times, np.arange(16) * 0.02, atol=1e-6)
    # every field's pose is its own instant's (the truth of the render woven into it)
    errors = [_t_error(r, truth[i]) for i, r in enumerate(rows)]
    assert max(errors) < 0.01, errors


def test_track_off_tracks_the_combed_frames(
    interlaced: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frames, camera, _ = interlaced
    out = tmp_path / "poses.csv"
    args = ["track", str(frames), "--camera", str(camera), *BOARD, "-o", str(out), "--json"]
    assert main([*args, "--deinterlace", "off"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["deinterlace"] == {"method": "off", "field_order": None, "found": None}
    rows = _poses(out)
    assert len(rows) == 8


def test_track_auto_leaves_a_progressive_clip_alone(
    interlaced: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A progressive clip: auto tracks the frames as decoded, poses.csv as with off."""
    _, camera, truth = interlaced
    tex, origin = video_scenes.board_texture()
    rng = np.random.default_rng(4)
    frames = tmp_path / "progressive"
    frames.mkdir()
    for k in range(6):
        image = video_scenes.render(tex, origin, K, truth[2 * k], SIZE, rng=rng)
        write_image(frames / f"f{k:02d}.png", image)
    outs = {}
    for how in ("auto", "off"):
        out = tmp_path / f"{how}.csv"
        args = ["track", str(frames), "--camera", str(camera), *BOARD, "-o", str(out)]
        assert main([*args, "--deinterlace", how, "--json"]) == 0
        captured = capsys.readouterr()
        summary = json.loads(captured.out)
        assert summary["deinterlace"]["method"] == "off"
        assert "progressive" not in captured.err  # an ordinary clip: nothing said
        outs[how] = out.read_text()
        if how == "auto":
            assert summary["deinterlace"]["found"]["interlaced"] is False
    assert outs["auto"] == outs["off"]
    assert len(outs["off"].splitlines()) == 7


def test_track_overlay_of_fields_has_the_frames_size(
    interlaced: tuple[Path, Path, list], tmp_path: Path
) -> None:
    pytest.importorskip("av")
    from imageform.io import open_video

    frames, camera, _ = interlaced
    overlay = tmp_path / "overlay.mp4"
    args = ["track", str(frames), "--camera", str(camera), *BOARD, "-o", str(tmp_path / "p.csv")]
    assert main([*args, "--deinterlace", "fields", "--overlay", str(overlay)]) == 0
    with open_video(overlay) as reader:
        assert (reader.info.width, reader.info.height) == SIZE
        assert math.isclose(reader.info.fps, 50.0)
        assert sum(1 for _ in reader) == 16


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--deinterlace", "yadif"], "--deinterlace"),
        (["--field-order", "left"], "--field-order"),
    ],
)
def test_track_bad_deinterlace_options(
    interlaced: tuple[Path, Path, list],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    extra: list[str],
    message: str,
) -> None:
    frames, camera, _ = interlaced
    args = ["track", str(frames), "--camera", str(camera), *BOARD, "-o", str(tmp_path / "p.csv")]
    assert main([*args, *extra]) != 0
    err = capsys.readouterr().err
    assert f"unknown {message}" in err, err
    assert not (tmp_path / "p.csv").exists()


def test_reconstruct_fields_of_an_interlaced_endoscope_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Real colonoscopy frames woven in pairs: auto keeps the top field (linear), K as is."""
    pytest.importorskip("matplotlib")
    from imageform.io import read_image

    names = [ENDO / f"c3vdv3_f{i:03d}.jpg" for i in range(0, 40, 4)]
    images = [read_image(p) for p in names]
    folder = tmp_path / "woven"
    folder.mkdir()
    for k in range(len(images) - 1):
        write_image(folder / f"w{k:02d}.png", _weave(images[k], images[k + 1]))
    out = tmp_path / "rec"
    args = ["reconstruct", str(folder), "--camera", str(ENDO / "camera.toml"), "--auto-mask"]
    args += ["--highlights", "--contrast-threshold", "0.01", "-o", str(out), "--json"]
    assert main(args) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["deinterlace"]["method"] == "linear"
    assert "frames deinterlaced (linear, the top field kept)" in captured.err
    assert summary["registered"] >= 7 and summary["frames"] == 9
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["deinterlace"]["field_order"] == "top"


def test_reconstruct_fields_use_the_fields_camera_matrix(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--deinterlace fields``: the first field of each frame, half height, fy/2 and cy/2."""
    pytest.importorskip("matplotlib")
    import imageform.geometry as geometry
    from imageform.errors import DegenerateConfigurationError

    seen: dict[str, np.ndarray] = {}

    def spy(images: list, K: np.ndarray, *args: object, **kwargs: object) -> None:
        seen["shape"], seen["K"] = np.array(images[0].shape), np.array(K)
        raise DegenerateConfigurationError("stop here")

    monkeypatch.setattr(geometry, "reconstruct_sequence", spy)
    frames = tmp_path / "frames"
    frames.mkdir()
    for i in (0, 4, 8):
        shutil.copy(ENDO / f"c3vdv3_f{i:03d}.jpg", frames)
    args = ["reconstruct", str(frames), "--camera", str(ENDO / "camera.toml")]
    args += ["--deinterlace", "fields", "--field-order", "bottom", "-o", str(tmp_path / "rec")]
    assert main(args) == 1
    assert "stop here" in capsys.readouterr().err
    assert seen["shape"].tolist() == [224, 445, 3]
    np.testing.assert_allclose(seen["K"][1], [0.0, 200.6124 / 2, (225.3 - 1) / 2])


def test_reconstruct_bad_deinterlace_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["reconstruct", str(ENDO), "--camera", str(ENDO / "camera.toml")]
    assert main([*args, "--deinterlace", "bob", "-o", str(tmp_path / "rec")]) != 0
    assert "--deinterlace" in capsys.readouterr().err


def test_the_note_speaks_only_when_there_is_something_to_say() -> None:
    """deinterlace_note: nothing for a progressive clip (stream silent or progressive); a
    note where the stream flags interlacing the frames do not show, or fields were taken."""
    from types import SimpleNamespace

    from imageform.io.interlace import Interlacing
    from imageform.workflows._video import deinterlace_note

    def reader(stream: str | None, interlaced: bool, method: str) -> SimpleNamespace:
        found = Interlacing(interlaced, "top" if interlaced else None, 30,
                            30 if interlaced else 0, 0, 0 if interlaced else 30, 0, 1.0,
                            stream)  # fmt: skip
        return SimpleNamespace(interlacing=found, deinterlaced=method, field_order="top")

    assert deinterlace_note(reader(None, False, "off"), 25) == ""  # type: ignore[arg-type]
    assert deinterlace_note(reader("progressive", False, "off"), 25) == ""  # type: ignore[arg-type]
    flagged = deinterlace_note(reader("tt", False, "off"), 25)  # type: ignore[arg-type]
    assert flagged.startswith("progressive (") and "the stream says tt" in flagged
    fields = deinterlace_note(reader("tt", True, "fields"), 25)  # type: ignore[arg-type]
    assert fields.endswith("tracking fields at 50 per second")
