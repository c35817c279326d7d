"""Issue 16 in imageform.batch: every public name refuses malformed arguments in one line
naming the parameter; a glob through looping symbolic links ends; two runs into one folder
keep each other's temporary files. No cluster is started here."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.batch import (
    BatchReport,
    JobResult,
    batch_options,
    batch_workflow,
    plan_jobs,
    print_summary,
    process_chunked,
    run_job,
)
from imageform.batch._temps import _remove_stale_temps, _run_lock, _temp_path
from imageform.batch.chunked import open_lazy
from imageform.errors import ImageformError
from imageform.io import write_image


def _one_line(exc: BaseException, name: str) -> None:
    msg = str(exc)
    assert isinstance(exc, ImageformError | TypeError), repr(exc)
    assert "\n" not in msg and len(msg) <= 200, msg
    assert name in msg, msg


@pytest.mark.parametrize("bad", [None, 0, True, ["convert"], object(), "", "x" * 100_000])
def test_command_named(bad: Any) -> None:
    for call in (batch_workflow, lambda c: batch_options(c, None)):
        with pytest.raises(ImageformError) as info:
            call(bad)
        _one_line(info.value, "command")


@pytest.mark.parametrize("bad", [True, object(), "to=lab", 3])
def test_options_named(bad: Any) -> None:
    with pytest.raises(ImageformError) as info:
        batch_options("convert", bad)
    _one_line(info.value, "options")


def test_options_by_flag_and_field_and_numpy_values() -> None:
    assert batch_options("convert", {"--to": "lab"}).dst == "lab"
    assert batch_options("white-balance", {"p": np.float64(3)}).p == 3.0
    with pytest.raises(ImageformError) as info:
        batch_options("white-balance", {"p": math.nan})
    _one_line(info.value, "--p")


@pytest.mark.parametrize(
    ("param", "bad"),
    [
        ("pattern", None),
        ("pattern", 0),
        ("pattern", True),
        ("pattern", ""),
        ("out_dir", None),
        ("out_dir", 0),
        ("out_suffix", 3),
        ("out_suffix", "."),
    ],
)
def test_plan_jobs_names_its_parameters(tmp_path: Path, param: str, bad: Any) -> None:
    write_image(tmp_path / "a.png", np.zeros((2, 2, 3), np.uint8))
    kw: dict[str, Any] = {"pattern": f"{tmp_path}/*.png", "out_dir": tmp_path / "o"}
    kw[param] = bad
    with pytest.raises(ImageformError) as info:
        plan_jobs(**kw)
    _one_line(info.value, param)


def test_run_job_names_paths(tmp_path: Path) -> None:
    for param, kw in (
        ("out_path", {"in_path": str(tmp_path / "a.png"), "out_path": None}),
        ("out_path", {"in_path": str(tmp_path / "a.png"), "out_path": 0}),
        ("in_path", {"in_path": None, "out_path": str(tmp_path / "o.png")}),
        ("hold_s", {"in_path": "a", "out_path": "b", "hold_s": math.nan}),
    ):
        with pytest.raises(ImageformError) as info:
            run_job("convert", **kw)
        _one_line(info.value, param)


def test_results_and_summary_checked(capsys: pytest.CaptureFixture[str]) -> None:
    r = JobResult("a.png", "o/a.png", "done", seconds=np.float64(0.5))  # type: ignore[arg-type]
    assert r.input == Path("a.png") and r.seconds == 0.5
    for param, kw in (
        ("seconds", {"seconds": math.nan}),
        ("seconds", {"seconds": -1.0}),
        ("seconds", {"seconds": 1j}),
        ("status", {"status": "ok"}),
        ("input", {"input": None}),
        ("metrics", {"metrics": [1]}),
    ):
        args: dict[str, Any] = {"input": "a", "output": "b", "status": "done", **kw}
        with pytest.raises(ImageformError) as info:
            JobResult(**args)
        _one_line(info.value, param)
    for bad in (None, "report", 0, object()):
        with pytest.raises(ImageformError) as info:
            print_summary(bad)  # type: ignore[arg-type]
        _one_line(info.value, "report")
    print_summary(BatchReport("convert", (r,)))
    assert "1 done" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("param", "bad"),
    [
        ("chunk", None),
        ("chunk", 0),
        ("chunk", math.nan),
        ("chunk", 10**30),
        ("chunk", [256, 256]),
        ("tile", True),
        ("tile", 8),
        ("tile", 100),
        ("num_workers", 0),
        ("num_workers", math.nan),
        ("num_workers", "2"),
        ("src", None),
        ("dst", 0),
        ("force", "yes"),
    ],
)
def test_process_chunked_names_its_parameters(tmp_path: Path, param: str, bad: Any) -> None:
    kw: dict[str, Any] = {"src": tmp_path / "in.tif", "dst": tmp_path / "out.tif", "chunk": 256}
    kw[param] = bad
    src, dst = kw.pop("src"), kw.pop("dst")
    with pytest.raises(ImageformError) as info:
        process_chunked(src, dst, "convert", {"to": "srgb"}, **kw)
    _one_line(info.value, param)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("bad", [None, 0, -3, math.inf, 2.5, (), 10**30])
def test_open_lazy_names_chunk(tmp_path: Path, bad: Any) -> None:
    with pytest.raises(ImageformError) as info:
        open_lazy(tmp_path / "in.tif", bad)
    _one_line(info.value, "chunk")
    with pytest.raises(ImageformError) as info:
        open_lazy(None)  # type: ignore[arg-type]
    _one_line(info.value, "path")


_LOOP = textwrap.dedent(
    """
    import sys
    from imageform.batch import plan_jobs
    jobs = plan_jobs(sys.argv[1] + "/in/**/*.png", sys.argv[1] + "/out")
    print(sorted(str(j.output.relative_to(sys.argv[1])) for j in jobs))
    """
)


def test_glob_through_looping_links_ends(tmp_path: Path) -> None:
    """``**`` through a link to an ancestor (and a link to itself) lists each real folder
    once; it once recursed until the path was too long (minutes)."""
    sub = tmp_path / "in" / "a"
    sub.mkdir(parents=True)
    write_image(sub / "x.png", np.zeros((2, 2, 3), np.uint8))
    write_image(tmp_path / "in" / "y.png", np.zeros((2, 2, 3), np.uint8))
    (sub / "up").symlink_to("..", target_is_directory=True)
    (sub / "self").symlink_to(".", target_is_directory=True)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[2] / "src")}
    proc = subprocess.run(
        [sys.executable, "-c", _LOOP, str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "['out/a/x.png', 'out/y.png']"


def test_two_runs_keep_each_others_temporary_files(tmp_path: Path) -> None:
    """A run's start (and end) removes the temporary files of runs that died, never those of
    a run still going into the same folder: each run holds a lock named by its id."""
    (tmp_path / "in").mkdir()
    write_image(tmp_path / "in" / "x.png", np.zeros((2, 2, 3), np.uint8))
    out = tmp_path / "out"
    (job,) = plan_jobs(f"{tmp_path}/in/*.png", out)
    out.mkdir()
    with _run_lock(out) as other:  # a run going on (its lock held)
        live = _temp_path(job.output, other)
        live.write_bytes(b"being written")
        with _run_lock(out) as mine:
            dead = _temp_path(job.output, "0123456789ab")  # a run that died: no lock held
            dead.write_bytes(b"left")
            old_style = _temp_path(job.output)
            old_style.write_bytes(b"left")
            own = _temp_path(job.output, mine)
            own.write_bytes(b"mine, left by a killed worker")
            assert _remove_stale_temps([job], out, mine) == 3
            assert live.exists()
            assert not dead.exists() and not old_style.exists() and not own.exists()
        live.unlink()
    assert sorted(p.name for p in out.iterdir()) == []  # the locks went with their runs


def test_batch_white_balance_keeps_16_bits(tmp_path: Path) -> None:
    """What each worker runs (run_job) on a 16-bit PNG writes a 16-bit PNG (not cut to 8)."""
    from imageform.io import read_image

    src = tmp_path / "in.png"
    a = np.random.default_rng(1).integers(2000, 63000, (10, 12, 3)).astype(np.uint16)
    write_image(src, a)
    out = tmp_path / "out" / "in.png"
    res = run_job("white-balance", str(src), str(out), {"method": "gray-world"}, 0.0, "ab" * 6)
    assert res["ok"], res
    got = read_image(out)
    assert got.dtype == np.uint16 and np.any(got % 257)
    assert sorted(p.name for p in out.parent.iterdir()) == ["in.png"]
    with pytest.raises(ImageformError) as info:
        run_job("white-balance", str(src), str(out), None, 0.0, "../x")
    _one_line(info.value, "run_id")


@pytest.mark.parametrize(
    ("param", "bad"),
    [
        ("n_workers", 0),
        ("n_workers", math.nan),
        ("n_workers", 10**30),
        ("worker_timeout_s", math.inf),
        ("worker_timeout_s", 0.0),
        ("hold_s", -1.0),
        ("force", "yes"),
        ("progress", None),
        ("scheduler", 0),
        ("on_result", 3),
    ],
)
def test_run_batch_refuses_before_any_cluster_starts(tmp_path: Path, param: str, bad: Any) -> None:
    from imageform.batch import run_batch

    write_image(tmp_path / "a.png", np.zeros((2, 2, 3), np.uint8))
    with pytest.raises(ImageformError) as info:
        run_batch("convert", f"{tmp_path}/*.png", tmp_path / "o", **{param: bad})
    _one_line(info.value, param)
    assert not (tmp_path / "o").exists()


def test_unknown_option_key_in_one_line() -> None:
    for key in ("bogus", 1, "x" * 1000):
        with pytest.raises(ImageformError) as info:
            batch_options("convert", {key: 1})
        _one_line(info.value, "unknown option")
