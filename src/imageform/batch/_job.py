"""One batch job, run on a worker (internal)."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from imageform._files import atomic_write
from imageform.batch._plan import batch_options, batch_workflow
from imageform.batch._temps import _RUN_ID, _temp_path
from imageform.errors import InvalidInputError
from imageform.workflows import Options


def _fsync_folder(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _metrics(summary: Mapping[str, Any]) -> dict[str, Any]:
    from imageform._jsonio import json_ready

    small = {k: v for k, v in summary.items() if k not in ("input", "output")}
    out: dict[str, Any] = json_ready(small)
    return out


def run_job(
    command: str,
    in_path: str,
    out_path: str,
    options: Options | Mapping[str, Any] | None = None,
    hold_s: float = 0.0,
    run_id: str | None = None,
) -> dict[str, Any]:
    """Run ``command`` on one file and publish ``out_path`` atomically (runs on a worker).

    The workflow writes a temporary file in the output's folder; it is fsync-ed and renamed
    onto ``out_path`` (:func:`imageform._files.atomic_write`: ``os.replace``, atomic on POSIX,
    never onto a FIFO or a device), then the folder is fsync-ed. An
    exception removes the temporary file and the output folders this job created (those still
    empty) and comes back as ``{"ok": False, "error": ...}``.
    ``hold_s`` waits between writing and renaming (a test hook: it widens the window in
    which a killed worker leaves a partial file behind). ``run_id`` names the run in the
    temporary file's name, so that another run into the same folder leaves it alone while
    this run holds its lock.
    """
    from imageform._validate import as_path, as_real, describe
    from imageform.workflows import run_file

    out = as_path(out_path, "out_path")
    in_file = as_path(in_path, "in_path")
    hold_s = as_real(hold_s, "hold_s", minimum=0.0, maximum=3600.0)
    if run_id is not None and not (isinstance(run_id, str) and _RUN_ID.fullmatch(run_id)):
        raise InvalidInputError(f"expected run_id as 12 hex digits, got {describe(run_id)}")
    tmp = _temp_path(out, run_id)
    t0 = time.perf_counter()
    results: list[Any] = []
    made: list[Path] = []  # the folders this job creates, removed again if it fails
    try:
        opts = batch_options(command, options)
        folder = out.parent
        while not folder.exists() and folder != folder.parent:
            made.append(folder)
            folder = folder.parent
        out.parent.mkdir(parents=True, exist_ok=True)

        def write(part: Path) -> None:
            results.append(run_file(batch_workflow(command).name, in_file, part, opts))
            if hold_s > 0:
                time.sleep(hold_s)

        # fsync-ed and renamed, never onto a FIFO or a device; removed on error (imageform._files)
        atomic_write(out, write, part=tmp)
        _fsync_folder(out.parent)
    except Exception as exc:
        tmp.unlink(missing_ok=True)
        for folder in made:  # innermost first; one another job filled in the meantime stays
            try:
                folder.rmdir()
            except OSError:
                break
        msg = str(exc).splitlines()[0] if str(exc) else ""
        return {"ok": False, "error": f"{type(exc).__name__}: {msg}".rstrip(": ")}
    result = results[0]
    return {"ok": True, "metrics": _metrics(result.summary), "seconds": time.perf_counter() - t0}
