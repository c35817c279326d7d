"""The library's batch job and chunked writer never replace a FIFO (issue 25).

The command line refused it already (tests/cli/test_special_outputs.py); the library
functions now publish through ``imageform._files.publish`` too.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np
import pytest

from imageform.batch.runner import run_job
from imageform.io import write_image


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def test_run_job_never_replaces_a_fifo(tmp_path: Path) -> None:
    src = tmp_path / "in.png"
    write_image(src, np.full((8, 8, 3), 120, np.uint8))
    out = _fifo(tmp_path / "out.png")
    res = run_job("convert", str(src), str(out), {"to": "display-p3"})
    assert not res["ok"] and "FIFO" in res["error"], res
    assert stat.S_ISFIFO(os.lstat(out).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.png", "out.png"]


def test_process_chunked_never_replaces_a_fifo(tmp_path: Path) -> None:
    pytest.importorskip("dask")
    pytest.importorskip("zarr")
    from imageform.batch.chunked import process_chunked
    from imageform.errors import InvalidInputError

    src = tmp_path / "in.tif"
    write_image(src, np.full((64, 64, 3), 0.5, np.float32))
    out = _fifo(tmp_path / "out.tif")
    with pytest.raises(InvalidInputError):
        process_chunked(src, out, "convert", {"to": "lab"}, chunk=32, force=True)
    assert stat.S_ISFIFO(os.lstat(out).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.tif", "out.tif"]
