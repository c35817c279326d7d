"""``imageform simulate`` with the pipeline replaced by fakes (the real pipeline is tested
end to end where both land): exit codes, the printed summary, --json, --force, --scene,
--seed and the progress bar."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import imageform.simulate
from imageform.cli import main
from imageform.cli._build import progress_bar as _progress_bar
from imageform.errors import InvalidInputError
from imageform.simulate.result import SimulationResult

pytest.importorskip("matplotlib")


_REAL_SCENE = imageform.simulate.default_scene()  # before any test replaces default_scene


class _FakeScene(str):
    """A scene stand-in: compares equal to its name, has no extra views; its sensor (for the
    truth camera file's tables) is the default scene's."""

    config = SimpleNamespace(views=(), sensor=_REAL_SCENE.config.sensor)
    sensor = _REAL_SCENE.sensor


class FakePipeline:
    """Stands in for imageform.simulate's default_scene, load_scene and simulate."""

    def __init__(self, result: SimulationResult) -> None:
        self.result = result
        self.calls: list[tuple[str, Any]] = []
        self.progress: Any = "not called"

    def default_scene(self) -> str:
        self.calls.append(("default_scene", None))
        return _FakeScene("DEFAULT")

    def load_scene(self, source: Any) -> str:
        self.calls.append(("load_scene", source))
        if "broken" in str(source):
            raise InvalidInputError("scene.toml line 3: unknown key 'colour_checker'")
        return _FakeScene("LOADED")

    def simulate(
        self, scene: Any, *, progress: Callable[[str, float], None] | None = None, rng: Any = None
    ) -> SimulationResult:
        self.calls.append(("simulate", (scene, rng)))
        self.progress = progress
        if progress is not None:
            for i, name in enumerate(("radiance", "raw", "output")):
                progress(name, (i + 1) / 3)
        return self.result


def _install(monkeypatch: pytest.MonkeyPatch, result: SimulationResult) -> FakePipeline:
    fake = FakePipeline(result)
    for name in ("default_scene", "load_scene", "simulate"):
        monkeypatch.setattr(imageform.simulate, name, getattr(fake, name), raising=False)
    return fake


def test_no_arguments_renders_the_default_scene(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    sim_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fake = _install(monkeypatch, sim_result)
    monkeypatch.chdir(tmp_path)
    assert main(["simulate"]) == 0
    out = capsys.readouterr().out
    assert fake.calls == [("default_scene", None), ("simulate", ("DEFAULT", 0))]
    assert (tmp_path / "simulation" / "report.html").is_file()
    assert (tmp_path / "simulation" / "metrics.json").is_file()
    assert "report  -> simulation/report.html" in out
    assert "mean ΔE00 0.08 (max 2.00)" in out and "vanishing-point error 5.00 px" in out
    assert "simulation 1.0 s" in out and "192x128 px, 5 stages" in out
    assert fake.progress is None  # not a terminal: no bar


def test_json_output(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    bare_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    _install(monkeypatch, bare_result)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    out_dir = tmp_path / "r"
    assert main(["simulate", "--out", str(out_dir), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["report"] == str(out_dir / "report.html")
    assert data["metrics"] == str(out_dir / "metrics.json")
    assert len(data["stages"]) == 5 and data["raw_files"] == [str(out_dir / "stages/01-raw-dn.png")]
    assert data["summary"] == {
        "simulation_time_s": None,  # the bare result records no simulation time
        "delta_e00_mean": None,
        "delta_e00_max": None,
        "vanishing_point_error_px": None,
        "system_gain_dn_per_e": None,
    }
    assert data["scene"] is None and data["image_size"] == [192, 128]
    assert data["report_time_s"] > 0 and data["total_time_s"] >= data["report_time_s"]


def test_scene_file_and_seed(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    bare_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fake = _install(monkeypatch, bare_result)
    scene = tmp_path / "scene.toml"
    scene.write_text("[scene]\nname = 'x'\n")
    rc = main(["simulate", "--scene", str(scene), "--seed", "7", "-o", str(tmp_path / "o")])
    assert rc == 0
    assert fake.calls == [("load_scene", scene), ("simulate", ("LOADED", 7))]


def test_progress_bar_on_a_terminal(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    bare_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fake = _install(monkeypatch, bare_result)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert main(["simulate", "-o", str(tmp_path / "o")]) == 0
    assert callable(fake.progress)
    assert "writing the report" in capsys.readouterr().err  # the bar's last step


def test_progress_bar_helper(capsys: pytest.CaptureFixture[str]) -> None:
    with _progress_bar(False) as p:
        assert p is None
    with _progress_bar(True) as p:
        assert p is not None
        p("demosaicing", 0.5)
        p("encoding", 1.5)  # out of range: shown full, no error
    assert "encoding" in capsys.readouterr().err


def test_existing_report_needs_force(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    bare_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fake = _install(monkeypatch, bare_result)
    out_dir = tmp_path / "o"
    assert main(["simulate", "-o", str(out_dir)]) == 0
    fake.calls.clear()
    assert main(["simulate", "-o", str(out_dir)]) == 1
    err = capsys.readouterr().err
    assert "exists; pass --force" in err and err.count("\n") == 1
    assert fake.calls == []  # refused before simulating
    assert main(["simulate", "-o", str(out_dir), "--force"]) == 0


def test_failures_exit_1(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    bare_result: SimulationResult,
    capsys: pytest.CaptureFixture[str],
) -> None:
    _install(monkeypatch, bare_result)
    assert main(["simulate", "--scene", str(tmp_path / "missing.toml")]) == 1
    assert "--scene file" in capsys.readouterr().err
    broken = tmp_path / "broken.toml"
    broken.write_text("x")
    assert main(["simulate", "--scene", str(broken), "-o", str(tmp_path / "o")]) == 1
    assert "line 3: unknown key" in capsys.readouterr().err
    (tmp_path / "afile").write_text("")
    assert main(["simulate", "-o", str(tmp_path / "afile")]) == 1
    assert "not a folder" in capsys.readouterr().err


def test_bad_usage_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "--seed", "many"]) == 2
    assert main(["simulate", "--colour"]) == 2


def test_without_matplotlib_says_which_extra(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "matplotlib" else real(name)
    )
    assert main(["simulate", "-o", str(tmp_path / "o")]) == 1
    assert 'pip install "imageform[plot]"' in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
