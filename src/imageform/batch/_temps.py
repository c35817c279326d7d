"""A batch run's temporary files and lock (internal).

Each job writes ``.NAME.<run>-<random>.tmpSUFFIX`` beside its output; a run holds a lock file
``.imageform-batch.<run>.lock`` in the output folder while it goes on, so that another run into
the same folder knows which temporary files are being written and which a dead run left.
The run id, not a process id, names them: a job runs on a worker, maybe on another host, where
:func:`imageform._files.remove_stale_parts`'s process-id check cannot tell a live writer.
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path

from imageform.batch._plan import Job


def temp_pattern(output: Path) -> str:
    """Return the glob of the temporary files that jobs writing ``output`` use."""
    return f".{glob.escape(output.name)}.*.tmp{glob.escape(output.suffix)}"


def _temp_path(output: Path, run_id: str | None = None) -> Path:
    token = uuid.uuid4().hex[:12]
    if run_id:
        token = f"{run_id}-{token}"
    return output.with_name(f".{output.name}.{token}.tmp{output.suffix}")


_RUN_ID = re.compile("[0-9a-f]{12}")
_LOCK = re.compile(r"\.imageform-batch\.([0-9a-f]{12})\.lock\Z")


@contextlib.contextmanager
def _run_lock(out_root: Path) -> Iterator[str]:
    """Return a run's id, holding a lock file ``.imageform-batch.<id>.lock`` in ``out_root``.

    The lock is held (``flock``) for as long as the run goes on: another run into the same folder
    then knows that the temporary files named with this id are being written, not left by a dead
    run. Without ``fcntl`` (Windows) the id alone, every temporary file counting as stale.
    """
    run_id = uuid.uuid4().hex[:12]
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield run_id
        return
    out_root.mkdir(parents=True, exist_ok=True)
    final = out_root / f".imageform-batch.{run_id}.lock"
    part = out_root / f".imageform-batch.{run_id}.lock-part"
    fd = os.open(part, os.O_CREAT | os.O_WRONLY, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.replace(part, final)  # visible only once held
        yield run_id
    finally:
        final.unlink(missing_ok=True)
        part.unlink(missing_ok=True)
        os.close(fd)


def _live_runs(out_root: Path, own: str | None) -> set[str]:
    """Return the ids of the other runs going on into ``out_root`` (their lock is held).

    The lock files of runs that died are removed.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return set()
    live: set[str] = set()
    try:
        names = os.listdir(out_root)
    except OSError:
        return live
    for name in names:
        m = _LOCK.match(name)
        if m is None or m.group(1) == own:
            continue
        path = out_root / name
        try:
            fd = os.open(path, os.O_RDONLY)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            live.add(m.group(1))  # held: that run goes on
        else:
            path.unlink(missing_ok=True)  # its run died
        finally:
            os.close(fd)
    return live


def _temps_of(output: Path) -> Iterator[tuple[Path, str | None]]:
    """Yield each temporary file of ``output`` in its folder, with the run id in its name.

    That is ``.NAME.<run>-<token>.tmpSUFFIX`` (``.NAME.<token>.tmpSUFFIX`` without a run id, None),
    and the names older versions nested inside it (``..NAME.<run>-<token>.tmpSUFFIX.<pid>-...``,
    one leading dot per level) when a worker was killed while the workflow wrote.
    """
    match = re.compile(
        rf"\.+{re.escape(output.name)}\.(?:([0-9a-f]{{12}})-)?[0-9a-f]{{12}}\.tmp"
        rf"(?:{re.escape(output.suffix)})?(?:\..*)?"
    ).fullmatch
    try:
        names = os.listdir(output.parent)
    except OSError:
        return
    for name in names:
        m = match(name)
        if m is not None:
            yield output.parent / name, m.group(1)


def _remove_stale_temps(
    jobs: list[Job], out_root: Path | None = None, own: str | None = None
) -> int:
    """Remove the temporary files of ``jobs``' outputs that no live run is writing; return how many.

    A file is stale when no run going on into ``out_root`` is writing it (those of run ``own``, this
    one, included: what it left is from killed workers).
    """
    live = _live_runs(out_root, own) if out_root is not None else set()
    n = 0
    for job in jobs:
        for stale, run_id in _temps_of(job.output):
            if run_id in live:
                continue
            with contextlib.suppress(OSError):
                if stale.is_dir() and not stale.is_symlink():
                    shutil.rmtree(stale, ignore_errors=True)
                else:
                    stale.unlink(missing_ok=True)
                n += 1
    return n
