"""``imageform batch``: a job that fails leaves no new empty folder (nothing half-written).

A run whose every job failed left ``OUT_DIR`` behind, empty (found walking the docs); the
folders a run creates and leaves empty are removed at its end, while a folder that existed
before the run, or that holds anything, is kept.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import write_image

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """A scheduler with one worker thread in this process (no worker processes to start)."""
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        dashboard_address=":0",
        silence_logs=logging.ERROR,
    ) as cluster:
        yield cluster.scheduler_address


def _good(path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_image(path, np.full((4, 6, 3), 128, np.uint8))


def _bad(path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\x89PNG\r\n\x1a\n truncated")  # a PNG cut short: its job fails


def _batch(src: Path, out: Path, scheduler: str, capsys: pytest.CaptureFixture[str]) -> Any:
    argv = ["batch", "convert", f"{src}/**/*.png", "-o", str(out), "--to", "linear-srgb"]
    code = main([*argv, "--scheduler", scheduler])
    return code, capsys.readouterr().out


def test_every_job_failed_leaves_no_folder(
    tmp_path: Path, scheduler: str, capsys: pytest.CaptureFixture[str]
) -> None:
    _bad(tmp_path / "in" / "a.png")
    _bad(tmp_path / "in" / "sub" / "b.png")
    out = tmp_path / "new" / "out"  # two folders the run would create
    code, text = _batch(tmp_path / "in", out, scheduler, capsys)
    assert code == 1 and "0 done, 0 skipped (already finished), 2 failed" in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in"]


def test_a_folder_that_existed_is_kept(
    tmp_path: Path, scheduler: str, capsys: pytest.CaptureFixture[str]
) -> None:
    _bad(tmp_path / "in" / "a.png")
    _bad(tmp_path / "in" / "sub" / "b.png")
    out = tmp_path / "out"
    (out / "sub").mkdir(parents=True)  # empty, but the user's: not the run's to remove
    code, _ = _batch(tmp_path / "in", out, scheduler, capsys)
    assert code == 1
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == ["sub"]


def test_only_the_failed_jobs_new_empty_folders_go(
    tmp_path: Path, scheduler: str, capsys: pytest.CaptureFixture[str]
) -> None:
    _good(tmp_path / "in" / "ok" / "a.png")
    _bad(tmp_path / "in" / "broken" / "b.png")
    _bad(tmp_path / "in" / "mixed" / "c.png")
    _good(tmp_path / "in" / "mixed" / "d.png")
    _bad(tmp_path / "in" / "deep" / "er" / "e.png")
    out = tmp_path / "out"
    (out / "kept").mkdir(parents=True)
    (out / "kept" / "notes.txt").write_text("the user's", encoding="utf-8")
    code, text = _batch(tmp_path / "in", out, scheduler, capsys)
    assert code == 1 and "2 done, 0 skipped (already finished), 3 failed" in text, text
    left = sorted(p.relative_to(out).as_posix() for p in out.rglob("*"))
    assert left == [
        ".imageform-batch.json",
        "kept",
        "kept/notes.txt",
        "mixed",
        "mixed/d.png",
        "ok",
        "ok/a.png",
    ]


def test_a_run_stopped_before_any_job_leaves_no_folder(tmp_path: Path) -> None:
    """No worker ever came: the run stops with a message, and the folder it made is gone."""
    from imageform.batch import NoWorkersError, run_batch

    _good(tmp_path / "in" / "a.png")
    with (
        distributed.LocalCluster(
            n_workers=0, processes=False, dashboard_address=":0", silence_logs=logging.ERROR
        ) as empty,
        pytest.raises(NoWorkersError, match="every dask worker is gone"),
    ):
        run_batch(
            "convert",
            f"{tmp_path}/in/*.png",
            tmp_path / "out",
            {"to": "srgb"},
            scheduler=empty.scheduler_address,
            worker_timeout_s=1,
        )
    assert not (tmp_path / "out").exists()
