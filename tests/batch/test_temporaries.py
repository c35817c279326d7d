"""Temporary names of ``imageform batch`` jobs never nest, and every temporary a killed worker
left is removed by the next run (in process: no cluster needed)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import imageform.io.image_io
from imageform._files import Outputs, atomic_write
from imageform.batch._temps import _remove_stale_temps, _temp_path
from imageform.batch.runner import Job, run_job
from imageform.io import write_image


def test_a_job_writes_its_temporary_in_place(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The workflow's own atomic writers write the job's temporary file directly: the only
    temporary name is the job's (``.NAME.<run>-<token>.tmpSUFFIX``), never one inside another."""
    write_image(tmp_path / "a.png", np.full((4, 4, 3), 90, np.uint8))
    seen: list[str] = []
    real = imageform.io.image_io.atomic_write

    def spy(final: Path, write: Any) -> None:
        def traced(p: Path) -> object:
            seen.append(p.name)
            return write(p)

        real(final, traced)

    monkeypatch.setattr(imageform.io.image_io, "atomic_write", spy)
    out = tmp_path / "out" / "a.tif"
    res = run_job("convert", str(tmp_path / "a.png"), str(out), {"to": "rec2020"}, 0.0, "a" * 12)
    assert res["ok"], res
    (name,) = seen
    assert name.startswith(".a.tif.aaaaaaaaaaaa-") and name.endswith(".tmp.tif"), name
    assert name.count(".tmp") == 1 and ".part" not in name
    assert sorted(p.name for p in out.parent.iterdir()) == ["a.tif"]


def test_a_failed_job_leaves_no_folder_it_made(tmp_path: Path) -> None:
    """A job whose input cannot be read removes the output folders it created (innermost
    first) and leaves a folder that was there, and another job's file, alone."""
    (tmp_path / "bad.png").write_bytes(b"not a png")
    out = tmp_path / "new" / "deeper" / "a.tif"
    res = run_job("convert", str(tmp_path / "bad.png"), str(out), {"to": "rec2020"}, 0.0, None)
    assert not res["ok"] and "bad.png" in res["error"]
    assert not (tmp_path / "new").exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "other.txt").write_text("x")
    res = run_job("convert", str(tmp_path / "bad.png"), str(kept / "b" / "a.tif"), None, 0.0, None)
    assert not res["ok"]
    assert sorted(p.name for p in kept.iterdir()) == ["other.txt"]


def test_outputs_and_atomic_write_do_not_nest(tmp_path: Path) -> None:
    """A single command: Outputs' temporary file is written in place by atomic_write."""
    final = tmp_path / "x.png"
    names: list[str] = []
    with Outputs(force=True) as outs:
        part = outs.file(final)
        atomic_write(part, lambda p: names.append(p.name) or p.write_bytes(b"x"))
    assert names == [part.name] and part.name.count(".part") == 1
    assert final.read_bytes() == b"x" and [p.name for p in tmp_path.iterdir()] == ["x.png"]


@pytest.mark.parametrize(
    "name",
    [
        ".x.tif.{run}-0123456789ab.tmp.tif",
        "..x.tif.{run}-0123456789ab.tmp.tif.4242-0badf00d.part.tif",
        "...x.tif.{run}-0123456789ab.tmp.tif.4242-0badf00d.part.tif.4242-deadbeef.part.tif",
        ".x.tif.deadbeef0000.tmp.tif",
    ],
)
def test_every_temporary_of_a_dead_run_is_removed(tmp_path: Path, name: str) -> None:
    """Whatever a killed worker left (also the nested names of older versions) goes."""
    out = tmp_path / "x.tif"
    stale = tmp_path / name.format(run="c0ffee000000")
    stale.write_bytes(b"partial")
    keep = tmp_path / ".y.tif.c0ffee000000-0123456789ab.tmp.tif"  # another output's
    keep.write_bytes(b"other")
    assert _remove_stale_temps([Job(tmp_path / "x.png", out)], tmp_path) == 1
    assert not stale.exists() and keep.exists()


def test_temp_path_is_hidden_and_keeps_the_suffix(tmp_path: Path) -> None:
    t = _temp_path(tmp_path / "x.tif", "b" * 12)
    assert t.name.startswith(".x.tif.bbbbbbbbbbbb-") and t.suffix == ".tif"
