"""All or nothing: an error, a second output that cannot be written, Ctrl-C or SIGTERM leave
nothing new behind and earlier outputs untouched; real runs are interrupted mid-write."""

from __future__ import annotations

import errno
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import imageform.io
from imageform.cli import main
from imageform.io import read_image, write_image

ROOT = Path(__file__).resolve().parents[2]


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".part" in p.name)


@pytest.fixture
def rgb(tmp_path: Path) -> Path:
    write_image(tmp_path / "in.png", np.random.default_rng(3).random((24, 32, 3)))
    return tmp_path / "in.png"


def test_error_with_force_keeps_the_previous_output(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out.png"
    assert main(["convert", str(rgb), "-o", str(out), "--to", "linear-srgb"]) == 0
    before = out.read_bytes()
    # the conversion fails half-way (Lab values cannot be clipped into a PNG): nothing changes
    assert main(["convert", str(rgb), "-o", str(out), "--to", "lab", "--force"]) == 1
    assert out.read_bytes() == before and _leftovers(tmp_path) == []
    assert capsys.readouterr().err.count("\n") == 1  # one line


def test_ctrl_c_inside_a_command_leaves_nothing(
    rgb: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    real = imageform.io.image_io.atomic_write

    def interrupted(final: Path, write: object) -> None:
        real(final, write)  # type: ignore[arg-type]
        raise KeyboardInterrupt  # after the temporary file is complete, before the rename

    monkeypatch.setattr(imageform.io.image_io, "atomic_write", interrupted)
    out = tmp_path / "wb.png"
    assert main(["white-balance", str(rgb), "-o", str(out)]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "imageform: interrupted; nothing new was written"
    assert not out.exists() and _leftovers(tmp_path) == []


def test_second_output_that_cannot_be_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """undistort writes an image and a camera file: the camera file fails (disk full), so
    the image is not left behind either."""
    cam = tmp_path / "cam.toml"
    from imageform.geometry import BrownConrady, Camera
    from imageform.io import write_camera

    K = [[100.0, 0, 15.5], [0, 100.0, 11.5], [0, 0, 1]]
    write_camera(cam, Camera(K, image_size=(32, 24), distortion=BrownConrady(k1=-0.1)))
    img = tmp_path / "in.png"
    write_image(img, np.random.default_rng(0).random((24, 32, 3)))

    def disk_full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "flat.toml"))

    monkeypatch.setattr(imageform.io.camera_file, "write_camera", disk_full)
    monkeypatch.setattr(imageform.io, "write_camera", disk_full)
    out, flat = tmp_path / "out.png", tmp_path / "flat.toml"
    args = ["undistort", str(img), "--camera", str(cam), "-o", str(out), "--camera-out", str(flat)]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "No space left on device" in err and "flat.toml" in err and err.count("\n") == 1
    assert not out.exists() and not flat.exists() and _leftovers(tmp_path) == []


@pytest.fixture(scope="module")
def first_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished simulation (the output an interrupted rerun must leave untouched)."""
    tmp = tmp_path_factory.mktemp("first")
    scene = _scene(tmp)
    run = _start(["simulate", "--scene", str(scene), "-o", "out"], tmp)
    assert run.wait(timeout=300) == 0, run.stderr.read() if run.stderr else ""
    return tmp


def _scene(tmp_path: Path) -> Path:
    """The default scene at 320 x 180, one ray per pixel (a run of a few seconds)."""
    text = (ROOT / "examples" / "scenes" / "default.toml").read_text()
    text = text.replace("width = 1280", "width = 320").replace("height = 720", "height = 180")
    text = text.replace("supersampling = 2", "supersampling = 1")
    scene = tmp_path / "small.toml"
    scene.write_text(text)
    return scene


def _start(args: list[str], cwd: Path) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    return subprocess.Popen(
        [sys.executable, "-m", "imageform", *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.parametrize(
    ("sig", "delay"), [(signal.SIGINT, 0.0), (signal.SIGINT, 0.8), (signal.SIGTERM, 0.3)]
)
def test_interrupting_simulate_mid_run_keeps_the_old_folder(
    tmp_path: Path, first_run: Path, sig: signal.Signals, delay: float
) -> None:
    # a run that finishes before the signal lands (a fast machine) is tried again with half
    # the delay, down to 0 (the signal as soon as the new folder appears): never skipped
    for attempt, wait in enumerate((delay, delay / 2, delay / 4, 0.0)):
        work = tmp_path / f"try{attempt}"
        work.mkdir()
        scene = _scene(work)
        shutil.copytree(first_run / "out", work / "out")
        old = {
            p.relative_to(work): p.read_bytes() for p in (work / "out").rglob("*") if p.is_file()
        }
        run = _start(
            ["simulate", "--scene", str(scene), "-o", "out", "--force", "--seed", "5"], work
        )
        t0 = time.monotonic()
        while not any(".part" in p.name for p in work.iterdir()):  # the new folder is started
            if run.poll() is not None or time.monotonic() - t0 > 120:
                pytest.fail(f"no temporary folder appeared (exit {run.returncode})")
            time.sleep(0.01)
        time.sleep(wait)
        run.send_signal(sig)
        _, err = run.communicate(timeout=120)
        if run.returncode != 0:
            break
    else:
        pytest.fail("every run finished before the signal, even sent at once")
    tmp_path = work
    assert run.returncode == 130, err
    assert err.strip().splitlines()[-1] == "imageform: interrupted; nothing new was written"
    assert "Traceback" not in err
    now = {
        p.relative_to(tmp_path): p.read_bytes()
        for p in (tmp_path / "out").rglob("*")
        if p.is_file()
    }
    assert now == old  # the previous output, byte for byte
    assert _leftovers(tmp_path) == []
    assert read_image(tmp_path / "out" / "stages" / "00-rendered.png").shape[:2] == (180, 320)
